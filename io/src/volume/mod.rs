//! Volume files: NIfTI-1 and -2 ([`nifti`]), NRRD ([`nrrd`]), MetaImage ([`metaimage`]) and
//! the raw + JSON grid `--samples-out` writes ([`samples`]), read into a
//! [`Volume`] whose affine maps voxel indices to world
//! coordinates.
//!
//! World coordinates are RAS (+x toward the subject's Right, +y Anterior, +z Superior: NIfTI's
//! world and what 3D Slicer shows) for every anatomical format: MetaImage's LPS and NRRD's named
//! spaces are converted. A grid with no anatomical space (an isolab grid, an NRRD
//! with `scanner-xyz` or no space) keeps its coordinates as they are.
//!
//! Why by hand: there is no NRRD or MetaImage crate; `nifti` (0.18) reads NIfTI-1 only (no
//! NIfTI-2), takes paths rather than bytes, and panics on user input (`qform_affine` on a
//! negative pixdim or a qfac other than ±1). The three headers are short (a fixed binary layout,
//! and two `key: value` texts); `flate2` does the decompression.

mod data;
pub mod metaimage;
pub mod nifti;
pub mod nrrd;
pub mod samples;
pub mod slabs;
pub mod zarr;

use super::IoError;
pub use data::{decode, decode_stored, decode_text, gunzip_prefix, inflate, is_gzip, read_stored, Compression};
use glam::DAffine3;
use isolab_algorithms::fields::Volume;
pub use isolab_algorithms::samples::StoredValues;
use std::io::Read;
use std::path::{Path, PathBuf};

/// Which side of the iso-value a file's object is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Inside {
    /// Values above the iso-value are inside (scans: the object is brighter than its background).
    Above,
    /// Values below the iso-value are inside (distance fields, isolab's own grids).
    Below,
}

impl Inside {
    /// The words that name each side (`--inside`, `inside=`), as serialized.
    pub const CHOICES: [(&'static str, Inside); 2] = [("above", Inside::Above), ("below", Inside::Below)];
}

impl std::str::FromStr for Inside {
    type Err = crate::UnknownChoice;
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        crate::choice::parse_choice("inside", text, &Inside::CHOICES)
    }
}

impl std::fmt::Display for Inside {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(crate::choice::choice_name(self, &Inside::CHOICES))
    }
}

/// The coordinate system of a volume's world.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Space {
    /// Right, Anterior, Superior (NIfTI, 3D Slicer's display).
    Ras,
    /// Not anatomical: coordinates as the file gives them.
    Unknown,
}

/// A volume read from a file, with what the file says about it.
#[derive(Clone, Debug)]
pub struct VolumeFile {
    /// The values and the index-to-world affine (RAS for anatomical files).
    pub volume: std::sync::Arc<Volume>,
    /// Format name ("NIfTI-1", "NRRD", ...).
    pub format: &'static str,
    /// The stored data type ("uint8", ...).
    pub data_type: &'static str,
    /// The world's coordinate system.
    pub space: Space,
    /// Which side is inside unless the user says: above for scans, below for isolab's grids.
    pub inside: Inside,
    /// The iso-value the file carries (isolab's grids), if any.
    pub iso: Option<f32>,
    /// Values at the voxel grid's cell centres, when the file holds a BCC lattice.
    pub centres: Option<Vec<f32>>,
    /// Things the user should know (a guessed offset, a unit conversion, a picked volume).
    pub notes: Vec<String>,
}

/// Where a volume file keeps the voxels of the volume asked for, and how: what reading them
/// slab by slab needs ([`slabs::VolumeSlabs`]). The values are x fastest, then y, then z, so a
/// z-slab is a contiguous run of the (decompressed) stream.
#[derive(Clone, Debug, PartialEq)]
pub struct DataLayout {
    /// The file holding the data (the header's own, or the data file it names).
    pub file: PathBuf,
    /// The byte of `file` where the stored data (compressed or not) begins.
    pub start: u64,
    /// How the stored data is compressed.
    pub compression: Option<Compression>,
    /// Bytes of the decompressed stream before the picked volume's first value.
    pub offset: u64,
    /// The stored type.
    pub ty: DataType,
    /// Byte order.
    pub big_endian: bool,
    /// Value scaling: `slope * v + inter`.
    pub slope: f64,
    /// Value offset.
    pub inter: f64,
}

/// Where a volume's values lie, for reading them a run of z-slices at a time.
#[derive(Clone, Debug, PartialEq)]
pub enum StoredData {
    /// A run of (raw or compressed) bytes in a file.
    File(DataLayout),
    /// A zarr array, read by its storage chunks.
    Zarr(zarr::ZarrLayout),
}

