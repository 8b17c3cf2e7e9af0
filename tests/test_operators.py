"""Operator identities (gpytoolbox style): hand-computed triangles, L = GᵀAG, L·1 = 0, Σ mass = area."""

import numpy as np
import pytest
import scipy.sparse as sp

from cvxgeodesic.mesh import TriMesh, cylinder, grid_plane, icosphere
from cvxgeodesic.operators import (
    cotan_stiffness,
    dirichlet_energy_matrix,
    gradient_blocks,
    gradient_matrix,
    gradient_norms,
    hessian_energy_matrix,
    laplacian_energy_matrix,
    mass_matrix,
)

MESHES = [icosphere(2), grid_plane(6, jitter=0.3), cylinder(12, 5)]


def test_gradient_of_hat_functions_on_unit_right_triangle():
    mesh = TriMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])
    B = gradient_blocks(mesh)[0]
    # local frame: ex along v0->v1 = x, ey = n x ex = y; ∇φ0 = (-1,-1), ∇φ1 = (1,0), ∇φ2 = (0,1)
    np.testing.assert_allclose(B, [[-1, 1, 0], [-1, 0, 1]], atol=1e-15)


@pytest.mark.parametrize("mesh", MESHES, ids=lambda m: m.name)
def test_gradient_exact_on_linear_functions(mesh):
    rng = np.random.default_rng(1)
    a = rng.normal(size=3)
    d = mesh.V @ a
    norms = gradient_norms(mesh, d)
    # the in-plane part of the constant 3D gradient a
    F = mesh.F
    nrm = np.cross(mesh.V[F[:, 1]] - mesh.V[F[:, 0]], mesh.V[F[:, 2]] - mesh.V[F[:, 0]])
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    tangential = a - (nrm @ a)[:, None] * nrm
    np.testing.assert_allclose(norms, np.linalg.norm(tangential, axis=1), rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("mesh", MESHES, ids=lambda m: m.name)
def test_stiffness_equals_G_transpose_A_G(mesh):
    G = gradient_matrix(mesh)
    A = sp.diags(np.repeat(mesh.face_areas, 2))
    S = cotan_stiffness(mesh)
    assert abs(G.T @ A @ G - S).max() < 1e-12 * abs(S).max()
    assert abs(S @ np.ones(mesh.n_vertices)).max() < 1e-12 * abs(S).max()
    assert abs(S - S.T).max() == 0


@pytest.mark.parametrize("mesh", MESHES, ids=lambda m: m.name)
def test_mass_sums_to_area(mesh):
    M = mass_matrix(mesh)
    assert M.diagonal().min() > 0
    assert M.diagonal().sum() == pytest.approx(mesh.face_areas.sum(), rel=1e-12)


def test_sphere_area_converges():
    assert icosphere(4).face_areas.sum() == pytest.approx(4 * np.pi, rel=5e-3)


def test_dirichlet_energy_of_linear_function_is_squared_slope():
    mesh = grid_plane(8, jitter=0.2)
    d = 3.0 * mesh.V[:, 0] - 4.0 * mesh.V[:, 1]
    assert d @ dirichlet_energy_matrix(mesh) @ d == pytest.approx(25.0, rel=1e-12)


def test_laplacian_energy_of_quadratic():
    # interior Laplacian of x² + y² is 4: the energy restricted to interior vertices approaches 16·area
    mesh = grid_plane(24)
    d = mesh.V[:, 0] ** 2 + mesh.V[:, 1] ** 2
    Q = laplacian_energy_matrix(mesh)
    assert abs(Q - Q.T).max() < 1e-9
    assert np.linalg.eigvalsh(laplacian_energy_matrix(grid_plane(4)).toarray()).min() > -1e-9
    S = cotan_stiffness(mesh)
    lap = -(S @ d) / mass_matrix(mesh).diagonal()
    interior = (mesh.V[:, 0] > 0.05) & (mesh.V[:, 0] < 0.95) & (mesh.V[:, 1] > 0.05) & (mesh.V[:, 1] < 0.95)
    np.testing.assert_allclose(lap[interior], 4.0, rtol=1e-9)


def test_hessian_energy_vanishes_on_linear_functions_of_flat_mesh():
    mesh = grid_plane(10, jitter=0.3)
    H = hessian_energy_matrix(mesh)
    for a in ([1, 0, 0], [0, 1, 0], [2, -3, 0]):
        d = mesh.V @ np.array(a, float)
        assert abs(d @ H @ d) < 1e-9


def test_hessian_energy_of_quadratic_converges():
    # ∫‖Hess(x²)‖² over the unit square is 4; the discrete value approaches it like 1/n
    errs = []
    for n in (8, 16, 32):
        mesh = grid_plane(n)
        d = mesh.V[:, 0] ** 2
        errs.append(abs(d @ hessian_energy_matrix(mesh) @ d - 4.0))
    assert errs[2] < 0.15
    assert errs[0] / errs[2] > 3.5


def test_hessian_energy_is_psd_on_sphere():
    H = hessian_energy_matrix(icosphere(2)).toarray()
    assert np.linalg.eigvalsh(H).min() > -1e-9 * np.abs(H).max()


def test_hessian_energy_on_a_nonmanifold_mesh_is_the_sum_over_its_sheets():
    """A book of three pages on edge (0, 1): the energy is that of the three triangles taken apart."""
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1.0]])
    F = np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]])
    notes = []
    Q = hessian_energy_matrix(TriMesh(V, F), notes)
    assert Q.shape == (5, 5) and "1 non-manifold edge(s)" in notes[0]
    d = np.random.default_rng(0).random(5)
    expected = 0.0
    for f in F:
        Qf = hessian_energy_matrix(TriMesh(V[f], [[0, 1, 2]]))
        expected += d[f] @ Qf @ d[f]
    assert d @ Q @ d == pytest.approx(expected, rel=1e-12)


