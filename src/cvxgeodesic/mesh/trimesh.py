"""The validated triangle-mesh model used everywhere in cvxgeodesic."""

from __future__ import annotations

from collections.abc import Sequence
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike

from ..validation import MAX_COORDINATE, MIN_EXTENT
from .reference import TRIANGLE
from .simplex import DEGENERATE_TOL, SimplexMesh, _as_cells, file_numbering

__all__ = ["DEGENERATE_TOL", "MAX_COORDINATE", "MIN_EXTENT", "TriMesh", "file_numbering"]


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
    reference = TRIANGLE
    domain = "surface"
    count_name = "n_faces"
    #: Set on the coarse meshes of :func:`~cvxgeodesic.mesh.decimate.simplify_mesh` only: the method used.
    simplifier: str

    def __init__(self, V: ArrayLike, F: ArrayLike, *, vertex_map: ArrayLike | None = None, name: str | None = None,
                 file_index: ArrayLike | None = None, dropped_vertices: ArrayLike | None = None,
                 notes: Sequence[str] = (), file_faces: ArrayLike | None = None) -> None:
        super().__init__(V, F, vertex_map=vertex_map, name=name, file_index=file_index,
                         dropped_vertices=dropped_vertices, notes=notes)
        self._file_faces = None if file_faces is None else _as_cells(file_faces, self.file_index.shape[0],
                                                                      f"{self.name} (file faces)", TRIANGLE)

    @property
    def F(self) -> np.ndarray:
        """(m, 3) int64 ndarray, read-only: the triangles (:attr:`cells`)."""
        return self.cells

    @property
    def n_faces(self) -> int:
        """Number of triangles."""
        return self.n_cells

    @property
    def file_cells(self) -> np.ndarray:
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

    @property
    def cell_measures(self) -> np.ndarray:
        """(m,) float ndarray: the cells' measures, :attr:`face_areas`."""
        return self.face_areas

    @cached_property
    def cell_facet_measures(self) -> np.ndarray:
        """(m, 3) float ndarray: the length of the edge opposite each corner."""
        return self.edge_lengths[self.cell_edges]

    def _with_vertices(self, V: np.ndarray) -> TriMesh:
        return TriMesh(V, self.F, vertex_map=self.vertex_map, name=self.name)

    def degenerate_faces(self, tol: float = DEGENERATE_TOL) -> np.ndarray:
        """(k,) int64 ndarray: the sorted indices of the faces too thin or too small for the gradient-based operators
        (:meth:`SimplexMesh.degenerate_cells`), left out of the convex formulations
        (:class:`~cvxgeodesic.problems.formulations.MeshOperators`); ``tol = 0`` selects only faces of exactly zero
        area."""
        return self.degenerate_cells(tol)
