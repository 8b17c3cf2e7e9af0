"""A structured primal–dual interior-point solver for :class:`ConicProblem`.

The problem (fixed variables eliminated) is written in the standard conic form ::

    minimize    ½ xᵀPx + qᵀx
    subject to  A x + s = b,   s ∈ K = R₊^p × SOC(3)^k

with one SOC(3) per cone t, ``s_t = (1, B_t x_t)`` (so ``b_t = (1, 0, 0)`` and
``A_t = [0; −B_t]``), and one nonnegative slack per linear inequality. The
method is the infeasible-start primal–dual path-following algorithm of CVXOPT's
``coneqp`` (L. Vandenberghe, "The CVXOPT linear and quadratic cone program
solvers", 2010) with Nesterov–Todd scaling and Mehrotra's predictor–corrector,
plus Gondzio's multiple centrality correctors (J. Gondzio, "Multiple centrality
corrections in a primal-dual method for linear programming", 1996, applied to
the eigenvalues of the SOC Jordan products; weighted as in Colombo & Gondzio
2008) and, without a quadratic term, separate primal and dual step lengths. The
starting point is strictly primal feasible (``x`` scaled towards the fixed
values) with a least-norm dual shifted cone by cone. Infeasibility and
unboundedness are detected with Clarabel's certificate tests on the iterates.

What makes it fast is the structure: every cone touches three variables and
every inequality at most two, so eliminating ``Δs`` and ``Δz`` leaves the n×n
SPD system ::

    (P + Σ_t B_tᵀ [W_t⁻²]_body B_t + Σ_k a_kᵀ (z_k/s_k) a_k) Δx = r

whose sparsity pattern is that of the mesh (:func:`~.problem.kkt_pattern`),
whatever the sources, the formulation or λ. Fixed variables become identity
rows, which keeps the pattern. One symbolic Cholesky analysis
(:class:`~.cholesky.SymbolicCholesky`) therefore serves every iteration of
every solve on a mesh; an iteration costs one numeric factorization, three to
five triangular solves (predictor, corrector, up to two centrality correctors,
iterative refinement of the final direction) and O(n) per-cone work done by the
compiled kernels of :mod:`._soc_kernels`. The factorization backend is MKL
PARDISO when installed, else CHOLMOD (see :mod:`.cholesky`).

``[W_t⁻²]_body = (I + 2 w̄₁w̄₁ᵀ)/η²`` (NT scaling point ``w̄``, scale ``η``), so the
3×3 clique of triangle t is ``(B_tᵀB_t + 2 (B_tᵀw̄₁)(B_tᵀw̄₁)ᵀ)/η²``: ``B_tᵀB_t`` is
computed once per problem and each iteration adds a rank-one term.

Residuals, gap and the stopping rule follow Clarabel's definitions (infinity
norms, relative to ``max(1, ‖b‖ + ‖x‖ + ‖s‖)`` and ``max(1, ‖q‖ + ‖x‖ + ‖z‖)``;
gap ``|pcost − dcost|``, absolute or relative to ``max(1, min(|pcost|, |dcost|))``),
evaluated on the problem with the fixed variables eliminated; convergence also
needs the dual residual below ``tol`` relative to ``max(1, ‖q‖ + ‖x‖)`` alone, so
that a dual blown up along a direction that ``Aᵀ`` cancels cannot hide it. Where
rounding stops the iterations after the best iterate came within 100 × ``tol``,
that iterate is returned as ``"almost_optimal"``.

Cone data are stored "structure of arrays": an SOC(3) vector field over k cones
is a (3, k) array (row 0 the heads), contiguous per component for the kernels
and the remaining NumPy operations.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from functools import partial

import numpy as np
import scipy.sparse as sp
from threadpoolctl import threadpool_limits

from ..errors import SolverError
from ..linalg import NotPositiveDefiniteError, SymbolicCholesky
from . import _soc_kernels as _kern
from .problem import BackendResult, ConicProblem

__all__ = ["InteriorPointSolver", "warm_up"]

# Fraction of the step to the boundary of the cone that is taken (CVXOPT's STEP).
_STEP = 0.99
# Mehrotra's centering exponent.
_SIGMA_EXP = 3
# Proportional static regularization of the diagonal, K_ii (1 + δ), undone by iterative refinement.
_STATIC_REG = 1e-12
# Relative tolerance of the infeasibility certificates (Clarabel's tol_infeas_rel).
_TOL_INFEAS = 1e-8
# Iterative refinement of the reduced Newton solves: at most this many steps.
_MAX_REFINE = 4
# ... until the residual of the reduced system is below this fraction of the dual-residual tolerance.
_REFINE_FRACTION = 0.1
# Once the gap is below this many times tol, refinement also aims at |xᵀr_x| ≤ 0.1·tol·max(1, |cost|): the gap
# contains xᵀr_x summed over n variables, and an ∞-norm residual far below tol left a gap floor of 5e-8 on
# dragon_20k's QGDF (n = 10K; 26 iterations ending "almost_optimal" → 15 "optimal"). Only in the end game:
# from the first iteration it cost bimba's QCQP-Hessian 21 more refinement solves (+10 %); from 100·tol, 7 and
# no measurable time.
_GAP_AWARE_BELOW = 100.0
# Separate primal and dual step lengths when P is None (measured: 20 → 18 iterations on spot's QCLP).
_SEPARATE_STEPS = True
# Gondzio's centrality correctors per iteration (measured on bimba's QCLP: 24 iterations without, 18 with 2,
# 18 with 4); each costs one triangular solve pair and no factorization.
_MAX_CORRECTORS = 2
# Corrector target: complementarity eigenvalues into [β_min σμ, β_max σμ] at the trial step min(1, a·α + b).
_BETA_MIN, _BETA_MAX = 0.1, 10.0
_GZ_A, _GZ_B = 1.5, 0.1
# Weighted correctors (Colombo & Gondzio, "Further development of multiple centrality correctors for interior
# point methods", 2008): a corrector that shortens the step at full weight is tried at these smaller weights
# (no extra solve) before giving up. Measured: 783 → 766 iterations over 7 meshes × 8 formulations, 119 → 115
# on spot/bimba/armadillo/horse (QCLP, QCQP-Hessian), 23 → 22 on a 278K-face bunny.
_CORRECTOR_WEIGHTS = (1.0, 0.5, 0.25)
# When the iterations end in numerical trouble, a stall or max_iter, the best iterate is returned as
# "almost_optimal" if its residuals and gap are below _REDUCED_FACTOR × tol (1e-6 at the default tol; Clarabel's
# reduced tolerances, 1e-4 and 5e-5, let through a field 5× off on a sliver mesh whose dual residual was hidden by
# ‖z‖ ≈ 1e7 in its scale). Seen on Thingi10K slivers: gap 1.6e-8, dual residual 1.5e-9, then rounding takes over.
_REDUCED_FACTOR = 100.0
# ... and iterating stops when the best iterate, meeting them, has not been improved on for this many iterations
# (seen: the dual residual stuck at 3–8e-8 by rounding while μ underflows, up to max_iter).
_STALL_ITERATIONS = 10
# Starting point: "cvxopt" (z = A x − b shifted into the cone), "mehrotra" (least-norm dual z = A y with
# Aᵀz = −q − Px, one uniform shift of s and of z, then balancing) or "interior" (x scaled towards x_F so that s
# is strictly feasible without a shift, the same least-norm z shifted cone by cone, no balancing; falls back to
# "mehrotra" when x_F is not strictly feasible). Measured on bimba: QCLP 18 (cvxopt) → 17 (mehrotra) → 15
# (interior) iterations; QCQP-Hessian 25 (y from the P + AᵀA factor) → 19 (mehrotra with y from the P-free
# system AᵀA y = …, one extra factorization) → 16 (interior). Over 7 meshes × 8 formulations (spot, fandisk,
# bunny_7k, kitten, camelhead, fertility, dragon_20k) "interior" took 783 iterations against 913, never more.
_INIT = "interior"
# "interior": fraction of the largest feasible step from x_F towards the least-squares x that is taken.
_INTERIOR_FRACTION = 0.9
# Mehrotra's shift: 1.5× the most negative eigenvalue (per cone for the "interior" dual).
_SHIFT_FACTOR = 1.5
# "interior": every dual cone's margin (head − ‖body‖) at least this fraction of the mean head (1e-3: the same
# iteration counts on spot/bimba/horse/armadillo, 1e-6 too; 1e-2 one fewer on two of them).
_DUAL_FLOOR = 1e-2


# ---------------------------------------------------------------------------------------------------------------
# Second-order cone SOC(3) algebra, vectorized over cones; (3, k) arrays, row 0 = heads.
# ---------------------------------------------------------------------------------------------------------------


def _soc_max_step(u: np.ndarray, du: np.ndarray) -> float:
    """Largest ``α`` with ``u + α du`` in SOC(3) for every cone (``inf`` when unbounded); ``u`` interior."""
    return _kern.max_step_soc(np.ascontiguousarray(u, dtype=np.float64), np.ascontiguousarray(du, dtype=np.float64))


def _max_step(u_c: np.ndarray, u_l: np.ndarray, du_c: np.ndarray, du_l: np.ndarray) -> float:
    """Largest ``α`` with ``(u_c, u_l) + α (du_c, du_l)`` in K (``inf`` when unbounded)."""
    a = _kern.max_step_soc(u_c, du_c)
    if u_l.size:
        a = min(a, _kern.max_step_lp(u_l, du_l))
    return a


class _SocScaling:
    """Nesterov–Todd scaling ``W = η W̄`` of SOC(3) pairs (s, z), vectorized (CVXOPT's formulas).

    ``W̄ = [[w₀, w₁ᵀ], [w₁, I + w₁w₁ᵀ/(1 + w₀)]]`` with ``w̄ᵀJw̄ = 1`` (``J = diag(1, −1, −1)``);
    ``W z = W⁻¹ s = λ``; ``W⁻² = (2 v vᵀ − J)/η²`` with ``v = J w̄``. The loops are the compiled
    kernels of :mod:`._soc_kernels`.
    """

    def __init__(self, s: np.ndarray, z: np.ndarray):
        k = s.shape[1]
        self.w = np.empty((3, k))
        self.eta = np.empty(k)
        self.inv_eta2 = np.empty(k)
        self.lam = np.empty((3, k))
        _kern.nt_scaling(s, z, self.w, self.eta, self.inv_eta2, self.lam)

    def apply(self, v: np.ndarray) -> np.ndarray:
        """``W v``."""
        out = np.empty_like(v)
        _kern.apply_w(self.w, self.eta, v, 1.0, out)
        return out

    def apply_inv(self, v: np.ndarray) -> np.ndarray:
        """``W⁻¹ v``."""
        out = np.empty_like(v)
        _kern.apply_w(self.w, self.eta, v, -1.0, out)
        return out

    def apply_inv2(self, v: np.ndarray) -> np.ndarray:
        """``W⁻² v = (2 v̂ (v̂ᵀv) − J v)/η²`` with ``v̂ = J w̄``."""
        out = np.empty_like(v)
        _kern.apply_inv2(self.w, self.inv_eta2, v, out)
        return out

    def body_to_inv2(self, g: np.ndarray) -> np.ndarray:
        """``W⁻² (0, −g)`` for a (2, k) body field ``g`` (that is ``W⁻² A Δx`` with ``g = B Δx``)."""
        w = self.w
        a = 2.0 * (w[1] * g[0] + w[2] * g[1])
        return np.stack([a * w[0], -g[0] - a * w[1], -g[1] - a * w[2]]) * self.inv_eta2


def _identity_scaling(k: int) -> _SocScaling:
    e = np.zeros((3, k))
    e[0] = 1.0
    return _SocScaling(e, e)


# ---------------------------------------------------------------------------------------------------------------
# Per-problem data
# ---------------------------------------------------------------------------------------------------------------

# local (a, b) index pairs of the 6 lower-triangle entries of a 3×3 clique
_CLIQUE_A = np.array([0, 1, 2, 1, 2, 2])
_CLIQUE_B = np.array([0, 1, 2, 0, 0, 1])


class _PatternMismatch(Exception):
    pass


def problem_pattern(problem: ConicProblem) -> sp.csc_matrix:
    """Sparsity pattern (ones, both triangles, full diagonal) of every Newton matrix of one problem.

    Parameters
    ----------
    problem : ConicProblem

    Returns
    -------
    (n, n) scipy.sparse.csc_matrix
    """
    n = problem.n
    cv, iv = np.asarray(problem.cone_vertices), np.asarray(problem.ineq_vertices)
    r = [np.arange(n), np.repeat(cv, 3, axis=1).ravel(), np.repeat(iv, 2, axis=1).ravel()]
    c = [np.arange(n), np.tile(cv, (1, 3)).ravel(), np.tile(iv, (1, 2)).ravel()]
    if problem.P is not None:
        Pc = sp.coo_matrix(problem.P)
        r.append(Pc.row)
        c.append(Pc.col)
    rows, cols = np.concatenate(r).astype(np.int64), np.concatenate(c).astype(np.int64)
    S = sp.csc_matrix((np.ones(rows.size), (rows, cols)), shape=(n, n))
    S.data[:] = 1.0
    return S


class _Prepared:
    """Everything about one problem that does not change across iterations."""

    def __init__(self, problem: ConicProblem, chol: SymbolicCholesky):
        n = int(problem.n)
        if n != chol.n:
            raise ValueError(f"problem has {n} variables but the solver was built for {chol.n} (another mesh?)")
        self.n = n
        self.fixed = np.asarray(problem.fixed_mask, dtype=bool).copy()
        self.x_fixed = np.where(self.fixed, np.asarray(problem.fixed_values, dtype=np.float64), 0.0)
        cv = np.asarray(problem.cone_vertices, dtype=np.int64).reshape(-1, 3)
        Bt = np.asarray(problem.cone_blocks, dtype=np.float64).reshape(-1, 2, 3)
        iv = np.asarray(problem.ineq_vertices, dtype=np.int64).reshape(-1, 2)
        ia = np.asarray(problem.ineq_coeffs, dtype=np.float64).reshape(-1, 2)
        self.k, self.p = cv.shape[0], iv.shape[0]
        k, p = self.k, self.p
        self.nu = k + p  # barrier degree
        self.P = None if problem.P is None else sp.csr_matrix(problem.P, dtype=np.float64)
        self.q = np.asarray(problem.q, dtype=np.float64)

        # Assembly plan first: a problem that does not fit the pattern is detected before any other work.
        nnz = chol.nnz
        try:
            cone_pos = chol.positions(cv[:, _CLIQUE_A].T.ravel(), cv[:, _CLIQUE_B].T.ravel())  # (6·k,) clique-major
            lp_pos = chol.positions(iv[:, [0, 1, 1]].T.ravel(), iv[:, [0, 1, 0]].T.ravel())
            Pl = sp.tril(self.P, format="coo") if self.P is not None else None
            P_pos = chol.positions(Pl.row, Pl.col) if Pl is not None else None
        except ValueError as exc:
            raise _PatternMismatch(str(exc)) from None
        self.base = np.zeros(nnz)
        if Pl is not None:
            self.base += np.bincount(P_pos, weights=Pl.data, minlength=nnz)

        # Cone blocks in SoA order for the kernels: B[:, :, t] is B_t.
        self.B = np.ascontiguousarray(Bt.transpose(1, 2, 0))  # (2, 3, k)
        self.cv = np.ascontiguousarray(cv)
        self.cone_pos = np.ascontiguousarray(cone_pos)
        self.lp_pos = np.ascontiguousarray(lp_pos)
        self.L = sp.csr_matrix((ia.ravel(), (np.repeat(np.arange(p), 2), iv.ravel())), shape=(p, n))
        self.LT = self.L.T.tocsr()
        self.rhs = np.asarray(problem.ineq_rhs, dtype=np.float64)

        # Clique constants: B_tᵀB_t (6, k) and a_i a_j (3, p); a repeated vertex gets its cross term twice.
        B = self.B
        self.BtB6 = np.stack([B[0, a] * B[0, b] + B[1, a] * B[1, b] for a, b in zip(_CLIQUE_A, _CLIQUE_B, strict=True)])
        same = np.where(iv[:, 0] == iv[:, 1], 2.0, 1.0)
        self.lp_coef = np.stack([ia[:, 0] ** 2, ia[:, 1] ** 2, ia[:, 0] * ia[:, 1] * same])

        # A free variable that nothing constrains or couples is either free to go to ±∞ or irrelevant.
        touched = np.zeros(n, dtype=bool)
        touched[cv.ravel()] = True
        touched[iv[ia != 0]] = True
        if self.P is not None:
            touched |= np.asarray(abs(self.P).sum(axis=1)).ravel() > 0
        loose = ~self.fixed & ~touched
        self.unbounded_var = -1
        if loose.any():
            bad = np.flatnonzero(loose & (self.q != 0))
            if bad.size:
                self.unbounded_var = int(bad[0])
            self.fixed |= loose  # q_i = 0: any value is optimal; keep 0
        self.free = ~self.fixed

        # Constants of the reduced problem: q̃ = q_f + P_fF x_F, b̃ = b − A_F x_F, const = objective of x_F.
        self.Px_fixed = self.P @ self.x_fixed if self.P is not None else np.zeros(n)
        self.qt_free = (self.q + self.Px_fixed)[self.free]
        self.const = float(self.q @ self.x_fixed) + 0.5 * float(self.x_fixed @ self.Px_fixed)
        self.cone_shift = self.Bx(self.x_fixed)  # b̃ body = +B x_F (A body is −B)
        self.lp_b = self.rhs - self.L @ self.x_fixed
        self.norm_b = max(
            1.0 if k else 0.0,
            float(np.abs(self.cone_shift).max()) if k else 0.0,
            float(np.abs(self.lp_b).max()) if p else 0.0,
        )
        self.norm_q = float(np.abs(self.qt_free).max()) if self.qt_free.size else 0.0

        # Fixed variables: rows and columns replaced by identity rows.
        r = chol.indices.astype(np.int64)
        c = np.repeat(np.arange(n), np.diff(chol.indptr))
        self.keep = (self.free[r] & self.free[c]).astype(np.float64)
        self.fixed_diag = chol.diag_positions[self.fixed]
        self.diag_pos = chol.diag_positions
        self.nnz = nnz

    # --- products with the constraint matrix (A x = (0, −B x) on cones, a·x on inequalities) ---
    def Bx(self, x: np.ndarray) -> np.ndarray:
        """(2, k): ``B_t x_t`` for every cone."""
        out = np.empty((2, self.k))
        _kern.gather(self.B, self.cv, x, out)
        return out

    def ax(self, x: np.ndarray) -> np.ndarray:
        """(p,): ``a_k · x`` for every inequality."""
        return self.L @ x

    def At(self, zbody: np.ndarray, zl: np.ndarray) -> np.ndarray:
        """``Aᵀz`` (n,) with fixed entries set to 0; ``zbody`` (2, k) are the cone bodies."""
        out = self.LT @ zl if self.p else np.zeros(self.n)
        if self.k:
            _kern.scatter(self.B, self.cv, zbody, -1.0, out)
        out[self.fixed] = 0.0
        return out

    def Pmul(self, x: np.ndarray) -> np.ndarray:
        return self.P @ x if self.P is not None else np.zeros(self.n)

    def kkt_mul(self, v: np.ndarray, sc: _SocScaling | None, lp_w: np.ndarray, with_P: bool = True) -> np.ndarray:
        """``(P + AᵀW⁻²A) v`` (without P if not ``with_P``) on the free variables, ``v`` on the fixed ones:
        the operator, unregularized."""
        out = self.Pmul(v) if with_P else np.zeros(self.n)
        if self.k:
            _kern.kkt_cones(self.B, self.cv, sc.w, sc.inv_eta2, v, out)
        if self.p:
            out += self.LT @ (lp_w * self.ax(v))
        out[self.fixed] = v[self.fixed]
        return out

    def assemble(self, sc: _SocScaling | None, lp_w: np.ndarray, with_P: bool = True) -> np.ndarray:
        """Lower-triangle data of ``P + AᵀW⁻²A`` (``AᵀW⁻²A`` if not ``with_P``), identity rows for fixed
        variables, aligned with the pattern."""
        data = self.base.copy() if with_P else np.zeros(self.nnz)
        if self.k:
            _kern.assemble_cones(self.B, self.BtB6, sc.w, sc.inv_eta2, self.cone_pos, data)
        if self.p:
            _kern.scatter_add((self.lp_coef * lp_w).ravel(), self.lp_pos, data)
        data *= self.keep
        data[self.fixed_diag] = 1.0
        return data


# ---------------------------------------------------------------------------------------------------------------
# The solver
# ---------------------------------------------------------------------------------------------------------------

_MESSAGES = {
    "max_iterations": "no convergence within max_iter iterations",
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
    pattern : (n, n) scipy.sparse matrix
        :func:`~cvxgeodesic.solvers.problem.kkt_pattern` of the mesh.
    backend : {"auto", "cholmod", "scipy"}
        Sparse Cholesky backend, see :class:`~cvxgeodesic.solvers.cholesky.SymbolicCholesky`.
    ordering : str
        CHOLMOD fill-reducing ordering.

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
    >>> from cvxgeodesic.formulations import MeshOperators, build_problem
    >>> from cvxgeodesic.solvers.problem import kkt_pattern
    >>> m = icosphere(2); ops = MeshOperators(m)
    >>> ipm = InteriorPointSolver(kkt_pattern(m.n_vertices, m.F, m.edges))
    >>> res = ipm.solve(build_problem(ops, np.array([0]), "qclp", 0.0))
    >>> res.status, ipm.n_analyses
    ('optimal', 1)
    """

    def __init__(self, pattern, *, backend: str = "auto", ordering: str = "metis"):
        self._backend = backend
        self._ordering = ordering
        self.cholesky = SymbolicCholesky(pattern, backend=backend, ordering=ordering)
        self.n = self.cholesky.n
        self.n_analyses = self.cholesky.n_analyses

    def _prepare(self, problem: ConicProblem) -> _Prepared:
        try:
            return _Prepared(problem, self.cholesky)
        except _PatternMismatch:
            old = self.cholesky
            union = old.matrix(np.ones(old.nnz)) + problem_pattern(problem)
            self.cholesky = SymbolicCholesky(union, backend=old.backend, ordering=self._ordering)
            self.n_analyses += self.cholesky.n_analyses
            return _Prepared(problem, self.cholesky)

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
            timing breakdown in seconds (``setup_time``, ``assembly_time``,
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
            its iteration.

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
        with threadpool_limits(limits):
            return self._solve(problem, tol=tol, max_iter=max_iter, callback=callback)

    def _solve(self, problem: ConicProblem, *, tol: float, max_iter: int, callback) -> BackendResult:
        t_start = time.perf_counter()
        analyses_before = self.n_analyses
        pr = self._prepare(problem)
        chol = self.cholesky
        timers = {"setup_time": time.perf_counter() - t_start, "assembly_time": 0.0, "factor_time": 0.0,
                  "linear_solve_time": 0.0}
        counters = {"refinement_steps": 0, "correctors": 0, "correctors_accepted": 0}
        k, p = pr.k, pr.p
        free, fixed = pr.free, pr.fixed
        info: dict = {"iterations": 0}

        def fail(status: str, extra_msg: str = "") -> SolverError:
            total = time.perf_counter() - t_start
            info.update(timers, status=status, solve_time=total, **counters)
            msg = _MESSAGES[status] + (f": {extra_msg}" if extra_msg else "")
            if status == "max_iterations":
                msg = f"no convergence within max_iter={max_iter} iterations"
            return SolverError(msg, solver="ipm", status=status, info=info)

        if pr.unbounded_var >= 0:
            raise fail("dual_infeasible", f"variable {pr.unbounded_var} has a linear cost and no constraint")

        def factorize(data: np.ndarray):
            # in place: the assembled data is not used again (refinement applies the operator itself)
            t0 = time.perf_counter()
            data[pr.diag_pos] *= 1.0 + _STATIC_REG
            try:
                return chol.factorize(data)
            finally:
                timers["factor_time"] += time.perf_counter() - t0

        def lsolve(f, r: np.ndarray) -> np.ndarray:
            t0 = time.perf_counter()
            try:
                if not np.isfinite(r).all():
                    raise fail("numerical_error", "non-finite right-hand side")
                out = f(r)
            except NotPositiveDefiniteError as exc:  # PARDISO's guard: a non-finite solve
                raise fail("numerical_error", str(exc)) from exc
            finally:
                timers["linear_solve_time"] += time.perf_counter() - t0
            out[fixed] = 0.0
            return out

        def solve_refined(f, rhs, sc, lp_w, target, with_P=True):
            """Solve with iterative refinement until ‖rhs − K dx‖∞ ≤ target (or no more progress)."""
            dx = lsolve(f, rhs)
            prev = np.inf
            for _ in range(_MAX_REFINE):
                res = rhs - pr.kkt_mul(dx, sc, lp_w, with_P)
                res[fixed] = 0.0
                rn = float(np.abs(res).max())
                if rn <= target or rn >= 0.5 * prev:
                    break
                prev = rn
                dx += lsolve(f, res)
                counters["refinement_steps"] += 1
            return dx

        # ---- starting point: x from the W = I system, then s and z (see _INIT) ----
        t0 = time.perf_counter()
        sc0 = _identity_scaling(k)
        w0 = np.ones(p)
        data0 = pr.assemble(sc0, w0)
        timers["assembly_time"] += time.perf_counter() - t0
        try:
            f0 = factorize(data0)
        except NotPositiveDefiniteError as exc:
            raise fail("numerical_error", "singular Newton matrix at the starting point") from exc
        bc = np.concatenate([np.ones((1, k)), pr.cone_shift])  # b̃ for the cones
        rhs0 = -(pr.q + pr.Px_fixed) + pr.At(bc[1:], pr.lp_b)  # −q̃ + A_fᵀb̃ with A body = −B
        rhs0[fixed] = 0.0
        x = solve_refined(f0, rhs0, sc0, w0, 1e-12 * max(1.0, float(np.abs(rhs0).max()))) + pr.x_fixed
        interior = _INIT == "interior" and (x_int := _interior_primal(pr, x)) is not None
        if interior:
            x = x_int
        s_c = np.concatenate([np.ones((1, k)), pr.Bx(x)])
        s_l = pr.lp_b - pr.ax(x - pr.x_fixed)
        y = None
        if _INIT in ("interior", "mehrotra"):
            # z = A y, the least-norm solution of A_fᵀz = −q̃ − P_ff x_f, which is scaled like the true dual,
            # unlike CVXOPT's z = A x − b (as large as the slacks, so the first iterations are spent shrinking a
            # huge duality gap). With a quadratic term the least-norm system (A_fᵀA_f without P) needs its own
            # factorization, and may be singular (a variable that only P couples): then CVXOPT's start is used.
            Pfx0 = pr.Pmul(x) - pr.Px_fixed
            rhs_y = -(pr.q + pr.Px_fixed + Pfx0)
            rhs_y[fixed] = 0.0
            target_y = 1e-12 * max(1e-300, float(np.abs(rhs_y).max()))
            f_y = f0
            if pr.P is not None:
                t0 = time.perf_counter()
                data_y = pr.assemble(sc0, w0, with_P=False)
                timers["assembly_time"] += time.perf_counter() - t0
                try:
                    f_y = factorize(data_y)
                except NotPositiveDefiniteError:
                    f_y = None
            if f_y is not None:
                try:
                    y = solve_refined(f_y, rhs_y, sc0, w0, target_y, with_P=pr.P is None)
                except SolverError:
                    y = None
        if y is not None:
            z_c = np.concatenate([np.zeros((1, k)), -pr.Bx(y)])  # z = A y (A body = −B)
            z_l = pr.ax(y)
            shifted = _dual_shift_per_cone(z_c, z_l) if interior else None
            if shifted is not None:
                z_c, z_l = shifted  # s is strictly interior already
            else:
                s_c, s_l, z_c, z_l = _mehrotra_shift(s_c, s_l, z_c, z_l)
        else:
            z_c, z_l = -s_c, -s_l
            s_c, s_l = _shift_into_cone(s_c, s_l)
            z_c, z_l = _shift_into_cone(z_c, z_l)

        # Without a quadratic term the primal and dual steps decouple (as in LP interior-point codes):
        # separate step lengths cut the iteration count on these highly degenerate problems.
        separate = pr.P is None and _SEPARATE_STEPS
        no_resid = _Residuals.zero(pr)  # correctors only change the complementarity right-hand side
        it = 0
        step = float("nan")
        small_steps = 0
        status = None
        best_it = {"merit": np.inf, "x": None, "info": None, "since": 0}
        while True:
            # ---- residuals, costs, convergence ----
            Px = pr.Pmul(x)
            Atz = pr.At(z_c[1:], z_l)
            rx = Px + pr.q + Atz
            rx[fixed] = 0.0
            Bx = pr.Bx(x)
            rzc = s_c.copy()
            rzc[0] -= 1.0
            rzc[1:] -= Bx
            ax = pr.ax(x)
            rzl = ax + s_l - pr.rhs
            xf = x[free]
            Pfx = (Px - pr.Px_fixed)[free] if pr.P is not None else np.zeros(xf.size)  # P_ff x_f
            xPffx = float(xf @ Pfx)
            qx = float(pr.qt_free @ xf)
            bz = float(z_c[0].sum() + (pr.cone_shift * z_c[1:]).sum()) + float(pr.lp_b @ z_l)
            pcost_r = 0.5 * xPffx + qx
            dcost_r = -0.5 * xPffx - bz
            pcost, dcost = pcost_r + pr.const, dcost_r + pr.const
            gap_abs = abs(pcost_r - dcost_r)
            gap_rel = gap_abs / max(1.0, min(abs(pcost), abs(dcost)))
            norm_x = float(np.abs(xf).max()) if xf.size else 0.0
            norm_s = max(_amax(s_c), _amax(s_l))
            norm_z = max(_amax(z_c), _amax(z_l))
            res_p = max(_amax(rzc), _amax(rzl)) / max(1.0, pr.norm_b + norm_x + norm_s)
            dual_scale = max(1.0, pr.norm_q + norm_x + norm_z)
            res_d = _amax(rx) / dual_scale
            # the same residual without ‖z‖ in its scale: a dual blown up along a direction that Aᵀ cancels
            # (edge bounds that are equalities in disguise: ‖z‖ ≈ 1e13, |r_x| ≈ 0.9 with res_d ≈ 1e-12)
            # must not pass for convergence
            res_d_plain = _amax(rx) / max(1.0, pr.norm_q + norm_x)
            mu = (float((s_c * z_c).sum()) + float(s_l @ z_l)) / max(pr.nu, 1)
            info = {
                "iterations": it, "pcost": pcost, "dcost": dcost, "gap_abs": gap_abs, "gap_rel": gap_rel,
                "res_primal": res_p, "res_dual": res_d, "res_dual_plain": res_d_plain, "mu": mu, "step": step,
                "time": time.perf_counter() - t_start,
            }
            if callback is not None:
                callback(it, dict(info))
            if not np.isfinite(res_p + res_d + gap_abs + mu):
                status = "numerical_error"
                break
            if res_p < tol and res_d < tol and res_d_plain < tol and (gap_abs < tol or gap_rel < tol):
                status = "optimal"
                break
            merit = max(res_p, res_d, min(gap_abs, gap_rel))
            if merit < best_it["merit"]:
                best_it.update(merit=merit, x=x.copy(), info=dict(info), since=0)
            else:
                best_it["since"] += 1
                # no better iterate for a while once the reduced tolerances hold: rounding has the last word
                if best_it["since"] >= _STALL_ITERATIONS and _almost(best_it["info"], tol):
                    status = "stalled"
                    break
            # Infeasibility certificates (Clarabel's tests on the current iterate): for an infeasible problem
            # z diverges along y with A_fᵀy = 0, b̃ᵀy < 0; for an unbounded one x_f diverges along d with
            # P_ff d = 0, −A_f d ∈ K, q̃ᵀd < 0, while the other terms stay bounded.
            if bz < 0 and _amax(Atz) < -_TOL_INFEAS * bz:
                status = "primal_infeasible"
                break
            if qx < 0:
                bd = Bx - pr.cone_shift  # B x_f
                ad = ax - (pr.rhs - pr.lp_b)  # a·x_f
                viol = max(_amax(np.sqrt(bd[0] ** 2 + bd[1] ** 2)), _amax(np.maximum(ad, 0.0)))
                if _amax(Pfx) < -_TOL_INFEAS * qx and viol < -_TOL_INFEAS * qx:
                    status = "dual_infeasible"
                    break
            if it >= max_iter:
                status = "max_iterations"
                break

            try:
                # ---- NT scaling and the reduced Newton matrix ----
                sc = _SocScaling(s_c, z_c) if k else _identity_scaling(0)
                lp_lam = np.sqrt(s_l * z_l)
                lp_w = z_l / s_l  # W⁻² of the inequalities
                lp_winv = np.sqrt(lp_w)  # W⁻¹
                t0 = time.perf_counter()
                data = pr.assemble(sc, lp_w)
                timers["assembly_time"] += time.perf_counter() - t0
                try:
                    f = factorize(data)
                except NotPositiveDefiniteError:
                    status = "numerical_error"
                    break
                # The solve error becomes the next dual residual: refine it below what the stopping test needs.
                target = _REFINE_FRACTION * tol * dual_scale
                if min(gap_abs, gap_rel) < _GAP_AWARE_BELOW * tol:
                    target = min(target, _REFINE_FRACTION * tol * max(1.0, min(abs(pcost), abs(dcost)))
                                 / max(1.0, float(np.abs(xf).sum())))

                def lin(rhs, f=f):
                    return lsolve(f, rhs)

                # ---- predictor (affine scaling): d_s = −λ∘λ, so W⁻¹(λ \ d_s) = −W⁻¹λ = −z ----
                resid = _Residuals(pr, sc, lp_w, rx, rzc, rzl)
                dx_a, dsc_a, dsl_a, dzc_a, dzl_a, _ = _newton(pr, lin, sc, lp_w, resid, -z_c, -z_l)
                step_s, step_z = partial(_max_step, s_c, s_l), partial(_max_step, z_c, z_l)
                ap_aff = min(1.0, step_s(dsc_a, dsl_a))
                ad_aff = min(1.0, step_z(dzc_a, dzl_a))
                if not separate:
                    ap_aff = ad_aff = min(ap_aff, ad_aff)
                gap = mu * max(pr.nu, 1)
                sz_aff = float(((s_c + ap_aff * dsc_a) * (z_c + ad_aff * dzc_a)).sum()) + float(
                    (s_l + ap_aff * dsl_a) @ (z_l + ad_aff * dzl_a))
                sigma = min(1.0, max(0.0, sz_aff / gap if gap > 0 else 0.0)) ** _SIGMA_EXP

                # ---- combined step: d_s = −λ∘λ − (W⁻¹Δs_a)∘(WΔz_a) + σμe ----
                wu_c = np.empty((3, k))
                _kern.mehrotra_cones(sc.w, sc.eta, sc.lam, dsc_a, dzc_a, z_c, sigma * mu, wu_c)
                wu_l = -z_l - lp_winv * (dsl_a * dzl_a - sigma * mu) / lp_lam
                dx, dsc, dsl, dzc, dzl, rhs_tot = _newton(pr, lin, sc, lp_w, resid, wu_c, wu_l)
                step_p = min(1.0, _STEP * step_s(dsc, dsl))
                step_d = min(1.0, _STEP * step_z(dzc, dzl))
                if not separate:
                    step_p = step_d = min(step_p, step_d)
                # ---- Gondzio's multiple centrality correctors: cheap extra solves with the same factor ----
                for _ in range(_MAX_CORRECTORS):
                    if min(step_p, step_d) >= 0.995:
                        break
                    tp, td = min(1.0, _GZ_A * step_p + _GZ_B), min(1.0, _GZ_A * step_d + _GZ_B)
                    lo, hi = _BETA_MIN * sigma * mu, _BETA_MAX * sigma * mu
                    wu_c2 = np.empty((3, k))
                    _kern.gondzio_cones(sc.w, sc.eta, sc.lam, s_c, dsc, tp, z_c, dzc, td, lo, hi, wu_c2)
                    vl = (s_l + tp * dsl) * (z_l + td * dzl)
                    wu_l2 = lp_winv * np.maximum(np.clip(vl, lo, hi) - vl, -hi) / lp_lam
                    cx, csc_, csl, czc, czl, crhs = _newton(pr, lin, sc, lp_w, no_resid, wu_c2, wu_l2)
                    counters["correctors"] += 1
                    best = None
                    for wgt in _CORRECTOR_WEIGHTS:
                        nsc, nsl, nzc, nzl = dsc + wgt * csc_, dsl + wgt * csl, dzc + wgt * czc, dzl + wgt * czl
                        np_ = min(1.0, _STEP * step_s(nsc, nsl))
                        nd_ = min(1.0, _STEP * step_z(nzc, nzl))
                        if not separate:
                            np_ = nd_ = min(np_, nd_)
                        if best is None or min(np_, nd_) > best[0]:
                            best = (min(np_, nd_), wgt, np_, nd_, nsc, nsl, nzc, nzl)
                        if min(np_, nd_) >= min(step_p, step_d) + 0.01:
                            break  # the largest weight that helps
                    if best[0] < min(step_p, step_d) + 0.01:
                        break
                    _, wgt, step_p, step_d, dsc, dsl, dzc, dzl = best
                    dx = dx + wgt * cx
                    rhs_tot = rhs_tot + wgt * crhs
                    counters["correctors_accepted"] += 1
                # ---- iterative refinement of the final direction (its Δx error becomes the next dual residual);
                # every direction above is linear in Δx, so one correction δ updates them all ----
                refined = False
                prev = np.inf
                for _ in range(_MAX_REFINE):
                    res_r = rhs_tot - pr.kkt_mul(dx, sc, lp_w)
                    res_r[fixed] = 0.0
                    rn = _amax(res_r)
                    if rn <= target or rn >= 0.5 * prev:
                        break
                    prev = rn
                    delta = lsolve(f, res_r)
                    counters["refinement_steps"] += 1
                    refined = True
                    dx += delta
                    g = pr.Bx(delta)
                    dzc = dzc + sc.body_to_inv2(g)
                    dsc = dsc.copy()
                    dsc[1:] += g
                    adl = pr.ax(delta)
                    dzl = dzl + lp_w * adl
                    dsl = dsl - adl
                if refined:
                    step_p = min(1.0, _STEP * step_s(dsc, dsl))
                    step_d = min(1.0, _STEP * step_z(dzc, dzl))
                    if not separate:
                        step_p = step_d = min(step_p, step_d)
                step = min(step_p, step_d)
                x = x + step_p * dx
                s_c = s_c + step_p * dsc
                s_l = s_l + step_p * dsl
                z_c = z_c + step_d * dzc
                z_l = z_l + step_d * dzl
                it += 1
                small_steps = small_steps + 1 if step < 1e-8 else 0
                if small_steps >= 3:
                    status = "stalled"
                    break
            except SolverError as exc:  # a non-finite solve: keep the best iterate (below)
                if exc.status != "numerical_error":
                    raise
                status = "numerical_error"
                break

        stopped = None
        if status != "optimal":
            certificate = status in ("primal_infeasible", "dual_infeasible")
            if certificate or best_it["x"] is None or not _almost(best_it["info"], tol):
                raise fail(status)
            # numerical trouble, a stall or max_iter after an iterate within the reduced tolerances
            stopped, status = status, "almost_optimal"
            x, info = best_it["x"], best_it["info"]
        total = time.perf_counter() - t_start
        extra = {
            **timers,
            "other_time": total - sum(timers.values()),
            "total_time": total,
            **counters,
            "analyze_time": chol.analyze_time,
            "new_analyses": self.n_analyses - analyses_before,
            "backend": chol.backend,
            "mu": info["mu"],
            "gap_abs": info["gap_abs"],
        }
        if stopped is not None:
            extra.update(stopped=stopped, best_iteration=info["iterations"])
        xout = x.copy()
        xout[np.asarray(problem.unreachable, dtype=bool)] = 0.0
        return BackendResult(
            x=xout,
            solver="ipm",
            status=status,
            iterations=it,
            solve_time=total,
            objective=problem.objective(xout),
            primal_residual=info["res_primal"],
            dual_residual=info["res_dual"],
            gap=info["gap_rel"],
            extra=extra,
        )


class _Residuals:
    """The parts of the Newton right-hand side that stay fixed during one iteration.

    With ``t = W⁻¹(λ \\ d_s) + W⁻² r_z`` the direction is
    ``(P + AᵀW⁻²A) Δx = −r_x − Aᵀt``, ``Δz = W⁻² A Δx + t``, ``Δs = −r_z − A Δx``;
    ``W⁻² r_z`` and ``−r_x − Aᵀ(W⁻² r_z)`` are computed once and shared by the
    predictor, the corrector and the centrality correctors (which have ``r = 0``).
    """

    def __init__(self, pr: _Prepared, sc: _SocScaling, lp_w, rx, rzc, rzl):
        self.rzc, self.rzl = rzc, rzl
        self.wrc = sc.apply_inv2(rzc)
        self.wrl = lp_w * rzl
        self.rhs = -rx - pr.At(self.wrc[1:], self.wrl)

    @staticmethod
    def zero(pr: _Prepared) -> _Residuals:
        out = _Residuals.__new__(_Residuals)
        out.rzc = out.wrc = np.zeros((3, pr.k))
        out.rzl = out.wrl = np.zeros(pr.p)
        out.rhs = np.zeros(pr.n)
        return out


def _newton(pr: _Prepared, lin, sc: _SocScaling, lp_w, res: _Residuals, wu_c, wu_l):
    """Direction for ``P Δx + AᵀΔz = −r_x``, ``A Δx + Δs = −r_z``, ``λ∘(WΔz + W⁻¹Δs) = d_s``.

    ``wu = W⁻¹(λ \\ d_s)`` is given; ``lin(rhs)`` solves the reduced system (see :class:`_Residuals`).
    Returns ``Δx, Δs_cones, Δs_ineq, Δz_cones, Δz_ineq`` and the reduced right-hand side.
    """
    rhs = res.rhs - pr.At(wu_c[1:], wu_l)
    rhs[pr.fixed] = 0.0
    dx = lin(rhs)
    g = pr.Bx(dx)  # A Δx = (0, −g) on the cones
    dzc = np.empty((3, pr.k))
    dsc = np.empty((3, pr.k))
    _kern.newton_cones(g, sc.w, sc.inv_eta2, wu_c, res.wrc, res.rzc, dzc, dsc)
    adx = pr.ax(dx)
    dzl = lp_w * adx + wu_l + res.wrl
    dsl = -res.rzl - adx
    return dx, dsc, dsl, dzc, dzl, rhs


def _almost(info: dict, tol: float) -> bool:
    """The reduced tolerances on one iterate's ``info``: residuals and gap below ``_REDUCED_FACTOR · tol``, and
    the dual residual also relative to ``max(1, ‖q‖ + ‖x‖)`` alone (``res_dual_plain``)."""
    red = _REDUCED_FACTOR * tol
    return (info["res_primal"] < red and info["res_dual"] < red and info["res_dual_plain"] < red
            and min(info["gap_abs"], info["gap_rel"]) < red)


def _amax(a: np.ndarray) -> float:
    return float(np.abs(a).max()) if a.size else 0.0


def _min_eigenvalue(uc: np.ndarray, ul: np.ndarray) -> float:
    """Smallest eigenvalue of ``(uc, ul)`` in K (``head − ‖body‖`` per cone, the entries of ``ul``), ``inf``
    when empty."""
    m = np.inf
    if uc.shape[1]:
        m = min(m, float((uc[0] - np.sqrt(uc[1] ** 2 + uc[2] ** 2)).min()))
    if ul.size:
        m = min(m, float(ul.min()))
    return m


def _mehrotra_shift(s_c, s_l, z_c, z_l):
    """Mehrotra's (1992) starting-point heuristic adapted to SOC: shift both s and z into the
    interior by 1.5× their most negative eigenvalue, then add ½ sᵀz/Σ(heads of the other) to each."""
    out = []
    for uc, ul in ((s_c, s_l), (z_c, z_l)):
        d = max(-_SHIFT_FACTOR * _min_eigenvalue(uc, ul), 0.0)
        uc = uc.copy()
        uc[0] += d
        out.append((uc, ul + d))
    (s_c, s_l), (z_c, z_l) = out
    sz = float((s_c * z_c).sum()) + float(s_l @ z_l)
    heads_s = float(s_c[0].sum()) + float(s_l.sum())
    heads_z = float(z_c[0].sum()) + float(z_l.sum())
    if sz <= 0 or heads_s <= 0 or heads_z <= 0:  # degenerate data: fall back to a unit shift
        sz, heads_s, heads_z = 1.0, 1.0, 1.0
    ds, dz = 0.5 * sz / heads_z, 0.5 * sz / heads_s
    s_c = s_c.copy()
    z_c = z_c.copy()
    s_c[0] += ds
    z_c[0] += dz
    return s_c, s_l + ds, z_c, z_l + dz


def _interior_primal(pr: _Prepared, x: np.ndarray) -> np.ndarray | None:
    """``x_F + α (x − x_F)`` with ``α = min(1, 0.9 α_max)``, ``α_max`` the largest step from ``x_F`` (the fixed
    values, free part 0) that keeps ``s = b̃ − A x`` in K; ``None`` when ``x_F`` itself is not strictly feasible.

    The least-squares ``x`` of the ``W = I`` system is usually infeasible (here: a few one-ring bounds next to
    the source), and shifting ``s`` into the cone then makes the primal residual as large as that violation.
    On the mesh problems ``x_F`` (all distances 0 but the fixed ones) is strictly feasible, so the segment
    gives a strictly feasible point with zero primal residual.
    """
    k = pr.k
    s0_c = np.concatenate([np.ones((1, k)), pr.cone_shift])
    s0_l = pr.lp_b
    if _min_eigenvalue(s0_c, s0_l) <= 0:
        return None
    step = x - pr.x_fixed  # zero on the fixed variables
    ds_c = np.concatenate([np.zeros((1, k)), pr.Bx(step)])  # s body = B x = cone_shift + α B step
    alpha_max = _max_step(s0_c, s0_l, ds_c, -pr.ax(step))
    return pr.x_fixed + min(1.0, _INTERIOR_FRACTION * alpha_max) * step


def _dual_shift_per_cone(z_c: np.ndarray, z_l: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Mehrotra's shift applied cone by cone: each cone's head raised by 1.5× its own deficit ``‖body‖ − head``
    (the inequalities shifted together by 1.5× the most negative one), every margin then at least
    ``_DUAL_FLOOR`` × the mean head. ``None`` when ``z`` is zero.

    The dual of a mesh problem scales with the triangle areas; one uniform shift (Mehrotra's) sized by the
    largest cone overestimates the small cones' duals by orders of magnitude, and the first iterations go to
    shrinking that duality gap (bimba, QCQP-Hessian: starting gap 550 for an optimum of −3.4).
    """
    z_c = z_c.copy()
    body = np.sqrt(z_c[1] ** 2 + z_c[2] ** 2)
    z_c[0] += _SHIFT_FACTOR * np.maximum(body - z_c[0], 0.0)
    z_l = z_l + max(-_SHIFT_FACTOR * float(z_l.min()), 0.0) if z_l.size else z_l.copy()
    mean_head = (float(z_c[0].sum()) + float(z_l.sum())) / max(z_c.shape[1] + z_l.size, 1)
    if not (np.isfinite(mean_head) and mean_head > 0):
        return None
    floor = _DUAL_FLOOR * mean_head
    z_c[0] = np.maximum(z_c[0], body + floor)
    return z_c, np.maximum(z_l, floor)


def _shift_into_cone(uc: np.ndarray, ul: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """CVXOPT's initialization: ``u + (1 + α)e`` when ``u`` is not strictly inside (``α`` = −min eigenvalue)."""
    worst = -np.inf
    if uc.shape[1]:
        worst = max(worst, float(np.max(np.sqrt(uc[1] ** 2 + uc[2] ** 2) - uc[0])))
    if ul.size:
        worst = max(worst, float(np.max(-ul)))
    if worst >= -1e-8 * max(_amax(uc), _amax(ul), 1.0):
        uc = uc.copy()
        uc[0] += 1.0 + worst
        ul = ul + (1.0 + worst)
    return uc, ul


def warm_up() -> None:
    """Compile (first run after an install, about 10 s) or load (later, under a second) the solver's kernels.

    The first :meth:`InteriorPointSolver.solve` of a process does this by itself; call it beforehand to keep
    that one-time cost out of a timing. ``make setup`` runs it once so that the on-disk cache exists.
    """
    from ..formulations import MeshOperators, build_problem, smoothness_weight
    from ..mesh.generate import icosphere
    from .problem import kkt_pattern

    mesh = icosphere(1)
    ops = MeshOperators(mesh)
    for method in ("qclp", "lclp", "qcqp-hessian"):
        p = build_problem(ops, np.array([0]), method, smoothness_weight(mesh, 1.0))
        InteriorPointSolver(kkt_pattern(mesh.n_vertices, mesh.F, mesh.edges, p.P)).solve(p)
