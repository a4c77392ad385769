"""isolab.dask on this machine's cores: zarr volumes larger than a worker's memory limit, meshed
block by block on a distributed.LocalCluster of 1 and 2 worker processes (loopback only).

Run by the `distributed` experiment (`distributed/mod.rs`) in the reference environment with
isolab installed from `python/`:

    python bench.py OUT.json [--repeats 3] [--memory-limit-mib 256] [--chunks 128,64] [--synthetic-n 640]
        [--tiles 4,4,2] [--mni nilearn] [--work DIR]

Volumes (written to zarr in DIR, chunks of 64³, zarr's default compression):
- synthetic: the built-in `asteroid` field sampled at n³ (float32), block by block through isolab;
- MNI152 T1 tiled: nilearn's template as nibabel's get_fdata() returns it, cast to float32, tiled.
For each volume, block size and worker count, `repeats` runs alternate between 1 and 2 workers
(another block of `repeats` rounds while either count's runs in the last block span more than
`--wide` times, up to `--max-blocks`; each run records its round and block),
each on a fresh cluster and a fresh fragment folder (merge=False: the blocks only), timed from
submitting the tasks to the last fragment written; then the weld of those fragments, timed alone,
in this process. Per run: wall time, blocks per second, each worker's peak resident memory
(VmHWM, which includes the worker's start-up), the workers' and this driver process's CPU
seconds (the scheduler and the nannies live in the driver), whether any worker was restarted.
Once per volume, at the first block size: the welded mesh against `isolab.extract(whole array, chunk=...)` in this process (the
one-process chunked mesh, which for marching cubes is the whole-volume mesh); a run in which one
worker process is killed (SIGKILL) once the first fragment is written, checked against the same;
and, for the synthetic volume, the same blocks meshed by zmesh (`zmesh.Mesher` per block, as
igneous runs it) and merged naively by exact position, with its seam defects counted.
"""
import argparse
import importlib.metadata
import json
import os
import shutil
import signal
import sys
import tempfile
import threading
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
import numpy as np  # noqa: E402
import zarr  # noqa: E402
from distributed import Client, LocalCluster  # noqa: E402

import isolab  # noqa: E402
import isolab.dask as idask  # noqa: E402
from isolab import _isolab  # noqa: E402


def version(name):
    try:
        return importlib.metadata.version(name)
    except importlib.metadata.PackageNotFoundError:
        return "not installed"


# The zarr stores' chunk edge (samples).
STORE_CHUNK = 64


def log(*a):
    print(*a, file=sys.stderr, flush=True)


def synthetic(path, n, chunk):
    z = zarr.open_array(path, mode="w", shape=(n, n, n), chunks=(chunk, chunk, chunk), dtype="f4")
    cells = [n - 1] * 3
    for k0 in range(0, n, chunk):
        dz = min(chunk, n - k0)
        b = _isolab.field_block("asteroid", cells, [0, 0, k0], [n, n, dz], None, False)
        z[k0:k0 + dz] = b["values"]
    return zarr.open_array(path, mode="r")


def mni_tiled(path, mni, tiles, chunk):
    import nibabel as nib
    vol = np.tile(nib.load(mni).get_fdata().astype(np.float32), tiles)
    z = zarr.open_array(path, mode="w", shape=vol.shape, chunks=(chunk, chunk, chunk), dtype="f4")
    z[:] = vol
    return zarr.open_array(path, mode="r")


def cluster(workers, memory_limit):
    c = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                     dashboard_address="127.0.0.1:0", memory_limit=memory_limit, silence_logs=50)
    return c, Client(c, timeout=120)


def peak_rss_mib():
    """This process's peak resident memory (VmHWM: the high-water mark of its own address space;
    getrusage's ru_maxrss would include the parent's memory at the fork before exec)."""
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024.0
    return float("nan")


def cpu_seconds():
    return time.process_time()


def one_run(vol, level, inside, workers, chunk, args, work):
    out = tempfile.mkdtemp(prefix="fragments-", dir=work)
    c, client = cluster(workers, f"{args.memory_limit_mib}MiB")
    try:
        pids = client.run(os.getpid)
        worker_cpu = client.run(cpu_seconds)
        driver = os.times()
        t = time.perf_counter()
        paths = idask.mesh_volume(vol, level, chunk=chunk, inside=inside, client=client, out=out, merge=False)
        seconds = time.perf_counter() - t
        driver_after = os.times()
        worker_cpu = sum(v - worker_cpu[k] for k, v in client.run(cpu_seconds).items())
        restarted = client.run(os.getpid) != pids
        peaks = sorted(client.run(peak_rss_mib).values())
    finally:
        client.close()
        c.close()
    driver_cpu = (driver_after.user - driver.user) + (driver_after.system - driver.system)
    return {"workers": workers, "chunk": chunk, "seconds": seconds, "blocks": len(paths),
            "blocks_per_second": len(paths) / seconds, "worker_peak_rss_mib": peaks, "restarted": restarted,
            "worker_cpu_seconds": worker_cpu, "driver_cpu_seconds": driver_cpu}, out, paths


