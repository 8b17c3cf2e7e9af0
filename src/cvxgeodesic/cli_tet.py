"""The command line on tetrahedral meshes: ``distance``, ``compare`` and ``view`` of a file that holds tetrahedra.

``cli.py`` loads the mesh and hands a :class:`~cvxgeodesic.mesh.tetmesh.TetMesh` to these functions: the same options
as on surfaces, with these differences: ``--source-point X,Y,Z`` is a point inside the solid, ``--boundary`` the
whole wall; the default method is ``qclp`` (the curved Hessian applies to surfaces only); outputs are ``.vtu`` /
``.vtk`` (or ``.npy``) in the file's numbering and ``--png`` draws a slice (``--slice-normal``, through the centre).
"""

from __future__ import annotations

import sys
from typing import Any

import numpy as np

from .errors import SourceError
from .mesh.tetmesh import TetMesh

__all__ = ["TET_OUTPUTS", "cmd_tet_compare", "cmd_tet_distance", "cmd_tet_view", "tet_method", "tet_sources"]

#: Output files of a field on a tetrahedral mesh.
TET_OUTPUTS = (".vtu", ".vtk", ".npy")


def tet_method(args: Any) -> str:
    """``--method`` when given, else ``qclp``."""
    return args.method if getattr(args, "method_given", False) else "qclp"


def tet_sources(args: Any, mesh: TetMesh) -> tuple[Any, str]:
    """The sources from ``--source`` (file vertex numbers), ``--source-point`` (inside the solid), ``--boundary``,
    and a label."""
    from .mesh.fileorder import file_sources
    from .sources import volume_point

    vertices = list(args.source or [])
    points = list(getattr(args, "source_point", None) or [])
    if getattr(args, "boundary", False):
        if vertices or points:
            raise SourceError("--boundary is a source on its own: do not combine it with --source/--source-point")
        return "boundary", "boundary"
    if not vertices and not points:
        raise SourceError("give a source: --source I, --source-point X,Y,Z (inside the solid) or --boundary")
    if vertices:
        vertices = file_sources(mesh, vertices).tolist()  # type: ignore[arg-type]  # a TetMesh has the file fields
    pts = [volume_point(mesh, np.array(x, dtype=float)) for x in points]
    label = ", ".join([*(str(v) for v in vertices), *("(" + ",".join(f"{c:g}" for c in x) + ")" for x in points)])
    return [*vertices, *pts], label


def _slice_normal(args: Any) -> np.ndarray:
    return np.array(getattr(args, "slice_normal", None) or (0.0, 0.0, 1.0), dtype=float)


def cmd_tet_distance(args: Any, mesh: TetMesh) -> int:
    """``cvxgeodesic distance`` on a tetrahedral mesh."""
    from ._atomic import output_set
    from ._verbose import progress_printer
    from .api import GeodesicSolver
    from .evaluation.tet_slice_plot import plot_tet_slice
    from .mesh.io import save_distance
    from .validation import check_output_path

    check_output_path(args.output, TET_OUTPUTS)
    sources, label = tet_sources(args, mesh)
    method = tet_method(args)
    log = sys.stderr
    if not args.quiet:
        print(f"{mesh.name}: {mesh.n_file_vertices} vertices, {mesh.n_tets} tetrahedra; method {method}"
              + (f", order {args.order}" if args.order != 1 else ""), file=log)
    solver = GeodesicSolver(mesh, method, m=args.m, lam=args.lam, solver=args.solver,
                            normalization=args.normalization, order=args.order)
    res = solver.solve(sources, callback=None if args.quiet else progress_printer(log))
    for note in res.info.notes:
        args.notes.say(note)
    outputs = [args.output, args.png] if args.png else [args.output]
    with output_set(*outputs, overwrite_read_only=args.overwrite_read_only) as tmp:  # both files or neither
        save_distance(tmp[0], mesh, res.distance, file_order=True)
        if args.png:
            fixed = res.source_set.fixed_vertices(mesh) if res.source_set is not None else res.sources
            marks = [mesh.V[fixed]] + ([np.array([p.position(mesh) for p in res.source_set.points])]
                                       if res.source_set is not None and res.source_set.points else [])
            plot_tet_slice(mesh, res.distance, tmp[1], normal=_slice_normal(args), points=np.vstack(marks),
                           title=f"{solver.method}, sources {label}", colorbar_label="distance")
    if not args.quiet:
        i = res.info
        print(f"{i.method} via {i.solver}: {i.status}, {i.iterations} iterations, set-up {i.setup_time:.2f} s, "
              f"solve {i.solve_time:.2f} s; wrote {args.output}" + (f" and {args.png}" if args.png else ""), file=log)
    return 0


def cmd_tet_compare(args: Any, mesh: TetMesh) -> int:
    """``cvxgeodesic compare`` on a tetrahedral mesh: every volume method against ``qclp`` at order 2."""
    from .compare_tet import format_tet_table, run_tet_compare

    sources, _ = tet_sources(args, mesh)
    methods = "all" if args.methods.strip().lower() == "all" else args.methods
    rows = run_tet_compare(mesh, sources, methods, args.out, m=args.m, solver=args.solver, progress=not args.quiet)
    print(format_tet_table(rows))
    return 0


def cmd_tet_view(args: Any, mesh: TetMesh) -> int:
    """``cvxgeodesic view`` on a tetrahedral mesh: the field on a volume mesh with a slice plane."""
    from .viewer import show_volume

    given = args.source or args.source_point or args.boundary
    sources = tet_sources(args, mesh)[0] if given else 0
    show_volume(mesh, sources=sources, method=tet_method(args), screenshot=args.screenshot, m=args.m,
                solver=args.solver, normal=_slice_normal(args), overwrite_read_only=args.overwrite_read_only)
    if args.screenshot and not args.quiet:
        print(f"wrote {args.screenshot}", file=sys.stderr)
    return 0

