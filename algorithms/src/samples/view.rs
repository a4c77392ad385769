//! Samples where they lie: a cubic grid's values read from the caller's memory (a numpy array, a
//! memory-mapped file, one block of a larger volume) in their own number type, through strides,
//! with no copy and no conversion pass.
//!
//! A [`GridView`] says where sample `(x, y, z)` is: element `origin + x sx + y sy + z sz` of a
//! slice, the strides in elements and of either sign, so C order, Fortran order, every `step`-th
//! sample, a reversed axis or a block of a larger array are all one view. Each read converts one
//! value to `f32` and multiplies it by the view's sign (`-1` reads the complement, for an object
//! brighter than its background); the same conversion as [`GridView::to_vec`], so an extractor
//! that reads the view gives the mesh it gives on the converted copy, bit for bit.
//!
//! Extractors that read views are generic over [`Sample`], so each sample type has its own
//! compiled loops (no per-sample dispatch); [`AnyView`] (`any_view.rs`) is the view with its type
//! as data, and [`with_view!`](crate::with_view) picks the monomorphised code once per call.

pub use super::any_view::AnyView;
use glam::Vec4;
use rayon::prelude::*;

mod sealed {
    pub trait Sealed {}
}

/// A number type a grid's samples can be read in where they lie.
pub trait Sample: Copy + Send + Sync + PartialEq + std::fmt::Debug + 'static + sealed::Sealed {
    /// numpy's name for the type.
    const DTYPE: &'static str;
    /// Whether values may be NaN or infinite (the float types).
    const FLOAT: bool;
    /// The value as an `f32` sample: exact for `bool` and the 8- and 16-bit integers, rounded to
    /// nearest for 32-bit integers beyond 2^24 and for `f64` (numpy's `astype(float32)`, the
    /// conversion scikit-image makes).
    fn to_f32(self) -> f32;
    /// A view of this type as an [`AnyView`].
    fn any_view(view: GridView<'_, Self>) -> AnyView<'_>;
}

macro_rules! numeric_sample {
    ($($t:ty => $name:literal, $float:literal, $variant:ident);*) => {$(
        impl sealed::Sealed for $t {}
        impl Sample for $t {
            const DTYPE: &'static str = $name;
            const FLOAT: bool = $float;
            #[inline(always)]
            fn to_f32(self) -> f32 {
                self as f32
            }
            fn any_view(view: GridView<'_, Self>) -> AnyView<'_> {
                AnyView::$variant(view)
            }
        }
    )*};
}
numeric_sample!(u8 => "uint8", false, U8; i8 => "int8", false, I8; u16 => "uint16", false, U16;
    i16 => "int16", false, I16; u32 => "uint32", false, U32; i32 => "int32", false, I32;
    f32 => "float32", true, F32; f64 => "float64", true, F64);

impl sealed::Sealed for bool {}
impl Sample for bool {
    const DTYPE: &'static str = "bool";
    const FLOAT: bool = false;
    #[inline(always)]
    fn to_f32(self) -> f32 {
        f32::from(u8::from(self))
    }
    fn any_view(view: GridView<'_, Self>) -> AnyView<'_> {
        AnyView::Bool(view)
    }
}

/// Why a view cannot be made.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ViewError {
    /// A sample would lie outside the slice.
    #[error("sample {sample:?} of a {dims:?} view lies at element {at} of a slice of {len}")]
    OutOfBounds {
        /// The offending sample (a corner of the grid).
        sample: [usize; 3],
        /// The view's dims.
        dims: [usize; 3],
        /// Where it would be (negative: before the slice).
        at: i128,
        /// The slice's length.
        len: usize,
    },
}

/// A cubic grid's samples where they lie: sample `(x, y, z)` is
/// `sign * data[origin + x sx + y sy + z sz]` as `f32` (module doc).
#[derive(Clone, Copy, Debug)]
pub struct GridView<'a, T> {
    data: &'a [T],
    dims: [usize; 3],
    origin: usize,
    strides: [isize; 3],
    sign: f32,
}

impl<'a, T: Sample> GridView<'a, T> {
    /// `data` in isolab's order (x fastest, then y, then z), exactly `dims` samples.
    pub fn contiguous(data: &'a [T], dims: [usize; 3]) -> Result<Self, ViewError> {
        let n = dims.iter().product::<usize>();
        if data.len() != n {
            let at = i128::try_from(n).unwrap_or(i128::MAX) - 1;
            return Err(ViewError::OutOfBounds { sample: dims.map(|d| d.saturating_sub(1)), dims, at, len: data.len() });
        }
        Self::strided(data, dims, 0, [1, dims[0] as isize, (dims[0] * dims[1]) as isize])
    }

