//! NIfTI-1 and NIfTI-2 (`.nii`, `.nii.gz`, and `.hdr` + `.img` pairs), the neuroimaging format.
//!
//! Both versions hold the same fields in a fixed binary layout (348 and 540 bytes; NIfTI-2
//! widens the integers to 64 bits and the floats to doubles), little- or big-endian, told apart
//! by the header size in the first four bytes. The world affine follows the standard's order
//! (nifti1.h, "3D IMAGE (VOLUME) ORIENTATION AND LOCATION IN SPACE"): the sform when
//! `sform_code > 0`, else the qform (quaternion, voxel sizes and `qfac`) when `qform_code > 0`,
//! else voxel sizes alone ("method 1", with a note). Values are scaled by `scl_slope` and
//! `scl_inter` unless the slope is 0 or not finite. Spatial units in metres or microns are
//! converted to millimetres.

use super::{
    check_size, decode_stored, inflate, is_gzip, pick_volume, stored_volume, Compression, DataLayout, DataType, Inside, Space,
    VolumeFile, VolumeHeader, VolumeOptions,
};
use crate::IoError;
use glam::{DAffine3, DMat3, DVec3};
use std::io::Read;
use std::path::Path;

/// The header fields isolab uses, from either version.
#[derive(Clone, Debug, PartialEq)]
pub struct Header {
    /// 1 or 2.
    pub version: u8,
    /// Big-endian file.
    pub big_endian: bool,
    /// `dim[0..8]`.
    pub dim: [i64; 8],
    /// NIfTI datatype code.
    pub datatype: i16,
    /// `pixdim[0..8]` (`pixdim[0]` is qfac).
    pub pixdim: [f64; 8],
    /// Byte offset of the data (in the `.img` file for a pair).
    pub vox_offset: f64,
    /// Value scaling.
    pub scl_slope: f64,
    /// Value offset.
    pub scl_inter: f64,
    /// Spatial and temporal unit codes.
    pub xyzt_units: i32,
    /// qform code.
    pub qform_code: i32,
    /// sform code.
    pub sform_code: i32,
    /// Quaternion b, c, d.
    pub quatern: [f64; 3],
    /// qform offset.
    pub qoffset: [f64; 3],
    /// sform rows.
    pub srow: [[f64; 4]; 3],
    /// Data in the same file (`n+1`/`n+2`) rather than a `.img`.
    pub single_file: bool,
}

/// Reads the header from the start of `bytes` (decompressed).
pub fn parse_header(bytes: &[u8], path: &Path) -> Result<Header, IoError> {
    let bad = |reason: String| IoError::Invalid { path: path.into(), reason };
    if bytes.len() < 4 {
        return Err(bad(format!("not a NIfTI file: {} bytes", bytes.len())));
    }
    let size = [bytes[0], bytes[1], bytes[2], bytes[3]];
    let (version, big_endian) = match (i32::from_le_bytes(size), i32::from_be_bytes(size)) {
        (348, _) => (1, false),
        (_, 348) => (1, true),
        (540, _) => (2, false),
        (_, 540) => (2, true),
        (le, _) => return Err(bad(format!("not a NIfTI file: the header size is {le}, not 348 (NIfTI-1) or 540 (NIfTI-2)"))),
    };
    let header_len = if version == 1 { 348 } else { 540 };
    if bytes.len() < header_len {
        return Err(bad(format!("the NIfTI-{version} header needs {header_len} bytes, the file has {}", bytes.len())));
    }
    let r = Fields { bytes, big_endian };
    let h = if version == 1 {
        let magic = &bytes[344..348];
        let single_file = match magic {
            b"n+1\0" => true,
            b"ni1\0" => false,
            _ => return Err(bad(format!("bad NIfTI-1 magic {magic:?}"))),
        };
        Header {
            version,
            big_endian,
            dim: std::array::from_fn(|k| r.i16(40 + 2 * k) as i64),
            datatype: r.i16(70),
            pixdim: std::array::from_fn(|k| r.f32(76 + 4 * k) as f64),
            vox_offset: r.f32(108) as f64,
            scl_slope: r.f32(112) as f64,
            scl_inter: r.f32(116) as f64,
            xyzt_units: bytes[123] as i32,
            qform_code: r.i16(252) as i32,
            sform_code: r.i16(254) as i32,
            quatern: [r.f32(256) as f64, r.f32(260) as f64, r.f32(264) as f64],
            qoffset: [r.f32(268) as f64, r.f32(272) as f64, r.f32(276) as f64],
            srow: std::array::from_fn(|row| std::array::from_fn(|c| r.f32(280 + 16 * row + 4 * c) as f64)),
            single_file,
        }
    } else {
        let magic = &bytes[4..12];
        let single_file = match magic {
            b"n+2\0\r\n\x1a\n" => true,
            b"ni2\0\r\n\x1a\n" => false,
            _ => return Err(bad(format!("bad NIfTI-2 magic {magic:?}"))),
        };
        Header {
            version,
            big_endian,
            dim: std::array::from_fn(|k| r.i64(16 + 8 * k)),
            datatype: r.i16(12),
            pixdim: std::array::from_fn(|k| r.f64(104 + 8 * k)),
            vox_offset: r.i64(168) as f64,
            scl_slope: r.f64(176),
            scl_inter: r.f64(184),
            xyzt_units: r.i32(500),
            qform_code: r.i32(344),
            sform_code: r.i32(348),
            quatern: [r.f64(352), r.f64(360), r.f64(368)],
            qoffset: [r.f64(376), r.f64(384), r.f64(392)],
            srow: std::array::from_fn(|row| std::array::from_fn(|c| r.f64(400 + 32 * row + 8 * c))),
            single_file,
        }
    };
    Ok(h)
}

