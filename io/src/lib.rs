//! Files: meshes in and out (one module per format), volumes in ([`volume`]), and atomic writes
//! (temporary file, then rename), so a failed write never leaves half a file behind.
//!
//! | format | read | write |
//! |---|---|---|
//! | OBJ ([`obj`]) | `v`/`f`, polygons, negative indices; errors name the line | positions, normals, `v x y z r g b` colours |
//! | PLY ([`ply`]) | ascii and binary (both endians), any property and list types | binary little-endian, normals, colours |
//! | STL ([`stl`]) | ascii and binary, vertices welded | binary |
//! | glTF 2.0 ([`gltf`]) | `.glb`, `.gltf` (embedded or external buffers) | `.glb`, `.gltf` with an embedded buffer; normals, colours |
//! | VTK legacy ([`vtk`]) | | tetrahedra |
//! | Gmsh MSH 2.2 ([`msh`]) | | labelled tetrahedra |
//! | volumes ([`volume`]) | NIfTI-1/2, NRRD, MetaImage, the raw + JSON grid of `--samples-out` | the raw + JSON grid |
//!
//! Every reader has a `parse_*` form taking bytes (and the path only to name it in errors), so
//! readers can be fed any bytes in tests; none panics on malformed input.

pub mod choice;
pub mod gltf;
pub mod msh;
pub mod neuroglancer;
pub mod obj;
pub mod ply;
pub mod stl;
pub mod stream;
pub mod volume;
pub mod vtk;

pub use choice::UnknownChoice;
pub use msh::write_msh_labelled_tets;
pub use obj::{parse_obj, write_obj_coloured};
pub use ply::{parse_ply, write_ply, write_ply_coloured};
pub use stream::PlyStream;
pub use volume::samples::write_samples;
pub use vtk::{tetrahedra_path, write_vtk_labelled_tets, write_vtk_tets};

use isolab_algorithms::TriMesh;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Errors reading or writing files.
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
    /// A line of a text file is malformed.
    #[error("{path}:{line}: {reason}")]
    Malformed {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// A file's content is invalid (binary formats, where there is no line to name).
    #[error("'{path}': {reason}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong, with the byte offset or element where there is one.
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
    #[error("cannot write '{path}': unknown extension (meshes: .obj, .ply, .stl, .glb or .gltf; pictures: .png or .gif)")]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
}

/// Which vertex coordinates a reader accepts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Coordinates {
    /// Only finite coordinates; NaN or infinity is an error naming the line (for fields).
    Finite,
    /// Any, so a measuring tool can report NaN vertices instead of refusing the file.
    Any,
}

/// A mesh file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    /// Wavefront OBJ.
    Obj,
    /// Stanford PLY.
    Ply,
    /// STL.
    Stl,
    /// Binary glTF.
    Glb,
    /// glTF JSON.
    Gltf,
}

impl MeshFormat {
    /// The format's name as reports give it: `OBJ`, `PLY`, `STL`, `glTF`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Obj => "OBJ",
            Self::Ply => "PLY",
            Self::Stl => "STL",
            Self::Glb | Self::Gltf => "glTF",
        }
    }

    /// The format an output path's extension names.
    pub fn from_extension(path: &Path) -> Option<Self> {
        Some(match extension(path).as_deref()? {
            "obj" => Self::Obj,
            "ply" => Self::Ply,
            "stl" => Self::Stl,
            "glb" => Self::Glb,
            "gltf" => Self::Gltf,
            _ => return None,
        })
    }

    /// The format of a file to read: its content's signature where it has one (`ply`, `glTF`,
    /// a binary STL's exact size), then its extension, then OBJ.
    pub fn detect(bytes: &[u8], path: &Path) -> Self {
        if bytes.starts_with(b"ply\n") || bytes.starts_with(b"ply\r\n") {
            return Self::Ply;
        }
        if bytes.starts_with(b"glTF") {
            return Self::Glb;
        }
        match Self::from_extension(path) {
            Some(f) => f,
            None if stl::is_binary_stl(bytes) || bytes.starts_with(b"solid") => Self::Stl,
            None if bytes.trim_ascii_start().starts_with(b"{") => Self::Gltf,
            None => Self::Obj,
        }
    }
}

/// The lower-case extension of `path`.
pub fn extension(path: &Path) -> Option<String> {
    path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase)
}

/// Reads a whole file.
pub fn read_bytes(path: &Path) -> Result<Vec<u8>, IoError> {
    std::fs::read(path).map_err(|source| IoError::Read { path: path.into(), source })
}

/// A word from a file, fit for an error message: at most 40 characters, control and
/// non-ASCII bytes escaped (binary garbage stays one short line).
pub fn shown(word: &str) -> String {
    let mut out: String = word.chars().take(40).flat_map(char::escape_default).collect();
    if word.chars().count() > 40 {
        out.push_str("...");
    }
    out
}

