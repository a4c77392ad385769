//! What every experiment uses: where it writes ([`Context`]), its error type, the [`Experiment`]
//! trait, and the shared helpers (loading the report's objects, measuring an extractor). The
//! registry in `experiment/mod.rs` lists the experiments; they import this, not the registry.

use indicatif::{MultiProgress, ProgressBar, ProgressStyle};
use isolab_algorithms::{Extraction, Extractor, Field, Samples};
use isolab_io::IoError;
use isolab_metrics::MeshMetrics;
use isolab_pipeline::RunError;
use serde::{de::DeserializeOwned, Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::Arc;

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
    /// Something the experiment needs is not there: an extractor in the registry, an experiment
    /// by that name, a row in another experiment's data.
    #[error("missing: {0}")]
    Missing(String),
    /// A thread pool of the size a measurement needs could not be built.
    #[error("thread pool: {0}")]
    ThreadPool(String),
    /// A setting (an environment variable) is malformed.
    #[error("setting {0}")]
    Setting(String),
    /// A step of the run failed: what it was, and why.
    #[error("{what}: {reason}")]
    Failed {
        /// The step (streaming a file, applying an edit, ...).
        what: String,
        /// The underlying error.
        reason: String,
    },
    /// A Python script, or the reference environment it runs in, failed.
    #[error("Python: {0}")]
    Python(String),
    /// A peer implementation failed where the experiment needs it.
    #[error("peer {0}")]
    Peer(#[from] crate::peers::PeerError),
}

// Field, lattice and sampling errors reach experiments as run errors, with their messages.
impl From<isolab_algorithms::FieldError> for ExperimentError {
    fn from(e: isolab_algorithms::FieldError) -> Self {
        ExperimentError::Run(e.into())
    }
}

impl From<isolab_algorithms::LatticeError> for ExperimentError {
    fn from(e: isolab_algorithms::LatticeError) -> Self {
        ExperimentError::Run(e.into())
    }
}

impl From<isolab_algorithms::SampleError> for ExperimentError {
    fn from(e: isolab_algorithms::SampleError) -> Self {
        ExperimentError::Run(e.into())
    }
}

/// Where and how experiments run.
pub struct Context {
    /// The report directory (`REPORT.md`, `data/`, `figures/`).
    pub report_dir: PathBuf,
    /// Extractions per configuration for timing medians.
    pub repeats: usize,
    /// A quick run (`report --quick`): every experiment at its smallest sizes ([`Context::sizes`],
    /// [`Context::pick`]), into a folder of its own, to see a change across the whole report;
    /// its numbers are not the report's.
    pub quick: bool,
    /// Progress bars, one per experiment.
    pub progress: MultiProgress,
    /// The data files written since [`Context::take_written`] last ran (names, in order).
    written: std::sync::Mutex<Vec<String>>,
}

impl Context {
    /// A context writing into `report_dir`.
    pub fn new(report_dir: PathBuf, repeats: usize) -> Self {
        Self { report_dir, repeats: repeats.max(1), quick: false, progress: MultiProgress::new(), written: Default::default() }
    }

    /// A quick run's context ([`Context::quick`]) writing into `report_dir`.
    pub fn quick(report_dir: PathBuf, repeats: usize) -> Self {
        Self { quick: true, ..Self::new(report_dir, repeats) }
    }

    /// The sizes (resolutions, models, cases) an experiment runs: all of `full`, or in a quick
    /// run its first, which each experiment lists as its smallest.
    pub fn sizes<'a, T>(&self, full: &'a [T]) -> &'a [T] {
        if self.quick {
            &full[..full.len().min(1)]
        } else {
            full
        }
    }

    /// `full`, or `quick` in a quick run: a single size or count an experiment shrinks.
    pub fn pick<T>(&self, full: T, quick: T) -> T {
        if self.quick {
            quick
        } else {
            full
        }
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
        isolab_pipeline::write_json(&path, data)?;
        let mut written = self.written.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        if !written.iter().any(|n| n == name) {
            written.push(name.to_owned());
        }
        Ok(())
    }

    /// The names of the data files written since the last call, which it forgets.
    pub fn take_written(&self) -> Vec<String> {
        std::mem::take(&mut *self.written.lock().unwrap_or_else(std::sync::PoisonError::into_inner))
    }

    /// Reads an experiment's data file.
    pub fn read_data<T: DeserializeOwned>(&self, name: &str) -> Result<T, ExperimentError> {
        let path = self.data_path(name);
        let text =
            std::fs::read_to_string(&path).map_err(|e| ExperimentError::Data { path: path.clone(), reason: e.to_string() })?;
        serde_json::from_str(&text).map_err(|e| ExperimentError::Data { path, reason: e.to_string() })
    }

    /// A path relative to the report directory, for links in the report's pages.
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
    /// The question its page answers, one sentence for the front page's list.
    fn question(&self) -> &'static str;
    /// Its page (`report/<name>.md`, headed by one `## ` title), from its data file.
    fn section(&self, ctx: &Context) -> Result<String, ExperimentError>;
    /// The peers it runs, by their names in [`crate::peer_versions::PEERS`]: its data record
    /// their versions and its page states them.
    fn peers(&self) -> &'static [&'static str] {
        &[]
    }
}

