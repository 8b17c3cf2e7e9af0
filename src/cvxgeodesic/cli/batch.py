"""``cvxgeodesic batch``: the same sources on many meshes with Dask (:mod:`cvxgeodesic.batch`)."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from ._options import add_solve_options, add_source_options, batch_sources, default_methods, volume_help


def add_parser(sub: Any) -> None:
    """The ``batch`` sub-command."""
    from ..batch import OUTPUT_FORMATS

    p = sub.add_parser(
        "batch", help="distance fields for many meshes with Dask (local cluster or --scheduler)",
        description="Solve the same sources on every mesh matched by MESH_GLOB, one Dask task per mesh. Writes "
                    "OUT/<stem>.ply (a volume: .vtu; or --format) and OUT/<stem>.json (SolveInfo, parameters); "
                    "skips meshes already done with the same parameters. Exit code 0: all solved; 1: some meshes "
                    "failed (listed); 2: usage error.")
    p.add_argument("meshes", nargs="+", metavar="MESH_GLOB",
                   help="mesh files or quoted glob patterns ('data/*.obj', 'data/**/*.ply', 'parts/*'); "
                        + volume_help())
    add_source_options(p, "source vertex index in each file's numbering, the same in every mesh "
                          "(repeat, or give a list: -s 0,5)")
    add_solve_options(p)
    p.add_argument("--multires", type=int, default=0, metavar="FACES",
                   help="coarse-to-fine approximation: solve on a mesh simplified to FACES faces (default 0: off)")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (created if missing)")
    p.add_argument("--format", choices=OUTPUT_FORMATS, default=None,
                   help="distance file format (default: ply for a surface, vtu for a tetrahedral mesh; ply holds no "
                        "tetrahedra: a volume with --format ply fails before its solve)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="address of a running Dask scheduler, e.g. tcp://SCHEDULER:8786 (default: a local cluster)")
    p.add_argument("--workers", type=int, default=2, metavar="N",
                   help="worker processes of the local cluster, one thread each (default 2)")
    p.add_argument("--force", action="store_true", help="recompute meshes whose outputs already exist")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bar (failures still in the summary)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """``cvxgeodesic batch``: 0 when every mesh was solved, 1 when some failed (listed)."""
    from ..batch import expand_mesh_paths, format_summary, run_batch

    sources = batch_sources(args)
    paths = expand_mesh_paths(args.meshes)
    if not args.quiet:
        where = args.scheduler or f"a local cluster of {args.workers} worker processes"
        method = args.method or f"the default ({default_methods()})"
        print(f"{len(paths)} mesh file(s); method {method}; running on {where}", file=sys.stderr)
    # --method not given: None, the default of each mesh's dimension
    rows = run_batch(paths, sources, args.out, method=args.method, m=args.m, solver=args.solver,
                     scheduler=args.scheduler, n_workers=args.workers, force=args.force, progress=not args.quiet,
                     multires=args.multires, output_format=args.format)
    print(format_summary(rows))
    return 1 if any(r["status"] == "failed" for r in rows) else 0
