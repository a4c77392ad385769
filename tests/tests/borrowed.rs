//! Borrowed samples ([`Samples::borrowed`]: a caller's array read where it lies, in its own type
//! and memory order) give every registered extractor the mesh their `f32` copy gives, bit for
//! bit, for every sample type, memory order and sign; extractors read them in place or copy them
//! as their `INFO` says; a NaN or infinity in borrowed samples is an error naming the sample,
//! never a mesh.

use glam::Vec3;
use isolab_algorithms::extract::SampleAccess;
use isolab_algorithms::samples::{AnyView, GridView, Sample, SampleError};
use isolab_algorithms::{extractors, ExtractError, Extraction, Grid, Lattice, Options, Samples};

const DIMS: [usize; 3] = [13, 11, 9];

/// Two blobs and a ripple on `DIMS`, as a value in `0..=scale` (before the type's conversion),
/// in isolab's order (x fastest).
fn field(scale: f64) -> Vec<f64> {
    let [nx, ny, nz] = DIMS;
    let mut out = Vec::with_capacity(nx * ny * nz);
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let p = Vec3::new(x as f32 / (nx - 1) as f32, y as f32 / (ny - 1) as f32, z as f32 / (nz - 1) as f32);
                let a = (p - Vec3::new(0.35, 0.4, 0.45)).length() / 0.3;
                let b = (p - Vec3::new(0.7, 0.6, 0.5)).length() / 0.22;
                let v = (a.min(b) as f64 + 0.05 * (9.0 * p.x as f64).sin()).clamp(0.0, 1.0);
                out.push(v * scale);
            }
        }
    }
    out
}

/// The memory orders a caller's array comes in: each a buffer and where `DIMS`' samples lie in it.
struct Stored<T> {
    name: &'static str,
    data: Vec<T>,
    origin: usize,
    strides: [isize; 3],
}

/// `values` (isolab's order) stored x fastest, z fastest (numpy's C order of a `(x, y, z)`
/// array), every other sample of a buffer twice as large, and with x reversed.
fn stored<T: Copy + Default>(values: &[T]) -> Vec<Stored<T>> {
    let [nx, ny, nz] = DIMS;
    let at = |x: usize, y: usize, z: usize| values[x + nx * (y + ny * z)];
    let mut z_fastest = vec![T::default(); values.len()];
    let mut spaced = vec![T::default(); 8 * values.len()];
    let mut reversed = vec![T::default(); values.len()];
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                z_fastest[z + nz * (y + ny * x)] = at(x, y, z);
                spaced[2 * x + 2 * nx * (2 * y + 2 * ny * 2 * z)] = at(x, y, z);
                reversed[(nx - 1 - x) + nx * (y + ny * z)] = at(x, y, z);
            }
        }
    }
    let (nx, ny, nz) = (nx as isize, ny as isize, nz as isize);
    vec![
        Stored { name: "x fastest", data: values.to_vec(), origin: 0, strides: [1, nx, nx * ny] },
        Stored { name: "z fastest", data: z_fastest, origin: 0, strides: [ny * nz, nz, 1] },
        Stored { name: "every other", data: spaced, origin: 0, strides: [2, 4 * nx, 8 * nx * ny] },
        Stored { name: "x reversed", data: reversed, origin: (nx - 1) as usize, strides: [-1, nx, nx * ny] },
    ]
}

/// An extraction's meshes as bits: positions, normals, triangles, tetrahedra and their vertices.
#[derive(PartialEq)]
struct Bits {
    vectors: [Vec<[u32; 3]>; 3],
    triangles: Vec<[u32; 3]>,
    tetrahedra: Vec<[u32; 4]>,
}

fn bits(e: &Extraction) -> Bits {
    let b = |v: &[Vec3]| v.iter().map(|p| p.to_array().map(f32::to_bits)).collect::<Vec<_>>();
    Bits {
        vectors: [b(&e.surface.positions), b(&e.surface.normals), b(&e.volume.positions)],
        triangles: e.surface.triangles.clone(),
        tetrahedra: e.volume.tetrahedra.clone(),
    }
}

