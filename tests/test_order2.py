"""Order 2: P2 elements for the squared distance (``cvxgeodesic.elements_p2``)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import cvxgeodesic as cg
import cvxgeodesic.elements_p2 as p2mod
from conftest import shared_mesh_path
from cvxgeodesic.elements_p2 import (
    P2Builder,
    P2Space,
    max_violation,
    p2_basis,
    parse_sources,
    solve_p2_clarabel,
)
from cvxgeodesic.errors import ParameterError, SourceError
from cvxgeodesic.mesh.generate import delaunay_plane as delaunay_mesh
from cvxgeodesic.mesh.generate import fan_plate, needle_strip

FLAT_TOL = 1e-5  # max vertex error / largest distance on flat meshes (issue 17)


# ---------------------------------------------------------------- meshes
def euclid_from(mesh: cg.TriMesh, src) -> np.ndarray:
    if isinstance(src, int | np.integer):
        p = mesh.V[src]
    else:
        p = np.asarray(src[1]) @ mesh.V[mesh.F[src[0]]]
    return np.linalg.norm(mesh.V - p, axis=1)


def order2(mesh, src, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", cg.DegenerateFacesWarning)
        return cg.GeodesicSolver(mesh, "qclp", order=2, **kw).solve(src)


def flat_error(mesh, src) -> float:
    res = order2(mesh, src)
    ex = euclid_from(mesh, src)
    assert res.info.status in ("optimal", "almost_optimal")  # Clarabel: AlmostSolved on the aspect-1000 needle
    return float(np.abs(res.distance - ex).max() / ex.max())


# ---------------------------------------------------------------- elements
def test_p2_basis_partition_of_unity_and_nodal():
    nodes = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [0, .5, .5], [.5, 0, .5], [.5, .5, 0]])
    N, dN = p2_basis(nodes)
    np.testing.assert_allclose(N, np.eye(6), atol=1e-15)
    lam = np.random.default_rng(0).dirichlet([1, 1, 1], 20)
    N, dN = p2_basis(lam)
    np.testing.assert_allclose(N.sum(axis=1), 1.0, atol=1e-14)


def test_p2_weights_integrate_quadratics_exactly():
    # ∫∫_{[0,1]²} (x² + y²) = 2/3 ; the consistent P2 weights are exact for quadratics on any triangulation
    mesh = cg.grid_plane(5, jitter=0.3, seed=2)
    space = P2Space(mesh)
    E = mesh.edges
    P = np.vstack([mesh.V, 0.5 * (mesh.V[E[:, 0]] + mesh.V[E[:, 1]])])
    phi = (P[:, :2] ** 2).sum(axis=1)
    assert space.weights("p2") @ phi == pytest.approx(2 / 3, abs=1e-13)
    assert space.weights("lumped").sum() == pytest.approx(1.0, abs=1e-13)
    assert abs(space.weights("lumped") @ phi - 2 / 3) > 1e-4  # lumped weights are not exact


def test_gradient_of_exact_square_distance_on_a_face():
    mesh = delaunay_mesh(30)
    space = P2Space(mesh)
    E = mesh.edges
    P = np.vstack([mesh.V, 0.5 * (mesh.V[E[:, 0]] + mesh.V[E[:, 1]])])
    p = np.array([0.3, 0.4, 0.0])
    phi = ((P - p) ** 2).sum(axis=1)
    vmax, _, _ = max_violation(space, phi)  # |∇φ|² − 4φ ≡ 0 for φ = |x − p|²
    assert np.abs(vmax).max() < 1e-12


def test_max_violation_finds_interior_maximum():
    # a hand-built quadratic on one face: v = |∇φ|² − 4φ, compare with dense sampling
    mesh = cg.TriMesh(np.array([[0, 0, 0], [1, 0, 0], [0.2, 0.9, 0.0]]), np.array([[0, 1, 2]]))
    space = P2Space(mesh)
    rng = np.random.default_rng(1)
    for _ in range(5):
        x = rng.random(space.n_dofs)
        vmax, bary, _ = max_violation(space, x)
        g = np.linspace(0, 1, 81)
        B = np.array([[1 - a - b, a, b] for a in g for b in g if a + b <= 1 + 1e-12])
        N, dN = p2_basis(B)
        grad = np.einsum("sai,ci->sca", dN, space.lam_grad[0]) @ x[space.face_dofs[0]]
        v = (grad**2).sum(axis=1) - 4 * N @ x[space.face_dofs[0]]
        assert vmax[0] >= v.max() - 1e-12
        assert vmax[0] <= v.max() + 1e-3 * (abs(v.max()) + 1)


# ---------------------------------------------------------------- flat meshes of any quality
@pytest.mark.parametrize("src", [0, 200, 37])
def test_flat_jittered_grid_vertex_sources(src):
    assert flat_error(cg.grid_plane(20, jitter=0.4, seed=1), src) <= FLAT_TOL


@pytest.mark.parametrize("aspect", [50, 240, 1000])
@pytest.mark.parametrize("src", [0, 5, (4, (0.25, 0.25, 0.5))])
def test_flat_needle_strip(aspect, src):
    assert flat_error(needle_strip(10, aspect), src) <= FLAT_TOL


def test_flat_random_delaunay():
    mesh = delaunay_mesh()
    for src in (0, 17):
        assert flat_error(mesh, src) <= FLAT_TOL


def test_flat_fan_plate():
    mesh = fan_plate()
    aspect = mesh.face_longest_edges / mesh.face_min_altitudes
    assert aspect.max() > 20  # the fans are long and thin
    for src in (0, 5, mesh.n_vertices - 1, (3, (0.3, 0.3, 0.4)), (15, (0.1, 0.1, 0.8))):
        assert flat_error(mesh, src) <= FLAT_TOL


@pytest.mark.parametrize("bary", [(0.2, 0.3, 0.5), (0.5, 0.5, 0.0), (1 / 3, 1 / 3, 1 / 3)])
def test_flat_in_face_sources(bary):
    mesh = cg.grid_plane(20, jitter=0.4, seed=1)
    assert flat_error(mesh, (37, bary)) <= FLAT_TOL
    assert flat_error(delaunay_mesh(), (10, bary)) <= FLAT_TOL


def test_in_face_source_from_surface_point_object():
    class Pt:  # anything with .face and .bary (cg.SurfacePoint, from another branch)
        face = 37
        bary = (0.2, 0.3, 0.5)

    mesh = cg.grid_plane(12, jitter=0.3, seed=4)
    res = order2(mesh, [Pt()])
    ex = euclid_from(mesh, (37, Pt.bary))
    assert np.abs(res.distance - ex).max() / ex.max() <= FLAT_TOL


def test_field_inside_faces_flat():
    mesh = delaunay_mesh(120)
    res = order2(mesh, 3)
    fld = res.info.extra["p2_field"]
    rng = np.random.default_rng(0)
    faces = rng.integers(0, mesh.n_faces, 300)
    bary = rng.dirichlet([1, 1, 1], 300)
    pts = np.einsum("ki,kij->kj", bary, mesh.V[mesh.F[faces]])
    ex = np.linalg.norm(pts - mesh.V[3], axis=1)
    # √φ near the source magnifies φ's last digits: 1e-4 here against 1e-5 at the vertices
    assert np.abs(fld.distance_at(faces, bary) - ex).max() <= 1e-4 * ex.max()
    np.testing.assert_allclose(fld.distance_at(faces[:1], bary[:1]), fld.distance_at(faces[0], bary[0]))


def test_field_inside_split_face_after_point_source():
    mesh = cg.grid_plane(10, jitter=0.3, seed=5)
    src = (12, (0.2, 0.5, 0.3))
    res = order2(mesh, src)
    fld = res.info.extra["p2_field"]
    p = np.asarray(src[1]) @ mesh.V[mesh.F[12]]
    bary = np.array([[0.6, 0.2, 0.2], [0.1, 0.1, 0.8], *[src[1]]])
    pts = bary @ mesh.V[mesh.F[12]]
    got = fld.distance_at(np.full(3, 12), bary)
    np.testing.assert_allclose(got, np.linalg.norm(pts - p, axis=1), atol=1e-4)
    assert got[-1] < 1e-4


def test_cutting_planes_are_needed_next_to_an_inserted_source():
    # without the cutting planes the corner/midpoint cones let the field overshoot: it measured 3.7e-3
    mesh = cg.grid_plane(20, jitter=0.4, seed=1)
    ex = euclid_from(mesh, (37, (0.2, 0.3, 0.5)))
    s = cg.GeodesicSolver(mesh, "qclp", order=2)
    s._strategy.p2.refine = 0
    d0 = s.solve((37, (0.2, 0.3, 0.5))).distance
    assert np.abs(d0 - ex).max() / ex.max() > 1e-3


# ---------------------------------------------------------------- curved meshes
def test_sphere_converges_faster_than_p1():
    levels = [2, 3, 4]  # at level 1 (80 faces) the polyhedral shrink dominates: P1 and P2 are both ~3 % off
    e1, e2, h = [], [], []
    for lv in levels:
        mesh = cg.icosphere(lv)
        ex = np.arccos(np.clip(mesh.V @ mesh.V[0] / np.linalg.norm(mesh.V, axis=1) / np.linalg.norm(mesh.V[0]),
                               -1, 1)) * np.linalg.norm(mesh.V[0])
        mask = ex > 1e-9
        d1 = cg.GeodesicSolver(mesh, "qclp").solve(0).distance
        d2 = order2(mesh, 0).distance
        e1.append(np.mean(np.abs(d1 - ex)[mask] / ex[mask]))
        e2.append(np.mean(np.abs(d2 - ex)[mask] / ex[mask]))
        h.append(mesh.mean_edge_length)
    r1 = np.polyfit(np.log(h), np.log(e1), 1)[0]
    r2 = np.polyfit(np.log(h), np.log(e2), 1)[0]
    assert all(a < b for a, b in zip(e2, e1, strict=True))
    assert r2 > r1 + 0.3, (r1, r2)


def test_multiple_components_and_degenerate_faces():
    a = cg.grid_plane(4)
    b = cg.grid_plane(4)
    V = np.vstack([a.V, b.V + [5, 0, 0], [[0.5, 0.5, 0.0]]])
    F = np.vstack([a.F, b.F + a.n_vertices, [[0, 1, V.shape[0] - 1]]])  # plus a needle-ish face
    V[-1] = (V[0] + V[1]) / 2 + [0, 1e-6, 0]
    mesh = cg.TriMesh(V, F)
    assert mesh.degenerate_faces().size == 1
    with pytest.warns(cg.DegenerateFacesWarning):
        res = cg.GeodesicSolver(mesh, "qclp", order=2).solve(0)
    d = res.distance
    assert np.all(np.isinf(d[a.n_vertices:2 * a.n_vertices]))
    ex = np.linalg.norm(V[: a.n_vertices] - V[0], axis=1)
    assert np.abs(d[: a.n_vertices] - ex).max() < 1e-5
    assert abs(d[-1] - np.linalg.norm(V[-1] - V[0])) < 1e-5  # held by the 1-D edge cones of the degenerate face
    assert res.info.n_unreachable == a.n_vertices
    assert any("degenerate" in n for n in res.info.notes)


def test_non_manifold_book_of_flat_pages():
    # three flat pages sharing the spine (0,0,0)-(0,0,1): from a spine vertex the distance is Euclidean on each
    spine = [[0, 0, 0], [0, 0, 1]]
    pages = [[1, 0, 0.5], [-1, 0, 0.5], [0, 1, 0.5]]
    V = np.array(spine + pages, dtype=float)
    F = np.array([[0, 1, 2], [0, 1, 3], [0, 1, 4]])
    mesh = cg.TriMesh(V, F)
    assert not mesh.is_edge_manifold
    d = order2(mesh, 0).distance
    np.testing.assert_allclose(d, np.linalg.norm(V - V[0], axis=1), atol=1e-6)


# ---------------------------------------------------------------- API
def test_order_parameter_validation():
    mesh = cg.icosphere(1)
    for bad in (0, 3, 1.5, True, "2"):
        with pytest.raises(ParameterError, match="order"):
            cg.GeodesicSolver(mesh, "qclp", order=bad)
    with pytest.raises(ParameterError, match="order=2"):
        cg.GeodesicSolver(mesh, "qcqp-hessian", order=2)
    with pytest.raises(ParameterError, match="order=2"):
        cg.GeodesicSolver(mesh, "heat", order=2)


def test_bad_sources():
    mesh = cg.icosphere(1)
    s = cg.GeodesicSolver(mesh, "qclp", order=2)
    for bad, msg in (([], "empty"), (mesh.n_vertices, "out of range"), ([1, 1], "more than once"),
                     ((0, (0.5, 0.6, 0.1)), "sum to 1"), ((mesh.n_faces, (1, 0, 0)), "face"),
                     (True, "vertex"), ("a", "sources")):
        with pytest.raises(SourceError, match=msg):
            s.solve(bad)


def test_parse_sources_vertex_and_edge_points():
    mesh = cg.grid_plane(3)
    v, pts = parse_sources([(0, (0, 1, 0)), 5, (2, (0.5, 0.5, 0))], mesh)
    assert v.tolist() == [int(mesh.F[0, 1]), 5]
    assert len(pts) == 1 and pts[0].face == 2


def test_geodesic_distance_and_distance_matrix_order2():
    mesh = cg.grid_plane(6, jitter=0.2, seed=0)
    d = cg.geodesic_distance(mesh, 4, method="qclp", order=2)
    np.testing.assert_allclose(d, euclid_from(mesh, 4), atol=1e-6)
    D = cg.distance_matrix(mesh, [4, 10, 4], method="qclp", order=2)
    assert D.shape == (3, mesh.n_vertices)
    np.testing.assert_allclose(D[1], euclid_from(mesh, 10), atol=1e-6)
    np.testing.assert_array_equal(D[0], D[2])


def test_solve_info_order2():
    res = order2(cg.icosphere(2), 0)
    info = res.info
    assert info.method == "qclp" and info.status == "optimal" and info.iterations > 0
    assert info.extra["order"] == 2 and info.solver == "ipm"  # the structured solver under solver="auto"
    assert order2(cg.icosphere(2), 0, solver="clarabel").info.solver == "clarabel"
    assert info.primal_residual < 1e-6 and info.gap < 1e-6
    assert info.solve_time > 0


def test_scale_equivariance():
    mesh = cg.icosphere(2)
    d = order2(mesh, 0).distance
    big = cg.TriMesh(mesh.V * 1024.0, mesh.F)
    np.testing.assert_allclose(order2(big, 0).distance, d * 1024.0, rtol=1e-12, atol=0)


# ---------------------------------------------------------------- structured solver
@pytest.mark.parametrize("mesh", [cg.grid_plane(12, jitter=0.3, seed=1), cg.icosphere(2)], ids=["grid", "ico2"])
def test_structured_ipm_matches_clarabel(mesh):
    from cvxgeodesic.mesh.trimesh import unit_mesh as _unit_mesh
    from cvxgeodesic.solvers.ipm_soc import P2InteriorPoint

    unit, _ = _unit_mesh(mesh)
    b = P2Builder(unit)
    pr = b.build(0)
    ipm = P2InteriorPoint(b)
    ri = ipm.solve(pr)
    rc = solve_p2_clarabel(pr)
    assert ri["status"] in ("optimal", "almost_optimal")
    assert np.abs(ri["x"] - rc["x"]).max() <= 1e-6 * rc["x"].max()
    assert ipm.chol.n_analyses == 1
    ipm.solve(b.build(5))  # another source: same symbolic analysis
    assert ipm.chol.n_analyses == 1


# ---------------------------------------------------------------- real meshes (development data)
CAD = ["thingi_243015.stl", "thingi_32770.stl", "thingi_37881.stl", "thingi_47076.stl", "thingi_65395.stl",
       "thingi_93703.stl", "thingi_96457.stl"]


def _rel(d, de):
    ok = np.isfinite(de) & (de > 1e-12 * np.nanmax(de[np.isfinite(de)]))
    return float(np.mean(np.abs(d[ok] - de[ok]) / de[ok]))


@pytest.mark.slow
def test_coarse_cad_median_ratio():
    from cvxgeodesic.baselines import BASELINES

    ratios = []
    for name in CAD:
        mesh = cg.load_mesh(shared_mesh_path(name))
        if mesh.n_faces > 10_000:
            continue  # thingi_32770 (38K faces) is not coarse; benchmarks/order2.py covers it
        de, _ = BASELINES["exact"](mesh).solve(np.array([0]))
        e1 = _rel(cg.GeodesicSolver(mesh, "qclp").solve(0).distance, de)
        e2 = _rel(order2(mesh, 0).distance, de)
        ratios.append(e2 / e1)
    assert np.median(ratios) <= 0.5, ratios


@pytest.mark.slow
@pytest.mark.parametrize("name", ["bunny_7k.off", "lucy_20k.obj"])
def test_fine_mesh_not_worse_than_p1(name):
    from cvxgeodesic.baselines import BASELINES

    mesh = cg.load_mesh(shared_mesh_path(name))
    de, _ = BASELINES["exact"](mesh).solve(np.array([0]))
    e1 = _rel(cg.GeodesicSolver(mesh, "qclp").solve(0).distance, de)
    e2 = _rel(order2(mesh, 0).distance, de)
    assert e2 <= e1


def test_auto_falls_back_to_clarabel(monkeypatch):
    from cvxgeodesic.errors import SolverError
    from cvxgeodesic.solvers import ipm_soc

    def boom(self, problem, **kw):
        raise SolverError("forced", solver="ipm", status="numerical_error")

    monkeypatch.setattr(ipm_soc.P2InteriorPoint, "solve", boom)
    monkeypatch.setattr(p2mod, "IPM_MIN_FACES", 0)  # "auto" picks the structured solver
    mesh = cg.grid_plane(6, jitter=0.2, seed=0)
    res = order2(mesh, 4)
    assert res.info.solver == "clarabel"
    assert any("Clarabel" in n for n in res.info.notes)
    np.testing.assert_allclose(res.distance, euclid_from(mesh, 4), atol=1e-6)
    with pytest.raises(SolverError):
        order2(mesh, 4, solver="ipm")


def test_distance_at_evaluates_the_p2_field_inside_faces():
    """cg.distance_at on an order=2 result reads the quadratic field: exact on a flat grid between vertices."""
    mesh = cg.grid_plane(8, jitter=0.3, seed=5)
    res = cg.GeodesicSolver(mesh, "qclp", order=2).solve(40)
    rng = np.random.default_rng(1)
    faces = rng.integers(0, mesh.n_faces, 20)
    bary = rng.dirichlet([1.0, 1.0, 1.0], 20)
    pts = [cg.SurfacePoint(int(f), b) for f, b in zip(faces, bary, strict=True)]
    xyz = np.einsum("kj,kjd->kd", bary, mesh.V[mesh.F[faces]])
    exact = np.linalg.norm(xyz - mesh.V[40], axis=1)
    np.testing.assert_allclose(cg.distance_at(mesh, res, pts), exact, atol=1e-5 * exact.max())
    linear = cg.distance_at(mesh, res.distance, pts)  # the vertex values interpolated linearly are not exact
    assert np.abs(linear - exact).max() > 1e-3


# ---------------------------------------------------------------- compiled kernels of the structured solver
def _interior(rng, k):
    """(k, 4) points strictly inside SOC(4), some close to the boundary."""
    u = rng.normal(size=(k, 4))
    u[:, 0] = np.linalg.norm(u[:, 1:], axis=1) * (1 + 10.0 ** rng.uniform(-6, 0, k))
    return u


def _dense_nt(s, z):
    """Reference NT scaling ``W`` (k, 4, 4) from the textbook formulas (CVXOPT), built densely."""
    J = np.diag([1.0, -1.0, -1.0, -1.0])
    out = []
    for sk, zk in zip(s, z, strict=True):
        sn, zn = sk / np.sqrt(sk @ J @ sk), zk / np.sqrt(zk @ J @ zk)
        gamma = np.sqrt((1 + sn @ zn) / 2)
        w = (sn + J @ zn) / (2 * gamma)
        Wb = np.eye(4)
        Wb[0, 0], Wb[0, 1:], Wb[1:, 0] = w[0], w[1:], w[1:]
        Wb[1:, 1:] += np.outer(w[1:], w[1:]) / (1 + w[0])
        out.append(((sk @ J @ sk) / (zk @ J @ zk)) ** 0.25 * Wb)
    return np.array(out)


def test_p2_kernels_nt_scaling_and_products_match_dense_reference():
    from cvxgeodesic.solvers import _p2_kernels as kern

    rng = np.random.default_rng(3)
    k = 50
    s, z, v = _interior(rng, k), _interior(rng, k), rng.normal(size=(k, 4))
    w, eta, lam = np.empty((k, 4)), np.empty(k), np.empty((k, 4))
    kern.nt_scaling(s, z, w, eta, lam)
    W = _dense_nt(s, z)
    Wi = np.linalg.inv(W)
    np.testing.assert_allclose(lam, np.einsum("kij,kj->ki", W, z), rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(lam, np.einsum("kij,kj->ki", Wi, s), rtol=1e-6, atol=1e-9)  # W z = W⁻¹ s
    for power, M in ((1, W), (-1, Wi), (-2, Wi @ Wi)):
        out = np.empty_like(v)
        kern.apply_w(w, eta, v, power, out)
        np.testing.assert_allclose(out, np.einsum("kij,kj->ki", M, v), rtol=1e-8, atol=1e-10, err_msg=str(power))
    # Jordan product and its inverse
    pr, back = np.empty_like(v), np.empty_like(v)
    kern.jprod(lam, v, pr)
    np.testing.assert_allclose(pr[:, 0], np.einsum("ki,ki->k", lam, v))
    np.testing.assert_allclose(pr[:, 1:], lam[:, :1] * v[:, 1:] + v[:, :1] * lam[:, 1:])
    kern.jdiv(lam, pr, back)
    np.testing.assert_allclose(back, v, rtol=1e-7, atol=1e-9)


def test_p2_kernels_gather_scatter_assembly_match_dense_reference():
    import scipy.sparse as sp

    from cvxgeodesic.solvers import _p2_kernels as kern

    rng = np.random.default_rng(4)
    k, n = 40, 30
    G = rng.normal(size=(k, 3, 6))  # compact: row 3 of each block is row 0
    Gf = G[:, [0, 1, 2, 0]]
    dofs = np.array([rng.choice(n, 6, replace=False) for _ in range(k)], dtype=np.int64)
    x, zc = rng.normal(size=n), rng.normal(size=(k, 4))
    dense = np.zeros((4 * k, n))
    for c in range(k):
        dense[4 * c:4 * c + 4, dofs[c]] = Gf[c]
    out = np.empty((k, 4))
    kern.gather(G, dofs, x, out)
    np.testing.assert_allclose(out.ravel(), dense @ x, rtol=1e-12, atol=1e-12)
    g = np.zeros(n)
    kern.scatter(G, dofs, zc, g)
    np.testing.assert_allclose(g, dense.T @ zc.ravel(), rtol=1e-12, atol=1e-12)
    # Σ G_kᵀ W_k⁻² G_k summed into a CSC-like data array at the lower-triangle positions of each clique
    s, z = _interior(rng, k), _interior(rng, k)
    w, eta, lam = np.empty((k, 4)), np.empty(k), np.empty((k, 4))
    kern.nt_scaling(s, z, w, eta, lam)
    Wi = np.linalg.inv(_dense_nt(s, z))
    tri, tci = (np.ascontiguousarray(i, dtype=np.int64) for i in np.tril_indices(6))
    r, c = dofs[:, tri], dofs[:, tci]
    lo, hi = np.maximum(r, c), np.minimum(r, c)
    key = np.unique(lo * n + hi)
    pos = np.searchsorted(key, lo * n + hi)
    data = np.zeros(key.size)
    kern.assemble(G, w, eta, pos, tri, tci, data)
    H = np.zeros((n, n))
    for c_ in range(k):
        H[np.ix_(dofs[c_], dofs[c_])] += Gf[c_].T @ Wi[c_] @ Wi[c_] @ Gf[c_]
    got = sp.coo_matrix((data, (key // n, key % n)), shape=(n, n)).toarray()
    np.testing.assert_allclose(got, np.tril(H), rtol=1e-8, atol=1e-10)


def test_p2_kernels_max_step_reaches_the_boundary():
    from cvxgeodesic.solvers import _p2_kernels as kern

    rng = np.random.default_rng(5)
    k = 200
    u, du = _interior(rng, k), rng.normal(size=(k, 4))
    out = np.empty(k)
    kern._soc_steps(u, du, out)
    for a, uk, dk in zip(out, u, du, strict=True):
        if np.isfinite(a):  # on the boundary at α, inside just before
            p = uk + a * dk
            assert p[0] == pytest.approx(np.linalg.norm(p[1:]), rel=1e-6, abs=1e-9)
            q = uk + 0.999 * a * dk
            assert q[0] >= np.linalg.norm(q[1:]) - 1e-12
        else:  # never leaves the cone
            for t in (1.0, 1e3, 1e6):
                p = uk + t * dk
                assert p[0] >= np.linalg.norm(p[1:]) * (1 - 1e-9)
    assert kern.max_step(u, du) == pytest.approx(float(out.min()))


def test_p2_kernels_gondzio_target_moves_eigenvalues_into_the_band():
    from cvxgeodesic.solvers import _p2_kernels as kern

    rng = np.random.default_rng(6)
    k = 100
    s, z = _interior(rng, k), _interior(rng, k)
    zero = np.zeros((k, 4))
    w, eta, lam = np.empty((k, 4)), np.empty(k), np.empty((k, 4))
    kern.nt_scaling(s, z, w, eta, lam)
    ev = np.stack([lam[:, 0] - np.linalg.norm(lam[:, 1:], axis=1), lam[:, 0] + np.linalg.norm(lam[:, 1:], axis=1)])
    lo, hi = np.quantile(ev, 0.2), np.quantile(ev, 0.4)
    assert (ev < lo).any() and (ev > 2 * hi).any()  # all three regimes: raised, clipped, decrease bounded
    c = np.empty((k, 4))
    kern.gondzio_rhs(w, eta, s, zero, 0.0, z, zero, 0.0, lo, hi, c)
    # at the current point v = λ∘λ; the target v + c has its eigenvalues clipped into [lo, hi] (decrease ≤ hi)
    v = np.empty((k, 4))
    kern.jprod(lam, lam, v)
    t = v + c
    e_v = np.stack([v[:, 0] - np.linalg.norm(v[:, 1:], axis=1), v[:, 0] + np.linalg.norm(v[:, 1:], axis=1)])
    e_t = np.stack([t[:, 0] - np.linalg.norm(t[:, 1:], axis=1), t[:, 0] + np.linalg.norm(t[:, 1:], axis=1)])
    want = np.maximum(np.clip(e_v, lo, hi), e_v - hi)
    np.testing.assert_allclose(np.sort(e_t, axis=0), np.sort(want, axis=0), rtol=1e-8, atol=1e-10 * hi)


def test_structured_ipm_iteration_counts():
    """Gondzio's correctors and Mehrotra's start took spot from 48 to 25 iterations and a jittered 20×20 grid from
    27 to 15 (2026-12-01); a regression in the correctors, the start, the step or the scaling shows here first."""
    spot = cg.load_mesh(shared_mesh_path("spot.obj"))
    r = order2(spot, 0)
    assert r.info.solver == "ipm" and r.info.status == "optimal"
    assert r.info.iterations <= 20  # 18 from the guess start (25 from Mehrotra's, 2026-12-01)
    g = order2(cg.grid_plane(20, jitter=0.4, seed=1), 0)
    assert g.info.status == "optimal" and g.info.iterations <= 16


def _scaled_system(mesh, src):
    """The equilibrated program's Newton-system object (as the solver builds it) for ``mesh`` from ``src``."""
    from cvxgeodesic.mesh.trimesh import unit_mesh as _unit_mesh
    from cvxgeodesic.solvers import ipm_soc

    unit, _ = _unit_mesh(mesh)
    b = P2Builder(unit)
    pr = b.build(src)
    ipm = ipm_soc.P2InteriorPoint(b)
    seen = {}
    real = ipm_soc._P2System.__init__

    def spy(self, solver, pb):
        real(self, solver, pb)
        seen["system"] = self

    ipm_soc._P2System.__init__ = spy
    try:
        ipm.solve(pr, max_iter=1)
    except cg.SolverError:
        pass
    finally:
        ipm_soc._P2System.__init__ = real
    return pr, seen["system"]


