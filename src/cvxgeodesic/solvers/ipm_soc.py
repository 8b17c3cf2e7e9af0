"""Structured primal-dual interior-point solver for the order-2 program (SOC(4) cones on face cliques).

Solves :class:`~cvxgeodesic.elements_p2.P2Problem`::

    minimize cᵀx   subject to   s_k = h_k − G_k x[dofs_k] ∈ SOC(4)   (every cone k),
                                E x = f,   x[fixed] = 0

with Nesterov–Todd scaling and Mehrotra's predictor–corrector (the scheme of CVXOPT's
``conelp``; written here from the textbook equations). Every cone touches the six P2 DOFs
of one face, so after eliminating ``Δs`` and ``Δz`` the Newton matrix is

    H = Σ_k G_kᵀ W_k⁻² G_k        (one 6 × 6 block per cone, summed per face clique)

whose sparsity pattern (the union of the face cliques) never changes: it is analyzed once
per mesh (:class:`~cvxgeodesic.linalg.SymbolicCholesky`) and only refactorized
numerically at each iteration, for every source and every cutting-plane round.

The few source equalities ``E x = f`` (one per edge at a source vertex) are kept as a
Schur complement ``E H⁻¹ Eᵀ`` (p × p dense, p = number of source-star edges), which needs
p extra triangular solves per iteration and keeps the pattern of ``H`` independent of the
sources. Fixed DOFs have zero columns in ``G`` and ``E`` and an identity row in ``H``.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from ..errors import SolverError
from ..linalg import NotPositiveDefiniteError, SymbolicCholesky
from ..linalg import pardiso as _pardiso
from . import _p2_kernels as _kern

_TRIL_R, _TRIL_C = (np.ascontiguousarray(i, dtype=np.int64) for i in np.tril_indices(6))
#: Iterative-refinement steps per Newton solve.
REFINE_STEPS = 3
#: The dual residual is accepted at this multiple of ``tol``: near the optimum Δz = W⁻²(…) magnifies rounding
#: by up to 1/μ and the dual residual stalls around 1e-7 (relative) while x has converged (measured on a flat
#: grid: x within 5e-8 of Clarabel's optimum, relative to max φ, when the gap was 2e-8 and the dual residual 1e-7).
DUAL_TOL_FACTOR = 1000.0
#: Static regularization of the Newton matrix, relative to each diagonal entry. Relative to the *largest* entry
#: (first version) it swamped the far-from-source rows, whose entries are ~1e10 smaller near the optimum, and
#: iterative refinement then gained only a factor 2.5 per step (spot stalled at a dual residual of 1e-2).
REG = 1e-13
#: Fraction of the step to the cone boundary that is taken.
STEP_FRACTION = 0.99
#: Separate primal and dual step lengths (no quadratic term: the updates decouple, as in LP codes). Measured
#: (2026-12-01, with the settings below) over spot, bunny_7k and the 25 flat cases of benchmarks/order2.py: 465
#: iterations against 470, the worst flat error 1.1e-6 against 3.5e-7; left off.
SEPARATE_STEPS = False
#: Gondzio's centrality correctors per iteration (each one Newton solve with the factor already computed).
#: Measured over the same 27 solves: 829 iterations without, 534 with 2, 470 with 4 (spot 48 → 26, bunny_7k
#: 48 → 27); the worst flat error 1.9e-6 without (needle strip of aspect 240, point source), 3.5e-7 with 4.
MAX_CORRECTORS = 4
#: Refine only the final direction (the predictor and the corrector terms unrefined): the same 48 iterations on
#: spot and bunny_7k without correctors, 276 PARDISO calls instead of 358 on spot.
REFINE_ONCE = True
#: Corrector target: complementarity eigenvalues into [BETA_MIN σμ, BETA_MAX σμ] at the trial step GZ_A α + GZ_B.
BETA_MIN, BETA_MAX, GZ_A, GZ_B = 0.1, 10.0, 1.5, 0.1
#: A corrector that shortens the step at full weight is tried at these weights (Colombo & Gondzio 2008).
CORRECTOR_WEIGHTS = (1.0, 0.5, 0.25)


#: Starting point: "guess" (the problem's guess field scaled into the cones' interior, so that the primal residual
#: is 0 from the start; the least-norm z shifted into the cones by 1.5 × its most negative eigenvalue and balanced by
#: ½ sᵀz / Σ heads of s; Mehrotra's start when the problem has no guess), "mehrotra" (least-squares x and least-norm
#: z, each shifted into the cones by 1.5 × its most negative eigenvalue, then balanced by ½ sᵀz / Σ heads; Mehrotra
#: 1992, as the order-1 solver's fallback) or "cvxopt" (both shifted by 1 + their most negative eigenvalue).
#: Measured (2026-12-01, source 0, iterations mehrotra → guess with the σ cap below): spot 25 → 18, bunny_7k 26 → 19,
#: bimba 39 → 22, lucy_20k and dragon_20k in docs/order2.md. Without the cap the guess alone: spot 21, bunny_7k 21,
#: bimba 28; the cap with Mehrotra's start: bimba 76. Earlier (over spot, bunny_7k and the 25 flat cases):
#: cvxopt 469 → mehrotra 436 iterations. Also tried from the guess: Mehrotra's shift of s as well (spot 24,
#: bunny_7k 27), a per-cone dual shift (23, 24), the perfectly centred z = μ s⁻¹ (22, 41).
START = "guess"
#: "guess": the largest θ ≤ 1 keeping every cone strictly inside is scaled by this (0.5: bimba 27, 0.99: 28, 0.9: 28
#: iterations without the σ cap; spot 21, 21, 20).
GUESS_FRACTION = 0.9
#: "guess": Mehrotra's centring parameter σ = (affine gap ratio)³ is capped at this. From a primal-feasible start the
#: tail converged linearly with σ ≈ 0.3 at steps of 0.95 (bimba: the gap ÷ 2.5 per iteration over 15 iterations);
#: measured iterations for caps 1 / 0.2 / 0.1 / 0.05: spot 21 / 20 / 18, bunny_7k 22 / 21 / 19, bimba 28 / – / 22 / 21.
SIGMA_CAP_GUESS = 0.1
#: PARDISO threads of the order-2 solver; None: the solve's thread policy (:mod:`cvxgeodesic._threads`). It was 1
#: (before the policy, on the shared 2-core machine, a spot solve took 63 ms with MKL's default threads and 9 ms
#: with one). Measured 2026-12-01 on bimba, quiet (load 0.5–1): one numeric factorization (92K DOFs, nnz(L) 5.0M)
#: 0.142 s with one thread, 0.087 s with two; one solve 11.9 / 7.3 ms; a whole order-2 solve 9.6–10.5 s / 7.7–9.3 s.
PARDISO_THREADS: int | None = None
#: Substitute the two-unknown source equalities into the cones (:func:`eliminate_pair_equalities`) instead of
#: keeping them as a Schur complement.
ELIMINATE = True


def _margin(u: np.ndarray) -> np.ndarray:
    """Smallest eigenvalue ``u0 − ‖u1‖`` of every cone."""
    return u[:, 0] - np.linalg.norm(u[:, 1:], axis=1)


def _mehrotra_shift(s: np.ndarray, z: np.ndarray, factor: float = 1.5, *,
                    shift_s: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Mehrotra's starting-point shift for SOC(4) cones: ``s`` and ``z`` (k, 4) into the interior, then balanced;
    with ``shift_s=False`` a strictly feasible ``s`` is kept as it is and only ``z`` is shifted and balanced."""
    s, z = s.copy(), z.copy()
    if shift_s:
        s[:, 0] += max(-factor * float(_margin(s).min()), 0.0)
    z[:, 0] += max(-factor * float(_margin(z).min()), 0.0)
    sz = float(np.einsum("ki,ki->", s, z))
    hs, hz = float(s[:, 0].sum()), float(z[:, 0].sum())
    if sz <= 0 or hs <= 0 or hz <= 0:
        sz, hs, hz = 1.0, 1.0, 1.0
    if shift_s:
        s[:, 0] += 0.5 * sz / hz
    z[:, 0] += 0.5 * sz / hs
    return s, z


