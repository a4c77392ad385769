//! The one extractor trait, its output buffer and statistics, and the post-process trait.

use crate::lattice::LatticeError;
use crate::mesh::{TetMesh, TriMesh};
use crate::samples::{SampleError, Samples};
use std::time::Duration;

/// Wall time of each stage. Stages an algorithm does not have stay zero.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StageTimes {
    /// Field evaluation (copied from [`Samples::sampling_time`]).
    pub sampling: Duration,
    /// Vertex pass: edge crossings, clustering, vertex placement.
    pub vertex: Duration,
    /// Geometry pass: triangles or tetrahedra.
    pub geometry: Duration,
    /// Vertex smoothing or relaxation inside the extractor (surface nets' constrained smoothing).
    pub smoothing: Duration,
    /// Vertex normals.
    pub normals: Duration,
    /// Post-processes (edge collapse, relaxation, smoothing).
    pub post: Duration,
}

impl StageTimes {
    /// Extraction only: vertex + geometry + smoothing + normals.
    pub fn extraction(&self) -> Duration {
        self.vertex + self.geometry + self.smoothing + self.normals
    }

    /// Everything: sampling + extraction + post.
    pub fn total(&self) -> Duration {
        self.sampling + self.extraction() + self.post
    }
}

/// What an extraction produced and what it cost.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Stats {
    /// Per-stage wall times.
    pub times: StageTimes,
    /// Surface vertices.
    pub vertices: usize,
    /// Surface triangles.
    pub triangles: usize,
    /// Tetrahedra (volume extractors).
    pub tetrahedra: usize,
    /// Triangles discarded as degenerate (repeated vertex), e.g. by clustering.
    pub discarded_triangles: usize,
    /// Lattice cells visited that could hold surface.
    pub active_cells: usize,
    /// Bytes of output buffers plus scratch buffers held at the end.
    pub buffer_bytes: usize,
    /// Iterative extractors: whether they met their stopping condition (`None`: not iterative).
    pub converged: Option<bool>,
    /// Things the user should know about the input or the result (an open input surface, ...).
    pub warnings: Vec<String>,
}

/// The output of an extractor: a reusable buffer. [`Extraction::clear`] keeps capacity so
/// re-meshing does not allocate once buffers have grown.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Extraction {
    /// The surface.
    pub surface: TriMesh,
    /// The tetrahedral volume, for volume extractors (empty otherwise).
    pub volume: TetMesh,
    /// Times and counts.
    pub stats: Stats,
    /// Where each vertex comes from, when asked ([`Chunking::Apron`] extractors only).
    pub origins: Origins,
    /// A value per surface vertex, when the extractor was asked for one (marching cubes'
    /// [`crate::extractors::marching_cubes::VertexValues`]); empty otherwise.
    pub vertex_values: Vec<f32>,
    /// Set by the caller: the bytes a fresh output may take. An extractor that can estimate its
    /// output before allocating it (marching cubes) fails with [`ExtractError::OverMemory`], having
    /// allocated nothing, when it would take more; others ignore it. Kept by
    /// [`Extraction::clear`].
    pub memory_limit: Option<u64>,
}

impl Extraction {
    /// Empties the buffers, keeping capacity, and resets the stats.
    pub fn clear(&mut self) {
        self.surface.clear();
        self.volume.clear();
        self.stats = Stats::default();
        self.origins.vertices.clear();
        self.vertex_values.clear();
    }

    /// Fills the counts and buffer bytes from the meshes (`scratch_bytes` is what the extractor
    /// held besides).
    pub fn finish_counts(&mut self, scratch_bytes: usize) {
        self.stats.vertices = self.surface.positions.len();
        self.stats.triangles = self.surface.triangles.len();
        self.stats.tetrahedra = self.volume.tetrahedra.len();
        self.stats.buffer_bytes =
            self.surface.capacity_bytes() + self.volume.capacity_bytes() + 4 * self.vertex_values.capacity() + scratch_bytes;
    }
}

