//! Tests of the parent module.

use super::*;

fn decimated(decimator: &str, object: &str, min_angle_deg: f64) -> decimation::Row {
    decimation::Row {
        object: object.into(),
        input_triangles: 100,
        target: 25,
        decimator: decimator.into(),
        triangles: 25,
        aspect_mean: 1.2,
        min_angle_deg,
        degenerate: 0,
        hausdorff_h: 0.1,
        manifold: true,
        self_intersections: 0,
        ms: 1.0,
    }
}

#[test]
fn a_decimator_picked_for_distance_states_its_slivers() {
    let rows = [decimated("quadric", "sphere", 0.006), decimated("quadric", "bunny", 3.0), decimated("safe", "sphere", 14.7)];
    let s = sliver_caveat("quadric", &rows);
    assert!(s.contains("falls to 0.006° at worst (sphere, 25 triangles)"), "{s}");
    assert!(s.contains("where safe keeps 14.7° at its worst (sphere)"), "{s}");
    assert_eq!(sliver_caveat("absent", &rows), "");
    assert!(sliver_caveat("safe", &rows).ends_with("(sphere, 25 triangles)."));
}

#[test]
fn interpolates_between_bracketing_resolutions() {
    // Error halves as triangles double: 1e-3 sits half-way (in log) between 100 and 400.
    let pts = [(100, 2e-3), (400, 5e-4), (1600, 1.25e-4)];
    let (t, bound) = triangles_at_error(&pts, 1e-3).unwrap();
    assert!(!bound);
    assert!((t - 200.0).abs() < 1e-6, "{t}");
}

#[test]
fn the_tetrahedra_pick_states_where_it_converges_less_than_the_paper() {
    let s = convergence_misses(&[(0.2, 0, 20, 4, 16), (0.4, 1, 20, 12, 16)]);
    assert!(s.contains("at offset ratio 0.2 on 0 of 20 runs and at offset ratio 0.4 on 1 of 20 runs"), "{s}");
    let three = convergence_misses(&[(0.2, 0, 20, 4, 16), (0.4, 1, 20, 12, 16), (0.6, 18, 20, 16, 16)]);
    assert!(three.contains("0 of 20 runs, at offset ratio 0.4 on 1 of 20 runs and at offset ratio 0.6"), "{three}");
    assert!(s.contains("against the paper's 4 of 16 and 12 of 16"), "{s}");
    assert_eq!(convergence_misses(&[]), "");
}

#[test]
fn small_distances_keep_their_digits() {
    assert_eq!(spacings(0.0), "0.00");
    assert_eq!(spacings(0.2637), "0.26");
    assert_eq!(spacings(2.8e-6), "2.8e-6");
}

#[test]
fn coarsest_within_target_is_a_bound_and_unreached_is_none() {
    assert_eq!(triangles_at_error(&[(50, -1e-4), (200, 1e-5)], 1e-3), Some((50.0, true)));
    assert_eq!(triangles_at_error(&[(50, 1e-1), (200, -1e-2)], 1e-3), None);
    assert_eq!(triangles_at_error(&[], 1e-3), None);
}
