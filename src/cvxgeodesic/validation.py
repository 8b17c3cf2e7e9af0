"""Input checks shared by every entry point, with one error vocabulary.

Every function here returns the normalized value or raises an error from :mod:`cvxgeodesic.errors`
whose message names the parameter and the offending value or index:

- :class:`~cvxgeodesic.errors.ParameterError` for options and per-vertex arrays
  (numbers, counts, choices, fields, masks, index arrays, output paths);
- :class:`~cvxgeodesic.errors.SourceError` for source vertices (:func:`validate_sources`).

A leaf module (NumPy and :mod:`cvxgeodesic.errors` only), so that the mesh code, the problem
builders, the API and the applications can all use it without importing each other.
"""

from __future__ import annotations

import numbers
import os
import tempfile
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .errors import ParameterError, SourceError

__all__ = [
    "as_points", "as_vertex_field", "check_choice", "check_cost", "check_count", "check_medium_method", "check_metric",
    "check_not_an_input", "check_number", "check_output_path", "check_plane_metric", "check_type", "is_integer",
    "is_real", "short_repr", "validate_sources", "vertex_indices", "vertex_mask",
]


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
    """The element order: 1 (P1 distance) or 2 (P2 squared distance); ParameterError otherwise."""
    if not is_integer(order) or int(order) not in (1, 2):
        raise ParameterError(f"order must be 1 (P1 distance) or 2 (P2 squared distance), got {short_repr(order)}")
    return int(order)


def check_smoothness(m: Any, lam: Any) -> tuple[float, float | None]:
    """``(m, lam)`` checked: ``m`` a finite number ≥ 0 (always, even when ``lam`` is given or the method has no
    smoothness term, so that every order and method gives the same verdict), ``lam`` None or a finite number ≥ 0."""
    m_value = check_number(m, "m", low=0)
    lam_value = None if lam is None else check_number(lam, "lam", low=0)
    return m_value, lam_value


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


def as_points(x: ArrayLike, name: str, *, error: type[Exception] = ParameterError) -> np.ndarray:
    """Return ``x`` as a (3,) or (k, 3) float64 array of finite positions, or raise ``error`` naming ``name``.

    Parameters
    ----------
    x : array_like
        One position (3,) or k positions (k, 3).
    name : str
        Parameter name used in the message.
    error : type
        :class:`~cvxgeodesic.errors.ParameterError` (default) or :class:`~cvxgeodesic.errors.SourceError`
        (positions that define sources).

    Returns
    -------
    (3,) or (k, 3) float64 ndarray

    Raises
    ------
    error
        Not numeric, of another shape, or with a NaN or infinite coordinate (the message names the
        first such row).
    """
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


def validate_sources(sources: Any, n: int) -> np.ndarray:
    """Check and normalize source vertex indices.

    Parameters
    ----------
    sources : int or sequence of int
        Python or NumPy integers; floats with an integral value are accepted, booleans
        (including NumPy bool arrays) are not.
    n : int
        Number of vertices.

    Returns
    -------
    (k,) int64 ndarray
        The indices, in the given order.

    Raises
    ------
    SourceError
        Empty, ragged, nested, non-integer (bool, float with a fraction, NaN, string,
        ``None``), negative, out-of-range or duplicated indices.
    """
    if isinstance(sources, bool | np.bool_):
        raise SourceError(f"sources must be vertex indices, got {sources!r}")
    try:
        arr = np.atleast_1d(np.asarray(sources))
    except (ValueError, TypeError, OverflowError):  # ragged nesting and the like
        raise SourceError(f"sources must be an int or a 1-D sequence of ints, got {short_repr(sources)}") from None
    if arr.ndim != 1:
        raise SourceError(f"sources must be an int or a 1-D sequence of ints, got shape {arr.shape}")
    if arr.size == 0:
        raise SourceError("sources is empty: give at least one source vertex")
    out_of_range = "is out of range: the mesh has {n} vertices (0..{last})"
    if arr.dtype == object and all(isinstance(v, int) and not isinstance(v, bool) for v in arr):
        # Python ints too large for int64
        big = next(v for v in arr if not -(2**63) <= v < 2**63)
        raise SourceError(f"source index {big} " + out_of_range.format(n=n, last=n - 1))
    if arr.dtype.kind == "f" and np.all(np.isfinite(arr)) and np.all(arr == np.round(arr)):
        big = np.abs(arr) >= 2.0**62
        if big.any():
            raise SourceError(f"source index {arr[big][0]:g} " + out_of_range.format(n=n, last=n - 1))
        arr = arr.astype(np.int64)
    if arr.dtype.kind not in "iu":
        raise SourceError(f"sources must be integer vertex indices, got {short_repr(sources)}")
    if arr.dtype.kind == "u" and arr.max() >= 2**63:
        raise SourceError(f"source index {int(arr.max())} " + out_of_range.format(n=n, last=n - 1))
    arr = arr.astype(np.int64)
    bad = (arr < 0) | (arr >= n)
    if bad.any():
        raise SourceError(f"source index {int(arr[bad][0])} " + out_of_range.format(n=n, last=n - 1))
    uniq, counts = np.unique(arr, return_counts=True)
    if (counts > 1).any():
        raise SourceError(f"source vertex {int(uniq[counts > 1][0])} is given more than once")
    return arr


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
            try:
                same = os.path.samefile(out, src)
            except OSError:
                same = False
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
        fd, probe = tempfile.mkstemp(prefix=f".{p.name}.", suffix=".probe", dir=p.parent)
    except OSError as exc:
        raise ParameterError(
            f"cannot write {p}: cannot create files in directory {p.parent} ({exc.strerror or exc})"
        ) from None
    os.close(fd)
    os.unlink(probe)
    return p


