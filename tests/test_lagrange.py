"""The one Lagrange space of both dimensions (``operators/lagrange.py``) and the one split mesh (``mesh/split.py``):
shape functions, DOFs, the exact largest cone violation, the field, and source points inserted as vertices, each
checked on triangles and on tetrahedra."""

from __future__ import annotations

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic.errors import ParameterError, SourceError
from cvxgeodesic.mesh.split import SplitMesh
from cvxgeodesic.mesh.tet_generate import tet_box
from cvxgeodesic.operators.lagrange import (
    LagrangeField,
    LagrangeSpace,
    lagrange_basis,
    lagrange_nodes,
    max_violation,
    sample_points,
)


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
    N, dN = lagrange_basis(lagrange_nodes(dim, order), order)
    np.testing.assert_allclose(N, np.eye(N.shape[1]), atol=1e-15)
    lam = np.random.default_rng(0).dirichlet(np.ones(dim + 1), 20)
    N, dN = lagrange_basis(lam, order)
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


def test_consistent_weights_are_for_triangles_only():
    with pytest.raises(ParameterError, match="weights='p2' is defined for order-2 triangles only"):
        LagrangeSpace(_mesh(3)).weights("p2")
    with pytest.raises(ParameterError, match=r"order must be 1 \(P1 distance\) or 2"):
        LagrangeSpace(_mesh(2), order=3)
    with pytest.raises(ParameterError, match="unknown weights 'exact'; choose one of lumped, p2"):
        LagrangeSpace(_mesh(2)).weights("exact")


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
    samples = np.vstack([rng.dirichlet(np.ones(dim + 1), 3000), lagrange_nodes(dim)])
    inside = sum(_check_max(space, x, samples) for x in fields)
    # the second field's maxima are away from the corners in the cells near x0 (measured: 13 of 32 faces on the
    # grid, where most faces' nearest point to x0 is a corner; 46 of 48 tetrahedra)
    assert inside >= (8 if dim == 2 else mesh.n_cells // 2)


def _check_max(space, x, samples) -> int:
    vmax, bary, phi_at = max_violation(space, x)
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


@pytest.mark.parametrize("dim", [2, 3])
def test_sample_points_are_barycentric_and_the_gauss_rule_is_the_triangles(dim):
    n_nodes = (dim + 1) * (dim + 2) // 2
    sizes = {"nodes": n_nodes, "corners": dim + 1, "midpoints": n_nodes - dim - 1, "nodes+centroid": n_nodes + 1}
    if dim == 2:
        sizes["nodes+gauss"] = n_nodes + 3
    for name, size in sizes.items():
        pts = sample_points(name, dim)
        assert pts.shape == (size, dim + 1)
        np.testing.assert_allclose(pts.sum(axis=1), 1.0, rtol=0, atol=1e-15)  # rounding of 1/6 + 1/6 + 2/3
    if dim == 3:
        with pytest.raises(ParameterError, match="samples 'nodes\\+gauss' is not defined on cells of dimension 3"):
            sample_points("nodes+gauss", 3)
    with pytest.raises(ParameterError, match="samples 'everywhere' is not defined"):
        sample_points("everywhere", dim)
