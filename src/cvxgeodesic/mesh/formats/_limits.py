"""Bounds on what a file's header may make a reader allocate, checked before meshio reads the file.

The built-in readers (OBJ, OFF, PLY, STL) never trust a count: they slice the records the file holds and stop
when a count runs past them. meshio (VTK, VTU, Gmsh, Medit) takes header counts as given, and a VTU's
compressed arrays inflate to whatever they hold: a 0.5 MB ``.vtu`` made meshio use 500 MB before it failed on
a count that did not match. So, before meshio opens such a file, :func:`check_limits` reads its header cheaply
(a memory map and a few regular expressions) and refuses, with a MeshFormatError naming the file and the count:

- a count no file of its size could hold: ``count × (the fewest bytes one item takes) > file size × ratio``,
  where an item takes at least 3 bytes for a point (one per coordinate) and 1 byte for anything else (a cell,
  a connectivity entry, a value), and ``ratio`` is 1 for uncompressed files and :data:`MAX_COMPRESSION` for
  compressed VTU files (:mod:`._bounds`). What meshio makes without data in the file counts as compressed: a legacy VTK
  structured grid's points (``DIMENSIONS``), and Gmsh 4's table indexed by node tag (8 bytes a tag, up to
  the largest tag the ``$Nodes`` header names);
- in a compressed VTU, an array that inflates to more than its counts allow (:mod:`._vtu_limits`).

The rule is generous on purpose: a genuine file always passes, whatever its content. VTU (XML) data is
decompressed by this check once more, block by block, in constant memory; the other formats cost a scan of
the file for their section keywords.
"""

from __future__ import annotations

import mmap
import re
from collections.abc import Iterator
from contextlib import contextmanager
from functools import lru_cache
from pathlib import Path

from ._bounds import MAX_COMPRESSION, POINT_BYTES, Count, FileBytes, check_counts
from ._vtu_limits import check_vtu

__all__ = ["check_limits"]

def check_limits(path: Path) -> None:
    """Check the header counts of a file meshio is about to read (formats without counts: nothing to check).

    A file already checked and unchanged (same size, time and inode) is not checked again: a mesh file is often
    read again for its point data (``load_vertex_property``, ``load_distance``).

    Raises
    ------
    MeshFormatError
        A count or an array past the bounds of the module's docstring.
    """
    st = path.stat()
    _check_cached(str(path.resolve()), st.st_size, st.st_mtime_ns, st.st_ino, path)


@lru_cache(maxsize=32)
def _check_cached(resolved: str, size: int, mtime_ns: int, ino: int, path: Path) -> None:
    check = _CHECKS.get(path.suffix.lower())
    if check is None or size == 0:
        return
    with _mapped(path) as data:
        check(path, data)


@contextmanager
def _mapped(path: Path) -> Iterator[FileBytes]:
    """The file's bytes, mapped (a scan then costs no memory of the file's size), else read."""
    with path.open("rb") as fh:
        try:
            data = mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ)
        except (OSError, ValueError):  # a file system without mmap
            yield fh.read()
            return
        try:
            yield data
        finally:
            try:
                data.close()
            except BufferError:  # a match in the traceback of an error still points into it: unmapped when freed
                pass


# ----------------------------------------------------------------------------------------------------------------------
# legacy VTK: every section keyword is on a line of its own, its counts in ASCII even in BINARY files
# ----------------------------------------------------------------------------------------------------------------------
_VTK_SECTION = re.compile(rb"^[ \t]*(POINTS|CELLS|CELL_TYPES|POINT_DATA|CELL_DATA|POLYGONS|LINES|VERTICES|"
                          rb"TRIANGLE_STRIPS|LOOKUP_TABLE|DIMENSIONS)[ \t]+([^\r\n]*)", re.M)
# a FIELD array's line: name, components, tuples, type
_VTK_FIELD_ARRAY = re.compile(rb"^[ \t]*\S+[ \t]+(\d+)[ \t]+(\d+)[ \t]+(?:bit|unsigned_char|char|unsigned_short|short|"
                              rb"unsigned_int|int|unsigned_long|long|float|double|vtkIdType|vtktypeint64|"
                              rb"vtktypeuint64)[ \t]*\r?$", re.M)


def _ints(text: bytes) -> list[int]:
    return [int(t) for t in re.findall(rb"\d+", text)]


