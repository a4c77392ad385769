use super::cover::CoverProblem;
use super::lattice::signed_volume;
use super::*;
use crate::geometry::Aabb;

/// Distinct vertices of the surface's triangles.
fn surface_vertices(surface: &TriangleBvh) -> Vec<Vec3> {
    let mut seen = std::collections::HashSet::new();
    surface.triangles().iter().flatten().copied().filter(|p| seen.insert(p.to_array().map(f32::to_bits))).collect()
}

fn octahedron(r: f32) -> TriangleBvh {
    let v = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z].map(|p| p * r);
    let faces = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
    TriangleBvh::new(faces.iter().map(|f: &[usize; 3]| f.map(|i| v[i])).collect())
}

#[test]
fn lattice_tetrahedra_are_alike_and_fill_the_box() {
    let lattice = bcc_lattice(Aabb::cube(1.0), 0.5, DQuat::IDENTITY, DVec3::ZERO);
    let volume: f64 = lattice.tets.iter().map(|t| signed_volume(t.map(|v| lattice.positions[v as usize])) / 6.0).sum();
    for t in &lattice.tets {
        let p = t.map(|v| lattice.positions[v as usize]);
        assert!((signed_volume(p) / 6.0 - 0.125 / 12.0).abs() < 1e-9, "every tetrahedron has h³/12");
        let mut a = dihedral_angles(p);
        a.sort_by(f64::total_cmp);
        let expect = [60.0, 60.0, 60.0, 60.0, 90.0, 90.0];
        assert!(a.iter().zip(expect).all(|(x, e)| (x - e).abs() < 1e-4), "{a:?}");
    }
    assert!(volume > 8.0, "the lattice covers the box and its margin: {volume}");
    let interior = (0..lattice.positions.len() as u32).filter(|&v| lattice.star(v).len() == SNOWFLAKE).count();
    assert!(interior > 0 && lattice.star_start.windows(2).all(|w| w[1] - w[0] <= SNOWFLAKE as u32));
    // Faces pair up: every interior face has a neighbour that points back.
    for (t, n) in lattice.neighbours.iter().enumerate() {
        for &u in n.iter().filter(|&&u| u != u32::MAX) {
            assert!(lattice.neighbours[u as usize].contains(&(t as u32)));
        }
    }
}

#[test]
fn sculpting_keeps_every_overlapping_tetrahedron_and_defusing_leaves_no_bomb() {
    let surface = octahedron(1.0);
    for attempt in 0..4 {
        let (rotation, shift) = perturbation(7, attempt);
        let lattice = bcc_lattice(surface.bounds(), 0.37, rotation, shift);
        let mut keep = sculpt(&lattice, &surface);
        // Every kept tetrahedron overlaps the octahedron |x|+|y|+|z| <= 1, and every lattice
        // tetrahedron containing a point of it is kept.
        for (t, tet) in lattice.tets.iter().enumerate() {
            let p = tet.map(|v| lattice.positions[v as usize]);
            let centroid = (p[0] + p[1] + p[2] + p[3]) / 4.0;
            if centroid.abs().element_sum() < 0.999 {
                assert!(keep[t], "tetrahedron {t} holds interior point {centroid}");
            }
            if keep[t] {
                let nearest = p.iter().map(|q| q.abs().element_sum()).fold(f32::INFINITY, f32::min);
                assert!(nearest < 1.0 + 0.37 * 1.5, "kept tetrahedron {t} is far outside");
            }
        }
        let defused = defuse_bombs(&lattice, &mut keep);
        assert!(bombs(&lattice, &keep).is_empty(), "attempt {attempt}: {defused:?}");
    }
}

