//! Lookup tables shared by extractors, each with its origin stated in its module.

pub mod marching_cubes;
pub mod marching_cubes_33;