/// How an extractor meshes a volume in chunks ([`crate::chunks`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Chunking {
    /// It cannot.
    Unsupported,
    /// Every triangle comes from one cell's samples and every vertex from one lattice edge's two
    /// samples: chunks that share their boundary samples mesh independently, in the lattice's
    /// index coordinates, and weld exactly by position (marching cubes, Kuhn marching tetrahedra).
    CellLocal,
    /// Its output near a sample depends on samples up to `apron` samples away (dual methods'
    /// neighbouring cells and smoothing, clustering's stars): each chunk also reads `apron`
    /// samples of its neighbours, the extractor reports where each vertex comes from
    /// ([`Origins`]), each chunk keeps the triangles it owns, and chunks weld by lattice key.
    Apron(usize),
}

/// How chunks meshed at different levels of detail meet without cracks ([`crate::chunks::lod`]).
#[derive(Clone, Copy)]
pub enum LevelsOfDetail<'a> {
    /// Not supported; the reason, for messages.
    Unsupported(&'static str),
    /// Restriction and stitching ([`crate::chunks::lod`]): vertices on lattice edges by linear
    /// interpolation, kept off the samples, and ambiguous faces that keep their inside corners
    /// apart (plain marching cubes).
    Stitched,
    /// Restriction and octree dual contouring's minimal edges: the extractor's own
    /// [`crate::chunks::lod::DualLevels`], a polygon per minimal crossing edge joining its
    /// cells' vertices (surface nets, dual contouring).
    Dual(&'a dyn crate::chunks::lod::DualLevels),
}

impl LevelsOfDetail<'_> {
    /// The method's name, for listings.
    pub fn method(&self) -> &'static str {
        match self {
            LevelsOfDetail::Unsupported(_) => "none",
            LevelsOfDetail::Stitched => "restriction and stitching",
            LevelsOfDetail::Dual(_) => "restriction and octree dual contouring's minimal edges",
        }
    }
}

/// Where each surface vertex comes from in the lattice, for chunked extraction: filled by
/// extractors whose [`Extractor::chunking`] is [`Chunking::Apron`] when `wanted` is set.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Origins {
    /// Set by the caller to ask for origins (kept by [`Extraction::clear`]).
    pub wanted: bool,
    /// Per vertex: the sample that owns it (`x`, `y`, `z` sample indices of a cubic grid; for
    /// dual methods the lower corner of its cell) and its ordinal among that sample's vertices.
    pub vertices: Vec<[u32; 4]>,
}

impl Origins {
    /// Fills `vertices` from each vertex's owning sample (a flat index of `grid`) and ordinal.
    pub fn fill_with_ordinals(&mut self, grid: &crate::lattice::Grid, owners: impl Iterator<Item = (usize, u32)>) {
        self.vertices.clear();
        let [nx, ny, _] = grid.dims;
        self.vertices.extend(owners.map(|(i, k)| [(i % nx) as u32, ((i / nx) % ny) as u32, (i / (nx * ny)) as u32, k]));
    }

    /// Fills `vertices` from each vertex's owning sample (a flat index of `grid`) and a tag, in
    /// vertex order: consecutive vertices with the same owner and tag are numbered from `tag`
    /// up. Tags keep apart vertices a sample makes in separate passes (a repair pass).
    pub fn fill_from_owners(&mut self, grid: &crate::lattice::Grid, owners: impl Iterator<Item = (usize, u32)>) {
        self.vertices.clear();
        let [nx, ny, _] = grid.dims;
        let mut last = (usize::MAX, 0u32, 0u32);
        for (i, tag) in owners {
            let ordinal = if i == last.0 && tag == last.1 { last.2 + 1 } else { tag };
            last = (i, tag, ordinal);
            self.vertices.push([(i % nx) as u32, ((i / nx) % ny) as u32, (i / (nx * ny)) as u32, ordinal]);
        }
    }
}

