"""Continuous Lagrange elements of order 1 or 2 on a simplex mesh (triangles or tetrahedra): the space, the exact
largest cone violation in a cell, and the field an order-2 solve returns.

The order-2 program (:mod:`cvxgeodesic.formulations_p2`) solves for ``φ = d²`` in the order-2 space: one value per
vertex and one per edge midpoint, on surfaces (:class:`~cvxgeodesic.mesh.trimesh.TriMesh`, gradients in each face's
2-D frame) and inside solids (:class:`~cvxgeodesic.mesh.tetmesh.TetMesh`, gradients in world coordinates) alike:
the simplex dimension ``dim`` (2 or 3) and the order are parameters, not separate modules. Here: the shape
functions (:func:`lagrange_basis`, :func:`edge_basis`), the space (:class:`LagrangeSpace`: DOF numbering, the
barycentric gradients mapped once, objective weights, flat cells, value and gradient rows at any point), the exact
largest ``|∇φ|² − 4φ`` in each cell (:func:`max_violation`, :func:`violations`, for the cutting planes), and the
field (:class:`LagrangeField`, evaluated inside cells; :class:`SplitLagrangeField` for a mesh whose source points
were inserted as vertices, :class:`~cvxgeodesic.mesh.split.SplitMesh`).
"""

from __future__ import annotations

import functools
import itertools
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..mesh.simplex import CELL_EDGES
from ..mesh.split import SplitMesh
from ..validation import check_choice, check_order
from .gradient import gradient_blocks
from .metric import Medium

__all__ = ["SAMPLES", "WEIGHTS", "LagrangeField", "LagrangeSpace", "SplitLagrangeField",
           "edge_basis", "lagrange_basis", "lagrange_nodes", "max_violation", "sample_points", "violations"]

#: Objective weights (:meth:`LagrangeSpace.weights`).
WEIGHTS = ("lumped", "p2")
#: Names of the sample-point sets (:func:`sample_points`).
SAMPLES = ("nodes", "corners", "midpoints", "nodes+centroid", "nodes+gauss")
#: Words for messages: (a cell, cells as an argument name).
CELL_WORDS = {2: ("face", "faces"), 3: ("tetrahedron", "tets")}


def lagrange_nodes(dim: int, order: int = 2) -> np.ndarray:
    """Barycentric coordinates of the nodes of a cell: the corners, then (order 2) the midpoints of
    :data:`~cvxgeodesic.mesh.simplex.CELL_EDGES` (the local DOF order). Shape ``(n_local, dim + 1)``."""
    corners = np.eye(dim + 1)
    if order == 1:
        return corners
    E = CELL_EDGES[dim]
    return np.vstack([corners, 0.5 * (corners[E[:, 0]] + corners[E[:, 1]])])


def sample_points(name: str, dim: int) -> np.ndarray:
    """Barycentric sample points ``(s, dim + 1)`` of one of :data:`SAMPLES` (``"nodes+gauss"``: triangles only)."""
    nodes = lagrange_nodes(dim)
    points = {"nodes": nodes, "corners": nodes[:dim + 1], "midpoints": nodes[dim + 1:],
              "nodes+centroid": np.vstack([nodes, np.full((1, dim + 1), 1.0 / (dim + 1))])}
    if dim == 2:  # the three-point Gauss rule of a triangle
        points["nodes+gauss"] = np.vstack([nodes, [[2 / 3, 1 / 6, 1 / 6], [1 / 6, 2 / 3, 1 / 6],
                                                   [1 / 6, 1 / 6, 2 / 3]]])
    if name not in points:
        raise ParameterError(f"samples {name!r} is not defined on cells of dimension {dim}")
    return points[name]


