"""Label maps to surfaces, as a segmentation user meets it: isolab's `mesh_labels` beside VTK's
`vtkSurfaceNets3D`, zmesh and scikit-image's marching cubes per label, on the same numpy label
maps, in one Python process.

Run by the `segmentations` experiment (`segmentations/mod.rs`) in the reference environment
(`tests/reference/.venv`, with `pip install ./python` done by the experiment):

    python bench.py OUT.json [--voronoi 128:64,256:64] [--repeats 5] [--threads 1,2] [--mni nilearn|PATH|none]
        [--save-tissue PATH.nii.gz] [--wide 2] [--max-blocks 3]

Inputs:
- `MNI152 tissue`: the MNI152 T1 template nilearn ships, split by a three-class Otsu threshold
  (scikit-image's `threshold_multiotsu` over the non-zero voxels) into background (0, and the
  zero voxels), darker tissue (1), middle (2) and brighter tissue (3); uint8, Fortran order as
  nibabel gives it.
- `voronoi N:L`: N³ samples, each the label of its nearest of 2L random seeds (seed 7), labels
  0..L-1 (0 is the background), so many triple junctions; uint8 (uint16 above 255 labels), C order.

Implementations (each a function from the label map to one (vertices, faces) pair per label,
in index coordinates, with every conversion inside the timed call; one-shot: a new filter or
mesher each call). Each also reports its meshing step alone, timed inside the call (`core_ms`):
isolab's `extract_ms` (the extraction, timed in Rust, without the per-label meshes and the
conversions), VTK's `Update()`, zmesh's `mesh()`; scikit-image has no such step apart. The rest
of a call is building each label's mesh and handing arrays to Python:
- `isolab surface-nets` (smoothed, the default), `isolab surface-nets unsmoothed`,
  `isolab marching-tetrahedra`: `isolab.mesh_labels`, per-label meshes built by it;
- `isolab lattice-cleaving`: the same call, which also fills every label with tetrahedra (handed
  to Python inside the timed call, then dropped); only on maps of at most `CLEAVING_MAX_SAMPLES`
  samples (it keeps up to thirty tetrahedra a sample where labels fill the map, ten on the tissue map: memory, not time, sets the cap);
- `VTK SurfaceNets3D` (smoothed, its defaults) and `VTK SurfaceNets3D unsmoothed`: the label
  map padded by one sample of background (as pyvista's `contour_labels` does, so labels at the
  border are closed) as vtkImageData (a copy into a VTK array), every label selected,
  triangles; each label's triangles selected from its one output by its `BoundaryLabels`
  pairs, over the output's one point array (ours and zmesh's per-label meshes each have their
  own vertices: a little more work, inside their calls);
- `zmesh`: `zmesh.Mesher((1, 1, 1)).mesh(labels, close=True)` (closed at the border), then
  `get(label)` per label (marching cubes of each label, one pass);
- `skimage per label`: for each label, `skimage.measure.marching_cubes` of the label's
  indicator at 0.5 over its bounding box grown by one sample (what a user scripting it would
  do; the whole map per label would take far longer).
Threads: 1, then 2 for isolab (`threads=2`) and VTK (STDThread backend, `Initialize(2)`); zmesh
and scikit-image have no threads to give.

Protocol: one unrecorded warm-up round, then `repeats` rounds, each implementation once per
round in an order rotated by one each round; while any implementation's calls in the last block
of `repeats` rounds span more than `WIDE` times (slowest over fastest), another block, up to
`MAX_BLOCKS` (each row records its blocks and whether its last block was still wide). After the
timed rounds, the last output of each implementation is checked (untimed), each label's mesh welded first (vertices at one position
made one, unused ones dropped, wound outward): per label, closed (every edge in two triangles), edge-manifold
and vertex-manifold (isolab.metrics), triangle shape (minimum angle, mean radius ratio), and
the interfaces: a triangle of label a that lies on the face between a sample of a and a
face-neighbour sample of another label b (the samples nearest its centroid pushed half a sample
against and along its normal) is an interface triangle, and it should appear, with the same three vertices, in another label's mesh;
those that do not are counted as unmatched (gaps and overlaps between neighbours).

Writes {"versions", "notes", "inputs", "rows": [{"implementation", "input", "threads", "ms",
"core_ms", "labels", "triangles", ...checks}]} to OUT.json.
"""
import argparse
import importlib.metadata
import json
import os
import sys
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
import numpy as np  # noqa: E402

