//! Files as every front end reads and writes them, so the CLI and the Python package say and do
//! the same: what a path holds, a volume or a mesh ([`read_file`]), a mesh where a mesh is
//! expected ([`read_mesh_file`], naming a volume given instead), outputs checked before any
//! work ([`check_outputs`]), and a run's meshes written: the surface in the format its extension
//! names, vertex colours from materials, the space tag of anatomical volumes, and a volume
//! extractor's tetrahedra beside it as `.vtk` ([`write_meshes`], [`RunOutcome::write_meshes`]).

use crate::{RunError, RunOutcome};
use isolab_algorithms::{TetMesh, TriMesh};
use isolab_io::volume::{self, VolumeFile, VolumeOptions};
use isolab_io::{self as io, Coordinates, IoError, MeshFormat};
use std::path::Path;

/// What a file holds.
pub enum FileContents {
    /// A volume (NIfTI, NRRD, MetaImage, isolab's grid, a zarr store).
    Volume(VolumeFile),
    /// A mesh (OBJ, PLY, STL, glTF) and its format.
    Mesh(TriMesh, MeshFormat),
}

/// Reads a volume or a mesh file, whichever `path` holds: a zarr store or a volume by its
/// signature or extension ([`volume::detect`]), a mesh otherwise (its format from content and
/// extension, [`MeshFormat::detect`]). `coordinates` says whether a mesh may hold non-finite
/// vertices (a measuring tool reports them; a field refuses them).
pub fn read_file(path: &Path, options: VolumeOptions, coordinates: Coordinates) -> Result<FileContents, RunError> {
    if volume::zarr::is_zarr(path) {
        return Ok(FileContents::Volume(volume::read_volume(path, options)?));
    }
    let bytes = io::read_bytes(path)?;
    if volume::detect(path, &bytes).is_some() {
        return Ok(FileContents::Volume(volume::read_volume_bytes(&bytes, path, options)?));
    }
    let format = MeshFormat::detect(&bytes, path);
    let mesh = match format {
        MeshFormat::Glb | MeshFormat::Gltf => {
            let mesh = io::gltf::parse_gltf_beside(&bytes, path)?;
            check_finite(mesh, path, coordinates)?
        }
        _ => io::parse_mesh(&bytes, path, coordinates)?,
    };
    Ok(FileContents::Mesh(mesh, format))
}

/// glTF positions are binary floats with no line to name: under [`Coordinates::Finite`] a
/// non-finite one is an error naming the vertex.
fn check_finite(mesh: TriMesh, path: &Path, coordinates: Coordinates) -> Result<TriMesh, IoError> {
    match mesh.positions.iter().position(|p| !p.is_finite()).filter(|_| coordinates == Coordinates::Finite) {
        Some(v) => Err(IoError::Invalid {
            path: path.into(),
            reason: format!("vertex {v} has a coordinate that is not finite ({:?})", mesh.positions[v].to_array()),
        }),
        None => Ok(mesh),
    }
}

/// Reads a mesh file for measuring or rendering (any coordinates), refusing a volume file with
/// what to do instead.
pub fn read_mesh_file(path: &Path) -> Result<TriMesh, RunError> {
    match read_file(path, VolumeOptions::default(), Coordinates::Any)? {
        FileContents::Mesh(mesh, _) => Ok(mesh),
        FileContents::Volume(_) => Err(IoError::Invalid {
            path: path.into(),
            reason: "is a volume, not a mesh: mesh it first (`isolab extract -f FILE -o mesh.ply`, or isolab.extract in \
                     Python)"
                .into(),
        }
        .into()),
    }
}

/// Refuses, before any work, a mesh output whose extension names no mesh format, and any
/// output (`-` is stdout) whose folder does not exist.
pub fn check_outputs<'a>(mesh: Option<&'a Path>, others: impl IntoIterator<Item = &'a Path>) -> Result<(), RunError> {
    for path in mesh.into_iter().chain(others).filter(|p| p.as_os_str() != "-") {
        let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
        if !dir.is_dir() {
            let source = std::io::Error::new(std::io::ErrorKind::NotFound, "directory does not exist");
            return Err(IoError::Write { path: path.into(), source }.into());
        }
    }
    if let Some(path) = mesh.filter(|p| MeshFormat::from_extension(p).is_none()) {
        return Err(IoError::UnknownFormat { path: path.into() }.into());
    }
    Ok(())
}

