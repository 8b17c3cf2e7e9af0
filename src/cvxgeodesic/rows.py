"""Rows of a distance matrix: the engines of :func:`~cvxgeodesic.api.distance_matrix`.

- :class:`RowStore`: the rows found so far, and the checkpoint file that keeps them (``checkpoint=``, the CLI's
  partial file): written as rows finish, on Ctrl-C and on an error; a call with the same arguments resumes from it.
- :func:`solve_rows`: the rows in this process, one solver, into a :class:`RowStore`, with a progress bar.
- :class:`LocalRows`: a solver of rows within ``max_distance`` of their source, each solved on the patch of the
  mesh around it (:func:`~cvxgeodesic.mesh.patch.ball_patch`), as sparse rows.
- :func:`distributed_rows`: rows on a Dask cluster. The rows are split into contiguous chunks, one per worker
  thread of the cluster. Every chunk is one task that builds one solver (the per-mesh set-up, paid once per
  chunk) and solves its rows in turn; the mesh is scattered to the workers once, and the rows come back in the
  order they were asked for. A local cluster's workers share the cores (``cpu_count // workers`` threads each,
  :func:`~cvxgeodesic._cluster.local_worker_environ`).

This module does not import :mod:`cvxgeodesic.api`: the caller passes the solver class
(``factory``), which reaches the workers by reference.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import pickle
import sys
import threading
import time
import warnings
from collections.abc import Callable, Iterator, Sequence
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import scipy.sparse as sp

from . import _signals, _verbose
from ._atomic import atomic_write, check_replaceable
from ._checkpoint import CHECKPOINT_FORMAT, checked_layout, checked_rows, read_checkpoint
from ._cluster import open_client, require_distributed, stop_after_interrupt
from ._threads import resolve_threads, thread_limit
from .errors import CheckpointWarning, ParameterError, warn_user
from .mesh.patch import ball_patch

if TYPE_CHECKING:
    from .mesh.simplex import SimplexMesh
    from .mesh.trimesh import TriMesh

__all__ = ["LocalRows", "RowStore", "checkpoint_rows", "cluster_rows", "distributed_rows", "keeping", "solve_rows",
           "sparse_to_file_order", "split_rows"]

#: Seconds an existing cluster without workers is given to get one before the run fails.
WORKER_WAIT = 60.0

WHAT = "distance_matrix on a Dask cluster (workers= or scheduler=, cvxgeodesic matrix --workers/--scheduler)"


#: Patch radius of a local row over ``max_distance`` (edge-graph distance; :func:`~cvxgeodesic.mesh.patch.ball_patch`).
#: Dijkstra's distance exceeds the geodesic one by at most 19 % on kitten (18.9K faces, 3 sources, vertices
#: within 10 % of the diagonal), so 1.5 holds the ball with a margin of ~1.25 r. Measured on kitten, r = 10 % of the
#: bounding-box diagonal, QCLP and QCQP-Hessian: the mean error against the exact distance inside r was 0.81–0.96×
#: the full solve's for every factor in 1.1–3 (the boundary of the patch does not reach inside r); 1.5 has
#: 1.4–1.5× the faces of 1.25 for about the same time (a row's fixed costs dominate).
PATCH_FACTOR = 1.5
#: Growth of the patch radius when the solved field is within ``max_distance`` somewhere on the patch's cut
#: (the ball may reach past the patch there).
PATCH_GROWTH = 1.5
#: Seconds between two writes of a checkpoint, at least; the finished rows are also written at the end, on Ctrl-C
#: and when a row fails.
SAVE_EVERY = 2.0
#: A checkpoint is written again only after SAVE_SHARE times its last write's duration: a large dense matrix
#: (1,000 rows of 100K vertices are 800 MB) then costs at most ~10 % of the time in writes.
SAVE_SHARE = 10.0
#: Options a checkpoint may be resumed across: the thread count changes at most the last digits of a row.
RESUMABLE_ACROSS = ("threads",)


def fingerprint(mesh: SimplexMesh, items: Sequence[Any], options: dict) -> dict[str, str]:
    """What a checkpoint's rows depend on, as short strings: the mesh, the sources, every option.

    Parameters
    ----------
    mesh : TriMesh or TetMesh
    items : sequence
        The distinct sources, one per row.
    options : dict
        Every option of the rows (method, m, ..., max_distance); arrays are hashed, anything else is its ``repr``;
        the options of :data:`RESUMABLE_ACROSS` are left out.

    Returns
    -------
    dict of str to str
    """
    def digest(*arrays: np.ndarray) -> str:
        h = hashlib.sha256()
        for a in arrays:
            h.update(str(a.dtype).encode() + str(a.shape).encode())
            h.update(np.ascontiguousarray(a).tobytes())
        return h.hexdigest()[:16]

    out = {"mesh": f"{mesh.n_vertices} vertices, {mesh.n_cells} cells, {digest(mesh.V, mesh.cells)}"}
    # a point or curve by its content (a curve's repr gives only its length)
    text = repr([int(i) if isinstance(i, int | np.integer)
                 else f"{type(i).__name__} {hashlib.sha256(pickle.dumps(i)).hexdigest()[:12]}" for i in items])
    out["sources"] = text if len(text) <= 60 else f"{len(items)} rows, {hashlib.sha256(text.encode()).hexdigest()[:16]}"
    from .capabilities import DOMAINS

    for key, value in sorted(options.items()):
        if key in RESUMABLE_ACROSS:
            continue
        if key == "order" and value is None and DOMAINS[mesh.domain].default_resolution == "mesh":
            value = 1  # no order on a domain solved on itself by default: order 1 (a cloud's default is another)
        value = _canonical(key, value)
        text = f"array {digest(value)}" if isinstance(value, np.ndarray) else repr(value)
        short = f"{type(value).__name__} {hashlib.sha256(text.encode()).hexdigest()[:12]}"
        out[key] = text if len(text) <= 60 else short
    return out


#: Options compared as what they mean, not as they were typed (:func:`_canonical`).
FLOAT_OPTIONS = ("m", "lam", "tol", "max_distance")
INT_OPTIONS = ("order", "max_iter")
NAME_OPTIONS = ("method", "solver", "normalization")
ARRAY_OPTIONS = ("cost", "metric")


def _canonical(key: str, value: Any) -> Any:
    """The value of option ``key`` as the solver reads it, so that ``m=1`` and ``m=1.0``, ``np.float64(1.0)``,
    ``"QCLP"`` and ``"qclp"``, ``"qgdf"`` and ``"lcqp-hessian"`` make the same fingerprint. A value that is not
    of the option's kind is kept as given (the solver refuses it with its own message)."""
    from .problems.formulations import ALIASES
    from .validation import is_integer, is_real

    if isinstance(value, bool | np.bool_):
        return bool(value)
    if key in FLOAT_OPTIONS and is_real(value):
        return float(value)
    if key in INT_OPTIONS and is_integer(value):
        return int(value)
    if key in NAME_OPTIONS and isinstance(value, str):
        return ALIASES.get(value.lower(), value.lower())
    if key in ARRAY_OPTIONS and value is not None:
        with contextlib.suppress(TypeError, ValueError):
            return np.asarray(value, dtype=np.float64)
    if key == "multires" and is_integer(value):
        return int(value)
    return value


