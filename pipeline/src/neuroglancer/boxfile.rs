//! A box's work file: every label's mesh in one octree box at one level, as floats (for the
//! next level) and Draco-encoded (for the segments). The index comes first, so a segment's bytes
//! are found by reading the header alone.
//!
//! Layout (little endian): `ISONGBX1`, level, position x y z, label count (u32 each); per label:
//! label, vertices, triangles (u32), Draco bytes (u64); then per label its positions (f32 x 3),
//! triangles (u32 x 3) and Draco bytes.

use std::io::{self, Read, Write};
use std::path::Path;

use glam::Vec3;
use isolab_algorithms::TriMesh;

use super::{file_error, NgError};

const MAGIC: &[u8; 8] = b"ISONGBX1";

/// A box's label meshes, each with its encoded fragment.
#[derive(Clone, Debug, Default)]
pub struct BoxMeshes {
    /// Its level of detail.
    pub level: u32,
    /// Its position at that level.
    pub position: [u32; 3],
    /// `(label, mesh, draco bytes)`, by label.
    pub labels: Vec<(u32, TriMesh, Vec<u8>)>,
}

/// What a box holds: each label's triangles and encoded bytes.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct BoxIndex {
    /// `(label, triangles, draco bytes)`, by label.
    pub labels: Vec<(u32, u32, u64)>,
}

impl BoxMeshes {
    /// Its index.
    pub fn index(&self) -> BoxIndex {
        BoxIndex { labels: self.labels.iter().map(|(l, m, d)| (*l, m.triangles.len() as u32, d.len() as u64)).collect() }
    }
}

/// Writes a box file.
pub fn write(w: &mut impl Write, b: &BoxMeshes) -> io::Result<()> {
    w.write_all(MAGIC)?;
    for v in [b.level, b.position[0], b.position[1], b.position[2], b.labels.len() as u32] {
        w.write_all(&v.to_le_bytes())?;
    }
    for (label, mesh, draco) in &b.labels {
        for v in [*label, mesh.positions.len() as u32, mesh.triangles.len() as u32] {
            w.write_all(&v.to_le_bytes())?;
        }
        w.write_all(&(draco.len() as u64).to_le_bytes())?;
    }
    for (_, mesh, draco) in &b.labels {
        w.write_all(bytemuck_f32(&mesh.positions))?;
        for t in &mesh.triangles {
            for v in t {
                w.write_all(&v.to_le_bytes())?;
            }
        }
        w.write_all(draco)?;
    }
    Ok(())
}

fn bytemuck_f32(p: &[Vec3]) -> &[u8] {
    bytemuck::cast_slice(p)
}

struct Header {
    level: u32,
    position: [u32; 3],
    /// `(label, vertices, triangles, draco bytes)`.
    rows: Vec<(u32, u32, u32, u64)>,
    /// Bytes of the header.
    len: u64,
}

fn u32_of(b: &[u8]) -> u32 {
    u32::from_le_bytes([b[0], b[1], b[2], b[3]])
}

fn read_header(r: &mut impl Read) -> io::Result<Header> {
    let mut head = [0u8; 28];
    r.read_exact(&mut head)?;
    if &head[..8] != MAGIC {
        return Err(io::Error::new(io::ErrorKind::InvalidData, "not an isolab neuroglancer box file"));
    }
    let level = u32_of(&head[8..]);
    let position = [u32_of(&head[12..]), u32_of(&head[16..]), u32_of(&head[20..])];
    let n = u32_of(&head[24..]) as usize;
    let mut rows_bytes = vec![0u8; 20 * n];
    r.read_exact(&mut rows_bytes)?;
    let rows = rows_bytes
        .chunks_exact(20)
        .map(|c| (u32_of(c), u32_of(&c[4..]), u32_of(&c[8..]), u64::from_le_bytes(c[12..20].try_into().unwrap_or([0; 8]))))
        .collect();
    Ok(Header { level, position, rows, len: 28 + 20 * n as u64 })
}

fn body_len(rows: &[(u32, u32, u32, u64)]) -> u64 {
    rows.iter().map(|&(_, v, t, d)| 12 * u64::from(v) + 12 * u64::from(t) + d).sum()
}

