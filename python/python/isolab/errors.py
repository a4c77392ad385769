"""isolab's exceptions: one base class, :class:`IsolabError`, whose subclasses are also the
built-in exceptions isolab raised before they existed (pyvista's way), so ``except ValueError``
keeps working and ``except isolab.IsolabError`` catches everything isolab raises on purpose.

>>> import numpy as np, isolab
>>> try:
...     isolab.extract(np.zeros((4, 4, 4), np.float32), 0.5, "no-such-extractor")
... except isolab.IsolabValueError as e:
...     print(isinstance(e, ValueError), "no-such-extractor" in str(e))
True True

Every public function of ``isolab`` and ``isolab.dask`` raises these: a bad argument, name,
option or array is an :class:`IsolabValueError` (or :class:`IsolabTypeError`), a file that cannot
be read or written an :class:`IsolabOSError` (``FileNotFoundError`` and the other ``OSError``
subclasses keep their class too), and an output larger than the memory available an
:class:`IsolabMemoryError`.
"""

from __future__ import annotations

import functools
from typing import Any, Callable, Dict, Type, TypeVar

__all__ = ["IsolabError", "IsolabValueError", "IsolabTypeError", "IsolabOSError", "IsolabMemoryError"]


class IsolabError(Exception):
    """The base of every exception isolab raises on purpose."""


class IsolabValueError(IsolabError, ValueError):
    """A bad value: an unknown extractor, field or option, an option out of range, an array
    isolab cannot mesh, a file in a format it does not read."""


class IsolabTypeError(IsolabError, TypeError):
    """An argument of the wrong type."""


class IsolabOSError(IsolabError, OSError):
    """A file or folder that cannot be read or written."""


class IsolabMemoryError(IsolabError, MemoryError):
    """An output larger than the memory available (or ``memory_limit=``), found before
    anything is allocated."""


_BASES = ((ValueError, IsolabValueError), (TypeError, IsolabTypeError), (OSError, IsolabOSError),
          (MemoryError, IsolabMemoryError))
_MADE: Dict[Type[BaseException], Type[IsolabError]] = {}


def _isolab_class(cls: Type[BaseException]) -> Type[IsolabError] | None:
    """The isolab class for a built-in exception class, made once for a subclass such as
    ``FileNotFoundError`` (``IsolabFileNotFoundError``: both that and ``IsolabOSError``)."""
    for builtin, base in _BASES:
        if cls is builtin:
            return base
        if issubclass(cls, builtin):
            if cls not in _MADE:
                _MADE[cls] = type(f"Isolab{cls.__name__}", (base, cls), {"__module__": __name__})
            return _MADE[cls]
    return None


def as_isolab_error(e: BaseException) -> BaseException:
    """``e`` as the matching :class:`IsolabError` (the same arguments and message), or ``e``
    itself when it is one already or matches none."""
    if isinstance(e, IsolabError):
        return e
    cls = _isolab_class(type(e))
    if cls is None:
        return e
    try:
        if isinstance(e, OSError) and e.errno is not None and e.filename is not None:
            new = cls(e.errno, e.strerror, e.filename, None, e.filename2)  # args hold no file names
        else:
            new = cls(*e.args)
    except Exception:  # an exception class with a constructor of its own: keep the original
        return e
    return new.with_traceback(e.__traceback__)


F = TypeVar("F", bound=Callable[..., Any])


def raises_isolab_errors(fn: F) -> F:
    """Wraps a public function so the built-in exceptions it raises leave as their
    :class:`IsolabError` subclasses (signature, docstring and doctests unchanged)."""

    @functools.wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return fn(*args, **kwargs)
        except (ValueError, TypeError, OSError, MemoryError) as e:
            new = as_isolab_error(e)
            if new is e:
                raise
            raise new from None

    return wrapper  # type: ignore[return-value]
