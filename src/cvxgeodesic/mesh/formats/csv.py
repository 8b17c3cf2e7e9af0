"""CSV: header ``vertex,file_vertex,x,y,z,<name>``, one row per vertex (``inf`` written as such); points in, one a
row (:func:`read_points`: the columns ``x, y, z`` and ``nx, ny, nz`` of a header, else the first three or six)."""

from __future__ import annotations

from pathlib import Path
from typing import BinaryIO

import numpy as np

from ._common import FieldData, RawPoints, format_error
from .xyz import read_text_points

__all__ = ["read_field", "read_points", "write_field"]


def read_points(path: Path) -> RawPoints:
    """The points (and normals) of a comma-separated file, one point a row (:func:`.xyz.read_text_points`)."""
    return read_text_points(path, ",")


def write_field(fh: BinaryIO, field: FieldData) -> None:
    """One row per vertex: mesh index, file index, coordinates and value, each float written to round-trip."""
    fh.write(f"vertex,file_vertex,x,y,z,{field.name}\n".encode("ascii"))
    # repr(float) round-trips exactly and writes inf / -inf / nan as such
    body = "".join(
        f"{i},{j},{x!r},{y!r},{z!r},{v!r}\n"
        for i, j, (x, y, z), v in zip(field.vertex.tolist(), field.file_vertex.tolist(), field.V.tolist(),
                                      field.d.tolist(), strict=True)
    )
    fh.write(body.encode("ascii"))


def read_field(path: Path, name: str) -> np.ndarray:
    """The column ``name`` as an (n,) float64 array, one value per row, in row order.

    Raises
    ------
    MeshFormatError
        No header with that column (the message lists the columns), or a value that is not a number
        (the message names the line).
    """
    with path.open("r", encoding="utf-8", errors="replace", newline="") as fh:
        header = fh.readline()
    columns = [c.strip().strip('"') for c in header.rstrip("\r\n").split(",")]
    if name not in columns:
        raise format_error(path, f"line 1: no column {name!r} (the header's columns: {', '.join(columns)})")
    col = columns.index(name)
    try:
        return np.loadtxt(path, delimiter=",", skiprows=1, usecols=col, dtype=np.float64, ndmin=1, quotechar='"',
                          encoding="utf-8")
    except ValueError as exc:  # numpy names the line in its message
        raise format_error(path, f"column {name!r}: {exc}") from None
