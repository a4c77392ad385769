"""Peer isosurface extractors for isolab's `peers` experiment, as one long-lived subprocess.

Protocol (JSON lines): on start it prints {"available": {peer: version or null}, "errors": {...}};
then for every request line {"raw": PATH, "peer": NAME, "threads": N, "protocol": P} it loads the
grid written by `isolab extract --samples-out PATH` (cached between requests), runs the peer once,
timing only the extraction call (grid conversion excluded), and prints {"ms": T, "vertices": V,
"triangles": F} or {"error": MESSAGE}. P is "one-shot" (the default: a new VTK filter per call) or
"steady-state" (VTK: the filter of the previous call on this grid, Modified() then Update(); the
other peers keep no state, so both protocols run them the same way). Peers: vtk-flying-edges (threads 1 or 2: VTK's STDThread SMP backend),
vtk-marching-cubes, skimage-lorensen, skimage-lewiner, pymcubes, libigl. And one decimator:
{"peer": "pymeshlab-quadric", "mesh": PATH, "target": FACES, "out": PATH}. And one mesh field:
{"peer": "libigl-signed-distance", "mesh": PATH, "origin": [x, y, z], "spacing": H, "dims": [NX, NY, NZ],
"out": PATH, "exact_out": PATH or absent} (the `mesh_fields` experiment; `exact_out` also gets libigl's
`point_mesh_squared_distance`, square-rooted, untimed).

Scans (the `real_volumes` experiment): {"peer": "scan", "library": "vtk-flying-edges" or
"skimage-lewiner", "nifti": PATH, "level": V, "out": PATH or null} meshes the NIfTI file's array
as nibabel loads it (cached between requests; VTK gets the stored dtype, scikit-image converts to
float itself), timing the extraction call only, and writes the mesh in world coordinates (the
file's affine) to `out` as binary PLY; {"peer": "scan-end-to-end", "nifti": PATH, "level": V}
times what a user runs: nibabel loading the file, the array into a vtkImageData, flying edges,
all fresh (nothing cached). The hello line names the MNI T1 template nilearn ships ("mni_t1").
"""
import json
import os
import sys
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
import numpy as np  # noqa: E402

available, errors = {}, {}
try:
    import vtk
    from vtk.util import numpy_support
    available["vtk"] = vtk.vtkVersion.GetVTKVersion()
except Exception as e:  # noqa: BLE001
    errors["vtk"] = str(e)
try:
    import skimage
    from skimage import measure
    available["skimage"] = skimage.__version__
except Exception as e:  # noqa: BLE001
    errors["skimage"] = str(e)
try:
    import mcubes
    available["pymcubes"] = getattr(mcubes, "__version__", "installed")
except Exception as e:  # noqa: BLE001
    errors["pymcubes"] = str(e)
try:
    import igl
    available["libigl"] = getattr(igl, "__version__", "installed")
except Exception as e:  # noqa: BLE001
    errors["libigl"] = str(e)

cache = {}


def load(raw):
    if raw not in cache:
        cache.clear()
        h = json.load(open(raw + ".json"))
        nx, ny, nz = h["dims"]
        vol = np.fromfile(raw, dtype="<f4").reshape(nz, ny, nx)
        cache[raw] = {"vol": vol, "h": h}
    return cache[raw]


def vtk_image(g):
    vol, h = g["vol"], g["h"]
    if "image" not in g:
        nz, ny, nx = vol.shape
        img = vtk.vtkImageData()
        img.SetDimensions(nx, ny, nz)
        img.SetSpacing(*[h["spacing"]] * 3)
        img.SetOrigin(*h["origin"])
        img.GetPointData().SetScalars(numpy_support.numpy_to_vtk(vol.ravel(order="C"), deep=True, array_type=vtk.VTK_FLOAT))
        g["image"] = img
    return g["image"]


