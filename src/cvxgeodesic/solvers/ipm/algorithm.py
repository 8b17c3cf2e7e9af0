"""One interior-point iteration: NT scaling, predictor, Mehrotra corrector, Gondzio's correctors, refinement.

The method is the infeasible-start primal–dual path-following algorithm of CVXOPT's ``coneqp``
(L. Vandenberghe, "The CVXOPT linear and quadratic cone program solvers", 2010) with Nesterov–Todd
scaling and Mehrotra's predictor–corrector, plus Gondzio's multiple centrality correctors (J. Gondzio,
"Multiple centrality corrections in a primal-dual method for linear programming", 1996, applied to the
eigenvalues of the cone Jordan products; weighted as in Colombo & Gondzio 2008) and, without a quadratic
term, separate primal and dual step lengths. Every per-cone operation is a method of the block's cone
(:mod:`.cones`); every product with ``A`` a method of the block (:mod:`.blocks`).
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import partial

import numpy as np

from .cones import Scaling
from .newton import LinearSystem, Residuals, newton
from .program import Program
from .residuals import Evaluation
from .settings import CORRECTORS_LARGE, IPMSettings
from .state import Direction, Iterate

__all__ = ["Stepper"]


class Stepper:
    """The iteration of one solve: ``stepper.step(it, ev, target) -> (next iterate, step length)``.

    Parameters
    ----------
    pr : Program
    ls : LinearSystem
    settings : IPMSettings
    counters : dict
        ``correctors``, ``correctors_accepted``, ``refinement_steps``, ``corrector_escalations``, accumulated in
        place; ``max_correctors`` (the per-iteration count chosen for this program's pattern) is set here.
    sigma_cap : float
        Upper bound of Mehrotra's centring parameter σ (``IPMSettings.sigma_cap_guess`` after a start from a
        guess, else 1).

    Raises (from :meth:`step`) NotPositiveDefiniteError when the Newton matrix cannot be factorized and
    :class:`~.newton.Trouble` when a solve is not finite.
    """

    def __init__(self, pr: Program, ls: LinearSystem, settings: IPMSettings, counters: dict,
                 sigma_cap: float = 1.0):
        self.pr, self.ls, self.st, self.counters = pr, ls, settings, counters
        self.sigma_cap = sigma_cap
        # Without a quadratic term the primal and dual steps decouple (as in LP interior-point codes):
        # separate step lengths cut the iteration count on these highly degenerate problems.
        self.separate = pr.P is None and settings.separate_steps
        self.no_resid = Residuals.zero(pr)  # correctors only change the complementarity right-hand side
        self.max_correctors = settings.correctors_for(ls.chol.nnz)
        counters["max_correctors"] = self.max_correctors
        counters.setdefault("corrector_escalations", 0)

    def _steps(self, it: Iterate, ds: Sequence[np.ndarray], dz: Sequence[np.ndarray], fraction: float
               ) -> tuple[float, float]:
        """Primal and dual step lengths: ``fraction`` of the step to the boundary, at most 1 (equal unless
        separate steps are on)."""
        blocks = self.pr.blocks
        ap = min([b.cone.max_step(s, d) for b, s, d in zip(blocks, it.s, ds, strict=True)], default=np.inf)
        ad = min([b.cone.max_step(z, d) for b, z, d in zip(blocks, it.z, dz, strict=True)], default=np.inf)
        step_p, step_d = min(1.0, fraction * ap), min(1.0, fraction * ad)
        if not self.separate:
            step_p = step_d = min(step_p, step_d)
        return step_p, step_d

    def step(self, it: Iterate, ev: Evaluation, target: float) -> tuple[Iterate, float]:
        pr, st = self.pr, self.st
        mu = ev.info["mu"]
        scalings = [b.cone.scaling(s, z) for b, s, z in zip(pr.blocks, it.s, it.z, strict=True)]
        f = self.ls.factorize(self.ls.assemble(scalings))
        lin = partial(self.ls.solve_kkt, f)
        resid = Residuals(pr, scalings, ev.rx, ev.rz, ev.ry)

        # ---- predictor (affine scaling): d_s = −λ∘λ, so W⁻¹(λ \ d_s) = −W⁻¹λ = −z ----
        aff = newton(pr, lin, scalings, resid, [-z for z in it.z])
        ap_aff, ad_aff = self._steps(it, aff.ds, aff.dz, 1.0)
        gap = mu * max(pr.nu, 1)
        sz_aff = sum(b.cone.dot(s + ap_aff * ds, z + ad_aff * dz)
                     for b, s, z, ds, dz in zip(pr.blocks, it.s, it.z, aff.ds, aff.dz, strict=True))
        sigma = min(1.0, max(0.0, sz_aff / gap if gap > 0 else 0.0)) ** st.sigma_exp
        sigma = min(sigma, self.sigma_cap)

        # ---- combined step: d_s = −λ∘λ − (W⁻¹Δs_a)∘(WΔz_a) + σμe ----
        if not st.mehrotra_correction:
            aff = Direction(aff.dx, [np.zeros_like(d) for d in aff.ds], [np.zeros_like(d) for d in aff.dz], aff.rhs,
                            aff.dy, aff.ey)
        wu = [b.cone.mehrotra(sc, ds, dz, z, sigma * mu)
              for b, sc, ds, dz, z in zip(pr.blocks, scalings, aff.ds, aff.dz, it.z, strict=True)]
        d = newton(pr, lin, scalings, resid, wu)
        step_p, step_d = self._steps(it, d.ds, d.dz, st.step)
        d, step_p, step_d = self._correct(it, scalings, lin, d, step_p, step_d, sigma, mu)
        d, step_p, step_d = self._refine(it, scalings, f, d, step_p, step_d, target)
        return it.step(d, step_p, step_d), min(step_p, step_d)

    def _correct(self, it: Iterate, scalings: Sequence[Scaling], lin, d: Direction, step_p: float, step_d: float,
                 sigma: float, mu: float) -> tuple[Direction, float, float]:
        """Gondzio's multiple centrality correctors: cheap extra solves with the same factor, each tried at the
        weights ``corrector_weights`` and kept when it lengthens the step by 0.01 at least."""
        pr, st = self.pr, self.st
        budget = self.max_correctors
        if st.max_correctors is None and min(step_p, step_d) < st.short_step and budget < CORRECTORS_LARGE:
            budget = CORRECTORS_LARGE  # a hard iteration: centrality is worth more than the solves
            self.counters["corrector_escalations"] += 1
        for _ in range(budget):
            if min(step_p, step_d) >= 0.995:
                break
            tp, td = min(1.0, st.gz_a * step_p + st.gz_b), min(1.0, st.gz_a * step_d + st.gz_b)
            lo, hi = st.beta_min * sigma * mu, st.beta_max * sigma * mu
            wu = [b.cone.gondzio(sc, s, ds, tp, z, dz, td, lo, hi)
                  for b, sc, s, ds, z, dz in zip(pr.blocks, scalings, it.s, d.ds, it.z, d.dz, strict=True)]
            c = newton(pr, lin, scalings, self.no_resid, wu)
            self.counters["correctors"] += 1
            best = None
            for wgt in st.corrector_weights:
                nds = [a + wgt * b for a, b in zip(d.ds, c.ds, strict=True)]
                ndz = [a + wgt * b for a, b in zip(d.dz, c.dz, strict=True)]
                np_, nd_ = self._steps(it, nds, ndz, st.step)
                if best is None or min(np_, nd_) > best[0]:
                    best = (min(np_, nd_), wgt, np_, nd_, nds, ndz)
                if min(np_, nd_) >= min(step_p, step_d) + 0.01:
                    break  # the largest weight that helps
            if best is None or best[0] < min(step_p, step_d) + 0.01:
                break
            _, wgt, step_p, step_d, nds, ndz = best
            d = Direction(d.dx + wgt * c.dx, nds, ndz, d.rhs + wgt * c.rhs, d.dy + wgt * c.dy, d.ey)
            self.counters["correctors_accepted"] += 1
        return d, step_p, step_d

    def _refine(self, it: Iterate, scalings: Sequence[Scaling], f, d: Direction, step_p: float, step_d: float,
                target: float) -> tuple[Direction, float, float]:
        """Iterative refinement of the final direction (its Δx error becomes the next dual residual); every
        direction above is linear in Δx, so one correction δ updates them all."""
        ds, dz = list(d.ds), list(d.dz)

        def refine_blocks(delta: np.ndarray) -> None:
            for i, (b, sc) in enumerate(zip(self.pr.blocks, scalings, strict=True)):
                ds[i], dz[i] = b.refine(delta, sc, ds[i], dz[i])

        before = self.counters["refinement_steps"]
        dx, dy = self.ls.refine(f, d.dx, d.dy, d.rhs, d.ey, scalings, target, on_step=refine_blocks)
        if self.counters["refinement_steps"] > before:
            step_p, step_d = self._steps(it, ds, dz, self.st.step)
        return Direction(dx, ds, dz, d.rhs, dy, d.ey), step_p, step_d
