//! Neuroglancer's sharded storage (`neuroglancer_uint64_sharded_v1`, google/neuroglancer
//! `src/datasource/precomputed/sharded.md`): chunk ids (segment ids for meshes) hashed by
//! MurmurHash3_x86_128 into shards and minishards; each `<shard>.shard` file is a fixed shard
//! index, then the chunks' data, then each minishard's index (gzip), whose entries are delta
//! encoded. For multi-resolution meshes a segment's chunk is its manifest, and its fragment
//! data lies just before it, unindexed ([`ShardEntry::prefix_len`]).

use std::io::{self, Write};

use flate2::write::GzEncoder;
use serde_json::{json, Value};

/// A sharding specification (murmurhash3_x86_128, gzip minishard indices, raw data).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ShardingSpec {
    /// Low bits of a chunk id left out of the hash.
    pub preshift_bits: u32,
    /// Bits of the hash that pick the minishard.
    pub minishard_bits: u32,
    /// Bits above those that pick the shard.
    pub shard_bits: u32,
}

impl ShardingSpec {
    /// A specification for `segments` segments: minishard indices of about 64 entries, and
    /// shards of up to about 16 k segments (a large volume is a few hundred files, not millions).
    pub fn for_segments(segments: usize) -> Self {
        let bits = |n: usize| if n <= 1 { 0 } else { usize::BITS - (n - 1).leading_zeros() };
        let total = bits(segments.div_ceil(64));
        let shard_bits = bits(segments.div_ceil(16 * 1024)).min(total);
        Self { preshift_bits: 0, minishard_bits: total - shard_bits, shard_bits }
    }

    /// The `sharding` member of an `info` file.
    pub fn to_json(&self) -> Value {
        json!({
            "@type": "neuroglancer_uint64_sharded_v1",
            "preshift_bits": self.preshift_bits,
            "hash": "murmurhash3_x86_128",
            "minishard_bits": self.minishard_bits,
            "shard_bits": self.shard_bits,
            "minishard_index_encoding": "gzip",
            "data_encoding": "raw",
        })
    }

    /// The hashed chunk id: the low 64 bits (little endian) of MurmurHash3_x86_128, seed 0, of
    /// `id >> preshift_bits` as 8 little-endian bytes.
    pub fn hashed(&self, id: u64) -> u64 {
        let key = (id >> self.preshift_bits).to_le_bytes();
        murmur3::murmur3_x86_128(&mut &key[..], 0).map(|h| h as u64).unwrap_or(0)
    }

    /// The minishard of chunk `id`.
    pub fn minishard(&self, id: u64) -> u64 {
        self.hashed(id) & ((1u64 << self.minishard_bits) - 1)
    }

    /// The shard of chunk `id`.
    pub fn shard(&self, id: u64) -> u64 {
        (self.hashed(id) >> self.minishard_bits) & ((1u64 << self.shard_bits) - 1)
    }

    /// The number of shards.
    pub fn shards(&self) -> u64 {
        1u64 << self.shard_bits
    }

    /// Shard `shard`'s file name: lowercase hex zero-padded to `ceil(shard_bits / 4)` digits.
    pub fn file_name(&self, shard: u64) -> String {
        let digits = self.shard_bits.div_ceil(4) as usize;
        format!("{shard:0digits$x}.shard")
    }
}

/// One chunk of a shard: its id, the unindexed bytes before it and its own bytes' length.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ShardEntry {
    /// The chunk id (segment id).
    pub id: u64,
    /// Bytes written just before the chunk, not in the index (a mesh's fragment data).
    pub prefix_len: u64,
    /// The chunk's bytes (a mesh's manifest).
    pub len: u64,
}

