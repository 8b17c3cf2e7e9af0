"""Generated tetrahedral meshes (issue 26): sizes, volumes, conformity, shape, jitter, the L prism's exact distance."""

from __future__ import annotations

import numpy as np
import pytest

from cvxgeodesic.errors import ParameterError
from cvxgeodesic.mesh.tet_generate import l_prism_distance, tet_ball, tet_box, tet_l_prism


def _conforming(mesh):
    """Manifold, no fold, one component, and the boundary is exactly the domain's surface area (checked by callers)."""
    return mesh.is_manifold and mesh.folded_faces.size == 0 and mesh.n_components == 1


def test_box_jitter_moves_interior_vertices_only_and_keeps_tets_positive():
    regular = tet_box(5)
    for seed in range(3):
        m = tet_box(5, jitter=0.25, seed=seed)
        moved = np.linalg.norm(m.V - regular.V, axis=1) > 0
        boundary = np.zeros(m.n_vertices, dtype=bool)
        boundary[regular.boundary_vertices] = True
        assert not moved[boundary].any() and moved[~boundary].all()
        assert np.abs(m.V - regular.V).max() <= 0.25 / 5 + 1e-15
        assert (m.signed_volumes > 0).all() and _conforming(m)
        np.testing.assert_allclose(m.total_volume, 1.0)
    np.testing.assert_array_equal(tet_box(4, jitter=0.2, seed=7).V, tet_box(4, jitter=0.2, seed=7).V)


@pytest.mark.parametrize("kwargs, match", [
    ({"nx": 0}, "nx must be a positive integer"),
    ({"nx": 2, "jitter": 0.3}, r"jitter must be a number in \[0, 0.25\]"),
    ({"nx": 2, "size": -1.0}, "size must be a positive number"),
    ({"nx": 2, "size": (1.0, 2.0)}, "size must be a positive number"),
])
def test_box_bad_parameters(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        tet_box(**kwargs)


@pytest.mark.parametrize("n, tets", [(4, 1152), (8, 9216)])
def test_l_prism_sizes_volume_and_surface(n, tets):
    m = tet_l_prism(n, jitter=0.2, seed=1)
    assert m.n_tets == tets == 18 * n**3
    np.testing.assert_allclose(m.total_volume, 3.0, rtol=1e-12)
    # the surface: top and bottom (3 each), six outer walls of height 1 with total length 8
    np.testing.assert_allclose(m.boundary_area, 3 + 3 + 8, rtol=1e-12)
    assert (m.signed_volumes > 0).all() and _conforming(m)
    # no vertex inside the removed square
    assert not ((m.V[:, 0] > 1 + 1e-12) & (m.V[:, 1] > 1 + 1e-12)).any()
    # the re-entrant edge is on the boundary, not jittered
    edge = np.flatnonzero((np.abs(m.V[:, 0] - 1) < 1e-15) & (np.abs(m.V[:, 1] - 1) < 1e-15))
    assert edge.size == n + 1 and np.isin(edge, m.boundary_vertices).all()


def test_ball_is_a_ball():
    m = tet_ball(6)
    assert m.n_tets == 6 * 6**3 + 36 * 6**2 * 2 and (m.signed_volumes > 0).all() and _conforming(m)
    r = np.linalg.norm(m.V[m.boundary_vertices], axis=1)
    np.testing.assert_allclose(r, 1.0, atol=1e-14)
    # an inscribed polyhedron: a little less than the ball's volume and area, converging
    errs = []
    for n in (4, 8):
        b = tet_ball(n)
        assert 0 < 4 / 3 * np.pi - b.total_volume and 0 < 4 * np.pi - b.boundary_area
        errs.append(4 / 3 * np.pi - b.total_volume)
    assert errs[1] < errs[0] / 3
    # the boundary surface is a closed sphere: Euler characteristic 2
    s = m.boundary_mesh()
    assert s.is_edge_manifold and m.boundary_vertices.size - s.edges.shape[0] + s.n_faces == 2
    np.testing.assert_allclose(tet_ball(4, radius=3.0).V, 3.0 * tet_ball(4).V, rtol=1e-14, atol=1e-14)


def test_ball_smoothing_improves_the_worst_tetrahedron():
    q = {s: (lambda b: (b.cell_min_altitudes / b.cell_longest_edges).min())(tet_ball(8, smooth=s)) for s in (0, 5)}
    assert q[0] < 0.1 and q[5] > 0.19  # the docstring's 0.098 → 0.196


def test_l_prism_distance_visible_and_around_the_corner():
    s = np.array([0.5, 1.5, 0.0])
    # visible: straight
    np.testing.assert_allclose(l_prism_distance(s, [[0.5, 0.5, 0.0], [0.9, 0.2, 1.0]]),
                               [1.0, np.linalg.norm([0.4, -1.3, 1.0])])
    # hidden behind the removed square: around the corner (1, 1), then lifted by Δz
    x = np.array([1.8, 0.5, 0.5])
    planar = np.hypot(0.5, 0.5) + np.hypot(0.8, 0.5)  # 1.650 (straight: 1.640)
    np.testing.assert_allclose(l_prism_distance(s, x[None]), [np.hypot(planar, 0.5)])
    # a segment grazing the corner exactly is not blocked; the distance is continuous across the shadow line
    graze = np.array([1.5, 0.5, 0.0])  # s, (1, 1), graze are collinear
    np.testing.assert_allclose(l_prism_distance(s, graze[None]), [np.linalg.norm(graze - s)])
    ts = np.linspace(-1e-6, 1e-6, 5)
    near = np.column_stack([1.5 + ts, 0.5 + ts, 0 * ts])
    d = l_prism_distance(s, near)
    np.testing.assert_allclose(d, np.linalg.norm(near - s, axis=1), atol=1e-9)
    # symmetric in source and target, on random pairs in the L
    rng = np.random.default_rng(0)
    P = rng.uniform(0, 2, (400, 3)) * [1, 1, 0.5]
    P = P[~((P[:, 0] > 1) & (P[:, 1] > 1))]
    D1 = np.array([l_prism_distance(p, P[:20]) for p in P[:20]])
    np.testing.assert_allclose(D1, D1.T, atol=1e-14)
    # and never below the straight distance
    assert (D1 >= np.linalg.norm(P[:20, None] - P[None, :20], axis=2) - 1e-14).all()


def test_l_prism_distance_against_visibility_by_sampling():
    rng = np.random.default_rng(1)
    P = rng.uniform(0, 2, (3000, 2))
    P = P[~((P[:, 0] > 1) & (P[:, 1] > 1))][:600]
    S, X = P[:300], P[300:600]
    t = np.linspace(0, 1, 2001)[:, None, None]
    samples = S[None] + t * (X - S)[None]  # (2001, 300, 2)
    depth = np.minimum(samples - 1, 2 - samples).min(axis=2)  # > 0 strictly inside the removed square
    blocked, clear = depth.max(axis=0) > 1e-3, depth.max(axis=0) < 0  # leave out grazing segments
    c = np.array([1.0, 1.0])
    straight = np.linalg.norm(X - S, axis=1)
    around = np.linalg.norm(S - c, axis=1) + np.linalg.norm(X - c, axis=1)
    d = np.array([l_prism_distance([*s, 0.0], [[*x, 0.0]])[0] for s, x in zip(S, X, strict=True)])
    assert blocked.sum() > 30 and clear.sum() > 100
    np.testing.assert_allclose(d[blocked], around[blocked], rtol=1e-14)
    np.testing.assert_allclose(d[clear], straight[clear], rtol=1e-14)
