"""Speed of the structured interior-point solver against Clarabel and the heat method.

Not a test: run it by hand (``make bench``)::

    python benchmarks/solver_speed.py                         # icosphere(5) + every mesh found in ../shared/meshes
    python benchmarks/solver_speed.py --meshes spot bimba     # names in ../shared/meshes, or icosphereN
    python benchmarks/solver_speed.py --meshes horse armadillo --no-clarabel

For every mesh (source vertex 0) and formulation (QCLP, QCQP-Hessian with m = 1)
it solves the same :class:`ConicProblem` with ``InteriorPointSolver`` and with
Clarabel, in one process, and times the heat method (potpourri3d, set-up + solve).

What the columns mean
---------------------
``t_ours``
    ``build_problem`` + ``InteriorPointSolver.solve`` wall time: all problem-specific
    set-up (the ConicProblem, our assembly plan and reduced-problem constants) plus all
    iterations. It excludes the once-per-mesh symbolic Cholesky analysis, printed
    separately in the per-mesh lines as "symbolic analysis", and the once-per-process load
    of the compiled kernels (a warm-up solve on a tiny mesh runs before any timing; the
    very first run after an install also compiles them, about 10 s).
``t_clarabel``
    ``build_problem`` + ``solve_clarabel`` wall time (Clarabel's own set-up included).
``build``
    The ``build_problem`` part of both columns. Per-mesh operators (gradient blocks,
    Hessian energy), which every solver needs, are built once before timing and
    printed in the per-mesh header.
``--repeat N``
    Every timed call is repeated N times and the minimum kept (the machine is shared).
``t_heat``
    potpourri3d ``MeshHeatMethodDistanceSolver`` construction + ``compute_distance``.
``err``
    ``max |d_ours − d_clarabel| / bbox diagonal``.
``rss``
    Peak resident set size of the whole process so far (``ru_maxrss``) right after
    our solve and after the row; it only grows, so run one mesh per process
    (``--meshes horse --no-clarabel``) to read a method's own peak.
"""

from __future__ import annotations

import argparse
import os
import resource
import sys
import time
from pathlib import Path

import numpy as np

from cvxgeodesic.mesh import icosphere
from cvxgeodesic.problems.conic import kkt_pattern
from cvxgeodesic.problems.formulations import MeshOperators, build_problem, smoothness_weight
from cvxgeodesic.solvers.ipm import InteriorPointSolver
from cvxgeodesic.strategies.warm_up import warm_up

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "meshes"
DEFAULT_SHARED = ["spot.obj", "bimba.obj", "horse.ply", "armadillo.obj"]
METHODS = ["qclp", "qcqp-hessian"]


def peak_rss_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # KiB on Linux


def load(name: str):
    """A mesh by name: ``icosphereN`` is generated, anything else is looked up in ../shared/meshes."""
    if name.startswith("icosphere") and name[len("icosphere"):].isdigit():
        return icosphere(int(name[len("icosphere"):]))
    from cvxgeodesic.mesh.io import load_mesh

    path = Path(name)
    if not path.exists():
        candidates = [SHARED / name] + [SHARED / f"{name}{ext}" for ext in (".obj", ".ply", ".off", ".stl")]
        path = next((c for c in candidates if c.exists()), None)
        if path is None:
            return None
    return load_mesh(path)


