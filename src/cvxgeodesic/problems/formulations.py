"""Assemble the paper's eight convex formulations (Table 1) as :class:`ConicProblem` s, on a surface (triangles)
or inside a solid (tetrahedra): the simplex dimension ``mesh.dim`` is a parameter of every function here.

=================  ===========================  =================
name               constraints                  smoothness energy
=================  ===========================  =================
lclp               LC: |d_i − d_j| ≤ ℓ_ij        none
lcqp-dirichlet     LC                           Dirichlet (eq. 16)
lcqp-laplacian     LC                           Laplacian (eq. 17)
lcqp-hessian       LC  (= QGDF, Cao et al.)     Hessian (eq. 18)
qclp               QC: ‖∇d|_t‖ ≤ 1               none
qcqp-dirichlet     QC                           Dirichlet
qcqp-laplacian     QC                           Laplacian
qcqp-hessian       QC  (recommended)            Hessian
=================  ===========================  =================

Objective: minimize ``E_stretch + λ E_smooth``. Default (normalization
``"area"``): ``E_stretch = −(1/|S|) Σ_i M_i d_i``, the mean of ``d`` over the
surface integrated exactly for the piecewise linear field (``M_i`` a third of
the area around vertex ``i``), and ``λ = m · κ · √|S|`` (:data:`KAPPA`): the
discretization of one continuous problem, so one ``m`` is one rounding measured
on the surface on every triangulation. Normalization ``"paper"``:
``E_stretch = −(c/n) Σ_i d_i`` with ``c = STRETCH_SCALE = 10`` and the paper's
``λ = m · 10² · h / n`` (§4.2.3), whose rounding is a fixed number of edges
wide. Both are scale-equivariant. Measurements: ``docs/method.md``.

Sources (DESIGN §1, "Situation #1"): source vertices are fixed at 0. The exact
field is a cone around a source, steeper than 1 on the source's incident
triangles when measured piecewise linearly, so the QC is dropped there, as in
the paper. Instead of fixing the one-ring to its Euclidean distance (which can
be infeasible next to obtuse triangles), each source-star edge gets the linear
bound ``d_j ≤ d_s + ‖v_j − v_s‖``: the problem stays feasible (``d = 0`` is
always feasible) and bounded, and the maximization drives the one-ring to the
Euclidean distance wherever the other constraints allow it. An edge between two
free vertices whose faces all lack a cone (a corner triangle of an open mesh next
to a source, the stars of neighbouring sources) gets the LC bound
``|d_i − d_j| ≤ l_ij``, which keeps ``d ≤ Dijkstra``. The LC
formulations keep every edge constraint (Lemma 1 then makes LCLP equal to
Dijkstra).

Every formulation bounds the vertices within :data:`NONNEGATIVE_HOPS` edges and within
:data:`NONNEGATIVE_EDGE_RADIUS` mean edge lengths (along edges) of the sources below by 0 from the start, and with a
second-order smoothness energy (Hessian, Laplacian) also those within :data:`NONNEGATIVE_RADIUS` smoothing lengths
(:func:`smoothing_length`, measured along edges): there, and only there, optima went negative.
The source stars carry no cone, so nothing bounds their vertices from below: the smoothing energy flattens the cone's
tip into a dip, −2.6e-4 to −0.51 on beetle, max_planck and the medial-axis bug; QCLP's optimum is not unique on the
medial axis's sheets that meet at a source, −0.76 to −5.2 there (docs/method.md). The dip is as wide as the
rounding, a length on the surface (``(m κ)^(1/3) √|S|``), not a number of edges: unbounded, it reached 1, 5 and 8
edges from five sources on max_planck at 5K, 21K and 84K vertices, and with two edges bounded the 21K mesh still
went negative three edges away and was solved twice (2026-12-03). On request (``nonnegative=True``; the API
re-solves with it when a solution still has negative values, noted in ``info.notes``) every free vertex is bounded
below by 0: bounds everywhere cost the interior-point method 20-35 % more iterations, which is why they are not the
default (docs/dev/performance-log.md, "Negative distances in one solve").

The radius in mean edge lengths (2026-12-06, issue 41; docs/dev/endgame.md, "after"): on camelhead_open, QCLP from
vertex 6104 went down to −5.2e-3 at 25 vertices 3–8 edges from the source but only 0.7–3.3 mean edge lengths
along edges from it (skinny faces, edges of 0.1× the mean at the source), and from 5637 to −4.4e-5 four edges but
0.4 mean edge lengths away; both were solved twice. Bounding the vertices within ``R`` mean edge lengths as well,
6104's optimum went down to −4.2e-3 (R = 1), −1.9e-4 (1.5, one vertex at 1.6), and stayed ≥ 0 from R = 1.75 on.
:data:`NONNEGATIVE_EDGE_RADIUS` = 2.5 is 1.4× that. Its cost, over the end-game sweep's 240 solves on the 14 shared
manifold scans (QCLP and QCQP-Hessian, the same sources side by side): 235 of 238 solves within ±1 iteration of
the hop rule alone, three QCLP solves +2 (each +0 or +1 at R = 2 and 3: the path, not a trend), 3559 → 3568 in all,
the two re-solves gone; the iteration tables of ``tests/test_ipm_regression.py`` move by −1 on two cylinder counts.
R = 2 kept every solve within ±1 and the tables as they were, with a margin of 1.14× over 1.75; R = 3 moved 5 of
the tables' 32 counts (+7 iterations, +2 on grid14's LCQP-Laplacian). The hop rule stays: where a source's edges
are longer than the mean, two edges reach vertices the radius does not (up to 13 on 12 of the 14 scans' sweep
sources, 25 on the medial-axis bug, whose QCLP dips were within two edges).

Vertices in connected components without a source are fixed and reported as
``inf``. Degenerate (zero or near-zero area) faces carry no cone and no energy
term; their edges get the LC constraint instead (:class:`MeshOperators`).

Inside a tetrahedral mesh (``docs/volumes.md``) the same programs hold one dimension up: the field is linear in each
tetrahedron, the cone ``‖B_t d_t‖ ≤ 1`` is an SOC(4), ``|S|`` becomes the volume ``|Ω|`` (the stretch is the mean of
``d`` over the solid, ``λ = m · κ · |Ω|^(1/3)``), and the energies are the Dirichlet and the squared-Laplacian ones
(the curved Hessian energy is a surface notion: its formulations are refused, :mod:`cvxgeodesic.capabilities`). The
sources fix vertices and source faces, and the edges of every tetrahedron without a cone get the edge bounds
(:mod:`.source_rows`); the near-source bounds ``d ≥ 0`` are the surface's, with :func:`smoothing_length`
measured in the volume.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from ..errors import DegenerateFacesWarning, MeshError, warn_user
from ..mesh.simplex import SimplexMesh
from ..mesh.trimesh import DEGENERATE_TOL
from ..operators import check_energy, energy_matrix
from ..operators.lagrange import LagrangeSpace
from ..operators.metric import Medium
from ..sources import SourceSet
from ..validation import check_choice, check_number
from . import _study
from .conic import ConeGroup, ConicProblem, PairInequalities
from .source_rows import source_constraints

FORMULATIONS: dict[str, tuple[str, str | None]] = {
    "lclp": ("lc", None),
    "lcqp-dirichlet": ("lc", "dirichlet"),
    "lcqp-laplacian": ("lc", "laplacian"),
    "lcqp-hessian": ("lc", "hessian"),
    "qclp": ("qc", None),
    "qcqp-dirichlet": ("qc", "dirichlet"),
    "qcqp-laplacian": ("qc", "laplacian"),
    "qcqp-hessian": ("qc", "hessian"),
}
ALIASES = {"qgdf": "lcqp-hessian"}
#: Every formulation bounds the vertices within this many edges of a source (of a source point's or curve's faces)
#: below by 0 (module docstring).
NONNEGATIVE_HOPS = 2
#: ... and the vertices within this many mean edge lengths (of the edges the cones and bounds use, in a medium's
#: lengths) of a source, measured along edges: tiny edges next to a source make a short distance many edges
#: (module docstring: camelhead_open).
NONNEGATIVE_EDGE_RADIUS = 2.5
#: ... and, with a second-order smoothness energy (Hessian, Laplacian), the vertices within this many smoothing lengths
#: (:func:`smoothing_length`) of a source, measured along edges (module docstring).
NONNEGATIVE_RADIUS = 4.0
#: Smallest right-hand side of an edge bound ``|d_i − d_j| ≤ l_ij``, as a fraction of the bounding-box diagonal.
MIN_EDGE_BOUND = 1e-9

#: ``c`` in the paper normalization's ``E_stretch = −(c/n) Σ d_i`` (see module docstring).
STRETCH_SCALE = 10.0
#: Stretch weights per vertex: ``"area"`` is ``−(1/|S|) ∫ d dA`` integrated exactly for the piecewise linear
#: field (barycentric lumped mass); ``"calibrated"`` the uniform weights of the paper normalization. (The uniform
#: weights of the normalization study, ``"mean"`` and ``"sum"``, are study switches: :mod:`.problems._study`.)
STRETCH_WEIGHTS = ("area", "calibrated")
#: Factor on the whole ``"area"`` objective as the backends see it (see :func:`build_problem`).
SOLVER_SCALE = 10.0
#: Smallest stretch weight of a vertex in the ``"area"`` stretch, as a fraction of the mean vertex area.
MIN_STRETCH_WEIGHT = 0.05
#: The normalizations of ``m`` (:func:`smoothness_weight`): ``"area"`` (default), ``"paper"``.
NORMALIZATIONS = ("area", "paper")
#: The energies of second derivatives, whose rounding has the length :func:`smoothing_length`.
SECOND_ORDER_ENERGIES = ("hessian", "laplacian")
#: ``κ`` of ``λ = m · κ · √|S|`` per energy, normalization ``"area"``. Calibrated on bimba (46K faces,
#: source vertex 0) so that ``m = 1`` rounds the ridge as the paper normalization's ``m = 1`` did there
#: (ridge sharpness 0.24, 0.41 of the exact field's; Laplacian 0.241, Dirichlet 0.243); docs/method.md has
#: the sweep and what other values of κ trade.
KAPPA = {"hessian": 3.0e-6, "laplacian": 3.0e-6, "dirichlet": 1.3e-2}
#: ``κ₂`` of ``λ = m · κ₂`` at order 2 (the energies of ``φ = d²``, :mod:`cvxgeodesic.operators.squared_energy`,
#: have the units of the stretch term, so λ is dimensionless); docs/order2.md, "Smoothing at order 2", has the
#: calibration. Changing it changes every smoothed order-2 field: bump
#: :data:`~cvxgeodesic.problems.squared_distance.ORDER2_CACHE_VERSION`.
KAPPA_ORDER2 = {"hessian": 5.0e-7, "laplacian": 5.0e-7, "dirichlet": 5.0e-7}


def stretch_weights(mesh: SimplexMesh, stretch: str = "area", area_ratio: np.ndarray | None = None) -> np.ndarray:
    """Per-vertex weights ``w`` of the stretch term ``E_stretch = −wᵀd``.

    Parameters
    ----------
    mesh : SimplexMesh
    stretch : {"area", "calibrated"}
        ``"area"``: ``w_i = M_i / |Ω|`` with ``M_i`` a third of the area of the faces around vertex ``i`` (a
        quarter of the volume of its tetrahedra): the exact integral of the piecewise linear field, so ``wᵀd`` is
        the mean of ``d`` over the surface (solid), whatever the mesh; floored at :data:`MIN_STRETCH_WEIGHT` of the
        mean. ``"calibrated"``: ``10 / n`` (the paper normalization of this library). Also the study values of
        :data:`cvxgeodesic.problems._study.STRETCH_WEIGHTS`.
    area_ratio : (m,) float ndarray, optional
        With a metric (:attr:`~cvxgeodesic.operators.metric.Medium.area_ratio`): the areas of ``"area"`` are
        measured in it.

    Returns
    -------
    (n,) float ndarray

    Raises
    ------
    MeshError
        ``"area"`` on a mesh of zero area (volume).
    """
    n = mesh.n_vertices
    if stretch == "area":
        measures = mesh.cell_measures if area_ratio is None else mesh.cell_measures * area_ratio
        w = mesh.dim + 1
        mass = np.bincount(mesh.cells.ravel(), weights=np.repeat(measures / w, w), minlength=n)
        total = mass.sum()
        if not total > 0:
            raise MeshError(f"{mesh.name}: the mesh has zero {mesh.reference.words.measure}")
        # A vertex whose cells have (almost) no measure would get (almost) no weight: the optimum is then (almost)
        # not unique there, and the solvers stop anywhere in its feasible range (measured: LCLP 3e-4 of the
        # diagonal off Dijkstra on Thingi10K slivers). The floor changes no vertex of an ordinary mesh.
        floor = MIN_STRETCH_WEIGHT * total / max(int(mesh.referenced.sum()), 1)
        mass = np.where(mesh.referenced, np.maximum(mass, floor), 0.0)
        return mass / mass.sum()
    if stretch in _study.STRETCH_WEIGHTS:
        return np.full(n, _study.stretch_scale(stretch, n))
    check_choice(stretch, "stretch", STRETCH_WEIGHTS, lower=False)
    return np.full(n, STRETCH_SCALE / n)


def canonical_method(method: str) -> str:
    """Lower-case formulation name with aliases resolved; raises ParameterError if unknown."""
    name = check_choice(method, "formulation", [*FORMULATIONS, *ALIASES])
    return ALIASES.get(name, name)


def smoothness_weight(mesh: SimplexMesh, m: float, normalization: str = "area", energy: str = "hessian",
                      medium: Medium | None = None, order: int = 1) -> float:
    """The smoothness weight λ for a multiplier ``m``.

    Parameters
    ----------
    mesh : SimplexMesh
    m : float
        Dimensionless multiplier; ``m = 1`` is the default rounding (docs/method.md).
    normalization : {"area", "paper"}
        ``"area"`` (default): ``λ = m · κ · |Ω|^(1/dim)`` (``|Ω|`` the surface area or the volume, ``κ`` =
        :data:`KAPPA` of the energy), paired with the measure-weighted stretch ``−(1/|Ω|) ∫ d``: the
        discretization of one continuous problem, so one ``m`` means one rounding, measured on the surface (in
        the solid), on every mesh and at every scale. ``"paper"``: the paper's ``λ = m · 10² · h / n`` (§4.2.3;
        ``h`` the mean edge length, ``n`` the vertex count), paired with the uniform stretch ``−(10/n) Σ d_i``:
        its rounding is a fixed number of edges wide.
    energy : {"hessian", "laplacian", "dirichlet"}
        Selects ``κ`` (``"area"`` only); ``"hessian"`` on triangles only.
    medium : Medium, optional
        A travel cost or metric (:mod:`cvxgeodesic.operators.metric`, surfaces): ``|S|`` and ``h`` are then
        measured in it, so that a constant cost ``c`` gives ``c λ``, as the mesh scaled by ``c`` would.
    order : {1, 2}
        ``2``: the weight of the order-2 energies of ``φ = d²``, ``λ = m · κ₂`` (:data:`KAPPA_ORDER2`; dimensionless,
        the same for both normalizations, since ``"paper"`` has no order-2 form).

    Returns
    -------
    float

    Raises
    ------
    ParameterError
        An unknown normalization, or an energy not defined on the mesh's dimension.

    Examples
    --------
    >>> import cvxgeodesic as cg
    >>> sphere = cg.icosphere(3)
    >>> round(cg.smoothness_weight(sphere, 1.0) / sphere.face_areas.sum() ** 0.5, 9)
    3e-06
    >>> round(cg.smoothness_weight(cg.tet_box(2, size=2.0), 1.0, energy="dirichlet") / 1.3e-2, 12)
    2.0
    """
    normalization = check_choice(normalization, "normalization", NORMALIZATIONS)
    if order == 2:
        check_choice(energy, "energy", KAPPA_ORDER2, lower=False)
        return float(m) * KAPPA_ORDER2[energy]
    if normalization == "paper":
        h = mesh.mean_edge_length if medium is None else medium.mean_edge_length
        return float(m) * 100.0 * h / mesh.n_vertices
    check_choice(energy, "energy", KAPPA, lower=False)
    check_energy(mesh, energy)
    measure = mesh.total_measure if medium is None else medium.surface_area
    # the root of the measure (``mesh.reference.measure_root``) is a length on a surface and in a solid alike; on
    # volumes κ keeps the surface values (not calibrated there; measurements in ``docs/volumes.md``)
    return float(m) * KAPPA[energy] * float(mesh.reference.measure_root(measure))


def smoothing_length(ops: MeshOperators, lam: float, stretch: str = "area") -> float:
    """The length over which a second-order smoothness energy rounds the field: ``ℓ = (λ |Ω|^(2/dim) / W)^(1/3)``.

    Rounding a cone's tip (a source) or a crease over a disc of radius ``ℓ`` lowers the stretch term by about
    ``(W / |S|) ℓ³`` (``W`` the sum of the stretch weights, spread over the surface area ``|S|``) and saves an energy
    ``λ ∫ |∇²d|² dA`` of order ``λ`` (scale-free for second derivatives): the two balance at ``ℓ``. Under the area
    normalization ``ℓ = (m κ)^(1/3) √|S|`` (0.0144 √|S| at ``m = 1``): a length on the surface, whatever the
    triangulation. Measured 2026-12-03 without bounds: the optimum's dip below 0 reached 1.4 ℓ, 2.6 ℓ and 2.4 ℓ
    from five sources on max_planck at 5K, 21K and 84K vertices, 1.2 ℓ from a source of the medial-axis bug.
    In a solid a ball of radius ``ℓ`` lowers the stretch by ``(W / |Ω|) ℓ⁴`` and saves ``λ ℓ / |Ω|^(1/3)`` (the
    volume's Laplacian energy is divided by ``|Ω|^(1/3)``, :func:`~cvxgeodesic.operators.energy_matrix`):
    ``ℓ³ = λ |Ω|^(2/3) / W``, ``(m κ)^(1/3) |Ω|^(1/3)`` under the area normalization, again a length in the solid.

    Parameters
    ----------
    ops : MeshOperators
    lam : float
        The smoothness weight λ of the problem (in the units of ``ops.mesh``).
    stretch : str
        The stretch weights (:func:`stretch_weights`).

    Returns
    -------
    float
    """
    mesh = ops.mesh
    measures = mesh.cell_measures if ops.medium is None else mesh.cell_measures * ops.medium.area_ratio
    measure = float(measures.sum())  # in the medium's normalized units, as the edge lengths the radius is measured in
    total = float(ops.stretch_weights(stretch).sum())
    return float(np.cbrt(lam * measure ** (2.0 / mesh.dim) / total)) if total > 0 else 0.0


@dataclass
class MeshOperators:
    """Per-mesh data shared by every solve: gradient blocks and energy matrices (built lazily), on triangles or
    tetrahedra.

    Degenerate cells (:meth:`~cvxgeodesic.mesh.simplex.SimplexMesh.degenerate_cells`: zero or near-zero measure,
    needles, caps, slivers, specks) are left out of the cone constraints and of the smoothness energies: their
    gradient has entries of order ``1 / altitude`` and would make both numerically singular. Every edge of such a
    cell gets the edge constraint ``|d_i − d_j| ≤ ℓ_ij`` instead (valid for the exact distance, and it keeps every
    vertex bounded and the QC fields below Dijkstra). Their measure is negligible by definition; measured on a grid
    with a zero-area split, QCLP moved by at most 0.2 % of the bounding-box diagonal against the unsplit grid, the
    Laplacian and Hessian fields by up to 2.3 % (they see one vertex more). A
    :class:`~cvxgeodesic.errors.DegenerateFacesWarning` says how many cells were left out.

    Parameters
    ----------
    mesh : SimplexMesh
    degenerate_tol : float
        Threshold of :meth:`~cvxgeodesic.mesh.simplex.SimplexMesh.degenerate_cells` (default
        :data:`~cvxgeodesic.mesh.trimesh.DEGENERATE_TOL`; 0 drops only cells of exactly zero measure).
    medium : Medium, optional
        A travel cost or metric on a surface (:mod:`cvxgeodesic.operators.metric`): the gradient blocks are
        multiplied by its :attr:`~cvxgeodesic.operators.metric.Medium.face_transforms` (the cones then bound
        ``‖∇d‖_{M⁻¹} ≤ c``), the edge lengths, the stretch's areas and the energies are measured in it (the
        Hessian energy only through its mean area ratio, :func:`~cvxgeodesic.operators.energy_matrix`).

    Attributes
    ----------
    degenerate : (k,) bool ndarray
        The cells left out.
    degenerate_edges : (q,) int64 ndarray
        Indices into ``mesh.edges`` of the edges of degenerate cells.
    notes : list of str
        One line per substitution made while building the operators (degenerate cells left out, a manifold cover
        or the planar Hessian energy), copied into every ``SolveInfo``.

    Raises
    ------
    MeshError
        Every cell of the mesh is degenerate.
    """

    mesh: SimplexMesh
    degenerate_tol: float = DEGENERATE_TOL
    medium: Medium | None = None

    def __post_init__(self):
        self._energies: dict[str, sp.csc_matrix] = {}
        self._stretch: dict[str, np.ndarray] = {}
        self.notes: list[str] = []
        mesh = self.mesh
        tol = self.degenerate_tol
        check_number(tol, "degenerate_tol", low=0, high=1, high_open=True)
        self.degenerate = np.zeros(mesh.n_cells, dtype=bool)
        self.degenerate[mesh.degenerate_cells(tol)] = True
        n_bad = int(self.degenerate.sum())
        words = mesh.reference.words
        word, counted = words.one, words.many
        if n_bad == mesh.n_cells:
            raise MeshError(
                f"{mesh.name}: all {n_bad} {counted} are degenerate (zero or near-zero "
                f"{words.measure}); the convex formulations need proper {counted}; use "
                "method='dijkstra' on this mesh"
            )
        self._face_metric = None
        if self.medium is not None:  # per-face transforms and area ratios of the energies' faces
            keep = ~self.degenerate
            self._face_metric = (self.medium.face_transforms[keep], self.medium.area_ratio[keep])
        self._energy_cells = None if not n_bad else ~self.degenerate
        self.degenerate_edges = np.unique(mesh.cell_edges[self.degenerate]).astype(np.int64)
        if n_bad:
            f = int(np.flatnonzero(self.degenerate)[0])
            message = (
                f"{mesh.name}: {n_bad} degenerate {counted} (smallest altitude below {tol:g} of the {word}'s longest "
                f"edge or of the mean edge length; first: {word} {f} {mesh.cells[f].tolist()}) are left out of the "
                "cone constraints and energies; their edges are constrained by |d_i - d_j| <= edge length instead"
            )
            warn_user(message, DegenerateFacesWarning)
            self.notes.append(message)

    @functools.cached_property
    def gradient_blocks(self) -> np.ndarray:
        """(k, dim, dim + 1) float ndarray: the gradient rows of the order-1
        :class:`~cvxgeodesic.operators.lagrange.LagrangeSpace` (:func:`~cvxgeodesic.operators.gradient_blocks`), zero
        on degenerate cells."""
        # the order-1 element's gradient rows, constant in a cell (gradient_blocks, zero on the degenerate cells)
        space = LagrangeSpace(self.mesh, 1, degenerate_tol=self.degenerate_tol)
        blocks = space.cell_cones(np.eye(space.reference.n_corners)[:1])[1][:, 0]
        if self.medium is not None:
            with np.errstate(invalid="ignore"):
                blocks = np.einsum("tij,tjk->tik", self.medium.face_transforms, blocks)
        blocks[self.degenerate] = 0.0
        return blocks

    def energy(self, name: str, *, analyse=None) -> sp.csc_matrix:
        """(n, n) csc_matrix of a named energy, assembled on the non-degenerate cells (cached).

        ``analyse`` (used when the energy is built, see :func:`~cvxgeodesic.operators.hessian_energy_matrix`)
        gives the PSD check of the Hessian energy the caller's symbolic analysis.

        Raises
        ------
        ParameterError
            An energy not defined on the mesh's dimension (the Hessian energy on tetrahedra).
        """
        if name not in self._energies:
            self._energies[name] = energy_matrix(self.mesh, name, self.notes, analyse=analyse,
                                                 face_metric=self._face_metric, cells=self._energy_cells)
        return self._energies[name]

    def stretch_weights(self, stretch: str = "area") -> np.ndarray:
        """(n,) float ndarray: :func:`stretch_weights` of the mesh (cached)."""
        if stretch not in self._stretch:
            ratio = None if self.medium is None else self.medium.area_ratio
            self._stretch[stretch] = stretch_weights(self.mesh, stretch, ratio)
        return self._stretch[stretch]

    @property
    def edge_lengths(self) -> np.ndarray:
        """(e,) float ndarray: length of each edge of ``mesh.edges``, in the medium when there is one."""
        return self.mesh.edge_lengths if self.medium is None else self.medium.edge_lengths


class _Inequalities:
    """Rows ``c₀ d[v₀] + c₁ d[v₁] ≤ r`` collected in order (the order is part of the problem the solvers see)."""

    def __init__(self) -> None:
        self._v: list[np.ndarray] = [np.zeros((0, 2), dtype=np.int64)]
        self._c: list[np.ndarray] = [np.zeros((0, 2))]
        self._r: list[np.ndarray] = [np.zeros(0)]

    def add(self, vertices: np.ndarray, coeffs, rhs: np.ndarray) -> None:
        self._v.append(np.asarray(vertices, dtype=np.int64).reshape(-1, 2))
        self._c.append(np.tile(np.asarray(coeffs, dtype=np.float64), (len(self._v[-1]), 1)))
        self._r.append(np.asarray(rhs, dtype=np.float64))

    def both_ways(self, edges: np.ndarray, ell: np.ndarray, pick: np.ndarray) -> None:
        """``|d_i − d_j| ≤ l_ij`` for the picked edges (a mask): all ``+`` rows, then all ``−`` rows."""
        edges, ell = edges[pick], ell[pick]
        self.add(edges, [1.0, -1.0], ell)
        self.add(edges, [-1.0, 1.0], ell)

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return (np.ascontiguousarray(np.vstack(self._v), dtype=np.int64), np.ascontiguousarray(np.vstack(self._c)),
                np.concatenate(self._r))


def _qc_constraints(ops: MeshOperators, sc, fixed_mask: np.ndarray, ell: np.ndarray, ineq: _Inequalities):
    """The QC formulations' cones (cells, gradient blocks) and the edge bounds where cells carry none, added to
    ``ineq``."""
    mesh = ops.mesh
    cells, E = mesh.cells, mesh.edges
    cell_free = ~fixed_mask[cells].all(axis=1)
    # cells incident to a source (and the cells of point and curve sources, source_rows.py) carry no cone
    keep = cell_free & ~sc.no_cone & ~ops.degenerate
    if mesh.reference.coneless_cell_edges:
        # every edge of a tetrahedron without a cone (next to a source, a point's, degenerate) gets |d_i - d_j| <=
        # l_ij: a tetrahedron's cone does not cover all the edges its neighbours share with it
        lc = np.unique(mesh.cell_edges[cell_free & ~keep])
        ineq.both_ways(E[lc], ell[lc], ~fixed_mask[E[lc]].all(axis=1))
        return np.ascontiguousarray(cells[keep]), np.ascontiguousarray(ops.gradient_blocks[keep])
    # d_j - d_s <= |v_j - v_s| on the source stars; with d_s fixed at 0 this is a bound on d_j
    ineq.add(np.column_stack([sc.star_other, sc.star_source]), [1.0, -1.0], sc.star_rhs)
    # degenerate faces carry no cone: their edges get |d_i - d_j| <= l_ij (both directions)
    Ed, ld = E[ops.degenerate_edges], ell[ops.degenerate_edges]
    ineq.both_ways(Ed, ld, ~fixed_mask[Ed].all(axis=1))
    # A cone on a face bounds the derivative along each of its edges, |d_i - d_j| <= l_ij. An edge between two free
    # vertices whose faces all carry no cone (faces incident to a source, point- and curve-source faces) would be
    # unconstrained: on an open mesh's corner triangle, or between two sources' stars, the maximization then pushed a
    # vertex above the edge-graph distance (found by hypothesis: 0.559 against Dijkstra's 0.5 on a 15-vertex grid with
    # two sources), breaking d <= Dijkstra (Theorem 2). Those edges get the LC bound instead; on an ordinary mesh
    # there are none. An edge with a fixed end is a source-star edge (bounded above) or lies outside the problem.
    covered, candidate = np.zeros(len(E), dtype=bool), np.zeros(len(E), dtype=bool)
    covered[mesh.cell_edges[keep].ravel()] = True
    covered[ops.degenerate_edges] = True
    candidate[mesh.cell_edges[cell_free].ravel()] = True
    ineq.both_ways(E, ell, candidate & ~covered & ~fixed_mask[E].any(axis=1))
    return np.ascontiguousarray(cells[keep]), np.ascontiguousarray(ops.gradient_blocks[keep])


def _within(mesh: SimplexMesh, ell: np.ndarray, seeds: np.ndarray, radius: float) -> np.ndarray:
    """(n,) bool ndarray: the vertices whose shortest edge path to ``seeds`` (edge lengths ``ell``) is at most
    ``radius`` (Dijkstra stopped at ``radius``: the cost follows the ball, not the mesh)."""
    n = mesh.n_vertices
    if not len(seeds) or not radius > 0:
        return np.zeros(n, dtype=bool)
    E = mesh.edges
    graph = sp.csr_matrix((np.r_[ell, ell], (np.r_[E[:, 0], E[:, 1]], np.r_[E[:, 1], E[:, 0]])), shape=(n, n))
    dist = dijkstra(graph, directed=True, indices=np.unique(seeds), min_only=True, limit=radius)
    return np.isfinite(dist)


def build_problem(
    ops: MeshOperators,
    sources: np.ndarray | SourceSet,
    method: str,
    lam: float,
    *,
    stretch: str = "area",
    nonnegative: bool = False,
) -> ConicProblem:
    """Assemble one formulation for given sources, on a surface or inside a solid.

    Parameters
    ----------
    ops : MeshOperators
    sources : (k,) int64 ndarray or SourceSet
        Validated source vertices, or any source set of :func:`cvxgeodesic.sources.resolve_sources`
        (points, curves, the boundary, source faces; their constraints are in
        :func:`cvxgeodesic.problems.source_rows.source_constraints`).
    method : str
        A name of :data:`FORMULATIONS` (aliases allowed) defined on the mesh's dimension
        (:func:`capabilities.methods_for`).
    lam : float
        Smoothness weight λ (ignored by lclp / qclp).
    stretch : {"area", "calibrated"}
        Weights of ``E_stretch`` (:func:`stretch_weights`): ``−(1/|S|) ∫ d dA``
        (default, normalization ``"area"``), ``−(10/n) Σd`` (normalization
        ``"paper"``); the study values of :mod:`cvxgeodesic.problems._study` reproduce the normalization study in
        ``docs/method.md``.
    nonnegative : bool
        Add the bounds ``d_i ≥ 0`` for every free vertex.

    Returns
    -------
    ConicProblem
        Over the vertex values; one :class:`ConeGroup` of SOC(dim + 1) cones on cells (QC), pair inequalities.

    Raises
    ------
    ParameterError
        An unknown method, one not defined on the mesh's dimension, or λ negative or not finite.
    """
    mesh = ops.mesh
    n = mesh.n_vertices
    name = canonical_method(method)
    constraint, energy = FORMULATIONS[name]
    check_number(lam, "smoothness weight lambda", low=0)

    # fixed vertices, cone-free faces and source bounds (source_rows.py)
    sc = source_constraints(ops, sources, min_edge_bound=MIN_EDGE_BOUND)
    unreachable = ~(mesh.connected_to(sc.anchors) & mesh.referenced)
    fixed_mask = unreachable.copy()
    fixed_mask[sc.fixed] = True
    fixed_values = np.zeros(n)

    # The "area" objective is solved times SOLVER_SCALE: its terms are then as large as the paper normalization's
    # (-(10/n) Σd), the scale the backends' absolute tolerances were tuned at (measured: at scale 1 Clarabel left
    # 1.8e-5 of the diagonal between a 20-vertex mesh and its 10x copy). ConicProblem.objective_scale undoes it.
    objective_scale = SOLVER_SCALE if stretch == "area" else 1.0
    q = np.where(fixed_mask, 0.0, -objective_scale * ops.stretch_weights(stretch))

    # Edge bounds |d_i - d_j| <= l_ij with l_ij at rounding level (near-duplicate vertices that exact welding
    # keeps, e.g. 6e-16 on thingi_65395) are equalities in disguise: their slacks start at ~0 and the duals
    # grow to 1e13, which ruins the interior-point method's dual residual. A floor far below any tolerance
    # (MIN_EDGE_BOUND x the bounding-box diagonal) keeps them inequalities.
    ell = np.maximum(ops.edge_lengths, MIN_EDGE_BOUND * mesh.bbox_diagonal)
    ineq = _Inequalities()
    if constraint == "qc":
        cone_vertices, cone_blocks = _qc_constraints(ops, sc, fixed_mask, ell, ineq)
    else:
        d = mesh.dim
        cone_vertices, cone_blocks = np.zeros((0, d + 1), dtype=np.int64), np.zeros((0, d, d + 1))
        ineq.both_ways(mesh.edges, ell, ~fixed_mask[mesh.edges].all(axis=1))
    # point and curve sources: d_v <= (a surface path to the source)
    ineq.add(np.column_stack([sc.bound_vertices] * 2), [1.0, 0.0], sc.bound_rhs)
    if nonnegative:
        # d_i >= 0 holds for the exact distance; without it maximizing the sum can push a few vertices of folded
        # or self-intersecting meshes (and strongly smoothed coarse fields) below zero. Not everywhere by default: the
        # bounds are inactive on ordinary meshes but cost the interior-point method 30-50 % more iterations
        # (2026-12-02: spot 11 -> 16, lucy_20k 14 -> 21, kitten 13 -> 17, qcqp-hessian)
        bounded = ~fixed_mask
    else:
        bounded = _within(mesh, np.ones(len(mesh.edges)), sc.anchors, NONNEGATIVE_HOPS) & ~fixed_mask  # edge hops
        bounded |= _within(mesh, ell, sc.anchors, NONNEGATIVE_EDGE_RADIUS * float(ell.mean())) & ~fixed_mask
        if energy in SECOND_ORDER_ENERGIES and lam > 0:
            radius = NONNEGATIVE_RADIUS * smoothing_length(ops, lam, stretch)
            bounded |= _within(mesh, ell, sc.anchors, radius) & ~fixed_mask
    free_v = np.flatnonzero(bounded)
    ineq.add(np.column_stack([free_v, free_v]), [-1.0, 0.0], np.zeros(len(free_v)))
    ineq_vertices, ineq_coeffs, ineq_rhs = ineq.arrays()

    P = None
    if energy is not None and lam > 0:
        P = sp.csc_matrix(2.0 * objective_scale * lam * ops.energy(energy))

    return ConicProblem(
        n=n, P=P, q=q,
        cones=[ConeGroup.norm_bound(cone_vertices, cone_blocks)],
        ineq=PairInequalities(ineq_vertices, ineq_coeffs, ineq_rhs),
        fixed_mask=fixed_mask, fixed_values=fixed_values, unreachable=unreachable,
        method=name, objective_scale=objective_scale,
    )
