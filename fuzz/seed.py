#!/usr/bin/env python3
"""Seeds fuzz/corpus/<target>/ for every fuzz target: small meshes made from the shipped models
(each model meshed coarsely by isolab and written in every format we read, plus the first lines
of each model's OBJ), and small volumes in every volume format (NIfTI-1 and -2, gzipped or not;
NRRD raw, ascii and gzip; MetaImage), with the committed MNI fixtures that carry their data.

Run from anywhere: python3 fuzz/seed.py (builds the isolab binary if needed). Standard library
only.
"""
import gzip
import os
import shutil
import struct
import subprocess
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
CORPUS = os.path.join(ROOT, "fuzz", "corpus")
TARGETS = ["obj", "ply", "stl", "gltf", "mesh_detect", "nifti", "nrrd", "metaimage"]


def put(target, name, data):
    with open(os.path.join(CORPUS, target, name), "wb") as f:
        f.write(data)


def meshes(isolab):
    models = os.path.join(ROOT, "models")
    tmp = os.path.join(CORPUS, ".tmp")
    os.makedirs(tmp, exist_ok=True)
    for model in sorted(os.listdir(models)):
        if not model.endswith(".obj"):
            continue
        stem = model[:-4]
        src = os.path.join(models, model)
        with open(src, "rb") as f:
            head = f.read(3000)
        put("obj", f"{stem}-head.obj", head[: head.rfind(b"\n") + 1])
        for ext, targets in [("obj", ["obj"]), ("ply", ["ply"]), ("stl", ["stl"]), ("glb", ["gltf"]), ("gltf", ["gltf"])]:
            out = os.path.join(tmp, f"{stem}.{ext}")
            subprocess.run([isolab, "extract", "-a", "marching-cubes", "-f", src, "-r", "6", "-o", out, "-m", os.devnull],
                           check=True, stderr=subprocess.DEVNULL)
            with open(out, "rb") as f:
                data = f.read()
            for t in targets + ["mesh_detect"]:
                put(t, f"{stem}.{ext}", data)
    shutil.rmtree(tmp)
    # An ascii PLY with an extra face property and ushort indices, and an ascii STL.
    put("ply", "ascii-extra.ply", b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        b"property float z\nelement face 1\nproperty list uchar ushort vertex_indices\nproperty uchar red\n"
        b"end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2 7\n")
    put("stl", "ascii.stl", b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
        b"endloop\nendfacet\nendsolid x\n")


def voxels(n=4):
    return bytes((i * 37) % 251 for i in range(n * n * n))


def nifti1(n=4, datatype=2, bitpix=8):
    h = bytearray(348)
    struct.pack_into("<i", h, 0, 348)
    struct.pack_into("<8h", h, 40, 3, n, n, n, 1, 1, 1, 1)
    struct.pack_into("<hh", h, 70, datatype, bitpix)
    struct.pack_into("<8f", h, 76, 1, 1.5, 1.5, 2.0, 1, 1, 1, 1)
    struct.pack_into("<f", h, 108, 352.0)  # vox_offset
    struct.pack_into("<f", h, 112, 1.0)  # scl_slope
    struct.pack_into("<hh", h, 252, 1, 1)  # qform_code, sform_code
    struct.pack_into("<12f", h, 280, 1.5, 0, 0, -3, 0, 1.5, 0, -3, 0, 0, 2, -4)  # srow_x, y, z
    h[344:348] = b"n+1\0"
    return bytes(h) + b"\0" * 4 + voxels(n)


def nifti2(n=4):
    h = bytearray(540)
    struct.pack_into("<i", h, 0, 540)
    h[4:12] = b"n+2\0\r\n\x1a\n"
    struct.pack_into("<hh", h, 12, 2, 8)  # datatype, bitpix
    struct.pack_into("<8q", h, 16, 3, n, n, n, 1, 1, 1, 1)
    struct.pack_into("<8d", h, 104, 1, 1, 1, 1, 1, 1, 1, 1)
    struct.pack_into("<q", h, 168, 544)  # vox_offset
    struct.pack_into("<d", h, 176, 1.0)  # scl_slope
    return bytes(h) + b"\0" * 4 + voxels(n)


def volumes():
    put("nifti", "tiny.nii", nifti1())
    put("nifti", "tiny.nii.gz", gzip.compress(nifti1()))
    put("nifti", "tiny-f32.nii", nifti1(datatype=16, bitpix=32)[:352] + struct.pack("<64f", *range(64)))
    put("nifti", "tiny-2.nii", nifti2())
    header = b"NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4 4 4\nspace: left-posterior-superior\n" \
             b"space directions: (1,0,0) (0,1,0) (0,0,1.5)\nspace origin: (0,0,0)\n"
    put("nrrd", "tiny-raw.nrrd", header + b"encoding: raw\n\n" + voxels())
    put("nrrd", "tiny-gzip.nrrd", header + b"encoding: gzip\n\n" + gzip.compress(voxels()))
    put("nrrd", "tiny-ascii.nrrd", header + b"encoding: ascii\n\n" + b" ".join(str(v).encode() for v in voxels()) + b"\n")
    put("metaimage", "tiny.mha", b"ObjectType = Image\nNDims = 3\nDimSize = 4 4 4\nElementType = MET_UCHAR\n"
        b"ElementSpacing = 1 1 1.5\nOffset = 0 0 0\nTransformMatrix = 1 0 0 0 1 0 0 0 1\n"
        b"ElementDataFile = LOCAL\n" + voxels())
    fixtures = os.path.join(ROOT, "tests", "reference", "volumes")
    for name, target in [("mni-small.nii.gz", "nifti"), ("mni-small-2.nii.gz", "nifti"), ("mni-small.nrrd", "nrrd"),
                         ("mni-small.mhd", "metaimage")]:
        shutil.copy(os.path.join(fixtures, name), os.path.join(CORPUS, target, name))


def main():
    isolab = os.path.join(ROOT, "target", "release", "isolab")
    if not os.path.exists(isolab):
        subprocess.run(["cargo", "build", "--release", "-q", "--bin", "isolab"], cwd=ROOT, check=True)
    for t in TARGETS:
        os.makedirs(os.path.join(CORPUS, t), exist_ok=True)
    meshes(isolab)
    volumes()
    for t in TARGETS:
        print(f"{t}: {len(os.listdir(os.path.join(CORPUS, t)))} seeds")


if __name__ == "__main__":
    sys.exit(main())
