"""isolab: isosurface meshes from numpy arrays.

Three ways in:

* :func:`marching_cubes` has scikit-image's signature, return value and conventions
  (``skimage.measure.marching_cubes``), so replacing the import is enough.
* :func:`mesh_labels` meshes a label map (a segmentation) into one closed mesh per label, the
  meshes of neighbouring labels sharing their interface triangles.
* :func:`extract` runs any registered isolab extractor (marching cubes, surface nets, dual
  contouring, marching tetrahedra, regularised marching tetrahedra, bcc-sculpt, ...) and its
  post-processes on an array, a built-in field or a file, and returns a :class:`Mesh` that can
  be measured (:meth:`Mesh.metrics`) and saved (:meth:`Mesh.save`).

>>> import numpy as np, isolab
>>> i, j, k = np.mgrid[-1:1:40j, -1:1:40j, -1:1:40j]
>>> ball = (i**2 + j**2 + k**2).astype(np.float32)
>>> verts, faces, normals, values = isolab.marching_cubes(ball, 0.5)
>>> mesh = isolab.extract(ball, 0.5, "surface-nets")
>>> mesh.metrics()["closed"]
True

Errors are :class:`IsolabError` subclasses that are also the built-in exceptions (``ValueError``,
``OSError``, ``MemoryError``, ``TypeError``): see :mod:`isolab.errors`.

Every call releases the GIL while it works; ``threads=N`` runs it on a pool of N threads (kept
for later calls), ``threads=None`` on rayon's global pool (one thread per core, or
``RAYON_NUM_THREADS``).
"""

from __future__ import annotations

import json
import os
import sys
import warnings
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _isolab
from .errors import (IsolabError, IsolabMemoryError, IsolabOSError, IsolabTypeError, IsolabValueError,
                     raises_isolab_errors)

__all__ = ["marching_cubes", "extract", "Mesh", "mesh_labels", "LabelMeshes", "Patch", "metrics", "load", "algorithms", "fields",
           "IsolabError", "IsolabValueError", "IsolabTypeError", "IsolabOSError", "IsolabMemoryError", "__version__"]
__version__ = _isolab.__version__

# The dtypes read in place; any other is converted to float32 first (a copy).
_READ_IN_PLACE = {np.dtype(t) for t in (np.bool_, np.uint8, np.int8, np.uint16, np.int16, np.uint32, np.int32,
                                        np.uint64, np.int64, np.float32, np.float64)}


def _as_volume(volume: Any) -> np.ndarray:
    if not isinstance(volume, np.ndarray):
        volume = np.asarray(volume)
    if volume.dtype not in _READ_IN_PLACE:
        volume = volume.astype(np.float32)
    return volume


