//! Neuroglancer's precomputed mesh sources, written: the multi-resolution format
//! (`neuroglancer_multilod_draco`) and the legacy single-resolution one, following
//! `src/datasource/precomputed/meshes.md` and `sharded.md` in google/neuroglancer.
//!
//! - [`MultilodInfo`]: the source's `info` file (quantization bits, the stored-model-to-model
//!   transform, the LOD scale multiplier, the sharding specification, segment properties).
//! - [`Manifest`]: one segment's manifest (`<id>.index` unsharded): the octree's finest node
//!   shape and origin, per level of detail its scale, vertex offset and fragments, each
//!   fragment's position and byte size, fragments in Z-curve order ([`z_order_key`]).
//! - [`quantize_fragment`] maps stored-model positions into a fragment's box as integers in
//!   `[0, 2^bits)`, and [`encode_fragment`] Draco-encodes them as the spec asks: a 3-component
//!   32-bit integer position attribute, Draco's own quantization off (the `draco-core` crate).
//! - [`sharded`]: the `neuroglancer_uint64_sharded_v1` shards (MurmurHash3_x86_128, minishards,
//!   a gzip minishard index).
//! - [`legacy_fragment`] and [`legacy_manifest`]: the legacy format's fragment file and
//!   `<id>:0` file.
//!
//! What goes into the fragments (cut at their boxes, coarser levels) is the pipeline's
//! (`isolab_pipeline::neuroglancer`); this module only encodes.

pub mod sharded;

use draco_core::{DataType, EncoderBuffer, EncoderOptions, FaceIndex, GeometryAttributeType, Mesh, MeshEncoder, PointAttribute};
use glam::Vec3;
use serde_json::{json, Value};

pub use sharded::ShardingSpec;

/// The `@type` of a multi-resolution mesh source's `info`.
pub const MULTILOD_TYPE: &str = "neuroglancer_multilod_draco";

/// The `info` file of a multi-resolution mesh source.
#[derive(Clone, Debug, PartialEq)]
pub struct MultilodInfo {
    /// Bits per quantized vertex coordinate within a fragment: 10 or 16.
    pub vertex_quantization_bits: u32,
    /// The 4x3 homogeneous transform, row-major (3 rows of 4), from stored-model coordinates
    /// (ours: the label map's sample indices, x the fastest axis) to model coordinates.
    pub transform: [f64; 12],
    /// Multiplies every manifest's `lod_scales`.
    pub lod_scale_multiplier: f64,
    /// Sharded storage when given.
    pub sharding: Option<ShardingSpec>,
    /// The subdirectory holding segment properties, when written.
    pub segment_properties: Option<String>,
}

impl MultilodInfo {
    /// The identity transform: model coordinates are sample indices.
    pub const IDENTITY: [f64; 12] = [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];

    /// The `info` JSON.
    pub fn to_json(&self) -> Value {
        let mut v = json!({
            "@type": MULTILOD_TYPE,
            "vertex_quantization_bits": self.vertex_quantization_bits,
            "transform": self.transform.to_vec(),
            "lod_scale_multiplier": self.lod_scale_multiplier,
        });
        if let Some(s) = &self.sharding {
            v["sharding"] = s.to_json();
        }
        if let Some(p) = &self.segment_properties {
            v["segment_properties"] = json!(p);
        }
        v
    }
}

/// A `segment_properties` directory's `info`: each id's label (its name), inline.
pub fn segment_properties_json(names: &[(u64, String)]) -> Value {
    json!({
        "@type": "neuroglancer_segment_properties",
        "inline": {
            "ids": names.iter().map(|(id, _)| id.to_string()).collect::<Vec<_>>(),
            "properties": [{
                "id": "label",
                "type": "label",
                "values": names.iter().map(|(_, n)| n.clone()).collect::<Vec<_>>(),
            }],
        },
    })
}

/// The legacy source's `info`.
pub fn legacy_info_json() -> Value {
    json!({ "@type": "neuroglancer_legacy_mesh" })
}

/// One segment's manifest.
#[derive(Clone, Debug, PartialEq)]
pub struct Manifest {
    /// Extent of the finest octree node (level 0), stored-model units.
    pub chunk_shape: [f32; 3],
    /// Origin of the octree.
    pub grid_origin: [f32; 3],
    /// Per level: its scale (stored-model units, times the info's multiplier).
    pub lod_scales: Vec<f32>,
    /// Per level: an offset added to its vertices.
    pub vertex_offsets: Vec<[f32; 3]>,
    /// Per level: its fragments, `(position, bytes)`, in Z-curve order of position.
    pub fragments: Vec<Vec<([u32; 3], u32)>>,
}

