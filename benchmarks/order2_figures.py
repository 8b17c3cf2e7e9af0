"""Figures for docs/order2.md from the JSON written by benchmarks/order2.py.

Usage: ``PYTHONPATH=src python benchmarks/order2_figures.py CAD.json FINE.json OUT_DIR``.
"""

from __future__ import annotations

import json
import sys
import warnings
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import cvxgeodesic as cg  # noqa: E402


def cad_scatter(rows, dest: Path):
    rows = [r for r in rows if "mean" in r.get("p1", {}) and "mean" in r.get("p2", {})]
    e1 = np.array([r["p1"]["mean"] for r in rows])
    fig, ax = plt.subplots(figsize=(5.2, 4.6))
    lo = 1e-4
    for key, mk, lab in (("p2", "o", "order 2"), ("heat", "^", "heat"), ("fmm", "s", "FMM")):
        e = np.array([r.get(key, {}).get("mean", np.nan) for r in rows])
        ax.scatter(np.maximum(e1, lo), np.maximum(e, lo), marker=mk, s=18, label=lab, alpha=0.8)
    ax.plot([lo, 1], [lo, 1], "k-", lw=0.8)
    ax.plot([lo, 1], [lo / 2, 0.5], "k:", lw=0.8, label="half of order 1")
    ax.set(xscale="log", yscale="log", xlim=(lo, 1), ylim=(lo, 1), xlabel="order 1 (P1 qclp): mean relative error",
           ylabel="mean relative error", title=f"Coarse CAD meshes ({len(rows)}), source vertex 0, vs exact MMP")
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(dest, dpi=120)
    plt.close(fig)


def flat_panel(dest: Path):
    """Error maps on a flat fan plate: order 1, order 2, heat."""
    import matplotlib.tri as mtri

    k = 12
    top = [(x, 1.0) for x in np.linspace(0, 2, k)]
    bottom = [(x, 0.0) for x in np.linspace(0, 2, k)]
    V = np.array([(*p, 0.0) for p in bottom + top])
    F = [[0, k + i + 1, k + i] for i in range(k - 1)] + [[i, i + 1, 2 * k - 1] for i in range(k - 1)]
    mesh = cg.TriMesh(V, np.array([f for f in F if len(set(f)) == 3]))
    src = 5
    ex = np.linalg.norm(V - V[src], axis=1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fields = {
            "order 1 (qclp)": cg.GeodesicSolver(mesh, "qclp").solve(src).distance,
            "order 2": cg.GeodesicSolver(mesh, "qclp", order=2).solve(src).distance,
            "heat": cg.GeodesicSolver(mesh, "heat").solve(src).distance,
        }
    tri = mtri.Triangulation(V[:, 0], V[:, 1], mesh.F)
    fig, axes = plt.subplots(1, 3, figsize=(11, 2.6))
    for ax, (name, d) in zip(axes, fields.items(), strict=True):
        err = np.abs(d - ex) / ex.max()
        tp = ax.tripcolor(tri, err, shading="gouraud", vmin=0, vmax=0.05, cmap="magma")
        ax.triplot(tri, lw=0.3, color="w")
        ax.set_title(f"{name}: max {err.max():.1e}", fontsize=9)
        ax.set_aspect("equal")
        ax.axis("off")
    fig.colorbar(tp, ax=axes, shrink=0.8, label="|d − exact| / max d")
    fig.savefig(dest, dpi=120)
    plt.close(fig)


def main(argv):
    cad, fine, out = json.loads(Path(argv[0]).read_text()), json.loads(Path(argv[1]).read_text()), Path(argv[2])
    out.mkdir(parents=True, exist_ok=True)
    cad_scatter(cad, out / "order2_cad.png")
    flat_panel(out / "order2_flat_fan.png")
    del fine


if __name__ == "__main__":
    main(sys.argv[1:])