/// `report/` at the workspace root.
pub fn default_report_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join("report")
}

/// `target/report-quick/` at the workspace root: where `report --quick` writes (git ignores it).
pub fn quick_report_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join("target").join("report-quick")
}

/// Path of a shipped model by name (`models/<name>.obj`).
pub fn model_path(name: &str) -> String {
    format!("{}/../models/{name}.obj", env!("CARGO_MANIFEST_DIR"))
}

/// A built-in field by name, or a shipped model by its file stem (`stanford-bunny`) as a
/// signed-distance field: the objects the paper reproductions use.
pub fn load_object(name: &str) -> Result<Arc<dyn Field>, ExperimentError> {
    if std::path::Path::new(&model_path(name)).exists() {
        Ok(isolab_pipeline::load_field(&model_path(name), isolab_algorithms::fields::DEFAULT_SEED)?)
    } else {
        Ok(isolab_algorithms::fields::builtin(name, Default::default())?)
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
    /// Median extraction time over every run, ms.
    pub extraction_ms: f64,
    /// Every extraction run, ms, in rounds until one is not wide ([`crate::report::rounds_until_narrow`]);
    /// absent from data written before runs were kept.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub extraction_runs: Option<crate::report::Rounds>,
    /// Median extraction time on the same sample values without the field, ms: gradients then
    /// come from the samples' interpolant, so the difference is the time spent querying the field
    /// (`compare_algorithms` measures it at the middle resolution; absent elsewhere).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub without_field_ms: Option<f64>,
    /// Extractions timed.
    pub repeats: usize,
    /// Analytic volume, where known.
    pub analytic_volume: Option<f64>,
    /// Every metric of the mesh.
    pub metrics: MeshMetrics,
}

/// Extracts `repeats` times a round, in rounds until one is not wide (keeping the last mesh),
/// measures it, and returns it with the row.
pub fn measure(
    extractor: &dyn Extractor,
    field: &Arc<dyn Field>,
    samples: &Samples,
    repeats: usize,
) -> Result<(Measured, Extraction), ExperimentError> {
    let mut out = Extraction::default();
    let rounds = crate::report::rounds_until_narrow(repeats, || -> Result<f64, ExperimentError> {
        extractor.extract(samples, &mut out)?;
        Ok(out.stats.times.extraction().as_secs_f64() * 1e3)
    })?;
    let row = Measured {
        algorithm: extractor.name().into(),
        field: field.name().into(),
        resolution: samples.grid().dims.iter().copied().max().unwrap_or(0),
        dims: samples.grid().dims,
        spacing: f64::from(samples.grid().spacing),
        sampling_ms: samples.sampling_time().as_secs_f64() * 1e3,
        extraction_ms: rounds.spread().median,
        extraction_runs: Some(rounds),
        without_field_ms: None,
        repeats: repeats.max(1),
        analytic_volume: field.analytic_volume(samples.iso()),
        metrics: MeshMetrics::measure(&out.surface, Some((field.as_ref(), samples.iso()))),
    };
    Ok((row, out))
}

/// `samples`' values alone, without their field: an extractor that asks the field for gradients
/// then takes them from the samples' interpolant ([`time_without_field`]).
pub fn without_field(samples: &Samples) -> Result<Samples<'static>, ExperimentError> {
    Ok(Samples::from_values(*samples.lattice(), samples.values().to_vec(), samples.iso())?)
}

