"""Continuous piecewise-quadratic (P2) elements on a tetrahedral mesh: the 10-node space, the exact largest cone
violation in a tetrahedron, and the field a solve returns (issue 26).

The order-2 program on tetrahedra (:mod:`cvxgeodesic.formulations_tet_p2`) solves for ``φ = d²`` in this space: one
value per vertex and one per edge midpoint. Inside a solid ``d²`` is exactly quadratic wherever the source is
visible (``|x − s|²``), and P2 represents it exactly on tetrahedra of any shape; ``|∇φ|² − 4φ`` is then itself a
quadratic on each tetrahedron, whose maximum :func:`tet_max_violation` finds exactly (corners, edges, faces,
interior) for the cutting planes.
"""

from __future__ import annotations

import itertools

import numpy as np

from ..errors import ParameterError
from ..mesh.tet_split import TetSplitMesh
from ..mesh.tetmesh import TET_EDGES, TetMesh
from .gradient import gradient_blocks as tet_gradient_blocks

__all__ = ["TET_P2_NODES", "SplitTetP2Field", "TetP2Field", "TetP2Space", "tet_max_violation", "tet_p2_basis"]

#: Barycentric coordinates of the ten nodes of a P2 tetrahedron: the corners, then the midpoints of the edges in
#: :data:`~cvxgeodesic.mesh.tetmesh.TET_EDGES` order (the local DOF order).
TET_P2_NODES = np.vstack([np.eye(4), 0.5 * (np.eye(4)[TET_EDGES[:, 0]] + np.eye(4)[TET_EDGES[:, 1]])])


