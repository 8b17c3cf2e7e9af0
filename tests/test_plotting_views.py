"""The camera of the surface pictures (issue 41): the up axis, ``view=`` and its panels, the front view's search for
the source, and the command line's ``--view`` / ``--up``."""

from __future__ import annotations

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic.cli import main
from cvxgeodesic.errors import ParameterError
from cvxgeodesic.evaluation.camera import UP_NAMES, VIEW_NAMES, _camera, up_vector, view_list
from cvxgeodesic.mesh import TriMesh, icosphere
from cvxgeodesic.plotting import _panel_cameras, _surface, plot_field

X, Y, Z = np.eye(3)


def _standing(axes: tuple[int, int, int], semi: tuple[float, float, float], base: float = -0.6) -> TriMesh:
    """An ellipsoid with a flat base: semi-axes ``semi`` along the world axes ``axes`` (width, length, height), cut
    flat at ``base`` of its height: a model standing on its base, up along ``axes[2]``."""
    s = icosphere(3)
    V = np.zeros_like(s.V)
    for k, (ax, r) in enumerate(zip(axes, semi, strict=True)):
        V[:, ax] = r * s.V[:, k]
    h = axes[2]
    V[:, h] = np.maximum(V[:, h], base * semi[2])
    return TriMesh(V, s.F, name="standing")


def _pixels(path) -> np.ndarray:
    import matplotlib.image as mpimg

    return mpimg.imread(path)[..., :3]


def _surface_mask(img) -> np.ndarray:
    return ~np.all(img > 0.98, axis=2)


# ----------------------------------------------------------------------------------------------------------------------
# view= and up=
# ----------------------------------------------------------------------------------------------------------------------


def test_view_list_forms():
    assert view_list(None) == ["front", "back"]
    assert view_list("back") == ["back"]
    assert view_list((30, 45)) == [(30.0, 45.0)]
    assert view_list(np.array([30, 45])) == [(30.0, 45.0)]
    assert view_list(["front", (10, -20), "BACK"]) == ["front", (10.0, -20.0), "back"]
    for bad in ("side", (1, 2, 3), (np.nan, 0), ["front", (1,)], [], ["front"] * 5, 3):
        with pytest.raises(ParameterError, match="view"):
            view_list(bad)


def test_up_names_and_vectors():
    V = icosphere(1).V
    assert np.array_equal(up_vector(V, "-y"), -Y)
    assert np.array_equal(up_vector(V, "Z"), Z)
    assert np.allclose(up_vector(V, (0, 2, 0)), Y)
    for bad in ("w", (0, 0, 0), (1, 2), (np.inf, 0, 0), None):
        with pytest.raises(ParameterError, match="up"):
            up_vector(V, bad)


@pytest.mark.parametrize("axes, up", [
    ((0, 1, 2), Z),  # long along y, standing on z (a horse in a z-up file): the y convention alone tips it over
    ((2, 0, 1), Y),  # standing on y (a y-up scan)
    ((1, 2, 0), X),
])
def test_auto_up_stands_a_model_on_its_base(axes, up):
    mesh = _standing(axes, (0.4, 1.0, 0.8))
    assert np.array_equal(up_vector(mesh.V), up)
    upside_down = TriMesh(-mesh.V, mesh.F[:, ::-1])
    assert np.array_equal(up_vector(upside_down.V), -up)


def test_auto_up_without_a_base_is_y_unless_y_is_thinnest():
    s = icosphere(3)
    assert np.array_equal(up_vector(s.V * [1.0, 0.8, 0.5]), Y)  # an ellipsoid: no flat end to stand on
    assert np.array_equal(up_vector(s.V * [1.0, 0.3, 0.8]), Z)


