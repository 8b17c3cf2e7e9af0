"""Point clouds at ``resolution=``: order 2 on a quadric copy of the surface through the points, answered at every
point."""

import numpy as np
import pytest

import cvxgeodesic as cg
from conftest import plane_points, sphere_points
from cvxgeodesic.mesh.pointcloud import PointCloud


def test_a_plane_cloud_is_exact_at_every_point():
    P = plane_points(30, seed=2)  # 900 points (seed 1: the copy has a sliver at a corner, exact to 2e-4 only there)
    cloud = PointCloud(P)
    res = cg.GeodesicSolver(cloud, "qclp", resolution=300).solve(12)
    ad = res.info.extra["adapted"]
    assert ad["fallback"] is None and ad["faces"] < cloud.surface()[0].n_faces and ad["order"] == 2
    assert any("copy" in n for n in res.info.notes)
    np.testing.assert_allclose(res.distance, np.linalg.norm(cloud.P - cloud.P[12], axis=1), atol=1e-6)
    p = cg.SurfacePoint(40, [0.2, 0.3, 0.5])  # a point of the cloud's triangles: at its position on the copy
    assert abs(cg.distance_at(cloud, res, p) - np.linalg.norm(p.position(cloud.mesh) - cloud.P[12])) < 1e-6


@pytest.mark.parametrize("resolution", [200, 300])
def test_planar_clouds_copies_stay_planar_and_exact(resolution):
    # the quadric decimation on a plane depends on where the origin lies: centring the coordinates (tried against
    # survey coordinates) left slivers in these copies, 0.0095-0.18 max error
    cloud = PointCloud(plane_points(20))
    res = cg.GeodesicSolver(cloud, "qclp", resolution=resolution).solve(50)
    assert res.info.extra["adapted"]["fallback"] is None
    np.testing.assert_allclose(res.distance, np.linalg.norm(cloud.P - cloud.P[50], axis=1), atol=1e-6)


def test_a_regular_grid_cloud_s_default_is_order_2_on_a_copy_and_exact():
    # every square's corners are cocircular: fans that chose its two diagonals differently overlapped and left the
    # consensus in pieces (30 x 30: 28), so the default fell back to order 1 (0.02-0.03 max error); the fans now
    # choose on points moved alike, and the three collinear points of a border row make no triangle
    g = np.linspace(0.0, 1.0, 40)
    x, y = np.meshgrid(g, g)
    P = np.c_[x.ravel(), y.ravel(), np.zeros(x.size)]
    cloud = PointCloud(P)
    np.testing.assert_array_equal(cloud.P, P)  # the move is for the fans' choices only
    assert cloud.mesh.degenerate_faces(1e-6).size == 0
    surface, why = cloud.surface()
    assert why is None and surface.n_faces == 2 * 39**2
    res = cg.GeodesicSolver(cloud).solve(0)
    ad = res.info.extra["adapted"]
    assert ad["fallback"] is None and ad["order"] == 2 and ad["faces"] < surface.n_faces
    np.testing.assert_allclose(res.distance, np.linalg.norm(P - P[0], axis=1), atol=1e-6)


def test_a_sphere_cloud_is_close_to_the_great_circle_distance():
    cloud = PointCloud(sphere_points(3000))
    res = cg.GeodesicSolver(cloud, "qclp", resolution=0.25).solve(0)
    great_circle = np.arccos(np.clip(cloud.P @ cloud.P[0], -1.0, 1.0))
    assert res.info.extra["adapted"]["fallback"] is None
    assert np.isfinite(res.distance).all()
    # the copy's chords shorten it: about the error of order 2 on a sphere mesh of the copy's size (measured 0.4 %)
    assert np.abs(res.distance - great_circle)[great_circle > 0.3].mean() < 0.01 * np.pi
    path = cg.geodesic_path(cloud, res, 1500)
    assert np.linalg.norm(np.diff(path, axis=0), axis=1).sum() == pytest.approx(res.distance[1500], rel=0.05)


