"""Reproduce the paper's experiments as a results report: ``docs/results.md`` + ``docs/figures/*.png``.

Usage (``make report`` runs the first line)::

    python benchmarks/report.py --out docs                       # every section; finished ones are skipped
    python benchmarks/report.py --out docs --sections fig4 fig9  # recompute these sections only
    python benchmarks/report.py --out docs --fresh               # drop all caches first
    python benchmarks/report.py --out /tmp/r --quick             # small meshes only (development)
    python benchmarks/report.py --out docs --sections order2 --order2-large   # order 2 on thingi_32770 too

Paper: *Convex Quadratic Programming for Computing Geodesic Distances on Triangle Meshes*,
Mathematics 12(7):993, 2024. Meshes come from ``--shared`` (default ``../shared/meshes`` next to the
repository). Each section caches its numbers in ``report_output/cache/sections`` and every distance
field in ``report_output/cache/fields``, so a rerun after an interruption continues where it stopped;
``results.md`` is rewritten from all cached sections at the end of every run.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import sys
import time
from pathlib import Path

import numpy as np

import cvxgeodesic as cg
from report_common import (
    COLORS,
    DEFAULT_SHARED,
    MARKERS,
    PANEL_DPI,
    REPO,
    Context,
    dump_json,
    environment,
    label,
    log,
    metrics,
    save_figure,
    save_png,
    solve,
    solver_text,
    status_text,
    submesh,
    tile,
)

SOURCE = 0
PAPER = {  # the paper's Table 2 figures we are sure of (MATLAB + Mosek, their machine and their meshes)
    "bunny": {"faces": "28K", "time_s": 20.5},
    "bimba": {"faces": "51K", "time_s": 35.8},
    "dragon": {"faces": "240K", "time_s": 501.5},
}
PAPER_MEAN_ERR = (0.46, 0.94)  # percent

TABLE2_MESHES = ["bunny.obj", "bimba.obj", "horse.ply", "lucy_20k.obj", "dragon_20k.obj"]
TABLE2_METHODS = ["qcqp-hessian", "heat", "dijkstra", "fmm", "lcqp-hessian", "exact", "qclp"]
SWEEP_M = [0.0, 0.1, 0.3, 1.0, 3.0, 10.0]
SWEEP_ENERGIES = ["qcqp-dirichlet", "qcqp-laplacian", "qcqp-hessian"]
RES_TARGETS = [5000, 20000]
RES_METHODS = ["qcqp-hessian", "qclp", "heat", "fmm"]
THINGI_METHODS = ["qcqp-hessian", "qclp", "lcqp-hessian", "heat", "fmm", "dijkstra"]
#: Order-2 section: (tag, method, order) of the compared fields; exact MMP is the reference.
ORDER2_METHODS = (("p1", "qclp", 1), ("p2", "qclp", 2), ("heat", "heat", 1), ("fmm", "fmm", 1))
#: Also solved on the CAD set: order 1 with the uniform stretch (the default before issue 12's area
#: normalization, and the order 1 of the stored run behind docs/order2.md).
ORDER2_EXTRA = (("p1u", "qclp", 1, "paper"),)
ORDER2_MAX_FACES = 10_000  # above: minutes per order-2 solve (thingi_32770, 38K faces: ~590 s)
ORDER2_QUICK_CAD = ["thingi_93703.stl", "thingi_96457.stl", "thingi10k_small/43858.stl",  # 96457: left out
                    "thingi10k_small/100036.stl", "thingi10k_small/54228.stl", "thingi10k_small/93068.stl"]
ORDER2_STORED = "benchmarks/order2_results/cad_default.json"  # the run behind docs/order2.md's tables
ORDER2_STORED_LOAD = "≈ 4"  # its 1-minute load average (2026-12-01 22:33 UTC, on 2 cores shared with two jobs)
ORDER2_FIGURE_CASE = ("CAD plate of fans", 5)  # the flat case and vertex source of the error-map figure
#: Smoothing at order 2 (issue 25): (tag, method, order, m) of the compared fields.
SMOOTH_RUNS = (("o1_qclp", "qclp", 1, 1.0), ("o1_hessian", "qcqp-hessian", 1, 1.0), ("o2_qclp", "qclp", 2, 1.0),
               ("o2_hessian", "qcqp-hessian", 2, 1.0), ("o2_hessian_30", "qcqp-hessian", 2, 30.0),
               ("o2_hessian_300", "qcqp-hessian", 2, 300.0))
SMOOTH_MESHES = ["bunny_7k.off", "lucy_20k.obj", "bimba.obj"]
SMOOTH_CAD = ["thingi_243015.stl", "thingi_37881.stl", "thingi_47076.stl", "thingi_65395.stl", "thingi_96457.stl",
              "thingi_93703.stl"]  # the coarse CAD set of issue 25 but thingi_32770 (38K faces, minutes per solve)
SMOOTH_BAND = 0.05  # width of the band around the cut locus for the ridge deficit, in bounding-box diagonals
MEDIAL_METHODS = ["exact", "fmm", "qcqp-hessian", "lcqp-hessian", "heat", "dijkstra", "qclp", "qcqp-laplacian",
                  "qcqp-dirichlet", "lclp"]


class Plan:
    """Which meshes each section uses (``--quick`` swaps in small ones for development).

    ``order2_large``: the order-2 section also solves the CAD meshes above ``ORDER2_MAX_FACES`` faces
    (thingi_32770, 38K faces, took ~590 s); by default it quotes the stored run for them.
    """

    def __init__(self, quick: bool, order2_large: bool = False):
        self.quick = quick
        self.order2_quick_cad = ORDER2_QUICK_CAD if quick else None  # None: the whole coarse CAD set
        self.order2_max_faces = None if order2_large else 1000 if quick else ORDER2_MAX_FACES
        self.table2 = ["spot.obj", "bunny_7k.off"] if quick else TABLE2_MESHES
        self.hist_pair = ("bunny_7k.off", "bunny.obj") if not quick else ("spot.obj", "bunny_7k.off")
        self.one = "spot.obj" if quick else "bimba.obj"  # Fig. 3, 4, 9
        self.res_base = "bunny_7k.off" if quick else "bunny.obj"
        self.res_targets = [1000, 3000] if quick else RES_TARGETS
        self.fig6 = "bunny_7k.off" if quick else "bunny.obj"
        self.sweep_m = [0.0, 1.0, 10.0] if quick else SWEEP_M
        self.smooth_plane = 24 if quick else 48  # cells of the two-source plane of the smoothing section
        self.smooth_meshes = ["spot.obj"] if quick else SMOOTH_MESHES  # the first one also gets a close-up
        self.smooth_cad = SMOOTH_CAD[-2:] if quick else SMOOTH_CAD


# ----------------------------------------------------------------------------------------------------------------------
# helpers
# ----------------------------------------------------------------------------------------------------------------------


def log_axis(ax, axis: str = "y") -> None:
    """Log scale with plain-number tick labels (1, 2, 5, 10, ...)."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    getattr(ax, f"set_{axis}scale")("log")
    a = ax.yaxis if axis == "y" else ax.xaxis
    a.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 3.0, 5.0)))
    a.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    a.set_minor_formatter(NullFormatter())


def mesh_row(mesh) -> dict:
    from cvxgeodesic.evaluation import mesh_anisotropy

    return {"name": mesh.name, "vertices": mesh.n_vertices, "faces": mesh.n_faces,
            "manifold": bool(mesh.is_edge_manifold), "components": int(len(np.unique(mesh.component_labels))),
            "tau": mesh_anisotropy(mesh), "bbox_diag": mesh.bbox_diagonal, "h": mesh.mean_edge_length}


def rec_row(rec: dict, mets: dict | None = None) -> dict:
    row = {k: rec.get(k) for k in ("method", "ok", "solver", "status", "time_s", "setup_s", "solve_s", "iterations",
                                   "fallback", "error", "warnings", "m", "resolved_nonnegative")}
    row["solver_text"] = solver_text(rec)
    row["attempts"] = rec.get("attempts")
    if rec.get("fallback") and rec.get("attempts"):
        row["ipm_time_s"] = rec["attempts"][0].get("time_s")
    row["status_text"] = status_text(rec)
    if mets:
        row.update(mets)
    return row


