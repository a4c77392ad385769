#!/usr/bin/env bash
# Live reference check: builds isolab, writes meshes, and has independent libraries (VTK's
# vtkMassProperties / vtkMeshQuality / vtkFeatureEdges, pymeshlab's topological measures) measure
# them. The virtual environment lives in tests/reference/.venv with pinned versions.
# `run.sh setup` only creates that environment.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
venv="$here/.venv"
if [ ! -x "$venv/bin/python" ] || ! "$venv/bin/python" -c "import vtk, pymeshlab, CGAL, igl, skimage, scipy, mcubes, tetgen" 2>/dev/null; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install --quiet --disable-pip-version-check -r "$here/requirements.txt"
fi
if [ "${1:-}" = "setup" ]; then
  exit 0  # the environment only (the `peers` experiment's Python peers use it)
fi
cargo build --release --quiet -p isolab-experiments --bin isolab
"$venv/bin/python" "$here/reference.py" live --isolab "$root/target/release/isolab"
