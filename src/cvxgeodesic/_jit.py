"""One line when the package's compiled kernels are being compiled: the first run after an installation.

The Numba kernels (:mod:`cvxgeodesic.solvers.ipm._kernels`, the order-2 solver's
``_clique_kernels``) are compiled on their first call and cached on disk (``cache=True``); later processes load them
in well under a second. The first solve after an installation (or a Numba upgrade, or with an empty
``NUMBA_CACHE_DIR``) therefore pauses for a few seconds, which would look like a hang without a word. What compiles
is what the solve needs, each kernel once per process: the order-1 solver's kernels (``_kernels``) at the first
order-1 solve, the order-2 solver's (``_clique_kernels``) at the first order-2 solve; ``benchmarks/first_run.py``
lists and times them. No set-up compiles anything: the curved Hessian energy is assembled in NumPy
(:mod:`cvxgeodesic.operators.curved_hessian`), whose Numba kernels were half the first QCQP-Hessian run's compile
time.

Numba announces every real compilation (a miss of its on-disk cache, after the cache was looked up) as a
``"numba:compile"`` event, so a listener learns of a cold cache at no cost: no marker file, no look at the
cache's index. :func:`watch_compiles` registers one (once per process, from each kernel module), and the first
compilation of a kernel of this package issues :class:`CompileNotice`, once per process: its estimate is per element
order (and for the Hessian energy), so the one line also accounts for a process that later uses the other order.
The command line prints it as ``cvxgeodesic: note: ...``; a Python user sees it as a warning at the line that called
the library.

Where Numba finds no writable place for its cache (no ``NUMBA_CACHE_DIR``, the package's ``__pycache__`` and the
home folder not writable: a read-only installation run by a user without a home), ``cache=True`` makes Numba
refuse the decoration itself (``cannot cache function 'nt_scaling': no locator available``), so nothing would
solve. :func:`njit` then compiles without a disk cache, and the one line says so instead (:data:`NO_CACHE_NOTICE`).
Not a cache in a temporary folder: a fresh private folder is gone when the process ends, so it would save
nothing over Numba's in-memory compiled code, and a fixed shared one (``/tmp/...``) would let another user plant
the pickled code Numba loads from its cache.
"""

from __future__ import annotations

import functools
import sys
import threading
import warnings
from collections.abc import Callable
from types import FrameType
from typing import Any

__all__ = ["HELPER_OPTIONS", "KERNEL_OPTIONS", "NOTICE", "NO_CACHE_NOTICE", "CompileNotice", "njit", "prefer_openmp",
           "watch_compiles"]

#: The options of every kernel of the package (``@njit(**KERNEL_OPTIONS)``). ``no_cfunc_wrapper``: the kernels are
#: called from Python and from each other, never through a C function pointer, and the C wrapper Numba builds by
#: default took about 5 % of the first compile (spot, qcqp-hessian: 5.1-5.2 s against 5.4 s).
KERNEL_OPTIONS = {"cache": True, "nogil": True, "error_model": "numpy", "no_cfunc_wrapper": True}
#: The helpers that only other kernels call: no Python wrapper either, whose argument unboxing is about a third of a
#: small kernel's compile; the first QCLP solve of spot with an empty cache took 8-17 % less (2026-12-06, 3
#: alternating pairs on a 2-core machine at load 9-11).
HELPER_OPTIONS = {**KERNEL_OPTIONS, "no_cpython_wrapper": True}


def prefer_openmp() -> None:
    """Numba's thread pool on OpenMP first, unless the user chose a threading layer.

    MKL PARDISO uses the GNU OpenMP runtime too, so both share one thread pool (started by a solve's thread limit,
    :mod:`cvxgeodesic._threads`) instead of two pools spinning against each other on a small machine. Called by
    every kernel module before its first kernel runs (a process may build an energy before it imports the solver).
    """
    import os

    if "NUMBA_THREADING_LAYER" not in os.environ and "NUMBA_THREADING_LAYER_PRIORITY" not in os.environ:
        import numba

        numba.config.THREADING_LAYER_PRIORITY = ["omp", "tbb", "workqueue"]  # type: ignore[attr-defined]

