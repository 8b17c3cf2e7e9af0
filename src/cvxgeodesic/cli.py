"""Command-line interface: ``cvxgeodesic distance | compare | batch | path | view | matrix | demo``.

Every error a user can cause ends the program with exit code 2 and a one-line
message on stderr; ``--debug`` shows the full traceback instead. ``batch``
returns 1 when some meshes failed (each listed) and the others were solved.
Ctrl-C ends it with 130 and SIGTERM with 143, one line each and no partial file.
Output files are checked before any work: never one of the inputs, and a read-only
one only with ``--overwrite-read-only`` (distance, path, view, matrix; batch refuses it
before its solves). The folders of ``compare`` and ``demo`` are checked up front; a
read-only file inside them is refused when it is written, after the solves.
"""

from __future__ import annotations

import argparse
import signal
import sys
import textwrap
import traceback
import warnings

# Only the standard library at import (the package's __init__ is lazy too): the console script imports this
# module before main() runs, and main() must have its Ctrl-C handling in place before NumPy, SciPy and Numba load.
from . import __version__
from .errors import ParameterError, SourceError

EXIT_USAGE = 2
EXIT_INTERRUPTED = 128 + signal.SIGINT  # 130, as a shell reports a process ended by Ctrl-C
EXIT_TERMINATED = 128 + signal.SIGTERM  # 143: kill, systemd, a batch system's time limit
M_HELP = "smoothness multiplier m (default 1): λ = m·κ·√area, one rounding on the surface whatever the mesh"
SLICE_HELP = "tetrahedral meshes: normal of the slice through the centre that --png (or view) shows (default 0,0,1)"


def _output_help() -> str:
    from .mesh.formats.registry import field_formats_help

    return (f"output file: {field_formats_help()} (trimesh and meshio: pip install 'cvxgeodesic[io]'); in the "
            "input file's vertex numbering, with its faces (a tetrahedral mesh: .vtu, .vtk or .npy)")


def _volume_help() -> str:
    from .cli_sources import MESH_HELP
    from .mesh.formats.registry import MESHIO_TET_EXTENSIONS, TETGEN_EXTENSIONS

    return (f"{MESH_HELP}; or tetrahedra, the distance inside the solid: {', '.join(MESHIO_TET_EXTENSIONS)} with "
            f"meshio, {', '.join(TETGEN_EXTENSIONS)} (TetGen)")


def _cmd_distance(args) -> int:
    from ._atomic import output_set
    from ._verbose import progress_printer
    from .api import GeodesicSolver
    from .cli_sources import check_outputs, cli_cost, cli_sources
    from .mesh.formats.registry import DISTANCE_EXTENSIONS
    from .mesh.io import load_mesh, save_distance
    from .mesh.tetmesh import TetMesh

    check_outputs(args, ("-o", args.output, DISTANCE_EXTENSIONS), ("--png", args.png, (".png",)))
    mesh = load_mesh(args.mesh)
    if isinstance(mesh, TetMesh):
        from .cli_tet import cmd_tet_distance

        return cmd_tet_distance(args, mesh)
    sources, label = cli_sources(args, mesh)
    log = sys.stderr
    if not args.quiet:
        print(f"{mesh.name}: {mesh.n_file_vertices} vertices, {mesh.n_faces} faces; method {args.method}", file=log)
    solver = GeodesicSolver(mesh, args.method, m=args.m, lam=args.lam, solver=args.solver,
                            normalization=args.normalization, order=args.order, cost=cli_cost(args, mesh))
    res = solver.solve(sources, callback=None if args.quiet else progress_printer(log))
    for note in res.info.notes:
        args.notes.say(note)
    outputs = [args.output, args.png] if args.png else [args.output]
    with output_set(*outputs, overwrite_read_only=args.overwrite_read_only) as tmp:
        # every file in the file's numbering and vertex count, so it joins the input by index
        save_distance(tmp[0], mesh, res.distance, file_order=True)
        if args.png:
            from .plotting import plot_field

            plot_field(mesh, res.distance, tmp[1], title=f"{solver.method}, sources {label}",
                       sources=res.sources, colorbar_label="geodesic distance")
    if not args.quiet:
        i = res.info
        print(f"{i.method} via {i.solver}: {i.status}, {i.iterations} iterations, set-up {i.setup_time:.2f} s, "
              f"solve {i.solve_time:.2f} s; wrote {args.output}" + (f" and {args.png}" if args.png else ""), file=log)
    return 0


