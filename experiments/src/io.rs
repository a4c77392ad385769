//! Mesh files: an OBJ reader that names the file and line of any error, OBJ and binary
//! little-endian PLY writers, and atomic writes (temporary file, then rename), so a failed write
//! never leaves half a file behind.
//!
//! Why not `tobj` for reading: its errors do not say which line is malformed, and the CLI promises
//! that they do. OBJ's geometry subset (`v`, `f` with `v`, `v/vt`, `v//vn`, `v/vt/vn` and negative
//! indices, polygons fan-triangulated) is small enough to parse here; every other statement
//! (`vn`, `vt`, `o`, `g`, `s`, `usemtl`, `mtllib`, ...) is ignored.

use glam::Vec3;
use isolab_algorithms::TriMesh;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Errors reading or writing mesh files.
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    /// The file could not be read.
    #[error("cannot read '{path}': {source}")]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The file could not be written.
    #[error("cannot write '{path}': {source}")]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A line of an OBJ file is malformed.
    #[error("{path}:{line}: {reason}")]
    Malformed {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// The file has no faces.
    #[error("'{path}' contains no faces ({vertices} vertices, 0 triangles)")]
    Empty {
        /// The file.
        path: PathBuf,
        /// Vertices it had.
        vertices: usize,
    },
    /// The output extension is not one we write.
    #[error("cannot write '{path}': unknown extension (meshes: .obj or .ply; pictures: .png or .gif)")]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
}

/// Which vertex coordinates an OBJ reader accepts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Coordinates {
    /// Only finite coordinates; NaN or infinity is an error naming the line (for fields).
    Finite,
    /// Any, so a measuring tool can report NaN vertices instead of refusing the file.
    Any,
}

/// Reads the triangles of an OBJ file.
pub fn read_obj(path: &Path, coordinates: Coordinates) -> Result<TriMesh, IoError> {
    let text = std::fs::read(path).map_err(|source| IoError::Read { path: path.into(), source })?;
    let text = String::from_utf8_lossy(&text);
    parse_obj(&text, path, coordinates)
}

/// Parses OBJ text; `path` is only used in error messages.
pub fn parse_obj(text: &str, path: &Path, coordinates: Coordinates) -> Result<TriMesh, IoError> {
    let mut mesh = TriMesh::default();
    let malformed = |line: usize, reason: String| IoError::Malformed { path: path.into(), line, reason };
    let mut face = Vec::with_capacity(8);
    for (n, raw) in text.lines().enumerate() {
        let line = n + 1;
        let content = raw.split('#').next().unwrap_or("").trim();
        let mut words = content.split_whitespace();
        match words.next() {
            Some("v") => {
                let mut xyz = [0.0f32; 3];
                for (k, c) in xyz.iter_mut().enumerate() {
                    let w = words.next().ok_or_else(|| malformed(line, format!("vertex has {k} coordinates, expected 3")))?;
                    *c = w.parse().map_err(|_| malformed(line, format!("'{w}' is not a number")))?;
                    if !c.is_finite() && coordinates == Coordinates::Finite {
                        return Err(malformed(line, format!("coordinate '{w}' is not finite")));
                    }
                }
                mesh.positions.push(Vec3::from(xyz));
            }
            Some("f") => {
                face.clear();
                for w in words {
                    let first = w.split('/').next().unwrap_or("");
                    let i: i64 = first.parse().map_err(|_| malformed(line, format!("face index '{w}' is not an integer")))?;
                    let count = mesh.positions.len() as i64;
                    let resolved = if i > 0 { i - 1 } else { count + i };
                    if i == 0 || resolved < 0 || resolved >= count {
                        return Err(malformed(line, format!("face index {i} is out of range: {count} vertices defined so far")));
                    }
                    face.push(resolved as u32);
                }
                if face.len() < 3 {
                    return Err(malformed(line, format!("face has {} vertices, at least 3 are needed", face.len())));
                }
                for k in 1..face.len() - 1 {
                    mesh.triangles.push([face[0], face[k], face[k + 1]]);
                }
            }
            _ => {}
        }
    }
    if mesh.triangles.is_empty() {
        return Err(IoError::Empty { path: path.into(), vertices: mesh.positions.len() });
    }
    Ok(mesh)
}

