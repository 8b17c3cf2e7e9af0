"""Rows of a distance matrix on a Dask cluster: the engine of ``distance_matrix(workers=…, scheduler=…)``.

The rows are split into contiguous chunks, one per worker thread of the cluster. Every chunk is one
task that builds one solver (the per-mesh set-up, paid once per chunk) and solves its rows in turn;
the mesh is scattered to the workers once, and the rows come back in the order they were asked for.
A local cluster's workers share the cores (``cpu_count // workers`` threads each,
:func:`~cvxgeodesic._cluster.local_worker_environ`).

This module does not import :mod:`cvxgeodesic.api`: the caller passes the solver class
(``factory``), which reaches the workers by reference.
"""

from __future__ import annotations

import contextlib
import os
import sys
import threading
import time
import warnings
from collections.abc import Callable, Sequence
from contextlib import ExitStack
from typing import Any

import numpy as np

from ._cluster import open_client, require_distributed, stop_after_interrupt

__all__ = ["distributed_rows", "split_rows"]

#: Seconds an existing cluster without workers is given to get one before the run fails.
WORKER_WAIT = 60.0

WHAT = "distance_matrix on a Dask cluster (workers= or scheduler=, cvxgeodesic matrix --workers/--scheduler)"


def split_rows(n_rows: int, n_chunks: int) -> list[slice]:
    """``n_rows`` rows as ``min(n_rows, n_chunks)`` contiguous slices whose lengths differ by at most one.

    Parameters
    ----------
    n_rows : int
        Rows, at least 1.
    n_chunks : int
        Chunks wanted, at least 1.

    Returns
    -------
    list of slice
        In row order, covering ``range(n_rows)`` once.
    """
    n_chunks = max(1, min(int(n_rows), int(n_chunks)))
    bounds = np.linspace(0, n_rows, n_chunks + 1).round().astype(int)
    return [slice(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:], strict=True)]


def solve_chunk(factory: Callable[..., Any], mesh: Any, items: Sequence[Any], options: dict,
                topic: str | None = None) -> tuple[np.ndarray, list[tuple[type[Warning], str]]]:
    """The task of one chunk, on a worker: one solver, its rows in order, and the warnings they raised.

    Parameters
    ----------
    factory : callable
        ``factory(mesh, **options)`` builds the solver (:class:`~cvxgeodesic.api.GeodesicSolver`).
    mesh : TriMesh
    items : sequence
        The sources of each row (anything ``solve`` takes).
    options : dict
        Keyword arguments of ``factory``.
    topic : str, optional
        Dask event topic that gets one event per solved row (the client's progress bar).

    Returns
    -------
    rows : (len(items), n) float ndarray
    warnings : list of (category, message)
        Every warning of the task, to be re-issued in the calling process (a worker's stderr is not
        the user's).
    """
    worker = None
    if topic is not None:
        from distributed import get_worker

        worker = get_worker()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        solver = factory(mesh, **options)
        rows = []
        for item in items:
            rows.append(solver.solve(item).distance)
            if worker is not None and topic is not None:
                worker.log_event(topic, 1)
    return np.stack(rows), [(w.category, str(w.message)) for w in caught]


def _slots(client: Any) -> int:
    """Worker threads of the cluster (tasks that run at once); waits for one when there are none yet."""
    slots = sum(client.nthreads().values())
    if slots == 0:
        try:
            client.wait_for_workers(1, timeout=WORKER_WAIT)
        except TimeoutError:
            raise ConnectionError(f"the Dask cluster has no worker (waited {WORKER_WAIT:g} s)") from None
        slots = sum(client.nthreads().values())
    return max(1, slots)


class _RowBar:
    """A row-counting tqdm bar fed from two threads: worker events (per row) and finished chunks."""

    def __init__(self, total: int, desc: str) -> None:
        from tqdm import tqdm

        self.bar = tqdm(total=total, desc=desc, unit="row", file=sys.stderr)
        self.lock = threading.Lock()
        self.events = 0
        self.done = 0
        self.closed = False

    def _show(self) -> None:
        target = min(self.bar.total, max(self.events, self.done))
        if target > self.bar.n:
            self.bar.update(target - self.bar.n)

    def event(self, _event: Any) -> None:
        with self.lock:
            self.events += 1
            if not self.closed:  # an event may arrive after the run ended
                self._show()

    def chunk_done(self, rows: int) -> None:
        with self.lock:
            self.done += rows
            self._show()

    def close(self) -> None:
        with self.lock:
            if not self.closed:
                self.closed = True
                self.bar.close()