def test_the_field_drops_to_its_envelope_over_the_clouds_own_edges():
    """The surface through the points leaves out the triangles the fans disagree on; the copy's field goes around those
    holes, which the cloud's own triangles close: it is lowered to its envelope along their edges (1,500 points of a
    sphere: max error 0.063 pi at a hole's rim without it, 0.011 pi with it)."""
    cloud = PointCloud(sphere_points(1500))
    great_circle = np.arccos(np.clip(cloud.P @ cloud.P[0], -1.0, 1.0))
    res = cg.GeodesicSolver(cloud, "qclp", resolution="auto").solve(0)
    assert res.info.extra["adapted"]["cloud_envelope"]["points"] > 0
    assert any("lowered to the least distance over the cloud's triangle edges" in n for n in res.info.notes)
    assert np.abs(res.distance - great_circle).max() < 0.02 * np.pi
    # distance_at reads the lowered field
    idx = np.arange(0, 1500, 37)
    np.testing.assert_allclose(cg.distance_at(cloud, res, cloud.P[idx]), res.distance[idx], atol=1e-9)


@pytest.mark.parametrize("off_surface", [None, 5])
def test_a_cloud_of_two_pieces_is_decimated_piece_by_piece(monkeypatch, off_surface):
    # before: "no manifold surface through the points (the cloud's triangles form 2 pieces)", order 1 on the cloud.
    # A point of the first piece off the surface (its consensus triangles dropped) gives the surface's components
    # other labels than the cloud's pieces: the points must still read their own piece's copy
    from cvxgeodesic.mesh import pointcloud

    if off_surface is not None:
        real = pointcloud.triangle_set
        monkeypatch.setattr(pointcloud, "triangle_set", lambda tri, owner, X, kind: (
            lambda F, notes: (F[~(F == off_surface).any(axis=1)] if kind == "consensus" else F, notes))(
                *real(tri, owner, X, kind)))
    P = plane_points(20)
    cloud = PointCloud(np.vstack([P, P + [5.0, 0.0, 0.0]]))
    surface, why = cloud.surface()
    assert why is None and np.unique(surface.component_labels[surface.F]).size == 2
    for source, own, other in ((0, slice(0, 400), slice(400, 800)), (450, slice(400, 800), slice(0, 400))):
        res = cg.GeodesicSolver(cloud, "qclp", resolution=200).solve(source)
        ad = res.info.extra["adapted"]
        assert ad["fallback"] is None and ad["order"] == 2 and ad["components"] == 2
        assert any("2 components were decimated one at a time" in n for n in res.info.notes)
        assert np.isinf(res.distance[other]).all()
        # exact on the planes; around the hole of the point off the surface the copy's field goes round it
        # (measured 0.0028 at most)
        np.testing.assert_allclose(res.distance[own], np.linalg.norm(cloud.P[own] - cloud.P[source], axis=1),
                                   atol=1e-6 if off_surface is None else 0.01)


def test_a_piece_of_a_cloud_without_consensus_falls_back_to_order_1_naming_it(monkeypatch):
    from cvxgeodesic.mesh import pointcloud

    P = plane_points(20)
    cloud = PointCloud(np.vstack([P, P + [5.0, 0.0, 0.0]]))
    real = pointcloud.triangle_set
    # the consensus of the second piece (its points 400..799) left empty
    monkeypatch.setattr(pointcloud, "triangle_set", lambda tri, owner, X, kind: (
        lambda F, notes: (F[(F < 400).all(axis=1)], notes))(*real(tri, owner, X, kind)))
    res = cg.GeodesicSolver(cloud, "qclp", resolution=200).solve(0)
    ad = res.info.extra["adapted"]
    assert ad["order"] == 1 and "no consensus triangle in piece 2 of the cloud's 2" in ad["fallback"]
    assert np.isinf(res.distance[400:]).all() and np.isfinite(res.distance[:400]).all()


def test_surface_through_the_points_is_manifold_and_keeps_the_indices():
    cloud = PointCloud(sphere_points(1500))
    surface, why = cloud.surface()
    assert why is None and surface.is_edge_manifold and surface.n_components == 1
    assert surface.n_vertices == cloud.n_points and np.array_equal(surface.V, cloud.P)
    assert surface.n_faces <= cloud.mesh.n_faces


def test_a_clouds_refused_copies_cost_one_decimation_per_cloud_aggressiveness(monkeypatch):
    from cvxgeodesic.strategies import decimation

    calls = []
    monkeypatch.setattr(decimation, "_decimated_once",
                        lambda mesh, target, agg=7.0: calls.append(agg) or (None, "refused (test)"))
    res = cg.GeodesicSolver(PointCloud(plane_points(30, seed=2)), "qclp", resolution=300).solve(0)
    assert calls == list(decimation.CLOUD_AGGS) and res.info.extra["adapted"]["fallback"] == "refused (test)"
    assert len(decimation.CLOUD_AGGS) < len(decimation.RETRY_AGGS)  # the gentlest never kept a cloud's copy
    calls.clear()
    cg.GeodesicSolver(cg.grid_plane(30), "qclp", resolution=300).solve(0)  # a mesh: every target at every agg
    retries = len(decimation.RETRY_TARGETS) + (len(decimation.RETRY_AGGS) - 1) * decimation.RETRY_TARGETS_LATER
    assert len(calls) == retries