def _vtk_counts(data: FileBytes) -> Iterator[Count]:
    for m in _VTK_SECTION.finditer(data):
        key, numbers = m.group(1).decode(), _ints(m.group(2))
        if not numbers:
            continue
        if key == "POINTS":
            yield Count("points (POINTS)", numbers[0], POINT_BYTES)
        elif key == "DIMENSIONS" and len(numbers) >= 3:
            # a structured grid's points are implicit (meshio makes them all): held as if compressed
            yield Count("grid points (DIMENSIONS)", numbers[0] * numbers[1] * numbers[2], POINT_BYTES, MAX_COMPRESSION)
        elif key != "LOOKUP_TABLE" or len(m.group(2).split()) >= 2:  # "LOOKUP_TABLE name size"; not "... default"
            yield Count(f"entries ({key})", numbers[-1])  # CELLS n size: size; POINT_DATA n: n
    for m in _VTK_FIELD_ARRAY.finditer(data):
        yield Count("field values (FIELD)", int(m.group(1)) * int(m.group(2)))


def _check_vtk(path: Path, data: FileBytes) -> None:
    if data[:200].lstrip().startswith(b"<"):  # a .vtk holding XML: meshio reads it as VTU
        check_vtu(path, data)
        return
    check_counts(path, len(data), _vtk_counts(data))


# ----------------------------------------------------------------------------------------------------------------------
# Gmsh: $Nodes and $Elements start with their counts (ASCII; size_t values in binary MSH 4)
# ----------------------------------------------------------------------------------------------------------------------
def _section_head(data: FileBytes, name: bytes, items: int, size_t: int) -> list[int]:
    """The counts that start section ``$<name>``: a line of ASCII numbers, or ``items`` binary size_t values."""
    m = re.search(rb"^\$" + name + rb"\r?\n", data, re.M)
    if m is None:
        return []
    start = m.end()
    if items:
        raw = data[start:start + items * size_t]
        return [int.from_bytes(raw[i:i + size_t], "little") for i in range(0, len(raw) - size_t + 1, size_t)]
    end = data.find(b"\n", start)
    return _ints(data[start:end if end >= 0 else len(data)])


def _check_msh(path: Path, data: FileBytes) -> None:
    fmt = re.search(rb"\$MeshFormat\s+([\d.]+)\s+(\d+)\s+(\d+)", data[:4096])
    if fmt is None:
        return  # not Gmsh's header: meshio says so
    version, binary, size_t = float(fmt.group(1)), fmt.group(2) == b"1", int(fmt.group(3))
    # MSH 4.1 starts $Nodes and $Elements with 4 numbers (binary: size_t), 4.0 with 2, MSH 2 with 1 (always ASCII)
    items = (4 if version >= 4.1 else 2) if version >= 4 and binary else 0
    nodes = _section_head(data, b"Nodes", items, size_t)
    elements = _section_head(data, b"Elements", items, size_t)
    counts = []
    if version >= 4:  # numEntityBlocks numNodes minNodeTag maxNodeTag
        if len(nodes) >= 2:
            counts += [Count("node blocks ($Nodes)", nodes[0]), Count("nodes ($Nodes)", nodes[1], POINT_BYTES)]
        if len(nodes) >= 4 and version >= 4.1:  # meshio makes a table indexed by tag, 8 bytes a tag
            counts.append(Count("node tags ($Nodes: the largest tag)", nodes[3], 8, MAX_COMPRESSION))
        if len(elements) >= 2:
            counts += [Count("element blocks ($Elements)", elements[0]), Count("elements ($Elements)", elements[1])]
    else:
        counts += [Count("nodes ($Nodes)", nodes[0], POINT_BYTES)] if nodes else []
        counts += [Count("elements ($Elements)", elements[0])] if elements else []
    check_counts(path, len(data), counts)


# ----------------------------------------------------------------------------------------------------------------------
# Medit (.mesh): a keyword line, then the count on the next line
# ----------------------------------------------------------------------------------------------------------------------
_MEDIT_SECTION = re.compile(rb"^[ \t]*(Vertices|Edges|Triangles|Quadrilaterals|Tetrahedra|Prisms|Pyramids|Hexahedra|"
                            rb"Corners|RequiredVertices|Ridges|RequiredEdges|Normals|Tangents|NormalAtVertices|"
                            rb"SubDomainFromMesh|VertexOnGeometricVertex|VertexOnGeometricEdge|EdgeOnGeometricEdge|"
                            rb"Identifier|Geometry)[ \t]*\r?\n?[ \t]*(\d+)", re.M)


def _check_medit(path: Path, data: FileBytes) -> None:
    counts = (Count(f"{m.group(1).decode().lower()} ({m.group(1).decode()})", int(m.group(2)),
                    POINT_BYTES if m.group(1) == b"Vertices" else 1) for m in _MEDIT_SECTION.finditer(data))
    check_counts(path, len(data), counts)


_CHECKS = {".vtu": check_vtu, ".vtk": _check_vtk, ".msh": _check_msh, ".mesh": _check_medit}
