//! Volumes as fields: a grid of values read from a file (a CT or MRI scan, a voxel volume, a grid
//! `--samples-out` wrote) with the affine that places each voxel in world coordinates.
//!
//! A [`Volume`] holds the voxel values in index order (x fastest, as everywhere in isolab), in
//! the type the file stores them in ([`StoredValues`]: a uint8 scan takes a byte a voxel), and
//! the index-to-world affine from the file's header (spacing, origin and direction: the NIfTI
//! sform/qform, NRRD's space directions, MetaImage's TransformMatrix). Extractors mesh it in two
//! ways:
//!
//! - **on its own voxel grid** (the default): the values become [`crate::Samples`] on the grid of
//!   index coordinates (origin 0, spacing 1), sharing the volume's memory
//!   ([`crate::Samples::stored`]), the extractor runs there, and the mesh is mapped to world
//!   coordinates afterwards by [`Volume::index_to_world`] ([`crate::TriMesh::transform`]). No
//!   value is interpolated, so the mesh is what a peer meshing the same array gives.
//! - **resampled** (`--resolution N`): [`VolumeField`] is the trilinear interpolant of the values
//!   in world coordinates, a [`Field`] like any other, sampled on an isotropic grid over its
//!   world bounding box. Points outside the volume take the nearest voxel's value.
//!
//! Which side is inside is the caller's choice ([`crate::fields::Complement`] turns "brighter
//! than the iso-value" into isolab's "`f < iso`"); this module only stores values.

use crate::field::{Field, FieldError};
use crate::geometry::Aabb;
use crate::samples::stored::with_stored;
use crate::samples::{Sample, StoredValues};
use glam::{DAffine3, DMat3, DVec3, Vec3};
use std::sync::Arc;

/// Voxel values on a grid and the affine placing voxel `(i, j, k)` in world coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct Volume {
    /// Name (the file stem), used in messages and reports.
    pub name: String,
    /// Voxels along i, j and k (at least 2 each).
    pub dims: [usize; 3],
    /// Values, `i + ni * (j + nj * k)`, in their stored type; all finite.
    values: Arc<StoredValues>,
    /// Voxel index `(i, j, k)` to world position (millimetres for scans).
    pub index_to_world: DAffine3,
}

impl Volume {
    /// Checks and wraps `f32` values read elsewhere ([`Volume::stored`]).
    pub fn new(
        name: impl Into<String>,
        dims: [usize; 3],
        values: Vec<f32>,
        index_to_world: DAffine3,
    ) -> Result<Self, FieldError> {
        Self::stored(name, dims, StoredValues::F32(values), index_to_world)
    }

    /// Checks and wraps values read elsewhere in their own type: at least 2 voxels per axis, as
    /// many values as voxels, every value finite (the first non-finite voxel is named), and an
    /// affine that is finite with a non-zero determinant (zero or non-finite spacing is refused).
    pub fn stored(
        name: impl Into<String>,
        dims: [usize; 3],
        values: StoredValues,
        index_to_world: DAffine3,
    ) -> Result<Self, FieldError> {
        let name = name.into();
        let bad = |reason: String| FieldError::BadVolume { name: name.clone(), reason };
        if dims.iter().any(|&d| d < 2) {
            return Err(bad(format!(
                "shape {} x {} x {}: at least 2 voxels are needed along every axis",
                dims[0], dims[1], dims[2]
            )));
        }
        let voxels = dims.iter().try_fold(1usize, |acc, &d| acc.checked_mul(d));
        if voxels != Some(values.len()) {
            return Err(bad(format!("{} values for a {} x {} x {} grid", values.len(), dims[0], dims[1], dims[2])));
        }
        if let (_, _, Some((at, value))) = values.range() {
            let [ni, nj, _] = dims;
            return Err(bad(format!(
                "voxel ({}, {}, {}) is {}; volumes must be finite",
                at % ni,
                (at / ni) % nj,
                at / (ni * nj),
                value
            )));
        }
        check_affine(&index_to_world).map_err(bad)?;
        Ok(Self { name, dims, values: Arc::new(values), index_to_world })
    }

    /// The values, in their stored type (shared: [`crate::Samples::stored`] meshes them in place).
    pub fn values(&self) -> &Arc<StoredValues> {
        &self.values
    }

