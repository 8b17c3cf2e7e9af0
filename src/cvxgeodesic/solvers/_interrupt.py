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

    Ctrl-C is honoured only in the main thread while SIGINT has Python's default handler (a caller
    that handles SIGINT itself keeps doing so). Progress is reported to the callback of an enclosing
    :func:`reporting_to` block, in any thread.

    Raises
    ------
    KeyboardInterrupt
        When SIGINT arrived during the block (after the solver stopped).
    Exception
        What the progress callback raised (the solve is stopped at that iteration).
    """
    progress = _progress.get()
    catch_sigint = (threading.current_thread() is threading.main_thread()
                    and signal.getsignal(signal.SIGINT) is signal.default_int_handler)
    if not hasattr(solver, "set_termination_callback") or not (catch_sigint or progress):
        yield
        return
    hit = threading.Event()
    failed: list[BaseException] = []

    def on_sigint(signum: int, frame: object) -> None:
        hit.set()

    def each_iteration(info: Any) -> bool:
        if progress is not None and not failed:
            try:
                progress(int(info.iterations), clarabel_iteration_info(info))
            except Exception as exc:  # raised after the solve: an exception must not cross Clarabel's Rust frames
                failed.append(exc)
        return hit.is_set() or bool(failed)

    solver.set_termination_callback(each_iteration)
    previous = signal.signal(signal.SIGINT, on_sigint) if catch_sigint else None
    try:
        yield
    finally:
        if catch_sigint:
            signal.signal(signal.SIGINT, previous)
        try:
            solver.unset_termination_callback()
        except Exception:  # pragma: no cover - older Clarabel: the solver is discarded anyway
            pass
    if hit.is_set():
        raise KeyboardInterrupt
    if failed:
        raise failed[0]
