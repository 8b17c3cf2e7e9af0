"""Point files: ``.xyz``, ``.pts``, ``.csv`` and ``.npy`` points, and PLY files with vertices and no faces.

:func:`load_point_cloud` reads them into a :class:`~cvxgeodesic.mesh.pointcloud.PointCloud`; ``as_mesh`` takes
their paths wherever a mesh is taken (:func:`is_point_file` decides). ``load_mesh`` keeps reading meshes only: a
PLY with faces is a mesh, one without faces a cloud.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import MeshError, MeshFileNotFoundError
from .pointcloud import PointCloud

__all__ = ["POINT_EXTENSIONS", "is_point_file", "load_point_cloud"]

#: Extensions read as points (a ``.ply`` is a cloud when it has no faces).
POINT_EXTENSIONS = (".xyz", ".pts", ".csv", ".npy")


def is_point_file(path: str | os.PathLike) -> bool:
    """Whether ``path`` names a point file: a :data:`POINT_EXTENSIONS` extension, or a PLY whose header declares no
    face (or a ``face`` element of count 0)."""
    p = Path(path)
    ext = p.suffix.lower()
    if ext in POINT_EXTENSIONS:
        return True
    if ext != ".ply" or not p.is_file():
        return False
    from .formats.ply import _parse_header

    with open(p, "rb") as fh:
        head = fh.read(1 << 16)
    try:
        _, elements, _, _ = _parse_header(p, head)
    except MeshError:
        return False
    return not any(el.name == "face" and el.count > 0 for el in elements)


def load_point_cloud(path: str | os.PathLike, **kwargs: Any) -> PointCloud:
    """Read a point file into a :class:`~cvxgeodesic.mesh.pointcloud.PointCloud`.

    Parameters
    ----------
    path : str or os.PathLike
        ``.xyz`` / ``.pts`` (whitespace-separated ``x y z`` per line, more columns allowed: columns 4–6 are normals
        when there are exactly six; a first line that is a point count, as ``.pts`` files often have, is skipped),
        ``.csv`` (comma-separated, an optional header line; columns ``nx, ny, nz`` in the header are normals),
        ``.npy`` (an (n, 3) or (n, 6) array: points, or points and normals), ``.ply`` without faces (``nx, ny, nz``
        vertex properties are normals).
    **kwargs
        Passed to :class:`PointCloud` (``triangles=``, ``neighbours=``).

    Returns
    -------
    PointCloud
        Named after the file's base name.

    Raises
    ------
    MeshError
        The file is unreadable (a missing one: :class:`~cvxgeodesic.errors.MeshFileNotFoundError`), a line is
        not numbers (the message names the line), the array has the wrong shape, a PLY has faces (read it with
        ``load_mesh``), or the points fail :class:`PointCloud`'s checks.
    """
    p = Path(path)
    if not p.is_file():
        raise MeshFileNotFoundError(f"{p}: no such file", str(p))
    ext = p.suffix.lower()
    if ext == ".npy":
        P, N = _split(_load_npy(p), p)
    elif ext == ".ply":
        P, N = _load_ply(p)
    elif ext in (".xyz", ".pts", ".csv"):
        P, N = _load_text(p, ext)
    else:
        raise MeshError(f"{p}: not a point file (extensions: {', '.join(POINT_EXTENSIONS)}, .ply without faces)")
    kwargs.setdefault("name", p.name)
    return PointCloud(P, N, **kwargs)


def _load_npy(p: Path) -> np.ndarray:
    try:
        A = np.load(p, allow_pickle=False)
    except (OSError, ValueError) as exc:
        raise MeshError(f"{p}: not a readable .npy array ({exc})") from None
    if A.dtype.kind not in "fiu":
        raise MeshError(f"{p}: the array holds {A.dtype}, not numbers")
    return np.asarray(A, dtype=np.float64)


def _split(A: np.ndarray, p: Path) -> tuple[np.ndarray, np.ndarray | None]:
    """Points and normals of an (n, 3) or (n, 6) array; (n, k > 6) keeps its first three columns."""
    if A.ndim != 2 or A.shape[1] < 3:
        raise MeshError(f"{p}: points must be an (n, 3) array (or (n, 6) with normals), got shape {A.shape}")
    return A[:, :3], (A[:, 3:6] if A.shape[1] == 6 else None)


def _load_text(p: Path, ext: str) -> tuple[np.ndarray, np.ndarray | None]:
    lines = p.read_text(encoding="utf-8", errors="replace").splitlines()
    sep = "," if ext == ".csv" else None
    rows: list[list[float]] = []
    numbers: list[int] = []
    header: list[str] | None = None
    for no, line in enumerate(lines, 1):
        text = line.split("#", 1)[0].strip()
        if not text:
            continue
        toks = [t.strip() for t in text.split(sep)]
        try:
            rows.append([float(t) for t in toks])
            numbers.append(no)
        except ValueError:
            if not rows and header is None:  # one header line (csv column names, a comment without '#')
                header = [t.lower() for t in toks]
                continue
            raise MeshError(f"{p}, line {no}: not numbers: {line.strip()[:60]!r}") from None
    if rows and len(rows[0]) == 1 and len(rows) > 1:  # a .pts point count
        rows, numbers = rows[1:], numbers[1:]
    if not rows:
        raise MeshError(f"{p}: no points")
    width = len(rows[0])
    for r, no in zip(rows, numbers, strict=True):
        if len(r) != width:
            raise MeshError(f"{p}, line {no}: {len(r)} numbers where the first point line has {width}")
    A = np.asarray(rows, dtype=np.float64)
    if header is not None and all(k in header for k in ("x", "y", "z")):
        cols = [header.index(k) for k in ("x", "y", "z")]
        ncols = [header.index(k) for k in ("nx", "ny", "nz")] if all(k in header for k in ("nx", "ny", "nz")) else None
        if max(cols + (ncols or [])) >= width:
            raise MeshError(f"{p}: the header names more columns than the lines have ({width})")
        return A[:, cols], (A[:, ncols] if ncols else None)
    return _split(A, p)


def _load_ply(p: Path) -> tuple[np.ndarray, np.ndarray | None]:
    from .formats._common import read_bytes
    from .formats.ply import _read_elements

    values, _ = _read_elements(p, read_bytes(p, "a PLY file"))
    if _count(values.get("face")):
        raise MeshError(f"{p}: the PLY file has faces: it is a mesh (load_mesh), not a point cloud")
    vert = values.get("vertex", {})
    missing = [c for c in "xyz" if c not in vert or isinstance(vert[c], tuple)]
    if missing:
        raise MeshError(f"{p}: the PLY 'vertex' element has no scalar propert{'y' if len(missing) == 1 else 'ies'} "
                        f"{', '.join(missing)}")
    P = np.stack([np.asarray(vert[c], dtype=np.float64) for c in "xyz"], axis=1)
    normal = ("nx", "ny", "nz")
    has_normals = all(c in vert and not isinstance(vert[c], tuple) for c in normal)
    N = np.stack([np.asarray(vert[c], dtype=np.float64) for c in normal], axis=1) if has_normals else None
    return P, N


def _count(element: dict[str, Any] | None) -> int:
    """Records of a parsed PLY element (0 for none): a list property is ``(flat, sizes)``."""
    if not element:
        return 0
    first = next(iter(element.values()))
    return len(first[1]) if isinstance(first, tuple) else len(first)
