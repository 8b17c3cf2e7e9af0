"""The reduced Newton system and the directions computed from it.

Eliminating ``Δs`` and ``Δz`` leaves the n×n SPD system ::

    K Δx = (P + Σ_i A_iᵀ W_i⁻² A_i) Δx = r

(:meth:`.program.Program.assemble`), factorized once per iteration and solved three to eight times
(predictor, corrector, centrality correctors, iterative refinement of the final direction). With equalities
``E x = f`` (a few rows) the system is ``[K Eᵀ; E 0] (Δx, Δy) = (r, e)``, solved through the dense Schur
complement ``S = E K⁻¹ Eᵀ``: ``Δy = S⁻¹(E K⁻¹ r − e)``, ``Δx = K⁻¹ r − (K⁻¹Eᵀ) Δy`` (``p`` extra solves per
factorization, and the pattern of ``K`` stays the mesh's).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence

import numpy as np
import scipy.linalg as sla

from ...linalg import Factor, NotPositiveDefiniteError, SymbolicCholesky
from .cones import Scaling, _amax
from .program import Program
from .settings import IPMSettings
from .state import Direction

__all__ = ["KKTFactor", "LinearSystem", "Residuals", "Trouble", "newton"]

#: Diagonal bumps (× the largest diagonal entry) tried in turn when a factorization fails: rounding can make a
#: nearly singular Newton matrix look indefinite near the optimum (the order-2 solver's rule, kept for every program).
REGULARIZATION_BUMPS = (1e-10, 1e-8, 1e-6)


class Trouble(Exception):
    """A non-finite right-hand side or solve (numerical failure inside one iteration)."""


class KKTFactor:
    """A factor of ``K`` and, with equalities, of the Schur complement: ``(factor, Y = K⁻¹Eᵀ, cho(S))``."""

    __slots__ = ("K", "Y", "S")

    def __init__(self, K: Factor, Y: np.ndarray | None = None, S=None):
        self.K, self.Y, self.S = K, Y, S


class LinearSystem:
    """Assembly, factorization and solves of the reduced system of one program, with their timers.

    Parameters
    ----------
    program : Program
    chol : SymbolicCholesky
    settings : IPMSettings
    timers, counters : dict
        Accumulated in place (``assembly_time``, ``factor_time``, ``linear_solve_time``;
        ``refinement_steps``).
    """

    def __init__(self, program: Program, chol: SymbolicCholesky, settings: IPMSettings, timers: dict,
                 counters: dict):
        self.pr, self.chol, self.settings = program, chol, settings
        self.timers, self.counters = timers, counters

    def assemble(self, scalings: Sequence[Scaling], with_P: bool = True) -> np.ndarray:
        t0 = time.perf_counter()
        data = self.pr.assemble(scalings, with_P)
        self.timers["assembly_time"] += time.perf_counter() - t0
        return data

    def factorize(self, data: np.ndarray) -> KKTFactor:
        """Factorize, in place: the assembled data is not used again (refinement applies the operator itself).

        A failed factorization is retried with the diagonal raised by :data:`REGULARIZATION_BUMPS` (counted in
        ``counters["regularized"]``). With equalities the Schur complement is formed and factorized too.

        Raises NotPositiveDefiniteError.
        """
        t0 = time.perf_counter()
        diag = self.pr.diag_pos
        data[diag] *= 1.0 + self.settings.static_reg
        try:
            try:
                f = self.chol.factorize(data)
            except NotPositiveDefiniteError:
                f = self._regularized(data)
            return self._schur(f)
        finally:
            self.timers["factor_time"] += time.perf_counter() - t0

    def _regularized(self, data: np.ndarray) -> Factor:
        scale = max(float(data[self.pr.diag_pos].max(initial=0.0)), 1e-300)
        for bump in REGULARIZATION_BUMPS:
            try:
                f = self.chol.factorize(data, beta=bump * scale)
            except NotPositiveDefiniteError:
                continue
            self.counters["regularized"] = self.counters.get("regularized", 0) + 1
            return f
        raise NotPositiveDefiniteError("the Newton matrix is not positive definite even after regularization")

    def _schur(self, f: Factor) -> KKTFactor:
        pr = self.pr
        if not pr.p:
            return KKTFactor(f)
        Y = f(pr.ET.toarray()).reshape(pr.n, pr.p)
        Y[pr.fixed] = 0.0
        S = pr.E @ Y
        S = 0.5 * (S + S.T)
        S[np.diag_indices_from(S)] += 1e-14 * max(1.0, float(np.abs(S).max()))
        try:
            cf = sla.cho_factor(S)
        except np.linalg.LinAlgError as exc:
            raise NotPositiveDefiniteError(f"the equality rows are dependent: {exc}") from exc
        return KKTFactor(f, Y, cf)

    def solve(self, f: KKTFactor, r: np.ndarray) -> np.ndarray:
        """``K⁻¹ r`` with the fixed entries 0; :class:`Trouble` when ``r`` or the solve is not finite."""
        t0 = time.perf_counter()
        try:
            if not np.isfinite(r).all():
                raise Trouble("non-finite right-hand side")
            out = f.K(r)
        except NotPositiveDefiniteError as exc:  # PARDISO's guard: a non-finite solve
            raise Trouble(str(exc)) from exc
        finally:
            self.timers["linear_solve_time"] += time.perf_counter() - t0
        out[self.pr.fixed] = 0.0
        return out

    def solve_kkt(self, f: KKTFactor, r: np.ndarray, e: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(Δx, Δy)`` of ``[K Eᵀ; E 0] (Δx, Δy) = (r, e)`` (``Δy`` empty without equalities)."""
        u = self.solve(f, r)
        if not self.pr.p:
            return u, np.zeros(0)
        dy = sla.cho_solve(f.S, self.pr.E @ u - e)
        return u - f.Y @ dy, dy

    def residual(self, dx: np.ndarray, dy: np.ndarray, r: np.ndarray, e: np.ndarray, scalings: Sequence[Scaling],
                 with_P: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """``(r − K dx − Eᵀdy, e − E dx)`` with the fixed entries of the first 0."""
        pr = self.pr
        res = r - pr.kkt_mul(dx, scalings, with_P)
        if pr.p:
            res -= pr.Et(dy)
        res[pr.fixed] = 0.0
        return res, (e - pr.E @ dx if pr.p else e)

    def solve_refined(self, f: KKTFactor, rhs: np.ndarray, scalings: Sequence[Scaling], target: float,
                      with_P: bool = True, e: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Solve ``[K Eᵀ; E 0] (dx, dy) = (rhs, e)`` (``e`` = 0 by default) with iterative refinement until the
        residual's ∞-norm is at most ``target`` (or no more progress)."""
        e = np.zeros(self.pr.p) if e is None else e
        dx, dy = self.solve_kkt(f, rhs, e)
        return self.refine(f, dx, dy, rhs, e, scalings, target, with_P)

    def refine(self, f: KKTFactor, dx: np.ndarray, dy: np.ndarray, rhs: np.ndarray, e: np.ndarray,
               scalings: Sequence[Scaling], target: float, with_P: bool = True,
               on_step: Callable[[np.ndarray], None] | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Iterative refinement of a solution ``(dx, dy)`` (``dx`` updated in place) until the residual's ∞-norm
        is at most ``target`` or stops halving; ``on_step(δ)`` after each correction ``dx += δ``."""
        prev = np.inf
        for _ in range(self.settings.max_refine):
            res, res_e = self.residual(dx, dy, rhs, e, scalings, with_P)
            rn = max(_amax(res), float(np.abs(res_e).max(initial=0.0)))
            if rn <= target or rn >= 0.5 * prev:
                break
            prev = rn
            ddx, ddy = self.solve_kkt(f, res, res_e)
            dx += ddx
            dy = dy + ddy
            self.counters["refinement_steps"] += 1
            if on_step is not None:
                on_step(ddx)
        return dx, dy


class Residuals:
    """The parts of the Newton right-hand side that stay fixed during one iteration.

    With ``t = W⁻¹(λ \\ d_s) + W⁻² r_z`` the direction is
    ``(P + AᵀW⁻²A) Δx = −r_x − Aᵀt``, ``Δz = W⁻² A Δx + t``, ``Δs = −r_z − A Δx``;
    ``W⁻² r_z`` and ``−r_x − Aᵀ(W⁻² r_z)`` are computed once and shared by the
    predictor, the corrector and the centrality correctors (which have ``r = 0``).
    """

    def __init__(self, pr: Program, scalings: Sequence[Scaling], rx: np.ndarray, rz: Sequence[np.ndarray],
                 ry: np.ndarray | None = None):
        self.rz = list(rz)
        self.wr = [sc.apply_winv2(r) for sc, r in zip(scalings, rz, strict=True)]
        self.rhs = -rx - pr.At(self.wr)
        self.ey = -ry if ry is not None and ry.size else np.zeros(0)  # E Δx = −(E x − f)

    @staticmethod
    def zero(pr: Program) -> Residuals:
        out = Residuals.__new__(Residuals)
        out.rz = [np.zeros(b.cone.shape(b.count)) for b in pr.blocks]
        out.wr = out.rz
        out.rhs = np.zeros(pr.n)
        out.ey = np.zeros(pr.p)
        return out


def newton(pr: Program, lin, scalings: Sequence[Scaling], res: Residuals, wu: Sequence[np.ndarray]) -> Direction:
    """Direction for ``P Δx + AᵀΔz + EᵀΔy = −r_x``, ``A Δx + Δs = −r_z``, ``E Δx = −r_y``,
    ``λ∘(WΔz + W⁻¹Δs) = d_s``.

    ``wu = W⁻¹(λ \\ d_s)`` per block is given; ``lin(rhs, e)`` solves the reduced system for ``(Δx, Δy)`` (see
    :class:`Residuals` and :meth:`LinearSystem.solve_kkt`).
    """
    rhs = res.rhs - pr.At(wu)
    rhs[pr.fixed] = 0.0
    dx, dy = lin(rhs, res.ey)
    ds, dz = [], []
    for b, sc, w, wr, rz in zip(pr.blocks, scalings, wu, res.wr, res.rz, strict=True):
        dsb, dzb = b.newton(dx, sc, w, wr, rz)
        ds.append(dsb)
        dz.append(dzb)
    return Direction(dx, ds, dz, rhs, dy, res.ey)
