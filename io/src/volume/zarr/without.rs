//! A build without the `zarr` feature: stores are recognised and refused with the reason.

use super::super::{VolumeFile, VolumeHeader, VolumeOptions};
use super::ZarrLayout;
use crate::IoError;
use std::path::Path;

/// The reason every zarr read gives in this build.
const NO_ZARR: &str = "a zarr store, and this isolab-io was built without its `zarr` feature";

fn refused(path: &Path) -> IoError {
    IoError::Invalid { path: path.into(), reason: NO_ZARR.into() }
}

/// Refuses the store: this build reads no zarr.
pub fn header_layout(path: &Path, _options: VolumeOptions) -> Result<VolumeHeader, IoError> {
    Err(refused(path))
}

/// Refuses the store: this build reads no zarr.
pub fn read_zarr(path: &Path, _options: VolumeOptions) -> Result<VolumeFile, IoError> {
    Err(refused(path))
}

/// No zarr reader in this build: [`ZarrSlices::open`] refuses every store.
pub struct ZarrSlices {
    never: std::convert::Infallible,
}

impl ZarrSlices {
    /// Refuses the store: this build reads no zarr.
    pub fn open(layout: &ZarrLayout) -> Result<ZarrSlices, IoError> {
        Err(refused(&layout.store))
    }

    /// Never called: no `ZarrSlices` can be made in this build.
    pub fn read(&mut self, _z: usize, _dims: [usize; 3], _count: usize, _out: &mut Vec<f32>) -> Result<(), IoError> {
        match self.never {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::read_volume;

    /// A store is recognised and refused with the reason, whichever way it is opened.
    #[test]
    fn a_store_is_refused_with_the_reason() {
        let dir = tempfile::tempdir().unwrap();
        let store = dir.path().join("a.zarr");
        std::fs::create_dir(&store).unwrap();
        std::fs::write(store.join("zarr.json"), r#"{"zarr_format": 3, "node_type": "array"}"#).unwrap();
        assert!(super::super::is_zarr(&store));
        let e = read_volume(&store, VolumeOptions::default()).err().expect("refused").to_string();
        assert!(e.contains("a.zarr") && e.contains("`zarr` feature"), "{e}");
        let layout =
            ZarrLayout { store: store.clone(), node: "/".into(), ty: super::super::DataType::F32, lead: vec![], chunk_z: 1 };
        assert!(ZarrSlices::open(&layout).err().expect("refused").to_string().contains("`zarr` feature"));
    }
}