/// Errors from extraction.
#[derive(Debug, thiserror::Error)]
pub enum ExtractError {
    /// The algorithm cannot run on this lattice.
    #[error("{algorithm} does not run on a {lattice} lattice; use {supported}")]
    UnsupportedLattice {
        /// Algorithm name.
        algorithm: &'static str,
        /// Lattice given.
        lattice: &'static str,
        /// Lattices it supports.
        supported: &'static str,
    },
    /// A surface post-process after an extractor that made no surface.
    #[error("{post} needs a triangle surface, but the extractor produced only a tetrahedral volume; drop --post {post}")]
    NoSurface {
        /// Post-process name.
        post: &'static str,
    },
    /// The input cannot be meshed with these settings (a spacing larger than the model, ...).
    #[error("{algorithm}: {reason}")]
    BadInput {
        /// Algorithm name.
        algorithm: &'static str,
        /// What is wrong, naming the input and the setting.
        reason: String,
    },
    /// The output would not fit 32-bit indices.
    #[error("{algorithm}: output too large for 32-bit indices ({vertices} vertices)")]
    TooLarge {
        /// Algorithm name.
        algorithm: &'static str,
        /// Vertices it would need.
        vertices: usize,
    },
    /// The output would not fit the memory the caller allows (checked before it is allocated).
    #[error(
        "{algorithm}: the mesh would need about {} MiB ({vertices} vertices estimated), over the {} MiB allowed; \
         mesh a coarser grid (step_size, --resolution), in blocks (--stream, isolab.dask), or allow more memory",
        needed >> 20, limit >> 20
    )]
    OverMemory {
        /// Algorithm name.
        algorithm: &'static str,
        /// Bytes the output and scratch would take, estimated.
        needed: u64,
        /// Bytes allowed.
        limit: u64,
        /// Vertices estimated.
        vertices: usize,
    },
    /// Sampling failed.
    #[error(transparent)]
    Samples(#[from] SampleError),
    /// The lattice could not be built.
    #[error(transparent)]
    Lattice(#[from] LatticeError),
}

/// How to build an extractor: its name, one line, and a constructor from options. Each
/// algorithm file defines its own as `pub const INFO` (the name and description are written there
/// once; [`Extractor::info`] returns it, and the provided [`Extractor::name`] and
/// [`Extractor::description`] read it); the registry ([`crate::extractors::INFOS`]) lists them.
pub struct ExtractorInfo {
    /// Stable kebab-case name (CLI, registry, report).
    pub name: &'static str,
    /// One line saying what it does.
    pub description: &'static str,
    /// The options it takes (`--set NAME=VALUE`).
    pub options: &'static [&'static str],
    /// Builds it; unknown or bad options are errors naming the option.
    pub make: fn(&crate::options::Options) -> Result<Box<dyn Extractor>, crate::options::OptionError>,
    /// What it promises with its default options, as data: the registry-wide contract test
    /// (`tests/tests/contract.rs`) checks every promise of every registered extractor.
    pub guarantees: Guarantees,
    /// How it reads a caller's borrowed samples ([`Samples::borrowed`]): in place, or from a
    /// copy, and why (`tests/tests/borrowed.rs` holds it to its word and to the same mesh).
    pub samples: SampleAccess,
}

/// How an extractor reads borrowed samples ([`Samples::borrowed`]: a numpy array, a
/// memory-mapped file, a block of a larger volume).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SampleAccess {
    /// In place, in their own type and memory order (its loops compiled for each sample type),
    /// checking that they are finite as it reads them; a surface extractor that reads them in
    /// place also keeps to [`Extraction::memory_limit`] (it is what a run that does not copy the
    /// samples relies on to fit).
    Borrowed,
    /// From their conversion into `f32` samples in isolab's order (one copy, made once per
    /// [`Samples`] and checked finite by [`Extractor::extract`] before the extractor runs); the
    /// reason it cannot read them in place.
    Copies(&'static str),
}

