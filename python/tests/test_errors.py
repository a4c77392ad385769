"""isolab's exceptions are IsolabError subclasses that are also the built-in exceptions raised
before (pyvista's way), from every entry point, with the messages unchanged."""

import numpy as np
import pytest

import isolab
import isolab.dask
from isolab.errors import IsolabError, as_isolab_error


def test_a_bad_name_is_an_isolab_value_error_and_a_value_error():
    with pytest.raises(isolab.IsolabValueError) as e:
        isolab.extract(np.zeros((4, 4, 4), np.float32), 0.5, "no-such-extractor")
    assert isinstance(e.value, ValueError) and isinstance(e.value, IsolabError)
    assert "no-such-extractor" in str(e.value)


def test_a_missing_file_is_an_isolab_os_error_of_its_own_os_class(tmp_path):
    missing = tmp_path / "missing.nii.gz"
    with pytest.raises(isolab.IsolabOSError) as e:
        isolab.load(missing)
    assert isinstance(e.value, OSError) and "missing.nii.gz" in str(e.value)


def test_an_output_over_the_memory_limit_is_an_isolab_memory_error():
    i, j, k = np.mgrid[-1:1:32j, -1:1:32j, -1:1:32j]
    ball = (i**2 + j**2 + k**2).astype(np.float32)
    with pytest.raises(isolab.IsolabMemoryError) as e:
        isolab.marching_cubes(ball, 0.5, memory_limit=1000)
    assert isinstance(e.value, MemoryError)


def test_methods_and_the_dask_front_end_raise_them_too(tmp_path):
    mesh = isolab.extract("sphere", 0.0, "marching-cubes", resolution=16)
    with pytest.raises(isolab.IsolabValueError):
        mesh.save(tmp_path / "mesh.unknown-extension")
    assert not (tmp_path / "mesh.unknown-extension").exists()
    with pytest.raises(isolab.IsolabOSError):
        isolab.dask.load_fragment(str(tmp_path / "no-fragment.npz"))


def test_subclasses_keep_their_class_and_others_pass_through():
    e = as_isolab_error(FileNotFoundError(2, "No such file", "x.nii"))
    assert isinstance(e, FileNotFoundError) and isinstance(e, isolab.IsolabOSError)
    assert e.filename == "x.nii" and type(e).__name__ == "IsolabFileNotFoundError"
    assert type(as_isolab_error(FileNotFoundError(2, "again"))) is type(e), "one class per built-in subclass"
    other = KeyError("k")
    assert as_isolab_error(other) is other
    already = isolab.IsolabValueError("v")
    assert as_isolab_error(already) is already
