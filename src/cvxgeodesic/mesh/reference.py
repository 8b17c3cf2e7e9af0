"""The reference simplex of each cell kind: what shared code asks instead of branching on a dimension.

A mesh class carries one (``SimplexMesh.reference``), as scikit-fem's meshes carry ``RefTri`` / ``RefTet`` and
Basix names a cell: the local edges and facets of a cell, the words its messages use, the measure root that turns
the total measure into a length, the kinds of source it takes, its point type and locator, and the map of a cell's
corners into an orthonormal frame of its affine hull (:meth:`ReferenceSimplex.local_coordinates`). A new kind of
cell is a new instance here (docs/architecture.md, "A domain"); nothing in shared code tests ``dim``.

The point type and the locator live in :mod:`cvxgeodesic.mesh.locate`, which imports the mesh classes; they are
named here and imported when first asked, so this module stays below the mesh classes.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["TETRAHEDRON", "TRIANGLE", "CellWords", "ReferenceSimplex"]


@dataclass(frozen=True)
class CellWords:
    """How messages name a cell kind and the meshes made of it.

    Attributes
    ----------
    one, many : str
        A cell and cells (``"face"``/``"faces"``, ``"tetrahedron"``/``"tetrahedra"``).
    short : str
        The short plural of messages that count cells (``"faces"``, ``"tets"``).
    shape : str
        The array shape of the cells as messages write it (``"(m, 3)"``).
    measure : str
        What a cell's measure is called (``"area"``, ``"volume"``).
    mesh : str
        A mesh of these cells (``"a triangle surface"``, ``"a tetrahedral volume"``).
    meshes : str
        Such meshes, in the plural (``"triangle meshes"``).
    preposition : str
        A point is ``"on"`` a face and ``"in"`` a tetrahedron.
    domain : str
        Where a point of such a mesh lies (``"on a surface"``, ``"inside a volume"``).
    argument : str
        The name of the cell-index argument of :meth:`distance_at`-like calls (``"faces"``, ``"tets"``).
    shape_hint : str
        Said after the shape when the cell array has the wrong one (triangles: polygons are fan-triangulated by
        ``load_mesh``, not by the mesh class).
    repeat_remedy : str
        What to do about a cell that repeats a vertex.
    """

    one: str
    many: str
    short: str
    shape: str
    measure: str
    mesh: str
    meshes: str
    preposition: str
    domain: str
    argument: str
    shape_hint: str = ""
    repeat_remedy: str = "remove them first"


def _triangle_axes(X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(k, 3) each, the orthonormal frame of triangles (k, 3, 3): ``ex`` along corner 0→1, ``ey = n̂ × ex`` (NaN on
    triangles of zero area, without a warning)."""
    e = X[:, 1] - X[:, 0]
    normal = np.cross(e, X[:, 2] - X[:, 0])
    with np.errstate(divide="ignore", invalid="ignore"):
        ex = e / np.linalg.norm(e, axis=1, keepdims=True)
        nhat = normal / np.linalg.norm(normal, axis=1, keepdims=True)
        ey = np.cross(nhat, ex)
    return ex, ey


def _triangle_frame_coordinates(X: np.ndarray) -> np.ndarray:
    """(k, 3, 2) corners of triangles (k, 3, 3) in each one's plane (:func:`_triangle_axes`), corner 0 at 0."""
    ex, ey = _triangle_axes(X)
    rel = X - X[:, :1]
    return np.stack([np.einsum("kvx,kx->kv", rel, ex), np.einsum("kvx,kx->kv", rel, ey)], axis=2)


def _world_coordinates(X: np.ndarray) -> np.ndarray:
    """A solid cell needs no frame: its corners in world coordinates."""
    return X


def _triangle_to_world(G: np.ndarray, X: np.ndarray) -> np.ndarray:
    """(k, m, 3) vectors ``G`` (k, 2, m) of each triangle's frame (:func:`_triangle_frame_coordinates`) in the
    world: ``G_x ex + G_y ey``."""
    ex, ey = _triangle_axes(X)
    return G[:, 0, :, None] * ex[:, None, :] + G[:, 1, :, None] * ey[:, None, :]


def _world_to_world(G: np.ndarray, X: np.ndarray) -> np.ndarray:
    """A solid cell's frame is the world's: (k, m, 3) the vectors ``G`` (k, 3, m) as rows."""
    return np.ascontiguousarray(np.swapaxes(G, 1, 2))


