//! What a run is asked to do ([`RunConfig`]) and the words its settings take, the front ends'
//! rules in one place: the CLI's flags and the Python package's arguments both become a
//! [`RunConfig`] through [`RunConfig::builder`], which holds their defaults (64 samples along
//! the longest side, a volume file meshed on its own voxels unless a resolution or dims are
//! given, sampling near the surface where certified, counts only), and every setting named by a
//! word parses with `str::parse` ([`LatticeKind`], [`OutputSpace`], [`VolumeGrid`],
//! [`Measure`], [`Sparse`], and io's [`Inside`]), refusing an unknown word with the words it
//! takes.

use crate::sparse::Sparse;
use glam::{DAffine3, DMat3, DVec3};
use isolab_algorithms::{fields, Options};
use isolab_io::choice::choice_name;
use isolab_io::volume::{Inside, VolumeOptions};
use serde::Serialize;

/// `FromStr` and `Display` for an enum from its table of words (`CHOICES`).
macro_rules! words {
    ($kind:ty, $setting:literal) => {
        impl std::str::FromStr for $kind {
            type Err = isolab_io::UnknownChoice;
            fn from_str(text: &str) -> Result<Self, Self::Err> {
                isolab_io::choice::parse_choice($setting, text, &<$kind>::CHOICES)
            }
        }
        impl std::fmt::Display for $kind {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(isolab_io::choice::choice_name(self, &<$kind>::CHOICES))
            }
        }
    };
}
pub(crate) use words;

/// Which lattice to sample on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum LatticeKind {
    /// A cubic grid.
    #[default]
    Cubic,
    /// A body-centred cubic lattice (twice the samples).
    Bcc,
}

