"""Sources anywhere on the surface: points, edge points, curves, the boundary (issue 15)."""

from __future__ import annotations

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic.errors import SourceError
from cvxgeodesic.problems.formulations import FORMULATIONS, MeshOperators, build_problem
from cvxgeodesic.sources import boundary_edges, resolve_sources

PLANE = cg.grid_plane(12, jitter=0.25)


def _center_vertex(mesh):
    return int(np.argmin(np.linalg.norm(mesh.V - [0.5, 0.5, 0.0], axis=1)))


@pytest.mark.parametrize("method", ["qclp", "qcqp-hessian", "lclp", "lcqp-laplacian"])
def test_point_at_vertex_position_reproduces_vertex_field(method):
    mesh = cg.icosphere(2)
    v = 17
    d0 = cg.geodesic_distance(mesh, v, method=method)
    p = cg.surface_point(mesh, mesh.V[v])
    d1 = cg.geodesic_distance(mesh, p, method=method)
    assert np.abs(d1 - d0).max() <= 1e-5 * mesh.bbox_diagonal
    # the same vertex written as a corner of one of its faces
    f = int(np.flatnonzero((mesh.F == v).any(axis=1))[0])
    d2 = cg.geodesic_distance(mesh, cg.SurfacePoint(f, (mesh.F[f] == v).astype(float)), method=method)
    assert np.abs(d2 - d0).max() <= 1e-5 * mesh.bbox_diagonal


def test_point_inside_face_on_jittered_plane():
    """Measured (grid_plane(20, jitter=0.25)): point 1.84 %, vertex source at the centre 2.66 %."""
    mesh = cg.grid_plane(20, jitter=0.25)
    p = cg.surface_point(mesh, [0.5 + 0.37 / 20, 0.5 + 0.21 / 20, 0.0])
    assert p.bary.min() > 0.1  # strictly inside its face
    x = p.position(mesh)
    exact = np.linalg.norm(mesh.V - x, axis=1)
    d = cg.geodesic_distance(mesh, p, method="qclp")
    far = exact > 0.1
    rel = np.abs(d - exact)[far] / exact[far]
    assert rel.mean() <= 0.025
    # the face's vertices sit at their straight distance to the point (the bounds are active)
    np.testing.assert_allclose(d[mesh.F[p.face]], exact[mesh.F[p.face]], atol=1e-6)


def test_edge_point_is_the_same_in_both_faces():
    mesh = PLANE
    E, _ = boundary_edges(mesh)
    interior = next(e for e in mesh.edges.tolist() if not any(set(e) == set(b) for b in E.tolist()))
    a, c = interior
    faces = np.flatnonzero((mesh.F == a).any(axis=1) & (mesh.F == c).any(axis=1))
    assert len(faces) == 2
    pts = []
    for f in faces:
        b = np.zeros(3)
        b[mesh.F[f] == a], b[mesh.F[f] == c] = 0.3, 0.7
        pts.append(cg.SurfacePoint(int(f), b))
    d0 = cg.geodesic_distance(mesh, pts[0], method="qclp")
    d1 = cg.geodesic_distance(mesh, pts[1], method="qclp")
    assert np.abs(d0 - d1).max() <= 1e-7
    ss = resolve_sources(mesh, pts[0])
    assert sorted(ss.point_faces.tolist()) == sorted(faces.tolist())


@pytest.mark.parametrize("mesh", [PLANE, cg.cylinder(16, 6)], ids=lambda m: m.name)
def test_boundary_source(mesh):
    E, _ = boundary_edges(mesh)
    bverts = np.unique(E)
    d = cg.geodesic_distance(mesh, "boundary", method="qclp")
    assert np.all(d[bverts] == 0.0)
    inside = np.setdiff1d(np.arange(mesh.n_vertices), bverts)
    assert np.all(d[inside] > 0)
    dij = cg.geodesic_distance(mesh, list(bverts), method="dijkstra")
    assert np.all(d <= dij + 1e-9)


@pytest.mark.parametrize("mesh", [PLANE, cg.cylinder(16, 6), cg.TriMesh(
    [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [0, 0, 1]], [[0, 1, 2], [1, 3, 2], [0, 1, 4]])],
    ids=["plane", "cylinder", "fin"])