def lagrange_basis(bary: np.ndarray, order: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """Lagrange shape functions of a simplex and their derivatives in the barycentric coordinates.

    Order 1: ``N_i = λ_i``. Order 2: ``N_i = λ_i (2λ_i − 1)`` at corner ``i``, then ``N_ab = 4 λ_a λ_b`` at the
    midpoint of each edge ``(a, b)`` of :data:`~cvxgeodesic.mesh.simplex.CELL_EDGES`.

    Parameters
    ----------
    bary : (s, dim + 1) float ndarray
        Barycentric coordinates of ``s`` points (``dim`` 2 or 3).
    order : {1, 2}

    Returns
    -------
    N : (s, n_local) float ndarray
        Shape function values (``n_local`` = 3, 6 on triangles, 4, 10 on tetrahedra).
    dN : (s, n_local, dim + 1) float ndarray
        ``∂N_a/∂λ_i``; the gradient in a cell is ``Σ_i dN[..., i] ∇λ_i``.
    """
    lam = np.atleast_2d(np.asarray(bary, dtype=float))
    s, c = lam.shape
    if order == 1:
        return lam.copy(), np.broadcast_to(np.eye(c), (s, c, c)).copy()
    E = CELL_EDGES[c - 1]
    N = np.empty((s, c + len(E)))
    dN = np.zeros((s, c + len(E), c))
    for k in range(c):
        N[:, k] = lam[:, k] * (2 * lam[:, k] - 1)
        dN[:, k, k] = 4 * lam[:, k] - 1
    for e, (a, b) in enumerate(E):
        N[:, c + e] = 4 * lam[:, a] * lam[:, b]
        dN[:, c + e, a] = 4 * lam[:, b]
        dN[:, c + e, b] = 4 * lam[:, a]
    return N, dN


def edge_basis(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """1-D order-2 shape functions on an edge ``[0, 1]`` for DOFs (start, midpoint, end) and their t-derivatives."""
    t = np.asarray(t, dtype=float)
    N = np.stack([(1 - t) * (1 - 2 * t), 4 * t * (1 - t), t * (2 * t - 1)], axis=-1)
    dN = np.stack([4 * t - 3, 4 - 8 * t, 4 * t - 1], axis=-1)
    return N, dN


class LagrangeSpace:
    """Continuous Lagrange space of order 1 or 2 on a triangle or tetrahedral mesh.

    Parameters
    ----------
    mesh : TriMesh or TetMesh
        A :class:`~cvxgeodesic.mesh.simplex.SimplexMesh` of dimension ``dim`` (2 or 3).
    order : {1, 2}
    medium : Medium, optional
        Triangles only: a travel cost or metric on ``mesh`` (:mod:`cvxgeodesic.operators.metric`): the gradient rows
        of :meth:`cell_cones` and :meth:`value_and_gradient_rows` are multiplied by its transform at each point
        (``|∇φ|`` is then the norm in the medium), the weights use its areas, :attr:`cell_longest_edges` and
        :attr:`adjacency` its edge lengths.

    Attributes
    ----------
    dim : int
    n_dofs : int
        ``n_vertices`` (order 1); ``n_vertices + n_edges`` (order 2: vertex DOFs first, then one per edge of
        ``mesh.edges``).
    cell_dofs : (k, n_local) int64 ndarray
        Global DOFs of each cell in the local order of :func:`lagrange_basis`.
    cell_edges : (k, dim (dim + 1) / 2) int64 ndarray
        Index into ``mesh.edges`` of each cell's edges, in :data:`~cvxgeodesic.mesh.simplex.CELL_EDGES` order.
    gbasis : (k, dim, dim + 1) float ndarray
        ``∇λ_i`` of each cell (:func:`~cvxgeodesic.operators.gradient.gradient_blocks`: in the face's 2-D frame on
        triangles, in world coordinates on tetrahedra), zero on degenerate cells.
    degenerate : (k,) bool ndarray
        Cells left out of the cones (:meth:`SimplexMesh.degenerate_cells`).

    Raises
    ------
    ParameterError
        An order other than 1 or 2; a medium on tetrahedra.
    """

    def __init__(self, mesh: Any, order: int = 2, medium: Medium | None = None):
        order = check_order(order)
        if medium is not None and mesh.dim != 2:
            raise ParameterError("a travel cost or metric is defined on surfaces only")
        self.mesh, self.order, self.medium, self.dim = mesh, order, medium, int(mesh.dim)
        n = mesh.n_vertices
        self.n_edges = int(mesh.edges.shape[0])
        self.n_dofs = n + self.n_edges if order == 2 else n
        self.cell_edges = mesh.cell_edges
        cells = mesh.cells.astype(np.int64)
        self.cell_dofs = np.hstack([cells, n + self.cell_edges]).astype(np.int64) if order == 2 else cells
        self.degenerate = np.zeros(mesh.n_cells, dtype=bool)
        self.degenerate[mesh.degenerate_cells()] = True
        self.gbasis = gradient_blocks(mesh)  # inf/nan on cells of zero measure (no warning): zeroed
        self.gbasis[self.degenerate] = 0.0

    @property
    def cell_longest_edges(self) -> np.ndarray:
        """(k,) float ndarray: the longest of each cell's edges (in the medium when there is one)."""
        return self.mesh.cell_longest_edges if self.medium is None else self.medium.face_longest_edges

    @property
    def adjacency(self):
        """(n, n) csr_matrix: the edge graph weighted by the edge lengths (in the medium when there is one)."""
        return self.mesh.vertex_adjacency if self.medium is None else self.medium.adjacency()

    @property
    def cell_measures(self) -> np.ndarray:
        """(k,) float ndarray: areas or volumes (in the medium when there is one)."""
        A = self.mesh.cell_measures
        return A if self.medium is None else A * self.medium.area_ratio

    def _transformed(self, cells: np.ndarray, bary: np.ndarray, grad: np.ndarray) -> np.ndarray:
        """Gradient rows ``grad`` (p, dim, n_local) at points of cells, in the medium's norm (unchanged without)."""
        if self.medium is None:
            return grad
        T = self.medium.transforms(cells, bary)
        T[self.degenerate[cells]] = 0.0
        return np.einsum("kij,kja->kia", T, grad)

    def value_and_gradient_rows(self, cells: np.ndarray, bary: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Value rows (p, n_local) and gradient rows (p, dim, n_local) of ``φ`` at points ``bary`` (p, dim + 1) of
        ``cells`` (p,): ``φ = val @ φ[cell_dofs[cells]]``."""
        N, dN = lagrange_basis(bary, self.order)
        return N, self._transformed(cells, bary, np.einsum("kai,kci->kca", dN, self.gbasis[cells]))

    def cell_cones(self, samples: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Value and gradient rows of ``φ`` at the same sample points of every cell.

        Returns
        -------
        val : (s, n_local) float ndarray
            Same for every cell.
        grad : (k, s, dim, n_local) float ndarray
            ``∇φ(sample) = grad[t, j] @ φ[cell_dofs[t]]``.
        """
        N, dN = lagrange_basis(samples, self.order)
        # optimize=True contracts through BLAS: 34 → 2.7 ms over armadillo's 86K faces (2026-12-02)
        grad = np.einsum("sai,tci->tsca", dN, self.gbasis, optimize=True)
        if self.medium is not None:
            m, s = grad.shape[:2]
            if self.medium.varies_in_faces:
                cells, bary = np.repeat(np.arange(m), s), np.tile(samples, (m, 1))
                grad = self._transformed(cells, bary, grad.reshape(m * s, 2, -1)).reshape(grad.shape)
            else:  # one transform per face
                T = np.where(self.degenerate[:, None, None], 0.0, self.medium.face_transforms)
                grad = np.einsum("tij,tsja->tsia", T, grad)
        return N, grad

    @functools.cached_property
    def flat_cells(self) -> np.ndarray:
        """(k,) bool ndarray: proper cells where ``d²`` is a quadratic wherever a source is visible: every proper
        tetrahedron (a solid is flat), the proper faces whose edge-neighbours all lie in their plane
        (|cos| ≥ 1 − 1e-10)."""
        if self.dim == 3:
            return ~self.degenerate
        nrm = self.mesh.face_normals_unnormalized
        with np.errstate(divide="ignore", invalid="ignore"):
            nrm = nrm / np.linalg.norm(nrm, axis=1, keepdims=True)
        fe = self.cell_edges.ravel()
        fo = np.repeat(np.arange(self.mesh.n_cells), 3)
        _, first = np.unique(fe, return_index=True)
        ref = np.zeros((self.n_edges, 3))
        ref[fe[first]] = nrm[fo[first]]
        cos = np.abs(np.einsum("ij,ij->i", nrm[fo], ref[fe]))
        edge_cos = np.ones(self.n_edges)
        np.minimum.at(edge_cos, fe, np.where(np.isfinite(cos), cos, 0.0))
        return (edge_cos[self.cell_edges] >= 1 - 1e-10).all(axis=1) & ~self.degenerate

    def weights(self, kind: str = "lumped") -> np.ndarray:
        """Objective weights ``w`` (``∫φ ≈ wᵀφ``).

        Parameters
        ----------
        kind : {"lumped", "p2"}
            ``"lumped"``: the cell's measure split equally over its nodes (``A/6`` on a triangle, ``vol/10`` on a
            tetrahedron at order 2). Triangles at order 2 also: ``"p2"``, the exact integrals of the shape
            functions (0 for corners, ``A/3`` for midpoints; on a tetrahedron the corners' would be negative,
            ``−vol/20``).

        Returns
        -------
        (n_dofs,) float ndarray

        Raises
        ------
        ParameterError
            An unknown kind, or ``"p2"`` on tetrahedra or at order 1.
        """
        A = self.cell_measures
        n_loc, c = self.cell_dofs.shape[1], self.dim + 1
        check_choice(kind, "weights", WEIGHTS, lower=False)
        if kind != "lumped" and (self.dim != 2 or self.order != 2):
            raise ParameterError(f"weights={kind!r} is defined for order-2 triangles only; use 'lumped'")
        if kind == "lumped":
            per = np.repeat(A[:, None] / float(n_loc), n_loc, axis=1)
        else:
            per = np.hstack([np.zeros((A.size, c)), np.repeat(A[:, None] / 3.0, 3, axis=1)])
        return np.bincount(self.cell_dofs.ravel(), per.ravel(), minlength=self.n_dofs)

    def hessian_rows(self, cells: np.ndarray) -> np.ndarray:
        """Hessian of ``φ`` (constant in an order-2 cell) as a linear map of the cell's DOFs.

        Returns
        -------
        (p, dim, dim, n_local) float ndarray
            ``Hess φ|_t = H[t] @ φ[cell_dofs[t]]``.
        """
        c = self.dim + 1
        E = CELL_EDGES[self.dim]
        D2 = np.zeros((c + len(E), c, c))
        D2[range(c), range(c), range(c)] = 4.0
        D2[c + np.arange(len(E)), E[:, 0], E[:, 1]] = 4.0
        D2[c + np.arange(len(E)), E[:, 1], E[:, 0]] = 4.0
        g = self.gbasis[cells]
        return np.einsum("aij,tci,tdj->tcda", D2, g, g)


def max_violation(space: LagrangeSpace, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Largest ``v = |∇φ|² − 4φ`` in each cell of an order-2 space, exactly (``v`` is itself a quadratic there).

    With a medium (:attr:`LagrangeSpace.medium`) ``|∇φ|`` is the norm in it: exact for a medium constant on each
    face; with per-vertex values, the quadratic through ``v``'s values at the six nodes (each with its own medium).

    Parameters
    ----------
    space : LagrangeSpace
        Of order 2.
    x : (n_dofs,) float ndarray
        ``φ`` (finite).

    Returns
    -------
    vmax : (k,) float ndarray
        ``max v`` over each cell (0 on degenerate ones).
    bary : (k, dim + 1) float ndarray
        Where it is reached.
    phi_at : (k,) float ndarray
        ``φ`` there.
    """
    C, vc, phi_c = _violation_candidates(space, x)
    best = np.argmax(vc, axis=1)
    r = np.arange(C.shape[0])
    vmax = vc[r, best]
    vmax[space.degenerate] = 0.0
    return vmax, C[r, best], phi_c[r, best]


def violations(space: LagrangeSpace, x: np.ndarray, rel_tol: float, cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every stationary point of ``v = |∇φ|² − 4φ`` on an edge, a face or the interior of the given cells where
    ``v > rel_tol · 4φ``: ``(cells (p,), bary (p, dim + 1))``.

    The cutting planes take them all in one round rather than each cell's worst one: a long face whose violation
    spans several local maxima then needs one round instead of one per maximum. The corners are left out: the
    cells the cutting planes run on carry cones at their corners already.
    """
    C, vc, phi_c = _violation_candidates(space, x)
    c = space.dim + 1
    C, vc, phi_c = C[:, c:], vc[:, c:], phi_c[:, c:]
    sel = np.zeros(C.shape[0], dtype=bool)
    sel[cells] = True
    hit = sel[:, None] & (vc > rel_tol * np.maximum(4 * phi_c, 1e-300)) & (vc > 1e-15)
    f, k = np.nonzero(hit)
    return f.astype(np.int64), C[f, k]


def _violation_candidates(space: LagrangeSpace, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The candidates for the maximum of ``v = |∇φ|² − 4φ`` in every cell: the corners, then the stationary point of
    each sub-simplex (edges, faces, the interior): ``(bary (k, c, dim + 1), v (k, c), φ (k, c))``, ``v = −inf`` at
    candidates outside their cell and on degenerate cells.

    On the simplex ``v = λᵀ Q λ`` with ``Q_ii = v(corner i)`` and ``Q_ab = 2 v(mid_ab) − (Q_aa + Q_bb)/2``; the
    stationary point of ``v`` on the sub-simplex ``S`` solves ``[2Q_SS, −1; 1ᵀ, 0] (λ_S, μ) = (0, 1)``: 7 candidates
    per triangle, 15 per tetrahedron.
    """
    if space.order != 2:
        raise ParameterError("the cone violation is computed on order-2 spaces")
    c = space.dim + 1
    N, grad = space.cell_cones(lagrange_nodes(space.dim))
    xt = x[space.cell_dofs]
    g = np.einsum("tsca,ta->tsc", grad, xt)
    v = (g**2).sum(-1) - 4 * xt @ N.T  # nodal values of v (N is the identity at the nodes)
    k = xt.shape[0]
    Q = np.zeros((k, c, c))
    Q[:, range(c), range(c)] = v[:, :c]
    for e, (a, b) in enumerate(CELL_EDGES[space.dim]):
        Q[:, a, b] = Q[:, b, a] = 2 * v[:, c + e] - 0.5 * (v[:, a] + v[:, b])
    scale = np.abs(Q).max(axis=(1, 2)) + 1e-300
    cands = [np.broadcast_to(np.eye(c), (k, c, c))]
    cands += [_stationary_point(Q, scale, list(S)) for size in range(2, c + 1)
              for S in itertools.combinations(range(c), size)]
    C = np.concatenate(cands, axis=1)
    inside = (C >= -1e-12).all(axis=2)
    C = np.clip(C, 0.0, None)
    C /= np.maximum(C.sum(axis=2, keepdims=True), 1e-300)
    vc = np.einsum("tci,tij,tcj->tc", C, Q, C)
    vc[~inside] = -np.inf
    vc[space.degenerate] = -np.inf
    Nc = lagrange_basis(C.reshape(-1, c))[0].reshape(k, C.shape[1], -1)
    return C, vc, np.einsum("tca,ta->tc", Nc, xt)


def _stationary_point(Q: np.ndarray, scale: np.ndarray, S: list[int]) -> np.ndarray:
    """The stationary point ``(k, 1, c)`` of ``λᵀQλ`` on the sub-simplex of corners ``S`` (−1 where singular)."""
    k, c = Q.shape[:2]
    size = len(S)
    M = np.zeros((k, size + 1, size + 1))
    M[:, :size, :size] = 2 * Q[:, S][:, :, S] / scale[:, None, None]
    M[:, :size, size] = -1.0
    M[:, size, :size] = 1.0
    rhs = np.zeros((k, size + 1))
    rhs[:, size] = 1.0
    ok = np.abs(np.linalg.det(M)) > 1e-12
    lam = np.full((k, c), -1.0)  # rejected by the caller unless solved and inside
    sol = np.linalg.solve(M[ok], rhs[ok][..., None])[..., 0]
    full = np.zeros((int(ok.sum()), c))
    full[:, S] = sol[:, :size]
    lam[ok] = full
    return lam[:, None, :]


class LagrangeField:
    """A piecewise-polynomial squared-distance field ``φ`` on a simplex mesh, evaluated as ``√max(φ, 0)``.

    Parameters
    ----------
    mesh : TriMesh or TetMesh
    phi : (n_dofs,) float ndarray
        Squared distance at the vertices then (order 2) at the midpoints of ``mesh.edges``, in the mesh's units
        squared; ``inf`` on components without a source.
    space : LagrangeSpace, optional
        Of ``mesh`` (default: order 2).
    medium : Medium, optional
        The travel cost or metric the field measures, on ``mesh`` in its own units (the
        :class:`~cvxgeodesic.results.Field` protocol's ``medium``); None: Euclidean.
    """

    def __init__(self, mesh: Any, phi: np.ndarray, space: LagrangeSpace | None = None, medium: Medium | None = None):
        self.mesh = mesh
        self.space = space if space is not None else LagrangeSpace(mesh)
        self.phi = np.asarray(phi, dtype=float)
        self.medium = medium
        self._dof_mesh = mesh  # the cells of the DOFs, in the field's units (the space may be a scaled copy's)

    @property
    def vertex_distance(self) -> np.ndarray:
        """(n,) float ndarray: ``√max(φ, 0)`` at the vertices."""
        return np.sqrt(np.maximum(self.phi[: self.mesh.n_vertices], 0.0))

    def _checked(self, cells, bary, n_cells: int) -> tuple[np.ndarray, np.ndarray]:
        one, arg = CELL_WORDS[self.space.dim]
        c = self.space.dim + 1
        cells = np.atleast_1d(np.asarray(cells))
        bary = np.atleast_2d(np.asarray(bary, dtype=float))
        if cells.ndim != 1 or not np.issubdtype(cells.dtype, np.integer):
            raise ParameterError(f"{arg} must be an int or a 1-D array of {one} indices")
        if bary.shape != (cells.size, c):
            raise ParameterError(f"bary must have shape ({cells.size}, {c}), got {bary.shape}")
        if cells.size and (cells.min() < 0 or cells.max() >= n_cells):
            raise ParameterError(f"{arg} must lie in [0, {n_cells})")
        if not np.all(np.isfinite(bary)) or np.any(bary < -1e-9) or np.any(np.abs(bary.sum(axis=1) - 1) > 1e-9):
            raise ParameterError("bary rows must be >= 0 and sum to 1")
        return cells.astype(np.int64), bary

    def squared_distance_at(self, cells, bary) -> np.ndarray:
        """``φ`` at points given by cells and barycentric coordinates.

        Parameters
        ----------
        cells : int or (p,) int array_like
            Faces or tetrahedra.
        bary : (dim + 1,) or (p, dim + 1) float array_like

        Returns
        -------
        (p,) float ndarray
        """
        return self._phi(*self._checked(cells, bary, self.mesh.n_cells))

    def _phi(self, cells: np.ndarray, bary: np.ndarray) -> np.ndarray:
        N, _ = lagrange_basis(bary, self.space.order)
        vals = self.phi[self.space.cell_dofs[cells]]
        bad = np.isinf(vals).any(axis=1)
        with np.errstate(invalid="ignore"):
            out = np.einsum("pa,pa->p", N, np.where(np.isinf(vals), 0.0, vals))
        out[bad] = np.inf
        return out

    def distance_at(self, cells, bary) -> np.ndarray:
        """Distance ``√max(φ, 0)`` at points inside cells (see :meth:`squared_distance_at`)."""
        return np.sqrt(np.maximum(self.squared_distance_at(cells, bary), 0.0))

    def gradient_at(self, cells, bary) -> np.ndarray:
        """Euclidean gradient ``∇φ / 2√φ`` of the distance at points inside cells, in world coordinates.

        Returns
        -------
        (p, 3) float ndarray
            Zero where ``φ ≤ 0`` (the distance is 0 there), NaN in degenerate cells and where ``φ`` is not finite.
        """
        return self._gradient(*self._checked(cells, bary, self.mesh.n_cells))

    @functools.cached_property
    def _gbasis(self) -> np.ndarray:
        """(k, dim, dim + 1) ``∇λ_i`` of the DOF mesh's cells in the field's units, zero on degenerate cells."""
        g = gradient_blocks(self._dof_mesh)
        g[self.space.degenerate] = 0.0
        return g

    def _gradient(self, cells: np.ndarray, bary: np.ndarray) -> np.ndarray:
        _, dN = lagrange_basis(bary, self.space.order)
        vals = self.phi[self.space.cell_dofs[cells]]
        rows = np.einsum("kai,kci->kca", dN, self._gbasis[cells])
        with np.errstate(invalid="ignore"):
            g = np.einsum("kca,ka->kc", rows, vals)  # ∇φ in each cell's frame
        mesh = self._dof_mesh
        g = mesh.reference.to_world(g[:, :, None], mesh.V[mesh.cells[cells]])[:, 0]
        phi = self._phi(cells, bary)
        with np.errstate(invalid="ignore", divide="ignore"):
            out = np.where((phi > 0)[:, None], g / (2 * np.sqrt(np.maximum(phi, 0.0)))[:, None], 0.0)
        out[~np.isfinite(phi) | self.space.degenerate[cells]] = np.nan
        return out


class SplitLagrangeField(LagrangeField):
    """:class:`LagrangeField` of a :class:`~cvxgeodesic.mesh.split.SplitMesh`, queried with the original mesh's
    cells."""

    def __init__(self, original: Any, split: SplitMesh, phi: np.ndarray, space: LagrangeSpace | None = None,
                 medium: Medium | None = None):
        super().__init__(split.mesh, phi, space, medium)
        self.mesh = self.original = original  # the queries name the original cells; the space is the split mesh's
        self.split = split

    def squared_distance_at(self, cells, bary) -> np.ndarray:
        cells, bary = self._checked(cells, bary, self.original.n_cells)
        return self._phi(*self.split.locate(cells, bary))

    def gradient_at(self, cells, bary) -> np.ndarray:
        cells, bary = self._checked(cells, bary, self.original.n_cells)
        return self._gradient(*self.split.locate(cells, bary))
