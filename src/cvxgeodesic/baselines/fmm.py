"""Fast marching on triangle meshes (potpourri3d / geometry-central)."""

from __future__ import annotations

import numpy as np

from ..mesh.reference import TRIANGLE
from ..sources import SourceSet
from .base import ComponentwiseSolver
from .points import fmm_points


class FastMarchingBaseline(ComponentwiseSolver):
    """Fast marching method, ``potpourri3d.MeshFastMarchingDistanceSolver``.

    A first-order upwind solver of the eikonal equation: accurate to O(h) on
    smooth regions, sharp (cusped) along the cut locus like the exact field.

    Sources are passed to the library as one point set ``[[(i, []), (j, []), ...]]``
    (a vertex is written ``(i, [])``: an index and empty barycentric
    coordinates; ``(i,)`` is rejected by the bindings). With several sources the
    library marches all fronts together, which is *not* bit-identical to the
    minimum of single-source runs: near the boundary of the sources' Voronoi
    cells a triangle may be updated from two fronts at once, which gives values
    slightly below that minimum (about 1% of an edge length on an icosphere).

    Limitations: geometry-central's fast marching needs a manifold mesh (it
    raises "handling of nonmanifold mesh not yet implemented"), so non-manifold
    input raises :class:`~cvxgeodesic.errors.NonManifoldError` up front.
    Several components are handled by running each component separately.
    The library's field depends on the faces' orientation (reversing every
    other face of an icosphere moved it by 10 % of the largest distance), so
    it is given the faces oriented consistently (``orient``; recorded in
    :attr:`notes`, with a :class:`~cvxgeodesic.errors.MeshRepairWarning`). A
    non-orientable surface (a Möbius strip) raises
    :class:`~cvxgeodesic.errors.MeshError`: the library was 11 % off there. Parameters and errors:
    :class:`ComponentwiseSolver` (``manifold``, ``orient``).
    """

    name = "fmm"
    library = "potpourri3d.MeshFastMarchingDistanceSolver"
    cells = (TRIANGLE,)
    orient = True
    manifold = True

    def _solve_sources(self, ss: SourceSet) -> tuple[np.ndarray, dict]:
        return super()._solve_sources(ss) if ss.kind == "boundary" else fmm_points(self, ss)

    def _build(self, V: np.ndarray, F: np.ndarray) -> object:
        return self._library(V, F)

    def _run(self, solver, local_sources: np.ndarray) -> np.ndarray:
        points = [[(int(s), []) for s in local_sources]]
        return np.asarray(solver.compute_distance(points, [], False), dtype=np.float64).reshape(-1)
