//! A volume file read slab by slab: its header first ([`super::read_header`]), then its
//! z-slices in order, decoded to f32 as they are asked for, so a volume larger than memory can be
//! meshed block by block (`isolab extract --stream`). Raw and compressed (gzip, zlib) data both
//! stream: the data of one volume is a contiguous run of the (decompressed) stream, x fastest.
//! What cannot stream (text encodings, interleaved channels, a BCC grid, an NRRD whose spatial
//! axes are not its first three) is refused when the file is opened, with the reason. A zarr
//! store is read by its storage chunks, a run of them along z at a time ([`super::zarr`]).

use super::zarr::ZarrSlices;
use super::{decode, read_header, Compression, DataLayout, StoredData, VolumeHeader, VolumeOptions};
use crate::IoError;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

/// An open volume file, read one run of z-slices at a time.
pub struct VolumeSlabs {
    /// What the header says (its layout is the one being read).
    pub header: VolumeHeader,
    path: PathBuf,
    source: Source,
    /// Slices read so far.
    next: usize,
}

/// Where the slices come from.
enum Source {
    /// A file's byte stream, decoded through `bytes`.
    File { layout: DataLayout, reader: Box<dyn Read + Send>, bytes: Vec<u8> },
    /// A zarr array.
    Zarr(Box<ZarrSlices>),
}

impl VolumeSlabs {
    /// Opens the volume file at `path` (header only: no voxel is read yet). A file whose data
    /// cannot be read slab by slab is an error saying why.
    pub fn open(path: &Path, options: VolumeOptions) -> Result<VolumeSlabs, IoError> {
        let header = read_header(path, options)?;
        let layout = header
            .layout
            .clone()
            .map_err(|why| IoError::Invalid { path: path.into(), reason: format!("cannot be read slab by slab: {why}") })?;
        let source = match layout {
            StoredData::File(layout) => Source::File { reader: open_data(path, &layout)?, layout, bytes: Vec::new() },
            StoredData::Zarr(layout) => Source::Zarr(Box::new(ZarrSlices::open(&layout)?)),
        };
        Ok(VolumeSlabs { header, path: path.into(), source, next: 0 })
    }

    /// Samples per axis.
    pub fn dims(&self) -> [usize; 3] {
        self.header.dims
    }

    /// Slices read so far (the next call starts at this z).
    pub fn position(&self) -> usize {
        self.next
    }

    /// Appends the next `count` z-slices to `out` (each `nx * ny` values, x fastest), decoded and
    /// scaled. Asking past the last slice, or data that ends early, is an error naming the file
    /// and the slice.
    pub fn read_slices(&mut self, count: usize, out: &mut Vec<f32>) -> Result<(), IoError> {
        let [nx, ny, nz] = self.header.dims;
        if self.next + count > nz {
            return Err(IoError::Invalid {
                path: self.path.clone(),
                reason: format!("slices {}..{} asked for; the volume has {nz}", self.next, self.next + count),
            });
        }
        match &mut self.source {
            Source::File { layout: l, reader, bytes } => {
                let values = nx * ny * count;
                bytes.resize(values * l.ty.size(), 0);
                reader.read_exact(bytes).map_err(|e| IoError::Invalid {
                    path: l.file.clone(),
                    reason: format!(
                        "the data ends or is corrupt within z-slices {}..{} of {nz} ({e})",
                        self.next,
                        self.next + count
                    ),
                })?;
                out.extend(decode(bytes, l.ty, l.big_endian, values, l.slope, l.inter));
            }
            Source::Zarr(zarr) => zarr.read(self.next, self.header.dims, count, out)?,
        }
        self.next += count;
        Ok(())
    }

    /// Starts again from the first slice (a second pass over the data).
    pub fn rewind(&mut self) -> Result<(), IoError> {
        if let Source::File { layout, reader, .. } = &mut self.source {
            *reader = open_data(&self.path, layout)?;
        }
        self.next = 0;
        Ok(())
    }
}