def tet_p2_basis(bary: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """P2 shape functions of a tetrahedron and their derivatives in the barycentric coordinates.

    ``N_i = λ_i (2λ_i − 1)`` at corner ``i``, ``N_ab = 4 λ_a λ_b`` at the midpoint of edge ``(a, b)``.

    Parameters
    ----------
    bary : (s, 4) float ndarray
        Barycentric coordinates of ``s`` points.

    Returns
    -------
    N : (s, 10) float ndarray
    dN : (s, 10, 4) float ndarray
        ``∂N_a/∂λ_i``; the gradient in a tetrahedron is ``Σ_i dN[..., i] ∇λ_i``.
    """
    lam = np.atleast_2d(np.asarray(bary, dtype=float))
    s = lam.shape[0]
    N = np.empty((s, 10))
    dN = np.zeros((s, 10, 4))
    r = np.arange(s)
    for k in range(4):
        N[:, k] = lam[:, k] * (2 * lam[:, k] - 1)
        dN[:, k, k] = 4 * lam[:, k] - 1
    for e, (a, b) in enumerate(TET_EDGES):
        N[:, 4 + e] = 4 * lam[:, a] * lam[:, b]
        dN[r, 4 + e, a] = 4 * lam[:, b]
        dN[r, 4 + e, b] = 4 * lam[:, a]
    return N, dN


class TetP2Space:
    """Continuous P2 space on a tetrahedral mesh.

    Parameters
    ----------
    mesh : TetMesh

    Attributes
    ----------
    n_dofs : int
        ``n_vertices + n_edges``: vertex DOFs first, then one per edge of ``mesh.edges``.
    tet_dofs : (k, 10) int64 ndarray
        Global DOFs of each tetrahedron in the local order of :func:`tet_p2_basis`.
    lam_grad : (k, 3, 4) float ndarray
        ``∇λ_i`` of each tetrahedron (:func:`~cvxgeodesic.operators.tet.tet_gradient_blocks`), zero on degenerate
        ones.
    degenerate : (k,) bool ndarray
        Tetrahedra left out of the cones (:meth:`TetMesh.degenerate_tets`).
    """

    def __init__(self, mesh: TetMesh):
        self.mesh = mesh
        n = mesh.n_vertices
        self.n_edges = int(mesh.edges.shape[0])
        self.n_dofs = n + self.n_edges
        self.tet_dofs = np.hstack([mesh.T, n + mesh.tet_edges]).astype(np.int64)
        deg = np.zeros(mesh.n_tets, dtype=bool)
        deg[mesh.degenerate_tets()] = True
        self.degenerate = deg
        g = tet_gradient_blocks(mesh)
        g[deg] = 0.0
        self.lam_grad = g

    def weights(self) -> np.ndarray:
        """(n_dofs,) float ndarray: lumped objective weights, a tenth of each tetrahedron's volume to each of its
        nodes (``∫φ ≈ wᵀφ``; the consistent P2 weights are negative at the corners, ``−vol/20``)."""
        per = np.repeat(self.mesh.volumes[:, None] / 10.0, 10, axis=1)
        return np.bincount(self.tet_dofs.ravel(), per.ravel(), minlength=self.n_dofs)

    def value_and_gradient_rows(self, tets: np.ndarray, bary: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Value rows (p, 10) and gradient rows (p, 3, 10) of ``φ`` at points ``bary`` (p, 4) of ``tets`` (p,)."""
        N, dN = tet_p2_basis(bary)
        return N, np.einsum("pai,pci->pca", dN, self.lam_grad[tets])


def tet_max_violation(space: TetP2Space, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Largest ``v = |∇φ|² − 4φ`` in each tetrahedron, exactly.

    ``∇φ`` is linear in a tetrahedron, so ``v`` is a quadratic, determined by its values at the ten nodes. On the
    simplex it is ``λᵀ Q λ`` with ``Q_ii = v(corner i)`` and ``Q_ab = 2 v(mid_ab) − (Q_aa + Q_bb)/2``; its
    maximum is at a corner or at a stationary point of a sub-simplex (an edge, a face, the interior): the
    solution of ``[2Q_SS, −1; 1ᵀ, 0] (λ_S, μ) = (0, 1)`` when it lies inside. 15 candidates per tetrahedron.

    Parameters
    ----------
    space : TetP2Space
    x : (n_dofs,) float ndarray
        ``φ`` (finite).

    Returns
    -------
    vmax : (k,) float ndarray
        ``max v`` over each tetrahedron (0 on degenerate ones).
    bary : (k, 4) float ndarray
        Where it is reached.
    phi_at : (k,) float ndarray
        ``φ`` there.
    """
    k = space.mesh.n_tets
    xt = x[space.tet_dofs]  # (k, 10)
    N, dN = tet_p2_basis(TET_P2_NODES)
    g = np.einsum("sai,tci,ta->tsc", dN, space.lam_grad, xt)  # (k, 10 nodes, 3)
    v = (g**2).sum(-1) - 4 * xt @ N.T  # nodal values of v (N is the identity at the nodes)
    Q = np.zeros((k, 4, 4))
    Q[:, range(4), range(4)] = v[:, :4]
    for e, (a, b) in enumerate(TET_EDGES):
        Q[:, a, b] = Q[:, b, a] = 2 * v[:, 4 + e] - 0.5 * (v[:, a] + v[:, b])
    cands = [np.broadcast_to(np.eye(4), (k, 4, 4))]
    scale = np.abs(Q).max(axis=(1, 2)) + 1e-300
    for size in (2, 3, 4):
        for subset in itertools.combinations(range(4), size):
            S = list(subset)
            M = np.zeros((k, size + 1, size + 1))
            M[:, :size, :size] = 2 * Q[:, S][:, :, S] / scale[:, None, None]
            M[:, :size, size] = -1.0
            M[:, size, :size] = 1.0
            rhs = np.zeros((k, size + 1))
            rhs[:, size] = 1.0
            ok = np.abs(np.linalg.det(M)) > 1e-12
            lam = np.full((k, 4), -1.0)  # rejected below unless solved and inside
            if ok.any():
                sol = np.linalg.solve(M[ok], rhs[ok][..., None])[..., 0]
                full = np.zeros((int(ok.sum()), 4))
                full[:, S] = sol[:, :size]
                lam[ok] = full
            cands.append(lam[:, None, :])
    C = np.concatenate(cands, axis=1)  # (k, 15, 4)
    inside = (C >= -1e-12).all(axis=2)
    C = np.clip(C, 0.0, None)
    C /= np.maximum(C.sum(axis=2, keepdims=True), 1e-300)
    vc = np.einsum("tci,tij,tcj->tc", C, Q, C)
    vc[~inside] = -np.inf
    best = np.argmax(vc, axis=1)
    r = np.arange(k)
    vmax = vc[r, best]
    vmax[space.degenerate] = 0.0
    bary = C[r, best]
    phi_at = np.einsum("ta,ta->t", tet_p2_basis(bary)[0], xt)
    return vmax, bary, phi_at


class TetP2Field:
    """A piecewise-quadratic squared-distance field ``φ`` inside a tetrahedral mesh, evaluated as ``√max(φ, 0)``.

    Parameters
    ----------
    mesh : TetMesh
    phi : (n_vertices + n_edges,) float ndarray
        Squared distance at the vertices then at the midpoints of ``mesh.edges``, in the mesh's units squared;
        ``inf`` on components without a source.
    space : TetP2Space, optional
    """

    def __init__(self, mesh: TetMesh, phi: np.ndarray, space: TetP2Space | None = None):
        self.mesh = mesh
        self.space = space if space is not None else TetP2Space(mesh)
        self.phi = np.asarray(phi, dtype=float)

    @property
    def vertex_distance(self) -> np.ndarray:
        """(n,) float ndarray: ``√max(φ, 0)`` at the vertices."""
        return np.sqrt(np.maximum(self.phi[: self.mesh.n_vertices], 0.0))

    def _checked(self, tets, bary, n_tets: int) -> tuple[np.ndarray, np.ndarray]:
        tets = np.atleast_1d(np.asarray(tets))
        bary = np.atleast_2d(np.asarray(bary, dtype=float))
        if tets.ndim != 1 or not np.issubdtype(tets.dtype, np.integer):
            raise ParameterError("tets must be an int or a 1-D array of tetrahedron indices")
        if bary.shape != (tets.size, 4):
            raise ParameterError(f"bary must have shape ({tets.size}, 4), got {bary.shape}")
        if tets.size and (tets.min() < 0 or tets.max() >= n_tets):
            raise ParameterError(f"tets must lie in [0, {n_tets})")
        if not np.all(np.isfinite(bary)) or np.any(bary < -1e-9) or np.any(np.abs(bary.sum(axis=1) - 1) > 1e-9):
            raise ParameterError("bary rows must be >= 0 and sum to 1")
        return tets.astype(np.int64), bary

    def squared_distance_at(self, tets, bary) -> np.ndarray:
        """``φ`` at points given by tetrahedra and barycentric coordinates.

        Parameters
        ----------
        tets : int or (p,) int array_like
        bary : (4,) or (p, 4) float array_like

        Returns
        -------
        (p,) float ndarray
        """
        tets, bary = self._checked(tets, bary, self.mesh.n_tets)
        return self._phi(tets, bary)

    def _phi(self, tets: np.ndarray, bary: np.ndarray) -> np.ndarray:
        N, _ = tet_p2_basis(bary)
        vals = self.phi[self.space.tet_dofs[tets]]
        bad = np.isinf(vals).any(axis=1)
        out = np.einsum("pa,pa->p", N, np.where(np.isinf(vals), 0.0, vals))
        out[bad] = np.inf
        return out

    def distance_at(self, tets, bary) -> np.ndarray:
        """Distance ``√max(φ, 0)`` at points inside tetrahedra (see :meth:`squared_distance_at`)."""
        return np.sqrt(np.maximum(self.squared_distance_at(tets, bary), 0.0))


class SplitTetP2Field(TetP2Field):
    """:class:`TetP2Field` of a :class:`~cvxgeodesic.mesh.tet_split.TetSplitMesh`, queried with the original
    mesh's tetrahedra."""

    def __init__(self, original: TetMesh, split: TetSplitMesh, phi: np.ndarray, space: TetP2Space | None = None):
        super().__init__(split.mesh, phi, space)
        self.original = original
        self.split = split

    @property
    def vertex_distance(self) -> np.ndarray:
        return super().vertex_distance[: self.split.n_original]

    def squared_distance_at(self, tets, bary) -> np.ndarray:
        tets, bary = self._checked(tets, bary, self.original.n_tets)
        return self._phi(*self.split.locate(tets, bary))
