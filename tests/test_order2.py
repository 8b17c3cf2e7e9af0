"""Order 2: P2 elements for d² (``operators/lagrange.py``, ``problems/squared_distance.py``,
``strategies/order2.py``)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import cvxgeodesic as cg
import cvxgeodesic.problems.squared_distance as p2mod
from conftest import shared_mesh_path
from cvxgeodesic.errors import ParameterError, SourceError
from cvxgeodesic.mesh.generate import delaunay_plane as delaunay_mesh
from cvxgeodesic.mesh.generate import fan_plate, needle_strip
from cvxgeodesic.mesh.reference import TRIANGLE
from cvxgeodesic.mesh.simplex import unit_mesh
from cvxgeodesic.operators.lagrange import P2, LagrangeSpace
from cvxgeodesic.problems import _study
from cvxgeodesic.problems.conic import clique_pattern
from cvxgeodesic.problems.squared_distance import SquaredDistanceBuilder
from cvxgeodesic.solvers import solve_clarabel
from cvxgeodesic.solvers.ipm import InteriorPointSolver
from cvxgeodesic.solvers.ipm.settings import ORDER2

FLAT_TOL = 1e-5  # max vertex error / largest distance on flat meshes (issue 17)


# ---------------------------------------------------------------- meshes
def euclid_from(mesh: cg.TriMesh, src) -> np.ndarray:
    if isinstance(src, int | np.integer):
        p = mesh.V[src]
    else:
        p = src.position(mesh)
    return np.linalg.norm(mesh.V - p, axis=1)


def pt(face, bary) -> cg.SurfacePoint:
    return cg.SurfacePoint(face, bary)


def ipm_for(builder: SquaredDistanceBuilder) -> InteriorPointSolver:
    """The order-2 strategy's structured solver for ``builder``'s mesh."""
    space = builder.space
    return InteriorPointSolver(clique_pattern(space.n_dofs, [space.cell_dofs]), settings=ORDER2)


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
    N, dN = P2.basis(TRIANGLE, nodes)
    np.testing.assert_allclose(N, np.eye(6), atol=1e-15)
    lam = np.random.default_rng(0).dirichlet([1, 1, 1], 20)
    N, dN = P2.basis(TRIANGLE, lam)
    np.testing.assert_allclose(N.sum(axis=1), 1.0, atol=1e-14)


def test_consistent_weights_integrate_quadratics_exactly(monkeypatch):
    # ∫∫_{[0,1]²} (x² + y²) = 2/3 ; the consistent P2 weights (a study switch) are exact for quadratics on any
    # triangulation
    mesh = cg.grid_plane(5, jitter=0.3, seed=2)
    space = LagrangeSpace(mesh)
    E = mesh.edges
    P = np.vstack([mesh.V, 0.5 * (mesh.V[E[:, 0]] + mesh.V[E[:, 1]])])
    phi = (P[:, :2] ** 2).sum(axis=1)
    assert np.array_equal(_study.objective_weights(space), space.weights())  # the library's default: lumped
    monkeypatch.setattr(_study, "WEIGHTS", "consistent")
    assert _study.objective_weights(space) @ phi == pytest.approx(2 / 3, abs=1e-13)
    assert space.weights().sum() == pytest.approx(1.0, abs=1e-13)
    assert abs(space.weights() @ phi - 2 / 3) > 1e-4  # lumped weights are not exact
    with pytest.raises(ParameterError, match="consistent weights are defined for order-2 triangles only"):
        _study.objective_weights(LagrangeSpace(mesh, 1))
    monkeypatch.setattr(_study, "WEIGHTS", "p2")
    with pytest.raises(ParameterError, match="_study.WEIGHTS must be one of"):
        _study.objective_weights(space)


def test_gradient_of_exact_square_distance_on_a_face():
    mesh = delaunay_mesh(30)
    space = LagrangeSpace(mesh)
    E = mesh.edges
    P = np.vstack([mesh.V, 0.5 * (mesh.V[E[:, 0]] + mesh.V[E[:, 1]])])
    p = np.array([0.3, 0.4, 0.0])
    phi = ((P - p) ** 2).sum(axis=1)
    vmax, _, _ = space.max_violation(phi)  # |∇φ|² − 4φ ≡ 0 for φ = |x − p|²
    assert np.abs(vmax).max() < 1e-12


def test_max_violation_finds_interior_maximum():
    # a hand-built quadratic on one face: v = |∇φ|² − 4φ, compare with dense sampling
    mesh = cg.TriMesh(np.array([[0, 0, 0], [1, 0, 0], [0.2, 0.9, 0.0]]), np.array([[0, 1, 2]]))
    space = LagrangeSpace(mesh)
    rng = np.random.default_rng(1)
    for _ in range(5):
        x = rng.random(space.n_dofs)
        vmax, bary, _ = space.max_violation(x)
        g = np.linspace(0, 1, 81)
        B = np.array([[1 - a - b, a, b] for a in g for b in g if a + b <= 1 + 1e-12])
        N, dN = P2.basis(TRIANGLE, B)
        grad = np.einsum("sai,ci->sca", dN, space.gbasis[0]) @ x[space.cell_dofs[0]]
        v = (grad**2).sum(axis=1) - 4 * N @ x[space.cell_dofs[0]]
        assert vmax[0] >= v.max() - 1e-12
        assert vmax[0] <= v.max() + 1e-3 * (abs(v.max()) + 1)


def test_violations_lists_every_local_maximum_above_the_tolerance():
    mesh = cg.TriMesh(np.array([[0, 0, 0], [1, 0, 0], [0.2, 0.9, 0.0]]), np.array([[0, 1, 2]]))
    space = LagrangeSpace(mesh)
    E = mesh.edges
    nodes = np.vstack([mesh.V, 0.5 * (mesh.V[E[:, 0]] + mesh.V[E[:, 1]])])
    for c in ([0.4, 0.3, 0.0], [0.5, 0.02, 0.0], [0.2, 0.2, 0.0]):
        # φ = ½|x − c|² − 0.1: v = |∇φ|² − 4φ = 0.4 − |x − c|², a maximum at c (inside the face or near an edge)
        x = 0.5 * ((nodes - c) ** 2).sum(axis=1) - 0.1
        vmax, bary, _ = space.max_violation(x)
        faces, points = space.violations(x, -np.inf, np.array([0]))
        assert (faces == 0).all() and points.shape == (faces.size, 3) and np.allclose(points.sum(axis=1), 1)
        assert vmax[0] == pytest.approx(0.4, abs=1e-12)
        assert np.abs(points - bary).max(axis=1).min() < 1e-12  # the worst point is among the listed ones
        assert np.abs(points @ mesh.V - c).max(axis=1).min() < 1e-12
        none, _ = space.violations(x, np.inf, np.array([0]))
        assert none.size == 0


# ---------------------------------------------------------------- flat meshes of any quality
@pytest.mark.parametrize("src", [0, 200, 37])
def test_flat_jittered_grid_vertex_sources(src):
    assert flat_error(cg.grid_plane(20, jitter=0.4, seed=1), src) <= FLAT_TOL


@pytest.mark.parametrize("aspect", [50, 240, 1000])
@pytest.mark.parametrize("src", [0, 5, pt(4, (0.25, 0.25, 0.5))], ids=["v0", "v5", "point"])
def test_flat_needle_strip(aspect, src):
    assert flat_error(needle_strip(10, aspect), src) <= FLAT_TOL


def test_flat_random_delaunay():
    mesh = delaunay_mesh()
    for src in (0, 17):
        assert flat_error(mesh, src) <= FLAT_TOL


def test_flat_fan_plate():
    mesh = fan_plate()
    aspect = mesh.cell_longest_edges / mesh.cell_min_altitudes
    assert aspect.max() > 20  # the fans are long and thin
    for src in (0, 5, mesh.n_vertices - 1, pt(3, (0.3, 0.3, 0.4)), pt(15, (0.1, 0.1, 0.8))):
        assert flat_error(mesh, src) <= FLAT_TOL


@pytest.mark.parametrize("bary", [(0.2, 0.3, 0.5), (0.5, 0.5, 0.0), (1 / 3, 1 / 3, 1 / 3)])
def test_flat_in_face_sources(bary):
    mesh = cg.grid_plane(20, jitter=0.4, seed=1)
    assert flat_error(mesh, pt(37, bary)) <= FLAT_TOL
    assert flat_error(delaunay_mesh(), pt(10, bary)) <= FLAT_TOL


def test_an_edge_point_is_one_source_at_order_2():
    # resolve_sources lists a point on an edge once per face of the edge; order 2 inserts it once
    mesh = cg.grid_plane(12, jitter=0.3, seed=4)
    p = pt(37, (0.5, 0.5, 0.0))
    sset = cg.sources.resolve_sources(mesh, p)
    assert sset.point_faces.size == 2 and len(sset.distinct_points(mesh)) == 1
    res = order2(mesh, [p])
    assert np.abs(res.distance - euclid_from(mesh, p)).max() <= FLAT_TOL
    assert any("1 source point(s) inserted" in n for n in res.info.notes)


def test_field_inside_faces_flat():
    mesh = delaunay_mesh(120)
    res = order2(mesh, 3)
    fld = res.field
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
    src = pt(12, (0.2, 0.5, 0.3))
    res = order2(mesh, src)
    fld = res.field
    p = src.position(mesh)
    bary = np.array([[0.6, 0.2, 0.2], [0.1, 0.1, 0.8], src.bary])
    pts = bary @ mesh.V[mesh.F[12]]
    got = fld.distance_at(np.full(3, 12), bary)
    np.testing.assert_allclose(got, np.linalg.norm(pts - p, axis=1), atol=1e-4)
    assert got[-1] < 1e-4


def test_sampled_cones_need_cutting_planes_next_to_an_inserted_source():
    # with the cone at the six nodes only ("flat-nodes", the default before the edge cones) the field overshoots
    # between the samples: 3.7e-3 of the largest distance without the cutting planes
    mesh = cg.grid_plane(20, jitter=0.4, seed=1)
    ex = euclid_from(mesh, pt(37, (0.2, 0.3, 0.5)))
    s = cg.GeodesicSolver(mesh, "qclp", order=2)
    s._strategy.refine, s._strategy.edge_cones = 0, False
    res = s.solve(pt(37, (0.2, 0.3, 0.5)))
    assert np.abs(res.distance - ex).max() / ex.max() > 1e-3
    assert res.info.extra["rounds"] == 0 and len(res.info.extra["round_iterations"]) == 1


def test_edge_cones_make_a_flat_mesh_exact_in_one_solve():
    # the Bernstein edge cones hold |∇φ|² ≤ 4φ on the whole of each flat face: no cutting plane is needed, from a
    # vertex or from a point inside a face (measured 5e-9 of the largest distance)
    mesh = cg.grid_plane(20, jitter=0.4, seed=1)
    s = cg.GeodesicSolver(mesh, "qclp", order=2)
    s._strategy.refine = 0
    for src in (pt(37, (0.2, 0.3, 0.5)), 200):
        ex = euclid_from(mesh, src if isinstance(src, int) else pt(37, (0.2, 0.3, 0.5)))
        res = s.solve(src)
        assert res.info.status == "optimal" and res.info.extra["rounds"] == 0
        assert np.abs(res.distance - ex).max() / ex.max() < 1e-7
    # and with the rounds allowed, none is run
    assert len(order2(mesh, pt(37, (0.2, 0.3, 0.5))).info.extra["round_iterations"]) == 1


def test_cutting_plane_rounds_are_counted_in_the_info():
    mesh = cg.grid_plane(20, jitter=0.4, seed=1)
    s = cg.GeodesicSolver(mesh, "qclp", order=2)
    s._strategy.edge_cones = False
    res = s.solve(pt(37, (0.2, 0.3, 0.5)))
    rounds = res.info.extra["round_iterations"]
    assert res.info.extra["rounds"] == len(rounds) - 1 >= 1
    assert res.info.iterations == sum(rounds)  # every round's solve, not the last one's


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
        cg.GeodesicSolver(mesh, "lcqp-hessian", order=2)
    with pytest.raises(ParameterError, match="order=2"):
        cg.GeodesicSolver(mesh, "heat", order=2)


def test_bad_sources():
    mesh = cg.icosphere(1)
    s = cg.GeodesicSolver(mesh, "qclp", order=2)
    for bad, msg in (([], "empty"), (mesh.n_vertices, "out of range"), ([1, 1], "more than once"),
                     ([pt(mesh.n_faces, (1, 0, 0))], "face"), (True, "vertex"), ("a", "sources")):
        with pytest.raises(SourceError, match=msg):
            s.solve(bad)
    with pytest.raises(SourceError, match="curves at order 1"):
        s.solve(cg.SurfaceCurve([pt(0, (0.2, 0.3, 0.5)), pt(5, (0.3, 0.3, 0.4))]))


def test_boundary_source_at_order_2():
    # the distance to the boundary of a flat square is exact at order 2 away from the medial axis
    mesh = cg.grid_plane(12, jitter=0.2, seed=3)
    res = order2(mesh, "boundary")
    x, y = mesh.V[:, 0], mesh.V[:, 1]
    ex = np.minimum.reduce([x, 1 - x, y, 1 - y])
    assert res.info.status == "optimal" and (res.distance[ex == 0] == 0).all()
    assert np.abs(res.distance - ex).max() <= 0.08  # the ridge (cut locus) of four faces of the square
    corner_band = np.minimum(np.abs(x - y), np.abs(x + y - 1)) > 0.15  # off the diagonals
    assert np.abs(res.distance - ex)[corner_band].max() <= 1e-4


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
    unit, _ = unit_mesh(mesh)
    b = SquaredDistanceBuilder(unit)
    pr = b.build(np.array([0])).problem
    ipm = ipm_for(b)
    ri = ipm.solve(pr)
    rc = solve_clarabel(pr)
    assert ri.status in ("optimal", "almost_optimal")
    assert np.abs(ri.x - rc.x).max() <= 1e-6 * rc.x.max()
    assert ipm.n_analyses == 1
    ipm.solve(b.build(np.array([5])).problem)  # another source: same symbolic analysis
    assert ipm.n_analyses == 1


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

    def boom(self, problem, **kw):
        raise SolverError("forced", solver="ipm", status="numerical_error")

    monkeypatch.setattr(InteriorPointSolver, "solve", boom)
    mesh = cg.grid_plane(6, jitter=0.2, seed=0)
    with pytest.warns(RuntimeWarning, match="solving with Clarabel instead"):
        res = order2(mesh, 4)
    assert res.info.solver == "clarabel" and res.info.extra["ipm_failure"] == "numerical_error"
    assert any("solving with Clarabel instead" in n for n in res.info.notes)
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


# ---------------------------------------------------------------- the order-2 program on the one solver
def test_clique_block_matches_the_general_sparse_block():
    """The compiled clique block (order 2's cones on six P2 nodes) against SparseBlock, the NumPy/SciPy block the
    solver's dense-reference tests cover: every product the algorithm takes."""
    import scipy.sparse as sp

    from cvxgeodesic.linalg import SymbolicCholesky
    from cvxgeodesic.problems.conic import ConeGroup
    from cvxgeodesic.solvers.ipm.blocks import CliqueSOCBlock, SparseBlock

    rng = np.random.default_rng(4)
    k, n, d, c = 40, 30, 4, 6
    dofs = np.array([rng.choice(n, c, replace=False) for _ in range(k)], dtype=np.int64)
    group = ConeGroup(dofs, rng.normal(size=(k, d, c)), rng.normal(size=(k, d)))
    chol = SymbolicCholesky(clique_pattern(n, [dofs]))
    x_fixed = np.zeros(n)
    x_fixed[3] = 0.7
    cb = CliqueSOCBlock(group, x_fixed, chol)
    sb = SparseBlock(cb.cone, group.matrix(n), group.h.ravel(), x_fixed, chol)
    x, v = rng.normal(size=n), rng.normal(size=n)
    np.testing.assert_allclose(cb.A(x), sb.A(x), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(cb.b_tilde, sb.b_tilde, rtol=1e-12, atol=1e-12)
    z = rng.normal(size=(d, k))
    o1, o2 = np.zeros(n), np.zeros(n)
    cb.At_add(z, o1)
    sb.At_add(z, o2)
    np.testing.assert_allclose(o1, o2, rtol=1e-12, atol=1e-12)
    u = rng.normal(size=(d, k))
    s_in, z_in = u.copy(), u.copy()
    s_in[0] = np.linalg.norm(u[1:], axis=0) * 1.5 + 0.1
    z_in[0] = np.linalg.norm(u[1:], axis=0) + 1.0
    sc = cb.cone.scaling(s_in, z_in)
    o1, o2 = np.zeros(n), np.zeros(n)
    cb.kkt_add(sc, v, o1)
    sb.kkt_add(sc, v, o2)
    np.testing.assert_allclose(o1, o2, rtol=1e-10, atol=1e-10)
    d1, d2 = np.zeros(chol.nnz), np.zeros(chol.nnz)
    cb.assemble_add(sc, d1)
    sb.assemble_add(sc, d2)
    np.testing.assert_allclose(d1, d2, rtol=1e-10, atol=1e-10)
    K = chol.matrix(d1)
    np.testing.assert_allclose(K @ v, o1, rtol=1e-10, atol=1e-10)  # the assembled matrix is the operator
    wu, wr, rz = rng.normal(size=(d, k)), rng.normal(size=(d, k)), rng.normal(size=(d, k))
    for got, want in zip(cb.newton(v, sc, wu, wr, rz), sb.newton(v, sc, wu, wr, rz), strict=True):
        np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-10)
    assert sp.issparse(group.matrix(n))


def test_structured_ipm_iteration_counts():
    """Gondzio's correctors and the guess start took spot from 48 to 16 iterations and a jittered 20×20 grid
    (Mehrotra's start then: flat faces had no guess) from 27 to 14 (2026-12-01, counted then from 1; 2026-12-02 on
    the generic solver: 16 and 14; with the edge cones and the guess start on flat faces 15, in one solve); a
    regression in the correctors, the start, the step or the scaling shows here first. Since the edge cones the grid's
    guess start was declined (too small a step towards the guess) and it took 14 from Mehrotra's; since the guess
    start leaves out the cones that block it (start.PARTIAL_GUESS_MIN_STEP), 13 from the guess."""
    spot = cg.load_mesh(shared_mesh_path("spot.obj"))
    r = order2(spot, 0)
    assert r.info.solver == "ipm" and r.info.status == "optimal" and r.info.extra["start"] == "guess"
    assert r.info.iterations <= 17
    g = order2(cg.grid_plane(20, jitter=0.4, seed=1), 0)
    assert g.info.status == "optimal" and g.info.extra["round_iterations"] == [g.info.iterations]
    assert g.info.iterations <= 14 and g.info.extra["start"] == "guess"


def _program(mesh, src, **kw):
    unit, _ = unit_mesh(mesh)
    b = SquaredDistanceBuilder(unit)
    return b, b.build(np.asarray(src), **kw)


def test_guess_start_is_strictly_feasible_and_meets_the_source_equalities():
    from cvxgeodesic.solvers.ipm.equilibrate import equilibrate
    from cvxgeodesic.solvers.ipm.program import Program
    from cvxgeodesic.solvers.ipm.start import guess_primal

    b, prog = _program(cg.icosphere(2), [0, 17], eliminate=False)
    pr = prog.problem
    assert pr.guess is not None and pr.guess[pr.fixed_mask].max() == 0.0
    assert np.abs(pr.eq.E @ pr.guess).max() <= 1e-12 * pr.guess.max()  # 4 φ_mid − φ_j = 0 on the source stars
    scaled, D = equilibrate(pr)
    chol = ipm_for(b).cholesky
    program = Program.from_problem(scaled, chol)
    x, left_out = guess_primal(program, ORDER2.interior_fraction)
    blk, bound = program.blocks[0], ~left_out[0]
    assert bound.mean() > 0.99  # a curved mesh: no edge cones, nearly every cone bounds the step
    s = blk.slack(x, program.x_fixed)
    assert (s[0] - np.linalg.norm(s[1:], axis=0))[bound].min() > 0  # those cones strictly inside
    # the scaling θ is the largest that keeps them inside (× interior_fraction), not a timid one
    x_full, _ = guess_primal(program, 1.0)
    s_full = blk.slack(x_full, program.x_fixed)
    assert (s_full[0] - np.linalg.norm(s_full[1:], axis=0))[bound].min() < 1e-9 * np.abs(s_full).max() or \
        np.allclose(x_full, program.guess)


def test_guess_start_leaves_out_the_few_cones_that_block_it():
    # a guess that some cones reject strongly (here one P2 node's value tripled; on armadillo 36 of 259K cones
    # held the start to 1.3 % of the way to the squared Dijkstra guess) is approached as far as the other cones
    # allow; the left-out cones' slacks are shifted into their cones
    from cvxgeodesic.solvers.ipm.equilibrate import equilibrate
    from cvxgeodesic.solvers.ipm.newton import LinearSystem
    from cvxgeodesic.solvers.ipm.program import Program
    from cvxgeodesic.solvers.ipm.start import PARTIAL_GUESS_MIN_STEP, guess_primal, starting_point

    b, prog = _program(cg.icosphere(2), [0])
    scaled, _ = equilibrate(prog.problem)
    solver = ipm_for(b)
    program = Program.from_problem(scaled, solver.cholesky)
    node = b.space.mesh.n_vertices + 200  # an edge's node far from the source
    program.guess[node] *= 3.0
    blk = program.blocks[0]
    step = np.where(program.fixed, 0.0, program.guess - program.x_fixed)
    reach = blk.cone.max_step_closed(blk.b_tilde, -blk.A(step))
    blocking = reach < PARTIAL_GUESS_MIN_STEP
    assert 0 < blocking.sum() <= 6 and reach.min() < 0.05  # the cones at that node
    x, left_out = guess_primal(program, ORDER2.interior_fraction)
    assert np.array_equal(left_out[0], blocking)
    alpha = ((x - program.x_fixed)[~program.fixed] / step[~program.fixed]).mean()
    assert alpha == pytest.approx(min(1.0, ORDER2.interior_fraction * reach[~blocking].min()))
    ls = LinearSystem(program, solver.cholesky, ORDER2, {"assembly_time": 0.0, "factor_time": 0.0,
                                                         "linear_solve_time": 0.0}, {"refinement_steps": 0})
    start = starting_point(program, ls, ORDER2)
    assert start.from_guess and np.allclose(start.iterate.x, x)
    for cone_block, s in zip(program.blocks, start.iterate.s, strict=True):
        assert s.size == 0 or cone_block.cone.min_eigenvalue(s) > 0  # every slack strictly inside its cone


@pytest.mark.parametrize("lift", [0.0, 0.3], ids=["on-boundary", "inside"])
def test_step_from_the_boundary_matches_a_direct_search(lift):
    from cvxgeodesic.solvers.ipm.cones import SOC

    _, prog = _program(cg.icosphere(1), [0])
    pr = prog.problem
    g = pr.cones[0]
    h = g.h.T.copy()
    h[0] *= 1.0 + lift  # the order-2 cones start on the boundary; a lifted head starts them inside
    du = -np.einsum("kdc,kc->dk", g.G, pr.guess[g.dofs])
    theta = SOC(4).max_step_closed(h, du)
    assert np.isfinite(theta).any()
    for k in np.random.default_rng(0).choice(theta.size, 25, replace=False):
        def margin(t, k=k):
            u = h[:, k] + t * du[:, k]
            return u[0] - np.linalg.norm(u[1:])

        if np.isfinite(theta[k]):
            assert margin(0.999 * theta[k]) > 0 > margin(1.001 * theta[k])
        else:
            assert min(margin(t) for t in np.geomspace(1e-6, 1e6, 200)) > 0


def test_guess_start_reaches_mehrotras_optimum_in_fewer_iterations():
    import dataclasses

    b, prog = _program(cg.icosphere(3), [0])
    guess = ipm_for(b).solve(prog.problem)
    plain = InteriorPointSolver(ipm_for(b).cholesky, settings=dataclasses.replace(ORDER2, init="mehrotra")
                                ).solve(prog.problem)
    assert guess.status == plain.status == "optimal"
    assert guess.extra["start"] == "guess" and plain.extra["start"] == "mehrotra"
    assert guess.iterations < plain.iterations
    assert np.abs(guess.x - plain.x).max() <= 1e-6 * plain.x.max()


def test_eliminating_the_source_equalities_keeps_the_optimum():
    """The zero cone: the source-star rows kept as equalities (Schur complement in the solver) or substituted into
    the cones give the same optimum."""
    b, with_rows = _program(cg.icosphere(2), [0, 5], eliminate=False)
    _, substituted = _program(cg.icosphere(2), [0, 5])
    E = with_rows.problem.eq.E
    elim = substituted.eliminated[0]
    assert substituted.problem.eq is None and elim.size == E.shape[0]  # every source-star edge row substituted
    assert substituted.problem.fixed_mask[elim].all() and np.allclose(substituted.eliminated[1].data, 0.25)
    ipm = ipm_for(b)
    x_sub = substituted.restore(ipm.solve(substituted.problem).x)
    r_rows = ipm.solve(with_rows.problem)
    assert r_rows.status == "optimal"
    assert np.abs(E @ x_sub).max() <= 1e-12 * x_sub.max()
    assert np.abs(E @ r_rows.x).max() <= 1e-9 * r_rows.x.max()
    assert np.abs(x_sub - r_rows.x).max() <= 1e-6 * r_rows.x.max()
    rc = solve_clarabel(with_rows.problem)  # Clarabel takes the rows as its zero cone
    assert np.abs(rc.x - r_rows.x).max() <= 1e-5 * r_rows.x.max()  # two solvers at tol 1e-8: 3e-6 measured


def test_pair_equalities_that_cannot_be_substituted_stay_rows():
    import scipy.sparse as sps

    from cvxgeodesic.problems.squared_distance import eliminate_pair_equalities

    b, prog = _program(cg.icosphere(2), [0], eliminate=False)
    pr = prog.problem
    mesh = b.mesh
    n_v = mesh.n_vertices
    far_edge = int(np.argmax(np.linalg.norm(mesh.V[mesh.edges].mean(axis=1) - mesh.V[0], axis=1)))
    near = int(np.argsort(np.linalg.norm(mesh.V - mesh.V[0], axis=1))[1])  # next to the source, far from the edge
    extra = sps.csr_matrix(([4.0, -1.0], ([0, 0], [n_v + far_edge, near])), shape=(1, pr.n))
    E = sps.vstack([pr.eq.E, extra]).tocsr()  # a midpoint tied to a vertex of another face
    g = pr.cones[0]
    _, _, E2, _, (elim, _, _) = eliminate_pair_equalities(pr.n, g.dofs, g.G, pr.q, E, pr.fixed_mask)
    assert E2.shape[0] == 1 and n_v + far_edge not in elim


def test_a_dof_fixed_by_a_one_unknown_row_keeps_no_cone_columns():
    import scipy.sparse as sps

    from cvxgeodesic.problems.squared_distance import eliminate_pair_equalities

    b, prog = _program(cg.icosphere(2), [0], eliminate=False)
    pr = prog.problem
    far = int(np.argmax(np.linalg.norm(b.mesh.V - b.mesh.V[0], axis=1)))
    E = sps.vstack([pr.eq.E, sps.csr_matrix(([2.0], ([0], [far])), shape=(1, pr.n))]).tocsr()  # φ_far = 0
    g = pr.cones[0]
    G2, c2, E2, fixed2, _ = eliminate_pair_equalities(pr.n, g.dofs, g.G, pr.q, E, pr.fixed_mask)
    assert fixed2[far] and E2.shape[0] == 0
    on = g.dofs == far
    assert on.any() and np.abs(g.G.transpose(0, 2, 1)[on]).max() > 0
    assert np.abs(G2.transpose(0, 2, 1)[on]).max() == 0.0 and c2[far] == 0.0


def test_a_midpoint_in_no_cone_is_tied_to_its_edge():
    """A degenerate face's edge shorter than MIN_EDGE gets no 1-D cone: its midpoint would be unbounded (the
    generic solver certifies that as dual infeasible). It is tied to the mean of its ends."""
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [1, 1e-12, 0]], float)
    F = np.array([[0, 1, 2], [1, 3, 2], [1, 4, 3]])  # the last face is degenerate, its edge (1, 4) tiny
    mesh = cg.TriMesh(V, F)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", cg.DegenerateFacesWarning)
        b, prog = _program(mesh, [0])
    e = int(np.flatnonzero((np.sort(b.mesh.edges, axis=1) == [1, 4]).all(axis=1))[0])
    m = b.mesh.n_vertices + e
    assert m in prog.eliminated[0] and prog.problem.fixed_mask[m] and prog.problem.q[m] == 0
    res = order2(mesh, 0)
    assert res.info.status == "optimal"
    phi = res.field.phi
    assert phi[m] == pytest.approx(0.5 * (phi[1] + phi[4]), rel=1e-12)


