//! Gmsh's MSH 2.2 ASCII format: labelled tetrahedra for finite element codes.
//!
//! The format follows Gmsh's reference manual, "Legacy formats: MSH file format version 2
//! (ASCII)": `$MeshFormat` (`2.2 0 8`), `$PhysicalNames`, `$Nodes` (1-based tags) and
//! `$Elements`, each tetrahedron as element type 4 with two tags, its physical group and its
//! elementary entity, both the label. Version 2.2 is chosen over 4.1 because it is the one every
//! reader takes: Gmsh itself, meshio, FEniCS' and Elmer's converters, Firedrake and
//! deal.II's `GridIn`. No Rust crate writes it (the `mshio` crate only reads), so it is written
//! here; the Python tests read what this writes with Gmsh's own API.

use super::{write_atomic, IoError};
use isolab_algorithms::Vec3;
use std::io::Write;
use std::path::Path;

/// Gmsh's element type of the 4-node tetrahedron.
const TETRAHEDRON: u32 = 4;

/// Writes labelled tetrahedra (`tetrahedra` index `positions`, `labels` one per tetrahedron) as a
/// Gmsh MSH 2.2 ASCII file: every label a physical volume of that number, named `label N`.
///
/// Gmsh's tags are positive C `int`s, so a label of 0 or above 2³¹ − 1 is an error, as is a
/// count of labels that differs from the tetrahedra's; nothing is written then.
pub fn write_msh_labelled_tets(path: &Path, positions: &[Vec3], tetrahedra: &[[u32; 4]], labels: &[u32]) -> Result<(), IoError> {
    let invalid = |reason: String| IoError::Write {
        path: path.into(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidInput, reason),
    };
    if labels.len() != tetrahedra.len() {
        return Err(invalid(format!("{} tetrahedra but {} labels", tetrahedra.len(), labels.len())));
    }
    if let Some(bad) = labels.iter().find(|&&l| l == 0 || l > i32::MAX as u32) {
        return Err(invalid(format!("label {bad} cannot be a Gmsh physical tag (1 to {})", i32::MAX)));
    }
    if let Some(t) = tetrahedra.iter().find(|t| t.iter().any(|&v| v as usize >= positions.len())) {
        return Err(invalid(format!("tetrahedron {t:?} names a vertex past the {} given", positions.len())));
    }
    let groups = physical_groups(labels);
    write_atomic(path, |w| {
        writeln!(w, "$MeshFormat\n2.2 0 8\n$EndMeshFormat")?;
        writeln!(w, "$PhysicalNames\n{}", groups.len())?;
        for l in &groups {
            writeln!(w, "3 {l} \"label {l}\"")?;
        }
        writeln!(w, "$EndPhysicalNames\n$Nodes\n{}", positions.len())?;
        for (i, p) in positions.iter().enumerate() {
            writeln!(w, "{} {} {} {}", i + 1, p.x, p.y, p.z)?;
        }
        writeln!(w, "$EndNodes\n$Elements\n{}", tetrahedra.len())?;
        for (i, (t, l)) in tetrahedra.iter().zip(labels).enumerate() {
            let [a, b, c, d] = t.map(|v| v + 1);
            writeln!(w, "{} {TETRAHEDRON} 2 {l} {l} {a} {b} {c} {d}", i + 1)?;
        }
        writeln!(w, "$EndElements")
    })
}

/// The distinct labels, sorted: one physical group each.
fn physical_groups(labels: &[u32]) -> Vec<u32> {
    let mut groups = labels.to_vec();
    groups.sort_unstable();
    groups.dedup();
    groups
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_tetrahedra() -> (Vec<Vec3>, Vec<[u32; 4]>) {
        let p = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE];
        (p, vec![[0, 1, 2, 3], [1, 2, 3, 4]])
    }

    #[test]
    fn writes_sections_in_gmsh_order_with_one_based_tags() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("two.msh");
        let (p, t) = unit_tetrahedra();
        write_msh_labelled_tets(&path, &p, &t, &[7, 3]).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(&lines[..3], ["$MeshFormat", "2.2 0 8", "$EndMeshFormat"]);
        assert_eq!(&lines[3..8], ["$PhysicalNames", "2", "3 3 \"label 3\"", "3 7 \"label 7\"", "$EndPhysicalNames"]);
        assert_eq!(&lines[8..10], ["$Nodes", "5"]);
        assert_eq!(lines[11], "2 1 0 0");
        assert_eq!(&lines[15..18], ["$EndNodes", "$Elements", "2"]);
        assert_eq!(&lines[18..], ["1 4 2 7 7 1 2 3 4", "2 4 2 3 3 2 3 4 5", "$EndElements"]);
    }

    #[test]
    fn refuses_labels_gmsh_cannot_tag_and_writes_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let (p, t) = unit_tetrahedra();
        for (labels, says) in [
            (vec![0, 1], "label 0 cannot"),
            (vec![1, u32::MAX], "label 4294967295 cannot"),
            (vec![1], "2 tetrahedra but 1 labels"),
        ] {
            let path = dir.path().join("bad.msh");
            let err = write_msh_labelled_tets(&path, &p, &t, &labels).unwrap_err().to_string();
            assert!(err.contains(says) && err.contains("bad.msh"), "{err}");
            assert!(!path.exists());
        }
        let path = dir.path().join("past.msh");
        let err = write_msh_labelled_tets(&path, &p[..4], &t, &[1, 1]).unwrap_err().to_string();
        assert!(err.contains("past the 4 given"), "{err}");
        assert!(std::fs::read_dir(dir.path()).unwrap().next().is_none(), "a temporary file was left");
    }
}
