"""The squared-distance program: Lagrange elements for the *squared* geodesic distance (``order=2``), as a
:class:`ConicProblem`.

The unknown is ``φ = d²`` in the space of an order's element (:data:`~cvxgeodesic.operators.lagrange.ELEMENTS`;
order 2, the continuous piecewise-quadratic space: one value per vertex and one per edge midpoint). Nothing here
depends on the order but the element's declaration and the edge cones (order 2). ``|∇√φ| ≤ 1`` is the same as
``|∇φ|² ≤ 4φ``, which is a second-order cone in ``(φ, ∇φ)``::

    ‖(∇φ, φ − 1)‖ ≤ φ + 1      ⇔      |∇φ|² ≤ 4φ

Maximizing ``∫φ`` under that constraint with ``φ = 0`` at the sources has ``d²`` as its
maximizer in the continuum (``√φ`` is 1-Lipschitz and vanishes at the sources, so
``√φ ≤ d``). On a flat region ``d²`` is a quadratic polynomial, which P2 represents
exactly, so flat distances come out exact on triangles of any shape.

The same holds inside a solid (a :class:`~cvxgeodesic.mesh.tetmesh.TetMesh`, the 10-node P2 tetrahedron, SOC(5)
cones): a solid is flat, so where the source is visible ``d² = |x − s|²`` is reproduced exactly whatever the
tetrahedra's shape. One builder, :class:`SquaredDistanceBuilder`, makes both programs; the cells are the mesh's.

Discretization (choices and measurements in ``docs/order2.md``):

* the cone is imposed at sample points of every cell, with the cone centred near the expected ``φ``
  (``‖(√a ∇φ, φ − a)‖ ≤ φ + a`` is the same cone for every ``a > 0``): on a curved face its three edge midpoints;
  on a flat face its three corners; in a tetrahedron its ten nodes; on a curved face also at a corner next to a
  source (:data:`SOURCE_CORNER_NEAR`);
* surfaces only: on *flat* faces (where ``d²`` is exactly quadratic) one :class:`BernsteinEdgeCones` cone per edge:
  with the corner cones it holds ``|∇φ|² ≤ 4φ`` on the whole face, and it is tight on the squared distance to any
  point, so flat regions come out exact in one solve; at a source vertex's edges and next to a line of sources the
  edge midpoints are sampled instead. Elsewhere (those faces; tetrahedra between their node samples) the
  strategy's cutting planes close the gap (a cone where ``|∇φ|² − 4φ`` exceeds a tolerance in a flat cell,
  :meth:`~cvxgeodesic.operators.lagrange.LagrangeElement.violations`, exact, and the problem re-solved);
* the objective is the mean of ``φ`` with lumped weights (``A/6`` per node of a face, ``vol/10`` per node of a
  tetrahedron; the consistent weights of order-2 triangles, 0 at corners and ``A/3`` at midpoints, are a study
  switch of :mod:`cvxgeodesic.problems._study`);
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

import functools
import itertools
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from ..errors import DegenerateFacesWarning, MeshError, ParameterError, warn_user
from ..mesh.reference import ReferenceSimplex
from ..mesh.simplex import SimplexMesh
from ..operators.lagrange import LagrangeSpace, quadratic_candidates
from ..operators.metric import Medium
from ..operators.squared_energy import SquaredEnergy, squared_energy
from ..validation import check_number
from . import _study
from .conic import ConeGroup, ConicProblem, Equalities, PairInequalities

__all__ = ["ORDER2_CACHE_VERSION", "BernsteinEdgeCones", "SquaredDistanceBuilder", "SquaredDistanceProgram",
           "bernstein_edge_cones", "eliminate_pair_equalities", "source_edges"]

# Where the cone is imposed: every node of a flat cell (:attr:`LagrangeSpace.flat_cells`), the nodes off the corners
# (order 2: the edge midpoints) of the others, and on flat faces of a surface the three :class:`BernsteinEdgeCones`
# in place of the midpoints (since 2026-12-02: fandisk 4.1 → 1.1 s, thingi_32770 13 → 3.8 s, no cutting-plane round
# on the development set, the 53 coarse CAD meshes' median error 0.974 → 0.972 %; docs/order2.md).
# Midpoints only on curved faces, measured 2026-12-01 against exact MMP, source 0, mean relative error all nodes →
# midpoints: bimba 0.22 → 0.11 %, bunny 0.099 → 0.058 %, lucy_20k 0.34 → 0.15 %, dragon_20k 0.62 → 0.32 %, spot
# 0.25 → 0.15 %; the 53 coarse CAD meshes: median ratio to P1 qclp 0.216 → 0.204, median error 0.85 → 0.95 %
# (29 better, 24 worse; docs/order2.md); flat meshes unchanged (all their faces are flat). In tetrahedra every node
# of every (flat) cell, the cutting planes between them.
#: A vertex joined to a source vertex (or to an inserted source point) by an edge shorter than this times its own
#: mean edge length is also sampled at, in every curved cell around it. Around a curved vertex that close to the
#: source the field is not one quadratic per face (the vertex's shadow or cut locus starts there): with the midpoints
#: alone the field overshot there and carried the overshoot downstream, so a source point moved toward a vertex lost
#: accuracy until it reached it. Measured 2026-12-06 (docs/dev/adapted-log.md, "Corner samples next to the
#: sources"): spot from points 0.9-0.98 of the way to a vertex, 0.40-1.37 → 0.11-0.19 % mean error; a cylinder from
#: a point 0.98 of the way, 1.66 % → exact; `resolution="auto"` from vertex n/2 (the source's closest point of the
#: copy next to a copy vertex): kitten 1.34 → 0.52 %, bimba 0.48 → 0.18 %. Sampling the corners of every curved cell
#: within a ring of the sources instead made lucy_20k from vertex n/2 worse (0.36 → 0.46 %). 0 turns it off.
SOURCE_CORNER_NEAR = 0.8
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
#: 4: 2026-12-06 (corner samples on the curved faces at vertices next to the sources, :data:`SOURCE_CORNER_NEAR`).
ORDER2_CACHE_VERSION = 4


@dataclass
class SquaredDistanceProgram:
    """One squared-distance program and what turns its solution back into ``φ`` on every DOF.

    Attributes
    ----------
    problem : ConicProblem
        Over the DOFs of the space (order 2: vertices, then edge midpoints), the equalities of two unknowns substituted.
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


