"""SciPy's SuperLU (``scipy.sparse.linalg.splu``) with a symmetric minimum-degree column ordering.

Always available, several times slower than PARDISO or CHOLMOD, and it redoes its ordering on every
factorization (there is no separate analysis to keep).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .base import NotPositiveDefiniteError, symmetric_matrix

__all__ = ["SuperLUBackend"]


class SuperLUBackend:
    """SuperLU on the full symmetric matrix (``ordering`` and ``mode`` are ignored); see
    :class:`~cvxgeodesic.linalg.base.Backend`."""

    name = "scipy"
    n_analyses = 0

    def __init__(self, indptr: np.ndarray, indices: np.ndarray, diag_positions: np.ndarray, *, ordering: str,
                 mode: str):
        self._indptr, self._indices = indptr, indices

    def factorize(self, data: np.ndarray, beta: float) -> Callable[[np.ndarray], np.ndarray]:
        K = symmetric_matrix(self._indptr, self._indices, data)
        if beta:
            K = (K + beta * sp.identity(K.shape[0], format="csc")).tocsc()
        try:
            lu = spla.splu(K, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
        except RuntimeError as exc:  # "Factor is exactly singular"
            raise NotPositiveDefiniteError(str(exc)) from None
        if np.any(lu.U.diagonal() <= 0):
            raise NotPositiveDefiniteError("SuperLU pivot <= 0: matrix not positive definite")
        return lu.solve
