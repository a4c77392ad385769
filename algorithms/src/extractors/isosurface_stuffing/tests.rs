//! The stencils against the paper's bound, exhaustively: every lattice tetrahedron orientation
//! (the twelve around a centre), every sign pattern, and warped vertices and cut points at the
//! extreme and middle positions warping allows.

use super::stencils::{self, Corner};
use super::*;
use crate::geometry::dihedral_angles;

/// The twelve lattice tetrahedra around the centre at doubled coordinates (1, 1, 1).
fn lattice_tets() -> Vec<[[i32; 3]; 4]> {
    let templates = &crate::extractors::tetrahedral::topology(crate::extractors::tetrahedral::TetKind::Bcc).templates;
    templates.iter().map(|t| t.map(|o| [1 + o[0], 1 + o[1], 1 + o[2]])).collect()
}

/// The fourteen lattice edges from a vertex, in doubled coordinates.
fn directions() -> Vec<[i32; 3]> {
    let mut d = Vec::new();
    for axis in 0..3 {
        for s in [-2, 2] {
            let mut v = [0; 3];
            v[axis] = s;
            d.push(v);
        }
    }
    for x in [-1, 1] {
        for y in [-1, 1] {
            for z in [-1, 1] {
                d.push([x, y, z]);
            }
        }
    }
    d
}

fn at(d: [i32; 3]) -> DVec3 {
    DVec3::new(d[0] as f64, d[1] as f64, d[2] as f64)
}

/// Worst angles over every case, and the count of tetrahedra checked; panics on an angle outside
/// `interval` or a tetrahedron not positively oriented.
///
/// A case is a lattice tetrahedron, its vertices' signs before warping, which of them warping
/// moved, where each moved vertex went and where each cut point left sits. A moved vertex went
/// along one of its fourteen lattice edges, by half or all of that edge's threshold, to a cut
/// point: the edge's other end had the opposite sign, and for a negative vertex (moved after the
/// positive ones) that end stayed positive; an edge leaving the tetrahedron may end anywhere. A
/// cut point left lies on an edge between two vertices that stayed, at least the threshold from
/// either end: at the threshold from one end, the other, or midway.
fn exhaust(alpha: [f64; 2], interval: DihedralInterval) -> (f64, f64, usize) {
    exhaust_at(alpha, interval, &[0.5, 1.0], &[0.0, 0.5, 1.0])
}

