#!/usr/bin/env bash
# The Python package as it would be published: maturin builds the abi3 wheel into target/wheels,
# `twine check` reads its metadata, a clean virtual environment (target/wheel-venv) installs the
# wheel and the tests' requirements and runs the Python tests against it (from python/tests, so
# the source folder is not on the path), and mypy's stubtest holds the type stubs to what the
# installed package really has (python/stubtest-allowlist.txt: the native module's names).
set -euo pipefail
cd "$(dirname "$0")/.."
TOOLS=target/package-venv
[ -x "$TOOLS/bin/python" ] || python3 -m venv "$TOOLS"
"$TOOLS/bin/python" -m pip install --quiet --upgrade pip
"$TOOLS/bin/python" -m pip install --quiet maturin==1.16.0 twine==7.0.0
rm -rf target/wheels
"$TOOLS/bin/maturin" build --release --quiet -m python/Cargo.toml --out target/wheels
wheel=$(ls target/wheels/isolab-*.whl)
case "$wheel" in
  *-abi3-*) ;;
  *) echo "error: $wheel is not an abi3 wheel" >&2; exit 1 ;;
esac
"$TOOLS/bin/twine" check --strict "$wheel"
VENV=target/wheel-venv
rm -rf "$VENV"
python3 -m venv "$VENV"
"$VENV/bin/python" -m pip install --quiet --upgrade pip
"$VENV/bin/python" -m pip install --quiet -r python/tests/requirements.txt mypy==2.4.1
"$VENV/bin/python" -m pip install --quiet --no-deps "$wheel"
cargo build --release --quiet -p isolab-cli --bin isolab
cd python/tests
ISOLAB_CLI="$PWD/../../target/release/isolab" "../../$VENV/bin/python" -m pytest -q -p no:cacheprovider . \
  --doctest-modules --pyargs isolab
"../../$VENV/bin/python" -m mypy.stubtest isolab --allowlist ../stubtest-allowlist.txt
