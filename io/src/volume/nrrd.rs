//! NRRD (`.nrrd` with attached data, `.nhdr` with a detached data file), Teem's "nearly raw
//! raster data", the format of 3D Slicer and ITK.
//!
//! The header is text: a `NRRD000N` line, then `field: value` lines up to a blank line (the
//! data follows it in an attached file). Read here: `type`, `dimension`, `sizes`, `encoding`
//! (`raw`, `gzip`, `ascii`/`text`; `bzip2` and `hex` are refused with a message), `endian`,
//! `space` (named spaces are converted to RAS), `space directions`, `space origin`, `spacings`
//! and `axis mins` when there are no directions, `kinds`, `data file` (one file; lists and
//! patterns are refused), `line skip` and `byte skip` (`-1`: the data is at the end of the file).
//! Axes without a space direction (`none`) are not spatial: one of size > 1 is a 4-D file's
//! fourth axis, picked with `--volume K`.
//! Reference: <https://teem.sourceforge.net/nrrd/format.html>.

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
        "signed char" | "int8" | "int8_t" => DataType::I8,
        "uchar" | "unsigned char" | "uint8" | "uint8_t" => DataType::U8,
        "short" | "short int" | "signed short" | "signed short int" | "int16" | "int16_t" => DataType::I16,
        "ushort" | "unsigned short" | "unsigned short int" | "uint16" | "uint16_t" => DataType::U16,
        "int" | "signed int" | "int32" | "int32_t" => DataType::I32,
        "uint" | "unsigned int" | "uint32" | "uint32_t" => DataType::U32,
        "longlong" | "long long" | "long long int" | "signed long long" | "signed long long int" | "int64" | "int64_t" => {
            DataType::I64
        }
        "ulonglong" | "unsigned long long" | "unsigned long long int" | "uint64" | "uint64_t" => DataType::U64,
        "float" => DataType::F32,
        "double" => DataType::F64,
        _ => return None,
    })
}

/// The sign flips taking a named space to RAS, its dimension, and whether it is anatomical.
fn named_space(name: &str) -> Option<([f64; 3], usize, Space)> {
    let lower = name.to_ascii_lowercase();
    Some(match lower.as_str() {
        "right-anterior-superior" | "ras" => ([1.0, 1.0, 1.0], 3, Space::Ras),
        "left-anterior-superior" | "las" => ([-1.0, 1.0, 1.0], 3, Space::Ras),
        "left-posterior-superior" | "lps" => ([-1.0, -1.0, 1.0], 3, Space::Ras),
        "right-anterior-superior-time" | "rast" => ([1.0, 1.0, 1.0], 4, Space::Ras),
        "left-anterior-superior-time" | "last" => ([-1.0, 1.0, 1.0], 4, Space::Ras),
        "left-posterior-superior-time" | "lpst" => ([-1.0, -1.0, 1.0], 4, Space::Ras),
        "scanner-xyz" | "3d-right-handed" | "3d-left-handed" => ([1.0, 1.0, 1.0], 3, Space::Unknown),
        "scanner-xyz-time" | "3d-right-handed-time" | "3d-left-handed-time" => ([1.0, 1.0, 1.0], 4, Space::Unknown),
        _ => return None,
    })
}

/// `(x,y,z)` or `none`.
fn vector(text: &str) -> Result<Option<Vec<f64>>, String> {
    let t = text.trim();
    if t == "none" {
        return Ok(None);
    }
    let inner =
        t.strip_prefix('(').and_then(|t| t.strip_suffix(')')).ok_or_else(|| format!("'{t}' is not a vector like (1,0,0)"))?;
    inner
        .split(',')
        .map(|c| c.trim().parse::<f64>().map_err(|_| format!("'{t}' is not a vector of numbers")))
        .collect::<Result<_, _>>()
        .map(Some)
}

/// What an NRRD header says, read before any data.
struct Header {
    ty: DataType,
    big_endian: bool,
    sizes: Vec<usize>,
    shape: String,
    encoding: String,
    enc_line: usize,
    space: Space,
    notes: Vec<String>,
    affine: DAffine3,
    /// The three spatial axes, in order.
    spatial: Vec<usize>,
    /// The non-spatial axis (a 4-D file's fourth), if any.
    extra_axis: Option<usize>,
    /// The volume picked along it.
    pick: usize,
    /// Values in the file.
    total: usize,
    /// Where attached data starts (after the header's blank line).
    data_start: usize,
    /// The detached data file and its header line.
    detached: Option<(String, usize)>,
    line_skip: Option<(String, usize)>,
    byte_skip: i64,
}

