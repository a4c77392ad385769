//! Sign-change summaries of x-rows of samples, shared by the cubic-grid extractors, that let them
//! skip rows, edges and cells that cannot hold surface (the trimming idea of Schroeder, Maynard &
//! Geveci, "Flying edges", LDAV 2015): [`classify_rows`] as a first pass over a whole block (the
//! tetrahedral engine), and, per sample layer as a sweep reaches it, the inside/outside state of every
//! sample packed 64 to a word ([`LayerSigns`]), so that crossing edges and surface cells are found
//! by word operations over 64 samples at a time and only those are visited one by one.

use crate::samples::{GridView, Sample};
use rayon::prelude::*;

/// Sign-change summary of one x-row of samples.
#[derive(Clone, Copy, Debug, Default)]
pub struct Row {
    /// First x whose inside/outside state differs from sample 0's (`u32::MAX` when uniform).
    pub first: u32,
    /// Last such x (`0` when uniform).
    pub last: u32,
    /// Whether sample 0 is inside.
    pub inside: bool,
}

impl Row {
    /// Whether every sample of the row has the same state.
    pub fn is_uniform(&self) -> bool {
        self.first > self.last
    }
}

/// The inclusive x-range of samples where any of `rows` may differ from the others or from
/// itself, or `None` when they are all uniform and agree.
pub fn span(rows: &[Row], nx: usize) -> Option<(usize, usize)> {
    let inside = rows[0].inside;
    if rows.iter().any(|r| r.inside != inside) {
        return Some((0, nx - 1));
    }
    let first = rows.iter().map(|r| r.first).min().unwrap_or(u32::MAX);
    let last = rows.iter().map(|r| r.last).max().unwrap_or(0);
    (first <= last).then_some((first as usize, last as usize))
}

/// Classifies every x-row of `values` (rows of `nx` samples, in order) into `rows`.
pub fn classify_rows(values: &[f32], nx: usize, iso: f32, rows: &mut Vec<Row>) {
    rows.clear();
    rows.resize(values.len() / nx, Row::default());
    rows.par_iter_mut().zip(values.par_chunks(nx)).for_each(|(row, v)| {
        let inside = v[0] < iso;
        let first = v.iter().position(|&s| (s < iso) != inside);
        *row = match first {
            None => Row { first: u32::MAX, last: 0, inside },
            Some(f) => {
                let last = v.iter().rposition(|&s| (s < iso) != inside).unwrap_or(f);
                Row { first: f as u32, last: last as u32, inside }
            }
        };
    });
}

/// The row summaries and inside bits (`value < iso`, one bit per sample, 64 to a word) of the two
/// sample layers a sweep along z is between, classified as the sweep reaches each layer, so the
/// layer's samples are still in cache when the surface near them is built; or, after
/// [`LayerSigns::reset_span`], of every layer of a slab, so a counting pass and the sweep that
/// follows it classify each sample once. Each bit row has one word past its samples that is always
/// zero, so a row can be read one word past its end.
#[derive(Clone, Debug, Default)]
pub struct LayerSigns {
    ny: usize,
    words: usize,
    /// The first layer of a span ([`LayerSigns::reset_span`]); `usize::MAX` for two slots taken
    /// in turn.
    first: usize,
    /// The layer each slot holds (`usize::MAX`: none).
    held: Vec<usize>,
    rows: Vec<Row>,
    bits: Vec<u64>,
    /// The first row `(y, z)` classified since the last reset with a sample that is not finite.
    non_finite: Option<(usize, usize)>,
}

impl LayerSigns {
    /// Forgets the held layers and sizes two slots, taken in turn, for rows of `nx` samples,
    /// `ny` rows a layer.
    pub fn reset(&mut self, nx: usize, ny: usize) {
        self.resize(nx, ny, 2);
        self.first = usize::MAX;
    }

    /// Forgets the held layers and sizes a slot for each of the layers `z0..=z1`, kept until the
    /// next reset.
    pub fn reset_span(&mut self, nx: usize, ny: usize, z0: usize, z1: usize) {
        self.resize(nx, ny, z1 - z0 + 1);
        self.first = z0;
    }

    /// Whether the layers `z0..=z1` are held (classified since a [`LayerSigns::reset_span`]).
    pub fn holds_span(&self, z0: usize, z1: usize) -> bool {
        self.first == z0 && self.held.len() == z1 - z0 + 1 && self.held.iter().enumerate().all(|(k, &z)| z == z0 + k)
    }

