"""Every time and accuracy figure that README.md and docs/ quote, measured on this machine beside the quoted value.

Run it (``make claims``; one thread, the shared meshes in ``../shared/meshes``)::

    python benchmarks/claims.py --quick                      # a subset of the meshes, ≤ 10 min on 2 cores
    python benchmarks/claims.py                              # every shared mesh each figure concerns
    python benchmarks/claims.py --quick --out docs/claims.md # the dated page (date, machine, load, mode)
    python benchmarks/claims.py --list                       # the registry only, nothing measured

:data:`CLAIMS` is the registry: each figure has an id, the page(s) and the exact text that quote it, and either
a measurement (an *experiment* of this file, run on the meshes it concerns, and the value it reads from each
mesh's result) or, for a dated record of a past run (a before/after, a development measurement), the command
that reproduces it. Each page marks the paragraph or table of a figure with ``<!-- claim: ID -->``;
``tests/test_claims.py`` fails when a figure has no such mark, a mark no entry, or an entry's text is gone.

The experiments reuse the benchmark scripts: ``matrix.py`` (rows against a heat loop), ``one_shot.py``
(one-shot solves against the heat method), ``order2.py --speed`` and ``method_choice.py`` (errors against the
exact distance), all in this one process with one thread, each ratio against a baseline timed in the same
run beside it. A measured claim prints its range over the meshes with the worst case named, and ``inside``
when that range, rounded as the page rounds it, lies within the quoted one.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import platform
import sys
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

for _var in ("CVXGEODESIC_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS",
             "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # before numpy/MKL/Numba load: every figure is a one-thread figure

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
SHARED = REPO.parent / "shared" / "meshes"
sys.path.insert(0, str(HERE))

#: The curved scans of the shared set (manifold; the exact algorithm runs on all but beetle_open).
SCANS = ["spot.obj", "bunny_7k.off", "fertility_genus4.off", "max_planck.obj", "bug_surface.off", "kitten.obj",
         "buddha.obj", "dragon_20k.obj", "lucy_20k.obj", "camelhead_open.off", "beetle_open.off", "bimba.obj",
         "bunny.obj", "armadillo.obj", "horse.ply"]
#: CAD parts with flat faces (the Thingi10K files of the shared set and fandisk).
CAD = ["fandisk.obj", "thingi_243015.stl", "thingi_32770.stl", "thingi_37881.stl", "thingi_47076.stl",
       "thingi_65395.stl", "thingi_93703.stl", "thingi_96457.stl"]
#: the three meshes of README's "Which method to use" (spot: the bundled copy)
CHOICE = ["spot", "bimba.obj", "thingi_37881.stl"]


# ---------------------------------------------------------------------------------------------- experiments
@dataclass(frozen=True)
class Experiment:
    """One measurement run: ``run(meshes, quick)`` → ``{mesh: result}``, over ``full`` or ``quick`` meshes."""

    run: Callable[[list[str], bool], dict[str, dict]]
    full: tuple[str, ...]
    quick: tuple[str, ...]
    what: str  # how it measures, for the page


def _load(name: str):
    import cvxgeodesic as cg
    from cvxgeodesic.demo import demo_mesh

    return demo_mesh() if name == "spot" else cg.load_mesh(SHARED / name)


def _rows(meshes: list[str], quick: bool) -> dict[str, dict]:
    """Full and local QCLP rows against a heat loop (``benchmarks/matrix.py``'s functions), in this process."""
    import numpy as np

    import matrix as mx

    out = {}
    for name in meshes:
        mesh = _load(name)
        n_rows = (30 if mesh.n_faces < 30_000 else 20) if quick else (50 if mesh.n_faces < 60_000 else 20)
        rows = np.random.default_rng(0).choice(mesh.n_vertices, size=n_rows, replace=False).tolist()
        r = 0.1 * mesh.bbox_diagonal
        mx._warm()
        t_heat, _, _ = mx._heat(name, rows)
        t_full, D_full, _ = mx._rows(name, rows, "qclp", None, None)
        t_local, L, _ = mx._rows(name, rows, "qclp", r, None)
        k = 3 if quick else 10
        exact = mx._exact(name, rows[:k])
        e_full = mx._error_inside(D_full[:k], exact, r)
        e_local = mx._error_inside(mx._dense(L[:k], mesh.n_vertices), exact, r)
        out[name] = {"faces": mesh.n_faces, "rows": n_rows, "full/heat": t_full / t_heat,
                     "local/heat": t_local / t_heat, "local/full error": e_local / e_full,
                     "ms per row": {"heat": 1e3 * t_heat / n_rows, "full": 1e3 * t_full / n_rows,
                                    "local": 1e3 * t_local / n_rows}}
        _progress(f"rows {name}: {out[name]}")
    return out


def _one_shot(meshes: list[str], quick: bool) -> dict[str, dict]:
    """One-shot QCLP and QCQP-Hessian solves against the heat method (``benchmarks/one_shot.py``'s ``child``)."""
    import one_shot

    out = {}
    for name in meshes:
        row = one_shot.child(str(SHARED / name), ["qclp", "qcqp-hessian"], 2, False)
        best, heat = row["best"], row["best"]["heat"]
        out[name] = {"faces": row["faces"], "qclp/heat": best["qclp/1"] / heat,
                     "hessian/heat": best["qcqp-hessian/1"] / heat,
                     "it qclp": row["iterations"]["qclp/1"], "it qcqp-hessian": row["iterations"]["qcqp-hessian/1"],
                     "seconds": best}
        _progress(f"one-shot {name}: {out[name]}")
    return out


def _order2(meshes: list[str], quick: bool) -> dict[str, dict]:
    """Order 2 against order 1, exact MMP and smoothed order 2 (``benchmarks/order2.py --speed``)."""
    import order2

    small = [m for m in meshes if _load(m).n_faces < 30_000]
    with contextlib.redirect_stdout(sys.stderr):  # its own table goes with the progress lines
        rows = order2.speed(["--repeat=2", *small]) if small else []
        big = [m for m in meshes if m not in small]
        rows += order2.speed(["--repeat=1", *big]) if big else []
    out = {}
    for r in rows:
        t = {k: r[k]["time"] for k in ("P1 qclp", "o2 qclp", "o2 hessian", "exact")}
        out[r["mesh"]] = {"faces": r["faces"], "o2/o1": t["o2 qclp"] / t["P1 qclp"],
                          "o2/exact": t["o2 qclp"] / t["exact"] if t["exact"] < float("inf") else None,
                          "hessian o2/o2": t["o2 hessian"] / t["o2 qclp"] if t["o2 qclp"] > 0.05 else None,
                          "seconds": {k: v if v < float("inf") else None for k, v in t.items()},
                          "it o2": r["o2 qclp"]["iterations"]}
    return out


def _choice(meshes: list[str], quick: bool, cases=None) -> dict[str, dict]:
    """Errors against the exact distance and times of ``method_choice.py``'s cases, per mesh."""
    import method_choice

    out = {}
    for name in meshes:
        mesh = _load(name)
        rows = method_choice.measure(mesh, 1 if quick else 2, cases or method_choice.CASES)
        out[name] = {"faces": mesh.n_faces, **{r["case"]: r for r in rows}}
        _progress(f"choice {name}: " + ", ".join(f"{r['case']} {100 * r['rel_mean']:.3g} % {r['time_s']:.2f} s"
                                                 for r in rows))
    return out


def _accuracy(meshes: list[str], quick: bool) -> dict[str, dict]:
    """The order-1 methods and the exact algorithm only (no order 2): error and time on many meshes."""
    import method_choice

    cases = [c for c in method_choice.CASES if c[2] == 1 and c[1] != "qcqp-hessian" or c[0].endswith("(default)")]
    return _choice(meshes, quick, cases)


EXPERIMENTS: dict[str, Experiment] = {
    "rows": Experiment(_rows, ("kitten.obj", "lucy_20k.obj", "bimba.obj", "horse.ply"), ("kitten.obj", "bimba.obj"),
                       "`distance_matrix(mesh, rows, method='qclp')` (full rows) and `max_distance=` 10 % of the "
                       "diagonal (local rows) against potpourri3d's heat solver built once and called per row; "
                       "50 random rows (20 above 60K faces; quick: 30, 20 above 30K), errors over the vertices "
                       "within r of the first 10 rows (quick: 3) against MMP"),
    "one-shot": Experiment(_one_shot, ("kitten.obj", "lucy_20k.obj", "dragon_20k.obj", "buddha.obj",
                                       "camelhead_open.off", "beetle_open.off", "bimba.obj", "bunny.obj",
                                       "armadillo.obj", "horse.ply"),
                           ("bimba.obj", "armadillo.obj", "horse.ply"),
                           "`GeodesicSolver(mesh, method).solve(0)` (set-up included) against "
                           "`MeshHeatMethodDistanceSolver(V, F).compute_distance(0)`, alternating, min of 2"),
    "order2": Experiment(_order2, tuple(SCANS + CAD), ("spot.obj", "bunny_7k.off", "fertility_genus4.off",
                                                       "max_planck.obj", "fandisk.obj", "thingi_37881.stl"),
                         "`benchmarks/order2.py --speed`: set-up + solve from vertex 0, min of 2 (one run above 30K "
                         "faces)"),
    "choice": Experiment(_choice, tuple(CHOICE), tuple(CHOICE),
                         "`benchmarks/method_choice.py`: each method from vertex 0, set-up included, min of 2 "
                         "(quick: 1); mean relative error against MMP"),
    "accuracy": Experiment(_accuracy, tuple(m for m in SCANS + CAD if m != "beetle_open.off"),
                           ("spot.obj", "bunny_7k.off", "fertility_genus4.off", "max_planck.obj", "bug_surface.off",
                            "kitten.obj", "fandisk.obj", "thingi_37881.stl"),
                           "`method_choice.measure` with the default, `qclp`, `heat` and `exact` only"),
}


def _progress(line: str) -> None:
    print(f"  {time.strftime('%H:%M:%S')} {line}", file=sys.stderr, flush=True)


# ---------------------------------------------------------------------------------------------- the registry
def _key(k: str) -> Callable[[dict], dict[str, float]]:
    """The value ``k`` of every mesh's result (meshes where it is None left out)."""
    return lambda res: {m: r[k] for m, r in res.items() if r.get(k) is not None}


def _only(names: list[str], k: str) -> Callable[[dict], dict[str, float]]:
    return lambda res: {m: v for m, v in _key(k)(res).items() if m in names}


def _iterations(res: dict) -> dict[str, float]:
    return {f"{m} {meth}": r[f"it {meth}"] for m, r in res.items() if 50_000 <= r["faces"] <= 100_000
            for meth in ("qclp", "qcqp-hessian")}


def _order2_gain(res: dict) -> dict[str, float]:
    """Best order-1 mean error (default, qclp, heat) over order-2 qclp's."""
    return {m: min(r[c]["rel_mean"] for c in ("qcqp-hessian (default)", "qclp", "heat"))
            / r["qclp, order=2"]["rel_mean"] for m, r in res.items()}


def _error_ratio(a: str, b: str) -> Callable[[dict], dict[str, float]]:
    return lambda res: {m: r[a]["rel_mean"] / r[b]["rel_mean"] for m, r in res.items()}


def _time_ratio(a: str, b: str) -> Callable[[dict], dict[str, float]]:
    return lambda res: {m: r[a]["time_s"] / r[b]["time_s"] for m, r in res.items()}


def _cells(case: str, key: str, scale: float) -> Callable[[dict], dict[str, float]]:
    return lambda res: {m: scale * res[m][case][key] for m in CHOICE if m in res}


@dataclass(frozen=True)
class Claim:
    """One quoted figure: where it is quoted and how it is measured (or, for a dated record, reproduced).

    ``where`` pairs a page (relative to the repository) with the exact text quoting the figure there
    (whitespace-insensitive). A measured claim names its ``experiment`` and ``value`` (the experiment's results →
    ``{case: value}``), the ``quoted`` range and which end is the ``worst`` case; a ``record`` says when it was
    measured and the command that measures it again.
    """

    id: str
    where: tuple[tuple[str, str], ...]
    quoted: tuple[float, float] | None = None
    unit: str = "×"
    experiment: str | None = None
    value: Callable[[dict], dict[str, float]] | None = None
    worst: str = "max"
    concerns: str = ""
    record: str = ""


def _q(text: str) -> tuple[float, float]:
    """The range a page writes (``"2.3–4.1"``, ``"17"``) as ``(low, high)``."""
    low, _, high = text.partition("–")
    return float(low), float(high or low)


def _c(id_: str, *where: tuple[str, str], **kw) -> Claim:
    return Claim(id_, tuple(where), **kw)


def _r(id_: str, date: str, how: str, *where: tuple[str, str]) -> Claim:
    """A dated record: measured on ``date`` by ``how`` (a command, or "no script"), not re-measured here."""
    return Claim(id_, tuple(where), record=f"{date}, {how}")


README, PERF, ORDER2 = "README.md", "docs/performance.md", "docs/order2.md"
BENCH, METHOD, METRICS = "docs/benchmarks.md", "docs/method.md", "docs/metrics.md"
SOURCES, VOLUMES = "docs/sources.md", "docs/volumes.md"
ADAPTED = "docs/adapted.md"
POINTCLOUDS = "docs/pointclouds.md"
NO_SCRIPT = "no script: a development measurement"

CLAIMS: list[Claim] = [
    # -- rows of a distance matrix
    _c("rows-full-vs-heat", (README, "full QCLP rows take 28–64× its time"), (PERF, "full rows 28–64× the heat loop"),
       quoted=_q("28–64"), experiment="rows", value=_key("full/heat"), concerns="scans of 18.9K–97K faces"),
    _c("rows-local-vs-heat", (README, "local rows (`r` = 10 % of the diagonal) 1.6–17×"), (PERF, "local rows 1.6–17×"),
       quoted=_q("1.6–17"), experiment="rows", value=_key("local/heat"), concerns="scans of 18.9K–97K faces"),
    _c("rows-local-accuracy", (PERF, "the local rows' error within `r`\n0.77–0.89× the full rows'"),
       quoted=_q("0.77–0.89"),
       experiment="rows", value=_key("local/full error"),
       concerns="local-row error within r over the full rows' (lower is better)"),
    # -- one-shot solves
    _c("one-shot-qclp-vs-heat", (PERF, "QCLP 2.4–5.6× the heat method's time"), quoted=_q("2.4–5.6"),
       experiment="one-shot", value=_key("qclp/heat"), concerns="scans of 18.9K–97K faces"),
    _c("one-shot-hessian-vs-heat", (PERF, "QCQP-Hessian 6.5–12×"), quoted=_q("6.5–12"), experiment="one-shot",
       value=_key("hessian/heat"), concerns="scans of 18.9K–97K faces"),
    _c("iterations-50k-100k", (PERF, "16–20 at 50K–100K"), quoted=_q("16–20"), unit=" it.", experiment="one-shot",
       value=_iterations, concerns="the scans of 50K–100K faces, QCLP and QCQP-Hessian"),
    # -- order 2
    _c("order2-vs-order1", (README, "0.78–19× the time of order 1"), (ORDER2, "it costs 0.78–19× the time of order 1"),
       (ORDER2, "and 0.78–19× over the scans and CAD parts"),
       quoted=_q("0.78–19"), experiment="order2", value=_key("o2/o1"), concerns="every scan and CAD part"),
    _c("order2-vs-order1-scans", (README, "(5.9–12× on\n  the scans)"),
       (ORDER2, "costs 5.9–12× order 1 on the\nshared scans"),
       quoted=_q("5.9–12"), experiment="order2", value=_only(SCANS, "o2/o1"), concerns="the scans"),
    _c("order2-vs-exact-scans", (README, "4–21× the exact algorithm's on the scans"),
       (ORDER2, "the exact algorithm is 4–21× faster"), quoted=_q("4–21"), experiment="order2",
       value=_only(SCANS, "o2/exact"), concerns="the scans where MMP runs"),
    _c("order2-smoothed-vs-plain", (ORDER2, "takes 0.81–1.6× order-2 `qclp`'s time"), quoted=_q("0.81–1.6"),
       experiment="order2", value=_key("hessian o2/o2"), concerns="meshes where order-2 qclp takes > 0.05 s"),
    _c("order2-accuracy", (README, "5.5–13× lower mean error than the best order-1 method"), quoted=(5.5, 13),
       experiment="choice", value=_order2_gain, worst="min",
       concerns="README's three meshes; best order-1 mean error over order 2's (higher is better)"),
    # -- README's "Which method to use"
    _c("choice-error-default", (README, "| 2.1 / 1.24 / 9.4 % |"), quoted=None, unit=" %", experiment="choice",
       value=_cells("qcqp-hessian (default)", "rel_mean", 100), concerns="mean error, spot / bimba / CAD part"),
    _c("choice-error-order2", (README, "| **0.13 / 0.11 / 1.65 %** |"), unit=" %", experiment="choice",
       value=_cells("qclp, order=2", "rel_mean", 100), concerns="mean error, spot / bimba / CAD part"),
    _c("choice-error-heat", (README, "| 1.69 / 1.34 / 13.9 % |"), unit=" %", experiment="choice",
       value=_cells("heat", "rel_mean", 100), concerns="mean error, spot / bimba / CAD part"),
    _c("choice-error-qclp", (README, "| 2.0 / 1.13 / 9.1 % |"), unit=" %", experiment="choice",
       value=_cells("qclp", "rel_mean", 100), concerns="mean error, spot / bimba / CAD part"),
    _c("choice-time-default", (README, "0.21 / 2.4 / 0.18 s"), unit=" s", experiment="choice",
       value=_cells("qcqp-hessian (default)", "time_s", 1), concerns="seconds on this machine"),
    _c("choice-time-order2", (README, "0.85 / 11.5 / 3.1 s"), unit=" s", experiment="choice",
       value=_cells("qclp, order=2", "time_s", 1), concerns="seconds on this machine"),
    _c("choice-time-heat", (README, "**0.01 / 0.36 / 0.02 s**"), unit=" s", experiment="choice",
       value=_cells("heat", "time_s", 1), concerns="seconds on this machine"),
    _c("choice-time-exact", (README, "0.06 / 2.0 / 0.09 s"), unit=" s", experiment="choice",
       value=_cells("exact", "time_s", 1), concerns="seconds on this machine"),
    _c("choice-time-qclp", (README, "0.09 / 0.77 / 0.04 s"), unit=" s", experiment="choice",
       value=_cells("qclp", "time_s", 1), concerns="seconds on this machine"),
    _c("qclp-vs-heat-error", (README, "mean error 0.15–4.8× the heat method's"), quoted=_q("0.15–4.8"),
       experiment="accuracy",
       value=_error_ratio("qclp", "heat"), concerns="qclp's mean error over the heat method's, every scan and "
                                                     "CAD part MMP runs on"),
    _c("exact-vs-default", (README, "it took 0.089–0.77× the default's time"), quoted=_q("0.089–0.77"),
       experiment="accuracy",
       value=_time_ratio("exact", "qcqp-hessian (default)"),
       concerns="exact MMP's time over the default's, every scan and CAD part it runs on"),
    _c("order2-smoothing-cost", (ORDER2, "Smoothing costs order 2 only 0.81–1.6×"), quoted=_q("0.81–1.6"),
       experiment="order2", value=_key("hessian o2/o2"), concerns="meshes where order-2 qclp takes > 0.05 s"),
    # -- dated records: a past run, a before/after, a development measurement
    _r("rows-table", "2026-12-03", "`python benchmarks/matrix.py --mesh MESH --rows N` (quiet machine)",
       (PERF, "| kitten (18.9K), 100 | 4.6 ms | 206 ms = 45×")),
    _r("one-shot-table", "2026-12-02", "`python benchmarks/one_shot.py --meshes bimba.obj horse.ply armadillo.obj "
       "--repeat 4` (quiet machine)", (PERF, "| bimba (46K) | 0.55 s (3.0× heat)")),
    _r("order2-speed-dev", "2026-12-02", "`python benchmarks/order2.py --speed --json=… MESH…` (two threads, quiet)",
       (README, "measured 1–11×"), (ORDER2, "1–11× with two in the development run"),
       (ORDER2, "| meshes | faces | order 1 `qclp` | order 2 `qclp` |")),
    _r("bm-dask-rows", "2026-12-01", "`python benchmarks/matrix_rows.py`",
       (BENCH, "every solve in a worker was about 1.8× slower")),
    _r("bm-multires-quadric", "2026-12-01", NO_SCRIPT,
       (BENCH, "the mean error on bimba at 1/4 is 2.4 %")),
    _r("bm-scaling-1m", "2026-12-03", "`python benchmarks/scaling.py`",
       (BENCH, "takes 3.5× the heat method's time")),
    _r("bm-scaling-order2", "2026-12-03", "`python benchmarks/scaling.py`",
       (BENCH, "Direct is 3.1× the heat method, order 2 82×")),
    _r("bm-order2-edge-cones", "2026-12-02", "`python benchmarks/scaling.py --sizes 1100000 --methods order2`",
       (BENCH, "19× the direct QCQP-Hessian solve's time")),
    _r("bm-volume-100k", "2026-12-03", "`python benchmarks/volume_scale.py`",
       (BENCH, "order 1 takes 6.5× the heat method's time and 1.8× its added memory")),
    _r("method-source-anchor", "2026-11-22", NO_SCRIPT,
       (METHOD, "error from 1.95 %")),
    _r("method-indefinite", "2026-11-22", NO_SCRIPT,
       (METHOD, "22–74 % mean error")),
    _r("method-paper-norm", "2026-12-01", "`python benchmarks/normalization_study.py`",
       (METHOD, "74 % mean error, field shrunk to a quarter")),
    _r("method-kappa", "2026-12-01", "`python benchmarks/normalization_study.py`",
       (METHOD, "error off the ridge at QCLP's (1.09 %")),
    _r("method-no-collapse", "2026-12-01", "`python benchmarks/normalization_study.py`",
       (METHOD, "error (5.07 %")),
    _r("method-paper-reading", "2026-11-22", NO_SCRIPT,
       (METHOD, "the ridge is 2.3–2.5× less sharp than the exact field's")),
    _r("method-analytic", "2026-11-22", "`pytest tests/test_formulations.py`",
       (METHOD, "QCLP's worst relative error at distance > 0.25 falls with refinement")),
    _r("metrics-hill", "2026-12-02", "the page's own code",
       (METRICS, "takes 2.4× less time")),
    _r("metrics-medium", "2026-12-02", NO_SCRIPT,
       (METRICS, "1.824 % mean error")),
    _r("order2-intro-accuracy", "2026-12-02", "`python benchmarks/order2.py`",
       (ORDER2, "is 7–12× lower than that of the best order-1 method")),
    _r("order2-held-out-cad", "2026-12-03", "a report on CAD parts outside ../shared/meshes; "
       "`python benchmarks/order2.py --speed PART…` measures yours",
       (README, "held-out CAD parts, outside the shared set, measured 7–12.6× order 1 and 6.9–13.8× exact"),
       (ORDER2, "held-out CAD parts measured slower,\n7–12.6×"),
       (ORDER2, "7–12.6× order 1 and 6.9–13.8× the\nexact algorithm"),
       (ORDER2, "(held-out CAD parts:\n6.9–13.8×)")),
    _r("order2-cone-samples", "2026-12-02", NO_SCRIPT,
       (ORDER2, "| mesh | corner + midpoint samples, cutting planes | edge cones, guess start |")),
    _r("order2-nonmanifold-jump", "2026-12-02", NO_SCRIPT,
       (ORDER2, "7 % at λ = 1e-5 to 1e-3), with the same errors")),
    _r("order2-kappa2", "2026-12-02", NO_SCRIPT,
       (ORDER2, "3.6× more accurate than order 1's")),
    _r("order2-smoothing-goal", "2026-12-03", "`python benchmarks/order2_smoothing.py fine`",
       (ORDER2, "**The time misses the 1.3× goal slightly**")),
    _r("order2-smoothed-accuracy", "2026-12-02", "`python benchmarks/order2_smoothing.py`",
       (ORDER2, "the smoothed order-2 field is 5–10× more accurate")),
    _r("order2-cutting-planes-before", "2026-12-02", "`python benchmarks/order2.py --speed`",
       (ORDER2, "20 iterations, 4.2 s, 43× order 1)")),
    _r("order2-to-mmp", "2026-12-02", "`python benchmarks/newton_change.py`",
       (ORDER2, "the solve still takes 15–19 iterations (5.5× MMP on armadillo")),
    _r("order2-coarse-cad", "2026-12-02", "`python benchmarks/order2.py OUT.json thingi10k_small`",
       (ORDER2, "max errors above 100 % even for FMM")),
    _r("order2-tiny-meshes", "2026-12-02", "`python benchmarks/order2.py OUT.json thingi10k_small`",
       (ORDER2, "0.22 % against 0.081 % mean error")),
    _r("perf-policy", "2026-12-02", "`python benchmarks/under_load.py --policies default 1 all`",
       (PERF, "stays within the fair share of 2×")),
    _r("perf-clarabel", "2026-12-02", "`make bench`",
       (PERF, "Clarabel takes 4–18× our solver's time")),
    _r("perf-rows-tol", "2026-12-03", "`python benchmarks/matrix.py --tol 1e-5`",
       (PERF, "845 ms per full row (56×)")),
    _r("perf-rows-why", "2026-12-03", "`python benchmarks/matrix.py`",
       (PERF, "3.1482 % at 1e-8 and 1e-5, 3.1502 % at 1e-4")),
    _r("sources-aabb", "2026-12-03", "`python benchmarks/curve_sources.py`",
       (SOURCES, "took 5.2× the")),
    _r("sources-table", "2026-12-01", "`pytest tests/test_sources.py`",
       (SOURCES, "| case | qclp | qcqp-hessian | dijkstra | fmm |")),
    _r("sources-jitter", "2026-12-01", NO_SCRIPT,
       (SOURCES, "1.30 % at 30×30, 1.13 % at 40×40")),
    _r("volumes-point", "2026-12-02", NO_SCRIPT,
       (VOLUMES, "4.1–4.8 % against 5.9–7.9 % mean error")),
    _r("volumes-table", "2026-12-02", "`pytest tests/test_tet_solve.py`",
       (VOLUMES, "| case | tetrahedra | order 1 | order 2 | heat | Dijkstra |")),
    _r("volumes-jitter", "2026-12-02", NO_SCRIPT,
       (VOLUMES, "the order-1 error stops decreasing near 5 %")),
    _r("volumes-speed", "2026-12-02", "`python benchmarks/volume_scale.py`",
       (VOLUMES, "Order 2 is slower: the P2 Newton matrix")),
    _r("endgame-resolve", "2026-12-06", "`python benchmarks/endgame_sweep.py --meshes max_planck.obj@subdiv1`",
       (BENCH, "a Clarabel re-solve cost 7–25× the time for a field equal within 1e-6")),
    _r("adapted-targets", "2026-12-07", "`python benchmarks/accuracy_per_second.py` (the last run: 00:41–00:45 UTC, "
       "run 16 of docs/dev/accuracy_per_second.md)",
       (BENCH, "the scans of 50K–100K faces reached ≤ 0.3 % at ≤ 3× heat on horse only"),
       (BENCH, "scans of 50K–100K faces reach ≤ 0.3 % at ≤ 3× heat on bunny (0.29 % at 2.5×) and horse"),
       (BENCH, "armadillo 0.295 % at 2.7×); fandisk 0.341 % at 7.3× heat, not ≤ 5×."),
       (BENCH, "bunny 0.202 % at 1.9×, horse 0.264 % at 1.8×, armadillo 0.298 % at 2.5×"),
       (BENCH, "bunny 0.202 % at 1.7×, horse 0.264 % at 1.9×, armadillo 0.298 % at 2.3×"),
       (BENCH, "5.9–6.0× at 0.1 and 6.9–7.4× for `\"auto\"`, so the CAD target is not settled by one run"),
       (BENCH, "0.439 % at 4.4× heat, and 4.6× in two more runs"), (README, "0.439 % at 4.4–4.6× heat with")),
    _r("choice-adapted", "2026-12-06", "`python benchmarks/accuracy_per_second.py --meshes spot.obj bimba.obj "
       "thingi_37881.stl bunny.obj armadillo.obj horse.ply --repeat 2`; `--meshes lucy_20k.obj dragon_20k.obj "
       "buddha.obj camelhead_open.off thingi_32770.stl beetle_open.off --repeat 2 --order2-max 0`; `--meshes "
       "fandisk.obj --repeat 2` (17:38–17:41 UTC, load 1.0, run 13 of docs/dev/accuracy_per_second.md)",
       (README, "| 0.71 / 0.31 / 1.39 % |"), (README, "| 0.79 / 0.43 / 2.43 % |"),
       (README, "0.20–0.30 % mean error at 1.8–2.5× the heat method's time"),
       (README, "it had 0.24–2.2 % mean error (the default: 0.92–3.8 %), a ridge of 0.29–0.60"),
       (ADAPTED, "the ridge figure goes from 0.76–1.03 to 0.29–0.37")),
    _r("adapted-switch", "2026-12-06", "`python benchmarks/accuracy_per_second.py` (run 12 of "
       "docs/dev/accuracy_per_second.md: the three invocations of choice-adapted); from n/2: " + NO_SCRIPT,
       (BENCH, "mean error 0.24–1.13 % against the default's 0.92–2.47 %")),
    _r("rows-default", "2026-12-06", "`python benchmarks/row_default.py`",
       (PERF, "0.063 s (28× heat), 2.04 %"), (PERF, "cost 1.5–2.3× `qclp`'s")),
    _r("adapted-source-snap", "2026-12-06", "`python benchmarks/adapted_levers.py fandisk`",
       (ADAPTED, "edge: mean error 1.95 %, max 108 %; snapped: 0.59 %")),
    _r("order2-source-corners", "2026-12-06", "`python benchmarks/source_position.py spot fandisk cylinder icosphere "
       "--faces 3` (and `--corners 0`); the vertex sources: " + NO_SCRIPT + " (docs/dev/adapted-log.md)",
       (ORDER2, "an icosphere 1.35–1.48 → 0.051–0.061 %")),
    _r("adapted-patch-reach", "2026-12-06", "`python benchmarks/accuracy_per_second.py` (vertex 0: runs 7 and 8 of "
       "docs/dev/accuracy_per_second.md); the 20 solves from vertex 0 and n/2, before and after: " + NO_SCRIPT +
       " (docs/dev/adapted-log.md)",
       (ADAPTED, "armadillo from vertex 0: 0.366 → 0.334 %, max 21.9 → 10.7 %")),
    _r("adapted-estimate-choice", "2026-12-06", "`python benchmarks/adapted_levers.py kitten fandisk bimba`",
       (ADAPTED, "0.59 % error), so it is not the estimate")),
    _r("adapted-table", "2026-12-06", "`python benchmarks/adapted_levers.py kitten fandisk bimba`",
       (ADAPTED, "was within 2× of the true mean error in 16 of these 18 rows")),
    _r("pointclouds-table", "2026-12-06",
       "`python benchmarks/point_clouds.py --quick` (19:26–19:32 UTC, load 0.5, one other job)",
       (POINTCLOUDS, "| cloud | noise | pc-heat | 8-NN Dijkstra |")),
    _r("pointclouds-max", "2026-12-06", "`python benchmarks/point_clouds.py --quick`",
       (POINTCLOUDS, "7–8 % for order 1 and 1.3–1.7 % for order 2")),
    _r("pointclouds-summary", "2026-12-06", "`python benchmarks/point_clouds.py --quick`; `--m 10` for m = 10",
       (POINTCLOUDS, "on the union is 15–21× more accurate than the point-cloud heat")),
    _r("pointclouds-resampled", "2026-12-06", "`python benchmarks/point_clouds.py --quick --resample 1.0,0.25 "
       "--noise 0 --sets union,repaired --repeats 1`; every other mesh (2026-12-07 02:34 UTC): `--meshes max_planck "
       "fandisk bug_surface dragon_20k lucy_20k buddha camelhead_open thingi_32770 bunny horse armadillo --resample "
       "1.0,0.25 --noise 0 --sets union --no-order2 --m 0 --resolution 0.25 --repeats 1`",
       (POINTCLOUDS, "| kitten, every face | 18,894 |"),
       (POINTCLOUDS, "| armadillo (86K / 21K) | 0.602 / **0.717** % | 0.609 / 1.60 %, 1.6 / 2.1× |")),
    _r("pointclouds-uneven", "2026-12-06", "`python benchmarks/point_clouds.py --meshes fandisk max_planck --sets "
       "union,repaired --repeats 1`; the re-measurement: `--sets union --no-order2 --repeats 2`",
       (POINTCLOUDS, "| fandisk | 0 | 3.44 %, 1× | 2.93 %, 0.07× | 0.681 %, 6.9× |"),
       (POINTCLOUDS, "the default at 5.67 / 3.77 / 2.69× pc-heat's time on fandisk (0 / 0.1 / 0.3 % noise) and 3.17 / "
                     "3.09 / 2.60× on")),
    _r("pointclouds-neighbours", "2026-12-06", "`python benchmarks/point_clouds.py --neighbours 20,30 --repeats 1` "
       "with `--quick`; `--meshes fandisk max_planck`; `--quick --resample 1.0,0.25 --noise 0`",
       (POINTCLOUDS, "on fandisk 0.49–0.80× its mean error")),
    _r("pointclouds-outliers", "2026-12-06", "`python benchmarks/cloud_outliers.py --resample 1.0,0.25`; `--no-plant "
       "--meshes …` for the 12 other meshes", (POINTCLOUDS, "1,384 of 1,440 found")),
    _r("pointclouds-normals", "2026-12-06", "`python benchmarks/point_clouds.py --meshes kitten bimba max_planck "
       "fandisk --sets union --normals --repeats 1` (load 0.5); `--meshes fandisk max_planck --resample 1.0 --noise 0 "
       "--sets union --normals --repeats 1`; the statues (2026-12-07 02:19 UTC): `--meshes dragon_20k buddha "
       "camelhead_open lucy_20k --noise 0 --sets union --m 0 --normals --repeats 1`",
       (POINTCLOUDS, "| fandisk vertices | 0 | 3.44 % (36.7 %) |"),
       (POINTCLOUDS, "with its vertex normals order 2 goes from 3.34 % to 0.058 % (59× below pc-heat"),
       (POINTCLOUDS, "| camelhead_open | 6.32 % | 5.95 / 5.30 / 5.67 % | 2.89 / 1.79 / 4.45 % |")),
    _r("pointclouds-resolution", "2026-12-06", "`python benchmarks/point_clouds.py --meshes kitten bimba max_planck "
       "fandisk --sets union --no-order2 --resolution auto --repeats 2` (16:10 UTC, load 0.3–0.6; the envelope: 15:57 "
       "UTC, load 0.6, against 15:52 UTC, load 0.3–1.0; with three decimation tries: 14:48 UTC, load 0.4–0.8)",
       (POINTCLOUDS, "3.50 / 3.69 / 4.98 % on the CAD part"), (POINTCLOUDS, "(2.4–2.7× pc-heat's time)")),
    _r("pointclouds-default", "2026-12-07", "`CVXGEODESIC_THREADS=1 python benchmarks/point_clouds.py --meshes kitten "
       "bimba max_planck fandisk --sets union --no-order2 --repeats 2` (two runs, 09:06 and 09:07 UTC, load 0.8–0.9; "
       "before denoise='auto': 07:42 and 07:43 UTC, load 1.1–1.3; 06:33 and 06:34 UTC, load 0.3–0.7; 05:02 and 05:04 "
       "UTC, load 0.7–0.9, and 00:27 UTC, load 0.8); the same with `--meshes bunny horse armadillo lucy_20k "
       "dragon_20k buddha camelhead_open bug_surface thingi_32770 --repeats 1` (09:08 UTC); the noise readings, "
       "(2026-12-06) the noisier draws and the small clouds' denoised copies (scratch scripts): " + NO_SCRIPT,
       (POINTCLOUDS, "| kitten | 0 / 0.1 / 0.3 % | 1.32 / 1.54 / 7.73 % |"),
       (POINTCLOUDS, "the default had 0.11–0.50 clean"),
       (POINTCLOUDS, "2.0–2.9× its time (order 1 on the points as given, the default before: 0.37, 0.32 and 0.63 at"),
       (POINTCLOUDS, "0.09–0.46 on kitten, bimba and the CAD part (max_planck's vertex cloud, 5,272 points, stays"),
       (POINTCLOUDS, "It reads 0.000–0.025 on the clean vertex clouds of 10 shared scans"),
       (POINTCLOUDS, "from 12 to 30 neighbours by 2.2–2.7× on those two"),
       (POINTCLOUDS, "max_planck 2.0–2.2 % against 1.3–1.4 %")),
    _r("pointclouds-clean-all", "2026-12-07", "`python benchmarks/point_clouds.py --meshes bunny horse armadillo "
       "lucy_20k dragon_20k buddha camelhead_open bug_surface thingi_32770 --noise 0 --sets union --m 0 --normals "
       "--resolution 0.25,0.5 --repeats 1` (02:08 UTC, load 0.6–1.0); `--meshes armadillo thingi_32770 --noise 0 "
       "--sets union,repaired,consensus --m 0 --repeats 1` (01:45 UTC); why the statues miss: `python "
       "benchmarks/cloud_shortcuts.py` (03:00 UTC)",
       (POINTCLOUDS, "| bunny | 1.10 % | 0.052 %, 10.8× | 0.132 % at 1/2, 4.7× |"),
       (POINTCLOUDS, "camelhead_open's order 2 goes from 5.30 % to 0.42 %")),
    _r("pointclouds-clean-copy", "2026-12-07", "`CVXGEODESIC_THREADS=1 python benchmarks/point_clouds.py --noise 0 "
       "--sets union --no-order2 --m 0 --resolution tenth --repeats 2` and the same with `--resample 1.0,0.25 "
       "--repeats 1` (04:12–04:25 UTC, load 0.3–0.9; bug_surface and thingi_32770 by `--meshes`); with normals: "
       "`--meshes camelhead_open dragon_20k --noise 0 --sets union --no-order2 --m 0 --normals --repeats 1` (04:34 "
       "UTC); noisy clouds at 1/4: `--meshes kitten bimba max_planck fandisk bunny horse --noise 0.001 --sets union "
       "--no-order2 --m 0 --resolution 0.25 --repeats 1` (04:37 UTC); the noise readings, bug_surface's random points "
       "and the far points' fill: " + NO_SCRIPT,
       (POINTCLOUDS, "| kitten (9K) | 1.32 % | **0.151 %**, 3.1× (4,727) | 0.375 %, 2.3× (1,999) | 0.40 / 1.33 |"),
       (POINTCLOUDS, "the default had 0.18–1.01 of the 1/10 copy's"),
       (POINTCLOUDS, "the vertex clouds of the 13 shared scans and CAD parts 0.000–0.024")),
    _r("pointclouds-random-all", "2026-12-07", "`CVXGEODESIC_THREADS=1 python benchmarks/point_clouds.py --resample "
       "1.0,0.25 --noise 0 --sets union --no-order2 --m 0 --repeats 1` (06:50 UTC, load 0.6–0.9)",
       (POINTCLOUDS, "pc-heat's error on all 26 clouds, at most half on 15")),
    _r("pointclouds-random-noisy", "2026-12-07", "`CVXGEODESIC_THREADS=1 python benchmarks/point_clouds.py --resample "
       "1.0,0.25 --noise 0.001,0.003 --sets union --no-order2 --m 0 --repeats 1` (09:11 UTC, load 0.9; before "
       "denoise='auto': 06:56 UTC)",
       (POINTCLOUDS, "the default had 0.07–1.77 of pc-heat's error (mean 0.52), at most half on 32"),
       (POINTCLOUDS, "| 0.07–1.77 (at most 0.5 on 32, above 1 on 7) | 1.4–4.2× |")),
    _r("pointclouds-default-all", "2026-12-07", "`CVXGEODESIC_THREADS=1 python benchmarks/point_clouds.py --meshes "
       "bunny horse armadillo lucy_20k dragon_20k buddha camelhead_open bug_surface thingi_32770 --sets union "
       "--no-order2 --repeats 1` (09:08 UTC, load 0.9; before denoise='auto': 06:47 UTC; 2026-12-06 19:46 UTC)",
       (POINTCLOUDS, "| bunny | 0 / 0.1 / 0.3 % | 1.10 / 2.99 / 15.4 % |"),
       (POINTCLOUDS, "Denoised, it was more accurate than order 1 on the points as given on 8 of the 13 noisy"),
       (POINTCLOUDS, "more accurate than order 1 on 10 of these 12 clouds (0.17–0.90 of its")),
    _r("pointclouds-noisy-copy", "2026-12-06", "`python benchmarks/point_clouds.py --meshes kitten bimba max_planck "
       "fandisk --sets union --no-order2 --noise 0.001,0.003 --denoise 2 --resolution auto --repeats 2` (19:49 UTC, "
       "load 1.2); `--meshes bunny horse armadillo lucy_20k dragon_20k buddha camelhead_open bug_surface thingi_32770 "
       "--m 0 --repeats 1` (19:52 UTC); the copy read at the raw points: " + NO_SCRIPT,
       (POINTCLOUDS, "| bimba | 0.3 % | 12.4 % | 3.93 %, 2.2× | **1.09 %**, 2.4× | 0.28 / 1.10 |"),
       (POINTCLOUDS, "on 15 of the 17 noisy clouds measured, at 0.98–1.94× the default's time"),
       (POINTCLOUDS, "(tried, not kept) lost on dragon_20k at 0.3 % (6.3 % against 2.8 %): the surface the")),
    _r("pointclouds-tilt", "2026-12-06", "`python benchmarks/point_clouds.py --meshes kitten bimba max_planck fandisk "
       "--sets union --no-order2 --repeats 2`, without the filter (17:04 UTC, load 0.3) and with it (17:11 UTC, load "
       "0.9); order 2: `--meshes max_planck fandisk kitten --noise 0 --sets union,repaired --repeats 1` (17:41 UTC) "
       "against the table of pointclouds-table; its cost (cProfile of PointCloud on kitten and max_planck), the angle "
       "alone and the thin box: " + NO_SCRIPT,
       (POINTCLOUDS, "| fandisk | 0 / 0.1 / 0.3 % | 5.24 → 1.84 / 4.97 → 2.30 / 6.05 → 3.95 % |"),
       (POINTCLOUDS, "It costs 0.01–0.03 s per cloud"),
       (POINTCLOUDS, "fandisk 3.34 → 0.206 % (1/17 of pc-heat's error"),
       (POINTCLOUDS, "fandisk's order-2 error on the union fell from 3.34 % to 0.206 %"),
       (POINTCLOUDS, "left out 20,030 of noisy bimba's 46K triangles"),
       (POINTCLOUDS, "grids 1.5–2.8 spacings apart")),
    _r("pointclouds-denoise-table", "2026-12-06", "`python benchmarks/point_clouds.py --meshes kitten bimba max_planck "
       "--sets union --denoise 1,2` (load 1.4 → 1.2)", (POINTCLOUDS, "| kitten | 0.3 % | 7.73 % | 0.80 % |"),
       (POINTCLOUDS, "70 % at order 1 and 77 % at order 2 raw, 86 % and 71 % denoised")),
    _r("pointclouds-denoise-sweep", "2026-12-06", "`python benchmarks/point_clouds.py --meshes kitten bimba max_planck "
       "--noise 0.0005,0.002,0.005,0.01 --sets union --denoise 2 --repeats 1` (load 1.1 → 1.3)",
       (POINTCLOUDS, "| kitten | 0.5 % (0.46) | 11.9 % |")),
    _r("pointclouds-denoise-cad", "2026-12-06", "`python benchmarks/point_clouds.py --meshes fandisk max_planck --sets "
       "union --denoise 2 --repeats 1` (load 0.3 → 0.6)", (POINTCLOUDS, "costs its clean order 2 7 % (3.34 → 3.58 %)")),
    _r("pointclouds-denoise-summary", "2026-12-06", "the two runs of pointclouds-denoise-table and -sweep; the closest-"
       "point geometry, the jet's median move and 24 neighbours: " + NO_SCRIPT,
       (POINTCLOUDS, "On the clean clouds it makes order 2's error 1.2–1.9× larger"),
       (POINTCLOUDS, "0.24 of the spacing on the clean"),
       (POINTCLOUDS, "made the clean clouds' order-2 error 2.1–2.4× larger")),
    _r("adapted-fold-retry", "2026-12-06", "`python benchmarks/accuracy_per_second.py --order2-max 0 --meshes "
       "bimba.obj lucy_20k.obj buddha.obj dragon_20k.obj camelhead_open.off kitten.obj fandisk.obj`",
       (ADAPTED, "the mean error falls from 1.95 % to 0.334 % (order 1 on the mesh: 1.13 %)"),
       (ADAPTED, "So 4 of the 5 refused settings of these meshes get a copy")),
    _r("adapted-estimate", "2026-12-06", "`python benchmarks/adapted_estimate.py MESH… [--source 0.5]` (17 shared "
       "surfaces >= 5K faces, sources vertex 0 and n/2); the cost: `python benchmarks/accuracy_per_second.py "
       "--order2-max 0`",
       (README, "within [0.5, 2] of the true mean error in 100 of 104 solves measured"),
       (ADAPTED, "was within [0.5, 2] of the true mean error in 100 of 104 solves (0.49–2.06×)"),
       (ADAPTED, "solves (the 8 other meshes, and every mesh from n/2) read 0.53–2.21× (3 outside)"),
       (ADAPTED, "surfaces of 5.9–97K faces: 1.6–3.6×, median 2.2×, where the coarser copy alone added 0.4–0.5×"),
       (README, "a coarser and a finer copy (1.6–3.6× the solve's time more)")),
]


# ---------------------------------------------------------------------------------------------- checking
def _decimals(x: float, text: str) -> int:
    """Decimals the page writes ``x`` with (``4.1`` → 1), read from the quoted text."""
    import re

    for num in re.findall(r"\d+(?:\.\d+)?", text):
        if abs(float(num) - x) < 1e-12:
            return len(num.partition(".")[2])
    return 2


def verdict(claim: Claim, values: dict[str, float]) -> str:
    """``inside`` when every value, rounded as the page rounds the bounds, lies in the quoted range."""
    if not values:
        return "not measured"
    if claim.quoted is None and claim.unit == " %":  # a table's cells, one per mesh: each within 5 % of its own
        import re

        cells = [float(x) for x in re.findall(r"\d+(?:\.\d+)?", claim.where[0][1])]
        ok = all(abs(v - q) <= 0.05 * q + 10 ** -_decimals(q, claim.where[0][1]) / 2
                 for v, q in zip(values.values(), cells, strict=False))
        return "inside" if ok and len(cells) == len(values) else "OUTSIDE"
    if claim.quoted is None:
        return "printed (machine-dependent)"
    if not values:
        return "not measured"
    lo, hi = claim.quoted
    text = " ".join(t for _, t in claim.where)
    d_lo, d_hi = _decimals(lo, text), _decimals(hi, text)
    inside = all(round(v, d_lo) >= lo and round(v, d_hi) <= hi for v in values.values())
    return "inside" if inside else "OUTSIDE"


def _fmt(v: float, unit: str = "") -> str:
    return f"{v:.0f}{unit}" if unit == " it." else f"{v:.3g}{unit}"


def describe(claim: Claim, values: dict[str, float], of: int) -> tuple[str, str]:
    """(measured range with the meshes, worst case) of a measured claim."""
    if not values:
        return "no mesh of this run", ""
    items = sorted(values.items(), key=lambda kv: kv[1])
    lo, hi = items[0], items[-1]
    worst = hi if claim.worst == "max" else lo
    if claim.quoted is None:  # a cell per mesh
        return " / ".join(_fmt(v, claim.unit) for _, v in values.items()) + f" ({' / '.join(values)})", ""
    span = f"{_fmt(lo[1])}–{_fmt(hi[1], claim.unit)}" if len(items) > 1 else _fmt(lo[1], claim.unit)
    meshes = {k.split(" ")[0] for k in values}  # a key is a mesh, or "mesh case"
    return f"{span} over {len(meshes)} meshes (of {of} in this run)", f"{worst[0]} {_fmt(worst[1], claim.unit)}"


def machine() -> str:
    model = ""
    with contextlib.suppress(OSError):
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    return f"{model or platform.processor() or platform.machine()}, {os.cpu_count()} cores, {platform.system()}"


def run(quick: bool, only: set[str] | None = None) -> tuple[dict[str, dict], dict[str, float]]:
    """Run every experiment a selected claim needs; → (results per experiment, seconds per experiment)."""
    import cvxgeodesic as cg

    warnings.simplefilter("ignore")
    cg.GeodesicSolver(cg.icosphere(1), "qclp", order=2).solve(0)  # load (or compile) the kernels, untimed
    cg.geodesic_distance(cg.icosphere(1), 0)
    needed = {c.experiment for c in CLAIMS if c.experiment and (only is None or c.id in only)}
    results, seconds = {}, {}
    for name, exp in EXPERIMENTS.items():
        if name not in needed:
            continue
        meshes = [m for m in (exp.quick if quick else exp.full) if m == "spot" or (SHARED / m).exists()]
        _progress(f"experiment {name}: {len(meshes)} meshes")
        t0 = time.perf_counter()
        results[name] = exp.run(meshes, quick)
        seconds[name] = time.perf_counter() - t0
    return results, seconds


def report(results: dict[str, dict], quick: bool, header: dict[str, str], seconds: dict[str, float]) -> str:
    """The Markdown page: one table row per claim, quoted beside measured."""
    lines = ["# Quoted figures, measured", "",
             "*This page is generated by `python benchmarks/claims.py --out docs/claims.md` (`make claims`): every "
             "time and accuracy figure README.md and docs/ quote, beside its value measured in one run (each further "
             "run in a section of its own). Do not edit it by hand.*", ""]
    lines += [f"- {k}: {v}" for k, v in header.items()]
    lines += ["", "Experiments (one process, one thread; each ratio against a baseline timed in the same run):", ""]
    for name, exp in EXPERIMENTS.items():
        if name in results:
            meshes = list(results[name])
            sub = f" (quick: {len(meshes)} of the {len(exp.full)} meshes of a full run)" if quick else ""
            lines.append(f"- `{name}`, {seconds.get(name, 0):.0f} s: {exp.what}. Meshes{sub}: "
                         + ", ".join(meshes) + ".")
    lines += ["", "| claim | quoted in | quoted | measured | worst case | |", "|---|---|---|---|---|---|"]
    records = []
    for c in CLAIMS:
        pages = ", ".join(dict.fromkeys(p for p, _ in c.where))
        text = " / ".join(f"“{' '.join(t.split())}”" for _, t in c.where).replace("|", "\\|")
        if c.record:
            records.append(f"| `{c.id}` | {pages} | {text} | {c.record} |")
            continue
        res = results.get(c.experiment or "")
        if res is None:
            lines.append(f"| `{c.id}` | {pages} | {text} | not run | | |")
            continue
        values = c.value(res) if c.value else {}
        measured, worst = describe(c, values, len(res))
        if quick:  # a subset: say so on the line
            measured += f" (quick: {len(res)} of the {len(EXPERIMENTS[c.experiment].full)} meshes of a full run)"
        lines.append(f"| `{c.id}` | {pages} | {text} | {measured}; {c.concerns} | {worst} | {verdict(c, values)} |")
    if records:
        lines += ["", "Dated records (a past run, a before/after or a development measurement quoted with its date):"
                  " not re-measured here; the command beside each measures it again.", "",
                  "| claim | quoted in | quoted | measured when, and by |", "|---|---|---|---|"] + records
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="a subset of the meshes (≤ 10 min on 2 cores)")
    ap.add_argument("--out", type=Path, help="also write the page here (docs/claims.md)")
    ap.add_argument("--only", nargs="*", help="claim ids to measure (default: all)")
    ap.add_argument("--list", action="store_true", help="print the registry and exit")
    ap.add_argument("--save", type=Path, help="also keep the measurements in this JSON file")
    ap.add_argument("--render", type=Path, nargs="+",
                    help="print (and --out) the page of --save files (one section per run), measuring nothing")
    args = ap.parse_args(argv)
    if args.list:
        for c in CLAIMS:
            print(f"{c.id:28s} {c.experiment or 'record':10s} " + "; ".join(f"{p}: {t!r}" for p, t in c.where))
        return 0
    if args.render:  # the same measurements against the registry as it is now (after a re-quote)
        pages = []
        for path in args.render:
            saved = json.loads(path.read_text(encoding="utf-8"))
            pages.append(report(saved["results"], saved["quick"], saved["header"], saved["seconds"]))
        # later runs as sections of the first one's page
        later = [p.split("\n- date:", 1)[1].split("\nDated records", 1)[0] for p in pages[1:]]
        page = "\n".join([pages[0]] + [f"## Another run\n\n- date:{p}" for p in later])
        print(page)
        if args.out:
            args.out.write_text(page, encoding="utf-8")
        return 0
    if not SHARED.is_dir():
        raise SystemExit(f"{SHARED}: the shared meshes are needed (../shared/meshes beside the checkout)")
    started, load0, t0 = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()), os.getloadavg(), time.perf_counter()
    results, seconds = run(args.quick, set(args.only) if args.only else None)
    load1 = os.getloadavg()
    header = {"date": started, "machine": machine(),
              "load average (1, 5, 15 min)": f"{' '.join(f'{x:.2f}' for x in load0)} at the start, "
                                             f"{' '.join(f'{x:.2f}' for x in load1)} at the end",
              "mode": ("quick (`--quick`: a subset of the meshes, named per experiment)" if args.quick
                       else "full (every shared mesh each figure concerns)") + ", one thread",
              "took": f"{time.perf_counter() - t0:.0f} s"}
    if args.save:
        args.save.write_text(json.dumps({"results": results, "quick": args.quick, "header": header,
                                         "seconds": seconds}, indent=1, default=float), encoding="utf-8")
    page = report(results, args.quick, header, seconds)
    print(page)
    if args.out:
        args.out.write_text(page, encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
