//! The nifti reader on arbitrary bytes (a detached data file, when the header names one, is
//! refused, so the header and attached data are what is fuzzed). A volume read must be finite
//! and of the size its dimensions say.
#![no_main]
use isolab_io::volume::{nifti, VolumeOptions};
use isolab_io::IoError;
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.nii");
    let sibling = |name: &str| -> Result<Vec<u8>, IoError> {
        Err(IoError::Invalid { path: name.into(), reason: "no detached files while fuzzing".into() })
    };
    if let Ok(file) = nifti::parse_nifti(data, path, VolumeOptions::default(), &sibling) {
        let v = &file.volume;
        assert_eq!(v.values().len(), v.dims.iter().product::<usize>());
        assert!(v.values_f32().iter().all(|x| x.is_finite()));
    }
});