def test_boundary_edges_and_their_faces(mesh):
    # brute force: every face's edges, counted; an edge of one face is a boundary edge, in that face
    count: dict[tuple, list] = {}
    for f, tri in enumerate(mesh.F.tolist()):
        for a, b in ((tri[1], tri[2]), (tri[2], tri[0]), (tri[0], tri[1])):
            count.setdefault((min(a, b), max(a, b)), []).append(f)
    expected = sorted((e, fs[0]) for e, fs in count.items() if len(fs) == 1)
    E, faces = boundary_edges(mesh)
    assert E.dtype == faces.dtype == np.int64
    assert [(tuple(e), f) for e, f in zip(E.tolist(), faces.tolist(), strict=True)] == expected


def test_boundary_on_closed_mesh_raises():
    with pytest.raises(SourceError, match="closed"):
        cg.geodesic_distance(cg.icosphere(1), "boundary", method="qclp")


def _exact_sources_field(mesh, sources):
    return cg.geodesic_distance(mesh, sources, method="exact")


@pytest.mark.parametrize("kind", ["point", "edge", "mixed"])
def test_constraints_do_not_cut_off_the_exact_field(kind):
    """Every source bound and star edge holds for the exact polyhedral distance (pygeodesic, points inserted)."""
    mesh = cg.icosphere(2)
    if kind == "point":
        src = cg.SurfacePoint(40, [0.2, 0.5, 0.3])
    elif kind == "edge":
        src = cg.SurfacePoint(40, [0.0, 0.4, 0.6])
    else:
        src = [cg.SurfacePoint(40, [0.2, 0.5, 0.3]), 100, cg.SurfacePoint(200, [0.1, 0.1, 0.8])]
    exact = _exact_sources_field(mesh, src)
    for method in ("qclp", "lclp"):
        prob = build_problem(MeshOperators(mesh), resolve_sources(mesh, src), method, 0.0)
        x = exact[prob.ineq.vertices]
        lhs = np.einsum("kj,kj->k", prob.ineq.coeffs, x)
        assert np.all(lhs <= prob.ineq.rhs + 1e-9), np.max(lhs - prob.ineq.rhs)
        assert np.all(exact[prob.fixed_mask & ~prob.unreachable] == 0.0)


def test_curve_constraints_hold_for_the_analytic_field_and_curve_accuracy():
    mesh = cg.grid_plane(16, jitter=0.2)
    A, B = np.array([0.25, 0.3, 0.0]), np.array([0.7, 0.65, 0.0])
    curve = cg.SurfaceCurve([A, B])
    ab = B - A
    t = np.clip((mesh.V - A) @ ab / (ab @ ab), 0, 1)
    exact = np.linalg.norm(mesh.V - (A + t[:, None] * ab), axis=1)  # flat and convex: Euclidean distance
    prob = build_problem(MeshOperators(mesh), resolve_sources(mesh, curve), "qclp", 0.0)
    lhs = np.einsum("kj,kj->k", prob.ineq.coeffs, exact[prob.ineq.vertices])
    assert np.all(lhs <= prob.ineq.rhs + 1e-9)
    d = cg.geodesic_distance(mesh, curve, method="qclp")
    far = exact > 0.1
    assert (np.abs(d - exact)[far] / exact[far]).mean() < 0.03
    assert np.all(d[exact < 1e-12] <= 1e-9)


@pytest.mark.parametrize("method", list(FORMULATIONS))
def test_every_formulation_takes_every_kind_of_source(method):
    mesh = PLANE
    kinds = [cg.SurfacePoint(30, [0.2, 0.3, 0.5]), [cg.SurfacePoint(30, [0.2, 0.3, 0.5]), 5],
             cg.SurfaceCurve([[0.2, 0.2, 0.0], [0.6, 0.7, 0.0]]), "boundary"]
    solver = cg.GeodesicSolver(mesh, method)
    for src in kinds:
        res = solver.solve(src)
        assert np.all(np.isfinite(res.distance)) and res.distance.min() >= -1e-6, (method, src)
        assert res.source_set is not None


