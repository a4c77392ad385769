"""Marching cubes as a Python user meets it: isolab's Python package beside scikit-image,
PyMCubes, zmesh, VTK's flying edges (directly and through pyvista), libigl, warp-lang on the CPU,
meshlib and marching-cubes-numpy, on the same numpy arrays, in one Python process.

Run by the `python_users` experiment (`python_users/mod.rs`) in the reference environment
(`tests/reference/.venv`, with `pip install ./python` done by the experiment):

    python bench.py OUT.json [--sizes 64,128,256,512] [--repeats 7] [--large-repeats 3] [--mni nilearn]
        [--large-size 512] [--threads 1,2] [--uint8 512] [--peak] [--only NAME,NAME] [--environment LABEL]
        [--wide 2] [--max-blocks 3]

`--environment` labels the rows with how the process was started (the experiment runs the script
a second time with glibc's malloc asking for transparent huge pages, `GLIBC_TUNABLES=glibc.malloc.hugetlb=1`).

Protocol, per input and per thread count (1, then 2):
- every implementation is a function from the user's array (and the level) to numpy vertex and
  face arrays, with whatever conversion it needs on either side inside the timed call: a first
  library call per call (one-shot: a new VTK filter, a new zmesh Mesher, nothing kept), except
  libigl's grid of sample positions, which its call takes as an argument and is built once per
  input outside the timed call (and not at all from 512³ on: 3 GiB of float64);
- one unrecorded warm-up round, then `repeats` rounds; in each round every implementation runs
  once, in an order rotated by one each round (alternating, so drift on this shared machine falls
  on all of them alike); while any implementation's block of rounds is wide (its slowest call over
  `--wide` times its fastest), another block, up to `--max-blocks` (each row records its blocks and
  whether its last block was still wide);
- 2 threads: isolab (`threads=2`), VTK and pyvista (the STDThread SMP backend, `Initialize(2)`) and
  meshlib (TBB, which takes every core and offers no setting: it runs in these rounds only, in
  rounds of its own after the others', since TBB's workers keep spinning after a call and would
  take the cores from whatever ran next); the others have no threads to give, so they run in the
  one-thread rounds only.

Peak memory (`--peak`): each implementation on each input in a fresh process of its own (this
script, `--measure-peak`), after a warm-up call on a small array of the input's dtype: the
process's resident high-water mark during one call (reset through `/proc/self/clear_refs`) above
its resident memory before the call, which holds the input; and the bytes of the arrays returned.

Inputs: the gyroid `sin x cos y + sin y cos z + sin z cos x` (three periods across the cube,
sampled at the centres of n samples per side, float32, C order, level 0) at each size; the same
gyroid as uint8 at `--uint8` n (rounded from 0 to 255 across -1.5..1.5, level 127.5); and the
MNI152 T1 template nilearn ships, both as nibabel hands it over (`get_fdata()`: float64, Fortran
order) and in its stored type (`np.asanyarray(img.dataobj)`: uint8, Fortran order), at the level
`isolab.extract` picks for the file.

Writes {"versions", "notes", "inputs", "rows": [{"implementation", "input", "n", "threads", "ms": [...],
"vertices", "triangles", "converts", "returns"}], "peaks": [{"implementation", "input", "n",
"peak_bytes", "output_bytes", "input_bytes"}], "floors": [{"input", "n", "output_bytes", "read_ms", "write_ms",
"first_touch_write_ms"}]} to OUT.json (the floor: one read of the array and one write of isolab's output).
"""
import argparse
import gc
import importlib.metadata
import json
import os
import subprocess
import sys
import tempfile
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


def optional(module, distribution, label):
    """Imports a peer; a missing one is a note, not a failure."""
    try:
        m = __import__(module, fromlist=["_"])
        versions[label] = version(distribution)
        return m
    except Exception as e:  # noqa: BLE001 (any import failure leaves the peer out, said in the notes)
        notes.append(f"{label} not run: {e}")
        return None