class RowStore:
    """The rows of a matrix found so far, kept in a checkpoint file when one is given.

    Parameters
    ----------
    n_rows, n_cols : int
        Shape of the matrix (distinct sources × mesh vertices).
    sparse : bool
        Rows are ``(1, n_cols)`` CSR matrices (``max_distance``), else ``(n_cols,)`` float arrays.
    path : str or os.PathLike, optional
        The checkpoint (``.npz``): read when it exists (its rows are then done), written as rows finish.
    parameters : dict of str to str, optional
        :func:`fingerprint` of the call; a checkpoint made with other parameters is refused.

    Raises
    ------
    ParameterError
        The checkpoint is not one, or was made with other parameters (the message names them).
    """

    def __init__(self, n_rows: int, n_cols: int, *, sparse: bool, path: str | os.PathLike | None = None,
                 parameters: dict[str, str] | None = None) -> None:
        self.shape = (int(n_rows), int(n_cols))
        self.sparse = sparse
        self.path = None if path is None else Path(path)
        if self.path is not None:  # a read-only checkpoint is refused now, not at its first write after some rows
            check_replaceable(self.path, allow=None)
        self.parameters = dict(parameters or {})
        self.done = np.zeros(n_rows, dtype=bool)
        self.rows: dict[int, Any] = {}
        self.resumed = 0
        self._saved_at = time.monotonic()
        self._interval = SAVE_EVERY
        self._unsaved = False
        self.write_error: str | None = None  # why the checkpoint could not be written (then it no longer is)
        if self.path is not None and os.path.lexists(self.path):  # a link to nothing too: refused, not replaced
            self._load()
            self.resumed = int(self.done.sum())

    def put(self, i: int, row: Any) -> None:
        """Row ``i`` is done: its distances (an ``(n,)`` array, or a ``(1, n)`` CSR matrix)."""
        self.rows[int(i)] = row
        self.done[int(i)] = True
        self._unsaved = True

    def save(self, *, force: bool = True) -> None:
        """Write the finished rows to the checkpoint (atomically); unless ``force``, only when the last write is
        SAVE_EVERY seconds old and SAVE_SHARE times its own duration.

        A write that fails (a full disk, a folder gone) does not stop the rows: it warns once, naming the file
        and the reason, records it in ``write_error``, and the checkpoint is not written again in this call
        (the finished matrix is still returned; only a resume after a later interruption is lost).
        """
        if self.path is None or self.write_error is not None or not self._unsaved or not self.done.any():
            return
        start = time.monotonic()
        if not force and start - self._saved_at < self._interval:
            return
        arrays = self._arrays()

        def write(fh: Any) -> None:
            with contextlib.suppress(AttributeError, OSError):  # private: read back only if no one else may write it
                os.fchmod(fh.fileno(), 0o600)
            np.savez(fh, **arrays)  # type: ignore[arg-type]

        try:
            atomic_write(self.path, write)
        except OSError as exc:
            self.write_error = (f"the finished rows could not be written to the checkpoint {self.path} "
                                f"({exc.strerror or exc})")
            warn_user(f"distance_matrix: {self.write_error}; the rows go on without it (an interruption now loses "
                      "them)", CheckpointWarning)
            return
        self._saved_at = time.monotonic()
        self._interval = max(SAVE_EVERY, SAVE_SHARE * (self._saved_at - start))
        self._unsaved = False

    def matrix(self, inverse: np.ndarray) -> np.ndarray | sp.csr_matrix:
        """The finished matrix, one row per entry of ``inverse`` (an index into the distinct rows)."""
        order = [self.rows[int(i)] for i in inverse]
        if not self.sparse:
            return np.stack(order) if order else np.zeros((0, self.shape[1]))
        return _vstack_keeping_zeros(order, self.shape[1])

    def _arrays(self) -> dict[str, np.ndarray]:
        index = np.flatnonzero(self.done)
        out: dict[str, np.ndarray] = {"format": np.array(CHECKPOINT_FORMAT), "shape": np.array(self.shape),
                                      "sparse": np.array(self.sparse), "index": index,
                                      "parameters": np.array(json.dumps(self.parameters, sort_keys=True))}
        if self.sparse:
            rows = [self.rows[int(i)] for i in index]
            out["lengths"] = np.array([r.nnz for r in rows], dtype=np.int64)
            out["cols"] = np.concatenate([r.indices for r in rows]).astype(np.int64)
            out["vals"] = np.concatenate([r.data for r in rows]).astype(np.float64)
        else:
            out["rows"] = np.stack([self.rows[int(i)] for i in index])
        return out

    def _load(self) -> None:
        assert self.path is not None
        data = read_checkpoint(self.path)
        theirs = checked_layout(data, self.path)
        differ = [k for k in sorted(set(theirs) | set(self.parameters)) if theirs.get(k) != self.parameters.get(k)]
        if differ or tuple(data["shape"]) != self.shape or bool(data["sparse"]) != self.sparse:
            shown = "; ".join(f"{k}: {theirs.get(k, '-')} there, {self.parameters.get(k, '-')} here" for k in differ)
            raise ParameterError(f"checkpoint {self.path} was made with other parameters ({shown or 'shape'}); "
                                 "delete it to start again, or give another path")
        index = checked_rows(data, self.path, self.shape, self.sparse)
        if self.sparse:
            bounds = np.concatenate([[0], np.cumsum(data["lengths"])])
            cols, vals = data["cols"].astype(np.int64), data["vals"]
            for k, i in enumerate(index):
                a, b = bounds[k], bounds[k + 1]
                self.put(i, _sparse_row(cols[a:b], vals[a:b], self.shape[1]))
        else:
            for k, i in enumerate(index):
                self.put(i, data["rows"][k])
        self._unsaved = False


