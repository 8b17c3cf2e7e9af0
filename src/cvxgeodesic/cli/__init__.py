"""Command-line interface: ``cvxgeodesic distance | compare | batch | path | view | matrix | demo``.

One module per command (``distance.py``, ``compare.py``, ...), each with ``add_parser(sub)`` and ``run(args)``;
``distance``, ``compare`` and ``view`` take a surface or a tetrahedral mesh, what differs asked of its reference
(``mesh.reference``: words, ``locate``). Every error a user can cause ends the program with exit code 2 and a
one-line message on stderr; ``--debug`` shows the full traceback instead. ``batch`` returns 1 when some meshes
failed (each listed) and the others were solved. Ctrl-C ends it with 130 and SIGTERM with 143, one line each and no
partial file. Output files are checked before any work: never one of the inputs, and a read-only one only with
``--overwrite-read-only`` (distance, path, view, matrix; batch refuses it before its solves). The folders of
``compare`` and ``demo`` are checked up front; a read-only file inside them is refused when it is written, after
the solves.
"""

from __future__ import annotations

import argparse
import sys
import traceback
import warnings

# Only the standard library at import (the package's __init__ is lazy too): the console script imports this
# package before main() runs, and main() must have its Ctrl-C handling in place before NumPy, SciPy and Numba load.
from .. import __version__, _signals
from ._common import EXIT_USAGE, Notes, Signals, check_numbers

__all__ = ["build_parser", "main"]

#: The command modules, in the order of ``cvxgeodesic --help``.
COMMANDS = ("distance", "compare", "batch", "path", "view", "matrix", "demo")


def build_parser() -> argparse.ArgumentParser:
    """The parser of every command (imports NumPy and the formats' registry for the help texts)."""
    import importlib

    from ..capabilities import help_text

    parser = argparse.ArgumentParser(
        prog="cvxgeodesic",
        description="Geodesic distance fields on triangle and tetrahedral meshes by convex optimization.",
        epilog=help_text(),  # what each dimension supports, from the one capability table
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    parser.add_argument("--debug", action="store_true", help="show full tracebacks on errors")
    sub = parser.add_subparsers(dest="command", required=True)
    for name in COMMANDS:
        importlib.import_module(f"{__name__}.{name}").add_parser(sub)
        # `cvxgeodesic distance ... --debug` as well as `cvxgeodesic --debug distance ...`
        sub.choices[name].add_argument("--debug", action="store_true", default=argparse.SUPPRESS,
                                       help=argparse.SUPPRESS)
    return parser


def main(argv=None) -> int:
    """Entry point of the ``cvxgeodesic`` console script; returns the exit code.

    Ctrl-C (SIGINT) and SIGTERM at any moment of the command, the start-up's imports of NumPy, SciPy and Numba
    included, end it with one line on stderr (``cvxgeodesic: interrupted`` / ``cvxgeodesic: terminated``), no
    partial output file, and exit code 130 / 143. (Before this function runs, the console script imports only
    the standard library's modules this package and the package's ``__init__`` need: tens of milliseconds, during
    which the handler that ``__init__`` installs first thing ends a Ctrl-C with the same line and 130; see
    :mod:`cvxgeodesic._signals`. Only Python's own start-up comes before it.)
    """
    args = None
    with Signals() as signals:
        try:
            parser = build_parser()  # the first heavy imports: inside the try
            _signals.check()  # a signal whose KeyboardInterrupt an optional import turned into an ignored ImportError
            args = parser.parse_args(argv)
            args.notes = Notes()
            check_numbers(args)
            with warnings.catch_warnings():
                if not args.debug:  # "cvxgeodesic: note: <message>", once, instead of file:line + source
                    warnings.showwarning = args.notes.showwarning
                return args.func(args)
        except KeyboardInterrupt:
            pass
        except Exception as exc:  # every failure becomes one line; --debug shows where it came from
            if signals.received is None:  # else the signal broke something on its way (an import)
                if args is None or getattr(args, "debug", False):  # before the arguments are read: a bug
                    traceback.print_exc()
                msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
                print(f"cvxgeodesic: error: {msg}", file=sys.stderr)
                return EXIT_USAGE
        line, code = signals.stop_line()
        print(line, file=sys.stderr)
        return code