def source_edges(mesh: SimplexMesh, vertices: np.ndarray, facets: np.ndarray | None = None) -> np.ndarray:
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


class SquaredDistanceBuilder:
    """Per-mesh part of the squared-distance program (everything that does not depend on the sources), in the space
    of an order's element (:data:`~cvxgeodesic.operators.lagrange.ELEMENTS`), on any simplex mesh.

    The cones are imposed at every node of a flat cell (:attr:`LagrangeSpace.flat_cells`) and at the nodes off the
    corners of the others (order 2: the edge midpoints); on the flat faces of a surface without a medium, the three
    :class:`BernsteinEdgeCones` stand in for the midpoints (their tangent is the Euclidean ``2I``).

    Parameters
    ----------
    mesh : SimplexMesh
        Already scaled to unit size by the caller.
    order : int
        The element's order (a key of :data:`~cvxgeodesic.operators.lagrange.ELEMENTS` above 1).
    medium : Medium, optional
        A travel cost or metric on ``mesh`` (:mod:`cvxgeodesic.operators.metric`, surfaces): every cone bounds
        ``|∇φ|²_{M⁻¹} ≤ 4c²φ`` with the medium at its sample point (:class:`LagrangeSpace`), a degenerate face's 1-D
        cones take the derivative along the edge's length in the medium, and Dijkstra (cone centres, start field)
        runs on the edge lengths in the medium.
    energy : {"hessian", "laplacian", "dirichlet"}, optional
        Surfaces: smoothness energy of ``φ`` (:func:`~cvxgeodesic.operators.squared_energy.squared_energy`); None:
        none (``qclp``). Not with a ``medium``: the energies vanish on the squared *Euclidean* distance of flat
        regions (Hessian ``2I``), which is not the exact field in a medium.
    lam : float
        Its weight λ (dimensionless: the energy has the units of the mean of ``φ``); 0: no energy.

    Attributes
    ----------
    space : LagrangeSpace
    energy : SquaredEnergy or None
        The smoothness energy when ``energy`` is given and ``lam > 0``.
    notes : list of str
        Substitutions made for every program of the mesh (degenerate cells).
    bernstein : BernsteinEdgeCones
        The flat faces' edge cones (none in a solid or with a medium).
    cone_replaced : (k,) bool ndarray
        The sampled cones (flat faces' edge midpoints) that the edge cones replace: kept only on an edge at a source
        vertex, or for every edge when two sources share an edge (:meth:`build`).
    """

    def __init__(self, mesh: SimplexMesh, order: int = 2, medium: Medium | None = None, energy: str | None = None,
                 lam: float = 0.0):
        self.dim = dim = mesh.reference.dim
        self.check(mesh, medium, energy, lam)
        self.mesh = mesh
        self.space = sp_ = LagrangeSpace(mesh, order, medium)
        self.w = _study.objective_weights(sp_)
        self.lam = float(lam) if energy is not None else 0.0
        self.energy_name = energy
        self.energy: SquaredEnergy | None = squared_energy(sp_, energy) if energy is not None and lam > 0 else None
        # the edge cones hold the Bernstein coefficients of a quadratic |∇φ|² − 4φ (an order-2 element) on a
        # triangle; their tangent is the Euclidean Hessian 2I (no medium)
        quadratic = sp_.element.search is quadratic_candidates
        edge_cones = quadratic and medium is None and dim == 2  # dimension: derived for triangles only
        nodes = sp_.element.local_nodes(sp_.reference)
        c = dim + 1
        good = np.flatnonzero(~sp_.degenerate)
        flat = sp_.flat_cells[good]
        flat_cells = good[flat]
        # with Bernstein edge cones the flat faces' midpoint samples stand in for the edge cones at sources only
        groups = [(flat_cells, nodes), (good[~flat], nodes[c:])]
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
        self.bernstein = bernstein_edge_cones(sp_, flat_cells if edge_cones else flat_cells[:0])
        # the midpoint samples a Bernstein edge cone replaces (kept on edges at a source, where it is dropped)
        self.cone_replaced = np.zeros(self.cone_cell.size, dtype=bool)
        if edge_cones:
            self.cone_replaced[:flat_cells.size * len(nodes)] = np.tile([False] * c + [True] * (len(nodes) - c),
                                                                        flat_cells.size)

    @staticmethod
    def check(mesh: SimplexMesh, medium: Medium | None, energy: str | None, lam: float) -> None:
        """ParameterError for a bad option: a smoothness energy on cells it is not derived for, or with a medium
        (what the API takes is the capability table's, :mod:`cvxgeodesic.capabilities`, checked there; this is the
        builder's own check for a direct user)."""
        check_number(lam, "smoothness weight lambda", low=0)
        smoothed = energy is not None and lam > 0
        if smoothed and mesh.reference.dim != 2:  # dimension: the energies are derived on triangles (squared_energy)
            raise ParameterError(f"the order-2 program on {mesh.reference.words.meshes} takes no smoothness energy "
                                 "(surfaces only)")
        if medium is not None and smoothed:  # a field biased without a word, else
            raise ParameterError("the order-2 smoothness energies vanish on the Euclidean squared distance only: a "
                                 "cost or metric takes lam=0")

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
        E = sp_.reference.edges
        a, b = E[local, 0], E[local, 1]
        per = sp_.element.dofs[1]
        t = np.array([0.0, 0.5, 1.0])
        r = np.arange(ids.size)
        # along the edge from corner a to corner b: its local DOFs (the edge's own in the local edge's direction)
        cols = np.column_stack([a, *(dim + 1 + local * per + k for k in range(per)), b])
        val, grd = np.zeros((3, ids.size, n_loc)), np.zeros((3, ids.size, 1, n_loc))
        eb = np.zeros((3, ids.size, dim + 1))
        for j in range(3):  # the edge's ends and midpoint
            eb[j, r, a], eb[j, r, b] = 1 - t[j], t[j]
            N, dN = sp_.basis(eb[j])
            dNt = dN[r, :, b] - dN[r, :, a]  # d/dt of the shape functions along the edge
            # dφ/ds along the edge's length (in the medium: its rate of length per unit t at the sample)
            L = mesh.edge_lengths[ids] if sp_.medium is None else sp_.medium.edge_speed(owner, a, b, t[j])
            val[j, r[:, None], cols] = N[r[:, None], cols]
            grd[j, r[:, None], 0, cols] = dNt[r[:, None], cols] / L[:, None]
        Ge, he = _cone_rows(val.reshape(-1, n_loc), grd.reshape(-1, 1, n_loc), dim)
        if deg.size:
            word = sp_.reference.words.many
            note = (f"{deg.size} degenerate {word} carry no cones at order {sp_.order}; their {ids.size} edge(s) get "
                    "the 1-D cone (dφ/ds)² ≤ 4φ instead")
            self.notes.append(note)
            warn_user(f"{mesh.name}: {note}", DegenerateFacesWarning)
        return Ge, he, np.tile(owner, 3), eb.reshape(-1, dim + 1)

    def _along_edge(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """The shape functions of an edge's DOFs along it, at ``t`` from its start (0) to its end (1): values and
        ``d/dt``, each (per + 2,) over (the start, the edge's own DOFs in its direction, the end)."""
        sp_ = self.space
        c, (a, b), per = sp_.reference.n_corners, sp_.reference.edges[0], sp_.element.dofs[1]
        bary = np.zeros((1, c))
        bary[0, a], bary[0, b] = 1 - t, t
        N, dN = sp_.basis(bary)
        cols = [a, *range(c, c + per), b]
        return N[0, cols], (dN[0, :, b] - dN[0, :, a])[cols]

    def _source_rows(self, is_src: np.ndarray) -> sp.csr_matrix:
        """Zero derivative along every edge from a source vertex ``s`` to a non-source ``j``, over the edge's DOFs and
        ``j`` (order 2: ``4 φ_mid − φ_j − 3 φ_s = 0`` with ``φ_s = 0``; ``∇φ(s) = 0`` in every cell at ``s`` without
        redundant rows), as an (r, n_dofs) matrix."""
        E = self.mesh.edges
        one = np.flatnonzero(is_src[E[:, 0]] ^ is_src[E[:, 1]])
        from_start = is_src[E[one, 0]]
        far = np.where(from_start, E[one, 1], E[one, 0])
        # d/dt at the start (the source at edges[:, 0]) or −d/dt at the end, without the source's own column
        at_start = self._along_edge(0.0)[1][1:]  # over (the edge's DOFs, the end)
        at_end = -self._along_edge(1.0)[1][:-1]  # over (the start, the edge's DOFs)
        vals = np.where(from_start[:, None], at_start, np.concatenate([at_end[1:], at_end[:1]]))
        cols = np.column_stack([self.space.edge_dofs[one], far])
        rows = np.repeat(np.arange(one.size), cols.shape[1])
        return sp.csr_matrix((vals.ravel(), (rows, cols.ravel())), shape=(one.size, self.space.n_dofs))

    def _tie_loose_midpoints(self, dofs, G, c, E, fixed):
        """A free edge DOF (order 2: midpoint) in no cone and no equality (the edge of a degenerate cell too short for a
        1-D cone, :data:`MIN_EDGE`) would be unbounded: it is tied to the linear interpolant of its edge's ends
        (order 2: ``φ_m = (φ_a + φ_b)/2``), its cost moved onto them. Returns ``(c, fixed, (elim, M))`` with
        ``x[elim] = M @ x``."""
        n = self.space.n_dofs
        used = np.zeros(n, dtype=bool)
        used[dofs[np.abs(G).max(axis=1) > 0]] = True
        used[sp.csr_matrix(E).indices] = True
        edge_dofs = self.space.edge_dofs
        e_idx, k_idx = np.nonzero(~used[edge_dofs] & ~fixed[edge_dofs])
        loose, ends = edge_dofs[e_idx, k_idx], self.mesh.edges[e_idx]
        coef = self._edge_linear()[k_idx]  # (p, 2): the DOF of the ends' hat functions
        c, fixed = c.copy(), fixed.copy()
        np.add.at(c, ends.ravel(), (coef * c[loose][:, None]).ravel())
        c[loose] = 0.0
        fixed[loose] = True
        c[fixed] = 0.0
        M = sp.csr_matrix((coef.ravel(), (np.repeat(np.arange(loose.size), 2), ends.ravel())), shape=(loose.size, n))
        return c, fixed, (loose, M)

    def _edge_linear(self) -> np.ndarray:
        """(per, 2): the value of each DOF of an edge in the hat functions of its start and end (its node's
        barycentric coordinates for a nodal basis; order 2: ``(0.5, 0.5)``)."""
        element, ref = self.space.element, self.space.reference
        c, (a, b), per = ref.n_corners, ref.edges[0], element.dofs[1]
        nodes, M = element.local_nodes(ref), element.node_values(ref)
        coef = nodes if np.array_equal(M, np.eye(len(nodes))) else np.linalg.solve(M, nodes)
        return coef[c:c + per][:, [a, b]]

    def build(self, vsrc: np.ndarray, zero_edges: np.ndarray | None = None,
              extra: tuple[np.ndarray, np.ndarray] | None = None, eliminate: bool = True, edge_cones: bool = True,
              guess: np.ndarray | None = None) -> SquaredDistanceProgram:
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
            Additional cone sample points (the cutting planes, :meth:`LagrangeSpace.violations`).
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
        SquaredDistanceProgram

        Raises
        ------
        MeshError
            Every cell is degenerate.
        """
        mesh, space = self.mesh, self.space
        vsrc = np.asarray(vsrc, dtype=np.int64)
        if mesh.n_cells == 0 or np.all(space.degenerate):
            one = space.reference.words.one
            raise MeshError(f"{mesh.name}: every {one} is degenerate; order {space.order} needs at least one proper "
                            f"{one}")
        n, E = mesh.n_vertices, mesh.edges
        is_src = np.zeros(n, dtype=bool)
        is_src[vsrc] = True
        if zero_edges is None:
            zero_edges = is_src[E[:, 0]] & is_src[E[:, 1]]
        reach_v = mesh.connected_to(vsrc) & mesh.referenced
        reach_v[vsrc] = True
        reach = space.on_vertices(reach_v)
        fixed = ~reach
        fixed[vsrc] = True
        # a source edge's midpoint is 0 (the zero-derivative rows at both ends would give it; as an E row of one
        # unknown it left its cone columns in place)
        fixed[space.edge_dofs[zero_edges].ravel()] = True
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
                guess = space.interpolate(functools.partial(_squared_linear, mesh.cells, dv))
        cf, Gk, hk, n_s, hb = self._cones(is_src, zero_edges, self._with_source_corners(is_src, extra), reach,
                                          point_like, dv)
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
        return SquaredDistanceProgram(problem, eliminated, ~reach_v, list(self.notes), const, bool(hb.shape[0]))

    def _with_source_corners(self, is_src: np.ndarray, extra: tuple[np.ndarray, np.ndarray] | None
                             ) -> tuple[np.ndarray, np.ndarray] | None:
        """``extra`` and the corner samples at the vertices next to the sources (:data:`SOURCE_CORNER_NEAR`), in each
        curved cell around them."""
        mesh, space = self.mesh, self.space
        if SOURCE_CORNER_NEAR <= 0 or not is_src.any() or space.flat_cells.all():
            return extra
        E, L = mesh.edges, mesh.edge_lengths
        n = mesh.n_vertices
        mean_edge = np.bincount(E.ravel(), np.repeat(L, 2), n) / np.maximum(np.bincount(E.ravel(), minlength=n), 1)
        near = np.zeros(n, dtype=bool)
        for a, b in ((0, 1), (1, 0)):
            to_source = is_src[E[:, a]] & ~is_src[E[:, b]]
            v = E[to_source, b]
            near[v[L[to_source] < SOURCE_CORNER_NEAR * mean_edge[v]]] = True
        cells = np.flatnonzero(near[mesh.cells].any(axis=1) & ~space.flat_cells & ~space.degenerate)
        k = space.reference.n_corners
        cell, corner = np.repeat(cells, k), np.tile(np.arange(k), cells.size)
        keep = near[mesh.cells[cell, corner]]
        cell, bary = cell[keep], np.eye(k)[corner[keep]]
        if extra is None or not len(extra[0]):
            return cell, bary
        return np.concatenate([np.asarray(extra[0], dtype=np.int64), cell]), np.concatenate([extra[1], bary])

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
        keep = (~_on_sources(space.reference, mesh.cells[cone_cell], space.cell_edges[cone_cell], cone_bary, is_src,
                             zero_edges)
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
    (``H = 2nnᵀ``) that cost 0.02 of the largest distance on a 12×12 square, so
    :meth:`SquaredDistanceBuilder.build` keeps the sampled cones and the cutting planes there (docs/order2.md).

    Attributes
    ----------
    face : (k,) int64 ndarray
    corner : (k,) int64 ndarray
        The edge is the one opposite this local corner (local DOFs ``corner + 1``, ``3 + corner``, ``corner + 2``).
    grad : (k, 4, 6) float ndarray
        ``(G_i, G_j)`` on the face's DOFs, in the face's 2-D frame.
    e2 : (k,) float ndarray
        ``|e|²``.
    midpoints : (3, 6) float ndarray
        The shape functions at the midpoint of the edge opposite each corner (a unit row for the nodal basis):
        ``φ_m = midpoints[corner] @ x``.
    """

    face: np.ndarray
    corner: np.ndarray
    grad: np.ndarray
    e2: np.ndarray
    midpoints: np.ndarray

    def rows(self, keep: np.ndarray, a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``G`` (k, 6, 6) and ``h`` (k, 6) with ``h − G x = (T + a, √a G_i, √a G_j, T − a)`` for the cones ``keep``
        (a mask or indices), centred at ``a`` (k,) (``‖(√a w, T − a)‖ ≤ T + a`` is ``|w|² ≤ 4T`` for every
        ``a > 0``)."""
        grad, corner, e2 = self.grad[keep], self.corner[keep], self.e2[keep]
        k = grad.shape[0]
        r = np.arange(k)
        T = np.zeros((k, 6))  # T = 3φ_i + 3φ_j − 4φ_m − |e|²
        T -= 4.0 * self.midpoints[corner]
        T[r, (corner + 1) % 3] += 3.0
        T[r, (corner + 2) % 3] += 3.0
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
        return BernsteinEdgeCones(z, z, np.zeros((0, 4, 6)), np.zeros(0), np.zeros((0, 6)))
    corners, E = np.eye(3), space.reference.edges
    midpoints = space.basis(0.5 * (corners[E[:, 0]] + corners[E[:, 1]]))[0]  # edge k is opposite corner k
    face, corner = np.repeat(faces, 3), np.tile(np.arange(3), faces.size)
    r = np.arange(face.size)
    # the corners' gradient rows of each cone's face (k, 3, 2, 6), for these faces only
    _, g = space.value_and_gradient_rows(np.repeat(face, 3), np.tile(np.eye(3), (face.size, 1)))
    g = g.reshape(face.size, 3, 2, 6)
    grad_ij = np.concatenate([g[r, (corner + 1) % 3], g[r, (corner + 2) % 3]], axis=1)
    e2 = space.mesh.edge_lengths[space.cell_edges[face, corner]] ** 2
    return BernsteinEdgeCones(face, corner, grad_ij, e2, midpoints)


def _squared_linear(cells: np.ndarray, dv: np.ndarray, at: np.ndarray, bary: np.ndarray) -> np.ndarray:
    """(p,) the square of the linear interpolant of the vertex values ``dv`` at points ``bary`` (p, c) of cells ``at``
    (p,)."""
    return np.einsum("pi,pi->p", bary, dv[cells[at]]) ** 2


def _restore_matrix(elim: np.ndarray, M: sp.csr_matrix, n: int) -> sp.csr_matrix:
    """(n, n) ``R`` with ``R x`` the full vector after ``x[elim] = M @ x`` (identity elsewhere)."""
    keep = np.ones(n)
    keep[elim] = 0.0
    P = sp.csr_matrix((np.ones(elim.size), (elim, np.arange(elim.size))), shape=(n, elim.size))
    return (sp.diags(keep) + P @ M).tocsr()


def _on_sources(reference: ReferenceSimplex, corners: np.ndarray, edges: np.ndarray, bary: np.ndarray,
                is_src: np.ndarray, zero_edges: np.ndarray) -> np.ndarray:
    """Which cone samples lie on sources only: the corners of their support all sources and its edges source edges
    (at a source, on a source edge, on a face of three sources joined by source edges).

    With the zero-derivative rows at every source, ``φ`` and ``∇φ`` vanish there for every feasible ``φ`` (on a face
    ``(s, t, x)`` with sources ``s, t`` the rows leave ``φ = φ_x λ_x²``, whose value and gradient are 0 on the edge
    ``st``): such a cone sits at its apex, implied by the rows, and with it the program has no strictly feasible
    point (the structured solver broke down on every pair of adjacent sources and Clarabel took over, docs/order2.md).

    Parameters
    ----------
    reference : ReferenceSimplex
        The cells'.
    corners : (p, dim + 1) int ndarray
        The vertices of each sample's cell.
    edges : (p, dim (dim + 1) / 2) int ndarray
        Their edges (indices into ``mesh.edges``, ``reference.edges`` order).
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
    E = reference.edges
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