impl StoredData {
    /// The stored type.
    pub fn data_type(&self) -> DataType {
        match self {
            StoredData::File(l) => l.ty,
            StoredData::Zarr(l) => l.ty,
        }
    }
}

/// What a volume file's header says, read without its data.
#[derive(Clone, Debug)]
pub struct VolumeHeader {
    /// Samples per axis.
    pub dims: [usize; 3],
    /// Index-to-world (RAS for anatomical files).
    pub affine: DAffine3,
    /// Format name.
    pub format: &'static str,
    /// The stored data type.
    pub data_type: &'static str,
    /// The world's coordinate system.
    pub space: Space,
    /// Which side is inside unless the user says.
    pub inside: Inside,
    /// The iso-value the file carries (isolab's grids), if any.
    pub iso: Option<f32>,
    /// Things the user should know.
    pub notes: Vec<String>,
    /// Where the data lies, or why it cannot be read slab by slab.
    pub layout: Result<StoredData, String>,
}

/// Reads the header of the volume file at `path` (its first bytes only; a zarr store's
/// metadata) and where its data lies.
pub fn read_header(path: &Path, options: VolumeOptions) -> Result<VolumeHeader, IoError> {
    if zarr::is_zarr(path) {
        return zarr::header_layout(path, options);
    }
    let read_err = |source| IoError::Read { path: path.into(), source };
    let mut prefix = Vec::new();
    std::fs::File::open(path).map_err(read_err)?.take(HEADER_PREFIX).read_to_end(&mut prefix).map_err(read_err)?;
    let format = detect(path, &prefix).ok_or_else(|| IoError::Invalid {
        path: path.into(),
        reason: "not a volume file we read (NIfTI, NRRD, MetaImage)".into(),
    })?;
    let text_header_ends = |end: &[u8]| prefix.len() < HEADER_PREFIX as usize || prefix.windows(end.len()).any(|w| w == end);
    let too_long = || IoError::Invalid {
        path: path.into(),
        reason: format!("its header is longer than {} KiB; it is read whole only", HEADER_PREFIX >> 10),
    };
    match format {
        VolumeFormat::Nifti => nifti::header_layout(&prefix, path, options),
        VolumeFormat::Nrrd if text_header_ends(b"\n\n") || text_header_ends(b"\r\n\r\n") => {
            nrrd::header_layout(&prefix, path, options)
        }
        VolumeFormat::MetaImage if text_header_ends(b"ElementDataFile") => metaimage::header_layout(&prefix, path, options),
        VolumeFormat::Nrrd | VolumeFormat::MetaImage => Err(too_long()),
        VolumeFormat::Samples => samples::header_layout(path),
    }
}

/// How much of a file [`read_header`] reads.
const HEADER_PREFIX: u64 = 1 << 20;

/// The stored data types.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DataType {
    /// Unsigned 8-bit.
    U8,
    /// Signed 8-bit.
    I8,
    /// Unsigned 16-bit.
    U16,
    /// Signed 16-bit.
    I16,
    /// Unsigned 32-bit.
    U32,
    /// Signed 32-bit.
    I32,
    /// Unsigned 64-bit.
    U64,
    /// Signed 64-bit.
    I64,
    /// 32-bit float.
    F32,
    /// 64-bit float.
    F64,
}

impl DataType {
    /// Bytes per value.
    pub fn size(self) -> usize {
        match self {
            Self::U8 | Self::I8 => 1,
            Self::U16 | Self::I16 => 2,
            Self::U32 | Self::I32 | Self::F32 => 4,
            Self::U64 | Self::I64 | Self::F64 => 8,
        }
    }

    /// The numpy-style name.
    pub fn name(self) -> &'static str {
        match self {
            Self::U8 => "uint8",
            Self::I8 => "int8",
            Self::U16 => "uint16",
            Self::I16 => "int16",
            Self::U32 => "uint32",
            Self::I32 => "int32",
            Self::U64 => "uint64",
            Self::I64 => "int64",
            Self::F32 => "float32",
            Self::F64 => "float64",
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Self::F32 | Self::F64)
    }
}

/// The volume formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VolumeFormat {
    /// NIfTI-1 or -2 (`.nii`, `.nii.gz`, `.hdr` + `.img`).
    Nifti,
    /// NRRD (`.nrrd`, `.nhdr`).
    Nrrd,
    /// MetaImage (`.mhd`, `.mha`).
    MetaImage,
    /// isolab's raw f32 grid with a `.json` header beside it.
    Samples,
}

