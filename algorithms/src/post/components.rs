//! # Keep components (post-process)
//!
//! A scan's isosurface comes with islands: noise, vessels cut by the iso-value, a few voxels of
//! skull at a brain's threshold. `keep-components` drops them: the mesh's connected components
//! (triangles joined through shared edges, as `metrics` and CGAL count them; two blobs touching
//! at a vertex are two components, and dropping one leaves the other whole) are
//! ranked by the volume they enclose, and only the `largest` of them (default 1; `0` keeps any
//! number) whose volume is at least `min-volume` grid cells (default 0) are kept. Volumes are in
//! cells (voxels, for a volume meshed on its own grid: spacing cubed), so one option value means
//! the same on any scan; an open component (one that reaches an open border) is ranked by the
//! volume its triangles bound about its own centre, which is no longer an enclosed volume.
//!
//! What it keeps is the input's: every kept triangle, vertex and normal unchanged, in their
//! order; unused vertices are dropped. So a closed, manifold, outward mesh stays so (each
//! component keeps its own Euler characteristic; the whole loses the dropped ones') and no
//! intersection is added. As `--post keep-components:largest=1` on the command line, or
//! `post=["keep-components:min-volume=100"]` from Python.
//!
//! ```
//! use isolab_algorithms::post::build_post;
//! use isolab_algorithms::{fields, Extraction, Extractor, Grid, Samples};
//! use isolab_algorithms::extractors::marching_cubes::MarchingCubes;
//! // One sphere is one component: keeping the largest drops nothing.
//! let field = fields::builtin("sphere", Default::default()).unwrap();
//! let samples = Samples::sample_cubic(field.clone(), Grid::covering(&field.domain(), 24).unwrap(), 0.0).unwrap();
//! let mut out = Extraction::default();
//! MarchingCubes::default().extract(&samples, &mut out).unwrap();
//! let before = out.surface.triangles.len();
//! build_post("keep-components:largest=1").unwrap().unwrap().apply(&samples, &mut out).unwrap();
//! assert_eq!(out.surface.triangles.len(), before, "one sphere is one component: nothing dropped");
//! ```

use crate::extract::{ExtractError, Extraction, PostGuarantees, PostInfo, PostProcess};
use crate::mesh::TriMesh;
use crate::options::{OptionError, Options};
use crate::samples::Samples;
use glam::DVec3;
use petgraph::unionfind::UnionFind;
use std::time::Instant;

/// The options, in the order `isolab list` shows them.
pub const OPTION_NAMES: &[&str] = &["largest", "min-volume"];

/// One line for listings.
pub const DESCRIPTION: &str =
    "keep the largest connected components (by enclosed volume) and drop those under a volume in grid cells: a scan's islands";

/// How many components `largest` keeps by default.
pub const DEFAULT_LARGEST: usize = 1;

/// The registry entry.
pub const INFO: PostInfo = PostInfo {
    name: "keep-components",
    description: DESCRIPTION,
    options: OPTION_NAMES,
    make: from_options,
    guarantees: PostGuarantees {
        keeps_closed_manifold: true,
        keeps_outward: true,
        adds_no_intersection: true,
        keeps_every_component: false,
    },
};

/// Which components to keep.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KeepComponents {
    /// How many of the largest to keep (`0`: any number).
    pub largest: usize,
    /// The least volume kept, in grid cells.
    pub min_volume_cells: f64,
}

impl Default for KeepComponents {
    fn default() -> Self {
        Self { largest: DEFAULT_LARGEST, min_volume_cells: 0.0 }
    }
}

/// Builds it from named options.
pub fn from_options(options: &Options) -> Result<Box<dyn PostProcess>, OptionError> {
    let mut r = options.reader(INFO.name, OPTION_NAMES);
    let largest = r.count("largest", DEFAULT_LARGEST, u32::MAX as usize)?;
    let min_volume_cells = r.parse("min-volume", 0.0, |v| match v.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x >= 0.0 => Ok(x),
        Ok(_) => Err("must be a volume in grid cells, at least 0".into()),
        Err(_) => Err("is not a number".into()),
    })?;
    r.finish()?;
    Ok(Box::new(KeepComponents { largest, min_volume_cells }))
}

impl PostProcess for KeepComponents {
    fn name(&self) -> &'static str {
        INFO.name
    }

    fn description(&self) -> &'static str {
        INFO.description
    }

    fn apply(&self, samples: &Samples, out: &mut Extraction) -> Result<(), ExtractError> {
        if out.surface.triangles.is_empty() && !out.volume.tetrahedra.is_empty() {
            return Err(ExtractError::NoSurface { post: self.name() });
        }
        let t = Instant::now();
        let cell_volume = f64::from(samples.grid().spacing).powi(3);
        let components = Components::of(&out.surface);
        let keep = components.kept(self.largest, self.min_volume_cells * cell_volume);
        let before = out.surface.triangles.len();
        let kept_vertices = keep_triangles(&mut out.surface, |t| keep[components.of_triangle(t) as usize]);
        if out.origins.vertices.len() == kept_vertices.len() {
            let mut k = kept_vertices.iter();
            out.origins.vertices.retain(|_| *k.next().unwrap_or(&false));
        }
        out.stats.discarded_triangles += before - out.surface.triangles.len();
        out.stats.vertices = out.surface.positions.len();
        out.stats.triangles = out.surface.triangles.len();
        out.stats.times.post += t.elapsed();
        Ok(())
    }
}

