//! A volume file's voxel data: stored bytes decoded into values (in their stored type where they
//! are read as stored, [`decode_stored`]; as scaled `f32` otherwise, [`decode`]), numbers written
//! as text, compressed streams inflated, and uncompressed data read straight from the file into
//! its type ([`read_stored`]).

use super::{read_header, stored_volume, DataType, StoredData, StoredValues, VolumeFile, VolumeOptions};
use crate::IoError;
use std::io::Read;
use std::path::Path;

/// `count` values of type `ty` from `bytes` (which must hold them), as f32 scaled by
/// `slope * v + inter`; in parallel blocks (a scan is millions of voxels).
pub fn decode(bytes: &[u8], ty: DataType, big_endian: bool, count: usize, slope: f64, inter: f64) -> Vec<f32> {
    use rayon::prelude::*;
    const BLOCK: usize = 1 << 16;
    let size = ty.size();
    let scaled = slope != 1.0 || inter != 0.0;
    let mut out = vec![0.0f32; count];
    macro_rules! run {
        ($t:ty) => {{
            out.par_chunks_mut(BLOCK).zip(bytes[..count * size].par_chunks(BLOCK * size)).for_each(|(out, raw)| {
                for (o, chunk) in out.iter_mut().zip(raw.chunks_exact(size)) {
                    let mut b = [0u8; std::mem::size_of::<$t>()];
                    b.copy_from_slice(chunk);
                    let v = if big_endian { <$t>::from_be_bytes(b) } else { <$t>::from_le_bytes(b) };
                    *o = if scaled { (slope * v as f64 + inter) as f32 } else { v as f32 };
                }
            })
        }};
    }
    match ty {
        DataType::U8 => out.par_chunks_mut(BLOCK).zip(bytes[..count].par_chunks(BLOCK)).for_each(|(out, raw)| {
            if scaled {
                out.iter_mut().zip(raw).for_each(|(o, &v)| *o = (slope * v as f64 + inter) as f32);
            } else {
                out.iter_mut().zip(raw).for_each(|(o, &v)| *o = v as f32);
            }
        }),
        DataType::I8 => run!(i8),
        DataType::U16 => run!(u16),
        DataType::I16 => run!(i16),
        DataType::U32 => run!(u32),
        DataType::I32 => run!(i32),
        DataType::U64 => run!(u64),
        DataType::I64 => run!(i64),
        DataType::F32 => run!(f32),
        DataType::F64 => run!(f64),
    }
    out
}

/// `count` values of type `ty` from `bytes` in their own type when they are read as they are
/// stored (no scaling; 8- to 32-bit integers and floats), byte-swapped to the machine's order;
/// otherwise as [`decode`] gives them (`f32`, scaled; 64-bit integers).
pub fn decode_stored(bytes: &[u8], ty: DataType, big_endian: bool, count: usize, slope: f64, inter: f64) -> StoredValues {
    use rayon::prelude::*;
    if slope != 1.0 || inter != 0.0 {
        return StoredValues::F32(decode(bytes, ty, big_endian, count, slope, inter));
    }
    macro_rules! typed {
        ($t:ty) => {{
            const SIZE: usize = std::mem::size_of::<$t>();
            let mut out: Vec<$t> = vec![<$t>::default(); count];
            out.par_chunks_mut(1 << 16).zip(bytes[..count * SIZE].par_chunks((1 << 16) * SIZE)).for_each(|(out, raw)| {
                for (o, chunk) in out.iter_mut().zip(raw.chunks_exact(SIZE)) {
                    let mut b = [0u8; SIZE];
                    b.copy_from_slice(chunk);
                    *o = if big_endian { <$t>::from_be_bytes(b) } else { <$t>::from_le_bytes(b) };
                }
            });
            out
        }};
    }
    match ty {
        DataType::U8 => StoredValues::U8(bytes[..count].to_vec()),
        DataType::I8 => StoredValues::I8(typed!(i8)),
        DataType::U16 => StoredValues::U16(typed!(u16)),
        DataType::I16 => StoredValues::I16(typed!(i16)),
        DataType::U32 => StoredValues::U32(typed!(u32)),
        DataType::I32 => StoredValues::I32(typed!(i32)),
        DataType::F32 => StoredValues::F32(typed!(f32)),
        DataType::F64 => StoredValues::F64(typed!(f64)),
        DataType::U64 | DataType::I64 => StoredValues::F32(decode(bytes, ty, big_endian, count, 1.0, 0.0)),
    }
}

