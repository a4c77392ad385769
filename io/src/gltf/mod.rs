//! glTF 2.0, the format game engines and web viewers open: a writer for binary glTF (`.glb`)
//! and for `.gltf` with the buffer embedded as a base64 data URI, with positions, unit normals
//! and vertex colours (materials); and a reader for both (and for external `.bin` buffers), so
//! `isolab metrics` measures what it wrote.
//!
//! The `gltf` crate's JSON types (`gltf::json`) parse the document; the GLB container, the
//! scene walk and the accessors are read here with every index and byte range checked: the
//! crate's own validation indexed arrays unchecked and panicked on a mutated file (found by
//! `tests/tests/parsers.rs`), and its GLB reader subtracts lengths unchecked. The JSON is written
//! with `serde_json` (a dozen objects), the GLB container by the crate.
//!
//! Every file passes the Khronos glTF validator with no errors (`tests/reference/run.sh` runs it
//! on what `isolab extract` writes). Coordinates are written as they are: glTF's +Y is up, which
//! isolab's terrain follows; a scan's world (RAS: +Z up) is written unrotated.

use super::IoError;
use base64::Engine as _;
use glam::{Mat4, Vec3};
use isolab_algorithms::TriMesh;
use serde_json::json;
use std::borrow::Cow;
use std::io::Write;
use std::path::Path;

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_BYTE: u32 = 5121;
const UNSIGNED_INT: u32 = 5125;
const UNSIGNED_SHORT: u32 = 5123;
/// Bits of a quantized coordinate ([`write_glb_quantized`]).
pub const QUANT_BITS: u32 = 16;
/// The largest quantized coordinate.
const QUANT_MAX: f32 = ((1u32 << QUANT_BITS) - 1) as f32;

/// How the buffer is stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Container {
    /// Binary glTF: a JSON chunk and a BIN chunk in one file (`.glb`).
    Binary,
    /// JSON with the buffer as a base64 data URI (`.gltf`).
    Embedded,
}

/// Unit normals for glTF: the mesh's own when it has them, else area-weighted ones; a vertex
/// whose normal is undefined (only degenerate triangles around it) gets +Z, since the format
/// requires unit length.
fn unit_normals(mesh: &TriMesh) -> Vec<Vec3> {
    let normals = if mesh.normals.len() == mesh.positions.len() && !mesh.normals.is_empty() {
        mesh.normals.clone()
    } else {
        mesh.face_weighted_normals()
    };
    normals.into_iter().map(|n| n.try_normalize().unwrap_or(Vec3::Z)).collect()
}

