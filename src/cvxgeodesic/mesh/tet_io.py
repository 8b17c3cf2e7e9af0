"""Tetrahedral meshes from files, and distance fields written for ParaView (issue 26).

Reading: :func:`load_tet_mesh` takes

- TetGen's ``.node`` / ``.ele`` pair (either file name; a small native reader: ``#`` comments,
  blank lines, 0- or 1-based numbering as the ``.node`` file's first point says, attributes and
  boundary markers ignored, 10-node tetrahedra reduced to their corners);
- through meshio (the ``io`` extra): ``.msh`` (Gmsh), ``.vtu``, ``.vtk``, ``.mesh`` (Medit),
  ``.inp`` (Abaqus), and more of meshio's volume formats in :data:`MESHIO_TET_EXTENSIONS`. The
  ``tetra`` cells are read (``tetra10``: their four corners); other cells (the boundary
  triangles of a Gmsh file, lines, points) are ignored, with a note.

Repairs, each recorded in the mesh's notes: tetrahedra repeating a vertex and exact duplicates
(same four vertices) are dropped; vertices in no tetrahedron are dropped (``file_index`` keeps the
file's numbering, as :func:`~cvxgeodesic.mesh.io.load_mesh` does for surfaces). Nothing is welded.

Writing: :func:`save_tet_distance` writes a ``.vtu`` (or legacy ``.vtk``) with the tetrahedra and the
field as point data, which ParaView opens (slices, clips, contours).
"""

from __future__ import annotations

import contextlib
import importlib
import io
import os
import re
import tempfile
import warnings
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._atomic import atomic_write
from ..errors import MeshFormatError, MeshRepairWarning, ParameterError
from ..validation import as_vertex_field, check_output_path
from .formats._common import check_file
from .formats._limits import check_limits
from .tetmesh import TetMesh

__all__ = ["MESHIO_TET_EXTENSIONS", "TETGEN_EXTENSIONS", "TET_DISTANCE_EXTENSIONS", "TET_MESH_EXTENSIONS",
           "load_tet_mesh", "read_tetgen", "read_volume", "save_tet_distance"]

#: Files read through meshio (the ``io`` extra).
MESHIO_TET_EXTENSIONS = (".msh", ".vtu", ".vtk", ".mesh", ".inp", ".xdmf", ".med")
#: TetGen's node and element files (either one names the pair).
TETGEN_EXTENSIONS = (".node", ".ele")
#: Every extension :func:`load_tet_mesh` reads.
TET_MESH_EXTENSIONS = MESHIO_TET_EXTENSIONS + TETGEN_EXTENSIONS
#: Files :func:`save_tet_distance` writes.
TET_DISTANCE_EXTENSIONS = (".vtu", ".vtk")

_HINT = "pip install 'cvxgeodesic[io]' (or pip install meshio)"


def _meshio(needed_for: str, error: type[Exception]) -> Any:
    try:
        return importlib.import_module("meshio")
    except ImportError:
        raise error(f"{needed_for} needs the optional package meshio: {_HINT}") from None


def load_tet_mesh(path: str | os.PathLike) -> TetMesh:
    """Read a tetrahedral mesh.

    Parameters
    ----------
    path : str or os.PathLike
        A file with an extension of :data:`TET_MESH_EXTENSIONS` (case-insensitive).

    Returns
    -------
    TetMesh
        ``name`` is the file name; ``vertex_map`` / ``file_index`` relate its numbering to the file's
        (0-based, in the file's point order); ``notes`` lists the repairs.

    Raises
    ------
    MeshFormatError
        Missing file, unknown extension, meshio missing (the message says what to install) or
        unable to read it, no tetrahedra, or a malformed TetGen file (the message names the file and
        line).

    Warns
    -----
    MeshRepairWarning
        For every repair (also in ``mesh.notes``).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (d / "t.node").write_text("4 3 0 0\\n1 0 0 0\\n2 1 0 0\\n3 0 1 0\\n4 0 0 1\\n")
    >>> _ = (d / "t.ele").write_text("# one tetrahedron\\n1 4 0\\n1 1 2 3 4\\n")
    >>> load_tet_mesh(d / "t.ele").T.tolist()
    [[0, 1, 2, 3]]
    """
    p = Path(path)
    ext = p.suffix.lower()
    if ext not in TET_MESH_EXTENSIONS:
        raise MeshFormatError(f"{p}: unsupported extension {p.suffix!r} for a tetrahedral mesh; use one of "
                              f"{', '.join(TET_MESH_EXTENSIONS)}")
    if ext in TETGEN_EXTENSIONS:
        V, T, notes = read_tetgen(p)
        name = p.with_suffix("").name
    else:
        check_file(p, "a mesh file")  # before meshio opens it: a FIFO or a device would block or never end
        V, T, notes = _read_meshio(p)
        name = p.name
    return _finish(V, T, notes, name)


