"""A connectome-sized label volume to neuroglancer multi-resolution meshes: isolab on Dask against
igneous, on the same volume, resolution and worker count.

Run by the `connectomics` experiment (`connectomics/mod.rs`) in the reference environment with
isolab installed from `python/`:

    python bench.py OUT.json --n 1024 --cells 2000 --chunk 128 --memory-limit-mib 1024
        --workers 1,2 --work DIR [--igneous-shape 256] [--screenshot-segments 40 --shots DIR]

The volume: a Voronoi foam of `cells` seeds (uniform random, seed 2026) in an n³ box, every voxel
labelled by its nearest seed (uint32, label = seed index + 1), computed per 128³ piece with
scipy's cKDTree, at 8 nm per voxel. It is written twice, uncompressed, so that neither reader pays a codec the other
does not: as a zarr array (64³ chunks; isolab's input) and as a precomputed segmentation by
cloud-volume (64³ chunks, raw encoding; igneous's input). Both are kept in `work` and reused when
their parameters match (the volume takes minutes to make).

Runs, one round, alternating isolab and igneous at each worker count:
- isolab: `isolab.dask.mesh_labels(zarr, chunk=chunk, format="neuroglancer", sharded=True,
  out=...)` on a fresh `distributed.LocalCluster` of `workers` processes (one thread each, each
  with `memory_limit`), timed from the call to its return (all levels, shards and info written).
- igneous: `create_meshing_tasks(layer, mip=0, shape=(s, s, s), sharded=True)` (zmesh per task,
  igneous's defaults: simplified, one-voxel overlap), then `create_sharded_multires_mesh_tasks`
  (its merge: per label fragments gathered, simplified per level, cut into an octree, Draco,
  shards), both on `LocalTaskQueue(parallel=workers)`, timed together.
Per run: wall seconds, bytes written, peak resident memory of the worker processes (isolab: each
Dask worker's VmHWM; igneous: the largest of its pool's processes, getrusage of the children),
and for isolab the fragments, triangles and bytes per level, the wall time of its phases (the
`seconds` mesh_labels returns) and, from Dask's task stream, each worker's seconds computing and
the seconds per kind of task. Then the Draco encoders side by side
on the same fragments (`draco_comparison`), and neuroglancer's own viewer draws
some segments of isolab's source in headless Chromium (tests/browser/neuroglancer.mjs), the
screenshot kept for the page.
"""
import argparse
import importlib.metadata
import json
import os
import resource
import shutil
import subprocess
import sys
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
import numpy as np  # noqa: E402

PIECE = 128
STORE_CHUNK = 64
SEED = 2026
# Nanometres per voxel (isotropic, as in serial-section EM after downsampling): igneous's
# simplification error (40 nm by default) is in these units.
RESOLUTION = 8


def log(*a):
    print(*a, file=sys.stderr, flush=True)


def version(name):
    try:
        return importlib.metadata.version(name)
    except importlib.metadata.PackageNotFoundError:
        return "not installed"


def dir_bytes(path):
    total = 0
    for root, _, files in os.walk(path):
        for f in files:
            total += os.path.getsize(os.path.join(root, f))
    return total


