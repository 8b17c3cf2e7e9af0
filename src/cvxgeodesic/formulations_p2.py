"""The order-2 program: P2 elements for the *squared* geodesic distance (``order=2``), as a :class:`ConicProblem`.

The unknown is ``φ = d²`` in the continuous piecewise-quadratic space: one value per
vertex and one per edge midpoint. ``|∇√φ| ≤ 1`` is the same as ``|∇φ|² ≤ 4φ``, which is
a second-order cone in ``(φ, ∇φ)``::

    ‖(∇φ, φ − 1)‖ ≤ φ + 1      ⇔      |∇φ|² ≤ 4φ

Maximizing ``∫φ`` under that constraint with ``φ = 0`` at the sources has ``d²`` as its
maximizer in the continuum (``√φ`` is 1-Lipschitz and vanishes at the sources, so
``√φ ≤ d``). On a flat region ``d²`` is a quadratic polynomial, which P2 represents
exactly, so flat distances come out exact on triangles of any shape.

Discretization (choices and measurements in ``docs/order2.md``):

* the cone is imposed at sample points of every face, by default the three edge midpoints of a curved face and
  the three corners of a flat one (:data:`DEFAULT_SAMPLES`), with the cone centred near the expected ``φ``
  (``‖(√a ∇φ, φ − a)‖ ≤ φ + a`` is the same cone for every ``a > 0``);
* on *flat* faces (where ``d²`` is exactly quadratic) one :class:`BernsteinEdgeCones` cone per edge: with the
  corner cones it holds ``|∇φ|² ≤ 4φ`` on the whole face, and it is tight on the squared distance to any point,
  so flat regions come out exact in one solve; at a source vertex's edges and next to a line of sources the edge
  midpoints are sampled instead, and the strategy's cutting planes close the gap there (a cone where
  ``|∇φ|² − 4φ`` is largest on each violating face, :func:`max_violation`, exact, and the problem re-solved);
* the objective is the mean of ``φ`` with lumped weights ``A/6`` per node of each face
  (``weights="lumped"``; the consistent P2 weights, 0 at corners and ``A/3`` at midpoints,
  are ``weights="p2"``);
* a source vertex ``s`` gets ``φ_s = 0`` and zero derivative at ``s`` along each of its
  edges (``4 φ_mid − φ_j = 0``), which is ``∇φ(s) = 0`` on every incident face without
  redundant rows; the cones at ``s`` (degenerate there) are left out;
* a source point inside a face or on an edge is inserted as a vertex
  (:class:`~cvxgeodesic.mesh.split.SplitMesh`, by the strategy; imposing ``φ(p) = 0``, ``∇φ(p) = 0`` on the
  unsplit face measured less accurate, docs/order2.md);
* the equalities of two unknowns (the zero derivative along a source-star edge) are substituted into the cones
  (:func:`eliminate_pair_equalities`), so the program keeps the face-clique pattern;
* a degenerate face (:meth:`TriMesh.degenerate_faces`) gets no face cones; the 1-D cone
  ``(∂φ/∂s)² ≤ 4φ`` along each of its edges (endpoints and midpoint) bounds its DOFs
  whatever its shape;
* non-manifold edges need nothing special: the edge DOF is shared by all its faces.

Distances at vertices are ``√max(φ, 0)``; :class:`~cvxgeodesic.operators.p2.P2Field` evaluates the field inside
faces. The space and its operators are in :mod:`cvxgeodesic.operators.p2`, the cutting-plane loop and the solve in
:mod:`cvxgeodesic.strategies.order2`.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from .errors import DegenerateFacesWarning, MeshError, ParameterError
from .mesh.trimesh import TriMesh
from .operators.metric import Medium
from .operators.p2 import SAMPLES, P2Space, edge_basis
from .operators.p2_energy import P2Energy, p2_energy
from .solvers.problem import ConeGroup, ConicProblem, Equalities, PairInequalities

__all__ = ["DEFAULT_SAMPLES", "DEFAULT_WEIGHTS", "ORDER2_CACHE_VERSION", "ORDER2_METHODS", "BernsteinEdgeCones",
           "P2Builder", "P2Program", "bernstein_edge_cones", "eliminate_pair_equalities"]

#: Where the cone is imposed: "flat-bernstein" = the three corners and the three :class:`BernsteinEdgeCones` on flat
#: faces (:attr:`P2Space.flat_faces`), the three edge midpoints on the others (since 2026-12-02: fandisk 4.1 → 1.1 s,
#: thingi_32770 13 → 3.8 s, no cutting-plane round on the development set, the 53 coarse CAD meshes' median
#: error 0.974 → 0.972 %; docs/order2.md); "flat-nodes" = all six nodes on flat faces, no edge cones (before).
#: Midpoints only on curved faces, measured 2026-12-01 against exact MMP, source 0, mean relative error all nodes →
#: flat-nodes: bimba 0.22 → 0.11 %, bunny 0.099 → 0.058 %, lucy_20k 0.34 → 0.15 %, dragon_20k 0.62 → 0.32 %, spot
#: 0.25 → 0.15 %; the 53 coarse CAD meshes: median ratio to P1 qclp 0.216 → 0.204, median error 0.85 → 0.95 %
#: (29 better, 24 worse; docs/order2.md); flat meshes unchanged (all their faces are flat).
DEFAULT_SAMPLES = "flat-bernstein"
#: Objective weights (:meth:`P2Space.weights`; docs/order2.md has the measurement behind the choice).
DEFAULT_WEIGHTS = "lumped"
#: The formulations with an order-2 program: ``qclp`` and the smoothed QC formulations, whose energies act on ``φ``
#: (:mod:`cvxgeodesic.operators.p2_energy`; ``qcqp-dirichlet`` takes the edge-jump term alone).
ORDER2_METHODS = ("qclp", "qcqp-hessian", "qcqp-laplacian", "qcqp-dirichlet")
#: Edges shorter than this fraction of the bounding-box diagonal get no 1-D cone (their DOF is tied linearly).
MIN_EDGE = 1e-9
#: Version of the order-2 fields, for caches keyed on the inputs only (``benchmarks/report_common.py``): bump it
#: whenever a change moves an order-2 result beyond the solver tolerance (formulation, samples, weights, defaults),
#: so that fields cached by older code are recomputed instead of silently reused. 1: 2026-12-02 (first version;
#: the fields of the 2026-12-01 defaults, midpoints on curved faces). 2: 2026-12-02 (the one solver; cutting planes
#: at every local maximum, stopped at a relative violation of 1e-5, warm-started: flat-face fields move by up to
#: ~1e-6 of the largest distance). 3: 2026-12-02 (the Bernstein edge cones on flat faces: CAD fields move by up to
#: ~1e-2 of the largest distance, flat ones by solver rounding).
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


def _cone_rows(val: np.ndarray, grad: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``G, h`` with ``h − G x = (φ + 1, ∇φ, φ − 1)``: val (k, 6), grad (k, 2, 6) or (k, 1, 6)."""
    k = val.shape[0]
    G = np.zeros((k, 4, 6))
    G[:, 0] = -val
    G[:, 1:1 + grad.shape[1]] = -grad
    G[:, 3] = -val
    h = np.tile([1.0, 0.0, 0.0, -1.0], (k, 1))
    return G, h


