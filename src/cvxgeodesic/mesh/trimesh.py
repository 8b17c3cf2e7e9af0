"""The validated triangle-mesh model used everywhere in cvxgeodesic."""

from __future__ import annotations

from collections.abc import Sequence
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike

from ..errors import MeshError
from ..validation import MAX_COORDINATE, MIN_EXTENT, check_coordinates
from .simplex import SimplexMesh, unit_mesh, unit_scale

#: Default of :meth:`TriMesh.degenerate_faces`: a face whose smallest altitude is below
#: ``DEGENERATE_TOL`` times its longest edge (a needle or a cap; exactly collinear or
#: coincident corners included) or below ``DEGENERATE_TOL`` times the mean edge length
#: of the mesh (a speck) is *degenerate*. See the README, "Input meshes".
DEGENERATE_TOL = 1e-3
__all__ = ["DEGENERATE_TOL", "MAX_COORDINATE", "MIN_EXTENT", "TriMesh", "file_numbering", "unit_mesh", "unit_scale"]


class TriMesh(SimplexMesh):
    """An immutable, validated triangle mesh.

    Parameters
    ----------
    V : (n, 3) array_like of float
        Vertex positions. Must be finite.
    F : (m, 3) array_like of int
        Triangles as 0-based vertex indices. Every index must lie in ``[0, n)``
        and the three indices of a face must be distinct.
    vertex_map : (n,) array_like of int, optional
        Index of each vertex in the file it was read from (``load_mesh`` sets
        it after welding duplicates and dropping unreferenced vertices).
    name : str, optional
        Label used in messages and reports (usually the file name).
    file_index : (n_file,) array_like of int, optional
        For each vertex *of the file*, its index in this mesh, or -1 for a vertex the
        reader dropped (referenced by no face). Welded duplicates share an index.
        ``load_mesh`` sets it; default ``arange(n)`` (the mesh is its own file).
    dropped_vertices : (k, 3) array_like of float, optional
        Positions of the file vertices with ``file_index == -1``, in file order (so that
        outputs in the file's numbering keep their coordinates).
    notes : sequence of str, optional
        One line per repair the reader made (welding, dropped vertices or faces).
    file_faces : (k, 3) array_like of int, optional
        The file's triangles in the file's vertex numbering (polygons fan-triangulated), before
        welding: what files written in the file's numbering use. ``load_mesh`` sets it when it
        differs from the default ``vertex_map[F]``.

    Raises
    ------
    MeshError
        If an array has the wrong shape or type (polygons with more than three
        vertices included: :func:`~cvxgeodesic.mesh.io.load_mesh` fan-triangulates
        them, ``TriMesh`` does not), is empty or ragged, a coordinate is not finite or
        beyond ``±MAX_COORDINATE`` (1e40), a mesh smaller than ``MIN_EXTENT`` (1e-40;
        :func:`~cvxgeodesic.validation.check_coordinates`), an index is out of range, or a face
        repeats a vertex.

    Notes
    -----
    Vertices not referenced by any face are allowed: they form components of
    their own and get an infinite distance. Coincident vertices are allowed (no
    welding). Faces of zero or near-zero area are allowed;
    :meth:`degenerate_faces` finds them and the convex formulations leave them
    out (README, "Input meshes"). ``V`` and ``F`` are stored as read-only
    float64 / int64 arrays: libraries that need writable arrays (e.g.
    ``open3d.utility.Vector3dVector``) take ``mesh.V.copy()``.

    Vertex numbering: every array of the Python API (``V``, fields, source indices)
    uses this mesh's numbering, which :func:`~cvxgeodesic.mesh.io.load_mesh` makes by
    welding duplicates and dropping unreferenced vertices;
    :func:`~cvxgeodesic.mesh.fileorder.to_file_order` maps a field back to the file's
    numbering (the command line does that for every file it writes).
    """

    dim = 2
    #: Set on the coarse meshes of :func:`~cvxgeodesic.mesh.decimate.simplify_mesh` only: the method used.
    simplifier: str

    def __init__(
        self,
        V: ArrayLike,
        F: ArrayLike,
        *,
        vertex_map: ArrayLike | None = None,
        name: str | None = None,
        file_index: ArrayLike | None = None,
        dropped_vertices: ArrayLike | None = None,
        notes: Sequence[str] = (),
        file_faces: ArrayLike | None = None,
    ) -> None:
        self.name = name or "mesh"
        self.V = _as_vertices(V, self.name)
        self.F = _as_cells(F, self.V.shape[0], self.name, 2)
        self.vertex_map, self.file_index, self.dropped_vertices = file_numbering(
            self.V.shape[0], vertex_map, file_index, dropped_vertices, self.name)
        self.notes: tuple[str, ...] = tuple(str(n) for n in notes)
        self._file_faces = None if file_faces is None else _as_cells(file_faces, self.file_index.shape[0],
                                                                      f"{self.name} (file faces)", 2)

    def __repr__(self) -> str:
        return f"TriMesh(name={self.name!r}, n_vertices={self.n_vertices}, n_faces={self.n_faces})"

    @property
    def n_faces(self) -> int:
        return int(self.F.shape[0])

    @property
    def file_faces(self) -> np.ndarray:
        """(k, 3) int64 ndarray: the file's triangles in the file's vertex numbering.

        The faces as the file has them (before welding; polygons fan-triangulated, faces that
        repeat a file vertex left out), for files written in the file's numbering; ``vertex_map[F]``
        when the mesh was not read from a file that needs more.
        """
        if self._file_faces is not None:
            return self._file_faces
        return self.vertex_map[self.F]

    @cached_property
    def face_normals_unnormalized(self) -> np.ndarray:
        """(m, 3) float ndarray: cross products (v2 - v1) x (v3 - v1), length 2·area."""
        V, F = self.V, self.F
        return np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])

    @cached_property
    def face_areas(self) -> np.ndarray:
        """(m,) float ndarray: triangle areas."""
        return 0.5 * np.linalg.norm(self.face_normals_unnormalized, axis=1)

    # the names of the surface vocabulary for the shared ones (:class:`~cvxgeodesic.mesh.simplex.SimplexMesh`)
    face_longest_edges = property(lambda self: self.cell_longest_edges, doc="(m,) float: longest edge of each face.")
    face_min_altitudes = property(lambda self: self.cell_min_altitudes, doc="(m,) float: smallest altitude.")
    face_edges = property(lambda self: self.cell_edges, doc="(m, 3) int64: the edge opposite each corner.")
    edge_face_counts = property(lambda self: self.edge_cell_counts, doc="(e,) int64: faces per edge.")

    @property
    def cells(self) -> np.ndarray:
        return self.F

    @property
    def cell_measures(self) -> np.ndarray:
        return self.face_areas

    @cached_property
    def cell_facet_measures(self) -> np.ndarray:
        """(m, 3) float ndarray: the length of the edge opposite each corner."""
        return self.edge_lengths[self.face_edges]

    def _with_vertices(self, V: np.ndarray) -> TriMesh:
        return TriMesh(V, self.F, vertex_map=self.vertex_map, name=self.name)

    def degenerate_faces(self, tol: float = DEGENERATE_TOL) -> np.ndarray:
        """Faces too thin or too small for the gradient-based operators (:meth:`SimplexMesh.degenerate_cells`).

        Left out of the convex formulations (:class:`~cvxgeodesic.formulations.MeshOperators`).

        Parameters
        ----------
        tol : float
            Relative threshold (default :data:`DEGENERATE_TOL`); 0 selects only faces of exactly zero area.

        Returns
        -------
        (k,) int64 ndarray
            Sorted indices of the degenerate faces.
        """
        return self.degenerate_cells(tol)

    @cached_property
    def is_edge_manifold(self) -> bool:
        """True when no edge is shared by more than two faces."""
        return bool(np.all(self.edge_face_counts <= 2))

    @cached_property
    def boundary_facets(self) -> np.ndarray:
        """(b, 2) int64 ndarray: the edges of a single face (the boundary of an open surface)."""
        return self.edges[self.edge_face_counts == 1]


