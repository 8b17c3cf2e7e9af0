"""The shared vocabulary of triangle and tetrahedral meshes (mesh/simplex.py) and the one gradient for any simplex."""

from __future__ import annotations

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic.mesh.simplex import unit_mesh
from cvxgeodesic.operators.gradient import gradient_blocks, gradient_matrix, gradient_norms


def _meshes():
    rng = np.random.default_rng(3)
    sphere = cg.icosphere(2)
    box = cg.tet_box(3)
    jittered = cg.TetMesh(box.V + 0.02 * rng.standard_normal(box.V.shape), box.T)
    return [sphere, cg.grid_plane(4), box, jittered]


@pytest.mark.parametrize("mesh", _meshes(), ids=lambda m: f"{type(m).__name__}{m.n_cells}")
def test_gradient_of_a_linear_function_is_exact_in_every_cell(mesh):
    # a linear function's interpolant is itself: its gradient, projected on the cell's frame, is a·(frame)
    a = np.array([1.0, -2.0, 0.5])
    B = gradient_blocks(mesh)
    assert B.shape == (mesh.n_cells, mesh.dim, mesh.dim + 1)
    g = np.einsum("kij,kj->ki", B, (mesh.V @ a)[mesh.cells])
    np.testing.assert_allclose(np.linalg.norm(g, axis=1), gradient_norms(mesh, mesh.V @ a), rtol=1e-13)
    if mesh.dim == 3:
        np.testing.assert_allclose(g, np.broadcast_to(a, g.shape), atol=1e-12)  # 1e-12: rounding of 1/altitude
    else:  # the tangential part of a
        nrm = mesh.face_normals_unnormalized / np.linalg.norm(mesh.face_normals_unnormalized, axis=1)[:, None]
        tangential = a - (nrm @ a)[:, None] * nrm
        np.testing.assert_allclose(np.linalg.norm(g, axis=1), np.linalg.norm(tangential, axis=1), atol=1e-12)
    np.testing.assert_allclose(B.sum(axis=2), 0.0, atol=1e-12 * np.abs(B).max())  # constants have no gradient
    G = gradient_matrix(mesh, B)
    assert G.shape == (mesh.dim * mesh.n_cells, mesh.n_vertices)


@pytest.mark.parametrize("mesh", _meshes()[::2], ids=lambda m: type(m).__name__)
def test_the_vocabulary_means_the_same_in_both_dimensions(mesh):
    assert mesh.cells is (mesh.F if mesh.dim == 2 else mesh.T)
    assert np.isclose(mesh.total_measure, mesh.cell_measures.sum())
    # each cell's edges are the unique edges of its local pairs
    pairs = np.sort(mesh.cells[:, mesh.reference.edges], axis=2)
    np.testing.assert_array_equal(mesh.edges[mesh.cell_edges], pairs)
    assert mesh.edge_cell_counts.sum() == mesh.n_cells * len(mesh.reference.edges)
    assert mesh.n_components == 1 and mesh.referenced.all()
    # a closed sphere has no boundary; a box's boundary faces cover its surface (area 6)
    assert mesh.boundary_facets.shape == ((0, 2) if mesh.dim == 2 else (mesh.boundary_facets.shape[0], 3))
    if mesh.dim == 3:
        assert np.isclose(mesh.boundary_area, 6.0)
    big = mesh._with_vertices(mesh.V * 3.0)
    unit, s = unit_mesh(big)
    assert type(unit) is type(mesh) and 0.5 <= unit.bbox_diagonal < 1 and np.log2(s) % 1 == 0
    np.testing.assert_array_equal(unit.V * s, big.V)  # a power of two: exact
    np.testing.assert_array_equal(unit.cells, mesh.cells)


