//! The report's experiments. Each one writes `report/data/<name>.json` (its rows and the
//! parameters that produced them) and `report/figures/<name>/*`, and renders its section of
//! `report/REPORT.md` from that data alone, so the report can be reassembled without rerunning.
//!
//! Adding an experiment: a file here implementing [`Experiment`], one line in [`all`], and a
//! two-line binary in `src/bin/` calling [`run_and_assemble`].

pub mod compare_algorithms;
pub mod costen_table;
pub mod decimation;
pub mod large_world;
pub mod peers;
pub mod real_volumes;
pub mod scaling;
pub mod sharp_features;
pub mod sphere_convergence;
pub mod stuart_tables;
pub mod surface_nets_smoothing;
pub mod svoboda_timing;
pub mod terrain_edit;
pub mod terrain_lod;

use crate::io::{write_atomic, IoError};
use crate::run::RunError;
use indicatif::{MultiProgress, ProgressBar, ProgressStyle};
use isolab_algorithms::{Extraction, Extractor, Field, Samples};
use isolab_metrics::MeshMetrics;
use serde::{de::DeserializeOwned, Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

/// Errors while running an experiment or assembling the report.
#[derive(Debug, thiserror::Error)]
pub enum ExperimentError {
    /// A file could not be read or written.
    #[error(transparent)]
    Io(#[from] IoError),
    /// A run failed.
    #[error(transparent)]
    Run(#[from] RunError),
    /// Extraction failed.
    #[error(transparent)]
    Extract(#[from] isolab_algorithms::ExtractError),
    /// A data file is missing or malformed.
    #[error("data file '{path}': {reason}; rerun the experiment")]
    Data {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// A figure could not be drawn.
    #[error("figure: {0}")]
    Figure(String),
}

/// Where and how experiments run.
pub struct Context {
    /// The report directory (`REPORT.md`, `data/`, `figures/`).
    pub report_dir: PathBuf,
    /// Extractions per configuration for timing medians.
    pub repeats: usize,
    /// Progress bars, one per experiment.
    pub progress: MultiProgress,
}

impl Context {
    /// A context writing into `report_dir`.
    pub fn new(report_dir: PathBuf, repeats: usize) -> Self {
        Self { report_dir, repeats: repeats.max(1), progress: MultiProgress::new() }
    }

    /// `data/<name>.json`.
    pub fn data_path(&self, name: &str) -> PathBuf {
        self.report_dir.join("data").join(format!("{name}.json"))
    }

    /// `figures/<name>/`, created.
    pub fn figure_dir(&self, name: &str) -> Result<PathBuf, ExperimentError> {
        let dir = self.report_dir.join("figures").join(name);
        std::fs::create_dir_all(&dir).map_err(|source| IoError::Write { path: dir.clone(), source })?;
        Ok(dir)
    }

    /// A progress bar of `len` steps labelled `name`.
    pub fn bar(&self, name: &str, len: u64) -> ProgressBar {
        let bar = self.progress.add(ProgressBar::new(len));
        if let Ok(style) = ProgressStyle::with_template("{prefix:>20} [{bar:30}] {pos}/{len} {elapsed:>4} {msg}") {
            bar.set_style(style.progress_chars("=> "));
        }
        bar.set_prefix(name.to_owned());
        bar
    }

    /// Writes an experiment's data file.
    pub fn write_data<T: Serialize>(&self, name: &str, data: &T) -> Result<(), ExperimentError> {
        let path = self.data_path(name);
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir).map_err(|source| IoError::Write { path: dir.into(), source })?;
        }
        crate::run::write_json(&path, data)?;
        Ok(())
    }

    /// Reads an experiment's data file.
    pub fn read_data<T: DeserializeOwned>(&self, name: &str) -> Result<T, ExperimentError> {
        let path = self.data_path(name);
        let text =
            std::fs::read_to_string(&path).map_err(|e| ExperimentError::Data { path: path.clone(), reason: e.to_string() })?;
        serde_json::from_str(&text).map_err(|e| ExperimentError::Data { path, reason: e.to_string() })
    }

    /// A path relative to the report directory, for links in `REPORT.md`.
    pub fn link(&self, path: &Path) -> String {
        path.strip_prefix(&self.report_dir).unwrap_or(path).to_string_lossy().replace('\\', "/")
    }
}

/// One experiment of the report.
pub trait Experiment: Send + Sync {
    /// Stable snake_case name: the binary, the data file and the figure folder.
    fn name(&self) -> &'static str;
    /// Runs it: writes its data and figures.
    fn run(&self, ctx: &Context) -> Result<(), ExperimentError>;
    /// Its section of `REPORT.md`, from its data file.
    fn section(&self, ctx: &Context) -> Result<String, ExperimentError>;
}

/// Every experiment, in report order.
pub fn all() -> Vec<Box<dyn Experiment>> {
    vec![
        Box::new(compare_algorithms::CompareAlgorithms),
        Box::new(sphere_convergence::SphereConvergence),
        Box::new(surface_nets_smoothing::SurfaceNetsSmoothing),
        Box::new(sharp_features::SharpFeatures),
        Box::new(costen_table::CostenTable),
        Box::new(peers::Peers),
        Box::new(real_volumes::RealVolumes),
        Box::new(scaling::Scaling),
        Box::new(decimation::Decimation),
        Box::new(svoboda_timing::SvobodaTiming),
        Box::new(stuart_tables::StuartTables),
        Box::new(terrain_edit::TerrainEdit),
        Box::new(terrain_lod::TerrainLod),
        Box::new(large_world::LargeWorld),
    ]
}

/// Writes `REPORT.md` from every experiment's data (a missing data file is noted, not fatal).
pub fn assemble(ctx: &Context) -> Result<PathBuf, ExperimentError> {
    let mut md = String::from("# isolab report\n\n");
    md.push_str(
        "Generated by `cargo run --release -p isolab-experiments --bin report`; do not edit by hand. Every number comes from \
         the data files in `data/`, written by the experiment binaries in `experiments/src/bin/` (one per section). \
         Times are wall-clock medians on a shared 2-core machine: compare ratios within one run, not across runs.\n\n",
    );
    md.push_str("Contents: ");
    md.push_str(&all().iter().map(|e| format!("[{0}](#{0})", e.name())).collect::<Vec<_>>().join(" · "));
    md.push_str("\n\n");
    for e in all() {
        md.push_str(&format!("<a id=\"{}\"></a>\n\n", e.name()));
        match e.section(ctx) {
            Ok(s) => md.push_str(&s),
            Err(err) => md.push_str(&format!("## {}\n\n_Not generated yet: {err}_\n", e.name())),
        }
        md.push('\n');
    }
    let path = ctx.report_dir.join("REPORT.md");
    write_atomic(&path, |w| std::io::Write::write_all(w, md.as_bytes()))?;
    Ok(path)
}

/// Runs the experiment called `name` and reassembles the report (what each binary does).
pub fn run_and_assemble(name: &str) -> std::process::ExitCode {
    let ctx = Context::new(default_report_dir(), 5);
    let result = all()
        .into_iter()
        .find(|e| e.name() == name)
        .ok_or_else(|| ExperimentError::Figure(format!("no experiment called {name}")))
        .and_then(|e| e.run(&ctx))
        .and_then(|()| assemble(&ctx));
    match result {
        Ok(path) => {
            eprintln!("wrote {}", path.display());
            std::process::ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

/// `report/` at the workspace root.
pub fn default_report_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join("report")
}

/// Path of a shipped model by name (`models/<name>.obj`).
pub fn model_path(name: &str) -> String {
    format!("{}/../models/{name}.obj", env!("CARGO_MANIFEST_DIR"))
}

/// A built-in field by name, or a shipped model by its file stem (`stanford-bunny`) as a
/// signed-distance field: the objects the paper reproductions use.
pub fn load_object(name: &str) -> Result<Arc<dyn Field>, ExperimentError> {
    if std::path::Path::new(&model_path(name)).exists() {
        Ok(crate::run::load_field(&model_path(name), isolab_algorithms::fields::DEFAULT_SEED)?)
    } else {
        Ok(isolab_algorithms::fields::builtin(name, Default::default()).map_err(crate::run::RunError::from)?)
    }
}

/// One extractor on one set of samples: median extraction time and every metric.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Measured {
    /// Extractor name.
    pub algorithm: String,
    /// Field name.
    pub field: String,
    /// Samples along the longest side.
    pub resolution: usize,
    /// Samples per axis.
    pub dims: [usize; 3],
    /// Grid spacing.
    pub spacing: f64,
    /// One parallel sampling pass, ms.
    pub sampling_ms: f64,
    /// Median extraction time, ms.
    pub extraction_ms: f64,
    /// Extractions timed.
    pub repeats: usize,
    /// Analytic volume, where known.
    pub analytic_volume: Option<f64>,
    /// Every metric of the mesh.
    pub metrics: MeshMetrics,
}

/// Extracts `repeats` times (keeping the last mesh), measures it, and returns it with the row.
pub fn measure(
    extractor: &dyn Extractor,
    field: &Arc<dyn Field>,
    samples: &Samples,
    repeats: usize,
) -> Result<(Measured, Extraction), ExperimentError> {
    let mut out = Extraction::default();
    let mut times = Vec::with_capacity(repeats);
    for _ in 0..repeats.max(1) {
        extractor.extract(samples, &mut out)?;
        times.push(out.stats.times.extraction());
    }
    let row = Measured {
        algorithm: extractor.name().into(),
        field: field.name().into(),
        resolution: samples.grid().dims.iter().copied().max().unwrap_or(0),
        dims: samples.grid().dims,
        spacing: f64::from(samples.grid().spacing),
        sampling_ms: samples.sampling_time().as_secs_f64() * 1e3,
        extraction_ms: crate::report::median(times).as_secs_f64() * 1e3,
        repeats: repeats.max(1),
        analytic_volume: field.analytic_volume(samples.iso()),
        metrics: MeshMetrics::measure(&out.surface, Some((field.as_ref(), samples.iso()))),
    };
    Ok((row, out))
}

/// Formats milliseconds compactly.
pub fn ms(v: f64) -> String {
    crate::report::ms(Duration::from_secs_f64(v.max(0.0) / 1e3))
}