    fn resize(&mut self, nx: usize, ny: usize, slots: usize) {
        self.ny = ny;
        self.words = nx.div_ceil(64) + 1;
        self.held.clear();
        self.held.resize(slots, usize::MAX);
        self.rows.resize(slots * ny, Row::default());
        self.bits.resize(slots * ny * self.words, 0);
        self.non_finite = None;
    }

    /// The slot of layer `z`.
    #[inline(always)]
    fn slot(&self, z: usize) -> usize {
        if self.first == usize::MAX {
            z & 1
        } else {
            z - self.first
        }
    }

    /// Classifies sample layer `z` of `values` (`dims` samples, x fastest) into its slot, unless
    /// already held.
    pub fn classify(&mut self, values: &[f32], dims: [usize; 3], iso: f32, z: usize) {
        let [nx, ny, _] = dims;
        let view = GridView::strided(values, dims, 0, [1, nx as isize, (nx * ny) as isize])
            .unwrap_or_else(|e| panic!("sign rows: the values do not hold the grid: {e}"));
        self.classify_view(&view, iso, z);
    }

    /// Classifies sample layer `z` of a view into its slot, unless already held, noting the
    /// first row with a sample that is not finite ([`LayerSigns::non_finite`]).
    #[inline]
    pub fn classify_view<T: Sample>(&mut self, values: &GridView<'_, T>, iso: f32, z: usize) {
        let slot = self.slot(z);
        if self.held[slot] == z {
            return;
        }
        let [nx, ny, _] = values.dims();
        let words = self.words;
        let rows = &mut self.rows[slot * ny..(slot + 1) * ny];
        let bits = &mut self.bits[slot * ny * words..(slot + 1) * ny * words];
        for (y, (row, out)) in rows.iter_mut().zip(bits.chunks_exact_mut(words)).enumerate() {
            if !values.pack_row(y, z, iso, out) && self.non_finite.is_none() {
                self.non_finite = Some((y, z));
            }
            *row = row_from_bits(out, nx);
        }
        self.held[slot] = z;
    }

    /// The first row `(y, z)` classified since the last reset that holds a NaN or an infinity.
    pub fn non_finite(&self) -> Option<(usize, usize)> {
        self.non_finite
    }

    /// The summary of row `(y, z)`; layer `z` must be held.
    #[inline]
    pub fn row(&self, y: usize, z: usize) -> Row {
        debug_assert_eq!(self.held[self.slot(z)], z, "layer {z} is not classified");
        self.rows[self.slot(z) * self.ny + y]
    }

    /// The inside bits of row `(y, z)`; layer `z` must be held.
    #[inline]
    pub fn bits(&self, y: usize, z: usize) -> &[u64] {
        debug_assert_eq!(self.held[self.slot(z)], z, "layer {z} is not classified");
        let r = self.slot(z) * self.ny + y;
        &self.bits[r * self.words..(r + 1) * self.words]
    }

    /// Bytes held.
    pub fn capacity_bytes(&self) -> usize {
        8 * self.bits.capacity() + std::mem::size_of::<Row>() * self.rows.capacity()
    }
}

/// The inside bits (`value < iso`) of every x-row of a whole grid, 64 samples to a word, each row
/// followed by one word that is always zero: what the tetrahedral engine reads on a cubic grid
/// to find the samples with a crossing on one of their 14 lattice edges, and the cubes with
/// surface, 64 at a time.
#[derive(Clone, Debug, Default)]
pub struct GridSigns {
    dims: [usize; 3],
    words: usize,
    bits: Vec<u64>,
}

/// Rows per rayon task when packing a grid's signs.
const MIN_SAMPLES_PER_PACK_TASK: usize = 1 << 16;

impl GridSigns {
    /// Packs the signs of `values` (`dims` samples, x fastest) against `iso`.
    pub fn classify(&mut self, values: &[f32], dims: [usize; 3], iso: f32) {
        let [nx, ny, nz] = dims;
        self.dims = dims;
        self.words = nx.div_ceil(64) + 1;
        self.bits.clear();
        self.bits.resize(ny * nz * self.words, 0);
        let per_task = (MIN_SAMPLES_PER_PACK_TASK / nx.max(1)).max(1);
        self.bits.par_chunks_mut(self.words).zip(values.par_chunks(nx)).with_min_len(per_task).for_each(|(out, v)| {
            for (word, chunk) in out.iter_mut().zip(v.chunks(64)) {
                *word = inside_bits(chunk, iso);
            }
        });
    }

