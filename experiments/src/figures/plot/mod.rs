//! Plots with plotters: scatter plots, line plots (optionally log-log) and histograms, each written
//! as SVG and PNG with text drawn from an embedded font (DejaVu Sans), so no system font is needed.
//! Log axes plot `log10` of the data on a linear axis whose ticks sit at round values (1, 2 and 5
//! times a power of ten, or every decade on wide ranges). The legend stands in a panel beside the
//! plot, never over the data, and each series has its own marker (and, in line plots, solid or
//! dashed lines), so series that overlap stay told apart.

use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};
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
    /// Each point's spread in y, `(fastest, slowest)` of its runs, drawn as a bar through it; one
    /// per point, or empty for none.
    pub ranges: Vec<(f64, f64)>,
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

/// Writes `text` into the top left corner of an RGB image (`width * height * 3` bytes, rows top
/// to bottom) on a pale band, so thumbnails in a grid say what each shows.
pub fn caption(rgb: &mut [u8], (width, height): (u32, u32), text: &str) -> Result<(), String> {
    init_fonts();
    let area = BitMapBackend::with_buffer(rgb, (width, height)).into_drawing_area();
    let err = |e: DrawingAreaErrorKind<_>| e.to_string();
    let band = (text.chars().count() as i32 * 7 + 10).min(width as i32);
    area.draw(&Rectangle::new([(0, 0), (band, 20)], WHITE.mix(0.8).filled())).map_err(err)?;
    area.draw(&Text::new(text.to_owned(), (5, 3), ("sans-serif", 13).into_font().color(&BLACK))).map_err(err)?;
    area.present().map_err(err)
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

/// An axis over `lo..hi` in plotted (for [`Scale::Log`]: `log10`) units, with ticks at round
/// values of the data.
#[derive(Clone)]
struct Axis {
    lo: f64,
    hi: f64,
    scale: Scale,
}

impl Ranged for Axis {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        RangedCoordf64::from(self.lo..self.hi).map(value, limit)
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        match self.scale {
            Scale::Linear => RangedCoordf64::from(self.lo..self.hi).key_points(hint),
            Scale::Log => log_ticks(self.lo, self.hi, hint.max_num_points()),
        }
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.lo..self.hi
    }
}

/// Ticks (in `log10` units) between `lo` and `hi` at round values: the densest of every decade,
/// 1-2-5 times a decade, or (within one decade) 1 to 9 times a decade that gives at most `max`
/// ticks (every n-th decade when even the decades are too many).
fn log_ticks(lo: f64, hi: f64, max: usize) -> Vec<f64> {
    let max = max.max(2);
    let within = |mantissas: &[f64]| -> Vec<f64> {
        let (k0, k1) = (lo.floor() as i32, hi.ceil() as i32);
        (k0..=k1)
            .flat_map(|k| mantissas.iter().map(move |m| f64::from(k) + m.log10()))
            .filter(|t| (lo - 1e-9..=hi + 1e-9).contains(t))
            .collect()
    };
    let sets: [&[f64]; 3] = [&[1.0], &[1.0, 2.0, 5.0], &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]];
    // Every integer mantissa only within one decade: across more, 7, 8 and 9 crowd each other.
    let usable = if hi - lo < 1.0 { 3 } else { 2 };
    let mut best = within(sets[0]);
    for set in &sets[1..usable] {
        let ticks = within(set);
        if ticks.len() <= max {
            best = ticks;
        }
    }
    if best.len() > max {
        let step = best.len().div_ceil(max);
        best = best.into_iter().step_by(step).collect();
    }
    best
}

/// How each series is marked: by its place in the list.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Marker {
    Circle,
    Triangle,
    Square,
    Diamond,
    Cross,
}

const MARKERS: [Marker; 5] = [Marker::Circle, Marker::Triangle, Marker::Square, Marker::Diamond, Marker::Cross];

fn marker_of(i: usize) -> Marker {
    MARKERS[i % MARKERS.len()]
}

/// The marker of an implementation, the same on every chart: from a hash of its name as the
/// colour table knows it ([`super::implementation_key`]).
fn marker_for(label: &str) -> Marker {
    let key = super::implementation_key(label).0;
    let hash = key.bytes().fold(0xcbf29ce484222325u64, |h, b| (h ^ u64::from(b)).wrapping_mul(0x100000001b3));
    marker_of((hash % MARKERS.len() as u64) as usize)
}

