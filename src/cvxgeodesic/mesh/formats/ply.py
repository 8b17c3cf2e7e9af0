"""PLY (ASCII, binary little- and big-endian): meshes in, fields out as a ``double`` vertex property; a PLY without
faces holds points (:func:`holds_points`, :func:`read_points`: ``nx, ny, nz`` vertex properties are normals)."""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np

from ...errors import MeshFormatError
from ._common import FieldData, RawMesh, RawPoints, format_error, read_bytes
from ._text import INT_RE, decode, parse_floats, parse_int_tokens

__all__ = ["holds_points", "read_field", "read_fields", "read_mesh", "read_points", "write_field"]

#: numpy's type code of each PLY type, by both of its names (the original and the sized one).
_PLY_TYPES = {name: code for names, code in (("char int8", "i1"), ("uchar uint8", "u1"), ("short int16", "i2"),
                                             ("ushort uint16", "u2"), ("int int32", "i4"), ("uint uint32", "u4"),
                                             ("float float32", "f4"), ("double float64", "f8"))
              for name in names.split()}


@dataclass
class _PlyProp:
    name: str
    dtype: str  # numpy type code without byte order, e.g. "f4"
    count_dtype: str | None = None  # set for list properties


@dataclass
class _PlyElement:
    name: str
    count: int
    props: list[_PlyProp]
    line: int


# ----------------------------------------------------------------------------------------------------------------------
# Reading
# ----------------------------------------------------------------------------------------------------------------------


def read_mesh(path: Path) -> RawMesh:
    """The ``vertex`` element's ``x, y, z`` and the ``face`` element's index lists, with line numbers for ASCII
    files; other elements are skipped."""
    values, line_nos = _read_elements(path, read_bytes(path, "a mesh file"))
    V, idx, sizes, v_lines, f_lines, _ = _mesh_parts(path, values, line_nos)
    return RawMesh(V, idx, sizes, v_lines, f_lines)