impl Manifest {
    /// The manifest's bytes, as the spec lays them out (little endian).
    pub fn to_bytes(&self) -> Vec<u8> {
        let lods = self.lod_scales.len();
        let mut out = Vec::new();
        let f32s = |out: &mut Vec<u8>, v: &[f32]| v.iter().for_each(|x| out.extend_from_slice(&x.to_le_bytes()));
        f32s(&mut out, &self.chunk_shape);
        f32s(&mut out, &self.grid_origin);
        out.extend_from_slice(&(lods as u32).to_le_bytes());
        f32s(&mut out, &self.lod_scales);
        for o in &self.vertex_offsets {
            f32s(&mut out, o);
        }
        for level in &self.fragments {
            out.extend_from_slice(&(level.len() as u32).to_le_bytes());
        }
        for level in &self.fragments {
            // Positions as a C-order [3, n] array: every x, then every y, then every z.
            for a in 0..3 {
                level.iter().for_each(|(p, _)| out.extend_from_slice(&p[a].to_le_bytes()));
            }
            level.iter().for_each(|(_, n)| out.extend_from_slice(&n.to_le_bytes()));
        }
        out
    }

    /// Bytes of fragment data the manifest describes (the fragment file's length).
    pub fn data_len(&self) -> u64 {
        self.fragments.iter().flatten().map(|&(_, n)| u64::from(n)).sum()
    }

    /// Sorts every level's fragments into Z-curve order (the order their data must follow).
    pub fn sort_z_order(&mut self) {
        for level in &mut self.fragments {
            level.sort_by_key(|(p, _)| z_order_key(*p));
        }
    }
}

/// A fragment position's place on the Z curve: bits interleaved x, y, z from the lowest.
pub fn z_order_key(p: [u32; 3]) -> u128 {
    let mut key = 0u128;
    for bit in 0..32 {
        for (a, &c) in p.iter().enumerate() {
            key |= u128::from((c >> bit) & 1) << (3 * bit + a);
        }
    }
    key
}

/// Positions (stored-model units) as integers in a fragment's box `[lo, lo + size]`: each
/// coordinate `round((p - lo) / size * (2^bits - 1))`, clamped into `[0, 2^bits - 1]`. The box's
/// midplanes map to `2^(bits-1)`, where neuroglancer splits a fragment into its eight children.
pub fn quantize_fragment(positions: &[Vec3], lo: [f64; 3], size: [f64; 3], bits: u32) -> Vec<[i32; 3]> {
    let top = f64::from((1u32 << bits) - 1);
    positions
        .iter()
        .map(|p| {
            std::array::from_fn(|a| {
                let t = (f64::from(p[a]) - lo[a]) / size[a];
                (t * top).round().clamp(0.0, top) as i32
            })
        })
        .collect()
}

/// Draco-encodes a fragment: integer positions (a 3-component `INT32` position attribute, no
/// Draco quantization) and triangles. An empty fragment is zero bytes.
pub fn encode_fragment(positions: &[[i32; 3]], triangles: &[[u32; 3]]) -> Result<Vec<u8>, String> {
    if triangles.is_empty() {
        return Ok(Vec::new());
    }
    let mut mesh = Mesh::new();
    let mut att = PointAttribute::new();
    att.init(GeometryAttributeType::Position, 3, DataType::Int32, false, positions.len());
    let bytes: Vec<u8> = positions.iter().flat_map(|p| p.iter().flat_map(|v| v.to_le_bytes())).collect();
    att.buffer_mut().write(0, &bytes);
    mesh.add_attribute(att);
    mesh.set_num_faces(triangles.len());
    for (i, t) in triangles.iter().enumerate() {
        mesh.set_face(FaceIndex(i as u32), [t[0].into(), t[1].into(), t[2].into()]);
    }
    let mut encoder = MeshEncoder::new();
    encoder.set_mesh(mesh);
    let mut buffer = EncoderBuffer::new();
    encoder.encode(&EncoderOptions::new(), &mut buffer).map_err(|e| format!("Draco encoding failed: {e:?}"))?;
    Ok(buffer.data().to_vec())
}