def evaluate(ctx, mesh, key, methods, source=SOURCE, m=1.0, exact=None):
    """Solve every method (cached), measure against the exact field; returns (rows by method, exact record)."""
    if exact is None:
        exact = solve(ctx, mesh, key, "exact", source)
    d_ex = exact["distance"]
    rows = {}
    for meth in methods:
        rec = exact if meth == "exact" else solve(ctx, mesh, key, meth, source, m)
        mets = None
        if rec["ok"] and d_ex is not None and meth != "exact":
            mets = metrics(mesh, rec["distance"], d_ex, source)
        elif meth == "exact" and rec["ok"]:
            mets = metrics(mesh, d_ex, d_ex, source)
        rows[meth] = rec_row(rec, mets)
    return rows, exact


def fin_max(d) -> int:
    """Index of the largest finite value."""
    return int(np.argmax(np.where(np.isfinite(d), d, -np.inf)))


def panel(ctx, name: str) -> Path:
    return ctx.panels / f"{name}.png"


def field_panel(ctx, mesh, d, name, title, *, vmin=0.0, vmax=None, levels=None, sources=(SOURCE,), view=None):
    from cvxgeodesic.plotting import plot_field

    p = panel(ctx, name)
    plot_field(mesh, d, p, isolines=levels if levels is not None else 20, title=title, vmin=vmin, vmax=vmax,
               dpi=PANEL_DPI, colorbar_label="distance", sources=list(sources) if sources else None, view=view)
    return p


def error_panel(ctx, mesh, rel, name, title, vmax, sources=(SOURCE,)):
    from cvxgeodesic.plotting import plot_error_map

    p = panel(ctx, name)
    plot_error_map(mesh, rel, p, title=title, vmax=vmax, dpi=PANEL_DPI, sources=list(sources))
    return p


def ridge_crop(mesh, d_exact, source, *, radius_frac=0.07):
    """A patch of the surface around a stretch of the exact field's ridge (for close-ups of the isolines).

    The ridge shows as edges where the exact field has a concave crease (signed normal-derivative jump
    below -0.5, fronts meeting at more than about 29°) at more than 30 % of the maximum distance. The centre
    is the crease vertex with the most crease edges within 0.6 patch radii; the patch is the connected piece
    of the faces within ``radius_frac`` bounding-box diagonals of it.
    Returns (patch mesh, vertex ids in ``mesh``, centre vertex).
    """
    from cvxgeodesic.evaluation import edge_gradient_jumps

    edges, jump = edge_gradient_jumps(mesh, d_exact, signed=True)
    fin = np.isfinite(d_exact)
    dmax = float(d_exact[fin].max())
    mid = 0.5 * (d_exact[edges[:, 0]] + d_exact[edges[:, 1]])
    crease = np.isfinite(jump) & (jump < -0.5) & (mid > 0.3 * dmax) & np.isfinite(mid)
    r = radius_frac * mesh.bbox_diagonal
    cand = np.unique(edges[crease].ravel())
    if cand.size == 0:
        cand = np.array([int(np.argmax(np.where(fin, d_exact, -1)))])
    cpts = 0.5 * (mesh.V[edges[crease, 0]] + mesh.V[edges[crease, 1]])
    if cand.size > 500:
        cand = np.random.default_rng(0).choice(cand, 500, replace=False)
    score = [int(np.sum(np.linalg.norm(cpts - mesh.V[c], axis=1) < 0.6 * r)) for c in cand]
    center = int(cand[int(np.argmax(score))])
    inside = np.linalg.norm(mesh.V - mesh.V[center], axis=1) < r
    fmask = inside[mesh.F].all(axis=1)
    sub, used = submesh(mesh, fmask, f"{mesh.name} (close-up)")
    lab = sub.component_labels
    keep = lab[sub.F[:, 0]] == lab[int(np.searchsorted(used, center))]
    fmask2 = np.zeros(mesh.n_faces, dtype=bool)
    fmask2[np.flatnonzero(fmask)[keep]] = True
    sub, used = submesh(mesh, fmask2, f"{mesh.name} (close-up)")
    return sub, used, center


# ----------------------------------------------------------------------------------------------------------------------
# sections: compute (numbers + figures)
# ----------------------------------------------------------------------------------------------------------------------


def sec_table2(ctx, plan):
    out = {"meshes": [], "rows": {}}
    for name in plan.table2:
        mesh = ctx.mesh(name)
        log(f"  Table 2: {name} ({mesh.n_faces} faces)")
        rows, _ = evaluate(ctx, mesh, name, TABLE2_METHODS)
        out["meshes"].append(mesh_row(mesh))
        out["rows"][name] = rows
    return out


def sec_fig2(ctx, plan):
    from cvxgeodesic.evaluation import gradient_norm_histogram
    from cvxgeodesic.operators import gradient_norms
    from cvxgeodesic.plotting import plot_gradient_histogram

    res = {"meshes": [], "stats": {}}
    hists = {}
    edges = np.linspace(0.0, 1.6, 129)
    for name in plan.hist_pair:
        mesh = ctx.mesh(name)
        ex = solve(ctx, mesh, name, "exact", SOURCE)
        d = ex["distance"]
        norms = gradient_norms(mesh, d)
        srcmask = np.zeros(mesh.n_vertices, bool)
        srcmask[SOURCE] = True
        at_src = srcmask[mesh.F].any(axis=1)
        a = mesh.face_areas
        st = {"triangles": int(mesh.n_faces), "source_triangles": int(at_src.sum())}
        for tag, sel in (("all", np.ones_like(at_src)), ("no_src", ~at_src)):
            nn, aa = norms[sel], a[sel]
            st[tag] = {
                "count_above_1.01": int(np.sum(nn > 1.01)), "count_above_1.05": int(np.sum(nn > 1.05)),
                "frac_above_1.05": float(np.mean(nn > 1.05)), "area_above_1.01": float(aa[nn > 1.01].sum() / aa.sum()),
                "count_below_0.99": int(np.sum(nn < 0.99)),
                "count_below_0.9": int(np.sum(nn < 0.9)),
                "frac_above_1.01": float(np.mean(nn > 1.01)), "frac_below_0.99": float(np.mean(nn < 0.99)),
                "frac_below_0.9": float(np.mean(nn < 0.9)),
                "area_below_0.99": float(aa[nn < 0.99].sum() / aa.sum()),
                "area_below_0.9": float(aa[nn < 0.9].sum() / aa.sum()),
                "max": float(nn.max()), "min": float(nn.min()),
            }
        res["stats"][name] = st
        res["meshes"].append(mesh_row(mesh))
        lab = f"{name} ({mesh.n_faces / 1000:.0f}K faces)"
        hists[lab] = gradient_norm_histogram(mesh, d, bins=edges, sources=None)
    fig = ctx.figures / "fig2_gradient_histograms.png"
    plot_gradient_histogram(hists, fig, title="‖∇d‖ per triangle of the exact field (area-weighted, all triangles)",
                            dpi=90)
    res["figures"] = [fig.name]
    return res