    /// The values as `f32`: borrowed when stored as `f32`, else converted (a copy).
    pub fn values_f32(&self) -> std::borrow::Cow<'_, [f32]> {
        self.values.as_f32()
    }

    /// The voxel edge lengths along i, j and k in world units (the affine's column lengths).
    pub fn spacing(&self) -> [f64; 3] {
        let m = self.index_to_world.matrix3;
        [m.x_axis.length(), m.y_axis.length(), m.z_axis.length()]
    }

    /// The world position of voxel index coordinates `p` (fractional allowed).
    pub fn to_world(&self, p: DVec3) -> DVec3 {
        self.index_to_world.transform_point3(p)
    }

    /// The world bounding box of the voxel centres.
    pub fn world_bounds(&self) -> Aabb {
        let mut b = Aabb::empty();
        for c in 0..8 {
            let corner = DVec3::new(
                if c & 1 == 0 { 0.0 } else { (self.dims[0] - 1) as f64 },
                if c & 2 == 0 { 0.0 } else { (self.dims[1] - 1) as f64 },
                if c & 4 == 0 { 0.0 } else { (self.dims[2] - 1) as f64 },
            );
            b.grow(self.to_world(corner).as_vec3());
        }
        b
    }

    /// Smallest and largest value.
    pub fn range(&self) -> (f32, f32) {
        let (lo, hi, _) = self.values.range();
        (lo, hi)
    }

    /// Value `i` (`i + ni * (j + nj * k)`) as `f32`.
    pub fn value(&self, i: usize) -> f32 {
        self.values.get(i)
    }

    /// The value at fractional index coordinates, trilinear between the eight voxels around it;
    /// coordinates outside the grid are clamped to it (the nearest voxel's value).
    pub fn trilinear(&self, p: DVec3) -> f32 {
        with_stored!(&*self.values, v => trilinear_in(v, self.dims, p))
    }

    /// Values at the cell centres of the voxel grid (the mean of each cell's eight voxels, which
    /// is the trilinear interpolant there): the centre half of a body-centred cubic lattice on
    /// the voxel grid.
    pub fn cell_centres(&self) -> Vec<f32> {
        with_stored!(&*self.values, v => cell_centres_of(v, self.dims))
    }

    /// The iso-value that best separates the values into two classes (Otsu 1979, on a
    /// 256-bin histogram between the smallest and largest value): a default for scans whose user
    /// gave none. `None` when every value is the same.
    pub fn otsu_threshold(&self) -> Option<f32> {
        let (lo, hi) = self.range();
        let mut histogram = OtsuHistogram::new(lo, hi)?;
        with_stored!(&*self.values, v => histogram.add_values(v));
        Some(histogram.threshold())
    }
}

/// [`Volume::trilinear`] of values of one type.
fn trilinear_in<T: Sample>(values: &[T], dims: [usize; 3], p: DVec3) -> f32 {
    let [ni, nj, nk] = dims;
    let clamp = |v: f64, n: usize| if v.is_nan() { 0.0 } else { v.clamp(0.0, (n - 1) as f64) };
    let (x, y, z) = (clamp(p.x, ni), clamp(p.y, nj), clamp(p.z, nk));
    let (i, j, k) = ((x as usize).min(ni - 2), (y as usize).min(nj - 2), (z as usize).min(nk - 2));
    let (fx, fy, fz) = ((x - i as f64) as f32, (y - j as f64) as f32, (z - k as f64) as f32);
    let at = |di: usize, dj: usize, dk: usize| values[(i + di) + ni * ((j + dj) + nj * (k + dk))].to_f32();
    let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
    let x00 = lerp(at(0, 0, 0), at(1, 0, 0), fx);
    let x10 = lerp(at(0, 1, 0), at(1, 1, 0), fx);
    let x01 = lerp(at(0, 0, 1), at(1, 0, 1), fx);
    let x11 = lerp(at(0, 1, 1), at(1, 1, 1), fx);
    lerp(lerp(x00, x10, fy), lerp(x01, x11, fy), fz)
}

/// [`Volume::cell_centres`] of values of one type.
fn cell_centres_of<T: Sample>(values: &[T], dims: [usize; 3]) -> Vec<f32> {
    let [ni, nj, nk] = dims;
    let mut out = Vec::with_capacity((ni - 1) * (nj - 1) * (nk - 1));
    for k in 0..nk - 1 {
        for j in 0..nj - 1 {
            for i in 0..ni - 1 {
                let at = |di: usize, dj: usize, dk: usize| values[(i + di) + ni * ((j + dj) + nj * (k + dk))].to_f32();
                let sum =
                    at(0, 0, 0) + at(1, 0, 0) + at(0, 1, 0) + at(1, 1, 0) + at(0, 0, 1) + at(1, 0, 1) + at(0, 1, 1) + at(1, 1, 1);
                out.push(sum * 0.125);
            }
        }
    }
    out
}

/// Otsu's threshold of `values` (256 bins between their extremes): the bin boundary that
/// maximises the between-class variance. `None` for fewer than two distinct values.
pub fn otsu_threshold(values: &[f32]) -> Option<f32> {
    let (lo, hi) = values.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    let mut histogram = OtsuHistogram::new(lo, hi)?;
    histogram.add(values);
    Some(histogram.threshold())
}

