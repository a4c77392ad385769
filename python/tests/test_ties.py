"""scikit-image's own marching cubes defects, ruled out: duplicate faces where corners tie at the
level (its issue #8109), holes where the level equals a sample (#8116), and the mask read at one
corner, so the first plane of cells cannot be masked (#8202)."""

import itertools

import numpy as np
import pytest

import isolab


def tie_volume(pattern, tie_value=0.5, inside=1.0):
    """A 4 x 4 x 4 volume, 0 on its border; its middle cell's eight corners are the level (0.5)
    where `pattern`'s bit is set, above it (inside) where not."""
    vol = np.zeros((4, 4, 4), dtype=np.float32)
    for bit, (i, j, k) in enumerate(itertools.product((1, 2), repeat=3)):
        vol[i, j, k] = tie_value if pattern >> bit & 1 else inside
    return vol


def edges_of(faces):
    e = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    _, counts = np.unique(e, axis=0, return_counts=True)
    return counts


def positions_closed(verts, faces):
    """Every edge in exactly two triangles once vertices at one position are one vertex."""
    _, weld = np.unique(verts, axis=0, return_inverse=True)
    welded = weld.ravel()[faces]
    keep = (welded[:, 0] != welded[:, 1]) & (welded[:, 1] != welded[:, 2]) & (welded[:, 0] != welded[:, 2])
    if not keep.any():
        return True
    return bool(np.all(edges_of(welded[keep]) % 2 == 0))


@pytest.mark.parametrize("method", ["lorensen", "lewiner"])
@pytest.mark.parametrize("allow_degenerate", [True, False])
def test_every_pattern_of_corners_at_the_level_is_closed_with_no_duplicate_face(method, allow_degenerate):
    meshed = 0
    for pattern in range(255):  # 255: every corner at the level, nothing above it: no surface
        vol = tie_volume(pattern)
        verts, faces, normals, values = isolab.marching_cubes(vol, 0.5, method=method,
                                                              allow_degenerate=allow_degenerate)
        meshed += 1
        what = f"{method}, pattern {pattern:08b}, allow_degenerate={allow_degenerate}"
        assert faces.min() >= 0 and faces.max() < len(verts), what
        assert len(normals) == len(values) == len(verts), what
        # No face twice: by its vertices, nor by its corner positions (a degenerate duplicate).
        by_index = np.sort(faces, axis=1)
        assert len(np.unique(by_index, axis=0)) == len(faces), f"{what}: a face twice"
        area = np.linalg.norm(np.cross(verts[faces[:, 1]] - verts[faces[:, 0]],
                                       verts[faces[:, 2]] - verts[faces[:, 0]]), axis=1)
        by_position = [tuple(sorted(map(tuple, verts[t].tolist()))) for t in faces[area > 0]]
        assert len(set(by_position)) == len(by_position), f"{what}: a face twice by position"
        # Closed: every edge in two triangles, by index and once coincident vertices are welded.
        if allow_degenerate:
            assert np.all(edges_of(faces) == 2), f"{what}: open or non-manifold"
        assert positions_closed(verts, faces), f"{what}: a hole"
        if not allow_degenerate:
            assert np.all(area > 0), f"{what}: a zero-area face kept"
            used = np.zeros(len(verts), bool)
            used[faces.ravel()] = True
            assert used.all(), f"{what}: an unused vertex"
    assert meshed == 255


def test_a_level_equal_to_samples_leaves_no_hole_in_scikit_images_example():
    # Two cubes side by side, the sample between them at the level (scikit-image #8116's shape):
    # every pattern of the shared face at the level, closed by position.
    for pattern in range(16):
        vol = np.zeros((4, 5, 4), dtype=np.float32)
        vol[1:3, 1:4, 1:3] = 1.0
        for bit, (i, k) in enumerate(itertools.product((1, 2), repeat=2)):
            if pattern >> bit & 1:
                vol[i, 2, k] = 0.0  # the level
        for method in ("lorensen", "lewiner"):
            verts, faces = isolab.marching_cubes(vol, 0.0, method=method)[:2]
            assert positions_closed(verts, faces), (pattern, method)


def test_the_mask_at_the_volumes_edges():
    rng = np.random.default_rng(3)
    vol = rng.random((6, 7, 8)).astype(np.float32)
    full = isolab.marching_cubes(vol, 0.5, method="lorensen")
    # scikit-image's rule: a cell is meshed when its far corner is True, so a False first plane
    # changes nothing and a False last plane removes the last layer of cells.
    for axis in range(3):
        first = np.ones_like(vol, dtype=bool)
        first[(slice(None),) * axis + (0,)] = False
        v, f = isolab.marching_cubes(vol, 0.5, method="lorensen", mask=first)[:2]
        assert len(f) == len(full[1]), axis
        last = np.ones_like(vol, dtype=bool)
        last[(slice(None),) * axis + (-1,)] = False
        v, f = isolab.marching_cubes(vol, 0.5, method="lorensen", mask=last)[:2]
        cut = vol.take(range(vol.shape[axis] - 1), axis=axis)
        assert len(f) == len(isolab.marching_cubes(cut, 0.5, method="lorensen")[1]), axis