def test_baselines():
    mesh = PLANE
    p = cg.SurfacePoint(30, [0.2, 0.3, 0.5])
    x = p.position(mesh)
    euclid = np.linalg.norm(mesh.V - x, axis=1)
    d_exact = cg.geodesic_distance(mesh, p, method="exact")
    np.testing.assert_allclose(d_exact, euclid, atol=1e-9)  # flat, convex: the exact field is Euclidean
    d_dij = cg.geodesic_distance(mesh, p, method="dijkstra")
    assert np.all(d_dij >= euclid - 1e-9)
    np.testing.assert_allclose(d_dij[mesh.F[30]], euclid[mesh.F[30]])
    d_fmm = cg.geodesic_distance(mesh, p, method="fmm")
    assert np.abs(d_fmm - euclid).max() < mesh.mean_edge_length
    with pytest.raises(SourceError, match="qclp") as info:
        cg.geodesic_distance(mesh, p, method="heat")
    assert "heat" in str(info.value) and "exact" in str(info.value)


def test_distance_matrix_rows_of_surface_points():
    mesh = PLANE
    pts = [cg.SurfacePoint(30, [0.2, 0.3, 0.5]), 7]
    D = cg.distance_matrix(mesh, pts, method="qclp")
    assert D.shape == (2, mesh.n_vertices)
    np.testing.assert_allclose(D[0], cg.geodesic_distance(mesh, pts[0], method="qclp"), atol=1e-7)
    np.testing.assert_allclose(D[1], cg.geodesic_distance(mesh, 7, method="qclp"), atol=1e-7)


def test_surface_point_many_and_positions():
    mesh = cg.icosphere(2)
    X = mesh.V[:5] * 0.999
    pts = cg.surface_point(mesh, X)
    assert isinstance(pts, list) and len(pts) == 5
    for p, x in zip(pts, X, strict=True):
        assert np.linalg.norm(p.position(mesh) - x) < 0.01
        assert p.bary.min() >= 0 and abs(p.bary.sum() - 1) < 1e-12


@pytest.mark.parametrize("bary, match", [
    ([-0.1, 0.6, 0.5], "must be >= 0"),
    ([np.nan, 0.5, 0.5], "finite"),
    ([0.2, 0.2, 0.2], "sum to 1"),
    ([0.5, 0.5], "3 coordinates"),
])
def test_bad_barycentric_coordinates(bary, match):
    with pytest.raises(SourceError, match=match) as info:
        cg.SurfacePoint(3, bary)
    assert "face=3" in str(info.value)


def test_face_out_of_range_names_the_point():
    mesh = PLANE
    with pytest.raises(SourceError, match=r"source 1 .*face index 9999 is out of range"):
        cg.geodesic_distance(mesh, [0, cg.SurfacePoint(9999, [0.2, 0.3, 0.5])], method="qclp")
    with pytest.raises(SourceError, match="face index 9999"):
        cg.geodesic_distance(mesh, cg.SurfacePoint(9999, [0.2, 0.3, 0.5]), method="qclp")


def test_curve_point_off_the_surface():
    mesh = PLANE
    off = 2e-6 * mesh.bbox_diagonal
    with pytest.raises(SourceError, match=r"point 1 at .* from the surface"):
        cg.geodesic_distance(mesh, cg.SurfaceCurve([[0.2, 0.2, 0.0], [0.5, 0.5, off]]), method="qclp")
    # within the tolerance it is accepted
    cg.geodesic_distance(mesh, cg.SurfaceCurve([[0.2, 0.2, 0.0], [0.5, 0.5, off / 4]]), method="qclp")


def test_other_bad_sources():
    mesh = PLANE
    with pytest.raises(SourceError, match="'boundary' \\(the only named source\\)"):
        cg.geodesic_distance(mesh, "everywhere", method="qclp")
    with pytest.raises(SourceError, match="source 1 must be"):
        cg.geodesic_distance(mesh, [0, "boundary"], method="qclp")
    with pytest.raises(SourceError, match="source 0: source index 10000"):
        cg.geodesic_distance(mesh, [10000, cg.SurfacePoint(0, [1 / 3, 1 / 3, 1 / 3])], method="qclp")
    with pytest.raises(SourceError, match="no points"):
        cg.SurfaceCurve([])
    with pytest.raises(SourceError, match="multires"):
        cg.GeodesicSolver(cg.icosphere(3), "qclp", multires=100).solve(cg.SurfacePoint(0, [0.2, 0.3, 0.5]))


