"""The validated tetrahedral-mesh model: distance *inside* a solid (issue 26).

:class:`TetMesh` is the volume counterpart of :class:`~cvxgeodesic.mesh.trimesh.TriMesh`: immutable
``V`` (n, 3) and ``T`` (k, 4) arrays checked once, and every derived quantity (volumes, edges, faces,
the boundary surface, adjacency, quality measures) computed lazily and cached.

Orientation: the four vertices of a tetrahedron may come in either order. ``T`` is kept as given
(so the caller's numbering holds); :attr:`TetMesh.signed_volumes` keeps the sign and everything
else uses :attr:`TetMesh.volumes` (absolute values) or :attr:`TetMesh.positive_tets` (each row
reordered so its signed volume is positive).
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike

from ..errors import MeshError
from .reference import TETRAHEDRON
from .simplex import DEGENERATE_TOL, SimplexMesh, _cached_parts
from .trimesh import TriMesh

__all__ = ["DEGENERATE_TET_TOL", "TetMesh"]

#: Default of :meth:`TetMesh.degenerate_tets`: :data:`~cvxgeodesic.mesh.simplex.DEGENERATE_TOL` (the one rule).
DEGENERATE_TET_TOL = DEGENERATE_TOL
#: A fold is reported only when the opposite vertices of an interior face lie on the same side by more than
#: this fraction of the face's longest edge (round-off on flat configurations is not a fold).
FOLD_TOL = 1e-9


class TetMesh(SimplexMesh):
    """An immutable, validated tetrahedral mesh.

    Parameters
    ----------
    V : (n, 3) array_like of float
        Vertex positions. Must be finite, within ``±1e40`` and at least ``1e-40`` across, as for ``TriMesh``.
    T : (k, 4) array_like of int
        Tetrahedra as 0-based vertex indices, in any orientation. Every index must lie in
        ``[0, n)`` and the four indices of a tetrahedron must be distinct.
    vertex_map : (n,) array_like of int, optional
        Index of each vertex in the file it was read from (default ``arange(n)``).
    name : str, optional
        Label used in messages (usually the file name).
    file_index : (n_file,) array_like of int, optional
        For each vertex of the file, its index in this mesh, or -1 for a vertex the reader dropped
        (in no tetrahedron). Default ``arange(n)``.
    dropped_vertices : (d, 3) array_like of float, optional
        Positions of the file vertices with ``file_index == -1``, in file order.
    notes : sequence of str, optional
        One line per repair the reader made. :attr:`notes` adds the mesh's own findings.

    Raises
    ------
    MeshError
        An array of the wrong shape or type, empty, a non-finite or huge coordinate, an index out
        of range or a tetrahedron repeating a vertex (the message names the parameter and the
        first bad index).

    Notes
    -----
    Degenerate (flat or tiny) tetrahedra, mixed orientations, folds and faces shared by more than
    two tetrahedra are accepted and *reported*: :meth:`degenerate_tets`, :attr:`folded_faces`,
    :attr:`nonmanifold_faces` and the lines of :attr:`notes`. Vertices in no tetrahedron are
    allowed (their own components, infinite distance).

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    >>> mesh = TetMesh(V, [[0, 2, 1, 3]])  # negatively oriented: accepted
    >>> round(float(mesh.total_volume), 6), mesh.boundary_facets.shape, mesh.is_manifold
    (0.166667, (4, 3), True)
    """

    dim = 3
    reference = TETRAHEDRON
    domain = "volume"
    default_name = "tetmesh"
    count_name = "n_tets"

    @property
    def T(self) -> np.ndarray:
        """(k, 4) int64 ndarray, read-only: the tetrahedra (:attr:`cells`)."""
        return self.cells

    @property
    def n_tets(self) -> int:
        """Number of tetrahedra."""
        return self.n_cells

    def __init__(self, V: ArrayLike, T: ArrayLike, *, vertex_map: ArrayLike | None = None, name: str | None = None,
                 file_index: ArrayLike | None = None, dropped_vertices: ArrayLike | None = None,
                 notes: Sequence[str] = ()) -> None:
        super().__init__(V, T, vertex_map=vertex_map, name=name, file_index=file_index,
                         dropped_vertices=dropped_vertices, notes=notes)

    # -- volumes and shape ------------------------------------------------------------------------------------
    @cached_property
    def signed_volumes(self) -> np.ndarray:
        """(k,) float ndarray: ``det[v1 − v0, v2 − v0, v3 − v0] / 6``, the sign from the vertex order."""
        V, T = self.V, self.T
        a, b, c = (V[T[:, i]] - V[T[:, 0]] for i in (1, 2, 3))
        return np.einsum("ij,ij->i", a, np.cross(b, c)) / 6.0

    @cached_property
    def volumes(self) -> np.ndarray:
        """(k,) float ndarray: volume of each tetrahedron (``|signed_volumes|``)."""
        return np.abs(self.signed_volumes)

    @cached_property
    def total_volume(self) -> float:
        """Sum of :attr:`volumes` (overlapping tetrahedra of a folded mesh count twice)."""
        return float(self.volumes.sum())

    @cached_property
    def positive_tets(self) -> np.ndarray:
        """(k, 4) int64 ndarray: ``T`` with vertices 2 and 3 swapped on rows of negative signed volume."""
        P = self.T.copy()
        neg = self.signed_volumes < 0
        P[neg, 2], P[neg, 3] = self.T[neg, 3], self.T[neg, 2]
        P.setflags(write=False)
        return P

    @cached_property
    def cell_facet_measures(self) -> np.ndarray:
        """(k, 4) float ndarray: area of the face opposite each local vertex."""
        V, T = self.V, self.T
        out = np.empty((self.n_tets, 4))
        for i, (a, b, c) in enumerate(TETRAHEDRON.facets):
            out[:, i] = 0.5 * np.linalg.norm(np.cross(V[T[:, b]] - V[T[:, a]], V[T[:, c]] - V[T[:, a]]), axis=1)
        return out

    @property
    def cell_measures(self) -> np.ndarray:
        """(k,) float ndarray: the cells' measures, :attr:`volumes`."""
        return self.volumes

    def _with_vertices(self, V: np.ndarray) -> TetMesh:
        return TetMesh(V, self.T, vertex_map=self.vertex_map, name=self.name, file_index=self.file_index,
                       dropped_vertices=self.dropped_vertices, notes=self._reader_notes)

    def degenerate_tets(self, tol: float = DEGENERATE_TET_TOL) -> np.ndarray:
        """Tetrahedra too flat or too small for the gradient-based operators: slivers with four nearly coplanar
        corners, needles, caps, wedges (zero volume included) and specks (:meth:`SimplexMesh.degenerate_cells`).

        Parameters
        ----------
        tol : float
            Relative threshold (default :data:`DEGENERATE_TET_TOL` = 1e-3); 0 selects only
            tetrahedra of exactly zero volume.

        Returns
        -------
        (d,) int64 ndarray
            Sorted indices of the degenerate tetrahedra.
        """
        return self.degenerate_cells(tol)

    # -- faces and the boundary -------------------------------------------------------------------------------
    faces, tet_faces, face_tet_counts = _cached_parts(
        "_facet_data", "(f, 3) int64 ndarray: unique triangular faces (each row sorted), lexicographically sorted.",
        "(k, 4) int64 ndarray: index into :attr:`faces` of the face opposite each local vertex.",
        "(f,) int64 ndarray: number of tetrahedra sharing each face of :attr:`faces`.")

    @cached_property
    def _boundary_slots(self) -> tuple[np.ndarray, np.ndarray]:
        """(tet, local vertex) of every face that belongs to a single tetrahedron."""
        t, i = np.nonzero(self.face_tet_counts[self.tet_faces] == 1)
        return t, i

    @cached_property
    def boundary_facets(self) -> np.ndarray:
        """(b, 3) int64 ndarray: faces of a single tetrahedron, oriented with normals pointing out of it.

        On a manifold mesh this is the closed boundary surface, outward oriented; faces shared by
        more than two tetrahedra are not boundary faces (see :attr:`nonmanifold_faces`).
        """
        t, i = self._boundary_slots
        return self.positive_tets[t[:, None], TETRAHEDRON.facets[i]].astype(np.int64)

    @cached_property
    def boundary_face_tets(self) -> np.ndarray:
        """(b,) int64 ndarray: the tetrahedron of each row of :attr:`boundary_facets`."""
        return self._boundary_slots[0].astype(np.int64)

    @cached_property
    def boundary_vertices(self) -> np.ndarray:
        """(v,) int64 ndarray: sorted indices of the vertices of :attr:`boundary_facets`."""
        return np.unique(self.boundary_facets).astype(np.int64)

    @cached_property
    def boundary_area(self) -> float:
        """Total area of :attr:`boundary_facets`."""
        V, B = self.V, self.boundary_facets
        return float(0.5 * np.linalg.norm(np.cross(V[B[:, 1]] - V[B[:, 0]], V[B[:, 2]] - V[B[:, 0]]), axis=1).sum())

    def boundary_mesh(self) -> TriMesh:
        """The boundary surface as a :class:`TriMesh` on all of ``V`` (interior vertices unreferenced).

        Returns
        -------
        TriMesh
            Faces :attr:`boundary_facets` (outward), the same vertex numbering as this mesh.

        Raises
        ------
        MeshError
            If the mesh has no boundary face (every face shared: impossible for a finite manifold mesh).
        """
        if self.boundary_facets.shape[0] == 0:
            raise MeshError(f"{self.name}: the mesh has no boundary faces")
        return TriMesh(self.V, self.boundary_facets, name=f"{self.name} (boundary)")

    @cached_property
    def nonmanifold_faces(self) -> np.ndarray:
        """(j,) int64 ndarray: indices into :attr:`faces` of faces shared by more than two tetrahedra."""
        return np.flatnonzero(self.face_tet_counts > 2).astype(np.int64)

    @cached_property
    def is_manifold(self) -> bool:
        """True when every face belongs to one (boundary) or two (interior) tetrahedra.

        Tetrahedra that touch along an edge or at a vertex only are not detected by this test.
        """
        return self.nonmanifold_faces.size == 0

    @cached_property
    def folded_faces(self) -> np.ndarray:
        """(j,) int64 ndarray: interior faces whose two tetrahedra lie on the same side of them.

        On a valid mesh the two tetrahedra sharing a face are on opposite sides of it; when one of
        them is inverted (e.g. a deformed mesh) they overlap. Independent of the vertex order of
        the rows of ``T``. Only faces shared by exactly two tetrahedra are checked.
        """
        counts = self.face_tet_counts
        slots = np.flatnonzero(counts[self.tet_faces.ravel()] == 2)
        if slots.size == 0:
            return np.empty(0, dtype=np.int64)
        face = self.tet_faces.ravel()[slots]
        order = np.argsort(face, kind="stable")
        slots, face = slots[order], face[order]
        t, i = slots // 4, slots % 4  # pairs: rows 2j and 2j + 1
        V, T = self.V, self.T
        F = self.faces[face[0::2]]
        a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
        nrm = np.cross(b - a, c - a)
        side1 = np.einsum("ij,ij->i", V[T[t[0::2], i[0::2]]] - a, nrm)
        side2 = np.einsum("ij,ij->i", V[T[t[1::2], i[1::2]]] - a, nrm)
        longest = np.max([np.linalg.norm(b - a, axis=1), np.linalg.norm(c - b, axis=1),
                          np.linalg.norm(a - c, axis=1)], axis=0)
        tol = FOLD_TOL * longest * np.linalg.norm(nrm, axis=1)
        folded = ((side1 > tol) & (side2 > tol)) | ((side1 < -tol) & (side2 < -tol))
        return np.sort(face[0::2][folded]).astype(np.int64)

    # -- findings ---------------------------------------------------------------------------------------------
    @cached_property
    def notes(self) -> tuple[str, ...]:
        """The reader's notes, then one line per finding: degenerate tetrahedra (at
        :data:`DEGENERATE_TET_TOL`), mixed orientation, folds, non-manifold faces, unreferenced vertices.

        Computed on first access (it needs the faces), then cached.
        """
        out = list(self._reader_notes)
        deg = self.degenerate_tets()
        if deg.size:
            zero = int(np.count_nonzero(self.volumes[deg] == 0))
            out.append(f"{self.name}: {deg.size} degenerate tetrahedra (smallest altitude below "
                       f"{DEGENERATE_TET_TOL:g} of the longest edge or of the mean edge length; {zero} of zero "
                       f"volume; first: tet {int(deg[0])})")
        neg = int(np.count_nonzero(self.signed_volumes < 0))
        pos = int(np.count_nonzero(self.signed_volumes > 0))
        if neg and pos:
            minority, sign = (neg, "negative") if neg <= pos else (pos, "positive")
            first = int(np.flatnonzero(self.signed_volumes < 0 if sign == "negative" else self.signed_volumes > 0)[0])
            out.append(f"{self.name}: {minority} of {self.n_tets} tetrahedra have {sign} orientation (first: tet "
                       f"{first}); orientation is free, volumes are taken as absolute values")
        fold = self.folded_faces
        if fold.size:
            out.append(f"{self.name}: {fold.size} interior faces have both their tetrahedra on the same side (the "
                       f"mesh folds over itself: inverted tetrahedra; first: face {self.faces[fold[0]].tolist()})")
        nm = self.nonmanifold_faces
        if nm.size:
            out.append(f"{self.name}: not manifold: {nm.size} faces are shared by more than two tetrahedra (first: "
                       f"face {self.faces[nm[0]].tolist()}, {int(self.face_tet_counts[nm[0]])} tetrahedra)")
        unref = np.flatnonzero(~self.referenced)
        if unref.size:
            out.append(f"{self.name}: {unref.size} vertices are in no tetrahedron (first: vertex {int(unref[0])}); "
                       "they get an infinite distance")
        return tuple(out)

