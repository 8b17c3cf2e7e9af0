"""The iteration log that ``GeodesicSolver(..., verbose=True)`` prints for the interior-point backend."""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import TextIO

IPMCallback = Callable[[int, dict], None]


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
