//! Values held in their own type: a volume file's voxels as the file stores them (a uint8 scan
//! takes one byte a voxel, not four), shared by the volume and the samples meshed from it
//! ([`crate::Samples::stored`]) and read by extractors through the same views as a caller's array
//! ([`super::view`]).

use super::view::{AnyView, GridView, Sample};
use rayon::prelude::*;

/// Values in one of the sample types, in isolab's order (x fastest).
#[derive(Clone, Debug, PartialEq)]
#[allow(missing_docs)]
pub enum StoredValues {
    Bool(Vec<bool>),
    U8(Vec<u8>),
    I8(Vec<i8>),
    U16(Vec<u16>),
    I16(Vec<i16>),
    U32(Vec<u32>),
    I32(Vec<i32>),
    F32(Vec<f32>),
    F64(Vec<f64>),
}

/// Runs `$body` with `$v` bound to the typed vector inside a [`StoredValues`].
macro_rules! with_stored {
    ($stored:expr, $v:ident => $body:expr) => {
        match $stored {
            $crate::samples::StoredValues::Bool($v) => $body,
            $crate::samples::StoredValues::U8($v) => $body,
            $crate::samples::StoredValues::I8($v) => $body,
            $crate::samples::StoredValues::U16($v) => $body,
            $crate::samples::StoredValues::I16($v) => $body,
            $crate::samples::StoredValues::U32($v) => $body,
            $crate::samples::StoredValues::I32($v) => $body,
            $crate::samples::StoredValues::F32($v) => $body,
            $crate::samples::StoredValues::F64($v) => $body,
        }
    };
}
pub(crate) use with_stored;

impl From<Vec<f32>> for StoredValues {
    fn from(v: Vec<f32>) -> Self {
        StoredValues::F32(v)
    }
}

impl StoredValues {
    /// Number of values.
    pub fn len(&self) -> usize {
        with_stored!(self, v => v.len())
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The type's numpy name.
    pub fn dtype(&self) -> &'static str {
        fn name<T: Sample>(_: &[T]) -> &'static str {
            T::DTYPE
        }
        with_stored!(self, v => name(v))
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        with_stored!(self, v => std::mem::size_of_val(v.as_slice()))
    }

    /// Value `i` as `f32` (one dispatch per call: for a few values; loops read a view).
    pub fn get(&self, i: usize) -> f32 {
        with_stored!(self, v => v[i].to_f32())
    }

    /// The values as a grid of `dims` (x fastest); `None` unless `dims` holds them exactly.
    pub fn view(&self, dims: [usize; 3]) -> Option<AnyView<'_>> {
        with_stored!(self, v => GridView::contiguous(v, dims).ok().map(AnyView::from))
    }

    /// Every value as `f32`, in parallel (a copy, for what needs `f32` samples).
    pub fn to_f32(&self) -> Vec<f32> {
        with_stored!(self, v => {
            let mut out = vec![0.0f32; v.len()];
            out.par_chunks_mut(1 << 16).zip(v.par_chunks(1 << 16)).for_each(|(o, i)| {
                for (o, &x) in o.iter_mut().zip(i) {
                    *o = x.to_f32();
                }
            });
            out
        })
    }

    /// `n` values picked from these in their type: value `i` of the result is value `index(i)`
    /// (an axis order or a channel of a file put into isolab's order).
    pub fn gather(&self, n: usize, index: impl Fn(usize) -> usize + Sync) -> StoredValues {
        fn of<T: Sample>(v: &[T], n: usize, index: &(impl Fn(usize) -> usize + Sync)) -> Vec<T> {
            (0..n).into_par_iter().map(|i| v[index(i)]).collect()
        }
        match self {
            StoredValues::Bool(v) => StoredValues::Bool(of(v, n, &index)),
            StoredValues::U8(v) => StoredValues::U8(of(v, n, &index)),
            StoredValues::I8(v) => StoredValues::I8(of(v, n, &index)),
            StoredValues::U16(v) => StoredValues::U16(of(v, n, &index)),
            StoredValues::I16(v) => StoredValues::I16(of(v, n, &index)),
            StoredValues::U32(v) => StoredValues::U32(of(v, n, &index)),
            StoredValues::I32(v) => StoredValues::I32(of(v, n, &index)),
            StoredValues::F32(v) => StoredValues::F32(of(v, n, &index)),
            StoredValues::F64(v) => StoredValues::F64(of(v, n, &index)),
        }
    }

    /// The values as `f32` borrowed when they are `f32`, else converted.
    pub fn as_f32(&self) -> std::borrow::Cow<'_, [f32]> {
        match self {
            StoredValues::F32(v) => std::borrow::Cow::Borrowed(v),
            other => std::borrow::Cow::Owned(other.to_f32()),
        }
    }

    /// The smallest and largest value (NaN skipped; `(inf, -inf)` when there is none) and the
    /// index and value of the first one that is not finite, in parallel.
    pub fn range(&self) -> (f32, f32, Option<(usize, f32)>) {
        fn of<T: Sample>(v: &[T]) -> (f32, f32, Option<(usize, f32)>) {
            const BLOCK: usize = 1 << 16;
            v.par_chunks(BLOCK)
                .enumerate()
                .map(|(b, chunk)| {
                    let (mut lo, mut hi, mut bad) = (f32::INFINITY, f32::NEG_INFINITY, None);
                    for (k, &x) in chunk.iter().enumerate() {
                        let x = x.to_f32();
                        lo = lo.min(x);
                        hi = hi.max(x);
                        if T::FLOAT && bad.is_none() && !x.is_finite() {
                            bad = Some((b * BLOCK + k, x));
                        }
                    }
                    (lo, hi, bad)
                })
                .reduce(|| (f32::INFINITY, f32::NEG_INFINITY, None), |a, b| (a.0.min(b.0), a.1.max(b.1), a.2.or(b.2)))
        }
        with_stored!(self, v => of(v))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stored_values_read_as_their_conversion() {
        let v = StoredValues::U16(vec![1, 2, 300, 40000, 5, 6, 7, 8]);
        assert_eq!((v.len(), v.dtype(), v.bytes()), (8, "uint16", 16));
        assert_eq!(v.get(3), 40000.0);
        assert_eq!(v.to_f32(), vec![1.0, 2.0, 300.0, 40000.0, 5.0, 6.0, 7.0, 8.0]);
        let view = v.view([2, 2, 2]).unwrap();
        assert_eq!(view.at(1, 1, 0), 40000.0);
        assert!(v.view([2, 2, 3]).is_none());
        assert_eq!(v.range(), (1.0, 40000.0, None));
        let f = StoredValues::from(vec![1.0f32, f32::NAN, 3.0]);
        assert!(matches!(f.as_f32(), std::borrow::Cow::Borrowed(_)));
        let (lo, hi, bad) = f.range();
        assert_eq!((lo, hi, bad.map(|b| b.0)), (1.0, 3.0, Some(1)));
    }
}