/// A mesh's connected components: triangles joined through shared edges, as `metrics` counts
/// them (and CGAL and MeshLab): two spheres touching at one vertex are two components.
#[derive(Clone, Debug)]
pub struct Components {
    /// Each triangle's component.
    triangle: Vec<u32>,
    /// Each component's triangle count.
    pub triangles: Vec<usize>,
    /// Each component's volume (the absolute signed volume its triangles bound about their own
    /// centre: the enclosed volume of a closed component).
    pub volumes: Vec<f64>,
}

impl Components {
    /// The components of `mesh`, numbered in the order of their first triangle.
    pub fn of(mesh: &TriMesh) -> Self {
        let count_t = mesh.triangles.len();
        // Each edge (smaller vertex in the high half) with a triangle holding it; triangles on
        // the same edge are joined.
        let mut edges: Vec<(u64, u32)> = mesh
            .triangles
            .iter()
            .enumerate()
            .flat_map(|(t, tri)| {
                (0..3).map(move |k| {
                    let (a, b) = (tri[k], tri[(k + 1) % 3]);
                    ((u64::from(a.min(b)) << 32) | u64::from(a.max(b)), t as u32)
                })
            })
            .collect();
        edges.sort_unstable();
        let mut union = UnionFind::<u32>::new(count_t);
        for pair in edges.windows(2) {
            if pair[0].0 == pair[1].0 {
                union.union(pair[0].1, pair[1].1);
            }
        }
        let mut number = vec![u32::MAX; count_t];
        let mut triangle = vec![u32::MAX; count_t];
        let mut count = 0u32;
        for (t, component) in triangle.iter_mut().enumerate() {
            let root = union.find(t as u32) as usize;
            if number[root] == u32::MAX {
                number[root] = count;
                count += 1;
            }
            *component = number[root];
        }
        let mut components = Self { triangle, triangles: vec![0; count as usize], volumes: vec![0.0; count as usize] };
        let mut centres = vec![(DVec3::ZERO, 0usize); count as usize];
        for (i, t) in mesh.triangles.iter().enumerate() {
            let c = components.triangle[i] as usize;
            components.triangles[c] += 1;
            let (sum, k) = &mut centres[c];
            *sum += t.iter().map(|&v| mesh.positions[v as usize].as_dvec3()).sum::<DVec3>();
            *k += 3;
        }
        let centres: Vec<DVec3> = centres.iter().map(|&(sum, k)| sum / k.max(1) as f64).collect();
        let mut signed = vec![0.0f64; count as usize];
        for (i, t) in mesh.triangles.iter().enumerate() {
            let c = components.triangle[i] as usize;
            let [a, b, d] = t.map(|v| mesh.positions[v as usize].as_dvec3() - centres[c]);
            signed[c] += a.dot(b.cross(d)) / 6.0;
        }
        components.volumes = signed.iter().map(|v| v.abs()).collect();
        components
    }

    /// How many components there are.
    pub fn count(&self) -> usize {
        self.triangles.len()
    }

    /// The component of the mesh's triangle number `t`.
    pub fn of_triangle(&self, t: usize) -> u32 {
        self.triangle[t]
    }

    /// Which components to keep: those of volume at least `min_volume`, the `largest` of them by
    /// volume (ties: more triangles, then the earlier), all of them when `largest` is 0.
    pub fn kept(&self, largest: usize, min_volume: f64) -> Vec<bool> {
        let mut order: Vec<usize> = (0..self.count()).filter(|&c| self.volumes[c] >= min_volume).collect();
        order.sort_by(|&a, &b| {
            self.volumes[b].total_cmp(&self.volumes[a]).then(self.triangles[b].cmp(&self.triangles[a])).then(a.cmp(&b))
        });
        if largest > 0 {
            order.truncate(largest);
        }
        let mut keep = vec![false; self.count()];
        order.into_iter().for_each(|c| keep[c] = true);
        keep
    }
}