def test_flat_nodes_samples_all_nodes_on_flat_faces_and_midpoints_elsewhere():
    g = cg.grid_plane(8)
    V = g.V.copy()
    V[40, 2] += 0.2  # a bump: the faces around vertex 40 and their neighbours are no longer flat
    mesh = cg.TriMesh(V, g.F)
    b = SquaredDistanceBuilder(mesh)
    flat = b.space.flat_cells
    assert 0 < flat.sum() < mesh.n_faces
    per_face = np.bincount(b.cone_cell, minlength=mesh.n_faces)
    assert (per_face[flat] == 6).all() and (per_face[~flat] == 3).all()
    mid = b.cone_bary[np.isin(b.cone_cell, np.flatnonzero(~flat))]
    assert np.isclose(mid.max(axis=1), 0.5).all()  # edge midpoints only
    # and three edge cones on each flat face, which replace its midpoint samples
    assert np.array_equal(np.sort(b.bernstein.face), np.repeat(np.flatnonzero(flat), 3))
    assert b.cone_replaced.sum() == 3 * flat.sum()


@pytest.mark.parametrize("threads", [1, 2])
def test_order2_pardiso_follows_the_thread_setting(threads):
    from cvxgeodesic.linalg import pardiso_available

    if not pardiso_available():
        pytest.skip("PARDISO not installed")
    solver = cg.GeodesicSolver(cg.icosphere(2), "qclp", order=2, threads=threads)
    solver.solve(0)  # the mesh's own analysis runs at the first solve from a vertex, under the solver's threads
    chol = solver._strategy.ipm.cholesky
    assert chol.backend == "pardiso" and chol.numeric.threads == threads


