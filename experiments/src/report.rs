//! Helpers for the report: repeated timing with medians, and Markdown tables.

use serde::{Deserialize, Serialize};
use std::time::Duration;

/// Median of durations (the mean of the two middle values for an even count).
pub fn median(mut samples: Vec<Duration>) -> Duration {
    if samples.is_empty() {
        return Duration::ZERO;
    }
    samples.sort_unstable();
    let n = samples.len();
    if n % 2 == 1 {
        samples[n / 2]
    } else {
        (samples[n / 2 - 1] + samples[n / 2]) / 2
    }
}

/// A Markdown table from a header and rows.
pub fn markdown_table(header: &[&str], rows: &[Vec<String>]) -> String {
    let mut s = format!("| {} |\n|{}\n", header.join(" | "), header.iter().map(|_| "---|").collect::<String>());
    for r in rows {
        s.push_str(&format!("| {} |\n", r.join(" | ")));
    }
    s
}

/// `items` joined by commas, or `none` when there are none (a reading's lists).
pub fn listed_or<S: AsRef<str>>(items: &[S], none: &str) -> String {
    if items.is_empty() {
        none.to_owned()
    } else {
        items.iter().map(AsRef::as_ref).collect::<Vec<_>>().join(", ")
    }
}

/// [`listed_or`] with "none".
pub fn listed<S: AsRef<str>>(items: &[S]) -> String {
    listed_or(items, "none")
}

/// The distinct items of `items`, each once, in the order first seen (unlike `Vec::dedup`,
/// which only drops adjacent repeats).
pub fn first_seen<T: PartialEq>(items: impl IntoIterator<Item = T>) -> Vec<T> {
    let mut out: Vec<T> = Vec::new();
    for item in items {
        if !out.contains(&item) {
            out.push(item);
        }
    }
    out
}

/// A duration in milliseconds.
pub fn millis(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// Milliseconds, formatted with three significant-ish decimals (no negative times).
pub fn ms(v: f64) -> String {
    let v = v.max(0.0);
    if v >= 100.0 {
        format!("{v:.0}")
    } else if v >= 10.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.2}")
    }
}

/// Least-squares slope of `ln y` against `ln x`.
pub fn log_slope(points: &[(f64, f64)]) -> Option<f64> {
    let pts: Vec<(f64, f64)> = points.iter().filter(|(x, y)| *x > 0.0 && *y > 0.0).map(|(x, y)| (x.ln(), y.ln())).collect();
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as f64;
    let (mx, my) = (pts.iter().map(|p| p.0).sum::<f64>() / n, pts.iter().map(|p| p.1).sum::<f64>() / n);
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_read_as_sentences() {
        let l = |v: &[&str]| and_list(&v.iter().map(|s| s.to_string()).collect::<Vec<_>>());
        assert_eq!(
            (l(&[]), l(&["a"]), l(&["a", "b"]), l(&["a", "b", "c"])),
            ("".into(), "a".into(), "a and b".into(), "a, b and c".into())
        );
    }

    #[test]
    fn ratio_ranges_pair_runs_of_the_same_round() {
        assert_eq!(ratio_range(&[1.0, 2.0, 4.0], &[3.0, 3.0, 4.0]), Some((1.0, 3.0)));
        assert_eq!(ratio_range(&[1.0, 2.0], &[2.0]), Some((2.0, 2.0)));
        assert_eq!(ratio_range(&[], &[1.0]), None);
    }

    #[test]
    fn a_wide_cell_gets_rounds_up_to_the_bound_and_then_a_flag() {
        let narrow = rounds_until_narrow::<()>(3, || Ok(10.0)).unwrap();
        assert_eq!((narrow.runs.len(), narrow.rounds, narrow.wide, narrow.flag()), (3, 1, false, String::new()));
        // A wide first round, a narrow second: two rounds, every run kept, no flag.
        let mut times = [30.0, 10.0, 10.0, 11.0, 10.0, 10.0].into_iter();
        let settled = rounds_until_narrow::<()>(3, || Ok(times.next().unwrap())).unwrap();
        assert_eq!((settled.runs.len(), settled.rounds, settled.wide), (6, 2, false));
        assert_eq!(settled.spread().max, 30.0);
        // Wide every round: the bound, then the flag.
        let mut k = 0.0;
        let wide = rounds_until_narrow::<()>(2, || {
            k += 1.0;
            Ok(if k % 2.0 == 0.0 { 30.0 } else { 10.0 })
        })
        .unwrap();
        assert_eq!((wide.runs.len(), wide.rounds, wide.wide), (2 * MAX_ROUNDS, MAX_ROUNDS, true));
        assert_eq!(wide.flag(), " (wide: 10.0-30.0 ms)");
        // One run a round cannot be judged: never wide.
        assert!(!rounds_until_narrow::<()>(1, || Ok(1.0)).unwrap().wide);
    }

    #[test]
    fn median_of_odd_and_even() {
        let d = |v: u64| Duration::from_millis(v);
        assert_eq!(median(vec![d(3), d(1), d(2)]), d(2));
        assert_eq!(median(vec![d(4), d(1), d(2), d(3)]), Duration::from_micros(2500));
        assert_eq!(median(vec![]), Duration::ZERO);
    }

    #[test]
    fn lists_say_none_when_empty() {
        assert_eq!(listed(&["mc", "sn"]), "mc, sn");
        assert_eq!(listed::<&str>(&[]), "none");
        assert_eq!(listed_or::<String>(&[], "no grid"), "no grid");
    }

    #[test]
    fn first_seen_drops_non_adjacent_repeats() {
        assert_eq!(first_seen(["mc", "sn", "mc", "dc", "sn"]), ["mc", "sn", "dc"]);
    }

    #[test]
    fn table_shape() {
        let t = markdown_table(&["a", "b"], &[vec!["1".into(), "2".into()]]);
        assert_eq!(t, "| a | b |\n|---|---|\n| 1 | 2 |\n");
    }
}

