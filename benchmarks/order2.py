"""Order 2 (P2 squared distance) against order 1 (P1 qclp), heat, FMM and exact MMP.

Usage: ``PYTHONPATH=src python benchmarks/order2.py [--weights=consistent|lumped] OUT.json [mesh ...]``; meshes are
names in ../shared/meshes (``thingi10k_small`` expands to its files); ``--weights`` sets the study switch
:data:`cvxgeodesic.problems._study.WEIGHTS`.

``PYTHONPATH=src python benchmarks/order2.py --speed [--repeat=N] [--json=PATH] [mesh ...]`` (default spot,
bunny_7k) prints the order-2 times (qclp, qcqp-hessian) beside P1 qclp's, the heat method's and exact MMP's (set-up
included) in one process, with the ratios, iteration counts and the load average, and ends with the ranges the docs
quote, the meshes named (``order 2 / order 1: 1.0–10.7× over 8 meshes: fandisk.obj, ...``). Source vertex 0; errors
are relative, per vertex, sources excluded, against pygeodesic's exact MMP. Times are wall-clock on whatever machine
runs it (state its load when you publish them).
"""

from __future__ import annotations

import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import cvxgeodesic as cg
from cvxgeodesic.baselines import BASELINES
from cvxgeodesic.mesh.generate import delaunay_plane as delaunay_mesh
from cvxgeodesic.mesh.generate import fan_plate, needle_strip

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "meshes"


# ---------------------------------------------------------------- flat test meshes (also used by report.py)
def euclid_from(mesh: cg.TriMesh, src) -> np.ndarray:
    """(n,) Euclidean distances from a vertex index or a ``(face, bary)`` point: exact on a flat mesh."""
    if isinstance(src, int | np.integer):
        p = mesh.V[src]
    else:
        p = np.asarray(src[1]) @ mesh.V[mesh.F[src[0]]]
    return np.linalg.norm(mesh.V - p, axis=1)


BARYS = ((0.2, 0.3, 0.5), (0.5, 0.5, 0.0), (1 / 3, 1 / 3, 1 / 3))  # inside, on an edge, at the centroid


def flat_cases(quick: bool = False) -> list[tuple[str, cg.TriMesh, list, list]]:
    """The flat meshes of ``tests/test_order2.py`` with their sources.

    Returns
    -------
    list of (label, mesh, vertex sources, point sources)
        Point sources are ``(face, (b0, b1, b2))``; ``quick`` gives smaller stand-ins.
    """
    fan = fan_plate()
    if quick:
        return [("jittered 8×8 grid", cg.grid_plane(8, jitter=0.4, seed=1), [0, 40], [(10, BARYS[0])]),
                ("needle strip, aspect 50", needle_strip(10, 50), [0, 5], [(4, (0.25, 0.25, 0.5))]),
                ("CAD plate of fans", fan, [0, 5, fan.n_vertices - 1], [(3, (0.3, 0.3, 0.4))])]
    cases = [("jittered 20×20 grid", cg.grid_plane(20, jitter=0.4, seed=1), [0, 200, 37],
              [(37, b) for b in BARYS])]
    cases += [(f"needle strip, aspect {a}", needle_strip(10, a), [0, 5], [(4, (0.25, 0.25, 0.5))])
              for a in (50, 240, 1000)]
    cases.append(("random Delaunay (300 points)", delaunay_mesh(), [0, 17], [(10, b) for b in BARYS]))
    cases.append(("CAD plate of fans", fan, [0, 5, fan.n_vertices - 1], [(3, (0.3, 0.3, 0.4)), (15, (0.1, 0.1, 0.8))]))
    return cases


def cad_names(shared: Path = SHARED) -> list[str]:
    """The coarse CAD set: the seven ``thingi_*.stl`` files, then ``thingi10k_small/*.stl`` (names in ``shared``)."""
    return (sorted(p.name for p in shared.glob("thingi_*.stl"))
            + [f"thingi10k_small/{p.name}" for p in sorted((shared / "thingi10k_small").glob("*.stl"))])


def rel_err(d, de):
    ok = np.isfinite(de) & (de > 1e-12 * np.nanmax(de[np.isfinite(de)]))
    r = np.abs(d[ok] - de[ok]) / de[ok]
    return float(np.mean(r)), float(np.max(r))


def run(name: str) -> dict:
    mesh = cg.load_mesh(SHARED / name)
    out = {"mesh": name, "faces": mesh.n_faces, "vertices": mesh.n_vertices}
    try:
        de, _ = BASELINES["exact"](mesh).solve(np.array([0]))
    except Exception as exc:  # non-manifold input: no exact reference
        out["skipped"] = f"exact: {type(exc).__name__}: {exc}"
        return out
    de = np.asarray(de, float)
    for label, kw in (("p1", {"method": "qclp"}), ("p2", {"method": "qclp", "order": 2}),
                      ("heat", {"method": "heat"}), ("fmm", {"method": "fmm"})):
        try:
            s = cg.GeodesicSolver(mesh, **kw)
            t = time.perf_counter()
            r = s.solve(0)
            out[label] = {"time": time.perf_counter() - t + s.setup_time, "status": r.info.status,
                          "mean": rel_err(r.distance, de)[0], "max": rel_err(r.distance, de)[1],
                          "solver": r.info.solver, "notes": list(r.info.notes)}
        except Exception as exc:
            out[label] = {"error": f"{type(exc).__name__}: {exc}"}
    return out


