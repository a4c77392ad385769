//! The extractor and post-process registries: one line per algorithm.
//!
//! Adding an algorithm: write `extractors/<name>.rs` with a type implementing
//! [`Extractor`](crate::Extractor) (module doc: paper, summary, guarantees, costs) and a
//! `from_options` constructor, declare the module below, and add one line to [`INFOS`].

pub mod bcc_sculpt;
pub mod dual;
pub mod dual_contouring;
pub mod marching_cubes;
pub mod marching_tetrahedra;
pub mod regularised_marching_tetrahedra;
pub mod surface_nets;

pub use bcc_sculpt::BccSculpt;
pub use dual_contouring::DualContouring;
pub use marching_cubes::MarchingCubes;
pub use marching_tetrahedra::MarchingTetrahedra;
pub use regularised_marching_tetrahedra::RegularisedMarchingTetrahedra;
pub use surface_nets::SurfaceNets;

use crate::extract::{Extractor, PostProcess};
use crate::options::{OptionError, Options};
use crate::post::edge_collapse;

/// How to build an extractor: its name, one line, and a constructor from options.
pub struct ExtractorInfo {
    /// Stable kebab-case name.
    pub name: &'static str,
    /// One line saying what it does.
    pub description: &'static str,
    /// The options it takes (`--set NAME=VALUE`).
    pub options: &'static [&'static str],
    /// Builds it; unknown or bad options are errors naming the option.
    pub make: fn(&Options) -> Result<Box<dyn Extractor>, OptionError>,
}

/// Every extractor, in the order the report lists them.
pub const INFOS: &[ExtractorInfo] = &[
    // Lorensen & Cline 1987: the 256-case cube table, one vertex per crossing edge.
    ExtractorInfo {
        name: "marching-cubes",
        description: marching_cubes::DESCRIPTION,
        options: marching_cubes::OPTION_NAMES,
        make: marching_cubes::from_options,
    },
    // Nielson & Hamann 1991: marching cubes whose ambiguous faces follow the trilinear interpolant.
    ExtractorInfo {
        name: "marching-cubes-decider",
        description: marching_cubes::DECIDER_DESCRIPTION,
        options: marching_cubes::OPTION_NAMES,
        make: marching_cubes::decider_from_options,
    },
    // Gibson 1998: one vertex per surface cell, quads across crossing edges, constrained smoothing.
    ExtractorInfo {
        name: "surface-nets",
        description: surface_nets::DESCRIPTION,
        options: surface_nets::OPTION_NAMES,
        make: surface_nets::from_options,
    },
    // Ju et al. 2002: the dual structure with vertices at the minimum of the quadric error.
    ExtractorInfo {
        name: "dual-contouring",
        description: dual_contouring::DESCRIPTION,
        options: dual_contouring::OPTION_NAMES,
        make: dual_contouring::from_options,
    },
    // Payne & Toga 1990: the 16-case tetrahedron table on a BCC lattice or Kuhn-split cubes.
    ExtractorInfo {
        name: "marching-tetrahedra",
        description: marching_tetrahedra::DESCRIPTION,
        options: marching_tetrahedra::OPTION_NAMES,
        make: marching_tetrahedra::from_options,
    },
    // Treece et al. 1999 / Costen 2026: marching tetrahedra with integrated vertex clustering.
    ExtractorInfo {
        name: "regularised-marching-tetrahedra",
        description: regularised_marching_tetrahedra::DESCRIPTION,
        options: regularised_marching_tetrahedra::OPTION_NAMES,
        make: regularised_marching_tetrahedra::from_options,
    },
    // Stuart et al. 2013: BCC lattice sculpted to the surface, snowflakes, ODT relaxation (volume).
    ExtractorInfo {
        name: "bcc-sculpt",
        description: bcc_sculpt::DESCRIPTION,
        options: bcc_sculpt::OPTION_NAMES,
        make: bcc_sculpt::from_options,
    },
];

/// Every extractor, built from its default options.
pub fn registry() -> Vec<Box<dyn Extractor>> {
    INFOS.iter().filter_map(|i| (i.make)(&Options::new()).ok()).collect()
}

/// How to build a post-process: its name, one line, and a constructor from options.
pub struct PostInfo {
    /// Stable kebab-case name (the CLI's `--post NAME` or `--post NAME:OPTION=VALUE,...`).
    pub name: &'static str,
    /// One line saying what it does.
    pub description: &'static str,
    /// The options it takes.
    pub options: &'static [&'static str],
    /// Builds it; unknown or bad options are errors naming the option.
    pub make: fn(&Options) -> Result<Box<dyn PostProcess>, OptionError>,
}

/// Every post-process, one line each.
pub const POST_INFOS: &[PostInfo] = &[
    // Costen 2026, section 2.6: merge short edges in one sweep, drop degenerate triangles.
    PostInfo {
        name: "edge-collapse",
        description: edge_collapse::PAPER_DESCRIPTION,
        options: edge_collapse::PAPER_OPTION_NAMES,
        make: edge_collapse::paper_from_options,
    },
    // Shortest-first collapse under the link condition and a normal test.
    PostInfo {
        name: "edge-collapse-safe",
        description: edge_collapse::SAFE_DESCRIPTION,
        options: edge_collapse::SAFE_OPTION_NAMES,
        make: edge_collapse::safe_from_options,
    },
];

/// Every post-process with default options.
pub fn post_processes() -> Vec<Box<dyn PostProcess>> {
    POST_INFOS.iter().filter_map(|i| (i.make)(&Options::new()).ok()).collect()
}

/// The post-process a CLI spec names: `NAME` or `NAME:OPTION=VALUE,OPTION=VALUE`. `Ok(None)` when
/// no post-process has that name; a malformed option list is an error naming it.
pub fn build_post(spec: &str) -> Result<Option<Box<dyn PostProcess>>, OptionError> {
    let (name, list) = spec.split_once(':').unwrap_or((spec, ""));
    let Some(info) = POST_INFOS.iter().find(|i| i.name == name.trim()) else { return Ok(None) };
    let mut options = Options::new();
    for item in list.split(',').filter(|s| !s.trim().is_empty()) {
        let (k, v) = item.split_once('=').ok_or_else(|| OptionError::BadValue {
            algorithm: info.name,
            option: item.trim().to_owned(),
            value: String::new(),
            reason: "options are written OPTION=VALUE".into(),
        })?;
        options.set(k.trim(), v.trim());
    }
    (info.make)(&options).map(Some)
}

/// The extractor called `name` with default options, or `None`.
pub fn by_name(name: &str) -> Option<Box<dyn Extractor>> {
    build(name, &Options::new()).ok().flatten()
}

/// The extractor called `name` built with `options`: `Ok(None)` when no extractor has that name.
pub fn build(name: &str, options: &Options) -> Result<Option<Box<dyn Extractor>>, OptionError> {
    INFOS.iter().find(|i| i.name == name).map(|i| (i.make)(options)).transpose()
}

/// The post-process called `name` with default options, or `None`.
pub fn post_by_name(name: &str) -> Option<Box<dyn PostProcess>> {
    build_post(name).ok().flatten()
}

/// Comma-separated names of all extractors (for error messages).
pub fn names() -> String {
    INFOS.iter().map(|e| e.name).collect::<Vec<_>>().join(", ")
}

/// Comma-separated names of all post-processes (for error messages).
pub fn post_names() -> String {
    post_processes().iter().map(|e| e.name()).collect::<Vec<_>>().join(", ")
}
