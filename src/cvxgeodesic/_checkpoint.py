"""The checkpoint file of :func:`~cvxgeodesic.api.distance_matrix` read back: trusted, then checked entry by entry.

A checkpoint's rows are returned as results without being solved again (:class:`~cvxgeodesic.rows.RowStore`), so
the file is

- trusted as ssh trusts a key (:func:`read_checkpoint`): a regular file (a FIFO would block the read forever),
  not reached through a symbolic link, owned by this user or root, writable by no one else;
- checked as strictly as a mesh file (:func:`checked_layout`, :func:`checked_rows`): a sparse column index of 10^9
  made ``toarray()`` crash with a segmentation fault, and NaN, negative or misshapen rows were returned silently.

A checkpoint that fails either is refused with a :class:`~cvxgeodesic.errors.ParameterError` naming the file, the
reason and the remedy, and left as it is: never ignored and overwritten, since it may hold hours of rows.
"""

from __future__ import annotations

import errno
import json
import os
import stat
from collections.abc import Callable
from pathlib import Path

import numpy as np

from .errors import ParameterError

__all__ = ["CHECKPOINT_FORMAT", "checked_layout", "checked_rows", "read_checkpoint"]

#: Version of the checkpoint file's layout.
CHECKPOINT_FORMAT = 1


def _refused(path: Path, why: str, how: str = "delete it to start again, or give another path") -> ParameterError:
    return ParameterError(f"checkpoint {path} {why}; it was not used: {how}")


def read_checkpoint(path: Path) -> dict[str, np.ndarray]:
    """The arrays of the checkpoint ``path``, read only from a regular file that no one else can have written.

    A checkpoint's rows are returned as results without being solved again, so it is trusted as ssh trusts a key:
    it must be a regular file (a FIFO would block the read forever), reached without a symbolic link at its
    name (the file is opened with ``O_NOFOLLOW`` and checked through its descriptor, so a link swapped in
    between cannot redirect the read), owned by this user (or root), and writable by no one else.

    Raises
    ------
    ParameterError
        The file is not one, belongs to another user, is writable by group or others, or is not an ``.npz``
        archive; the message names the file, the reason and the remedy.
    """
    flags = (os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_NONBLOCK", 0)
             | getattr(os, "O_CLOEXEC", 0) | getattr(os, "O_BINARY", 0))
    try:
        fd = os.open(path, flags)  # non-blocking: a FIFO opens at once, and is refused below
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            raise _refused(path, "is a symbolic link (a checkpoint is read from a regular file only)") from None
        raise _refused(path, f"cannot be read ({exc.strerror or exc})") from None
    with os.fdopen(fd, "rb") as fh:
        _check_trusted(path, os.fstat(fd))
        try:
            with np.load(fh, allow_pickle=False) as z:
                if not isinstance(z, np.lib.npyio.NpzFile):
                    raise ValueError("a single array, not an .npz archive")
                return {k: z[k] for k in z.files}
        except Exception as exc:  # any unreadable file: not a checkpoint of this function
            raise _refused(path, f"is not a distance_matrix checkpoint ({exc})") from None


def _check_trusted(path: Path, st: os.stat_result) -> None:
    """Refuse a checkpoint that is not a regular file, or that another user has or may have written."""
    if not stat.S_ISREG(st.st_mode):
        kinds = ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a character device"),
                 (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))
        kind = next((k for test, k in kinds if test(st.st_mode)), "not a regular file")
        raise _refused(path, f"is {kind}, not a checkpoint file", "give the path of a file")
    if os.name != "posix":  # no owner and group permission bits to go by
        return
    me = os.geteuid()
    if st.st_uid not in (me, 0):
        raise _refused(path, f"belongs to another user (uid {st.st_uid}, you are uid {me}): its rows would be "
                       "returned as your results", "delete it (or have it deleted) to start again, or give another "
                       "path")
    if st.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        who = "group and others" if st.st_mode & stat.S_IWGRP and st.st_mode & stat.S_IWOTH else (
            "its group" if st.st_mode & stat.S_IWGRP else "others")
        raise _refused(path, f"is writable by {who} ({stat.filemode(st.st_mode)}): anyone who can write it could "
                       "change the rows it returns", "if you made it and trust it, chmod go-w it to resume; else "
                       "delete it to start again")


