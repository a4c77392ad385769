#!/usr/bin/env python3
"""Table 2 of Stuart et al. 2013 for the `stuart_tables` experiment: the paper's alternative to its
own method, "computing an offset surface and running an off-the-shelf meshing program" (section 4),
run for real on the shipped models.

1. **The offset surface.** For each model, `S`'s signed distance (libigl, fast winding number sign,
   so the bunny's holes do not matter) on a grid of spacing h/5, h = longest side / 10 (the
   configuration `bcc-sculpt` runs beside the peers), and its level set at d_offset = 0.6 h
   (scikit-image marching cubes), remeshed isotropically (pymeshlab) to edges of about h, the
   length of our lattice's edges. `bcc-sculpt`'s boundary stops within the same d_offset of `S`,
   so every mesher gets the region ours may occupy.
2. **The meshers**, each on that offset surface:
   - TetGen (`tetgen`): quality mode, radius-edge ratio <= 2 (its defaults); keeps the input facets;
   - CGAL Mesh_3 (`cgal`): polyhedral domain, cell and facet size h, facet distance h/10, then ODT
     optimisation and exudation; and again with cell and facet size scaled until its tetrahedron count
     is within 5% of ours ("tets matched");
   - NETGEN (`netgen-mesher`): the STL geometry, maximum size h, its default optimisation;
   - fTetWild (`pytetwild`): ideal edge length h, its default envelope.
3. **Measured here with one formula for all**: tetrahedra, min/max dihedral angle, volume over the
   volume of `S`, and whether every vertex of `S` is inside the mesh (winding number of its
   boundary), as `bcc-sculpt`'s rows are.

Reads our tetrahedron counts from report/data/stuart_tables.json (run the experiment first) and
writes report/data/stuart_tables_peers.json, which the experiment reads (the report builds without
Python). Run: tests/reference/.venv/bin/python experiments/src/experiment/stuart_tables/peers.py
"""
import functools
import json
import multiprocessing as mp
import os
import signal
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))
MODELS = ["stanford-bunny", "spot", "rocker-arm", "fandisk", "cheburashka"]
CELLS = 10  # h = longest side / CELLS: stuart_tables::TABLE2_CELLS
RATIO = 0.6  # d_offset / h: stuart_tables::TABLE2_RATIO
GRID_PER_H = 5  # signed-distance samples per h
SURFACE_EDGE_H = 1.0  # the offset surface's target edge length, in h
MATCH_TOLERANCE = 0.05  # CGAL's tetrahedron count within this fraction of ours
MATCH_STEPS = 8
TIMEOUT_S = 600


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


def signed_volume(v, f):
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    return float(np.sum(np.einsum("ij,ij->i", a, np.cross(b, c))) / 6.0)


def offset_surface(v, f, h):
    """The level set `sd = RATIO h` of S's signed distance, remeshed to edges of about h."""
    import igl
    import pymeshlab
    from skimage import measure

    d = RATIO * h
    step = h / GRID_PER_H
    lo = v.min(axis=0) - d - 3 * step
    hi = v.max(axis=0) + d + 3 * step
    axes = [np.arange(lo[k], hi[k] + step, step) for k in range(3)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    sd = igl.signed_distance(grid, v, f, sign_type=igl.SIGNED_DISTANCE_TYPE_FAST_WINDING_NUMBER)[0]
    sd = sd.reshape(len(axes[0]), len(axes[1]), len(axes[2]))
    verts, faces, _, _ = measure.marching_cubes(sd, level=d, spacing=(step, step, step))
    verts = verts + lo
    faces = faces.astype(np.int64)
    if signed_volume(verts, faces) < 0:
        faces = faces[:, ::-1].copy()
    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(verts, faces))
    ms.meshing_isotropic_explicit_remeshing(targetlen=pymeshlab.PureValue(SURFACE_EDGE_H * h), iterations=10)
    m = ms.current_mesh()
    out_v, out_f = np.asarray(m.vertex_matrix(), dtype=float), np.asarray(m.face_matrix(), dtype=np.int64)
    topo = ms.get_topological_measures()
    closed = topo["boundary_edges"] == 0 and topo["non_two_manifold_edges"] == 0 and topo["non_two_manifold_vertices"] == 0
    return out_v, out_f, {"triangles": int(len(out_f)), "closed_manifold": bool(closed), "grid_step": step, "d_offset": d}


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


