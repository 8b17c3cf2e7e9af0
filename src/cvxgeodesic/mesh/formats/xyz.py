"""Text point files: ``.xyz`` and ``.pts`` (whitespace-separated), and the points of a ``.csv`` (:mod:`.csv`).

One point a line, ``x y z`` and possibly more columns: columns 4–6 are normals when a line has exactly six. A first
line that is not numbers is a header (``x,y,z,nx,ny,nz`` column names choose the columns); a first line that is one
number is a point count, as ``.pts`` files often have, and is skipped; ``#`` starts a comment.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ._common import RawPoints, format_error, read_bytes, split_normals
from ._text import decode

__all__ = ["read_points", "read_text_points"]


def read_points(path: Path) -> RawPoints:
    """The points (and normals) of a whitespace-separated ``.xyz`` or ``.pts`` file."""
    return read_text_points(path, None)


def read_text_points(path: Path, sep: str | None) -> RawPoints:
    """The points (and normals) of a text file with one point a line, columns split at ``sep`` (None: whitespace).

    Raises
    ------
    MeshFormatError
        A line after the first that is not numbers or has another count of them than the first point line (the
        message names the line), no points, or a header naming more columns than the lines have.
    """
    rows, numbers, header = _rows(path, decode(read_bytes(path, "a point file")).splitlines(), sep)
    if rows and len(rows[0]) == 1 and len(rows) > 1:  # a .pts point count
        rows, numbers = rows[1:], numbers[1:]
    if not rows:
        raise format_error(path, "no points")
    width = len(rows[0])
    for r, no in zip(rows, numbers, strict=True):
        if len(r) != width:
            raise format_error(path, f"line {no}: {len(r)} numbers where the first point line has {width}")
    A = np.asarray(rows, dtype=np.float64)
    if header is None or not all(k in header for k in "xyz"):
        return split_normals(path, A)
    cols = [header.index(k) for k in "xyz"]
    ncols = [header.index(k) for k in ("nx", "ny", "nz")] if all(k in header for k in ("nx", "ny", "nz")) else []
    if max(cols + ncols) >= width:
        raise format_error(path, f"the header names more columns than the lines have ({width})")
    return RawPoints(A[:, cols], A[:, ncols] if ncols else None)


def _rows(path: Path, lines: list[str], sep: str | None) -> tuple[list[list[float]], list[int], list[str] | None]:
    """The lines that are numbers, their 1-based line numbers, and the header's column names (lower case) if any."""
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
                header = [t.strip('"').lower() for t in toks]
                continue
            raise format_error(path, f"line {no}: not numbers: {line.strip()[:60]!r}") from None
    return rows, numbers, header