/// The index of a box file that exists and is whole (its length matches its header); `None`
/// otherwise, so that the box is made again.
pub fn read_index_if_complete(path: &Path) -> Option<BoxIndex> {
    let mut f = std::fs::File::open(path).ok()?;
    let len = f.metadata().ok()?.len();
    let h = read_header(&mut f).ok()?;
    (h.len + body_len(&h.rows) == len).then(|| BoxIndex { labels: h.rows.iter().map(|r| (r.0, r.2, r.3)).collect() })
}

/// Every label's float mesh in a box file.
pub fn read_meshes(path: &Path) -> Result<Vec<(u32, TriMesh)>, NgError> {
    let bytes = std::fs::read(path).map_err(file_error(path))?;
    let bad = |why: &str| NgError::Invalid(format!("{}: {why}", path.display()));
    let h = read_header(&mut &bytes[..]).map_err(file_error(path))?;
    if h.len + body_len(&h.rows) != bytes.len() as u64 {
        return Err(bad("the file is shorter or longer than its header says"));
    }
    let _ = (h.level, h.position);
    let mut at = h.len as usize;
    let mut out = Vec::with_capacity(h.rows.len());
    for &(label, nv, nt, draco) in &h.rows {
        let (nv, nt) = (nv as usize, nt as usize);
        let positions: Vec<Vec3> =
            bytes[at..at + 12 * nv].chunks_exact(12).map(|c| Vec3::new(f32_of(c), f32_of(&c[4..]), f32_of(&c[8..]))).collect();
        at += 12 * nv;
        let triangles: Vec<[u32; 3]> =
            bytes[at..at + 12 * nt].chunks_exact(12).map(|c| [u32_of(c), u32_of(&c[4..]), u32_of(&c[8..])]).collect();
        at += 12 * nt + draco as usize;
        if triangles.iter().flatten().any(|&v| v as usize >= nv) {
            return Err(bad(&format!("label {label}'s triangles name vertices it does not have")));
        }
        out.push((label, TriMesh { positions, normals: Vec::new(), triangles }));
    }
    Ok(out)
}

fn f32_of(b: &[u8]) -> f32 {
    f32::from_le_bytes([b[0], b[1], b[2], b[3]])
}

/// Where `label`'s Draco bytes lie in an open box file: `(offset, length)`.
pub fn draco_range(f: &mut std::fs::File, label: u32) -> io::Result<(u64, u64)> {
    use std::io::Seek;
    f.seek(io::SeekFrom::Start(0))?;
    let h = read_header(f)?;
    let mut at = h.len;
    for &(l, nv, nt, d) in &h.rows {
        at += 12 * u64::from(nv) + 12 * u64::from(nt);
        if l == label {
            return Ok((at, d));
        }
        at += d;
    }
    Err(io::Error::new(io::ErrorKind::NotFound, format!("segment {label} is not in this box")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_box_file_reads_back() {
        let mesh = TriMesh { positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y], normals: Vec::new(), triangles: vec![[0, 1, 2]] };
        let b = BoxMeshes { level: 2, position: [1, 2, 3], labels: vec![(5, mesh.clone(), vec![9; 7]), (8, mesh, vec![4; 3])] };
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.box");
        let mut bytes = Vec::new();
        write(&mut bytes, &b).unwrap();
        std::fs::write(&path, &bytes).unwrap();
        assert_eq!(read_index_if_complete(&path), Some(b.index()));
        let meshes = read_meshes(&path).unwrap();
        assert_eq!(meshes.len(), 2);
        assert_eq!(meshes[1].1.positions, b.labels[1].1.positions);
        let mut f = std::fs::File::open(&path).unwrap();
        let (at, len) = draco_range(&mut f, 8).unwrap();
        assert_eq!(&bytes[at as usize..(at + len) as usize], &[4, 4, 4]);
        std::fs::write(&path, &bytes[..bytes.len() - 1]).unwrap();
        assert_eq!(read_index_if_complete(&path), None);
    }
}
