//! A bounding volume hierarchy over triangles, answering the two queries a mesh field needs:
//! the closest point (exact unsigned distance) and the generalized winding number
//! (Jacobson, Kavan & Sorkine-Hornung 2013, "Robust inside-outside segmentation using generalized
//! winding numbers", DOI 10.1145/2461912.2461916), accelerated by the far-field dipole
//! approximation of Barill et al. 2018 ("Fast winding numbers for soups and clouds",
//! DOI 10.1145/3197517.3201337).
//!
//! Built by median split on the longest axis of the triangle centroids; leaves hold up to
//! [`LEAF_SIZE`] triangles. Queries are read-only and may run from many threads at once.

use crate::geometry::{closest_point_on_triangle, solid_angle, Aabb};
use glam::{DVec3, Vec3};

/// Most triangles in one leaf.
pub const LEAF_SIZE: usize = 4;

/// Far-field acceptance ratio: a node is approximated by its dipole when the query is farther
/// than `BETA` times the node's radius from its area-weighted centre (Barill et al. use 2).
pub const BETA: f64 = 2.0;

#[derive(Clone, Debug)]
struct Node {
    bounds: Aabb,
    /// Leaf: first triangle; inner: index of the left child (the right child is `left + 1`).
    start: u32,
    /// Leaf: triangle count; inner: 0.
    count: u32,
    /// Area-weighted centroid of the node's triangles.
    centre: DVec3,
    /// Sum of area-weighted normals (half the cross products).
    normal_sum: DVec3,
    /// Largest distance from `centre` to a vertex of the node's triangles.
    radius: f64,
    /// Total area of the node's triangles (bounds its dipole's variation).
    area: f64,
}

/// What [`TriangleBvh::winding_interval`] knows of the winding number over a box: the exact
/// winding number moves by at most `error` across the box, and every point of the box is at least
/// `distance` from every triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WindingInterval {
    /// The fast winding number at the box's centre.
    pub centre: f64,
    /// Bound on how far the exact winding number anywhere in the box is from `centre`.
    pub error: f64,
    /// Lower bound on the distance from any point of the box to the mesh.
    pub distance: f32,
}

/// Largest share of [`TriangleBvh::winding_interval`]'s budget one far node's dipole may take;
/// a node whose bound exceeds it is opened instead.
const NODE_ERROR_SHARE: f64 = 0.02;

/// A triangle BVH. Triangles are stored by value, in tree order.
#[derive(Clone, Debug)]
pub struct TriangleBvh {
    nodes: Vec<Node>,
    triangles: Vec<[Vec3; 3]>,
    /// Original index of each stored triangle.
    ids: Vec<u32>,
}

impl TriangleBvh {
    /// Builds the hierarchy. `triangles` holds vertex positions, wound counter-clockwise seen from
    /// outside. An empty input gives an empty tree (every query then answers "far, outside").
    pub fn new(triangles: Vec<[Vec3; 3]>) -> Self {
        let mut tagged: Vec<([Vec3; 3], u32)> = triangles.into_iter().zip(0..).collect();
        let mut nodes = Vec::with_capacity(2 * tagged.len() / LEAF_SIZE + 1);
        if !tagged.is_empty() {
            nodes.push(placeholder());
            build(&mut nodes, &mut tagged, 0, 0);
        }
        let (triangles, ids) = tagged.into_iter().unzip();
        Self { nodes, triangles, ids }
    }

