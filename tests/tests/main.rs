//! The integration tests, one binary: each file beside this one is a module (linking the
//! workspace's crates once instead of once per file). `allocations.rs` is its own binary: it
//! installs a counting global allocator, which would count every other test's allocations too.

mod bcc_sculpt;
mod borrowed;
mod chunks;
mod contract;
mod dual_contouring;
mod edge_collapse;
mod house;
mod keep_components;
mod labels;
mod liquids;
mod lod;
mod manifold_dual_contouring;
mod marching_cubes;
mod marching_cubes_33;
mod marching_cubes_decider;
mod marching_tetrahedra;
mod materials;
mod metrics_determinism;
mod models;
mod neuroglancer;
mod parsers;
mod reference_golden;
mod self_intersections;
mod sparse;
mod stuffing;
mod surface_nets;
mod ties;
mod volumes;