def _triangle_normals(X: np.ndarray) -> np.ndarray:
    """(k, 1, 3) the normal ``(b − a) × (c − a)`` of triangles (k, 3, 3), of length twice the area."""
    return np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0])[:, None, :]


def _no_normals(X: np.ndarray) -> np.ndarray:
    """A solid cell spans space: (k, 0, 3)."""
    return np.zeros((X.shape[0], 0, 3))


@dataclass(frozen=True, eq=False)
class ReferenceSimplex:
    """One cell kind: a simplex of dimension :attr:`dim` embedded in 3-D.

    Attributes
    ----------
    name : str
        ``"triangle"``, ``"tetrahedron"``.
    dim : int
        The simplex dimension (a cell has ``dim + 1`` corners).
    edges : (dim (dim + 1) / 2, 2) int64 ndarray
        Local corner pairs of a cell's edges. Triangles: the edge opposite corner ``k`` in row ``k``.
    facets : (dim + 1, dim) int64 ndarray
        Local corners of the facet opposite corner ``i`` (row ``i``). Tetrahedra: ordered so that the normal
        ``(b − a) × (c − a)`` points away from corner ``i`` when the signed volume is positive.
    words : CellWords
        How messages name the cells.
    source_kinds : tuple of str
        The kinds of source (:data:`cvxgeodesic.capabilities.SOURCE_KINDS`) a mesh of these cells takes.
    measure_root : callable
        Turns a total measure (area, volume) into a length: ``np.sqrt``, ``np.cbrt``.
    shared_points : bool
        Whether a point source on the boundary of a cell (a triangle's edge) is listed in every cell around it, so
        that its bounds hold in each (triangles), or only in the cell it was given in (tetrahedra)
        (:func:`cvxgeodesic.sources.resolve_sources`).
    picture : str
        How a field on such a mesh is drawn: ``"surface"``, the cells themselves seen from a camera
        (:func:`~cvxgeodesic.plotting.plot_field`, :func:`~cvxgeodesic.viewer.show`); ``"slice"``, a plane's cut through
        a solid, the cells hiding one another (:func:`~cvxgeodesic.evaluation.slice_plot.plot_slice`,
        :func:`~cvxgeodesic.viewer.show_volume`).
    libigl_operators : bool
        The cells are triangles that libigl's surface operators take: the stiffness and lumped (mixed-Voronoi) mass
        of a whole mesh come from ``igl.cotmatrix`` / ``igl.massmatrix`` (:mod:`cvxgeodesic.operators.laplacian`);
        otherwise from the library's own gradient blocks (barycentric mass).
    coneless_cell_edges : bool
        The order-1 QC programs bound ``|d_i − d_j| ≤ l_ij`` on every edge of a cell that carries no cone (next to a
        source, a point's cell, a degenerate cell): a tetrahedron's cone does not cover all the edges its
        neighbours share with it. False (triangles): the source stars and the degenerate cells' edges are bounded
        instead (:func:`cvxgeodesic.problems.formulations.build_problem`).
    point_type, locate
        Given as objects, or as names in :mod:`cvxgeodesic.mesh.locate` (imported when first asked).
    """

    name: str
    dim: int
    edges: np.ndarray
    facets: np.ndarray
    words: CellWords
    source_kinds: tuple[str, ...]
    measure_root: Callable[[Any], Any]
    shared_points: bool
    _frame: Callable[[np.ndarray], np.ndarray] = field(repr=False)
    _to_world: Callable[[np.ndarray, np.ndarray], np.ndarray] = field(repr=False)
    _point_type: str | type = field(repr=False)
    _locator: str | Callable[..., Any] = field(repr=False)
    picture: str = "surface"
    libigl_operators: bool = False
    coneless_cell_edges: bool = False
    _normals: Callable[[np.ndarray], np.ndarray] = field(repr=False, default=_no_normals)

    @property
    def n_corners(self) -> int:
        """Corners of a cell: ``dim + 1``."""
        return self.dim + 1

    def local_coordinates(self, X: np.ndarray) -> np.ndarray:
        """The corners of each cell in an orthonormal frame of its affine hull.

        Parameters
        ----------
        X : (k, dim + 1, 3) float ndarray
            The cells' corners in world coordinates.

        Returns
        -------
        (k, dim + 1, dim) float ndarray
            Triangles: in each face's 2-D frame (corner 0 at the origin, ``ex`` along corner 0→1); tetrahedra: the
            world coordinates. NaN on triangles of zero area (their frame is undefined).

        Examples
        --------
        >>> import numpy as np
        >>> X = np.array([[[0.0, 0, 0], [2, 0, 0], [0, 3, 0]]])
        >>> TRIANGLE.local_coordinates(X).round(6).tolist()
        [[[0.0, 0.0], [2.0, 0.0], [0.0, 3.0]]]
        """
        return self._frame(X)

    def to_world(self, G: np.ndarray, X: np.ndarray) -> np.ndarray:
        """Vectors given in each cell's frame (:meth:`local_coordinates`), in world coordinates.

        Parameters
        ----------
        G : (k, dim, m) float ndarray
            ``m`` vectors per cell, their frame components along axis 1 (the layout of
            :func:`~cvxgeodesic.operators.gradient.gradient_blocks`).
        X : (k, dim + 1, 3) float ndarray
            The cells' corners in world coordinates.

        Returns
        -------
        (k, m, 3) float ndarray
            Triangles: ``G_x ex + G_y ey`` (in each face's plane; NaN on faces of zero area); tetrahedra: ``G``
            itself, transposed.

        Examples
        --------
        >>> import numpy as np
        >>> X = np.array([[[0.0, 0, 0], [0, 2, 0], [0, 0, 3]]])  # a face in the y-z plane: ex = y
        >>> TRIANGLE.to_world(np.array([[[1.0], [0.0]]]), X).tolist()
        [[[0.0, 1.0, 0.0]]]
        """
        return self._to_world(G, X)

    def normals(self, X: np.ndarray) -> np.ndarray:
        """Normals of each cell's affine hull in 3-D, of any length.

        Parameters
        ----------
        X : (k, dim + 1, 3) float ndarray
            The cells' corners.

        Returns
        -------
        (k, 3 − dim, 3) float ndarray
            Triangles: ``(b − a) × (c − a)`` (twice the area long); tetrahedra span space: none.
        """
        return self._normals(X)

    @property
    def point_type(self) -> type[Any]:  # a CellPoint subclass: mesh.locate is above this module
        """The :class:`~cvxgeodesic.mesh.locate.CellPoint` subclass of a point in such a cell."""
        return _resolve(self._point_type)

    @property
    def locate(self) -> Callable[..., Any]:
        """``locate(mesh, X)``: the point(s) of the mesh at positions ``X`` (closest on a surface, inside a solid)."""
        return _resolve(self._locator)

    def __repr__(self) -> str:
        return f"ReferenceSimplex({self.name!r})"


