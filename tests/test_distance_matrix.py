"""``cvxgeodesic.distance_matrix``: one GeodesicSolver, one row per source vertex."""

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic.errors import SourceError


@pytest.fixture(scope="module")
def sphere():
    return cg.icosphere(2)


def test_rows_match_single_solves(sphere):
    verts = [0, 17, 100, 17]
    D = cg.distance_matrix(sphere, verts, method="qcqp-hessian", m=1.0)
    assert D.shape == (4, sphere.n_vertices) and D.dtype == np.float64
    solver = cg.GeodesicSolver(sphere, "qcqp-hessian")
    for i, v in enumerate(verts):
        np.testing.assert_allclose(D[i], solver.solve(v).distance, rtol=1e-9, atol=1e-12)
        assert D[i, v] == 0.0
    np.testing.assert_array_equal(D[1], D[3])  # a repeated vertex is solved once
    # nearly symmetric (each row is its own problem), close to the great-circle distance
    sub = D[:3][:, [0, 17, 100]]
    np.testing.assert_allclose(sub, sub.T, atol=0.05)


def test_single_int_and_baseline(sphere):
    D = cg.distance_matrix(sphere, 5, method="dijkstra", progress=True)
    assert D.shape == (1, sphere.n_vertices)
    np.testing.assert_allclose(D[0], cg.geodesic_distance(sphere, 5, method="dijkstra"))


@pytest.mark.parametrize("verts, match", [([], "empty"), ([0, 999], "out of range"), ([[0, 1]], "1-D"),
                                          (True, "vertex indices"), ([0.5], "integer")])
def test_bad_vertices(sphere, verts, match):
    with pytest.raises(SourceError, match=match):
        cg.distance_matrix(sphere, verts)
