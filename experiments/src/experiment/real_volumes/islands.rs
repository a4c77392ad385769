//! A scan's islands: the connected components an isosurface of a real volume comes with (noise,
//! vessels cut by the iso-value, specks of skull), counted per mesh, and what the
//! `keep-components` post-process leaves of them (ranked by the very function the post-process
//! uses, [`Components::kept`]).

use isolab_algorithms::post::components::Components;
use isolab_algorithms::TriMesh;
use serde::{Deserialize, Serialize};

/// The volume below which a component counts as an island here, in voxels: the value the page's
/// command passes to `keep-components:min-volume=`.
pub(crate) const MIN_ISLAND_VOXELS: f64 = 100.0;

/// `keep-components:largest=` values: the largest alone, and any number (with a volume floor).
pub(crate) const KEEP_LARGEST: usize = 1;
pub(crate) const KEEP_ANY: usize = 0;

/// The page's example of an object darker than its surroundings: a CT's air, below this many
/// Hounsfield units (water is 0, air -1000).
pub(crate) const AIR_ISO_HU: i32 = -500;

/// One mesh's components and what `keep-components` keeps of them.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub(crate) struct Islands {
    /// The volume threshold, voxels.
    pub(crate) min_volume_voxels: f64,
    pub(crate) components: usize,
    pub(crate) triangles: usize,
    /// After `keep-components:largest=0,min-volume=MIN_ISLAND_VOXELS`.
    pub(crate) components_after: usize,
    pub(crate) triangles_after: usize,
    /// The largest component's triangles (`keep-components:largest=1`).
    pub(crate) largest_triangles: usize,
}

/// The islands of `mesh` (in world coordinates, a voxel `voxel_volume` cubic world units).
pub(crate) fn islands(mesh: &TriMesh, voxel_volume: f64) -> Islands {
    let c = Components::of(mesh);
    let kept = c.kept(0, MIN_ISLAND_VOXELS * voxel_volume);
    let largest = c.kept(1, 0.0);
    let sum = |keep: &[bool]| keep.iter().zip(&c.triangles).filter(|(k, _)| **k).map(|(_, t)| t).sum::<usize>();
    Islands {
        min_volume_voxels: MIN_ISLAND_VOXELS,
        components: c.count(),
        triangles: mesh.triangles.len(),
        components_after: kept.iter().filter(|&&k| k).count(),
        triangles_after: sum(&kept),
        largest_triangles: sum(&largest),
    }
}

/// Table cells: components, after the threshold, triangles kept, the largest's share.
pub(crate) fn cells(i: &Islands) -> [String; 4] {
    let share = |t: usize| 100.0 * t as f64 / i.triangles.max(1) as f64;
    [
        i.components.to_string(),
        i.components_after.to_string(),
        format!("{:.1}%", share(i.triangles_after)),
        format!("{:.1}%", share(i.largest_triangles)),
    ]
}

/// The table's headers, matching [`cells`].
pub(crate) fn headers() -> [String; 4] {
    [
        "components".into(),
        format!("components of {MIN_ISLAND_VOXELS:.0} voxels or more"),
        "their triangles".into(),
        "the largest's triangles".into(),
    ]
}

/// One sentence over `islands` (label, islands): the range of components, what the threshold
/// leaves and keeps.
pub(crate) fn reading(what: &str, islands: &[(&str, &Islands)]) -> Option<String> {
    let range = |f: &dyn Fn(&Islands) -> f64| {
        let v: Vec<f64> = islands.iter().map(|(_, i)| f(i)).collect();
        (v.iter().copied().fold(f64::INFINITY, f64::min), v.iter().copied().fold(f64::NEG_INFINITY, f64::max))
    };
    if islands.is_empty() {
        return None;
    }
    let (c0, c1) = range(&|i| i.components as f64);
    let (a0, a1) = range(&|i| i.components_after as f64);
    let (k0, k1) = range(&|i| 100.0 * i.triangles_after as f64 / i.triangles.max(1) as f64);
    let span = |a: f64, b: f64, digits: usize| {
        if (a - b).abs() < 0.5 * 10f64.powi(-(digits as i32)) {
            format!("{a:.digits$}")
        } else {
            format!("{a:.digits$}-{b:.digits$}")
        }
    };
    Some(format!(
        "{what}: {} components per mesh; dropping those under {MIN_ISLAND_VOXELS:.0} voxels leaves {} and keeps {}% of the \
         triangles.",
        span(c0, c1, 0),
        span(a0, a1, 0),
        span(k0, k1, 1)
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn cube(mesh: &mut TriMesh, o: Vec3, s: f32) {
        let base = mesh.positions.len() as u32;
        for k in 0..8u32 {
            mesh.positions.push(o + Vec3::new((k & 1) as f32, (k >> 1 & 1) as f32, (k >> 2 & 1) as f32) * s);
        }
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        for q in quads {
            mesh.triangles.push([q[0], q[1], q[2]].map(|v| v + base));
            mesh.triangles.push([q[0], q[2], q[3]].map(|v| v + base));
        }
    }

    #[test]
    fn islands_count_what_the_post_process_keeps() {
        let mut mesh = TriMesh::default();
        cube(&mut mesh, Vec3::ZERO, 10.0); // 1000 voxels
        cube(&mut mesh, Vec3::splat(20.0), 2.0); // 8 voxels
        cube(&mut mesh, Vec3::splat(-20.0), 5.0); // 125 voxels
        let i = islands(&mesh, 1.0);
        assert_eq!((i.components, i.components_after, i.triangles, i.triangles_after, i.largest_triangles), (3, 2, 36, 24, 12));
        // With voxels of 8 world units, the 125-unit cube is under 100 voxels.
        assert_eq!(islands(&mesh, 8.0).components_after, 1);
        let r = reading("brain", &[("a", &i), ("b", &islands(&mesh, 8.0))]).unwrap();
        assert!(r.contains("3 components") && r.contains("leaves 1-2") && r.contains("33.3-66.7%"), "{r}");
    }
}
