"""Volume files: fixtures written by the libraries people read scans with, and marching cubes
equivalence on them.

The fixture is real MRI data: the MNI ICBM152 2009a T1 template that nilearn ships, every 5th
voxel (40 x 47 x 38, uint8), placed by an affine that exercises every path a reader can get wrong:
a rotation, anisotropic voxels (5, 5.5, 4.5 mm) and a flip of the third axis (negative determinant;
    the qform stores it as qfac = -1 with a well-conditioned quaternion). It
is written as
  - mni-small.nii.gz       NIfTI-1 by nibabel, gzip, sform and qform, uint8;
  - mni-small-qform.nii    NIfTI-1 by nibabel, qform only, int16 holding 2x the values with
                           scl_slope 0.5 patched into the header (nibabel reads the same values);
  - mni-small-2.nii.gz     NIfTI-2 by nibabel, float32;
  - mni-small.nrrd         NRRD by pynrrd, gzip, space left-posterior-superior;
  - mni-small.nhdr + .raw  NRRD by pynrrd, detached, big-endian uint16, space right-anterior-superior;
  - mni-small.mhd + .zraw  MetaImage by SimpleITK, zlib-compressed (ITK's LPS world).
Each library reads its own file back, scikit-image meshes the array (`marching_cubes(volume,
level, spacing)`), and the vertices are mapped through the file's affine to RAS world
coordinates: every copy must give the same vertex set (checked here), which is the golden that
`cargo test` (tests/tests/volumes.rs) compares isolab's `marching-cubes --set on-iso=exact` with.
"""
import json
import os
import subprocess
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
FIXTURES = os.path.join(HERE, "volumes")
GOLDEN = os.path.join(HERE, "golden")
LEVEL = 60.5  # skin: between the zero background and the tissue; no voxel is at the level
STRIDE = 5
FILES = ["mni-small.nii.gz", "mni-small-qform.nii", "mni-small-2.nii.gz", "mni-small.nrrd", "mni-small.nhdr", "mni-small.mhd"]
LPS = np.diag([-1.0, -1.0, 1.0])


def mni_t1_path():
    import nilearn
    return os.path.join(os.path.dirname(nilearn.__file__), "datasets", "data", "mni_icbm152_t1_tal_nlin_sym_09a_converted.nii.gz")


def fixture_affine():
    """Rotation (12 degrees about z, 5 about x) times a flip of the k axis and anisotropic voxels."""
    cz, sz = np.cos(np.radians(12)), np.sin(np.radians(12))
    cx, sx = np.cos(np.radians(5)), np.sin(np.radians(5))
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    spacing = np.array([5.0, 5.5, 4.5])
    m = rz @ rx @ np.diag([1.0, 1.0, -1.0]) @ np.diag(spacing)
    a = np.eye(4)
    a[:3, :3] = m
    a[:3, 3] = [-98.0, -118.0, 100.0]
    return a


def write_fixtures(out=FIXTURES, data=None):
    """Writes the six files into `out` (the committed fixtures, or a scratch directory)."""
    import nibabel as nib
    import nrrd
    import SimpleITK as sitk
    os.makedirs(out, exist_ok=True)
    if data is None:
        data = np.asanyarray(nib.load(mni_t1_path()).dataobj)[::STRIDE, ::STRIDE, ::STRIDE].astype(np.uint8)
    a = fixture_affine()
    img = nib.Nifti1Image(data, a)
    img.set_sform(a, code=2)
    img.set_qform(a, code=1)
    nib.save(img, os.path.join(out, "mni-small.nii.gz"))
    q = nib.Nifti1Image((data.astype(np.int16) * 2), None)
    q.set_qform(a, code=1)
    q.set_sform(None, code=0)
    path = os.path.join(out, "mni-small-qform.nii")
    nib.save(q, path)
    raw = bytearray(open(path, "rb").read())
    raw[112:120] = np.array([0.5, 0.0], dtype="<f4").tobytes()  # scl_slope, scl_inter
    open(path, "wb").write(bytes(raw))
    nib.save(nib.Nifti2Image(data.astype(np.float32), a), os.path.join(out, "mni-small-2.nii.gz"))
    m, t = a[:3, :3], a[:3, 3]
    nrrd.write(os.path.join(out, "mni-small.nrrd"), data, header={
        "space": "left-posterior-superior", "space directions": (LPS @ m).T, "space origin": LPS @ t, "encoding": "gzip"})
    nrrd.write(os.path.join(out, "mni-small.nhdr"), data.astype(">u2"), header={
        "space": "right-anterior-superior", "space directions": m.T, "space origin": t, "encoding": "raw"}, detached_header=True)
    spacing = np.linalg.norm(m, axis=0)
    image = sitk.GetImageFromArray(np.ascontiguousarray(np.transpose(data, (2, 1, 0))))
    image.SetSpacing([float(s) for s in spacing])
    image.SetOrigin([float(v) for v in LPS @ t])
    image.SetDirection([float(v) for v in (LPS @ (m / spacing)).ravel()])
    sitk.WriteImage(image, os.path.join(out, "mni-small.mhd"), True)


