"""A travel cost and a Riemannian metric on a triangle mesh: lengths, gradient norms and areas in the medium.

A :class:`Medium` says how long a tangent vector ``u`` at a surface point ``x`` is: ``c(x) √(uᵀ M(x) u)``, with
``c`` a travel cost (time per unit length, ``1/speed``; 1 when not given) and ``M`` a symmetric 3×3 tensor (the
identity when not given) restricted to the face's plane, where it must be positive definite. The distance it
defines is the travel time; its gradient bound ``‖∇d‖_{M⁻¹} ≤ c`` is, in a face's orthonormal frame ``E_t``
(:func:`~cvxgeodesic.operators.gradient.triangle_frames`) with ``c² E_tᵀ M E_t = L Lᵀ``, the Euclidean bound
``‖L⁻¹ ∇d‖ ≤ 1``: every gradient row of every cone is multiplied by the 2×2 :meth:`Medium.transforms`, so the
programs keep their shape (and the structured solver its fast triangle kernels). A cost is the isotropic case
``M = c² I``; both go through the same transform.

Where the medium is read:

* **per face** (``(m,)`` costs, ``(m, 3, 3)`` tensors, or one constant): constant on each face; an edge's length is
  the smaller of its faces' lengths (a path along the edge inside the cheaper face, so it bounds the distance from
  above);
* **per vertex** (``(n,)``, ``(n, 3, 3)``): the tensor and the cost are interpolated linearly inside faces (the
  cost itself, not the speed ``1/c``: measured below); edges and segments are integrated along their length (5-point
  Gauss–Legendre: exact for a medium constant along them, and for a linear cost along an edge);
* order 1 takes each face's medium at its centroid; order 2 takes it at each cone's sample point.

Every length, transform and area ratio here is divided by :attr:`Medium.scale` (a power of two near the medium's
typical length factor): the programs then see lengths of the mesh's own size, whatever the units of the cost, and
the strategies multiply the field back by it (exactly, as it is a power of two).
"""

from __future__ import annotations

import functools
import math
from typing import Any, cast

import numpy as np
import scipy.sparse as sp

from ..mesh.simplex import SimplexMesh
from ..mesh.trimesh import TriMesh
from ..validation import check_cost, check_metric, check_plane_metric
from .gradient import triangle_frames

__all__ = ["Medium", "make_medium"]

# A per-vertex cost is interpolated linearly, not the speed 1/c (which the rule "speed" did until 2026-12-03, never
# selected). Measured 2026-12-02 on the linear-velocity medium (speed 1 + 2y on a jittered 60 × 60 Delaunay grid of
# the unit square, source near (0.5, 0.2), qclp): mean relative error cost 1.814 % / speed 1.824 % at order 1,
# 0.114 % / 0.117 % at order 2 (the two differ by O(h²) inside a face); the cost is read as the piecewise-linear
# field it is given as, like the tensors. Per-face values at the centroids: 1.84 % / 0.245 %.

_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(5)
_TAU = 0.5 * (_NODES + 1.0)  # Gauss-Legendre nodes and weights on [0, 1]
_W = 0.5 * _WEIGHTS
_CENTROID = np.full(3, 1.0 / 3.0)
_KIND_NAMES = {"constant": "constant", "vertices": "per-vertex", "faces": "per-face"}