struct Fields<'a> {
    bytes: &'a [u8],
    big_endian: bool,
}

impl Fields<'_> {
    fn take<const N: usize>(&self, at: usize) -> [u8; N] {
        let mut b = [0u8; N];
        b.copy_from_slice(&self.bytes[at..at + N]);
        if self.big_endian {
            b.reverse();
        }
        b
    }
    fn i16(&self, at: usize) -> i16 {
        i16::from_le_bytes(self.take(at))
    }
    fn i32(&self, at: usize) -> i32 {
        i32::from_le_bytes(self.take(at))
    }
    fn i64(&self, at: usize) -> i64 {
        i64::from_le_bytes(self.take(at))
    }
    fn f32(&self, at: usize) -> f32 {
        f32::from_le_bytes(self.take(at))
    }
    fn f64(&self, at: usize) -> f64 {
        f64::from_le_bytes(self.take(at))
    }
}

fn data_type(code: i16) -> Result<DataType, String> {
    Ok(match code {
        2 => DataType::U8,
        4 => DataType::I16,
        8 => DataType::I32,
        16 => DataType::F32,
        64 => DataType::F64,
        256 => DataType::I8,
        512 => DataType::U16,
        768 => DataType::U32,
        1024 => DataType::I64,
        1280 => DataType::U64,
        1 => return Err("datatype 1 (1-bit binary) is not supported".into()),
        32 | 1792 | 2048 => return Err(format!("datatype {code} (complex) is not supported: mesh its magnitude")),
        128 | 2304 => return Err(format!("datatype {code} (RGB colour) is not supported: mesh one channel")),
        1536 => return Err("datatype 1536 (128-bit float) is not supported".into()),
        c => return Err(format!("datatype {c} is not a NIfTI datatype")),
    })
}

/// The index-to-world affine the header describes, in millimetres, and a note when it had to
/// fall back.
pub fn affine(h: &Header, notes: &mut Vec<String>) -> Result<DAffine3, String> {
    let a = if h.sform_code > 0 {
        let col = |c: usize| DVec3::new(h.srow[0][c], h.srow[1][c], h.srow[2][c]);
        DAffine3 { matrix3: DMat3::from_cols(col(0), col(1), col(2)), translation: col(3) }
    } else {
        let spacing = [h.pixdim[1], h.pixdim[2], h.pixdim[3]];
        if let Some(bad) = spacing.iter().find(|s| !s.is_finite() || **s == 0.0) {
            return Err(format!("voxel size pixdim[1..4] = {spacing:?} has a zero or non-finite side ({bad})"));
        }
        let [dx, dy, dz] = spacing.map(f64::abs);
        if h.qform_code > 0 {
            let dz = if h.pixdim[0] < 0.0 { -dz } else { dz };
            let r = quaternion_matrix(h.quatern);
            DAffine3 {
                matrix3: DMat3::from_cols(r.x_axis * dx, r.y_axis * dy, r.z_axis * dz),
                translation: DVec3::from(h.qoffset),
            }
        } else {
            notes.push("the header has no sform or qform: voxel sizes only, origin at voxel 0 (NIfTI method 1)".into());
            DAffine3 { matrix3: DMat3::from_diagonal(DVec3::new(dx, dy, dz)), translation: DVec3::ZERO }
        }
    };
    let scale = match h.xyzt_units & 7 {
        1 => 1000.0,
        3 => 1e-3,
        _ => 1.0,
    };
    if scale != 1.0 {
        notes.push(format!("spatial units converted to millimetres (x{scale})"));
    }
    Ok(DAffine3 { matrix3: a.matrix3 * scale, translation: a.translation * scale })
}

