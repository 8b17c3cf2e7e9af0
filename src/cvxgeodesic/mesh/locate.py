"""Points located in the cells of a mesh: the point types, closest points on a surface, containing tetrahedra.

A point of a mesh is a cell and its barycentric coordinates (:class:`CellPoint`): a :class:`SurfacePoint` in a face
of a triangle mesh, a :class:`VolumePoint` in a tetrahedron. :func:`surface_point` finds the closest surface point
of a position (the AABB tree of :mod:`cvxgeodesic.mesh.closest`); :func:`volume_point` the tetrahedron containing a
position (:func:`locate_points`): a k-d tree on the tetrahedra's centroids gives, for each point, every tetrahedron
whose circumscribing ball around its centroid (radius: its farthest vertex) holds the point, and the barycentric
coordinates of those candidates decide. No Delaunay triangulation of the vertices is involved, so non-convex meshes
(an L-shaped prism) and meshes with holes work.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from typing import Any, overload

import numpy as np
from numpy.typing import ArrayLike

from ..errors import ParameterError, SourceError
from ..validation import as_points, as_vertex_field, is_integer, is_real
from .closest import closest_point_index
from .simplex import SimplexMesh
from .tetmesh import TetMesh
from .trimesh import TriMesh

__all__ = ["BARY_TOL", "INSIDE_TOL", "CellPoint", "SurfacePoint", "VolumePoint",
           "closest_points", "interpolate_at", "locate_points", "surface_point", "volume_point"]

#: Tolerance of the barycentric checks of :class:`SurfacePoint` (negative coordinates, sum ≠ 1).
BARY_TOL = 1e-9

#: A point counts as inside a tetrahedron when its smallest barycentric coordinate is ``>= -INSIDE_TOL``
#: (points on a shared face or on the boundary surface, up to round-off).
INSIDE_TOL = 1e-9


def _tet_barycentric(mesh: TetMesh, tets: np.ndarray, X: np.ndarray) -> np.ndarray:
    """(p, 4) barycentric coordinates of ``X[j]`` in ``T[tets[j]]``; NaN rows for tetrahedra of zero volume."""
    V, T = mesh.V, mesh.T[tets]
    out = np.empty((len(tets), 4))
    with np.errstate(divide="ignore", invalid="ignore"):
        for i, (a, b, c) in enumerate(mesh.reference.facets):
            pa = V[T[:, a]]
            nrm = np.cross(V[T[:, b]] - pa, V[T[:, c]] - pa)
            out[:, i] = np.einsum("ij,ij->i", nrm, X - pa) / np.einsum("ij,ij->i", nrm, V[T[:, i]] - pa)
    return out


def locate_points(mesh: TetMesh, points: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """The tetrahedron containing each point, and the point's barycentric coordinates in it.

    Parameters
    ----------
    mesh : TetMesh
    points : (p, 3) or (3,) float array_like

    Returns
    -------
    tets : (p,) int64 ndarray
        Index of the containing tetrahedron, ``-1`` for a point outside the mesh. A point on a
        shared face (or edge, vertex) gets the tetrahedron where it is deepest inside (largest
        smallest coordinate), so the answer is deterministic.
    bary : (p, 4) float ndarray
        Barycentric coordinates (clipped at 0 and renormalized); NaN rows for points outside.

    Raises
    ------
    ParameterError
        ``points`` not finite positions.
    """
    X = as_points(points, "points").reshape(-1, 3)
    tree, radius = mesh.centroid_tree
    # only points within ``radius`` of the bounding box can be within it of a centroid: the others are outside
    # without a search, whose squared distances overflow from coordinates of about 1e154 on (scipy's ValueError)
    near = np.flatnonzero(((X >= mesh.V.min(axis=0) - radius) & (X <= mesh.V.max(axis=0) + radius)).all(axis=1))
    cand = tree.query_ball_point(X[near], radius, return_sorted=False)
    counts = np.fromiter((len(c) for c in cand), dtype=np.int64, count=len(cand))
    point_of = np.repeat(near, counts)
    tet_of = np.fromiter((t for c in cand for t in c), dtype=np.int64, count=int(counts.sum()))
    tets = np.full(len(X), -1, dtype=np.int64)
    bary = np.full((len(X), 4), np.nan)
    if tet_of.size:
        B = _tet_barycentric(mesh, tet_of, X[point_of])
        depth = np.where(np.isnan(B).any(axis=1), -np.inf, B.min(axis=1))
        # best candidate per point: sort by (point, -depth) and take the first of each point
        order = np.lexsort((-depth, point_of))
        first = order[np.r_[True, point_of[order][1:] != point_of[order][:-1]]]
        ok = depth[first] >= -INSIDE_TOL
        p = point_of[first][ok]
        tets[p] = tet_of[first][ok]
        b = np.clip(B[first][ok], 0.0, None)
        bary[p] = b / b.sum(axis=1, keepdims=True)
    return tets, bary


class CellPoint:
    """A point of a mesh located in one of its cells: a cell index and ``dim + 1`` barycentric coordinates.

    The base of :class:`SurfacePoint` (a face of a triangle mesh, attribute ``face``) and :class:`VolumePoint` (a
    tetrahedron, attribute ``tet``); built through those, whose checks are these: the cell a non-negative integer
    (checked against the mesh when the point is used); the coordinates finite, each ``>= 0`` and summing to 1 (to
    :data:`BARY_TOL`; tiny negative round-off is clipped and the sum renormalized), else :class:`SourceError`.
    Immutable, hashable, equal when the cell and the coordinates are.

    Attributes
    ----------
    cell : int
    bary : (dim + 1,) float ndarray, read-only
        Each ``>= 0``, summing to 1.
    """

    #: The attribute naming the cell, the coordinate count, the cell and its plural in messages, the hint of a
    #: negative coordinate (set by each point type's class keywords).
    _field, _n_bary, _word, _cells, _outside = "cell", 0, "cell", "cells", "outside the cell"
    __slots__ = ("bary", "cell")
    cell: int
    bary: np.ndarray

    def __init_subclass__(cls, *, field: str, n_bary: int, word: str, cells: str, hint: str) -> None:
        super().__init_subclass__()
        cls._field, cls._n_bary, cls._word, cls._cells = field, n_bary, word, cells
        cls._outside = f"outside the {word}; {hint}"

    def __init__(self, cell: Any, bary: ArrayLike) -> None:
        name = type(self).__name__
        if not (is_integer(cell) or (is_real(cell) and float(cell).is_integer())):
            raise SourceError(f"{name} {self._field} must be a {self._word} index (int), got {cell!r}")
        f = int(cell)
        if f < 0:
            raise SourceError(f"{name} {self._field} index {f} is negative")
        where, k = f"{name}({self._field}={f}", self._n_bary
        try:
            b = np.asarray(bary, dtype=float).reshape(-1).copy()
        except (TypeError, ValueError):
            raise SourceError(f"{where}): bary must be {k} numbers, got {bary!r}") from None
        if b.shape != (k,):
            raise SourceError(f"{where}): bary must have {k} coordinates, got {b.size}")
        if not np.all(np.isfinite(b)):
            raise SourceError(f"{where}, bary={b.tolist()}): barycentric coordinates must be finite")
        if b.min() < -BARY_TOL:
            raise SourceError(f"{where}, bary={b.tolist()}): barycentric coordinates must be >= 0 (a negative one is "
                              f"{self._outside})")
        if abs(b.sum() - 1.0) > BARY_TOL:
            raise SourceError(f"{where}, bary={b.tolist()}): barycentric coordinates must sum to 1, they sum to "
                              f"{b.sum():.12g}")
        b = np.clip(b, 0.0, None)
        b /= b.sum()
        b.setflags(write=False)
        object.__setattr__(self, "cell", f)
        object.__setattr__(self, "bary", b)

    @classmethod
    def _exact(cls, cell: int, bary: np.ndarray):
        """A point of coordinates already checked and normalized, kept to the last bit (no renormalization)."""
        p = object.__new__(cls)
        b = np.array(bary, dtype=float)
        b.setflags(write=False)
        object.__setattr__(p, "cell", int(cell))
        object.__setattr__(p, "bary", b)
        return p

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(f"{type(self).__name__} is immutable")

    def __reduce__(self):
        return (type(self)._exact, (self.cell, np.array(self.bary)))

    def __getattr__(self, name: str) -> Any:
        if name == self._field:  # face / tet
            return self.cell
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self._field}={self.cell}, bary=[{', '.join(f'{x:.6g}' for x in self.bary)}])"

    def __eq__(self, other) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        return self.cell == other.cell and bool(np.array_equal(self.bary, other.bary))

    def __hash__(self) -> int:
        return hash((self.cell, self.bary.tobytes()))

    def check(self, mesh: SimplexMesh, label: str | None = None) -> None:
        """Raise :class:`SourceError` unless the cell is one of ``mesh``'s (``label`` starts the message)."""
        k = mesh.n_cells
        if self.cell >= k:
            head = f"{label} {self!r}" if label else repr(self)
            raise SourceError(f"{head}: {self._word} index {self.cell} is out of range: {mesh.name} has {k} "
                              f"{self._cells} (0..{k - 1})")

    def vertices(self, mesh: SimplexMesh) -> np.ndarray:
        """(dim + 1,) int64 ndarray: the vertices of the point's cell (the order of ``bary``)."""
        self.check(mesh)
        return mesh.cells[self.cell].copy()

    def position(self, mesh: SimplexMesh) -> np.ndarray:
        """(3,) float ndarray: the point's position on ``mesh``."""
        self.check(mesh)
        return bary_positions(mesh, np.array([self.cell]), self.bary[None])[0]


