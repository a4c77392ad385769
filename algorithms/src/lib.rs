//! # isolab algorithms
//!
//! The library half of isolab: scalar **fields**, the **lattices** they are sampled on, the
//! **meshes** that come out, and the **extractors** that turn samples into meshes, all behind
//! one dyn-compatible trait ([`Extractor`]).
//!
//! Data flows one way:
//!
//! ```text
//! Field --sample once--> Samples --Extractor::extract--> Extraction { surface, volume, stats }
//! ```
//!
//! Conventions used everywhere:
//! - inside is `f < iso`; triangles are wound counter-clockwise seen from outside, so normals
//!   point toward increasing `f` and a closed mesh has positive signed volume;
//! - samples are `f32`, in a flat array, x fastest (see [`Grid::index`]).
//!
//! ```
//! use isolab_algorithms::{fields, extractors, Extraction, Samples, Grid};
//! let field = fields::builtin("sphere", fields::FieldParams::default()).unwrap();
//! let grid = Grid::covering(&field.domain(), 32).unwrap();
//! let samples = Samples::sample_cubic(field.clone(), grid, 0.0).unwrap();
//! let mc = extractors::by_name("marching-cubes").unwrap();
//! let mut out = Extraction::default();
//! mc.extract(&samples, &mut out).unwrap();
//! assert!(out.surface.triangles.len() > 1000);
//! ```

pub mod bvh;
pub mod chunks;
pub mod extract;
pub mod extractors;
pub mod field;
pub mod fields;
pub mod geometry;
pub mod labels;
pub mod lattice;
pub mod liquids;
pub mod materials;
pub mod mesh;
pub mod options;
pub mod post;
pub mod predicates;
pub mod random;
pub mod samples;
pub mod sweep;
pub mod tables;

pub use extract::{
    Chunking, DihedralInterval, ExtractError, Extraction, Extractor, Guarantees, LevelsOfDetail, Origins, PostGuarantees,
    PostProcess, StageTimes, Stats,
};
pub use field::{Field, FieldError};
pub use geometry::Aabb;
pub use lattice::{Grid, Lattice, LatticeError};
pub use mesh::{TetMesh, TriMesh};
pub use options::{OptionError, Options};
pub use samples::{SampleError, Samples};

/// Re-exported so that users of the library name the same vector type.
pub use glam::Vec3;