def measure_tets(points, tets, s_vertices, s_volume):
    """Tetrahedra, dihedral range, volume ratio and enclosure of S, one formula for every mesher."""
    import igl

    points = np.asarray(points, dtype=float)
    tets = np.asarray(tets, dtype=np.int64)[:, :4]
    lo, hi = dihedral_range(points, tets)
    p = points[tets]
    volume = float(np.sum(np.abs(np.einsum("ij,ij->i", p[:, 1] - p[:, 0], np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0])))) / 6.0)
    boundary = igl.boundary_facets(tets)[0]
    winding = np.abs(igl.fast_winding_number(points, boundary, s_vertices))
    return {"tetrahedra": int(len(tets)), "dihedral_min": lo, "dihedral_max": hi,
            "volume_ratio": volume / s_volume, "encloses": bool(np.all(winding > 0.5))}


def run_tetgen(v, f, h):
    import tetgen

    t0 = time.perf_counter()
    tg = tetgen.TetGen(v, f)
    nodes, elems = tg.tetrahedralize(quality=True, minratio=2.0, quiet=True)[:2]
    return nodes, elems, time.perf_counter() - t0, "quality, radius-edge <= 2 (tetgen defaults)"


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


def write_off(path, v, f):
    with open(path, "w") as out:
        out.write(f"OFF\n{len(v)} {len(f)} 0\n")
        for p in v:
            out.write(f"{p[0]:.17g} {p[1]:.17g} {p[2]:.17g}\n")
        for t in f:
            out.write(f"3 {t[0]} {t[1]} {t[2]}\n")


def run_cgal(v, f, h, scale=1.0):
    import CGAL.CGAL_Mesh_3 as M
    from CGAL.CGAL_Polyhedron_3 import Polyhedron_3

    size = scale * h
    with tempfile.TemporaryDirectory() as d:
        off = os.path.join(d, "in.off")
        write_off(off, v, f)
        poly = Polyhedron_3(off)
        if not poly.is_closed():
            raise RuntimeError("the polyhedral domain needs a closed surface")
        t0 = time.perf_counter()
        domain = M.Polyhedral_mesh_domain_3(poly)
        params = M.Mesh_3_parameters()
        params.no_perturb()
        params.no_exude()
        criteria = M.Default_mesh_criteria()
        criteria.facet_angle(25).facet_size(size).facet_distance(size / 10).cell_radius_edge_ratio(3).cell_size(size)
        c3t3 = M.make_mesh_3(domain, criteria, params)
        # time limit (s), iterations, convergence, freeze bound: CGAL's documented defaults but a
        # 60 s cap
        M.odt_optimize_mesh_3(c3t3, domain, 60.0, 100, 0.02, 0.01)
        M.exude_mesh_3(c3t3, 60.0, 0.0)
        seconds = time.perf_counter() - t0
        medit = os.path.join(d, "out.mesh")
        c3t3.output_to_medit(medit)
        points, tets = read_medit(medit)
    settings = f"cell and facet size {size:.4g}, facet distance {size / 10:.4g}, radius-edge 3, facet angle 25; ODT, exude"
    return points, tets, seconds, settings


def run_netgen(v, f, h):
    from netgen.stl import STLGeometry

    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "in.stl")
        with open(path, "w") as out:
            out.write("solid offset\n")
            for t in f:
                a, b, c = v[t[0]], v[t[1]], v[t[2]]
                n = np.cross(b - a, c - a)
                n = n / (np.linalg.norm(n) or 1.0)
                out.write(f"facet normal {n[0]:.17g} {n[1]:.17g} {n[2]:.17g}\n outer loop\n")
                for p in (a, b, c):
                    out.write(f"  vertex {p[0]:.17g} {p[1]:.17g} {p[2]:.17g}\n")
                out.write(" endloop\nendfacet\n")
            out.write("endsolid offset\n")
        # NETGEN writes __tracked_surface.stl into the working directory: keep it in the temporary one.
        here = os.getcwd()
        os.chdir(d)
        try:
            t0 = time.perf_counter()
            geo = STLGeometry(path)
            mesh = geo.GenerateMesh(maxh=h)
            seconds = time.perf_counter() - t0
        finally:
            os.chdir(here)
    points = np.array([list(p) for p in mesh.Points()], dtype=float)
    tets = np.array([[int(x.nr) - 1 for x in el.vertices] for el in mesh.Elements3D()], dtype=np.int64)
    if len(tets) == 0:
        raise RuntimeError("NETGEN produced no tetrahedra")
    return points, tets, seconds, f"STL geometry, maxh {h:.4g}, default optimisation"


def run_ftetwild(v, f, h):
    import pytetwild

    t0 = time.perf_counter()
    points, tets = pytetwild.tetrahedralize(v.astype(np.float64), f.astype(np.int32), edge_length_abs=h, num_threads=1, quiet=True)
    return points, tets, time.perf_counter() - t0, f"ideal edge length {h:.4g}, envelope 1e-3 of the box (defaults), one thread"


