"""TetMesh (issue 26): validation, derived quantities against hand-computed values, findings in the notes."""

from __future__ import annotations

import numpy as np
import pytest

from cvxgeodesic.errors import MeshError
from cvxgeodesic.mesh.convert import as_mesh
from cvxgeodesic.mesh.reference import TETRAHEDRON
from cvxgeodesic.mesh.simplex import unit_mesh
from cvxgeodesic.mesh.tet_generate import kuhn_tets, tet_ball, tet_box, tet_l_prism
from cvxgeodesic.mesh.tetmesh import TetMesh

CORNER = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)


def two_tets():
    """Two tetrahedra sharing the face (1, 2, 3), on opposite sides of it."""
    V = np.vstack([CORNER, [[1.0, 1.0, 1.0]]])
    return TetMesh(V, [[0, 1, 2, 3], [4, 1, 3, 2]])


# -- validation ---------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("V, T, match", [
    (CORNER[:, :2], [[0, 1, 2, 3]], r"vertices must have shape \(n, 3\)"),
    (np.vstack([CORNER, [[np.nan, 0, 0]]]), [[0, 1, 2, 3]], "vertex 4 has a non-finite coordinate"),
    (CORNER, [[0, 1, 2]], r"tetrahedra must have shape \(k, 4\)"),
    (CORNER, np.zeros((0, 4), dtype=int), "no tetrahedra"),
    (CORNER, [[0, 1, 2, 3], [0, 1, 2, 4]], r"tetrahedron 1 has vertex index \[0, 1, 2, 4\] outside \[0, 4\)"),
    (CORNER, [[0, 1, 2, 3], [0, 1, -1, 3]], "tetrahedron 1 has vertex index"),
    (CORNER, [[0, 1, 2, 3], [0, 1, 1, 3]], r"tetrahedron 1 repeats a vertex \[0, 1, 1, 3\]"),
    (CORNER, [[0, 1, 2, 3.5]], "tetrahedron indices must be integers"),
    (CORNER, [["a", "b", "c", "d"]], "must be integers"),
])
def test_invalid_arrays_name_the_problem(V, T, match):
    with pytest.raises(MeshError, match=match):
        TetMesh(V, T, name="m")


def test_arrays_are_read_only_and_float_indices_accepted():
    mesh = TetMesh(CORNER, np.array([[0.0, 1.0, 2.0, 3.0]]))
    assert mesh.T.dtype == np.int64 and not mesh.T.flags.writeable and not mesh.V.flags.writeable


def test_as_mesh_takes_tetrahedra():
    mesh = as_mesh((CORNER, [[0, 1, 2, 3]]))
    assert isinstance(mesh, TetMesh) and as_mesh(mesh) is mesh


# -- derived quantities -------------------------------------------------------------------------------------------
def test_volume_orientation_and_positive_tets():
    m = TetMesh(CORNER, [[0, 1, 2, 3], [0, 2, 1, 3]])  # the same tetrahedron twice, both orientations
    np.testing.assert_allclose(m.signed_volumes, [1 / 6, -1 / 6])
    np.testing.assert_allclose(m.volumes, [1 / 6, 1 / 6])
    P = m.positive_tets
    assert TetMesh(CORNER, P).signed_volumes.min() > 0
    assert sorted(P[1].tolist()) == [0, 1, 2, 3]