/// The median time of `repeats` extractions by `extractor` of `bare`, samples without their field
/// ([`without_field`]), ms.
pub fn time_without_field(extractor: &dyn Extractor, bare: &Samples, repeats: usize) -> Result<f64, ExperimentError> {
    let mut out = Extraction::default();
    let mut times = Vec::with_capacity(repeats);
    for _ in 0..repeats.max(1) {
        extractor.extract(bare, &mut out)?;
        times.push(out.stats.times.extraction());
    }
    Ok(crate::report::median(times).as_secs_f64() * 1e3)
}

pub use crate::report::ms;

/// Samples along the longest side for built-in fields, in `compare_algorithms` (and the meshes of
/// `viewer`, at the first).
pub const FIELD_LEVELS: [usize; 3] = [32, 64, 128];
/// Samples along the longest side for shipped models, likewise.
pub const MODEL_LEVELS: [usize; 3] = [48, 96, 144];
/// Shipped models measured.
pub const MODELS: [&str; 6] = ["stanford-bunny", "spot", "fandisk", "rocker-arm", "cheburashka", "teapot"];

/// Every compared input: (name, field spec, its three resolutions); built-in fields, then models
/// (`compare_algorithms` measures them, `viewer` shows them).
pub fn compared_inputs() -> Vec<(String, String, [usize; 3])> {
    let mut v: Vec<(String, String, [usize; 3])> =
        isolab_algorithms::fields::registry().iter().map(|f| (f.name.to_owned(), f.name.to_owned(), FIELD_LEVELS)).collect();
    v.extend(MODELS.iter().map(|m| (m.to_string(), model_path(m), MODEL_LEVELS)));
    v
}

/// The distance from each of the `csg` field's true sharp corners to the nearest mesh vertex, in
/// grid spacings `h` (how far the mesh rounds the corner off): `sharp_features` and
/// `surface_nets_smoothing` measure it.
pub fn corner_distances_h(mesh: &isolab_algorithms::TriMesh, spacing: f32) -> Vec<f64> {
    isolab_algorithms::fields::Csg::sharp_corners()
        .iter()
        .map(|c| f64::from(mesh.positions.iter().map(|p| p.distance(*c)).fold(f32::INFINITY, f32::min) / spacing))
        .collect()
}

/// The options each extractor ran with, as recorded in an experiment's data (name, its
/// `Extractor::settings()`): a list for the page, empty when none were recorded.
pub fn options_as_run(settings: &[(String, String)]) -> String {
    options_list("Options as run (each extractor's defaults)", settings)
}

/// `settings` as a list under `heading`, empty when none is given.
fn options_list(heading: &str, settings: &[(String, String)]) -> String {
    let listed: Vec<String> =
        settings.iter().filter(|(_, s)| !s.is_empty()).map(|(name, s)| format!("- `{name}`: {s}\n")).collect();
    if listed.is_empty() {
        return String::new();
    }
    format!("{heading}:\n\n{}\n", listed.concat())
}

/// Each extractor's name and `settings()`, to record in an experiment's data as it runs.
pub fn settings_of<'a>(extractors: impl IntoIterator<Item = &'a dyn isolab_algorithms::Extractor>) -> Vec<(String, String)> {
    extractors.into_iter().map(|e| (e.name().to_owned(), e.settings())).collect()
}

/// The options of the registered extractors `names` as this commit builds them by default, for
/// pages whose data does not record them (the experiment runs each with its defaults): a list, or
/// empty when no name is registered.
pub fn default_options(names: &[&str]) -> String {
    let settings: Vec<(String, String)> = names
        .iter()
        .filter_map(|n| isolab_algorithms::extractors::by_name(n))
        .map(|e| (e.name().to_owned(), e.settings()))
        .collect();
    options_list("Options (each extractor's defaults in this commit)", &settings)
}
