"""The convex formulations inside a tetrahedral mesh (order 1), as :class:`ConicProblem` s (issue 26).

The surface formulations carry over unchanged, one dimension up: the field is linear in each tetrahedron,
its gradient ``B_t d[T[t]]`` (:func:`~cvxgeodesic.operators.tet.tet_gradient_blocks`), and

=================  ====================================  =======================================
name               constraints                           smoothness energy
=================  ====================================  =======================================
lclp               LC: ``|d_i − d_j| ≤ ℓ_ij`` per edge    none (equals Dijkstra on the edges)
lcqp-dirichlet     LC                                    Dirichlet
lcqp-laplacian     LC                                    squared Laplacian
qclp               QC: ``‖B_t d_t‖ ≤ 1``, an SOC(4)        none
qcqp-dirichlet     QC                                    Dirichlet
qcqp-laplacian     QC                                    squared Laplacian
=================  ====================================  =======================================

The curved Hessian energy is a surface notion: its formulations, fast marching and the exact (MMP) method do
not apply to volumes (:func:`check_tet_method` says so and names those that do).

Objective: minimize ``E_stretch + λ E_smooth`` with, for normalization ``"area"`` (the default; on a volume it
normalizes by the volume), ``E_stretch = −(1/|Ω|) Σ_i M_i d_i``, the mean of ``d`` over the solid integrated
exactly for the piecewise-linear field (``M_i`` a quarter of the volume of the tetrahedra around vertex ``i``),
and ``λ = m · κ · |Ω|^{1/3}`` (:data:`TET_KAPPA`). The energies are dimensionless
(``Σ_t vol_t ‖∇d‖² / |Ω|`` and ``dᵀ L M⁻¹ L d / |Ω|^{1/3}``), so one ``m`` is one rounding, relative to the
solid's size, on every tetrahedralization and at every scale (tested). Normalization ``"paper"`` keeps the
uniform stretch ``−(10/n) Σ d_i`` and ``λ = m · 10² · h / n``.

Sources (:mod:`cvxgeodesic.sources_tet`): source vertices and the vertices of source faces are fixed at 0;
tetrahedra next to them whose interpolated local field is steeper than 1 carry no cone; the edges of every
tetrahedron without a cone (those, degenerate ones, the tetrahedron of a source point) get the edge bounds.
Degenerate tetrahedra (:meth:`~cvxgeodesic.mesh.tetmesh.TetMesh.degenerate_tets`) carry no cone and no energy
term, recorded in the notes. Vertices in components without a source are fixed and reported as ``inf``.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .errors import DegenerateFacesWarning, MeshError, ParameterError
from .formulations import (
    KAPPA,
    MIN_EDGE_BOUND,
    MIN_STRETCH_WEIGHT,
    NORMALIZATIONS,
    SOLVER_SCALE,
    STRETCH_SCALE,
    _Inequalities,
)
from .mesh.tetmesh import DEGENERATE_TET_TOL, TetMesh
from .operators.tet import (
    tet_dirichlet_energy_matrix,
    tet_gradient_blocks,
    tet_laplacian_energy_matrix,
    tet_mass_matrix,
)
from .solvers.problem import ConeGroup, ConicProblem, PairInequalities
from .sources_tet import TetSources, tet_source_constraints
from .validation import check_choice, check_number

__all__ = ["TET_BASELINE_METHODS", "TET_FORMULATIONS", "TET_KAPPA", "TET_METHODS", "TET_ORDER2_METHODS",
           "TetOperators", "build_tet_problem", "check_tet_method", "tet_smoothness_weight", "tet_stretch_weights"]

TET_FORMULATIONS: dict[str, tuple[str, str | None]] = {
    "lclp": ("lc", None),
    "lcqp-dirichlet": ("lc", "dirichlet"),
    "lcqp-laplacian": ("lc", "laplacian"),
    "qclp": ("qc", None),
    "qcqp-dirichlet": ("qc", "dirichlet"),
    "qcqp-laplacian": ("qc", "laplacian"),
}
#: The baselines on tetrahedra (:mod:`cvxgeodesic.baselines.tet`).
TET_BASELINE_METHODS = ("dijkstra", "heat")
#: Every method a tetrahedral mesh takes.
TET_METHODS = (*TET_FORMULATIONS, *TET_BASELINE_METHODS)
#: The formulations with an order-2 program on tetrahedra (:mod:`cvxgeodesic.formulations_tet_p2`).
TET_ORDER2_METHODS = ("qclp",)
#: ``κ`` of ``λ = m · κ · |Ω|^{1/3}`` per energy: the surface values (:data:`~cvxgeodesic.formulations.KAPPA`),
#: not calibrated on volumes; with the dimensionless energies above they round by a comparable fraction of the
#: domain's size. Measurements in ``docs/volumes.md``.
TET_KAPPA = {"dirichlet": KAPPA["dirichlet"], "laplacian": KAPPA["laplacian"]}


def check_tet_method(method: str) -> str:
    """The lower-case name of a method that applies to tetrahedral meshes; ParameterError naming those that do.

    Raises
    ------
    ParameterError
        Not a string, or a method without a volume counterpart (the curved Hessian formulations, ``"fmm"``,
        ``"exact"``) or unknown.
    """
    if not isinstance(method, str):
        raise ParameterError(f"method must be a string, got {type(method).__name__}")
    name = {"qgdf": "lcqp-hessian"}.get(method.lower(), method.lower())
    if name not in TET_METHODS:
        why = ("the curved Hessian energy is defined on surfaces" if "hessian" in name
               else "it is a surface algorithm" if name in ("fmm", "exact") else "unknown method")
        raise ParameterError(f"method {method!r} does not apply to tetrahedral meshes ({why}); on a volume use one "
                             f"of {', '.join(TET_METHODS)}")
    return name


def tet_stretch_weights(mesh: TetMesh, stretch: str = "area", tets: np.ndarray | None = None) -> np.ndarray:
    """Per-vertex weights ``w`` of the stretch term ``E_stretch = −wᵀd``.

    Parameters
    ----------
    mesh : TetMesh
    stretch : {"area", "calibrated", "mean", "sum"}
        ``"area"`` (the volume normalization): ``w_i = M_i / |Ω|``, the lumped mass (a quarter of the volume of
        each tetrahedron around vertex ``i``), floored at :data:`~cvxgeodesic.formulations.MIN_STRETCH_WEIGHT` of
        the mean so that vertices of slivers stay determined; the others are uniform, as on surfaces.
    tets : (k,) bool ndarray, optional
        Tetrahedra whose volume counts (default: every one of nonzero volume).

    Returns
    -------
    (n,) float ndarray
    """
    n = mesh.n_vertices
    if stretch == "area":
        mass = tet_mass_matrix(mesh, tets=tets).diagonal()
        total = mass.sum()
        if not total > 0:
            raise MeshError(f"{mesh.name}: the mesh has zero volume")
        floor = MIN_STRETCH_WEIGHT * total / max(int(mesh.referenced.sum()), 1)
        mass = np.where(mesh.referenced, np.maximum(mass, floor), 0.0)
        return mass / mass.sum()
    check_choice(stretch, "stretch", ("area", "calibrated", "mean", "sum"), lower=False)
    return np.full(n, {"calibrated": STRETCH_SCALE / n, "mean": 1.0 / n, "sum": 1.0}[stretch])


def tet_smoothness_weight(mesh: TetMesh, m: float, normalization: str = "area", energy: str = "laplacian") -> float:
    """The smoothness weight λ on a tetrahedral mesh: ``m · κ · |Ω|^{1/3}`` (``"area"``) or ``m · 10² · h / n``
    (``"paper"``).

    Examples
    --------
    >>> from cvxgeodesic.mesh.tet_generate import tet_box
    >>> tet_smoothness_weight(tet_box(2, size=2.0), 1.0, energy="dirichlet") / tet_smoothness_weight(
    ...     tet_box(2), 1.0, energy="dirichlet")
    2.0
    """
    normalization = check_choice(normalization, "normalization", NORMALIZATIONS)
    if normalization == "paper":
        return float(m) * 100.0 * mesh.mean_edge_length / mesh.n_vertices
    check_choice(energy, "energy", TET_KAPPA, lower=False)
    return float(m) * TET_KAPPA[energy] * float(np.cbrt(mesh.total_volume))


@dataclass
class TetOperators:
    """Per-mesh data of the order-1 programs: degenerate tetrahedra, gradient blocks, energies (built lazily).

    Degenerate tetrahedra carry no cone and no energy term; their edges get the edge bounds instead (valid for
    the exact distance). A :class:`~cvxgeodesic.errors.DegenerateFacesWarning` and a note say how many.

    Parameters
    ----------
    mesh : TetMesh
    degenerate_tol : float
        Threshold of :meth:`TetMesh.degenerate_tets`.

    Attributes
    ----------
    degenerate : (k,) bool ndarray
    blocks : (k, 3, 4) float ndarray
        Gradient blocks, zero on degenerate tetrahedra.
    notes : list of str

    Raises
    ------
    MeshError
        Every tetrahedron is degenerate.
    """

    mesh: TetMesh
    degenerate_tol: float = DEGENERATE_TET_TOL

    def __post_init__(self):
        mesh = self.mesh
        check_number(self.degenerate_tol, "degenerate_tol", low=0, high=1, high_open=True)
        self.notes: list[str] = []
        self.degenerate = np.zeros(mesh.n_tets, dtype=bool)
        self.degenerate[mesh.degenerate_tets(self.degenerate_tol)] = True
        n_bad = int(self.degenerate.sum())
        if n_bad == mesh.n_tets:
            raise MeshError(f"{mesh.name}: all {n_bad} tetrahedra are degenerate (flat or tiny); the convex "
                            "formulations need proper tetrahedra; use method='dijkstra' on this mesh")
        if n_bad:
            t = int(np.flatnonzero(self.degenerate)[0])
            message = (f"{mesh.name}: {n_bad} degenerate tetrahedra (smallest altitude below {self.degenerate_tol:g} "
                       f"of the longest edge or of the mean edge length; first: tet {t} {mesh.T[t].tolist()}) are "
                       "left out of the cones and energies; their edges are constrained by |d_i - d_j| <= edge "
                       "length instead")
            warnings.warn(message, DegenerateFacesWarning, stacklevel=3)
            self.notes.append(message)
        with np.errstate(divide="ignore", invalid="ignore"):
            blocks = tet_gradient_blocks(mesh)
        blocks[self.degenerate] = 0.0
        self.blocks = blocks
        self._energies: dict[str, sp.csc_matrix] = {}
        self._stretch: dict[str, np.ndarray] = {}

    def energy(self, name: str) -> sp.csc_matrix:
        """(n, n) csc_matrix of ``"dirichlet"`` or ``"laplacian"`` on the proper tetrahedra, dimensionless (cached)."""
        if name not in self._energies:
            keep = ~self.degenerate
            if name == "dirichlet":
                Q = tet_dirichlet_energy_matrix(self.mesh, tets=keep)
            elif name == "laplacian":
                Q = tet_laplacian_energy_matrix(self.mesh, tets=keep) / np.cbrt(self.mesh.volumes[keep].sum())
            else:
                raise ParameterError(f"energy {name!r} does not apply to tetrahedral meshes; use 'dirichlet' or "
                                     "'laplacian'")
            self._energies[name] = sp.csc_matrix(Q)
        return self._energies[name]

    def stretch_weights(self, stretch: str = "area") -> np.ndarray:
        """(n,) float ndarray: :func:`tet_stretch_weights` over the proper tetrahedra (cached)."""
        if stretch not in self._stretch:
            self._stretch[stretch] = tet_stretch_weights(self.mesh, stretch, ~self.degenerate)
        return self._stretch[stretch]


def build_tet_problem(ops: TetOperators, src: TetSources, method: str, lam: float, *, stretch: str = "area",
                      nonnegative: bool = False) -> ConicProblem:
    """Assemble one formulation on a tetrahedral mesh for given sources.

    Parameters
    ----------
    ops : TetOperators
    src : TetSources
        From :func:`~cvxgeodesic.sources_tet.resolve_tet_sources` on ``ops.mesh`` (or a mesh with the same
        tetrahedra).
    method : str
        A key of :data:`TET_FORMULATIONS`.
    lam : float
        Smoothness weight λ in the mesh's units (ignored by lclp and qclp).
    stretch : {"area", "calibrated", "mean", "sum"}
    nonnegative : bool
        Add ``d_i ≥ 0`` for every free vertex.

    Returns
    -------
    ConicProblem
        Over the vertex values; one :class:`ConeGroup` of SOC(4) cones on tetrahedra (QC), pair inequalities.
    """
    mesh = ops.mesh
    n, T, E = mesh.n_vertices, mesh.T, mesh.edges
    if method not in TET_FORMULATIONS:
        check_tet_method(method)
        raise ParameterError(f"{method!r} is a baseline, not a convex formulation")
    constraint, energy = TET_FORMULATIONS[method]
    if not np.isfinite(lam) or lam < 0:
        raise ParameterError(f"smoothness weight lambda must be finite and >= 0, got {lam}")
    floor = MIN_EDGE_BOUND * mesh.bbox_diagonal
    sc = tet_source_constraints(mesh, ops.blocks, ops.degenerate, src, floor)
    unreachable = ~(mesh.connected_to(sc.anchors) & mesh.referenced)
    fixed_mask = unreachable.copy()
    fixed_mask[sc.fixed] = True
    objective_scale = SOLVER_SCALE if stretch == "area" else 1.0
    q = np.where(fixed_mask, 0.0, -objective_scale * ops.stretch_weights(stretch))
    ell = np.maximum(mesh.edge_lengths, floor)
    ineq = _Inequalities()
    if constraint == "qc":
        tet_free = ~fixed_mask[T].all(axis=1)
        keep = tet_free & ~sc.no_cone & ~ops.degenerate
        cone_T, cone_B = T[keep], ops.blocks[keep]
        # the edges of every tetrahedron without a cone (next to a source, a point's, degenerate)
        lc_edges = np.unique(mesh.tet_edges[tet_free & ~keep])
    else:
        cone_T, cone_B = np.zeros((0, 4), dtype=np.int64), np.zeros((0, 3, 4))
        lc_edges = np.arange(len(E))
    lc_edges = lc_edges[~fixed_mask[E[lc_edges]].all(axis=1)]
    ineq.both_ways(E[lc_edges], ell[lc_edges])
    if sc.bound_vertices.size:
        ineq.add(np.column_stack([sc.bound_vertices] * 2), [1.0, 0.0], sc.bound_rhs)
    if nonnegative:
        free_v = np.flatnonzero(~fixed_mask)
        ineq.add(np.column_stack([free_v, free_v]), [-1.0, 0.0], np.zeros(len(free_v)))
    ineq_vertices, ineq_coeffs, ineq_rhs = ineq.arrays()
    P = None
    if energy is not None and lam > 0:
        P = sp.csc_matrix(2.0 * objective_scale * lam * ops.energy(energy))
    return ConicProblem(
        n=n, P=P, q=q, cones=[ConeGroup.norm_bound(cone_T, cone_B)],
        ineq=PairInequalities(ineq_vertices, ineq_coeffs, ineq_rhs),
        fixed_mask=fixed_mask, fixed_values=np.zeros(n), unreachable=unreachable, method=method,
        objective_scale=objective_scale,
    )
