"""Tests of cvxgeodesic.plotting: PNG output, pixel content, marching triangles, validation and atomic writes."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from cvxgeodesic.errors import ParameterError
from cvxgeodesic.mesh import TriMesh, cylinder, grid_plane, icosphere
from cvxgeodesic.plotting import isoline_segments, plot_error_map, plot_field, plot_gradient_histogram


def _png_size(path) -> tuple[int, int]:
    with open(path, "rb") as fh:
        assert fh.read(8) == b"\x89PNG\r\n\x1a\n"
    with Image.open(path) as im:
        im.verify()
    with Image.open(path) as im:
        im.load()  # decodes the whole image: a truncated file fails here
        return im.size


def _sphere_distance(mesh: TriMesh, i: int = 0) -> np.ndarray:
    return np.arccos(np.clip(mesh.V @ mesh.V[i] / np.linalg.norm(mesh.V[i]), -1.0, 1.0))


def _chord_length(a: float, b: float, c: float) -> float:
    """Length of {a x + b y = c} inside the unit square, by dense sampling along the line."""
    t = np.linspace(-3.0, 3.0, 600_001)
    p0 = np.array([a, b]) * c / (a * a + b * b)
    d = np.array([-b, a]) / np.hypot(a, b)
    pts = p0 + t[:, None] * d
    inside = np.all((pts >= 0) & (pts <= 1), axis=1)
    return float(inside.sum() * (t[1] - t[0]))


# ----------------------------------------------------------------------------------------------------------------------
# plot_field
# ----------------------------------------------------------------------------------------------------------------------


def test_plot_field_writes_png_of_expected_size(tmp_path):
    mesh = icosphere(2)
    out = plot_field(mesh, _sphere_distance(mesh), tmp_path / "field.png", title="sphere")
    assert out == tmp_path / "field.png"
    # the default: two panels side by side (front and back), each as wide as a one-panel picture's
    assert _png_size(out) == (1728, 810)
    assert [p.name for p in tmp_path.iterdir()] == ["field.png"]  # no temporary left behind
    assert _png_size(plot_field(mesh, _sphere_distance(mesh), tmp_path / "one.png", view="front")) == (960, 810)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"isolines": 0, "show_colorbar": False, "dpi": 50, "view": "back"},
        {"isolines": [0.5, 1.0, 2.0], "view": (30, 45), "dpi": 50, "cmap": "magma"},
        {"isolines": None, "vmin": 0.5, "vmax": 1.5, "dpi": 50, "view": (90, 0)},
    ],
)
def test_plot_field_options(tmp_path, kwargs):
    mesh = icosphere(2)
    out = plot_field(mesh, _sphere_distance(mesh), tmp_path / "f.png", **kwargs)
    assert _png_size(out) == (320, 270)


def test_plot_field_marks_sources_and_faces_them(tmp_path):
    from cvxgeodesic.evaluation.camera import _camera

    mesh = icosphere(2)
    for src in (0, [5, 17]):
        out = plot_field(mesh, _sphere_distance(mesh), tmp_path / "s.png", sources=src, dpi=40)
        assert _png_size(out) == (460, 216)  # two panels
        plot_error_map(mesh, np.abs(mesh.V[:, 0]), tmp_path / "e.png", sources=src, dpi=40)
    # the default view turns towards the first marked vertex's normal
    for i in (0, 7, 30):
        n = mesh.V[i] / np.linalg.norm(mesh.V[i])
        assert _camera(mesh.V, None, n)[2] @ n > 0.5
    with pytest.raises(ValueError, match="sources"):
        plot_field(mesh, mesh.V[:, 0], tmp_path / "bad.png", sources=[mesh.n_vertices])
    with pytest.raises(ValueError, match="sources"):
        plot_field(mesh, mesh.V[:, 0], tmp_path / "bad.png", sources=[0.5])
    assert not (tmp_path / "bad.png").exists()


def test_plot_field_open_meshes_and_unreachable(tmp_path):
    plane = grid_plane(6, jitter=0.2)
    plot_field(plane, plane.V[:, 0] + plane.V[:, 1], tmp_path / "plane.png", dpi=40)
    cyl = cylinder(16, 6)
    d = cyl.V[:, 2].copy()
    d[cyl.V[:, 2] > 1.0] = np.inf  # unreachable part drawn grey
    d[0] = np.nan
    plot_field(cyl, d, tmp_path / "cyl.png", dpi=40)
    all_inf = np.full(cyl.n_vertices, np.inf)
    plot_field(cyl, all_inf, tmp_path / "inf.png", dpi=40)
    for name in ("plane.png", "cyl.png", "inf.png"):
        assert _png_size(tmp_path / name) == (460, 216)  # two panels


def test_plot_field_accepts_vf_tuple_and_str_path(tmp_path):
    mesh = icosphere(1)
    plot_field((mesh.V, mesh.F), mesh.V[:, 2], str(tmp_path / "t.PNG"), dpi=30)
    assert (tmp_path / "t.PNG").is_file()


def test_values_shape_error_names_values_and_shapes(tmp_path):
    mesh = icosphere(1)  # 42 vertices
    with pytest.raises(ValueError, match=r"values.*\(42,\).*\(41,\)"):
        plot_field(mesh, np.zeros(41), tmp_path / "x.png")
    with pytest.raises(ValueError, match=r"values.*\(42,\).*\(42, 1\)"):
        plot_field(mesh, np.zeros((42, 1)), tmp_path / "x.png")
    with pytest.raises(ValueError, match="rel_error"):
        plot_error_map(mesh, np.zeros(3), tmp_path / "x.png")
    with pytest.raises(ValueError, match="values"):
        isoline_segments(mesh, np.zeros(5), [0.5])
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("name", ["x.jpg", "x.pdf", "x", "x.png.tmp"])
def test_unsupported_extension(tmp_path, name):
    mesh = icosphere(1)
    with pytest.raises(ValueError, match="extension"):
        plot_field(mesh, mesh.V[:, 0], tmp_path / name)
    with pytest.raises(ValueError, match="extension"):
        plot_gradient_histogram({"a": np.ones(5)}, tmp_path / name)
    assert list(tmp_path.iterdir()) == []


def test_bad_view_and_missing_directory(tmp_path):
    mesh = icosphere(1)
    with pytest.raises(ValueError, match="view"):
        plot_field(mesh, mesh.V[:, 0], tmp_path / "v.png", view=(1, 2, 3))
    with pytest.raises(ParameterError, match="does not exist"):
        plot_field(mesh, mesh.V[:, 0], tmp_path / "nope" / "v.png")


def test_atomic_write_leaves_nothing_on_failure(tmp_path, monkeypatch):
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    mesh = icosphere(1)
    target = tmp_path / "keep.png"
    target.write_bytes(b"old contents")

    def broken_print_png(self, fh, *args, **kwargs):
        fh.write(b"\x89PNG\r\n\x1a\n half a picture")
        raise OSError("disk full")

    monkeypatch.setattr(FigureCanvasAgg, "print_png", broken_print_png)
    with pytest.raises(OSError, match="disk full"):
        plot_field(mesh, mesh.V[:, 0], target)
    with pytest.raises(OSError, match="disk full"):
        plot_field(mesh, mesh.V[:, 0], tmp_path / "new.png")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.png"]
    assert target.read_bytes() == b"old contents"


# ----------------------------------------------------------------------------------------------------------------------
# marching triangles
# ----------------------------------------------------------------------------------------------------------------------


def test_isolines_of_planar_linear_field_are_straight_and_placed():
    mesh = grid_plane(9, jitter=0.3, seed=3)
    a, b, c0 = 0.3, 0.7, 0.1
    f = a * mesh.V[:, 0] + b * mesh.V[:, 1] + c0
    levels = np.array([0.2, 0.45, 0.6, 0.95])
    seg = isoline_segments(mesh, f, levels)
    assert seg.ndim == 3 and seg.shape[1:] == (2, 3)
    assert np.allclose(seg[..., 2], 0.0)
    fseg = a * seg[..., 0] + b * seg[..., 1] + c0
    which = np.argmin(np.abs(fseg[:, 0, None] - levels[None, :]), axis=1)
    assert np.allclose(fseg, levels[which][:, None], atol=1e-12)  # both end points on the level line
    lengths = np.linalg.norm(seg[:, 1] - seg[:, 0], axis=1)
    assert np.all(lengths > 0)
    for k, lev in enumerate(levels):
        # the pieces add up to the chord of the straight line inside the square (no gaps, no overlaps)
        assert lengths[which == k].sum() == pytest.approx(_chord_length(a, b, lev - c0), abs=2e-4)


def test_isoline_through_vertices_and_along_edges_is_not_duplicated():
    mesh = grid_plane(8)  # regular grid: x = 0.5 is a grid line made of mesh edges
    seg = isoline_segments(mesh, mesh.V[:, 0], [0.5])
    assert np.allclose(seg[..., 0], 0.5)
    ys = np.sort(seg[..., 1], axis=1)
    assert len(seg) == 8  # each vertical edge exactly once
    assert np.allclose(np.sort(ys[:, 0]), np.arange(8) / 8)
    assert np.allclose(np.linalg.norm(seg[:, 1] - seg[:, 0], axis=1).sum(), 1.0)


def test_isolines_skip_non_finite_and_handle_empty():
    mesh = grid_plane(4)
    f = mesh.V[:, 0].copy()
    assert isoline_segments(mesh, f, []).shape == (0, 2, 3)
    assert isoline_segments(mesh, f, [5.0]).shape == (0, 2, 3)
    f[mesh.V[:, 0] > 0.6] = np.inf
    seg = isoline_segments(mesh, f, [0.3, 0.9])
    assert len(seg) and np.allclose(seg[..., 0], 0.3)
    with pytest.raises(ValueError, match="finite"):
        isoline_segments(mesh, mesh.V[:, 0], [np.nan])


def test_isolines_on_sphere_lie_on_circles():
    mesh = icosphere(3)
    d = mesh.V[:, 2]  # height: linear on the sphere's chords, levels are circles z = const
    seg = isoline_segments(mesh, d, [0.0, 0.5])
    assert np.allclose(np.minimum(np.abs(seg[..., 2]), np.abs(seg[..., 2] - 0.5)), 0.0, atol=1e-12)


# ----------------------------------------------------------------------------------------------------------------------
# error map and histograms
# ----------------------------------------------------------------------------------------------------------------------


def test_plot_error_map(tmp_path):
    mesh = icosphere(2)
    exact = _sphere_distance(mesh)
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.abs(exact * (1 + 0.05 * mesh.V[:, 0]) - exact) / exact
    rel[0] = np.nan  # the source
    out = plot_error_map(mesh, rel, tmp_path / "err.png", title="error")
    assert _png_size(out) == (1728, 810)  # two panels
    assert _png_size(plot_error_map(mesh, rel, tmp_path / "one.png", view=(10, 20))) == (960, 810)
    plot_error_map(mesh, np.zeros(mesh.n_vertices), tmp_path / "zero.png", vmax=0.1, dpi=40)
    plot_error_map(mesh, np.full(mesh.n_vertices, np.nan), tmp_path / "nan.png", dpi=40)
    assert _png_size(tmp_path / "nan.png") == (460, 216)


def test_plot_gradient_histogram(tmp_path):
    rng = np.random.default_rng(0)
    norms = {
        "exact": np.clip(rng.normal(1.0, 0.02, 500), 0, None),
        "dijkstra": rng.uniform(0.8, 1.4, 500),
        "heat": np.r_[rng.normal(0.97, 0.05, 499), np.inf],  # non-finite entries are ignored
    }
    out = plot_gradient_histogram(norms, tmp_path / "h.png", title="norms", weights=np.ones(500))
    w, h = _png_size(out)
    assert w > 100 and h > 100
    counts, edges = np.histogram(norms["dijkstra"], bins=20)
    many = {**norms, "pre": (counts, edges), **{f"m{i}": rng.uniform(0.5, 1.1, 50) for i in range(4)}}
    many.pop("heat")
    plot_gradient_histogram(many, tmp_path / "many.png", dpi=40)
    _png_size(tmp_path / "many.png")
    with pytest.raises(ValueError, match="weights"):
        plot_gradient_histogram(norms, tmp_path / "bad.png", weights=np.ones(3))
    with pytest.raises(ValueError, match="edges"):
        plot_gradient_histogram({"a": (counts, edges[:-1])}, tmp_path / "bad.png")
    with pytest.raises(ValueError, match="non-empty"):
        plot_gradient_histogram({}, tmp_path / "bad.png")
    for bins in (0, True, 2.5):  # the shared count check (validation.check_count): a ParameterError, a ValueError
        with pytest.raises(ValueError, match=f"bins must be a positive integer, got {bins!r}"):
            plot_gradient_histogram(norms, tmp_path / "bad.png", bins=bins)
    assert not (tmp_path / "bad.png").exists()


# ----------------------------------------------------------------------------------------------------------------------
# pixel content: what the renderer draws (issue 13: these guard the surface, the isolines and the culling)
# ----------------------------------------------------------------------------------------------------------------------


def _pixels(path) -> np.ndarray:
    import matplotlib.image as mpimg

    return mpimg.imread(path)[..., :3]  # (H, W, 3) float in [0, 1]


def _screen(mesh, view="front", up="auto") -> np.ndarray:
    """Vertex positions in the renderer's camera frame: (n, 3) screen right, screen up, towards the viewer."""
    from cvxgeodesic.evaluation.camera import _camera

    return (mesh.V - mesh.V.mean(axis=0)) @ _camera(mesh.V, view, up=up).T