def _cmd_compare(args) -> int:
    from ._atomic import check_output_dir
    from .cli_sources import cli_sources
    from .compare import format_table, run_compare
    from .mesh.io import load_mesh
    from .mesh.tetmesh import TetMesh

    check_output_dir(args.out, "--out")  # before the solves, not when their results are written
    mesh = load_mesh(args.mesh)
    if isinstance(mesh, TetMesh):
        from .cli_tet import cmd_tet_compare

        return cmd_tet_compare(args, mesh)
    sources, _ = cli_sources(args, mesh)
    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    rows = run_compare(mesh, sources, methods, args.out, m=args.m, solver=args.solver, progress=not args.quiet)
    print(format_table(rows))
    return 0


def _cmd_batch(args) -> int:
    from .batch import expand_mesh_paths, format_summary, run_batch
    from .cli_sources import batch_sources

    sources = batch_sources(args)
    paths = expand_mesh_paths(args.meshes)
    if not args.quiet:
        where = args.scheduler or f"a local cluster of {args.workers} worker processes"
        print(f"{len(paths)} mesh file(s); method {args.method}; running on {where}", file=sys.stderr)
    rows = run_batch(paths, sources, args.out, method=args.method, m=args.m, solver=args.solver,
                     scheduler=args.scheduler, n_workers=args.workers, force=args.force, progress=not args.quiet,
                     multires=args.multires, output_format=args.format)
    print(format_summary(rows))
    return 1 if any(r["status"] == "failed" for r in rows) else 0


def _cmd_view(args) -> int:
    from .cli_sources import check_outputs, cli_sources
    from .mesh.io import load_mesh
    from .mesh.tetmesh import TetMesh
    from .viewer import show

    check_outputs(args, ("--screenshot", args.screenshot, (".png",)))
    mesh = load_mesh(args.mesh)
    if isinstance(mesh, TetMesh):
        from .cli_tet import cmd_tet_view

        return cmd_tet_view(args, mesh)
    given = args.source or args.source_point or args.boundary
    sources = cli_sources(args, mesh)[0] if given else 0  # a field to start from; clicks choose the next ones
    show(mesh, sources=sources, method=args.method, screenshot=args.screenshot, m=args.m, solver=args.solver,
         overwrite_read_only=args.overwrite_read_only)
    if args.screenshot and not args.quiet:
        print(f"wrote {args.screenshot}", file=sys.stderr)
    return 0


def _cmd_matrix(args) -> int:
    from pathlib import Path

    import numpy as np

    from ._atomic import atomic_write
    from .api import distance_matrix
    from .cli_sources import check_outputs
    from .mesh.fileorder import file_sources, to_file_order
    from .mesh.io import load_mesh
    from .rows import checkpoint_rows, sparse_to_file_order

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
        from .validation import check_number

        check_number(args.max_distance, "--max-distance", low=0, low_open=True)  # before the mesh is read
    if args.workers is not None and args.scheduler is not None:
        raise ParameterError("give --workers (a local Dask cluster) or --scheduler (an existing one), not both")
    mesh = load_mesh(args.mesh)
    if not args.source:
        raise SourceError("give the source vertex of each row: -s I[,J...] (repeatable)")
    rows = [int(file_sources(mesh, [s])[0]) for s in args.source]  # one row per -s, in the given order
    partial = Path(f"{args.output}.partial.npz")  # finished rows as they come; the same command resumes from it
    if not args.quiet:
        where = ("" if args.workers is None and args.scheduler is None
                 else f"; on {args.scheduler or f'a local cluster of {args.workers} worker processes'}")
        within = f", distances up to {args.max_distance:g}" if local else ""
        print(f"{mesh.name}: {mesh.n_file_vertices} vertices, {len(rows)} rows{within}; method {args.method}{where}",
              file=sys.stderr)
        kept = checkpoint_rows(partial)
        if kept:
            print(f"resuming from {partial}: {kept[0]} of {kept[1]} rows already done", file=sys.stderr)
    try:
        D = distance_matrix(mesh, rows, args.method, m=args.m, solver=args.solver, progress=not args.quiet,
                            workers=args.workers, scheduler=args.scheduler, max_distance=args.max_distance,
                            checkpoint=partial)
    except KeyboardInterrupt:
        kept = checkpoint_rows(partial)
        if kept:
            print(f"cvxgeodesic: {kept[0]} of {kept[1]} rows kept in {partial}; run the same command again to "
                  "resume", file=sys.stderr)
        raise
    if local:
        import scipy.sparse as sp

        S = sparse_to_file_order(mesh, D)  # columns in the file's numbering, like every other output
        atomic_write(args.output, lambda fh: sp.save_npz(fh, S), overwrite_read_only=args.overwrite_read_only)
        shape, what = S.shape, f"sparse, {S.nnz} distances up to {args.max_distance:g} stored"
    else:
        D = to_file_order(mesh, D)
        atomic_write(args.output, lambda fh: np.save(fh, D), overwrite_read_only=args.overwrite_read_only)
        shape, what = D.shape, "distances"
    partial.unlink(missing_ok=True)
    if not args.quiet:
        print(f"wrote {args.output}: {shape[0]} × {shape[1]}, {what}", file=sys.stderr)
    return 0


