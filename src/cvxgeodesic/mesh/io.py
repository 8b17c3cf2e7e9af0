"""Reading triangle meshes (OBJ, OFF, PLY, STL) and writing distance fields (PLY, NPY, CSV).

The readers are small, dependency-free and vectorized with numpy. Every problem
with a file is reported as a :class:`~cvxgeodesic.errors.MeshFormatError` whose
message names the file and, for text formats, the line.
"""

from __future__ import annotations

import os
import re
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._atomic import atomic_write
from ..errors import MeshError, MeshFormatError, MeshRepairWarning, ParameterError
from ..validation import as_vertex_field
from ..validation import check_output_path as _check_output_path
from .external import EXTERNAL_DISTANCE_EXTENSIONS, EXTERNAL_MESH_EXTENSIONS, read_external, write_external
from .trimesh import TriMesh

__all__ = [
    "as_trimesh", "check_output_path", "file_order_mesh", "load_distance_ply", "load_mesh", "save_distance",
    "MESH_EXTENSIONS", "DISTANCE_EXTENSIONS",
]

#: File extensions understood by :func:`load_mesh` (compared case-insensitively); the last five
#: through the optional packages trimesh (``.glb``, ``.gltf``, ``.3mf``) and meshio (``.vtk``, ``.vtu``).
MESH_EXTENSIONS = (".obj", ".off", ".ply", ".stl", *EXTERNAL_MESH_EXTENSIONS)
#: File extensions understood by :func:`save_distance` (compared case-insensitively); ``.vtu`` and
#: ``.vtk`` through the optional package meshio, ``.glb`` through trimesh.
DISTANCE_EXTENSIONS = (".ply", ".npy", ".csv", *EXTERNAL_DISTANCE_EXTENSIONS)


# ----------------------------------------------------------------------------------------------------------------------
# Raw polygon soup returned by the format readers
# ----------------------------------------------------------------------------------------------------------------------


@dataclass
class _Raw:
    """Polygon mesh as read from a file, before validation and welding.

    Attributes
    ----------
    V : (n, 3) float64 ndarray
        Vertex positions in file order.
    idx : (k,) int64 ndarray
        Concatenated 0-based vertex indices of all polygons (not yet range-checked).
    sizes : (p,) int64 ndarray
        Number of vertices of each polygon; ``sizes.sum() == k``.
    v_lines, f_lines : (n,) / (p,) int64 ndarray (or lazily computed equivalent) or None
        1-based line number of each vertex / polygon (text formats only).
    raw_idx : (k,) int64 ndarray or None
        The indices as written in the file (for messages), when they differ from ``idx``.
    """

    V: np.ndarray
    idx: np.ndarray
    sizes: np.ndarray
    v_lines: Any = None
    f_lines: Any = None
    raw_idx: np.ndarray | None = None


def _read_bytes(p: Path, what: str) -> bytes:
    """The whole file, or MeshFormatError when it is missing, a directory, unreadable or empty."""
    if not p.exists():
        raise _err(p, "no such file")
    if p.is_dir():
        raise _err(p, f"is a directory, not {what}")
    try:
        data = p.read_bytes()
    except OSError as exc:
        raise _err(p, f"cannot read file ({exc.strerror or exc})") from None
    if not data.strip():
        raise _err(p, "file is empty")
    return data


def _err(path: Path, msg: str) -> MeshFormatError:
    return MeshFormatError(f"{path}: {msg}")


def _at_line(lines: np.ndarray | None, i: int) -> str:
    return f" (line {int(lines[i])})" if lines is not None else ""


# ----------------------------------------------------------------------------------------------------------------------
# Public: load_mesh
# ----------------------------------------------------------------------------------------------------------------------


def load_mesh(path: str | os.PathLike) -> TriMesh:
    """Read a triangle mesh from an OBJ, OFF, PLY or STL file (glTF, GLB, 3MF, VTK, VTU with the ``io`` extra).

    The format is chosen from the extension (case-insensitive): ``.obj``, ``.off``,
    ``.ply`` (ASCII, binary little- or big-endian) or ``.stl`` (ASCII or binary), read by
    this module; ``.glb``, ``.gltf``, ``.3mf`` through trimesh and ``.vtk``, ``.vtu``
    through meshio, when installed (``pip install 'cvxgeodesic[io]'``), with the same
    welding and checks.

    Parameters
    ----------
    path : str or os.PathLike
        The file to read.

    Returns
    -------
    TriMesh
        The welded triangle mesh, named after the file's base name.
        ``mesh.vertex_map[i]`` is the 0-based index in the file of the (first)
        original vertex of vertex ``i``; for STL, whose vertices are the triangle
        corners, it is the corner number ``3 * triangle + corner``.
        ``mesh.file_index[j]`` is the mesh index of file vertex ``j`` (-1: in no face),
        ``mesh.n_file_vertices`` the file's vertex count, and ``mesh.notes`` one line per
        repair. The mesh's numbering differs from the file's when vertices were welded or
        dropped: :func:`~cvxgeodesic.mesh.fileorder.to_file_order` maps a field back.

    Raises
    ------
    MeshFormatError
        If the file does not exist, is a directory, has an unsupported extension,
        is empty or malformed (the message names the line for text formats), has a
        face index out of range (the message names the face and the index), a
        non-finite coordinate, or no faces.

    Warns
    -----
    MeshRepairWarning
        (a ``UserWarning``) When faces that became degenerate by welding (a repeated
        vertex) or exact duplicate faces (the same vertex set as an earlier face) are
        dropped, and when welding or dropping vertices makes the mesh's vertex count
        differ from the file's; the message says how many.

    Notes
    -----
    - OBJ: only ``v`` and ``f`` statements are used; face entries may be ``i``,
      ``i/t``, ``i//n`` or ``i/t/n`` and negative (relative) indices are resolved.
      Texture coordinates, normals, groups, materials, lines and points are ignored.
    - OFF: ``OFF`` and its ``C``/``N``/``ST``/``4`` variants (ASCII only); extra
      per-vertex values (colors, normals) and per-face colors are ignored.
    - PLY: the ``vertex`` element's ``x``, ``y``, ``z`` and the ``face`` element's
      ``vertex_indices`` (or ``vertex_index``) list; other elements are skipped.
    - Polygons with more than three vertices are fan-triangulated:
      ``(v0, v1, v2, v3, ...)`` becomes ``(v0, v1, v2), (v0, v2, v3), ...``.
    - Vertices with exactly identical positions are always welded (this repairs STL
      triangle soups and OBJ files split at texture seams); vertices referenced by
      no face are dropped. Vertices keep their file order.
    """
    p = Path(path)
    ext = p.suffix.lower()
    if ext not in MESH_EXTENSIONS:
        raise _err(
            p, f"unsupported mesh file extension {p.suffix!r}; supported: {', '.join(MESH_EXTENSIONS)} (any case)"
        )
    try:
        if ext in EXTERNAL_MESH_EXTENSIONS:
            _read_bytes(p, "a mesh file")  # the same messages for missing, directory and empty files
            raw = _Raw(*read_external(p))
        else:
            data = _read_bytes(p, "a mesh file")
            raw = {".obj": _read_obj, ".off": _read_off, ".ply": _read_ply_raw, ".stl": _read_stl}[ext](p, data)
        V, F, vertex_map, file_index, dropped, notes = _finish(p, raw)
        return TriMesh(V, F, vertex_map=vertex_map, file_index=file_index, dropped_vertices=dropped, notes=notes,
                       name=p.name)
    except MeshFormatError:
        raise
    except MeshError as exc:
        raise _err(p, str(exc)) from None
    except (ValueError, TypeError, IndexError, OverflowError, UnicodeDecodeError, MemoryError) as exc:
        raise _err(p, f"malformed {ext[1:].upper()} file ({type(exc).__name__}: {exc})") from None