    /// Sample `(x, y, z)` at element `origin + x strides[0] + y strides[1] + z strides[2]` of
    /// `data`; every sample must lie inside the slice (checked at its corners). A view with no
    /// samples (a zero among `dims`) is allowed and reads nothing.
    pub fn strided(data: &'a [T], dims: [usize; 3], origin: usize, strides: [isize; 3]) -> Result<Self, ViewError> {
        if dims.contains(&0) {
            return Ok(GridView { data, dims, origin, strides, sign: 1.0 });
        }
        for corner in 0..8 {
            let sample: [usize; 3] = std::array::from_fn(|a| if corner >> a & 1 == 1 { dims[a] - 1 } else { 0 });
            let at = origin as i128 + (0..3).map(|a| sample[a] as i128 * strides[a] as i128).sum::<i128>();
            if at < 0 || at >= data.len() as i128 {
                return Err(ViewError::OutOfBounds { sample, dims, at, len: data.len() });
            }
        }
        Ok(GridView { data, dims, origin, strides, sign: 1.0 })
    }

    /// The same samples read with the opposite sign (the complement: inside above the level).
    pub fn negated(self) -> Self {
        GridView { sign: -self.sign, ..self }
    }

    /// Every `step`-th sample along each axis, from the first (numpy's `a[::step, ::step,
    /// ::step]`); `None` when `step` is 0.
    pub fn every(self, step: usize) -> Option<Self> {
        (step > 0).then(|| GridView {
            dims: self.dims.map(|d| d.div_ceil(step)),
            strides: self.strides.map(|s| s * step as isize),
            ..self
        })
    }

    /// The block of `dims` samples whose first sample is `lo` (`None` when it does not fit).
    pub fn block(self, lo: [usize; 3], dims: [usize; 3]) -> Option<Self> {
        if (0..3).any(|a| dims[a] == 0 || lo[a] + dims[a] > self.dims[a]) {
            return None;
        }
        Some(GridView { origin: self.offset(lo[0], lo[1], lo[2]), dims, ..self })
    }

    /// Samples along x, y, z.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Elements between neighbouring samples along x, y, z.
    pub fn strides(&self) -> [isize; 3] {
        self.strides
    }

    /// `1.0`, or `-1.0` for a negated view.
    pub fn sign(&self) -> f32 {
        self.sign
    }

    /// Whether sample `(x, y, z)` is element `origin + x + nx (y + ny z)`: rows contiguous and
    /// in order, so a flat sample index plus the origin is the element.
    pub fn is_dense(&self) -> bool {
        let [nx, ny, _] = self.dims;
        self.strides == [1, nx as isize, (nx * ny) as isize]
    }

    /// The element holding sample `(x, y, z)`.
    #[inline(always)]
    pub fn offset(&self, x: usize, y: usize, z: usize) -> usize {
        self.origin
            .wrapping_add_signed(x as isize * self.strides[0])
            .wrapping_add_signed(y as isize * self.strides[1])
            .wrapping_add_signed(z as isize * self.strides[2])
    }

    /// The sample at element `at` (an [`GridView::offset`], or one moved by strides).
    #[inline(always)]
    pub fn read(&self, at: usize) -> f32 {
        self.sign * self.data[at].to_f32()
    }

    /// Sample `(x, y, z)`.
    #[inline(always)]
    pub fn at(&self, x: usize, y: usize, z: usize) -> f32 {
        self.read(self.offset(x, y, z))
    }

    /// Packs the inside bits (`sample < iso`) of row `(y, z)` into `out`, 64 samples a word (bit
    /// `k` of word `w` is sample `64 w + k`; the last word's bits past the row are zero), and
    /// says whether every sample of the row is finite.
    #[inline]
    pub fn pack_row(&self, y: usize, z: usize, iso: f32, out: &mut [u64]) -> bool {
        let nx = self.dims[0];
        let start = self.offset(0, y, z);
        let mut nan = Vec4::ZERO;
        if self.strides[0] == 1 {
            let row = &self.data[start..start + nx];
            for (word, chunk) in out.iter_mut().zip(row.chunks(64)) {
                *word = inside_bits(chunk, self.sign, iso, &mut nan);
            }
        } else {
            let mut buffer = [self.data[start]; 64];
            for (w, word) in out.iter_mut().enumerate().take(nx.div_ceil(64)) {
                let n = (nx - 64 * w).min(64);
                for (k, slot) in buffer[..n].iter_mut().enumerate() {
                    *slot = self.data[start.wrapping_add_signed((64 * w + k) as isize * self.strides[0])];
                }
                *word = inside_bits(&buffer[..n], self.sign, iso, &mut nan);
            }
        }
        !T::FLOAT || !nan.is_nan_mask().any()
    }

