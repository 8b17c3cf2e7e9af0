"""What a travel cost or a metric adds to a solve: time ratios against the unweighted solve, in one run.

Not a test: run it by hand (target of issue 24: at most 1.2x)::

    python benchmarks/metric_speed.py                       # bundled spot (5.9K faces), orders 1 and 2
    python benchmarks/metric_speed.py --mesh bimba --repeat 5 --orders 1

For each method and order it builds one ``GeodesicSolver`` per medium (none; a per-vertex cost from the height,
``1 + z²`` scaled to [1, 3]; a per-face anisotropic metric, ``I + 3 t tᵀ`` with ``t`` a tangent direction of each
face) and times ``solve(0)`` ``--repeat`` times, the media interleaved in each repetition (the machine may be
shared: only runs side by side compare); the set-up (``GeodesicSolver(...)``) is timed once per medium. Prints the
minimum times, the ratios to the unweighted solve, the iteration counts, the machine's load and the date.

A mesh is the bundled ``spot``, a name in ``../shared/meshes`` (``bimba`` finds ``bimba.obj``) or a path.
"""

from __future__ import annotations

import argparse
import os
import time
from datetime import date
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SHARED = HERE.parents[1] / "shared" / "meshes"


def load(spec: str):
    import cvxgeodesic as cg

    if spec == "spot":
        return cg.load_mesh(Path(cg.__file__).parent / "data" / "spot.obj")
    path = Path(spec)
    if not path.exists():
        found = sorted(SHARED.glob(f"{spec}.*"))
        if not found:
            raise SystemExit(f"no mesh {spec!r} (bundled: spot; shared: {SHARED})")
        path = found[0]
    return cg.load_mesh(path)


def media(mesh) -> dict[str, dict]:
    """The media compared: none, a per-vertex cost, a per-face anisotropic metric."""
    z = mesh.V[:, 2]
    z = (z - z.min()) / max(np.ptp(z), 1e-300)
    cost = 1.0 + 2.0 * z**2
    e = mesh.V[mesh.F[:, 1]] - mesh.V[mesh.F[:, 0]]
    t = e / np.linalg.norm(e, axis=1, keepdims=True)
    metric = np.eye(3)[None] + 3.0 * np.einsum("ki,kj->kij", t, t)
    return {"none": {}, "cost": {"cost": cost}, "metric": {"metric": metric}}


def run(mesh, method: str, order: int, repeat: int) -> list[dict]:
    import cvxgeodesic as cg

    cases = media(mesh)
    solvers, setup = {}, {}
    for name, kw in cases.items():
        t0 = time.perf_counter()
        solvers[name] = cg.GeodesicSolver(mesh, method, order=order, **kw)
        setup[name] = time.perf_counter() - t0
    times: dict[str, list[float]] = {name: [] for name in cases}
    iters = {}
    for _ in range(repeat):
        for name, solver in solvers.items():
            t0 = time.perf_counter()
            res = solver.solve(0)
            times[name].append(time.perf_counter() - t0)
            iters[name] = res.info.iterations
    base = min(times["none"])
    return [{"method": method, "order": order, "medium": name, "setup_s": setup[name], "solve_s": min(times[name]),
             "ratio": min(times[name]) / base, "iterations": iters[name]} for name in cases]


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--mesh", default="spot")
    p.add_argument("--methods", nargs="+", default=["qclp", "qcqp-hessian"])
    p.add_argument("--orders", nargs="+", type=int, default=[1, 2])
    p.add_argument("--repeat", type=int, default=3)
    args = p.parse_args(argv)
    from cvxgeodesic.strategies.warm_up import warm_up

    warm_up()
    mesh = load(args.mesh)
    load0 = os.getloadavg()
    rows = []
    for order in args.orders:
        for method in args.methods if order == 1 else ["qclp"]:
            rows += run(mesh, method, order, args.repeat)
    load1 = os.getloadavg()
    print(f"{mesh.name}: {mesh.n_vertices} vertices, {mesh.n_faces} faces; {date.today()}; minimum of {args.repeat} "
          f"solves; load average {load0[0]:.2f} before, {load1[0]:.2f} after; "
          f"CVXGEODESIC_THREADS={os.environ.get('CVXGEODESIC_THREADS', 'default')}")
    print(f"{'method':<14}{'order':>6}{'medium':>8}{'set-up s':>10}{'solve s':>10}{'ratio':>8}{'iter':>6}")
    for r in rows:
        print(f"{r['method']:<14}{r['order']:>6}{r['medium']:>8}{r['setup_s']:>10.3f}{r['solve_s']:>10.3f}"
              f"{r['ratio']:>8.2f}{r['iterations']:>6}")


if __name__ == "__main__":
    main()