def run(req):
    g = load(req["raw"])
    vol, iso, peer, threads = g["vol"], g["h"]["iso"], req["peer"], int(req.get("threads", 1))
    if peer in ("vtk-flying-edges", "vtk-marching-cubes"):
        if "vtk" not in available:
            raise RuntimeError("vtk not installed: " + errors.get("vtk", ""))
        img = vtk_image(g)
        smp = vtk.vtkSMPTools
        smp.SetBackend("STDThread" if threads > 1 else "Sequential")
        smp.Initialize(threads)
        key = ("filter", peer, threads)
        steady = req.get("protocol") == "steady-state"
        if steady and key in g:
            f = g[key]
            f.Modified()
        else:
            f = vtk.vtkFlyingEdges3D() if peer == "vtk-flying-edges" else vtk.vtkMarchingCubes()
            f.SetInputData(img)
            f.SetValue(0, iso)
            f.ComputeNormalsOff()
            f.ComputeGradientsOff()
            f.ComputeScalarsOff()
            if steady:
                g[key] = f
        t = time.perf_counter()
        f.Update()
        ms = (time.perf_counter() - t) * 1e3
        out = f.GetOutput()
        return ms, out.GetNumberOfPoints(), out.GetNumberOfPolys()
    if peer.startswith("skimage-"):
        if "skimage" not in available:
            raise RuntimeError("scikit-image not installed: " + errors.get("skimage", ""))
        t = time.perf_counter()
        v, f, _, _ = measure.marching_cubes(vol, level=iso, method=peer.split("-")[1])
        ms = (time.perf_counter() - t) * 1e3
        return ms, len(v), len(f)
    if peer == "pymcubes":
        if "pymcubes" not in available:
            raise RuntimeError("PyMCubes not installed: " + errors.get("pymcubes", ""))
        data = g.setdefault("f64", vol.astype(np.float64))
        t = time.perf_counter()
        v, f = mcubes.marching_cubes(data, iso)
        ms = (time.perf_counter() - t) * 1e3
        return ms, len(v), len(f)
    if peer == "libigl":
        if "libigl" not in available:
            raise RuntimeError("libigl not installed: " + errors.get("libigl", ""))
        nz, ny, nx = vol.shape
        if "igl" not in g:
            hh = g["h"]
            xs = hh["origin"][0] + hh["spacing"] * np.arange(nx)
            ys = hh["origin"][1] + hh["spacing"] * np.arange(ny)
            zs = hh["origin"][2] + hh["spacing"] * np.arange(nz)
            zz, yy, xx = np.meshgrid(zs, ys, xs, indexing="ij")
            g["igl"] = (vol.ravel().astype(np.float64), np.stack([xx.ravel(), yy.ravel(), zz.ravel()], axis=1))
        s, gv = g["igl"]
        t = time.perf_counter()
        res = igl.marching_cubes(s, gv, nx, ny, nz, iso)
        v, f = res[0], res[1]
        ms = (time.perf_counter() - t) * 1e3
        return ms, len(v), len(f)
    raise RuntimeError(f"unknown peer {peer}")


scans = {}


def scan_array(path):
    import nibabel as nib
    if path not in scans:
        scans.clear()
        img = nib.load(path)
        scans[path] = (np.asanyarray(img.dataobj), img.affine)
    return scans[path]


def vtk_scan_image(data, affine):
    """The array as a vtkImageData with the affine's voxel sizes and origin (axis-aligned
    affines only: flying edges does not take a direction matrix)."""
    if not np.allclose(affine[:3, :3], np.diag(np.diag(affine[:3, :3]))):
        raise RuntimeError("the scan's affine is not axis-aligned")
    img = vtk.vtkImageData()
    img.SetDimensions(*data.shape)
    img.SetSpacing(*np.diag(affine[:3, :3]))
    img.SetOrigin(*affine[:3, 3])
    img.GetPointData().SetScalars(numpy_support.numpy_to_vtk(np.ascontiguousarray(data).ravel(order="F"), deep=True))
    return img


def flying_edges(img, level):
    f = vtk.vtkFlyingEdges3D()
    f.SetInputData(img)
    f.SetValue(0, level)
    f.ComputeNormalsOff()
    f.ComputeGradientsOff()
    f.ComputeScalarsOff()
    return f


def write_ply(path, verts, faces):
    """Binary little-endian PLY: float xyz, uchar-int faces."""
    verts = np.ascontiguousarray(verts, dtype="<f4")
    rows = np.empty(len(faces), dtype=[("n", "u1"), ("i", "<i4", 3)])
    rows["n"], rows["i"] = 3, faces
    with open(path, "wb") as f:
        f.write(f"ply\nformat binary_little_endian 1.0\nelement vertex {len(verts)}\nproperty float x\nproperty float y\n"
                f"property float z\nelement face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n".encode())
        f.write(verts.tobytes())
        f.write(rows.tobytes())


def scan(req):
    data, affine = scan_array(req["nifti"])
    level = float(req["level"])
    if req["library"] == "vtk-flying-edges":
        smp_threads(int(req.get("threads", 1)))
        f = flying_edges(vtk_scan_image(data, affine), level)
        t = time.perf_counter()
        f.Update()
        ms = (time.perf_counter() - t) * 1e3
        out = f.GetOutput()
        verts = numpy_support.vtk_to_numpy(out.GetPoints().GetData()).astype(np.float64) if out.GetNumberOfPoints() else np.zeros((0, 3))
        faces = numpy_support.vtk_to_numpy(out.GetPolys().GetConnectivityArray()).reshape(-1, 3)
    elif req["library"] == "skimage-lewiner":
        t = time.perf_counter()
        v, faces, _, _ = measure.marching_cubes(data, level=level, method="lewiner")
        ms = (time.perf_counter() - t) * 1e3
        verts = v.astype(np.float64) @ affine[:3, :3].T + affine[:3, 3]
    else:
        raise RuntimeError(f"unknown scan library {req['library']}")
    if req.get("out"):
        write_ply(req["out"], verts, faces)
    return ms, len(verts), len(faces)


def smp_threads(threads):
    vtk.vtkSMPTools.SetBackend("STDThread" if threads > 1 else "Sequential")
    vtk.vtkSMPTools.Initialize(threads)