def file_numbering(n: int, vertex_map: ArrayLike | None, file_index: ArrayLike | None,
                   dropped_vertices: ArrayLike | None, name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The checked file-numbering arrays of a mesh of ``n`` vertices (read-only; identity when not from a file).

    Returns
    -------
    vertex_map : (n,) int64 ndarray
    file_index : (n_file,) int64 ndarray
        Each file vertex's mesh vertex, −1 for the dropped ones.
    dropped_vertices : (n_dropped, 3) float ndarray
        Positions of the dropped file vertices (NaN when not given).

    Raises
    ------
    MeshError
        Wrong shapes or indices, naming ``name``.
    """
    def as_index(x: ArrayLike, what: str) -> np.ndarray:
        try:
            return np.array(x, dtype=np.int64)
        except (TypeError, ValueError, OverflowError):
            raise MeshError(f"{name}: {what} must be an integer array") from None

    vmap = as_index(np.arange(n) if vertex_map is None else vertex_map, "vertex_map")
    if vmap.shape != (n,):
        raise MeshError(f"{name}: vertex_map must have shape ({n},), got {vmap.shape}")
    findex = as_index(np.arange(n) if file_index is None else file_index, "file_index")
    if findex.ndim != 1 or np.any(findex < -1) or np.any(findex >= n):
        raise MeshError(f"{name}: file_index must be a 1-D array of indices in [-1, {n})")
    n_dropped = int(np.count_nonzero(findex < 0))
    dropped = (np.full((n_dropped, 3), np.nan) if dropped_vertices is None
               else np.array(dropped_vertices, dtype=np.float64).reshape(-1, 3))
    if dropped.shape[0] != n_dropped:
        raise MeshError(f"{name}: dropped_vertices must have {n_dropped} rows, got {dropped.shape[0]}")
    for arr in (vmap, findex, dropped):
        arr.setflags(write=False)
    return vmap, findex, dropped


def _as_vertices(V, name: str) -> np.ndarray:
    try:
        V = np.array(V, dtype=np.float64, order="C")
    except (TypeError, ValueError) as exc:
        raise MeshError(f"{name}: vertices must be a numeric (n, 3) array ({exc})") from None
    if V.ndim != 2 or V.shape[1] != 3:
        raise MeshError(f"{name}: vertices must have shape (n, 3), got {V.shape}")
    if V.shape[0] == 0:
        raise MeshError(f"{name}: the mesh has no vertices")
    bad = ~np.isfinite(V).all(axis=1)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise MeshError(
            f"{name}: vertex {i} has a non-finite coordinate {V[i].tolist()} ({int(bad.sum())} such vertices)"
        )
    check_coordinates(V, name)
    V.setflags(write=False)
    return V


# per simplex dimension: (cell, cells, shape, hint after the shape, remedy for a repeated vertex)
_CELL_WORDS = {
    2: ("face", "faces", "(m, 3)", " (triangles only; load_mesh fan-triangulates polygons)",
        "remove degenerate faces first"),
    3: ("tetrahedron", "tetrahedra", "(k, 4)", "", "remove them first"),
}


def _as_cells(C, n: int, name: str, dim: int) -> np.ndarray:
    """(k, dim + 1) read-only int64 cells checked against ``n`` vertices; a MeshError naming the first bad cell."""
    one, many, shape, hint, remedy = _CELL_WORDS[dim]
    try:
        C_in = np.asarray(C)
    except (TypeError, ValueError, OverflowError):  # ragged lists (polygons of several sizes), ...
        raise MeshError(f"{name}: {many} must be an {shape} integer array{hint}") from None
    if C_in.ndim != 2 or C_in.shape[1] != dim + 1:
        raise MeshError(f"{name}: {many} must have shape {shape}{hint}, got {C_in.shape}")
    if C_in.shape[0] == 0:
        raise MeshError(f"{name}: the mesh has no {many}")
    if C_in.dtype.kind == "f":
        if not np.all(np.isfinite(C_in)) or not np.all(C_in == np.round(C_in)):
            raise MeshError(f"{name}: {one} indices must be integers")
    elif C_in.dtype.kind not in "iu":
        raise MeshError(f"{name}: {one} indices must be integers, got dtype {C_in.dtype}")
    if dim == 3 and C_in.dtype.kind == "u" and int(C_in.max()) >= 2**63:
        raise MeshError(f"{name}: {one} indices must be in [0, {n})")
    cells = np.array(C_in, dtype=np.int64, order="C")
    out = (cells < 0) | (cells >= n)
    if out.any():
        c = int(np.flatnonzero(out.any(axis=1))[0])
        raise MeshError(f"{name}: {one} {c} has vertex index {cells[c].tolist()} outside [0, {n})")
    S = np.sort(cells, axis=1)
    rep = (S[:, 1:] == S[:, :-1]).any(axis=1)
    if rep.any():
        c = int(np.flatnonzero(rep)[0])
        raise MeshError(f"{name}: {one} {c} repeats a vertex {cells[c].tolist()} ({int(rep.sum())} such {many}); "
                        f"{remedy}")
    cells.setflags(write=False)
    return cells