import isolab  # noqa: E402


def version(distribution):
    try:
        return importlib.metadata.version(distribution)
    except importlib.metadata.PackageNotFoundError:
        return "unknown"


versions = {"isolab": version("isolab"), "numpy": np.__version__, "python": sys.version.split()[0]}
notes = []
try:
    from skimage import measure
    versions["scikit-image"] = version("scikit-image")
except ImportError as e:
    measure = None
    notes.append(f"scikit-image not run: {e}")
try:
    import zmesh
    versions["zmesh"] = version("zmesh")
except ImportError as e:
    zmesh = None
    notes.append(f"zmesh not run: {e}")
try:
    import vtk
    from vtk.util import numpy_support
    versions["vtk"] = vtk.vtkVersion.GetVTKVersion()
except ImportError as e:
    vtk = None
    notes.append(f"VTK not run: {e}")


def isolab_impl(algorithm, smoothing):
    def run(seg, labels, threads):
        kwargs = {} if smoothing is None else {"smoothing": smoothing}
        meshes = isolab.mesh_labels(seg, algorithm=algorithm, threads=threads, **kwargs)
        return {label: (m.vertices, m.faces) for label, m in meshes.items()}, meshes.extract_ms
    return run


def vtk_impl(smoothing):
    def run(seg, labels, threads):
        vtk.vtkSMPTools.SetBackend("STDThread" if threads > 1 else "Sequential")
        vtk.vtkSMPTools.Initialize(threads)
        # One sample of background around the map, as pyvista's contour_labels pads it, so
        # labels touching the border are closed there (VTK leaves them open otherwise).
        padded = np.pad(seg, 1)
        image = vtk.vtkImageData()
        image.SetDimensions(*padded.shape)
        image.SetOrigin(-1.0, -1.0, -1.0)
        flat = padded.ravel(order="F")  # VTK's point order is x fastest: numpy's first axis
        image.GetPointData().SetScalars(numpy_support.numpy_to_vtk(flat, deep=True))
        nets = vtk.vtkSurfaceNets3D()
        nets.SetInputData(image)
        for i, label in enumerate(labels):
            nets.SetLabel(i, float(label))
        nets.SetSmoothing(smoothing)
        nets.SetOutputMeshTypeToTriangles()
        start = time.perf_counter()
        nets.Update()
        core_ms = (time.perf_counter() - start) * 1e3
        out = nets.GetOutput()
        points = numpy_support.vtk_to_numpy(out.GetPoints().GetData()).astype(np.float32)
        cells = numpy_support.vtk_to_numpy(out.GetPolys().GetConnectivityArray()).reshape(-1, 3).astype(np.int32)
        pairs = numpy_support.vtk_to_numpy(out.GetCellData().GetArray("BoundaryLabels")).reshape(-1, 2)
        # Each label's triangles (reversed where it is the second of the pair), over the
        # filter's one point array (compacted only for the untimed checks).
        return {label: (points, np.concatenate([cells[pairs[:, 0] == label], cells[pairs[:, 1] == label][:, ::-1]]))
                for label in labels}, core_ms
    return run


def zmesh_impl(seg, labels, threads):
    mesher = zmesh.Mesher((1, 1, 1))
    start = time.perf_counter()
    mesher.mesh(seg, close=True)  # closed where labels touch the border, as the others
    core_ms = (time.perf_counter() - start) * 1e3
    meshes = {}
    for label in mesher.ids():
        m = mesher.get(label, normals=False)
        meshes[int(label)] = (np.asarray(m.vertices, dtype=np.float32), np.asarray(m.faces, dtype=np.int32))
    mesher.clear()
    return meshes, core_ms