def test_manifold_cover_of_a_fin_on_a_grid():
    """A fin on an interior edge of a grid: the cut separates the fin from one side; linear stays linear."""
    from cvxgeodesic.mesh.cover import manifold_cover

    g = grid_plane(6)
    a, b = g.edges[np.flatnonzero(g.edge_cell_counts == 2)[0]]
    V = np.vstack([g.V, [[0.5, 0.5, 1.0]]])
    F = np.vstack([g.F, [[a, b, g.n_vertices]]])
    mesh = TriMesh(V, F)
    cover, to_mesh = manifold_cover(mesh)
    assert cover.is_edge_manifold and not mesh.is_edge_manifold
    np.testing.assert_array_equal(cover.V, V[to_mesh])
    np.testing.assert_array_equal(to_mesh[cover.F], F)  # the same faces, corner for corner
    # each end of the edge splits in two, or in three where the grid's fan around it is cut open too
    assert V.shape[0] + 2 <= cover.n_vertices <= V.shape[0] + 4
    Q = hessian_energy_matrix(mesh)
    x = V[:, 0] + 2 * V[:, 1]  # linear on the flat grid and on the flat fin: zero Hessian energy
    assert abs(x @ Q @ x) < 1e-8 * abs(Q).sum()


def _flipped(mesh: TriMesh, every: int = 3) -> TriMesh:
    """The mesh with every ``every``-th face reversed: neighbouring half-edges then run the same way."""
    F = mesh.F.copy()
    F[::every] = F[::every, ::-1]
    return TriMesh(mesh.V, F, name=mesh.name + "-flipped")


def _with_a_loose_vertex(mesh: TriMesh) -> TriMesh:
    """The mesh with a vertex in no face appended (libigl sizes its matrix by the largest referenced index)."""
    return TriMesh(np.vstack([mesh.V, [[9.0, 9.0, 9.0]]]), mesh.F, name=mesh.name + "-loose")


TETRAHEDRON = TriMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.3, 0.2, 0.9]],
                      [[0, 1, 2], [0, 3, 1], [1, 3, 2], [2, 3, 0]], name="tetrahedron")
FACE_ASSEMBLY_MESHES = [icosphere(2), grid_plane(7, jitter=0.3, seed=2), cylinder(10, 4),
                         _flipped(icosphere(1)), _with_a_loose_vertex(grid_plane(4, jitter=0.2)), TETRAHEDRON]


