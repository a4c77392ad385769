//! Where, when and on what each data file was made. After an experiment runs, every data file it
//! wrote gets a `provenance` entry ([`stamp`]): the commit and whether the tree had changes
//! outside `report/` and `README.md` (which runs write), the date, the CPU, cores, memory, OS, the rustc that built the binary,
//! the Python of the reference environment, isolab's version, the command that regenerates it,
//! and a digest of the experiment's own source files. Pages state it under their title
//! ([`line()`]); the front page lists each page's commit and flags data whose experiment code
//! changed since it was made ([`code_since`]: the digest recomputed from the tree, so no git
//! history is needed to check it).

use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{SystemTime, UNIX_EPOCH};

/// One run's provenance, as recorded in its data files.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Provenance {
    /// The experiment that wrote the file.
    pub experiment: String,
    /// `git rev-parse HEAD` when the run started (`unknown` outside a git checkout).
    pub commit: String,
    /// Whether the tree had uncommitted changes outside `report/` and `README.md` when the run started.
    pub dirty: bool,
    /// When the run started, UTC (`YYYY-MM-DDTHH:MM:SSZ`).
    pub date_utc: String,
    /// The run's wall time in seconds.
    pub seconds: f64,
    /// The CPU model (`/proc/cpuinfo`).
    pub cpu: String,
    /// Threads available to the process.
    pub cores: usize,
    /// Total memory in GiB (`/proc/meminfo`).
    pub memory_gib: f64,
    /// The OS (`/etc/os-release`) and kernel.
    pub os: String,
    /// The rustc that built the experiment binary.
    pub rustc: String,
    /// The reference environment's Python (`tests/reference/.venv`), or the system `python3`.
    pub python: String,
    /// isolab's version (the workspace's).
    pub isolab: String,
    /// The command that regenerates the file.
    pub command: String,
    /// FNV-1a digest of the experiment's source files ([`source_digest`]).
    pub source_digest: String,
    /// The versions of the peers the experiment runs, library and wrapper apart
    /// ([`crate::peer_versions`]); empty in data made before they were recorded.
    #[serde(default)]
    pub peers: Vec<crate::peer_versions::PeerVersion>,
    /// Made by `report --quick` (every experiment at its smallest sizes): not the report's data.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub quick: bool,
}

/// The workspace root (the experiments crate's parent), whose sources [`code_since`] digests.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().map(Path::to_path_buf).unwrap_or_default()
}

/// The command that regenerates experiment `name`'s data and page.
pub fn command(name: &str) -> String {
    format!("cargo run --release -p isolab-experiments --bin {name}")
}

impl Provenance {
    /// This machine and `checkout` (read when the run started: [`Checkout::now`]), for a run of
    /// `experiment` (which runs `peers`) that started at `started` and took `seconds`.
    pub fn collect(experiment: &str, peers: &[&str], started: SystemTime, seconds: f64, checkout: Checkout) -> Self {
        let root = root();
        let Checkout { commit, dirty } = checkout;
        let venv = root.join("tests/reference/.venv/bin/python");
        let python =
            command_output(Command::new(if venv.exists() { venv.as_os_str() } else { "python3".as_ref() }).arg("--version"))
                .unwrap_or_else(|| "not found".into());
        Provenance {
            experiment: experiment.to_owned(),
            commit,
            dirty,
            date_utc: utc_date(started.duration_since(UNIX_EPOCH).map(|d| d.as_secs()).unwrap_or(0)),
            seconds: (seconds * 10.0).round() / 10.0,
            cpu: read("/proc/cpuinfo").and_then(|t| cpu_model(&t)).unwrap_or_else(|| "unknown".into()),
            cores: std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1),
            memory_gib: read("/proc/meminfo").and_then(|t| mem_total_gib(&t)).unwrap_or(0.0),
            os: os_name(),
            rustc: env!("ISOLAB_RUSTC_VERSION").to_owned(),
            python,
            isolab: env!("CARGO_PKG_VERSION").to_owned(),
            command: command(experiment),
            source_digest: source_digest(&root, experiment),
            peers: crate::peer_versions::versions_of(peers),
            quick: false,
        }
    }

    /// The commit's first 10 hex digits, with `+changes` for a dirty tree.
    pub fn short_commit(&self) -> String {
        let short: String = self.commit.chars().take(10).collect();
        if self.dirty {
            format!("{short}+changes")
        } else {
            short
        }
    }
}

/// The commit checked out and whether the tree has changes outside `report/` and `README.md`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Checkout {
    /// `git rev-parse HEAD` (`unknown` outside a git checkout).
    pub commit: String,
    /// Uncommitted changes outside `report/` and `README.md` (which runs write).
    pub dirty: bool,
}