/// Appends `bytes` to the buffer (4-byte aligned) as a new buffer view; its index.
fn push_view(bin: &mut Vec<u8>, views: &mut Vec<serde_json::Value>, bytes: &[u8], target: u32) -> usize {
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    views.push(json!({ "buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len(), "target": target }));
    bin.extend_from_slice(bytes);
    views.len() - 1
}

/// Appends a mesh's indices, positions and unit normals to the buffer, a view and an accessor
/// each (accessors `a`, `a + 1`, `a + 2`); returns `a`.
fn push_mesh(
    bin: &mut Vec<u8>,
    views: &mut Vec<serde_json::Value>,
    accessors: &mut Vec<serde_json::Value>,
    mesh: &TriMesh,
) -> usize {
    let indices: Vec<u8> = mesh.triangles.iter().flatten().flat_map(|i| i.to_le_bytes()).collect();
    let positions: Vec<u8> = mesh.positions.iter().flat_map(|p| p.to_array()).flat_map(f32::to_le_bytes).collect();
    let normals: Vec<u8> = unit_normals(mesh).iter().flat_map(|n| n.to_array()).flat_map(f32::to_le_bytes).collect();
    let (min, max) = mesh
        .positions
        .iter()
        .fold((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let max_index = mesh.triangles.iter().flatten().copied().max().unwrap_or(0);
    let min_index = mesh.triangles.iter().flatten().copied().min().unwrap_or(0);
    let vi = push_view(bin, views, &indices, ELEMENT_ARRAY_BUFFER);
    let vp = push_view(bin, views, &positions, ARRAY_BUFFER);
    let vn = push_view(bin, views, &normals, ARRAY_BUFFER);
    let n = mesh.positions.len();
    let a = accessors.len();
    accessors.push(json!({ "bufferView": vi, "componentType": UNSIGNED_INT, "count": 3 * mesh.triangles.len(), "type": "SCALAR",
                           "min": [min_index], "max": [max_index] }));
    accessors.push(json!({ "bufferView": vp, "componentType": FLOAT, "count": n, "type": "VEC3",
                           "min": min.to_array(), "max": max.to_array() }));
    accessors.push(json!({ "bufferView": vn, "componentType": FLOAT, "count": n, "type": "VEC3" }));
    a
}

/// The glTF JSON and its binary buffer for `mesh` (vertex colours from `colours`).
fn document(mesh: &TriMesh, colours: Option<&[[u8; 3]]>, generator: &str) -> (serde_json::Value, Vec<u8>) {
    let asset = json!({ "version": "2.0", "generator": generator });
    if mesh.triangles.is_empty() || mesh.positions.is_empty() {
        // A glTF accessor cannot be empty: an empty mesh is a scene of one empty node (the
        // validator refuses an empty node list, the `gltf` crate a scene without one).
        return (
            json!({ "asset": asset, "scene": 0, "scenes": [{ "nodes": [0] }], "nodes": [{ "name": "isolab (empty mesh)" }] }),
            Vec::new(),
        );
    }
    let mut bin = Vec::new();
    let mut views = Vec::new();
    let mut accessors = Vec::new();
    push_mesh(&mut bin, &mut views, &mut accessors, mesh);
    let n = mesh.positions.len();
    let mut attributes = json!({ "POSITION": 1, "NORMAL": 2 });
    let colours = colours.filter(|c| c.len() == n);
    if let Some(colours) = colours {
        // RGBA: vertex attribute elements must be 4-byte aligned, which RGB bytes are not.
        let rgba: Vec<u8> = colours.iter().flat_map(|&[r, g, b]| [r, g, b, 255]).collect();
        let view = push_view(&mut bin, &mut views, &rgba, ARRAY_BUFFER);
        accessors
            .push(json!({ "bufferView": view, "componentType": UNSIGNED_BYTE, "normalized": true, "count": n, "type": "VEC4" }));
        attributes["COLOR_0"] = json!(3);
    }
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let base = if colours.is_some() { [1.0, 1.0, 1.0, 1.0] } else { [0.8, 0.8, 0.8, 1.0] };
    let doc = json!({
        "asset": asset,
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0, "name": "isolab" }],
        "meshes": [{ "primitives": [{ "attributes": attributes, "indices": 0, "material": 0, "mode": 4 }] }],
        "materials": [{ "pbrMetallicRoughness": { "baseColorFactor": base, "metallicFactor": 0.0, "roughnessFactor": 0.8 } }],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{ "byteLength": bin.len() }],
    });
    (doc, bin)
}

/// Writes `mesh` as glTF 2.0 (`.glb` or `.gltf` with an embedded buffer).
pub fn write_gltf(
    w: &mut impl Write,
    mesh: &TriMesh,
    colours: Option<&[[u8; 3]]>,
    container: Container,
    generator: &str,
) -> std::io::Result<()> {
    let (mut doc, bin) = document(mesh, colours, generator);
    match container {
        Container::Binary => write_glb(w, &doc, bin),
        Container::Embedded => {
            if !bin.is_empty() {
                let uri =
                    format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(&bin));
                doc["buffers"][0]["uri"] = json!(uri);
            }
            serde_json::to_writer(&mut *w, &doc).map_err(std::io::Error::other)?;
            w.write_all(b"\n")
        }
    }
}

/// One named, coloured mesh of a scene ([`write_glb_parts`]).
#[derive(Clone, Copy, Debug)]
pub struct Part<'a> {
    /// The node's name (a viewer lists it).
    pub name: &'a str,
    /// Its mesh.
    pub mesh: &'a TriMesh,
    /// Its material's colour (sRGB).
    pub colour: [u8; 3],
}

