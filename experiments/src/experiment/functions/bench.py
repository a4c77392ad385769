"""The `functions` experiment's Python side: callables meshed by isolab.extract(fn, ...) and by the
peers a Python user can install, on the same callables, bounds and grids.

Callables (numpy, batched: (N, 3) float64 points in, N values out):
- sphere: |p| - 0.4, a signed distance (Lipschitz 1);
- mlp: |p| - 0.35 + 0.05 tanh-MLP(p), a small fixed-seed network (3-64-64-1) standing in for a
  neural SDF; its Lipschitz bound is 1 + 0.05 times the product of its layers' spectral norms
  (tanh is 1-Lipschitz).

Implementations, each run in a fresh process (one-shot: import, call, exit) so that its peak RSS
(`os.wait4`'s ru_maxrss) is its own; the time is the call's, after the imports (warp's `wp.init()`
included in the set-up); the order alternates between rounds, and while any implementation's
block of rounds is wide (its slowest run over --wide times its fastest) another block runs, up to
--max-blocks (each row records its blocks and whether its last block was still wide):
- isolab: isolab.extract(fn, 0.0, "marching-cubes", bounds=..., resolution=n, lipschitz=L);
- warp: warp.geometry.sparse_marching_cubes on the CPU, the same bound;
- skimage: the dense grid sampled in batches, then skimage.measure.marching_cubes (sizes up to
  --dense-up-to);
- pymcubes: mcubes.marching_cubes_func, one Python call per point (sizes up to --pymcubes-up-to).

The mlp runs on smaller grids (--mlp-up-to, --mlp-dense-up-to): at 512³ warp's CPU run of it
peaked at 5.4 GiB (its batches are large, and each holds the network's 64-wide layers), so 1024³
would not fit this machine; scikit-image's dense 512³ would take minutes of evaluations.

Usage: functions/bench.py OUT.json --sizes 256,512 --repeats 3 [--dense-up-to 512]
       [--pymcubes-up-to 64] [--repeat-up-to 512] [--mlp-up-to 512] [--mlp-dense-up-to 256]
       [--wide 2] [--max-blocks 3]
"""

import argparse
import json
import os
import platform
import subprocess
import sys
import time

LO, HI = (-0.5, -0.5, -0.5), (0.5, 0.5, 0.5)

WORKER = r'''
import json, sys, time
import numpy as np
impl, callable_name, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
LO, HI = (-0.5, -0.5, -0.5), (0.5, 0.5, 0.5)

rng = np.random.default_rng(20261205)
W1, b1 = rng.normal(0, 1.0, (3, 64)), rng.normal(0, 0.5, 64)
W2, b2 = rng.normal(0, 1.0 / 8, (64, 64)), rng.normal(0, 0.5, 64)
W3, b3 = rng.normal(0, 1.0 / 8, (64, 1)), rng.normal(0, 0.5, 1)
MLP_L = 1.0 + 0.05 * np.prod([np.linalg.norm(W, 2) for W in (W1, W2, W3)])
evaluations = [0, 0]

def sphere(p):
    evaluations[0] += len(p); evaluations[1] += 1
    return np.sqrt((p * p).sum(axis=1)) - 0.4

def mlp(p):
    evaluations[0] += len(p); evaluations[1] += 1
    h = np.tanh(p @ W1 + b1)
    h = np.tanh(h @ W2 + b2)
    return np.sqrt((p * p).sum(axis=1)) - 0.35 + 0.05 * (h @ W3 + b3)[:, 0]

fn = {"sphere": sphere, "mlp": mlp}[callable_name]
L = {"sphere": 1.0, "mlp": float(MLP_L)}[callable_name]
grid = np.linspace(-0.5, 0.5, n)

def dense_values():
    out = np.empty((n, n, n), dtype=np.float32)
    yz = np.stack(np.meshgrid(grid, grid, indexing="ij"), axis=-1).reshape(-1, 2)
    for i, x in enumerate(grid):
        p = np.column_stack([np.full(len(yz), x), yz])
        out[i] = fn(p).reshape(n, n)
    return out

# Imports and set-up first: the time is the call's alone.
if impl == "isolab":
    import isolab
elif impl == "warp":
    import warp as wp, warp.geometry as wg
    wp.config.quiet = True
    wp.init()
    def field(points):
        return wp.array(fn(points.numpy().astype(np.float64)).astype(np.float32), dtype=wp.float32, device="cpu")
elif impl == "skimage":
    from skimage.measure import marching_cubes
elif impl == "pymcubes":
    import mcubes
    def one(x, y, z):
        return float(fn(np.array([[x, y, z]]))[0])
t = time.perf_counter()
if impl == "isolab":
    m = isolab.extract(fn, 0.0, "marching-cubes", bounds=(LO, HI), resolution=n, lipschitz=L)
    faces = len(m.faces)
elif impl == "warp":
    with wp.ScopedDevice("cpu"):
        v, f = wg.sparse_marching_cubes(field, n, n, n, lower=LO, upper=HI, threshold=0.0, lipschitz_bound=L, device="cpu")
    f = f.numpy()
    faces = len(f) // 3 if f.ndim == 1 else len(f)
elif impl == "skimage":
    v, f, _, _ = marching_cubes(dense_values(), 0.0, spacing=(grid[1] - grid[0],) * 3)
    faces = len(f)
elif impl == "pymcubes":
    v, f = mcubes.marching_cubes_func(LO, HI, n, n, n, one, 0.0)
    faces = len(f)
seconds = time.perf_counter() - t
print(json.dumps({"seconds": seconds, "faces": faces, "evaluations": evaluations[0], "calls": evaluations[1], "lipschitz": L}))
'''