def test_edges_faces_and_boundary_of_two_tets():
    m = two_tets()
    assert m.edges.tolist() == [[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [1, 4], [2, 3], [2, 4], [3, 4]]
    # every tet edge maps back to its two vertices
    for t in range(2):
        for k, (a, b) in enumerate([[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]]):
            assert sorted(m.edges[m.cell_edges[t, k]].tolist()) == sorted([m.T[t, a], m.T[t, b]])
    np.testing.assert_allclose(m.edge_lengths[m.edges.tolist().index([0, 1])], 1.0)
    assert m.faces.shape == (7, 3) and m.face_tet_counts.tolist().count(2) == 1
    assert m.boundary_facets.shape == (6, 3) and m.is_manifold
    assert m.boundary_vertices.tolist() == [0, 1, 2, 3, 4]
    assert m.boundary_face_tets.tolist().count(0) == 3
    # outward: the normals of the closed boundary integrate the divergence theorem, Σ (c · n) A = 3 · volume
    V, B = m.V, m.boundary_facets
    nrm = np.cross(V[B[:, 1]] - V[B[:, 0]], V[B[:, 2]] - V[B[:, 0]]) / 2
    flux = np.einsum("ij,ij->", V[B].mean(axis=1), nrm)
    np.testing.assert_allclose(flux, 3 * m.total_volume)
    # the opposite face really is opposite: it does not contain the vertex
    for i, face in enumerate(TETRAHEDRON.facets):
        assert i not in face


def test_outward_boundary_on_generated_meshes():
    for mesh in (tet_box(3, jitter=0.2), tet_l_prism(2), tet_ball(3)):
        V, B = mesh.V, mesh.boundary_facets
        nrm = np.cross(V[B[:, 1]] - V[B[:, 0]], V[B[:, 2]] - V[B[:, 0]]) / 2
        np.testing.assert_allclose(np.einsum("ij,ij->", V[B].mean(axis=1), nrm), 3 * mesh.total_volume, rtol=1e-12)
        assert mesh.boundary_mesh().is_edge_manifold


def test_box_counts_area_and_adjacency():
    m = tet_box(2, 3, 4, size=(2.0, 3.0, 4.0))
    assert m.n_vertices == 3 * 4 * 5 and m.n_tets == 6 * 24
    np.testing.assert_allclose(m.total_volume, 24.0)
    np.testing.assert_allclose(m.boundary_area, 2 * (6 + 8 + 12))
    assert m.boundary_vertices.size == m.n_vertices - 1 * 2 * 3
    A = m.vertex_adjacency
    assert (A != A.T).nnz == 0 and A.nnz == 2 * m.edges.shape[0]
    # edges of a Kuhn grid: axes, face diagonals, one cube diagonal per cell
    assert set(np.round(m.edge_lengths, 12)) == {1.0, round(2**0.5, 12), round(3**0.5, 12)}
    np.testing.assert_allclose(m.bbox_diagonal, 29**0.5)


def test_components_connected_to_and_referenced():
    V = np.vstack([CORNER, CORNER + 5, [[9.0, 9.0, 9.0]]])
    m = TetMesh(V, [[0, 1, 2, 3], [4, 5, 6, 7]])
    assert m.n_components == 3
    assert m.connected_to([5]).tolist() == [False] * 4 + [True] * 4 + [False]
    assert m.referenced.tolist() == [True] * 8 + [False]
    assert any("1 vertices are in no tetrahedron (first: vertex 8)" in n for n in m.notes)


# -- quality, folds, manifoldness ---------------------------------------------------------------------------------
def test_altitudes_of_known_tetrahedra():
    # the corner tetrahedron: altitudes 1, 1, 1 and 1/√3 (to the face x + y + z = 1)
    m = TetMesh(CORNER, [[0, 1, 2, 3]])
    np.testing.assert_allclose(m.cell_min_altitudes, [1 / 3**0.5])
    np.testing.assert_allclose(m.cell_longest_edges, [2**0.5])
    # Kuhn tetrahedra: 0.408 of their longest edge (the docstring's number)
    box = tet_box(2)
    np.testing.assert_allclose(box.cell_min_altitudes / box.cell_longest_edges, (1 / 6) ** 0.5)


def test_degenerate_tets_found_and_noted():
    flat = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 1e-5]], dtype=float)  # a sliver: altitude 7e-6
    V = np.vstack([CORNER, flat + 3])
    m = TetMesh(V, [[0, 1, 2, 3], [4, 5, 6, 7]], name="m")
    assert m.degenerate_tets().tolist() == [1]
    assert m.degenerate_tets(1e-6).tolist() == []
    assert any("1 degenerate tetrahedra" in n and "first: tet 1" in n for n in m.notes)
    zero = np.vstack([CORNER, [[0, 0, 0.0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]])
    mz = TetMesh(zero, [[0, 1, 2, 3], [4, 5, 6, 7]])
    assert mz.degenerate_tets(0.0).tolist() == [1] and mz.volumes[1] == 0
    assert any("1 of zero volume" in n for n in mz.notes)


def test_a_fold_is_found_whatever_the_vertex_order():
    V = np.vstack([CORNER, [[0.2, 0.2, 0.2]]])  # vertex 4 on the same side of face (1, 2, 3) as vertex 0
    for order in ([4, 1, 3, 2], [4, 1, 2, 3]):
        m = TetMesh(V, [[0, 1, 2, 3], order])
        assert m.folded_faces.size == 1 and m.faces[m.folded_faces[0]].tolist() == [1, 2, 3]
        assert any("folds over itself" in n for n in m.notes)
    assert two_tets().folded_faces.size == 0 and two_tets().notes == ()


def test_mixed_orientation_is_noted():
    m = TetMesh(two_tets().V, [[0, 1, 2, 3], [4, 1, 2, 3]])  # second one negative
    assert any("1 of 2 tetrahedra have negative orientation (first: tet 1)" in n for n in m.notes)


def test_nonmanifold_faces_reported():
    V = np.vstack([CORNER, [[1.0, 1.0, 1.0], [0.6, 0.6, 0.6]]])
    m = TetMesh(V, [[0, 1, 2, 3], [4, 1, 3, 2], [5, 1, 3, 2]])
    assert not m.is_manifold
    assert m.faces[m.nonmanifold_faces].tolist() == [[1, 2, 3]]
    assert any("not manifold: 1 faces are shared by more than two tetrahedra" in n for n in m.notes)


def test_notes_keep_the_readers_notes_first():
    m = TetMesh(CORNER, [[0, 1, 2, 3]], notes=["read: something"])
    assert m.notes == ("read: something",)


# -- scaling ------------------------------------------------------------------------------------------------------
def test_unit_tetmesh_scales_by_a_power_of_two():
    m = tet_box(2, size=5.0)
    u, s = unit_mesh(m)
    assert s == 16.0 and 0.5 <= u.bbox_diagonal < 1
    np.testing.assert_array_equal(u.V * s, m.V)
    assert unit_mesh(u) == (u, 1.0)


def test_kuhn_tets_are_positive_on_a_cube():
    cube = np.array([[i, j, k] for k in (0, 1) for j in (0, 1) for i in (0, 1)], dtype=float)
    T = kuhn_tets(np.arange(8)[None])
    m = TetMesh(cube, T)
    assert (m.signed_volumes > 0).all()
    np.testing.assert_allclose(m.total_volume, 1.0)
