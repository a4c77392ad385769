"""Volumes bigger than one machine, meshed block by block on Dask.

``mesh_volume`` splits a volume into blocks of ``chunk``³ cells. Each Dask task reads one block
(its cells plus the samples its extractor's apron needs: none beyond the shared boundary for
marching cubes and Kuhn marching tetrahedra, one to a few for surface nets, dual contouring and
regularised marching tetrahedra), meshes it with isolab's chunk engine in the volume's sample
indices, and returns (or writes to ``out``) a *fragment*: the block's mesh and an integer weld
key for every vertex another block can make. The weld joins the fragments by those keys, never by
float positions, into exactly the mesh ``isolab.extract(array, chunk=...)`` makes in one process
(the same vertices in the same order, the same triangles), which for marching cubes is the
whole-volume mesh.

Needs ``dask`` (and ``distributed`` for a cluster; ``zarr`` to read zarr stores):
``pip install "./python[dask]"``.

>>> import numpy as np, isolab, isolab.dask
>>> i, j, k = np.mgrid[-1:1:41j, -1:1:33j, -1:1:37j]
>>> ball = (i**2 + j**2 + k**2 - 0.6).astype(np.float32)
>>> mesh = isolab.dask.mesh_volume(ball, 0.0, chunk=16)
>>> whole = isolab.extract(ball, 0.0)
>>> mesh.faces.shape == whole.faces.shape, mesh.stats["blocks"]["meshed"]
(True, 12)
"""
import contextlib
import importlib.util
import json
import os
import tempfile
import time
import warnings
from typing import Any, Dict, List, Mapping, Optional, Sequence, Union

import numpy as np

from . import LabelMeshes, Mesh, _index_to_world, _isolab
from .errors import raises_isolab_errors

if importlib.util.find_spec("dask") is None:  # pragma: no cover - the message is the point
    raise ImportError("isolab.dask needs dask: pip install \"./python[dask]\" (dask, distributed, zarr)")
import dask  # noqa: E402

__all__ = ["mesh_volume", "mesh_labels", "bake_world", "load_fragment", "save_fragment", "load_label_fragment",
           "save_label_fragment"]

MANIFEST = "manifest.json"


def _options(options: Optional[Mapping[str, Any]]) -> Optional[Dict[str, str]]:
    return None if options is None else {str(k): str(v) for k, v in options.items()}


def _is_dask_array(array) -> bool:
    try:
        import dask.array as da
    except ImportError:  # pragma: no cover
        return False
    return isinstance(array, da.Array)


def _fragment_name(block_id: Sequence[int]) -> str:
    return "fragment-{}-{}-{}.npz".format(*block_id)


def _save_npz(path: str, arrays: Dict[str, Any]) -> None:
    """Writes ``arrays`` as ``.npz``, atomically: a temporary file in the same folder, renamed
    over ``path`` once complete, so a reader (or a rerun) never sees half a fragment."""
    folder = os.path.dirname(path) or "."
    fd, tmp = tempfile.mkstemp(prefix=".fragment-", suffix=".npz.tmp", dir=folder)
    try:
        with os.fdopen(fd, "wb") as f:
            np.savez(f, **arrays)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


@raises_isolab_errors
def save_fragment(path: str, fragment: Dict[str, Any]) -> None:
    """Writes a volume fragment as ``.npz``, atomically (never half a file)."""
    _save_npz(path, dict(id=np.asarray(fragment["id"], dtype=np.int64), state=np.asarray(fragment["state"]),
                         active_cells=np.asarray(fragment["active_cells"], dtype=np.int64),
                         discarded_triangles=np.asarray(fragment["discarded_triangles"], dtype=np.int64),
                         positions=fragment["positions"], normals=fragment["normals"],
                         triangles=fragment["triangles"], keys=fragment["keys"], keyed=fragment["keyed"]))


@raises_isolab_errors
def load_fragment(path: str) -> Dict[str, Any]:
    """A fragment ``mesh_volume(..., out=...)`` wrote: the block's mesh (``positions`` in the
    volume's sample indices, isolab's x = numpy's last axis), ``triangles``, ``normals``, the
    weld ``keys`` (N x 2 uint64) and ``keyed`` flags, its ``id`` and ``state``."""
    with np.load(path) as z:
        return {"id": tuple(int(v) for v in z["id"]), "state": str(z["state"]),
                "active_cells": int(z["active_cells"]), "discarded_triangles": int(z["discarded_triangles"]),
                "positions": z["positions"], "normals": z["normals"], "triangles": z["triangles"], "keys": z["keys"],
                "keyed": z["keyed"]}


def _write_json(path: str, value: Any) -> None:
    folder = os.path.dirname(path) or "."
    fd, tmp = tempfile.mkstemp(prefix=".manifest-", suffix=".tmp", dir=folder)
    with os.fdopen(fd, "w") as f:
        json.dump(value, f, indent=1)
    os.replace(tmp, path)


