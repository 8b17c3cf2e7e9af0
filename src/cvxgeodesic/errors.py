"""Exception types raised by cvxgeodesic.

Every error a user can cause is one of these. They derive from the built-in
exception a caller would expect (``ValueError`` for bad input, ``RuntimeError``
for solver failure), so ``except ValueError`` keeps working.
"""

from __future__ import annotations

import errno
import os


class CvxGeodesicError(Exception):
    """Base class of every exception raised on purpose by cvxgeodesic."""


class MeshError(CvxGeodesicError, ValueError):
    """A mesh (arrays or file contents) is invalid; the message names the problem."""


class MeshFormatError(MeshError):
    """A mesh file cannot be read: missing, unsupported extension or malformed."""


class MeshFileNotFoundError(MeshFormatError, FileNotFoundError):
    """A mesh (or distance) file does not exist.

    Both a :class:`MeshFormatError` and a :class:`FileNotFoundError`, so ``except OSError`` and
    ``except FileNotFoundError`` catch it as they would ``open()``'s error; ``errno`` is ``ENOENT`` and
    ``filename`` the path. ``str()`` is the message alone (``"<path>: no such file"``).

    Parameters
    ----------
    message : str
    filename : str, optional
    """

    def __init__(self, message: str, filename: str | None = None) -> None:
        super().__init__(message)
        self.errno = errno.ENOENT
        self.strerror = "No such file or directory"
        self.filename = filename

    def __str__(self) -> str:
        # OSError's own __str__ would print "[Errno 2] No such file or directory: '<path>'" instead
        return str(self.args[0]) if self.args else ""

    def __reduce__(self) -> tuple[type, tuple[str, str | None]]:
        # OSError pickles as (errno, strerror, filename), which this __init__ does not take
        return type(self), (str(self), self.filename)


class OutputError(CvxGeodesicError, OSError):
    """An output could not be written (a full disk, a failing file system); the message names the file.

    An :class:`OSError` too (``except OSError`` catches it), with the ``errno`` of the failure and ``filename`` the
    output; ``str()`` is the message alone.

    Parameters
    ----------
    message : str
    filename : str, optional
    code : int, optional
        The ``errno`` of the failure.
    """

    def __init__(self, message: str, filename: str | None = None, code: int | None = None) -> None:
        super().__init__(message)
        self.errno = code
        self.strerror = os.strerror(code) if code is not None else None
        self.filename = filename

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""

    def __reduce__(self) -> tuple[type, tuple[str, str | None, int | None]]:
        return type(self), (str(self), self.filename, self.errno)


class SourceError(CvxGeodesicError, ValueError):
    """The source vertices passed to a solve are invalid."""


class ParameterError(CvxGeodesicError, ValueError):
    """A parameter (method name, smoothness weight, solver name, ...) is invalid."""


class NonManifoldError(MeshError):
    """The requested method needs an edge-manifold mesh and the mesh is not one."""


class DegenerateFacesWarning(UserWarning):
    """The mesh has degenerate (zero or near-zero area) faces, which the convex formulations leave out."""


class MeshRepairWarning(UserWarning):
    """``load_mesh`` changed the file's mesh: welded or dropped vertices, dropped faces; or a method reoriented faces
    for a library that depends on their orientation (the message says which; also in ``info.notes``)."""


class SolverError(CvxGeodesicError, RuntimeError):
    """A numerical solver did not return an optimal solution.

    Parameters
    ----------
    message : str
        Human-readable explanation.
    solver : str
        Name of the backend (``"clarabel"``, ``"ipm"``).
    status : str
        The backend's own status string (e.g. ``"MaxIterations"``).
    info : dict, optional
        Iterations, residuals and timings reached before the failure.
    """

    def __init__(self, message: str, *, solver: str, status: str, info: dict | None = None):
        super().__init__(f"{message} (solver={solver}, status={status})")
        self.solver = solver
        self.status = status
        self.info = dict(info or {})


class IndefiniteEnergyWarning(UserWarning):
    """libigl's curved Hessian energy is indefinite on this mesh; the planar Hessian energy is used instead."""


class CheckpointWarning(UserWarning):
    """``distance_matrix`` could not write its checkpoint (a full disk): the rows go on, and the matrix is returned,
    without it."""


#: Modules whose frames :func:`warn_user` passes over, as it does the package's own.
_TRANSPARENT = frozenset({"functools", "contextlib"})


def warn_user(message: str, category: type[Warning] = UserWarning) -> None:
    """``warnings.warn`` attributed to the first frame outside this package (the user's call), however deep the
    library's own call chain is."""
    import sys
    import types
    import warnings

    package = __name__.rsplit(".", 1)[0] + "."
    # stacklevel 1 is this function's own frame, 2 its caller's (``sys._getframe(1)``): counting from 1 here
    # attributed the warning to the last frame inside the package (issue 41: ``_threads.py:318``)
    frame: types.FrameType | None = sys._getframe(1)
    level = 2
    # the standard library's wrappers between two of the package's frames (a ``functools.cached_property``, a
    # ``contextlib`` manager) are the package's too: a lazy builder's warning was attributed to functools.py
    while frame is not None and ((name := frame.f_globals.get("__name__") or "").startswith(package)
                                 or name in _TRANSPARENT):
        frame, level = frame.f_back, level + 1
    warnings.warn(message, category, stacklevel=level)


def error_line(exc: BaseException, *, typed: bool = False) -> str:
    """The message of ``exc`` on one line (for a CSV cell, a table, a batch row), after its type's name unless it is
    one of the library's errors (whose messages say what went wrong) and not ``typed``."""
    msg = " ".join(str(exc).split())
    if isinstance(exc, CvxGeodesicError) and not typed:
        return msg or type(exc).__name__
    return f"{type(exc).__name__}: {msg}" if msg else type(exc).__name__
