"""Tests of cvxgeodesic.compare (the engine of ``cvxgeodesic compare``) on small generated meshes."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest
from PIL import Image

from cvxgeodesic.api import ALL_METHODS, GeodesicSolver
from cvxgeodesic.compare import CSV_COLUMNS, format_table, resolve_methods, run_compare
from cvxgeodesic.errors import ParameterError, SolverError, SourceError
from cvxgeodesic.mesh import TriMesh, grid_plane, icosphere

METHODS = ["exact", "dijkstra", "heat", "qclp"]


def _read_csv(path):
    with open(path, newline="", encoding="utf-8") as fh:
        reader = csv.DictReader(fh)
        return reader.fieldnames, list(reader)


def _valid_png(path) -> bool:
    with Image.open(path) as im:
        im.verify()
    with Image.open(path) as im:
        im.load()
        return im.size[0] > 100 and im.size[1] > 100


@pytest.fixture(scope="module")
def sphere_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("cmp")
    mesh = icosphere(2)
    rows = run_compare(mesh, 0, METHODS, out, progress=False)
    return mesh, out, rows


def test_every_promised_file_exists(sphere_run):
    _, out, _ = sphere_run
    expected = {"compare.csv", "gradient_histogram.png"}
    expected |= {f"field_{m}.png" for m in METHODS} | {f"error_{m}.png" for m in METHODS}
    assert {p.name for p in out.iterdir()} == expected  # and no temporary files left
    for name in expected - {"compare.csv"}:
        assert _valid_png(out / name), name


def test_csv_columns_rows_and_values(sphere_run):
    _, out, rows = sphere_run
    header, records = _read_csv(out / "compare.csv")
    assert header == list(CSV_COLUMNS)
    for col in ("method", "time_s", "setup_s", "iterations", "rel_mean", "rel_max", "rel_p99", "abs_max",
                "off_ridge_rel_mean", "status"):
        assert col in header
    assert [r["method"] for r in records] == METHODS
    assert [r["method"] for r in rows] == METHODS
    by = {r["method"]: r for r in records}
    for m in METHODS:
        assert by[m]["status"] in ("optimal", "almost_optimal"), by[m]["status"]
        for col in ("time_s", "setup_s", "rel_mean", "rel_max", "rel_p99", "abs_max", "ridge_jump_p95",
                    "off_ridge_rel_mean"):
            assert math.isfinite(float(by[m][col])), (m, col)
    assert float(by["exact"]["rel_max"]) == 0.0
    assert float(by["exact"]["ridge_jump_ratio"]) == pytest.approx(1.0)
    assert float(by["dijkstra"]["rel_mean"]) > float(by["heat"]["rel_mean"]) > 0.0
    assert int(by["qclp"]["iterations"]) > 0
    # returned rows carry the same numbers as the CSV
    for row in rows:
        rec = by[row["method"]]
        assert float(rec["rel_mean"]) == pytest.approx(row["rel_mean"], rel=1e-5, abs=1e-12)
        assert set(row) == set(CSV_COLUMNS)


def test_format_table(sphere_run):
    _, _, rows = sphere_run
    text = format_table(rows)
    lines = text.splitlines()
    assert len(lines) == 2 + len(METHODS)
    assert lines[0].startswith("method") and set(lines[1]) <= {"-", " "}
    for m, line in zip(METHODS, lines[2:], strict=True):
        assert line.split()[0] == m
    # columns line up: every row has its status column starting where the header's does
    col = lines[0].index("status")
    assert all(line[col:].split()[0] in ("optimal", "almost_optimal") for line in lines[2:])
    partial = format_table([{"method": "x", "status": "boom " * 30, "time_s": 1.5}])
    assert "-" in partial and "…" in partial and "1.50" in partial


def test_failing_method_is_reported_and_others_continue(tmp_path, monkeypatch, capsys):
    real_solve = GeodesicSolver.solve

    def flaky_solve(self, sources, **kwargs):
        if self.method == "heat":
            raise SolverError("did not converge", solver="ipm", status="MaxIterations", info={"iterations": 7})
        if self.method == "fmm":
            raise RuntimeError("library crashed")
        return real_solve(self, sources, **kwargs)

    monkeypatch.setattr(GeodesicSolver, "solve", flaky_solve)
    mesh = icosphere(2)
    rows = run_compare(mesh, [0], ["heat", "exact", "fmm", "dijkstra"], tmp_path, progress=True)
    err = capsys.readouterr().err
    assert "heat" in err and "FAILED" in err and "dijkstra" in err
    header, records = _read_csv(tmp_path / "compare.csv")
    by = {r["method"]: r for r in records}
    assert [r["method"] for r in records] == ["heat", "exact", "fmm", "dijkstra"]
    assert "did not converge" in by["heat"]["status"] and "MaxIterations" in by["heat"]["status"]
    assert by["heat"]["solver"] == "ipm" and by["heat"]["iterations"] == "7"
    assert by["heat"]["rel_mean"] == ""
    assert by["fmm"]["status"] == "RuntimeError: library crashed"
    assert by["dijkstra"]["status"] == "optimal" and float(by["dijkstra"]["rel_mean"]) > 0
    names = {p.name for p in tmp_path.iterdir()}
    assert not {"field_heat.png", "error_heat.png", "field_fmm.png", "error_fmm.png"} & names
    assert {"field_dijkstra.png", "error_dijkstra.png", "field_exact.png", "gradient_histogram.png"} <= names
    assert rows[0]["status"].startswith("did not converge")
    assert "did not converge" in format_table(rows)


def test_without_exact_reference(tmp_path, capsys):
    """A non-manifold mesh: the exact method cannot run, the others are still timed and drawn."""
    plane = grid_plane(4)
    V = np.vstack([plane.V, [[0.25, 0.5, 0.3], [0.5, 0.5, 0.3]]])  # a fin on the edges of the line y = 0.5
    a, b, c = [int(np.flatnonzero(np.all(np.isclose(plane.V, p), axis=1))[0]) for p in
               ([0.25, 0.5, 0], [0.5, 0.5, 0], [0.75, 0.5, 0])]
    n = plane.n_vertices
    mesh = TriMesh(V, np.vstack([plane.F, [[a, b, n], [b, c, n + 1]]]), name="fin")
    assert not mesh.is_edge_manifold
    rows = run_compare(mesh, 0, ["exact", "dijkstra"], tmp_path, progress=True)
    err = capsys.readouterr().err
    assert "no exact reference" in err
    exact, dijk = rows
    assert exact["status"] and exact["status"] != "optimal" and exact["rel_mean"] is None
    assert dijk["status"] == "optimal" and dijk["rel_mean"] is None and dijk["time_s"] is not None
    names = {p.name for p in tmp_path.iterdir()}
    assert names == {"compare.csv", "field_dijkstra.png", "gradient_histogram.png"}


def test_alias_solved_once_and_quiet(tmp_path, monkeypatch, capsys):
    calls = []
    real_solve = GeodesicSolver.solve

    def counting_solve(self, sources, **kwargs):
        calls.append(self.method)
        return real_solve(self, sources, **kwargs)

    monkeypatch.setattr(GeodesicSolver, "solve", counting_solve)
    rows = run_compare(icosphere(1), 3, ["lcqp-hessian", "QGDF"], tmp_path / "new" / "dir", progress=False)
    assert capsys.readouterr().err == ""
    assert calls.count("lcqp-hessian") == 1 and calls.count("exact") == 1
    assert [r["method"] for r in rows] == ["lcqp-hessian", "qgdf"]
    assert rows[0]["rel_mean"] == rows[1]["rel_mean"]
    assert (tmp_path / "new" / "dir" / "field_qgdf.png").is_file()


def test_resolve_methods():
    allm = resolve_methods(["all"])
    assert "qgdf" not in allm and "lcqp-hessian" in allm and len(allm) == len(ALL_METHODS) - 1
    assert set(allm) <= set(ALL_METHODS)
    assert resolve_methods("Exact, dijkstra,exact") == ["exact", "dijkstra"]
    assert resolve_methods(["qgdf"]) == ["qgdf"]
    assert resolve_methods(["heat", "all"])[0] == "heat"
    with pytest.raises(ParameterError, match="unknown method 'nope'"):
        resolve_methods(["exact", "nope"])
    with pytest.raises(ParameterError, match="empty"):
        resolve_methods([])


def test_bad_input_fails_before_any_work(tmp_path):
    mesh = icosphere(1)
    with pytest.raises(SourceError):
        run_compare(mesh, [10_000], ["exact"], tmp_path / "a", progress=False)
    with pytest.raises(ParameterError):
        run_compare(mesh, 0, ["exact", "magic"], tmp_path / "b", progress=False)
    with pytest.raises(ParameterError, match="solver"):
        run_compare(mesh, 0, ["exact"], tmp_path / "c", solver="mosek", progress=False)
    assert list(tmp_path.iterdir()) == []


def test_rows_are_the_evaluation_summary(sphere_run):
    """compare measures with the one evaluation record that demo and the report use."""
    from cvxgeodesic.evaluation.summary import summarize_field

    mesh, _, rows = sphere_run
    exact = GeodesicSolver(mesh, "exact").solve(0).distance
    for row in rows:
        d = GeodesicSolver(mesh, row["method"]).solve(0).distance if row["method"] != "exact" else exact
        rec = summarize_field(mesh, d, exact, [0], gradient=False)
        for key in ("rel_mean", "rel_max", "rel_p99", "abs_max", "ridge_jump_p95", "ridge_jump_ratio",
                    "off_ridge_rel_mean"):
            assert row[key] == pytest.approx(rec[key], rel=1e-6, abs=1e-9), (row["method"], key)


# -- inside a tetrahedral mesh: the same comparison, against qclp at order 2 --------------------------------------
@pytest.fixture(scope="module")
def box_run(tmp_path_factory):
    from cvxgeodesic.mesh.tet_generate import tet_box

    out = tmp_path_factory.mktemp("cmp_tet")
    mesh = tet_box(3)
    rows = run_compare(mesh, 0, ["qclp", "dijkstra"], out, progress=False)
    return mesh, out, rows


def test_volume_rows_are_the_evaluation_summary(box_run):
    """The drift item: compare_tet measured its own three numbers; a volume row is now summarize's record, as on
    surfaces (rel_p99 was missing), against the reference that the row before it is."""
    from cvxgeodesic.evaluation.summary import summarize

    mesh, out, rows = box_run
    assert [(r["method"], r["order"]) for r in rows] == [("qclp", 2), ("qclp", 1), ("dijkstra", 1)]
    assert {r["reference"] for r in rows} == {"qclp order 2"}
    ref = GeodesicSolver(mesh, "qclp", order=2).solve(0)
    for row in rows:
        res = ref if row["order"] == 2 else GeodesicSolver(mesh, row["method"]).solve(0)
        rec = summarize(mesh, res, ref.distance, gradient=False)
        for key in ("rel_mean", "rel_max", "rel_p99", "abs_max"):
            # the same solve twice: equal to rounding (1e-9 relative covers a differently ordered sum)
            assert row[key] == pytest.approx(rec[key], rel=1e-9, abs=1e-12), (row["method"], key)
        assert row["rel_p99"] is not None
        assert row["ridge_jump_p95"] is None  # the ridge is a surface measure
    assert rows[0]["rel_max"] == 0.0 and rows[2]["rel_mean"] > rows[1]["rel_mean"] > 0  # Dijkstra zigzags
    header, records = _read_csv(out / "compare.csv")
    assert header == list(CSV_COLUMNS) and [r["order"] for r in records] == ["2", "1", "1"]
    stems = ("qclp_order2", "qclp", "dijkstra")
    assert {p.name for p in out.iterdir()} == {"compare.csv", "gradient_histogram.png",
                                              *(f"field_{s}.png" for s in stems), *(f"error_{s}.png" for s in stems)}
    assert format_table(rows).splitlines()[2].split()[:2] == ["qclp", "2"]  # the order column


def test_volume_compare_takes_a_given_reference(tmp_path):
    from cvxgeodesic.mesh.tet_generate import tet_box

    mesh = tet_box(2)
    exact = np.linalg.norm(mesh.V - mesh.V[0], axis=1)  # a convex box: the straight line
    rows = run_compare(mesh, 0, "all", tmp_path, reference=exact, progress=False)
    assert "qclp" in [r["method"] for r in rows] and "fmm" not in [r["method"] for r in rows]
    assert all(r["order"] == 1 and r["reference"] == "given" for r in rows)
    by = {r["method"]: r for r in rows}
    assert 0 < by["qclp"]["rel_mean"] < by["dijkstra"]["rel_mean"]  # measured against the given field
    with pytest.raises(ParameterError, match="reference"):
        run_compare(mesh, 0, "qclp", tmp_path / "b", reference=exact[:-1], progress=False)
    with pytest.raises(ParameterError, match="does not apply to tetrahedral meshes"):
        run_compare(mesh, 0, "fmm", tmp_path / "c", progress=False)
    assert not (tmp_path / "b").exists() and not (tmp_path / "c").exists()


def test_surface_compare_takes_a_given_reference(tmp_path, monkeypatch):
    """What the volume comparison had, surfaces have too: a reference field of the caller's (the exact method then
    never runs), named in the rows."""
    calls = []
    real_solve = GeodesicSolver.solve

    def counting_solve(self, sources, **kwargs):
        calls.append(self.method)
        return real_solve(self, sources, **kwargs)

    mesh = icosphere(1)
    exact = GeodesicSolver(mesh, "exact").solve(0).distance
    monkeypatch.setattr(GeodesicSolver, "solve", counting_solve)
    rows = run_compare(mesh, 0, ["dijkstra"], tmp_path, reference=exact, progress=False)
    assert calls == ["dijkstra"]
    (row,) = rows
    assert row["reference"] == "given" and row["order"] == 1 and row["rel_mean"] > 0
    assert row["ridge_jump_ratio"] is not None  # measured against the given field's ridge


def test_a_full_disk_while_drawing_leaves_nothing_of_the_run(tmp_path, monkeypatch):
    """issue 41 (D17): a full disk at the pictures left compare.csv and no pictures. Now the run writes everything
    or nothing (files there before stay as they were), and the error names the file that failed."""
    import errno
    import pickle

    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from cvxgeodesic.errors import OutputError

    out = tmp_path / "out"
    out.mkdir()
    (out / "compare.csv").write_text("from before\n")
    (out / "notes.txt").write_text("mine\n")
    calls = []
    print_png = FigureCanvasAgg.print_png

    def disk_full(self, *args, **kwargs):
        calls.append(1)
        if len(calls) == 2:  # the second picture: the CSV and one picture are written by then
            raise OSError(errno.ENOSPC, "No space left on device")
        return print_png(self, *args, **kwargs)

    monkeypatch.setattr(FigureCanvasAgg, "print_png", disk_full)
    with pytest.raises(OutputError) as exc:
        run_compare(icosphere(1), 0, ["dijkstra", "heat"], out, progress=False)
    assert isinstance(exc.value, OSError) and exc.value.errno == errno.ENOSPC
    back = pickle.loads(pickle.dumps(exc.value))  # a worker's error crosses processes
    assert type(back) is OutputError and str(back) == str(exc.value) and back.filename == exc.value.filename
    failed = exc.value.filename
    assert failed is not None and failed.startswith(str(out / "")) and failed.endswith(".png")
    assert str(exc.value) == (f"cannot write {failed} (No space left on device); nothing of this comparison was "
                              f"written to {out}")
    assert sorted(p.name for p in out.iterdir()) == ["compare.csv", "notes.txt"]  # no private folder left either
    assert (out / "compare.csv").read_text() == "from before\n"
    # the same run on a disk with room: everything appears
    monkeypatch.setattr(FigureCanvasAgg, "print_png", print_png)
    run_compare(icosphere(1), 0, ["dijkstra", "heat"], out, progress=False)
    names = sorted(p.name for p in out.iterdir())
    assert "compare.csv" in names and "gradient_histogram.png" in names and "field_heat.png" in names
    assert not [n for n in names if n.startswith(".")]


def test_compare_where_every_cell_touches_a_source_has_no_log_scale_note(tmp_path):
    """issue 41: on a box of 6 tetrahedra around vertex 0 the histograms count nothing; matplotlib's "cannot be
    log-scaled" warning became a note of compare."""
    import warnings

    from cvxgeodesic.mesh.tet_generate import tet_box

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        run_compare(tet_box(1), 0, ["dijkstra"], tmp_path, progress=False)
    assert not [str(w.message) for w in caught if "log-scaled" in str(w.message)]
    assert (tmp_path / "gradient_histogram.png").is_file()