def test_a_solve_from_points_never_analyses_the_unsplit_mesh():
    # a point source is solved on its split mesh with that mesh's own analysis: the unsplit mesh's analysis would be
    # paid for nothing (an adapted copy's sources are always points)
    solver = cg.GeodesicSolver(cg.icosphere(2), "qclp", order=2, solver="ipm")
    solver.solve(cg.SurfacePoint(3, (0.2, 0.3, 0.5)))
    assert "ipm" not in vars(solver._strategy)
    solver.solve(0)
    assert "ipm" in vars(solver._strategy)


def test_guess_start_on_flat_faces_steps_over_the_cones_that_hold_at_zero(monkeypatch):
    # the edge cones do not hold at φ = 0 (T = −|e|² there): the segment from x_F towards the guess is bounded by
    # the sampled cones alone, and the edge cones' slacks are shifted into their cone
    from cvxgeodesic.solvers.ipm.equilibrate import equilibrate
    from cvxgeodesic.solvers.ipm.program import Program
    from cvxgeodesic.solvers.ipm.start import guess_primal, starting_point

    b, prog = _program(cg.grid_plane(6, jitter=0.3, seed=2), [0])
    pr = prog.problem
    assert pr.guess is not None and [g.size for g in pr.cones] == [4, 6]
    scaled, _ = equilibrate(pr)
    solver = ipm_for(b)
    program = Program.from_problem(scaled, solver.cholesky)
    x, left_out = guess_primal(program, ORDER2.interior_fraction)
    # every SOC(6) edge cone is left out (none holds at x_F); the sampled SOC(4) cones bound the step
    assert [getattr(blk.cone, "size", 0) for blk, out in zip(program.blocks, left_out, strict=True)
            if out.size and out.all()] == [6]
    s4 = program.blocks[0].slack(x, program.x_fixed)
    assert (s4[0] - np.linalg.norm(s4[1:], axis=0))[~left_out[0]].min() > 0
    from cvxgeodesic.solvers.ipm.newton import LinearSystem

    ls = LinearSystem(program, solver.cholesky, ORDER2, {"assembly_time": 0.0, "factor_time": 0.0,
                                                         "linear_solve_time": 0.0}, {"refinement_steps": 0})
    start = starting_point(program, ls, ORDER2)
    assert start.from_guess
    for blk, s in zip(program.blocks, start.iterate.s, strict=True):
        assert s.size == 0 or blk.cone.min_eigenvalue(s) > 0  # every slack strictly inside its cone
    # no cone reaching PARTIAL_GUESS_MIN_STEP: no guess start
    import cvxgeodesic.solvers.ipm.start as start_mod

    monkeypatch.setattr(start_mod, "PARTIAL_GUESS_MIN_STEP", np.inf)
    assert guess_primal(program, ORDER2.interior_fraction) is None


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
    assert any("interior-point solver is not available" in n for n in info["notes"]), info
    assert info["forced"] and "solver='ipm' is not available" in info["forced"], info


