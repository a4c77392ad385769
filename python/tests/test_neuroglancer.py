"""isolab.dask.mesh_labels(..., format="neuroglancer") read back by a reader written here from
neuroglancer's spec (src/datasource/precomputed/meshes.md and sharded.md), sharing no code with
the writer: DracoPy (Google's C++ Draco) decodes the fragments and mmh3 (the reference
MurmurHash3) finds segments in shards.

Checked: every manifest and fragment decodes; fragments are in Z-curve order and their sizes
add up to the data; level 0 reassembled per label is isolab.mesh_labels of the whole map within
the quantization; no triangle above level 0 crosses its fragment's 2x2x2 grid (neuroglancer's
own partition rule on the quantized integers); sharded and unsharded sources hold the same
segments; names become segment properties; a run on a LocalCluster of two workers writes the
same bytes as one in-process; a rerun resumes; bad settings raise."""

import gzip
import json
import os
import struct
import time

import DracoPy
import mmh3
import numpy as np
import pytest
from scipy.spatial import cKDTree

import isolab

dask = pytest.importorskip("dask")
import isolab.dask as idask  # noqa: E402

from test_dask_labels import voronoi  # noqa: E402


# ---- an independent reader, from the spec ----------------------------------------------------

def read_manifest(data: bytes):
    """A multi-resolution manifest: chunk_shape, grid_origin, lod_scales, vertex_offsets and, per
    level, fragment positions (n x 3) and sizes."""
    at = 0

    def take(fmt, n):
        nonlocal at
        values = struct.unpack_from("<" + fmt * n, data, at)
        at += struct.calcsize("<" + fmt * n)
        return values

    chunk_shape = np.array(take("f", 3))
    grid_origin = np.array(take("f", 3))
    (num_lods,) = take("I", 1)
    lod_scales = np.array(take("f", num_lods))
    vertex_offsets = np.array(take("f", 3 * num_lods)).reshape(num_lods, 3)
    per_lod = take("I", num_lods)
    levels = []
    for n in per_lod:
        positions = np.array(take("I", 3 * n), dtype=np.int64).reshape(3, n).T
        sizes = np.array(take("I", n), dtype=np.int64)
        levels.append((positions, sizes))
    assert at == len(data), "the manifest has trailing bytes"
    return dict(chunk_shape=chunk_shape, grid_origin=grid_origin, lod_scales=lod_scales,
                vertex_offsets=vertex_offsets, levels=levels)


def morton(p):
    key = 0
    for bit in range(32):
        for a in range(3):
            key |= ((int(p[a]) >> bit) & 1) << (3 * bit + a)
    return key


class Source:
    """A precomputed multi-resolution mesh source on disk: segment -> (manifest, fragment data)."""

    def __init__(self, folder):
        self.folder = folder
        with open(os.path.join(folder, "info")) as f:
            self.info = json.load(f)
        assert self.info["@type"] == "neuroglancer_multilod_draco"
        assert self.info["vertex_quantization_bits"] in (10, 16)
        self.sharding = self.info.get("sharding")

    def segments(self):
        if self.sharding is None:
            return sorted(int(n[:-6]) for n in os.listdir(self.folder) if n.endswith(".index"))
        out = []
        for name in os.listdir(self.folder):
            if name.endswith(".shard"):
                out.extend(seg for seg, _, _ in self._shard_entries(os.path.join(self.folder, name)))
        return sorted(out)

    def _shard_entries(self, path):
        s = self.sharding
        with open(path, "rb") as f:
            data = f.read()
        minishards = 1 << s["minishard_bits"]
        end = 16 * minishards
        entries = []
        for m in range(minishards):
            lo, hi = struct.unpack_from("<QQ", data, 16 * m)
            if lo == hi:
                continue
            raw = data[end + lo:end + hi]
            if s.get("minishard_index_encoding", "raw") == "gzip":
                raw = gzip.decompress(raw)
            n = len(raw) // 24
            a = np.frombuffer(raw, dtype="<u8").reshape(3, n)
            ids = np.cumsum(a[0].astype(np.uint64))
            start = end
            for i in range(n):
                start += int(a[1, i])
                entries.append((int(ids[i]), start, int(a[2, i])))
                start += int(a[2, i])
        return entries

    def _shard_of(self, segment):
        s = self.sharding
        assert s["hash"] == "murmurhash3_x86_128"
        h = mmh3.hash64(struct.pack("<Q", segment >> s["preshift_bits"]), seed=0, x64arch=False, signed=False)[0]
        minishard = h & ((1 << s["minishard_bits"]) - 1)
        shard = (h >> s["minishard_bits"]) & ((1 << s["shard_bits"]) - 1)
        digits = -(-s["shard_bits"] // 4)
        return format(shard, "x").zfill(digits) + ".shard", minishard

    def read(self, segment):
        """(manifest, fragment data bytes)."""
        if self.sharding is None:
            with open(os.path.join(self.folder, f"{segment}.index"), "rb") as f:
                manifest = read_manifest(f.read())
            with open(os.path.join(self.folder, str(segment)), "rb") as f:
                data = f.read()
            return manifest, data
        name, _ = self._shard_of(segment)
        path = os.path.join(self.folder, name)
        found = [(start, size) for seg, start, size in self._shard_entries(path) if seg == segment]
        assert len(found) == 1, f"segment {segment} is not in {name}"
        start, size = found[0]
        with open(path, "rb") as f:
            blob = f.read()
        manifest = read_manifest(blob[start:start + size])
        total = sum(int(s.sum()) for _, s in manifest["levels"])
        return manifest, blob[start - total:start]

    def fragments(self, segment):
        """Per level: [(position, quantized (n x 3) int, faces, model-space vertices)]."""
        m, data = self.read(segment)
        assert sum(int(s.sum()) for _, s in m["levels"]) == len(data)
        bits = self.info["vertex_quantization_bits"]
        top = (1 << bits) - 1
        transform = np.array(self.info["transform"], dtype=np.float64).reshape(3, 4)
        at, out = 0, []
        for lod, (positions, sizes) in enumerate(m["levels"]):
            keys = [morton(p) for p in positions]
            assert keys == sorted(keys), f"segment {segment}: level {lod} is not in Z-curve order"
            frags = []
            for p, size in zip(positions, sizes):
                blob = data[at:at + size]
                at += size
                if size == 0:
                    continue
                mesh = DracoPy.decode(blob)
                q = np.asarray(mesh.points, dtype=np.float64)
                assert np.all(q == np.round(q)) and q.min() >= 0 and q.max() <= top
                stored = (m["grid_origin"] + m["vertex_offsets"][lod]
                          + m["chunk_shape"] * (2 ** lod) * (p + q / top))
                model = stored @ transform[:, :3].T + transform[:, 3]
                frags.append((p, q.astype(np.int64), np.asarray(mesh.faces, dtype=np.int64), model))
            out.append(frags)
        return out


# ---- the checks -------------------------------------------------------------------------------

def area(v, f):
    return 0.5 * np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=1).sum()


