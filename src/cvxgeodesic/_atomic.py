"""Atomic file output: a failure never leaves a half-written file behind."""

from __future__ import annotations

import os
import secrets
from collections.abc import Callable
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