class SurfacePoint(CellPoint, field="face", n_bary=3, word="face", cells="faces",
                   hint="use surface_point(mesh, xyz) for the closest point"):
    """A point of the surface: a face index and barycentric coordinates (checks: :class:`CellPoint`).

    Parameters
    ----------
    face : int
        Face index.
    bary : (3,) float array_like
        Barycentric coordinates with respect to ``F[face]``.

    Examples
    --------
    >>> import cvxgeodesic as cg
    >>> p = cg.SurfacePoint(10, [0.2, 0.3, 0.5])
    >>> p.face, p.bary.tolist()
    (10, [0.2, 0.3, 0.5])
    """

    __slots__ = ()
    face: int

    def __init__(self, face: Any, bary: ArrayLike) -> None:
        super().__init__(face, bary)

    def position(self, mesh: SimplexMesh | tuple[ArrayLike, ArrayLike]) -> np.ndarray:
        """(3,) float ndarray: the point's position on ``mesh`` (a TriMesh or ``(V, F)``)."""
        return super().position(_mesh(mesh))


class VolumePoint(CellPoint, field="tet", n_bary=4, word="tetrahedron", cells="tetrahedra",
                  hint="use volume_point(mesh, xyz) to find the containing one"):
    """A point inside a tetrahedral mesh: a tetrahedron index and four barycentric coordinates (checks:
    :class:`CellPoint`).

    Parameters
    ----------
    tet : int
        Tetrahedron index.
    bary : (4,) float array_like
        Barycentric coordinates with respect to ``T[tet]``: the point is ``bary @ V[T[tet]]``
        (:meth:`~CellPoint.position`).

    Examples
    --------
    >>> from cvxgeodesic.mesh.tet_generate import tet_box
    >>> mesh = tet_box(2)
    >>> p = VolumePoint(3, [0.25, 0.25, 0.25, 0.25])
    >>> p.tet, p.bary.tolist()
    (3, [0.25, 0.25, 0.25, 0.25])
    >>> p.vertices(mesh).tolist() == mesh.T[3].tolist()
    True
    """

    __slots__ = ()
    tet: int

    def __init__(self, tet: Any, bary: ArrayLike) -> None:
        super().__init__(tet, bary)


