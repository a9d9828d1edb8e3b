"""Exceptions raised by curvflow: one class per kind of library status.

Every library failure carries the library's one-line message (naming the
problem and its place: file, line, vertex, face, iteration) and the status
name, e.g. ``InvalidMeshError("face 12: edge (3, 9) is shared by 3 faces")``
with ``.status == "CF_ERR_NONMANIFOLD_EDGE"``. The classes also derive from
the matching built-in exception (ValueError, OSError, MemoryError,
ArithmeticError), so generic handlers keep working.

Failures of a flow run (raised by :func:`curvflow.flow` and
:func:`curvflow.edit` after the flow has started) carry the state reached:
``.last_positions`` (the last good (n, 3) positions) and ``.log`` (the
per-step log up to that state).
"""

__all__ = [
    "CurvflowError", "UsageError", "InvalidMeshError", "MeshFormatError", "MeshIOError",
    "UnsupportedError", "NumericalError", "CurvflowMemoryError", "CancelledError",
    "LibraryNotFoundError",
]


class CurvflowError(Exception):
    """Base class. ``status`` is the library's status name ("CF_ERR_...")
    or None for checks made in Python; ``code`` the numeric status;
    ``last_positions`` / ``log`` are set for failures during a flow run."""

    def __init__(self, message, status=None, code=None, last_positions=None, log=None):
        super().__init__(message)
        self.message = message
        self.status = status
        self.code = code
        self.last_positions = last_positions
        self.log = log


class UsageError(CurvflowError, ValueError):
    """A bad argument: unknown method or parameter, value out of range,
    wrong array shape (CF_ERR_INVALID_ARG; the CLI's exit status 1)."""


class InvalidMeshError(CurvflowError, ValueError):
    """The mesh is unusable: out-of-range or repeated face indices, NaN/Inf
    coordinates, zero-area faces, non-manifold edges or vertices,
    inconsistent orientation, a genus the option cannot handle
    (the CLI's exit status 2)."""


class MeshFormatError(InvalidMeshError):
    """Malformed or truncated file content (CF_ERR_PARSE, CF_ERR_TRUNCATED)."""


class MeshIOError(CurvflowError, OSError):
    """A file could not be opened, read, written or renamed (CF_ERR_IO)."""


class UnsupportedError(CurvflowError, ValueError):
    """A valid request this method, format or build does not support
    (CF_ERR_UNSUPPORTED), e.g. fields in an OFF file."""


class NumericalError(CurvflowError, ArithmeticError):
    """A numerical failure: NaN, a step that blew up, a matrix that is not
    positive definite, no convergence (the CLI's exit status 3).
    ``last_positions`` holds the last good state when raised by a flow."""


class CurvflowMemoryError(CurvflowError, MemoryError):
    """An allocation inside the library failed (CF_ERR_NOMEM)."""


class CancelledError(CurvflowError):
    """The flow was cancelled through the progress hook (CF_ERR_CANCELLED)
    for a reason other than Ctrl-C or a callback's exception (those are
    re-raised as themselves)."""


class LibraryNotFoundError(CurvflowError, OSError):
    """libcurvflow.so could not be found or loaded (see curvflow._lib)."""


# status code -> (name, class). Names and codes are the library's
# (include/curvflow/curvflow.h); the name is also asked from the library
# (cf_status_name) when an error is raised.
_BY_CODE = {
    -1: ("CF_ERR_INVALID_ARG", UsageError),
    -2: ("CF_ERR_NOMEM", CurvflowMemoryError),
    -3: ("CF_ERR_BAD_MESH", InvalidMeshError),
    -4: ("CF_ERR_IO", MeshIOError),
    -5: ("CF_ERR_NOT_POSDEF", NumericalError),
    -6: ("CF_ERR_NUMERICAL", NumericalError),
    -7: ("CF_ERR_NOT_CONVERGED", NumericalError),
    -8: ("CF_ERR_CANCELLED", CancelledError),
    -9: ("CF_ERR_PARSE", MeshFormatError),
    -10: ("CF_ERR_TRUNCATED", MeshFormatError),
    -11: ("CF_ERR_INDEX_RANGE", InvalidMeshError),
    -12: ("CF_ERR_REPEATED_INDEX", InvalidMeshError),
    -13: ("CF_ERR_NONFINITE", InvalidMeshError),
    -14: ("CF_ERR_DEGENERATE_FACE", InvalidMeshError),
    -15: ("CF_ERR_NONMANIFOLD_EDGE", InvalidMeshError),
    -16: ("CF_ERR_NONMANIFOLD_VERTEX", InvalidMeshError),
    -17: ("CF_ERR_ORIENTATION", InvalidMeshError),
    -18: ("CF_ERR_UNSUPPORTED", UnsupportedError),
}


def error_class(code):
    """The exception class for a library status code (CurvflowError for an
    unknown code)."""
    return _BY_CODE.get(code, (None, CurvflowError))[1]


def status_name(code):
    """Status name from the table above ("CF_ERR_..." or "status N")."""
    return _BY_CODE.get(code, ("status %d" % code, None))[0]
