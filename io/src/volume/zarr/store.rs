//! Reading zarr stores with the `zarrs` crate (the `zarr` feature): the metadata into a header,
//! the picked volume whole or a run of z-slices at a time.

use super::super::{decode, volume, DataType, Inside, Space, StoredData, VolumeFile, VolumeHeader, VolumeOptions};
use super::ZarrLayout;
use crate::IoError;
use glam::{DAffine3, DMat3, DVec3};
use serde_json::Value;
use std::path::Path;
use std::sync::Arc;
use zarrs::array::Array;
use zarrs::array_subset::ArraySubset;
use zarrs::filesystem::FilesystemStore;
use zarrs::group::Group;

/// Reads the store's metadata (no chunk) into a header.
pub fn header_layout(path: &Path, options: VolumeOptions) -> Result<VolumeHeader, IoError> {
    let invalid = |reason: String| IoError::Invalid { path: path.into(), reason };
    let store = Arc::new(FilesystemStore::new(path).map_err(|e| invalid(format!("cannot open the zarr store ({e})")))?);
    let mut notes = Vec::new();
    let (array, node, transform) = match Array::open(store.clone(), "/") {
        Ok(array) => {
            notes.push("a plain zarr array (no OME-Zarr metadata): unit spacing, origin at voxel 0".to_owned());
            (array, "/".to_owned(), None)
        }
        Err(_) => {
            let group = Group::open(store.clone(), "/")
                .map_err(|e| invalid(format!("neither a zarr array nor a zarr group at its root ({e})")))?;
            let (node, transform) = ome_level(group.attributes()).map_err(invalid)?;
            let array = Array::open(store, &node).map_err(|e| invalid(format!("the OME-Zarr level '{node}': {e}")))?;
            (array, node, Some(transform))
        }
    };
    let transform = transform.unwrap_or_else(|| Transform::identity(array.dimensionality()));
    let shape = array.shape().to_vec();
    if shape.len() < 3 {
        return Err(invalid(format!("the array has {} dimensions ({shape:?}); a volume needs 3", shape.len())));
    }
    let ty = data_type(&array.data_type().name()).ok_or_else(|| {
        invalid(format!("its data type '{}' is not one we mesh (integers and floats)", array.data_type().name()))
    })?;
    let spatial = &shape[shape.len() - 3..];
    let lead = pick_lead(&shape[..shape.len() - 3], options.index, &shape, &mut notes).map_err(invalid)?;
    let dims = [spatial[2] as usize, spatial[1] as usize, spatial[0] as usize];
    let chunks = array.chunk_shape(&vec![0; shape.len()]).map_err(|e| invalid(format!("its chunk grid: {e}")))?;
    let chunk_z = chunks[shape.len() - 3].get() as usize;
    if transform.scale.len() != shape.len() {
        return Err(invalid(format!(
            "its OME-Zarr scale has {} values for an array of {} dimensions",
            transform.scale.len(),
            shape.len()
        )));
    }
    let n = shape.len();
    let axis = |v: &[f64]| DVec3::new(v[n - 1], v[n - 2], v[n - 3]);
    let (scale, shift) = (axis(&transform.scale), axis(&transform.translation));
    if !scale.is_finite() || scale.min_element() <= 0.0 || !shift.is_finite() {
        return Err(invalid(format!("its OME-Zarr scale {scale} or translation {shift} is not positive and finite")));
    }
    if let Some(unit) = transform.unit {
        notes.push(format!("coordinates in {unit} (OME-Zarr axes)"));
    }
    Ok(VolumeHeader {
        dims,
        affine: DAffine3 { matrix3: DMat3::from_diagonal(scale), translation: shift },
        format: if node == "/" { "zarr" } else { "OME-Zarr" },
        data_type: ty.name(),
        space: Space::Unknown,
        inside: Inside::Above,
        iso: None,
        notes,
        layout: Ok(StoredData::Zarr(ZarrLayout { store: path.into(), node, ty, lead, chunk_z })),
    })
}