def in_child(queue, fn, args):
    try:
        queue.put(("ok", fn(*args)))
    except Exception as e:  # recorded, shown as a dash in the report
        queue.put(("error", f"{type(e).__name__}: {e}"))


def isolated(fn, *args):
    """Runs a mesher in its own process: a crash or a hang becomes an error row."""
    ctx = mp.get_context("spawn")  # a fresh interpreter: NETGEN aborted in a fork of this process
    queue = ctx.Queue()
    proc = ctx.Process(target=in_child, args=(queue, fn, args))
    proc.start()
    kind, value = "error", f"no result within {TIMEOUT_S} s"
    deadline = time.monotonic() + TIMEOUT_S
    while time.monotonic() < deadline:
        try:
            kind, value = queue.get(timeout=1.0)
            break
        except Exception:
            if not proc.is_alive() and queue.empty():
                code = proc.exitcode
                how = f"signal {signal.Signals(-code).name}" if code is not None and code < 0 else f"exit code {code}"
                kind, value = "error", f"the mesher's process died ({how})"
                break
    proc.join(5)
    if proc.is_alive():
        proc.kill()
    if kind == "error":
        raise RuntimeError(value)
    return value


def measured(tool, fn, v, f, h, s_vertices, s_volume):
    try:
        points, tets, seconds, settings = isolated(fn, v, f, h)
        r = measure_tets(points, tets, s_vertices, s_volume)
        r.update({"seconds": seconds, "settings": settings})
    except Exception as e:
        r = {"error": str(e)}
    r["tool"] = tool
    return r


def cgal_matched(v, f, h, target, s_vertices, s_volume):
    """CGAL with cell and facet size scaled (count ~ size^-3) until within MATCH_TOLERANCE of ours."""
    scale, best = 1.0, None
    for _ in range(MATCH_STEPS):
        r = measured("CGAL Mesh_3 (tets matched)", functools.partial(run_cgal, scale=scale), v, f, h, s_vertices, s_volume)
        if "error" in r:
            return r
        r["scale"] = scale
        if best is None or abs(r["tetrahedra"] - target) < abs(best["tetrahedra"] - target):
            best = r
        if abs(r["tetrahedra"] - target) <= MATCH_TOLERANCE * target:
            break
        scale *= (r["tetrahedra"] / target) ** (1.0 / 3.0)
    best["target"] = target
    return best


def main():
    ours = json.load(open(os.path.join(ROOT, "report", "data", "stuart_tables.json")))
    rows, surfaces = [], []
    for name in MODELS:
        sv, sf = read_obj(os.path.join(ROOT, "models", f"{name}.obj"))
        h = float((sv.max(axis=0) - sv.min(axis=0)).max()) / CELLS
        s_volume = abs(signed_volume(sv, sf))
        v, f, info = offset_surface(sv, sf, h)
        info.update({"model": name, "h": h, "encloses": measure_encloses_surface(v, f, sv)})
        print(json.dumps(info), file=sys.stderr)
        surfaces.append(info)
        target = next(r["tetrahedra"] for r in ours["rows"]
                      if r["model"] == name and r["cells"] == CELLS and abs(r["ratio"] - RATIO) < 1e-6)
        for tool, fn in [("TetGen", run_tetgen), ("CGAL Mesh_3", run_cgal), ("NETGEN", run_netgen), ("fTetWild", run_ftetwild)]:
            r = measured(tool, fn, v, f, h, sv, s_volume)
            r["model"] = name
            print(json.dumps(r), file=sys.stderr)
            rows.append(r)
        r = cgal_matched(v, f, h, target, sv, s_volume)
        r["model"] = name
        print(json.dumps(r), file=sys.stderr)
        rows.append(r)
    import importlib.metadata as md

    versions = {k: md.version(p) for k, p in [("TetGen", "tetgen"), ("CGAL", "cgal"), ("NETGEN", "netgen-mesher"),
                                              ("fTetWild", "pytetwild"), ("libigl", "libigl"), ("pymeshlab", "pymeshlab"),
                                              ("scikit-image", "scikit-image")]}
    out = {"versions": versions, "cells": CELLS, "ratio": RATIO, "grid_per_h": GRID_PER_H, "surface_edge_h": SURFACE_EDGE_H,
           "match_tolerance": MATCH_TOLERANCE, "surfaces": surfaces, "rows": rows}
    path = os.path.join(ROOT, "report", "data", "stuart_tables_peers.json")
    with open(path, "w") as fh:
        json.dump(out, fh, indent=1)
        fh.write("\n")


def measure_encloses_surface(v, f, s_vertices):
    """Every vertex of S inside the offset surface (winding number)."""
    import igl

    return bool(np.all(np.abs(igl.fast_winding_number(v, f, s_vertices)) > 0.5))


if __name__ == "__main__":
    main()
