"""Input checks shared by every entry point, with one error vocabulary.

Every function here returns the normalized value or raises an error from :mod:`cvxgeodesic.errors`
whose message names the parameter and the offending value or index:

- :class:`~cvxgeodesic.errors.ParameterError` for options and per-vertex arrays
  (numbers, counts, choices, fields, masks, index arrays, output paths);
- :class:`~cvxgeodesic.errors.SourceError` for source vertices (:func:`validate_sources`).

A leaf module (NumPy and the other leaf modules: :mod:`cvxgeodesic.errors`, the result types of
:mod:`cvxgeodesic.results`, ...), so that the mesh code, the problem
builders, the API and the applications can all use it without importing each other.
"""

from __future__ import annotations

import numbers
import os
import re
from collections.abc import Iterable
from contextlib import suppress
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from . import capabilities
from ._atomic import probe_folder
from .errors import MeshError, ParameterError, SourceError
from .results import Field, GeodesicResult

__all__ = [
    "MAX_COORDINATE", "MAX_COST", "MAX_COST_RATIO", "MAX_M", "MAX_METRIC_CONDITION", "MIN_COST", "MIN_EXTENT",
    "as_field",
    "as_points", "as_vertex_field", "check_choice", "check_coordinates", "check_cost", "check_count", "check_lam",
    "check_metric", "check_not_an_input", "check_number", "check_output_path",
    "check_plane_metric", "check_real", "check_type", "is_integer", "is_real", "short_repr", "validate_sources",
    "vertex_indices", "vertex_mask",
]

#: Largest accepted coordinate magnitude of a mesh, and :data:`MIN_EXTENT` the smallest nonzero size (largest side
#: of its bounding box). Inside [1e-40, 1e40] every length, area and volume of a mesh, their squares (``np.linalg.norm``
#: of a cross product squares an area) and cubes stay normal floating-point numbers, also for edges 1e-10 of the
#: mesh's size: measured before this bound, areas overflowed from coordinates of about 1e77 (λ became inf) and the
#: libraries' absolute tolerances broke pygeodesic below 1e-12. Every method is solved on the mesh divided by a power
#: of two (exact), so inside the range a mesh scaled by ``s`` gives ``s`` times the distances.
MAX_COORDINATE = 1e40
MIN_EXTENT = 1e-40