def read_volume(path: str | os.PathLike) -> TetMesh | None:
    """The tetrahedral mesh of a meshio file (VTK, VTU, ...), or None when it holds no tetrahedra.

    Raises
    ------
    MeshFormatError
        meshio is missing or cannot read the file.
    """
    p = Path(path)
    V, T, notes = _read_meshio(p, allow_none=True)
    return None if T is None else _finish(V, T, notes, p.name)


def _finish(V: np.ndarray, T: np.ndarray, notes: list[str], name: str) -> TetMesh:
    """Drop tetrahedra repeating a vertex, duplicates and unused vertices (each noted); build the TetMesh."""
    n = V.shape[0]
    S = np.sort(T, axis=1)
    rep = (S[:, 1:] == S[:, :-1]).any(axis=1)
    if rep.any():
        notes.append(f"{name}: dropped {int(rep.sum())} tetrahedra that repeat a vertex (first: tet "
                     f"{int(np.flatnonzero(rep)[0])} of the file)")
        T, S = T[~rep], S[~rep]
    if T.shape[0]:
        _, first = np.unique(S, axis=0, return_index=True)
        if first.size < T.shape[0]:
            notes.append(f"{name}: dropped {T.shape[0] - first.size} duplicate tetrahedra (same vertices as an "
                         "earlier one)")
            T = T[np.sort(first)]
    if T.shape[0] == 0:
        raise MeshFormatError(f"{name}: no tetrahedra left after dropping those that repeat a vertex")
    used = np.zeros(n, dtype=bool)
    used[T.ravel()] = True
    vertex_map = np.flatnonzero(used)
    file_index = np.full(n, -1, dtype=np.int64)
    file_index[vertex_map] = np.arange(vertex_map.size)
    if vertex_map.size < n:
        notes.append(f"{name}: dropped {n - vertex_map.size} vertices in no tetrahedron (first: file vertex "
                     f"{int(np.flatnonzero(~used)[0])}); mesh indices differ from the file's, file_index maps them")
    for msg in notes:
        warnings.warn(msg, MeshRepairWarning, stacklevel=3)
    return TetMesh(V[vertex_map], file_index[T], vertex_map=vertex_map, name=name, file_index=file_index,
                   dropped_vertices=V[~used], notes=notes)


# ----------------------------------------------------------------------------------------------------------------------
# TetGen .node / .ele
# ----------------------------------------------------------------------------------------------------------------------


def _records(path: Path) -> list[tuple[int, list[str]]]:
    """Non-empty lines of ``path`` without ``#`` comments, as (line number, tokens)."""
    check_file(path, "a TetGen file")  # a FIFO named x.node would block the open below, a device never end
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise MeshFormatError(f"{path}: cannot read the file ({exc.strerror or exc})") from None
    out = []
    for i, line in enumerate(text.splitlines(), start=1):
        toks = line.split("#", 1)[0].replace(",", " ").split()
        if toks:
            out.append((i, toks))
    return out


#: TetGen's numbers (counts, point numbers) are stored as int64; larger ones cannot name anything in a file.
_INT_LIMIT = 2**63


def _ints(path: Path, line: int, toks: list[str], what: str) -> list[int]:
    """``toks`` as integers that fit int64, or a MeshFormatError naming the file and line."""
    try:
        values = [int(t) for t in toks]
    except ValueError:
        raise MeshFormatError(f"{path}, line {line}: {what} must be integers, got {' '.join(toks)!r}") from None
    for t, v in zip(toks, values, strict=True):
        if not -_INT_LIMIT < v < _INT_LIMIT:
            raise MeshFormatError(f"{path}, line {line}: {what}: {t} is out of range (at most 2**63 - 1)")
    return values