/// Reads any mesh file we read, accepting any coordinates (for measuring).
pub fn read_mesh(path: &Path) -> Result<TriMesh, IoError> {
    read_mesh_with(path, Coordinates::Any)
}

/// Reads any mesh file we read (format from its content and extension, [`MeshFormat::detect`]).
pub fn read_mesh_with(path: &Path, coordinates: Coordinates) -> Result<TriMesh, IoError> {
    let bytes = read_bytes(path)?;
    match MeshFormat::detect(&bytes, path) {
        MeshFormat::Gltf | MeshFormat::Glb => finite_if_asked(gltf::parse_gltf_beside(&bytes, path)?, path, coordinates),
        _ => parse_mesh(&bytes, path, coordinates),
    }
}

/// glTF positions are binary floats with no line to name: under [`Coordinates::Finite`] a
/// non-finite one is an error naming the vertex.
fn finite_if_asked(mesh: TriMesh, path: &Path, coordinates: Coordinates) -> Result<TriMesh, IoError> {
    if coordinates == Coordinates::Finite {
        if let Some(v) = mesh.positions.iter().position(|p| !p.is_finite()) {
            return Err(IoError::Invalid {
                path: path.into(),
                reason: format!("vertex {v} has a coordinate that is not finite ({:?})", mesh.positions[v].to_array()),
            });
        }
    }
    Ok(mesh)
}

/// Parses mesh bytes of any format we read; glTF buffers must be in the file (GLB or data URIs).
pub fn parse_mesh(bytes: &[u8], path: &Path, coordinates: Coordinates) -> Result<TriMesh, IoError> {
    match MeshFormat::detect(bytes, path) {
        MeshFormat::Obj => {
            // Text with stray non-UTF-8 bytes (a Latin-1 comment) is still OBJ; a NUL byte is not.
            if let Some(at) = bytes.iter().position(|&b| b == 0) {
                let line = bytes[..at].iter().filter(|&&b| b == b'\n').count() + 1;
                return Err(IoError::Malformed {
                    path: path.into(),
                    line,
                    reason: "binary data (a NUL byte): not an OBJ file, and not PLY, STL or glTF by its content".into(),
                });
            }
            parse_obj(&String::from_utf8_lossy(bytes), path, coordinates)
        }
        MeshFormat::Ply => parse_ply(bytes, path, coordinates),
        MeshFormat::Stl => stl::parse_stl(bytes, path, coordinates),
        MeshFormat::Glb | MeshFormat::Gltf => finite_if_asked(
            gltf::parse_gltf(bytes, path, &|uri: &str| Err(format!("external buffer '{uri}'")))?,
            path,
            coordinates,
        ),
    }
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

/// The mesh as its triangles' corner positions, in order (what survives any format, STL's
/// renumbering of vertices included).
pub fn soup(mesh: &TriMesh) -> Vec<[glam::Vec3; 3]> {
    mesh.triangles.iter().map(|t| t.map(|i| mesh.positions[i as usize])).collect()
}

/// What goes into a written mesh besides its geometry.
#[derive(Clone, Copy, Debug, Default)]
pub struct MeshExtras<'a> {
    /// Per-vertex colours (materials); ignored unless one per vertex. STL has none.
    pub colours: Option<&'a [[u8; 3]]>,
    /// The coordinate system, written where the format has a place 3D Slicer reads
    /// (`SPACE=RAS` in an OBJ or PLY comment, the STL header, the VTK title).
    pub space: Option<&'a str>,
}

/// Writes a mesh in the format its extension names.
pub fn write_mesh(path: &Path, mesh: &TriMesh) -> Result<(), IoError> {
    write_mesh_with(path, mesh, MeshExtras::default())
}

/// Writes a mesh in the format its extension names, with `extras`: colours as `v x y z r g b`
/// in OBJ (what MeshLab, Blender and trimesh read), `uchar red green blue` in PLY, `COLOR_0` in
/// glTF.
pub fn write_mesh_with(path: &Path, mesh: &TriMesh, extras: MeshExtras) -> Result<(), IoError> {
    let colours = extras.colours.filter(|c| c.len() == mesh.positions.len());
    let generator = concat!("isolab ", env!("CARGO_PKG_VERSION"));
    match MeshFormat::from_extension(path) {
        Some(MeshFormat::Obj) => write_atomic(path, |w| write_obj_coloured(w, mesh, colours, extras.space)),
        Some(MeshFormat::Ply) => write_atomic(path, |w| write_ply_coloured(w, mesh, colours, extras.space)),
        Some(MeshFormat::Stl) => {
            let header = match extras.space {
                Some(space) => format!("isolab binary STL SPACE={space}"),
                None => "isolab binary STL".to_owned(),
            };
            write_atomic(path, |w| stl::write_stl(w, mesh, &header))
        }
        Some(MeshFormat::Glb) => write_atomic(path, |w| gltf::write_gltf(w, mesh, colours, gltf::Container::Binary, generator)),
        Some(MeshFormat::Gltf) => {
            write_atomic(path, |w| gltf::write_gltf(w, mesh, colours, gltf::Container::Embedded, generator))
        }
        None => Err(IoError::UnknownFormat { path: path.into() }),
    }
}

