#!/usr/bin/env python3
"""The peers of the `quality_tets` experiment: TetGen, CGAL Mesh_3, NETGEN and fTetWild on each
shipped model's own triangle mesh, sized to `isosurface-stuffing`'s tetrahedron count.

1. **The input.** The model's triangles as the file has them; the bunny, which has holes in its
   base, with its holes closed by pymeshlab (`meshing_close_holes`, its unused vertices dropped),
   since every peer needs a closed surface (stuffing closes them by the winding number's sign).
   Nothing else is repaired: a mesher that refuses the surface (TetGen: the scanned bunny
   intersects itself) gets an error row.
2. **The target.** Stuffing's count at h = longest side / 32, read from
   report/data/quality_tets.json (run the experiment first).
3. **Matching.** Each peer's sizing parameter (TetGen's maximum volume, CGAL's cell and facet
   size, NETGEN's maxh, fTetWild's ideal edge length) starts at the value that would give the
   target for uniform tetrahedra of edge h and is scaled by (count / target)^(1/3) until the count
   is within MATCH_TOLERANCE of the target or MATCH_STEPS tries have run; the try nearest the
   target is kept and run RERUNS more times for its time (median and spread on the page). TetGen
   keeps every input triangle, so its count cannot fall below what the surface alone needs.
4. **Settings**: each mesher's defaults otherwise, one thread: TetGen quality mode (radius-edge
   <= 2); CGAL Mesh_3 with facet angle 25, facet distance size/10, radius-edge 3, then ODT and
   exudation (60 s caps); NETGEN's STL geometry and default optimisation; fTetWild's default
   envelope.
5. **Measured by the definitions the experiment uses for ours** (`quality_tets::measure`): dihedral
   range, radius ratio R / 3r (mean, largest), tetrahedra of the minority orientation or zero
   volume as inverted (meshers differ in which orientation is positive), the distance from the
   boundary's vertices to the model's own surface and from the model's vertices to the boundary
   (libigl, in h), volume over the model's, and whether every model vertex is inside the mesh
   (winding number of its boundary, or within 1e-6 of its box).

Writes report/data/quality_tets_peers.json (committed; the report builds without Python).
Run: tests/reference/.venv/bin/python experiments/src/experiment/quality_tets/peers.py
"""
import functools
import json
import os
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "stuart_tables"))
# CGAL, NETGEN and fTetWild as Table 2 runs them, the size (their `h`) given here.
from peers import ROOT, dihedral_range, isolated, read_obj, run_cgal, run_ftetwild, run_netgen, signed_volume  # noqa: E402

MODELS = ["stanford-bunny", "spot", "rocker-arm", "fandisk", "cheburashka"]
CELLS = 32  # quality_tets::PEER_CELLS
MATCH_TOLERANCE = 0.10
MATCH_STEPS = 4
RERUNS = 2
# Tetrahedra per h³ in a lattice of edge h (the BCC lattice has 6 per cube): the first guess.
REGULAR_TET_VOLUME = 1.0 / 6.0


def closed_input(name, v, f):
    """The model as a closed surface, and how it was made so."""
    e = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    _, counts = np.unique(e, axis=0, return_counts=True)
    if (counts == 1).sum() == 0:
        return v, f, "the model's own triangles"
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(v, f))
    ms.meshing_close_holes(maxholesize=10000, selfintersection=False)
    ms.meshing_remove_unreferenced_vertices()
    m = ms.current_mesh()
    return (np.asarray(m.vertex_matrix(), dtype=float), np.asarray(m.face_matrix(), dtype=np.int64),
            f"its {int((counts == 1).sum())} boundary edges closed by pymeshlab's meshing_close_holes")


def run_tetgen(v, f, size):
    import tetgen

    here = os.getcwd()
    with tempfile.TemporaryDirectory() as d:
        os.chdir(d)  # TetGen writes the facets it skipped into the working directory
        try:
            t0 = time.perf_counter()
            tg = tetgen.TetGen(v, f)
            nodes, elems = tg.tetrahedralize(quality=True, minratio=2.0, fixedvolume=True, maxvolume=size, quiet=True)[:2]
            seconds = time.perf_counter() - t0
        finally:
            os.chdir(here)
    return nodes, elems, seconds, f"quality (radius-edge <= 2), maximum volume {size:.4g}"


# Each mesher, its size parameter's first value for a target count, and how the count scales with it.
MESHERS = [
    ("TetGen", run_tetgen, lambda volume, target, h: volume / target, 1.0),
    ("CGAL Mesh_3", run_cgal, lambda volume, target, h: (volume / target / REGULAR_TET_VOLUME) ** (1 / 3), 3.0),
    ("NETGEN", run_netgen, lambda volume, target, h: (volume / target / REGULAR_TET_VOLUME) ** (1 / 3), 3.0),
    ("fTetWild", run_ftetwild, lambda volume, target, h: (volume / target / REGULAR_TET_VOLUME) ** (1 / 3), 3.0),
]


def circumradius(p):
    a = p[:, 0]
    b, c, d = p[:, 1] - a, p[:, 2] - a, p[:, 3] - a
    num = (np.sum(b * b, 1)[:, None] * np.cross(c, d) + np.sum(c * c, 1)[:, None] * np.cross(d, b)
           + np.sum(d * d, 1)[:, None] * np.cross(b, c))
    den = 2.0 * np.einsum("ij,ij->i", b, np.cross(c, d))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.linalg.norm(num, axis=1) / np.abs(den)