/// Reads the whole picked volume of the store at `path`.
pub fn read_zarr(path: &Path, options: VolumeOptions) -> Result<VolumeFile, IoError> {
    let header = header_layout(path, options)?;
    let Ok(StoredData::Zarr(layout)) = &header.layout else {
        return Err(IoError::Invalid { path: path.into(), reason: "not a zarr array".into() });
    };
    let mut slices = ZarrSlices::open(layout)?;
    let mut values = Vec::new();
    slices.read(0, header.dims, header.dims[2], &mut values)?;
    Ok(VolumeFile {
        volume: Arc::new(volume(path, header.dims, values, header.affine)?),
        format: header.format,
        data_type: header.data_type,
        space: header.space,
        inside: header.inside,
        iso: None,
        centres: None,
        notes: header.notes,
    })
}

/// A zarr array read a run of z-slices at a time: whole storage chunks along z are fetched
/// (decoded in parallel by `zarrs`) and kept as stored bytes until their slices are asked for.
pub struct ZarrSlices {
    array: Array<FilesystemStore>,
    layout: ZarrLayout,
    /// The stored bytes of slices `held_from..held_from + held`, x fastest.
    held: Vec<u8>,
    held_from: usize,
    held_count: usize,
}

impl ZarrSlices {
    /// Opens the array `layout` names.
    pub fn open(layout: &ZarrLayout) -> Result<ZarrSlices, IoError> {
        let invalid = |reason: String| IoError::Invalid { path: layout.store.clone(), reason };
        let store =
            Arc::new(FilesystemStore::new(&layout.store).map_err(|e| invalid(format!("cannot open the zarr store ({e})")))?);
        let array = Array::open(store, &layout.node).map_err(|e| invalid(format!("the array '{}': {e}", layout.node)))?;
        Ok(ZarrSlices { array, layout: layout.clone(), held: Vec::new(), held_from: 0, held_count: 0 })
    }

    /// Appends z-slices `z..z + count` of a volume of `dims` to `out`, decoded to f32.
    pub fn read(&mut self, z: usize, dims: [usize; 3], count: usize, out: &mut Vec<f32>) -> Result<(), IoError> {
        let slice = dims[0] * dims[1];
        let size = self.layout.ty.size();
        let mut z = z;
        let end = z + count;
        while z < end {
            if !(self.held_from..self.held_from + self.held_count).contains(&z) {
                self.fetch(z, dims)?;
            }
            let take = (self.held_from + self.held_count).min(end) - z;
            let from = (z - self.held_from) * slice * size;
            let bytes = &self.held[from..from + take * slice * size];
            out.extend(decode(bytes, self.layout.ty, cfg!(target_endian = "big"), take * slice, 1.0, 0.0));
            z += take;
        }
        Ok(())
    }

    /// Fetches the run of storage chunks along z that holds slice `z`.
    fn fetch(&mut self, z: usize, dims: [usize; 3]) -> Result<(), IoError> {
        let chunk_z = self.layout.chunk_z.max(1);
        let from = z / chunk_z * chunk_z;
        let count = chunk_z.min(dims[2] - from);
        let mut ranges: Vec<std::ops::Range<u64>> = self.layout.lead.iter().map(|&i| i..i + 1).collect();
        ranges.push(from as u64..(from + count) as u64);
        ranges.push(0..dims[1] as u64);
        ranges.push(0..dims[0] as u64);
        let read_err = |e: String| IoError::Invalid {
            path: self.layout.store.clone(),
            reason: format!("z-slices {from}..{} of {}: {e}", from + count, dims[2]),
        };
        let bytes = self
            .array
            .retrieve_array_subset(&ArraySubset::new_with_ranges(&ranges))
            .map_err(|e| read_err(e.to_string()))?
            .into_fixed()
            .map_err(|e| read_err(e.to_string()))?;
        self.held = bytes.into_owned();
        self.held_from = from;
        self.held_count = count;
        Ok(())
    }
}

/// An OME-Zarr level's placement: per-axis scale and translation (array axis order).
#[derive(Debug, PartialEq)]
struct Transform {
    scale: Vec<f64>,
    translation: Vec<f64>,
    unit: Option<String>,
}

impl Transform {
    fn identity(rank: usize) -> Transform {
        Transform { scale: vec![1.0; rank], translation: vec![0.0; rank], unit: None }
    }

