"""isolab.dask on a real distributed.LocalCluster (two worker processes, loopback only): the welded
mesh of blocks against the one-process meshes, zarr and dask inputs, fragments on disk, reruns."""

import os

import numpy as np
import pytest

import isolab

dask = pytest.importorskip("dask")
distributed = pytest.importorskip("distributed")
import isolab.dask as idask  # noqa: E402

CHUNKING = [a["name"] for a in isolab.algorithms() if a["kind"] == "extractor" and a["chunking"] != "unsupported"]


def gyroid(shape, period=9.0):
    i, j, k = np.meshgrid(*(np.arange(n, dtype=np.float64) * (2 * np.pi / period) + 0.3 for n in shape), indexing="ij")
    return (np.sin(i) * np.cos(j) + np.sin(j) * np.cos(k) + np.sin(k) * np.cos(i)).astype(np.float32)


def test_the_cluster_listens_on_loopback_only(client):
    assert len(client.scheduler_info()["workers"]) == 2
    assert client.scheduler.address.startswith("tcp://127.0.0.1:")
    assert all(w.startswith("tcp://127.0.0.1:") for w in client.scheduler_info()["workers"])
    assert client.dashboard_link.startswith("http://127.0.0.1:")


def test_progress_shows_the_blocks(client, capsys):
    vol = gyroid((17, 17, 17))
    with dask.config.set(scheduler="threads"):  # not the module's client, Dask's own threads
        idask.mesh_volume(vol, 0.0, chunk=8, progress=True)  # dask.diagnostics' bar
    assert "Completed" in capsys.readouterr().out
    mesh = idask.mesh_volume(vol, 0.0, chunk=8, client=client, progress=True)  # distributed.progress
    assert len(mesh.faces) == len(isolab.extract(vol, 0.0).faces)


def test_every_chunking_extractor_is_listed():
    assert {"marching-cubes", "surface-nets", "dual-contouring"} <= set(CHUNKING)


@pytest.mark.parametrize("algorithm", CHUNKING)
def test_welded_blocks_equal_the_one_process_chunked_mesh(client, algorithm):
    vol = gyroid((33, 41, 25))  # (24, 40, 32) cells in isolab's x, y, z: blocks of 8 fit
    ours = idask.mesh_volume(vol, 0.0, algorithm, chunk=8, client=client)
    ref = isolab.extract(vol, 0.0, algorithm, chunk=8)
    np.testing.assert_array_equal(ours.vertices, ref.vertices)
    np.testing.assert_array_equal(ours.faces, ref.faces)
    whole = isolab.extract(vol, 0.0, algorithm)
    # The same triangles over the same vertices (a whole-volume extraction may also keep
    # vertices no triangle uses, in cells on the volume's boundary; blocks keep only used ones).
    assert ours.faces.shape == whole.faces.shape
    assert len(np.unique(ours.faces)) == len(ours.vertices) == len(np.unique(whole.faces))
    assert ours.stats["blocks"]["meshed"] + ours.stats["blocks"]["empty"] + ours.stats["blocks"]["full"] == 3 * 5 * 4


def triangle_set(mesh):
    return sorted(tuple(sorted(map(tuple, np.round(mesh.vertices[f], 5)))) for f in mesh.faces)


def test_blocks_that_do_not_divide_the_volume_give_the_whole_volume_marching_cubes(client):
    vol = gyroid((30, 37, 23))
    ours = idask.mesh_volume(vol, 0.0, chunk=8, client=client, spacing=(0.5, 1.0, 2.0))
    whole = isolab.extract(vol, 0.0, spacing=(0.5, 1.0, 2.0))
    assert ours.faces.shape == whole.faces.shape
    np.testing.assert_allclose(np.sort(ours.vertices, axis=0), np.sort(whole.vertices, axis=0), atol=1e-5)
    assert triangle_set(ours) == triangle_set(whole)
    m = ours.metrics()
    assert m["edge_manifold"] and m["vertex_manifold"] and m["oriented"]


@pytest.mark.parametrize("algorithm", ["surface-nets", "dual-contouring"])
def test_uneven_blocks_keep_an_apron_extractors_whole_volume_topology(client, algorithm):
    vol = np.pad(gyroid((28, 35, 21)), 1, constant_values=1.0)  # closed: the surface stays inside
    ours = idask.mesh_volume(vol, 0.0, algorithm, chunk=8, client=client)
    whole = isolab.extract(vol, 0.0, algorithm)
    assert ours.faces.shape == whole.faces.shape and len(ours.vertices) == len(np.unique(whole.faces))
    m, w = ours.metrics(), whole.metrics()
    assert m["closed"] and m["edge_manifold"] and m["vertex_manifold"] and m["genus"] == w["genus"]


