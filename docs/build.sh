#!/usr/bin/env bash
# Builds the documentation site into target/site with MkDocs (mkdocs.yml; the tools pinned in
# docs/requirements.txt, installed into target/docs-venv): first the command line's reference,
# docs/reference/cli.md, from `isolab --help` and each command's --help (generated, not
# committed), then `mkdocs build --strict`, which fails on any warning. Open
# target/site/index.html, or `target/docs-venv/bin/mkdocs serve` to browse while editing.
set -euo pipefail
cd "$(dirname "$0")/.."
VENV=target/docs-venv
[ -x "$VENV/bin/python" ] || python3 -m venv "$VENV"
"$VENV/bin/python" -m pip install --quiet --upgrade pip
"$VENV/bin/python" -m pip install --quiet -r docs/requirements.txt
cargo build --release --quiet -p isolab-cli --bin isolab
isolab=target/release/isolab
{
  echo "# Command-line reference"
  echo
  echo "Generated from the binary's own help by \`docs/build.sh\`; the [guide](../cli.md) has examples."
  echo
  echo '```text'
  "$isolab" --help
  echo '```'
  # The commands, as clap lists them under "Commands:" (help itself left out).
  for command in $("$isolab" --help | sed -n '/^Commands:/,/^$/p' | awk 'NR > 1 && NF && $1 != "help" {print $1}'); do
    echo
    echo "## isolab $command"
    echo
    echo '```text'
    "$isolab" "$command" --help
    echo '```'
  done
} > docs/reference/cli.md.tmp
mv docs/reference/cli.md.tmp docs/reference/cli.md
# NO_MKDOCS_2_WARNING: the Material theme prints a banner on its end of life (May 2027) at every
# build; docs/contributing.md says so once.
NO_MKDOCS_2_WARNING=1 "$VENV/bin/mkdocs" build --strict --quiet
echo "wrote target/site/index.html"
