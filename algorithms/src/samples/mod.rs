//! Field values taken once on a lattice, reusable by any number of extractors: owned `f32`
//! samples that isolab takes itself, or a caller's array borrowed where it lies, in its own type
//! ([`view`]).
//!
//! Sampling runs in parallel (rayon, one z-slice per task) and its wall time is recorded on its
//! own ([`Samples::sampling_time`]), so extraction times never include field evaluation: the
//! control the RMT paper (Costen 2026, section 1.1) asks for.
//!
//! Borrowed samples ([`Samples::borrowed`]) are read in place by the extractors whose `INFO`
//! says [`SampleAccess::Borrowed`](crate::extract::SampleAccess): generic over the sample type,
//! they check finiteness as they read. For any other extractor, [`crate::Extractor::extract`]
//! converts the view once into `f32` samples ([`Samples::values`], kept for later calls) and
//! checks them first, so every extractor meshes borrowed samples as it meshes their copy.

mod any_view;
pub mod stored;
pub mod view;

use crate::field::Field;
use crate::lattice::{Grid, Lattice};
use glam::Vec3;
use rayon::prelude::*;
use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};
pub use stored::StoredValues;
pub use view::{f32_at_or_below, AnyView, GridView, Sample, ViewError, ViewRange};

/// Errors taking samples.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SampleError {
    /// The field returned NaN or an infinity.
    #[error("field '{field}' is {value} at ({:.6}, {:.6}, {:.6}) (sample {index}); fields must be finite", position[0], position[1], position[2])]
    NonFinite {
        /// The field's name.
        field: String,
        /// Where it happened.
        position: [f32; 3],
        /// Flat sample index.
        index: usize,
        /// The value (NaN or ±inf).
        value: f32,
    },
    /// Values given directly do not match the lattice.
    #[error("{given} values given for a lattice of {expected} samples")]
    WrongLength {
        /// Values given.
        given: usize,
        /// Samples in the lattice.
        expected: usize,
    },
    /// Borrowed samples need a cubic lattice of the view's dims.
    #[error("a {view:?} view of samples cannot be a {lattice} lattice of {dims:?} samples")]
    ViewMismatch {
        /// The view's dims.
        view: [usize; 3],
        /// The lattice's kind.
        lattice: &'static str,
        /// The lattice's corner grid dims.
        dims: [usize; 3],
    },
}

/// Field values on a lattice, with the iso-value to extract and (optionally) the field itself, so
/// extractors may ask for exact gradients: owned, or borrowed for `'a` (module doc).
#[derive(Clone)]
pub struct Samples<'a> {
    lattice: Lattice,
    values: Values<'a>,
    iso: f32,
    field: Option<Arc<dyn Field>>,
    sampling_time: Duration,
}

/// Where the values are.
#[derive(Clone)]
enum Values<'a> {
    /// Taken by isolab, in the lattice's order.
    Owned(Vec<f32>),
    /// The caller's, and their conversion once an extractor that cannot read them asked for it.
    Borrowed { view: AnyView<'a>, copy: OnceLock<Vec<f32>> },
    /// Held in their own type, shared (a volume file's voxels), read with a sign, and their
    /// conversion once asked for.
    Stored { values: Arc<StoredValues>, sign: f32, copy: OnceLock<Vec<f32>> },
}

impl std::fmt::Debug for Samples<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Samples")
            .field("lattice", &self.lattice)
            .field("iso", &self.iso)
            .field("field", &self.field.as_ref().map(|f| f.name().to_owned()))
            .field("sampling_time", &self.sampling_time)
            .finish_non_exhaustive()
    }
}

