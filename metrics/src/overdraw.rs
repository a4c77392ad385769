//! Rendering cost: quad overshading.
//!
//! GPUs run the pixel shader on 2x2 pixel quads, so a triangle that covers one pixel of a quad
//! still pays for four invocations. Small and thin triangles waste most of that work (the RMT
//! paper, Costen 2026, section 1.1). We rasterize the mesh with an orthographic camera at a given
//! resolution (pixel centres, top-left fill rule, back faces culled, depth test), then count:
//! - `covered_pixels`: pixels showing the mesh;
//! - `quad_invocations_visible`: 4 x the (triangle, quad) pairs where the triangle owns at least
//!   one visible pixel of the quad: the cost with a depth pre-pass (early z);
//! - `quad_invocations_all`: the same over every rasterized fragment, before the depth test;
//! - `overshading = quad_invocations_visible / covered_pixels` (ideal 1; 4 at worst for the
//!   visible pixels alone) and `depth_complexity = fragments / covered_pixels`.

use glam::{Vec2, Vec3};
use isolab_algorithms::TriMesh;
use serde::{Deserialize, Serialize};

/// Camera: orthographic, looking along `-direction` (from the `direction` side of the mesh), the
/// mesh's bounding box fitted to the image with a 5% margin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Direction from the mesh toward the camera.
    pub direction: Vec3,
}

impl Default for View {
    fn default() -> Self {
        Self { width: 1024, height: 1024, direction: Vec3::new(1.0, 0.8, 1.3) }
    }
}

/// Quad overshading report.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Overdraw {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Pixels showing the mesh.
    pub covered_pixels: u64,
    /// Front-facing fragments rasterized before the depth test.
    pub fragments: u64,
    /// Shader invocations with early depth testing.
    pub quad_invocations_visible: u64,
    /// Shader invocations without early depth testing.
    pub quad_invocations_all: u64,
    /// `quad_invocations_visible / covered_pixels` (ideal 1).
    pub overshading: f64,
    /// `fragments / covered_pixels` (1 for a convex mesh).
    pub depth_complexity: f64,
    /// Front-facing triangles that cover no pixel centre at all.
    pub triangles_without_pixels: u64,
}

/// Projects positions to pixel coordinates and depth for `view`.
pub fn project(mesh: &TriMesh, view: &View) -> Vec<Vec3> {
    let forward = -view.direction.normalize_or(Vec3::Z);
    let up_hint = if forward.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
    let right = forward.cross(up_hint).normalize();
    let up = right.cross(forward);
    let camera: Vec<Vec3> = mesh.positions.iter().map(|p| Vec3::new(p.dot(right), p.dot(up), p.dot(forward))).collect();
    let (mut lo, mut hi) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
    for c in &camera {
        lo = lo.min(c.truncate());
        hi = hi.max(c.truncate());
    }
    let size = Vec2::new(view.width as f32, view.height as f32);
    let extent = (hi - lo).max(Vec2::splat(1e-12));
    let scale = (size * 0.9 / extent).min_element();
    let centre = (lo + hi) * 0.5;
    camera
        .iter()
        .map(|c| {
            let s = (c.truncate() - centre) * scale;
            // Image y grows downward.
            Vec3::new(size.x * 0.5 + s.x, size.y * 0.5 - s.y, c.z)
        })
        .collect()
}

/// Rasterizes front faces with a depth test; calls `fragment(triangle, x, y, depth)` for every
/// covered pixel centre before the depth test, and returns the visible triangle per pixel.
pub fn rasterize(mesh: &TriMesh, screen: &[Vec3], width: u32, height: u32, mut fragment: impl FnMut(u32, u32, u32)) -> Vec<u32> {
    let (w, h) = (width as usize, height as usize);
    let mut depth = vec![f32::INFINITY; w * h];
    let mut id = vec![u32::MAX; w * h];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let [a, b, c] = tri.map(|i| screen[i as usize]);
        // Signed doubled area in image coordinates (y down): counter-clockwise seen from the
        // camera is negative here.
        let area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
        if area >= 0.0 {
            continue; // back-facing or degenerate
        }
        let (a, b) = (b, a); // make the winding positive in image space
        let area = -area;
        let edge = |p: Vec3, q: Vec3, x: f32, y: f32| (q.x - p.x) * (y - p.y) - (q.y - p.y) * (x - p.x);
        // Top-left rule: an edge owns its pixels when it is a top or a left edge.
        let owns = |p: Vec3, q: Vec3| (q.y == p.y && q.x < p.x) || q.y > p.y;
        let bias = [owns(b, c), owns(c, a), owns(a, b)];
        let x0 = a.x.min(b.x).min(c.x).floor().max(0.0) as usize;
        let x1 = (a.x.max(b.x).max(c.x).ceil() as usize).min(w);
        let y0 = a.y.min(b.y).min(c.y).floor().max(0.0) as usize;
        let y1 = (a.y.max(b.y).max(c.y).ceil() as usize).min(h);
        for y in y0..y1 {
            for x in x0..x1 {
                let (px, py) = (x as f32 + 0.5, y as f32 + 0.5);
                let e = [edge(b, c, px, py), edge(c, a, px, py), edge(a, b, px, py)];
                let inside = (0..3).all(|k| e[k] > 0.0 || (e[k] == 0.0 && bias[k]));
                if !inside {
                    continue;
                }
                let z = (e[0] * a.z + e[1] * b.z + e[2] * c.z) / area;
                fragment(t as u32, x as u32, y as u32);
                let i = x + w * y;
                if z < depth[i] {
                    depth[i] = z;
                    id[i] = t as u32;
                }
            }
        }
    }
    id
}