    /// The inside bits of row `(y, z)` (one zero word past its samples).
    #[inline]
    pub fn bits(&self, y: usize, z: usize) -> &[u64] {
        let r = y + self.dims[1] * z;
        &self.bits[r * self.words..(r + 1) * self.words]
    }

    /// Word `w` of the samples `x` of row `(y, z)` whose state differs from their neighbour at
    /// sample offset `offset` (x offset -1, 0 or 1); zero where that neighbour is outside the grid.
    #[inline]
    pub fn changes_toward(&self, y: usize, z: usize, offset: [isize; 3], w: usize) -> u64 {
        self.changes_toward_each(y, z, &[offset], w)[0]
    }

    /// [`GridSigns::changes_toward`] for each of `offsets` (x offsets -1, 0 or 1), reading the
    /// row's own word and the valid ranges once.
    #[inline]
    pub fn changes_toward_each<const N: usize>(&self, y: usize, z: usize, offsets: &[[isize; 3]; N], w: usize) -> [u64; N] {
        let [nx, ny, nz] = self.dims;
        let own = self.bits(y, z)[w];
        // Samples whose neighbour at x offset -1, 0, +1 lies inside the row.
        let valid = [range_mask(w, 1, nx - 1), range_mask(w, 0, nx - 1), if nx < 2 { 0 } else { range_mask(w, 0, nx - 2) }];
        let mut changes = [0u64; N];
        for (c, o) in changes.iter_mut().zip(offsets) {
            let (ry, rz) = (y as isize + o[1], z as isize + o[2]);
            if ry < 0 || rz < 0 || ry as usize >= ny || rz as usize >= nz {
                continue;
            }
            let other = self.bits(ry as usize, rz as usize);
            let shifted = match o[0] {
                1 => next_bits(other, w),
                -1 => other[w] << 1 | if w > 0 { other[w - 1] >> 63 } else { 0 },
                _ => other[w],
            };
            *c = (own ^ shifted) & valid[(o[0] + 1).clamp(0, 2) as usize];
        }
        changes
    }

    /// Whether these are the signs of a grid of `dims` samples (classified, not empty).
    pub fn holds(&self, dims: [usize; 3]) -> bool {
        self.dims == dims && !self.bits.is_empty()
    }

    /// Bytes held.
    pub fn capacity_bytes(&self) -> usize {
        8 * self.bits.capacity()
    }
}

/// Bit `k` set when `values[k] < iso`, for up to 64 values; four at a time with SIMD compares.
#[inline]
fn inside_bits(values: &[f32], iso: f32) -> u64 {
    let quads = values.chunks_exact(4);
    let rest = quads.remainder();
    let threshold = glam::Vec4::splat(iso);
    let mut word = 0u64;
    for (k, q) in quads.enumerate() {
        word |= u64::from(glam::Vec4::from_slice(q).cmplt(threshold).bitmask()) << (4 * k);
    }
    let done = values.len() - rest.len();
    for (k, &s) in rest.iter().enumerate() {
        word |= u64::from(s < iso) << (done + k);
    }
    word
}

/// The [`Row`] summary of one row's bits.
fn row_from_bits(bits: &[u64], nx: usize) -> Row {
    let inside = bits[0] & 1 == 1;
    let flip = if inside { u64::MAX } else { 0 };
    let differs = |w: usize| (bits[w] ^ flip) & range_mask(w, 0, nx - 1);
    let full = nx.div_ceil(64);
    let Some(first) = (0..full).find_map(|w| {
        let m = differs(w);
        (m != 0).then(|| 64 * w + m.trailing_zeros() as usize)
    }) else {
        return Row { first: u32::MAX, last: 0, inside };
    };
    let last = (0..full).rev().find_map(|w| {
        let m = differs(w);
        (m != 0).then(|| 64 * w + 63 - m.leading_zeros() as usize)
    });
    Row { first: first as u32, last: last.unwrap_or(first) as u32, inside }
}