/// Writes `path` atomically: `write` fills a temporary file beside it, which is renamed over
/// `path` only when everything succeeded; on any failure the temporary file is removed.
///
/// A path that exists and is not a regular file (`/dev/null`, a FIFO, a terminal) is written
/// directly: renaming over it would replace the device with a file. (Writing `-m /dev/null`
/// once did exactly that here, and every later reader of `/dev/null` on the machine got our
/// JSON, the compiler's probes included.)
pub fn write_atomic(path: &Path, write: impl FnOnce(&mut BufWriter<File>) -> std::io::Result<()>) -> Result<(), IoError> {
    let err = |source| IoError::Write { path: path.into(), source };
    if std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir()) {
        let result = (|| {
            let mut w = BufWriter::new(std::fs::OpenOptions::new().write(true).open(path)?);
            write(&mut w)?;
            w.flush()
        })();
        return result.map_err(err);
    }
    let name = path.file_name().ok_or_else(|| err(std::io::Error::new(std::io::ErrorKind::InvalidInput, "not a file name")))?;
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(format!(".{}.tmp", std::process::id()));
    let tmp = path.with_file_name(tmp_name);
    let result = (|| {
        let mut w = BufWriter::new(File::create(&tmp)?);
        write(&mut w)?;
        let file = w.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(err)
}

/// Writes a mesh as OBJ or binary little-endian PLY, chosen by the extension.
pub fn write_mesh(path: &Path, mesh: &TriMesh) -> Result<(), IoError> {
    write_mesh_coloured(path, mesh, None)
}

/// Writes a mesh with optional per-vertex colours (materials): OBJ as `v x y z r g b` (the
/// common extension MeshLab, Blender and trimesh read), PLY as `uchar red green blue`.
pub fn write_mesh_coloured(path: &Path, mesh: &TriMesh, colours: Option<&[[u8; 3]]>) -> Result<(), IoError> {
    let colours = colours.filter(|c| c.len() == mesh.positions.len());
    match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some("obj") => write_atomic(path, |w| write_obj_coloured(w, mesh, colours)),
        Some("ply") => write_atomic(path, |w| write_ply_coloured(w, mesh, colours)),
        _ => Err(IoError::UnknownFormat { path: path.into() }),
    }
}

/// Writes tetrahedra as a legacy ASCII VTK unstructured grid (cell type 10), which ParaView,
/// VisIt, meshio and VTK itself open.
pub fn write_vtk_tets(path: &Path, mesh: &isolab_algorithms::TetMesh) -> Result<(), IoError> {
    write_atomic(path, |w| {
        writeln!(w, "# vtk DataFile Version 3.0\nisolab tetrahedra\nASCII\nDATASET UNSTRUCTURED_GRID")?;
        writeln!(w, "POINTS {} float", mesh.positions.len())?;
        for p in &mesh.positions {
            writeln!(w, "{} {} {}", p.x, p.y, p.z)?;
        }
        writeln!(w, "CELLS {} {}", mesh.tetrahedra.len(), 5 * mesh.tetrahedra.len())?;
        for t in &mesh.tetrahedra {
            writeln!(w, "4 {} {} {} {}", t[0], t[1], t[2], t[3])?;
        }
        writeln!(w, "CELL_TYPES {}", mesh.tetrahedra.len())?;
        for _ in &mesh.tetrahedra {
            writeln!(w, "10")?;
        }
        Ok(())
    })
}

/// The path of the tetrahedra written beside a surface output: the same stem with `.vtk`.
pub fn tetrahedra_path(surface: &Path) -> std::path::PathBuf {
    surface.with_extension("vtk")
}

/// OBJ text: `v`, `vn` (when normals exist) and `f` lines, 1-based.
pub fn write_obj(w: &mut impl Write, mesh: &TriMesh) -> std::io::Result<()> {
    write_obj_coloured(w, mesh, None)
}

