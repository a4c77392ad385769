//! Mesh types: an indexed triangle mesh and a tetrahedral mesh.

use glam::{DAffine3, Vec3};

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
    /// The corner tetrahedron (the origin and the three unit axis points), closed and wound
    /// outward (counter-clockwise seen from outside): the one small closed mesh the tests share.
    pub fn unit_tetrahedron() -> TriMesh {
        TriMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
            normals: vec![],
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        }
    }

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

    /// Recomputes normals as the area-weighted mean of incident triangle normals, in the normals'
    /// own buffer (no allocation once it has grown).
    pub fn compute_face_weighted_normals(&mut self) {
        let mut acc = std::mem::take(&mut self.normals);
        acc.clear();
        acc.resize(self.positions.len(), Vec3::ZERO);
        accumulate_face_normals(&self.positions, &self.triangles, &mut acc);
        for n in &mut acc {
            *n = n.normalize_or_zero();
        }
        self.normals = acc;
    }

    /// The area-weighted mean of each vertex's incident triangle normals, unit length (zero where
    /// only degenerate triangles meet), without changing the mesh.
    pub fn face_weighted_normals(&self) -> Vec<Vec3> {
        let mut acc = vec![Vec3::ZERO; self.positions.len()];
        accumulate_face_normals(&self.positions, &self.triangles, &mut acc);
        acc.into_iter().map(|n| n.normalize_or_zero()).collect()
    }

    /// Maps the mesh through `affine` (in double precision): positions directly, normals by the
    /// inverse transpose of its linear part (renormalised). A mirroring affine (negative
    /// determinant, such as a scan's left-right flip) also reverses every triangle, so the mesh
    /// keeps its orientation: normals that pointed outward still do, and the signed volume of a
    /// closed mesh stays positive.
    pub fn transform(&mut self, affine: &DAffine3) {
        for p in &mut self.positions {
            *p = affine.transform_point3(p.as_dvec3()).as_vec3();
        }
        let normal_map = affine.matrix3.inverse().transpose();
        for n in &mut self.normals {
            *n = (normal_map * n.as_dvec3()).normalize_or_zero().as_vec3();
        }
        if affine.matrix3.determinant() < 0.0 {
            for t in &mut self.triangles {
                t.swap(1, 2);
            }
        }
    }
}

/// Adds each triangle's vector area (twice it) to its three vertices' entries of `acc`.
fn accumulate_face_normals(positions: &[Vec3], triangles: &[[u32; 3]], acc: &mut [Vec3]) {
    for t in triangles {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        let n = (b - a).cross(c - a);
        for &i in t {
            acc[i as usize] += n;
        }
    }
}

/// The vertices where `mesh` is not a consistently oriented 2-manifold (with boundary): ends of
/// edges with more than two triangles or two triangles wound the same way, and vertices whose
/// triangles form more than one fan. Sorted, without repeats. O(triangles) with no global
/// hashing or sorting of edges: each vertex's link (the opposite edges of its triangles, directed
/// by the winding, gathered by one counting sort) must be one simple path or cycle, checked in
/// O(link) with a small table keyed by tail. Used by extractors that repair their own output
/// (regularised marching tetrahedra's guard); the metrics crate lists offenders for reports.
pub fn manifold_defects(mesh: &TriMesh) -> Vec<u32> {
    ManifoldCheck::default().defects_among(mesh, |_| true).to_vec()
}

/// [`manifold_defects`] with its buffers kept between calls, and restricted to a subset of the
/// vertices: a caller that repairs in steady state (regularised marching tetrahedra's guard on a
/// re-meshed chunk) allocates nothing once the buffers have grown.
#[derive(Clone, Debug, Default)]
pub struct ManifoldCheck {
    /// The wanted vertices' links in compressed rows: vertex `v`'s directed link edges are
    /// `links[start[v]..start[v + 1]]`.
    start: Vec<u32>,
    links: Vec<(u32, u32)>,
    bad: Vec<u32>,
}