def measure(points, tets, s_v, s_f, h):
    """The experiment's measures (quality_tets::measure) of one mesh against the model (s_v, s_f)."""
    import igl

    points = np.asarray(points, dtype=float)
    tets = np.asarray(tets, dtype=np.int64)[:, :4]
    p = points[tets]
    six_v = np.einsum("ij,ij->i", p[:, 1] - p[:, 0], np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]))
    majority = 1.0 if (six_v > 0).sum() >= (six_v < 0).sum() else -1.0
    inverted = int((six_v * majority <= 0).sum())
    faces = [(1, 2, 3), (0, 2, 3), (0, 1, 3), (0, 1, 2)]
    area = sum(0.5 * np.linalg.norm(np.cross(p[:, j] - p[:, i], p[:, k] - p[:, i]), axis=1) for i, j, k in faces)
    r_in = np.abs(six_v) / 2.0 / area  # 3 V / area, V = |six_v| / 6
    rr = circumradius(p) / (3.0 * r_in)
    lo, hi = dihedral_range(points, tets)
    boundary = igl.boundary_facets(tets)
    boundary = boundary[0] if isinstance(boundary, tuple) else boundary
    used = np.unique(boundary)
    to = np.sqrt(igl.point_mesh_squared_distance(points[used], s_v, s_f)[0]) / h
    frm = np.sqrt(igl.point_mesh_squared_distance(s_v, points, boundary)[0]) / h
    winding = np.abs(igl.fast_winding_number(points, boundary, s_v))
    box = float((points.max(axis=0) - points.min(axis=0)).max())
    encloses = bool(np.all((winding >= 0.5) | (frm * h <= 1e-6 * box)))
    return {"tetrahedra": int(len(tets)), "dihedral": [lo, hi], "radius_ratio": [float(np.mean(rr)), float(np.max(rr))],
            "inverted": inverted, "to_surface_h": [float(to.mean()), float(to.max())],
            "from_surface_h": [float(frm.mean()), float(frm.max())],
            "volume_ratio": float(np.abs(six_v).sum() / 6.0 / abs(signed_volume(s_v, s_f))), "encloses": encloses}


def check_measures():
    """The regular tetrahedron: every angle arccos(1/3), radius ratio 1."""
    s = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], dtype=float)
    lo, hi = dihedral_range(s, np.array([[0, 1, 2, 3]]))
    assert abs(lo - 70.5288) < 1e-3 and abs(hi - 70.5288) < 1e-3, (lo, hi)
    assert abs(circumradius(s[None])[0] / (3.0 * np.sqrt(3.0) / 3.0) - 1.0) < 1e-9


def matched(tool, run, first, exponent, v, f, s_v, s_f, h, target):
    size, best, tries = first, None, 0
    for _ in range(MATCH_STEPS):
        tries += 1
        try:
            points, tets, seconds, settings = isolated(run, v, f, size)
        except Exception as e:
            if best is None:
                return {"tool": tool, "target": target, "tries": tries, "error": str(e)}
            break
        n = len(tets)
        if best is None or abs(n - target) < abs(best[0] - target):
            best = (n, size, points, tets, [seconds], settings)
        if abs(n - target) <= MATCH_TOLERANCE * target:
            break
        size *= (n / target) ** (1.0 / exponent)
    n, size, points, tets, seconds, settings = best
    for _ in range(RERUNS):
        try:
            seconds.append(isolated(run, v, f, size)[2])
        except Exception:
            break
    return {"tool": tool, "target": target, "tries": tries, "quality": measure(points, tets, s_v, s_f, h),
            "seconds": seconds, "settings": settings}


def main():
    check_measures()
    ours = json.load(open(os.path.join(ROOT, "report", "data", "quality_tets.json")))
    only = sys.argv[1:]
    rows, inputs = [], []
    for name in MODELS:
        s_v, s_f = read_obj(os.path.join(ROOT, "models", f"{name}.obj"))
        h = float((s_v.max(axis=0) - s_v.min(axis=0)).max()) / CELLS
        v, f, how = closed_input(name, s_v, s_f)
        inputs.append({"model": name, "how": how, "triangles": int(len(f))})
        volume = abs(signed_volume(v, f))
        target = next(r["quality"]["tetrahedra"] for r in ours["rows"]
                      if r["model"] == name and r["tool"] == "isosurface-stuffing" and r["cells"] == CELLS)
        for tool, run, first, exponent in MESHERS:
            if only and tool not in only:
                continue
            r = matched(tool, run, first(volume, target, h), exponent, v, f, s_v, s_f, h, target)
            r["model"] = name
            print(json.dumps({k: r.get(k) for k in ("model", "tool", "tries", "target", "error", "seconds")}
                             | {"tetrahedra": r.get("quality", {}).get("tetrahedra")}), file=sys.stderr, flush=True)
            rows.append(r)
    out = {"cells": CELLS, "match_tolerance": MATCH_TOLERANCE, "inputs": inputs, "rows": rows}
    path = os.path.join(ROOT, "report", "data", "quality_tets_peers.json")
    with open(path + ".tmp", "w") as fh:
        json.dump(out, fh, indent=1)
        fh.write("\n")
    os.replace(path + ".tmp", path)


if __name__ == "__main__":
    main()