/// The rotation of a NIfTI quaternion (b, c, d), with a = sqrt(1 - b² - c² - d²) (nifti1_io's
/// `nifti_quatern_to_mat44`, including its renormalisation when the sum exceeds 1).
pub fn quaternion_matrix([b, c, d]: [f64; 3]) -> DMat3 {
    let mut a = 1.0 - (b * b + c * c + d * d);
    let (mut b, mut c, mut d) = (b, c, d);
    if a < 1e-7 {
        let n = 1.0 / (b * b + c * c + d * d).sqrt();
        b *= n;
        c *= n;
        d *= n;
        a = 0.0;
    } else {
        a = a.sqrt();
    }
    DMat3::from_cols(
        DVec3::new(a * a + b * b - c * c - d * d, 2.0 * (b * c + a * d), 2.0 * (b * d - a * c)),
        DVec3::new(2.0 * (b * c - a * d), a * a + c * c - b * b - d * d, 2.0 * (c * d + a * b)),
        DVec3::new(2.0 * (b * d + a * c), 2.0 * (c * d - a * b), a * a + d * d - c * c - b * b),
    )
}

/// What a NIfTI header says about the volume `options` picks, before any data is read.
struct Plan {
    h: Header,
    ty: DataType,
    grid: [usize; 3],
    voxels: usize,
    shape: String,
    notes: Vec<String>,
    pick: usize,
    affine: DAffine3,
    total: usize,
    nbytes: usize,
    slope: f64,
    inter: f64,
}

/// Reads the header (from `head`, decompressed) and works out the volume's shape, pick and affine.
fn plan(head: &[u8], path: &Path, options: VolumeOptions) -> Result<Plan, IoError> {
    let bad = |reason: String| IoError::Invalid { path: path.into(), reason };
    let h = parse_header(head, path)?;
    let ty = data_type(h.datatype).map_err(bad)?;
    let rank = h.dim[0];
    if !(1..=7).contains(&rank) {
        return Err(bad(format!("dim[0] = {rank}: the number of dimensions must be 1 to 7")));
    }
    let dims: Vec<i64> = h.dim[1..=rank as usize].to_vec();
    let shape = dims.iter().map(|d| d.to_string()).collect::<Vec<_>>().join(" x ");
    if let Some(d) = dims.iter().find(|&&d| d < 1) {
        return Err(bad(format!("shape {shape}: dimension {d} is not positive")));
    }
    let size = |k: usize| dims.get(k).copied().unwrap_or(1) as usize;
    if (4..dims.len()).any(|k| k > 3 && size(k) > 1) {
        return Err(bad(format!("shape {shape}: only 3-D and 4-D volumes are read")));
    }
    let grid = [size(0), size(1), size(2)];
    let voxels =
        grid.iter().try_fold(1usize, |a, &d| a.checked_mul(d)).ok_or_else(|| bad(format!("shape {shape} is too large")))?;
    let mut notes = Vec::new();
    let pick = pick_volume(path, &shape, size(3), options.index, &mut notes)?;
    let affine = affine(&h, &mut notes).map_err(bad)?;
    let total = voxels.checked_mul(size(3)).ok_or_else(|| bad(format!("shape {shape} is too large")))?;
    let nbytes = total.checked_mul(ty.size()).ok_or_else(|| bad(format!("shape {shape} is too large")))?;
    let (slope, inter) = if h.scl_slope.is_finite() && h.scl_slope != 0.0 {
        (h.scl_slope, if h.scl_inter.is_finite() { h.scl_inter } else { 0.0 })
    } else {
        (1.0, 0.0)
    };
    Ok(Plan { h, ty, grid, voxels, shape, notes, pick, affine, total, nbytes, slope, inter })
}

