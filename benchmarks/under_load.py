"""A solve alone and under load: beside a second solving process and beside a busy loop.

Not a test: run it by hand::

    python benchmarks/under_load.py                       # bimba from ../shared/meshes, else icosphere(5)
    python benchmarks/under_load.py --mesh icosphere5 --repeat 3 --methods qclp

For every method (QCQP-Hessian and QCLP, source vertex 0) and thread policy (the
default, ``threads=None``, and ``threads=1``; ``--policies default 1 all`` adds
``threads`` = all cores, the behaviour before the default policy) it times set-up + solve (a new
:class:`~cvxgeodesic.GeodesicSolver` each run, since the default policy decides the
thread count when a solver is built), minimum of ``--repeat`` runs:

``alone``
    nothing else started by this script (the rest of the machine as it is: the load
    average is printed with the results);
``beside solver``
    while a second process solves the same problem in a loop with the same policy;
``beside busy``
    while a process runs ``while True: pass``.

``ratio`` is the time under load over the time alone. The three take turns in
every repetition (the neighbours are paused with SIGSTOP outside their turn), so a
change in the rest of the machine's load affects them alike. Every process this
script starts stops by itself after ``--neighbour-seconds`` and is terminated when
the measurement is done.
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "meshes"
BUSY = "import time\nt = time.monotonic() + {s}\nwhile time.monotonic() < t:\n    pass\n"


def load(name: str):
    import cvxgeodesic as cg

    if name.startswith("icosphere"):
        return cg.icosphere(int(name[len("icosphere"):] or 5))
    path = SHARED / (name if "." in name else f"{name}.obj")
    if path.exists():
        return cg.load_mesh(path)
    print(f"{path} not found: using icosphere(5)", file=sys.stderr)
    return cg.icosphere(5)


def policy_threads(policy: str):
    if policy == "default":
        return None
    if policy == "all":
        from cvxgeodesic._threads import usable_cores

        return usable_cores()
    return int(policy)


def solve_once(mesh, method: str, threads) -> tuple[float, int]:
    import cvxgeodesic as cg

    t0 = time.perf_counter()
    res = cg.GeodesicSolver(mesh, method, threads=threads).solve(0)
    return time.perf_counter() - t0, int(res.info.extra["threads"])


def worker(args) -> None:
    """The neighbour that solves in a loop; prints "ready" once its first solve is done."""
    mesh = load(args.mesh)
    threads = None if args.worker_threads == 0 else args.worker_threads
    stop = time.monotonic() + args.neighbour_seconds
    solve_once(mesh, args.worker, threads)
    print("ready", flush=True)
    while time.monotonic() < stop:
        solve_once(mesh, args.worker, threads)


def start_neighbour(kind: str, args, method: str, threads) -> subprocess.Popen:
    if kind == "busy":
        return subprocess.Popen([sys.executable, "-c", BUSY.format(s=args.neighbour_seconds)])
    cmd = [sys.executable, __file__, "--worker", method, "--worker-threads", str(threads or 0),
           "--mesh", args.mesh, "--neighbour-seconds", str(args.neighbour_seconds)]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True)
    line = proc.stdout.readline()  # its first solve (imports, compiled kernels) is done: it now solves in a loop
    if line.strip() != "ready":
        proc.kill()
        raise RuntimeError("the neighbour solver did not start")
    return proc


def stop(proc: subprocess.Popen) -> None:
    proc.send_signal(signal.SIGCONT)
    proc.terminate()
    try:
        proc.wait(timeout=10)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


def measure(mesh, method, threads, kinds, args) -> dict:
    """(best time, thread counts used in the repetitions) per kind; the kinds take turns in every repetition,
    so that a change in the rest of the machine's load hits them alike. A neighbour runs only during its own
    turn (SIGSTOP else)."""
    neighbours = {}
    best: dict = {}
    used: dict = {}
    try:
        for kind in kinds:
            if kind != "alone":
                neighbours[kind] = proc = start_neighbour(kind, args, method, threads)
                proc.send_signal(signal.SIGSTOP)
        for _ in range(args.repeat):
            for kind in kinds:
                proc = neighbours.get(kind)
                if proc is not None:
                    proc.send_signal(signal.SIGCONT)
                    time.sleep(0.3)  # back in its loop (a solve, or the busy loop)
                try:
                    run = solve_once(mesh, method, threads)
                finally:
                    if proc is not None:
                        proc.send_signal(signal.SIGSTOP)
                best[kind] = min(best.get(kind, run[0]), run[0])
                used.setdefault(kind, []).append(run[1])
    finally:
        for proc in neighbours.values():
            stop(proc)
    return {kind: (best[kind], ",".join(map(str, used[kind]))) for kind in best}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--mesh", default="bimba")
    ap.add_argument("--methods", nargs="+", default=["qcqp-hessian", "qclp"])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--policies", nargs="+", default=["default", "1"],
                    help="thread policies: default (threads=None), a number, or all (threads = usable cores, "
                         "the library's behaviour before the policy)")
    ap.add_argument("--alone-only", action="store_true", help="time the solves alone only")
    ap.add_argument("--neighbour-seconds", type=float, default=120.0,
                    help="every neighbour process stops by itself after this long")
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    ap.add_argument("--worker-threads", type=int, default=0, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker:
        worker(args)
        return
    mesh = load(args.mesh)
    print(f"mesh {mesh.name}: {mesh.n_vertices} vertices, {mesh.n_faces} faces; {os.cpu_count()} cores; "
          f"load average before: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    for method in args.methods:
        solve_once(mesh, method, 1)  # warm-up: compiled kernels loaded, caches filled
    header = f"{'method':14s} {'threads':>8s} {'alone':>8s} {'beside solver':>14s} {'ratio':>6s} " \
             f"{'beside busy':>12s} {'ratio':>6s}   threads used per repetition (alone/solver/busy)"
    print(header)
    for method in args.methods:
        for policy in args.policies:
            threads = policy_threads(policy)
            kinds = ("alone",) if args.alone_only else ("alone", "solver", "busy")
            t = measure(mesh, method, threads, kinds, args)
            a = t["alone"][0]
            if args.alone_only:
                print(f"{method:14s} {policy:>8s} {a:8.3f}   threads used {t['alone'][1]}", flush=True)
                continue
            print(f"{method:14s} {policy:>8s} {a:8.3f} {t['solver'][0]:14.3f} "
                  f"{t['solver'][0] / a:6.2f} {t['busy'][0]:12.3f} {t['busy'][0] / a:6.2f}   "
                  f"{t['alone'][1]}/{t['solver'][1]}/{t['busy'][1]}", flush=True)
    print(f"load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    main()
