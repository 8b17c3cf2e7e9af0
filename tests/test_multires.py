"""Coarse-to-fine solves: ``GeodesicSolver(..., multires=...)`` and the pieces in ``cvxgeodesic.multires``."""

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic.errors import ParameterError
from cvxgeodesic.mesh.decimate import simplify_mesh
from cvxgeodesic.mesh.transfer import SurfaceTransfer
from cvxgeodesic.strategies import default_target_faces, resolve_target


@pytest.fixture(scope="module")
def sphere():
    return cg.icosphere(3)  # 1280 faces


@pytest.mark.parametrize("method", ["shortest-edge", "quadric"])
def test_simplify_to_target(sphere, method):
    c = simplify_mesh(sphere, 320, method=method)
    assert abs(c.n_faces - 320) <= 4 and c.is_edge_manifold and c.simplifier == method
    assert np.abs(np.linalg.norm(c.V, axis=1) - 1).max() < 0.05  # still near the unit sphere


def test_transfer_is_exact_for_linear_fields():
    fine = cg.grid_plane(21, 21)
    coarse = simplify_mesh(fine, 120)
    tr = SurfaceTransfer(coarse, fine.V)
    f = lambda V: 0.3 + 2.0 * V[:, 0] - 0.7 * V[:, 1]  # noqa: E731
    inside = tr.sq_distance < 1e-20  # decimation may cut the square's corners; those points project to the rim
    assert inside.mean() > 0.8
    np.testing.assert_allclose(tr.apply(f(coarse.V))[inside], f(fine.V)[inside], atol=1e-12)
    assert tr.weights.min() >= 0 and np.allclose(tr.weights.sum(axis=1), 1)
    idx, dist = tr.nearest_vertex(coarse.V[[3, 7]] + 1e-9)
    assert idx.tolist() == [3, 7] and dist.max() < 1e-8


def test_approximation_is_labelled_and_close(sphere):
    direct = cg.GeodesicSolver(sphere).solve(0)
    res = cg.GeodesicSolver(sphere, multires=400).solve(0)
    info = res.info
    assert info.status == "approximate" and info.solver == "ipm"
    mr = info.extra["multires"]
    assert mr["polished"] is False and abs(mr["coarse_faces"] - 400) <= 4 and mr["max_source_offset"] >= 0
    assert res.distance[0] == 0 and np.isfinite(res.distance).all()
    err = np.abs(res.distance - direct.distance)
    assert err.mean() < 0.05 * direct.distance.max() and err.max() < 0.2 * direct.distance.max()


def test_polish_returns_the_fine_optimum(sphere):
    direct = cg.geodesic_distance(sphere, [0, 200])
    res = cg.GeodesicSolver(sphere, multires=400, multires_polish=True).solve([0, 200])
    assert res.info.status == "optimal"
    np.testing.assert_allclose(res.distance, direct, atol=1e-6)
    mr = res.info.extra["multires"]
    assert mr["polished"] is True and mr["max_diff_to_coarse_transfer"] > 0
    assert mr["rel_max_diff_to_coarse_transfer"] < 0.5


def test_small_mesh_is_solved_directly():
    mesh = cg.icosphere(1)  # 80 faces, below the 100-face minimum target
    res = cg.GeodesicSolver(mesh, "qclp", multires=True).solve(0)
    assert res.info.status == "optimal" and "skipped" in res.info.extra["multires"]
    np.testing.assert_allclose(res.distance, cg.geodesic_distance(mesh, 0, method="qclp"), atol=1e-9)


def test_unreached_component_stays_inf():
    a, b = cg.icosphere(3), cg.icosphere(2)
    V = np.vstack([a.V, b.V + [5.0, 0, 0]])
    F = np.vstack([a.F, b.F + a.n_vertices])
    res = cg.GeodesicSolver((V, F), "qclp", multires=600).solve(0)
    d = res.distance
    assert np.isfinite(d[: a.n_vertices]).all() and np.isinf(d[a.n_vertices:]).all()
    assert res.info.n_unreachable == b.n_vertices


@pytest.mark.parametrize("normalization", ["area", "paper"])
def test_lam_is_carried_to_the_coarse_mesh(sphere, normalization):
    lam = cg.smoothness_weight(sphere, 1.0, normalization)
    s1 = cg.GeodesicSolver(sphere, multires=400, normalization=normalization)
    s2 = cg.GeodesicSolver(sphere, lam=lam, multires=400, normalization=normalization)
    assert s2._strategy.coarse.config.lam == pytest.approx(s1._strategy.coarse.config.lam, rel=1e-12)
    np.testing.assert_allclose(s1.solve(5).distance, s2.solve(5).distance, atol=1e-7)


def test_distance_matrix_with_multires(sphere):
    D = cg.distance_matrix(sphere, [0, 9], method="qclp", multires=400)
    assert D.shape == (2, sphere.n_vertices) and D[0, 0] == 0 and D[1, 9] == 0


@pytest.mark.parametrize("value", [50, -3, "yes", 1.5])
def test_bad_multires_values(sphere, value):
    with pytest.raises(ParameterError, match="multires"):
        cg.GeodesicSolver(sphere, multires=value)


def test_multires_rejects_baselines_and_nonmanifold_hessian(sphere):
    with pytest.raises(ParameterError, match="baseline"):
        cg.GeodesicSolver(sphere, "heat", multires=True)
    # a fin: a third triangle on an interior edge of a grid
    g = cg.grid_plane(12, 12)
    E = np.sort(np.concatenate([g.F[:, [0, 1]], g.F[:, [1, 2]], g.F[:, [2, 0]]]), axis=1)
    uniq, counts = np.unique(E, axis=0, return_counts=True)
    a, b = uniq[np.flatnonzero(counts == 2)[0]]
    V = np.vstack([g.V, [[0.5, 0.5, 1.0]]])
    F = np.vstack([g.F, [[a, b, g.n_vertices]]])
    assert not cg.TriMesh(V, F).is_edge_manifold
    res = cg.GeodesicSolver((V, F), "qcqp-hessian", multires=100).solve(0)  # the Hessian on a manifold cover
    assert res.info.status == "approximate" and np.isfinite(res.distance).all()
    res = cg.GeodesicSolver((V, F), "qclp", multires=100).solve(0)  # falls back to quadric simplification
    assert res.info.status == "approximate" and np.isfinite(res.distance).all()
    assert res.info.extra["multires"]["simplifier"].startswith("quadric (shortest-edge: the mesh is not")


def test_decimation_time_limit_falls_back_to_quadric(sphere, monkeypatch):
    import cvxgeodesic.mesh.decimate as mr

    monkeypatch.setattr(mr, "decimate_timeout", lambda n_faces: 0.01)  # libigl hangs on some meshes
    c = simplify_mesh(sphere, 320)
    assert c.simplifier.startswith("quadric (shortest-edge: libigl decimate did not finish")
    assert abs(c.n_faces - 320) <= 4


def test_targets():
    assert resolve_target(False, 10**6) is None and resolve_target(0, 10**6) is None
    assert resolve_target(True, 10**6) == 50_000 == default_target_faces(10**7)
    assert resolve_target(True, 8000) == 2000 and resolve_target(1234, 10) == 1234