def _finish(path: Path, raw: _Raw) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, list[str]]:
    """Validate, triangulate, weld and clean a raw polygon mesh.

    Returns ``(V, F, vertex_map, file_index, dropped_vertices, notes)``.
    """
    V = np.asarray(raw.V, dtype=np.float64).reshape(-1, 3)
    n = V.shape[0]
    idx, sizes = raw.idx, raw.sizes
    if sizes.size == 0:
        raise _err(path, "no faces" + (" and no vertices" if n == 0 else ""))
    if n == 0:
        raise _err(path, "no vertices")
    bad = ~np.isfinite(V).all(axis=1)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise _err(
            path,
            f"vertex {i}{_at_line(raw.v_lines, i)} has a non-finite coordinate {V[i].tolist()} "
            f"({int(bad.sum())} such vertices)",
        )
    small = sizes < 3
    if small.any():
        f = int(np.flatnonzero(small)[0])
        raise _err(path, f"face {f}{_at_line(raw.f_lines, f)} has {int(sizes[f])} vertices; a face needs at least 3")
    starts = np.cumsum(sizes) - sizes
    out = (idx < 0) | (idx >= n)
    if out.any():
        k = int(np.flatnonzero(out)[0])
        f = int(np.searchsorted(starts, k, side="right") - 1)
        shown = int(raw.raw_idx[k]) if raw.raw_idx is not None else int(idx[k])
        base = " (1-based)" if raw.raw_idx is not None else ""
        raise _err(
            path,
            f"face {f}{_at_line(raw.f_lines, f)} has vertex index {shown}{base} out of range; "
            f"the file has {n} vertices",
        )
    F = _fan_triangulate(idx, sizes, starts)

    # Weld vertices with exactly identical positions, keeping the first occurrence (file order).
    order = np.lexsort((V[:, 2], V[:, 1], V[:, 0]))
    Vs = V[order]
    new_group = np.empty(n, dtype=bool)
    new_group[0] = True
    np.any(Vs[1:] != Vs[:-1], axis=1, out=new_group[1:])
    group_sorted = np.cumsum(new_group) - 1
    group = np.empty(n, dtype=np.int64)
    group[order] = group_sorted
    rep = order[new_group]  # lexsort is stable: the smallest file index of each group
    F = group[F]  # faces in terms of group ids

    notes: list[str] = []

    # Drop faces made degenerate by welding.
    degenerate = (F[:, 0] == F[:, 1]) | (F[:, 1] == F[:, 2]) | (F[:, 0] == F[:, 2])
    n_deg = int(degenerate.sum())
    if n_deg:
        F = F[~degenerate]
        msg = (f"{path.name}: dropped {n_deg} degenerate face(s) with a repeated vertex after welding "
               "vertices with identical positions")
        notes.append(msg)
        warnings.warn(msg, MeshRepairWarning, stacklevel=3)
    # Drop exact duplicate faces (same vertex set), keeping the first.
    n_dup = 0
    if F.shape[0]:
        _, first = np.unique(np.sort(F, axis=1), axis=0, return_index=True)
        n_dup = F.shape[0] - first.size
        if n_dup:
            F = F[np.sort(first)]
            msg = f"{path.name}: dropped {n_dup} duplicate face(s) (same vertices as an earlier face)"
            notes.append(msg)
            warnings.warn(msg, MeshRepairWarning, stacklevel=3)
    if F.shape[0] == 0:
        raise _err(path, f"no faces left after dropping {n_deg} degenerate and {n_dup} duplicate face(s)")

    # Keep only referenced groups, ordered by their first file index.
    used = np.zeros(rep.size, dtype=bool)
    used[F.ravel()] = True
    kept = np.flatnonzero(used)
    kept = kept[np.argsort(rep[kept], kind="stable")]
    new_id = np.full(rep.size, -1, dtype=np.int64)
    new_id[kept] = np.arange(kept.size)
    vertex_map = rep[kept]
    file_index = new_id[group]  # mesh index of every file vertex; -1: dropped (in no face)

    n_welded = n - rep.size
    n_dropped = int(np.count_nonzero(file_index < 0))
    if n_welded or n_dropped:
        what = []
        if n_welded:
            what.append(f"welded {n_welded} vertices at the same position as an earlier one")
        if n_dropped:
            what.append(f"dropped {n_dropped} vertices in no face")
        changed = np.flatnonzero(file_index != np.arange(n))
        msg = (f"{path.name}: {n} vertices in the file, {kept.size} in the mesh ({'; '.join(what)}); mesh indices "
               f"differ from the file's from file vertex {int(changed[0])} on: cvxgeodesic.to_file_order(mesh, field) "
               "maps a field to the file's numbering")
        notes.append(msg)
        if path.suffix.lower() != ".stl":  # an STL is a triangle soup: welding its corners is always expected
            warnings.warn(msg, MeshRepairWarning, stacklevel=3)
    return V[vertex_map], new_id[F], vertex_map, file_index, V[file_index < 0], notes