def sec_fig3(ctx, plan):
    from cvxgeodesic.evaluation import relative_error

    name = plan.one
    mesh = ctx.mesh(name)
    rows, exact = evaluate(ctx, mesh, name, ["lclp", "qclp", "dijkstra"])
    d_ex = exact["distance"]
    lclp = solve(ctx, mesh, name, "lclp", SOURCE)
    qclp = solve(ctx, mesh, name, "qclp", SOURCE)
    dij = solve(ctx, mesh, name, "dijkstra", SOURCE)
    checks = {}
    if lclp["ok"] and dij["ok"]:
        checks["lclp_minus_dijkstra_max_abs_over_diag"] = float(
            np.max(np.abs(lclp["distance"] - dij["distance"])) / mesh.bbox_diagonal)
    if qclp["ok"] and dij["ok"]:
        checks["qclp_minus_dijkstra_max_over_diag"] = float(
            np.max(qclp["distance"] - dij["distance"]) / mesh.bbox_diagonal)
        checks["qclp_below_dijkstra_share"] = float(np.mean(qclp["distance"] <= dij["distance"] + 1e-9))
    panels = []
    dmax = float(np.max(d_ex[np.isfinite(d_ex)]))
    levels = np.linspace(0, dmax, 22)[1:-1]
    rels = {}
    for meth, rec in (("lclp", lclp), ("qclp", qclp)):
        if rec["ok"]:
            rels[meth] = relative_error(rec["distance"], d_ex, [SOURCE])
    vmax = float(np.nanpercentile(np.concatenate([r[np.isfinite(r)] for r in rels.values()]), 99)) if rels else None
    for meth, rec in (("lclp", lclp), ("qclp", qclp)):
        if not rec["ok"]:
            continue
        panels.append(field_panel(ctx, mesh, rec["distance"], f"fig3_field_{meth}", f"{label(meth)}: field",
                                  vmax=dmax, levels=levels))
    for meth in rels:
        panels.append(error_panel(ctx, mesh, rels[meth], f"fig3_err_{meth}",
                                  f"{label(meth)}: relative error", vmax))
    fig = tile(panels, ctx.figures / "fig3_lclp_vs_qclp.png", ncols=2)
    return {"mesh": mesh_row(mesh), "rows": rows, "checks": checks, "figures": [fig.name]}


def sec_fig4(ctx, plan):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    name = plan.one
    mesh = ctx.mesh(name)
    exact = solve(ctx, mesh, name, "exact", SOURCE)
    d_ex = exact["distance"]
    table = {}
    for energy in SWEEP_ENERGIES:
        table[energy] = {}
        for m in plan.sweep_m:
            meth = "qclp" if m == 0 else energy
            log(f"  Fig. 4: {energy}, m = {m:g}")
            rec = solve(ctx, mesh, name, meth, SOURCE, m)
            mets = metrics(mesh, rec["distance"], d_ex, SOURCE) if rec["ok"] else None
            table[energy][f"{m:g}"] = rec_row(rec, mets)
    refs = {}
    for meth in ("heat", "fmm", "exact"):
        rec = exact if meth == "exact" else solve(ctx, mesh, name, meth, SOURCE)
        refs[meth] = rec_row(rec, metrics(mesh, rec["distance"], d_ex, SOURCE) if rec["ok"] else None)

    # -- the sweep plot
    xs = np.arange(len(plan.sweep_m))
    fig, axes = plt.subplots(1, 3, figsize=(11.5, 3.5))
    specs = [("rel_mean", "mean relative error (%)", 100.0),
             ("off_ridge_rel_mean", "off-ridge mean rel. error (%)", 100.0),
             ("ridge_jump_p95", "ridge sharpness (p95 jump)", 1.0)]
    ecolors = {"qcqp-dirichlet": "tab:olive", "qcqp-laplacian": "tab:cyan", "qcqp-hessian": "tab:red"}
    for ax, (k, ylab, scale) in zip(axes, specs, strict=True):
        for energy in SWEEP_ENERGIES:
            ys = [table[energy][f"{m:g}"].get(k) for m in plan.sweep_m]
            ys = [np.nan if y is None else scale * y for y in ys]
            ax.plot(xs, ys, marker="o", ms=4, color=ecolors[energy], label=label(energy))
        for meth, ls in (("heat", "--"), ("fmm", ":"), ("exact", "-.")):
            v = refs[meth].get(k)
            if v is not None and np.isfinite(v) and not (meth == "exact" and k != "ridge_jump_p95"):
                ax.axhline(scale * v, color=COLORS[meth], ls=ls, lw=1, label=label(meth))
        ax.set_xticks(xs, [f"{m:g}" for m in plan.sweep_m])
        ax.set_xlabel("m  (λ = m·100·h/n; m = 0 is QCLP)")
        ax.set_ylabel(ylab)
        ax.grid(alpha=0.3)
        if k != "ridge_jump_p95":
            log_axis(ax)
    axes[2].legend(fontsize=7, frameon=False)
    fig.suptitle(f"λ sweep on {name} (source vertex {SOURCE}; errors against the exact MMP distance)", fontsize=10)
    fig.tight_layout()
    f1 = save_figure(fig, ctx.figures / "fig4_lambda_sweep.png", dpi=90)
    plt.close(fig)

    # -- close-ups of QCQP-Hessian fields near the ridge for a few m
    sub, used, center = ridge_crop(mesh, d_ex, SOURCE)
    dsub = d_ex[used]
    lo, hi = float(dsub.min()), float(dsub.max())
    levels = np.linspace(lo, hi, 22)[1:-1]
    panels = []
    ms = [m for m in (0.0, 0.3, 1.0, 10.0) if m in plan.sweep_m] or plan.sweep_m[:4]
    for m in ms:
        meth = "qclp" if m == 0 else "qcqp-hessian"
        rec = solve(ctx, mesh, name, meth, SOURCE, m)
        if not rec["ok"]:
            continue
        r = table["qcqp-hessian"][f"{m:g}"]
        t = f"QCQP-Hessian m={m:g}" if m else "QCLP (m=0)"
        t += f": sharpness {r['ridge_jump_p95']:.2f}"
        panels.append(field_panel(ctx, sub, rec["distance"][used], f"fig4_crop_{m:g}", t, vmin=lo, vmax=hi,
                                  levels=levels, sources=None))
    f2 = tile(panels, ctx.figures / "fig4_hessian_closeups.png", ncols=2 if len(panels) <= 4 else 3)
    return {"mesh": mesh_row(mesh), "table": table, "refs": refs, "figures": [f1.name, f2.name],
            "crop_center": center, "crop_vertices": int(used.size)}


def decimate(mesh, target: int, name: str):
    """QEM decimation to about ``target`` faces (fast-simplification, else libigl)."""
    V, F = np.array(mesh.V, dtype=np.float64), np.array(mesh.F, dtype=np.int64)
    try:
        import fast_simplification as fs

        V2, F2 = fs.simplify(V, F, target_reduction=1.0 - target / mesh.n_faces)
        tool = "fast-simplification " + __import__("importlib.metadata").metadata.version("fast_simplification")
    except ImportError:
        import igl

        r = igl.decimate(V, F, int(target))
        V2, F2 = (r[1], r[2]) if isinstance(r[0], bool | np.bool_) else (r[0], r[1])
        tool = "libigl decimate"
    return cg.TriMesh(np.asarray(V2, float), np.asarray(F2, np.int64), name=name), tool


def sec_fig5(ctx, plan):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    base = ctx.mesh(plan.res_base)
    p0 = base.V[SOURCE]
    levels = []
    tool = None
    for target in plan.res_targets:
        key = f"{Path(plan.res_base).stem}_dec{target // 1000}k"
        mesh, tool = decimate(base, target, key)
        ctx.register(key, mesh)
        levels.append((key, mesh))
    levels.append((plan.res_base, base))
    out = {"levels": [], "rows": {}, "tool": tool}
    for key, mesh in levels:
        src = int(np.argmin(np.linalg.norm(mesh.V - p0, axis=1)))
        log(f"  Fig. 5: {key} ({mesh.n_faces} faces), source {src}")
        rows, _ = evaluate(ctx, mesh, key, RES_METHODS, source=src)
        mr = mesh_row(mesh)
        mr.update(key=key, source=src, source_offset=float(np.linalg.norm(mesh.V[src] - p0) / base.bbox_diagonal))
        out["levels"].append(mr)
        out["rows"][key] = rows
    fig, axes = plt.subplots(1, 3, figsize=(11.5, 3.4))
    faces = [lv["faces"] for lv in out["levels"]]
    for meth in RES_METHODS:
        for ax, k, sc in ((axes[0], "rel_mean", 100), (axes[1], "rel_max", 100), (axes[2], "time_s", 1)):
            ys = [out["rows"][lv["key"]][meth].get(k) for lv in out["levels"]]
            ys = [np.nan if y is None else sc * y for y in ys]
            ax.plot(faces, ys, marker=MARKERS.get(meth, "o"), color=COLORS[meth], label=label(meth))
    from matplotlib.ticker import NullLocator

    for ax, yl in zip(axes, ("mean relative error (%)", "max relative error (%)", "time (s)"), strict=True):
        ax.set_xscale("log")
        log_axis(ax)
        ax.set_xlabel("faces")
        ax.set_ylabel(yl)
        ax.grid(alpha=0.3, which="major")
        ax.set_xticks(faces, [f"{f / 1000:.0f}K" for f in faces])
        ax.xaxis.set_minor_locator(NullLocator())
    axes[0].legend(fontsize=8, frameon=False)
    fig.suptitle(f"Accuracy vs resolution: {plan.res_base} decimated ({tool}); source nearest to the original "
                 f"vertex {SOURCE}", fontsize=10)
    fig.tight_layout()
    f = save_figure(fig, ctx.figures / "fig5_resolution.png", dpi=90)
    plt.close(fig)
    out["figures"] = [f.name]
    return out


