"""The descent's view of a mesh (:class:`Cells`), shared by the walk (:mod:`~cvxgeodesic.paths.descent`) and the
corridor's straightening (:mod:`~cvxgeodesic.paths.corridor`)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..mesh.locate import cells_around
from ..mesh.simplex import SimplexMesh
from ..operators.linear_field import hat_gradients

__all__ = ["Cells"]


class Cells:
    """Per-mesh data of a path's walk: corner positions, the cells, barycentric gradients, the cells it may step
    through, and the cells around a vertex, an edge or a facet.

    Parameters
    ----------
    mesh : SimplexMesh
        ``n`` vertices, ``k`` cells of ``dim + 1`` corners.
    H : (k, dim + 1, 3) float ndarray, optional
        :func:`~cvxgeodesic.operators.linear_field.hat_gradients` of ``mesh`` when already computed.

    Attributes
    ----------
    mesh : SimplexMesh
    V : (n, 3) float ndarray
        ``mesh.V``.
    C : (k, dim + 1) int ndarray
        ``mesh.cells``.
    H : (k, dim + 1, 3) float ndarray
        World-coordinate gradients of each cell's barycentric coordinates (NaN/inf on degenerate cells).
    ok : (k,) bool ndarray
        The cells the walk may step through: finite ``H``, not degenerate.
    """

    def __init__(self, mesh: SimplexMesh, H: np.ndarray | None = None) -> None:
        self.mesh, self.V, self.C = mesh, mesh.V, mesh.cells
        self.H = hat_gradients(mesh) if H is None else H
        with np.errstate(invalid="ignore"):
            self.ok = np.isfinite(self.H).all(axis=(1, 2)) & ~np.isin(np.arange(len(self.C)), mesh.degenerate_cells())

    def cells_of(self, verts: Sequence[int]) -> np.ndarray:
        """(j,) int64 ndarray: the cells that contain all of ``verts`` (the cells around a vertex, an edge or a
        facet)."""
        return cells_around(self.mesh, verts)

    def bary(self, c: int, x: np.ndarray) -> np.ndarray:
        """(dim + 1,) float ndarray: barycentric coordinates of ``x`` (3,) in cell ``c``, clipped to it (least
        squares: any cell shape)."""
        A = np.vstack([self.V[self.C[c]].T, np.ones(self.C.shape[1])])
        b = np.clip(np.linalg.lstsq(A, np.r_[x, 1.0], rcond=None)[0], 0.0, None)
        return b / b.sum()
