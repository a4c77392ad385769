//! The one error type of a run, shared by the input loader and the pipeline (so neither imports
//! the other for it), with the CLI's exit code.

use isolab_algorithms::{ExtractError, FieldError, LatticeError, OptionError, SampleError};
use isolab_io::IoError;

/// Everything that can go wrong in a run. [`RunError::exit_code`] maps it to the CLI's code.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// No extractor has that name.
    #[error("unknown algorithm '{name}'; valid algorithms: {valid}")]
    UnknownAlgorithm {
        /// Name given.
        name: String,
        /// Valid names.
        valid: String,
    },
    /// A setting named by a word (`lattice`, `inside`, `space`, ...) got a word it does not take.
    #[error(transparent)]
    Choice(#[from] isolab_io::UnknownChoice),
    /// An algorithm option is unknown or out of range.
    #[error(transparent)]
    Option(#[from] OptionError),
    /// No post-process has that name.
    #[error("unknown post-process '{name}'; valid post-processes: {valid}")]
    UnknownPost {
        /// Name given.
        name: String,
        /// Valid names.
        valid: String,
    },
    /// Field problems (unknown name, bad mesh).
    #[error(transparent)]
    Field(#[from] FieldError),
    /// File problems.
    #[error(transparent)]
    Io(#[from] IoError),
    /// Impossible lattice.
    #[error(transparent)]
    Lattice(#[from] LatticeError),
    /// Non-finite samples.
    #[error(transparent)]
    Samples(#[from] SampleError),
    /// Extraction failed.
    #[error(transparent)]
    Extract(#[from] ExtractError),
    /// The iso-value is NaN or infinite.
    #[error("iso-value {0} is not finite")]
    BadIso(f32),
    /// Not enough memory for the lattice.
    #[error(
        "a {dims:?} {lattice} lattice needs about {need_mib} MiB, but only {available_mib} MiB of memory is available; lower \
         --resolution (a volume file is then resampled), or mesh it block by block in bounded memory: \
         --stream with a .ply output, or isolab.dask.mesh_volume (Python)"
    )]
    OutOfMemory {
        /// Samples per axis.
        dims: [usize; 3],
        /// Lattice kind.
        lattice: &'static str,
        /// Estimated need.
        need_mib: u64,
        /// Available.
        available_mib: u64,
    },
    /// A volume file cannot be meshed block by block as asked (`--stream`); nothing was read
    /// beyond its header.
    #[error("cannot stream '{path}': {reason}")]
    Stream {
        /// The volume file.
        path: String,
        /// Why, and what to do instead.
        reason: String,
    },
    /// A run asked to mesh sparsely cannot, or its sparse extraction failed.
    #[error("cannot mesh '{field}' sparsely: {reason}")]
    Sparse {
        /// The field or file.
        field: String,
        /// Why, and what to do instead.
        reason: String,
    },
    /// A neuroglancer source cannot be written as asked, or writing it failed.
    #[error("cannot write the neuroglancer source '{output}': {reason}")]
    Neuroglancer {
        /// The output folder.
        output: String,
        /// Why.
        reason: String,
    },
}

impl RunError {
    /// 2 for an unknown name (usage error), 1 otherwise.
    pub fn exit_code(&self) -> i32 {
        match self {
            RunError::UnknownAlgorithm { .. }
            | RunError::UnknownPost { .. }
            | RunError::Option(_)
            | RunError::Choice(_)
            | RunError::Field(FieldError::Unknown { .. }) => 2,
            _ => 1,
        }
    }
}
