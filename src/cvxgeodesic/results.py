"""Result types of a solve: :class:`SolveInfo`, :class:`GeodesicResult` and the :class:`Field` protocol of the
field it holds (a leaf module: NumPy only).

Every solve strategy (:mod:`cvxgeodesic.strategies`) returns a :class:`GeodesicResult`; both types are
re-exported unchanged by :mod:`cvxgeodesic.api` and the package top level.
"""

from __future__ import annotations

import weakref
from dataclasses import asdict, dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np

__all__ = ["Field", "GeodesicResult", "SolveInfo", "remember_sources", "remembered_sources"]

# fields computed from point, curve or boundary sources remember them, so that a plain array returned by
# geodesic_distance still leads geodesic_path to the source points (id -> (weak reference, source set))
_FIELD_SOURCES: dict[int, tuple] = {}


def remember_sources(distance: np.ndarray, ss: Any) -> None:
    """Record that the array ``distance`` was computed from ``ss`` (for as long as the array lives)."""
    key = id(distance)
    try:
        ref = weakref.ref(distance)
    except TypeError:  # pragma: no cover - not weak-referenceable
        return
    _FIELD_SOURCES[key] = (ref, ss)
    weakref.finalize(distance, _FIELD_SOURCES.pop, key, None)


def remembered_sources(distance: Any) -> Any:
    """The source set :func:`remember_sources` recorded for this very array, if any."""
    entry = _FIELD_SOURCES.get(id(distance))
    if entry is None or entry[0]() is not distance:
        return None
    return entry[1]


@runtime_checkable
class Field(Protocol):
    """A distance field on a mesh, answered at points of its cells: what :attr:`GeodesicResult.field` holds.

    Implemented by :class:`~cvxgeodesic.operators.linear_field.LinearField` (order 1 and the baselines: the
    piecewise-linear interpolant of the vertex values), :class:`~cvxgeodesic.operators.lagrange.LagrangeField` and
    :class:`~cvxgeodesic.operators.lagrange.SplitLagrangeField` (order 2: ``√φ`` of the squared distance), and
    :class:`~cvxgeodesic.mesh.transfer.ProjectedField` (an adapted solve: a field of another mesh of the surface).
    :func:`~cvxgeodesic.paths.distance_at` and :func:`~cvxgeodesic.paths.geodesic_path` ask it.

    Attributes
    ----------
    mesh : SimplexMesh
        The mesh whose cells the queries name (``n`` vertices, ``k`` cells of ``dim + 1`` corners). Typed ``Any``
        here: this module sits below the mesh classes.
    medium : Medium or None
        The travel cost or metric the field measures (:mod:`cvxgeodesic.operators.metric`); None: Euclidean.
    vertex_distance : (n,) float ndarray
        The field at the vertices (``inf`` where no source is reachable): ``GeodesicResult.distance``.

    Examples
    --------
    An order-2 field is exact on a flat mesh: inside a triangle of the unit square, from the corner vertex 0 (the
    origin), it is the point's distance from the origin, and its gradient the unit vector away from it. Pictures,
    files and paths (:func:`~cvxgeodesic.plot_field`, :func:`~cvxgeodesic.save_distance`,
    :func:`~cvxgeodesic.geodesic_path`) take a result or its field as well as vertex values.

    >>> import numpy as np, cvxgeodesic as cg
    >>> mesh = cg.grid_plane(4)
    >>> res = cg.GeodesicSolver(mesh, "qclp", order=2).solve(0)
    >>> isinstance(res.field, cg.Field)
    True
    >>> centre = mesh.V[mesh.F[0]].mean(axis=0)  # (1/6, 1/12, 0)
    >>> print(res.field.distance_at([0], [[1 / 3, 1 / 3, 1 / 3]]).round(6), round(float(np.linalg.norm(centre)), 6))
    [0.186339] 0.186339
    >>> print(res.field.gradient_at([0], [[1 / 3, 1 / 3, 1 / 3]]).round(6))
    [[0.894427 0.447214 0.      ]]
    """

    @property
    def mesh(self) -> Any: ...

    @property
    def medium(self) -> Any: ...

    @property
    def vertex_distance(self) -> np.ndarray: ...

    def distance_at(self, cells: Any, bary: Any) -> np.ndarray:
        """(p,) float ndarray: the field at points ``bary`` (p, dim + 1) of ``cells`` (p,)."""
        ...

    def gradient_at(self, cells: Any, bary: Any) -> np.ndarray:
        """(p, 3) float ndarray: the field's (Euclidean) gradient there, in world coordinates; zero where the field
        is 0 around a source, NaN in cells of zero measure or without a finite value."""
        ...


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
        Seconds spent on this solve, the resolution of its sources included (``extra["source_time"]``).
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
        Details, by who produced the field (every time in seconds, each a part of ``solve_time``):

        - every solve: ``threads`` (the thread limit it ran under); ``source_time`` (the sources resolved
          against the mesh: closest surface points of positions, a curve's samples; on the first search of a mesh
          object also the build of its closest-point tree, about 0.1 s per 70K faces);
        - the interior-point solver (``solver == "ipm"``): ``program_time`` (the problem turned into blocks),
          ``assembly_time``, ``factor_time``, ``linear_solve_time``, ``other_time`` (their sum is ``total_time``),
          ``analyze_time`` (the once-per-mesh symbolic analysis, *not* part of ``solve_time``), ``new_analyses``,
          ``backend`` (PARDISO, CHOLMOD or SciPy), ``start`` (the starting point), ``refinement_steps``,
          ``correctors``, ``correctors_accepted``, ``max_correctors``, ``corrector_escalations``,
          ``regularized`` (factorizations retried with a raised diagonal), ``mu``, ``gap_abs``; with
          ``status == "almost_optimal"`` also ``stopped`` and ``best_iteration``;
        - Clarabel: ``clarabel_setup_time``, ``clarabel_solve_time``; after a retry ``ipm_failure`` (the
          interior-point status that caused it);
        - the ``d ≥ 0`` re-solve: ``negative_min``, ``resolved_nonnegative``;
        - ``order=2``: ``order``, ``n_dofs``, ``n_cones``, ``rounds`` (cutting-plane rounds), ``round_iterations``
          (iterations of each round's solve; ``iterations`` is their sum); the field itself is
          :attr:`GeodesicResult.field`;
        - ``multires``: ``multires`` (the coarse mesh and the transfer), ``coarse``;
        - ``resolution=``: ``adapted`` (the solve mesh's counts and times; ``error_estimate``, made from
          ``estimate_differences`` to the fields on the coarser and finer copies of ``estimate_faces``; the keys are
          listed in docs/adapted.md, "What info records"), ``solve_mesh`` (the copy);
        - baselines: the library's own parameters (e.g. ``t_coef`` of the heat method).
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
    field : Field
        The field inside the cells (values and gradients at any point; its medium), ``distance`` at the vertices.
    source_set : SourceSet or None
        The normalized sources (:func:`cvxgeodesic.sources.resolve_sources`) when they were not all
        vertices; ``None`` otherwise.
    """

    distance: np.ndarray
    info: SolveInfo
    sources: np.ndarray
    field: Field
    source_set: Any = None

    def __post_init__(self) -> None:
        if self.source_set is not None:  # geodesic_path(mesh, result.distance, ...) then knows the sources
            remember_sources(self.distance, self.source_set)
