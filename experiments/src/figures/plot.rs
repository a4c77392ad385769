//! Plots with plotters: scatter plots, line plots (optionally log-log) and histograms, each written
//! as SVG and PNG with text drawn from an embedded font (DejaVu Sans), so no system font is needed.
//! Log axes plot `log10` of the data on a linear axis labelled with powers of ten.

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

/// One named set of points.
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend label.
    pub label: String,
    /// Colour.
    pub color: (u8, u8, u8),
    /// Points `(x, y)`.
    pub points: Vec<(f64, f64)>,
}

/// What kind of XY plot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Style {
    /// Markers only.
    Scatter,
    /// Markers joined by lines, in the order given.
    Lines,
}

/// Axis scaling.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scale {
    /// Linear.
    Linear,
    /// Base-10 logarithmic (non-positive values are dropped).
    Log,
}

/// An XY plot.
#[derive(Clone, Debug)]
pub struct XyPlot {
    /// Title above the plot.
    pub title: String,
    /// X axis label.
    pub x_label: String,
    /// Y axis label.
    pub y_label: String,
    /// X scaling.
    pub x_scale: Scale,
    /// Y scaling.
    pub y_scale: Scale,
    /// Markers or lines.
    pub style: Style,
    /// The data.
    pub series: Vec<Series>,
}

static FONTS: Once = Once::new();

/// Registers the embedded font as `sans-serif` (once per process).
pub fn init_fonts() {
    FONTS.call_once(|| {
        // The font is compiled in; registering it cannot fail for a valid TTF.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular());
    });
}

fn transform(v: f64, scale: Scale) -> Option<f64> {
    match scale {
        Scale::Linear => v.is_finite().then_some(v),
        Scale::Log => (v > 0.0 && v.is_finite()).then(|| v.log10()),
    }
}

fn label(v: f64, scale: Scale) -> String {
    match scale {
        Scale::Linear => {
            if v.abs() >= 1e4 || (v != 0.0 && v.abs() < 1e-2) {
                format!("{v:.1e}")
            } else {
                format!("{}", (v * 1000.0).round() / 1000.0)
            }
        }
        Scale::Log => {
            let p = 10f64.powf(v);
            if !(0.01..10_000.0).contains(&p) {
                format!("{p:.0e}")
            } else {
                // Three significant digits, no trailing zeros.
                let digits = (2 - p.log10().floor() as i32).max(0) as usize;
                let t = format!("{p:.digits$}");
                if t.contains('.') {
                    t.trim_end_matches('0').trim_end_matches('.').to_owned()
                } else {
                    t
                }
            }
        }
    }
}

fn padded(lo: f64, hi: f64) -> (f64, f64) {
    if !(lo.is_finite() && hi.is_finite()) {
        return (0.0, 1.0);
    }
    let span = (hi - lo).abs().max(1e-9);
    (lo - 0.06 * span, hi + 0.06 * span)
}

/// The legend, in the same place and style on every chart.
fn draw_legend<'a, DB: DrawingBackend + 'a>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(180, 180, 180))
        .label_font(("sans-serif", 13))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
}

fn draw_xy<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, plot: &XyPlot) -> Result<(), String> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(err)?;
    let series: Vec<(Series, Vec<(f64, f64)>)> = plot
        .series
        .iter()
        .map(|s| {
            let pts =
                s.points.iter().filter_map(|&(x, y)| Some((transform(x, plot.x_scale)?, transform(y, plot.y_scale)?))).collect();
            (s.clone(), pts)
        })
        .collect();
    let all = series.iter().flat_map(|(_, p)| p.iter());
    let (x0, x1) = padded(
        all.clone().map(|p| p.0).fold(f64::INFINITY, f64::min),
        all.clone().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max),
    );
    let (y0, y1) =
        padded(all.clone().map(|p| p.1).fold(f64::INFINITY, f64::min), all.map(|p| p.1).fold(f64::NEG_INFINITY, f64::max));
    let mut chart = ChartBuilder::on(root)
        .caption(&plot.title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err)?;
    let (xs, ys) = (plot.x_scale, plot.y_scale);
    chart
        .configure_mesh()
        .x_desc(&plot.x_label)
        .y_desc(&plot.y_label)
        .label_style(("sans-serif", 13))
        .axis_desc_style(("sans-serif", 15))
        .x_label_formatter(&|v| label(*v, xs))
        .y_label_formatter(&|v| label(*v, ys))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(err)?;
    for (s, pts) in &series {
        let color = RGBColor(s.color.0, s.color.1, s.color.2);
        if plot.style == Style::Lines {
            chart.draw_series(LineSeries::new(pts.iter().copied(), color.stroke_width(2))).map_err(err)?;
        }
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 4, color.filled())))
            .map_err(err)?
            .label(&s.label)
            .legend(move |(x, y)| Circle::new((x + 8, y), 5, color.filled()));
    }
    draw_legend(&mut chart).map_err(err)?;
    root.present().map_err(err)
}

/// A histogram per series (fraction of values per bin), drawn as lines over the bin centres.
#[derive(Clone, Debug)]
pub struct HistogramPlot {
    /// Title.
    pub title: String,
    /// X axis label.
    pub x_label: String,
    /// Label, colour and histogram of each series.
    pub series: Vec<(String, (u8, u8, u8), isolab_metrics::Histogram)>,
}

