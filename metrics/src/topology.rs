//! Topology of a triangle mesh: closed, manifold, oriented, outward, components, Euler
//! characteristic, genus. Offending edges and vertices are listed (first
//! [`MAX_LISTED`] of each), not just counted.
//!
//! Definitions (triangles with a repeated vertex index are left out and counted as degenerate):
//! - an edge is **boundary** when one triangle uses it, **manifold** when two do, **non-manifold**
//!   when more do;
//! - **closed**: no boundary edge; **edge-manifold**: no non-manifold edge;
//! - **vertex-manifold**: the triangles around every vertex form one fan (the link is one cycle,
//!   or one path at the boundary);
//! - **oriented**: every manifold edge is used once in each direction;
//! - **outward**: closed, oriented and positive signed volume;
//! - **Euler characteristic** `χ = V - E + F` over used vertices;
//! - **genus** `g = (2C - χ - B) / 2` with `C` components and `B` boundary loops, for an
//!   edge-manifold oriented mesh (otherwise `null`).

use isolab_algorithms::mesh::{link_is_one_fan, Incidence};
use isolab_algorithms::TriMesh;
use petgraph::unionfind::UnionFind;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// At most this many offenders of each kind are listed.
pub const MAX_LISTED: usize = 100;

/// Topology report.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Topology {
    /// No boundary edges (ideal: true for a surface inside the domain).
    pub closed: bool,
    /// No edge shared by more than two triangles.
    pub edge_manifold: bool,
    /// Every vertex's triangles form one fan.
    pub vertex_manifold: bool,
    /// Every manifold edge used once in each direction.
    pub oriented: bool,
    /// Closed, oriented, positive volume.
    pub outward: bool,
    /// Connected components: triangles joined through shared edges.
    pub components: usize,
    /// `V - E + F`.
    pub euler: i64,
    /// `(2C - χ - B) / 2`, when edge-manifold and oriented.
    pub genus: Option<i64>,
    /// Edges used by one triangle.
    pub boundary_edges: usize,
    /// Closed loops of boundary edges.
    pub boundary_loops: usize,
    /// Edges used by more than two triangles.
    pub non_manifold_edges: usize,
    /// Vertices whose triangles do not form one fan.
    pub non_manifold_vertices: usize,
    /// Manifold edges used twice in the same direction.
    pub misoriented_edges: usize,
    /// Vertices no triangle uses.
    pub unused_vertices: usize,
    /// Offenders, listed.
    pub offenders: Offenders,
}

/// The first [`MAX_LISTED`] offenders of each kind.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Offenders {
    /// Boundary edges as vertex pairs.
    pub boundary_edges: Vec<[u32; 2]>,
    /// Non-manifold edges.
    pub non_manifold_edges: Vec<[u32; 2]>,
    /// Misoriented edges.
    pub misoriented_edges: Vec<[u32; 2]>,
    /// Non-manifold vertices.
    pub non_manifold_vertices: Vec<u32>,
    /// Triangles with a repeated index.
    pub repeated_index_triangles: Vec<u32>,
}

impl Topology {
    /// Closed, edge- and vertex-manifold and oriented: what a watertight game mesh needs.
    pub fn is_watertight_manifold(&self) -> bool {
        self.closed && self.edge_manifold && self.vertex_manifold && self.oriented
    }
}

fn push_listed<T>(list: &mut Vec<T>, item: T) {
    if list.len() < MAX_LISTED {
        list.push(item);
    }
}