def skimage_impl(seg, labels, threads):
    meshes = {}
    for label in labels:
        where = np.nonzero(seg == label)
        lo = np.maximum(np.array([w.min() for w in where]) - 1, 0)
        hi = np.minimum(np.array([w.max() for w in where]) + 2, seg.shape)
        box = (seg[lo[0]:hi[0], lo[1]:hi[1], lo[2]:hi[2]] == label)
        box = np.pad(box, 1).astype(np.float32)  # closed where the label touches the map's border
        v, f, _, _ = measure.marching_cubes(box, 0.5, method="lewiner")
        meshes[label] = ((v + lo - 1).astype(np.float32), f.astype(np.int32))
    return meshes, None


# The report's rule for spreads (experiments/src/report.rs: WIDE, MAX_ROUNDS, which the experiment
# passes as --wide and --max-blocks): a wide block of rounds is followed by another, up to a bound.
WIDE = 2.0
MAX_BLOCKS = 3

# Lattice cleaving's largest map: the MNI152 tissue map (197 x 233 x 189, 8.7M samples) is under
# it; 256³ is not.
CLEAVING_MAX_SAMPLES = 10_000_000


def implementations(threads, samples):
    impls = [("isolab surface-nets", isolab_impl("surface-nets", None)),
             ("isolab surface-nets unsmoothed", isolab_impl("surface-nets", False)),
             ("isolab marching-tetrahedra", isolab_impl("marching-tetrahedra", None))]
    if samples <= CLEAVING_MAX_SAMPLES:
        impls.append(("isolab lattice-cleaving", isolab_impl("lattice-cleaving", None)))
    if vtk is not None:
        impls += [("VTK SurfaceNets3D", vtk_impl(True)), ("VTK SurfaceNets3D unsmoothed", vtk_impl(False))]
    if threads == THREADS[0]:
        if zmesh is not None:
            impls.append(("zmesh", zmesh_impl))
        if measure is not None:
            impls.append(("skimage per label", skimage_impl))
    return impls



def weld(vertices, faces):
    """The mesh with its unused vertices dropped and vertices at one position made one (VTK
    duplicates points where it resolves a non-manifold case): the checks judge the surface, not
    its index bookkeeping."""
    used, remap = np.unique(faces, return_inverse=True)
    unique, back = np.unique(vertices[used], axis=0, return_inverse=True)
    return unique, back.reshape(-1)[remap.reshape(-1)].reshape(-1, 3).astype(np.int32)


def outward(vertices, faces):
    """The mesh wound outward (positive signed volume): implementations differ in convention."""
    p = vertices[faces].astype(np.float64)
    volume = np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6.0
    return (vertices, faces) if volume >= 0 else (vertices, faces[:, ::-1].copy())