def test_degenerate_cells_one_rule_in_both_dimensions():
    # a flat triangle and a flat tetrahedron (all corners in one plane) are degenerate; the regular ones are not
    tri = cg.TriMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0]], [[0, 1, 2], [0, 1, 3]])
    tet = cg.TetMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0]], [[0, 1, 2, 3], [0, 1, 2, 4]])
    for mesh in (tri, tet):
        np.testing.assert_array_equal(mesh.degenerate_cells(), [1])
        assert mesh.cell_min_altitudes[1] == 0.0
    np.testing.assert_array_equal(tri.degenerate_faces(), tri.degenerate_cells())
    np.testing.assert_array_equal(tet.degenerate_tets(), tet.degenerate_cells())


def test_open_surface_boundary_facets_are_its_boundary_edges():
    tri = cg.TriMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], [[0, 1, 2], [1, 3, 2]])
    np.testing.assert_array_equal(tri.boundary_facets, [[0, 1], [0, 2], [1, 3], [2, 3]])


def test_reference_simplex_matches_the_mesh_classes():
    """Each mesh class carries its cell kind; its local frame gives the gradient code's corner coordinates."""
    from cvxgeodesic.mesh.reference import TETRAHEDRON, TRIANGLE
    from cvxgeodesic.operators.gradient import triangle_frames

    sphere, box = cg.icosphere(1), cg.tet_box(2)
    assert sphere.reference is TRIANGLE and box.reference is TETRAHEDRON
    for mesh in (sphere, box):
        ref = mesh.reference
        assert ref.dim == mesh.dim and ref.n_corners == mesh.cells.shape[1]
        X = mesh.V[mesh.cells]
        expected = X
        if mesh is sphere:  # each face's frame of triangle_frames, corner 0 at the origin
            ex, ey = triangle_frames(sphere)
            rel = X - X[:, :1]
            expected = np.stack([np.einsum("kvx,kx->kv", rel, ex), np.einsum("kvx,kx->kv", rel, ey)], axis=2)
        np.testing.assert_array_equal(ref.local_coordinates(X), expected)
        assert isinstance(ref.locate(mesh, mesh.V[3] * 0.999), ref.point_type)
    assert TRIANGLE.words.one == "face" and TETRAHEDRON.words.many == "tetrahedra"


@pytest.mark.parametrize("mesh", [cg.icosphere(1), cg.tet_box(2)], ids=["tri", "tet"])
def test_vertex_cells_and_centroid_tree_are_cached_members(mesh):
    """The incidence of vertices and cells and the cells' centroid tree: computed once per mesh, as members (no
    hand-made entries in the mesh's __dict__)."""
    inc = mesh.vertex_cells
    assert inc is mesh.vertex_cells and mesh.centroid_tree is mesh.centroid_tree
    for v in (0, 3, mesh.n_vertices - 1):
        np.testing.assert_array_equal(inc.indices[inc.indptr[v]:inc.indptr[v + 1]],
                                      np.flatnonzero((mesh.cells == v).any(axis=1)))
    tree, radius = mesh.centroid_tree
    corners = mesh.V[mesh.cells]
    assert np.all(np.linalg.norm(corners - tree.data[:, None], axis=2) <= radius)
    assert not [k for k in vars(mesh) if k.startswith("_cg") or k == "_tet_locator"]


@pytest.mark.parametrize("n", [50, 2**21])  # keys of one int64, and rows too wide for them (np.unique's path)
def test_unique_rows_is_numpys_row_unique(n):
    from cvxgeodesic.mesh.simplex import unique_rows

    rng = np.random.default_rng(4)
    rows = np.sort(rng.integers(0, 50, size=(400, 3)), axis=1) * (n // 50)
    unique, inverse, counts = unique_rows(rows, n)
    want_u, want_i, want_c = np.unique(rows, axis=0, return_inverse=True, return_counts=True)
    np.testing.assert_array_equal(unique, want_u)
    np.testing.assert_array_equal(inverse, want_i.reshape(-1))
    np.testing.assert_array_equal(counts, want_c)
    assert unique.dtype == inverse.dtype == counts.dtype == np.int64
