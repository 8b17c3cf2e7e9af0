"""The analytic cases of travel cost and metrics (docs/metrics.md), for the report's section and by hand.

Run by hand for one table (a minute)::

    python benchmarks/metric_cases.py            # the cases at the report's resolutions
    python benchmarks/metric_cases.py --quick    # small meshes

Every case is a flat jittered Delaunay grid of the unit square (:func:`cvxgeodesic.mesh.generate.delaunay_grid`):

- **linear velocity** ``v = a + b y``: ``T = arccosh(1 + b²|x − x₀|² / (2 v(x) v(x₀))) / b``; per-vertex cost
  ``1/v``; mean and max relative error of qclp at orders 1 and 2 and of Dijkstra;
- **two layers** of cost 1 below ``y = 1/2`` and 2 above (per face): where the path from a target crosses the
  interface, against Snell's law (the crossing that minimizes ``c₁|x − s| + c₂|t − x|``);
- **constant metric** ``M``: ``d = √((x − s)ᵀ M (x − s))``, the largest error over the largest distance;
- **constant cost** ``c``: the largest deviation from ``c`` times the unweighted field.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.optimize import minimize_scalar

import cvxgeodesic as cg
from cvxgeodesic.mesh.generate import delaunay_grid

#: The anisotropic metric of the constant-metric case (eigenvalues 2.33 and 0.67 in the plane).
METRIC = np.array([[2.0, 0.6, 0.0], [0.6, 1.0, 0.0], [0.0, 0.0, 1.0]])
LINEAR = (1.0, 2.0)  # a, b of v = a + b y
LAYERS = (1.0, 2.0)  # costs below and above y = 1/2


def nearest(mesh, xy) -> int:
    return int(np.argmin(np.linalg.norm(mesh.V[:, :2] - np.asarray(xy), axis=1)))


def errors(d: np.ndarray, exact: np.ndarray) -> dict:
    ok = exact > 0
    rel = np.abs(d - exact)[ok] / exact[ok]
    return {"rel_mean": float(rel.mean()), "rel_max": float(rel.max())}


def linear_velocity(nx: int):
    """``(mesh, cost (n,), source, exact (n,))`` of the linear-velocity medium."""
    a, b = LINEAR
    mesh = delaunay_grid(nx)
    v = a + b * mesh.V[:, 1]
    src = nearest(mesh, (0.5, 0.2))
    x0 = mesh.V[src]
    exact = np.arccosh(1 + b**2 * np.sum((mesh.V - x0) ** 2, axis=1) / (2 * v * (a + b * x0[1]))) / b
    return mesh, 1.0 / v, src, exact


def two_layers(nx: int):
    """``(mesh, cost (m,), source, target, Snell's crossing x)``: the interface y = 1/2 is made of edges."""
    c1, c2 = LAYERS
    mesh = delaunay_grid(nx, fix_rows=(0.5,))
    cost = np.where(mesh.V[mesh.F].mean(axis=1)[:, 1] < 0.5, c1, c2)
    s, t = nearest(mesh, (0.15, 0.1)), nearest(mesh, (0.85, 0.9))
    S, E = mesh.V[s], mesh.V[t]

    def time_through(x):
        return c1 * np.hypot(x - S[0], 0.5 - S[1]) + c2 * np.hypot(E[0] - x, E[1] - 0.5)

    crossing = minimize_scalar(time_through, bounds=(0, 1), method="bounded", options={"xatol": 1e-12}).x
    return mesh, cost, s, t, float(crossing)


def crossing_of(P: np.ndarray, y: float = 0.5) -> float:
    """x where the polyline ``P`` first crosses the line ``y``."""
    k = int(np.flatnonzero((P[:-1, 1] - y) * (P[1:, 1] - y) <= 0)[0])
    a, b = P[k], P[k + 1]
    return float(a[0] + (y - a[1]) / (b[1] - a[1]) * (b[0] - a[0]) if b[1] != a[1] else a[0])


def timed(mesh, method: str, src, **kw):
    t0 = time.perf_counter()
    res = cg.GeodesicSolver(mesh, method, **kw).solve(src)
    return res, time.perf_counter() - t0


def run(quick: bool = False) -> dict:
    """Every case; the numbers of the report's section (and the fields of its figures under ``"_fields"``)."""
    out: dict = {"linear": [], "layers": [], "metric": [], "constant": []}
    figs: dict = {}
    for nx in (10, 20) if quick else (15, 30, 60):
        mesh, cost, src, exact = linear_velocity(nx)
        row = {"nx": nx, "faces": mesh.n_faces}
        for tag, method, order in (("p1", "qclp", 1), ("p2", "qclp", 2), ("dijkstra", "dijkstra", 1)):
            res, wall = timed(mesh, method, src, order=order, cost=cost)
            row[tag] = {**errors(res.distance, exact), "time_s": wall}
            if tag == "p2":
                figs["linear"] = (mesh, res.distance, exact, src)
        out["linear"].append(row)
    nx = 20 if quick else 40
    mesh, cost, s, t, analytic = two_layers(nx)
    straight = crossing_of(mesh.V[[s, t]])  # of the Euclidean straight line
    paths = {}
    for order in (1, 2):
        res, wall = timed(mesh, "qclp", s, order=order, cost=cost)
        P = cg.geodesic_path(mesh, res, t)
        paths[order] = P
        out["layers"].append({"nx": nx, "order": order, "crossing": crossing_of(P), "analytic": analytic,
                              "straight": straight, "error": abs(crossing_of(P) - analytic), "time_s": wall})
    figs["layers"] = (mesh, cost, s, t, paths, analytic)
    for nx in (10, 20) if quick else (20, 40):
        mesh = delaunay_grid(nx)
        src = nearest(mesh, (0.4, 0.45))
        X = mesh.V - mesh.V[src]
        exact = np.sqrt(np.einsum("ki,ij,kj->k", X, METRIC, X))
        for order in (1, 2):
            res, wall = timed(mesh, "qclp", src, order=order, metric=METRIC)
            out["metric"].append({"nx": nx, "order": order, "max_over_largest":
                                  float(np.abs(res.distance - exact).max() / exact.max()),
                                  **errors(res.distance, exact), "time_s": wall})
    mesh = cg.icosphere(2 if quick else 3)
    for method, order in (("qclp", 1), ("qcqp-hessian", 1), ("qclp", 2)):
        d0 = cg.geodesic_distance(mesh, 0, method=method, order=order)
        for c in (0.3, 3.7):
            d = cg.geodesic_distance(mesh, 0, method=method, order=order, cost=c)
            out["constant"].append({"mesh": mesh.name, "method": method, "order": order, "c": c,
                                    "deviation": float(np.abs(d - c * d0).max() / (c * d0).max())})
    out["_fields"] = figs
    return out


def figures(data: dict, linear_png, layers_png) -> None:
    """The section's two pictures: the linear-velocity field against the exact one (with the errors against the
    resolution), and the two-layer paths over the cost."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    mesh, d, exact, src = data["_fields"]["linear"]
    fig, axes = plt.subplots(1, 2, figsize=(9.5, 4.0))
    ax = axes[0]
    levels = np.linspace(0, float(exact.max()), 12)[1:-1]
    ax.tricontour(mesh.V[:, 0], mesh.V[:, 1], mesh.F, exact, levels=levels, colors="k", linewidths=2.2, alpha=0.35)
    ax.tricontour(mesh.V[:, 0], mesh.V[:, 1], mesh.F, d, levels=levels, colors="C3", linewidths=0.9)
    ax.plot(*mesh.V[src, :2], "o", color="c", ms=6)
    ax.set_aspect("equal")
    ax.set_title("travel time, v = 1 + 2y: exact (grey), order 2 (red)", fontsize=9)
    ax = axes[1]
    rows = data["linear"]
    faces = [r["faces"] for r in rows]
    for tag, name in (("dijkstra", "Dijkstra"), ("p1", "order 1 (qclp)"), ("p2", "order 2")):
        ax.plot(faces, [100 * r[tag]["rel_mean"] for r in rows], marker="o", label=name)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("faces")
    ax.set_ylabel("mean relative error (%)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, frameon=False)
    fig.tight_layout()
    fig.savefig(linear_png, dpi=90)
    plt.close(fig)

    mesh, cost, s, t, paths, analytic = data["_fields"]["layers"]
    fig, ax = plt.subplots(figsize=(4.6, 4.4))
    ax.tripcolor(mesh.V[:, 0], mesh.V[:, 1], mesh.F, facecolors=cost, cmap="Greys", vmin=0, vmax=4, alpha=0.6)
    for order, style in ((1, "C0-"), (2, "C3--")):
        ax.plot(paths[order][:, 0], paths[order][:, 1], style, lw=1.5, label=f"path, order {order}")
    ax.plot([mesh.V[s, 0], analytic, mesh.V[t, 0]], [mesh.V[s, 1], 0.5, mesh.V[t, 1]], "k:", lw=1,
            label="Snell's law")
    ax.axhline(0.5, color="k", lw=0.5)
    ax.set_aspect("equal")
    ax.legend(fontsize=8, loc="upper left", frameon=False)
    ax.set_title("two layers: cost 1 (below), 2 (above)", fontsize=9)
    fig.tight_layout()
    fig.savefig(layers_png, dpi=90)
    plt.close(fig)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args(argv)
    data = run(args.quick)
    for r in data["linear"]:
        print(f"linear velocity {r['nx']}x{r['nx']}: " + ", ".join(
            f"{tag} {100 * r[tag]['rel_mean']:.3f} % / {100 * r[tag]['rel_max']:.2f} %" for tag in ("p1", "p2",
                                                                                                   "dijkstra")))
    for r in data["layers"]:
        print(f"two layers, order {r['order']}: crossing {r['crossing']:.5f}, Snell {r['analytic']:.5f}, "
              f"straight {r['straight']:.5f}")
    for r in data["metric"]:
        print(f"constant metric {r['nx']}x{r['nx']}, order {r['order']}: max error / largest distance "
              f"{r['max_over_largest']:.2e}, mean relative {100 * r['rel_mean']:.3f} %")
    for r in data["constant"]:
        print(f"constant cost {r['c']} on {r['mesh']}, {r['method']} order {r['order']}: "
              f"deviation {r['deviation']:.1e}")


if __name__ == "__main__":
    main()
