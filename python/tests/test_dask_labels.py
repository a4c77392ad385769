"""isolab.dask.mesh_labels on a real distributed.LocalCluster (two worker processes, loopback
only): each label's mesh welded from blocks against isolab.mesh_labels of the whole map, zarr
and dask inputs, fragments on disk, reruns, bad input."""

import os
import warnings

import numpy as np
import pytest

import isolab

dask = pytest.importorskip("dask")
distributed = pytest.importorskip("distributed")
import isolab.dask as idask  # noqa: E402

# Every label extractor, and surface nets with and without its smoothing (None: no such option).
CASES = [(a["name"], s) for a in isolab.algorithms() if a["kind"] == "labels"
         for s in ((True, False) if "smoothing" in a["options"] else (None,))]


def voronoi(shape, cells, seed=7, dtype=np.uint16):
    """Labels 1..cells of the nearest of `cells` random seeds, background 0 outside a ball."""
    rng = np.random.default_rng(seed)
    seeds = rng.uniform(0, 1, (cells, 3)) * np.asarray(shape)
    idx = np.stack(np.meshgrid(*(np.arange(n) for n in shape), indexing="ij"), -1).reshape(-1, 1, 3)
    nearest = np.argmin(((idx - seeds[None]) ** 2).sum(-1), axis=1).reshape(shape) + 1
    centre = (np.asarray(shape) - 1) / 2
    inside = (((np.stack(np.meshgrid(*(np.arange(n) for n in shape), indexing="ij"), -1) - centre) /
               (np.asarray(shape) / 2.2)) ** 2).sum(-1) < 1
    return np.where(inside, nearest, 0).astype(dtype)


def triangles_as_points(mesh):
    """A mesh's triangles as rows of their corners' coordinates, each rotated to start at its
    smallest corner (winding kept), sorted: equal for equal meshes whatever their vertex order."""
    t = mesh.vertices[mesh.faces]  # (M, 3, 3)
    keys = [tuple(map(tuple, tri)) for tri in t]
    rotated = [min((k[i], k[(i + 1) % 3], k[(i + 2) % 3]) for i in range(3)) for k in keys]
    return sorted(rotated)


def assert_same_label_meshes(blocks, whole, what):
    assert sorted(blocks) == sorted(whole), what
    for label in whole:
        assert triangles_as_points(blocks[label]) == triangles_as_points(whole[label]), f"{what}: label {label}"
        assert blocks[label].stats["neighbours"] == whole[label].stats["neighbours"], f"{what}: label {label}"
        assert blocks[label].stats["samples"] == whole[label].stats["samples"], f"{what}: label {label}"
    assert len(blocks.faces) == len(whole.faces), what
    np.testing.assert_array_equal(np.unique(blocks.pairs, axis=0), np.unique(whole.pairs, axis=0))
    # Tetrahedra (lattice cleaving's): the same, as labelled rows of corner coordinates.
    def tets(m):
        corners = np.sort(m.vertices[m.tetrahedra].reshape(len(m.tetrahedra), 12).view("f4,f4,f4"), axis=1)
        return sorted(zip(map(bytes, corners), m.tetrahedron_labels.tolist()))
    assert len(blocks.tetrahedra) == len(whole.tetrahedra), what
    assert tets(blocks) == tets(whole), what


@pytest.mark.parametrize("algorithm, smoothing", CASES)
def test_welded_blocks_equal_the_whole_maps_label_meshes(client, algorithm, smoothing):
    seg = voronoi((41, 30, 37), 9)
    kwargs = {} if smoothing is None else {"smoothing": smoothing}
    whole = isolab.mesh_labels(seg, algorithm=algorithm, spacing=(0.5, 1.0, 2.0), **kwargs)
    for chunk in (8, 13):
        blocks = idask.mesh_labels(seg, chunk=chunk, algorithm=algorithm, spacing=(0.5, 1.0, 2.0), client=client,
                                   **kwargs)
        assert_same_label_meshes(blocks, whole, f"{algorithm} smoothing={smoothing} chunk={chunk}")
        if algorithm == "surface-nets":
            # The weld orders vertices by key, which is the whole map's sweep order.
            np.testing.assert_array_equal(blocks.vertices, whole.vertices)
    for label, mesh in blocks.items():
        m = mesh.metrics()
        assert m["closed"], (algorithm, label)


