"""A structured primal–dual interior-point solver for :class:`~cvxgeodesic.problems.conic.ConicProblem`, at
every element order.

The problem (fixed variables eliminated) is written in the standard conic form ::

    minimize    ½ xᵀPx + qᵀx
    subject to  A x + s = b,   s ∈ K = SOC(d₁)^k₁ × … × R₊^p,    E x = f

with one block per cone group (:mod:`.blocks`: the fused SOC(3) kernels for the order-1 triangle cones
``s_t = (1, B_t x_t)``, the clique kernels for any other ``s_t = h_t − G_t x[dofs_t]``), one nonnegative slack
per linear inequality and a few equalities. The algorithm is in :mod:`.algorithm`, the starting point in
:mod:`.start`, residuals, stopping rule and certificates in :mod:`.residuals`, the reduced Newton system in
:mod:`.newton` and :mod:`.program`, the equilibration of order-2 programs in :mod:`.equilibrate`, the tuning
constants in :mod:`.settings` (:data:`~.settings.ORDER2` for the order-2 programs).

What makes it fast is the structure: every cone touches a small clique of variables (a triangle's three
vertices, a face's six P2 nodes) and every inequality at most two, so eliminating ``Δs`` and ``Δz`` leaves the
n×n SPD system ::

    (P + Σ_t G_tᵀ W_t⁻² G_t + Σ_k a_kᵀ (z_k/s_k) a_k) Δx = r

whose sparsity pattern is the union of the cliques (:func:`~cvxgeodesic.problems.conic.kkt_pattern` at order 1),
whatever the sources, the formulation or λ. Fixed variables become identity rows, which keeps the pattern; the
equalities enter through a small dense Schur complement. One symbolic Cholesky analysis
(:class:`~cvxgeodesic.linalg.SymbolicCholesky`) therefore serves every iteration of every solve on a mesh; an
iteration costs one numeric factorization, three to eight triangular solves (predictor, corrector, up to four
centrality correctors, iterative refinement of the final direction) and O(n) per-cone work done by compiled
kernels. The factorization backend is MKL PARDISO when installed, else CHOLMOD (see :mod:`cvxgeodesic.linalg`).

``W_t⁻² = (2 v̂ v̂ᵀ − J)/η²`` (``v̂ = J w̄``, NT scaling point ``w̄``, scale ``η``), so the clique of cone t is
``(2 (G_tᵀv̂)(G_tᵀv̂)ᵀ − G_tᵀJG_t)/η²``: ``G_tᵀJG_t`` is computed once per problem and each iteration adds a
rank-one term.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from ... import _threads
from ...errors import SolverError
from ...linalg import NotPositiveDefiniteError, SymbolicCholesky
from ...problems.conic import BackendResult, ConicProblem
from .algorithm import Stepper
from .equilibrate import equilibrate
from .newton import LinearSystem, Trouble
from .program import PatternMismatch, Program, problem_pattern
from .residuals import BestIterate, acceptable, almost, certificate, converged, evaluate, refine_target
from .settings import IPMSettings
from .start import StartFailure, starting_point

__all__ = ["InteriorPointSolver"]

_MESSAGES = {
    "max_iterations": "no convergence within max_iter={max_iter} iterations",
    "primal_infeasible": "the problem is primal infeasible (an infeasibility certificate was found)",
    "dual_infeasible": "the problem is unbounded (dual infeasible; a certificate was found)",
    "stalled": "the step lengths became negligible before convergence",
    "numerical_error": "numerical failure (the reduced Newton matrix could not be factorized or NaN appeared)",
}


class InteriorPointSolver:
    """Primal–dual interior-point solver specialized to the mesh problems of :class:`ConicProblem`.

    Construct it once per mesh with the mesh's Newton-matrix pattern; every
    :meth:`solve` (any sources, formulation or λ whose matrices fit the pattern)
    reuses the one symbolic Cholesky analysis done here. A problem that does not
    fit (e.g. a Laplacian-energy problem on a solver built with the Hessian
    pattern, whose 2-rings differ) triggers one new analysis of the union
    pattern, which is then kept for later solves.

    Parameters
    ----------
    pattern : (n, n) scipy.sparse matrix or SymbolicCholesky
        :func:`~cvxgeodesic.problems.conic.kkt_pattern` of the mesh, or an analysis of it (then ``backend``
        and ``ordering`` are its own).
    backend : {"auto", "pardiso", "cholmod", "scipy"}
        Sparse Cholesky backend, see :class:`~cvxgeodesic.linalg.SymbolicCholesky`.
    ordering : str
        Fill-reducing ordering of the analysis (:class:`~cvxgeodesic.linalg.SymbolicCholesky`; ``"auto"``: by the
        pattern's size).
    settings : IPMSettings
        Tuning constants (:mod:`.settings`; the defaults are the measured choices).

    Attributes
    ----------
    cholesky : SymbolicCholesky
        The current symbolic analysis.
    n_analyses : int
        Symbolic analyses done so far (1 unless a problem needed a wider pattern).

    Examples
    --------
    >>> import numpy as np
    >>> from cvxgeodesic.mesh import icosphere
    >>> from cvxgeodesic.problems.formulations import MeshOperators, build_problem
    >>> from cvxgeodesic.problems.conic import kkt_pattern
    >>> m = icosphere(2); ops = MeshOperators(m)
    >>> ipm = InteriorPointSolver(kkt_pattern(m.n_vertices, m.F, m.edges))
    >>> res = ipm.solve(build_problem(ops, np.array([0]), "qclp", 0.0))
    >>> res.status, ipm.n_analyses
    ('optimal', 1)
    """

    def __init__(self, pattern, *, backend: str = "auto", ordering: str = "auto",
                 settings: IPMSettings | None = None):
        if settings is not None and not isinstance(settings, IPMSettings):
            raise TypeError(f"settings must be an IPMSettings, got {type(settings).__name__}")
        self.settings = settings if settings is not None else IPMSettings()
        self._ordering = ordering
        # an analysis made already (the direct strategy's, which the energy's PSD check used) is taken as it is
        self.cholesky = (pattern if isinstance(pattern, SymbolicCholesky)
                         else SymbolicCholesky(pattern, backend=backend, ordering=ordering))
        self.n = self.cholesky.n
        self.n_analyses = self.cholesky.n_analyses

    def _prepare(self, problem: ConicProblem) -> Program:
        try:
            return Program.from_problem(problem, self.cholesky)
        except PatternMismatch:
            old = self.cholesky
            union = old.matrix(np.ones(old.nnz)) + problem_pattern(problem)
            self.cholesky = SymbolicCholesky(union, backend=old.backend, ordering=self._ordering)
            self.n_analyses += self.cholesky.n_analyses
            return Program.from_problem(problem, self.cholesky)

    def solve(
        self,
        problem: ConicProblem,
        *,
        tol: float = 1e-8,
        max_iter: int = 100,
        callback: Callable[[int, dict], None] | None = None,
    ) -> BackendResult:
        """Solve one problem.

        Parameters
        ----------
        problem : ConicProblem
            A problem on the mesh the solver was built for.
        tol : float
            Tolerance on the relative primal and dual residuals and on the
            duality gap (absolute or relative), as Clarabel's ``tol_feas``,
            ``tol_gap_abs`` and ``tol_gap_rel``.
        max_iter : int
            Maximum number of iterations.
        callback : callable, optional
            ``callback(iteration, info)`` at every iteration, ``info`` a dict with
            ``pcost``, ``dcost``, ``gap_abs``, ``gap_rel``, ``res_primal``,
            ``res_dual``, ``mu``, ``step`` (the previous step length) and ``time``.

        Returns
        -------
        BackendResult
            ``x`` (n,) with unreachable vertices set to 0. ``extra`` holds the
            timing breakdown in seconds (``program_time``: the problem turned into blocks, ``assembly_time``,
            ``factor_time``, ``linear_solve_time``, ``other_time``; their sum is
            ``total_time`` = ``solve_time``), ``refinement_steps``, ``correctors``,
            ``correctors_accepted``, ``new_analyses`` (symbolic analyses this call
            needed: 0 unless the problem did not fit the pattern), ``backend``, and
            the once-per-mesh ``analyze_time``, which is *not* part of ``solve_time``.
            ``status`` is ``"optimal"`` (``tol`` met) or ``"almost_optimal"``: the
            iterations ended in numerical trouble, a stall (no better iterate in
            10 iterations) or ``max_iter`` after an iterate whose residuals and gap
            were below 100 × ``tol``; ``x`` and the residuals are then that best
            iterate's, ``extra["stopped"]`` the reason and ``extra["best_iteration"]``
            its iteration, ``extra["acceptable"]`` whether it is within ``IPMSettings.accept_factor`` × ``tol``
            (``extra["accept_tol"]``; the backend policy keeps such an iterate without a Clarabel re-solve).

        Raises
        ------
        SolverError
            ``status`` is ``"max_iterations"``, ``"primal_infeasible"``,
            ``"dual_infeasible"`` (unbounded), ``"stalled"`` or ``"numerical_error"``
            when not even the reduced tolerances were met (infeasibility certificates
            always raise); ``info`` has the last iterate's residuals, gap and timings.

        Notes
        -----
        Without a quadratic term the Cholesky factor's supernodes are small, and
        BLAS/OpenMP threads cost more than they bring: measured on bimba (46K faces,
        2 cores) QCLP took 3.7 s with the default threads and 2.35 s with one, so
        such solves run single-threaded (threadpoolctl). With the Hessian energy's
        larger supernodes two threads are slightly faster (7.6 s against 8.7 s) and
        the default is kept.
        """
        if self.cholesky.backend == "cholmod":
            limits = 1 if problem.P is None else None
        else:
            # PARDISO pins its own threads; an idle OpenBLAS thread pool spins after NumPy's BLAS calls and
            # takes a core from it (measured on bimba's QCLP: 1.2 s with OpenBLAS on one thread, 2.4 s without).
            limits = {"libopenblas": 1, "libscipy_openblas": 1}
        with _threads.pool_limits(limits):
            return self._solve(problem, tol=tol, max_iter=max_iter, callback=callback)

    def _solve(self, problem: ConicProblem, *, tol: float, max_iter: int, callback) -> BackendResult:
        t_start = time.perf_counter()
        analyses_before = self.n_analyses
        solved, scale = (equilibrate(problem) if problem.equilibrate else (problem, None))
        pr = self._prepare(solved)
        x, status, info, stopped, run = self._run(pr, t_start, tol, max_iter, callback)
        xout = x * scale if scale is not None else x.copy()
        xout[np.asarray(problem.unreachable, dtype=bool)] = 0.0
        return run.result(xout, problem.objective(xout), status, info, stopped, analyses_before)

    def solve_program(self, program: Program, *, tol: float = 1e-8, max_iter: int = 100,
                      callback: Callable[[int, dict], None] | None = None) -> BackendResult:
        """Solve a :class:`~.program.Program` built on :attr:`cholesky` (any cone blocks, e.g.
        :class:`~.blocks.SparseBlock`); parameters, result and errors as :meth:`solve`.

        No thread limits are applied (:meth:`solve` chooses them for the mesh problems).
        """
        t_start = time.perf_counter()
        x, status, info, stopped, run = self._run(program, t_start, tol, max_iter, callback)
        objective = float(program.q @ x) + (0.5 * float(x @ (program.P @ x)) if program.P is not None else 0.0)
        return run.result(x.copy(), objective, status, info, stopped, self.n_analyses)

    def _run(self, pr: Program, t_start: float, tol: float, max_iter: int, callback):
        """Start, iterate, and settle the status: ``(x, status, info, stopped, run)``; raises SolverError."""
        run = _Run(self, pr, t_start, max_iter, tol)
        if pr.unbounded_var >= 0:
            raise run.fail("dual_infeasible", f"variable {pr.unbounded_var} has a linear cost and no constraint")
        try:
            start = starting_point(pr, run.ls, self.settings)
        except StartFailure as exc:
            raise run.fail("numerical_error", str(exc)) from exc
        sigma_cap = self.settings.sigma_cap_guess if start.from_guess else 1.0
        # the "guess" start falls back to Mehrotra's without a usable guess
        run.counters["start"] = "guess" if start.from_guess else self.settings.init.replace("guess", "mehrotra")
        it, status, _ = self._iterate(pr, run, start.iterate, tol, max_iter, callback, sigma_cap)
        info = run.info
        x = it.x
        stopped = None
        if status != "optimal":
            certified = status in ("primal_infeasible", "dual_infeasible")
            if certified or run.best.x is None or not almost(run.best.info, tol, self.settings):
                raise run.fail(status)
            # numerical trouble, a stall or max_iter after an iterate within the reduced tolerances
            stopped, status = status, "almost_optimal"
            x, info = run.best.x, run.best.info
        return x, status, info, stopped, run

    def _iterate(self, pr: Program, run: _Run, it, tol: float, max_iter: int, callback, sigma_cap: float = 1.0):
        """Iterate until a status is reached: ``(last iterate, status, last step)``."""
        stepper = Stepper(pr, run.ls, self.settings, run.counters, sigma_cap)
        k = 0
        step = float("nan")
        small_steps = 0
        while True:
            ev = evaluate(pr, it, k, step, time.perf_counter() - run.t_start)
            run.info = info = ev.info
            if callback is not None:
                callback(k, dict(info))
            if not np.isfinite(info["res_primal"] + info["res_dual"] + info["gap_abs"] + info["mu"]):
                return it, "numerical_error", step
            if converged(info, tol, self.settings):
                return it, "optimal", step
            if run.best.update(it.x, info, tol, self.settings):
                return it, "stalled", step
            status = certificate(pr, ev, self.settings)
            if status is not None:
                return it, status, step
            if k >= max_iter:
                return it, "max_iterations", step
            try:
                it, step = stepper.step(it, ev, refine_target(ev, tol, self.settings))
            except (NotPositiveDefiniteError, Trouble):  # a non-finite solve: keep the best iterate
                return it, "numerical_error", step
            k += 1
            run.iterations = k
            small_steps = small_steps + 1 if step < 1e-8 else 0
            if small_steps >= 3:
                return it, "stalled", step


class _Run:
    """The bookkeeping of one solve: timers, counters, the latest ``info``, the best iterate, the result."""

    def __init__(self, solver: InteriorPointSolver, pr: Program, t_start: float, max_iter: int, tol: float):
        self.solver, self.pr, self.t_start, self.max_iter, self.tol = solver, pr, t_start, max_iter, tol
        self.timers = {"program_time": time.perf_counter() - t_start, "assembly_time": 0.0, "factor_time": 0.0,
                       "linear_solve_time": 0.0}
        self.counters = {"refinement_steps": 0, "correctors": 0, "correctors_accepted": 0}
        self.info: dict = {"iterations": 0}
        self.iterations = 0
        self.best = BestIterate()
        self.ls = LinearSystem(pr, solver.cholesky, solver.settings, self.timers, self.counters)

    def fail(self, status: str, extra_msg: str = "") -> SolverError:
        total = time.perf_counter() - self.t_start
        info = self.info
        info.update(self.timers, status=status, solve_time=total, **self.counters)
        msg = _MESSAGES[status].format(max_iter=self.max_iter) + (f": {extra_msg}" if extra_msg else "")
        return SolverError(msg, solver="ipm", status=status, info=info)

    def result(self, x: np.ndarray, objective: float, status: str, info: dict, stopped: str | None,
               analyses_before: int) -> BackendResult:
        chol = self.solver.cholesky
        total = time.perf_counter() - self.t_start
        extra = {
            **self.timers,
            "other_time": total - sum(self.timers.values()),
            "total_time": total,
            **self.counters,
            "analyze_time": chol.analyze_time,
            "new_analyses": self.solver.n_analyses - analyses_before,
            "backend": chol.backend,
            "mu": info["mu"],
            "gap_abs": info["gap_abs"],
        }
        if stopped is not None:
            extra.update(stopped=stopped, best_iteration=info["iterations"],
                         acceptable=acceptable(info, self.tol, self.solver.settings),
                         accept_tol=self.solver.settings.accept_factor * self.tol)
        return BackendResult(
            x=x,
            solver="ipm",
            status=status,
            iterations=self.iterations,
            solve_time=total,
            objective=objective,
            primal_residual=info["res_primal"],
            dual_residual=info["res_dual"],
            gap=info["gap_rel"],
            extra=extra,
        )