    /// Applies OME-NGFF `coordinateTransformations` (scale and translation, in order) on top.
    fn then(mut self, transformations: Option<&Value>) -> Result<Transform, String> {
        for t in transformations.and_then(Value::as_array).into_iter().flatten() {
            let values = |key: &str| -> Result<Vec<f64>, String> {
                let v = t.get(key).and_then(Value::as_array).ok_or_else(|| format!("an OME-Zarr {key} without values"))?;
                v.iter().map(|x| x.as_f64().ok_or_else(|| format!("an OME-Zarr {key} value '{x}' is not a number"))).collect()
            };
            let check = |v: &[f64], key: &str| {
                if v.len() == self.scale.len() {
                    Ok(())
                } else {
                    Err(format!("an OME-Zarr {key} of {} values for {} axes", v.len(), self.scale.len()))
                }
            };
            match t.get("type").and_then(Value::as_str) {
                Some("scale") => {
                    let s = values("scale")?;
                    check(&s, "scale")?;
                    for (i, s) in s.iter().enumerate() {
                        self.scale[i] *= s;
                        self.translation[i] *= s;
                    }
                }
                Some("translation") => {
                    let s = values("translation")?;
                    check(&s, "translation")?;
                    for (i, s) in s.iter().enumerate() {
                        self.translation[i] += s;
                    }
                }
                Some("identity") => {}
                other => return Err(format!("an OME-Zarr coordinate transformation of type {other:?}, not read")),
            }
        }
        Ok(self)
    }
}

/// The full-resolution level of an OME-Zarr image (`multiscales[0].datasets[0]`, under `ome`
/// in 0.5): its node path and placement.
fn ome_level(attributes: &serde_json::Map<String, Value>) -> Result<(String, Transform), String> {
    let ome = attributes.get("ome").and_then(Value::as_object).unwrap_or(attributes);
    let multiscale = ome
        .get("multiscales")
        .and_then(Value::as_array)
        .and_then(|m| m.first())
        .ok_or("a zarr group without OME-Zarr multiscales: give the folder of the array to mesh (e.g. store.zarr/NAME)")?;
    let axes = multiscale.get("axes").and_then(Value::as_array).ok_or("OME-Zarr multiscales without axes")?;
    let dataset = multiscale
        .get("datasets")
        .and_then(Value::as_array)
        .and_then(|d| d.first())
        .ok_or("OME-Zarr multiscales without datasets")?;
    let path = dataset.get("path").and_then(Value::as_str).ok_or("an OME-Zarr dataset without a path")?;
    let spatial: Vec<&Value> = axes.iter().filter(|a| a.get("type").and_then(Value::as_str) == Some("space")).collect();
    let last_three_spatial = axes.len() >= 3
        && axes[axes.len() - 3..].iter().all(|a| a.get("type").and_then(Value::as_str) == Some("space"))
        && spatial.len() == 3;
    if !last_three_spatial {
        return Err(format!(
            "OME-Zarr axes {}: a volume needs three space axes, last",
            serde_json::to_string(axes).unwrap_or_default()
        ));
    }
    let unit = spatial.iter().find_map(|a| a.get("unit").and_then(Value::as_str)).map(str::to_owned);
    let transform = Transform::identity(axes.len())
        .then(dataset.get("coordinateTransformations"))?
        .then(multiscale.get("coordinateTransformations"))?;
    Ok((format!("/{}", path.trim_matches('/')), Transform { unit, ..transform }))
}

/// The index fixed on each leading axis: 0 on axes of size 1, `--volume K` on the one longer
/// axis (refused when there are two, or none and K is given).
fn pick_lead(lead: &[u64], index: Option<usize>, shape: &[u64], notes: &mut Vec<String>) -> Result<Vec<u64>, String> {
    let long: Vec<usize> = (0..lead.len()).filter(|&a| lead[a] > 1).collect();
    let mut picked = vec![0; lead.len()];
    match (long.as_slice(), index) {
        ([], None | Some(0)) => {}
        ([], Some(k)) => return Err(format!("--volume {k}: the array {shape:?} holds one 3-D volume")),
        ([a], None) => {
            return Err(format!(
                "is {}-D ({shape:?}): {} volumes; pick one with --volume K (0 to {})",
                shape.len(),
                lead[*a],
                lead[*a] - 1
            ))
        }
        ([a], Some(k)) if (k as u64) < lead[*a] => {
            picked[*a] = k as u64;
            notes.push(format!("volume {k} of {} ({shape:?})", lead[*a]));
        }
        ([a], Some(k)) => {
            return Err(format!("--volume {k} is out of range: {shape:?} holds {} volumes (0 to {})", lead[*a], lead[*a] - 1))
        }
        _ => return Err(format!("{shape:?} has more than one leading axis longer than 1; isolab meshes one 3-D volume")),
    }
    Ok(picked)
}