def _cmd_demo(args) -> int:
    from ._atomic import check_output_dir
    from .demo import run_demo

    check_output_dir(args.out, "--out")  # before the six solves, not when their results are written
    run_demo(args.out, source=args.source)
    return 0


class _Notes:
    """Prints each note or warning once per command, as ``cvxgeodesic: note: <first line>`` on stderr."""

    def __init__(self) -> None:
        self.seen: set[str] = set()

    def say(self, text: str) -> None:
        line = str(text).splitlines()[0] if str(text) else ""
        if line and line not in self.seen:
            self.seen.add(line)
            from tqdm import tqdm

            # above any progress bar on stderr (a rows bar of `matrix`), not after its last redraw
            tqdm.write(f"cvxgeodesic: note: {line}", file=sys.stderr)

    def showwarning(self, message, category, filename, lineno, file=None, line=None) -> None:
        self.say(str(message))


def build_parser() -> argparse.ArgumentParser:
    from .api import SOLVERS
    from .cli_sources import MESH_HELP, add_cost_options, add_method_option, add_path_parser, add_source_options, xyz
    from .cli_sources import add_overwrite_option as add_overwrite

    VOLUME_HELP, OUTPUT_HELP = _volume_help(), _output_help()  # noqa: N806  (the module constants they were)
    parser = argparse.ArgumentParser(
        prog="cvxgeodesic",
        description="Geodesic distance fields on triangle meshes by convex optimization.",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    parser.add_argument("--debug", action="store_true", help="show full tracebacks on errors")
    sub = parser.add_subparsers(dest="command", required=True)

    def common(p):
        p.add_argument("mesh", help=VOLUME_HELP)
        add_source_options(p)
        p.add_argument("--m", type=float, default=1.0, help=M_HELP)
        p.add_argument("--solver", default="auto", choices=SOLVERS, help="backend for the convex formulations")
        p.add_argument("--quiet", "-q", action="store_true", help="no progress output")
        p.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help=argparse.SUPPRESS)

    p = sub.add_parser("distance", help="compute one distance field and write it")
    common(p)
    add_method_option(p)
    p.add_argument("--lam", type=float, default=None, help="give λ directly (overrides --m)")
    p.add_argument("--normalization", default="area", choices=("area", "paper"),
                   help="meaning of --m: 'area' (default) or the paper's λ = m·100·h/n")
    p.add_argument("--order", type=int, default=1, choices=(1, 2),
                   help="2: second-order elements for the squared distance (qclp and the qcqp methods; docs/order2.md)")
    add_cost_options(p)
    p.add_argument("-o", "--output", required=True, help=OUTPUT_HELP)
    p.add_argument("--png", default=None,
                   help="also render the field with isolines and the sources to this PNG (both files or neither; "
                        "a slice of a tetrahedral mesh)")
    p.add_argument("--slice-normal", type=xyz, default=None, metavar="NX,NY,NZ", help=SLICE_HELP)
    add_overwrite(p)
    p.set_defaults(func=_cmd_distance)

    from .compare import table_legend

    p = sub.add_parser("compare", help="run several methods, compare them with the exact distance",
                       description="Run several methods on one mesh and compare each with the exact distance "
                                   "(pygeodesic's MMP): prints a table, writes compare.csv and pictures.",
                       epilog="columns of the table:\n" + "\n".join(
                           textwrap.fill(line, 100, initial_indent="  ", subsequent_indent="      ")
                           for line in table_legend().split("\n")),
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    common(p)
    p.add_argument("--methods", default="all", help="comma-separated method names, or 'all' (default)")
    p.add_argument("--out", default="compare_output", help="output folder (CSV table and PNGs)")
    p.set_defaults(func=_cmd_compare)

    p = sub.add_parser(
        "batch", help="distance fields for many meshes with Dask (local cluster or --scheduler)",
        description="Solve the same sources on every mesh matched by MESH_GLOB, one Dask task per mesh. Writes "
                    "OUT/<stem>.ply (or .npy) and OUT/<stem>.json (SolveInfo, parameters); skips meshes already "
                    "done with the same parameters. Exit code 0: all solved; 1: some meshes failed (listed); "
                    "2: usage error.")
    p.add_argument("meshes", nargs="+", metavar="MESH_GLOB",
                   help="mesh files or quoted glob patterns ('data/*.obj', 'data/**/*.ply'); " + MESH_HELP)
    add_source_options(p, "source vertex index in each file's numbering, the same in every mesh "
                          "(repeat, or give a list: -s 0,5)")
    add_method_option(p)
    p.add_argument("--m", type=float, default=1.0, help=M_HELP)
    p.add_argument("--solver", default="auto", choices=SOLVERS, help="backend for the convex formulations")
    p.add_argument("--multires", type=int, default=0, metavar="FACES",
                   help="coarse-to-fine approximation: solve on a mesh simplified to FACES faces (default 0: off)")
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (created if missing)")
    p.add_argument("--format", choices=("ply", "npy"), default="ply", help="distance file format (default ply)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="address of a running Dask scheduler, e.g. tcp://SCHEDULER:8786 (default: a local cluster)")
    p.add_argument("--workers", type=int, default=2, metavar="N",
                   help="worker processes of the local cluster, one thread each (default 2)")
    p.add_argument("--force", action="store_true", help="recompute meshes whose outputs already exist")
    p.add_argument("--quiet", "-q", action="store_true", help="no progress bar (failures still in the summary)")
    p.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help=argparse.SUPPRESS)
    p.set_defaults(func=_cmd_batch)

    add_path_parser(sub)

    p = sub.add_parser("view", help="interactive viewer (polyscope): field, isolines, sources; a click re-solves "
                                      "(default source: the first vertex of a face)")
    common(p)
    add_method_option(p)
    p.add_argument("--screenshot", default=None, metavar="OUT.png",
                   help="render one frame to this PNG without opening a window (works without a display)")
    p.add_argument("--slice-normal", type=xyz, default=None, metavar="NX,NY,NZ", help=SLICE_HELP)
    add_overwrite(p)
    p.set_defaults(func=_cmd_view)

    p = sub.add_parser("matrix", help="distance matrix: one row per source vertex (-s), in the given order")
    p.add_argument("mesh", help=MESH_HELP)
    add_source_options(p, "source vertex of a row, in the file's numbering (repeat, or give a list: -s 0,5,9)",
                       points=False)
    add_method_option(p)
    p.add_argument("--m", type=float, default=1.0, help=M_HELP)
    p.add_argument("--solver", default="auto", choices=SOLVERS, help="backend for the convex formulations")
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
    add_overwrite(p)
    p.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help=argparse.SUPPRESS)
    p.set_defaults(func=_cmd_matrix)

    p = sub.add_parser("demo", help="QCQP-Hessian on the bundled Spot mesh; writes PLY + PNG, prints a table")
    p.add_argument("--out", default="demo_output", help="output folder (default demo_output)")
    p.add_argument("--source", type=int, default=0, help="source vertex (default 0)")
    p.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help=argparse.SUPPRESS)
    p.set_defaults(func=_cmd_demo)
    return parser


