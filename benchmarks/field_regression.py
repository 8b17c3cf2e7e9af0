"""Fields, iterations and times of a fixed set of solves, saved from one source tree and compared with another.

Not a test: the check that a refactor changed nothing but rounding (issue 35). Run it with the old tree and with
the new one, then compare::

    PYTHONPATH=/path/to/old/src python benchmarks/field_regression.py --save old.npz
    PYTHONPATH=src python benchmarks/field_regression.py --save new.npz
    python benchmarks/field_regression.py --compare old.npz new.npz

With ``--shared`` (needs ``../shared/meshes``) three scan-sized cases are added, where setup and solve take
seconds rather than milliseconds: the default method on bimba (46K faces), qclp on max_planck (11K), and order 2
on spot (5.9K); their times are the ones that show whether a refactor slowed the solver.

The cases cover both dimensions (surfaces, tetrahedra), both element orders, the order-1 formulations with and
without an energy, vertex / point / curve / boundary sources, a travel cost, the baselines and geodesic paths, on
generated meshes (no ../shared needed). Only the public API is called, so the script runs unchanged on both trees.
``--compare`` prints, per case, the largest difference of the fields relative to the field's largest finite
value, the iteration counts of both and the ratio of the solve times (``--repeat`` solves each, the fastest kept;
the load average is printed: times from a loaded machine are not a quiet-machine measurement).
"""

from __future__ import annotations

import argparse
import os
import sys
import time

os.environ.setdefault("CVXGEODESIC_THREADS", "1")

import numpy as np  # noqa: E402

SHARED = os.path.join(os.path.dirname(__file__), "..", "..", "shared", "meshes")


def _solve(mesh, method, sources, **kw):
    """A thunk: construction (setup) and one solve, returning (field, iterations)."""
    import cvxgeodesic as cg

    def run():
        r = cg.GeodesicSolver(mesh, method, **kw).solve(sources)
        return r.distance, r.info.iterations
    return run


def _shared_cases():
    """Scan-sized (name, thunk) pairs on ../shared/meshes, each mesh read once (outside the timed thunks)."""
    import cvxgeodesic as cg

    def load(name):
        return cg.load_mesh(os.path.join(SHARED, name))

    return [("scan bimba qcqp-hessian", _solve(load("bimba.obj"), "qcqp-hessian", 0)),
            ("scan max_planck qclp", _solve(load("max_planck.obj"), "qclp", 0)),
            ("scan spot order2", _solve(load("spot.obj"), "qclp", 0, order=2))]


def _cases():
    """(name, thunk) pairs; each thunk returns (field, iterations) with the public API of either tree."""
    import cvxgeodesic as cg

    sphere, plane = cg.icosphere(3), cg.grid_plane(12, jitter=0.2)
    box, prism = cg.tet_box(4), cg.tet_l_prism(3)
    bottom = np.flatnonzero(box.V[box.boundary_facets].mean(axis=1)[:, 2] == 0)
    p_tri = cg.surface_point(sphere, sphere.V[5] * 0.6 + sphere.V[40] * 0.4)
    p_tet = cg.volume_point(box, [0.31, 0.42, 0.27])

    solve = _solve

    def path(mesh, sources, target, **kw):
        def run():
            d = cg.geodesic_distance(mesh, sources, method="qclp", **kw)
            return np.asarray(cg.geodesic_path(mesh, d, target, sources=sources)).ravel(), 0
        return run

    return [
        ("tri qclp vertex", solve(sphere, "qclp", 0)),
        ("tri qcqp-hessian vertex", solve(sphere, "qcqp-hessian", 0)),
        ("tri lcqp-laplacian vertex", solve(sphere, "lcqp-laplacian", [0, 100])),
        ("tri qcqp-dirichlet plane", solve(plane, "qcqp-dirichlet", 7)),
        ("tri qclp point", solve(sphere, "qclp", p_tri)),
        ("tri qclp cost", solve(plane, "qclp", 0, cost=1.0 + plane.V[:, 0])),
        ("tri order2 vertex", solve(sphere, "qclp", 0, order=2)),
        ("tri order2 point", solve(plane, "qclp", cg.surface_point(plane, [0.43, 0.57, 0.0]), order=2)),
        ("tri heat", solve(sphere, "heat", 0)),
        ("tri dijkstra", solve(sphere, "dijkstra", 0)),
        ("tri path", path(plane, 0, plane.n_vertices - 1)),
        ("tet qclp vertex", solve(box, "qclp", 0)),
        ("tet qcqp-laplacian vertex", solve(box, "qcqp-laplacian", 0)),
        ("tet lclp vertex", solve(box, "lclp", [0, 30])),
        ("tet qcqp-dirichlet prism", solve(prism, "qcqp-dirichlet", 0)),
        ("tet qclp point", solve(box, "qclp", p_tet)),
        ("tet qclp boundary", solve(box, "qclp", "boundary")),
        ("tet qclp faces", solve(box, "qclp", cg.BoundaryFaces(bottom))),
        ("tet order2 vertex", solve(prism, "qclp", 0, order=2)),
        ("tet order2 point", solve(box, "qclp", p_tet, order=2)),
        ("tet heat", solve(box, "heat", 0)),
        ("tet dijkstra", solve(box, "dijkstra", 0)),
        ("tet path", path(box, 0, box.n_vertices - 1)),
    ]


