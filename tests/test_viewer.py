"""Issue 16, item 8: the polyscope viewer (cg.show, cvxgeodesic view), tested off-screen on pixels.

The rendering tests need polyscope (the ``viewer`` extra) and an off-screen OpenGL context (EGL with
Mesa: libegl1 libegl-mesa0 libgl1-mesa-dri, installed by ``make``); they skip when either is missing.
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic.errors import ParameterError

W, H = 400, 300


def _egl_works(folder) -> bool:
    # in a subprocess (a failed polyscope.init can abort the interpreter) run in a scratch folder, where
    # Dear ImGui saves its imgui.ini at exit
    code = "import polyscope as ps; ps.set_allow_headless_backends(True); ps.init('openGL3_egl')"
    try:
        res = subprocess.run([sys.executable, "-c", code], capture_output=True, timeout=60, cwd=folder)
    except (OSError, subprocess.TimeoutExpired):
        return False
    return res.returncode == 0


@pytest.fixture(scope="module")
def gl(tmp_path_factory):
    pytest.importorskip("polyscope", reason="polyscope not installed (pip install 'cvxgeodesic[viewer]')",
                        exc_type=ImportError)
    if not _egl_works(tmp_path_factory.mktemp("egl")):
        pytest.skip("no off-screen OpenGL context (EGL/Mesa missing)")


@pytest.fixture(scope="module")
def sphere():
    return cg.icosphere(3)


def _front_vertex(mesh) -> int:
    # polyscope's home view looks down the -z axis: the vertex of largest z faces the camera
    return int(np.argmax(mesh.V[:, 2]))


def _render(tmp_path, name, *args, **kw) -> np.ndarray:
    import matplotlib.image as mpimg

    path = tmp_path / name
    cg.show(*args, screenshot=path, window_size=(W, H), **kw)
    img = mpimg.imread(path)[..., :3]  # (H, W, 3) float in [0, 1]
    assert img.shape == (H, W, 3)
    return img


def _surface(img):
    return np.abs(img - 1.0).sum(axis=-1) > 0.05  # background is white


def _dark(img):
    return img.sum(axis=-1) < 0.45


def _red(img):
    return (img[..., 0] > 0.6) & (img[..., 1] < 0.25) & (img[..., 2] < 0.25)


def test_screenshot_shows_field_isolines_and_sources(gl, sphere, tmp_path):
    s = _front_vertex(sphere)
    d = cg.geodesic_distance(sphere, s, method="fmm")
    on = _render(tmp_path, "on.png", sphere, d, sources=[s])
    off = _render(tmp_path, "off.png", sphere, d, sources=[s], isolines=False)
    surf = _surface(off)
    assert surf.mean() > 0.3  # the sphere fills ~half of the frame
    assert (surf != _surface(on)).sum() < 0.01 * surf.sum()  # the same view (isoline tubes touch the rim)
    # the field is drawn in colour (a grey, shaded surface has r = g = b) ...
    colours = off[surf]
    assert np.median(colours.max(axis=1) - colours.min(axis=1)) > 0.1
    # ... and it follows the distance: the source faces the camera, so the distance grows with the radius
    # in the image; viridis goes from purple (more red) near the source to teal (less red) farther out
    ys, xs = np.nonzero(surf)
    R = np.sqrt(surf.sum() / np.pi)
    r = np.hypot(*np.meshgrid(np.arange(W) - xs.mean(), np.arange(H) - ys.mean())) / R
    chroma = off / np.maximum(off.sum(axis=-1, keepdims=True), 1e-6)  # colour without the shading's brightness
    near, far = chroma[surf & (r > 0.2) & (r < 0.4)].mean(axis=0), chroma[surf & (r > 0.75) & (r < 0.95)].mean(axis=0)
    assert near[0] > far[0] + 0.04 and far[1] > near[1] + 0.04
    # isolines: thin dark lines, only when switched on: pixels much darker than without them, a few percent
    # of the surface (20 isolines of a few pixels; polyscope's own isoline bands would cover a third)
    line = (off - on).sum(axis=-1) > 0.3
    assert 0.02 < line[surf].mean() < 0.15
    assert on[line].sum(axis=-1).mean() < 1.0 and not _dark(off)[surf].any()
    # the source: a red mark where the centre of the view is (viridis has no red)
    red = _red(on)
    assert 10 < red.sum() < 0.05 * surf.sum()
    ys, xs = np.nonzero(red)
    assert abs(xs.mean() - W / 2) < 0.1 * W and abs(ys.mean() - H / 2) < 0.1 * H
    # no sources: marks at the zeros of the field (the same vertex)
    assert _red(_render(tmp_path, "zeros.png", sphere, d)).sum() > 10


def test_show_solves_and_returns_the_field(gl, sphere, tmp_path):
    s = _front_vertex(sphere)
    d = cg.show(sphere, sources=s, method="fmm", screenshot=tmp_path / "x.png", window_size=(W, H))
    np.testing.assert_array_equal(d, cg.geodesic_distance(sphere, s, method="fmm"))


def test_a_pick_resolves_from_the_picked_vertex(gl, sphere, tmp_path):
    import polyscope as ps

    from cvxgeodesic.viewer import _Viewer

    cg.show(sphere, sources=0, method="fmm", screenshot=tmp_path / "x.png", window_size=(W, H))
    v = _Viewer(ps, sphere, method="fmm", solver_kwargs={}, isolines=True)
    v.solve([0])
    ps.screenshot_to_buffer()  # a rendered frame to pick from
    hit = ps.pick(screen_coords=(W // 2, H // 2))
    assert v.pick(hit)
    i = hit.structure_data["index"]
    assert i == _front_vertex(sphere) or np.linalg.norm(sphere.V[i] - sphere.V[_front_vertex(sphere)]) < 0.2
    np.testing.assert_allclose(v.distance, cg.geodesic_distance(sphere, i, method="fmm"), atol=1e-12)
    assert not v.pick(ps.pick(screen_coords=(2, 2)))  # background: nothing re-solved
    np.testing.assert_allclose(v.distance, cg.geodesic_distance(sphere, i, method="fmm"), atol=1e-12)


def test_the_user_callback_runs_in_a_frame(gl, sphere, tmp_path):
    # a frame without a click leaves the field; what a click selects is ps.get_selection(), which only
    # a real mouse sets (polyscope has no set_selection), so the click path is tested through pick() above
    import polyscope as ps

    from cvxgeodesic.viewer import _Viewer

    cg.show(sphere, sources=0, method="fmm", screenshot=tmp_path / "x.png", window_size=(W, H))
    v = _Viewer(ps, sphere, method="fmm", solver_kwargs={}, isolines=True)
    before = v.solve([0]).copy()
    ps.set_user_callback(v.callback)
    try:
        ps.frame_tick()
    finally:
        ps.clear_user_callback()
    assert not ps.have_selection()
    np.testing.assert_array_equal(v.distance, before)
    assert v.message.startswith("fmm: sources [0]")


def test_no_window_once_polyscope_runs_off_screen(gl, sphere, tmp_path, monkeypatch):
    cg.show(sphere, sources=0, method="fmm", screenshot=tmp_path / "x.png", window_size=(W, H))
    monkeypatch.setenv("DISPLAY", ":99")
    with pytest.raises(ParameterError, match="off-screen in this process"):
        cg.show(sphere, np.zeros(sphere.n_vertices))


def test_cli_view_screenshot(gl, sphere, tmp_path):
    import matplotlib.image as mpimg

    from cvxgeodesic.cli import main

    # file vertex 0 is in no face (load_mesh drops it): file vertex i + 1 is mesh vertex i, and -s is a file index
    obj = tmp_path / "sphere.obj"
    obj.write_text("v 9 9 9\n" + "".join(f"v {x} {y} {z}\n" for x, y, z in sphere.V)
                   + "".join(f"f {a + 2} {b + 2} {c + 2}\n" for a, b, c in sphere.F))
    out = tmp_path / "view.png"
    argv = ["view", str(obj), "--method", "fmm", "--screenshot", str(out), "-q"]
    assert main([*argv, "-s", str(_front_vertex(sphere) + 1)]) == 0
    red = _red(mpimg.imread(out)[..., :3])
    ys, xs = np.nonzero(red)
    assert red.sum() > 10 and abs(xs.mean() - 512) < 100 and abs(ys.mean() - 384) < 100  # default 1024 x 768
    assert main([*argv, "-s", "0"]) == 2  # the dropped vertex: a one-line error
    assert main(argv) == 0  # no source: the first vertex


def test_show_is_exported_lazily():
    from cvxgeodesic import viewer

    assert cg.show is viewer.show and "show" in cg.__all__


def test_missing_polyscope_names_the_extra(monkeypatch):
    from cvxgeodesic import viewer

    monkeypatch.setitem(sys.modules, "polyscope", None)  # import polyscope now raises ImportError
    with pytest.raises(ImportError, match=r"cvxgeodesic\[viewer\]"):
        viewer._polyscope()


def test_bad_arguments_are_named(sphere, monkeypatch, tmp_path):
    with pytest.raises(ParameterError, match="distance must have shape"):
        cg.show(sphere, np.zeros(3), screenshot=tmp_path / "x.png")
    with pytest.raises(ParameterError, match="window_size"):
        cg.show(sphere, np.zeros(sphere.n_vertices), screenshot=tmp_path / "x.png", window_size=(0, 0))
    with pytest.raises(ParameterError, match=r"\.png"):
        cg.show(sphere, np.zeros(sphere.n_vertices), screenshot=tmp_path / "x.jpg")
    with pytest.raises(ParameterError, match="does not exist"):
        cg.show(sphere, np.zeros(sphere.n_vertices), screenshot=tmp_path / "no" / "x.png")
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    with pytest.raises(ParameterError, match="no display"):
        cg.show(sphere, np.zeros(sphere.n_vertices))


def test_show_volume_refuses_a_surface_and_a_zero_normal(sphere, tmp_path):
    from cvxgeodesic.mesh.tet_generate import tet_box
    from cvxgeodesic.viewer import show_volume

    # both checked before polyscope is imported or started: no OpenGL needed
    with pytest.raises(ParameterError, match="takes a tetrahedral mesh"):
        show_volume(sphere, screenshot=tmp_path / "x.png")
    with pytest.raises(ParameterError, match=r"normal must be a nonzero vector, got \[0.0, 0.0, 0.0\]"):
        show_volume(tet_box(2), np.zeros(27), normal=(0, 0, 0), screenshot=tmp_path / "x.png")


def test_cli_view_hands_a_solid_to_show_volume_with_its_slice_normal(sphere, tmp_path, monkeypatch):
    """issue 42: ``view`` calls ``show`` on every mesh; ``show`` hands a mesh drawn by a slice
    (``mesh.reference.picture``) to ``show_volume`` with ``--slice-normal``, and draws a surface itself. No OpenGL:
    both ends are replaced by recorders."""
    import cvxgeodesic.viewer as viewer
    from cvxgeodesic.cli import main
    from cvxgeodesic.mesh.tet_generate import tet_box

    calls = []

    def volume(mesh, distance=None, **kw):
        calls.append(("volume", mesh.n_cells, kw["normal"], kw["method"]))
        return np.zeros(mesh.n_vertices)

    def start(*args):
        calls.append(("surface",))
        raise ParameterError("stopped before polyscope")

    monkeypatch.setattr(viewer, "show_volume", volume)
    monkeypatch.setattr(viewer, "_start", start)
    box = tet_box(2)
    (tmp_path / "box.node").write_text(f"{box.n_vertices} 3 0 0\n" + "".join(
        f"{i} {x!r} {y!r} {z!r}\n" for i, (x, y, z) in enumerate(box.V.tolist())))
    (tmp_path / "box.ele").write_text(f"{box.n_tets} 4 0\n" + "".join(
        f"{i} {' '.join(map(str, t))}\n" for i, t in enumerate(box.T.tolist())))
    out = str(tmp_path / "v.png")
    assert main(["view", str(tmp_path / "box.ele"), "--slice-normal", "1,0,0", "--screenshot", out, "-q"]) == 0
    assert calls == [("volume", box.n_tets, (1.0, 0.0, 0.0), "qclp")]
    obj = tmp_path / "sphere.obj"
    obj.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in sphere.V)
                   + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in sphere.F))
    assert main(["view", str(obj), "--slice-normal", "1,0,0", "--screenshot", out, "-q"]) == 2
    assert calls[1:] == [("surface",)]


def test_show_draws_a_solid_by_its_slice_with_the_normal_given(gl, tmp_path):
    """``cg.show`` on a tetrahedral mesh renders ``show_volume``'s cut, turned by ``normal`` (issue 42: the mesh's
    reference says it is drawn by a slice)."""
    from cvxgeodesic.mesh.tet_generate import tet_box

    box = tet_box(3)
    along_x = _render(tmp_path, "x.png", box, sources=0, normal=(1.0, 0.0, 0.0))
    along_z = _render(tmp_path, "z.png", box, sources=0, normal=(0.0, 0.0, 1.0))
    assert _surface(along_x).mean() > 0.05 and _surface(along_z).mean() > 0.05
    assert np.abs(along_x - along_z).sum(axis=-1).mean() > 0.01  # another cut, seen from another side


# -- point clouds (issue 44): drawn as polyscope point clouds -----------------------------------------------------


class _Structure:
    """What the viewer calls on a polyscope structure, recorded."""

    def __init__(self, kind, name, points):
        self.kind, self.name, self.points, self.quantities, self.radius = kind, name, np.asarray(points), {}, None

    def add_scalar_quantity(self, name, values, **kw):
        self.quantities[name] = np.asarray(values)

    def set_radius(self, radius, relative=True):
        self.radius = radius

    def set_selection_mode(self, mode):
        pass


class _FakePolyscope:
    """The polyscope calls of ``_Viewer`` and ``_add_marks``, recorded (no OpenGL)."""

    def __init__(self):
        self.structures = []

    def _add(self, kind, name, points):
        self.structures.append(_Structure(kind, name, points))
        return self.structures[-1]

    def register_point_cloud(self, name, points, **kw):
        return self._add("point cloud", name, points)

    def register_surface_mesh(self, name, V, F, **kw):
        return self._add("surface mesh", name, V)

    def register_curve_network(self, name, nodes, edges, **kw):
        return self._add("curve network", name, nodes)

    def has_curve_network(self, name):
        return False


@pytest.fixture()
def fake_ps(monkeypatch):
    import cvxgeodesic.viewer as viewer

    ps = _FakePolyscope()
    monkeypatch.setattr(viewer, "_start", lambda *args: ps)
    monkeypatch.setattr(viewer, "_present", lambda *args, **kw: None)
    return ps


def _sphere_cloud(n=600):
    X = np.random.default_rng(3).normal(size=(n, 3))
    return cg.PointCloud(X / np.linalg.norm(X, axis=1)[:, None])


def test_a_cloud_is_shown_as_its_points_coloured_by_the_field(fake_ps, tmp_path):
    cloud = _sphere_cloud()
    d = cg.show(cloud, sources=5, screenshot=tmp_path / "x.png")  # the cloud's default method: qclp
    np.testing.assert_allclose(d, cg.geodesic_distance(cloud, 5, method="qclp"), rtol=1e-6, atol=1e-9)
    kinds = [(s.kind, s.name) for s in fake_ps.structures]
    assert ("point cloud", "points") in kinds and ("surface mesh", "surface") not in kinds
    (points,) = [s for s in fake_ps.structures if s.name == "points"]
    np.testing.assert_array_equal(points.points, cloud.P)
    np.testing.assert_array_equal(points.quantities["geodesic distance"], d)
    assert 0 < points.radius < 0.2  # about the spacing of 600 points on the unit sphere, not the scene's scale
    marks = [s for s in fake_ps.structures if s.name == "sources"]
    np.testing.assert_array_equal(marks[-1].points, cloud.P[[5]])
    fake_ps.structures.clear()
    cg.show(cg.icosphere(1), np.zeros(42), screenshot=tmp_path / "x.png")  # a surface is still its triangles
    assert [s.kind for s in fake_ps.structures][0] == "surface mesh"


def test_cli_view_takes_a_point_file(fake_ps, tmp_path):
    from cvxgeodesic.cli import main

    cloud = _sphere_cloud()
    np.savetxt(tmp_path / "c.xyz", cloud.P)
    assert main(["view", str(tmp_path / "c.xyz"), "-s", "3", "--screenshot", str(tmp_path / "v.png"), "-q"]) == 0
    (points,) = [s for s in fake_ps.structures if s.kind == "point cloud" and s.name == "points"]
    np.testing.assert_allclose(points.quantities["geodesic distance"], cg.geodesic_distance(cloud, 3, method="qclp"),
                               rtol=1e-6, atol=1e-9)


def test_a_picked_point_of_a_cloud_resolves_from_it(fake_ps):
    from types import SimpleNamespace

    from cvxgeodesic.viewer import _Viewer

    cloud = _sphere_cloud()
    v = _Viewer(fake_ps, cloud.mesh, method="dijkstra", solver_kwargs={}, isolines=True)
    v.solve([0])
    # polyscope's pick of a point cloud: the structure's name and the point's index, no element type
    assert v.pick(SimpleNamespace(is_hit=True, structure_name="points", structure_data={"index": 17}))
    np.testing.assert_array_equal(v.distance, cg.geodesic_distance(cloud, 17, method="dijkstra"))
    assert not v.pick(SimpleNamespace(is_hit=True, structure_name="sources", structure_data={"index": 0}))


def test_screenshot_of_a_cloud_shows_coloured_points(gl, tmp_path):
    cloud = _sphere_cloud(2000)
    front = int(np.argmax(cloud.P[:, 2]))
    img = _render(tmp_path, "cloud.png", cloud, sources=front, method="dijkstra", isolines=False)
    surf = _surface(img)
    assert surf.mean() > 0.2  # the points cover the sphere's disc (a tenth of the diagonal would not)
    colours = img[surf & ~_red(img)]
    assert np.median(colours.max(axis=1) - colours.min(axis=1)) > 0.1  # coloured by the field, not grey
    red = _red(img)
    ys, xs = np.nonzero(red)
    assert red.sum() > 10 and abs(xs.mean() - W / 2) < 0.1 * W and abs(ys.mean() - H / 2) < 0.1 * H
