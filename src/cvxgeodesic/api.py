"""Public entry points: :class:`GeodesicSolver` (stateful) and :func:`geodesic_distance` (one shot)."""

from __future__ import annotations

import math
import numbers
import time
import warnings
from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ._threads import limited
from .errors import ParameterError, SolverError, SourceError
from .formulations import (
    ALIASES,
    FORMULATIONS,
    MeshOperators,
    build_problem,
    canonical_method,
    check_normalization,
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
        ``"optimal"`` on success, or ``"almost_optimal"`` (only reduced tolerances
        were met: Clarabel's ``AlmostSolved``, or an interior-point iterate within
        100 × ``tol`` before rounding stopped the iterations);
        ``"approximate"`` for an unpolished coarse-to-fine solve
        (``GeodesicSolver(..., multires=...)``), whose field is *not* the
        optimum on this mesh.
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
    notes : list of str
        One line per substitution or repair the library made for this result (degenerate
        faces left out, another energy, a manifold cover, a Clarabel retry, the ``d ≥ 0``
        re-solve, ...). Empty when the problem was solved exactly as asked.
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
    notes: list[str] = field(default_factory=list)
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
        The source vertices (fixed at 0). With point, curve or boundary sources: the vertices among them
        (points that lie on a vertex, boundary vertices), possibly none; the whole set is ``source_set``.
    source_set : SourceSet or None
        The normalized sources (:func:`cvxgeodesic.sources.resolve_sources`) when they were not all
        vertices; ``None`` otherwise.
    """

    distance: np.ndarray
    info: SolveInfo
    sources: np.ndarray
    source_set: Any = None

    def __post_init__(self) -> None:
        if self.source_set is not None:  # geodesic_path(mesh, result.distance, ...) then knows the sources
            from .sources import remember_sources

            remember_sources(self.distance, self.source_set)


def _is_real(value) -> bool:
    """True for Python and NumPy real numbers other than booleans."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool | np.bool_)


def _unit_mesh(mesh: TriMesh) -> tuple[TriMesh, float]:
    """The mesh divided by the power of two ``s`` that puts its bounding-box diagonal in [0.5, 1), and ``s``.

    The convex formulations are solved on this copy and the field is multiplied by ``s``:
    the backends' absolute tolerances then mean the same thing on a mesh of any size
    (without it a 1e-6-sized mesh lost three digits), and since ``s`` is a power of two
    the division is exact, so ``d(2^k V) = 2^k d(V)`` to the last bit.
    """
    diag = mesh.bbox_diagonal
    if not (np.isfinite(diag) and diag > 0):
        return mesh, 1.0
    scale = math.ldexp(1.0, math.frexp(diag)[1])
    if scale == 1.0:
        return mesh, 1.0
    return TriMesh(mesh.V / scale, mesh.F, vertex_map=mesh.vertex_map, name=mesh.name), scale


def _is_2d(x: Any) -> bool:
    """True for a 2-D array_like (a vertex or face array), False for anything else (meshes, sources)."""
    if isinstance(x, TriMesh | str) or not isinstance(x, np.ndarray | list | tuple) and not hasattr(x, "__array__"):
        return False
    try:
        return np.ndim(x) == 2
    except ValueError:  # ragged
        return False


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
    mesh : TriMesh, tuple (V, F), file path, trimesh.Trimesh, open3d TriangleMesh or meshio.Mesh
        ``V`` (n, 3) float, ``F`` (m, 3) int (see :func:`~cvxgeodesic.mesh.trimesh.as_trimesh`).
    method : str
        One of :data:`ALL_METHODS`: the eight convex formulations
        (``"lclp"``, ``"lcqp-dirichlet"``, ``"lcqp-laplacian"``, ``"lcqp-hessian"``
        (alias ``"qgdf"``), ``"qclp"``, ``"qcqp-dirichlet"``, ``"qcqp-laplacian"``,
        ``"qcqp-hessian"``) or a baseline (``"dijkstra"``, ``"fmm"``, ``"heat"``,
        ``"exact"``). Default ``"qcqp-hessian"``, the paper's recommendation.
    m : float
        Smoothness multiplier (default 1; 0 is the LP without smoothing). With the
        default ``normalization="area"`` the objective is
        ``−(1/|S|) ∫ d dA + λ E(d)`` with ``λ = m · κ · √|S|`` (``|S|`` the surface
        area, :data:`~cvxgeodesic.formulations.KAPPA`): one ``m`` rounds the ridge
        by the same length *on the surface* on every triangulation and at every
        scale; ``m = 1`` rounds it to about 0.4 of the exact field's sharpness on
        bimba (``docs/method.md``). Ignored by LP formulations and baselines.
    lam : float, optional
        Give λ directly instead of ``m``.
    normalization : {"area", "paper"}
        ``"paper"`` reproduces the paper's ``λ = m · 10² · h / n`` with the
        uniform stretch ``−(10/n) Σ d_i`` (this library's default before 0.2),
        whose rounding is a fixed number of *edges* wide: too strong on coarse
        meshes, invisible on fine ones.
    solver : {"auto", "ipm", "clarabel"}
        Backend for the convex formulations. ``"auto"`` uses the structured
        interior-point solver (``"ipm"``) when it is available, else Clarabel.
    tol : float
        Relative tolerance of residuals and duality gap.
    max_iter : int
        Interior-point iteration limit.
    verbose : bool
        Print the backend's iteration log.
    multires : bool or int
        Coarse-to-fine solve (convex formulations only): ``True`` simplifies the
        mesh to ``clip(n_faces // 4, 100, 50_000)`` faces, an int to that many
        faces (``0``/``False``: off; meshes already at or below the target are
        solved directly). Every solve then runs on the coarse mesh (sources
        mapped to the nearest coarse vertex, same ``m``) and the field is moved
        to this mesh by closest-point barycentric interpolation
        (:mod:`cvxgeodesic.multires`). **Without** ``multires_polish`` the result
        is an approximation of this mesh's optimum, reported with
        ``info.status == "approximate"``: it is the optimum of a coarser mesh.
        Measured against the direct solve at 1/4 of the faces, source vertex 0:
        mean ``|Δd|`` 0.6 % of the largest distance on bimba (46K faces; worst
        vertex 4.2 %), 3.4 % on spot (5.9K faces; worst 12.6 %); coarser
        meshes underestimate distances more (README "Coarse-to-fine"). Use it
        on large meshes, where the coarse mesh is still fine.
        ``info.extra["multires"]`` holds the coarse face count, the simplifier
        used, the largest source offset and the timings.
    multires_polish : bool
        With ``multires``, finish every solve with a full solve on this mesh, to
        the same tolerance as a direct solve: the result is this mesh's optimum
        (status ``"optimal"``) and ``info.extra["multires"]`` adds
        ``max_diff_to_coarse_transfer``, the largest difference between the
        transferred and the optimal field. The interior-point solver takes no
        warm start yet, so this costs a coarse solve *more* than a direct solve.
    order : {1, 2}
        ``2``: second-order elements for the squared distance (``method="qclp"`` only;
        :mod:`cvxgeodesic.elements_p2`, ``docs/order2.md``): exact on flat regions whatever
        the triangle shapes, sources may also be ``(face, bary)`` points, and
        ``info.extra["p2_field"].distance_at(faces, bary)`` evaluates the field inside
        faces. ``solver="auto"`` uses the order-2 structured solver (Clarabel as its
        fallback). Not with ``multires`` or the baselines.
    threads : int, optional
        Threads of every pool the solver uses (PARDISO, the compiled kernels, BLAS),
        for its construction and each solve; recorded in ``info.extra["threads"]``.
        ``None``: the environment variable ``CVXGEODESIC_THREADS``, else the cores
        that other processes leave free when the solver is built, at least one
        (``docs/performance.md``).

    Raises
    ------
    MeshError
        Invalid arrays (see :class:`~cvxgeodesic.mesh.trimesh.TriMesh`), or every face is
        degenerate (convex formulations).
    NonManifoldError
        ``"fmm"`` / ``"exact"`` on any non-manifold mesh (the Hessian formulations build their
        energy on a manifold cover instead, see ``info.notes``).
    ParameterError
        Unknown method or solver, invalid ``m``, ``lam``, ``tol``, ``max_iter`` or ``threads``
        (or ``CVXGEODESIC_THREADS``).
    TypeError
        ``mesh`` is none of the accepted kinds.

    Warns
    -----
    DegenerateFacesWarning
        Convex formulations on a mesh with degenerate faces (zero or near-zero area,
        :meth:`TriMesh.degenerate_faces`): they are left out of the cone constraints and
        energies and their edges get ``|d_i − d_j| ≤ ℓ_ij`` (README, "Input meshes").

    Notes
    -----
    Vertices in a connected component without a source, and vertices in no face, get
    ``inf`` with every method. The convex formulations are solved on a copy of the mesh
    divided by a power of two (its bounding-box diagonal then lies in [0.5, 1)) and the
    field is multiplied back, so results scale exactly with the mesh and the solver
    tolerances mean the same at any size; ``info.objective`` and ``info.lam`` are in the
    mesh's own units, the residuals and the gap are relative.

    Examples
    --------
    >>> import cvxgeodesic as cg
    >>> mesh = cg.icosphere(3)
    >>> solver = cg.GeodesicSolver(mesh, method="qclp")
    >>> result = solver.solve(0)
    >>> result.distance.shape, result.info.status
    ((642,), 'optimal')
    """

    @limited
    def __init__(
        self,
        mesh: Any,
        method: str = "qcqp-hessian",
        *,
        m: float = 1.0,
        lam: float | None = None,
        solver: str = "auto",
        tol: float = DEFAULT_TOL,
        max_iter: int = 200,
        verbose: bool = False,
        multires: bool | int = False,
        multires_polish: bool = False,
        normalization: str = "area",
        order: int = 1,
        threads: int | None = None,
    ) -> None:
        t0 = time.perf_counter()
        self.mesh: TriMesh = as_trimesh(mesh)
        if not isinstance(method, str):
            raise ParameterError(f"method must be a string, got {type(method).__name__}")
        key = method.lower()
        if key in BASELINE_METHODS:
            self.method = key
        elif key not in FORMULATIONS and key not in ALIASES:
            raise ParameterError(f"unknown method {method!r}; choose one of {', '.join(ALL_METHODS)}")
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
        if not (_is_real(tol) and 0 < tol < 1):
            raise ParameterError(f"tol must be a number in (0, 1), got {tol!r}")
        if isinstance(max_iter, bool) or not isinstance(max_iter, int | np.integer) or max_iter < 1:
            raise ParameterError(f"max_iter must be a positive integer, got {max_iter!r}")
        self.tol, self.max_iter, self.verbose = float(tol), int(max_iter), bool(verbose)
        self.normalization = check_normalization(normalization)
        # substitutions made for every solve of this object (copied into SolveInfo): the loader's repairs first
        self.notes: list[str] = list(getattr(self.mesh, "notes", ()))
        if isinstance(order, bool) or order not in (1, 2):
            raise ParameterError(f"order must be 1 (P1 distance) or 2 (P2 squared distance), got {order!r}")
        self.order = int(order)
        self._order2 = None
        if self.order == 2:  # P2 elements for d² (cvxgeodesic.elements_p2): its own program and solvers
            if self.is_baseline or multires:
                raise ParameterError("order=2 applies to the convex formulations without multires")
            from .elements_p2 import Order2Strategy

            self.lam = 0.0
            self.m = None
            self.energy = None
            self._order2 = Order2Strategy(self, solver)
            self.solver_name = self._order2.backend
            self.setup_time = time.perf_counter() - t0
            return

        self.energy = None if self.method in BASELINE_METHODS else FORMULATIONS[self.method][1]
        if lam is not None:
            if not _is_real(lam) or not np.isfinite(lam) or lam < 0:
                raise ParameterError(f"lam must be a finite number >= 0, got {lam!r}")
            self.lam = float(lam)
        else:
            if not _is_real(m) or not np.isfinite(m) or m < 0:
                raise ParameterError(f"m must be a finite number >= 0, got {m!r}")
            self.lam = smoothness_weight(self.mesh, m, self.normalization, self.energy or "hessian")
        self.m = None if lam is not None else float(m)

        self._baseline: Any = None
        self._ops: Any = None
        self._ipm: Any = None
        self._scale = 1.0  # the convex formulations are solved on the mesh divided by this power of two
        self._multires = None
        from .multires import resolve_target

        mr_target = resolve_target(multires, self.mesh.n_faces)
        if mr_target is not None and self.is_baseline:
            raise ParameterError(f"multires applies to the convex formulations, not to baseline {self.method!r}")
        self._multires_skipped = mr_target is not None and mr_target >= self.mesh.n_faces
        if self._multires_skipped:
            mr_target = None
        if self.is_baseline:
            from .baselines import BASELINES

            self._baseline = BASELINES[self.method](self.mesh)
            self.solver_name = self.method
        else:
            if self.energy is None:
                self.lam = 0.0
            if mr_target is not None:
                from .multires import CoarseToFine

                self._multires = CoarseToFine(self, mr_target, solver, multires_polish)
                self.solver_name = self._multires.coarse.solver_name
            if self._multires is None or self._multires.polish:  # the fine mesh's own operators and solver
                unit_mesh, self._scale = _unit_mesh(self.mesh)
                self._ops = MeshOperators(unit_mesh)
                self._ops.notes[0:0] = self.notes
                self.notes = self._ops.notes  # the operators add their substitutions as they build
                if self.energy is not None:
                    self._ops.energy(self.energy)  # builds it now (PSD check, manifold cover)
                self.solver_name = ("ipm" if _ipm_available() else "clarabel") if solver == "auto" else solver
                self._fallback_to_clarabel = solver == "auto"
                if self.solver_name == "ipm":
                    if not _ipm_available():
                        raise ParameterError("solver='ipm' is not available in this installation")
                    from .solvers.ipm import InteriorPointSolver
                    from .solvers.problem import kkt_pattern

                    P = self._ops.energy(self.energy) if self.energy is not None else None
                    self._ipm = InteriorPointSolver(
                        kkt_pattern(self.mesh.n_vertices, self.mesh.F, self.mesh.edges, P))
                _ = self._ops.gradient_blocks
        self.setup_time = time.perf_counter() - t0

    def __repr__(self) -> str:
        return (
            f"GeodesicSolver(mesh={self.mesh!r}, method={self.method!r}, "
            f"solver={self.solver_name!r}, lam={self.lam:.3g})"
        )

    @limited
    def solve(self, sources: ArrayLike, *, callback: Callable[[int, dict], None] | None = None) -> GeodesicResult:
        """Distance field from one or several source vertices.

        Parameters
        ----------
        sources : int, sequence of int, SurfacePoint, SurfaceCurve, "boundary", or a list mixing them
            Source vertex indices (distinct, in ``[0, n)``), points anywhere on the surface, curves,
            or every boundary edge (``docs/sources.md``). With ``order=2``
            (P2 squared distance): vertices and points (SurfacePoints, ``(face, bary)``) only.
        callback : callable, optional
            ``callback(iteration, info_dict)`` after every interior-point
            iteration of the ``"ipm"`` backend (used for progress reports).

        Returns
        -------
        GeodesicResult

        Raises
        ------
        SourceError
            Invalid sources: empty, ragged, not integers (bools included), out of range,
            repeated; several sources for a baseline that takes one; a bad SurfacePoint or
            SurfaceCurve, ``"boundary"`` on a closed mesh; a kind of source the method cannot take
            (the message names the methods that can).
        SolverError
            The backend did not reach an optimal solution (for the Hessian energy the
            message adds that it can be indefinite on meshes with sharp corners).
        """
        if self._order2 is not None:
            return self._order2.solve(sources, callback=callback)
        from .sources import resolve_sources

        sset = resolve_sources(self.mesh, sources)
        src = sset.vertices if sset.vertex_only else sset
        t0 = time.perf_counter()
        if self.is_baseline and not sset.vertex_only:
            from .baselines.points import solve_baseline_sources

            d, binfo = solve_baseline_sources(self._baseline, sset)
            info = SolveInfo(method=self.method, solver=str(binfo.pop("solver")), status="optimal",
                             setup_time=self.setup_time, solve_time=time.perf_counter() - t0,
                             n_unreachable=int(np.isinf(d).sum()), notes=list(self.notes), extra=binfo)
            return GeodesicResult(distance=d, info=info, sources=sset.vertices, source_set=sset)
        if self.is_baseline:
            src = sset.vertices
            if len(src) > 1 and not self._baseline.supports_multiple_sources:
                raise SourceError(f"method {self.method!r} supports a single source only")
            d, binfo = self._baseline.solve(src)
            d = np.asarray(d, dtype=float)
            info = SolveInfo(
                method=self.method, solver=str(binfo.get("solver", self.method)), status=binfo.get("status", "optimal"),
                iterations=int(binfo.get("iterations", 0)), setup_time=self.setup_time,
                solve_time=time.perf_counter() - t0, n_unreachable=int(np.isinf(d).sum()), notes=list(self.notes),
                extra={k: v for k, v in binfo.items() if k not in ("solver", "status", "iterations")},
            )
            return GeodesicResult(distance=d, info=info, sources=src)

        if self._multires is not None:
            if not sset.vertex_only:
                raise SourceError("multires takes vertex sources only; solve point, curve and boundary sources "
                                  "without multires")
            return self._multires.solve(self, sset.vertices, callback=callback)
        res = self._solve_direct(src, t0, callback)
        if self._multires_skipped:
            res.info.extra["multires"] = {"coarse_faces": self.mesh.n_faces, "polished": True,
                                          "skipped": "the mesh has no more faces than the multires target"}
        return res

    def _run_backend(self, problem, callback=None, notes=None):
        """Solve ``problem`` with the chosen backend; under ``solver="auto"`` Clarabel retries a failed or
        ``almost_optimal`` IPM solve."""
        from .solvers import solve_clarabel

        try:
            if self.solver_name != "ipm":
                return solve_clarabel(problem, tol=self.tol, max_iter=self.max_iter, verbose=self.verbose)
            if self.verbose:
                from ._verbose import ipm_log

                callback = ipm_log(callback)
            try:
                res = self._ipm.solve(problem, tol=self.tol, max_iter=self.max_iter, callback=callback)
            except SolverError as exc:
                if not self._fallback_to_clarabel or exc.status in ("primal_infeasible", "dual_infeasible"):
                    raise
                return self._clarabel_retry(problem, exc.status, notes)
            if res.status == "optimal" or not self._fallback_to_clarabel:
                return res
            try:  # "almost_optimal": Clarabel may reach the full accuracy; else keep the IPM's best iterate
                return self._clarabel_retry(problem, res.status, notes)
            except SolverError:
                if notes is not None:
                    notes.append("Clarabel failed too; kept the interior-point solver's almost optimal iterate")
                return res
        except SolverError as exc:
            if self.energy != "hessian" or problem.P is None:
                raise
            # measured on Thingi10K CAD meshes: libigl's curved Hessian energy has negative eigenvalues where
            # the angle defect is large (sharp corners), and the problem is then not convex
            msg = str(exc).rsplit(" (solver=", 1)[0]
            raise SolverError(
                f"{msg} on {self.mesh.name}; the curved Hessian energy can be indefinite on meshes with sharp "
                f"corners, which makes {self.method!r} non-convex: try 'qcqp-laplacian' or 'qclp'",
                solver=exc.solver, status=exc.status, info=exc.info,
            ) from exc

    def _clarabel_retry(self, problem, ipm_status: str, notes=None):
        from .solvers import solve_clarabel

        message = (f"the interior-point solver stopped with status {ipm_status!r} on {self.mesh.name}; "
                   "solving with Clarabel instead")
        warnings.warn(message, RuntimeWarning, stacklevel=5)
        if notes is not None:
            notes.append(message)
        res = solve_clarabel(problem, tol=self.tol, max_iter=self.max_iter, verbose=self.verbose)
        res.extra = dict(res.extra, ipm_failure=ipm_status)
        return res

    def _solve_direct(self, src: Any, t0: float, callback=None) -> GeodesicResult:
        """Solve the formulation on this mesh (no multires); ``t0`` starts the solve clock."""
        # on the mesh scaled by 1/s, the field d/s minimizes (objective)/s when lambda becomes lambda/s
        stretch = "area" if self.normalization == "area" else "calibrated"
        problem = build_problem(self._ops, src, self.method, self.lam / self._scale, stretch=stretch)
        notes = list(self.notes)
        res = self._run_backend(problem, callback, notes)
        negative_min = np.min(res.x[~problem.fixed_mask], initial=0.0)
        if negative_min < -1e-9 * self.mesh.bbox_diagonal / self._scale:
            # folded meshes (and strongly smoothed coarse fields) can trade a few negative values for a larger sum;
            # the bounds d >= 0 fix that but slow ordinary solves down, so they are added only when needed
            extra = dict(res.extra, negative_min=float(np.min(res.x)), resolved_nonnegative=True)
            notes.append(f"the optimum had negative distances (down to {negative_min * self._scale:.3g}); "
                         "re-solved with the bounds d >= 0")
            problem = build_problem(self._ops, src, self.method, self.lam / self._scale, stretch=stretch,
                                    nonnegative=True)
            res = self._run_backend(problem, callback, notes)
            res.extra = {**extra, **res.extra}
        d = np.array(res.x, dtype=float) * self._scale
        d[problem.unreachable] = np.inf
        vertices = src if isinstance(src, np.ndarray) else src.vertices
        d[vertices] = 0.0
        info = SolveInfo(
            method=self.method, solver=res.solver, status=res.status, iterations=res.iterations,
            setup_time=self.setup_time, solve_time=time.perf_counter() - t0,
            primal_residual=res.primal_residual, dual_residual=res.dual_residual, gap=res.gap,
            objective=res.objective / problem.objective_scale * self._scale, lam=self.lam,
            n_unreachable=int(problem.unreachable.sum()),
            notes=notes, extra=res.extra,
        )
        return GeodesicResult(distance=d, info=info, sources=vertices,
                              source_set=None if isinstance(src, np.ndarray) else src)

    def solve_many(self, sources_list: Iterable[Any], *, progress: bool = False) -> list[GeodesicResult]:
        """Solve for each entry of ``sources_list`` (each anything :meth:`solve` takes), reusing all per-mesh work.

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


def geodesic_distance(mesh: Any, *args: Any, sources: Any = None, method: str | None = None, m: float | None = None,
                      solver: str | None = None, lam: float | None = None, tol: float = DEFAULT_TOL,
                      max_iter: int = 200, normalization: str = "area",
                      order: int = 1, threads: int | None = None) -> np.ndarray:
    """Geodesic distance field from source vertices (one-shot form of :class:`GeodesicSolver`).

    Two call forms, told apart by the second argument (sources are never a 2-D array):

    - ``geodesic_distance(mesh, sources, method="qcqp-hessian", m=1.0, solver="auto")``;
    - ``geodesic_distance(V, F, sources, method, m, solver)``: the argument order of
      potpourri3d and libigl, used when both ``V`` and ``F`` are 2-D arrays.

    ``sources`` may also be SurfacePoints, SurfaceCurves, ``"boundary"`` or a list mixing them
    with vertex indices (see :meth:`GeodesicSolver.solve` and ``docs/sources.md``).

    Parameters
    ----------
    mesh : TriMesh, tuple (V, F), file path, trimesh.Trimesh, open3d TriangleMesh or meshio.Mesh
        See :func:`~cvxgeodesic.mesh.trimesh.as_trimesh`; or ``V``, (n, 3) float vertex
        positions, followed by ``F``, (m, 3) int triangles.
    sources : int or sequence of int
        Source vertex indices (positional after the mesh, or keyword), or surface sources.
    method, m, solver, lam, tol, max_iter, normalization, threads
        See :class:`GeodesicSolver` (defaults ``"qcqp-hessian"``, 1.0, ``"auto"``).

    Returns
    -------
    (n,) float ndarray
        Distance to the nearest source; 0 at sources, ``inf`` on components
        that contain no source (and on vertices in no face), in every method.

    Raises
    ------
    MeshError, NonManifoldError, ParameterError, SourceError, SolverError, TypeError
        See :class:`GeodesicSolver` and :meth:`GeodesicSolver.solve`; ``TypeError`` also for
        missing sources or an argument given both by position and by keyword.

    Examples
    --------
    >>> import cvxgeodesic as cg
    >>> d = cg.geodesic_distance(cg.icosphere(2), 0, method="qclp")
    >>> float(d[0])
    0.0
    >>> mesh = cg.icosphere(2)
    >>> bool((cg.geodesic_distance(mesh.V, mesh.F, 0, method="qclp") == d).all())
    True
    """
    rest = list(args)
    if rest and _is_2d(mesh) and _is_2d(rest[0]):  # potpourri3d / libigl order: (V, F, sources, ...)
        mesh = (mesh, rest.pop(0))
    names = ("sources", "method", "m", "solver")
    if len(rest) > len(names):
        raise TypeError(f"geodesic_distance() takes at most {len(names)} arguments after the mesh")
    given = dict(zip(names, rest, strict=False))
    for key, value in (("sources", sources), ("method", method), ("m", m), ("solver", solver)):
        if value is not None:
            if key in given:
                raise TypeError(f"geodesic_distance() got multiple values for argument {key!r}")
            given[key] = value
    if "sources" not in given:
        raise TypeError("geodesic_distance() missing the source vertices: geodesic_distance(mesh, sources)")
    sources = given["sources"]
    method = given.get("method", "qcqp-hessian")
    m = given.get("m", 1.0)
    solver = given.get("solver", "auto")
    solver_obj = GeodesicSolver(mesh, method, m=m, lam=lam, solver=solver, tol=tol, max_iter=max_iter,
                                normalization=normalization, order=order, threads=threads)
    return solver_obj.solve(sources).distance


def distance_matrix(mesh: Any, vertices: ArrayLike, method: str = "qcqp-hessian", m: float = 1.0, solver: str = "auto",
                    progress: bool = False, *, lam: float | None = None, tol: float = DEFAULT_TOL,
                    max_iter: int = 200, multires: bool | int = False, normalization: str = "area",
                    order: int = 1, threads: int | None = None) -> np.ndarray:
    """Distance fields from several vertices, one row per vertex, with one :class:`GeodesicSolver`.

    The per-mesh work (operators, energy matrix, symbolic Cholesky analysis) is
    done once; every row is one solve with a single source. A vertex listed
    twice is solved once and its row copied. ``vertices`` may also be a SurfacePoint, a
    SurfaceCurve, ``"boundary"`` or a list of them and ints: one row per item.

    Parameters
    ----------
    mesh : TriMesh or tuple (V, F)
        ``V`` (n, 3) float vertex positions, ``F`` (m, 3) int triangles.
    vertices : int or (k,) sequence of int
        Source vertex of each row.
    method, m, solver, lam, tol, max_iter, multires, normalization, threads
        See :class:`GeodesicSolver`.
    progress : bool
        Show a tqdm progress bar (one step per distinct vertex) on stderr.

    Returns
    -------
    (k, n) float ndarray
        ``D[i, j]`` is the distance of vertex ``j`` from ``vertices[i]``
        (``inf`` where ``j`` is not connected to it). The matrix is not exactly
        symmetric: every row is its own optimization problem.

    Raises
    ------
    SourceError
        ``vertices`` is empty, not integers, or out of range.

    Examples
    --------
    >>> import cvxgeodesic as cg
    >>> D = cg.distance_matrix(cg.icosphere(2), [0, 5, 9], method="qclp")
    >>> D.shape, float(D[1, 5])
    ((3, 162), 0.0)
    """
    mesh = as_trimesh(mesh)
    from .sources import SurfaceCurve, SurfacePoint

    def rows_of(items: list) -> np.ndarray:
        solver_obj = GeodesicSolver(mesh, method, m=m, lam=lam, solver=solver, tol=tol, max_iter=max_iter,
                                    multires=multires, normalization=normalization, order=order, threads=threads)
        return np.stack([r.distance for r in solver_obj.solve_many(items, progress=progress)])

    surface = (SurfacePoint, SurfaceCurve, str)
    if isinstance(vertices, surface) or (isinstance(vertices, list | tuple)
                                         and any(isinstance(v, surface) for v in vertices)):
        return rows_of([vertices] if isinstance(vertices, surface) else list(vertices))  # one row per item
    if isinstance(vertices, bool | np.bool_):
        raise SourceError(f"vertices must be vertex indices, got {vertices!r}")
    arr = np.atleast_1d(np.asarray(vertices))
    if arr.ndim != 1:
        raise SourceError(f"vertices must be an int or a 1-D sequence of ints, got shape {arr.shape}")
    if arr.size == 0:
        raise SourceError("vertices is empty: give at least one source vertex")
    uniq, inverse = np.unique(arr, return_inverse=True)
    uniq = validate_sources(uniq, mesh.n_vertices)
    return rows_of(uniq.tolist())[np.asarray(inverse).ravel()]