def check_source(folder, lab, algorithm="surface-nets", spacing=None):
    src = Source(folder)
    whole = isolab.mesh_labels(lab, algorithm=algorithm, spacing=spacing)
    assert src.segments() == sorted(whole)
    bits = src.info["vertex_quantization_bits"]
    partition = (((1 << 32) - 1) >> (32 - bits)) // 2 + 1  # neuroglancer_draco.cc's partition point
    for label in src.segments():
        levels = src.fragments(label)
        # Level 0 reassembled is the whole map's mesh: its area, and every vertex of it found
        # within the quantization (cut points added on the boxes' faces).
        verts = np.concatenate([v for _, _, _, v in levels[0]])
        faces_area = sum(area(v, f) for _, _, f, v in levels[0])
        w = whole[label]
        assert abs(faces_area - area(w.vertices, w.faces)) <= 2e-3 * area(w.vertices, w.faces), label
        step = (np.abs(np.array(src.info["transform"]).reshape(3, 4)[:, :3]).sum(1).max()
                * 2 * float(read_manifest_chunk(src, label)) / ((1 << bits) - 1))
        dist, _ = cKDTree(verts).query(w.vertices)
        assert dist.max() <= step, (label, dist.max(), step)
        # Above level 0 no triangle crosses the 2x2x2 grid (on the quantized integers).
        for lod in range(1, len(levels)):
            for _, q, f, _ in levels[lod]:
                c = q[f]  # (M, 3 corners, 3 axes)
                crosses = (c < partition).any(axis=1) & (c > partition).any(axis=1)
                assert not crosses.any(), f"label {label}: level {lod} has {int(crosses.any(1).sum())} triangles across the grid"
            assert levels[lod], f"label {label} has no fragment at level {lod}"
    return src


def read_manifest_chunk(src, label):
    m, _ = src.read(label)
    return m["chunk_shape"].max()


def test_unsharded_source_reads_back(tmp_path):
    lab = voronoi((34, 30, 38), 12)
    started = time.perf_counter()
    report = idask.mesh_labels(lab, chunk=8, format="neuroglancer", out=tmp_path / "ng", names={1: "first", 2: "second"})
    took = time.perf_counter() - started
    # The phases' wall times: each measured (boxes take the meshing), together within the call.
    phases = report["seconds"]
    assert sorted(phases) == ["boxes", "files", "info_and_cleanup"]
    assert all(s >= 0 for s in phases.values()) and phases["boxes"] > 0
    assert sum(phases.values()) <= took
    assert report["lods"] == 4 and report["segments"] == 12
    assert report["fragments"][0] > report["fragments"][-1] >= 12
    assert report["triangles"][0] > report["triangles"][1] > report["triangles"][-1]
    check_source(str(tmp_path / "ng"), lab)
    with open(tmp_path / "ng" / "segment_properties" / "info") as f:
        props = json.load(f)
    assert props["inline"]["ids"] == ["1", "2"] and props["inline"]["properties"][0]["values"] == ["first", "second"]
    assert not (tmp_path / "ng" / ".isolab-work").exists()