def is_real(value: Any) -> bool:
    """True for Python and NumPy real numbers other than booleans."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool | np.bool_)


def is_integer(value: Any) -> bool:
    """True for Python and NumPy integers other than booleans."""
    return isinstance(value, int | np.integer) and not isinstance(value, bool | np.bool_)


def short_repr(value: Any, limit: int = 60) -> str:
    """``repr(value)``, cut to ``limit`` characters for error messages."""
    r = repr(value)
    return r if len(r) <= limit else r[: limit - 3] + "..."


def check_type(value: Any, name: str, kinds: type | tuple[type, ...], what: str) -> Any:
    """``value`` unchanged if it is an instance of ``kinds``; else a TypeError naming ``name`` and ``what``."""
    if not isinstance(value, kinds):
        raise TypeError(f"{name} must be {what}, got {type(value).__name__}")
    return value


def check_number(value: Any, name: str, *, low: float | None = None, high: float | None = None,
                 low_open: bool = False, high_open: bool = False) -> float:
    """``value`` as a float, or a ParameterError naming ``name``.

    Parameters
    ----------
    value : object
        A Python or NumPy real number (not a bool).
    name : str
        Parameter name used in the message.
    low, high : float, optional
        Bounds; ``low_open`` / ``high_open`` exclude them. With both bounds the message reads
        ``"<name> must be a number in [low, high]"``, else ``"<name> must be a finite number >= low"``
        (NaN and ±inf are always rejected).

    Returns
    -------
    float
        ``value`` converted.

    Raises
    ------
    ParameterError
        Not a real number, not finite, or outside the bounds.
    """
    if low is not None and high is not None:
        what = f"a number in {'(' if low_open else '['}{low:g}, {high:g}{')' if high_open else ']'}"
    elif low is not None:
        what = f"a finite number {'>' if low_open else '>='} {low:g}"
    elif high is not None:
        what = f"a finite number {'<' if high_open else '<='} {high:g}"
    else:
        what = "a finite number"
    ok = is_real(value) and bool(np.isfinite(value))
    if ok and low is not None:
        ok = value > low if low_open else value >= low
    if ok and high is not None:
        ok = value < high if high_open else value <= high
    if not ok:
        raise ParameterError(f"{name} must be {what}, got {value!r}")
    return float(value)


def check_count(value: Any, name: str, *, minimum: int = 1, or_none: bool = False) -> int:
    """``value`` as an int ``>= minimum``, else a ParameterError naming ``name``.

    ``or_none`` only adds "or None" to the message, for parameters whose caller handles None itself.
    """
    if not is_integer(value) or value < minimum:
        what = "a positive integer" if minimum == 1 else f"an integer >= {minimum}"
        raise ParameterError(f"{name} must be {what}{' or None' if or_none else ''}, got {value!r}")
    return int(value)


def check_choice(value: Any, name: str, choices: Iterable[str], *, lower: bool = True) -> str:
    """``value`` (lower-cased when ``lower``) if it is one of ``choices``, else a ParameterError.

    The message is ``"unknown <name> <value!r>; choose one of a, b, c"``.
    """
    choices = tuple(choices)
    key = value.lower() if isinstance(value, str) and lower else value
    if not isinstance(value, str) or key not in choices:
        raise ParameterError(f"unknown {name} {value!r}; choose one of {', '.join(choices)}")
    return key


def check_order(order: Any) -> int:
    """The element order: one of :data:`cvxgeodesic.capabilities.ORDERS` (the orders of the declared elements,
    :data:`cvxgeodesic.operators.lagrange.ELEMENTS`); ParameterError otherwise."""
    if not is_integer(order) or int(order) not in capabilities.ORDERS:
        *rest, last = [f"{o} (P{o})" for o in capabilities.ORDERS]
        raise ParameterError(f"order must be {', '.join(rest)} or {last}, got {short_repr(order)}")
    return int(order)


#: Largest accepted smoothness multiplier ``m`` (and ``lam`` up to the weight of this ``m``). Measured 2026-12-03 on
#: icosphere(2) and a jittered 8×8 grid, every order-1 and order-2 formulation: at m = 1e4 the smoothing already
#: flattens a sphere's field to a fifth, at 1e6 to 1 %; the structured solver solved every case up to 1e8, the
#: curved Hessian energy needed Clarabel from 1e10 and failed from 1e12 (reported as an indefinite energy).
MAX_M = 1e6


def check_smoothness(m: Any, lam: Any) -> tuple[float, float | None]:
    """``(m, lam)`` checked: ``m`` a number in ``[0, MAX_M]`` (always, even when ``lam`` is given or the method has no
    smoothness term, so that every order and method gives the same verdict), ``lam`` None or a finite number ≥ 0
    (its upper bound needs the mesh: :func:`check_lam`)."""
    m_value = check_number(m, "m", low=0)
    if m_value > MAX_M:
        d = _apart(m_value, MAX_M)
        raise ParameterError(f"m = {_g(m_value, d)} is outside the supported range [0, {_g(MAX_M, d)}]: beyond it the "
                             "smoothing outweighs the distance a million times and the solvers fail")
    lam_value = None if lam is None else check_number(lam, "lam", low=0)
    return m_value, lam_value


def check_lam(lam: float, unit: float) -> float:
    """``lam`` unless it exceeds the weight of ``m = MAX_M``; a ParameterError naming both otherwise.

    Parameters
    ----------
    lam : float
        A finite λ ≥ 0 (:func:`check_smoothness`).
    unit : float
        The weight of ``m = 1`` on this mesh (``smoothness_weight(mesh, 1.0, ...)``).
    """
    if unit > 0 and lam > MAX_M * unit:
        d = _apart(lam, MAX_M * unit)
        raise ParameterError(f"lam = {_g(lam, d)} is outside the supported range [0, {_g(MAX_M * unit, d)}] on this "
                             f"mesh (the weight of m = {_g(MAX_M)}; m = 1 is lam = {_g(unit)}): beyond it the "
                             "smoothing outweighs the distance a million times and the solvers fail")
    return lam


def as_vertex_field(values: ArrayLike, name: str, n: int | None = None, *, nan_ok: bool = True) -> np.ndarray:
    """Return ``values`` as a (n,) float64 array, or raise a ParameterError naming ``name``.

    Parameters
    ----------
    values : array_like
        One number per vertex.
    name : str
        Parameter name used in the message.
    n : int, optional
        Required length (the mesh's vertex count).
    nan_ok : bool
        Accept NaN values (``inf`` is always accepted: it marks unreachable vertices).

    Returns
    -------
    (n,) float64 ndarray

    Raises
    ------
    ParameterError
        Not numeric, not 1-D, not of length ``n``, or NaN where ``nan_ok`` is False (the message names the
        first NaN vertex).
    """
    shape = f"({n},)" if n is not None else "(n,)"
    try:
        arr = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ParameterError(f"{name} must be a numeric array of shape {shape} ({exc})") from None
    if arr.ndim != 1 or (n is not None and arr.shape[0] != n):
        raise ParameterError(f"{name} must have shape {shape} (one value per mesh vertex), got shape {arr.shape}")
    if not nan_ok and np.isnan(arr).any():
        raise ParameterError(f"{name} has NaN values (first at vertex {int(np.flatnonzero(np.isnan(arr))[0])})")
    return arr


def as_field(values: ArrayLike | GeodesicResult | Field, name: str, n: int, *,
             nan_ok: bool = True) -> tuple[np.ndarray, Field | None]:
    """The vertex values of a field given as an array, a :class:`~cvxgeodesic.results.GeodesicResult` or a
    :class:`~cvxgeodesic.results.Field`, and that field: what the outputs (pictures, files, paths) take.

    Parameters
    ----------
    values : (n,) array_like of float, GeodesicResult or Field
        One number per vertex, or a result (its :attr:`~cvxgeodesic.results.GeodesicResult.field`), or a field.
    name : str
        Parameter name used in the message.
    n : int
        The mesh's vertex count.
    nan_ok : bool
        Accept NaN values (as :func:`as_vertex_field`).

    Returns
    -------
    values : (n,) float64 ndarray
        The field at the vertices: a result's ``distance``, a field's ``vertex_distance``.
    field : Field or None
        The field, to be asked inside cells; None for an array (its piecewise-linear interpolant is meant).

    Raises
    ------
    ParameterError
        A field of a mesh with another vertex count (the message names both), or values as
        :func:`as_vertex_field` refuses them.
    """
    if isinstance(values, GeodesicResult):  # its distance: the field's vertex values, 0 at the source vertices
        field, vertex_values = values.field, values.distance
    elif isinstance(values, Field):
        field, vertex_values = values, values.vertex_distance
    else:
        return as_vertex_field(values, name, n, nan_ok=nan_ok), None
    m = field.mesh.n_vertices
    if m != n:
        raise ParameterError(f"{name} is a field on a mesh of {m} vertices, not on this mesh of {n} vertices")
    return as_vertex_field(vertex_values, name, n, nan_ok=nan_ok), field


def as_points(x: ArrayLike, name: str, *, error: type[Exception] = ParameterError,
              row: str | None = None) -> np.ndarray:
    """Return ``x`` as a (3,) or (k, 3) float64 array of finite positions, or raise ``error`` naming ``name``.

    Parameters
    ----------
    x : array_like
        One position (3,) or k positions (k, 3).
    name : str
        Parameter name used in the message.
    error : type
        :class:`~cvxgeodesic.errors.ParameterError` (default) or :class:`~cvxgeodesic.errors.SourceError`
        (positions that define sources); :class:`~cvxgeodesic.errors.MeshError` for a point cloud's points.
    row : str, optional
        What one row is, for rows of a data set (``"point"``, ``"normal"`` of a point cloud named ``name``): then
        ``x`` must be (k, 3) and the messages read ``"<name>: <row> <i> has a non-finite coordinate ..."``.

    Returns
    -------
    (3,) or (k, 3) float64 ndarray

    Raises
    ------
    error
        Not numeric, of another shape, or with a NaN or infinite coordinate (the message names the
        first such row).
    """
    if row is not None:
        return _as_rows(x, name, error, row)
    try:
        X = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise error(f"{name} must be a (3,) or (k, 3) array of positions, got {short_repr(x)}") from None
    if X.shape[-1:] != (3,) or X.ndim > 2:
        raise error(f"{name} must be a (3,) or (k, 3) array of finite positions, got shape {X.shape}")
    bad = ~np.isfinite(X.reshape(-1, 3)).all(axis=1)
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        where = name if X.ndim == 1 else f"{name}[{k}]"
        raise error(f"{name} must be a (3,) or (k, 3) array of finite positions: {where} = "
                    f"{X.reshape(-1, 3)[k].tolist()}")
    return X


def _as_rows(x: ArrayLike, name: str, error: type[Exception], row: str) -> np.ndarray:
    """:func:`as_points` for the (k, 3) rows of a data set: the messages name the data set and the row."""
    try:
        X = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise error(f"{name}: {row}s must be an (n, 3) array of numbers ({exc})") from None
    if X.ndim != 2 or X.shape[1] != 3:
        raise error(f"{name}: {row}s must be an (n, 3) array, got shape {X.shape}")
    bad = np.flatnonzero(~np.isfinite(X).all(axis=1))
    if bad.size:
        raise error(f"{name}: {row} {int(bad[0])} has a non-finite coordinate ({X[bad[0]].tolist()}); "
                    f"{bad.size} such {row}s in all")
    return X


def vertex_indices(x: ArrayLike, name: str, n: int) -> np.ndarray:
    """Return ``x`` (an int or a 1-D sequence) as a (k,) int64 array of indices in ``[0, n)``.

    Floats with integral values are accepted; repeated indices are allowed (see
    :func:`validate_sources` for the strict rules of source vertices).

    Raises
    ------
    ParameterError
        Not 1-D, not integers, or an index outside ``[0, n)`` (the message gives the first one).
    """
    try:
        arr = np.asarray(x)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be an int or a 1-D array of vertex indices, got {short_repr(x)}") from None
    if arr.ndim == 0:
        arr = arr.reshape(1)
    if arr.ndim != 1:
        raise ParameterError(f"{name} must be an int or a 1-D array of vertex indices, got shape {arr.shape}")
    if arr.size and arr.dtype.kind not in "iu":  # bool is kind "b": rejected
        if arr.dtype.kind == "f" and np.all(np.isfinite(arr)) and np.all(arr == np.round(arr)):
            arr = arr.astype(np.int64)
        else:
            raise ParameterError(f"{name} must hold integer vertex indices, got dtype {arr.dtype}")
    arr = arr.astype(np.int64)
    bad = (arr < 0) | (arr >= n)
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        raise ParameterError(f"{name}[{k}] = {int(arr[k])} is outside [0, {n}): the mesh has {n} vertices")
    return arr


def vertex_mask(x: ArrayLike, name: str, n: int) -> np.ndarray:
    """Return ``x`` as a (n,) bool array or raise a ParameterError naming ``name``."""
    arr = np.asarray(x)
    if arr.dtype != bool:
        raise ParameterError(f"{name} must be a boolean vertex mask of shape ({n},), got dtype {arr.dtype}")
    if arr.shape != (n,):
        raise ParameterError(f"{name} must have shape ({n},), got {arr.shape}")
    return arr


def validate_sources(sources: Any, n: int, *, name: str = "sources", repeats: bool = False) -> np.ndarray:
    """Check and normalize source vertex indices.

    Parameters
    ----------
    sources : int or sequence of int
        Python or NumPy integers; floats with an integral value are accepted, booleans
        (including NumPy bool arrays) are not.
    n : int
        Number of vertices.
    name : str
        The parameter's name in the messages about its type, shape and emptiness (``distance_matrix``:
        ``"vertices"``).
    repeats : bool
        Accept an index given more than once (``distance_matrix`` solves it once).

    Returns
    -------
    (k,) int64 ndarray
        The indices, in the given order.

    Raises
    ------
    SourceError
        Empty, ragged, nested, non-integer (bool, float with a fraction, NaN, string,
        ``None``), negative, out-of-range or (unless ``repeats``) duplicated indices.
    """
    if isinstance(sources, bool | np.bool_):
        raise SourceError(f"{name} must be vertex indices, got {sources!r}")
    try:
        arr = np.atleast_1d(np.asarray(sources))
    except (ValueError, TypeError, OverflowError):  # ragged nesting and the like
        raise SourceError(f"{name} must be an int or a 1-D sequence of ints, got {short_repr(sources)}") from None
    if arr.ndim != 1:
        raise SourceError(f"{name} must be an int or a 1-D sequence of ints, got shape {arr.shape}")
    if arr.size == 0:
        raise SourceError(f"{name} is empty: give at least one source vertex")
    out_of_range = f"is out of range: the mesh has {n} vertices (0..{n - 1})"
    if arr.dtype == object and all(isinstance(v, int) and not isinstance(v, bool) for v in arr):
        # Python ints too large for int64
        big = next(v for v in arr if not -(2**63) <= v < 2**63)
        raise SourceError(f"source index {big} " + out_of_range)
    if arr.dtype.kind == "f" and np.all(np.isfinite(arr)) and np.all(arr == np.round(arr)):
        big = np.abs(arr) >= 2.0**62
        if big.any():
            raise SourceError(f"source index {arr[big][0]:g} " + out_of_range)
        arr = arr.astype(np.int64)
    if arr.dtype.kind not in "iu":
        raise SourceError(f"{name} must be integer vertex indices, got {short_repr(sources)}")
    if arr.dtype.kind == "u" and arr.max() >= 2**63:
        raise SourceError(f"source index {int(arr.max())} " + out_of_range)
    arr = arr.astype(np.int64)
    bad = (arr < 0) | (arr >= n)
    if bad.any():
        raise SourceError(f"source index {int(arr[bad][0])} " + out_of_range)
    uniq, counts = np.unique(arr, return_counts=True)
    if not repeats and (counts > 1).any():
        raise SourceError(f"source vertex {int(uniq[counts > 1][0])} is given more than once")
    return arr


def check_coordinates(V: np.ndarray, name: str) -> None:
    """Raise a :class:`~cvxgeodesic.errors.MeshError` unless finite vertex positions lie in the supported range.

    Parameters
    ----------
    V : (n, 3) float ndarray
        Finite coordinates.
    name : str
        The mesh's name, for the message.

    Raises
    ------
    MeshError
        A coordinate beyond ``±MAX_COORDINATE`` (the message names the first such vertex), or a mesh whose
        largest bounding-box side is positive but below ``MIN_EXTENT`` (a mesh whose vertices all coincide is
        accepted: it has no size to lose).
    """
    supported = (f"supported: |coordinates| <= {MAX_COORDINATE:g} and a mesh size (largest bounding-box side) "
                 f">= {MIN_EXTENT:g}; rescale the mesh")
    big = np.abs(V).max(axis=1) > MAX_COORDINATE
    if big.any():
        i = int(np.flatnonzero(big)[0])
        raise MeshError(f"{name}: vertex {i} has a coordinate beyond ±{MAX_COORDINATE:g} {V[i].tolist()}; squared "
                        f"lengths and areas would overflow ({supported})")
    extent = float((V.max(axis=0) - V.min(axis=0)).max()) if V.size else 0.0
    if 0.0 < extent < MIN_EXTENT:
        raise MeshError(f"{name}: the mesh is only {extent:.3g} across (largest bounding-box side); areas would "
                        f"underflow ({supported})")


def check_not_an_input(path: str | os.PathLike, inputs, what: str = "output") -> None:
    """Refuse an output path that names one of the input files (the same file, also through links).

    Writing a result over the mesh it was computed from destroys the input; the atomic rename that
    protects outputs would do it silently.

    Parameters
    ----------
    path : str or os.PathLike
        The output about to be written.
    inputs : iterable of str or os.PathLike
        The files the run reads.
    what : str
        The output's name in the message (``"-o"``, ``"--out"``).

    Raises
    ------
    ParameterError
        ``path`` and an input are the same file (same device and inode, or the same resolved path).
    """
    out = Path(os.fspath(path))
    for source in inputs:
        src = Path(os.fspath(source))
        same = out.resolve() == src.resolve()
        if not same and out.exists() and src.exists():
            with suppress(OSError):  # unreadable: not known to be the same file
                same = os.path.samefile(out, src)
        if same:
            raise ParameterError(f"{what} {out} is the input file {src}: refusing to overwrite an input; "
                                 "choose another output path")


def check_output_path(path: str | os.PathLike, extensions: tuple[str, ...]) -> Path:
    """Check that ``path`` can be written before expensive work produces its content.

    Parameters
    ----------
    path : str or os.PathLike
    extensions : tuple of str
        Accepted lower-case suffixes.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    TypeError
        ``path`` is not a str or os.PathLike.
    ParameterError
        Unsupported extension, missing parent directory, ``path`` is a directory, or
        no file can be created in the directory (permissions, read-only file system:
        checked by creating and removing an empty temporary file there).
    """
    try:
        p = Path(os.fspath(path))
    except TypeError:
        raise TypeError(f"path must be a str or os.PathLike, got {type(path).__name__}") from None
    if p.suffix.lower() not in extensions:
        raise ParameterError(f"{p}: unsupported output file extension {p.suffix!r}; supported: {', '.join(extensions)}")
    if not p.parent.is_dir():
        raise ParameterError(f"cannot write {p}: directory {p.parent} does not exist")
    if p.is_dir():
        raise ParameterError(f"cannot write {p}: it is a directory")
    try:  # the output is written to a temporary file in this directory: try exactly that
        probe_folder(p.parent, prefix=f".{p.name}.")
    except OSError as exc:
        raise ParameterError(
            f"cannot write {p}: cannot create files in directory {p.parent} ({exc.strerror or exc})"
        ) from None
    return p


# ---------------------------------------------------------------------------------------------------------------
# travel cost and metric (cvxgeodesic.operators.metric)
# ---------------------------------------------------------------------------------------------------------------
def _where(kind: str, k: int) -> str:
    return {"vertices": f"vertex {k}", "faces": f"face {k}"}.get(kind, "the constant")


#: Supported travel costs (and length factors ``√λ`` of a metric's eigenvalues ``λ`` in a face's plane): a constant
#: cost ``c`` only rescales the distance, so any range would do, but inside this one the medium's lengths, areas and
#: their products (``c⁴ det M``) stay normal floats with coordinates up to :data:`MAX_COORDINATE`. Measured before
#: the bound: ``cost=1e100`` was reported as an unbounded problem, ``1e-300`` as a surface of zero area.
MIN_COST, MAX_COST = 1e-30, 1e30
#: Largest accepted ratio of the largest to the smallest cost. Measured 2026-12-03 on a jittered 10×10 grid with
#: two costs (per face, 1 and r): up to r = 1e6 the structured solver solved qclp (orders 1 and 2) and qcqp-hessian;
#: from 1e8 order 2 and the Hessian fell back to Clarabel, at 1e12 Clarabel failed and at 1e16 every solver did.
MAX_COST_RATIO = 1e6
#: Largest accepted condition number of a metric in a face's plane (lengths differing by up to ``√1e8 = 1e4``
#: between directions). Measured 2026-12-03 with ``diag(κ, 1, 1)`` on a jittered 10×10 grid and on icosphere(2):
#: the structured solver solved qclp (orders 1 and 2) and qcqp-hessian up to κ = 1e8; from 1e10 order 2 failed
#: (reported as an unbounded problem); from about 1e12 the old check called the tensor "not positive definite".
MAX_METRIC_CONDITION = 1e8


def check_real(value: Any, name: str) -> None:
    """A ParameterError naming ``name`` when ``value`` holds complex numbers (a conversion to float would drop their
    imaginary part silently) or, for a NumPy array, anything but real numbers (strings, records)."""
    if isinstance(value, np.ndarray) and value.dtype.kind in "USVMm":  # strings, records, dates (object: scanned)
        raise ParameterError(f"{name} must hold real numbers, got an array of dtype {value.dtype}")
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError):
        return  # the caller's conversion reports it
    if arr.dtype.kind == "c" or (arr.dtype == object and any(isinstance(v, complex) for v in arr.ravel())):
        raise ParameterError(f"{name} must hold real numbers, got complex values (dtype {arr.dtype}): pass the real "
                             "part explicitly if that is what you mean")


def _g(x: float, digits: int = 6) -> str:
    """``x`` for messages: ``1e6``, ``1e-30``, ``2.5`` (not ``1e+06``), to ``digits`` significant digits."""
    return re.sub(r"e([+-])0*(\d)", lambda mt: "e" + ("-" if mt.group(1) == "-" else "") + mt.group(2),
                  f"{x:.{digits}g}")


def _apart(x: float, *bounds: float, digits: int = 6) -> int:
    """The fewest significant digits, at least ``digits`` and at most 17 (exact), at which :func:`_g` writes ``x``
    and each bound it differs from as different numbers: ``m = 1000000.1 is outside [0, 1e6]``, not
    ``m = 1e6 is outside [0, 1e6]``."""
    for d in range(digits, 17):
        if all(float(_g(x, d)) != float(_g(b, d)) for b in bounds if b != x):
            return d
    return 17


def _per_item(value: Any, name: str, n: int, m: int, item: tuple[int, ...], *, what: str,
              shapes: str) -> tuple[np.ndarray, str]:
    """``value`` (a cost or a metric) as a float64 array of ``item``-shaped entries, and whose they are.

    Returns ``(values, kind)``: one entry (1, *item) ``"constant"``, one per vertex (n, *item) ``"vertices"`` or one
    per face (m, *item) ``"faces"`` (per vertex when ``n == m``). The ParameterErrors name ``name`` and say it must
    be ``what`` (not numeric) or have one of the ``shapes``; complex values are refused by :func:`check_real`.
    """
    check_real(value, name)
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be {what}, got {short_repr(value)}") from None
    if arr.shape == item:
        return arr.reshape(1, *item), "constant"
    for kind, count in (("vertices", n), ("faces", m)):
        if arr.shape == (count, *item):
            return arr, kind
    raise ParameterError(f"{name} must have shape {shapes}, got shape {arr.shape}")


def check_cost(cost: Any, n: int, m: int) -> tuple[np.ndarray, str]:
    """A travel cost (time per unit length, ``1/speed``) checked and classified.

    Parameters
    ----------
    cost : float or (n,) or (m,) float array_like
        One positive number, one per vertex or one per face. When ``n == m`` a 1-D array is read per vertex.
    n, m : int
        The mesh's vertex and face counts.

    Returns
    -------
    values : (1,), (n,) or (m,) float64 ndarray
    kind : {"constant", "vertices", "faces"}

    Raises
    ------
    ParameterError
        Complex or not numeric, another shape, a value that is not positive and finite or outside
        ``[MIN_COST, MAX_COST]`` (the message names the first one), or values whose ratio max/min exceeds
        ``MAX_COST_RATIO`` (the message names both).
    """
    arr, kind = _per_item(cost, "cost", n, m, (), what=f"a positive number or an array of shape ({n},) (per vertex) "
                          f"or ({m},) (per face)", shapes=f"({n},) (one value per vertex) or ({m},) (one per face)")
    bad = ~(np.isfinite(arr) & (arr > 0))
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        at = "" if kind == "constant" else f"[{k}]"
        raise ParameterError(f"cost{at} = {float(arr[k])!r} ({_where(kind, k)}) must be positive and finite")
    _check_cost_range(arr, kind)
    return arr, kind


def _check_cost_range(arr: np.ndarray, kind: str) -> None:
    """A ParameterError unless positive costs lie in ``[MIN_COST, MAX_COST]`` with a ratio up to ``MAX_COST_RATIO``."""
    at = (lambda k: "cost") if kind == "constant" else (lambda k: f"cost[{k}] ({_where(kind, k)})")
    out = (arr < MIN_COST) | (arr > MAX_COST)
    if out.any():
        k = int(np.flatnonzero(out)[0])
        d = _apart(arr[k], MIN_COST, MAX_COST)
        raise ParameterError(f"{at(k)} = {_g(arr[k], d)} is outside the supported range [{_g(MIN_COST)}, "
                             f"{_g(MAX_COST)}]; a constant factor only scales the distances: divide it out and "
                             "multiply the result by it")
    lo, hi = int(np.argmin(arr)), int(np.argmax(arr))
    if arr[hi] > MAX_COST_RATIO * arr[lo]:
        d = _apart(arr[hi] / arr[lo], MAX_COST_RATIO)
        raise ParameterError(f"cost varies by a factor {_g(arr[hi] / arr[lo], d)} ({at(hi)} = {_g(arr[hi], d)}, "
                             f"{at(lo)} = {_g(arr[lo], d)}); the supported ratio of the largest to the smallest cost "
                             f"is at most {_g(MAX_COST_RATIO)} (beyond, the solvers fail)")


def check_metric(metric: Any, n: int, m: int) -> tuple[np.ndarray, str]:
    """A Riemannian metric (symmetric 3×3 tensors) checked for shape, finiteness and symmetry, and classified.

    Positive definiteness in each face's plane needs the mesh: :func:`check_plane_metric`.

    Parameters
    ----------
    metric : (3, 3), (n, 3, 3) or (m, 3, 3) float array_like
        One tensor, one per vertex or one per face (per vertex when ``n == m``).
    n, m : int

    Returns
    -------
    values : (1, 3, 3), (n, 3, 3) or (m, 3, 3) float64 ndarray
    kind : {"constant", "vertices", "faces"}

    Raises
    ------
    ParameterError
        Complex or not numeric, another shape, a non-finite entry or a tensor that is not symmetric (relative 1e-10),
        naming the first.
    """
    arr, kind = _per_item(metric, "metric", n, m, (3, 3),
                          what=f"a (3, 3), ({n}, 3, 3) or ({m}, 3, 3) array of symmetric tensors",
                          shapes=f"(3, 3) (one tensor), ({n}, 3, 3) (per vertex) or ({m}, 3, 3) (per face)")
    at = (lambda k: "metric") if kind == "constant" else (lambda k: f"metric[{k}]")
    finite = np.isfinite(arr).all(axis=(1, 2))
    if not finite.all():
        k = int(np.flatnonzero(~finite)[0])
        raise ParameterError(f"{at(k)} ({_where(kind, k)}) has a non-finite entry: {arr[k].tolist()}")
    scale = np.abs(arr).max(axis=(1, 2))
    asym = np.abs(arr - arr.transpose(0, 2, 1)).max(axis=(1, 2)) > 1e-10 * scale
    if asym.any():
        k = int(np.flatnonzero(asym)[0])
        raise ParameterError(f"{at(k)} ({_where(kind, k)}) is not symmetric: {arr[k].tolist()}")
    return 0.5 * (arr + arr.transpose(0, 2, 1)), kind


def check_plane_metric(M2: np.ndarray, owner: np.ndarray, face: np.ndarray, kind: str) -> None:
    """Raise a ParameterError unless every metric restricted to a face's plane is positive definite, with a condition
    number up to ``MAX_METRIC_CONDITION`` and length factors ``√λ`` in ``[MIN_COST, MAX_COST]``.

    Parameters
    ----------
    M2 : (k, 2, 2) float ndarray
        Restricted tensors ``E_tᵀ M E_t`` (NaN rows, of faces without a plane, are skipped).
    owner : (k,) int ndarray
        Index of the tensor each row comes from (in the user's array).
    face : (k,) int ndarray
        The face whose plane each row is restricted to.
    kind : {"constant", "vertices", "faces"}

    Raises
    ------
    ParameterError
        Three messages: not positive definite (an eigenvalue ≤ 0), too anisotropic (the condition number) and out
        of range (the eigenvalues); each names the tensor, the face and the eigenvalues there.
    """
    ok = np.isfinite(M2).all(axis=(1, 2))
    ev = np.full((len(M2), 2), 1.0)
    if ok.any():
        ev[ok] = np.linalg.eigvalsh(M2[ok])
    low, high = ev[:, 0], ev[:, 1]
    limits = (f"supported: eigenvalues in [{_g(MIN_COST**2)}, {_g(MAX_COST**2)}] with a ratio up to "
              f"{_g(MAX_METRIC_CONDITION)} (lengths differing by a factor up to {_g(MAX_METRIC_CONDITION**0.5)} "
              "between directions); beyond, the solvers fail")
    with np.errstate(invalid="ignore", divide="ignore"):
        condition = high / low
    for bad, what, why in (
        (low <= 0, "is not positive definite", "lengths along the surface need a positive definite metric"),
        # (1 + 1e-6): the smaller eigenvalue carries an error of about 1e-16 times the larger one, so the condition
        # number of diag(1e8, 1, 1) in a face's plane came back 1e8 (1 + 2e-8)
        (high > MAX_METRIC_CONDITION * (1 + 1e-6) * low, "is too anisotropic", limits),
        ((low < MIN_COST**2 * (1 - 1e-6)) | (high > MAX_COST**2 * (1 + 1e-6)), "is outside the supported range",
         limits),
    ):
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            k, t = int(owner[i]), int(face[i])
            name = "metric" if kind == "constant" else f"metric[{k}] ({_where(kind, k)})"
            d = max(_apart(low[i], MIN_COST**2, MAX_COST**2, digits=3), _apart(high[i], MIN_COST**2, MAX_COST**2,
                    digits=3), _apart(condition[i], MAX_METRIC_CONDITION, digits=3))  # not read as the bounds
            raise ParameterError(f"{name} {what} in the plane of face {t} (eigenvalues there {_g(low[i], d)}, "
                                 f"{_g(high[i], d)}: condition number {_g(condition[i], d)}); {why}")