def test_cones_on_sources_only():
    corners = np.array([[0, 1, 2], [0, 1, 2], [0, 1, 2], [3, 0, 1], [3, 0, 1]])
    # the cells' edges in reference.edges order ((1, 2), (2, 0), (0, 1) locally): edge 0 joins the sources 0 and 1
    edges = np.array([[1, 2, 0], [1, 2, 0], [1, 2, 0], [0, 3, 4], [0, 3, 4]])
    bary = np.array([[1, 0, 0], [0.5, 0.5, 0], [0, 0.5, 0.5], [0, 0.5, 0.5], [0.2, 0.4, 0.4]])
    is_src = np.isin(np.arange(4), [0, 1])
    zero = np.array([True, False, False, False, False])
    np.testing.assert_array_equal(p2mod._on_sources(TRIANGLE, corners, edges, bary, is_src, zero),
                                  [True, True, False, True, False])
    # two sources joined by an edge that is no source edge (a chord of a solid's source wall): its midpoint is free
    np.testing.assert_array_equal(p2mod._on_sources(TRIANGLE, corners, edges, bary, is_src, ~zero),
                                  [True, False, False, False, False])


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
    monkeypatch.setattr(p2mod, "_on_sources", lambda r, c, e, b, s, z: (b == 1).any(axis=1) & ((b <= 0) | s[c]).all(1))
    unit, scale = unit_mesh(mesh)
    full = SquaredDistanceBuilder(unit).build(np.array(src))
    x = full.restore(solve_clarabel(full.problem, tol=1e-10).x)
    d_full = np.sqrt(np.maximum(x[: mesh.n_vertices], 0.0)) * scale
    assert np.abs(r.distance - d_full).max() <= 1e-6 * mesh.bbox_diagonal