def read_tetgen(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Read TetGen's ``.node`` and ``.ele`` files (give either; the other has the same stem).

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    V : (n, 3) float64 ndarray
        Points in file order.
    T : (k, 4) int64 ndarray
        Tetrahedra as 0-based indices into ``V`` (TetGen's numbering, 0- or 1-based, is
        translated through the point numbers of the ``.node`` file).
    notes : list of str
        Second-order elements reduced to their corners.

    Raises
    ------
    MeshFormatError
        A missing file, a malformed header or record (file and line named), fewer records than
        the header says, repeated point numbers, or an element naming an unknown point.
    """
    p = Path(path)
    upper = p.suffix.isupper()
    node, ele = (p.with_suffix(ext.upper() if upper else ext) for ext in (".node", ".ele"))
    recs = _records(node)
    if not recs:
        raise MeshFormatError(f"{node}: file is empty")
    ln, head = recs[0]
    h = _ints(node, ln, head[:4], "the header (points, dimension, attributes, markers)")
    if len(h) < 2 or h[0] < 1 or h[1] != 3:
        raise MeshFormatError(f"{node}, line {ln}: the header must be '<points> 3 [attributes] [markers]' with at "
                              f"least one point, got {' '.join(head)!r}")
    n = h[0]
    body = recs[1:n + 1]
    if len(body) < n:
        raise MeshFormatError(f"{node}: the header (line {ln}) announces {n} points, the file has {len(body)}")
    numbers = np.empty(n, dtype=np.int64)
    V = np.empty((n, 3))
    for k, (line, toks) in enumerate(body):
        if len(toks) < 4:
            raise MeshFormatError(f"{node}, line {line}: a point needs a number and 3 coordinates, got "
                                  f"{' '.join(toks)!r}")
        numbers[k] = _ints(node, line, toks[:1], "point numbers")[0]
        try:
            V[k] = [float(t) for t in toks[1:4]]
        except ValueError:
            raise MeshFormatError(f"{node}, line {line}: coordinates must be numbers, got "
                                  f"{' '.join(toks[1:4])!r}") from None
        if not np.all(np.isfinite(V[k])):
            raise MeshFormatError(f"{node}, line {line}: point {numbers[k]} has a non-finite coordinate")
    order = np.argsort(numbers, kind="stable")
    dup = numbers[order][1:] == numbers[order][:-1]
    if dup.any():
        raise MeshFormatError(f"{node}: point number {int(numbers[order][1:][dup][0])} is given more than once")

    recs = _records(ele)
    if not recs:
        raise MeshFormatError(f"{ele}: file is empty")
    ln, head = recs[0]
    h = _ints(ele, ln, head[:3], "the header (tetrahedra, nodes per tetrahedron, attributes)")
    if len(h) < 2 or h[0] < 1 or h[1] not in (4, 10):
        raise MeshFormatError(f"{ele}, line {ln}: the header must be '<tetrahedra> <4 or 10> [attributes]' with at "
                              f"least one tetrahedron, got {' '.join(head)!r}")
    k_tets, per = h[0], h[1]
    body = recs[1:k_tets + 1]
    if len(body) < k_tets:
        raise MeshFormatError(f"{ele}: the header (line {ln}) announces {k_tets} tetrahedra, the file has {len(body)}")
    raw = np.empty((k_tets, 4), dtype=np.int64)
    for k, (line, toks) in enumerate(body):
        if len(toks) < 1 + per:
            raise MeshFormatError(f"{ele}, line {line}: a tetrahedron needs a number and {per} point numbers, got "
                                  f"{' '.join(toks)!r}")
        raw[k] = _ints(ele, line, toks[1:5], "point numbers")
    pos = np.searchsorted(numbers[order], raw)
    pos = np.clip(pos, 0, n - 1)
    known = numbers[order][pos] == raw
    if not known.all():
        k = int(np.flatnonzero(~known.all(axis=1))[0])
        bad = int(raw[k][~known[k]][0])
        raise MeshFormatError(f"{ele}, line {body[k][0]}: tetrahedron {body[k][1][0]} names point {bad}, which "
                              f"{node.name} does not have")
    notes = []
    if per == 10:
        notes.append(f"{ele.name}: 10-node (quadratic) tetrahedra: their 4 corners are used")
    return V, order[pos], notes


# ----------------------------------------------------------------------------------------------------------------------
# meshio
# ----------------------------------------------------------------------------------------------------------------------


def _read_meshio(path: Path, allow_none: bool = False) -> tuple[np.ndarray, Any, list[str]]:
    meshio = _meshio(f"{path}: reading {path.suffix} files", MeshFormatError)
    check_limits(path)  # header counts and compressed arrays within the file's size: meshio allocates what they say
    try:
        # meshio prints its own error and calls sys.exit(1) on some files it cannot parse
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()), \
                warnings.catch_warnings():
            warnings.simplefilter("ignore")
            mm = meshio.read(str(path))
    except (Exception, SystemExit) as exc:
        detail = f"{type(exc).__name__}: {exc}" if not isinstance(exc, SystemExit) else "not a valid file"
        raise MeshFormatError(f"{path}: meshio cannot read the file ({detail})") from None
    if allow_none and not any(block.type in ("tetra", "tetra10") for block in mm.cells):
        return np.zeros((0, 3)), None, []
    V = np.asarray(mm.points, dtype=np.float64)
    if V.ndim != 2 or V.shape[1] != 3:
        raise MeshFormatError(f"{path}: points must be 3-D for a tetrahedral mesh, got shape {V.shape}")
    bad = ~np.isfinite(V).all(axis=1)
    if bad.any():
        raise MeshFormatError(f"{path}: point {int(np.flatnonzero(bad)[0])} has a non-finite coordinate")
    parts: list[np.ndarray] = []
    other: dict[str, int] = {}
    notes: list[str] = []
    for block in mm.cells:
        if block.type in ("tetra", "tetra10"):
            parts.append(np.asarray(block.data, dtype=np.int64)[:, :4])
            if block.type == "tetra10":
                notes.append(f"{path.name}: {len(block.data)} 10-node (quadratic) tetrahedra: their 4 corners are used")
        else:
            other[block.type] = other.get(block.type, 0) + len(block.data)
    if not parts:
        types = ", ".join(sorted(other)) or "none"
        raise MeshFormatError(f"{path}: no tetrahedra (cell types: {types})")
    if other:
        notes.append(f"{path.name}: ignored cells other than tetrahedra: "
                     + ", ".join(f"{c} {t}" for t, c in sorted(other.items())))
    T = np.vstack(parts)
    out = (T < 0) | (T >= V.shape[0])
    if out.any():
        k = int(np.flatnonzero(out.any(axis=1))[0])
        raise MeshFormatError(f"{path}: tetrahedron {k} has point index {T[k].tolist()} outside [0, {V.shape[0]})")
    return V, T, notes


def save_tet_distance(path: str | os.PathLike, mesh: TetMesh, distance: ArrayLike, *, name: str = "distance",
                      fields: dict[str, ArrayLike] | None = None, overwrite_read_only: bool = False) -> Path:
    """Write a tetrahedral mesh with a distance field as point data: ``.vtu`` (XML) or ``.vtk`` (legacy).

    The file holds ``mesh.V`` and ``mesh.T`` (this mesh's numbering) and one point array per field;
    ParaView opens it. ``inf`` (unreachable) is written as is. The file is replaced atomically.

    Parameters
    ----------
    path : str or os.PathLike
        Output file, extension in :data:`TET_DISTANCE_EXTENSIONS`.
    mesh : TetMesh
    distance : (n,) float array_like
        One value per vertex.
    name : str
        Name of the point array.
    fields : dict of str to (n,) float array_like, optional
        More point arrays (e.g. a reference distance and the error).
    overwrite_read_only : bool, default False
        Replace ``path`` even when it is read-only (:func:`cvxgeodesic.mesh.io.save_distance`).

    Returns
    -------
    pathlib.Path

    Raises
    ------
    ParameterError
        Unsupported extension, missing folder, a field of the wrong length, or meshio missing.
    """
    out = check_output_path(path, TET_DISTANCE_EXTENSIONS)
    data = {name: as_vertex_field(distance, "distance", mesh.n_vertices)}
    for key, values in (fields or {}).items():
        if not isinstance(key, str) or not re.fullmatch(r"[^\s]+", key) or key in data:
            raise ParameterError(f"fields: names must be unique strings without spaces, got {key!r}")
        data[key] = as_vertex_field(values, f"fields[{key!r}]", mesh.n_vertices)
    meshio = _meshio(f"writing {out.suffix} files", ParameterError)
    mm = meshio.Mesh(np.asarray(mesh.V), [("tetra", np.asarray(mesh.T))], point_data=data)
    ext = out.suffix.lower()

    def write(fh):
        # meshio writes to paths only: a private temporary folder, then copied into fh
        with tempfile.TemporaryDirectory(prefix="cvxgeodesic-") as tmp:
            f = Path(tmp) / f"field{ext}"
            mm.write(f, file_format="vtu" if ext == ".vtu" else "vtk")
            fh.write(f.read_bytes())

    atomic_write(out, write, overwrite_read_only=overwrite_read_only)
    return out