def sec_fig6(ctx, plan):
    from cvxgeodesic.evaluation import relative_error

    name = plan.fig6
    mesh = ctx.mesh(name)
    methods = ["qcqp-hessian", "qclp", "lcqp-hessian", "heat", "fmm", "dijkstra"]
    rows, exact = evaluate(ctx, mesh, name, methods)
    d_ex = exact["distance"]
    rels = {}
    for meth in methods:
        rec = solve(ctx, mesh, name, meth, SOURCE)
        if rec["ok"]:
            rels[meth] = relative_error(rec["distance"], d_ex, [SOURCE])
    p99 = [float(np.nanpercentile(r[np.isfinite(r)], 99)) for r in rels.values()]
    vmax = float(np.median(p99)) if p99 else None
    panels = [error_panel(ctx, mesh, r, f"fig6_{meth}", label(meth), vmax) for meth, r in rels.items()]
    f = tile(panels, ctx.figures / "fig6_error_maps.png", ncols=3)
    return {"mesh": mesh_row(mesh), "rows": rows, "vmax": vmax, "figures": [f.name]}


def sec_fig7(ctx, plan):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from cvxgeodesic.evaluation import triangle_anisotropy

    files = sorted(p.name for p in ctx.shared.glob("thingi_*.stl"))
    if plan.quick:
        files = files[:3]
    out = {"meshes": [], "rows": {}}
    for name in files:
        mesh = ctx.mesh(name)
        log(f"  Fig. 7: {name} ({mesh.n_faces} faces)")
        mr = mesh_row(mesh)
        tau = triangle_anisotropy(mesh)
        mr["tau_median"] = float(np.median(tau[np.isfinite(tau)]))
        rel_area = mesh.face_areas / np.median(mesh.face_areas)
        mr["near_zero_faces"] = int(np.sum(rel_area < 1e-6))
        out["meshes"].append(mr)
        rows, exact = evaluate(ctx, mesh, name, THINGI_METHODS)
        counts = [int(g) for r in rows.values() for w in (r.get("warnings") or [])
                  for g in re.findall(r"(\d+) degenerate face", w)]
        mr["degenerate_faces"] = max(counts) if counts else 0
        if not exact["ok"]:
            for r in rows.values():
                r["note"] = "no exact reference"
        out["rows"][name] = rows
    from matplotlib.transforms import blended_transform_factory

    fig, axes = plt.subplots(1, 2, figsize=(11.0, 4.3), sharey=True)
    ok_vals = [100 * out["rows"][n][m]["rel_mean"] for n in files for m in THINGI_METHODS
               if out["rows"][n][m].get("rel_mean") is not None and np.isfinite(out["rows"][n][m]["rel_mean"])]
    ymax = max(ok_vals) if ok_vals else 100.0
    yfail = ymax * 2.2
    for ax, key, xl in ((axes[0], "tau", "τ(T): mean of τ(t) = P·H / (2√3·S)  (paper's measure)"),
                        (axes[1], "tau_median", "median of τ(t)  (robust to a few slivers)")):
        xv = {m["name"]: m[key] for m in out["meshes"]}
        for k, meth in enumerate(THINGI_METHODS):
            good = [n for n in files if out["rows"][n][meth].get("rel_mean") is not None
                    and np.isfinite(out["rows"][n][meth]["rel_mean"])]
            bad = [n for n in files if n not in good]
            mk = MARKERS.get(meth, "o")
            ax.scatter([xv[n] for n in good], [100 * out["rows"][n][meth]["rel_mean"] for n in good], marker=mk,
                       color=COLORS[meth], label=label(meth), s=32, alpha=0.85, zorder=3)
            if bad:
                ax.scatter([xv[n] * (1 + 0.06 * (k - 2.5)) for n in bad], [yfail] * len(bad), marker=mk,
                           color=COLORS[meth], s=32, alpha=0.85, zorder=3)
        ax.axhline(ymax * 1.5, color="0.6", lw=0.8, ls="--")
        tr = blended_transform_factory(ax.transAxes, ax.transData)
        ax.text(0.01, yfail * 1.25, "failed: no field", transform=tr, fontsize=7, color="0.35", va="bottom")
        trx = blended_transform_factory(ax.transData, ax.transAxes)
        placed = []
        for n in sorted(files, key=lambda n: xv[n]):
            lx = np.log10(xv[n])
            level = sum(1 for p in placed if abs(p - lx) < 0.06 * (np.log10(max(xv.values()) + 1) + 1))
            placed.append(lx)
            ax.text(xv[n], 0.01 + 0.1 * level, n.replace("thingi_", "").replace(".stl", ""), transform=trx,
                    fontsize=6, color="0.4", ha="center", va="bottom", rotation=90)
        ax.set_xscale("log")
        ax.set_xlabel(xl, fontsize=9)
        ax.grid(alpha=0.3, which="major")
    log_axis(axes[0])
    axes[0].set_ylim(top=yfail * 2.0)
    axes[0].set_ylabel("mean relative error (%)")
    axes[1].legend(fontsize=7, frameon=False, loc="center left", bbox_to_anchor=(1.0, 0.5))
    fig.suptitle("Thingi10K meshes: accuracy vs anisotropy (source vertex 0; errors against exact MMP)", fontsize=10)
    fig.tight_layout()
    f = save_figure(fig, ctx.figures / "fig7_anisotropy.png", dpi=90)
    plt.close(fig)
    out["figures"] = [f.name]
    return out


def sec_fig8(ctx, plan):
    name = "bug_medial_axis.obj"
    mesh = ctx.mesh(name)
    mr = mesh_row(mesh)
    mr["nonmanifold_edges"] = int(np.sum(mesh.edge_cell_counts > 2))
    mr["boundary_edges"] = int(np.sum(mesh.edge_cell_counts == 1))
    lab = mesh.component_labels
    mr["source_component_vertices"] = int(np.sum(lab == lab[SOURCE]))
    rows = {}
    recs = {}
    for meth in MEDIAL_METHODS:
        rec = solve(ctx, mesh, name, meth, SOURCE)
        recs[meth] = rec
        rows[meth] = rec_row(rec)
    comp = {}
    ok = {k: r for k, r in recs.items() if r["ok"]}
    if "dijkstra" in ok:
        dj = ok["dijkstra"]["distance"]
        fin = np.isfinite(dj) & (dj > 0)
        for k, r in ok.items():
            d = r["distance"]
            comp[k] = {
                "mean_rel_diff_to_dijkstra": float(np.mean(np.abs(d[fin] - dj[fin]) / dj[fin])),
                "max_above_dijkstra_over_diag": float(np.max(d[fin] - dj[fin]) / mesh.bbox_diagonal),
                "share_below_dijkstra": float(np.mean(d[fin] <= dj[fin] + 1e-9 * mesh.bbox_diagonal)),
                "unreachable": int(np.sum(~np.isfinite(d))),
            }
    shown = [m for m in ("heat", "dijkstra", "qclp", "qcqp-laplacian") if m in ok]
    ref = ok.get("dijkstra") or (next(iter(ok.values())) if ok else None)
    figs = []
    if ref is not None:
        dref = ref["distance"]
        vmax = float(np.max(dref[np.isfinite(dref)]))
        levels = np.linspace(0, vmax, 22)[1:-1]
        panels = []
        for m in shown:
            t = f"{label(m)} ({ok[m]['time_s']:.2f} s, {solver_text(ok[m]).split(';')[0]})"
            panels.append(field_panel(ctx, mesh, ok[m]["distance"], f"fig8_{m}", t, vmax=vmax, levels=levels))
        figs.append(tile(panels, ctx.figures / "fig8_medial_axis.png", ncols=2).name)
    return {"mesh": mr, "rows": rows, "comparison": comp, "figures": figs, "shown": shown}