def scan_end_to_end(req):
    import nibabel as nib
    smp_threads(int(req.get("threads", 1)))
    t = time.perf_counter()
    img = nib.load(req["nifti"])
    data = np.asanyarray(img.dataobj)
    f = flying_edges(vtk_scan_image(data, img.affine), float(req["level"]))
    f.Update()
    ms = (time.perf_counter() - t) * 1e3
    out = f.GetOutput()
    return ms, out.GetNumberOfPoints(), out.GetNumberOfPolys()


def decimate(req):
    """pymeshlab's quadric edge collapse of the PLY/OBJ `mesh` down to `target` faces, written to
    `out` (OBJ); times the filter only."""
    import pymeshlab
    ms_set = pymeshlab.MeshSet()
    ms_set.load_new_mesh(req["mesh"])
    t = time.perf_counter()
    ms_set.meshing_decimation_quadric_edge_collapse(targetfacenum=int(req["target"]), preservetopology=True,
                                                    preservenormal=True, qualitythr=0.3, optimalplacement=True)
    ms = (time.perf_counter() - t) * 1e3
    ms_set.save_current_mesh(req["out"], save_vertex_normal=False)
    m = ms_set.current_mesh()
    return ms, m.vertex_number(), m.face_number()


sdf_meshes = {}


def signed_distance(req):
    """libigl's signed distance of the mesh `mesh` (OBJ) with the fast winding number sign
    (`SIGNED_DISTANCE_TYPE_FAST_WINDING_NUMBER`) at every sample of the grid `origin`, `spacing`,
    `dims` (x fastest), as isolab samples it; the mesh and the points are built outside the
    timing (cached between requests), libigl uses its default threads. Writes the values as
    little-endian float32 to `out` and answers the count of negative values as "vertices" and the
    sample count as "triangles"."""
    key = req["mesh"]
    if key not in sdf_meshes:
        sdf_meshes.clear()
        v, f = igl.read_triangle_mesh(key)[:2]
        sdf_meshes[key] = (np.ascontiguousarray(v, dtype=np.float64), np.ascontiguousarray(f, dtype=np.int64))
    v, f = sdf_meshes[key]
    o, h, (nx, ny, nz) = req["origin"], req["spacing"], req["dims"]
    axes = [o[i] + h * np.arange(n, dtype=np.float64) for i, n in enumerate((nx, ny, nz))]
    zz, yy, xx = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")
    points = np.stack([xx.ravel(), yy.ravel(), zz.ravel()], 1)
    t = time.perf_counter()
    s = igl.signed_distance(points, v, f, sign_type=igl.SIGNED_DISTANCE_TYPE_FAST_WINDING_NUMBER)[0]
    ms = (time.perf_counter() - t) * 1e3
    np.asarray(s, dtype="<f4").tofile(req["out"])
    if req.get("exact_out"):
        # libigl's own exact distance (untimed), to check ours against and its FWN mode's magnitudes.
        d = np.sqrt(igl.point_mesh_squared_distance(points, v, f)[0])
        np.asarray(d, dtype="<f4").tofile(req["exact_out"])
    return ms, int((s < 0).sum()), len(s)


def main():
    try:
        import pymeshlab
        available["pymeshlab"] = getattr(pymeshlab, "__version__", "installed")
    except Exception as e:  # noqa: BLE001
        errors["pymeshlab"] = str(e)
    hello = {"available": available, "errors": errors}
    try:
        import nibabel
        import nilearn
        available["nibabel"] = nibabel.__version__
        available["nilearn"] = nilearn.__version__
        path = os.path.join(os.path.dirname(nilearn.__file__), "datasets", "data", "mni_icbm152_t1_tal_nlin_sym_09a_converted.nii.gz")
        if os.path.exists(path):
            hello["mni_t1"] = path
        # A second volume of another kind: the fMRI series nibabel ships as test data (int16,
        # 2 x 2 x 2.2 mm, oblique, 4-D), with the affine and orientation nibabel reads.
        epi = os.path.join(os.path.dirname(nibabel.__file__), "tests", "data", "example4d.nii.gz")
        if os.path.exists(epi):
            img = nibabel.load(epi)
            hello["epi"] = epi
            hello["epi_affine"] = [[float(x) for x in row] for row in img.affine]
            hello["epi_axcodes"] = "".join(nibabel.aff2axcodes(img.affine))
    except Exception as e:  # noqa: BLE001
        errors["nilearn"] = str(e)
    print(json.dumps(hello), flush=True)
    for line in sys.stdin:
        if not line.strip():
            continue
        try:
            req = json.loads(line)
            handler = {"pymeshlab-quadric": decimate, "scan": scan, "scan-end-to-end": scan_end_to_end,
                       "libigl-signed-distance": signed_distance}.get(req.get("peer"), run)
            ms, nv, nf = handler(req)
            print(json.dumps({"ms": ms, "vertices": int(nv), "triangles": int(nf)}), flush=True)
        except Exception as e:  # noqa: BLE001
            print(json.dumps({"error": f"{type(e).__name__}: {e}"}), flush=True)


if __name__ == "__main__":
    main()