#: What :func:`surface_point` takes: a triangle mesh, or its ``(V, F)`` arrays.
_SurfaceLike = TriMesh | tuple[ArrayLike, ArrayLike]


def _mesh(mesh: SimplexMesh | tuple[ArrayLike, ArrayLike]) -> TriMesh:
    from .io import as_trimesh

    return as_trimesh(mesh)


def closest_points(mesh: TriMesh, X: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Closest surface points of positions ``X`` (k, 3): ``faces (k,), bary (k, 3), dist (k,)``, one search in the
    mesh's :func:`~cvxgeodesic.mesh.closest.closest_point_index` (see
    :meth:`~cvxgeodesic.mesh.closest.ClosestPointIndex.query`)."""
    return closest_point_index(mesh).query(np.ascontiguousarray(np.asarray(X, dtype=np.float64).reshape(-1, 3)))


# the return type follows the shape of xyz where a type checker sees it: one position (a sequence of 3 numbers), or
# several (a sequence of sequences); an ndarray's shape is unknown to it, so either
@overload
def surface_point(mesh: _SurfaceLike, xyz: Sequence[float]) -> SurfacePoint: ...
@overload
def surface_point(mesh: _SurfaceLike, xyz: Sequence[Sequence[float]]) -> list[SurfacePoint]: ...
@overload
def surface_point(mesh: _SurfaceLike, xyz: ArrayLike) -> SurfacePoint | list[SurfacePoint]: ...


def surface_point(mesh: _SurfaceLike, xyz: ArrayLike) -> SurfacePoint | list[SurfacePoint]:
    """The closest :class:`SurfacePoint` of a 3D position (or of each of ``k`` positions).

    Parameters
    ----------
    mesh : TriMesh or tuple (V, F)
    xyz : (3,) or (k, 3) float array_like

    Returns
    -------
    SurfacePoint, or list of SurfacePoint for a ``(k, 3)`` input
        Typed ``SurfacePoint`` for a sequence of numbers, ``list[SurfacePoint]`` for a sequence of sequences, the
        union for an ndarray (whose shape a type checker does not know).

    Raises
    ------
    SourceError
        ``xyz`` is not one or several finite 3D positions (NaN or infinite coordinates included).

    Notes
    -----
    One search in the mesh's :func:`~cvxgeodesic.mesh.closest.closest_point_index` (a libigl AABB tree built on
    the first search of the mesh object). Any finite position is accepted: one farther than
    :data:`~cvxgeodesic.mesh.closest.FAR_QUERY` (1e7) bounding-box diagonals
    from the box's center is moved in along the ray from the center first, which leaves the point found at most
    ``diag / 8e7`` farther from it than the closest point.

    Examples
    --------
    >>> import cvxgeodesic as cg
    >>> mesh = cg.grid_plane(4)
    >>> p = cg.surface_point(mesh, [0.3, 0.6, 0.1])
    >>> p.position(mesh).round(6).tolist()
    [0.3, 0.6, 0.0]
    """
    mesh = _mesh(mesh)
    X = as_points(xyz, "xyz", error=SourceError)
    single = X.ndim == 1
    faces, bary, _ = closest_points(mesh, X.reshape(-1, 3))
    pts = [SurfacePoint(int(f), b) for f, b in zip(faces, bary, strict=True)]
    return pts[0] if single else pts


def _nearest_distance(V: np.ndarray, x: np.ndarray) -> float:
    """The distance from ``x`` (3,) to the nearest of the points ``V`` (n, 3), without overflow for any finite
    ``x`` (the differences are scaled by their largest magnitude before they are squared)."""
    d = V - x
    scale = float(np.abs(d).max())
    return 0.0 if scale == 0.0 else float(np.linalg.norm(d / scale, axis=1).min()) * scale


@overload
def volume_point(mesh: TetMesh, xyz: Sequence[float]) -> VolumePoint: ...
@overload
def volume_point(mesh: TetMesh, xyz: Sequence[Sequence[float]]) -> list[VolumePoint]: ...
@overload
def volume_point(mesh: TetMesh, xyz: ArrayLike) -> VolumePoint | list[VolumePoint]: ...


def volume_point(mesh: TetMesh, xyz: ArrayLike) -> VolumePoint | list[VolumePoint]:
    """The :class:`VolumePoint` (or points) at position(s) ``xyz`` inside ``mesh``
    (:func:`~cvxgeodesic.mesh.locate.locate_points`).

    Parameters
    ----------
    mesh : TetMesh
    xyz : (3,) or (p, 3) float array_like

    Returns
    -------
    VolumePoint for one position (3,), list of VolumePoint for (p, 3).
        Typed as :func:`surface_point`'s: by the kind of sequence, the union for an ndarray.

    Raises
    ------
    SourceError
        A position that is not finite, or outside the mesh (the message names the first such
        point, its coordinates and how far it is from the nearest vertex).

    Examples
    --------
    >>> from cvxgeodesic.mesh.tet_generate import tet_box
    >>> p = volume_point(tet_box(2), [0.3, 0.4, 0.2])
    >>> bool(abs(p.position(tet_box(2)) - [0.3, 0.4, 0.2]).max() < 1e-12)
    True
    """
    X = as_points(xyz, "xyz", error=SourceError)
    tets, bary = locate_points(mesh, X.reshape(-1, 3))
    out = np.flatnonzero(tets < 0)
    if out.size:
        k = int(out[0])
        x = X.reshape(-1, 3)[k]
        gap = _nearest_distance(mesh.V, x)
        where = "xyz" if X.ndim == 1 else f"xyz[{k}]"
        more = f" ({out.size} such points)" if out.size > 1 else ""
        raise SourceError(f"{where} = {x.tolist()} is outside {mesh.name} (in no tetrahedron; the nearest vertex is "
                          f"{gap:.6g} away){more}")
    points = [VolumePoint(int(t), b) for t, b in zip(tets, bary, strict=True)]
    return points[0] if X.ndim == 1 else points


def interpolate_at(mesh: TetMesh, values: ArrayLike, points: Any) -> np.ndarray:
    """A vertex field's linear interpolant at points inside a tetrahedral mesh.

    Parameters
    ----------
    mesh : TetMesh
    values : (n,) float array_like
        One value per vertex (``inf`` allowed: unreachable vertices).
    points : (p, 3) float array_like, VolumePoint or sequence of VolumePoint

    Returns
    -------
    (p,) float ndarray
        NaN for positions outside the mesh.

    Raises
    ------
    ParameterError
        ``values`` of the wrong length or ``points`` not positions.
    SourceError
        A VolumePoint whose tetrahedron is not in the mesh.
    """
    d = as_vertex_field(values, "values", mesh.n_vertices)
    if isinstance(points, VolumePoint):
        points = [points]
    if isinstance(points, list | tuple) and points and all(isinstance(p, VolumePoint) for p in points):
        for p in points:
            p.check(mesh)
        tets = np.array([p.tet for p in points], dtype=np.int64)
        bary = np.array([p.bary for p in points])
    elif isinstance(points, list | tuple) and any(isinstance(p, VolumePoint) for p in points):
        raise ParameterError("points must be all VolumePoints or all positions, not a mix")
    else:
        tets, bary = locate_points(mesh, points)
    out = np.full(len(tets), np.nan)
    inside = tets >= 0
    out[inside] = corner_interpolant(d[mesh.T[tets[inside]]], bary[inside])
    return out


def cells_around(mesh: SimplexMesh, verts: Sequence[int]) -> np.ndarray:
    """(q,) int32 ndarray: the cells that contain all of ``verts`` (around a vertex, an edge or a face), sorted.

    Read from the rows of :attr:`SimplexMesh.vertex_cells <cvxgeodesic.mesh.simplex.SimplexMesh.vertex_cells>` by
    their index pointers, not by sparse slicing.
    """
    inc = mesh.vertex_cells
    return functools.reduce(np.intersect1d, [inc.indices[inc.indptr[v]:inc.indptr[v + 1]] for v in map(int, verts)])


def bary_positions(mesh: SimplexMesh, cells: np.ndarray, bary: np.ndarray) -> np.ndarray:
    """(k, 3) float ndarray: the positions of barycentric coordinates ``bary`` (k, dim + 1) in ``mesh``'s cells
    ``cells`` (k,); row by row the rounding of one point's ``b @ V[cell]`` (matmul, not einsum)."""
    if not len(cells):  # no cells: the coordinates may be of another dimension (a volume's empty curve pieces)
        return np.zeros((0, 3))
    return np.matmul(bary[:, None, :], mesh.V[mesh.cells[cells]])[:, 0, :]


