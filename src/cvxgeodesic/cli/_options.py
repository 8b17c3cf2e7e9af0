"""The options several commands share and what they become: sources, method, travel cost, help texts.

A surface and a volume take the same options; what differs between the two is the mesh's reference simplex
(``mesh.reference``, :mod:`cvxgeodesic.mesh.reference`): the words for the cells and where a ``--source-point`` goes
(``locate``: the closest surface point, or the point itself inside the solid); the method names, the default method
of each domain and what a travel cost applies to are the capability table's (:mod:`cvxgeodesic.capabilities`), the
formats of a field the registry's (``Format.dims``).

Only the standard library at import, as the whole :mod:`cvxgeodesic.cli` package (see its ``__init__``).
"""

from __future__ import annotations

import argparse
import math
import sys
from typing import TYPE_CHECKING, Any

from ..errors import ParameterError, SourceError

if TYPE_CHECKING:
    from ..api import Method
    from ..mesh.simplex import SimplexMesh

M_HELP = "smoothness multiplier m (default 1): λ = m·κ·√area, one rounding on the surface whatever the mesh"
SLICE_HELP = "tetrahedral meshes: normal of the slice through the centre that --png (or view) shows (default 0,0,1)"


def mesh_help() -> str:
    """Help of the mesh argument of the surface-only commands: the formats of the registry."""
    from ..mesh.formats.registry import mesh_formats_help

    return f"mesh file: {mesh_formats_help()} (trimesh and meshio: pip install 'cvxgeodesic[io]')"


def volume_help() -> str:
    """Help of the mesh argument of the commands that take tetrahedra too."""
    from ..mesh.formats.registry import MESHIO_TET_EXTENSIONS, TETGEN_EXTENSIONS

    return (f"{mesh_help()}; or tetrahedra, the distance inside the solid: {', '.join(MESHIO_TET_EXTENSIONS)} with "
            f"meshio, {', '.join(TETGEN_EXTENSIONS)} (TetGen)")


def input_help() -> str:
    """Help of the mesh argument of the commands that take point files too (``_common.load_input``)."""
    from ..mesh.formats.registry import point_formats_help

    return f"{volume_help()}; or a point cloud: {point_formats_help()} (laspy: the io extra too)"


#: The point-file options (``PointCloud``'s keywords) and their values, spelled here because the command line imports
#: only the standard library to build its parser (``tests/test_cli.py`` holds them equal to
#: :mod:`cvxgeodesic.mesh.pointcloud`'s).
CLOUD_TRIANGLES = ("union", "consensus", "repaired")
CLOUD_OUTLIERS = ("exclude", "keep", "error")
#: ``PointCloud``'s keyword of each point-file option, and the option.
CLOUD_OPTIONS = {"neighbours": "--neighbours", "triangles": "--triangles", "outliers": "--outliers",
                 "denoise": "--denoise", "use_normals": "--ignore-normals"}


def add_input_argument(p: argparse.ArgumentParser) -> None:
    """The input (a surface, tetrahedra or a point file) and the options of a point file's cloud."""
    p.add_argument("mesh", help=input_help())
    g = p.add_argument_group("point files", "how a point file's triangles are built (docs/pointclouds.md); "
                                            "refused for a mesh file")
    g.add_argument("--neighbours", type=int, default=None, metavar="K",
                   help="nearest neighbours of each point's local Delaunay fan (default 30)")
    g.add_argument("--triangles", default=None, choices=CLOUD_TRIANGLES,
                   help="which fan triangles to solve on (default union)")
    g.add_argument("--outliers", default=None, choices=CLOUD_OUTLIERS,
                   help="isolated outliers and points whose neighbours lie on a line: left out of the triangles "
                        "with a note, their distance carried from their neighbours (exclude, the default), kept in "
                        "the triangles (keep), or refused (error)")
    g.add_argument("--ignore-normals", dest="use_normals", action="store_const", const=False, default=None,
                   help="build the fans without the file's normals (by default oriented normals keep the fans from "
                        "crossing thin walls and sharp creases)")
    g.add_argument("--denoise", type=denoise_spec, default=None, metavar="auto|none|jet|PASSES",
                   help="move the points onto local degree-2 fits before the triangles are built: auto (the "
                        "default: two passes where the points read as noisy, and there are at least 6,000), none, "
                        "jet (two passes) or a number of passes (docs/pointclouds.md)")