/// Writes `parts` as one binary glTF: a node per part, named, with its own material colour (a
/// segmentation's labels, say). Parts without triangles are left out; with none left the file is
/// one empty node, as [`write_gltf`] writes an empty mesh.
pub fn write_glb_parts(w: &mut impl Write, parts: &[Part<'_>], generator: &str) -> std::io::Result<()> {
    let parts: Vec<&Part<'_>> = parts.iter().filter(|p| !p.mesh.triangles.is_empty() && !p.mesh.positions.is_empty()).collect();
    if parts.is_empty() {
        let (doc, bin) = document(&TriMesh::default(), None, generator);
        return write_glb(w, &doc, bin);
    }
    let mut bin = Vec::new();
    let (mut views, mut accessors, mut nodes, mut meshes, mut materials) = (vec![], vec![], vec![], vec![], vec![]);
    for (k, part) in parts.iter().enumerate() {
        let a = push_mesh(&mut bin, &mut views, &mut accessors, part.mesh);
        meshes.push(
            json!({ "name": part.name, "primitives": [{ "attributes": { "POSITION": a + 1, "NORMAL": a + 2 }, "indices": a,
                                                                "material": k, "mode": 4 }] }),
        );
        // glTF colour factors are linear; the part's colour is sRGB.
        let linear = part.colour.map(|c| {
            let c = f64::from(c) / 255.0;
            if c <= 0.04045 {
                c / 12.92
            } else {
                ((c + 0.055) / 1.055).powf(2.4)
            }
        });
        materials.push(json!({ "name": part.name, "pbrMetallicRoughness": {
            "baseColorFactor": [linear[0], linear[1], linear[2], 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.8 } }));
        nodes.push(json!({ "mesh": k, "name": part.name }));
    }
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let doc = json!({
        "asset": { "version": "2.0", "generator": generator },
        "scene": 0,
        "scenes": [{ "nodes": (0..nodes.len()).collect::<Vec<_>>() }],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{ "byteLength": bin.len() }],
    });
    write_glb(w, &doc, bin)
}

/// Writes `mesh` as a small binary glTF for web viewers: positions quantized to 16 bits over the
/// mesh's bounding box (`KHR_mesh_quantization`; the node's translation and scale map them back,
/// so the error is at most half a box / 65535 per axis), 16-bit indices where they fit, and no
/// normals (a viewer computes them). About a third of [`write_gltf`]'s bytes.
pub fn write_glb_quantized(w: &mut impl Write, mesh: &TriMesh, generator: &str) -> std::io::Result<()> {
    let (doc, bin) = quantized_document(mesh, generator);
    write_glb(w, &doc, bin)
}

/// The GLB container (the crate's writer): a JSON chunk and, when there is one, a BIN chunk.
fn write_glb(w: &mut impl Write, doc: &serde_json::Value, bin: Vec<u8>) -> std::io::Result<()> {
    let json = serde_json::to_vec(doc).map_err(std::io::Error::other)?;
    let glb = gltf::binary::Glb {
        header: gltf::binary::Header { magic: *b"glTF", version: 2, length: 0 },
        json: Cow::Owned(json),
        bin: (!bin.is_empty()).then_some(Cow::Owned(bin)),
    };
    glb.to_writer(w).map_err(std::io::Error::other)
}

/// The quantized glTF JSON and buffer (see [`write_glb_quantized`]).
fn quantized_document(mesh: &TriMesh, generator: &str) -> (serde_json::Value, Vec<u8>) {
    if mesh.triangles.is_empty() || mesh.positions.is_empty() {
        return document(mesh, None, generator);
    }
    let (lo, hi) = mesh
        .positions
        .iter()
        .fold((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let extent = (hi - lo).max(Vec3::splat(f32::MIN_POSITIVE));
    let quantized: Vec<[u16; 3]> = mesh
        .positions
        .iter()
        .map(|&p| ((p - lo) / extent * QUANT_MAX).round().clamp(Vec3::ZERO, Vec3::splat(QUANT_MAX)).to_array().map(|c| c as u16))
        .collect();
    let mut bin = Vec::new();
    let wide = mesh.positions.len() > usize::from(u16::MAX);
    for &i in mesh.triangles.iter().flatten() {
        if wide {
            bin.extend_from_slice(&i.to_le_bytes());
        } else {
            bin.extend_from_slice(&(i as u16).to_le_bytes());
        }
    }
    let index_bytes = bin.len();
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let position_offset = bin.len();
    for q in &quantized {
        // Vertex attribute elements are 4-byte aligned: three shorts and two bytes of padding.
        for c in q {
            bin.extend_from_slice(&c.to_le_bytes());
        }
        bin.extend_from_slice(&[0, 0]);
    }
    let (qmin, qmax) = quantized.iter().fold(([u16::MAX; 3], [0u16; 3]), |(mut a, mut b), q| {
        for k in 0..3 {
            a[k] = a[k].min(q[k]);
            b[k] = b[k].max(q[k]);
        }
        (a, b)
    });
    let max_index = mesh.triangles.iter().flatten().copied().max().unwrap_or(0);
    let min_index = mesh.triangles.iter().flatten().copied().min().unwrap_or(0);
    let scale = extent / QUANT_MAX;
    let doc = json!({
        "asset": { "version": "2.0", "generator": generator },
        "extensionsUsed": ["KHR_mesh_quantization"],
        "extensionsRequired": ["KHR_mesh_quantization"],
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0, "name": "isolab", "translation": lo.to_array(), "scale": scale.to_array() }],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 1 }, "indices": 0, "material": 0, "mode": 4 }] }],
        "materials": [{ "pbrMetallicRoughness": { "baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.8 } }],
        "accessors": [
            { "bufferView": 0, "componentType": if wide { UNSIGNED_INT } else { UNSIGNED_SHORT }, "count": 3 * mesh.triangles.len(),
              "type": "SCALAR", "min": [min_index], "max": [max_index] },
            { "bufferView": 1, "componentType": UNSIGNED_SHORT, "count": quantized.len(), "type": "VEC3",
              "min": qmin, "max": qmax },
        ],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": index_bytes, "target": ELEMENT_ARRAY_BUFFER },
            { "buffer": 0, "byteOffset": position_offset, "byteLength": bin.len() - position_offset, "byteStride": 8,
              "target": ARRAY_BUFFER },
        ],
        "buffers": [{ "byteLength": bin.len() }],
    });
    (doc, bin)
}

