//! The peers in `tests/reference/peers.py`, served by one long-lived Python process in the pinned
//! virtual environment `tests/reference/run.sh setup` creates (created here when missing).
//!
//! Each request is one JSON line and each answer `{"ms", "vertices", "triangles"}` or
//! `{"error"}`; the script's header documents the protocol. The peers' code is in that script,
//! so on this side each is a name: `vtk-flying-edges`, `vtk-marching-cubes`, `skimage-lorensen`,
//! `skimage-lewiner`, `pymcubes`, `libigl` (grids), `pymeshlab-quadric` (decimation), and for
//! scans `vtk-flying-edges` and `skimage-lewiner` on nibabel's array, end to end
//! nibabel + VTK. A peer that is not installed answers with an error saying so.

use super::{Job, Peer, PeerError, PeerRun, Protocol};
use std::cell::RefCell;
use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};
use std::rc::Rc;
use std::time::Duration;

/// The Python peer server.
pub struct PythonServer {
    child: Child,
    stdin: ChildStdin,
    stdout: BufReader<ChildStdout>,
}

/// What the server said on start: `{"available": {package: version}, "errors": {package: why},
/// "mni_t1": path}`.
pub type Hello = serde_json::Value;

impl PythonServer {
    /// Starts `peers.py` in the reference environment under `root`, creating it when missing.
    pub fn start(root: &Path) -> Result<(Rc<RefCell<PythonServer>>, Hello), String> {
        let python = reference_python(root)?;
        let mut child = Command::new(&python)
            .arg(root.join("tests/reference/peers.py"))
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .map_err(|e| format!("cannot start {}: {e}", python.display()))?;
        let stdin = child.stdin.take().ok_or("no stdin")?;
        let mut stdout = BufReader::new(child.stdout.take().ok_or("no stdout")?);
        let mut line = String::new();
        stdout.read_line(&mut line).map_err(|e| e.to_string())?;
        let hello: Hello = serde_json::from_str(&line).map_err(|e| format!("peers.py said {line:?}: {e}"))?;
        Ok((Rc::new(RefCell::new(PythonServer { child, stdin, stdout })), hello))
    }

    /// Sends one request line and reads its answer: (ms, vertices, triangles), or the peer's error.
    pub(crate) fn request(&mut self, request: &serde_json::Value) -> Result<(f64, usize, usize), String> {
        writeln!(self.stdin, "{request}").map_err(|e| e.to_string())?;
        self.stdin.flush().map_err(|e| e.to_string())?;
        let mut line = String::new();
        self.stdout.read_line(&mut line).map_err(|e| e.to_string())?;
        let v: serde_json::Value = serde_json::from_str(&line).map_err(|e| format!("{line:?}: {e}"))?;
        if let Some(e) = v.get("error") {
            return Err(e.as_str().map_or_else(|| e.to_string(), str::to_owned));
        }
        let n = |k: &str| v[k].as_u64().unwrap_or(0) as usize;
        Ok((v["ms"].as_f64().unwrap_or(f64::NAN), n("vertices"), n("triangles")))
    }
}

/// The Python of the pinned reference environment under `root` (`tests/reference/.venv`), made
/// by `tests/reference/run.sh setup` when missing.
pub fn reference_python(root: &Path) -> Result<PathBuf, String> {
    let python = root.join("tests/reference/.venv/bin/python");
    if !python.exists() {
        let status = Command::new("bash")
            .arg(root.join("tests/reference/run.sh"))
            .arg("setup")
            .status()
            .map_err(|e| format!("cannot run tests/reference/run.sh setup: {e}"))?;
        if !status.success() {
            return Err("tests/reference/run.sh setup failed (no Python peers)".into());
        }
    }
    Ok(python)
}

/// `pip install ./python` into the reference environment's `python`: the package of this commit,
/// built by maturin as a user's `pip install` builds it (for experiments that time the package).
pub fn install_package(python: &Path, root: &Path) -> Result<(), String> {
    let status = Command::new(python)
        .args(["-m", "pip", "install", "--quiet", "--disable-pip-version-check", "--no-deps", "--force-reinstall"])
        .arg(root.join("python"))
        .status()
        .map_err(|e| format!("cannot run pip with {}: {e}", python.display()))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("pip install ./python failed ({status})"))
    }
}

/// Runs an experiment's Python `script` with `args` (its first argument the JSON file it
/// writes), `env` set, and returns what it wrote, parsed.
pub fn run_script<T: serde::de::DeserializeOwned>(
    python: &Path,
    script: &Path,
    args: &[String],
    env: &[(&str, &str)],
) -> Result<T, String> {
    let out = std::env::temp_dir().join(format!(
        "isolab-{}-{}.json",
        script.file_stem().and_then(|s| s.to_str()).unwrap_or("script"),
        std::process::id()
    ));
    let mut command = Command::new(python);
    command.arg(script).arg(&out).args(args);
    for (k, v) in env {
        command.env(k, v);
    }
    let status = command.status().map_err(|e| format!("cannot run {} with {}: {e}", script.display(), python.display()))?;
    if !status.success() {
        return Err(format!("{} failed ({status})", script.display()));
    }
    let text = std::fs::read_to_string(&out).map_err(|e| format!("{}: {e}", out.display()))?;
    let _ = std::fs::remove_file(&out);
    serde_json::from_str(&text).map_err(|e| format!("{}: {e}", out.display()))
}

impl Drop for PythonServer {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// One peer of the Python server, by the name `peers.py` knows it by.
pub struct PythonPeer {
    server: Rc<RefCell<PythonServer>>,
    name: &'static str,
}

impl PythonPeer {
    /// The peer `name` on `server`.
    pub fn new(server: &Rc<RefCell<PythonServer>>, name: &'static str) -> PythonPeer {
        PythonPeer { server: Rc::clone(server), name }
    }

    fn request(&self, job: &Job<'_>, protocol: Protocol) -> Option<serde_json::Value> {
        let protocol = protocol.name();
        Some(match job {
            Job::Grid { file, threads, .. } => {
                serde_json::json!({"raw": file, "peer": self.name, "threads": threads, "protocol": protocol})
            }
            Job::Decimate { mesh, target, out } if self.name == "pymeshlab-quadric" => {
                serde_json::json!({"peer": self.name, "mesh": mesh, "target": target, "out": out})
            }
            Job::Scan { file, level, threads, end_to_end: true, .. } if self.name == "vtk-flying-edges" => {
                serde_json::json!({"peer": "scan-end-to-end", "nifti": file, "level": level, "threads": threads})
            }
            Job::Scan { file, level, threads, out, end_to_end: false } => {
                serde_json::json!({"peer": "scan", "library": self.name, "nifti": file, "level": level, "threads": threads, "out": out})
            }
            _ => return None,
        })
    }
}

impl Peer for PythonPeer {
    fn name(&self) -> String {
        self.name.into()
    }

    fn run(&mut self, job: &Job<'_>, protocol: Protocol) -> Result<PeerRun, PeerError> {
        let request = self.request(job, protocol).ok_or_else(|| self.unsupported())?;
        let (ms, vertices, triangles) =
            self.server.borrow_mut().request(&request).map_err(|message| PeerError::Failed { peer: self.name(), message })?;
        if !(ms.is_finite() && ms >= 0.0) {
            return Err(PeerError::Failed { peer: self.name(), message: format!("answered a time of {ms} ms") });
        }
        Ok(PeerRun { time: Duration::from_secs_f64(ms / 1e3), vertices, triangles, ..PeerRun::default() })
    }
}
