//! The page's opening reading: each world's time and peak memory against its dense grid, the
//! streamed volume's peak against its file, and streaming against meshing in memory.

use super::{Data, VolumeData};

/// The page's opening reading: each world's time and peak memory against its dense grid, the
/// streamed volume's peak against its file, and streaming against meshing in memory.
pub(super) fn reading(runs: &[&Data], volume: Option<&VolumeData>) -> String {
    let mut lines: Vec<String> = runs
        .iter()
        .map(|r| {
            format!(
                "The {:.1} G-sample world ({:.1} GiB as a dense grid) was meshed in {:.0} s into {} triangles{}.",
                r.samples as f64 / 1e9,
                r.dense_gib,
                r.seconds,
                r.triangles,
                r.peak_rss_mib.map_or(String::new(), |m| format!(", {}", peak_phrase(m, r.rss_before_mib, r.dense_gib)))
            )
        })
        .collect();
    if let Some(v) = volume {
        if let Some(peak) = v.streamed.peak_rss_mib {
            lines.push(format!(
                "The {}³ volume file ({:.2} GiB) streamed in {:.1} s at a peak of {peak:.0} MiB, {:.2}× the file.",
                v.side,
                v.file_gib,
                v.streamed.seconds,
                peak / (v.file_gib * 1024.0)
            ));
        }
        if let Some(p) = v.in_place.as_ref().filter(|p| p.peak_rss_mib.is_some()) {
            let peak = p.peak_rss_mib.unwrap_or(f64::NAN);
            lines.push(format!(
                "Meshed whole in memory where its voxels lie, it took {:.1} s at a peak of {peak:.0} MiB, {:.2}× the file (the \
                 header check before asked for {} MiB).",
                p.seconds,
                peak / (v.file_gib * 1024.0),
                v.in_memory_need_mib
            ));
        }
        let same = if v.compare_triangles[0] == v.compare_triangles[1] { "the same" } else { "different" };
        lines.push(format!(
            "At {}³, streaming takes {:.2}× the time of meshing in memory at {:.2}× its peak memory (medians), with {same} \
             triangle counts ({} and {}).",
            v.compare_side,
            v.stream_seconds.median / v.memory_seconds.median,
            v.stream_peak_mib.median / v.memory_peak_mib.median,
            v.compare_triangles[0],
            v.compare_triangles[1]
        ));
    }
    if lines.is_empty() {
        return String::new();
    }
    format!("**Reading.** {}\n\n", lines.join(" "))
}

/// The world's peak resident memory in words. The peak is the process's (`VmHWM`): when it did not
/// rise above what the process held before the run, it is that baseline, not the run's own, and
/// the run's peak is only known to be at most it.
pub(super) fn peak_phrase(peak_mib: f64, before_mib: Option<f64>, dense_gib: f64) -> String {
    let share = |m: f64| 100.0 * m / (dense_gib * 1024.0);
    match before_mib {
        Some(before) if peak_mib <= before + PEAK_RISE_MIB => format!(
            "its peak resident memory not above the {before:.0} MiB the report process held before the run (the run's own \
             peak is at most that, {:.2} % of the dense grid, and is not measured apart)",
            share(before)
        ),
        Some(before) => format!(
            "its peak resident memory {peak_mib:.0} MiB, {:.0} MiB above the process's before the run, {:.2} % of the dense grid",
            peak_mib - before,
            share(peak_mib)
        ),
        None => format!("its peak resident memory {peak_mib:.0} MiB, {:.2} % of the dense grid", share(peak_mib)),
    }
}

/// A peak within this of the baseline did not rise above it.
const PEAK_RISE_MIB: f64 = 1.0;

#[cfg(test)]
mod tests {
    use super::super::volume::StreamedRun;
    use super::*;
    use crate::report::Spread;

    #[test]
    fn a_peak_equal_to_the_baseline_is_not_called_the_runs_peak() {
        // The old wording gave the baseline as the world's peak: "its peak resident memory 665 MiB".
        let p = peak_phrase(665.0, Some(665.0), 8.0);
        assert!(!p.starts_with("its peak resident memory 665 MiB"), "{p}");
        assert!(p.contains("not above the 665 MiB the report process held before the run"), "{p}");
        let p = peak_phrase(900.0, Some(665.0), 8.0);
        assert!(p.contains("900 MiB, 235 MiB above the process's before the run"), "{p}");
        assert!(peak_phrase(512.0, None, 8.0).contains("512 MiB, 6.25 %"));
    }

    #[test]
    fn the_reading_follows_the_data() {
        assert_eq!(reading(&[], None), "");
        let world: Data = serde_json::from_value(serde_json::json!({
            "dims": [1, 1, 1], "chunk": 32, "algorithm": "marching-cubes", "samples": 2_000_000_000u64, "dense_gib": 8.0,
            "machine_gib": null, "seconds": 90.0, "samples_per_second": 1.0, "triangles_per_second": 1.0, "vertices": 1,
            "triangles": 7, "welded": 0, "chunks": [1, 1, 1], "meshed": 1, "empty": 0, "full": 0, "file_gib": 0.1,
            "rss_before_mib": null, "peak_rss_mib": 512.0, "peak_reset": true, "peak_keys": 1, "peak_slab_mib": 1.0
        }))
        .unwrap();
        let run = StreamedRun {
            seconds: 9.0,
            threshold_seconds: 4.0,
            peak_rss_mib: Some(512.0),
            peak_reset: true,
            vertices: 1,
            triangles: 1,
            output_mib: 1.0,
            iso: 1.0,
            iso_from: None,
        };
        let mut volume = VolumeData {
            side: 1024,
            file_gib: 1.0,
            in_memory_need_mib: 1,
            available_mib: None,
            chunk: 64,
            algorithm: "marching-cubes".into(),
            streamed: run,
            zarr: None,
            compare_side: 513,
            compare_iso: 100.0,
            memory_seconds: Spread::of(vec![2.0]),
            memory_peak_mib: Spread::of(vec![400.0]),
            stream_seconds: Spread::of(vec![3.0]),
            stream_peak_mib: Spread::of(vec![100.0]),
            compare_triangles: [5, 5],
            in_place: None,
        };
        let r = reading(&[&world], Some(&volume));
        assert!(r.contains("The 2.0 G-sample world (8.0 GiB as a dense grid) was meshed in 90 s into 7 triangles, its peak resident memory 512 MiB, 6.25 % of the dense grid."), "{r}");
        assert!(r.contains("streamed in 9.0 s at a peak of 512 MiB, 0.50× the file"), "{r}");
        assert!(
            r.contains("streaming takes 1.50× the time of meshing in memory at 0.25× its peak memory (medians), with the same"),
            "{r}"
        );
        volume.compare_triangles = [5, 6];
        assert!(reading(&[&world], Some(&volume)).contains("with different triangle counts (5 and 6)"));
        assert!(!r.contains("where its voxels lie"));
        volume.in_place = Some(super::super::volume::InPlaceRun {
            seconds: 6.0,
            reading_seconds: 1.0,
            peak_rss_mib: Some(768.0),
            peak_reset: true,
            need_mib: 1024,
            vertices: 1,
            triangles: 2,
            output_mib: 1.0,
            iso: 100.0,
        });
        volume.in_memory_need_mib = 25600;
        let r = reading(&[&world], Some(&volume));
        assert!(
            r.contains("it took 6.0 s at a peak of 768 MiB, 0.75× the file (the header check before asked for 25600 MiB)"),
            "{r}"
        );
    }
}
