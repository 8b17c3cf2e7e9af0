"""Continuous piecewise-quadratic (P2) elements on a triangle mesh: the space, its operators and the field.

The order-2 formulations (:mod:`cvxgeodesic.formulations_p2`) solve for ``φ = d²`` in this space: one value per
vertex and one per edge midpoint. Here: the shape functions (:func:`p2_basis`, :func:`edge_basis`), the space
(:class:`P2Space`: DOF numbering, per-face gradients of the shape functions, objective weights, flat faces), the
exact largest cone violation on a face (:func:`max_violation`, for the cutting planes), and the field the solve
returns (:class:`P2Field`, evaluated inside faces; :class:`SplitP2Field` for a mesh whose source points were
inserted as vertices, :class:`~cvxgeodesic.mesh.split.SplitMesh`).
"""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from ..mesh.split import SplitMesh
from ..mesh.trimesh import TriMesh
from .gradient import gradient_blocks
from .metric import Medium

__all__ = ["SAMPLES", "WEIGHTS", "P2Field", "P2Space", "SplitP2Field", "edge_basis", "max_violation", "p2_basis",
           "violations"]

#: Barycentric sample points where the cone is imposed on each face (corners, then edge midpoints).
SAMPLES = {
    "nodes": np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0.5, 0.5], [0.5, 0, 0.5], [0.5, 0.5, 0]], float),
}
SAMPLES["corners"] = SAMPLES["nodes"][:3]
SAMPLES["midpoints"] = SAMPLES["nodes"][3:]
SAMPLES["nodes+centroid"] = np.vstack([SAMPLES["nodes"], [[1 / 3, 1 / 3, 1 / 3]]])
SAMPLES["nodes+gauss"] = np.vstack([SAMPLES["nodes"], [[2 / 3, 1 / 6, 1 / 6], [1 / 6, 2 / 3, 1 / 6],
                                                      [1 / 6, 1 / 6, 2 / 3]]])
WEIGHTS = ("lumped", "p2", "mixed")