def check(seg, meshes):
    """The untimed checks of one output (see the module doc)."""
    meshes = {label: outward(*weld(v, f)) for label, (v, f) in meshes.items() if len(f)}
    labels_closed = labels_manifold = non_manifold = degenerate = 0
    min_angle, rr_sum, rr_n = 180.0, 0.0, 0
    keys = {label: triangle_keys(v, f) for label, (v, f) in meshes.items() if len(f)}
    # How many labels' meshes hold each triangle: an interface triangle shared by its two labels
    # is in two.
    holders = {}
    for label, ks in keys.items():
        for k in set(ks):
            holders[k] = holders.get(k, 0) + 1
    unmatched = interface = 0
    shape = np.array(seg.shape)
    for label, (v, f) in meshes.items():
        if not len(f):
            continue
        m = isolab.metrics(v, f, self_intersections=False)
        labels_closed += bool(m["closed"])
        manifold = m["edge_manifold"] and m["vertex_manifold"]
        labels_manifold += bool(manifold)
        non_manifold += m["non_manifold_edges"] + m["non_manifold_vertices"]
        degenerate += m["degenerate_triangles"]
        min_angle = min(min_angle, m["min_angle_deg"])
        rr_sum += m["radius_ratio"]["mean"] * len(f)
        rr_n += len(f)
        # Interfaces: the label outside each triangle, and whether its mesh has the triangle.
        p = v[f].astype(np.float64)
        n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
        length = np.linalg.norm(n, axis=1)
        ok = length > 0
        unit = n / np.where(ok, length, 1)[:, None]
        centre = p.mean(1)

        def sample_at(points):
            at = np.round(points).astype(np.int64)
            inside_map = (at >= 0).all(1) & (at < shape).all(1)
            clipped = np.clip(at, 0, shape - 1)
            return at, np.where(inside_map, seg[clipped[:, 0], clipped[:, 1], clipped[:, 2]].astype(np.int64), 0)

        # On the face between a sample of this label (half a sample inward) and a face-neighbour
        # sample of another (half a sample outward).
        (out_at, outside), (in_at, inward) = sample_at(centre + 0.5 * unit), sample_at(centre - 0.5 * unit)
        face_neighbours = np.abs(out_at - in_at).sum(1) == 1
        neighbour = ok & face_neighbours & (inward == label) & (outside != 0) & (outside != label)
        for key, is_interface in zip(keys[label], neighbour):
            if is_interface:
                interface += 1
                unmatched += holders.get(key, 0) < 2
    return {"labels_closed": labels_closed, "labels_manifold": labels_manifold, "non_manifold": int(non_manifold),
            "degenerate_triangles": int(degenerate),
            "min_angle_deg": float(min_angle), "mean_radius_ratio": rr_sum / max(rr_n, 1),
            "interface_triangles": int(interface), "unmatched_interface_triangles": int(unmatched)}


def triangle_keys(vertices, faces):
    """Each triangle as the bytes of its three vertices (rounded to 1e-4, sorted), for matching
    triangles across meshes; a list in the faces' order."""
    q = np.round(vertices.astype(np.float64) * 1e4).astype(np.int64)
    tri = q[faces]
    order = np.lexsort((tri[:, :, 2], tri[:, :, 1], tri[:, :, 0]), axis=1) if len(faces) else np.zeros((0, 3), np.int64)
    tri = np.take_along_axis(tri, order[:, :, None], axis=1)
    return [bytes(t) for t in np.ascontiguousarray(tri).reshape(len(faces), 9)]


THREADS = (1, 2)