def test_guess_start_is_strictly_feasible_and_meets_the_source_equalities():
    pr, system = _scaled_system(cg.icosphere(2), [0, 17])
    assert pr.guess is not None and pr.guess[pr.fixed].max() == 0.0
    x = system.interior_guess()
    s = system.pb.h - system.solver._Gx(system.pb, x)
    assert (s[:, 0] - np.linalg.norm(s[:, 1:], axis=1)).min() > 0  # every cone strictly inside
    assert np.abs(pr.E @ pr.guess).max() <= 1e-12 * pr.guess.max()  # 4 φ_mid − φ_j = 0 on the source stars
    # the scaling θ is the largest that keeps every cone inside (× GUESS_FRACTION), not a timid one
    from cvxgeodesic.solvers.ipm_soc import GUESS_FRACTION

    theta = system._cone_theta(x / GUESS_FRACTION)
    assert theta.min() == pytest.approx(1.0, rel=1e-9) or theta.min() > 1.0


@pytest.mark.parametrize("lift", [0.0, 0.3], ids=["on-boundary", "inside"])
def test_cone_theta_matches_a_direct_search(lift):
    pr, system = _scaled_system(cg.icosphere(1), 0)
    psi = system.pb.guess
    system.pb.h = system.pb.h.copy()
    system.pb.h[:, 0] *= 1.0 + lift  # the order-2 cones start on the boundary; a lifted head starts them inside
    theta = system._cone_theta(psi)
    g, h = system.solver._Gx(system.pb, psi), system.pb.h
    assert np.isfinite(theta).any()
    for k in np.random.default_rng(0).choice(theta.size, 25, replace=False):
        def margin(t, k=k):
            return (h[k, 0] - t * g[k, 0]) - np.linalg.norm(h[k, 1:] - t * g[k, 1:])

        if np.isfinite(theta[k]):
            assert margin(0.999 * theta[k]) > 0 > margin(1.001 * theta[k])
        else:
            assert min(margin(t) for t in np.geomspace(1e-6, 1e6, 200)) > 0