def p2_basis(bary: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """P2 shape functions and their derivatives in the barycentric coordinates.

    Local DOF order: corners 0, 1, 2, then the midpoints of the edges opposite corners
    0, 1, 2 (edges (1, 2), (2, 0), (0, 1)).

    Parameters
    ----------
    bary : (s, 3) float ndarray
        Barycentric coordinates of ``s`` points.

    Returns
    -------
    N : (s, 6) float ndarray
        Shape function values.
    dN : (s, 6, 3) float ndarray
        ``∂N_a/∂λ_i``; the gradient on a face is ``Σ_i dN[..., i] ∇λ_i``.
    """
    lam = np.atleast_2d(np.asarray(bary, dtype=float))
    s = lam.shape[0]
    N = np.empty((s, 6))
    dN = np.zeros((s, 6, 3))
    for k in range(3):
        N[:, k] = lam[:, k] * (2 * lam[:, k] - 1)
        dN[:, k, k] = 4 * lam[:, k] - 1
        i, j = (k + 1) % 3, (k + 2) % 3
        N[:, 3 + k] = 4 * lam[:, i] * lam[:, j]
        dN[:, 3 + k, i] = 4 * lam[:, j]
        dN[:, 3 + k, j] = 4 * lam[:, i]
    return N, dN


def edge_basis(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """1-D P2 shape functions on an edge ``[0, 1]`` for DOFs (start, midpoint, end) and their t-derivatives."""
    t = np.asarray(t, dtype=float)
    N = np.stack([(1 - t) * (1 - 2 * t), 4 * t * (1 - t), t * (2 * t - 1)], axis=-1)
    dN = np.stack([4 * t - 3, 4 - 8 * t, 4 * t - 1], axis=-1)
    return N, dN


class P2Space:
    """Continuous P2 space on a mesh: DOF numbering, per-face shape-function gradients, weights.

    Parameters
    ----------
    mesh : TriMesh
    medium : Medium, optional
        A travel cost or metric on ``mesh`` (:mod:`cvxgeodesic.operators.metric`): the gradient rows of
        :meth:`face_cones`, :meth:`sample_rows` and :meth:`point_rows` are multiplied by its transform at each
        point (``|∇φ|`` is then the norm in the medium), the weights use its areas and :attr:`edge_lengths` its
        lengths.

    Attributes
    ----------
    n_dofs : int
        ``n_vertices + n_edges``: vertex DOFs first, then one per edge of ``mesh.edges``.
    face_dofs : (m, 6) int64 ndarray
        Global DOFs of each face in the local order of :func:`p2_basis`.
    face_edges : (m, 3) int64 ndarray
        Index into ``mesh.edges`` of the edge opposite each corner.
    lam_grad : (m, 2, 3) float ndarray
        ``∇λ_i`` of each face in its local 2-D frame (``operators.gradient_blocks``).
    degenerate : (m,) bool ndarray
        Faces left out of the face cones.
    """

    def __init__(self, mesh: TriMesh, medium: Medium | None = None):
        self.mesh = mesh
        self.medium = medium
        n, F = mesh.n_vertices, mesh.F
        E = mesh.edges
        self.n_edges = int(E.shape[0])
        self.n_dofs = n + self.n_edges
        fe = mesh.face_edges  # column k: the edge opposite corner k
        self.face_edges = fe
        self.face_dofs = np.hstack([F, n + fe]).astype(np.int64)
        deg = np.zeros(mesh.n_faces, dtype=bool)
        deg[mesh.degenerate_faces()] = True
        self.degenerate = deg
        with np.errstate(divide="ignore", invalid="ignore"):
            g = gradient_blocks(mesh)
        g[deg] = 0.0
        self.lam_grad = g

    @property
    def edge_lengths(self) -> np.ndarray:
        """(e,) float ndarray: lengths of ``mesh.edges`` (in the medium when there is one)."""
        return self.mesh.edge_lengths if self.medium is None else self.medium.edge_lengths

    @property
    def face_longest_edges(self) -> np.ndarray:
        """(m,) float ndarray: the longest of each face's :attr:`edge_lengths`."""
        return self.mesh.face_longest_edges if self.medium is None else self.medium.face_longest_edges

    @property
    def adjacency(self):
        """(n, n) csr_matrix: the edge graph weighted by :attr:`edge_lengths`."""
        return self.mesh.vertex_adjacency if self.medium is None else self.medium.adjacency()

    def _transformed(self, faces: np.ndarray, bary: np.ndarray, grad: np.ndarray) -> np.ndarray:
        """Gradient rows ``grad`` (k, 2, 6) at points of faces, in the medium's norm (unchanged without one)."""
        if self.medium is None:
            return grad
        T = self.medium.transforms(faces, bary)
        T[self.degenerate[faces]] = 0.0
        return np.einsum("kij,kja->kia", T, grad)

    def sample_rows(self, faces: np.ndarray, bary: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Value rows (k, 6) and gradient rows (k, 2, 6) of ``φ`` at points ``bary`` (k, 3) of ``faces`` (k,)."""
        N, dN = p2_basis(bary)
        return N, self._transformed(faces, bary, np.einsum("kai,kci->kca", dN, self.lam_grad[faces]))

    @property
    def flat_faces(self) -> np.ndarray:
        """(m,) bool ndarray: proper faces whose edge-neighbours all lie in their plane (|cos| ≥ 1 − 1e-10)."""
        if getattr(self, "_flat", None) is None:
            nrm = self.mesh.face_normals_unnormalized
            with np.errstate(divide="ignore", invalid="ignore"):
                nrm = nrm / np.linalg.norm(nrm, axis=1, keepdims=True)
            fe = self.face_edges.ravel()
            fo = np.repeat(np.arange(self.mesh.n_faces), 3)
            _, first = np.unique(fe, return_index=True)
            ref = np.zeros((self.n_edges, 3))
            ref[fe[first]] = nrm[fo[first]]
            cos = np.abs(np.einsum("ij,ij->i", nrm[fo], ref[fe]))
            edge_cos = np.ones(self.n_edges)
            np.minimum.at(edge_cos, fe, np.where(np.isfinite(cos), cos, 0.0))
            self._flat = (edge_cos[self.face_edges] >= 1 - 1e-10).all(axis=1) & ~self.degenerate
        return self._flat

    def weights(self, kind: str = "lumped") -> np.ndarray:
        """Objective weights ``w`` (``∫φ ≈ wᵀφ``).

        Parameters
        ----------
        kind : {"lumped", "p2", "mixed"}
            ``"lumped"``: ``A/6`` to each of a face's six nodes. ``"p2"``: the exact
            integrals of the P2 shape functions (0 for corners, ``A/3`` for midpoints).
            ``"mixed"``: their average (``A/12`` and ``A/4``).

        Returns
        -------
        (n_dofs,) float ndarray
        """
        A = self.mesh.face_areas if self.medium is None else self.mesh.face_areas * self.medium.area_ratio
        if kind == "lumped":
            per = np.repeat(A[:, None] / 6.0, 6, axis=1)
        elif kind == "p2":
            per = np.hstack([np.zeros((A.size, 3)), np.repeat(A[:, None] / 3.0, 3, axis=1)])
        elif kind == "mixed":
            per = np.hstack([np.repeat(A[:, None] / 12.0, 3, axis=1), np.repeat(A[:, None] / 4.0, 3, axis=1)])
        else:
            raise ParameterError(f"weights must be one of {WEIGHTS}, got {kind!r}")
        return np.bincount(self.face_dofs.ravel(), per.ravel(), minlength=self.n_dofs)

    def face_cones(self, samples: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Value and gradient rows of ``φ`` at the sample points of every face.

        Returns
        -------
        val : (s, 6) float ndarray
            Same for every face.
        grad : (m, s, 2, 6) float ndarray
            ``∇φ(sample) = grad[t, j] @ φ[face_dofs[t]]`` in the face's 2-D frame.
        """
        N, dN = p2_basis(samples)
        # optimize=True contracts through BLAS: 34 → 2.7 ms over armadillo's 86K faces (2026-12-02)
        grad = np.einsum("sai,tci->tsca", dN, self.lam_grad, optimize=True)
        if self.medium is not None:
            m, s = grad.shape[:2]
            if self.medium.varies_in_faces:
                faces, bary = np.repeat(np.arange(m), s), np.tile(samples, (m, 1))
                grad = self._transformed(faces, bary, grad.reshape(m * s, 2, 6)).reshape(m, s, 2, 6)
            else:  # one transform per face
                T = np.where(self.degenerate[:, None, None], 0.0, self.medium.face_transforms)
                grad = np.einsum("tij,tsja->tsia", T, grad)
        return N, grad

    def hessian_rows(self, faces: np.ndarray) -> np.ndarray:
        """Hessian of ``φ`` (constant on a face) as a linear map of the face's DOFs.

        Returns
        -------
        (k, 2, 2, 6) float ndarray
            ``Hess φ|_t = H[t] @ φ[face_dofs[t]]``.
        """
        g = self.lam_grad[faces]  # (k, 2, 3)
        D2 = np.zeros((6, 3, 3))
        for k in range(3):
            D2[k, k, k] = 4.0
            i, j = (k + 1) % 3, (k + 2) % 3
            D2[3 + k, i, j] = D2[3 + k, j, i] = 4.0
        return np.einsum("aij,tci,tdj->tcda", D2, g, g)

    def point_rows(self, face: int, bary: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Value row (6,) and gradient rows (2, 6) of ``φ`` at one point of one face."""
        N, G = self.sample_rows(np.array([face]), np.asarray(bary, dtype=float).reshape(1, 3))
        return N[0], G[0]


def max_violation(space: P2Space, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Largest ``v = |∇φ|² − 4φ`` on each face, exactly (``v`` is itself a quadratic on the face).

    With a medium (:attr:`P2Space.medium`) ``|∇φ|`` is the norm in it: exact for a medium constant on each face;
    with per-vertex values, the quadratic through ``v``'s values at the six nodes (each with its own medium).

    Parameters
    ----------
    space : P2Space
    x : (n_dofs,) float ndarray
        ``φ`` (finite).

    Returns
    -------
    vmax : (m,) float ndarray
        ``max_T v`` (NaN-free; 0 on degenerate faces).
    bary : (m, 3) float ndarray
        Where it is reached.
    phi_at : (m,) float ndarray
        ``φ`` there.
    """
    C, vc, phi_c = _violation_candidates(space, x)
    m = C.shape[0]
    best = np.argmax(vc, axis=1)
    r = np.arange(m)
    vmax = vc[r, best]
    vmax[space.degenerate] = 0.0
    return vmax, C[r, best], phi_c[r, best]


def violations(space: P2Space, x: np.ndarray, rel_tol: float, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every local maximum of ``v = |∇φ|² − 4φ`` on the given faces (its interior stationary point and the
    stationary points of its three edges) where ``v > rel_tol · 4φ``: ``(faces (k,), bary (k, 3))``.

    The cutting planes take them all in one round rather than each face's worst one: a long face whose
    violation spans several local maxima then needs one round instead of one per maximum.
    """
    C, vc, phi_c = _violation_candidates(space, x)
    C, vc, phi_c = C[:, 3:], vc[:, 3:], phi_c[:, 3:]  # the corners carry cones already on flat faces
    sel = np.zeros(C.shape[0], dtype=bool)
    sel[faces] = True
    hit = sel[:, None] & (vc > rel_tol * np.maximum(4 * phi_c, 1e-300)) & (vc > 1e-15)
    f, c = np.nonzero(hit)
    return f.astype(np.int64), C[f, c]


def _violation_candidates(space: P2Space, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The candidates for the maximum of ``v = |∇φ|² − 4φ`` on every face (corners, the interior stationary point,
    the stationary points of the three edges): ``(bary (m, c, 3), v (m, c), φ (m, c))``, ``v = −inf`` at candidates
    outside their face."""
    nodes = SAMPLES["nodes"]
    N, grad = space.face_cones(nodes)
    xf = x[space.face_dofs]
    g = np.einsum("tsca,ta->tsc", grad, xf)
    v = (g**2).sum(-1) - 4 * np.einsum("sa,ta->ts", N, xf)  # nodal values of the quadratic v
    # candidates: corners, edge extrema, interior extremum, in barycentric coordinates (λ1, λ2), λ0 = 1 − λ1 − λ2
    m = xf.shape[0]
    cands = [np.eye(3)[None].repeat(m, 0)]
    # v(λ) = Σ_a v_a N_a(λ): write v = c0 + b·y + yᵀ A y with y = (λ1, λ2)
    def at(b3):
        Nn, _ = p2_basis(b3.reshape(-1, 3))
        return Nn.reshape(b3.shape[:-1] + (6,))
    # fit the quadratic in y from its nodal values (exact: P2 is unisolvent on the nodes)
    Y = nodes[:, 1:]
    Mfit = np.column_stack([np.ones(6), Y[:, 0], Y[:, 1], Y[:, 0] ** 2, Y[:, 0] * Y[:, 1], Y[:, 1] ** 2])
    coef = np.linalg.solve(Mfit, v.T).T  # (m, 6): c, b1, b2, a11, a12, a22
    c0, b1, b2, a11, a12, a22 = coef.T
    # interior stationary point: [2a11 a12; a12 2a22] y = −b
    det = 4 * a11 * a22 - a12**2
    with np.errstate(divide="ignore", invalid="ignore"):
        y1 = (-b1 * 2 * a22 + b2 * a12) / det
        y2 = (-b2 * 2 * a11 + b1 * a12) / det
    inter = np.stack([1 - y1 - y2, y1, y2], axis=1)
    inter[~np.isfinite(inter).all(axis=1)] = 1 / 3
    cands.append(inter[:, None])
    # edge stationary points: along each edge, v is a 1-D quadratic in t through its three nodal values
    for k in range(3):
        i, j = (k + 1) % 3, (k + 2) % 3
        vi, vm, vj = v[:, i], v[:, 3 + k], v[:, j]
        # q(t) = vi (1−t)(1−2t) + vm 4t(1−t) + vj t(2t−1); q'(t) = 0
        A2 = 2 * vi - 4 * vm + 2 * vj
        B1 = -3 * vi + 4 * vm - vj
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.clip(-B1 / (2 * A2), 0.0, 1.0)
        t = np.where(np.isfinite(t), t, 0.5)
        bb = np.zeros((m, 3))
        bb[:, i] = 1 - t
        bb[:, j] = t
        cands.append(bb[:, None])
    C = np.concatenate(cands, axis=1)  # (m, c, 3)
    inside = (C >= -1e-12).all(axis=2)
    C = np.clip(C, 0.0, None)
    C /= C.sum(axis=2, keepdims=True)
    Nc = at(C)  # (m, c, 6)
    vc = np.einsum("tca,ta->tc", Nc, v)
    vc[~inside] = -np.inf
    vc[space.degenerate] = -np.inf
    return C, vc, np.einsum("tca,ta->tc", Nc, xf)


class P2Field:
    """A piecewise-quadratic squared-distance field ``φ`` on a mesh, evaluated as ``√max(φ, 0)``.

    Parameters
    ----------
    mesh : TriMesh
    phi : (n_vertices + n_edges,) float ndarray
        Squared distance at the vertices then at the midpoints of ``mesh.edges``, in the
        mesh's units squared; ``inf`` on components without a source.
    """

    def __init__(self, mesh: TriMesh, phi: np.ndarray, space: P2Space | None = None):
        self.mesh = mesh
        self.space = space if space is not None else P2Space(mesh)
        self.phi = np.asarray(phi, dtype=float)

    @property
    def vertex_distance(self) -> np.ndarray:
        """(n,) float ndarray: ``√max(φ, 0)`` at the vertices."""
        return np.sqrt(np.maximum(self.phi[: self.mesh.n_vertices], 0.0))

    def squared_distance_at(self, faces, bary) -> np.ndarray:
        """``φ`` at points given by faces and barycentric coordinates.

        Parameters
        ----------
        faces : int or (k,) int array_like
        bary : (3,) or (k, 3) float array_like

        Returns
        -------
        (k,) float ndarray
        """
        faces = np.atleast_1d(np.asarray(faces))
        bary = np.atleast_2d(np.asarray(bary, dtype=float))
        if faces.ndim != 1 or not np.issubdtype(faces.dtype, np.integer):
            raise ParameterError("faces must be an int or a 1-D array of face indices")
        if bary.shape != (faces.size, 3):
            raise ParameterError(f"bary must have shape ({faces.size}, 3), got {bary.shape}")
        if faces.size and (faces.min() < 0 or faces.max() >= self.mesh.n_faces):
            raise ParameterError(f"faces must lie in [0, {self.mesh.n_faces})")
        if not np.all(np.isfinite(bary)) or np.any(bary < -1e-9) or np.any(np.abs(bary.sum(axis=1) - 1) > 1e-9):
            raise ParameterError("bary rows must be >= 0 and sum to 1")
        N, _ = p2_basis(bary)
        vals = self.phi[self.space.face_dofs[faces]]
        with np.errstate(invalid="ignore"):
            out = np.einsum("ka,ka->k", N, np.where(np.isinf(vals), 0.0, vals))
        out[np.isinf(vals).any(axis=1)] = np.inf
        return out

    def distance_at(self, faces, bary) -> np.ndarray:
        """Geodesic distance ``√max(φ, 0)`` at points inside faces (see :meth:`squared_distance_at`)."""
        return np.sqrt(np.maximum(self.squared_distance_at(faces, bary), 0.0))


class SplitP2Field(P2Field):
    """:class:`P2Field` of a :class:`SplitMesh`, queried with the original mesh's faces."""

    def __init__(self, original: TriMesh, split: SplitMesh, phi: np.ndarray, space: P2Space | None = None):
        super().__init__(split.mesh, phi, space)
        self.original = original
        self.split = split

    @property
    def vertex_distance(self) -> np.ndarray:
        return super().vertex_distance[: self.split.n_original]

    def squared_distance_at(self, faces, bary) -> np.ndarray:
        faces = np.atleast_1d(np.asarray(faces))
        bary = np.atleast_2d(np.asarray(bary, dtype=float))
        if faces.ndim == 1 and np.issubdtype(faces.dtype, np.integer) and bary.shape == (faces.size, 3) \
                and (faces.size == 0 or (faces.min() >= 0 and faces.max() < self.original.n_faces)):
            faces, bary = self.split.locate(faces, bary)
        else:
            raise ParameterError(f"faces must be indices in [0, {self.original.n_faces}) and bary of shape (k, 3)")
        return super().squared_distance_at(faces, bary)
