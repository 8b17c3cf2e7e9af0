"""distance_at and geodesic_path (issue 15), on surfaces and in volumes (issue 35)."""

from __future__ import annotations

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic.errors import ParameterError, SolverError, SourceError


def _on_faces(mesh, P, faces, bary):
    assert np.all(bary >= 0) and np.allclose(bary.sum(axis=1), 1.0)
    np.testing.assert_allclose(np.einsum("kj,kji->ki", bary, mesh.V[mesh.F[faces]]), P, atol=1e-12)


def _length(P):
    return float(np.linalg.norm(np.diff(P, axis=0), axis=1).sum())


@pytest.fixture(scope="module")
def sphere_field():
    mesh = cg.icosphere(4)
    return mesh, cg.GeodesicSolver(mesh, "qclp").solve(0)


@pytest.mark.parametrize("target", [100, 1000, 2000, 2500])
def test_sphere_path_length_is_great_circle(sphere_field, target):
    """Measured: -0.06 % (straightened: the polyhedral geodesic, inscribed), +0.18 % .. +0.48 % (raw descent)."""
    mesh, res = sphere_field
    gc = float(np.arccos(np.clip(mesh.V[0] @ mesh.V[target], -1, 1)))
    for straighten in (True, False):
        P, faces, bary = cg.geodesic_path(mesh, res, target, straighten=straighten, return_surface_points=True)
        assert abs(_length(P) - gc) <= 0.03 * gc
        np.testing.assert_array_equal(P[-1], mesh.V[0])
        _on_faces(mesh, P, faces, bary)


@pytest.mark.parametrize("method", ["exact", "qclp", "qcqp-hessian"])
@pytest.mark.parametrize("target", [400, cg.SurfacePoint(700, [0.3, 0.3, 0.4])], ids=["vertex", "point"])
def test_path_on_plane_is_straight(method, target):
    """Measured: 2e-16 from the chord for every method and target (the raw descent: 6e-3 .. 7e-2)."""
    mesh = cg.grid_plane(20, jitter=0.25)
    s = int(np.argmin(np.linalg.norm(mesh.V - [0.2, 0.3, 0.0], axis=1)))
    res = cg.GeodesicSolver(mesh, method).solve(s)
    P, faces, bary = cg.geodesic_path(mesh, res, target, return_surface_points=True)
    a, b = P[0], P[-1]
    u = (b - a) / np.linalg.norm(b - a)
    dev = np.linalg.norm((P - a) - ((P - a) @ u)[:, None] * u, axis=1)
    assert dev.max() <= 1e-6
    start = mesh.V[target] if isinstance(target, int) else target.position(mesh)
    np.testing.assert_allclose(P[0], start, atol=1e-12)
    np.testing.assert_array_equal(P[-1], mesh.V[s])
    _on_faces(mesh, P, faces, bary)


def test_straightened_path_is_never_shorter_than_the_exact_distance(sphere_field):
    mesh, res = sphere_field
    exact = cg.geodesic_distance(mesh, 0, method="exact")
    for target in (100, 1000, 2000, 2500):
        L = _length(cg.geodesic_path(mesh, res, target))
        assert exact[target] - 1e-9 <= L <= exact[target] * 1.001


def test_descent_path_on_plane_in_the_source_face_is_straight():
    mesh = cg.grid_plane(20, jitter=0.25)
    src = cg.SurfacePoint(300, [0.2, 0.3, 0.5])
    res = cg.GeodesicSolver(mesh, "qclp").solve(src)
    P = cg.geodesic_path(mesh, res, cg.SurfacePoint(300, [0.6, 0.2, 0.2]))
    assert len(P) == 2
    np.testing.assert_allclose(P[-1], src.position(mesh), atol=1e-12)


