"""Issue 42, "one field": the outputs (pictures, files, the viewer) take a result or its field as well as vertex
values, and a slice of a tetrahedral mesh asks the field at its cut points."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic import capabilities
from cvxgeodesic.errors import ParameterError
from cvxgeodesic.evaluation import slice_plot
from cvxgeodesic.mesh.tet_slice import slice_tets
from cvxgeodesic.operators.linear_field import LinearField
from cvxgeodesic.results import Field
from cvxgeodesic.validation import as_field

# an oblique plane through the box's inside, cutting edges at generic points
ORIGIN, NORMAL = [0.5, 0.5, 0.37], [0.3, 0.2, 1.0]


@pytest.fixture(scope="module")
def box_order2():
    """An order-2 solve on a tetrahedral box from its corner vertex: the field is exact (|x − V[s]|) on a flat mesh."""
    mesh = cg.tet_box(4)
    s = int(np.argmin(np.linalg.norm(mesh.V, axis=1)))
    return mesh, s, cg.GeodesicSolver(mesh, "qclp", order=2).solve(s)


@pytest.fixture(scope="module")
def sphere_result():
    mesh = cg.icosphere(2)
    return mesh, cg.GeodesicSolver(mesh, "dijkstra").solve(0)


# -- the one helper ------------------------------------------------------------------------------------------------
def test_as_field_reads_arrays_results_and_fields(box_order2):
    mesh, s, res = box_order2
    n = mesh.n_vertices
    values, field = as_field(res, "values", n)
    np.testing.assert_array_equal(values, res.distance)  # the result's distance (0 at the source vertex)
    assert field is res.field and values[s] == 0.0
    edited = dataclasses.replace(res, distance=2 * res.distance)  # the result's own array, not its field's values
    np.testing.assert_array_equal(as_field(edited, "values", n)[0], 2 * res.distance)
    values, field = as_field(res.field, "values", n)
    np.testing.assert_array_equal(values, res.field.vertex_distance)
    assert field is res.field
    values, field = as_field(list(res.distance), "values", n)
    np.testing.assert_array_equal(values, res.distance)
    assert field is None
    with pytest.raises(ParameterError, match=r"values must have shape \(3,\)"):
        as_field(res.distance, "values", 3)


def test_a_field_of_another_mesh_is_refused_naming_both_counts(tmp_path, box_order2, sphere_result):
    _, _, res = box_order2  # 125 vertices
    sphere, _ = sphere_result  # 162 vertices
    message = r"distance is a field on a mesh of 125 vertices, not on this mesh of 162 vertices"
    with pytest.raises(ParameterError, match=message):
        cg.save_distance(tmp_path / "d.npy", sphere, res)
    with pytest.raises(ParameterError, match=message):
        cg.save_distance(tmp_path / "d.npy", sphere, res.field)
    with pytest.raises(ParameterError, match=message.replace("distance", "values")):
        cg.plot_field(sphere, res, tmp_path / "f.png")
    with pytest.raises(ParameterError, match=message):
        cg.show(sphere, res, screenshot=tmp_path / "v.png")  # refused before polyscope starts
    assert not list(tmp_path.iterdir())


# -- the slice asks the field ------------------------------------------------------------------------------------
def test_an_order2_slice_has_the_fields_values(box_order2):
    mesh, s, res = box_order2
    by_field = slice_tets(mesh, res, origin=ORIGIN, normal=NORMAL)
    linear = slice_tets(mesh, res.distance, origin=ORIGIN, normal=NORMAL)
    np.testing.assert_array_equal(by_field.points, linear.points)
    exact = np.linalg.norm(by_field.points - mesh.V[s], axis=1)
    # order 2 is exact on a flat mesh (measured 9.5e-9 of the maximum); the vertex values interpolated linearly
    # along the cut edges are not (1.2e-2)
    assert np.abs(by_field.values - exact).max() <= 1e-6 * exact.max()
    assert np.abs(linear.values - exact).max() >= 1e-3 * exact.max()
    np.testing.assert_array_equal(slice_tets(mesh, res.field, origin=ORIGIN, normal=NORMAL).values, by_field.values)
    # an order-1 field through the same road equals the linear interpolation
    p1 = slice_tets(mesh, LinearField(mesh, res.distance), origin=ORIGIN, normal=NORMAL)
    np.testing.assert_allclose(p1.values, linear.values, rtol=1e-14, atol=1e-15)


def test_a_slice_refuses_a_field_of_other_tetrahedra(box_order2):
    mesh, _, res = box_order2
    other = cg.TetMesh(mesh.V, mesh.T[::-1])  # the same vertices, the cells numbered otherwise
    with pytest.raises(ParameterError, match="other tetrahedra"):
        slice_tets(other, res, origin=ORIGIN, normal=NORMAL)
    slice_tets(other, res.distance, origin=ORIGIN, normal=NORMAL)  # vertex values fit any cells


def _spy_slices(monkeypatch) -> list:
    cuts = []

    def spy(*args, **kwargs):
        cuts.append(slice_tets(*args, **kwargs))
        return cuts[-1]

    monkeypatch.setattr(slice_plot, "slice_tets", spy)
    return cuts


def test_the_pictures_of_a_volume_draw_the_fields_values(monkeypatch, tmp_path, box_order2):
    mesh, s, res = box_order2
    cuts = _spy_slices(monkeypatch)
    slice_plot.plot_slice(mesh, res, tmp_path / "a.png", origin=ORIGIN, normal=NORMAL, dpi=20)
    slice_plot.draw_field(mesh, res, tmp_path / "b.png", title="t", sources=[s], normal=NORMAL)
    from cvxgeodesic.cli.distance import draw_field as cli_draw  # what `cvxgeodesic distance --png` draws

    cli_draw(mesh, res, tmp_path / "c.png", title="t", normal=(0.3, 0.2, 1.0))
    assert len(cuts) == 3
    for cut in cuts:
        exact = np.linalg.norm(cut.points - mesh.V[s], axis=1)
        assert np.abs(cut.values - exact).max() <= 1e-6 * exact.max()
    assert all((tmp_path / f"{k}.png").stat().st_size > 1000 for k in "abc")


def test_compare_draws_each_result_with_its_field(monkeypatch, tmp_path):
    from cvxgeodesic.compare import run_compare

    mesh = cg.tet_box(4)
    s = int(np.argmin(np.linalg.norm(mesh.V, axis=1)))
    drawn = []
    monkeypatch.setattr(slice_plot, "draw_field", lambda mesh, values, path, **kw: drawn.append((path.name, values)))
    run_compare(mesh, s, ["qclp"], tmp_path, progress=False)  # in a volume the reference is qclp at order 2
    fields = {name: v for name, v in drawn if name.startswith("field_")}
    assert sorted(fields) == ["field_qclp.png", "field_qclp_order2.png"]
    assert all(isinstance(v, cg.GeodesicResult) for v in fields.values())
    assert fields["field_qclp_order2.png"].info.extra["order"] == 2


# -- surfaces, files, the viewer: the vertex values --------------------------------------------------------------
def test_plot_field_of_a_result_is_the_picture_of_its_distance(tmp_path, sphere_result):
    mesh, res = sphere_result
    for name, values in (("array", res.distance), ("result", res), ("field", res.field)):
        cg.plot_field(mesh, values, tmp_path / f"{name}.png", sources=[0], dpi=30)
    data = {p.stem: p.read_bytes() for p in tmp_path.glob("*.png")}
    assert data["result"] == data["array"] == data["field"]


def test_save_distance_writes_a_results_distance(tmp_path, box_order2, sphere_result):
    mesh, res = sphere_result
    back = cg.load_distance(cg.save_distance(tmp_path / "s.ply", mesh, res))
    np.testing.assert_array_equal(back, res.distance)
    tets, s, res2 = box_order2
    back = cg.load_distance(cg.save_distance(tmp_path / "t.npy", tets, res2))
    np.testing.assert_array_equal(back, res2.distance)
    back = cg.load_distance(cg.save_distance(tmp_path / "f.npy", tets, res2.field))
    np.testing.assert_array_equal(back, res2.field.vertex_distance)


def test_show_takes_a_result(tmp_path, sphere_result):
    pytest.importorskip("polyscope", exc_type=ImportError)
    from tests.test_viewer import _egl_works  # the same off-screen check as the viewer's tests

    if not _egl_works(tmp_path):
        pytest.skip("no off-screen OpenGL context (EGL/Mesa missing)")
    mesh, res = sphere_result
    shown = cg.show(mesh, res, screenshot=tmp_path / "v.png", window_size=(200, 150))
    np.testing.assert_array_equal(shown, res.distance)


# -- the package and the command line ------------------------------------------------------------------------------
def test_field_is_public():
    assert cg.Field is Field and "Field" in cg.__all__
    res = cg.GeodesicSolver(cg.grid_plane(3), "dijkstra").solve(0)
    assert isinstance(res.field, cg.Field) and not isinstance(res.distance, cg.Field)


def _order_choices(parser) -> dict[str, tuple]:
    """{command: the choices of its --order} over the command line's sub-commands."""
    import argparse

    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    out = {}
    for name, p in sub.choices.items():
        for a in p._actions:
            if "--order" in a.option_strings:
                out[name] = tuple(a.choices)
    return out


def test_the_command_lines_orders_are_the_capability_tables(monkeypatch):
    from cvxgeodesic.cli import build_parser

    choices = _order_choices(build_parser())
    assert "distance" in choices and all(c == tuple(capabilities.ORDERS) for c in choices.values()), choices
    monkeypatch.setattr(capabilities, "ORDERS", (1, 2, 3))  # an order added to the table: every --order takes it
    assert set(_order_choices(build_parser()).values()) == {(1, 2, 3)}
