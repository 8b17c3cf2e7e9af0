"""Backends that solve :class:`~cvxgeodesic.problems.conic.ConicProblem`.

:class:`InteriorPointSolver` is imported on first use (PEP 562): its compiled kernels need Numba, and
``import cvxgeodesic`` must work without it (the API then solves with Clarabel and says so in the notes).
"""

from typing import Any

from ..problems.conic import BackendResult, ConicProblem, kkt_pattern
from .clarabel_backend import solve_clarabel

__all__ = ["BackendResult", "ConicProblem", "InteriorPointSolver", "kkt_pattern", "solve_clarabel"]


def __getattr__(name: str) -> Any:
    if name == "InteriorPointSolver":
        from .ipm import InteriorPointSolver

        return InteriorPointSolver
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
