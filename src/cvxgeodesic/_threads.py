"""How many threads a solve uses: the ``threads=`` parameter, ``CVXGEODESIC_THREADS`` and the default policy.

A solve runs four thread pools: MKL PARDISO (GNU OpenMP), the parallel Numba kernels (the
order-2 solver's; Numba's ``omp`` layer, the same GNU OpenMP runtime), OpenBLAS
(NumPy, SciPy, CHOLMOD) and OpenMP regions of other libraries (libigl). Every pool
is bounded by :func:`thread_limit` for the whole construction of a solver and for
each of its solves.

Why a policy at all: OpenMP threads wait for each other at the end of every parallel
region, and an interior-point iteration has hundreds of short regions. When the
machine's cores are all taken (another solving process, any CPU-bound neighbour),
the threads of one region are not scheduled together and every barrier waits for a
time slice: measured on a 2-core machine, a solve beside another solving process
took 14–17× its time alone (``DESIGN.md`` §9), and with one thread each 1.4×.

The default (``threads=None``, no ``CVXGEODESIC_THREADS``) counts the cores this
process may run on and the runnable threads of other processes (:func:`busy_neighbours`,
sampled a few times) when a solver is built, and uses the cores left free, at least one.
The count is taken once per solver because PARDISO's thread count is fixed by its
analysis (changing it afterwards crashes it, see :mod:`~cvxgeodesic.linalg.pardiso`).
"""

from __future__ import annotations

import functools
import os
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager, suppress
from typing import Any, Concatenate, ParamSpec, Protocol, TypeVar

# nothing heavier than the standard library at import: the package imports this module first, and the command
# line's start-up (before its Ctrl-C handling is in place) should not wait for NumPy
from . import _signals
from .errors import ParameterError

__all__ = ["ENV_VAR", "default_threads", "pool_limits", "resolve_threads", "resolve_threads_noted", "thread_limit",
           "usable_cores"]

ENV_VAR = "CVXGEODESIC_THREADS"

# GNU OpenMP (PARDISO through MKL's GNU threading layer, the Numba kernels, CHOLMOD) lets an idle thread spin
# GOMP_SPINCOUNT times before it sleeps: 300 000 by default, milliseconds of a core that a neighbour process
# could use, and the cause of the collapse beside other jobs. The runtime reads the variable once, when it is
# loaded, so it is set (unless the user set it or OMP_WAIT_POLICY) when cvxgeodesic is imported, before
# anything loads libgomp. Measured with 2 threads on bimba's QCLP beside a second solving process
# (docs/performance.md): SPINCOUNT_DEFAULT spins cut the slowdown from 3.1x to 1.6x.
SPINCOUNT_DEFAULT = "10000"

# the limit of the solve running in this thread; nested solvers (multires' coarse solver) inherit it
_local = threading.local()

# procs_running is an instantaneous count: a few samples a couple of milliseconds apart see a busy neighbour
# every time and a neighbour between bursts of work only sometimes (about 5 ms per solver built)
_SAMPLES = 5
_SAMPLE_INTERVAL = 0.001


def _libgomp_loaded() -> bool:
    try:
        with open("/proc/self/maps") as fh:
            return "libgomp" in fh.read()
    except OSError:
        return False


def set_openmp_wait_policy() -> str | None:
    """Shorten GNU OpenMP's busy wait (``GOMP_SPINCOUNT``) unless the user chose one or libgomp is loaded.

    Returns the value set, or None when nothing was changed.
    """
    if any(k in os.environ for k in ("GOMP_SPINCOUNT", "OMP_WAIT_POLICY")) or _libgomp_loaded():
        return None
    os.environ["GOMP_SPINCOUNT"] = SPINCOUNT_DEFAULT
    return SPINCOUNT_DEFAULT


set_openmp_wait_policy()


def env_threads() -> int | None:
    """The thread count set by ``CVXGEODESIC_THREADS`` (None when unset or empty)."""
    raw = os.environ.get(ENV_VAR, "").strip()
    if not raw:
        return None
    try:
        value = int(raw)
    except ValueError:
        value = 0
    if value < 1:
        raise ParameterError(f"environment variable {ENV_VAR} must be a positive integer, got {raw!r}")
    return value


def usable_cores() -> int:
    """Cores this process may run on (its CPU affinity), at least 1."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)


#: ``PF_KTHREAD`` of ``/proc/PID/stat``'s flags: a kernel thread (no process of anyone's)
_PF_KTHREAD = 0x00200000
#: where the task states are read (a fake tree in tests)
_PROC = "/proc"


def _procs_running() -> int | None:
    """``procs_running`` of ``/proc/stat``: every runnable task of the machine, this process's included."""
    try:
        with open(f"{_PROC}/stat", "rb") as fh:
            for line in fh:
                if line.startswith(b"procs_running"):
                    return int(line.split()[1])
    except (OSError, ValueError, IndexError):
        return None
    return None


