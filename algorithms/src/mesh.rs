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