/// Writes labelled tetrahedra (`tetrahedra` index `positions`, one label each) in the format
/// `path`'s extension names: `.vtk` ([`write_vtk_labelled_tets`], `space` in its title) or
/// `.msh` ([`write_msh_labelled_tets`]). Another extension is an `InvalidInput` write error
/// naming the two, and nothing is written.
pub fn write_labelled_tets(
    path: &Path,
    positions: &[isolab_algorithms::Vec3],
    tetrahedra: &[[u32; 4]],
    labels: &[u32],
    space: Option<&str>,
) -> Result<(), IoError> {
    match extension(path).as_deref() {
        Some("vtk") => write_vtk_labelled_tets(path, positions, tetrahedra, labels, space),
        Some("msh") => write_msh_labelled_tets(path, positions, tetrahedra, labels),
        _ => Err(IoError::Write {
            path: path.into(),
            source: std::io::Error::new(std::io::ErrorKind::InvalidInput, "tetrahedra are written as .vtk or .msh"),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[cfg(unix)]
    #[test]
    fn writing_to_dev_null_keeps_it_a_device() {
        use std::os::unix::fs::FileTypeExt;
        write_atomic(Path::new("/dev/null"), |w| w.write_all(b"{}")).unwrap();
        let kind = std::fs::metadata("/dev/null").unwrap().file_type();
        assert!(kind.is_char_device(), "/dev/null was replaced by a regular file");
    }

    fn tetrahedron() -> TriMesh {
        // The shared fixture, skewed so that no coordinate is trivially 0 or 1 everywhere.
        let mut t = TriMesh::unit_tetrahedron();
        t.positions = vec![Vec3::ZERO, Vec3::new(1.5, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.25), Vec3::new(0.0, 0.0, 1.0)];
        t
    }

    #[test]
    fn every_format_round_trips_and_a_failed_write_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let mesh = tetrahedron();
        let colours = [[200, 10, 10], [10, 200, 10], [10, 10, 200], [90, 90, 90]];
        for ext in ["obj", "ply", "stl", "glb", "gltf"] {
            let p = dir.path().join(format!("t.{ext}"));
            write_mesh_with(&p, &mesh, MeshExtras { colours: Some(&colours), space: Some("RAS") }).unwrap();
            let back = read_mesh(&p).unwrap();
            assert_eq!(soup(&back), soup(&mesh), "{ext}");
            if ext != "stl" {
                assert_eq!(back.positions, mesh.positions, "{ext}: vertex order");
            }
        }
        let missing = dir.path().join("no/such/dir/t.obj");
        assert!(matches!(write_mesh(&missing, &mesh), Err(IoError::Write { .. })));
        assert!(matches!(write_mesh(&dir.path().join("t.xyz"), &mesh), Err(IoError::UnknownFormat { .. })));
        let tets = dir.path().join("tets.obj");
        let err = write_labelled_tets(&tets, &mesh.positions, &[], &[], None).unwrap_err().to_string();
        assert!(err.contains(".vtk or .msh") && err.contains("tets.obj") && !tets.exists(), "{err}");
        let p = dir.path().join("fail.obj");
        let r = write_atomic(&p, |_| Err(std::io::Error::other("boom")));
        assert!(r.is_err());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 5);
    }

    #[test]
    fn content_decides_the_format_before_the_extension() {
        let mut ply = Vec::new();
        write_ply(&mut ply, &tetrahedron()).unwrap();
        // A binary PLY named .obj is still read as PLY, not as OBJ garbage.
        let m = parse_mesh(&ply, Path::new("horse.obj"), Coordinates::Finite).unwrap();
        assert_eq!(m.triangles.len(), 4);
        assert_eq!(MeshFormat::detect(b"v 0 0 0\n", Path::new("x")), MeshFormat::Obj);
        assert_eq!(MeshFormat::detect(b"solid x\n", Path::new("x")), MeshFormat::Stl);
        assert_eq!(shown("ab\u{1}c"), "ab\\u{1}c");
        assert!(shown(&"x".repeat(100)).ends_with("..."));
    }
}