def _stat(path: str) -> tuple[bytes, int, int] | None:
    """(state, flags, num_threads) of a ``/proc/.../stat`` file, None when it is gone or unreadable."""
    try:
        with open(path, "rb") as fh:
            text = fh.read()
        fields = text[text.rindex(b")") + 2:].split()  # the name in parentheses may hold spaces
        return fields[0], int(fields[6]), int(fields[17])
    except (OSError, ValueError, IndexError):
        return None


def _runnable_threads(pid: str) -> int:
    """Threads of process ``pid`` in state R (running or waiting for a core)."""
    try:
        tids = os.listdir(f"{_PROC}/{pid}/task")
    except OSError:
        return 0
    return sum(1 for tid in tids if (st := _stat(f"{_PROC}/{pid}/task/{tid}/stat")) is not None and st[0] == b"R")


def _other_runnable() -> int | None:
    """Runnable threads of other processes, kernel threads left out; None when ``/proc`` does not show them all.

    ``procs_running`` counts more than neighbours' work: this process's own threads (OpenBLAS's and
    OpenMP's workers spin for a while after every parallel region; right after ``import cvxgeodesic`` a
    fresh process read 3 on an idle 2-core machine) and, on some virtual machines, a kernel thread that
    is always runnable (an idle machine read as one busy core). Hence the scan of every task's state.
    """
    own = str(os.getpid())
    try:
        pids = [p for p in os.listdir(_PROC) if p.isdigit()]
    except OSError:
        return None
    if _stat(f"{_PROC}/1/stat") is None:  # hidepid: others' processes are hidden and would look like an idle machine
        return None
    count = 0
    for pid in pids:
        if pid == own:
            continue
        st = _stat(f"{_PROC}/{pid}/stat")
        if st is None or st[1] & _PF_KTHREAD:
            continue
        # the process's own stat is its main thread's state: other threads may run while it waits (a Dask worker)
        count += (st[0] == b"R") if st[2] == 1 else _runnable_threads(pid)
    return count


def _fallback_runnable() -> int | None:
    """``procs_running`` less this process's runnable threads (kernel threads cannot be told apart here)."""
    n = _procs_running()
    return None if n is None else n - max(1, _runnable_threads(str(os.getpid())))


def busy_neighbours(samples: int = _SAMPLES, interval: float = _SAMPLE_INTERVAL) -> int:
    """Runnable threads of other processes: the median over ``samples`` reads of the task states in ``/proc``.

    Neither this process's threads nor kernel threads count. Where ``/proc`` does not list every
    process (``hidepid``), ``procs_running`` of ``/proc/stat`` less this process's runnable threads;
    0 where neither is readable (not Linux). In a container only the processes it sees count.
    """
    counts = []
    for i in range(samples):
        if i:
            time.sleep(interval)
        n = _other_runnable()
        if n is None:
            n = _fallback_runnable()
        if n is None:
            return 0
        counts.append(n)
    import statistics  # here: 8 ms of imports the package's start does not need

    return max(0, int(statistics.median(counts)))


def default_threads() -> int:
    """The default policy: the usable cores not taken by other runnable tasks, at least 1."""
    cores = usable_cores()
    if cores == 1:
        return 1
    return max(1, min(cores, cores - busy_neighbours()))


def resolve_threads(threads=None) -> int:
    """The thread count of a solver: ``threads``, else the enclosing solve's, else ``CVXGEODESIC_THREADS``,
    else :func:`default_threads`; an explicit count is capped at :func:`usable_cores` (:func:`resolve_threads_noted`).

    Raises
    ------
    ParameterError
        ``threads`` or ``CVXGEODESIC_THREADS`` is not a positive integer.
    """
    return resolve_threads_noted(threads)[0]


def resolve_threads_noted(threads=None) -> tuple[int, str | None]:
    """:func:`resolve_threads` and the note recording a cap (None when nothing was capped).

    A count above the cores this process may run on (``threads=`` or ``CVXGEODESIC_THREADS``) is capped
    at them: more threads than cores only wait for each other at every barrier, and a count like 10**6
    asked every thread pool for that many threads (reported to hang).

    Returns
    -------
    threads : int
    note : str or None
        ``"threads=1000000 capped at 2 (the cores available)"`` (or ``CVXGEODESIC_THREADS=...``).
    """
    if threads is None:
        current = getattr(_local, "limit", None)
        if current is not None:  # the enclosing solve's count, capped when it was resolved
            return current, None
        value = env_threads()
        if value is None:
            return default_threads(), None
        source = f"{ENV_VAR}={value}"
    else:
        from .validation import check_count  # NumPy: not at the package's import

        value = check_count(threads, "threads", or_none=True)
        source = f"threads={value}"
    cores = usable_cores()
    if value > cores:
        return cores, f"{source} capped at {cores} (the cores available)"
    return value, None