impl ManifoldCheck {
    /// The vertices `v` with `wanted(v)` where `mesh` is not a consistently oriented 2-manifold,
    /// sorted, without repeats, plus the wanted link vertices at fault there. Every defect is
    /// seen from both ends (an edge with more than two triangles, or two alike-wound ones, is
    /// in both its ends' links), so with every vertex wanted this is [`manifold_defects`], and
    /// with a subset it is that list restricted to the subset.
    pub fn defects_among(&mut self, mesh: &TriMesh, wanted: impl Fn(u32) -> bool) -> &[u32] {
        let n = mesh.positions.len();
        // The links in one counting sort over the triangles: triangle (a, b, c) adds b -> c to
        // a's link, c -> a to b's and a -> b to c's.
        let (start, links) = (&mut self.start, &mut self.links);
        start.clear();
        start.resize(n + 1, 0);
        for t in &mesh.triangles {
            for &v in t {
                if wanted(v) {
                    start[v as usize + 1] += 1;
                }
            }
        }
        for v in 0..n {
            start[v + 1] += start[v];
        }
        links.clear();
        links.resize(start[n] as usize, (0, 0));
        // Fill with start[v] as vertex v's cursor (it ends at start[v + 1]), then shift back.
        for &[a, b, c] in &mesh.triangles {
            for (v, edge) in [(a, (b, c)), (b, (c, a)), (c, (a, b))] {
                if wanted(v) {
                    links[start[v as usize] as usize] = edge;
                    start[v as usize] += 1;
                }
            }
        }
        for v in (1..=n).rev() {
            start[v] = start[v - 1];
        }
        start[0] = 0;
        self.bad.clear();
        for v in 0..n {
            let link = &links[start[v] as usize..start[v + 1] as usize];
            if !link.is_empty() && !link_is_consistent_fan(link) {
                self.bad.push(v as u32);
                self.bad.extend(repeated_link_ends(link).filter(|&a| wanted(a)));
            }
        }
        self.bad.sort_unstable();
        self.bad.dedup();
        &self.bad
    }
}

/// The elements (triangles or tetrahedra) around each vertex, in compressed rows: vertex `v`'s
/// are `items[start[v]..start[v + 1]]`, in increasing element order. Built by a counting sort in
/// two passes over the elements.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Incidence {
    /// Row offsets, one per vertex plus one.
    pub start: Vec<u32>,
    /// Element indices.
    pub items: Vec<u32>,
}

impl Incidence {
    /// The incidence of every element of `elements` on `vertices` vertices.
    pub fn of<const K: usize>(vertices: usize, elements: &[[u32; K]]) -> Self {
        Self::of_subset(vertices, elements, 0..elements.len() as u32)
    }

    /// The incidence of the elements `ids` (increasing) of `elements`.
    pub fn of_subset<const K: usize>(vertices: usize, elements: &[[u32; K]], ids: impl Iterator<Item = u32> + Clone) -> Self {
        let mut incidence = Self::default();
        incidence.rebuild_subset(vertices, elements, ids);
        incidence
    }

    /// [`Incidence::of`] into this incidence's buffers.
    pub fn rebuild<const K: usize>(&mut self, vertices: usize, elements: &[[u32; K]]) {
        self.rebuild_subset(vertices, elements, 0..elements.len() as u32)
    }

    /// [`Incidence::of_subset`] into this incidence's buffers.
    pub fn rebuild_subset<const K: usize>(
        &mut self,
        vertices: usize,
        elements: &[[u32; K]],
        ids: impl Iterator<Item = u32> + Clone,
    ) {
        let (start, items) = (&mut self.start, &mut self.items);
        start.clear();
        start.resize(vertices + 1, 0);
        for e in ids.clone() {
            for &v in &elements[e as usize] {
                start[v as usize + 1] += 1;
            }
        }
        for v in 0..vertices {
            start[v + 1] += start[v];
        }
        items.clear();
        items.resize(start[vertices] as usize, 0);
        // Fill with start[v] as vertex v's cursor (it ends at start[v + 1]), then shift back.
        for e in ids {
            for &v in &elements[e as usize] {
                items[start[v as usize] as usize] = e;
                start[v as usize] += 1;
            }
        }
        for v in (1..=vertices).rev() {
            start[v] = start[v - 1];
        }
        start[0] = 0;
    }

    /// The elements around vertex `v`.
    pub fn of_vertex(&self, v: u32) -> &[u32] {
        &self.items[self.start[v as usize] as usize..self.start[v as usize + 1] as usize]
    }
}

/// Whether a vertex's link, given as edges `a - b` (one per incident triangle, direction
/// ignored), is one simple path or cycle: no link vertex on more than two edges, and one
/// connected piece. The vertex-manifold test of both the repairing extractors and the metrics.
pub fn link_is_one_fan(link: &[(u32, u32)]) -> bool {
    let mut verts: Vec<u32> = link.iter().flat_map(|&(a, b)| [a, b]).collect();
    verts.sort_unstable();
    verts.dedup();
    let local = |x: u32| verts.binary_search(&x).unwrap_or(0);
    let mut degree = vec![0u8; verts.len()];
    let mut pieces = petgraph::unionfind::UnionFind::<usize>::new(verts.len());
    for &(a, b) in link {
        let (la, lb) = (local(a), local(b));
        degree[la] += 1;
        degree[lb] += 1;
        if degree[la] > 2 || degree[lb] > 2 {
            return false;
        }
        pieces.union(la, lb);
    }
    (1..verts.len()).all(|i| pieces.equiv(0, i))
}