@pytest.mark.parametrize("source_kind", ["vertex", "point", "curve", "boundary"])
def test_paths_end_on_their_source_and_stay_on_the_surface(source_kind):
    mesh = cg.grid_plane(16, jitter=0.2)
    src = {"vertex": 20, "point": cg.SurfacePoint(100, [0.2, 0.3, 0.5]),
           "curve": cg.SurfaceCurve([[0.2, 0.2, 0.0], [0.45, 0.6, 0.0]]), "boundary": "boundary"}[source_kind]
    res = cg.GeodesicSolver(mesh, "qcqp-hessian").solve(src)
    for target in (250, cg.SurfacePoint(400, [0.1, 0.6, 0.3])):
        P, faces, bary = cg.geodesic_path(mesh, res, target, return_surface_points=True)
        _on_faces(mesh, P, faces, bary)
        end = P[-1]
        if source_kind == "vertex":
            np.testing.assert_allclose(end, mesh.V[20])
        elif source_kind == "point":
            np.testing.assert_allclose(end, src.position(mesh), atol=1e-12)
        elif source_kind == "curve":
            A, B = np.array([0.2, 0.2, 0.0]), np.array([0.45, 0.6, 0.0])
            t = np.clip((end - A) @ (B - A) / ((B - A) @ (B - A)), 0, 1)
            assert np.linalg.norm(end - (A + t * (B - A))) < 1e-9
        else:
            assert min(end[0], end[1], 1 - end[0], 1 - end[1]) < 1e-12
        # the raw descent never climbs (the last point is the source itself, where the interpolant is not 0)
        P, faces, bary = cg.geodesic_path(mesh, res, target, return_surface_points=True, straighten=False)
        vals = cg.distance_at(mesh, res, [cg.SurfacePoint(int(f), b) for f, b in zip(faces, bary, strict=True)])
        assert np.all(np.diff(vals[:-1]) <= 1e-9)


def test_distance_at():
    mesh = cg.grid_plane(4)
    d = np.arange(mesh.n_vertices, dtype=float)
    f = 3
    b = np.array([0.2, 0.3, 0.5])
    assert cg.distance_at(mesh, d, cg.SurfacePoint(f, b)) == pytest.approx(b @ d[mesh.F[f]])
    vals = cg.distance_at(mesh, d, [cg.SurfacePoint(f, b), cg.SurfacePoint(0, [1.0, 0.0, 0.0])])
    np.testing.assert_allclose(vals, [b @ d[mesh.F[f]], d[mesh.F[0, 0]]])
    x = cg.SurfacePoint(f, b).position(mesh)
    assert cg.distance_at(mesh, d, x) == pytest.approx(b @ d[mesh.F[f]])
    with pytest.raises(ParameterError, match=rf"distance must have shape \({mesh.n_vertices},\)"):
        cg.distance_at(mesh, d[:-1], cg.SurfacePoint(f, b))
    with pytest.raises(SourceError, match="out of range"):
        cg.distance_at(mesh, d, [cg.SurfacePoint(999, b)])


def test_path_errors():
    mesh = cg.grid_plane(8)
    res = cg.GeodesicSolver(mesh, "qclp").solve(0)
    with pytest.raises(SourceError, match="out of range"):
        cg.geodesic_path(mesh, res, 10_000)
    with pytest.raises(SourceError, match="face index"):
        cg.geodesic_path(mesh, res, cg.SurfacePoint(10_000, [0.2, 0.3, 0.5]))
    with pytest.raises(SolverError, match="max_steps=2"):
        cg.geodesic_path(mesh, res.distance, 80, max_steps=2)
    d = res.distance.copy()
    d[40] = -1.0  # a local minimum that is no source (vertex 40 is not a field minimum otherwise)
    with pytest.raises(SolverError, match="local minimum|max_steps"):
        cg.geodesic_path(mesh, d, 41, sources=0)