/// Writes a surface in the format `path`'s extension names, atomically, with each vertex's
/// material as its colour (`materials`: one per vertex, or empty) and the coordinate system's
/// tag (`space`: `RAS`, `LPS`), and `volume`'s tetrahedra, when it has any, beside it as `.vtk`
/// ([`io::tetrahedra_path`]). An unknown extension is refused before anything is written.
pub fn write_meshes(
    path: &Path,
    surface: &TriMesh,
    volume: &TetMesh,
    materials: &[u8],
    space: Option<&str>,
) -> Result<(), RunError> {
    if MeshFormat::from_extension(path).is_none() {
        return Err(IoError::UnknownFormat { path: path.into() }.into());
    }
    let colours: Vec<[u8; 3]> = materials.iter().map(|&m| isolab_algorithms::materials::colour(m)).collect();
    let extras = io::MeshExtras { colours: (!colours.is_empty()).then_some(colours.as_slice()), space };
    io::write_mesh_with(path, surface, extras)?;
    if !volume.tetrahedra.is_empty() {
        io::write_vtk_tets(&io::tetrahedra_path(path), volume, space)?;
    }
    Ok(())
}

impl RunOutcome {
    /// Writes the run's meshes as [`write_meshes`] does: the surface at `path`, coloured by
    /// material when the run gave materials, tagged with the space of an anatomical volume,
    /// and the tetrahedra beside it.
    pub fn write_meshes(&self, path: &Path) -> Result<(), RunError> {
        write_meshes(path, &self.extraction.surface, &self.extraction.volume, &self.vertex_materials, self.space_tag)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_is_read_as_what_it_holds_and_a_volume_is_refused_where_a_mesh_is_expected() {
        let dir = tempfile::tempdir().unwrap();
        let mesh = TriMesh::unit_tetrahedron();
        let obj = dir.path().join("t.obj");
        io::write_mesh(&obj, &mesh).unwrap();
        assert!(
            matches!(read_file(&obj, VolumeOptions::default(), Coordinates::Finite), Ok(FileContents::Mesh(m, MeshFormat::Obj)) if m.triangles.len() == 4)
        );
        let grid = dir.path().join("g.raw");
        let samples = isolab_algorithms::Samples::from_values(
            isolab_algorithms::Lattice::Cubic(isolab_algorithms::Grid {
                origin: glam::Vec3::ZERO,
                spacing: 1.0,
                dims: [2, 2, 2],
            }),
            vec![-1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0],
            0.0,
        )
        .unwrap();
        io::write_samples(&grid, &samples, None).unwrap();
        assert!(
            matches!(read_file(&grid, VolumeOptions::default(), Coordinates::Any), Ok(FileContents::Volume(v)) if v.volume.dims == [2, 2, 2])
        );
        // A mesh with its metrics beside it (`-o m.ply -m m.ply.json`) is still a mesh.
        let ply = dir.path().join("m.ply");
        io::write_mesh(&ply, &mesh).unwrap();
        std::fs::write(dir.path().join("m.ply.json"), "{}").unwrap();
        assert_eq!(read_mesh_file(&ply).expect("a mesh").triangles.len(), 4);
        let err = read_mesh_file(&grid).expect_err("a volume is not a mesh").to_string();
        assert!(err.contains("g.raw") && err.contains("is a volume, not a mesh"), "{err}");
    }

    #[test]
    fn outputs_are_checked_before_any_work() {
        let dir = tempfile::tempdir().unwrap();
        let good = dir.path().join("m.ply");
        assert!(check_outputs(Some(&good), [Path::new("-"), dir.path().join("r.json").as_path()]).is_ok());
        let err = check_outputs(Some(&dir.path().join("m.xyz")), []).unwrap_err().to_string();
        assert!(err.contains("m.xyz"), "{err}");
        let missing = dir.path().join("no-such-folder").join("r.json");
        let err = check_outputs(None, [missing.as_path()]).unwrap_err().to_string();
        assert!(err.contains("no-such-folder") && err.contains("directory does not exist"), "{err}");
    }

    #[test]
    fn meshes_are_written_with_colours_tags_and_tetrahedra_beside() {
        let dir = tempfile::tempdir().unwrap();
        let surface = TriMesh::unit_tetrahedron();
        let volume = TetMesh { positions: surface.positions.clone(), tetrahedra: vec![[0, 1, 2, 3]] };
        let path = dir.path().join("m.ply");
        write_meshes(&path, &surface, &volume, &[1, 1, 2, 2], Some("LPS")).unwrap();
        let text = String::from_utf8_lossy(&std::fs::read(&path).unwrap()).into_owned();
        assert!(text.contains("SPACE=LPS") && text.contains("property uchar red"), "{}", &text[..text.len().min(400)]);
        let tets = std::fs::read_to_string(io::tetrahedra_path(&path)).unwrap();
        assert!(tets.contains("CELLS 1 5"), "{tets}");
        let refused = dir.path().join("refused.txt");
        assert!(write_meshes(&refused, &surface, &volume, &[], None).is_err());
        assert!(!refused.exists() && !io::tetrahedra_path(&refused).exists());
    }
}