/// Keeps the triangles whose numbers `keep` accepts, in order, and the vertices they use
/// (positions and normals, in order); returns which of the input's vertices were kept.
fn keep_triangles(mesh: &mut TriMesh, keep: impl Fn(usize) -> bool) -> Vec<bool> {
    let mut number = 0..;
    mesh.triangles.retain(|_| keep(number.next().unwrap_or(0)));
    let mut used = vec![false; mesh.positions.len()];
    mesh.triangles.iter().flatten().for_each(|&v| used[v as usize] = true);
    let mut new_index = vec![u32::MAX; used.len()];
    let mut next = 0u32;
    for (v, &u) in used.iter().enumerate() {
        if u {
            new_index[v] = next;
            next += 1;
        }
    }
    let mut k = used.iter();
    mesh.positions.retain(|_| *k.next().unwrap_or(&false));
    if mesh.normals.len() == used.len() {
        let mut k = used.iter();
        mesh.normals.retain(|_| *k.next().unwrap_or(&false));
    }
    mesh.triangles.iter_mut().flatten().for_each(|v| *v = new_index[*v as usize]);
    used
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// A closed tetrahedron of edge `s` at `o`, wound outward.
    fn tetrahedron(mesh: &mut TriMesh, o: Vec3, s: f32) {
        let base = mesh.positions.len() as u32;
        let unit = TriMesh::unit_tetrahedron();
        mesh.positions.extend(unit.positions.iter().map(|&p| o + p * s));
        mesh.triangles.extend(unit.triangles.iter().map(|t| t.map(|v| v + base)));
    }

    #[test]
    fn components_are_counted_and_measured() {
        let mut mesh = TriMesh::default();
        tetrahedron(&mut mesh, Vec3::ZERO, 1.0);
        tetrahedron(&mut mesh, Vec3::splat(5.0), 2.0);
        tetrahedron(&mut mesh, Vec3::splat(-5.0), 0.5);
        let c = Components::of(&mesh);
        assert_eq!(c.count(), 3);
        assert_eq!(c.triangles, vec![4, 4, 4]);
        for (v, s) in c.volumes.iter().zip([1.0f64, 2.0, 0.5]) {
            assert!((v - s.powi(3) / 6.0).abs() < 1e-9, "{v} against {}", s.powi(3) / 6.0);
        }
        assert_eq!(c.kept(1, 0.0), vec![false, true, false]);
        assert_eq!(c.kept(2, 0.0), vec![true, true, false]);
        assert_eq!(c.kept(0, 0.1), vec![true, true, false]);
        assert_eq!(c.kept(0, 0.0), vec![true; 3]);
        assert_eq!(c.kept(0, 100.0), vec![false; 3]);
    }

    #[test]
    fn components_touching_at_a_vertex_are_two() {
        // Two tetrahedra sharing only vertex 0 (the second's apex): joined through a vertex, not
        // an edge; the smaller one dropped leaves the larger whole, the shared vertex kept.
        let mut mesh = TriMesh::default();
        tetrahedron(&mut mesh, Vec3::ZERO, 2.0);
        tetrahedron(&mut mesh, Vec3::splat(-1.0), 1.0);
        let apex = mesh.positions.len() as u32 - 1;
        mesh.positions[apex as usize] = Vec3::ZERO;
        mesh.triangles.iter_mut().flatten().filter(|v| **v == apex).for_each(|v| *v = 0);
        let c = Components::of(&mesh);
        assert_eq!(c.count(), 2);
        assert_eq!(c.triangles, vec![4, 4]);
        assert_eq!(c.kept(1, 0.0), vec![true, false]);
        let kept = keep_triangles(&mut mesh, |t| c.kept(1, 0.0)[c.of_triangle(t) as usize]);
        assert!(kept[0], "the shared vertex stays with the kept tetrahedron");
        assert_eq!(mesh.triangles.len(), 4);
        assert_eq!(mesh.positions.len(), 4);
    }

    #[test]
    fn kept_triangles_and_vertices_are_the_inputs_in_order() {
        let mut mesh = TriMesh::default();
        tetrahedron(&mut mesh, Vec3::ZERO, 1.0);
        tetrahedron(&mut mesh, Vec3::splat(5.0), 2.0);
        mesh.compute_face_weighted_normals();
        let input = mesh.clone();
        let kept = keep_triangles(&mut mesh, |t| t >= 4);
        assert_eq!(kept, [vec![false; 4], vec![true; 4]].concat());
        assert_eq!(mesh.positions, input.positions[4..]);
        assert_eq!(mesh.normals, input.normals[4..]);
        assert_eq!(mesh.triangles, input.triangles[4..].iter().map(|t| t.map(|v| v - 4)).collect::<Vec<_>>());
    }

    #[test]
    fn bad_options_name_the_option() {
        for (option, bad) in
            [("largest", "-1"), ("largest", "two"), ("min-volume", "-3"), ("min-volume", "nan"), ("minimum", "1")]
        {
            let mut o = Options::new();
            o.set(option, bad);
            let e = from_options(&o).err().expect("refused").to_string();
            assert!(e.contains(option), "{e}");
        }
    }
}
