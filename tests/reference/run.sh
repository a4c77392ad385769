#!/usr/bin/env bash
# Live reference check: builds isolab, writes meshes, and has independent libraries (VTK's
# vtkMassProperties / vtkMeshQuality / vtkFeatureEdges, pymeshlab's topological measures) measure
# them. The virtual environment lives in tests/reference/.venv with pinned versions.
# `run.sh setup` only creates that environment.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
venv="$here/.venv"
if [ ! -x "$venv/bin/python" ] || ! "$venv/bin/python" -c "import vtk, pymeshlab, CGAL, igl, skimage, scipy, mcubes, tetgen, nibabel, nilearn, nrrd, SimpleITK, netgen.stl, pytetwild, zmesh, dask, distributed, zarr, warp, meshlib, marching_cubes, neuroglancer, cloudvolume, DracoPy, igneous" 2>/dev/null; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install --quiet --disable-pip-version-check -r "$here/requirements.txt"
fi
# The C++ decimators the `decimation` experiment runs (CGAL's edge_collapse, OpenMesh's
# Decimater): Debian's libcgal-dev and libopenmesh-dev, installed when missing and possible, and
# two small programs built into tests/reference/.bin when missing or older than their source (and
# a third, CGAL Mesh_3 on labeled images, beside them).
# Without them the experiment lists those decimators as not run, with this script's note.
build_decimators() {
  local bin="$here/.bin" src="$here/decimators"
  mkdir -p "$bin"
  if ! dpkg -s libcgal-dev libopenmesh-dev >/dev/null 2>&1; then
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
      export DEBIAN_FRONTEND=noninteractive
      apt-get install -y -qq --no-install-recommends libcgal-dev libopenmesh-dev >/dev/null \
        || { apt-get update -qq && apt-get install -y -qq --no-install-recommends libcgal-dev libopenmesh-dev >/dev/null; } \
        || echo "note: could not install Debian's libcgal-dev and libopenmesh-dev" >&2
    else
      echo "note: Debian's libcgal-dev and libopenmesh-dev are missing (install them as root)" >&2
    fi
  fi
  if [ ! -x "$bin/cgal_edge_collapse" ] || [ "$src/cgal_edge_collapse.cpp" -nt "$bin/cgal_edge_collapse" ]; then
    g++ -O2 -std=c++17 "$src/cgal_edge_collapse.cpp" -o "$bin/cgal_edge_collapse" -lgmp -lmpfr \
      || echo "note: could not build tests/reference/decimators/cgal_edge_collapse.cpp" >&2
  fi
  if [ ! -x "$bin/openmesh_decimater" ] || [ "$src/openmesh_decimater.cpp" -nt "$bin/openmesh_decimater" ]; then
    g++ -O2 -std=c++17 "$src/openmesh_decimater.cpp" -o "$bin/openmesh_decimater" -lOpenMeshTools -lOpenMeshCore \
      || echo "note: could not build tests/reference/decimators/openmesh_decimater.cpp" >&2
  fi
  # CGAL Mesh_3 on labeled images, the peer of lattice-cleaving (mesh3/labeled_vs_cleaving.py).
  if [ ! -x "$bin/cgal_labeled_image" ] || [ "$here/mesh3/cgal_labeled_image.cpp" -nt "$bin/cgal_labeled_image" ]; then
    g++ -O2 -std=c++17 "$here/mesh3/cgal_labeled_image.cpp" -o "$bin/cgal_labeled_image" -lgmp -lmpfr \
      || echo "note: could not build tests/reference/mesh3/cgal_labeled_image.cpp" >&2
  fi
}
build_decimators
# The Khronos glTF validator (npm, pinned by package-lock.json), for isolab's .glb/.gltf outputs.
if [ ! -d "$here/node_modules/gltf-validator" ]; then
  if command -v npm >/dev/null; then
    (cd "$here" && npm ci --no-audit --no-fund --silent) || echo "note: could not install gltf-validator with npm" >&2
  else
    echo "note: npm is missing: the glTF validator check will fail" >&2
  fi
fi
if [ "${1:-}" = "setup" ]; then
  exit 0  # the environment only (the `peers` experiment's Python peers use it)
fi
cargo build --release --quiet -p isolab-cli --bin isolab
"$venv/bin/python" "$here/reference.py" live --isolab "$root/target/release/isolab"
# Neuroglancer sources (isolab labels --format neuroglancer): cloud-volume reads every segment at
# every level, then neuroglancer's own viewer draws them in headless Chromium (Debian's chromium
# and playwright-core from tests/browser, installed there when missing).
ng_data="$root/target/neuroglancer-check"
segments=$("$venv/bin/python" "$here/precomputed.py" "$root/target/release/isolab" "$ng_data" \
  | "$venv/bin/python" -c 'import json, sys; print(",".join(map(str, json.load(sys.stdin)["segments"][:12])))')
[ -d "$root/tests/browser/node_modules/playwright-core" ] || (cd "$root/tests/browser" && npm ci --no-audit --no-fund --silent)
node "$root/tests/browser/neuroglancer.mjs" "$venv/bin/python" "$here/ng_viewer.py" "$ng_data" "$segments" "$(command -v chromium)"