/// The data stream of `layout`, positioned at its volume's first value.
fn open_data(path: &Path, layout: &DataLayout) -> Result<Box<dyn Read + Send>, IoError> {
    let file_err = |source| IoError::Read { path: layout.file.clone(), source };
    let mut file = std::fs::File::open(&layout.file).map_err(file_err)?;
    let seek = layout.start + if layout.compression.is_none() { layout.offset } else { 0 };
    file.seek(SeekFrom::Start(seek)).map_err(file_err)?;
    let file = BufReader::with_capacity(1 << 20, file);
    let mut reader: Box<dyn Read + Send> = match layout.compression {
        None => Box::new(file),
        Some(Compression::Gzip) => Box::new(flate2::read::MultiGzDecoder::new(file)),
        Some(Compression::Zlib) => Box::new(flate2::read::ZlibDecoder::new(file)),
    };
    if layout.compression.is_some() && layout.offset > 0 {
        let skipped = std::io::copy(&mut (&mut reader).take(layout.offset), &mut std::io::sink()).map_err(|e| {
            IoError::Invalid { path: path.into(), reason: format!("the compressed data is corrupt or truncated ({e})") }
        })?;
        if skipped < layout.offset {
            return Err(IoError::Invalid {
                path: path.into(),
                reason: format!(
                    "the data decompresses to {skipped} bytes, before the volume's first value at byte {}",
                    layout.offset
                ),
            });
        }
    }
    Ok(reader)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::volume::{nifti, read_volume};
    use std::io::Write;

    const DIMS: [usize; 3] = [5, 4, 7];

    fn gzip(data: &[u8]) -> Vec<u8> {
        let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
        gz.write_all(data).unwrap();
        gz.finish().unwrap()
    }

    fn zlib(data: &[u8]) -> Vec<u8> {
        let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        z.write_all(data).unwrap();
        z.finish().unwrap()
    }

    /// Two volumes of u16 values (the second a 4-D file's volume 1), big-endian when asked.
    fn data(volumes: usize, big_endian: bool) -> Vec<u8> {
        let n: usize = DIMS.iter().product::<usize>() * volumes;
        (0..n as u16).flat_map(|v| if big_endian { (v * 7).to_be_bytes() } else { (v * 7).to_le_bytes() }).collect()
    }

    /// The whole reader's values against the slab reader's, read in runs of 1, 2 and 4 slices.
    fn same_values(path: &Path, index: Option<usize>) {
        let options = VolumeOptions { index };
        let whole = read_volume(path, options).unwrap();
        let mut slabs = VolumeSlabs::open(path, options).unwrap();
        assert_eq!(slabs.dims(), whole.volume.dims, "{}", path.display());
        assert_eq!(slabs.header.affine, whole.volume.index_to_world, "{}", path.display());
        for run in [1, 2, 4] {
            slabs.rewind().unwrap();
            let mut out = Vec::new();
            while slabs.position() < DIMS[2] {
                let n = run.min(DIMS[2] - slabs.position());
                slabs.read_slices(n, &mut out).unwrap();
            }
            assert_eq!(out.as_slice(), whole.volume.values_f32().as_ref(), "{} in runs of {run}", path.display());
        }
        let e = slabs.read_slices(1, &mut Vec::new()).unwrap_err().to_string();
        assert!(e.contains("the volume has 7"), "{e}");
    }

    #[test]
    fn every_streamable_layout_reads_the_values_the_whole_reader_reads() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let [nx, ny, nz] = DIMS;
        let srow = [[2.0, 0.0, 0.0, 1.0], [0.0, -1.0, 0.0, 2.0], [0.0, 0.0, 3.0, 3.0]];
        // NIfTI-1: plain, gzip, and a 4-D file's second volume, with scaling.
        let nii = nifti::write::nifti1(&[nx, ny, nz], 512, 16, &data(1, false), srow, 0.5, 1.0);
        std::fs::write(d.join("a.nii"), &nii).unwrap();
        std::fs::write(d.join("a.nii.gz"), gzip(&nii)).unwrap();
        let four = nifti::write::nifti1(&[nx, ny, nz, 2], 512, 16, &data(2, false), srow, 1.0, 0.0);
        std::fs::write(d.join("b.nii.gz"), gzip(&four)).unwrap();
        // NRRD: raw big-endian, gzip attached, detached raw, a 4-D file, data at the end.
        let head = |enc: &str, extra: &str| {
            format!("NRRD0004\ntype: ushort\ndimension: 3\nsizes: {nx} {ny} {nz}\nspace: LPS\nspace directions: (1,0,0) (0,2,0) (0,0,1)\nencoding: {enc}\n{extra}\n\n")
        };
        let mut raw = head("raw", "endian: big").into_bytes();
        raw.extend(data(1, true));
        std::fs::write(d.join("c.nrrd"), raw).unwrap();
        let mut gz = head("gzip", "endian: little").into_bytes();
        gz.extend(gzip(&data(1, false)));
        std::fs::write(d.join("d.nrrd"), gz).unwrap();
        std::fs::write(d.join("e.nhdr"), head("raw", "data file: e.raw")).unwrap();
        std::fs::write(d.join("e.raw"), data(1, false)).unwrap();
        let mut tail = head("raw", "byte skip: -1").into_bytes();
        tail.extend([9u8; 13]);
        tail.extend(data(1, false));
        std::fs::write(d.join("f.nrrd"), tail).unwrap();
        let mut four = format!(
            "NRRD0004\ntype: ushort\ndimension: 4\nsizes: {nx} {ny} {nz} 2\nspace: RAS\n\
             space directions: (1,0,0) (0,1,0) (0,0,1) none\nencoding: gzip\n\n"
        )
        .into_bytes();
        four.extend(gzip(&data(2, false)));
        std::fs::write(d.join("g.nrrd"), four).unwrap();
        // MetaImage: local raw, detached zlib, a 4-D file.
        let meta = |ndims: usize, extra: &str, file: &str| {
            let size = if ndims == 4 { format!("{nx} {ny} {nz} 2") } else { format!("{nx} {ny} {nz}") };
            format!("ObjectType = Image\nNDims = {ndims}\nDimSize = {size}\nElementType = MET_USHORT\n{extra}ElementDataFile = {file}\n")
        };
        let mut mha = meta(3, "ElementSpacing = 1 2 3\n", "LOCAL").into_bytes();
        mha.extend(data(1, false));
        std::fs::write(d.join("h.mha"), mha).unwrap();
        std::fs::write(d.join("i.mhd"), meta(3, "CompressedData = True\n", "i.zraw")).unwrap();
        std::fs::write(d.join("i.zraw"), zlib(&data(1, false))).unwrap();
        let mut mha4 = meta(4, "BinaryDataByteOrderMSB = True\n", "LOCAL").into_bytes();
        mha4.extend(data(2, true));
        std::fs::write(d.join("j.mha"), mha4).unwrap();
        for (name, index) in [
            ("a.nii", None),
            ("a.nii.gz", None),
            ("b.nii.gz", Some(1)),
            ("c.nrrd", None),
            ("d.nrrd", None),
            ("e.nhdr", None),
            ("f.nrrd", None),
            ("g.nrrd", Some(1)),
            ("h.mha", None),
            ("i.mhd", None),
            ("j.mha", Some(1)),
        ] {
            same_values(&d.join(name), index);
        }
    }

    #[test]
    fn what_cannot_stream_says_why_and_truncated_data_names_the_slice() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let ascii = "NRRD0004\ntype: float\ndimension: 3\nsizes: 2 2 2\nencoding: ascii\n\n0 1 2 3 4 5 6 7\n";
        std::fs::write(d.join("t.nrrd"), ascii).unwrap();
        let e = VolumeSlabs::open(&d.join("t.nrrd"), VolumeOptions::default()).err().unwrap().to_string();
        assert!(e.contains("t.nrrd") && e.contains("slab by slab") && e.contains("ascii"), "{e}");
        let channels =
            "NDims = 3\nDimSize = 2 2 2\nElementType = MET_UCHAR\nElementNumberOfChannels = 3\nElementDataFile = LOCAL\n";
        let mut mha = channels.as_bytes().to_vec();
        mha.extend([0u8; 24]);
        std::fs::write(d.join("c.mha"), mha).unwrap();
        let e = VolumeSlabs::open(&d.join("c.mha"), VolumeOptions { index: Some(0) }).err().unwrap().to_string();
        assert!(e.contains("3 channels"), "{e}");
        // Cut in the middle of the data: the slice where it ends is named.
        let nii = nifti::write::nifti1(
            &[4, 4, 4],
            2,
            8,
            &[1u8; 64],
            [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]],
            1.0,
            0.0,
        );
        std::fs::write(d.join("cut.nii.gz"), gzip(&nii[..nii.len() - 20])).unwrap();
        let mut slabs = VolumeSlabs::open(&d.join("cut.nii.gz"), VolumeOptions::default()).unwrap();
        let mut out = Vec::new();
        slabs.read_slices(2, &mut out).unwrap();
        let e = slabs.read_slices(2, &mut out).unwrap_err().to_string();
        assert!(e.contains("cut.nii.gz") && e.contains("z-slices 2..4 of 4"), "{e}");
    }
}