def weld(paths, report):
    t = time.perf_counter()
    fragments = [idask.load_fragment(p) for p in paths]
    parts = _isolab.weld_fragments(fragments, None, json.dumps(report))
    return parts, time.perf_counter() - t


def killed_run(vol, level, inside, chunk, args, work):
    out = tempfile.mkdtemp(prefix="killed-", dir=work)
    c, client = cluster(2, f"{args.memory_limit_mib}MiB")
    result = {}
    try:
        victim = next(iter(client.run(os.getpid).values()))
        run = threading.Thread(target=lambda: result.update(paths=idask.mesh_volume(
            vol, level, chunk=chunk, inside=inside, client=client, out=out, merge=False)))
        t = time.perf_counter()
        run.start()
        written = 0
        while written == 0 and run.is_alive():
            written = len([p for p in os.listdir(out) if p.startswith("fragment-")])
            time.sleep(0.005)
        os.kill(victim, signal.SIGKILL)
        run.join()
        seconds = time.perf_counter() - t
        replaced = victim not in client.run(os.getpid).values()
    finally:
        client.close()
        c.close()
    return result.get("paths"), {"seconds": seconds, "fragments_before_kill": written, "worker_replaced": replaced}, out


def zmesh_naive(vol, level, inside, chunk):
    """zmesh per block (the blocks of our plan, without apron: cell-local), each block's vertices
    shifted to the volume's sample indices, concatenated, and merged by exact position."""
    import zmesh
    dims = [vol.shape[2], vol.shape[1], vol.shape[0]]
    _, _, blocks = _isolab.block_plan("marching-cubes", None, dims, chunk)
    verts, faces, offset, t = [], [], 0, time.perf_counter()
    for _, lo, bd in blocks:
        block = np.asarray(vol[lo[2]:lo[2] + bd[2], lo[1]:lo[1] + bd[1], lo[0]:lo[0] + bd[0]])
        labels = ((block > level) if inside == "above" else (block < level)).astype(np.uint8)
        if not labels.any():
            continue
        mesher = zmesh.Mesher((1, 1, 1))
        mesher.mesh(labels)
        if 1 not in mesher.ids():
            continue
        m = mesher.get(1, normals=False)
        verts.append(m.vertices + np.array([lo[2], lo[1], lo[0]], dtype=np.float32))
        faces.append(m.faces.astype(np.int64) + offset)
        offset += len(m.vertices)
    seconds = time.perf_counter() - t
    v, f = np.concatenate(verts), np.concatenate(faces)
    unique, inverse = np.unique(v, axis=0, return_inverse=True)
    merged_faces = inverse.reshape(-1)[f]
    duplicates = len(v) - len(unique)
    keep = (merged_faces[:, 0] != merged_faces[:, 1]) & (merged_faces[:, 1] != merged_faces[:, 2]) & \
        (merged_faces[:, 0] != merged_faces[:, 2])
    m = json.loads(_isolab.metrics(unique.astype(np.float32), merged_faces[keep].astype(np.int32), None, None, None, None,
                                   False, None))
    return {"seconds": seconds, "vertices_before_merge": int(len(v)), "coincident_vertices_merged": int(duplicates),
            "vertices": int(len(unique)), "triangles": int(keep.sum()), "collapsed_triangles": int((~keep).sum()),
            "boundary_edges": m["boundary_edges"], "non_manifold_edges": m["non_manifold_edges"],
            "closed": m["closed"]}


def canonical(vertices, faces):
    """Vertices sorted, and triangles as sorted rows of indices into them (rotation kept
    apart from winding: each triangle starts at its smallest index)."""
    order = np.lexsort(vertices.T[::-1])
    rank = np.empty(len(order), dtype=np.int64)
    rank[order] = np.arange(len(order))
    f = rank[faces]
    first = np.argmin(f, axis=1)
    f = np.stack([f[np.arange(len(f)), (first + k) % 3] for k in range(3)], axis=1)
    return vertices[order], f[np.lexsort(f.T[::-1])]


def same_mesh(v1, f1, v2, f2):
    if v1.shape != v2.shape or f1.shape != f2.shape:
        return False
    a, b = canonical(v1, f1), canonical(v2, f2)
    return bool(np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1]))


def topology(vertices, faces):
    m = json.loads(_isolab.metrics(vertices, faces, None, None, None, None, False, None))
    return {k: m[k] for k in ("closed", "boundary_edges", "non_manifold_edges", "genus", "components")}


