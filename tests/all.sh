#!/usr/bin/env bash
# The README's test command: the Rust tests (cargo test --workspace --release), then the Python
# package's (python/tests with pytest, and the docstrings' examples as doctests), built with
# maturin into a virtual environment this script creates (target/python-venv; python3 with venv
# and pip, packages from PyPI). The Python tests compare with scikit-image and with the CLI
# binary the Rust tests built (target/release/isolab).
set -euo pipefail
cd "$(dirname "$0")/.."
step_start=$SECONDS
step() {
  [ -n "${step_name:-}" ] && echo "   ($step_name: $((SECONDS - step_start)) s)"
  step_name="$1"; step_start=$SECONDS; echo "== $1"
}
trap 'step done' EXIT

step "Rust tests"
cargo test --workspace --release

step "Python package: build into target/python-venv"
VENV=target/python-venv
[ -x "$VENV/bin/python" ] || python3 -m venv "$VENV"
"$VENV/bin/python" -m pip install --quiet --upgrade pip
"$VENV/bin/python" -m pip install --quiet -r python/tests/requirements.txt
# The package as a user installs it (maturin is its build backend, fetched by pip); --no-deps:
# numpy is there already.
"$VENV/bin/python" -m pip install --quiet --no-deps --force-reinstall ./python
cargo build --release --quiet -p isolab-cli --bin isolab

step "Python tests (pytest, and the docstrings' examples)"
cd python/tests  # not python/: the installed package is tested, not the source folder
ISOLAB_CLI="$PWD/../../target/release/isolab" "../../$VENV/bin/python" -m pytest -q -p no:cacheprovider . \
  --doctest-modules --pyargs isolab
