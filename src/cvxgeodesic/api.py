"""Public entry points: :class:`GeodesicSolver` (stateful) and :func:`geodesic_distance` (one shot)."""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field

import numpy as np

from .errors import ParameterError, SourceError
from .formulations import (
    ALIASES,
    FORMULATIONS,
    MeshOperators,
    build_problem,
    canonical_method,
    smoothness_weight,
    validate_sources,
)
from .mesh.trimesh import TriMesh, as_trimesh

BASELINE_METHODS = ("dijkstra", "fmm", "heat", "exact")
ALL_METHODS = (*FORMULATIONS, *ALIASES, *BASELINE_METHODS)
SOLVERS = ("auto", "ipm", "clarabel")
DEFAULT_TOL = 1e-8


@dataclass
class SolveInfo:
    """What happened during one solve.

    Attributes
    ----------
    method : str
        Formulation or baseline name (aliases resolved).
    solver : str
        Backend that produced the field (``"ipm"``, ``"clarabel"`` or the library of a baseline).
    status : str
        ``"optimal"`` (or ``"almost_optimal"`` from Clarabel) on success.
    iterations : int
        Interior-point iterations (0 for baselines).
    setup_time : float
        Seconds spent on per-mesh precomputation, paid once per solver object
        (operators, energy matrices, symbolic factorization, baseline set-up).
    solve_time : float
        Seconds spent on this solve.
    primal_residual, dual_residual, gap : float
        Final relative residuals / duality gap (NaN for baselines).
    objective : float
        Optimal objective value (NaN for baselines).
    lam : float
        Smoothness weight λ used (0 for LP formulations and baselines).
    n_unreachable : int
        Vertices with no path to a source (their distance is ``inf``).
    extra : dict
        Backend-specific details (timing breakdown, library parameters).
    """

    method: str
    solver: str
    status: str
    iterations: int = 0
    setup_time: float = 0.0
    solve_time: float = 0.0
    primal_residual: float = float("nan")
    dual_residual: float = float("nan")
    gap: float = float("nan")
    objective: float = float("nan")
    lam: float = 0.0
    n_unreachable: int = 0
    extra: dict = field(default_factory=dict)

    @property
    def total_time(self) -> float:
        """``setup_time + solve_time`` in seconds."""
        return self.setup_time + self.solve_time

    def as_dict(self) -> dict:
        """Plain-dict copy (with ``total_time``), e.g. for JSON or CSV."""
        out = asdict(self)
        out["total_time"] = self.total_time
        return out


@dataclass
class GeodesicResult:
    """Distance field plus the :class:`SolveInfo` of the solve that made it.

    Attributes
    ----------
    distance : (n,) float ndarray
        Distance of every vertex to the nearest source; ``inf`` where no source is reachable.
    info : SolveInfo
    sources : (k,) int64 ndarray
    """

    distance: np.ndarray
    info: SolveInfo
    sources: np.ndarray


def _ipm_available() -> bool:
    try:
        from .solvers import ipm  # noqa: F401
    except ImportError:
        return False
    return True


