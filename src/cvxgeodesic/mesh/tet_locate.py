"""Points inside a tetrahedral mesh: :class:`VolumePoint` sources, point location, interpolation (issue 26).

:func:`locate_points` finds the tetrahedron containing each of many points at once: a k-d tree on
the tetrahedra's centroids gives, for each point, every tetrahedron whose circumscribing ball
around its centroid (radius: its farthest vertex) holds the point, and the barycentric
coordinates of those candidates decide. No Delaunay triangulation of the vertices is involved,
so non-convex meshes (an L-shaped prism) and meshes with holes work.
"""

from __future__ import annotations

import numbers
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial import cKDTree

from ..errors import ParameterError, SourceError
from ..validation import as_points, as_vertex_field
from .tetmesh import TET_FACES, TetMesh

__all__ = ["BARY_TOL", "INSIDE_TOL", "VolumePoint", "interpolate_at", "locate_points", "volume_point"]

#: Tolerance of the barycentric checks of :class:`VolumePoint` (negative coordinates, sum ≠ 1).
BARY_TOL = 1e-9
#: A point counts as inside a tetrahedron when its smallest barycentric coordinate is ``>= -INSIDE_TOL``
#: (points on a shared face or on the boundary surface, up to round-off).
INSIDE_TOL = 1e-9


@dataclass(frozen=True, eq=False)
class VolumePoint:
    """A point inside a tetrahedral mesh: a tetrahedron index and four barycentric coordinates.

    Parameters
    ----------
    tet : int
        Tetrahedron index (checked against the mesh when the point is used).
    bary : (4,) float array_like
        Barycentric coordinates with respect to ``T[tet]``: each ``>= 0`` and summing to 1 (to
        ``1e-9``; tiny negative round-off is clipped and the sum renormalized).

    Raises
    ------
    SourceError
        A tetrahedron index that is not a non-negative integer; ``bary`` not 4 finite numbers,
        with a negative coordinate, or not summing to 1.

    Examples
    --------
    >>> p = VolumePoint(3, [0.25, 0.25, 0.25, 0.25])
    >>> p.tet, p.bary.tolist()
    (3, [0.25, 0.25, 0.25, 0.25])
    """

    tet: int
    bary: np.ndarray = field(repr=False)

    def __post_init__(self):
        t = self.tet
        if isinstance(t, bool | np.bool_) or not isinstance(t, numbers.Integral):
            if isinstance(t, numbers.Real) and not isinstance(t, bool | np.bool_) and float(t).is_integer():
                t = int(t)
            else:
                raise SourceError(f"VolumePoint tet must be a tetrahedron index (int), got {t!r}")
        t = int(t)
        if t < 0:
            raise SourceError(f"VolumePoint tet index {t} is negative")
        try:
            b = np.asarray(self.bary, dtype=float).reshape(-1).copy()
        except (TypeError, ValueError):
            raise SourceError(f"VolumePoint(tet={t}): bary must be 4 numbers, got {self.bary!r}") from None
        if b.shape != (4,):
            raise SourceError(f"VolumePoint(tet={t}): bary must have 4 coordinates, got {b.size}")
        if not np.all(np.isfinite(b)):
            raise SourceError(f"VolumePoint(tet={t}, bary={b.tolist()}): barycentric coordinates must be finite")
        if b.min() < -BARY_TOL:
            raise SourceError(
                f"VolumePoint(tet={t}, bary={b.tolist()}): barycentric coordinates must be >= 0 (a negative one is "
                "outside the tetrahedron; use volume_point(mesh, xyz) to find the containing one)")
        if abs(b.sum() - 1.0) > BARY_TOL:
            raise SourceError(f"VolumePoint(tet={t}, bary={b.tolist()}): barycentric coordinates must sum to 1, "
                              f"they sum to {b.sum():.12g}")
        b = np.clip(b, 0.0, None)
        b /= b.sum()
        b.setflags(write=False)
        object.__setattr__(self, "tet", t)
        object.__setattr__(self, "bary", b)

    def __repr__(self) -> str:
        return f"VolumePoint(tet={self.tet}, bary=[{', '.join(f'{x:.6g}' for x in self.bary)}])"

    def __eq__(self, other) -> bool:
        if not isinstance(other, VolumePoint):
            return NotImplemented
        return self.tet == other.tet and bool(np.array_equal(self.bary, other.bary))

    def __hash__(self) -> int:
        return hash((self.tet, self.bary.tobytes()))

    def check(self, mesh: TetMesh) -> None:
        """Raise :class:`SourceError` unless :attr:`tet` is a tetrahedron of ``mesh``."""
        if self.tet >= mesh.n_tets:
            raise SourceError(f"{self!r}: tetrahedron index {self.tet} is out of range: {mesh.name} has "
                              f"{mesh.n_tets} tetrahedra (0..{mesh.n_tets - 1})")

    def position(self, mesh: TetMesh) -> np.ndarray:
        """(3,) float ndarray: the point's position in ``mesh``."""
        self.check(mesh)
        return self.bary @ mesh.V[mesh.T[self.tet]]

    def vertices(self, mesh: TetMesh) -> np.ndarray:
        """(4,) int64 ndarray: the vertices of the point's tetrahedron (the order of ``bary``)."""
        self.check(mesh)
        return mesh.T[self.tet].copy()


