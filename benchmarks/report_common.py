"""Shared machinery of ``benchmarks/report.py``: solving with fallback, caches, metrics, figures, environment.

Not a library module: it is imported by the report script only (``python benchmarks/report.py``
puts this folder on ``sys.path``).

Caches (under ``report_output/cache`` by default, ignored by git):

* ``fields/<key>.npz``: one distance field with its solve record (method, solver actually used,
  times, status, fallback note, warnings). A field is computed once and reused by every section
  that needs it (e.g. the exact bunny field of Table 2 is the reference of Fig. 5).
* ``sections/<name>.json``: the numbers of a finished section and the figures it wrote; a rerun
  skips the section when its JSON and its figures are there.
"""

from __future__ import annotations

import hashlib
import json
import os
import platform
import re
import subprocess
import sys
import time
import warnings
from dataclasses import dataclass, field
from datetime import UTC, datetime
from importlib import metadata
from pathlib import Path

import numpy as np

import cvxgeodesic as cg
from cvxgeodesic.api import BASELINE_METHODS
from cvxgeodesic.errors import NonManifoldError
from cvxgeodesic.problems.formulations import ALIASES, FORMULATIONS

REPO = Path(__file__).resolve().parents[1]
DEFAULT_SHARED = REPO.parent / "shared" / "meshes"
PANEL_DPI = 72  # surface pictures: 461 x 389 px per panel

#: Display names of the methods in tables and legends.
LABELS = {
    "qcqp-hessian": "QCQP-Hessian (ours)",
    "qclp": "QCLP",
    "lclp": "LCLP",
    "lcqp-hessian": "QGDF (= LCQP-Hessian)",
    "qgdf": "QGDF (= LCQP-Hessian)",
    "qcqp-laplacian": "QCQP-Laplacian",
    "qcqp-dirichlet": "QCQP-Dirichlet",
    "lcqp-laplacian": "LCQP-Laplacian",
    "lcqp-dirichlet": "LCQP-Dirichlet",
    "heat": "heat method",
    "fmm": "fast marching",
    "dijkstra": "Dijkstra",
    "exact": "exact (MMP)",
}
COLORS = {
    "qcqp-hessian": "tab:red", "qclp": "tab:orange", "lcqp-hessian": "tab:purple", "heat": "tab:blue",
    "fmm": "tab:green", "dijkstra": "tab:gray", "exact": "black", "lclp": "tab:brown",
    "qcqp-laplacian": "tab:cyan", "qcqp-dirichlet": "tab:olive",
}
MARKERS = {
    "qcqp-hessian": "o", "qclp": "s", "lcqp-hessian": "D", "heat": "^", "fmm": "v", "dijkstra": "x",
    "qcqp-laplacian": "P", "qcqp-dirichlet": "*",
}


def label(method: str) -> str:
    return LABELS.get(method, method)


def canonical(method: str) -> str:
    return ALIASES.get(method, method)


def log(msg: str) -> None:
    print(f"[{time.strftime('%H:%M:%S')}] {msg}", file=sys.stderr, flush=True)


# ----------------------------------------------------------------------------------------------------------------------
# context: paths, meshes, field cache
# ----------------------------------------------------------------------------------------------------------------------


@dataclass
class Context:
    shared: Path
    out: Path  # docs/
    cache: Path  # report_output/cache
    quick: bool = False
    meshes: dict = field(default_factory=dict)

    @property
    def figures(self) -> Path:
        return self.out / "figures"

    @property
    def panels(self) -> Path:
        return self.cache.parent / "panels"

    def setup(self) -> None:
        for p in (self.figures, self.cache / "fields", self.cache / "sections", self.panels):
            p.mkdir(parents=True, exist_ok=True)

    def mesh(self, name: str) -> cg.TriMesh:
        """A mesh of the shared folder by file name, loaded once per process."""
        if name not in self.meshes:
            path = self.shared / name
            if not path.exists():
                raise FileNotFoundError(f"mesh {path} not found")
            self.meshes[name] = cg.load_mesh(path)
        return self.meshes[name]

    def register(self, key: str, mesh: cg.TriMesh) -> cg.TriMesh:
        """Make a generated mesh (e.g. a decimated one) available under ``key``."""
        self.meshes[key] = mesh
        return mesh


def mesh_fingerprint(mesh) -> str:
    h = hashlib.sha1()
    h.update(np.ascontiguousarray(mesh.V, dtype=np.float64).tobytes())
    h.update(np.ascontiguousarray(mesh.F, dtype=np.int64).tobytes())
    return h.hexdigest()[:10]


def _json_default(o):
    if isinstance(o, np.integer):
        return int(o)
    if isinstance(o, np.floating):
        return float(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, Path):
        return str(o)
    return str(o)