/// The bits of word `w` that stand for samples `lo..=hi`.
#[inline]
pub fn range_mask(w: usize, lo: usize, hi: usize) -> u64 {
    let (start, end) = (64 * w, 64 * w + 63);
    if hi < start || lo > end {
        return 0;
    }
    let low = if lo > start { u64::MAX << (lo - start) } else { u64::MAX };
    let high = if hi < end { u64::MAX >> (end - hi) } else { u64::MAX };
    low & high
}

/// Word `w` of `row` shifted by one sample: bit `k` is sample `64 w + k + 1`.
#[inline]
pub fn next_bits(row: &[u64], w: usize) -> u64 {
    row[w] >> 1 | row[w + 1] << 63
}

/// How many `x` in `lo..=hi` have their bit set in `word(w)` (`w = x / 64`): what
/// [`for_each_bit`] would visit, counted a word at a time.
#[inline]
pub fn count_bits(lo: usize, hi: usize, word: impl Fn(usize) -> u64) -> usize {
    if lo > hi {
        return 0;
    }
    (lo / 64..=hi / 64).map(|w| (word(w) & range_mask(w, lo, hi)).count_ones() as usize).sum()
}

/// Calls `visit(x)` for every `x` in `lo..=hi` whose bit is set in `word(w)` (`w = x / 64`).
#[inline]
pub fn for_each_bit(lo: usize, hi: usize, mut word: impl FnMut(usize) -> u64, mut visit: impl FnMut(usize)) {
    if lo > hi {
        return;
    }
    for w in lo / 64..=hi / 64 {
        let mut m = word(w) & range_mask(w, lo, hi);
        while m != 0 {
            visit(64 * w + m.trailing_zeros() as usize);
            m &= m - 1;
        }
    }
}

/// The cells whose corners disagree, one bit per cell (its lower corner's x), from word `w` of
/// the four sample rows `(y, z)`, `(y + 1, z)`, `(y, z + 1)`, `(y + 1, z + 1)`; `hi` must be below
/// the row's last sample (the bits past it are meaningless).
#[inline]
pub fn surface_cell_word(rows: [&[u64]; 4], w: usize, lo: usize, hi: usize) -> u64 {
    surface_cells(rows.map(|r| r[w]), rows.map(|r| next_bits(r, w))) & range_mask(w, lo, hi)
}

/// Cells whose eight corners (`a`: the rows' words, `s`: the same shifted by one sample) disagree.
#[inline]
fn surface_cells(a: [u64; 4], s: [u64; 4]) -> u64 {
    let any = a[0] | a[1] | a[2] | a[3] | s[0] | s[1] | s[2] | s[3];
    let all = a[0] & a[1] & a[2] & a[3] & s[0] & s[1] & s[2] & s[3];
    any & !all
}

/// Calls `visit(x, case)` for every cell `x` in `lo..=hi` (its lower corner's x) whose corners
/// disagree, with its sign case (bit `c` set: marching cubes corner `c` inside). `rows` are the
/// sample rows `(y, z)`, `(y + 1, z)`, `(y, z + 1)`, `(y + 1, z + 1)`; `hi` must be below the
/// row's last sample.
#[inline]
pub fn for_each_surface_cell(rows: [&[u64]; 4], lo: usize, hi: usize, mut visit: impl FnMut(usize, u8)) {
    if lo > hi {
        return;
    }
    for w in lo / 64..=hi / 64 {
        let a = rows.map(|r| r[w]);
        let s = rows.map(|r| next_bits(r, w));
        let mut m = surface_cells(a, s) & range_mask(w, lo, hi);
        while m != 0 {
            let b = m.trailing_zeros();
            m &= m - 1;
            let bit = |word: u64, c: u32| ((word >> b) as u8 & 1) << c;
            let case = bit(a[0], 0)
                | bit(s[0], 1)
                | bit(s[1], 2)
                | bit(a[1], 3)
                | bit(a[2], 4)
                | bit(s[2], 5)
                | bit(s[3], 6)
                | bit(a[3], 7);
            visit(64 * w + b as usize, case);
        }
    }
}