def run_one(impl, callable_name, n):
    """One fresh process: its result and its peak RSS in MiB."""
    child = subprocess.Popen([sys.executable, "-c", WORKER, impl, callable_name, str(n)], stdout=subprocess.PIPE, text=True)
    out = child.stdout.read()
    _, status, usage = os.wait4(child.pid, 0)
    child.returncode = os.waitstatus_to_exitcode(status)
    if child.returncode != 0:
        return {"error": f"exit {child.returncode}"}
    row = json.loads(out.strip().splitlines()[-1])
    row["peak_mib"] = usage.ru_maxrss / 1024.0
    return row


# The report's rule for spreads (experiments/src/report.rs: WIDE, MAX_ROUNDS, which the experiment
# passes as --wide and --max-blocks): a wide block of rounds is followed by another, up to a bound.
WIDE = 2.0


def is_wide(seconds):
    """Whether a block's slowest run took over WIDE times its fastest (runs that failed left out;
    a block of one run is never wide)."""
    done = [x for x in seconds if x is not None]
    return len(done) > 1 and max(done) > WIDE * min(done)


def version(module):
    try:
        from importlib.metadata import version as v
        return v(module)
    except Exception:  # noqa: BLE001 - a missing peer is reported, not fatal
        return None


def main():
    global WIDE
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--sizes", default="256,512")
    ap.add_argument("--callables", default="sphere,mlp")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--repeat-up-to", type=int, default=512)
    ap.add_argument("--dense-up-to", type=int, default=512)
    ap.add_argument("--pymcubes-up-to", type=int, default=64)
    ap.add_argument("--mlp-up-to", type=int, default=512, help="largest grid for the mlp callable")
    ap.add_argument("--mlp-dense-up-to", type=int, default=256, help="largest dense grid for the mlp callable")
    ap.add_argument("--wide", type=float, default=WIDE, help="a block is wide when its slowest run took this many times its fastest")
    ap.add_argument("--max-blocks", type=int, default=3, help="the most blocks of rounds a grid gets")
    a = ap.parse_args()
    WIDE = a.wide
    sizes = [int(s) for s in a.sizes.split(",")]
    rows = []
    for callable_name in a.callables.split(","):
        for n in sizes:
            if callable_name == "mlp" and n > a.mlp_up_to:
                continue
            impls = ["isolab", "warp"]
            dense_up_to = a.mlp_dense_up_to if callable_name == "mlp" else a.dense_up_to
            if n <= dense_up_to:
                impls.append("skimage")
            if n <= a.pymcubes_up_to:
                impls.append("pymcubes")
            rounds = a.repeats if n <= a.repeat_up_to else 1
            runs = {i: [] for i in impls}
            # Blocks of `rounds` rounds until no implementation's block is wide (its slowest run
            # over WIDE times its fastest) or MAX_BLOCKS have run; every run kept.
            blocks, r = 0, 0
            while True:
                first = {i: len(runs[i]) for i in impls}
                for _ in range(rounds):
                    order = impls if r % 2 == 0 else impls[::-1]
                    for impl in order:
                        runs[impl].append(run_one(impl, callable_name, n))
                        print(f"{callable_name} {n} {impl}: {runs[impl][-1]}", file=sys.stderr, flush=True)
                    r += 1
                blocks += 1
                wide = {i: is_wide([x.get("seconds") for x in runs[i][first[i]:]]) for i in impls}
                if not any(wide.values()) or blocks == a.max_blocks:
                    break
            for impl, rs in runs.items():
                rows.append({"callable": callable_name, "n": n, "implementation": impl, "runs": rs,
                             "blocks": blocks, "wide": wide[impl]})
    versions = {m: version(m) for m in ["isolab", "warp-lang", "scikit-image", "PyMCubes", "numpy"]}
    versions["python"] = platform.python_version()
    versions["libigl"] = version("libigl")
    notes = []
    try:
        import igl
        names = [n for n in dir(igl) if "lipschitz" in n.lower()]
        notes.append("libigl's Python bindings here offer " + (", ".join(names) if names else "no Lipschitz octree") + ".")
    except ImportError:
        notes.append("libigl's Python bindings are not installed here.")
    callables = {
        "sphere": "|p| - 0.4, a signed distance (Lipschitz bound 1)",
        "mlp": "|p| - 0.35 + 0.05 MLP(p), a fixed-seed 3-64-64-1 tanh network standing in for a neural signed distance; "
        "its Lipschitz bound is 1 + 0.05 times the product of its layers' spectral norms",
    }
    with open(a.out, "w") as f:
        json.dump({"versions": versions, "rows": rows, "notes": notes, "callables": callables}, f)


if __name__ == "__main__":
    main()