class GeodesicSolver:
    """Geodesic distances on one mesh, with per-mesh work done once.

    Parameters
    ----------
    mesh : TriMesh or tuple (V, F)
        ``V`` (n, 3) float, ``F`` (m, 3) int.
    method : str
        One of :data:`ALL_METHODS`: the eight convex formulations
        (``"lclp"``, ``"lcqp-dirichlet"``, ``"lcqp-laplacian"``, ``"lcqp-hessian"``
        (alias ``"qgdf"``), ``"qclp"``, ``"qcqp-dirichlet"``, ``"qcqp-laplacian"``,
        ``"qcqp-hessian"``) or a baseline (``"dijkstra"``, ``"fmm"``, ``"heat"``,
        ``"exact"``). Default ``"qcqp-hessian"``, the paper's recommendation.
    m : float
        Smoothness multiplier of the paper: ``λ = m · 10² · h / n`` with ``h``
        the mean edge length and ``n`` the vertex count (``E_stretch`` is the
        mean distance; see ``docs/method.md``). Ignored by LP formulations and
        baselines.
    lam : float, optional
        Give λ directly instead of ``m``.
    solver : {"auto", "ipm", "clarabel"}
        Backend for the convex formulations. ``"auto"`` uses the structured
        interior-point solver (``"ipm"``) when it is available, else Clarabel.
    tol : float
        Relative tolerance of residuals and duality gap.
    max_iter : int
        Interior-point iteration limit.
    verbose : bool
        Print the backend's iteration log.

    Examples
    --------
    >>> import cvxgeodesic as cg
    >>> mesh = cg.icosphere(3)
    >>> solver = cg.GeodesicSolver(mesh, method="qclp")
    >>> result = solver.solve(0)
    >>> result.distance.shape, result.info.status
    ((642,), 'optimal')
    """

    def __init__(
        self,
        mesh,
        method: str = "qcqp-hessian",
        *,
        m: float = 1.0,
        lam: float | None = None,
        solver: str = "auto",
        tol: float = DEFAULT_TOL,
        max_iter: int = 200,
        verbose: bool = False,
    ):
        t0 = time.perf_counter()
        self.mesh: TriMesh = as_trimesh(mesh)
        if not isinstance(method, str):
            raise ParameterError(f"method must be a string, got {type(method).__name__}")
        key = method.lower()
        if key in BASELINE_METHODS:
            self.method = key
        else:
            self.method = canonical_method(method)
        if not isinstance(solver, str) or solver.lower() not in SOLVERS:
            raise ParameterError(f"unknown solver {solver!r}; choose one of {', '.join(SOLVERS)}")
        solver = solver.lower()
        self.is_baseline = self.method in BASELINE_METHODS
        if self.is_baseline and solver not in ("auto",):
            raise ParameterError(
                f"solver={solver!r} applies to the convex formulations, not to baseline {self.method!r}"
            )
        if not (isinstance(tol, int | float) and 0 < tol < 1):
            raise ParameterError(f"tol must be a number in (0, 1), got {tol!r}")
        if isinstance(max_iter, bool) or not isinstance(max_iter, int | np.integer) or max_iter < 1:
            raise ParameterError(f"max_iter must be a positive integer, got {max_iter!r}")
        self.tol, self.max_iter, self.verbose = float(tol), int(max_iter), bool(verbose)

        if lam is not None:
            if not np.isfinite(lam) or lam < 0:
                raise ParameterError(f"lam must be a finite number >= 0, got {lam!r}")
            self.lam = float(lam)
        else:
            if not isinstance(m, int | float) or not np.isfinite(m) or m < 0:
                raise ParameterError(f"m must be a finite number >= 0, got {m!r}")
            self.lam = smoothness_weight(self.mesh, m)
        self.m = None if lam is not None else float(m)

        self._baseline = None
        self._ops = None
        self._ipm = None
        if self.is_baseline:
            from .baselines import BASELINES

            self._baseline = BASELINES[self.method](self.mesh)
            self.solver_name = self.method
        else:
            self.energy = FORMULATIONS[self.method][1]
            if self.energy is None:
                self.lam = 0.0
            self._ops = MeshOperators(self.mesh)
            if self.energy is not None:
                self._ops.energy(self.energy)  # builds it now; raises NonManifoldError early for 'hessian'
            self.solver_name = ("ipm" if _ipm_available() else "clarabel") if solver == "auto" else solver
            if self.solver_name == "ipm":
                if not _ipm_available():
                    raise ParameterError("solver='ipm' is not available in this installation")
                from .solvers.ipm import InteriorPointSolver
                from .solvers.problem import kkt_pattern

                P = self._ops.energy(self.energy) if self.energy is not None else None
                self._ipm = InteriorPointSolver(kkt_pattern(self.mesh.n_vertices, self.mesh.F, self.mesh.edges, P))
            _ = self._ops.gradient_blocks
        self.setup_time = time.perf_counter() - t0

    def __repr__(self) -> str:
        return (
            f"GeodesicSolver(mesh={self.mesh!r}, method={self.method!r}, "
            f"solver={self.solver_name!r}, lam={self.lam:.3g})"
        )

    def solve(self, sources, *, callback=None) -> GeodesicResult:
        """Distance field from one or several source vertices.

        Parameters
        ----------
        sources : int or sequence of int
            Source vertex indices (distinct, in ``[0, n)``).
        callback : callable, optional
            ``callback(iteration, info_dict)`` after every interior-point
            iteration of the ``"ipm"`` backend (used for progress reports).

        Returns
        -------
        GeodesicResult

        Raises
        ------
        SourceError
            Invalid sources.
        SolverError
            The backend did not reach an optimal solution.
        """
        src = validate_sources(sources, self.mesh.n_vertices)
        t0 = time.perf_counter()
        if self.is_baseline:
            if len(src) > 1 and not self._baseline.supports_multiple_sources:
                raise SourceError(f"method {self.method!r} supports a single source only")
            d, binfo = self._baseline.solve(src)
            d = np.asarray(d, dtype=float)
            info = SolveInfo(
                method=self.method, solver=str(binfo.get("solver", self.method)), status=binfo.get("status", "optimal"),
                iterations=int(binfo.get("iterations", 0)), setup_time=self.setup_time,
                solve_time=time.perf_counter() - t0, n_unreachable=int(np.isinf(d).sum()),
                extra={k: v for k, v in binfo.items() if k not in ("solver", "status", "iterations")},
            )
            return GeodesicResult(distance=d, info=info, sources=src)

        problem = build_problem(self._ops, src, self.method, self.lam)
        if self.solver_name == "ipm":
            res = self._ipm.solve(problem, tol=self.tol, max_iter=self.max_iter, callback=callback)
        else:
            from .solvers import solve_clarabel

            res = solve_clarabel(problem, tol=self.tol, max_iter=self.max_iter, verbose=self.verbose)
        d = np.array(res.x, dtype=float)
        d[problem.unreachable] = np.inf
        d[src] = 0.0
        info = SolveInfo(
            method=self.method, solver=res.solver, status=res.status, iterations=res.iterations,
            setup_time=self.setup_time, solve_time=time.perf_counter() - t0,
            primal_residual=res.primal_residual, dual_residual=res.dual_residual, gap=res.gap,
            objective=res.objective, lam=self.lam, n_unreachable=int(problem.unreachable.sum()), extra=res.extra,
        )
        return GeodesicResult(distance=d, info=info, sources=src)

    def solve_many(self, sources_list, *, progress: bool = False) -> list[GeodesicResult]:
        """Solve for each entry of ``sources_list`` (each an int or a list of ints), reusing all per-mesh work.

        Parameters
        ----------
        sources_list : sequence
        progress : bool
            Show a tqdm progress bar on stderr.

        Returns
        -------
        list of GeodesicResult
        """
        items = list(sources_list)
        if progress:
            from tqdm import tqdm

            items = tqdm(items, desc=f"{self.method}", unit="solve")
        return [self.solve(s) for s in items]


def geodesic_distance(mesh, sources, method: str = "qcqp-hessian", m: float = 1.0, solver: str = "auto",
                      *, lam: float | None = None, tol: float = DEFAULT_TOL, max_iter: int = 200) -> np.ndarray:
    """Geodesic distance field from source vertices (one-shot form of :class:`GeodesicSolver`).

    Parameters
    ----------
    mesh : TriMesh or tuple (V, F)
        ``V`` (n, 3) float vertex positions, ``F`` (m, 3) int triangles.
    sources : int or sequence of int
        Source vertex indices.
    method, m, solver, lam, tol, max_iter
        See :class:`GeodesicSolver`.

    Returns
    -------
    (n,) float ndarray
        Distance to the nearest source; 0 at sources, ``inf`` on components
        that contain no source.

    Examples
    --------
    >>> import cvxgeodesic as cg
    >>> d = cg.geodesic_distance(cg.icosphere(2), 0, method="qclp")
    >>> float(d[0])
    0.0
    """
    solver_obj = GeodesicSolver(mesh, method, m=m, lam=lam, solver=solver, tol=tol, max_iter=max_iter)
    return solver_obj.solve(sources).distance