impl SampleAccess {
    /// `"borrowed"` or `"copies: REASON"`, as listings show it.
    pub fn describe(&self) -> String {
        match self {
            SampleAccess::Borrowed => "borrowed".to_owned(),
            SampleAccess::Copies(why) => format!("copies: {why}"),
        }
    }
}

/// What an extractor promises, for any finite samples none of which equals the iso-value
/// exactly. A promise not made is not a defect: it is a property the extractor does not have
/// (its module's **Non-guarantees** say why), and the report counts it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Guarantees {
    /// It meshes cubic grids; otherwise it refuses them with [`ExtractError::UnsupportedLattice`].
    pub cubic: bool,
    /// It meshes BCC lattices; otherwise it refuses them.
    pub bcc: bool,
    /// Closed wherever the surface stays inside the lattice: every edge in exactly two triangles.
    pub closed: bool,
    /// Edge- and vertex-manifold, no unused vertex.
    pub manifold: bool,
    /// Consistently wound with normals toward increasing `f` (a closed surface has positive
    /// volume).
    pub outward: bool,
    /// No two triangles meet except at the vertices and edges they share.
    pub intersection_free: bool,
    /// On a cubic grid, the surface in every cell has the topology (components and Euler
    /// characteristic) of the level set of the cell's trilinear interpolant: ambiguous faces and
    /// tunnels through the cell as the interpolant has them (marching cubes 33).
    pub trilinear_topology: bool,
    /// Every part of the inside that holds a sample gives a surface (where the field changes sign
    /// inside the lattice, the output is not empty). An extractor that snaps lattice vertices onto
    /// the surface can lose parts thinner than its snapping distance.
    pub keeps_small_parts: bool,
    /// Tetrahedra (volume extractors): every dihedral angle within this interval and none
    /// inverted, with its default options (`None`: no bound promised; the module doc says what
    /// holds the bound: a proof, or an exhaustive test of its cases).
    pub dihedral: Option<DihedralInterval>,
}

/// A closed interval of dihedral angles, in degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DihedralInterval {
    /// Smallest angle allowed.
    pub min_degrees: f64,
    /// Largest angle allowed.
    pub max_degrees: f64,
}

impl DihedralInterval {
    /// Whether `degrees` lies in the interval.
    pub fn contains(&self, degrees: f64) -> bool {
        (self.min_degrees..=self.max_degrees).contains(&degrees)
    }
}

impl Guarantees {
    /// Lattices it meshes, as the CLI spells them.
    pub fn lattices(&self) -> Vec<&'static str> {
        [("cubic", self.cubic), ("bcc", self.bcc)].into_iter().filter(|(_, ok)| *ok).map(|(name, _)| name).collect()
    }
}

/// How to build a post-process: [`ExtractorInfo`]'s counterpart (`pub const INFO` in its file,
/// listed in [`crate::post::POST_INFOS`]).
pub struct PostInfo {
    /// Stable kebab-case name (the CLI's `--post NAME` or `--post NAME:OPTION=VALUE,...`).
    pub name: &'static str,
    /// One line saying what it does.
    pub description: &'static str,
    /// The options it takes.
    pub options: &'static [&'static str],
    /// Builds it; unknown or bad options are errors naming the option.
    pub make: fn(&crate::options::Options) -> Result<Box<dyn PostProcess>, crate::options::OptionError>,
    /// What it keeps of its input, with its default options (checked by `tests/tests/contract.rs`).
    pub guarantees: PostGuarantees,
}

/// What a post-process promises to keep of a closed, manifold, outward surface with no
/// self-intersection, as data (the extractors' [`Guarantees`] for post-processes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PostGuarantees {
    /// The output is closed and manifold, each component with its Euler characteristic in the
    /// input (the whole's too when it also keeps every component).
    pub keeps_closed_manifold: bool,
    /// Triangles keep facing the way they faced (an outward input stays outward).
    pub keeps_outward: bool,
    /// No two triangles come to meet that did not meet in the input.
    pub adds_no_intersection: bool,
    /// Every connected component of the input is kept (so a closed manifold keeps its Euler
    /// characteristic, not only each kept component's).
    pub keeps_every_component: bool,
}