measure = optional("skimage.measure", "scikit-image", "scikit-image")
mcubes = optional("mcubes", "PyMCubes", "PyMCubes")
zmesh = optional("zmesh", "zmesh", "zmesh")
vtk = optional("vtk", "vtk", "VTK")
numpy_support = optional("vtk.util.numpy_support", "vtk", "VTK") if vtk is not None else None
pv = optional("pyvista", "pyvista", "pyvista")
igl = optional("igl", "libigl", "libigl")
wp = optional("warp", "warp-lang", "warp-lang")
if wp is not None:
    try:
        import warp.geometry  # noqa: F401
        wp.config.quiet = True
        wp.init()
    except Exception as e:  # noqa: BLE001
        notes.append(f"warp-lang not run: {e}")
        wp = None
mr = optional("meshlib.mrmeshpy", "meshlib", "meshlib")
mrn = optional("meshlib.mrmeshnumpy", "meshlib", "meshlib") if mr is not None else None
mcn = optional("marching_cubes", "marching-cubes-numpy", "marching-cubes-numpy")


# Each implementation returns the arrays its call gives (vertices and faces first).

def isolab_mc(method):
    def run(vol, level, threads):
        return isolab.marching_cubes(vol, level, method=method, threads=threads)
    return run


def skimage_mc(method):
    def run(vol, level, threads):
        return measure.marching_cubes(vol, level, method=method)
    return run


def pymcubes(vol, level, threads):
    return mcubes.marching_cubes(np.asarray(vol, dtype=np.float64), level)


def zmesh_binary(vol, level, threads):
    labels = (vol > level).view(np.uint8)
    mesher = zmesh.Mesher((1, 1, 1))
    mesher.mesh(labels, close=True)
    mesh = mesher.get(1, normals=False)
    return mesh.vertices, mesh.faces


def vtk_image(vol):
    """The array as a vtkImageData over its own buffer: VTK's x runs fastest, so a C-ordered array
    is handed over as it lies with its axes reversed, a Fortran one as given; any other is copied
    into Fortran order first."""
    c_order = vol.flags.c_contiguous
    img = vtk.vtkImageData()
    img.SetDimensions(*(vol.shape[::-1] if c_order else vol.shape))
    img.GetPointData().SetScalars(numpy_support.numpy_to_vtk(vol.ravel(order="C" if c_order else "F"), deep=False))
    return img, c_order


def vtk_threads(threads):
    vtk.vtkSMPTools.SetBackend("STDThread" if threads > 1 else "Sequential")
    vtk.vtkSMPTools.Initialize(threads)


def vtk_flying_edges(normals):
    def run(vol, level, threads):
        vtk_threads(threads)
        img, c_order = vtk_image(vol)
        f = vtk.vtkFlyingEdges3D()
        f.SetInputData(img)
        f.SetValue(0, level)
        f.SetComputeNormals(normals)
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
        if normals:
            return v, faces, numpy_support.vtk_to_numpy(out.GetPointData().GetNormals())
        return v, faces
    return run


def pyvista_contour(vol, level, threads):
    vtk_threads(threads)
    grid = pv.wrap(vol)
    mesh = grid.contour([level], method="flying_edges", compute_scalars=False)
    return mesh.points, mesh.faces.reshape(-1, 4)[:, 1:]


_igl_grids = {}


