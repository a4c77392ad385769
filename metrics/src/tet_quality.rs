//! Tetrahedron quality.
//!
//! For a tetrahedron with signed volume `V`, face areas `A_i`, inradius `r = 3|V| / ΣA_i`,
//! circumradius `R`, shortest and longest edges `l_min`, `l_max`:
//! - **dihedral angles** at the six edges, degrees (regular: 70.53; a BCC lattice tetrahedron:
//!   60 and 90; a Kuhn cube-split tetrahedron: 45 to 90);
//! - **Verdict aspect ratio** (VTK's tetrahedron `AspectRatio`) `l_max / (2 sqrt(6) r)`; 1 regular;
//! - **radius ratio** `R / (3 r)`; 1 regular;
//! - **radius-edge ratio** (CGAL Mesh_3 / TetGen) `R / l_min`; sqrt(6)/4 = 0.612 regular;
//! - **inverted**: `V <= 0` for a tetrahedron `[a, b, c, d]` expected positive
//!   (`(b-a)×(c-a)·(d-a) > 0`).

use crate::Summary;
use glam::Vec3;
use isolab_algorithms::geometry::circumcentre;
use isolab_algorithms::TetMesh;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Shape of one tetrahedron.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TetShape {
    /// Signed volume.
    pub volume: f64,
    /// Smallest dihedral angle, degrees.
    pub min_dihedral_deg: f64,
    /// Largest dihedral angle, degrees.
    pub max_dihedral_deg: f64,
    /// Verdict aspect ratio.
    pub aspect_ratio: f64,
    /// `R / 3r`.
    pub radius_ratio: f64,
    /// `R / l_min`.
    pub radius_edge_ratio: f64,
}

pub use isolab_algorithms::geometry::dihedral_angles;

/// The shape of tetrahedron `p`.
pub fn tet_shape(p: [Vec3; 4]) -> TetShape {
    let d = p.map(|v| v.as_dvec3());
    let (u, v, w) = (d[1] - d[0], d[2] - d[0], d[3] - d[0]);
    let det = u.dot(v.cross(w));
    let volume = det / 6.0;
    let faces = [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]];
    let area_sum: f64 = faces.iter().map(|f| 0.5 * (d[f[1]] - d[f[0]]).cross(d[f[2]] - d[f[0]]).length()).sum();
    let r_in = 3.0 * volume.abs() / area_sum;
    let r_circ = circumcentre(d).map_or(f64::INFINITY, |c| c.distance(d[0]));
    let lengths = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)].map(|(i, j)| d[i].distance(d[j]));
    let l_min = lengths.iter().copied().fold(f64::INFINITY, f64::min);
    let l_max = lengths.iter().copied().fold(0.0, f64::max);
    let angles = dihedral_angles(p);
    TetShape {
        volume,
        min_dihedral_deg: angles.iter().copied().fold(f64::INFINITY, f64::min),
        max_dihedral_deg: angles.iter().copied().fold(0.0, f64::max),
        aspect_ratio: l_max / (2.0 * 6f64.sqrt() * r_in),
        radius_ratio: r_circ / (3.0 * r_in),
        radius_edge_ratio: r_circ / l_min,
    }
}

/// Min and max (the metrics JSON's `dihedral_deg`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MinMax {
    /// Smallest.
    pub min: f64,
    /// Largest.
    pub max: f64,
}

/// Quality statistics of a tetrahedral mesh.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TetQuality {
    /// Tetrahedra.
    pub tetrahedra: usize,
    /// Smallest and largest dihedral angle over all tetrahedra, degrees.
    pub dihedral_deg: MinMax,
    /// Verdict aspect ratio (ideal 1).
    pub tet_aspect_ratio: Summary,
    /// `R / 3r` (ideal 1).
    pub tet_radius_ratio: Summary,
    /// `R / l_min` (ideal 0.612).
    pub radius_edge_ratio: Summary,
    /// Tetrahedra with non-positive volume (ideal 0).
    pub inverted: usize,
    /// Sum of signed volumes.
    pub total_volume: f64,
}

/// Quality statistics of `mesh`; inverted tetrahedra are counted and left out of the ratios.
pub fn tet_quality(mesh: &TetMesh) -> TetQuality {
    let shapes: Vec<TetShape> = mesh.tetrahedra.par_iter().map(|t| tet_shape(t.map(|i| mesh.positions[i as usize]))).collect();
    let good = shapes.iter().filter(|s| s.volume > 0.0);
    TetQuality {
        tetrahedra: shapes.len(),
        dihedral_deg: MinMax {
            min: shapes.iter().map(|s| s.min_dihedral_deg).fold(f64::INFINITY, f64::min).min(180.0),
            max: shapes.iter().map(|s| s.max_dihedral_deg).fold(0.0, f64::max),
        },
        tet_aspect_ratio: Summary::of(good.clone().map(|s| s.aspect_ratio)),
        tet_radius_ratio: Summary::of(good.clone().map(|s| s.radius_ratio)),
        radius_edge_ratio: Summary::of(good.map(|s| s.radius_edge_ratio)),
        inverted: shapes.iter().filter(|s| s.volume <= 0.0).count(),
        total_volume: shapes.iter().map(|s| s.volume).sum(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regular_bcc_and_kuhn_reference_values() {
        let regular =
            [Vec3::new(1.0, 1.0, 1.0), Vec3::new(1.0, -1.0, -1.0), Vec3::new(-1.0, 1.0, -1.0), Vec3::new(-1.0, -1.0, 1.0)];
        let mut regular_pos = regular;
        if tet_shape(regular).volume < 0.0 {
            regular_pos.swap(0, 1);
        }
        let s = tet_shape(regular_pos);
        assert!(s.volume > 0.0);
        assert!((s.min_dihedral_deg - 70.5288).abs() < 1e-3 && (s.max_dihedral_deg - 70.5288).abs() < 1e-3);
        assert!((s.aspect_ratio - 1.0).abs() < 1e-9 && (s.radius_ratio - 1.0).abs() < 1e-9);
        assert!((s.radius_edge_ratio - 6f64.sqrt() / 4.0).abs() < 1e-9);
        // BCC: two cube centres and two adjacent corners of their shared face.
        let bcc = tet_shape([Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 1.0), Vec3::new(1.0, -1.0, 1.0)]);
        assert!((bcc.min_dihedral_deg - 60.0).abs() < 1e-4 && (bcc.max_dihedral_deg - 90.0).abs() < 1e-4, "{bcc:?}");
        // Kuhn: a path along the cube's axes from (0,0,0) to (1,1,1).
        let kuhn = tet_shape([Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::ONE]);
        assert!((kuhn.min_dihedral_deg - 45.0).abs() < 1e-4 && (kuhn.max_dihedral_deg - 90.0).abs() < 1e-4, "{kuhn:?}");
    }

    #[test]
    fn inverted_tetrahedra_are_counted() {
        let mesh =
            TetMesh { positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z], tetrahedra: vec![[0, 1, 2, 3], [0, 2, 1, 3]] };
        let q = tet_quality(&mesh);
        assert_eq!((q.tetrahedra, q.inverted), (2, 1));
        assert!(q.total_volume.abs() < 1e-12);
    }
}
