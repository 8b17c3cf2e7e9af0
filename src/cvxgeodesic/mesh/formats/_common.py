"""What the format modules share: the cells a reader returns, the field a writer takes, file checks."""

from __future__ import annotations

import importlib
import stat
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ...errors import MeshError, MeshFileNotFoundError, MeshFormatError

__all__ = ["FieldData", "RawMesh", "RawPoints", "at_line", "check_file", "file_errors", "format_error",
           "optional_package", "read_bytes", "split_normals"]

#: What to install for a format read or written through an optional package.
INSTALL_HINT = "pip install 'cvxgeodesic[io]' (or pip install {pkg})"


@dataclass
class RawMesh:
    """The cells a file holds, as read, before validation and welding: polygons and/or tetrahedra.

    Attributes
    ----------
    V : (n, 3) float64 ndarray
        Vertex positions in file order.
    idx : (k,) int64 ndarray
        Concatenated 0-based vertex indices of all polygons (not yet range-checked).
    sizes : (p,) int64 ndarray
        Number of vertices of each polygon; ``sizes.sum() == k``.
    v_lines, f_lines : (n,) / (p,) int64 ndarray (or lazily computed equivalent) or None
        1-based line number of each vertex / polygon (text formats only).
    raw_idx : (k,) int64 ndarray or None
        The indices as written in the file (for messages), when they differ from ``idx``.
    tets : (t, 4) int64 ndarray or None
        0-based corners of the file's tetrahedra (not yet range-checked); None or empty: it holds none.
    other_cells : dict of str to int or None
        For formats whose cells are typed: the file's cells other than tetrahedra, by type (meshio's names:
        ``"triangle"``, ``"line"``, ...) with their counts; what a volume ignores, named in its notes.
    notes : list of str
        What the reader changed in what it returns (10-node tetrahedra reduced to their corners).
    name : str or None
        The mesh's name when it is not the file's name (TetGen's pair: the common stem).
    """

    V: np.ndarray
    idx: np.ndarray
    sizes: np.ndarray
    v_lines: Any = None
    f_lines: Any = None
    raw_idx: np.ndarray | None = None
    tets: np.ndarray | None = None
    other_cells: dict[str, int] | None = None
    notes: list[str] = field(default_factory=list)
    name: str | None = None


@dataclass(frozen=True)
class RawPoints:
    """The points a point file holds, as read, before :class:`~cvxgeodesic.mesh.pointcloud.PointCloud` checks them.

    Attributes
    ----------
    P : (n, 3) float64 ndarray
        The points in file order.
    normals : (n, 3) float64 ndarray or None
        Their normals, when the file has them.
    """

    P: np.ndarray
    normals: np.ndarray | None = None


@dataclass(frozen=True)
class FieldData:
    """A per-vertex field on its mesh, as a writer gets it (one row per vertex written).

    Attributes
    ----------
    V : (n, 3) float64 ndarray
    cells : (m, 3) or (m, 4) int64 ndarray
        The triangles of a surface or the tetrahedra of a volume, as indices into ``V``.
    d : (n,) float64 ndarray
        The field (``inf`` allowed).
    name : str
        The field's name (a valid PLY property / CSV column name).
    vertex : (n,) int64 ndarray
        Mesh index of each row (-1: a file vertex the mesh dropped).
    file_vertex : (n,) int64 ndarray
        File index of each row.
    label : str
        The mesh's name, for a comment in the file.
    """

    V: np.ndarray
    cells: np.ndarray
    d: np.ndarray
    name: str
    vertex: np.ndarray
    file_vertex: np.ndarray
    label: str = "mesh"


def format_error(path: Path, msg: str) -> MeshFormatError:
    """``MeshFormatError("<path>: <msg>")``."""
    return MeshFormatError(f"{path}: {msg}")


@contextmanager
def file_errors(path: Path) -> Iterator[None]:
    """Turn every failure of reading ``path`` into a MeshFormatError naming the file.

    A reader's own MeshFormatError passes through; a MeshError (the arrays did not make a mesh) gets the
    path in front; the exceptions of parsing garbage (``ValueError``, ``IndexError``, ...) become
    ``"<path>: malformed <FORMAT> file (<exception>)"``.
    """
    try:
        yield
    except MeshFormatError:
        raise
    except MeshError as exc:
        raise format_error(path, str(exc)) from None
    except (ValueError, TypeError, IndexError, OverflowError, UnicodeDecodeError, MemoryError) as exc:
        raise format_error(path, f"malformed {path.suffix[1:].upper()} file ({type(exc).__name__}: {exc})") from None


def at_line(lines: Any, i: int) -> str:
    """``" (line N)"`` for record ``i`` when line numbers are known, else ``""``."""
    return f" (line {int(lines[i])})" if lines is not None else ""


def check_file(p: Path, what: str) -> None:
    """Raise unless ``p`` is an existing, non-empty regular file (after following links).

    Checked before anything opens the file: opening a FIFO blocks until someone writes to it, and a
    device (``/dev/zero``, ``/dev/urandom``) never ends, so either would make a reader wait or read forever.

    Raises
    ------
    MeshFileNotFoundError
        ``p`` does not exist (also a ``FileNotFoundError``; a link to nothing counts as missing).
    MeshFormatError
        ``p`` is a directory, not a regular file (a FIFO, a device, a socket), or has no bytes.
    """
    try:
        st = p.stat()  # follows links; never opens, so a FIFO cannot block here
    except (FileNotFoundError, NotADirectoryError):
        raise MeshFileNotFoundError(f"{p}: no such file", str(p)) from None
    except OSError as exc:
        raise format_error(p, f"cannot read file ({exc.strerror or exc})") from None
    if stat.S_ISDIR(st.st_mode):
        raise format_error(p, f"is a directory, not {what}")
    if not stat.S_ISREG(st.st_mode):
        raise format_error(p, f"is {_file_kind(st.st_mode)}, not {what} (only regular files are read)")
    if st.st_size == 0:
        raise format_error(p, "file is empty")


def _file_kind(mode: int) -> str:
    """What a non-regular file is, in words: ``"a FIFO"``, ``"a character device"``, ..."""
    for test, kind in ((stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a character device"),
                       (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return kind
    return "a special file"


def read_bytes(p: Path, what: str) -> bytes:
    """The whole file after :func:`check_file`; MeshFormatError when unreadable or only whitespace."""
    check_file(p, what)
    try:
        data = p.read_bytes()
    except OSError as exc:
        raise format_error(p, f"cannot read file ({exc.strerror or exc})") from None
    if not data.strip():
        raise format_error(p, "file is empty")
    return data


def optional_package(pkg: str, needed_for: str, error: type[Exception]) -> Any:
    """The optional package ``pkg``, or ``error("<needed_for> needs the optional package <pkg>: <hint>")``."""
    try:
        return importlib.import_module(pkg)
    except ImportError:
        raise error(f"{needed_for} needs the optional package {pkg}: " + INSTALL_HINT.format(pkg=pkg)) from None


def split_normals(path: Path, A: np.ndarray) -> RawPoints:
    """The points of an (n, 3) array, or the points and normals of an (n, 6) one; (n, k > 6) keeps its first three
    columns (a MeshFormatError for fewer than three)."""
    if A.ndim != 2 or A.shape[1] < 3:
        raise format_error(path, f"points must be an (n, 3) array (or (n, 6) with normals), got shape {A.shape}")
    return RawPoints(A[:, :3], A[:, 3:6] if A.shape[1] == 6 else None)