class Medium:
    """A travel cost and/or a metric on one mesh (see the module docstring).

    Parameters
    ----------
    mesh : TriMesh
    cost : (1,), (n,) or (m,) float ndarray, optional
        Validated positive costs (:func:`~cvxgeodesic.validation.check_cost`).
    cost_kind : {"constant", "vertices", "faces"}, optional
    metric : (1, 3, 3), (n, 3, 3) or (m, 3, 3) float ndarray, optional
        Validated symmetric tensors (:func:`~cvxgeodesic.validation.check_metric`).
    metric_kind : {"constant", "vertices", "faces"}, optional
    scale : float, optional
        The normalization (computed when None; :meth:`on` passes it on).
    check : bool
        Check that the metric is positive definite in every face's plane.

    Raises
    ------
    ParameterError
        The metric is not positive definite in some face's plane (the message names the first tensor and face).

    Examples
    --------
    >>> import numpy as np
    >>> from cvxgeodesic.mesh import grid_plane
    >>> mesh = grid_plane(2)
    >>> med = Medium(mesh, cost=np.array([3.0]), cost_kind="constant")
    >>> med.scale, float(med.edge_lengths[0] * med.scale / mesh.edge_lengths[0])
    (4.0, 3.0)
    """

    def __init__(self, mesh: TriMesh, cost: np.ndarray | None = None, cost_kind: str | None = None,
                 metric: np.ndarray | None = None, metric_kind: str | None = None, *,
                 scale: float | None = None, check: bool = True) -> None:
        self.mesh = mesh
        self.cost = None if cost is None else np.asarray(cost, dtype=np.float64)
        self.cost_kind = None if cost is None else cost_kind
        self.metric = None if metric is None else np.asarray(metric, dtype=np.float64)
        self.metric_kind = None if metric is None else metric_kind
        with np.errstate(invalid="ignore", divide="ignore"):
            self._ex, self._ey = triangle_frames(mesh)
        self.scale = 1.0
        if check and self.metric is not None:
            self._check_positive()
        self.scale = self._normalization() if scale is None else float(scale)
        self._cache: dict[str, Any] = {}
        self.notes: list[str] = []

    # -- what it is ------------------------------------------------------------------------------------------
    def describe(self) -> dict[str, str]:
        """``{"cost": ..., "metric": ...}``: ``"constant"``, ``"per-vertex"`` or ``"per-face"`` for what was given
        (for ``info.extra``)."""
        out = {}
        if self.cost is not None:
            out["cost"] = _KIND_NAMES[self.cost_kind or "constant"]
        if self.metric is not None:
            out["metric"] = _KIND_NAMES[self.metric_kind or "constant"]
        return out

    @property
    def cost_ratio(self) -> float:
        """The largest over the smallest travel cost (1 without a cost, or with one number)."""
        if self.cost is None or self.cost.ndim == 0:
            return 1.0
        return float(self.cost.max() / self.cost.min())

    @property
    def varies_in_faces(self) -> bool:
        """True when something is given per vertex (the medium then varies inside faces)."""
        return "vertices" in (self.cost_kind, self.metric_kind)

    def on(self, mesh: SimplexMesh) -> Medium:
        """The same medium on a mesh with the same vertices and faces (e.g. scaled by :func:`unit_mesh`): a triangle
        surface, as this medium's."""
        return Medium(cast(TriMesh, mesh), self.cost, self.cost_kind, self.metric, self.metric_kind, scale=self.scale,
                      check=False)

    def split(self, split_mesh: SimplexMesh, parent: np.ndarray, points) -> Medium:
        """The medium on a mesh whose faces were split around inserted vertices.

        Parameters
        ----------
        split_mesh : TriMesh (a medium lives on a surface: the capability table refuses it elsewhere)
            The original vertices first, then one per point.
        parent : (m',) int ndarray
            The original face of each face of ``split_mesh``.
        points : sequence of objects with ``face`` and ``bary``
            The inserted vertices, in order.
        """
        cost, metric = self.cost, self.metric
        faces = np.array([p.face for p in points], dtype=np.int64)
        bary = np.array([p.bary for p in points], dtype=np.float64).reshape(-1, 3)
        if self.cost_kind == "faces":
            cost = self.cost[parent]
        elif self.cost_kind == "vertices":
            cost = np.concatenate([self.cost, self._cost_at(faces, bary)])
        if self.metric_kind == "faces":
            metric = self.metric[parent]
        elif self.metric_kind == "vertices":
            metric = np.concatenate([self.metric, np.einsum("kc,kcij->kij", bary, self.metric[self.mesh.F[faces]])])
        return Medium(cast(TriMesh, split_mesh), cost, self.cost_kind, metric, self.metric_kind, scale=self.scale,
                      check=False)

    def subset(self, mesh: TriMesh, vertices: np.ndarray, faces: np.ndarray) -> Medium:
        """The medium on a mesh made of some of this one's faces (a patch around a source).

        Parameters
        ----------
        mesh : TriMesh
            The smaller mesh.
        vertices : (p,) int ndarray
            This medium's vertex of each vertex of ``mesh``.
        faces : (k,) int ndarray
            This medium's face of each face of ``mesh``.

        Returns
        -------
        Medium
            The values taken as they are, the normalization kept.
        """
        def taken(values: np.ndarray | None, kind: str | None) -> np.ndarray | None:
            if values is None or kind == "constant":
                return values
            return values[faces] if kind == "faces" else values[vertices]

        return Medium(mesh, taken(self.cost, self.cost_kind), self.cost_kind, taken(self.metric, self.metric_kind),
                      self.metric_kind, scale=self.scale, check=False)

    # -- pointwise values ------------------------------------------------------------------------------------
    def _cost_at(self, faces: np.ndarray, bary: np.ndarray) -> np.ndarray:
        """(k,) cost at points (unnormalized; 1 without a cost)."""
        if self.cost is None:
            return np.ones(len(faces))
        if self.cost_kind == "constant":
            return np.full(len(faces), self.cost[0])
        if self.cost_kind == "faces":
            return self.cost[faces]
        return np.einsum("kc,kc->k", bary, self.cost[self.mesh.F[faces]])

    def _bilinear(self, faces: np.ndarray, bary: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """(k,) ``uᵀ M v`` with the metric at points (no cost; the identity without a metric)."""
        if self.metric is None:
            return np.einsum("ki,ki->k", u, v)
        if self.metric_kind == "constant":
            return np.einsum("ki,ij,kj->k", u, self.metric[0], v)
        if self.metric_kind == "faces":
            return np.einsum("ki,kij,kj->k", u, self.metric[faces], v)
        F = self.mesh.F
        out = np.zeros(len(faces))
        for c in range(3):  # corner by corner: (k, 3, 3) at a time
            out += bary[:, c] * np.einsum("ki,kij,kj->k", u, self.metric[F[faces, c]], v)
        return out

    def plane(self, faces: np.ndarray, bary: np.ndarray) -> np.ndarray:
        """``c² E_tᵀ M E_t / scale²`` at points: the medium in each face's 2-D frame.

        Parameters
        ----------
        faces : (k,) int ndarray
        bary : (k, 3) or (3,) float ndarray

        Returns
        -------
        (k, 2, 2) float ndarray
            NaN on faces without a plane (zero area).
        """
        faces = np.asarray(faces, dtype=np.int64)
        bary = np.broadcast_to(np.asarray(bary, dtype=np.float64), (len(faces), 3))
        ex, ey = self._ex[faces], self._ey[faces]
        c2 = (self._cost_at(faces, bary) / self.scale) ** 2
        a, b, d = self._bilinear(faces, bary, ex, ex), self._bilinear(faces, bary, ex, ey), \
            self._bilinear(faces, bary, ey, ey)
        return (c2[:, None, None] * np.stack([np.stack([a, b], -1), np.stack([b, d], -1)], -2))

    def transforms(self, faces: np.ndarray, bary: np.ndarray) -> np.ndarray:
        """``T = L⁻¹`` with ``L Lᵀ`` = :meth:`plane`: ``‖T g‖ = ‖g‖`` in the medium's dual norm, for a gradient
        ``g`` in the face's frame (so ``‖T g‖ ≤ 1`` is ``‖∇d‖_{M⁻¹} ≤ c``).

        Returns
        -------
        (k, 2, 2) float ndarray
            Lower triangular; the identity on faces without a plane.
        """
        P = self.plane(faces, bary)
        a, b, d = P[:, 0, 0], P[:, 0, 1], P[:, 1, 1]
        with np.errstate(invalid="ignore", divide="ignore"):
            l11 = np.sqrt(a)
            l21 = b / l11
            l22 = np.sqrt(d - l21 * l21)
            T = np.zeros_like(P)
            T[:, 0, 0] = 1.0 / l11
            T[:, 1, 0] = -l21 / (l11 * l22)
            T[:, 1, 1] = 1.0 / l22
        bad = ~np.isfinite(T).all(axis=(1, 2))
        T[bad] = np.eye(2)
        return T

    # -- per-face and per-edge data (normalized) -------------------------------------------------------------
    @functools.cached_property
    def face_transforms(self) -> np.ndarray:
        """(m, 2, 2) float ndarray: :meth:`transforms` at each face's centroid (order 1)."""
        return self.transforms(np.arange(self.mesh.n_faces), _CENTROID)

    @functools.cached_property
    def area_ratio(self) -> np.ndarray:
        """(m,) float ndarray: area in the medium over Euclidean area, ``√det`` of :meth:`plane` at the centroid
        (1 on faces without a plane)."""
        P = self.plane(np.arange(self.mesh.n_faces), _CENTROID)
        with np.errstate(invalid="ignore"):
            r = np.sqrt(P[:, 0, 0] * P[:, 1, 1] - P[:, 0, 1] ** 2)
        return np.where(np.isfinite(r), r, 1.0)

    def segment_lengths(self, faces: np.ndarray, bary_a: np.ndarray, bary_b: np.ndarray) -> np.ndarray:
        """Lengths in the medium of straight segments inside faces.

        Parameters
        ----------
        faces : (k,) int ndarray
        bary_a, bary_b : (k, 3) float ndarray
            The ends' barycentric coordinates in those faces.

        Returns
        -------
        (k,) float ndarray
            ``∫ c √(uᵀ M u)`` along each segment (divided by :attr:`scale`).
        """
        faces = np.asarray(faces, dtype=np.int64)
        bary_a = np.broadcast_to(np.asarray(bary_a, dtype=np.float64), (len(faces), 3))
        bary_b = np.broadcast_to(np.asarray(bary_b, dtype=np.float64), (len(faces), 3))
        T = self.mesh.V[self.mesh.F[faces]]
        u = np.einsum("kc,kcj->kj", bary_b - bary_a, T)
        # along the segment the interpolated tensor, hence uᵀMu, and c are linear
        qa, qb = self._bilinear(faces, bary_a, u, u), self._bilinear(faces, bary_b, u, u)
        ca, cb = self._cost_at(faces, bary_a), self._cost_at(faces, bary_b)
        q = np.maximum(np.outer(1 - _TAU, qa) + np.outer(_TAU, qb), 0.0)
        c = np.outer(1 - _TAU, ca) + np.outer(_TAU, cb)
        return (_W @ (c * np.sqrt(q))) / self.scale

    def vector_lengths(self, faces: np.ndarray, U: np.ndarray) -> np.ndarray:
        """(k,) lengths ``c √(uᵀ M u)`` of vectors ``U`` (k, 3) with the medium at the centroids of ``faces``
        (normalized)."""
        faces = np.asarray(faces, dtype=np.int64)
        bary = np.broadcast_to(_CENTROID, (len(faces), 3))
        q = np.maximum(self._bilinear(faces, bary, U, U), 0.0)
        return self._cost_at(faces, bary) * np.sqrt(q) / self.scale

    def edge_speed(self, faces: np.ndarray, a: np.ndarray, b: np.ndarray, t: float) -> np.ndarray:
        """(k,) ``c √(uᵀ M u)`` at ``(1 − t)·corner a + t·corner b`` of each face, ``u`` the edge from corner ``a``
        to corner ``b``: the edge's length per unit ``t`` there (normalized)."""
        faces = np.asarray(faces, dtype=np.int64)
        k = len(faces)
        bary = np.zeros((k, 3))
        bary[np.arange(k), a] = 1 - t
        bary[np.arange(k), b] += t
        V, F = self.mesh.V, self.mesh.F
        u = V[F[faces, b]] - V[F[faces, a]]
        q = np.maximum(self._bilinear(faces, bary, u, u), 0.0)
        return self._cost_at(faces, bary) * np.sqrt(q) / self.scale

    @functools.cached_property
    def edge_lengths(self) -> np.ndarray:
        """(e,) float ndarray: the length of each edge of ``mesh.edges``, the smaller of its faces' (normalized)."""
        mesh = self.mesh
        m = mesh.n_faces
        eye = np.eye(3)
        k = np.tile(np.arange(3), m)
        faces = np.repeat(np.arange(m), 3)
        per = self.segment_lengths(faces, eye[(k + 1) % 3], eye[(k + 2) % 3])
        out = np.full(len(mesh.edges), np.inf)
        np.minimum.at(out, mesh.cell_edges.ravel(), per)
        return out

    @property
    def face_longest_edges(self) -> np.ndarray:
        """(m,) float ndarray: the longest of each face's three :attr:`edge_lengths`."""
        return self.edge_lengths[self.mesh.cell_edges].max(axis=1)

    def adjacency(self) -> sp.csr_matrix:
        """(n, n) csr_matrix: the edge graph weighted by :attr:`edge_lengths` (as ``mesh.vertex_adjacency``)."""
        if "adjacency" not in self._cache:
            E, w = self.mesh.edges, np.maximum(self.edge_lengths, 1e-300)  # a zero weight would be no edge
            n = self.mesh.n_vertices
            self._cache["adjacency"] = sp.coo_matrix((np.r_[w, w], (np.r_[E[:, 0], E[:, 1]], np.r_[E[:, 1], E[:, 0]])),
                                                     shape=(n, n)).tocsr()
        return self._cache["adjacency"]

    def least_crossings(self, q0: np.ndarray, ends: np.ndarray, faces: np.ndarray, q1: np.ndarray) -> np.ndarray | None:
        """The polyline of least length in the medium from ``q0`` across a chain of edges to ``q1``.

        A second-order cone program (Clarabel) in the crossings' parameters ``t_k ∈ [0, 1]`` along their edges:
        each piece's length ``‖Lᵀ u‖`` (``L Lᵀ`` the face's :meth:`plane` at its centroid, ``u`` in its frame) is
        the norm of an affine function of them.

        Parameters
        ----------
        q0, q1 : (3,) float ndarray
            The fixed ends: ``q0`` in ``faces[0]``, ``q1`` in ``faces[-1]``.
        ends : (K, 2) int ndarray
            The vertices ``(a, c)`` of each edge crossed: the crossing is ``(1 − t) V[a] + t V[c]``.
        faces : (K + 1,) int ndarray
            The face of each piece (piece ``k`` ends on edge ``k``).

        Returns
        -------
        (K,) float ndarray or None
            ``t``; None when Clarabel does not solve it.
        """
        import clarabel

        V = self.mesh.V
        K = len(ends)
        a_pt, dirs = V[ends[:, 0]], V[ends[:, 1]] - V[ends[:, 0]]
        L = np.linalg.cholesky(self.plane(faces, _CENTROID))
        R = np.stack([self._ex[faces], self._ey[faces]], 1)  # (K + 1, 2, 3): the face's frame
        Mj = np.einsum("kji,kjl->kil", L, R)  # (K + 1, 2, 3): u -> Lᵀ (u in the frame)
        base = np.vstack([q0, a_pt, q1])
        # variables (t_1..t_K, s_0..s_K); piece j from point j to j + 1: (s_j, Mj (x_{j+1} − x_j)) ∈ SOC(3)
        n_var, n_soc = 2 * K + 1, 3 * (K + 1)
        j = np.arange(K + 1)
        w = np.einsum("kil,kl->ki", Mj, base[1:] - base[:-1])  # (K + 1, 2): the pieces at t = 0
        rows = [3 * j]
        cols = [K + j]
        vals = [-np.ones(K + 1)]
        for i in range(2):
            nxt = j[:-1]  # + t_{j+1} Mj dirs_{j+1}: pieces 0..K-1
            rows.append(3 * nxt + 1 + i)
            cols.append(nxt)
            vals.append(-np.einsum("kl,kl->k", Mj[nxt, i], dirs[nxt]))
            prv = j[1:]  # − t_j Mj dirs_j: pieces 1..K
            rows.append(3 * prv + 1 + i)
            cols.append(prv - 1)
            vals.append(np.einsum("kl,kl->k", Mj[prv, i], dirs[prv - 1]))
        k = np.arange(K)  # t_k >= 0 and 1 − t_k >= 0
        rows += [n_soc + k, n_soc + K + k]
        cols += [k, k]
        vals += [-np.ones(K), np.ones(K)]
        rhs = np.r_[np.column_stack([np.zeros(K + 1), w]).ravel(), np.zeros(K), np.ones(K)]
        A = sp.csc_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                          shape=(n_soc + 2 * K, n_var))
        settings = clarabel.DefaultSettings()
        settings.verbose = False
        # the length is flat at its minimum: a gap of ε moves the crossings by about √ε (measured: the default
        # 1e-8 bowed a straight path by 6e-5)
        settings.tol_gap_abs = settings.tol_gap_rel = settings.tol_feas = 1e-14
        cones = [clarabel.SecondOrderConeT(3)] * (K + 1) + [clarabel.NonnegativeConeT(2 * K)]
        q = np.r_[np.zeros(K), np.ones(K + 1)]
        sol = clarabel.DefaultSolver(sp.csc_matrix((n_var, n_var)), q, A, rhs, cones, settings).solve()
        if str(sol.status) not in ("Solved", "AlmostSolved"):
            return None
        return np.clip(np.asarray(sol.x)[:K], 0.0, 1.0)

    # -- totals in the user's units --------------------------------------------------------------------------
    @property
    def surface_area(self) -> float:
        """Area of the surface in the medium (the user's units: not normalized)."""
        return float((self.mesh.face_areas * self.area_ratio).sum()) * self.scale**2

    @property
    def mean_edge_length(self) -> float:
        """Mean edge length in the medium (not normalized)."""
        return float(self.edge_lengths.mean()) * self.scale if len(self.mesh.edges) else 0.0

    # -- construction helpers --------------------------------------------------------------------------------
    def _check_positive(self) -> None:
        mesh, kind = self.mesh, self.metric_kind or "constant"
        m = mesh.n_faces
        faces, bary = np.arange(m), _CENTROID
        owner = faces if kind == "faces" else np.zeros(m, dtype=np.int64)
        if kind == "vertices":  # each corner's tensor in its face's plane (at the corner, the tensor is its own)
            faces, bary, owner = np.repeat(faces, 3), np.tile(np.eye(3), (m, 1)), mesh.F.ravel()
        saved, self.cost = self.cost, None  # the cost is positive: the metric alone decides
        try:
            P = self.plane(faces, bary)
        finally:
            self.cost = saved
        check_plane_metric(P, owner, faces, kind)

    def _normalization(self) -> float:
        """A power of two near the median length factor ``det(plane)^{1/4}`` of the faces."""
        P = self.plane(np.arange(self.mesh.n_faces), _CENTROID)
        with np.errstate(invalid="ignore"):
            f = (P[:, 0, 0] * P[:, 1, 1] - P[:, 0, 1] ** 2) ** 0.25
        f = f[np.isfinite(f) & (f > 0)]
        if not f.size:
            return 1.0
        return math.ldexp(1.0, round(math.log2(float(np.median(f)))))


