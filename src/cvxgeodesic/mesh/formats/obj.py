"""Wavefront OBJ: ``v`` and ``f`` statements (``i``, ``i/t``, ``i//n``, ``i/t/n``, negative indices)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ._common import RawMesh, format_error, read_bytes
from ._text import LazyLines, decode, match_lines, parse_floats, parse_int_tokens

__all__ = ["read_mesh"]

_SLASH_RE = re.compile(r"/\S*")
# A 'v' / 'f' statement: the keyword alone or followed by whitespace (so 'vt', 'vn', 'fo' do not match).
_OBJ_V_RE = re.compile(r"^[ \t]*v(?![^ \t\n])([^\n]*)", re.M)
_OBJ_F_RE = re.compile(r"^[ \t]*f(?![^ \t\n])([^\n]*)", re.M)


def read_mesh(path: Path) -> RawMesh:
    """The vertices and polygons of an OBJ file, with line numbers and the 1-based indices as written (``raw_idx``)
    for messages; texture coordinates, normals, groups and materials are ignored."""
    text = decode(read_bytes(path, "a mesh file"))
    if "\r" in text:
        text = text.replace("\r\n", "\n").replace("\r", "\n")
    v_body = _OBJ_V_RE.findall(text)
    f_body = _OBJ_F_RE.findall(text)
    if not v_body and not f_body:
        raise format_error(path, "no 'v' or 'f' statements found (empty or not an OBJ file)")
    v_lines = LazyLines(lambda: match_lines(text, _OBJ_V_RE))
    f_lines = LazyLines(lambda: match_lines(text, _OBJ_F_RE))

    # Vertices: 'v x y z [w]' or 'v x y z r g b'; only x, y, z are used.
    v_toks = [b.split() for b in v_body]
    if all(len(t) == 3 for t in v_toks):
        try:
            V = np.array(" ".join(v_body).split(), dtype=np.float64).reshape(-1, 3)
        except ValueError:
            V = parse_floats(path, v_toks, v_lines, "vertex ('v')", 3)
    else:
        V = parse_floats(path, [t[:3] if len(t) > 3 else t for t in v_toks], v_lines, "vertex ('v')", 3)

    # Faces: strip the '/texture/normal' part of each entry, then split.
    if f_body:
        body = "\n".join(f_body)
        if "/" in body:
            f_body = _SLASH_RE.sub("", body).split("\n")
    sizes = np.fromiter((len(b.split()) for b in f_body), dtype=np.int64, count=len(f_body))
    toks = " ".join(f_body).split()
    tok_lines = LazyLines(lambda: np.repeat(f_lines.array, sizes))
    raw_idx = parse_int_tokens(path, toks, tok_lines, "face ('f')")
    zero = raw_idx == 0
    if zero.any():
        k = int(np.flatnonzero(zero)[0])
        raise format_error(path, f"line {int(tok_lines[k])}: face vertex index 0 is invalid (OBJ indices start at 1)")
    neg = raw_idx < 0
    if neg.any():  # relative indices: -1 is the last vertex defined before the face
        v_pos = np.fromiter((m.start() for m in _OBJ_V_RE.finditer(text)), dtype=np.int64)
        f_pos = np.fromiter((m.start() for m in _OBJ_F_RE.finditer(text)), dtype=np.int64)
        nv_before = np.repeat(np.searchsorted(v_pos, f_pos), sizes)
        idx = np.where(neg, nv_before + raw_idx, raw_idx - 1)
    else:
        idx = raw_idx - 1
    return RawMesh(V, idx, sizes, v_lines, f_lines, raw_idx)
