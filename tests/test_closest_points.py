"""The closest-point search behind surface_point and curve sources (issues 34 and 36).

One libigl AABB tree per mesh object (``cvxgeodesic.mesh.closest``) answers every search; these tests hold it
to a brute-force reference computed here (every face of the mesh, in NumPy), to the pre-index search for curve
sources (``igl.point_mesh_squared_distance`` per call, as the library did before), and to positions far beyond
the mesh, whose squares overflow.
"""

from __future__ import annotations

import gc
import time
import weakref

import numpy as np
import pytest

import cvxgeodesic as cg
from conftest import shared_mesh_path
from cvxgeodesic import sources
from cvxgeodesic.errors import SourceError
from cvxgeodesic.mesh import closest
from cvxgeodesic.mesh.geometry import clipped_barycentric
from cvxgeodesic.mesh.locate import closest_points
from cvxgeodesic.sources import resolve_sources

# Distances of the index and of the brute-force reference are computed by different formulas: each is within
# a few ulps of the diagonal; 1e-12 of it leaves room and still catches a wrong face (any other face is farther
# by the gaps measured below, >= 1e-9 of the diagonal where faces are compared).
DIST_TOL = 1e-12
# A face is compared only where the reference's best face beats every other by this much (no tie).
TIE_GAP = 1e-9


def _closest_on_triangles(p: np.ndarray, A: np.ndarray, B: np.ndarray, C: np.ndarray) -> np.ndarray:
    """(m, 3) closest point of ``p`` (3,) on each triangle (A, B, C) (each (m, 3)): Ericson's regions."""
    ab, ac, ap = B - A, C - A, p - A
    d1, d2 = np.einsum("ij,ij->i", ab, ap), np.einsum("ij,ij->i", ac, ap)
    bp, cp = p - B, p - C
    d3, d4 = np.einsum("ij,ij->i", ab, bp), np.einsum("ij,ij->i", ac, bp)
    d5, d6 = np.einsum("ij,ij->i", ab, cp), np.einsum("ij,ij->i", ac, cp)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        inside = A + ab * (vb / (va + vb + vc))[:, None] + ac * (vc / (va + vb + vc))[:, None]
        on_ab = A + ab * (d1 / (d1 - d3))[:, None]
        on_ac = A + ac * (d2 / (d2 - d6))[:, None]
        on_bc = B + (C - B) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))[:, None]
    conditions = [(d1 <= 0) & (d2 <= 0), (d3 >= 0) & (d4 <= d3), (vc <= 0) & (d1 >= 0) & (d3 <= 0),
                  (d6 >= 0) & (d5 <= d6), (vb <= 0) & (d2 >= 0) & (d6 <= 0),
                  (va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0)]
    choices = [A, B, on_ab, C, on_ac, on_bc]
    out = inside.copy()
    for cond, pt in zip(reversed(conditions), reversed(choices), strict=True):  # the first region wins
        out[cond] = pt[cond]
    return out


def brute_force(mesh, X):
    """Distance to every face of ``mesh`` for each position: (k, m) float ndarray."""
    A, B, C = (mesh.V[mesh.F[:, i]] for i in range(3))
    return np.stack([np.linalg.norm(_closest_on_triangles(x, A, B, C) - x, axis=1) for x in X])