def test_a_point_source_in_a_face_of_a_vertex_source_is_solved_by_the_structured_solver():
    # the inserted point's vertex is joined to the vertex source by an edge of the split: adjacent sources again
    # (before 2026-12-02: the structured solver broke down, Clarabel took 19 iterations)
    mesh = cg.icosphere(2)
    f = int(np.flatnonzero((mesh.F == 0).any(axis=1))[0])
    r = order2(mesh, [0, pt(f, (0.2, 0.3, 0.5))])
    assert r.info.solver == "ipm" and r.info.status == "optimal"
    assert not [n for n in r.info.notes if "Clarabel" in n] and r.info.iterations <= 16  # 14


# ---------------------------------------------------------------- Bernstein edge cones
def _triangle_and_nodes(rng):
    V = np.column_stack([rng.uniform(-1, 1, (3, 2)), np.zeros(3)])
    mesh = cg.TriMesh(V, np.array([[0, 1, 2]]))
    b = SquaredDistanceBuilder(mesh)
    X = V[:, :2]
    nodes = np.vstack([X, 0.5 * (X[[1, 2, 0]] + X[[2, 0, 1]])])  # local DOF order: corners, then the midpoint
    return mesh, b, nodes  # opposite each corner


def _edge_slacks(b, phi_face):
    keep = np.ones(b.bernstein.face.size, dtype=bool)
    G, h = b.bernstein.rows(keep, np.ones(keep.size))
    s = h - G @ phi_face
    return s[:, 0] - np.linalg.norm(s[:, 1:], axis=1)


