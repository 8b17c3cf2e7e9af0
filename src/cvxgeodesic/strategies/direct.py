"""The direct strategy: one conic solve of a P1 formulation on the mesh, with the backend policy.

The policy, every step of which is recorded in ``info.notes``:

- ``solver="auto"`` uses the structured interior-point solver when it can be imported (it needs Numba),
  else Clarabel;
- under ``"auto"``, Clarabel retries an interior-point solve that failed or was only ``almost_optimal``
  (an almost optimal iterate is kept when Clarabel fails too);
- an optimum with negative distances is re-solved with the bounds ``d >= 0``;
- a failed Hessian solve says that the curved Hessian energy can be indefinite.
"""

from __future__ import annotations

import time
import warnings
from typing import Any

import numpy as np

from ..errors import ParameterError, SolverError
from ..formulations import MeshOperators, build_problem
from ..mesh.trimesh import unit_mesh
from ..results import GeodesicResult, SolveInfo
from ..sources import resolve_sources
from .base import Callback, SolveConfig

# frames between the warning and the caller of GeodesicSolver.solve: _clarabel_retry, _run_backend, _solve,
# DirectStrategy.solve, GeodesicSolver.solve, the thread-limit wrapper
_RETRY_STACKLEVEL = 7


def ipm_available() -> bool:
    """True when the structured interior-point solver (and so Numba) can be imported."""
    try:
        from ..solvers import ipm  # noqa: F401
    except ImportError:
        return False
    return True


def _solve_clarabel(problem: Any, config: SolveConfig) -> Any:
    from ..solvers import solve_clarabel  # looked up at call time: tests replace it to simulate failures

    return solve_clarabel(problem, tol=config.tol, max_iter=config.max_iter, verbose=config.verbose)


class DirectStrategy:
    """A P1 formulation solved on the mesh itself (no coarse mesh).

    Parameters
    ----------
    config : SolveConfig
        A convex formulation (not a baseline).

    Attributes
    ----------
    ops : MeshOperators
        Operators of the mesh divided by ``scale`` (:func:`~cvxgeodesic.mesh.trimesh.unit_mesh`).
    scale : float
        The power of two the mesh was divided by.
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
        self.ops = MeshOperators(unit)
        self.ops.notes[0:0] = list(config.notes)
        self.notes: list[str] = self.ops.notes  # the operators add their substitutions as they build
        if config.solver == "auto":
            self.backend = "ipm" if ipm_available() else "clarabel"
            if self.backend == "clarabel":
                self.notes.append("the interior-point solver is not available in this installation (it needs "
                                  "Numba); solved with Clarabel")
        else:
            self.backend = config.solver
        if self.backend == "ipm" and not ipm_available():
            raise ParameterError("solver='ipm' is not available in this installation")
        self.fallback_to_clarabel = config.solver == "auto"
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
        from ..solvers.problem import kkt_pattern

        # the unit mesh's edge table: the operators built it already (the mesh's own would be a second one)
        mesh = self.ops.mesh
        return kkt_pattern(mesh.n_vertices, mesh.F, mesh.edges, P)

    def _analyse(self, Q: Any) -> Any:
        """``analyse(Q)`` for :meth:`MeshOperators.energy`: the analysis of the mesh's Newton pattern with ``Q``,
        kept with the ``Q`` it was made for (a planar energy that replaced an indefinite curved one gets an
        analysis of its own)."""
        from ..linalg import SymbolicCholesky

        chol = SymbolicCholesky(self._pattern(Q))
        self._analysis = (Q, chol)
        return chol

    def solve(self, sources: Any, *, callback: Callback | None = None) -> GeodesicResult:
        """Distance field from ``sources`` (see :meth:`~cvxgeodesic.api.GeodesicSolver.solve`)."""
        sset = resolve_sources(self.config.mesh, sources)
        return self._solve(sset.vertices if sset.vertex_only else sset, time.perf_counter(), callback)

    def _solve(self, src: Any, t0: float, callback: Callback | None) -> GeodesicResult:
        cfg = self.config
        # on the mesh scaled by 1/s, the field d/s minimizes (objective)/s when lambda becomes lambda/s
        stretch = "area" if cfg.normalization == "area" else "calibrated"
        problem = build_problem(self.ops, src, cfg.method, cfg.lam / self.scale, stretch=stretch)
        notes = list(self.notes)
        res = self._run_backend(problem, callback, notes)
        negative_min = np.min(res.x[~problem.fixed_mask], initial=0.0)
        if negative_min < -1e-9 * cfg.mesh.bbox_diagonal / self.scale:
            # folded meshes (and strongly smoothed coarse fields) can trade a few negative values for a larger sum;
            # the bounds d >= 0 fix that but slow ordinary solves down, so they are added only when needed
            extra = dict(res.extra, negative_min=float(np.min(res.x)), resolved_nonnegative=True)
            notes.append(f"the optimum had negative distances (down to {negative_min * self.scale:.3g}); "
                         "re-solved with the bounds d >= 0")
            problem = build_problem(self.ops, src, cfg.method, cfg.lam / self.scale, stretch=stretch,
                                    nonnegative=True)
            res = self._run_backend(problem, callback, notes)
            res.extra = {**extra, **res.extra}
        d = np.array(res.x, dtype=float) * self.scale
        d[problem.unreachable] = np.inf
        vertices = src if isinstance(src, np.ndarray) else src.vertices
        d[vertices] = 0.0
        info = SolveInfo(
            method=cfg.method, solver=res.solver, status=res.status, iterations=res.iterations,
            setup_time=self.setup_time, solve_time=time.perf_counter() - t0,
            primal_residual=res.primal_residual, dual_residual=res.dual_residual, gap=res.gap,
            objective=res.objective / problem.objective_scale * self.scale, lam=cfg.lam,
            n_unreachable=int(problem.unreachable.sum()),
            notes=notes, extra=res.extra,
        )
        return GeodesicResult(distance=d, info=info, sources=vertices,
                              source_set=None if isinstance(src, np.ndarray) else src)

    def _run_backend(self, problem: Any, callback: Callback | None, notes: list[str]) -> Any:
        """Solve ``problem`` with the chosen backend; under ``solver="auto"`` Clarabel retries a failed or
        ``almost_optimal`` IPM solve."""
        cfg = self.config
        try:
            if self.backend != "ipm":
                return _solve_clarabel(problem, cfg)
            if cfg.verbose:
                from .._verbose import ipm_log

                callback = ipm_log(callback)
            try:
                res = self.ipm.solve(problem, tol=cfg.tol, max_iter=cfg.max_iter, callback=callback)
            except SolverError as exc:
                if not self.fallback_to_clarabel or exc.status in ("primal_infeasible", "dual_infeasible"):
                    raise
                return self._clarabel_retry(problem, exc.status, notes)
            if res.status == "optimal" or not self.fallback_to_clarabel:
                return res
            try:  # "almost_optimal": Clarabel may reach the full accuracy; else keep the IPM's best iterate
                return self._clarabel_retry(problem, res.status, notes)
            except SolverError:
                notes.append("Clarabel failed too; kept the interior-point solver's almost optimal iterate")
                return res
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

    def _clarabel_retry(self, problem: Any, ipm_status: str, notes: list[str]) -> Any:
        message = (f"the interior-point solver stopped with status {ipm_status!r} on {self.config.mesh.name}; "
                   "solving with Clarabel instead")
        warnings.warn(message, RuntimeWarning, stacklevel=_RETRY_STACKLEVEL)
        notes.append(message)
        res = _solve_clarabel(problem, self.config)
        res.extra = dict(res.extra, ipm_failure=ipm_status)
        return res