def time_input(name, seg, repeats, rows):
    labels = [int(l) for l in np.unique(seg) if l != 0]
    if seg.size > CLEAVING_MAX_SAMPLES:
        notes.append(f"isolab lattice-cleaving not run on {name}: {seg.size} samples, above its cap of "
                     f"{CLEAVING_MAX_SAMPLES} (memory: up to thirty tetrahedra a sample)")
    for threads in THREADS:
        impls = implementations(threads, seg.size)
        times = {label: [] for label, _ in impls}
        cores = {label: [] for label, _ in impls}
        last = {}
        # Blocks of `repeats` rounds (after one warm-up round) until no implementation's block is
        # wide (its slowest call over WIDE times its fastest) or MAX_BLOCKS have run; every call kept.
        blocks, wide, r = 0, {label: False for label, _ in impls}, 0
        while True:
            first = len(times[impls[0][0]])
            for _ in range(repeats + (1 if r == 0 else 0)):
                k = r % len(impls)
                for label, fn in impls[k:] + impls[:k]:
                    t = time.perf_counter()
                    out, core_ms = fn(seg, labels, threads)
                    ms = (time.perf_counter() - t) * 1e3
                    if r > 0:
                        times[label].append(ms)
                        if core_ms is not None:
                            cores[label].append(core_ms)
                    last[label] = out
                r += 1
            blocks += 1
            wide = {label: repeats > 1 and max(times[label][first:]) > WIDE * min(times[label][first:])
                    for label, _ in impls}
            if not any(wide.values()) or blocks == MAX_BLOCKS:
                break
        for label, _ in impls:
            out = last[label]
            row = {"implementation": label, "input": name, "threads": threads, "ms": times[label],
                   "core_ms": cores[label] or None, "blocks": blocks, "wide": wide[label],
                   "labels": len([1 for v, f in out.values() if len(f)]),
                   "triangles": int(sum(len(f) for v, f in out.values()))}
            if threads == THREADS[0]:
                row.update(check(seg, out))
            rows.append(row)
            med = sorted(times[label])[len(times[label]) // 2]
            print(f"{name} t{threads} {label}: {med:.1f} ms, {row['triangles']} triangles", file=sys.stderr, flush=True)
        last.clear()


def voronoi(n, labels, seed=7):
    rng = np.random.default_rng(seed)
    seeds = rng.uniform(0, n, (2 * labels, 3))
    from scipy.spatial import cKDTree
    grid = np.stack(np.meshgrid(*[np.arange(n)] * 3, indexing="ij"), axis=-1).reshape(-1, 3)
    _, nearest = cKDTree(seeds).query(grid)
    dtype = np.uint8 if labels <= 256 else np.uint16
    return np.ascontiguousarray((nearest % labels).astype(dtype).reshape(n, n, n))


def mni_tissue(path):
    import nibabel as nib
    from skimage.filters import threshold_multiotsu
    versions["nibabel"] = nib.__version__
    image = nib.load(path)
    t1 = image.get_fdata()
    low, high = threshold_multiotsu(t1[t1 > 0], classes=3)
    seg = np.zeros(t1.shape, np.uint8, order="F")
    seg[(t1 > 0) & (t1 <= low)] = 1
    seg[(t1 > low) & (t1 <= high)] = 2
    seg[t1 > high] = 3
    return seg, [float(low), float(high)], image.affine


def main():
    global THREADS, WIDE, MAX_BLOCKS
    p = argparse.ArgumentParser()
    p.add_argument("out")
    p.add_argument("--voronoi", default="128:64,256:64")
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--threads", default="1,2")
    p.add_argument("--mni", default="nilearn")
    p.add_argument("--save-tissue", default=None, help="write the tissue map here (NIfTI, the template's affine)")
    p.add_argument("--wide", type=float, default=WIDE, help="a block is wide when its slowest call took this many times its fastest")
    p.add_argument("--max-blocks", type=int, default=MAX_BLOCKS, help="blocks of rounds at most")
    a = p.parse_args()
    THREADS = tuple(int(t) for t in a.threads.split(","))
    WIDE, MAX_BLOCKS = a.wide, a.max_blocks
    rows, inputs = [], []
    mni = a.mni
    if mni == "nilearn":
        try:
            import nilearn
            mni = os.path.join(os.path.dirname(nilearn.__file__), "datasets", "data",
                               "mni_icbm152_t1_tal_nlin_sym_09a_converted.nii.gz")
        except ImportError as e:
            notes.append(f"MNI152 tissue map not run: {e}")
            mni = None
    if mni and mni != "none":
        seg, thresholds, affine = mni_tissue(mni)
        if a.save_tissue:
            import nibabel as nib
            nib.save(nib.Nifti1Image(seg, affine), a.save_tissue)
        time_input("MNI152 tissue", seg, a.repeats, rows)
        inputs.append({"input": "MNI152 tissue", "shape": list(seg.shape), "dtype": str(seg.dtype), "order": "F",
                       "labels": 3, "thresholds": thresholds,
                       "counts": {str(int(k)): int(c) for k, c in zip(*np.unique(seg, return_counts=True))}})
    for spec in a.voronoi.split(","):
        n, labels = (int(x) for x in spec.split(":"))
        seg = voronoi(n, labels)
        name = f"voronoi {n}³, {labels - 1} labels"
        time_input(name, seg, a.repeats, rows)
        inputs.append({"input": name, "shape": list(seg.shape), "dtype": str(seg.dtype), "order": "C",
                       "labels": labels - 1})
    with open(a.out + ".tmp", "w") as f:
        json.dump({"versions": versions, "notes": notes, "inputs": inputs, "rows": rows}, f)
    os.replace(a.out + ".tmp", a.out)


if __name__ == "__main__":
    main()
