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


def _triangle_frame_coordinates(X: np.ndarray) -> np.ndarray:
    """(k, 3, 2) corners of triangles (k, 3, 3) in each one's plane: ``ex`` along corner 0→1, ``ey = n̂ × ex``."""
    e = X[:, 1] - X[:, 0]
    normal = np.cross(e, X[:, 2] - X[:, 0])
    with np.errstate(divide="ignore", invalid="ignore"):
        ex = e / np.linalg.norm(e, axis=1, keepdims=True)
        nhat = normal / np.linalg.norm(normal, axis=1, keepdims=True)
    ey = np.cross(nhat, ex)
    rel = X - X[:, :1]
    return np.stack([np.einsum("kvx,kx->kv", rel, ex), np.einsum("kvx,kx->kv", rel, ey)], axis=2)


def _world_coordinates(X: np.ndarray) -> np.ndarray:
    """A solid cell needs no frame: its corners in world coordinates."""
    return X


def _triangle_to_world(G: np.ndarray, X: np.ndarray) -> np.ndarray:
    """(k, m, 3) vectors ``G`` (k, 2, m) of each triangle's frame (:func:`_triangle_frame_coordinates`) in the
    world: ``G_x ex + G_y ey``."""
    e = X[:, 1] - X[:, 0]
    normal = np.cross(e, X[:, 2] - X[:, 0])
    with np.errstate(divide="ignore", invalid="ignore"):
        ex = e / np.linalg.norm(e, axis=1, keepdims=True)
        nhat = normal / np.linalg.norm(normal, axis=1, keepdims=True)
        ey = np.cross(nhat, ex)
        return G[:, 0, :, None] * ex[:, None, :] + G[:, 1, :, None] * ey[:, None, :]


def _world_to_world(G: np.ndarray, X: np.ndarray) -> np.ndarray:
    """A solid cell's frame is the world's: (k, m, 3) the vectors ``G`` (k, 3, m) as rows."""
    return np.ascontiguousarray(np.swapaxes(G, 1, 2))


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
    """

    name: str
    dim: int
    edges: np.ndarray
    facets: np.ndarray
    words: CellWords
    source_kinds: tuple[str, ...]
    measure_root: Callable[[Any], Any]
    _frame: Callable[[np.ndarray], np.ndarray] = field(repr=False)
    _point_type: str = field(repr=False)
    _locator: str = field(repr=False)
    _to_world: Callable[[np.ndarray, np.ndarray], np.ndarray] = field(repr=False)

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

    @property
    def point_type(self) -> type:
        """The :class:`~cvxgeodesic.mesh.locate.CellPoint` subclass of a point in such a cell."""
        return getattr(importlib.import_module("cvxgeodesic.mesh.locate"), self._point_type)

    @property
    def locate(self) -> Callable[..., Any]:
        """``locate(mesh, X)``: the point(s) of the mesh at positions ``X`` (closest on a surface, inside a solid)."""
        return getattr(importlib.import_module("cvxgeodesic.mesh.locate"), self._locator)

    def __repr__(self) -> str:
        return f"ReferenceSimplex({self.name!r})"


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
                    argument="faces"),
    source_kinds=("vertex", "point", "curve", "boundary"),
    measure_root=np.sqrt,
    _frame=_triangle_frame_coordinates, _point_type="SurfacePoint", _locator="surface_point",
    _to_world=_triangle_to_world,
)

TETRAHEDRON = ReferenceSimplex(
    name="tetrahedron", dim=3,
    edges=_readonly([[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]]),
    facets=_readonly([[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]]),
    words=CellWords(one="tetrahedron", many="tetrahedra", short="tets", shape="(k, 4)", measure="volume",
                    mesh="a tetrahedral volume", meshes="tetrahedral meshes", preposition="in",
                    domain="inside a volume", argument="tets"),
    source_kinds=("vertex", "point", "boundary", "boundary faces"),
    measure_root=np.cbrt,
    _frame=_world_coordinates, _point_type="VolumePoint", _locator="volume_point", _to_world=_world_to_world,
)
