//! Mesh types: an indexed triangle mesh and a tetrahedral mesh.

use glam::Vec3;

/// An indexed triangle mesh. Triangles are counter-clockwise seen from outside.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Unit vertex normals, one per position, or empty when not computed.
    pub normals: Vec<Vec3>,
    /// Vertex indices of each triangle.
    pub triangles: Vec<[u32; 3]>,
}

impl TriMesh {
    /// Empties the mesh, keeping its capacity.
    pub fn clear(&mut self) {
        self.positions.clear();
        self.normals.clear();
        self.triangles.clear();
    }

    /// Bytes of capacity held.
    pub fn capacity_bytes(&self) -> usize {
        (self.positions.capacity() + self.normals.capacity()) * std::mem::size_of::<Vec3>()
            + self.triangles.capacity() * std::mem::size_of::<[u32; 3]>()
    }

    /// Appends `other`, offsetting its indices.
    pub fn append(&mut self, other: &TriMesh) {
        let offset = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.normals.extend_from_slice(&other.normals);
        self.triangles.extend(other.triangles.iter().map(|t| t.map(|i| i + offset)));
    }

    /// Recomputes normals as the area-weighted mean of incident triangle normals.
    pub fn compute_face_weighted_normals(&mut self) {
        let mut acc = vec![Vec3::ZERO; self.positions.len()];
        for t in &self.triangles {
            let [a, b, c] = t.map(|i| self.positions[i as usize]);
            let n = (b - a).cross(c - a);
            for &i in t {
                acc[i as usize] += n;
            }
        }
        self.normals = acc.into_iter().map(|n| n.normalize_or_zero()).collect();
    }
}

/// The vertices where `mesh` is not a consistently oriented 2-manifold (with boundary): ends of
/// edges with more than two triangles or two triangles wound the same way, and vertices whose
/// triangles form more than one fan. Sorted, without repeats. O(triangles log triangles); used by
/// extractors that repair their own output (regularised marching tetrahedra's guard), so it lives
/// here rather than in the metrics crate, which lists the offenders for reports.
pub fn manifold_defects(mesh: &TriMesh) -> Vec<u32> {
    let mut bad = Vec::new();
    // Edges: sorted (low, high, forward?) triples.
    let mut edges: Vec<(u32, u32, bool)> = Vec::with_capacity(3 * mesh.triangles.len());
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edges.push((a.min(b), a.max(b), a < b));
        }
    }
    edges.sort_unstable();
    for group in edges.chunk_by(|x, y| (x.0, x.1) == (y.0, y.1)) {
        if group.len() > 2 || (group.len() == 2 && group[0].2 == group[1].2) {
            bad.extend([group[0].0, group[0].1]);
        }
    }
    // Fans: the link of each vertex (the opposite edges of its triangles) must be one path or one cycle.
    let mut incident: Vec<(u32, u32, u32)> = Vec::with_capacity(3 * mesh.triangles.len());
    for t in &mesh.triangles {
        for k in 0..3 {
            incident.push((t[k], t[(k + 1) % 3], t[(k + 2) % 3]));
        }
    }
    incident.sort_unstable();
    let mut link: Vec<u32> = Vec::new();
    let mut parent: Vec<usize> = Vec::new();
    for fan in incident.chunk_by(|x, y| x.0 == y.0) {
        link.clear();
        for &(_, a, b) in fan {
            link.extend([a, b]);
        }
        link.sort_unstable();
        link.dedup();
        parent.clear();
        parent.extend(0..link.len());
        fn root(parent: &mut [usize], mut i: usize) -> usize {
            while parent[i] != i {
                parent[i] = parent[parent[i]];
                i = parent[i];
            }
            i
        }
        let mut components = link.len();
        for &(_, a, b) in fan {
            let (ia, ib) = (link.binary_search(&a).unwrap_or(0), link.binary_search(&b).unwrap_or(0));
            let (ra, rb) = (root(&mut parent, ia), root(&mut parent, ib));
            if ra != rb {
                parent[ra] = rb;
                components -= 1;
            }
        }
        if components > 1 {
            bad.push(fan[0].0);
        }
    }
    bad.sort_unstable();
    bad.dedup();
    bad
}

/// A tetrahedral mesh. Tetrahedra `[a, b, c, d]` have positive orientation:
/// `(b - a) x (c - a) . (d - a) > 0`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TetMesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Vertex indices of each tetrahedron.
    pub tetrahedra: Vec<[u32; 4]>,
}

impl TetMesh {
    /// Empties the mesh, keeping its capacity.
    pub fn clear(&mut self) {
        self.positions.clear();
        self.tetrahedra.clear();
    }

    /// Bytes of capacity held.
    pub fn capacity_bytes(&self) -> usize {
        self.positions.capacity() * std::mem::size_of::<Vec3>() + self.tetrahedra.capacity() * std::mem::size_of::<[u32; 4]>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetrahedron() -> TriMesh {
        TriMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
            normals: vec![],
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        }
    }

    #[test]
    fn a_closed_tetrahedron_has_no_defects() {
        assert!(manifold_defects(&tetrahedron()).is_empty());
        let mut open = tetrahedron();
        open.triangles.pop();
        assert!(manifold_defects(&open).is_empty(), "a boundary is not a defect");
    }

    #[test]
    fn defects_are_found() {
        // A flipped triangle: its edges run the same way as their neighbours'.
        let mut flipped = tetrahedron();
        flipped.triangles[3] = [1, 3, 2];
        assert_eq!(manifold_defects(&flipped), vec![1, 2, 3]);
        // Two tetrahedra sharing only vertex 0: a pinched vertex.
        let mut pinched = tetrahedron();
        pinched.positions.extend([-Vec3::X, -Vec3::Y, -Vec3::Z]);
        pinched.triangles.extend([[0, 4, 5], [0, 6, 4], [0, 5, 6], [4, 6, 5]]);
        assert_eq!(manifold_defects(&pinched), vec![0]);
        // A third triangle on edge 0-1.
        let mut fin = tetrahedron();
        fin.positions.push(Vec3::new(0.5, -1.0, 0.0));
        fin.triangles.push([0, 4, 1]);
        assert!(manifold_defects(&fin).starts_with(&[0, 1]));
    }
}
