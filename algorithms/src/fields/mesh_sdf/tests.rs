//! `MeshField`'s tests: signs, distances, the narrow band against exact sampling, inward and
//! open meshes.

use super::sides::crossing_x;
use super::*;

fn octahedron() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let v = vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
    let t = vec![[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
    (v, t)
}

#[test]
fn octahedron_sign_and_distance() {
    let (v, t) = octahedron();
    let f = MeshField::new("octa", &v, &t).unwrap();
    assert!(f.value(Vec3::ZERO) < 0.0);
    assert!((f.value(Vec3::ZERO) + 1.0 / 3f32.sqrt()).abs() < 1e-5);
    assert!((f.value(Vec3::new(2.0, 0.0, 0.0)) - 1.0).abs() < 1e-5);
}

#[test]
fn open_mesh_still_has_an_inside() {
    let (v, mut t) = octahedron();
    t.pop(); // a hole
    let f = MeshField::new("open", &v, &t).unwrap();
    assert!(f.value(Vec3::new(0.1, 0.1, 0.1)) < 0.0);
    assert!(f.value(Vec3::new(0.0, 0.0, 3.0)) > 0.0);
}

#[test]
fn an_inward_mesh_gives_the_same_field_and_is_flipped() {
    let (v, t) = octahedron();
    let outward = MeshField::new("out", &v, &t).unwrap();
    let inward_triangles: Vec<[u32; 3]> = t.iter().map(|&[a, b, c]| [a, c, b]).collect();
    let inward = MeshField::new("in", &v, &inward_triangles).unwrap();
    assert!(!outward.reoriented() && inward.reoriented());
    for p in [Vec3::ZERO, Vec3::new(0.2, -0.1, 0.3), Vec3::new(1.5, 0.0, 0.2), Vec3::new(-0.4, 0.4, 0.1)] {
        assert_eq!(inward.value(p), outward.value(p), "{p}");
    }
    // Two disjoint shells, one wound each way: both have an inside (|w|).
    let mut v2 = v.clone();
    v2.extend(v.iter().map(|p| *p + Vec3::new(5.0, 0.0, 0.0)));
    let mut t2 = t.clone();
    t2.extend(inward_triangles.iter().map(|tri| tri.map(|i| i + 6)));
    let mixed = MeshField::new("mixed", &v2, &t2).unwrap();
    assert!(mixed.value(Vec3::ZERO) < 0.0 && mixed.value(Vec3::new(5.0, 0.0, 0.0)) < 0.0);
    assert!(mixed.value(Vec3::new(2.5, 0.0, 0.0)) > 0.0);
}

/// A triangle soup (every triangle with corners of its own, as many files store patches) is
/// the same field: its seams are not holes, so it gets the caps, signs and band values of the
/// indexed mesh, closed or open.
#[test]
fn unwelded_seams_are_not_holes() {
    let (v, t) = octahedron();
    let soup_of = |tris: &[[u32; 3]]| -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let positions: Vec<Vec3> = tris.iter().flat_map(|tri| tri.map(|i| v[i as usize])).collect();
        let triangles = (0..tris.len() as u32).map(|k| [3 * k, 3 * k + 1, 3 * k + 2]).collect();
        (positions, triangles)
    };
    let mut bent = t.clone();
    bent.truncate(6);
    for (name, tris, closed) in [("closed", &t, true), ("bent", &bent, false)] {
        let welded = MeshField::new(name, &v, tris).unwrap();
        let (sv, st) = soup_of(tris);
        let soup = MeshField::new(name, &sv, &st).unwrap();
        assert_eq!((welded.is_closed(), soup.is_closed()), (closed, closed), "{name}");
        assert_eq!(welded.caps.triangles, soup.caps.triangles, "{name}");
        let grid = Grid { origin: Vec3::new(-1.3, -1.21, -1.17), spacing: 0.0931, dims: [29, 27, 26] };
        let (mut a, mut b) = (vec![0.0; grid.len()], vec![0.0; grid.len()]);
        welded.sample_grid(&grid, 0.0, &mut a);
        soup.sample_grid(&grid, 0.0, &mut b);
        assert_eq!(a, b, "{name}");
    }
}