/// isolab's name for a zarr data type.
fn data_type(name: &str) -> Option<DataType> {
    Some(match name {
        "uint8" => DataType::U8,
        "int8" => DataType::I8,
        "uint16" => DataType::U16,
        "int16" => DataType::I16,
        "uint32" => DataType::U32,
        "int32" => DataType::I32,
        "uint64" => DataType::U64,
        "int64" => DataType::I64,
        "float32" => DataType::F32,
        "float64" => DataType::F64,
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    //! Stores written by hand here (metadata JSON and raw chunk files, no codec), so the reader
    //! is checked against the zarr specifications rather than against `zarrs`'s own writer;
    //! zarr-python's stores, with their default codecs, are checked in the Python tests.
    use super::*;
    use crate::volume::read_volume;
    use crate::volume::slabs::VolumeSlabs;
    use crate::volume::zarr::is_zarr;
    use serde_json::json;

    /// `[z, y, x]`, not a multiple of the chunks on any axis.
    const SHAPE: [usize; 3] = [5, 4, 7];
    const CHUNKS: [usize; 3] = [2, 3, 4];

    fn value(lead: usize, z: usize, y: usize, x: usize) -> u16 {
        (x + 10 * y + 100 * z + 1000 * lead) as u16
    }

    /// Writes a chunked array of `volumes` volumes (a leading axis when more than one) at
    /// `dir`: v3 (`c/...` keys, `bytes` codec) or v2 (`0.0.0` keys, no compressor, big-endian).
    /// The chunk at the grid's origin is left out when `skip_first` (it reads as fill values).
    fn write_array(dir: &Path, volumes: usize, v3: bool, skip_first: bool) {
        std::fs::create_dir_all(dir).unwrap();
        let lead: Vec<usize> = if volumes > 1 { vec![volumes] } else { vec![] };
        let shape: Vec<usize> = lead.iter().copied().chain(SHAPE).collect();
        let chunks: Vec<usize> = lead.iter().map(|_| 1).chain(CHUNKS).collect();
        let meta = if v3 {
            json!({"zarr_format": 3, "node_type": "array", "shape": shape, "data_type": "uint16",
                "chunk_grid": {"name": "regular", "configuration": {"chunk_shape": chunks}},
                "chunk_key_encoding": {"name": "default", "configuration": {"separator": "/"}},
                "fill_value": 7, "codecs": [{"name": "bytes", "configuration": {"endian": "little"}}], "attributes": {}})
        } else {
            json!({"zarr_format": 2, "shape": shape, "chunks": chunks, "dtype": ">u2", "compressor": null,
                "fill_value": 7, "order": "C", "filters": null})
        };
        std::fs::write(dir.join(if v3 { "zarr.json" } else { ".zarray" }), meta.to_string()).unwrap();
        let grid = |a: usize| shape[a].div_ceil(chunks[a]);
        let n = shape.len();
        let mut index = vec![0; n];
        loop {
            if !(skip_first && index.iter().all(|&i| i == 0)) {
                let mut bytes = Vec::new();
                let (l, c) = (if n == 4 { index[0] } else { 0 }, &index[n - 3..]);
                for z in 0..CHUNKS[0] {
                    for y in 0..CHUNKS[1] {
                        for x in 0..CHUNKS[2] {
                            let (gz, gy, gx) = (c[0] * CHUNKS[0] + z, c[1] * CHUNKS[1] + y, c[2] * CHUNKS[2] + x);
                            let inside = gz < SHAPE[0] && gy < SHAPE[1] && gx < SHAPE[2];
                            let v = if inside { value(l, gz, gy, gx) } else { 0 };
                            bytes.extend(if v3 { v.to_le_bytes() } else { v.to_be_bytes() });
                        }
                    }
                }
                let key: Vec<String> = index.iter().map(usize::to_string).collect();
                let file = if v3 { dir.join("c").join(key.join("/")) } else { dir.join(key.join(".")) };
                std::fs::create_dir_all(file.parent().unwrap()).unwrap();
                std::fs::write(file, bytes).unwrap();
            }
            let Some(a) = (0..n).rev().find(|&a| index[a] + 1 < grid(a)) else { break };
            index[a] += 1;
            index[a + 1..].iter_mut().for_each(|i| *i = 0);
        }
    }

    /// The volume's values in isolab's order (x fastest, x the array's last axis).
    fn expected(lead: usize, skip_first: bool) -> Vec<f32> {
        let mut out = Vec::new();
        for z in 0..SHAPE[0] {
            for y in 0..SHAPE[1] {
                for x in 0..SHAPE[2] {
                    let fill = skip_first && z < CHUNKS[0] && y < CHUNKS[1] && x < CHUNKS[2];
                    out.push(if fill { 7.0 } else { value(lead, z, y, x) as f32 });
                }
            }
        }
        out
    }

    /// Reads `path` whole and slab by slab (runs of 1, 2 and 3 slices) and checks both give
    /// `want`.
    fn reads(path: &Path, options: VolumeOptions, want: &[f32]) -> VolumeFile {
        let file = read_volume(path, options).unwrap();
        assert_eq!(file.volume.dims, [SHAPE[2], SHAPE[1], SHAPE[0]]);
        assert_eq!(file.volume.values_f32(), want, "{}", path.display());
        let mut slabs = VolumeSlabs::open(path, options).unwrap();
        assert_eq!(slabs.header.affine, file.volume.index_to_world);
        for run in [1, 2, 3] {
            slabs.rewind().unwrap();
            let mut out = Vec::new();
            while slabs.position() < SHAPE[0] {
                let n = run.min(SHAPE[0] - slabs.position());
                slabs.read_slices(n, &mut out).unwrap();
            }
            assert_eq!(out, want, "{} in runs of {run}", path.display());
        }
        file
    }

    #[test]
    fn plain_arrays_read_in_numpy_order_with_fill_values_for_missing_chunks() {
        let dir = tempfile::tempdir().unwrap();
        for (v3, name) in [(true, "v3.zarr"), (false, "v2.zarr")] {
            let path = dir.path().join(name);
            write_array(&path, 1, v3, true);
            assert!(is_zarr(&path));
            let file = reads(&path, VolumeOptions::default(), &expected(0, true));
            assert_eq!(file.format, "zarr");
            assert_eq!(file.data_type, "uint16");
            assert_eq!(file.volume.index_to_world, DAffine3::IDENTITY);
            assert!(file.notes.iter().any(|n| n.contains("unit spacing")), "{:?}", file.notes);
        }
    }

    #[test]
    fn ome_zarr_levels_are_placed_by_their_scale_and_translation() {
        let dir = tempfile::tempdir().unwrap();
        // 0.4 (zarr v2, attributes in .zattrs), axes z, y, x.
        let v2 = dir.path().join("ome04.zarr");
        write_array(&v2.join("0"), 1, false, false);
        std::fs::write(v2.join(".zgroup"), r#"{"zarr_format": 2}"#).unwrap();
        let axes = json!([{"name": "z", "type": "space", "unit": "micrometer"}, {"name": "y", "type": "space"},
            {"name": "x", "type": "space"}]);
        let ms = json!({"multiscales": [{"version": "0.4", "axes": axes, "datasets": [{"path": "0",
            "coordinateTransformations": [{"type": "scale", "scale": [2.0, 0.5, 0.25]},
                {"type": "translation", "translation": [10.0, 20.0, 30.0]}]}]}]});
        std::fs::write(v2.join(".zattrs"), ms.to_string()).unwrap();
        let file = reads(&v2, VolumeOptions::default(), &expected(0, false));
        assert_eq!(file.format, "OME-Zarr");
        let a = file.volume.index_to_world;
        assert_eq!(a.transform_point3(DVec3::ZERO), DVec3::new(30.0, 20.0, 10.0));
        assert_eq!(a.transform_point3(DVec3::ONE), DVec3::new(30.25, 20.5, 12.0));
        assert!(file.notes.iter().any(|n| n.contains("micrometer")), "{:?}", file.notes);

        // 0.5 (zarr v3, under "ome"), a time axis of three volumes first, an image-wide scale.
        let v3 = dir.path().join("ome05.zarr");
        write_array(&v3.join("0"), 3, true, false);
        let axes = json!([{"name": "t", "type": "time"}, {"name": "z", "type": "space"}, {"name": "y", "type": "space"},
            {"name": "x", "type": "space"}]);
        let ome = json!({"version": "0.5", "multiscales": [{"axes": axes, "datasets": [{"path": "0",
            "coordinateTransformations": [{"type": "scale", "scale": [1.0, 1.0, 1.0, 3.0]}]}],
            "coordinateTransformations": [{"type": "scale", "scale": [1.0, 2.0, 2.0, 2.0]}]}]});
        let group = json!({"zarr_format": 3, "node_type": "group", "attributes": {"ome": ome}});
        std::fs::write(v3.join("zarr.json"), group.to_string()).unwrap();
        let e = read_volume(&v3, VolumeOptions::default()).unwrap_err().to_string();
        assert!(e.contains("3 volumes; pick one with --volume K (0 to 2)"), "{e}");
        let file = reads(&v3, VolumeOptions { index: Some(2) }, &expected(2, false));
        assert_eq!(file.volume.spacing(), [6.0, 2.0, 2.0]);
        let e = read_volume(&v3, VolumeOptions { index: Some(3) }).unwrap_err().to_string();
        assert!(e.contains("--volume 3 is out of range"), "{e}");
    }

    #[test]
    fn what_is_not_a_volume_is_refused_with_the_reason() {
        let dir = tempfile::tempdir().unwrap();
        let refused = |path: &Path, options: VolumeOptions, want: &str| {
            let e = read_volume(path, options).unwrap_err().to_string();
            assert!(e.contains(want) && e.contains(&*path.to_string_lossy()), "{e}");
            let e = VolumeSlabs::open(path, options).err().unwrap().to_string();
            assert!(e.contains(want), "{e}");
        };
        let plain = dir.path().join("plain.zarr");
        write_array(&plain, 1, true, false);
        refused(&plain, VolumeOptions { index: Some(1) }, "holds one 3-D volume");

        let group = dir.path().join("group.zarr");
        write_array(&group.join("a"), 1, true, false);
        std::fs::write(group.join("zarr.json"), r#"{"zarr_format": 3, "node_type": "group", "attributes": {}}"#).unwrap();
        refused(&group, VolumeOptions::default(), "without OME-Zarr multiscales");
        // ... and the array inside it is read when named.
        reads(&group.join("a"), VolumeOptions::default(), &expected(0, false));

        let flat = dir.path().join("flat.zarr");
        std::fs::create_dir_all(&flat).unwrap();
        let meta = json!({"zarr_format": 3, "node_type": "array", "shape": [4, 4], "data_type": "uint8",
            "chunk_grid": {"name": "regular", "configuration": {"chunk_shape": [4, 4]}},
            "chunk_key_encoding": {"name": "default"}, "fill_value": 0, "codecs": [{"name": "bytes"}]});
        std::fs::write(flat.join("zarr.json"), meta.to_string()).unwrap();
        refused(&flat, VolumeOptions::default(), "has 2 dimensions");

        let boolean = dir.path().join("bool.zarr");
        std::fs::create_dir_all(&boolean).unwrap();
        let meta = json!({"zarr_format": 3, "node_type": "array", "shape": [2, 2, 2], "data_type": "bool",
            "chunk_grid": {"name": "regular", "configuration": {"chunk_shape": [2, 2, 2]}},
            "chunk_key_encoding": {"name": "default"}, "fill_value": false, "codecs": [{"name": "bytes"}]});
        std::fs::write(boolean.join("zarr.json"), meta.to_string()).unwrap();
        refused(&boolean, VolumeOptions::default(), "data type 'bool'");

        let broken = dir.path().join("broken.zarr");
        std::fs::create_dir_all(&broken).unwrap();
        std::fs::write(broken.join("zarr.json"), "{not json").unwrap();
        refused(&broken, VolumeOptions::default(), "neither a zarr array nor a zarr group");

        // A chunk file that is too short for its chunk: an error naming the slices, no panic.
        let short = dir.path().join("short.zarr");
        write_array(&short, 1, true, false);
        std::fs::write(short.join("c/0/0/0"), [1u8, 2, 3]).unwrap();
        let e = read_volume(&short, VolumeOptions::default()).unwrap_err().to_string();
        assert!(e.contains("z-slices 0..2 of 5"), "{e}");
    }
}