/// Writes one shard: `entries` (all of this shard, any order; ids distinct), and for each, in
/// the order the shard needs, `write(entry, w)` writes its prefix then its chunk, exactly
/// `prefix_len + len` bytes (checked). Entries are laid out by minishard, then by id.
pub fn write_shard<W: Write>(
    w: &mut W,
    spec: &ShardingSpec,
    entries: &[ShardEntry],
    mut write: impl FnMut(&ShardEntry, &mut CountingWriter<&mut W>) -> io::Result<()>,
) -> io::Result<()> {
    let minishards = 1usize << spec.minishard_bits;
    let mut sorted: Vec<(u64, ShardEntry)> = entries.iter().map(|e| (spec.minishard(e.id), *e)).collect();
    sorted.sort_unstable_by_key(|&(m, e)| (m, e.id));
    // Offsets relative to the end of the shard index: data first, minishard indices after.
    let mut indices: Vec<Vec<[u64; 3]>> = vec![Vec::new(); minishards];
    let mut at = 0u64;
    for &(m, e) in &sorted {
        at += e.prefix_len;
        indices[m as usize].push([e.id, at, e.len]);
        at += e.len;
    }
    let mut encoded = Vec::with_capacity(minishards);
    for rows in &indices {
        if rows.is_empty() {
            encoded.push(Vec::new());
            continue;
        }
        // A [3, n] array: delta ids, delta starts (after the previous chunk's end), sizes.
        let mut raw = Vec::with_capacity(24 * rows.len());
        let (mut last_id, mut last_end) = (0u64, 0u64);
        for r in rows {
            raw.extend_from_slice(&r[0].wrapping_sub(last_id).to_le_bytes());
            last_id = r[0];
        }
        for r in rows {
            raw.extend_from_slice(&(r[1] - last_end).to_le_bytes());
            last_end = r[1] + r[2];
        }
        for r in rows {
            raw.extend_from_slice(&r[2].to_le_bytes());
        }
        let mut gz = GzEncoder::new(Vec::new(), flate2::Compression::default());
        gz.write_all(&raw)?;
        encoded.push(gz.finish()?);
    }
    let mut index_at = at;
    for e in &encoded {
        w.write_all(&index_at.to_le_bytes())?;
        index_at += e.len() as u64;
        w.write_all(&index_at.to_le_bytes())?;
    }
    let mut counting = CountingWriter { inner: w, written: 0 };
    for (_, e) in &sorted {
        let before = counting.written;
        write(e, &mut counting)?;
        if counting.written - before != e.prefix_len + e.len {
            return Err(io::Error::other(format!(
                "segment {}: {} bytes written for a chunk of {} + {}",
                e.id,
                counting.written - before,
                e.prefix_len,
                e.len
            )));
        }
    }
    for e in &encoded {
        counting.write_all(e)?;
    }
    Ok(())
}

/// A writer that counts the bytes through it.
pub struct CountingWriter<W> {
    inner: W,
    written: u64,
}

impl<W: Write> Write for CountingWriter<W> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.written += n as u64;
        Ok(n)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.inner.flush()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use flate2::read::GzDecoder;
    use std::io::Read;

    #[test]
    fn murmurhash_matches_the_reference_vectors() {
        // The low 64 bits of MurmurHash3_x86_128 (seed 0) of ids as 8 little-endian bytes, from
        // the reference C++ implementation (Python's mmh3 5.3.1, `hash64(..., x64arch=False)`).
        let spec = ShardingSpec { preshift_bits: 0, minishard_bits: 6, shard_bits: 2 };
        assert_eq!(spec.hashed(0), 0x4772_b084_e028_ae41);
        assert_eq!(spec.hashed(1), 0xe8bd_67d6_16d4_ce9a);
        assert_eq!(spec.hashed(123_456_789), 0x1265_76fc_191a_1827);
        assert_eq!(ShardingSpec { preshift_bits: 3, ..spec }.hashed(8), spec.hashed(1));
        assert_eq!(spec.file_name(3), "3.shard");
        assert_eq!(ShardingSpec { shard_bits: 9, ..spec }.file_name(10), "00a.shard");
        assert_eq!(ShardingSpec { shard_bits: 0, ..spec }.file_name(0), "0.shard");
    }

    #[test]
    fn a_shard_reads_back_through_its_indices() {
        let spec = ShardingSpec { preshift_bits: 0, minishard_bits: 2, shard_bits: 0 };
        let entries: Vec<ShardEntry> = (1..20u64).map(|id| ShardEntry { id, prefix_len: id % 3, len: id }).collect();
        let mut out = Vec::new();
        write_shard(&mut out, &spec, &entries, |e, w| {
            w.write_all(&vec![0xEE; e.prefix_len as usize])?;
            w.write_all(&vec![e.id as u8; e.len as usize])
        })
        .unwrap();
        let end = 16 * 4;
        let word = |b: &[u8], i: usize| u64::from_le_bytes(b[8 * i..8 * i + 8].try_into().unwrap());
        let mut found = 0;
        for m in 0..4 {
            let (s, e) = (word(&out, 2 * m) as usize + end, word(&out, 2 * m + 1) as usize + end);
            if s == e {
                continue;
            }
            let mut raw = Vec::new();
            GzDecoder::new(&out[s..e]).read_to_end(&mut raw).unwrap();
            let n = raw.len() / 24;
            let (mut id, mut at) = (0u64, end as u64);
            for i in 0..n {
                id += word(&raw, i);
                at += word(&raw, n + i);
                let len = word(&raw, 2 * n + i);
                assert_eq!(spec.minishard(id), m as u64);
                assert_eq!(len, id);
                assert!(out[at as usize..(at + len) as usize].iter().all(|&b| b == id as u8));
                at += len;
                found += 1;
            }
        }
        assert_eq!(found, 19);
    }
}