/// Quad overshading of `mesh` seen through `view`.
pub fn quad_overdraw(mesh: &TriMesh, view: &View) -> Overdraw {
    let screen = project(mesh, view);
    let quads_x = view.width.div_ceil(2) as u64;
    let quad = |x: u32, y: u32| u64::from(y / 2) * quads_x + u64::from(x / 2);
    let mut all: Vec<u64> = Vec::new();
    let mut touched = vec![false; mesh.triangles.len()];
    let ids = rasterize(mesh, &screen, view.width, view.height, |t, x, y| {
        all.push((u64::from(t) << 32) | quad(x, y));
        touched[t as usize] = true;
    });
    let fragments = all.len() as u64;
    all.sort_unstable();
    all.dedup();
    let mut visible: Vec<u64> = ids
        .iter()
        .enumerate()
        .filter(|(_, &t)| t != u32::MAX)
        .map(|(i, &t)| (u64::from(t) << 32) | quad(i as u32 % view.width, i as u32 / view.width))
        .collect();
    let covered = visible.len() as u64;
    visible.sort_unstable();
    visible.dedup();
    let front_facing_without_pixels = mesh
        .triangles
        .iter()
        .zip(&touched)
        .filter(|(tri, &hit)| {
            let [a, b, c] = tri.map(|i| screen[i as usize]);
            !hit && (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x) < 0.0
        })
        .count() as u64;
    let per = |n: u64| if covered > 0 { n as f64 / covered as f64 } else { 0.0 };
    Overdraw {
        width: view.width,
        height: view.height,
        covered_pixels: covered,
        fragments,
        quad_invocations_visible: 4 * visible.len() as u64,
        quad_invocations_all: 4 * all.len() as u64,
        overshading: per(4 * visible.len() as u64),
        depth_complexity: per(fragments),
        triangles_without_pixels: front_facing_without_pixels,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A square of two triangles facing the camera along +z.
    fn square(n: u32) -> TriMesh {
        // n x n grid of quads, each split in two.
        let mut m = TriMesh::default();
        for j in 0..=n {
            for i in 0..=n {
                m.positions.push(Vec3::new(i as f32 / n as f32, j as f32 / n as f32, 0.0));
            }
        }
        let v = |i: u32, j: u32| i + (n + 1) * j;
        for j in 0..n {
            for i in 0..n {
                m.triangles.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
                m.triangles.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
            }
        }
        m
    }

    #[test]
    fn big_triangles_shade_about_once_and_tiny_ones_four_times() {
        let view = View { width: 200, height: 200, direction: Vec3::Z };
        let coarse = quad_overdraw(&square(1), &view);
        assert_eq!(coarse.covered_pixels, 180 * 180);
        assert!((coarse.depth_complexity - 1.0).abs() < 1e-12, "no pixel is covered twice: {coarse:?}");
        assert!(coarse.overshading > 1.0 && coarse.overshading < 1.05, "{coarse:?}");
        let fine = quad_overdraw(&square(180), &view);
        assert!((fine.depth_complexity - 1.0).abs() < 1e-12, "{fine:?}");
        assert!(fine.overshading > 3.0, "{fine:?}");
        // Seen from behind, every face is culled.
        let back = quad_overdraw(&square(1), &View { direction: -Vec3::Z, ..view });
        assert_eq!(back.covered_pixels, 0);
    }
}
