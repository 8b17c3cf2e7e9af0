"""``cvxgeodesic distance``: one distance field, written in the input file's numbering (and ``--png``).

On a surface the picture is the field with isolines; in a tetrahedral mesh it is a slice through the centre
(``--slice-normal``). Both files or neither.
"""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING, Any

from . import _options as opt
from ._common import add_overwrite_option, check_outputs, load_input

if TYPE_CHECKING:
    from ..mesh.simplex import SimplexMesh


def add_parser(sub: Any) -> None:
    """The ``distance`` sub-command."""
    from ..capabilities import ORDERS

    p = sub.add_parser("distance", help="compute one distance field and write it")
    add_common_options(p, points=True)
    p.add_argument("--lam", type=float, default=None, help="give λ directly (overrides --m)")
    p.add_argument("--normalization", default="area", choices=("area", "paper"),
                   help="meaning of --m: 'area' (default) or the paper's λ = m·100·h/n")
    p.add_argument("--order", type=int, default=None, choices=ORDERS, help=opt.ORDER_HELP)
    opt.add_cost_options(p)
    opt.add_resolution_option(p)
    p.add_argument("--estimate-error", action="store_true",
                   help="with --resolution: estimate the mean relative error by two more solves, on copies with half "
                        "and twice the faces (about twice the solve's time more; docs/adapted.md)")
    p.add_argument("-o", "--output", required=True, help=opt.output_help())
    p.add_argument("--png", default=None,
                   help="also render the field with isolines and the sources to this PNG (both files or neither; "
                        "a slice of a tetrahedral mesh)")
    add_slice_option(p)
    opt.add_view_options(p)
    add_overwrite_option(p)
    p.set_defaults(func=run)


def add_common_options(p: argparse.ArgumentParser, *, method: bool = True, points: bool = False) -> None:
    """The mesh (a surface or tetrahedra; with ``points``, a point file too), the sources, ``--method``, ``--m``,
    ``--solver`` and ``--quiet``: what ``distance``, ``compare`` and ``view`` share."""
    if points:
        opt.add_input_argument(p)
    else:
        p.add_argument("mesh", help=opt.volume_help())
    opt.add_source_options(p)
    opt.add_solve_options(p, method=method)
    p.add_argument("--quiet", "-q", action="store_true", help="no progress output")


def add_slice_option(p: argparse.ArgumentParser) -> None:
    """``--slice-normal NX,NY,NZ``."""
    p.add_argument("--slice-normal", type=opt.xyz, default=None, metavar="NX,NY,NZ", help=opt.SLICE_HELP)


def slice_normal(args: argparse.Namespace) -> tuple[float, float, float]:
    """``--slice-normal``, default ``z``."""
    return getattr(args, "slice_normal", None) or (0.0, 0.0, 1.0)


def run(args: argparse.Namespace) -> int:
    """``cvxgeodesic distance``: returns the exit code."""
    from .._atomic import output_set
    from .._verbose import progress_printer
    from ..api import GeodesicSolver
    from ..capabilities import DOMAINS
    from ..mesh.formats.registry import DISTANCE_EXTENSIONS, FORMATS
    from ..mesh.io import save_distance
    from ..validation import check_output_path

    check_outputs(args, ("-o", args.output, DISTANCE_EXTENSIONS), ("--png", args.png, (".png",)))
    mesh = load_input(args.mesh, opt.cloud_options(args))
    # before the solve: the formats that hold a field on this mesh's cells (a volume's: fewer)
    check_output_path(args.output, tuple(e for e in DISTANCE_EXTENSIONS if mesh.dim in FORMATS[e].dims))
    sources, label = opt.cli_sources(args, mesh)
    method = opt.method_for(args, mesh)
    log = sys.stderr
    solver = GeodesicSolver(mesh, method, m=args.m, lam=args.lam, solver=args.solver,
                            normalization=args.normalization, order=args.order, cost=opt.cli_cost(args, mesh),
                            resolution=args.resolution, estimate_error=args.estimate_error)
    if not args.quiet:  # the order and resolution the solver chose (a cloud's default is order 2 on a copy)
        domain = DOMAINS[mesh.domain]
        print(f"{mesh.name}: {mesh.n_file_vertices} {domain.vertex_words}, {mesh.n_cells} "
              f"{domain.cell_words or mesh.reference.words.many}; method {method}"
              + (f", order {solver.order}" if solver.order != 1 else "")
              + (f", resolution {solver.resolution}" if solver.resolution != "mesh" else ""), file=log)
    res = solver.solve(sources, callback=None if args.quiet else progress_printer(log))
    for note in res.info.notes:
        args.notes.say(note)
    outputs = [args.output, args.png] if args.png else [args.output]
    with output_set(*outputs, overwrite_read_only=args.overwrite_read_only) as tmp:  # both files or neither
        # every file in the file's numbering and vertex count, so it joins the input by index
        save_distance(tmp[0], mesh, res.distance, file_order=True)
        if args.png:
            draw_field(mesh, res, tmp[1], title=f"{solver.method}, sources {label}", normal=slice_normal(args),
                       view=args.view, up=args.up)
    if not args.quiet:
        i = res.info
        print(f"{i.method} via {i.solver}: {i.status}, {i.iterations} iterations, set-up {i.setup_time:.2f} s, "
              f"solve {i.solve_time:.2f} s; wrote {args.output}" + (f" and {args.png}" if args.png else ""), file=log)
        ad = i.extra.get("adapted")
        if ad is not None and ad.get("error_estimate") is not None:
            print(f"solved on {ad['faces']} of {ad['user_faces']} faces; estimated mean relative error "
                  f"{100 * ad['error_estimate']:.2g} %", file=log)
    return 0


def draw_field(mesh: SimplexMesh, res: Any, path: Any, *, title: str, normal: tuple[float, float, float],
               line: Any = None, view: Any = None, up: Any = "auto") -> None:
    """The field of ``res`` and its sources into a PNG (:func:`~cvxgeodesic.evaluation.slice_plot.draw_field`): on a
    slice every source is marked, its points inside too; ``line``, a geodesic path, replaces the marks. ``view`` and
    ``up``: a surface's camera (:func:`~cvxgeodesic.plotting.plot_field`), whose path picture has no colour bar
    label."""
    import numpy as np

    from ..evaluation.slice_plot import draw_field as draw

    sset, points = res.source_set, None
    if sset is not None:  # the vertices at 0 and the points (a slice's marks; a surface marks res.sources)
        points = np.vstack([mesh.V[sset.fixed_vertices(mesh)], sset.point_positions(mesh)])
    label = None if line is not None and mesh.reference.picture == "surface" else "geodesic distance"
    draw(mesh, res, path, title=title, sources=res.sources, points=points, line=line, normal=normal,
         label=label, view=view, up=up)