#[test]
fn a_hollow_shell_keeps_its_cavity_either_way_round() {
    let (v, t) = octahedron();
    // Outer shell outward, inner shell (half size) facing the cavity.
    let mut positions = v.clone();
    positions.extend(v.iter().map(|p| *p * 0.5));
    let mut triangles = t.clone();
    triangles.extend(t.iter().map(|&[a, b, c]| [a + 6, c + 6, b + 6]));
    let flipped: Vec<[u32; 3]> = triangles.iter().map(|&[a, b, c]| [a, c, b]).collect();
    for (name, tris) in [("hollow", &triangles), ("hollow-inward", &flipped)] {
        let f = MeshField::new(name, &positions, tris).unwrap();
        assert!(f.value(Vec3::ZERO) > 0.0, "{name}: the cavity is outside");
        assert!(f.value(Vec3::new(0.7, 0.0, 0.0)) < 0.0, "{name}: the wall is inside");
    }
}

/// Narrow-band values against exact ones on a grid: the same sign everywhere, the same bits
/// within the band, a lower bound no less than the band beyond it. Returns how many samples
/// were in the band and how many beyond.
fn check_band(field: MeshField, n: usize, iso: f32) -> (usize, usize) {
    let grid = Grid::covering(&field.domain(), n).unwrap();
    let mut banded = vec![0.0; grid.len()];
    field.sample_grid(&grid, iso, &mut banded);
    let exact = field.with_band_cells(f32::INFINITY);
    let mut reference = vec![0.0; grid.len()];
    exact.sample_grid(&grid, iso, &mut reference);
    let band = iso.abs() + DEFAULT_BAND_CELLS * grid.spacing;
    let (mut near, mut far) = (0, 0);
    for (i, (&b, &e)) in banded.iter().zip(&reference).enumerate() {
        assert_eq!(b < 0.0, e < 0.0, "sample {i}: sign {b} against {e}");
        if e.abs() < band {
            assert_eq!(b, e, "sample {i} is in the band");
            near += 1;
        } else {
            assert!(b.abs() >= band && b.abs() <= e.abs(), "sample {i}: {b} is no bound on {e} (band {band})");
            far += 1;
        }
    }
    (near, far)
}

#[test]
fn narrow_band_samples_are_exact_near_the_surface_and_bounds_beyond() {
    let (v, t) = octahedron();
    let (near, far) = check_band(MeshField::new("octa", &v, &t).unwrap(), 41, 0.0);
    assert!(near > 1000 && far > 10_000, "{near} in the band, {far} beyond");
    // An offset level set widens the band by the offset.
    check_band(MeshField::new("octa", &v, &t).unwrap(), 41, 0.15);
    check_band(MeshField::new("octa", &v, &t).unwrap(), 41, -0.1);
    // An open mesh: the |w| = 1/2 sheet across the hole is found sample by sample.
    let mut open = t.clone();
    open.pop();
    check_band(MeshField::new("open", &v, &open).unwrap(), 41, 0.0);
    // A bent hole (two faces gone): the cone capping it is not the |w| = 1/2 sheet, so
    // samples between them must take their own winding numbers.
    open.pop();
    for n in [41, 64, 77] {
        check_band(MeshField::new("bent", &v, &open).unwrap(), n, 0.0);
    }
    // A hollow shell, and two shells wound opposite ways.
    let mut positions = v.clone();
    positions.extend(v.iter().map(|p| *p * 0.5));
    let mut hollow = t.clone();
    hollow.extend(t.iter().map(|&[a, b, c]| [a + 6, c + 6, b + 6]));
    check_band(MeshField::new("hollow", &positions, &hollow).unwrap(), 41, 0.0);
    let mut apart = v.clone();
    apart.extend(v.iter().map(|p| *p + Vec3::new(2.5, 0.0, 0.0)));
    let mut mixed = t.clone();
    mixed.extend(t.iter().map(|&[a, b, c]| [a + 6, c + 6, b + 6]));
    check_band(MeshField::new("mixed", &apart, &mixed).unwrap(), 37, 0.0);
}

#[test]
fn closed_meshes_are_told_apart_from_open_and_inconsistent_ones() {
    let (v, t) = octahedron();
    assert!(MeshField::new("octa", &v, &t).unwrap().is_closed());
    let mut open = t.clone();
    open.pop();
    assert!(!MeshField::new("open", &v, &open).unwrap().is_closed());
    let mut twice = t.clone();
    twice.push(t[0]);
    assert!(!MeshField::new("twice", &v, &twice).unwrap().is_closed());
    let mut one_flipped = t.clone();
    one_flipped[3].swap(1, 2);
    assert!(!MeshField::new("flipped", &v, &one_flipped).unwrap().is_closed());
}

