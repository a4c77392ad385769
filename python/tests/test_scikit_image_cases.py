"""scikit-image's own marching cubes test cases (skimage/measure/tests/test_marching_cubes.py,
0.26) with ``isolab.marching_cubes`` in place of ``skimage.measure.marching_cubes``: the same
inputs, the same assertions (written anew here), and where scikit-image's test compares with
its own output, a comparison with scikit-image's output."""

import numpy as np
import pytest
from skimage import measure
from skimage.draw import ellipsoid, ellipsoid_stats

import isolab

marching_cubes = isolab.marching_cubes


def mesh_area(verts, faces):
    v = verts.astype(np.float64)
    a, b, c = v[faces[:, 0]], v[faces[:, 1]], v[faces[:, 2]]
    return float(0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum())


def same_mesh(v1, f1, v2, f2, tol=1e-10):
    """The same triangles as point triples, in any order and any vertex order."""
    def triangles(v, f):
        t = [tuple(np.concatenate(sorted(v[tri].astype(np.float64).tolist()))) for tri in f]
        return np.array(sorted(t))
    t1, t2 = triangles(v1, f1), triangles(v2, f2)
    return t1.shape == t2.shape and np.allclose(t1, t2, rtol=0, atol=tol)


def double_torus(n=48):
    """Thomas Lewiner's double torus, as scikit-image's test builds it (float32, level 0)."""
    a, b = 2.5 / n, -1.25
    z, y, x = np.ogrid[b:b + n * a:complex(n), b:b + n * a:complex(n), b:b + n * a:complex(n)]
    first = (8 * x) ** 2 + (8 * y - 2) ** 2 + (8 * z) ** 2 + 16 - 1.85 * 1.85
    second = (8 * x) ** 2 + (8 * y + 2) ** 2 + (8 * z) ** 2 + 16 - 1.85 * 1.85
    vol = (first * first - 64 * ((8 * x) ** 2 + (8 * y - 2) ** 2)) * \
          (second * second - 64 * ((8 * y + 2) ** 2 + (8 * z) ** 2)) + 1025
    return vol.astype(np.float32)


@pytest.mark.parametrize("method", ["lorensen", "lewiner"])
def test_isotropic_ellipsoid_area_within_one_percent_below(method):
    vol = ellipsoid(6, 10, 16, levelset=True)
    _, surf = ellipsoid_stats(6, 10, 16)
    verts, faces = marching_cubes(vol, 0.0, method=method)[:2]
    area = mesh_area(verts, faces)
    assert surf > area > surf * 0.99


@pytest.mark.parametrize("method", ["lorensen", "lewiner"])
def test_anisotropic_ellipsoid_area_within_one_and_a_half_percent_below(method):
    spacing = np.array([1.0, 10 / 6.0, 16 / 6.0])  # an array, not a tuple, as theirs
    vol = ellipsoid(6, 10, 16, spacing=spacing, levelset=True)
    _, surf = ellipsoid_stats(6, 10, 16)
    verts, faces = marching_cubes(vol, 0.0, spacing=spacing, method=method)[:2]
    area = mesh_area(verts, faces)
    assert surf > area > surf * 0.985
    # Without degenerate faces, the same bounds.
    verts, faces = marching_cubes(vol, 0.0, spacing=spacing, method=method, allow_degenerate=False)[:2]
    assert surf > mesh_area(verts, faces) > surf * 0.985


@pytest.mark.parametrize("method", ["lorensen", "lewiner"])
def test_invalid_input_is_a_value_error(method):
    for call in [lambda: marching_cubes(np.zeros((2, 2, 1)), 0, method=method),
                 lambda: marching_cubes(np.zeros((2, 2, 1)), 1, method=method),
                 lambda: marching_cubes(np.ones((3, 3, 3)), 1, spacing=(1, 2), method=method),
                 lambda: marching_cubes(np.zeros((20, 20)), 0, method=method),
                 lambda: marching_cubes(ellipsoid(6, 10, 16, levelset=True), 0, mask=np.array([]), method=method)]:
        with pytest.raises(ValueError):
            call()
    with pytest.raises(ValueError, match="method should be either"):
        marching_cubes(np.ones((3, 3, 3)), 0.5, method="abcd")


