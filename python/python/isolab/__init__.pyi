"""Type stubs for isolab (the docstrings are in __init__.py)."""

import os
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__all__ = ["marching_cubes", "extract", "Mesh", "mesh_labels", "LabelMeshes", "Patch", "metrics", "load", "algorithms", "fields",
           "IsolabError", "IsolabValueError", "IsolabTypeError", "IsolabOSError", "IsolabMemoryError", "__version__"]

from .errors import IsolabError as IsolabError
from .errors import IsolabMemoryError as IsolabMemoryError
from .errors import IsolabOSError as IsolabOSError
from .errors import IsolabTypeError as IsolabTypeError
from .errors import IsolabValueError as IsolabValueError

__version__: str

def marching_cubes(
    volume: npt.NDArray[Any],
    level: Optional[float] = None,
    *,
    spacing: Sequence[float] = (1.0, 1.0, 1.0),
    gradient_direction: str = "descent",
    step_size: int = 1,
    allow_degenerate: bool = True,
    method: str = "lewiner",
    mask: Optional[npt.NDArray[np.bool_]] = None,
    threads: Optional[int] = None,
    memory_limit: Optional[int] = None,
) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.int32], npt.NDArray[np.float32], npt.NDArray[np.float32]]: ...

class Mesh:
    def __init__(self, parts: Dict[str, Any]) -> None: ...
    vertices: npt.NDArray[np.float32]
    faces: npt.NDArray[np.int32]
    normals: Optional[npt.NDArray[np.float32]]
    materials: Optional[npt.NDArray[np.uint8]]
    tet_vertices: Optional[npt.NDArray[np.float32]]
    tetrahedra: Optional[npt.NDArray[np.int32]]
    stats: Dict[str, Any]
    warnings: List[str]
    notes: List[str]
    def metrics(self, self_intersections: bool = False, threads: Optional[int] = None) -> Dict[str, Any]: ...
    def save(self, path: Union[str, os.PathLike[str]]) -> None: ...

def extract(
    data: Union[npt.NDArray[Any], str, os.PathLike[str], Callable[[npt.NDArray[np.float64]], Any]],
    level: Optional[float] = None,
    algorithm: str = "marching-cubes",
    *,
    spacing: Optional[Sequence[float]] = None,
    affine: Optional[npt.ArrayLike] = None,
    inside: Optional[str] = None,
    options: Optional[Mapping[str, Any]] = None,
    post: Sequence[str] = (),
    threads: Optional[int] = None,
    resolution: Optional[int] = None,
    dims: Optional[Sequence[int]] = None,
    lattice: str = "cubic",
    seed: Optional[int] = None,
    chunk: Optional[int] = None,
    materials: bool = False,
    bounds: Optional[Sequence[Sequence[float]]] = None,
    lipschitz: Optional[float] = None,
    sparse: bool = True,
    batch: int = 65536,
    progress: bool = False,
) -> Mesh: ...
def metrics(
    vertices: npt.ArrayLike, faces: npt.ArrayLike, *, self_intersections: bool = True, threads: Optional[int] = None
) -> Dict[str, Any]: ...
def load(path: Union[str, os.PathLike[str]]) -> Tuple[npt.NDArray[Any], npt.NDArray[Any]]: ...
def algorithms() -> List[Dict[str, Any]]: ...
def fields() -> List[Tuple[str, str]]: ...

class Patch:
    labels: Tuple[int, int]
    vertices: np.ndarray
    faces: np.ndarray
    vertex_ids: np.ndarray
    border: np.ndarray
    def __init__(
        self, labels: Tuple[int, int], vertices: np.ndarray, faces: np.ndarray, vertex_ids: np.ndarray, border: np.ndarray
    ) -> None: ...

def _patches(vertices: np.ndarray, faces: np.ndarray, pairs: np.ndarray) -> Dict[Tuple[int, int], Patch]: ...

class LabelMeshes(Dict[int, Mesh]):
    vertices: np.ndarray
    faces: np.ndarray
    pairs: np.ndarray
    tetrahedra: np.ndarray
    tetrahedron_labels: np.ndarray
    missing: List[int]
    notes: List[str]
    extract_ms: float
    _patches: Optional[Dict[Tuple[int, int], Patch]]
    _space: Optional[str]
    def save_tetrahedra(self, path: Union[str, os.PathLike[str]]) -> None: ...
    @property
    def patches(self) -> Dict[Tuple[int, int], Patch]: ...
    def __init__(self, parts: Dict[str, Any]) -> None: ...

def mesh_labels(
    label_map: Union[np.ndarray, str, os.PathLike],
    /,
    *,
    spacing: Optional[Sequence[float]] = ...,
    affine: Optional[np.ndarray] = ...,
    labels: Optional[Sequence[int]] = ...,
    algorithm: str = ...,
    smoothing: Optional[Union[bool, str]] = ...,
    border: str = ...,
    options: Optional[Mapping[str, Any]] = ...,
    threads: Optional[int] = ...,
) -> LabelMeshes: ...

def _index_to_world(affine: Optional[npt.NDArray[Any]], spacing: Optional[Sequence[float]]) -> Optional[List[List[float]]]: ...
