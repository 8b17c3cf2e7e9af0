"""lipschitz_envelope: the largest field below given values that is 1-Lipschitz along the edges."""

import numpy as np

import cvxgeodesic as cg
from cvxgeodesic.mesh.envelope import lipschitz_envelope


def test_an_exact_flat_field_is_left_as_it_is():
    # the Euclidean distance obeys the triangle inequality along every edge: nothing to lower
    grid = cg.grid_plane(12, jitter=0.2, seed=1)
    d = np.linalg.norm(grid.V - grid.V[40], axis=1)
    np.testing.assert_array_equal(lipschitz_envelope(grid, d), d)


def test_a_raised_value_drops_to_its_least_neighbour_plus_the_edge():
    grid = cg.grid_plane(12, jitter=0.2, seed=1)
    d = np.linalg.norm(grid.V - grid.V[40], axis=1)
    raised = d.copy()
    raised[77] += 1.0
    out = lipschitz_envelope(grid, raised)
    A = grid.vertex_adjacency.tocsr()
    nbrs, lengths = A[77].indices, A[77].data
    assert np.isclose(out[77], np.min(d[nbrs] + lengths)) and d[77] <= out[77] < raised[77]
    others = np.arange(grid.n_vertices) != 77
    np.testing.assert_array_equal(out[others], d[others])


def test_no_value_stays_no_value_and_a_source_stays_zero():
    mesh = cg.TriMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [5, 5, 0], [6, 5, 0], [5, 6, 0]], [[0, 1, 2], [3, 4, 5]])
    d = np.array([0.0, 3.0, 0.2, np.inf, np.inf, np.inf])  # the second triangle: unreached
    out = lipschitz_envelope(mesh, d)
    np.testing.assert_allclose(out[:3], [0.0, 1.0, 0.2])
    assert np.isinf(out[3:]).all()
    assert np.isinf(lipschitz_envelope(mesh, np.full(6, np.inf))).all()
