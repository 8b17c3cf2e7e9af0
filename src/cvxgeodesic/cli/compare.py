"""``cvxgeodesic compare``: several methods on one mesh, each against a reference (:mod:`cvxgeodesic.compare`)."""

from __future__ import annotations

import argparse
import textwrap
from typing import Any

from ._options import add_view_options, cli_sources
from .distance import add_common_options


def add_parser(sub: Any) -> None:
    """The ``compare`` sub-command."""
    from ..compare import table_legend

    p = sub.add_parser("compare", help="run several methods, compare them with the exact distance",
                       description="Run several methods on one mesh and compare each with the exact distance "
                                   "(pygeodesic's MMP; inside a tetrahedral mesh with qclp at order 2): prints a "
                                   "table, writes compare.csv and pictures.",
                       epilog="columns of the table:\n" + "\n".join(
                           textwrap.fill(line, 100, initial_indent="  ", subsequent_indent="      ")
                           for line in table_legend().split("\n")),
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    add_common_options(p, method=False)
    p.add_argument("--methods", default="all", help="comma-separated method names, or 'all' (default)")
    p.add_argument("--out", default="compare_output", help="output folder (CSV table and PNGs)")
    add_view_options(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """``cvxgeodesic compare``: returns the exit code."""
    from .._atomic import check_output_dir
    from ..compare import format_table, run_compare
    from ..mesh.io import load_mesh

    check_output_dir(args.out, "--out")  # before the solves, not when their results are written
    mesh = load_mesh(args.mesh)
    sources, _ = cli_sources(args, mesh)
    rows = run_compare(mesh, sources, args.methods, args.out, m=args.m, solver=args.solver, progress=not args.quiet,
                       view=args.view, up=args.up)
    print(format_table(rows))
    if rows:
        print(f"(errors against: {rows[0]['reference']})")
    return 0