def make_volume(work, n, cells):
    """The zarr and precomputed copies of the foam (reused when their parameters match)."""
    import zarr
    from cloudvolume import CloudVolume
    from scipy.spatial import cKDTree
    params = {"n": n, "cells": cells, "seed": SEED, "piece": PIECE, "store_chunk": STORE_CHUNK,
              "resolution_nm": RESOLUTION}
    stamp = os.path.join(work, "volume.json")
    zpath, seg = os.path.join(work, "labels.zarr"), os.path.join(work, "seg")
    if os.path.exists(stamp) and json.load(open(stamp)) == params:
        return zarr.open_array(zpath, mode="r"), seg, params, 0.0
    shutil.rmtree(zpath, ignore_errors=True)
    shutil.rmtree(seg, ignore_errors=True)
    t = time.perf_counter()
    rng = np.random.default_rng(SEED)
    tree = cKDTree(rng.uniform(0, n, (cells, 3)))
    z = zarr.create_array(zpath, shape=(n, n, n), chunks=(STORE_CHUNK,) * 3, dtype="u4", compressors=None,
                          overwrite=True)
    info = CloudVolume.create_new_info(num_channels=1, layer_type="segmentation", data_type="uint32", encoding="raw",
                                       resolution=[RESOLUTION] * 3, voxel_offset=[0, 0, 0], chunk_size=[STORE_CHUNK] * 3,
                                       volume_size=[n, n, n])
    cv = CloudVolume("file://" + seg, info=info, compress=False, progress=False)
    cv.commit_info()
    axis = np.arange(PIECE, dtype=np.float32)
    for i0 in range(0, n, PIECE):
        for j0 in range(0, n, PIECE):
            for k0 in range(0, n, PIECE):
                g = np.stack(np.meshgrid(axis[:min(PIECE, n - i0)] + i0, axis[:min(PIECE, n - j0)] + j0,
                                         axis[:min(PIECE, n - k0)] + k0, indexing="ij"), -1)
                _, idx = tree.query(g.reshape(-1, 3), workers=-1)
                piece = (idx + 1).astype(np.uint32).reshape(g.shape[:3])
                z[i0:i0 + piece.shape[0], j0:j0 + piece.shape[1], k0:k0 + piece.shape[2]] = piece
                # cloud-volume indexes (x, y, z): the same array, axis 0 as x.
                cv[i0:i0 + piece.shape[0], j0:j0 + piece.shape[1], k0:k0 + piece.shape[2]] = piece
        log(f"  volume: {i0 + PIECE} of {n} slabs, {time.perf_counter() - t:.0f} s")
    json.dump(params, open(stamp, "w"))
    return zarr.open_array(zpath, mode="r"), seg, params, time.perf_counter() - t


def peak_rss_mib():
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024.0
    return float("nan")


def run_isolab(vol, workers, args, out):
    import isolab.dask as idask
    from distributed import Client, LocalCluster
    shutil.rmtree(out, ignore_errors=True)
    c = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                     dashboard_address="127.0.0.1:0", memory_limit=f"{args.memory_limit_mib}MiB", silence_logs=50)
    client = Client(c, timeout=120)
    from distributed import get_task_stream
    try:
        pids = client.run(os.getpid)
        t = time.perf_counter()
        with get_task_stream(client) as stream:
            report = idask.mesh_labels(vol, chunk=args.chunk, format="neuroglancer", sharded=True, out=out,
                                       client=client, spacing=(RESOLUTION,) * 3)
        seconds = time.perf_counter() - t
        busy, by_kind = task_seconds(stream.data)
        peaks = sorted(client.run(peak_rss_mib).values())
        restarted = client.run(os.getpid) != pids
    finally:
        client.close()
        c.close()
    return {"tool": "isolab", "workers": workers, "seconds": seconds, "bytes": dir_bytes(out),
            "peak_rss_mib": peaks, "restarted": restarted, "segments": report["segments"], "lods": report["lods"],
            "fragments": report["fragments"], "triangles": report["triangles"], "level_bytes": report["bytes"],
            "shards": report["shards"], "phases": report.get("seconds", {}), "busy_seconds": busy,
            "task_seconds": by_kind}


def task_seconds(stream):
    """From Dask's task stream: each worker's seconds computing (sorted), and the seconds computing
    per kind of task (the task function's name, as Dask keys it)."""
    busy, by_kind = {}, {}
    for task in stream:
        spent = sum(s["stop"] - s["start"] for s in task.get("startstops", ()) if s.get("action") == "compute")
        busy[task.get("worker")] = busy.get(task.get("worker"), 0.0) + spent
        kind = str(task.get("key", "?"))
        kind = kind.strip("()'").split("-")[0]
        by_kind[kind] = by_kind.get(kind, 0.0) + spent
    return sorted(busy.values()), by_kind


def igneous_job(seg, workers, shape, mesh_dir):
    """Runs in a fresh process (so that its pool's peak memory is its own children's)."""
    import igneous.task_creation as tc
    from taskqueue import LocalTaskQueue
    tq = LocalTaskQueue(parallel=workers, progress=False)
    tq.insert(tc.create_meshing_tasks("file://" + seg, mip=0, shape=(shape,) * 3, sharded=True, mesh_dir=mesh_dir))
    tq.execute(progress=False)
    tq.insert(tc.create_sharded_multires_mesh_tasks("file://" + seg, mesh_dir=mesh_dir, progress=False))
    tq.execute(progress=False)
    children = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0
    print(json.dumps({"children_peak_mib": children, "self_peak_mib": peak_rss_mib()}))


