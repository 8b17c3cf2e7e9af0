"""The order-2 program inside a tetrahedral mesh: P2 tetrahedra for the squared distance ``φ = d²`` (issue 26).

The surface program (:mod:`cvxgeodesic.formulations_p2`) one dimension up. ``|∇√φ| ≤ 1`` is ``|∇φ|² ≤ 4φ``, the
cone ``‖(√a ∇φ, φ − a)‖ ≤ φ + a`` (the same cone for every ``a > 0``), here an SOC(5) on the ten DOFs of a
tetrahedron. Maximizing the mean of ``φ`` under it with ``φ = 0`` at the sources has ``d²`` as its maximizer,
and a solid is flat: where the source is visible ``d² = |x − s|²`` is a quadratic, which the 10-node P2
tetrahedron reproduces exactly, so convex regions come out exact whatever the tetrahedra's shape.

Discretization:

* the cone at the ten nodes of every tetrahedron, centred at ``a`` = (Dijkstra distance at the node)², floored at
  the squared mean longest edge; then cutting planes (by the strategy): a cone where ``|∇φ|² − 4φ`` is largest in
  each violating tetrahedron (:func:`~cvxgeodesic.operators.tet_p2.tet_max_violation`, exact);
* the objective is the mean of ``φ`` with lumped weights ``vol/10`` per node;
* a source vertex ``s`` gets ``φ_s = 0`` and zero derivative along each of its edges to a non-source vertex
  (``4 φ_mid − φ_j = 0``: ``∇φ(s) = 0`` in every incident tetrahedron), substituted into the cones
  (:func:`~cvxgeodesic.formulations_p2.eliminate_pair_equalities`); the midpoint of a *source edge* (joining two
  source vertices, or an edge of a source face) is 0. An edge joining two vertices of the wall through the solid
  is no source edge: its midpoint stays free, bounded by its cones;
* cones whose sample lies on sources only (where the rows make ``φ`` and ``∇φ`` vanish) are left out: they sit
  at their apex and would leave the program without a strictly feasible point;
* a degenerate tetrahedron gets no cones; the 1-D cone ``(∂φ/∂s)² ≤ 4φ`` along each of its edges (ends and
  midpoint) bounds its DOFs; a midpoint of an edge shorter than :data:`~cvxgeodesic.formulations_p2.MIN_EDGE`
  of the diagonal is tied to the mean of its ends (an equality).

Source points are inserted as vertices by the strategy (:class:`~cvxgeodesic.mesh.tet_split.TetSplitMesh`).
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from .errors import DegenerateFacesWarning, MeshError
from .formulations_p2 import MIN_EDGE, P2Program, eliminate_pair_equalities
from .mesh.tetmesh import TET_EDGES, TetMesh
from .operators.tet_p2 import TET_P2_NODES, TetP2Space
from .solvers.problem import ConeGroup, ConicProblem, Equalities, PairInequalities

__all__ = ["TetP2Builder", "source_edges"]


def _cone_rows(val: np.ndarray, grad: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``G, h`` with ``h − G x = (φ + 1, ∇φ, φ − 1)`` (SOC(5)): val (p, 10), grad (p, r ≤ 3, 10)."""
    p = val.shape[0]
    G = np.zeros((p, 5, 10))
    G[:, 0] = -val
    G[:, 1:1 + grad.shape[1]] = -grad
    G[:, 4] = -val
    return G, np.tile([1.0, 0.0, 0.0, 0.0, -1.0], (p, 1))


def source_edges(mesh: TetMesh, vertices: np.ndarray, face_triangles: np.ndarray) -> np.ndarray:
    """(e,) bool ndarray over ``mesh.edges``: edges joining two source vertices, and the edges of source faces.

    Parameters
    ----------
    mesh : TetMesh
    vertices : (s,) int ndarray
        Vertex sources (points inserted as vertices included).
    face_triangles : (f, 3) int ndarray
        Source faces.
    """
    E = mesh.edges
    is_src = np.zeros(mesh.n_vertices, dtype=bool)
    is_src[vertices] = True
    out = is_src[E[:, 0]] & is_src[E[:, 1]]
    if len(face_triangles):
        n = np.int64(mesh.n_vertices)
        F = np.sort(np.asarray(face_triangles, dtype=np.int64), axis=1)
        keys = np.unique(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [0, 2]]]) @ np.array([n, 1]))
        out |= np.isin(E @ np.array([n, 1]), keys)
    return out