@raises_isolab_errors
def marching_cubes(volume: np.ndarray, level: Optional[float] = None, *, spacing: Sequence[float] = (1.0, 1.0, 1.0),
                   gradient_direction: str = "descent", step_size: int = 1, allow_degenerate: bool = True,
                   method: str = "lewiner", mask: Optional[np.ndarray] = None,
                   threads: Optional[int] = None,
                   memory_limit: Optional[int] = None) -> Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Marching cubes with scikit-image's interface: ``skimage.measure.marching_cubes``'s
    arguments, return value, axis order, winding and errors.

    Parameters
    ----------
    volume : (M, N, P) array
        Meshed where it lies, with no copy, in its own dtype (bool, 8- to 32-bit integers,
        float32, float64: the sweep is compiled for each) and memory order (C, Fortran, or any
        strided view of an array of the same dtype, ``step_size`` included). Each sample is read
        as float32, as scikit-image's ``astype(float32)`` converts it. 64-bit integers, other
        dtypes (float16, ...) and views over another dtype's memory are converted into float32
        first (one copy).
    level : float, optional
        The iso-value; by default the middle of the data range, ``(min + max) / 2`` (one pass
        over the samples). A sample is inside where it is above the level compared as a float64,
        as scikit-image compares. A level outside the range raises ``ValueError`` (checked only
        when nothing was meshed, as only such a level meshes nothing).
    spacing : 3 floats
        Voxel spacing along each axis; the vertices are scaled by it (the normals are not, as in
        scikit-image).
    gradient_direction : 'descent' or 'ascent'
        'descent' (the object is brighter than its surroundings) winds the faces as
        scikit-image does; 'ascent' reverses them.
    step_size : int
        Mesh every ``step_size``-th sample along each axis (a coarser mesh).
    allow_degenerate : bool
        With False, as in scikit-image, every triangle with two vertices at one position is
        removed and those vertices are merged (samples at the level are then interpolated
        exactly, for both methods); vertices no triangle uses are dropped as well.
    method : 'lewiner' or 'lorensen'
        'lorensen' gives scikit-image's ``method='lorensen'`` vertices (linear interpolation on
        every crossing edge, within float32 rounding) and triangle count: isolab's
        ``marching-cubes`` table makes as many triangles as scikit-image's classic table in each of
        the 254 corner patterns that have a surface (tested), though it may cut a polygon along
        other diagonals. 'lewiner' is isolab's ``marching-cubes-33`` (Chernyaev's marching cubes
        33, as scikit-image's is): every cell's mesh has the topology of the trilinear
        interpolant's level set, the ambiguous faces by the asymptotic decider and the tunnels
        through a cell's interior by an exact test (scikit-image's Lewiner tests one slice of the
        cell, which errs on some cells; tested against a fine sampling of the interpolant). Like
        scikit-image it adds a vertex inside some cells, at the same weighted centre (kept a
        thousandth of the cell inside its faces); a tunnel's tube may be drawn otherwise than
        scikit-image's, each cell taking one that does not cross itself at its own vertices
        (another triangulation, a ring of three vertices around the tunnel's waist, or its
        centre vertex moved), so the mesh never crosses itself. The mesh is closed wherever it
        does not reach the volume's boundary and manifold, and no triangle has zero area (a
        crossing within 1e-4 of a sample is kept that far from it).
    mask : (M, N, P) bool array, optional
        Only the cells whose highest corner (the largest index along every axis) is True are
        meshed, the corner scikit-image reads the mask at.
    threads : int, optional
        Threads for this call (isolab's addition; None: every core).
    memory_limit : int, optional
        Bytes the returned arrays may take (isolab's addition). Before they are allocated, the
        call estimates them (counting the crossing edges of a sample of the volume's layers) and
        raises ``MemoryError``, having allocated nothing, when they would not fit. None: the
        memory available to the process (``MemAvailable``, or ``ISOLAB_MEMORY_MIB`` when set).

    Returns
    -------
    verts : (V, 3) float32
        Vertex positions in index order (axis 0, 1, 2) times ``spacing``.
    faces : (F, 3) int32
        Triangles, indices into ``verts``.
    normals : (V, 3) float32
        Unit normals from the volume's gradient (central differences), toward decreasing values.
    values : (V,) float32
        For each vertex, the largest range of values, ``max(0, max - level) - min(0, min -
        level)``, over the cells around it (around its edge; around its sample for a vertex at
        a sample; with a mask, the cells whose triangles use it): scikit-image's measure.

    >>> import numpy as np, isolab
    >>> i, j, k = np.mgrid[-1:1:32j, -1:1:32j, -1:1:32j]
    >>> verts, faces, normals, values = isolab.marching_cubes(i**2 + j**2 + k**2, 0.5, method="lorensen")
    >>> verts.dtype, faces.dtype, faces.shape[1]
    (dtype('float32'), dtype('int32'), 3)
    >>> bool(np.allclose(np.linalg.norm(verts / 15.5 - 1, axis=1), 0.5 ** 0.5, atol=0.02))
    True
    """
    if not isinstance(volume, np.ndarray) or volume.ndim != 3:
        raise ValueError("Input volume should be a 3D numpy array.")
    if volume.shape[0] < 2 or volume.shape[1] < 2 or volume.shape[2] < 2:
        raise ValueError("Input array must be at least 2x2x2.")
    if len(spacing) != 3:
        raise ValueError("`spacing` must consist of three floats.")
    step_size = int(step_size)
    if step_size < 1:
        raise ValueError("step_size must be at least one.")
    if gradient_direction not in ("descent", "ascent"):
        raise ValueError(f"Incorrect input {gradient_direction} in `gradient_direction`, see docstring.")
    if method == "lewiner":
        faces_rule, on_iso = "trilinear", "separate"
    elif method == "lorensen":
        faces_rule, on_iso = "separate", "exact"
    else:
        raise ValueError("method should be either 'lewiner' or 'lorensen'")
    if mask is not None:
        if not mask.shape == volume.shape:
            raise ValueError("volume and mask must have the same shape.")
        mask = np.asarray(mask, dtype=bool)
    volume = _as_volume(volume)
    out = _isolab.marching_cubes(volume, None if level is None else float(level), tuple(float(s) for s in spacing),
                                 step_size, faces_rule, on_iso, gradient_direction == "ascent", bool(allow_degenerate),
                                 mask, threads, None if memory_limit is None else int(memory_limit))
    verts, faces, normals, values = out["vertices"], out["faces"], out["normals"], out["values"]
    if not len(verts):
        raise RuntimeError("No surface found at the given iso value.")
    return verts, faces, normals, values


def _index_to_world(affine: Optional[np.ndarray], spacing: Optional[Sequence[float]]) -> Optional[List[List[float]]]:
    """An array's index-to-world matrix as rows: ``affine`` (4 x 4), else ``spacing`` on the
    diagonal, else None (index coordinates)."""
    if affine is not None:
        a = np.asarray(affine, dtype=np.float64)
        if a.shape != (4, 4):
            raise ValueError(f"affine must be a 4 x 4 matrix; its shape is {a.shape}")
        return [list(map(float, row)) for row in a]
    if spacing is not None:
        if len(spacing) != 3:
            raise ValueError("spacing must consist of three floats.")
        sx, sy, sz = (float(s) for s in spacing)
        return [[sx, 0.0, 0.0, 0.0], [0.0, sy, 0.0, 0.0], [0.0, 0.0, sz, 0.0], [0.0, 0.0, 0.0, 1.0]]
    return None


class Mesh:
    """A mesh :func:`extract` made: numpy arrays in world coordinates and the run's numbers.

    Attributes
    ----------
    vertices : (N, 3) float32
    faces : (M, 3) int32
        Counter-clockwise seen from outside (normals toward the outside of ``inside``).
    normals : (N, 3) float32 or None
    materials : (N,) uint8 or None
        Each vertex's material (``materials=True``).
    tet_vertices, tetrahedra : (K, 3) float32 and (T, 4) int32, or None
        The tetrahedral mesh of a volume extractor (``bcc-sculpt``, ``isosurface-stuffing``).
    stats : dict
        The CLI's JSON for the run: stage times in ``times_ms``, counts, the input, warnings.
    warnings : list of str
    """

    def __init__(self, parts: Dict[str, Any]):
        self.vertices: np.ndarray = parts["vertices"]
        self.faces: np.ndarray = parts["faces"]
        normals = parts.get("normals")
        self.normals: Optional[np.ndarray] = normals if normals is not None and len(normals) else None
        self.materials: Optional[np.ndarray] = parts.get("materials")
        self.tet_vertices: Optional[np.ndarray] = parts.get("tet_vertices")
        self.tetrahedra: Optional[np.ndarray] = parts.get("tetrahedra")
        self.warnings: List[str] = list(parts.get("warnings", []))
        self.notes: List[str] = list(parts.get("notes", []))
        self._run = parts["run"]
        self._space = parts.get("space")
        self.stats: Dict[str, Any] = json.loads(self._run.report())

    def __repr__(self) -> str:
        tets = "" if self.tetrahedra is None else f", {len(self.tetrahedra)} tetrahedra"
        return f"<isolab.Mesh {self.stats.get('algorithm')}: {len(self.vertices)} vertices, {len(self.faces)} faces{tets}>"

    @raises_isolab_errors
    def metrics(self, self_intersections: bool = False, threads: Optional[int] = None) -> Dict[str, Any]:
        """The CLI's metrics of this mesh (``isolab extract -m``): triangle quality, topology
        (closed, manifold, oriented, genus), volume, area, distance of the vertices to the true
        surface and normal deviation (the field the mesh came from is kept for this), quad
        overdraw, histograms; the tetrahedra's measures for a volume extractor. The exact
        self-intersection test (``--self-intersections``; seconds on millions of triangles)
        only with ``self_intersections=True``.

        >>> import isolab
        >>> m = isolab.extract("torus", algorithm="marching-cubes", resolution=32).metrics()
        >>> m["closed"], m["genus"]
        (True, 1)
        """
        return json.loads(_isolab.metrics(self.vertices, self.faces, self.normals, self.tet_vertices, self.tetrahedra,
                                          self._run, self_intersections, threads))

    @raises_isolab_errors
    def save(self, path: Union[str, os.PathLike]) -> None:
        """Writes the mesh in the format the extension names: ``.obj``, ``.ply``, ``.stl``
        (binary), ``.glb`` or ``.gltf`` (with normals, and vertex colours for materials),
        atomically (a failed write leaves no file); a volume extractor's tetrahedra beside it as
        ``.vtk``. Raises ``OSError`` for an unwritable path, ``ValueError`` for another
        extension.
        """
        materials = None if self.materials is None else np.asarray(self.materials, dtype=np.uint8).tolist()
        _isolab.save(os.fspath(path), self.vertices, self.faces, self.normals, materials, self.tet_vertices,
                     self.tetrahedra, self._space)


def _batch_caller(fn: Callable[[np.ndarray], Any], progress: bool) -> Callable[[np.ndarray], np.ndarray]:
    """``fn`` as :func:`extract` calls it: its answer for a batch of points as a float64 vector,
    or ``ValueError`` naming the batch and its points' bounds for a wrong length, a dtype that
    is not real numbers, or a value that is not finite."""
    state = {"batch": 0, "points": 0}

    def call(points: np.ndarray) -> np.ndarray:
        number = state["batch"]
        state["batch"] += 1
        state["points"] += len(points)
        where = lambda: f"batch {number} (points in {points.min(axis=0).tolist()}..{points.max(axis=0).tolist()})"
        values = fn(points)
        if hasattr(values, "__array__") or isinstance(values, (list, tuple)):
            array = np.asarray(values)
        elif hasattr(values, "__dlpack__"):
            array = np.from_dlpack(values)
        else:
            raise ValueError(f"{where()}: the function returned {type(values).__name__}; an array of {len(points)} values is needed")
        if array.dtype.kind not in "biuf":
            raise ValueError(f"{where()}: the function returned dtype {array.dtype}; real numbers are needed")
        array = array.reshape(-1) if array.ndim == 2 and array.shape[1:] == (1,) else array
        if array.shape != (len(points),):
            raise ValueError(f"{where()}: {len(points)} points gave values of shape {array.shape}; one value per point is needed")
        array = np.ascontiguousarray(array, dtype=np.float64)
        bad = ~np.isfinite(array)
        if bad.any():
            i = int(np.argmax(bad))
            raise ValueError(f"{where()}: the value at point {points[i].tolist()} is {array[i]}; every value must be finite")
        if progress:
            print(f"\risolab: {state['batch']} batches, {state['points']} points evaluated", end="", file=sys.stderr, flush=True)
        return array

    return call


@raises_isolab_errors
def extract(data: Union[np.ndarray, str, os.PathLike, Callable[[np.ndarray], Any]], level: Optional[float] = None, algorithm: str = "marching-cubes", *,
            spacing: Optional[Sequence[float]] = None, affine: Optional[np.ndarray] = None, inside: Optional[str] = None,
            options: Optional[Mapping[str, Any]] = None, post: Sequence[str] = (), threads: Optional[int] = None,
            resolution: Optional[int] = None, dims: Optional[Sequence[int]] = None, lattice: str = "cubic",
            seed: Optional[int] = None, chunk: Optional[int] = None, materials: bool = False,
            bounds: Optional[Sequence[Sequence[float]]] = None, lipschitz: Optional[float] = None, sparse: bool = True,
            batch: int = 1 << 16, progress: bool = False) -> Mesh:
    """Meshes ``data`` with a registered extractor (``isolab.algorithms()`` lists them) and
    post-processes, through the pipeline the ``isolab extract`` CLI runs; or, when ``data`` is a
    callable, the field it gives, evaluated only near its surface.

    Parameters
    ----------
    data : 3-D numpy array, str or path
        An array (any numeric dtype, C or Fortran order or strided; meshed on its own grid,
        sample ``[i, j, k]`` at index ``(i, j, k)``; copied once, in its own dtype for an
        extractor that reads samples where they lie (``isolab.algorithms()``' ``samples``), as
        float32 for one that copies them anyway), a built-in field name (``"sphere"``,
        ``"torus"``, ``"gyroid"``, ... ``isolab.fields()``) sampled at ``resolution``, or a path
        to any file the CLI reads (a mesh: .obj .ply .stl .glb .gltf, meshed as its signed
        distance; a volume: .nii .nii.gz .nrrd .nhdr .mhd .mha, a zarr store's folder); or a
        callable ``fn(points) -> values``: ``points`` an (N, 3) float64 array of world points,
        ``values`` N real numbers (numpy, anything with ``__array__`` or DLPack, such as a CPU
        torch tensor). A callable needs ``bounds`` and ``resolution``; inside is below
        ``level``. Its grid's samples sit at ``bounds[0] + index * h``, ``resolution`` of them
        along the longest side, the first and last on the bounds there (along a shorter side,
        the last within ``h / 2`` of its bound), so a numpy grid built that way and meshed with
        ``affine=`` gives the same mesh. The grid is split into blocks of ``chunk`` cells (default 4,
        or for an extractor with an apron four times it and at least 8; a sample two blocks read is
        evaluated once, so smaller blocks follow the surface closer for more work outside ``fn``:
        ``chunk=2`` pays for an expensive ``fn`` such as a neural network, a larger chunk for a
        cheap one) and only the blocks that may hold the surface are evaluated: with ``lipschitz`` (a
        bound L with ``|fn(p) - fn(q)| <= L |p - q|``; 1 for a signed distance) a block is dropped
        only when values at its centre, or at its halves' and quarters' centres, prove it
        one-sided, and the mesh equals the dense grid's meshed in blocks; without one, blocks are kept where the values at the block corners change
        sign, with one block of margin, a heuristic that misses any part of the surface that lies
        wholly inside the blocks it drops (a bubble or a tube thinner than a block that crosses no
        block edge twice). ``sparse=False`` evaluates every sample, for comparison. Points come in
        batches of at most ``batch``; the GIL is held only while ``fn`` runs. ``mesh.stats``
        gives ``evaluations`` (each grid sample at most once, however many blocks read it, and
        ``pruning_evaluations`` of them spent ruling blocks out, ``refinement_evaluations`` of
        those below the blocks), ``batches``, ``function_ms``
        (time inside ``fn``) and ``other_ms``.
        A wrong length, dtype or a NaN raises ``ValueError`` naming the batch and its points'
        bounds; an exception inside ``fn`` propagates unchanged.
    level : float, optional
        The iso-value; default 0 for fields and arrays, Otsu's threshold for a scan file.
    algorithm : str
        An extractor name, e.g. ``"marching-cubes"``, ``"surface-nets"``, ``"dual-contouring"``.
    spacing : 3 floats, optional
        Voxel spacing of an array along its axes (world = index * spacing).
    affine : (4, 4) array, optional
        An array's index-to-world matrix (as nibabel's ``img.affine``); overrides ``spacing``.
    inside : 'below' or 'above', optional
        Which side of ``level`` is inside; the mesh is wound outward from it. Default 'below'
        for arrays and fields (signed distances), the file's own for volume files (scans:
        'above').
    options : dict, optional
        Extractor options as the CLI's ``--set NAME=VALUE`` (``{"smoothing": "elastic"}``).
    post : list of str
        Post-processes to apply in order, each ``NAME`` or ``NAME:OPTION=VALUE,...`` as the
        CLI's ``--post`` (``"edge-collapse"``; ``"keep-components:largest=1"`` keeps a scan's
        largest part, ``"keep-components:largest=0,min-volume=100"`` drops parts under 100 voxels).
    threads : int, optional
        Threads for this call; 1 runs the extractors that have a serial path serially.
    resolution, dims, lattice, seed, chunk, materials
        As the CLI's ``--resolution`` (samples along the longest side; for a volume file it
        resamples), ``--dims``, ``--lattice`` ('cubic' or 'bcc'), ``--seed``, ``--chunk`` and
        ``--materials``.

    Returns
    -------
    Mesh
        No mesh metric is computed unless asked for (:meth:`Mesh.metrics`).

    Raises ``ValueError`` with the CLI's message for an unknown algorithm, option or
    post-process, NaN or infinite data, an impossible lattice; ``OSError`` for an unreadable file.

    >>> import numpy as np, isolab
    >>> i, j, k = np.mgrid[-1:1:48j, -1:1:48j, -1:1:48j]
    >>> mesh = isolab.extract(i**2 + j**2 + k**2 - 0.5, algorithm="surface-nets", spacing=(2/47, 2/47, 2/47))
    >>> mesh.stats["algorithm"], mesh.faces.shape[1]
    ('surface-nets', 3)
    >>> bool(abs(np.linalg.norm(mesh.vertices - 1, axis=1).mean() - 0.5 ** 0.5) < 0.01)
    True

    A function, evaluated near its surface only (a signed distance: Lipschitz bound 1):

    >>> sphere = lambda points: np.linalg.norm(points, axis=1) - 0.4
    >>> mesh = isolab.extract(sphere, 0.0, "marching-cubes", bounds=((-0.5,) * 3, (0.5,) * 3), resolution=129, lipschitz=1.0)
    >>> mesh.stats["evaluations"] * 4 < mesh.stats["dense_points"], mesh.metrics()["closed"]
    (True, True)
    """
    opts = None if options is None else {str(k): str(v) for k, v in options.items()}
    if callable(data) and not isinstance(data, np.ndarray):
        if bounds is None or resolution is None:
            raise ValueError("a callable needs bounds=((x0, y0, z0), (x1, y1, z1)) and resolution= (samples along the longest side)")
        try:
            lo, hi = (tuple(float(v) for v in corner) for corner in bounds)
        except (TypeError, ValueError):
            raise ValueError(f"bounds must be ((x0, y0, z0), (x1, y1, z1)), not {bounds!r}") from None
        if len(lo) != 3 or len(hi) != 3:
            raise ValueError(f"bounds must be ((x0, y0, z0), (x1, y1, z1)), not {bounds!r}")
        parts = _isolab.extract_function(_batch_caller(data, progress), 0.0 if level is None else float(level), algorithm,
                                         (lo, hi), int(resolution), None if lipschitz is None else float(lipschitz),
                                         bool(sparse), int(batch), None if chunk is None else int(chunk), opts, threads)
        if progress:
            print(file=sys.stderr)
        return Mesh(parts)
    dims_ = None if dims is None else tuple(int(d) for d in dims)
    if len(dims_ or (0, 0, 0)) != 3:
        raise ValueError(f"dims must be three numbers of samples, not {dims!r}")
    affine_ = None
    if isinstance(data, (str, os.PathLike)):
        data = os.fspath(data)
    else:
        data = _as_volume(data)
        affine_ = _index_to_world(affine, spacing)
    parts = _isolab.extract(data, None if level is None else float(level), algorithm, affine_, inside, opts, list(post),
                            threads, resolution, dims_, lattice, seed, chunk, materials)
    return Mesh(parts)


class Patch:
    """One interface of a label map's meshes: the triangles two labels share (VTK's
    ``vtkSurfaceNetsAtlas`` calls it a patch), from :attr:`LabelMeshes.patches`.

    Attributes
    ----------
    labels : (int, int)
        ``(inside, outside)``, ``inside > outside`` as in :attr:`LabelMeshes.pairs`; the normals
        point from ``inside`` into ``outside``. ``0`` is the background.
    vertices : (N, 3) float32
        The patch's own vertices (a copy).
    faces : (M, 3) int32
        Its triangles, indices into ``vertices``.
    vertex_ids : (N,) int64
        Each vertex's index in :attr:`LabelMeshes.vertices`, so an edit of the patch can be
        written back (``meshes.vertices[patch.vertex_ids] = patch.vertices``).
    border : (N,) bool
        The vertices on the patch's border (an edge in one of its triangles): where it meets
        other patches (the junctions of three or more labels) or the map's open border. Keep
        them in place to smooth or decimate this interface without pulling the others apart.
    """

    def __init__(self, labels: Tuple[int, int], vertices: np.ndarray, faces: np.ndarray, vertex_ids: np.ndarray,
                 border: np.ndarray):
        self.labels = labels
        self.vertices = vertices
        self.faces = faces
        self.vertex_ids = vertex_ids
        self.border = border

    def __repr__(self) -> str:
        return (f"<isolab.Patch {self.labels[0]}|{self.labels[1]}: {len(self.vertices)} vertices "
                f"({int(self.border.sum())} on its border), {len(self.faces)} faces>")


def _patches(vertices: np.ndarray, faces: np.ndarray, pairs: np.ndarray) -> Dict[Tuple[int, int], Patch]:
    """The triangles of each label pair, each with its own vertices and border (see :class:`Patch`)."""
    out: Dict[Tuple[int, int], Patch] = {}
    if len(faces) == 0:
        return out
    key = (pairs[:, 0].astype(np.uint64) << np.uint64(32)) | pairs[:, 1].astype(np.uint64)
    order = np.argsort(key, kind="stable")
    _, starts = np.unique(key[order], return_index=True)
    for lo, hi in zip(starts, list(starts[1:]) + [len(order)]):
        rows = order[lo:hi]
        ids, local = np.unique(faces[rows], return_inverse=True)
        local = local.reshape(-1, 3).astype(np.int32)
        edges = np.sort(np.concatenate([local[:, [0, 1]], local[:, [1, 2]], local[:, [2, 0]]]), axis=1)
        unique_edges, counts = np.unique(edges, axis=0, return_counts=True)
        border = np.zeros(len(ids), dtype=bool)
        border[unique_edges[counts == 1].ravel()] = True
        a, b = (int(x) for x in pairs[rows[0]])
        out[(a, b)] = Patch((a, b), vertices[ids], local, ids.astype(np.int64), border)
    return out


class LabelMeshes(dict):
    """What :func:`mesh_labels` returns: a dict from each meshed label to its :class:`Mesh`
    (closed, wound outward from the label; ``mesh.stats`` has its label, counts and the triangles
    it shares with each neighbour, ``mesh.metrics()`` measures it), and the interfaces all labels
    share.

    Attributes
    ----------
    vertices : (N, 3) float32
        The vertices of the interface surface (every label's mesh uses some of them).
    faces : (M, 3) int32
        Its triangles, each once however many labels it bounds.
    pairs : (M, 2) uint32
        Each triangle's ``(inside, outside)`` labels, ``inside > outside``; its normal points
        from ``inside`` into ``outside``. ``0`` is the background.
    tetrahedra : (K, 4) int32
        From ``algorithm="lattice-cleaving"``: tetrahedra filling every label (indices into
        ``vertices``, positively oriented), conforming where labels meet: every interface
        triangle is a face of one tetrahedron of each of its two labels. Empty (0, 4) from a
        surface algorithm.
    tetrahedron_labels : (K,) uint32
        Each tetrahedron's label.
    patches : dict
        Each label pair's interface, ``(inside, outside)`` to a :class:`Patch` (computed on first
        use). With the per-label meshes (VTK's atlas calls them regions) this is what
        ``vtkSurfaceNetsAtlas`` gives. A label's surface is the patches that name it, so an edit
        of one patch that keeps its ``border`` in place, written back into ``vertices``, moves
        that interface alone and leaves every label sealed against its neighbours (two patches
        share only border vertices where the meshes are manifold: every map for
        ``marching-tetrahedra`` and ``lattice-cleaving``).
    missing : list of int
        Labels asked for (``labels=``) that do not occur (a warning is also issued).
    notes : list of str
    extract_ms : float
        The extraction's wall time (without reading the array and building the per-label
        meshes).
    """

    def __init__(self, parts: Dict[str, Any]):
        super().__init__()
        for label, one in parts["meshes"].items():
            self[int(label)] = Mesh(one)
        self.vertices: np.ndarray = parts["vertices"]
        self.faces: np.ndarray = parts["faces"]
        self.pairs: np.ndarray = parts["pairs"]
        self.tetrahedra: np.ndarray = parts["tetrahedra"]
        self.tetrahedron_labels: np.ndarray = parts["tetrahedron_labels"]
        self.missing: List[int] = list(parts["missing"])
        self.notes: List[str] = list(parts["notes"])
        self.extract_ms: float = float(parts["extract_ms"])
        self._patches: Optional[Dict[Tuple[int, int], Patch]] = None
        self._space: Optional[str] = parts.get("space")

    @property
    def patches(self) -> Dict[Tuple[int, int], Patch]:
        """Each label pair's interface (see :class:`Patch`).

        >>> import numpy as np, isolab
        >>> seg = np.zeros((8, 8, 8), np.uint8); seg[2:6, 2:6, 2:6] = 1; seg[4:6, 2:6, 2:6] = 2
        >>> meshes = isolab.mesh_labels(seg)
        >>> sorted(meshes.patches)
        [(1, 0), (2, 0), (2, 1)]
        >>> inner = meshes.patches[(2, 1)]
        >>> bool(inner.border.any()), len(inner.faces) == int((meshes.pairs == [2, 1]).all(1).sum())
        (True, True)
        """
        if self._patches is None:
            self._patches = _patches(self.vertices, self.faces, self.pairs)
        return self._patches

    @raises_isolab_errors
    def save_tetrahedra(self, path: Union[str, os.PathLike]) -> None:
        """Writes the tetrahedra and their labels as ``isolab labels -o`` does, in the format the
        extension names: ``.vtk`` (a legacy unstructured grid with a ``label`` cell array, for
        ParaView and meshio) or ``.msh`` (Gmsh's MSH 2.2, each label a physical volume of its
        number, for finite element codes), atomically. Raises ``ValueError`` for another
        extension or when there are no tetrahedra (only ``algorithm="lattice-cleaving"`` makes
        them), ``OSError`` for an unwritable path.

        >>> import numpy as np, isolab, os, tempfile
        >>> seg = np.zeros((6, 6, 6), np.uint8); seg[1:5, 1:5, 1:3] = 1; seg[1:5, 1:5, 3:5] = 2
        >>> meshes = isolab.mesh_labels(seg, algorithm="lattice-cleaving")
        >>> path = os.path.join(tempfile.mkdtemp(), "seg.msh")
        >>> meshes.save_tetrahedra(path)
        >>> open(path).readline().strip()
        '$MeshFormat'
        """
        if len(self.tetrahedra) == 0:
            raise ValueError(f"{os.fspath(path)}: no tetrahedra to write (algorithm=\"lattice-cleaving\" makes them)")
        _isolab.save_tetrahedra(os.fspath(path), self.vertices, self.tetrahedra, self.tetrahedron_labels.tolist(),
                                self._space)

    def __repr__(self) -> str:
        tets = f", {len(self.tetrahedra)} tetrahedra" if len(self.tetrahedra) else ""
        return f"<isolab.LabelMeshes: {len(self)} labels, {len(self.faces)} interface triangles{tets}>"


@raises_isolab_errors
def mesh_labels(label_map: Union[np.ndarray, str, os.PathLike], /, *, spacing: Optional[Sequence[float]] = None,
                affine: Optional[np.ndarray] = None, labels: Optional[Sequence[int]] = None,
                algorithm: str = "surface-nets", smoothing: Optional[Union[bool, str]] = None,
                border: str = "closed", options: Optional[Mapping[str, Any]] = None,
                threads: Optional[int] = None) -> LabelMeshes:
    """Meshes a label map (a segmentation: every sample an integer label, ``0`` the background)
    into one closed mesh per label, in one pass; where two labels meet, both meshes hold the same
    triangles (reversed), so there is no gap and no overlap between them.

    Parameters
    ----------
    label_map : 3-D integer array, or str or path
        An array of labels (uint8, uint16 and uint32 are read in place, other integer dtypes
        converted; ``bool`` is one label), sample ``[i, j, k]`` at index ``(i, j, k)``; or a
        volume file (.nii, .nii.gz, .nrrd, .nhdr, .mhd, .mha), placed in its world (RAS) as the
        CLI's ``isolab labels`` places it. A float array is refused: an intensity volume is
        meshed at a level with :func:`extract`.
    spacing : 3 floats, optional
        Voxel spacing along the array's axes (world = index * spacing).
    affine : (4, 4) array, optional
        The array's index-to-world matrix (as nibabel's ``img.affine``); overrides ``spacing``.
    labels : list of int, optional
        The labels to mesh (default: every label but 0); the others count as background.
    algorithm : str
        ``"surface-nets"`` (Frisken 2022, as VTK's ``vtkSurfaceNets3D``: smoothed, junctions kept
        sharp; a label's mesh can be non-manifold where three labels meet) or
        ``"marching-tetrahedra"`` (manifold for every map, unsmoothed, more triangles) or
        ``"lattice-cleaving"`` (Bronson et al. 2012: also fills every label with tetrahedra,
        ``tetrahedra`` and ``tetrahedron_labels``, every dihedral angle within the interval
        ``isolab.algorithms()`` declares for it; closed border only).
    smoothing : bool or str, optional
        Surface nets' constrained smoothing: ``True``/``"constrained"`` (the default) or
        ``False``/``"none"``.
    border : 'closed' or 'open'
        ``closed``: outside the array is background, so labels touching its border are closed
        there; ``open``: their meshes stay open at the border.
    options : dict, optional
        Other options, as ``isolab labels --set NAME=VALUE`` (``{"iterations": 32}``).
    threads : int, optional
        Threads for this call.

    Returns
    -------
    LabelMeshes
        A dict ``label -> Mesh`` with the shared interface surface as attributes.

    Raises ``TypeError`` for a float array, ``ValueError`` for a negative or too large label,
    an unknown algorithm or option; ``OSError`` for an unreadable file.

    >>> import numpy as np, isolab
    >>> seg = np.zeros((12, 12, 12), np.uint8)
    >>> seg[2:6, 2:10, 2:10] = 1
    >>> seg[6:10, 2:10, 2:10] = 2
    >>> meshes = isolab.mesh_labels(seg)
    >>> sorted(meshes), [meshes[l].metrics()["closed"] for l in (1, 2)]
    ([1, 2], [True, True])
    >>> shared = meshes.pairs.tolist().count([2, 1])
    >>> shared > 0 and shared == meshes[1].stats["neighbours"]["2"]
    True
    """
    opts = {} if options is None else {str(k): str(v) for k, v in options.items()}
    if smoothing is not None:
        opts["smoothing"] = ("constrained" if smoothing else "none") if isinstance(smoothing, bool) else str(smoothing)
    opts["border"] = str(border)
    affine_ = None
    if isinstance(label_map, (str, os.PathLike)):
        label_map = os.fspath(label_map)
    else:
        if not isinstance(label_map, np.ndarray):
            label_map = np.asarray(label_map)
        affine_ = _index_to_world(affine, spacing)
    chosen = None if labels is None else [int(s) for s in labels]
    out = LabelMeshes(_isolab.mesh_labels(label_map, affine_, chosen, algorithm, opts, threads))
    if out.missing:
        warnings.warn(f"labels {out.missing} do not occur in the label map: no mesh for them", stacklevel=2)
    return out


@raises_isolab_errors
def metrics(vertices: np.ndarray, faces: np.ndarray, *, self_intersections: bool = True,
            threads: Optional[int] = None) -> Dict[str, Any]:
    """The metrics ``isolab metrics FILE`` prints, for any triangle mesh given as arrays:
    quality, topology, volume, area, overdraw, histograms and (unless
    ``self_intersections=False``) the exact count of self-intersecting triangle pairs.

    >>> import numpy as np, isolab
    >>> tetra = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float32)
    >>> m = isolab.metrics(tetra, np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]))
    >>> m["closed"], m["euler"], m["self_intersections"]["count"], round(m["volume"], 6)
    (True, 2, 0, 0.166667)
    """
    return json.loads(_isolab.metrics(vertices, faces, None, None, None, None, self_intersections, threads))


@raises_isolab_errors
def load(path: Union[str, os.PathLike]) -> Tuple[np.ndarray, np.ndarray]:
    """Reads a file the CLI reads, deciding what it holds as the CLI does. A volume file (NIfTI,
    NRRD, MetaImage, isolab's grid, or a zarr store's folder: its last axis is x) gives
    ``(array, affine)``: the voxels in index order ``[i, j, k]`` (float32, Fortran-ordered over
    the buffer isolab read, no copy) and the 4 x 4 index-to-world affine (RAS for anatomical
    files, as nibabel's). A mesh file gives ``(vertices, faces)``. Raises ``OSError`` or
    ``ValueError`` naming the file and what is wrong.
    """
    kind, a, b = _isolab.load(os.fspath(path))
    if kind == "volume":
        return a, np.asarray(b, dtype=np.float64)
    return a, b


def algorithms() -> List[Dict[str, Any]]:
    """The registered extractors, post-processes and label extractors: ``name``, ``kind``
    ('extractor', 'post-process' or 'labels': what :func:`mesh_labels` runs), ``description``,
    ``options`` and ``guarantees`` (for label extractors: whether every label's mesh is closed,
    manifold and outward; for extractors: the
    lattices they mesh and whether their surface is closed, manifold, outward and free of
    self-intersections, as the contract test checks); for extractors also ``chunking``, how they
    mesh in blocks (``chunk=``, :mod:`isolab.dask`) with their default options: 'cell-local'
    (blocks share their boundary samples), 'apron' (blocks also read ``apron`` samples of their
    neighbours) or 'unsupported'; and ``samples``, how they read a numpy array: 'borrowed' (where
    it lies, in its own dtype and memory order, no copy) or 'copies: REASON' (converted once into
    float32 samples, and why). Every entry also has ``promises``, its guarantees as the one line
    ``isolab list`` prints: both read one listing, ``isolab_pipeline::registry``.

    >>> import isolab
    >>> [(a["chunking"], a["apron"]) for a in isolab.algorithms() if a["name"] == "marching-cubes"]
    [('cell-local', 0)]
    >>> [a["samples"] for a in isolab.algorithms() if a["name"] == "marching-cubes-33"]
    ['borrowed']
    """
    return json.loads(_isolab.algorithms())


def fields() -> List[Tuple[str, str]]:
    """The built-in fields :func:`extract` samples by name: ``(name, description)``."""
    return _isolab.fields()