@pytest.mark.parametrize("mesh", FACE_ASSEMBLY_MESHES, ids=lambda m: m.name)
def test_face_assembly_of_curved_hessian_equals_libigl(mesh):
    """The face-by-face assembly is libigl's matrix to rounding (closed, open, inconsistently oriented
    meshes, a loose vertex, a tetrahedron whose three opposite vertices coincide), on libigl's pattern but for
    entries whose contributions cancel (exactly 0 in one assembly, rounding in the other)."""
    from cvxgeodesic.operators.energies import curved_hessian_energy

    Q = curved_hessian_energy(mesh, libigl=False)
    ref = curved_hessian_energy(mesh, libigl=True)
    assert Q.shape == ref.shape == (mesh.n_vertices, mesh.n_vertices)
    scale = abs(ref).max()
    assert abs(Q - ref).max() <= 1e-13 * scale
    ones = sp.csc_matrix((np.ones(Q.nnz), Q.indices, Q.indptr), shape=Q.shape)
    ones_ref = sp.csc_matrix((np.ones(ref.nnz), ref.indices, ref.indptr), shape=ref.shape)
    r, c = (ones != ones_ref).nonzero()
    assert np.abs(Q.toarray()[r, c]).max(initial=0) <= 1e-13 * scale
    assert np.abs(ref.toarray()[r, c]).max(initial=0) <= 1e-13 * scale
    assert r.size <= 0.05 * ref.nnz
    assert abs(Q - Q.T).max() == 0.0


@pytest.mark.shared
@pytest.mark.parametrize("name", ["spot.obj", "camelhead_open.off", "thingi_37881.stl"])
def test_face_assembly_of_curved_hessian_equals_libigl_on_shared_meshes(name):
    """Real meshes: a closed one, an open one (the angle defect is 0 on the boundary) and the CAD mesh whose
    curved energy is indefinite (the PSD check must see the same matrix)."""
    from conftest import shared_mesh_path
    from cvxgeodesic import load_mesh
    from cvxgeodesic.operators.energies import curved_hessian_energy

    mesh = load_mesh(shared_mesh_path(name))
    Q, ref = curved_hessian_energy(mesh, libigl=False), curved_hessian_energy(mesh, libigl=True)
    assert abs(Q - ref).max() <= 1e-13 * abs(ref).max()
    assert abs(Q.nnz - ref.nnz) <= 1e-4 * ref.nnz


def test_curved_hessian_uses_libigl_off_the_face_assembly():
    """A non-manifold mesh (not handled by the face assembly) and a degenerate face (inf/nan there) get
    libigl's matrix itself."""
    import igl

    from cvxgeodesic.operators.energies import _padded_symmetric, curved_hessian_energy

    book = TriMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1.0]], [[0, 1, 2], [1, 0, 3], [0, 1, 4]])
    sliver = TriMesh([[0, 0, 0], [1, 0, 0], [2, 0, 0], [1, 1, 0]], [[0, 1, 3], [1, 2, 3], [0, 2, 1]])
    for mesh in (book, sliver):
        ref = _padded_symmetric(igl.curved_hessian_energy(mesh.V, mesh.F), mesh.n_vertices)
        Q = curved_hessian_energy(mesh)
        np.testing.assert_array_equal(Q.toarray(), ref.toarray())


@pytest.mark.shared
def test_indefinite_curved_hessian_falls_back_to_planar_energy():
    # measured: libigl's curved Hessian energy has eigenvalue -59 (largest diagonal 1.2e7) on this CAD mesh
    from conftest import shared_mesh_path
    from cvxgeodesic import IndefiniteEnergyWarning, load_mesh
    from cvxgeodesic.linalg import is_positive_semidefinite

    mesh = load_mesh(shared_mesh_path("thingi_37881.stl"))
    with pytest.warns(IndefiniteEnergyWarning, match="planar Hessian"):
        H = hessian_energy_matrix(mesh)
    assert is_positive_semidefinite(H)


