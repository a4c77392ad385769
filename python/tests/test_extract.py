"""isolab.extract, Mesh.metrics, isolab.metrics, Mesh.save and isolab.load, against the CLI."""

import json
import os
import subprocess
import threading
import time

import numpy as np
import pytest

import isolab

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
CLI = os.environ.get("ISOLAB_CLI", os.path.join(ROOT, "target", "release", "isolab"))
needs_cli = pytest.mark.skipif(not os.path.exists(CLI), reason=f"no CLI at {CLI} (tests/all.sh builds it)")

EXTRACTORS = [a for a in isolab.algorithms() if a["kind"] == "extractor"]


def cli(*args):
    out = subprocess.run([CLI, *args], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    return out


def test_algorithms_come_from_the_registry_with_guarantees():
    names = [a["name"] for a in EXTRACTORS]
    listed = cli("list").stdout if os.path.exists(CLI) else ""
    assert "marching-cubes" in names and "surface-nets" in names and "bcc-sculpt" in names
    for a in isolab.algorithms():
        assert a["description"] and set(a["guarantees"]) and (not listed or a["name"] in listed)


@needs_cli
@pytest.mark.parametrize("algorithm", [a["name"] for a in EXTRACTORS])
def test_every_extractor_gives_the_clis_mesh_and_metrics(tmp_path, algorithm):
    lattice = "cubic" if "cubic" in next(a for a in EXTRACTORS if a["name"] == algorithm)["guarantees"]["lattices"] else "bcc"
    field, res = ("sphere", 20) if algorithm != "bcc-sculpt" else ("models/spot.obj", 16)
    spec = os.path.join(ROOT, field) if "/" in field else field
    out = tmp_path / "m.ply"
    cli("extract", "-a", algorithm, "-f", spec, "-r", str(res), "--lattice", lattice, "-o", str(out), "-m", str(tmp_path / "m.json"))
    theirs_v, theirs_f = isolab.load(out)
    mesh = isolab.extract(spec, algorithm=algorithm, resolution=res, lattice=lattice)
    assert mesh.faces.shape == theirs_f.shape and mesh.vertices.shape == theirs_v.shape
    np.testing.assert_array_equal(mesh.faces, theirs_f)
    np.testing.assert_allclose(mesh.vertices, theirs_v, atol=1e-6)
    # Metrics equal the CLI's -m, the true surface included.
    ours = mesh.metrics()
    report = json.load(open(tmp_path / "m.json"))
    for key in ["vertices", "triangles", "closed", "edge_manifold", "oriented", "genus", "euler", "boundary_edges",
                "degenerate_triangles", "aspect_ratio", "min_angle_deg", "volume", "area", "surface_distance"]:
        assert ours.get(key) == report.get(key), key
    assert "self_intersections" not in ours
    assert mesh.stats["algorithm"] == algorithm and mesh.stats["triangles"] == len(mesh.faces)


def test_an_array_meshes_in_world_coordinates_through_spacing_or_affine():
    i, j, k = np.mgrid[-1:1:33j, -1:1:33j, -1:1:33j]
    sdf = np.sqrt(i**2 + j**2 + k**2) - 0.6
    h = 2 / 32
    by_spacing = isolab.extract(sdf, 0.0, "marching-cubes", spacing=(h, h, h))
    affine = np.diag([h, h, h, 1.0])
    affine[:3, 3] = -1.0
    by_affine = isolab.extract(sdf, 0.0, "marching-cubes", affine=affine)
    r = np.linalg.norm(by_affine.vertices, axis=1)
    assert np.abs(r - 0.6).max() < 0.01
    np.testing.assert_allclose(by_spacing.vertices - 1.0, by_affine.vertices, atol=1e-5)
    m = by_affine.metrics()
    assert m["closed"] and m["genus"] == 0 and m["volume"] > 0  # outward: inside is below
    # The same array in Fortran order and as a strided view: the same mesh.
    for arr in (np.asfortranarray(sdf), np.pad(sdf, ((0, 0), (0, 0), (0, 5)))[:, :, :33]):
        other = isolab.extract(arr, 0.0, "marching-cubes", affine=affine)
        assert other.faces.shape == by_affine.faces.shape
        assert abs(other.metrics()["volume"] - m["volume"]) < 1e-6 * abs(m["volume"])


def test_inside_above_meshes_a_bright_object_outward():
    vol = np.zeros((20, 20, 20), np.uint8)
    vol[5:15, 6:14, 4:16] = 200
    mesh = isolab.extract(vol, 100, "surface-nets", inside="above")
    m = mesh.metrics(self_intersections=True)
    assert m["closed"] and m["volume"] > 0 and m["self_intersections"]["count"] == 0


def test_options_post_processes_threads_and_materials():
    a = isolab.extract("torus", algorithm="surface-nets", resolution=32, options={"smoothing": "elastic"}, threads=1)
    b = isolab.extract("torus", algorithm="surface-nets", resolution=32, options={"smoothing": "elastic"}, threads=2)
    np.testing.assert_array_equal(a.faces, b.faces)
    c = isolab.extract("torus", algorithm="marching-tetrahedra", resolution=32, post=["edge-collapse"])
    assert c.stats["post"] == ["edge-collapse"] and c.metrics()["genus"] == 1
    # Two boxes of different sizes: keep-components keeps the larger, or both above a volume.
    vol = np.zeros((24, 20, 20), dtype=np.uint8)
    vol[2:12, 3:15, 3:15] = 200
    vol[16:20, 5:9, 5:9] = 200
    both = isolab.extract(vol, 100, "marching-cubes", inside="above")
    big = isolab.extract(vol, 100, "marching-cubes", inside="above", post=["keep-components:largest=1"])
    assert both.metrics()["components"] == 2 and big.metrics()["components"] == 1
    assert big.metrics()["volume"] > 0.8 * both.metrics()["volume"]
    kept = isolab.extract(vol, 100, "marching-cubes", inside="above", post=["keep-components:largest=0,min-volume=20"])
    assert kept.metrics()["components"] == 2
    with pytest.raises(ValueError, match="min-volume"):
        isolab.extract(vol, 100, "marching-cubes", inside="above", post=["keep-components:min-volume=x"])
    t = isolab.extract("terrain", algorithm="marching-cubes", resolution=24, materials=True)
    assert t.materials is not None and t.materials.shape == (len(t.vertices),)


def test_volume_extractors_give_tetrahedra(tmp_path):
    mesh = isolab.extract(os.path.join(ROOT, "models", "spot.obj"), algorithm="bcc-sculpt", resolution=16)
    assert mesh.tetrahedra is not None and mesh.tetrahedra.shape[1] == 4
    assert mesh.tetrahedra.max() < len(mesh.tet_vertices)
    assert "dihedral_deg" in mesh.metrics()
    mesh.save(tmp_path / "spot.ply")
    assert (tmp_path / "spot.ply").exists() and (tmp_path / "spot.vtk").exists()


@pytest.mark.parametrize("ext", ["obj", "ply", "stl", "glb", "gltf"])
def test_save_writes_every_format_load_reads_back(tmp_path, ext):
    mesh = isolab.extract("sphere", algorithm="marching-cubes", resolution=24)
    path = tmp_path / f"s.{ext}"
    mesh.save(path)
    v, f = isolab.load(path)
    assert len(f) == len(mesh.faces)
    assert isolab.metrics(v, f)["euler"] == 2


def test_load_gives_a_volume_and_its_affine(tmp_path):
    grid = tmp_path / "g.raw"
    cli_ok = os.path.exists(CLI)
    if not cli_ok:
        pytest.skip("needs the CLI to write a grid")
    cli("extract", "-a", "marching-cubes", "-f", "sphere", "-r", "17", "--samples-out", str(grid))
    values, affine = isolab.load(grid)
    assert values.shape == (17, 17, 17) and values.dtype == np.float32 and affine.shape == (4, 4)
    # The grid meshed from the array gives the CLI's mesh of the same grid.
    mesh = isolab.extract(values, 0.0, "marching-cubes", affine=affine)
    out = tmp_path / "m.ply"
    cli("extract", "-a", "marching-cubes", "-f", str(grid), "-o", str(out))
    v, f = isolab.load(out)
    assert mesh.faces.shape == f.shape
    np.testing.assert_allclose(np.sort(mesh.vertices, axis=0), np.sort(v, axis=0), atol=1e-5)


def test_the_gil_is_released_while_an_extraction_runs():
    i, j, k = np.mgrid[-1:1:160j, -1:1:160j, -1:1:160j]
    vol = (np.sin(8 * i) * np.cos(8 * j) + np.sin(8 * j) * np.cos(8 * k) + np.sin(8 * k) * np.cos(8 * i)).astype(np.float32)
    ticks = 0
    done = threading.Event()

    def work():
        for _ in range(3):
            isolab.extract(vol, 0.0, "surface-nets", threads=1)
        done.set()

    worker = threading.Thread(target=work)
    start = time.perf_counter()
    worker.start()
    while not done.is_set():
        ticks += 1
        time.sleep(0)
    worker.join()
    # This thread kept running Python code while the other meshed (a held GIL would let it
    # run only between the calls).
    assert ticks > 100, (ticks, time.perf_counter() - start)


BAD = [
    (lambda: isolab.extract("sphere", algorithm="marching-squares"), ValueError, "unknown algorithm 'marching-squares'; valid algorithms: .*marching-cubes"),
    (lambda: isolab.extract("sphere", algorithm="surface-nets", options={"smoothing": "gauss"}), ValueError, "smoothing"),
    (lambda: isolab.extract("sphere", algorithm="surface-nets", options={"no-such-option": "1"}), ValueError, "no-such-option"),
    (lambda: isolab.extract("sphere", post=["no-such-post"]), ValueError, "unknown post-process"),
    (lambda: isolab.extract("no-such-field"), ValueError, "no-such-field"),
    (lambda: isolab.extract("sphere", resolution=1), ValueError, "resolution|samples"),
    (lambda: isolab.extract(np.full((4, 4, 4), np.nan)), ValueError, "not finite|NaN"),
    (lambda: isolab.extract(np.zeros((4, 4))), ValueError, "3-D"),
    (lambda: isolab.extract(np.zeros((4, 4, 4)), inside="left"), ValueError, "inside"),
    (lambda: isolab.extract(np.zeros((4, 4, 4)), affine=np.eye(3)), ValueError, "4 x 4"),
    (lambda: isolab.extract("/no/such/file.nii"), OSError, "/no/such/file.nii"),
    (lambda: isolab.extract("sphere", threads=0), ValueError, "threads"),
    (lambda: isolab.extract("sphere", resolution=16).save("/no/such/dir/m.ply"), OSError, "/no/such/dir/m.ply"),
    (lambda: isolab.extract("sphere", resolution=16).save("m.xyz"), ValueError, "m.xyz"),
    (lambda: isolab.metrics(np.zeros((3, 3)), np.array([[0, 1, 5]])), ValueError, "index 5"),
    (lambda: isolab.metrics(np.zeros((3, 2)), np.array([[0, 1, 2]])), ValueError, "N x 3"),
    (lambda: isolab.load("/no/such/mesh.obj"), OSError, "/no/such/mesh.obj"),
]


@pytest.mark.parametrize("call,kind,message", BAD)
def test_bad_input_raises_the_clis_message_never_a_panic(call, kind, message):
    with pytest.raises(kind, match=message) as raised:
        call()
    assert "PanicException" not in type(raised.value).__name__