class TetP2Builder:
    """Per-mesh part of the order-2 program on tetrahedra.

    Parameters
    ----------
    mesh : TetMesh
        Already scaled to unit size by the caller.

    Attributes
    ----------
    space : TetP2Space
    notes : list of str
        Substitutions made for every program of the mesh (degenerate tetrahedra).
    """

    def __init__(self, mesh: TetMesh):
        self.mesh = mesh
        self.space = space = TetP2Space(mesh)
        self.w = space.weights()
        self.notes: list[str] = []
        good = np.flatnonzero(~space.degenerate)
        tets = np.repeat(good, 10)
        bary = np.tile(TET_P2_NODES, (good.size, 1))
        self.G, self.h = _cone_rows(*space.value_and_gradient_rows(tets, bary))
        Ge, he, te, be = self._degenerate_edge_cones()
        self.G, self.h = np.concatenate([self.G, Ge]), np.concatenate([self.h, he])
        self.cone_tet = np.concatenate([tets, te])
        self.cone_bary = np.concatenate([bary, be])

    def _degenerate_edge_cones(self):
        """1-D cones along each edge of a degenerate tetrahedron (each edge once, in one of its tetrahedra), at its
        ends and midpoint: ``(G, h, tet, bary)``."""
        mesh, space = self.mesh, self.space
        deg = np.flatnonzero(space.degenerate)
        if not deg.size:
            return np.zeros((0, 5, 10)), np.zeros((0, 5)), np.zeros(0, dtype=np.int64), np.zeros((0, 4))
        ids, first = np.unique(mesh.tet_edges[deg].ravel(), return_index=True)
        owner, local = deg[first // 6], first % 6
        L = mesh.edge_lengths[ids]
        ok = L > MIN_EDGE * max(mesh.bbox_diagonal, 1e-300)
        owner, local, L = owner[ok], local[ok], L[ok]
        a, b = TET_EDGES[local, 0], TET_EDGES[local, 1]
        r = np.arange(owner.size)
        rows_v, rows_g, bb = [], [], []
        for t in (0.0, 0.5, 1.0):
            # along the edge from corner a to corner b: φ(t) = φ_a (1−t)(1−2t) + φ_m 4t(1−t) + φ_b t(2t−1)
            val = np.zeros((owner.size, 10))
            grd = np.zeros((owner.size, 1, 10))
            for col, cv, cd in ((a, (1 - t) * (1 - 2 * t), 4 * t - 3), (4 + local, 4 * t * (1 - t), 4 - 8 * t),
                                (b, t * (2 * t - 1), 4 * t - 1)):
                val[r, col] = cv
                grd[r, 0, col] = cd / L
            rows_v.append(val)
            rows_g.append(grd)
            bary = np.zeros((owner.size, 4))
            bary[r, a], bary[r, b] = 1 - t, t
            bb.append(bary)
        G, h = _cone_rows(np.concatenate(rows_v), np.concatenate(rows_g))
        message = (f"{mesh.name}: {deg.size} degenerate tetrahedra carry no cones at order 2; their {owner.size} "
                   "edge(s) get the 1-D cone (dφ/ds)² <= 4φ instead")
        self.notes.append(message)
        warnings.warn(message, DegenerateFacesWarning, stacklevel=4)
        return G, h, np.tile(owner, 3), np.concatenate(bb)

    def build(self, fixed_vertices: np.ndarray, zero_edges: np.ndarray,
              extra: tuple[np.ndarray, np.ndarray] | None = None, guess: np.ndarray | None = None) -> P2Program:
        """The program for a set of source vertices.

        Parameters
        ----------
        fixed_vertices : (s,) int ndarray
            Vertices where ``φ = 0`` (vertex sources, inserted points, vertices of source faces).
        zero_edges : (e,) bool ndarray
            :func:`source_edges`: edges whose midpoint is 0 (no derivative row along them).
        extra : tuple ((p,) int ndarray, (p, 4) float ndarray), optional
            Additional cone samples (tetrahedra and barycentric coordinates; the cutting planes).
        guess : (n_dofs,) float ndarray, optional
            The structured solver's starting field (the previous cutting-plane round's ``φ``); default the squared
            Dijkstra distance at the vertices and the squared mean of its ends at the midpoints.

        Returns
        -------
        P2Program

        Raises
        ------
        MeshError
            Every tetrahedron is degenerate.
        """
        mesh, space = self.mesh, self.space
        if np.all(space.degenerate):
            raise MeshError(f"{mesh.name}: every tetrahedron is degenerate; order 2 needs at least one proper one")
        n, E = mesh.n_vertices, mesh.edges
        vsrc = np.asarray(fixed_vertices, dtype=np.int64)
        G0, h0, ct, cb = self.G, self.h, self.cone_tet, self.cone_bary
        if extra is not None and len(extra[0]):
            et, eb = np.asarray(extra[0], dtype=np.int64), np.asarray(extra[1], dtype=float)
            ok = ~space.degenerate[et]
            Gx, hx = _cone_rows(*space.value_and_gradient_rows(et[ok], eb[ok]))
            G0, h0 = np.concatenate([G0, Gx]), np.concatenate([h0, hx])
            ct, cb = np.concatenate([ct, et[ok]]), np.concatenate([cb, eb[ok]])
        is_src = np.zeros(n, dtype=bool)
        is_src[vsrc] = True
        reach_v = mesh.connected_to(vsrc) & mesh.referenced
        reach_v[vsrc] = True
        reach = np.concatenate([reach_v, reach_v[E[:, 0]] & reach_v[E[:, 1]]])
        fixed = ~reach
        fixed[vsrc] = True
        fixed[n + np.flatnonzero(zero_edges)] = True
        # samples where the rows make φ and ∇φ vanish: their support's corners all sources, its edges source edges
        corners = mesh.T[ct]
        support = cb > 0
        ze = zero_edges[mesh.tet_edges[ct]]
        need = support[:, TET_EDGES[:, 0]] & support[:, TET_EDGES[:, 1]]
        on_sources = (is_src[corners] | ~support).all(axis=1) & (ze | ~need).all(axis=1)
        dofs_all = space.tet_dofs[ct]
        keep = ~on_sources & reach[dofs_all].all(axis=1)
        # zero derivative along every edge from a source to a non-source vertex: 4 φ_mid − φ_j = 0
        one = np.flatnonzero(is_src[E[:, 0]] ^ is_src[E[:, 1]])
        far = np.where(is_src[E[one, 0]], E[one, 1], E[one, 0])
        rows = [np.repeat(np.arange(one.size), 2)]
        cols = [np.column_stack([n + one, far]).ravel()]
        vals = [np.tile([4.0, -1.0], one.size)]
        # a midpoint of an edge too short for a 1-D cone, in degenerate tetrahedra only: φ_m = (φ_a + φ_b) / 2
        used = np.zeros(space.n_dofs, dtype=bool)
        used[dofs_all[keep][np.abs(G0[keep]).max(axis=1) > 0]] = True
        loose = np.flatnonzero(~used[n:] & ~fixed[n:])
        loose = loose[~np.isin(loose, one)]
        if loose.size:
            r0 = one.size + np.arange(loose.size)
            rows.append(np.repeat(r0, 3))
            cols.append(np.column_stack([n + loose, E[loose, 0], E[loose, 1]]).ravel())
            vals.append(np.tile([1.0, -0.5, -0.5], loose.size))
        Emat = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                             shape=(one.size + loose.size, space.n_dofs))
        Emat = (Emat @ sp.diags((~fixed).astype(float))).tocsr()
        Emat.eliminate_zeros()
        Emat = Emat[np.diff(Emat.indptr) > 0]
        c = -self.w / max(self.w.sum(), 1e-300)
        c[fixed] = 0.0
        ckeep, bkeep = ct[keep], cb[keep]
        Gk, hk = G0[keep].copy(), h0[keep].copy()
        if vsrc.size:
            dv = dijkstra(mesh.vertex_adjacency, indices=vsrc, min_only=True)
            dv = np.where(np.isfinite(dv), dv, 0.0)
            if guess is None:
                # on an edge at a source vertex (ℓ/2)² = φ_j / 4 meets the zero-derivative rows. Measured on the
                # jittered L prism (n = 4, 8): 25 → 19 and 39 → 27 iterations, the same field to 1e-8 of its maximum
                guess = np.concatenate([dv**2, (0.5 * (dv[E[:, 0]] + dv[E[:, 1]])) ** 2])
            h2 = np.mean(mesh.tet_longest_edges[ckeep]) ** 2 if ckeep.size else 1.0
            a = np.maximum(np.einsum("ki,ki->k", bkeep, dv[mesh.T[ckeep]]) ** 2, h2)
            Gk[:, 1:4] *= np.sqrt(a)[:, None, None]
            hk[:, 0] = a
            hk[:, 4] = -a
        dofs = dofs_all[keep]
        Gk = np.where(fixed[dofs][:, None, :], 0.0, Gk)
        Gk, c, Emat, fixed, (elim, onto, alpha) = eliminate_pair_equalities(space.n_dofs, dofs, Gk, c, Emat, fixed)
        M = sp.csr_matrix((alpha, (np.arange(elim.size), onto)), shape=(elim.size, space.n_dofs))
        problem = ConicProblem(
            n=space.n_dofs, P=None, q=c, cones=[ConeGroup(dofs, Gk, hk)], ineq=PairInequalities(),
            fixed_mask=fixed, fixed_values=np.zeros(space.n_dofs), unreachable=~reach,
            eq=Equalities(Emat, np.zeros(Emat.shape[0])) if Emat.shape[0] else None, method="qclp",
            guess=None if guess is None else np.where(fixed, 0.0, guess), equilibrate=True,
        )
        return P2Program(problem, (elim, M), ~reach_v, list(self.notes))