def _queries(mesh, rng, k=150):
    """Positions near the surface (vertices, edge midpoints, face points, pushed off by up to 5 % of the
    diagonal) and a few farther away (up to 100 diagonals: still searched as given, no move in)."""
    V, F, h = mesh.V, mesh.F, mesh.bbox_diagonal
    f = rng.integers(0, mesh.n_faces, k)
    w = rng.dirichlet(np.ones(3), k)
    w[: k // 5] = [1.0, 0.0, 0.0]  # on a vertex
    w[k // 5: 2 * k // 5] = [0.5, 0.5, 0.0]  # on an edge
    X = np.einsum("kj,kjd->kd", w, V[F[f]]) + 0.05 * h * rng.standard_normal((k, 3))
    X[: k // 10] *= 0.0  # the origin: inside or beside the mesh
    far = rng.standard_normal((10, 3))
    return np.vstack([X, V.mean(axis=0) + h * np.geomspace(2, 100, 10)[:, None] * far / np.linalg.norm(far, axis=1,
                                                                                                           keepdims=True)])


def _check_against_brute_force(mesh, X):
    h = mesh.bbox_diagonal
    faces, bary, dist = closest_points(mesh, X)
    D = brute_force(mesh, X)
    best = D.min(axis=1)
    assert np.abs(dist - best).max() <= DIST_TOL * max(h, best.max())
    # the returned point lies on the returned face (barycentric) at the least distance
    C = np.einsum("kj,kjd->kd", bary, mesh.V[mesh.F[faces]])
    assert np.abs(np.linalg.norm(C - X, axis=1) - best).max() <= 1e-9 * max(h, best.max())
    gap = np.sort(D, axis=1)[:, 1] - best
    unique = gap > TIE_GAP * h
    assert unique.sum() > len(X) // 4  # the face check below bites on many queries
    np.testing.assert_array_equal(faces[unique], D[unique].argmin(axis=1))


@pytest.mark.parametrize("mesh", [cg.icosphere(3), cg.grid_plane(10, jitter=0.3), cg.cylinder(12, 5)],
                         ids=lambda m: m.name)
def test_closest_points_match_a_brute_force_search(mesh):
    _check_against_brute_force(mesh, _queries(mesh, np.random.default_rng(3)))


@pytest.mark.shared
@pytest.mark.parametrize("name", ["spot.obj", "fandisk.obj"])
def test_closest_points_match_a_brute_force_search_on_shared_meshes(name):
    mesh = cg.load_mesh(shared_mesh_path(name))
    _check_against_brute_force(mesh, _queries(mesh, np.random.default_rng(4), k=60))


def _search_before_the_index(mesh, X):
    """closest_points as it was before the index: libigl builds a tree for every call."""
    import igl

    X = np.ascontiguousarray(np.asarray(X, dtype=np.float64).reshape(-1, 3))
    V = np.ascontiguousarray(mesh.V, dtype=np.float64)
    F = np.ascontiguousarray(mesh.F, dtype=np.int64)
    sqd, faces, C = igl.point_mesh_squared_distance(X, V, F)
    faces = np.asarray(faces, dtype=np.int64)
    T = V[F[faces]]
    bary = clipped_barycentric(np.asarray(C), T[:, 0], T[:, 1], T[:, 2])
    return faces, bary, np.sqrt(np.maximum(np.asarray(sqd), 0.0))


def _curves(mesh, rng, count=3, k=25):
    """Polylines through the surface: chords between random vertices projected, given as positions and as
    SurfacePoints (a curve along a surface, its segments at a few edge lengths)."""
    out = []
    for _ in range(count):
        a, b = rng.integers(0, mesh.n_vertices, 2)
        t = np.linspace(0.0, 1.0, k)[:, None]
        pts = cg.surface_point(mesh, (1 - t) * mesh.V[a] + t * mesh.V[b])
        out.append(cg.SurfaceCurve(pts))
        out.append(cg.SurfaceCurve(np.array([p.position(mesh) for p in pts])))
    return out


def _same_source_sets(a, b):
    for name in ("vertices", "point_faces", "point_bary", "segment_faces", "segment_bary"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)


def _curve_before_the_index(mesh, curve):
    """resolve_sources(mesh, curve) as the library did it before the index: a search per point and per segment,
    a SurfacePoint per sample, the pieces pair by pair."""
    step = sources.CURVE_STEP * mesh.mean_edge_length
    pts = []
    for p in curve.points:
        if not isinstance(p, cg.SurfacePoint):
            f, b, _ = _search_before_the_index(mesh, p[None, :])
            p = cg.SurfacePoint(int(f[0]), b[0])
        pts.append(p)
    samples_f, samples_b = [pts[0].face], [pts[0].bary]
    for a, b in zip(pts[:-1], pts[1:], strict=True):
        xa, xb = a.position(mesh), b.position(mesh)
        k = max(1, int(np.ceil(np.linalg.norm(xb - xa) / step)))
        if k > 1:
            t = np.linspace(0.0, 1.0, k + 1)[1:-1, None]
            faces, bary, _ = _search_before_the_index(mesh, (1 - t) * xa + t * xb)
            samples_f.extend(int(f) for f in faces)
            samples_b.extend(bary)
        samples_f.append(b.face)
        samples_b.append(b.bary)
    builder = sources._Builder(mesh)
    for f, bc in zip(samples_f, samples_b, strict=True):
        p = cg.SurfacePoint(f, bc)
        builder.add_bary(p.face, p.bary)
    V, F, h = mesh.V, mesh.F, mesh.bbox_diagonal
    for i in range(len(samples_f) - 1):
        fa, fb = samples_f[i], samples_f[i + 1]
        if fa == fb:
            builder.add_piece(fa, samples_b[i], samples_b[i + 1])
            continue
        xa, xb = samples_b[i] @ V[F[fa]], samples_b[i + 1] @ V[F[fb]]
        for g in (fa, fb):
            T = V[F[g]][None]
            ba = clipped_barycentric(xa[None], T[:, 0], T[:, 1], T[:, 2])[0]
            bb = clipped_barycentric(xb[None], T[:, 0], T[:, 1], T[:, 2])[0]
            if np.linalg.norm(ba @ T[0] - xa) <= 1e-12 * h and np.linalg.norm(bb @ T[0] - xb) <= 1e-12 * h:
                builder.add_piece(g, ba, bb)
                break
    return builder.build("curve", "")


@pytest.mark.parametrize("mesh", [cg.icosphere(3), cg.grid_plane(12, jitter=0.25)], ids=lambda m: m.name)
def test_curve_sources_are_unchanged_by_the_index(mesh):
    """The same searches as before the index, batched: the same source sets, bit for bit."""
    rng = np.random.default_rng(5)
    for curve in _curves(mesh, rng):
        new = resolve_sources(mesh, curve)
        assert new.segment_faces.size > 10 and new.point_faces.size > 10
        _same_source_sets(new, _curve_before_the_index(mesh, curve))


@pytest.mark.shared
def test_curve_sources_are_unchanged_by_the_index_on_bunny():
    mesh = cg.load_mesh(shared_mesh_path("bunny.obj"))
    curve = _curves(mesh, np.random.default_rng(6), count=1, k=12)[1]  # positions: their search too
    _same_source_sets(resolve_sources(mesh, curve), _curve_before_the_index(mesh, curve))


def test_the_index_is_built_once_per_mesh(monkeypatch):
    builds = []

    class Counting(closest.ClosestPointIndex):
        def __init__(self, mesh):
            builds.append(mesh)
            super().__init__(mesh)

    monkeypatch.setattr(closest, "ClosestPointIndex", Counting)
    mesh = cg.icosphere(3)
    curve = _curves(mesh, np.random.default_rng(7), count=1)[1]  # 25 positions, 24 segments
    solver = cg.GeodesicSolver(mesh, method="qclp")
    for _ in range(2):
        solver.solve(curve)
    cg.surface_point(mesh, [0.1, 0.2, 2.0])
    resolve_sources(mesh, [curve, curve])
    assert builds == [mesh]
    # another mesh object gets its own; the index does not keep its mesh alive
    other = cg.icosphere(3)
    cg.surface_point(other, [0.0, 0.0, 2.0])
    assert len(builds) == 2
    ref = weakref.ref(other)
    del other, builds[1]
    gc.collect()
    assert ref() is None


def test_source_time_is_counted_in_the_solve(monkeypatch):
    """The sources' resolution is part of ``solve_time`` and reported as ``extra["source_time"]`` (a sleep in
    it gives a lower bound that does not depend on the machine's speed)."""
    from cvxgeodesic import api

    def slow(mesh, s):
        time.sleep(0.2)
        return resolve_sources(mesh, s)

    monkeypatch.setattr(api, "resolve_sources", slow)
    res = cg.GeodesicSolver(cg.icosphere(2), method="qclp").solve(cg.SurfaceCurve([[1, 0, 0], [0, 1, 0]]))
    assert res.info.extra["source_time"] >= 0.2
    assert res.info.solve_time >= res.info.extra["source_time"]


# ---------------------------------------------------------------------------------------------------------------
# positions far away (issue 34)
# ---------------------------------------------------------------------------------------------------------------
def _rotated_sphere():
    """icosphere(3) turned by a generic rotation: along each axis its farthest vertex is unique."""
    q, _ = np.linalg.qr(np.random.default_rng(8).standard_normal((3, 3)))
    mesh = cg.icosphere(3)
    return cg.TriMesh(mesh.V @ q.T + [0.3, -0.2, 0.1], mesh.F)


DIRECTIONS = [np.eye(3)[i] * s for i in range(3) for s in (1, -1)] + [np.array([0.3, -0.5, 0.8])]


@pytest.mark.parametrize("scale", [1e300, 1e154, 1e12])
@pytest.mark.parametrize("u", DIRECTIONS, ids=lambda u: np.array2string(u, separator=","))
def test_a_far_position_finds_the_farthest_vertex_in_its_direction(u, scale):
    """Brute force: seen from far along ``u``, the closest point of the mesh is its vertex farthest along ``u``
    (unique here by far more than the search's bound ``diag / 8e7``, ``mesh.closest.FAR_QUERY``)."""
    mesh = _rotated_sphere()
    h = mesh.bbox_diagonal
    support = mesh.V @ u
    v = int(np.argmax(support))
    # one farthest vertex, ahead of the next by far more than the bound (2.8e-5 of the diagonal along the
    # oblique direction, 1e-3 along the axes)
    assert np.sort(support)[-2] < support[v] - 1e-5 * h
    p = cg.surface_point(mesh, scale * u)
    assert v in mesh.F[p.face]
    # the search at FAR_QUERY diagonals rounds at about 2e-16 * 1e7 of the diagonal
    assert np.linalg.norm(p.position(mesh) - mesh.V[v]) <= 1e-7 * h


@pytest.mark.parametrize("exponent", [120, -120])
def test_meshes_with_huge_or_tiny_coordinates(exponent):
    """Coordinates near TriMesh's bound (validation.MAX_COORDINATE, 1e40), or a diagonal near its inverse, are
    searched in the mesh's unit frame: the closest points are those of the unit-sized mesh, scaled."""
    small = _rotated_sphere()
    k = 2.0**exponent
    big = cg.TriMesh(small.V * k, small.F)
    X = np.random.default_rng(9).standard_normal((40, 3))
    f0, b0, d0 = closest_points(small, X)
    f1, b1, d1 = closest_points(big, X * k)
    assert closest.closest_point_index(big).unit_frame and not closest.closest_point_index(small).unit_frame
    # the same points up to the rounding of the frame's shift (a few ulps of the diagonal); faces may differ where
    # the point is a vertex or on an edge (a tie)
    P0 = np.einsum("kj,kjd->kd", b0, small.V[small.F[f0]])
    P1 = np.einsum("kj,kjd->kd", b1, big.V[big.F[f1]]) / k
    np.testing.assert_allclose(P1, P0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(d1 / k, d0, rtol=1e-12, atol=1e-12)
    assert (f0 == f1).mean() > 0.9
    v = int(np.argmax(big.V[:, 0]))
    assert v in big.F[cg.surface_point(big, [1e300, 0, 0]).face]


def test_far_curve_point_names_its_distance():
    mesh = cg.icosphere(2)
    with pytest.raises(SourceError, match=r"point 1 at \[1e\+300, 0.0, 0.0\] is 1e\+300 from the surface"):
        resolve_sources(mesh, cg.SurfaceCurve([[1.0, 0, 0], [1e300, 0, 0]]))


@pytest.mark.parametrize("bad", [[np.nan, 0, 0], [0, np.inf, 0], [0, 0, -np.inf]])
def test_nan_and_inf_positions_are_refused(bad):
    with pytest.raises(SourceError, match=r"xyz must be a \(3,\) or \(k, 3\) array of finite positions: xyz = "):
        cg.surface_point(cg.icosphere(1), bad)
    with pytest.raises(SourceError, match=r"xyz\[1\] = "):
        cg.surface_point(cg.icosphere(1), [[0, 0, 0], bad])


def test_triangle_point_is_the_closest_point_of_the_closed_triangle():
    """triangle_point against a dense sampling of each triangle (random, plus a needle and a degenerate one); the
    sampling's step bounds how much farther its best sample can be than the exact closest point."""
    rng = np.random.default_rng(11)
    T = rng.normal(size=(40, 3, 3))
    T[0, 2] = T[0, 0] + 1e-9 * (T[0, 1] - T[0, 0])  # a needle
    T[1, 2] = 0.5 * (T[1, 0] + T[1, 1])  # a degenerate triangle: the segment
    P = rng.normal(size=(40, 3)) * 2
    P[2] = T[2].mean(axis=0) + 0.3 * np.cross(T[2, 1] - T[2, 0], T[2, 2] - T[2, 0])  # above the inside
    Y = closest.triangle_point(P, T[:, 0], T[:, 1], T[:, 2])
    u, v = np.meshgrid(np.linspace(0, 1, 201), np.linspace(0, 1, 201))
    keep = u + v <= 1
    W = np.stack([1 - u[keep] - v[keep], u[keep], v[keep]], axis=1)  # (s, 3) barycentric samples
    for k in range(len(P)):
        S = W @ T[k]
        sampled = np.linalg.norm(S - P[k], axis=1).min()
        exact = np.linalg.norm(Y[k] - P[k])
        # the closest point is no farther than the best sample, which is within a sampling step of it
        step = np.linalg.norm(T[k] - T[k].mean(axis=0), axis=1).max() * 2 / 200
        assert exact <= sampled + 1e-12 and sampled <= exact + step
    np.testing.assert_allclose(closest.point_triangle_distance(P, T[:, 0], T[:, 1], T[:, 2]),
                               np.linalg.norm(Y - P, axis=1), rtol=0, atol=0)
    # a segment's closest point: the foot inside it, else the nearer end
    A, B = np.zeros((3, 3)), np.array([[1.0, 0, 0]] * 3)
    Q = np.array([[0.25, 1.0, 0.0], [-2.0, 0.5, 0.0], [3.0, 0.0, 1.0]])
    np.testing.assert_array_equal(closest.segment_point(Q, A, B), [[0.25, 0, 0], [0, 0, 0], [1, 0, 0]])