# ----------------------------------------------------------------------------------------------------------------------
# the camera
# ----------------------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("elev", [-60.0, -10.0, 0.0, 25.0, 80.0])
@pytest.mark.parametrize("azim", [0.0, 70.0, 200.0])
def test_elev_azim_are_about_the_up_axis(elev, azim):
    V = _standing((2, 0, 1), (0.4, 1.0, 0.8)).V  # y-up
    e, a = np.radians(elev), np.radians(azim)
    R = _camera(V, (elev, azim))
    assert np.allclose(R @ R.T, np.eye(3)) and np.isclose(np.linalg.det(R), 1.0)
    # screen up is world y's projection: y never turns sideways; azim turns from +z towards +x about y
    assert np.isclose(R[1] @ Y, np.cos(e))
    assert np.isclose(R[0] @ Y, 0.0, atol=1e-12)
    assert np.allclose(R[2], [np.cos(e) * np.sin(a), np.sin(e), np.cos(e) * np.cos(a)])
    # up="z": matplotlib's mplot3d convention, as before
    Rz = _camera(V, (elev, azim), up="z")
    assert np.allclose(Rz[2], [np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
    assert np.isclose(Rz[1] @ Z, np.cos(e))


def test_y_up_model_is_drawn_upright_from_a_given_view(tmp_path):
    mesh = _standing((2, 0, 1), (0.4, 1.0, 0.8))  # y-up: its height is V[:, 1]
    kw = {"isolines": 0, "show_colorbar": False, "dpi": 40, "cmap": "bwr"}
    img = _pixels(plot_field(mesh, mesh.V[:, 1], tmp_path / "y.png", view=(20, 60), **kw))
    surf = _surface_mask(img)
    rows = np.flatnonzero(surf.any(axis=1))
    top, bottom = img[rows[:5]][surf[rows[:5]]], img[rows[-5:]][surf[rows[-5:]]]
    assert np.mean(top[:, 0] > top[:, 2]) > 0.9  # high y at the top of the picture: red
    assert np.mean(bottom[:, 2] > bottom[:, 0]) > 0.9  # low y at the bottom: blue


def test_default_views_face_the_source_and_the_opposite_side():
    mesh = _standing((2, 0, 1), (0.4, 1.0, 0.8))
    for s in (5, 100, 400):
        (front, cap_f), (back, cap_b) = _panel_cameras(_surface(mesh, mesh.V[:, 0], np.empty(0)), np.array([s]),
                                                       None, "auto")
        hf, hb = front[2] - (front[2] @ Y) * Y, back[2] - (back[2] @ Y) * Y  # horizontal parts of the view directions
        assert np.isclose(hf @ hb, -np.linalg.norm(hf) * np.linalg.norm(hb))  # opposite about up
        assert front[1] @ Y > 0 and back[1] @ Y > 0  # both upright
        side = mesh.V[s] - mesh.V.mean(axis=0)  # the source's side of the (convex) model
        assert front[2] @ side > 0 > back[2] @ side
        assert cap_f.startswith(f"facing source {s}: elev ") and cap_b.startswith("far side: elev ")
        assert cap_f.endswith("up +y")


def test_front_view_turns_until_nothing_hides_the_source():
    a, b = icosphere(2), icosphere(2)
    # sphere b in front of sphere a's vertex s, along s's normal: the straight view is blocked
    s = int(np.argmax(a.V[:, 0]))
    V = np.vstack([a.V, b.V + [3.0, 0.0, 0.0]])  # radius 1 at distance 2: it hides s from 15° above too
    mesh = TriMesh(V, np.vstack([a.F, b.F + a.n_vertices]))
    surf = _surface(mesh, V[:, 0], np.empty(0))
    from cvxgeodesic.plotting import _occluded

    assert _occluded(surf, s, X) and not _occluded(surf, s, Z)  # along its normal b hides it; from above nothing
    (R, _), = _panel_cameras(surf, np.array([s]), "front", "z")
    assert R[2] @ a.V[s] > 0.3  # still facing the source ...
    assert not _occluded(surf, s, R[2])  # ... from where it is seen


def test_default_png_has_two_panels_near_side_and_far_side(tmp_path):
    mesh = icosphere(3)
    d = np.arccos(np.clip(mesh.V @ mesh.V[0], -1.0, 1.0))
    img = _pixels(plot_field(mesh, d, tmp_path / "two.png", isolines=0, show_colorbar=False, dpi=40, cmap="bwr",
                             sources=0))
    surf = _surface_mask(img)
    half = img.shape[1] // 2
    cols = np.flatnonzero(surf.any(axis=0))
    assert cols.min() < half - 10 and cols.max() > half + 10 and not surf[:, half - 2: half + 2].any()  # two pictures
    left, right = img[:, :half][surf[:, :half]], img[:, half:][surf[:, half:]]
    # the front panel shows the source's side (small distances: blue), the back panel the far side (red)
    assert np.mean(left[:, 2] > left[:, 0]) > 0.9
    assert np.mean(right[:, 0] > right[:, 2]) > 0.9


# ----------------------------------------------------------------------------------------------------------------------
# the command line
# ----------------------------------------------------------------------------------------------------------------------


def test_cli_names_match_the_library():
    from cvxgeodesic.cli import _options

    assert _options.VIEW_NAMES == VIEW_NAMES and _options.UP_NAMES == UP_NAMES


@pytest.mark.parametrize("args, view, up", [
    ([], None, "auto"),
    (["--view", "front,back"], ["front", "back"], "auto"),
    (["--view", "30,45", "--view", "BACK", "--up=-y"], [(30.0, 45.0), "back"], "-y"),
    (["--view=-20,90", "--up", "0,0,2"], [(-20.0, 90.0)], (0.0, 0.0, 2.0)),
])
def test_cli_view_and_up_reach_the_picture(tmp_path, plot_field_calls, args, view, up):
    calls = plot_field_calls
    path = cg.save_distance(tmp_path / "in.ply", icosphere(1), np.zeros(42))
    rc = main(["distance", str(path), "-s", "3", "--method", "dijkstra", "-q", "-o", str(tmp_path / "d.ply"),
               "--png", str(tmp_path / "d.png"), *args])
    assert rc == 0 and (tmp_path / "d.png").is_file()
    assert calls[0]["view"] == view and calls[0]["up"] == up


@pytest.mark.parametrize("args, message", [
    (["--view", "sideways"], "--view 'sideways': expected front, back"),
    (["--view", "1,2,3"], "--view '1,2,3'"),
    (["--view", "front,30"], "--view 'front,30'"),
    (["--view", "nan,0"], "--view 'nan,0'"),
    (["--view", "front,back", "--view", "front,back", "--view", "back"], "--view: at most 4 views, got 5"),
    (["--up", "w"], "--up 'w': expected auto, x, y"),
    (["--up", "0,0,0"], "--up '0,0,0'"),
])
@pytest.mark.parametrize("command", ["distance", "path", "compare"])
def test_cli_bad_view_or_up_is_one_line_before_any_solve(tmp_path, capsys, monkeypatch, args, message, command):
    solved = []
    monkeypatch.setattr(cg.GeodesicSolver, "solve", lambda *a, **k: solved.append(1))
    path = cg.save_distance(tmp_path / "in.ply", icosphere(1), np.zeros(42))
    out = {"distance": ["-o", str(tmp_path / "d.ply"), "--png", str(tmp_path / "d.png")],
           "path": ["--to", "5", "-o", str(tmp_path / "p.csv"), "--png", str(tmp_path / "p.png")],
           "compare": ["--methods", "dijkstra", "--out", str(tmp_path)]}[command]
    rc = main([command, str(path), "-s", "0", "-q", *out, *args])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and err[0].startswith("cvxgeodesic: error: "), err
    assert message in err[0], err
    assert not solved and not list(tmp_path.glob("*.png"))


def test_compare_draws_the_views_it_is_given(tmp_path, plot_field_calls):
    calls = plot_field_calls
    mesh = icosphere(2)
    from cvxgeodesic.compare import run_compare

    run_compare(mesh, 0, ["dijkstra"], tmp_path, progress=False, view=(10, 20), up="z")
    assert calls and all(c["view"] == (10, 20) and c["up"] == "z" for c in calls)
    with pytest.raises(ParameterError, match="view"):
        run_compare(mesh, 0, ["dijkstra"], tmp_path / "x", progress=False, view="sideways")
