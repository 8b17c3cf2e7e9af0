"""A positive-semidefiniteness check of a sparse symmetric matrix by one shifted Cholesky factorization."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from . import symbolic
from .base import NotPositiveDefiniteError

__all__ = ["is_positive_semidefinite"]


def is_positive_semidefinite(Q: sp.spmatrix, *, rel_shift: float = 1e-9, backend: str = "auto") -> bool | None:
    """Whether a symmetric sparse matrix is positive semidefinite, by one Cholesky factorization.

    ``Q + rel_shift · max|diag Q| · I`` is factored; a failed factorization (a zero or
    negative pivot) means ``Q`` has an eigenvalue below ``-rel_shift · max|diag Q|``.
    The ordering is AMD: for a single factorization its quick analysis beats METIS's
    smaller fill (measured on bunny's Hessian energy, 35K vertices: PARDISO with AMD
    0.12 s in all, with METIS 0.28 s; CHOLMOD 0.20 s and 0.49 s).

    Parameters
    ----------
    Q : (n, n) scipy.sparse matrix
        Symmetric.
    rel_shift : float
        Relative diagonal shift that absorbs rounding in the zero eigenvalues.
    backend : {"auto", "pardiso", "cholmod"}
        ``"auto"``: PARDISO when installed, else CHOLMOD.

    Returns
    -------
    bool or None
        ``None`` when neither PARDISO nor CHOLMOD is installed (the check is skipped).
    """
    if backend not in ("auto", "pardiso", "cholmod"):
        raise ValueError(f"backend must be 'auto', 'pardiso' or 'cholmod', got {backend!r}")
    if backend == "auto":
        found = [name for name in ("pardiso", "cholmod") if symbolic.available(name)]
        if not found:
            return None
        backend = found[0]
    n = Q.shape[0]
    tri = sp.tril(sp.coo_matrix(Q))
    # an explicit (zero) diagonal: the symbolic analysis wants a full diagonal, e.g. for unreferenced vertices
    lower = sp.csc_matrix(
        (np.r_[tri.data, np.zeros(n)], (np.r_[tri.row, np.arange(n)], np.r_[tri.col, np.arange(n)])), shape=(n, n)
    )
    lower.sum_duplicates()
    lower.sort_indices()
    scale = float(np.abs(Q.diagonal()).max()) if Q.shape[0] else 0.0
    try:
        symbolic.SymbolicCholesky(lower, backend=backend, ordering="amd", mode="supernodal").factorize(
            lower.data, beta=rel_shift * scale)
    except NotPositiveDefiniteError:
        return False
    return True
