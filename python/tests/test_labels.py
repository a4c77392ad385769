"""isolab.mesh_labels: label maps from numpy (any integer dtype, C or Fortran order, strided views)
and from files, against the CLI's `isolab labels`; bad input raises."""

import os
import subprocess
import warnings

import numpy as np
import pytest

import isolab

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
CLI = os.environ.get("ISOLAB_CLI", os.path.join(ROOT, "target", "release", "isolab"))
needs_cli = pytest.mark.skipif(not os.path.exists(CLI), reason=f"no CLI at {CLI} (tests/all.sh builds it)")
LABEL_EXTRACTORS = [a["name"] for a in isolab.algorithms() if a["kind"] == "labels"]


def voronoi(shape, labels, seed=7):
    """A label map with triple junctions: every sample the label of its nearest seed (0 among them)."""
    rng = np.random.default_rng(seed)
    seeds = rng.uniform(0, 1, (2 * labels, 3)) * np.array(shape)
    grid = np.stack(np.meshgrid(*[np.arange(n) for n in shape], indexing="ij"), axis=-1).astype(np.float64)
    d = ((grid[..., None, :] - seeds) ** 2).sum(-1)
    return (np.argmin(d, axis=-1) % labels).astype(np.uint8)


def triangles(mesh):
    """A mesh's triangles as sorted tuples of vertex positions."""
    return {tuple(sorted(map(tuple, mesh.vertices[f].round(5)))) for f in mesh.faces}


def same_mesh(va, fa, vb, fb, tol=1e-4):
    """Whether two meshes have the same vertices (within ``tol``) and triangles."""
    from scipy.spatial import cKDTree
    if len(va) != len(vb) or len(fa) != len(fb):
        return False
    d, to_b = cKDTree(vb).query(va)
    if d.max(initial=0) > tol:
        return False
    return {tuple(sorted(t)) for t in to_b[fa]} == {tuple(sorted(t)) for t in fb}


def test_the_label_extractors_are_listed_with_guarantees():
    assert set(LABEL_EXTRACTORS) == {"surface-nets", "marching-tetrahedra", "lattice-cleaving"}
    mt = next(a for a in isolab.algorithms() if a["kind"] == "labels" and a["name"] == "marching-tetrahedra")
    assert mt["guarantees"] == {"closed": True, "manifold": True, "outward": True, "dihedral_degrees": None}
    cleaving = next(a for a in isolab.algorithms() if a["kind"] == "labels" and a["name"] == "lattice-cleaving")
    low, high = cleaving["guarantees"]["dihedral_degrees"]
    assert 0 < low < 60 < 90 < high < 180 and "tetrahedra" in cleaving["promises"]


def dihedral_angles(p):
    """The six dihedral angles (degrees) of each tetrahedron of ``p`` (K, 4, 3)."""
    out = []
    for i, j, k, m in [(0, 1, 2, 3), (0, 2, 1, 3), (0, 3, 1, 2), (1, 2, 0, 3), (1, 3, 0, 2), (2, 3, 0, 1)]:
        e = p[:, j] - p[:, i]
        e /= np.linalg.norm(e, axis=1, keepdims=True)
        u = p[:, k] - p[:, i]
        w = p[:, m] - p[:, i]
        u -= (u * e).sum(1, keepdims=True) * e
        w -= (w * e).sum(1, keepdims=True) * e
        c = (u * w).sum(1) / (np.linalg.norm(u, axis=1) * np.linalg.norm(w, axis=1))
        out.append(np.degrees(np.arccos(np.clip(c, -1, 1))))
    return np.stack(out, 1)


