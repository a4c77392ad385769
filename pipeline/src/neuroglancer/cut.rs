//! Meshes cut at octree boxes and simplified inside them, for neuroglancer's fragments.
//!
//! [`clip_to_box`] clips each triangle to an axis-aligned box (Sutherland-Hodgman, planes in a
//! fixed order) and fans the pieces. A cut point is computed from its edge's two ends in a
//! canonical order, so the blocks on both sides of a face make it bit for bit alike; a triangle
//! lying in a box face belongs to the box whose low face it is. [`simplify_locked`] simplifies a
//! box's mesh with meshoptimizer, every vertex on the box's faces locked; [`join_welded`] joins
//! meshes, welding vertices at equal positions.

use rustc_hash::FxHashMap as HashMap;

use glam::{DVec3, Vec3};
use isolab_algorithms::TriMesh;
use meshopt::SimplifyOptions;

/// The point where edge `p q` meets the plane `axis = value`, the same whichever end comes
/// first; its `axis` coordinate is exactly `value`.
fn cut(p: Vec3, q: Vec3, axis: usize, value: f32) -> Vec3 {
    let p_first = (0..3).map(|a| p[a].total_cmp(&q[a])).find(|o| o.is_ne()) != Some(std::cmp::Ordering::Greater);
    let (a, b) = if p_first { (p.as_dvec3(), q.as_dvec3()) } else { (q.as_dvec3(), p.as_dvec3()) };
    let t = (f64::from(value) - a[axis]) / (b[axis] - a[axis]);
    let mut r = (a + (b - a) * t).as_vec3();
    r[axis] = value;
    r
}

/// Clips a polygon to one side of `axis = value` (`above`: keep `>= value`).
fn clip_polygon(poly: &[Vec3], out: &mut Vec<Vec3>, axis: usize, value: f32, above: bool) {
    out.clear();
    let inside = |p: Vec3| if above { p[axis] >= value } else { p[axis] <= value };
    for i in 0..poly.len() {
        let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
        let (pin, qin) = (inside(p), inside(q));
        if pin {
            out.push(p);
        }
        // A cut only where the edge crosses strictly: an end on the plane is itself the cut.
        if pin != qin && p[axis] != value && q[axis] != value {
            out.push(cut(p, q, axis, value));
        }
    }
}

/// The part of `mesh` inside the box `[lo, hi]` (closed), its triangles cut at the faces, its
/// vertices welded by position. A triangle lying in a face `axis = hi` is left to the next box.
pub fn clip_to_box(mesh: &TriMesh, lo: [f32; 3], hi: [f32; 3]) -> TriMesh {
    let mut out = TriMesh::default();
    let mut ids: HashMap<[u32; 3], u32> = HashMap::default();
    let mut id_of = |p: Vec3, out: &mut TriMesh| {
        *ids.entry(p.to_array().map(f32::to_bits)).or_insert_with(|| {
            out.positions.push(p);
            (out.positions.len() - 1) as u32
        })
    };
    let (mut poly, mut scratch) = (Vec::with_capacity(9), Vec::with_capacity(9));
    for t in &mesh.triangles {
        let v = t.map(|i| mesh.positions[i as usize]);
        if (0..3).any(|a| v.iter().all(|p| p[a] < lo[a]) || v.iter().all(|p| p[a] > hi[a])) {
            continue;
        }
        if (0..3).any(|a| v.iter().all(|p| p[a] == hi[a])) {
            continue;
        }
        let within = v.iter().all(|p| (0..3).all(|a| p[a] >= lo[a] && p[a] <= hi[a]));
        if within {
            let tri = v.map(|p| id_of(p, &mut out));
            if tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2] {
                out.triangles.push(tri);
            }
            continue;
        }
        poly.clear();
        poly.extend_from_slice(&v);
        for a in 0..3 {
            clip_polygon(&poly, &mut scratch, a, lo[a], true);
            std::mem::swap(&mut poly, &mut scratch);
            clip_polygon(&poly, &mut scratch, a, hi[a], false);
            std::mem::swap(&mut poly, &mut scratch);
        }
        poly.dedup();
        while poly.len() > 1 && poly.first() == poly.last() {
            poly.pop();
        }
        if poly.len() < 3 {
            continue;
        }
        let first = poly[0];
        for w in poly[1..].windows(2) {
            let (b, c) = (w[0], w[1]);
            let area = (b.as_dvec3() - first.as_dvec3()).cross(c.as_dvec3() - first.as_dvec3());
            if area == DVec3::ZERO {
                continue;
            }
            let tri = [first, b, c].map(|p| id_of(p, &mut out));
            if tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2] {
                out.triangles.push(tri);
            }
        }
    }
    out
}

/// The absolute error (samples) meshoptimizer may add at `level`: half a level's sample.
pub fn level_error(level: usize) -> f32 {
    0.5 * (1u32 << (level.max(1) - 1)) as f32
}

/// `mesh` (inside the box `[lo, hi]`) simplified for `level`: to a quarter of its triangles or
/// [`level_error`], whichever comes first, with every vertex on the box's faces locked, so the
/// box's boundary is the finer level's. A simplification to nothing keeps the mesh as it is.
pub fn simplify_locked(mesh: &TriMesh, lo: [f32; 3], hi: [f32; 3], level: usize) -> TriMesh {
    if mesh.triangles.len() < 4 {
        return mesh.clone();
    }
    let locks: Vec<bool> = mesh.positions.iter().map(|p| (0..3).any(|a| p[a] == lo[a] || p[a] == hi[a])).collect();
    let indices: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
    let positions = super::as_arrays(&mesh.positions);
    let target = (mesh.triangles.len() / 4).max(1) * 3;
    let kept = meshopt::simplify_with_locks_decoder(
        &indices,
        &positions,
        &locks,
        target,
        level_error(level),
        SimplifyOptions::ErrorAbsolute,
        None,
    );
    if kept.is_empty() {
        return mesh.clone();
    }
    let mut map = vec![u32::MAX; mesh.positions.len()];
    let mut out = TriMesh::default();
    for t in kept.chunks_exact(3) {
        out.triangles.push([t[0], t[1], t[2]].map(|v| {
            let m = &mut map[v as usize];
            if *m == u32::MAX {
                *m = out.positions.len() as u32;
                out.positions.push(mesh.positions[v as usize]);
            }
            *m
        }));
    }
    out
}