/// OBJ with optional vertex colours (`v x y z r g b`, components in [0, 1]).
pub fn write_obj_coloured(w: &mut impl Write, mesh: &TriMesh, colours: Option<&[[u8; 3]]>) -> std::io::Result<()> {
    writeln!(w, "# isolab: {} vertices, {} triangles", mesh.positions.len(), mesh.triangles.len())?;
    for (i, p) in mesh.positions.iter().enumerate() {
        match colours {
            Some(c) => {
                let [r, g, b] = c[i].map(|v| f32::from(v) / 255.0);
                writeln!(w, "v {} {} {} {r:.4} {g:.4} {b:.4}", p.x, p.y, p.z)?
            }
            None => writeln!(w, "v {} {} {}", p.x, p.y, p.z)?,
        }
    }
    let normals = mesh.normals.len() == mesh.positions.len() && !mesh.normals.is_empty();
    if normals {
        for n in &mesh.normals {
            writeln!(w, "vn {} {} {}", n.x, n.y, n.z)?;
        }
    }
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| i + 1);
        if normals {
            writeln!(w, "f {a}//{a} {b}//{b} {c}//{c}")?;
        } else {
            writeln!(w, "f {a} {b} {c}")?;
        }
    }
    Ok(())
}

/// Binary little-endian PLY: float x y z (and nx ny nz), faces as `uchar int` lists.
pub fn write_ply(w: &mut impl Write, mesh: &TriMesh) -> std::io::Result<()> {
    write_ply_coloured(w, mesh, None)
}

/// Binary PLY with optional `uchar red green blue` vertex colours after the floats.
pub fn write_ply_coloured(w: &mut impl Write, mesh: &TriMesh, colours: Option<&[[u8; 3]]>) -> std::io::Result<()> {
    let normals = mesh.normals.len() == mesh.positions.len() && !mesh.normals.is_empty();
    writeln!(w, "ply\nformat binary_little_endian 1.0\ncomment isolab")?;
    writeln!(w, "element vertex {}", mesh.positions.len())?;
    writeln!(w, "property float x\nproperty float y\nproperty float z")?;
    if normals {
        writeln!(w, "property float nx\nproperty float ny\nproperty float nz")?;
    }
    if colours.is_some() {
        writeln!(w, "property uchar red\nproperty uchar green\nproperty uchar blue")?;
    }
    writeln!(w, "element face {}\nproperty list uchar int vertex_indices\nend_header", mesh.triangles.len())?;
    for (i, p) in mesh.positions.iter().enumerate() {
        for c in p.to_array() {
            w.write_all(&c.to_le_bytes())?;
        }
        if normals {
            for c in mesh.normals[i].to_array() {
                w.write_all(&c.to_le_bytes())?;
            }
        }
        if let Some(c) = colours {
            w.write_all(&c[i])?;
        }
    }
    for t in &mesh.triangles {
        w.write_all(&[3u8])?;
        for &i in t {
            w.write_all(&(i as i32).to_le_bytes())?;
        }
    }
    Ok(())
}