def heat_time(mesh, source: int) -> tuple[float, np.ndarray]:
    import potpourri3d as pp3d

    t0 = time.perf_counter()
    solver = pp3d.MeshHeatMethodDistanceSolver(mesh.V, mesh.F)
    d = solver.compute_distance(source)
    return time.perf_counter() - t0, d


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--meshes", nargs="+", default=None,
                    help="mesh names (files in ../shared/meshes, with or without extension, or icosphereN); "
                         "default: icosphere5 and every default shared mesh present")
    ap.add_argument("--methods", nargs="+", default=METHODS)
    ap.add_argument("--no-clarabel", action="store_true", help="skip Clarabel (slow on big meshes)")
    ap.add_argument("--source", type=int, default=0)
    ap.add_argument("--tol", type=float, default=1e-8)
    ap.add_argument("--m", type=float, default=1.0, help="smoothness multiplier m (λ = m·100·h/n)")
    ap.add_argument("--repeat", type=int, default=1, help="time every call N times and keep the minimum")
    ap.add_argument("--backend", default="auto", choices=["auto", "pardiso", "cholmod", "scipy"],
                    help="factorization backend of our solver (auto: PARDISO, else CHOLMOD)")
    args = ap.parse_args(argv)

    names = args.meshes or (["icosphere5"] + [n for n in DEFAULT_SHARED if (SHARED / n).exists()])
    warm_up()
    print(f"# OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}, "
          f"cores={os.cpu_count()}, tol={args.tol}", flush=True)
    rows = []
    for name in names:
        t0 = time.perf_counter()
        mesh = load(name)
        if mesh is None:
            print(f"# {name}: not found, skipped", flush=True)
            continue
        t_load = time.perf_counter() - t0
        ops = MeshOperators(mesh)
        t0 = time.perf_counter()
        _ = ops.gradient_blocks
        energies = {}
        for method in args.methods:
            if "hessian" in method:
                energies["hessian"] = ops.energy("hessian")
            elif "laplacian" in method:
                energies["laplacian"] = ops.energy("laplacian")
            elif "dirichlet" in method:
                energies["dirichlet"] = ops.energy("dirichlet")
        t_ops = time.perf_counter() - t0
        t_heat = min(heat_time(mesh, args.source)[0] for _ in range(args.repeat))
        lam = smoothness_weight(mesh, args.m)
        print(f"# {mesh.name}: {mesh.n_vertices} vertices, {mesh.n_faces} faces; load {t_load:.2f} s, "
              f"operators {t_ops:.2f} s (once per mesh), heat {t_heat:.3f} s", flush=True)
        solvers: dict[str, InteriorPointSolver] = {}
        for method in args.methods:
            t_build = np.inf
            for _ in range(args.repeat):
                t0 = time.perf_counter()
                p = build_problem(ops, np.array([args.source]), method, lam)
                t_build = min(t_build, time.perf_counter() - t0)
            key = "none" if p.P is None else method
            if key not in solvers:
                t0 = time.perf_counter()
                solvers[key] = InteriorPointSolver(kkt_pattern(mesh.n_vertices, mesh.F, mesh.edges, p.P),
                                                   backend=args.backend)
                t_an = time.perf_counter() - t0
                chol = solvers[key].cholesky
                print(f"#   symbolic analysis for the {'face/edge' if p.P is None else method} pattern: "
                      f"{t_an:.3f} s (once per mesh; {chol.backend} analysis {chol.analyze_time:.3f} s)",
                      flush=True)
            ipm = solvers[key]
            res = min((ipm.solve(p, tol=args.tol) for _ in range(args.repeat)), key=lambda r: r.solve_time)
            rss_ours = peak_rss_mib()
            row = dict(mesh=mesh.name, faces=mesh.n_faces, method=method, t_build=t_build,
                       t_ours=t_build + res.solve_time,
                       it_ours=res.iterations, t_heat=t_heat, rss_ours=rss_ours, extra=res.extra,
                       t_clar=float("nan"), it_clar=None, err=float("nan"))
            if not args.no_clarabel:
                from cvxgeodesic.solvers.clarabel_backend import solve_clarabel

                ref = min((solve_clarabel(p, tol=args.tol) for _ in range(args.repeat)), key=lambda r: r.solve_time)
                row.update(t_clar=t_build + ref.solve_time, it_clar=ref.iterations,
                           err=float(np.max(np.abs(res.x - ref.x))) / mesh.bbox_diagonal,
                           obj_rel=abs(res.objective - ref.objective) / max(1.0, abs(ref.objective)))
            row["rss"] = peak_rss_mib()
            rows.append(row)
            ex = res.extra
            print(f"#   {method}: ours {res.solve_time:.3f} s = setup {ex['setup_time']:.3f} + assembly "
                  f"{ex['assembly_time']:.3f} + factor {ex['factor_time']:.3f} + solves {ex['linear_solve_time']:.3f}"
                  f" + other {ex['other_time']:.3f}; {res.iterations} it, {ex['refinement_steps']} refinements, "
                  f"{ex['correctors_accepted']}/{ex['correctors']} correctors"
                  + (f"; clarabel {row['t_clar']:.2f} s ({row['it_clar']} it)" if not args.no_clarabel else ""),
                  flush=True)

    hdr = (f"{'mesh':<16}{'faces':>8} {'method':<14}{'t_clarabel':>11}{'t_ours':>8}{'clar/ours':>10}"
           f"{'t_heat':>8}{'ours/heat':>10}{'it(clar/ours)':>14}{'err/bbox':>10}{'build':>7}"
           f"{'rss_ours':>10}{'rss_row':>9}")
    print()
    print(hdr)
    print("-" * len(hdr))
    for r in rows:
        it = f"{r['it_clar'] if r['it_clar'] is not None else '-'}/{r['it_ours']}"
        print(f"{r['mesh']:<16}{r['faces']:>8} {r['method']:<14}{r['t_clar']:>10.2f}s{r['t_ours']:>7.2f}s"
              f"{r['t_clar'] / r['t_ours']:>9.1f}x{r['t_heat']:>7.2f}s{r['t_ours'] / r['t_heat']:>9.1f}x"
              f"{it:>14}{r['err']:>10.1e}{r['t_build']:>6.2f}s{r['rss_ours']:>8.0f}Mi{r['rss']:>7.0f}Mi")
    return 0


if __name__ == "__main__":
    sys.exit(main())
