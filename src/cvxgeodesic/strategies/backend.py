"""The backend policy every convex strategy shares (order 1 and order 2): which backend solves a program and what
happens when it fails, each step recorded in ``info.notes``.

- ``solver="auto"`` uses the structured interior-point solver when it can be imported (it needs Numba), else
  Clarabel (noted);
- an ``almost_optimal`` interior-point solve whose best iterate is within ``IPMSettings.accept_factor`` × ``tol``
  (``extra["acceptable"]``: the iterations stopped at the rounding floor of the residuals, just above ``tol``) is
  kept, with a note giving its gap and residuals: a Clarabel re-solve cost 7–25× the time for a field equal within
  1e-6 (issue 41, docs/dev/endgame.md);
- under ``"auto"``, Clarabel retries an interior-point solve that failed or was ``almost_optimal`` farther from
  ``tol`` (warned and noted); an almost optimal iterate is kept when Clarabel fails too (noted);
- an infeasibility certificate is retried under ``"auto"`` too: the distance programs are feasible and bounded by
  construction, so a certificate on them comes from rounding (order 2 with a cost ratio of 1e5 was certified
  unbounded, issue 41); when Clarabel fails as well, the interior-point solver's error is raised.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..errors import ParameterError, SolverError, warn_user
from ..problems.conic import BackendResult, ConicProblem

__all__ = ["Backend", "ipm_available"]


def ipm_available() -> bool:
    """True when the structured interior-point solver (and so Numba) can be imported."""
    try:
        from ..solvers import ipm  # noqa: F401
    except ImportError:
        return False
    return True


def _solve_clarabel(problem: ConicProblem, tol: float, max_iter: int, verbose: bool) -> BackendResult:
    from ..solvers import solve_clarabel  # looked up at call time: tests replace it to simulate failures

    return solve_clarabel(problem, tol=tol, max_iter=max_iter, verbose=verbose)


class Backend:
    """The backend choice of one strategy and the policy of :meth:`solve`.

    Parameters
    ----------
    solver : {"auto", "ipm", "clarabel"}
        What the user asked for.
    tol, max_iter, verbose
        The solve parameters (:class:`~cvxgeodesic.strategies.base.SolveConfig`).
    mesh_name : str
        For messages.

    Attributes
    ----------
    name : {"ipm", "clarabel"}
        The backend that solves.
    notes : list of str
        The substitution made at construction (Clarabel for want of Numba), if any.

    Raises
    ------
    ParameterError
        ``solver="ipm"`` where the structured solver cannot be imported.
    """

    def __init__(self, solver: str, tol: float, max_iter: int, verbose: bool, mesh_name: str):
        self.tol, self.max_iter, self.verbose, self.mesh_name = tol, max_iter, verbose, mesh_name
        self.notes: list[str] = []
        if solver == "auto":
            self.name = "ipm" if ipm_available() else "clarabel"
            if self.name == "clarabel":
                self.notes.append("the interior-point solver is not available in this installation (it needs "
                                  "Numba); solved with Clarabel")
        else:
            self.name = solver
        if self.name == "ipm" and not ipm_available():
            raise ParameterError("solver='ipm' is not available in this installation (it needs Numba)")
        self.fallback_to_clarabel = solver == "auto"

    def solve(self, problem: ConicProblem, ipm: Any, callback: Callable[[int, dict], None] | None,
              notes: list[str], fallback: bool = True) -> BackendResult:
        """Solve ``problem`` with the chosen backend (``ipm``: the strategy's InteriorPointSolver), appending every
        substitution to ``notes``; ``fallback=False``: no Clarabel retry (the caller has another program to try).

        Raises
        ------
        SolverError
            Both backends failed (or the chosen one, without ``"auto"``); an infeasibility certificate.
        """
        if self.name != "ipm":
            return _solve_clarabel(problem, self.tol, self.max_iter, self.verbose)
        if self.verbose:
            from .._verbose import ipm_log

            callback = ipm_log(callback)
        retry = self.fallback_to_clarabel and fallback
        try:
            res = ipm.solve(problem, tol=self.tol, max_iter=self.max_iter, callback=callback)
        except SolverError as exc:
            if not retry:
                raise
            try:
                return self._clarabel_retry(problem, exc.status, notes)
            except SolverError as clarabel_exc:
                if exc.status not in ("primal_infeasible", "dual_infeasible"):
                    raise
                notes.append(f"Clarabel failed too ({clarabel_exc.status})")
                raise exc from clarabel_exc
        if res.status == "optimal":
            return res
        if res.extra.get("acceptable"):
            notes.append(_accepted_note(res, self.tol))
            return res
        if not retry:
            return res
        try:  # "almost_optimal": Clarabel may reach the full accuracy; else keep the IPM's best iterate
            return self._clarabel_retry(problem, res.status, notes)
        except SolverError:
            notes.append("Clarabel failed too; kept the interior-point solver's almost optimal iterate")
            return res

    def _clarabel_retry(self, problem: ConicProblem, ipm_status: str, notes: list[str]) -> BackendResult:
        message = (f"the interior-point solver stopped with status {ipm_status!r} on {self.mesh_name}; "
                   "solving with Clarabel instead")
        warn_user(message, RuntimeWarning)
        notes.append(message)
        res = _solve_clarabel(problem, self.tol, self.max_iter, self.verbose)
        res.extra = dict(res.extra, ipm_failure=ipm_status)
        return res


def _accepted_note(res: BackendResult, tol: float) -> str:
    """The note of an ``almost_optimal`` iterate kept without a re-solve: the criterion and the iterate's values."""
    extra = res.extra
    within = extra.get("accept_tol", 10 * tol)
    return (f"the interior-point solver stopped ({extra.get('stopped')}) with its best iterate (iteration "
            f"{extra.get('best_iteration')}) short of tol={tol:.3g} but within {within:.3g}: relative gap "
            f"{res.gap:.2g} (absolute {extra.get('gap_abs', float('nan')):.2g}), primal residual "
            f"{res.primal_residual:.2g}, dual residual {res.dual_residual:.2g}; accepted as 'almost_optimal' "
            "without a Clarabel re-solve")