impl Checkout {
    /// The checkout now: read before an experiment runs, so edits made while it runs do not
    /// count against code it was built from.
    pub fn now() -> Self {
        let root = root();
        let git = |args: &[&str]| command_output(Command::new("git").arg("-C").arg(&root).args(args));
        Checkout {
            commit: git(&["rev-parse", "HEAD"]).unwrap_or_else(|| "unknown".into()),
            // report/ and README.md's generated parts are what runs write, not what they run.
            dirty: git(&["status", "--porcelain", "--", ".", ":!report", ":!README.md"]).is_some_and(|s| !s.is_empty()),
        }
    }
}

fn read(path: &str) -> Option<String> {
    std::fs::read_to_string(path).ok()
}

fn command_output(cmd: &mut Command) -> Option<String> {
    let out = cmd.output().ok()?;
    out.status.success().then(|| String::from_utf8_lossy(&out.stdout).trim().to_owned())
}

/// The first `model name` of a `/proc/cpuinfo` text.
fn cpu_model(cpuinfo: &str) -> Option<String> {
    cpuinfo
        .lines()
        .find_map(|l| l.strip_prefix("model name"))
        .and_then(|rest| rest.split_once(':'))
        .map(|(_, v)| v.trim().to_owned())
}

/// `MemTotal` of a `/proc/meminfo` text, in GiB to two decimals.
fn mem_total_gib(meminfo: &str) -> Option<f64> {
    let kib: f64 =
        meminfo.lines().find_map(|l| l.strip_prefix("MemTotal:"))?.trim().trim_end_matches("kB").trim().parse().ok()?;
    Some((kib / (1024.0 * 1024.0) * 100.0).round() / 100.0)
}

/// `PRETTY_NAME` of `/etc/os-release` and the kernel release.
fn os_name() -> String {
    let pretty = read("/etc/os-release")
        .and_then(|t| t.lines().find_map(|l| l.strip_prefix("PRETTY_NAME=")).map(|v| v.trim_matches('"').to_owned()))
        .unwrap_or_else(|| std::env::consts::OS.to_owned());
    match read("/proc/sys/kernel/osrelease") {
        Some(k) => format!("{pretty}, kernel {}", k.trim()),
        None => pretty,
    }
}

/// Seconds since the Unix epoch as `YYYY-MM-DDTHH:MM:SSZ` (the proleptic Gregorian calendar;
/// days to civil date after Howard Hinnant's `civil_from_days`).
pub fn utc_date(secs: u64) -> String {
    let days = (secs / 86_400) as i64;
    let rem = secs % 86_400;
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!("{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}Z", rem / 3600, rem % 3600 / 60, rem % 60)
}

/// The experiment's own source files: every file under `experiments/src/experiment/<name>/`
/// (or a single `<name>.rs`, as experiments once were), sorted by path. What running or
/// checking the sources leaves beside them is not source and is skipped (Python bytecode
/// caches, hidden files, editor backups), so a digest depends on the checkout's sources alone.
pub fn source_files(root: &Path, name: &str) -> Vec<PathBuf> {
    let dir = root.join("experiments/src/experiment");
    let single = dir.join(format!("{name}.rs"));
    let mut files = Vec::new();
    if single.is_file() {
        files.push(single);
    }
    collect_files(&dir.join(name), &mut files);
    files.sort();
    files
}

fn collect_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for entry in entries.flatten() {
        let path = entry.path();
        if is_generated(&path) {
            continue;
        }
        if path.is_dir() {
            collect_files(&path, out);
        } else {
            out.push(path);
        }
    }
}

/// Whether `path` is something a run leaves beside the sources rather than a source: Python's
/// bytecode caches (`__pycache__/`, `*.pyc`, made by importing or `py_compile`), hidden files
/// and editor backups. Counting them once flagged unchanged experiments as changed on a clean
/// checkout.
fn is_generated(path: &Path) -> bool {
    let name = path.file_name().map(|n| n.to_string_lossy()).unwrap_or_default();
    name == "__pycache__" || name.starts_with('.') || name.ends_with('~') || name.ends_with(".pyc") || name.ends_with(".pyo")
}

/// FNV-1a (64 bits) over each source file's path relative to the root and its bytes, as 16 hex
/// digits; `none` when the experiment has no source file of its own.
pub fn source_digest(root: &Path, name: &str) -> String {
    let files = source_files(root, name);
    if files.is_empty() {
        return "none".into();
    }
    let mut hash = Fnv1a::default();
    for f in files {
        let rel = f.strip_prefix(root).unwrap_or(&f).to_string_lossy().replace('\\', "/");
        hash.write(rel.as_bytes());
        hash.write(&[0]);
        hash.write(&std::fs::read(&f).unwrap_or_default());
        hash.write(&[0]);
    }
    format!("{:016x}", hash.0)
}

