"""Dask plumbing shared by everything that runs on a cluster (``batch`` meshes, ``distance_matrix`` rows).

One place for: the optional import with an error that names the extra, the probe that fails fast on an
address that is not a Dask scheduler, the thread budget of local workers, the client/cluster of a run
(a local cluster speaks TLS with credentials of its own: no other user of the machine can submit work to it;
it serves no HTTP pages unless :data:`DASHBOARD_VARIABLE` asks for the dashboard, which is then plain HTTP on
127.0.0.1), and Ctrl-C (one line, no worker tracebacks). Dask (``pip install 'cvxgeodesic[cluster]'``) is imported
only inside these functions.
"""

from __future__ import annotations

import contextlib
import os
import socket
import struct
import sys
from collections.abc import Iterator
from contextlib import ExitStack
from typing import Any

from .errors import ParameterError

__all__ = ["DASHBOARD_VARIABLE", "LOCAL_HOST", "PROBE_TIMEOUT", "THREAD_VARIABLES", "check_scheduler",
           "dashboard_wanted", "local_http_config", "local_security", "local_worker_environ",
           "open_client", "require_distributed", "sigint_ignored", "stop_after_interrupt"]

#: The one address a local cluster listens on (scheduler, workers, nannies and the scheduler's dashboard).
#: Dask binds the dashboard of ``dashboard_address=":0"`` to every interface, so a job would be reachable
#: from the network while it runs; on loopback it stays reachable from this machine (or an SSH tunnel).
LOCAL_HOST = "127.0.0.1"

#: The environment variable that turns on the scheduler's dashboard of a local cluster (``1``; unset, empty or
#: ``0``: off). Off, the cluster's HTTP servers (Dask starts them whatever the dashboard) have no pages at all: any
#: user of the machine who finds the port of Dask's pages could read what runs (tasks, arguments, worker logs) and,
#: through ``/info/logs/<address>.html``, make the scheduler open TLS connections to any address and write their
#: errors into the job's stderr.
DASHBOARD_VARIABLE = "CVXGEODESIC_DASHBOARD"

#: Seconds :func:`check_scheduler` waits for the connection and for the scheduler's first bytes.
PROBE_TIMEOUT = 4.0


def require_distributed(what: str = "cvxgeodesic batch") -> tuple[Any, Any]:
    """``(dask, distributed)``, or ImportError naming the packages to install.

    Parameters
    ----------
    what : str
        What needs them, the subject of the message (``"cvxgeodesic batch"``).
    """
    try:
        import dask
        import distributed
    except ImportError as exc:
        raise ImportError(
            f"{what} needs Dask's distributed scheduler, which is not installed: "
            "pip install 'dask[distributed]' (or pip install 'cvxgeodesic[cluster]')"
        ) from exc
    return dask, distributed


def check_scheduler(address: str, timeout: float | None = None) -> None:
    """Fail fast, with a clear message, when ``address`` is not a Dask scheduler.

    Dask's own client trusts the first 8 bytes the server sends as a message length: an
    HTTP or SSH server there makes it allocate exabytes ("Unable to allocate 3.07 EiB"),
    and a server that never speaks makes it wait. A scheduler sends its handshake as soon
    as a connection opens, a small message whose 8-byte little-endian length comes
    first; this checks exactly that, within ``2 * timeout`` seconds (default
    :data:`PROBE_TIMEOUT`). Only plain TCP addresses (``tcp://SCHEDULER:8786`` or
    ``host:port``) are checked; others go to Dask.

    Raises
    ------
    ConnectionError
        Nothing listens there, the connection or the first bytes time out, or the server
        does not speak Dask's protocol.
    """
    timeout = PROBE_TIMEOUT if timeout is None else timeout
    scheme, _, rest = str(address).rpartition("://")
    if scheme not in ("", "tcp"):
        return
    host, sep, port_text = rest.rstrip("/").rpartition(":")
    if not sep or not port_text.isdigit():
        raise ConnectionError(f"--scheduler {address!r} is not an address like tcp://SCHEDULER:8786")
    host = host.strip("[]") or "127.0.0.1"
    what = f"the Dask scheduler at {address}"
    head = b""
    try:
        with socket.create_connection((host, int(port_text)), timeout=timeout) as sock:
            sock.settimeout(timeout)
            while len(head) < 8 and (chunk := sock.recv(8 - len(head))):
                head += chunk
    except TimeoutError:
        raise ConnectionError(f"{what} did not answer within {timeout:g} s: is it a Dask scheduler "
                              "(dask scheduler --port 8786), and reachable?") from None
    except OSError as exc:
        raise ConnectionError(f"cannot connect to {what}: {exc.strerror or exc}") from None
    if len(head) < 8:
        raise ConnectionError(f"{what} closed the connection without a Dask handshake: is it a Dask scheduler?")
    (nbytes,) = struct.unpack("<Q", head)
    if not 0 < nbytes < 2**24:
        raise ConnectionError(f"{what} does not speak Dask's protocol (first bytes {head!r}): "
                              "is the address a Dask scheduler's (default port 8786), not a web or other server?")