def test_zarr_and_dask_label_maps_are_read_block_by_block_with_a_selection(client, tmp_path):
    zarr = pytest.importorskip("zarr")
    import dask.array as da
    seg = voronoi((33, 29, 31), 7, seed=3, dtype=np.uint32)
    z = zarr.open_array(str(tmp_path / "seg.zarr"), mode="w", shape=seg.shape, chunks=(16, 16, 16), dtype="u4")
    z[:] = seg
    z = zarr.open_array(str(tmp_path / "seg.zarr"), mode="r")
    with pytest.warns(UserWarning, match=r"\[99\]"):
        whole = isolab.mesh_labels(seg, labels=[2, 5, 99], algorithm="marching-tetrahedra")
    for source in (z, da.from_array(seg, chunks=(11, 11, 11))):
        with pytest.warns(UserWarning, match=r"\[99\]"):
            blocks = idask.mesh_labels(source, chunk=10, labels=[2, 5, 99], algorithm="marching-tetrahedra",
                                       client=client)
        assert blocks.missing == [99]
        assert sorted(blocks) == [2, 5]
        assert_same_label_meshes(blocks, whole, type(source).__name__)


def test_without_a_client_dask_threads_mesh_the_same():
    seg = voronoi((20, 21, 22), 5, seed=1, dtype=np.uint8)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        blocks = idask.mesh_labels(seg, chunk=7, smoothing=False)
    assert_same_label_meshes(blocks, isolab.mesh_labels(seg, smoothing=False), "threads")


def test_label_fragments_on_disk_resume_stream_and_refuse_another_run(client, tmp_path):
    seg = voronoi((25, 25, 25), 6, seed=5, dtype=np.uint8)
    out = tmp_path / "frags"
    first = idask.mesh_labels(seg, chunk=8, client=client, out=out)
    names = sorted(p for p in os.listdir(out) if p.startswith("fragment-"))
    assert len(names) == 4 ** 3 and not any(p.endswith(".tmp") for p in os.listdir(out))
    kept = {n: os.stat(out / n).st_mtime_ns for n in names[2:]}
    for n in names[:2]:
        os.unlink(out / n)
    again = idask.mesh_labels(seg, chunk=8, client=client, out=out)
    assert {n: os.stat(out / n).st_mtime_ns for n in names[2:]} == kept  # not meshed again
    assert_same_label_meshes(again, first, "rerun")
    paths = idask.mesh_labels(seg, chunk=8, client=client, out=out, merge=False)
    fragments = [idask.load_label_fragment(p) for p in paths]
    assert sum(len(f["triangles"]) for f in fragments) == len(first.faces)
    assert sum(sum(f["counts"].values()) for f in fragments) == seg.size
    assert all(len(f["keys"]) == len(f["positions"]) and len(f["pairs"]) == len(f["triangles"]) for f in fragments)
    with pytest.raises(ValueError, match="another run"):
        idask.mesh_labels(seg, chunk=8, client=client, out=out, smoothing=False)
    with pytest.raises(ValueError, match="another run"):
        idask.mesh_volume(seg.astype(np.float32), 0.5, chunk=8, client=client, out=out)


def test_bad_label_maps_raise_clear_errors():
    with pytest.raises(TypeError, match="integer labels.*float32"):
        idask.mesh_labels(np.zeros((8, 8, 8), np.float32))
    with pytest.raises(ValueError, match="3-D"):
        idask.mesh_labels(np.zeros((8, 8), np.uint8))
    with pytest.raises(ValueError, match="too small"):
        idask.mesh_labels(np.zeros((8, 8, 8), np.uint8), chunk=1)
    with pytest.raises(ValueError, match="marching-cubes"):
        idask.mesh_labels(np.zeros((8, 8, 8), np.uint8), algorithm="marching-cubes")
    with pytest.raises(ValueError, match="merge=False"):
        idask.mesh_labels(np.zeros((8, 8, 8), np.uint8), merge=False)
    negative = np.zeros((9, 9, 9), np.int16)
    negative[4, 4, 4] = -3
    with pytest.raises(ValueError, match="-3"):
        idask.mesh_labels(negative, chunk=4)
