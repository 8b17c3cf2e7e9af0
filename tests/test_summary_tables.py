"""The evaluation record (cvxgeodesic.evaluation.summary) and the table formatter (cvxgeodesic.tables)."""

from __future__ import annotations

import numpy as np
import pytest

from cvxgeodesic.api import GeodesicSolver
from cvxgeodesic.evaluation import error_stats, gradient_norm_stats, smoothness_report
from cvxgeodesic.evaluation.summary import SUMMARY_KEYS, summarize, summarize_field, summarize_run
from cvxgeodesic.mesh import grid_plane, icosphere
from cvxgeodesic.tables import Column, format_markdown, markdown_table, text_table


@pytest.fixture(scope="module")
def sphere_fields():
    mesh = icosphere(2)
    exact = GeodesicSolver(mesh, "exact").solve(0)
    heat = GeodesicSolver(mesh, "heat").solve(0)
    return mesh, exact, heat


# ----------------------------------------------------------------------------------------------------------------------
# summary
# ----------------------------------------------------------------------------------------------------------------------


def test_field_summary_is_the_evaluation_functions_numbers(sphere_fields):
    mesh, exact, heat = sphere_fields
    rec = summarize_field(mesh, heat.distance, exact.distance, [0])
    st = error_stats(heat.distance, exact.distance, [0])
    sm = smoothness_report(mesh, heat.distance, exact.distance, [0])
    g = gradient_norm_stats(mesh, heat.distance, sources=[0])
    for k in ("rel_mean", "rel_max", "rel_p99", "abs_max", "n_compared", "n_nonfinite"):
        assert rec[k] == st[k], k
    for k in ("ridge_jump_p95", "ridge_jump_ratio", "exact_ridge_jump_p95", "off_ridge_rel_mean",
              "on_ridge_rel_mean", "band_vertices"):
        assert rec[k] == sm[k], k
    assert (rec["grad_mean"], rec["grad_max"], rec["grad_unit_share"]) == (g["mean"], g["max"], g["share_0.9_1.1"])
    assert all(type(v) in (int, float) for v in rec.values())  # JSON- and CSV-ready
    light = summarize_field(mesh, heat.distance, exact.distance, [0], smoothness=False, gradient=False)
    assert light["ridge_jump_p95"] is None and light["grad_mean"] is None and light["rel_mean"] == st["rel_mean"]


def test_area_weighted_error_weights_by_vertex_area():
    mesh = grid_plane(6, jitter=0.3, seed=1)  # uneven vertex areas
    d_exact = np.linalg.norm(mesh.V - mesh.V[0], axis=1)
    rng = np.random.default_rng(0)
    e = rng.uniform(0.0, 0.2, mesh.n_vertices)
    d = d_exact * (1.0 + e)
    w = np.zeros(mesh.n_vertices)
    for f, a in zip(mesh.F, mesh.face_areas, strict=True):
        w[f] += a / 3.0
    keep = np.arange(mesh.n_vertices) != 0
    rec = summarize_field(mesh, d, d_exact, [0], smoothness=False, gradient=False)
    assert rec["area_rel_mean"] == pytest.approx(np.sum(w[keep] * e[keep]) / np.sum(w[keep]), rel=1e-12)
    assert rec["rel_mean"] == pytest.approx(e[keep].mean(), rel=1e-12)
    assert abs(rec["area_rel_mean"] - rec["rel_mean"]) > 1e-4  # the weights matter on this mesh
    d[5] = np.inf  # a reachable vertex left unreached counts as an infinite error
    assert summarize_field(mesh, d, d_exact, [0], smoothness=False, gradient=False)["area_rel_mean"] == np.inf


def test_summarize_result_record(sphere_fields):
    mesh, exact, heat = sphere_fields
    rec = summarize(mesh, heat, exact.distance, smoothness=False)
    assert tuple(rec) == SUMMARY_KEYS
    info = heat.info
    assert rec["method"] == "heat" and rec["solver"] == info.solver and rec["status"] == info.status
    assert rec["time_s"] == info.setup_time + info.solve_time and rec["iterations"] == info.iterations
    assert rec["notes"] == list(info.notes)
    assert summarize_run(info, time_s=2.5)["time_s"] == 2.5
    own = summarize(mesh, exact, exact.distance)
    assert own["rel_max"] == 0.0 and own["ridge_jump_ratio"] == pytest.approx(1.0)


def test_summary_names_the_bad_argument(sphere_fields):
    mesh, exact, heat = sphere_fields
    with pytest.raises(ValueError, match=r"\bd\b"):
        summarize_field(mesh, heat.distance[:-1], exact.distance, [0])
    with pytest.raises(ValueError, match="sources"):
        summarize_field(mesh, heat.distance, exact.distance, [mesh.n_vertices])


# ----------------------------------------------------------------------------------------------------------------------
# tables
# ----------------------------------------------------------------------------------------------------------------------

COLS = (
    Column("name", "name", align="left"),
    Column("value %", "v", lambda x: f"{100 * x:.1f}"),
    Column("note", "note", align="left", max_len=8),
)
ROWS = [{"name": "a", "v": 0.5, "note": "short"}, {"name": "longer", "v": None, "note": "a very long note"},
        {"name": "c", "v": "n/a", "note": ""}]


def test_text_table_layout():
    text = text_table(ROWS, COLS)
    assert text.splitlines() == [
        "name    value %  note",
        "------  -------  --------",
        "a          50.0  short",
        "longer        -  a very …",
        "c           n/a  -",  # a value the format cannot take is shown as it is; '' is missing
    ]


def test_markdown_table():
    assert markdown_table(["a", "b", "c"], [[1, "x", 2.5]], "lcr") == (
        "| a | b | c |\n| --- | :---: | ---: |\n| 1 | x | 2.5 |")
    assert markdown_table(["a", "b"], []).splitlines()[1] == "| --- | ---: |"
    assert format_markdown(ROWS[:1], COLS) == "| name | value % | note |\n| --- | ---: | --- |\n| a | 50.0 | short |"
    with pytest.raises(ValueError, match="align"):
        markdown_table(["a", "b"], [], "l")


def test_column_checks_its_arguments():
    with pytest.raises(ValueError, match="align"):
        Column("x", "x", align="middle")
    with pytest.raises(ValueError, match="max_len"):
        Column("x", "x", max_len=0)