/// Every cubic extractor on `T` samples (`values` before conversion), each memory order, plain
/// and negated: the borrowed mesh is the copy's, bit for bit.
fn same_mesh_as_the_copy<T: Sample + Default>(values: &[T], iso: f32) -> usize {
    let grid = Grid { origin: Vec3::new(-0.5, 0.25, 2.0), spacing: 0.125, dims: DIMS };
    let mut meshed = 0;
    for info in extractors::INFOS.iter().filter(|i| i.guarantees.cubic) {
        let e = (info.make)(&Options::new()).unwrap();
        for s in stored(values) {
            let view = GridView::strided(&s.data, DIMS, s.origin, s.strides).unwrap();
            for (negated, view) in [(false, view), (true, view.negated())] {
                let iso = if negated { -iso } else { iso };
                let what =
                    format!("{} on {} {} ({}{})", info.name, T::DTYPE, s.name, if negated { "negated, " } else { "" }, iso);
                let borrowed = Samples::borrowed(grid, view, iso).unwrap();
                let owned = Samples::from_values(Lattice::Cubic(grid), AnyView::from(view).to_vec(), iso).unwrap();
                let (mut a, mut b) = (Extraction::default(), Extraction::default());
                e.extract(&borrowed, &mut a).unwrap_or_else(|err| panic!("{what}: {err}"));
                e.extract(&owned, &mut b).unwrap_or_else(|err| panic!("{what}: {err}"));
                assert!(!b.surface.triangles.is_empty() || !b.volume.tetrahedra.is_empty(), "{what}: nothing meshed");
                assert!(bits(&a) == bits(&b), "{what}: the borrowed mesh differs from the copy's");
                match info.samples {
                    SampleAccess::Borrowed => assert!(!borrowed.was_converted(), "{what}: says borrowed, copied"),
                    SampleAccess::Copies(_) => assert!(borrowed.was_converted(), "{what}: says it copies, did not"),
                }
                meshed += 1;
            }
        }
    }
    meshed
}

#[test]
fn every_extractor_meshes_borrowed_samples_as_their_copy_in_every_type_and_order() {
    let f = field(1.0);
    let cases = [
        same_mesh_as_the_copy(&f.iter().map(|&v| v as f32).collect::<Vec<_>>(), 0.5),
        same_mesh_as_the_copy(&f, 0.5),
        same_mesh_as_the_copy(&f.iter().map(|&v| (v * 255.0) as u8).collect::<Vec<_>>(), 127.5),
        same_mesh_as_the_copy(&f.iter().map(|&v| (v * 255.0 - 128.0) as i8).collect::<Vec<_>>(), -0.5),
        same_mesh_as_the_copy(&f.iter().map(|&v| (v * 4000.0) as u16).collect::<Vec<_>>(), 2000.0),
        same_mesh_as_the_copy(&f.iter().map(|&v| (v * 4000.0 - 2000.0) as i16).collect::<Vec<_>>(), 0.0),
        // Beyond 2^24: the conversion to f32 rounds, the same in both.
        same_mesh_as_the_copy(&f.iter().map(|&v| (v * 4e9) as u32).collect::<Vec<_>>(), 2e9),
        same_mesh_as_the_copy(&f.iter().map(|&v| (v * 4e9 - 2e9) as i32).collect::<Vec<_>>(), 1000.0),
        same_mesh_as_the_copy(&f.iter().map(|&v| v > 0.5).collect::<Vec<_>>(), 0.5),
    ];
    assert!(cases.iter().all(|&n| n >= 8), "{cases:?}");
}

#[test]
fn a_nan_or_infinity_in_borrowed_samples_is_an_error_naming_it_for_every_extractor() {
    let [nx, ny, _] = DIMS;
    let mut values: Vec<f32> = field(1.0).iter().map(|&v| v as f32).collect();
    let (x, y, z) = (7, 3, 5);
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        values[x + nx * (y + ny * z)] = bad;
        let grid = Grid { origin: Vec3::ZERO, spacing: 1.0, dims: DIMS };
        for info in extractors::INFOS.iter().filter(|i| i.guarantees.cubic) {
            let e = (info.make)(&Options::new()).unwrap();
            let samples = Samples::borrowed(grid, GridView::contiguous(&values, DIMS).unwrap(), 0.5).unwrap();
            let err = e.extract(&samples, &mut Extraction::default()).expect_err(info.name);
            match err {
                ExtractError::Samples(SampleError::NonFinite { index, position, .. }) => {
                    assert_eq!(index, x + nx * (y + ny * z), "{}", info.name);
                    assert_eq!(position, [x as f32, y as f32, z as f32], "{}", info.name);
                }
                other => panic!("{}: {other}", info.name),
            }
        }
    }
}

#[test]
fn borrowed_samples_need_a_grid_of_their_view() {
    let values = vec![0u8; 8];
    let view = GridView::contiguous(&values, [2, 2, 2]).unwrap();
    let grid = Grid { origin: Vec3::ZERO, spacing: 1.0, dims: [2, 2, 3] };
    assert!(matches!(Samples::borrowed(grid, view, 0.5), Err(SampleError::ViewMismatch { .. })));
}