def _numba():
    try:  # importing the kernels first selects their threading layer (OpenMP) before Numba starts a pool
        import numba

        from .solvers.ipm import _kernels  # noqa: F401
    except ImportError:
        return None
    return numba


_controller_lock = threading.Lock()
_controller: tuple[int, Any] | None = None  # (len(sys.modules) when it was made, threadpoolctl's controller)


def pool_limits(limits: Any) -> Any:
    """``threadpoolctl.threadpool_limits(limits)`` (a context manager), through a controller kept between calls.

    Making a controller scans every loaded library (0.7-2.4 ms: a third of a heat solve from a factorized spot, the
    same again inside every interior-point solve); it is made again only after a module was imported, the way a
    new thread pool arrives (OpenBLAS with NumPy, Numba's OpenMP layer, open3d; MKL is loaded first, below).
    """
    global _controller
    from threadpoolctl import ThreadpoolController

    key = len(sys.modules)
    with _controller_lock:
        if _controller is None or _controller[0] != key:
            _controller = (key, ThreadpoolController())
        controller = _controller[1]
    return controller.limit(limits=limits)


@contextmanager
def thread_limit(threads: int) -> Iterator[None]:
    """Bound every thread pool of a solve to ``threads`` while the block runs (in this thread).

    OpenBLAS, MKL (hence PARDISO analyses run inside) and OpenMP through threadpoolctl,
    the Numba kernels through :func:`numba.set_num_threads` (thread-local in Numba).
    """
    threads = int(threads)
    previous = getattr(_local, "limit", None)
    if previous == threads:  # inside the same limit already (local rows: a patch solver per row): ~10 ms saved
        yield
        return
    numba = _numba()
    nb_previous = None
    _local.limit = threads
    try:
        if numba is not None:
            nb_previous = numba.get_num_threads()
            numba.set_num_threads(max(1, min(threads, numba.config.NUMBA_NUM_THREADS)))
        with suppress(ImportError):  # no PARDISO binding in this installation: no MKL to load
            from .linalg.pardiso import pardiso_available

            pardiso_available()  # loads MKL now, so that the limit covers it (threadpoolctl sees loaded libraries)
        with pool_limits(threads):
            _signals.check()  # a Ctrl-C that threadpoolctl's ctypes callbacks swallowed while finding the libraries
            yield
        _signals.check()  # the same while it restored the limits
    finally:
        _local.limit = previous
        if nb_previous is not None:
            numba.set_num_threads(nb_previous)


class _HasThreads(Protocol):
    threads: int


_S = TypeVar("_S", bound=_HasThreads)
_P = ParamSpec("_P")
_R = TypeVar("_R")


def limited(method: Callable[Concatenate[_S, _P], _R]) -> Callable[Concatenate[_S, _P], _R]:
    """Run a :class:`~cvxgeodesic.api.GeodesicSolver` method under the solver's thread limit.

    On ``__init__`` it resolves the ``threads`` keyword into ``self.threads`` first; a
    result with an ``info`` gets ``info.extra["threads"]``, and the note of a capped count
    (:func:`resolve_threads_noted`) in ``info.notes`` (and in the solver's ``notes``). Typed so
    that the decorated method keeps its signature and return type for type checkers (an untyped
    decorator made the class and every result ``Any`` to mypy).
    """

    @functools.wraps(method)
    def wrapper(self: _S, /, *args: _P.args, **kwargs: _P.kwargs) -> _R:
        if method.__name__ == "__init__":
            self.threads, note = resolve_threads_noted(kwargs.get("threads"))
            setattr(self, _NOTE, note)
        with thread_limit(self.threads):
            result = method(self, *args, **kwargs)
        note = getattr(self, _NOTE, None)
        for notes in (getattr(self, "notes", None), getattr(getattr(result, "info", None), "notes", None)):
            if note and isinstance(notes, list) and note not in notes:
                notes.append(note)
        info = getattr(result, "info", None)
        if info is not None and isinstance(getattr(info, "extra", None), dict):
            info.extra["threads"] = self.threads
        return result

    return wrapper


#: the attribute of a solver that holds the note of its capped thread count
_NOTE = "_threads_note"
