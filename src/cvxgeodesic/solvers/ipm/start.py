"""The starting point (:attr:`.settings.IPMSettings.init`): ``x``, then ``s`` and ``z``.

"graph" (the default): ``x`` the shortest-path field of the program's edge bounds (:mod:`.graph`) scaled towards
``x_F`` so that ``s`` is strictly feasible, the least-norm dual ``z = A y`` shifted cone by cone; "interior": the
same with the least-squares ``x`` of the ``W = I`` system (also the graph start's fallback); "mehrotra": the
least-squares ``x`` and the same ``z`` with Mehrotra's uniform shifts; "cvxopt": ``z = A x − b`` shifted into
the cone; "guess": the program's own guess field (:attr:`.program.Program.guess`, the order-2 programs' squared
Dijkstra distance) scaled towards ``x_F`` into the interior of the cones that allow a step of at least
:data:`PARTIAL_GUESS_MIN_STEP` towards it (the slacks of the others, such as the order-2 edge cones, which do not
hold at ``φ = 0``, shifted cone by cone into their cone), the least-norm ``z`` with Mehrotra's shift of ``z`` alone
("mehrotra" without a guess). The equality duals start at 0.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ...linalg import NotPositiveDefiniteError
from .cones import _amax
from .graph import graph_field
from .newton import LinearSystem, Trouble
from .program import Program
from .settings import IPMSettings
from .state import Iterate

__all__ = ["Start", "StartFailure", "starting_point"]


class Start:
    """The starting iterate and whether it came from the program's guess (the step then caps σ)."""

    def __init__(self, iterate: Iterate, from_guess: bool = False):
        self.iterate, self.from_guess = iterate, from_guess


class StartFailure(Exception):
    """The starting point's system could not be solved (a message for the "numerical_error" status)."""


def _min_eigenvalue(pr: Program, u: Sequence[np.ndarray]) -> float:
    return min([b.cone.min_eigenvalue(ub) for b, ub in zip(pr.blocks, u, strict=True)], default=np.inf)


def _add_identity(pr: Program, u: Sequence[np.ndarray], d: float) -> list[np.ndarray]:
    return [b.cone.add_identity(ub, d) for b, ub in zip(pr.blocks, u, strict=True)]


def interior_primal(pr: Program, x: np.ndarray, fraction: float) -> np.ndarray | None:
    """``x_F + α (x − x_F)`` with ``α = min(1, fraction · α_max)``, ``α_max`` the largest step from ``x_F`` (the
    fixed values, free part 0) that keeps ``s = b̃ − A x`` strictly in K on all of ``(0, α_max)``; ``None`` when no
    ``α > 0`` does.

    The least-squares ``x`` of the ``W = I`` system is usually infeasible (here: a few one-ring bounds next to
    the source), and shifting ``s`` into the cone then makes the primal residual as large as that violation.
    On the mesh problems ``x_F`` (all distances 0 but the fixed ones) is feasible, so the segment gives a strictly
    feasible point with zero primal residual. ``x_F`` may lie on the cones' boundary (the order-2 cones at
    ``φ = 0``, the bounds ``d ≥ 0`` next to the sources): the step is then the closed one
    (:meth:`~.cones.Cone.max_step_closed`).
    """
    s0 = [b.b_tilde for b in pr.blocks]
    step = np.where(pr.fixed, 0.0, x - pr.x_fixed)
    du = [-b.A(step) for b in pr.blocks]
    if _min_eigenvalue(pr, s0) > 0:
        alpha_max = min([b.cone.max_step(u, d) for b, u, d in zip(pr.blocks, s0, du, strict=True)], default=np.inf)
    else:
        alpha_max = min([float(b.cone.max_step_closed(u, d).min(initial=np.inf))
                         for b, u, d in zip(pr.blocks, s0, du, strict=True)], default=np.inf)
    if not alpha_max > 0:
        return None
    return pr.x_fixed + min(1.0, fraction * alpha_max) * step


def dual_shift_per_cone(pr: Program, z: Sequence[np.ndarray], st: IPMSettings) -> list[np.ndarray] | None:
    """Mehrotra's shift applied cone by cone: each cone's head raised by ``shift_factor`` × its own deficit
    ``‖body‖ − head`` (the inequalities shifted together by that factor × the most negative one), every margin
    then at least ``dual_floor`` × the mean head. ``None`` when ``z`` is zero.

    The dual of a mesh problem scales with the triangle areas; one uniform shift (Mehrotra's) sized by the
    largest cone overestimates the small cones' duals by orders of magnitude, and the first iterations go to
    shrinking that duality gap (bimba, QCQP-Hessian: starting gap 550 for an optimum of −3.4).
    """
    z = [b.cone.dual_shift(zb, st.shift_factor) for b, zb in zip(pr.blocks, z, strict=True)]
    mean_head = sum(b.cone.sum_heads(zb) for b, zb in zip(pr.blocks, z, strict=True)) / max(
        sum(b.count for b in pr.blocks), 1)
    if not (np.isfinite(mean_head) and mean_head > 0):
        return None
    floor = st.dual_floor * mean_head
    return [b.cone.floor(zb, floor) for b, zb in zip(pr.blocks, z, strict=True)]