def _surface_mask(img) -> np.ndarray:
    return ~np.all(img > 0.98, axis=2)  # the figure background is white


def test_surface_is_drawn_and_coloured_along_the_field(tmp_path):
    mesh = icosphere(3)
    P = _screen(mesh)
    src = int(np.argmin(P[:, 0]))  # the vertex furthest left on screen
    d = np.linalg.norm(mesh.V - mesh.V[src], axis=1)
    img = _pixels(plot_field(mesh, d, tmp_path / "f.png", isolines=0, show_colorbar=False, dpi=40, view="front"))
    surf = _surface_mask(img)
    # a unit sphere fills about half of the square panel it is fitted into
    assert 0.35 < surf.mean() < 0.75
    cols = np.flatnonzero(surf.any(axis=0))
    width = cols[-1] - cols[0]
    near = img[:, cols[0]: cols[0] + width // 5][surf[:, cols[0]: cols[0] + width // 5]]
    far = img[:, cols[-1] - width // 5: cols[-1]][surf[:, cols[-1] - width // 5: cols[-1]]]
    # viridis: blue over red at the low end (near the source), red over blue at the high end (far from it);
    # the Lambert shading scales all three channels alike, so the comparison holds in shadow too
    assert np.mean(near[:, 2] > near[:, 0]) > 0.9
    assert np.mean(far[:, 0] > far[:, 2]) > 0.9
    assert np.ptp(img[surf].mean(axis=1)) > 0.3  # not one flat colour


def test_isolines_are_drawn_where_the_levels_are_and_only_then(tmp_path):
    plane = grid_plane(16)
    view = (90.0, 0.0)  # from straight above (up z: mplot3d's convention): the plane is a square on screen, unshaded
    x = _screen(plane, view, up="z")[:, 0]  # screen right, centred: -0.5 .. 0.5
    levels = [-0.3, 0.05, 0.3]
    kw = {"show_colorbar": False, "dpi": 80, "cmap": "autumn", "view": view, "up": "z"}  # autumn: bright everywhere
    on = _pixels(plot_field(plane, x, tmp_path / "on.png", isolines=levels, **kw))
    off = _pixels(plot_field(plane, x, tmp_path / "off.png", isolines=0, **kw))

    def dips(img):
        # pixels darker than the surface two pixels to their left and right: thin dark lines across each row
        lum = img.mean(axis=2)
        return lum[:, 2:-2] < np.minimum(lum[:, :-4], lum[:, 4:]) - 0.1

    assert dips(off).sum() == 0
    dark = dips(on)
    surf = _surface_mask(off)
    assert 0 < dark.sum() < 0.05 * surf.sum()  # lines, not areas
    rows = np.flatnonzero(surf.any(axis=1))
    line_cols = np.flatnonzero(dark.sum(axis=0) > 0.5 * rows.size) + 2  # columns dark over half the square's height
    cols = np.flatnonzero(surf.any(axis=0))
    expected = cols[0] + (np.array(levels) + 0.5) * (cols[-1] - cols[0])
    groups = np.split(line_cols, np.flatnonzero(np.diff(line_cols) > 1) + 1)
    assert len(groups) == len(levels), line_cols
    assert np.allclose([g.mean() for g in groups], expected, atol=3.0)


def test_back_faces_are_culled_on_a_closed_mesh(tmp_path):
    mesh = icosphere(3)
    front = (_screen(mesh)[:, 2] > 0).astype(float)  # 1 on the half facing the camera, 0 on the far half
    img = _pixels(plot_field(mesh, front, tmp_path / "c.png", isolines=0, show_colorbar=False, dpi=40, cmap="bwr",
                             vmin=0.0, vmax=1.0, view="front"))
    s = img[_surface_mask(img)]
    red = np.mean(s[:, 0] - s[:, 2] > 0.2)  # bwr: 1 is red, 0 is blue
    blue = np.mean(s[:, 2] - s[:, 0] > 0.2)
    assert red > 0.9 and blue < 0.02, (red, blue)


def test_a_histogram_with_nothing_counted_asks_for_no_log_scale(tmp_path):
    """issue 41: every count zero (every cell touches a source) made matplotlib warn "Data has no positive values,
    and therefore cannot be log-scaled", which compare showed as a note."""
    import warnings

    edges = np.linspace(0.0, 2.0, 11)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        path = plot_gradient_histogram({"exact": (np.zeros(10), edges), "qclp": (np.zeros(10), edges)},
                                       tmp_path / "h.png")
    assert Image.open(path).size[0] > 100


def _level_error(segments: np.ndarray, levels: np.ndarray, origin: np.ndarray) -> float:
    """Largest distance of an isoline's points (segment ends and middles) from the nearest level's circle about
    ``origin``."""
    points = np.concatenate([segments.reshape(-1, 3), segments.mean(axis=1)])
    r = np.linalg.norm(points - origin, axis=1)
    return float(np.abs(r[:, None] - levels[None, :]).min(axis=1).max())


def test_an_order_2_field_is_drawn_with_its_curved_isolines():
    """An order-2 field is exact on a flat mesh (circles about the source); drawn from its vertex values alone its
    isolines are the chords of a coarse grid, drawn on the mesh split at its edge midpoints they follow the circles."""
    from cvxgeodesic import GeodesicSolver
    from cvxgeodesic.plotting import _surface_inputs

    mesh = grid_plane(4)
    res = GeodesicSolver(mesh, "qclp", order=2).solve(0)
    levels = np.linspace(0.4, 1.3, 7)  # away from the source, whose cone no piecewise-linear drawing follows
    drawn, values, *_ = _surface_inputs(mesh, res, "values", None, "x.png", 100, field=True)
    assert drawn.n_faces == 4 * mesh.n_faces and np.array_equal(drawn.V[: mesh.n_vertices], mesh.V)
    np.testing.assert_allclose(values, np.linalg.norm(drawn.V - mesh.V[0], axis=1), atol=1e-7)
    chords = _level_error(isoline_segments(mesh, res.distance, levels), levels, mesh.V[0])
    curved = _level_error(isoline_segments(drawn, values, levels), levels, mesh.V[0])
    assert chords > 0.02 and curved < 0.35 * chords, (chords, curved)  # 0.029 and 0.0071 when written
    # an order-1 field, an array, or a field on many faces are drawn as they are
    linear = GeodesicSolver(mesh, "qclp").solve(0)
    for given in (linear, res.distance):
        assert _surface_inputs(mesh, given, "values", None, "x.png", 100, field=True)[0] is mesh


def test_unreachable_midpoints_stay_unreachable():
    from cvxgeodesic import GeodesicSolver
    from cvxgeodesic.plotting import _surface_inputs

    grid = grid_plane(3)
    two = TriMesh(np.vstack([grid.V, grid.V + [5.0, 0, 0]]), np.vstack([grid.F, grid.F + grid.n_vertices]))
    res = GeodesicSolver(two, "qclp", order=2).solve(0)
    drawn, values, *_ = _surface_inputs(two, res, "values", None, "x.png", 100, field=True)
    far = drawn.V[:, 0] > 2.5
    assert drawn.n_faces == 4 * two.n_faces
    assert np.isinf(values[far]).all() and np.isfinite(values[~far]).all()