def _barycentric(mesh: TetMesh, tets: np.ndarray, X: np.ndarray) -> np.ndarray:
    """(p, 4) barycentric coordinates of ``X[j]`` in ``T[tets[j]]``; NaN rows for tetrahedra of zero volume."""
    V, T = mesh.V, mesh.T[tets]
    out = np.empty((len(tets), 4))
    with np.errstate(divide="ignore", invalid="ignore"):
        for i, (a, b, c) in enumerate(TET_FACES):
            pa = V[T[:, a]]
            nrm = np.cross(V[T[:, b]] - pa, V[T[:, c]] - pa)
            out[:, i] = np.einsum("ij,ij->i", nrm, X - pa) / np.einsum("ij,ij->i", nrm, V[T[:, i]] - pa)
    return out


class _Locator:
    """The k-d tree of one mesh's tetrahedron centroids (built once per mesh, cached on it)."""

    def __init__(self, mesh: TetMesh):
        P = mesh.V[mesh.T]  # (k, 4, 3)
        self.centroids = P.mean(axis=1)
        self.radius = float(np.linalg.norm(P - self.centroids[:, None], axis=2).max()) * (1 + 1e-9)
        self.tree = cKDTree(self.centroids)


def _locator(mesh: TetMesh) -> _Locator:
    loc = mesh.__dict__.get("_tet_locator")
    if loc is None:
        loc = _Locator(mesh)
        mesh.__dict__["_tet_locator"] = loc  # TetMesh is immutable: a cache like its cached properties
    return loc


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
    loc = _locator(mesh)
    cand = loc.tree.query_ball_point(X, loc.radius, return_sorted=False)
    counts = np.fromiter((len(c) for c in cand), dtype=np.int64, count=len(cand))
    point_of = np.repeat(np.arange(len(X)), counts)
    tet_of = np.fromiter((t for c in cand for t in c), dtype=np.int64, count=int(counts.sum()))
    tets = np.full(len(X), -1, dtype=np.int64)
    bary = np.full((len(X), 4), np.nan)
    if tet_of.size:
        B = _barycentric(mesh, tet_of, X[point_of])
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


def volume_point(mesh: TetMesh, xyz: ArrayLike) -> VolumePoint | list[VolumePoint]:
    """The :class:`VolumePoint` (or points) at position(s) ``xyz`` inside ``mesh``.

    Parameters
    ----------
    mesh : TetMesh
    xyz : (3,) or (p, 3) float array_like

    Returns
    -------
    VolumePoint for one position (3,), list of VolumePoint for (p, 3).

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
        gap = float(np.linalg.norm(mesh.V - x, axis=1).min())
        where = "xyz" if X.ndim == 1 else f"xyz[{k}]"
        more = f" ({out.size} such points)" if out.size > 1 else ""
        raise SourceError(f"{where} = {x.tolist()} is outside {mesh.name} (in no tetrahedron; the nearest vertex is "
                          f"{gap:.6g} away){more}")
    points = [VolumePoint(int(t), b) for t, b in zip(tets, bary, strict=True)]
    return points[0] if X.ndim == 1 else points


def interpolate_at(mesh: TetMesh, values: ArrayLike, points: Any) -> np.ndarray:
    """A vertex field's linear interpolant at points inside the mesh.

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
    vals = d[mesh.T[tets[inside]]]
    with np.errstate(invalid="ignore"):  # inf · 0 where an unreachable vertex has coordinate 0
        w = bary[inside]
        out[inside] = np.where(w > 0, vals * w, 0.0).sum(axis=1)
    return out
