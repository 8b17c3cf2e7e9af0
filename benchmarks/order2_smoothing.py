"""Smoothing at order 2 (issue 25): what ``m`` means, accuracy on the CAD set and the fine scans, the cost.

Usage (``PYTHONPATH=src``; one thread each, other jobs state the load)::

    python benchmarks/order2_smoothing.py widths [--m=30,300,3000] [--energy=hessian]   # flat two-source widths
    python benchmarks/order2_smoothing.py order1-width                                    # order 1's m = 1, same case
    python benchmarks/order2_smoothing.py cad                     # the seven thingi_*.stl: order 1 vs order 2
    python benchmarks/order2_smoothing.py fine [--repeat=3] [mesh ...]   # bunny_7k, lucy_20k, bimba: error, time
    python benchmarks/order2_smoothing.py sphere                  # icosphere(3), one source: the issue's prototype
    python benchmarks/order2_smoothing.py ... --json=OUT.json     # also write the rows
    python benchmarks/order2_smoothing.py fine --jump=p2 --m=2    # the alternative jump term (docs/order2.md)

**Widths.** Two sources on the unit square, at the vertices nearest (0.25, 0.5) and (0.75, 0.5); the exact field
is the distance to the nearer one. The rounding width is that of the parabolic rounding with the same deficit
(:func:`cvxgeodesic.evaluation.rounding_width`): the deficit of the smoothed field integrated over a band 0.3 wide
around the ridge (:func:`~cvxgeodesic.evaluation.ridge_deficit`), minus the unsmoothed (``qclp``) field's at the
same order, over ``K = ∫ sin(θ/2) dl`` of the ridge. Two triangulations at three resolutions each: jittered grids
(right triangles, vertices moved by up to 1/4 cell) and anisotropic ones (cells 4× longer along the ridge).

Errors are relative, per vertex, sources excluded, against pygeodesic's exact MMP, source vertex 0.
"""

from __future__ import annotations

import json
import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import cvxgeodesic as cg
from cvxgeodesic.baselines import BASELINES
from cvxgeodesic.evaluation import ridge_deficit, rounding_width
from cvxgeodesic.problems.formulations import KAPPA_ORDER2

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "meshes"
CAD = ["thingi_243015.stl", "thingi_32770.stl", "thingi_37881.stl", "thingi_47076.stl", "thingi_65395.stl",
       "thingi_93703.stl", "thingi_96457.stl"]
FINE = ["bunny_7k.off", "lucy_20k.obj", "bimba.obj"]
#: Width of the band around the ridge over which the deficit is integrated (the unit square's side is 1).
BAND = 0.3
#: The two triangulations of the width study and their resolutions (cells across the ridge).
TRIANGULATIONS = {"jittered": (24, 32, 48, 64), "anisotropic": (32, 64, 128)}


