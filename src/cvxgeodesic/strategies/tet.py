"""The strategies inside tetrahedral meshes (issue 26): order 1 and the baselines (order 2: :mod:`.order2`).

- :class:`TetDirect`: one order-1 program (:mod:`cvxgeodesic.formulations_tet`) on the mesh scaled to unit size,
  under the backend policy every strategy shares (:class:`~cvxgeodesic.strategies.backend.Backend`), on the
  tetrahedron-clique pattern (one symbolic analysis per mesh), the ``d ≥ 0`` re-solve when needed;
- order 2: :class:`~cvxgeodesic.strategies.order2.Order2`, the one order-2 strategy of both dimensions;
- the baselines (Dijkstra, heat): :class:`~cvxgeodesic.strategies.baseline.BaselineStrategy`, as on surfaces.

:func:`make_tet_strategy` chooses; :func:`~cvxgeodesic.strategies.make_strategy` calls it for a
:class:`~cvxgeodesic.mesh.tetmesh.TetMesh`.
"""

from __future__ import annotations

import time
from typing import Any, cast

import numpy as np

from ..formulations_tet import TET_FORMULATIONS, TetOperators, build_tet_problem
from ..mesh.tetmesh import TetMesh
from ..mesh.trimesh import unit_mesh
from ..results import GeodesicResult, SolveInfo
from ..solvers.problem import BackendResult, ConicProblem, clique_pattern
from ..sources_tet import TetSources
from .backend import Backend
from .base import Callback, SolveConfig
from .order2 import Order2

__all__ = ["TetDirect", "make_tet_strategy"]


def make_tet_strategy(config: SolveConfig, *, baseline: bool, order: int = 1) -> Any:
    """The strategy for a validated config whose mesh is a :class:`TetMesh`.

    Raises
    ------
    ParameterError
        ``order=2`` with a method other than :data:`~cvxgeodesic.formulations_tet.TET_ORDER2_METHODS`.
    """
    if order == 2:
        return Order2(config)
    if baseline:
        from .baseline import BaselineStrategy

        return BaselineStrategy(config)
    return TetDirect(config)


def _volume(config: SolveConfig) -> TetMesh:
    """The config's mesh, a TetMesh here (SolveConfig is typed for the surface strategies)."""
    return cast(TetMesh, config.mesh)


def _info(config: SolveConfig, res: BackendResult, setup_time: float, t0: float, objective: float,
          n_unreachable: int, notes: list[str], extra: dict) -> SolveInfo:
    return SolveInfo(method=config.method, solver=res.solver, status=res.status, iterations=res.iterations,
                     setup_time=setup_time, solve_time=time.perf_counter() - t0,
                     primal_residual=res.primal_residual, dual_residual=res.dual_residual, gap=res.gap,
                     objective=objective, lam=config.lam, n_unreachable=n_unreachable, notes=notes, extra=extra)


class TetDirect:
    """An order-1 formulation solved inside a tetrahedral mesh.

    Parameters
    ----------
    config : SolveConfig
        ``config.mesh`` a TetMesh, ``config.method`` a key of :data:`~cvxgeodesic.formulations_tet.TET_FORMULATIONS`.

    Attributes
    ----------
    ops : TetOperators
        Of the mesh divided by ``scale`` (:func:`~cvxgeodesic.mesh.tetmesh.unit_tetmesh`).
    scale : float
    ipm : InteriorPointSolver or None
    """

    def __init__(self, config: SolveConfig) -> None:
        t0 = time.perf_counter()
        self.config = config
        unit, self.scale = unit_mesh(_volume(config))
        self.ops = TetOperators(unit)
        self.policy = Backend(config.solver, config.tol, config.max_iter, config.verbose, config.mesh.name)
        self.notes: list[str] = [*config.notes, *self.ops.notes, *self.policy.notes]
        self.backend = self.policy.name
        self.ipm: Any = None
        energy = TET_FORMULATIONS[config.method][1]
        P = self.ops.energy(energy) if energy is not None else None
        if self.backend == "ipm":
            from ..solvers.ipm import InteriorPointSolver

            pattern = clique_pattern(unit.n_vertices, [unit.T])
            if P is not None:
                pattern = pattern + abs(P).astype(bool).astype(float)
                pattern.data[:] = 1.0
                pattern.sort_indices()
            self.ipm = InteriorPointSolver(pattern.tocsc())
        self.setup_time = time.perf_counter() - t0

    def _problem(self, src: TetSources, nonnegative: bool) -> ConicProblem:
        cfg = self.config
        return build_tet_problem(self.ops, src, cfg.method, cfg.lam / self.scale, stretch=cfg.stretch,
                                 nonnegative=nonnegative)

    def solve(self, sources: TetSources, *, callback: Callback | None = None) -> GeodesicResult:
        """Distance field from resolved sources (:func:`~cvxgeodesic.sources_tet.resolve_tet_sources`)."""
        t0 = time.perf_counter()
        cfg = self.config
        notes = list(self.notes)
        problem = self._problem(sources, False)
        res = self.policy.solve(problem, self.ipm, callback, notes)
        negative_min = np.min(res.x[~problem.fixed_mask], initial=0.0)
        extra: dict = {}
        if negative_min < -1e-9 * cfg.mesh.bbox_diagonal / self.scale:
            extra = {"negative_min": float(negative_min * self.scale), "resolved_nonnegative": True}
            notes.append(f"the optimum had negative distances (down to {negative_min * self.scale:.3g}); "
                         "re-solved with the bounds d >= 0")
            problem = self._problem(sources, True)
            res = self.policy.solve(problem, self.ipm, callback, notes)
        d = np.array(res.x, dtype=float) * self.scale
        d[problem.unreachable] = np.inf
        d[sources.fixed_vertices(_volume(cfg))] = 0.0
        info = _info(cfg, res, self.setup_time, t0, res.objective / problem.objective_scale * self.scale,
                     int(problem.unreachable.sum()), notes, {**extra, **res.extra})
        return GeodesicResult(distance=d, info=info, sources=sources.vertices,
                              source_set=None if sources.vertex_only else sources)