#: The variables that bound a worker's thread pools (OpenMP, OpenBLAS, MKL, Numba, the solver's own).
THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS",
                    "CVXGEODESIC_THREADS")


PRE_SPAWN = "distributed.nanny.pre-spawn-environ"
MALLOC_TRIM = "MALLOC_TRIM_THRESHOLD_"


def local_worker_environ(n_workers: int) -> dict:
    """Dask config of a local cluster: every worker process's pools get ``cpu_count // n_workers`` threads.

    Two processes whose OpenMP pools each take every core slow each other down many times over
    (``docs/performance.md``), so the cores are divided between the workers. A variable already set
    in this process's environment is inherited by the workers instead (Dask's behaviour).
    Values are ints, or None for a variable the workers must not get.
    """
    threads = max(1, (os.cpu_count() or 1) // n_workers)
    env: dict = {f"{PRE_SPAWN}.{k}": threads for k in THREAD_VARIABLES}
    # Dask sets MALLOC_TRIM_THRESHOLD_=65536 in its workers; any fixed value turns off glibc's adaptive mmap
    # threshold, so every large NumPy temporary of the interior-point loop is mapped and faulted in afresh:
    # measured on bimba (QCLP, 1 thread), 0.49 s per solve without it and 0.89 s with it. None unsets it.
    env[f"{PRE_SPAWN}.{MALLOC_TRIM}"] = None
    return env


def dashboard_wanted() -> bool:
    """Whether :data:`DASHBOARD_VARIABLE` asks for the dashboard of a local cluster (ParameterError for a value
    other than ``1``, ``0`` or empty)."""
    raw = os.environ.get(DASHBOARD_VARIABLE, "").strip()
    if raw not in ("", "0", "1"):
        raise ParameterError(f"environment variable {DASHBOARD_VARIABLE} must be 1 (a local cluster's Dask dashboard "
                             f"on 127.0.0.1) or 0 (none, the default), got {raw!r}")
    return raw == "1"


def local_http_config(dashboard: bool) -> dict:
    """Dask config of a local cluster's HTTP servers: Dask's pages with the dashboard, else none.

    The scheduler and each worker start an HTTP server whatever the dashboard; without one, their routes are
    emptied, so that they answer every request with 404 (the scheduler's pages include ``/info/logs/<address>``,
    which makes it connect to any address).
    """
    return {} if dashboard else {"distributed.scheduler.http.routes": [], "distributed.worker.http.routes": []}


@contextlib.contextmanager
def _environ_kept(names: tuple[str, ...]) -> Iterator[None]:
    """Restore ``os.environ[name]`` (set or unset) for every name when the block ends.

    Dask's nanny writes its pre-spawn variables into *this* process's environment before it spawns a
    worker; left there, ``CVXGEODESIC_THREADS`` would pin every later in-process solve of the caller
    to the workers' share of the cores instead of the default policy.
    """
    saved = {k: os.environ.get(k) for k in names}
    try:
        yield
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def local_security(what: str = "cvxgeodesic batch") -> Any:
    """TLS credentials for one local cluster: a fresh self-signed certificate and key, held in memory.

    A Dask scheduler or worker on ``tcp://`` runs any function a client submits, and a loopback port is
    open to every user of the machine: without credentials, anyone there could run code as the caller
    while a job runs. With these, scheduler, workers and nannies listen on ``tls://`` and accept only a
    peer that presents this certificate (Dask's TLS is mutual), which only the processes of the run hold:
    the client of the run, and the workers, which get it from their nanny through the spawn pipe.

    Parameters
    ----------
    what : str
        What needs them, the subject of the ImportError.

    Returns
    -------
    distributed.security.Security
        With ``require_encryption=True``.

    Raises
    ------
    ImportError
        The ``cryptography`` package, which makes the certificate, is not installed.
    """
    from distributed.security import Security

    try:
        import cryptography  # noqa: F401  (Security.temporary's own message does not name the extra)
    except ImportError as exc:
        raise ImportError(
            f"{what} on a local cluster needs the package cryptography (its workers talk TLS with a "
            "certificate made for the run): pip install cryptography (or pip install 'cvxgeodesic[cluster]')"
        ) from exc
    return Security.temporary()


@contextlib.contextmanager
def sigint_ignored() -> Iterator[None]:
    """Ignore SIGINT while the block runs (processes started then inherit it); main thread only."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def open_client(stack: ExitStack, scheduler: Any, n_workers: int, what: str = "cvxgeodesic batch") -> tuple[Any, Any]:
    """The client of a run and the local cluster it started (None on an existing cluster).

    Parameters
    ----------
    stack : contextlib.ExitStack
        Closes the client and the local cluster this opens when the run ends.
    scheduler : None, str or distributed.Client
        None: a ``LocalCluster`` of ``n_workers`` worker processes with one Dask thread each and
        :func:`local_worker_environ`'s thread budget, every socket of it on :data:`LOCAL_HOST`, scheduler,
        workers and nannies on ``tls://`` with :func:`local_security`'s credentials (held by the returned client
        alone), no dashboard and no HTTP pages (:func:`local_http_config`) unless :data:`DASHBOARD_VARIABLE` is
        ``1`` (then its address is printed on stderr); an address (probed by :func:`check_scheduler`
        first; a ``tls://`` one uses the Dask configuration's credentials); or a connected client,
        used as it is (not closed).
    n_workers : int
        Workers of the local cluster.
    what : str
        Subject of the ImportError when Dask is missing.

    Returns
    -------
    (distributed.Client, distributed.LocalCluster or None)

    Raises
    ------
    ImportError
        Dask's ``distributed`` is not installed, or (local cluster) ``cryptography``.
    ParameterError
        :data:`DASHBOARD_VARIABLE` is set to something else than ``0`` or ``1`` (local cluster).
    ConnectionError
        ``scheduler`` is not a reachable Dask scheduler.
    """
    dask, distributed = require_distributed(what)
    if scheduler is None:
        dashboard = dashboard_wanted()
        security = local_security(what)
        # Ctrl-C goes to the whole process group: worker processes started with SIGINT ignored keep
        # quiet (no tracebacks of their own) and this process alone stops them (stop_after_interrupt)
        kept = _environ_kept((*THREAD_VARIABLES, MALLOC_TRIM))
        config = {**local_worker_environ(n_workers), **local_http_config(dashboard)}
        with dask.config.set(config), sigint_ignored(), kept:
            cluster = stack.enter_context(distributed.LocalCluster(
                n_workers=n_workers, threads_per_worker=1, processes=True, host=LOCAL_HOST, protocol="tls://",
                security=security, dashboard_address=f"{LOCAL_HOST}:0" if dashboard else None,
                # the scheduler's HTTP server (no pages without the dashboard) on a free port, not Dask's 8787
                scheduler_kwargs={"dashboard_address": f"{LOCAL_HOST}:0"}))
        if dashboard:
            print(f"cvxgeodesic: Dask dashboard at {cluster.dashboard_link} ({DASHBOARD_VARIABLE}=1)",
                  file=sys.stderr, flush=True)
        return stack.enter_context(distributed.Client(cluster, security=security)), cluster
    if isinstance(scheduler, distributed.Client):
        return scheduler, None
    check_scheduler(scheduler)
    try:
        client = stack.enter_context(distributed.Client(scheduler, timeout="20s"))
    except OSError as exc:
        raise ConnectionError(f"cannot connect to the Dask scheduler at {scheduler}: {exc}") from None
    return client, None


def stop_after_interrupt(client: Any, futures, cluster: Any) -> None:
    """After Ctrl-C: cancel the tasks, kill the local workers (a running solve does not return for
    seconds) and silence Dask's shutdown logging, so that one line says what happened."""
    import logging
    import signal

    for name in ("distributed", "tornado", "asyncio"):
        logging.getLogger(name).setLevel(logging.CRITICAL + 1)
    try:
        client.cancel(list(futures), force=True)
    except Exception:  # the connection may be gone already; nothing to report
        pass
    if cluster is None:
        return
    for nanny in list(getattr(cluster, "workers", {}).values()):
        try:
            nanny.close_gracefully()  # no restart of the worker we kill next
            pid = nanny.process.process.pid
            if pid:
                os.kill(pid, signal.SIGKILL)
        except Exception:
            pass
