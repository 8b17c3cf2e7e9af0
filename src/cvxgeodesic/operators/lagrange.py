"""Continuous Lagrange elements on a simplex mesh: one declared element per order, its space on a mesh, the exact
largest cone violation in a cell, and the field a squared-distance solve returns.

An order is a declaration, as scikit-fem declares ``ElementTriP2`` by its DOF counts and Basix names an element by
``create_element(family, cell, degree)``: a :class:`LagrangeElement` says how many DOFs sit on each vertex, edge,
triangle and tetrahedron and where (its nodes, in the barycentric coordinates of each sub-simplex), gives its shape
functions and their derivatives in the barycentric coordinates of any simplex, and owns the search for the largest
``|∇φ|² − 4φ`` in a cell (:meth:`LagrangeElement.max_violation`, :meth:`LagrangeElement.violations`, for the
cutting planes). :data:`ELEMENTS` registers the elements by order (docs/architecture.md, "An element order").

:class:`LagrangeSpace` numbers the DOFs of an order's element on any mesh, whatever its cells
(:attr:`~cvxgeodesic.mesh.simplex.SimplexMesh.reference`): one per vertex, then those of the edges (of
``mesh.edges``, ordered from the edge's lower-numbered vertex to its higher one, so that two cells sharing an edge
agree on its DOFs whatever their local orientation), then the triangles' and the cells' interiors. Order 1 is the
piecewise-linear space of the order-1 program (its gradient rows are
:func:`~cvxgeodesic.operators.gradient.gradient_blocks`); the squared-distance program
(:mod:`cvxgeodesic.problems.squared_distance`) solves for ``φ = d²`` in the space of order 2. Gradients are in each
face's 2-D frame on surfaces and in world coordinates inside solids. :class:`LagrangeField` evaluates a solution inside
cells; :class:`SplitLagrangeField` one on a mesh whose source points were inserted as vertices
(:class:`~cvxgeodesic.mesh.split.SplitMesh`).
"""

from __future__ import annotations

import functools
import itertools
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..mesh.locate import checked_points
from ..mesh.reference import ReferenceSimplex
from ..mesh.simplex import DEGENERATE_TOL, SimplexMesh
from ..mesh.split import SplitMesh
from ..validation import check_order
from .gradient import gradient_blocks
from .metric import Medium

__all__ = ["ELEMENTS", "FLAT_COS", "P1", "P2", "LagrangeElement", "LagrangeField", "LagrangeSpace",
           "SplitLagrangeField", "lagrange_basis", "nodal_basis"]

#: Two cells lie in one affine hull where their unit normals' |cos| is at least this (:attr:`LagrangeSpace.flat_cells`).
FLAT_COS = 1 - 1e-10