def test_zarr_and_dask_arrays_are_read_block_by_block(client, tmp_path):
    zarr = pytest.importorskip("zarr")
    import dask.array as da
    vol = gyroid((33, 25, 41))
    z = zarr.open_array(str(tmp_path / "vol.zarr"), mode="w", shape=vol.shape, chunks=(16, 16, 16), dtype="f4")
    z[:] = vol
    ref = isolab.extract(vol, 0.0, chunk=8)
    from_zarr = idask.mesh_volume(zarr.open_array(str(tmp_path / "vol.zarr"), mode="r"), 0.0, chunk=8, client=client)
    from_dask = idask.mesh_volume(da.from_array(vol, chunks=(10, 10, 10)), 0.0, chunk=8, client=client)
    for mesh in (from_zarr, from_dask):
        np.testing.assert_array_equal(mesh.vertices, ref.vertices)
        np.testing.assert_array_equal(mesh.faces, ref.faces)


def test_without_a_client_dask_threads_mesh_the_same():
    vol = gyroid((17, 25, 33))
    with dask.config.set(scheduler="threads"):  # Dask's threads, not a distributed client
        mesh = idask.mesh_volume(vol, 0.0, chunk=8, threads=2)
    np.testing.assert_array_equal(mesh.faces, isolab.extract(vol, 0.0, chunk=8).faces)


def test_inside_above_and_any_dtype(client):
    vol = (gyroid((25, 17, 33)) * 100 + 100).astype(np.uint8)
    ours = idask.mesh_volume(vol, 100.0, chunk=8, inside="above", client=client)
    ref = isolab.extract(vol, 100.0, inside="above", chunk=8)
    np.testing.assert_array_equal(ours.faces, ref.faces)
    np.testing.assert_array_equal(ours.vertices, ref.vertices)


def test_fragments_on_disk_resume_and_refuse_another_run(client, tmp_path):
    vol = gyroid((33, 33, 33))
    out = tmp_path / "frags"
    first = idask.mesh_volume(vol, 0.0, chunk=8, client=client, out=out)
    names = sorted(p for p in os.listdir(out) if p.startswith("fragment-"))
    assert len(names) == 64 and not any(p.endswith(".tmp") for p in os.listdir(out))
    kept = {n: os.stat(out / n).st_mtime_ns for n in names[2:]}
    for n in names[:2]:
        os.unlink(out / n)
    again = idask.mesh_volume(vol, 0.0, chunk=8, client=client, out=out)
    np.testing.assert_array_equal(again.faces, first.faces)
    np.testing.assert_array_equal(again.vertices, first.vertices)
    assert {n: os.stat(out / n).st_mtime_ns for n in names[2:]} == kept  # not meshed again
    assert all(os.path.exists(out / n) for n in names[:2])
    with pytest.raises(ValueError, match="another run"):
        idask.mesh_volume(vol, 0.5, chunk=8, client=client, out=out)


def test_merge_false_leaves_fragments_a_reader_can_stream(client, tmp_path):
    vol = gyroid((17, 17, 33))
    paths = idask.mesh_volume(vol, 0.0, chunk=8, client=client, out=tmp_path, merge=False)
    assert len(paths) == 2 * 2 * 4 and all(os.path.exists(p) for p in paths)
    fragments = [idask.load_fragment(p) for p in paths]
    meshed = [f for f in fragments if f["state"] == "meshed"]
    assert meshed and all(f["positions"].shape[1] == 3 and len(f["keys"]) == len(f["positions"]) for f in meshed)
    welded = sum(len(f["triangles"]) for f in fragments)
    assert welded == len(isolab.extract(vol, 0.0).faces)


def test_bad_input_raises_value_errors(client):
    with pytest.raises(ValueError, match="3-D"):
        idask.mesh_volume(np.zeros((4, 4)), 0.0)
    with pytest.raises(ValueError, match="cannot mesh in blocks"):
        idask.mesh_volume(gyroid((9, 9, 9)), 0.0, "bcc-sculpt", chunk=4)
    with pytest.raises(ValueError, match="below 2 cells"):
        idask.mesh_volume(gyroid((9, 9, 9)), 0.0, chunk=1)
    with pytest.raises(ValueError, match="unknown algorithm"):
        idask.mesh_volume(gyroid((9, 9, 9)), 0.0, "no-such")
    bad = gyroid((17, 9, 9))
    bad[12, 3, 4] = np.nan
    with pytest.raises(ValueError, match="finite"):
        idask.mesh_volume(bad, 0.0, chunk=8, client=client)
    with pytest.raises(ValueError, match="merge=False"):
        idask.mesh_volume(gyroid((9, 9, 9)), 0.0, merge=False)


