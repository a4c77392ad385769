//! What the cubic-grid extractors share to sweep a grid: slabs of cell layers meshed in parallel
//! and joined in order ([`slabs`]: the tasks, the tagged indices into the slab below, the join,
//! the one-shot path's sized output, the scratch pool), and the samples' signs packed 64 to a word
//! ([`sign_rows`]: uniform rows skipped whole, crossing edges and surface cells found by word
//! operations). Marching cubes, the dual engine and the tetrahedral engine read both; public for
//! extractor authors.

pub mod sign_rows;
pub mod slabs;
