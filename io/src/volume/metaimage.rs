//! MetaImage (`.mhd` with a `.raw`/`.zraw` data file, `.mha` with the data attached), ITK's
//! and VTK's format.
//!
//! The header is `Key = Value` lines ending with `ElementDataFile` (`LOCAL`: the data follows).
//! Read here: `NDims` (3, or 4 with `--volume K`), `DimSize`, `ElementType` (`MET_UCHAR` ...
//! `MET_DOUBLE`), `ElementSpacing` (or `ElementSize`), `Offset` (or `Origin`, `Position`),
//! `TransformMatrix` (or `Rotation`, `Orientation`: the direction of index axis 0, then 1, then
//! 2, as ITK's MetaImageIO writes them), `BinaryData`, `BinaryDataByteOrderMSB` (or
//! `ElementByteOrderMSB`), `CompressedData` (zlib), `HeaderSize` (`-1`: the data is at the end),
//! `ElementNumberOfChannels` (channels interleaved; `--volume K` picks one). ITK's world is LPS:
//! it is converted to RAS.

use super::{
    check_size, data_path, decode_stored, decode_text, inflate, pick_volume, stored_volume, Compression, DataLayout, DataType,
    Inside, Space, StoredValues, VolumeFile, VolumeHeader, VolumeOptions,
};
use crate::IoError;
use glam::{DAffine3, DMat3, DVec3};
use std::collections::HashMap;
use std::path::Path;

fn data_type(name: &str) -> Option<DataType> {
    Some(match name {
        "MET_UCHAR" => DataType::U8,
        "MET_CHAR" => DataType::I8,
        "MET_USHORT" => DataType::U16,
        "MET_SHORT" => DataType::I16,
        "MET_UINT" | "MET_ULONG" => DataType::U32,
        "MET_INT" | "MET_LONG" => DataType::I32,
        "MET_ULONG_LONG" => DataType::U64,
        "MET_LONG_LONG" => DataType::I64,
        "MET_FLOAT" => DataType::F32,
        "MET_DOUBLE" => DataType::F64,
        _ => return None,
    })
}

/// What a MetaImage header says, read before any data.
struct Header {
    ty: DataType,
    sizes: Vec<usize>,
    shape: String,
    channels: usize,
    affine: DAffine3,
    big_endian: bool,
    compressed: bool,
    binary: bool,
    notes: Vec<String>,
    pick: usize,
    voxels: usize,
    total: usize,
    data_file: String,
    data_line: usize,
    data_start: usize,
    header_size: i64,
}