def _mean_error(cloud, res):
    great_circle = np.arccos(np.clip(cloud.P @ cloud.P[0], -1.0, 1.0))
    return float(np.abs(res.distance - great_circle).mean())


def test_a_clean_cloud_s_default_copy_has_a_quarter_of_the_faces_a_noisy_one_a_tenth():
    # 8,000 sphere points: 16K faces, so 1/4 is 4,000 faces and 1/10 the floor of 2,000. Measured mean error 0.00033 π
    # at 1/4 against 0.00069 π at 2,000 faces
    from cvxgeodesic.strategies.adapted import (
        AUTO_MIN_FACES,
        CLEAN_CLOUD_FRACTION,
        CURVED_COPY_TOL,
        NOISY_CLOUD_COPY_TOL,
    )

    X = sphere_points(8000, seed=3)
    clean = PointCloud(X)
    assert clean.clean and clean.noise < 0.01
    res = cg.GeodesicSolver(clean).solve(0)
    ad = res.info.extra["adapted"]
    assert ad["target_faces"] == round(CLEAN_CLOUD_FRACTION * clean.mesh.n_faces) > 1.5 * AUTO_MIN_FACES
    assert ad["refused"] is None and ad["fallback"] is None and ad["source_patches"] == 1
    assert ad["copy_tol"] == CURVED_COPY_TOL
    assert any("on a clean point cloud" in n and "0.25 of the faces" in n for n in res.info.notes)
    usual = cg.GeodesicSolver(clean, resolution=AUTO_MIN_FACES).solve(0)  # "auto" on a noisy cloud of this size
    assert _mean_error(clean, res) < 0.8 * _mean_error(clean, usual)
    # noise of 0.1 of the spacing reads about 0.055: not clean, below the order-1 threshold: the usual copy
    spacing = np.sqrt(4 * np.pi / X.shape[0])
    noisy = PointCloud(X + np.random.default_rng(4).normal(scale=0.1 * spacing, size=X.shape))
    assert not noisy.clean and noisy.default_refusal() is None
    res = cg.GeodesicSolver(noisy).solve(0)
    assert res.info.extra["adapted"]["target_faces"] == AUTO_MIN_FACES
    assert not any("on a clean point cloud" in n for n in res.info.notes)
    # no order-2 patch of the cloud's own (noisy) triangles around the source, and a looser copy
    assert res.info.extra["adapted"]["source_patches"] == 0
    assert res.info.extra["adapted"]["copy_tol"] == NOISY_CLOUD_COPY_TOL
    assert any(n.startswith("no patch solve around the sources: a noisy point cloud") for n in res.info.notes)


def test_a_clean_cloud_s_refused_finer_copy_is_followed_by_the_usual_one(monkeypatch):
    from cvxgeodesic.strategies import adapted

    cloud = PointCloud(sphere_points(8000, seed=3))
    lost = adapted._lost_surface
    monkeypatch.setattr(adapted, "_lost_surface",
                        lambda copy: "refused by the test" if copy.mesh.n_faces > 3000 else lost(copy))
    res = cg.GeodesicSolver(cloud).solve(0)
    ad = res.info.extra["adapted"]
    assert ad["refused"]["target_faces"] > 3000 and ad["refused"]["why"] == "refused by the test"
    assert ad["refused"]["decimation_tries"] and ad["fallback"] is None
    assert ad["target_faces"] == adapted.AUTO_MIN_FACES and ad["faces"] < 3000
    assert any("copy was refused (refused by the test); tried 2000 faces" in n for n in res.info.notes)
    assert _mean_error(cloud, res) < 0.002 * np.pi


def test_clean_is_a_noise_reading_of_at_most_clean_noise_max():
    from cvxgeodesic.mesh.pointcloud import CLEAN_NOISE_MAX

    cloud = PointCloud(sphere_points(500))
    for noise, clean in ((0.0, True), (CLEAN_NOISE_MAX, True), (1.01 * CLEAN_NOISE_MAX, False)):
        cloud.noise = noise
        assert cloud.clean is clean
