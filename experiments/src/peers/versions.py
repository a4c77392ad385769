"""The installed version of each Python peer named on the command line, and of the library it
wraps where the wrapper says (experiments/src/peer_versions.rs runs this in the reference
environment, once per report run).

Usage: versions.py DIST [DIST ...]   (distribution names, as pip lists them)

Prints one JSON object: {dist: {"package": version or null, "library": version or null}}.
"library" is asked of the imported module only for the wrappers below; a wrapper that does not
say which library version it bundles gets null, never a guess.
"""

import importlib.metadata
import json
import os
import sys
import tempfile


def _vtk():
    import vtk

    return vtk.vtkVersion.GetVTKVersion()


def _cgal():
    import CGAL

    return CGAL.__version__


def _meshlab():
    """pymeshlab prints "PyMeshLab X based on MeshLab Y" from C++, so stdout is caught at the
    file-descriptor level."""
    import pymeshlab

    sys.stdout.flush()
    saved = os.dup(1)
    with tempfile.TemporaryFile(mode="w+b") as caught:
        os.dup2(caught.fileno(), 1)
        try:
            pymeshlab.print_pymeshlab_version()
        finally:
            sys.stdout.flush()
            os.dup2(saved, 1)
            os.close(saved)
        caught.seek(0)
        text = caught.read().decode("utf-8", "replace")
    marker = "based on MeshLab "
    return text.split(marker, 1)[1].split()[0] if marker in text else None


# Wrappers whose module says which library version it wraps.
LIBRARY_PROBES = {"vtk": _vtk, "cgal": _cgal, "pymeshlab": _meshlab}


def version_of(dist):
    try:
        package = importlib.metadata.version(dist)
    except importlib.metadata.PackageNotFoundError:
        return {"package": None, "library": None}
    probe = LIBRARY_PROBES.get(dist)
    library = None
    if probe is not None:
        try:
            library = probe()
        except Exception:  # an import that fails leaves the library version unknown
            library = None
    return {"package": package, "library": library}


def main(argv):
    json.dump({dist: version_of(dist) for dist in argv}, sys.stdout)
    sys.stdout.write("\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