def _check_numbers(args) -> None:
    """``--m``, ``--lam`` and ``--slice-normal`` checked as the Python API checks them, before a command prints or
    reads anything."""
    from .validation import check_number, check_smoothness

    if getattr(args, "lam", None) is not None:
        check_number(args.lam, "lam", low=0)
    elif getattr(args, "m", None) is not None:
        check_smoothness(args.m, None)  # its range too (validation.MAX_M)
    normal = getattr(args, "slice_normal", None)
    if normal is not None and not any(normal):  # the plane's normal: any direction, but a direction
        raise ParameterError(f"--slice-normal {','.join(f'{c:g}' for c in normal)}: the normal of the slice must "
                             "not be zero (e.g. 0,0,1)")


class _Signals:
    """Ctrl-C (SIGINT) and SIGTERM for the duration of a command: recorded, then ``KeyboardInterrupt``.

    Both handlers raise ``KeyboardInterrupt``, so every ``finally`` that removes temporary files runs, and
    record the signal: :func:`main` then prints the line and returns the code of the signal that came, also
    when the interrupt surfaced as another error (an extension module's import that it broke turns it into
    an ``ImportError``). During a Clarabel solve they run once the solve stopped (their mark,
    :data:`cvxgeodesic.solvers._interrupt.STOPS_SOLVES`). A SIGINT or SIGTERM that the process ignores (a
    background job of a script, a parent's choice) stays ignored.
    """

    def __init__(self) -> None:
        self.received: int | None = None
        self.previous: dict[int, object] = {}

    def __enter__(self) -> _Signals:
        import threading

        from . import _signals

        def on_signal(signum: int, frame: object) -> None:
            self.received = self.received or signum
            _signals.record(signum)  # raised again at the library's next check if a ctypes callback swallows it
            raise KeyboardInterrupt

        # named as solvers._interrupt.STOPS_SOLVES, which is not imported here: it loads Clarabel and SciPy
        setattr(on_signal, "cvxgeodesic_stops_solves", True)  # noqa: B010
        if threading.current_thread() is threading.main_thread():  # signal.signal works there only
            if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
                self.previous[signal.SIGINT] = signal.signal(signal.SIGINT, on_signal)
            if signal.getsignal(signal.SIGTERM) is not signal.SIG_IGN:  # a parent's deliberate ignore stays
                self.previous[signal.SIGTERM] = signal.signal(signal.SIGTERM, on_signal)
        return self

    def __exit__(self, *exc: object) -> None:
        from . import _signals

        for signum, handler in self.previous.items():
            signal.signal(signum, handler)  # type: ignore[arg-type]
        _signals.clear()  # handled (main printed its line): a later command in this process starts afresh

    def check(self) -> None:
        """``KeyboardInterrupt`` if a signal came and what it raised was lost (an optional import that an
        extension module turned it into an ``ImportError``, which its caller then ignored)."""
        if self.received is not None:
            raise KeyboardInterrupt

    def stop_line(self) -> tuple[str, int]:
        """The message and the exit code of the signal received (Ctrl-C when none was recorded)."""
        if self.received == signal.SIGTERM:
            return "cvxgeodesic: terminated", EXIT_TERMINATED
        return "cvxgeodesic: interrupted", EXIT_INTERRUPTED