/// The volume format of a file, by its content (magic numbers, a NIfTI header size) and name;
/// `None` for anything else (meshes).
pub fn detect(path: &Path, bytes: &[u8]) -> Option<VolumeFormat> {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("").to_ascii_lowercase();
    if bytes.starts_with(b"NRRD") || name.ends_with(".nrrd") || name.ends_with(".nhdr") {
        return Some(VolumeFormat::Nrrd);
    }
    if name.ends_with(".mhd") || name.ends_with(".mha") {
        return Some(VolumeFormat::MetaImage);
    }
    if name.ends_with(".nii") || name.ends_with(".nii.gz") || name.ends_with(".hdr") || name.ends_with(".hdr.gz") {
        return Some(VolumeFormat::Nifti);
    }
    // A grid `--samples-out` wrote has its header beside it (`NAME.json`); a mesh file never is
    // one, even with a JSON beside it (`-o m.ply -m m.ply.json`).
    if samples::header_path(path).is_file() && crate::MeshFormat::from_extension(path).is_none() {
        return Some(VolumeFormat::Samples);
    }
    let head = if is_gzip(bytes) { gunzip_prefix(bytes, 4, path).ok()? } else { bytes.get(..4)?.to_vec() };
    let size = |h: &[u8]| {
        let b = [h[0], h[1], h[2], h[3]];
        [i32::from_le_bytes(b), i32::from_be_bytes(b)]
    };
    if head.len() == 4 && size(&head).iter().any(|&s| s == 348 || s == 540) {
        return Some(VolumeFormat::Nifti);
    }
    None
}

/// How to read a volume.
#[derive(Clone, Copy, Debug, Default)]
pub struct VolumeOptions {
    /// Which 3-D volume of a 4-D file (`--volume K`, from 0).
    pub index: Option<usize>,
}

/// Reads a volume file (or zarr store) of any format we read: uncompressed data straight into
/// the stored type ([`read_stored`]), anything else parsed whole.
pub fn read_volume(path: &Path, options: VolumeOptions) -> Result<VolumeFile, IoError> {
    if zarr::is_zarr(path) {
        return zarr::read_zarr(path, options);
    }
    if let Some(file) = read_stored(path, options)? {
        return Ok(file);
    }
    read_volume_bytes(&super::read_bytes(path)?, path, options)
}

/// Reads a volume from the bytes of the file at `path`, already read (detached data files and
/// `.img` halves are read beside it).
pub fn read_volume_bytes(bytes: &[u8], path: &Path, options: VolumeOptions) -> Result<VolumeFile, IoError> {
    let format = detect(path, bytes).ok_or_else(|| IoError::Invalid {
        path: path.into(),
        reason: "not a volume file we read (NIfTI, NRRD, MetaImage)".into(),
    })?;
    let sibling = |name: &str| -> Result<Vec<u8>, IoError> {
        let file = path.parent().unwrap_or(Path::new("")).join(name);
        super::read_bytes(&file)
    };
    match format {
        VolumeFormat::Nifti => nifti::parse_nifti(bytes, path, options, &sibling),
        VolumeFormat::Nrrd => nrrd::parse_nrrd(bytes, path, options, &sibling),
        VolumeFormat::MetaImage => metaimage::parse_metaimage(bytes, path, options, &sibling),
        VolumeFormat::Samples => samples::read_samples(path),
    }
}

/// Picks 3-D volume `index` of `extra` volumes stored one after the other (a 4-D file's time
/// points); the shape is named when no index was given for a 4-D file.
pub fn pick_volume(
    path: &Path,
    shape: &str,
    extra: usize,
    index: Option<usize>,
    notes: &mut Vec<String>,
) -> Result<usize, IoError> {
    match (extra, index) {
        (1, None | Some(0)) => Ok(0),
        (1, Some(k)) => {
            Err(IoError::Invalid { path: path.into(), reason: format!("--volume {k}: the file holds one 3-D volume ({shape})") })
        }
        (n, None) => Err(IoError::Invalid {
            path: path.into(),
            reason: format!("is 4-D ({shape}): {n} volumes; pick one with --volume K (0 to {})", n - 1),
        }),
        (n, Some(k)) if k < n => {
            notes.push(format!("volume {k} of {n} ({shape})"));
            Ok(k)
        }
        (n, Some(k)) => Err(IoError::Invalid {
            path: path.into(),
            reason: format!("--volume {k} is out of range: {shape} holds {n} volumes (0 to {})", n - 1),
        }),
    }
}

/// Checks `count` values of `ty` fit in `available` bytes from `offset`; the error names both.
pub fn check_size(path: &Path, count: usize, ty: DataType, offset: usize, available: usize) -> Result<usize, IoError> {
    let need = count
        .checked_mul(ty.size())
        .ok_or_else(|| IoError::Invalid { path: path.into(), reason: "the header's shape is too large".into() })?;
    if offset.checked_add(need).is_none_or(|end| end > available) {
        return Err(IoError::Invalid {
            path: path.into(),
            reason: format!(
                "header and data disagree: {count} {} values need {need} bytes from byte {offset}, but the data has {available} bytes",
                ty.name()
            ),
        });
    }
    Ok(need)
}