class P2Builder:
    """Per-mesh part of the order-2 program (everything that does not depend on the sources).

    Parameters
    ----------
    mesh : TriMesh
        Already scaled to unit size by the caller.
    samples : str
        "flat-bernstein" (:data:`DEFAULT_SAMPLES`), "flat-nodes", or a key of :data:`~cvxgeodesic.operators.p2.SAMPLES`
        (on every face, no edge cones). With a ``medium`` "flat-bernstein" is "flat-nodes": the edge cones' tangent
        is the Euclidean ``2I``.
    weights : {"lumped", "p2", "mixed"}, optional
        Objective weights (:meth:`P2Space.weights`); default :data:`DEFAULT_WEIGHTS`.
    cone_scale : {"dijkstra", "unit"}
        Centre of each cone: ``a`` = (Dijkstra distance at the sample)², floored at the squared
        mean longest edge, or ``a = 1``.
    medium : Medium, optional
        A travel cost or metric on ``mesh`` (:mod:`cvxgeodesic.operators.metric`): every cone bounds
        ``|∇φ|²_{M⁻¹} ≤ 4c²φ`` with the medium at its sample point (:class:`~cvxgeodesic.operators.p2.P2Space`),
        a degenerate face's 1-D cones take the derivative along the edge's length in the medium, and Dijkstra
        (cone centres, start field) runs on the edge lengths in the medium.
    energy : {"hessian", "laplacian", "dirichlet"}, optional
        Smoothness energy of ``φ`` (:func:`~cvxgeodesic.operators.p2_energy.p2_energy`); None: none (``qclp``).
        Not with a ``medium``: the energies vanish on the squared *Euclidean* distance of flat regions (Hessian
        ``2I``), which is not the exact field in a medium.
    lam : float
        Its weight λ (dimensionless: the energy has the units of the mean of ``φ``); 0: no energy.

    Attributes
    ----------
    space : P2Space
    energy : P2Energy or None
        The smoothness energy when ``energy`` is given and ``lam > 0``.
    notes : list of str
        Substitutions made for every program of the mesh (degenerate faces).
    bernstein : BernsteinEdgeCones
        The flat faces' edge cones (none unless ``samples="flat-bernstein"``).
    cone_replaced : (k,) bool ndarray
        The sampled cones (flat faces' edge midpoints) that the edge cones replace: kept only on an edge at a source
        vertex, or for every edge when two sources share an edge (:meth:`build`).
    """

    def __init__(self, mesh: TriMesh, samples: str = DEFAULT_SAMPLES, weights: str | None = None,
                 cone_scale: str = "dijkstra", medium: Medium | None = None, energy: str | None = None,
                 lam: float = 0.0):
        weights = DEFAULT_WEIGHTS if weights is None else weights
        if not (np.isfinite(lam) and lam >= 0):
            raise ParameterError(f"smoothness weight lambda must be finite and >= 0, got {lam}")
        if medium is not None and energy is not None and lam > 0:
            raise ParameterError("order-2 smoothing takes no cost or metric: its energies vanish on the Euclidean "
                                 "squared distance only; use order=1 or method='qclp'")
        if samples not in SAMPLES and samples not in ("flat-nodes", "flat-bernstein"):
            raise ParameterError(f"samples must be 'flat-bernstein', 'flat-nodes' or one of {tuple(SAMPLES)}, "
                                 f"got {samples!r}")
        if cone_scale not in ("dijkstra", "unit"):
            raise ParameterError(f"cone_scale must be 'dijkstra' or 'unit', got {cone_scale!r}")
        self.cone_scale = cone_scale
        self.mesh = mesh
        self.space = sp_ = P2Space(mesh, medium)
        self.w = sp_.weights(weights)
        self.lam = float(lam) if energy is not None else 0.0
        self.energy_name = energy
        self.energy: P2Energy | None = p2_energy(sp_, energy) if energy is not None and lam > 0 else None
        good = np.flatnonzero(~sp_.degenerate)
        if samples == "flat-bernstein" and medium is not None:
            # the tangent in bernstein_edge_cones is taken at the Euclidean Hessian 2I
            samples = "flat-nodes"
        flat_faces = np.zeros(0, dtype=np.int64)
        if samples in ("flat-nodes", "flat-bernstein"):
            flat = sp_.flat_faces[good]
            flat_faces = good[flat]
            # with Bernstein edge cones the flat faces' midpoint samples stand in for the edge cones at sources only
            groups = [(flat_faces, SAMPLES["nodes"]), (good[~flat], SAMPLES["midpoints"])]
        else:
            groups = [(good, SAMPLES[samples])]
        parts = []
        for faces, bary in groups:
            val, grad = sp_.face_cones(bary)
            parts.append(_cone_rows(np.tile(val, (faces.size, 1)), grad[faces].reshape(-1, 2, 6)))
        Gf, hf = np.concatenate([g for g, _ in parts]), np.concatenate([h for _, h in parts])
        self.notes: list[str] = []
        Ge, he, e_face, e_samples = self._degenerate_edge_cones()
        self.G = np.concatenate([Gf, Ge])
        self.h = np.concatenate([hf, he])
        self.cone_face = np.concatenate([*[np.repeat(f, b.shape[0]) for f, b in groups], e_face]).astype(np.int64)
        # each cone's barycentric point (for dropping the cones on source vertices, :func:`_on_sources`)
        self.cone_bary = np.concatenate([*[np.tile(b, (f.size, 1)) for f, b in groups], e_samples])
        self.bernstein = bernstein_edge_cones(sp_, flat_faces if samples == "flat-bernstein" else flat_faces[:0])
        # the midpoint samples a Bernstein edge cone replaces (kept on edges at a source, where it is dropped)
        self.cone_replaced = np.zeros(self.cone_face.size, dtype=bool)
        if samples == "flat-bernstein":
            self.cone_replaced[:flat_faces.size * 6] = np.tile([False] * 3 + [True] * 3, flat_faces.size)

    def _degenerate_edge_cones(self):
        """The 1-D cones ``(dφ/ds)² ≤ 4φ`` along each edge of a degenerate face (each edge once), at its ends and
        midpoint: ``(G, h, face, bary)``."""
        mesh, sp_ = self.mesh, self.space
        deg = np.flatnonzero(sp_.degenerate)
        if not deg.size:
            return np.zeros((0, 4, 6)), np.zeros((0, 4)), np.zeros(0, dtype=np.int64), np.zeros((0, 3))
        fe = sp_.face_edges[deg]
        ids, first = np.unique(fe.ravel(), return_index=True)
        owner = deg[first // 3]
        kloc = first % 3  # edge opposite local corner kloc of its owner face
        ok = mesh.edge_lengths[ids] > MIN_EDGE * max(mesh.bbox_diagonal, 1e-300)
        ids, owner, kloc = ids[ok], owner[ok], kloc[ok]
        t = np.array([0.0, 0.5, 1.0])
        Nt, dNt = edge_basis(t)
        rows_v, rows_g, fo, eb = [], [], [], []
        r = np.arange(ids.size)
        a, b = (kloc + 1) % 3, (kloc + 2) % 3
        for j in range(3):
            # dφ/ds along the edge's length (in the medium: its rate of length per unit t at the sample)
            L = mesh.edge_lengths[ids] if sp_.medium is None else sp_.medium.edge_speed(owner, a, b, t[j])
            # edge opposite corner k runs from corner k+1 to corner k+2; local DOFs (k+1, 3+k, k+2)
            val_e = np.zeros((ids.size, 6))
            grd_e = np.zeros((ids.size, 1, 6))
            for col, coeff_v, coeff_d in ((a, Nt[j, 0], dNt[j, 0]), (3 + kloc, Nt[j, 1], dNt[j, 1]),
                                          (b, Nt[j, 2], dNt[j, 2])):
                val_e[r, col] = coeff_v
                grd_e[r, 0, col] = coeff_d / L
            rows_v.append(val_e)
            rows_g.append(grd_e)
            fo.append(owner)
            bb = np.zeros((ids.size, 3))
            bb[r, a] = 1 - t[j]
            bb[r, b] = t[j]
            eb.append(bb)
        Ge, he = _cone_rows(np.concatenate(rows_v), np.concatenate(rows_g))
        self.notes.append(
            f"{deg.size} degenerate face(s) carry no face cones; their {ids.size} edge(s) get the "
            "1-D cone (dφ/ds)² ≤ 4φ instead")
        warnings.warn(f"{mesh.name}: {deg.size} degenerate face(s) left out of the order-2 face cones "
                      "(their edges carry 1-D cones)", DegenerateFacesWarning, stacklevel=4)
        return Ge, he, np.concatenate(fo), np.concatenate(eb)

    def _source_rows(self, vsrc: np.ndarray) -> tuple[list[int], list[int], list[float], int]:
        """Zero derivative along every edge at a source vertex ``s``: ``4 φ_mid − φ_j − 3 φ_s = 0`` (``φ_s`` fixed
        at 0), as COO rows ``(rows, cols, vals, count)``."""
        n = self.mesh.n_vertices
        E = self.mesh.edges
        is_src = np.zeros(n, dtype=bool)
        is_src[vsrc] = True
        inc = np.flatnonzero(is_src[E[:, 0]] | is_src[E[:, 1]])
        far = np.where(is_src[E[inc, 0]], E[inc, 1], E[inc, 0])
        r = np.repeat(np.arange(inc.size), 2)
        cols = np.column_stack([n + inc, far]).ravel()
        vals = np.tile([4.0, -1.0], inc.size)
        return r.tolist(), cols.tolist(), vals.tolist(), int(inc.size)

    def _tie_loose_midpoints(self, dofs, G, c, E, fixed):
        """A free midpoint DOF in no cone and no equality (the edge of a degenerate face too short for a 1-D cone,
        :data:`MIN_EDGE`) would be unbounded: it is tied to the mean of its edge's ends, ``φ_m = (φ_a + φ_b)/2``, its
        cost moved onto them. Returns ``(c, fixed, (elim, M))`` with ``x[elim] = M @ x``."""
        n_v, n = self.mesh.n_vertices, self.space.n_dofs
        used = np.zeros(n, dtype=bool)
        used[dofs[np.abs(G).max(axis=1) > 0]] = True
        used[sp.csr_matrix(E).indices] = True
        loose = np.flatnonzero(~used[n_v:] & ~fixed[n_v:]) + n_v
        if not loose.size:
            return c, fixed, (np.zeros(0, dtype=np.int64), sp.csr_matrix((0, n)))
        ends = self.mesh.edges[loose - n_v]
        c, fixed = c.copy(), fixed.copy()
        np.add.at(c, ends.ravel(), np.repeat(0.5 * c[loose], 2))
        c[loose] = 0.0
        fixed[loose] = True
        c[fixed] = 0.0
        M = sp.csr_matrix((np.full(2 * loose.size, 0.5), (np.repeat(np.arange(loose.size), 2), ends.ravel())),
                          shape=(loose.size, n))
        return c, fixed, (loose, M)

    def build(self, vsrc: np.ndarray, extra: tuple[np.ndarray, np.ndarray] | None = None,
              eliminate: bool = True, edge_cones: bool = True) -> P2Program:
        """The program for a set of source vertices.

        Parameters
        ----------
        vsrc : (k,) int ndarray
            Source vertices (source points are inserted as vertices first, by the caller).
        extra : tuple (faces (k,) int ndarray, bary (k, 3) float ndarray), optional
            Additional cone sample points (from :func:`~cvxgeodesic.operators.p2.max_violation`).
        eliminate : bool
            Substitute the equalities of two unknowns (:func:`eliminate_pair_equalities`); False keeps them as rows
            of ``E`` (the interior-point solver then solves them through its Schur complement: the same optimum,
            ``p`` more triangular solves per factorization).
        edge_cones : bool
            False: the flat faces keep their midpoint samples instead of the :class:`BernsteinEdgeCones` (the
            strategy's fallback when the edge cones leave no feasible or solvable program).

        Returns
        -------
        P2Program

        Raises
        ------
        MeshError
            Every face is degenerate.
        """
        mesh, space = self.mesh, self.space
        vsrc = np.asarray(vsrc, dtype=np.int64)
        if mesh.n_faces == 0 or np.all(space.degenerate):
            raise MeshError(f"{mesh.name}: every face is degenerate; order 2 needs at least one proper face")
        reach_v = mesh.connected_to(vsrc) & mesh.referenced
        reach_v[vsrc] = True
        E = mesh.edges
        reach = np.concatenate([reach_v, reach_v[E[:, 0]] & reach_v[E[:, 1]]])
        fixed = ~reach
        fixed[vsrc] = True
        both = np.flatnonzero(np.isin(E, vsrc).all(axis=1))
        # an edge joining two sources: the zero-derivative rows at both ends give φ_mid = 0, so fix it here (as an
        # E row of one unknown it left its cone columns in place)
        fixed[mesh.n_vertices + both] = True
        # sources joined by an edge form a curve, whose squared distance is not a point's (Hessian 2nnᵀ, not 2I):
        # the edge cones would hold the field back there, so the sampled cones and the cutting planes take over
        point_like = both.size == 0 and edge_cones
        rows, cols, vals, r = self._source_rows(vsrc)
        Emat = sp.csr_matrix((vals, (rows, cols)), shape=(r, space.n_dofs))
        # fixed DOFs leave the equalities; drop rows that are then empty
        Emat = (Emat @ sp.diags((~fixed).astype(float))).tocsr()
        Emat.eliminate_zeros()
        Emat = Emat[np.diff(Emat.indptr) > 0]
        # the mean of φ, not its integral: the backends' absolute gap tolerance then means the same on any area
        c = -self.w / max(self.w.sum(), 1e-300)
        c[fixed] = 0.0
        dv = guess = None
        if vsrc.size:
            dv = dijkstra(space.adjacency, indices=vsrc, min_only=True)
            dv = np.where(np.isfinite(dv), dv, 0.0)
            # a starting field for the structured solver: squared distance at the vertices, squared mean at the
            # midpoints (on an edge at a source vertex that is ℓ²/4 = φ_j / 4, so it meets the zero-derivative
            # equalities). With flat faces too since the edge cones (2026-12-02: fandisk 30 → 24 iterations,
            # bug_surface 27 → 20); with the corner and midpoint samples alone, a needle strip's solve from it had
            # stopped 7.6e-5 of the largest distance away from the optimum (the samples barely determine it)
            guess = np.concatenate([dv**2, (0.5 * (dv[E[:, 0]] + dv[E[:, 1]]))**2])
            guess[fixed] = 0.0
        cf, Gk, hk, n4, hb = self._cones(vsrc, extra, reach, point_like, dv)
        dofs = space.face_dofs[cf]
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
        unreachable = ~reach
        P, c = self._smoothing(c, fixed, eliminated)
        cones = [ConeGroup(dofs[:n4], Gk[:n4, :4], hk)]
        if hb.shape[0]:
            cones.append(ConeGroup(dofs[n4:], Gk[n4:], hb))
        problem = ConicProblem(
            n=space.n_dofs, P=P, q=c, cones=cones, ineq=PairInequalities(),
            fixed_mask=fixed, fixed_values=np.zeros(space.n_dofs), unreachable=unreachable,
            eq=Equalities(Emat, np.zeros(Emat.shape[0])) if Emat.shape[0] else None,
            method="qclp" if P is None else f"qcqp-{self.energy_name}",
            guess=None if guess is None else np.where(fixed, 0.0, guess), equilibrate=True,
        )
        const = 0.0 if self.energy is None else self.lam * self.energy.c
        return P2Program(problem, eliminated, ~reach_v, list(self.notes), const, bool(hb.shape[0]))

    def _cones(self, vsrc: np.ndarray, extra: tuple[np.ndarray, np.ndarray] | None, reach: np.ndarray,
               point_like: bool, dv: np.ndarray | None):
        """The cones of one program, centred: ``(faces (k,), G (k, 6, 6), h4 (k4, 4), k4, h6 (k − k4, 6))``, the
        sampled SOC(4) cones first (their ``G`` padded with two zero rows: the substitutions act on columns only),
        then the :class:`BernsteinEdgeCones`."""
        mesh, space, bern = self.mesh, self.space, self.bernstein
        G0, h0, cone_face, cone_bary = self.G, self.h, self.cone_face, self.cone_bary
        replaced = self.cone_replaced
        if extra is not None and len(extra[0]):
            ef, eb = np.asarray(extra[0], dtype=np.int64), np.asarray(extra[1], dtype=float)
            ok = ~space.degenerate[ef]
            ef, eb = ef[ok], eb[ok]
            Gx, hx = _cone_rows(*space.sample_rows(ef, eb))
            G0, h0 = np.concatenate([G0, Gx]), np.concatenate([h0, hx])
            cone_face, cone_bary = np.concatenate([cone_face, ef]), np.concatenate([cone_bary, eb])
            replaced = np.pad(replaced, (0, ef.size))
        keep = ~_on_sources(mesh.F[cone_face], cone_bary, vsrc) & reach[space.face_dofs[cone_face]].all(axis=1)
        # at a source the edge cone pins its far end (φ_j = |e|², ∇φ_j = 2e: no interior point), as the corner cone
        # there sits at its apex; the midpoint sample stands in for it
        ends = mesh.F[bern.face[:, None], (bern.corner[:, None] + [1, 2]) % 3]
        keep_b = ~np.isin(ends, vsrc).any(axis=1) & reach[space.face_dofs[bern.face]].all(axis=1) & point_like
        if point_like:
            at_source = (np.isin(mesh.F[cone_face], vsrc) & (cone_bary > 0)).any(axis=1)
            keep &= ~replaced | at_source
        cf, cb = cone_face[keep], cone_bary[keep]
        Gk, hk = G0[keep].copy(), h0[keep].copy()
        a_b = np.ones(int(keep_b.sum()))
        if self.cone_scale == "dijkstra" and dv is not None:
            # ‖(√a ∇φ, φ − a)‖ ≤ φ + a is |∇φ|² ≤ 4φ for every a > 0; a ≈ φ at the sample centres the cone there
            h2 = np.mean(space.face_longest_edges[cf]) ** 2 if cf.size else 1.0
            a = np.maximum(np.einsum("ki,ki->k", cb, dv[mesh.F[cf]]) ** 2, h2)
            Gk[:, 1:3] *= np.sqrt(a)[:, None, None]
            hk[:, 0] = a
            hk[:, 3] = -a
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
        G = np.zeros((k, 6, 6))
        G[:, 0] = -T
        G[:, 1:5] = -np.sqrt(a)[:, None, None] * grad
        G[:, 5] = -T
        h = np.zeros((k, 6))
        h[:, 0] = a - e2
        h[:, 5] = -a - e2
        return G, h


def bernstein_edge_cones(space: P2Space, faces: np.ndarray) -> BernsteinEdgeCones:
    """The :class:`BernsteinEdgeCones` of ``faces`` (k,) int ndarray (three per face, flat faces)."""
    faces = np.asarray(faces, dtype=np.int64)
    face, corner = np.repeat(faces, 3), np.tile(np.arange(3), faces.size)
    r = np.arange(face.size)
    # the corners' gradient rows of each cone's face (k, 3, 2, 6), for these faces only
    _, g = space.sample_rows(np.repeat(face, 3), np.tile(SAMPLES["corners"], (face.size, 1)))
    g = g.reshape(face.size, 3, 2, 6)
    grad_ij = np.concatenate([g[r, (corner + 1) % 3], g[r, (corner + 2) % 3]], axis=1)
    e2 = space.mesh.edge_lengths[space.face_edges[face, corner]] ** 2
    return BernsteinEdgeCones(face, corner, grad_ij, e2)


def _restore_matrix(elim: np.ndarray, M: sp.csr_matrix, n: int) -> sp.csr_matrix:
    """(n, n) ``R`` with ``R x`` the full vector after ``x[elim] = M @ x`` (identity elsewhere)."""
    keep = np.ones(n)
    keep[elim] = 0.0
    P = sp.csr_matrix((np.ones(elim.size), (elim, np.arange(elim.size))), shape=(n, elim.size))
    return (sp.diags(keep) + P @ M).tocsr()


def _on_sources(corners: np.ndarray, bary: np.ndarray, vsrc: np.ndarray) -> np.ndarray:
    """Which cone samples lie on source vertices only: at a source, on an edge joining two, or on a face of three.

    With the zero-derivative rows at every source, ``φ`` and ``∇φ`` vanish there for every feasible ``φ`` (on a face
    ``(s, t, x)`` with sources ``s, t`` the rows leave ``φ = φ_x λ_x²``, whose value and gradient are 0 on the edge
    ``st``): such a cone sits at its apex, implied by the rows, and with it the program has no strictly feasible
    point (the structured solver broke down on every pair of adjacent sources and Clarabel took over, docs/order2.md).

    Parameters
    ----------
    corners : (k, 3) int ndarray
        The vertices of each sample's face.
    bary : (k, 3) float ndarray
        The samples' barycentric coordinates in those faces.
    vsrc : (p,) int ndarray
        Source vertices.

    Returns
    -------
    (k,) bool ndarray
    """
    return ((bary <= 0) | np.isin(corners, vsrc)).all(axis=1)



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
    np.add.at(G, (kk, slice(None), jj), a_of[dofs[kk, ii]][:, None] * G[kk, :, ii])
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