/// The header of MetaImage `bytes` (the whole file or its start, up to `ElementDataFile`).
fn header(bytes: &[u8], path: &Path, options: VolumeOptions) -> Result<Header, IoError> {
    let malformed = |line: usize, reason: String| IoError::Malformed { path: path.into(), line, reason };
    let bad = |reason: String| IoError::Invalid { path: path.into(), reason };
    let mut fields: HashMap<String, (String, usize)> = HashMap::new();
    let mut at = 0;
    let mut line = 0;
    let mut data_file = None;
    while at < bytes.len() {
        let end = bytes[at..].iter().position(|&b| b == b'\n').map_or(bytes.len(), |p| at + p);
        let text = String::from_utf8_lossy(&bytes[at..end]).trim_end_matches('\r').to_string();
        at = (end + 1).min(bytes.len());
        line += 1;
        if text.trim().is_empty() {
            continue;
        }
        let (key, value) = text.split_once('=').ok_or_else(|| {
            if line == 1 {
                malformed(1, "not a MetaImage file: it does not start with 'Key = Value' lines".into())
            } else {
                malformed(line, format!("'{}' is not 'Key = Value'", crate::shown(&text)))
            }
        })?;
        let (key, value) = (key.trim().to_owned(), value.trim().to_owned());
        if key == "ElementDataFile" {
            data_file = Some((value, line));
            break;
        }
        fields.insert(key, (value, line));
    }
    let (data_file, data_line) = data_file.ok_or_else(|| bad("the header has no 'ElementDataFile' line".into()))?;
    let data_start = at;
    let get = |keys: &[&str]| keys.iter().find_map(|k| fields.get(*k)).map(|(v, l)| (v.as_str(), *l));
    let numbers = |keys: &[&str], n: usize| -> Result<Option<Vec<f64>>, IoError> {
        match get(keys) {
            None => Ok(None),
            Some((text, l)) => {
                let v: Vec<f64> = text
                    .split_whitespace()
                    .map(|w| w.parse::<f64>().map_err(|_| malformed(l, format!("{}: '{w}' is not a number", keys[0]))))
                    .collect::<Result<_, _>>()?;
                if v.len() < n {
                    return Err(malformed(l, format!("{} has {} numbers, {n} are needed", keys[0], v.len())));
                }
                Ok(Some(v))
            }
        }
    };
    if let Some((kind, l)) = get(&["ObjectType"]) {
        if kind != "Image" {
            return Err(malformed(l, format!("ObjectType '{kind}' is not an Image")));
        }
    }
    let (ndims_text, ndims_line) = get(&["NDims"]).ok_or_else(|| bad("the header has no 'NDims' line".into()))?;
    let ndims: usize = ndims_text.parse().map_err(|_| malformed(ndims_line, format!("NDims '{ndims_text}'")))?;
    if !(3..=4).contains(&ndims) {
        return Err(malformed(ndims_line, format!("NDims {ndims}: 3-D and 4-D images are read")));
    }
    let sizes = numbers(&["DimSize"], ndims)?.ok_or_else(|| bad("the header has no 'DimSize' line".into()))?;
    if sizes.iter().any(|&s| s < 1.0 || s.fract() != 0.0 || s > 1e12) {
        return Err(bad(format!("DimSize {sizes:?} is not a list of positive counts")));
    }
    let sizes: Vec<usize> = sizes.iter().take(ndims).map(|&s| s as usize).collect();
    let shape = sizes.iter().map(|s| s.to_string()).collect::<Vec<_>>().join(" x ");
    let (ty_name, ty_line) = get(&["ElementType"]).ok_or_else(|| bad("the header has no 'ElementType' line".into()))?;
    let ty = data_type(ty_name).ok_or_else(|| malformed(ty_line, format!("ElementType '{ty_name}' is not supported")))?;
    let channels = match get(&["ElementNumberOfChannels"]) {
        Some((c, l)) => {
            c.parse::<usize>().ok().filter(|&c| c >= 1).ok_or_else(|| malformed(l, format!("ElementNumberOfChannels '{c}'")))?
        }
        None => 1,
    };
    let spacing = numbers(&["ElementSpacing", "ElementSize"], 3)?.unwrap_or_else(|| vec![1.0; 3]);
    let offset = numbers(&["Offset", "Origin", "Position"], 3)?.unwrap_or_else(|| vec![0.0; 3]);
    let m = numbers(&["TransformMatrix", "Rotation", "Orientation"], ndims * ndims)?;
    let dir = |axis: usize| match &m {
        Some(m) => DVec3::new(m[axis * ndims], m[axis * ndims + 1], m[axis * ndims + 2]),
        None => DVec3::AXES[axis],
    };
    // LPS -> RAS: negate x and y.
    let ras = DVec3::new(-1.0, -1.0, 1.0);
    let affine = DAffine3 {
        matrix3: DMat3::from_cols(dir(0) * spacing[0] * ras, dir(1) * spacing[1] * ras, dir(2) * spacing[2] * ras),
        translation: DVec3::new(offset[0], offset[1], offset[2]) * ras,
    };
    let is_true = |keys: &[&str]| get(keys).is_some_and(|(v, _)| v.eq_ignore_ascii_case("true"));
    let big_endian = is_true(&["BinaryDataByteOrderMSB", "ElementByteOrderMSB"]);
    let compressed = is_true(&["CompressedData"]);
    let binary = get(&["BinaryData"]).is_none_or(|(v, _)| v.eq_ignore_ascii_case("true"));
    let mut notes = Vec::new();
    let extra = if ndims == 4 { sizes[3] } else { 1 } * channels;
    let pick = pick_volume(
        path,
        &format!("{shape}{}", if channels > 1 { format!(" x {channels} channels") } else { String::new() }),
        extra,
        options.index,
        &mut notes,
    )?;
    let voxels =
        sizes[..3].iter().try_fold(1usize, |a, &s| a.checked_mul(s)).ok_or_else(|| bad(format!("shape {shape} is too large")))?;
    let total = voxels.checked_mul(extra).ok_or_else(|| bad(format!("shape {shape} is too large")))?;
    let header_size: i64 = match get(&["HeaderSize"]) {
        Some((h, l)) => h.parse().map_err(|_| malformed(l, format!("HeaderSize '{h}'")))?,
        None => 0,
    };
    Ok(Header {
        ty,
        sizes,
        shape,
        channels,
        affine,
        big_endian,
        compressed,
        binary,
        notes,
        pick,
        voxels,
        total,
        data_file,
        data_line,
        data_start,
        header_size,
    })
}

