"""Atomic file output: a failure never leaves a half-written file behind."""

from __future__ import annotations

import os
import secrets
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import BinaryIO


def atomic_write(target: str | os.PathLike, write: Callable[[BinaryIO], None]) -> Path:
    """Call ``write(fh)`` on a fresh temporary file next to ``target``, then move it over ``target``.

    The temporary file lives in the target's directory, so ``os.replace`` is an
    atomic rename; on any exception (including KeyboardInterrupt) it is removed
    and ``target`` keeps its previous content, if any.

    Parameters
    ----------
    target : str or os.PathLike
        Final path; its directory must exist.
    write : callable
        Receives a binary file object opened for writing.

    Returns
    -------
    pathlib.Path
        ``target``.
    """
    target = Path(target)
    while True:
        tmp = target.parent / f".{target.name}.{secrets.token_hex(4)}.tmp"
        try:
            fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0), 0o666)
            break
        except FileExistsError:  # pragma: no cover - astronomically unlikely
            continue
    try:
        with os.fdopen(fd, "wb") as fh:
            write(fh)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, target)
    except BaseException:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        raise
    return target


@contextmanager
def output_set(*targets: str | os.PathLike) -> Iterator[list[Path]]:
    """Temporary paths for several outputs that must appear together: all of them, or none.

    Yields one temporary path per target, next to it and with the same suffix (so writers
    that check the extension accept it). When the block ends normally, every temporary file
    is renamed over its target; when it raises (KeyboardInterrupt included), every
    temporary file is removed and no target changes. A failure between two renames (the
    disk vanishing) can still leave the first target replaced.

    Parameters
    ----------
    *targets : str or os.PathLike
        Final paths; their directories must exist.

    Yields
    ------
    list of pathlib.Path
        The temporary paths, in the order of ``targets``.
    """
    finals = [Path(t) for t in targets]
    tmps = [p.parent / f".{p.stem}.{secrets.token_hex(4)}.part{p.suffix}" for p in finals]
    try:
        yield tmps
        missing = [str(f) for f, t in zip(finals, tmps, strict=True) if not t.exists()]
        if missing:
            raise RuntimeError(f"output_set: nothing was written for {', '.join(missing)}")
        for final, tmp in zip(finals, tmps, strict=True):
            os.replace(tmp, final)
    finally:
        for tmp in tmps:
            try:
                os.unlink(tmp)
            except FileNotFoundError:
                pass