def test_guess_start_reaches_mehrotras_optimum_in_fewer_iterations(monkeypatch):
    from cvxgeodesic.solvers import ipm_soc

    mesh = cg.icosphere(3)
    guess = order2(mesh, 0)
    monkeypatch.setattr(ipm_soc, "START", "mehrotra")
    plain = order2(mesh, 0)
    assert guess.info.status == plain.info.status == "optimal"
    assert guess.info.iterations < plain.info.iterations
    assert np.abs(guess.distance - plain.distance).max() <= 1e-6 * plain.distance.max()


def test_eliminating_the_source_equalities_keeps_the_optimum(monkeypatch):
    from cvxgeodesic.mesh.trimesh import unit_mesh as _unit_mesh
    from cvxgeodesic.solvers import ipm_soc

    unit, _ = _unit_mesh(cg.icosphere(2))
    b = P2Builder(unit)
    pr = b.build([0, 5])
    reduced, (elim, onto, alpha) = ipm_soc.eliminate_pair_equalities(pr)
    assert reduced.E.shape[0] == 0 and elim.size == pr.E.shape[0]  # every source-star edge row substituted
    assert reduced.fixed[elim].all() and np.allclose(alpha, 0.25)
    ipm = ipm_soc.P2InteriorPoint(b)
    with_elim = ipm.solve(pr)
    monkeypatch.setattr(ipm_soc, "ELIMINATE", False)
    with_schur = ipm.solve(pr)
    assert np.abs(pr.E @ with_elim["x"]).max() <= 1e-12 * with_elim["x"].max()
    assert np.abs(with_elim["x"] - with_schur["x"]).max() <= 1e-6 * with_schur["x"].max()


