//! Tests of the parent module.

use super::*;

#[test]
fn writes_svg_and_png_with_text() {
    let dir = tempfile::tempdir().unwrap();
    let stem = dir.path().join("plot");
    let plot = XyPlot {
        title: "quality against cost".into(),
        x_label: "time".into(),
        y_label: "aspect".into(),
        x_scale: Scale::Log,
        y_scale: Scale::Linear,
        style: Style::Scatter,
        series: vec![Series {
            label: "marching-cubes".into(),
            color: (10, 20, 30),
            points: vec![(1.0, 2.0), (10.0, 3.0)],
            ranges: Vec::new(),
        }],
    };
    xy(&stem, &plot).unwrap();
    let svg = std::fs::read_to_string(stem.with_extension("svg")).unwrap();
    assert!(svg.contains("quality against cost") && svg.contains("marching-cubes"));
    let png = std::fs::read(stem.with_extension("png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2, "no temporary files left");
}

#[test]
fn bar_chart_names_its_categories() {
    let dir = tempfile::tempdir().unwrap();
    let stem = dir.path().join("bars");
    let chart = BarChart {
        title: "triangles".into(),
        y_label: "count".into(),
        y_scale: Scale::Linear,
        categories: vec!["sphere".into(), "torus".into()],
        series: vec![
            BarSeries { label: "marching-cubes".into(), color: (1, 2, 3), values: vec![10.0, 20.0] },
            BarSeries { label: "other".into(), color: (4, 5, 6), values: vec![5.0, f64::NAN] },
        ],
    };
    bars(&stem, &chart).unwrap();
    let svg = std::fs::read_to_string(stem.with_extension("svg")).unwrap();
    assert!(svg.contains("sphere") && svg.contains("torus") && svg.contains("other"));
    assert!(stem.with_extension("png").exists());
}

#[test]
fn captions_write_dark_text_on_the_corner_only() {
    let (w, h) = (120u32, 60u32);
    let mut rgb = vec![128u8; (w * h * 3) as usize];
    caption(&mut rgb, (w, h), "surface-nets").unwrap();
    let dark = |x: u32, y: u32| rgb[((y * w + x) * 3) as usize] < 100;
    assert!((0..20).any(|y| (0..100).any(|x| dark(x, y))), "no text drawn");
    assert!((30..h).all(|y| (0..w).all(|x| rgb[((y * w + x) * 3) as usize] == 128)), "drawn outside the band");
}

#[test]
fn log_ticks_sit_at_round_values() {
    let values = |lo: f64, hi: f64, max: usize| -> Vec<String> {
        log_ticks(lo.log10(), hi.log10(), max).iter().map(|&t| label(t, Scale::Log)).collect()
    };
    // The range that drew 15.8, 25.1 and 39.8 before: now round values only.
    assert_eq!(values(12.0, 45.0, 2), ["20"]);
    assert_eq!(values(12.0, 45.0, 4), ["20", "30", "40"]);
    assert_eq!(values(0.5, 300.0, 6), ["1", "10", "100"]);
    assert_eq!(values(0.5, 300.0, 12), ["0.5", "1", "2", "5", "10", "20", "50", "100", "200"]);
    assert_eq!(values(16.0, 256.0, 20), ["20", "50", "100", "200"], "more than a decade: no crowding 7-8-9");
    assert_eq!(values(1.0, 1e9, 4), ["1", "1000", "1e6", "1e9"]);
}

#[test]
fn the_legend_has_room_beside_the_plot() {
    assert_eq!(legend_width(&[]), 0);
    assert!(legend_width(&["marching-cubes"]) > 100 && legend_width(&["x".repeat(500).as_str()]) <= SIZE.0 / 2);
    assert_eq!(marker_of(0), Marker::Circle);
    assert_ne!(marker_of(1), marker_of(0));
}

#[test]
fn log_labels() {
    assert_eq!(label(2.0, Scale::Log), "100");
    assert_eq!(label(0.5f64.log10(), Scale::Log), "0.5");
    assert_eq!(label(5.0, Scale::Log), "1e5");
    assert_eq!(label(0.5, Scale::Linear), "0.5");
}