/// Parses the bytes of the glTF file at `path`, already read; external buffers are read beside it.
pub fn parse_gltf_beside(bytes: &[u8], path: &Path) -> Result<TriMesh, IoError> {
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    parse_gltf(bytes, path, &|uri: &str| {
        let file = dir.join(uri);
        std::fs::read(&file).map_err(|e| format!("cannot read buffer '{}': {e}", file.display()))
    })
}

/// Splits a GLB into its JSON and BIN chunks, with checked lengths.
fn split_glb(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>), String> {
    let word = |at: usize| bytes.get(at..at + 4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize);
    let version = word(4).ok_or("the GLB header is cut short")?;
    if version != 2 {
        return Err(format!("GLB version {version}, only 2 is read"));
    }
    let length = word(8).ok_or("the GLB header is cut short")?.min(bytes.len());
    let mut at = 12;
    let mut chunk = |kind: &[u8; 4]| -> Result<Option<&[u8]>, String> {
        if at + 8 > length {
            return Ok(None);
        }
        let size = word(at).ok_or("a chunk header is cut short")?;
        if &bytes[at + 4..at + 8] != kind {
            return Err(format!("expected a {} chunk at byte {at}", String::from_utf8_lossy(kind)));
        }
        let data = bytes.get(at + 8..at + 8 + size).filter(|_| at + 8 + size <= length).ok_or_else(|| {
            format!("the {} chunk at byte {at} has {size} bytes, past the file's end", String::from_utf8_lossy(kind))
        })?;
        at += 8 + size;
        Ok(Some(data))
    };
    let json = chunk(b"JSON")?.ok_or("the GLB has no JSON chunk")?;
    let bin = chunk(b"BIN\0")?;
    Ok((json, bin))
}

