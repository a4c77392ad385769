//! # isolab experiments: the report
//!
//! The report's experiments ([`experiment`], one file or folder each, and the assembler of
//! `report/`), their figures ([`figures`]), the peers they measure against ([`peers`]), and the
//! binaries `report` (the main job) and one per experiment. Files come from `isolab-io`, runs
//! from `isolab-pipeline`, pictures from `isolab-cli`'s renderer.

pub mod alloc_meter;
pub mod bibliography;
pub mod experiment;
pub mod figures;
pub mod html;
pub mod memory;
pub mod peer_versions;
pub mod peers;
pub mod provenance;
pub mod readme;
#[cfg(test)]
mod readme_check;
pub mod report;
#[cfg(test)]
mod report_check;
#[cfg(test)]
mod reviewed_literals;
pub mod verdict;
