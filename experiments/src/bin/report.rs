//! Regenerates `report/`: every extractor on every built-in field and shipped model, with
//! topology, quality, accuracy and cost, plus an accuracy-convergence table on the sphere.
//! Timings are medians of repeated extractions on the same samples.
//!
//! Usage: `cargo run --release -p isolab-experiments --bin report [-- --out DIR --repeats N]`

use clap::Parser;
use isolab_algorithms::{extractors, fields, Extraction, Field, Samples};
use isolab_experiments::report::{markdown_table, median, ms};
use isolab_experiments::run::{lattice_for, load_field, write_json, RunConfig};
use isolab_metrics::MeshMetrics;
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Duration;

#[derive(Parser)]
#[command(about = "Regenerate the isolab report")]
struct Args {
    /// Output directory (REPORT.md and data/).
    #[arg(long, default_value = concat!(env!("CARGO_MANIFEST_DIR"), "/../report"))]
    out: PathBuf,
    /// Extractions per configuration for the timing medians.
    #[arg(long, default_value_t = 5)]
    repeats: usize,
}

/// Models shipped in `models/` and the resolution they are meshed at.
const MODELS: &[(&str, usize)] =
    &[("stanford-bunny", 96), ("spot", 96), ("fandisk", 96), ("rocker-arm", 96), ("cheburashka", 96), ("teapot", 96)];
const FIELD_RESOLUTION: usize = 64;

#[derive(Serialize)]
struct Row {
    algorithm: String,
    field: String,
    dims: [usize; 3],
    spacing: f64,
    sampling_ms: f64,
    extraction_ms_median: f64,
    repeats: usize,
    analytic_volume: Option<f64>,
    #[serde(flatten)]
    metrics: MeshMetrics,
}

fn model_path(name: &str) -> String {
    format!("{}/../models/{name}.obj", env!("CARGO_MANIFEST_DIR"))
}

fn measure(
    extractor: &dyn isolab_algorithms::Extractor,
    field: &Arc<dyn Field>,
    samples: &Samples,
    repeats: usize,
) -> Result<Row, String> {
    let mut out = Extraction::default();
    let mut times = Vec::with_capacity(repeats);
    for _ in 0..repeats.max(1) {
        extractor.extract(samples, &mut out).map_err(|e| e.to_string())?;
        times.push(out.stats.times.extraction());
    }
    let extraction = median(times);
    Ok(Row {
        algorithm: extractor.name().into(),
        field: field.name().into(),
        dims: samples.grid().dims,
        spacing: f64::from(samples.grid().spacing),
        sampling_ms: samples.sampling_time().as_secs_f64() * 1e3,
        extraction_ms_median: extraction.as_secs_f64() * 1e3,
        repeats: repeats.max(1),
        analytic_volume: field.analytic_volume(samples.iso()),
        metrics: MeshMetrics::measure(&out.surface, Some((field.as_ref(), samples.iso()))),
    })
}

