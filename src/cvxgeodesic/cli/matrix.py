"""``cvxgeodesic matrix``: a distance matrix, one row per source vertex, resumable (``OUTPUT.partial.npz``)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from ..errors import ParameterError, SourceError
from ._common import add_overwrite_option, check_outputs, load_input
from ._options import (
    add_input_argument,
    add_precision_options,
    add_resolution_option,
    add_solve_options,
    add_source_options,
    check_tol,
    cloud_options,
)


def add_parser(sub: Any) -> None:
    """The ``matrix`` sub-command."""
    p = sub.add_parser("matrix", help="distance matrix: one row per source vertex (-s), in the given order")
    add_input_argument(p)
    add_source_options(p, "source vertex of a row, in the file's numbering (repeat, or give a list: -s 0,5,9)",
                       points=False)
    from ..api import ALL_METHODS, DEFAULT_ROW_METHOD, LOCAL_ROW_TOL

    p.add_argument("--method", default=None, choices=ALL_METHODS, metavar="NAME",
                   help=f"one of: {', '.join(ALL_METHODS)} (default {DEFAULT_ROW_METHOD}, the default of "
                        "distance_matrix's rows on every mesh: docs/performance.md)")
    add_solve_options(p, method=False)
    add_precision_options(p, tol_default=f"1e-8; {LOCAL_ROW_TOL:g} with --max-distance")
    add_resolution_option(p)
    p.add_argument("-o", "--output", required=True,
                   help="output .npy: (rows, file vertices) float64, columns in the file's numbering; with "
                        "--max-distance a sparse .npz (scipy.sparse.load_npz). Finished rows are kept in "
                        "OUTPUT.partial.npz as they come: after Ctrl-C or an error the same command resumes")
    p.add_argument("--max-distance", type=float, default=None, metavar="R",
                   help="keep the distances up to R (mesh units): a sparse matrix, each row solved on the patch "
                        "of the mesh around its source (much faster for small R)")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="solve the rows on a local Dask cluster of N worker processes, cpu_count // N threads "
                        "each (default: in this process)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="solve the rows on a running Dask cluster, e.g. tcp://SCHEDULER:8786")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bar")
    add_overwrite_option(p)
    p.set_defaults(func=run)


def _check(args: argparse.Namespace) -> bool:
    """The options checked before the mesh is read; True for a sparse matrix (``--max-distance``)."""
    local = args.max_distance is not None
    suffix = Path(args.output).suffix.lower()
    if local and suffix != ".npz":
        raise ParameterError(f"{args.output}: --max-distance writes a sparse matrix (scipy.sparse.save_npz): "
                             "give -o FILE.npz")
    if not local and suffix == ".npz":
        raise ParameterError(f"{args.output}: a full matrix is written as .npy (or add --max-distance R for a "
                             "sparse .npz)")
    # a full .npy or a sparse .npz, never the mesh, a read-only file only when asked: before anything is solved
    check_outputs(args, ("-o", args.output, (".npz",) if local else (".npy",)))
    if local:
        from ..validation import check_number

        check_number(args.max_distance, "--max-distance", low=0, low_open=True)
    check_tol(args)
    if args.workers is not None and args.scheduler is not None:
        raise ParameterError("give --workers (a local Dask cluster) or --scheduler (an existing one), not both")
    return local


def run(args: argparse.Namespace) -> int:
    """``cvxgeodesic matrix``: returns the exit code."""
    from .._atomic import atomic_write
    from ..api import DEFAULT_ROW_METHOD, distance_matrix
    from ..capabilities import DOMAINS
    from ..mesh.fileorder import file_sources, to_file_order
    from ..rows import checkpoint_rows, sparse_to_file_order

    local = _check(args)
    mesh = load_input(args.mesh, cloud_options(args))  # a TriMesh or a TetMesh: both have the file's numbering
    if not args.source:
        raise SourceError("give the source vertex of each row: -s I[,J...] (repeatable)")
    rows = [int(file_sources(mesh, [s])[0]) for s in args.source]  # one row per -s, in the given order
    method = args.method or DEFAULT_ROW_METHOD  # distance_matrix's default, named in the first line
    partial = Path(f"{args.output}.partial.npz")  # finished rows as they come; the same command resumes from it
    if not args.quiet:
        where = ("" if args.workers is None and args.scheduler is None
                 else f"; on {args.scheduler or f'a local cluster of {args.workers} worker processes'}")
        within = (f", distances up to {args.max_distance:g}" if local else "") + (
            f", order {args.order}" if args.order not in (None, 1) else "")
        print(f"{mesh.name}: {mesh.n_file_vertices} {DOMAINS[mesh.domain].vertex_words}, {len(rows)} rows{within}; "
              f"method {method}{where}",
              file=sys.stderr)  # "resuming from ..." comes from distance_matrix, once it has accepted the checkpoint
    try:
        D: Any = distance_matrix(mesh, rows, method, m=args.m, solver=args.solver, progress=not args.quiet,
                                 lam=args.lam, tol=args.tol, order=args.order, workers=args.workers,
                                 scheduler=args.scheduler, max_distance=args.max_distance, checkpoint=partial,
                                 resolution=args.resolution)
    except KeyboardInterrupt:
        kept = checkpoint_rows(partial)
        if kept:
            print(f"cvxgeodesic: {kept[0]} of {kept[1]} rows kept in {partial}; run the same command again to "
                  "resume", file=sys.stderr)
        raise
    import numpy as np
    import scipy.sparse as sp

    # columns in the file's numbering, like every other output
    D, save = (sparse_to_file_order(mesh, D), sp.save_npz) if local else (to_file_order(mesh, D), np.save)
    atomic_write(args.output, lambda fh: save(fh, D), overwrite_read_only=args.overwrite_read_only)
    what = f"sparse, {D.nnz} distances up to {args.max_distance:g} stored" if local else "distances"
    try:
        partial.unlink(missing_ok=True)
    except OSError as exc:  # another user's file in a sticky folder: the output is written all the same
        args.notes.say(f"{partial} could not be removed ({exc.strerror or exc}); delete it before another run")
    if not args.quiet:
        print(f"wrote {args.output}: {D.shape[0]} × {D.shape[1]}, {what}", file=sys.stderr)
    return 0
