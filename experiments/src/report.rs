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

impl Spread {
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
