"""Lattice cleaving against CGAL Mesh_3 on labeled images, on one machine, one thread each.

    python labeled_vs_cleaving.py OUT.json --map NAME:PATH.npy[:STEP] ... [--voronoi N:LABELS]

Each map (a uint8 array saved by numpy; STEP keeps every STEP-th voxel along each axis) is meshed
by
`isolab.mesh_labels(..., algorithm="lattice-cleaving", threads=1)` three times (every run kept),
then by `cgal_labeled_image` (tests/reference/mesh3, built by run.sh into .bin) one-shot in a fresh
process, timed around `make_mesh_3` alone, its cell size scaled until its tetrahedron count is
within 20% of ours (four tries; facet size = cell size). Both meshes get the same measures here:
count, smallest and largest dihedral angle, inverted tetrahedra, and each label's volume against
its voxels. Runs in the Python venv that has isolab (tests/all.sh's). The report's run:

    python tests/reference/mesh3/labeled_vs_cleaving.py report/data/quality_tets_labels.json \
        --map "MNI152 tissue, every 4th voxel:mni_tissue.npy:4" --voronoi 32:7

where mni_tissue.npy is the tissue map `segmentations` meshes (its bench.py's `--save-tissue`
writes it as NIfTI; `np.save` of its data array, numpy order kept).
"""

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time

import numpy as np

import isolab

HERE = os.path.dirname(os.path.abspath(__file__))
CGAL = os.path.join(HERE, "..", ".bin", "cgal_labeled_image")


def dihedral_range(p):
    """Smallest and largest dihedral angle (degrees) of tetrahedra ``p`` (K, 4, 3)."""
    lo, hi = 180.0, 0.0
    for i, j, k, m in [(0, 1, 2, 3), (0, 2, 1, 3), (0, 3, 1, 2), (1, 2, 0, 3), (1, 3, 0, 2), (2, 3, 0, 1)]:
        e = p[:, j] - p[:, i]
        e /= np.linalg.norm(e, axis=1, keepdims=True)
        u = p[:, k] - p[:, i]
        w = p[:, m] - p[:, i]
        u -= (u * e).sum(1, keepdims=True) * e
        w -= (w * e).sum(1, keepdims=True) * e
        c = (u * w).sum(1) / (np.linalg.norm(u, axis=1) * np.linalg.norm(w, axis=1))
        a = np.degrees(np.arccos(np.clip(c, -1, 1)))
        lo, hi = min(lo, float(a.min())), max(hi, float(a.max()))
    return [lo, hi]


def measure(vertices, tets, labels, seg):
    p = vertices.astype(np.float64)[tets]
    vol = np.einsum("ij,ij->i", p[:, 1] - p[:, 0], np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0])) / 6
    counts = {int(l): int(n) for l, n in zip(*np.unique(seg, return_counts=True)) if l != 0}
    volumes = {l: float(np.abs(vol[labels == l]).sum()) for l in counts}
    return {"tetrahedra": int(len(tets)), "dihedral": dihedral_range(p), "inverted": int((vol <= 0).sum()),
            "volume_error": {str(l): volumes[l] / counts[l] - 1 for l in counts}}


def ours(seg):
    runs = []
    for _ in range(3):
        start = time.perf_counter()
        m = isolab.mesh_labels(seg, algorithm="lattice-cleaving", threads=1)
        runs.append((time.perf_counter() - start) * 1e3)
    row = measure(m.vertices, m.tetrahedra, m.tetrahedron_labels, np.asarray(seg))
    row.update(tool="lattice-cleaving", ms=runs, extract_ms=m.extract_ms)
    return row


def cgal(seg, target, tmp):
    # isolab reads numpy's last axis as x; CGAL's image is x fastest too: write C order, swap back.
    raw = os.path.join(tmp, "labels.raw")
    np.ascontiguousarray(seg).tofile(raw)
    nz, ny, nx = seg.shape
    size, best = 1.5, None
    for attempt in range(4):
        out = os.path.join(tmp, "cgal.txt")
        run = subprocess.run([CGAL, raw, str(nx), str(ny), str(nz), str(size), str(size), out],
                             capture_output=True, text=True, timeout=1800)
        if run.returncode != 0:
            return {"tool": "CGAL Mesh_3", "error": run.stderr.strip()[-300:]}
        info = json.loads(run.stdout.strip().splitlines()[-1])
        if best is None or abs(info["tetrahedra"] - target) < abs(best[0]["tetrahedra"] - target):
            v, t = [], []
            with open(out) as f:
                for line in f:
                    parts = line.split()
                    (v if parts[0] == "v" else t).append([float(x) for x in parts[1:]])
            best = (info, size, np.asarray(v), np.asarray(t, dtype=np.int64))
        if abs(info["tetrahedra"] / target - 1) <= 0.2:
            break
        size *= (info["tetrahedra"] / target) ** (1 / 3)
    info, size, v, t = best
    # Back to isolab's axes (x = numpy's last) and labels per cell.
    row = measure(v, t[:, :4], t[:, 4], np.asarray(seg))
    row.update(tool="CGAL Mesh_3", ms=[info["make_mesh_3_ms"]], cell_size=size, tries=attempt + 1, cgal=info["cgal"])
    return row


def compiler():
    """The C++ compiler that built the CGAL program (run.sh's g++)."""
    try:
        return subprocess.run(["g++", "--version"], capture_output=True, text=True).stdout.splitlines()[0]
    except (OSError, IndexError):
        return "unknown"


def voronoi(n, labels, seed=7):
    rng = np.random.default_rng(seed)
    seeds = rng.uniform(0, n, (2 * labels, 3))
    from scipy.spatial import cKDTree
    grid = np.stack(np.meshgrid(*[np.arange(n)] * 3, indexing="ij"), axis=-1).reshape(-1, 3)
    _, nearest = cKDTree(seeds).query(grid)
    return np.ascontiguousarray((nearest % labels).astype(np.uint8).reshape(n, n, n))


def main():
    p = argparse.ArgumentParser()
    p.add_argument("out")
    p.add_argument("--map", action="append", default=[])
    p.add_argument("--voronoi", default="")
    a = p.parse_args()
    inputs = []
    for spec in a.map:
        name, path, *step = spec.split(":")
        s = int(step[0]) if step else 1
        inputs.append((name, np.ascontiguousarray(np.load(path)[::s, ::s, ::s])))
    for spec in filter(None, a.voronoi.split(",")):
        n, labels = (int(x) for x in spec.split(":"))
        inputs.append((f"voronoi {n}³, {labels - 1} labels", voronoi(n, labels)))
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, seg in inputs:
            ours_row = ours(seg)
            rows.append(dict(ours_row, input=name, shape=list(seg.shape)))
            rows.append(dict(cgal(seg, ours_row["tetrahedra"], tmp), input=name, shape=list(seg.shape)))
            print(json.dumps(rows[-2:]), file=sys.stderr)
    commit = subprocess.run(["git", "rev-parse", "--short=10", "HEAD"], capture_output=True, text=True, cwd=HERE).stdout.strip()
    dirty = bool(subprocess.run(["git", "status", "--porcelain"], capture_output=True, text=True, cwd=HERE).stdout.strip())
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), platform.machine())
    with open(a.out, "w") as f:
        json.dump({"commit": commit, "dirty": dirty, "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
                   "cpu": cpu, "cores": os.cpu_count(), "os": platform.platform(), "python": platform.python_version(),
                   "numpy": np.__version__, "compiler": compiler(), "isolab": isolab.__version__, "rows": rows}, f, indent=1)


if __name__ == "__main__":
    main()