/// Meshes joined into one, vertices at bit-equal positions welded.
pub fn join_welded(meshes: &[TriMesh]) -> TriMesh {
    let mut out = TriMesh::default();
    let mut ids: HashMap<[u32; 3], u32> = HashMap::default();
    for m in meshes {
        let map: Vec<u32> = m
            .positions
            .iter()
            .map(|&p| {
                *ids.entry(p.to_array().map(f32::to_bits)).or_insert_with(|| {
                    out.positions.push(p);
                    (out.positions.len() - 1) as u32
                })
            })
            .collect();
        out.triangles.extend(m.triangles.iter().map(|t| t.map(|v| map[v as usize])));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(m: &TriMesh) -> f64 {
        m.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.positions[i as usize].as_dvec3());
                (b - a).cross(c - a).length() / 2.0
            })
            .sum()
    }

    fn one(a: Vec3, b: Vec3, c: Vec3) -> TriMesh {
        TriMesh { positions: vec![a, b, c], normals: Vec::new(), triangles: vec![[0, 1, 2]] }
    }

    #[test]
    fn a_triangle_cut_by_a_face_splits_between_the_two_boxes() {
        let t = one(Vec3::new(-0.7, 0.1, 0.2), Vec3::new(1.3, 0.3, 0.4), Vec3::new(0.3, 0.9, 0.6));
        let left = clip_to_box(&t, [-2.0, -2.0, -2.0], [0.0, 2.0, 2.0]);
        let right = clip_to_box(&t, [0.0, -2.0, -2.0], [2.0, 2.0, 2.0]);
        assert!((area(&left) + area(&right) - area(&t)).abs() < 1e-6);
        // The cut points on x = 0 are the same bits in both.
        let on = |m: &TriMesh| {
            let mut v: Vec<[u32; 3]> =
                m.positions.iter().filter(|p| p.x == 0.0).map(|p| p.to_array().map(f32::to_bits)).collect();
            v.sort_unstable();
            v
        };
        assert_eq!(on(&left).len(), 2);
        assert_eq!(on(&left), on(&right));
        // The winding is kept.
        let n = |m: &TriMesh| {
            let [a, b, c] = m.triangles[0].map(|i| m.positions[i as usize]);
            (b - a).cross(c - a).z
        };
        assert!(n(&left) > 0.0 && n(&right) > 0.0);
    }

    #[test]
    fn a_triangle_in_a_face_goes_to_one_box() {
        let t = one(Vec3::new(1.0, 0.1, 0.1), Vec3::new(1.0, 0.8, 0.1), Vec3::new(1.0, 0.1, 0.9));
        assert_eq!(clip_to_box(&t, [0.0; 3], [1.0, 2.0, 2.0]).triangles.len(), 0);
        assert_eq!(clip_to_box(&t, [1.0, 0.0, 0.0], [2.0; 3]).triangles.len(), 1);
    }

    #[test]
    fn a_triangle_across_a_corner_keeps_its_area_over_eight_boxes() {
        let t = one(Vec3::new(-0.9, -0.8, -0.3), Vec3::new(0.9, -0.2, 0.7), Vec3::new(-0.1, 0.95, 0.4));
        let mut total = 0.0;
        for i in 0..8 {
            let lo = [0, 1, 2].map(|a| if i >> a & 1 == 0 { -1.0 } else { 0.0 });
            let hi = lo.map(|v| v + 1.0);
            total += area(&clip_to_box(&t, lo, hi));
        }
        assert!((total - area(&t)).abs() < 1e-6, "{total} {}", area(&t));
    }

    #[test]
    fn simplification_keeps_the_box_faces_and_stays_inside() {
        // A finely triangulated square in z = 0.5 across the box [0, 4] x [0, 4] x [0, 1].
        let n = 16;
        let mut m = TriMesh::default();
        for y in 0..=n {
            for x in 0..=n {
                m.positions.push(Vec3::new(4.0 * x as f32 / n as f32, 4.0 * y as f32 / n as f32, 0.5));
            }
        }
        for y in 0..n {
            for x in 0..n {
                let a = (y * (n + 1) + x) as u32;
                let r = (n + 1) as u32;
                m.triangles.push([a, a + 1, a + r]);
                m.triangles.push([a + 1, a + r + 1, a + r]);
            }
        }
        let s = simplify_locked(&m, [0.0, 0.0, 0.0], [4.0, 4.0, 1.0], 2);
        assert!(s.triangles.len() < m.triangles.len() / 2, "{} of {}", s.triangles.len(), m.triangles.len());
        assert!((area(&s) - 16.0).abs() < 1e-4);
        let boundary = |mm: &TriMesh| {
            let mut v: Vec<[u32; 3]> = mm
                .positions
                .iter()
                .filter(|p| p.x == 0.0 || p.x == 4.0 || p.y == 0.0 || p.y == 4.0)
                .map(|p| p.to_array().map(f32::to_bits))
                .collect();
            v.sort_unstable();
            v
        };
        assert_eq!(boundary(&s), boundary(&m));
        let joined = join_welded(&[s.clone(), s.clone()]);
        assert_eq!(joined.positions.len(), s.positions.len());
    }
}
