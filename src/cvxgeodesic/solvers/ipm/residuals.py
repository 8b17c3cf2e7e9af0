"""Residuals, costs, the stopping rule and the infeasibility certificates of one iterate.

Residuals, gap and the stopping rule follow Clarabel's definitions (infinity norms, relative to
``max(1, ‖b‖ + ‖x‖ + ‖s‖)`` and ``max(1, ‖q‖ + ‖x‖ + ‖z‖)``; gap ``|pcost − dcost|``, absolute or
relative to ``max(1, min(|pcost|, |dcost|))``), evaluated on the problem with the fixed variables
eliminated; convergence also needs the dual residual below ``tol`` relative to ``max(1, ‖q‖ + ‖x‖)``
alone, so that a dual blown up along a direction that ``Aᵀ`` cancels cannot hide it. Where rounding
stops the iterations after the best iterate came within ``reduced_factor`` × ``tol``, that iterate is
returned as ``"almost_optimal"``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .cones import _amax
from .program import Program
from .settings import IPMSettings
from .state import Iterate

__all__ = ["BestIterate", "Evaluation", "acceptable", "almost", "certificate", "evaluate"]


@dataclass
class Evaluation:
    """One iterate's residuals (``rx`` (n,), ``rz`` per block), the terms the certificates and the refinement
    target need, and ``info`` (what the callback sees)."""

    info: dict
    rx: np.ndarray
    rz: list
    ry: np.ndarray
    aux: list
    Atz: np.ndarray
    Pfx: np.ndarray
    bz: float
    qx: float
    dual_scale: float
    abs_sum_x: float


def evaluate(pr: Program, it: Iterate, iteration: int, step: float, elapsed: float) -> Evaluation:
    """Residuals, costs, gap and ``μ`` of ``it``."""
    x = it.x
    Px = pr.Pmul(x)
    Atz = pr.At(it.z)
    if pr.p:
        Atz = Atz + pr.Et(it.y)
    rx = Px + pr.q + Atz
    rx[pr.fixed] = 0.0
    ry = pr.eq_residual(x)
    rz, aux = [], []
    for b, s in zip(pr.blocks, it.s, strict=True):
        r, a = b.residual(x, s)
        rz.append(r)
        aux.append(a)
    xf = x[pr.free]
    Pfx = (Px - pr.Px_fixed)[pr.free] if pr.P is not None else np.zeros(xf.size)  # P_ff x_f
    xPffx = float(xf @ Pfx)
    qx = float(pr.qt_free @ xf)
    bz = sum(b.b_dot(z) for b, z in zip(pr.blocks, it.z, strict=True))
    if pr.p:
        bz += float(pr.f_tilde @ it.y)
    pcost_r = 0.5 * xPffx + qx
    dcost_r = -0.5 * xPffx - bz
    pcost, dcost = pcost_r + pr.const, dcost_r + pr.const
    gap_abs = abs(pcost_r - dcost_r)
    gap_rel = gap_abs / max(1.0, min(abs(pcost), abs(dcost)))
    norm_x = _amax(xf)
    norm_s = max([_amax(s) for s in it.s], default=0.0)
    norm_z = max([_amax(z) for z in it.z], default=0.0)
    res_p = max([_amax(r) for r in rz] + [_amax(ry)], default=0.0) / max(1.0, pr.norm_b + norm_x + norm_s)
    # ‖P x‖ as well: r_x = P x + q + Aᵀz sums terms of that size, so its rounding floor is eps·‖P x‖ (OSQP's
    # scaling). On the medial-axis bug the curved Hessian energy of near-degenerate faces reaches 4.6e6 × its median
    # diagonal entry: (P x)_i ≈ 3e8 cancelled to a residual floor of 3e-8, above tol, and every solve ended
    # "almost_optimal" and went to Clarabel (reliability sweep, 2026-12-02)
    norm_px = _amax(Pfx)
    dual_scale = max(1.0, pr.norm_q + norm_x + norm_z, norm_px)
    res_d = _amax(rx) / dual_scale
    # the same residual without ‖z‖ in its scale: a dual blown up along a direction that Aᵀ cancels
    # (edge bounds that are equalities in disguise: ‖z‖ ≈ 1e13, |r_x| ≈ 0.9 with res_d ≈ 1e-12)
    # must not pass for convergence
    res_d_plain = _amax(rx) / max(1.0, pr.norm_q + norm_x, norm_px)
    mu = sum(b.cone.dot(s, z) for b, s, z in zip(pr.blocks, it.s, it.z, strict=True)) / max(pr.nu, 1)
    info = {
        "iterations": iteration, "pcost": pcost, "dcost": dcost, "gap_abs": gap_abs, "gap_rel": gap_rel,
        "res_primal": res_p, "res_dual": res_d, "res_dual_plain": res_d_plain, "mu": mu, "step": step,
        "time": elapsed,
    }
    return Evaluation(info, rx, rz, ry, aux, Atz, Pfx, bz, qx, dual_scale, float(np.abs(xf).sum()))


def converged(info: dict, tol: float, settings: IPMSettings) -> bool:
    """``tol`` met by the residuals (the plain dual one at ``plain_dual_factor · tol``) and the gap (absolute or
    relative)."""
    return (info["res_primal"] < tol and info["res_dual"] < tol
            and info["res_dual_plain"] < settings.plain_dual_factor * tol
            and (info["gap_abs"] < tol or info["gap_rel"] < tol))


def almost(info: dict, tol: float, settings: IPMSettings) -> bool:
    """The reduced tolerances on one iterate's ``info``: :func:`converged` at ``reduced_factor · tol`` (residuals and
    gap, the dual residual also relative to ``max(1, ‖q‖ + ‖x‖)`` alone, ``res_dual_plain``)."""
    return converged(info, settings.reduced_factor * tol, settings)


def acceptable(info: dict, tol: float, settings: IPMSettings) -> bool:
    """:func:`converged` at ``accept_factor · tol``: an ``"almost_optimal"`` iterate the backend policy keeps."""
    return converged(info, settings.accept_factor * tol, settings)


def certificate(pr: Program, ev: Evaluation, settings: IPMSettings) -> str | None:
    """``"primal_infeasible"``, ``"dual_infeasible"`` or None (Clarabel's tests on the current iterate).

    For an infeasible problem z diverges along y with ``A_fᵀy = 0``, ``b̃ᵀy < 0``; for an unbounded one x_f
    diverges along d with ``P_ff d = 0``, ``−A_f d ∈ K``, ``q̃ᵀd < 0``, while the other terms stay bounded.
    """
    tol = settings.tol_infeas
    if ev.bz < 0 and _amax(ev.Atz) < -tol * ev.bz:
        return "primal_infeasible"
    if ev.qx < 0:
        viol = max([b.recession_violation(a) for b, a in zip(pr.blocks, ev.aux, strict=True)], default=0.0)
        if _amax(ev.Pfx) < -tol * ev.qx and viol < -tol * ev.qx:
            return "dual_infeasible"
    return None


def refine_target(ev: Evaluation, tol: float, settings: IPMSettings) -> float:
    """The solve error becomes the next dual residual: refine it below what the stopping test needs (and, in
    the end game, below what the gap test needs: ``xᵀr_x`` is part of the gap)."""
    info = ev.info
    target = settings.refine_fraction * tol * ev.dual_scale
    if min(info["gap_abs"], info["gap_rel"]) < settings.gap_aware_below * tol:
        target = min(target, settings.refine_fraction * tol * max(1.0, min(abs(info["pcost"]), abs(info["dcost"])))
                     / max(1.0, ev.abs_sum_x))
    return target


class BestIterate:
    """The iterate with the smallest merit ``max(res_p, res_d, min(gap_abs, gap_rel))`` so far."""

    def __init__(self) -> None:
        self.merit = np.inf
        self.x: np.ndarray | None = None
        self.info: dict | None = None
        self.since = 0

    def update(self, x: np.ndarray, info: dict, tol: float, settings: IPMSettings) -> bool:
        """Record ``x`` if better; True when nothing better came for ``stall_iterations`` iterations after an
        iterate within the reduced tolerances (rounding has the last word)."""
        merit = max(info["res_primal"], info["res_dual"], min(info["gap_abs"], info["gap_rel"]))
        if merit < self.merit:
            self.merit, self.x, self.info, self.since = merit, x.copy(), dict(info), 0
            return False
        self.since += 1
        return self.since >= settings.stall_iterations and self.info is not None and almost(self.info, tol,
                                                                                           settings)
