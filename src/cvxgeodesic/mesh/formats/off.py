"""OFF (Object File Format), ASCII: ``OFF`` and its ``C``/``N``/``ST`` variants; colors and normals are ignored."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ._common import RawMesh, format_error, read_bytes
from ._text import INT_RE, decode, parse_floats, parse_int_tokens

__all__ = ["read_mesh"]

_OFF_HEADER_RE = re.compile(r"(ST)?(C)?(N)?(4)?(n)?OFF\Z")


def read_mesh(path: Path) -> RawMesh:
    """The vertices and polygons of an ASCII OFF file, with line numbers (binary, 4-D and n-D OFF are refused)."""
    text = decode(read_bytes(path, "a mesh file"))
    if "#" in text:
        text = re.sub(r"#[^\r\n]*", "", text)
    all_lines = text.splitlines()
    # (line number, content) of non-blank lines
    nonblank = [(i, s) for i, s in enumerate(all_lines, 1) if s.strip()]
    if not nonblank:
        raise format_error(path, "file is empty")
    ln0, head = nonblank[0]
    head_toks = head.split()
    if not _OFF_HEADER_RE.match(head_toks[0]):
        raise format_error(path, f"line {ln0}: expected an 'OFF' header, got {head_toks[0][:40]!r}")
    if "BINARY" in (t.upper() for t in head_toks[1:]):
        raise format_error(path, f"line {ln0}: binary OFF files are not supported (convert to ASCII OFF or PLY)")
    if "4" in head_toks[0] or "n" in head_toks[0]:
        raise format_error(path, f"line {ln0}: {head_toks[0]!r} (4-D or n-D OFF) is not supported")
    pos = 1
    count_toks = head_toks[1:]
    count_line = ln0
    if not count_toks:
        if pos >= len(nonblank):
            raise format_error(path, f"line {ln0}: missing the 'vertices faces edges' counts line")
        count_line, s = nonblank[pos]
        count_toks = s.split()
        pos += 1
    if len(count_toks) < 2 or not all(INT_RE.match(t) for t in count_toks[:3]):
        got = " ".join(count_toks)
        raise format_error(path, f"line {count_line}: expected the counts 'vertices faces [edges]', got {got!r}")
    nv, nf = int(count_toks[0]), int(count_toks[1])
    if nv < 0 or nf < 0:
        raise format_error(path, f"line {count_line}: negative vertex or face count")
    vblock = nonblank[pos : pos + nv]
    if len(vblock) < nv:
        raise format_error(path, f"file ends after {len(vblock)} of {nv} vertices (line {len(all_lines)})")
    v_lines = np.fromiter((ln for ln, _ in vblock), dtype=np.int64, count=nv)
    V = parse_floats(path, [s.split() for _, s in vblock], v_lines, "vertex", 3)
    pos += nv
    fblock = nonblank[pos : pos + nf]
    if len(fblock) < nf:
        raise format_error(path, f"file ends after {len(fblock)} of {nf} faces (line {len(all_lines)})")
    f_lines = np.fromiter((ln for ln, _ in fblock), dtype=np.int64, count=nf)
    tok_lists = [s.split() for _, s in fblock]
    first = [t[0] for t in tok_lists]
    counts = parse_int_tokens(path, first, f_lines, "face vertex count")
    rows_ok = counts >= 0
    if not rows_ok.all():
        f = int(np.flatnonzero(~rows_ok)[0])
        raise format_error(path, f"line {int(f_lines[f])}: face {f} has a negative vertex count")
    lens = np.fromiter((len(t) for t in tok_lists), dtype=np.int64, count=nf)
    short = lens - 1 < counts
    if short.any():
        f = int(np.flatnonzero(short)[0])
        raise format_error(
            path, f"line {int(f_lines[f])}: face {f} announces {int(counts[f])} vertices but lists {int(lens[f] - 1)}"
        )
    if nf and np.all(lens == counts + 1):
        toks = [x for t in tok_lists for x in t[1:]]
    else:
        toks = [x for t, c in zip(tok_lists, counts.tolist(), strict=True) for x in t[1 : 1 + c]]
    tok_lines = np.repeat(f_lines, counts)
    idx = parse_int_tokens(path, toks, tok_lines, "face")
    return RawMesh(V, idx, counts.astype(np.int64), v_lines, f_lines)
