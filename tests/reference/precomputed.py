"""Live check of `isolab labels --format neuroglancer` against the connectomics tools themselves.

1. A Voronoi label volume is written by cloud-volume as a precomputed segmentation, and isolab's
   CLI writes its multi-resolution mesh source into the volume's `mesh` folder (unsharded), and a
   sharded one into `mesh_sharded`.
2. cloud-volume 12.15 reads every segment's mesh at every level from both; level 0 must hold the
   area of isolab's own per-label meshes (`isolab labels -o folder`) within the quantization, and
   the two sources the same triangles.
3. The folder is left for `tests/browser/neuroglancer.mjs`, which loads it in neuroglancer's own
   client (the `neuroglancer` package's bundled build) in headless Chromium.

Usage: python precomputed.py ISOLAB_BINARY OUT_DIR   (prints the neuroglancer client folder)
"""
import json
import os
import shutil
import subprocess
import sys

import numpy as np


def voronoi(shape, cells, seed=4):
    rng = np.random.default_rng(seed)
    seeds = rng.uniform(0, 1, (cells, 3)) * np.asarray(shape)
    grid = np.stack(np.meshgrid(*(np.arange(n) for n in shape), indexing="ij"), -1)
    nearest = np.argmin(((grid.reshape(-1, 1, 3) - seeds[None]) ** 2).sum(-1), axis=1).reshape(shape) + 1
    centre = (np.asarray(shape) - 1) / 2
    inside = (((grid - centre) / (np.asarray(shape) / 2.2)) ** 2).sum(-1) < 1
    return np.where(inside, nearest, 0).astype(np.uint32)


def nrrd(path, labels):
    """A raw NRRD of a (x, y, z)-indexed array: x fastest on disk."""
    nx, ny, nz = labels.shape
    head = f"NRRD0004\ntype: uint32\ndimension: 3\nsizes: {nx} {ny} {nz}\nencoding: raw\nendian: little\n\n"
    with open(path, "wb") as f:
        f.write(head.encode())
        f.write(np.asfortranarray(labels).tobytes(order="F"))


def area(v, f):
    v, f = np.asarray(v, np.float64), np.asarray(f, np.int64)
    return 0.5 * np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=1).sum()


def read_ply(path):
    """isolab's binary little-endian PLY: vertex x y z float (maybe normals), faces uchar/int."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode().splitlines()
    nv = nf = 0
    props = []
    for line in header:
        if line.startswith("element vertex"):
            nv = int(line.split()[-1])
        elif line.startswith("element face"):
            nf = int(line.split()[-1])
        elif line.startswith("property float") and nf == 0:
            props.append(line.split()[-1])
    assert "binary_little_endian" in header[1], header[1]
    v = np.frombuffer(data, "<f4", nv * len(props), end).reshape(nv, len(props))[:, :3]
    at = end + 4 * nv * len(props)
    rows = np.frombuffer(data, np.dtype([("n", "u1"), ("i", "<i4", 3)]), nf, at)
    assert (rows["n"] == 3).all()
    return v, rows["i"]


def run(command):
    """Runs isolab quietly; its output is shown only if it fails."""
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(command)} failed ({done.returncode}):\n{done.stderr}")


def main():
    isolab, out = sys.argv[1], sys.argv[2]
    from cloudvolume import CloudVolume
    import neuroglancer
    shutil.rmtree(out, ignore_errors=True)
    os.makedirs(out)
    labels = voronoi((48, 40, 44), 24)
    seg = os.path.join(out, "seg")
    info = CloudVolume.create_new_info(num_channels=1, layer_type="segmentation", data_type="uint32",
                                       encoding="raw", resolution=[1, 1, 1], voxel_offset=[0, 0, 0],
                                       chunk_size=[16, 16, 16], volume_size=list(labels.shape), mesh="mesh")
    cv = CloudVolume("file://" + seg, info=info, compress=False)
    cv.commit_info()
    cv[:, :, :] = labels
    path = os.path.join(out, "seg.nrrd")
    nrrd(path, labels)
    for folder, extra in (("mesh", []), ("mesh_sharded", ["--sharded"])):
        run([isolab, "labels", "-f", path, "--format", "neuroglancer", "--chunk", "16", "-o",
             os.path.join(seg, folder)] + extra)
    run([isolab, "labels", "-f", path, "-o", os.path.join(out, "whole")])
    present = sorted(int(v) for v in np.unique(labels) if v)
    checked = 0
    for folder in ("mesh", "mesh_sharded"):
        info["mesh"] = folder
        cv = CloudVolume("file://" + seg, info=info, compress=False)
        meta = json.load(open(os.path.join(seg, folder, "info")))
        lods = None
        for label in present:
            whole = read_ply(os.path.join(out, "whole", f"seg-label-{label}.ply"))
            m = cv.mesh.get(label, lod=0)
            m = m[label] if isinstance(m, dict) else m
            a, b = area(m.vertices, m.faces), area(*whole)
            if abs(a - b) > 2e-3 * b:
                raise SystemExit(f"{folder}: cloud-volume's level 0 of label {label} has area {a}, isolab's mesh {b}")
            manifest_lods = cv.mesh.get_manifest(label).num_lods if hasattr(cv.mesh, "get_manifest") else None
            lods = manifest_lods or lods
            for lod in range(1, manifest_lods or 1):
                coarse = cv.mesh.get(label, lod=lod)
                coarse = coarse[label] if isinstance(coarse, dict) else coarse
                if len(coarse.faces) == 0 or len(coarse.faces) > len(m.faces):
                    raise SystemExit(f"{folder}: label {label} level {lod} has {len(coarse.faces)} triangles "
                                     f"(level 0: {len(m.faces)})")
            checked += 1
        if meta["@type"] != "neuroglancer_multilod_draco":
            raise SystemExit(f"{folder}: info type {meta['@type']}")
    client = os.path.join(os.path.dirname(neuroglancer.__file__), "static", "client")
    print(json.dumps({"client": client, "data": out, "segments": present, "checked": checked, "lods": lods}))


if __name__ == "__main__":
    main()