/// A marker centred at pixel `(x, y)` of `area`.
fn draw_marker<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    m: Marker,
    (x, y): (i32, i32),
    color: RGBColor,
) -> Result<(), String> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let fill = color.filled();
    match m {
        Marker::Circle => area.draw(&Circle::new((x, y), 4, fill)),
        Marker::Triangle => area.draw(&Polygon::new(vec![(x, y - 5), (x + 5, y + 4), (x - 5, y + 4)], fill)),
        Marker::Square => area.draw(&Rectangle::new([(x - 4, y - 4), (x + 4, y + 4)], fill)),
        Marker::Diamond => area.draw(&Polygon::new(vec![(x, y - 5), (x + 5, y), (x, y + 5), (x - 5, y)], fill)),
        Marker::Cross => area.draw(&Cross::new((x, y), 4, color.stroke_width(2))),
    }
    .map_err(err)
}

/// What a legend entry shows: a marker, a bar swatch, and the line style.
#[derive(Clone, Copy)]
enum Swatch {
    Marker(Marker, Option<bool>),
    Bar,
}

/// The width a legend panel needs for `labels` (0 when there are none).
fn legend_width(labels: &[&str]) -> u32 {
    let longest = labels.iter().map(|l| l.chars().count()).max().unwrap_or(0);
    if longest == 0 {
        0
    } else {
        (longest as u32 * 7 + 44).min(SIZE.0 / 2)
    }
}

/// The legend in its own panel beside the plot: one row per entry.
fn draw_legend_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[(String, RGBColor, Swatch)],
) -> Result<(), String> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let style = TextStyle::from(("sans-serif", 13).into_font()).color(&BLACK);
    for (i, (label, color, swatch)) in entries.iter().enumerate() {
        let y = 24 + 20 * i as i32;
        match *swatch {
            Swatch::Marker(m, line) => {
                if let Some(dashed) = line {
                    let seg = if dashed { vec![(2, y), (8, y)] } else { vec![(2, y), (22, y)] };
                    area.draw(&PathElement::new(seg, color.stroke_width(2))).map_err(err)?;
                    if dashed {
                        area.draw(&PathElement::new(vec![(16, y), (22, y)], color.stroke_width(2))).map_err(err)?;
                    }
                }
                draw_marker(area, m, (12, y), *color)?;
            }
            Swatch::Bar => area.draw(&Rectangle::new([(6, y - 5), (18, y + 5)], color.filled())).map_err(err)?,
        }
        area.draw(&Text::new(label.clone(), (28, y - 7), style.clone())).map_err(err)?;
    }
    Ok(())
}

/// A series with its points and its spread bars `(x, fastest, slowest)`, in plotted units.
type Plotted = (Series, Vec<(f64, f64)>, Vec<(f64, f64, f64)>);