def test_edge_cones_are_tight_on_the_squared_distance_to_any_point():
    rng = np.random.default_rng(0)
    for _ in range(20):
        _, b, nodes = _triangle_and_nodes(rng)
        assert b.bernstein.face.size == 3
        p = rng.uniform(-3, 3, 2)
        phi = np.sum((nodes - p) ** 2, axis=1)
        # the cone |w|² ≤ 4T holds with equality: its slack head − ‖body‖ is 0 up to rounding
        np.testing.assert_allclose(_edge_slacks(b, phi), 0.0, atol=1e-10)
        # lowered by 1e-3 it leaves every edge cone (T drops by 2e-3); raised, it is inside
        assert (_edge_slacks(b, phi - 1e-3) < 0).all() and (_edge_slacks(b, phi + 1e-3) > 0).all()


def test_edge_and_corner_cones_hold_the_gradient_bound_on_the_whole_face():
    # every quadratic that meets the corner cones and the edge cones has |∇φ|² ≤ 4φ everywhere on the triangle
    # (the Bernstein coefficients of |∇φ|² − 4φ are ≤ 0); perturbations of |x − p|², kept where the cones hold
    rng = np.random.default_rng(1)
    t = np.linspace(0, 1, 41)
    l1, l2 = np.meshgrid(t, t)
    bary = np.column_stack([l1.ravel(), l2.ravel(), 1 - l1.ravel() - l2.ravel()])
    bary = bary[bary[:, 2] >= -1e-12]
    N, dN = P2.basis(TRIANGLE, bary)
    tried = accepted = 0
    while accepted < 200:
        mesh, b, nodes = _triangle_and_nodes(rng)
        p = rng.uniform(-3, 3, 2)
        phi = np.sum((nodes - p) ** 2, axis=1) * rng.uniform(0.9, 1.3) + rng.normal(0, 0.05, 6)
        tried += 1
        grad = np.einsum("sai,ci->sca", dN, b.space.gbasis[0])  # (s, 2, 6)
        _, gc = b.space.cell_cones(np.eye(3))
        corner_ok = np.all(np.sum((gc[0] @ phi) ** 2, axis=1) <= 4 * phi[:3])
        if not (corner_ok and (_edge_slacks(b, phi) >= 0).all()):
            continue
        accepted += 1
        v = np.sum((grad @ phi) ** 2, axis=1) - 4 * (N @ phi)
        assert v.max() <= 1e-9 * np.abs(phi).max()
    assert tried > accepted  # the filter rejects some: the test is not vacuous


