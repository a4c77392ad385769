//! Cut points refined on the field: the root of the field along a lattice edge, by regula falsi.

/// Regula falsi (Illinois) steps refining a cut point on the field, at most.
const ROOT_STEPS: usize = 12;

/// A cut point is refined until the field there is within this fraction of the edge's value
/// range (`|f(a)| + |f(b)|`) of the iso-value: for a distance field, a millionth of an edge, a
/// thousandth of what the tests allow. Most cut points stop after three or four field queries
/// instead of twelve (each is an exact distance for a mesh field).
pub(super) const ROOT_TOLERANCE: f64 = 1e-6;

/// The root of `f` between `(t0, f0)` and `(t1, f1)` (opposite signs), from the first guess
/// `guess`, by the Illinois variant of regula falsi: stays in the bracket, so inside the edge.
/// Stops where `|f| <= tolerance`.
pub(super) fn refine_root(
    f: impl Fn(f64) -> f64,
    (mut t0, mut f0): (f64, f64),
    (mut t1, mut f1): (f64, f64),
    guess: f64,
    tolerance: f64,
) -> f64 {
    let mut t = guess;
    let mut side = 0i8;
    for _ in 0..ROOT_STEPS {
        let ft = f(t);
        if !ft.is_finite() || ft.abs() <= tolerance {
            break;
        }
        if (ft < 0.0) == (f0 < 0.0) {
            (t0, f0) = (t, ft);
            if side == -1 {
                f1 *= 0.5;
            }
            side = -1;
        } else {
            (t1, f1) = (t, ft);
            if side == 1 {
                f0 *= 0.5;
            }
            side = 1;
        }
        t = (t0 * f1 - t1 * f0) / (f1 - f0);
        if !(t0..=t1).contains(&t) || (t1 - t0) < 1e-12 {
            t = 0.5 * (t0 + t1);
            break;
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::Cell;

    #[test]
    fn the_root_is_found_within_the_tolerance_and_the_search_stops_there() {
        // A distance-like field along an edge, slightly curved: the root at 0.3.
        let calls = Cell::new(0);
        let f = |t: f64| {
            calls.set(calls.get() + 1);
            (t - 0.3) + 0.2 * (t - 0.3) * (t - 0.3)
        };
        let (f0, f1) = (f(0.0), f(1.0));
        calls.set(0);
        let tolerance = ROOT_TOLERANCE * (f0.abs() + f1.abs());
        let t = refine_root(f, (0.0, f0), (1.0, f1), f0 / (f0 - f1), tolerance);
        assert!((t - 0.3).abs() < 2.0 * tolerance, "root {t}");
        assert!(calls.get() < ROOT_STEPS, "{} field queries: the tolerance stops the search early", calls.get());
        // With no tolerance it runs every step and stays in the bracket.
        calls.set(0);
        let t = refine_root(f, (0.0, f0), (1.0, f1), 0.9, 0.0);
        assert!((0.0..=1.0).contains(&t) && (t - 0.3).abs() < 1e-9, "root {t}");
    }
}
