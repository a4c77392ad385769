//! `keep-components` on meshes with known islands: what it keeps is exactly the mesh of the
//! kept parts alone, for every surface extractor whose output welds its components apart.

use glam::Vec3;
use isolab_algorithms::post::build_post;
use isolab_algorithms::post::components::Components;
use isolab_algorithms::{extractors, Extraction, Grid, Lattice, Samples};
use isolab_tests::{assert_closed_manifold, grid_samples};

const N: usize = 40;
/// A big sphere and a small one, far apart (cells): `(centre, radius)`.
const BIG: (Vec3, f32) = (Vec3::new(12.0, 14.0, 15.0), 8.5);
const SMALL: (Vec3, f32) = (Vec3::new(30.0, 28.0, 27.0), 4.2);

/// Distance to the nearer of `spheres`, on an `N³` grid of unit spacing.
fn spheres(spheres: &[(Vec3, f32)]) -> Samples<'static> {
    grid_samples([N, N, N], |x, y, z| {
        let p = Vec3::new(x as f32, y as f32, z as f32);
        spheres.iter().map(|&(c, r)| (p - c).length() - r).fold(f32::INFINITY, f32::min)
    })
}

fn run(name: &str, samples: &Samples, post: Option<&str>) -> Extraction {
    let mut out = Extraction::default();
    extractors::by_name(name).expect("registered").extract(samples, &mut out).expect("extracts");
    if let Some(spec) = post {
        build_post(spec).expect("options").expect("registered").apply(samples, &mut out).expect("applies");
    }
    out
}

/// Surface extractors whose mesh of the two spheres has the two as its two components and whose
/// mesh of each sphere does not depend on the other (every one but those that move vertices by
/// global passes; checked below rather than assumed).
fn cell_local_surface_extractors() -> Vec<&'static str> {
    extractors::INFOS.iter().filter(|i| !(i.make)(&Default::default()).unwrap().produces_volume()).map(|i| i.name).collect()
}

#[test]
fn the_largest_component_is_the_big_spheres_mesh_alone() {
    let both = spheres(&[BIG, SMALL]);
    let big = spheres(&[BIG]);
    for name in cell_local_surface_extractors() {
        let whole = run(name, &both, None);
        let components = Components::of(&whole.surface);
        assert_eq!(components.count(), 2, "{name}: two spheres, two components");
        let kept = run(name, &both, Some("keep-components:largest=1"));
        let alone = run(name, &big, None);
        assert_eq!(kept.surface.triangles, alone.surface.triangles, "{name}: triangles");
        assert_eq!(kept.surface.positions, alone.surface.positions, "{name}: positions");
        assert_eq!(kept.stats.triangles, kept.surface.triangles.len(), "{name}: stats");
        assert_eq!(
            kept.stats.discarded_triangles - whole.stats.discarded_triangles,
            whole.surface.triangles.len() - kept.surface.triangles.len()
        );
        assert_closed_manifold(&kept.surface, name);
    }
}

#[test]
fn min_volume_is_in_grid_cells() {
    let both = spheres(&[BIG, SMALL]);
    let whole = run("marching-cubes", &both, None);
    let volumes = Components::of(&whole.surface).volumes;
    let ball = |r: f32| 4.0 / 3.0 * std::f64::consts::PI * f64::from(r).powi(3);
    // The meshes' volumes are the balls' within a few percent (marching cubes cuts the corners).
    for (v, r) in volumes.iter().zip([BIG.1, SMALL.1]) {
        assert!((v / ball(r) - 1.0).abs() < 0.05, "volume {v} against the ball's {}", ball(r));
    }
    let between = (volumes[0] * volumes[1]).sqrt();
    let keep_big = run("marching-cubes", &both, Some(&format!("keep-components:largest=0,min-volume={between}")));
    assert_eq!(keep_big.surface.triangles, run("marching-cubes", &spheres(&[BIG]), None).surface.triangles);
    let keep_both = run("marching-cubes", &both, Some(&format!("keep-components:largest=0,min-volume={}", volumes[1] * 0.99)));
    assert_eq!(keep_both.surface, whole.surface);
    let keep_none = run("marching-cubes", &both, Some(&format!("keep-components:largest=0,min-volume={}", volumes[0] * 1.01)));
    // The same values on a grid of spacing 2: the meshes' volumes are 8 times larger, the option
    // counts cells, so the same value keeps the same component.
    let doubled =
        Samples::from_values(Lattice::Cubic(Grid { spacing: 2.0, ..*both.grid() }), both.values().to_vec(), 0.0).expect("finite");
    let spec = format!("keep-components:largest=0,min-volume={between}");
    let kept = run("marching-cubes", &doubled, Some(&spec));
    assert_eq!(kept.surface.triangles, keep_big.surface.triangles);
    assert!(keep_none.surface.triangles.is_empty() && keep_none.surface.positions.is_empty());
}

#[test]
fn unknown_options_are_refused_by_name() {
    let e = build_post("keep-components:smallest=2").err().expect("refused").to_string();
    assert!(e.contains("smallest") && e.contains("largest"), "{e}");
}
