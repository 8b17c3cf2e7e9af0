"""Progress while a solve runs: the CLI's lines on stderr (both backends, after a delay), the API's callback for
Clarabel, and batch's progress and notes, which must not print over each other."""

from __future__ import annotations

import io
import re
import sys
from types import SimpleNamespace

import numpy as np
import pytest

import cvxgeodesic as cg
import cvxgeodesic._verbose as verbose
import cvxgeodesic.batch as batch
from cvxgeodesic.cli import main
from cvxgeodesic.cli._common import Notes as _Notes

LINE = re.compile(r"^  iteration +(\d+)  gap \S+  residuals \S+ / \S+ +\d+\.\d s(  \((\w+)\))?$")


@pytest.fixture(scope="module")
def sphere_file(tmp_path_factory):
    return cg.save_distance(tmp_path_factory.mktemp("mesh") / "sphere.ply", cg.icosphere(2), np.zeros(162))


def progress_lines(err: str) -> list[re.Match]:
    return [m for m in map(LINE.match, err.splitlines()) if m]


@pytest.mark.parametrize("solver", ["clarabel", "ipm"])
def test_cli_distance_prints_each_iteration_once_the_delay_has_passed(sphere_file, tmp_path, capsys, monkeypatch,
                                                                      solver):
    monkeypatch.setattr(verbose, "PROGRESS_DELAY", 0.0)
    out = tmp_path / "d.npy"
    assert main(["distance", str(sphere_file), "-s", "0", "--method", "qclp", "--solver", solver, "-o", str(out)]) == 0
    captured = capsys.readouterr()
    lines = progress_lines(captured.err)
    iterations = int(re.search(r"optimal, (\d+) iterations", captured.err).group(1))
    assert len(lines) >= iterations  # Clarabel also reports its iteration 0
    assert [int(m.group(1)) for m in lines][-1] == iterations
    assert {m.group(3) for m in lines} == ({"clarabel"} if solver == "clarabel" else {None})
    assert captured.out == ""  # progress is not output


def test_cli_path_prints_progress_too(sphere_file, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(verbose, "PROGRESS_DELAY", 0.0)
    assert main(["path", str(sphere_file), "-s", "0", "--to", "100", "--method", "qclp", "--solver", "clarabel",
                 "-o", str(tmp_path / "p.csv")]) == 0
    assert progress_lines(capsys.readouterr().err)


def test_cli_quiet_and_fast_solves_print_no_progress(sphere_file, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(verbose, "PROGRESS_DELAY", 0.0)
    args = ["distance", str(sphere_file), "-s", "0", "--solver", "clarabel", "-o"]
    assert main([*args, str(tmp_path / "a.npy"), "-q"]) == 0
    monkeypatch.setattr(verbose, "PROGRESS_DELAY", 1e9)  # a solve that ends before the delay
    assert main([*args, str(tmp_path / "b.npy")]) == 0
    assert progress_lines(capsys.readouterr().err) == []


def test_progress_printer_waits_for_the_delay():
    now = [0.0]
    stream = io.StringIO()
    progress = verbose.progress_printer(stream, delay=2.0, clock=lambda: now[0])
    info = {"gap_rel": 3.1e-4, "res_primal": 1.2e-9, "res_dual": 3.4e-8}
    for t, it in ((0.5, 1), (1.9, 2), (2.4, 3), (3.0, 4)):
        now[0] = t
        progress(it, info)
    progress(5, {**info, "solver": "clarabel"})
    assert stream.getvalue().splitlines() == [
        "  iteration   3  gap 3.1e-04  residuals 1.2e-09 / 3.4e-08     2.4 s",
        "  iteration   4  gap 3.1e-04  residuals 1.2e-09 / 3.4e-08     3.0 s",
        "  iteration   5  gap 3.1e-04  residuals 1.2e-09 / 3.4e-08     3.0 s  (clarabel)",
    ]


@pytest.mark.parametrize("order", [1, 2])
def test_solve_callback_sees_every_clarabel_iteration(order):
    seen = []
    res = cg.GeodesicSolver(cg.icosphere(1), "qclp", solver="clarabel", order=order).solve(
        0, callback=lambda it, info: seen.append((it, info)))
    assert [it for it, _ in seen] == list(range(res.info.iterations + 1))
    assert all(info["solver"] == "clarabel" and np.isfinite(info["gap_rel"]) for _, info in seen)
    assert seen[-1][1]["gap_rel"] < 1e-6


def test_an_error_in_the_callback_stops_clarabel_and_is_raised():
    def callback(it, info):
        if it == 2:
            raise ValueError("stop here")

    with pytest.raises(ValueError, match="stop here"):
        cg.GeodesicSolver(cg.icosphere(1), "qclp", solver="clarabel").solve(0, callback=callback)


# ----------------------------------------------------------------------------------------------------------------------
# batch and notes: one line each, never on the bar's line
# ----------------------------------------------------------------------------------------------------------------------


class _Done:
    def __init__(self, row):
        self.row = row

    def result(self):
        return self.row


def test_batch_progress_in_a_log_is_plain_lines(tmp_path, capsys):
    """Where stderr is no terminal (a log, a pipe) the bar's redraws would stay on the notes' lines."""
    a, b = tmp_path / "a.off", tmp_path / "b.off"
    futures = {_Done({"mesh": str(a), "status": "ok", "notes": ["a.off: welded 2 vertices"]}): a,
               _Done({"mesh": str(b), "status": "failed", "error": "no such file", "notes": []}): b}
    fake = SimpleNamespace(as_completed=lambda fs: list(fs))
    bar = batch._progress(len(futures))  # capsys: stderr is not a terminal
    batch._collect(fake, futures, {}, bar)
    bar.close()
    err = capsys.readouterr().err
    assert "\r" not in err
    assert err.splitlines() == ["meshes: 0/2 done", "meshes: 1/2 done", "cvxgeodesic: note: a.off: welded 2 vertices",
                                "meshes: 2/2 done", f"FAILED {b}: no such file"]


def test_batch_progress_in_a_terminal_is_a_bar(monkeypatch):
    from tqdm import tqdm

    monkeypatch.setattr(sys, "stderr", SimpleNamespace(isatty=lambda: True, write=lambda s: None, flush=lambda: None))
    bar = batch._progress(3)
    try:
        assert isinstance(bar, tqdm)
    finally:
        bar.close()


def test_a_cli_note_goes_above_an_active_progress_bar(capsys):
    from tqdm import tqdm

    bar = tqdm(total=4, desc="rows", file=sys.stderr)
    bar.update(1)
    _Notes().say("m.off: planar Hessian used")
    bar.close()
    err = capsys.readouterr().err
    lines = [ln.split("\r")[-1] for ln in err.split("\n")]  # what a terminal shows of each line
    assert "cvxgeodesic: note: m.off: planar Hessian used" in lines, err