def holds_points(path: Path) -> bool:
    """Whether the PLY file ``path`` holds points: its header declares no ``face`` element, or one of count 0 (an
    unreadable header: False, and ``load_mesh`` says what is wrong)."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(1 << 16)
        return not _has_faces(_parse_header(path, head)[1])
    except (OSError, MeshFormatError):
        return False


def read_points(path: Path) -> RawPoints:
    """The ``vertex`` element's ``x, y, z`` (and ``nx, ny, nz`` when it has all three) of a PLY without faces.

    Raises
    ------
    MeshFormatError
        The file has faces (it is a mesh: ``load_mesh``), or no scalar ``x``, ``y``, ``z`` vertex properties.
    """
    data = read_bytes(path, "a PLY file")
    if _has_faces(_parse_header(path, data)[1]):
        raise format_error(path, "the PLY file has faces: it is a mesh (load_mesh), not a point cloud")
    vert = _read_elements(path, data)[0].get("vertex", {})
    missing = [c for c in "xyz" if c not in vert or isinstance(vert[c], tuple)]
    if missing:
        raise format_error(path, f"the PLY 'vertex' element has no scalar propert{'y' if len(missing) == 1 else 'ies'}"
                                 f" {', '.join(missing)}")
    P = np.stack([np.asarray(vert[c], dtype=np.float64) for c in "xyz"], axis=1)
    normals = ("nx", "ny", "nz")
    if not all(c in vert and not isinstance(vert[c], tuple) for c in normals):
        return RawPoints(P)
    return RawPoints(P, np.stack([np.asarray(vert[c], dtype=np.float64) for c in normals], axis=1))


def _has_faces(elements: list[_PlyElement]) -> bool:
    return any(el.name == "face" and el.count > 0 for el in elements)


def read_fields(path: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, np.ndarray]]:
    """Vertices, polygons and every scalar vertex property of a PLY file, nothing welded.

    Parameters
    ----------
    path : pathlib.Path

    Returns
    -------
    V : (n, 3) float64 ndarray
    idx, sizes : (k,) / (p,) int64 ndarray
        The polygons, as in :class:`RawMesh`.
    fields : dict of str to (n,) float64 ndarray
        Every scalar vertex property other than ``x``, ``y``, ``z``.
    """
    values, line_nos = _read_elements(path, read_bytes(path, "a PLY file"))
    V, idx, sizes, _, _, props = _mesh_parts(path, values, line_nos)
    return V, idx, sizes, {k: np.asarray(v, dtype=np.float64) for k, v in props.items()}


def read_field(path: Path, name: str) -> np.ndarray:
    """The scalar vertex property ``name`` as an (n,) float64 array.

    Raises
    ------
    MeshFormatError
        The file has no such property (the message lists the ones it has).
    """
    values, _ = _read_elements(path, read_bytes(path, "a PLY file"))
    vert = values.get("vertex")
    if vert is None:
        raise format_error(path, "PLY file has no 'vertex' element")
    scalars = [k for k, v in vert.items() if not isinstance(v, tuple) and k not in "xyz"]
    if name not in scalars:
        raise format_error(path, f"no vertex property {name!r} (the file's fields: {', '.join(scalars) or 'none'})")
    return np.asarray(vert[name], dtype=np.float64)


def _parse_header(path: Path, data: bytes) -> tuple[str, list[_PlyElement], int, int]:
    """Return ``(format, elements, body_offset, header_line_count)``."""
    if not data.startswith(b"ply"):
        raise format_error(path, "line 1: not a PLY file (missing the 'ply' magic line)")
    m = re.search(rb"end_header[ \t]*(\r\n|\n|\r)", data)
    if m is None:
        raise format_error(path, "PLY header has no 'end_header' line")
    header = data[: m.start()].decode("latin-1").splitlines()
    fmt = None
    elements: list[_PlyElement] = []
    for ln_no, line in enumerate(header, 1):
        toks = line.split()
        if not toks or toks[0] in ("ply", "comment", "obj_info"):
            continue
        if toks[0] == "format":
            if len(toks) < 2 or toks[1] not in ("ascii", "binary_little_endian", "binary_big_endian"):
                raise format_error(path, f"line {ln_no}: unknown PLY format {line.strip()!r}")
            fmt = toks[1]
        elif toks[0] == "element":
            if len(toks) != 3 or not INT_RE.match(toks[2]) or int(toks[2]) < 0:
                raise format_error(path, f"line {ln_no}: malformed element line {line.strip()!r}")
            elements.append(_PlyElement(toks[1], int(toks[2]), [], ln_no))
        elif toks[0] == "property":
            if not elements:
                raise format_error(path, f"line {ln_no}: property before any element")
            if len(toks) == 5 and toks[1] == "list":
                if toks[2] not in _PLY_TYPES or toks[3] not in _PLY_TYPES:
                    raise format_error(path, f"line {ln_no}: unknown PLY type in {line.strip()!r}")
                elements[-1].props.append(_PlyProp(toks[4], _PLY_TYPES[toks[3]], _PLY_TYPES[toks[2]]))
            elif len(toks) == 3 and toks[1] in _PLY_TYPES:
                elements[-1].props.append(_PlyProp(toks[2], _PLY_TYPES[toks[1]]))
            else:
                raise format_error(path, f"line {ln_no}: malformed property line {line.strip()!r}")
        else:
            raise format_error(path, f"line {ln_no}: unexpected PLY header line {line.strip()!r}")
    if fmt is None:
        raise format_error(path, "PLY header has no 'format' line")
    return fmt, elements, m.end(), len(header) + 1


def _read_elements(path: Path, data: bytes) -> tuple[dict[str, dict[str, Any]], dict[str, np.ndarray]]:
    """Read every element of a PLY file.

    Returns
    -------
    values : dict
        ``values[element][property]``: an (count,) array for scalar properties, or for
        list properties a tuple ``(flat, sizes)`` of the concatenated items and the
        per-record lengths.
    lines : dict
        ``lines[element]``: (count,) 1-based line number of each record (ASCII only).
    """
    fmt, elements, offset, n_header = _parse_header(path, data)
    if fmt == "ascii":
        return _read_ascii(path, data[offset:], elements, n_header)
    bo = "<" if fmt == "binary_little_endian" else ">"
    values: dict[str, dict[str, Any]] = {}
    pos = offset
    for el in elements:
        values[el.name], pos = _read_binary_element(path, data, pos, el, bo)
    return values, {}


def _read_binary_element(path: Path, data: bytes, pos: int, el: _PlyElement, bo: str) -> tuple[dict[str, Any], int]:
    n = el.count
    if not any(p.count_dtype for p in el.props):
        dt = np.dtype([(f"p{i}", bo + p.dtype) for i, p in enumerate(el.props)])
        need = dt.itemsize * n
        if len(data) - pos < need:
            raise format_error(
                path, f"binary PLY data ends inside element '{el.name}' (needs {need} bytes, {len(data) - pos} left)"
            )
        arr = np.frombuffer(data, dtype=dt, count=n, offset=pos)
        return {p.name: arr[f"p{i}"] for i, p in enumerate(el.props)}, pos + need
    if n == 0:
        return {p.name: ((np.zeros(0), np.zeros(0, np.int64)) if p.count_dtype else np.zeros(0)) for p in el.props}, pos
    # Fast path: assume every record has the list lengths of the first record.
    fields: list[Any] = []
    q = pos
    for i, p in enumerate(el.props):
        if p.count_dtype:
            cdt = np.dtype(bo + p.count_dtype)
            if len(data) - q < cdt.itemsize:
                raise format_error(path, f"binary PLY data ends inside element '{el.name}'")
            c = int(np.frombuffer(data, dtype=cdt, count=1, offset=q)[0])
            fields += [(f"c{i}", cdt), (f"p{i}", bo + p.dtype, (c,))]
            q += cdt.itemsize + c * np.dtype(p.dtype).itemsize
        else:
            fields.append((f"p{i}", bo + p.dtype))
            q += np.dtype(p.dtype).itemsize
    dt = np.dtype(fields)
    if len(data) - pos >= dt.itemsize * n:
        arr = np.frombuffer(data, dtype=dt, count=n, offset=pos)
        ok = all(
            np.all(arr[f"c{i}"] == arr.dtype[f"p{i}"].shape[0]) for i, p in enumerate(el.props) if p.count_dtype
        )
        if ok:
            out: dict[str, Any] = {}
            for i, p in enumerate(el.props):
                if p.count_dtype:
                    c = arr.dtype[f"p{i}"].shape[0]
                    out[p.name] = (arr[f"p{i}"].reshape(-1), np.full(n, c, dtype=np.int64))
                else:
                    out[p.name] = arr[f"p{i}"]
            return out, pos + dt.itemsize * n
    # Slow path: variable-length lists, record by record.
    cols: dict[str, list] = {p.name: [] for p in el.props}
    sizes: dict[str, list[int]] = {p.name: [] for p in el.props if p.count_dtype}
    def take(dtype: str, count: int, r: int) -> np.ndarray:
        """The next ``count`` items of type ``dtype``, in record ``r``."""
        nonlocal pos
        dt = np.dtype(bo + dtype)
        if count < 0 or pos + count * dt.itemsize > len(data):
            raise format_error(path, f"binary PLY data ends in record {r} of element '{el.name}'")
        pos += count * dt.itemsize
        return np.frombuffer(data, dtype=dt, count=count, offset=pos - count * dt.itemsize)

    for r in range(n):
        for p in el.props:
            if p.count_dtype:
                c = int(take(p.count_dtype, 1, r)[0])
                cols[p.name].append(take(p.dtype, c, r))
                sizes[p.name].append(c)
            else:
                cols[p.name].append(take(p.dtype, 1, r)[0])
    out = {}
    for p in el.props:
        if p.count_dtype:
            out[p.name] = (np.concatenate(cols[p.name]), np.asarray(sizes[p.name], dtype=np.int64))
        else:
            out[p.name] = np.asarray(cols[p.name])
    return out, pos


def _read_ascii(
    path: Path, body: bytes, elements: list[_PlyElement], n_header: int
) -> tuple[dict[str, dict[str, Any]], dict[str, np.ndarray]]:
    lines = decode(body).splitlines()
    values: dict[str, dict[str, Any]] = {}
    line_nos: dict[str, np.ndarray] = {}
    pos = 0
    for el in elements:
        # skip blank lines between records
        rec: list[list[str]] = []
        rec_lines: list[int] = []
        while len(rec) < el.count and pos < len(lines):
            toks = lines[pos].split()
            pos += 1
            if toks:
                rec.append(toks)
                rec_lines.append(n_header + pos)
        if len(rec) < el.count:
            raise format_error(
                path,
                f"file ends after {len(rec)} of {el.count} '{el.name}' records (line {n_header + len(lines)})",
            )
        ln_a = np.asarray(rec_lines, dtype=np.int64)
        line_nos[el.name] = ln_a
        values[el.name] = _ascii_records(path, el, rec, ln_a)
    return values, line_nos


def _ascii_records(path: Path, el: _PlyElement, rec: list[list[str]], ln_a: np.ndarray) -> dict[str, Any]:
    n = len(rec)
    if not any(p.count_dtype for p in el.props):
        w = len(el.props)
        A = parse_floats(path, rec, ln_a, f"'{el.name}' record", w) if w else np.zeros((n, 0))
        extra = [i for i, r in enumerate(rec) if len(r) != w]
        if extra:
            i = extra[0]
            raise format_error(path, f"line {int(ln_a[i])}: '{el.name}' record has {len(rec[i])} values, expected {w}")
        return {p.name: A[:, i] for i, p in enumerate(el.props)}
    cols: dict[str, list] = {p.name: [] for p in el.props}
    sizes: dict[str, list[int]] = {p.name: [] for p in el.props if p.count_dtype}
    for r, toks in enumerate(rec):
        k = 0
        try:
            for p in el.props:
                if p.count_dtype:
                    c = int(toks[k])
                    if c < 0 or k + 1 + c > len(toks):
                        raise ValueError
                    cols[p.name].append(toks[k + 1 : k + 1 + c])
                    sizes[p.name].append(c)
                    k += 1 + c
                else:
                    cols[p.name].append(toks[k])
                    k += 1
            if k != len(toks):
                raise ValueError
        except (ValueError, IndexError):
            raise format_error(
                path, f"line {int(ln_a[r])}: malformed '{el.name}' record {r} ({' '.join(toks)[:80]!r})"
            ) from None
    out: dict[str, Any] = {}
    for p in el.props:
        if p.count_dtype:
            flat = [t for lst in cols[p.name] for t in lst]
            sz = np.asarray(sizes[p.name], dtype=np.int64)
            if p.dtype[0] in "iu":
                arr = parse_int_tokens(path, flat, np.repeat(ln_a, sz), f"'{el.name}' record")
            else:
                arr = parse_floats(path, [[t] for t in flat], np.repeat(ln_a, sz), f"'{el.name}' record", 1)[:, 0]
            out[p.name] = (arr, sz)
        else:
            out[p.name] = parse_floats(path, [[t] for t in cols[p.name]], ln_a, f"'{el.name}' record", 1)[:, 0]
    return out


def _mesh_parts(path: Path, values: dict[str, dict[str, Any]], line_nos: dict[str, np.ndarray]) -> tuple[Any, ...]:
    """Extract ``(V, idx, sizes, v_lines, f_lines, vertex_props)`` from parsed PLY elements."""
    if "vertex" not in values:
        raise format_error(path, "PLY file has no 'vertex' element")
    vert = values["vertex"]
    missing = [c for c in "xyz" if c not in vert]
    if missing:
        raise format_error(
            path, f"PLY 'vertex' element lacks the propert{'y' if len(missing) == 1 else 'ies'} {missing}"
        )
    if any(isinstance(vert[c], tuple) for c in "xyz"):
        raise format_error(path, "PLY vertex coordinates must be scalar properties")
    V = np.stack([np.asarray(vert[c], dtype=np.float64) for c in "xyz"], axis=1)
    face = values.get("face")
    if face is None or not face:
        raise format_error(path, "no faces (PLY file has no 'face' element)")
    key = "vertex_indices" if "vertex_indices" in face else "vertex_index" if "vertex_index" in face else None
    if key is None or not isinstance(face[key], tuple):
        raise format_error(path, "PLY 'face' element has no 'vertex_indices' list property")
    flat, sizes = face[key]
    if flat.dtype.kind == "f" and flat.size:
        raise format_error(path, "PLY face indices must be integers")
    idx = np.asarray(flat).astype(np.int64)
    props = {k: np.asarray(v) for k, v in vert.items() if k not in "xyz" and not isinstance(v, tuple)}
    return V, idx, sizes, line_nos.get("vertex"), line_nos.get("face"), props


# ----------------------------------------------------------------------------------------------------------------------
# Writing
# ----------------------------------------------------------------------------------------------------------------------


def write_field(fh: BinaryIO, field: FieldData) -> None:
    """Binary little-endian PLY: ``double`` ``x, y, z`` and the field; faces as ``list uchar int vertex_indices``."""
    n, m = field.V.shape[0], field.cells.shape[0]
    header = (
        "ply\n"
        "format binary_little_endian 1.0\n"
        "comment written by cvxgeodesic\n"
        f"comment mesh {re.sub(r'[^ -~]', '?', field.label)}\n"
        f"element vertex {n}\n"
        "property double x\nproperty double y\nproperty double z\n"
        f"property double {field.name}\n"
        f"element face {m}\n"
        "property list uchar int vertex_indices\n"
        "end_header\n"
    )
    fh.write(header.encode("ascii"))
    # float64 coordinates: float32 moves georeferenced coordinates (~5e6) by up to 0.25
    vert = np.empty(n, dtype=[("x", "<f8"), ("y", "<f8"), ("z", "<f8"), ("d", "<f8")])
    vert["x"], vert["y"], vert["z"] = field.V[:, 0], field.V[:, 1], field.V[:, 2]
    vert["d"] = field.d
    fh.write(vert.tobytes())
    face = np.empty(m, dtype=[("c", "u1"), ("i", "<i4", (3,))])
    face["c"] = 3
    face["i"] = field.cells
    fh.write(face.tobytes())
