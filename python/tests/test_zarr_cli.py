"""`isolab extract -f store.zarr`: zarr stores written by zarr-python (v2 and v3, its default
codecs and others, sharding, OME-Zarr 0.4 and 0.5) meshed by the CLI, in memory and streamed,
against isolab.extract on the same numpy array."""

import os
import subprocess

import numpy as np
import pytest
import zarr

import isolab

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
CLI = os.environ.get("ISOLAB_CLI", os.path.join(ROOT, "target", "release", "isolab"))
needs_cli = pytest.mark.skipif(not os.path.exists(CLI), reason=f"no CLI at {CLI} (tests/all.sh builds it)")

LEVEL = 100.5  # between the integer samples: no vertex on a sample, no degenerate triangle


def volume():
    """A uint16 ellipsoid of shape (z, y, x) = (25, 17, 33): cells a multiple of 8 (for the
    in-memory --chunk 8 it is compared with), samples a multiple of no storage chunk."""
    z, y, x = np.mgrid[-1:1:25j, -1:1:17j, -1:1:33j]
    r = np.sqrt(x**2 / 0.8 + y**2 + z**2 / 1.3)
    return ((0.8 - r) * 400 + LEVEL).clip(0, 60000).astype(np.uint16)


def run(*args, ok=True):
    out = subprocess.run([CLI, *args], capture_output=True, text=True)
    assert (out.returncode == 0) == ok, out.stderr
    return out


def same_mesh(got, want, tol=1e-4):
    """Whether two meshes (vertices, faces) are the same triangles, winding kept: every vertex of
    `got` is matched to the nearest of `want` (within `tol`, for float rounding in two
    pipelines), and the triangles, each started at its smallest index, compared as sets."""
    (gv, gf), (wv, wf) = [(np.asarray(v, dtype=np.float64), np.asarray(f)) for v, f in (got, want)]
    if len(gv) != len(wv) or len(gf) != len(wf):
        return False
    d = np.linalg.norm(gv[:, None, :] - wv[None, :, :], axis=2)
    nearest = d.argmin(axis=1)
    if d[np.arange(len(gv)), nearest].max() > tol or len(set(nearest)) != len(wv):
        return False

    def tris(faces):
        return {tuple(np.roll(t, -int(np.argmin(t)))) for t in faces}
    return tris(nearest[gf]) == tris(wf)


def expected(vol, scale=(1.0, 1.0, 1.0), shift=(0.0, 0.0, 0.0), chunk=None):
    """isolab.extract on the array, its vertices turned from numpy's (i, j, k) = (z, y, x) to
    the store's world (x, y, z); swapping two axes mirrors, so the winding is reversed back."""
    affine = np.diag([*scale, 1.0])
    affine[:3, 3] = shift
    mesh = isolab.extract(vol, LEVEL, "marching-cubes", affine=affine, inside="above", chunk=chunk)
    return mesh.vertices[:, ::-1], mesh.faces[:, ::-1]