/// Row crossings give every sample the winding number's side; rows through the octahedron's
/// vertices and edges (the grid below has them) are left to the winding number.
#[test]
fn row_crossings_agree_with_the_winding_number() {
    let (v, t) = octahedron();
    let f = MeshField::new("octa", &v, &t).unwrap();
    for (grid, expect_unsure) in [
        (Grid { origin: Vec3::splat(-1.5), spacing: 0.125, dims: [25, 25, 25] }, true),
        (Grid { origin: Vec3::new(-1.3, -1.21, -1.17), spacing: 0.0931, dims: [29, 27, 26] }, false),
    ] {
        let sides = crossing_signs(f.bvh(), &f.caps, &grid, 0..grid.dims[2]);
        let (mut known, mut unsure) = (0, 0);
        for (i, side) in sides.iter().enumerate() {
            let [nx, ny, _] = grid.dims;
            let p = grid.position(i % nx, i / nx % ny, i / (nx * ny));
            match side {
                Side::Unknown | Side::NearCaps(_) => unsure += 1,
                s => {
                    assert_eq!(*s == Side::Inside, winds_inside(f.bvh(), p), "at {p}");
                    known += 1;
                }
            }
        }
        assert!(known > 10_000, "{known}");
        assert_eq!(unsure > 0, expect_unsure, "{unsure} samples unsure");
    }
}

#[test]
fn a_crossing_is_placed_on_the_plane_and_refused_on_a_sliver() {
    let t = [Vec3::new(1.0, 0.0, 0.0), Vec3::new(3.0, 1.0, 0.0), Vec3::new(2.0, 0.0, 1.0)];
    let x = crossing_x(&t, Vec3::new(0.0, 0.25, 0.25)).unwrap();
    // The plane through t: x = 1 + 2y + z.
    assert!((x - 1.75).abs() < 1e-12, "{x}");
    // Seen almost edge-on from x, the weights cancel: no crossing is trusted.
    let sliver = [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0e4, 1.0, 1.0), Vec3::new(2.0e4, 2.0, 2.0 + 1.0e-6)];
    assert_eq!(crossing_x(&sliver, Vec3::new(0.0, 1.0, 1.0 + 2.5e-7)), None);
}

/// The caps close the mesh (with them its winding number is an integer everywhere), and
/// their own winding number stays within the bound the signs rely on.
#[test]
fn caps_close_the_boundary_and_bound_their_winding_number() {
    let (v, mut t) = octahedron();
    t.truncate(6); // a bent hole of four edges
    let f = MeshField::new("bent", &v, &t).unwrap();
    assert!(!f.is_closed() && f.caps.cones.len() == 1 && f.caps.triangles.len() == 4, "{:?}", f.caps);
    let winding = |p: Vec3, soup: &[[Vec3; 3]]| {
        soup.iter().map(|t| crate::geometry::solid_angle(p, t[0], t[1], t[2])).sum::<f64>() / (4.0 * std::f64::consts::PI)
    };
    let mesh: Vec<[Vec3; 3]> = f.bvh().triangles().to_vec();
    let mut bounded = 0;
    for i in 0..2000 {
        let k = i as f32;
        let p = Vec3::new((k * 0.731).sin(), (k * 1.37).cos(), (k * 0.413).sin() * 1.2) * 1.6;
        let closed: Vec<[Vec3; 3]> = mesh.iter().chain(&f.caps.triangles).copied().collect();
        let n = winding(p, &closed);
        assert!((n - n.round()).abs() < 1e-9, "at {p}: mesh and caps wind {n}");
        let bound = f.caps.winding_bound(p);
        if bound.is_finite() {
            assert!(winding(p, &f.caps.triangles).abs() <= bound, "at {p}");
            bounded += 1;
        }
    }
    assert!(bounded > 500, "{bounded}");
    assert!(MeshField::new("octa", &v, &octahedron().1).unwrap().caps.triangles.is_empty());
}