/// Parses glTF or GLB bytes; `external` reads a buffer given by a relative URI (return an error
/// to refuse). `path` is only used in error messages. Every index and byte range in the file is
/// checked here: the `gltf` crate's validation indexes arrays unchecked (it panicked on a
/// mutated file), so only its JSON types are used.
pub fn parse_gltf(bytes: &[u8], path: &Path, external: &dyn Fn(&str) -> Result<Vec<u8>, String>) -> Result<TriMesh, IoError> {
    use gltf::json::accessor::Type;
    use gltf::json::mesh::{Mode, Semantic};
    use gltf::json::validation::Checked;
    let invalid = |reason: String| IoError::Invalid { path: path.into(), reason };
    let (json, blob) = if bytes.starts_with(b"glTF") { split_glb(bytes).map_err(&invalid)? } else { (bytes, None) };
    let root = gltf::json::Root::from_slice(json).map_err(|e| invalid(format!("not valid glTF JSON: {e}")))?;
    let mut buffers = Vec::new();
    for (i, buffer) in root.buffers.iter().enumerate() {
        let data = match &buffer.uri {
            None => {
                blob.map(<[u8]>::to_vec).ok_or_else(|| invalid(format!("buffer {i} refers to a GLB BIN chunk the file lacks")))?
            }
            Some(uri) if uri.starts_with("data:") => {
                let (_, payload) =
                    uri.split_once(";base64,").ok_or_else(|| invalid(format!("buffer {i}: a data URI that is not base64")))?;
                base64::engine::general_purpose::STANDARD
                    .decode(payload)
                    .map_err(|e| invalid(format!("buffer {i}: bad base64: {e}")))?
            }
            Some(uri) => external(uri).map_err(&invalid)?,
        };
        if (data.len() as u64) < buffer.byte_length.0 {
            return Err(invalid(format!("buffer {i} has {} bytes, the file says {}", data.len(), buffer.byte_length.0)));
        }
        buffers.push(data);
    }
    let mut mesh = TriMesh::default();
    let mut add = |m: usize, to_world: Mat4| -> Result<(), IoError> {
        let json_mesh = root.meshes.get(m).ok_or_else(|| invalid(format!("a node refers to mesh {m}, which does not exist")))?;
        for (k, primitive) in json_mesh.primitives.iter().enumerate() {
            let mode = match primitive.mode {
                Checked::Valid(mode) => mode,
                Checked::Invalid => return Err(invalid(format!("mesh {m} primitive {k}: unknown mode"))),
            };
            if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
                continue;
            }
            let position = primitive
                .attributes
                .get(&Checked::Valid(Semantic::Positions))
                .ok_or_else(|| invalid(format!("mesh {m} primitive {k} has no POSITION")))?;
            let accessor =
                root.accessors.get(position.value()).ok_or_else(|| invalid(format!("mesh {m}: POSITION accessor missing")))?;
            if accessor.type_ != Checked::Valid(Type::Vec3) {
                return Err(invalid(format!("mesh {m} POSITION is not VEC3")));
            }
            let points =
                read_accessor(&root, position.value(), &buffers).map_err(|e| invalid(format!("mesh {m} POSITION: {e}")))?;
            let base = mesh.positions.len() as u32;
            mesh.positions.extend(
                points.chunks_exact(3).map(|c| to_world.transform_point3(Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32))),
            );
            let count = points.len() / 3;
            let order: Vec<u32> = match primitive.indices {
                Some(a) => read_accessor(&root, a.value(), &buffers)
                    .map_err(|e| invalid(format!("mesh {m} indices: {e}")))?
                    .iter()
                    .map(|&v| v as u32)
                    .collect(),
                None => (0..count as u32).collect(),
            };
            if let Some(&bad) = order.iter().find(|&&i| i as usize >= count) {
                return Err(invalid(format!("mesh {m}: index {bad} is out of range ({count} vertices)")));
            }
            let mirrored = to_world.determinant() < 0.0;
            let mut push = |mut t: [u32; 3]| {
                if mirrored {
                    t.swap(1, 2);
                }
                mesh.triangles.push(t.map(|i| base + i));
            };
            match mode {
                Mode::Triangles => order.chunks_exact(3).for_each(|t| push([t[0], t[1], t[2]])),
                Mode::TriangleStrip => {
                    for (k, w) in order.windows(3).enumerate() {
                        push(if k % 2 == 0 { [w[0], w[1], w[2]] } else { [w[1], w[0], w[2]] });
                    }
                }
                _ => {
                    for k in 2..order.len() {
                        push([order[0], order[k - 1], order[k]]);
                    }
                }
            }
        }
        Ok(())
    };
    let scene = root.scene.map(|s| s.value()).or((!root.scenes.is_empty()).then_some(0));
    match scene {
        Some(s) => {
            let scene = root.scenes.get(s).ok_or_else(|| invalid(format!("scene {s} does not exist")))?;
            let mut stack: Vec<(usize, Mat4, usize)> = scene.nodes.iter().map(|n| (n.value(), Mat4::IDENTITY, 0)).collect();
            while let Some((n, parent, depth)) = stack.pop() {
                if depth > 64 {
                    return Err(invalid("the node hierarchy is deeper than 64 levels (a cycle?)".into()));
                }
                let node = root.nodes.get(n).ok_or_else(|| invalid(format!("node {n} does not exist")))?;
                let local = match node.matrix {
                    Some(m) => Mat4::from_cols_array(&m),
                    None => Mat4::from_scale_rotation_translation(
                        Vec3::from(node.scale.unwrap_or([1.0; 3])),
                        glam::Quat::from_array(node.rotation.map_or([0.0, 0.0, 0.0, 1.0], |r| r.0)),
                        Vec3::from(node.translation.unwrap_or([0.0; 3])),
                    ),
                };
                let world = parent * local;
                if let Some(m) = node.mesh {
                    add(m.value(), world)?;
                }
                stack.extend(node.children.iter().flatten().map(|c| (c.value(), world, depth + 1)));
            }
        }
        None => {
            for m in 0..root.meshes.len() {
                add(m, Mat4::IDENTITY)?;
            }
        }
    }
    if mesh.triangles.is_empty() {
        return Err(IoError::Empty { path: path.into(), vertices: mesh.positions.len() });
    }
    Ok(mesh)
}