def sec_fig9(ctx, plan):
    name = plan.one
    mesh = ctx.mesh(name)
    methods = ["exact", "heat", "fmm", "qclp", "qcqp-hessian", "lcqp-hessian"]
    rows, exact = evaluate(ctx, mesh, name, methods)
    d_ex = exact["distance"]
    sub, used, center = ridge_crop(mesh, d_ex, SOURCE)
    dsub = d_ex[used]
    lo, hi = float(dsub.min()), float(dsub.max())
    levels = np.linspace(lo, hi, 22)[1:-1]
    # where the close-up is: the whole model, the patch in grey-free colours and the rest dimmed
    from cvxgeodesic.plotting import plot_field

    where = np.full(mesh.n_vertices, np.nan)
    where[used] = d_ex[used]
    pw = panel(ctx, "fig9_where")
    plot_field(mesh, where, pw, isolines=0, title=f"{name}: where the close-up is",
               vmin=0.0, vmax=float(d_ex[fin_max(d_ex)]), dpi=PANEL_DPI, colorbar_label="exact distance",
               sources=[SOURCE])
    panels = [pw]
    for meth in ("exact", "heat", "fmm", "qclp", "qcqp-hessian"):
        rec = exact if meth == "exact" else solve(ctx, mesh, name, meth, SOURCE)
        if not rec["ok"]:
            continue
        r = rows[meth]
        t = f"{label(meth)}: sharpness {r['ridge_jump_p95']:.2f}"
        if meth != "exact":
            t += f", off-ridge {100 * r['off_ridge_rel_mean']:.2f}%"
        panels.append(field_panel(ctx, sub, rec["distance"][used], f"fig9_{meth}", t, vmin=lo, vmax=hi,
                                  levels=levels, sources=None))
    f = tile(panels, ctx.figures / "fig9_ridge_isolines.png", ncols=3)
    return {"mesh": mesh_row(mesh), "rows": rows, "figures": [f.name], "crop_center": center,
            "crop_vertices": int(used.size), "crop_faces": int(sub.n_faces), "n_isolines": int(len(levels))}


def _norm_row(mesh, source, d_exact, normalization):
    """QCLP and QCQP-Hessian (m = 1) under one normalization of m: errors, deficit, sharpness, time."""
    from normalization_study import field_metrics
    from normalization_study import solve as solve_norm

    d_lp, t_lp, _ = solve_norm(mesh, "qclp", source, normalization=normalization)
    d_h, t_h, info = solve_norm(mesh, "qcqp-hessian", source, normalization=normalization)
    lp = field_metrics(mesh, d_lp, d_exact, source, d_lp)
    h = field_metrics(mesh, d_h, d_exact, source, d_lp)
    return {"normalization": normalization, "qclp": {**lp, "time_s": t_lp},
            "hessian": {**h, "time_s": t_h, "iterations": info.iterations, "lam": info.lam}}, d_h


def sec_norm_resolution(ctx, plan):
    """One surface at six resolutions: does m = 1 round the same on every one (area) or not (paper)?"""
    from cvxgeodesic.mesh.generate import _subdivide_midpoint

    base = ctx.mesh(plan.res_base)
    p0 = base.V[SOURCE]
    targets = [t for t in (500, 2000, 8000, 20000) if t < base.n_faces]
    from cvxgeodesic.mesh.decimate import simplify_mesh  # shortest-edge collapse: stays manifold (QEM did not at 500)

    levels = [(f"{Path(plan.res_base).stem}_se{t}", simplify_mesh(base, t)) for t in targets]
    levels.append((plan.res_base, base))
    if not plan.quick:
        V2, F2 = _subdivide_midpoint(np.array(base.V), np.array(base.F))
        levels.append((f"{Path(plan.res_base).stem}_sub4", cg.TriMesh(V2, F2, name="bunny subdivided")))
    out = {"levels": [], "figures": []}
    for key, mesh in levels:
        ctx.register(key, mesh)
        src = int(np.argmin(np.linalg.norm(mesh.V - p0, axis=1)))
        log(f"  resolution: {key} ({mesh.n_faces} faces), source {src}")
        d_ex = solve(ctx, mesh, key, "exact", src)["distance"]
        rows = [_norm_row(mesh, src, d_ex, norm)[0] for norm in ("area", "paper")]
        out["levels"].append({**mesh_row(mesh), "key": key, "source": src, "rows": rows,
                              "h_over_sqrt_area": mesh.mean_edge_length / float(np.sqrt(mesh.face_areas.sum()))})
    return out


def sec_norm_remeshing(ctx, plan):
    """One cylinder, an isotropic and a strongly anisotropic triangulation, against the unrolled distance."""
    rng = np.random.default_rng(0)
    n_pts = 2000
    theta, z = rng.uniform(0, 2 * np.pi, n_pts), rng.uniform(0.05, 1.95, n_pts)
    P = np.column_stack([np.cos(theta), np.sin(theta), z])
    dth = np.minimum(np.abs(theta), 2 * np.pi - np.abs(theta))
    d_pts = np.hypot(dth, z - 1.0)
    cases = [("isotropic (96 × 32 cells, 1 : 1)", cg.cylinder(96, 32)),
             ("anisotropic (192 × 8 cells, 1 : 7.6)", cg.cylinder(192, 8))]
    out = {"cases": [], "agreement": {}, "figures": []}
    fields = {}
    for label_text, mesh in cases:
        src = int(np.argmin(np.linalg.norm(mesh.V - [1.0, 0.0, 1.0], axis=1)))
        th = np.arctan2(mesh.V[:, 1], mesh.V[:, 0]) - np.arctan2(mesh.V[src, 1], mesh.V[src, 0])
        th = np.abs((th + np.pi) % (2 * np.pi) - np.pi)
        d_ex = np.hypot(th, mesh.V[:, 2] - mesh.V[src, 2])
        rows = []
        for norm in ("area", "paper"):
            row, d_h = _norm_row(mesh, src, d_ex, norm)
            sp_ = cg.surface_point(mesh, P)
            row["hessian"]["at_points"] = cg.distance_at(mesh, d_h, sp_).tolist()
            rows.append(row)
        fields[label_text] = rows
        out["cases"].append({**mesh_row(mesh), "label": label_text, "source": src, "rows": rows})
    a, b = (np.array([r["hessian"]["at_points"] for r in fields[c[0]]]) for c in cases)
    for i, norm in enumerate(("area", "paper")):
        diff = np.abs(a[i] - b[i])
        out["agreement"][norm] = {"mean": float(diff.mean()), "max": float(diff.max()),
                                  "err_iso": float(np.mean(np.abs(a[i] - d_pts) / d_pts)),
                                  "err_aniso": float(np.mean(np.abs(b[i] - d_pts) / d_pts))}
    for case in out["cases"]:
        for row in case["rows"]:
            row["hessian"].pop("at_points")
    return out


# ----------------------------------------------------------------------------------------------------------------------
# order 2 (issue 17; not in the paper)
# ----------------------------------------------------------------------------------------------------------------------