def _write_manifest(out_dir: str, params: Dict[str, Any], blocks, counts, apron, done) -> None:
    """The run's manifest: its parameters, its blocks and (once they ran) the blocks done."""
    _write_json(os.path.join(out_dir, MANIFEST), {"params": params, "blocks": len(blocks), "counts": counts,
                                                 "apron": apron, "done": done})


def _open_out(out, params: Dict[str, Any], blocks, counts, apron) -> Optional[str]:
    """Creates ``out`` with a manifest of the run's parameters, or checks that the manifest
    already there is this run's (a rerun resumes it); returns the folder."""
    if out is None:
        return None
    out_dir = os.fspath(out)
    os.makedirs(out_dir, exist_ok=True)
    manifest_path = os.path.join(out_dir, MANIFEST)
    if os.path.exists(manifest_path):
        with open(manifest_path) as f:
            old = json.load(f).get("params")
        if old != params:
            raise ValueError(f"out {out_dir!r} holds the fragments of another run ({old}); give another folder or "
                             "empty it")
    _write_manifest(out_dir, params, blocks, counts, apron, None)
    return out_dir


def _compute(tasks, client, progress: bool) -> Sequence[Any]:
    """Runs the delayed tasks on ``client`` (else Dask's current scheduler), with a progress bar
    when asked."""
    if client is not None:
        futures = client.compute(tasks)
        if progress:
            from distributed import progress as show
            show(futures)
        return client.gather(futures)
    bar: Any = contextlib.nullcontext()
    if progress:
        from dask.diagnostics import ProgressBar
        bar = ProgressBar()
    with bar:
        return dask.compute(*tasks)


def _mesh_volume_block(block: np.ndarray, block_id, job: Dict[str, Any]) -> Dict[str, Any]:
    return _isolab.mesh_block(block, job["algorithm"], job["options"], job["dims"], job["chunk"], block_id, job["level"],
                              job["inside"] == "above", job["threads"])


def _mesh_label_block(block: np.ndarray, block_id, job: Dict[str, Any]) -> Dict[str, Any]:
    return _isolab.mesh_label_block(block, job["algorithm"], job["options"], job["dims"], job["chunk"], block_id,
                                    job["labels"], job["threads"])


def _read_block(source, slices) -> np.ndarray:
    """A block's samples as a C-ordered numpy array: ``source[slices]`` (a zarr or numpy array
    read on the worker), or ``source`` itself (a dask array's block, computed by Dask)."""
    block = source if slices is None else source[slices]
    return np.ascontiguousarray(np.asarray(block))


def _block_task(kind: str, source, slices, block_id, job: Dict[str, Any], path: Optional[str]):
    """One Dask task of either kind: read a block, mesh it, write or return its fragment."""
    if path is not None and os.path.exists(path):
        return path  # a rerun of a task whose fragment was written (a worker died after writing)
    mesh, save, _ = _KINDS[kind]
    fragment = mesh(_read_block(source, slices), block_id, job)
    if path is None:
        return fragment
    save(path, fragment)
    return path