    /// Reads one sample of every cache line of layer `z` (every sample of a strided row), so
    /// that reads of the layer that follow hit the cache: a sweep that will read a layer ahead
    /// of the one it classifies (normals from central differences) calls it a layer ahead.
    pub fn touch_layer(&self, z: usize) -> f32 {
        let [nx, ny, _] = self.dims;
        let per_line = (64 / std::mem::size_of::<T>()).max(1);
        let mut sum = 0.0f32;
        for y in 0..ny {
            let start = self.offset(0, y, z);
            if self.strides[0] == 1 {
                for v in self.data[start..start + nx].iter().step_by(per_line) {
                    sum += v.to_f32();
                }
            } else {
                for x in 0..nx {
                    sum += self.data[start.wrapping_add_signed(x as isize * self.strides[0])].to_f32();
                }
            }
        }
        std::hint::black_box(sum)
    }

    /// The samples converted, in isolab's order (x fastest), sign applied: what an extractor
    /// that cannot read the view meshes instead. z-slices in parallel.
    pub fn to_vec(&self) -> Vec<f32> {
        let [nx, ny, nz] = self.dims;
        let mut out = vec![0.0f32; nx * ny * nz];
        out.par_chunks_mut(nx * ny).with_max_len(1).enumerate().for_each(|(z, slice)| {
            for (y, row) in slice.chunks_exact_mut(nx).enumerate() {
                let start = self.offset(0, y, z);
                if self.strides[0] == 1 {
                    for (o, &v) in row.iter_mut().zip(&self.data[start..start + nx]) {
                        *o = self.sign * v.to_f32();
                    }
                } else {
                    for (x, o) in row.iter_mut().enumerate() {
                        *o = self.read(start.wrapping_add_signed(x as isize * self.strides[0]));
                    }
                }
            }
        });
        out
    }

    /// The samples as they are stored, in their own type and isolab's order (x fastest), the
    /// view's sign not applied: a copy a caller can keep.
    pub fn to_vec_typed(&self) -> Vec<T> {
        let [nx, ny, nz] = self.dims;
        let mut out = Vec::with_capacity(nx * ny * nz);
        for z in 0..nz {
            for y in 0..ny {
                let start = self.offset(0, y, z);
                if self.strides[0] == 1 {
                    out.extend_from_slice(&self.data[start..start + nx]);
                } else {
                    out.extend((0..nx).map(|x| self.data[start.wrapping_add_signed(x as isize * self.strides[0])]));
                }
            }
        }
        out
    }

    /// The smallest and largest sample (NaN skipped; `(inf, -inf)` when every sample is NaN),
    /// and the first non-finite sample in isolab's order, in one parallel pass.
    pub fn range(&self) -> ViewRange {
        let [nx, ny, nz] = self.dims;
        (0..nz)
            .into_par_iter()
            .map(|z| {
                let mut r = ViewRange::EMPTY;
                for y in 0..ny {
                    let start = self.offset(0, y, z);
                    for x in 0..nx {
                        let v = self.read(start.wrapping_add_signed(x as isize * self.strides[0]));
                        r.min = r.min.min(v);
                        r.max = r.max.max(v);
                        if T::FLOAT && !v.is_finite() && r.non_finite.is_none() {
                            r.non_finite = Some(([x, y, z], v));
                        }
                    }
                }
                r
            })
            .reduce(|| ViewRange::EMPTY, ViewRange::join)
    }

    /// How many samples are below `iso` (inside), in parallel over z-slices.
    pub fn count_below(&self, iso: f32) -> usize {
        let [nx, ny, nz] = self.dims;
        let words = nx.div_ceil(64);
        (0..nz)
            .into_par_iter()
            .map(|z| {
                let mut bits = vec![0u64; words];
                (0..ny)
                    .map(|y| {
                        self.pack_row(y, z, iso, &mut bits);
                        bits.iter().map(|w| w.count_ones() as usize).sum::<usize>()
                    })
                    .sum::<usize>()
            })
            .sum()
    }