def _flat_solve(mesh, method: str, order: int, src, exact: np.ndarray) -> tuple[dict, np.ndarray | None]:
    """One flat-case solve (set-up + solve timed): its record and field, or an ``error`` record and None.

    ``err`` is ``max |d − exact| / max exact`` over the vertices (:func:`summarize_field`'s ``abs_max``
    over the largest exact distance); a vertex source is left out of the comparison.
    """
    import warnings

    from cvxgeodesic.evaluation.summary import summarize_field, summarize_run

    kwargs = {"order": order} if order != 1 else {}
    point = not isinstance(src, int | np.integer)
    arg = cg.SurfacePoint(int(src[0]), np.asarray(src[1], dtype=float)) if point else int(src)
    t0 = time.perf_counter()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # DegenerateFacesWarning on split needles: in the notes too
            res = cg.GeodesicSolver(mesh, method, **kwargs).solve(arg)
    except Exception as exc:  # noqa: BLE001 - e.g. heat cannot take a point source: a '—' in the table
        return {"err": None, "error": f"{type(exc).__name__}: {str(exc).split(';')[0]}"[:160]}, None
    wall = time.perf_counter() - t0
    run = summarize_run(res.info, time_s=wall)
    vs = [] if point else [int(src)]
    acc = summarize_field(mesh, res.distance, exact, vs, smoothness=False, gradient=False)
    rec = {k: run[k] for k in ("solver", "status", "time_s", "iterations", "notes")}
    rec["err"] = acc["abs_max"] / float(exact.max())
    return rec, np.asarray(res.distance, dtype=np.float64)


def order2_flat(plan) -> tuple[list[dict], tuple | None]:
    """Flat meshes against the Euclidean distance: one row per (mesh, kind of source).

    Returns (rows, figure data): each row has the case, its size and largest face aspect, the kind
    (``vertex`` / ``point``) and per source the records of :data:`ORDER2_METHODS`; the figure data is
    (mesh, exact, {label: field}) of :data:`ORDER2_FIGURE_CASE`, or None when that case was not run.
    """
    from order2 import euclid_from, flat_cases

    rows, fig_data = [], None
    for _tag, meth, order in ORDER2_METHODS:  # load the compiled kernels before anything is timed
        _flat_solve(cg.grid_plane(3), meth, order, 0, np.ones(16))
    for case, mesh, vsrc, psrc in flat_cases(plan.quick):
        aspect = float(np.max(mesh.cell_longest_edges / mesh.cell_min_altitudes))
        for kind, sources in (("vertex", vsrc), ("point", psrc)):
            per = []
            for src in sources:
                exact = euclid_from(mesh, src)
                one = {"source": src if kind == "vertex" else [int(src[0]), [float(b) for b in src[1]]]}
                fields = {}
                for tag, meth, order in ORDER2_METHODS:
                    one[tag], fields[tag] = _flat_solve(mesh, meth, order, src, exact)
                per.append(one)
                if (case, src) == ORDER2_FIGURE_CASE:
                    fig_data = (mesh, exact, {"order 1 (qclp)": fields["p1"], "order 2": fields["p2"],
                                              "heat": fields["heat"], "FMM": fields["fmm"]})
            log(f"  order 2, flat: {case}, {kind} sources: order 2 max "
                f"{max((o['p2']['err'] or 0.0) for o in per):.1e}")
            rows.append({"case": case, "faces": mesh.n_faces, "vertices": mesh.n_vertices, "aspect_max": aspect,
                         "kind": kind, "per_source": per, "loadavg_1min": round(os.getloadavg()[0], 2)})
    return rows, fig_data


def _order2_record(rec: dict, exact: dict, mesh) -> dict:
    """A cached solve record cut to what the order-2 tables show, with its errors against exact MMP."""
    from cvxgeodesic.evaluation.summary import summarize_field

    out = {k: rec.get(k) for k in ("ok", "solver", "status", "time_s", "setup_s", "solve_s", "iterations",
                                   "notes", "warnings", "error", "loadavg_1min")}
    if rec["ok"]:
        acc = summarize_field(mesh, rec["distance"], exact["distance"], [SOURCE], smoothness=False, gradient=False)
        out.update(rel_mean=acc["rel_mean"], rel_max=acc["rel_max"], n_compared=acc["n_compared"])
    return out


def order2_cad(ctx, plan) -> dict:
    """The coarse CAD meshes against exact MMP from vertex 0: order 1, order 2, heat, FMM (fields cached).

    Meshes above ``plan.order2_max_faces`` faces are left out (with the stored run's numbers from
    :data:`ORDER2_STORED`, labelled so); meshes without an exact reference (non-manifold) are skipped.
    """
    from order2 import cad_names

    names = plan.order2_quick_cad or cad_names(ctx.shared)
    stored_path = REPO / ORDER2_STORED
    stored = {r["mesh"]: r for r in json.loads(stored_path.read_text())} if stored_path.exists() else {}
    out = {"rows": [], "skipped": [], "left_out": [], "stored_file": ORDER2_STORED, "stored_load": ORDER2_STORED_LOAD,
           "stored": {}}
    for name in names:
        mesh = ctx.mesh(name)
        cad_set = "thingi10k_small" if name.startswith("thingi10k_small/") else "thingi_*.stl"
        if plan.order2_max_faces is not None and mesh.n_faces > plan.order2_max_faces:
            out["left_out"].append({"name": name, "set": cad_set, "faces": mesh.n_faces, "stored": stored.get(name)})
            continue
        key = f"o2_{name}"  # this section's own fields: its times are of this run, not of Fig. 7's
        exact = solve(ctx, mesh, key, "exact", SOURCE)
        if not exact["ok"]:
            out["skipped"].append({"name": name, "set": cad_set, "faces": mesh.n_faces, "why": status_text(exact)})
            continue
        log(f"  order 2, CAD: {name} ({mesh.n_faces} faces)")
        row = {"name": name, "set": cad_set, "faces": mesh.n_faces, "vertices": mesh.n_vertices,
               "exact": _order2_record(exact, exact, mesh)}
        for tag, meth, order in ORDER2_METHODS:
            row[tag] = _order2_record(solve(ctx, mesh, key, meth, SOURCE, order=order), exact, mesh)
        for tag, meth, order, norm in ORDER2_EXTRA:
            row[tag] = _order2_record(solve(ctx, mesh, key, meth, SOURCE, order=order, normalization=norm), exact,
                                      mesh)
        out["rows"].append(row)
        if name in stored and "p2" in stored[name]:
            out["stored"][name] = {t: {k: stored[name].get(t, {}).get(k) for k in ("mean", "max", "time")}
                                   for t in ("p1", "p2", "heat", "fmm")}
    return out


def sec_order2(ctx, plan):
    """Issue 17: order 1, order 2, heat, FMM against exact on flat meshes and on the coarse CAD set."""
    from order2_figures import cad_scatter, flat_panel

    flat, fig_data = order2_flat(plan)
    cad = order2_cad(ctx, plan)
    figs = []
    points = [{t: r[t].get("rel_mean") for t in ("p1", "p2", "heat", "fmm")} for r in cad["rows"]]
    figs.append(cad_scatter(points, ctx.figures / "fig12_order2_cad.png").name)
    if fig_data is not None:
        figs.append(flat_panel(*fig_data, ctx.figures / "fig12_order2_flat.png",
                               title=f"{ORDER2_FIGURE_CASE[0]}, source vertex {ORDER2_FIGURE_CASE[1]} (cyan): "
                               "error against the Euclidean distance").name)
    from PIL import Image

    for f in figs:  # 256 colours like the report's other figures
        path = ctx.figures / f
        with Image.open(path) as im:
            rgb = im.convert("RGB")
        save_png(rgb, path)
    return {"flat": flat, "cad": cad, "max_faces": plan.order2_max_faces, "figures": figs,
            "figure_case": list(ORDER2_FIGURE_CASE)}


# ----------------------------------------------------------------------------------------------------------------------
# volumes (issue 26; not in the paper)
# ----------------------------------------------------------------------------------------------------------------------

#: (tag, method, order) of the volume section's fields.
VOLUME_METHODS = (("p1", "qclp", 1), ("p2", "qclp", 2), ("heat", "heat", 1), ("dijkstra", "dijkstra", 1))


