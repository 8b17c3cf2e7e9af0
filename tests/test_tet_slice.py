"""Planar slices of tetrahedral meshes (issue 26): exact cut areas and fields, and the PNG."""

from __future__ import annotations

import numpy as np
import pytest

from cvxgeodesic.errors import MeshError, ParameterError
from cvxgeodesic.evaluation.slice_plot import plot_slice
from cvxgeodesic.mesh.generate import icosphere
from cvxgeodesic.mesh.tet_generate import tet_ball, tet_box, tet_l_prism
from cvxgeodesic.mesh.tet_slice import plane_frame, slice_tets


def test_plane_frame():
    n, e1, e2 = plane_frame([0, 0, 2.0])
    np.testing.assert_array_equal(np.array([n, e1, e2]), np.eye(3)[[2, 0, 1]])
    n, e1, e2 = plane_frame([1.0, 0, 0])
    np.testing.assert_array_equal(np.array([e1, e2]), np.eye(3)[[1, 2]])
    n, e1, e2 = plane_frame([1.0, 2.0, -0.5])
    np.testing.assert_allclose(np.cross(e1, e2), n, atol=1e-15)
    np.testing.assert_allclose([e1 @ n, e2 @ n, e1 @ e2], 0, atol=1e-15)
    with pytest.raises(ParameterError, match="nonzero"):
        plane_frame([0, 0, 0])


@pytest.mark.parametrize("origin, normal, area", [
    ([0.5, 0.5, 0.37], [0, 0, 1], 1.0),  # a horizontal square
    ([0.5, 0.5, 0.5], [0, 0, 1], 1.0),  # through a layer of vertices: counted once
    ([0.5, 0.5, 0.5], [1, 1, 0], 2**0.5),  # the diagonal rectangle √2 × 1
    ([0.5, 0.5, 0.5], [1, 1, 1], 3 * 3**0.5 / 4),  # the regular hexagon of side √2/2
])
def test_cut_areas_of_a_box(origin, normal, area):
    for mesh in (tet_box(4), tet_box(4, jitter=0.2, seed=3)):
        cut = slice_tets(mesh, origin=origin, normal=normal)
        assert cut.area == pytest.approx(area, rel=1e-12)
        np.testing.assert_allclose((cut.points - cut.origin) @ cut.normal, 0, atol=1e-15)


def test_linear_fields_are_exact_on_the_cut_and_the_outline_is_the_rim():
    m = tet_l_prism(3, jitter=0.2, seed=1)
    a = np.array([0.7, -0.2, 1.5])
    cut = slice_tets(m, m.V @ a, origin=[1, 1, 0.43], normal=[0, 0, 1])
    np.testing.assert_allclose(cut.values, cut.points @ a, atol=1e-12)
    assert cut.area == pytest.approx(3.0, rel=1e-12)
    # the outline is the L's perimeter (8), the uv frame is x, y
    seg = cut.points[cut.outline]
    assert np.linalg.norm(seg[:, 1] - seg[:, 0], axis=1).sum() == pytest.approx(8.0, rel=1e-12)
    np.testing.assert_allclose(cut.uv, (cut.points - cut.origin)[:, :2], atol=1e-15)
    assert cut.tets.shape == (cut.triangles.shape[0],) and (np.diff(cut.tets) >= 0).all()


def test_inf_propagates_and_a_missed_plane_is_empty():
    m = tet_box(2)
    d = np.zeros(m.n_vertices)
    d[13] = np.inf  # the centre
    cut = slice_tets(m, d, origin=[0.5, 0.5, 0.6])
    assert np.isinf(cut.values).any() and np.isfinite(cut.values).any()
    empty = slice_tets(m, d, origin=[0, 0, 3.0])
    assert empty.triangles.shape == (0, 3) and empty.area == 0


def test_ball_cut_through_the_centre_is_a_disc():
    b = tet_ball(8)
    cut = slice_tets(b, origin=[0, 0, 0], normal=[0.3, 0.2, 1.0])
    # an inscribed polygon of the unit disc: a little less than π
    assert 0.97 * np.pi < cut.area < np.pi


def test_plot_writes_a_png(tmp_path):
    m = tet_box(6)
    d = np.linalg.norm(m.V - 0.5, axis=1)
    d[0] = np.inf
    out = plot_slice(m, d, tmp_path / "s.png", origin=[0.5, 0.5, 0.02], title="t", points=[[0.5, 0.5, 0.5]],
                         colorbar_label="distance", dpi=40)
    data = out.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 1000
    from matplotlib.image import imread

    img = imread(out)
    assert img.shape[:2] == (round(5.4 * 40), round(6.4 * 40))
    with pytest.raises(ParameterError, match="misses"):
        plot_slice(m, d, tmp_path / "t.png", origin=[0, 0, 5])
    with pytest.raises(ParameterError, match="png"):
        plot_slice(m, d, tmp_path / "t.jpg")
    with pytest.raises(ParameterError, match="values"):
        plot_slice(m, d[:-1], tmp_path / "t.png")
    surface = icosphere(1)
    with pytest.raises(MeshError, match="takes a tetrahedral mesh.*plot_field"):
        plot_slice(surface, np.zeros(surface.n_vertices), tmp_path / "t.png")
    assert not (tmp_path / "t.png").exists()
