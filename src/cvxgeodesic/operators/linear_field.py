"""The piecewise-linear (P1) field of vertex values on a simplex mesh: the :class:`~cvxgeodesic.results.Field` of
order-1 solves and baselines.

In each cell the field is ``d(x) = Σ_i λ_i(x) d_i`` and its gradient the constant ``Σ_i d_i ∇λ_i``, with the
barycentric gradients of :func:`~cvxgeodesic.operators.gradient.gradient_blocks` carried from each cell's frame into
world coordinates (:meth:`~cvxgeodesic.mesh.reference.ReferenceSimplex.to_world`): one code for triangles and
tetrahedra.
"""

from __future__ import annotations

import functools
from typing import Any

import numpy as np

from ..mesh.locate import checked_points, corner_interpolant
from ..mesh.simplex import SimplexMesh
from .gradient import gradient_blocks

__all__ = ["LinearField", "hat_gradients"]


def hat_gradients(mesh: SimplexMesh) -> np.ndarray:
    """World-coordinate gradients of each cell's barycentric coordinates.

    Parameters
    ----------
    mesh : SimplexMesh
        ``k`` cells of ``dim + 1`` corners.

    Returns
    -------
    (k, dim + 1, 3) float ndarray
        Row ``i`` of cell ``t`` is ``∇λ_i`` (tangent to a triangle's plane); NaN/inf on cells of zero measure.
    """
    with np.errstate(invalid="ignore", divide="ignore"):
        B = gradient_blocks(mesh)  # (k, dim, dim + 1) in each cell's frame
        return mesh.reference.to_world(B, mesh.V[mesh.cells])


class LinearField:
    """The piecewise-linear interpolant of vertex values on a triangle or tetrahedral mesh.

    Parameters
    ----------
    mesh : SimplexMesh
        ``n`` vertices, ``k`` cells.
    values : (n,) float ndarray
        The field at the vertices (``inf`` where no source is reachable); kept, not copied.
    medium : Medium, optional
        The travel cost or metric the field measures (:mod:`cvxgeodesic.operators.metric`); None: Euclidean.

    Attributes
    ----------
    mesh, medium
        As given.
    vertex_distance : (n,) float ndarray
        ``values``.
    """

    def __init__(self, mesh: SimplexMesh, values: np.ndarray, medium: Any = None) -> None:
        self.mesh, self.medium = mesh, medium
        self.vertex_distance = values

    @functools.cached_property
    def hat_gradients(self) -> np.ndarray:
        """(k, dim + 1, 3) float ndarray: :func:`hat_gradients` of the mesh."""
        return hat_gradients(self.mesh)

    @functools.cached_property
    def cell_gradients(self) -> np.ndarray:
        """(k, 3) float ndarray: the field's gradient in each cell; NaN on cells of zero measure and on cells with a
        non-finite corner value."""
        H = self.hat_gradients
        with np.errstate(invalid="ignore"):
            grad = np.einsum("kij,ki->kj", H, self.vertex_distance[self.mesh.cells])
        grad[~np.isfinite(H).all(axis=(1, 2))] = np.nan
        grad[self.mesh.degenerate_cells()] = np.nan
        return grad

    def distance_at(self, cells: Any, bary: Any) -> np.ndarray:
        """The field at points of cells.

        Parameters
        ----------
        cells : int or (p,) int array_like
        bary : (dim + 1,) or (p, dim + 1) float array_like

        Returns
        -------
        (p,) float ndarray
            ``Σ_i b_i d_i``; a corner of weight 0 does not count (an unreachable corner leaves the others' value).
        """
        cells, bary = checked_points(self.mesh, cells, bary)
        return corner_interpolant(self.vertex_distance[self.mesh.cells[cells]], bary)

    def gradient_at(self, cells: Any, bary: Any) -> np.ndarray:
        """The field's gradient at points of cells (constant in each cell).

        Returns
        -------
        (p, 3) float ndarray
            In world coordinates (in a triangle's plane); NaN where :attr:`cell_gradients` is.
        """
        cells, _ = checked_points(self.mesh, cells, bary)
        return self.cell_gradients[cells]