def run_igneous(seg, workers, args):
    mesh_dir = "mesh_igneous"
    target = os.path.join(seg, mesh_dir)
    shutil.rmtree(target, ignore_errors=True)
    for stale in ("mesh_igneous_mip_0_err_40", ):
        shutil.rmtree(os.path.join(seg, stale), ignore_errors=True)
    t = time.perf_counter()
    done = subprocess.run([sys.executable, __file__, "--igneous-job", seg, str(workers), str(args.igneous_shape),
                           mesh_dir], capture_output=True, text=True)
    seconds = time.perf_counter() - t
    if done.returncode != 0:
        raise RuntimeError(f"igneous failed ({done.returncode}): {done.stderr[-3000:]}")
    mem = json.loads(done.stdout.strip().splitlines()[-1])
    written = sum(dir_bytes(os.path.join(seg, d)) for d in os.listdir(seg) if d.startswith(mesh_dir))
    return {"tool": "igneous", "workers": workers, "seconds": seconds, "bytes": written,
            "peak_rss_mib": [max(mem["children_peak_mib"], mem["self_peak_mib"])], "restarted": False,
            "shape": args.igneous_shape}


def draco_comparison(vol, work, side=256, rounds=3):
    """The Draco encoders side by side on the same fragments: isolab's finest fragments of a
    side³ crop (64³ boxes), decoded by DracoPy, then encoded again by isolab's writer (the
    draco-core crate, speed 5) and by DracoPy (Google's C++ Draco, compression levels 5 and 7,
    Draco's own 16-bit quantization with range 65535 and origin 0, which maps the integers to
    themselves, as igneous calls it); one process, one thread, alternating, `rounds` rounds."""
    import statistics
    import DracoPy
    import isolab
    import isolab.dask as idask
    out = os.path.join(work, "draco-crop")
    shutil.rmtree(out, ignore_errors=True)
    crop = np.ascontiguousarray(np.asarray(vol[:side, :side, :side]))
    idask.mesh_labels(crop, chunk=64, format="neuroglancer", lods=1, out=out)
    frags = []
    for name in os.listdir(out):
        if not name.endswith(".index"):
            continue
        m = open(os.path.join(out, name), "rb").read()
        n = int.from_bytes(m[44:48], "little")  # one level: 3+3 floats, count, scale, offset (3)
        sizes = np.frombuffer(m, "<u4", n, 48 + 12 * n)
        data, at = open(os.path.join(out, name[:-6]), "rb").read(), 0
        for size in sizes:
            d = DracoPy.decode(data[at:at + int(size)])
            at += int(size)
            frags.append((np.asarray(d.points).astype(np.int32), np.asarray(d.faces).astype(np.uint32)))
    shutil.rmtree(out, ignore_errors=True)

    def ours():
        return sum(len(isolab._isolab.ng_encode_fragment(p, f)) for p, f in frags)

    def dracopy(level):
        return lambda: sum(len(DracoPy.encode(p.astype(np.float32), f, quantization_bits=16, compression_level=level,
                                              quantization_range=65535.0, quantization_origin=[0.0, 0.0, 0.0]))
                           for p, f in frags)

    runs = {"isolab (draco-core, speed 5)": ours, "DracoPy, level 5": dracopy(5), "DracoPy, level 7": dracopy(7)}
    times, size = {k: [] for k in runs}, {}
    for r in range(rounds):
        for k in (list(runs) if r % 2 == 0 else list(runs)[::-1]):
            t = time.perf_counter()
            size[k] = runs[k]()
            times[k].append(time.perf_counter() - t)
    triangles = int(sum(len(f) for _, f in frags))
    return {"side": side, "fragments": len(frags), "triangles": triangles,
            "encoders": [{"encoder": k, "seconds": times[k], "median": statistics.median(times[k]), "bytes": size[k]}
                         for k in runs]}


