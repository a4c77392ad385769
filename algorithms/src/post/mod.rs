//! Post-processes: mesh-to-mesh filters usable after any surface extractor, and their registry
//! ([`POST_INFOS`]: one line each, as [`crate::extractors::INFOS`] for the extractors).

pub mod components;
pub mod edge_collapse;
pub mod triangle_grid;

pub use edge_collapse::EdgeCollapse;

use crate::extract::{PostInfo, PostProcess};
use crate::options::{OptionError, Options};

/// Every post-process, one line each.
pub const POST_INFOS: &[PostInfo] = &[edge_collapse::PAPER_INFO, edge_collapse::SAFE_INFO, components::INFO];

/// Every post-process with default options (tested to build, as [`crate::extractors::registry`]).
pub fn post_processes() -> Vec<Box<dyn PostProcess>> {
    POST_INFOS
        .iter()
        .map(|i| (i.make)(&Options::new()).unwrap_or_else(|e| panic!("{}'s default options fail: {e}", i.name)))
        .collect()
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

/// Comma-separated names of all post-processes (for error messages).
pub fn post_names() -> String {
    post_processes().iter().map(|e| e.name()).collect::<Vec<_>>().join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_entry_builds_with_defaults_and_reports_its_registered_name() {
        let mut names = std::collections::HashSet::new();
        for info in POST_INFOS {
            let p = (info.make)(&Options::new()).unwrap_or_else(|err| panic!("{}: {err}", info.name));
            assert_eq!(p.name(), info.name);
            assert!(names.insert(info.name), "{} is registered twice", info.name);
        }
        // The list builds every entry, in the table's order.
        assert!(
            post_processes().iter().map(|p| p.name()).eq(POST_INFOS.iter().map(|i| i.name)),
            "post_processes() is not POST_INFOS in order"
        );
    }
}