def mehrotra_shift(pr: Program, s: Sequence[np.ndarray], z: Sequence[np.ndarray], st: IPMSettings,
                   shift_s: bool = True):
    """Mehrotra's (1992) starting-point heuristic adapted to cones: shift both s and z into the interior by
    ``shift_factor`` × their most negative eigenvalue, then add ½ sᵀz/Σ(heads of the other) to each; with
    ``shift_s=False`` a strictly feasible ``s`` is kept as it is and only ``z`` is shifted and balanced."""
    if shift_s:
        s = _add_identity(pr, s, max(-st.shift_factor * _min_eigenvalue(pr, s), 0.0))
    z = _add_identity(pr, z, max(-st.shift_factor * _min_eigenvalue(pr, z), 0.0))
    sz = sum(b.cone.dot(sb, zb) for b, sb, zb in zip(pr.blocks, s, z, strict=True))
    heads_s = sum(b.cone.sum_heads(sb) for b, sb in zip(pr.blocks, s, strict=True))
    heads_z = sum(b.cone.sum_heads(zb) for b, zb in zip(pr.blocks, z, strict=True))
    if sz <= 0 or heads_s <= 0 or heads_z <= 0:  # degenerate data: fall back to a unit shift
        sz, heads_s, heads_z = 1.0, 1.0, 1.0
    if shift_s:
        s = _add_identity(pr, s, 0.5 * sz / heads_z)
    return list(s), _add_identity(pr, z, 0.5 * sz / heads_s)


def shift_into_cone(pr: Program, u: Sequence[np.ndarray]) -> list[np.ndarray]:
    """CVXOPT's initialization: ``u + (1 + α)e`` when ``u`` is not strictly inside (``α`` = −min eigenvalue)."""
    worst = -_min_eigenvalue(pr, u)
    if worst >= -1e-8 * max([_amax(a) for a in u] + [1.0]):
        return _add_identity(pr, u, 1.0 + worst)
    return list(u)


def _least_norm_dual(pr: Program, ls: LinearSystem, f_y, x: np.ndarray, scalings) -> np.ndarray | None:
    """``y`` of the least-norm dual ``z = A y`` with ``A_fᵀz = −q̃ − P_ff x_f`` (``None`` when singular).

    ``z = A y`` is scaled like the true dual, unlike CVXOPT's ``z = A x − b`` (as large as the slacks, so the
    first iterations are spent shrinking a huge duality gap). ``f_y`` is the factor of ``A_fᵀA_f`` (the
    ``W = I`` matrix without P), or None to factorize it here; with a quadratic term it needs its own
    factorization and may be singular (a variable that only P couples): then CVXOPT's start is used.
    """
    Pfx0 = pr.Pmul(x) - pr.Px_fixed
    rhs_y = -(pr.q + pr.Px_fixed + Pfx0)
    rhs_y[pr.fixed] = 0.0
    target_y = 1e-12 * max(1e-300, float(np.abs(rhs_y).max()))
    if f_y is None:
        try:
            f_y = ls.factorize(ls.assemble(scalings, with_P=False))
        except NotPositiveDefiniteError:
            return None
    try:
        return ls.solve_refined(f_y, rhs_y, scalings, target_y, with_P=False)[0]
    except Trouble:
        return None


def _least_squares_x(pr: Program, ls: LinearSystem, st: IPMSettings, scalings) -> tuple[np.ndarray, object]:
    """``x`` of the ``W = I`` system and its factor (P-free when there is no P); :class:`StartFailure` when
    the system is singular or not finite."""
    try:
        f0 = ls.factorize(ls.assemble(scalings))
    except NotPositiveDefiniteError as exc:
        raise StartFailure("singular Newton matrix at the starting point") from exc
    rhs0 = pr.At([b.b_tilde for b in pr.blocks])  # A_fᵀb̃ − q̃
    if st.least_squares_cost:
        rhs0 -= pr.q + pr.Px_fixed
    rhs0[pr.fixed] = 0.0
    try:
        x = ls.solve_refined(f0, rhs0, scalings, 1e-12 * max(1.0, float(np.abs(rhs0).max())),
                             e=pr.f_tilde)[0] + pr.x_fixed
    except Trouble as exc:
        raise StartFailure(str(exc)) from exc
    return x, f0