    /// Calls `visit(id, triangle)` for every triangle whose bounds overlap `query` (closed boxes),
    /// where `id` is the triangle's index in the input to [`TriangleBvh::new`].
    pub fn for_each_overlapping(&self, query: &Aabb, mut visit: impl FnMut(u32, &[Vec3; 3])) {
        if self.nodes.is_empty() {
            return;
        }
        let overlaps = |b: &Aabb| b.min.cmple(query.max).all() && query.min.cmple(b.max).all();
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            if !overlaps(&node.bounds) {
                continue;
            }
            if node.count > 0 {
                for k in node.start as usize..(node.start + node.count) as usize {
                    let t = &self.triangles[k];
                    let b = triangle_bounds(t);
                    if overlaps(&b) {
                        visit(self.ids[k], t);
                    }
                }
            } else {
                stack[top] = node.start;
                stack[top + 1] = node.start + 1;
                top += 2;
            }
        }
    }

    /// A lower bound on the distance from every point of `region` to every triangle, when it is
    /// at least `limit` (the distance between the box and the nearest triangle's bounding box,
    /// shaved by a relative 1e-5 against rounding); `None` when some triangle's bounding box
    /// comes nearer than `limit`. Stops at the first such triangle.
    pub fn distance_from_box_at_least(&self, region: &Aabb, limit: f32) -> Option<f32> {
        if self.nodes.is_empty() {
            return Some(f32::INFINITY);
        }
        let limit = f64::from(limit);
        let mut nearest = f64::INFINITY;
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            let gap = box_distance(region, &node.bounds);
            if gap >= nearest {
                continue;
            }
            if node.count > 0 {
                for t in &self.triangles[node.start as usize..(node.start + node.count) as usize] {
                    let b = triangle_bounds(t);
                    nearest = nearest.min(box_distance(region, &b));
                }
            } else if gap >= limit {
                nearest = nearest.min(gap);
            } else {
                stack[top] = node.start;
                stack[top + 1] = node.start + 1;
                top += 2;
            }
            if nearest < limit {
                return None;
            }
        }
        Some((nearest * (1.0 - 1e-5)) as f32)
    }

    /// The triangles, in tree order.
    pub fn triangles(&self) -> &[[Vec3; 3]] {
        &self.triangles
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// Whether the tree holds no triangle.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// Bounds of all triangles.
    pub fn bounds(&self) -> Aabb {
        self.nodes.first().map_or(Aabb::empty(), |n| n.bounds)
    }

    /// The closest point on any triangle to `p`, and its squared distance.
    pub fn closest_point(&self, p: Vec3) -> Option<(Vec3, f32)> {
        self.closest(p).map(|(q, d, _)| (q, d))
    }

    /// The closest point on any triangle to `p` and its squared distance, if one is nearer than
    /// `radius` (a query that stops early: far points cost almost nothing).
    pub fn closest_point_within(&self, p: Vec3, radius: f32) -> Option<(Vec3, f32)> {
        self.closest_within(p, radius * radius).map(|(q, d, _)| (q, d))
    }

    fn closest(&self, p: Vec3) -> Option<(Vec3, f32, u32)> {
        self.closest_within(p, f32::INFINITY)
    }

    fn closest_within(&self, p: Vec3, radius_squared: f32) -> Option<(Vec3, f32, u32)> {
        if self.nodes.is_empty() {
            return None;
        }
        let mut best = (Vec3::ZERO, radius_squared, u32::MAX);
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            if node.bounds.distance_squared(p) >= best.1 {
                continue;
            }
            if node.count > 0 {
                for k in node.start as usize..(node.start + node.count) as usize {
                    let t = &self.triangles[k];
                    let q = closest_point_on_triangle(p, t[0], t[1], t[2]);
                    let d = q.distance_squared(p);
                    if d < best.1 {
                        best = (q, d, self.ids[k]);
                    }
                }
            } else {
                // Visit the nearer child first: push it last.
                let (l, r) = (node.start, node.start + 1);
                let dl = self.nodes[l as usize].bounds.distance_squared(p);
                let dr = self.nodes[r as usize].bounds.distance_squared(p);
                let (near, far) = if dl <= dr { (l, r) } else { (r, l) };
                stack[top] = far;
                stack[top + 1] = near;
                top += 2;
            }
        }
        (best.2 != u32::MAX).then_some(best)
    }

    /// The generalized winding number at `p`: about 1 inside a closed outward mesh, 0 outside, and
    /// a smooth in-between value near holes.
    pub fn winding_number(&self, p: Vec3) -> f64 {
        if self.nodes.is_empty() {
            return 0.0;
        }
        let q = p.as_dvec3();
        let mut total = 0.0;
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            let to_centre = node.centre - q;
            let dist = to_centre.length();
            if node.count == 0 && dist > BETA * node.radius {
                total += to_centre.dot(node.normal_sum) / (dist * dist * dist);
            } else if node.count > 0 {
                let range = node.start as usize..(node.start + node.count) as usize;
                for t in &self.triangles[range] {
                    total += solid_angle(p, t[0], t[1], t[2]);
                }
            } else {
                stack[top] = node.start;
                stack[top + 1] = node.start + 1;
                top += 2;
            }
        }
        total / (4.0 * std::f64::consts::PI)
    }

    /// The fast winding number at the centre of a box, with a bound on how much the exact winding
    /// number varies across the box, so that a box whose interval keeps clear of a threshold can
    /// take one inside/outside answer for all its points.
    ///
    /// The centre's value is [`TriangleBvh::winding_number`]'s. The variation bound comes from
    /// the kernel `k(y) = y / |y|^3` of the solid angle, whose Jacobian has norm `2 / |y|^3`: the
    /// solid angle of triangles of total area `A`, all at least `D > 0` from the box, moves by at
    /// most `2 A R / D^3` across a box of half-diagonal `R`. A node is taken whole when its term
    /// is at most `NODE_ERROR_SHARE` of the budget, and opened otherwise; `D` is the distance
    /// between bounding boxes, or for a single triangle the larger of that and its distance from
    /// the box's centre less `R`.
    ///
    /// Returns `None` when the bound exceeds `budget` (in winding-number units) or a triangle's
    /// bounding box touches the box: the caller splits the box and asks again.
    pub fn winding_interval(&self, region: &Aabb, budget: f64) -> Option<WindingInterval> {
        let (error, distance) = self.winding_variation(region, budget * 4.0 * std::f64::consts::PI)?;
        let scale = 1.0 / (4.0 * std::f64::consts::PI);
        Some(WindingInterval { centre: self.winding_number(region.centre()), error: error * scale, distance })
    }

    /// The variation bound of [`TriangleBvh::winding_interval`] in steradians, and the distance
    /// from the box to the nearest bounding box taken.
    fn winding_variation(&self, region: &Aabb, budget: f64) -> Option<(f64, f32)> {
        if self.nodes.is_empty() {
            return Some((0.0, f32::INFINITY));
        }
        let half_diagonal = 0.5 * region.extent().as_dvec3().length();
        let centre = region.centre();
        let node_budget = NODE_ERROR_SHARE * budget;
        let (mut error, mut distance) = (0.0, f64::INFINITY);
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            let gap = box_distance(region, &node.bounds);
            let node_error = if gap > 0.0 { 2.0 * node.area * half_diagonal / gap.powi(3) } else { f64::INFINITY };
            if node_error <= node_budget {
                error += node_error;
                distance = distance.min(gap);
            } else if node.count > 0 {
                for t in &self.triangles[node.start as usize..(node.start + node.count) as usize] {
                    let b = triangle_bounds(t);
                    let to_triangle = closest_point_on_triangle(centre, t[0], t[1], t[2]).distance(centre) as f64;
                    let gap = box_distance(region, &b).max(to_triangle - half_diagonal);
                    if gap <= 0.0 {
                        return None;
                    }
                    let area = 0.5 * (t[1] - t[0]).as_dvec3().cross((t[2] - t[0]).as_dvec3()).length();
                    error += 2.0 * area * half_diagonal / gap.powi(3);
                    distance = distance.min(gap);
                }
            } else {
                stack[top] = node.start;
                stack[top + 1] = node.start + 1;
                top += 2;
            }
            if error > budget {
                return None;
            }
        }
        // Shaved by a relative 1e-5 so that rounding never lifts the bound above a distance.
        Some((error, (distance * (1.0 - 1e-5)) as f32))
    }
}