/// Calls `edges(y, axis, lo, hi, word)` for every row `y` of sample layer `z` (of a grid of
/// `dims` samples, held by `signs`) that may hold crossing x-edges (`axis` 0) or y-edges (`axis`
/// 1): the edge from sample `x` along `axis` crosses for each `x` in `lo..=hi` whose bit is set
/// in `word(x / 64)`.
#[inline]
pub fn layer_edge_words(
    signs: &LayerSigns,
    dims: [usize; 3],
    z: usize,
    mut edges: impl FnMut(usize, usize, usize, usize, &dyn Fn(usize) -> u64),
) {
    let [nx, ny, _] = dims;
    for y in 0..ny {
        let row = signs.row(y, z);
        let here = signs.bits(y, z);
        if row.first <= row.last {
            let lo = (row.first as usize).saturating_sub(1);
            let hi = (row.last as usize).min(nx - 2);
            edges(y, 0, lo, hi, &|w| here[w] ^ next_bits(here, w));
        }
        if y + 1 < ny {
            if let Some((lo, hi)) = span(&[row, signs.row(y + 1, z)], nx) {
                let next = signs.bits(y + 1, z);
                edges(y, 1, lo, hi, &|w| here[w] ^ next[w]);
            }
        }
    }
}

/// Like [`layer_edge_words`] for the z-edges between sample layers `z` and `z + 1` (`axis` 2).
#[inline]
pub fn z_edge_words(
    signs: &LayerSigns,
    dims: [usize; 3],
    z: usize,
    mut edges: impl FnMut(usize, usize, usize, usize, &dyn Fn(usize) -> u64),
) {
    let [nx, ny, _] = dims;
    for y in 0..ny {
        if let Some((lo, hi)) = span(&[signs.row(y, z), signs.row(y, z + 1)], nx) {
            let (here, above) = (signs.bits(y, z), signs.bits(y, z + 1));
            edges(y, 2, lo, hi, &|w| here[w] ^ above[w]);
        }
    }
}

/// The crossing lattice edges of cell layers `z0..z1` (the x- and y-edges of sample layers
/// `z0 + 1..=z1`, and of `z0` when `bottom`, and the z-edges between), counted a word at a time:
/// a sign pass without per-edge work, so an extractor can size a fresh output once (marching
/// cubes makes one vertex per crossing edge; surface nets one quad per interior one).
pub fn count_crossing_edges(
    signs: &mut LayerSigns,
    values: &[f32],
    dims: [usize; 3],
    iso: f32,
    z0: usize,
    z1: usize,
    bottom: bool,
) -> usize {
    let [nx, ny, _] = dims;
    let view = GridView::strided(values, dims, 0, [1, nx as isize, (nx * ny) as isize])
        .unwrap_or_else(|e| panic!("sign rows: the values do not hold the grid: {e}"));
    count_crossing_edges_in(signs, &view, iso, z0, z1, bottom)
}

