"""The plumbing every command shares: signals, notes, the number checks and the output checks.

Only the standard library at import, as the whole :mod:`cvxgeodesic.cli` package (see its ``__init__``).
"""

from __future__ import annotations

import argparse
import signal
import sys
from typing import TYPE_CHECKING, Any

from ..errors import ParameterError
from ._options import CLOUD_OPTIONS

if TYPE_CHECKING:
    from ..mesh.simplex import SimplexMesh

EXIT_USAGE = 2
EXIT_INTERRUPTED = 128 + signal.SIGINT  # 130, as a shell reports a process ended by Ctrl-C
EXIT_TERMINATED = 128 + signal.SIGTERM  # 143: kill, systemd, a batch system's time limit

#: The flag that lets a command replace read-only output files.
OVERWRITE_READ_ONLY = "--overwrite-read-only"


class Notes:
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


class Signals:
    """Ctrl-C (SIGINT) and SIGTERM for the duration of a command: recorded, then ``KeyboardInterrupt``.

    Both handlers raise ``KeyboardInterrupt``, so every ``finally`` that removes temporary files runs, and
    record the signal: :func:`~cvxgeodesic.cli.main` then prints the line and returns the code of the signal that
    came, also when the interrupt surfaced as another error (an extension module's import that it broke turns it
    into an ``ImportError``). During a Clarabel solve they run once the solve stopped (their mark,
    :data:`cvxgeodesic.solvers._interrupt.STOPS_SOLVES`). A SIGINT or SIGTERM that the process ignores (a
    background job of a script, a parent's choice) stays ignored.
    """

    def __init__(self) -> None:
        self.received: int | None = None
        self.previous: dict[int, object] = {}

    def __enter__(self) -> Signals:
        import threading

        from .. import _signals

        def on_signal(signum: int, frame: object) -> None:
            self.received = self.received or signum
            _signals.record(signum)  # raised again at the library's next check if a ctypes callback swallows it
            if _signals.in_c_callback(frame):
                return  # raised there would print a traceback and be lost: _signals.check raises it next
            raise KeyboardInterrupt

        # named as solvers._interrupt.STOPS_SOLVES, which is not imported here: it loads Clarabel and SciPy
        setattr(on_signal, "cvxgeodesic_stops_solves", True)  # noqa: B010
        if threading.current_thread() is threading.main_thread():  # signal.signal works there only
            current = signal.getsignal(signal.SIGINT)
            # Python's handler, or the one the package installed until this one (_signals.install_early)
            if current is signal.default_int_handler or getattr(current, _signals.EARLY_MARK, False):
                self.previous[signal.SIGINT] = signal.signal(signal.SIGINT, on_signal)
            if signal.getsignal(signal.SIGTERM) is not signal.SIG_IGN:  # a parent's deliberate ignore stays
                self.previous[signal.SIGTERM] = signal.signal(signal.SIGTERM, on_signal)
        return self

    def __exit__(self, *exc: object) -> None:
        from .. import _signals

        for signum, handler in self.previous.items():
            signal.signal(signum, handler)  # type: ignore[arg-type]
        _signals.clear()  # handled (main printed its line): a later command in this process starts afresh

    def stop_line(self) -> tuple[str, int]:
        """The message and the exit code of the signal received (Ctrl-C when none was recorded)."""
        if self.received == signal.SIGTERM:
            return "cvxgeodesic: terminated", EXIT_TERMINATED
        return "cvxgeodesic: interrupted", EXIT_INTERRUPTED


def load_input(path: str, cloud: dict[str, Any] | None = None) -> SimplexMesh:
    """The command's input: a point file's cloud (its triangle soup; ``mesh/formats/registry.is_point_file``) built
    with ``cloud``'s keywords (``_options.cloud_options``), else :func:`~cvxgeodesic.mesh.load.load_mesh`, which
    takes none of them (a ParameterError names the first option given)."""
    from ..mesh.formats.registry import is_point_file
    from ..mesh.io import load_mesh
    from ..mesh.pointcloud_io import load_point_cloud

    cloud = cloud or {}
    if is_point_file(path):
        return load_point_cloud(path, **cloud).mesh
    if cloud:
        raise ParameterError(f"{CLOUD_OPTIONS[next(iter(cloud))]} applies to point files; {path} is a mesh file")
    return load_mesh(path)


def check_numbers(args: argparse.Namespace) -> None:
    """``--m``, ``--lam``, ``--slice-normal``, ``--view`` and ``--up`` checked as the Python API checks them, before a
    command prints or reads anything."""
    from ..validation import check_number, check_smoothness

    if getattr(args, "lam", None) is not None:
        check_number(args.lam, "lam", low=0)
    elif getattr(args, "m", None) is not None:
        check_smoothness(args.m, None)  # its range too (validation.MAX_M)
    normal = getattr(args, "slice_normal", None)
    if normal is not None and not any(normal):  # the plane's normal: any direction, but a direction
        raise ParameterError(f"--slice-normal {','.join(f'{c:g}' for c in normal)}: the normal of the slice must "
                             "not be zero (e.g. 0,0,1)")
    if hasattr(args, "up"):  # the commands with pictures: --view and --up read here, one line naming the option
        from ._options import parse_view_options

        parse_view_options(args)


def add_overwrite_option(p: argparse.ArgumentParser) -> None:
    """``--overwrite-read-only``: replace output files that are read-only (refused otherwise, before any work)."""
    p.add_argument(OVERWRITE_READ_ONLY, action="store_true",
                   help="replace an output file even when it is read-only (no write permission for its owner; it "
                        "keeps its mode); without it such a file is refused before anything is computed")


def check_outputs(args: argparse.Namespace, *outputs: tuple[str, str | None, tuple[str, ...]]) -> None:
    """Every output file of a command checked before any work, as ``(option, path or None, extensions)``.

    Raises
    ------
    ParameterError
        An unsupported extension, a missing or unwritable folder (:func:`~cvxgeodesic.validation.check_output_path`),
        an output that is one of the command's input files (the mesh, ``--cost``;
        :func:`~cvxgeodesic.validation.check_not_an_input`), or a read-only file without ``--overwrite-read-only``.
    """
    from .._atomic import check_replaceable
    from ..validation import check_not_an_input, check_output_path

    inputs = [f for f in (getattr(args, "mesh", None), getattr(args, "cost", None)) if f]
    for option, path, extensions in outputs:
        if path is None:
            continue
        check_output_path(path, extensions)
        check_not_an_input(path, inputs, option)
        check_replaceable(path, overwrite_read_only=getattr(args, "overwrite_read_only", False),
                          allow=OVERWRITE_READ_ONLY)
