//! Our command line, `isolab extract`, run as a user runs it: a new process per call, on the very
//! grid file the experiment wrote (`Job::Grid`'s `file`), timed by the `times_ms.extraction` it
//! reports in the JSON it prints (no `-m`, so no mesh metric is computed). One-shot only: a
//! process makes one extraction, on pages the kernel has never handed out, so this is the
//! library's one-shot call as a process's first.
//!
//! Run with the CLI's default, where it re-executes itself with huge pages for malloc (Linux
//! with glibc), or without (`ISOLAB_NO_HUGE_PAGES`), to show what the huge pages change.
//!
//! The binary is built first (`cargo build --release -p isolab-cli --bin isolab`, which
//! does nothing when it is up to date), so the CLI measured is the code the report describes.

use super::{Job, Peer, PeerError, PeerRun, Protocol};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

/// `isolab extract -a ALGORITHM` with `--set` options, one process per run.
pub struct Cli {
    algorithm: &'static str,
    options: Vec<(&'static str, &'static str)>,
    huge_pages: bool,
    /// The built binary, or why there is none.
    binary: Result<PathBuf, String>,
}

impl Cli {
    /// The CLI `binary` ([`build`]'s answer) running `algorithm` with `options` (`name=value`
    /// pairs), with or without its huge pages.
    pub fn new(
        binary: Result<PathBuf, String>,
        algorithm: &'static str,
        options: &[(&'static str, &'static str)],
        huge_pages: bool,
    ) -> Cli {
        Cli { algorithm, options: options.to_vec(), huge_pages, binary }
    }
}

/// Builds the `isolab` binary of the workspace at `root` (once per experiment run, for every
/// [`Cli`] row) and returns its path, or why there is none.
pub fn build(root: &Path) -> Result<PathBuf, String> {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let status = Command::new(cargo)
        .current_dir(root)
        .args(["build", "--release", "--quiet", "-p", "isolab-cli", "--bin", "isolab"])
        .status()
        .map_err(|e| format!("cannot run cargo to build the isolab binary: {e}"))?;
    if !status.success() {
        return Err(format!("building the isolab binary failed ({status})"));
    }
    let target = std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| root.join("target"), PathBuf::from);
    let binary = target.join("release").join("isolab");
    if binary.exists() {
        Ok(binary)
    } else {
        Err(format!("no binary at {} after building it", binary.display()))
    }
}

impl Peer for Cli {
    fn name(&self) -> String {
        let pages = if self.huge_pages { "" } else { ", no huge pages" };
        format!("isolab {} CLI{pages}", self.algorithm)
    }

    fn run(&mut self, job: &Job<'_>, protocol: Protocol) -> Result<PeerRun, PeerError> {
        let Job::Grid { file, threads, .. } = job else { return Err(self.unsupported()) };
        if protocol != Protocol::OneShot {
            return Err(self.unsupported());
        }
        let failed = |message: String| PeerError::Failed { peer: self.name(), message };
        let binary = self.binary.as_ref().map_err(|e| failed(e.clone()))?;
        // No `-m`: the run's JSON (times and counts, no mesh metric) comes on stdout.
        let mut command = Command::new(binary);
        command.args(["extract", "-a", self.algorithm, "-f"]).arg(file);
        for (k, v) in &self.options {
            command.arg("--set").arg(format!("{k}={v}"));
        }
        if *threads <= 1 {
            command.args(["--set", "parallelism=serial"]);
        }
        command.env("RAYON_NUM_THREADS", (*threads).max(1).to_string()).env_remove("GLIBC_TUNABLES");
        if self.huge_pages {
            command.env_remove("ISOLAB_NO_HUGE_PAGES");
        } else {
            command.env("ISOLAB_NO_HUGE_PAGES", "1");
        }
        let output = command.output().map_err(|e| failed(format!("cannot run {}: {e}", binary.display())))?;
        if !output.status.success() {
            return Err(failed(String::from_utf8_lossy(&output.stderr).trim().to_owned()));
        }
        let json: serde_json::Value =
            serde_json::from_slice(&output.stdout).map_err(|e| failed(format!("its JSON on stdout: {e}")))?;
        let count = |key: &str| json[key].as_u64().map(|n| n as usize);
        let ms = json["times_ms"]["extraction"].as_f64();
        let (Some(ms), Some(vertices), Some(triangles)) = (ms, count("vertices"), count("triangles")) else {
            return Err(failed("its JSON lacks times_ms.extraction, vertices or triangles".into()));
        };
        Ok(PeerRun { time: Duration::from_secs_f64(ms / 1e3), vertices, triangles, ..PeerRun::default() })
    }
}