def test_edge_cones_that_leave_no_feasible_program_are_replaced_by_samples():
    # between two sources of one flat region the edge cones (tangent at the Hessian 2I) can exclude every field:
    # thingi_243015 from vertices 1462 and 551 is infeasible with them; the strategy solves again with the midpoint
    # samples and cutting planes, and says so
    mesh = cg.load_mesh(shared_mesh_path("thingi_243015.stl"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = cg.GeodesicSolver(mesh, "qclp", order=2).solve([1462, 551])
    assert res.info.status == "optimal" and res.info.solver == "ipm"
    assert any("edge cones ended 'primal_infeasible'" in n for n in res.info.notes)
    assert res.info.extra["rounds"] >= 1 and np.isfinite(res.distance).all() and res.distance.min() == 0.0


def test_surface_only_options_are_refused_on_tetrahedra():
    # the edge cones and the smoothness energies exist on triangles only
    from cvxgeodesic.mesh.tet_generate import tet_box

    box = tet_box(2)
    b = SquaredDistanceBuilder(box)  # every node of every tetrahedron, no edge cones
    assert b.space.dim == 3 and b.bernstein.face.size == 0 and not b.cone_replaced.any()
    assert np.array_equal(np.bincount(b.cone_cell), np.full(box.n_cells, 10))
    # the builder's own argument check (the API edge refuses these with the capability table's reasons)
    for energy in ("hessian", "laplacian"):
        with pytest.raises(ParameterError, match="^the order-2 program on tetrahedral meshes takes no smoothness "
                                                 "energy"):
            SquaredDistanceBuilder(box, energy=energy, lam=0.1)
    assert SquaredDistanceBuilder(box, energy="laplacian", lam=0.0).energy is None  # λ = 0: qclp



@pytest.mark.parametrize("w", [0.98, 0.9])
def test_a_source_point_next_to_a_curved_vertex(w):
    """Around a curved vertex next to a source point the field is not one quadratic per face (the vertex's shadow
    starts there); with midpoint samples alone it overshot and carried the overshoot downstream (cylinder: 1.1-1.7 %
    mean error, sphere 0.7-0.9 %). The corner samples next to the sources keep it as accurate as from the vertex."""
    point = cg.SurfacePoint(10, [w, (1 - w) / 2, (1 - w) / 2])
    cylinder = cg.cylinder(24, 12)  # developable: d² is one quadratic per face wherever one unfolding reaches it
    exact = cg.geodesic_distance(cylinder, [point], method="exact")
    d = cg.geodesic_distance(cylinder, [point], method="qclp", order=2)
    np.testing.assert_allclose(d, exact, rtol=1e-4, atol=1e-4)
    sphere = cg.icosphere(3)

    def far_error(source):
        exact = cg.geodesic_distance(sphere, source, method="exact")
        d = cg.geodesic_distance(sphere, source, method="qclp", order=2)
        far = exact > 0.2 * exact.max()
        return np.mean(np.abs(d[far] - exact[far]) / exact[far])

    assert far_error([point]) < 1.5 * far_error(int(sphere.F[10, 0]))  # 0.060 % and 0.063 % against 0.061 %
