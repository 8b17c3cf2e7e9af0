"""Parsing helpers of the text formats (OBJ, OFF, ASCII PLY and STL): numbers and indices with line numbers."""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ._common import format_error

__all__ = ["INT_RE", "LazyLines", "decode", "match_lines", "parse_floats", "parse_int_tokens"]

INT_RE = re.compile(r"[+-]?\d+\Z")


def decode(data: bytes) -> str:
    # latin-1 never fails; every keyword and number of the text formats is ASCII.
    return data.decode("latin-1")


class LazyLines:
    """Sequence of 1-based line numbers, computed on first access (only messages and rare cases need them)."""

    def __init__(self, compute: Callable[[], Any]) -> None:
        self._compute = compute
        self._arr: np.ndarray | None = None

    @property
    def array(self) -> np.ndarray:
        if self._arr is None:
            self._arr = np.asarray(self._compute(), dtype=np.int64)
        return self._arr

    def __getitem__(self, i: Any) -> Any:
        return self.array[i]


def match_lines(text: str, regex: re.Pattern) -> np.ndarray:
    """1-based line numbers of the starts of all matches of ``regex`` in ``text`` (lines end with '\\n')."""
    starts = np.fromiter((m.start() for m in regex.finditer(text)), dtype=np.int64)
    newlines = np.flatnonzero(np.frombuffer(text.encode("latin-1"), dtype=np.uint8) == 10)
    return np.searchsorted(newlines, starts, side="left") + 1


def parse_floats(
    path: Path, rows: Sequence[list[str]], lines: np.ndarray | LazyLines, what: str, width: int = 3
) -> np.ndarray:
    """Parse lists of number tokens (``width`` per row) into an (len(rows), width) float64 array."""
    if not rows:
        return np.zeros((0, width))
    try:
        if all(len(r) == width for r in rows):
            return np.array(rows, dtype=np.float64)
    except ValueError:
        pass
    for i, r in enumerate(rows):  # slow path: locate the offending line
        if len(r) < width:
            raise format_error(path, f"line {int(lines[i])}: {what} needs {width} numbers, got {len(r)}")
        for t in r[:width]:
            try:
                float(t)
            except ValueError:
                raise format_error(path, f"line {int(lines[i])}: {what} has a non-numeric value {t!r}") from None
    return np.array([r[:width] for r in rows], dtype=np.float64)


def parse_int_tokens(path: Path, toks: list[str], tok_lines: np.ndarray | LazyLines, what: str) -> np.ndarray:
    """Parse a flat list of integer tokens into an int64 array; errors name the line."""
    try:
        return np.array(toks, dtype=np.int64) if toks else np.zeros(0, dtype=np.int64)
    except (ValueError, OverflowError):
        pass
    for k, t in enumerate(toks):
        if not INT_RE.match(t):
            raise format_error(path, f"line {int(tok_lines[k])}: {what} has a non-integer vertex index {t!r}")
        if abs(int(t)) > 2**62:
            raise format_error(path, f"line {int(tok_lines[k])}: {what} has a vertex index {t} that is far too large")
    raise format_error(path, f"cannot parse the {what} indices")  # pragma: no cover - unreachable in practice
