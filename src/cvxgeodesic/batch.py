"""Distance fields for many meshes on a Dask cluster: the engine behind ``cvxgeodesic batch``.

:func:`run_batch` runs one Dask task per mesh. By default it starts a
``dask.distributed.LocalCluster`` on this machine (worker processes with one
thread each); ``scheduler="tcp://SCHEDULER:8786"`` uses an existing cluster instead,
whose workers must have cvxgeodesic installed and see the mesh files and the
output folder at the same paths (a shared file system).

Every task loads its mesh, solves, and writes, atomically,

- ``OUT/<mesh stem>.ply`` (mesh + per-vertex ``distance``, read it with
  :func:`~cvxgeodesic.mesh.io.load_distance_ply`), ``OUT/<mesh stem>.vtu`` (the mesh, tetrahedra
  included, + the field as point data, for ParaView) or ``OUT/<mesh stem>.npy``
  (the (n_file,) array), all in the file's vertex numbering and count (welded duplicates
  share a value, vertices in no face get ``inf``; see
  :func:`~cvxgeodesic.mesh.fileorder.to_file_order`); without a format, ``.ply`` for a surface and
  ``.vtu`` for a tetrahedral mesh (:data:`DEFAULT_FORMATS`: PLY holds no tetrahedra), then
- ``OUT/<mesh stem>.json``: the mesh path, the parameters, the mesh's dimension and size, the
  :class:`~cvxgeodesic.api.SolveInfo` as a dict, ``warnings`` (from loading) and
  ``notes`` (every repair, substitution and warning of the task, each once).

The JSON file is written last, so it marks a finished mesh: a rerun skips every
mesh whose two outputs exist and were computed with the same parameters
(``force=True`` recomputes them). A mesh that fails (unreadable file, source out
of range, solver failure, worker crash) gives a ``"failed"`` row with the error
and does not stop the others.

Dask is an optional dependency (``pip install 'cvxgeodesic[cluster]'``); it is
imported only when a batch runs.
"""

from __future__ import annotations

import glob
import json
import math
import os
import socket
import sys
import time
import warnings
from contextlib import ExitStack
from pathlib import Path

import numpy as np

from ._atomic import check_output_dir, check_replaceable
from ._cluster import open_client, require_distributed, stop_after_interrupt
from .errors import ParameterError, error_line
from .tables import Column, text_table
from .validation import check_choice, check_count, check_not_an_input, check_smoothness

__all__ = ["DEFAULT_FORMATS", "OUTPUT_FORMATS", "expand_mesh_paths", "format_summary", "output_paths", "run_batch",
           "solve_one"]

#: Formats of the distance file written per mesh (each one's meshes: ``Format.dims`` in
#: :data:`~cvxgeodesic.mesh.formats.registry.FORMATS`).
OUTPUT_FORMATS = ("ply", "npy", "vtu")
#: The format of a mesh's distance file when none is given, by the mesh's simplex dimension.
DEFAULT_FORMATS = {2: "ply", 3: "vtu"}


def expand_mesh_paths(patterns) -> list[Path]:
    """Mesh files named by paths and glob patterns.

    Parameters
    ----------
    patterns : str or sequence of str
        File names or patterns (``*``, ``?``, ``[...]``; ``**`` matches any depth).
        A pattern keeps only files with an extension that :func:`~cvxgeodesic.mesh.io.load_mesh` reads,
        surfaces' and volumes' (``.obj``, ..., ``.msh``, ``.ele``; TetGen's ``.node`` only where no ``.ele`` of
        the same name matched: the two are one mesh); a plain file name is kept whatever its extension (so
        that a wrong file is reported, not silently dropped).

    Returns
    -------
    list of pathlib.Path
        Absolute paths, sorted, without duplicates.

    Raises
    ------
    ParameterError
        Nothing matches.
    """
    from .mesh.formats.registry import MESH_EXTENSIONS, VOLUME_EXTENSIONS

    readable = tuple(dict.fromkeys((*MESH_EXTENSIONS, *VOLUME_EXTENSIONS)))
    if isinstance(patterns, str | os.PathLike):
        patterns = [patterns]
    found: dict[Path, None] = {}
    for pat in patterns:
        pat = os.fspath(pat)
        if glob.has_magic(pat):
            for name in sorted(glob.glob(os.path.expanduser(pat), recursive=True)):
                p = Path(name)
                if p.is_file() and p.suffix.lower() in readable:
                    found[p.resolve()] = None
        else:
            p = Path(pat).expanduser()
            if p.is_dir():
                raise ParameterError(f"{p} is a directory; give mesh files or a pattern such as '{p}/*.obj'")
            if not p.exists():
                raise ParameterError(f"{p}: no such file")
            found[p.resolve()] = None
    if not found:
        raise ParameterError(f"no mesh file ({', '.join(readable)}) matches {' '.join(map(str, patterns))}")
    return sorted(_one_per_tetgen_pair(found))