impl LatticeKind {
    /// The words that name each lattice (`--lattice`, `lattice=`), as serialized.
    pub const CHOICES: [(&'static str, LatticeKind); 2] = [("cubic", LatticeKind::Cubic), ("bcc", LatticeKind::Bcc)];
}
words!(LatticeKind, "lattice");

/// Where a volume file is meshed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum VolumeGrid {
    /// On its own voxel grid: no value is interpolated (`resolution` and `dims` are ignored).
    #[default]
    Native,
    /// Resampled trilinearly on an isotropic grid of `resolution` (or `dims`) over its world box.
    Resampled,
}

impl VolumeGrid {
    /// The words that name each grid, as serialized.
    pub const CHOICES: [(&'static str, VolumeGrid); 2] = [("native", VolumeGrid::Native), ("resampled", VolumeGrid::Resampled)];

    /// The front ends' rule: a volume file is meshed on its own voxels unless the user gave a
    /// resolution or dims, which resample it.
    pub fn for_request(resolution: Option<usize>, dims: Option<[usize; 3]>) -> VolumeGrid {
        if resolution.is_some() || dims.is_some() {
            VolumeGrid::Resampled
        } else {
            VolumeGrid::Native
        }
    }
}
words!(VolumeGrid, "volume grid");

/// The coordinate system meshes of anatomical volumes are written in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum OutputSpace {
    /// Right, Anterior, Superior: NIfTI's world, FreeSurfer's, what 3D Slicer displays.
    #[default]
    #[serde(rename = "RAS")]
    Ras,
    /// Left, Posterior, Superior: ITK's and DICOM's world, what 3D Slicer assumes of a file
    /// that does not say.
    #[serde(rename = "LPS")]
    Lps,
}

impl OutputSpace {
    /// The words that name each space (any case: `ras` and `RAS` alike), as serialized.
    pub const CHOICES: [(&'static str, OutputSpace); 2] = [("RAS", OutputSpace::Ras), ("LPS", OutputSpace::Lps)];

    /// The tag written into mesh files (`SPACE=RAS`).
    pub fn tag(self) -> &'static str {
        choice_name(&self, &OutputSpace::CHOICES)
    }

    /// The map from RAS to this space.
    pub(crate) fn map_from_ras(self) -> Option<DAffine3> {
        match self {
            OutputSpace::Ras => None,
            OutputSpace::Lps => {
                Some(DAffine3 { matrix3: DMat3::from_diagonal(DVec3::new(-1.0, -1.0, 1.0)), translation: DVec3::ZERO })
            }
        }
    }
}
words!(OutputSpace, "space");

/// Which measures of the mesh a run computes. The run's own numbers (stage times, counts,
/// active cells, buffer bytes) are always there; the mesh metrics cost as much as the extraction
/// or (self-intersections) many times it, so a run computes them only when asked.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Measure {
    /// None: the report has the vertex and triangle counts only.
    Counts,
    /// Every mesh metric but the exact self-intersection test.
    Metrics,
    /// Every mesh metric, self-intersections included (what the report's experiments use).
    #[default]
    All,
}

impl Measure {
    /// The words that name each measure, as serialized.
    pub const CHOICES: [(&'static str, Measure); 3] =
        [("counts", Measure::Counts), ("metrics", Measure::Metrics), ("all", Measure::All)];

    /// The front ends' rule: self-intersections ask for everything, metrics for every other
    /// measure, neither for the counts alone.
    pub fn asked(metrics: bool, self_intersections: bool) -> Measure {
        match (self_intersections, metrics) {
            (true, _) => Measure::All,
            (false, true) => Measure::Metrics,
            (false, false) => Measure::Counts,
        }
    }
}
words!(Measure, "measure");

/// What to run.
#[derive(Clone, Debug)]
pub struct RunConfig {
    /// Extractor name.
    pub algorithm: String,
    /// Built-in field name, or a path to a mesh (`.obj`, `.ply`, `.stl`, `.glb`) or volume
    /// (`.nii[.gz]`, `.nrrd`, `.nhdr`, `.mhd`, `.mha`, or a `--samples-out` grid) file.
    pub field: String,
    /// Samples along the domain's longest side.
    pub resolution: usize,
    /// Exact samples per axis, overriding `resolution` (e.g. the RMT paper's 75x40x56 bunny).
    pub dims: Option<[usize; 3]>,
    /// Lattice kind.
    pub lattice: LatticeKind,
    /// Iso-value in the input's own values; `None`: the input's default (the iso-value an
    /// isolab grid carries, Otsu's threshold for a scan, 0 otherwise).
    pub iso: Option<f32>,
    /// Which side of the iso-value is inside; `None`: above for scans, below otherwise.
    pub inside: Option<Inside>,
    /// Which volume of a 4-D file.
    pub volume: VolumeOptions,
    /// Where a volume file is meshed.
    pub volume_grid: VolumeGrid,
    /// The coordinate system of meshes of anatomical volumes.
    pub space: OutputSpace,
    /// Seed of noise fields.
    pub seed: i32,
    /// Post-processes to apply in order.
    pub post: Vec<String>,
    /// Algorithm options by name (`smoothing`, `iterations`, ...).
    pub options: Options,
    /// Mesh in chunks of this many cells per side and weld (`--chunk N`).
    pub chunk: Option<usize>,
    /// Give every vertex the field's material (`--materials`).
    pub materials: bool,
    /// Which measures of the mesh to compute (`RunConfig::new`: all of them).
    pub measure: Measure,
    /// Whether to sample only near the surface. `RunConfig::new` says [`Sparse::Never`], so
    /// that a run measures the extractor on the dense grid as the experiments compare them; the
    /// CLI and the Python package say [`Sparse::Auto`] (the builder's default).
    pub sparse: Sparse,
    /// A Lipschitz bound of the field to prune with, replacing the field's own.
    pub lipschitz: Option<f64>,
}

impl RunConfig {
    /// Samples along the longest side when a front end is given neither a resolution nor dims.
    pub const DEFAULT_RESOLUTION: usize = 64;

    /// A config with defaults for everything but the algorithm, field and resolution, as the
    /// experiments compare extractors: every sample of the grid, every measure.
    pub fn new(algorithm: &str, field: &str, resolution: usize) -> Self {
        Self {
            algorithm: algorithm.into(),
            field: field.into(),
            resolution,
            dims: None,
            lattice: LatticeKind::Cubic,
            iso: None,
            inside: None,
            volume: VolumeOptions::default(),
            volume_grid: VolumeGrid::Native,
            space: OutputSpace::Ras,
            seed: fields::DEFAULT_SEED,
            post: Vec::new(),
            options: Options::new(),
            chunk: None,
            materials: false,
            measure: Measure::All,
            sparse: Sparse::Never,
            lipschitz: None,
        }
    }

    /// A config as the CLI and the Python package make one, with their defaults: see
    /// [`RunConfigBuilder`].
    ///
    /// ```
    /// use isolab_pipeline::{LatticeKind, Measure, RunConfig, Sparse, VolumeGrid};
    /// let config = RunConfig::builder("marching-cubes", "torus")
    ///     .resolution(48)
    ///     .lattice("bcc".parse()?)
    ///     .option("parallelism", "serial")
    ///     .build();
    /// assert_eq!((config.resolution, config.lattice), (48, LatticeKind::Bcc));
    /// assert_eq!((config.sparse, config.measure), (Sparse::Auto, Measure::Counts));
    /// assert_eq!(config.volume_grid, VolumeGrid::Resampled);
    /// # Ok::<(), isolab_pipeline::RunError>(())
    /// ```
    pub fn builder(algorithm: &str, field: &str) -> RunConfigBuilder {
        let mut config = RunConfig::new(algorithm, field, Self::DEFAULT_RESOLUTION);
        config.sparse = Sparse::Auto;
        config.measure = Measure::Counts;
        RunConfigBuilder { config, resolution: None }
    }
}

/// Builds a [`RunConfig`] with the front ends' defaults: [`RunConfig::DEFAULT_RESOLUTION`]
/// samples along the longest side; a volume file on its own voxels unless [`resolution`] or
/// [`dims`] is given ([`VolumeGrid::for_request`]); [`Sparse::Auto`]; [`Measure::Counts`];
/// the rest as [`RunConfig::new`]. Settings the user may leave out take an `Option` as well as
/// a value (`.iso(None)` keeps the input's default).
///
/// [`resolution`]: RunConfigBuilder::resolution
/// [`dims`]: RunConfigBuilder::dims
#[derive(Clone, Debug)]
#[must_use = "a builder does nothing until `build`"]
pub struct RunConfigBuilder {
    config: RunConfig,
    resolution: Option<usize>,
}

impl RunConfigBuilder {
    /// Samples along the longest side (a volume file is then resampled).
    pub fn resolution(mut self, resolution: impl Into<Option<usize>>) -> Self {
        self.resolution = resolution.into();
        self
    }

    /// Exact samples per axis, overriding the resolution (a volume file is then resampled).
    pub fn dims(mut self, dims: impl Into<Option<[usize; 3]>>) -> Self {
        self.config.dims = dims.into();
        self
    }

    /// The lattice to sample on.
    pub fn lattice(mut self, lattice: LatticeKind) -> Self {
        self.config.lattice = lattice;
        self
    }

    /// The iso-value in the input's own values (`None`: the input's default).
    pub fn iso(mut self, iso: impl Into<Option<f32>>) -> Self {
        self.config.iso = iso.into();
        self
    }

    /// Which side of the iso-value is inside (`None`: the input's default).
    pub fn inside(mut self, inside: impl Into<Option<Inside>>) -> Self {
        self.config.inside = inside.into();
        self
    }

    /// Which 3-D volume of a 4-D file (`None`: the first).
    pub fn volume(mut self, index: impl Into<Option<usize>>) -> Self {
        self.config.volume = VolumeOptions { index: index.into() };
        self
    }

    /// The coordinate system of meshes of anatomical volumes.
    pub fn space(mut self, space: OutputSpace) -> Self {
        self.config.space = space;
        self
    }

    /// The seed of noise fields (`None`: [`fields::DEFAULT_SEED`]).
    pub fn seed(mut self, seed: impl Into<Option<i32>>) -> Self {
        self.config.seed = seed.into().unwrap_or(fields::DEFAULT_SEED);
        self
    }

    /// Post-processes to apply, in order.
    pub fn post(mut self, names: impl IntoIterator<Item = impl Into<String>>) -> Self {
        self.config.post = names.into_iter().map(Into::into).collect();
        self
    }

    /// One algorithm option, as `--set NAME=VALUE` gives it.
    pub fn option(mut self, name: &str, value: &str) -> Self {
        self.config.options.set(name, value);
        self
    }

    /// Algorithm options, as `--set NAME=VALUE` gives them, in order (a later one wins).
    pub fn options<K: AsRef<str>, V: AsRef<str>>(mut self, options: impl IntoIterator<Item = (K, V)>) -> Self {
        for (name, value) in options {
            self.config.options.set(name.as_ref(), value.as_ref());
        }
        self
    }

    /// Mesh in chunks of this many cells per side and weld.
    pub fn chunk(mut self, cells: impl Into<Option<usize>>) -> Self {
        self.config.chunk = cells.into();
        self
    }

    /// Give every vertex the field's material.
    pub fn materials(mut self, materials: bool) -> Self {
        self.config.materials = materials;
        self
    }

    /// Which measures of the mesh to compute.
    pub fn measure(mut self, measure: Measure) -> Self {
        self.config.measure = measure;
        self
    }

    /// Whether to sample only near the surface.
    pub fn sparse(mut self, sparse: Sparse) -> Self {
        self.config.sparse = sparse;
        self
    }

    /// A Lipschitz bound of the field to prune with (`None`: the field's own).
    pub fn lipschitz(mut self, bound: impl Into<Option<f64>>) -> Self {
        self.config.lipschitz = bound.into();
        self
    }

    /// The config, with the resolution rule applied.
    pub fn build(self) -> RunConfig {
        let RunConfigBuilder { mut config, resolution } = self;
        config.volume_grid = VolumeGrid::for_request(resolution, config.dims);
        config.resolution = resolution.unwrap_or(RunConfig::DEFAULT_RESOLUTION);
        config
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use isolab_io::UnknownChoice;

    /// Every word parses back to its value and is what the JSON report writes for it.
    fn round_trips<T>(choices: &[(&'static str, T)])
    where
        T: Copy + PartialEq + std::fmt::Debug + std::str::FromStr<Err = UnknownChoice> + std::fmt::Display + Serialize,
    {
        for &(word, value) in choices {
            assert_eq!(word.parse::<T>(), Ok(value));
            assert_eq!(word.to_ascii_uppercase().parse::<T>(), Ok(value), "{word} in capitals");
            assert_eq!(value.to_string(), word);
            assert_eq!(serde_json::to_value(value).unwrap(), serde_json::Value::from(word), "{word}");
        }
        let err = "no-such-word".parse::<T>().unwrap_err();
        assert_eq!(err.valid, choices.iter().map(|(w, _)| *w).collect::<Vec<_>>());
    }

    #[test]
    fn every_setting_parses_its_words_and_writes_them_as_the_report_does() {
        round_trips(&LatticeKind::CHOICES);
        round_trips(&VolumeGrid::CHOICES);
        round_trips(&OutputSpace::CHOICES);
        round_trips(&Measure::CHOICES);
        round_trips(&Sparse::CHOICES);
        round_trips(&Inside::CHOICES);
        let err = "hexagonal".parse::<LatticeKind>().unwrap_err();
        assert_eq!(err.to_string(), "lattice 'hexagonal': expected 'cubic' or 'bcc'");
    }

    #[test]
    fn the_builder_resamples_a_volume_only_when_a_resolution_or_dims_are_given() {
        let plain = RunConfig::builder("marching-cubes", "scan.nii").build();
        assert_eq!((plain.volume_grid, plain.resolution), (VolumeGrid::Native, RunConfig::DEFAULT_RESOLUTION));
        let resolution = RunConfig::builder("marching-cubes", "scan.nii").resolution(Some(100)).build();
        assert_eq!((resolution.volume_grid, resolution.resolution), (VolumeGrid::Resampled, 100));
        let dims = RunConfig::builder("marching-cubes", "scan.nii").dims([5, 6, 7]).build();
        assert_eq!((dims.volume_grid, dims.dims), (VolumeGrid::Resampled, Some([5, 6, 7])));
        let none = RunConfig::builder("marching-cubes", "scan.nii").resolution(None).dims(None).seed(None).build();
        assert_eq!((none.volume_grid, none.seed), (VolumeGrid::Native, fields::DEFAULT_SEED));
    }

    #[test]
    fn the_builder_keeps_every_setting_and_later_options_win() {
        let c = RunConfig::builder("surface-nets", "gyroid")
            .iso(0.5)
            .inside(Inside::Above)
            .volume(2)
            .space(OutputSpace::Lps)
            .seed(9)
            .post(["keep-largest"])
            .options([("smoothing", "none"), ("iterations", "3")])
            .option("iterations", "5")
            .chunk(16)
            .materials(true)
            .measure(Measure::All)
            .sparse(Sparse::Never)
            .lipschitz(2.0)
            .build();
        assert_eq!(
            (c.iso, c.inside, c.volume.index, c.space, c.seed),
            (Some(0.5), Some(Inside::Above), Some(2), OutputSpace::Lps, 9)
        );
        assert_eq!((c.post.as_slice(), c.chunk, c.materials), (["keep-largest".to_owned()].as_slice(), Some(16), true));
        assert_eq!((c.measure, c.sparse, c.lipschitz), (Measure::All, Sparse::Never, Some(2.0)));
        assert_eq!((c.options.get("iterations"), c.options.get("smoothing")), (Some("5"), Some("none")));
    }

    #[test]
    fn measures_follow_the_flags() {
        assert_eq!(Measure::asked(false, false), Measure::Counts);
        assert_eq!(Measure::asked(true, false), Measure::Metrics);
        assert_eq!(Measure::asked(false, true), Measure::All);
        assert_eq!(Measure::asked(true, true), Measure::All);
    }
}