/// Parses NRRD bytes; `sibling` reads a detached data file named in the header.
pub fn parse_nrrd(
    bytes: &[u8],
    path: &Path,
    options: VolumeOptions,
    sibling: &dyn Fn(&str) -> Result<Vec<u8>, IoError>,
) -> Result<VolumeFile, IoError> {
    let malformed = |line: usize, reason: String| IoError::Malformed { path: path.into(), line, reason };
    let bad = |reason: String| IoError::Invalid { path: path.into(), reason };
    let Header {
        ty,
        big_endian,
        sizes,
        shape,
        encoding,
        enc_line,
        space,
        notes,
        affine,
        spatial,
        extra_axis,
        pick,
        total,
        data_start,
        detached,
        line_skip,
        byte_skip,
    } = header(bytes, path, options)?;
    // The data: attached after the blank line, or in a detached file.
    let owned;
    let mut data: &[u8] = match &detached {
        Some((name, _)) => {
            owned = sibling(name).map_err(|e| match e {
                IoError::Read { source, .. } => IoError::Read { path: data_path(path, name), source },
                e => e,
            })?;
            &owned
        }
        None => &bytes[data_start..],
    };
    if let Some((skip, l)) = line_skip {
        let n: usize = skip.parse().map_err(|_| malformed(l, format!("line skip '{skip}'")))?;
        for _ in 0..n {
            let p = data
                .iter()
                .position(|&b| b == b'\n')
                .ok_or_else(|| malformed(l, format!("line skip {n}: the data has fewer lines")))?;
            data = &data[p + 1..];
        }
    }
    let decoded: StoredValues = match encoding.as_str() {
        "raw" | "gzip" | "gz" => {
            let nbytes = total.checked_mul(ty.size()).ok_or_else(|| bad(format!("shape {shape} is too large")))?;
            let raw_owned;
            let raw: &[u8] = if encoding == "raw" {
                if byte_skip == -1 {
                    let from = data.len().checked_sub(nbytes).ok_or_else(|| {
                        bad(format!(
                            "header and data disagree: shape {shape} of {} needs {nbytes} bytes, the data has {}",
                            ty.name(),
                            data.len()
                        ))
                    })?;
                    &data[from..]
                } else {
                    let skip = usize::try_from(byte_skip).map_err(|_| bad(format!("byte skip {byte_skip}")))?;
                    check_size(path, total, ty, skip, data.len())?;
                    &data[skip..]
                }
            } else {
                if byte_skip < 0 {
                    return Err(bad("byte skip -1 is only allowed with raw encoding".into()));
                }
                let skip = (byte_skip as usize).min(data.len());
                raw_owned = inflate(&data[skip..], Compression::Gzip, nbytes, path).map_err(|e| match e {
                    IoError::Invalid { reason, .. } if reason.contains("decompresses to only") => {
                        bad(format!("header and data disagree: shape {shape} of {}: {reason}", ty.name()))
                    }
                    e => e,
                })?;
                &raw_owned
            };
            decode_stored(raw, ty, big_endian, total, 1.0, 0.0)
        }
        "ascii" | "text" | "txt" => StoredValues::F32(decode_text(data, ty, total, path)?),
        "bzip2" | "bz2" => return Err(malformed(enc_line, "bzip2 encoding is not supported: re-save as gzip or raw".into())),
        "hex" => return Err(malformed(enc_line, "hex encoding is not supported: re-save as gzip or raw".into())),
        e => return Err(malformed(enc_line, format!("encoding '{e}' is not an NRRD encoding"))),
    };
    // Gather the picked volume in x-fastest order of the spatial axes.
    let dims = [sizes[spatial[0]], sizes[spatial[1]], sizes[spatial[2]]];
    let strides: Vec<usize> = (0..sizes.len()).map(|a| sizes[..a].iter().product()).collect();
    let base = extra_axis.map_or(0, |a| pick * strides[a]);
    let [s0, s1, s2] = [strides[spatial[0]], strides[spatial[1]], strides[spatial[2]]];
    let count: usize = dims.iter().product();
    let values = if base == 0 && s0 == 1 && s1 == dims[0] && s2 == dims[0] * dims[1] && decoded.len() == count {
        decoded // already in isolab's order
    } else {
        let [d0, d1, _] = dims;
        decoded.gather(count, |v| base + (v % d0) * s0 + (v / d0 % d1) * s1 + (v / (d0 * d1)) * s2)
    };
    Ok(VolumeFile {
        volume: std::sync::Arc::new(stored_volume(path, dims, values, affine)?),
        format: "NRRD",
        data_type: ty.name(),
        space,
        inside: Inside::Above,
        iso: None,
        centres: None,
        notes,
    })
}

