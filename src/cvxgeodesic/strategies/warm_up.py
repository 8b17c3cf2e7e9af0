"""Load (or, after an install, compile) the interior-point solver's kernels before a timing.

It builds a few small programs with the problem builders and solves them, so it sits above both: the solver
(:mod:`cvxgeodesic.solvers.ipm`) knows the conic program, not the builders that make one.
"""

from __future__ import annotations

import numpy as np

from ..mesh.generate import icosphere
from ..problems.conic import clique_pattern, kkt_pattern
from ..problems.formulations import MeshOperators, build_problem, smoothness_weight
from ..problems.squared_distance import SquaredDistanceBuilder
from ..solvers.ipm.settings import ORDER2
from ..solvers.ipm.solver import InteriorPointSolver

__all__ = ["warm_up"]


def warm_up() -> None:
    """Compile (first run after an install: the kernels of both orders, about 5 s by :data:`cvxgeodesic._jit.NOTICE`'s
    estimates) or load (later, under a second) the solver's kernels.

    The first :meth:`~cvxgeodesic.solvers.ipm.InteriorPointSolver.solve` of a process does this by itself; call it
    beforehand to keep that one-time cost out of a timing. ``make setup`` runs it once so that the on-disk cache
    exists.
    """
    mesh = icosphere(1)
    ops = MeshOperators(mesh)
    for method in ("qclp", "lclp", "qcqp-hessian"):
        p = build_problem(ops, np.array([0]), method, smoothness_weight(mesh, 1.0))
        InteriorPointSolver(kkt_pattern(mesh.n_vertices, mesh.F, mesh.edges, p.P)).solve(p)
    builder = SquaredDistanceBuilder(mesh)  # order 2: the SOC(4) clique kernels
    space = builder.space
    InteriorPointSolver(clique_pattern(space.n_dofs, [space.cell_dofs]), settings=ORDER2).solve(
        builder.build(np.array([0])).problem)
