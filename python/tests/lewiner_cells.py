"""Classifies every cell where isolab's marching cubes 33 (`isolab.marching_cubes(method='lewiner')`)
and scikit-image's Lewiner differ, by a named reason: the rules of
`test_marching_cubes_33.py` (read its docstring), kept here so that the `real_volumes`
experiment publishes the same counts for the scans of the report.

`named_differences(vol, level)` returns the counts (and "same", "same, with a centre") and the
cells no rule names (each with its corner values), which the test requires to be none.
"""

from collections import Counter

import numpy as np
from scipy.spatial import cKDTree
from skimage import measure

import isolab

LEWINER_ERRS, CRITICAL = "scikit-image's Lewiner misses the interpolant's topology", "near a critical value"
TUBE_RETILED = "a tube ours draws otherwise so that it does not cross itself"


def spread(vol):
    """Every cell of `vol` as its own 2 x 2 x 2 block of a volume twice the size, and the mask
    (read at a cell's highest corner, as both libraries read it) that keeps only the blocks."""
    n = [s - 1 for s in vol.shape]
    out = np.zeros([2 * s for s in n], dtype=vol.dtype)
    for di in range(2):
        for dj in range(2):
            for dk in range(2):
                out[di::2, dj::2, dk::2] = vol[di:di + n[0], dj:dj + n[1], dk:dk + n[2]]
    mask = np.zeros(out.shape, dtype=bool)
    mask[1::2, 1::2, 1::2] = True
    return out, mask


def per_cell(verts, faces):
    """Triangles by cell of the spread volume: {cell index (i, j, k): faces}."""
    cell = np.floor(verts[faces].astype(np.float64).mean(axis=1) / 2).astype(np.int64)
    out = {}
    for key, t in zip(map(tuple, cell), faces):
        out.setdefault(key, []).append(t)
    return {k: np.array(v) for k, v in out.items()}


def inside_a_cell(verts):
    """Vertices on no lattice edge (at most one integer coordinate is not allowed)."""
    off = np.abs(verts - np.round(verts)) > 1e-6
    return off.sum(axis=1) >= 2


def shape(faces):
    """Sorted Euler characteristics of the connected components (a disc 1, a tube 0)."""
    parent = {int(v): int(v) for v in np.unique(faces)}

    def find(v):
        while parent[v] != v:
            parent[v] = parent[parent[v]]
            v = parent[v]
        return v
    for a, b, c in faces:
        for x, y in ((a, b), (b, c)):
            parent[find(int(x))] = find(int(y))
    chi = Counter()
    for v in parent:
        chi[find(v)] += 1
    edges = {tuple(sorted((int(t[i]), int(t[(i + 1) % 3])))) for t in faces for i in range(3)}
    for e in edges:
        chi[find(e[0])] -= 1
    for t in faces:
        chi[find(int(t[0]))] += 1
    return tuple(sorted(chi.values()))


def interpolant_shape(g, level, n):
    """The shape of the trilinear interpolant's level set in the unit cell with corner values
    g[i, j, k], sampled n times per side."""
    t = np.linspace(0.0, 1.0, n)
    x, y, z = np.meshgrid(t, t, t, indexing="ij")
    w = [(1 - x, x), (1 - y, y), (1 - z, z)]
    s = sum(g[i, j, k] * w[0][i] * w[1][j] * w[2][k] for i in range(2) for j in range(2) for k in range(2))
    _, f, _, _ = measure.marching_cubes(s, level, method="lorensen")
    return shape(f)


def judged_shape(g, level):
    """The interpolant's shape, or None within a hair of a critical value."""
    at = interpolant_shape(g, level, 33)
    d = 2e-3 * np.abs(g - level).max()
    stable = all(interpolant_shape(g, level + e, n) == at for e, n in ((d, 33), (-d, 33), (0.0, 65)))
    return at if stable else None


def self_intersecting_pairs(verts, faces):
    used, local = np.unique(faces, return_inverse=True)
    return isolab.metrics(verts[used], local.reshape(-1, 3).astype(np.int32))["self_intersections"]["count"]


def named_differences(vol, level):
    """Compares every cell; returns the count of each named difference and of equal cells, and
    the cells no rule names; checks the vertices: the same points on the lattice edges."""
    # One memory order for the volume and its spread copy: at an exact critical value (integer
    # data can hit one) the axis order may decide the tie.
    vol = np.ascontiguousarray(vol, dtype=np.float32)
    big, mask = spread(vol)
    sv, sf, _, _ = measure.marching_cubes(big, level, method="lewiner", mask=mask)
    ov, of, _, _ = isolab.marching_cubes(big, level, method="lewiner", mask=mask)
    # The spread cells add up to the whole volume's mesh.
    whole_s = measure.marching_cubes(vol, level, method="lewiner")[1]
    whole_o = isolab.marching_cubes(vol, level, method="lewiner")[1]
    assert (len(sf), len(of)) == (len(whole_s), len(whole_o))
    s_centre, o_centre = inside_a_cell(sv), inside_a_cell(ov)
    edge_s, edge_o = sv[~s_centre], ov[~o_centre]
    assert len(edge_s) == len(edge_o)
    assert cKDTree(edge_s).query(edge_o)[0].max() < 1e-4
    scells, ocells = per_cell(sv, sf), per_cell(ov, of)
    counts, unnamed = Counter(), []
    for key in set(scells) | set(ocells):
        st, ot = scells.get(key, np.zeros((0, 3), int)), ocells.get(key, np.zeros((0, 3), int))
        sc, oc = sv[np.unique(st)][s_centre[np.unique(st)]], ov[np.unique(ot)][o_centre[np.unique(ot)]]
        # Lewiner's weighted centre, which ours keeps a thousandth of the cell inside its faces.
        base = 2 * np.array(key, dtype=np.float64)
        kept = base + np.clip(sc - base, 1e-3, 1 - 1e-3)
        same_centre = len(sc) == 0 or (len(sc) == len(oc) and np.abs(kept - oc).max() < 1e-4)
        if len(st) == len(ot) and len(sc) == len(oc) and same_centre:
            counts["same"] += 1
            if len(sc):
                counts["same, with a centre"] += 1
            continue
        i, j, k = key
        g = vol[i:i + 2, j:j + 2, k:k + 2].astype(np.float64)
        truth = judged_shape(g, level)
        if truth is None:
            counts[CRITICAL] += 1
        elif shape(ot) == truth != shape(st):
            counts[LEWINER_ERRS] += 1
        elif shape(ot) == truth == shape(st) and 0 in truth and len(oc) and self_intersecting_pairs(ov, ot) == 0:
            counts[TUBE_RETILED] += 1
        else:
            unnamed.append(f"cell {key} (corner values {g.ravel().tolist()}, level {level}): ours {len(ot)} triangles "
                           f"{shape(ot)}, scikit-image's {len(st)} {shape(st)}, the interpolant's {truth}")
    return counts, unnamed