/// The 64-bit FNV-1a hash.
struct Fnv1a(u64);

impl Default for Fnv1a {
    fn default() -> Self {
        Fnv1a(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv1a {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
}

/// Adds `provenance` as the first entry of the JSON object in `path` (replacing an older one);
/// a file whose top level is not an object is left as it is.
pub fn stamp(path: &Path, provenance: &Provenance) -> Result<(), crate::experiment::ExperimentError> {
    let data_error = |reason: String| crate::experiment::ExperimentError::Data { path: path.to_owned(), reason };
    let text = std::fs::read_to_string(path).map_err(|e| data_error(e.to_string()))?;
    let value: serde_json::Value = serde_json::from_str(&text).map_err(|e| data_error(e.to_string()))?;
    let serde_json::Value::Object(fields) = value else { return Ok(()) };
    let mut stamped = serde_json::Map::new();
    stamped.insert("provenance".into(), serde_json::to_value(provenance).map_err(|e| data_error(e.to_string()))?);
    stamped.extend(fields.into_iter().filter(|(k, _)| k != "provenance"));
    isolab_pipeline::write_json(path, &serde_json::Value::Object(stamped))?;
    Ok(())
}

/// The provenance recorded in the data file at `path`, if any.
pub fn recorded(path: &Path) -> Option<Provenance> {
    let text = std::fs::read_to_string(path).ok()?;
    let value: serde_json::Value = serde_json::from_str(&text).ok()?;
    serde_json::from_value(value.get("provenance")?.clone()).ok()
}

/// The line a page states under its title: where, when and on what its data ran, the versions
/// of the peers it ran, and the command that regenerates it.
pub fn line(name: &str, provenance: Option<&Provenance>) -> String {
    match provenance {
        Some(p) if p.quick => format!(
            "**A quick run** (`report --quick`: every experiment at its smallest sizes, one extraction each; the text \
             may name the full run's sizes): not the report's numbers. {}",
            line(name, Some(&Provenance { quick: false, ..p.clone() }))
        ),
        Some(p) => format!(
            "_Data made at commit `{}` on {} in {:.0} s: {}, {} threads, {:.1} GiB, {}; {}; {}; isolab {}{}. Regenerate: `{}`._",
            p.short_commit(),
            p.date_utc,
            p.seconds,
            p.cpu,
            p.cores,
            p.memory_gib,
            p.os,
            p.rustc,
            p.python,
            p.isolab,
            peers_clause(&p.peers),
            p.command
        ),
        None => format!("_Provenance not recorded (the data predate it). Regenerate: `{}`._", command(name)),
    }
}

/// `; peers: A 1.0, B 2 (package b 2.1)` for the page's line, empty without peers.
fn peers_clause(peers: &[crate::peer_versions::PeerVersion]) -> String {
    if peers.is_empty() {
        return String::new();
    }
    let described: Vec<String> = peers.iter().map(crate::peer_versions::PeerVersion::describe).collect();
    format!("; peers: {}", described.join(", "))
}

/// Whether experiment `name`'s source changed since its data were made: `Some(true)` when the
/// digest of its files in the tree at `root` differs from the recorded one, `None` when none
/// was recorded.
pub fn code_since(root: &Path, name: &str, provenance: Option<&Provenance>) -> Option<bool> {
    provenance.map(|p| p.source_digest != source_digest(root, name))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dates_are_civil_utc() {
        assert_eq!(utc_date(0), "1970-01-01T00:00:00Z");
        assert_eq!(utc_date(951_782_400), "2000-02-29T00:00:00Z");
        assert_eq!(utc_date(1_796_506_651), "2026-12-05T21:37:31Z");
        assert_eq!(utc_date(4_107_542_399), "2100-02-28T23:59:59Z");
    }

    #[test]
    fn machine_texts_are_parsed() {
        let cpuinfo = "processor\t: 0\nvendor_id\t: GenuineIntel\nmodel name\t: Intel(R) Xeon(R) CPU @ 2.20GHz\n";
        assert_eq!(cpu_model(cpuinfo).as_deref(), Some("Intel(R) Xeon(R) CPU @ 2.20GHz"));
        assert_eq!(cpu_model("processor : 0\n"), None);
        assert_eq!(mem_total_gib("MemTotal:        8388608 kB\nMemFree: 1 kB\n"), Some(8.0));
        assert_eq!(mem_total_gib("MemFree: 1 kB\n"), None);
    }

    #[test]
    fn the_digest_follows_the_experiments_files() {
        let dir = tempfile::tempdir().unwrap();
        let exp = dir.path().join("experiments/src/experiment");
        std::fs::create_dir_all(exp.join("big/sub")).unwrap();
        std::fs::write(exp.join("small.rs"), "fn a() {}").unwrap();
        std::fs::write(exp.join("big/mod.rs"), "mod sub;").unwrap();
        std::fs::write(exp.join("big/sub/bench.py"), "print(1)").unwrap();
        assert_eq!(source_files(dir.path(), "big").len(), 2);
        assert_eq!(source_digest(dir.path(), "absent"), "none");
        let (small, big) = (source_digest(dir.path(), "small"), source_digest(dir.path(), "big"));
        assert_ne!(small, big);
        let p = Provenance { source_digest: big.clone(), ..sample() };
        assert_eq!(code_since(dir.path(), "big", Some(&p)), Some(false));
        std::fs::write(exp.join("big/sub/bench.py"), "print(2)").unwrap();
        assert_ne!(source_digest(dir.path(), "big"), big);
        assert_eq!(code_since(dir.path(), "big", Some(&p)), Some(true));
        assert_eq!(code_since(dir.path(), "big", None), None);
        let changed = source_digest(dir.path(), "big");
        std::fs::create_dir_all(exp.join("big/sub/__pycache__")).unwrap();
        std::fs::write(exp.join("big/sub/__pycache__/bench.cpython-311.pyc"), [0u8, 1, 2]).unwrap();
        std::fs::write(exp.join("big/stray.pyc"), [3u8]).unwrap();
        std::fs::write(exp.join("big/.mod.rs.swp"), [4u8]).unwrap();
        assert_eq!(source_files(dir.path(), "big").len(), 2, "bytecode and hidden files are not sources");
        assert_eq!(source_digest(dir.path(), "big"), changed);
    }

    #[test]
    fn stamping_puts_provenance_first_and_keeps_the_rest() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.json");
        std::fs::write(&path, "{\"zeta\": [1.25, 2], \"alpha\": {\"b\": 1, \"a\": 2}}").unwrap();
        stamp(&path, &sample()).unwrap();
        stamp(&path, &Provenance { commit: "abcdef0123456789".into(), ..sample() }).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        let value: serde_json::Value = serde_json::from_str(&text).unwrap();
        let keys: Vec<&String> = value.as_object().unwrap().keys().collect();
        assert_eq!(keys, ["provenance", "zeta", "alpha"]);
        assert_eq!(value["zeta"], serde_json::json!([1.25, 2]));
        let inner: Vec<&String> = value["alpha"].as_object().unwrap().keys().collect();
        assert_eq!(inner, ["b", "a"]);
        assert_eq!(recorded(&path).unwrap().commit, "abcdef0123456789");
        let list = dir.path().join("list.json");
        std::fs::write(&list, "[1, 2]").unwrap();
        stamp(&list, &sample()).unwrap();
        assert_eq!(std::fs::read_to_string(&list).unwrap(), "[1, 2]");
        assert_eq!(recorded(&list), None);
    }

    #[test]
    fn pages_state_the_commit_machine_and_command() {
        let l = line("peers", Some(&Provenance { dirty: true, ..sample() }));
        assert!(l.contains("`0123456789+changes`") && l.contains("2026-12-05T20:17:31Z") && l.contains("Test CPU"), "{l}");
        assert!(l.contains("--bin peers"), "{l}");
        assert!(line("peers", None).contains("not recorded"));
        let vtk = crate::peer_versions::PeerVersion {
            name: "VTK".into(),
            package: "vtk".into(),
            package_version: Some("9.7.2".into()),
            library: "VTK".into(),
            library_version: Some("9.7.1".into()),
        };
        let l = line("peers", Some(&Provenance { peers: vec![vtk], ..sample() }));
        assert!(l.contains("; peers: VTK 9.7.1 (package vtk 9.7.2). Regenerate"), "{l}");
        let l = line("peers", Some(&Provenance { quick: true, ..sample() }));
        assert!(l.starts_with("**A quick run**") && l.contains("Test CPU"), "{l}");
    }

    fn sample() -> Provenance {
        Provenance {
            experiment: "peers".into(),
            commit: "0123456789abcdef".into(),
            dirty: false,
            date_utc: "2026-12-05T20:17:31Z".into(),
            seconds: 12.0,
            cpu: "Test CPU".into(),
            cores: 2,
            memory_gib: 8.0,
            os: "Debian".into(),
            rustc: "rustc 1.0.0".into(),
            python: "Python 3.11".into(),
            isolab: "0.1.0".into(),
            command: command("peers"),
            source_digest: "none".into(),
            peers: Vec::new(),
            quick: false,
        }
    }
}
