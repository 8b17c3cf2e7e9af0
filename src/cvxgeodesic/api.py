"""Public entry points: :class:`GeodesicSolver` (stateful) and :func:`geodesic_distance` (one shot).

:class:`GeodesicSolver` is a façade: it validates its arguments once, builds the solve strategy that fits
them (:mod:`cvxgeodesic.strategies`: direct, baseline, coarse-to-fine, order 2) and delegates every solve
to it. The result types live in :mod:`cvxgeodesic.results` and are re-exported here.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING, Any, Literal, TypeAlias, overload

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike

from . import capabilities
from ._threads import limited
from .baselines import BASELINES
from .capabilities import DOMAINS, METHODS, Capability, methods_for, source_kinds, supported
from .errors import ParameterError
from .mesh.convert import MeshLike, as_mesh
from .mesh.simplex import SimplexMesh
from .operators.metric import make_medium
from .problems.formulations import ALIASES, FORMULATIONS, NORMALIZATIONS, smoothness_weight
from .results import GeodesicResult, SolveInfo
from .solvers._interrupt import reporting_to
from .sources import resolve_sources
from .strategies import SolveConfig, SolveStrategy, make_strategy, resolve_target
from .strategies.adapted import resolve_resolution
from .strategies.cloud_default import denoised_copy_refusal
from .validation import (
    check_choice,
    check_count,
    check_lam,
    check_number,
    check_order,
    check_output_path,
    check_smoothness,
    validate_sources,
)

if TYPE_CHECKING:
    from .mesh.pointcloud import PointCloud

__all__ = ["ALL_METHODS", "BASELINE_METHODS", "DEFAULT_TOL", "GeodesicResult", "GeodesicSolver", "Method", "SOLVERS",
           "SolveInfo", "SolverName", "distance_matrix", "geodesic_distance"]

BASELINE_METHODS = tuple(BASELINES)
ALL_METHODS = (*FORMULATIONS, *ALIASES, *BASELINE_METHODS)
SOLVERS = ("auto", "ipm", "clarabel")
#: A method name as a type: every name of :data:`ALL_METHODS` (formulations, aliases, baselines), so that a type
#: checker refuses ``method="qclpp"``. At run time the names are also taken in any case (``"QCLP"``); a name held
#: in a ``str`` variable is checked at run time: ``typing.cast(cg.Method, name)``. tests/test_typing.py keeps it
#: equal to :data:`ALL_METHODS`.
Method: TypeAlias = Literal["lclp", "lcqp-dirichlet", "lcqp-laplacian", "lcqp-hessian", "qclp", "qcqp-dirichlet",
                            "qcqp-laplacian", "qcqp-hessian", "qgdf", "dijkstra", "fmm", "heat", "exact"]
#: A backend name of :data:`SOLVERS` as a type.
SolverName: TypeAlias = Literal["auto", "ipm", "clarabel"]
DEFAULT_TOL = 1e-8
#: The method of ``distance_matrix(method=None)`` (and ``cvxgeodesic matrix``) on every mesh: as accurate as
#: ``qcqp-hessian`` against the exact distance and 1.5-2.3x faster per row (benchmarks/row_default.py,
#: docs/performance.md).
DEFAULT_ROW_METHOD: Method = "qclp"


def _is_2d(x: Any) -> bool:
    """True for a 2-D array_like (a vertex or face array), False for anything else (meshes, sources)."""
    if not isinstance(x, np.ndarray | list | tuple) and not hasattr(x, "__array__"):  # a mesh object, a path
        return False
    try:
        return np.ndim(x) == 2
    except ValueError:  # ragged
        return False


class GeodesicSolver:
    """Geodesic distances on one mesh, with per-mesh work done once.

    Parameters
    ----------
    mesh : TriMesh, tuple (V, F), file path, trimesh.Trimesh, open3d TriangleMesh or meshio.Mesh
        ``V`` (n, 3) float, ``F`` (m, 3) int (see :func:`~cvxgeodesic.mesh.io.as_trimesh`); or a tetrahedral
        mesh: a :class:`~cvxgeodesic.mesh.tetmesh.TetMesh`, ``(V, T)`` with ``T`` (k, 4) int, a file holding
        tetrahedra, a meshio.Mesh with ``tetra`` cells: the distance *inside* the solid (``docs/volumes.md``;
        sources vertices, VolumePoints, BoundaryFaces and ``"boundary"``). Which method takes which mesh,
        order, medium and source: :mod:`cvxgeodesic.capabilities` (``docs/capabilities.md``).
    method : str (:data:`Method`)
        One of :data:`ALL_METHODS`: the eight convex formulations
        (``"lclp"``, ``"lcqp-dirichlet"``, ``"lcqp-laplacian"``, ``"lcqp-hessian"``
        (alias ``"qgdf"``), ``"qclp"``, ``"qcqp-dirichlet"``, ``"qcqp-laplacian"``,
        ``"qcqp-hessian"``) or a baseline (``"dijkstra"``, ``"fmm"``, ``"heat"``,
        ``"exact"``). Default (None) ``"qcqp-hessian"``, the paper's recommendation; ``"qclp"`` on a
        tetrahedral mesh, where the curved Hessian does not apply.
    m : float
        Smoothness multiplier (default 1; 0 is the LP without smoothing). With the
        default ``normalization="area"`` the objective is
        ``−(1/|S|) ∫ d dA + λ E(d)`` with ``λ = m · κ · √|S|`` (``|S|`` the surface
        area, :data:`~cvxgeodesic.problems.formulations.KAPPA`): one ``m`` rounds the ridge
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
        (:mod:`cvxgeodesic.strategies.coarse_to_fine`). **Without** ``multires_polish`` the result
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
    order : {1, 2}, optional
        The element order. None (the default): order 1 on this mesh, except where the domain's default resolution
        applies (point clouds: ``resolution="auto"``, order 2 on a decimated copy; docs/pointclouds.md). A given order
        solves on this mesh unless ``resolution`` is given too. ``2``: second-order elements for the squared
        distance (``method="qclp"`` and the ``qcqp`` methods; :mod:`cvxgeodesic.problems.squared_distance`,
        ``docs/order2.md``): exact on flat regions whatever the triangle shapes; sources may be vertices,
        SurfacePoints (at most one per face) and ``"boundary"``; ``result.field.distance_at(faces, bary)`` evaluates
        the field inside faces. The same solvers and fallback as order 1. Not with ``multires`` or the baselines. The
        smoothed methods take energies of ``φ = d²`` that vanish on the exact field of flat regions
        (:mod:`cvxgeodesic.operators.squared_energy`) with the dimensionless ``λ = m · κ₂``
        (:data:`~cvxgeodesic.problems.formulations.KAPPA_ORDER2`): ``m = 1`` rounds the ridge of two sources half a
        side apart on a unit square over about 1.2 % of the side, ``m = 30`` over 4 % (order 1's ``m = 1``); the width
        grows as ``m^(1/3)`` (docs/order2.md, "Smoothing at order 2").
    threads : int, optional
        Threads of every pool the solver uses (PARDISO, the compiled kernels, BLAS),
        for its construction and each solve; recorded in ``info.extra["threads"]``.
        ``None``: the environment variable ``CVXGEODESIC_THREADS``, else the cores
        that other processes leave free when the solver is built, at least one
        (``docs/performance.md``).
    cost : float or (n,) or (m,) float array_like, optional
        Travel cost (time per unit length, ``1/speed``; positive): the distance becomes the
        travel time. Per vertex or per face (``docs/metrics.md``). The eight formulations at order 1,
        ``"qclp"`` (or a smoothed method with ``m=0``) at order 2, and ``"dijkstra"``; recorded in
        ``info.extra["cost"]``.
    metric : (3, 3), (n, 3, 3) or (m, 3, 3) float array_like, optional
        Riemannian metric: a tangent vector ``u`` is ``√(uᵀ M u)`` long (times the cost, with
        both). Symmetric, positive definite in each face's plane. Recorded in
        ``info.extra["metric"]``.
    resolution : "mesh", "auto", int or float, optional
        The mesh the field is solved on (``docs/adapted.md``). ``"mesh"``: this mesh. An int (>= 4): a
        quadric-decimated copy with about that many faces; a float in (0, 1): that fraction of the faces;
        ``"auto"``: 1/10 of the faces, at least 2,000 (:data:`~cvxgeodesic.strategies.adapted.AUTO_FRACTION`).
        Any of these solves **at order 2** (``order=1`` with one of them is refused) on the copy, with the sources
        at their exact positions, and answers on this mesh: ``distance`` per vertex, ``distance_at`` and
        ``geodesic_path`` on this surface; ``info.extra["adapted"]`` records the solve mesh, its times and, with
        ``estimate_error=True``, an error estimate. Non-manifold meshes, several components and faces of zero area
        are solved on this mesh at order 1 instead, with a note. Surfaces, and point clouds (the copy decimated from
        the surface through the points, ``PointCloud.surface``; docs/pointclouds.md); not with ``multires``. None: the
        mesh's domain's (:attr:`cvxgeodesic.capabilities.Domain.default_resolution`: ``"mesh"`` on surfaces and
        volumes, ``"auto"`` on point clouds) when ``order`` is not given and the method, medium and smoothing have an
        adapted solve, else ``"mesh"``.
    estimate_error : bool, default False
        With ``resolution``: estimate every solve's mean relative error by two more solves, on copies with half and
        twice the faces (``info.extra["adapted"]["error_estimate"]``, within [0.5, 2] of the true mean error in 100
        of 104 measured solves, docs/adapted.md). Off by default: the two solves cost about twice the adapted solve
        (1.6–3.6× on the shared surfaces), which would triple the price of the field. False: None there.

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
        (or ``CVXGEODESIC_THREADS``); a method, order, medium or ``multires`` that
        :func:`cvxgeodesic.capabilities.check` refuses on this mesh (the message says why and names
        what is supported).
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

    threads: int  # set by @limited before __init__'s body runs
    _lam_checked: bool = False  # a lam= checked elsewhere already (the patches of local rows: _PatchSolver)

    @limited
    def __init__(
        self,
        mesh: MeshLike,
        method: Method | None = None,
        *,
        m: float = 1.0,
        lam: float | None = None,
        solver: SolverName = "auto",
        tol: float = DEFAULT_TOL,
        max_iter: int = 200,
        verbose: bool = False,
        multires: bool | int = False,
        multires_polish: bool = False,
        normalization: str = "area",
        order: int | None = None,
        threads: int | None = None,
        cost: Any = None,
        metric: Any = None,
        resolution: Any = None,
        estimate_error: bool = False,
    ) -> None:
        t0 = time.perf_counter()
        self.mesh: SimplexMesh = as_mesh(mesh)  # a TriMesh, TetMesh or CloudMesh: what differs, its reference says,
        self.domain = DOMAINS[self.mesh.domain]  # and its domain names its defaults and the words of its messages
        self._check_method_and_solver(method, solver)
        target = resolve_target(multires, self.mesh.n_cells)  # a volume refuses multires below (capabilities)
        medium = "none" if cost is None and metric is None else "cost" if cost is not None else "metric"
        m_value, lam_value = check_smoothness(m, lam)
        smoothing = self._smoothing(m_value, lam_value)
        self._set_order_and_resolution(order, resolution, multires=target is not None, medium=medium,
                                       smoothing=smoothing)
        self._check_capabilities(medium=medium, multires=target is not None, smoothing=smoothing)
        # a travel cost or metric (operators/metric.py): validated here, once
        self.medium = make_medium(self.mesh, cost, metric)
        self.tol = check_number(tol, "tol", low=0, high=1, low_open=True, high_open=True)
        self.max_iter = check_count(max_iter, "max_iter")
        self.verbose = bool(verbose)
        self.normalization = check_choice(normalization, "normalization", NORMALIZATIONS)
        self._set_smoothness(m_value, lam_value)
        config = SolveConfig(mesh=self.mesh, method=self.method, lam=self.lam, m=self.m,
                             normalization=self.normalization, solver=self._solver, tol=self.tol,
                             max_iter=self.max_iter, verbose=self.verbose, medium=self.medium,
                             notes=(*getattr(self.mesh, "notes", ()), *self._default_notes,
                                    *getattr(self.medium, "notes", ())),
                             capability=self.capability)
        self._strategy: SolveStrategy = make_strategy(config, baseline=self.is_baseline, order=self.order,
                                                      multires_target=target, polish=bool(multires_polish),
                                                      resolution=self.resolution, estimate=bool(estimate_error))
        self.solver_name = self._strategy.backend
        # substitutions made for every solve of this object (copied into SolveInfo): the loader's repairs first
        self.notes: list[str] = self._strategy.notes
        self.setup_time = time.perf_counter() - t0

    def _set_order_and_resolution(self, order: Any, resolution: Any, *, multires: bool, medium: str,
                                  smoothing: bool) -> None:
        """``self.order`` and ``self.resolution`` (``"mesh"``, or what :func:`resolve_resolution` takes) checked. A
        resolution other than ``"mesh"`` solves at order 2 (docs/adapted.md), so ``order=1`` with one is refused.
        With neither given, the domain's default resolution applies where the capability table has an adapted
        solve for this method, medium and smoothing (:attr:`~cvxgeodesic.capabilities.Domain.default_resolution`:
        ``"auto"`` on point clouds), else this mesh at order 1."""
        given = None if order is None else check_order(order)
        self._default_notes: list[str] = []
        if resolution is None:
            resolution = "mesh" if given is not None else self._default_resolution(
                multires=multires, medium=medium, smoothing=smoothing)
        self.order: int = 1 if given is None else given
        if resolve_resolution(resolution, self.mesh.n_cells) is None:
            self.resolution: Any = "mesh"
            return
        if multires:
            raise ParameterError("give multires= or resolution=, not both: each chooses the mesh the field is "
                                 "solved on (resolution= at order 2 with the sources at their positions, "
                                 "docs/adapted.md)")
        if given == 1:
            raise ParameterError(f"resolution={resolution!r} solves at order 2 on a decimated copy; order=1 solves "
                                 "on this mesh: give resolution='mesh' with order=1, or leave order out "
                                 "(docs/adapted.md)")
        self.resolution = resolution.strip().lower() if isinstance(resolution, str) else resolution
        self.order = 2

    def _default_resolution(self, *, multires: bool, medium: str, smoothing: bool) -> Any:
        """The resolution of ``resolution=None`` and ``order=None``: the domain's where the capability table has an
        adapted solve for this method, medium and smoothing, else ``"mesh"``; on a point cloud too noisy for a copy
        (:meth:`~cvxgeodesic.mesh.pointcloud.PointCloud.default_refusal`), or denoised with a surface whose holes
        keep its copy above target (:func:`~cvxgeodesic.strategies.cloud_default.denoised_copy_refusal`), ``"mesh"``
        with a note."""
        resolution = self.domain.default_resolution
        if resolution == "mesh" or multires or not supported(
                self.method, domain=self.domain.name, order=2, medium=medium, smoothing=smoothing, resolution=True):
            return "mesh"
        cloud = getattr(self.mesh, "cloud", None)
        if cloud is None:
            return resolution
        why = cloud.default_refusal()  # noisy points as given: order 1 on their triangles beats a copy of them
        advice = ("; on the cloud denoised first (PointCloud(..., denoise='jet')) it was more accurate on most "
                  "noisy clouds measured, at up to twice the time") if why else ""
        why = why or denoised_copy_refusal(self.mesh, resolution)
        if why is None:
            return resolution
        self._default_notes.append(
            f"{self.mesh.name}: solved at order 1 on its triangles, not at order 2 on a copy (the default, "
            f"resolution={resolution!r}): {why} (docs/pointclouds.md); resolution={resolution!r} asks for it{advice}")
        return "mesh"

    def _check_method_and_solver(self, method: Any, solver: Any) -> None:
        if method is None:
            method = self.domain.default_method
        if not isinstance(method, str):
            raise ParameterError(f"method must be a string, got {type(method).__name__}")
        key = ALIASES.get(method.lower(), method.lower())
        if key not in ALL_METHODS:
            known = methods_for(self.domain.name)  # every name where every method applies (aliases too), else the
            names = ALL_METHODS if len(known) == len(METHODS) else known  # domain's methods
            raise ParameterError(f"unknown method {method!r}; choose one of {', '.join(names)} "
                                 f"(on {self.domain.meshes})")
        self.method = key
        self._solver = check_choice(solver, "solver", SOLVERS)
        self.is_baseline = self.method in BASELINE_METHODS
        if self.is_baseline and self._solver != "auto":
            raise ParameterError(
                f"solver={self._solver!r} applies to the convex formulations, not to baseline {self.method!r}"
            )

    def _smoothing(self, m_value: float, lam_value: float | None) -> bool:
        """Whether the solve has a smoothness term (a smoothed order-2 solve takes no medium); sets ``self.energy``
        (None: the method has none)."""
        self.energy = FORMULATIONS.get(self.method, ("", None))[1]
        return self.energy is not None and (m_value > 0 if lam_value is None else lam_value > 0)

    def _check_capabilities(self, *, medium: str, multires: bool, smoothing: bool) -> None:
        """Raise when the capability table (:mod:`cvxgeodesic.capabilities`) refuses the method on this mesh's domain,
        at this order, with this medium, multires and resolution: the one :func:`~cvxgeodesic.capabilities.check` of
        this solver, whose cell (``self.capability``) the strategy is given and each solve's sources are checked
        against."""
        self.capability: Capability = capabilities.check(
            self.method, domain=self.domain.name, order=self.order, medium=medium, multires=multires,
            smoothing=smoothing, resolution=self.resolution != "mesh")

    def _set_smoothness(self, m_value: float, lam_value: float | None) -> None:
        """``self.lam`` (λ in the mesh's units) and ``self.m`` from the checked ``m`` or ``lam``
        (:meth:`_check_capabilities`): λ computed once (0 without a smoothness energy)."""
        self.m = None if lam_value is not None else m_value
        if self.energy is None:
            self.lam = 0.0
        elif lam_value is not None and self._lam_checked:  # checked on the whole mesh (a patch of local rows)
            self.lam = lam_value
        else:  # one weight for surfaces and volumes (mesh.dim); a given λ is at most the weight of the largest m
            weight = smoothness_weight(self.mesh, 1.0 if lam_value is not None else m_value, self.normalization,
                                       self.energy, medium=self.medium, order=self.order)
            self.lam = check_lam(lam_value, weight) if lam_value is not None else weight

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
            or every boundary edge (``docs/sources.md``), resolved once here
            (:func:`~cvxgeodesic.sources.resolve_sources`). With ``order=2`` (P2 squared distance):
            vertices, SurfacePoints and ``"boundary"``.
        callback : callable, optional
            ``callback(iteration, info_dict)`` after every iteration of the convex solve,
            for progress reports: of the structured interior-point solver and of Clarabel
            (``info_dict["solver"] == "clarabel"``; also where ``solver="auto"`` retries
            with it). Keys include ``gap_rel``, ``res_primal``, ``res_dual``, ``pcost``,
            ``dcost``, ``mu``, ``step`` and ``time``. Not called by the baselines.

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
        t0 = time.perf_counter()
        # a curve in a volume, boundary faces on a surface, a cloud's "boundary" (its soup's free edges would pass for
        # one): refused by the solver's cell with the table's reason before any resolution; the resolved kinds after
        self.capability.admit(_named_kinds(sources))
        sset = resolve_sources(self.mesh, sources)
        self.capability.admit(source_kinds(sset))
        source_time = time.perf_counter() - t0  # closest points and curve samples: part of this solve
        with reporting_to(callback):  # Clarabel's iterations too, wherever a strategy runs it
            res = self._strategy.solve(sset, callback=callback)
        cloud = getattr(self.mesh, "cloud", None)
        if cloud is not None:
            self._carry_to_left_out(res, cloud)
            if cloud.denoised:  # the substitution recorded, not only noted
                res.info.extra["denoised"] = {"passes": cloud.denoised, "noise": cloud.noise,
                                              "automatic": cloud.denoised_automatically}
        res.info.setup_time = self.setup_time
        res.info.solve_time += source_time
        res.info.extra["source_time"] = source_time
        if self.medium is not None:  # what the field measures: {"cost": "per-vertex", ...}; the medium: res.field
            res.info.extra.update(self.medium.describe())
        return res

    def _carry_to_left_out(self, res: GeodesicResult, cloud: PointCloud) -> None:
        """On the point cloud whose soup this solver's mesh is, the field carried to the points in no triangle (its
        outliers, line points and isolated points: :meth:`~cvxgeodesic.mesh.pointcloud.PointCloud.reach_left_out`), in
        place, with a note and ``info.extra["left_out_reached"]``."""
        carried, reached = cloud.reach_left_out(res.distance)
        if not reached:
            return
        left = np.flatnonzero(np.isinf(res.distance) & np.isfinite(carried))
        res.distance[left] = carried[left]  # in place: the array keeps its remembered sources (geodesic_path)
        res.info.n_unreachable = int(np.isinf(res.distance).sum())
        res.info.extra["left_out_reached"] = reached
        res.info.notes.append(f"{self.mesh.name}: {reached} point(s) in no triangle (outliers, line points or isolated "
                              "points, left out of the triangles) given the least distance through their nearest "
                              "neighbours (a neighbour's distance plus the straight distance to it)")

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


def geodesic_distance(mesh: MeshLike, *args: Any, sources: Any = None, method: Method | None = None,
                      m: float | None = None, solver: SolverName | None = None, lam: float | None = None,
                      tol: float = DEFAULT_TOL,
                      max_iter: int = 200, normalization: str = "area",
                      order: int | None = None, threads: int | None = None, cost: Any = None, metric: Any = None,
                      resolution: Any = None) -> np.ndarray:
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
        Any mesh :class:`GeodesicSolver` takes (a tetrahedral one too); or ``V``, (n, 3) float vertex
        positions, followed by ``F``, (m, 3) int triangles.
    sources : int or sequence of int
        Source vertex indices (positional after the mesh, or keyword), or surface sources.
    method, m, solver, lam, tol, max_iter, normalization, threads, cost, metric, resolution
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
    solver_obj = GeodesicSolver(mesh, given.get("method"), m=given.get("m", 1.0), lam=lam,
                                solver=given.get("solver", "auto"), tol=tol, max_iter=max_iter,
                                normalization=normalization, order=order, threads=threads, cost=cost, metric=metric,
                                resolution=resolution)  # no estimate: geodesic_distance returns no info
    return solver_obj.solve(given["sources"]).distance


#: The default tolerance of local rows (``distance_matrix(..., max_distance=r)``): see its ``tol``.
LOCAL_ROW_TOL = 1e-5


# the return type follows max_distance: dense full rows without it, sparse local rows with it
@overload
def distance_matrix(mesh: MeshLike, vertices: ArrayLike, method: Method | None = None, m: float = 1.0,
                    solver: SolverName = "auto", progress: bool | None = None, *, lam: float | None = None,
                    tol: float | None = None, max_iter: int = 200, multires: bool | int = False,
                    normalization: str = "area", order: int | None = None, threads: int | None = None,
                    workers: int | None = None, scheduler: Any = None, cost: Any = None, metric: Any = None,
                    max_distance: None = None, checkpoint: str | os.PathLike | None = None,
                    resolution: Any = None) -> np.ndarray: ...
@overload
def distance_matrix(mesh: MeshLike, vertices: ArrayLike, method: Method | None = None, m: float = 1.0,
                    solver: SolverName = "auto", progress: bool | None = None, *, lam: float | None = None,
                    tol: float | None = None, max_iter: int = 200, multires: bool | int = False,
                    normalization: str = "area", order: int | None = None, threads: int | None = None,
                    workers: int | None = None, scheduler: Any = None, cost: Any = None, metric: Any = None,
                    max_distance: float, checkpoint: str | os.PathLike | None = None,
                    resolution: Any = None) -> sp.csr_matrix: ...
@overload
def distance_matrix(mesh: MeshLike, vertices: ArrayLike, method: Method | None = None, m: float = 1.0,
                    solver: SolverName = "auto", progress: bool | None = None, *, lam: float | None = None,
                    tol: float | None = None, max_iter: int = 200, multires: bool | int = False,
                    normalization: str = "area", order: int | None = None, threads: int | None = None,
                    workers: int | None = None, scheduler: Any = None, cost: Any = None, metric: Any = None,
                    max_distance: float | None = None,
                    checkpoint: str | os.PathLike | None = None,
                    resolution: Any = None) -> np.ndarray | sp.csr_matrix: ...


def distance_matrix(mesh: MeshLike, vertices: ArrayLike, method: Method | None = None, m: float = 1.0,
                    solver: SolverName = "auto",
                    progress: bool | None = None, *, lam: float | None = None, tol: float | None = None,
                    max_iter: int = 200, multires: bool | int = False, normalization: str = "area",
                    order: int | None = None, threads: int | None = None, workers: int | None = None,
                    scheduler: Any = None, cost: Any = None, metric: Any = None, max_distance: float | None = None,
                    checkpoint: str | os.PathLike | None = None, resolution: Any = None) -> np.ndarray | sp.csr_matrix:
    """Distance fields from several vertices, one row per vertex, with one :class:`GeodesicSolver`.

    The per-mesh work (operators, energy matrix, symbolic Cholesky analysis) is
    done once; every row is one solve with a single source. A vertex listed
    twice is solved once and its row copied. ``vertices`` may also be a SurfacePoint, a
    SurfaceCurve, ``"boundary"`` or a list of them and ints: one row per item.

    With ``max_distance`` the matrix is sparse and local: each row keeps the distances up to
    ``max_distance`` and is solved on the patch of the mesh around its source, the faces within
    ``1.5 · max_distance`` on the edge graph (:class:`~cvxgeodesic.rows.LocalRows`; docs/performance.md
    "Rows of a distance matrix"), with the whole mesh's smoothness weight.

    With ``checkpoint`` the finished rows are written to that ``.npz`` file as they come (every couple of
    seconds, atomically, and when a row fails or Ctrl-C stops the call); the same call again resumes from
    it, skipping the rows it holds, and returns the whole matrix once it has every row. A checkpoint made
    with other arguments (mesh, sources, method, any option, compared by value: ``m=1`` is ``m=1.0``) is refused,
    and so is one that is damaged (its entries are checked as strictly as a mesh file), not a regular file, not
    owned by this user or writable by others (as ssh treats a key): the error names the file and why, and the
    file is left alone. Checkpoints are written readable by their owner only. A checkpoint that cannot be
    written (a full disk) does not stop the rows: a :class:`~cvxgeodesic.errors.CheckpointWarning` names the
    file and the matrix is still returned.

    With ``workers`` or ``scheduler`` the rows are solved on a Dask cluster
    (``pip install 'cvxgeodesic[cluster]'``; :mod:`cvxgeodesic.rows`): split into contiguous
    chunks, one per worker, each chunk one task with its own solver (the set-up is paid once per
    chunk), the mesh sent to the workers once. The rows are the same solves as in-process.

    Parameters
    ----------
    mesh : TriMesh, TetMesh, tuple (V, F) or (V, T), ...
        Any mesh :class:`GeodesicSolver` takes (a tetrahedral one too, without ``max_distance``).
    vertices : int or (k,) sequence of int
        Source vertex of each row.
    method : str, optional
        See :class:`GeodesicSolver`. Default (None): :data:`DEFAULT_ROW_METHOD` = ``"qclp"`` on every mesh, not the
        one-shot default ``"qcqp-hessian"``: measured side by side (one thread, 4 rows on spot, kitten and bimba,
        ``benchmarks/row_default.py``), ``qclp``'s rows were as accurate against the exact distance (mean relative
        error 2.04 / 1.08 / 0.84 % against 2.16 / 1.13 / 0.91 %) and 1.5-2.3x faster (docs/performance.md).
    m, solver, lam, max_iter, multires, normalization, threads, cost, metric, resolution
        See :class:`GeodesicSolver`. With ``resolution`` every row is solved on the one decimated copy (made once per
        solver: once, or once per chunk on a cluster). On a cluster, ``threads=None`` lets every worker's solver
        follow the worker's environment: ``cpu_count // workers`` threads on a local cluster.
    tol : float, optional
        See :class:`GeodesicSolver`. Default: 1e-8 (the tolerance of every other solve) for full rows,
        :data:`LOCAL_ROW_TOL` = 1e-5 for local rows (``max_distance``), whose patch already makes them an
        approximation of the whole mesh's solve: measured on bimba and kitten (100 rows, QCLP), 1e-5 takes
        ~35 % less time and leaves the mean error within ``max_distance`` against the exact distance
        unchanged to three digits (``benchmarks/matrix.py --tol``; docs/performance.md).
    progress : bool or None
        A progress bar counting rows on stderr: None (default) shows it once the rows have run
        for 2 s (:data:`~cvxgeodesic._verbose.PROGRESS_DELAY`), True from the start, False never.
    workers : int, optional
        Solve on a ``LocalCluster`` of this many worker processes, started for this call and
        closed at the end. Default None: in this process, without Dask.
    scheduler : str or distributed.Client, optional
        Solve on an existing Dask cluster: its scheduler's address (``"tcp://SCHEDULER:8786"``) or a
        connected client; its workers need cvxgeodesic installed (the mesh is sent to them).
        Not together with ``workers``.
    max_distance : float, optional
        Keep the distances up to this one (in the mesh's units, > 0): a sparse matrix of local rows.
        Source vertices only; not with ``multires``, ``cost`` or ``metric``.
    checkpoint : str or os.PathLike, optional
        A ``.npz`` file that keeps the finished rows and resumes a call (see above).

    Returns
    -------
    (k, n) float ndarray, or (k, n) scipy.sparse.csr_matrix with ``max_distance``
        (so typed: ``np.ndarray`` when ``max_distance`` is left out or None, ``csr_matrix`` when it is a number)
        ``D[i, j]`` is the distance of vertex ``j`` from ``vertices[i]``
        (``inf`` where ``j`` is not connected to it). The matrix is not exactly
        symmetric: every row is its own optimization problem. Sparse: the entries are the
        distances ``≤ max_distance``, the source's 0 included as a stored entry; a missing entry
        is farther away.

    Raises
    ------
    SourceError
        ``vertices`` is empty, not integers, or out of range; not vertices with ``max_distance``.
    ParameterError
        ``workers`` is not a positive integer, or both ``workers`` and ``scheduler`` are given;
        ``max_distance`` is not a positive number or comes with ``multires``, ``cost`` or ``metric``;
        ``checkpoint`` is not a writable ``.npz`` path, is not a checkpoint, or was made with other arguments.
    ImportError
        ``workers`` or ``scheduler`` without Dask's ``distributed`` installed.
    ConnectionError
        ``scheduler`` is not a reachable Dask scheduler.

    Examples
    --------
    >>> import cvxgeodesic as cg
    >>> D = cg.distance_matrix(cg.icosphere(2), [0, 5, 9], method="qclp")
    >>> D.shape, float(D[1, 5])
    ((3, 162), 0.0)
    >>> L = cg.distance_matrix(cg.icosphere(3), [0, 5], method="qclp", max_distance=0.5)
    >>> L.shape, L.nnz < 2 * 642, float(L[1].max()) <= 0.5
    ((2, 642), True, True)
    """
    mesh = as_mesh(mesh)
    method = DEFAULT_ROW_METHOD if method is None else method
    if tol is None:
        tol = DEFAULT_TOL if max_distance is None else LOCAL_ROW_TOL
    if workers is not None:
        check_count(workers, "workers", or_none=True)
        if scheduler is not None:
            raise ParameterError("give workers (a local Dask cluster) or scheduler (an existing one), not both")
    options: dict[str, Any] = {"method": method, "m": m, "lam": lam, "solver": solver, "tol": tol, "max_iter": max_iter,
               "multires": multires, "normalization": normalization, "order": order, "threads": threads,
               "cost": cost, "metric": metric, "resolution": resolution}
    if resolution is not None and not _is_mesh_resolution(resolution):  # rows keep no info: no estimate to pay for
        options["estimate_error"] = False
    items, inverse = _matrix_rows(mesh, vertices)
    factory: Any = GeodesicSolver
    if max_distance is not None:
        factory, options = _local_rows(mesh, options, max_distance, items)
    from .rows import RowStore, cluster_rows, fingerprint, solve_rows

    if checkpoint is not None:
        checkpoint = check_output_path(checkpoint, (".npz",))
    store = RowStore(len(items), mesh.n_vertices, sparse=max_distance is not None, path=checkpoint,
                     parameters=fingerprint(mesh, items, options) if checkpoint is not None else None)
    desc = str(method)
    if workers is not None or scheduler is not None:
        cluster_rows(factory, mesh, items, options, store, scheduler=scheduler, workers=workers, progress=progress,
                     desc=desc)
    else:
        solve_rows(factory, mesh, items, options, store, progress=progress, desc=desc)
    return store.matrix(inverse)


def _matrix_rows(mesh: SimplexMesh, vertices: Any) -> tuple[list, np.ndarray]:
    """The distinct sources of ``distance_matrix``'s rows and, for each row asked for, its index among them."""
    from .mesh.locate import CellPoint
    from .sources import BoundaryFaces, SurfaceCurve

    objects = (CellPoint, SurfaceCurve, BoundaryFaces, str)  # points, curves, boundary faces, "boundary"
    if isinstance(vertices, objects) or (isinstance(vertices, list | tuple)
                                         and any(isinstance(v, objects) for v in vertices)):
        items = [vertices] if isinstance(vertices, objects) else list(vertices)
        return items, np.arange(len(items))  # one row per item
    uniq, inverse = np.unique(validate_sources(vertices, mesh.n_vertices, name="vertices", repeats=True),
                              return_inverse=True)
    mesh.check_source_vertices(uniq)  # before any row (local rows never resolve their sources on the mesh)
    return uniq.tolist(), np.asarray(inverse).ravel()


def _named_kinds(sources: Any, *, points: bool = False) -> set[str]:
    """The kinds of source (:data:`~cvxgeodesic.capabilities.SOURCE_KINDS`) that a raw ``sources`` value names by its
    type alone: curves, boundary faces, ``"boundary"`` and, with ``points``, points (a point at a corner resolves to
    a vertex)."""
    from .sources import BoundaryFaces, CellPoint, SurfaceCurve

    items = sources if isinstance(sources, list | tuple) else [sources]
    kinds = {"curve": SurfaceCurve, "boundary faces": BoundaryFaces, **({"point": CellPoint} if points else {})}
    named = {k for k, t in kinds.items() if any(isinstance(s, t) for s in items)}
    return named | ({"boundary"} if any(isinstance(s, str) and s.strip().lower() == "boundary" for s in items)
                    else set())


class _PatchSolver(GeodesicSolver):
    """The solver of one local row's patch: its λ is the whole mesh's scaled by the area ratio, checked once on the
    whole mesh (:func:`~cvxgeodesic.rows._whole_mesh_lambda`). On the patch it can exceed the weight of
    ``m = MAX_M`` of the patch alone, which is no reason to refuse it: the patch's program is the whole one's."""

    _lam_checked = True


def _is_mesh_resolution(value: Any) -> bool:
    """``resolution="mesh"`` in any case (an array or a number is not)."""
    return isinstance(value, str) and value.strip().lower() == "mesh"


def _local_rows(mesh: SimplexMesh, options: dict, max_distance: Any, items: list) -> tuple[Any, dict]:
    """The factory and options of local rows (:class:`~cvxgeodesic.rows.LocalRows`), after their checks: the
    capability table's cell of local rows (a volume, multires, a medium, resolution= and sources other than vertices
    are refused there), checked once for the matrix; each patch's solver checks its own solve."""
    from .rows import LocalRows

    r = check_number(max_distance, "max_distance", low=0, low_open=True)
    given = {"multires": bool(options["multires"]), "cost": options["cost"] is not None,
             "metric": options["metric"] is not None,
             "resolution": options["resolution"] is not None and not _is_mesh_resolution(options["resolution"])}
    method = options["method"]
    key = ALIASES.get(method.lower(), method.lower()) if isinstance(method, str) else None
    if key in ALL_METHODS:  # an unknown name: the solver names the known ones
        medium = "cost" if given["cost"] else "metric" if given["metric"] else "none"
        capabilities.check(key, domain=mesh.domain, local=True, multires=given["multires"], medium=medium,
                         order=2 if given["resolution"] else check_order(options["order"] or 1),
                         resolution=given["resolution"], sources=_named_kinds(items, points=True) | (
                             {"boundary"} if any(isinstance(i, str) for i in items) else set()))  # any word
    rest = {k: v for k, v in options.items() if k not in given}
    rest["resolution"] = "mesh"  # a patch is solved on itself, whatever the domain's default resolution
    return LocalRows, {"max_distance": r, "factory": _PatchSolver, **rest}
