//! The extractor and post-process registries: one line per algorithm.
//!
//! Adding an algorithm: write `extractors/<name>.rs` with a type implementing
//! [`Extractor`](crate::Extractor) (module doc: paper, summary, guarantees, costs), declare the
//! module below, and add one line to [`registry`].

pub mod marching_cubes;

pub use marching_cubes::MarchingCubes;

use crate::extract::{Extractor, PostProcess};

/// Every extractor, built from its default options, in the order the report lists them.
pub fn registry() -> Vec<Box<dyn Extractor>> {
    vec![
        // Lorensen & Cline 1987: the 256-case cube table, one vertex per crossing edge.
        Box::new(MarchingCubes::default()),
    ]
}

/// Every post-process (mesh -> mesh filters usable after any extractor).
pub fn post_processes() -> Vec<Box<dyn PostProcess>> {
    Vec::new()
}

/// The extractor called `name`, or `None`.
pub fn by_name(name: &str) -> Option<Box<dyn Extractor>> {
    registry().into_iter().find(|e| e.name() == name)
}

/// The post-process called `name`, or `None`.
pub fn post_by_name(name: &str) -> Option<Box<dyn PostProcess>> {
    post_processes().into_iter().find(|p| p.name() == name)
}

/// Comma-separated names of all extractors (for error messages).
pub fn names() -> String {
    registry().iter().map(|e| e.name()).collect::<Vec<_>>().join(", ")
}

/// Comma-separated names of all post-processes (for error messages).
pub fn post_names() -> String {
    post_processes().iter().map(|e| e.name()).collect::<Vec<_>>().join(", ")
}