def save(path: str, repeat: int, shared: bool = False) -> None:
    out = {}
    for name, run in _cases() + (_shared_cases() if shared else []):
        times = []
        for _ in range(repeat):
            t0 = time.perf_counter()
            field, iterations = run()
            times.append(time.perf_counter() - t0)
        out[name] = np.asarray(field, dtype=float)
        out[name + "/iterations"] = np.array(iterations)
        out[name + "/time"] = np.array(min(times))
        print(f"{name:28s} {iterations:4d} it  {min(times):7.3f} s", flush=True)
    np.savez(path, **out)


def compare(old_path: str, new_path: str) -> None:
    old, new = np.load(old_path), np.load(new_path)
    print(f"{'case':28s} {'max |Δd| / max d':>17s} {'iterations':>11s} {'time new/old':>12s}")
    for name in [k for k in old.files if "/" not in k and k in new.files]:
        a, b = old[name], new[name]
        if a.shape != b.shape:
            print(f"{name:28s} shapes differ: {a.shape} vs {b.shape}")
            continue
        finite = np.isfinite(a) & np.isfinite(b)
        same_inf = np.array_equal(np.isinf(a), np.isinf(b))
        scale = np.abs(a[finite]).max() if finite.any() else 1.0
        diff = np.abs(a[finite] - b[finite]).max() / scale if finite.any() else 0.0
        it = f"{int(old[name + '/iterations'])} → {int(new[name + '/iterations'])}"
        ratio = float(new[name + "/time"]) / float(old[name + "/time"])
        print(f"{name:28s} {diff:17.2e} {it:>11s} {ratio:12.2f}{'' if same_inf else '  (inf pattern differs)'}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--save", help="solve every case and save fields, iterations and times to this .npz")
    ap.add_argument("--compare", nargs=2, metavar=("OLD", "NEW"), help="compare two saved runs")
    ap.add_argument("--repeat", type=int, default=1, help="solves per case; the fastest time is kept")
    ap.add_argument("--shared", action="store_true", help="add three scan-sized cases from ../shared/meshes")
    args = ap.parse_args(argv)
    print(f"load average {os.getloadavg()[0]:.1f}, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}")
    if args.save:
        import cvxgeodesic

        print(f"cvxgeodesic from {os.path.dirname(cvxgeodesic.__file__)}")
        if args.shared and not os.path.isdir(SHARED):
            ap.error(f"--shared: {SHARED} is not there")
        save(args.save, args.repeat, args.shared)
    if args.compare:
        compare(*args.compare)
    return 0


if __name__ == "__main__":
    sys.exit(main())
