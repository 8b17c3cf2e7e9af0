"""Ctrl-C during a Clarabel solve: honoured at the next iteration instead of after the whole solve.

Clarabel's Rust solve does not return to the interpreter, so Python's SIGINT handler (which
raises ``KeyboardInterrupt``) only runs when the solve ends, seconds to minutes later. While
a solve runs, :func:`interruptible` replaces that handler by one that records the signal, and
gives Clarabel a termination callback (called once per iteration) that stops the solve once
it is recorded; ``KeyboardInterrupt`` is then raised as usual.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any


@contextmanager
def interruptible(solver: Any) -> Iterator[None]:
    """Run a Clarabel ``solver.solve()`` inside this block to make it stop at Ctrl-C within an iteration.

    Does nothing outside the main thread, or when SIGINT has a handler other than Python's
    default (a caller that handles SIGINT itself keeps doing so).

    Raises
    ------
    KeyboardInterrupt
        When SIGINT arrived during the block (after the solver stopped).
    """
    if (threading.current_thread() is not threading.main_thread()
            or signal.getsignal(signal.SIGINT) is not signal.default_int_handler
            or not hasattr(solver, "set_termination_callback")):
        yield
        return
    hit = threading.Event()

    def on_sigint(signum: int, frame: object) -> None:
        hit.set()

    solver.set_termination_callback(lambda info: hit.is_set())
    previous = signal.signal(signal.SIGINT, on_sigint)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
        try:
            solver.unset_termination_callback()
        except Exception:  # pragma: no cover - older Clarabel: the solver is discarded anyway
            pass
    if hit.is_set():
        raise KeyboardInterrupt