impl HistogramPlot {
    fn as_xy(&self) -> XyPlot {
        XyPlot {
            title: self.title.clone(),
            x_label: self.x_label.clone(),
            y_label: "fraction of triangles".into(),
            x_scale: Scale::Linear,
            y_scale: Scale::Linear,
            style: Style::Lines,
            series: self
                .series
                .iter()
                .map(|(label, color, h)| {
                    let total = h.total().max(1) as f64;
                    let width = (h.max - h.min) / h.counts.len() as f64;
                    let mut points: Vec<(f64, f64)> =
                        h.counts.iter().enumerate().map(|(i, &c)| (h.edge(i) + 0.5 * width, c as f64 / total)).collect();
                    // Values above the range, as one last point past the end.
                    points.push((h.max + 0.5 * width, h.above as f64 / total));
                    Series { label: format!("{label} (last point: > {})", h.max), color: *color, points }
                })
                .collect(),
        }
    }
}

/// A grouped bar chart: one group per category, one bar per series in each group.
#[derive(Clone, Debug)]
pub struct BarChart {
    /// Title.
    pub title: String,
    /// Y axis label.
    pub y_label: String,
    /// Category names along x.
    pub categories: Vec<String>,
    /// One bar per category in each series.
    pub series: Vec<BarSeries>,
}

/// One series of a bar chart.
#[derive(Clone, Debug)]
pub struct BarSeries {
    /// Legend label.
    pub label: String,
    /// Colour.
    pub color: (u8, u8, u8),
    /// One value per category (NaN: no bar).
    pub values: Vec<f64>,
}

fn draw_bars<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, chart_spec: &BarChart) -> Result<(), String> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(err)?;
    let n = chart_spec.categories.len().max(1);
    let k = chart_spec.series.len().max(1);
    let top =
        chart_spec.series.iter().flat_map(|s| s.values.iter().copied()).filter(|v| v.is_finite()).fold(0.0, f64::max).max(1e-12)
            * 1.1;
    let mut chart = ChartBuilder::on(root)
        .caption(&chart_spec.title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(70)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..n as f64, 0.0..top)
        .map_err(err)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(0)
        .y_desc(&chart_spec.y_label)
        .label_style(("sans-serif", 13))
        .axis_desc_style(("sans-serif", 15))
        .y_label_formatter(&|v| label(*v, Scale::Linear))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(err)?;
    let width = 0.8 / k as f64;
    for (j, BarSeries { label: name, color, values }) in chart_spec.series.iter().enumerate() {
        let color = RGBColor(color.0, color.1, color.2);
        chart
            .draw_series(values.iter().enumerate().filter(|(_, v)| v.is_finite()).map(|(i, &v)| {
                let x0 = i as f64 + 0.1 + j as f64 * width;
                Rectangle::new([(x0, 0.0), (x0 + width * 0.92, v)], color.filled())
            }))
            .map_err(err)?
            .label(name)
            .legend(move |(x, y)| Rectangle::new([(x + 2, y - 5), (x + 12, y + 5)], color.filled()));
    }
    draw_legend(&mut chart).map_err(err)?;
    // Category names under their groups, turned to fit.
    let style = TextStyle::from(("sans-serif", 13).into_font()).transform(FontTransform::Rotate270).color(&BLACK);
    for (i, c) in chart_spec.categories.iter().enumerate() {
        let (px, py) = chart.backend_coord(&(i as f64 + 0.5, 0.0));
        root.draw(&Text::new(c.clone(), (px - 7, py + 8 + 7 * c.len() as i32), style.clone())).map_err(err)?;
    }
    root.present().map_err(err)
}

/// Writes a bar chart as `<stem>.svg` and `<stem>.png`.
pub fn bars(stem: &Path, chart: &BarChart) -> Result<(), String> {
    write_both(stem, |path, svg| {
        if svg {
            draw_bars(&SVGBackend::new(path, SIZE).into_drawing_area(), chart)
        } else {
            draw_bars(&BitMapBackend::new(path, SIZE).into_drawing_area(), chart)
        }
    })
}

/// Writes `<stem>.svg` and `<stem>.png` (800x520) through temporary files.
fn write_both(stem: &Path, draw: impl Fn(&Path, bool) -> Result<(), String>) -> Result<(), String> {
    init_fonts();
    if let Some(dir) = stem.parent() {
        std::fs::create_dir_all(dir).map_err(|e| format!("cannot create '{}': {e}", dir.display()))?;
    }
    for (ext, svg) in [("svg", true), ("png", false)] {
        let path = stem.with_extension(ext);
        let tmp = stem.with_extension(format!("tmp.{ext}"));
        let result = draw(&tmp, svg).and_then(|()| std::fs::rename(&tmp, &path).map_err(|e| e.to_string()));
        if let Err(e) = result {
            let _ = std::fs::remove_file(&tmp);
            return Err(format!("cannot write '{}': {e}", path.display()));
        }
    }
    Ok(())
}

const SIZE: (u32, u32) = (800, 520);

/// Writes an XY plot as `<stem>.svg` and `<stem>.png`.
pub fn xy(stem: &Path, plot: &XyPlot) -> Result<(), String> {
    write_both(stem, |path, svg| {
        if svg {
            draw_xy(&SVGBackend::new(path, SIZE).into_drawing_area(), plot)
        } else {
            draw_xy(&BitMapBackend::new(path, SIZE).into_drawing_area(), plot)
        }
    })
}

/// Writes a histogram plot as `<stem>.svg` and `<stem>.png`.
pub fn histogram(stem: &Path, plot: &HistogramPlot) -> Result<(), String> {
    xy(stem, &plot.as_xy())
}

#[cfg(test)]
mod tests {
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
            series: vec![Series { label: "marching-cubes".into(), color: (10, 20, 30), points: vec![(1.0, 2.0), (10.0, 3.0)] }],
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
    fn log_labels() {
        assert_eq!(label(2.0, Scale::Log), "100");
        assert_eq!(label(0.5f64.log10(), Scale::Log), "0.5");
        assert_eq!(label(5.0, Scale::Log), "1e5");
        assert_eq!(label(0.5, Scale::Linear), "0.5");
    }
}