/// [`exhaust`] with the warp fractions (of the threshold) and cut positions (0: at the threshold
/// from the lower end, 1: from the upper end) given.
fn exhaust_at(alpha: [f64; 2], interval: DihedralInterval, warps: &[f64], cuts: &[f64]) -> (f64, f64, usize) {
    let (mut lo, mut hi, mut checked) = (f64::INFINITY, 0.0f64, 0usize);
    let threshold = |e: [i32; 3]| alpha[if e.iter().filter(|&&c| c != 0).count() == 1 { 0 } else { 1 }];
    for d in lattice_tets() {
        for pattern in 0..81 {
            let before: [i8; 4] = std::array::from_fn(|i| ((pattern / 3usize.pow(i as u32)) % 3) as i8 - 1);
            for moved in 0..16u32 {
                let warped = |i: usize| moved & (1 << i) != 0;
                if (0..4).any(|i| warped(i) && before[i] == 0) {
                    continue;
                }
                let signs: [i8; 4] = std::array::from_fn(|i| if warped(i) { 0 } else { before[i] });
                // Where each vertex can sit.
                let places: Vec<Vec<DVec3>> = (0..4)
                    .map(|i| {
                        if !warped(i) {
                            return vec![at(d[i])];
                        }
                        let mut p = Vec::new();
                        for e in directions() {
                            let w = [d[i][0] + e[0], d[i][1] + e[1], d[i][2] + e[2]];
                            let allowed = match (0..4).find(|&j| d[j] == w) {
                                None => true,
                                Some(j) => before[j] == -before[i] && (before[i] > 0 || !warped(j)),
                            };
                            if allowed {
                                for &f in warps {
                                    p.push(at(d[i]) + at(e) * (f * threshold(e)));
                                }
                            }
                        }
                        p
                    })
                    .collect();
                if places.iter().any(Vec::is_empty) {
                    continue;
                }
                let cut_edges: Vec<(usize, usize)> = EDGES.iter().copied().filter(|&(i, j)| signs[i] * signs[j] < 0).collect();
                let fill = stencils::fill(&d, signs);
                let tets: Vec<[Corner; 4]> = fill.tets().map(|t| stencils::orient(&d, t)).collect();
                for t in &tets {
                    assert!(stencils::reference_volume(&d, *t) > 0, "{d:?} {signs:?}: a flat stencil {t:?}");
                }
                let vertex_choices: usize = places.iter().map(Vec::len).product();
                let cut_choices = cuts.len().pow(cut_edges.len() as u32);
                for v in 0..vertex_choices {
                    let mut rest = v;
                    let p: [DVec3; 4] = std::array::from_fn(|i| {
                        let k = rest % places[i].len();
                        rest /= places[i].len();
                        places[i][k]
                    });
                    for c in 0..cut_choices {
                        let mut rest = c;
                        let mut cut_at = HashMap::new();
                        for &(i, j) in &cut_edges {
                            let a = alpha[if stencils::is_long(&d, i, j) { 0 } else { 1 }];
                            let f = a + (1.0 - 2.0 * a) * cuts[rest % cuts.len()];
                            rest /= cuts.len();
                            cut_at.insert((i as u8, j as u8), p[i] + (p[j] - p[i]) * f);
                        }
                        for t in &tets {
                            let q = t.map(|c| match c {
                                Corner::Vertex(i) => p[i as usize],
                                Corner::Cut(i, j) => cut_at[&(i, j)],
                            });
                            let volume = (q[1] - q[0]).dot((q[2] - q[0]).cross(q[3] - q[0]));
                            assert!(volume > 0.0, "{d:?} {before:?} moved {moved:b}: inverted {t:?} at {q:?}");
                            for a in dihedral_angles(q.map(|x| x.as_vec3())) {
                                assert!(
                                    interval.contains(a),
                                    "{d:?} {before:?} moved {moved:b}: {a:.3}° outside {interval:?} in {t:?} at {q:?}"
                                );
                                lo = lo.min(a);
                                hi = hi.max(a);
                            }
                            checked += 1;
                        }
                    }
                }
            }
        }
    }
    (lo, hi, checked)
}

#[test]
fn every_stencil_keeps_the_declared_interval_at_every_extreme_warp() {
    let declared = INFO.guarantees.dihedral.expect("declared");
    assert_eq!(declared, GUARANTEED);
    let (lo, hi, checked) = exhaust([ALPHA_LONG, ALPHA_SHORT], declared);
    assert!(checked > 1_000_000, "{checked} tetrahedra");
    // The interval is the worst case, not a loose one.
    assert!(lo < declared.min_degrees + 0.1 && hi > declared.max_degrees - 0.1, "[{lo}, {hi}] inside {declared:?}");
    // The paper's own bound is not reached (its module doc says where we differ).
    assert!(lo < PAPER.min_degrees);
}

#[test]
fn a_finer_sweep_finds_no_worse_case() {
    let (lo, hi, _) = exhaust_at([ALPHA_LONG, ALPHA_SHORT], GUARANTEED, &[0.25, 0.5, 0.75, 1.0], &[0.0, 0.25, 0.5, 0.75, 1.0]);
    let (coarse_lo, coarse_hi, _) = exhaust([ALPHA_LONG, ALPHA_SHORT], GUARANTEED);
    assert!(
        (lo - coarse_lo).abs() < 1e-9 && (hi - coarse_hi).abs() < 1e-9,
        "finer [{lo}, {hi}], coarse [{coarse_lo}, {coarse_hi}]"
    );
}

