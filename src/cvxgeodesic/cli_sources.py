"""Command-line options for surface sources (``--source-point``, ``--boundary``) and ``cvxgeodesic path``."""

from __future__ import annotations

import argparse
import sys

import numpy as np

from ._verbose import progress_printer
from .api import ALL_METHODS, SOLVERS
from .errors import ParameterError, SourceError
from .mesh.formats.registry import mesh_formats_help
from .mesh.trimesh import TriMesh
from .validation import check_real

#: Help of every command's mesh argument: the formats of the registry.
MESH_HELP = f"mesh file: {mesh_formats_help()} (trimesh and meshio: pip install 'cvxgeodesic[io]')"


def xyz(text: str) -> tuple[float, float, float]:
    """``"1,2,3"`` -> ``(1.0, 2.0, 3.0)``: an option's X,Y,Z value."""
    parts = [p for p in text.replace(" ", "").split(",") if p]
    try:
        vals = tuple(float(p) for p in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected X,Y,Z (three numbers), got {text!r}") from None
    if len(vals) != 3 or not all(np.isfinite(vals)):
        raise argparse.ArgumentTypeError(f"expected X,Y,Z (three finite numbers), got {text!r}")
    return vals


#: The flag that lets a command replace read-only output files.
OVERWRITE_READ_ONLY = "--overwrite-read-only"


def add_overwrite_option(p: argparse.ArgumentParser) -> None:
    """``--overwrite-read-only``: replace output files that are read-only (refused otherwise, before any work)."""
    p.add_argument(OVERWRITE_READ_ONLY, action="store_true",
                   help="replace an output file even when it is read-only (no write permission for its owner; it "
                        "keeps its mode); without it such a file is refused before anything is computed")


def check_outputs(args, *outputs: tuple[str, str | None, tuple[str, ...]]) -> None:
    """Every output file of a command checked before any work, as ``(option, path or None, extensions)``.

    Raises
    ------
    ParameterError
        An unsupported extension, a missing or unwritable folder (:func:`~cvxgeodesic.validation.check_output_path`),
        an output that is one of the command's input files (the mesh, ``--cost``;
        :func:`~cvxgeodesic.validation.check_not_an_input`), or a read-only file without ``--overwrite-read-only``.
    """
    from ._atomic import check_replaceable
    from .validation import check_not_an_input, check_output_path

    inputs = [f for f in (getattr(args, "mesh", None), getattr(args, "cost", None)) if f]
    for option, path, extensions in outputs:
        if path is None:
            continue
        check_output_path(path, extensions)
        check_not_an_input(path, inputs, option)
        check_replaceable(path, overwrite_read_only=getattr(args, "overwrite_read_only", False),
                          allow=OVERWRITE_READ_ONLY)


def vertex_list(text: str) -> list[int]:
    """``"0,5"`` -> ``[0, 5]``: the value of one ``--source`` option."""
    try:
        values = [int(t) for t in text.split(",") if t.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"invalid vertex index list {text!r}: give integers like 0 or 0,5") from None
    if not values:
        raise argparse.ArgumentTypeError("empty vertex index list")
    return values


def add_source_options(p: argparse.ArgumentParser,
                       help_text: str = "source vertex index in the file's numbering (repeat, or give a list: -s 0,5)",
                       *, points: bool = True) -> None:
    """``--source/-s I[,J...]`` (file vertex indices) and, with ``points``, the surface-source options."""
    p.add_argument("--source", "-s", type=vertex_list, action="extend", default=None, metavar="I[,J...]",
                   help=help_text)
    if points:
        add_point_options(p)


class _Given(argparse.Action):
    """Stores the value and records that the option was given (``args.method_given``)."""

    def __call__(self, parser, namespace, values, option_string=None):
        setattr(namespace, self.dest, values)
        namespace.method_given = True


def add_cost_options(p: argparse.ArgumentParser) -> None:
    """``--cost FILE.npy`` and ``--cost-field NAME``: a travel cost (docs/metrics.md)."""
    g = p.add_mutually_exclusive_group()
    g.add_argument("--cost", default=None, metavar="FILE.npy",
                   help="travel cost (time per unit length, > 0): a .npy of one value per vertex of the file, or "
                        "one per triangle of the loaded mesh; the distance becomes the travel time")
    g.add_argument("--cost-field", default=None, metavar="NAME",
                   help="travel cost from the input file's per-vertex property NAME (PLY property, VTK/VTU point "
                        "data)")


def cli_cost(args, mesh) -> np.ndarray | None:
    """The ``cost`` of :class:`~cvxgeodesic.api.GeodesicSolver` from ``--cost`` / ``--cost-field``, in the mesh's
    numbering (None without either); notes go to ``args.notes``.

    Raises
    ------
    ParameterError
        A ``--cost`` file that is not a .npy array of real numbers, one per file vertex or per mesh triangle.
    MeshFormatError
        ``--cost-field`` on a format without per-vertex properties, or a property the file does not have.
    """
    from .mesh.fileorder import from_file_order

    if getattr(args, "cost_field", None):
        from .mesh.io import load_vertex_property

        values = load_vertex_property(args.mesh, args.cost_field)
        what = f"--cost-field {args.cost_field}"
    elif getattr(args, "cost", None):
        if not str(args.cost).lower().endswith(".npy"):
            raise ParameterError(f"--cost {args.cost}: give a .npy file (one value per vertex or per triangle)")
        from pathlib import Path

        from .mesh.formats._common import check_file

        check_file(Path(args.cost), "a .npy file (--cost)")  # a FIFO or a device would block or never end
        try:
            values = np.load(args.cost, allow_pickle=False)
        except (OSError, ValueError) as exc:
            raise ParameterError(f"--cost {args.cost}: cannot read it as a .npy array ({exc})") from None
        what = f"--cost {args.cost}"
        check_real(values, what)  # before any conversion to float drops an imaginary part
        if values.shape == (mesh.n_faces,) and values.shape != (mesh.n_file_vertices,):
            return values  # one per triangle of the loaded mesh
        if values.shape != (mesh.n_file_vertices,):
            raise ParameterError(f"{what}: an array of shape {values.shape}; give ({mesh.n_file_vertices},) (one value "
                                 f"per vertex of the file) or ({mesh.n_faces},) (one per triangle of the loaded mesh)")
    else:
        return None
    values, note = from_file_order(mesh, values, what)
    if note:
        args.notes.say(note)
    return values


def add_method_option(p: argparse.ArgumentParser) -> None:
    """``--method NAME``, any method of :data:`~cvxgeodesic.api.ALL_METHODS` (default qcqp-hessian; qclp on a
    tetrahedral mesh, which ``args.method_given`` tells apart)."""
    p.add_argument("--method", default="qcqp-hessian", choices=ALL_METHODS, metavar="NAME", action=_Given,
                   help=f"one of: {', '.join(ALL_METHODS)} (default qcqp-hessian; qclp on a tetrahedral mesh)")
    p.set_defaults(method_given=False)


def add_point_options(p: argparse.ArgumentParser) -> None:
    """``--source-point X,Y,Z`` (repeatable) and ``--boundary``."""
    p.add_argument("--source-point", type=xyz, action="append", default=None, metavar="X,Y,Z",
                   help="source at the surface point closest to X,Y,Z (repeat for several)")
    p.add_argument("--boundary", action="store_true", help="the mesh boundary (every boundary edge) is the source")


def cli_sources(args, mesh) -> tuple[object, str]:
    """The ``sources`` value for :meth:`GeodesicSolver.solve` from the options, and a label for titles.

    Raises
    ------
    SourceError
        No source option, or ``--boundary`` together with other sources.
    """
    from .mesh.fileorder import file_sources
    from .sources import ON_SURFACE_TOL, closest_points, surface_point

    vertices = list(args.source or [])
    points = list(getattr(args, "source_point", None) or [])
    boundary = bool(getattr(args, "boundary", False))
    if not vertices and not points and not boundary:
        raise SourceError("give a source: --source I, --source-point X,Y,Z or --boundary")
    if boundary:
        if vertices or points:
            raise SourceError("--boundary is a source on its own: do not combine it with --source/--source-point")
        return "boundary", "boundary"
    if vertices:  # vertex indices of the file (load_mesh may weld or drop vertices)
        vertices = file_sources(mesh, vertices).tolist()
    if not points:
        return vertices, str(vertices)
    X = np.array(points, dtype=float)
    _, _, dist = closest_points(mesh, X)
    for x, dd in zip(points, dist, strict=True):
        if dd > ON_SURFACE_TOL * mesh.bbox_diagonal:
            print(f"cvxgeodesic: note: --source-point {','.join(f'{c:g}' for c in x)} is {dd:.3g} from the surface; "
                  "using the closest surface point", file=sys.stderr)
    pts = surface_point(mesh, X)
    label = ", ".join([*(str(v) for v in vertices), *("(" + ",".join(f"{c:g}" for c in x) + ")" for x in points)])
    return [*vertices, *pts], label


def batch_sources(args):
    """The ``sources`` of :func:`~cvxgeodesic.batch.run_batch` from the options (positions stay positions)."""
    vertices = list(args.source or [])
    points = [list(x) for x in (getattr(args, "source_point", None) or [])]
    if getattr(args, "boundary", False):
        if vertices or points:
            raise SourceError("--boundary is a source on its own: do not combine it with --source/--source-point")
        return "boundary"
    if not vertices and not points:
        raise SourceError("give a source: --source I, --source-point X,Y,Z or --boundary")
    return [*vertices, *points] if points else vertices


def _target(args, mesh):
    from .sources import surface_point

    if (args.to is None) == (args.to_point is None):
        raise ParameterError("give exactly one target: --to I or --to-point X,Y,Z")
    if args.to is not None:
        if not 0 <= args.to < mesh.n_vertices:
            raise SourceError(f"target vertex {args.to} is out of range: the mesh has {mesh.n_vertices} vertices "
                              f"(0..{mesh.n_vertices - 1})")
        return args.to
    return surface_point(mesh, np.array(args.to_point))


def _write_path(path: str, P: np.ndarray, faces: np.ndarray, bary: np.ndarray) -> None:
    import io

    from ._atomic import atomic_write

    lower = path.lower()
    if lower.endswith(".npy"):
        def write(fh):
            np.save(fh, P)
    elif lower.endswith(".csv"):
        def write(fh):
            buf = io.StringIO()
            buf.write("x,y,z,face,b0,b1,b2\n")
            for x, f, b in zip(P, faces, bary, strict=True):
                buf.write(",".join([*(repr(float(c)) for c in x), str(int(f)), *(repr(float(c)) for c in b)]) + "\n")
            fh.write(buf.getvalue().encode())
    elif lower.endswith(".ply"):
        def write(fh):
            k = len(P)
            head = (f"ply\nformat ascii 1.0\ncomment geodesic path (cvxgeodesic)\nelement vertex {k}\n"
                    f"property double x\nproperty double y\nproperty double z\nelement edge {max(k - 1, 0)}\n"
                    "property int vertex1\nproperty int vertex2\nend_header\n")
            body = "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in P.tolist())
            body += "".join(f"{i} {i + 1}\n" for i in range(k - 1))
            fh.write((head + body).encode())
    else:
        raise ParameterError(f"output {path!r}: the path is written as .csv, .npy or .ply")
    atomic_write(path, write)


def _cmd_path(args) -> int:
    from ._atomic import output_set
    from .api import GeodesicSolver
    from .mesh.io import load_mesh
    from .paths import geodesic_path
    from .sources import SurfacePoint

    if not args.output.lower().endswith((".csv", ".npy", ".ply")):
        raise ParameterError(f"output {args.output!r}: the path is written as .csv, .npy or .ply")
    check_outputs(args, ("-o", args.output, (".csv", ".npy", ".ply")), ("--png", args.png, (".png",)))
    mesh = load_mesh(args.mesh)
    if not isinstance(mesh, TriMesh):  # a TetMesh
        raise ParameterError(f"{mesh.name} holds tetrahedra: the path command draws paths on surfaces; inside a "
                             "solid use cg.geodesic_path(mesh, result, target) (docs/volumes.md)")
    sources, label = cli_sources(args, mesh)
    target = _target(args, mesh)
    cost = cli_cost(args, mesh)
    res = GeodesicSolver(mesh, args.method, m=args.m, solver=args.solver, cost=cost).solve(
        sources, callback=None if args.quiet else progress_printer(sys.stderr))
    P, faces, bary = geodesic_path(mesh, res, target, return_surface_points=True)
    outputs = [args.output, args.png] if args.png else [args.output]
    with output_set(*outputs, overwrite_read_only=args.overwrite_read_only) as tmp:  # both files or neither
        _write_path(str(tmp[0]), P, faces, bary)
        if args.png:
            from .plotting import plot_field

            plot_field(mesh, res.distance, tmp[1], title=f"{res.info.method}, path to sources {label}", paths=[P])
    if not args.quiet:
        from .paths import distance_at

        length = float(np.linalg.norm(np.diff(P, axis=0), axis=1).sum())
        time = "" if cost is None else f", travel time {distance_at(mesh, res, SurfacePoint(faces[0], bary[0])):.6g}"
        print(f"{res.info.method}: path of {len(P)} points, length {length:.6g}{time}; wrote {args.output}"
              + (f" and {args.png}" if args.png else ""), file=sys.stderr)
    return 0


def add_path_parser(sub) -> None:
    """The ``path`` sub-command."""
    p = sub.add_parser("path", help="geodesic path from a target down the distance field to the nearest source")
    p.add_argument("mesh", help=MESH_HELP)
    add_source_options(p)
    p.add_argument("--to", type=int, default=None, metavar="I", help="target vertex")
    p.add_argument("--to-point", type=xyz, default=None, metavar="X,Y,Z", help="target: the closest surface point")
    add_method_option(p)
    p.add_argument("--m", type=float, default=1.0, help="smoothness multiplier m (default 1)")
    p.add_argument("--solver", default="auto", choices=SOLVERS, help="backend for the convex formulations")
    add_cost_options(p)
    p.add_argument("-o", "--output", required=True, help="path file: .csv (x,y,z,face,b0,b1,b2), .npy or .ply")
    p.add_argument("--png", default=None, help="also draw the path on the field to this PNG (both files or neither)")
    add_overwrite_option(p)
    p.add_argument("--quiet", "-q", action="store_true", help="no progress output")
    p.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help=argparse.SUPPRESS)
    p.set_defaults(func=_cmd_path)