def test_exact_path_between_surface_points():
    """method='exact' with point sources: pygeodesic's path on the mesh with the points inserted."""
    mesh = cg.grid_plane(20, jitter=0.25)
    src, tgt = cg.SurfacePoint(300, [0.2, 0.3, 0.5]), cg.SurfacePoint(700, [0.3, 0.3, 0.4])
    res = cg.GeodesicSolver(mesh, "exact").solve(src)
    P, faces, bary = cg.geodesic_path(mesh, res, tgt, return_surface_points=True)
    x, y = tgt.position(mesh), src.position(mesh)
    np.testing.assert_allclose(P[0], x, atol=1e-15)
    np.testing.assert_allclose(P[-1], y, atol=1e-15)
    assert _length(P) == pytest.approx(np.linalg.norm(x - y), abs=1e-12)
    _on_faces(mesh, P, faces, bary)


def test_plain_array_from_geodesic_distance_remembers_its_sources():
    mesh = cg.grid_plane(12, jitter=0.2)
    src = cg.SurfacePoint(100, [0.2, 0.3, 0.5])
    d = cg.geodesic_distance(mesh, src, method="qclp")
    P = cg.geodesic_path(mesh, d, 150)
    np.testing.assert_allclose(P[-1], src.position(mesh), atol=1e-12)
    # an array of unknown origin: the sources are the field's minimum vertices (here the lowest corner of the face)
    P = cg.geodesic_path(mesh, d.copy(), 150)
    assert int(np.argmin(np.linalg.norm(mesh.V - P[-1], axis=1))) in mesh.F[100]
    np.testing.assert_allclose(cg.geodesic_path(mesh, d.copy(), 150, sources=src)[-1], src.position(mesh), atol=1e-12)


# -- the same walk on surfaces and in volumes (issue 35): every guard and behaviour in both dimensions --------------
def _flat(dim):
    """A jittered unit square (dim 2) or cube (dim 3) and its point type."""
    mesh = cg.grid_plane(8, jitter=0.2) if dim == 2 else cg.tet_box(3, jitter=0.2, seed=1)
    return mesh, (cg.SurfacePoint if dim == 2 else cg.VolumePoint)


def _cells(mesh):
    return mesh.F if isinstance(mesh, cg.TriMesh) else mesh.T


def _point(mesh, cell, bary):
    return (cg.SurfacePoint if isinstance(mesh, cg.TriMesh) else cg.VolumePoint)(cell, bary)


def _inside(mesh, P, cells, bary):
    """Every path point is the barycentric combination of its cell's corners (to rounding)."""
    assert cells.shape == (len(P),) and bary.shape == (len(P), _cells(mesh).shape[1])
    assert np.all(bary >= 0) and np.allclose(bary.sum(axis=1), 1.0)
    np.testing.assert_allclose(np.einsum("kj,kji->ki", bary, mesh.V[_cells(mesh)[cells]]), P, atol=1e-12)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_target_on_its_source_is_a_one_point_path(dim):
    """Was two equal rows on surfaces (the straightening repeated the only node)."""
    mesh, _ = _flat(dim)
    d = cg.geodesic_distance(mesh, 0, method="dijkstra")
    np.testing.assert_array_equal(cg.geodesic_path(mesh, d, 0), mesh.V[:1])
    src = _point(mesh, 5, np.full(dim + 1, 1 / (dim + 1)))
    res = cg.GeodesicSolver(mesh, "qclp").solve(src)
    for straighten in (True, False):
        P = cg.geodesic_path(mesh, res, src, straighten=straighten)
        np.testing.assert_allclose(P, src.position(mesh)[None], atol=1e-12)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_target_that_no_source_reaches_is_refused(dim):
    mesh, _ = _flat(dim)
    d = np.linalg.norm(mesh.V - mesh.V[0], axis=1)
    d[-1] = np.inf  # as in another component
    with pytest.raises(ParameterError, match=rf"infinite at the target \(vertex {mesh.n_vertices - 1}\): no source is "
                                             "reachable"):
        cg.geodesic_path(mesh, d, mesh.n_vertices - 1, sources=0)
    corner = int(np.flatnonzero((_cells(mesh) == mesh.n_vertices - 1).any(axis=1))[0])
    bary = np.where(_cells(mesh)[corner] == mesh.n_vertices - 1, 0.5, 0.5 / dim)
    with pytest.raises(ParameterError, match=rf"infinite at the target \(the point in cell {corner}\)"):
        cg.geodesic_path(mesh, d, _point(mesh, corner, bary), sources=0)