def ball_zarr(path, n, dtype="f4"):
    """A zarr volume of n³ samples, a ball's signed distance (written slab by slab)."""
    zarr = pytest.importorskip("zarr")
    z = zarr.open_array(str(path), mode="w", shape=(n, n, n), chunks=(64, 64, 64), dtype=dtype)
    c = (n - 1) / 2
    j, k = np.meshgrid(np.arange(n) - c, np.arange(n) - c, indexing="ij")
    for i0 in range(0, n, 64):
        i = np.arange(i0, min(i0 + 64, n))[:, None, None] - c
        z[i0:i0 + len(i)] = (np.sqrt(i * i + j * j + k * k) - 0.4 * n).astype(dtype)
    return zarr.open_array(str(path), mode="r")


def worker_pids(client):
    return client.run(os.getpid)


def test_a_volume_larger_than_each_workers_memory_limit_meshes_without_a_restart(tmp_path):
    # 512³ float32: 512 MiB on disk uncompressed, against workers allowed 400 MiB each.
    vol = ball_zarr(tmp_path / "ball.zarr", 512)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address="127.0.0.1:0", memory_limit="400MiB", silence_logs=40) as cluster, \
            distributed.Client(cluster, timeout=60) as client:
        before = worker_pids(client)
        mesh = idask.mesh_volume(vol, 0.0, chunk=64, client=client, out=tmp_path / "fragments")
        assert worker_pids(client) == before  # no worker was restarted (for memory or anything else)
    assert vol.nbytes > 400 * 2**20
    m = mesh.metrics()
    assert m["closed"] and m["edge_manifold"] and m["vertex_manifold"] and m["genus"] == 0
    r = np.linalg.norm(mesh.vertices - 255.5, axis=1)
    assert abs(r.mean() - 0.4 * 512) < 0.05 and r.max() - r.min() < 1.0


def test_a_worker_killed_mid_run_leaves_the_output_unchanged(tmp_path):
    import signal
    import threading
    import time
    vol = gyroid((97, 97, 97))
    ref = isolab.extract(vol, 0.0, chunk=8)
    out = tmp_path / "fragments"
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address="127.0.0.1:0", memory_limit="1GiB", silence_logs=50) as cluster, \
            distributed.Client(cluster, timeout=60) as client:
        victim = next(iter(worker_pids(client).values()))
        result = {}
        run = threading.Thread(target=lambda: result.update(mesh=idask.mesh_volume(vol, 0.0, chunk=8, client=client,
                                                                                  out=out)))
        run.start()
        deadline = time.monotonic() + 60
        written = 0
        while time.monotonic() < deadline and written == 0:
            written = len([p for p in os.listdir(out) if p.startswith("fragment-")]) if out.exists() else 0
            time.sleep(0.002)
        os.kill(victim, signal.SIGKILL)
        run.join(120)
        assert not run.is_alive()
        assert victim not in worker_pids(client).values()  # it died; the nanny started another
    assert 0 < written < 12 ** 3  # killed mid-run
    np.testing.assert_array_equal(result["mesh"].vertices, ref.vertices)
    np.testing.assert_array_equal(result["mesh"].faces, ref.faces)


def test_a_baked_world_is_block_files_a_game_streams_and_welds_to_the_sampled_world(client, tmp_path):
    from isolab import _isolab
    cells = (128, 64, 96)
    files = idask.bake_world("terrain", cells, chunk=32, out=tmp_path, client=client)
    assert files and all(f.endswith(".glb") and os.path.exists(f) for f in files)
    per_block = [isolab.load(f) for f in files]
    mesh = idask.bake_world("terrain", cells, chunk=32, out=tmp_path, client=client, merge=True)
    assert sum(len(faces) for _, faces in per_block) == len(mesh.faces)
    # The same world sampled whole and meshed in one process, placed by the same affine.
    world = _isolab.field_block("terrain", list(cells), [0, 0, 0], [c + 1 for c in cells], None)
    (ox, oy, oz), h = world["origin"], world["spacing"]
    affine = [[0, 0, h, ox], [0, h, 0, oy], [h, 0, 0, oz], [0, 0, 0, 1]]
    ref = isolab.extract(world["values"], 0.0, chunk=32, affine=affine)
    np.testing.assert_array_equal(mesh.vertices, ref.vertices)
    np.testing.assert_array_equal(mesh.faces, ref.faces)
    # Block files are in world space: each lies inside its block's box.
    lo = np.min([v.min(axis=0) for v, _ in per_block], axis=0)
    assert np.all(lo >= np.array([ox, oy, oz]) - 1e-6)
    manifest = __import__("json").load(open(tmp_path / "manifest.json"))
    assert len(manifest["done"]) == 4 * 2 * 3 and {d["state"] for d in manifest["done"]} <= {"meshed", "empty", "full"}


def test_bake_world_refuses_unknown_fields_and_formats(tmp_path):
    with pytest.raises(ValueError, match="unknown field"):
        idask.bake_world("no-such-field", (32, 32, 32), out=tmp_path)
    with pytest.raises(ValueError, match="format"):
        idask.bake_world("terrain", (32, 32, 32), out=tmp_path, format="fbx")
