//! isolab's own grid: raw little-endian f32 values in the lattice's index order (x fastest; a
//! BCC lattice's corner grid, then its centres) in `PATH`, and a JSON header in `PATH.json`
//! (`lattice`, `dims`, `origin`, `spacing`, `iso`, `inside`, and `index_to_world` when the
//! samples were taken on a volume's own voxel grid). `--samples-out` writes it, so a peer library
//! can read the very samples isolab meshed; `-f PATH` reads it back (the same mesh again).

use super::{volume, Inside, Space, VolumeFile};
use crate::{write_atomic, IoError};
use glam::{DAffine3, DMat3, DVec3};
use std::io::Write;
use std::path::{Path, PathBuf};

/// `PATH.json`.
pub fn header_path(path: &Path) -> PathBuf {
    let mut json = path.as_os_str().to_owned();
    json.push(".json");
    PathBuf::from(json)
}

/// Writes `samples` to `path` and its header to `path.json`. `index_to_world` places the grid
/// when the samples are a volume's voxels in index coordinates.
pub fn write_samples(
    path: &Path,
    samples: &isolab_algorithms::Samples,
    index_to_world: Option<&DAffine3>,
) -> Result<(), IoError> {
    write_atomic(path, |w| {
        for v in samples.values() {
            w.write_all(&v.to_le_bytes())?;
        }
        Ok(())
    })?;
    let g = samples.grid();
    let mut header = serde_json::json!({
        "lattice": samples.lattice().kind(),
        "dims": g.dims,
        "origin": g.origin.to_array(),
        "spacing": g.spacing,
        "iso": samples.iso(),
        "inside": "below",
    });
    if let Some(a) = index_to_world {
        let m = a.matrix3;
        let row = |r: usize| [m.x_axis[r], m.y_axis[r], m.z_axis[r], a.translation[r]];
        header["index_to_world"] = serde_json::json!([row(0), row(1), row(2)]);
    }
    write_atomic(&header_path(path), |w| serde_json::to_writer_pretty(&mut *w, &header).map_err(std::io::Error::other))
}

/// What a grid `--samples-out` wrote says of itself, and where its values lie (a cubic grid's
/// values are the whole file; a BCC lattice's centres follow its corners, read whole only).
pub fn header_layout(path: &Path) -> Result<super::VolumeHeader, IoError> {
    let h = header(path)?;
    let layout = if h.lattice == "cubic" {
        Ok(super::DataLayout {
            file: path.to_path_buf(),
            start: 0,
            compression: None,
            offset: 0,
            ty: super::DataType::F32,
            big_endian: false,
            slope: 1.0,
            inter: 0.0,
        })
    } else {
        Err(format!("it holds a {} lattice, read whole only", h.lattice))
    };
    Ok(super::VolumeHeader {
        dims: h.dims,
        affine: h.affine,
        format: "isolab grid",
        data_type: "float32",
        space: Space::Unknown,
        inside: h.inside,
        iso: h.iso,
        notes: Vec::new(),
        layout: layout.map(super::StoredData::File),
    })
}

/// A grid header, read.
struct Header {
    dims: [usize; 3],
    lattice: String,
    iso: Option<f32>,
    inside: Inside,
    affine: DAffine3,
}

fn header(path: &Path) -> Result<Header, IoError> {
    let json_path = header_path(path);
    let text = crate::read_bytes(&json_path)?;
    let bad = |reason: String| IoError::Invalid { path: json_path.clone(), reason };
    let header: serde_json::Value = serde_json::from_slice(&text).map_err(|e| bad(format!("not JSON: {e}")))?;
    let dims: [usize; 3] =
        serde_json::from_value(header["dims"].clone()).map_err(|_| bad("'dims' is not three counts".into()))?;
    let lattice = header["lattice"].as_str().unwrap_or("cubic").to_owned();
    if lattice != "cubic" && lattice != "bcc" {
        return Err(bad(format!("lattice '{lattice}' is not cubic or bcc")));
    }
    let iso = header["iso"].as_f64().map(|v| v as f32);
    let inside = match header["inside"].as_str() {
        Some("above") => Inside::Above,
        _ => Inside::Below,
    };
    let affine = match header.get("index_to_world") {
        Some(rows) => {
            let rows: [[f64; 4]; 3] =
                serde_json::from_value(rows.clone()).map_err(|_| bad("'index_to_world' is not 3 rows of 4".into()))?;
            let col = |c: usize| DVec3::new(rows[0][c], rows[1][c], rows[2][c]);
            DAffine3 { matrix3: DMat3::from_cols(col(0), col(1), col(2)), translation: col(3) }
        }
        None => {
            let origin: [f64; 3] =
                serde_json::from_value(header["origin"].clone()).map_err(|_| bad("'origin' is not three numbers".into()))?;
            let spacing = header["spacing"].as_f64().ok_or_else(|| bad("'spacing' is not a number".into()))?;
            DAffine3 { matrix3: DMat3::from_diagonal(DVec3::splat(spacing)), translation: DVec3::from(origin) }
        }
    };
    Ok(Header { dims, lattice, iso, inside, affine })
}

/// Reads a grid `--samples-out` wrote.
pub fn read_samples(path: &Path) -> Result<VolumeFile, IoError> {
    let json_path = header_path(path);
    let bad = |reason: String| IoError::Invalid { path: json_path.clone(), reason };
    let Header { dims, lattice, iso, inside, affine } = header(path)?;
    let lattice = lattice.as_str();
    let corners =
        dims.iter().try_fold(1usize, |a, &d| a.checked_mul(d)).ok_or_else(|| bad(format!("dims {dims:?} are too large")))?;
    let centres = match lattice {
        "cubic" => 0,
        "bcc" => dims.iter().map(|d| d.saturating_sub(1)).product(),
        other => return Err(bad(format!("lattice '{other}' is not cubic or bcc"))),
    };
    let bytes = crate::read_bytes(path)?;
    let need = (corners + centres).checked_mul(4).ok_or_else(|| bad(format!("dims {dims:?} are too large")))?;
    if bytes.len() != need {
        return Err(IoError::Invalid {
            path: path.into(),
            reason: format!(
                "header and data disagree: a {dims:?} {lattice} lattice needs {need} bytes of f32, the file has {}",
                bytes.len()
            ),
        });
    }
    let mut values = super::decode(&bytes, super::DataType::F32, false, corners + centres, 1.0, 0.0);
    let centre_values = (centres > 0).then(|| values.split_off(corners));
    if let Some(at) = centre_values.as_ref().and_then(|c| c.iter().position(|v| !v.is_finite())) {
        return Err(IoError::Invalid { path: path.into(), reason: format!("centre sample {at} is not finite") });
    }
    Ok(VolumeFile {
        volume: std::sync::Arc::new(volume(path, dims, values, affine)?),
        format: "isolab grid",
        data_type: "float32",
        space: Space::Unknown,
        inside,
        iso,
        centres: centre_values,
        notes: Vec::new(),
    })
}