/// Numbers written as text (NRRD `ascii`, MetaImage `BinaryData = False`): `count` of them.
pub fn decode_text(text: &[u8], ty: DataType, count: usize, path: &Path) -> Result<Vec<f32>, IoError> {
    let mut out = Vec::with_capacity(count.min(text.len() / 2 + 1));
    for word in text.split(|b| b.is_ascii_whitespace() || *b == b',').filter(|w| !w.is_empty()) {
        if out.len() == count {
            break;
        }
        let w = String::from_utf8_lossy(word);
        let v: f64 = w.parse().map_err(|_| IoError::Invalid {
            path: path.into(),
            reason: format!("value {}: '{}' is not a number", out.len(), crate::shown(&w)),
        })?;
        if ty.is_integer() && v.fract() != 0.0 {
            return Err(IoError::Invalid { path: path.into(), reason: format!("value {}: '{w}' is not an integer", out.len()) });
        }
        out.push(v as f32);
    }
    if out.len() < count {
        return Err(IoError::Invalid {
            path: path.into(),
            reason: format!("the data holds {} values, the header says {count}", out.len()),
        });
    }
    Ok(out)
}

/// How compressed data is framed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Compression {
    /// gzip (NIfTI `.nii.gz`, NRRD `gzip`).
    Gzip,
    /// zlib (MetaImage `CompressedData = True`).
    Zlib,
}

/// Decompresses `bytes` into exactly `need` bytes, then reads the stream to its end so that a
/// truncated or corrupt stream (a bad checksum) is an error even when the data came out whole.
/// Trailing data past `need` is read and dropped, up to a bound.
pub fn inflate(bytes: &[u8], compression: Compression, need: usize, path: &Path) -> Result<Vec<u8>, IoError> {
    // Deflate expands at most about 1032 times: a header claiming more than that from a short
    // stream gets no more memory than its data can fill (the stream then ends early, an error),
    // instead of a reservation of whatever the header says (a 5 KB fuzzed file asked for 4 GB).
    let plausible = bytes.len().saturating_mul(1032).saturating_add(1 << 20);
    let mut out = Vec::new();
    out.try_reserve_exact(need.min(plausible)).map_err(|_| IoError::Invalid {
        path: path.into(),
        reason: format!("the header asks for {need} bytes of data, more than this machine can hold"),
    })?;
    let mut reader: Box<dyn Read> = match compression {
        Compression::Gzip => Box::new(flate2::read::MultiGzDecoder::new(bytes)),
        Compression::Zlib => Box::new(flate2::read::ZlibDecoder::new(bytes)),
    };
    let corrupt = |e: std::io::Error| IoError::Invalid {
        path: path.into(),
        reason: format!(
            "the {} data is corrupt or truncated ({e})",
            if compression == Compression::Gzip { "gzip" } else { "zlib" }
        ),
    };
    (&mut reader).take(need as u64).read_to_end(&mut out).map_err(corrupt)?;
    if out.len() < need {
        return Err(IoError::Invalid {
            path: path.into(),
            reason: format!("the header says {need} bytes, but the data decompresses to only {}", out.len()),
        });
    }
    std::io::copy(&mut reader.take(1 << 26), &mut std::io::sink()).map_err(corrupt)?;
    Ok(out)
}

/// Whether bytes start a gzip stream.
pub fn is_gzip(bytes: &[u8]) -> bool {
    bytes.starts_with(&[0x1f, 0x8b])
}

/// The first `n` decompressed bytes of a gzip stream (fewer if it is shorter); corrupt data is
/// an error.
pub fn gunzip_prefix(bytes: &[u8], n: usize, path: &Path) -> Result<Vec<u8>, IoError> {
    let mut out = Vec::with_capacity(n);
    flate2::read::MultiGzDecoder::new(bytes)
        .take(n as u64)
        .read_to_end(&mut out)
        .map_err(|e| IoError::Invalid { path: path.into(), reason: format!("the gzip data is corrupt or truncated ({e})") })?;
    Ok(out)
}