    /// The first non-finite sample in isolab's order and its value (float types only).
    pub fn first_non_finite(&self) -> Option<([usize; 3], f32)> {
        if !T::FLOAT {
            return None;
        }
        let [_, ny, nz] = self.dims;
        let mut bits = vec![0u64; self.dims[0].div_ceil(64)];
        let row = (0..ny * nz).find(|&r| !self.pack_row(r % ny, r / ny, 0.0, &mut bits))?;
        let (y, z) = (row % ny, row / ny);
        (0..self.dims[0]).map(|x| ([x, y, z], self.at(x, y, z))).find(|(_, v)| !v.is_finite())
    }
}

/// The largest `f32` at or below `level`: an `f32` sample is above `level` (compared as `f64`,
/// as scikit-image compares) exactly when it is above this one. NaN stays NaN.
pub fn f32_at_or_below(level: f64) -> f32 {
    let f = level as f32;
    if level.is_nan() || f64::from(f) <= level {
        return f;
    }
    // One float32 step toward minus infinity.
    if f == 0.0 {
        -f32::from_bits(1)
    } else if f > 0.0 {
        f32::from_bits(f.to_bits() - 1)
    } else {
        f32::from_bits(f.to_bits() + 1)
    }
}

/// What [`GridView::range`] found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewRange {
    /// The smallest sample (NaN skipped).
    pub min: f32,
    /// The largest sample (NaN skipped).
    pub max: f32,
    /// The first non-finite sample in isolab's order (x fastest) and its value.
    pub non_finite: Option<([usize; 3], f32)>,
}

impl ViewRange {
    const EMPTY: ViewRange = ViewRange { min: f32::INFINITY, max: f32::NEG_INFINITY, non_finite: None };

    fn join(a: ViewRange, b: ViewRange) -> ViewRange {
        // Slices are joined in z order, so the first non-finite of `a` comes first.
        ViewRange { min: a.min.min(b.min), max: a.max.max(b.max), non_finite: a.non_finite.or(b.non_finite) }
    }
}

