"""Accuracy and rounding of the smoothed formulations under the two normalizations of ``m``.

For every mesh: the exact (MMP) field from one source vertex, then QCLP and the smoothed method under
``normalization="area"`` (default) and ``"paper"``, with mean / off-ridge relative error, ridge
sharpness (``evaluation.smoothness``), the median of ``d / d_exact``, the share of vertices at 0 away
from the source, and the *deficit*: the area-weighted mean of ``(d_qclp − d)`` over the surface,
divided by the bounding-box diagonal (how much the smoothing lowers the field, measured on the surface,
so comparable across triangulations).

    python benchmarks/normalization_study.py --meshes bimba.obj spot.obj thingi_*.stl
    python benchmarks/normalization_study.py --kappa-sweep 1e-6,3e-6,1e-5 --meshes bimba.obj

Prints one Markdown table; ``--json`` writes the records.
"""

from __future__ import annotations

import argparse
import glob
import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import cvxgeodesic as cg
from cvxgeodesic.baselines import BASELINES
from cvxgeodesic.evaluation import error_stats, smoothness_report
from cvxgeodesic.problems import formulations

SHARED = Path(__file__).resolve().parents[1] / ".." / "shared" / "meshes"


def area_mean(mesh, values) -> float:
    """Area-weighted mean of a vertex field over the surface (barycentric lumped mass)."""
    w = formulations.stretch_weights(mesh, "area")
    ok = np.isfinite(values)
    return float(np.sum(w[ok] * values[ok]) / np.sum(w[ok]))


def field_metrics(mesh, d, d_exact, source, d_qclp=None) -> dict:
    src = np.array([source])
    st = error_stats(d, d_exact, src)
    sm = smoothness_report(mesh, d, d_exact, src)
    far = np.isfinite(d_exact) & (d_exact > 0.05 * np.nanmax(d_exact[np.isfinite(d_exact)]))
    ratio = d[far] / d_exact[far]
    out = {"rel_mean": st["rel_mean"], "rel_max": st["rel_max"], "off_ridge": sm["off_ridge_rel_mean"],
           "sharpness": sm["ridge_jump_p95"], "exact_sharpness": sm["exact_ridge_jump_p95"],
           "median_ratio": float(np.median(ratio)), "zeros": float(np.mean(d[far] <= 1e-9 * mesh.bbox_diagonal))}
    if d_qclp is not None:
        out["deficit"] = area_mean(mesh, d_qclp - d) / mesh.bbox_diagonal
    return out


def solve(mesh, method, source, **kw):
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = cg.GeodesicSolver(mesh, method, **kw).solve(source)
    return res.distance, time.perf_counter() - t0, res.info


def study_mesh(mesh, source: int, method: str, m: float, exact=None) -> list[dict]:
    d_exact = exact if exact is not None else BASELINES["exact"](mesh).solve(np.array([source]))[0]
    rows = []
    d_qclp, t, info = solve(mesh, "qclp", source)
    rows.append({"mesh": mesh.name, "faces": mesh.n_faces, "variant": "qclp (area stretch)", "time": t,
                 **field_metrics(mesh, d_qclp, d_exact, source, d_qclp)})
    d_u, t, info = solve(mesh, "qclp", source, normalization="paper")
    rows.append({"mesh": mesh.name, "faces": mesh.n_faces, "variant": "qclp (uniform stretch)", "time": t,
                 **field_metrics(mesh, d_u, d_exact, source, d_qclp)})
    for norm in ("area", "paper"):
        d, t, info = solve(mesh, method, source, m=m, normalization=norm)
        rows.append({"mesh": mesh.name, "faces": mesh.n_faces, "variant": f"{method} m={m:g} ({norm})", "time": t,
                     "notes": len(info.notes), **field_metrics(mesh, d, d_exact, source, d_qclp)})
    return rows


def kappa_sweep(mesh, source: int, method: str, kappas: list[float]) -> list[dict]:
    d_exact = BASELINES["exact"](mesh).solve(np.array([source]))[0]
    d_qclp, _, _ = solve(mesh, "qclp", source)
    rows = []
    energy = formulations.FORMULATIONS[method][1]
    for kappa in kappas:
        lam = kappa * float(np.sqrt(mesh.face_areas.sum()))
        d, t, _ = solve(mesh, method, source, lam=lam)
        rows.append({"mesh": mesh.name, "faces": mesh.n_faces, "variant": f"{method} κ={kappa:g} ({energy})",
                     "time": t, **field_metrics(mesh, d, d_exact, source, d_qclp)})
    d, t, _ = solve(mesh, method, source, normalization="paper")
    rows.append({"mesh": mesh.name, "faces": mesh.n_faces, "variant": f"{method} m=1 (paper)", "time": t,
                 **field_metrics(mesh, d, d_exact, source, d_qclp)})
    return rows


def table(rows: list[dict]) -> str:
    cols = [("mesh", "{}"), ("faces", "{:,}"), ("variant", "{}"), ("rel_mean", "{:.2%}"), ("off_ridge", "{:.2%}"),
            ("sharpness", "{:.3f}"), ("exact_sharpness", "{:.3f}"), ("deficit", "{:.2e}"),
            ("median_ratio", "{:.3f}"), ("zeros", "{:.1%}"), ("time", "{:.2f} s")]
    lines = ["| " + " | ".join(c for c, _ in cols) + " |", "|" + "---|" * len(cols)]
    for r in rows:
        lines.append("| " + " | ".join(fmt.format(r[c]) if c in r else "" for c, fmt in cols) + " |")
    return "\n".join(lines)


def resolve_meshes(names: list[str]) -> list[Path]:
    out = []
    for name in names:
        hits = sorted(glob.glob(str(SHARED / name))) or sorted(glob.glob(name))
        if not hits:
            raise SystemExit(f"no mesh matches {name!r} (looked in {SHARED})")
        out.extend(Path(h) for h in hits)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", nargs="+", default=["bimba.obj", "spot.obj"])
    ap.add_argument("--source", type=int, default=0)
    ap.add_argument("--method", default="qcqp-hessian")
    ap.add_argument("--m", type=float, default=1.0)
    ap.add_argument("--kappa-sweep", default=None, help="comma-separated κ values (λ = κ √|S|)")
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    rows = []
    for path in resolve_meshes(args.meshes):
        mesh = cg.load_mesh(path)
        if args.kappa_sweep:
            rows += kappa_sweep(mesh, args.source, args.method, [float(k) for k in args.kappa_sweep.split(",")])
        else:
            rows += study_mesh(mesh, args.source, args.method, args.m)
        print(f"done {mesh.name}", file=sys.stderr, flush=True)
    print(f"<!-- {time.strftime('%Y-%m-%d')}, source vertex {args.source}, "
          f"command: python benchmarks/normalization_study.py {' '.join(argv or sys.argv[1:])} -->")
    print(table(rows))
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1, default=float))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