def distributed_rows(factory: Callable[..., Any], mesh: Any, items: Sequence[Any], options: dict, *,
                     scheduler: Any = None, workers: int | None = None, progress: bool = False,
                     desc: str = "rows") -> np.ndarray:
    """Solve one row per item on a Dask cluster, in contiguous chunks; the rows in the order of ``items``.

    Parameters
    ----------
    factory : callable
        ``factory(mesh, **options)`` builds a solver whose ``solve(item).distance`` is a row; it must be
        importable on the workers (it is sent by reference).
    mesh : TriMesh
        Scattered to the workers once.
    items : sequence
        One entry per row, at least one.
    options : dict
        Keyword arguments of ``factory``.
    scheduler : None, str or distributed.Client
        None: a ``LocalCluster`` of ``workers`` processes (closed at the end); an address such as
        ``"tcp://SCHEDULER:8786"`` or a connected client: an existing cluster.
    workers : int, optional
        Worker processes of the local cluster (default 2; ignored with ``scheduler``).
    progress : bool
        A progress bar counting rows on stderr.
    desc : str
        Label of the progress bar.

    Returns
    -------
    (len(items), n) float ndarray

    Raises
    ------
    ImportError
        Dask's ``distributed`` is not installed.
    ConnectionError
        ``scheduler`` is not a Dask scheduler, or its cluster has no worker.
    Exception
        The first error a chunk raised (the solver's own, e.g. SolverError), after the other chunks
        were cancelled.
    """
    items = list(items)
    n_workers = 2 if workers is None else int(workers)
    with ExitStack() as stack:
        client, cluster = open_client(stack, scheduler, n_workers, what=WHAT)
        if cluster is not None:
            client.wait_for_workers(n_workers)
        chunks = split_rows(len(items), n_workers if cluster is not None else _slots(client))
        token = f"{os.getpid()}-{time.time_ns()}"
        topic = f"cvxgeodesic-rows-{token}" if progress else None
        bar = _RowBar(len(items), desc) if progress else None
        if bar is not None:  # before the tasks start, so that no row's event is missed
            client.subscribe_topic(topic, bar.event)
        futures: list = []
        try:  # the scatter too: the workers import the package while they unpickle the mesh, seconds of it
            mesh_future = client.scatter(mesh, broadcast=True, hash=False)
            futures = [client.submit(solve_chunk, factory, mesh_future, items[s], options, topic,
                                     key=f"cvxgeodesic-rows-{i}-{token}", pure=False)
                       for i, s in enumerate(chunks)]
            parts = _gather(futures, chunks, bar)
        except KeyboardInterrupt:
            if bar is not None:
                bar.close()
            stop_after_interrupt(client, futures, cluster)
            raise
        except BaseException:
            with contextlib.suppress(Exception):  # on an existing cluster the other chunks would run on
                client.cancel(futures, force=True)
            raise
        finally:
            if bar is not None:
                bar.close()
                with contextlib.suppress(Exception):  # the connection may be gone after Ctrl-C
                    client.unsubscribe_topic(topic)
    _rewarn(w for _, ws in parts for w in ws)
    return np.concatenate([rows for rows, _ in parts])


def _gather(futures: list, chunks: list[slice], bar: _RowBar | None) -> list:
    """The chunks' results in chunk order, gathered as they finish (the bar moves by each one's rows)."""
    distributed = require_distributed(WHAT)[1]
    index = {f.key: i for i, f in enumerate(futures)}
    parts: list = [None] * len(futures)
    for fut in distributed.as_completed(futures):
        i = index[fut.key]
        parts[i] = fut.result()  # a chunk's error is raised here, as the solver raised it
        if bar is not None:
            bar.chunk_done(chunks[i].stop - chunks[i].start)
    return parts


def _rewarn(caught) -> None:
    """Issue the workers' warnings here, each (category, message) once, in order."""
    for category, message in dict.fromkeys(caught):
        warnings.warn(message, category, stacklevel=3)