_NONE = (np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0))


def eliminate_pair_equalities(problem):
    """Substitute the source equalities of two unknowns, ``a x_m + b x_j = 0`` (the zero derivative along an edge
    at a source vertex, ``4 φ_mid − φ_j = 0``), into the cones and the objective.

    ``x_m = α x_j`` (``α = −b / a``) is eliminated where every cone on ``x_m`` also holds ``x_j`` (on a source-star
    edge both are DOFs of each face of the edge), so the Newton matrix keeps its pattern: ``x_m`` becomes a fixed
    DOF. Rows of one unknown (``x = 0``) fix it. Left in ``E``: rows of other shapes, nonzero ``f``, an ``x_m``
    in several rows or on a cone without its ``x_j``.

    Returns
    -------
    problem : P2Problem
        A shallow copy with new ``G``, ``c``, ``E``, ``f`` and ``fixed``.
    (elim, onto, alpha) : ((r,) int, (r,) int, (r,) float)
        ``x[elim] = alpha · x[onto]`` restores the eliminated unknowns from a solution.
    """
    import copy

    pb = copy.copy(problem)
    E = problem.E.tocsr()
    E.sum_duplicates()
    n_row = np.diff(E.indptr)
    col_count = np.bincount(E.indices, minlength=problem.n)
    zero_f = problem.f == 0
    fixed = problem.fixed.copy()
    ones = np.flatnonzero((n_row == 1) & zero_f)
    fixed[E.indices[E.indptr[ones]]] = True
    pairs = np.flatnonzero((n_row == 2) & zero_f)
    c0, c1 = E.indices[E.indptr[pairs]], E.indices[E.indptr[pairs] + 1]
    v0, v1 = E.data[E.indptr[pairs]], E.data[E.indptr[pairs] + 1]
    m, j = np.maximum(c0, c1), np.minimum(c0, c1)  # the midpoint DOFs come after the vertices
    vm, vj = np.where(c0 > c1, v0, v1), np.where(c0 > c1, v1, v0)
    ok = (col_count[m] == 1) & ~fixed[m] & ~np.isin(m, j) & (vm != 0)
    alpha = -vj / np.where(vm != 0, vm, 1.0)
    onto_of = np.full(problem.n, -1, dtype=np.int64)
    onto_of[m[ok]] = j[ok]
    dofs = problem.cone_dofs
    kk, ii = np.nonzero(onto_of[dofs] >= 0)
    target = onto_of[dofs[kk, ii]]
    jj = np.argmax(dofs[kk] == target[:, None], axis=1)
    lacking = np.unique(dofs[kk, ii][dofs[kk, jj] != target])  # x_m on a cone without x_j: keep its row
    ok &= ~np.isin(m, lacking)
    onto_of[lacking] = -1
    keep = onto_of[dofs[kk, ii]] >= 0
    kk, ii, jj = kk[keep], ii[keep], jj[keep]
    a_of = np.zeros(problem.n)
    a_of[m[ok]] = alpha[ok]
    G = problem.G.copy()
    np.add.at(G, (kk, slice(None), jj), a_of[dofs[kk, ii]][:, None] * G[kk, :, ii])
    G[kk, :, ii] = 0.0
    c = problem.c.copy()
    np.add.at(c, j[ok], alpha[ok] * c[m[ok]])
    c[m[ok]] = 0.0
    fixed[m[ok]] = True
    # a DOF fixed by a row of one unknown keeps no cone columns (the Newton matrix gives fixed DOFs an identity row
    # only; with their columns left in, x there drifted from 0 during the iterations)
    G = np.where(fixed[dofs][:, None, :], 0.0, G)
    c[fixed] = 0.0
    rows_left = np.setdiff1d(np.arange(E.shape[0]), np.concatenate([ones, pairs[ok]]))
    pb.G, pb.c, pb.E, pb.f, pb.fixed = G, c, E[rows_left], problem.f[rows_left], fixed
    fx = np.flatnonzero(fixed)
    if fx.size and pb.E.nnz:
        keep_cols = np.ones(problem.n)
        keep_cols[fx] = 0.0
        pb.E = (pb.E @ sp.diags(keep_cols)).tocsr()
        pb.E.eliminate_zeros()
    return pb, (m[ok], j[ok], alpha[ok])