/// Next to a cap, the mesh winds around a sample as often as row crossings count (mesh and
/// caps together) less the caps' winding number: the rule [`side_from_caps`] decides by.
#[test]
fn near_a_cap_the_mesh_winds_as_the_crossings_less_the_caps() {
    let (v, mut t) = octahedron();
    t.truncate(6);
    let f = MeshField::new("bent", &v, &t).unwrap();
    let caps = f.caps.bvh.as_ref().unwrap();
    let exact = |p: Vec3, soup: &[[Vec3; 3]]| {
        soup.iter().map(|t| crate::geometry::solid_angle(p, t[0], t[1], t[2])).sum::<f64>() / (4.0 * std::f64::consts::PI)
    };
    let grid = Grid { origin: Vec3::new(-1.3, -1.21, -1.17), spacing: 0.0931, dims: [29, 27, 26] };
    let sides = crossing_signs(f.bvh(), &f.caps, &grid, 0..grid.dims[2]);
    let [nx, ny, _] = grid.dims;
    let (mut near, mut wound, mut decided) = (0, 0, 0);
    for (i, side) in sides.iter().enumerate() {
        let Side::NearCaps(n) = *side else { continue };
        let p = grid.position(i % nx, i / nx % ny, i / (nx * ny));
        let w = exact(p, f.bvh().triangles());
        assert!((w - (f64::from(n) - exact(p, &f.caps.triangles))).abs() < 1e-9, "at {p}: {w} with {n} crossings");
        if let Some(inside) = side_from_caps(n, caps.winding_number(p), 0.0) {
            assert_eq!(inside, winds_inside(f.bvh(), p), "at {p}");
            decided += 1;
        }
        near += 1;
        wound += usize::from(n != 0);
    }
    assert!(near > 1000 && wound > 100 && decided > near / 2, "{near} near a cap, {wound} wound, {decided} decided");
}

#[test]
fn a_box_is_as_far_from_the_mesh_as_its_nearest_triangle_box() {
    let (v, t) = octahedron();
    let f = MeshField::new("octa", &v, &t).unwrap();
    let corner = Aabb::new(Vec3::splat(2.0), Vec3::splat(2.5));
    let d = f.bvh().distance_from_box_at_least(&corner, 0.5).unwrap();
    assert!(d <= f.unsigned_distance(Vec3::splat(2.0)) && d > 1.5, "{d}");
    assert!(f.bvh().distance_from_box_at_least(&corner, 2.0).is_none());
    // Inside, the triangles' boxes reach the centre: no bound.
    assert!(f.bvh().distance_from_box_at_least(&Aabb::new(Vec3::splat(-0.01), Vec3::splat(0.01)), 0.1).is_none());
}

#[test]
fn a_box_clear_of_the_mesh_gets_a_winding_interval_and_one_touching_it_does_not() {
    let (v, t) = octahedron();
    let f = MeshField::new("octa", &v, &t).unwrap();
    let inner = Aabb::new(Vec3::splat(-0.02), Vec3::splat(0.02));
    let w = f.bvh().winding_interval(&inner, 0.5).unwrap();
    assert!(w.centre - w.error >= 0.5 && w.error > 0.0, "{w:?}");
    assert!(w.distance > 0.0 && w.distance <= 1.0 / 3f32.sqrt() - 0.02, "{w:?}");
    let outer = Aabb::new(Vec3::splat(2.0), Vec3::splat(2.2));
    let w = f.bvh().winding_interval(&outer, 0.5).unwrap();
    assert!(w.centre + w.error < 0.5 && w.centre - w.error > -0.5, "{w:?}");
    // The distance is a lower bound on every point of the box.
    let nearest_corner = f.unsigned_distance(Vec3::splat(2.0));
    assert!(w.distance <= nearest_corner && w.distance > 0.0, "{w:?} against {nearest_corner}");
    let straddling = Aabb::new(Vec3::splat(0.2), Vec3::splat(0.6));
    assert!(f.bvh().winding_interval(&straddling, 0.5).is_none());
}

#[test]
fn bad_meshes_are_rejected_with_the_offender_named() {
    let (v, _) = octahedron();
    assert!(matches!(MeshField::new("e", &v, &[]), Err(FieldError::EmptyMesh { .. })));
    let e = MeshField::new("b", &v, &[[0, 1, 9]]).err().unwrap();
    assert!(e.to_string().contains("vertex 9"), "{e}");
    let mut nan = v.clone();
    nan[3].y = f32::NAN;
    assert!(matches!(MeshField::new("n", &nan, &[[0, 1, 3]]), Err(FieldError::NonFiniteVertex { vertex: 3, .. })));
}
