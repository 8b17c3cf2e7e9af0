"""Sparse Cholesky with one symbolic analysis reused for many numeric factorizations: the backend choice.

The interior-point solvers factorize a sequence of SPD matrices that all share
one sparsity pattern (the mesh's :func:`~cvxgeodesic.problems.conic.kkt_pattern`).
:func:`analyse` (or :class:`SymbolicCholesky`) analyses that pattern once
(fill-reducing ordering, supernodal structure) and then only does numeric
factorizations: the caller fills a data array aligned with the pattern's
lower-triangular CSC storage, and :meth:`SymbolicCholesky.factorize` returns a
:class:`~cvxgeodesic.linalg.base.Factor`.

Backends (one module each; the choice and the fallback are here only)
--------------------------------------------------------------------
``"pardiso"``
    Intel oneMKL PARDISO (:mod:`.pardiso`, the ``mkl`` wheel): analysis once, then
    numeric factorizations only. The fastest here: 3–5× CHOLMOD's speed on the mesh
    Newton matrices (see that module).
``"cholmod"``
    CHOLMOD through scikit-sparse (:mod:`.cholmod`).
``"scipy"``
    SciPy's SuperLU (:mod:`.superlu`). Always available, several times slower.
"""

from __future__ import annotations

import time
import warnings

import numpy as np
import scipy.sparse as sp

from . import pardiso as _pardiso
from .base import Backend, Factor, symmetric_matrix
from .cholmod import CholmodBackend, cholmod_available
from .superlu import SuperLUBackend

__all__ = ["AMD_BELOW_NNZ", "BACKENDS", "SymbolicCholesky", "analyse", "cholmod_available", "factor_matrix",
           "pardiso_available", "resolve_ordering"]

#: backend name → class, in the order ``"auto"`` tries them (SuperLU last, with a warning)
BACKENDS: dict[str, type] = {"pardiso": _pardiso.PardisoBackend, "cholmod": CholmodBackend, "scipy": SuperLUBackend}

_FALLBACK_WARNING = (
    "neither MKL PARDISO nor scikit-sparse (CHOLMOD) is available: falling back to SciPy's SuperLU, which is "
    "several times slower for the interior-point solver. On Linux x86-64: pip install 'cvxgeodesic[pardiso]'; "
    "elsewhere: pip install 'cvxgeodesic[cholmod]' (needs SuiteSparse, e.g. apt-get install libsuitesparse-dev "
    "or brew install suite-sparse)."
)
_fallback_warned = False  # the warning is given once per process, not once per solver object

_SIMPLICIAL_BELOW = 10_000

#: ``ordering="auto"``: AMD below this many stored (lower-triangular) entries, METIS from it. Measured 2026-12-06 with
#: PARDISO, one thread (2-core VM, load 0.5-1): on the order-2 and order-1 QCLP patterns of decimated armadillo
#: (n = 1K-100K) AMD analysed 2-3x faster than PARDISO's METIS with no more fill (order 2 at 2,000 faces: 6.0 against
#: 16.4 ms, nnz(L) 82K against 90K), and whole solves were 5-20 % faster: order 2 on spot (73K entries) 0.51 -> 0.45 s,
#: fandisk (165K) 2.44 -> 2.32 s; QCLP on bimba (92K) 0.73 -> 0.66 s; the default (QCQP-Hessian) on kitten (95K)
#: 0.60 -> 0.56 s; ``resolution="auto"`` on armadillo (a 108K-entry copy) 1.16 -> 0.94 s, fandisk 0.33 -> 0.29 s. From
#: about 200K entries METIS's orderings factor faster: the default on bimba (233K) 1.72 s with METIS against 1.82 s,
#: horse (0.48M) 4.43 against 4.62 s; order 2 on armadillo (n = 173K) 117 against 159 ms per factorization. CHOLMOD
#: (supernodal) the same way: AMD analysed order-2 patterns of decimated armadillo 4-5x faster, factorizing as fast at
#: n = 4K and 20K (1.8 / 26 ms against 2.1 / 26 ms) and 9 % slower at n = 60K (about 370K entries).
AMD_BELOW_NNZ = 200_000


def resolve_ordering(ordering: str, nnz: int) -> str:
    """The fill-reducing ordering an analysis of ``nnz`` stored entries uses: ``"auto"`` is ``"amd"`` below
    :data:`AMD_BELOW_NNZ`, else ``"metis"``; any other name is returned as given."""
    if ordering != "auto":
        return ordering
    return "amd" if nnz < AMD_BELOW_NNZ else "metis"


