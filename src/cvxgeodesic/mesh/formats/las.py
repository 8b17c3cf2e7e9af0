"""LAS and LAZ (ASPRS LiDAR point files) through laspy, an optional package (the ``io`` extra); LAZ also needs a
LAZ backend of laspy (lazrs, in the extra).

The points are the scaled coordinates ``x, y, z`` (float64, so georeferenced coordinates keep their digits); extra
dimensions ``nx, ny, nz`` are normals. Classification, intensity and colours are not read.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...errors import MeshFormatError
from ._common import INSTALL_HINT, RawPoints, check_file, format_error, optional_package

__all__ = ["read_points"]


def read_points(path: Path) -> RawPoints:
    """The points (and normals) of a ``.las`` or ``.laz`` file.

    Raises
    ------
    MeshFormatError
        laspy is not installed, or for a ``.laz`` no LAZ backend (the message names what to install); a file laspy
        cannot read (its message follows the file's name); a file without points.
    """
    laspy = optional_package("laspy", f"{path}: reading {path.suffix} files", MeshFormatError)
    check_file(path, "a LAS file")
    if path.suffix.lower() == ".laz" and not laspy.LazBackend.detect_available():
        raise format_error(path, "reading .laz files needs a LAZ backend of laspy, the optional package lazrs: "
                                 + INSTALL_HINT.format(pkg="lazrs"))
    try:
        las = laspy.read(path)
    except (laspy.LaspyException, OSError, ValueError) as exc:
        raise format_error(path, f"not a readable {path.suffix[1:].upper()} file ({exc})") from None
    P = np.column_stack([np.asarray(las.x, dtype=np.float64), np.asarray(las.y, dtype=np.float64),
                         np.asarray(las.z, dtype=np.float64)])
    if P.shape[0] == 0:
        raise format_error(path, "the file holds no points")
    names = set(las.point_format.dimension_names)
    if not {"nx", "ny", "nz"} <= names:
        return RawPoints(P)
    return RawPoints(P, np.column_stack([np.asarray(las[c], dtype=np.float64) for c in ("nx", "ny", "nz")]))