def checkpoint_rows(path: str | os.PathLike) -> tuple[int, int] | None:
    """``(finished rows, distinct rows)`` of a checkpoint file, or None when there is none or it is unreadable,
    untrusted (:func:`read_checkpoint`) or damaged."""
    try:
        data = read_checkpoint(Path(path))
        checked_layout(data, Path(path))
        return int(data["index"].size), int(data["shape"][0])
    except (ParameterError, KeyError):
        return None


def _sparse_row(cols: np.ndarray, vals: np.ndarray, n: int) -> sp.csr_matrix:
    """A (1, n) CSR row holding ``vals`` at ``cols``, zeros included (a source's distance is a stored 0)."""
    order = np.argsort(cols, kind="stable")
    return sp.csr_matrix((np.asarray(vals, dtype=np.float64)[order], np.asarray(cols, dtype=np.int64)[order],
                          np.array([0, len(cols)])), shape=(1, n))


def _vstack_keeping_zeros(rows: Sequence[sp.csr_matrix], n: int) -> sp.csr_matrix:
    """CSR matrices of ``n`` columns one under the other, stored zeros kept (``vstack`` of CSR blocks joins their
    arrays; a source's distance is a stored 0)."""
    return sp.vstack(rows, format="csr", dtype=np.float64) if rows else sp.csr_matrix((0, n))


