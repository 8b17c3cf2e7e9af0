"""Figures of order 2 against order 1, heat and FMM: the coarse-CAD scatter and the flat fan-plate error maps.

``benchmarks/report.py`` (section ``order2``) draws both from the numbers of its run. Standalone, from
the JSON written by ``benchmarks/order2.py`` (the figures of ``docs/order2.md``)::

    PYTHONPATH=src python benchmarks/order2_figures.py CAD.json OUT_DIR
"""

from __future__ import annotations

import json
import sys
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import cvxgeodesic as cg  # noqa: E402

#: (key, marker, legend) of the methods plotted against order 1.
SCATTER = (("p2", "o", "order 2"), ("heat", "^", "heat"), ("fmm", "s", "FMM"))


def cad_scatter(points: Sequence[Mapping[str, float | None]], dest: Path, title: str | None = None) -> Path:
    """Mean error of order 2, heat and FMM against order 1's, one point per mesh, log-log.

    Parameters
    ----------
    points : sequence of mapping
        One per mesh: ``"p1"`` (order 1's mean relative error) and ``"p2"``, ``"heat"``, ``"fmm"``
        (None or missing where that method has no result); meshes without ``p1`` or ``p2`` are left out.
    dest : Path
        The PNG to write.
    title : str, optional
        Default: the number of meshes, source vertex 0, against exact MMP.

    Returns
    -------
    Path
        ``dest``.
    """
    rows = [p for p in points if p.get("p1") is not None and p.get("p2") is not None]
    e1 = np.array([r["p1"] for r in rows], dtype=float)
    fig, ax = plt.subplots(figsize=(5.2, 4.6))
    lo = 1e-4
    for key, mk, lab in SCATTER:
        e = np.array([np.nan if r.get(key) is None else r[key] for r in rows], dtype=float)
        ax.scatter(np.maximum(e1, lo), np.maximum(e, lo), marker=mk, s=18, label=lab, alpha=0.8)
    ax.plot([lo, 1], [lo, 1], "k-", lw=0.8)
    ax.plot([lo, 1], [lo / 2, 0.5], "k:", lw=0.8, label="half of order 1")
    ax.set(xscale="log", yscale="log", xlim=(lo, 1), ylim=(lo, 1), xlabel="order 1 (P1 qclp): mean relative error",
           ylabel="mean relative error",
           title=title or f"Coarse CAD meshes ({len(rows)}), source vertex 0, vs exact MMP")
    ax.title.set_fontsize(9)
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(dest, dpi=120)
    plt.close(fig)
    return dest


def flat_panel(mesh: cg.TriMesh, exact: np.ndarray, fields: Mapping[str, np.ndarray], dest: Path,
               vmax: float = 0.05, title: str | None = None) -> Path:
    """Error maps ``|d − exact| / max exact`` of several fields on one flat mesh (z = 0), side by side.

    Parameters
    ----------
    mesh : TriMesh
        A flat mesh, ``n`` vertices; drawn in its x-y plane.
    exact : (n,) float ndarray
        The exact distance.
    fields : mapping of str to (n,) float ndarray
        Panel title → field, left to right.
    dest : Path
        The PNG to write.
    vmax : float, default 0.05
        Top of the colour scale.
    title : str, optional
        A title above the panels.

    Returns
    -------
    Path
        ``dest``.
    """
    import matplotlib.tri as mtri

    V = np.asarray(mesh.V)
    tri = mtri.Triangulation(V[:, 0], V[:, 1], np.asarray(mesh.F))
    fig, axes = plt.subplots(1, len(fields), figsize=(3.7 * len(fields), 2.6))
    axes = np.atleast_1d(axes)
    tp = None
    for ax, (name, d) in zip(axes, fields.items(), strict=True):
        err = np.abs(np.asarray(d) - exact) / exact.max()
        tp = ax.tripcolor(tri, err, shading="gouraud", vmin=0, vmax=vmax, cmap="magma")
        ax.triplot(tri, lw=0.3, color="w")
        if np.min(exact) == 0.0:  # a vertex source: mark it
            k = int(np.argmin(exact))
            ax.plot(V[k, 0], V[k, 1], "o", ms=5, mfc="cyan", mec="k", mew=0.6)
        ax.set_title(f"{name}: max {err.max():.1e}", fontsize=9)
        ax.set_aspect("equal")
        ax.axis("off")
    fig.colorbar(tp, ax=list(axes), shrink=0.8, label="|d − exact| / max d")
    if title:
        fig.suptitle(title, fontsize=10)
    fig.savefig(dest, dpi=120, bbox_inches="tight")
    plt.close(fig)
    return dest


def fan_fields(src: int = 5) -> tuple[cg.TriMesh, np.ndarray, dict[str, np.ndarray]]:
    """The fan plate of ``order2.fan_plate`` from vertex ``src``: (mesh, exact, fields of order 1, order 2, heat)."""
    from order2 import fan_plate

    mesh = fan_plate()
    ex = np.linalg.norm(mesh.V - mesh.V[src], axis=1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fields = {
            "order 1 (qclp)": cg.GeodesicSolver(mesh, "qclp").solve(src).distance,
            "order 2": cg.GeodesicSolver(mesh, "qclp", order=2).solve(src).distance,
            "heat": cg.GeodesicSolver(mesh, "heat").solve(src).distance,
        }
    return mesh, ex, fields


def main(argv):
    cad, out = json.loads(Path(argv[0]).read_text()), Path(argv[-1])
    out.mkdir(parents=True, exist_ok=True)
    points = [{k: r.get(k, {}).get("mean") for k in ("p1", "p2", "heat", "fmm")} for r in cad]
    cad_scatter(points, out / "order2_cad.png")
    flat_panel(*fan_fields(), out / "order2_flat_fan.png")


if __name__ == "__main__":
    main(sys.argv[1:])