def _timed(mesh: cg.TriMesh, repeat: int, method: str = "qclp", **kw) -> tuple[float, object]:
    """Best wall-clock time of ``repeat`` solves from vertex 0, each with its setup (solver construction); ``(inf,
    None)`` when the method cannot run on the mesh (the exact algorithm on a non-manifold one)."""
    best, res = np.inf, None
    for _ in range(repeat):
        t = time.perf_counter()
        try:
            res = cg.GeodesicSolver(mesh, method, **kw).solve(0)
        except Exception:  # noqa: BLE001 - a method that cannot run is a blank cell
            return np.inf, None
        best = min(best, time.perf_counter() - t)
    return best, res


#: The columns of ``--speed``: (label, method, keyword arguments).
SPEED_RUNS = (("heat", "heat", {}), ("exact", "exact", {}), ("P1 qclp", "qclp", {}),
              ("o2 qclp", "qclp", {"order": 2}), ("o2 hessian", "qcqp-hessian", {"order": 2}))


def speed(argv: list[str]) -> list[dict]:
    """``--speed [--repeat=N] [--json=PATH] [mesh ...]``: order 2 (qclp and qcqp-hessian) against P1 qclp, the heat
    method and exact MMP, one row per mesh, printed as it goes: times (set-up + solve), order-2 iterations (all
    cutting-plane rounds) and the ratios of issue 29 (order 2 / exact, order 2 / P1) and of issue 25 (smoothed /
    plain order 2)."""
    import os

    repeat, dest = 1, None
    while argv and argv[0].startswith("--"):
        key, _, value = argv.pop(0).partition("=")
        if key == "--repeat":
            repeat = int(value)
        elif key == "--json":
            dest = Path(value)
        else:
            raise SystemExit(f"unknown option {key}")
    names = argv or ["spot.obj", "bunny_7k.off"]
    warm = cg.icosphere(1)
    for _, method, kw in SPEED_RUNS:  # compiles (or loads) the Numba kernels outside the timings
        _timed(warm, 1, method, **kw)
    rows = []
    print(f"{'mesh':22s} {'faces':>6s} " + " ".join(f"{lab:>10s}" for lab, _, _ in SPEED_RUNS)
          + "  o2/exact  o2/P1  hess/o2  it(o2)  load (1, 5, 15 min)")
    for nm in names:
        mesh = cg.load_mesh(SHARED / nm)
        row: dict = {"mesh": nm, "faces": mesh.n_faces, "date": time.strftime("%Y-%m-%d %H:%M")}
        for label, method, kw in SPEED_RUNS:
            t, r = _timed(mesh, repeat, method, **kw)
            row[label] = {"time": t, "iterations": None if r is None else r.info.iterations,
                          "status": None if r is None else r.info.status,
                          "rounds": None if r is None else r.info.extra.get("rounds")}
        row["load"] = os.getloadavg()
        rows.append(row)
        t = {lab: row[lab]["time"] for lab, _, _ in SPEED_RUNS}
        print(f"{nm:22s} {mesh.n_faces:6d} " + " ".join(f"{t[lab]:9.2f}s" for lab, _, _ in SPEED_RUNS)
              + f"  {t['o2 qclp'] / t['exact']:8.1f} {t['o2 qclp'] / t['P1 qclp']:6.1f} "
              f"{t['o2 hessian'] / t['o2 qclp']:8.2f}  {row['o2 qclp']['iterations']:6d}  "
              + " ".join(f"{x:.2f}" for x in row["load"]), flush=True)
        if dest is not None:
            dest.write_text(json.dumps(rows, indent=1, default=float))
    for line in speed_summary(rows):
        print(line)
    return rows


def speed_summary(rows: list[dict]) -> list[str]:
    """The lines the docs quote (README, docs/order2.md "Speed"): the range of each ratio over the meshes, named.

    ``order 2 / order 1`` is order-2 ``qclp`` against P1 ``qclp``, ``order 2 / exact`` against exact MMP (over the
    meshes it ran on: not the non-manifold ones), both set-up + solve from vertex 0.
    """
    out = []
    for label, ref in (("order 1", "P1 qclp"), ("exact", "exact")):
        pairs = [(r["mesh"], r["o2 qclp"]["time"] / r[ref]["time"]) for r in rows
                 if np.isfinite(r[ref]["time"]) and np.isfinite(r["o2 qclp"]["time"])]
        if pairs:
            ratios = [x for _, x in pairs]
            out.append(f"order 2 / {label}: {min(ratios):.1f}–{max(ratios):.1f}× over {len(pairs)} meshes: "
                       + ", ".join(name for name, _ in pairs))
    return out


def main(argv):
    warnings.simplefilter("ignore")
    if argv and argv[0] == "--speed":
        speed(argv[1:])
        return
    if argv[0].startswith("--weights="):
        from cvxgeodesic.problems import _study

        _study.WEIGHTS = argv.pop(0).split("=", 1)[1]
    dest = Path(argv[0])
    names = []
    for a in argv[1:]:
        if a == "thingi10k_small":
            names += [n for n in cad_names() if n.startswith("thingi10k_small/")]
        else:
            names.append(a)
    rows = json.loads(dest.read_text()) if dest.exists() else []
    done = {r["mesh"] for r in rows}
    for nm in names:
        if nm in done:
            continue
        row = run(nm)
        rows.append(row)
        dest.write_text(json.dumps(rows, indent=1))
        print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