def main(argv=None) -> int:
    """Entry point of the ``cvxgeodesic`` console script; returns the exit code.

    Ctrl-C (SIGINT) and SIGTERM at any moment of the command, the start-up's imports of NumPy, SciPy and Numba
    included, end it with one line on stderr (``cvxgeodesic: interrupted`` / ``cvxgeodesic: terminated``), no
    partial output file, and exit code 130 / 143. (Before this function runs, the console script imports only
    the standard library's modules this one and the package's ``__init__`` need: tens of milliseconds.)
    """
    args = None
    with _Signals() as signals:
        try:
            parser = build_parser()  # the first heavy imports: inside the try
            signals.check()
            args = parser.parse_args(argv)
            args.notes = _Notes()
            _check_numbers(args)
            with warnings.catch_warnings():
                if not args.debug:  # "cvxgeodesic: note: <message>", once, instead of file:line + source
                    warnings.showwarning = args.notes.showwarning
                return args.func(args)
        except KeyboardInterrupt:
            line, code = signals.stop_line()
            print(line, file=sys.stderr)
            return code
        except Exception as exc:  # every failure becomes one line; --debug shows where it came from
            if signals.received is not None:  # the signal broke something on its way (an import)
                line, code = signals.stop_line()
                print(line, file=sys.stderr)
                return code
            if args is None or getattr(args, "debug", False):  # before the arguments are read: a bug
                traceback.print_exc()
            msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            print(f"cvxgeodesic: error: {msg}", file=sys.stderr)
            return EXIT_USAGE


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