/// The header of NRRD `bytes` (the whole file or its start, up to the blank line).
fn header(bytes: &[u8], path: &Path, options: VolumeOptions) -> Result<Header, IoError> {
    let malformed = |line: usize, reason: String| IoError::Malformed { path: path.into(), line, reason };
    let bad = |reason: String| IoError::Invalid { path: path.into(), reason };
    if !bytes.starts_with(b"NRRD000") {
        return Err(malformed(1, "not an NRRD file: it does not start with 'NRRD000'".into()));
    }
    // Header lines up to the first blank line (or the end of a detached header).
    let mut fields: HashMap<String, (String, usize)> = HashMap::new();
    let mut at = 0;
    let mut line = 0;
    while at < bytes.len() {
        let end = bytes[at..].iter().position(|&b| b == b'\n').map_or(bytes.len(), |p| at + p);
        let text = String::from_utf8_lossy(&bytes[at..end]).trim_end_matches('\r').to_string();
        at = (end + 1).min(bytes.len());
        line += 1;
        if line == 1 || text.starts_with('#') {
            continue;
        }
        if text.trim().is_empty() {
            break;
        }
        if text.contains(":=") {
            continue; // key/value pairs: free-form metadata
        }
        let (key, value) =
            text.split_once(": ").ok_or_else(|| malformed(line, format!("'{}' is not 'field: value'", crate::shown(&text))))?;
        fields.insert(key.trim().to_ascii_lowercase().replace(' ', ""), (value.trim().to_owned(), line));
    }
    let data_start = at;
    let get = |k: &str| fields.get(k).map(|(v, l)| (v.as_str(), *l));
    let need = |k: &str| get(k).ok_or_else(|| bad(format!("the header has no '{k}' field")));
    let (ty_name, ty_line) = need("type")?;
    let ty = data_type(ty_name).ok_or_else(|| malformed(ty_line, format!("type '{ty_name}' is not supported")))?;
    let (dim_text, dim_line) = need("dimension")?;
    let rank: usize = dim_text.parse().map_err(|_| malformed(dim_line, format!("dimension '{dim_text}' is not a number")))?;
    let (sizes_text, sizes_line) = need("sizes")?;
    let sizes: Vec<usize> = sizes_text
        .split_whitespace()
        .map(|s| s.parse().map_err(|_| malformed(sizes_line, format!("size '{s}' is not a count"))))
        .collect::<Result<_, _>>()?;
    if sizes.len() != rank || !(3..=4).contains(&rank) {
        return Err(malformed(sizes_line, format!("sizes '{sizes_text}' for dimension {rank}: 3-D and 4-D files are read")));
    }
    let shape = sizes.iter().map(|s| s.to_string()).collect::<Vec<_>>().join(" x ");
    let (encoding, enc_line) = need("encoding")?;
    let encoding = encoding.to_ascii_lowercase();
    let big_endian = match get("endian") {
        Some(("big", _)) => true,
        Some(("little", _)) | None => false,
        Some((e, l)) => return Err(malformed(l, format!("endian '{e}' is not 'little' or 'big'"))),
    };
    // Geometry: which axes are spatial, their direction and spacing, the origin.
    let (flips, space_dim, space) = match get("space") {
        Some((name, l)) => named_space(name).ok_or_else(|| malformed(l, format!("space '{name}' is not a space NRRD names")))?,
        None => match get("spacedimension") {
            Some((d, l)) => ([1.0; 3], d.parse().map_err(|_| malformed(l, format!("space dimension '{d}'")))?, Space::Unknown),
            None => ([1.0; 3], 3, Space::Unknown),
        },
    };
    let mut notes = Vec::new();
    let mut axes: Vec<Option<DVec3>> = Vec::new();
    let mut origin = DVec3::ZERO;
    if let Some((text, l)) = get("spacedirections") {
        let parts: Vec<&str> = split_vectors(text);
        if parts.len() != rank {
            return Err(malformed(l, format!("space directions has {} entries for dimension {rank}", parts.len())));
        }
        for p in parts {
            let v = vector(p).map_err(|e| malformed(l, e))?;
            axes.push(match v {
                Some(v) if v.len() >= 3 && v.len() == space_dim => {
                    Some(DVec3::new(v[0] * flips[0], v[1] * flips[1], v[2] * flips[2]))
                }
                Some(v) => {
                    return Err(malformed(l, format!("a direction has {} components, the space has {space_dim}", v.len())))
                }
                None => None,
            });
        }
        if let Some((text, l)) = get("spaceorigin") {
            let v = vector(text).map_err(|e| malformed(l, e))?.ok_or_else(|| malformed(l, "space origin is 'none'".into()))?;
            if v.len() < 3 {
                return Err(malformed(l, "space origin needs 3 components".into()));
            }
            origin = DVec3::new(v[0] * flips[0], v[1] * flips[1], v[2] * flips[2]);
        }
    } else {
        let spacings: Vec<f64> = match get("spacings") {
            Some((text, l)) => text
                .split_whitespace()
                .map(|s| s.parse::<f64>().map_err(|_| malformed(l, format!("spacing '{s}' is not a number"))))
                .collect::<Result<_, _>>()?,
            None => {
                notes.push("the header gives no spacing: 1 per voxel".into());
                vec![1.0; rank]
            }
        };
        let mins: Vec<f64> = match get("axismins") {
            Some((text, l)) => text
                .split_whitespace()
                .map(|s| s.parse::<f64>().map_err(|_| malformed(l, format!("axis min '{s}'"))))
                .collect::<Result<_, _>>()?,
            None => vec![0.0; rank],
        };
        if spacings.len() != rank || mins.len() != rank {
            return Err(bad(format!("spacings or axis mins do not have {rank} entries")));
        }
        let kinds: Vec<String> =
            get("kinds").map(|(k, _)| k.split_whitespace().map(str::to_ascii_lowercase).collect()).unwrap_or_default();
        let mut spatial = 0;
        for a in 0..rank {
            let non_spatial =
                spacings[a].is_nan() || kinds.get(a).is_some_and(|k| !matches!(k.as_str(), "domain" | "space" | "???" | "none"));
            if non_spatial || spatial == 3 {
                axes.push(None);
            } else {
                let mut e = DVec3::ZERO;
                e[spatial] = spacings[a];
                origin[spatial] = if mins[a].is_finite() { mins[a] } else { 0.0 };
                spatial += 1;
                axes.push(Some(e));
            }
        }
    }
    let spatial: Vec<usize> = (0..rank).filter(|&a| axes[a].is_some()).collect();
    if spatial.len() != 3 {
        return Err(bad(format!("shape {shape}: {} spatial axes, 3 are needed", spatial.len())));
    }
    let extra_axis = (0..rank).find(|&a| axes[a].is_none());
    let extra = extra_axis.map_or(1, |a| sizes[a]);
    let pick = pick_volume(path, &shape, extra, options.index, &mut notes)?;
    let cols: Vec<DVec3> = spatial.iter().map(|&a| axes[a].unwrap_or(DVec3::ZERO)).collect();
    let affine = DAffine3 { matrix3: DMat3::from_cols(cols[0], cols[1], cols[2]), translation: origin };
    let total =
        sizes.iter().try_fold(1usize, |a, &s| a.checked_mul(s)).ok_or_else(|| bad(format!("shape {shape} is too large")))?;
    let detached = get("datafile").or_else(|| get("data_file")).map(|(name, l)| (name.to_owned(), l));
    if let Some((name, l)) = &detached {
        if name.starts_with("LIST") || name.contains('%') || name.split_whitespace().count() > 1 {
            return Err(malformed(*l, format!("data file '{name}': multi-file data is not supported")));
        }
    }
    let byte_skip: i64 = match get("byteskip") {
        Some((s, l)) => s.parse().map_err(|_| malformed(l, format!("byte skip '{s}'")))?,
        None => 0,
    };
    let line_skip = get("lineskip").map(|(s, l)| (s.to_owned(), l));
    Ok(Header {
        ty,
        big_endian,
        sizes,
        shape,
        encoding,
        enc_line,
        space,
        notes,
        affine,
        spatial,
        extra_axis,
        pick,
        total,
        data_start,
        detached,
        line_skip,
        byte_skip,
    })
}