@raises_isolab_errors
def mesh_volume(array, level: float, algorithm: str = "marching-cubes", *, chunk: int = 128,
                spacing: Optional[Sequence[float]] = None, affine: Optional[np.ndarray] = None, inside: str = "below",
                options: Optional[Mapping[str, Any]] = None, client=None, out: Optional[Union[str, os.PathLike]] = None,
                merge: bool = True, progress: bool = False, threads: int = 1) -> Union[Mesh, List[str]]:
    """Meshes a 3-D volume block by block on Dask and welds the blocks into one mesh.

    Parameters
    ----------
    array : zarr array, dask array or numpy array
        Any numeric dtype, shape (I, J, K) (isolab's x is the last axis, as for a C-ordered
        array in :func:`isolab.extract`). A zarr array (or anything sliceable and picklable, such
        as an h5py dataset opened per worker) is read block by block on the workers, so no task
        holds more than one block; a dask array's blocks are computed by Dask as the tasks'
        inputs; a numpy array is shared with the tasks (``client.scatter`` on a cluster).
    level : float
        The iso-value.
    algorithm : str
        A registered extractor that meshes in chunks (``isolab.algorithms()``: its
        ``chunking`` is not ``"unsupported"``).
    chunk : int
        Cells per block along each axis (the last block on an axis takes what remains). A block
        reads ``chunk + 1`` samples per axis (more with an apron), so from a zarr array it reads
        whole storage chunks past its own: a multiple of the store's chunk edge of a few times
        it keeps that overhead small (the ``distributed`` report page measures 64 and 128 on
        64³ storage chunks).
    spacing, affine
        Voxel spacing along the array's axes, or a 4 x 4 index-to-world matrix (as nibabel's
        ``img.affine``), as in :func:`isolab.extract`.
    inside : 'below' or 'above'
        Which side of ``level`` is inside (the mesh winds outward from it).
    options : dict, optional
        Extractor options, as :func:`isolab.extract`'s.
    client : distributed.Client, optional
        Where the tasks run; by default Dask's current scheduler (a ``Client`` created in this
        process, else Dask's threads).
    out : path, optional
        A folder for the fragments (``fragment-X-Y-Z.npz``, each written atomically) and
        ``manifest.json`` (the run's parameters and the blocks done). A second run with the
        same ``out`` and parameters meshes only the blocks whose fragment is missing; an ``out``
        holding another run's fragments is refused.
    merge : bool
        Weld the fragments into one :class:`isolab.Mesh` (default), or return the fragment
        paths (needs ``out``) for a reader that streams them (:func:`load_fragment`).
    progress : bool
        Show Dask's progress bar (``distributed.progress`` on a client, else
        ``dask.diagnostics.ProgressBar``).
    threads : int
        Threads each task's extraction uses (1: let Dask's workers be the parallelism).

    Returns
    -------
    isolab.Mesh, or a list of fragment paths when ``merge=False``
        The mesh's ``stats`` hold the counts and ``blocks`` (meshed, empty, full, and vertices
        welded at seams).
    """
    shape = tuple(int(s) for s in array.shape)
    if len(shape) != 3:
        raise ValueError(f"the volume must be a 3-D array; this one has {len(shape)} dimensions")
    if inside not in ("below", "above"):
        raise ValueError(f"inside '{inside}': expected 'below' or 'above'")
    if not merge and out is None:
        raise ValueError("merge=False keeps the fragments in `out`: give out=FOLDER")
    opts = _options(options)
    dims = [shape[2], shape[1], shape[0]]
    counts, apron, blocks = _isolab.block_plan(algorithm, opts, dims, int(chunk))
    job = {"algorithm": algorithm, "options": opts, "dims": dims, "chunk": int(chunk), "level": float(level),
           "inside": inside, "threads": int(threads)}
    loaded = _mesh_blocks(array, "volume", job, (counts, apron, blocks), client, out, progress, merge)
    if not merge:
        return loaded
    affine_ = _index_to_world(affine, spacing)
    report = {"algorithm": algorithm, "driver": "isolab.dask", "shape": list(shape), "dims": dims, "iso": float(level),
              "inside": inside, "chunk": int(chunk), "apron": apron, "block_counts": counts}
    return Mesh(_isolab.weld_fragments(loaded, affine_, json.dumps(report)))


def _bake_task(block_id, lo, dims, job: Dict[str, Any], fragment_path: str, mesh_path: str) -> Dict[str, Any]:
    """One block of a baked world: sampled from the field (or proven empty or full without
    sampling), meshed, written as a fragment (for the weld) and, when it has triangles, as a
    world-space mesh file a game streams."""
    if os.path.exists(fragment_path):
        f = load_fragment(fragment_path)
    else:
        b = _isolab.field_block(job["field"], job["cells"], lo, dims, job["seed"])
        if b["side"] == "mixed":
            f = _isolab.mesh_block(b["values"], job["algorithm"], job["options"], job["dims"], job["chunk"], block_id,
                                   0.0, False, job["threads"])
        else:
            f = _isolab.skipped_fragment(block_id, b["side"] == "full")
        if len(f["triangles"]):
            origin, h = np.asarray(b["origin"], dtype=np.float64), float(b["spacing"])
            vertices = (origin + f["positions"].astype(np.float64) * h).astype(np.float32)
            normals = f["normals"] if len(f["normals"]) else None
            _isolab.save(mesh_path, vertices, f["triangles"].astype(np.int32), normals, None, None, None, None)
        save_fragment(fragment_path, f)
    return {"id": tuple(block_id), "state": f["state"], "triangles": int(len(f["triangles"])),
            "mesh": os.path.basename(mesh_path) if len(f["triangles"]) else None}