/// The histogram [`otsu_threshold`] reads, filled a run of values at a time: for a volume read in
/// slabs, one pass for the extremes, then one to fill it (the same threshold as the whole).
#[derive(Clone, Debug)]
pub struct OtsuHistogram {
    lo: f32,
    width: f64,
    counts: [u64; OtsuHistogram::BINS],
    total: u64,
}

impl OtsuHistogram {
    const BINS: usize = 256;

    /// An empty histogram of 256 bins between the values' extremes; `None` unless `lo < hi`, both
    /// finite.
    pub fn new(lo: f32, hi: f32) -> Option<Self> {
        if hi <= lo || !hi.is_finite() || !lo.is_finite() {
            return None;
        }
        let width = (hi as f64 - lo as f64) / Self::BINS as f64;
        Some(Self { lo, width, counts: [0; Self::BINS], total: 0 })
    }

    /// Counts `values` (each within the extremes given).
    pub fn add(&mut self, values: &[f32]) {
        self.add_values(values);
    }

    /// Counts `values` of any sample type, each read as `f32`.
    pub fn add_values<T: Sample>(&mut self, values: &[T]) {
        for &v in values {
            let bin = (((v.to_f32() as f64 - self.lo as f64) / self.width) as usize).min(Self::BINS - 1);
            self.counts[bin] += 1;
        }
        self.total += values.len() as u64;
    }

    /// The bin boundary that maximises the between-class variance.
    pub fn threshold(&self) -> f32 {
        let total = self.total as f64;
        let sum_all: f64 = self.counts.iter().enumerate().map(|(b, &n)| b as f64 * n as f64).sum();
        let (mut below, mut sum_below, mut best, mut best_bin) = (0.0f64, 0.0f64, -1.0f64, 0usize);
        for (b, &n) in self.counts.iter().enumerate().take(Self::BINS - 1) {
            below += n as f64;
            sum_below += b as f64 * n as f64;
            let above = total - below;
            if below == 0.0 || above == 0.0 {
                continue;
            }
            let (mean_below, mean_above) = (sum_below / below, (sum_all - sum_below) / above);
            let between = below * above * (mean_below - mean_above).powi(2);
            if between > best {
                best = between;
                best_bin = b;
            }
        }
        (self.lo as f64 + (best_bin + 1) as f64 * self.width) as f32
    }
}

fn check_affine(a: &DAffine3) -> Result<(), String> {
    let m = a.matrix3;
    let finite = m.x_axis.is_finite() && m.y_axis.is_finite() && m.z_axis.is_finite() && a.translation.is_finite();
    if !finite {
        return Err(format!("the index-to-world affine is not finite ({})", describe(a)));
    }
    let spacing = [m.x_axis.length(), m.y_axis.length(), m.z_axis.length()];
    if spacing.contains(&0.0) {
        return Err(format!("voxel spacing {spacing:?} has a zero side ({})", describe(a)));
    }
    let det = m.determinant();
    if det.abs() <= 1e-12 * spacing.iter().product::<f64>() {
        return Err(format!("the index-to-world affine is singular: its axes are parallel ({})", describe(a)));
    }
    Ok(())
}

fn describe(a: &DAffine3) -> String {
    let m = a.matrix3;
    let row = |r: usize| format!("[{} {} {} {}]", m.col(0)[r], m.col(1)[r], m.col(2)[r], a.translation[r]);
    format!("rows {} {} {}", row(0), row(1), row(2))
}

/// The affine with columns `axes[a] * spacing[a]` and translation `origin`: how NRRD and
/// MetaImage headers describe a grid.
pub fn affine_from_axes(axes: [DVec3; 3], spacing: [f64; 3], origin: DVec3) -> DAffine3 {
    DAffine3 { matrix3: DMat3::from_cols(axes[0] * spacing[0], axes[1] * spacing[1], axes[2] * spacing[2]), translation: origin }
}

/// A [`Volume`] as a field in world coordinates: the trilinear interpolant of its values at the
/// index coordinates of `p`, clamped to the grid.
pub struct VolumeField {
    volume: std::sync::Arc<Volume>,
    world_to_index: DAffine3,
    domain: Aabb,
}

impl VolumeField {
    /// The field of `volume`.
    pub fn new(volume: std::sync::Arc<Volume>) -> Self {
        let world_to_index = volume.index_to_world.inverse();
        let domain = volume.world_bounds();
        Self { volume, world_to_index, domain }
    }

    /// The volume.
    pub fn volume(&self) -> &std::sync::Arc<Volume> {
        &self.volume
    }
}

impl Field for VolumeField {
    fn name(&self) -> &str {
        &self.volume.name
    }