/// What the header of the NRRD file at `path` says (from its first bytes, `prefix`), and where
/// the data of the volume `options` picks lies, for reading it slab by slab; the layout is an
/// error saying why when the data cannot be read that way (text encodings, line skips, axes
/// that are not x, y, z first).
pub fn header_layout(prefix: &[u8], path: &Path, options: VolumeOptions) -> Result<VolumeHeader, IoError> {
    let h = header(prefix, path, options)?;
    let dims = [h.sizes[h.spatial[0]], h.sizes[h.spatial[1]], h.sizes[h.spatial[2]]];
    let layout = (|| {
        let compression = match h.encoding.as_str() {
            "raw" => None,
            "gzip" | "gz" => Some(Compression::Gzip),
            e => return Err(format!("its '{e}' encoding is read whole only: re-save it as raw or gzip")),
        };
        if h.line_skip.is_some() {
            return Err("its 'line skip' is read whole only".into());
        }
        if h.spatial != [0, 1, 2] {
            return Err(format!("its axes ({}) do not start with the three spatial ones", h.shape));
        }
        let file = match &h.detached {
            Some((name, _)) => data_path(path, name),
            None => path.to_path_buf(),
        };
        let mut start = if h.detached.is_some() { 0 } else { h.data_start as u64 };
        let volume_bytes = (dims.iter().product::<usize>() * h.ty.size()) as u64;
        match (h.byte_skip, compression) {
            (-1, None) => {
                let len = std::fs::metadata(&file).map_err(|e| format!("{}: {e}", file.display()))?.len();
                start = len.checked_sub((h.total * h.ty.size()) as u64).ok_or("the data file is shorter than its shape")?;
            }
            (s, _) if s >= 0 => start += s as u64,
            (s, _) => return Err(format!("byte skip {s} is only allowed with raw encoding")),
        }
        Ok(DataLayout {
            file,
            start,
            compression,
            offset: h.pick as u64 * volume_bytes,
            ty: h.ty,
            big_endian: h.big_endian,
            slope: 1.0,
            inter: 0.0,
        })
    })();
    Ok(VolumeHeader {
        dims,
        affine: h.affine,
        format: "NRRD",
        data_type: h.ty.name(),
        space: h.space,
        inside: Inside::Above,
        iso: None,
        notes: h.notes,
        layout: layout.map(super::StoredData::File),
    })
}