/// The link vertices at fault in one vertex's link, given as directed edges `a -> b` (one per
/// incident triangle `(v, a, b)`): those that are the tail, or the head, of two edges (an edge
/// `v-a` with more than two triangles or two alike-wound ones).
fn repeated_link_ends(link: &[(u32, u32)]) -> impl Iterator<Item = u32> + '_ {
    link.iter().enumerate().flat_map(move |(i, &(a, b))| {
        link[i + 1..].iter().flat_map(move |&(c, d)| [(a == c).then_some(a), (b == d).then_some(b)].into_iter().flatten())
    })
}

/// Whether one vertex's link, given as directed edges `a -> b` (one per incident triangle
/// `(v, a, b)`), is one directed simple path or cycle: no link vertex is the tail or the head of
/// two edges, and following heads to tails from the path's start (or any edge of a cycle)
/// visits every edge. Without allocating; links of up to [`SHORT_LINK`] edges (nearly all) are
/// hashed by tail, longer ones by scans.
fn link_is_consistent_fan(link: &[(u32, u32)]) -> bool {
    if link.len() <= SHORT_LINK {
        short_link_is_consistent_fan(link)
    } else {
        long_link_is_consistent_fan(link)
    }
}

/// Links up to this many edges take the hashed test.
const SHORT_LINK: usize = 16;

/// [`link_is_consistent_fan`] for at most [`SHORT_LINK`] edges, in O(edges): the edges are
/// hashed by tail (a repeated tail fails), each edge's successor (the edge whose tail is its
/// head) is looked up, an edge with two predecessors fails (a repeated head), and the walk
/// along successors from the path's start (or any edge of a cycle) must visit every edge. A
/// repeated head left (two path ends alike) leaves more than one path start, so the walk cannot
/// cover every edge.
fn short_link_is_consistent_fan(link: &[(u32, u32)]) -> bool {
    const NONE: u8 = u8::MAX;
    const SLOTS: usize = 2 * SHORT_LINK;
    let k = link.len();
    if k == 0 {
        return true;
    }
    // Open addressing by tail: slot -> edge index + 1 (0: empty).
    let mut by_tail = [0u8; SLOTS];
    let home = |v: u32| (v.wrapping_mul(0x9E37_79B1) >> 27) as usize % SLOTS;
    for (i, &(a, _)) in link.iter().enumerate() {
        let mut h = home(a);
        while by_tail[h] != 0 {
            if link[by_tail[h] as usize - 1].0 == a {
                return false;
            }
            h = (h + 1) % SLOTS;
        }
        by_tail[h] = i as u8 + 1;
    }
    let edge_from = |v: u32| {
        let mut h = home(v);
        while by_tail[h] != 0 {
            let e = by_tail[h] as usize - 1;
            if link[e].0 == v {
                return Some(e);
            }
            h = (h + 1) % SLOTS;
        }
        None
    };
    let mut next = [NONE; SHORT_LINK];
    let mut followed = 0u32;
    for (i, &(_, b)) in link.iter().enumerate() {
        if let Some(j) = edge_from(b) {
            if followed >> j & 1 == 1 {
                return false;
            }
            followed |= 1 << j;
            next[i] = j as u8;
        }
    }
    // Tails no edge leads to start paths; with one (or none: a cycle) the walk from it must
    // visit every edge.
    let starts = !followed & ((1u32 << k) - 1);
    let first = if starts == 0 { 0 } else { starts.trailing_zeros() as usize };
    let (mut at, mut visited) = (first, 1);
    while next[at] != NONE && visited <= k {
        at = next[at] as usize;
        if at == first {
            break;
        }
        visited += 1;
    }
    visited == k
}