def test_sharded_source_holds_the_same_segments(tmp_path):
    lab = voronoi((26, 30, 22), 9, seed=3)
    idask.mesh_labels(lab, chunk=8, format="neuroglancer", out=tmp_path / "flat", quantization_bits=10)
    idask.mesh_labels(lab, chunk=8, format="neuroglancer", out=tmp_path / "sharded", sharded=True,
                      quantization_bits=10)
    flat, sharded = Source(str(tmp_path / "flat")), check_source(str(tmp_path / "sharded"), lab)
    assert sharded.sharding["@type"] == "neuroglancer_uint64_sharded_v1"
    assert flat.segments() == sharded.segments()
    for label in flat.segments():
        m1, d1 = flat.read(label)
        m2, d2 = sharded.read(label)
        assert d1 == d2
        assert all((a[0] == b[0]).all() and (a[1] == b[1]).all() for a, b in zip(m1["levels"], m2["levels"]))


def test_marching_tetrahedra_with_spacing(tmp_path):
    lab = voronoi((20, 24, 18), 7, seed=5, dtype=np.uint8)
    idask.mesh_labels(lab, chunk=6, algorithm="marching-tetrahedra", spacing=(2.0, 1.0, 0.5), format="neuroglancer",
                      out=tmp_path / "ng", lods=2)
    src = check_source(str(tmp_path / "ng"), lab, "marching-tetrahedra", spacing=(2.0, 1.0, 0.5))
    assert len(src.fragments(src.segments()[0])) == 2


def test_cluster_writes_what_one_process_writes(tmp_path, client):
    lab = voronoi((30, 28, 26), 10, seed=11)
    idask.mesh_labels(lab, chunk=8, format="neuroglancer", out=tmp_path / "local")
    idask.mesh_labels(lab, chunk=8, format="neuroglancer", out=tmp_path / "cluster", client=client)
    a, b = Source(str(tmp_path / "local")), Source(str(tmp_path / "cluster"))
    assert a.segments() == b.segments()
    for label in a.segments():
        assert a.read(label)[1] == b.read(label)[1]


def test_rerun_resumes_from_the_box_files(tmp_path):
    lab = voronoi((24, 24, 24), 6, seed=2)
    out = tmp_path / "ng"
    idask.mesh_labels(lab, chunk=8, format="neuroglancer", out=out, keep_work=True)
    boxes = sorted((out / ".isolab-work" / "lod0").iterdir())
    stamp = {p: p.stat().st_mtime_ns for p in boxes}
    os.remove(out / "1")
    idask.mesh_labels(lab, chunk=8, format="neuroglancer", out=out, keep_work=True)
    assert {p: p.stat().st_mtime_ns for p in boxes} == stamp, "a rerun remade finished boxes"
    check_source(str(out), lab)


def test_bad_settings_raise(tmp_path):
    lab = voronoi((12, 12, 12), 3)
    with pytest.raises(ValueError, match="out=FOLDER"):
        idask.mesh_labels(lab, format="neuroglancer")
    with pytest.raises(ValueError, match="format must be"):
        idask.mesh_labels(lab, format="draco", out=tmp_path / "x")
    with pytest.raises(ValueError, match="out=FOLDER"):
        idask.mesh_labels(lab, format="neuroglancer-legacy")
    with pytest.raises(ValueError, match="10 or 16"):
        idask.mesh_labels(lab, chunk=4, format="neuroglancer", out=tmp_path / "y", quantization_bits=12)
    with pytest.raises(ValueError, match="lods must be"):
        idask.mesh_labels(lab, chunk=4, format="neuroglancer", out=tmp_path / "z", lods=0)


def test_legacy_format_reassembles_each_label(tmp_path):
    lab = voronoi((22, 26, 20), 8, seed=9)
    report = idask.mesh_labels(lab, chunk=8, spacing=(1.0, 2.0, 0.5), format="neuroglancer-legacy", out=tmp_path / "ng")
    with open(tmp_path / "ng" / "info") as f:
        assert json.load(f)["@type"] == "neuroglancer_legacy_mesh"
    whole = isolab.mesh_labels(lab, spacing=(1.0, 2.0, 0.5))
    assert report["segments"] == len(whole)
    for label, mesh in whole.items():
        with open(tmp_path / "ng" / f"{label}:0") as f:
            names = json.load(f)["fragments"]
        total = 0.0
        verts = []
        for name in names:
            with open(tmp_path / "ng" / name, "rb") as f:
                data = f.read()
            (nv,) = struct.unpack_from("<I", data, 0)
            v = np.frombuffer(data, "<f4", 3 * nv, 4).reshape(nv, 3).astype(np.float64)
            rest = (len(data) - 4 - 12 * nv)
            assert rest % 12 == 0
            faces = np.frombuffer(data, "<u4", rest // 4, 4 + 12 * nv).reshape(-1, 3).astype(np.int64)
            assert faces.max() < nv
            total += area(v, faces)
            verts.append(v)
        a = area(mesh.vertices, mesh.faces)
        assert abs(total - a) <= 1e-3 * a, (label, total, a)
        dist, _ = cKDTree(np.concatenate(verts)).query(mesh.vertices)
        assert dist.max() < 1e-4, label