/// Wraps values into a [`Volume`], naming the file in any error.
pub fn volume(path: &Path, dims: [usize; 3], values: Vec<f32>, affine: DAffine3) -> Result<Volume, IoError> {
    stored_volume(path, dims, StoredValues::F32(values), affine)
}

/// Wraps values in their stored type into a [`Volume`], naming the file in any error.
pub fn stored_volume(path: &Path, dims: [usize; 3], values: StoredValues, affine: DAffine3) -> Result<Volume, IoError> {
    let name = stem(path);
    Volume::stored(name, dims, values, affine)
        .map_err(|e| IoError::Invalid { path: path.into(), reason: strip_name(&e.to_string()) })
}

/// The file name without its volume extensions (`.nii.gz`, `.nrrd`, ...).
pub fn stem(path: &Path) -> String {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("volume");
    let lower = name.to_ascii_lowercase();
    for ext in [".nii.gz", ".hdr.gz", ".nii", ".hdr", ".nrrd", ".nhdr", ".mhd", ".mha", ".raw"] {
        if lower.ends_with(ext) && name.len() > ext.len() {
            return name[..name.len() - ext.len()].to_owned();
        }
    }
    path.file_stem().and_then(|s| s.to_str()).unwrap_or("volume").to_owned()
}

fn strip_name(message: &str) -> String {
    message.split_once("': ").map_or(message, |(_, rest)| rest).to_owned()
}

/// A data file named in a header, relative to the header's directory.
pub fn data_path(header: &Path, name: &str) -> PathBuf {
    header.parent().unwrap_or(Path::new("")).join(name)
}

/// The samples per axis of a 3-D volume file, read from its header alone (the first bytes of the
/// file, gunzipped for `.nii.gz`), so that a volume too large to mesh can be refused before its
/// data is read. `None` when the header does not say plainly (4-D files, detached NIfTI
/// headers, anything malformed: the full reader then decides and names the problem).
pub fn peek_dims(path: &Path) -> Option<[usize; 3]> {
    let mut prefix = Vec::new();
    std::fs::File::open(path).ok()?.take(1 << 16).read_to_end(&mut prefix).ok()?;
    let three = |v: &[usize]| (v.len() == 3 && v.iter().all(|&n| n > 0)).then(|| [v[0], v[1], v[2]]);
    match detect(path, &prefix)? {
        VolumeFormat::Nifti => {
            let head = if is_gzip(&prefix) {
                gunzip_prefix(&prefix, 540, path).or_else(|_| gunzip_prefix(&prefix, 348, path)).ok()?
            } else {
                prefix
            };
            let h = nifti::parse_header(&head, path).ok()?;
            let d = h.dim;
            (d[0] == 3).then(|| three(&[d[1] as usize, d[2] as usize, d[3] as usize])).flatten()
        }
        VolumeFormat::Nrrd => {
            let text = String::from_utf8_lossy(&prefix);
            let value = |key: &str| {
                text.lines().take_while(|l| !l.trim().is_empty()).find_map(|l| {
                    let (k, v) = l.split_once(':')?;
                    (k.trim().eq_ignore_ascii_case(key)).then(|| v.trim().to_owned())
                })
            };
            let sizes: Vec<usize> = value("sizes")?.split_whitespace().map(|s| s.parse().ok()).collect::<Option<_>>()?;
            three(&sizes)
        }
        VolumeFormat::MetaImage => {
            let text = String::from_utf8_lossy(&prefix);
            let value = |key: &str| {
                text.lines().find_map(|l| {
                    let (k, v) = l.split_once('=')?;
                    (k.trim().eq_ignore_ascii_case(key)).then(|| v.trim().to_owned())
                })
            };
            if value("NDims")? != "3" {
                return None;
            }
            let sizes: Vec<usize> = value("DimSize")?.split_whitespace().map(|s| s.parse().ok()).collect::<Option<_>>()?;
            three(&sizes)
        }
        VolumeFormat::Samples => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn four_d_files_need_a_volume_index() {
        let p = Path::new("f.nii");
        let mut notes = Vec::new();
        let e = pick_volume(p, "64 x 64 x 30 x 5", 5, None, &mut notes).unwrap_err().to_string();
        assert!(e.contains("64 x 64 x 30 x 5") && e.contains("--volume"), "{e}");
        assert_eq!(pick_volume(p, "s", 5, Some(3), &mut notes).unwrap(), 3);
        assert!(pick_volume(p, "s", 5, Some(5), &mut notes).is_err());
        assert_eq!(stem(Path::new("/a/mni.nii.gz")), "mni");
    }
}