def plane(kind: str, n: int) -> cg.TriMesh:
    """The unit square: ``"jittered"`` n × n cells, ``"anisotropic"`` n × n/4 (cells 4× taller than wide)."""
    mesh = cg.grid_plane(n, n if kind == "jittered" else n // 4, jitter=0.25, seed=7)
    mesh.name = f"{kind} {n}×{n if kind == 'jittered' else n // 4}"
    return mesh


def two_sources(mesh: cg.TriMesh) -> tuple[list[int], np.ndarray, float]:
    """Source vertices nearest (0.25, 0.5) and (0.75, 0.5), the exact field and ``K = 2a·asinh(1/(2a))`` (``2a``
    the sources' distance; the ridge is the bisector across the square)."""
    s = [int(np.argmin(np.linalg.norm(mesh.V[:, :2] - p, axis=1))) for p in ([0.25, 0.5], [0.75, 0.5])]
    exact = np.linalg.norm(mesh.V[:, None] - mesh.V[s], axis=2).min(axis=1)
    a = 0.5 * float(np.linalg.norm(mesh.V[s[0]] - mesh.V[s[1]]))
    return s, exact, 2 * a * float(np.arcsinh(0.5 / a))


def solve(mesh, sources, method: str, order: int, m: float = 1.0):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t = time.perf_counter()
        solver = cg.GeodesicSolver(mesh, method, order=order, m=m)
        res = solver.solve(sources)
        return res, time.perf_counter() - t


def deficit(mesh, d, exact, sources) -> dict:
    # exclude_radius 1: the default (3 longest edges) hides the ridge's middle on the anisotropic meshes
    return ridge_deficit(mesh, d, exact, BAND, sources=sources, exclude_radius=1.0)


def rounding(mesh, method: str, order: int, m: float) -> dict:
    """The added rounding of ``method`` at ``m`` on a two-source plane (against ``qclp`` at the same order)."""
    s, exact, K = two_sources(mesh)
    base = deficit(mesh, solve(mesh, s, "qclp", order)[0].distance, exact, s)
    res, t = solve(mesh, s, method, order, m)
    r = deficit(mesh, res.distance, exact, s)
    off = np.abs(mesh.V[:, 0] - 0.5) > 0.2
    return {"mesh": mesh.name, "faces": mesh.n_faces, "method": method, "order": order, "m": m, "lam": res.info.lam,
            "width": rounding_width(r["deficit_integral"] - base["deficit_integral"], K),
            "deficit_max": r["deficit_max"], "deficit_integral": r["deficit_integral"],
            "base_deficit_integral": base["deficit_integral"],
            "off_ridge_max_error": float(np.abs(res.distance - exact)[off].max() / exact.max()),
            "status": res.info.status, "time": t}


def widths(ms: list[float], energy: str = "hessian") -> list[dict]:
    rows = []
    for m in ms:
        print(f"m = {m:g} (λ = {m * KAPPA_ORDER2[energy]:.3g}), qcqp-{energy} at order 2:", flush=True)
        for kind, ns in TRIANGULATIONS.items():
            for n in ns:
                r = rounding(plane(kind, n), f"qcqp-{energy}", 2, m)
                rows.append(r)
                print(f"  {r['mesh']:22s} {r['faces']:6d} faces  width {r['width']:.4f}  max lowering "
                      f"{r['deficit_max']:.2e}  off-ridge error {r['off_ridge_max_error']:.1e}  {r['status']}",
                      flush=True)
        w = [r["width"] for r in rows if r["m"] == m]
        print(f"  spread max/min {max(w) / min(w):.2f}", flush=True)
    return rows


def order1_width() -> list[dict]:
    """Order 1's ``qcqp-hessian`` at m = 1 on the same case (its rounding against its own ``qclp``)."""
    rows = []
    for n in (64, 128):
        r = rounding(plane("jittered", n), "qcqp-hessian", 1, 1.0)
        rows.append(r)
        print(f"order 1, m = 1: {r['mesh']:22s} width {r['width']:.4f}  max lowering {r['deficit_max']:.2e}",
              flush=True)
    return rows


def rel_err(d, de) -> tuple[float, float]:
    ok = np.isfinite(de) & (de > 1e-12 * np.nanmax(de[np.isfinite(de)]))
    r = np.abs(d[ok] - de[ok]) / de[ok]
    return float(np.mean(r)), float(np.max(r))


def exact_field(mesh) -> np.ndarray:
    return np.asarray(BASELINES["exact"](mesh).solve(np.array([0]))[0], dtype=float)


def collapsed(d, de) -> bool:
    """A field that lost its shape: non-finite where the exact one is finite, or its largest value below half
    the exact one's."""
    fin = np.isfinite(de)
    return bool(not np.isfinite(d[fin]).all() or d[fin].max() < 0.5 * de[fin].max())


def cad(names: list[str] | None = None) -> list[dict]:
    """Order 1 and order 2, ``qclp`` and ``qcqp-hessian`` (m = 1), on the coarse CAD set."""
    rows = []
    runs = (("o1_qclp", "qclp", 1), ("o1_hessian", "qcqp-hessian", 1), ("o2_qclp", "qclp", 2),
            ("o2_hessian", "qcqp-hessian", 2))
    for nm in names or CAD:
        mesh = cg.load_mesh(SHARED / nm)
        de = exact_field(mesh)
        row = {"mesh": nm, "faces": mesh.n_faces}
        for tag, meth, order in runs:
            res, t = solve(mesh, 0, meth, order)
            mean, mx = rel_err(res.distance, de)
            row[tag] = {"mean": mean, "max": mx, "time": t, "status": res.info.status, "solver": res.info.solver,
                        "collapsed": collapsed(res.distance, de)}
        row["ratio"] = row["o2_hessian"]["mean"] / row["o1_hessian"]["mean"]
        rows.append(row)
        print(f"{nm:18s} {mesh.n_faces:6d}  " + "  ".join(
            f"{tag} {100 * row[tag]['mean']:.2f}%{' COLLAPSED' if row[tag]['collapsed'] else ''}"
            f"{'' if row[tag]['status'] == 'optimal' else ' ' + row[tag]['status']}" for tag, _, _ in runs)
            + f"  o2/o1 hessian {row['ratio']:.3f}", flush=True)
    print(f"median ratio order-2 / order-1 qcqp-hessian: {np.median([r['ratio'] for r in rows]):.3f}; "
          f"collapsed: {sum(r[t]['collapsed'] for r in rows for t, _, _ in runs)}", flush=True)
    return rows


def fine(names: list[str] | None = None, repeat: int = 3, m: float = 1.0) -> list[dict]:
    """Order-2 ``qclp`` against the smoothed order-2 methods (m = 1): errors, and set-up + solve times of
    ``qclp`` and ``qcqp-hessian`` in alternating runs (minimum of ``repeat``)."""
    solve(cg.icosphere(1), 0, "qcqp-hessian", 2)  # compile or load the kernels outside the timings
    rows = []
    for nm in names or FINE:
        mesh = cg.load_mesh(SHARED / nm)
        de = exact_field(mesh)
        row = {"mesh": nm, "faces": mesh.n_faces, "load_before": os.getloadavg()}
        times: dict[str, list[float]] = {"qclp": [], "qcqp-hessian": []}
        for _ in range(repeat):
            for meth in times:
                res, t = solve(mesh, 0, meth, 2, m)
                times[meth].append(t)
                row[meth] = {"mean": rel_err(res.distance, de)[0], "max": rel_err(res.distance, de)[1],
                             "status": res.info.status, "iterations": res.info.iterations}
        for meth in ("qcqp-laplacian", "qcqp-dirichlet"):
            res, t = solve(mesh, 0, meth, 2, m)
            row[meth] = {"mean": rel_err(res.distance, de)[0], "max": rel_err(res.distance, de)[1],
                         "status": res.info.status, "time": t}
        for meth, ts in times.items():
            row[meth]["time"] = min(ts)
            row[meth]["times"] = ts
        row["error_ratio"] = row["qcqp-hessian"]["mean"] / row["qclp"]["mean"]
        row["time_ratio"] = row["qcqp-hessian"]["time"] / row["qclp"]["time"]
        row["load_after"] = os.getloadavg()
        rows.append(row)
        print(f"{nm:14s} {mesh.n_faces:6d}  qclp {100 * row['qclp']['mean']:.3f}% {row['qclp']['time']:.2f}s  "
              f"hessian {100 * row['qcqp-hessian']['mean']:.3f}% {row['qcqp-hessian']['time']:.2f}s  "
              f"laplacian {100 * row['qcqp-laplacian']['mean']:.3f}%  "
              f"dirichlet {100 * row['qcqp-dirichlet']['mean']:.3f}%"
              f"  error ×{row['error_ratio']:.2f}  time ×{row['time_ratio']:.2f}  load "
              f"{row['load_before'][0]:.1f}–{row['load_after'][0]:.1f}", flush=True)
    return rows


def sphere(ms=(0.0, 1.0, 10.0, 100.0, 1000.0)) -> list[dict]:
    """icosphere(3), source vertex 0: mean error against the great-circle distance and the antipode's lowering."""
    mesh = cg.icosphere(3)
    V = mesh.V / np.linalg.norm(mesh.V, axis=1, keepdims=True)
    great = np.arccos(np.clip(V @ V[0], -1, 1))
    anti = int(np.argmax(great))
    rows = []
    for m in ms:
        res, t = solve(mesh, 0, "qcqp-hessian" if m else "qclp", 2, m)
        row = {"m": m, "lam": res.info.lam, "mean": rel_err(res.distance, great)[0],
               "antipode_lowered": float(great[anti] - res.distance[anti]), "time": t}
        rows.append(row)
        print(f"m = {m:6g} (λ = {row['lam']:.2g}): mean error {100 * row['mean']:.2f}%, antipode lowered by "
              f"{row['antipode_lowered']:.3f}", flush=True)
    return rows


def use_jump(jump: str) -> None:
    """Build every order-2 energy with this form of the jump term (``squared_energy(..., jump=jump)``)."""
    import functools

    import cvxgeodesic.problems.squared_distance as fp2
    from cvxgeodesic.operators.squared_energy import squared_energy

    fp2.squared_energy = functools.partial(squared_energy, jump=jump)


def main(argv: list[str]) -> None:
    opts = {a.split("=", 1)[0]: a.split("=", 1)[1] for a in argv if a.startswith("--") and "=" in a}
    args = [a for a in argv if not a.startswith("--")]
    what = args.pop(0) if args else "widths"
    if "--jump" in opts:
        use_jump(opts["--jump"])
    print(f"{time.strftime('%Y-%m-%d %H:%M')}, load {' '.join(f'{x:.2f}' for x in os.getloadavg())}, "
          f"threads {os.environ.get('CVXGEODESIC_THREADS', 'default')}", flush=True)
    if what == "widths":
        ms = [float(x) for x in opts.get("--m", "30,300,3000").split(",")]
        rows = widths(ms, opts.get("--energy", "hessian"))
    elif what == "order1-width":
        rows = order1_width()
    elif what == "cad":
        rows = cad(args or None)
    elif what == "fine":
        rows = fine(args or None, int(opts.get("--repeat", "3")), float(opts.get("--m", "1")))
    elif what == "sphere":
        rows = sphere()
    else:
        raise SystemExit(f"unknown measurement {what!r}; see the module docstring")
    if "--json" in opts:
        Path(opts["--json"]).write_text(json.dumps(rows, indent=1, default=float))


if __name__ == "__main__":
    main(sys.argv[1:])