def test_lattice_cleaving_fills_every_label_with_conforming_tetrahedra():
    seg = voronoi((18, 16, 14), 5, seed=3)
    spacing = (0.5, 0.75, 1.0)
    meshes = isolab.mesh_labels(seg, algorithm="lattice-cleaving", spacing=spacing)
    tets, tet_labels, v = meshes.tetrahedra, meshes.tetrahedron_labels, meshes.vertices.astype(np.float64)
    assert tets.shape[1] == 4 and tets.dtype == np.int32 and tet_labels.shape == (len(tets),)
    assert sorted(set(tet_labels.tolist())) == sorted(meshes) == [1, 2, 3, 4]
    p = v[tets]
    volumes = np.einsum("ij,ij->i", p[:, 1] - p[:, 0], np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0])) / 6
    assert (volumes > 0).all()
    # Each label's volume within 10% of its samples' (the voxel is 0.375 units): these regions
    # are a few hundred samples, split in pieces and cut by the map's border, where the staircase's
    # chamfer and the border's ties take most (the Rust tests hold a ball to 2.5%).
    voxel = np.prod(spacing)
    for label in meshes:
        want = (seg == label).sum() * voxel
        assert abs(volumes[tet_labels == label].sum() - want) < 0.10 * want, label
    # Dihedral angles in the declared interval (spacing is not isotropic, so only on a cube grid).
    cube = isolab.mesh_labels(seg, algorithm="lattice-cleaving")
    low, high = next(a for a in isolab.algorithms() if a["name"] == "lattice-cleaving")["guarantees"]["dihedral_degrees"]
    angles = dihedral_angles(cube.vertices.astype(np.float64)[cube.tetrahedra])
    assert angles.min() >= low - 1e-3 and angles.max() <= high + 1e-3, (angles.min(), angles.max())
    # Conforming: every face of a tetrahedron is shared by two of one label, or is an interface
    # triangle of its two labels (one with the background).
    faces = {}
    for t, label in zip(tets.tolist(), tet_labels.tolist()):
        for k in range(4):
            f = tuple(sorted(t[:k] + t[k + 1:]))
            faces.setdefault(f, []).append(label)
    interfaces = {tuple(sorted(f)): tuple(pair) for f, pair in zip(meshes.faces.tolist(), meshes.pairs.tolist())}
    for f, labels in faces.items():
        assert len(labels) <= 2, f
        sides = tuple(sorted(labels + [0] * (2 - len(labels)), reverse=True))
        if sides[0] == sides[1]:
            assert f not in interfaces
        else:
            assert interfaces[f] == sides, (f, labels)
    assert set(interfaces) <= set(faces)
    # Surface extractors give no tetrahedra.
    nets = isolab.mesh_labels(seg)
    assert nets.tetrahedra.shape == (0, 4) and nets.tetrahedron_labels.shape == (0,)


@pytest.mark.parametrize("algorithm", LABEL_EXTRACTORS)
def test_every_label_is_closed_and_interfaces_are_shared(algorithm):
    seg = voronoi((18, 16, 14), 4)
    meshes = isolab.mesh_labels(seg, algorithm=algorithm)
    assert sorted(meshes) == [1, 2, 3]
    guarantees = next(a for a in isolab.algorithms() if a["kind"] == "labels" and a["name"] == algorithm)["guarantees"]
    for label, mesh in meshes.items():
        m = mesh.metrics()
        assert m["closed"], (label, m)
        if m["edge_manifold"] and m["vertex_manifold"]:
            assert m["volume"] > 0, (label, m)
        # The label's samples are inside its box (vertices within one sample of them).
        where = np.argwhere(seg == label)
        assert (mesh.vertices.min(0) >= where.min(0) - 1).all() and (mesh.vertices.max(0) <= where.max(0) + 1).all()
    if guarantees["manifold"]:
        assert all(m["edge_manifold"] and m["vertex_manifold"] for m in (mesh.metrics() for mesh in meshes.values()))
    # Each pair's interface: the same triangles in both meshes, as many as the tags say.
    for a in (1, 2, 3):
        for b in (1, 2, 3):
            if a < b:
                shared = len(triangles(meshes[a]) & triangles(meshes[b]))
                tagged = int(((meshes.pairs == [b, a]).all(1)).sum())
                assert shared == tagged == meshes[a].stats["neighbours"].get(str(b), 0), (a, b)