@pytest.mark.parametrize("backend", ["auto", "pardiso", "cholmod"])
def test_psd_check_detects_a_negative_eigenvalue(backend):
    from cvxgeodesic import linalg as cholesky

    if backend != "auto" and not getattr(cholesky, f"{backend}_available")():
        pytest.skip(f"{backend} not installed")
    S = cotan_stiffness(icosphere(2))  # PSD with one zero eigenvalue (constants)
    assert cholesky.is_positive_semidefinite(S, backend=backend)
    shift = 1e-3 * abs(S.diagonal()).max()
    assert not cholesky.is_positive_semidefinite(S - shift * sp.identity(S.shape[0]), backend=backend)
    # a rank-one dent along a random direction v: with constants in the kernel of S the smallest eigenvalue is
    # at most -shift (1ᵀv)²/n, about -6e-6 of the largest diagonal here, far beyond the 1e-9 rounding shift
    v = np.random.default_rng(0).standard_normal(S.shape[0])
    v /= np.linalg.norm(v)
    assert not cholesky.is_positive_semidefinite(S.toarray() - shift * np.outer(v, v), backend=backend)


def test_psd_check_in_an_existing_analysis():
    """``analysis=``: the same answers as the check's own analysis, for a PSD matrix, a shifted one and one with
    a rank-one dent, factored in a wider pattern (the mesh's Newton pattern with the matrix)."""
    from cvxgeodesic import linalg as cholesky
    from cvxgeodesic.problems.conic import kkt_pattern

    if not (cholesky.pardiso_available() or cholesky.cholmod_available()):
        pytest.skip("the PSD check needs PARDISO or CHOLMOD")
    mesh = icosphere(2)
    S = cotan_stiffness(mesh)
    shift = 1e-3 * abs(S.diagonal()).max()
    v = np.random.default_rng(1).standard_normal(S.shape[0])
    v /= np.linalg.norm(v)
    H = hessian_energy_matrix(mesh)
    chol = cholesky.SymbolicCholesky(kkt_pattern(mesh.n_vertices, mesh.F, mesh.edges, H))
    for Q, expected in [(S, True), (H, True), (S - shift * sp.identity(S.shape[0]), False),
                        (sp.csc_matrix(S.toarray() - shift * np.outer(v, v)), None)]:
        if expected is None:  # dense: does not fit the pattern
            with pytest.raises(ValueError, match="not in the sparsity pattern"):
                cholesky.is_positive_semidefinite(Q, analysis=chol)
            continue
        assert cholesky.is_positive_semidefinite(Q, analysis=chol) is expected
        assert cholesky.is_positive_semidefinite(Q) is expected
    assert chol.n_factorizations == 3
    with pytest.raises(ValueError, match="analysis is of a"):
        cholesky.is_positive_semidefinite(cotan_stiffness(icosphere(1)), analysis=chol)


def test_face_edges_index_the_edge_opposite_each_corner():
    mesh = grid_plane(5, jitter=0.2, seed=1)
    fe = mesh.cell_edges
    for k in range(3):
        expected = np.sort(mesh.F[:, [(k + 1) % 3, (k + 2) % 3]], axis=1)
        np.testing.assert_array_equal(mesh.edges[fe[:, k]], expected)


def test_flat_generators_shapes_and_aspect():
    from cvxgeodesic.mesh.generate import delaunay_plane, fan_plate, needle_strip

    strip = needle_strip(10, 240)
    assert (strip.n_vertices, strip.n_faces) == (22, 20) and np.all(strip.V[:, 2] == 0)
    e = strip.edge_lengths[strip.cell_edges]
    # longest edge / altitude = aspect for every needle (altitude = 2 area / longest edge)
    np.testing.assert_allclose(e.max(axis=1) ** 2 / (2 * strip.face_areas), 240, rtol=0.01)
    fan = fan_plate(12)
    assert (fan.n_vertices, fan.n_faces) == (24, 22) and fan.face_areas.min() > 0
    assert fan.face_areas.sum() == pytest.approx(2.0)  # the 2 × 1 plate, covered once
    pts = delaunay_plane(50, seed=1)
    assert pts.n_vertices == 50 and pts.face_areas.sum() <= 1.0
    from cvxgeodesic.errors import ParameterError

    with pytest.raises(ParameterError, match="aspect"):
        needle_strip(10, 0)
