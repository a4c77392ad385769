"""The CLI and the package keep one set of front-end rules, held by `isolab_pipeline`: the
registry's listing (`registry`), the words settings take (`config`: `str::parse` for every
enum), what a file holds and how a run's meshes are written (`files`). These tests hold the two
front ends to the same answers."""

import os
import subprocess

import numpy as np
import pytest
import zarr

import isolab

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
CLI = os.environ.get("ISOLAB_CLI", os.path.join(ROOT, "target", "release", "isolab"))
needs_cli = pytest.mark.skipif(not os.path.exists(CLI), reason=f"no CLI at {CLI} (tests/all.sh builds it)")


def cli(*args, ok=True):
    out = subprocess.run([CLI, *args], capture_output=True, text=True)
    assert (out.returncode == 0) == ok, out.stderr
    return out


@needs_cli
def test_isolab_list_prints_the_listing_python_returns():
    lines = [line.strip() for line in cli("list").stdout.splitlines()]
    entries = isolab.algorithms()
    assert {e["kind"] for e in entries} == {"extractor", "post-process", "labels"}
    for e in entries:
        # The name's line has the description (a label extractor may share an extractor's name);
        # the promises line follows it, after the options.
        at = next(i for i, line in enumerate(lines) if line.split()[:1] == [e["name"]] and line.endswith(e["description"]))
        assert e["promises"] in lines[at + 1:at + 3], (e["name"], e["promises"], lines[at:at + 3])
        if e["kind"] == "extractor":
            closed = e["guarantees"]["closed"]
            assert ("closed" in e["promises"].split("guarantees:")[1]) == closed, e["name"]


def test_settings_take_their_words_in_any_case_and_name_the_choices_otherwise():
    lower = isolab.extract("sphere", algorithm="marching-tetrahedra", resolution=12, lattice="bcc")
    upper = isolab.extract("sphere", algorithm="marching-tetrahedra", resolution=12, lattice="BCC")
    np.testing.assert_array_equal(lower.faces, upper.faces)
    assert upper.stats["lattice"] == "bcc"
    with pytest.raises(ValueError, match="lattice 'hexagonal': expected 'cubic' or 'bcc'"):
        isolab.extract("sphere", algorithm="marching-cubes", resolution=12, lattice="hexagonal")
    with pytest.raises(ValueError, match="inside 'outside': expected 'above' or 'below'"):
        isolab.extract(np.zeros((4, 4, 4), dtype=np.float32), 0.5, "marching-cubes", inside="outside")


def test_load_reads_a_zarr_store_as_the_cli_does(tmp_path):
    z, y, x = np.mgrid[-1:1:9j, -1:1:7j, -1:1:11j]
    values = (np.sqrt(x**2 + y**2 + z**2) - 0.7).astype(np.float32)
    store = tmp_path / "ball.zarr"
    zarr.create_array(str(store), shape=values.shape, chunks=(4, 4, 4), dtype=values.dtype)[:] = values
    array, affine = isolab.load(store)
    # The store's last axis is x: the array comes back in index order [i, j, k] = (x, y, z).
    np.testing.assert_array_equal(array, values.transpose(2, 1, 0))
    assert affine.shape == (4, 4)


@needs_cli
def test_a_volume_where_a_mesh_is_expected_is_refused_naming_it(tmp_path):
    grid = tmp_path / "g.raw"
    cli("extract", "-a", "marching-cubes", "-f", "sphere", "-r", "9", "--samples-out", str(grid))
    out = cli("metrics", str(grid), ok=False)
    assert "g.raw" in out.stderr and "is a volume, not a mesh" in out.stderr


@needs_cli
def test_saved_materials_are_the_clis_colours(tmp_path):
    ours = tmp_path / "ours.ply"
    theirs = tmp_path / "theirs.ply"
    isolab.extract("terrain", algorithm="marching-cubes", resolution=20, materials=True).save(ours)
    cli("extract", "-a", "marching-cubes", "-f", "terrain", "-r", "20", "--materials", "-o", str(theirs))
    assert ours.read_bytes() == theirs.read_bytes()
    mesh = isolab.extract("sphere", algorithm="marching-cubes", resolution=8)
    mesh.materials = np.zeros(3, dtype=np.uint8)  # not one per vertex
    with pytest.raises(ValueError, match="materials: 3 values for"):
        mesh.save(tmp_path / "bad.ply")
    assert not (tmp_path / "bad.ply").exists()