def _volume_cases(quick: bool):
    """(case, n, mesh, source, exact field, error kind) of the analytic volume cases: a jittered box from its centre,
    the L-shaped prism from one arm, the unit ball's wall distance ``1 − r``."""
    from cvxgeodesic.mesh.tet_generate import l_prism_distance

    for n in ((4,) if quick else (4, 8)):
        box = cg.tet_box(n, jitter=0.2, seed=1)
        c = int(np.argmin(np.linalg.norm(box.V - 0.5, axis=1)))
        yield "box, vertex source at the centre", n, box, c, np.linalg.norm(box.V - box.V[c], axis=1), "rel"
    for n in ((4,) if quick else (4, 8)):
        prism = cg.tet_l_prism(n, jitter=0.2, seed=1)
        c = int(np.argmin(np.linalg.norm(prism.V - [0.5, 1.5, 0.5], axis=1)))
        yield "L-shaped prism, source in one arm", n, prism, c, l_prism_distance(prism.V[c], prism.V), "rel"
    for n in ((4,) if quick else (4, 8)):
        ball = cg.tet_ball(n)
        yield "unit ball, 'boundary' (1 − r)", n, ball, "boundary", 1 - np.linalg.norm(ball.V, axis=1), "abs"


def sec_volumes(ctx, plan):
    """Issue 26: order 1, order 2, heat and Dijkstra inside tetrahedral meshes against analytic distances."""
    import warnings

    rows = []
    for case, n, mesh, src, exact, kind in _volume_cases(plan.quick):
        row = {"case": case, "n": n, "tets": mesh.n_tets, "vertices": mesh.n_vertices, "kind": kind}
        for tag, method, order in VOLUME_METHODS:
            t0 = time.perf_counter()
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    res = cg.GeodesicSolver(mesh, method, order=order).solve(src)
            except Exception as exc:  # noqa: BLE001 - a failed method is a cell of the table
                row[tag] = {"error": f"{type(exc).__name__}: {exc}"[:160]}
                continue
            d, k = res.distance, exact > 1e-12
            err = np.abs(d - exact)
            row[tag] = {"time_s": time.perf_counter() - t0, "solver": res.info.solver,
                        "mean": float(np.mean(err[k] / exact[k]) if kind == "rel" else np.mean(err)),
                        "max": float(err.max() / exact.max()), "rounds": res.info.extra.get("rounds")}
        row["loadavg_1min"] = round(os.getloadavg()[0], 2)
        log(f"  volumes: {case}, n = {n}: order 2 mean {row['p2'].get('mean')}")
        rows.append(row)
    return {"rows": rows, "figures": []}


# travel cost and metrics (issue 24; not in the paper)
# ----------------------------------------------------------------------------------------------------------------------


def sec_metric(ctx, plan):
    """The analytic cases of travel cost and metrics (benchmarks/metric_cases.py): linear velocity, two layers,
    a constant metric, a constant cost; generated meshes only."""
    import metric_cases

    data = metric_cases.run(plan.quick)
    names = ["fig13_metric_linear.png", "fig13_metric_layers.png"]
    metric_cases.figures(data, *(ctx.figures / n for n in names))
    from PIL import Image

    for n in names:  # 256 colours like the report's other figures
        with Image.open(ctx.figures / n) as im:
            rgb = im.convert("RGB")
        save_png(rgb, ctx.figures / n)
    data.pop("_fields")
    data["figures"] = names
    data["loadavg_1min"] = round(os.getloadavg()[0], 2)
    return data


# ----------------------------------------------------------------------------------------------------------------------
# smoothing at order 2 (issue 25; not in the paper)
# ----------------------------------------------------------------------------------------------------------------------


def _p2_render_mesh(mesh, space):
    """Each face split in four at its edge midpoints (vertices: the P2 nodes), so that a P2 field draws with its
    values at the midpoints; returns the mesh."""
    V = np.vstack([mesh.V, mesh.V[mesh.edges].mean(axis=1)])
    a, b, c, m0, m1, m2 = space.cell_dofs.T  # m0 opposite corner 0: on edge (b, c)
    F = np.vstack([np.column_stack(t) for t in ((a, m2, m1), (b, m0, m2), (c, m1, m0), (m0, m1, m2))])
    return cg.TriMesh(V, F, name=mesh.name)


def smooth_plane_case(plan) -> tuple[dict, list]:
    """The two-source plane: each run's rounding width and off-ridge error, and the fields at the P2 nodes."""
    import warnings

    from cvxgeodesic.evaluation import ridge_deficit, rounding_width
    from cvxgeodesic.operators.lagrange import LagrangeSpace
    from order2_smoothing import BAND, plane, two_sources

    mesh = plane("jittered", plan.smooth_plane)
    s, exact, K = two_sources(mesh)
    space = LagrangeSpace(mesh)
    X = np.vstack([mesh.V, mesh.V[mesh.edges].mean(axis=1)])
    exact_nodes = np.linalg.norm(X[:, None] - mesh.V[s], axis=2).min(axis=1)
    rows, fields, base = {}, {"exact": exact_nodes}, {}
    off = np.abs(mesh.V[:, 0] - 0.5) > 0.2
    for tag, meth, order, m in SMOOTH_RUNS:
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = cg.GeodesicSolver(mesh, meth, order=order, m=m).solve(s)
        wall = time.perf_counter() - t0
        d = res.distance
        I = ridge_deficit(mesh, d, exact, BAND, sources=s, exclude_radius=1.0)["deficit_integral"]
        base.setdefault(order, I)  # qclp comes first at each order
        rows[tag] = {"method": meth, "order": order, "m": m, "lam": res.info.lam, "time_s": wall,
                     "status": res.info.status, "deficit_integral": I,
                     "width": rounding_width(I - base[order], K) if meth != "qclp" else 0.0,
                     "lowered_max": float(np.max(exact - d)),
                     "off_ridge_max": float(np.abs(d - exact)[off].max() / exact.max())}
        if order == 2:
            fields[tag] = np.sqrt(np.maximum(res.field.phi, 0.0))
        else:
            fields[tag] = np.concatenate([d, d[mesh.edges].mean(axis=1)])  # linear along the edges
    return {"mesh": mesh.name, "faces": mesh.n_faces, "sources": s, "rows": rows}, [mesh, space, fields]


def _smooth_figure(ctx, mesh, fields: dict, titles: dict, crop, name: str, levels, sources) -> str:
    panels = []
    for tag, d in fields.items():
        panels.append(field_panel(ctx, crop, d, f"{name}_{tag}", titles[tag], vmin=float(levels[0]),
                                  vmax=float(levels[-1]), levels=levels[1:-1], sources=sources))
    return tile(panels, ctx.figures / f"{name}.png", ncols=4).name


SMOOTH_TITLES = {"exact": "exact", "o1_qclp": "order 1, qclp", "o1_hessian": "order 1, qcqp-hessian m = 1",
                 "o2_qclp": "order 2, qclp", "o2_hessian": "order 2, qcqp-hessian m = 1",
                 "o2_hessian_30": "order 2, qcqp-hessian m = 30", "o2_hessian_300": "order 2, qcqp-hessian m = 300"}


