"""``cvxgeodesic demo``: QCQP-Hessian on the bundled Spot mesh next to the other methods (:mod:`cvxgeodesic.demo`)."""

from __future__ import annotations

import argparse
from typing import Any


def add_parser(sub: Any) -> None:
    """The ``demo`` sub-command."""
    p = sub.add_parser("demo", help="QCQP-Hessian on the bundled Spot mesh; writes PLY + PNG, prints a table")
    p.add_argument("--out", default="demo_output", help="output folder (default demo_output)")
    p.add_argument("--source", type=int, default=0, help="source vertex (default 0)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """``cvxgeodesic demo``: returns the exit code."""
    from .._atomic import check_output_dir
    from ..demo import run_demo

    check_output_dir(args.out, "--out")  # before the six solves, not when their results are written
    run_demo(args.out, source=args.source)
    return 0
