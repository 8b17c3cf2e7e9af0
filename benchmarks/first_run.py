"""The first solve after an installation (an empty Numba cache) against the same solve once the cache is filled.

Not a test: run it by hand::

    python benchmarks/first_run.py                      # spot: qcqp-hessian, qclp, qclp order 2, both orders
    python benchmarks/first_run.py --repeat 3 --kernels  # min of 3; which kernels compiled and how long each took

Every case runs in a fresh Python process with ``NUMBA_CACHE_DIR`` pointed at a new empty folder ("cold": the state
right after ``pip install``), then again in a fresh process on the cache the first one filled ("warm"). The time is
that of the user's calls, from ``GeodesicSolver(...)`` to the end of ``solve`` (imports excluded), wall-clock and
the process's CPU time (on a loaded machine the CPU time is the steadier of the two); the cold run
also lists the package's kernels that compiled (Numba's ``numba:compile`` events) with the CPU seconds each took,
nested compilations included in their caller's. State the machine's load (``uptime``) with the numbers.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

CASES = {
    "qcqp-hessian": [("qcqp-hessian", 1)],
    "qclp": [("qclp", 1)],
    "qclp order 2": [("qclp", 2)],
    "both orders": [("qclp", 1), ("qclp", 2)],
}

CHILD = r"""
import json, sys, time, warnings
from numba.core import event
import cvxgeodesic as cg
from cvxgeodesic.mesh.io import load_mesh
from importlib.resources import files

compiled, stack = [], []

class Record(event.Listener):  # compilations nest (a kernel calling another): a stack of the open ones
    def on_start(self, ev):
        f = ev.data["dispatcher"].py_func
        stack.append((f.__module__.rsplit(".", 1)[-1] + "." + f.__name__, f.__module__, time.process_time()))
    def on_end(self, ev):
        name, module, t0 = stack.pop()
        if module.startswith("cvxgeodesic."):
            compiled.append((name, round(time.process_time() - t0, 3)))

event.register("numba:compile", Record())
mesh = load_mesh(str(files("cvxgeodesic") / "data" / "spot.obj"))
runs = json.loads(sys.argv[1])
times, notices = [], []
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    for method, order in runs:
        t0, c0 = time.perf_counter(), time.process_time()
        res = cg.GeodesicSolver(mesh, method, order=order, threads=1).solve(0)
        times.append((time.perf_counter() - t0, time.process_time() - c0))
        assert res.info.status == "optimal", res.info.status
notices = [str(w.message) for w in caught if type(w.message).__name__ == "CompileNotice"]
print(json.dumps({"times": times, "compiled": compiled, "notices": notices}))
"""


def run_child(runs: list, cache: Path, src: Path) -> dict:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache), "CVXGEODESIC_THREADS": "1",
           "PYTHONPATH": os.pathsep.join([str(src), os.environ.get("PYTHONPATH", "")])}
    out = subprocess.run([sys.executable, "-c", CHILD, json.dumps(runs)], env=env, capture_output=True, text=True,
                         timeout=900)
    if out.returncode:
        raise SystemExit(out.stderr)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", nargs="*", default=list(CASES), choices=list(CASES))
    ap.add_argument("--repeat", type=int, default=1, help="cold/warm pairs per case; the minimum is kept")
    ap.add_argument("--kernels", action="store_true", help="list the kernels the cold run compiled")
    args = ap.parse_args()
    import cvxgeodesic

    src = Path(cvxgeodesic.__file__).resolve().parents[1]
    print(f"{'case':<14} {'clock':<5} {'cold s':>8} {'warm s':>8} {'cold/warm':>9} {'4x warm+2':>9}  kernels  notices")
    for name in args.cases:
        cold, warm, last = [], [], {}
        for _ in range(args.repeat):
            with tempfile.TemporaryDirectory(prefix="numba-cold-") as tmp:
                last = run_child(CASES[name], Path(tmp), src)
                cold.append([sum(t) for t in zip(*last["times"], strict=True)])
                warm.append([sum(t) for t in zip(*run_child(CASES[name], Path(tmp), src)["times"], strict=True)])
        for k, clock in enumerate(("wall", "cpu")):
            c, w = min(t[k] for t in cold), min(t[k] for t in warm)
            print(f"{name:<14} {clock:<5} {c:8.2f} {w:8.2f} {c / w:9.1f} {4 * w + 2:9.2f}  {len(last['compiled']):7d}  "
                  + (f"{len(last['notices'])}: {' | '.join(last['notices'])}" if k == 0 else ""))
        if args.kernels:
            for kernel, seconds in sorted(last["compiled"], key=lambda k: -k[1]):
                print(f"    {seconds:6.2f}  {kernel}")


if __name__ == "__main__":
    main()
