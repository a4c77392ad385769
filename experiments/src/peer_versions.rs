//! Which version of each peer an experiment ran, the library apart from the wrapper that reaches
//! it: VTK 9.7.2 through the `vtk` wheel, MeshLab 2025.07 through `pymeshlab`, TetGen through the
//! `tetgen` bindings (which do not say which TetGen). [`PEERS`] lists every peer the report runs
//! and where its version is read:
//! - Python packages, from the reference environment (`tests/reference/.venv`) by
//!   `src/peers/versions.py`, which also asks the wrappers that say so for their library's version;
//! - Rust crates, from `Cargo.lock` at build time (`build.rs`), and the C library `meshopt` wraps
//!   from its vendored header;
//! - the C++ libraries the decimators link, from Debian's package database (`dpkg-query`).
//!
//! An experiment names its peers ([`Experiment::peers`](crate::experiment::Experiment::peers));
//! its data files record them in their provenance, and its page states them under its title.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::process::Command;
use std::sync::OnceLock;

/// Where a peer comes from, and so where its versions are read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    /// A Python distribution (its pip name) in the reference environment.
    Python(&'static str),
    /// A Rust crate the experiments link.
    Crate(&'static str),
    /// A Debian package (the C++ decimators link it).
    Debian(&'static str),
}

/// The library behind a peer, as far as its wrapper says.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Library {
    /// The package is the library (scikit-image, zmesh, a crate): one version.
    IsThePackage,
    /// A wrapper that says which version of `name` it wraps.
    Wrapped(&'static str),
    /// A wrapper that bundles `name` and does not say which version.
    Unsaid(&'static str),
}

/// One peer the report runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Peer {
    /// The name experiments use for it.
    pub name: &'static str,
    /// Where it comes from.
    pub source: Source,
    /// The library behind it.
    pub library: Library,
}

const fn py(name: &'static str, dist: &'static str, library: Library) -> Peer {
    Peer { name, source: Source::Python(dist), library }
}

const fn rust(name: &'static str, krate: &'static str, library: Library) -> Peer {
    Peer { name, source: Source::Crate(krate), library }
}

use Library::{IsThePackage as Same, Unsaid, Wrapped};

/// Every peer the report runs, and the packages around them a run depends on.
pub const PEERS: &[Peer] = &[
    py("VTK", "vtk", Wrapped("VTK")),
    py("scikit-image", "scikit-image", Same),
    py("PyMCubes", "PyMCubes", Same),
    py("libigl", "libigl", Unsaid("libigl")),
    py("pymeshlab", "pymeshlab", Wrapped("MeshLab")),
    py("CGAL (Python)", "cgal", Wrapped("CGAL")),
    py("TetGen", "tetgen", Unsaid("TetGen")),
    py("NETGEN", "netgen-mesher", Same),
    py("fTetWild", "pytetwild", Unsaid("fTetWild")),
    py("zmesh", "zmesh", Same),
    py("meshlib", "meshlib", Same),
    py("marching-cubes-numpy", "marching-cubes-numpy", Same),
    py("warp", "warp-lang", Same),
    py("igneous", "igneous_pipeline", Same),
    py("cloud-volume", "cloud_volume", Same),
    py("DracoPy", "DracoPy", Unsaid("Draco")),
    py("neuroglancer", "neuroglancer", Same),
    py("dask", "dask", Same),
    py("distributed", "distributed", Same),
    py("zarr", "zarr", Same),
    py("numpy", "numpy", Same),
    py("nibabel", "nibabel", Same),
    py("nilearn", "nilearn", Same),
    rust("fast-surface-nets", "fast-surface-nets", Same),
    rust("isosurface crate", "isosurface", Same),
    rust("transvoxel", "transvoxel", Same),
    rust("meshopt", "meshopt", Wrapped("meshoptimizer")),
    rust("ferreus_rmt", "ferreus_rmt", Same),
    Peer { name: "CGAL (C++)", source: Source::Debian("libcgal-dev"), library: Same },
    Peer { name: "OpenMesh", source: Source::Debian("libopenmesh-dev"), library: Same },
];

/// The peer called `name`.
pub fn peer(name: &str) -> Option<&'static Peer> {
    PEERS.iter().find(|p| p.name == name)
}

/// A peer's versions as a data file records them.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PeerVersion {
    /// The peer's name in [`PEERS`].
    pub name: String,
    /// The package (pip distribution, crate or Debian package) and its version, `null` when it
    /// is not installed.
    pub package: String,
    /// The package's version.
    pub package_version: Option<String>,
    /// The library behind it.
    pub library: String,
    /// The library's version, `null` when the wrapper does not say (or the peer is missing).
    pub library_version: Option<String>,
}