def test_pair_equalities_that_cannot_be_substituted_stay_rows():
    import scipy.sparse as sps

    from cvxgeodesic.solvers.ipm_soc import eliminate_pair_equalities

    b = P2Builder(cg.icosphere(2))
    pr = b.build(0)
    n_v = b.mesh.n_vertices
    far_edge = int(np.argmax(np.linalg.norm(b.mesh.V[b.mesh.edges].mean(axis=1) - b.mesh.V[0], axis=1)))
    near = int(np.argsort(np.linalg.norm(b.mesh.V - b.mesh.V[0], axis=1))[1])  # next to the source, far from the edge
    extra = sps.csr_matrix(([4.0, -1.0, 1.0, 1.0], ([0, 0, 1, 1], [n_v + far_edge, near, 2, 3])), shape=(2, pr.n))
    pr.E = sps.vstack([pr.E, extra]).tocsr()  # a midpoint tied to a vertex of another face; a row with f ≠ 0
    pr.f = np.concatenate([pr.f, [0.0, 1.0]])
    reduced, (elim, _, _) = eliminate_pair_equalities(pr)
    assert reduced.E.shape[0] == 2 and n_v + far_edge not in elim
    np.testing.assert_array_equal(reduced.f, [0.0, 1.0])


def test_flat_nodes_samples_all_nodes_on_flat_faces_and_midpoints_elsewhere():
    g = cg.grid_plane(8)
    V = g.V.copy()
    V[40, 2] += 0.2  # a bump: the faces around vertex 40 and their neighbours are no longer flat
    mesh = cg.TriMesh(V, g.F)
    b = P2Builder(mesh, samples="flat-nodes")
    flat = b.space.flat_faces
    assert 0 < flat.sum() < mesh.n_faces
    per_face = np.bincount(b.cone_face, minlength=mesh.n_faces)
    assert (per_face[flat] == 6).all() and (per_face[~flat] == 3).all()
    mid = b.cone_bary[np.isin(b.cone_face, np.flatnonzero(~flat))]
    assert np.isclose(mid.max(axis=1), 0.5).all()  # edge midpoints only
    assert p2mod.DEFAULT_SAMPLES == "flat-nodes" and P2Builder(mesh).cone_face.size == b.cone_face.size
    with pytest.raises(ParameterError, match="samples must be 'flat-nodes' or one of"):
        P2Builder(mesh, samples="everywhere")


