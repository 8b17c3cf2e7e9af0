"""Time and peak memory against face count: QCQP-Hessian direct and coarse-to-fine, order 2, the heat method.

Not a test: run it by hand::

    python benchmarks/scaling.py                                   # 10K .. 1.1M faces from bunny.obj
    python benchmarks/scaling.py --sizes 10000,50000,70000 --no-direct-above 100000
    python benchmarks/scaling.py --sizes 1100000 --methods multires,heat
    python benchmarks/scaling.py --sizes 70000,1100000 --methods order2,heat    # P2 qclp

Meshes: ``../shared/meshes/bunny.obj`` (69,630 faces; ``--mesh`` for another file),
decimated with fast-simplification for the sizes below it and subdivided
(midpoint 4-to-1, ``cvxgeodesic.mesh.generate._subdivide_midpoint``, then
decimated to the size if it is not a power of 4 times the base) for those above.
Each (size, method) runs in its own Python process, which reports its own peak
resident set size (``ru_maxrss``, the whole process: interpreter and imports,
about 130 MiB with the solver's libraries, included), for multires plus that of
its child process (libigl's decimation runs in one); a case that exceeds ``--timeout`` is killed and shown
as ``>T``. Source vertex 0, m = 1.

Columns
-------
``direct``      ``GeodesicSolver(mesh)`` set-up (operators, Hessian energy, symbolic
                analysis) + ``solve(0)``, seconds; ``it`` its interior-point iterations.
``fact``        mean seconds of one numeric Cholesky factorization in that solve
                (``factor_time / factorizations``): the reference growth rate.
``multires``    ``GeodesicSolver(mesh, multires=True)`` set-up (decimation, coarse
                operators, transfer) + ``solve(0)``: an *approximation* (status
                ``"approximate"``), coarse mesh ``min(faces // 4, 50K)`` faces.
``err``         mean / max ``|d_multires − d_direct|`` over vertices, in % of the largest
                direct distance (when the direct case ran).
``order2``      ``GeodesicSolver(mesh, "qclp", order=2)`` set-up + ``solve(0)`` (P2 squared distance).
``heat``        potpourri3d heat method, set-up + solve, the ratio baseline.
``MiB``         peak resident memory of the case's process.

The growth exponents are least-squares slopes of log(time) against log(faces).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "meshes"
DEFAULT_SIZES = [10_000, 50_000, 70_000, 280_000, 1_100_000]
METHODS = ("direct", "multires", "order2", "heat")


def peak_mib(with_children: bool) -> float:
    """Peak RSS of this process, plus that of its largest child if ``with_children`` (multires: the libigl
    decimation runs in one), MiB.

    With children it is an upper bound of the simultaneous use: the parent waits while its child runs.
    Children are left out otherwise: short helper processes (threadpoolctl's ``ldconfig -p``) are forked
    from the solver process and their ``ru_maxrss`` is the parent's resident size at the fork, which would
    count the solver twice (measured: 715 MiB reported for a 390 MiB direct solve on bunny).
    """
    own = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    child = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss if with_children else 0
    return (own + child) / 1024.0  # KiB on Linux


# ---------------------------------------------------------------------------------------------------------------
# child: one case
# ---------------------------------------------------------------------------------------------------------------


def run_case(case: dict) -> dict:
    import cvxgeodesic as cg

    data = np.load(case["mesh"])
    mesh = cg.TriMesh(data["V"], data["F"], name=f"{case['faces']}")
    out: dict = {"method": case["method"], "faces": mesh.n_faces, "vertices": mesh.n_vertices}
    t0 = time.perf_counter()
    if case["method"] == "heat":
        solver = cg.GeodesicSolver(mesh, "heat")
    elif case["method"] == "multires":
        solver = cg.GeodesicSolver(mesh, "qcqp-hessian", multires=case.get("multires_faces") or True)
    elif case["method"] == "order2":
        solver = cg.GeodesicSolver(mesh, "qclp", order=2)
    else:
        solver = cg.GeodesicSolver(mesh, "qcqp-hessian")
    t1 = time.perf_counter()
    res = solver.solve(0)
    t2 = time.perf_counter()
    info = res.info
    out.update(setup=t1 - t0, solve=t2 - t1, total=t2 - t0, iterations=info.iterations, status=info.status)
    extra = info.extra
    if case["method"] in ("direct", "order2"):
        nfact = extra.get("factorizations") or extra.get("n_factorizations") or info.iterations
        out["fact"] = extra.get("factor_time", float("nan")) / max(1, nfact)
    if case["method"] == "direct":
        np.save(case["direct_field"], res.distance)
    if case["method"] == "multires":
        mr = extra.get("multires", {})
        out.update(coarse_faces=mr.get("coarse_faces"), simplifier=mr.get("simplifier"),
                   simplify_time=mr.get("simplify_time"), coarse_solve_time=mr.get("coarse_solve_time"),
                   transfer_time=(mr.get("transfer_setup_time") or 0) + (mr.get("transfer_time") or 0))
        if os.path.exists(case["direct_field"]):
            d = np.load(case["direct_field"])
            ok = np.isfinite(d) & np.isfinite(res.distance)
            e = np.abs(res.distance[ok] - d[ok]) / d[ok].max()
            out.update(err_mean=float(e.mean()), err_max=float(e.max()))
    out["peak_mib"] = peak_mib(with_children=case["method"] == "multires")
    return out


# ---------------------------------------------------------------------------------------------------------------
# parent: meshes, cases, table
# ---------------------------------------------------------------------------------------------------------------


def make_mesh(V: np.ndarray, F: np.ndarray, faces: int) -> tuple[np.ndarray, np.ndarray]:
    """A mesh with about ``faces`` faces from (V, F): subdivide while too small, then decimate to size."""
    import fast_simplification

    from cvxgeodesic.mesh.generate import _subdivide_midpoint

    while F.shape[0] < 0.95 * faces:
        V, F = _subdivide_midpoint(V, F)
    if F.shape[0] > 1.05 * faces:
        V, F = fast_simplification.simplify(np.array(V, dtype=np.float64), np.array(F, dtype=np.int64),
                                            target_count=int(faces))
        used = np.unique(F)
        remap = np.full(len(V), -1, dtype=np.int64)
        remap[used] = np.arange(used.size)
        V, F = V[used], remap[F]
    return np.asarray(V, dtype=np.float64), np.asarray(F, dtype=np.int64)


def run_child(case: dict, timeout: float) -> dict:
    cmd = [sys.executable, __file__, "--child", json.dumps(case)]
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"method": case["method"], "timeout": timeout}
    if proc.returncode != 0:
        last = (proc.stderr.strip().splitlines() or [f"exit code {proc.returncode}"])[-1]
        return {"method": case["method"], "error": last, "wall": time.perf_counter() - t0}
    return json.loads(proc.stdout.strip().splitlines()[-1])


def fmt_time(r: dict | None) -> str:
    if r is None:
        return "-"
    if "timeout" in r:
        return f">{r['timeout']:.0f}"
    if "error" in r:
        return "error"
    return f"{r['total']:.2f}"


def fmt_mem(r: dict | None) -> str:
    return f"{r['peak_mib']:.0f}" if r and "peak_mib" in r else "-"


def slope(xs, ys) -> float:
    pts = [(x, y) for x, y in zip(xs, ys, strict=True) if y is not None and np.isfinite(y) and y > 0]
    if len(pts) < 2:
        return float("nan")
    x, y = np.log([p[0] for p in pts]), np.log([p[1] for p in pts])
    return float(np.polyfit(x, y, 1)[0])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--child", help=argparse.SUPPRESS)
    ap.add_argument("--mesh", default=str(SHARED / "bunny.obj"), help="base mesh (default ../shared/meshes/bunny.obj)")
    ap.add_argument("--sizes", default=",".join(map(str, DEFAULT_SIZES)), help="comma-separated face counts")
    ap.add_argument("--max-faces", type=int, default=None, help="skip sizes above this")
    ap.add_argument("--no-direct-above", type=int, default=None, metavar="N",
                    help="run only multires and heat on meshes with more than N faces")
    ap.add_argument("--methods", default=",".join(METHODS), help="subset of direct,multires,heat")
    ap.add_argument("--multires-faces", type=int, default=None, help="coarse face count (default: multires=True)")
    ap.add_argument("--timeout", type=float, default=540.0, help="seconds per case (default 540)")
    ap.add_argument("--json", default=None, help="also write the rows to this JSON file")
    ap.add_argument("--merge", nargs="+", default=None, metavar="JSON",
                    help="print the table of rows saved by earlier --json runs (no new runs); "
                         "a later file's cases replace an earlier one's for the same size")
    args = ap.parse_args(argv)

    if args.child:
        print(json.dumps(run_case(json.loads(args.child))))
        return 0
    if args.merge:
        merged: dict[int, dict] = {}
        for name in args.merge:
            for row in json.loads(Path(name).read_text()):
                merged.setdefault(row["faces"], {}).update(row)
        report([merged[k] for k in sorted(merged)])
        return 0

    import cvxgeodesic as cg

    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    bad = [m for m in methods if m not in METHODS]
    if bad:
        ap.error(f"unknown methods {bad}; choose from {', '.join(METHODS)}")
    sizes = sorted(int(s) for s in args.sizes.split(","))
    if args.max_faces:
        sizes = [s for s in sizes if s <= args.max_faces]
    if not Path(args.mesh).exists():
        ap.error(f"{args.mesh} not found; pass --mesh")
    base = cg.load_mesh(args.mesh)
    load = os.getloadavg()
    print(f"base mesh {Path(args.mesh).name}: {base.n_faces} faces; {os.cpu_count()} CPUs; "
          f"load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}", flush=True)

    rows = []
    with tempfile.TemporaryDirectory(prefix="cvxgeodesic-scaling-") as tmp:
        for size in sizes:
            t = time.perf_counter()
            V, F = make_mesh(base.V, base.F, size)
            path = f"{tmp}/mesh_{size}.npz"
            np.savez(path, V=V, F=F)
            row = {"size": size, "faces": int(F.shape[0]), "vertices": int(V.shape[0])}
            print(f"{F.shape[0]} faces ({time.perf_counter() - t:.1f} s to build)", flush=True)
            for method in methods:
                if method == "direct" and args.no_direct_above and F.shape[0] > args.no_direct_above:
                    continue
                case = {"mesh": path, "faces": int(F.shape[0]), "method": method,
                        "direct_field": f"{tmp}/direct_{size}.npy", "multires_faces": args.multires_faces}
                r = run_child(case, args.timeout)
                row[method] = r
                detail = {k: (round(v, 3) if isinstance(v, float) else v) for k, v in r.items()
                          if k not in ("method", "faces", "vertices")}
                print(f"  {method:8s} {detail}", flush=True)
            rows.append(row)
    report(rows)
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    return 0


def report(rows: list[dict]) -> None:
    """Print the table and the growth exponents."""
    head = ["faces", "vertices", "direct s", "it", "fact s", "MiB", "multires s", "coarse", "err mean/max %",
            "MiB", "order2 s", "it", "MiB", "heat s", "MiB", "direct/heat", "multires/heat", "order2/heat"]
    lines = [head]
    for row in rows:
        d, mr, o2, h = row.get("direct"), row.get("multires"), row.get("order2"), row.get("heat")
        ok = lambda r: r is not None and "total" in r  # noqa: E731
        err = (f"{100 * mr['err_mean']:.2f} / {100 * mr['err_max']:.1f}" if ok(mr) and "err_mean" in mr else "-")
        lines.append([
            str(row["faces"]), str(row["vertices"]), fmt_time(d), str(d["iterations"]) if ok(d) else "-",
            f"{d['fact']:.3f}" if ok(d) else "-", fmt_mem(d), fmt_time(mr),
            str(mr.get("coarse_faces")) if ok(mr) else "-", err, fmt_mem(mr), fmt_time(o2),
            str(o2["iterations"]) if ok(o2) else "-", fmt_mem(o2), fmt_time(h), fmt_mem(h),
            f"{d['total'] / h['total']:.1f}" if ok(d) and ok(h) else "-",
            f"{mr['total'] / h['total']:.1f}" if ok(mr) and ok(h) else "-",
            f"{o2['total'] / h['total']:.1f}" if ok(o2) and ok(h) else "-",
        ])
    widths = [max(len(r[i]) for r in lines) for i in range(len(head))]
    print()
    print("| " + " | ".join(c.ljust(w) for c, w in zip(lines[0], widths, strict=True)) + " |")
    print("|" + "|".join("-" * (w + 2) for w in widths) + "|")
    for r in lines[1:]:
        print("| " + " | ".join(c.rjust(w) for c, w in zip(r, widths, strict=True)) + " |")

    faces = [row["faces"] for row in rows]

    def series(method, key="total"):
        return [row[method][key] if method in row and key in row[method] else None for row in rows]

    print()
    print("growth exponents (slope of log time vs log faces):")
    for label, ys in [("direct total", series("direct")), ("one factorization", series("direct", "fact")),
                      ("multires total", series("multires")), ("order2 total", series("order2")),
                      ("heat total", series("heat"))]:
        print(f"  {label:18s} {slope(faces, ys):.2f}")


if __name__ == "__main__":
    sys.exit(main())
