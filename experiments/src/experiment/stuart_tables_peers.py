#!/usr/bin/env python3
"""Table 2 of Stuart et al. 2013 for the `stuart_tables` experiment: the shipped models meshed by
TetGen (Python package `tetgen`, quality mode, radius-edge ratio <= 2, the library's defaults) and by
CGAL's Mesh_3 (`make_mesh_3` on the polyhedral domain, then `odt_optimize_mesh_3`, then exudation),
with the element count and the min/max dihedral angle measured here with one formula for both.

CGAL's sizing follows the lattice spacing our middle column uses (h = longest side / 10): cell size
and facet size h, facet distance h/10, so the two meshers work at a comparable resolution.
Writes report/data/stuart_tables_peers.json, which the experiment reads (the report builds without
Python). Run: tests/reference/.venv/bin/python experiments/src/experiment/stuart_tables_peers.py
"""
import json
import os
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))
MODELS = ["stanford-bunny", "spot", "rocker-arm", "fandisk", "cheburashka"]
CELLS = 10  # h = longest side / CELLS, the experiment's second spacing


def read_obj(path):
    vs, fs = [], []
    with open(path) as f:
        for line in f:
            t = line.split()
            if not t:
                continue
            if t[0] == "v":
                vs.append([float(x) for x in t[1:4]])
            elif t[0] == "f":
                idx = [int(x.split("/")[0]) for x in t[1:]]
                idx = [i - 1 if i > 0 else len(vs) + i for i in idx]
                for k in range(1, len(idx) - 1):
                    fs.append([idx[0], idx[k], idx[k + 1]])
    return np.array(vs, dtype=float), np.array(fs, dtype=np.int64)


def dihedral_range(points, tets):
    p = points[tets]  # (n, 4, 3)
    pairs = [(0, 1, 2, 3), (0, 2, 1, 3), (0, 3, 1, 2), (1, 2, 0, 3), (1, 3, 0, 2), (2, 3, 0, 1)]
    angles = []
    for i, j, k, l in pairs:
        e = p[:, j] - p[:, i]
        e /= np.linalg.norm(e, axis=1, keepdims=True)
        u = p[:, k] - p[:, i]
        w = p[:, l] - p[:, i]
        u -= e * np.sum(u * e, axis=1, keepdims=True)
        w -= e * np.sum(w * e, axis=1, keepdims=True)
        c = np.sum(u * w, axis=1) / (np.linalg.norm(u, axis=1) * np.linalg.norm(w, axis=1))
        angles.append(np.degrees(np.arccos(np.clip(c, -1.0, 1.0))))
    a = np.stack(angles, axis=1)
    return float(a.min()), float(a.max())


def run_tetgen(v, f):
    import tetgen

    t0 = time.perf_counter()
    tg = tetgen.TetGen(v, f)
    nodes, elems = tg.tetrahedralize(quality=True, minratio=2.0, quiet=True)[:2]
    seconds = time.perf_counter() - t0
    lo, hi = dihedral_range(np.asarray(nodes), np.asarray(elems)[:, :4])
    return {"tetrahedra": int(len(elems)), "dihedral_min": lo, "dihedral_max": hi, "seconds": seconds,
            "settings": "quality, radius-edge <= 2 (tetgen defaults)"}


def read_medit(path):
    with open(path) as f:
        tokens = f.read().split()
    points, tets = [], []
    i = 0
    while i < len(tokens):
        t = tokens[i]
        if t == "Vertices":
            n = int(tokens[i + 1])
            i += 2
            for _ in range(n):
                points.append([float(x) for x in tokens[i:i + 3]])
                i += 4
            continue
        if t == "Tetrahedra":
            n = int(tokens[i + 1])
            i += 2
            for _ in range(n):
                tets.append([int(x) - 1 for x in tokens[i:i + 4]])
                i += 5
            continue
        i += 1
    return np.array(points), np.array(tets, dtype=np.int64)


def run_cgal(v, f, h):
    import CGAL.CGAL_Mesh_3 as M
    from CGAL.CGAL_Polyhedron_3 import Polyhedron_3

    with tempfile.TemporaryDirectory() as d:
        off = os.path.join(d, "in.off")
        with open(off, "w") as out:
            out.write(f"OFF\n{len(v)} {len(f)} 0\n")
            for p in v:
                out.write(f"{p[0]} {p[1]} {p[2]}\n")
            for t in f:
                out.write(f"3 {t[0]} {t[1]} {t[2]}\n")
        poly = Polyhedron_3(off)
        if not poly.is_closed():
            return {"error": "the polyhedral domain needs a closed surface; this model has holes"}
        t0 = time.perf_counter()
        domain = M.Polyhedral_mesh_domain_3(poly)
        params = M.Mesh_3_parameters()
        params.no_perturb()
        params.no_exude()
        criteria = M.Default_mesh_criteria()
        criteria.facet_angle(25).facet_size(h).facet_distance(h / 10).cell_radius_edge_ratio(3).cell_size(h)
        c3t3 = M.make_mesh_3(domain, criteria, params)
        # time limit (s), iterations, convergence, freeze bound: CGAL's documented defaults but a
        # 60 s cap
        M.odt_optimize_mesh_3(c3t3, domain, 60.0, 100, 0.02, 0.01)
        M.exude_mesh_3(c3t3, 60.0, 0.0)
        seconds = time.perf_counter() - t0
        medit = os.path.join(d, "out.mesh")
        c3t3.output_to_medit(medit)
        points, tets = read_medit(medit)
    lo, hi = dihedral_range(points, tets)
    return {"tetrahedra": int(len(tets)), "dihedral_min": lo, "dihedral_max": hi, "seconds": seconds,
            "settings": f"cell and facet size {h:.4g}, facet distance {h / 10:.4g}, radius-edge 3, facet angle 25; ODT, exude"}


def main():
    rows = []
    for name in MODELS:
        v, f = read_obj(os.path.join(ROOT, "models", f"{name}.obj"))
        h = float((v.max(axis=0) - v.min(axis=0)).max()) / CELLS
        for tool, fn in [("TetGen", lambda: run_tetgen(v, f)), ("CGAL Mesh_3", lambda: run_cgal(v, f, h))]:
            try:
                r = fn()
            except Exception as e:  # recorded, shown as a dash in the report
                r = {"error": f"{type(e).__name__}: {e}"}
            r.update({"model": name, "tool": tool})
            print(json.dumps(r), file=sys.stderr)
            rows.append(r)
    import CGAL
    import tetgen

    out = {"tetgen_version": tetgen.__version__, "cgal_version": getattr(CGAL, "__version__", "6.0.1"), "rows": rows}
    path = os.path.join(ROOT, "report", "data", "stuart_tables_peers.json")
    with open(path, "w") as fh:
        json.dump(out, fh, indent=1)
        fh.write("\n")


if __name__ == "__main__":
    main()