def _one_per_tetgen_pair(paths) -> list[Path]:
    """``paths`` without each TetGen ``.node`` whose ``.ele`` is among them (either names the one mesh)."""
    eles = {(p.parent, p.stem) for p in paths if p.suffix.lower() == ".ele"}
    return [p for p in paths if not (p.suffix.lower() == ".node" and (p.parent, p.stem) in eles)]


def output_paths(mesh_path, out_dir, output_format: str = "ply") -> tuple[Path, Path]:
    """``(OUT/<stem>.<format>, OUT/<stem>.json)`` for one mesh and format."""
    stem = Path(mesh_path).stem
    out = Path(out_dir)
    return out / f"{stem}.{output_format}", out / f"{stem}.json"


def _output_formats(mesh_path, output_format: str | None) -> tuple[str, ...]:
    """The formats the distance file of ``mesh_path`` may have before the mesh is read: the one given, else the
    default of each dimension its extension may hold (a VTK file holds either; an unknown extension fails on
    loading)."""
    from .mesh.formats.registry import FORMATS

    if output_format is not None:
        return (output_format,)
    fmt = FORMATS.get(Path(mesh_path).suffix.lower())
    dims = fmt.dims if fmt is not None and fmt.read_mesh is not None else (2,)
    return tuple(dict.fromkeys(DEFAULT_FORMATS[d] for d in dims))


def _output_format(mesh, mesh_path, output_format: str | None) -> str:
    """The format of the distance file of the loaded ``mesh``: the one given, if it holds the mesh's dimension
    (else ParameterError, before the solve), or its dimension's default; one that needs an optional package not
    installed fails now too (ParameterError)."""
    from .mesh.formats._common import optional_package
    from .mesh.formats.registry import FORMATS

    fmt = output_format or DEFAULT_FORMATS[mesh.dim]
    spec = FORMATS["." + fmt]
    if mesh.dim not in spec.dims:
        fits = [f for f in OUTPUT_FORMATS if mesh.dim in FORMATS["." + f].dims]
        kind = "a tetrahedral mesh" if mesh.dim == 3 else "a triangle mesh"
        raise ParameterError(f"{Path(mesh_path).name} is {kind}: its field cannot be written as .{fmt} "
                             f"({spec.description} holds no {'tetrahedra' if mesh.dim == 3 else 'triangles'}); "
                             f"give --format {' or '.join(fits)}, or no --format (.{DEFAULT_FORMATS[mesh.dim]})")
    if spec.package is not None:
        optional_package(spec.package, f"writing .{fmt} files", ParameterError)
    return fmt


def _source_spec(sources):
    """JSON form of batch sources: ``"boundary"``, or a list of vertex indices and ``[x, y, z]`` positions."""
    if isinstance(sources, str):
        if sources.lower() != "boundary":
            raise ParameterError(f"unknown source {sources!r}: the only named source is 'boundary'")
        return "boundary"
    items = list(sources) if isinstance(sources, list | tuple) else [sources]
    if not any(isinstance(s, list | tuple) for s in items):
        src = np.atleast_1d(np.asarray(sources))
        if src.ndim != 1 or src.size == 0 or src.dtype.kind not in "iu" or (src < 0).any():
            raise ParameterError(f"sources must be one or more vertex indices >= 0, got {sources!r}")
        if len(np.unique(src)) != src.size:
            raise ParameterError(f"sources contain a duplicate: {src.tolist()}")
        return [int(s) for s in src]
    out = []
    for s in items:
        if isinstance(s, list | tuple):
            if len(s) != 3 or not all(isinstance(c, int | float) and math.isfinite(c) for c in s):
                raise ParameterError(f"a source position must be 3 finite numbers, got {s!r}")
            out.append([float(c) for c in s])
        elif isinstance(s, int | np.integer) and not isinstance(s, bool) and s >= 0:
            out.append(int(s))
        else:
            raise ParameterError(f"sources must be vertex indices >= 0 or [x, y, z] positions, got {s!r}")
    return out


