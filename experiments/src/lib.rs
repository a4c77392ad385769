//! # isolab experiments
//!
//! Everything that knows about files, command lines and the report: mesh file formats
//! ([`io`]), the one-call pipeline the CLI and experiments share ([`run`]), and the binaries
//! `isolab` (the CLI) and `report` (regenerates `report/`).

pub mod alloc_meter;
pub mod error;
pub mod experiment;
pub mod figures;
pub mod input;
pub mod io;
pub mod memory;
pub mod peers;
pub mod report;
pub mod run;