@raises_isolab_errors
def bake_world(field: str = "terrain", size: Sequence[int] = (8192, 512, 8192), *, out: Union[str, os.PathLike],
               chunk: int = 128, algorithm: str = "marching-cubes", options: Optional[Mapping[str, Any]] = None,
               seed: Optional[int] = None, format: str = "glb", client=None, merge: bool = False,
               progress: bool = False, threads: int = 1) -> Union[Mesh, List[str]]:
    """Bakes a built-in field's world block by block on Dask: each task samples its block from
    the field (blocks the field proves all air or all solid are skipped unsampled), meshes it and
    writes one world-space mesh per block (``chunk-X-Y-Z.glb`` or ``.ply``) that a game streams,
    plus the block's weld fragment; the manifest lists every block's file and triangle count.

    Parameters
    ----------
    field : str
        A built-in field (``isolab.fields()``), e.g. ``"terrain"``.
    size : 3 ints
        Cells along x, y (up) and z. The world starts at the field's domain's lowest corner, at
        the spacing that fits the domain's height in ``size[1]`` cells (the ``large_world``
        experiment's grid).
    out : path
        The folder for the block meshes, fragments and ``manifest.json``; a rerun with the same
        parameters bakes only the missing blocks.
    chunk, algorithm, options, seed
        Cells per block, the extractor (one that meshes in chunks), its options, the noise seed.
    format : 'glb' or 'ply'
    merge : bool
        Also weld every block into one :class:`isolab.Mesh` (world coordinates) and return it;
        by default the block files' paths are returned (blocks with no triangles have none).
    client, progress, threads
        As :func:`mesh_volume`.

    >>> import tempfile, isolab.dask
    >>> files = isolab.dask.bake_world("terrain", (64, 32, 64), chunk=32, out=tempfile.mkdtemp())
    >>> len(files) > 0 and all(f.endswith(".glb") for f in files)
    True
    """
    if format not in ("glb", "ply"):
        raise ValueError(f"format '{format}': expected 'glb' or 'ply'")
    cells = [int(s) for s in size]
    if len(cells) != 3:
        raise ValueError(f"size must be three cell counts, not {size!r}")
    opts = _options(options)
    dims = [c + 1 for c in cells]
    counts, apron, blocks = _isolab.block_plan(algorithm, opts, dims, int(chunk))
    job = {"field": field, "cells": cells, "seed": seed, "algorithm": algorithm, "options": opts, "dims": dims,
           "chunk": int(chunk), "threads": int(threads)}
    params = dict(job, format=format)
    params.pop("threads")
    if field not in [name for name, _ in _isolab.fields()]:
        raise ValueError(f"unknown field '{field}' (isolab.fields() lists them)")
    out_dir = _open_out(out, params, blocks, counts, apron)
    assert out_dir is not None, "out is required here"
    tasks, fragment_paths = [], []
    for block_id, lo, bdims in blocks:
        x, y, z = block_id
        fragment_path = os.path.join(out_dir, _fragment_name(block_id))
        mesh_path = os.path.join(out_dir, f"chunk-{x}-{y}-{z}.{format}")
        fragment_paths.append(fragment_path)
        tasks.append(dask.delayed(_bake_task, pure=False)(tuple(block_id), list(lo), list(bdims), job, fragment_path,
                                                          mesh_path))
    done = list(_compute(tasks, client, progress))
    _write_manifest(out_dir, params, blocks, counts, apron, done)
    files = [os.path.join(out_dir, d["mesh"]) for d in done if d["mesh"]]
    if not merge:
        return files
    b = _isolab.field_block(field, cells, [0, 0, 0], [2, 2, 2], seed)
    (ox, oy, oz), h = b["origin"], float(b["spacing"])
    # World = origin + h * (x, y, z); the weld's affine is in numpy index order (z, y, x).
    affine_ = [[0.0, 0.0, h, ox], [0.0, h, 0.0, oy], [h, 0.0, 0.0, oz], [0.0, 0.0, 0.0, 1.0]]
    report = {"algorithm": algorithm, "driver": "isolab.dask.bake_world", "field": field, "size": cells, "dims": dims,
              "iso": 0.0, "inside": "below", "chunk": int(chunk), "apron": apron, "block_counts": counts}
    return Mesh(_isolab.weld_fragments([load_fragment(p) for p in fragment_paths], affine_, json.dumps(report)))


@raises_isolab_errors
def save_label_fragment(path: str, fragment: Dict[str, Any]) -> None:
    """Writes a label fragment (what one block of :func:`mesh_labels` makes) as ``.npz``,
    atomically (never half a file)."""
    labels = sorted(fragment["counts"])
    _save_npz(path, dict(id=np.asarray(fragment["id"], dtype=np.int64),
                         active_cells=np.asarray(fragment["active_cells"], dtype=np.int64),
                         positions=fragment["positions"], triangles=fragment["triangles"], pairs=fragment["pairs"],
                         keys=fragment["keys"], tetrahedra=fragment["tetrahedra"],
                         tetrahedron_labels=fragment["tetrahedron_labels"], count_labels=np.asarray(labels, dtype=np.uint32),
                         count_samples=np.asarray([fragment["counts"][k] for k in labels], dtype=np.int64)))