/// Parses MetaImage bytes; `sibling` reads a data file named in the header.
pub fn parse_metaimage(
    bytes: &[u8],
    path: &Path,
    options: VolumeOptions,
    sibling: &dyn Fn(&str) -> Result<Vec<u8>, IoError>,
) -> Result<VolumeFile, IoError> {
    let malformed = |line: usize, reason: String| IoError::Malformed { path: path.into(), line, reason };
    let bad = |reason: String| IoError::Invalid { path: path.into(), reason };
    let Header {
        ty,
        sizes,
        shape,
        channels,
        affine,
        big_endian,
        compressed,
        binary,
        notes,
        pick,
        voxels,
        total,
        data_file,
        data_line,
        data_start,
        header_size,
    } = header(bytes, path, options)?;
    let owned;
    let data: &[u8] = if data_file.eq_ignore_ascii_case("LOCAL") {
        &bytes[data_start..]
    } else if data_file.starts_with("LIST") || data_file.contains('%') || data_file.split_whitespace().count() > 1 {
        return Err(malformed(data_line, format!("ElementDataFile '{data_file}': multi-file data is not supported")));
    } else {
        owned = sibling(&data_file).map_err(|e| match e {
            IoError::Read { source, .. } => IoError::Read { path: data_path(path, &data_file), source },
            e => e,
        })?;
        &owned
    };
    let nbytes = total.checked_mul(ty.size()).ok_or_else(|| bad(format!("shape {shape} is too large")))?;
    let decoded = if !binary {
        StoredValues::F32(decode_text(data, ty, total, path)?)
    } else if compressed {
        let raw = inflate(data, Compression::Zlib, nbytes, path).map_err(|e| match e {
            IoError::Invalid { reason, .. } if reason.contains("decompresses to only") => {
                bad(format!("header and data disagree: shape {shape} of {}: {reason}", ty.name()))
            }
            e => e,
        })?;
        decode_stored(&raw, ty, big_endian, total, 1.0, 0.0)
    } else {
        let skip = if header_size == -1 {
            data.len()
                .checked_sub(nbytes)
                .ok_or_else(|| bad(format!("header and data disagree: {nbytes} bytes needed, the data has {}", data.len())))?
        } else {
            usize::try_from(header_size).map_err(|_| bad(format!("HeaderSize {header_size}")))?
        };
        check_size(path, total, ty, skip, data.len())?;
        decode_stored(&data[skip..], ty, big_endian, total, 1.0, 0.0)
    };
    // Channels interleave fastest, the fourth axis is slowest.
    let (time, channel) = (pick / channels, pick % channels);
    let values = if channels == 1 && time == 0 && decoded.len() == voxels {
        decoded
    } else {
        decoded.gather(voxels, |v| (time * voxels + v) * channels + channel)
    };
    Ok(VolumeFile {
        volume: std::sync::Arc::new(stored_volume(path, [sizes[0], sizes[1], sizes[2]], values, affine)?),
        format: "MetaImage",
        data_type: ty.name(),
        space: Space::Ras,
        inside: Inside::Above,
        iso: None,
        centres: None,
        notes,
    })
}

