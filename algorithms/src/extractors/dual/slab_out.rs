//! Where a slab's sweep writes ([`SweepOut`]): a slab's own mesh (indices slab-local, the layer
//! below the slab tagged) or its piece of an output sized beforehand ([`Piece`]).

use super::resolve;
use crate::mesh::TriMesh;
use glam::Vec3;

/// What a slab writes: its vertices and triangles, and how many vertices come before its last
/// cell layer's (the layer the slab above refers to).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct SlabCount {
    pub(super) vertices: usize,
    pub(super) triangles: usize,
    pub(super) last_layer_start: usize,
}

/// Where the sweep writes: a slab's own mesh (indices slab-local, tagged below the slab) or its
/// piece of the output ([`Piece`]).
pub(super) trait SweepOut {
    /// Where triangles go.
    type Triangles: TriangleOut;
    /// Vertices written so far.
    fn vertex_count(&self) -> usize;
    /// Appends a vertex and, when given, its normal.
    fn push_vertex(&mut self, p: Vec3, normal: Option<Vec3>);
    /// The normals from vertex `first` on (none when the sweep makes none).
    fn normals_from(&mut self, first: usize) -> &mut [Vec3];
    /// The vertices written so far (by slab-local index) and where triangles go.
    fn positions_and_triangles(&mut self) -> (&[Vec3], &mut Self::Triangles);
}

/// Takes triangles of slab-local indices (tagged: the layer below the slab).
pub(super) trait TriangleOut {
    fn push_triangle(&mut self, t: [u32; 3]);
}

impl TriangleOut for Vec<[u32; 3]> {
    #[inline]
    fn push_triangle(&mut self, t: [u32; 3]) {
        self.push(t);
    }
}

impl SweepOut for TriMesh {
    type Triangles = Vec<[u32; 3]>;
    #[inline]
    fn vertex_count(&self) -> usize {
        self.positions.len()
    }
    #[inline]
    fn push_vertex(&mut self, p: Vec3, normal: Option<Vec3>) {
        self.positions.push(p);
        if let Some(n) = normal {
            self.normals.push(n);
        }
    }
    fn normals_from(&mut self, first: usize) -> &mut [Vec3] {
        // No normals at all when the sweep makes none (smoothing moves the vertices first).
        let first = first.min(self.normals.len());
        &mut self.normals[first..]
    }
    fn positions_and_triangles(&mut self) -> (&[Vec3], &mut Vec<[u32; 3]>) {
        (&self.positions, &mut self.triangles)
    }
}

/// A slab's piece of an output sized beforehand: vertices and normals written in place, triangle
/// indices made global as they are written.
pub(super) struct Piece<'a> {
    pub(super) positions: &'a mut [Vec3],
    pub(super) normals: &'a mut [Vec3],
    pub(super) vertices: usize,
    pub(super) triangles: PieceTriangles<'a>,
}

/// A piece's triangles: slab-local index `i` becomes `base + i`, a tagged one the slab below's
/// last-layer vertex `below + i`.
pub(super) struct PieceTriangles<'a> {
    pub(super) out: &'a mut [[u32; 3]],
    pub(super) written: usize,
    pub(super) base: u32,
    pub(super) below: u32,
}

impl TriangleOut for PieceTriangles<'_> {
    #[inline]
    fn push_triangle(&mut self, t: [u32; 3]) {
        let d = &mut self.out[self.written];
        // Element by element, not `t.map(..)`: see `slabs::join_parts`' callers.
        d[0] = resolve(t[0], self.base, self.below);
        d[1] = resolve(t[1], self.base, self.below);
        d[2] = resolve(t[2], self.base, self.below);
        self.written += 1;
    }
}

impl<'a> SweepOut for Piece<'a> {
    type Triangles = PieceTriangles<'a>;
    #[inline]
    fn vertex_count(&self) -> usize {
        self.vertices
    }
    #[inline]
    fn push_vertex(&mut self, p: Vec3, normal: Option<Vec3>) {
        self.positions[self.vertices] = p;
        if let Some(n) = normal {
            self.normals[self.vertices] = n;
        }
        self.vertices += 1;
    }
    fn normals_from(&mut self, first: usize) -> &mut [Vec3] {
        let written = if self.normals.is_empty() { 0 } else { self.vertices };
        &mut self.normals[first.min(written)..written]
    }
    fn positions_and_triangles(&mut self) -> (&[Vec3], &mut PieceTriangles<'a>) {
        (&self.positions[..self.vertices], &mut self.triangles)
    }
}
