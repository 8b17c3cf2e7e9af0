"""``load_mesh``: read a mesh file through the format registry, then check it and build a surface (triangulated,
welded) or, from a file holding tetrahedra, a volume.

Every problem with a file is reported as a :class:`~cvxgeodesic.errors.MeshFormatError` whose message
names the file and, for text formats, the line (a missing file as a
:class:`~cvxgeodesic.errors.MeshFileNotFoundError`, also a ``FileNotFoundError``).
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path
from typing import Literal, overload

import numpy as np

from ..errors import MeshError, MeshFormatError, MeshRepairWarning
from ..validation import check_choice
from .formats._common import RawMesh, at_line, check_file, file_errors, format_error
from .formats.registry import mesh_format
from .tetmesh import TetMesh
from .trimesh import TriMesh

__all__ = ["load_mesh"]


#: What ``load_mesh(path, kind=...)`` asks the file to hold: the mesh class of each kind.
MESH_KINDS: dict[str, type[TriMesh] | type[TetMesh]] = {"surface": TriMesh, "volume": TetMesh}


def _other_kind(wanted: type) -> str:
    """The kind of :data:`MESH_KINDS` other than that of the class ``wanted``."""
    return next(k for k, cls in MESH_KINDS.items() if cls is not wanted)


@overload
def load_mesh(path: str | os.PathLike, *, kind: Literal["surface"]) -> TriMesh: ...
@overload
def load_mesh(path: str | os.PathLike, *, kind: Literal["volume"]) -> TetMesh: ...
@overload
def load_mesh(path: str | os.PathLike, *, kind: None = None) -> TriMesh | TetMesh: ...


def load_mesh(path: str | os.PathLike, *, kind: Literal["surface", "volume"] | None = None) -> TriMesh | TetMesh:
    """Read a triangle mesh from an OBJ, OFF, PLY or STL file (glTF, GLB, 3MF, VTK, VTU with the ``io`` extra), or
    a tetrahedral mesh from a file that holds tetrahedra.

    The format is chosen from the extension (case-insensitive; the list is
    :data:`~cvxgeodesic.mesh.formats.registry.MESH_EXTENSIONS`): ``.obj``, ``.off``,
    ``.ply`` (ASCII, binary little- or big-endian) or ``.stl`` (ASCII or binary), read by
    this package; ``.glb``, ``.gltf``, ``.3mf`` through trimesh and ``.vtk``, ``.vtu``
    through meshio, when installed (``pip install 'cvxgeodesic[io]'``), with the same
    welding and checks.

    Parameters
    ----------
    path : str or os.PathLike
        The file to read.
    kind : {"surface", "volume"}, optional
        What the file must hold: ``"surface"`` returns a :class:`~cvxgeodesic.mesh.trimesh.TriMesh` and
        ``"volume"`` a :class:`~cvxgeodesic.mesh.tetmesh.TetMesh`, and a type checker knows it
        (``load_mesh("part.obj", kind="surface").F`` type-checks); a file holding the other kind is refused
        with a :class:`~cvxgeodesic.errors.MeshError`. Default None: whatever the file holds, typed
        ``TriMesh | TetMesh`` (tell them apart with ``isinstance`` or ``mesh.dim``).

    Files holding tetrahedra give a :class:`~cvxgeodesic.mesh.tetmesh.TetMesh` (the list is
    :data:`~cvxgeodesic.mesh.formats.registry.VOLUME_EXTENSIONS`): TetGen's ``.node``/``.ele`` pair (either
    name; named after the stem), and through meshio ``.msh``, ``.mesh``, ``.inp``, ``.xdmf``, ``.med``, and
    ``.vtu``/``.vtk`` files with ``tetra`` cells (a VTK file without them is a surface). ``tetra10`` cells
    give their corners; the file's other cells are ignored (noted). Tetrahedra repeating a vertex, exact
    duplicates and vertices in no tetrahedron are dropped (noted); nothing is welded.

    Returns
    -------
    TriMesh or TetMesh
        A ``TetMesh`` when the file holds tetrahedra, else a ``TriMesh``: the welded triangle mesh, named after
        the file's base name.
        ``mesh.vertex_map[i]`` is the 0-based index in the file of the (first)
        original vertex of vertex ``i``; for STL, whose vertices are the triangle
        corners, it is the corner number ``3 * triangle + corner``.
        ``mesh.file_index[j]`` is the mesh index of file vertex ``j`` (-1: in no face),
        ``mesh.n_file_vertices`` the file's vertex count, ``mesh.file_cells`` the file's
        triangles in its own numbering, and ``mesh.notes`` one line per repair. The mesh's
        numbering differs from the file's when vertices were welded or dropped:
        :func:`~cvxgeodesic.mesh.fileorder.to_file_order` maps a field back.

    Raises
    ------
    MeshFileNotFoundError
        If the file does not exist (a ``MeshFormatError`` and a ``FileNotFoundError``).
    ParameterError
        ``kind`` is not ``"surface"``, ``"volume"`` or None.
    MeshError
        ``kind`` asks for a surface and the file holds tetrahedra, or for a volume and it holds none (the message
        names the file and what it holds); a format that holds only the other kind is refused before reading.
    MeshFormatError
        If the file is a directory or not a regular file, has an unsupported extension, is empty or malformed
        (the message names the line for text formats), has a face or tetrahedron index out of range
        (the message names the cell and the index), a non-finite coordinate, or no faces (no tetrahedra, for
        a format only volumes have), or needs meshio or trimesh that is not installed (the message says what
        to install).

    Warns
    -----
    MeshRepairWarning
        (a ``UserWarning``) When faces that became degenerate by welding (a repeated
        vertex) or exact duplicate faces (the same vertex set as an earlier face) are
        dropped, and when welding or dropping vertices makes the mesh's vertex count
        differ from the file's; the message says how many. For a volume, every note.

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

    Examples
    --------
    >>> import cvxgeodesic as cg
    >>> try:
    ...     cg.load_mesh("no_such_mesh.obj")
    ... except FileNotFoundError as exc:
    ...     print(exc)
    no_such_mesh.obj: no such file
    """
    wanted = None if kind is None else MESH_KINDS[check_choice(kind, "kind", MESH_KINDS, lower=False)]
    p = Path(path)
    fmt = mesh_format(p)
    if wanted is not None and wanted.dim not in fmt.dims:
        other = _other_kind(wanted)
        raise MeshError(f"{p}: kind={kind!r} asks for {wanted.reference.words.mesh}, and a {fmt.extension} file holds "
                        f"only {MESH_KINDS[other].reference.words.mesh} (kind={other!r})")
    check_file(p, "a mesh file")  # the same messages for missing, directory and empty files in every format
    assert fmt.read_mesh is not None  # mesh_format returns formats with a reader
    with file_errors(p):
        raw = fmt.read_mesh(p)
    volume = raw.tets is not None and raw.tets.size > 0
    holds = TetMesh if volume else TriMesh
    if wanted is not None and holds is not wanted:
        raise MeshError(f"{p}: kind={kind!r} asks for {wanted.reference.words.mesh}, and this file holds "
                        f"{holds.reference.words.mesh} (kind={_other_kind(wanted)!r})")
    if volume:
        return _finish_volume(p, raw)
    cell_types = ", ".join(sorted(raw.other_cells or {})) or "none"
    if 2 not in fmt.dims:
        raise format_error(p, f"no tetrahedra (cell types: {cell_types})")
    if raw.other_cells is not None and raw.sizes.size == 0:
        raise format_error(p, f"no triangle or quad cells (cell types: {cell_types})")
    with file_errors(p):
        return _finish(p, raw)


def _finish_volume(path: Path, raw: RawMesh) -> TetMesh:
    """Check the points and tetrahedra of a file; drop tetrahedra repeating a vertex, duplicates and vertices in
    no tetrahedron (each noted and warned); build the :class:`TetMesh` that remembers the file's numbering."""
    V, T = np.asarray(raw.V, dtype=np.float64), np.asarray(raw.tets, dtype=np.int64)
    n, name, notes = V.shape[0], raw.name or path.name, list(raw.notes)
    bad = ~np.isfinite(V).all(axis=1)
    if bad.any():
        raise format_error(path, f"point {int(np.flatnonzero(bad)[0])} has a non-finite coordinate")
    out = (T < 0) | (T >= n)
    if out.any():
        k = int(np.flatnonzero(out.any(axis=1))[0])
        raise format_error(path, f"tetrahedron {k} has point index {T[k].tolist()} outside [0, {n})")
    if raw.other_cells:
        notes.append(f"{path.name}: ignored cells other than tetrahedra: "
                     + ", ".join(f"{c} {t}" for t, c in sorted(raw.other_cells.items())))
    T = _unique_tets(T, name, notes)
    used = np.bincount(T.ravel(), minlength=n) > 0
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


