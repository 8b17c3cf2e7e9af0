"""The set-up of a one-shot ``GeodesicSolver(mesh, method, solver="ipm").solve(0)``, piece by piece.

Not a test: run it by hand (docs/dev/performance-log.md, "Set-up cost")::

    python benchmarks/setup_cost.py --meshes bimba horse armadillo --methods qcqp-hessian qclp --repeat 3
    python benchmarks/setup_cost.py --meshes /tmp/bunny_1m.npz --methods qcqp-hessian --no-solve
    python benchmarks/setup_cost.py --meshes bimba --compare /path/to/other/checkout/src   # alternating runs

Every run is a fresh process (``--child``) that loads the compiled kernels first (``warm_up``, not timed), then
times, with ``time.perf_counter`` around the library's own functions (each piece exclusive of the pieces
nested in it):

``energy``
    the smoothness energy's assembly (``hessian_energy_matrix`` without its PSD check);
``psd``
    the PSD check (``is_positive_semidefinite``), with its own symbolic analysis where it makes one;
``pattern``
    ``kkt_pattern``;
``analysis``
    the interior-point solver's symbolic analysis (``SymbolicCholesky``; PARDISO's METIS ordering and
    symbolic factorization);
``other``
    the rest of the construction: the unit mesh, ``MeshOperators`` (degenerate faces), gradient blocks, the
    mesh's edge tables;
``api``
    the façade around the strategy (validation, the default thread count's samples of ``/proc/stat``);
``setup``
    the whole construction (``GeodesicSolver(...)``), the sum of the above;
``prep``
    the first solve up to its first iteration (sources, ``build_problem``, the IPM's program and starting
    point);
``solve``, ``iterations``
    the whole first solve (with ``--no-solve``: stopped at the first iteration).

``--compare SRC`` runs every case with ``PYTHONPATH=SRC`` too, alternating with this checkout's ``src`` in
each repetition (the machine may be shared: compare only runs made side by side). A mesh is a name in
``../shared/meshes`` (``bimba`` finds ``bimba.obj``) or an ``.npz`` with ``V`` and ``F``.
"""

from __future__ import annotations

import argparse
import functools
import json
import os
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
SRC = HERE.parent / "src"
SHARED = HERE.parents[1] / "shared" / "meshes"
PIECES = ("energy", "psd", "pattern", "analysis", "other")
#: the façade around the strategy (validation, the thread count), reported as ``api``


def _mesh(spec: str):
    import numpy as np

    import cvxgeodesic as cg

    if spec.endswith(".npz"):
        data = np.load(spec)
        return cg.TriMesh(data["V"], data["F"], name=Path(spec).stem)
    path = Path(spec)
    if not path.exists():
        path = next(p for p in sorted(SHARED.glob(spec + ".*")) if p.suffix in (".obj", ".ply", ".off", ".stl"))
    return cg.load_mesh(path)


def _instrument(acc: dict[str, float]) -> None:
    """Wrap the library's set-up functions so that each adds its own time (nested pieces excluded) to ``acc``."""
    from cvxgeodesic.linalg import symbolic
    from cvxgeodesic.operators import energies
    from cvxgeodesic.problems import conic as problem
    from cvxgeodesic.strategies import direct

    stack: list[list] = []  # [label, time spent in nested wrapped calls]

    def wrap(owner, name, label):
        fn = getattr(owner, name)

        @functools.wraps(fn)
        def timed(*args, **kwargs):
            lab = label
            if label == "analysis" and any(frame[0] == "psd" for frame in stack):
                lab = "psd"  # the PSD check's own analysis
            stack.append([lab, 0.0])
            t0 = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                dt = time.perf_counter() - t0
                _, inner = stack.pop()
                acc[lab] = acc.get(lab, 0.0) + dt - inner
                if stack:
                    stack[-1][1] += dt

        setattr(owner, name, timed)

    wrap(energies, "hessian_energy_matrix", "energy")
    wrap(energies, "is_positive_semidefinite", "psd")
    wrap(symbolic.SymbolicCholesky, "__init__", "analysis")
    wrap(direct.DirectStrategy, "__init__", "other")
    for module in (problem, direct):
        if hasattr(module, "kkt_pattern"):
            wrap(module, "kkt_pattern", "pattern")


