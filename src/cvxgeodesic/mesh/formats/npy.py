"""NumPy ``.npy``: the field alone, an (n,) float64 array."""

from __future__ import annotations

from pathlib import Path
from typing import BinaryIO

import numpy as np

from ._common import FieldData, format_error

__all__ = ["read_field", "write_field"]


def write_field(fh: BinaryIO, field: FieldData) -> None:
    """``numpy.save`` of the (n,) float64 field (no pickles)."""
    np.save(fh, field.d, allow_pickle=False)


def read_field(path: Path, name: str) -> np.ndarray:
    """The (n,) array of a ``.npy`` file as float64 (``name`` is not stored in the format and is ignored).

    Raises
    ------
    MeshFormatError
        Not a ``.npy`` file, or not a 1-D numeric array.
    """
    try:
        arr = np.load(path, allow_pickle=False)
    except (ValueError, OSError, EOFError) as exc:
        raise format_error(path, f"not a NumPy .npy file ({type(exc).__name__}: {exc})") from None
    if not isinstance(arr, np.ndarray) or arr.ndim != 1 or arr.dtype.kind not in "iuf":
        what = f"shape {arr.shape}, dtype {arr.dtype}" if isinstance(arr, np.ndarray) else type(arr).__name__
        raise format_error(path, f"expected a 1-D numeric array (one value per vertex), got {what}")
    return arr.astype(np.float64)