def _mesh_sources(mesh, spec):
    """The ``sources`` of one mesh: file vertex indices become mesh indices, positions its closest surface points
    (inside a tetrahedral mesh, the points themselves)."""
    if spec == "boundary":
        return spec
    from .mesh.fileorder import file_sources

    if all(isinstance(s, int) for s in spec):
        return file_sources(mesh, spec).tolist()
    at = mesh.reference.locate  # the closest surface point, or the point inside the solid
    return [int(file_sources(mesh, [s])[0]) if isinstance(s, int) else at(mesh, s) for s in spec]


def _params(sources, method, m, solver, multires, output_format) -> dict:
    return {"sources": _source_spec(sources), "numbering": "file", "method": method, "m": float(m),
            "solver": solver, "multires": multires if isinstance(multires, bool) else int(multires),
            "format": output_format}


def _json_safe(obj):
    """Replace NaN/inf by None and numpy scalars by Python numbers, recursively (strict JSON)."""
    if isinstance(obj, dict):
        return {str(k): _json_safe(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_json_safe(v) for v in obj]
    if isinstance(obj, np.generic):
        obj = obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if isinstance(obj, str | int | float | bool) or obj is None:
        return obj
    return str(obj)


def _finished(dist_path: Path, sidecar: Path, params: dict) -> bool | None:
    """True: done with these parameters; False: not done; None: done with other parameters."""
    if not (dist_path.is_file() and sidecar.is_file()):
        return False
    try:
        meta = json.loads(sidecar.read_text())
    except (OSError, ValueError):
        return False
    if not isinstance(meta, dict) or meta.get("status") != "ok":  # a sidecar of another shape: not ours, redo
        return False
    if params["method"] is None:  # the default: done if solved with the default of the mesh's dimension
        from .api import DEFAULT_METHODS

        dim = meta.get("dim", 2)  # absent in older files: taken as a surface (at worst the mesh is solved again)
        params = {**params, "method": DEFAULT_METHODS.get(dim) if isinstance(dim, int) else None}
    return True if meta.get("params") == params else None


def solve_one(mesh_path: str, sources: list[int], out_dir: str, method: str | None = None, m: float = 1.0,
              solver: str = "auto", multires: bool | int = False, output_format: str | None = None) -> dict:
    """Load one mesh, solve, write its outputs; the task that :func:`run_batch` runs on a worker.

    Never raises: a failure is returned as a row with ``status="failed"``.

    Parameters
    ----------
    mesh_path : str
        Mesh file (absolute path, visible to the worker).
    sources : list of int and [x, y, z] positions, or "boundary"
        Source vertices as vertex indices of the file (before welding; see
        :func:`~cvxgeodesic.mesh.fileorder.file_sources`), positions (the mesh's closest
        surface points) or the boundary.
    out_dir : str
        Existing output folder.
    method, m, solver, multires
        See :class:`~cvxgeodesic.api.GeodesicSolver` (method None: its default for the mesh's dimension).
    output_format : {"ply", "npy", "vtu"} or None
        None: by the mesh's dimension (:data:`DEFAULT_FORMATS`). A format that cannot hold the mesh (``"ply"``
        for tetrahedra) fails the row before the solve.

    Returns
    -------
    dict
        A row of :func:`run_batch`'s result.
    """
    t0 = time.perf_counter()
    row = _row(mesh_path, "failed", worker=socket.gethostname())
    caught: list[warnings.WarningMessage] = []
    try:
        from . import __version__
        from ._atomic import atomic_write
        from .api import DEFAULT_METHODS, GeodesicSolver
        from .mesh.io import load_mesh, save_distance

        # every warning of the task becomes a note of its row (a worker's stderr would print it as raw
        # "file.py:309: Warning: ..." text inside the client's progress bar)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            mesh = load_mesh(mesh_path)
            row["warnings"] = [str(w.message) for w in caught]
            row["n_vertices"], row["n_faces"] = mesh.n_file_vertices, mesh.n_cells  # tetrahedra in a volume
            output_format = _output_format(mesh, mesh_path, output_format)  # before the solve: it may not fit
            dist_path, sidecar = output_paths(mesh_path, out_dir, output_format)
            src = _mesh_sources(mesh, sources)  # vertex indices are the file's
            method = method or DEFAULT_METHODS[mesh.dim]  # recorded as if given: a rerun naming it skips the mesh
            res = GeodesicSolver(mesh, method, m=m, solver=solver, multires=multires).solve(src)
            save_distance(dist_path, mesh, res.distance, file_order=True)
        row["notes"] = _unique([*res.info.notes, *(str(w.message) for w in caught)])
        row.update(status="ok", output=str(dist_path), iterations=res.info.iterations,
                   solve_status=res.info.status, time_s=time.perf_counter() - t0)
        meta = {"status": "ok", "mesh": mesh_path, "output": dist_path.name, "cvxgeodesic": __version__,
                "params": _params(sources, method, m, solver, multires, output_format), "dim": mesh.dim,
                "n_vertices": mesh.n_file_vertices, "n_mesh_vertices": mesh.n_vertices, "n_faces": mesh.n_cells,
                "wall_time": row["time_s"], "worker": row["worker"], "warnings": row["warnings"],
                "notes": row["notes"], "info": res.info.as_dict()}
        text = json.dumps(_json_safe(meta), indent=1, allow_nan=False) + "\n"
        atomic_write(sidecar, lambda fh: fh.write(text.encode("utf-8")))
    except Exception as exc:  # one bad mesh must not stop the batch: report it in the row
        row.update(status="failed", output=None, error=error_line(exc, typed=True), time_s=time.perf_counter() - t0,
                   notes=_unique(str(w.message) for w in caught))
    return row


def _row(mesh, status: str, **values) -> dict:
    """A row of :func:`run_batch`'s result: every key, None (no lists) where ``values`` gives none."""
    return {"mesh": str(mesh), "status": status, "output": None, "n_vertices": None, "n_faces": None,
            "iterations": None, "solve_status": None, "time_s": None, "error": None, "warnings": [], "notes": [],
            "worker": None, **values}


def _unique(lines) -> list[str]:
    """The lines in order, each once."""
    return list(dict.fromkeys(str(x) for x in lines))


def run_batch(paths, sources, out_dir, *, method: str | None = None, m: float = 1.0, solver: str = "auto",
              scheduler=None, n_workers: int = 2, force: bool = False, progress: bool = True,
              multires: bool | int = False, output_format: str | None = None) -> list[dict]:
    """Solve the same sources on many meshes, one Dask task per mesh.

    Parameters
    ----------
    paths : sequence of str or Path
        Mesh files (see :func:`expand_mesh_paths` for globs). Their stems must
        be distinct: each names the outputs ``out_dir/<stem>.<format|json>``.
    sources : int, sequence of int and [x, y, z] positions, or "boundary"
        Source vertex indices, the same for every mesh (a mesh where one is out
        of range fails, the others go on); a position is each mesh's closest
        surface point (in a tetrahedral mesh, the point inside); ``"boundary"`` each mesh's boundary.
    out_dir : str or Path
        Output folder, created if missing. With a remote ``scheduler`` it must
        be writable by the workers at the same path.
    method, m, solver, multires
        See :class:`~cvxgeodesic.api.GeodesicSolver`; method None (default): its default on each mesh,
        ``"qcqp-hessian"`` on a surface, ``"qclp"`` on a tetrahedral mesh.
    scheduler : str or distributed.Client, optional
        Address of a running Dask scheduler (``"tcp://SCHEDULER:8786"``) or a
        connected client. Default: a ``LocalCluster`` of ``n_workers`` worker
        processes with one thread each, closed at the end. Each worker's solver
        threads (PARDISO/MKL, the compiled kernels, CHOLMOD's BLAS) get
        ``cpu_count // n_workers`` threads (``CVXGEODESIC_THREADS`` and the
        libraries' own variables); on an existing cluster the workers' solvers
        follow their environment or the default policy (``docs/performance.md``).
    n_workers : int
        Workers of the local cluster (ignored with ``scheduler``).
    force : bool
        Recompute meshes whose outputs exist.
    progress : bool
        Show a progress bar and one line per failed mesh on stderr.
    output_format : {"ply", "npy", "vtu"} or None
        Format of the distance file; None (default): ``"ply"`` for a surface, ``"vtu"`` for a tetrahedral mesh
        (:data:`DEFAULT_FORMATS`). A mesh whose dimension the format cannot hold (``"ply"`` and tetrahedra) fails
        before its solve.

    Returns
    -------
    list of dict
        One row per mesh, in the order of ``paths``: ``mesh``, ``status``
        (``"ok"``, ``"skipped"`` (already done) or ``"failed"``), ``output``,
        ``n_vertices``, ``n_faces`` (tetrahedra in a volume), ``iterations``, ``solve_status``, ``time_s``
        (load + solve + write, on the worker), ``error`` (one line, or None),
        ``warnings`` (from loading the mesh), ``notes`` (every note and warning of the
        task, each once) and ``worker`` (host name). ``n_vertices`` is the file's count.

    Raises
    ------
    ParameterError
        Bad parameters, no paths, or two meshes with the same stem.
    ImportError
        Dask's ``distributed`` is not installed.
    """
    from .api import ALL_METHODS, SOLVERS
    from .capabilities import check
    from .formulations import ALIASES
    from .strategies import resolve_target

    paths = [Path(p).expanduser().resolve() for p in ([paths] if isinstance(paths, str | os.PathLike) else paths)]
    paths = list(dict.fromkeys(paths))
    if not paths:
        raise ParameterError("no mesh files given")
    sources_list = _source_spec(sources)
    if method is not None:  # None: each mesh gets the default of its dimension, chosen by GeodesicSolver
        method = check_choice(method, "method", ALL_METHODS)
    check_choice(solver, "solver", SOLVERS, lower=False)
    check_smoothness(m, None)  # its range too (validation.MAX_M): once, not once per mesh
    if method is not None and resolve_target(multires, 10**9) is not None:  # multires is for surfaces
        check(ALIASES.get(method, method), dim=2, multires=True)
    if output_format is not None:
        check_choice(output_format, "output_format", OUTPUT_FORMATS, lower=False)
    if scheduler is None:
        check_count(n_workers, "n_workers")
    stems: dict[str, Path] = {}
    for p in paths:
        if p.stem in stems:
            raise ParameterError(f"{stems[p.stem]} and {p} would write the same outputs ({p.stem}.*); "
                                 "rename one or run them into different --out folders")
        stems[p.stem] = p
    out = Path(out_dir).expanduser().resolve()
    _check_not_inputs(paths, out, output_format)
    check_output_dir(out, "--out")  # a folder that cannot take files fails now, not after the solves
    out.mkdir(parents=True, exist_ok=True)
    params = _params(sources_list, method, m, solver, multires, output_format)

    rows: dict[Path, dict] = {}
    todo: list[Path] = []
    for p in paths:
        done = None if force else _done_output(p, out, output_format, params)
        if done is not None:
            rows[p] = _row(p, "skipped", output=str(done))
        else:
            for fmt in _output_formats(p, output_format):
                for target in output_paths(p, out, fmt):  # a read-only output: refused now, not after its solve
                    check_replaceable(target, allow=None)
            todo.append(p)
    if todo:
        _run_on_cluster(todo, rows, sources_list, out, method, m, solver, multires, output_format,
                        scheduler, n_workers, progress)
    return [rows[p] for p in paths]


def _done_output(path: Path, out: Path, output_format: str | None, params: dict) -> Path | None:
    """The distance file of ``path`` when it is done with ``params`` (in one of the formats it may have), or
    None."""
    for fmt in _output_formats(path, output_format):
        dist_path, sidecar = output_paths(path, out, fmt)
        if _finished(dist_path, sidecar, {**params, "format": fmt}) is True:
            return dist_path
    return None


def _check_not_inputs(paths: list[Path], out: Path, output_format: str | None) -> None:
    """ParameterError when an output of the batch (``OUT/<stem>.<format>`` or ``.json``) is one of its inputs.

    ``batch 'in/*.ply' --out in`` would replace every mesh by its distance file. Distinct stems (checked
    before) leave the same path and a file system that ignores case (``A.PLY``) as the ways an output can
    be an input, so each output is compared with the inputs of the same stem, case folded.
    """
    by_stem: dict[str, list[Path]] = {}
    for p in paths:
        by_stem.setdefault(p.stem.casefold(), []).append(p)
    for p in paths:
        for fmt in _output_formats(p, output_format):
            for target in output_paths(p, out, fmt):
                check_not_an_input(target, by_stem[p.stem.casefold()], "--out")


def _printable(text: str) -> str:
    """``text`` with the undecodable bytes of file names (surrogate escapes, ``\\udcff``) as ``\\xff``.

    A file name that is not UTF-8 comes out of ``os.listdir`` with such escapes; printed to a UTF-8
    stream they raise UnicodeEncodeError.
    """
    try:
        return text.encode("utf-8", "surrogateescape").decode("utf-8", "backslashreplace")
    except UnicodeEncodeError:  # a surrogate that no file name gave
        return text.encode("utf-8", "backslashreplace").decode("utf-8")


def _run_on_cluster(todo, rows, sources, out, method, m, solver, multires, output_format,
                    scheduler, n_workers, progress) -> None:
    with ExitStack() as stack:
        client, cluster = open_client(stack, scheduler, n_workers)
        futures = {}
        for i, p in enumerate(todo):
            size = p.stat().st_size if p.exists() else 0
            fut = client.submit(solve_one, str(p), sources, str(out), method, m, solver, multires, output_format,
                                # a key goes through msgpack, strict UTF-8: a non-UTF-8 file name would break
                                # the message that submits every task of the batch, so its bytes are escaped
                                key=f"cvxgeodesic-batch-{i}-{_printable(p.stem)}-{os.getpid()}-{time.time_ns()}",
                                pure=False, priority=size)  # biggest meshes first: better load balance
            futures[fut] = p
        bar = _progress(len(futures)) if progress else None
        try:
            _collect(require_distributed()[1], futures, rows, bar)
        except KeyboardInterrupt:
            stop_after_interrupt(client, futures, cluster)
            raise
        finally:
            if bar is not None:
                bar.close()


class _LogLines:
    """A batch's progress where stderr is no terminal (a log file, a pipe, CI): a plain line per finished mesh.

    A tqdm bar redraws itself with carriage returns, which only a terminal turns back into one line: in a log,
    every redraw stays, and each note lands on the same line as the bar drawn before it.
    """

    def __init__(self, total: int) -> None:
        self.total, self.n = total, 0
        self.update(0)  # the tasks are submitted: the batch is under way

    def update(self, k: int = 1) -> None:
        self.n += k
        print(f"meshes: {self.n}/{self.total} done", file=sys.stderr, flush=True)

    def write(self, text: str, file=None) -> None:
        print(text, file=sys.stderr if file is None else file, flush=True)

    def close(self) -> None:
        pass


def _progress(total: int):
    """A tqdm bar on stderr in a terminal (notes go above it through ``bar.write``), else :class:`_LogLines`."""
    if not getattr(sys.stderr, "isatty", lambda: False)():
        return _LogLines(total)
    from tqdm import tqdm

    return tqdm(total=total, desc="meshes", unit="mesh", file=sys.stderr)


def _collect(distributed, futures: dict, rows: dict, bar) -> None:
    """Gather the rows of ``futures`` as they finish; progress bar and notes on stderr."""
    for fut in distributed.as_completed(list(futures)):
        p = futures[fut]
        try:
            row = fut.result()
        except Exception as exc:  # the task itself died (worker killed, out of memory, ...)
            row = _row(p, "failed", error=error_line(exc, typed=True))
        rows[p] = row
        if bar is not None:
            bar.update(1)
            for note in row.get("notes", []):
                bar.write(_printable(f"cvxgeodesic: note: {_with_name(p.name, note)}"), file=sys.stderr)
            if row["status"] == "failed":
                bar.write(_printable(f"FAILED {p}: {row['error']}"), file=sys.stderr)


def _with_name(name: str, note: str) -> str:
    """``note``'s first line, prefixed with the mesh's file name unless it already starts with it."""
    line = note.splitlines()[0] if note else ""
    return line if line.startswith(name) else f"{name}: {line}"


#: The columns of :func:`format_summary` (``name`` and ``note`` are made there), all left-aligned.
SUMMARY_COLUMNS = tuple(Column(h, k, *f, align="left") for h, k, *f in (
    ("mesh", "name"), ("status", "status"), ("vertices", "n_vertices"), ("faces", "n_faces"), ("iters", "iterations"),
    ("time_s", "time_s", lambda v: f"{v:.2f}"), ("output / error", "note")))


def format_summary(rows: list[dict]) -> str:
    """Plain-text table of :func:`run_batch` rows (:func:`cvxgeodesic.tables.text_table`), with a totals line."""
    body = []
    for r in rows:
        note = r["error"] if r["status"] == "failed" else (r["output"] or "")
        if r["status"] == "ok" and r.get("solve_status") not in (None, "optimal"):
            note = f"[{r['solve_status']}] {note}"
        body.append({**r, "name": _printable(Path(r["mesh"]).name), "note": _printable(note or "")})
    counts = {s: sum(r["status"] == s for r in rows) for s in ("ok", "skipped", "failed")}
    return (text_table(body, SUMMARY_COLUMNS, missing="") + f"\n{len(rows)} meshes: {counts['ok']} solved, "
            f"{counts['skipped']} skipped (already done), {counts['failed']} failed")
