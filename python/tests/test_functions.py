"""isolab.extract on a callable: the field evaluated in batches near its surface only. With a
Lipschitz bound the mesh equals the dense grid's for every extractor that meshes in blocks, and
a numpy grid built on the same samples gives the same mesh; the heuristic's stated blind spot is
real; every wrong answer of a callable is a ValueError naming its batch, and the callable's own
exception comes back unchanged."""

import numpy as np
import pytest

import isolab

BOUNDS = ((-0.5, -0.5, -0.5), (0.5, 0.5, 0.5))
BLOCKS = [a["name"] for a in isolab.algorithms() if a["kind"] == "extractor" and a["chunking"] != "unsupported"]


def sphere(points):
    return np.linalg.norm(points, axis=1) - 0.4


def torus(points):
    q = np.stack([np.hypot(points[:, 0], points[:, 1]) - 0.3, points[:, 2]], axis=1)
    return np.linalg.norm(q, axis=1) - 0.12


@pytest.mark.parametrize("algorithm", BLOCKS)
@pytest.mark.parametrize("fn", [sphere, torus])
def test_certified_pruning_gives_the_dense_mesh(algorithm, fn):
    sparse = isolab.extract(fn, 0.0, algorithm, bounds=BOUNDS, resolution=97, lipschitz=1.0)
    dense = isolab.extract(fn, 0.0, algorithm, bounds=BOUNDS, resolution=97, sparse=False)
    assert len(dense.faces) > 0
    np.testing.assert_array_equal(sparse.vertices, dense.vertices)
    np.testing.assert_array_equal(sparse.faces, dense.faces)
    # Dense: every sample once. Sparse: each grid sample at most once, by the sampling or by the
    # pruning (a refinement centre on the grid is not sampled again); the refinement below the
    # blocks costs at most 8 + 64 evaluations a block.
    assert dense.stats["evaluations"] == dense.stats["dense_points"]
    assert dense.stats["pruning_evaluations"] == 0
    assert dense.stats["refinement_evaluations"] == 0
    sampled = sparse.stats["evaluations"] - sparse.stats["pruning_evaluations"]
    assert sampled <= dense.stats["dense_points"]
    assert sparse.stats["refinement_evaluations"] <= 72 * sparse.stats["blocks"]
    # Blocks a bound rules out are not evaluated; with the wide blocks of a wide apron (surface
    # nets: 24 cells) the sphere at this size leaves none to rule out, and the octree's centres
    # are all the certificate costs.
    pruned = sparse.stats["blocks"] - sparse.stats["sampled_blocks"]
    if algorithm in ("marching-cubes", "marching-tetrahedra", "dual-contouring") or fn is torus:
        assert pruned > 0
    if pruned > 0:
        assert sampled < dense.stats["evaluations"]
    else:
        assert sampled + sparse.stats["pruning_evaluations"] >= dense.stats["evaluations"]
        assert sparse.stats["pruning_evaluations"] - sparse.stats["refinement_evaluations"] < 100


def test_a_numpy_grid_on_the_same_samples_meshed_with_affine_gives_the_same_mesh():
    n = 65
    h = 1.0 / (n - 1)
    x = -0.5 + np.arange(n) * h
    grid = np.stack(np.meshgrid(x, x, x, indexing="ij"), axis=-1).reshape(-1, 3)
    volume = torus(grid).reshape(n, n, n)
    affine = np.diag([h, h, h, 1.0])
    affine[:3, 3] = -0.5
    dense = isolab.extract(volume, 0.0, "marching-cubes", affine=affine)
    sparse = isolab.extract(torus, 0.0, "marching-cubes", bounds=BOUNDS, resolution=n, lipschitz=1.0)
    assert len(dense.faces) == len(sparse.faces) and len(dense.vertices) == len(sparse.vertices)
    key = lambda v: v[np.lexsort(v.T)]
    np.testing.assert_allclose(key(sparse.vertices), key(dense.vertices), atol=1e-6)
    m = sparse.metrics()
    assert m["closed"] and m["genus"] == 1


def test_the_heuristic_misses_a_bubble_inside_a_block_and_the_certificate_does_not():
    def two(points):  # a large sphere and a bubble smaller than a block, between block corners
        bubble = np.linalg.norm(points - np.array([0.3, 0.3, 0.3]), axis=1) - 0.03
        return np.minimum(np.linalg.norm(points + 0.1, axis=1) - 0.25, bubble)

    # h = 1/96: the bubble spans samples 73.9..79.7 on each axis, inside the 8-cell block 72..80.
    args = dict(bounds=BOUNDS, resolution=97, chunk=8)
    dense = isolab.extract(two, 0.0, "marching-cubes", sparse=False, **args)
    certified = isolab.extract(two, 0.0, "marching-cubes", lipschitz=1.0, **args)
    heuristic = isolab.extract(two, 0.0, "marching-cubes", **args)
    near_bubble = lambda mesh: int((np.linalg.norm(mesh.vertices - 0.3, axis=1) < 0.05).sum())
    assert near_bubble(dense) > 0 and near_bubble(certified) == near_bubble(dense)
    assert near_bubble(heuristic) == 0
    assert len(heuristic.faces) < len(dense.faces)