/// Bit `k` set when `sign * values[k] < iso`, for up to 64 values, four at a time with SIMD
/// compares; `nan` gathers `0 v` of every value (NaN once any is not finite) for float types.
#[inline(always)]
fn inside_bits<T: Sample>(values: &[T], sign: f32, iso: f32, nan: &mut Vec4) -> u64 {
    let quads = values.chunks_exact(4);
    let rest = quads.remainder();
    let threshold = Vec4::splat(iso);
    let mut word = 0u64;
    for (k, q) in quads.enumerate() {
        let v = Vec4::new(q[0].to_f32(), q[1].to_f32(), q[2].to_f32(), q[3].to_f32()) * sign;
        if T::FLOAT {
            *nan += v * 0.0;
        }
        word |= u64::from(v.cmplt(threshold).bitmask()) << (4 * k);
    }
    let done = values.len() - rest.len();
    for (k, &s) in rest.iter().enumerate() {
        let v = sign * s.to_f32();
        if T::FLOAT {
            nan.x += v * 0.0;
        }
        word |= u64::from(v < iso) << (done + k);
    }
    word
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strided_views_read_what_a_copy_holds() {
        // A 5 x 4 x 3 grid stored with z fastest (numpy's C order read with x = its last axis
        // reversed here: x along the slowest stride), every sample's value its flat index.
        let dims = [5usize, 4, 3];
        let data: Vec<i16> = (0..60).collect();
        // Element of (x, y, z) = z + 3 (y + 4 x): strides [12, 3, 1].
        let v = GridView::strided(&data, dims, 0, [12, 3, 1]).unwrap();
        let copy = v.to_vec();
        for z in 0..3 {
            for y in 0..4 {
                for x in 0..5 {
                    let expected = (z + 3 * (y + 4 * x)) as f32;
                    assert_eq!(v.at(x, y, z), expected);
                    assert_eq!(copy[x + 5 * (y + 4 * z)], expected);
                }
            }
        }
        // Reversed x: origin at the last row.
        let r = GridView::strided(&data, dims, 48, [-12, 3, 1]).unwrap();
        assert_eq!(r.at(0, 0, 0), 48.0);
        assert_eq!(r.negated().at(4, 0, 0), -0.0);
        assert!(GridView::strided(&data, dims, 49, [-12, 3, 1]).is_err());
        assert!(GridView::strided(&data, dims, 0, [-12, 3, 1]).is_err());
        let every = v.every(2).unwrap();
        assert_eq!(every.dims(), [3, 2, 2]);
        assert_eq!(every.at(2, 1, 1), v.at(4, 2, 2));
        assert_eq!(v.every(3).unwrap().dims(), [2, 2, 1]);
        assert!(v.every(0).is_none());
        let b = v.block([1, 1, 1], [2, 3, 2]).unwrap();
        assert_eq!(b.at(1, 2, 1), v.at(2, 3, 2));
        assert!(v.block([4, 0, 0], [2, 2, 2]).is_none());
    }

    #[test]
    fn packed_rows_are_the_comparisons_of_every_sample() {
        for nx in [2usize, 3, 5, 63, 64, 65, 130] {
            let data: Vec<f64> = (0..nx * 2 * 2).map(|i| ((i * 37) % 11) as f64 - 5.0).collect();
            for (view, label) in [
                (GridView::contiguous(&data, [nx, 2, 2]).unwrap(), "dense"),
                (GridView::strided(&data, [nx, 2, 2], 0, [4, 1, 2]).unwrap(), "strided"),
            ] {
                for sign in [1.0f32, -1.0] {
                    let view = if sign < 0.0 { view.negated() } else { view };
                    let mut words = vec![u64::MAX; nx.div_ceil(64)];
                    assert!(view.pack_row(1, 1, 0.5, &mut words));
                    for x in 0..nx {
                        assert_eq!(words[x / 64] >> (x % 64) & 1 == 1, view.at(x, 1, 1) < 0.5, "{label} nx {nx} x {x}");
                    }
                    if nx % 64 != 0 {
                        assert_eq!(words[nx / 64] >> (nx % 64), 0, "bits past the row are zero");
                    }
                }
            }
        }
    }

    #[test]
    fn non_finite_samples_are_found_where_they_are() {
        let mut data = vec![1.0f32; 70 * 3 * 2];
        data[66 + 70 * (2 + 3)] = f32::INFINITY;
        data[3 + 70 * (1 + 3)] = f32::NAN;
        let v = GridView::contiguous(&data, [70, 3, 2]).unwrap();
        let mut words = vec![0u64; 2];
        assert!(v.pack_row(0, 1, 0.0, &mut words));
        assert!(!v.pack_row(1, 1, 0.0, &mut words));
        assert!(!v.pack_row(2, 1, 0.0, &mut words));
        let (at, value) = v.first_non_finite().unwrap();
        assert_eq!(at, [3, 1, 1]);
        assert!(value.is_nan());
        let r = v.range();
        assert_eq!(r.non_finite.map(|(at, _)| at), Some([3, 1, 1]));
        assert_eq!((r.min, r.max), (1.0, f32::INFINITY));
        let ints = vec![7u8; 8];
        assert!(GridView::contiguous(&ints, [2, 2, 2]).unwrap().first_non_finite().is_none());
    }

    #[test]
    fn the_f32_at_or_below_a_level_splits_samples_as_the_f64_level_does() {
        // The float32 values around each level: above the level exactly when above its f32.
        for level in [0.1f64, -0.1, 0.5, 1e-40, -1e-40, 3.0e38, -3.0e38, 1e39, -1e39, 0.0, 16_777_217.0, 1.0 / 3.0] {
            let f = f32_at_or_below(level);
            let near = level as f32;
            for bits in [near.to_bits().wrapping_sub(2), near.to_bits().wrapping_sub(1), near.to_bits(), near.to_bits() + 1] {
                for sample in [f32::from_bits(bits), -f32::from_bits(bits)] {
                    if sample.is_finite() {
                        assert_eq!(f64::from(sample) > level, sample > f, "level {level}, sample {sample}");
                    }
                }
            }
        }
        assert_eq!(f32_at_or_below(0.1), 0.099_999_994);
        assert_eq!(f32_at_or_below(0.5), 0.5);
        assert!(f32_at_or_below(f64::NAN).is_nan());
    }

    #[test]
    fn conversions_are_numpys_astype_float32() {
        assert_eq!(16_777_217u32.to_f32(), 16_777_216.0);
        assert_eq!(0.1f64.to_f32(), 0.1f32);
        assert_eq!(true.to_f32(), 1.0);
        assert_eq!((-128i8).to_f32(), -128.0);
        assert_eq!(AnyView::from(GridView::contiguous(&[0u16; 8], [2, 2, 2]).unwrap()).dtype(), "uint16");
    }
}
