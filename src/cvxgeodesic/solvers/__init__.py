"""Backends that solve :class:`~cvxgeodesic.solvers.problem.ConicProblem`."""

from .clarabel_backend import solve_clarabel
from .ipm import InteriorPointSolver
from .problem import BackendResult, ConicProblem, kkt_pattern

__all__ = ["BackendResult", "ConicProblem", "InteriorPointSolver", "kkt_pattern", "solve_clarabel"]