@pytest.mark.parametrize("threads", [1, 2])
def test_order2_pardiso_follows_the_thread_setting(threads):
    from cvxgeodesic.linalg import pardiso_available

    if not pardiso_available():
        pytest.skip("PARDISO not installed")
    solver = cg.GeodesicSolver(cg.icosphere(2), "qclp", order=2, threads=threads)
    chol = solver._strategy.p2._ipm.chol
    assert chol.backend == "pardiso" and chol.numeric.threads == threads


def test_no_guess_on_meshes_with_flat_faces():
    assert P2Builder(cg.grid_plane(6)).build(0).guess is None


def test_structured_ipm_rejects_cones_of_another_shape():
    from cvxgeodesic.errors import SolverError
    from cvxgeodesic.solvers.ipm_soc import P2InteriorPoint

    b = P2Builder(cg.grid_plane(4))
    pr = b.build(0)
    pr.G = pr.G.copy()
    pr.G[7, 3, 2] += 0.5
    with pytest.raises(SolverError, match="order-2 cone 7: rows 0 and 3 of G differ"):
        P2InteriorPoint(b).solve(pr)


def test_order2_without_numba_solves_with_clarabel_and_says_so(tmp_path):
    import json

    from test_architecture import _BLOCKER, _run

    code = _BLOCKER + r"""
import json
import cvxgeodesic as cg
res = cg.GeodesicSolver(cg.grid_plane(6), "qclp", order=2).solve(0)
assert "numba" not in sys.modules
try:
    cg.GeodesicSolver(cg.grid_plane(6), "qclp", order=2, solver="ipm")
except cg.ParameterError as exc:
    forced = str(exc)
else:
    forced = None
print(json.dumps({"solver": res.info.solver, "status": res.info.status, "notes": res.info.notes, "forced": forced}))
"""
    proc = _run(code, tmp_path / "x")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    info = json.loads(proc.stdout.strip().splitlines()[-1])
    assert info["solver"] == "clarabel" and info["status"] == "optimal"
    assert any("order-2 interior-point solver is not available" in n for n in info["notes"]), info
    assert info["forced"] and "solver='ipm' is not available" in info["forced"], info


