"""The direct strategy: one conic solve of a P1 formulation on the mesh (triangles or tetrahedra), with the backend
policy.

The policy (:class:`~cvxgeodesic.strategies.backend.Backend`: the structured solver, Clarabel as its fallback
under ``solver="auto"``) and what this strategy adds, every step recorded in ``info.notes``:

- an optimum with negative distances (beyond the bounds next to the sources that every formulation has,
  :data:`~cvxgeodesic.problems.formulations.NONNEGATIVE_HOPS`, ``NONNEGATIVE_EDGE_RADIUS``, ``NONNEGATIVE_RADIUS``)
  is re-solved with the bounds ``d >= 0`` everywhere;
- a failed Hessian solve says that the curved Hessian energy can be indefinite.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from ..errors import SolverError
from ..linalg import SymbolicCholesky
from ..mesh.simplex import unit_mesh
from ..operators.linear_field import LinearField
from ..problems.conic import BackendResult, ConicProblem, kkt_pattern
from ..problems.formulations import MeshOperators, build_problem
from ..results import GeodesicResult, SolveInfo
from ..sources import SourceSet
from .backend import Backend, ipm_available
from .base import Callback, SolveConfig

__all__ = ["DirectStrategy", "ipm_available"]


class DirectStrategy:
    """A P1 formulation solved on the mesh itself (no coarse mesh), a surface or a solid.

    Parameters
    ----------
    config : SolveConfig
        A convex formulation (not a baseline) defined on the mesh's dimension.

    Attributes
    ----------
    ops : MeshOperators
        Operators of the mesh divided by ``scale`` (:func:`~cvxgeodesic.mesh.simplex.unit_mesh`).
    scale : float
        The power of two the fields were divided by: the mesh's (:func:`~cvxgeodesic.mesh.simplex.unit_mesh`) times
        the medium's normalization (:attr:`~cvxgeodesic.operators.metric.Medium.scale`) when there is one.
    ipm : InteriorPointSolver or None
        The structured solver on the union sparsity pattern (analysed once), when ``backend == "ipm"``.

    Raises
    ------
    ParameterError
        ``solver="ipm"`` where the structured solver cannot be imported.
    """

    def __init__(self, config: SolveConfig) -> None:
        t0 = time.perf_counter()
        self.config = config
        unit, self.scale = unit_mesh(config.mesh)
        medium = None if config.medium is None else config.medium.on(unit)
        if medium is not None:
            self.scale *= medium.scale
        self.ops = MeshOperators(unit, medium=medium)
        self.ops.notes[0:0] = list(config.notes)
        self.notes: list[str] = self.ops.notes  # the operators add their substitutions as they build
        self.policy = Backend(config.solver, config.tol, config.max_iter, config.verbose, config.mesh.name)
        self.notes.extend(self.policy.notes)
        self.backend = self.policy.name
        self.ipm: Any = None
        energy = config.energy
        self._analysis: tuple[Any, Any] | None = None  # (energy, the analysis made for it), see _analyse
        if energy is not None:
            # builds it now (PSD check, manifold cover); the interior-point solver's symbolic analysis is made
            # from the energy before its PSD check, which then factors the energy in that analysis
            self.ops.energy(energy, analyse=self._analyse if self.backend == "ipm" else None)
        if self.backend == "ipm":
            from ..solvers.ipm import InteriorPointSolver

            P = self.ops.energy(energy) if energy is not None else None
            chol = self._analysis[1] if self._analysis is not None and self._analysis[0] is P else None
            self.ipm = InteriorPointSolver(chol if chol is not None else self._pattern(P))
        _ = self.ops.gradient_blocks
        self.setup_time = time.perf_counter() - t0

    def _pattern(self, P: Any) -> Any:
        # the unit mesh's edge table: the operators built it already (the mesh's own would be a second one); the
        # edges of a tetrahedron are all its pairs, so the same pattern is its clique's
        mesh = self.ops.mesh
        return kkt_pattern(mesh.n_vertices, mesh.cells, mesh.edges, P)

    def _analyse(self, Q: Any) -> Any:
        """``analyse(Q)`` for :meth:`MeshOperators.energy`: the analysis of the mesh's Newton pattern with ``Q``,
        kept with the ``Q`` it was made for (a planar energy that replaced an indefinite curved one gets an
        analysis of its own)."""
        chol = SymbolicCholesky(self._pattern(Q))
        self._analysis = (Q, chol)
        return chol

    def solve(self, sources: SourceSet, *, callback: Callback | None = None) -> GeodesicResult:
        """Distance field from resolved ``sources`` (see :meth:`~cvxgeodesic.api.GeodesicSolver.solve`)."""
        t0 = time.perf_counter()
        cfg, src = self.config, sources
        # on the mesh scaled by 1/s, the field d/s minimizes (objective)/s when lambda becomes lambda/s
        stretch = cfg.stretch
        problem = build_problem(self.ops, src, cfg.method, cfg.lam / self.scale, stretch=stretch)
        notes = list(self.notes)
        res = self._run_backend(problem, callback, notes)
        negative_min = np.min(res.x[~problem.fixed_mask], initial=0.0)
        if negative_min < -1e-9 * cfg.mesh.bbox_diagonal / self.scale:
            # the bounds next to the sources (formulations.NONNEGATIVE_HOPS, NONNEGATIVE_EDGE_RADIUS,
            # NONNEGATIVE_RADIUS) cover the dips seen;
            # a negative value elsewhere is re-solved with d >= 0 everywhere, which slows ordinary solves down by
            # 20-35 % and is therefore not the default
            extra = dict(res.extra, negative_min=float(negative_min * self.scale), resolved_nonnegative=True)
            notes.append(f"the optimum had negative distances (down to {negative_min * self.scale:.3g}); "
                         "re-solved with the bounds d >= 0")
            problem = build_problem(self.ops, src, cfg.method, cfg.lam / self.scale, stretch=stretch,
                                    nonnegative=True)
            res = self._run_backend(problem, callback, notes)
            res.extra = {**extra, **res.extra}
        d = np.array(res.x, dtype=float) * self.scale
        d[problem.unreachable] = np.inf
        d[src.fixed_vertices(cfg.mesh)] = 0.0
        info = SolveInfo(
            method=cfg.method, solver=res.solver, status=res.status, iterations=res.iterations,
            setup_time=self.setup_time, solve_time=time.perf_counter() - t0,
            primal_residual=res.primal_residual, dual_residual=res.dual_residual, gap=res.gap,
            objective=res.objective / problem.objective_scale * self.scale, lam=cfg.lam,
            n_unreachable=int(problem.unreachable.sum()),
            notes=notes, extra=res.extra,
        )
        return GeodesicResult(distance=d, info=info, sources=src.vertices, field=LinearField(cfg.mesh, d, cfg.medium),
                              source_set=None if src.vertex_only else src)

    def _run_backend(self, problem: ConicProblem, callback: Callback | None, notes: list[str]) -> BackendResult:
        """Solve ``problem`` under the backend policy; a failed Hessian solve names the indefinite energy."""
        cfg = self.config
        try:
            return self.policy.solve(problem, self.ipm, callback, notes)
        except SolverError as exc:
            if cfg.energy != "hessian" or problem.P is None:
                raise
            # measured on Thingi10K CAD meshes: libigl's curved Hessian energy has negative eigenvalues where
            # the angle defect is large (sharp corners), and the problem is then not convex
            msg = str(exc).rsplit(" (solver=", 1)[0]
            raise SolverError(
                f"{msg} on {cfg.mesh.name}; the curved Hessian energy can be indefinite on meshes with sharp "
                f"corners, which makes {cfg.method!r} non-convex: try 'qcqp-laplacian' or 'qclp'",
                solver=exc.solver, status=exc.status, info=exc.info,
            ) from exc