/// Accessor `index`'s components as f64 (exact for every component type), with every index and
/// byte range checked.
fn read_accessor(root: &gltf::json::Root, index: usize, buffers: &[Vec<u8>]) -> Result<Vec<f64>, String> {
    use gltf::json::accessor::{ComponentType, Type};
    use gltf::json::validation::Checked;
    let a = root.accessors.get(index).ok_or_else(|| format!("accessor {index} does not exist"))?;
    if a.sparse.is_some() {
        return Err("sparse accessors are not supported".into());
    }
    let view_index = a.buffer_view.ok_or("the accessor has no buffer view")?.value();
    let view = root.buffer_views.get(view_index).ok_or_else(|| format!("buffer view {view_index} does not exist"))?;
    let data = buffers.get(view.buffer.value()).ok_or("the buffer view's buffer does not exist")?;
    let components = match a.type_ {
        Checked::Valid(Type::Scalar) => 1,
        Checked::Valid(Type::Vec2) => 2,
        Checked::Valid(Type::Vec3) => 3,
        Checked::Valid(Type::Vec4) | Checked::Valid(Type::Mat2) => 4,
        Checked::Valid(Type::Mat3) => 9,
        Checked::Valid(Type::Mat4) => 16,
        Checked::Invalid => return Err("unknown accessor type".into()),
    };
    let (size, read): (usize, fn(&[u8]) -> f64) = match a.component_type {
        Checked::Valid(gltf::json::accessor::GenericComponentType(c)) => match c {
            ComponentType::F32 => (4, |b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64),
            ComponentType::U32 => (4, |b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64),
            ComponentType::U16 => (2, |b| u16::from_le_bytes([b[0], b[1]]) as f64),
            ComponentType::U8 => (1, |b| b[0] as f64),
            ComponentType::I16 => (2, |b| i16::from_le_bytes([b[0], b[1]]) as f64),
            ComponentType::I8 => (1, |b| b[0] as i8 as f64),
        },
        Checked::Invalid => return Err("unknown component type".into()),
    };
    let element = size * components;
    let stride = view.byte_stride.map_or(element, |s| s.0).max(element);
    let to_usize = |v: u64| usize::try_from(v).map_err(|_| "an offset is too large".to_string());
    let view_start = to_usize(view.byte_offset.map_or(0, |o| o.0))?;
    let view_end = view_start.checked_add(to_usize(view.byte_length.0)?).ok_or("the view overflows")?;
    let start = view_start.checked_add(to_usize(a.byte_offset.map_or(0, |o| o.0))?).ok_or("the offset overflows")?;
    let count = to_usize(a.count.0)?;
    if count == 0 {
        return Ok(Vec::new());
    }
    let end = (count - 1)
        .checked_mul(stride)
        .and_then(|s| s.checked_add(start))
        .and_then(|s| s.checked_add(element))
        .ok_or("the accessor's range overflows")?;
    if end > view_end || end > data.len() {
        return Err(format!("{count} elements need bytes {start}..{end}, beyond the buffer view"));
    }
    let mut out = Vec::with_capacity(count * components);
    for k in 0..count {
        let at = start + k * stride;
        for c in 0..components {
            out.push(read(&data[at + c * size..]));
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests;