def test_dtypes_orders_and_views_give_the_same_meshes():
    seg = voronoi((12, 11, 10), 3)
    want = {l: triangles(m) for l, m in isolab.mesh_labels(seg, smoothing=False).items()}
    for variant in (np.asfortranarray(seg), seg.astype(np.int64), seg.astype(np.uint32), seg.astype(np.uint16),
                    np.ascontiguousarray(np.pad(seg, ((0, 0), (0, 0), (0, 3)))[:, :, :10])):
        got = {l: triangles(m) for l, m in isolab.mesh_labels(variant, smoothing=False).items()}
        assert got == want, variant.dtype
    strided = np.pad(seg, ((0, 0), (0, 0), (0, 10)))[:, :, ::2][:, :, :10]
    assert not strided.flags.c_contiguous
    expected = {l: triangles(m) for l, m in isolab.mesh_labels(np.ascontiguousarray(strided), smoothing=False).items()}
    assert {l: triangles(m) for l, m in isolab.mesh_labels(strided, smoothing=False).items()} == expected


def test_spacing_and_affine_place_the_meshes():
    seg = np.zeros((8, 8, 8), np.uint8)
    seg[2:6, 2:6, 2:6] = 4
    plain = isolab.mesh_labels(seg, algorithm="marching-tetrahedra")[4]
    scaled = isolab.mesh_labels(seg, algorithm="marching-tetrahedra", spacing=(2.0, 1.0, 0.5))[4]
    assert np.allclose(scaled.vertices, plain.vertices * [2.0, 1.0, 0.5], atol=1e-5)
    affine = np.diag([1.0, 1.0, 1.0, 1.0])
    affine[:3, 3] = [10, 20, 30]
    moved = isolab.mesh_labels(seg, algorithm="marching-tetrahedra", affine=affine)[4]
    assert np.allclose(moved.vertices, plain.vertices + [10, 20, 30], atol=1e-5)
    # A block of 64 samples: the volume of its dual cells with chamfered edges and corners.
    volume = plain.metrics()["volume"]
    assert 0.8 * 64 < volume < 64, volume


def test_labels_select_and_absent_ones_warn():
    seg = voronoi((10, 10, 10), 4)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        meshes = isolab.mesh_labels(seg, labels=[2, 9])
    assert sorted(meshes) == [2] and meshes.missing == [9]
    assert any("[9] do not occur" in str(w.message) for w in caught)
    # Label 2 against everything else as background: closed, one neighbour (0).
    assert set(meshes[2].stats["neighbours"]) == {"0"}


def test_bad_label_maps_raise():
    seg = voronoi((6, 6, 6), 3)
    with pytest.raises(TypeError, match="intensity volume"):
        isolab.mesh_labels(seg.astype(np.float32))
    with pytest.raises(ValueError, match="-1"):
        isolab.mesh_labels(seg.astype(np.int16) - 1)
    with pytest.raises(ValueError, match="2-D|3-D"):
        isolab.mesh_labels(seg[0])
    with pytest.raises(ValueError, match="surface-nets, marching-tetrahedra"):
        isolab.mesh_labels(seg, algorithm="marching-cubes")
    with pytest.raises(ValueError, match="smoothing"):
        isolab.mesh_labels(seg, algorithm="marching-tetrahedra", smoothing=True)
    with pytest.raises(OSError):
        isolab.mesh_labels("/no/such/file.nii.gz")