def screenshot(args, seg, out_rel, segments):
    here = os.path.dirname(os.path.abspath(__file__))
    root = os.path.abspath(os.path.join(here, "..", "..", "..", ".."))
    chromium = shutil.which("chromium") or "/usr/bin/chromium"
    cmd = ["node", os.path.join(root, "tests", "browser", "neuroglancer.mjs"), sys.executable,
           os.path.join(root, "tests", "reference", "ng_viewer.py"), os.path.dirname(seg),
           ",".join(map(str, segments)), chromium, f"isolab={out_rel}", f"OUT={args.shots}",
           "POS=" + ",".join([str(args.n * RESOLUTION / 2)] * 3), f"SCALE={args.n * RESOLUTION * 1.5}"]
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=900)
    return {"ok": done.returncode == 0, "log": (done.stdout + done.stderr)[-2000:]}


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "--igneous-job":
        igneous_job(sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), sys.argv[5])
        return
    p = argparse.ArgumentParser()
    p.add_argument("out")
    p.add_argument("--n", type=int, default=1024)
    p.add_argument("--cells", type=int, default=2000)
    p.add_argument("--chunk", type=int, default=128)
    p.add_argument("--memory-limit-mib", type=int, default=1024)
    p.add_argument("--workers", default="1,2")
    p.add_argument("--igneous-shape", type=int, default=256)
    p.add_argument("--work", required=True)
    p.add_argument("--no-igneous", dest="igneous", action="store_false")
    p.add_argument("--screenshot-segments", type=int, default=40)
    p.add_argument("--shots", default=None)
    args = p.parse_args()
    os.makedirs(args.work, exist_ok=True)
    workers = [int(w) for w in args.workers.split(",")]
    vol, seg, params, made = make_volume(args.work, args.n, args.cells)
    log(f"volume {vol.shape} uint32 ({vol.nbytes / 2**30:.2f} GiB), made in {made:.0f} s (0: reused)")
    runs, notes = [], []
    ours = os.path.join(args.work, "seg", "mesh_isolab")
    for i, w in enumerate(workers):
        order = ("isolab", "igneous") if i % 2 == 0 else ("igneous", "isolab")
        for tool in order:
            if tool == "isolab":
                row = run_isolab(vol, w, args, ours)
            elif args.igneous:
                try:
                    row = run_igneous(seg, w, args)
                except RuntimeError as e:
                    notes.append(str(e))
                    log(str(e))
                    continue
            else:
                continue
            runs.append(row)
            log(f"  {tool}, {w} worker(s): {row['seconds']:.1f} s, {row['bytes'] / 2**20:.0f} MiB written, "
                f"peak {max(row['peak_rss_mib']):.0f} MiB")
    draco = None
    try:
        draco = draco_comparison(vol, args.work)
        for e in draco["encoders"]:
            log(f"  {e['encoder']}: {e['median']:.2f} s, {e['bytes'] / 2**20:.1f} MiB")
    except Exception as e:  # noqa: BLE001 - the note says what failed
        notes.append(f"Draco comparison not run: {e}")
    shot = None
    if args.shots:
        labels = list(range(1, args.cells + 1))
        rng = np.random.default_rng(1)
        shot = screenshot(args, seg, "seg/mesh_isolab", sorted(rng.choice(labels, args.screenshot_segments,
                                                                           replace=False).tolist()))
        if not shot["ok"]:
            notes.append("neuroglancer screenshot failed: " + shot["log"])
    versions = {k: version(k) for k in ("isolab", "dask", "distributed", "zarr", "igneous-pipeline", "cloud-volume",
                                        "zmesh", "DracoPy", "neuroglancer", "numpy", "scipy")}
    versions["python"] = sys.version.split()[0]
    doc = {"versions": versions, "notes": notes, "volume": dict(params, voxels=int(np.prod(vol.shape)),
                                                                gib=vol.nbytes / 2**30, dtype="uint32",
                                                                made_seconds=made),
           "chunk": args.chunk, "memory_limit_mib": args.memory_limit_mib, "igneous_shape": args.igneous_shape,
           "cores": os.cpu_count(), "runs": runs, "screenshot": shot is not None and shot["ok"], "draco": draco}
    with open(args.out + ".tmp", "w") as f:
        json.dump(doc, f)
    os.replace(args.out + ".tmp", args.out)


if __name__ == "__main__":
    main()