/// What the header of the MetaImage file at `path` says (from its first bytes, `prefix`), and
/// where the picked volume's data lies, for reading it slab by slab; the layout is an error
/// saying why when the data cannot be read that way (text data, interleaved channels).
pub fn header_layout(prefix: &[u8], path: &Path, options: VolumeOptions) -> Result<VolumeHeader, IoError> {
    let h = header(prefix, path, options)?;
    let layout = (|| {
        if !h.binary {
            return Err("its data is text (BinaryData = False), read whole only".to_string());
        }
        if h.channels > 1 {
            return Err(format!("its {} channels are interleaved, read whole only", h.channels));
        }
        let local = h.data_file.eq_ignore_ascii_case("LOCAL");
        if !local && (h.data_file.starts_with("LIST") || h.data_file.contains('%')) {
            return Err(format!("ElementDataFile '{}': multi-file data is not supported", h.data_file));
        }
        let file = if local { path.to_path_buf() } else { data_path(path, &h.data_file) };
        let mut start = if local { h.data_start as u64 } else { 0 };
        let bytes = (h.total * h.ty.size()) as u64;
        match (h.compressed, h.header_size) {
            (false, -1) => {
                let len = std::fs::metadata(&file).map_err(|e| format!("{}: {e}", file.display()))?.len();
                start = len.checked_sub(bytes).ok_or("the data file is shorter than its shape")?;
            }
            (false, s) if s >= 0 => start += s as u64,
            (false, s) => return Err(format!("HeaderSize {s}")),
            (true, _) => {}
        }
        Ok(DataLayout {
            file,
            start,
            compression: h.compressed.then_some(Compression::Zlib),
            offset: (h.pick * h.voxels * h.ty.size()) as u64,
            ty: h.ty,
            big_endian: h.big_endian,
            slope: 1.0,
            inter: 0.0,
        })
    })();
    Ok(VolumeHeader {
        dims: [h.sizes[0], h.sizes[1], h.sizes[2]],
        affine: h.affine,
        format: "MetaImage",
        data_type: h.ty.name(),
        space: Space::Ras,
        inside: Inside::Above,
        iso: None,
        notes: h.notes,
        layout: layout.map(super::StoredData::File),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(bytes: &[u8], files: &[(&str, Vec<u8>)]) -> Result<VolumeFile, IoError> {
        let files: Vec<(String, Vec<u8>)> = files.iter().map(|(n, b)| (n.to_string(), b.clone())).collect();
        parse_metaimage(bytes, Path::new("v.mhd"), VolumeOptions::default(), &move |name| {
            files
                .iter()
                .find(|(n, _)| n == name)
                .map(|(_, b)| b.clone())
                .ok_or_else(|| IoError::Read { path: name.into(), source: std::io::Error::from(std::io::ErrorKind::NotFound) })
        })
    }

    /// What SimpleITK 2.5 wrote for spacing (1, 2, 3), origin (10, 20, 30) and the direction
    /// matrix with axis 0 along +y (LPS).
    const SITK: &str =
        "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\nCompressedData = True\n\
        TransformMatrix = 0 1 0 -1 0 0 0 0 1\nOffset = 10 20 30\nCenterOfRotation = 0 0 0\nAnatomicalOrientation = ALI\n\
        ElementSpacing = 1 2 3\nDimSize = 2 3 4\nElementType = MET_UCHAR\nElementDataFile = t.zraw\n";

    #[test]
    fn the_transform_matrix_lists_axis_directions_and_lps_becomes_ras() {
        use std::io::Write;
        let data: Vec<u8> = (0..24).collect();
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        z.write_all(&data).unwrap();
        let f = read(SITK.as_bytes(), &[("t.zraw", z.finish().unwrap())]).unwrap();
        assert_eq!(f.volume.values_f32()[23], 23.0);
        // SimpleITK put index (1, 0, 0) at LPS (10, 21, 30): RAS (-10, -21, 30).
        assert_eq!(f.volume.to_world(DVec3::X), DVec3::new(-10.0, -21.0, 30.0));
        assert_eq!(f.volume.to_world(DVec3::Y), DVec3::new(-8.0, -20.0, 30.0));
    }

    #[test]
    fn local_data_headers_and_faults() {
        let mut mha =
            b"NDims = 3\nDimSize = 2 2 2\nElementType = MET_SHORT\nBinaryDataByteOrderMSB = True\nElementDataFile = LOCAL\n"
                .to_vec();
        mha.extend((0..8i16).flat_map(|v| v.to_be_bytes()));
        assert_eq!(read(&mha, &[]).unwrap().volume.values_f32()[3], 3.0);
        let e = read(&mha[..mha.len() - 1], &[]).unwrap_err().to_string();
        assert!(e.contains("header and data disagree"), "{e}");
        let e = read(SITK.as_bytes(), &[("t.zraw", vec![0x78, 0x9c, 1, 2, 3])]).unwrap_err().to_string();
        assert!(e.contains("zlib data is corrupt or truncated"), "{e}");
        let e = read(SITK.as_bytes(), &[]).unwrap_err().to_string();
        assert!(e.contains("t.zraw"), "{e}");
        let e = read(SITK.replace("MET_UCHAR", "MET_OTHER").as_bytes(), &[]).unwrap_err().to_string();
        assert!(e.contains("v.mhd:12:") && e.contains("MET_OTHER"), "{e}");
        let e = read(b"\x01\x02binary", &[]).unwrap_err().to_string();
        assert!(e.contains("not a MetaImage file"), "{e}");
    }
}
