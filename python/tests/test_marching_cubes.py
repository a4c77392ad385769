"""isolab.marching_cubes against scikit-image's, on the same arrays."""

import numpy as np
import pytest
from scipy.spatial import cKDTree
from skimage import draw, measure

import isolab


def signed_volume(verts, faces):
    v = verts.astype(np.float64)
    a, b, c = v[faces[:, 0]], v[faces[:, 1]], v[faces[:, 2]]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def area(verts, faces):
    v = verts.astype(np.float64)
    a, b, c = v[faces[:, 0]], v[faces[:, 1]], v[faces[:, 2]]
    return float(0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum())


def assert_same_vertex_set(ours, theirs, tol=1e-5):
    assert len(ours) == len(theirs)
    d_ot, _ = cKDTree(theirs).query(ours)
    d_to, _ = cKDTree(ours).query(theirs)
    assert d_ot.max() <= tol and d_to.max() <= tol, (d_ot.max(), d_to.max())


ELLIPSOIDS = [(6, 10, 16, False), (6, 10, 16, True), (9, 9, 9, True), (4.5, 12, 7.25, False)]


@pytest.mark.parametrize("a,b,c,levelset", ELLIPSOIDS)
@pytest.mark.parametrize("spacing", [(1.0, 1.0, 1.0), (0.5, 2.0, 1.25)])
def test_lorensen_gives_scikit_images_vertices_and_triangle_count(a, b, c, levelset, spacing):
    vol = draw.ellipsoid(a, b, c, levelset=levelset).astype(np.float32)
    level = 0.0 if levelset else 0.5
    sv, sf, sn, sval = measure.marching_cubes(vol, level, spacing=spacing, method="lorensen")
    ov, of, on, oval = isolab.marching_cubes(vol, level, spacing=spacing, method="lorensen")
    assert (ov.dtype, of.dtype, on.dtype, oval.dtype) == (np.float32, np.int32, np.float32, np.float32)
    assert len(of) == len(sf)
    assert_same_vertex_set(ov, sv.astype(np.float32), tol=1e-4 * max(spacing))
    # The same winding (scikit-image's descent), and normals toward decreasing values, as theirs.
    assert np.sign(signed_volume(ov, of)) == np.sign(signed_volume(sv, sf))
    _, match = cKDTree(sv).query(ov)
    assert np.mean(np.einsum("ij,ij->i", on, sn[match])) > 0.9
    # scikit-image's values: coincident vertices (at a sample, on a level set) share theirs.
    np.testing.assert_allclose(oval, sval[match], atol=1e-6)


def test_every_corner_pattern_makes_as_many_triangles_as_scikit_images_table():
    for case in range(1, 255):
        vol = np.array([(case >> b) & 1 for b in range(8)], dtype=np.float32).reshape(2, 2, 2)
        sv, sf, _, _ = measure.marching_cubes(vol, 0.5, method="lorensen")
        ov, of, _, _ = isolab.marching_cubes(vol, 0.5, method="lorensen")
        assert (len(ov), len(of)) == (len(sv), len(sf)), case


def test_area_is_the_analytic_ellipsoids():
    a, b, c = 12.0, 18.0, 24.0
    spacing = (0.5, 0.75, 1.0)
    vol = draw.ellipsoid(a, b, c, spacing=spacing, levelset=True).astype(np.float32)
    _, analytic_area = draw.ellipsoid_stats(a, b, c)
    for method in ("lorensen", "lewiner"):
        verts, faces, _, _ = isolab.marching_cubes(vol, 0.0, spacing=spacing, method=method)
        assert abs(area(verts, faces) - analytic_area) < 0.01 * analytic_area, method


def test_lewiner_is_closed_manifold_and_as_scikit_image_winds():
    rng = np.random.default_rng(7)
    vol = rng.random((14, 15, 16)).astype(np.float32)
    vol = np.pad(vol, 1, constant_values=0.0)  # every surface inside the volume: closed
    verts, faces, _, _ = isolab.marching_cubes(vol, 0.5)
    m = isolab.metrics(verts, faces, self_intersections=False)
    assert m["closed"] and m["edge_manifold"] and m["vertex_manifold"] and m["oriented"], m
    sv, sf, _, _ = measure.marching_cubes(vol, 0.5)
    assert np.sign(signed_volume(verts, faces)) == np.sign(signed_volume(sv, sf)) != 0


@pytest.mark.parametrize("step", [2, 3])
def test_step_size_as_scikit_image(step):
    vol = draw.ellipsoid(7, 11, 9, levelset=True).astype(np.float32)
    sv, sf, _, _ = measure.marching_cubes(vol, 0.0, step_size=step, method="lorensen")
    ov, of, _, _ = isolab.marching_cubes(vol, 0.0, step_size=step, method="lorensen")
    assert len(of) == len(sf)
    assert_same_vertex_set(ov, sv.astype(np.float32), tol=1e-4)


def test_mask_as_scikit_image():
    rng = np.random.default_rng(1)
    vol = rng.random((12, 13, 14)).astype(np.float32)
    mask = rng.random(vol.shape) > 0.3
    sv, sf, _, sval = measure.marching_cubes(vol, 0.5, method="lorensen", mask=mask)
    ov, of, _, oval = isolab.marching_cubes(vol, 0.5, method="lorensen", mask=mask)
    assert len(of) == len(sf)
    assert_same_vertex_set(ov, sv, tol=1e-5)
    _, match = cKDTree(sv).query(ov)
    np.testing.assert_allclose(oval, sval[match], atol=1e-6)