def sec_order2_smoothing(ctx, plan):
    """Issue 25: order 1 vs order 2, smoothed vs not: the two-source plane, the fine meshes, the coarse CAD set."""
    from cvxgeodesic.evaluation import ridge_deficit
    from cvxgeodesic.problems.formulations import KAPPA_ORDER2

    plane_rec, (pm, space, pfields) = smooth_plane_case(plan)
    fine = []
    figs = []
    # the plane, cut to the ridge's middle, drawn with the P2 fields' midpoint values
    rm = _p2_render_mesh(pm, space)
    cen = rm.V[rm.F].mean(axis=1)
    keep = (np.abs(cen[:, 0] - 0.5) < 0.2) & (np.abs(cen[:, 1] - 0.5) < 0.3)
    crop, used = submesh(rm, keep, f"{pm.name} (close-up)")
    lo, hi = float(pfields["exact"][used].min()), float(pfields["exact"][used].max())
    figs.append(_smooth_figure(ctx, rm, {t: v[used] for t, v in pfields.items()}, SMOOTH_TITLES, crop,
                               "fig15_smoothing_plane", np.linspace(lo, hi, 24), None))
    for i, name in enumerate(plan.smooth_meshes):
        mesh = ctx.mesh(name)
        log(f"  order-2 smoothing: {name} ({mesh.n_faces} faces)")
        exact = solve(ctx, mesh, name, "exact", SOURCE)
        row = {"mesh": mesh_row(mesh), "band": SMOOTH_BAND * mesh.bbox_diagonal}
        recs = {}
        for tag, meth, order, m in SMOOTH_RUNS:
            rec = recs[tag] = solve(ctx, mesh, name, meth, SOURCE, m, order=order)
            row[tag] = rec_row(rec, metrics(mesh, rec["distance"], exact["distance"], SOURCE) if rec["ok"] else None)
            if rec["ok"]:
                row[tag]["ridge_deficit"] = ridge_deficit(mesh, rec["distance"], exact["distance"], row["band"],
                                                          sources=[SOURCE])
        fine.append(row)
        if i == 0 and exact["ok"]:
            d_ex = exact["distance"]
            sub, used, _ = ridge_crop(mesh, d_ex, SOURCE, radius_frac=0.12)
            levels = np.linspace(float(d_ex[used].min()), float(d_ex[used].max()), 22)
            shown = {"exact": d_ex[used], **{t: r["distance"][used] for t, r in recs.items() if r["ok"]}}
            figs.append(_smooth_figure(ctx, mesh, shown, SMOOTH_TITLES, sub, "fig15_smoothing_mesh", levels, None))
    cad = []
    for name in plan.smooth_cad:
        mesh = ctx.mesh(name)
        key = f"o2_{name}"  # the order-2 section's fields
        exact = solve(ctx, mesh, key, "exact", SOURCE)
        if not exact["ok"]:
            continue
        log(f"  order-2 smoothing, CAD: {name} ({mesh.n_faces} faces)")
        row = {"name": name, "faces": mesh.n_faces}
        for tag, meth, order, m in SMOOTH_RUNS[:4]:
            rec = solve(ctx, mesh, key, meth, SOURCE, m, order=order)
            row[tag] = _order2_record(rec, exact, mesh)
        cad.append(row)
    return {"plane": plane_rec, "meshes": fine, "cad": cad, "figures": figs, "kappa": dict(KAPPA_ORDER2)}


SECTIONS = {
    "table2": sec_table2, "fig2": sec_fig2, "fig3": sec_fig3, "fig4": sec_fig4, "fig5": sec_fig5,
    "fig6": sec_fig6, "fig7": sec_fig7, "fig8": sec_fig8, "fig9": sec_fig9,
    "norm_resolution": sec_norm_resolution, "norm_remeshing": sec_norm_remeshing, "order2": sec_order2,
    "metric": sec_metric, "volumes": sec_volumes, "order2_smoothing": sec_order2_smoothing,
}


# ----------------------------------------------------------------------------------------------------------------------
# markdown
# ----------------------------------------------------------------------------------------------------------------------


def section_version(name: str) -> int | None:
    """The library code version a section's cached numbers depend on, or None: the order-2 section's
    (:data:`cvxgeodesic.problems.squared_distance.ORDER2_CACHE_VERSION`, as its fields' cache keys)."""
    if name in ("order2", "order2_smoothing"):
        from cvxgeodesic.problems.squared_distance import ORDER2_CACHE_VERSION

        return ORDER2_CACHE_VERSION
    return None


def cached_section_ok(name: str, data: dict, figures: Path) -> bool:
    """Whether a section's cached numbers ``data`` can be reused: its figures are there and it was computed with
    the code version it depends on (:func:`section_version`; sections without one keep their caches)."""
    if data.get("code_version") != section_version(name):
        return False
    return all((figures / f).exists() for f in data.get("figures", []))


def render(results: dict, env: dict, timings: dict, plan: Plan) -> str:
    import report_text as rt

    return rt.render(results, env, timings, plan, helpers=sys.modules[__name__])


# ----------------------------------------------------------------------------------------------------------------------
# main
# ----------------------------------------------------------------------------------------------------------------------


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default="docs", help="output folder: results.md and figures/ (default: docs)")
    ap.add_argument("--shared", default=None, help=f"folder of the meshes (default: {DEFAULT_SHARED})")
    ap.add_argument("--cache", default=None, help="cache folder (default: report_output/cache in the repository)")
    ap.add_argument("--sections", nargs="+", choices=list(SECTIONS), default=None,
                    help="recompute these sections (their cached numbers are dropped; fields stay cached)")
    ap.add_argument("--fresh", action="store_true", help="delete every cache (sections and fields) first")
    ap.add_argument("--quick", action="store_true", help="small meshes only, for development (use another --out)")
    ap.add_argument("--no-compute", action="store_true", help="only rewrite results.md from the cached sections")
    ap.add_argument("--order2-large", action="store_true",
                    help=f"order2: also solve the CAD meshes above {ORDER2_MAX_FACES:,} faces (thingi_32770: ~10 min)")
    args = ap.parse_args(argv)

    shared = Path(args.shared) if args.shared else DEFAULT_SHARED
    if not shared.is_dir() or not (shared / "bunny.obj").exists():
        print(f"error: mesh folder {shared} not found (or without bunny.obj). The report needs the development "
              "meshes; pass --shared DIR.", file=sys.stderr)
        return 2
    cache = Path(args.cache) if args.cache else REPO / "report_output" / ("cache_quick" if args.quick else "cache")
    if args.fresh and cache.exists():
        shutil.rmtree(cache)
    ctx = Context(shared=shared.resolve(), out=Path(args.out), cache=cache, quick=args.quick)
    ctx.setup()
    plan = Plan(args.quick, order2_large=args.order2_large)
    argv_used = ["benchmarks/report.py", *(argv if argv is not None else sys.argv[1:])]
    env_path = cache / "environment.json"
    timings_path = cache / "timings.json"
    timings = json.loads(timings_path.read_text()) if timings_path.exists() else {}

    if not env_path.exists() and not args.no_compute:  # the date and load of the first (fresh) run's start
        start = environment(argv_used)
        start["first_run"] = start["date"]
        dump_json(env_path, start)

    wanted = args.sections or list(SECTIONS)
    if not args.no_compute:
        for name in SECTIONS:
            path = cache / "sections" / f"{name}.json"
            if args.sections and name in args.sections and path.exists():
                path.unlink()
            if name not in wanted and args.sections:
                continue
            if path.exists() and cached_section_ok(name, json.loads(path.read_text()), ctx.figures):
                log(f"{name}: cached, skipped")
                continue
            log(f"{name}: computing")
            t0 = time.perf_counter()
            data = SECTIONS[name](ctx, plan)
            wall = time.perf_counter() - t0
            if (version := section_version(name)) is not None:
                data["code_version"] = version
            dump_json(path, data)
            timings[name] = {"wall_s": wall, "finished": time.strftime("%Y-%m-%d %H:%M:%S"),
                             "loadavg_1min": round(os.getloadavg()[0], 2)}
            dump_json(timings_path, timings)
            log(f"{name}: done in {wall:.1f} s")
        env = environment(argv_used)  # refresh versions and date; keep the first run's start and load
        old = json.loads(env_path.read_text())
        env["first_run"] = old.get("first_run", old.get("date"))
        env["loadavg_at_start"] = old.get("loadavg_at_start", env["loadavg_at_start"])
        dump_json(env_path, env)
    env = json.loads(env_path.read_text()) if env_path.exists() else environment(argv_used)
    results = {}
    for name in SECTIONS:
        path = cache / "sections" / f"{name}.json"
        if path.exists():
            results[name] = json.loads(path.read_text())
    text = render(results, env, timings, plan)
    out_md = ctx.out / "results.md"
    out_md.write_text(text)
    log(f"wrote {out_md} ({len(results)}/{len(SECTIONS)} sections)")
    written = {f for r in results.values() for f in r.get("figures", [])}
    for png in ctx.figures.glob("fig*.png"):
        if png.name not in written:
            log(f"removing stale figure {png}")
            png.unlink()
    return 0 if len(results) == len(SECTIONS) else 1


if __name__ == "__main__":
    sys.exit(main())
