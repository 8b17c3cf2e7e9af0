"""Smoothness energies of the order-2 field ``φ = d²`` that vanish on the exact squared distance of flat regions.

On a flat region the squared distance to a point ``p`` is ``|x − p|²``: its Hessian is ``2I`` and its gradient is
continuous. A polyhedral surface is flat face by face and unfolding two faces about their common edge is an
isometry, so wherever the exact field is ``|x − p′|²`` (``p′`` a source unfolded along a window of faces) both
hold there too. The energies below measure the departure from that, and are zero on such fields whatever the
triangulation; they see the ridge's kink (where two fronts meet) and, on curved surfaces, the fronts bent around
saddle vertices. With the order-2 space of :mod:`cvxgeodesic.operators.lagrange`:

* **Hessian** ``E_H(φ) = Σ_t A_t ‖H_t(φ) − 2I‖²_F + E_J(φ)`` (``H_t``: the Hessian of ``φ``, constant on each face,
  in the face's frame);
* **Laplacian** ``E_L(φ) = Σ_t A_t (tr H_t(φ) − 4)² + E_J(φ)``;
* **jump** (the order-2 ``"dirichlet"``) ``E_J(φ)`` alone: the interior penalty on the jumps of the conormal
  derivative across interior edges, ``E_J(φ) = Σ_e (σ / h_e) ∫_e (∂_{ν1} φ|_{t1} + ∂_{ν2} φ|_{t2})² ds``, with
  ``ν_i`` the unit conormal of edge ``e`` in the plane of face ``t_i`` pointing out of ``t_i``, ``h_e = (A_{t1} +
  A_{t2}) / ℓ_e`` (the mean of the two heights over the edge) and ``σ`` = :data:`JUMP_SIGMA`. The jump is linear
  along the edge, so Simpson's rule on its ends and midpoint integrates its square exactly.

A P2 field is only continuous: its Hessian is a distribution with the face Hessians as density and the conormal
jump ``J`` on each edge as a line density, ``J ν⊗ν δ_e``. The face terms see the first, ``E_J`` the second (the
symmetric interior-penalty discretization of ``∫‖Hess φ − 2I‖²`` by continuous elements, as for the biharmonic
problem). ``h_e`` is the width a jump spread over the two faces occupies: spreading a slope change ``J`` evenly
across both faces (total width ``2 h_e``) costs ``J² ℓ / (2 h_e)`` of Hessian energy, which is ``E_J`` with
``σ = 1/2``; the heights rather than the edge length make the penalty follow a face's extent across the edge on
needles. Each energy has units of length² (as the stretch term ``−(1/|S|) ∫φ``), so its weight λ is
dimensionless.

**Edges.** Boundary edges carry no jump term. A non-manifold edge (three or more faces) carries none either: on
such an edge the exact field of a front arriving through one face continues, unfolded, into every other face, so
the conormal derivatives of two receiving faces do not cancel (they are equal) and a pairwise penalty would be
wrong for the exact field. Degenerate faces (:attr:`LagrangeSpace.degenerate`) carry no face term and their edges
no jump term (their shape-function derivatives grow like the inverse altitude).

Every energy is returned as the quadratic ``E(φ) = φᵀQφ + 2gᵀφ + c`` (:class:`SquaredEnergy`); ``Q`` couples the DOFs
of the two faces of each interior edge (:func:`edge_pair_dofs`: nine DOFs per edge).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..errors import ParameterError
from ..validation import check_choice
from .lagrange import LagrangeSpace

__all__ = ["JUMPS", "JUMP_SIGMA", "SQUARED_ENERGIES", "SquaredEnergy", "edge_diamonds", "edge_pair_dofs",
           "face_hessian_energy", "interior_edge_pairs", "jump_energy", "squared_energy", "vertex_jump_energy"]

#: The order-2 energies by the formulation energy name they stand for (``"dirichlet"`` is the jump term alone).
SQUARED_ENERGIES = ("hessian", "laplacian", "dirichlet")
#: ``σ`` of the jump penalty ``(σ / h_e) ∫_e J² ds``: 1/2 is the Hessian energy of a slope change spread evenly
#: over the edge's two faces (module docstring). docs/order2.md, "Smoothing at order 2", has the measurements.
JUMP_SIGMA = 0.5
#: The two forms of the jump term (:func:`squared_energy`).
JUMPS = ("vertex", "p2")


@dataclass
class SquaredEnergy:
    """A quadratic energy ``E(φ) = φᵀQφ + 2gᵀφ + c`` on the P2 DOFs.

    Attributes
    ----------
    Q : (n_dofs, n_dofs) scipy.sparse.csr_matrix
        Symmetric positive semidefinite.
    g : (n_dofs,) float ndarray
    c : float
    cliques : list of int64 ndarray
        The DOF cliques of the program with this energy: every face's DOFs (m, 6: the cones' cliques, degenerate
        faces included) and the pairs of :func:`edge_pair_dofs` (k, 9).
    """

    Q: sp.csr_matrix
    g: np.ndarray
    c: float
    cliques: list[np.ndarray]

    def __call__(self, phi: np.ndarray) -> float:
        """``E(φ)`` for ``φ`` (n_dofs,)."""
        phi = np.asarray(phi, dtype=float)
        return float(phi @ (self.Q @ phi) + 2.0 * self.g @ phi + self.c)


def interior_edge_pairs(space: LagrangeSpace) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The edges that carry a jump term: exactly two incident faces, neither degenerate.

    Parameters
    ----------
    space : LagrangeSpace

    Returns
    -------
    edges : (k,) int64 ndarray
        Indices into ``space.mesh.edges``.
    faces : (k, 2) int64 ndarray
        The two faces of each edge.
    corners : (k, 2) int64 ndarray
        The local corner of each face opposite the edge (the edge is local edge ``corners`` of its face).
    """
    fe = space.cell_edges.ravel()  # face f, local corner k at position 3f + k
    order = np.argsort(fe, kind="stable")
    counts = np.bincount(fe, minlength=space.n_edges)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    two = np.flatnonzero(counts == 2)
    first, second = order[starts[two]], order[starts[two] + 1]
    faces = np.column_stack([first // 3, second // 3]).astype(np.int64)
    corners = np.column_stack([first % 3, second % 3]).astype(np.int64)
    ok = ~space.degenerate[faces].any(axis=1)
    return two[ok].astype(np.int64), faces[ok], corners[ok]


def edge_pair_dofs(space: LagrangeSpace) -> np.ndarray:
    """(k, 9) int64 ndarray: the DOFs of the two faces of each edge of :func:`interior_edge_pairs` (the first face's
    six, then the second face's opposite vertex and its two other midpoints): the cliques the jump term couples."""
    _, faces, corners = interior_edge_pairs(space)
    fd = space.cell_dofs
    t2, k2 = faces[:, 1], corners[:, 1]
    return np.column_stack([fd[faces[:, 0]], fd[t2, k2], fd[t2, 3 + (k2 + 1) % 3], fd[t2, 3 + (k2 + 2) % 3]])


def edge_diamonds(space: LagrangeSpace) -> np.ndarray:
    """(k, 4) int64 ndarray: the ends and the two opposite vertices of each edge of :func:`interior_edge_pairs`:
    the cliques the vertex jump term couples."""
    edges, faces, corners = interior_edge_pairs(space)
    F = space.mesh.cells
    return np.column_stack([space.mesh.edges[edges], F[faces[:, 0], corners[:, 0]], F[faces[:, 1], corners[:, 1]]])


def _conormal_rows(space: LagrangeSpace, faces: np.ndarray, corners: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """(k, 3, 6): ``∂_ν φ`` on face ``faces[i]`` (``ν`` the outward unit conormal of its edge opposite local corner
    ``corners[i]``) at the edge's global endpoint ``ends[i, 0]``, the midpoint and ``ends[i, 1]``, as rows on the
    face's six DOFs."""
    k = faces.size
    F = space.mesh.cells[faces]
    r = np.arange(k)
    loc_a = np.argmax(F == ends[:, :1], axis=1)
    loc_b = np.argmax(F == ends[:, 1:], axis=1)
    bary = np.zeros((k, 3, 3))
    bary[r, 0, loc_a] = 1.0
    bary[r, 1, loc_a] = bary[r, 1, loc_b] = 0.5
    bary[r, 2, loc_b] = 1.0
    _, dN = space.basis(bary.reshape(-1, 3))
    g = space.gbasis[faces]  # (k, 2, 3)
    grad = np.einsum("kpai,kci->kpca", dN.reshape(k, 3, 6, 3), g)
    nu = -g[r, :, corners]  # λ_corner grows towards the corner: its gradient points into the face
    nu /= np.linalg.norm(nu, axis=1, keepdims=True)
    return np.einsum("kc,kpca->kpa", nu, grad)


def _assemble(dofs: np.ndarray, blocks: np.ndarray, n: int) -> sp.csr_matrix:
    """Σ over cliques of the dense blocks (k, c, c) on ``dofs`` (k, c), as an (n, n) csr_matrix (duplicates summed)."""
    c = dofs.shape[1]
    rows = np.repeat(dofs, c, axis=1).ravel()
    cols = np.tile(dofs, (1, c)).ravel()
    return sp.csr_matrix((blocks.ravel(), (rows, cols)), shape=(n, n))


def jump_energy(space: LagrangeSpace, sigma: float = JUMP_SIGMA) -> sp.csr_matrix:
    """``Q_J`` with ``E_J(φ) = φᵀ Q_J φ``: the interior penalty on the P2 field's conormal jumps (``jump="p2"``).

    Parameters
    ----------
    space : LagrangeSpace
    sigma : float
        ``σ`` (:data:`JUMP_SIGMA`).

    Returns
    -------
    (n_dofs, n_dofs) csr_matrix
    """
    edges, faces, corners = interior_edge_pairs(space)
    mesh = space.mesh
    ends = mesh.edges[edges]
    J = np.concatenate([_conormal_rows(space, faces[:, 0], corners[:, 0], ends),
                        _conormal_rows(space, faces[:, 1], corners[:, 1], ends)], axis=2)  # (k, 3, 12)
    # Simpson's rule: exact for J² (J is linear along the edge)
    w = (_jump_weights(space, edges, faces, sigma) / 6.0)[:, None] * np.array([1.0, 4.0, 1.0])
    blocks = np.einsum("kp,kpa,kpb->kab", w, J, J)
    dofs = np.concatenate([space.cell_dofs[faces[:, 0]], space.cell_dofs[faces[:, 1]]], axis=1)
    return _assemble(dofs, blocks, space.n_dofs)


def _jump_weights(space: LagrangeSpace, edges: np.ndarray, faces: np.ndarray, sigma: float = JUMP_SIGMA) -> np.ndarray:
    """(k,) ``σ ℓ_e / h_e`` with ``h_e = (A_{t1} + A_{t2}) / ℓ_e``: the weight of ``J²`` (a constant jump) per edge."""
    ell = space.mesh.edge_lengths[edges]
    return sigma * ell**2 / space.mesh.cell_measures[faces].sum(axis=1)


def vertex_jump_energy(space: LagrangeSpace, sigma: float = JUMP_SIGMA) -> tuple[sp.csr_matrix, np.ndarray, float]:
    """``(Q, g, c)`` of the jump penalty on the conormal derivatives *predicted from the vertex values*
    (``jump="vertex"``, the default).

    On face ``t`` the quadratic with Hessian ``2I`` through ``φ``'s three vertex values is ``φ̂_t = |x − o|² + ℓ_t``
    (``ℓ_t`` the linear interpolant of ``φ − |x − o|²`` at the corners, ``o`` any point): its conormal derivative on
    an edge is that of ``|x − o|²`` plus the constant ``ν·∇ℓ_t``. Unfolded about the edge, ``ν_{t2} = −ν_{t1}``, so
    the ``|x − o|²`` parts cancel and the jump ``Ĵ_e = ν_{t1}·∇ℓ_{t1} + ν_{t2}·∇ℓ_{t2}`` is constant along the edge:
    one linear function of the edge's four vertex values (its ends and the two opposite vertices), plus a constant
    of the geometry. ``Ĵ_e = 0`` wherever both faces carry one ``|x − p|²`` (``φ̂_t`` is then exact), and where each
    face carries its own (a kink along the edge) ``Ĵ_e`` is the true jump. The face term sees the rest (the field's
    departure from ``φ̂_t``), so the two together vanish exactly where the P2 interior penalty does, while coupling
    only vertex DOFs across an edge: the Newton matrix then keeps nearly the face-clique fill (docs/order2.md).

    Parameters
    ----------
    space : LagrangeSpace
    sigma : float
        ``σ`` of ``Σ_e (σ/h_e) ℓ_e Ĵ_e²``.

    Returns
    -------
    Q : (n_dofs, n_dofs) csr_matrix
    g : (n_dofs,) float ndarray
    c : float
    """
    edges, faces, corners = interior_edge_pairs(space)
    mesh = space.mesh
    ends = mesh.edges[edges]
    o = mesh.V[ends].mean(axis=1)  # a point of the edge: distances to it are the same in both faces' planes
    rows, offset, dofs = [], np.zeros(edges.size), []
    for side in (0, 1):
        t, k = faces[:, side], corners[:, side]
        g = space.gbasis[t]  # (k, 2, 3)
        nu = -g[np.arange(t.size), :, k]
        nu /= np.linalg.norm(nu, axis=1, keepdims=True)
        row = np.einsum("kc,kcv->kv", nu, g)  # ν·∇λ_v of the face's corners: the P1 conormal derivative
        q = ((mesh.V[mesh.cells[t]] - o[:, None]) ** 2).sum(axis=2)  # |x − o|² at the corners
        offset += np.einsum("kv,kv->k", row, q)
        rows.append(row)
        dofs.append(mesh.cells[t])
    J = np.concatenate(rows, axis=1)  # (k, 6) on the corners of both faces (the edge's ends twice)
    D = np.concatenate(dofs, axis=1)
    w = _jump_weights(space, edges, faces, sigma)
    Q = _assemble(D, w[:, None, None] * np.einsum("ka,kb->kab", J, J), space.n_dofs)
    g = np.bincount(D.ravel(), (-w * offset)[:, None].repeat(6, axis=1).ravel() * J.ravel(), minlength=space.n_dofs)
    return Q, g, float(w @ offset**2)


def face_hessian_energy(space: LagrangeSpace, kind: str = "hessian") -> tuple[sp.csr_matrix, np.ndarray, float]:
    """``(Q, g, c)`` of ``Σ_t A_t ‖H_t − 2I‖²_F`` (``kind="hessian"``) or ``Σ_t A_t (tr H_t − 4)²``
    (``"laplacian"``) over the proper faces.

    Returns
    -------
    Q : (n_dofs, n_dofs) csr_matrix
    g : (n_dofs,) float ndarray
    c : float
    """
    check_choice(kind, "kind", ("hessian", "laplacian"), lower=False)
    faces = np.flatnonzero(~space.degenerate)
    A = space.mesh.cell_measures[faces]
    H = space.hessian_rows(faces)  # (k, 2, 2, 6)
    T = H[:, 0, 0] + H[:, 1, 1]  # (k, 6): tr H
    if kind == "hessian":
        blocks = A[:, None, None] * np.einsum("kcda,kcdb->kab", H, H)
        gf, c = -2.0 * A[:, None] * T, 8.0 * A.sum()  # ‖H − 2I‖² = ‖H‖² − 4 tr H + 8
    else:
        blocks = A[:, None, None] * np.einsum("ka,kb->kab", T, T)
        gf, c = -4.0 * A[:, None] * T, 16.0 * A.sum()  # (tr H − 4)² = (tr H)² − 8 tr H + 16
    dofs = space.cell_dofs[faces]
    g = np.bincount(dofs.ravel(), gf.ravel(), minlength=space.n_dofs)
    return _assemble(dofs, blocks, space.n_dofs), g, float(c)


def squared_energy(space: LagrangeSpace, name: str, sigma: float = JUMP_SIGMA,
                   jump: str = "vertex") -> SquaredEnergy:
    """A smoothness energy of the order-2 field by name.

    Parameters
    ----------
    space : LagrangeSpace
    name : {"hessian", "laplacian", "dirichlet"}
        ``"hessian"``: ``Σ_t A_t ‖H_t − 2I‖² + E_J``; ``"laplacian"``: ``Σ_t A_t (tr H_t − 4)² + E_J``;
        ``"dirichlet"``: ``E_J`` alone (module docstring).
    sigma : float
        ``σ`` of the jump term (:data:`JUMP_SIGMA`).
    jump : {"vertex", "p2"}
        ``"vertex"``: the jumps of the conormal derivatives predicted from the vertex values
        (:func:`vertex_jump_energy`; couples four vertex DOFs per edge); ``"p2"``: the P2 field's own jumps
        (:func:`jump_energy`; nine DOFs per edge, 2.7× the Cholesky fill on lucy_20k).

    Returns
    -------
    SquaredEnergy

    Examples
    --------
    Zero on the squared distance to a point of the plane, on any triangulation:

    >>> import numpy as np
    >>> import cvxgeodesic as cg
    >>> from cvxgeodesic.operators.lagrange import LagrangeSpace
    >>> mesh = cg.grid_plane(6, jitter=0.3)
    >>> space = LagrangeSpace(mesh)
    >>> X = np.vstack([mesh.V, mesh.V[mesh.edges].mean(axis=1)])
    >>> E = squared_energy(space, "hessian")
    >>> abs(E(((X - [0.3, 0.2, 0.0]) ** 2).sum(axis=1))) < 1e-10
    True
    """
    check_choice(name, "order-2 energy", SQUARED_ENERGIES, lower=False)
    if not (np.isfinite(sigma) and sigma > 0):
        raise ParameterError(f"sigma must be a finite number > 0, got {sigma!r}")
    check_choice(jump, "jump", JUMPS, lower=False)
    n = space.n_dofs
    if jump == "p2":
        QJ, gJ, cJ = jump_energy(space, sigma), np.zeros(n), 0.0
        cliques = [space.cell_dofs, edge_pair_dofs(space)]
    else:
        QJ, gJ, cJ = vertex_jump_energy(space, sigma)
        cliques = [space.cell_dofs, edge_diamonds(space)]
    if name == "dirichlet":
        Q, g, c = QJ, gJ, cJ
    else:
        QH, gH, cH = face_hessian_energy(space, name)
        Q, g, c = (QH + QJ).tocsr(), gH + gJ, cH + cJ
    Q.sum_duplicates()
    return SquaredEnergy(Q, g, c, cliques)
