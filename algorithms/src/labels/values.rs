//! Label samples as they arrive: owned in the narrowest type that holds them ([`LabelValues`]),
//! or borrowed ([`LabelSamples`]), with the counts and the selection the front ends need.

use std::collections::BTreeMap;

use super::Label;

/// The samples of a label map, in the narrowest type that holds them.
#[derive(Clone, Debug, PartialEq)]
pub enum LabelValues {
    /// Up to 255.
    U8(Vec<u8>),
    /// Up to 65535.
    U16(Vec<u16>),
    /// Anything else that fits 32 bits.
    U32(Vec<u32>),
}

impl LabelValues {
    /// Narrows `u32` labels to the smallest type that holds the largest.
    pub fn narrowest(values: Vec<u32>) -> Self {
        let max = values.iter().copied().max().unwrap_or(0);
        if max <= u32::from(u8::MAX) {
            Self::U8(values.into_iter().map(|v| v as u8).collect())
        } else if max <= u32::from(u16::MAX) {
            Self::U16(values.into_iter().map(|v| v as u16).collect())
        } else {
            Self::U32(values)
        }
    }

    /// The values, borrowed (their length: `as_slice().len()`).
    pub fn as_slice(&self) -> LabelSamples<'_> {
        match self {
            Self::U8(v) => LabelSamples::U8(v),
            Self::U16(v) => LabelSamples::U16(v),
            Self::U32(v) => LabelSamples::U32(v),
        }
    }
}

/// Borrowed label samples (a numpy array's memory read in place, one block of a map).
#[derive(Clone, Copy, Debug)]
pub enum LabelSamples<'a> {
    /// 8-bit labels.
    U8(&'a [u8]),
    /// 16-bit labels.
    U16(&'a [u16]),
    /// 32-bit labels.
    U32(&'a [u32]),
}

impl LabelSamples<'_> {
    /// Number of samples.
    pub fn len(&self) -> usize {
        match self {
            Self::U8(v) => v.len(),
            Self::U16(v) => v.len(),
            Self::U32(v) => v.len(),
        }
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Every label's sample count (background included).
    pub fn counts(&self) -> BTreeMap<u32, usize> {
        match self {
            Self::U8(v) => Self::counts_of_bytes(v),
            Self::U16(v) => Self::counts_of(v),
            Self::U32(v) => Self::counts_of(v),
        }
    }

    /// Every byte label's count in `v`: eight samples at a time where they are all the label of
    /// the eight before (long runs, the background's above all), one at a time elsewhere.
    pub fn counts_of_bytes(v: &[u8]) -> BTreeMap<u32, usize> {
        let mut table = [0usize; 256];
        let mut words = v.chunks_exact(8);
        let mut last = u64::MAX;
        for word in &mut words {
            let w = u64::from_le_bytes(word.try_into().unwrap_or([0; 8]));
            if w == last {
                table[usize::from(word[0])] += 8;
                continue;
            }
            for &l in word {
                table[usize::from(l)] += 1;
            }
            last = if word.iter().all(|&l| l == word[0]) { w } else { u64::MAX };
        }
        for &l in words.remainder() {
            table[usize::from(l)] += 1;
        }
        table.iter().enumerate().filter(|(_, &n)| n > 0).map(|(l, &n)| (l as u32, n)).collect()
    }

    /// Every label's count in `v`, counted a run of equal labels at a time.
    pub fn counts_of<T: Label>(v: &[T]) -> BTreeMap<u32, usize> {
        let mut out = BTreeMap::new();
        let mut run: Option<(T, usize)> = None;
        for &l in v {
            match &mut run {
                Some((last, n)) if *last == l => *n += 1,
                _ => {
                    if let Some((last, n)) = run {
                        *out.entry(last.id()).or_insert(0) += n;
                    }
                    run = Some((l, 1));
                }
            }
        }
        if let Some((last, n)) = run {
            *out.entry(last.id()).or_insert(0) += n;
        }
        out
    }

    /// Every label not in `keep` (sorted) replaced by the background.
    pub fn keep_only(&self, keep: &[u32]) -> LabelValues {
        fn map<T: Label>(v: &[T], keep: &[u32]) -> Vec<T> {
            v.iter().map(|&l| if keep.binary_search(&l.id()).is_ok() { l } else { T::default() }).collect()
        }
        match self {
            Self::U8(v) => LabelValues::U8(map(v, keep)),
            Self::U16(v) => LabelValues::U16(map(v, keep)),
            Self::U32(v) => LabelValues::U32(map(v, keep)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_are_each_labels_samples() {
        let mut random = crate::random::Random::new(3);
        for round in 0..60usize {
            // Runs of random lengths, maps of any length.
            let mut v: Vec<u16> = Vec::new();
            while v.len() < round * 7 {
                let label = (random.next_u64() % 5) as u16;
                let run = 1 + (random.next_u64() % 40) as usize;
                v.extend(std::iter::repeat_n(label, run));
            }
            let mut expected = BTreeMap::new();
            for &l in &v {
                *expected.entry(u32::from(l)).or_insert(0usize) += 1;
            }
            assert_eq!(LabelSamples::counts_of(&v), expected, "round {round}");
            let bytes: Vec<u8> = v.iter().map(|&l| l as u8).collect();
            assert_eq!(LabelSamples::counts_of_bytes(&bytes), expected, "round {round}, bytes");
        }
    }
}