@needs_cli
def test_a_file_gives_the_clis_meshes(tmp_path):
    seg = voronoi((9, 8, 7), 3)
    # A raw NRRD, written by hand: x fastest, so the array's Fortran order.
    path = tmp_path / "seg.nrrd"
    header = "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 9 8 7\nencoding: raw\n\n".encode()
    path.write_bytes(header + np.asfortranarray(seg).tobytes(order="F"))
    out = tmp_path / "cli"
    done = subprocess.run([CLI, "labels", "-f", str(path), "-o", str(out)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    from_file = isolab.mesh_labels(str(path))
    from_array = isolab.mesh_labels(seg)
    for label in (1, 2):
        verts, faces = isolab.load(out / f"seg-label-{label}.ply")
        f, a = from_file[label], from_array[label]
        assert same_mesh(verts, faces, f.vertices, f.faces) and same_mesh(f.vertices, f.faces, a.vertices, a.faces), label


@needs_cli
def test_gmsh_reads_the_clis_msh_as_the_python_tetrahedra(tmp_path):
    """`isolab labels -o x.msh` read by Gmsh's own API (the format's reference reader): the
    same nodes and tetrahedra as `mesh_labels`, each in the physical volume of its label, and
    every tetrahedron's volume positive by Gmsh's measure."""
    import gmsh

    seg = voronoi((12, 11, 10), 4, seed=5)
    path = tmp_path / "seg.nrrd"
    header = "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 12 11 10\nencoding: raw\n\n".encode()
    path.write_bytes(header + np.asfortranarray(seg).tobytes(order="F"))
    msh = tmp_path / "seg.msh"
    done = subprocess.run([CLI, "labels", "-f", str(path), "-a", "lattice-cleaving", "-o", str(msh)],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    want = isolab.mesh_labels(str(path), algorithm="lattice-cleaving")
    gmsh.initialize(["-noenv"], readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.open(str(msh))
        tags, coords, _ = gmsh.model.mesh.getNodes()
        order = np.argsort(tags)
        nodes = coords.reshape(-1, 3)[order]
        assert np.array_equal(tags[order], np.arange(1, len(want.vertices) + 1))
        assert np.allclose(nodes, want.vertices, atol=1e-5)
        groups = gmsh.model.getPhysicalGroups(3)
        assert sorted(tag for _, tag in groups) == sorted(want) == sorted(set(want.tetrahedron_labels.tolist()))
        got = []
        for _, label in groups:
            assert gmsh.model.getPhysicalName(3, label) == f"label {label}"
            for entity in gmsh.model.getEntitiesForPhysicalGroup(3, label):
                types, elements, corners = gmsh.model.mesh.getElements(3, entity)
                assert list(types) == [4]  # 4-node tetrahedra
                volumes = gmsh.model.mesh.getElementQualities(elements[0], "volume")
                assert (volumes > 0).all(), label
                got += [(int(e), label, tuple(c - 1)) for e, c in zip(elements[0], corners[0].reshape(-1, 4))]
        got.sort()
        assert [t for _, _, t in got] == [tuple(t) for t in want.tetrahedra.tolist()]
        assert [label for _, label, _ in got] == want.tetrahedron_labels.tolist()
    finally:
        gmsh.finalize()


@pytest.mark.parametrize("algorithm", LABEL_EXTRACTORS)
def test_patches_split_the_interfaces_by_pair_and_meet_only_at_their_borders(algorithm):
    seg = voronoi((14, 13, 12), 5, seed=11)
    meshes = isolab.mesh_labels(seg, algorithm=algorithm)
    patches = meshes.patches
    assert set(patches) == {tuple(p) for p in meshes.pairs.tolist()} and len(patches) > 4
    assert meshes.patches is patches  # computed once
    seen = np.zeros(len(meshes.faces), dtype=int)
    row_of = {tuple(f): i for i, f in enumerate(meshes.faces.tolist())}
    owners = {}
    for (a, b), patch in patches.items():
        assert patch.labels == (a, b) and a > b
        assert np.array_equal(patch.vertices, meshes.vertices[patch.vertex_ids])
        assert len(np.unique(patch.vertex_ids)) == len(patch.vertex_ids) == len(patch.vertices)
        for f in patch.vertex_ids[patch.faces].tolist():
            i = row_of[tuple(f)]
            seen[i] += 1
            assert tuple(meshes.pairs[i]) == (a, b)
        for v in patch.vertex_ids.tolist():
            owners.setdefault(v, set()).add((a, b))
    assert (seen == 1).all()  # every interface triangle in exactly one patch, as given
    # Every label's mesh is closed, so a patch's border is where it meets others; where the
    # meshes are manifold, two patches share border vertices only.
    for key, patch in patches.items():
        shared = np.array([len(owners[v]) > 1 for v in patch.vertex_ids.tolist()])
        assert not (patch.border & ~shared).any(), key
        if algorithm != "surface-nets":
            assert np.array_equal(patch.border, shared), key


def test_a_patch_smoothed_with_its_border_fixed_moves_that_interface_alone():
    seg = voronoi((14, 13, 12), 4, seed=2)
    meshes = isolab.mesh_labels(seg, algorithm="marching-tetrahedra")
    key = max(meshes.patches, key=lambda k: len(meshes.patches[k].faces))
    patch = meshes.patches[key]
    v = patch.vertices.astype(np.float64)
    edges = np.concatenate([patch.faces[:, [0, 1]], patch.faces[:, [1, 2]], patch.faces[:, [2, 0]]])
    for _ in range(5):  # Laplacian smoothing of the interior
        total, count = np.zeros_like(v), np.zeros(len(v))
        for i, j in (edges.T, edges[:, ::-1].T):
            np.add.at(total, i, v[j])
            np.add.at(count, i, 1)
        v = np.where(patch.border[:, None], v, total / count[:, None])
    edited = meshes.vertices.copy()
    edited[patch.vertex_ids] = v.astype(np.float32)
    moved = np.nonzero((edited != meshes.vertices).any(1))[0]
    assert len(moved) > 0 and not patch.border[np.searchsorted(patch.vertex_ids, moved)].any()
    for other, p in meshes.patches.items():
        if other != key:
            assert np.array_equal(edited[p.vertex_ids], meshes.vertices[p.vertex_ids]), other


def test_save_tetrahedra_writes_what_the_cli_writes(tmp_path):
    seg = voronoi((10, 9, 8), 4, seed=4)
    path = tmp_path / "seg.nrrd"
    header = "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 10 9 8\nencoding: raw\n\n".encode()
    path.write_bytes(header + np.asfortranarray(seg).tobytes(order="F"))
    meshes = isolab.mesh_labels(str(path), algorithm="lattice-cleaving")
    for ext in ("vtk", "msh"):
        mine = tmp_path / f"python.{ext}"
        meshes.save_tetrahedra(mine)
        if os.path.exists(CLI):
            cli_out = tmp_path / f"cli.{ext}"
            done = subprocess.run([CLI, "labels", "-f", str(path), "-a", "lattice-cleaving", "-o", str(cli_out)],
                                  capture_output=True, text=True)
            assert done.returncode == 0, done.stderr
            assert mine.read_text() == cli_out.read_text(), ext
        else:
            assert mine.stat().st_size > 0
    text = (tmp_path / "python.vtk").read_text()
    assert f"CELL_DATA {len(meshes.tetrahedra)}" in text
    # Bad requests raise, and write nothing.
    with pytest.raises(ValueError, match=r"\.vtk or \.msh"):
        meshes.save_tetrahedra(tmp_path / "seg.obj")
    with pytest.raises(ValueError, match="lattice-cleaving"):
        isolab.mesh_labels(seg).save_tetrahedra(tmp_path / "nets.vtk")
    with pytest.raises(OSError):
        meshes.save_tetrahedra(tmp_path / "no" / "such" / "seg.msh")
    assert not (tmp_path / "seg.obj").exists() and not (tmp_path / "nets.vtk").exists()