def stores(tmp_path, vol):
    """zarr-python's stores of `vol`: name -> (path, OME scale (z, y, x), OME translation)."""
    import numcodecs
    out = {}
    p = str(tmp_path / "v3-default.zarr")
    zarr.create_array(p, shape=vol.shape, chunks=(8, 8, 8), dtype=vol.dtype)[:] = vol
    out["v3 zstd (default)"] = (p, None, None)
    p = str(tmp_path / "v3-sharded.zarr")
    zarr.create_array(p, shape=vol.shape, shards=(16, 16, 16), chunks=(8, 4, 8), dtype=vol.dtype,
                      compressors=zarr.codecs.BloscCodec(cname="lz4", shuffle="bitshuffle"))[:] = vol
    out["v3 sharded, blosc"] = (p, None, None)
    p = str(tmp_path / "v3-gzip-be.zarr")
    zarr.create_array(p, shape=vol.shape, chunks=(5, 19, 29), dtype=vol.dtype, compressors=zarr.codecs.GzipCodec(),
                      serializer=zarr.codecs.BytesCodec(endian="big"))[:] = vol
    out["v3 gzip, big-endian"] = (p, None, None)
    p = str(tmp_path / "v2-blosc.zarr")
    zarr.create_array(p, shape=vol.shape, chunks=(10, 7, 9), dtype=vol.dtype, zarr_format=2,
                      compressors=numcodecs.Blosc(cname="lz4", clevel=5, shuffle=numcodecs.Blosc.SHUFFLE))[:] = vol
    out["v2 blosc"] = (p, None, None)
    p = str(tmp_path / "v2-zlib-f4.zarr")
    zarr.create_array(p, shape=vol.shape, chunks=(6, 6, 6), dtype="f4", zarr_format=2,
                      compressors=numcodecs.Zlib(level=3))[:] = vol.astype("f4")
    out["v2 zlib float32"] = (p, None, None)

    # OME-Zarr 0.4 (zarr v2) with a channel axis of one, and 0.5 (zarr v3).
    scale, shift = (2.0, 0.5, 0.25), (10.0, -20.0, 30.0)
    for version, fmt in (("0.4", 2), ("0.5", 3)):
        p = str(tmp_path / f"ome-{version}.zarr")
        g = zarr.open_group(p, mode="w", zarr_format=fmt)
        axes = [{"name": "c", "type": "channel"}] + [{"name": n, "type": "space", "unit": "micrometer"} for n in "zyx"]
        ms = [{"version": version, "axes": axes, "datasets": [{"path": "0", "coordinateTransformations": [
            {"type": "scale", "scale": [1.0, *scale]}, {"type": "translation", "translation": [0.0, *shift]}]}]}]
        if version == "0.4":
            g.attrs["multiscales"] = ms
        else:
            g.attrs["ome"] = {"version": version, "multiscales": ms}
        g.create_array("0", shape=(1,) + vol.shape, chunks=(1, 8, 8, 8), dtype=vol.dtype)[:] = vol[None]
        out[f"OME-Zarr {version}"] = (p, scale, shift)
    return out


@needs_cli
def test_zarr_stores_mesh_as_the_array_does_in_memory_and_streamed(tmp_path):
    vol = volume()
    whole = expected(vol)
    assert len(whole[1]) > 1000 and same_mesh(expected(vol, chunk=8), whole)  # marching cubes: chunks weld whole
    for name, (path, scale, shift) in stores(tmp_path, vol).items():
        want = whole if scale is None else expected(vol, scale, shift)
        for stream in (False, True):
            out = tmp_path / f"out-{len(os.listdir(tmp_path))}.ply"
            args = ["extract", "-a", "marching-cubes", "-f", path, "--iso", str(LEVEL), "-o", str(out)]
            run(*args, *(["--stream", "--chunk", "8"] if stream else []))
            assert same_mesh(isolab.load(out), want), f"{name} {'streamed' if stream else 'in memory'}"


@needs_cli
def test_zarr_refusals_name_the_store_and_the_reason(tmp_path):
    vol = volume()
    four = str(tmp_path / "four.zarr")
    zarr.create_array(four, shape=(2,) + vol.shape, chunks=(1, 8, 8, 8), dtype=vol.dtype)[:] = np.stack([vol, vol])
    group = str(tmp_path / "group.zarr")
    zarr.open_group(group, mode="w").create_array("raw", shape=vol.shape, chunks=(8, 8, 8), dtype=vol.dtype)[:] = vol
    cases = [
        (four, [], "pick one with --volume K (0 to 1)"),
        (four, ["--volume", "2"], "--volume 2 is out of range"),
        (group, [], "without OME-Zarr multiscales"),
    ]
    for path, extra, reason in cases:
        out = tmp_path / "refused.ply"
        err = run("extract", "-a", "marching-cubes", "-f", path, "--iso", "1", "-o", str(out), *extra, ok=False).stderr
        assert reason in err and os.path.basename(path) in err, err
        assert not out.exists()
    # The 4-D store's volume 1 and the group's array, named, are meshed.
    run("extract", "-a", "marching-cubes", "-f", four, "--volume", "1", "--iso", str(LEVEL), "-o", str(tmp_path / "a.ply"))
    run("extract", "-a", "marching-cubes", "-f", os.path.join(group, "raw"), "--iso", str(LEVEL), "-o",
        str(tmp_path / "b.ply"))
    assert same_mesh(isolab.load(tmp_path / "a.ply"), expected(vol))
    assert same_mesh(isolab.load(tmp_path / "b.ply"), expected(vol))