@raises_isolab_errors
def load_label_fragment(path: str) -> Dict[str, Any]:
    """A fragment ``mesh_labels(..., out=...)`` wrote: the block's interface triangles
    (``positions`` in the map's sample indices, isolab's x = numpy's last axis; ``triangles``;
    ``pairs``, each triangle's ``(inside, outside)`` labels), the weld ``keys`` (N x 2 uint64),
    ``tetrahedra`` and ``tetrahedron_labels`` (lattice cleaving's; empty for a surface
    extractor), its ``id``, ``active_cells`` and ``counts`` (each label's samples among those it
    owns)."""
    with np.load(path) as z:
        empty = (np.zeros((0, 4), np.uint32), np.zeros(0, np.uint32))
        tets = (z["tetrahedra"], z["tetrahedron_labels"]) if "tetrahedra" in z.files else empty
        return {"id": tuple(int(v) for v in z["id"]), "active_cells": int(z["active_cells"]),
                "positions": z["positions"], "triangles": z["triangles"], "pairs": z["pairs"], "keys": z["keys"],
                "tetrahedra": tets[0], "tetrahedron_labels": tets[1],
                "counts": {int(k): int(n) for k, n in zip(z["count_labels"], z["count_samples"])}}


# Each kind's block mesher, fragment writer and reader, which :func:`_block_task` and
# :func:`_mesh_blocks` look up by name (a name pickles into a task; the functions are this module's).
_KINDS = {"volume": (_mesh_volume_block, save_fragment, load_fragment),
          "labels": (_mesh_label_block, save_label_fragment, load_label_fragment)}


def _mesh_blocks(array, kind: str, job: Dict[str, Any], plan, client, out, progress: bool, merge: bool) -> List[Any]:
    """Either kind's run: ``out``'s manifest opened (or a rerun's checked), a task per block
    still to mesh, the manifest's list of blocks done; the fragments in plan order (loaded
    back where they were written) for the weld, or with ``merge=False`` their paths."""
    counts, apron, blocks = plan
    params = dict(job, shape=[int(s) for s in array.shape], dtype=str(array.dtype))
    params.pop("threads")
    out_dir = _open_out(out, params, blocks, counts, apron)
    fragments, paths = _run_blocks(array, blocks, kind, job, client, out_dir, progress)
    if out_dir is not None:
        _write_manifest(out_dir, params, blocks, counts, apron, [os.path.basename(p) for p in paths])
    if not merge:
        return list(paths)
    load = _KINDS[kind][2]
    return [load(f) if isinstance(f, str) else f for f in fragments]


def _shared_source(array, client, name: str):
    """What the tasks read blocks from: a numpy array shared once (``client.scatter`` on a
    cluster, else one delayed value), any other array as it is (a zarr array pickles as its
    store's address; a dask array's blocks become the tasks' inputs)."""
    if not _is_dask_array(array) and isinstance(array, np.ndarray):
        return client.scatter(array, broadcast=True) if client is not None else dask.delayed(array, name=name)
    return array


def _block_input(array, source, lo, bdims):
    """A task's ``(source, slices)`` for the block of ``bdims`` samples at ``lo`` (isolab's x, y,
    z; numpy's axes reversed): a dask array's own block with no slices, else the shared source
    and the slices the task reads."""
    slices = tuple(slice(lo[a], lo[a] + bdims[a]) for a in (2, 1, 0))
    return (array[slices], None) if _is_dask_array(array) else (source, slices)


def _run_blocks(array, blocks, kind: str, job, client, out_dir, progress):
    """One task per block (:func:`_block_task` of ``kind``), skipping those whose file is in
    ``out_dir``: the results (or paths) in plan order, and every block's path."""
    source = _shared_source(array, client, f"isolab-{kind}")
    tasks, paths = [], []
    for block_id, lo, bdims in blocks:
        path = None if out_dir is None else os.path.join(out_dir, _fragment_name(block_id))
        paths.append(path)
        if path is not None and os.path.exists(path):
            tasks.append(path)
            continue
        tasks.append(dask.delayed(_block_task, pure=False)(kind, *_block_input(array, source, lo, bdims),
                                                          tuple(block_id), job, path))
    results = iter(_compute([t for t in tasks if not isinstance(t, str)], client, progress))
    return [t if isinstance(t, str) else next(results) for t in tasks], paths


