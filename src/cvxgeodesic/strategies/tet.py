"""The strategies inside tetrahedral meshes (issue 26): order 1, order 2 and the baselines.

- order 1: :class:`~cvxgeodesic.strategies.direct.DirectStrategy`, the surfaces' (one program over ``mesh.cells``);
- :class:`TetOrder2`: the P2 squared-distance program (:mod:`cvxgeodesic.formulations_tet_p2`) with the order-2
  settings, source points inserted as vertices, then cutting planes: a solid is flat, ``d²`` is exactly quadratic
  where the source is visible, so a cone at each tetrahedron's worst point
  (:func:`~cvxgeodesic.operators.tet_p2.tet_max_violation`) closes the gap between the node samples;
- :class:`TetBaselineStrategy`: Dijkstra on the edges and the heat method (:mod:`cvxgeodesic.baselines.tet`).

:func:`make_tet_strategy` chooses; :func:`~cvxgeodesic.strategies.make_strategy` calls it for a
:class:`~cvxgeodesic.mesh.tetmesh.TetMesh`.
"""

from __future__ import annotations

import time
from typing import Any, cast

import numpy as np

from ..baselines.tet import TET_BASELINES
from ..errors import ParameterError, SolverError
from ..formulations import TET_ORDER2_METHODS
from ..formulations_p2 import P2Program
from ..formulations_tet_p2 import TetP2Builder, source_edges
from ..mesh.tet_split import TetSplitMesh
from ..mesh.tetmesh import TetMesh
from ..mesh.trimesh import unit_mesh
from ..operators.tet_p2 import SplitTetP2Field, TetP2Field, tet_max_violation
from ..results import GeodesicResult, SolveInfo
from ..solvers.problem import BackendResult, clique_pattern
from ..sources import SourceSet as TetSources
from .backend import Backend
from .base import Callback, SolveConfig
from .direct import DirectStrategy
from .order2 import REFINE_ROUNDS, REFINE_TOL

__all__ = ["REFINE_STALL", "TetBaselineStrategy", "TetOrder2", "make_tet_strategy"]

#: The cutting-plane rounds stop after a round that moved no vertex distance by more than this fraction of the
#: largest. Where the source is hidden (behind an edge) ``d²`` is not quadratic and the cones are violated between
#: the samples whatever the round, so :data:`~cvxgeodesic.strategies.order2.REFINE_TOL` alone would always run
#: every round. Measured on the jittered L prism (n = 8, 9.2K tetrahedra, 2026-12-02): the rounds moved the field
#: by 2.0e-4, 1.9e-5, 6.9e-6, 3.5e-6 of its maximum and the mean error went 0.234 % → 0.230 % after the first and
#: stayed there (5 digits); on jittered boxes no round is needed.
REFINE_STALL = 1e-4


def make_tet_strategy(config: SolveConfig, *, baseline: bool, order: int = 1) -> Any:
    """The strategy for a validated config whose mesh is a :class:`TetMesh`.

    Raises
    ------
    ParameterError
        ``order=2`` with a method other than :data:`~cvxgeodesic.formulations.TET_ORDER2_METHODS`.
    """
    if order == 2:
        return TetOrder2(config)
    if baseline:
        return TetBaselineStrategy(config)
    return DirectStrategy(config)


def _volume(config: SolveConfig) -> TetMesh:
    """The config's mesh, a TetMesh here (SolveConfig is typed for the surface strategies)."""
    return cast(TetMesh, config.mesh)


def _info(config: SolveConfig, res: BackendResult, setup_time: float, t0: float, objective: float,
          n_unreachable: int, notes: list[str], extra: dict) -> SolveInfo:
    return SolveInfo(method=config.method, solver=res.solver, status=res.status, iterations=res.iterations,
                     setup_time=setup_time, solve_time=time.perf_counter() - t0,
                     primal_residual=res.primal_residual, dual_residual=res.dual_residual, gap=res.gap,
                     objective=objective, lam=config.lam, n_unreachable=n_unreachable, notes=notes, extra=extra)


