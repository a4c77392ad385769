"""real_volumes: isolab's marching-cubes-33 against scikit-image's Lewiner, cell by cell, on a
scan at the page's levels; every cell where they differ named by the rules of
python/tests/lewiner_cells.py (the Python test's own), counted by reason.

Usage: lewiner_cells.py OUT.json SCAN.nii.gz[:VOLUME] LEVEL [LEVEL ...] (VOLUME: which volume of a
4D series, 0 when a 4D scan names none). Writes {"rows": [{"iso",
"counts", "unnamed", "examples", "seconds"}], "versions": {...}}.
"""

import json
import os
import sys
import time

import nibabel
import numpy as np
import skimage

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "python", "tests"))

import isolab  # noqa: E402
from lewiner_cells import named_differences  # noqa: E402


def main(out, scan, *levels):
    path, _, index = scan.partition(":") if not os.path.exists(scan) else (scan, "", "")
    vol = np.asarray(nibabel.load(path).dataobj, dtype=np.float32)
    if vol.ndim == 4:
        vol = np.ascontiguousarray(vol[..., int(index or 0)])
    rows = []
    for level in levels:
        start = time.perf_counter()
        counts, unnamed = named_differences(vol, float(level))
        rows.append({
            "iso": float(level),
            "counts": dict(counts),
            "unnamed": len(unnamed),
            "examples": unnamed[:5],
            "seconds": time.perf_counter() - start,
        })
    versions = {"scikit-image": skimage.__version__, "nibabel": nibabel.__version__, "isolab": isolab.__version__}
    with open(out, "w") as f:
        json.dump({"rows": rows, "versions": versions}, f)


if __name__ == "__main__":
    main(*sys.argv[1:])
