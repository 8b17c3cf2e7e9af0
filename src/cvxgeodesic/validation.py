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
    "as_points", "as_vertex_field", "check_choice", "check_count", "check_number", "check_output_path", "check_type",
    "is_integer", "is_real", "short_repr", "validate_sources", "vertex_indices", "vertex_mask",
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
