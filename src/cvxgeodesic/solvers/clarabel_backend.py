"""Reference backend: the Clarabel interior-point conic solver."""

from __future__ import annotations

import time

import clarabel
import numpy as np
import scipy.sparse as sp

from ..errors import SolverError
from ._interrupt import interruptible
from .problem import BackendResult, ConicProblem

_SOLVED = {"Solved"}
_ALMOST = {"AlmostSolved"}


def reduce_to_free(problem: ConicProblem):
    """Eliminate fixed variables.

    Returns
    -------
    free : (nf,) int64 ndarray
        Indices of the free variables.
    P : (nf, nf) csc_matrix or None
    q : (nf,) float ndarray
    const : float
        Objective contribution of the fixed variables.
    A_cone, b_cone : sparse (2k, nf) and (2k,)
        ``‖b_cone - A_cone x‖`` per pair of rows... expressed so that ``B_t d = A x + b``.
    A_ineq, b_ineq : sparse (p, nf) and (p,)
        ``A_ineq x ≤ b_ineq``.
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
    C = problem.cone_matrix().tocsc()
    A_cone = C[:, free]
    g_cone = C @ dc
    Aq = problem.ineq_matrix().tocsc()
    A_ineq = Aq[:, free]
    b_ineq = problem.ineq_rhs - Aq @ dc
    return free, P, q, const, A_cone, g_cone, A_ineq, b_ineq


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
    free, P, q, const, A_cone, g_cone, A_ineq, b_ineq = reduce_to_free(problem)
    nf = free.size
    k = problem.n_cones
    # Clarabel form: A x + s = b, s ∈ K.  Nonnegative rows: A_ineq x + s = b_ineq.
    # SOC rows per cone t: s = (1, B_t d) = (1, A_t x + g_t)  ->  A = [0; -A_t], b = [1; g_t].
    soc_rows = np.arange(3 * k).reshape(k, 3)
    A_soc_body = sp.coo_matrix(A_cone)
    pair_row = soc_rows[:, 1:].ravel()  # the two body rows of every cone, in cone order
    A_soc = sp.csc_matrix((-A_soc_body.data, (pair_row[A_soc_body.row], A_soc_body.col)), shape=(3 * k, nf))
    b_soc = np.zeros(3 * k)
    b_soc[soc_rows[:, 0]] = 1.0
    b_soc[pair_row] = g_cone
    A = sp.vstack([A_ineq, A_soc]).tocsc()
    b = np.concatenate([b_ineq, b_soc])
    cones = []
    if problem.n_ineq:
        cones.append(clarabel.NonnegativeConeT(problem.n_ineq))
    cones.extend([clarabel.SecondOrderConeT(3)] * k)
    Pu = sp.triu(P).tocsc() if P is not None else sp.csc_matrix((nf, nf))

    solver = clarabel.DefaultSolver(Pu, q, A, b, cones, clarabel_settings(tol, max_iter, verbose, time_limit))
    t_setup = time.perf_counter() - t0
    with interruptible(solver):  # Ctrl-C stops the solve at the next iteration
        sol = solver.solve()
    status = str(sol.status)
    info = {"iterations": int(sol.iterations), "setup_time": t_setup}
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
        extra={"setup_time": t_setup, "clarabel_solve_time": float(sol.solve_time)},
    )