def sparse_to_file_order(mesh: SimplexMesh, D: sp.csr_matrix) -> sp.csr_matrix:
    """Columns of a sparse matrix in the numbering of the file ``mesh`` was read from, stored zeros kept.

    Parameters
    ----------
    mesh : TriMesh or TetMesh
    D : (k, n) CSR matrix
        Columns are mesh vertices.

    Returns
    -------
    (k, n_file) CSR matrix
        Welded duplicates share their mesh vertex's entries; file vertices in no face have none.
    """
    file_index = np.asarray(mesh.file_index, dtype=np.int64)
    n = mesh.n_vertices
    # an empty column n more, for the file vertices in no face; column indexing keeps the stored zeros
    padded = sp.csr_matrix((D.data, D.indices, D.indptr), shape=(D.shape[0], n + 1))
    out = padded[:, np.where(file_index >= 0, file_index, n)].tocsr()
    out.sort_indices()
    return out


@dataclass(frozen=True)
class LocalRow:
    """One local row: ``distance`` is a (1, n) CSR matrix of the distances within ``max_distance``."""

    distance: sp.csr_matrix
    patch_faces: int


class LocalRows:
    """A solver of rows within ``max_distance``: every row solved on the patch of the mesh around its source.

    The patch is the faces within ``PATCH_FACTOR · max_distance`` of the source on the edge graph
    (:func:`~cvxgeodesic.mesh.patch.ball_patch`), solved by ``factory`` (a :class:`~cvxgeodesic.api.GeodesicSolver`)
    with the whole mesh's smoothness: λ is computed once on the whole mesh and scaled by the ratio of the whole
    surface's area to the patch's (the stretch term is a mean over the surface solved), so that the patch's program
    is the whole one restricted to the patch. A row whose field is within ``max_distance`` on the patch's cut is
    solved again on a patch ``PATCH_GROWTH`` times wider.

    Parameters
    ----------
    mesh : TriMesh
    max_distance : float
        Distances kept, > 0.
    factory : callable
        ``factory(patch_mesh, **options)`` builds a solver whose ``solve(vertex).distance`` is the field.
    **options
        Keyword arguments of ``factory`` (``method``, ``m``, ``lam``, ``normalization``, ``order``, ...).
    """

    def __init__(self, mesh: TriMesh, *, max_distance: float, factory: Callable[..., Any], **options: Any) -> None:
        self.mesh = mesh
        self.max_distance = float(max_distance)
        self.factory = factory
        self.options = dict(options)
        self.lam = _whole_mesh_lambda(mesh, self.options)
        self.threads = resolve_threads(self.options.get("threads"))  # once: every patch's solver runs under it
        self.options["threads"] = self.threads
        self.paper = self.options.get("normalization", "area") == "paper"
        self.size = float(mesh.face_areas.sum())

    def solve(self, vertex: int) -> LocalRow:
        """The row of source ``vertex``: a :class:`LocalRow` whose ``distance`` holds the distances ≤ max_distance."""
        with thread_limit(self.threads):  # free inside solve_rows' limit; else once for the patch's two calls
            return self._solve(int(vertex))

    def _solve(self, vertex: int) -> LocalRow:
        r = self.max_distance
        radius = PATCH_FACTOR * r
        while True:
            patch = ball_patch(self.mesh, vertex, radius)
            if patch.mesh is None:  # a source in no face (or faces longer than the radius: grow)
                if self.mesh.referenced[vertex] and radius < np.inf:
                    radius = np.inf
                    continue
                return LocalRow(_sparse_row(np.array([vertex]), np.zeros(1), self.mesh.n_vertices), 0)
            d = self._field(patch)
            if patch.cut.size == 0 or d[patch.cut].min() > r:
                break
            radius *= PATCH_GROWTH
        cloud = getattr(self.mesh, "cloud", None)
        if cloud is not None and cloud.left_out.size:  # a cloud's points in no triangle, carried as in whole rows
            whole = np.full(self.mesh.n_vertices, np.inf)
            whole[patch.vertices] = d
            whole = cloud.reach_left_out(whole)[0]
            near = np.flatnonzero(whole <= r)
            return LocalRow(_sparse_row(near, whole[near], self.mesh.n_vertices), patch.mesh.n_faces)
        keep = d <= r
        return LocalRow(_sparse_row(patch.vertices[keep], d[keep], self.mesh.n_vertices), patch.mesh.n_faces)

    def _field(self, patch: Any) -> np.ndarray:
        options = dict(self.options)
        if self.lam is not None:
            scale = (self.mesh.n_vertices / patch.mesh.n_vertices if self.paper
                     else self.size / float(patch.mesh.face_areas.sum()))
            options["lam"] = self.lam * scale
        return self.factory(patch.mesh, **options).solve(patch.source).distance