/// Reads a binary little-endian PLY written by [`write_ply`] (or any with float xyz first and
/// triangle faces), so `isolab metrics` accepts what `isolab extract` writes.
pub fn read_ply(path: &Path) -> Result<TriMesh, IoError> {
    let bytes = std::fs::read(path).map_err(|source| IoError::Read { path: path.into(), source })?;
    let bad = |reason: &str| IoError::Malformed { path: path.into(), line: 0, reason: reason.into() };
    let end = bytes.windows(11).position(|w| w == b"end_header\n").ok_or_else(|| bad("no 'end_header' line"))? + 11;
    let header = std::str::from_utf8(&bytes[..end]).map_err(|_| bad("header is not text"))?;
    if !header.contains("format binary_little_endian") {
        return Err(bad("only binary_little_endian PLY is read"));
    }
    let (mut nv, mut nf, mut vprops, mut vbytes, mut in_vertex) = (0usize, 0usize, 0usize, 0usize, false);
    for (k, l) in header.lines().enumerate() {
        let words: Vec<&str> = l.split_whitespace().collect();
        match words.as_slice() {
            ["element", "vertex", n] => {
                nv = n.parse().map_err(|_| IoError::Malformed {
                    path: path.into(),
                    line: k + 1,
                    reason: "bad vertex count".into(),
                })?;
                in_vertex = true;
            }
            ["element", "face", n] => {
                nf = n.parse().map_err(|_| IoError::Malformed {
                    path: path.into(),
                    line: k + 1,
                    reason: "bad face count".into(),
                })?;
                in_vertex = false;
            }
            ["property", "float", _] if in_vertex && vbytes == 4 * vprops => {
                vprops += 1;
                vbytes += 4;
            }
            ["property", "uchar", _] if in_vertex => vbytes += 1,
            ["property", t, _] if in_vertex => {
                return Err(IoError::Malformed {
                    path: path.into(),
                    line: k + 1,
                    reason: format!("vertex property type '{t}' unsupported (float, then uchar colours)"),
                })
            }
            _ => {}
        }
    }
    if vprops < 3 {
        return Err(bad("vertices need float x, y, z"));
    }
    let mut mesh = TriMesh::default();
    let mut at = end;
    let mut take = |n: usize| -> Result<&[u8], IoError> {
        let s = bytes.get(at..at + n).ok_or_else(|| bad("file ends early"))?;
        at += n;
        Ok(s)
    };
    for _ in 0..nv {
        let v = take(vbytes)?;
        let f = |i: usize| f32::from_le_bytes([v[4 * i], v[4 * i + 1], v[4 * i + 2], v[4 * i + 3]]);
        mesh.positions.push(Vec3::new(f(0), f(1), f(2)));
    }
    for _ in 0..nf {
        let n = take(1)?[0] as usize;
        let idx = take(4 * n)?;
        let ids: Vec<u32> =
            (0..n).map(|i| i32::from_le_bytes([idx[4 * i], idx[4 * i + 1], idx[4 * i + 2], idx[4 * i + 3]]) as u32).collect();
        if ids.iter().any(|&i| i as usize >= nv) || n < 3 {
            return Err(bad("face refers to a missing vertex"));
        }
        for k in 1..n - 1 {
            mesh.triangles.push([ids[0], ids[k], ids[k + 1]]);
        }
    }
    Ok(mesh)
}

/// Reads `.obj` or `.ply` by extension, accepting any coordinates (for measuring).
pub fn read_mesh(path: &Path) -> Result<TriMesh, IoError> {
    match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some("ply") => read_ply(path),
        _ => read_obj(path, Coordinates::Any),
    }
}

