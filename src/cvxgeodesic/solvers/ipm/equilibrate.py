"""Equilibration of a program before the interior-point iterations (one Ruiz pass), for the order-2 programs.

The order-2 cones mix rows of very different sizes (``φ`` itself, its gradient scaled by each sample's expected
distance, 1-D cones along short edges): the columns are scaled by the square root of their largest cone-row entry,
then every cone by its largest entry (a positive multiple of a cone vector stays in the cone), and the objective to
∞-norm 1. The scaled problem has the same solution ``x = D x̃``; the order-1 programs are solved as they are.

Before that pass, a variable whose starting guess exceeds :data:`GUESS_SPREAD` × the median guess is divided by
that excess: ``φ = d²`` squares the spread of a travel cost, and with one vertex of cost 1e5 on icosphere(2) the
guess reached 1.3e7 against a median of 4, the iterates ``x̃`` reached 4e8 and the unboundedness test (relative to
``q̃ᵀx̃``) certified a bounded program as unbounded after 6 iterations (issue 41; with the division: optimal in 12–14
iterations at costs 1e5 and 1e6). Programs whose guesses stay within the spread are scaled as before.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.sparse as sp

from ...problems.conic import ConeGroup, ConicProblem, Equalities, PairInequalities

__all__ = ["GUESS_SPREAD", "equilibrate"]

#: A guess above this many times the median guess of the free variables is scaled down to it (see above). Without a
#: medium the guess's ``max / median`` was 3.9–7.5 (the largest over 20 random vertex sources on each of spot,
#: bunny_7k, fandisk, kitten, camelhead, fertility, max_planck, beetle and lucy_20k, 2026-12-06), so those programs
#: are not changed.
GUESS_SPREAD = 100.0


def equilibrate(problem: ConicProblem) -> tuple[ConicProblem, np.ndarray]:
    """The scaled problem and the column scaling ``D`` (n,): its solution ``x̃`` gives ``x = D x̃``.

    Parameters
    ----------
    problem : ConicProblem

    Returns
    -------
    scaled : ConicProblem
    D : (n,) float ndarray
        1 on the fixed variables (and on variables in no cone whose guess is within the spread).
    """
    pre = _guess_scaling(problem)
    if pre is not None:
        problem = _scale_columns(problem, pre)
    scaled, D = _ruiz(problem)
    return scaled, D if pre is None else D * pre


def _guess_scaling(problem: ConicProblem) -> np.ndarray | None:
    """``max(1, guess / (GUESS_SPREAD · median guess))`` on the free variables, or None when that is all 1."""
    g = problem.guess
    if g is None:
        return None
    free = ~problem.fixed_mask & (g > 0)
    if not free.any():
        return None
    excess = g / (GUESS_SPREAD * float(np.median(g[free])))
    if not np.any(excess[free] > 1.0):
        return None
    return np.where(free, np.maximum(1.0, excess), 1.0)


def _scale_columns(problem: ConicProblem, D: np.ndarray) -> ConicProblem:
    """The problem in ``x̃`` with ``x = D x̃`` (cones, objective, inequalities, equalities, guess, fixed values)."""
    Dm = sp.diags(D)
    groups = [ConeGroup(g.dofs, g.G * D[g.dofs][:, None, :], g.h) for g in problem.cones]
    P = None if problem.P is None else sp.csc_matrix(Dm @ problem.P @ Dm)
    ineq = problem.ineq
    ineq = PairInequalities(ineq.vertices, ineq.coeffs * D[ineq.vertices], ineq.rhs)
    eq = None if problem.eq is None else Equalities(sp.csr_matrix(problem.eq.E @ Dm), problem.eq.f)
    guess = None if problem.guess is None else problem.guess / D
    return dataclasses.replace(problem, cones=groups, q=problem.q * D, P=P, ineq=ineq, eq=eq, guess=guess,
                               fixed_values=problem.fixed_values / D)


def _ruiz(problem: ConicProblem) -> tuple[ConicProblem, np.ndarray]:
    """One Ruiz pass (the module's description)."""
    n = problem.n
    colmax = np.zeros(n)
    for g in problem.cones:
        if g.count:
            np.maximum.at(colmax, g.dofs.ravel(), np.abs(g.G).max(axis=1).ravel())
    D = np.where((colmax > 0) & ~problem.fixed_mask, 1.0 / np.sqrt(np.where(colmax > 0, colmax, 1.0)), 1.0)
    groups = []
    for g in problem.cones:
        G = g.G * D[g.dofs][:, None, :]
        rs = 1.0 / np.maximum(np.abs(G).max(axis=(1, 2)), np.abs(g.h).max(axis=1))  # (k,): each cone's row scale
        groups.append(ConeGroup(g.dofs, G * rs[:, None, None], g.h * rs[:, None]))
    qD = problem.q * D
    scale = max(float(np.abs(qD).max(initial=0.0)), 1e-300)
    Dm = sp.diags(D)
    P = None if problem.P is None else sp.csc_matrix(Dm @ problem.P @ Dm) / scale
    ineq = problem.ineq
    ineq = PairInequalities(ineq.vertices, ineq.coeffs * D[ineq.vertices], ineq.rhs)
    eq = None if problem.eq is None else Equalities(sp.csr_matrix(problem.eq.E @ Dm), problem.eq.f)
    guess = None if problem.guess is None else problem.guess / D
    scaled = dataclasses.replace(problem, cones=groups, q=qD / scale, P=P, ineq=ineq, eq=eq, guess=guess,
                                 fixed_values=problem.fixed_values / D)
    return scaled, D