impl PeerVersion {
    /// `VTK 9.7.2 (package vtk 9.7.2)`, `libigl (version not said by package libigl 2.6.1)`,
    /// `scikit-image 0.26.0`, `TetGen (not installed)`.
    pub fn describe(&self) -> String {
        let Some(package_version) = &self.package_version else {
            return format!("{} (not installed)", self.name);
        };
        let library = match &self.library_version {
            Some(v) => format!("{} {v}", self.library),
            None => format!("{} (version not said", self.library),
        };
        if self.library == self.package && self.library_version.as_ref() == Some(package_version) {
            return library;
        }
        if self.library_version.is_none() {
            format!("{library} by package {} {package_version})", self.package)
        } else {
            format!("{library} (package {} {package_version})", self.package)
        }
    }
}

/// The versions of the peers `names` (unknown names are left out; [`unknown`] finds them).
pub fn versions_of(names: &[&str]) -> Vec<PeerVersion> {
    let found = all_versions();
    names.iter().filter_map(|n| found.iter().find(|v| v.name == *n).cloned()).collect()
}

/// The names among `names` that [`PEERS`] does not list.
pub fn unknown<'a>(names: &[&'a str]) -> Vec<&'a str> {
    names.iter().copied().filter(|n| peer(n).is_none()).collect()
}

/// Every peer's versions, read once per process.
fn all_versions() -> &'static [PeerVersion] {
    static ALL: OnceLock<Vec<PeerVersion>> = OnceLock::new();
    ALL.get_or_init(|| {
        let python = python_versions();
        let crates = crate_versions(env!("ISOLAB_PEER_CRATES"));
        PEERS.iter().map(|p| version(p, &python, &crates)).collect()
    })
}

/// One peer's entry from what was read.
fn version(p: &Peer, python: &BTreeMap<String, Found>, crates: &BTreeMap<String, String>) -> PeerVersion {
    let (package, found) = match p.source {
        Source::Python(dist) => (dist, python.get(dist).cloned().unwrap_or_default()),
        Source::Crate(krate) => (krate, Found { package: crates.get(krate).cloned(), library: crate_library(krate) }),
        Source::Debian(pkg) => (pkg, Found { package: debian_version(pkg), library: None }),
    };
    let (library, library_version) = match p.library {
        Library::IsThePackage => (package, found.package.clone()),
        Library::Wrapped(name) => (name, found.library),
        Library::Unsaid(name) => (name, None),
    };
    PeerVersion {
        name: p.name.to_owned(),
        package: package.to_owned(),
        package_version: found.package,
        library: library.to_owned(),
        library_version,
    }
}

/// What `versions.py` says of one distribution.
#[derive(Debug, Clone, Default, Deserialize)]
struct Found {
    package: Option<String>,
    library: Option<String>,
}

/// The library version a crate's build recorded (meshopt's meshoptimizer).
fn crate_library(krate: &str) -> Option<String> {
    let v = env!("ISOLAB_MESHOPTIMIZER_VERSION");
    (krate == "meshopt" && !v.is_empty()).then(|| v.to_owned())
}

/// `name=version;name=version` (what `build.rs` records) as a map.
fn crate_versions(recorded: &str) -> BTreeMap<String, String> {
    recorded.split(';').filter_map(|kv| kv.split_once('=')).map(|(k, v)| (k.to_owned(), v.to_owned())).collect()
}

/// The Python peers' versions from `versions.py` in the reference environment (empty when it is
/// missing or fails: every Python peer then reads as not installed).
fn python_versions() -> BTreeMap<String, Found> {
    let root = crate::provenance::root();
    let python = root.join("tests/reference/.venv/bin/python");
    if !python.exists() {
        return BTreeMap::new();
    }
    let dists: Vec<&str> = PEERS
        .iter()
        .filter_map(|p| match p.source {
            Source::Python(d) => Some(d),
            _ => None,
        })
        .collect();
    ask_python(&python, &dists)
}

/// What `versions.py`, run by `python`, says of the distributions `dists`.
fn ask_python(python: &std::path::Path, dists: &[&str]) -> BTreeMap<String, Found> {
    ask_python_in(python, dists, None)
}

/// [`ask_python`] with `path` first on Python's `sys.path` (`PYTHONPATH`), if given.
fn ask_python_in(python: &std::path::Path, dists: &[&str], path: Option<&std::path::Path>) -> BTreeMap<String, Found> {
    let script = crate::provenance::root().join("experiments/src/peers/versions.py");
    let mut command = Command::new(python);
    if let Some(p) = path {
        command.env("PYTHONPATH", p);
    }
    command
        .arg(script)
        .args(dists)
        .output()
        .ok()
        .filter(|o| o.status.success())
        .and_then(|o| serde_json::from_slice(&o.stdout).ok())
        .unwrap_or_default()
}