#[test]
fn the_papers_second_parameters_keep_their_interval() {
    let (lo, _, _) = exhaust([ALPHA_LONG_NARROW, ALPHA_SHORT_NARROW], GUARANTEED_NARROW);
    assert!(lo < PAPER_NARROW.min_degrees);
}

#[test]
fn the_parity_rule_names_one_diagonal_per_face() {
    // Every face of every lattice tetrahedron whose long edge is (a, b): swapping a and b names the
    // same diagonal, and the four faces around a long edge alternate.
    for d in lattice_tets() {
        for (a, b) in EDGES.iter().copied().filter(|&(a, b)| stencils::is_long(&d, a, b)) {
            let apexes: Vec<usize> = (0..4).filter(|&t| t != a && t != b).collect();
            for &t in &apexes {
                assert_ne!(stencils::parity_diagonal_from(&d, a, b, t), stencils::parity_diagonal_from(&d, b, a, t));
            }
            // The tetrahedron's two faces on its long edge: opposite answers (compatible prisms).
            assert_ne!(
                stencils::parity_diagonal_from(&d, a, b, apexes[0]),
                stencils::parity_diagonal_from(&d, a, b, apexes[1]),
                "{d:?}: ({a}, {b})"
            );
        }
    }
}

#[test]
fn signs_decide_what_is_kept() {
    let d = lattice_tets()[0];
    assert_eq!(stencils::fill(&d, [1, 1, 1, 1]).len(), 0);
    assert_eq!(stencils::fill(&d, [-1, -1, 0, -1]).len(), 1);
    assert_eq!(stencils::fill(&d, [0, 0, 0, 0]).len(), 0);
    assert_eq!(stencils::fill(&d, [1, 0, 0, 0]).len(), 0);
    assert_eq!(stencils::fill(&d, [1, -1, 1, 1]).len(), 1);
    assert_eq!(stencils::fill(&d, [1, -1, -1, 0]).len(), 2);
    assert_eq!(stencils::fill(&d, [1, -1, -1, -1]).len(), 3);
    assert_eq!(stencils::fill(&d, [1, -1, 1, -1]).len(), 3);
}

#[test]
fn a_sphere_is_filled_with_its_volume_and_its_surface_on_the_sphere() {
    let sphere = crate::fields::builtin("sphere", Default::default()).unwrap();
    for lattice in ["cubic", "bcc"] {
        let grid = Grid::covering(&sphere.domain(), 33).unwrap();
        let l = if lattice == "bcc" { Lattice::Bcc(grid) } else { Lattice::Cubic(grid) };
        let samples = Samples::sample(sphere.clone(), l, 0.0).unwrap();
        let mut out = Extraction::default();
        IsosurfaceStuffing::default().extract(&samples, &mut out).unwrap();
        let t = &out.volume;
        let volume: f64 = t
            .tetrahedra
            .iter()
            .map(|tet| {
                let [a, b, c, d] = tet.map(|i| t.positions[i as usize].as_dvec3());
                (b - a).dot((c - a).cross(d - a)) / 6.0
            })
            .sum();
        let r = 0.4f64;
        let exact = 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
        assert!((volume - exact).abs() < 0.02 * exact, "{lattice}: volume {volume} against {exact}");
        // Boundary vertices on the sphere (cut points refined on the field), closed, outward.
        for p in &out.surface.positions {
            assert!((f64::from(p.length()) - r).abs() < 1e-5, "{lattice}: {p} off the sphere");
        }
        let topo = crate::mesh::manifold_defects(&out.surface);
        assert!(topo.is_empty(), "{lattice}: non-manifold at {topo:?}");
        let v = out.surface.positions.len() as i64;
        assert_eq!(v - out.surface.triangles.len() as i64 / 2, 2, "{lattice}: Euler characteristic of a sphere");
    }
}