def run_case(spec: str, method: str, solve: bool) -> dict:
    """One case in this process: the pieces in seconds, the iterations, the load average."""
    import cvxgeodesic as cg
    from cvxgeodesic.strategies.warm_up import warm_up

    mesh = _mesh(spec)
    warm_up()
    acc: dict[str, float] = {}
    _instrument(acc)
    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    solver = cg.GeodesicSolver(mesh, method, solver="ipm")
    t1 = time.perf_counter()
    out: dict = {"mesh": mesh.name, "faces": mesh.n_faces, "method": method, "setup": t1 - t0, "load": load,
                 **{k: acc.get(k, 0.0) for k in PIECES}}
    out["api"] = out["setup"] - sum(out[k] for k in PIECES)
    first: dict = {}

    class _Stop(Exception):
        pass

    def callback(it, info):
        first.setdefault("t", time.perf_counter())
        if not solve:
            raise _Stop

    try:
        res = solver.solve(0, callback=callback)
        out.update(iterations=res.info.iterations, status=res.info.status)
    except _Stop:
        pass
    t2 = time.perf_counter()
    out.update(prep=first.get("t", t2) - t1, solve=t2 - t1)
    return out


def _child(src: Path, spec: str, method: str, solve: bool, timeout: float) -> dict:
    env = dict(os.environ, PYTHONPATH=str(src))
    cmd = [sys.executable, __file__, "--child", json.dumps([spec, method, solve])]
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=timeout)
    if proc.returncode:
        raise RuntimeError(proc.stderr[-2000:])
    return json.loads(proc.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--child", help=argparse.SUPPRESS)
    ap.add_argument("--meshes", nargs="+", default=["bimba", "horse", "armadillo"])
    ap.add_argument("--methods", nargs="+", default=["qcqp-hessian", "qclp"])
    ap.add_argument("--repeat", type=int, default=3, help="runs per case and checkout; the minimum is kept")
    ap.add_argument("--compare", type=Path, default=None, metavar="SRC", help="another checkout's src, alternated")
    ap.add_argument("--no-solve", action="store_true", help="stop the first solve at its first iteration")
    ap.add_argument("--timeout", type=float, default=900.0)
    ap.add_argument("--json", type=Path, default=None, help="also write every run to this file")
    ap.add_argument("--table", type=Path, default=None, help="only print the table of a --json file")
    args = ap.parse_args(argv)
    if args.child:
        spec, method, solve = json.loads(args.child)
        print(json.dumps(run_case(spec, method, solve)))
        return 0
    if args.table:
        _table(json.loads(args.table.read_text()))
        return 0
    srcs = {"this": SRC} | ({"compare": args.compare.resolve()} if args.compare else {})
    runs: list[dict] = []
    print(f"load average at the start: {os.getloadavg()}", flush=True)
    for spec in args.meshes:
        for method in args.methods:
            for rep in range(args.repeat):
                for label, src in srcs.items():
                    row = _child(src, spec, method, not args.no_solve, args.timeout) | {"src": label, "rep": rep}
                    runs.append(row)
                    print(json.dumps(row), flush=True)
    print(f"load average at the end: {os.getloadavg()}")
    if args.json:
        args.json.write_text(json.dumps(runs, indent=1) + "\n")
    _table(runs)
    return 0


def _table(runs: list[dict]) -> None:
    """Markdown table: per case and checkout the run with the shortest set-up (its pieces, and their share of
    it), the shortest first solve, and the load averages seen."""
    keys = [*PIECES, "api", "setup", "prep", "solve"]
    print("| mesh (faces) | method | checkout | " + " | ".join(keys) + " | it. | load |")
    print("|" + "---|" * (len(keys) + 5))
    cases = list(dict.fromkeys((r["mesh"], r["method"], r["src"]) for r in runs))
    for case in cases:
        same = [x for x in runs if (x["mesh"], x["method"], x["src"]) == case]
        best = min(same, key=lambda x: x["setup"])
        cells = [f"{best[k]:.3f} ({100 * best[k] / best['setup']:.0f} %)" for k in (*PIECES, "api")]
        cells += [f"{best['setup']:.3f}", f"{best['prep']:.3f}", f"{min(x['solve'] for x in same):.3f}"]
        loads = [x["load"] for x in same]
        print(f"| {case[0]} ({best['faces']:,}) | {case[1]} | {case[2]} | " + " | ".join(cells)
              + f" | {best.get('iterations', '-')} | {min(loads):.1f}–{max(loads):.1f} |")


if __name__ == "__main__":
    sys.exit(main())