def _unique_tets(T: np.ndarray, name: str, notes: list[str]) -> np.ndarray:
    """``T`` without the tetrahedra that repeat a vertex and the exact duplicates (same four vertices as an earlier
    one), each noted; a MeshFormatError when none is left."""
    S = np.sort(T, axis=1)
    rep = (S[:, 1:] == S[:, :-1]).any(axis=1)
    if rep.any():
        notes.append(f"{name}: dropped {int(rep.sum())} tetrahedra that repeat a vertex (first: tet "
                     f"{int(np.flatnonzero(rep)[0])} of the file)")
        T = T[~rep]
    if T.shape[0] == 0:
        raise MeshFormatError(f"{name}: no tetrahedra left after dropping those that repeat a vertex")
    T, n_dup = _without_duplicates(T)
    if n_dup:
        notes.append(f"{name}: dropped {n_dup} duplicate tetrahedra (same vertices as an earlier one)")
    return T


def _without_duplicates(cells: np.ndarray) -> tuple[np.ndarray, int]:
    """``cells`` ((m, k) int) without those with the same vertices as an earlier one, and how many were dropped."""
    _, first = np.unique(np.sort(cells, axis=1), axis=0, return_index=True)
    return cells[np.sort(first)], cells.shape[0] - first.size


def _finish(path: Path, raw: RawMesh) -> TriMesh:
    """Validate, triangulate, weld and clean a raw polygon mesh into a :class:`TriMesh` that remembers the file."""
    V = np.asarray(raw.V, dtype=np.float64).reshape(-1, 3)
    n = V.shape[0]
    idx, sizes = raw.idx, raw.sizes
    if sizes.size == 0:
        raise format_error(path, "no faces" + (" and no vertices" if n == 0 else ""))
    if n == 0:
        raise format_error(path, "no vertices")
    bad = ~np.isfinite(V).all(axis=1)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise format_error(
            path,
            f"vertex {i}{at_line(raw.v_lines, i)} has a non-finite coordinate {V[i].tolist()} "
            f"({int(bad.sum())} such vertices)",
        )
    small = sizes < 3
    if small.any():
        f = int(np.flatnonzero(small)[0])
        raise format_error(
            path, f"face {f}{at_line(raw.f_lines, f)} has {int(sizes[f])} vertices; a face needs at least 3"
        )
    starts = np.cumsum(sizes) - sizes
    out = (idx < 0) | (idx >= n)
    if out.any():
        k = int(np.flatnonzero(out)[0])
        f = int(np.searchsorted(starts, k, side="right") - 1)
        shown = int(raw.raw_idx[k]) if raw.raw_idx is not None else int(idx[k])
        base = " (1-based)" if raw.raw_idx is not None else ""
        raise format_error(
            path,
            f"face {f}{at_line(raw.f_lines, f)} has vertex index {shown}{base} out of range; "
            f"the file has {n} vertices",
        )
    F_file = _fan_triangulate(idx, sizes, starts)

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
    F = group[F_file]  # faces in terms of group ids

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
    F, n_dup = _without_duplicates(F)
    if n_dup:
        msg = f"{path.name}: dropped {n_dup} duplicate face(s) (same vertices as an earlier face)"
        notes.append(msg)
        warnings.warn(msg, MeshRepairWarning, stacklevel=3)
    if F.shape[0] == 0:
        raise format_error(path, f"no faces left after dropping {n_deg} degenerate and {n_dup} duplicate face(s)")

    # Keep only referenced groups, ordered by their first file index.
    used = np.bincount(F.ravel(), minlength=rep.size) > 0
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
    F_mesh = new_id[F]
    # the file's own triangles, for files written in its numbering; a face naming one file vertex twice is no
    # triangle in any numbering. Kept only when they differ from what vertex_map[F] gives back.
    F_file = F_file[(F_file[:, 0] != F_file[:, 1]) & (F_file[:, 1] != F_file[:, 2]) & (F_file[:, 0] != F_file[:, 2])]
    same = F_file.shape == F_mesh.shape and np.array_equal(F_file, vertex_map[F_mesh])
    return TriMesh(V[vertex_map], F_mesh, vertex_map=vertex_map, file_index=file_index,
                   dropped_vertices=V[file_index < 0], notes=notes, name=path.name,
                   file_faces=None if same else F_file)


def _fan_triangulate(idx: np.ndarray, sizes: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """Fan-triangulate polygons given as concatenated indices. Returns an (t, 3) int64 array."""
    if np.all(sizes == 3):
        return idx.reshape(-1, 3).astype(np.int64, copy=False)
    ntri = sizes - 2
    poly = np.repeat(np.arange(sizes.size), ntri)
    j = np.arange(poly.size) - np.repeat(np.cumsum(ntri) - ntri, ntri)
    s = starts[poly]
    return np.stack([idx[s], idx[s + j + 1], idx[s + j + 2]], axis=1).astype(np.int64, copy=False)
