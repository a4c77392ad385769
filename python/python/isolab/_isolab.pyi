# The native module (python/src, pyo3): its functions are called only through the typed wrappers
# in __init__.py and dask.py, whose signatures users read; here every name is Any.
from typing import Any

def __getattr__(name: str) -> Any: ...