/// Median and spread of repeated runs, ms.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Spread {
    /// Median.
    pub median: f64,
    /// Fastest run.
    pub min: f64,
    /// Slowest run.
    pub max: f64,
    /// Every run, in the order measured (absent from data written before it was kept).
    #[serde(default)]
    pub runs: Vec<f64>,
}

/// A round of runs is wide when its slowest run takes more than this many times its fastest: the
/// cell gets another round ([`rounds_until_narrow`]) and, if its last round stays wide, a flag on
/// its page ([`Rounds::flag`]).
pub const WIDE: f64 = 2.0;

/// The most rounds a cell gets.
pub const MAX_ROUNDS: usize = 3;

/// A cell's runs over its rounds, every one kept.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Rounds {
    /// Every run, in order.
    pub runs: Vec<f64>,
    /// Rounds run.
    pub rounds: usize,
    /// Whether its last round was still wide after [`MAX_ROUNDS`].
    pub wide: bool,
}

impl Rounds {
    /// The spread over every run.
    pub fn spread(&self) -> Spread {
        Spread::of(self.runs.clone())
    }

    /// `" (wide: 1.2-9.8 ms)"` after a cell's median on a page when it stayed wide, else empty.
    pub fn flag(&self) -> String {
        if self.wide {
            let s = self.spread();
            format!(" (wide: {}-{} ms)", ms(s.min), ms(s.max))
        } else {
            String::new()
        }
    }
}

/// Runs `run` in rounds of `repeats` until a round is not wide ([`WIDE`]) or [`MAX_ROUNDS`] have
/// run; keeps every run.
pub fn rounds_until_narrow<E>(repeats: usize, mut run: impl FnMut() -> Result<f64, E>) -> Result<Rounds, E> {
    let repeats = repeats.max(1);
    let mut out = Rounds::default();
    loop {
        // Kept to a tenth of a microsecond (in ms): the data file holds every run.
        let round: Vec<f64> = (0..repeats).map(|_| run().map(|ms| (ms * 1e4).round() / 1e4)).collect::<Result<_, E>>()?;
        out.runs.extend(&round);
        out.rounds += 1;
        out.wide = repeats > 1 && Spread::of(round).is_wide();
        if !out.wide || out.rounds == MAX_ROUNDS {
            return Ok(out);
        }
    }
}

/// `a`, `a and b`, `a, b and c`: a list in a sentence.
pub fn and_list(items: &[String]) -> String {
    match items {
        [] => String::new(),
        [one] => one.clone(),
        [rest @ .., last] => format!("{} and {last}", rest.join(", ")),
    }
}

/// The range of `theirs[i] / ours[i]` over the rounds both ran (runs paired by their index, so
/// both ends come from the same rounds), or `None` without a shared round.
pub fn ratio_range(ours: &[f64], theirs: &[f64]) -> Option<(f64, f64)> {
    let ratios: Vec<f64> = ours.iter().zip(theirs).map(|(o, t)| t / o).filter(|r| r.is_finite()).collect();
    let lo = ratios.iter().copied().reduce(f64::min)?;
    let hi = ratios.iter().copied().reduce(f64::max)?;
    Some((lo, hi))
}

impl Spread {
    /// Whether its slowest run took more than [`WIDE`] times its fastest.
    pub fn is_wide(&self) -> bool {
        self.max > WIDE * self.min
    }

    /// The spread of `runs` (non-finite runs dropped).
    pub fn of(mut runs: Vec<f64>) -> Spread {
        runs.retain(|v| v.is_finite());
        let mut sorted = runs.clone();
        sorted.sort_by(f64::total_cmp);
        let median = if sorted.is_empty() {
            f64::NAN
        } else if sorted.len() % 2 == 1 {
            sorted[sorted.len() / 2]
        } else {
            (sorted[sorted.len() / 2 - 1] + sorted[sorted.len() / 2]) / 2.0
        };
        Spread { median, min: sorted.first().copied().unwrap_or(f64::NAN), max: sorted.last().copied().unwrap_or(f64::NAN), runs }
    }
}