class TetOrder2:
    """P2 squared-distance solves inside a tetrahedral mesh (``order=2``).

    Parameters
    ----------
    config : SolveConfig
        ``config.method`` in :data:`~cvxgeodesic.formulations.TET_ORDER2_METHODS`.
    refine : int
        Cutting-plane rounds at most.

    Attributes
    ----------
    builder : TetP2Builder
    ipm : InteriorPointSolver or None
    scale : float
    """

    def __init__(self, config: SolveConfig, refine: int = REFINE_ROUNDS) -> None:
        t0 = time.perf_counter()
        if config.method not in TET_ORDER2_METHODS:
            raise ParameterError(f"order=2 is implemented for {', '.join(TET_ORDER2_METHODS)}, not for "
                                 f"{config.method!r}")
        self.config = config
        self.refine = int(refine)
        unit, self.scale = unit_mesh(_volume(config))
        self.builder = TetP2Builder(unit)
        self.policy = Backend(config.solver, config.tol, config.max_iter, config.verbose, config.mesh.name)
        self.backend = self.policy.name
        self.notes: list[str] = [*config.notes, *self.policy.notes]
        self.ipm = self._ipm(self.builder)
        self.setup_time = time.perf_counter() - t0

    def _ipm(self, builder: TetP2Builder) -> Any:
        if self.backend != "ipm":
            return None
        from ..solvers.ipm import InteriorPointSolver
        from ..solvers.ipm.settings import ORDER2

        space = builder.space
        return InteriorPointSolver(clique_pattern(space.n_dofs, [space.tet_dofs]), settings=ORDER2)

    def solve(self, sources: TetSources, *, callback: Callback | None = None) -> GeodesicResult:
        """Distance field from vertex, point, face and boundary sources."""
        t0 = time.perf_counter()
        mesh = _volume(self.config)
        builder, ipm, split = self.builder, self.ipm, None
        notes = list(self.notes)
        fixed = sources.fixed_vertices(mesh)
        vertex_sources = sources.vertices
        if sources.points:
            # a point inside a tetrahedron becomes a vertex of a locally split mesh, as on surfaces
            split = TetSplitMesh(mesh, sources.points)
            sm = split.mesh
            builder = TetP2Builder(TetMesh(sm.V / self.scale, sm.T, name=sm.name) if self.scale != 1.0 else sm)
            ipm = self._ipm(builder)
            fixed = np.concatenate([fixed, split.point_vertices])
            vertex_sources = np.concatenate([vertex_sources, split.point_vertices])
            notes.append(f"{len(sources.points)} source point(s) inserted as vertices ({sm.n_tets - mesh.n_tets} "
                         "tetrahedra added; new symbolic analysis for this solve)")
        zero = source_edges(builder.mesh, vertex_sources, sources.face_triangles(mesh))
        program, res, rounds = self._solve_with_cuts(builder, ipm, fixed, zero, callback, notes)
        phi = program.restore(res.x) * self.scale**2
        phi[program.problem.unreachable] = np.inf
        fld = (TetP2Field(mesh, phi, builder.space) if split is None
               else SplitTetP2Field(mesh, split, phi, builder.space))
        d = fld.vertex_distance.copy()
        d[sources.fixed_vertices(mesh)] = 0.0
        problem = program.problem
        info = _info(self.config, res, self.setup_time, t0, res.objective * self.scale**2, int(np.isinf(d).sum()),
                     notes, {**res.extra, "order": 2, "p2_field": fld, "n_dofs": problem.n,
                             "n_cones": problem.n_cones, "rounds": len(rounds) - 1, "round_iterations": rounds})
        info.iterations = int(sum(rounds))
        return GeodesicResult(distance=d, info=info, sources=sources.vertices,
                              source_set=None if sources.vertex_only else sources)

    def _solve_with_cuts(self, builder: TetP2Builder, ipm: Any, fixed: np.ndarray, zero: np.ndarray,
                         callback: Callback | None, notes: list[str]) -> tuple[P2Program, BackendResult, list[int]]:
        """The program solved, then re-solved with a cone at the worst point of each violating tetrahedron."""
        program = builder.build(fixed, zero)
        notes[len(self.notes):len(self.notes)] = program.notes
        res = self.policy.solve(program.problem, ipm, callback, notes)
        rounds = [res.iterations]
        extra_t, extra_b = np.zeros(0, dtype=np.int64), np.zeros((0, 4))
        n = builder.mesh.n_vertices
        x = program.restore(res.x)
        moved = np.inf
        while len(rounds) <= self.refine and moved > REFINE_STALL:
            vmax, bary, phi_at = tet_max_violation(builder.space, x)
            rel = vmax / np.maximum(4 * phi_at, 1e-300)
            add = np.flatnonzero((rel > REFINE_TOL) & (vmax > 1e-15) & ~builder.space.degenerate)
            if add.size == 0:
                break
            # the last round's field is the next one's start: 27 → 22 iterations per round on the L prism (n = 8)
            cand = builder.build(fixed, zero, extra=(np.concatenate([extra_t, add]),
                                                     np.concatenate([extra_b, bary[add]])), guess=x)
            try:
                res_c: BackendResult | None = self.policy.solve(cand.problem, ipm, callback, notes)
            except SolverError:
                res_c = None
            if res_c is None or (res_c.status != "optimal" and res.status == "optimal"):
                notes.append(f"cutting-plane round {len(rounds)} not fully solved; kept round {len(rounds) - 1}")
                break
            extra_t, extra_b = np.concatenate([extra_t, add]), np.concatenate([extra_b, bary[add]])
            program, res = cand, res_c
            rounds.append(res.iterations)
            x_new = program.restore(res.x)
            d_old, d_new = (np.sqrt(np.maximum(v[:n], 0.0)) for v in (x, x_new))
            moved = float(np.abs(d_new - d_old).max() / max(d_new.max(), 1e-300))
            x = x_new
        if len(rounds) > 1:
            notes.append(f"{len(rounds) - 1} cutting-plane round(s) added {extra_t.size} cone(s)")
        return program, res, rounds


class TetBaselineStrategy:
    """Dijkstra or the heat method inside a tetrahedral mesh (:data:`~cvxgeodesic.baselines.tet.TET_BASELINES`)."""

    def __init__(self, config: SolveConfig) -> None:
        t0 = time.perf_counter()
        self.config = config
        self.baseline = TET_BASELINES[config.method](config.mesh)
        self.backend = config.method
        self.notes: list[str] = [*config.notes, *self.baseline.notes]
        self.setup_time = time.perf_counter() - t0

    def solve(self, sources: TetSources, *, callback: Callback | None = None) -> GeodesicResult:
        """Distance field from resolved sources; ``callback`` is ignored (no iterations)."""
        t0 = time.perf_counter()
        d, binfo = self.baseline.solve(sources)
        notes = [*self.config.notes, *binfo.pop("notes", [])]
        info = SolveInfo(method=self.config.method, solver=str(binfo.pop("solver")), status=binfo.pop("status"),
                         setup_time=self.setup_time, solve_time=time.perf_counter() - t0,
                         n_unreachable=int(np.isinf(d).sum()), notes=notes,
                         extra={k: v for k, v in binfo.items() if k not in ("method", "iterations")})
        return GeodesicResult(distance=d, info=info, sources=sources.vertices,
                              source_set=None if sources.vertex_only else sources)
