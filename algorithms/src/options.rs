//! Named options for building extractors from text (the CLI's `--smoothing elastic`,
//! `--set iterations=5`), with errors that name the algorithm, the option and what is wrong.

use std::collections::BTreeMap;

/// Errors building an extractor from options.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OptionError {
    /// The algorithm has no such option.
    #[error("{algorithm} does not take option '{option}'; it takes: {valid}")]
    Unknown {
        /// Algorithm name.
        algorithm: &'static str,
        /// The option given.
        option: String,
        /// Options it takes.
        valid: String,
    },
    /// The value cannot be used.
    #[error("{algorithm}: option '{option}' = '{value}': {reason}")]
    BadValue {
        /// Algorithm name.
        algorithm: &'static str,
        /// The option.
        option: String,
        /// The value given.
        value: String,
        /// Why it is refused.
        reason: String,
    },
}

/// Option values by name, consumed by an algorithm's constructor.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Options {
    values: BTreeMap<String, String>,
}

impl Options {
    /// No options: every algorithm's defaults.
    pub fn new() -> Self {
        Self::default()
    }

    /// Sets `name` to `value` (later values win).
    pub fn set(&mut self, name: &str, value: &str) -> &mut Self {
        self.values.insert(name.to_owned(), value.to_owned());
        self
    }

    /// The value given for `name`, as text, if any.
    pub fn get(&self, name: &str) -> Option<&str> {
        self.values.get(name).map(String::as_str)
    }

    /// Whether no option is set.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// A reader for `algorithm`, which must [`OptionReader::finish`] to reject unknown options.
    pub fn reader(&self, algorithm: &'static str, valid: &'static [&'static str]) -> OptionReader {
        OptionReader { algorithm, valid, values: self.values.clone() }
    }
}

/// Takes typed values out of [`Options`] for one algorithm.
pub struct OptionReader {
    algorithm: &'static str,
    valid: &'static [&'static str],
    values: BTreeMap<String, String>,
}

impl OptionReader {
    fn bad(&self, option: &str, value: &str, reason: impl Into<String>) -> OptionError {
        OptionError::BadValue { algorithm: self.algorithm, option: option.into(), value: value.into(), reason: reason.into() }
    }

    /// A value parsed with `parse`, or `default` when absent.
    pub fn parse<T>(&mut self, option: &str, default: T, parse: impl Fn(&str) -> Result<T, String>) -> Result<T, OptionError> {
        match self.values.remove(option) {
            None => Ok(default),
            Some(v) => parse(&v).map_err(|reason| self.bad(option, &v, reason)),
        }
    }

    /// A count (a non-negative integer) no larger than `max`.
    pub fn count(&mut self, option: &str, default: usize, max: usize) -> Result<usize, OptionError> {
        self.parse(option, default, |v| match v.trim().parse::<i64>() {
            Ok(n) if n < 0 => Err("must not be negative".into()),
            Ok(n) if n as u64 > max as u64 => Err(format!("must be at most {max}")),
            Ok(n) => Ok(n as usize),
            Err(_) => Err("is not an integer".into()),
        })
    }

    /// A finite number in `[lo, hi]`.
    pub fn number(&mut self, option: &str, default: f32, lo: f32, hi: f32) -> Result<f32, OptionError> {
        self.parse(option, default, |v| match v.trim().parse::<f32>() {
            Ok(x) if x.is_finite() && (lo..=hi).contains(&x) => Ok(x),
            Ok(_) => Err(format!("must be a number in [{lo}, {hi}]")),
            Err(_) => Err("is not a number".into()),
        })
    }

    /// One of `choices` (by name).
    pub fn choice<T: Copy>(&mut self, option: &str, default: T, choices: &[(&str, T)]) -> Result<T, OptionError> {
        self.parse(option, default, |v| {
            choices
                .iter()
                .find(|(n, _)| *n == v.trim())
                .map(|&(_, t)| t)
                .ok_or_else(|| format!("must be one of {}", choices.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")))
        })
    }

    /// The `parallelism` option, which every slab-sweeping extractor takes: `rayon` (slabs in
    /// parallel on the pool) or `serial` (one slab on the calling thread).
    pub fn parallelism(
        &mut self,
        default: crate::sweep::slabs::Parallelism,
    ) -> Result<crate::sweep::slabs::Parallelism, OptionError> {
        use crate::sweep::slabs::Parallelism;
        self.choice("parallelism", default, &[("rayon", Parallelism::Rayon), ("serial", Parallelism::Serial)])
    }

    /// Fails if any option was not taken.
    pub fn finish(self) -> Result<(), OptionError> {
        match self.values.into_keys().next() {
            None => Ok(()),
            Some(option) => Err(OptionError::Unknown {
                algorithm: self.algorithm,
                option,
                valid: if self.valid.is_empty() { "no options".into() } else { self.valid.join(", ") },
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn typed_values_and_errors_name_the_option() {
        let mut o = Options::new();
        o.set("iterations", "-3").set("damping", "2.5").set("mode", "fast").set("color", "red");
        let mut r = o.reader("surface-nets", &["iterations", "damping", "mode"]);
        let e = r.count("iterations", 5, 100).unwrap_err().to_string();
        assert!(e.contains("surface-nets") && e.contains("'iterations'") && e.contains("negative"), "{e}");
        let e = r.number("damping", 0.5, 0.0, 1.0).unwrap_err().to_string();
        assert!(e.contains("[0, 1]"), "{e}");
        let e = r.choice("mode", 1, &[("slow", 1), ("exact", 2)]).unwrap_err().to_string();
        assert!(e.contains("slow, exact"), "{e}");
        assert_eq!(r.count("absent", 7, 100).unwrap(), 7);
        let e = r.finish().unwrap_err().to_string();
        assert!(e.contains("'color'") && e.contains("iterations, damping, mode"), "{e}");
    }
}
