"""Exact polyhedral geodesic distance (MMP algorithm, Kirsanov's code) via pygeodesic."""

from __future__ import annotations

import contextlib
import io

import numpy as np

from ..errors import SolverError
from ..mesh.reference import TRIANGLE
from ..sources import SourceSet
from .base import ComponentwiseSolver
from .points import exact_inserted


class ExactBaseline(ComponentwiseSolver):
    """Exact geodesic distance on the polyhedral surface, ``pygeodesic.geodesic.PyGeodesicAlgorithmExact``.

    The Mitchell–Mount–Papadimitriou window-propagation algorithm: the true
    shortest-path distance on the piecewise-flat surface (to round-off). It is
    the ground truth of every error figure in this library.

    ``geodesicDistances(sources, None)`` accepts several sources and returns
    the distance to the nearest one; it equals the minimum of single-source
    runs exactly (tested).

    Limitations found: pygeodesic crashes the interpreter (segmentation fault)
    on edges shared by three or more faces and silently cuts the surface at a
    vertex that joins several sheets, so non-manifold meshes raise
    :class:`~cvxgeodesic.errors.NonManifoldError` up front. It also refuses
    meshes with unreferenced vertices and leaves unreached components at
    ``1e100``; both are avoided by running each connected component on its own
    submesh. Its own input errors are printed and ``None`` is returned; that
    becomes a :class:`~cvxgeodesic.errors.SolverError`. Parameters and errors: :class:`ComponentwiseSolver`
    (``manifold``).
    """

    name = "exact"
    library = "pygeodesic.geodesic.PyGeodesicAlgorithmExact"
    cells = (TRIANGLE,)
    manifold = True

    def _solve_sources(self, ss: SourceSet) -> tuple[np.ndarray, dict]:
        return super()._solve_sources(ss) if ss.kind == "boundary" else exact_inserted(type(self), self.mesh, ss)

    def _build(self, V: np.ndarray, F: np.ndarray) -> object:
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            alg = self._library(V, F.astype(np.int32))
        msg = out.getvalue().strip()
        if msg:
            raise SolverError(f"baseline {self.name!r}: pygeodesic could not load {self.mesh.name}: {msg}",
                              solver=self.library, status="error")
        return alg

    def _run(self, solver, local_sources: np.ndarray) -> np.ndarray:
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            d, _best = solver.geodesicDistances(local_sources.astype(np.int32), None)
        if d is None:
            msg = out.getvalue().strip()
            raise SolverError(f"baseline {self.name!r}: pygeodesic failed on {self.mesh.name}: {msg}",
                              solver=self.library, status="error")
        d = np.asarray(d, dtype=np.float64).reshape(-1)
        d[d >= 1e99] = np.inf  # GEODESIC_INF = 1e100 marks unreached vertices
        return d