def test_cones_on_sources_only():
    corners = np.array([[0, 1, 2], [0, 1, 2], [0, 1, 2], [3, 0, 1], [3, 0, 1]])
    bary = np.array([[1, 0, 0], [0.5, 0.5, 0], [0, 0.5, 0.5], [0, 0.5, 0.5], [0.2, 0.4, 0.4]])
    np.testing.assert_array_equal(p2mod._on_sources(corners, bary, np.array([0, 1])),
                                  [True, True, False, True, False])


@pytest.mark.parametrize("which", ["edge", "face"])
def test_adjacent_sources_are_solved_by_the_structured_solver(which, monkeypatch):
    """Two sources joined by an edge (or a face of three) put the cones on that edge at their apex for every
    feasible φ: with them the program had no strictly feasible point, the structured solver broke down and Clarabel
    took over (icosphere(2): 17 Clarabel iterations; bimba from [0, 7]: 45). They are implied by the source rows
    and left out: the same optimum, from the guess start."""
    mesh = cg.icosphere(2)
    src = mesh.F[0].tolist()[: 2 if which == "edge" else 3]
    r = order2(mesh, src)
    assert r.info.solver == "ipm" and r.info.status == "optimal" and not r.info.notes
    assert r.info.iterations <= 13  # 11 and 12 (2026-12-02); 10 from one source
    # the optimum with the apex cones kept, solved by Clarabel: the cones were redundant
    from cvxgeodesic.mesh.trimesh import unit_mesh as _unit_mesh

    unit, scale = _unit_mesh(mesh)
    monkeypatch.setattr(p2mod, "_on_sources", lambda c, b, v: (b == 1).any(axis=1) & ((b <= 0) | np.isin(c, v)).all(1))
    full = solve_p2_clarabel(P2Builder(unit).build(src), tol=1e-10)
    d_full = np.sqrt(np.maximum(full["x"][: mesh.n_vertices], 0.0)) * scale
    assert np.abs(r.distance - d_full).max() <= 1e-6 * mesh.bbox_diagonal