def test_batches_stay_within_the_batch_size_and_stats_count_them():
    sizes = []

    def counted(points):
        sizes.append(len(points))
        assert points.dtype == np.float64 and points.shape[1:] == (3,)
        return sphere(points)

    mesh = isolab.extract(counted, 0.0, "surface-nets", bounds=BOUNDS, resolution=33, lipschitz=1.0, batch=700)
    assert max(sizes) <= 700
    assert mesh.stats["batches"] == len(sizes)
    assert mesh.stats["evaluations"] == sum(sizes)
    assert mesh.stats["function_ms"] >= 0 and mesh.stats["other_ms"] >= 0


class OnlyArray:
    def __init__(self, values):
        self.values = values

    def __array__(self, dtype=None, copy=None):
        return np.asarray(self.values, dtype=dtype)


class OnlyDlpack:
    def __init__(self, values):
        self.values = np.ascontiguousarray(values)

    def __dlpack__(self, **kwargs):
        return self.values.__dlpack__(**kwargs)

    def __dlpack_device__(self):
        return self.values.__dlpack_device__()


@pytest.mark.parametrize(
    "wrap",
    [lambda v: v.astype(np.float32), lambda v: v[:, None], lambda v: list(v), OnlyArray, OnlyDlpack],
    ids=["float32", "column", "list", "__array__", "dlpack"],
)
def test_what_a_callable_may_return(wrap):
    reference = isolab.extract(sphere, 0.0, "marching-cubes", bounds=BOUNDS, resolution=33, lipschitz=1.0)
    mesh = isolab.extract(lambda p: wrap(sphere(p)), 0.0, "marching-cubes", bounds=BOUNDS, resolution=33, lipschitz=1.0)
    assert len(mesh.faces) == len(reference.faces)


def failing_after(n, answer):
    calls = {"n": 0}

    def fn(points):
        calls["n"] += 1
        return answer(points) if calls["n"] > n else sphere(points)

    return fn


class Mine(Exception):
    pass


@pytest.mark.parametrize(
    "answer,message",
    [
        (lambda p: sphere(p)[:-1], "one value per point"),
        (lambda p: np.zeros((len(p), 2)), "one value per point"),
        (lambda p: sphere(p).astype(complex), "real numbers are needed"),
        (lambda p: np.array(["x"] * len(p)), "real numbers are needed"),
        (lambda p: np.where(np.arange(len(p)) == 3, np.nan, sphere(p)), "must be finite"),
        (lambda p: None, "an array of"),
    ],
    ids=["short", "two-columns", "complex", "strings", "nan", "none"],
)
def test_a_wrong_answer_is_a_value_error_naming_the_batch(answer, message):
    with pytest.raises(ValueError, match=message) as raised:
        isolab.extract(failing_after(2, answer), 0.0, "marching-cubes", bounds=BOUNDS, resolution=33, lipschitz=1.0,
                       batch=500)
    assert "batch 2 (points in [" in str(raised.value)


def test_the_callables_own_exception_comes_back_unchanged():
    error = Mine("from inside")

    def fn(points):
        raise error

    with pytest.raises(Mine) as raised:
        isolab.extract(fn, 0.0, "marching-cubes", bounds=BOUNDS, resolution=33, lipschitz=1.0)
    assert raised.value is error


@pytest.mark.parametrize(
    "kwargs,message",
    [
        (dict(resolution=33), "needs bounds"),
        (dict(bounds=BOUNDS), "needs bounds"),
        (dict(bounds=((0, 0), (1, 1)), resolution=33), "bounds must be"),
        (dict(bounds=((0, 0, 0), (1, 0, 1)), resolution=33), "above its lower bound"),
        (dict(bounds=BOUNDS, resolution=1), "at least 2 samples"),
        (dict(bounds=BOUNDS, resolution=33, lipschitz=-1.0), "lipschitz must be"),
        (dict(bounds=BOUNDS, resolution=33, batch=0), "batch must be"),
        (dict(bounds=BOUNDS, resolution=33, chunk=1), "chunk"),
    ],
)
def test_bad_settings_are_value_errors(kwargs, message):
    with pytest.raises(ValueError, match=message):
        isolab.extract(sphere, 0.0, "marching-cubes", **kwargs)


def test_an_extractor_that_cannot_mesh_in_blocks_is_refused_by_name():
    with pytest.raises(ValueError, match="bcc-sculpt"):
        isolab.extract(sphere, 0.0, "bcc-sculpt", bounds=BOUNDS, resolution=17, lipschitz=1.0)


def test_a_named_field_on_a_large_grid_is_sampled_near_its_surface():
    """A built-in field with a Lipschitz bound, on a grid over 512³, is meshed sparsely unasked
    (as on the CLI); a small grid stays dense."""
    mesh = isolab.extract("sphere", 0.0, "marching-cubes", resolution=600)
    sparse = mesh.stats["sparse"]
    assert sparse["evaluations"] * 15 < sparse["dense_points"] == 600**3
    assert sparse["lipschitz"] == 1.0 and sparse["field_bound"] is True
    assert len(mesh.faces) > 1_000_000
    small = isolab.extract("sphere", 0.0, "marching-cubes", resolution=64)
    assert "sparse" not in small.stats
