//! The 16-case marching tetrahedra table, generated: for each sign pattern of a tetrahedron, the
//! crossing edges of its triangle or quad, wound so normals point toward increasing `f`.

use glam::Vec3;
use std::sync::LazyLock;

/// One marching tetrahedra case for a positively oriented tetrahedron: the crossing edges of its
/// polygon in cyclic order, wound counter-clockwise seen from outside (`f > iso`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MtCase {
    /// 0 (no surface), 3 (a triangle) or 4 (a quad).
    pub count: u8,
    /// Local vertex pairs `(inside, outside)` of the crossing edges.
    pub edges: [(u8, u8); 4],
}

/// The 16-case marching tetrahedra table, indexed by the inside mask (bit `i`: vertex `i` has
/// `f < iso`), generated from the geometry of a reference tetrahedron.
pub static MT_TABLE: LazyLock<[MtCase; 16]> = LazyLock::new(|| std::array::from_fn(|c| mt_case(c as u8)));

pub(super) fn mt_case(case: u8) -> MtCase {
    let inside: Vec<u8> = (0..4).filter(|i| case >> i & 1 == 1).collect();
    let outside: Vec<u8> = (0..4).filter(|i| case >> i & 1 == 0).collect();
    let mut edges = [(0u8, 0u8); 4];
    let count = match (inside.len(), outside.len()) {
        (1, 3) => {
            for (k, &o) in outside.iter().enumerate() {
                edges[k] = (inside[0], o);
            }
            3
        }
        (3, 1) => {
            for (k, &i) in inside.iter().enumerate() {
                edges[k] = (i, outside[0]);
            }
            3
        }
        (2, 2) => {
            let ([i, j], [k, l]) = ([inside[0], inside[1]], [outside[0], outside[1]]);
            edges = [(i, k), (j, k), (j, l), (i, l)];
            4
        }
        _ => 0,
    };
    if count > 0 {
        // Reference tetrahedron (positive orientation); flip the cycle if it faces inward.
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
        let mid = |(a, b): (u8, u8)| 0.5 * (p[a as usize] + p[b as usize]);
        let centroid = |s: &[u8]| s.iter().map(|&i| p[i as usize]).sum::<Vec3>() / s.len() as f32;
        let n = (mid(edges[1]) - mid(edges[0])).cross(mid(edges[2]) - mid(edges[0]));
        if n.dot(centroid(&outside) - centroid(&inside)) < 0.0 {
            edges[..count as usize].reverse();
        }
    }
    MtCase { count, edges }
}
