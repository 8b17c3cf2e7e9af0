"""``cvxgeodesic path``: the geodesic path from a target down the field to the nearest source, on a surface or
inside a tetrahedral mesh (:func:`cvxgeodesic.paths.geodesic_path`)."""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING, Any

from ..errors import ParameterError, SourceError
from . import _options as opt
from ._common import add_overwrite_option, check_outputs, load_input
from .distance import add_slice_option, draw_field, slice_normal

if TYPE_CHECKING:
    from ..mesh.simplex import SimplexMesh

#: The formats of a path file.
PATH_EXTENSIONS = (".csv", ".npy", ".ply")


def add_parser(sub: Any) -> None:
    """The ``path`` sub-command."""
    p = sub.add_parser("path", help="geodesic path from a target down the distance field to the nearest source")
    opt.add_input_argument(p)
    opt.add_source_options(p)
    p.add_argument("--to", type=int, default=None, metavar="I", help="target vertex")
    p.add_argument("--to-point", type=opt.xyz, default=None, metavar="X,Y,Z",
                   help="target: the closest surface point (in a tetrahedral mesh: the point inside the solid)")
    opt.add_solve_options(p, m_help="smoothness multiplier m (default 1)")
    opt.add_cost_options(p)
    p.add_argument("-o", "--output", required=True,
                   help="path file: .csv (x,y,z,face,b0,b1,b2; in a tetrahedral mesh x,y,z,tet,b0,b1,b2,b3), .npy or "
                        ".ply")
    p.add_argument("--png", default=None, help="also draw the path on the field to this PNG (both files or neither; "
                                               "in a tetrahedral mesh its points on the slice)")
    add_slice_option(p)
    opt.add_view_options(p)
    add_overwrite_option(p)
    p.add_argument("--quiet", "-q", action="store_true", help="no progress output")
    p.set_defaults(func=run)


def _target(args: argparse.Namespace, mesh: SimplexMesh) -> Any:
    import numpy as np

    if (args.to is None) == (args.to_point is None):
        raise ParameterError("give exactly one target: --to I or --to-point X,Y,Z")
    if args.to is not None:
        if not 0 <= args.to < mesh.n_vertices:
            raise SourceError(f"target vertex {args.to} is out of range: the mesh has {mesh.n_vertices} vertices "
                              f"(0..{mesh.n_vertices - 1})")
        return args.to
    # the mesh's point there (mesh.reference.locate): a SurfacePoint, so that an exact field's path is pygeodesic's;
    # inside a solid the VolumePoint at the position
    return mesh.reference.locate(mesh, np.array(args.to_point))


def _path_writer(path: str, P: Any, cells: Any, bary: Any, cell: str) -> Any:
    """The function that writes the path into an open binary file, by the extension of ``path``; ``cell`` names
    the column of the cell that holds each point (``face``, ``tet``: the singular of the reference's
    ``words.argument``)."""
    import io

    import numpy as np

    lower = path.lower()
    if lower.endswith(".npy"):
        return lambda fh: np.save(fh, P)
    if lower.endswith(".csv"):
        buf = io.StringIO()
        buf.write(",".join(["x", "y", "z", cell, *(f"b{i}" for i in range(bary.shape[1]))]) + "\n")
        for x, f, b in zip(P, cells, bary, strict=True):
            buf.write(",".join([*(repr(float(c)) for c in x), str(int(f)), *(repr(float(c)) for c in b)]) + "\n")
        return lambda fh: fh.write(buf.getvalue().encode())
    k = len(P)
    head = (f"ply\nformat ascii 1.0\ncomment geodesic path (cvxgeodesic)\nelement vertex {k}\n"
            f"property double x\nproperty double y\nproperty double z\nelement edge {max(k - 1, 0)}\n"
            "property int vertex1\nproperty int vertex2\nend_header\n")
    body = "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in P.tolist()) + "".join(f"{i} {i + 1}\n" for i in range(k - 1))
    return lambda fh: fh.write((head + body).encode())


def run(args: argparse.Namespace) -> int:
    """``cvxgeodesic path``: returns the exit code."""
    import numpy as np

    from .._atomic import atomic_write, output_set
    from .._verbose import progress_printer
    from ..api import GeodesicSolver
    from ..paths import distance_at, geodesic_path

    check_outputs(args, ("-o", args.output, PATH_EXTENSIONS), ("--png", args.png, (".png",)))
    mesh = load_input(args.mesh, opt.cloud_options(args))
    sources, label = opt.cli_sources(args, mesh)
    target = _target(args, mesh)
    cost = opt.cli_cost(args, mesh)
    res = GeodesicSolver(mesh, opt.method_for(args, mesh), m=args.m, solver=args.solver, cost=cost).solve(
        sources, callback=None if args.quiet else progress_printer(sys.stderr))
    P, cells, bary = geodesic_path(mesh, res, target, return_surface_points=True)
    outputs = [args.output, args.png] if args.png else [args.output]
    with output_set(*outputs, overwrite_read_only=args.overwrite_read_only) as tmp:  # both files or neither
        atomic_write(tmp[0], _path_writer(str(tmp[0]), P, cells, bary, mesh.reference.words.argument.removesuffix("s")))
        if args.png:
            draw_field(mesh, res, tmp[1], title=f"{res.info.method}, path to sources {label}",
                       normal=slice_normal(args), line=P, view=args.view, up=args.up)
    if not args.quiet:
        length = float(np.linalg.norm(np.diff(P, axis=0), axis=1).sum())
        start = mesh.reference.point_type(cells[0], bary[0])  # the target, as the path's first point
        time = "" if cost is None else f", travel time {distance_at(mesh, res, start):.6g}"
        print(f"{res.info.method}: path of {len(P)} points, length {length:.6g}{time}; wrote {args.output}"
              + (f" and {args.png}" if args.png else ""), file=sys.stderr)
    return 0

