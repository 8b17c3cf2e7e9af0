"""Intel oneMKL PARDISO: a minimal ctypes binding for repeated SPD factorizations, and its backend.

Only what the interior-point solver needs: one symmetric positive definite
pattern (``mtype = 2``), analysed once (phase 11), factorized many times with new
values (phase 22) and solved (phase 33). PARDISO's supernodal kernels factor the
mesh Newton matrices 3–5× faster than CHOLMOD with OpenBLAS on this project's
2-core machine (bimba, 23K vertices: 15–20 ms against 45–70 ms for the QCLP
pattern, 45–50 ms against 125–300 ms for the Hessian energy's 2-ring pattern).

The library is found as ``libmkl_rt`` in the Python environment (the ``mkl``
wheel puts it in ``sys.prefix/lib``) or on the system search path. MKL is told
to use the GNU OpenMP runtime when ``libgomp`` is loadable (libigl and others
already load it into the process; two OpenMP runtimes in one process
oversubscribe the cores), unless ``MKL_THREADING_LAYER`` is set by the user.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import glob
import os
import sys
import weakref
from collections.abc import Callable
from typing import Any

import numpy as np

from .base import NotPositiveDefiniteError

__all__ = ["PardisoBackend", "PardisoFactor", "PardisoError", "pardiso_available"]

_MTYPE_SPD = 2
# iparm[23], the parallel factorization algorithm: 0 classic. The improved two-level algorithm (10) factored 25–35 %
# faster on bimba but crashed the process (general protection fault in libmkl_gnu_thread) on armadillo's
# QCQP-Hessian solve, and it does not report negative pivots; the two-level one (1) was no faster than 0.
_FACTOR_ALGORITHM = 0
# iparm[24]: 2 = parallel forward/backward substitution (measured 5–10 % faster solves than sequential, 0).
_SOLVE_ALGORITHM = 2
_MKL_THREADING_GNU = 3
# iparm[1] for "metis": 3 = PARDISO's OpenMP-parallel nested dissection. Measured 2026-12-02 (2 threads, quiet):
# the same orderings as the serial METIS (2) (same nnz(L), factorization and solve times), analyses 35-40 % faster:
# order-2 patterns of armadillo and the 70K-face bunny (QCQP-Hessian) 0.66 -> 0.41 s, order-1 patterns of
# armadillo and horse 0.12 -> 0.075 s, 0.105 -> 0.068 s.
_METIS = 3

# PARDISO error codes (oneMKL reference, "pardiso" error parameter).
_ERRORS = {
    -1: "input inconsistent",
    -2: "not enough memory",
    -3: "reordering problem",
    -4: "zero or negative pivot: the matrix is not positive definite",
    -5: "unclassified internal error",
    -6: "reordering failed",
    -7: "diagonal matrix is singular",
    -8: "32-bit integer overflow problem",
    -9: "not enough memory for out-of-core",
    -10: "error opening out-of-core files",
    -11: "read/write error with out-of-core files",
    -12: "wrong pardiso_64 call",
    -13: "interrupted by the mkl_progress function",
    -15: "internal error in the reordering",
}
NOT_POSITIVE_DEFINITE = -4

_lib: ctypes.CDLL | None = None
_lib_error: str | None = None


class PardisoError(RuntimeError):
    """PARDISO returned a nonzero error code (``code``)."""

    def __init__(self, code: int, phase: int):
        self.code = int(code)
        self.phase = int(phase)
        super().__init__(f"MKL PARDISO phase {phase} failed with error {code}: {_ERRORS.get(code, 'unknown error')}")


def _candidates() -> list[str]:
    names = []
    for prefix in dict.fromkeys([sys.prefix, sys.base_prefix, sys.exec_prefix]):
        names += sorted(glob.glob(os.path.join(prefix, "lib", "libmkl_rt.so*")))
    if not names:
        # find_library runs ldconfig, gcc and ld in subprocesses: only when the environment has no MKL wheel
        found = ctypes.util.find_library("mkl_rt")
        if found:
            names.append(found)
    names += ["libmkl_rt.so.3", "libmkl_rt.so.2", "libmkl_rt.so"]
    return list(dict.fromkeys(names))


def _load() -> ctypes.CDLL | None:
    global _lib, _lib_error
    if _lib is not None or _lib_error is not None:
        return _lib
    for name in _candidates():
        try:
            lib = ctypes.CDLL(name)
            fn = lib.pardiso
        except (OSError, AttributeError):
            continue
        break
    else:
        _lib_error = "libmkl_rt not found (pip install mkl)"
        return None
    if "MKL_THREADING_LAYER" not in os.environ:
        try:
            ctypes.CDLL("libgomp.so.1")
            lib.MKL_Set_Threading_Layer.argtypes = [ctypes.c_int]
            lib.MKL_Set_Threading_Layer(_MKL_THREADING_GNU)
        except (OSError, AttributeError):
            pass  # MKL keeps its default (Intel OpenMP from the intel-openmp wheel)
    lib.MKL_Set_Num_Threads_Local.argtypes = [ctypes.c_int]
    lib.MKL_Set_Num_Threads_Local.restype = ctypes.c_int
    lib.MKL_Get_Max_Threads.restype = ctypes.c_int
    fn.restype = None
    ptr_i32 = ctypes.POINTER(ctypes.c_int32)
    fn.argtypes = [
        ctypes.c_void_p,  # pt (64 handles)
        ptr_i32, ptr_i32, ptr_i32, ptr_i32, ptr_i32,  # maxfct, mnum, mtype, phase, n
        ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p,  # a, ia, ja
        ctypes.c_void_p,  # perm
        ptr_i32,  # nrhs
        ctypes.c_void_p,  # iparm (64 int32)
        ptr_i32,  # msglvl
        ctypes.c_void_p, ctypes.c_void_p,  # b, x
        ptr_i32,  # error
    ]
    _lib = lib
    return _lib


def pardiso_available() -> bool:
    """True when MKL's ``libmkl_rt`` with the ``pardiso`` entry point can be loaded."""
    return _load() is not None


