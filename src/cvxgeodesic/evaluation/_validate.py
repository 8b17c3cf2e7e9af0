"""Shape checks shared by the evaluation functions (private)."""

from __future__ import annotations

import numpy as np

from ..mesh.trimesh import TriMesh
from ..validation import as_vertex_field as vertex_field  # noqa: F401  (re-exported for the evaluation modules)


def check_mesh(mesh, name: str = "mesh") -> TriMesh:
    if not isinstance(mesh, TriMesh):
        raise TypeError(f"{name} must be a TriMesh, got {type(mesh).__name__}")
    return mesh


def vertex_indices(x, name: str, n: int) -> np.ndarray:
    """Return ``x`` as a (k,) int64 array of indices in ``[0, n)`` or raise ValueError naming ``name``."""
    arr = np.asarray(x)
    if arr.ndim == 0:
        arr = arr.reshape(1)
    if arr.ndim != 1:
        raise ValueError(f"{name} must be a 1-D array of vertex indices, got shape {arr.shape}")
    if arr.size and arr.dtype.kind not in "iu":
        if arr.dtype.kind == "f" and np.all(np.isfinite(arr)) and np.all(arr == np.round(arr)):
            arr = arr.astype(np.int64)
        else:
            raise ValueError(f"{name} must hold integer vertex indices, got dtype {arr.dtype}")
    arr = arr.astype(np.int64)
    if arr.size and (arr.min() < 0 or arr.max() >= n):
        raise ValueError(f"{name} has indices outside [0, {n}): min {arr.min()}, max {arr.max()}")
    return arr


def vertex_mask(x, name: str, n: int) -> np.ndarray:
    """Return ``x`` as a (n,) bool array or raise ValueError naming ``name``."""
    arr = np.asarray(x)
    if arr.dtype != bool:
        raise ValueError(f"{name} must be a boolean vertex mask of shape ({n},), got dtype {arr.dtype}")
    if arr.shape != (n,):
        raise ValueError(f"{name} must have shape ({n},), got {arr.shape}")
    return arr
