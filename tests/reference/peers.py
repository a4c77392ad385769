"""Peer isosurface extractors for isolab's `peers` experiment, as one long-lived subprocess.

Protocol (JSON lines): on start it prints {"available": {peer: version or null}, "errors": {...}};
then for every request line {"raw": PATH, "peer": NAME, "threads": N} it loads the grid written by
`isolab extract --samples-out PATH` (cached between requests), runs the peer once, timing only the
extraction call (grid conversion excluded), and prints {"ms": T, "vertices": V, "triangles": F} or
{"error": MESSAGE}. Peers: vtk-flying-edges (threads 1 or 2: VTK's STDThread SMP backend),
vtk-marching-cubes, skimage-lorensen, skimage-lewiner, pymcubes, libigl. And one decimator:
{"peer": "pymeshlab-quadric", "mesh": PATH, "target": FACES, "out": PATH}.
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
        f = vtk.vtkFlyingEdges3D() if peer == "vtk-flying-edges" else vtk.vtkMarchingCubes()
        f.SetInputData(img)
        f.SetValue(0, iso)
        f.ComputeNormalsOff()
        f.ComputeGradientsOff()
        f.ComputeScalarsOff()
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


def main():
    try:
        import pymeshlab
        available["pymeshlab"] = getattr(pymeshlab, "__version__", "installed")
    except Exception as e:  # noqa: BLE001
        errors["pymeshlab"] = str(e)
    print(json.dumps({"available": available, "errors": errors}), flush=True)
    for line in sys.stdin:
        if not line.strip():
            continue
        try:
            req = json.loads(line)
            ms, nv, nf = decimate(req) if req.get("peer") == "pymeshlab-quadric" else run(req)
            print(json.dumps({"ms": ms, "vertices": int(nv), "triangles": int(nf)}), flush=True)
        except Exception as e:  # noqa: BLE001
            print(json.dumps({"error": f"{type(e).__name__}: {e}"}), flush=True)


if __name__ == "__main__":
    main()
