"""curvflow: curvature-driven deformation of triangle meshes, from Python.

A thin ctypes layer over libcurvflow (the C library of this repository):
every computation is the library's. Quick start::

    import curvflow
    V, F, extras = curvflow.load("spot.obj")
    V2, log = curvflow.flow(V, F, "spin-willmore", steps=10)
    curvflow.save("spot_round.ply", V2, F, uv=extras["uv"], uv_faces=extras["uv_faces"],
                  fields={"Q": curvflow.compare(V, V2, F)["Q"]})
    print(log[-1]["energy"], curvflow.info(V2, F)["willmore_over_4pi"])

See docs/python.md for the array conventions, errors, cancellation and the
batch runner (python3 -m curvflow.batch).
"""
from . import _blas_kernels, _lib

# before numpy (imported by .core) loads OpenBLAS: its kernels (_blas_kernels.py)
_blas_kernels.choose_before_loading(_lib.first_candidate())

from .core import (check_params, compare, edit, flow, info, load, loop_subdivide, method_params, methods, read_log,
                   save, spin, weld, write_log, write_text_atomic)
from .errors import (CancelledError, CurvflowError, CurvflowMemoryError, InvalidMeshError, LibraryNotFoundError,
                     MeshFormatError, MeshIOError, NumericalError, UnsupportedError, UsageError)
from .report import report

__version__ = "0.1.0"


def library_path():
    """Path of the libcurvflow.so in use (loads it if needed)."""
    from . import _lib
    return _lib.lib().curvflow_path


def library_version():
    """The library's version string (cf_version_string)."""
    from . import _lib
    return _lib.lib().cf_version_string().decode()


__all__ = ["flow", "edit", "spin", "compare", "load", "save", "info", "weld", "loop_subdivide", "methods",
           "method_params", "check_params", "write_log", "read_log", "write_text_atomic", "report", "library_path", "library_version",
           "CurvflowError", "UsageError", "InvalidMeshError", "MeshFormatError", "MeshIOError", "UnsupportedError",
           "NumericalError", "CurvflowMemoryError", "CancelledError", "LibraryNotFoundError"]