fn main() -> ExitCode {
    let args = Args::parse();
    match generate(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn generate(args: &Args) -> Result<(), String> {
    let data = args.out.join("data");
    std::fs::create_dir_all(&data).map_err(|e| format!("cannot create '{}': {e}", data.display()))?;
    let mut inputs: Vec<(String, usize)> = fields::registry().iter().map(|f| (f.name.to_owned(), FIELD_RESOLUTION)).collect();
    inputs.extend(MODELS.iter().map(|&(m, r)| (model_path(m), r)));

    let mut rows = Vec::new();
    for (spec, resolution) in &inputs {
        let field = load_field(spec, fields::DEFAULT_SEED).map_err(|e| e.to_string())?;
        let config = RunConfig::new("", spec, *resolution);
        let lattice = lattice_for(field.as_ref(), &config).map_err(|e| e.to_string())?;
        let samples = Samples::sample(field.clone(), lattice, 0.0).map_err(|e| e.to_string())?;
        for extractor in extractors::registry() {
            eprintln!("{} on {} at {:?}", extractor.name(), field.name(), samples.grid().dims);
            rows.push(measure(extractor.as_ref(), &field, &samples, args.repeats)?);
        }
    }
    write_json(&data.join("extractors.json"), &rows).map_err(|e| e.to_string())?;

    let convergence = sphere_convergence(args.repeats)?;
    write_json(&data.join("sphere_convergence.json"), &convergence).map_err(|e| e.to_string())?;
    let markdown = render(&rows, &convergence, args.repeats);
    isolab_experiments::io::write_atomic(&args.out.join("REPORT.md"), |w| std::io::Write::write_all(w, markdown.as_bytes()))
        .map_err(|e| e.to_string())?;
    eprintln!("wrote {}", args.out.join("REPORT.md").display());
    Ok(())
}

#[derive(Serialize)]
struct ConvergenceRow {
    algorithm: String,
    resolution: usize,
    triangles: usize,
    volume_error: f64,
    area_error: f64,
    mean_distance_over_spacing: f64,
    max_distance_over_spacing: f64,
}

fn sphere_convergence(repeats: usize) -> Result<Vec<ConvergenceRow>, String> {
    let field = fields::builtin("sphere", Default::default()).map_err(|e| e.to_string())?;
    let (v, a) = (field.analytic_volume(0.0).unwrap_or(1.0), field.analytic_area(0.0).unwrap_or(1.0));
    let mut rows = Vec::new();
    for n in [16, 32, 64, 128, 256] {
        let lattice = lattice_for(field.as_ref(), &RunConfig::new("", "sphere", n)).map_err(|e| e.to_string())?;
        let spacing = f64::from(lattice.grid().spacing);
        let samples = Samples::sample(field.clone(), lattice, 0.0).map_err(|e| e.to_string())?;
        for extractor in extractors::registry() {
            let r = measure(extractor.as_ref(), &field, &samples, repeats.min(1))?;
            let d = r.metrics.surface_distance.unwrap_or_default();
            rows.push(ConvergenceRow {
                algorithm: r.algorithm,
                resolution: n,
                triangles: r.metrics.triangles,
                volume_error: (r.metrics.volume - v) / v,
                area_error: (r.metrics.area - a) / a,
                mean_distance_over_spacing: d.mean / spacing,
                max_distance_over_spacing: d.max / spacing,
            });
        }
    }
    Ok(rows)
}

fn yes(b: bool) -> &'static str {
    if b {
        "yes"
    } else {
        "**no**"
    }
}

fn render(rows: &[Row], convergence: &[ConvergenceRow], repeats: usize) -> String {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut s = String::new();
    s.push_str("# isolab report\n\n");
    s.push_str("Generated by `cargo run --release -p isolab-experiments --bin report`; do not edit by hand. ");
    s.push_str(&format!(
        "Every number below comes from that run, on a machine with {cores} cores. Extraction times are the median of \
         {repeats} extractions of the same samples (sampling excluded); sampling times are one parallel pass. \
         The machine is shared and noisy: compare ratios within one run, not across runs.\n\n"
    ));
    s.push_str(&format!(
        "Built-in fields are sampled at {FIELD_RESOLUTION} samples along the longest side; shipped models (`models/`) \
         at 96, as signed distance with the sign from the generalized winding number.\n\n"
    ));

    s.push_str("## Topology\n\n");
    s.push_str("`closed`: no boundary edge (gyroid and terrain are cut by the domain, so open there by design). ");
    s.push_str("`manifold`: edge- and vertex-manifold. χ is the Euler characteristic, `g` the genus.\n\n");
    let topo: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            let t = &r.metrics.topology;
            vec![
                r.algorithm.clone(),
                r.field.clone(),
                format!("{}x{}x{}", r.dims[0], r.dims[1], r.dims[2]),
                r.metrics.vertices.to_string(),
                r.metrics.triangles.to_string(),
                yes(t.closed).into(),
                yes(t.edge_manifold && t.vertex_manifold).into(),
                yes(t.oriented).into(),
                t.components.to_string(),
                t.euler.to_string(),
                t.genus.map_or("-".into(), |g| g.to_string()),
                t.boundary_edges.to_string(),
                r.metrics.quality.degenerate_triangles.to_string(),
            ]
        })
        .collect();
    s.push_str(&markdown_table(
        &[
            "algorithm",
            "field",
            "samples",
            "vertices",
            "triangles",
            "closed",
            "manifold",
            "oriented",
            "components",
            "χ",
            "g",
            "boundary edges",
            "degenerate",
        ],
        &topo,
    ));

    s.push_str("\n## Triangle quality\n\n");
    s.push_str(
        "Verdict aspect ratio `l_max (l0+l1+l2) / (4 sqrt(3) A)` (1 is equilateral; VTK's definition) and the CGAL/OpenMesh ",
    );
    s.push_str("ratio `l_max^2 / (2A)` (1.1547 is equilateral), over non-degenerate triangles.\n\n");
    let quality: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            let q = &r.metrics.quality;
            vec![
                r.algorithm.clone(),
                r.field.clone(),
                format!("{:.3}", q.aspect_ratio.mean),
                format!("{:.3}", q.aspect_ratio.sd),
                format!("{:.1}", q.aspect_ratio.max),
                format!("{:.3}", q.aspect_ratio_cgal.mean),
                format!("{:.2}", q.min_angle_deg),
                format!("{:.2}", q.max_angle_deg),
            ]
        })
        .collect();
    s.push_str(&markdown_table(
        &["algorithm", "field", "aspect mean", "aspect sd", "aspect max", "CGAL aspect mean", "min angle °", "max angle °"],
        &quality,
    ));

    s.push_str("\n## Accuracy and cost\n\n");
    s.push_str("Distance of vertices to the true surface (`|f|/|∇f|` for analytic fields, exact for meshes), in units of the grid spacing; ");
    s.push_str("volume error against the analytic volume where one exists.\n\n");
    let cost: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            let spacing = r.spacing;
            let d = r.metrics.surface_distance.unwrap_or_default();
            vec![
                r.algorithm.clone(),
                r.field.clone(),
                format!("{:.4}", d.mean / spacing),
                format!("{:.3}", d.max / spacing),
                r.analytic_volume.map_or("-".into(), |v| format!("{:+.3}%", 100.0 * (r.metrics.volume - v) / v)),
                format!("{:.1}", r.sampling_ms),
                ms(Duration::from_secs_f64(r.extraction_ms_median / 1e3)),
                format!("{:.1}", r.metrics.triangles as f64 / (r.extraction_ms_median / 1e3) / 1e6),
            ]
        })
        .collect();
    s.push_str(&markdown_table(
        &[
            "algorithm",
            "field",
            "mean dist / h",
            "max dist / h",
            "volume error",
            "sampling ms",
            "extraction ms (median)",
            "M triangles/s",
        ],
        &cost,
    ));

    s.push_str("\n## Convergence on the sphere\n\n");
    s.push_str("Relative volume and area error against 4/3 π r³ and 4 π r² (r = 0.4), and vertex distance in grid spacings, as the resolution doubles.\n\n");
    let conv: Vec<Vec<String>> = convergence
        .iter()
        .map(|c| {
            vec![
                c.algorithm.clone(),
                c.resolution.to_string(),
                c.triangles.to_string(),
                format!("{:+.4}%", 100.0 * c.volume_error),
                format!("{:+.4}%", 100.0 * c.area_error),
                format!("{:.4}", c.mean_distance_over_spacing),
                format!("{:.4}", c.max_distance_over_spacing),
            ]
        })
        .collect();
    s.push_str(&markdown_table(
        &["algorithm", "resolution", "triangles", "volume error", "area error", "mean dist / h", "max dist / h"],
        &conv,
    ));
    s.push_str("\nData: `data/extractors.json`, `data/sphere_convergence.json`.\n");
    s
}
