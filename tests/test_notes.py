"""Issue 16, item 5 (the CLI and batch side): notes in the batch JSON, each note printed once and formatted."""

from __future__ import annotations

import json
import warnings
from pathlib import Path
from types import SimpleNamespace

import numpy as np

import cvxgeodesic as cg
import cvxgeodesic.batch as batch
from cvxgeodesic.cli import main

# a plane with one zero-area face: the convex formulations leave it out, with a DegenerateFacesWarning
SLIVER_V = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.5, 0.5, 0], [1, 1, 0]]
SLIVER_F = [[0, 1, 3], [0, 3, 2], [1, 4, 3], [3, 4, 2], [1, 2, 3]]


def _write_off(path: Path, V, F) -> Path:
    text = f"OFF\n{len(V)} {len(F)} 0\n" + "".join(" ".join(map(repr, map(float, v))) + "\n" for v in V)
    path.write_text(text + "".join("3 " + " ".join(map(str, f)) + "\n" for f in F))
    return path


def test_batch_json_carries_the_notes_and_the_worker_prints_nothing(tmp_path, capfd):
    mesh = _write_off(tmp_path / "sliver.off", SLIVER_V, SLIVER_F)
    out = tmp_path / "out"
    out.mkdir()
    row = batch.solve_one(str(mesh), [0], str(out), method="qclp", solver="clarabel", output_format="npy")
    assert row["status"] == "ok", row
    meta = json.loads((out / "sliver.json").read_text())
    assert any("1 degenerate face" in n for n in meta["notes"]), meta["notes"]
    # SolveInfo.notes itself, not only the warnings batch merges into the row's notes
    assert any("1 degenerate face" in n for n in meta["info"]["notes"]), meta["info"]["notes"]
    assert meta["notes"] == row["notes"] and len(set(meta["notes"])) == len(meta["notes"])
    assert isinstance(meta["info"]["notes"], list)  # SolveInfo.notes, as the solver filled it
    captured = capfd.readouterr()
    assert captured.err == "" and captured.out == ""  # no raw "file.py:309: Warning" text from the worker


def test_failed_batch_task_keeps_its_notes(tmp_path):
    mesh = _write_off(tmp_path / "sliver.off", SLIVER_V, SLIVER_F)
    row = batch.solve_one(str(mesh), [99], str(tmp_path), method="qclp")
    assert row["status"] == "failed" and "out of range" in row["error"]
    assert isinstance(row["notes"], list)


def test_batch_prints_each_note_once_above_the_progress_bar(tmp_path, capsys):
    from tqdm import tqdm

    class Done:
        def __init__(self, row):
            self.row = row

        def result(self):
            return self.row

    p = tmp_path / "a.off"
    futures = {Done({"mesh": str(p), "status": "ok", "notes": ["a.off: welded 2 vertices", "planar Hessian used"]}): p}
    fake = SimpleNamespace(as_completed=lambda fs: list(fs))
    rows = {}
    bar = tqdm(total=1, file=open("/dev/null", "w"))  # noqa: SIM115 - the bar's own output is not under test
    batch._collect(fake, futures, rows, bar)
    err = capsys.readouterr().err.splitlines()
    assert err == ["cvxgeodesic: note: a.off: welded 2 vertices", "cvxgeodesic: note: a.off: planar Hessian used"]


def test_cli_prints_each_note_once(tmp_path, monkeypatch, capsys):
    import cvxgeodesic.api as api

    real_solve = api.GeodesicSolver.solve

    def solve(self, sources, **kw):
        res = real_solve(self, sources, **kw)
        for _ in range(2):  # the same substitution reported twice (e.g. two Clarabel retries)
            warnings.warn("m.off: solving with Clarabel instead", RuntimeWarning, stacklevel=1)
        res.info.notes[:] = ["m.off: solving with Clarabel instead", "m.off: planar Hessian used"]
        return res

    monkeypatch.setattr(api.GeodesicSolver, "solve", solve)
    mesh = _write_off(tmp_path / "m.off", cg.icosphere(1).V, cg.icosphere(1).F)
    rc = main(["distance", str(mesh), "-s", "0", "--method", "dijkstra", "-q", "-o", str(tmp_path / "d.npy")])
    err = capsys.readouterr().err.splitlines()
    assert rc == 0
    assert err == ["cvxgeodesic: note: m.off: solving with Clarabel instead",
                   "cvxgeodesic: note: m.off: planar Hessian used"]
    assert np.load(tmp_path / "d.npy").shape == (42,)


def test_results_of_both_orders_carry_the_loaders_and_the_builders_notes(tmp_path):
    """The loader's repairs (welded and dropped vertices) and the formulation's (degenerate faces) reach
    ``info.notes`` at order 1 and at order 2 alike."""
    path = tmp_path / "sliver.obj"
    lines = [f"v {x} {y} {z}" for x, y, z in SLIVER_V] + ["v 0 0 0", "v 9 9 9"]  # a duplicate and a loose vertex
    lines += ["f " + " ".join(str(i + 1) for i in f) for f in SLIVER_F]
    path.write_text("\n".join(lines) + "\n")
    mesh = cg.load_mesh(path)
    assert mesh.notes, "the loader records its repairs"
    for order in (1, 2):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            notes = cg.GeodesicSolver(mesh, "qclp", order=order).solve(0).info.notes
        for note in mesh.notes:
            assert note in notes, (order, notes)
        assert any("degenerate face" in n for n in notes), (order, notes)
