//! Post-processes: mesh-to-mesh filters usable after any surface extractor. The registry is
//! [`crate::extractors::POST_INFOS`].

pub mod edge_collapse;
pub mod triangle_grid;

pub use edge_collapse::EdgeCollapse;