@pytest.mark.parametrize("dim", [2, 3])
def test_max_steps_and_false_minima(dim):
    mesh, _ = _flat(dim)
    d = np.linalg.norm(mesh.V - mesh.V[0], axis=1)
    far = int(np.argmax(d))
    with pytest.raises(SolverError, match="no source reached within max_steps=2 steps"):
        cg.geodesic_path(mesh, d, far, sources=0, max_steps=2)
    with pytest.raises(ParameterError, match="max_steps must be a positive integer, got 0"):
        cg.geodesic_path(mesh, d, far, sources=0, max_steps=0)
    inner = int(np.argmin(np.linalg.norm(mesh.V - 0.5, axis=1)))
    d[inner] = 0.0  # a pit that is no source, and no source cell next to it
    with pytest.raises(SolverError, match=f"local minimum at vertex {inner} .* which is no source"):
        cg.geodesic_path(mesh, d, inner, sources=0)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_field_below_its_point_source_ends_on_the_point(dim):
    """A smoothed field can dip below the straight distance next to its source: a vertex with no way down, in a
    cell of the source point, ends on the point (was a 'local minimum' error in volumes)."""
    mesh, _ = _flat(dim)
    src = _point(mesh, 5, np.full(dim + 1, 1 / (dim + 1)))
    x = src.position(mesh)
    d = np.linalg.norm(mesh.V - x, axis=1)
    v = int(_cells(mesh)[5, 0])
    d[v] = 0.0
    P = cg.geodesic_path(mesh, d, v, sources=src, straighten=False)
    np.testing.assert_allclose(P, [mesh.V[v], x], atol=1e-12)


@pytest.mark.parametrize("dim", [2, 3])
def test_an_array_from_geodesic_distance_ends_on_its_point_source(dim):
    """The array remembers its sources in volumes too (the path ended at a corner of the point's cell)."""
    mesh, _ = _flat(dim)
    src = _point(mesh, 5, [0.2, 0.3, 0.5] if dim == 2 else [0.1, 0.2, 0.3, 0.4])
    d = cg.geodesic_distance(mesh, src, method="qclp")
    far = int(np.argmax(d))
    np.testing.assert_allclose(cg.geodesic_path(mesh, d, far)[-1], src.position(mesh), atol=1e-12)


@pytest.mark.parametrize("dim", [2, 3])
def test_targets_positions_and_points_of_cells(dim):
    """A position is its closest surface point (the point inside the volume); on both, the path's cells and
    barycentric coordinates (return_surface_points) hold its points."""
    mesh, kind = _flat(dim)
    res = cg.GeodesicSolver(mesh, "qclp").solve(0)
    xyz = [0.7, 0.6, 0.0] if dim == 2 else [0.7, 0.6, 0.5]
    p = cg.surface_point(mesh, xyz) if dim == 2 else cg.volume_point(mesh, xyz)
    np.testing.assert_array_equal(cg.geodesic_path(mesh, res, xyz), cg.geodesic_path(mesh, res, p))
    for target in (xyz, p, mesh.n_vertices - 1):
        P, cells, bary = cg.geodesic_path(mesh, res, target, return_surface_points=True, straighten=False)
        _inside(mesh, P, cells, bary)
        np.testing.assert_array_equal(P[-1], mesh.V[0])
    for bad in ("corner", [0.5, np.nan, 0.5], True):
        with pytest.raises(SourceError, match=f"target must be a vertex index, a {kind.__name__} or a finite "):
            cg.geodesic_path(mesh, res, bad)
    with pytest.raises(SourceError, match="index 9999 is out of range"):
        cg.geodesic_path(mesh, res, kind(9999, np.full(dim + 1, 1 / (dim + 1))))