def _compact(G: np.ndarray) -> np.ndarray:
    """Rows 0–2 of the cone blocks ``G`` (k, 4, 6): (k, 3, 6), the layout of :mod:`._p2_kernels`.

    Raises
    ------
    SolverError
        Row 3 of some block differs from row 0 (every order-2 cone is ``(φ + 1, ∇φ, φ − 1)``).
    """
    bad = np.flatnonzero((G[:, 0] != G[:, 3]).any(axis=1))
    if bad.size:
        raise SolverError(f"order-2 cone {bad[0]}: rows 0 and 3 of G differ (the structured solver needs cones "
                          "h − G x = (φ + 1, ∇φ, φ − 1))", solver="ipm", status="invalid_problem")
    return np.ascontiguousarray(G[:, :3])


class _Scaling:
    """The NT scaling of every cone (``w`` (k, 4), ``eta`` (k,); see :mod:`._p2_kernels`) and products with it."""

    def __init__(self, w: np.ndarray, eta: np.ndarray):
        self.w, self.eta = w, eta

    @classmethod
    def at(cls, s: np.ndarray, z: np.ndarray) -> tuple[_Scaling, np.ndarray]:
        """Nesterov–Todd scaling ``W`` with ``W z = W⁻¹ s = λ``; returns the scaling and λ (k, 4)."""
        k = s.shape[0]
        w, eta, lam = np.empty((k, 4)), np.empty(k), np.empty((k, 4))
        _kern.nt_scaling(s, z, w, eta, lam)
        return cls(w, eta), lam

    @classmethod
    def identity(cls, k: int) -> _Scaling:
        w = np.zeros((k, 4))
        w[:, 0] = 1.0
        return cls(w, np.ones(k))

    def apply(self, v: np.ndarray, power: int) -> np.ndarray:
        """``W^power v`` per cone, ``power`` ∈ {1, −1, −2}; v (k, 4)."""
        out = np.empty_like(v)
        _kern.apply_w(self.w, self.eta, v, power, out)
        return out