/// A volume file whose data is uncompressed and unscaled, read from its header and its data's
/// bytes straight into values of the stored type: the only copy of the data in memory is the
/// volume's own (a 1 GiB uint8 scan takes 1 GiB). `None` when the file is read otherwise
/// (compressed, scaled, 64-bit integers, text, a zarr store, a header that cannot say where the
/// data is): [`read_volume`](super::read_volume) then parses it whole.
pub fn read_stored(path: &Path, options: VolumeOptions) -> Result<Option<VolumeFile>, IoError> {
    if super::zarr::is_zarr(path) {
        return Ok(None);
    }
    let Ok(header) = read_header(path, options) else { return Ok(None) };
    let Ok(StoredData::File(l)) = &header.layout else { return Ok(None) };
    if l.compression.is_some() || l.slope != 1.0 || l.inter != 0.0 || matches!(l.ty, DataType::U64 | DataType::I64) {
        return Ok(None);
    }
    let count: usize = header.dims.iter().product();
    let read_err = |source| IoError::Read { path: l.file.clone(), source };
    let mut file = std::fs::File::open(&l.file).map_err(read_err)?;
    let length = file.metadata().map_err(read_err)?.len();
    let need = (count as u64).saturating_mul(l.ty.size() as u64);
    if l.start.saturating_add(l.offset).saturating_add(need) > length {
        return Ok(None); // the whole-file reader names the disagreement
    }
    std::io::Seek::seek(&mut file, std::io::SeekFrom::Start(l.start + l.offset)).map_err(read_err)?;
    macro_rules! read_typed {
        ($t:ty, $variant:ident) => {{
            let mut out: Vec<$t> = vec![<$t>::default(); count];
            file.read_exact(bytemuck::cast_slice_mut(&mut out)).map_err(read_err)?;
            if l.big_endian != cfg!(target_endian = "big") {
                use rayon::prelude::*;
                out.par_iter_mut().for_each(|v| *v = <$t>::from_bits(v.to_bits().swap_bytes()));
            }
            StoredValues::$variant(out)
        }};
    }
    macro_rules! read_int {
        ($t:ty, $variant:ident) => {{
            let mut out: Vec<$t> = vec![0; count];
            file.read_exact(bytemuck::cast_slice_mut(&mut out)).map_err(read_err)?;
            if l.big_endian != cfg!(target_endian = "big") {
                use rayon::prelude::*;
                out.par_iter_mut().for_each(|v| *v = v.swap_bytes());
            }
            StoredValues::$variant(out)
        }};
    }
    let values = match l.ty {
        DataType::U8 => read_int!(u8, U8),
        DataType::I8 => read_int!(i8, I8),
        DataType::U16 => read_int!(u16, U16),
        DataType::I16 => read_int!(i16, I16),
        DataType::U32 => read_int!(u32, U32),
        DataType::I32 => read_int!(i32, I32),
        DataType::F32 => read_typed!(f32, F32),
        DataType::F64 => read_typed!(f64, F64),
        DataType::U64 | DataType::I64 => return Ok(None),
    };
    Ok(Some(VolumeFile {
        volume: std::sync::Arc::new(stored_volume(path, header.dims, values, header.affine)?),
        format: header.format,
        data_type: header.data_type,
        space: header.space,
        inside: header.inside,
        iso: header.iso,
        centres: None,
        notes: header.notes,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decode_every_type_both_endians_with_scaling() {
        let p = Path::new("d");
        assert_eq!(decode(&[1, 255], DataType::U8, false, 2, 1.0, 0.0), vec![1.0, 255.0]);
        assert_eq!(decode(&[255], DataType::I8, false, 1, 2.0, 1.0), vec![-1.0]);
        assert_eq!(decode(&[1, 0], DataType::U16, true, 1, 1.0, 0.0), vec![256.0]);
        assert_eq!(decode(&(-300i16).to_le_bytes(), DataType::I16, false, 1, 0.5, 0.0), vec![-150.0]);
        assert_eq!(decode(&7u32.to_be_bytes(), DataType::U32, true, 1, 1.0, 0.0), vec![7.0]);
        assert_eq!(decode(&(-7i32).to_le_bytes(), DataType::I32, false, 1, 1.0, 0.0), vec![-7.0]);
        assert_eq!(decode(&9u64.to_le_bytes(), DataType::U64, false, 1, 1.0, 0.0), vec![9.0]);
        assert_eq!(decode(&(-9i64).to_be_bytes(), DataType::I64, true, 1, 1.0, 0.0), vec![-9.0]);
        assert_eq!(decode(&1.5f32.to_le_bytes(), DataType::F32, false, 1, 1.0, 0.0), vec![1.5]);
        assert_eq!(decode(&2.5f64.to_be_bytes(), DataType::F64, true, 1, 1.0, 0.0), vec![2.5]);
        assert_eq!(decode_text(b"1 2\n3,4", DataType::I16, 4, p).unwrap(), vec![1.0, 2.0, 3.0, 4.0]);
        assert!(decode_text(b"1 2", DataType::I16, 3, p).unwrap_err().to_string().contains("holds 2 values"));
        assert!(decode_text(b"1 2.5", DataType::I16, 2, p).unwrap_err().to_string().contains("not an integer"));
    }

    #[test]
    fn inflate_refuses_truncated_and_corrupt_streams() {
        use std::io::Write;
        let data: Vec<u8> = (0..5000u32).map(|i| (i * 7 % 251) as u8).collect();
        let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
        gz.write_all(&data).unwrap();
        let gz = gz.finish().unwrap();
        let p = Path::new("v.nii.gz");
        assert_eq!(inflate(&gz, Compression::Gzip, 5000, p).unwrap(), data);
        // The data is whole, but the trailer (CRC, size) is cut: still an error.
        let e = inflate(&gz[..gz.len() - 4], Compression::Gzip, 5000, p).unwrap_err().to_string();
        assert!(e.contains("corrupt or truncated"), "{e}");
        let e = inflate(&gz[..gz.len() / 2], Compression::Gzip, 5000, p).unwrap_err().to_string();
        assert!(e.contains("corrupt or truncated") || e.contains("only"), "{e}");
        let mut bad = gz.clone();
        let mid = bad.len() / 2;
        bad[mid] ^= 0x55;
        assert!(inflate(&bad, Compression::Gzip, 5000, p).is_err());
        let e = inflate(&gz, Compression::Gzip, 6000, p).unwrap_err().to_string();
        assert!(e.contains("only 5000"), "{e}");
    }
}
