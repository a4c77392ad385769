//! The `isolab` command line's tests, one binary (each file beside this one a module, so the
//! crates link once).

mod cli;
mod cli_bad_input;
mod cli_inputs;
mod cli_labels;
mod cli_stream;
mod common;