/// [`count_crossing_edges`] of a view (its non-finite rows noted in `signs`).
pub fn count_crossing_edges_in<T: Sample>(
    signs: &mut LayerSigns,
    values: &GridView<'_, T>,
    iso: f32,
    z0: usize,
    z1: usize,
    bottom: bool,
) -> usize {
    let dims = values.dims();
    signs.reset(dims[0], dims[1]);
    signs.classify_view(values, iso, z0);
    let mut n = 0;
    let mut count = |_: usize, _: usize, lo: usize, hi: usize, word: &dyn Fn(usize) -> u64| n += count_bits(lo, hi, word);
    if bottom {
        layer_edge_words(signs, dims, z0, &mut count);
    }
    for z in z0..z1 {
        signs.classify_view(values, iso, z + 1);
        z_edge_words(signs, dims, z, &mut count);
        layer_edge_words(signs, dims, z + 1, &mut count);
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bits_give_the_rows_and_the_cell_cases_of_the_values() {
        // Pseudo-random values on 3 x 2 x 2 rows of lengths that straddle word boundaries.
        for nx in [2usize, 3, 63, 64, 65, 127, 130] {
            let ny = 2;
            let values: Vec<f32> = (0..nx * ny * 2)
                .map(|i| ((i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40) as f32 / 16_777_216.0 - 0.5)
                .collect();
            let values: Vec<f32> = values.iter().enumerate().map(|(i, v)| if i % 7 == 0 { 0.3 } else { *v }).collect();
            let (mut signs, mut plain) = (LayerSigns::default(), Vec::new());
            signs.reset(nx, ny);
            signs.classify(&values, [nx, ny, 2], 0.0, 0);
            signs.classify(&values, [nx, ny, 2], 0.0, 1);
            classify_rows(&values, nx, 0.0, &mut plain);
            for (r, b) in plain.iter().enumerate() {
                let a = signs.row(r % ny, r / ny);
                assert_eq!((a.first, a.last, a.inside), (b.first, b.last, b.inside), "nx {nx}");
            }
            let inside = |x: usize, y: usize, z: usize| values[x + nx * (y + ny * z)] < 0.0;
            let mut seen = Vec::new();
            for_each_surface_cell(
                [signs.bits(0, 0), signs.bits(1, 0), signs.bits(0, 1), signs.bits(1, 1)],
                0,
                nx - 2,
                |x, case| seen.push((x, case)),
            );
            let mut expected = Vec::new();
            for x in 0..nx - 1 {
                let corners = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]];
                let case = corners.iter().enumerate().fold(0u8, |c, (k, d)| c | u8::from(inside(x + d[0], d[1], d[2])) << k);
                if case != 0 && case != 255 {
                    expected.push((x, case));
                }
            }
            assert_eq!(seen, expected, "nx {nx}");
            let mut crossings = Vec::new();
            let first = signs.bits(0, 0);
            for_each_bit(0, nx - 2, |w| first[w] ^ next_bits(first, w), |x| crossings.push(x));
            let expected: Vec<usize> = (0..nx - 1).filter(|&x| inside(x, 0, 0) != inside(x + 1, 0, 0)).collect();
            assert_eq!(crossings, expected, "nx {nx}");
        }
    }

    #[test]
    fn grid_sign_changes_toward_each_neighbour_match_the_values() {
        // Every sample of small grids (rows straddling word boundaries) against its 26
        // neighbours: a change where the neighbour exists and has the other sign.
        let offsets: [[isize; 3]; 26] = std::array::from_fn(|k| {
            let k = if k >= 13 { k + 1 } else { k } as isize;
            [k % 3 - 1, k / 3 % 3 - 1, k / 9 - 1]
        });
        for dims in [[1usize, 2, 2], [2, 3, 2], [63, 2, 3], [64, 3, 2], [65, 2, 2], [130, 2, 2]] {
            let [nx, ny, nz] = dims;
            let values: Vec<f32> = (0..nx * ny * nz)
                .map(|i| ((i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 40) as f32 / 16_777_216.0 - 0.5)
                .collect();
            let mut signs = GridSigns::default();
            signs.classify(&values, dims, 0.0);
            let inside = |x: isize, y: isize, z: isize| values[x as usize + nx * (y as usize + ny * z as usize)] < 0.0;
            for (y, z) in (0..ny).flat_map(|y| (0..nz).map(move |z| (y, z))) {
                for w in 0..nx.div_ceil(64) {
                    let each = signs.changes_toward_each(y, z, &offsets, w);
                    for (o, &got) in offsets.iter().zip(&each) {
                        assert_eq!(got, signs.changes_toward(y, z, *o, w), "{dims:?} {o:?}");
                        for x in 64 * w..(64 * w + 64).min(nx) {
                            let (p, q) =
                                ([x as isize, y as isize, z as isize], [x as isize + o[0], y as isize + o[1], z as isize + o[2]]);
                            let exists = (0..3).all(|a| (0..dims[a] as isize).contains(&q[a]));
                            let change = exists && inside(p[0], p[1], p[2]) != inside(q[0], q[1], q[2]);
                            assert_eq!(got >> (x - 64 * w) & 1 == 1, change, "{dims:?} {o:?} x {x}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn rows_and_spans() {
        let mut rows = Vec::new();
        classify_rows(&[1.0, 1.0, -1.0, 1.0, /* */ 1.0, 1.0, 1.0, 1.0, /* */ -1.0, -1.0, -1.0, -1.0], 4, 0.0, &mut rows);
        assert_eq!((rows[0].first, rows[0].last, rows[0].inside), (2, 2, false));
        assert!(rows[1].is_uniform() && !rows[1].inside);
        assert!(rows[2].is_uniform() && rows[2].inside);
        assert_eq!(span(&rows[0..2], 4), Some((2, 2)));
        assert_eq!(span(&rows[1..3], 4), Some((0, 3)));
        assert_eq!(span(&rows[1..2], 4), None);
    }
}