#: Shape functions of an element: ``basis(reference, bary (s, c))`` → ``(N (s, n_local), dN (s, n_local, c))``.
Basis = Callable[[ReferenceSimplex, np.ndarray], tuple[np.ndarray, np.ndarray]]
#: The candidates for the largest violation in every cell: ``search(space, x)`` → ``(bary (k, p, c), v (k, p),
#: φ (k, p))``, the cell's corners first (:meth:`LagrangeElement.violations` leaves them out).
Search = Callable[["LagrangeSpace", np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]


def _sub_simplices(reference: ReferenceSimplex, d: int) -> np.ndarray:
    """(l, d + 1) local corners of a cell's sub-simplices of dimension ``d``: the corners, the edges in the order of
    ``reference.edges``, then every ``d + 1`` corners in lexicographic order (the cell itself at ``d = dim``)."""
    if d == 0:
        return np.arange(reference.n_corners)[:, None]
    if d == 1:
        return np.asarray(reference.edges)
    return np.array(list(itertools.combinations(range(reference.n_corners), d + 1)), dtype=np.int64).reshape(-1, d + 1)


@dataclass(frozen=True, eq=False)
class LagrangeElement:
    """A continuous Lagrange element of one order on any simplex, declared by its DOFs.

    Parameters
    ----------
    name : str
        ``"P1"``, ``"P2"``.
    order : int
        The polynomial degree.
    entity_nodes : tuple of 4 float array_likes
        Per vertex, edge, triangle and tetrahedron: the nodes of its DOFs, shape ``(dofs, d + 1)``, in the
        barycentric coordinates of the sub-simplex, its corners ordered by their global index (two cells sharing the
        sub-simplex then agree on each DOF's place). A set of nodes must be mapped onto itself by every permutation
        of the corners. A vertex holds one DOF (``[[1.0]]``): the field is continuous.
    search : callable
        The candidates for the largest ``|∇φ|² − 4φ`` in every cell of a space (:data:`Search`): for order 2
        :func:`quadratic_candidates` (``v`` is itself a quadratic), for order 1 :func:`corner_candidates` (``v`` is
        affine).
    basis_function : callable, optional
        ``basis_function(reference, bary)``: the shape functions at barycentric points and their derivatives in the
        barycentric coordinates, in the local DOF order of :meth:`local_nodes`; default :func:`nodal_basis` of the
        nodes (the polynomials of degree ``order`` that are 1 at one node and 0 at the others).
    second_derivative_function : callable, optional
        ``second_derivative_function(reference)`` → ``(n_local, c, c)``: ``∂²N_a/∂λ_i∂λ_j`` of an element of order 2
        (constant); default from the nodal basis.

    Attributes
    ----------
    dofs : tuple of int
        DOFs per vertex, edge, triangle and tetrahedron (order 2: ``(1, 1, 0, 0)``).

    Raises
    ------
    ParameterError
        Nodes not given for each of the four kinds of sub-simplex, a vertex without its one DOF, or nodes that an
        order of a sub-simplex's corners moves (two cells sharing it would not agree on them).
    """

    name: str
    order: int
    entity_nodes: tuple[Any, ...]
    search: Search = field(repr=False)
    basis_function: Basis | None = field(default=None, repr=False)
    second_derivative_function: Callable[[ReferenceSimplex], np.ndarray] | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        nodes = tuple(np.asarray(n, dtype=float).reshape(-1, d + 1) for d, n in enumerate(self.entity_nodes))
        if len(nodes) != 4 or nodes[0].tolist() != [[1.0]]:
            raise ParameterError(f"element {self.name}: give the nodes of a vertex ([[1.0]]), an edge, a triangle "
                                 "and a tetrahedron")
        object.__setattr__(self, "entity_nodes", nodes)
        for d in range(len(nodes)):
            self._orientations(d)  # raises when a permutation of the corners does not map the nodes onto themselves

    @property
    def dofs(self) -> tuple[int, ...]:
        """DOFs per vertex, edge, triangle and tetrahedron."""
        return tuple(n.shape[0] for n in self.entity_nodes)

    @functools.cache  # noqa: B019 (a handful of elements, each kept for the process)
    def _orientations(self, d: int) -> dict[tuple[int, ...], np.ndarray]:
        """For each order of a sub-simplex's ``d + 1`` corners by global index (``perm[m]``: the local corner that is
        ``m``-th), which global DOF of the sub-simplex each local DOF is."""
        nodes = self.entity_nodes[d]
        out = {}
        for perm in itertools.permutations(range(d + 1)):
            # global DOF j sits at Σ_m nodes[j, m] corner(perm[m]); local DOF i at Σ_m nodes[i, m] corner(m)
            placed = np.zeros_like(nodes)
            placed[:, list(perm)] = nodes
            match = np.all(np.abs(nodes[:, None, :] - placed[None, :, :]) < 1e-12, axis=2)  # (local i, global j)
            if not np.all(match.sum(axis=1) == 1):
                raise ParameterError(f"element {self.name}: the nodes of a {d}-simplex are not mapped onto themselves "
                                     "by every order of its corners")
            out[perm] = np.argmax(match, axis=1) if nodes.size else np.zeros(0, dtype=np.int64)
        return out

    def local_nodes(self, reference: ReferenceSimplex) -> np.ndarray:
        """(n_local, c) barycentric nodes of a cell in the local DOF order: each sub-simplex of
        :func:`_sub_simplices` (corners, edges, triangles, the interior), its nodes in its local corners' order."""
        c = reference.n_corners
        parts = []
        for d in range(reference.dim + 1):
            nodes = self.entity_nodes[d]
            for corners in _sub_simplices(reference, d):
                if nodes.size:
                    X = np.zeros((nodes.shape[0], c))
                    X[:, corners] = nodes
                    parts.append(X)
        return np.vstack(parts)

    def n_local(self, reference: ReferenceSimplex) -> int:
        """DOFs of one cell."""
        return sum(self.dofs[d] * len(_sub_simplices(reference, d)) for d in range(reference.dim + 1))

    def basis(self, reference: ReferenceSimplex, bary: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Shape functions ``N`` (s, n_local) at barycentric points ``bary`` (s, c) and ``∂N_a/∂λ_i``
        (s, n_local, c): the gradient in a cell is ``Σ_i dN[..., i] ∇λ_i``."""
        if self.basis_function is not None:
            return self.basis_function(reference, bary)
        return nodal_basis(self, reference, bary)[:2]

    def second_derivatives(self, reference: ReferenceSimplex) -> np.ndarray:
        """(n_local, c, c) ``∂²N_a/∂λ_i∂λ_j`` of an element of order 2 (constant in the cell)."""
        if self.order != 2:
            raise ParameterError(f"element {self.name}: second derivatives are constant at order 2 only")
        if self.second_derivative_function is not None:
            return self.second_derivative_function(reference)
        return nodal_basis(self, reference, np.eye(reference.n_corners)[:1])[2][0]

    @functools.cache  # noqa: B019
    def node_values(self, reference: ReferenceSimplex) -> np.ndarray:
        """(n_local, n_local) ``N`` at the element's own nodes (the identity for a nodal basis): the values at the
        nodes of a field with DOFs ``x`` are ``node_values @ x``."""
        return self.basis(reference, self.local_nodes(reference))[0]

    def max_violation(self, space: LagrangeSpace, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Largest ``v = |∇φ|² − 4φ`` in each cell, exactly.

        With a medium (:attr:`LagrangeSpace.medium`) ``|∇φ|`` is the norm in it: exact for a medium constant on each
        face; with per-vertex values, the quadratic through ``v``'s values at the nodes (each with its own medium).

        Parameters
        ----------
        space : LagrangeSpace
            Of this element.
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
        C, vc, phi_c = self.search(space, x)
        best = np.argmax(vc, axis=1)
        r = np.arange(C.shape[0])
        vmax = vc[r, best]
        vmax[space.degenerate] = 0.0
        return vmax, C[r, best], phi_c[r, best]

    def violations(self, space: LagrangeSpace, x: np.ndarray, rel_tol: float,
                   cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Every candidate of :attr:`search` off the corners of the given cells where ``v > rel_tol · 4φ``:
        ``(cells (p,), bary (p, dim + 1))``.

        The cutting planes take them all in one round rather than each cell's worst one: a long face whose violation
        spans several local maxima then needs one round instead of one per maximum. The corners are left out: the
        cells the cutting planes run on carry cones at their corners already.
        """
        C, vc, phi_c = self.search(space, x)
        c = space.reference.n_corners
        C, vc, phi_c = C[:, c:], vc[:, c:], phi_c[:, c:]
        sel = np.zeros(C.shape[0], dtype=bool)
        sel[cells] = True
        hit = sel[:, None] & (vc > rel_tol * np.maximum(4 * phi_c, 1e-300)) & (vc > 1e-15)
        f, k = np.nonzero(hit)
        return f.astype(np.int64), C[f, k]

    def __repr__(self) -> str:
        return f"LagrangeElement({self.name!r}, order={self.order}, dofs={self.dofs})"


def _monomials(order: int, c: int) -> np.ndarray:
    """(m, c) exponents of the monomials of degree ``order`` in ``c`` barycentric coordinates (a basis of the
    polynomials of degree ``order`` on the simplex, since ``Σλ = 1``)."""
    return np.array([e for e in itertools.product(range(order + 1), repeat=c) if sum(e) == order], dtype=np.int64)


def nodal_basis(element: LagrangeElement, reference: ReferenceSimplex,
                bary: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The nodal basis of an element's nodes: ``(N (s, n_local), dN (s, n_local, c), d2N (s, n_local, c, c))``.

    The polynomials of degree ``element.order`` written in the monomials of the barycentric coordinates, with
    coefficients from the inverse of their values at :meth:`LagrangeElement.local_nodes` (a Vandermonde matrix).
    """
    lam = np.atleast_2d(np.asarray(bary, dtype=float))
    c = reference.n_corners
    E = _monomials(element.order, c)
    coef = np.linalg.inv(np.prod(element.local_nodes(reference)[:, None, :] ** E[None], axis=2))  # (m, n_local)

    def mono(shift: np.ndarray, factor: np.ndarray) -> np.ndarray:
        p = np.clip(E - shift, 0, None)
        return factor * np.prod(lam[:, None, :] ** p[None], axis=2)

    eye = np.eye(c, dtype=np.int64)
    N = mono(np.zeros(c, dtype=np.int64), np.ones(len(E))) @ coef
    dN = np.stack([mono(eye[i], E[:, i]) @ coef for i in range(c)], axis=2)
    d2N = np.stack([np.stack([mono(eye[i] + eye[j], E[:, i] * (E[:, j] - (i == j))) @ coef for j in range(c)], axis=2)
                    for i in range(c)], axis=2)
    return N, dN, d2N


def lagrange_basis(reference: ReferenceSimplex, bary: np.ndarray, order: int = 2) -> tuple[np.ndarray, np.ndarray]:
    """The shape functions of :data:`P1` and :data:`P2` in closed form, and their barycentric derivatives.

    Order 1: ``N_i = λ_i``. Order 2: ``N_i = λ_i (2λ_i − 1)`` at corner ``i``, then ``N_ab = 4 λ_a λ_b`` at the
    midpoint of each edge ``(a, b)`` of ``reference.edges``.

    Parameters
    ----------
    reference : ReferenceSimplex
    bary : (s, dim + 1) float ndarray
        Barycentric coordinates of ``s`` points.
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
    E = reference.edges
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


def _p2_second_derivatives(reference: ReferenceSimplex) -> np.ndarray:
    """(n_local, c, c) ``∂²N_a/∂λ_i∂λ_j`` of :data:`P2`: 4 on the diagonal at a corner, 4 off it at an edge."""
    c, E = reference.n_corners, reference.edges
    D2 = np.zeros((c + len(E), c, c))
    D2[range(c), range(c), range(c)] = 4.0
    D2[c + np.arange(len(E)), E[:, 0], E[:, 1]] = 4.0
    D2[c + np.arange(len(E)), E[:, 1], E[:, 0]] = 4.0
    return D2


def corner_candidates(space: LagrangeSpace, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The candidates of an order-1 element: its corners (``v = |∇φ|² − 4φ`` is affine in a cell, ``∇φ`` constant),
    ``(bary (k, c, c), v (k, c), φ (k, c))``, ``v = −inf`` on degenerate cells."""
    c = space.reference.n_corners
    corners = np.eye(c)
    N, grad = space.cell_cones(corners)
    xt = x[space.cell_dofs]
    v = (np.einsum("tsca,ta->tsc", grad, xt) ** 2).sum(-1) - 4 * xt @ N.T
    v[space.degenerate] = -np.inf
    return np.broadcast_to(corners, (xt.shape[0], c, c)).copy(), v, xt @ N.T


def quadratic_candidates(space: LagrangeSpace, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The candidates of an order-2 element for the maximum of ``v = |∇φ|² − 4φ`` in every cell: the corners, then
    the stationary point of each sub-simplex (edges, faces, the interior): ``(bary (k, p, c), v (k, p), φ (k, p))``,
    ``v = −inf`` at candidates outside their cell and on degenerate cells.

    ``v`` is itself a quadratic: on the simplex ``v = λᵀ Q λ`` with ``Q_ii = v(corner i)`` and
    ``Q_ab = 2 v(mid_ab) − (Q_aa + Q_bb)/2``; the stationary point of ``v`` on the sub-simplex ``S`` solves
    ``[2Q_SS, −1; 1ᵀ, 0] (λ_S, μ) = (0, 1)``: 7 candidates per triangle, 15 per tetrahedron.
    """
    ref = space.reference
    c, E = ref.n_corners, ref.edges
    corners = np.eye(c)
    points = np.vstack([corners, 0.5 * (corners[E[:, 0]] + corners[E[:, 1]])])  # corners, then edge midpoints
    N, grad = space.cell_cones(points)
    xt = x[space.cell_dofs]
    g = np.einsum("tsca,ta->tsc", grad, xt)
    v = (g**2).sum(-1) - 4 * xt @ N.T  # values of v at the points
    k = xt.shape[0]
    Q = np.zeros((k, c, c))
    Q[:, range(c), range(c)] = v[:, :c]
    for e, (a, b) in enumerate(E):
        Q[:, a, b] = Q[:, b, a] = 2 * v[:, c + e] - 0.5 * (v[:, a] + v[:, b])
    scale = np.abs(Q).max(axis=(1, 2)) + 1e-300
    cands = [np.broadcast_to(corners, (k, c, c))]
    cands += [_stationary_point(Q, scale, list(S)) for size in range(2, c + 1)
              for S in itertools.combinations(range(c), size)]
    C = np.concatenate(cands, axis=1)
    inside = (C >= -1e-12).all(axis=2)
    C = np.clip(C, 0.0, None)
    C /= np.maximum(C.sum(axis=2, keepdims=True), 1e-300)
    vc = np.einsum("tci,tij,tcj->tc", C, Q, C)
    vc[~inside] = -np.inf
    vc[space.degenerate] = -np.inf
    Nc = space.element.basis(ref, C.reshape(-1, c))[0].reshape(k, C.shape[1], -1)
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


_NONE = (np.zeros((0, 2)), np.zeros((0, 3)), np.zeros((0, 4)))

#: The piecewise-linear element: one DOF per vertex (the order-1 program's unknowns).
P1 = LagrangeElement("P1", 1, ([[1.0]], *_NONE), search=corner_candidates,
                     basis_function=functools.partial(lagrange_basis, order=1))
#: The piecewise-quadratic element: one DOF per vertex and one at each edge's midpoint (the squared distance's).
P2 = LagrangeElement("P2", 2, ([[1.0]], [[0.5, 0.5]], *_NONE[1:]), search=quadratic_candidates,
                     basis_function=functools.partial(lagrange_basis, order=2),
                     second_derivative_function=_p2_second_derivatives)
#: The elements by order: :class:`LagrangeSpace` takes ``ELEMENTS[order]``; the orders the API accepts
#: (:data:`cvxgeodesic.capabilities.ORDERS`) are its keys.
ELEMENTS: dict[int, LagrangeElement] = {1: P1, 2: P2}


class LagrangeSpace:
    """The continuous space of an order's element (:data:`ELEMENTS`) on a simplex mesh.

    Parameters
    ----------
    mesh : SimplexMesh
        Of any cells (:attr:`~cvxgeodesic.mesh.simplex.SimplexMesh.reference`).
    order : int
        A key of :data:`ELEMENTS` (:func:`~cvxgeodesic.validation.check_order`).
    medium : Medium, optional
        A travel cost or metric on ``mesh`` (:mod:`cvxgeodesic.operators.metric`, surfaces): the gradient rows
        of :meth:`cell_cones` and :meth:`value_and_gradient_rows` are multiplied by its transform at each point
        (``|∇φ|`` is then the norm in the medium), the weights use its areas, :attr:`cell_longest_edges` and
        :attr:`adjacency` its edge lengths.
    degenerate_tol : float
        Threshold of :meth:`~cvxgeodesic.mesh.simplex.SimplexMesh.degenerate_cells`.

    Attributes
    ----------
    element : LagrangeElement
    reference : ReferenceSimplex
        The mesh's cells.
    dim : int
    n_dofs : int
        One per vertex, then ``element.dofs[1]`` per edge of ``mesh.edges``, then those of the triangles and cells
        (order 2: ``n_vertices + n_edges``).
    cell_dofs : (k, n_local) int64 ndarray
        Global DOFs of each cell in the local order of :meth:`LagrangeElement.local_nodes`.
    edge_dofs : (e, element.dofs[1]) int64 ndarray
        Global DOFs of each edge of ``mesh.edges``, from ``edges[:, 0]`` towards ``edges[:, 1]``.
    cell_edges : (k, dim (dim + 1) / 2) int64 ndarray
        Index into ``mesh.edges`` of each cell's edges, in ``reference.edges`` order.
    gbasis : (k, dim, dim + 1) float ndarray
        ``∇λ_i`` of each cell (:func:`~cvxgeodesic.operators.gradient.gradient_blocks`: in the face's 2-D frame on
        triangles, in world coordinates on tetrahedra), zero on degenerate cells.
    degenerate : (k,) bool ndarray
        Cells left out of the cones (:meth:`SimplexMesh.degenerate_cells`).

    Raises
    ------
    ParameterError
        An order without an element.
    """

    def __init__(self, mesh: SimplexMesh, order: int = 2, medium: Medium | None = None,
                 degenerate_tol: float = DEGENERATE_TOL):
        self.element = ELEMENTS[check_order(order)]
        self.mesh, self.order, self.medium = mesh, self.element.order, medium
        self.reference = mesh.reference
        self.dim = self.reference.dim
        self.n_edges = int(mesh.edges.shape[0])
        self.cell_edges = mesh.cell_edges
        self._number()
        self.degenerate = np.zeros(mesh.n_cells, dtype=bool)
        self.degenerate[mesh.degenerate_cells(degenerate_tol)] = True
        self.gbasis = gradient_blocks(mesh)  # inf/nan on cells of zero measure (no warning): zeroed
        self.gbasis[self.degenerate] = 0.0

    def _number(self) -> None:
        """The generic DOF numbering: :attr:`n_dofs`, :attr:`cell_dofs`, :attr:`edge_dofs` and, per DOF, the
        vertices of the sub-simplex it belongs to (:meth:`on_vertices`)."""
        mesh, ref, element = self.mesh, self.reference, self.element
        cells = mesh.cells.astype(np.int64)
        n = mesh.n_vertices
        blocks, owners = [cells], [(np.arange(n)[:, None], 1)]
        start = n
        for d in range(1, ref.dim + 1):
            per = element.dofs[d]
            if not per:
                continue
            local = _sub_simplices(ref, d)
            if d == 1:
                corners, ids = mesh.edges, self.cell_edges
            elif d == ref.dim:
                corners, ids = np.sort(cells, axis=1), np.arange(mesh.n_cells)[:, None]
            else:
                corners, ids = np.unique(np.sort(cells[:, local], axis=2).reshape(-1, d + 1), axis=0,
                                         return_inverse=True)
                ids = ids.reshape(mesh.n_cells, -1)
            dofs = start + ids[..., None] * per + self._local_order(cells[:, local], d)
            blocks.append(dofs.reshape(mesh.n_cells, -1))
            owners.append((corners, per))
            start += len(corners) * per
        self.n_dofs = int(start)
        self.cell_dofs = np.hstack(blocks).astype(np.int64)
        per_edge = element.dofs[1]
        self.edge_dofs = (n + np.arange(self.n_edges * per_edge, dtype=np.int64)).reshape(self.n_edges, per_edge)
        self._owners = owners

    def _local_order(self, corners: np.ndarray, d: int) -> np.ndarray:
        """(k, l, per) which global DOF of its sub-simplex each local DOF of the sub-simplices with these global
        ``corners`` (k, l, d + 1) is: the element's table for the order of the corners by global index."""
        table = self.element._orientations(d)
        lookup = np.stack(list(table.values()))  # (perms, per)
        if (lookup == lookup[0]).all():  # one DOF, or none moved by any order (order 2's midpoint): no sort needed
            return np.broadcast_to(lookup[0], (*corners.shape[:2], lookup.shape[1]))
        order = np.argsort(corners, axis=2, kind="stable")  # perm[m] = the m-th corner by global index
        key = np.zeros(order.shape[:2], dtype=np.int64)
        for m in range(d + 1):
            key = key * (d + 1) + order[..., m]
        perm_of_key = np.full((d + 1) ** (d + 1), -1, dtype=np.int64)
        for i, perm in enumerate(table):
            code = 0
            for m in perm:
                code = code * (d + 1) + m
            perm_of_key[code] = i
        return lookup[perm_of_key[key]]

    def on_vertices(self, mask: np.ndarray) -> np.ndarray:
        """(n_dofs,) bool ndarray: the DOFs whose vertex, edge, triangle or cell has all its vertices in ``mask``
        (n_vertices,) bool."""
        return np.concatenate([np.repeat(mask[corners].all(axis=1), per) for corners, per in self._owners])

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

    def basis(self, bary: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The element's shape functions at barycentric points of this mesh's cells
        (:meth:`LagrangeElement.basis`)."""
        return self.element.basis(self.reference, bary)

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
        N, dN = self.basis(bary)
        return N, self._transformed(cells, bary, np.einsum("kai,kci->kca", dN, self.gbasis[cells]))

    def cell_cones(self, samples: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Value and gradient rows of ``φ`` at the same sample points of every cell.

        At order 1 ``cell_cones(corners)[1][:, 0]`` is :func:`~cvxgeodesic.operators.gradient.gradient_blocks` (zero on
        degenerate cells): the order-1 program's gradient rows.

        Returns
        -------
        val : (s, n_local) float ndarray
            Same for every cell.
        grad : (k, s, dim, n_local) float ndarray
            ``∇φ(sample) = grad[t, j] @ φ[cell_dofs[t]]``.
        """
        N, dN = self.basis(samples)
        # optimize=True contracts through BLAS: 34 → 2.7 ms over armadillo's 86K faces (2026-12-02)
        grad = np.einsum("sai,tci->tsca", dN, self.gbasis, optimize=True)
        if self.medium is not None:
            m, s = grad.shape[:2]
            if self.medium.varies_in_faces:
                cells, bary = np.repeat(np.arange(m), s), np.tile(samples, (m, 1))
                grad = self._transformed(cells, bary, grad.reshape(m * s, self.dim, -1)).reshape(grad.shape)
            else:  # one transform per face
                T = np.where(self.degenerate[:, None, None], 0.0, self.medium.face_transforms)
                grad = np.einsum("tij,tsja->tsia", T, grad)
        return N, grad

    @functools.cached_property
    def flat_cells(self) -> np.ndarray:
        """(k,) bool ndarray: proper cells where ``d²`` is a quadratic wherever a source is visible: those whose
        edge-neighbours all share their affine hull (:meth:`ReferenceSimplex.normals`; |cos| ≥ :data:`FLAT_COS`
        between the unit normals): every proper tetrahedron (a solid is flat), the faces of a surface whose
        edge-neighbours lie in their plane."""
        mesh = self.mesh
        nrm = self.reference.normals(mesh.V[mesh.cells])  # (k, 3 − dim, 3)
        with np.errstate(divide="ignore", invalid="ignore"):
            nrm = nrm / np.linalg.norm(nrm, axis=2, keepdims=True)
        fe = self.cell_edges.ravel()
        fo = np.repeat(np.arange(mesh.n_cells), self.cell_edges.shape[1])
        _, first = np.unique(fe, return_index=True)
        ref = np.zeros((self.n_edges, *nrm.shape[1:]))
        ref[fe[first]] = nrm[fo[first]]
        cos = np.abs(np.einsum("icj,icj->ic", nrm[fo], ref[fe]))
        edge_cos = np.ones((self.n_edges, nrm.shape[1]))
        np.minimum.at(edge_cos, fe, np.where(np.isfinite(cos), cos, 0.0))
        return (edge_cos[self.cell_edges] >= FLAT_COS).all(axis=(1, 2)) & ~self.degenerate

    def weights(self) -> np.ndarray:
        """Objective weights ``w`` (``∫φ ≈ wᵀφ``): each cell's measure split equally over its nodes (``A/6`` on a
        triangle, ``vol/10`` on a tetrahedron at order 2), as weights of the DOFs (:meth:`LagrangeElement.node_values`;
        the same for a nodal basis).

        Returns
        -------
        (n_dofs,) float ndarray
        """
        A = self.cell_measures
        n_loc = self.cell_dofs.shape[1]
        per_node = self.element.node_values(self.reference).sum(axis=0)  # ones for a nodal basis
        per = (A[:, None] / float(n_loc)) * per_node[None, :]
        return np.bincount(self.cell_dofs.ravel(), per.ravel(), minlength=self.n_dofs)

    def interpolate(self, values_at: Callable[[np.ndarray, np.ndarray], np.ndarray]) -> np.ndarray:
        """(n_dofs,) float ndarray: the DOFs of the field whose values at each cell's nodes are
        ``values_at(cells (p,), bary (p, dim + 1))`` (p,) (the values themselves for a nodal basis)."""
        nodes = self.element.local_nodes(self.reference)
        k, n_loc = self.cell_dofs.shape
        vals = values_at(np.repeat(np.arange(k), n_loc), np.tile(nodes, (k, 1))).reshape(k, n_loc)
        M = self.element.node_values(self.reference)
        if not np.array_equal(M, np.eye(n_loc)):
            vals = np.linalg.solve(M, vals.T).T
        out = np.zeros(self.n_dofs)
        out[self.cell_dofs.ravel()] = vals.ravel()
        return out

    def hessian_rows(self, cells: np.ndarray) -> np.ndarray:
        """Hessian of ``φ`` (constant in an order-2 cell) as a linear map of the cell's DOFs.

        Returns
        -------
        (p, dim, dim, n_local) float ndarray
            ``Hess φ|_t = H[t] @ φ[cell_dofs[t]]``.
        """
        D2 = self.element.second_derivatives(self.reference)
        g = self.gbasis[cells]
        return np.einsum("aij,tci,tdj->tcda", D2, g, g)

    def max_violation(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`LagrangeElement.max_violation` of this space's element."""
        return self.element.max_violation(self, x)

    def violations(self, x: np.ndarray, rel_tol: float, cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`LagrangeElement.violations` of this space's element."""
        return self.element.violations(self, x, rel_tol, cells)


class LagrangeField:
    """A piecewise-polynomial squared-distance field ``φ`` on a simplex mesh, evaluated as ``√max(φ, 0)``.

    Parameters
    ----------
    mesh : SimplexMesh
    phi : (n_dofs,) float ndarray
        The DOFs of ``space`` (order 2: the squared distance at the vertices then at the midpoints of ``mesh.edges``),
        in the mesh's units squared; ``inf`` on components without a source.
    space : LagrangeSpace, optional
        Of ``mesh`` (default: order 2).
    medium : Medium, optional
        The travel cost or metric the field measures, on ``mesh`` in its own units (the
        :class:`~cvxgeodesic.results.Field` protocol's ``medium``); None: Euclidean.
    """

    def __init__(self, mesh: SimplexMesh, phi: np.ndarray, space: LagrangeSpace | None = None,
                 medium: Medium | None = None):
        self.mesh = mesh
        self.space = space if space is not None else LagrangeSpace(mesh)
        self.phi = np.asarray(phi, dtype=float)
        self.medium = medium
        self._dof_mesh = mesh  # the cells of the DOFs, in the field's units (the space may be a scaled copy's)

    @property
    def vertex_distance(self) -> np.ndarray:
        """(n,) float ndarray: ``√max(φ, 0)`` at the vertices."""
        return np.sqrt(np.maximum(self.phi[: self.mesh.n_vertices], 0.0))

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
        return self._phi(*checked_points(self.mesh, cells, bary))

    def _phi(self, cells: np.ndarray, bary: np.ndarray) -> np.ndarray:
        N, _ = self.space.basis(bary)
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
        return self._gradient(*checked_points(self.mesh, cells, bary))

    @functools.cached_property
    def _gbasis(self) -> np.ndarray:
        """(k, dim, dim + 1) ``∇λ_i`` of the DOF mesh's cells in the field's units, zero on degenerate cells."""
        g = gradient_blocks(self._dof_mesh)
        g[self.space.degenerate] = 0.0
        return g

    def _gradient(self, cells: np.ndarray, bary: np.ndarray) -> np.ndarray:
        _, dN = self.space.basis(bary)
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

    def __init__(self, original: SimplexMesh, split: SplitMesh, phi: np.ndarray, space: LagrangeSpace | None = None,
                 medium: Medium | None = None):
        super().__init__(split.mesh, phi, space, medium)
        self.mesh = self.original = original  # the queries name the original cells; the space is the split mesh's
        self.split = split

    def squared_distance_at(self, cells, bary) -> np.ndarray:
        cells, bary = checked_points(self.original, cells, bary)
        return self._phi(*self.split.locate(cells, bary))

    def gradient_at(self, cells, bary) -> np.ndarray:
        cells, bary = checked_points(self.original, cells, bary)
        return self._gradient(*self.split.locate(cells, bary))