@raises_isolab_errors
def mesh_labels(array, *, chunk: int = 128, spacing: Optional[Sequence[float]] = None,
                affine: Optional[np.ndarray] = None, labels: Optional[Sequence[int]] = None,
                algorithm: str = "surface-nets", smoothing: Optional[Union[bool, str]] = None, border: str = "closed",
                options: Optional[Mapping[str, Any]] = None, client=None, out: Optional[Union[str, os.PathLike]] = None,
                merge: bool = True, progress: bool = False, threads: int = 1, format: str = "fragments",
                lods: Optional[int] = None, sharded: bool = False, quantization_bits: int = 16,
                names: Optional[Mapping[int, str]] = None,
                keep_work: bool = False) -> Union[LabelMeshes, List[str], Dict[str, Any]]:
    """Meshes a label map (a segmentation) block by block on Dask into one mesh per label, as
    :func:`isolab.mesh_labels` does in one process, and with the same result: each block meshes
    its own cells (and the apron its extractor needs: none for ``marching-tetrahedra``, one cell,
    plus one per smoothing pass, for ``surface-nets``, so that smoothing moves every vertex as in
    the whole map); the fragments weld by integer keys into the very surface of the whole map,
    then split per label.

    Parameters
    ----------
    array : zarr array, dask array or numpy array
        Integer labels (``0`` the background), shape (I, J, K); read block by block as
        :func:`mesh_volume` reads volumes.
    chunk : int
        Cells per block along each axis. With smoothing, each block also meshes ``iterations +
        1`` cells around it (17 by default), so blocks much larger than that waste less.
    spacing, affine, labels, algorithm, smoothing, border, options
        As :func:`isolab.mesh_labels`.
    client, out, merge, progress, threads
        As :func:`mesh_volume`: ``out`` keeps one ``fragment-X-Y-Z.npz`` per block
        (:func:`load_label_fragment`) and a manifest, and a rerun meshes only the missing blocks.
    format : str
        ``"fragments"`` (the default: the above), or ``"neuroglancer"``: ``out`` becomes a
        neuroglancer precomputed multi-resolution mesh source (``neuroglancer_multilod_draco``)
        that neuroglancer and cloud-volume read. Each block's task writes its own level-0
        fragments (its labels' triangles cut at the block's box, quantized and Draco-encoded);
        each coarser level's task joins the eight boxes below it, each simplified with its box
        faces locked (so no triangle crosses the 2x2x2 grid, and levels meet without cracks);
        the segments' files are the fragments' bytes copied in Z-curve order. No label is ever
        held whole by a task, and a rerun resumes from the box files in ``out/.isolab-work``.
        A level of fewer boxes than the scheduler has threads (the octree's top, whose tasks run
        alone at the end) gives each of its tasks an equal share of them where that share is
        more than ``threads``.
        Coordinates: ``affine`` or ``spacing`` become the ``info``'s transform; with neither,
        vertices are in voxels in the array's axis order, as :func:`isolab.mesh_labels` gives
        them (axis 0 is neuroglancer's x, as for arrays cloud-volume reads).
        ``"neuroglancer-legacy"``: the legacy single-resolution format instead (each block's
        task writes its labels' fragments ``<label>:0:<x>_<y>_<z>`` as floats in model
        coordinates; then each label's ``<label>:0`` names them).
    lods : int, optional
        Levels of detail for ``"neuroglancer"`` (default: until one box holds the volume).
    sharded : bool
        ``"neuroglancer"`` in shards (``neuroglancer_uint64_sharded_v1``: murmurhash3_x86_128,
        minishards, gzip indices) instead of two files per label.
    quantization_bits : int
        10 or 16 bits per vertex coordinate within a fragment.
    names : mapping of label to str, optional
        Label names, written as the source's ``segment_properties``.
    keep_work : bool
        Keep ``out/.isolab-work`` (the per-box meshes) after a finished run.

    Returns
    -------
    isolab.LabelMeshes, or a list of fragment paths when ``merge=False``, or with
    ``format="neuroglancer"`` a dict of what was written (``segments``, ``lods``, per level
    ``fragments``, ``triangles`` and ``bytes``, ``shards``, and ``seconds``: wall time of the
    ``boxes`` (every level's boxes, planning and reading included), of the segments' ``files``
    (shards, or manifests and fragment files) and of ``info_and_cleanup``)
        Its ``extract_ms`` is the weld's time (the blocks ran on the workers).

    >>> import numpy as np, isolab, isolab.dask
    >>> seg = np.zeros((30, 20, 24), np.uint8)
    >>> seg[3:15, 3:17, 3:20] = 1
    >>> seg[15:27, 3:17, 3:20] = 2
    >>> blocks = isolab.dask.mesh_labels(seg, chunk=8)
    >>> whole = isolab.mesh_labels(seg)
    >>> sorted(blocks), all((blocks[l].faces.shape == whole[l].faces.shape) for l in (1, 2))
    ([1, 2], True)
    """
    shape = tuple(int(s) for s in array.shape)
    if len(shape) != 3:
        raise ValueError(f"the label map must be a 3-D array; this one has {len(shape)} dimensions")
    if np.dtype(array.dtype).kind == "f":
        raise TypeError(f"a label map holds integer labels, but this array's dtype is {array.dtype}: an intensity "
                        "volume is meshed at a level with mesh_volume; labels stored as floats convert with "
                        ".astype(np.uint16)")
    if format not in ("fragments", "neuroglancer", "neuroglancer-legacy"):
        raise ValueError(f"format must be 'fragments', 'neuroglancer' or 'neuroglancer-legacy', not {format!r}")
    if format.startswith("neuroglancer") and out is None:
        raise ValueError("format='neuroglancer' writes a folder: give out=FOLDER")
    if not merge and out is None:
        raise ValueError("merge=False keeps the fragments in `out`: give out=FOLDER")
    opts = {} if options is None else {str(k): str(v) for k, v in options.items()}
    if smoothing is not None:
        opts["smoothing"] = ("constrained" if smoothing else "none") if isinstance(smoothing, bool) else str(smoothing)
    opts["border"] = str(border)
    chosen = None if labels is None else sorted({int(s) for s in labels})
    dims = [shape[2], shape[1], shape[0]]
    counts, apron, blocks = _isolab.label_block_plan(algorithm, opts, dims, int(chunk))
    if format == "neuroglancer-legacy":
        return _neuroglancer_legacy(array, algorithm, opts, dims, int(chunk), chosen, _index_to_world(affine, spacing),
                                    client, out, progress, int(threads))
    if format == "neuroglancer":
        return _neuroglancer(array, algorithm, opts, dims, int(chunk), counts, lods, bool(sharded),
                             int(quantization_bits), chosen, _index_to_world(affine, spacing), names, client, out,
                             progress, int(threads), keep_work)
    job = {"kind": "labels", "algorithm": algorithm, "options": opts, "dims": dims, "chunk": int(chunk),
           "labels": chosen, "threads": int(threads)}
    loaded = _mesh_blocks(array, "labels", job, (counts, apron, blocks), client, out, progress, merge)
    if not merge:
        return loaded
    result = LabelMeshes(_isolab.weld_label_fragments(loaded, _index_to_world(affine, spacing), chosen, algorithm))
    if result.missing:
        warnings.warn(f"labels {result.missing} do not occur in the label map: no mesh for them", stacklevel=2)
    return result


