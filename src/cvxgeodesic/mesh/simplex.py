"""What a triangle mesh and a tetrahedral mesh share: a simplicial mesh of dimension 2 or 3.

:class:`SimplexMesh` is the base of :class:`~cvxgeodesic.mesh.trimesh.TriMesh` (``dim = 2``, cells are the
triangles ``F``) and :class:`~cvxgeodesic.mesh.tetmesh.TetMesh` (``dim = 3``, cells are the tetrahedra ``T``).
Everything an algorithm needs that does not depend on the dimension is here, under one vocabulary, so that a
formulation, a source resolution or a path descent is written once over ``cells``:

==================  ============================================================================
``dim``             the simplex dimension (2: triangles, 3: tetrahedra)
``cells``           (k, dim + 1) int64 vertex indices
``cell_measures``   (k,) areas or volumes; ``total_measure`` their sum
``cell_edges``      (k, 3) or (k, 6) indices into ``edges`` (:data:`CELL_EDGES` gives the local pairs)
``facets``          the (dim − 1)-faces of a cell (:data:`CELL_FACETS`: the facet opposite each corner)
``boundary_facets`` (b, dim) the facets of a single cell: boundary edges of a surface, faces of a solid
==================  ============================================================================

The subclasses provide ``cells``, ``cell_measures``, the measures of each cell's facets
(``cell_facet_measures``) and ``_with_vertices`` (a copy on other coordinates, for :func:`unit_mesh`).
"""

from __future__ import annotations

import math
from functools import cached_property
from typing import Any, TypeVar

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike
from scipy.sparse.csgraph import connected_components

__all__ = ["CELL_EDGES", "CELL_FACETS", "SimplexMesh", "unit_mesh", "unit_scale"]

#: Local vertex pairs of a cell's edges, per dimension. Triangles: the edge opposite corner ``k`` in column ``k``
#: (``TriMesh.face_edges``); tetrahedra: the order of ``TetMesh.tet_edges``.
CELL_EDGES = {
    2: np.array([[1, 2], [2, 0], [0, 1]], dtype=np.int64),
    3: np.array([[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]], dtype=np.int64),
}
#: Local vertices of the facet opposite corner ``i`` (row ``i``). Tetrahedra: ordered so that the face's normal
#: ``(b − a) × (c − a)`` points away from corner ``i`` when the signed volume is positive.
CELL_FACETS = {
    2: CELL_EDGES[2],
    3: np.array([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]], dtype=np.int64),
}

MeshT = TypeVar("MeshT", bound="SimplexMesh")