def _whole_mesh_lambda(mesh: TriMesh, options: dict) -> float | None:
    """λ of the whole mesh (None without a smoothness energy or for an unknown method: the solver says why)."""
    from .capabilities import DOMAINS
    from .problems.formulations import ALIASES, FORMULATIONS, canonical_method, smoothness_weight
    from .validation import check_lam, check_smoothness

    m, lam = check_smoothness(options.get("m", 1.0), options.get("lam"))
    method = options.get("method") or DOMAINS[mesh.domain].default_method  # the solver's default of the domain
    if not isinstance(method, str) or method.lower() not in FORMULATIONS and method.lower() not in ALIASES:
        return None
    energy = FORMULATIONS[canonical_method(method)][1]
    if energy is None:
        return None
    normalization, order = options.get("normalization", "area"), options.get("order") or 1  # None: order 1
    if lam is not None:  # its range on the whole mesh: each patch takes it scaled, unchecked (api._PatchSolver)
        return check_lam(lam, smoothness_weight(mesh, 1.0, normalization, energy, order=order))
    return smoothness_weight(mesh, m, normalization, energy, order=order)


def solve_rows(factory: Callable[..., Any], mesh: SimplexMesh, items: Sequence[Any], options: dict, store: RowStore, *,
               progress: bool | None, desc: str) -> None:
    """Solve the rows ``store`` has not got, in this process, with one solver; each row into ``store`` as it ends.

    Parameters
    ----------
    factory : callable
        ``factory(mesh, **options)`` builds the solver (built only when a row is left).
    mesh : TriMesh or TetMesh
    items : sequence
        The source of each distinct row.
    options : dict
    store : RowStore
        Receives the rows; its checkpoint is written every SAVE_EVERY seconds, at the end, and when a row fails
        or Ctrl-C stops it (the exception then says how many rows were kept).
    progress : bool or None
        True: a row bar on stderr; None: the bar shows once the rows have run for
        :data:`~cvxgeodesic._verbose.PROGRESS_DELAY` seconds; False: none.
    desc : str
        Label of the bar.
    """
    _say_resumed(store, progress)
    todo = np.flatnonzero(~store.done)
    if todo.size == 0:
        return
    with _row_bar(len(items), store.resumed, desc, progress) as bar, keeping(store):
        # one thread limit around the rows: each solve's own (the same count) is then free, not ~10 ms of library
        # discovery by threadpoolctl (measured: 16 % of a local row's time on kitten)
        with thread_limit(resolve_threads(options.get("threads"))):
            solver = factory(mesh, **options)
            for i in todo:
                store.put(int(i), solver.solve(items[int(i)]).distance)
                _signals.check()  # a command-line Ctrl-C whose exception a ctypes callback swallowed during the row
                store.save(force=False)
                bar.update(1)


