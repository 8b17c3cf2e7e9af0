"""Reference backend: the Clarabel interior-point conic solver."""

from __future__ import annotations

import time

import clarabel
import numpy as np
import scipy.sparse as sp

from ..errors import SolverError
from ..problems.conic import BackendResult, ConicProblem
from ._interrupt import interruptible

_SOLVED = {"Solved"}
_ALMOST = {"AlmostSolved"}


def reduce_to_free(problem: ConicProblem):
    """Eliminate the fixed variables.

    Returns
    -------
    free : (nf,) int64 ndarray
        Indices of the free variables.
    P : (nf, nf) csc_matrix or None
    q : (nf,) float ndarray
    const : float
        Objective contribution of the fixed variables.
    A, b : sparse (rows, nf) and (rows,)
        Clarabel's ``A x + s = b``: the equalities (zero cone) first, then the inequalities (nonnegative
        cone), then every cone group's rows ``h_t − G_t x`` cone by cone.
    cones : list
        Clarabel's cone list in the same order.
    """
    fixed = problem.fixed_mask
    free = np.flatnonzero(~fixed)
    dc = np.where(fixed, problem.fixed_values, 0.0)
    q = problem.q[free].copy()
    const = float(problem.q[fixed] @ problem.fixed_values[fixed])
    P = None
    if problem.P is not None:
        Pc = problem.P.tocsc()
        P = Pc[free][:, free].tocsc()
        Pd = Pc @ dc
        q += Pd[free]
        const += 0.5 * float(dc @ Pd)
    n = problem.n
    mats, rhs, cones = [], [], []
    if problem.n_eq:
        E = sp.csr_matrix(problem.eq.E)
        mats.append(E)
        rhs.append(problem.eq.f)
        cones.append(clarabel.ZeroConeT(E.shape[0]))
    if problem.n_ineq:
        mats.append(problem.ineq.matrix(n))
        rhs.append(problem.ineq.rhs)
        cones.append(clarabel.NonnegativeConeT(problem.n_ineq))
    for g in problem.cones:
        if g.count:
            mats.append(g.matrix(n))
            rhs.append(g.h.ravel())
            cones.extend([clarabel.SecondOrderConeT(g.size)] * g.count)
    if mats:
        A_full = sp.vstack(mats).tocsc()
        b = np.concatenate(rhs) - A_full @ dc
        A = A_full[:, free].tocsc()
    else:
        A, b = sp.csc_matrix((0, free.size)), np.zeros(0)
    return free, P, q, const, A, b, cones


def clarabel_settings(tol: float, max_iter: int, verbose: bool = False, time_limit: float | None = None):
    """Clarabel settings of every cvxgeodesic solve: ``tol`` on gap and feasibility, ``max_iter``, a time limit."""
    settings = clarabel.DefaultSettings()
    settings.verbose = verbose
    settings.max_iter = max_iter
    settings.tol_gap_abs = tol
    settings.tol_gap_rel = tol
    settings.tol_feas = tol
    settings.tol_ktratio = 1e-6
    if time_limit is not None:
        settings.time_limit = float(time_limit)
    return settings


def solve_clarabel(
    problem: ConicProblem,
    *,
    tol: float = 1e-8,
    max_iter: int = 200,
    verbose: bool = False,
    time_limit: float | None = None,
) -> BackendResult:
    """Solve a :class:`ConicProblem` with Clarabel.

    Parameters
    ----------
    problem : ConicProblem
    tol : float
        Used for Clarabel's relative/absolute gap and feasibility tolerances.
    max_iter : int
    verbose : bool
        Print Clarabel's iteration log.
    time_limit : float, optional
        Seconds.

    Returns
    -------
    BackendResult

    Raises
    ------
    SolverError
        Clarabel did not reach ``Solved`` (``AlmostSolved`` is accepted and
        reported in the status).
    """
    t0 = time.perf_counter()
    free, P, q, const, A, b, cones = reduce_to_free(problem)
    nf = free.size
    Pu = sp.triu(P).tocsc() if P is not None else sp.csc_matrix((nf, nf))

    solver = clarabel.DefaultSolver(Pu, q, A, b, cones, clarabel_settings(tol, max_iter, verbose, time_limit))
    t_setup = time.perf_counter() - t0
    with interruptible(solver):  # Ctrl-C stops the solve at the next iteration
        sol = solver.solve()
    status = str(sol.status)
    info = {"iterations": int(sol.iterations), "clarabel_setup_time": t_setup}
    if status not in _SOLVED | _ALMOST:
        raise SolverError("Clarabel did not solve the problem", solver="clarabel", status=status, info=info)
    x = problem.fixed_values.copy()
    x[problem.unreachable] = 0.0
    x[free] = np.asarray(sol.x)
    return BackendResult(
        x=x,
        solver="clarabel",
        status="optimal" if status in _SOLVED else "almost_optimal",
        iterations=int(sol.iterations),
        solve_time=time.perf_counter() - t0,
        objective=float(sol.obj_val) + const,
        primal_residual=float(sol.r_prim),
        dual_residual=float(sol.r_dual),
        gap=abs(float(sol.obj_val) - float(sol.obj_val_dual)) / max(1.0, abs(float(sol.obj_val))),
        extra={"clarabel_setup_time": t_setup, "clarabel_solve_time": float(sol.solve_time)},
    )