    fn value(&self, p: Vec3) -> f32 {
        self.volume.trilinear(self.world_to_index.transform_point3(p.as_dvec3()))
    }

    fn domain(&self) -> Aabb {
        self.domain
    }

    /// Central differences over a tenth of the smallest voxel side: within a cell the
    /// interpolant is smooth, and the step stays well under a voxel.
    fn difference_step(&self) -> f32 {
        let s = self.volume.spacing();
        (0.1 * s[0].min(s[1]).min(s[2])) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    fn ramp(affine: DAffine3) -> Volume {
        let dims = [4, 5, 6];
        let values = (0..120).map(|n| (n % 4) as f32 + 10.0 * ((n / 4) % 5) as f32 + 100.0 * (n / 20) as f32).collect();
        Volume::new("ramp", dims, values, affine).unwrap()
    }

    #[test]
    fn trilinear_is_exact_on_a_linear_ramp_and_clamps_outside() {
        let v = ramp(DAffine3::IDENTITY);
        assert_eq!(v.trilinear(DVec3::new(1.0, 2.0, 3.0)), 1.0 + 20.0 + 300.0);
        assert!((v.trilinear(DVec3::new(1.5, 2.25, 3.5)) - (1.5 + 22.5 + 350.0)).abs() < 1e-4);
        assert_eq!(v.trilinear(DVec3::new(-5.0, 0.0, 99.0)), 500.0);
        assert_eq!(v.trilinear(DVec3::new(3.0, 4.0, 5.0)), 3.0 + 40.0 + 500.0);
    }

    #[test]
    fn the_field_reads_world_coordinates_through_the_affine() {
        // x flipped (negative determinant), anisotropic, shifted.
        let a = affine_from_axes([DVec3::NEG_X, DVec3::Z, DVec3::Y], [2.0, 0.5, 3.0], DVec3::new(10.0, -4.0, 1.0));
        let v = Arc::new(ramp(a));
        let f = VolumeField::new(v.clone());
        let idx = DVec3::new(2.0, 3.0, 1.0);
        let world = v.to_world(idx).as_vec3();
        assert!((f.value(world) - (2.0 + 30.0 + 100.0)).abs() < 1e-3, "{}", f.value(world));
        let b = f.domain();
        assert!((b.min.x - 4.0).abs() < 1e-6 && (b.max.x - 10.0).abs() < 1e-6, "{b:?}");
        assert!((b.max.y - (-4.0 + 15.0)).abs() < 1e-5 && (b.max.z - 3.0).abs() < 1e-6, "{b:?}");
        assert_eq!(v.spacing(), [2.0, 0.5, 3.0]);
    }

    #[test]
    fn bad_volumes_are_named() {
        let e = Volume::new("flat", [4, 4, 1], vec![0.0; 16], DAffine3::IDENTITY).unwrap_err().to_string();
        assert!(e.contains("flat") && e.contains("4 x 4 x 1"), "{e}");
        let mut values = vec![0.0; 8];
        values[5] = f32::NAN;
        let e = Volume::new("nan", [2, 2, 2], values, DAffine3::IDENTITY).unwrap_err().to_string();
        assert!(e.contains("voxel (1, 0, 1) is NaN"), "{e}");
        let zero = affine_from_axes([DVec3::X, DVec3::Y, DVec3::Z], [1.0, 0.0, 1.0], DVec3::ZERO);
        let e = Volume::new("z", [2, 2, 2], vec![0.0; 8], zero).unwrap_err().to_string();
        assert!(e.contains("zero side"), "{e}");
        let inf = affine_from_axes([DVec3::X, DVec3::Y, DVec3::Z], [1.0, f64::INFINITY, 1.0], DVec3::ZERO);
        let e = Volume::new("i", [2, 2, 2], vec![0.0; 8], inf).unwrap_err().to_string();
        assert!(e.contains("not finite"), "{e}");
        assert!(Volume::new("short", [2, 2, 2], vec![0.0; 7], DAffine3::IDENTITY).is_err());
    }

    #[test]
    fn otsu_splits_two_clusters_between_them() {
        let values: Vec<f32> =
            (0..1000).map(|i| if i % 3 == 0 { 200.0 + (i % 7) as f32 } else { 10.0 + (i % 5) as f32 }).collect();
        let t = otsu_threshold(&values).unwrap();
        assert!(t > 14.0 && t < 200.0, "{t}");
        assert_eq!(otsu_threshold(&[3.0; 10]), None);
    }

    #[test]
    fn cell_centres_are_the_mean_of_eight_voxels() {
        let v = ramp(DAffine3::IDENTITY);
        let c = v.cell_centres();
        assert_eq!(c.len(), 3 * 4 * 5);
        assert!((c[0] - (0.5 + 5.0 + 50.0)).abs() < 1e-5);
    }
}