/// Where a single-file NIfTI's data starts: `vox_offset`, or just past the header (with a note)
/// when the offset points inside it.
fn single_file_offset(h: &Header, path: &Path, notes: &mut Vec<String>) -> Result<usize, IoError> {
    let header_len = if h.version == 1 { 348 } else { 540 };
    if !(h.vox_offset.is_finite() && h.vox_offset >= 0.0 && h.vox_offset < 1e15) {
        return Err(IoError::Invalid { path: path.into(), reason: format!("vox_offset {} is not a byte offset", h.vox_offset) });
    }
    Ok(if (h.vox_offset as usize) < header_len + 4 {
        notes.push(format!("vox_offset {} is inside the header; the data is read from byte {}", h.vox_offset, header_len + 4));
        header_len + 4
    } else {
        h.vox_offset as usize
    })
}

/// The image file of a header-only NIfTI pair (`.hdr` beside `.img` or `.img.gz`).
fn image_names(path: &Path) -> [String; 2] {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
    let stem = name.strip_suffix(".gz").unwrap_or(name);
    let stem = stem.strip_suffix(".hdr").or_else(|| stem.strip_suffix(".HDR")).unwrap_or(stem);
    [format!("{stem}.img"), format!("{stem}.img.gz")]
}

/// Parses NIfTI bytes (gzip or not); `sibling` reads the `.img` of a header/image pair.
pub fn parse_nifti(
    bytes: &[u8],
    path: &Path,
    options: VolumeOptions,
    sibling: &dyn Fn(&str) -> Result<Vec<u8>, IoError>,
) -> Result<VolumeFile, IoError> {
    let bad = |reason: String| IoError::Invalid { path: path.into(), reason };
    let gz = is_gzip(bytes);
    let head = if gz { super::gunzip_prefix(bytes, 544, path)? } else { bytes[..bytes.len().min(544)].to_vec() };
    let Plan { h, ty, grid, voxels, shape, mut notes, pick, affine, total, nbytes, slope, inter } = plan(&head, path, options)?;
    let data: std::borrow::Cow<[u8]>;
    let offset;
    if h.single_file {
        offset = single_file_offset(&h, path, &mut notes)?;
        data = if gz {
            let need = offset.checked_add(nbytes).ok_or_else(|| bad("the data size overflows".into()))?;
            inflate(bytes, Compression::Gzip, need, path).map(std::borrow::Cow::Owned).map_err(|e| match e {
                IoError::Invalid { reason, .. } if reason.contains("decompresses to only") => bad(format!(
                    "header and data disagree: shape {shape} of {} needs {nbytes} bytes from byte {offset}; {reason}",
                    ty.name()
                )),
                e => e,
            })?
        } else {
            std::borrow::Cow::Borrowed(bytes)
        };
    } else {
        let [img, img_gz] = image_names(path);
        let img = sibling(&img).or_else(|_| sibling(&img_gz)).map_err(|_| {
            bad(format!("a header-only NIfTI (magic ni{}) needs its image file {img} or {img_gz} beside it", h.version))
        })?;
        offset = h.vox_offset.max(0.0) as usize;
        data = if is_gzip(&img) {
            std::borrow::Cow::Owned(inflate(&img, Compression::Gzip, offset.saturating_add(nbytes), path)?)
        } else {
            std::borrow::Cow::Owned(img)
        };
    }
    check_size(path, total, ty, offset, data.len())?;
    let start = offset + pick * voxels * ty.size();
    let values = decode_stored(&data[start..], ty, h.big_endian, voxels, slope, inter);
    Ok(VolumeFile {
        volume: std::sync::Arc::new(stored_volume(path, grid, values, affine)?),
        format: if h.version == 1 { "NIfTI-1" } else { "NIfTI-2" },
        data_type: ty.name(),
        space: Space::Ras,
        inside: Inside::Above,
        iso: None,
        centres: None,
        notes,
    })
}

