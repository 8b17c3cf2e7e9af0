"""``cvxgeodesic view``: the interactive viewer (polyscope), or one frame of it into a PNG (``--screenshot``)."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from ._common import add_overwrite_option, check_outputs, load_input
from ._options import cli_sources, cloud_options, method_for
from .distance import add_common_options, add_slice_option, slice_normal


def add_parser(sub: Any) -> None:
    """The ``view`` sub-command."""
    p = sub.add_parser("view", help="interactive viewer (polyscope): field, isolines, sources; a click re-solves "
                                      "(default source: the first vertex of a face)")
    add_common_options(p, points=True)
    p.add_argument("--screenshot", default=None, metavar="OUT.png",
                   help="render one frame to this PNG without opening a window (works without a display)")
    add_slice_option(p)
    add_overwrite_option(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """``cvxgeodesic view``: returns the exit code."""
    from ..viewer import show

    check_outputs(args, ("--screenshot", args.screenshot, (".png",)))
    mesh = load_input(args.mesh, cloud_options(args))  # a point file: its cloud's soup, drawn as the points
    given = args.source or args.source_point or args.boundary
    sources = cli_sources(args, mesh)[0] if given else 0  # a field to start from; clicks choose the next ones
    # a solid is shown cut by a plane through the centre with this normal (show_volume); a surface ignores it
    show(mesh, sources=sources, method=method_for(args, mesh), screenshot=args.screenshot, m=args.m,
         solver=args.solver, overwrite_read_only=args.overwrite_read_only, normal=slice_normal(args))
    if args.screenshot and not args.quiet:
        print(f"wrote {args.screenshot}", file=sys.stderr)
    return 0