#[test]
fn the_cover_search_finds_the_cheapest_combination() {
    // Two bombs; vertex 2 covers both and costs 4 (greedy's pick); 0 and 1 cost 2 each but
    // share a tetrahedron, 3 together.
    let problem = CoverProblem {
        vertices: vec![10, 11, 12],
        cost: vec![vec![0, 1], vec![1, 2], vec![3, 4, 5, 6]],
        bombs: vec![vec![0, 2], vec![1, 2]],
        tets: 7,
    };
    let (mut chosen, exhaustive) = problem.solve(1000);
    chosen.sort();
    assert!(exhaustive);
    assert_eq!(chosen, vec![10, 11], "3 tetrahedra through the shared one beat greedy's 4");
    let problem = CoverProblem { cost: vec![vec![0, 1], vec![2, 3], vec![4, 5]], ..problem };
    let (chosen, _) = problem.solve(1000);
    assert_eq!(chosen, vec![12], "one snowflake of 2 beats two of 2 each");
}

#[test]
fn relaxed_mesh_encloses_and_approaches_the_surface() {
    let surface = octahedron(1.0);
    let options = SculptOptions { spacing: Some(0.4), offset_ratio: 0.6, ..Default::default() };
    let result = sculpt_surface(&surface, "octahedron", &options).unwrap();
    let r = &result.report;
    assert!(r.converged, "{r:?}");
    assert!(r.max_distance <= 0.24 + 1e-6);
    assert!(r.dihedral_deg[0] > 0.0, "no inverted tetrahedron: {r:?}");
    for t in &result.volume.tetrahedra {
        assert!(signed_volume(t.map(|v| result.volume.positions[v as usize])) > 0.0);
    }
    // Enclosure: no boundary vertex inside S, and S's vertices inside the boundary.
    let boundary =
        TriangleBvh::new(result.boundary.triangles.iter().map(|t| t.map(|i| result.boundary.positions[i as usize])).collect());
    for &p in &result.boundary.positions {
        assert!(surface.winding_number(p) < 0.5, "boundary vertex {p} went inside S");
    }
    for p in surface_vertices(&surface) {
        assert!(boundary.winding_number(p) > 0.5, "S vertex {p} is outside the tetrahedral mesh");
    }
}

#[test]
fn the_trace_records_every_iteration_and_changes_nothing() {
    let surface = octahedron(1.0);
    let options = SculptOptions { spacing: Some(0.4), offset_ratio: 0.3, ..Default::default() };
    let plain = sculpt_surface(&surface, "octahedron", &options).unwrap();
    assert!(plain.report.trace.is_empty(), "no trace unless asked");
    let traced = sculpt_surface(&surface, "octahedron", &SculptOptions { trace: true, ..options }).unwrap();
    let t = &traced.report.trace;
    assert_eq!(traced.volume.positions, plain.volume.positions, "tracing changes no step");
    assert_eq!(t.len(), traced.report.iterations);
    assert!(!t.is_empty());
    // The first entry is the sculpted lattice: every dihedral angle 60° or 90°, farthest
    // vertex beyond the offset (else no iteration would run).
    assert!((t[0].min_dihedral - 60.0).abs() < 1e-3, "{:?}", t[0]);
    assert!(t[0].max_distance_h > options.offset_ratio);
    assert!(t.iter().all(|i| i.min_dihedral >= f64::from(options.quality_floor) - 1e-9), "the floor holds: {t:?}");
    assert!(t.iter().all(|i| i.boundary_moved + i.interior_moved > 0), "every iteration moves something: {t:?}");
    // Distances shrink overall: the last recorded iteration is closer than the first.
    assert!(t[t.len() - 1].max_distance_h < t[0].max_distance_h);
}
#[test]
fn bad_settings_are_refused_by_name() {
    let surface = octahedron(1.0);
    let options = SculptOptions { spacing: Some(5.0), ..Default::default() };
    let err = sculpt_surface(&surface, "octahedron", &options).unwrap_err().to_string();
    assert!(err.contains("spacing 5") && err.contains("octahedron"), "{err}");
    let mut o = Options::new();
    o.set("offset-ratio", "0");
    assert!(from_options(&o).err().unwrap().to_string().contains("offset-ratio"));
    let mut o = Options::new();
    o.set("perturbations", "0");
    assert!(from_options(&o).err().unwrap().to_string().contains("perturbations"));
}
