//! Memory checks: a run refuses, before it samples or reads a volume's data, what the memory
//! available to this process cannot hold (the samples, a generous estimate of the output, and a
//! volume file's data and values while its samples are made).

use crate::{input, LatticeKind, RunConfig, RunError, VolumeGrid};
use isolab_algorithms::{Grid, Lattice};

/// Memory available to this process, from `/proc/meminfo` (None where unknown), or the
/// `ISOLAB_MEMORY_MIB` environment variable when it is set (to try the memory checks as a
/// smaller machine would see them).
pub fn available_memory() -> Option<u64> {
    if let Some(mib) = std::env::var("ISOLAB_MEMORY_MIB").ok().and_then(|v| v.trim().parse::<u64>().ok()) {
        return Some(mib << 20);
    }
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Refuses lattices whose samples plus a generous output estimate (four times the samples'
/// bytes) exceed the memory available to this process.
pub fn check_memory(lattice: &Lattice) -> Result<(), RunError> {
    check_memory_against(lattice, available_memory())
}

/// [`check_memory`] against a given number of available bytes (`None`: unknown, accept).
pub fn check_memory_against(lattice: &Lattice, available: Option<u64>) -> Result<(), RunError> {
    check_memory_plus(lattice, 0, available)
}

/// [`check_memory_against`] with `extra` bytes held beside the lattice (a volume file's data and
/// values while its samples are made).
fn check_memory_plus(lattice: &Lattice, extra: u64, available: Option<u64>) -> Result<(), RunError> {
    let need = lattice.sample_count() as u64 * 4 * 5 + extra;
    match available {
        Some(available) if need > available => Err(RunError::OutOfMemory {
            dims: lattice.grid().dims,
            lattice: lattice.kind(),
            need_mib: need >> 20,
            available_mib: available >> 20,
        }),
        _ => Ok(()),
    }
}

/// Whether a run meshes a volume file's voxels where they lie, in their stored type, with an
/// extractor that reads them in place and keeps its output to the memory available
/// ([`isolab_algorithms::extract::SampleAccess::Borrowed`], a surface): the run then needs the
/// file's data and the mesh only.
pub(crate) fn meshes_in_place(config: &RunConfig) -> bool {
    let in_place = isolab_algorithms::extractors::INFOS
        .iter()
        .find(|i| i.name == config.algorithm)
        .is_some_and(|i| i.samples == isolab_algorithms::extract::SampleAccess::Borrowed);
    let surface = isolab_algorithms::extractors::build(&config.algorithm, &config.options)
        .ok()
        .flatten()
        .is_some_and(|e| !e.produces_volume());
    in_place
        && surface
        && config.lattice == LatticeKind::Cubic
        && config.volume_grid == VolumeGrid::Native
        && config.post.is_empty()
        && !config.materials
        && config.chunk.is_none()
}

/// Refuses a volume file meshed on its own grid that cannot fit in memory, from its header,
/// before its data is read (a file whose header does not say plainly is left to the reader).
/// The file's data is read in its stored type; an extractor that meshes it in place needs only
/// that (its output it checks itself, before allocating it); any other also needs the samples as
/// f32 and a generous estimate of its output.
pub(crate) fn check_volume_size(config: &RunConfig) -> Result<(), RunError> {
    if config.volume_grid != VolumeGrid::Native || !input::is_file_spec(&config.field) {
        return Ok(());
    }
    let path = std::path::Path::new(&config.field);
    let (dims, data_bytes) = match isolab_io::volume::read_header(path, config.volume) {
        Ok(h) => (h.dims, h.layout.as_ref().map_or(4, |l| l.data_type().size()) as u64),
        Err(_) => match isolab_io::volume::peek_dims(path) {
            Some(dims) => (dims, 4),
            None => return Ok(()),
        },
    };
    let grid = Grid { origin: glam::Vec3::ZERO, spacing: 1.0, dims };
    let data = volume_reading_bytes(dims, data_bytes);
    if meshes_in_place(config) {
        let available = available_memory();
        return match available {
            Some(available) if data > available => {
                Err(RunError::OutOfMemory { dims, lattice: "cubic", need_mib: data >> 20, available_mib: available >> 20 })
            }
            _ => Ok(()),
        };
    }
    let lattice = match config.lattice {
        LatticeKind::Cubic => Lattice::Cubic(grid),
        LatticeKind::Bcc => Lattice::Bcc(grid),
    };
    check_memory_plus(&lattice, data, available_memory())
}

/// Bytes a run holds to read a volume file of `dims` voxels of `data_bytes` each: its data, in
/// its stored type.
fn volume_reading_bytes(dims: [usize; 3], data_bytes: u64) -> u64 {
    dims.iter().map(|&n| n as u64).product::<u64>() * data_bytes
}

/// What the in-memory run's header check asks for to mesh a volume file of `dims` voxels of
/// `data_bytes` each on its own cubic grid with an extractor that copies the samples into f32,
/// bytes (one that meshes them in place asks for the data alone).
pub fn volume_file_need(dims: [usize; 3], data_bytes: u64) -> u64 {
    let lattice = Lattice::Cubic(Grid { origin: glam::Vec3::ZERO, spacing: 1.0, dims });
    lattice.sample_count() as u64 * 4 * 5 + volume_reading_bytes(dims, data_bytes)
}