def measure_volume(name, vol, level, inside, args, work, rows, checks):
    log(f"{name}: {vol.shape} {vol.dtype}, {vol.nbytes / 2**20:.0f} MiB")
    kept = paths = None
    for chunk in args.chunks:
        # Blocks of `repeats` rounds until neither worker count's block is wide (its slowest run
        # over `--wide` times its fastest) or `--max-blocks` have run; every run kept.
        r, block = 0, 0
        while True:
            start = len(rows)
            for _ in range(args.repeats):
                for workers in ((1, 2) if r % 2 == 0 else (2, 1)):
                    row, out, run_paths = one_run(vol, level, inside, workers, chunk, args, work)
                    row.update(volume=name, round=r, block=block)
                    rows.append(row)
                    log(f"  chunk {chunk}, {workers} worker(s): {row['seconds']:.1f} s, worker CPU "
                        f"{row['worker_cpu_seconds']:.1f} s, driver CPU {row['driver_cpu_seconds']:.1f} s")
                    if kept is None and chunk == args.chunks[0]:
                        kept, paths = out, run_paths
                    else:
                        shutil.rmtree(out)
                r += 1
            block += 1
            spans = [[x["seconds"] for x in rows[start:] if x["workers"] == w] for w in (1, 2)]
            if not any(len(t) > 1 and max(t) > args.wide * min(t) for t in spans) or block == args.max_blocks:
                break
    chunk = args.chunks[0]
    report = {"algorithm": "marching-cubes", "driver": "isolab.dask"}
    parts, weld_seconds = weld(paths, report)
    shutil.rmtree(kept)
    ref = isolab.extract(np.asarray(vol[:]), level, inside=inside) if args.check else None
    killed_paths, killed, killed_out = killed_run(vol, level, inside, chunk, args, work)
    killed_parts, _ = weld(killed_paths, report)
    shutil.rmtree(killed_out)
    check = {"volume": name, "shape": list(vol.shape), "dtype": str(vol.dtype), "mib": vol.nbytes / 2**20,
             "level": level, "inside": inside, "chunk": chunk, "weld_seconds": weld_seconds,
             "vertices": int(len(parts["vertices"])), "triangles": int(len(parts["faces"])),
             "topology": topology(parts["vertices"], parts["faces"]), "killed": killed,
             "killed_equal": bool(np.array_equal(killed_parts["vertices"], parts["vertices"])
                                  and np.array_equal(killed_parts["faces"], parts["faces"]))}
    if ref is not None:
        # Both in the array's index coordinates: the same vertices (as a set, bit for bit) and the
        # same triangles over them.
        check["equals_one_process"] = same_mesh(ref.vertices, ref.faces, parts["vertices"], parts["faces"])
    checks.append(check)
    log(f"  weld {weld_seconds:.1f} s; killed run equal: {check['killed_equal']}; "
        f"one process equal: {check.get('equals_one_process')}")
    return check


def main():
    p = argparse.ArgumentParser()
    p.add_argument("out")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--wide", type=float, default=2.0, help="a block of rounds is wide when its slowest run took this many times its fastest")
    p.add_argument("--max-blocks", type=int, default=3, help="blocks of rounds at most")
    p.add_argument("--memory-limit-mib", type=int, default=256)
    p.add_argument("--chunks", default="128,64", help="block sizes in cells; checks run at the first")
    p.add_argument("--synthetic-n", type=int, default=640)
    p.add_argument("--tiles", default="4,4,2")
    p.add_argument("--mni", default="nilearn")
    p.add_argument("--work", default=None)
    p.add_argument("--no-check", dest="check", action="store_false")
    args = p.parse_args()
    args.chunks = [int(c) for c in args.chunks.split(",")]
    work = tempfile.mkdtemp(prefix="isolab-distributed-", dir=args.work)
    rows, checks, notes = [], [], []
    try:
        t = time.perf_counter()
        vol = synthetic(os.path.join(work, "asteroid.zarr"), args.synthetic_n, STORE_CHUNK)
        log(f"synthetic volume written in {time.perf_counter() - t:.1f} s")
        check = measure_volume("asteroid", vol, 0.0, "below", args, work, rows, checks)
        try:
            check["zmesh"] = zmesh_naive(vol, 0.0, "below", args.chunks[0])
            check["ours_blocks"] = check["topology"]
        except ImportError as e:
            notes.append(f"zmesh not run: {e}")
        del vol
        mni = args.mni
        if mni == "nilearn":
            import nilearn
            mni = os.path.join(os.path.dirname(nilearn.__file__), "datasets", "data",
                               "mni_icbm152_t1_tal_nlin_sym_09a_converted.nii.gz")
        if mni and os.path.exists(mni):
            tiles = tuple(int(t) for t in args.tiles.split(","))
            vol = mni_tiled(os.path.join(work, "mni.zarr"), mni, tiles, STORE_CHUNK)
            level = float(isolab.extract(mni).stats["iso"])
            check = measure_volume("MNI152 T1 tiled " + "x".join(map(str, tiles)), vol, level, "above", args, work, rows,
                                   checks)
        else:
            notes.append("MNI152 T1 not found: nilearn is not installed")
    finally:
        shutil.rmtree(work, ignore_errors=True)
    versions = {k: version(k) for k in ("isolab", "dask", "distributed", "zarr", "zmesh", "numpy")}
    versions["python"] = sys.version.split()[0]
    doc = {"versions": versions, "notes": notes, "memory_limit_mib": args.memory_limit_mib, "chunks": args.chunks,
           "store_chunk": STORE_CHUNK,
           "repeats": args.repeats, "cores": os.cpu_count(), "runs": rows, "volumes": checks}
    with open(args.out + ".tmp", "w") as f:
        json.dump(doc, f)
    os.replace(args.out + ".tmp", args.out)


if __name__ == "__main__":
    main()
