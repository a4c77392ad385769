//! Field values taken once on a lattice, reusable by any number of extractors.
//!
//! Sampling runs in parallel (rayon, one z-slice per task) and its wall time is recorded on its
//! own ([`Samples::sampling_time`]), so extraction times never include field evaluation: the
//! control the RMT paper (Costen 2026, section 1.1) asks for.

use crate::field::Field;
use crate::lattice::{Grid, Lattice};
use glam::Vec3;
use rayon::prelude::*;
use std::sync::Arc;
use std::time::{Duration, Instant};

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
}

/// Field values on a lattice, with the iso-value to extract and (optionally) the field itself, so
/// extractors may ask for exact gradients.
#[derive(Clone)]
pub struct Samples {
    lattice: Lattice,
    values: Vec<f32>,
    iso: f32,
    field: Option<Arc<dyn Field>>,
    sampling_time: Duration,
}

impl std::fmt::Debug for Samples {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Samples")
            .field("lattice", &self.lattice)
            .field("iso", &self.iso)
            .field("field", &self.field.as_ref().map(|f| f.name().to_owned()))
            .field("sampling_time", &self.sampling_time)
            .finish_non_exhaustive()
    }
}

impl Samples {
    /// Samples `field` on a cubic grid.
    pub fn sample_cubic(field: Arc<dyn Field>, grid: Grid, iso: f32) -> Result<Samples, SampleError> {
        Self::sample(field, Lattice::Cubic(grid), iso)
    }

    /// Samples `field` on `lattice` in parallel and checks every value is finite.
    pub fn sample(field: Arc<dyn Field>, lattice: Lattice, iso: f32) -> Result<Samples, SampleError> {
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
        Ok(Samples { lattice, values, iso, field: Some(field), sampling_time })
    }

    /// Wraps values sampled elsewhere (a file, a peer, a test). They must be finite.
    pub fn from_values(lattice: Lattice, values: Vec<f32>, iso: f32) -> Result<Samples, SampleError> {
        if values.len() != lattice.sample_count() {
            return Err(SampleError::WrongLength { given: values.len(), expected: lattice.sample_count() });
        }
        check_finite("values", &lattice, &values)?;
        Ok(Samples { lattice, values, iso, field: None, sampling_time: Duration::ZERO })
    }

    /// Attaches the field these values were taken from (so extractors may ask it for exact
    /// gradients); the caller vouches that the values are the field's.
    pub fn with_field(mut self, field: Arc<dyn Field>) -> Samples {
        self.field = Some(field);
        self
    }

    /// Records how long taking these values took (for values wrapped by [`Samples::from_values`]
    /// after converting a file's voxels, say).
    pub fn with_sampling_time(mut self, time: Duration) -> Samples {
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

    /// All values in the documented order ([`crate::lattice`]).
    pub fn values(&self) -> &[f32] {
        &self.values
    }

    /// Mutable values, for editing (terrain brushes). Callers must keep them finite.
    pub fn values_mut(&mut self) -> &mut [f32] {
        &mut self.values
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

    /// Bytes held by the values.
    pub fn bytes(&self) -> usize {
        self.values.len() * std::mem::size_of::<f32>()
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