/// What the header of the NIfTI file at `path` says (from its first bytes, `prefix`, gzip or
/// not), and where the picked volume's data lies, for reading it slab by slab.
pub fn header_layout(prefix: &[u8], path: &Path, options: VolumeOptions) -> Result<VolumeHeader, IoError> {
    let gz = is_gzip(prefix);
    let head = if gz { super::gunzip_prefix(prefix, 544, path)? } else { prefix[..prefix.len().min(544)].to_vec() };
    let Plan { h, ty, grid, voxels, mut notes, pick, affine, slope, inter, .. } = plan(&head, path, options)?;
    let (file, offset, compression) = if h.single_file {
        (path.to_path_buf(), single_file_offset(&h, path, &mut notes)?, gz.then_some(Compression::Gzip))
    } else {
        let dir = path.parent().unwrap_or(Path::new(""));
        let [img, img_gz] = image_names(path).map(|n| dir.join(n));
        let file = if img.is_file() { img } else { img_gz };
        let mut magic = [0u8; 2];
        let gz = std::fs::File::open(&file).and_then(|mut f| f.read_exact(&mut magic)).is_ok() && is_gzip(&magic);
        (file, h.vox_offset.max(0.0) as usize, gz.then_some(Compression::Gzip))
    };
    let layout = DataLayout {
        file,
        start: 0,
        compression,
        offset: (offset + pick * voxels * ty.size()) as u64,
        ty,
        big_endian: h.big_endian,
        slope,
        inter,
    };
    Ok(VolumeHeader {
        dims: grid,
        affine,
        format: if h.version == 1 { "NIfTI-1" } else { "NIfTI-2" },
        data_type: ty.name(),
        space: Space::Ras,
        inside: Inside::Above,
        iso: None,
        notes,
        layout: Ok(super::StoredData::File(layout)),
    })
}

