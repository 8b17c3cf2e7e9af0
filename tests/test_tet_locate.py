"""Points inside tetrahedral meshes (issue 26): VolumePoint validation, point location, interpolation."""

from __future__ import annotations

import re

import numpy as np
import pytest

from cvxgeodesic.errors import ParameterError, SourceError
from cvxgeodesic.mesh.locate import VolumePoint, interpolate_at, locate_points, volume_point
from cvxgeodesic.mesh.tet_generate import tet_ball, tet_box, tet_l_prism


@pytest.mark.parametrize("tet, bary, match", [
    (-1, [1, 0, 0, 0], "negative"),
    (1.5, [1, 0, 0, 0], "must be a tetrahedron index"),
    (True, [1, 0, 0, 0], "must be a tetrahedron index"),
    (0, [0.5, 0.5, 0], "must have 4 coordinates"),
    (0, [0.5, 0.5, np.nan, 0], "must be finite"),
    (0, [1.1, -0.1, 0, 0], "must be >= 0"),
    (0, [0.5, 0.5, 0.5, 0], "must sum to 1"),
    (0, "abcd", "bary must be 4 numbers"),
])
def test_volume_point_validation(tet, bary, match):
    with pytest.raises(SourceError, match=match):
        VolumePoint(tet, bary)


def test_volume_point_normalizes_and_compares():
    p = VolumePoint(np.int64(2), [1 + 1e-12, -1e-12, 0, 0])
    assert p.tet == 2 and p.bary.min() == 0 and p.bary.sum() == 1 and not p.bary.flags.writeable
    assert p == VolumePoint(2.0, [1, 0, 0, 0]) and hash(p) == hash(VolumePoint(2, [1, 0, 0, 0]))
    assert repr(VolumePoint(1, [0.25] * 4)) == "VolumePoint(tet=1, bary=[0.25, 0.25, 0.25, 0.25])"
    with pytest.raises(SourceError, match="tetrahedron index 48 is out of range"):
        VolumePoint(48, [1, 0, 0, 0]).position(tet_box(2))


def test_locate_random_points_in_a_nonconvex_mesh():
    m = tet_l_prism(3, jitter=0.2, seed=5)
    rng = np.random.default_rng(0)
    X = rng.uniform([0, 0, 0], [2, 2, 1], (500, 3))
    inside = ~((X[:, 0] > 1) & (X[:, 1] > 1))
    tets, bary = locate_points(m, X)
    assert ((tets >= 0) == inside).all()
    np.testing.assert_allclose(np.einsum("pi,pij->pj", bary[inside], m.V[m.T[tets[inside]]]), X[inside], atol=1e-12)
    assert (bary[inside] >= 0).all() and np.isnan(bary[~inside]).all()


def test_points_on_vertices_faces_and_the_boundary_are_found():
    m = tet_box(2)
    tets, bary = locate_points(m, m.V)  # every vertex, boundary corners included
    assert (tets >= 0).all()
    np.testing.assert_allclose(np.einsum("pi,pij->pj", bary, m.V[m.T[tets]]), m.V, atol=1e-14)
    assert (bary.max(axis=1) > 1 - 1e-12).all()


def test_volume_point_and_its_errors():
    m = tet_ball(4)
    p = volume_point(m, [0.1, 0.2, -0.3])
    np.testing.assert_allclose(p.position(m), [0.1, 0.2, -0.3], atol=1e-14)
    many = volume_point(m, [[0, 0, 0.5], [0.2, 0, 0]])
    assert isinstance(many, list) and len(many) == 2
    with pytest.raises(SourceError, match=r"xyz = \[2.0, 0.0, 0.0\] is outside ball4 .*nearest vertex is 1 away"):
        volume_point(m, [2.0, 0, 0])
    with pytest.raises(SourceError, match=r"xyz\[1\] = \[0.0, 0.0, 5.0\] is outside"):
        volume_point(m, [[0, 0, 0], [0, 0, 5.0], [0, 0, 6.0]])
    with pytest.raises(SourceError, match="finite"):
        volume_point(m, [np.nan, 0, 0])


# issue 41: from about 1e154 on, scipy's k-d tree search overflowed ("The value of p too large for this dataset")
@pytest.mark.parametrize("x", [1e154, 1e200, 1e300, -1.7e308, np.finfo(float).max])
def test_huge_finite_positions_are_outside_with_a_clean_error(x):
    m = tet_box(2)
    with np.errstate(over="raise", invalid="raise"):  # nor an overflow on the way
        with pytest.raises(SourceError, match=re.escape(f"xyz = {[float(x), 0.0, 0.0]} is outside box2x2x2 (in no "
                                                        "tetrahedron; the nearest vertex is ") + r"[0-9.e+]+ away\)$"):
            volume_point(m, [x, 0, 0])
        tets, bary = locate_points(m, [[0.25, 0.5, 0.75], [0, x, 0], [x, x, x]])
    assert tets[0] >= 0 and (tets[1:] == -1).all() and np.isnan(bary[1:]).all()
    values = interpolate_at(m, m.V[:, 0], [[0.25, 0.5, 0.75], [0, 0, x]])
    assert values[0] == pytest.approx(0.25) and np.isnan(values[1])


def test_interpolation_is_exact_for_linear_fields_and_keeps_inf():
    m = tet_box(3, jitter=0.2, seed=1)
    a = np.array([1.0, -2.0, 0.5])
    f = m.V @ a
    rng = np.random.default_rng(2)
    X = rng.uniform(0, 1, (50, 3))
    np.testing.assert_allclose(interpolate_at(m, f, X), X @ a, atol=1e-12)
    pts = volume_point(m, X[:3])
    np.testing.assert_allclose(interpolate_at(m, f, pts), X[:3] @ a, atol=1e-12)
    np.testing.assert_allclose(interpolate_at(m, f, pts[0]), X[:1] @ a, atol=1e-12)
    assert np.isnan(interpolate_at(m, f, [[3.0, 0, 0]]))[0]
    g = f.copy()
    g[m.T[0, 0]] = np.inf  # an unreachable vertex: only points with a zero coordinate on it stay finite
    on_face, inside = VolumePoint(0, [0, 0.2, 0.3, 0.5]), VolumePoint(0, [0.1, 0.2, 0.2, 0.5])
    out = interpolate_at(m, g, [on_face, inside])
    np.testing.assert_allclose(out[0], on_face.position(m) @ a, rtol=1e-12)
    assert out[1] == np.inf
    with pytest.raises(ParameterError, match="values"):
        interpolate_at(m, f[:-1], X)
    with pytest.raises(ParameterError, match="not a mix"):
        interpolate_at(m, f, [pts[0], [0.1, 0.1, 0.1]])
