"""The guides' examples run as written (docs/*.md), each page in a fresh folder that holds the
small zarr stores they name (stack.zarr, a ball; seg.zarr, two labels):
- its ```python blocks in order in one namespace, with the Dask cluster a block starts closed
  afterwards;
- its command-line blocks (```sh blocks that call `./target/release/isolab`) in order, each as a
  bash script (`set -euo pipefail`), in a folder laid out as a clone (`models/`, `tests/`, and
  `target/release/isolab`, the binary the Rust tests built: ISOLAB_CLI). The other ```sh blocks
  are the install, test and report commands, which CI runs itself.
A block that cannot run here says why in a `<!-- not run: REASON -->` line just above it."""

import faulthandler
import os
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

DOCS = Path(__file__).resolve().parents[2] / "docs"
NOT_RUN = re.compile(r"<!-- not run: (.+?) -->\s*$")
# A page's examples, its Dask cluster included, end within this or the run stops with their stacks.
TIME_BOUND_S = 300


def examples(page, language="python"):
    """The page's blocks in `language`, each with its line and the reason it is not run (or None)."""
    lines = page.read_text().splitlines()
    out, i = [], 0
    while i < len(lines):
        if lines[i].strip() == "```" + language:
            start = i + 1
            end = next(j for j in range(start, len(lines)) if lines[j].startswith("```"))
            above = next((lines[j] for j in range(i - 1, -1, -1) if lines[j].strip()), "")
            reason = NOT_RUN.search(above)
            out.append((start + 1, "\n".join(lines[start:end]) + "\n", reason.group(1) if reason else None))
            i = end
        i += 1
    return out


PAGES = sorted(p for p in DOCS.glob("*.md") if examples(p))


def command_lines(page):
    """The page's command-line blocks: its ```sh blocks that call the isolab binary."""
    return [(line, code, why) for line, code, why in examples(page, "sh") if "./target/release/isolab " in code]


CLI_PAGES = sorted(p for p in DOCS.glob("*.md") if command_lines(p))


def make_stores(folder):
    import zarr
    i, j, k = np.mgrid[-1:1:48j, -1:1:48j, -1:1:48j]
    zarr.save_array(str(folder / "stack.zarr"), (i**2 + j**2 + k**2).astype(np.float32))
    seg = np.zeros((48, 48, 48), np.uint8)
    seg[8:24, 8:40, 8:40] = 1
    seg[24:40, 8:40, 8:40] = 2
    zarr.save_array(str(folder / "seg.zarr"), seg)


def test_the_guides_have_examples_and_say_why_one_is_not_run():
    assert {p.name for p in PAGES} >= {"python.md", "choosing.md"}
    skipped = [(p.name, line, why) for p in PAGES for line, _, why in examples(p) if why]
    assert all(why.strip() for _, _, why in skipped)
    assert len(skipped) <= 1, f"more examples left unrun than the TLS one: {skipped}"


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_a_guides_python_examples_run(page, tmp_path, monkeypatch):
    make_stores(tmp_path)
    monkeypatch.chdir(tmp_path)
    namespace = {}
    faulthandler.dump_traceback_later(TIME_BOUND_S, exit=True)
    try:
        for line, code, why in examples(page):
            if why is None:
                exec(compile(code, f"{page}:{line}", "exec"), namespace)
    finally:
        client = namespace.get("client")
        if client is not None:
            cluster = getattr(client, "cluster", None)
            client.close()
            if cluster is not None:
                cluster.close()
        faulthandler.cancel_dump_traceback_later()
    made = sorted(os.listdir(tmp_path))
    assert made, "the examples wrote nothing"
    if page.name == "python.md":
        assert {"stack.glb", "left.glb", "seg"} <= set(made), made
        assert (tmp_path / "seg" / "mesh" / "info").is_file(), "no neuroglancer source"


def test_the_guides_have_command_line_examples_and_run_every_one():
    assert {p.name for p in CLI_PAGES} >= {"cli.md", "python.md", "choosing.md"}
    assert sum(len(command_lines(p)) for p in CLI_PAGES) >= 10
    skipped = [(p.name, line) for p in CLI_PAGES for line, _, why in command_lines(p) if why]
    assert not skipped, f"command-line examples left unrun: {skipped}"


@pytest.mark.parametrize("page", CLI_PAGES, ids=lambda p: p.name)
def test_a_guides_command_line_examples_run(page, tmp_path):
    cli = os.environ.get("ISOLAB_CLI")
    if not cli:
        pytest.fail("ISOLAB_CLI names the isolab binary (tests/all.sh sets it)")
    root = DOCS.parent
    make_stores(tmp_path)
    for shipped in ["models", "tests"]:
        (tmp_path / shipped).symlink_to(root / shipped)
    (tmp_path / "target" / "release").mkdir(parents=True)
    (tmp_path / "target" / "release" / "isolab").symlink_to(Path(cli).resolve())
    before = set(os.listdir(tmp_path))
    printed = ""
    for line, code, why in command_lines(page):
        run = subprocess.run(["bash", "-c", "set -euo pipefail\n" + code], cwd=tmp_path, capture_output=True, text=True,
                             timeout=TIME_BOUND_S)
        assert run.returncode == 0, f"{page.name}:{line}: exit {run.returncode}\n{run.stderr[-2000:]}"
        printed += run.stdout
    made = set(os.listdir(tmp_path)) - before
    assert made or page.name == "choosing.md", "the examples wrote nothing"
    if page.name == "choosing.md":
        assert "marching-cubes" in printed and "guarantees:" in printed, printed[:500]
    if page.name == "cli.md":
        assert {"sphere.obj", "bunny.png", "brain.glb", "head-dc.glb", "spot-boundary.vtk", "sphere.vtk", "seg.glb", "meshes",
                "seg.vtk", "seg.msh"} <= made, made
    if page.name == "python.md":
        assert {"stack.ply", "seg.glb", "meshes", "seg-mesh"} <= made, made
        assert (tmp_path / "seg-mesh" / "info").is_file(), "no neuroglancer source"