def igl_grid(shape):
    """libigl's positions of the samples (x fastest over the array's axes reversed, as a C-ordered
    array lies), built once per shape outside the timed call."""
    if shape not in _igl_grids:
        nz, ny, nx = shape
        r = np.arange(nx * ny * nz)
        _igl_grids[shape] = np.stack([r % nx, r // nx % ny, r // (nx * ny)], axis=1).astype(np.float64)
    return _igl_grids[shape]


def libigl(vol, level, threads):
    nz, ny, nx = vol.shape
    s = np.ascontiguousarray(vol, dtype=np.float64).ravel()
    v, f = igl.marching_cubes(s, igl_grid(vol.shape), nx, ny, nz, level)[:2]
    return v, f


def warp_mc(vol, level, threads):
    field = wp.array(np.ascontiguousarray(vol, dtype=np.float32), dtype=wp.float32, device="cpu")
    v, i = wp.geometry.IsoSurfaceMarchingCubes.extract(field, float(level))
    return v.numpy(), i.numpy().reshape(-1, 3)


def meshlib_mc(vol, level, threads):
    volume = mrn.simpleVolumeFrom3Darray(np.ascontiguousarray(vol, dtype=np.float32))
    params = mr.MarchingCubesParams()
    params.iso = float(level)
    mesh = mr.marchingCubes(volume, params)
    return mrn.getNumpyVerts(mesh), mrn.getNumpyFaces(mesh.topology)


def numpy_mc(vol, level, threads):
    return mcn.marching_cubes(vol, level)


# name: (function, threads it runs on: "one", "both" or "many", what it returns, what it converts)
IMPLEMENTATIONS = {
    "isolab lorensen": (isolab_mc("lorensen"), "both", "vertices, faces, normals, values",
                        "none: reads the array where it lies, in its own dtype and memory order; writes the four arrays once"),
    "isolab lewiner": (isolab_mc("lewiner"), "both", "vertices, faces, normals, values", "as isolab lorensen"),
    "skimage lorensen": (skimage_mc("lorensen"), "one", "vertices, faces, normals, values",
                         "np.ascontiguousarray(float32): a C-ordered float32 copy unless the array is one"),
    "skimage lewiner": (skimage_mc("lewiner"), "one", "vertices, faces, normals, values", "as skimage lorensen"),
    "PyMCubes": (pymcubes, "one", "vertices (float64), faces (uint64)", "its C++ reads float64 (astype when the array is not)"),
    "zmesh": (zmesh_binary, "one", "vertices, faces", "thresholds the array into a uint8 label volume (timed); meshes that binary volume"),
    "VTK flying edges": (vtk_flying_edges(False), "both", "vertices, faces",
                         "numpy_to_vtk over the array's own buffer (no copy for C or Fortran order, any dtype); vertices and "
                         "connectivity back as views"),
    "VTK flying edges + normals": (vtk_flying_edges(True), "both", "vertices, faces, normals", "as VTK flying edges"),
    "pyvista contour": (pyvista_contour, "both", "vertices, faces",
                        "pyvista.wrap copies the array into Fortran order; faces unpacked from VTK's cell array"),
    "libigl": (libigl, "one", "vertices (float64), faces (int64)",
               "a float64 C-ordered copy of the values; its n³ x 3 float64 position grid is built outside the timed call"),
    "warp-lang (CPU)": (warp_mc, "one", "vertices, faces", "a float32 C-ordered copy into a warp array; vertices and indices copied back"),
    "meshlib": (meshlib_mc, "many", "vertices, faces", "simpleVolumeFrom3Darray copies the values into its float volume"),
    "marching-cubes-numpy": (numpy_mc, "one", "vertices (float64), faces", "np.ascontiguousarray; whole-array numpy passes"),
}

AVAILABLE = {
    "skimage lorensen": measure, "skimage lewiner": measure, "PyMCubes": mcubes, "zmesh": zmesh, "VTK flying edges": vtk,
    "VTK flying edges + normals": vtk, "pyvista contour": pv, "libigl": igl, "warp-lang (CPU)": wp, "meshlib": mr,
    "marching-cubes-numpy": mcn,
}


def implementations(threads, one, only, n):
    out = []
    for name, (fn, runs_on, _, _) in IMPLEMENTATIONS.items():
        if only and name not in only:
            continue
        if name in AVAILABLE and AVAILABLE[name] is None:
            continue
        if name == "libigl" and n >= 512:
            continue
        if (runs_on == "one" and threads != one) or (runs_on == "many" and threads == one):
            continue
        out.append((name, fn))
    return out


def gyroid(n):
    t = (np.arange(n, dtype=np.float64) + 0.5) * (3 * 2 * np.pi / n)
    x, y, z = t[:, None, None], t[None, :, None], t[None, None, :]
    g = np.sin(x) * np.cos(y) + np.sin(y) * np.cos(z) + np.sin(z) * np.cos(x)
    return np.ascontiguousarray(g, dtype=np.float32)


def gyroid_uint8(n):
    g = gyroid(n)
    return np.clip(np.rint((g + 1.5) * (255 / 3.0)), 0, 255).astype(np.uint8)


def mni_path():
    import nilearn
    return os.path.join(os.path.dirname(nilearn.__file__), "datasets", "data",
                        "mni_icbm152_t1_tal_nlin_sym_09a_converted.nii.gz")


THREADS = (1, 2)


# The report's rule for spreads (experiments/src/report.rs: WIDE, MAX_ROUNDS, which the experiment
# passes as --wide and --max-blocks): a wide block of rounds is followed by another, up to a bound.
WIDE = 2.0
MAX_BLOCKS = 3


def rounds(impls, vol, level, threads, repeats, times, counts, blocks):
    """One warm-up round, then blocks of `repeats` rounds, each implementation once a round, in an
    order rotated by one each round, until no implementation's block is wide (its slowest call
    over WIDE times its fastest) or MAX_BLOCKS have run; every call kept. `blocks` receives each
    implementation's (blocks run, whether its last block was still wide)."""
    r, run = 0, 0
    while True:
        first = {label: len(times[label]) for label, _ in impls}
        for _ in range(repeats + (1 if r == 0 else 0)):
            k = r % len(impls)
            for label, fn in impls[k:] + impls[:k]:
                t = time.perf_counter()
                out = fn(vol, level, threads)
                ms = (time.perf_counter() - t) * 1e3
                counts[label] = (len(out[0]), len(out[1]))
                del out
                if r > 0:
                    times[label].append(ms)
            r += 1
        run += 1
        wide = {label: repeats > 1 and max(times[label][first[label]:]) > WIDE * min(times[label][first[label]:])
                for label, _ in impls}
        if not any(wide.values()) or run == MAX_BLOCKS:
            break
    for label, _ in impls:
        blocks[label] = (run, wide[label])


def time_input(name, n, vol, level, repeats, rows, environment, only, floors):
    for threads in THREADS:
        impls = implementations(threads, THREADS[0], only, n)
        times = {label: [] for label, _ in impls}
        counts, blocks = {}, {}
        # What takes every core (TBB's workers keep spinning after a call, taking the cores from
        # whatever runs next) is timed in rounds of its own after the others'.
        alone = [i for i in impls if IMPLEMENTATIONS[i[0]][1] == "many"]
        shared = [i for i in impls if i not in alone]
        rounds(shared, vol, level, threads, repeats, times, counts, blocks)
        for one in alone:
            rounds([one], vol, level, threads, repeats, times, counts, blocks)
        for label, _ in impls:
            _, _, returns, converts = IMPLEMENTATIONS[label]
            rows.append({"implementation": label, "input": name, "n": n, "threads": threads, "environment": environment,
                         "ms": times[label], "vertices": counts[label][0], "triangles": counts[label][1],
                         "converts": converts, "returns": returns,
                         "blocks": blocks[label][0], "wide": blocks[label][1]})
            med = sorted(times[label])[len(times[label]) // 2]
            print(f"{environment}: {name} {n} t{threads} {label}: {med:.1f} ms, {counts[label][1]} triangles",
                  file=sys.stderr, flush=True)
    if "isolab lorensen" in counts:
        vertices, triangles = counts["isolab lorensen"]
        # isolab's four arrays: float32 vertices and normals, float32 values, int32 faces.
        output_bytes = vertices * 28 + triangles * 12
        floors.append({"input": name, "n": n, "output_bytes": output_bytes, **floor(vol, output_bytes)})


def floor(vol, output_bytes, repeats=5):
    """The memory floor of a call on `vol` making `output_bytes`: one read of the array (a
    bitwise-or reduction over its memory, which numpy runs at memory speed) and one write of the
    output into memory touched before, and that write into fresh memory (its page faults
    included); medians of `repeats`, ms."""
    flat = np.ravel(vol, order="K")
    words = flat.view(np.uint64) if flat.nbytes % 8 == 0 else flat.view(np.uint8)
    def median(fn):
        ts = []
        for _ in range(repeats):
            t = time.perf_counter()
            fn()
            ts.append((time.perf_counter() - t) * 1e3)
        return sorted(ts)[len(ts) // 2]
    read = median(lambda: np.bitwise_or.reduce(words))
    touched = np.empty(output_bytes, np.uint8)
    touched.fill(2)
    write = median(lambda: touched.fill(1))
    del touched
    fresh = median(lambda: np.empty(output_bytes, np.uint8).fill(1))
    return {"read_ms": read, "write_ms": write, "first_touch_write_ms": fresh}


def rss_and_peak():
    """(VmRSS, VmHWM) of this process, bytes."""
    fields = {}
    with open("/proc/self/status") as f:
        for line in f:
            key, _, value = line.partition(":")
            if key in ("VmRSS", "VmHWM"):
                fields[key] = int(value.split()[0]) * 1024
    return fields["VmRSS"], fields["VmHWM"]


def measure_peak(name, path, level, threads):
    """Child mode: one call of `name` on the array in `path`; prints its peak above the input."""
    vol = np.load(path)
    fn = IMPLEMENTATIONS[name][0]
    # A warm-up on the middle of the volume, in its dtype and order, loads, compiles and pools
    # what the implementation keeps between calls.
    m = [s // 2 for s in vol.shape]
    small = vol[m[0] - 12:m[0] + 12, m[1] - 12:m[1] + 12, m[2] - 12:m[2] + 12]
    small = np.ascontiguousarray(small) if vol.flags.c_contiguous else np.asfortranarray(small)
    try:
        fn(small, level, threads)
    except (RuntimeError, ValueError):
        pass  # no surface in the middle: nothing was warmed, the call below does it
    gc.collect()
    before, _ = rss_and_peak()
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")
    out = fn(vol, level, threads)
    _, peak = rss_and_peak()
    print(json.dumps({"peak_bytes": peak - before, "output_bytes": int(sum(np.asarray(a).nbytes for a in out)),
                      "input_bytes": int(vol.nbytes)}))


def peaks(inputs, only):
    """Every implementation on every input in a process of its own: their peaks."""
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for name, n, vol, level in inputs:
            path = os.path.join(tmp, f"{name.replace(' ', '_')}_{n}.npy")
            np.save(path, vol)
            for label, _ in implementations(THREADS[0], THREADS[0], only, n):
                cmd = [sys.executable, __file__, "-", "--measure-peak", label, path, repr(float(level)), str(THREADS[0])]
                done = subprocess.run(cmd, capture_output=True, text=True)
                if done.returncode != 0:
                    notes.append(f"peak of {label} on {name} {n} not measured: {done.stderr.strip()[-300:]}")
                    continue
                m = json.loads(done.stdout.strip().splitlines()[-1])
                out.append({"implementation": label, "input": name, "n": n, **m})
                print(f"peak: {name} {n} {label}: {m['peak_bytes'] >> 20} MiB above the input, output {m['output_bytes'] >> 20} MiB",
                      file=sys.stderr, flush=True)
    return out


def main():
    global THREADS, WIDE, MAX_BLOCKS
    p = argparse.ArgumentParser()
    p.add_argument("out")
    p.add_argument("--sizes", default="64,128,256,512")
    p.add_argument("--repeats", type=int, default=7)
    p.add_argument("--large-repeats", type=int, default=3)
    p.add_argument("--large-size", type=int, default=512)
    p.add_argument("--threads", default="1,2", help="thread counts: the first is one thread, the others the threaded peers'")
    p.add_argument("--mni", default=None)
    p.add_argument("--uint8", type=int, default=0, help="the size of the uint8 gyroid (0: none)")
    p.add_argument("--peak", action="store_true", help="also measure each call's peak memory, a process each")
    p.add_argument("--only", default="", help="comma-separated implementations (default: all)")
    p.add_argument("--environment", default="default")
    p.add_argument("--measure-peak", nargs=4, metavar=("NAME", "NPY", "LEVEL", "THREADS"))
    p.add_argument("--wide", type=float, default=WIDE, help="a block is wide when its slowest call took this many times its fastest")
    p.add_argument("--max-blocks", type=int, default=MAX_BLOCKS, help="the most blocks of rounds an input gets")
    a = p.parse_args()
    THREADS = tuple(int(t) for t in a.threads.split(","))
    WIDE, MAX_BLOCKS = a.wide, a.max_blocks
    if a.measure_peak:
        name, path, level, threads = a.measure_peak
        measure_peak(name, path, float(level), int(threads))
        return
    only = set(filter(None, a.only.split(",")))
    rows, inputs, peak_inputs, floors = [], [], [], []
    for n in (int(s) for s in a.sizes.split(",") if s):
        vol = gyroid(n)
        time_input("gyroid", n, vol, 0.0, a.repeats if n < a.large_size else a.large_repeats, rows, a.environment, only, floors)
        inputs.append({"input": "gyroid", "n": n, "dtype": "float32", "order": "C", "shape": [n, n, n], "level": 0.0})
        if a.peak and n == 256:
            peak_inputs.append(("gyroid", n, vol, 0.0))
    if a.uint8:
        n = a.uint8
        vol = gyroid_uint8(n)
        time_input("gyroid uint8", n, vol, 127.5, a.large_repeats if n >= a.large_size else a.repeats, rows, a.environment, only, floors)
        inputs.append({"input": "gyroid uint8", "n": n, "dtype": "uint8", "order": "C", "shape": [n, n, n], "level": 127.5})
        if a.peak:
            peak_inputs.append(("gyroid uint8", n, vol, 127.5))
    if a.mni:
        try:
            path = mni_path() if a.mni == "nilearn" else a.mni
            import nibabel as nib
            versions["nibabel"] = nib.__version__
            versions["nilearn"] = version("nilearn")
            img = nib.load(path)
            level = float(isolab.extract(path).stats["iso"])
            for name, vol in [("MNI152 T1", img.get_fdata()), ("MNI152 T1 stored", np.asanyarray(img.dataobj))]:
                order = "F" if vol.flags.f_contiguous else "C"
                time_input(name, max(vol.shape), vol, level, a.repeats, rows, a.environment, only, floors)
                inputs.append({"input": name, "n": max(vol.shape), "dtype": str(vol.dtype), "order": order,
                               "shape": list(vol.shape), "level": level})
                if a.peak:
                    peak_inputs.append((name, max(vol.shape), vol, level))
        except ImportError as e:
            notes.append(f"MNI152 T1 not run: {e}")
    peak_rows = peaks(peak_inputs, only) if peak_inputs else []
    with open(a.out + ".tmp", "w") as f:
        json.dump({"versions": versions, "notes": notes, "inputs": inputs, "rows": rows, "peaks": peak_rows,
                   "floors": floors}, f)
    os.replace(a.out + ".tmp", a.out)


if __name__ == "__main__":
    main()