#: What the compilation costs: the first solve of the bundled spot mesh in a fresh process with an empty cache minus
#: the same with the cache filled (``benchmarks/first_run.py --repeat 2``, wall clock, 2026-12-06 09:42 UTC on a
#: 2-core machine at load 2.3-2.6): QCLP 2.48 - 0.38 s, order 2 2.84 - 0.88 s, QCQP-Hessian 2.61 - 0.44 s (its energy
#: compiles nothing), both orders in one process 4.67 - 0.89 s. Per element order, so that one line holds for a
#: process that uses both.
_COST = "about 2-3 s for each element order used"
NOTICE = f"compiling the solver's kernels once after installation ({_COST}); later runs load them from the cache"

#: The line instead of :data:`NOTICE` when Numba has no writable cache location (see the module's docstring).
NO_CACHE_NOTICE = (f"compiling the solver's kernels without a disk cache, in every process ({_COST}): Numba found "
                   "no writable cache location; set NUMBA_CACHE_DIR to a writable folder to keep them")

_PACKAGE = __name__.rsplit(".", 1)[0]
_lock = threading.Lock()
_state = {"watching": False, "told": False, "uncached": False}


class CompileNotice(UserWarning):
    """The package's compiled kernels are being compiled (once after an installation; cached afterwards)."""


def _user_stacklevel() -> int:
    """``stacklevel`` of the first frame outside this package, Numba and the standard library's helpers."""
    frame: FrameType | None = sys._getframe(1)
    level = 1
    while frame is not None:
        name = frame.f_globals.get("__name__", "")
        if not (name == _PACKAGE or name.startswith((f"{_PACKAGE}.", "numba.", "llvmlite.", "contextlib"))):
            return level
        frame = frame.f_back
        level += 1
    return 1


def _tell(dispatcher: Any) -> None:
    """Issue :class:`CompileNotice` the first time a kernel of this package compiles in this process."""
    module = getattr(getattr(dispatcher, "py_func", None), "__module__", "") or ""
    if _state["told"] or not module.startswith(f"{_PACKAGE}."):
        return
    with _lock:
        if _state["told"]:
            return
        _state["told"] = True
    try:
        warnings.warn(NO_CACHE_NOTICE if _state["uncached"] else NOTICE, CompileNotice,
                      stacklevel=_user_stacklevel())
    except Warning:  # warnings turned into errors (-W error): a notice must never fail a compilation
        pass


def watch_compiles() -> None:
    """Register (once per process) the Numba listener that issues :class:`CompileNotice`."""
    with _lock:
        if _state["watching"]:
            return
        _state["watching"] = True
    from numba.core import event

    class _Listener(event.Listener):
        def on_start(self, ev: Any) -> None:
            _tell((ev.data or {}).get("dispatcher"))

        def on_end(self, ev: Any) -> None:
            pass

    event.register("numba:compile", _Listener())


def njit(*args: Any, **options: Any) -> Any:
    """``numba.njit`` (``@njit`` or ``@njit(**options)``), compiling without a disk cache where ``cache=True``
    finds no writable cache location: then :class:`CompileNotice` says :data:`NO_CACHE_NOTICE`, once."""
    if args and callable(args[0]):
        return _jit(args[0], options)
    return functools.partial(_jit, options=options)


def _jit(func: Callable, options: dict) -> Any:
    import numba

    if options.get("cache"):
        try:
            return numba.njit(**options)(func)
        except RuntimeError as exc:  # raised by the decoration, before anything compiles
            if "no locator available" not in str(exc):
                raise
            _state["uncached"] = True
            options = {**options, "cache": False}
    return numba.njit(**options)(func)
