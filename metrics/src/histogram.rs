//! Fixed-bin histograms for quality distributions.

use serde::{Deserialize, Serialize};

/// A histogram with equal bins over `[min, max)`, plus counts below and above.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Histogram {
    /// Lower edge of the first bin.
    pub min: f64,
    /// Upper edge of the last bin.
    pub max: f64,
    /// Counts per bin.
    pub counts: Vec<u64>,
    /// Values below `min`.
    pub below: u64,
    /// Values at or above `max`.
    pub above: u64,
}

impl Histogram {
    /// `bins` equal bins over `[min, max)` filled with `values` (NaN counts as above).
    pub fn new(min: f64, max: f64, bins: usize, values: impl Iterator<Item = f64>) -> Histogram {
        let mut h = Histogram { min, max, counts: vec![0; bins.max(1)], below: 0, above: 0 };
        let width = (max - min) / h.counts.len() as f64;
        for v in values {
            if v < min {
                h.below += 1;
            } else if v >= max || v.is_nan() {
                h.above += 1;
            } else {
                let i = (((v - min) / width) as usize).min(h.counts.len() - 1);
                h.counts[i] += 1;
            }
        }
        h
    }

    /// Total values counted.
    pub fn total(&self) -> u64 {
        self.counts.iter().sum::<u64>() + self.below + self.above
    }

    /// Lower edge of bin `i`.
    pub fn edge(&self, i: usize) -> f64 {
        self.min + (self.max - self.min) * i as f64 / self.counts.len() as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bins_and_tails() {
        let h = Histogram::new(0.0, 1.0, 4, [-1.0, 0.0, 0.24, 0.25, 0.99, 1.0, f64::NAN].into_iter());
        assert_eq!(h.counts, vec![2, 1, 0, 1]);
        assert_eq!((h.below, h.above, h.total()), (1, 2, 7));
        assert_eq!(h.edge(2), 0.5);
    }
}