BRAIN_MASK = "mni-brain-mask.nii.gz"


def write_brain_mask(out=FIXTURES):
    """The MNI152 whole-brain mask as nilearn makes it (`load_mni152_brain_mask(resolution=2)`: the
    same T1 template resampled to 2 mm voxels, above 0.2 of its range), 99 x 117 x 95, uint8 0/1,
    with the template's own affine: the real binary segmentation `isosurface-stuffing` is tested
    on (tests/tests/stuffing.rs)."""
    import nibabel as nib
    from nilearn import datasets
    mask = datasets.load_mni152_brain_mask(resolution=2)
    data = np.asarray(mask.dataobj).astype(np.uint8)
    img = nib.Nifti1Image(data, mask.affine)
    img.set_sform(mask.affine, code=4)
    img.set_qform(mask.affine, code=4)
    nib.save(img, os.path.join(out, BRAIN_MASK))


def read_with_library(path):
    """The array (i fastest axis first) and RAS affine as the file's own library reads it."""
    if path.endswith((".nii", ".nii.gz")):
        import nibabel as nib
        img = nib.load(path)
        return np.asarray(img.get_fdata(), dtype=np.float32), img.affine
    if path.endswith((".nrrd", ".nhdr")):
        import nrrd
        data, h = nrrd.read(path)
        flip = LPS if h["space"] in ("left-posterior-superior", "LPS") else np.eye(3)
        a = np.eye(4)
        a[:3, :3] = flip @ np.asarray(h["space directions"]).T
        a[:3, 3] = flip @ np.asarray(h["space origin"])
        return data.astype(np.float32), a
    import SimpleITK as sitk
    image = sitk.ReadImage(path)
    data = np.transpose(sitk.GetArrayFromImage(image), (2, 1, 0)).astype(np.float32)
    d = np.asarray(image.GetDirection()).reshape(3, 3) * np.asarray(image.GetSpacing())
    a = np.eye(4)
    a[:3, :3] = LPS @ d
    a[:3, 3] = LPS @ np.asarray(image.GetOrigin())
    return data, a


def skimage_world(path, level=LEVEL):
    """scikit-image's marching cubes of the file's array with its voxel spacing, mapped to RAS
    world coordinates through the file's affine (with the spacing divided out); float32."""
    from skimage import measure
    data, a = read_with_library(path)
    spacing = np.linalg.norm(a[:3, :3], axis=0)
    verts, faces, _, _ = measure.marching_cubes(data, level=level, spacing=tuple(spacing))
    m = a[:3, :3] / spacing
    world = verts.astype(np.float64) @ m.T + a[:3, 3]
    return world.astype(np.float32), faces


def matched(ours, theirs, tol):
    """How many vertices of each set have no partner within `tol` in the other."""
    from scipy.spatial import cKDTree
    d1, _ = cKDTree(theirs).query(ours)
    d2, _ = cKDTree(ours).query(theirs)
    return int((d1 > tol).sum() + (d2 > tol).sum()), float(max(d1.max(initial=0), d2.max(initial=0)))


def tolerance(path):
    """1e-4 of the smallest voxel side: float32 rounding of coordinates near 100 mm is 8e-6 mm."""
    _, a = read_with_library(path)
    return 1e-4 * float(np.linalg.norm(a[:3, :3], axis=0).min())


