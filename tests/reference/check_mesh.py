"""Independent check of isolab's meshes and metrics.

For each case, `isolab extract` writes a binary PLY mesh and its metrics JSON; VTK and pymeshlab
then measure the mesh themselves:
- counts (vtkPLYReader points and cells),
- volume and area (vtkMassProperties),
- Verdict triangle aspect ratio mean and max (vtkMeshQuality, AspectRatio),
- boundary and non-manifold edges (vtkFeatureEdges),
- genus, components, two-manifoldness (pymeshlab get_topological_measures).
Each comparison is one check; the script ends with the line 'N passed, M failed' and exits
non-zero when any failed.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

import pymeshlab
import vtk
from vtk.util.numpy_support import vtk_to_numpy

CASES = [
    # (field, resolution, expected genus)
    ("sphere", 64, 0),
    ("torus", 64, 1),
    ("csg", 64, 0),
    ("asteroid", 64, 0),
    ("rocker-arm.obj", 96, 1),
    ("stanford-bunny.obj", 64, 0),
]

passed = 0
failed = 0


def check(name, ok, detail):
    global passed, failed
    if ok:
        passed += 1
        print(f"ok    {name}: {detail}")
    else:
        failed += 1
        print(f"FAIL  {name}: {detail}")


def close(a, b, rel, abs_=0.0):
    return abs(a - b) <= max(rel * max(abs(a), abs(b)), abs_)


def vtk_measures(path):
    reader = vtk.vtkPLYReader()
    reader.SetFileName(path)
    reader.Update()
    poly = reader.GetOutput()
    mass = vtk.vtkMassProperties()
    mass.SetInputData(poly)
    mass.Update()
    quality = vtk.vtkMeshQuality()
    quality.SetInputData(poly)
    quality.SetTriangleQualityMeasureToAspectRatio()
    quality.Update()
    q = vtk_to_numpy(quality.GetOutput().GetCellData().GetArray("Quality"))
    finite = q[(q > 0) & (q < 1e300)]
    edges = vtk.vtkFeatureEdges()
    edges.SetInputData(poly)
    edges.BoundaryEdgesOn()
    edges.NonManifoldEdgesOff()
    edges.FeatureEdgesOff()
    edges.ManifoldEdgesOff()
    edges.Update()
    boundary = edges.GetOutput().GetNumberOfCells()
    edges.BoundaryEdgesOff()
    edges.NonManifoldEdgesOn()
    edges.Update()
    non_manifold = edges.GetOutput().GetNumberOfCells()
    return {
        "vertices": poly.GetNumberOfPoints(),
        "triangles": poly.GetNumberOfCells(),
        "volume": mass.GetVolume(),
        "area": mass.GetSurfaceArea(),
        "aspect_mean": float(finite.mean()),
        "aspect_max": float(finite.max()),
        "boundary_edges": boundary,
        "non_manifold_edges": non_manifold,
    }


def meshlab_measures(path):
    ms = pymeshlab.MeshSet()
    ms.load_new_mesh(path)
    return ms.get_topological_measures()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--isolab", required=True)
    ap.add_argument("--models", required=True)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        for field, resolution, genus in CASES:
            spec = os.path.join(args.models, field) if field.endswith(".obj") else field
            name = f"{field}@{resolution}"
            mesh = os.path.join(tmp, "m.ply")
            metrics = os.path.join(tmp, "m.json")
            subprocess.run(
                [args.isolab, "extract", "--algorithm", "marching-cubes", "--field", spec,
                 "--resolution", str(resolution), "--output", mesh, "--metrics", metrics],
                check=True,
            )
            ours = json.load(open(metrics))
            v = vtk_measures(mesh)
            m = meshlab_measures(mesh)
            check(name, v["vertices"] == ours["vertices"] and v["triangles"] == ours["triangles"],
                  f"counts vtk {v['vertices']}/{v['triangles']} ours {ours['vertices']}/{ours['triangles']}")
            check(name, close(v["volume"], ours["volume"], 1e-5), f"volume vtk {v['volume']:.7f} ours {ours['volume']:.7f}")
            check(name, close(v["area"], ours["area"], 1e-5), f"area vtk {v['area']:.7f} ours {ours['area']:.7f}")
            check(name, close(v["aspect_mean"], ours["aspect_ratio"]["mean"], 1e-4),
                  f"aspect mean vtk {v['aspect_mean']:.6f} ours {ours['aspect_ratio']['mean']:.6f}")
            check(name, close(v["aspect_max"], ours["aspect_ratio"]["max"], 1e-3),
                  f"aspect max vtk {v['aspect_max']:.4f} ours {ours['aspect_ratio']['max']:.4f}")
            check(name, v["boundary_edges"] == ours["boundary_edges"] and v["non_manifold_edges"] == ours["non_manifold_edges"],
                  f"boundary/non-manifold edges vtk {v['boundary_edges']}/{v['non_manifold_edges']} ours {ours['boundary_edges']}/{ours['non_manifold_edges']}")
            check(name, m["is_mesh_two_manifold"] and m["genus"] == ours["genus"] == genus,
                  f"genus meshlab {m['genus']} ours {ours['genus']} expected {genus}, two-manifold {m['is_mesh_two_manifold']}")
            check(name, m["connected_components_number"] == ours["components"],
                  f"components meshlab {m['connected_components_number']} ours {ours['components']}")
            check(name, ours["volume"] > 0 and ours["outward"], f"outward, volume {ours['volume']:.6f}")
    print(f"{passed} passed, {failed} failed")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