@pytest.mark.parametrize("method", ["qclp", "qcqp-hessian", "lcqp-laplacian"])
def test_both_backends_agree_on_surface_sources(method):
    mesh = PLANE
    srcs = [cg.SurfacePoint(30, [0.2, 0.3, 0.5]), cg.SurfaceCurve([[0.2, 0.2, 0.0], [0.6, 0.7, 0.0]]), "boundary"]
    ipm = cg.GeodesicSolver(mesh, method, solver="ipm")
    cla = cg.GeodesicSolver(mesh, method, solver="clarabel")
    for src in srcs:
        a, b = ipm.solve(src), cla.solve(src)
        assert a.info.status == "optimal" and b.info.status == "optimal"
        assert np.abs(a.distance - b.distance).max() <= 1e-5 * mesh.bbox_diagonal


@pytest.mark.parametrize("mesh", [PLANE, cg.icosphere(2)], ids=lambda m: m.name)
def test_qclp_stays_below_dijkstra_for_surface_sources(mesh):
    """Theorem 2 with point and curve sources: Dijkstra starts from the same vertex bounds (virtual node)."""
    p = cg.SurfacePoint(30, [0.2, 0.3, 0.5])
    curve = cg.SurfaceCurve([cg.SurfacePoint(10, [0.3, 0.3, 0.4]), cg.SurfacePoint(60, [0.5, 0.2, 0.3])])
    for src in (p, [p, 3], curve):
        d = cg.geodesic_distance(mesh, src, method="qclp")
        dij = cg.geodesic_distance(mesh, src, method="dijkstra")
        assert np.all(d <= dij + 1e-7 * mesh.bbox_diagonal)


def test_the_accepted_source_types_come_from_the_cell_kind():
    # the resolver asks mesh.reference (its point type and source kinds), not the dimension
    from dataclasses import replace

    from cvxgeodesic.sources import source_types

    assert source_types(cg.icosphere(1)) == (cg.SurfacePoint, cg.SurfaceCurve)
    assert source_types(cg.tet_box(1)) == (cg.VolumePoint, cg.BoundaryFaces)
    mesh = cg.grid_plane(4)
    curve = cg.SurfaceCurve([[0.2, 0.5, 0.0], [0.8, 0.5, 0.0]])
    assert resolve_sources(mesh, curve).kind == "curve"
    mesh.reference = replace(mesh.reference, source_kinds=("vertex", "point", "boundary"))  # this mesh takes no curve
    assert source_types(mesh) == (cg.SurfacePoint,)
    with pytest.raises(SourceError, match="must be a vertex index, a SurfacePoint, got SurfaceCurve"):
        resolve_sources(mesh, [curve])
    ss = resolve_sources(mesh, cg.SurfacePoint(3, [0.2, 0.3, 0.5]))
    assert ss.reference is mesh.reference and type(ss.points[0]) is cg.SurfacePoint


def test_the_source_rows_do_not_ask_the_dimension():
    # the rows around a point source are the same kind of rows in a solid: the star and cone-free cells' edges; the
    # solid program bounds every edge of a cell without a cone instead, which implies them
    from cvxgeodesic.problems.source_rows import source_constraints

    mesh = cg.tet_box(2)
    ops = MeshOperators(mesh)
    ss = resolve_sources(mesh, [0, cg.volume_point(mesh, [0.5, 0.4, 0.3])])
    sc = source_constraints(ops, ss, min_edge_bound=1e-9)
    assert sc.star_other.size and sc.star_other.size == sc.star_source.size == sc.star_rhs.size
    E = mesh.edges
    pairs = {tuple(sorted(p)) for p in zip(sc.star_other.tolist(), sc.star_source.tolist(), strict=True)}
    assert pairs <= {tuple(e) for e in E.tolist()}
    edge = {tuple(e): i for i, e in enumerate(E.tolist())}
    rhs = np.array([mesh.edge_lengths[edge[p]] for p in
                    (tuple(sorted(p)) for p in zip(sc.star_other.tolist(), sc.star_source.tolist(), strict=True))])
    np.testing.assert_allclose(sc.star_rhs, np.maximum(rhs, 1e-9 * mesh.bbox_diagonal))
    # the star of the source vertex 0: each of its edges bounds its other end
    star = {int(e[1 - list(e).index(0)]) for e in E.tolist() if 0 in e}
    assert star <= {o for o, s in zip(sc.star_other.tolist(), sc.star_source.tolist(), strict=True) if s == 0}
