"""Equilibration of a program before the interior-point iterations (one Ruiz pass), for the order-2 programs.

The order-2 cones mix rows of very different sizes (``φ`` itself, its gradient scaled by each sample's expected
distance, 1-D cones along short edges): the columns are scaled by the square root of their largest cone-row entry,
then every cone by its largest entry (a positive multiple of a cone vector stays in the cone), and the objective to
∞-norm 1. The scaled problem has the same solution ``x = D x̃``; the order-1 programs are solved as they are.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.sparse as sp

from ..problem import ConeGroup, ConicProblem, Equalities, PairInequalities

__all__ = ["equilibrate"]


def equilibrate(problem: ConicProblem) -> tuple[ConicProblem, np.ndarray]:
    """The scaled problem and the column scaling ``D`` (n,): its solution ``x̃`` gives ``x = D x̃``.

    Parameters
    ----------
    problem : ConicProblem

    Returns
    -------
    scaled : ConicProblem
    D : (n,) float ndarray
        1 on the fixed variables and on variables in no cone.
    """
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