def _fan_triangulate(idx: np.ndarray, sizes: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """Fan-triangulate polygons given as concatenated indices. Returns an (t, 3) int64 array."""
    if np.all(sizes == 3):
        return idx.reshape(-1, 3).astype(np.int64, copy=False)
    ntri = sizes - 2
    poly = np.repeat(np.arange(sizes.size), ntri)
    j = np.arange(poly.size) - np.repeat(np.cumsum(ntri) - ntri, ntri)
    s = starts[poly]
    return np.stack([idx[s], idx[s + j + 1], idx[s + j + 2]], axis=1).astype(np.int64, copy=False)


# ----------------------------------------------------------------------------------------------------------------------
# Helpers for text formats
# ----------------------------------------------------------------------------------------------------------------------


def _decode(data: bytes) -> str:
    # latin-1 never fails; every keyword and number of the text formats is ASCII.
    return data.decode("latin-1")


def _parse_floats(
    path: Path, rows: list[list[str]], lines: np.ndarray | _LazyLines, what: str, width: int = 3
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
            raise _err(path, f"line {int(lines[i])}: {what} needs {width} numbers, got {len(r)}")
        for t in r[:width]:
            try:
                float(t)
            except ValueError:
                raise _err(path, f"line {int(lines[i])}: {what} has a non-numeric value {t!r}") from None
    return np.array([r[:width] for r in rows], dtype=np.float64)


_INT_RE = re.compile(r"[+-]?\d+\Z")


def _parse_int_tokens(path: Path, toks: list[str], tok_lines: np.ndarray | _LazyLines, what: str) -> np.ndarray:
    """Parse a flat list of integer tokens into an int64 array; errors name the line."""
    try:
        return np.array(toks, dtype=np.int64) if toks else np.zeros(0, dtype=np.int64)
    except (ValueError, OverflowError):
        pass
    for k, t in enumerate(toks):
        if not _INT_RE.match(t):
            raise _err(path, f"line {int(tok_lines[k])}: {what} has a non-integer vertex index {t!r}")
        if abs(int(t)) > 2**62:
            raise _err(path, f"line {int(tok_lines[k])}: {what} has a vertex index {t} that is far too large")
    raise _err(path, f"cannot parse the {what} indices")  # pragma: no cover - unreachable in practice


# ----------------------------------------------------------------------------------------------------------------------
# OBJ
# ----------------------------------------------------------------------------------------------------------------------

_SLASH_RE = re.compile(r"/\S*")
# A 'v' / 'f' statement: the keyword alone or followed by whitespace (so 'vt', 'vn', 'fo' do not match).
_OBJ_V_RE = re.compile(r"^[ \t]*v(?![^ \t\n])([^\n]*)", re.M)
_OBJ_F_RE = re.compile(r"^[ \t]*f(?![^ \t\n])([^\n]*)", re.M)


class _LazyLines:
    """Sequence of 1-based line numbers, computed on first access (only messages and rare cases need them)."""

    def __init__(self, compute):
        self._compute = compute
        self._arr: np.ndarray | None = None

    @property
    def array(self) -> np.ndarray:
        if self._arr is None:
            self._arr = np.asarray(self._compute(), dtype=np.int64)
        return self._arr

    def __getitem__(self, i):
        return self.array[i]


def _match_lines(text: str, regex: re.Pattern) -> np.ndarray:
    """1-based line numbers of the starts of all matches of ``regex`` in ``text`` (lines end with '\\n')."""
    starts = np.fromiter((m.start() for m in regex.finditer(text)), dtype=np.int64)
    newlines = np.flatnonzero(np.frombuffer(text.encode("latin-1"), dtype=np.uint8) == 10)
    return np.searchsorted(newlines, starts, side="left") + 1


def _read_obj(path: Path, data: bytes) -> _Raw:
    text = _decode(data)
    if "\r" in text:
        text = text.replace("\r\n", "\n").replace("\r", "\n")
    v_body = _OBJ_V_RE.findall(text)
    f_body = _OBJ_F_RE.findall(text)
    if not v_body and not f_body:
        raise _err(path, "no 'v' or 'f' statements found (empty or not an OBJ file)")
    v_lines = _LazyLines(lambda: _match_lines(text, _OBJ_V_RE))
    f_lines = _LazyLines(lambda: _match_lines(text, _OBJ_F_RE))

    # Vertices: 'v x y z [w]' or 'v x y z r g b'; only x, y, z are used.
    v_toks = [b.split() for b in v_body]
    if all(len(t) == 3 for t in v_toks):
        try:
            V = np.array(" ".join(v_body).split(), dtype=np.float64).reshape(-1, 3)
        except ValueError:
            V = _parse_floats(path, v_toks, v_lines, "vertex ('v')", 3)
    else:
        V = _parse_floats(path, [t[:3] if len(t) > 3 else t for t in v_toks], v_lines, "vertex ('v')", 3)

    # Faces: strip the '/texture/normal' part of each entry, then split.
    if f_body:
        body = "\n".join(f_body)
        if "/" in body:
            f_body = _SLASH_RE.sub("", body).split("\n")
    sizes = np.fromiter((len(b.split()) for b in f_body), dtype=np.int64, count=len(f_body))
    toks = " ".join(f_body).split()
    tok_lines = _LazyLines(lambda: np.repeat(f_lines.array, sizes))
    raw_idx = _parse_int_tokens(path, toks, tok_lines, "face ('f')")
    zero = raw_idx == 0
    if zero.any():
        k = int(np.flatnonzero(zero)[0])
        raise _err(path, f"line {int(tok_lines[k])}: face vertex index 0 is invalid (OBJ indices start at 1)")
    neg = raw_idx < 0
    if neg.any():  # relative indices: -1 is the last vertex defined before the face
        v_pos = np.fromiter((m.start() for m in _OBJ_V_RE.finditer(text)), dtype=np.int64)
        f_pos = np.fromiter((m.start() for m in _OBJ_F_RE.finditer(text)), dtype=np.int64)
        nv_before = np.repeat(np.searchsorted(v_pos, f_pos), sizes)
        idx = np.where(neg, nv_before + raw_idx, raw_idx - 1)
    else:
        idx = raw_idx - 1
    return _Raw(V, idx, sizes, v_lines, f_lines, raw_idx)


# ----------------------------------------------------------------------------------------------------------------------
# OFF
# ----------------------------------------------------------------------------------------------------------------------

_OFF_HEADER_RE = re.compile(r"(ST)?(C)?(N)?(4)?(n)?OFF\Z")


def _read_off(path: Path, data: bytes) -> _Raw:
    text = _decode(data)
    if "#" in text:
        text = re.sub(r"#[^\r\n]*", "", text)
    all_lines = text.splitlines()
    # (line number, content) of non-blank lines
    nonblank = [(i, s) for i, s in enumerate(all_lines, 1) if s.strip()]
    if not nonblank:
        raise _err(path, "file is empty")
    pos = 0
    ln0, head = nonblank[0]
    head_toks = head.split()
    if not _OFF_HEADER_RE.match(head_toks[0]):
        raise _err(path, f"line {ln0}: expected an 'OFF' header, got {head_toks[0][:40]!r}")
    if "BINARY" in (t.upper() for t in head_toks[1:]):
        raise _err(path, f"line {ln0}: binary OFF files are not supported (convert to ASCII OFF or PLY)")
    if "4" in head_toks[0] or "n" in head_toks[0]:
        raise _err(path, f"line {ln0}: {head_toks[0]!r} (4-D or n-D OFF) is not supported")
    pos = 1
    count_toks = head_toks[1:]
    count_line = ln0
    if not count_toks:
        if pos >= len(nonblank):
            raise _err(path, f"line {ln0}: missing the 'vertices faces edges' counts line")
        count_line, s = nonblank[pos]
        count_toks = s.split()
        pos += 1
    if len(count_toks) < 2 or not all(_INT_RE.match(t) for t in count_toks[:3]):
        got = " ".join(count_toks)
        raise _err(path, f"line {count_line}: expected the counts 'vertices faces [edges]', got {got!r}")
    nv, nf = int(count_toks[0]), int(count_toks[1])
    if nv < 0 or nf < 0:
        raise _err(path, f"line {count_line}: negative vertex or face count")
    vblock = nonblank[pos : pos + nv]
    if len(vblock) < nv:
        raise _err(path, f"file ends after {len(vblock)} of {nv} vertices (line {len(all_lines)})")
    v_lines = np.fromiter((ln for ln, _ in vblock), dtype=np.int64, count=nv)
    V = _parse_floats(path, [s.split() for _, s in vblock], v_lines, "vertex", 3)
    pos += nv
    fblock = nonblank[pos : pos + nf]
    if len(fblock) < nf:
        raise _err(path, f"file ends after {len(fblock)} of {nf} faces (line {len(all_lines)})")
    f_lines = np.fromiter((ln for ln, _ in fblock), dtype=np.int64, count=nf)
    tok_lists = [s.split() for _, s in fblock]
    first = [t[0] for t in tok_lists]
    counts = _parse_int_tokens(path, first, f_lines, "face vertex count")
    rows_ok = counts >= 0
    if not rows_ok.all():
        f = int(np.flatnonzero(~rows_ok)[0])
        raise _err(path, f"line {int(f_lines[f])}: face {f} has a negative vertex count")
    lens = np.fromiter((len(t) for t in tok_lists), dtype=np.int64, count=nf)
    short = lens - 1 < counts
    if short.any():
        f = int(np.flatnonzero(short)[0])
        raise _err(
            path, f"line {int(f_lines[f])}: face {f} announces {int(counts[f])} vertices but lists {int(lens[f] - 1)}"
        )
    if nf and np.all(lens == counts + 1):
        toks = [x for t in tok_lists for x in t[1:]]
    else:
        toks = [x for t, c in zip(tok_lists, counts.tolist(), strict=True) for x in t[1 : 1 + c]]
    tok_lines = np.repeat(f_lines, counts)
    idx = _parse_int_tokens(path, toks, tok_lines, "face")
    return _Raw(V, idx, counts.astype(np.int64), v_lines, f_lines)


# ----------------------------------------------------------------------------------------------------------------------
# PLY
# ----------------------------------------------------------------------------------------------------------------------

_PLY_TYPES = {
    "char": "i1",
    "int8": "i1",
    "uchar": "u1",
    "uint8": "u1",
    "short": "i2",
    "int16": "i2",
    "ushort": "u2",
    "uint16": "u2",
    "int": "i4",
    "int32": "i4",
    "uint": "u4",
    "uint32": "u4",
    "float": "f4",
    "float32": "f4",
    "double": "f8",
    "float64": "f8",
}


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


def _parse_ply_header(path: Path, data: bytes) -> tuple[str, list[_PlyElement], int, int]:
    """Return ``(format, elements, body_offset, header_line_count)``."""
    if not data.startswith(b"ply"):
        raise _err(path, "line 1: not a PLY file (missing the 'ply' magic line)")
    m = re.search(rb"end_header[ \t]*(\r\n|\n|\r)", data)
    if m is None:
        raise _err(path, "PLY header has no 'end_header' line")
    header = data[: m.start()].decode("latin-1").splitlines()
    fmt = None
    elements: list[_PlyElement] = []
    for ln_no, line in enumerate(header, 1):
        toks = line.split()
        if not toks or toks[0] in ("ply", "comment", "obj_info"):
            continue
        if toks[0] == "format":
            if len(toks) < 2 or toks[1] not in ("ascii", "binary_little_endian", "binary_big_endian"):
                raise _err(path, f"line {ln_no}: unknown PLY format {line.strip()!r}")
            fmt = toks[1]
        elif toks[0] == "element":
            if len(toks) != 3 or not _INT_RE.match(toks[2]) or int(toks[2]) < 0:
                raise _err(path, f"line {ln_no}: malformed element line {line.strip()!r}")
            elements.append(_PlyElement(toks[1], int(toks[2]), [], ln_no))
        elif toks[0] == "property":
            if not elements:
                raise _err(path, f"line {ln_no}: property before any element")
            if len(toks) == 5 and toks[1] == "list":
                if toks[2] not in _PLY_TYPES or toks[3] not in _PLY_TYPES:
                    raise _err(path, f"line {ln_no}: unknown PLY type in {line.strip()!r}")
                elements[-1].props.append(_PlyProp(toks[4], _PLY_TYPES[toks[3]], _PLY_TYPES[toks[2]]))
            elif len(toks) == 3 and toks[1] in _PLY_TYPES:
                elements[-1].props.append(_PlyProp(toks[2], _PLY_TYPES[toks[1]]))
            else:
                raise _err(path, f"line {ln_no}: malformed property line {line.strip()!r}")
        else:
            raise _err(path, f"line {ln_no}: unexpected PLY header line {line.strip()!r}")
    if fmt is None:
        raise _err(path, "PLY header has no 'format' line")
    return fmt, elements, m.end(), len(header) + 1


def _read_ply_elements(path: Path, data: bytes) -> tuple[dict[str, dict[str, object]], dict[str, np.ndarray]]:
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
    fmt, elements, offset, n_header = _parse_ply_header(path, data)
    if fmt == "ascii":
        return _read_ply_ascii(path, data[offset:], elements, n_header)
    bo = "<" if fmt == "binary_little_endian" else ">"
    values: dict[str, dict[str, object]] = {}
    pos = offset
    for el in elements:
        values[el.name], pos = _read_ply_binary_element(path, data, pos, el, bo)
    return values, {}


def _read_ply_binary_element(path: Path, data: bytes, pos: int, el: _PlyElement, bo: str):
    n = el.count
    if not any(p.count_dtype for p in el.props):
        dt = np.dtype([(f"p{i}", bo + p.dtype) for i, p in enumerate(el.props)])
        need = dt.itemsize * n
        if len(data) - pos < need:
            raise _err(
                path, f"binary PLY data ends inside element '{el.name}' (needs {need} bytes, {len(data) - pos} left)"
            )
        arr = np.frombuffer(data, dtype=dt, count=n, offset=pos)
        return {p.name: arr[f"p{i}"] for i, p in enumerate(el.props)}, pos + need
    if n == 0:
        return {p.name: ((np.zeros(0), np.zeros(0, np.int64)) if p.count_dtype else np.zeros(0)) for p in el.props}, pos
    # Fast path: assume every record has the list lengths of the first record.
    fields = []
    q = pos
    for i, p in enumerate(el.props):
        if p.count_dtype:
            cdt = np.dtype(bo + p.count_dtype)
            if len(data) - q < cdt.itemsize:
                raise _err(path, f"binary PLY data ends inside element '{el.name}'")
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
            out: dict[str, object] = {}
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
    for r in range(n):
        for p in el.props:
            if p.count_dtype:
                cdt = np.dtype(bo + p.count_dtype)
                if pos + cdt.itemsize > len(data):
                    raise _err(path, f"binary PLY data ends in record {r} of element '{el.name}'")
                c = int(np.frombuffer(data, dtype=cdt, count=1, offset=pos)[0])
                pos += cdt.itemsize
                idt = np.dtype(bo + p.dtype)
                if c < 0 or pos + c * idt.itemsize > len(data):
                    raise _err(path, f"binary PLY data ends in record {r} of element '{el.name}'")
                cols[p.name].append(np.frombuffer(data, dtype=idt, count=c, offset=pos))
                sizes[p.name].append(c)
                pos += c * idt.itemsize
            else:
                idt = np.dtype(bo + p.dtype)
                if pos + idt.itemsize > len(data):
                    raise _err(path, f"binary PLY data ends in record {r} of element '{el.name}'")
                cols[p.name].append(np.frombuffer(data, dtype=idt, count=1, offset=pos)[0])
                pos += idt.itemsize
    out = {}
    for p in el.props:
        if p.count_dtype:
            out[p.name] = (np.concatenate(cols[p.name]), np.asarray(sizes[p.name], dtype=np.int64))
        else:
            out[p.name] = np.asarray(cols[p.name])
    return out, pos


def _read_ply_ascii(path: Path, body: bytes, elements: list[_PlyElement], n_header: int):
    lines = _decode(body).splitlines()
    values: dict[str, dict[str, object]] = {}
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
            raise _err(
                path,
                f"file ends after {len(rec)} of {el.count} '{el.name}' records (line {n_header + len(lines)})",
            )
        ln_a = np.asarray(rec_lines, dtype=np.int64)
        line_nos[el.name] = ln_a
        values[el.name] = _ply_ascii_records(path, el, rec, ln_a)
    return values, line_nos


def _ply_ascii_records(path: Path, el: _PlyElement, rec: list[list[str]], ln_a: np.ndarray) -> dict[str, object]:
    n = len(rec)
    if not any(p.count_dtype for p in el.props):
        w = len(el.props)
        A = _parse_floats(path, rec, ln_a, f"'{el.name}' record", w) if w else np.zeros((n, 0))
        extra = [i for i, r in enumerate(rec) if len(r) != w]
        if extra:
            i = extra[0]
            raise _err(path, f"line {int(ln_a[i])}: '{el.name}' record has {len(rec[i])} values, expected {w}")
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
            raise _err(
                path, f"line {int(ln_a[r])}: malformed '{el.name}' record {r} ({' '.join(toks)[:80]!r})"
            ) from None
    out: dict[str, object] = {}
    for p in el.props:
        if p.count_dtype:
            flat = [t for lst in cols[p.name] for t in lst]
            sz = np.asarray(sizes[p.name], dtype=np.int64)
            if p.dtype[0] in "iu":
                arr = _parse_int_tokens(path, flat, np.repeat(ln_a, sz), f"'{el.name}' record")
            else:
                arr = _parse_floats(path, [[t] for t in flat], np.repeat(ln_a, sz), f"'{el.name}' record", 1)[:, 0]
            out[p.name] = (arr, sz)
        else:
            out[p.name] = _parse_floats(path, [[t] for t in cols[p.name]], ln_a, f"'{el.name}' record", 1)[:, 0]
    return out


def _ply_mesh_parts(path: Path, values, line_nos):
    """Extract ``(V, idx, sizes, v_lines, f_lines, vertex_props)`` from parsed PLY elements."""
    if "vertex" not in values:
        raise _err(path, "PLY file has no 'vertex' element")
    vert = values["vertex"]
    missing = [c for c in "xyz" if c not in vert]
    if missing:
        raise _err(path, f"PLY 'vertex' element lacks the propert{'y' if len(missing) == 1 else 'ies'} {missing}")
    if any(isinstance(vert[c], tuple) for c in "xyz"):
        raise _err(path, "PLY vertex coordinates must be scalar properties")
    V = np.stack([np.asarray(vert[c], dtype=np.float64) for c in "xyz"], axis=1)
    face = values.get("face")
    if face is None or not face:
        raise _err(path, "no faces (PLY file has no 'face' element)")
    key = "vertex_indices" if "vertex_indices" in face else "vertex_index" if "vertex_index" in face else None
    if key is None or not isinstance(face[key], tuple):
        raise _err(path, "PLY 'face' element has no 'vertex_indices' list property")
    flat, sizes = face[key]
    if flat.dtype.kind == "f" and flat.size:
        raise _err(path, "PLY face indices must be integers")
    idx = np.asarray(flat).astype(np.int64)
    props = {k: np.asarray(v) for k, v in vert.items() if k not in "xyz" and not isinstance(v, tuple)}
    return V, idx, sizes, line_nos.get("vertex"), line_nos.get("face"), props


def _read_ply_raw(path: Path, data: bytes) -> _Raw:
    values, line_nos = _read_ply_elements(path, data)
    V, idx, sizes, v_lines, f_lines, _ = _ply_mesh_parts(path, values, line_nos)
    return _Raw(V, idx, sizes, v_lines, f_lines)


# ----------------------------------------------------------------------------------------------------------------------
# STL
# ----------------------------------------------------------------------------------------------------------------------

_STL_DTYPE = np.dtype([("normal", "<f4", (3,)), ("v", "<f4", (3, 3)), ("attr", "<u2")])


def _read_stl(path: Path, data: bytes) -> _Raw:
    n_bin = int.from_bytes(data[80:84], "little") if len(data) >= 84 else -1
    binary_size = 84 + 50 * n_bin if n_bin >= 0 else -1
    looks_ascii = data.lstrip()[:5].lower() == b"solid" and b"\0" not in data[:1024]
    if len(data) == binary_size or (not looks_ascii and 0 <= binary_size < len(data)):
        if len(data) > binary_size:
            warnings.warn(
                f"{path.name}: ignoring {len(data) - binary_size} trailing bytes after the binary STL data",
                UserWarning,
                stacklevel=3,
            )
        tri = np.frombuffer(data, dtype=_STL_DTYPE, count=n_bin, offset=84)
        V = tri["v"].reshape(-1, 3).astype(np.float64)
        return _Raw(V, np.arange(V.shape[0], dtype=np.int64), np.full(n_bin, 3, dtype=np.int64))
    if looks_ascii:
        return _read_stl_ascii(path, data)
    if len(data) < 84:
        raise _err(path, f"not an ASCII STL and too short ({len(data)} bytes) for a binary STL (84-byte header)")
    raise _err(
        path,
        f"binary STL is truncated: the header announces {n_bin} triangles ({binary_size} bytes) "
        f"but the file has {len(data)} bytes",
    )


def _read_stl_ascii(path: Path, data: bytes) -> _Raw:
    lines = _decode(data).splitlines()
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
                raise _err(path, f"line {ln_no}: 'vertex' outside an 'outer loop'")
            v_rows.append(toks[1:])
            v_lines.append(ln_no)
            count += 1
        elif key == "outer":
            if in_loop:
                raise _err(path, f"line {ln_no}: 'outer loop' inside another loop (missing 'endloop')")
            in_loop, count = True, 0
            f_lines.append(ln_no)
        elif key == "endloop":
            if not in_loop:
                raise _err(path, f"line {ln_no}: 'endloop' without 'outer loop'")
            if count < 3:
                raise _err(path, f"line {ln_no}: facet has {count} vertices; a facet needs 3")
            in_loop = False
            sizes.append(count)
        elif key not in ("solid", "endsolid", "facet", "endfacet"):
            raise _err(path, f"line {ln_no}: unexpected ASCII STL keyword {toks[0][:40]!r}")
    if in_loop:
        raise _err(path, f"line {len(lines)}: file ends inside a facet (missing 'endloop')")
    v_lines_a = np.asarray(v_lines, dtype=np.int64)
    bad = [i for i, r in enumerate(v_rows) if len(r) != 3]
    if bad:
        i = bad[0]
        raise _err(path, f"line {v_lines[i]}: 'vertex' needs 3 numbers, got {len(v_rows[i])}")
    V = _parse_floats(path, v_rows, v_lines_a, "'vertex'", 3)
    return _Raw(
        V,
        np.arange(V.shape[0], dtype=np.int64),
        np.asarray(sizes, dtype=np.int64),
        v_lines_a,
        np.asarray(f_lines, dtype=np.int64),
    )


# ----------------------------------------------------------------------------------------------------------------------
# Writing distance fields
# ----------------------------------------------------------------------------------------------------------------------

_NAME_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_.\-]*\Z")


def save_distance(path: str | os.PathLike, mesh: Any, distance: ArrayLike, *, name: str = "distance",
                  file_order: bool = False) -> Path:
    """Write a per-vertex distance field, atomically.

    The format follows the extension (case-insensitive):

    - ``.ply``: binary little-endian PLY; vertices with ``double`` ``x, y, z`` and a
      ``double`` property called ``name``; faces as ``property list uchar int
      vertex_indices``. Read it back with :func:`load_distance_ply`; open3d's tensor
      reader (``o3d.t.io.read_triangle_mesh``) and meshio (``point_data[name]``) read the
      field by name. trimesh (5.2) keeps custom PLY properties only in
      ``mesh.metadata["_ply_raw"]["vertex"]["data"][name]``, never in ``vertex_attributes``
      (it does not read them back from its own PLY export either): write ``.glb`` for trimesh.
    - ``.npy``: the (n,) float64 array (``numpy.save``).
    - ``.csv``: header ``vertex,file_vertex,x,y,z,<name>``, one row per vertex;
      ``file_vertex`` is ``mesh.vertex_map``; infinite values are written as ``inf``.
    - ``.vtu`` / ``.vtk`` (needs meshio, ``pip install 'cvxgeodesic[io]'``): VTK
      unstructured grid with the field as point data ``name``, for ParaView.
    - ``.glb`` (needs trimesh, ``pip install 'cvxgeodesic[io]'``): binary glTF with the field
      as the custom vertex attribute ``"_" + name.upper()`` (``_DISTANCE``), which
      ``trimesh.load`` puts in ``vertex_attributes``; float32 (glTF has no float64), and
      ``inf`` is written as -1 (the format's JSON header cannot hold infinity).

    The data is written to a temporary file in the target directory which then
    replaces ``path`` (``os.replace``); if anything fails, the temporary file is
    removed and ``path`` is left as it was.

    Parameters
    ----------
    path : str or os.PathLike
        Output file; its directory must exist.
    mesh : TriMesh or tuple (V, F)
        The mesh the field lives on, with ``n`` vertices.
    distance : (n,) array_like of float
        One value per vertex (``inf`` allowed, e.g. for unreachable vertices).
    name : str, optional
        Name of the PLY property / CSV column (letters, digits, ``_``, ``.``, ``-``;
        not ``x``, ``y``, ``z``, ``vertex`` or ``file_vertex``).
    file_order : bool, default False
        Write the file's vertices in the numbering of the file ``mesh`` was read from
        (``mesh.n_file_vertices`` rows; :func:`~cvxgeodesic.mesh.fileorder.to_file_order`:
        welded duplicates share a value, vertices in no face get ``inf``), so the
        output joins the input file by vertex index. In the CSV, ``vertex`` is then
        the mesh index (-1 for dropped vertices). The command line always does this.

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    ParameterError
        If the extension is unsupported, ``distance`` does not have shape (n,),
        ``name`` is invalid, or the parent directory does not exist.
    OSError
        If writing fails (e.g. permission denied).
    """
    p = check_output_path(path)
    ext = p.suffix.lower()
    mesh = as_trimesh(mesh)
    n = mesh.n_vertices
    d = as_vertex_field(distance, "distance", n)
    if not isinstance(name, str) or not _NAME_RE.match(name) or name in ("x", "y", "z", "vertex", "file_vertex"):
        raise ParameterError(
            f"invalid field name {name!r}: use letters, digits, '_', '.', '-' (not x, y, z, vertex, file_vertex)"
        )
    if file_order:
        idx = mesh.file_index
        vertex = np.where(idx >= 0, idx, -1)
        d_file = np.full(idx.size, np.inf)  # file vertices in no face: unreachable, as cg.to_file_order fills them
        d_file[idx >= 0] = d[idx[idx >= 0]]
        d, mesh = d_file, file_order_mesh(mesh)
    else:
        vertex = np.arange(n)
    out_mesh = mesh
    if ext in EXTERNAL_DISTANCE_EXTENSIONS:
        atomic_write(p, lambda fh: write_external(fh, out_mesh.V, out_mesh.F, d, name, ext))
    elif ext == ".csv":
        atomic_write(p, lambda fh: _write_csv(fh, out_mesh, d, name, vertex))
    else:
        writer = {".ply": _write_ply, ".npy": _write_npy}[ext]
        atomic_write(p, lambda fh: writer(fh, out_mesh, d, name))
    return p


def check_output_path(path: str | os.PathLike, extensions: tuple[str, ...] = DISTANCE_EXTENSIONS) -> Path:
    """:func:`cvxgeodesic.validation.check_output_path` with the distance-file extensions as the default."""
    return _check_output_path(path, extensions)


def _write_ply(fh, mesh: TriMesh, d: np.ndarray, name: str) -> None:
    n, m = mesh.n_vertices, mesh.n_faces
    header = (
        "ply\n"
        "format binary_little_endian 1.0\n"
        "comment written by cvxgeodesic\n"
        f"comment mesh {re.sub(r'[^ -~]', '?', mesh.name)}\n"
        f"element vertex {n}\n"
        "property double x\nproperty double y\nproperty double z\n"
        f"property double {name}\n"
        f"element face {m}\n"
        "property list uchar int vertex_indices\n"
        "end_header\n"
    )
    fh.write(header.encode("ascii"))
    # float64 coordinates: float32 moves georeferenced coordinates (~5e6) by up to 0.25
    vert = np.empty(n, dtype=[("x", "<f8"), ("y", "<f8"), ("z", "<f8"), ("d", "<f8")])
    vert["x"], vert["y"], vert["z"] = mesh.V[:, 0], mesh.V[:, 1], mesh.V[:, 2]
    vert["d"] = d
    fh.write(vert.tobytes())
    face = np.empty(m, dtype=[("c", "u1"), ("i", "<i4", (3,))])
    face["c"] = 3
    face["i"] = mesh.F
    fh.write(face.tobytes())


def _write_npy(fh, mesh: TriMesh, d: np.ndarray, name: str) -> None:
    np.save(fh, d, allow_pickle=False)


def _write_csv(fh, mesh: TriMesh, d: np.ndarray, name: str, vertex: np.ndarray) -> None:
    fh.write(f"vertex,file_vertex,x,y,z,{name}\n".encode("ascii"))
    V = mesh.V.tolist()
    # repr(float) round-trips exactly and writes inf / -inf / nan as such
    body = "".join(
        f"{i},{j},{x!r},{y!r},{z!r},{v!r}\n"
        for i, j, (x, y, z), v in zip(vertex.tolist(), mesh.vertex_map.tolist(), V, d.tolist(), strict=True)
    )
    fh.write(body.encode("ascii"))


def load_distance_ply(path: str | os.PathLike) -> tuple[TriMesh, dict[str, np.ndarray]]:
    """Read a PLY file written by :func:`save_distance`, without welding.

    Parameters
    ----------
    path : str or os.PathLike
        A PLY file (any PLY with triangle faces works).

    Returns
    -------
    mesh : TriMesh
        The mesh exactly as stored (vertex order kept, no welding; coordinates are
        the file's: float64 for files from :func:`save_distance`).
    fields : dict of str to (n,) ndarray
        Every scalar per-vertex property other than ``x``, ``y``, ``z``, as float64.

    Raises
    ------
    MeshFormatError
        If the file is missing or malformed, or has non-triangle faces.
    """
    p = Path(path)
    data = _read_bytes(p, "a PLY file")
    try:
        values, line_nos = _read_ply_elements(p, data)
        V, idx, sizes, _, _, props = _ply_mesh_parts(p, values, line_nos)
        if not np.all(sizes == 3):
            raise _err(p, "faces must all be triangles")
        mesh = TriMesh(V, idx.reshape(-1, 3), name=p.name)
    except MeshFormatError:
        raise
    except MeshError as exc:
        raise _err(p, str(exc)) from None
    except (ValueError, TypeError, IndexError, OverflowError, UnicodeDecodeError, MemoryError) as exc:
        raise _err(p, f"malformed PLY file ({type(exc).__name__}: {exc})") from None
    return mesh, {k: np.asarray(v, dtype=np.float64) for k, v in props.items()}


def as_trimesh(mesh: Any, name: str = "mesh") -> TriMesh:
    """Return ``mesh`` as a :class:`TriMesh`, accepting the meshes other libraries use.

    Accepted, by duck typing (none of these libraries is imported or required):

    - a :class:`TriMesh` (returned as is);
    - a ``(V, F)`` tuple or list of arrays;
    - a ``str`` or :class:`os.PathLike`: read with :func:`~cvxgeodesic.mesh.io.load_mesh`;
    - ``trimesh.Trimesh`` (anything with ``.vertices`` and ``.faces``);
    - open3d's ``TriangleMesh`` (``.vertices`` and ``.triangles``, converted with ``np.asarray``);
    - ``meshio.Mesh`` (``.points`` and ``.cells_dict["triangle"]``; other cell types are ignored).

    The vertex order of the object is kept (no welding): indices mean the same in both.

    Parameters
    ----------
    mesh : object
        One of the above.
    name : str
        Label for messages (a file's base name for paths; the object's ``name``
        attribute, if it is a non-empty string, for the others).

    Returns
    -------
    TriMesh

    Raises
    ------
    TypeError
        If ``mesh`` is none of these.
    MeshError
        If the arrays are invalid, or a ``meshio.Mesh`` has no triangle cells.
    """
    if isinstance(mesh, TriMesh):
        return mesh
    if isinstance(mesh, str | os.PathLike):
        return load_mesh(mesh)
    if isinstance(mesh, tuple | list) and len(mesh) == 2:
        return TriMesh(mesh[0], mesh[1], name=name)
    label = getattr(mesh, "name", None)
    label = label if isinstance(label, str) and label else name
    if hasattr(mesh, "vertices") and hasattr(mesh, "faces"):  # trimesh.Trimesh
        return TriMesh(np.asarray(mesh.vertices), np.asarray(mesh.faces), name=label)
    if hasattr(mesh, "vertices") and hasattr(mesh, "triangles"):  # open3d.geometry.TriangleMesh
        return TriMesh(np.asarray(mesh.vertices), np.asarray(mesh.triangles), name=label)
    if hasattr(mesh, "points") and hasattr(mesh, "cells_dict"):  # meshio.Mesh
        cells = mesh.cells_dict
        if "triangle" not in cells:
            raise MeshError(f"{label}: the meshio.Mesh has no 'triangle' cells (cell types: {', '.join(cells)})")
        return TriMesh(np.asarray(mesh.points)[:, :3], np.asarray(cells["triangle"]), name=label)
    raise TypeError(
        "mesh must be a TriMesh, a (V, F) tuple, a file path, or a trimesh.Trimesh / open3d TriangleMesh / "
        f"meshio.Mesh, got {type(mesh).__name__}"
    )


def file_order_mesh(mesh: TriMesh) -> TriMesh:
    """The mesh with the file's vertices, numbering and vertex count (for writing files).

    Welded duplicates get their mesh vertex's position, dropped vertices their file position;
    faces use the first file vertex of each welded group.

    Parameters
    ----------
    mesh : TriMesh

    Returns
    -------
    TriMesh
        ``n_file_vertices`` vertices (``mesh`` itself when the numberings agree).
    """
    idx = mesh.file_index
    if idx.size == mesh.n_vertices and np.array_equal(idx, np.arange(idx.size)):
        return mesh
    keep = idx >= 0
    V = np.empty((idx.size, 3))
    V[keep] = mesh.V[idx[keep]]
    V[~keep] = mesh.dropped_vertices
    if not np.all(np.isfinite(V[~keep])):  # positions unknown (file_index given without them): put them at the origin
        V[~keep] = 0.0
    return TriMesh(V, mesh.vertex_map[mesh.F], name=mesh.name)
