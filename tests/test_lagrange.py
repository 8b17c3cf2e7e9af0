"""The declared elements and the one Lagrange space of both dimensions (``operators/lagrange.py``) and the one split
mesh (``mesh/split.py``): the elements' DOF counts, shape functions and generic DOF numbering, the exact largest cone
violation, the field, and source points inserted as vertices, each checked on triangles and on tetrahedra."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic import capabilities
from cvxgeodesic.errors import ParameterError, SourceError
from cvxgeodesic.mesh.split import SplitMesh
from cvxgeodesic.mesh.tet_generate import tet_box
from cvxgeodesic.operators.gradient import gradient_blocks
from cvxgeodesic.operators.lagrange import (
    ELEMENTS,
    P1,
    P2,
    LagrangeElement,
    LagrangeField,
    LagrangeSpace,
    corner_candidates,
    quadratic_candidates,
)
from cvxgeodesic.problems.formulations import MeshOperators


def _mesh(dim: int, seed: int = 3):
    return cg.grid_plane(4, jitter=0.3, seed=seed) if dim == 2 else tet_box(2, jitter=0.2, seed=seed)


def _point(dim: int, cell: int, bary):
    return cg.SurfacePoint(cell, bary) if dim == 2 else cg.VolumePoint(cell, bary)


def _nodes_xyz(mesh) -> np.ndarray:
    E = mesh.edges
    return np.vstack([mesh.V, 0.5 * (mesh.V[E[:, 0]] + mesh.V[E[:, 1]])])


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("order", [1, 2])
def test_basis_is_nodal_and_a_partition_of_unity(dim, order):
    element, ref = ELEMENTS[order], _mesh(dim).reference
    N, dN = element.basis(ref, element.local_nodes(ref))
    np.testing.assert_allclose(N, np.eye(N.shape[1]), atol=1e-15)
    lam = np.random.default_rng(0).dirichlet(np.ones(dim + 1), 20)
    N, dN = element.basis(ref, lam)
    np.testing.assert_allclose(N.sum(axis=1), 1.0, atol=1e-14)
    # a constant has no gradient: Σ_a ∂N_a/∂λ_i is the same for every i (3 at order 2), and Σ_i ∇λ_i = 0
    np.testing.assert_allclose(dN.sum(axis=1), 3.0 if order == 2 else 1.0, atol=1e-13)


@pytest.mark.parametrize("dim", [2, 3])
def test_cell_edges_follow_the_local_edge_order(dim):
    mesh = _mesh(dim)
    ends = np.sort(mesh.cells[:, mesh.reference.edges], axis=2)  # (k, e, 2)
    np.testing.assert_array_equal(mesh.edges[LagrangeSpace(mesh).cell_edges], ends)


@pytest.mark.parametrize("dim", [2, 3])
def test_order2_reproduces_quadratics_and_their_gradient_norms(dim):
    mesh = _mesh(dim)
    space = LagrangeSpace(mesh)
    rng = np.random.default_rng(1)
    A, b, c = rng.normal(size=(3, 3)), rng.normal(size=3), 0.3
    if dim == 2:  # the grid lies in z = 0: a quadratic of (x, y)
        A[2], A[:, 2], b[2] = 0.0, 0.0, 0.0
    f = lambda X: np.einsum("pi,ij,pj->p", X, A, X) + X @ b + c  # noqa: E731
    grad = lambda X: X @ (A + A.T) + b  # noqa: E731
    phi = f(_nodes_xyz(mesh))
    cells = rng.integers(0, mesh.n_cells, 40)
    bary = rng.dirichlet(np.ones(dim + 1), 40)
    X = np.einsum("pk,pkj->pj", bary, mesh.V[mesh.cells[cells]])
    val, gr = space.value_and_gradient_rows(cells, bary)
    dofs = phi[space.cell_dofs[cells]]
    np.testing.assert_allclose(np.einsum("pa,pa->p", val, dofs), f(X), atol=1e-12)
    # the gradient in each face's 2-D frame on triangles, in world coordinates on tetrahedra: compare norms
    np.testing.assert_allclose(np.linalg.norm(np.einsum("pca,pa->pc", gr, dofs), axis=1),
                               np.linalg.norm(grad(X), axis=1), atol=1e-10)
    assert space.weights().sum() == pytest.approx(mesh.cell_measures.sum(), rel=1e-13)


def test_an_order_without_an_element_is_refused():
    with pytest.raises(ParameterError, match=r"^order must be 1 \(P1\) or 2 \(P2\), got 3$"):
        LagrangeSpace(_mesh(2), order=3)


def test_the_orders_the_api_accepts_are_the_declared_elements():
    # capabilities.py is a leaf module and cannot import the elements: this test keeps its ORDERS true
    assert capabilities.ORDERS == tuple(sorted(ELEMENTS))
    assert all(ELEMENTS[order].order == order for order in ELEMENTS)


@pytest.mark.parametrize("dim", [2, 3])
def test_elements_declare_their_dofs_per_vertex_edge_triangle_and_tetrahedron(dim):
    mesh = _mesh(dim)
    ref = mesh.reference
    assert P1.dofs == (1, 0, 0, 0) and P2.dofs == (1, 1, 0, 0)
    assert (P1.n_local(ref), P2.n_local(ref)) == ((3, 6) if dim == 2 else (4, 10))
    for element in (P1, P2):
        space = LagrangeSpace(mesh, element.order)
        assert space.element is element and space.cell_dofs.shape == (mesh.n_cells, element.n_local(ref))
    assert LagrangeSpace(mesh, 1).n_dofs == mesh.n_vertices
    assert LagrangeSpace(mesh, 2).n_dofs == mesh.n_vertices + len(mesh.edges)


@pytest.mark.parametrize("dim", [2, 3])
def test_order1_gradient_rows_are_the_gradient_blocks_of_the_order1_program(dim):
    mesh = _mesh(dim)
    space = LagrangeSpace(mesh, 1)
    rows = space.cell_cones(np.eye(dim + 1))[1]  # (k, corners, dim, dim + 1): constant in each cell
    np.testing.assert_array_equal(rows, np.repeat(gradient_blocks(mesh)[:, None], dim + 1, axis=1))
    # the order-1 builder takes its gradient rows from this space: bit for bit the same blocks
    np.testing.assert_array_equal(MeshOperators(mesh).gradient_blocks, rows[:, 0])


def _p3() -> LagrangeElement:
    """A cubic element declared by its nodes only (two per edge, one per triangle): the nodal basis and the
    generic numbering, with edges whose two DOFs must be matched across cells by orientation."""
    return LagrangeElement("P3", 3, ([[1.0]], [[2 / 3, 1 / 3], [1 / 3, 2 / 3]], [[1 / 3, 1 / 3, 1 / 3]],
                                     np.zeros((0, 4))), search=corner_candidates)


@pytest.mark.parametrize("dim", [2, 3])
def test_generic_numbering_puts_each_dof_at_one_place_whatever_the_cells_orientation(dim, monkeypatch):
    mesh = _mesh(dim)
    monkeypatch.setitem(ELEMENTS, 3, _p3())
    monkeypatch.setattr(capabilities, "ORDERS", (1, 2, 3))
    space = LagrangeSpace(mesh, 3)
    triangles = np.array(list(itertools.combinations(range(dim + 1), 3)))  # of each cell: itself, or its faces
    n_tri = len(np.unique(np.sort(mesh.cells[:, triangles], axis=2).reshape(-1, 3), axis=0))
    assert space.n_dofs == mesh.n_vertices + 2 * len(mesh.edges) + n_tri
    # every cell places each of its DOFs at the same point of space as every other cell holding it
    X = np.einsum("li,kix->klx", space.element.local_nodes(mesh.reference), mesh.V[mesh.cells])
    where = np.full((space.n_dofs, 3), np.nan)
    where[space.cell_dofs.ravel()] = X.reshape(-1, 3)
    np.testing.assert_allclose(where[space.cell_dofs], X, atol=1e-12)
    # so the space is continuous and holds the cubics: a cubic's values at the DOFs' points interpolate it anywhere
    cubic = lambda P: P[:, 0] ** 3 - 2 * P[:, 0] * P[:, 1] ** 2 + P[:, 2] ** 2 * P[:, 1] + P[:, 1]  # noqa: E731
    rng = np.random.default_rng(4)
    cells, bary = rng.integers(0, mesh.n_cells, 50), rng.dirichlet(np.ones(dim + 1), 50)
    val, _ = space.value_and_gradient_rows(cells, bary)
    P = np.einsum("pi,pix->px", bary, mesh.V[mesh.cells[cells]])
    np.testing.assert_allclose(np.einsum("pa,pa->p", val, cubic(where)[space.cell_dofs[cells]]), cubic(P),
                               atol=1e-12)


@pytest.mark.parametrize("dim", [2, 3])
def test_an_element_declared_by_its_nodes_alone_is_the_closed_form_one(dim, monkeypatch):
    # the default basis (nodal_basis: the Vandermonde inverse of the monomials at the nodes) of P2's nodes is P2:
    # the same values, gradients and Hessians in every cell
    mesh = _mesh(dim)
    by_nodes = LagrangeElement("P2-by-nodes", 2, P2.entity_nodes, search=quadratic_candidates)
    rng = np.random.default_rng(5)
    cells, bary = rng.integers(0, mesh.n_cells, 30), rng.dirichlet(np.ones(dim + 1), 30)
    spaces = [LagrangeSpace(mesh, 2)]
    monkeypatch.setitem(ELEMENTS, 2, by_nodes)
    spaces.append(LagrangeSpace(mesh, 2))
    (v0, g0), (v1, g1) = (s.value_and_gradient_rows(cells, bary) for s in spaces)
    np.testing.assert_allclose(v1, v0, atol=1e-12)
    np.testing.assert_allclose(g1, g0, atol=1e-10)
    np.testing.assert_allclose(spaces[1].hessian_rows(cells), spaces[0].hessian_rows(cells), atol=1e-9)
    np.testing.assert_array_equal(spaces[1].cell_dofs, spaces[0].cell_dofs)


def test_nodes_that_an_order_of_the_corners_moves_are_refused():
    # one node a third along each edge: the two cells of an edge would place it at two points
    with pytest.raises(ParameterError, match="not mapped onto themselves by every order of its corners"):
        LagrangeElement("bad", 2, ([[1.0]], [[2 / 3, 1 / 3]], np.zeros((0, 3)), np.zeros((0, 4))),
                        search=corner_candidates)


@pytest.mark.parametrize("dim", [2, 3])
def test_max_violation_is_the_maximum_over_each_cell(dim):
    mesh = _mesh(dim, seed=4)
    space = LagrangeSpace(mesh)
    rng = np.random.default_rng(2)
    nodes = _nodes_xyz(mesh)
    # a random field (v mostly convex: its maximum at corners), and half a squared distance from a point inside,
    # whose v = −|x − x0|² + noise is concave: its maximum on facets, edges or inside
    x0 = [0.4, 0.45, 0.55][:dim] + [0.0] * (3 - dim)
    fields = [rng.uniform(0.0, 1.0, space.n_dofs),
              0.5 * ((nodes - x0) ** 2).sum(axis=1) + 1e-3 * rng.normal(size=space.n_dofs)]
    samples = np.vstack([rng.dirichlet(np.ones(dim + 1), 3000), P2.local_nodes(mesh.reference)])
    inside = sum(_check_max(space, x, samples) for x in fields)
    # the second field's maxima are away from the corners in the cells near x0 (measured: 13 of 32 faces on the
    # grid, where most faces' nearest point to x0 is a corner; 46 of 48 tetrahedra)
    assert inside >= (8 if dim == 2 else mesh.n_cells // 2)


@pytest.mark.parametrize("dim", [2, 3])
def test_the_order1_element_finds_its_largest_violation_at_a_corner(dim):
    # at order 1 ∇φ is constant in a cell and v = |∇φ|² − 4φ affine: its maximum is at a corner
    mesh = _mesh(dim, seed=4)
    space = LagrangeSpace(mesh, 1)
    x = np.random.default_rng(3).uniform(0.0, 1.0, space.n_dofs)
    samples = np.vstack([np.random.default_rng(6).dirichlet(np.ones(dim + 1), 500), np.eye(dim + 1)])
    assert _check_max(space, x, samples) == 0  # every maximum at a corner


def _check_max(space, x, samples) -> int:
    vmax, bary, phi_at = space.max_violation(x)
    for t in range(space.mesh.n_cells):
        val, gr = space.value_and_gradient_rows(np.full(len(samples), t), samples)
        xt = x[space.cell_dofs[t]]
        v = (np.einsum("pca,a->pc", gr, xt) ** 2).sum(axis=1) - 4 * val @ xt
        assert vmax[t] >= v.max() - 1e-9  # never below a sample (v is O(1) here)
        vb_val, vb_gr = space.value_and_gradient_rows(np.array([t]), bary[t][None])
        at = float((vb_gr[0] @ xt) @ (vb_gr[0] @ xt) - 4 * vb_val[0] @ xt)
        assert at == pytest.approx(vmax[t], abs=1e-9)  # reached where it says
        assert phi_at[t] == pytest.approx(float(vb_val[0] @ xt))
        assert bary[t].min() >= 0 and bary[t].sum() == pytest.approx(1.0)
    return int(np.count_nonzero(bary.max(axis=1) < 1 - 1e-9))


@pytest.mark.parametrize("dim", [2, 3])
def test_split_mesh_keeps_the_measure_and_locates_points(dim):
    mesh = _mesh(dim, seed=5)
    inside, on_edge = (([0.2, 0.3, 0.5], [0.5, 0.5, 0.0]) if dim == 2 else
                       ([0.1, 0.2, 0.3, 0.4], [0.5, 0.5, 0.0, 0.0]))
    pts = [_point(dim, 3, inside), _point(dim, 20, on_edge)]
    split = SplitMesh(mesh, pts)
    assert type(split.mesh) is type(mesh)
    assert split.mesh.cell_measures.sum() == pytest.approx(mesh.cell_measures.sum(), rel=1e-13)
    assert split.mesh.cell_measures.min() > 0
    np.testing.assert_allclose(split.mesh.V[split.point_vertices], [p.position(mesh) for p in pts])
    around = np.flatnonzero(np.isin(mesh.cells, mesh.cells[20, :2]).sum(axis=1) == 2)  # the cells of the edge
    assert split.mesh.n_cells == mesh.n_cells + dim + around.size
    np.testing.assert_array_equal(np.bincount(split.cell_parent, minlength=mesh.n_cells)[[3, *around]],
                                  [dim + 1] + [2] * around.size)
    rng = np.random.default_rng(3)
    cells = np.concatenate([[3] * 20, [20] * 20, rng.integers(0, mesh.n_cells, 20)])
    bary = rng.dirichlet(np.ones(dim + 1), 60)
    X = np.einsum("pk,pkj->pj", bary, mesh.V[mesh.cells[cells]])
    t2, b2 = split.locate(cells, bary)
    assert b2.min() >= 0
    np.testing.assert_allclose(np.einsum("pk,pkj->pj", b2, split.mesh.V[split.mesh.cells[t2]]), X, atol=1e-12)


@pytest.mark.parametrize("dim", [2, 3])
def test_split_mesh_refuses_two_points_in_a_cell_and_a_point_at_a_vertex(dim):
    mesh = _mesh(dim)
    b = np.full(dim + 1, 1.0 / (dim + 1))
    one = "face" if dim == 2 else "tetrahedron"
    with pytest.raises(SourceError, match=f"two source points (on|in) {one} 0: order 2 takes at most one per {one}"):
        SplitMesh(mesh, [_point(dim, 0, b), _point(dim, 0, np.roll(b + np.eye(dim + 1)[0], 1) / 2)])
    with pytest.raises(SourceError, match="lies at a vertex"):
        SplitMesh(mesh, [_point(dim, 0, np.eye(dim + 1)[0])])


@pytest.mark.parametrize("dim", [2, 3])
def test_field_checks_its_queries(dim):
    mesh = _mesh(dim)
    fld = LagrangeField(mesh, np.zeros(mesh.n_vertices + mesh.edges.shape[0]))
    arg = "faces" if dim == 2 else "tets"
    b = np.full(dim + 1, 1.0 / (dim + 1))
    assert fld.distance_at(0, b).tolist() == [0.0]
    with pytest.raises(ParameterError, match=f"{arg} must lie in \\[0, {mesh.n_cells}\\)"):
        fld.distance_at(mesh.n_cells, b)
    with pytest.raises(ParameterError, match=f"bary must have shape \\(1, {dim + 1}\\)"):
        fld.distance_at(0, [1.0, 0.0])
    with pytest.raises(ParameterError, match=f"{arg} must be an int or a 1-D array"):
        fld.distance_at(0.5, b)