/// Splits `(1,0,0) none (0,1,0)` into its entries.
fn split_vectors(text: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let mut rest = text.trim();
    while !rest.is_empty() {
        if let Some(r) = rest.strip_prefix('(') {
            let end = r.find(')').map_or(rest.len(), |e| e + 2);
            out.push(&rest[..end.min(rest.len())]);
            rest = rest[end.min(rest.len())..].trim_start();
        } else {
            let end = rest.find(char::is_whitespace).unwrap_or(rest.len());
            out.push(&rest[..end]);
            rest = rest[end..].trim_start();
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(bytes: &[u8], files: &[(&str, Vec<u8>)], index: Option<usize>) -> Result<VolumeFile, IoError> {
        let files: Vec<(String, Vec<u8>)> = files.iter().map(|(n, b)| (n.to_string(), b.clone())).collect();
        parse_nrrd(bytes, Path::new("v.nrrd"), VolumeOptions { index }, &move |name| {
            files
                .iter()
                .find(|(n, _)| n == name)
                .map(|(_, b)| b.clone())
                .ok_or_else(|| IoError::Read { path: name.into(), source: std::io::Error::from(std::io::ErrorKind::NotFound) })
        })
    }

    fn attached(header: &str, data: &[u8]) -> Vec<u8> {
        let mut b = format!("NRRD0004\n{header}\n").into_bytes();
        b.extend_from_slice(data);
        b
    }

    #[test]
    fn lps_directions_become_ras_and_values_keep_their_order() {
        let data: Vec<u8> = (0..8u16).flat_map(|v| v.to_be_bytes()).collect();
        let f = read(
            &attached(
                "type: ushort\ndimension: 3\nspace: left-posterior-superior\nsizes: 2 2 2\n\
                 space directions: (2,0,0) (0,3,0) (0,0,4)\nendian: big\nencoding: raw\nspace origin: (10,20,30)\n",
                &data,
            ),
            &[],
            None,
        )
        .unwrap();
        assert_eq!(f.volume.values_f32(), (0..8).map(|v| v as f32).collect::<Vec<_>>());
        let a = f.volume.index_to_world;
        assert_eq!(a.translation, DVec3::new(-10.0, -20.0, 30.0));
        assert_eq!(a.matrix3.x_axis, DVec3::new(-2.0, 0.0, 0.0));
        assert_eq!(a.matrix3.y_axis, DVec3::new(0.0, -3.0, 0.0));
        assert_eq!(f.space, Space::Ras);
    }

    #[test]
    fn gzip_detached_ascii_and_a_component_axis() {
        use std::io::Write;
        let data: Vec<u8> = (0..8u8).collect();
        let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
        gz.write_all(&data).unwrap();
        let gz = gz.finish().unwrap();
        let header = "type: uchar\ndimension: 3\nsizes: 2 2 2\nspacings: 1 1 1\nencoding: gzip\n";
        assert_eq!(read(&attached(header, &gz), &[], None).unwrap().volume.values_f32()[7], 7.0);
        let detached = "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\ndata file: v.raw\n";
        assert_eq!(read(detached.as_bytes(), &[("v.raw", data.clone())], None).unwrap().volume.values_f32()[5], 5.0);
        let ascii = attached("type: float\ndimension: 3\nsizes: 2 2 2\nencoding: ascii\n", b"0 1 2 3\n4 5 6 7.5\n");
        assert_eq!(read(&ascii, &[], None).unwrap().volume.values_f32()[7], 7.5);
        // Two components interleaved on the fastest axis (a vector field): pick one.
        let two: Vec<u8> = (0..16u8).collect();
        let header = "type: uchar\ndimension: 4\nsizes: 2 2 2 2\nkinds: vector domain domain domain\n\
                      space: RAS\nspace directions: none (1,0,0) (0,1,0) (0,0,1)\nencoding: raw\n";
        let e = read(&attached(header, &two), &[], None).unwrap_err().to_string();
        assert!(e.contains("2 x 2 x 2 x 2") && e.contains("--volume"), "{e}");
        let f = read(&attached(header, &two), &[], Some(1)).unwrap();
        assert_eq!(f.volume.values_f32(), vec![1.0, 3.0, 5.0, 7.0, 9.0, 11.0, 13.0, 15.0]);
    }

    #[test]
    fn bad_files_are_named() {
        let e = read(&attached("type: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n", &[0; 5]), &[], None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("v.nrrd") && e.contains("header and data disagree"), "{e}");
        let e = read(&attached("type: complex\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n", &[0; 8]), &[], None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("v.nrrd:2:") && e.contains("complex"), "{e}");
        let e = read(&attached("type: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: bzip2\n", &[0; 8]), &[], None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("bzip2"), "{e}");
        let e =
            read(&attached("type: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: gzip\n", &[0x1f, 0x8b, 8, 0, 1, 2]), &[], None)
                .unwrap_err()
                .to_string();
        assert!(e.contains("corrupt or truncated"), "{e}");
        let e = read(&attached("type: uchar\ndimension: 3\nsizes: 2 2 2\nspacings: 1 0 1\nencoding: raw\n", &[0; 8]), &[], None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("zero side"), "{e}");
        let e = read(&attached("type: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\ndata file: gone.raw\n", &[]), &[], None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("gone.raw"), "{e}");
        let e = read(b"not nrrd", &[], None).unwrap_err().to_string();
        assert!(e.contains("not an NRRD file"), "{e}");
    }
}
