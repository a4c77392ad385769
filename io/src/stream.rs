//! Streaming a binary PLY as a mesh is produced chunk by chunk (`large_world`), with no
//! half-written file on failure.

use super::{write_atomic, IoError};
use glam::Vec3;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

/// A binary PLY written as it streams in ([`isolab_algorithms::chunks::MeshSink`]): vertices and
/// faces go to two scratch files beside the target (PLY needs the counts in its header), and
/// [`PlyStream::finish`] writes the header and both parts into the target atomically. Dropping an
/// unfinished stream removes the scratch files, so a failure leaves no half-written mesh.
pub struct PlyStream {
    path: std::path::PathBuf,
    parts: [std::path::PathBuf; 2],
    vertices: BufWriter<File>,
    faces: BufWriter<File>,
    counts: [u64; 2],
    space: Option<&'static str>,
}

impl PlyStream {
    /// Starts streaming to `path`.
    pub fn create(path: &Path) -> Result<Self, IoError> {
        let part = |tag: &str| {
            let mut name = path.file_name().unwrap_or_default().to_os_string();
            name.push(format!(".{tag}.part"));
            path.with_file_name(name)
        };
        let parts = [part("vertices"), part("faces")];
        let open = |p: &Path| File::create(p).map(BufWriter::new).map_err(|source| IoError::Write { path: p.into(), source });
        let vertices = open(&parts[0])?;
        let faces = open(&parts[1]).inspect_err(|_| {
            let _ = std::fs::remove_file(&parts[0]);
        })?;
        Ok(Self { path: path.into(), parts, vertices, faces, counts: [0, 0], space: None })
    }

    /// Names the coordinate system in the header (`comment SPACE=RAS`, which 3D Slicer reads), as
    /// [`crate::write_mesh_with`] does for anatomical volumes.
    pub fn with_space(mut self, space: Option<&'static str>) -> Self {
        self.space = space;
        self
    }

    /// Writes the PLY (header, vertices, faces) to the target and returns its size in bytes.
    pub fn finish(mut self) -> Result<u64, IoError> {
        let err = |source: std::io::Error| IoError::Write { path: self.path.clone(), source };
        self.vertices.flush().map_err(err)?;
        self.faces.flush().map_err(err)?;
        let (counts, parts, space) = (self.counts, self.parts.clone(), self.space);
        write_atomic(&self.path, |w| {
            writeln!(w, "ply\nformat binary_little_endian 1.0\ncomment isolab streamed mesh")?;
            if let Some(space) = space {
                writeln!(w, "comment SPACE={space}")?;
            }
            writeln!(w, "element vertex {}\nproperty float x\nproperty float y\nproperty float z", counts[0])?;
            writeln!(w, "element face {}\nproperty list uchar int vertex_indices\nend_header", counts[1])?;
            for part in &parts {
                std::io::copy(&mut File::open(part)?, w)?;
            }
            Ok(())
        })?;
        std::fs::metadata(&self.path).map(|m| m.len()).map_err(|source| IoError::Write { path: self.path.clone(), source })
    }
}

impl Drop for PlyStream {
    fn drop(&mut self) {
        for part in &self.parts {
            let _ = std::fs::remove_file(part);
        }
    }
}

impl isolab_algorithms::chunks::MeshSink for PlyStream {
    fn vertices(&mut self, positions: &[Vec3]) -> std::io::Result<()> {
        for p in positions {
            for c in p.to_array() {
                self.vertices.write_all(&c.to_le_bytes())?;
            }
        }
        self.counts[0] += positions.len() as u64;
        Ok(())
    }

    fn triangles(&mut self, triangles: &[[u32; 3]]) -> std::io::Result<()> {
        for t in triangles {
            self.faces.write_all(&[3u8])?;
            for &i in t {
                self.faces.write_all(&(i as i32).to_le_bytes())?;
            }
        }
        self.counts[1] += triangles.len() as u64;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_streamed_ply_reads_back_and_an_unfinished_one_leaves_nothing() {
        use isolab_algorithms::chunks::MeshSink;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("world.ply");
        let mut s = PlyStream::create(&path).unwrap();
        s.vertices(&[Vec3::ZERO, Vec3::X, Vec3::Y]).unwrap();
        s.triangles(&[[0, 1, 2]]).unwrap();
        s.vertices(&[Vec3::Z]).unwrap();
        s.triangles(&[[0, 2, 3], [1, 3, 2]]).unwrap();
        let bytes = s.finish().unwrap();
        let back = crate::read_mesh(&path).unwrap();
        assert_eq!((back.positions.len(), back.triangles.len()), (4, 3));
        assert_eq!(back.triangles[2], [1, 3, 2]);
        assert_eq!(bytes, std::fs::metadata(&path).unwrap().len());
        let other = dir.path().join("unfinished.ply");
        drop(PlyStream::create(&other).unwrap());
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(left, vec![std::ffi::OsString::from("world.ply")], "no scratch parts, no half-written file");
    }
}