def library_triangles(path, level=LEVEL):
    """Triangles each library's marching cubes makes of the file's array (their tables resolve
    ambiguous cells differently: Lewiner follows the trilinear interpolant, Lorensen's table and
    VTK's flying edges separate the values above the level)."""
    from skimage import measure
    import reference as ref
    data, _ = read_with_library(path)
    out = {m: int(len(measure.marching_cubes(data, level=level, method=m)[1])) for m in ("lewiner", "lorensen")}
    _, faces = ref.vtk_flying_edges(np.ascontiguousarray(np.transpose(data, (2, 1, 0))), np.zeros(3), 1.0, level)
    return {"skimage-lewiner": out["lewiner"], "skimage-lorensen": out["lorensen"], "vtkFlyingEdges3D": int(len(faces))}


def golden():
    write_fixtures()
    write_brain_mask()
    reference, faces = skimage_world(os.path.join(FIXTURES, FILES[0]))
    reference.tofile(os.path.join(GOLDEN, "volumes-skimage.f32"))
    out = {"level": LEVEL, "inside": "above", "source": "MNI ICBM152 2009a T1 (nilearn), every 5th voxel",
           "vertex_file": "tests/reference/golden/volumes-skimage.f32", "vertices": int(len(reference)), "triangles": int(len(faces)),
           "triangles_by_library": library_triangles(os.path.join(FIXTURES, FILES[0])), "files": {}}
    for name in FILES:
        verts, f = skimage_world(os.path.join(FIXTURES, name))
        tol = tolerance(os.path.join(FIXTURES, name))
        unmatched, worst = matched(verts, reference, tol)
        assert unmatched == 0 and len(f) == len(faces), f"{name}: {unmatched} vertices differ from the NIfTI copy's (worst {worst})"
        out["files"][name] = {"vertices": int(len(verts)), "triangles": int(len(f)), "tolerance_mm": tol, "max_distance_mm": worst}
    json.dump(out, open(os.path.join(GOLDEN, "volumes.json"), "w"), indent=1)
    print("golden volumes")


def obj_vertices(path):
    """The `v` lines of an OBJ isolab wrote, as float32."""
    rows = [line.split()[1:4] for line in open(path) if line.startswith("v ")]
    return np.array(rows, dtype=np.float64).astype(np.float32)


