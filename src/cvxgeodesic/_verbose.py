"""What a solve prints while it runs: the iteration log of ``GeodesicSolver(..., verbose=True)`` (interior-point
backend) and the CLI's progress lines (:func:`progress_printer`)."""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import TextIO

IPMCallback = Callable[[int, dict], None]

#: Seconds a solve runs before :func:`progress_printer` prints its first line: a solve that ends sooner prints
#: nothing, a longer one a line per iteration. Read at each call (tests set it to 0).
PROGRESS_DELAY = 2.0


def ipm_log(callback: IPMCallback | None = None, stream: TextIO | None = None) -> IPMCallback:
    """An IPM callback printing one line per iteration (after a header), then calling ``callback``.

    Parameters
    ----------
    callback : callable, optional
        The caller's own ``callback(iteration, info)``, still called at every iteration.
    stream : text file, optional
        Where to print (default ``sys.stdout`` at call time, like Clarabel's log).

    Returns
    -------
    callable
        ``log(iteration, info)`` with ``info`` the dict of
        :meth:`~cvxgeodesic.solvers.ipm.InteriorPointSolver.solve`.
    """
    state = {"header": False}

    def log(iteration: int, info: dict) -> None:
        out = sys.stdout if stream is None else stream
        if not state["header"]:
            print("iter    pcost          dcost          gap_rel   pres      dres      mu        step  time", file=out)
            state["header"] = True
        print(f"{iteration:4d}  {info.get('pcost', float('nan')):+.6e}  {info.get('dcost', float('nan')):+.6e}  "
              f"{info.get('gap_rel', float('nan')):.2e}  {info.get('res_primal', float('nan')):.2e}  "
              f"{info.get('res_dual', float('nan')):.2e}  {info.get('mu', float('nan')):.2e}  "
              f"{info.get('step', float('nan')):.2f}  {info.get('time', float('nan')):.2f}s", file=out, flush=True)
        if callback is not None:
            callback(iteration, info)

    return log


def progress_printer(stream: TextIO | None = None, *, delay: float | None = None,
                     clock: Callable[[], float] = time.perf_counter) -> IPMCallback:
    """A ``callback(iteration, info)`` for :meth:`GeodesicSolver.solve` that prints progress once a solve is slow.

    From ``delay`` seconds after this call on, every iteration prints one line: the iteration, the relative
    gap, the primal and dual residuals and the time since this call, e.g.
    ``  iteration  12  gap 3.1e-04  residuals 1.2e-09 / 3.4e-08     2.4 s``, and ``(clarabel)`` at the end of
    Clarabel's lines. Earlier iterations print nothing, so a fast solve stays silent.

    Parameters
    ----------
    stream : text file, optional
        Where to print (default ``sys.stderr`` at call time: progress is not output).
    delay : float, optional
        Seconds before the first line (default :data:`PROGRESS_DELAY`).
    clock : callable, optional
        Seconds as a float (for tests).

    Returns
    -------
    callable
        ``progress(iteration, info)`` with ``info`` the dict described in :meth:`GeodesicSolver.solve`.
    """
    wait = PROGRESS_DELAY if delay is None else float(delay)
    t0 = clock()

    def progress(iteration: int, info: dict) -> None:
        elapsed = clock() - t0
        if elapsed < wait:
            return
        nan = float("nan")
        line = (f"  iteration {iteration:3d}  gap {info.get('gap_rel', nan):.1e}  "
                f"residuals {info.get('res_primal', nan):.1e} / {info.get('res_dual', nan):.1e}  {elapsed:6.1f} s")
        if info.get("solver"):
            line += f"  ({info['solver']})"
        print(line, file=sys.stderr if stream is None else stream, flush=True)

    return progress
