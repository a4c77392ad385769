//! Running the `isolab` binary from the CLI tests.

use std::process::{Command, Output};

/// Runs `isolab` with `args`.
pub fn isolab(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_isolab")).args(args).output().expect("isolab runs")
}

/// Its standard error, as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}
