"""Sparse symmetric positive definite linear algebra: fixed-pattern Cholesky behind one small interface.

A low layer: it imports NumPy, SciPy and the optional backend libraries only (no Numba, nothing of
:mod:`cvxgeodesic.solvers`), so that the operators may use it.

- :func:`analyse` (``pattern → SymbolicCholesky``), :meth:`SymbolicCholesky.factorize`
  (``values → Factor``), :meth:`Factor.solve` (``b → K⁻¹ b``): :mod:`.symbolic` chooses the
  backend (PARDISO → CHOLMOD → SuperLU) and owns the pattern, positions and counters.
- One module per backend: :mod:`.pardiso` (MKL, ctypes), :mod:`.cholmod` (scikit-sparse),
  :mod:`.superlu` (SciPy); their common protocol and :class:`NotPositiveDefiniteError` in :mod:`.base`.
- :func:`is_positive_semidefinite` (:mod:`.psd`), the check the smoothness energies use;
- :func:`factor_matrix`: one SPD matrix analysed and factorized once (the heat method, ridge rounding).
"""

from .base import Factor, NotPositiveDefiniteError
from .cholmod import cholmod_available
from .psd import is_positive_semidefinite
from .symbolic import BACKENDS, SymbolicCholesky, analyse, choose_backend, factor_matrix, pardiso_available

__all__ = ["BACKENDS", "Factor", "NotPositiveDefiniteError", "SymbolicCholesky", "analyse", "choose_backend",
           "cholmod_available", "factor_matrix", "is_positive_semidefinite", "pardiso_available"]