DTYPES = [np.bool_, np.uint8, np.int8, np.uint16, np.int16, np.uint32, np.int32, np.uint64, np.int64, np.float32,
          np.float64, np.float16]


@pytest.mark.parametrize("dtype", DTYPES)
def test_every_dtype_and_memory_order_gives_the_same_mesh(dtype):
    ball = draw.ellipsoid(5, 7, 6).astype(dtype)  # 0/1 in every dtype
    ref_v, ref_f, _, _ = isolab.marching_cubes(ball.astype(np.float32), 0.5, method="lorensen")
    padded = np.zeros(tuple(2 * n for n in ball.shape), dtype=dtype)
    padded[::2, ::2, ::2] = ball
    for name, arr in [("C", ball), ("F", np.asfortranarray(ball)), ("strided", padded[::2, ::2, ::2]),
                      ("transposed view", np.transpose(np.transpose(ball, (2, 1, 0)).copy(), (2, 1, 0)))]:
        v, f, _, _ = isolab.marching_cubes(arr, 0.5, method="lorensen")
        assert len(f) == len(ref_f), name
        assert_same_vertex_set(v, ref_v, tol=1e-6)
        assert np.sign(signed_volume(v, f)) == np.sign(signed_volume(ref_v, ref_f)), name


def test_default_level_is_the_middle_of_the_range_as_scikit_images():
    vol = draw.ellipsoid(6, 8, 5, levelset=True).astype(np.float32)
    sv, sf, _, _ = measure.marching_cubes(vol, method="lorensen")
    ov, of, _, _ = isolab.marching_cubes(vol, method="lorensen")
    assert len(of) == len(sf)
    assert_same_vertex_set(ov, sv, tol=1e-4)


def test_allow_degenerate_false_leaves_no_zero_area_triangle():
    vol = np.zeros((6, 6, 6), dtype=np.float32)
    vol[2:4, 2:4, 2:4] = 1.0
    vol[1, 2, 2] = 0.5  # a sample exactly at the level: coincident vertices
    v, f, _, _ = isolab.marching_cubes(vol, 0.5, method="lorensen", allow_degenerate=False)
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    assert len(f) and np.all(np.linalg.norm(np.cross(b - a, c - a), axis=1) > 0)
    assert f.max() < len(v)


@pytest.mark.parametrize("call,message", [
    (lambda: isolab.marching_cubes(np.zeros((4, 4))), "3D numpy array"),
    (lambda: isolab.marching_cubes(np.zeros((4, 1, 4))), "at least 2x2x2"),
    (lambda: isolab.marching_cubes(np.random.rand(4, 4, 4), spacing=(1, 1)), "three floats"),
    (lambda: isolab.marching_cubes(np.random.rand(4, 4, 4), level=3.0), "within volume data range"),
    (lambda: isolab.marching_cubes(np.random.rand(4, 4, 4), mask=np.ones((4, 4, 3), bool)), "same shape"),
    (lambda: isolab.marching_cubes(np.random.rand(4, 4, 4), step_size=0), "at least one"),
    (lambda: isolab.marching_cubes(np.random.rand(4, 4, 4), method="mc33"), "lewiner"),
    (lambda: isolab.marching_cubes(np.random.rand(4, 4, 4), gradient_direction="up"), "gradient_direction"),
    (lambda: isolab.marching_cubes(np.where(np.arange(64).reshape(4, 4, 4) == 37, np.nan, 1.0), level=0.5),
     r"volume\[2, 1, 1\] is NaN"),
])
def test_bad_input_raises_value_error_as_scikit_image(call, message):
    with pytest.raises(ValueError, match=message):
        call()


def test_no_surface_raises_runtime_error_as_scikit_image():
    vol = np.zeros((4, 4, 4), dtype=np.float32)
    vol[0, 0, 0] = 1.0
    with pytest.raises(RuntimeError, match="No surface"):
        isolab.marching_cubes(vol, 1.0)


def test_an_output_over_the_memory_limit_is_a_memory_error_before_it_is_made(monkeypatch):
    i, j, k = np.mgrid[-1:1:48j, -1:1:48j, -1:1:48j]
    vol = (np.sin(6 * i) * np.cos(6 * j) + np.sin(6 * j) * np.cos(6 * k) + np.sin(6 * k) * np.cos(6 * i)).astype(np.float32)
    verts, faces, normals, values = isolab.marching_cubes(vol, 0.0)
    made = verts.nbytes + faces.nbytes + normals.nbytes + values.nbytes
    for threads in (1, 2):
        with pytest.raises(MemoryError, match="MiB allowed"):
            isolab.marching_cubes(vol, 0.0, threads=threads, memory_limit=made // 2)
        # Twice the output is enough (the estimate and the scratch fit).
        v, f = isolab.marching_cubes(vol, 0.0, threads=threads, memory_limit=2 * made)[:2]
        assert len(f) == len(faces)
    # By default, the memory available: ISOLAB_MEMORY_MIB plays a smaller machine.
    monkeypatch.setenv("ISOLAB_MEMORY_MIB", "0")
    with pytest.raises(MemoryError):
        isolab.marching_cubes(vol, 0.0)