fn draw_xy<DB: DrawingBackend>(root: &DrawingArea<DB, Shift>, plot: &XyPlot) -> Result<(), String> {
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    root.fill(&WHITE).map_err(err)?;
    let series: Vec<Plotted> = plot
        .series
        .iter()
        .map(|s| {
            let pts =
                s.points.iter().filter_map(|&(x, y)| Some((transform(x, plot.x_scale)?, transform(y, plot.y_scale)?))).collect();
            let bars = s
                .points
                .iter()
                .zip(&s.ranges)
                .filter_map(|(&(x, _), &(lo, hi))| {
                    Some((transform(x, plot.x_scale)?, transform(lo, plot.y_scale)?, transform(hi, plot.y_scale)?))
                })
                .collect();
            (s.clone(), pts, bars)
        })
        .collect();
    let spans = series.iter().flat_map(|(_, _, b)| b.iter().flat_map(|&(x, lo, hi)| [(x, lo), (x, hi)]));
    let all: Vec<(f64, f64)> = series.iter().flat_map(|(_, p, _)| p.iter().copied()).chain(spans).collect();
    let all = all.iter();
    let (x0, x1) = padded(
        all.clone().map(|p| p.0).fold(f64::INFINITY, f64::min),
        all.clone().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max),
    );
    let (y0, y1) =
        padded(all.clone().map(|p| p.1).fold(f64::INFINITY, f64::min), all.map(|p| p.1).fold(f64::NEG_INFINITY, f64::max));
    let labels: Vec<&str> = series.iter().map(|(s, _, _)| s.label.as_str()).collect();
    // The title over the whole width (legend panel included), so a long one is not cut.
    let body = root.titled(&plot.title, ("sans-serif", 20)).map_err(err)?;
    let (w, _) = body.dim_in_pixel();
    let (plot_area, legend_area) = body.split_horizontally(w - legend_width(&labels));
    let mut chart = ChartBuilder::on(&plot_area)
        .margin(12)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d(Axis { lo: x0, hi: x1, scale: plot.x_scale }, Axis { lo: y0, hi: y1, scale: plot.y_scale })
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
    let mut entries = Vec::new();
    for (i, (s, pts, bars)) in series.iter().enumerate() {
        let color = RGBColor(s.color.0, s.color.1, s.color.2);
        let dashed = i % 2 == 1;
        if plot.style == Style::Lines {
            if dashed {
                chart.draw_series(DashedLineSeries::new(pts.iter().copied(), 6, 4, color.stroke_width(2))).map_err(err)?;
            } else {
                chart.draw_series(LineSeries::new(pts.iter().copied(), color.stroke_width(2))).map_err(err)?;
            }
        }
        // Each point's spread: a bar from its fastest to its slowest run, capped.
        for &(x, lo, hi) in bars {
            let (ox, oy) = plot_area.get_base_pixel();
            let (a, b) = (chart.backend_coord(&(x, lo)), chart.backend_coord(&(x, hi)));
            let (a, b) = ((a.0 - ox, a.1 - oy), (b.0 - ox, b.1 - oy));
            let style = color.stroke_width(1);
            plot_area.draw(&PathElement::new(vec![a, b], style)).map_err(err)?;
            for end in [a, b] {
                plot_area.draw(&PathElement::new(vec![(end.0 - 3, end.1), (end.0 + 3, end.1)], style)).map_err(err)?;
            }
        }
        let m = marker_for(&s.label);
        for p in pts {
            let px = chart.backend_coord(p);
            let (ox, oy) = plot_area.get_base_pixel();
            draw_marker(&plot_area, m, (px.0 - ox, px.1 - oy), color)?;
        }
        entries.push((s.label.clone(), color, Swatch::Marker(m, (plot.style == Style::Lines).then_some(dashed))));
    }
    draw_legend_panel(&legend_area, &entries)?;
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
                    Series { label: format!("{label} (last point: > {})", h.max), color: *color, points, ranges: Vec::new() }
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
    /// The y axis: linear from zero, or log (bars from below the smallest value) where values
    /// span decades.
    pub y_scale: Scale,
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
    let scale = chart_spec.y_scale;
    let plotted: Vec<f64> = chart_spec.series.iter().flat_map(|s| s.values.iter().filter_map(|&v| transform(v, scale))).collect();
    let (y0, y1) = match scale {
        Scale::Linear => (0.0, plotted.iter().copied().fold(0.0, f64::max).max(1e-12) * 1.1),
        Scale::Log => {
            let lo = plotted.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = plotted.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            if lo.is_finite() {
                ((lo - 0.1).floor(), hi + 0.1)
            } else {
                (0.0, 1.0)
            }
        }
    };
    let labels: Vec<&str> = chart_spec.series.iter().map(|s| s.label.as_str()).collect();
    // The title over the whole width (legend panel included), so a long one is not cut.
    let body = root.titled(&chart_spec.title, ("sans-serif", 20)).map_err(err)?;
    let (w, _) = body.dim_in_pixel();
    let (plot_area, legend_area) = body.split_horizontally(w - legend_width(&labels));
    let mut chart = ChartBuilder::on(&plot_area)
        .margin(12)
        .x_label_area_size(70)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..n as f64, Axis { lo: y0, hi: y1, scale })
        .map_err(err)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(0)
        .y_desc(&chart_spec.y_label)
        .label_style(("sans-serif", 13))
        .axis_desc_style(("sans-serif", 15))
        .y_label_formatter(&|v| label(*v, scale))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(err)?;
    let width = 0.8 / k as f64;
    let mut entries = Vec::new();
    for (j, BarSeries { label: name, color, values }) in chart_spec.series.iter().enumerate() {
        let color = RGBColor(color.0, color.1, color.2);
        chart
            .draw_series(values.iter().enumerate().filter_map(|(i, &v)| transform(v, scale).map(|t| (i, t))).map(|(i, t)| {
                let x0 = i as f64 + 0.1 + j as f64 * width;
                Rectangle::new([(x0, y0), (x0 + width * 0.92, t)], color.filled())
            }))
            .map_err(err)?;
        entries.push((name.clone(), color, Swatch::Bar));
    }
    draw_legend_panel(&legend_area, &entries)?;
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
mod tests;