def pardiso_available() -> bool:
    """True when MKL PARDISO (``libmkl_rt``) can be loaded."""
    return _pardiso.pardiso_available()


def available(name: str) -> bool:
    """Whether backend ``name`` can be used here (SuperLU always)."""
    return {"pardiso": pardiso_available, "cholmod": cholmod_available}.get(name, lambda: True)()


def choose_backend(backend: str) -> str:
    """The backend ``backend`` names, ``"auto"`` resolved to the first available of PARDISO, CHOLMOD and (with a
    warning, once per process) SciPy.

    Raises
    ------
    ValueError
        An unknown name.
    ImportError
        ``"pardiso"`` or ``"cholmod"`` whose library is missing.
    """
    if backend not in ("auto", *BACKENDS):
        raise ValueError(f"backend must be 'auto', 'pardiso', 'cholmod' or 'scipy', got {backend!r}")
    if backend == "auto":
        for name in BACKENDS:
            if name != "scipy" and available(name):
                return name
        global _fallback_warned
        if not _fallback_warned:
            _fallback_warned = True
            warnings.warn(_FALLBACK_WARNING, RuntimeWarning, stacklevel=3)
        return "scipy"
    if backend == "cholmod" and not cholmod_available():
        raise ImportError(_FALLBACK_WARNING)
    if backend == "pardiso" and not pardiso_available():
        raise ImportError("MKL PARDISO is not available: pip install 'cvxgeodesic[pardiso]' (Linux/Windows x86-64)")
    return backend