def dump_json(path: Path, obj) -> None:
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text(json.dumps(obj, indent=1, default=_json_default, allow_nan=True))
    os.replace(tmp, path)


def _short(msg: str, n: int = 240) -> str:
    msg = " ".join(str(msg).split())
    return msg if len(msg) <= n else msg[: n - 1] + "…"


def _error_text(exc: BaseException) -> str:
    return _short(f"{type(exc).__name__}: {exc}")


def _attempt(mesh, method: str, source, m: float, solver: str, order: int = 1, normalization: str = "area"):
    """One solve with a fresh solver object; returns (result or None, wall seconds, exception, warnings)."""
    t0 = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            kwargs = {} if method in BASELINE_METHODS else {"solver": solver, "m": m}
            if order != 1:
                kwargs["order"] = order
            if normalization != "area":
                kwargs["normalization"] = normalization
            res = cg.GeodesicSolver(mesh, method, **kwargs).solve(source)
            err = None
        except Exception as exc:  # noqa: BLE001 - every failure becomes a status in the report
            res, err = None, exc
    wall = time.perf_counter() - t0
    msgs = []
    for w in caught:
        found = re.search(r"interior-point solver stopped with status '([^']+)'", str(w.message))
        if found:  # solver="auto" retried with Clarabel inside the library
            msgs.append(f"ipm-fallback:{found.group(1)}")
            continue
        text = _short(f"{w.category.__name__}: {str(w.message).split(' (')[0]}", 160)
        if text not in msgs and w.category.__name__ not in ("RuntimeWarning",):
            msgs.append(text)
    return res, wall, err, msgs


def _attempt_record(solver: str, wall: float, err) -> dict:
    if err is None:
        return {"solver": solver, "time_s": wall, "status": "ok", "error": None, "hint": None}
    msg = " ".join(str(err).split())
    hint = None
    if "; " in msg:  # the library appends its diagnosis after "on <mesh>; "
        hint = msg.split("; ", 1)[1].split(" (solver=")[0]
    return {"solver": solver, "time_s": wall, "status": str(getattr(err, "status", type(err).__name__)),
            "error": _short(f"{type(err).__name__}: {msg}", 400), "hint": hint}


def field_key(mesh_key: str, method: str, source: int, m: float, order: int, normalization: str,
              fingerprint: str) -> str:
    """The name of one cached field (``fields/<key>.npz``): mesh, method, order, m, source and mesh fingerprint.

    Order-1 keys are the ones used before order 2 existed, so the existing cache stays valid. Order-2 keys carry
    :data:`cvxgeodesic.problems.squared_distance.ORDER2_CACHE_VERSION` (``__o2v<version>``): a field computed by
    order-2 code whose results have changed since is recomputed, not reused.
    """
    from cvxgeodesic.problems.squared_distance import ORDER2_CACHE_VERSION

    method = canonical(method)
    is_formulation = method in FORMULATIONS
    mtag = f"{m:g}" if is_formulation and FORMULATIONS[method][1] is not None else "-"
    otag = "" if order == 1 else f"__o{order}" + (f"v{ORDER2_CACHE_VERSION}" if order == 2 else "")
    if normalization != "area" and is_formulation:
        otag += f"__n{normalization}"
    return f"{mesh_key}__{method}{otag}__m{mtag}__s{source}__{fingerprint}".replace("/", "+")