def _call(lib, pt, iparm, phase, n, a, indptr, indices, b, x, nrhs, threads) -> int:
    one = ctypes.c_int32(1)
    err = ctypes.c_int32(0)
    # PARDISO crashes (seen: segfault in phase 22) when the thread count changes between the analysis and
    # later phases, e.g. under a caller's threadpoolctl limit; a thread-local setting pins it for this call.
    previous = lib.MKL_Set_Num_Threads_Local(threads)
    try:
        lib.pardiso(
            pt.ctypes.data, ctypes.byref(one), ctypes.byref(one), ctypes.byref(ctypes.c_int32(_MTYPE_SPD)),
            ctypes.byref(ctypes.c_int32(phase)), ctypes.byref(ctypes.c_int32(n)),
            a.ctypes.data if a is not None else None, indptr.ctypes.data, indices.ctypes.data, None,
            ctypes.byref(ctypes.c_int32(nrhs)), iparm.ctypes.data, ctypes.byref(ctypes.c_int32(0)),
            b.ctypes.data if b is not None else None, x.ctypes.data if x is not None else None, ctypes.byref(err),
        )
    finally:
        lib.MKL_Set_Num_Threads_Local(previous)
    return err.value


def _release(lib, pt, iparm, n, indptr, indices, threads) -> None:
    _call(lib, pt, iparm, -1, n, None, indptr, indices, None, None, 1, threads)


