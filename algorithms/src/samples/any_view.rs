//! [`AnyView`]: a [`GridView`] with its sample type as data, and [`with_view!`](crate::with_view),
//! which hands the typed view to generic code (one dispatch per call, each arm its own
//! monomorphised code).

use super::view::{GridView, Sample, ViewRange};

/// A [`GridView`] with its sample type as data; [`with_view!`](crate::with_view) gives the
/// typed view to generic code.
#[derive(Clone, Copy, Debug)]
#[allow(missing_docs)]
pub enum AnyView<'a> {
    Bool(GridView<'a, bool>),
    U8(GridView<'a, u8>),
    I8(GridView<'a, i8>),
    U16(GridView<'a, u16>),
    I16(GridView<'a, i16>),
    U32(GridView<'a, u32>),
    I32(GridView<'a, i32>),
    F32(GridView<'a, f32>),
    F64(GridView<'a, f64>),
}

/// Runs `$body` with `$v` bound to the typed [`GridView`] inside an [`AnyView`]: one dispatch per
/// call, each arm its own monomorphised code.
#[macro_export]
macro_rules! with_view {
    ($any:expr, $v:ident => $body:expr) => {
        match $any {
            $crate::samples::AnyView::Bool($v) => $body,
            $crate::samples::AnyView::U8($v) => $body,
            $crate::samples::AnyView::I8($v) => $body,
            $crate::samples::AnyView::U16($v) => $body,
            $crate::samples::AnyView::I16($v) => $body,
            $crate::samples::AnyView::U32($v) => $body,
            $crate::samples::AnyView::I32($v) => $body,
            $crate::samples::AnyView::F32($v) => $body,
            $crate::samples::AnyView::F64($v) => $body,
        }
    };
}

impl<'a, T: Sample> From<GridView<'a, T>> for AnyView<'a> {
    fn from(v: GridView<'a, T>) -> Self {
        T::any_view(v)
    }
}

impl<'a> AnyView<'a> {
    /// Samples along x, y, z.
    pub fn dims(&self) -> [usize; 3] {
        crate::with_view!(self, v => v.dims())
    }

    /// The sample type's numpy name.
    pub fn dtype(&self) -> &'static str {
        fn name<T: Sample>(_: &GridView<'_, T>) -> &'static str {
            T::DTYPE
        }
        crate::with_view!(self, v => name(v))
    }

    /// Whether the type's values may be non-finite.
    pub fn is_float(&self) -> bool {
        matches!(self, AnyView::F32(_) | AnyView::F64(_))
    }

    /// The same samples read with the opposite sign.
    pub fn negated(self) -> Self {
        crate::with_view!(self, v => AnyView::from(v.negated()))
    }

    /// See [`GridView::every`].
    pub fn every(self, step: usize) -> Option<Self> {
        crate::with_view!(self, v => v.every(step).map(AnyView::from))
    }

    /// See [`GridView::block`].
    pub fn block(self, lo: [usize; 3], dims: [usize; 3]) -> Option<Self> {
        crate::with_view!(self, v => v.block(lo, dims).map(AnyView::from))
    }

    /// See [`GridView::to_vec`].
    pub fn to_vec(&self) -> Vec<f32> {
        crate::with_view!(self, v => v.to_vec())
    }

    /// See [`GridView::to_vec_typed`]: the samples in their own type (the sign not applied).
    pub fn to_stored(&self) -> super::StoredValues {
        use super::StoredValues as S;
        match self {
            AnyView::Bool(v) => S::Bool(v.to_vec_typed()),
            AnyView::U8(v) => S::U8(v.to_vec_typed()),
            AnyView::I8(v) => S::I8(v.to_vec_typed()),
            AnyView::U16(v) => S::U16(v.to_vec_typed()),
            AnyView::I16(v) => S::I16(v.to_vec_typed()),
            AnyView::U32(v) => S::U32(v.to_vec_typed()),
            AnyView::I32(v) => S::I32(v.to_vec_typed()),
            AnyView::F32(v) => S::F32(v.to_vec_typed()),
            AnyView::F64(v) => S::F64(v.to_vec_typed()),
        }
    }

    /// See [`GridView::range`].
    pub fn range(&self) -> ViewRange {
        crate::with_view!(self, v => v.range())
    }

    /// See [`GridView::count_below`].
    pub fn count_below(&self, iso: f32) -> usize {
        crate::with_view!(self, v => v.count_below(iso))
    }

    /// See [`GridView::first_non_finite`].
    pub fn first_non_finite(&self) -> Option<([usize; 3], f32)> {
        crate::with_view!(self, v => v.first_non_finite())
    }

    /// Sample `(x, y, z)`.
    pub fn at(&self, x: usize, y: usize, z: usize) -> f32 {
        crate::with_view!(self, v => v.at(x, y, z))
    }
}
