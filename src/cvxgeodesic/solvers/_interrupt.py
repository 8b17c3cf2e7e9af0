"""Clarabel's once-per-iteration hook: Ctrl-C within an iteration, and progress reports.

Clarabel's Rust solve does not return to the interpreter, so Python's SIGINT handler (which
raises ``KeyboardInterrupt``) only runs when the solve ends, seconds to minutes later. While
a solve runs, :func:`interruptible` replaces that handler by one that records the signal, and
gives Clarabel a termination callback (called once per iteration) that stops the solve once
it is recorded; ``KeyboardInterrupt`` is then raised as usual.

The same termination callback reports every iteration to the progress callback that
:func:`reporting_to` installed (``GeodesicSolver.solve(callback=...)`` does, so the CLI's progress
lines cover Clarabel as they cover the structured solver), as ``callback(iteration, info)`` with the
keys of the interior-point solver's ``info`` (:func:`clarabel_iteration_info`).
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Any

IterationCallback = Callable[[int, dict], None]

#: The attribute (set to True) of a Python signal handler that ends the program by raising, as the command line's
#: SIGINT and SIGTERM handlers do (``cli._Signals`` sets it by this name: importing this module loads Clarabel).
#: During a Clarabel solve such a handler is not run inside the solver's callback, where what it raises would not
#: stop the solve: the signal stops the solve at its next iteration, as Ctrl-C does, and the handler runs then.
STOPS_SOLVES = "cvxgeodesic_stops_solves"

# a context variable rather than a parameter: Clarabel is reached through the solve strategies, which pass
# a callback to the interior-point solver only, and through the order-2 solve's own fallback
_progress: ContextVar[IterationCallback | None] = ContextVar("cvxgeodesic_clarabel_progress", default=None)


@contextmanager
def reporting_to(callback: IterationCallback | None) -> Iterator[None]:
    """Report every iteration of the Clarabel solves run inside this block to ``callback(iteration, info)``.

    ``None`` leaves an enclosing block's callback in place.
    """
    if callback is None:
        yield
        return
    token = _progress.set(callback)
    try:
        yield
    finally:
        _progress.reset(token)


def clarabel_iteration_info(info: Any) -> dict:
    """Clarabel's per-iteration ``DefaultInfo`` as the interior-point solver's ``info`` dict, plus ``solver``."""
    return {"solver": "clarabel", "pcost": float(info.cost_primal), "dcost": float(info.cost_dual),
            "gap_rel": float(info.gap_rel), "res_primal": float(info.res_primal), "res_dual": float(info.res_dual),
            "mu": float(info.mu), "step": float(info.step_length), "time": float(info.solve_time)}


@contextmanager
def interruptible(solver: Any) -> Iterator[None]:
    """Run a Clarabel ``solver.solve()`` inside this block to make it stop at Ctrl-C within an iteration.

    Ctrl-C is honoured only in the main thread while SIGINT has Python's default handler or one marked
    :data:`STOPS_SOLVES` (a caller that handles SIGINT otherwise keeps doing so); a SIGTERM handler marked
    so is honoured the same way. Progress is reported to the callback of an enclosing
    :func:`reporting_to` block, in any thread.

    Raises
    ------
    KeyboardInterrupt
        When SIGINT arrived during the block (after the solver stopped), or what the marked handler of the
        signal that arrived raises.
    Exception
        What the progress callback raised (the solve is stopped at that iteration).
    """
    progress = _progress.get()
    handlers: dict[int, Any] = {}  # signal -> the handler it had, for the signals this block catches
    if threading.current_thread() is threading.main_thread():
        for sig in (signal.SIGINT, signal.SIGTERM):
            handler = signal.getsignal(sig)
            if (sig == signal.SIGINT and handler is signal.default_int_handler) or \
                    getattr(handler, STOPS_SOLVES, False) is True:
                handlers[sig] = handler
    if not hasattr(solver, "set_termination_callback") or not (handlers or progress):
        yield
        return
    hit = threading.Event()
    received: list[int] = []
    failed: list[BaseException] = []

    def on_signal(signum: int, frame: object) -> None:
        received.append(signum)
        hit.set()

    def each_iteration(info: Any) -> bool:
        if progress is not None and not failed:
            try:
                progress(int(info.iterations), clarabel_iteration_info(info))
            except Exception as exc:  # raised after the solve: an exception must not cross Clarabel's Rust frames
                failed.append(exc)
        return hit.is_set() or bool(failed)

    solver.set_termination_callback(each_iteration)
    for signum in handlers:
        signal.signal(signum, on_signal)
    try:
        yield
    finally:
        for signum, previous in handlers.items():
            signal.signal(signum, previous)
        try:
            solver.unset_termination_callback()
        except Exception:  # pragma: no cover - older Clarabel: the solver is discarded anyway
            pass
    if received and handlers[received[0]] is not signal.default_int_handler:
        handlers[received[0]](received[0], None)  # the marked handler's turn, out of Clarabel's frames
    if hit.is_set():
        raise KeyboardInterrupt
    if failed:
        raise failed[0]