#: ``--denoise none``: ``PointCloud(..., denoise=None)``, the points as given.
NO_DENOISE = "none"


def denoise_spec(text: str) -> str | int:
    """``--denoise``: ``auto``, ``none``, ``jet`` or a number of passes (its range is ``PointCloud``'s check)."""
    if text in ("auto", NO_DENOISE, "jet"):
        return text
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected 'auto', 'none', 'jet' or a number of passes, "
                                         f"got {text!r}") from None


def cloud_options(args: argparse.Namespace) -> dict[str, Any]:
    """The point-file options given on the command line, as :class:`~cvxgeodesic.PointCloud` keywords."""
    options = {k: getattr(args, k) for k in CLOUD_OPTIONS if getattr(args, k, None) is not None}
    if options.get("denoise") == NO_DENOISE:
        options["denoise"] = None  # given, as None: the points as given, not the default "auto"
    return options


def output_help() -> str:
    """Help of ``distance -o``."""
    from ..mesh.formats.registry import field_formats_help

    return (f"output file: {field_formats_help()} (trimesh and meshio: pip install 'cvxgeodesic[io]'); in the "
            "input file's vertex numbering, with its faces (a tetrahedral mesh: .vtu, .vtk or .npy)")


def xyz(text: str) -> tuple[float, float, float]:
    """``"1,2,3"`` -> ``(1.0, 2.0, 3.0)``: an option's X,Y,Z value."""
    parts = [p for p in text.replace(" ", "").split(",") if p]
    try:
        vals = tuple(float(p) for p in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected X,Y,Z (three numbers), got {text!r}") from None
    if len(vals) != 3 or not all(math.isfinite(v) for v in vals):
        raise argparse.ArgumentTypeError(f"expected X,Y,Z (three finite numbers), got {text!r}")
    return vals


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
    """``--source/-s I[,J...]`` (file vertex indices) and, with ``points``, ``--source-point`` and ``--boundary``."""
    p.add_argument("--source", "-s", type=vertex_list, action="extend", default=None, metavar="I[,J...]",
                   help=help_text)
    if points:
        p.add_argument("--source-point", type=xyz, action="append", default=None, metavar="X,Y,Z",
                       help="source at the surface point closest to X,Y,Z, in a tetrahedral mesh the point X,Y,Z "
                            "inside the solid (repeat for several)")
        p.add_argument("--boundary", action="store_true",
                       help="the mesh boundary (every boundary edge; of a volume, every boundary face) is the source")


def add_solve_options(p: argparse.ArgumentParser, *, method: bool = True, m_help: str = M_HELP) -> None:
    """``--method`` (with ``method``), ``--m`` and ``--solver``."""
    from ..api import SOLVERS
    from ..capabilities import METHODS
    from ..problems.formulations import ALIASES

    if method:  # None when not given: the default of the mesh's domain (method_for)
        names = (*METHODS, *ALIASES)  # the table's methods and their aliases
        p.add_argument("--method", default=None, choices=names, metavar="NAME",
                       help=f"one of: {', '.join(names)} (default {default_methods()})")
    p.add_argument("--m", type=float, default=1.0, help=m_help)
    p.add_argument("--solver", default="auto", choices=SOLVERS, help="backend for the convex formulations")


def default_methods() -> str:
    """The defaults of ``--method`` in words: each domain's (:attr:`~cvxgeodesic.capabilities.Domain.default_method`),
    the first one's first."""
    from ..capabilities import DOMAINS

    first, *rest = DOMAINS.values()
    return "; ".join([first.default_method, *(f"{d.default_method} on {d.meshes}" for d in rest)])


def method_for(args: argparse.Namespace, mesh: SimplexMesh) -> Method:
    """``--method`` when given, else the default of the mesh's domain
    (:attr:`~cvxgeodesic.capabilities.Domain.default_method`; a point file's is the cloud's, docs/pointclouds.md)."""
    from ..capabilities import DOMAINS

    return args.method or DOMAINS[mesh.domain].default_method  # type: ignore[return-value]


def add_cost_options(p: argparse.ArgumentParser) -> None:
    """``--cost FILE.npy`` and ``--cost-field NAME``: a travel cost (docs/metrics.md)."""
    g = p.add_mutually_exclusive_group()
    g.add_argument("--cost", default=None, metavar="FILE.npy",
                   help="travel cost (time per unit length, > 0): a .npy of one value per vertex of the file, or "
                        "one per triangle of the loaded mesh; the distance becomes the travel time")
    g.add_argument("--cost-field", default=None, metavar="NAME",
                   help="travel cost from the input file's per-vertex property NAME (PLY property, VTK/VTU point "
                        "data)")


def cli_cost(args: argparse.Namespace, mesh: SimplexMesh) -> Any:
    """The ``cost`` of :class:`~cvxgeodesic.api.GeodesicSolver` from ``--cost`` / ``--cost-field``, in the mesh's
    numbering (None without either); notes go to ``args.notes``.

    Returns
    -------
    (n,) or (k,) float ndarray or None
        Per vertex of the mesh, or per triangle of the loaded mesh.

    Raises
    ------
    ParameterError
        A ``--cost`` file that is not a .npy array of real numbers, one per file vertex or per mesh triangle; a
        cost on a mesh whose domain no method takes one on (the capability table: a tetrahedral mesh).
    MeshFormatError
        ``--cost-field`` on a format without per-vertex properties, or a property the file does not have.
    """
    from ..mesh.fileorder import from_file_order

    given = "--cost-field" if getattr(args, "cost_field", None) else "--cost" if getattr(args, "cost", None) else None
    if given is None:
        return None
    from ..capabilities import DOMAINS, methods_for

    if not methods_for(mesh.domain, medium="cost"):  # before reading the file: no method of this domain takes one
        where = [d.meshes for d in DOMAINS.values() if methods_for(d.name, medium="cost")]
        raise ParameterError(f"{given}: a travel cost applies to {' and '.join(where)}, not to "
                             f"{DOMAINS[mesh.domain].meshes} ({mesh.name})")
    if given == "--cost-field":
        from ..mesh.io import load_vertex_property

        values = load_vertex_property(args.mesh, args.cost_field)
        what = f"--cost-field {args.cost_field}"
    else:
        values = _load_cost(args.cost)
        what = f"--cost {args.cost}"
        if values.shape == (mesh.n_cells,) and values.shape != (mesh.n_file_vertices,):
            return values  # one per triangle of the loaded mesh
        if values.shape != (mesh.n_file_vertices,):
            raise ParameterError(f"{what}: an array of shape {values.shape}; give ({mesh.n_file_vertices},) (one value "
                                 f"per vertex of the file) or ({mesh.n_cells},) (one per triangle of the loaded mesh)")
    values, note = from_file_order(mesh, values, what)
    if note:
        args.notes.say(note)
    return values


def _load_cost(path: str) -> Any:
    """The array of a ``--cost`` file, checked to be real."""
    from pathlib import Path

    import numpy as np

    from ..mesh.formats._common import check_file
    from ..validation import check_real

    if not str(path).lower().endswith(".npy"):
        raise ParameterError(f"--cost {path}: give a .npy file (one value per vertex or per triangle)")
    check_file(Path(path), "a .npy file (--cost)")  # a FIFO or a device would block or never end
    try:
        values = np.load(path, allow_pickle=False)
    except (OSError, ValueError) as exc:
        raise ParameterError(f"--cost {path}: cannot read it as a .npy array ({exc})") from None
    check_real(values, f"--cost {path}")  # before any conversion to float drops an imaginary part
    return values


def _given_sources(args: argparse.Namespace, where: str = "") -> tuple[list[int], list[tuple[float, ...]], bool]:
    """``(vertices, points, boundary)`` of the options, checked: some source, and ``--boundary`` alone."""
    vertices = list(args.source or [])
    points = list(getattr(args, "source_point", None) or [])
    boundary = bool(getattr(args, "boundary", False))
    if boundary and (vertices or points):
        raise SourceError("--boundary is a source on its own: do not combine it with --source/--source-point")
    if not (vertices or points or boundary):
        raise SourceError(f"give a source: --source I, --source-point X,Y,Z{where} or --boundary")
    return vertices, points, boundary


def cli_sources(args: argparse.Namespace, mesh: SimplexMesh) -> tuple[Any, str]:
    """The ``sources`` value for :meth:`GeodesicSolver.solve` from the options, and a label for titles.

    ``--source`` are vertex numbers of the file; ``--source-point`` the mesh's point there
    (``mesh.reference.locate``): the closest surface point on a surface (a note when it is off the surface), the
    point itself inside a solid.

    Raises
    ------
    SourceError
        No source option, ``--boundary`` together with other sources, a point outside the solid.
    """
    import numpy as np

    from ..mesh.fileorder import file_sources

    vertices, points, boundary = _given_sources(args, f" ({mesh.reference.words.domain})")
    if boundary:
        return "boundary", "boundary"
    if vertices:  # vertex indices of the file (load_mesh may weld or drop vertices)
        vertices = file_sources(mesh, vertices).tolist()
    pts: list[Any] = []
    if points:
        pts = _located_points(mesh, np.array(points, dtype=float), points)
    label = ", ".join([*(str(v) for v in vertices), *("(" + ",".join(f"{c:g}" for c in x) + ")" for x in points)])
    return [*vertices, *pts], label


def _located_points(mesh: SimplexMesh, X: Any, points: list) -> list:
    """The mesh's points at the (p, 3) positions ``X`` (``mesh.reference.locate``: a surface's closest points, a
    solid's points inside, which refuses a position outside), with a note for each one that is off the mesh."""
    import numpy as np

    from ..sources import ON_SURFACE_TOL

    located = list(mesh.reference.locate(mesh, X))  # a list for (p, 3) positions
    dist = np.linalg.norm(np.array([p.position(mesh) for p in located]).reshape(-1, 3) - X, axis=1)
    for x, dd in zip(points, dist, strict=True):
        if dd > ON_SURFACE_TOL * mesh.bbox_diagonal:
            print(f"cvxgeodesic: note: --source-point {','.join(f'{c:g}' for c in x)} is {dd:.3g} from "
                  f"{mesh.name}; using the closest point {mesh.reference.words.preposition} it", file=sys.stderr)
    return located


def batch_sources(args: argparse.Namespace) -> Any:
    """The ``sources`` of :func:`~cvxgeodesic.batch.run_batch` from the options (positions stay positions)."""
    vertices, points, boundary = _given_sources(args)
    if boundary:
        return "boundary"
    return [*vertices, *(list(x) for x in points)] if points else vertices


#: ``--view`` names and ``--up`` axes: :data:`cvxgeodesic.evaluation.camera.VIEW_NAMES` and ``UP_NAMES`` (this
#: module imports only the standard library; a test holds them equal).
VIEW_NAMES = ("front", "back")
UP_NAMES = ("auto", "x", "y", "z", "-x", "-y", "-z")
MAX_VIEWS = 4


def view_spec(text: str) -> list[str | tuple[float, float]]:
    """``"front,back"`` -> ``["front", "back"]``, ``"30,45"`` -> ``[(30.0, 45.0)]``: the value of one ``--view``."""
    parts = [p.strip().lower() for p in text.split(",")]
    if all(p in VIEW_NAMES for p in parts):
        return list(parts)
    try:
        angles = tuple(float(p) for p in parts)
    except ValueError:
        angles = ()
    if len(angles) != 2 or not all(math.isfinite(a) for a in angles):
        raise ParameterError(f"--view {text!r}: expected front, back, front,back or ELEV,AZIM (two finite numbers "
                             "of degrees)")
    return [(angles[0], angles[1])]


def up_spec(text: str) -> str | tuple[float, float, float]:
    """``--up``: a name of :data:`UP_NAMES` or ``X,Y,Z`` (a non-zero vector)."""
    name = text.strip().lower()
    if name in UP_NAMES:
        return name
    try:
        vec = xyz(text)
    except argparse.ArgumentTypeError:
        vec = (0.0, 0.0, 0.0)
    if not any(vec):
        raise ParameterError(f"--up {text!r}: expected {', '.join(UP_NAMES)} or X,Y,Z (three finite numbers, not "
                             "all zero)")
    return vec


def add_view_options(p: argparse.ArgumentParser) -> None:
    """``--view`` (repeatable) and ``--up``: the camera of a surface's ``--png``; read by :func:`parse_view_options`."""
    p.add_argument("--view", action="append", default=None, metavar="front|back|ELEV,AZIM",
                   help="the panels of a surface's picture, side by side (repeat, or give front,back; at most "
                        f"{MAX_VIEWS}): front faces the first source, back is the far side (turned 180° about the up "
                        "axis); ELEV,AZIM in degrees about the up axis (--view=-20,90 for a negative number). "
                        "Default: front,back")
    p.add_argument("--up", default="auto", metavar="auto|x|y|z|-x|-y|-z|X,Y,Z",
                   help="the world axis drawn upwards in a surface's picture (--up=-y for a negative one). Default "
                        "auto: away from the flat end the model stands on, else y (the OBJ convention; z where y is "
                        "the mesh's thinnest axis)")


def parse_view_options(args: argparse.Namespace) -> None:
    """``--view`` and ``--up`` read into ``args.view`` (a list of panels, or None: the default) and ``args.up``.

    Raises
    ------
    ParameterError
        A value that is not a view or an axis, or more than :data:`MAX_VIEWS` views (the message names the option).
    """
    if getattr(args, "view", None) is not None:
        views = [v for text in args.view for v in view_spec(text)]
        if len(views) > MAX_VIEWS:
            raise ParameterError(f"--view: at most {MAX_VIEWS} views, got {len(views)}")
        args.view = views
    if isinstance(getattr(args, "up", None), str):
        args.up = up_spec(args.up)


LAM_HELP = "give λ directly (overrides --m)"
ORDER_HELP = ("2: second-order elements for the squared distance (qclp and the qcqp methods; docs/order2.md); "
              "default 1, or on a point cloud order 2 on a decimated copy (--resolution auto; docs/pointclouds.md)")


def add_precision_options(p: argparse.ArgumentParser, *, tol_default: str) -> None:
    """``--lam``, ``--order`` and ``--tol``: what :class:`~cvxgeodesic.api.GeodesicSolver` takes beyond ``--m``;
    ``--lam`` is checked with ``--m`` (:func:`~cvxgeodesic.cli._common.check_numbers`), ``--tol`` by
    :func:`check_tol` before the mesh is read."""
    from ..capabilities import ORDERS

    p.add_argument("--lam", type=float, default=None, help=LAM_HELP)
    p.add_argument("--order", type=int, default=None, choices=ORDERS, help=ORDER_HELP)
    p.add_argument("--tol", type=float, default=None, metavar="TOL",
                   help=f"relative tolerance of the solver's residuals and duality gap, in (0, 1) "
                        f"(default {tol_default})")


def check_tol(args: argparse.Namespace) -> None:
    """``--tol`` in (0, 1) as the API checks ``tol``, when given."""
    from ..validation import check_number

    if getattr(args, "tol", None) is not None:
        check_number(args.tol, "--tol", low=0, high=1, low_open=True, high_open=True)


def add_resolution_option(p: argparse.ArgumentParser) -> None:
    """``--resolution`` (docs/adapted.md): the mesh the field is solved on."""
    p.add_argument("--resolution", type=resolution, default=None, metavar="R",
                   help="solve at order 2 on a quadric-decimated copy and answer on this mesh: a face count (e.g. "
                        "4000), a fraction of the faces (e.g. 0.1), 'auto' (1/10, at least 2000 faces) or 'mesh' "
                        "(this mesh; docs/adapted.md). Default: 'mesh', and 'auto' on a point cloud without --order "
                        "(docs/pointclouds.md)")


def resolution(text: str) -> Any:
    """``--resolution`` as :class:`~cvxgeodesic.api.GeodesicSolver` takes it: ``"mesh"``, ``"auto"``, an int or a
    float (the values are checked there)."""
    t = text.strip().lower()
    if t in ("mesh", "auto"):
        return t
    try:
        return int(t)
    except ValueError:
        pass
    try:
        return float(t)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected 'mesh', 'auto', a face count or a fraction, got {text!r}") from None