def corner_interpolant(Dv: np.ndarray, bary: np.ndarray) -> np.ndarray:
    """(k,) ``Σ_i b_i d_i`` of corner values ``Dv`` (k, s) at ``bary`` (k, s); a corner of weight 0 does not count
    (``inf · 0`` is NaN: a point whose cell touches an unreachable vertex takes the other corners' value)."""
    with np.errstate(invalid="ignore"):
        return np.where(bary > 0, bary * Dv, 0.0).sum(axis=1)


def checked_points(mesh: SimplexMesh, cells: Any, bary: Any) -> tuple[np.ndarray, np.ndarray]:
    """Points of a mesh's cells as arrays, checked.

    Parameters
    ----------
    mesh : SimplexMesh
    cells : int or (p,) int array_like
    bary : (dim + 1,) or (p, dim + 1) float array_like

    Returns
    -------
    cells : (p,) int64 ndarray
    bary : (p, dim + 1) float ndarray

    Raises
    ------
    ParameterError
        Cells that are not integers or out of range, or barycentric rows of the wrong shape, negative or not summing
        to 1.
    """
    words, c = mesh.reference.words, mesh.reference.n_corners
    cells = np.atleast_1d(np.asarray(cells))
    bary = np.atleast_2d(np.asarray(bary, dtype=float))
    if cells.ndim != 1 or not np.issubdtype(cells.dtype, np.integer):
        raise ParameterError(f"{words.argument} must be an int or a 1-D array of {words.one} indices")
    if bary.shape != (cells.size, c):
        raise ParameterError(f"bary must have shape ({cells.size}, {c}), got {bary.shape}")
    if cells.size and (cells.min() < 0 or cells.max() >= mesh.n_cells):
        raise ParameterError(f"{words.argument} must lie in [0, {mesh.n_cells})")
    if not np.all(np.isfinite(bary)) or np.any(bary < -1e-9) or np.any(np.abs(bary.sum(axis=1) - 1) > 1e-9):
        raise ParameterError("bary rows must be >= 0 and sum to 1")
    return cells.astype(np.int64), bary