def _resolve(member: Any) -> Any:
    """A member given by its name in :mod:`cvxgeodesic.mesh.locate` (imported now), or the object itself."""
    return getattr(importlib.import_module("cvxgeodesic.mesh.locate"), member) if isinstance(member, str) else member


def _readonly(a: list[list[int]]) -> np.ndarray:
    out = np.array(a, dtype=np.int64)
    out.setflags(write=False)
    return out


TRIANGLE = ReferenceSimplex(
    name="triangle", dim=2,
    edges=_readonly([[1, 2], [2, 0], [0, 1]]),
    facets=_readonly([[1, 2], [2, 0], [0, 1]]),
    words=CellWords(one="face", many="faces", short="faces", shape="(m, 3)", measure="area",
                    mesh="a triangle surface", meshes="triangle meshes", preposition="on", domain="on a surface",
                    argument="faces", shape_hint=" (triangles only; load_mesh fan-triangulates polygons)",
                    repeat_remedy="remove degenerate faces first"),
    source_kinds=("vertex", "point", "curve", "boundary"),
    measure_root=np.sqrt, shared_points=True,
    _frame=_triangle_frame_coordinates, _to_world=_triangle_to_world, _point_type="SurfacePoint",
    _locator="surface_point",
    libigl_operators=True,
    _normals=_triangle_normals,
)

TETRAHEDRON = ReferenceSimplex(
    name="tetrahedron", dim=3,
    edges=_readonly([[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]]),
    facets=_readonly([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]]),
    words=CellWords(one="tetrahedron", many="tetrahedra", short="tets", shape="(k, 4)", measure="volume",
                    mesh="a tetrahedral volume", meshes="tetrahedral meshes", preposition="in",
                    domain="inside a volume", argument="tets"),
    source_kinds=("vertex", "point", "boundary", "boundary faces"),
    measure_root=np.cbrt, shared_points=False,
    _frame=_world_coordinates, _to_world=_world_to_world, _point_type="VolumePoint", _locator="volume_point",
    picture="slice", coneless_cell_edges=True,
)
