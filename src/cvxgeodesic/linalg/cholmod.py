"""CHOLMOD through scikit-sparse (``sksparse.cholmod``): ``analyze`` once, ``cholesky_inplace`` per matrix.

Fast; needs ``pip install scikit-sparse==0.4.16`` on top of Debian's ``libsuitesparse-dev``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.sparse as sp

from .base import NotPositiveDefiniteError

try:  # optional dependency
    from sksparse import cholmod as _cholmod
except ImportError:  # pragma: no cover - exercised by forcing backend="scipy" in the tests
    _cholmod = None

__all__ = ["CholmodBackend", "cholmod_available"]


def cholmod_available() -> bool:
    """True when ``sksparse.cholmod`` could be imported."""
    return _cholmod is not None


class CholmodBackend:
    """CHOLMOD's analysis of one pattern (ordering ``"metis"``, ``"nesdis"``, ``"amd"``, ``"best"``, ...;
    ``mode`` ``"supernodal"`` or ``"simplicial"``); see :class:`~cvxgeodesic.linalg.base.Backend`."""

    name = "cholmod"

    def __init__(self, indptr: np.ndarray, indices: np.ndarray, diag_positions: np.ndarray, *, ordering: str,
                 mode: str):
        if _cholmod is None:
            raise ImportError("scikit-sparse (CHOLMOD) is not installed")
        n = indptr.size - 1
        self.mode = mode
        # The matrix handed to CHOLMOD: its index arrays are ours, only .data changes.
        self._matrix = sp.csc_matrix((np.ones(indices.size), indices, indptr), shape=(n, n))
        self.factor = _cholmod.analyze(self._matrix, mode=mode, ordering_method=ordering)
        self.n_analyses = 1

    def factorize(self, data: np.ndarray, beta: float) -> Callable[[np.ndarray], np.ndarray]:
        self._matrix.data = data
        try:
            self.factor.cholesky_inplace(self._matrix, beta=beta)
        except _cholmod.CholmodNotPositiveDefiniteError as exc:
            raise NotPositiveDefiniteError(str(exc)) from None
        # simplicial CHOLMOD computes LDLᵀ, which does not fail on indefinite matrices
        if self.mode == "simplicial" and not np.all(self.factor.D() > 0):
            raise NotPositiveDefiniteError("LDLᵀ pivot <= 0: matrix not positive definite")
        return self.factor.solve_A