def test_both_methods_give_the_same_degenerate_free_ellipse():
    small = ellipsoid(1, 1, 1, levelset=True)
    v1, f1 = marching_cubes(small, 0, method="lorensen", allow_degenerate=False)[:2]
    v2, f2 = marching_cubes(small, 0, method="lewiner", allow_degenerate=False)[:2]
    assert same_mesh(v1, f1, v2, f2)
    # And scikit-image's: an octahedron, 8 faces on 6 vertices, every vertex used.
    sv, sf = measure.marching_cubes(small, 0, allow_degenerate=False)[:2]
    assert same_mesh(v1, f1, sv, sf)
    assert (len(v1), len(f1)) == (len(sv), len(sf)) == (6, 8)
    assert len(np.unique(f1)) == len(v1)


def test_the_double_torus_differs_between_the_methods():
    vol = double_torus()
    v1, f1 = marching_cubes(vol, 0, method="lorensen")[:2]
    v2, f2 = marching_cubes(vol, 0)[:2]
    assert not same_mesh(v1, f1, v2, f2)
    # Closed and manifold, both (the torus stays inside the volume).
    for v, f in [(v1, f1), (v2, f2)]:
        m = isolab.metrics(v, f, self_intersections=False)
        assert m["closed"] and m["edge_manifold"] and m["vertex_manifold"], m


def test_masked_area_as_scikit_images():
    vol = ellipsoid(6, 10, 16, levelset=True)
    mask = np.ones_like(vol, dtype=bool)
    mask[:10, :, :] = False
    mask[:, :, 20:] = False
    verts, faces = marching_cubes(vol, 0, mask=mask)[:2]
    sv, sf = measure.marching_cubes(vol, 0, mask=mask)[:2]
    # scikit-image's test: the masked surface's area (its value on their mask rule).
    np.testing.assert_allclose(mesh_area(verts, faces), 299.56878662109375, rtol=0.01)
    np.testing.assert_allclose(mesh_area(verts, faces), mesh_area(sv, sf), rtol=1e-5)
    used = np.zeros(len(verts), bool)
    used[faces.ravel()] = True
    assert used.all(), "no vertex outside the kept triangles"


def test_an_all_true_mask_is_no_mask():
    vol = ellipsoid(6, 10, 16, levelset=True)
    with_mask = marching_cubes(vol, 0, mask=np.ones_like(vol, dtype=bool))
    without = marching_cubes(vol, 0)
    for a, b in zip(with_mask, without):
        np.testing.assert_array_equal(a, b)


def test_an_all_false_mask_finds_no_surface():
    vol = ellipsoid(6, 10, 16, levelset=True)
    with pytest.raises(RuntimeError, match="No surface found"):
        marching_cubes(vol, 0, mask=np.zeros_like(vol, dtype=bool))


@pytest.mark.parametrize("method", ["lorensen", "lewiner"])
@pytest.mark.parametrize("step", [2, 3])
def test_step_sizes_as_scikit_images(method, step):
    vol = ellipsoid(6, 10, 16, levelset=True).astype(np.float32)
    verts, faces = marching_cubes(vol, 0.0, step_size=step, method=method)[:2]
    sv, sf = measure.marching_cubes(vol, 0.0, step_size=step, method=method)[:2]
    assert len(faces) == len(sf)
    np.testing.assert_allclose(mesh_area(verts, faces), mesh_area(sv, sf), rtol=1e-4)


def test_masks_with_step_sizes_as_scikit_images():
    vol = ellipsoid(6, 10, 16, levelset=True).astype(np.float32)
    mask = np.ones_like(vol, dtype=bool)
    mask[:10, :, :] = False
    mask[:, :, 20:] = False
    verts, faces = marching_cubes(vol, 0.0, mask=mask, step_size=2, method="lorensen")[:2]
    sv, sf = measure.marching_cubes(vol, 0.0, mask=mask, step_size=2, method="lorensen")[:2]
    assert len(faces) == len(sf)
    np.testing.assert_allclose(mesh_area(verts, faces), mesh_area(sv, sf), rtol=1e-5)