impl Samples<'static> {
    /// Samples `field` on a cubic grid.
    pub fn sample_cubic(field: Arc<dyn Field>, grid: Grid, iso: f32) -> Result<Samples<'static>, SampleError> {
        Self::sample(field, Lattice::Cubic(grid), iso)
    }

    /// Samples `field` on `lattice` in parallel and checks every value is finite.
    pub fn sample(field: Arc<dyn Field>, lattice: Lattice, iso: f32) -> Result<Samples<'static>, SampleError> {
        let start = Instant::now();
        let mut values = vec![0.0f32; lattice.sample_count()];
        let grid = *lattice.grid();
        let (corners, centres) = values.split_at_mut(grid.len());
        field.sample_grid(&grid, iso, corners);
        if let Lattice::Bcc(_) = lattice {
            field.sample_grid(&grid.centres(), iso, centres);
        }
        let sampling_time = start.elapsed();
        check_finite(field.name(), &lattice, &values)?;
        Ok(Samples { lattice, values: Values::Owned(values), iso, field: Some(field), sampling_time })
    }

    /// Wraps values sampled elsewhere (a file, a peer, a test). They must be finite.
    pub fn from_values(lattice: Lattice, values: Vec<f32>, iso: f32) -> Result<Samples<'static>, SampleError> {
        if values.len() != lattice.sample_count() {
            return Err(SampleError::WrongLength { given: values.len(), expected: lattice.sample_count() });
        }
        check_finite("values", &lattice, &values)?;
        Ok(Samples { lattice, values: Values::Owned(values), iso, field: None, sampling_time: Duration::ZERO })
    }

    /// Values held in their own type on `grid` (as many as it has samples), shared with whoever
    /// else holds them (a volume), read times -1 when `negated` (inside above the level). Their
    /// holder vouches that they are finite ([`crate::fields::Volume::stored`] checks).
    pub fn stored(grid: Grid, values: Arc<StoredValues>, negated: bool, iso: f32) -> Result<Samples<'static>, SampleError> {
        if values.len() != grid.len() {
            return Err(SampleError::WrongLength { given: values.len(), expected: grid.len() });
        }
        let sign = if negated { -1.0 } else { 1.0 };
        Ok(Samples {
            lattice: Lattice::Cubic(grid),
            values: Values::Stored { values, sign, copy: OnceLock::new() },
            iso,
            field: None,
            sampling_time: Duration::ZERO,
        })
    }
}

impl<'a> Samples<'a> {
    /// Borrows a caller's samples where they lie, on `grid` (the view's dims), with no copy.
    /// Their finiteness is checked as they are meshed (module doc): an extraction from a view
    /// with a NaN or an infinity fails with [`SampleError::NonFinite`] naming the sample.
    pub fn borrowed(grid: Grid, view: impl Into<AnyView<'a>>, iso: f32) -> Result<Samples<'a>, SampleError> {
        let view = view.into();
        if view.dims() != grid.dims {
            return Err(SampleError::ViewMismatch { view: view.dims(), lattice: "cubic", dims: grid.dims });
        }
        Ok(Samples {
            lattice: Lattice::Cubic(grid),
            values: Values::Borrowed { view, copy: OnceLock::new() },
            iso,
            field: None,
            sampling_time: Duration::ZERO,
        })
    }

    /// The corner grid's samples as a view: the borrowed view, or the owned values' (`f32`, in
    /// isolab's order), which generic extractors read through the same code.
    pub fn view(&self) -> AnyView<'_> {
        match &self.values {
            Values::Owned(v) => {
                let grid = self.lattice.grid();
                // The corner grid is the first `grid.len()` values, in isolab's order.
                let dims = grid.dims;
                AnyView::F32(
                    GridView::strided(&v[..grid.len()], dims, 0, [1, dims[0] as isize, (dims[0] * dims[1]) as isize])
                        .unwrap_or_else(|_| unreachable!("values of length grid.len() hold the corner grid")),
                )
            }
            Values::Borrowed { view, .. } => *view,
            Values::Stored { values, sign, .. } => {
                let view = values
                    .view(self.lattice.grid().dims)
                    .unwrap_or_else(|| unreachable!("stored values hold the grid (checked when made)"));
                if *sign < 0.0 {
                    view.negated()
                } else {
                    view
                }
            }
        }
    }

    /// Whether the values are borrowed (and so their finiteness is not yet checked).
    pub fn is_borrowed(&self) -> bool {
        matches!(self.values, Values::Borrowed { .. })
    }

    /// Whether values not held as `f32` in isolab's order have been converted into `f32`
    /// samples (by [`Samples::values`]).
    pub fn was_converted(&self) -> bool {
        match &self.values {
            Values::Owned(_) => false,
            Values::Borrowed { copy, .. } | Values::Stored { copy, .. } => copy.get().is_some(),
        }
    }

    /// Checks that borrowed values are finite, converting them once (what
    /// [`crate::Extractor::extract`] does before an extractor that cannot read them in place).
    pub fn check_converted(&self) -> Result<(), SampleError> {
        if let Values::Borrowed { view, .. } = &self.values {
            if view.is_float() {
                check_finite("values", &self.lattice, self.values())?;
            }
        }
        Ok(())
    }

