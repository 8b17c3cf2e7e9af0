"""Plain-text and markdown tables: the one formatter behind compare, demo, the report and the CLI.

A table is a list of rows (dicts) and a list of :class:`Column` specs saying which key each column
shows, under which header, formatted how and aligned which way. :func:`text_table` lays it out for a
terminal (what ``cvxgeodesic compare`` and ``cvxgeodesic demo`` print), :func:`markdown_table` and
:func:`format_markdown` for markdown (``docs/results.md``).

This module imports nothing from the rest of the package, so any layer may use it.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

__all__ = ["Column", "MISSING", "cell_text", "format_markdown", "markdown_table", "text_table"]

#: What a cell shows when its value is missing (None or an empty string).
MISSING = "-"


@dataclass(frozen=True)
class Column:
    """One column of a table.

    Parameters
    ----------
    header : str
        The column's title.
    key : str
        The row key it shows.
    fmt : callable, default str
        Turns a present value into its cell text; a value it cannot format
        (``TypeError`` / ``ValueError``) is shown with ``str``.
    align : {"right", "left"}, default "right"
        Alignment in :func:`text_table` and in markdown.
    max_len : int, optional
        Longer cell texts are cut to this many characters, the last one an ellipsis ``…``.
    """

    header: str
    key: str
    fmt: Callable[[Any], str] = str
    align: str = "right"
    max_len: int | None = None

    def __post_init__(self) -> None:
        if self.align not in ("right", "left"):
            raise ValueError(f"align must be 'right' or 'left', got {self.align!r} (column {self.header!r})")
        if self.max_len is not None and self.max_len < 1:
            raise ValueError(f"max_len must be a positive int, got {self.max_len!r} (column {self.header!r})")


def cell_text(row: Mapping[str, Any], col: Column, missing: str = MISSING) -> str:
    """The text of one cell: ``missing`` for an absent, None or empty value, else ``col.fmt(value)``."""
    v = row.get(col.key)
    if v is None or (isinstance(v, str) and not v):
        return missing
    try:
        s = col.fmt(v)
    except (TypeError, ValueError):
        s = str(v)
    if col.max_len is not None and len(s) > col.max_len:
        s = s[: col.max_len - 1] + "…"
    return s


def text_table(rows: Iterable[Mapping[str, Any]], columns: Sequence[Column], *, missing: str = MISSING) -> str:
    """Aligned plain-text table: a header line, a rule of dashes under each column, one line per row.

    Parameters
    ----------
    rows : iterable of mapping
        One dict per line; keys not named by a column are ignored.
    columns : sequence of Column
        The columns, left to right.
    missing : str, default "-"
        Text of a missing value.

    Returns
    -------
    str
        Lines joined by newlines (no trailing newline); columns two spaces apart, each as wide as
        its widest cell or header, trailing blanks stripped.
    """
    cells = [[cell_text(row, c, missing) for c in columns] for row in rows]
    heads = [c.header for c in columns]
    widths = [max([len(h)] + [len(line[j]) for line in cells]) for j, h in enumerate(heads)]

    def fmt_line(items: Sequence[str]) -> str:
        parts = [s.ljust(w) if c.align == "left" else s.rjust(w)
                 for s, w, c in zip(items, widths, columns, strict=True)]
        return "  ".join(parts).rstrip()

    lines = [fmt_line(heads), "  ".join("-" * w for w in widths)]
    lines += [fmt_line(line) for line in cells]
    return "\n".join(lines)


def markdown_table(header: Sequence[str], rows: Iterable[Sequence[Any]], align: str | None = None) -> str:
    """A markdown (GitHub) table of cells already formatted.

    Parameters
    ----------
    header : sequence of str
        Column titles, ``k`` of them.
    rows : iterable of sequence
        Each of ``k`` cells (shown with ``str``).
    align : str, optional
        One letter per column: ``"l"`` left, ``"r"`` right, ``"c"`` centred. Default: the first
        column left, the others right.

    Returns
    -------
    str
        Header, separator and row lines (no trailing newline).
    """
    align = align or "l" + "r" * (len(header) - 1)
    if len(align) != len(header):
        raise ValueError(f"align must have one letter per column ({len(header)}), got {align!r}")
    sep = ["---:" if a == "r" else ":---:" if a == "c" else "---" for a in align]
    lines = ["| " + " | ".join(header) + " |", "| " + " | ".join(sep) + " |"]
    lines += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(lines)


def format_markdown(rows: Iterable[Mapping[str, Any]], columns: Sequence[Column], *, missing: str = MISSING) -> str:
    """The rows of :func:`text_table` as a markdown table (same columns, formats and alignment)."""
    align = "".join("l" if c.align == "left" else "r" for c in columns)
    body = [[cell_text(row, c, missing) for c in columns] for row in rows]
    return markdown_table([c.header for c in columns], body, align)
