"""NumPy ``.npy``: the field alone, an (n,) float64 array; points in, an (n, 3) or (n, 6) array (with normals)."""

from __future__ import annotations

from pathlib import Path
from typing import BinaryIO

import numpy as np

from ._common import FieldData, RawPoints, check_file, format_error, split_normals

__all__ = ["read_field", "read_points", "write_field"]


def write_field(fh: BinaryIO, field: FieldData) -> None:
    """``numpy.save`` of the (n,) float64 field (no pickles)."""
    np.save(fh, field.d, allow_pickle=False)


def read_points(path: Path) -> RawPoints:
    """The points of an (n, 3) array, or the points and normals of an (n, 6) one.

    Raises
    ------
    MeshFormatError
        Not a ``.npy`` file, not numbers, or of another shape.
    """
    arr = _load(path)
    if arr.dtype.kind not in "iuf":
        raise format_error(path, f"the array holds {arr.dtype}, not numbers")
    return split_normals(path, arr.astype(np.float64))


def _load(path: Path) -> np.ndarray:
    """The array of a ``.npy`` file (no pickles), or a MeshFormatError."""
    check_file(path, "a NumPy .npy file")
    try:
        arr = np.load(path, allow_pickle=False)
    except (ValueError, OSError, EOFError) as exc:
        raise format_error(path, f"not a NumPy .npy file ({type(exc).__name__}: {exc})") from None
    if not isinstance(arr, np.ndarray):
        raise format_error(path, f"expected a NumPy array, got {type(arr).__name__}")
    return arr


def read_field(path: Path, name: str) -> np.ndarray:
    """The (n,) array of a ``.npy`` file as float64 (``name`` is not stored in the format and is ignored).

    Raises
    ------
    MeshFormatError
        Not a ``.npy`` file, or not a 1-D numeric array.
    """
    arr = _load(path)
    if arr.ndim != 1 or arr.dtype.kind not in "iuf":
        raise format_error(path, f"expected a 1-D numeric array (one value per vertex), got shape {arr.shape}, "
                                 f"dtype {arr.dtype}")
    return arr.astype(np.float64)