#: The guess start's segment from ``x_F`` is bounded by the cones whose own largest step towards the guess is at
#: least this: the others (those that do not hold at ``x_F``, step 0, and the few that the guess violates most)
#: are left out, their slacks shifted cone by cone. Measured 2026-12-02 (order 2, source vertex 0): a handful of
#: cones bounded the whole segment (armadillo: 36 of 259K cones below 0.1, the lowest 0.015, the median 0.93), so
#: the start took 1.3 % of the way to the guess; leaving them out took it 9.6 % of the way and armadillo from 27 to
#: 24 iterations, fandisk from 24 to 21. Before, a start that left out whole blocks (the edge cones) was declined
#: below a step of 0.1, where it cost iterations (the 1.1M-face subdivided bunny 127 against 56).
PARTIAL_GUESS_MIN_STEP = 0.1
#: ... and each left-out cone's margin after its shift, relative to its largest slack entry.
_LEFT_OUT_MARGIN = 1e-2


def guess_primal(pr: Program, fraction: float) -> tuple[np.ndarray, list[np.ndarray]] | None:
    """The start towards the program's guess (order 2: the squared Dijkstra distance): ``(x, left_out)``,
    ``x = x_F + α (guess − x_F)`` with ``α = min(1, fraction · α_max)``, ``α_max`` the largest step that keeps the
    slacks of the cones that bound it strictly in their cones, ``left_out[b]`` (count,) bool the cones of block
    ``b`` that do not bound it (their own step is below :data:`PARTIAL_GUESS_MIN_STEP`; their slacks are left to
    a shift). ``None`` without a guess, when the guess breaks an equality, or when no cone reaches that step."""
    g = pr.guess
    if g is None:
        return None
    if pr.p and np.abs(pr.eq_residual(g)).max() > 1e-9 * max(1.0, float(np.abs(g).max())):
        return None
    step = np.where(pr.fixed, 0.0, g - pr.x_fixed)
    reach = [np.asarray(b.cone.max_step_closed(b.b_tilde, -b.A(step)), dtype=np.float64).reshape(b.count)
             for b in pr.blocks]
    left_out = [r < PARTIAL_GUESS_MIN_STEP for r in reach]
    if all(out.all() for out in left_out):
        return None
    alpha_max = min(float(r[~out].min(initial=np.inf)) for r, out in zip(reach, left_out, strict=True))
    return pr.x_fixed + min(1.0, fraction * alpha_max) * step, left_out


def _primal(pr: Program, ls: LinearSystem, st: IPMSettings, scalings) -> tuple[np.ndarray, bool, object]:
    """``(x, interior, f_y)``: the primal start, whether its slacks are strictly feasible as they are, and the
    P-free ``W = I`` factor if one was made (else None)."""
    if st.init == "graph" and (xg := graph_field(pr)) is not None:
        x_int = interior_primal(pr, xg, st.interior_fraction)
        if x_int is not None:
            return x_int, True, None  # no least-squares system to solve
    x, f0 = _least_squares_x(pr, ls, st, scalings)
    f_y = f0 if pr.P is None else None
    if st.init in ("interior", "graph") and (x_int := interior_primal(pr, x, st.interior_fraction)) is not None:
        return x_int, True, f_y
    return x, False, f_y


def starting_point(pr: Program, ls: LinearSystem, st: IPMSettings) -> Start:
    """The starting iterate; :class:`StartFailure` when the ``W = I`` system is singular or not finite."""
    scalings = pr.identity_scalings()
    y0 = np.zeros(pr.p)
    if st.init == "guess" and (guess := guess_primal(pr, st.interior_fraction)) is not None:
        x, left_out = guess
        s = [b.slack(x, pr.x_fixed) for b in pr.blocks]
        s = [b.cone.shift_cones(sb, out, st.shift_factor, _LEFT_OUT_MARGIN) if out.any() else sb
             for b, sb, out in zip(pr.blocks, s, left_out, strict=True)]
        y = _least_norm_dual(pr, ls, None, x, scalings)
        if y is not None:
            s, z = mehrotra_shift(pr, s, [b.A(y) for b in pr.blocks], st, shift_s=False)
            return Start(Iterate(x, s, z, y0), from_guess=True)
    x, interior, f_y = _primal(pr, ls, st, scalings)
    s = [b.slack(x, pr.x_fixed) for b in pr.blocks]
    y = _least_norm_dual(pr, ls, f_y, x, scalings) if st.init != "cvxopt" else None
    if y is not None:
        z = [b.A(y) for b in pr.blocks]
        shifted = dual_shift_per_cone(pr, z, st) if interior else None
        if shifted is not None:
            z = shifted  # s is strictly interior already
        else:
            s, z = mehrotra_shift(pr, s, z, st)
    else:
        z = [-sb for sb in s]
        s, z = shift_into_cone(pr, s), shift_into_cone(pr, z)
    return Start(Iterate(x, list(s), list(z), y0))
