"""The guides' Python examples run as written (docs/*.md): each page's ```python blocks in order
in one namespace, in a fresh folder that holds the small zarr stores they name (stack.zarr, a
ball; seg.zarr, two labels), with the Dask cluster a block starts closed afterwards. A block
that cannot run here says why in a `<!-- not run: REASON -->` line just above it."""

import faulthandler
import os
import re
from pathlib import Path

import numpy as np
import pytest

DOCS = Path(__file__).resolve().parents[2] / "docs"
NOT_RUN = re.compile(r"<!-- not run: (.+?) -->\s*$")
# A page's examples, its Dask cluster included, end within this or the run stops with their stacks.
TIME_BOUND_S = 300


def examples(page):
    """The page's Python blocks, each with its line and the reason it is not run (or None)."""
    lines = page.read_text().splitlines()
    out, i = [], 0
    while i < len(lines):
        if lines[i].strip() == "```python":
            start = i + 1
            end = next(j for j in range(start, len(lines)) if lines[j].startswith("```"))
            above = next((lines[j] for j in range(i - 1, -1, -1) if lines[j].strip()), "")
            reason = NOT_RUN.search(above)
            out.append((start + 1, "\n".join(lines[start:end]) + "\n", reason.group(1) if reason else None))
            i = end
        i += 1
    return out


PAGES = sorted(p for p in DOCS.glob("*.md") if examples(p))


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