def make_medium(mesh: SimplexMesh, cost=None, metric=None) -> Medium | None:
    """The :class:`Medium` of user input, validated (None when neither is given).

    Parameters
    ----------
    mesh : SimplexMesh
        A triangle surface when ``cost`` or ``metric`` is given (the capability table refuses a medium on any other
        mesh before).
    cost : float or (n,) or (m,) float array_like, optional
        Travel cost (time per unit length): one number, per vertex or per face.
    metric : (3, 3), (n, 3, 3) or (m, 3, 3) float array_like, optional
        Symmetric tensors, positive definite in each face's plane.

    Returns
    -------
    Medium or None
        Its ``notes`` say how an array of ambiguous length (``n == m``) was read.

    Raises
    ------
    ParameterError
        A wrong shape, a cost that is not positive and finite, a tensor that is not finite, symmetric or positive
        definite in a face's plane: the message names the first.
    """
    if cost is None and metric is None:
        return None
    n, m = mesh.n_vertices, mesh.n_cells
    c, ck = check_cost(cost, n, m) if cost is not None else (None, None)
    g, gk = check_metric(metric, n, m) if metric is not None else (None, None)
    medium = Medium(cast(TriMesh, mesh), c, ck, g, gk)
    medium.notes = [f"{name} of length {n} read per vertex (the mesh has as many vertices as faces)"
                    for name, kind in (("cost", ck), ("metric", gk)) if kind == "vertices" and n == m]
    return medium
