"""A command-line signal whose ``KeyboardInterrupt`` was swallowed, raised again at the library's next safe point.

The command line's SIGINT/SIGTERM handler (:class:`cvxgeodesic.cli._Signals`) raises ``KeyboardInterrupt``
wherever the main thread is. Inside a ctypes callback that exception is lost: ctypes prints "Exception ignored on
calling ctypes callback function" and the C call goes on. threadpoolctl finds the BLAS and OpenMP libraries
through such a callback (``dl_iterate_phdr``) every time a solve limits its threads, so a Ctrl-C that landed there
let a matrix of 320 rows run to its end (seen in a loaded test run, 2026-12-03). The handler therefore also records
the signal here, and the places that call into ctypes, and the loops over rows, call :func:`check`.

Only the command line records signals: in a Python session nothing is recorded, and :func:`check` does nothing.
Standard library only (imported by the command line before NumPy).

Before :func:`cvxgeodesic.cli.main` installs its handlers, the command's process imports the package and the
command line's modules (tens of milliseconds); a Ctrl-C there printed a ``KeyboardInterrupt`` traceback. So the
package's ``__init__``, first thing and before it imports anything of its own, installs a handler in the command's
process only (the console script ``cvxgeodesic``, ``python -m cvxgeodesic.cli``): until ``main`` takes over, a
Ctrl-C prints the command's one line and exits with 130 (nothing is written yet, so nothing is left to remove).
That handler carries the attribute :data:`EARLY_MARK`; what comes before it is Python's own start-up.
"""

from __future__ import annotations

__all__ = ["C_CALLBACKS", "EARLY_MARK", "check", "clear", "in_c_callback", "record"]

#: The attribute that marks the package's early SIGINT handler (``cvxgeodesic/__init__.py``), which the command
#: line replaces with its own.
EARLY_MARK = "cvxgeodesic_early"

_pending: dict[str, int | None] = {"signum": None}

#: Python functions whose exceptions the interpreter prints ("Exception ignored ...", with a traceback) and drops, as
#: (file name ending, function name): a callback C code calls through ctypes (threadpoolctl's), and the weak-reference
#: callback of importlib's module locks, which runs while the start-up imports (a Ctrl-C 0.05–0.3 s after NumPy was
#: mapped printed its traceback in a clean clone's first test run, 2026-12-06).
C_CALLBACKS = (("threadpoolctl.py", "match_library_callback"), ("importlib._bootstrap>", "cb"))


def in_c_callback(frame: object) -> bool:
    """Whether ``frame`` (a signal handler's frame argument) runs under one of :data:`C_CALLBACKS`.

    The command line's handler then only records the signal: :func:`check` raises it at the next safe point, where
    raising it at once would print a traceback and lose it (seen in a loaded run of the Ctrl-C test of
    ``cvxgeodesic matrix``, 2026-12-06).
    """
    while frame is not None:
        code = frame.f_code  # type: ignore[attr-defined]
        if any(code.co_filename.endswith(name) and code.co_name == func for name, func in C_CALLBACKS):
            return True
        frame = frame.f_back  # type: ignore[attr-defined]
    return False


def record(signum: int) -> None:
    """Remember that ``signum`` came (its handler is about to raise ``KeyboardInterrupt``)."""
    _pending["signum"] = signum


def clear() -> None:
    """Forget the signal: the command handled its ``KeyboardInterrupt``."""
    _pending["signum"] = None


def check() -> None:
    """Raise ``KeyboardInterrupt`` if a recorded signal's own exception was lost on its way.

    Call it on normal paths only (not in ``finally`` blocks): while the handler's exception propagates, the
    signal is recorded too.
    """
    if _pending["signum"] is not None:
        raise KeyboardInterrupt