/// A legacy fragment file: vertex count, float positions (model units), triangle indices.
pub fn legacy_fragment(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<u8> {
    let mut out = Vec::with_capacity(4 + 12 * (positions.len() + triangles.len()));
    out.extend_from_slice(&(positions.len() as u32).to_le_bytes());
    positions.iter().for_each(|p| p.to_array().iter().for_each(|v| out.extend_from_slice(&v.to_le_bytes())));
    triangles.iter().flatten().for_each(|v| out.extend_from_slice(&v.to_le_bytes()));
    out
}

/// A legacy `<id>:0` file naming the segment's fragment files.
pub fn legacy_manifest(fragments: &[String]) -> Value {
    json!({ "fragments": fragments })
}

#[cfg(test)]
mod tests {
    use super::*;
    use draco_core::{DecoderBuffer, MeshDecoder};

    #[test]
    fn z_order_interleaves_x_lowest() {
        assert_eq!(z_order_key([1, 0, 0]), 1);
        assert_eq!(z_order_key([0, 1, 0]), 2);
        assert_eq!(z_order_key([0, 0, 1]), 4);
        assert_eq!(z_order_key([2, 0, 0]), 8);
        assert!(z_order_key([1, 1, 1]) < z_order_key([2, 0, 0]));
    }

    #[test]
    fn quantization_puts_the_midplane_where_neuroglancer_splits() {
        let q = quantize_fragment(&[Vec3::new(0.0, 5.0, 10.0), Vec3::new(-3.0, 20.0, 9.0)], [0.0; 3], [10.0; 3], 10);
        assert_eq!(q[0], [0, 512, 1023]);
        assert_eq!(q[1], [0, 1023, 921]);
        let q16 = quantize_fragment(&[Vec3::splat(5.0)], [0.0; 3], [10.0; 3], 16);
        assert_eq!(q16[0], [32768; 3]);
    }

    #[test]
    fn manifest_bytes_follow_the_spec_layout() {
        let m = Manifest {
            chunk_shape: [8.0; 3],
            grid_origin: [-1.0; 3],
            lod_scales: vec![1.0, 2.0],
            vertex_offsets: vec![[0.0; 3]; 2],
            fragments: vec![vec![([0, 0, 0], 10), ([1, 0, 0], 20)], vec![([0, 0, 0], 7)]],
        };
        let b = m.to_bytes();
        let word = |i: usize| u32::from_le_bytes(b[4 * i..4 * i + 4].try_into().unwrap());
        let float = |i: usize| f32::from_le_bytes(b[4 * i..4 * i + 4].try_into().unwrap());
        assert_eq!(float(0), 8.0);
        assert_eq!(float(3), -1.0);
        assert_eq!(word(6), 2);
        assert_eq!((float(7), float(8)), (1.0, 2.0));
        assert_eq!((word(15), word(16)), (2, 1));
        // lod 0: x of both, y of both, z of both, then sizes.
        assert_eq!([word(17), word(18), word(19), word(20), word(21), word(22)], [0, 1, 0, 0, 0, 0]);
        assert_eq!([word(23), word(24)], [10, 20]);
        assert_eq!(b.len(), 4 * (3 + 3 + 1 + 2 + 6 + 2 + 8 + 4));
        assert_eq!(m.data_len(), 37);
    }

    #[test]
    fn fragments_decode_to_their_integer_positions() {
        let positions = vec![[0, 0, 0], [1023, 0, 0], [0, 1023, 0], [0, 0, 1023]];
        let triangles = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        let bytes = encode_fragment(&positions, &triangles).unwrap();
        let mut decoder = MeshDecoder::new();
        let mut mesh = Mesh::new();
        decoder.decode(&mut DecoderBuffer::new(&bytes), &mut mesh).unwrap();
        assert_eq!(mesh.num_faces(), 4);
        let att = mesh.named_attribute(GeometryAttributeType::Position).unwrap();
        assert_eq!(att.data_type(), DataType::Int32);
        let mut got: Vec<[i32; 3]> = (0..mesh.num_points())
            .map(|p| {
                let i = att.mapped_index(draco_core::PointIndex(p as u32)).0 as usize;
                std::array::from_fn(|a| {
                    let o = 12 * i + 4 * a;
                    i32::from_le_bytes(att.buffer().data()[o..o + 4].try_into().unwrap())
                })
            })
            .collect();
        got.sort_unstable();
        let mut want = positions.clone();
        want.sort_unstable();
        assert_eq!(got, want);
        assert!(encode_fragment(&positions, &[]).unwrap().is_empty());
    }
}
