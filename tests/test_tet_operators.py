"""P1 operators on tetrahedra (issue 26): exact on linear fields, the stiffness identities, mass, energies."""

from __future__ import annotations

import numpy as np
import pytest

from cvxgeodesic.mesh.tet_generate import tet_ball, tet_box
from cvxgeodesic.mesh.tetmesh import TetMesh
from cvxgeodesic.operators import (
    cotan_stiffness,
    dirichlet_energy_matrix,
    divergence,
    gradient_blocks,
    gradient_matrix,
    gradient_norms,
    laplacian_energy_matrix,
    mass_matrix,
)

MESHES = {"box": lambda: tet_box(3, jitter=0.2, seed=2), "ball": lambda: tet_ball(4)}


@pytest.fixture(params=sorted(MESHES))
def mesh(request):
    return MESHES[request.param]()


def _mixed_orientation(mesh):
    """The same mesh with every other tetrahedron's vertex order reversed (operators must not care)."""
    T = mesh.T.copy()
    T[::2] = T[::2, ::-1]
    return TetMesh(mesh.V, T)


def test_gradient_of_a_linear_function_is_exact(mesh):
    a = np.array([0.3, -1.2, 2.5])
    f = mesh.V @ a + 4.0
    for m in (mesh, _mixed_orientation(mesh)):
        B = gradient_blocks(m)
        g = np.einsum("tij,tj->ti", B, f[m.T])
        np.testing.assert_allclose(g, np.broadcast_to(a, g.shape), atol=1e-12)
        np.testing.assert_allclose((gradient_matrix(m) @ f).reshape(-1, 3), g, atol=1e-12)
        np.testing.assert_allclose(gradient_norms(m, f), np.linalg.norm(a), rtol=1e-12)
        np.testing.assert_allclose(B.sum(axis=2), 0, atol=1e-9)  # constants have no gradient


def test_stiffness_identities(mesh):
    L = cotan_stiffness(mesh)
    assert abs(L - L.T).max() < 1e-14
    np.testing.assert_allclose(L @ np.ones(mesh.n_vertices), 0, atol=1e-12)
    G = gradient_matrix(mesh)
    W = np.repeat(mesh.volumes, 3)
    np.testing.assert_allclose((G.T @ (W[:, None] * G.toarray())), L.toarray(), atol=1e-12)
    # dᵀ L d = Σ vol |∇d|², = |Ω| |a|² for a linear field
    a = np.array([1.0, 2.0, -0.5])
    f = mesh.V @ a
    np.testing.assert_allclose(f @ L @ f, mesh.total_volume * a @ a, rtol=1e-12)
    assert np.linalg.eigvalsh(L.toarray()).min() > -1e-12
    # orientation does not matter
    np.testing.assert_allclose(cotan_stiffness(_mixed_orientation(mesh)).toarray(), L.toarray(), atol=1e-14)


def test_stiffness_is_the_cotangent_formula():
    # L_ij = -(1/6) Σ ℓ_kl cot θ_kl over the tetrahedra of edge ij (θ_kl the dihedral angle at the opposite edge)
    rng = np.random.default_rng(3)
    V = rng.normal(size=(4, 3))
    m = TetMesh(V, [[0, 1, 2, 3]])
    L = cotan_stiffness(m).toarray()
    for i, j in [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]:
        k, l = (v for v in range(4) if v not in (i, j))
        e = V[l] - V[k]
        # the dihedral angle at edge kl: between the faces (k, l, i) and (k, l, j)
        ui = V[i] - V[k] - (V[i] - V[k]) @ e / (e @ e) * e
        uj = V[j] - V[k] - (V[j] - V[k]) @ e / (e @ e) * e
        cos = ui @ uj / np.linalg.norm(ui) / np.linalg.norm(uj)
        cot = cos / np.sqrt(1 - cos**2)
        np.testing.assert_allclose(L[i, j], -np.linalg.norm(e) * cot / 6, rtol=1e-10)


def test_mass_sums_to_the_volume(mesh):
    M = mass_matrix(mesh).diagonal()
    np.testing.assert_allclose(M.sum(), mesh.total_volume, rtol=1e-13)
    assert (M > 0).all()
    # one Kuhn cube: the ends of its diagonal, (0,0,0) and (1,1,1), are in all six tetrahedra (6 × 1/6 / 4)
    m = tet_box(1)
    np.testing.assert_allclose(mass_matrix(m).diagonal()[[0, 7]], [6 / 24, 6 / 24])


def test_divergence_is_the_transpose_of_the_gradient(mesh):
    rng = np.random.default_rng(1)
    X = rng.normal(size=(mesh.n_tets, 3))
    u = rng.normal(size=mesh.n_vertices)
    G = gradient_matrix(mesh)
    lhs = divergence(mesh, X) @ u
    rhs = np.sum(mesh.volumes[:, None] * X * (G @ u).reshape(-1, 3))
    np.testing.assert_allclose(lhs, rhs, rtol=1e-12)
    # the divergence of a constant field integrates to the boundary flux; it sums to 0 over the vertices
    np.testing.assert_allclose(divergence(mesh, np.ones((mesh.n_tets, 3))).sum(), 0, atol=1e-12)


def test_energies():
    m = tet_box(3, jitter=0.15, seed=4)
    a = np.array([0.0, 3.0, 4.0])
    f = m.V @ a
    np.testing.assert_allclose(f @ dirichlet_energy_matrix(m) @ f, 25.0, rtol=1e-12)
    Q = laplacian_energy_matrix(m)
    assert abs(Q - Q.T).max() < 1e-12
    # a linear field has zero Laplacian at interior vertices; the energy only sees boundary rows
    L = cotan_stiffness(m)
    interior = np.setdiff1d(np.arange(m.n_vertices), m.boundary_vertices)
    np.testing.assert_allclose((L @ f)[interior], 0, atol=1e-12)
    np.testing.assert_allclose(np.ones(m.n_vertices) @ Q @ np.ones(m.n_vertices), 0, atol=1e-12)


def test_zero_volume_tets_are_left_out_and_selection_works():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0]], dtype=float)
    m = TetMesh(V, [[0, 1, 2, 3], [0, 1, 2, 4]])  # the second is flat
    B = gradient_blocks(m)
    assert not np.isfinite(B[1]).all()
    L = cotan_stiffness(m)
    assert np.isfinite(L.toarray()).all()
    np.testing.assert_allclose(L.toarray(), cotan_stiffness(m, cells=[0]).toarray())
    np.testing.assert_allclose(L.toarray(), cotan_stiffness(m, cells=np.array([True, False])).toarray())
    np.testing.assert_allclose(mass_matrix(m).diagonal().sum(), 1 / 6)
    with pytest.raises(ValueError, match="cells"):
        cotan_stiffness(m, cells=[2])


def test_triangle_stiffness_from_blocks_is_libigls():
    """The generic assembly over cells (what tetrahedra use) gives libigl's cotangent matrix on triangles, to
    rounding (1e-12 of the largest entry: sums of the same terms in another order), and the barycentric mass sums to
    the area."""
    import cvxgeodesic as cg
    from cvxgeodesic.operators import barycentric_mass

    s = cg.icosphere(2)
    ref = cotan_stiffness(s)  # libigl
    mine = cotan_stiffness(s, cells=np.ones(s.n_cells, dtype=bool))
    assert abs(ref - mine).max() <= 1e-12 * abs(ref).max()
    np.testing.assert_allclose(barycentric_mass(s).diagonal().sum(), s.face_areas.sum(), rtol=1e-12)
