"""The structured interior-point solver for the mesh problems, split along its seams.

================  ===================================================================================
module            owns
================  ===================================================================================
``solver``        :class:`InteriorPointSolver` (pattern, re-analysis, threads, the loop, the result)
``settings``      :class:`IPMSettings`: every tuning constant, its default and why
``program``       :class:`~.program.Program`: the problem with the fixed variables eliminated, its
                  blocks, the reduced Newton matrix (operator and assembly)
``blocks``        constraint blocks (cone type + linear map): mesh triangle cones, pair inequalities,
                  a general sparse block
``cones``         the cone-block protocol: SOC(k), nonnegative orthant
``state``         :class:`~.state.Iterate`, :class:`~.state.Direction`
``start``         the starting point
``algorithm``     one iteration (predictor, corrector, Gondzio correctors, refinement, step lengths)
``newton``        the reduced system's factorization and solves, the Newton direction
``residuals``     residuals, stopping rule, certificates, the best iterate
``_kernels``      compiled (Numba) per-cone loops of SOC(3)
================  ===================================================================================
"""

from .program import problem_pattern
from .settings import IPMSettings
from .solver import InteriorPointSolver

__all__ = ["IPMSettings", "InteriorPointSolver", "problem_pattern"]
