//! Marching cubes' unit tests (the corner-pattern, slab and contract tests are in `tests/`).

use super::*;
use crate::fields;

fn sphere_samples(n: usize) -> Samples<'static> {
    let f = fields::builtin("sphere", Default::default()).unwrap();
    Samples::sample_cubic(f.clone(), Grid::covering(&f.domain(), n).unwrap(), 0.0).unwrap()
}

#[test]
fn the_vertex_count_before_the_sweep_is_exact_and_the_estimate_close() {
    for (name, n) in [("sphere", 37), ("gyroid", 41), ("terrain", 33), ("asteroid", 29), ("gyroid", 170), ("sphere", 190)] {
        let f = fields::builtin(name, Default::default()).unwrap();
        let s = Samples::sample_cubic(f.clone(), Grid::covering(&f.domain(), n).unwrap(), 0.0).unwrap();
        let Lattice::Cubic(grid) = *s.lattice() else { unreachable!() };
        let view = GridView::contiguous(s.values(), grid.dims).unwrap();
        let ctx = Ctx::new(view, grid, s.iso(), false, MIN_EDGE_FRACTION, &McOptions::default());
        let mut out = Extraction::default();
        let mc =
            MarchingCubes::new(McOptions { normals: NormalSource::None, parallelism: Parallelism::Serial, ..Default::default() });
        mc.extract(&s, &mut out).unwrap();
        let nz = grid.dims[2];
        let mut signs = LayerSigns::default();
        let count = |signs: &mut LayerSigns, z0, z1, bottom| count_crossing_edges_in(signs, &ctx.values, ctx.iso, z0, z1, bottom);
        let v = out.surface.positions.len();
        assert_eq!(count(&mut signs, 0, nz - 1, true), v, "{name}");
        // Slabs: the bottom layer of a slab above the first is counted by the slab below.
        let mid = nz / 2;
        let split = count(&mut signs, 0, mid, true) + count(&mut signs, mid, nz - 1, false);
        assert_eq!(split, v, "{name}, two slabs");
        // The fresh output's reservation: from every layer's count on small grids, else from a
        // sample of the layers, within 10% on these smooth fields.
        let estimate = estimate_crossing_edges(&mut signs, &ctx.values, ctx.iso);
        if grid.len() <= COUNT_ALL_SAMPLES || nz - 1 <= 2 * ESTIMATE_LAYERS {
            assert_eq!(estimate, v, "{name} {n}");
        } else {
            assert!(estimate.abs_diff(v) * 10 <= v, "{name} {n}: estimated {estimate} of {v}");
        }
        let reserved = estimate + estimate / 8;
        assert_eq!(out.surface.positions.capacity(), (reserved + reserved / 64 + 16).max(v), "{name} {n}");
        assert!(out.surface.triangles.len() <= out.surface.triangles.capacity());
    }
}

#[test]
fn serial_and_parallel_give_the_same_mesh() {
    let s = sphere_samples(90);
    let mut a = Extraction::default();
    let mut b = Extraction::default();
    MarchingCubes::new(McOptions { parallelism: Parallelism::Serial, ..Default::default() }).extract(&s, &mut a).unwrap();
    let par = MarchingCubes::default();
    par.extract(&s, &mut b).unwrap();
    assert_eq!(a.surface.positions.len(), b.surface.positions.len());
    assert_eq!(a.surface.triangles.len(), b.surface.triangles.len());
    // Same triangles as position triples (vertex order differs between runs).
    let key = |m: &TriMesh| {
        let mut v: Vec<[[u32; 3]; 3]> =
            m.triangles.iter().map(|t| t.map(|i| m.positions[i as usize].to_array().map(f32::to_bits))).collect();
        v.sort_unstable();
        v
    };
    assert_eq!(key(&a.surface), key(&b.surface));
}

#[test]
fn bcc_samples_are_refused() {
    let f = fields::builtin("sphere", Default::default()).unwrap();
    let s = Samples::sample(f.clone(), Lattice::Bcc(Grid::covering(&f.domain(), 8).unwrap()), 0.0).unwrap();
    let err = MarchingCubes::default().extract(&s, &mut Extraction::default()).unwrap_err();
    assert!(err.to_string().contains("cubic"), "{err}");
}

#[test]
fn reuse_keeps_buffers() {
    let s = sphere_samples(40);
    let mc = MarchingCubes::default();
    let mut out = Extraction::default();
    mc.extract(&s, &mut out).unwrap();
    let cap = out.surface.positions.capacity();
    let first = out.clone();
    mc.extract(&s, &mut out).unwrap();
    assert_eq!(out.surface, first.surface);
    assert_eq!(out.surface.positions.capacity(), cap);
}