def _jprod(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    out = np.empty_like(a)
    _kern.jprod(a, b, out)
    return out


def _jdiv(lam: np.ndarray, d: np.ndarray) -> np.ndarray:
    """``u`` with ``lam ∘ u = d`` (Jordan product of the SOC), per cone."""
    out = np.empty_like(d)
    _kern.jdiv(lam, d, out)
    return out


class P2InteriorPoint:
    """Interior-point solver bound to one :class:`~cvxgeodesic.elements_p2.P2Builder` (one mesh).

    Parameters
    ----------
    builder : P2Builder
    backend : str
        :class:`SymbolicCholesky` backend.

    Attributes
    ----------
    chol : SymbolicCholesky
        The one symbolic analysis of the face-clique pattern.
    """

    def __init__(self, builder, *, backend: str = "auto"):
        space = builder.space
        self.n = n = space.n_dofs
        fd = space.face_dofs
        rows = np.repeat(fd, 6, axis=1).ravel()
        cols = np.tile(fd, (1, 6)).ravel()
        pattern = sp.coo_matrix((np.ones(rows.size), (rows, cols)), shape=(n, n)).tocsc()
        t0 = time.perf_counter()
        lib = _pardiso._load() if backend in ("auto", "pardiso") else None
        if lib is not None:
            # PARDISO keeps the analysis's thread count
            previous = lib.MKL_Set_Num_Threads_Local(self._pardiso_threads())
        try:
            self.chol = SymbolicCholesky(pattern, backend=backend)
        finally:
            if lib is not None:
                lib.MKL_Set_Num_Threads_Local(previous)
        # positions of each face's lower-triangular 6×6 entries in the factor's data array
        r = fd[:, _TRIL_R]
        c = fd[:, _TRIL_C]
        self.face_pos = self.chol.positions(r.ravel(), c.ravel()).reshape(fd.shape[0], 21)
        self.analyze_time = time.perf_counter() - t0

    # ------------------------------------------------------------------ helpers
    @staticmethod
    def _pardiso_threads() -> int:
        """:data:`PARDISO_THREADS`, or the thread count of the enclosing solve (:mod:`cvxgeodesic._threads`)."""
        if PARDISO_THREADS is not None:
            return PARDISO_THREADS
        from .._threads import resolve_threads

        return resolve_threads(None)

    def _Gx(self, pb, x):
        out = np.empty((pb.G.shape[0], 4))
        _kern.gather(pb.G, pb.cone_dofs, np.ascontiguousarray(x, dtype=float), out)
        return out

    def _Gtz(self, pb, z):
        out = np.zeros(self.n)
        _kern.scatter(pb.G, pb.cone_dofs, z, out)
        return out

    def solve(self, problem, *, tol: float = 1e-8, max_iter: int = 200, callback=None) -> dict:
        """Solve one :class:`~cvxgeodesic.elements_p2.P2Problem`.

        Returns
        -------
        dict
            As :func:`~cvxgeodesic.elements_p2.solve_p2_clarabel`.

        Raises
        ------
        SolverError
            Numerical failure or iteration limit without reaching 100 × ``tol``.
        """
        from threadpoolctl import threadpool_limits

        # PARDISO runs its own threads; an idle OpenBLAS pool spinning beside it costs a core (as in ipm/solver.py)
        with threadpool_limits({"libopenblas": 1, "libscipy_openblas": 1}):
            return self._solve(problem, tol=tol, max_iter=max_iter, callback=callback)

    def _solve(self, problem, *, tol, max_iter, callback) -> dict:
        import copy

        t0 = time.perf_counter()
        pb, (elim, onto, alpha) = eliminate_pair_equalities(problem) if ELIMINATE else (copy.copy(problem), _NONE)
        # equilibration (one Ruiz pass): columns by the square root of their largest cone-row norm, then every
        # cone by its largest row (a positive multiple of a cone vector stays in the cone), the objective to ∞-norm 1
        n = self.n
        colmax = np.zeros(n)
        np.maximum.at(colmax, pb.cone_dofs.ravel(), np.abs(pb.G).max(axis=1).ravel())
        D = np.where((colmax > 0) & ~pb.fixed, 1.0 / np.sqrt(np.where(colmax > 0, colmax, 1.0)), 1.0)
        G = pb.G * D[pb.cone_dofs][:, None, :]
        rs = 1.0 / np.maximum(np.abs(G).max(axis=(1, 2)), np.abs(pb.h).max(axis=1))
        pb.G = _compact(G * rs[:, None, None])
        pb.h = pb.h * rs[:, None]
        cD = pb.c * D
        csc = max(float(np.abs(cD).max()), 1e-300)
        pb.c = cD / csc
        pb.E = (pb.E @ sp.diags(D)).tocsr()
        if problem.guess is not None:
            pb.guess = problem.guess / D
        out = self._solve_scaled(pb, tol=tol, max_iter=max_iter, callback=callback)
        out["x"] = out["x"] * D
        out["x"][elim] = alpha * out["x"][onto]
        out["objective"] = float(problem.c @ out["x"])
        out["time"] = time.perf_counter() - t0
        return out

    def _solve_scaled(self, pb, *, tol, max_iter, callback) -> dict:
        t0 = time.perf_counter()
        k = pb.n_cones
        c, h = pb.c, pb.h
        E, ET, p, f, fixed = pb.E.tocsr(), pb.E.tocsr().T.tocsc(), pb.E.shape[0], pb.f, pb.fixed
        hnorm = max(1.0, float(np.linalg.norm(h)))
        cnorm = max(1.0, float(np.linalg.norm(c)))
        system = _P2System(self, pb)
        x, s, z = system.start()
        y = np.zeros(p)
        status = "max_iterations"
        info = {}
        best = None
        it = 0
        last_step = last_sigma = float("nan")
        for it in range(1, max_iter + 1):
            rd = c + self._Gtz(pb, z) + (ET @ y if p else 0.0)
            rd[fixed] = 0.0
            rp = self._Gx(pb, x) + s - h
            re = E @ x - f if p else np.zeros(0)
            gap = float(np.einsum("ki,ki->", s, z))
            mu = gap / k
            pobj = float(c @ x)
            dobj = -float(np.einsum("ki,ki->", h, z)) - float(f @ y)
            pres = max(float(np.linalg.norm(rp)) / hnorm, float(np.linalg.norm(re)) / max(1.0, np.linalg.norm(f)))
            dres = float(np.linalg.norm(rd)) / cnorm
            # the objective gap as well as sᵀz: with the dual residual accepted at DUAL_TOL_FACTOR × tol, sᵀz alone
            # ended a needle strip's solve (from the guess start) 7.6e-5 of the largest distance from its optimum
            rgap = max(gap, abs(pobj - dobj)) / max(1.0, abs(pobj))
            info = {"primal_residual": pres, "dual_residual": dres, "gap": rgap, "pobj": pobj, "dobj": dobj,
                    "step": last_step, "sigma": last_sigma}
            if callback is not None:
                callback(it, dict(info))
            score = max(pres, dres / DUAL_TOL_FACTOR, rgap)
            if best is None or score < best[0]:
                best = (score, x.copy(), dict(info))
            if pres <= tol and dres <= DUAL_TOL_FACTOR * tol and rgap <= tol:
                status = "optimal"
                break
            try:
                (dx, dy, dz, ds), alpha_p, alpha_d, sigma = system.direction(s, z, rd, rp, re, mu, gap)
            except (FloatingPointError, np.linalg.LinAlgError, NotPositiveDefiniteError, ValueError) as exc:
                status = f"numerical_error: {exc}"
                break
            alpha = min(alpha_p, alpha_d)
            if not np.isfinite(alpha) or alpha <= 1e-12:
                status = "step_failure"
                break
            last_step, last_sigma = alpha, sigma
            x = x + alpha_p * dx
            s = s + alpha_p * ds
            y = y + alpha_d * dy
            z = z + alpha_d * dz
        if status != "optimal":
            score, xb, ib = best
            if score <= 100 * tol:
                x, info, status = xb, ib, "almost_optimal"
            else:
                raise SolverError(f"order-2 interior-point solver stopped: {status}", solver="ipm",
                                  status="numerical_error" if status != "max_iterations" else status,
                                  info={"iterations": it, **ib})
        x = x.copy()
        x[fixed] = 0.0
        return {
            "x": x, "status": status, "solver": "ipm", "iterations": it, "objective": float(c @ x),
            "primal_residual": info["primal_residual"], "dual_residual": info["dual_residual"], "gap": info["gap"],
            "time": time.perf_counter() - t0,
        }


class _P2System:
    """The Newton systems of one (equilibrated) order-2 program: the face-clique matrix ``H = Σ GᵀW⁻²G`` in the
    fixed pattern, the source equalities through a dense Schur complement, refined Newton directions."""

    def __init__(self, solver: P2InteriorPoint, pb):
        self.solver, self.pb = solver, pb
        self.n = solver.n
        self.E = pb.E.tocsr()
        self.ET = self.E.T.tocsc()
        self.p = self.E.shape[0]
        self.fixed = pb.fixed
        self.Gl = pb.G
        self.face_pos = solver.face_pos[pb.cone_face]
        self.chol = solver.chol
        self.diag = solver.chol.diag_positions
        self.sigma_cap = 1.0  # SIGMA_CAP_GUESS once :meth:`start` starts from the guess

    def factor(self, sc: _Scaling):
        """Factor of ``H`` (Σ_k G_kᵀ (W_k⁻²) G_k, lower triangle of each 6×6 block, summed straight into the fixed
        pattern's data) and of the Schur complement ``E H⁻¹ Eᵀ``."""
        Gl, fixed, p, n = self.Gl, self.fixed, self.p, self.n
        data = np.zeros(self.chol.nnz)
        _kern.assemble(Gl, sc.w, sc.eta, self.face_pos, _TRIL_R, _TRIL_C, data)
        dg = data[self.diag]
        scale = max(float(dg.max()), 1e-300)
        data[self.diag] += np.where(fixed, 1.0, 0.0) + REG * np.abs(dg) + np.where(dg <= 0, scale, 0.0) * (~fixed)
        solve_h = None
        for bump in (0.0, 1e-10, 1e-8, 1e-6):  # rounding can make the near-singular H look indefinite
            try:
                solve_h = self.chol.factorize(data, beta=bump * scale)
                break
            except NotPositiveDefiniteError:
                continue
        if solve_h is None:
            raise NotPositiveDefiniteError("Newton matrix not positive definite after regularization")
        if p:
            Y = solve_h(self.ET.toarray())
            Y = Y.reshape(n, p)
            S = self.E @ Y
            S = 0.5 * (S + S.T)
            cf = sla.cho_factor(S + 1e-14 * max(1.0, np.abs(S).max()) * np.eye(p))
        else:
            Y, cf = None, None
        return solve_h, Y, cf

    def reduced(self, fac, b1, b2):
        """Solve [H Eᵀ; E 0] (dx, dy) = (b1, b2) through the (regularized) factor."""
        solve_h, Y, cf = fac
        hb = solve_h(b1)
        if self.p:
            dy = sla.cho_solve(cf, self.E @ hb - b2)
            return hb - Y @ dy, dy
        return hb, np.zeros(0)

    def kkt_solve(self, fac, sc: _Scaling, bd, be, bp, bu):
        """Solve Gᵀdz + Eᵀdy = bd, E dx = be, G dx + ds = bp, W dz + W⁻¹ ds = bu (reduced to H)."""
        sv, pb = self.solver, self.pb
        wib, t = np.empty_like(bu), np.empty_like(bu)
        _kern.rhs_cones(sc.w, sc.eta, bu, bp, wib, t)
        b1 = bd - sv._Gtz(pb, t)
        b1[self.fixed] = 0.0
        dx, dy = self.reduced(fac, b1, be)
        ds, dz = np.empty_like(bu), np.empty_like(bu)
        _kern.back_cones(pb.G, pb.cone_dofs, sc.w, sc.eta, np.ascontiguousarray(dx), bp, wib, ds, dz)
        return dx, dy, dz, ds

    def newton(self, fac, sc: _Scaling, lam, rd, rp, re, d, *, refine: bool = True):
        """The direction for the complementarity right-hand side ``d`` (refined on the full system unless
        ``refine`` is False) and ``u = λ \\ d``."""
        u = _jdiv(lam, d)
        bd, be, bp = -rd, -re, -rp
        dirn = self.kkt_solve(fac, sc, bd, be, bp, u)
        if refine:
            dirn = self.refine(fac, sc, bd, be, bp, u, dirn)
        return dirn, u

    def refine(self, fac, sc: _Scaling, bd, be, bp, u, dirn):
        """Iterative refinement of ``dirn = (dx, dy, dz, ds)`` on the full system with right-hand side
        ``(bd, be, bp, u)``: Δz = W⁻²(…) amplifies any error in Δx by up to 1/μ, so the residual of the dual
        equation has to be corrected through Δz itself."""
        pb, p, E, ET = self.pb, self.p, self.E, self.ET
        dx, dy, dz, ds = dirn
        scale_b = max(float(np.abs(bd).max(initial=0.0)), float(np.abs(u).max(initial=0.0)), 1e-300)
        for _ in range(REFINE_STEPS):
            r3, r4, gtz = np.empty_like(u), np.empty_like(u), np.zeros(self.n)
            _kern.residual_cones(pb.G, pb.cone_dofs, sc.w, sc.eta, np.ascontiguousarray(dx), ds, dz, bp, u, r3, r4,
                                 gtz)
            r1 = bd - gtz - (ET @ dy if p else 0.0)
            r1[self.fixed] = 0.0
            r2 = be - (E @ dx if p else np.zeros(0))
            err = max(float(np.abs(r1).max(initial=0.0)), float(np.abs(r3).max(initial=0.0)),
                      float(np.abs(r4).max(initial=0.0)), float(np.abs(r2).max(initial=0.0)))
            if err <= 1e-11 * scale_b:
                break
            ex, ey, ez, es = self.kkt_solve(fac, sc, r1, r2, r3, r4)
            dx, dy, dz, ds = dx + ex, dy + ey, dz + ez, ds + es
        return dx, dy, dz, ds

    def steps(self, s, ds, z, dz, fraction: float) -> tuple[float, float]:
        """Primal and dual step lengths: ``fraction`` of the step to the cone boundary, at most 1 (equal unless
        :data:`SEPARATE_STEPS`)."""
        ap = min(1.0, fraction * _kern.max_step(s, ds))
        ad = min(1.0, fraction * _kern.max_step(z, dz))
        if not SEPARATE_STEPS:
            ap = ad = min(ap, ad)
        return ap, ad

    def direction(self, s, z, rd, rp, re, mu: float, gap: float):
        """One iteration's search direction: NT scaling, predictor, Mehrotra corrector, Gondzio's correctors.

        Returns
        -------
        (dx, dy, dz, ds), alpha_p, alpha_d, sigma
            The direction, its primal and dual step lengths (0.99 of the way to the boundary, at most 1) and
            the centering parameter.
        """
        sc, lam = _Scaling.at(s, z)
        fac = self.factor(sc)
        d_a = -_jprod(lam, lam)
        (dxa, dya, dza, dsa), _ = self.newton(fac, sc, lam, rd, rp, re, d_a, refine=not REFINE_ONCE)
        ap, ad = self.steps(s, dsa, z, dza, 1.0)
        ratio = min(1.0, max(float(np.einsum("ki,ki->", s + ap * dsa, z + ad * dza)), 0.0) / gap)
        sigma = min(self.sigma_cap, ratio**3)
        d_c = np.empty_like(d_a)
        _kern.mehrotra_rhs(sc.w, sc.eta, d_a, dsa, dza, sigma * mu, d_c)
        d, u = self.newton(fac, sc, lam, rd, rp, re, d_c, refine=not REFINE_ONCE)
        ap, ad = self.steps(s, d[3], z, d[2], STEP_FRACTION)
        d, u, ap, ad = self.correct(fac, sc, lam, s, z, d, u, ap, ad, sigma * mu)
        if REFINE_ONCE:
            d = self.refine(fac, sc, -rd, -re, -rp, u, d)
            ap, ad = self.steps(s, d[3], z, d[2], STEP_FRACTION)
        return d, ap, ad, sigma

    def correct(self, fac, sc: _Scaling, lam, s, z, d, u, ap: float, ad: float, sigma_mu: float):
        """Gondzio's centrality correctors (as the order-1 solver's, :mod:`.ipm.algorithm`): extra solves with the
        same factor that move the complementarity eigenvalues at a trial point into ``[β_min σμ, β_max σμ]``, each
        kept, at the largest of :data:`CORRECTOR_WEIGHTS` that helps, when it lengthens the step by 0.01."""
        zero_d, zero_p, zero_e = np.zeros(self.n), np.zeros_like(z), np.zeros(self.p)
        for _ in range(MAX_CORRECTORS):
            if min(ap, ad) >= 0.995:
                break
            tp, td = min(1.0, GZ_A * ap + GZ_B), min(1.0, GZ_A * ad + GZ_B)
            cc = np.empty_like(z)
            dx, dy, dz, ds = d
            _kern.gondzio_rhs(sc.w, sc.eta, s, ds, tp, z, dz, td, BETA_MIN * sigma_mu, BETA_MAX * sigma_mu, cc)
            (cx, cy, cz, cs), cu = self.newton(fac, sc, lam, zero_d, zero_p, zero_e, cc, refine=not REFINE_ONCE)
            best = None
            for wgt in CORRECTOR_WEIGHTS:
                nds, ndz = ds + wgt * cs, dz + wgt * cz
                np_, nd_ = self.steps(s, nds, z, ndz, STEP_FRACTION)
                if best is None or min(np_, nd_) > best[0]:
                    best = (min(np_, nd_), wgt, np_, nd_, nds, ndz)
                if min(np_, nd_) >= min(ap, ad) + 0.01:
                    break
            if best is None or best[0] < min(ap, ad) + 0.01:
                break
            _, wgt, ap, ad, nds, ndz = best
            d, u = (dx + wgt * cx, dy + wgt * cy, ndz, nds), u + wgt * cu
        return d, u, ap, ad

    def start(self):
        """The least-norm z with Gᵀz = −c and, from the guess (:data:`START` "guess") or least squares with W = I,
        x; both shifted into the cones (:data:`START`); returns ``x, s, z``."""
        sv, pb, p, E = self.solver, self.pb, self.p, self.E
        k = pb.n_cones
        solve_h, Y, cf = self.factor(_Scaling.identity(k))
        cc = -pb.c.copy()
        cc[self.fixed] = 0.0
        hb = solve_h(cc)
        if p:
            wy = sla.cho_solve(cf, E @ hb)
            wv = hb - Y @ wy
        else:
            wv = hb
        z = sv._Gx(pb, wv)  # least-norm z with Gᵀz = −c
        if START == "guess" and (xg := self.interior_guess()) is not None:
            self.sigma_cap = SIGMA_CAP_GUESS
            return (xg, *_mehrotra_shift(pb.h - sv._Gx(pb, xg), z, shift_s=False))
        g = sv._Gtz(pb, pb.h)
        g[self.fixed] = 0.0
        hb = solve_h(g)
        if p:
            y0 = sla.cho_solve(cf, E @ hb - pb.f)
            x = hb - Y @ y0
        else:
            x = hb
        x[self.fixed] = 0.0
        s = pb.h - sv._Gx(pb, x)

        def shift(u):
            m = u[:, 0] - np.linalg.norm(u[:, 1:], axis=1)
            a = -float(m.min())
            if a >= -1e-8:
                u = u.copy()
                u[:, 0] += 1 + max(a, 0.0)
            return u

        if START == "cvxopt":
            return x, shift(s), shift(z)
        return (x, *_mehrotra_shift(s, z))

    def interior_guess(self):
        """``θ ψ`` for the problem's guess ``ψ`` (scaled), ``θ = min(1, GUESS_FRACTION θ_max)`` with ``θ_max`` the
        largest ``θ`` keeping every cone's slack ``h − θ Gψ`` strictly inside; ``None`` when no ``θ > 0`` does."""
        pb = self.pb
        psi = pb.guess
        if psi is None or (self.p and np.abs(self.E @ psi - pb.f).max() > 1e-9 * max(1.0, np.abs(psi).max())):
            return None
        theta = self._cone_theta(psi)
        theta_max = float(theta.min(initial=np.inf))
        if not theta_max > 0:
            return None
        x = min(1.0, GUESS_FRACTION * theta_max) * psi
        x[self.fixed] = 0.0
        return x

    def _cone_theta(self, psi: np.ndarray) -> np.ndarray:
        """Per cone, the largest ``θ`` with ``h − θ G ψ`` strictly inside on all of ``(0, θ)``: (k,) ndarray, 0 where
        no ``θ > 0`` is, ``inf`` where every one is."""
        pb = self.pb
        g, h = self.solver._Gx(pb, psi), pb.h
        # the margin (head² − ‖body‖²) of the slack at θ is m0 + B θ + A θ²; the order-2 cones start on the boundary
        m0 = h[:, 0] ** 2 - np.einsum("ki,ki->k", h[:, 1:], h[:, 1:])
        m0 = np.where(np.abs(m0) <= 1e-12 * h[:, 0] ** 2, 0.0, m0)
        B = -2.0 * (h[:, 0] * g[:, 0] - np.einsum("ki,ki->k", h[:, 1:], g[:, 1:]))
        A = g[:, 0] ** 2 - np.einsum("ki,ki->k", g[:, 1:], g[:, 1:])
        disc = B * B - 4.0 * A * m0
        sq = np.sqrt(np.maximum(disc, 0.0))
        # from inside (m0 > 0, or m0 = 0 and B > 0) the first positive root is (−B − √disc) / 2A, or −m0 / B when A = 0
        with np.errstate(divide="ignore", invalid="ignore"):
            root = np.where(A != 0, (-B - sq) / (2 * A), -m0 / B)
        theta = np.where((disc >= 0) & (root > 0), root, np.inf)
        inside = (m0 > 0) & (h[:, 0] > 0) | (m0 == 0) & (B > 0)
        return np.where(inside, theta, 0.0)