/// An isosurface or volume extractor. Dyn-compatible: experiments iterate over
/// [`crate::extractors::registry`].
pub trait Extractor: Send + Sync {
    /// Its registry entry (the `INFO` its file defines): the one place its name, description,
    /// options and guarantees are written.
    fn info(&self) -> &'static ExtractorInfo;

    /// Stable kebab-case name used by the CLI, the registry and the report (its `INFO`'s).
    fn name(&self) -> &'static str {
        self.info().name
    }

    /// One line saying what it does (its `INFO`'s).
    fn description(&self) -> &'static str {
        self.info().description
    }

    /// Whether its main output is a tetrahedral volume (whose boundary is the surface) rather
    /// than an isosurface: experiments about isosurface accuracy leave such extractors out.
    fn produces_volume(&self) -> bool {
        false
    }

    /// How [`crate::chunks`] can mesh a volume in chunks with it.
    fn chunking(&self) -> Chunking {
        Chunking::Unsupported
    }

    /// The options that shape its output as it was built (smoothing and its iterations, vertex
    /// placement, the ambiguous-face rule), in words for the report's tables; empty when it has
    /// none.
    fn settings(&self) -> String {
        String::new()
    }

    /// How [`crate::chunks::lod`] makes its chunks at different levels of detail meet.
    fn levels_of_detail(&self) -> LevelsOfDetail<'_> {
        LevelsOfDetail::Unsupported("its seams between levels of detail are not stitched")
    }

    /// The algorithm's own work: fills `out`, which arrives cleared (capacity kept) with its
    /// sampling time set, from samples on a lattice its guarantees declare; fills the stage times
    /// it has (`vertex`, `geometry`, `smoothing`, `normals`) and returns the bytes of scratch it
    /// holds between calls. [`Extractor::extract`] does the rest.
    fn extract_into(&self, samples: &Samples, out: &mut Extraction) -> Result<usize, ExtractError>;

    /// Extracts from `samples` into `out`: the bookkeeping every extractor shares around its
    /// [`Extractor::extract_into`] (clear the output keeping capacity, copy the sampling time,
    /// refuse a lattice its `INFO`'s guarantees do not declare, convert and check borrowed
    /// samples for an extractor that [`SampleAccess::Copies`] them, and fill the counts and
    /// buffer sizes with [`Extraction::finish_counts`]).
    fn extract(&self, samples: &Samples, out: &mut Extraction) -> Result<(), ExtractError> {
        out.clear();
        out.stats.times.sampling = samples.sampling_time();
        let guarantees = &self.info().guarantees;
        let declared = match samples.lattice() {
            crate::lattice::Lattice::Cubic(_) => guarantees.cubic,
            crate::lattice::Lattice::Bcc(_) => guarantees.bcc,
        };
        if !declared {
            return Err(ExtractError::UnsupportedLattice {
                algorithm: self.name(),
                lattice: samples.lattice().kind(),
                supported: if guarantees.cubic { "cubic" } else { "bcc" },
            });
        }
        if samples.is_borrowed() && self.info().samples != SampleAccess::Borrowed {
            samples.check_converted()?;
        }
        let scratch = self.extract_into(samples, out)?;
        out.finish_counts(scratch);
        Ok(())
    }
}

/// A mesh-to-mesh filter that composes with any extractor (edge collapse, relaxation, ...).
/// Implementations add their wall time to `stats.times.post`.
pub trait PostProcess: Send + Sync {
    /// Stable kebab-case name (the CLI's `--post` value).
    fn name(&self) -> &'static str;

    /// One line saying what it does.
    fn description(&self) -> &'static str;

    /// Rewrites `out` in place.
    fn apply(&self, samples: &Samples, out: &mut Extraction) -> Result<(), ExtractError>;
}