/// Test and tool support: NIfTI bytes for `values` (f32 or another type's raw bytes).
pub mod write {
    /// A single-file NIfTI-1 (`n+1`, little-endian) with an sform, the given datatype code,
    /// raw little-endian data and scaling.
    pub fn nifti1(
        dims: &[usize],
        datatype: i16,
        bitpix: i16,
        data: &[u8],
        srow: [[f32; 4]; 3],
        slope: f32,
        inter: f32,
    ) -> Vec<u8> {
        let mut h = vec![0u8; 352];
        h[0..4].copy_from_slice(&348i32.to_le_bytes());
        let put16 = |h: &mut Vec<u8>, at: usize, v: i16| h[at..at + 2].copy_from_slice(&v.to_le_bytes());
        let put32 = |h: &mut Vec<u8>, at: usize, v: f32| h[at..at + 4].copy_from_slice(&v.to_le_bytes());
        put16(&mut h, 40, dims.len() as i16);
        for (k, &d) in dims.iter().enumerate() {
            put16(&mut h, 42 + 2 * k, d as i16);
        }
        put16(&mut h, 70, datatype);
        put16(&mut h, 72, bitpix);
        for k in 0..8 {
            put32(&mut h, 76 + 4 * k, 1.0);
        }
        put32(&mut h, 108, 352.0);
        put32(&mut h, 112, slope);
        put32(&mut h, 116, inter);
        h[123] = 2;
        put16(&mut h, 254, 1);
        for (row, values) in srow.iter().enumerate() {
            for (c, &v) in values.iter().enumerate() {
                put32(&mut h, 280 + 16 * row + 4 * c, v);
            }
        }
        h[344..348].copy_from_slice(b"n+1\0");
        h.extend_from_slice(data);
        h
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ID: [[f32; 4]; 3] = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]];

    fn read(bytes: &[u8]) -> Result<VolumeFile, IoError> {
        parse_nifti(bytes, Path::new("t.nii"), VolumeOptions::default(), &|_| {
            Err(IoError::Empty { path: "x".into(), vertices: 0 })
        })
    }

    #[test]
    fn every_data_type_reads_with_scaling() {
        let ramp: Vec<f64> = (0..8).map(|v| v as f64).collect();
        let cases: Vec<(i16, i16, Vec<u8>)> = vec![
            (2, 8, ramp.iter().map(|&v| v as u8).collect()),
            (256, 8, ramp.iter().map(|&v| v as i8 as u8).collect()),
            (512, 16, ramp.iter().flat_map(|&v| (v as u16).to_le_bytes()).collect()),
            (4, 16, ramp.iter().flat_map(|&v| (v as i16).to_le_bytes()).collect()),
            (768, 32, ramp.iter().flat_map(|&v| (v as u32).to_le_bytes()).collect()),
            (8, 32, ramp.iter().flat_map(|&v| (v as i32).to_le_bytes()).collect()),
            (16, 32, ramp.iter().flat_map(|&v| (v as f32).to_le_bytes()).collect()),
            (64, 64, ramp.iter().flat_map(|&v| v.to_le_bytes()).collect()),
        ];
        for (code, bitpix, data) in cases {
            let f = read(&write::nifti1(&[2, 2, 2], code, bitpix, &data, ID, 2.0, -1.0)).unwrap();
            let want: Vec<f32> = (0..8).map(|v| 2.0 * v as f32 - 1.0).collect();
            assert_eq!(f.volume.values_f32(), want, "datatype {code}");
            assert_eq!(f.format, "NIfTI-1");
        }
        // A zero slope means no scaling.
        let f = read(&write::nifti1(&[2, 2, 2], 2, 8, &[5; 8], ID, 0.0, 3.0)).unwrap();
        assert_eq!(f.volume.values_f32(), vec![5.0; 8]);
    }

    #[test]
    fn bad_headers_and_data_are_named() {
        let good = write::nifti1(&[2, 2, 2], 2, 8, &[1; 8], ID, 1.0, 0.0);
        let e = read(&good[..good.len() - 3]).unwrap_err().to_string();
        assert!(e.contains("t.nii") && e.contains("header and data disagree"), "{e}");
        let e = read(&write::nifti1(&[2, 2, 2], 32, 64, &[0; 64], ID, 1.0, 0.0)).unwrap_err().to_string();
        assert!(e.contains("complex"), "{e}");
        let e = read(&write::nifti1(&[2, 2, 2, 3], 2, 8, &[0; 24], ID, 1.0, 0.0)).unwrap_err().to_string();
        assert!(e.contains("2 x 2 x 2 x 3") && e.contains("--volume"), "{e}");
        let zero = [[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]];
        let e = read(&write::nifti1(&[2, 2, 2], 2, 8, &[1; 8], zero, 1.0, 0.0)).unwrap_err().to_string();
        assert!(e.contains("zero side"), "{e}");
        let nan: Vec<u8> = [0.0f32, 1.0, f32::NAN, 0.0, 0.0, 0.0, 0.0, 0.0].iter().flat_map(|v| v.to_le_bytes()).collect();
        let e = read(&write::nifti1(&[2, 2, 2], 16, 32, &nan, ID, 1.0, 0.0)).unwrap_err().to_string();
        assert!(e.contains("voxel (0, 1, 0) is NaN"), "{e}");
        let e = read(b"\x00\x01\x02\x03 garbage").unwrap_err().to_string();
        assert!(e.contains("not a NIfTI file"), "{e}");
        let e = read(&write::nifti1(&[2, 2], 2, 8, &[1; 4], ID, 1.0, 0.0)).unwrap_err().to_string();
        assert!(e.contains("at least 2 voxels"), "{e}");
    }

    #[test]
    fn a_four_d_file_gives_the_volume_asked_for() {
        let data: Vec<u8> = (0..24).collect();
        let f = parse_nifti(
            &write::nifti1(&[2, 2, 2, 3], 2, 8, &data, ID, 1.0, 0.0),
            Path::new("t.nii"),
            VolumeOptions { index: Some(2) },
            &|_| unreachable!(),
        )
        .unwrap();
        assert_eq!(f.volume.values_f32(), (16..24).map(|v| v as f32).collect::<Vec<_>>());
    }

    #[test]
    fn quaternion_identity_and_a_half_turn() {
        assert!(quaternion_matrix([0.0, 0.0, 0.0]).abs_diff_eq(DMat3::IDENTITY, 1e-12));
        // b = 1: a half turn about x, y -> -y, z -> -z.
        let r = quaternion_matrix([1.0, 0.0, 0.0]);
        assert!(r.abs_diff_eq(DMat3::from_diagonal(DVec3::new(1.0, -1.0, -1.0)), 1e-12), "{r}");
    }
}
