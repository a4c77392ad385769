//! zarr stores (v2 and v3, on the file system): a 3-D array, or the full-resolution level of an
//! OME-Zarr image (OME-NGFF 0.4 and 0.5 `multiscales`), read whole or a run of z-slices at a
//! time by the `zarrs` crate, which decodes the codecs zarr-python writes by default (blosc for
//! v2, zstd for v3; gzip, zlib, sharding, crc32c and transposes too).
//!
//! Axis order is numpy's: a C-ordered array of shape `(Z, Y, X)` has x fastest, so isolab's x is
//! the array's last axis, as in `isolab.extract` and `isolab.dask.mesh_volume`. Leading axes
//! (OME-Zarr's time and channel) must be of size 1, or one of them picked with `--volume K`.
//! OME-Zarr's `scale` and `translation` place the voxels (the image's own transformations
//! after the level's); a plain array has unit spacing and its origin at voxel 0, noted. There
//! is no anatomical orientation in zarr: the world is the store's coordinates as they are.
//!
//! The reading needs the crate's `zarr` feature (on by default; the `zarrs` crate and its codecs).
//! Without it a store is still recognised ([`is_zarr`]) and refused with that reason.

use super::DataType;
use std::path::{Path, PathBuf};

#[cfg(feature = "zarr")]
mod store;
#[cfg(feature = "zarr")]
pub use store::{header_layout, read_zarr, ZarrSlices};
#[cfg(not(feature = "zarr"))]
mod without;
#[cfg(not(feature = "zarr"))]
pub use without::{header_layout, read_zarr, ZarrSlices};

/// The zarr array of a store and how to read the picked volume from it.
#[derive(Clone, Debug, PartialEq)]
pub struct ZarrLayout {
    /// The store's folder.
    pub store: PathBuf,
    /// The array's node path in the store (`/` or an OME-Zarr dataset's, like `/0`).
    pub node: String,
    /// The stored type.
    pub ty: DataType,
    /// Index fixed on each leading (non-spatial) axis.
    pub lead: Vec<u64>,
    /// Samples per storage chunk along z (the array's third axis from the end).
    pub chunk_z: usize,
}

/// Whether `path` is a zarr store's folder (v3 `zarr.json`, v2 `.zarray` or `.zgroup`).
pub fn is_zarr(path: &Path) -> bool {
    path.is_dir() && ["zarr.json", ".zarray", ".zgroup"].iter().any(|f| path.join(f).is_file())
}
