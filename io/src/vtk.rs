//! Legacy VTK unstructured grids: the tetrahedra of volume extractors.

use super::{write_atomic, IoError};
use isolab_algorithms::Vec3;
use std::io::Write;
use std::path::Path;

/// Writes tetrahedra as a legacy ASCII VTK unstructured grid (cell type 10), which ParaView,
/// VisIt, meshio and VTK itself open; `space` goes into the title line (`SPACE=RAS`, which 3D
/// Slicer reads).
pub fn write_vtk_tets(path: &Path, mesh: &isolab_algorithms::TetMesh, space: Option<&str>) -> Result<(), IoError> {
    write_grid(path, &mesh.positions, &mesh.tetrahedra, None, &title("isolab tetrahedra", space))
}

/// Writes labelled tetrahedra (a label map's, from `lattice-cleaving`: `tetrahedra` index
/// `positions`) as [`write_vtk_tets`] does, with the cell array `label` (ParaView colours by it;
/// meshio reads it as `cell_data["label"]`). A tetrahedron without a label is an error, and
/// nothing is written.
pub fn write_vtk_labelled_tets(
    path: &Path,
    positions: &[Vec3],
    tetrahedra: &[[u32; 4]],
    labels: &[u32],
    space: Option<&str>,
) -> Result<(), IoError> {
    if labels.len() != tetrahedra.len() {
        return Err(IoError::Write {
            path: path.into(),
            source: std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                format!("{} tetrahedra but {} labels", tetrahedra.len(), labels.len()),
            ),
        });
    }
    write_grid(path, positions, tetrahedra, Some(labels), &title("isolab labelled tetrahedra", space))
}

/// The title line: `what`, and the space tag when there is one.
fn title(what: &str, space: Option<&str>) -> String {
    space.map_or(what.to_owned(), |s| format!("{what} SPACE={s}"))
}

/// One unstructured grid of tetrahedra, with a `label` cell array when `labels` are given.
fn write_grid(
    path: &Path,
    positions: &[Vec3],
    tetrahedra: &[[u32; 4]],
    labels: Option<&[u32]>,
    title: &str,
) -> Result<(), IoError> {
    write_atomic(path, |w| {
        writeln!(w, "# vtk DataFile Version 3.0\n{title}\nASCII\nDATASET UNSTRUCTURED_GRID")?;
        writeln!(w, "POINTS {} float", positions.len())?;
        for p in positions {
            writeln!(w, "{} {} {}", p.x, p.y, p.z)?;
        }
        writeln!(w, "CELLS {} {}", tetrahedra.len(), 5 * tetrahedra.len())?;
        for t in tetrahedra {
            writeln!(w, "4 {} {} {} {}", t[0], t[1], t[2], t[3])?;
        }
        writeln!(w, "CELL_TYPES {}", tetrahedra.len())?;
        for _ in tetrahedra {
            writeln!(w, "10")?;
        }
        if let Some(labels) = labels {
            writeln!(w, "CELL_DATA {}\nSCALARS label unsigned_int 1\nLOOKUP_TABLE default", labels.len())?;
            for l in labels {
                writeln!(w, "{l}")?;
            }
        }
        Ok(())
    })
}

/// The path of the tetrahedra written beside a surface output: the same stem with `.vtk`.
pub fn tetrahedra_path(surface: &Path) -> std::path::PathBuf {
    surface.with_extension("vtk")
}
