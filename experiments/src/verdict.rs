//! Comparison words chosen by the numbers they judge, so a page never types a verdict its data
//! could contradict: `report_check` fails on a comparison word typed into a page's prose, and the
//! words these functions return are the way round it.

/// How one time compares with another, as a page says it: `ratio` is the other's time over this
/// one's; `decimals` is the precision of the factor. `2.5× faster` above one, `2.5× slower` (the
/// inverse factor) below it. A factor that rounds to one at that precision is shown to two
/// decimals instead (`1.20× faster`: 20% is not "as fast"), and only one that still rounds to one
/// is `as fast`.
pub fn times_faster(ratio: f64, decimals: usize) -> String {
    if !ratio.is_finite() || ratio <= 0.0 {
        return "not comparable (no time on one side)".into();
    }
    let (factor, word) = if ratio >= 1.0 { (ratio, "faster") } else { (1.0 / ratio, "slower") };
    let rounds_to_one = |shown: &str| shown.parse::<f64>().is_ok_and(|f| f == 1.0);
    let mut shown = format!("{factor:.decimals$}");
    if rounds_to_one(&shown) {
        shown = format!("{factor:.2}");
        if rounds_to_one(&shown) {
            return "as fast".into();
        }
    }
    format!("{shown}× {word}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_word_follows_the_ratio() {
        assert_eq!(times_faster(194.2, 0), "194× faster");
        assert_eq!(times_faster(0.25, 1), "4.0× slower");
        assert_eq!(times_faster(1.04, 1), "1.04× faster", "a factor that rounds to one is shown finer");
        assert_eq!(times_faster(1.2, 0), "1.20× faster", "20% is not as fast");
        assert_eq!(times_faster(1.001, 1), "as fast");
        assert_eq!(times_faster(1.0 / 1.3, 0), "1.30× slower");
        assert_eq!(times_faster(2.04, 1), "2.0× faster");
        assert!(times_faster(f64::NAN, 0).starts_with("not comparable"));
        assert!(times_faster(0.0, 0).starts_with("not comparable"));
    }
}