class PardisoFactor:
    """PARDISO analysis of one SPD pattern; :meth:`factorize` then :meth:`solve`.

    Parameters
    ----------
    indptr : (n + 1,) int ndarray
    indices : (nnz,) int ndarray
        Lower-triangular CSC structure with sorted row indices and a full
        diagonal, which is PARDISO's upper-triangular CSR of the same matrix.
    ordering : {"metis", "amd"}
        Fill-reducing ordering of the analysis.

    Attributes
    ----------
    n : int
    nnz_factor : int
        Nonzeros in the factor, as PARDISO reports them after the analysis.
    threads : int
        OpenMP threads of every phase: MKL's maximum when the analysis ran.
    """

    def __init__(self, indptr: np.ndarray, indices: np.ndarray, *, ordering: str = "metis"):
        lib = _load()
        if lib is None:
            raise ImportError(f"MKL PARDISO is not available: {_lib_error}")
        self._lib = lib
        self.n = int(indptr.size - 1)
        self._indptr = np.ascontiguousarray(indptr, dtype=np.int32)
        self._indices = np.ascontiguousarray(indices, dtype=np.int32)
        self._pt = np.zeros(64, dtype=np.int64)
        iparm = np.zeros(64, dtype=np.int32)
        iparm[0] = 1  # use the values below, defaults elsewhere
        iparm[1] = {"amd": 0, "metis": _METIS}.get(ordering, _METIS)  # fill-reducing ordering
        iparm[7] = 0  # no iterative refinement inside PARDISO (the caller refines with its own operator)
        iparm[17] = -1  # report nnz(L)
        iparm[23] = _FACTOR_ALGORITHM
        iparm[24] = _SOLVE_ALGORITHM
        iparm[34] = 1  # zero-based indices
        self._iparm = iparm
        self._data = None
        self.threads = max(1, int(lib.MKL_Get_Max_Threads()))
        dummy = np.zeros(1)
        err = self._call(11, np.ones(self._indices.size), dummy, dummy, 1)
        if err:
            raise PardisoError(err, 11)
        self.nnz_factor = int(iparm[17])
        weakref.finalize(self, _release, lib, self._pt, iparm, self.n, self._indptr, self._indices, self.threads)

    def _call(self, phase, a, b, x, nrhs) -> int:
        return _call(self._lib, self._pt, self._iparm, phase, self.n, a, self._indptr, self._indices, b, x, nrhs,
                     self.threads)

    def factorize(self, data: np.ndarray) -> None:
        """Numeric factorization (phase 22) of the matrix with lower-triangular values ``data`` (nnz,).

        Raises
        ------
        PardisoError
            ``code == -4`` when the matrix is not numerically positive definite (a zero or
            negative pivot).
        """
        data = np.ascontiguousarray(data, dtype=np.float64)
        dummy = np.zeros(1)
        err = self._call(22, data, dummy, dummy, 1)
        if err:
            self._data = None
            raise PardisoError(err, 22)
        self._data = data  # PARDISO reads the values again in the solve phase

    def solve(self, b: np.ndarray) -> np.ndarray:
        """``A⁻¹ b`` for ``b`` of shape (n,) or (n, r), with the latest factorization.

        Raises
        ------
        PardisoError
            ``code == -4`` when the solution is not finite although ``b`` is (a factor spoiled
            by a pivot that the factorization did not report; a guard, PARDISO's own check
            comes first).
        """
        if self._data is None:
            raise RuntimeError("no successful factorization to solve with")
        b = np.asarray(b, dtype=np.float64)
        if b.shape[0] != self.n or b.ndim not in (1, 2):
            raise ValueError(f"right-hand side must have shape ({self.n},) or ({self.n}, r), got {b.shape}")
        if not np.isfinite(b).all():
            raise ValueError("right-hand side has non-finite values")
        nrhs = 1 if b.ndim == 1 else b.shape[1]
        bf = np.array(b, order="F")  # a column-major copy: PARDISO may overwrite b
        x = np.zeros_like(bf, order="F")
        err = self._call(33, self._data, bf, x, nrhs)
        if err:
            raise PardisoError(err, 33)
        if not np.isfinite(x).all():
            raise PardisoError(NOT_POSITIVE_DEFINITE, 33)
        return np.ascontiguousarray(x)


class PardisoBackend:
    """PARDISO's analysis of one pattern (ordering ``"metis"`` or ``"amd"``; ``mode`` is ignored); see
    :class:`~cvxgeodesic.linalg.base.Backend`."""

    name = "pardiso"
    n_analyses = 1

    def __init__(self, indptr: np.ndarray, indices: np.ndarray, diag_positions: np.ndarray, *, ordering: str,
                 mode: str):
        self.factor = PardisoFactor(indptr, indices, ordering=ordering)
        self._diag = diag_positions

    @property
    def threads(self) -> int:
        """OpenMP threads of every phase, fixed by the analysis."""
        return self.factor.threads

    def _solve(self, b: np.ndarray) -> np.ndarray:
        return _positive_definite(self.factor.solve, b)

    def factorize(self, data: np.ndarray, beta: float) -> Callable[[np.ndarray], np.ndarray]:
        if beta:
            data = data.copy()
            data[self._diag] += beta
        _positive_definite(self.factor.factorize, data)
        return self._solve


def _positive_definite(phase: Callable[[np.ndarray], Any], arg: np.ndarray) -> Any:
    """``phase(arg)``, PARDISO's "not positive definite" raised as :class:`NotPositiveDefiniteError`."""
    try:
        return phase(arg)
    except PardisoError as exc:
        if exc.code == NOT_POSITIVE_DEFINITE:
            raise NotPositiveDefiniteError(str(exc)) from None
        raise