def solve(ctx: Context, mesh, mesh_key: str, method: str, source: int, m: float = 1.0, order: int = 1,
          normalization: str = "area") -> dict:
    """Solve ``method`` on ``mesh`` from ``source`` (cached), falling back from our IPM to Clarabel.

    ``order=2``: the library's second-order elements (``method="qclp"`` only); ``normalization`` other
    than the default ``"area"`` (formulations only): each cached under its own key.
    Returns a record: ``method, mesh, source, m, order, ok, solver, status, time_s`` (construction +
    solve, what one call costs), ``setup_s, solve_s, iterations, fallback`` (why Clarabel was used, or
    None), ``warnings``, ``notes`` (the library's ``info.notes``; absent in fields cached before it was
    recorded) and ``distance`` ((n,) ndarray, or None when every attempt failed).
    """
    method = canonical(method)
    is_formulation = method in FORMULATIONS
    mtag = f"{m:g}" if is_formulation and FORMULATIONS[method][1] is not None else "-"
    key = field_key(mesh_key, method, source, m, order, normalization, mesh_fingerprint(mesh))
    path = ctx.cache / "fields" / f"{key}.npz"
    if path.exists():
        with np.load(path, allow_pickle=False) as z:
            rec = json.loads(str(z["record"]))
            rec["distance"] = z["distance"] if rec["ok"] else None
        return rec

    rec = {"method": method, "mesh": mesh_key, "source": int(source), "m": m if mtag != "-" else None,
           "order": order, "normalization": normalization if is_formulation else None,
           "n_vertices": mesh.n_vertices, "n_faces": mesh.n_faces, "fallback": None, "attempts": []}
    res, wall, err, msgs = _attempt(mesh, method, source, m, "auto", order, normalization)
    internal = [w.split(":", 1)[1] for w in msgs if w.startswith("ipm-fallback:")]
    msgs = [w for w in msgs if not w.startswith("ipm-fallback:")]
    if res is not None and (internal or res.info.extra.get("ipm_failure")):
        # the library's solver="auto" retried a failed IPM solve with Clarabel itself; the time includes both
        status = str(res.info.extra.get("ipm_failure") or internal[0])
        rec["fallback"] = f"ipm {'stopped short' if status == 'almost_optimal' else 'failed'}: {status}"
        rec["attempts"] += [{"solver": "ipm", "time_s": None, "status": status, "error": None, "hint": None},
                            _attempt_record("clarabel", wall, None)]
    elif err is not None and internal and getattr(err, "solver", None) == "clarabel":
        rec["fallback"] = f"ipm failed: {internal[0]}"
        rec["attempts"] += [{"solver": "ipm", "time_s": None, "status": internal[0], "error": None, "hint": None},
                            _attempt_record("clarabel", wall, err)]
    else:
        rec["attempts"].append(_attempt_record("ipm" if is_formulation else method, wall, err))
    if err is not None and is_formulation and not isinstance(err, NonManifoldError) and not rec["fallback"]:
        rec["fallback"] = f"ipm failed: {_short(getattr(err, 'status', type(err).__name__), 60)}"
        log(f"    {method} on {mesh_key}: {_error_text(err)}; retrying with clarabel")
        res, wall2, err2, msgs2 = _attempt(mesh, method, source, m, "clarabel", order, normalization)
        rec["attempts"].append(_attempt_record("clarabel", wall2, err2))
        msgs = msgs + [w for w in msgs2 if w not in msgs]
        wall, err = wall2, err2
    rec["warnings"] = msgs
    if err is None:
        from cvxgeodesic.evaluation.summary import summarize_run

        run = summarize_run(res.info, time_s=wall)  # the library's solve record, with the wall-clock time
        rec.update(ok=True, **{k: run[k] for k in ("solver", "status", "time_s", "setup_s", "solve_s", "iterations",
                                                   "notes")},
                   error=None, resolved_nonnegative=bool(res.info.extra.get("resolved_nonnegative", False)))
        d = np.asarray(res.distance, dtype=np.float64)
    else:
        rec.update(ok=False, solver=getattr(err, "solver", None), status=_short(getattr(err, "status", "error"), 60),
                   time_s=float(wall), setup_s=None, solve_s=None, iterations=None, error=_error_text(err))
        d = np.zeros(0)
    rec["loadavg_1min"] = round(os.getloadavg()[0], 2)  # the load this time was measured under
    np.savez_compressed(path, distance=d, record=np.array(json.dumps(rec, default=_json_default)))
    rec["distance"] = d if rec["ok"] else None
    state = f"{rec['solver']} {rec['status']}" if rec["ok"] else f"FAILED {rec['error']}"
    log(f"    {method + (f' order {order}' if order != 1 else ''):<15} on {mesh_key}: {rec['time_s']:7.2f} s  {state}")
    return rec


def solver_text(rec: dict) -> str:
    """How a field was produced, for the tables: 'ipm', 'clarabel (ipm failed: …)', library name for baselines."""
    if rec["method"] in BASELINE_METHODS:
        return {"dijkstra": "scipy", "fmm": "potpourri3d", "heat": "potpourri3d", "exact": "pygeodesic"}.get(
            rec["method"], str(rec.get("solver")))
    s = str(rec.get("solver") or "-")
    if rec.get("fallback"):
        s = f"{s}; {rec['fallback']}" if rec["ok"] else "ipm and clarabel failed"
    return s


def status_text(rec: dict) -> str:
    if rec["ok"]:
        return rec["status"]
    err = rec.get("error") or ""
    if "NonManifoldError" in err:
        return "NonManifoldError"
    if rec.get("fallback"):
        return "failed (" + "; ".join(f"{a['solver']}: {a.get('status')}" for a in rec.get("attempts", [])) + ")"
    return "failed: " + _short(err, 80)


# ----------------------------------------------------------------------------------------------------------------------
# metrics
# ----------------------------------------------------------------------------------------------------------------------


def metrics(mesh, d, d_exact, source) -> dict:
    """Errors against the exact field plus ridge sharpness / off-ridge error (NaN-free JSON-able dict).

    The library's evaluation record (:func:`cvxgeodesic.evaluation.summary.summarize_field`, the one
    ``cvxgeodesic compare`` and the demo print) without the gradient statistics the report does not use.
    """
    from cvxgeodesic.evaluation.summary import summarize_field

    rec = summarize_field(mesh, d, d_exact, np.array([source]), gradient=False)
    return {k: v for k, v in rec.items() if v is not None}


