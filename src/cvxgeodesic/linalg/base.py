"""What every linear-algebra backend shares: the error, the factor handle and the backend protocol.

A backend factorizes symmetric positive definite matrices that all share one sparsity pattern, given
as the lower-triangular CSC structure (``indptr``, ``indices``; sorted row indices, full diagonal):
its constructor does the symbolic analysis, :meth:`Backend.factorize` a numeric factorization of new
values. :class:`~cvxgeodesic.linalg.symbolic.SymbolicCholesky` chooses the backend and keeps the
pattern, positions and counters; backends know nothing of one another.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

import numpy as np
import scipy.sparse as sp

__all__ = ["Backend", "Factor", "NotPositiveDefiniteError", "symmetric_matrix"]


class NotPositiveDefiniteError(ArithmeticError):
    """The matrix handed to a numeric factorization is not (numerically) positive definite."""


class Factor:
    """One numeric factorization: ``factor.solve(b)`` (or ``factor(b)``) returns ``K⁻¹ b``.

    Parameters
    ----------
    solve : callable
        ``solve(b)`` for ``b`` of shape (n,) or (n, r), returning an array of the same shape.
    """

    __slots__ = ("solve",)

    def __init__(self, solve: Callable[[np.ndarray], np.ndarray]):
        self.solve = solve

    def __call__(self, b: np.ndarray) -> np.ndarray:
        return self.solve(b)


class Backend(Protocol):
    """A sparse Cholesky backend analysed once for one pattern (its constructor), then factorized many times.

    Constructor: ``Backend(indptr, indices, diag_positions, *, ordering, mode)`` with the lower-triangular CSC
    structure ``indptr`` (n + 1,), ``indices`` (nnz,) (int32) and the positions of the diagonal entries
    ``diag_positions`` (n,).
    """

    name: str
    #: symbolic analyses the constructor ran (0 for a backend that analyses at every factorization)
    n_analyses: int

    def factorize(self, data: np.ndarray, beta: float) -> Callable[[np.ndarray], np.ndarray]:
        """Factorize ``K + beta·I`` (``data`` (nnz,): the lower triangle of ``K``); return its solve.

        Raises :class:`NotPositiveDefiniteError` when the matrix is not numerically positive definite.
        """
        ...


def symmetric_matrix(indptr: np.ndarray, indices: np.ndarray, data: np.ndarray) -> sp.csc_matrix:
    """The full symmetric (n, n) CSC matrix whose lower triangle is ``data`` on the structure (indptr, indices)."""
    n = indptr.size - 1
    Lw = sp.csc_matrix((np.asarray(data, dtype=float), indices, indptr), shape=(n, n))
    return (Lw + sp.tril(Lw, -1).T).tocsc()