# ---------------------------------------------------------------------------------------------------------------
# travel cost and metric (cvxgeodesic.operators.metric)
# ---------------------------------------------------------------------------------------------------------------
def _where(kind: str, k: int) -> str:
    return {"vertices": f"vertex {k}", "faces": f"face {k}"}.get(kind, "the constant")


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
        Not numeric, another shape, or a value that is not positive and finite (the message names the first one).
    """
    try:
        arr = np.asarray(cost, dtype=np.float64)
    except (TypeError, ValueError):
        raise ParameterError(f"cost must be a positive number or an array of shape ({n},) (per vertex) or ({m},) "
                             f"(per face), got {short_repr(cost)}") from None
    if arr.ndim == 0:
        kind, arr = "constant", arr.reshape(1)
    elif arr.ndim == 1 and arr.shape[0] == n:
        kind = "vertices"
    elif arr.ndim == 1 and arr.shape[0] == m:
        kind = "faces"
    else:
        raise ParameterError(f"cost must have shape ({n},) (one value per vertex) or ({m},) (one per face), "
                             f"got shape {arr.shape}")
    bad = ~(np.isfinite(arr) & (arr > 0))
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        at = "" if kind == "constant" else f"[{k}]"
        raise ParameterError(f"cost{at} = {float(arr[k])!r} ({_where(kind, k)}) must be positive and finite")
    return arr, kind


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
        Not numeric, another shape, a non-finite entry or a tensor that is not symmetric (relative 1e-10), naming
        the first.
    """
    try:
        arr = np.asarray(metric, dtype=np.float64)
    except (TypeError, ValueError):
        raise ParameterError(f"metric must be a (3, 3), ({n}, 3, 3) or ({m}, 3, 3) array of symmetric tensors, "
                             f"got {short_repr(metric)}") from None
    if arr.shape == (3, 3):
        kind, arr = "constant", arr.reshape(1, 3, 3)
    elif arr.ndim == 3 and arr.shape[1:] == (3, 3) and arr.shape[0] == n:
        kind = "vertices"
    elif arr.ndim == 3 and arr.shape[1:] == (3, 3) and arr.shape[0] == m:
        kind = "faces"
    else:
        raise ParameterError(f"metric must have shape (3, 3) (one tensor), ({n}, 3, 3) (per vertex) or ({m}, 3, 3) "
                             f"(per face), got shape {arr.shape}")
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
    """Raise a ParameterError unless every metric restricted to a face's plane is positive definite.

    Parameters
    ----------
    M2 : (k, 2, 2) float ndarray
        Restricted tensors ``E_tᵀ M E_t`` (NaN rows, of faces without a plane, are skipped).
    owner : (k,) int ndarray
        Index of the tensor each row comes from (in the user's array).
    face : (k,) int ndarray
        The face whose plane each row is restricted to.
    kind : {"constant", "vertices", "faces"}
    """
    a, b, c = M2[:, 0, 0], M2[:, 0, 1], M2[:, 1, 1]
    with np.errstate(invalid="ignore"):
        bad = (a <= 0) | (a * c - b * b <= 1e-12 * np.maximum(a * c, 1e-300))
    bad &= np.isfinite(M2).all(axis=(1, 2))
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        k, t = int(owner[i]), int(face[i])
        name = "metric" if kind == "constant" else f"metric[{k}] ({_where(kind, k)})"
        ev = np.linalg.eigvalsh(M2[i])
        raise ParameterError(f"{name} is not positive definite in the plane of face {t} (eigenvalues there "
                             f"{ev[0]:.3g}, {ev[1]:.3g}); lengths along the surface need a positive definite metric")


def check_medium_method(method: str, supported: Iterable[str], *, multires: bool = False) -> None:
    """A ParameterError unless ``method`` takes a travel cost or metric (``supported`` lists those that do)."""
    if method not in tuple(supported):
        raise ParameterError(f"method {method!r} cannot take a travel cost or metric (its library computes Euclidean "
                             f"distances); methods that can: {', '.join(supported)}")
    if multires:
        raise ParameterError("cost and metric are not implemented with multires; solve on the mesh itself")