def test_a_dof_fixed_by_a_one_unknown_row_keeps_no_cone_columns():
    import scipy.sparse as sps

    from cvxgeodesic.solvers.ipm_soc import eliminate_pair_equalities

    b = P2Builder(cg.icosphere(2))
    pr = b.build(0)
    far = int(np.argmax(np.linalg.norm(b.mesh.V - b.mesh.V[0], axis=1)))
    pr.E = sps.vstack([pr.E, sps.csr_matrix(([2.0], ([0], [far])), shape=(1, pr.n))]).tocsr()  # φ_far = 0
    pr.f = np.concatenate([pr.f, [0.0]])
    reduced, _ = eliminate_pair_equalities(pr)
    assert reduced.fixed[far] and reduced.E.shape[0] == 0
    on = pr.cone_dofs == far
    assert on.any() and np.abs(pr.G.transpose(0, 2, 1)[on]).max() > 0
    assert np.abs(reduced.G.transpose(0, 2, 1)[on]).max() == 0.0 and reduced.c[far] == 0.0


def test_a_point_source_in_a_face_of_a_vertex_source_is_solved_by_the_structured_solver():
    # the inserted point's vertex is joined to the vertex source by an edge of the split: adjacent sources again
    # (before 2026-12-02: the structured solver broke down, Clarabel took 19 iterations)
    mesh = cg.icosphere(2)
    f = int(np.flatnonzero((mesh.F == 0).any(axis=1))[0])
    r = order2(mesh, [0, (f, (0.2, 0.3, 0.5))])
    assert r.info.solver == "ipm" and r.info.status == "optimal"
    assert not [n for n in r.info.notes if "Clarabel" in n] and r.info.iterations <= 16  # 14