/// Writes sampled values as raw little-endian f32 in the lattice's index order (x fastest; a BCC
/// lattice's corner grid, then its centres) to `path`, and `path.json` with `lattice`, `dims`,
/// `origin`, `spacing` and `iso`, so a peer library can read the very same samples.
pub fn write_samples(path: &Path, samples: &isolab_algorithms::Samples) -> Result<(), IoError> {
    write_atomic(path, |w| {
        for v in samples.values() {
            w.write_all(&v.to_le_bytes())?;
        }
        Ok(())
    })?;
    let g = samples.grid();
    let header = serde_json::json!({
        "lattice": samples.lattice().kind(),
        "dims": g.dims,
        "origin": g.origin.to_array(),
        "spacing": g.spacing,
        "iso": samples.iso(),
    });
    let mut json = path.as_os_str().to_owned();
    json.push(".json");
    write_atomic(Path::new(&json), |w| serde_json::to_writer_pretty(&mut *w, &header).map_err(std::io::Error::other))
}

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
        Ok(Self { path: path.into(), parts, vertices, faces, counts: [0, 0] })
    }

    /// Writes the PLY (header, vertices, faces) to the target and returns its size in bytes.
    pub fn finish(mut self) -> Result<u64, IoError> {
        let err = |source: std::io::Error| IoError::Write { path: self.path.clone(), source };
        self.vertices.flush().map_err(err)?;
        self.faces.flush().map_err(err)?;
        let (counts, parts) = (self.counts, self.parts.clone());
        write_atomic(&self.path, |w| {
            writeln!(w, "ply\nformat binary_little_endian 1.0\ncomment isolab streamed world")?;
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

/// The process's peak resident memory (`VmHWM`), MiB, where the OS reports it.
pub fn peak_rss_mib() -> Option<f64> {
    proc_status_kib("VmHWM:").map(|k| k as f64 / 1024.0)
}

/// The process's resident memory now (`VmRSS`), MiB.
pub fn rss_mib() -> Option<f64> {
    proc_status_kib("VmRSS:").map(|k| k as f64 / 1024.0)
}

/// Resets the peak resident memory to the current one (Linux `clear_refs` 5); false if the OS
/// does not allow it.
pub fn reset_peak_rss() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

fn proc_status_kib(key: &str) -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    status.lines().find(|l| l.starts_with(key))?.split_whitespace().nth(1)?.parse().ok()
}

#[cfg(test)]
mod tests {
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
        let back = read_ply(&path).unwrap();
        assert_eq!((back.positions.len(), back.triangles.len()), (4, 3));
        assert_eq!(back.triangles[2], [1, 3, 2]);
        assert_eq!(bytes, std::fs::metadata(&path).unwrap().len());
        let other = dir.path().join("unfinished.ply");
        drop(PlyStream::create(&other).unwrap());
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(left, vec![std::ffi::OsString::from("world.ply")], "no scratch parts, no half-written file");
    }

    use super::*;

    #[cfg(unix)]
    #[test]
    fn writing_to_dev_null_keeps_it_a_device() {
        use std::os::unix::fs::FileTypeExt;
        write_atomic(Path::new("/dev/null"), |w| w.write_all(b"{}")).unwrap();
        let kind = std::fs::metadata("/dev/null").unwrap().file_type();
        assert!(kind.is_char_device(), "/dev/null was replaced by a regular file");
    }

    #[test]
    fn obj_errors_name_the_line() {
        let p = Path::new("m.obj");
        let e = parse_obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", p, Coordinates::Finite).unwrap_err().to_string();
        assert!(e.starts_with("m.obj:4:"), "{e}");
        let e = parse_obj("v 0 0 0\nv 1 zero 0\n", p, Coordinates::Finite).unwrap_err().to_string();
        assert!(e.starts_with("m.obj:2:"), "{e}");
        let e = parse_obj("v 0 0 0\nf 1 2 3\n", p, Coordinates::Finite).unwrap_err().to_string();
        assert!(e.contains(":2:") && e.contains("out of range"), "{e}");
        assert!(matches!(parse_obj("# nothing\n", p, Coordinates::Finite), Err(IoError::Empty { .. })));
    }

    #[test]
    fn obj_polygons_and_negative_indices() {
        let m = parse_obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1/1/1 2//2 3 -1\n", Path::new("q.obj"), Coordinates::Finite)
            .unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    }

    #[test]
    fn round_trips_and_atomic_failure() {
        let dir = tempfile::tempdir().unwrap();
        let mesh = parse_obj(
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
            Path::new("t.obj"),
            Coordinates::Finite,
        )
        .unwrap();
        for ext in ["obj", "ply"] {
            let p = dir.path().join(format!("t.{ext}"));
            write_mesh(&p, &mesh).unwrap();
            let back = read_mesh(&p).unwrap();
            assert_eq!(back.triangles, mesh.triangles);
            assert_eq!(back.positions, mesh.positions);
        }
        let missing = dir.path().join("no/such/dir/t.obj");
        assert!(matches!(write_mesh(&missing, &mesh), Err(IoError::Write { .. })));
        // A failing writer leaves nothing behind.
        let p = dir.path().join("fail.obj");
        let r = write_atomic(&p, |_| Err(std::io::Error::other("boom")));
        assert!(r.is_err());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
    }
}
