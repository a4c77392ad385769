#!/usr/bin/env bash
# Copies the pinned three.js files (package-lock.json) into report/vendor/three, the only
# JavaScript the report's index.html loads besides its own viewer.js (no network at view time).
# `--check` compares instead and fails if the committed copies differ from the pinned package.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
dest="$here/../../report/vendor/three"
files=(build/three.min.js examples/js/loaders/GLTFLoader.js examples/js/controls/OrbitControls.js LICENSE)
[ -d "$here/node_modules/three" ] || (cd "$here" && npm ci --no-audit --no-fund --silent)
if [ "${1:-}" = "--check" ]; then
  for f in "${files[@]}"; do
    cmp -s "$here/node_modules/three/$f" "$dest/$(basename "$f")" || { echo "report/vendor/three/$(basename "$f") differs from three $(node -p "require('$here/node_modules/three/package.json').version")'s $f: run tests/browser/vendor.sh" >&2; exit 1; }
  done
  echo "report/vendor/three matches the pinned three.js"
else
  mkdir -p "$dest"
  for f in "${files[@]}"; do cp "$here/node_modules/three/$f" "$dest/"; done
  echo "copied ${#files[@]} files into report/vendor/three"
fi