class SimplexMesh:
    """A validated simplicial mesh in 3-D space: vertices ``V`` (n, 3) and cells of ``dim + 1`` vertices.

    Not built directly: :class:`~cvxgeodesic.mesh.trimesh.TriMesh` and :class:`~cvxgeodesic.mesh.tetmesh.TetMesh`
    validate their arrays and derive from it.

    Attributes
    ----------
    dim : int
        2 for triangles, 3 for tetrahedra.
    V : (n, 3) float64 ndarray, read-only
    name : str
    """

    dim: int
    V: np.ndarray
    name: str
    file_index: np.ndarray

    @property
    def cells(self) -> np.ndarray:
        """(k, dim + 1) int64 ndarray: the triangles or tetrahedra."""
        raise NotImplementedError

    @property
    def cell_measures(self) -> np.ndarray:
        """(k,) float ndarray: the area of each triangle or the volume of each tetrahedron."""
        raise NotImplementedError

    @property
    def cell_facet_measures(self) -> np.ndarray:
        """(k, dim + 1) float ndarray: the length (area) of the facet opposite each corner."""
        raise NotImplementedError

    def _with_vertices(self: MeshT, V: np.ndarray) -> MeshT:
        """The same mesh (cells, numbering, name) on the coordinates ``V``."""
        raise NotImplementedError

    @property
    def n_vertices(self) -> int:
        return int(self.V.shape[0])

    @property
    def n_cells(self) -> int:
        return int(self.cells.shape[0])

    @property
    def n_file_vertices(self) -> int:
        """Number of vertices in the file the mesh was read from (``n_vertices`` when not from a file)."""
        return int(self.file_index.shape[0])

    @cached_property
    def total_measure(self) -> float:
        """Sum of :attr:`cell_measures`: the surface area or the volume."""
        return float(self.cell_measures.sum())

    # -- edges ----------------------------------------------------------------------------------------------------
    def _sub_simplices(self, local: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The unique sub-simplices of the cells whose local corners are the rows of ``local`` (l, s).

        Returns
        -------
        unique : (u, s) int64 ndarray
            Each row sorted, rows in lexicographic order.
        per_cell : (k, l) int64 ndarray
            Index into ``unique`` of each cell's sub-simplices, in the order of ``local``.
        counts : (u,) int64 ndarray
            How many cells share each one.
        """
        rows = np.sort(self.cells[:, local].reshape(-1, local.shape[1]), axis=1)
        n, s = self.n_vertices, rows.shape[1]
        if n ** s < 2**62:  # one 1-D key per row: ~10x faster than np.unique(axis=0) on million-cell meshes
            keys = rows[:, 0].copy()
            for j in range(1, s):
                keys = keys * np.int64(n) + rows[:, j]
            uniq, inv, counts = np.unique(keys, return_inverse=True, return_counts=True)
            unique = np.empty((uniq.size, s), dtype=np.int64)
            for j in reversed(range(s)):
                unique[:, j] = uniq % n
                uniq = uniq // n
        else:
            unique, inv, counts = np.unique(rows, axis=0, return_inverse=True, return_counts=True)
        return unique.astype(np.int64), inv.reshape(self.n_cells, -1).astype(np.int64), counts.astype(np.int64)

    @cached_property
    def _edge_data(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self._sub_simplices(CELL_EDGES[self.dim])

    @cached_property
    def edges(self) -> np.ndarray:
        """(e, 2) int64 ndarray: unique undirected edges, ``edges[:, 0] < edges[:, 1]``, sorted."""
        return self._edge_data[0]

    @cached_property
    def cell_edges(self) -> np.ndarray:
        """(k, 3) or (k, 6) int64 ndarray: index into :attr:`edges` of each cell's edges (:data:`CELL_EDGES`)."""
        return self._edge_data[1]

    @cached_property
    def edge_cell_counts(self) -> np.ndarray:
        """(e,) int64 ndarray: number of cells incident to each edge of :attr:`edges`."""
        return self._edge_data[2]

    @cached_property
    def edge_lengths(self) -> np.ndarray:
        """(e,) float ndarray: Euclidean length of each edge of :attr:`edges`."""
        E = self.edges
        return np.linalg.norm(self.V[E[:, 0]] - self.V[E[:, 1]], axis=1)

    @cached_property
    def mean_edge_length(self) -> float:
        """Mean length of the unique edges (``h`` in the paper's λ formula)."""
        return float(self.edge_lengths.mean()) if len(self.edge_lengths) else 0.0

    @cached_property
    def bbox_diagonal(self) -> float:
        """Length of the diagonal of the axis-aligned bounding box."""
        return float(np.linalg.norm(self.V.max(axis=0) - self.V.min(axis=0)))

    # -- cell quality -----------------------------------------------------------------------------------------
    @cached_property
    def cell_longest_edges(self) -> np.ndarray:
        """(k,) float ndarray: length of the longest edge of each cell."""
        return self.edge_lengths[self.cell_edges].max(axis=1)

    @cached_property
    def cell_min_altitudes(self) -> np.ndarray:
        """(k,) float ndarray: smallest corner-to-opposite-facet distance, ``dim · measure / largest facet``.

        The gradients of the hat functions have lengths ``1 / altitude``: this length decides how ill-conditioned a
        cell's gradient and stiffness are. 0 for a cell whose corners coincide.
        """
        largest = self.cell_facet_measures.max(axis=1)
        alt = np.zeros(self.n_cells)
        np.divide(self.dim * self.cell_measures, largest, out=alt, where=largest > 0)
        return alt

    def degenerate_cells(self, tol: float = 1e-3) -> np.ndarray:
        """Cells too thin or too small for the gradient-based operators.

        A cell is degenerate when its smallest altitude :attr:`cell_min_altitudes` is below ``tol`` times its
        longest edge (a sliver: zero measure, needles, caps, wedges) or below ``tol`` times
        :attr:`mean_edge_length` (a speck). The gradient of such a cell has entries of order ``1 / altitude``,
        which makes the cone constraints and the energies numerically singular; the convex formulations leave
        these cells out.

        Parameters
        ----------
        tol : float
            Relative threshold (default 1e-3, ``DEGENERATE_TOL``); 0 selects only cells of exactly zero measure.

        Returns
        -------
        (d,) int64 ndarray
            Sorted indices of the degenerate cells.
        """
        alt = self.cell_min_altitudes
        bad = (alt <= tol * self.cell_longest_edges) | (alt <= tol * self.mean_edge_length)
        return np.flatnonzero(bad).astype(np.int64)

    # -- the edge graph ---------------------------------------------------------------------------------------
    @cached_property
    def vertex_adjacency(self) -> sp.csr_matrix:
        """(n, n) sparse matrix with the edge lengths of the edge graph (symmetric)."""
        n = self.n_vertices
        E, w = self.edges, self.edge_lengths
        A = sp.coo_matrix((np.r_[w, w], (np.r_[E[:, 0], E[:, 1]], np.r_[E[:, 1], E[:, 0]])), shape=(n, n))
        return A.tocsr()

    @cached_property
    def component_labels(self) -> np.ndarray:
        """(n,) int ndarray: connected-component label of each vertex (edge graph)."""
        return connected_components(self.vertex_adjacency, directed=False)[1]

    @cached_property
    def n_components(self) -> int:
        """Number of connected components of the edge graph (an unreferenced vertex is one)."""
        return int(self.component_labels.max()) + 1

    @cached_property
    def referenced(self) -> np.ndarray:
        """(n,) bool ndarray: vertices of at least one cell."""
        mask = np.zeros(self.n_vertices, dtype=bool)
        mask[self.cells.ravel()] = True
        return mask

    def connected_to(self, sources: ArrayLike) -> np.ndarray:
        """Vertices connected to at least one of ``sources`` through the edge graph.

        Parameters
        ----------
        sources : (s,) int array_like
            Valid vertex indices.

        Returns
        -------
        (n,) bool ndarray
            Includes the sources themselves (an unreferenced source is its own component).
        """
        labels = self.component_labels
        return np.isin(labels, labels[np.asarray(sources, dtype=np.int64)])


def unit_scale(mesh: Any) -> float:
    """The power of two ``s`` that puts ``mesh``'s bounding-box diagonal in [0.5, 1) when divided by it (1.0 for a
    zero-size mesh): :func:`unit_mesh`'s, for the methods that scale their own copy of the coordinates."""
    diag = mesh.bbox_diagonal
    if not (np.isfinite(diag) and diag > 0):
        return 1.0
    return math.ldexp(1.0, math.frexp(diag)[1])


def unit_mesh(mesh: MeshT) -> tuple[MeshT, float]:
    """The mesh divided by the power of two ``s`` that puts its bounding-box diagonal in [0.5, 1), and ``s``.

    Every method is solved on this copy (the baselines on its coordinates, :func:`unit_scale`) and the field is
    multiplied by ``s``: the backends' and libraries' absolute tolerances then mean the same thing on a mesh of any
    size (without it a 1e-6-sized mesh lost three digits in the convex formulations, and pygeodesic returned
    infinite or 24x too small distances below 1e-12), and since ``s`` is a power of two the division is exact, so
    ``d(2^k V) = 2^k d(V)`` to the last bit.

    Parameters
    ----------
    mesh : TriMesh or TetMesh
        ``n`` vertices ``V`` (n, 3).

    Returns
    -------
    unit : TriMesh or TetMesh
        ``V / s`` with the same cells, vertex numbering and name (``mesh`` itself when ``s == 1``).
    s : float
        A power of two (1.0 for an empty or zero-size mesh).
    """
    scale = unit_scale(mesh)
    if scale == 1.0:
        return mesh, 1.0
    return mesh._with_vertices(mesh.V / scale), scale