def cluster_rows(factory: Callable[..., Any], mesh: SimplexMesh, items: Sequence[Any], options: dict,
                 store: RowStore, *, scheduler: Any, workers: int | None, progress: bool | None, desc: str) -> None:
    """:func:`solve_rows` on a Dask cluster (:func:`distributed_rows`): the rows ``store`` has not got, each chunk's
    rows into ``store`` (and its checkpoint) as the chunk finishes."""
    _say_resumed(store, progress)
    todo = np.flatnonzero(~store.done)
    if todo.size == 0:
        return

    def keep(chunk: slice, rows: Any) -> None:
        for i, row in zip(todo[chunk], rows, strict=True):
            store.put(int(i), row)
        store.save()

    with keeping(store):
        distributed_rows(factory, mesh, [items[i] for i in todo], options, scheduler=scheduler, workers=workers,
                         progress=progress, desc=desc, on_chunk=keep)


def _say_resumed(store: RowStore, progress: bool | None) -> None:
    """One line on stderr when rows were taken from the checkpoint (after it was accepted), unless ``progress`` is
    False."""
    if store.resumed and progress is not False:
        print(f"resuming from {store.path}: {store.resumed} of {store.shape[0]} rows already done", file=sys.stderr,
              flush=True)


@contextlib.contextmanager
def keeping(store: RowStore) -> Iterator[None]:
    """Write the finished rows whatever happens; an error or Ctrl-C gets a note on what was kept."""
    try:
        yield
    except BaseException as exc:
        try:
            store.save()
        except Exception as save_error:  # the row's error (or Ctrl-C) stays the one raised; the save's is a note
            exc.add_note(f"distance_matrix: the finished rows could not be written to {store.path}: {save_error}")
            raise exc from None
        if store.write_error is not None:
            exc.add_note(f"distance_matrix: {store.write_error}")
            raise
        done = int(store.done.sum())
        if store.path is not None and done:
            exc.add_note(f"distance_matrix: {done} of {store.shape[0]} rows kept in {store.path}; "
                         "the same call resumes from there")
        elif done and isinstance(exc, KeyboardInterrupt):
            exc.add_note(f"distance_matrix: {done} of {store.shape[0]} rows were done; with checkpoint='rows.npz' "
                         "they are kept and the same call resumes")
        raise
    store.save()


