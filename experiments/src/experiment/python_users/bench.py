"""Marching cubes as a Python user meets it: isolab's Python package beside scikit-image,
PyMCubes, zmesh and VTK's flying edges, on the same numpy arrays, in one Python process.

Run by the `python_users` experiment (`python_users/mod.rs`) in the reference environment
(`tests/reference/.venv`, with `pip install ./python` done by the experiment):

    python bench.py OUT.json [--sizes 64,128,256,512] [--repeats 7] [--large-repeats 3] [--mni PATH|nilearn]
        [--large-size 512] [--threads 1,2] [--environment LABEL]

`--environment` labels the rows with how the process was started (the experiment runs the script
a second time with glibc's malloc asking for transparent huge pages, `GLIBC_TUNABLES=glibc.malloc.hugetlb=1`).

Protocol, per input and per thread count (1, then 2):
- every implementation is a function from the user's array (and the level) to numpy vertex and
  face arrays, with whatever conversion it needs on either side inside the timed call: a first
  library call per call (one-shot: a new VTK filter, a new zmesh Mesher, nothing kept);
- one unrecorded warm-up round, then `repeats` rounds; in each round every implementation runs
  once, in an order rotated by one each round (alternating, so drift on this shared machine falls
  on all of them alike);
- 2 threads: isolab (`threads=2`) and VTK (the STDThread SMP backend, `Initialize(2)`); the
  others have no threads to give, so they run in the one-thread rounds only.

Inputs: the gyroid `sin x cos y + sin y cos z + sin z cos x` (three periods across the cube,
sampled at the centres of n samples per side, float32 C order, level 0) at each size, and the MNI152
T1 template nilearn ships, as `nibabel.load(path).get_fdata()` gives it (float64, Fortran order:
every implementation converts it as it must) at the level `isolab.extract` picks for the file.

Writes {"versions": {...}, "notes": [...], "rows": [{"implementation", "input", "n", "threads",
"ms": [...], "vertices", "triangles", "converts"}]} to OUT.json.
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
    import skimage
    from skimage import measure
    versions["scikit-image"] = version("scikit-image")
except ImportError as e:
    notes.append(f"scikit-image not run: {e}")
    measure = None
try:
    import mcubes
    versions["PyMCubes"] = version("PyMCubes")
except ImportError as e:
    notes.append(f"PyMCubes not run: {e}")
    mcubes = None
try:
    import zmesh
    versions["zmesh"] = version("zmesh")
except ImportError as e:
    notes.append(f"zmesh not run: {e}")
    zmesh = None
try:
    import vtk
    from vtk.util import numpy_support
    versions["VTK"] = version("vtk")
except ImportError as e:
    notes.append(f"VTK not run: {e}")
    vtk = None


# What each side converts, as the report states it.
CONVERTS = {
    "isolab lorensen": "reads the array in place into its float32 samples (one copy); returns arrays over its own buffers",
    "isolab lewiner": "as isolab lorensen",
    "skimage lorensen": "np.asarray(float32), C-contiguous copy when the array is not; returns its arrays",
    "skimage lewiner": "as skimage lorensen",
    "PyMCubes": "its C++ reads float64 (astype when the array is not); vertices float64, faces uint64",
    "zmesh": "thresholds the array into a uint8 label volume (timed); meshes that binary volume",
    "VTK flying edges": "numpy_to_vtk over the array's own buffer (no copy for C or Fortran order), a vtkImageData; "
                        "points and connectivity back with vtk_to_numpy (views)",
}


def isolab_mc(method):
    def run(vol, level, threads):
        v, f, _, _ = isolab.marching_cubes(vol, level, method=method, threads=threads)
        return v, f
    return run


def skimage_mc(method):
    def run(vol, level, threads):
        v, f, _, _ = measure.marching_cubes(vol, level, method=method)
        return v, f
    return run


def pymcubes(vol, level, threads):
    return mcubes.marching_cubes(np.asarray(vol, dtype=np.float64), level)


def zmesh_binary(vol, level, threads):
    labels = (vol > level).view(np.uint8)
    mesher = zmesh.Mesher((1, 1, 1))
    mesher.mesh(labels, close=True)
    mesh = mesher.get(1, normals=False)
    return mesh.vertices, mesh.faces


def vtk_flying_edges(vol, level, threads):
    vtk.vtkSMPTools.SetBackend("STDThread" if threads > 1 else "Sequential")
    vtk.vtkSMPTools.Initialize(threads)
    # VTK's x runs fastest: a C-ordered array is handed over as it lies, its axes reversed (no
    # copy), and its vertices' columns reversed back (a view); any other array as Fortran.
    c_order = vol.flags.c_contiguous
    img = vtk.vtkImageData()
    img.SetDimensions(*(vol.shape[::-1] if c_order else vol.shape))
    img.GetPointData().SetScalars(numpy_support.numpy_to_vtk(vol.ravel(order="C" if c_order else "F"), deep=False))
    f = vtk.vtkFlyingEdges3D()
    f.SetInputData(img)
    f.SetValue(0, level)
    f.ComputeNormalsOn()
    f.ComputeGradientsOff()
    f.ComputeScalarsOff()
    f.Update()
    out = f.GetOutput()
    if out.GetNumberOfPoints() == 0:
        return np.zeros((0, 3), np.float32), np.zeros((0, 3), np.int64)
    v = numpy_support.vtk_to_numpy(out.GetPoints().GetData())
    if c_order:
        v = v[:, ::-1]
    faces = numpy_support.vtk_to_numpy(out.GetPolys().GetConnectivityArray()).reshape(-1, 3)
    return v, faces


def implementations(threads):
    impls = [("isolab lorensen", isolab_mc("lorensen")), ("isolab lewiner", isolab_mc("lewiner"))]
    if threads == THREADS[0]:
        if measure is not None:
            impls += [("skimage lorensen", skimage_mc("lorensen")), ("skimage lewiner", skimage_mc("lewiner"))]
        if mcubes is not None:
            impls.append(("PyMCubes", pymcubes))
        if zmesh is not None:
            impls.append(("zmesh", zmesh_binary))
    if vtk is not None:
        impls.append(("VTK flying edges", vtk_flying_edges))
    return impls


def gyroid(n):
    t = (np.arange(n, dtype=np.float64) + 0.5) * (3 * 2 * np.pi / n)
    x, y, z = t[:, None, None], t[None, :, None], t[None, None, :]
    g = np.sin(x) * np.cos(y) + np.sin(y) * np.cos(z) + np.sin(z) * np.cos(x)
    return np.ascontiguousarray(g, dtype=np.float32)


THREADS = (1, 2)


def time_input(name, n, vol, level, repeats, rows, environment):
    for threads in THREADS:
        impls = implementations(threads)
        times = {label: [] for label, _ in impls}
        counts = {}
        for r in range(repeats + 1):
            k = r % len(impls)
            for label, fn in impls[k:] + impls[:k]:
                t = time.perf_counter()
                v, f = fn(vol, level, threads)
                ms = (time.perf_counter() - t) * 1e3
                counts[label] = (len(v), len(f))
                del v, f
                if r > 0:
                    times[label].append(ms)
        for label, _ in impls:
            rows.append({"implementation": label, "input": name, "n": n, "threads": threads, "environment": environment,
                         "ms": times[label],
                         "vertices": counts[label][0], "triangles": counts[label][1], "converts": CONVERTS[label]})
            med = sorted(times[label])[len(times[label]) // 2]
            print(f"{environment}: {name} {n} t{threads} {label}: {med:.1f} ms, {counts[label][1]} triangles", file=sys.stderr, flush=True)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("out")
    p.add_argument("--sizes", default="64,128,256,512")
    p.add_argument("--repeats", type=int, default=7)
    p.add_argument("--large-repeats", type=int, default=3)
    p.add_argument("--large-size", type=int, default=512)
    p.add_argument("--threads", default="1,2", help="thread counts: the first is one thread, the others the threaded peers'")
    p.add_argument("--mni", default=None)
    p.add_argument("--environment", default="default")
    a = p.parse_args()
    global THREADS
    THREADS = tuple(int(t) for t in a.threads.split(","))
    rows = []
    inputs = []
    for n in (int(s) for s in a.sizes.split(",")):
        time_input("gyroid", n, gyroid(n), 0.0, a.repeats if n < a.large_size else a.large_repeats, rows, a.environment)
        inputs.append({"input": "gyroid", "n": n, "dtype": "float32", "order": "C", "shape": [n, n, n], "level": 0.0})
    mni = a.mni
    if mni == "nilearn":
        try:
            import nilearn
            mni = os.path.join(os.path.dirname(nilearn.__file__), "datasets", "data",
                               "mni_icbm152_t1_tal_nlin_sym_09a_converted.nii.gz")
        except ImportError as e:
            notes.append(f"MNI152 T1 not run: {e}")
            mni = None
    if mni:
        import nibabel as nib
        versions["nibabel"] = nib.__version__
        vol = nib.load(mni).get_fdata()
        level = float(isolab.extract(mni).stats["iso"])
        order = "F" if vol.flags.f_contiguous else "C"
        time_input("MNI152 T1", max(vol.shape), vol, level, a.repeats, rows, a.environment)
        inputs.append({"input": "MNI152 T1", "n": max(vol.shape), "dtype": str(vol.dtype), "order": order,
                       "shape": list(vol.shape), "level": level})
    with open(a.out + ".tmp", "w") as f:
        json.dump({"versions": versions, "notes": notes, "inputs": inputs, "rows": rows}, f)
    os.replace(a.out + ".tmp", a.out)


if __name__ == "__main__":
    main()
