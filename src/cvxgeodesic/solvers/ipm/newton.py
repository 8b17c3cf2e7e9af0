"""The reduced Newton system and the directions computed from it.

Eliminating ``Δs`` and ``Δz`` leaves the n×n SPD system ::

    (P + Σ_i A_iᵀ W_i⁻² A_i) Δx = r

(:meth:`.program.Program.assemble`), factorized once per iteration and solved three to eight times
(predictor, corrector, centrality correctors, iterative refinement of the final direction).
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np

from ...linalg import Factor, NotPositiveDefiniteError, SymbolicCholesky
from .cones import Scaling
from .program import Program
from .settings import IPMSettings
from .state import Direction

__all__ = ["LinearSystem", "Residuals", "Trouble", "newton"]


class Trouble(Exception):
    """A non-finite right-hand side or solve (numerical failure inside one iteration)."""


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

    def factorize(self, data: np.ndarray) -> Factor:
        """Factorize, in place: the assembled data is not used again (refinement applies the operator itself).

        Raises NotPositiveDefiniteError.
        """
        t0 = time.perf_counter()
        data[self.pr.diag_pos] *= 1.0 + self.settings.static_reg
        try:
            return self.chol.factorize(data)
        finally:
            self.timers["factor_time"] += time.perf_counter() - t0

    def solve(self, f: Factor, r: np.ndarray) -> np.ndarray:
        """``K⁻¹ r`` with the fixed entries 0; :class:`Trouble` when ``r`` or the solve is not finite."""
        t0 = time.perf_counter()
        try:
            if not np.isfinite(r).all():
                raise Trouble("non-finite right-hand side")
            out = f(r)
        except NotPositiveDefiniteError as exc:  # PARDISO's guard: a non-finite solve
            raise Trouble(str(exc)) from exc
        finally:
            self.timers["linear_solve_time"] += time.perf_counter() - t0
        out[self.pr.fixed] = 0.0
        return out

    def solve_refined(self, f: Factor, rhs: np.ndarray, scalings: Sequence[Scaling], target: float,
                      with_P: bool = True) -> np.ndarray:
        """Solve with iterative refinement until ‖rhs − K dx‖∞ ≤ target (or no more progress)."""
        pr = self.pr
        dx = self.solve(f, rhs)
        prev = np.inf
        for _ in range(self.settings.max_refine):
            res = rhs - pr.kkt_mul(dx, scalings, with_P)
            res[pr.fixed] = 0.0
            rn = float(np.abs(res).max())
            if rn <= target or rn >= 0.5 * prev:
                break
            prev = rn
            dx += self.solve(f, res)
            self.counters["refinement_steps"] += 1
        return dx


class Residuals:
    """The parts of the Newton right-hand side that stay fixed during one iteration.

    With ``t = W⁻¹(λ \\ d_s) + W⁻² r_z`` the direction is
    ``(P + AᵀW⁻²A) Δx = −r_x − Aᵀt``, ``Δz = W⁻² A Δx + t``, ``Δs = −r_z − A Δx``;
    ``W⁻² r_z`` and ``−r_x − Aᵀ(W⁻² r_z)`` are computed once and shared by the
    predictor, the corrector and the centrality correctors (which have ``r = 0``).
    """

    def __init__(self, pr: Program, scalings: Sequence[Scaling], rx: np.ndarray, rz: Sequence[np.ndarray]):
        self.rz = list(rz)
        self.wr = [sc.apply_winv2(r) for sc, r in zip(scalings, rz, strict=True)]
        self.rhs = -rx - pr.At(self.wr)

    @staticmethod
    def zero(pr: Program) -> Residuals:
        out = Residuals.__new__(Residuals)
        out.rz = [np.zeros(b.cone.shape(b.count)) for b in pr.blocks]
        out.wr = out.rz
        out.rhs = np.zeros(pr.n)
        return out


def newton(pr: Program, lin, scalings: Sequence[Scaling], res: Residuals, wu: Sequence[np.ndarray]) -> Direction:
    """Direction for ``P Δx + AᵀΔz = −r_x``, ``A Δx + Δs = −r_z``, ``λ∘(WΔz + W⁻¹Δs) = d_s``.

    ``wu = W⁻¹(λ \\ d_s)`` per block is given; ``lin(rhs)`` solves the reduced system (see :class:`Residuals`).
    """
    rhs = res.rhs - pr.At(wu)
    rhs[pr.fixed] = 0.0
    dx = lin(rhs)
    ds, dz = [], []
    for b, sc, w, wr, rz in zip(pr.blocks, scalings, wu, res.wr, res.rz, strict=True):
        dsb, dzb = b.newton(dx, sc, w, wr, rz)
        ds.append(dsb)
        dz.append(dzb)
    return Direction(dx, ds, dz, rhs)