/// The bounding box of one triangle.
fn triangle_bounds(t: &[Vec3; 3]) -> Aabb {
    let mut b = Aabb::empty();
    t.iter().for_each(|&v| b.grow(v));
    b
}

/// Distance between two boxes (0 when they touch or overlap).
fn box_distance(a: &Aabb, b: &Aabb) -> f64 {
    let gap = (a.min - b.max).max(b.min - a.max).max(Vec3::ZERO);
    gap.as_dvec3().length()
}

fn placeholder() -> Node {
    Node { bounds: Aabb::empty(), start: 0, count: 0, centre: DVec3::ZERO, normal_sum: DVec3::ZERO, radius: 0.0, area: 0.0 }
}

/// Builds the subtree for `tris` (a slice starting at triangle `offset`) into `nodes[index]`.
fn build(nodes: &mut Vec<Node>, tris: &mut [([Vec3; 3], u32)], offset: usize, index: usize) {
    let mut bounds = Aabb::empty();
    let mut centroid_bounds = Aabb::empty();
    let mut weighted = DVec3::ZERO;
    let mut area_sum = 0.0;
    let mut normal_sum = DVec3::ZERO;
    for (t, _) in tris.iter() {
        for v in t {
            bounds.grow(*v);
        }
        let c = (t[0] + t[1] + t[2]) / 3.0;
        centroid_bounds.grow(c);
        let n = 0.5 * (t[1] - t[0]).as_dvec3().cross((t[2] - t[0]).as_dvec3());
        let area = n.length();
        weighted += c.as_dvec3() * area;
        area_sum += area;
        normal_sum += n;
    }
    let centre = if area_sum > 0.0 { weighted / area_sum } else { bounds.centre().as_dvec3() };
    let radius = tris.iter().flat_map(|(t, _)| t.iter()).map(|v| v.as_dvec3().distance(centre)).fold(0.0, f64::max);
    let node = Node { bounds, start: offset as u32, count: tris.len() as u32, centre, normal_sum, radius, area: area_sum };
    if tris.len() <= LEAF_SIZE {
        nodes[index] = node;
        return;
    }
    let axis = centroid_bounds.extent().max_position();
    let mid = tris.len() / 2;
    let key = |(t, _): &([Vec3; 3], u32)| (t[0][axis] + t[1][axis] + t[2][axis]) / 3.0;
    tris.select_nth_unstable_by(mid, |a, b| key(a).total_cmp(&key(b)));
    let left = nodes.len();
    nodes.push(placeholder());
    nodes.push(placeholder());
    nodes[index] = Node { start: left as u32, count: 0, ..node };
    let (lo, hi) = tris.split_at_mut(mid);
    build(nodes, lo, offset, left);
    build(nodes, hi, offset + mid, left + 1);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube_triangles() -> Vec<[Vec3; 3]> {
        // Unit cube [0,1]^3, outward counter-clockwise.
        let v = |i: usize| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32);
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        quads.iter().flat_map(|q| [[v(q[0]), v(q[1]), v(q[2])], [v(q[0]), v(q[2]), v(q[3])]]).collect()
    }

    #[test]
    fn closest_point_and_winding_agree_with_brute_force() {
        // Subdivide the cube faces so the tree has depth.
        let mut tris = Vec::new();
        for t in cube_triangles() {
            let m = [(t[0] + t[1]) * 0.5, (t[1] + t[2]) * 0.5, (t[2] + t[0]) * 0.5];
            tris.extend([[t[0], m[0], m[2]], [m[0], t[1], m[1]], [m[2], m[1], t[2]], [m[0], m[1], m[2]]]);
        }
        let bvh = TriangleBvh::new(tris.clone());
        for p in [Vec3::splat(0.5), Vec3::new(0.9, 0.1, 0.2), Vec3::new(2.0, -1.0, 0.5), Vec3::new(0.5, 0.5, 1.3)] {
            let brute = tris
                .iter()
                .map(|t| closest_point_on_triangle(p, t[0], t[1], t[2]).distance_squared(p))
                .fold(f32::INFINITY, f32::min);
            assert!((bvh.closest_point(p).unwrap().1 - brute).abs() < 1e-6);
            let exact: f64 = tris.iter().map(|t| solid_angle(p, t[0], t[1], t[2])).sum::<f64>() / (4.0 * std::f64::consts::PI);
            let inside = Aabb::new(Vec3::ZERO, Vec3::ONE).contains(p);
            assert!((exact - if inside { 1.0 } else { 0.0 }).abs() < 1e-9);
            assert!((bvh.winding_number(p) - exact).abs() < 0.05, "{p}: {} vs {exact}", bvh.winding_number(p));
        }
    }
}