/// A Debian package's installed version (`dpkg-query`), if any.
fn debian_version(package: &str) -> Option<String> {
    let out = Command::new("dpkg-query").args(["-W", "-f=${Version}", package]).output().ok()?;
    let v = String::from_utf8_lossy(&out.stdout).trim().to_owned();
    (out.status.success() && !v.is_empty()).then_some(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entry(name: &str, package: &str, pv: Option<&str>, library: &str, lv: Option<&str>) -> PeerVersion {
        PeerVersion {
            name: name.into(),
            package: package.into(),
            package_version: pv.map(Into::into),
            library: library.into(),
            library_version: lv.map(Into::into),
        }
    }

    #[test]
    fn the_library_and_its_wrapper_are_told_apart() {
        assert_eq!(entry("VTK", "vtk", Some("9.7.2"), "VTK", Some("9.7.2")).describe(), "VTK 9.7.2 (package vtk 9.7.2)");
        assert_eq!(
            entry("libigl", "libigl", Some("2.6.1"), "libigl", None).describe(),
            "libigl (version not said by package libigl 2.6.1)"
        );
        assert_eq!(
            entry("scikit-image", "scikit-image", Some("0.26.0"), "scikit-image", Some("0.26.0")).describe(),
            "scikit-image 0.26.0"
        );
        assert_eq!(entry("TetGen", "tetgen", None, "TetGen", None).describe(), "TetGen (not installed)");
    }

    #[test]
    fn a_peer_is_read_from_its_source() {
        let mut python = BTreeMap::new();
        python.insert("pymeshlab".to_owned(), Found { package: Some("2025.7.post1".into()), library: Some("2025.07d".into()) });
        python.insert("tetgen".to_owned(), Found { package: Some("0.8.4".into()), library: None });
        let crates = crate_versions("fast-surface-nets=0.2.1;isosurface=0.0.4");
        let v = version(peer("pymeshlab").unwrap(), &python, &crates);
        assert_eq!((v.library.as_str(), v.library_version.as_deref()), ("MeshLab", Some("2025.07d")));
        assert_eq!(v.package_version.as_deref(), Some("2025.7.post1"));
        let v = version(peer("TetGen").unwrap(), &python, &crates);
        assert_eq!((v.package_version.as_deref(), v.library_version), (Some("0.8.4"), None));
        let v = version(peer("isosurface crate").unwrap(), &python, &crates);
        assert_eq!((v.package.as_str(), v.library_version.as_deref()), ("isosurface", Some("0.0.4")));
        let v = version(peer("VTK").unwrap(), &python, &crates);
        assert_eq!(v.package_version, None, "a peer the environment lacks reads as not installed");
    }

    #[test]
    fn the_script_answers_for_installed_and_missing_packages() {
        // A distribution made for the test (its metadata alone) on the system Python's path.
        let dir = tempfile::tempdir().unwrap();
        let info = dir.path().join("isolab_probe-1.2.3.dist-info");
        std::fs::create_dir(&info).unwrap();
        std::fs::write(info.join("METADATA"), "Metadata-Version: 2.1\nName: isolab-probe\nVersion: 1.2.3\n").unwrap();
        let found = ask_python_in(std::path::Path::new("python3"), &["isolab-probe", "isolab-no-such-package"], Some(dir.path()));
        assert_eq!(found["isolab-probe"].package.as_deref(), Some("1.2.3"));
        assert_eq!(found["isolab-probe"].library, None, "it has no library probe");
        assert_eq!(found["isolab-no-such-package"].package, None);
    }

    #[test]
    fn the_build_recorded_every_peer_crate() {
        let crates = crate_versions(env!("ISOLAB_PEER_CRATES"));
        for p in PEERS {
            if let Source::Crate(k) = p.source {
                assert!(crates.contains_key(k), "Cargo.lock gave no version of {k}: {crates:?}");
            }
        }
    }

    #[test]
    fn every_experiment_names_known_peers_once() {
        assert_eq!(crate::report::first_seen(PEERS.iter().map(|p| p.name)).len(), PEERS.len());
        for e in crate::experiment::all() {
            assert_eq!(unknown(e.peers()), Vec::<&str>::new(), "{} names a peer PEERS lacks", e.name());
            assert_eq!(crate::report::first_seen(e.peers().iter().copied()).len(), e.peers().len(), "{}", e.name());
        }
    }
}
