"""The order-2 program: P2 elements for the *squared* geodesic distance (``order=2``), as a :class:`ConicProblem`.

The unknown is ``φ = d²`` in the continuous piecewise-quadratic space: one value per
vertex and one per edge midpoint. ``|∇√φ| ≤ 1`` is the same as ``|∇φ|² ≤ 4φ``, which is
a second-order cone in ``(φ, ∇φ)``::

    ‖(∇φ, φ − 1)‖ ≤ φ + 1      ⇔      |∇φ|² ≤ 4φ

Maximizing ``∫φ`` under that constraint with ``φ = 0`` at the sources has ``d²`` as its
maximizer in the continuum (``√φ`` is 1-Lipschitz and vanishes at the sources, so
``√φ ≤ d``). On a flat region ``d²`` is a quadratic polynomial, which P2 represents
exactly, so flat distances come out exact on triangles of any shape.

The same holds inside a solid (a :class:`~cvxgeodesic.mesh.tetmesh.TetMesh`, the 10-node P2 tetrahedron, SOC(5)
cones): a solid is flat, so where the source is visible ``d² = |x − s|²`` is reproduced exactly whatever the
tetrahedra's shape. One builder, :class:`P2Builder`, makes both programs; the simplex dimension is the mesh's.

Discretization (choices and measurements in ``docs/order2.md``):

* the cone is imposed at sample points of every cell, with the cone centred near the expected ``φ``
  (``‖(√a ∇φ, φ − a)‖ ≤ φ + a`` is the same cone for every ``a > 0``): on a curved face its three edge midpoints;
  on a flat face its three corners (:data:`DEFAULT_SAMPLES`); in a tetrahedron its ten nodes;
* surfaces only: on *flat* faces (where ``d²`` is exactly quadratic) one :class:`BernsteinEdgeCones` cone per edge:
  with the corner cones it holds ``|∇φ|² ≤ 4φ`` on the whole face, and it is tight on the squared distance to any
  point, so flat regions come out exact in one solve; at a source vertex's edges and next to a line of sources the
  edge midpoints are sampled instead. Elsewhere (those faces; tetrahedra between their node samples) the
  strategy's cutting planes close the gap (a cone where ``|∇φ|² − 4φ`` exceeds a tolerance in a flat cell,
  :func:`~cvxgeodesic.operators.lagrange.violations`, exact, and the problem re-solved);
* the objective is the mean of ``φ`` with lumped weights (``A/6`` per node of a face, ``vol/10`` per node of a
  tetrahedron; on faces also the consistent P2 weights, 0 at corners and ``A/3`` at midpoints, ``weights="p2"``);
* a source vertex ``s`` gets ``φ_s = 0`` and zero derivative at ``s`` along each of its edges to a non-source
  vertex (``4 φ_mid − φ_j = 0``), which is ``∇φ(s) = 0`` in every incident cell without redundant rows; the
  midpoint of a *source edge* (:func:`source_edges`: joining two source vertices, or an edge of a source face) is 0;
  an edge joining two vertices of a wall through a solid is no source edge: its midpoint stays free;
* cones whose sample lies on sources only (where the rows make ``φ`` and ``∇φ`` vanish) are left out: they sit at
  their apex and would leave the program without a strictly feasible point;
* a source point inside a cell, on a facet or on an edge is inserted as a vertex
  (:class:`~cvxgeodesic.mesh.split.SplitMesh`, by the strategy; imposing ``φ(p) = 0``, ``∇φ(p) = 0`` on the
  unsplit face measured less accurate, docs/order2.md);
* the equalities of two unknowns (the zero derivative along a source-star edge) are substituted into the cones
  (:func:`eliminate_pair_equalities`), so the program keeps the cell-clique pattern;
* a degenerate cell (:meth:`SimplexMesh.degenerate_cells`) gets no cones; the 1-D cone ``(∂φ/∂s)² ≤ 4φ`` along each
  of its edges (endpoints and midpoint) bounds its DOFs whatever its shape; the midpoint of an edge shorter than
  :data:`MIN_EDGE` of the diagonal is tied to the mean of its ends;
* surfaces only: a travel cost or metric (``medium``) and the smoothness energies of ``φ`` (``energy``, ``lam``);
* non-manifold edges need nothing special: the edge DOF is shared by all its cells.

Distances at vertices are ``√max(φ, 0)``; :class:`~cvxgeodesic.operators.lagrange.LagrangeField` evaluates the field
inside cells. The space and its operators are in :mod:`cvxgeodesic.operators.lagrange`, the cutting-plane loop and
the solve in :mod:`cvxgeodesic.strategies.order2`.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from .. import capabilities
from ..errors import DegenerateFacesWarning, MeshError, ParameterError, warn_user
from ..mesh.simplex import CELL_EDGES
from ..operators.lagrange import SAMPLES, LagrangeSpace, edge_basis, sample_points
from ..operators.metric import Medium
from ..operators.squared_energy import P2Energy, p2_energy
from ..solvers.problem import ConeGroup, ConicProblem, Equalities, PairInequalities
from ..validation import check_number

__all__ = ["DEFAULT_SAMPLES", "DEFAULT_VOLUME_SAMPLES", "DEFAULT_WEIGHTS", "ORDER2_CACHE_VERSION", "BernsteinEdgeCones",
           "P2Builder", "P2Program", "bernstein_edge_cones", "eliminate_pair_equalities", "source_edges"]

#: Where the cone is imposed on triangles: "flat-bernstein" = the three corners and the three
#: :class:`BernsteinEdgeCones` on flat faces (:attr:`LagrangeSpace.flat_cells`), the three edge midpoints on the
#: others (since 2026-12-02: fandisk 4.1 → 1.1 s, thingi_32770 13 → 3.8 s, no cutting-plane round on the
#: development set, the 53 coarse CAD meshes' median error 0.974 → 0.972 %; docs/order2.md); "flat-nodes" = all six
#: nodes on flat faces, no edge cones (before).
#: Midpoints only on curved faces, measured 2026-12-01 against exact MMP, source 0, mean relative error all nodes →
#: flat-nodes: bimba 0.22 → 0.11 %, bunny 0.099 → 0.058 %, lucy_20k 0.34 → 0.15 %, dragon_20k 0.62 → 0.32 %, spot
#: 0.25 → 0.15 %; the 53 coarse CAD meshes: median ratio to P1 qclp 0.216 → 0.204, median error 0.85 → 0.95 %
#: (29 better, 24 worse; docs/order2.md); flat meshes unchanged (all their faces are flat).
DEFAULT_SAMPLES = "flat-bernstein"
#: ... and in tetrahedra: every node of every (flat) cell, the cutting planes between them.
DEFAULT_VOLUME_SAMPLES = "flat-nodes"
#: Objective weights (:meth:`LagrangeSpace.weights`; docs/order2.md has the measurement behind the choice).
DEFAULT_WEIGHTS = "lumped"
#: Edges shorter than this fraction of the bounding-box diagonal get no 1-D cone (their DOF is tied linearly).
MIN_EDGE = 1e-9
#: Version of the order-2 fields, for caches keyed on the inputs only (``benchmarks/report_common.py``): bump it
#: whenever a change moves an order-2 result beyond the solver tolerance (formulation, samples, weights, defaults),
#: so that fields cached by older code are recomputed instead of silently reused. 1: 2026-12-02 (first version;
#: the fields of the 2026-12-01 defaults, midpoints on curved faces). 2: 2026-12-02 (the one solver; cutting planes
#: at every local maximum, stopped at a relative violation of 1e-5, warm-started: flat-face fields move by up to
#: ~1e-6 of the largest distance). 3: 2026-12-02 (the Bernstein edge cones on flat faces: CAD fields move by up to
#: ~1e-2 of the largest distance, flat ones by solver rounding). Still 3 after the one builder of both dimensions
#: (2026-12-03): the surface fields of the tests' cases bit-identical, or within 2e-14 where cutting planes ran.
ORDER2_CACHE_VERSION = 3


@dataclass
class P2Program:
    """One order-2 program and what turns its solution back into ``φ`` on every DOF.

    Attributes
    ----------
    problem : ConicProblem
        Over the P2 DOFs (vertices, then edge midpoints), the equalities of two unknowns substituted.
    eliminated : tuple of (r,) int ndarray and (r, n) csr_matrix
        ``x[elim] = M @ x`` restores the substituted DOFs from a solution.
    unreachable_vertices : (n_vertices,) bool ndarray
        Vertices in components without a source.
    notes : list of str
        The substitutions the builder made (degenerate faces, ...).
    objective_constant : float
        ``λ c`` of the smoothness energy ``λ(φᵀQφ + 2gᵀφ + c)``, left out of :attr:`problem`'s objective.
    has_edge_cones : bool
        Whether the program holds :class:`BernsteinEdgeCones`.
    """

    problem: ConicProblem
    eliminated: tuple[np.ndarray, sp.csr_matrix]
    unreachable_vertices: np.ndarray
    notes: list[str]
    objective_constant: float = 0.0
    has_edge_cones: bool = False

    def restore(self, x: np.ndarray) -> np.ndarray:
        """The full ``φ`` from a solution ``x`` of :attr:`problem`."""
        elim, M = self.eliminated
        x = np.array(x, dtype=float)
        x[elim] = M @ x
        return x


def _cone_rows(val: np.ndarray, grad: np.ndarray, dim: int) -> tuple[np.ndarray, np.ndarray]:
    """``G, h`` with ``h − G x = (φ + 1, ∇φ, φ − 1)`` (SOC(dim + 2)): val (p, n_local), grad (p, r ≤ dim, n_local)."""
    p = val.shape[0]
    G = np.zeros((p, dim + 2, val.shape[1]))
    G[:, 0] = -val
    G[:, 1:1 + grad.shape[1]] = -grad
    G[:, dim + 1] = -val
    h = np.zeros((p, dim + 2))
    h[:, 0], h[:, dim + 1] = 1.0, -1.0
    return G, h


def source_edges(mesh, vertices: np.ndarray, facets: np.ndarray | None = None) -> np.ndarray:
    """(e,) bool ndarray over ``mesh.edges``: the edges whose midpoint is 0 (no derivative row along them): those
    joining two source vertices, and the edges of source facets.

    An edge joining two vertices of a source wall *through* a solid is no such edge unless both ends are vertex
    sources: pass the wall as ``facets``, not its vertices as ``vertices``. (A surface's ``"boundary"`` passes its
    vertices: every edge joining two of them is a source edge there.)

    Parameters
    ----------
    mesh : TriMesh or TetMesh
    vertices : (s,) int ndarray
        Vertex sources (points inserted as vertices included).
    facets : (f, dim) int ndarray, optional
        Source facets: boundary edges of a surface, faces of a solid's wall.
    """
    E = mesh.edges
    is_src = np.zeros(mesh.n_vertices, dtype=bool)
    is_src[np.asarray(vertices, dtype=np.int64)] = True
    out = is_src[E[:, 0]] & is_src[E[:, 1]]
    if facets is not None and len(facets):
        n = np.int64(mesh.n_vertices)
        F = np.sort(np.asarray(facets, dtype=np.int64), axis=1)
        pairs = np.concatenate([F[:, [i, j]] for i, j in itertools.combinations(range(F.shape[1]), 2)])
        keys = np.unique(pairs @ np.array([n, 1]))
        out |= np.isin(E @ np.array([n, 1]), keys)
    return out


class P2Builder:
    """Per-mesh part of the order-2 program (everything that does not depend on the sources), on triangles or
    tetrahedra.

    The surface-only parts are options: the :class:`BernsteinEdgeCones` (``samples="flat-bernstein"``, the surface
    default), the weights other than ``"lumped"``, a ``medium`` and a smoothness ``energy`` raise a
    :class:`~cvxgeodesic.errors.ParameterError` on tetrahedra.

    Parameters
    ----------
    mesh : TriMesh or TetMesh
        Already scaled to unit size by the caller.
    samples : str, optional
        "flat-bernstein" (:data:`DEFAULT_SAMPLES`, triangles), "flat-nodes" (all nodes of flat cells, the midpoints
        of the others; the default on tetrahedra, where every proper cell is flat), or a name of
        :data:`~cvxgeodesic.operators.lagrange.SAMPLES` (on every cell, no edge cones). With a ``medium``
        "flat-bernstein" is "flat-nodes": the edge cones' tangent is the Euclidean ``2I``.
    weights : {"lumped", "p2"}, optional
        Objective weights (:meth:`LagrangeSpace.weights`); default :data:`DEFAULT_WEIGHTS`.
    medium : Medium, optional
        Triangles only: a travel cost or metric on ``mesh`` (:mod:`cvxgeodesic.operators.metric`): every cone bounds
        ``|∇φ|²_{M⁻¹} ≤ 4c²φ`` with the medium at its sample point (:class:`LagrangeSpace`), a degenerate face's 1-D
        cones take the derivative along the edge's length in the medium, and Dijkstra (cone centres, start field)
        runs on the edge lengths in the medium.
    energy : {"hessian", "laplacian", "dirichlet"}, optional
        Triangles only: smoothness energy of ``φ`` (:func:`~cvxgeodesic.operators.squared_energy.p2_energy`); None: none
        (``qclp``). Not with a ``medium``: the energies vanish on the squared *Euclidean* distance of flat regions
        (Hessian ``2I``), which is not the exact field in a medium.
    lam : float
        Its weight λ (dimensionless: the energy has the units of the mean of ``φ``); 0: no energy.

    Attributes
    ----------
    space : LagrangeSpace
        Of order 2.
    energy : P2Energy or None
        The smoothness energy when ``energy`` is given and ``lam > 0``.
    notes : list of str
        Substitutions made for every program of the mesh (degenerate cells).
    bernstein : BernsteinEdgeCones
        The flat faces' edge cones (none unless ``samples="flat-bernstein"``).
    cone_replaced : (k,) bool ndarray
        The sampled cones (flat faces' edge midpoints) that the edge cones replace: kept only on an edge at a source
        vertex, or for every edge when two sources share an edge (:meth:`build`).
    """

    def __init__(self, mesh, samples: str | None = None, weights: str | None = None, medium: Medium | None = None,
                 energy: str | None = None, lam: float = 0.0):
        self.dim = dim = int(mesh.dim)
        samples = (DEFAULT_SAMPLES if dim == 2 else DEFAULT_VOLUME_SAMPLES) if samples is None else samples
        self._check(samples, medium, energy, lam)
        self.mesh = mesh
        self.space = sp_ = LagrangeSpace(mesh, 2, medium)
        self.w = sp_.weights(DEFAULT_WEIGHTS if weights is None else weights)
        self.lam = float(lam) if energy is not None else 0.0
        self.energy_name = energy
        self.energy: P2Energy | None = p2_energy(sp_, energy) if energy is not None and lam > 0 else None
        if samples == "flat-bernstein" and medium is not None:
            # the tangent in bernstein_edge_cones is taken at the Euclidean Hessian 2I
            samples = "flat-nodes"
        good = np.flatnonzero(~sp_.degenerate)
        flat_cells = np.zeros(0, dtype=np.int64)
        if samples in ("flat-nodes", "flat-bernstein"):
            flat = sp_.flat_cells[good]
            flat_cells = good[flat]
            # with Bernstein edge cones the flat faces' midpoint samples stand in for the edge cones at sources only
            groups = [(flat_cells, sample_points("nodes", dim)), (good[~flat], sample_points("midpoints", dim))]
        else:
            groups = [(good, sample_points(samples, dim))]
        parts = []
        for cells, bary in groups:
            val, grad = sp_.cell_cones(bary)
            parts.append(_cone_rows(np.tile(val, (cells.size, 1)), grad[cells].reshape(-1, dim, val.shape[1]), dim))
        self.notes: list[str] = []
        Ge, he, e_cell, e_samples = self._degenerate_edge_cones()
        self.G = np.concatenate([*[g for g, _ in parts], Ge])
        self.h = np.concatenate([*[h for _, h in parts], he])
        self.cone_cell = np.concatenate([*[np.repeat(f, b.shape[0]) for f, b in groups], e_cell]).astype(np.int64)
        # each cone's barycentric point (for dropping the cones on sources, :func:`_on_sources`)
        self.cone_bary = np.concatenate([*[np.tile(b, (f.size, 1)) for f, b in groups], e_samples])
        self.bernstein = bernstein_edge_cones(sp_, flat_cells if samples == "flat-bernstein" else flat_cells[:0])
        # the midpoint samples a Bernstein edge cone replaces (kept on edges at a source, where it is dropped)
        self.cone_replaced = np.zeros(self.cone_cell.size, dtype=bool)
        if samples == "flat-bernstein":
            self.cone_replaced[:flat_cells.size * 6] = np.tile([False] * 3 + [True] * 3, flat_cells.size)

    def _check(self, samples: str, medium: Medium | None, energy: str | None, lam: float) -> None:
        """ParameterError for a bad option, or one the capability table refuses (:func:`capabilities.check`: a
        smoothness energy with a medium; either on tetrahedra), or the edge cones on tetrahedra."""
        check_number(lam, "smoothness weight lambda", low=0)
        if samples not in SAMPLES and samples not in ("flat-nodes", "flat-bernstein"):
            raise ParameterError(f"samples must be 'flat-bernstein', 'flat-nodes' or one of {SAMPLES}, "
                                 f"got {samples!r}")
        capabilities.check(f"qcqp-{energy}" if energy is not None and lam > 0 else "qclp", dim=self.dim, order=2,
                           medium="none" if medium is None else "metric")
        if self.dim == 3 and samples == "flat-bernstein":
            raise ParameterError("the order-2 program on tetrahedra takes no samples='flat-bernstein' (surfaces only)")

    def _degenerate_edge_cones(self):
        """The 1-D cones ``(dφ/ds)² ≤ 4φ`` along each edge of a degenerate cell (each edge once, in one of its
        cells), at its ends and midpoint: ``(G, h, cell, bary)``."""
        mesh, sp_, dim = self.mesh, self.space, self.dim
        deg = np.flatnonzero(sp_.degenerate)
        n_loc, n_e = sp_.cell_dofs.shape[1], sp_.cell_edges.shape[1]
        ids, first = np.unique(sp_.cell_edges[deg].ravel(), return_index=True)
        owner, local = deg[first // n_e], first % n_e
        ok = mesh.edge_lengths[ids] > MIN_EDGE * max(mesh.bbox_diagonal, 1e-300)
        ids, owner, local = ids[ok], owner[ok], local[ok]
        a, b = CELL_EDGES[dim][local, 0], CELL_EDGES[dim][local, 1]
        t = np.array([0.0, 0.5, 1.0])
        Nt, dNt = edge_basis(t)
        r = np.arange(ids.size)
        cols = np.column_stack([a, dim + 1 + local, b])  # along the edge from corner a to corner b: its local DOFs
        val, grd = np.zeros((3, ids.size, n_loc)), np.zeros((3, ids.size, 1, n_loc))
        eb = np.zeros((3, ids.size, dim + 1))
        for j in range(3):  # the edge's ends and midpoint
            # dφ/ds along the edge's length (in the medium: its rate of length per unit t at the sample)
            L = mesh.edge_lengths[ids] if sp_.medium is None else sp_.medium.edge_speed(owner, a, b, t[j])
            val[j, r[:, None], cols] = Nt[j]
            grd[j, r[:, None], 0, cols] = dNt[j] / L[:, None]
            eb[j, r, a], eb[j, r, b] = 1 - t[j], t[j]
        Ge, he = _cone_rows(val.reshape(-1, n_loc), grd.reshape(-1, 1, n_loc), dim)
        if deg.size:
            word = "face(s)" if dim == 2 else "tetrahedra"
            note = (f"{deg.size} degenerate {word} carry no cones at order 2; their {ids.size} edge(s) get the 1-D "
                    "cone (dφ/ds)² ≤ 4φ instead")
            self.notes.append(note)
            warn_user(f"{mesh.name}: {note}", DegenerateFacesWarning)
        return Ge, he, np.tile(owner, 3), eb.reshape(-1, dim + 1)

    def _source_rows(self, is_src: np.ndarray) -> sp.csr_matrix:
        """Zero derivative along every edge from a source vertex ``s`` to a non-source ``j``:
        ``4 φ_mid − φ_j − 3 φ_s = 0`` with ``φ_s = 0`` (``∇φ(s) = 0`` in every cell at ``s`` without redundant
        rows), as an (r, n_dofs) matrix."""
        n = self.mesh.n_vertices
        E = self.mesh.edges
        one = np.flatnonzero(is_src[E[:, 0]] ^ is_src[E[:, 1]])
        far = np.where(is_src[E[one, 0]], E[one, 1], E[one, 0])
        rows = np.repeat(np.arange(one.size), 2)
        cols = np.column_stack([n + one, far]).ravel()
        vals = np.tile([4.0, -1.0], one.size)
        return sp.csr_matrix((vals, (rows, cols)), shape=(one.size, self.space.n_dofs))

    def _tie_loose_midpoints(self, dofs, G, c, E, fixed):
        """A free midpoint DOF in no cone and no equality (the edge of a degenerate cell too short for a 1-D cone,
        :data:`MIN_EDGE`) would be unbounded: it is tied to the mean of its edge's ends, ``φ_m = (φ_a + φ_b)/2``, its
        cost moved onto them. Returns ``(c, fixed, (elim, M))`` with ``x[elim] = M @ x``."""
        n_v, n = self.mesh.n_vertices, self.space.n_dofs
        used = np.zeros(n, dtype=bool)
        used[dofs[np.abs(G).max(axis=1) > 0]] = True
        used[sp.csr_matrix(E).indices] = True
        loose = np.flatnonzero(~used[n_v:] & ~fixed[n_v:]) + n_v
        ends = self.mesh.edges[loose - n_v]
        c, fixed = c.copy(), fixed.copy()
        np.add.at(c, ends.ravel(), np.repeat(0.5 * c[loose], 2))
        c[loose] = 0.0
        fixed[loose] = True
        c[fixed] = 0.0
        M = sp.csr_matrix((np.full(2 * loose.size, 0.5), (np.repeat(np.arange(loose.size), 2), ends.ravel())),
                          shape=(loose.size, n))
        return c, fixed, (loose, M)

    def build(self, vsrc: np.ndarray, zero_edges: np.ndarray | None = None,
              extra: tuple[np.ndarray, np.ndarray] | None = None, eliminate: bool = True, edge_cones: bool = True,
              guess: np.ndarray | None = None) -> P2Program:
        """The program for a set of source vertices.

        Parameters
        ----------
        vsrc : (s,) int ndarray
            Vertices where ``φ = 0``: vertex sources, inserted points (source points are inserted as vertices
            first, by the caller), the vertices of source faces.
        zero_edges : (e,) bool ndarray, optional
            :func:`source_edges`: the edges whose midpoint is 0 (no derivative row along them); default the edges
            joining two vertices of ``vsrc``.
        extra : tuple (cells (p,) int ndarray, bary (p, dim + 1) float ndarray), optional
            Additional cone sample points (the cutting planes, :func:`~cvxgeodesic.operators.lagrange.violations`).
        eliminate : bool
            Substitute the equalities of two unknowns (:func:`eliminate_pair_equalities`); False keeps them as rows
            of ``E`` (the interior-point solver then solves them through its Schur complement: the same optimum,
            ``p`` more triangular solves per factorization).
        edge_cones : bool
            False: the flat faces keep their midpoint samples instead of the :class:`BernsteinEdgeCones` (the
            strategy's fallback when the edge cones leave no feasible or solvable program).
        guess : (n_dofs,) float ndarray, optional
            The structured solver's starting field (the previous cutting-plane round's); default the squared
            Dijkstra distance at the vertices and the squared mean of its ends at the midpoints.

        Returns
        -------
        P2Program

        Raises
        ------
        MeshError
            Every cell is degenerate.
        """
        mesh, space = self.mesh, self.space
        vsrc = np.asarray(vsrc, dtype=np.int64)
        if mesh.n_cells == 0 or np.all(space.degenerate):
            one = "face" if self.dim == 2 else "tetrahedron"
            raise MeshError(f"{mesh.name}: every {one} is degenerate; order 2 needs at least one proper {one}")
        n, E = mesh.n_vertices, mesh.edges
        is_src = np.zeros(n, dtype=bool)
        is_src[vsrc] = True
        if zero_edges is None:
            zero_edges = is_src[E[:, 0]] & is_src[E[:, 1]]
        reach_v = mesh.connected_to(vsrc) & mesh.referenced
        reach_v[vsrc] = True
        reach = np.concatenate([reach_v, reach_v[E[:, 0]] & reach_v[E[:, 1]]])
        fixed = ~reach
        fixed[vsrc] = True
        # a source edge's midpoint is 0 (the zero-derivative rows at both ends would give it; as an E row of one
        # unknown it left its cone columns in place)
        fixed[n + np.flatnonzero(zero_edges)] = True
        # sources joined by an edge form a curve, whose squared distance is not a point's (Hessian 2nnᵀ, not 2I):
        # the edge cones would hold the field back there, so the sampled cones and the cutting planes take over
        point_like = not zero_edges.any() and edge_cones
        Emat = self._source_rows(is_src)
        # fixed DOFs leave the equalities; drop rows that are then empty
        Emat = (Emat @ sp.diags((~fixed).astype(float))).tocsr()
        Emat.eliminate_zeros()
        Emat = Emat[np.diff(Emat.indptr) > 0]
        # the mean of φ, not its integral: the backends' absolute gap tolerance then means the same on any size
        c = -self.w / max(self.w.sum(), 1e-300)
        c[fixed] = 0.0
        dv = None
        if vsrc.size:
            dv = dijkstra(space.adjacency, indices=vsrc, min_only=True)
            dv = np.where(np.isfinite(dv), dv, 0.0)
            if guess is None:
                # a starting field for the structured solver: squared distance at the vertices, squared mean at
                # the midpoints (on an edge at a source vertex that is ℓ²/4 = φ_j / 4, so it meets the
                # zero-derivative equalities). Measured: fandisk 30 → 24 iterations, bug_surface 27 → 20 (with the
                # edge cones, 2026-12-02), the jittered L prism (n = 4, 8) 25 → 19 and 39 → 27; with the corner and
                # midpoint samples alone, a needle strip's solve from it had stopped 7.6e-5 of the largest distance
                # away from the optimum (the samples barely determine it)
                guess = np.concatenate([dv**2, (0.5 * (dv[E[:, 0]] + dv[E[:, 1]]))**2])
        cf, Gk, hk, n_s, hb = self._cones(is_src, zero_edges, extra, reach, point_like, dv)
        dofs = space.cell_dofs[cf]
        # a fixed DOF is 0: its columns do not matter, but zero them so that backends need not know
        Gk = np.where(fixed[dofs][:, None, :], 0.0, Gk)
        if eliminate:
            Gk, c, Emat, fixed, (elim, onto, alpha) = eliminate_pair_equalities(space.n_dofs, dofs, Gk, c, Emat,
                                                                                 fixed)
        else:
            elim = onto = np.zeros(0, dtype=np.int64)
            alpha = np.zeros(0)
        c, fixed, (elim2, M2) = self._tie_loose_midpoints(dofs, Gk, c, Emat, fixed)
        n_dofs = space.n_dofs
        M1 = sp.csr_matrix((alpha, (np.arange(elim.size), onto)), shape=(elim.size, n_dofs))
        # the pair-eliminated midpoints first: the tied ones may average them
        eliminated = (np.concatenate([elim, elim2]), sp.vstack([M1, M2 @ _restore_matrix(elim, M1, n_dofs)]).tocsr())
        P, c = self._smoothing(c, fixed, eliminated)
        cones = [ConeGroup(dofs[:n_s], Gk[:n_s, :self.dim + 2], hk)]
        if hb.shape[0]:
            cones.append(ConeGroup(dofs[n_s:], Gk[n_s:], hb))
        problem = ConicProblem(
            n=n_dofs, P=P, q=c, cones=cones, ineq=PairInequalities(),
            fixed_mask=fixed, fixed_values=np.zeros(n_dofs), unreachable=~reach,
            eq=Equalities(Emat, np.zeros(Emat.shape[0])) if Emat.shape[0] else None,
            method="qclp" if P is None else f"qcqp-{self.energy_name}",
            guess=None if guess is None else np.where(fixed, 0.0, guess), equilibrate=True,
        )
        const = 0.0 if self.energy is None else self.lam * self.energy.c
        return P2Program(problem, eliminated, ~reach_v, list(self.notes), const, bool(hb.shape[0]))

    def _cones(self, is_src: np.ndarray, zero_edges: np.ndarray, extra: tuple[np.ndarray, np.ndarray] | None,
               reach: np.ndarray, point_like: bool, dv: np.ndarray | None):
        """The cones of one program, centred: ``(cells (p,), G (p, r, n_local), h (p_s, dim + 2), p_s, h6)``, the
        sampled SOC(dim + 2) cones first (with edge cones their ``G`` padded with two zero rows: the substitutions
        act on columns only), then the :class:`BernsteinEdgeCones` (``h6`` (p − p_s, 6))."""
        mesh, space, bern, dim = self.mesh, self.space, self.bernstein, self.dim
        G0, h0, cone_cell, cone_bary = self.G, self.h, self.cone_cell, self.cone_bary
        replaced = self.cone_replaced
        if extra is not None and len(extra[0]):
            ef, eb = np.asarray(extra[0], dtype=np.int64), np.asarray(extra[1], dtype=float)
            ok = ~space.degenerate[ef]
            ef, eb = ef[ok], eb[ok]
            Gx, hx = _cone_rows(*space.value_and_gradient_rows(ef, eb), dim)
            G0, h0 = np.concatenate([G0, Gx]), np.concatenate([h0, hx])
            cone_cell, cone_bary = np.concatenate([cone_cell, ef]), np.concatenate([cone_bary, eb])
            replaced = np.pad(replaced, (0, ef.size))
        keep = (~_on_sources(mesh.cells[cone_cell], space.cell_edges[cone_cell], cone_bary, is_src, zero_edges)
                & reach[space.cell_dofs[cone_cell]].all(axis=1))
        # at a source the edge cone pins its far end (φ_j = |e|², ∇φ_j = 2e: no interior point), as the corner cone
        # there sits at its apex; the midpoint sample stands in for it
        ends = mesh.cells[bern.face[:, None], (bern.corner[:, None] + [1, 2]) % 3]
        keep_b = ~is_src[ends].any(axis=1) & reach[space.cell_dofs[bern.face]].all(axis=1) & point_like
        if point_like:
            at_source = (is_src[mesh.cells[cone_cell]] & (cone_bary > 0)).any(axis=1)
            keep &= ~replaced | at_source
        cf, cb = cone_cell[keep], cone_bary[keep]
        Gk, hk = G0[keep].copy(), h0[keep].copy()
        a_b = np.ones(int(keep_b.sum()))
        if dv is not None:
            # ‖(√a ∇φ, φ − a)‖ ≤ φ + a is |∇φ|² ≤ 4φ for every a > 0; a ≈ φ at the sample centres the cone there:
            # (Dijkstra distance at the sample)², floored at the squared mean longest edge (a = 1 without sources)
            h2 = np.mean(space.cell_longest_edges[cf]) ** 2 if cf.size else 1.0
            a = np.maximum(np.einsum("ki,ki->k", cb, dv[mesh.cells[cf]]) ** 2, h2)
            Gk[:, 1:dim + 1] *= np.sqrt(a)[:, None, None]
            hk[:, 0] = a
            hk[:, dim + 1] = -a
            a_b = np.maximum(np.sum(dv[ends[keep_b]] ** 2, axis=1), h2)  # T = φ_i + φ_j on |x − p|²
        Gb, hb = bern.rows(keep_b, a_b)
        if Gb.shape[0]:
            Gk = np.concatenate([np.pad(Gk, ((0, 0), (0, 2), (0, 0))), Gb])
            cf = np.concatenate([cf, bern.face[keep_b]])
        return cf, Gk, hk, hk.shape[0], hb

    def _smoothing(self, c: np.ndarray, fixed: np.ndarray, eliminated: tuple[np.ndarray, sp.csr_matrix]):
        """``(P, q)``: ``λ E(φ) = ½ φᵀ(2λQ)φ + (2λg)ᵀφ + λc`` added to the linear objective ``c``, on the reduced
        unknowns: the substituted DOFs restored by ``φ = R x`` (``P ← RᵀPR``, ``q ← q + Rᵀ 2λg``), the fixed ones
        (zero) left out of both. ``P`` is None without an energy."""
        if self.energy is None:
            return None, c
        n = self.space.n_dofs
        R = _restore_matrix(*eliminated, n)
        keep = sp.diags((~fixed).astype(float))
        R = (R @ keep).tocsr()
        P = (R.T @ (2.0 * self.lam * self.energy.Q) @ R).tocsc()
        P.eliminate_zeros()
        q = c + R.T @ (2.0 * self.lam * self.energy.g)
        return P, np.where(fixed, 0.0, q)



@dataclass
class BernsteinEdgeCones:
    """Cones that hold ``|∇φ|² ≤ 4φ`` on the whole of a flat face, one per edge of the face.

    ``v = |∇φ|² − 4φ`` is a quadratic on a face; in the Bernstein basis ``λ_i²``, ``2λ_iλ_j`` (nonnegative, summing
    to 1) it is ``≤ 0`` on the whole triangle when its six coefficients are. The corner coefficients are ``v`` at the
    corners (the corner cones). The coefficient of edge ``ij`` is ``G_i·G_j − 4(2φ_m − (φ_i + φ_j)/2)`` with ``G_i``
    the gradient at corner ``i``; ``G_i·G_j = (|G_i|² + |G_j|² − |u|²)/2`` with ``u = G_j − G_i = H e`` (``e`` the
    edge, ``H`` the face's Hessian of ``φ``). ``−|u|²`` is concave: its tangent at a point ``u₀``,
    ``|u₀|² − 2u₀·u``, bounds it from above, which leaves the convex cone::

        |G_i|² + |G_j|² ≤ 4 T,    T = 4φ_m − φ_i − φ_j + u₀·u / 2 − |u₀|² / 4,

    stricter than the Bernstein coefficient by ``|u − u₀|² / 2`` and equal to it at ``u = u₀``. The tangent is
    ``u₀ = 2e`` (``H = 2I``, the Hessian of ``|x − p|²``; then ``T = 3φ_i + 3φ_j − 4φ_m − |e|²``), so the exact
    field of a flat region stays feasible wherever it is the squared distance to a point, and the gap between the
    samples is closed without cutting planes. Where the field is not (a face crossed by the cut locus, the window
    behind a saddle vertex) the cone is stricter than needed by ``|(H − 2I)e|² / 2``; next to a line of sources
    (``H = 2nnᵀ``) that cost 0.02 of the largest distance on a 12×12 square, so :meth:`P2Builder.build` keeps the
    sampled cones and the cutting planes there (docs/order2.md).

    Attributes
    ----------
    face : (k,) int64 ndarray
    corner : (k,) int64 ndarray
        The edge is the one opposite this local corner (local DOFs ``corner + 1``, ``3 + corner``, ``corner + 2``).
    grad : (k, 4, 6) float ndarray
        ``(G_i, G_j)`` on the face's DOFs, in the face's 2-D frame.
    e2 : (k,) float ndarray
        ``|e|²``.
    """

    face: np.ndarray
    corner: np.ndarray
    grad: np.ndarray
    e2: np.ndarray

    def rows(self, keep: np.ndarray, a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``G`` (k, 6, 6) and ``h`` (k, 6) with ``h − G x = (T + a, √a G_i, √a G_j, T − a)`` for the cones ``keep``
        (a mask or indices), centred at ``a`` (k,) (``‖(√a w, T − a)‖ ≤ T + a`` is ``|w|² ≤ 4T`` for every
        ``a > 0``)."""
        grad, corner, e2 = self.grad[keep], self.corner[keep], self.e2[keep]
        k = grad.shape[0]
        r = np.arange(k)
        T = np.zeros((k, 6))  # T = 3φ_i + 3φ_j − 4φ_m − |e|²
        T[r, (corner + 1) % 3] = 3.0
        T[r, (corner + 2) % 3] = 3.0
        T[r, 3 + corner] = -4.0
        G, h = _cone_rows(T, np.sqrt(a)[:, None, None] * grad, 4)  # h = (1, 0, 0, 0, 0, −1)
        h = a[:, None] * h
        h[:, [0, 5]] -= e2[:, None]
        return G, h


def bernstein_edge_cones(space: LagrangeSpace, faces: np.ndarray) -> BernsteinEdgeCones:
    """The :class:`BernsteinEdgeCones` of ``faces`` (k,) int ndarray (three per face, flat faces of a triangle mesh;
    none when ``faces`` is empty, on any mesh)."""
    faces = np.asarray(faces, dtype=np.int64)
    if not faces.size:
        z = np.zeros(0, dtype=np.int64)
        return BernsteinEdgeCones(z, z, np.zeros((0, 4, 6)), np.zeros(0))
    face, corner = np.repeat(faces, 3), np.tile(np.arange(3), faces.size)
    r = np.arange(face.size)
    # the corners' gradient rows of each cone's face (k, 3, 2, 6), for these faces only
    _, g = space.value_and_gradient_rows(np.repeat(face, 3), np.tile(np.eye(3), (face.size, 1)))
    g = g.reshape(face.size, 3, 2, 6)
    grad_ij = np.concatenate([g[r, (corner + 1) % 3], g[r, (corner + 2) % 3]], axis=1)
    e2 = space.mesh.edge_lengths[space.cell_edges[face, corner]] ** 2
    return BernsteinEdgeCones(face, corner, grad_ij, e2)


def _restore_matrix(elim: np.ndarray, M: sp.csr_matrix, n: int) -> sp.csr_matrix:
    """(n, n) ``R`` with ``R x`` the full vector after ``x[elim] = M @ x`` (identity elsewhere)."""
    keep = np.ones(n)
    keep[elim] = 0.0
    P = sp.csr_matrix((np.ones(elim.size), (elim, np.arange(elim.size))), shape=(n, elim.size))
    return (sp.diags(keep) + P @ M).tocsr()


def _on_sources(corners: np.ndarray, edges: np.ndarray, bary: np.ndarray, is_src: np.ndarray,
                zero_edges: np.ndarray) -> np.ndarray:
    """Which cone samples lie on sources only: the corners of their support all sources and its edges source edges
    (at a source, on a source edge, on a face of three sources joined by source edges).

    With the zero-derivative rows at every source, ``φ`` and ``∇φ`` vanish there for every feasible ``φ`` (on a face
    ``(s, t, x)`` with sources ``s, t`` the rows leave ``φ = φ_x λ_x²``, whose value and gradient are 0 on the edge
    ``st``): such a cone sits at its apex, implied by the rows, and with it the program has no strictly feasible
    point (the structured solver broke down on every pair of adjacent sources and Clarabel took over, docs/order2.md).

    Parameters
    ----------
    corners : (p, dim + 1) int ndarray
        The vertices of each sample's cell.
    edges : (p, dim (dim + 1) / 2) int ndarray
        Their edges (indices into ``mesh.edges``, :data:`~cvxgeodesic.mesh.simplex.CELL_EDGES` order).
    bary : (p, dim + 1) float ndarray
        The samples' barycentric coordinates in those cells.
    is_src : (n,) bool ndarray
        Source vertices.
    zero_edges : (e,) bool ndarray
        Source edges (:func:`source_edges`).

    Returns
    -------
    (p,) bool ndarray
    """
    support = bary > 0
    E = CELL_EDGES[corners.shape[1] - 1]
    need = support[:, E[:, 0]] & support[:, E[:, 1]]
    return (is_src[corners] | ~support).all(axis=1) & (zero_edges[edges] | ~need).all(axis=1)


def eliminate_pair_equalities(n: int, dofs: np.ndarray, G: np.ndarray, c: np.ndarray, E: sp.csr_matrix,
                              fixed: np.ndarray):
    """Substitute the source equalities of two unknowns, ``a x_m + b x_j = 0`` (the zero derivative along an edge
    at a source vertex, ``4 φ_mid − φ_j = 0``), into the cones and the objective.

    ``x_m = α x_j`` (``α = −b / a``) is eliminated where every cone on ``x_m`` also holds ``x_j`` (on a source-star
    edge both are DOFs of each face of the edge), so the Newton matrix keeps its pattern: ``x_m`` becomes a fixed
    DOF. Rows of one unknown (``x = 0``) fix it. Left in ``E``: rows of other shapes, an ``x_m`` in several rows or
    on a cone without its ``x_j``.

    Parameters
    ----------
    n : int
        Number of DOFs.
    dofs : (k, 6) int ndarray
    G : (k, 4, 6) float ndarray
        The cone blocks (``h − G x``).
    c : (n,) float ndarray
        The linear objective.
    E : (r, n) sparse matrix
        The equalities ``E x = 0``.
    fixed : (n,) bool ndarray

    Returns
    -------
    G, c, E, fixed
        New arrays (the inputs are not changed).
    (elim, onto, alpha) : ((r,) int, (r,) int, (r,) float)
        ``x[elim] = alpha · x[onto]`` restores the eliminated unknowns from a solution.
    """
    E = sp.csr_matrix(E)
    E.sum_duplicates()
    n_row = np.diff(E.indptr)
    col_count = np.bincount(E.indices, minlength=n)
    fixed = fixed.copy()
    ones = np.flatnonzero(n_row == 1)
    fixed[E.indices[E.indptr[ones]]] = True
    pairs = np.flatnonzero(n_row == 2)
    c0, c1 = E.indices[E.indptr[pairs]], E.indices[E.indptr[pairs] + 1]
    v0, v1 = E.data[E.indptr[pairs]], E.data[E.indptr[pairs] + 1]
    m, j = np.maximum(c0, c1), np.minimum(c0, c1)  # the midpoint DOFs come after the vertices
    vm, vj = np.where(c0 > c1, v0, v1), np.where(c0 > c1, v1, v0)
    ok = (col_count[m] == 1) & ~fixed[m] & ~np.isin(m, j) & (vm != 0)
    alpha = -vj / np.where(vm != 0, vm, 1.0)
    onto_of = np.full(n, -1, dtype=np.int64)
    onto_of[m[ok]] = j[ok]
    kk, ii = np.nonzero(onto_of[dofs] >= 0)
    target = onto_of[dofs[kk, ii]]
    jj = np.argmax(dofs[kk] == target[:, None], axis=1)
    lacking = np.unique(dofs[kk, ii][dofs[kk, jj] != target])  # x_m on a cone without x_j: keep its row
    ok &= ~np.isin(m, lacking)
    onto_of[lacking] = -1
    keep = onto_of[dofs[kk, ii]] >= 0
    kk, ii, jj = kk[keep], ii[keep], jj[keep]
    a_of = np.zeros(n)
    a_of[m[ok]] = alpha[ok]
    G = G.copy()
    np.add.at(G, (kk, slice(None), jj), a_of[dofs[kk, ii]][:, None] * G[kk, :, ii])  # type: ignore[arg-type]
    G[kk, :, ii] = 0.0
    c = c.copy()
    np.add.at(c, j[ok], alpha[ok] * c[m[ok]])
    c[m[ok]] = 0.0
    fixed[m[ok]] = True
    # a DOF fixed by a row of one unknown keeps no cone columns (the Newton matrix gives fixed DOFs an identity row
    # only; with their columns left in, x there drifted from 0 during the iterations)
    G = np.where(fixed[dofs][:, None, :], 0.0, G)
    c[fixed] = 0.0
    rows_left = np.setdiff1d(np.arange(E.shape[0]), np.concatenate([ones, pairs[ok]]))
    E = E[rows_left]
    fx = np.flatnonzero(fixed)
    if fx.size and E.nnz:
        keep_cols = np.ones(n)
        keep_cols[fx] = 0.0
        E = (E @ sp.diags(keep_cols)).tocsr()
        E.eliminate_zeros()
    return G, c, E, fixed, (m[ok], j[ok], alpha[ok])