/// [`link_is_consistent_fan`] by scans, for long links.
fn long_link_is_consistent_fan(link: &[(u32, u32)]) -> bool {
    if repeated_link_ends(link).next().is_some() {
        return false;
    }
    let Some(first) = link.iter().position(|&(a, _)| link.iter().all(|&(_, b)| b != a)).or((!link.is_empty()).then_some(0))
    else {
        return true;
    };
    let mut at = first;
    for visited in 1..=link.len() {
        let head = link[at].1;
        match link.iter().position(|&(a, _)| a == head) {
            Some(next) if next != first => at = next,
            _ => return visited == link.len(),
        }
    }
    false
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

    /// Maps the positions through `affine`; a mirroring affine also swaps two vertices of every
    /// tetrahedron, so orientations stay positive.
    pub fn transform(&mut self, affine: &DAffine3) {
        for p in &mut self.positions {
            *p = affine.transform_point3(p.as_dvec3()).as_vec3();
        }
        if affine.matrix3.determinant() < 0.0 {
            for t in &mut self.tetrahedra {
                t.swap(2, 3);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetrahedron() -> TriMesh {
        TriMesh::unit_tetrahedron()
    }

    #[test]
    fn a_closed_tetrahedron_has_no_defects() {
        assert!(manifold_defects(&tetrahedron()).is_empty());
        let mut open = tetrahedron();
        open.triangles.pop();
        assert!(manifold_defects(&open).is_empty(), "a boundary is not a defect");
    }

    #[test]
    fn a_mirroring_transform_keeps_the_orientation() {
        use glam::{DMat3, DVec3};
        let signed_volume = |m: &TriMesh| -> f32 {
            m.triangles.iter().map(|t| t.map(|i| m.positions[i as usize])).map(|[a, b, c]| a.dot(b.cross(c)) / 6.0).sum()
        };
        let mut m = tetrahedron();
        m.compute_face_weighted_normals();
        let before = signed_volume(&m);
        assert!(before > 0.0);
        let mirror = DAffine3 {
            matrix3: DMat3::from_cols(DVec3::new(-2.0, 0.0, 0.0), DVec3::new(0.0, 0.0, 3.0), DVec3::new(0.0, 1.0, 0.0)),
            translation: DVec3::new(5.0, 6.0, 7.0),
        };
        m.transform(&mirror);
        assert!((signed_volume(&m) - before * 6.0).abs() < 1e-5, "{}", signed_volume(&m));
        assert_eq!(m.positions[1], Vec3::new(3.0, 6.0, 7.0));
        // Vertex 0's normal pointed away from the others (into -x-y-z); it still points away.
        let centroid = (m.positions[1] + m.positions[2] + m.positions[3]) / 3.0;
        assert!(m.normals[0].dot(m.positions[0] - centroid) > 0.0);
        assert!((m.normals[0].length() - 1.0).abs() < 1e-6);
        let mut tets = TetMesh { positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z], tetrahedra: vec![[0, 1, 2, 3]] };
        tets.transform(&mirror);
        let [a, b, c, d] = tets.tetrahedra[0].map(|i| tets.positions[i as usize]);
        assert!((b - a).cross(c - a).dot(d - a) > 0.0);
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

    #[test]
    fn short_and_long_link_tests_agree() {
        // Every link of up to five edges over four link vertices (self-loops included), and
        // random longer ones: the hashed test decides as the scans do.
        let mut checked = [0usize; 2];
        let mut check = |link: &[(u32, u32)]| {
            let expected = long_link_is_consistent_fan(link);
            assert_eq!(short_link_is_consistent_fan(link), expected, "{link:?}");
            checked[usize::from(expected)] += 1;
        };
        for len in 0..=5u32 {
            for code in 0..16u32.pow(len) {
                let link: Vec<(u32, u32)> = (0..len).map(|i| code / 16u32.pow(i) % 16).map(|e| (e / 4, e % 4)).collect();
                check(&link);
            }
        }
        let mut rng = crate::random::Random::new(7);
        for _ in 0..20_000 {
            let len = 1 + rng.next_u64() as usize % SHORT_LINK;
            let alphabet = len as u64 + 1 + rng.next_u64() % 3;
            let mut link: Vec<(u32, u32)> = (0..len as u32).map(|i| (i, (i + 1) % len as u32)).collect();
            // A ring or path, then a few random changes.
            if rng.next_u64() % 2 == 0 {
                link.pop();
            }
            for _ in 0..rng.next_u64() % 3 {
                let k = rng.next_u64() as usize % link.len().max(1);
                if let Some(e) = link.get_mut(k) {
                    *e = ((rng.next_u64() % alphabet) as u32, (rng.next_u64() % alphabet) as u32);
                }
            }
            let shift = rng.next_u64() as usize % link.len().max(1);
            link.rotate_left(shift);
            check(&link);
        }
        assert!(checked[0] > 1000 && checked[1] > 1000, "both answers are exercised: {checked:?}");
    }
}
