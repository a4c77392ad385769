//! # isolab CLI
//!
//! The `isolab` binary (`src/main.rs`: `list`, `extract`, `metrics`, `render`) over the one run
//! of `isolab-pipeline`, and the mesh renderer ([`render`]) it shares with the report's pictures.

pub mod render;