def _row_bar(total: int, initial: int, desc: str, progress: bool | None) -> Any:
    """Rows counted on stderr (from PROGRESS_DELAY seconds on, read now, when ``progress`` is None): a tqdm bar in a
    terminal, else :class:`RowLines`."""
    delay = _verbose.PROGRESS_DELAY if progress is None else 0.0
    if progress is not False and not getattr(sys.stderr, "isatty", lambda: False)():
        return RowLines(total, initial, desc, sys.stderr, delay=delay)
    from tqdm import tqdm

    return tqdm(total=total, initial=initial, desc=desc, unit="row", file=sys.stderr, disable=progress is False,
                delay=delay)


#: Seconds between two lines of :class:`RowLines`.
LINE_EVERY = 10.0


class RowLines:
    """Rows counted where the output is no terminal (a log file, a pipe): one plain line every LINE_EVERY seconds.

    A tqdm bar redraws itself up to ten times a second with carriage returns, which only a terminal folds back into
    one line: written to a file, 1,000 rows were 45 KB of redraws. Here a line such as
    ``qclp: rows 120/1000, 12 s, ~88 s left`` is written once ``delay`` seconds have passed (at once when it is 0,
    and again when the first row is done), then at most every LINE_EVERY seconds, and a last one when the rows end
    (only if an earlier line was written).

    Parameters
    ----------
    total, initial : int
        Rows in all, and already done (resumed from a checkpoint).
    desc : str
        Label at the start of each line.
    stream : text file
    delay : float
        Seconds before the first line.
    clock : callable, optional
        Seconds as a float (for tests).
    """

    def __init__(self, total: int, initial: int, desc: str, stream: Any, *, delay: float,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.total, self.n, self.initial = int(total), int(initial), int(initial)
        self.desc, self.stream, self.delay, self.clock = desc, stream, float(delay), clock
        self.start = clock()
        self.last: float | None = None  # when the last line was written
        self.shown = -1  # the count it showed
        if self.delay <= 0:  # shown from the start (progress=True): the rows are under way
            self._line(self.start)

    def update(self, k: int = 1) -> None:
        self.n += k
        now = self.clock()
        # the first finished row at once (its time gives the first estimate), then every LINE_EVERY seconds
        due = self.last is None or self.shown == self.initial or now - self.last >= LINE_EVERY
        if now - self.start >= self.delay and due:
            self._line(now)

    def close(self) -> None:
        if self.last is not None and self.shown != self.n:
            self._line(self.clock())

    def _line(self, now: float) -> None:
        elapsed = now - self.start
        done = self.n - self.initial
        left = f", ~{elapsed / done * (self.total - self.n):.0f} s left" if 0 < done and self.n < self.total else ""
        print(f"{self.desc}: rows {self.n}/{self.total}, {elapsed:.0f} s{left}", file=self.stream, flush=True)
        self.last, self.shown = now, self.n

    def __enter__(self) -> RowLines:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


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


def solve_chunk(factory: Callable[..., Any], mesh: SimplexMesh, items: Sequence[Any], options: dict,
                topic: str | None = None) -> tuple[np.ndarray, list[tuple[type[Warning], str]]]:
    """The task of one chunk, on a worker: one solver, its rows in order, and the warnings they raised.

    Parameters
    ----------
    factory : callable
        ``factory(mesh, **options)`` builds the solver (:class:`~cvxgeodesic.api.GeodesicSolver`).
    mesh : TriMesh or TetMesh
    items : sequence
        The sources of each row (anything ``solve`` takes).
    options : dict
        Keyword arguments of ``factory``.
    topic : str, optional
        Dask event topic that gets one event per solved row (the client's progress bar).

    Returns
    -------
    rows : (len(items), n) float ndarray, or CSR matrix for sparse rows (:class:`LocalRows`)
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
    return _stack(rows), [(w.category, str(w.message)) for w in caught]


def _stack(rows: Sequence[Any]) -> Any:
    """Rows (or chunks of rows) one under the other: dense arrays, or CSR matrices keeping their stored zeros."""
    if rows and sp.issparse(rows[0]):
        return _vstack_keeping_zeros([sp.csr_matrix(r) for r in rows], rows[0].shape[1])
    return np.concatenate([np.atleast_2d(r) for r in rows])


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
    """A row-counting bar (:func:`_row_bar`) fed from two threads: worker events (per row) and finished chunks."""

    def __init__(self, bar: Any) -> None:
        self.bar = bar
        self.lock = threading.Lock()
        self.events = 0
        self.done = 0
        self.closed = False

    def _show(self) -> None:
        target = min(self.bar.total, max(self.events, self.done))
        if target > self.bar.n and not self.closed:  # an event may arrive after the run ended
            self.bar.update(target - self.bar.n)

    def event(self, _event: Any) -> None:
        with self.lock:
            self.events += 1
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


def distributed_rows(factory: Callable[..., Any], mesh: SimplexMesh, items: Sequence[Any], options: dict, *,
                     scheduler: Any = None, workers: int | None = None, progress: bool | None = False,
                     desc: str = "rows", on_chunk: Callable[[slice, Any], None]) -> None:
    """Solve one row per item on a Dask cluster, in contiguous chunks, each chunk's rows to ``on_chunk``.

    Parameters
    ----------
    factory : callable
        ``factory(mesh, **options)`` builds a solver whose ``solve(item).distance`` is a row; it must be
        importable on the workers (it is sent by reference).
    mesh : TriMesh or TetMesh
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
    progress : bool or None
        A progress bar counting rows on stderr; None: shown after :data:`~cvxgeodesic._verbose.PROGRESS_DELAY`
        seconds.
    desc : str
        Label of the progress bar.
    on_chunk : callable
        ``on_chunk(rows_slice, rows)`` as each chunk finishes (before the others): where ``distance_matrix``
        keeps them, ``(len(rows_slice), n)`` float ndarray or CSR matrix (sparse rows). They are not kept here
        (a matrix held once, not three times).

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
        topic = f"cvxgeodesic-rows-{token}" if progress is not False else None
        bar = _RowBar(_row_bar(len(items), 0, desc, progress)) if progress is not False else None
        if bar is not None:  # before the tasks start, so that no row's event is missed
            client.subscribe_topic(topic, bar.event)
        futures: list = []
        try:  # the scatter too: the workers import the package while they unpickle the mesh, seconds of it
            mesh_future = client.scatter(mesh, broadcast=True, hash=False)
            futures = [client.submit(solve_chunk, factory, mesh_future, items[s], options, topic,
                                     key=f"cvxgeodesic-rows-{i}-{token}", pure=False)
                       for i, s in enumerate(chunks)]
            caught = _gather(futures, chunks, bar, on_chunk)
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
    _rewarn(w for ws in caught for w in ws)


def _gather(futures: list, chunks: list[slice], bar: _RowBar | None, on_chunk: Callable[[slice, Any], None]) -> list:
    """Each chunk's rows to ``on_chunk`` as it finishes (the bar moves by its rows); the warnings, in chunk order."""
    distributed = require_distributed(WHAT)[1]
    index = {f.key: i for i, f in enumerate(futures)}
    caught: list = [None] * len(futures)
    for fut in distributed.as_completed(futures):
        i = index[fut.key]
        rows, caught[i] = fut.result()  # a chunk's error is raised here, as the solver raised it
        on_chunk(chunks[i], rows)
        if bar is not None:
            bar.chunk_done(chunks[i].stop - chunks[i].start)
    return caught


def _rewarn(caught) -> None:
    """Issue the workers' warnings here, each (category, message) once, in order."""
    for category, message in dict.fromkeys(caught):
        warnings.warn(message, category, stacklevel=3)