def _ng_level0_task(source, slices, block_id, job, work: str, select, threads: int):
    """One Dask task: a block's level-0 box (skipped when its file is whole)."""
    done = _isolab.ng_box_index(work, 0, list(block_id))
    if done is not None:
        return done
    return _isolab.ng_level0(job, _read_block(source, slices), list(block_id), work, select, threads)


def _ng_coarser_task(job, level: int, position, work: str, threads: int, *children):
    """One Dask task: a box at ``level`` from its children (``children``: their tasks, so that
    Dask runs them first), on ``threads`` threads."""
    return _isolab.ng_coarser(job, level, list(position), work, threads)


def _scheduler_threads(client) -> int:
    """Threads the tasks run on at once: the cluster's (``client``), else this machine's cores
    (Dask's local schedulers)."""
    if client is not None:
        return max(1, sum(int(n) for n in client.nthreads().values()))
    return max(1, os.cpu_count() or 1)


def _ng_segments_task(job, work: str, out_dir: str, segments) -> None:
    """One Dask task: a batch of segments' files (unsharded)."""
    _isolab.ng_segments(job, work, out_dir, segments)


def _ng_shard_task(job, work: str, out_dir: str, count: int, shard: int, segments) -> None:
    """One Dask task: one shard file."""
    _isolab.ng_shard(job, work, out_dir, count, shard, segments)


def _ng_transform(affine_) -> List[float]:
    """The stored model (isolab's x, y, z: the array's last axis first) to model transform: the
    array's index-to-world affine (identity: voxels in the array's axis order) after the axis
    swap, its top three rows."""
    a = np.eye(4) if affine_ is None else np.asarray(affine_, dtype=np.float64)
    swap = np.zeros((4, 4))
    swap[0, 2] = swap[1, 1] = swap[2, 0] = swap[3, 3] = 1.0
    return [float(v) for v in (a @ swap)[:3].ravel()]