def live(isolab, check):
    """The libraries still give the golden vertex set on the committed files; fresh copies the
    installed pynrrd and SimpleITK write read the same; isolab's marching cubes on every file
    (committed and fresh) gives that vertex set in RAS world coordinates."""
    g = json.load(open(os.path.join(GOLDEN, "volumes.json")))
    reference = np.fromfile(os.path.join(ROOT, g["vertex_file"]), dtype="<f4").reshape(-1, 3)
    with tempfile.TemporaryDirectory() as tmp:
        fresh = os.path.join(tmp, "fresh")
        data = np.asarray(read_with_library(os.path.join(FIXTURES, FILES[0]))[0], dtype=np.uint8)
        write_fixtures(fresh, data)
        for where, name in [(FIXTURES, n) for n in FILES] + [(fresh, n) for n in FILES]:
            path = os.path.join(where, name)
            label = f"{'committed' if where == FIXTURES else 'fresh'} {name}"
            tol = tolerance(path)
            verts, faces = skimage_world(path)
            unmatched, worst = matched(verts, reference, tol)
            check(f"volume {label} skimage", unmatched == 0 and len(faces) == g["triangles"],
                  f"scikit-image: {len(verts)} vertices, {unmatched} off the golden (worst {worst:.2e} mm)")
            out = os.path.join(tmp, "m.obj")
            subprocess.run([isolab, "extract", "-a", "marching-cubes", "-f", path, "--iso", str(g["level"]), "--set", "on-iso=exact",
                            "-o", out, "-m", out + ".json"], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            ours = obj_vertices(out)
            m = json.load(open(out + ".json"))
            unmatched, worst = matched(ours, reference, tol)
            check(f"volume {label} isolab", unmatched == 0 and len(ours) == g["vertices"] and m["outward"] and m["closed"],
                  f"isolab: {len(ours)} vertices ({g['vertices']} golden), {unmatched} unmatched, worst {worst:.2e} mm "
                  f"(tolerance {tol:.1e}); closed {m['closed']} outward {m['outward']}")
            if where == FIXTURES and name == FILES[0]:
                polygons_match_flying_edges(check, path, out)
    check("volume triangles by library", library_triangles(os.path.join(FIXTURES, FILES[0])) == g["triangles_by_library"],
          f"golden {g['triangles_by_library']}")


def polygons_match_flying_edges(check, path, obj):
    """isolab's mesh of the fixture and VTK's flying edges on the same array, in voxel index
    coordinates: the same polygon in every cell but those an ambiguous face or a corner at the
    level explains (reference.compare_meshes, the check of the built-in grids)."""
    import reference as ref
    data, a = read_with_library(path)
    faces = np.array([[int(w.split("/")[0]) - 1 for w in line.split()[1:4]] for line in open(obj) if line.startswith("f ")])
    index = (obj_vertices(obj).astype(np.float64) - a[:3, 3]) @ np.linalg.inv(a[:3, :3]).T
    vol = np.ascontiguousarray(np.transpose(-data, (2, 1, 0)))  # inside above: isolab meshes -value < -level
    fe = ref.vtk_flying_edges(np.ascontiguousarray(np.transpose(data, (2, 1, 0))), np.zeros(3), 1.0, LEVEL)
    r = ref.compare_meshes((index, faces), fe, np.zeros(3), 1.0, vol, -LEVEL, tol=1e-3)
    check("volume mni-small.nii.gz polygons vs vtkFlyingEdges3D", r["unmatched_vertices"] == 0 and not r["unexplained_cells"],
          f"triangles ours {len(faces)} FE {r['triangles']}; cells whose polygons differ {r['differing_cells']} {r['why']}; "
          f"unexplained {r['unexplained_cells']}")


def gltf_validator(isolab, check):
    """isolab's .glb and .gltf outputs (with and without vertex colours, an empty mesh, and a label
    map's scene of one named, coloured node per label) pass the Khronos glTF validator with no
    errors."""
    node_dir = HERE
    if not os.path.exists(os.path.join(node_dir, "node_modules", "gltf-validator")):
        check("gltf-validator", False, "tests/reference/node_modules/gltf-validator is not installed (run.sh installs it with npm ci)")
        return
    with tempfile.TemporaryDirectory() as tmp:
        cases = [("terrain-materials.glb", ["-a", "marching-cubes", "-f", "terrain", "-r", "40", "--materials"]),
                 ("sphere.gltf", ["-a", "surface-nets", "-f", "sphere", "-r", "24"]),
                 ("scan.glb", ["-a", "marching-cubes", "-f", os.path.join(FIXTURES, "mni-small.nii.gz"), "--iso", "60.5"]),
                 ("empty.glb", ["-a", "marching-cubes", "-f", "sphere", "-r", "16", "--iso", "5"])]
        cases = [(name, ["extract", *args], True) for name, args in cases]
        seg = np.zeros((12, 10, 8), np.uint8)
        seg[2:6, 2:8, 2:6], seg[6:10, 2:8, 2:6], seg[4, 8, 6] = 1, 2, 7
        labels = os.path.join(tmp, "seg.nrrd")
        with open(labels, "wb") as f:
            f.write(b"NRRD0004\ntype: uint8\ndimension: 3\nsizes: 12 10 8\nencoding: raw\n\n" + seg.tobytes(order="F"))
        cases.append(("labels.glb", ["labels", "-f", labels], False))
        for name, args, with_metrics in cases:
            path = os.path.join(tmp, name)
            metrics = ["-m", path + ".json"] if with_metrics else []
            subprocess.run([isolab, *args, "-o", path, *metrics], check=True, stdout=subprocess.DEVNULL,
                           stderr=subprocess.DEVNULL)
            r = subprocess.run(["node", os.path.join(HERE, "validate_gltf.mjs"), path], capture_output=True, text=True)
            try:
                report = json.loads(r.stdout)
                errors, warnings = report["issues"]["numErrors"], report["issues"]["numWarnings"]
                detail = f"{errors} errors, {warnings} warnings: " + "; ".join(
                    f"{m['code']} {m.get('pointer', '')}" for m in report["issues"]["messages"][:5])
            except (ValueError, KeyError):
                errors, detail = -1, f"validator failed: {r.stderr.strip()[:300]}"
            check(f"gltf-validator {name}", errors == 0, detail)
