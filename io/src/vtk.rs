//! Legacy VTK unstructured grids: the tetrahedra of volume extractors.

use super::{write_atomic, IoError};
use std::io::Write;
use std::path::Path;

/// Writes tetrahedra as a legacy ASCII VTK unstructured grid (cell type 10), which ParaView,
/// VisIt, meshio and VTK itself open; `space` goes into the title line (`SPACE=RAS`, which 3D
/// Slicer reads).
pub fn write_vtk_tets(path: &Path, mesh: &isolab_algorithms::TetMesh, space: Option<&str>) -> Result<(), IoError> {
    let title = space.map_or("isolab tetrahedra".to_owned(), |s| format!("isolab tetrahedra SPACE={s}"));
    write_atomic(path, |w| {
        writeln!(w, "# vtk DataFile Version 3.0\n{title}\nASCII\nDATASET UNSTRUCTURED_GRID")?;
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

/// Writes labelled tetrahedra (a label map's, from `lattice-cleaving`) as a legacy ASCII VTK
/// unstructured grid with the cell array `label` (ParaView colours by it; meshio reads it as
/// `cell_data["label"]`); `space` as [`write_vtk_tets`]. A tetrahedron without a label is an
/// error, and nothing is written.
pub fn write_vtk_labelled_tets(
    path: &Path,
    mesh: &isolab_algorithms::TetMesh,
    labels: &[u32],
    space: Option<&str>,
) -> Result<(), IoError> {
    if labels.len() != mesh.tetrahedra.len() {
        return Err(IoError::Write {
            path: path.into(),
            source: std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                format!("{} tetrahedra but {} labels", mesh.tetrahedra.len(), labels.len()),
            ),
        });
    }
    let title = space.map_or("isolab labelled tetrahedra".to_owned(), |s| format!("isolab labelled tetrahedra SPACE={s}"));
    write_atomic(path, |w| {
        writeln!(w, "# vtk DataFile Version 3.0\n{title}\nASCII\nDATASET UNSTRUCTURED_GRID")?;
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
        writeln!(w, "CELL_DATA {}\nSCALARS label unsigned_int 1\nLOOKUP_TABLE default", labels.len())?;
        for l in labels {
            writeln!(w, "{l}")?;
        }
        Ok(())
    })
}

/// The path of the tetrahedra written beside a surface output: the same stem with `.vtk`.
pub fn tetrahedra_path(surface: &Path) -> std::path::PathBuf {
    surface.with_extension("vtk")
}