def _neuroglancer(array, algorithm, opts, dims, chunk, counts, lods, sharded, bits, chosen, affine_, names, client,
                  out, progress, threads, keep_work) -> Dict[str, Any]:
    """``mesh_labels(..., format="neuroglancer")``: level-0 boxes, coarser boxes, segments."""
    import shutil
    started = time.perf_counter()
    if lods is None:
        lods = 1 + max(int(np.ceil(np.log2(c))) if c > 1 else 0 for c in counts)
    job = (algorithm, opts, list(dims), chunk, int(lods), bits)
    level_counts, windows = _isolab.ng_plan(job)
    out_dir = os.fspath(out)
    work = os.path.join(out_dir, ".isolab-work")
    os.makedirs(work, exist_ok=True)
    source = _shared_source(array, client, "isolab-ng")
    tasks: Dict[Any, Any] = {}
    for block_id, lo, bdims in windows:
        tasks[(0, tuple(block_id))] = dask.delayed(_ng_level0_task, pure=False)(
            *_block_input(array, source, lo, bdims), tuple(block_id), job, work, chosen, threads)
    # A level of fewer boxes than the scheduler has threads (the top of the octree, its tasks
    # alone at the end of the run) gives each box's task a share of the idle threads.
    total_threads = _scheduler_threads(client)
    for level in range(1, lods):
        cx, cy, cz = level_counts[level]
        below = level_counts[level - 1]
        level_threads = max(threads, total_threads // max(1, cx * cy * cz))
        for z in range(cz):
            for y in range(cy):
                for x in range(cx):
                    kids = [tasks[(level - 1, (2 * x + dx, 2 * y + dy, 2 * z + dz))]
                            for dz in (0, 1) for dy in (0, 1) for dx in (0, 1)
                            if 2 * x + dx < below[0] and 2 * y + dy < below[1] and 2 * z + dz < below[2]]
                    tasks[(level, (x, y, z))] = dask.delayed(_ng_coarser_task, pure=False)(job, level, (x, y, z), work,
                                                                                           level_threads, *kids)
    keys = list(tasks)
    results = _compute([tasks[k] for k in keys], client, progress)
    boxes_done = time.perf_counter()
    segments: Dict[int, List[Any]] = {}
    per_level = [[0, 0, 0] for _ in range(lods)]
    for (level, position), index in zip(keys, results):
        for label, triangles, nbytes in index:
            segments.setdefault(int(label), []).append((level, list(position), int(nbytes)))
            per_level[level][0] += 1
            per_level[level][1] += int(triangles)
            per_level[level][2] += int(nbytes)
    labels_ = sorted(segments)
    writes = []
    if sharded:
        shard_of = _isolab.ng_shard_of(len(labels_), labels_)
        by_shard: Dict[int, Dict[int, Any]] = {}
        for label, shard in zip(labels_, shard_of):
            by_shard.setdefault(int(shard), {})[label] = segments[label]
        for shard, segs in sorted(by_shard.items()):
            writes.append(dask.delayed(_ng_shard_task, pure=False)(job, work, out_dir, len(labels_), shard, segs))
    else:
        batch = 256
        for i in range(0, len(labels_), batch):
            segs = {label: segments[label] for label in labels_[i:i + batch]}
            writes.append(dask.delayed(_ng_segments_task, pure=False)(job, work, out_dir, segs))
    _compute(writes, client, progress)
    files_done = time.perf_counter()
    named = None if names is None else sorted((int(k), str(v)) for k, v in names.items())
    _isolab.ng_info(job, out_dir, _ng_transform(affine_), len(labels_) if sharded else None, named)
    if not keep_work:
        shutil.rmtree(work, ignore_errors=True)
    finished = time.perf_counter()
    missing = [] if chosen is None else [label for label in chosen if label not in segments]
    if missing:
        warnings.warn(f"labels {missing} do not occur in the label map: no mesh for them", stacklevel=3)
    return {"out": out_dir, "format": "neuroglancer", "segments": len(labels_), "lods": int(lods),
            "fragments": [p[0] for p in per_level], "triangles": [p[1] for p in per_level],
            "bytes": [p[2] for p in per_level], "shards": len(writes) if sharded else 0,
            "sharded": sharded, "quantization_bits": bits, "chunk": chunk,
            "seconds": {"boxes": boxes_done - started, "files": files_done - boxes_done,
                        "info_and_cleanup": finished - files_done}}


def _ng_legacy_task(source, slices, block_id, job, out_dir: str, transform, select, threads: int):
    """One Dask task: a block's legacy fragments."""
    return _isolab.ng_legacy_block(job, _read_block(source, slices), list(block_id), out_dir, transform, select, threads)


def _neuroglancer_legacy(array, algorithm, opts, dims, chunk, chosen, affine_, client, out, progress,
                         threads) -> Dict[str, Any]:
    """``mesh_labels(..., format="neuroglancer-legacy")``: each block's fragments, then the
    labels' ``<label>:0`` files."""
    job = (algorithm, opts, list(dims), chunk, 1, 16)
    _, windows = _isolab.ng_plan(job)
    out_dir = os.fspath(out)
    os.makedirs(out_dir, exist_ok=True)
    transform = _ng_transform(affine_)
    source = _shared_source(array, client, "isolab-ngl")
    tasks, ids = [], []
    for block_id, lo, bdims in windows:
        tasks.append(dask.delayed(_ng_legacy_task, pure=False)(*_block_input(array, source, lo, bdims), tuple(block_id),
                                                               job, out_dir, transform, chosen, threads))
        ids.append(list(block_id))
    results = _compute(tasks, client, progress)
    segments: Dict[int, List[Any]] = {}
    triangles = 0
    for block_id, rows in zip(ids, results):
        for label, t in rows:
            segments.setdefault(int(label), []).append(block_id)
            triangles += int(t)
    _isolab.ng_legacy_manifests(out_dir, segments)
    return {"out": out_dir, "format": "neuroglancer-legacy", "segments": len(segments),
            "fragments": [sum(len(v) for v in segments.values())], "triangles": [triangles], "chunk": chunk}