/// The topology report of `mesh`.
pub fn topology(mesh: &TriMesh) -> Topology {
    let n = mesh.positions.len();
    let mut report = Topology::default();
    let valid: Vec<u32> = (0..mesh.triangles.len() as u32)
        .filter(|&t| {
            let [a, b, c] = mesh.triangles[t as usize];
            a != b && b != c && a != c
        })
        .collect();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] {
            push_listed(&mut report.offenders.repeated_index_triangles, t as u32);
        }
    }

    // Half-edges keyed by (min, max) with the direction in the low bit of the payload.
    let mut half: Vec<(u64, bool, u32)> = valid
        .par_iter()
        .flat_map_iter(|&t| {
            let tri = mesh.triangles[t as usize];
            (0..3).map(move |k| {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                ((u64::from(a.min(b)) << 32) | u64::from(a.max(b)), a < b, t)
            })
        })
        .collect();
    half.par_sort_unstable();

    let mut edges = 0i64;
    let mut face_uf = UnionFind::<u32>::new(mesh.triangles.len());
    let mut boundary_uf = UnionFind::<u32>::new(n);
    let mut boundary_vertices = Vec::new();
    let mut i = 0;
    while i < half.len() {
        let key = half[i].0;
        let mut j = i;
        while j < half.len() && half[j].0 == key {
            j += 1;
        }
        let pair = [(key >> 32) as u32, key as u32];
        edges += 1;
        for k in i + 1..j {
            face_uf.union(half[i].2, half[k].2);
        }
        match j - i {
            1 => {
                report.boundary_edges += 1;
                push_listed(&mut report.offenders.boundary_edges, pair);
                boundary_uf.union(pair[0], pair[1]);
                boundary_vertices.push(pair[0]);
            }
            2 => {
                if half[i].1 == half[i + 1].1 {
                    report.misoriented_edges += 1;
                    push_listed(&mut report.offenders.misoriented_edges, pair);
                }
            }
            _ => {
                report.non_manifold_edges += 1;
                push_listed(&mut report.offenders.non_manifold_edges, pair);
            }
        }
        i = j;
    }
    boundary_vertices.sort_unstable();
    boundary_vertices.dedup();
    let mut loop_roots: Vec<u32> = boundary_vertices.iter().map(|&v| boundary_uf.find_mut(v)).collect();
    loop_roots.sort_unstable();
    loop_roots.dedup();
    report.boundary_loops = loop_roots.len();

    // Components: triangles connected through shared edges (as CGAL and MeshLab count them).
    report.components = valid.iter().filter(|&&t| face_uf.find_mut(t) == t).count();
    let mut used = vec![false; n];
    for t in &mesh.triangles {
        for &v in t {
            used[v as usize] = true;
        }
    }
    let used_count = used.iter().filter(|&&u| u).count();
    report.unused_vertices = n - used_count;

    // Vertex manifoldness from each vertex's link.
    let bad_vertices = non_manifold_vertices(mesh, &valid);
    report.non_manifold_vertices = bad_vertices.len();
    report.offenders.non_manifold_vertices = bad_vertices.into_iter().take(MAX_LISTED).collect();

    report.closed = report.boundary_edges == 0;
    report.edge_manifold = report.non_manifold_edges == 0;
    report.vertex_manifold = report.non_manifold_vertices == 0;
    report.oriented = report.misoriented_edges == 0 && report.edge_manifold;
    report.euler = used_count as i64 - edges + valid.len() as i64;
    if report.edge_manifold && report.oriented {
        let twice = 2 * report.components as i64 - report.euler - report.boundary_loops as i64;
        report.genus = Some(twice / 2);
    }
    report.outward = report.closed && report.oriented && crate::signed_volume(mesh) > 0.0;
    report
}

/// Vertices whose link (the opposite edges of their triangles) is not a single cycle or path.
fn non_manifold_vertices(mesh: &TriMesh, valid: &[u32]) -> Vec<u32> {
    let n = mesh.positions.len();
    let around = Incidence::of_subset(n, &mesh.triangles, valid.iter().copied());
    (0..n as u32)
        .into_par_iter()
        .filter(|&v| {
            let tris = around.of_vertex(v);
            !tris.is_empty() && !link_is_one_fan(&link_of(mesh, v, tris))
        })
        .collect()
}

/// The link edges of `v`: each incident triangle's edge opposite `v`.
fn link_of(mesh: &TriMesh, v: u32, tris: &[u32]) -> Vec<(u32, u32)> {
    tris.iter()
        .map(|&t| {
            let tri = mesh.triangles[t as usize];
            let k = tri.iter().position(|&x| x == v).unwrap_or(0);
            (tri[(k + 1) % 3], tri[(k + 2) % 3])
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn tetra() -> TriMesh {
        TriMesh::unit_tetrahedron()
    }

    #[test]
    fn closed_tetrahedron() {
        let t = topology(&tetra());
        assert!(t.is_watertight_manifold() && t.outward);
        assert_eq!((t.euler, t.genus, t.components), (2, Some(0), 1));
    }

    #[test]
    fn flipped_face_is_misoriented_and_listed() {
        let mut m = tetra();
        m.triangles[3] = [1, 3, 2];
        let t = topology(&m);
        assert!(!t.oriented);
        assert_eq!(t.misoriented_edges, 3);
        assert_eq!(t.offenders.misoriented_edges.len(), 3);
    }

    #[test]
    fn open_and_nonmanifold_cases() {
        let mut m = tetra();
        m.triangles.pop();
        let t = topology(&m);
        assert!(!t.closed);
        assert_eq!((t.boundary_edges, t.boundary_loops, t.genus), (3, 1, Some(0)));
        // Two tetrahedra sharing only vertex 0: edge-manifold but not vertex-manifold.
        let mut two = tetra();
        let off = two.positions.len() as u32;
        two.positions.extend([Vec3::NEG_X, Vec3::NEG_Y, Vec3::NEG_Z]);
        let extra: Vec<[u32; 3]> = tetra().triangles.iter().map(|t| t.map(|i| if i == 0 { 0 } else { i - 1 + off })).collect();
        two.triangles.extend(extra);
        let t = topology(&two);
        assert!(t.closed && t.edge_manifold);
        assert!(!t.vertex_manifold);
        assert_eq!(t.components, 2, "touching at a vertex does not join components");
        assert_eq!(t.offenders.non_manifold_vertices, vec![0]);
        // A fin: three triangles on one edge.
        let mut fin = tetra();
        fin.positions.push(Vec3::new(1.0, 1.0, 1.0));
        fin.triangles.push([0, 1, 4]);
        assert_eq!(topology(&fin).non_manifold_edges, 1);
    }
}