def checked_layout(data: dict[str, np.ndarray], path: Path) -> dict[str, str]:
    """The parameters of a checkpoint's arrays after checking its header entries (format, shape, sparse, index,
    parameters); a ParameterError naming the file and the first defect otherwise."""
    def bad(what: str) -> ParameterError:
        return _refused(path, f"is damaged or not a distance_matrix checkpoint ({what})")

    for key in ("format", "shape", "sparse", "index", "parameters"):
        if key not in data:
            raise bad(f"no {key!r} entry")
    fmt, shape, sparse, index = data["format"], data["shape"], data["sparse"], data["index"]
    if fmt.shape != () or fmt.dtype.kind not in "iu":
        raise bad(f"'format' is {fmt.dtype} {fmt.shape}, not an integer")
    if int(fmt) != CHECKPOINT_FORMAT:
        raise bad(f"format {int(fmt)}, expected {CHECKPOINT_FORMAT}")
    if shape.shape != (2,) or shape.dtype.kind not in "iu" or (shape < 0).any():
        raise bad(f"'shape' is {shape.dtype} {shape.shape} {_short(shape)}, not two counts")
    if sparse.shape != () or sparse.dtype != np.bool_:
        raise bad(f"'sparse' is {sparse.dtype} {sparse.shape}, not a boolean")
    if index.ndim != 1 or index.dtype.kind not in "iu":
        raise bad(f"'index' is {index.dtype} {index.shape}, not a list of row numbers")
    if index.size and ((index < 0).any() or (index >= shape[0]).any()):
        raise bad(f"a row number outside [0, {int(shape[0])}) in 'index'")
    if (np.diff(index) <= 0).any():
        raise bad("row numbers in 'index' repeated or out of order")
    text = data["parameters"]
    try:
        theirs = json.loads(str(text)) if text.shape == () and text.dtype.kind == "U" else None
    except ValueError:
        theirs = None
    if not isinstance(theirs, dict) or not all(isinstance(k, str) and isinstance(v, str) for k, v in theirs.items()):
        raise bad("'parameters' is not the JSON text of the call's parameters")
    return theirs


def checked_rows(data: dict[str, np.ndarray], path: Path, shape: tuple[int, int], sparse: bool) -> np.ndarray:
    """The row numbers of a checkpoint (of ``shape`` and kind ``sparse``, header checked) after checking its rows:
    shapes, types, column ranges, sorted distinct columns, distances ≥ 0 (dense: ``inf`` where unreachable)."""
    def bad(what: str) -> ParameterError:
        return _refused(path, f"is damaged ({what})")

    index = data["index"].astype(np.int64)
    n_cols = shape[1]
    if not sparse:
        rows = data.get("rows")
        if rows is None:
            raise bad("no 'rows' entry")
        if rows.shape != (index.size, n_cols) or rows.dtype != np.float64:
            raise bad(f"'rows' is {rows.dtype} {rows.shape}, expected float64 {(index.size, n_cols)}")
        _check_distances(rows, bad, finite=False)
        return index
    for key in ("lengths", "cols", "vals"):
        if key not in data or data[key].ndim != 1:
            raise bad(f"no {key!r} entry" if key not in data else f"{key!r} is not one-dimensional")
    lengths, cols, vals = data["lengths"], data["cols"], data["vals"]
    if lengths.dtype.kind not in "iu" or cols.dtype.kind not in "iu" or vals.dtype != np.float64:
        raise bad(f"'lengths', 'cols', 'vals' are {lengths.dtype}, {cols.dtype}, {vals.dtype}: expected integers, "
                  "integers, float64")
    if lengths.size != index.size or (lengths < 0).any() or int(lengths.sum()) != cols.size or cols.size != vals.size:
        raise bad(f"{lengths.size} row lengths summing to {int(lengths.sum())} for {index.size} rows, {cols.size} "
                  f"columns and {vals.size} values")
    if cols.size and ((cols < 0).any() or (cols >= n_cols).any()):
        where = int(np.flatnonzero((cols < 0) | (cols >= n_cols))[0])
        raise bad(f"column {int(cols[where])} at entry {where} of 'cols', outside [0, {n_cols})")
    row_of = np.repeat(np.arange(index.size), lengths.astype(np.int64))
    if ((np.diff(cols.astype(np.int64)) <= 0) & (np.diff(row_of) == 0)).any():
        raise bad("columns of a row repeated or out of order in 'cols'")
    _check_distances(vals, bad, finite=True)
    return index


def _check_distances(values: np.ndarray, bad: Callable[[str], ParameterError], *, finite: bool) -> None:
    """Distances are ≥ 0 and never NaN; ``inf`` (an unreachable vertex of a dense row) unless ``finite``."""
    # one comparison pass (NaN compares False): a dense checkpoint can hold hundreds of MB
    wrong = ~((values >= 0) & (values < np.inf)) if finite else ~(values >= 0)
    if wrong.any():
        k = np.unravel_index(int(np.flatnonzero(wrong)[0]), values.shape)
        allowed = "finite and ≥ 0" if finite else "≥ 0 (or inf)"
        raise bad(f"distance {float(values[k])!r} at {tuple(int(i) for i in k)}; distances are {allowed}")


def _short(a: np.ndarray) -> str:
    return np.array2string(a, threshold=6)