    /// Attaches the field these values were taken from (so extractors may ask it for exact
    /// gradients); the caller vouches that the values are the field's.
    pub fn with_field(mut self, field: Arc<dyn Field>) -> Samples<'a> {
        self.field = Some(field);
        self
    }

    /// Records how long taking these values took (for values wrapped by [`Samples::from_values`]
    /// after converting a file's voxels, say).
    pub fn with_sampling_time(mut self, time: Duration) -> Samples<'a> {
        self.sampling_time = time;
        self
    }

    /// The lattice.
    pub fn lattice(&self) -> &Lattice {
        &self.lattice
    }

    /// The corner grid (the whole lattice for cubic samples).
    pub fn grid(&self) -> &Grid {
        self.lattice.grid()
    }

    /// All values in the documented order ([`crate::lattice`]) as `f32`; borrowed values are
    /// converted on the first call (a copy, kept for later calls).
    pub fn values(&self) -> &[f32] {
        match &self.values {
            Values::Owned(v) => v,
            Values::Borrowed { view, copy } => copy.get_or_init(|| view.to_vec()),
            Values::Stored { values, sign, .. } if *sign > 0.0 && matches!(**values, StoredValues::F32(_)) => match &**values {
                StoredValues::F32(v) => v,
                _ => unreachable!("matched as f32"),
            },
            Values::Stored { copy, .. } => copy.get_or_init(|| self.view().to_vec()),
        }
    }

    /// Mutable values, for editing (terrain brushes); borrowed values become owned (a copy).
    /// Callers must keep them finite.
    pub fn values_mut(&mut self) -> &mut [f32] {
        if !matches!(self.values, Values::Owned(_)) {
            let owned = match &mut self.values {
                Values::Borrowed { copy, .. } | Values::Stored { copy, .. } => copy.take(),
                Values::Owned(_) => None,
            };
            let owned = owned.unwrap_or_else(|| self.view().to_vec());
            self.values = Values::Owned(owned);
        }
        match &mut self.values {
            Values::Owned(v) => v,
            _ => &mut [],
        }
    }

    /// The iso-value: inside is `f < iso`.
    pub fn iso(&self) -> f32 {
        self.iso
    }

    /// The field the samples came from, if known.
    pub fn field(&self) -> Option<&Arc<dyn Field>> {
        self.field.as_ref()
    }

    /// Wall time spent evaluating the field.
    pub fn sampling_time(&self) -> Duration {
        self.sampling_time
    }

    /// Bytes held by the values (none for borrowed values until converted).
    pub fn bytes(&self) -> usize {
        match &self.values {
            Values::Owned(v) => v.len() * std::mem::size_of::<f32>(),
            Values::Borrowed { copy, .. } => copy.get().map_or(0, Vec::len) * std::mem::size_of::<f32>(),
            Values::Stored { values, copy, .. } => values.bytes() + copy.get().map_or(0, Vec::len) * std::mem::size_of::<f32>(),
        }
    }
}

fn check_finite(name: &str, lattice: &Lattice, values: &[f32]) -> Result<(), SampleError> {
    // Blocks of 64 Ki values: rayon's per-item `position_first` cost 74 ms on 8.7 M values.
    const BLOCK: usize = 1 << 16;
    let block = values.par_chunks(BLOCK).position_first(|c| c.iter().fold(false, |bad, v| bad | !v.is_finite()));
    let first = block.and_then(|b| values[b * BLOCK..].iter().position(|v| !v.is_finite()).map(|i| b * BLOCK + i));
    match first {
        None => Ok(()),
        Some(index) => {
            let p: Vec3 = lattice.position_of(index);
            Err(SampleError::NonFinite { field: name.to_owned(), position: p.to_array(), index, value: values[index] })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Aabb;

    struct HoleAt(Vec3);
    impl Field for HoleAt {
        fn name(&self) -> &str {
            "hole"
        }
        fn value(&self, p: Vec3) -> f32 {
            if p.distance(self.0) < 1e-4 {
                f32::NAN
            } else {
                p.length() - 0.3
            }
        }
        fn domain(&self) -> Aabb {
            Aabb::cube(0.5)
        }
    }

    #[test]
    fn non_finite_values_name_their_position() {
        let grid = Grid::covering(&Aabb::cube(0.5), 11).unwrap();
        let bad = grid.position(3, 4, 5);
        let err = Samples::sample_cubic(Arc::new(HoleAt(bad)), grid, 0.0).unwrap_err();
        match &err {
            SampleError::NonFinite { position, index, .. } => {
                assert_eq!(*index, grid.index(3, 4, 5));
                assert!(Vec3::from(*position).distance(bad) < 1e-6);
            }
            e => panic!("unexpected {e}"),
        }
        assert!(err.to_string().contains("NaN"), "{err}");
    }

    #[test]
    fn bcc_samples_hold_both_grids() {
        let grid = Grid::covering(&Aabb::cube(0.5), 5).unwrap();
        let s = Samples::sample(Arc::new(crate::fields::Sphere::default()), Lattice::Bcc(grid), 0.0).unwrap();
        assert_eq!(s.values().len(), 125 + 64);
        // The first centre sample is at the first cell's centre.
        let c = grid.position(0, 0, 0) + Vec3::splat(grid.spacing / 2.0);
        assert!((s.values()[125] - (c.length() - 0.4)).abs() < 1e-6);
    }
}