@pytest.mark.parametrize("dim", [2, 3])
def test_a_point_source_on_a_shared_facet_is_reached_from_both_sides(dim):
    """A point on an edge (a face between two tetrahedra) is the source of both cells: the path from the other
    cell goes straight to it (in volumes it went on through the shared face and around: 4 points)."""
    mesh, _ = _flat(dim)
    C = _cells(mesh)
    c = 5
    bary = np.r_[0.0, np.full(dim, 1 / dim)]  # on the facet opposite corner 0
    h = next(h for h in range(len(C)) if h != c and np.isin(C[c, 1:], C[h]).all())
    res = cg.GeodesicSolver(mesh, "qclp").solve(_point(mesh, c, bary))
    target = _point(mesh, h, np.full(dim + 1, 1 / (dim + 1)))
    P = cg.geodesic_path(mesh, res, target, straighten=False)
    assert len(P) == 2
    np.testing.assert_allclose(P[-1], _point(mesh, c, bary).position(mesh), atol=1e-12)


def test_a_volume_path_takes_no_cost_or_metric():
    """Was silently ignored."""
    mesh = cg.tet_box(2)
    d = cg.geodesic_distance(mesh, 0, method="dijkstra")
    for kw in ({"cost": 2.0}, {"metric": np.eye(3)}):
        with pytest.raises(ParameterError, match="cost and metric apply to paths on triangle meshes"):
            cg.geodesic_path(mesh, d, 5, **kw)


@pytest.mark.parametrize("dim", [2, 3])
def test_distance_at_in_both_dimensions(dim):
    mesh, kind = _flat(dim)
    C = _cells(mesh)
    d = np.linalg.norm(mesh.V - mesh.V[0], axis=1)
    b = np.full(dim + 1, 1 / (dim + 1))
    assert cg.distance_at(mesh, d, kind(3, b)) == pytest.approx(b @ d[C[3]], rel=1e-15)
    assert cg.distance_at(mesh, d, []).shape == (0,)  # was an error in volumes
    d[C[3, 0]] = np.inf  # an unreachable corner counts only where its weight is not 0
    b0 = np.r_[0.0, np.full(dim, 1 / dim)]
    np.testing.assert_allclose(cg.distance_at(mesh, d, [kind(3, b0), kind(3, b)]), [b0 @ np.nan_to_num(d[C[3]]),
                                                                                     np.inf])
    with pytest.raises(SourceError, match=f"points must be {kind.__name__}s or \\(k, 3\\) positions"):
        cg.distance_at(mesh, d, [object()])
    with pytest.raises(SourceError, match="point 1 .* index 9999 is out of range"):
        cg.distance_at(mesh, d, [kind(3, b), kind(9999, b)])


@pytest.mark.parametrize("dim", [2, 3])
def test_the_raw_descent_never_climbs(dim):
    mesh, kind = _flat(dim)
    src = _point(mesh, 5, [0.2, 0.3, 0.5] if dim == 2 else [0.1, 0.2, 0.3, 0.4])
    res = cg.GeodesicSolver(mesh, "qclp").solve(src)
    for target in (mesh.n_vertices - 1, int(np.argmax(res.distance))):
        P, cells, bary = cg.geodesic_path(mesh, res, target, return_surface_points=True, straighten=False)
        _inside(mesh, P, cells, bary)
        vals = cg.distance_at(mesh, res, [kind(int(c), b) for c, b in zip(cells, bary, strict=True)])
        # the last point is the source itself, where the interpolant is not 0; 1e-9: rounding of the crossings
        assert np.all(np.diff(vals[:-1]) <= 1e-9)
        np.testing.assert_allclose(P[-1], src.position(mesh), atol=1e-12)

