//! The extractor and post-process registries: one line per algorithm.
//!
//! Adding an algorithm: write `extractors/<name>.rs` with a type implementing
//! [`Extractor`] (module doc: paper, summary, guarantees, costs), a
//! `from_options` constructor and `pub const INFO: ExtractorInfo` (its name, written once there);
//! declare the module below and add `<name>::INFO,` to [`INFOS`]. The tests below check that every
//! entry builds with its default options and reports the name it is registered under.

pub mod bcc_sculpt;
pub mod dual;
pub mod dual_contouring;
pub mod isosurface_stuffing;
pub mod marching_cubes;
pub mod marching_tetrahedra;
pub mod regularised_marching_tetrahedra;
pub mod surface_nets;
pub mod tetrahedral;

pub use bcc_sculpt::BccSculpt;
pub use dual_contouring::{DualContouring, ManifoldDualContouring};
pub use isosurface_stuffing::IsosurfaceStuffing;
pub use marching_cubes::MarchingCubes;
pub use marching_tetrahedra::MarchingTetrahedra;
pub use regularised_marching_tetrahedra::RegularisedMarchingTetrahedra;
pub use surface_nets::SurfaceNets;

/// Manifold dual contouring's former path: the mode now lives in [`dual_contouring`] (kept so
/// that code naming this module still builds).
pub mod manifold_dual_contouring {
    pub use super::dual_contouring::{
        manifold_from_options as from_options, ManifoldDualContouring, MdcOptions, MANIFOLD_DESCRIPTION as DESCRIPTION,
        MANIFOLD_INFO as INFO, MANIFOLD_OPTION_NAMES as OPTION_NAMES,
    };
}

pub use crate::extract::{DihedralInterval, ExtractorInfo, Guarantees, PostInfo};

use crate::extract::Extractor;
use crate::options::{OptionError, Options};

/// Every extractor, in the order the report lists them: one line each (the paper is in each
/// `INFO`'s doc and its module's).
pub const INFOS: &[ExtractorInfo] = &[
    marching_cubes::INFO,
    marching_cubes::DECIDER_INFO,
    marching_cubes::MC33_INFO,
    surface_nets::INFO,
    dual_contouring::INFO,
    dual_contouring::MANIFOLD_INFO,
    marching_tetrahedra::INFO,
    regularised_marching_tetrahedra::INFO,
    bcc_sculpt::INFO,
    isosurface_stuffing::INFO,
];

/// Every extractor, built from its default options (which every registered extractor accepts:
/// tested, so a failure here is a bug in the registry, not in the user's input).
pub fn registry() -> Vec<Box<dyn Extractor>> {
    INFOS.iter().map(|i| (i.make)(&Options::new()).unwrap_or_else(|e| panic!("{}'s default options fail: {e}", i.name))).collect()
}

/// The extractor called `name` with default options, or `None`.
pub fn by_name(name: &str) -> Option<Box<dyn Extractor>> {
    build(name, &Options::new()).ok().flatten()
}

/// The extractor called `name` built with `options`: `Ok(None)` when no extractor has that name.
pub fn build(name: &str, options: &Options) -> Result<Option<Box<dyn Extractor>>, OptionError> {
    INFOS.iter().find(|i| i.name == name).map(|i| (i.make)(options)).transpose()
}

/// Comma-separated names of all extractors (for error messages).
pub fn names() -> String {
    INFOS.iter().map(|e| e.name).collect::<Vec<_>>().join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_entry_builds_with_defaults_and_reports_its_registered_name() {
        let mut names = std::collections::HashSet::new();
        for info in INFOS {
            let e = (info.make)(&Options::new()).unwrap_or_else(|err| panic!("{}: {err}", info.name));
            assert_eq!(e.name(), info.name);
            assert_eq!(e.description(), info.description, "{}", info.name);
            assert!(names.insert(info.name), "{} is registered twice", info.name);
        }
        for info in crate::post::POST_INFOS {
            assert!(names.insert(info.name), "{} is registered both as an extractor and a post-process", info.name);
        }
        // The registry builds every entry, in the table's order.
        assert!(registry().iter().map(|e| e.name()).eq(INFOS.iter().map(|i| i.name)), "registry() is not INFOS in order");
    }
}
