"""STL, binary or ASCII: a triangle soup, whose file vertices are the triangle corners (welded on loading)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from ._common import RawMesh, format_error, read_bytes
from ._text import decode, parse_floats

__all__ = ["read_mesh"]

_STL_DTYPE = np.dtype([("normal", "<f4", (3,)), ("v", "<f4", (3, 3)), ("attr", "<u2")])


def read_mesh(path: Path) -> RawMesh:
    """The triangles of a binary or ASCII STL file, corner ``3 * triangle + k`` as file vertex, with line numbers
    for ASCII files.

    Warns
    -----
    UserWarning
        When a binary STL has bytes after its last triangle (they are ignored).
    """
    data = read_bytes(path, "a mesh file")
    n_bin = int.from_bytes(data[80:84], "little") if len(data) >= 84 else -1
    binary_size = 84 + 50 * n_bin if n_bin >= 0 else -1
    looks_ascii = data.lstrip()[:5].lower() == b"solid" and b"\0" not in data[:1024]
    if len(data) == binary_size or (not looks_ascii and 0 <= binary_size < len(data)):
        if len(data) > binary_size:
            warnings.warn(
                f"{path.name}: ignoring {len(data) - binary_size} trailing bytes after the binary STL data",
                UserWarning,
                stacklevel=3,  # read_mesh <- load_mesh <- the caller
            )
        tri = np.frombuffer(data, dtype=_STL_DTYPE, count=n_bin, offset=84)
        V = tri["v"].reshape(-1, 3).astype(np.float64)
        return RawMesh(V, np.arange(V.shape[0], dtype=np.int64), np.full(n_bin, 3, dtype=np.int64))
    if looks_ascii:
        return _read_ascii(path, data)
    if len(data) < 84:
        raise format_error(
            path, f"not an ASCII STL and too short ({len(data)} bytes) for a binary STL (84-byte header)"
        )
    raise format_error(
        path,
        f"binary STL is truncated: the header announces {n_bin} triangles ({binary_size} bytes) "
        f"but the file has {len(data)} bytes",
    )


def _read_ascii(path: Path, data: bytes) -> RawMesh:
    lines = decode(data).splitlines()
    v_rows: list[list[str]] = []
    v_lines: list[int] = []
    sizes: list[int] = []
    f_lines: list[int] = []
    in_loop = False
    count = 0
    for ln_no, line in enumerate(lines, 1):
        toks = line.split()
        if not toks:
            continue
        key = toks[0].lower()
        if key == "vertex":
            if not in_loop:
                raise format_error(path, f"line {ln_no}: 'vertex' outside an 'outer loop'")
            v_rows.append(toks[1:])
            v_lines.append(ln_no)
            count += 1
        elif key == "outer":
            if in_loop:
                raise format_error(path, f"line {ln_no}: 'outer loop' inside another loop (missing 'endloop')")
            in_loop, count = True, 0
            f_lines.append(ln_no)
        elif key == "endloop":
            if not in_loop:
                raise format_error(path, f"line {ln_no}: 'endloop' without 'outer loop'")
            if count < 3:
                raise format_error(path, f"line {ln_no}: facet has {count} vertices; a facet needs 3")
            in_loop = False
            sizes.append(count)
        elif key not in ("solid", "endsolid", "facet", "endfacet"):
            raise format_error(path, f"line {ln_no}: unexpected ASCII STL keyword {toks[0][:40]!r}")
    if in_loop:
        raise format_error(path, f"line {len(lines)}: file ends inside a facet (missing 'endloop')")
    v_lines_a = np.asarray(v_lines, dtype=np.int64)
    bad = [i for i, r in enumerate(v_rows) if len(r) != 3]
    if bad:
        i = bad[0]
        raise format_error(path, f"line {v_lines[i]}: 'vertex' needs 3 numbers, got {len(v_rows[i])}")
    V = parse_floats(path, v_rows, v_lines_a, "'vertex'", 3)
    return RawMesh(
        V,
        np.arange(V.shape[0], dtype=np.int64),
        np.asarray(sizes, dtype=np.int64),
        v_lines_a,
        np.asarray(f_lines, dtype=np.int64),
    )
