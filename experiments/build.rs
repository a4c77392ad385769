//! Records what each data file's provenance names but the running binary cannot ask: the rustc
//! that builds the experiments, and the versions of the peer crates they link (from the
//! workspace's `Cargo.lock`; the C library `meshopt` wraps, from its vendored header).

use std::path::{Path, PathBuf};

/// The peer crates whose versions the provenance records (`experiments::peer_versions` names
/// them by these crate names).
const PEER_CRATES: [&str; 5] = ["fast-surface-nets", "isosurface", "transvoxel", "meshopt", "ferreus_rmt"];

fn main() {
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let version = std::process::Command::new(rustc)
        .arg("--version")
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_owned())
        .unwrap_or_else(|| "rustc (unknown version)".into());
    println!("cargo:rustc-env=ISOLAB_RUSTC_VERSION={version}");
    println!("cargo:rerun-if-env-changed=RUSTC");

    let lock = Path::new(&std::env::var("CARGO_MANIFEST_DIR").unwrap_or_default()).join("../Cargo.lock");
    println!("cargo:rerun-if-changed={}", lock.display());
    let text = std::fs::read_to_string(&lock).unwrap_or_default();
    let crates: Vec<String> =
        PEER_CRATES.iter().filter_map(|name| locked_version(&text, name).map(|v| format!("{name}={v}"))).collect();
    println!("cargo:rustc-env=ISOLAB_PEER_CRATES={}", crates.join(";"));
    let meshoptimizer = locked_version(&text, "meshopt").and_then(|v| meshoptimizer_version(&v)).unwrap_or_default();
    println!("cargo:rustc-env=ISOLAB_MESHOPTIMIZER_VERSION={meshoptimizer}");
}

/// The version `Cargo.lock` gives the package `name` (its first entry).
fn locked_version(lock: &str, name: &str) -> Option<String> {
    let mut lines = lock.lines();
    while let Some(line) = lines.next() {
        if line.trim() == format!("name = \"{name}\"") {
            let next = lines.next()?;
            return next.trim().strip_prefix("version = \"")?.strip_suffix('"').map(str::to_owned);
        }
    }
    None
}

/// `MESHOPTIMIZER_VERSION` of the header vendored in cargo's unpacked `meshopt-<crate_version>`
/// (`1030` is 1.3), as `major.minor`.
fn meshoptimizer_version(crate_version: &str) -> Option<String> {
    let home = std::env::var_os("CARGO_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cargo")))?;
    let registries = std::fs::read_dir(home.join("registry/src")).ok()?;
    for registry in registries.flatten() {
        let header = registry.path().join(format!("meshopt-{crate_version}/vendor/src/meshoptimizer.h"));
        let Ok(text) = std::fs::read_to_string(&header) else { continue };
        println!("cargo:rerun-if-changed={}", header.display());
        let number: u32 = text
            .lines()
            .find_map(|l| l.trim().strip_prefix("#define MESHOPTIMIZER_VERSION"))?
            .split_whitespace()
            .next()?
            .parse()
            .ok()?;
        return Some(format!("{}.{}", number / 1000, number % 1000 / 10));
    }
    None
}