def pct(x, digits: int = 2) -> str:
    if x is None or not np.isfinite(x):
        return "—" if x is None or np.isnan(x) else "∞"
    return f"{100 * x:.{digits}f} %"


def secs(x) -> str:
    if x is None or not np.isfinite(x):
        return "—"
    return f"{x:.3f}" if x < 0.1 else f"{x:.2f}" if x < 100 else f"{x:.0f}"


# ----------------------------------------------------------------------------------------------------------------------
# figures
# ----------------------------------------------------------------------------------------------------------------------


def tile(panels: list[Path], out_path: Path, ncols: int) -> Path:
    """Paste equally sized PNG panels into a grid and save it as a small 256-colour PNG."""
    from PIL import Image

    imgs = [Image.open(p).convert("RGB") for p in panels]
    w = max(i.width for i in imgs)
    h = max(i.height for i in imgs)
    nrows = (len(imgs) + ncols - 1) // ncols
    canvas = Image.new("RGB", (w * min(ncols, len(imgs)), h * nrows), "white")
    for k, im in enumerate(imgs):
        canvas.paste(im, ((k % ncols) * w, (k // ncols) * h))
    save_png(canvas, out_path)
    return out_path


def save_png(img, out_path: Path) -> None:
    """Quantize to 256 colours (the pictures are smooth colour ramps: no visible loss) and write optimized."""
    from PIL import Image

    q = img.quantize(colors=256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
    tmp = out_path.with_suffix(".tmp.png")
    q.save(tmp, optimize=True)
    os.replace(tmp, out_path)


def save_figure(fig, out_path: Path, dpi: int = 100) -> Path:
    """Save a matplotlib figure (line plots) through PIL quantization."""
    import io

    from PIL import Image

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    buf.seek(0)
    save_png(Image.open(buf).convert("RGB"), out_path)
    return out_path


def submesh(mesh, faces_mask: np.ndarray, name: str):
    """The faces selected by ``faces_mask`` as a mesh of their own; returns (mesh, old vertex ids)."""
    F = mesh.F[faces_mask]
    used = np.unique(F)
    remap = -np.ones(mesh.n_vertices, dtype=np.int64)
    remap[used] = np.arange(used.size)
    return cg.TriMesh(mesh.V[used], remap[F], name=name), used


# ----------------------------------------------------------------------------------------------------------------------
# environment
# ----------------------------------------------------------------------------------------------------------------------

PACKAGES = ("numpy", "scipy", "clarabel", "libigl", "potpourri3d", "pygeodesic", "scikit-sparse",
            "fast_simplification", "matplotlib", "pillow")


def environment(argv: list[str]) -> dict:
    cpu = platform.processor() or "?"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    mem = None
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemTotal"):
                mem = round(int(line.split()[1]) / 1024**2, 1)
    except OSError:
        pass
    versions = {"cvxgeodesic": cg.__version__, "python": platform.python_version()}
    for p in PACKAGES:
        try:
            versions[p] = metadata.version(p)
        except metadata.PackageNotFoundError:
            versions[p] = "not installed"
    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=REPO, capture_output=True, text=True,
                                timeout=10).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=REPO,
                               capture_output=True, text=True, timeout=10).stdout.strip()
        commit = commit + (" (with uncommitted changes)" if dirty else "")
    except (OSError, subprocess.SubprocessError):
        commit = "?"
    blas = "?"
    try:
        out = subprocess.run(["ldconfig", "-p"], capture_output=True, text=True, timeout=10).stdout
        blas = "OpenBLAS (pthread)" if "libopenblas" in out else "reference BLAS"
    except (OSError, subprocess.SubprocessError):
        pass
    return {
        "date": datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC"),
        "cpu": cpu, "cores": os.cpu_count(), "memory_gib": mem, "os": platform.platform(),
        "loadavg_at_start": [round(x, 2) for x in os.getloadavg()],
        "versions": versions, "commit": commit, "blas": blas,
        "command": " ".join(["python", *argv]),
    }


def emit_row(row: dict, out: str | os.PathLike | None) -> None:
    """Print one measured row as a JSON line and, given ``out``, append it there (a run stopped midway keeps
    its rows)."""
    line = json.dumps(row)
    print(line, flush=True)
    if out:
        with open(out, "a") as fh:
            fh.write(line + "\n")


def timed(fn, repeats: int):
    """The result of ``fn()`` and its best time over ``repeats`` runs."""
    best, out = np.inf, None
    for _ in range(repeats):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return out, best