class SymbolicCholesky:
    """Symbolic analysis of a symmetric sparsity pattern, reused by every numeric factorization.

    Parameters
    ----------
    pattern : (n, n) scipy.sparse matrix
        Symmetric sparsity pattern (values ignored) with a full diagonal, e.g. from
        :func:`~cvxgeodesic.problems.conic.kkt_pattern`. Only its lower triangle is kept.
    backend : {"auto", "pardiso", "cholmod", "scipy"}
        ``"auto"`` takes the first available of PARDISO, CHOLMOD and (with a
        warning) SciPy. ``"pardiso"`` and ``"cholmod"`` raise ImportError when
        their library is missing.
    ordering : str
        Fill-reducing ordering (CHOLMOD: ``"metis"``, ``"nesdis"``, ``"amd"``, ``"best"``,
        ...; PARDISO: ``"metis"`` or ``"amd"``). ``"auto"`` (the default): AMD below
        :data:`AMD_BELOW_NNZ` stored entries, where it analyses 2-3x faster with no more fill,
        METIS from there, where its orderings factor faster (:func:`resolve_ordering`).
    mode : {"auto", "supernodal", "simplicial"}
        CHOLMOD factorization kind. ``"auto"`` (ours, not CHOLMOD's) takes simplicial
        below 10 000 unknowns, where it measured about twice as fast as supernodal
        on mesh matrices, and supernodal (BLAS-3) above.

    Attributes
    ----------
    n : int
        Matrix size.
    indptr, indices : int32 ndarrays
        CSC structure of the lower triangle (sorted row indices); a data array
        for :meth:`factorize` has one value per stored entry, in this order.
    nnz : int
        Number of stored (lower-triangular) entries.
    diag_positions : (n,) int64 ndarray
        Positions of the diagonal entries in a data array.
    backend : str
        The backend actually used.
    numeric : Backend
        The backend object (its analysis).
    n_analyses, n_factorizations : int
        Counters (the analysis runs once, in the constructor).
    analyze_time, factor_time : float
        Seconds spent in the symbolic analysis and in all numeric factorizations.
    """

    def __init__(self, pattern, *, backend: str = "auto", ordering: str = "auto", mode: str = "auto"):
        if mode not in ("auto", "supernodal", "simplicial"):
            raise ValueError(f"mode must be 'auto', 'supernodal' or 'simplicial', got {mode!r}")
        S = sp.csc_matrix(pattern)
        if S.ndim != 2 or S.shape[0] != S.shape[1]:
            raise ValueError(f"pattern must be square, got shape {S.shape}")
        n = S.shape[0]
        S = sp.tril(S, format="csc") + sp.identity(n, format="csc")  # guarantee a full diagonal
        S.sum_duplicates()
        S.sort_indices()
        S.data[:] = 1.0
        self.n = int(n)
        self.indptr = S.indptr.astype(np.int32)
        self.indices = S.indices.astype(np.int32)
        self.nnz = int(self.indices.size)
        # the lower CSC structure read as CSR is the upper triangle; its values are positions + 1, so that SciPy's
        # compiled sampling (a binary search per entry) looks positions up, 0 meaning "not in the pattern"
        self._lookup = sp.csr_matrix((np.arange(1, self.nnz + 1, dtype=np.int64), self.indices, self.indptr),
                                     shape=(n, n))
        self.diag_positions = self.positions(np.arange(n), np.arange(n))

        self.backend = choose_backend(backend)
        self.ordering = resolve_ordering(ordering, self.nnz)
        self.mode = mode if mode != "auto" else ("simplicial" if n < _SIMPLICIAL_BELOW else "supernodal")
        self.n_factorizations = 0
        self.factor_time = 0.0
        t0 = time.perf_counter()
        self.numeric: Backend = BACKENDS[self.backend](self.indptr, self.indices, self.diag_positions,
                                                       ordering=self.ordering, mode=self.mode)
        self.n_analyses = self.numeric.n_analyses
        self.analyze_time = time.perf_counter() - t0 if self.n_analyses else 0.0

    def positions(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """Positions in the data array of entries ``(rows[i], cols[i])`` (either triangle).

        Parameters
        ----------
        rows, cols : (N,) int ndarrays

        Returns
        -------
        (N,) int64 ndarray
            Index into the lower-triangular data array of each entry.

        Raises
        ------
        ValueError
            If an entry is not in the pattern.
        """
        rows = np.ascontiguousarray(rows, dtype=np.int64).ravel()
        cols = np.ascontiguousarray(cols, dtype=np.int64).ravel()
        if rows.shape != cols.shape:
            raise ValueError(f"rows and cols must have the same length, got {rows.size} and {cols.size}")
        lo, hi = np.minimum(rows, cols), np.maximum(rows, cols)
        inside = (lo >= 0) & (hi < self.n)
        out = np.full(rows.size, -1, dtype=np.int64)
        if inside.any():  # (SciPy returns a sparse matrix, not an array, for empty index arrays)
            out[inside] = np.asarray(self._lookup[lo[inside], hi[inside]], dtype=np.int64).ravel() - 1
        if (out < 0).any():
            bad = int(np.flatnonzero(out < 0)[0])
            raise ValueError(f"entry ({rows[bad]}, {cols[bad]}) is not in the sparsity pattern")
        return out

    def matrix(self, data: np.ndarray) -> sp.csc_matrix:
        """The full symmetric (n, n) CSC matrix whose lower triangle is ``data`` (for checks)."""
        return symmetric_matrix(self.indptr, self.indices, data)

    def factorize(self, data: np.ndarray, *, beta: float = 0.0) -> Factor:
        """Numeric Cholesky factorization of ``K + beta·I``.

        Parameters
        ----------
        data : (nnz,) float64 ndarray
            Lower-triangular values of ``K`` aligned with :attr:`indices`.
        beta : float
            Added to the diagonal (static regularization) without touching ``data``.

        Returns
        -------
        Factor
            ``factor.solve(b)`` (or ``factor(b)``) with ``b`` of shape (n,) or (n, r), returning
            ``(K + beta I)⁻¹ b``.

        Raises
        ------
        NotPositiveDefiniteError
            If the matrix is not numerically positive definite. With PARDISO the returned
            ``solve`` also raises it when its result is not finite (a guard).
        """
        data = np.ascontiguousarray(data, dtype=np.float64)
        if data.shape != (self.nnz,):
            raise ValueError(f"data must have shape ({self.nnz},), got {data.shape}")
        t0 = time.perf_counter()
        try:
            return Factor(self.numeric.factorize(data, beta))
        finally:
            self.n_factorizations += 1
            self.factor_time += time.perf_counter() - t0


def analyse(pattern, *, backend: str = "auto", ordering: str = "auto", mode: str = "auto") -> SymbolicCholesky:
    """Analyse a symmetric sparsity pattern once: :class:`SymbolicCholesky` (same parameters)."""
    return SymbolicCholesky(pattern, backend=backend, ordering=ordering, mode=mode)


def factor_matrix(K: sp.spmatrix) -> tuple[Factor, str]:
    """A Cholesky factor of the symmetric positive definite matrix ``K`` (analysed and factorized once), and the
    backend's name: ``factor(b)`` solves ``K x = b``.

    Raises
    ------
    NotPositiveDefiniteError
        ``K`` is not numerically positive definite.
    """
    K = sp.csc_matrix(K)
    S = analyse(K)
    low = sp.tril(K, format="coo")
    data = np.zeros(S.nnz)
    np.add.at(data, S.positions(low.row, low.col), low.data)
    return S.factorize(data), S.backend
