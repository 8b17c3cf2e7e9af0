"""A planar slice through a tetrahedral mesh: the cut polygons as triangles, with a field read on them.

Marching tetrahedra: the plane cuts a tetrahedron whose vertices lie on both sides of it in a
triangle (one vertex against three) or a quadrilateral (two against two, split into two
triangles). Each cut point lies on a mesh edge and is shared by every tetrahedron of that edge, so
the slice is a connected triangulation. A vertex array is interpolated linearly along the cut edges (the exact
restriction of the piecewise-linear field to the plane); a :class:`~cvxgeodesic.results.Field` (a result's) is
asked at the cut points, so an order-2 field has its own values there. A vertex exactly on the plane counts as
being on the positive side (the rule of :func:`~cvxgeodesic.plotting.isoline_segments`), so no piece is counted
twice.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..errors import ParameterError
from ..results import Field, GeodesicResult
from ..validation import as_field, as_points
from .reference import TETRAHEDRON
from .tetmesh import TetMesh

__all__ = ["TetSlice", "plane_frame", "slice_tets"]


def _cases() -> list[list[tuple[int, int, int]]]:
    """For each of the 16 sign patterns (bit i: vertex i below the plane), the triangles as local edge numbers."""
    edge_of = {tuple(e): k for k, e in enumerate(TETRAHEDRON.edges.tolist())}

    def e(a: int, b: int) -> int:
        return edge_of[(min(a, b), max(a, b))]

    out: list[list[tuple[int, int, int]]] = []
    for mask in range(16):
        below = [i for i in range(4) if mask >> i & 1]
        above = [i for i in range(4) if not mask >> i & 1]
        if len(below) in (0, 4):
            out.append([])
        elif len(below) in (1, 3):
            a = below[0] if len(below) == 1 else above[0]
            b, c, d = (i for i in range(4) if i != a)
            out.append([(e(a, b), e(a, c), e(a, d))])
        else:
            (a, b), (c, d) = below, above
            # the cut edges a-c, a-d, b-d, b-c go around the quadrilateral in this order
            out.append([(e(a, c), e(a, d), e(b, d)), (e(a, c), e(b, d), e(b, c))])
    return out


_CASES = _cases()


@dataclass(frozen=True)
class TetSlice:
    """The cut of a tetrahedral mesh by a plane.

    Attributes
    ----------
    points : (p, 3) float ndarray
        Cut points (on mesh edges), in 3-D.
    uv : (p, 2) float ndarray
        The same points in the plane's frame (:func:`plane_frame`), relative to ``origin``.
    triangles : (q, 3) int64 ndarray
        Triangles of the cut, indices into ``points``.
    values : (p,) float ndarray
        The field at the cut points (a vertex array: linear along the edge, ``inf`` if an end is ``inf``; a field:
        its own value there).
    tets : (q,) int64 ndarray
        The tetrahedron each triangle comes from.
    outline : (r, 2) int64 ndarray
        Segments (indices into ``points``) where the plane cuts the boundary surface.
    origin, normal, e1, e2 : (3,) float ndarrays
        The plane and its frame.
    """

    points: np.ndarray
    uv: np.ndarray
    triangles: np.ndarray
    values: np.ndarray
    tets: np.ndarray
    outline: np.ndarray
    origin: np.ndarray
    normal: np.ndarray
    e1: np.ndarray
    e2: np.ndarray

    @property
    def area(self) -> float:
        """Total area of the cut."""
        P = self.points[self.triangles]
        return float(0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1).sum())


def plane_frame(normal: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit normal and an orthonormal in-plane frame ``(n̂, e1, e2)`` with ``e1 × e2 = n̂``.

    ``e1`` is the world axis least aligned with the normal, projected into the plane (the first
    such axis on ties): the normal ``z`` gives ``e1 = x``, ``e2 = y``; the normal ``x`` gives
    ``e1 = y``, ``e2 = z``.

    Raises
    ------
    ParameterError
        A zero or non-finite normal.
    """
    n = as_points(normal, "normal").reshape(3)
    length = float(np.linalg.norm(n))
    if not length > 0:
        raise ParameterError(f"normal must be a nonzero vector, got {n.tolist()}")
    n = n / length
    axis = np.eye(3)[int(np.argmin(np.abs(n)))]
    e1 = axis - (axis @ n) * n
    e1 /= np.linalg.norm(e1)
    return n, e1, np.cross(n, e1)


def slice_tets(mesh: TetMesh, values: ArrayLike | GeodesicResult | Field | None = None, *,
               origin: ArrayLike | None = None, normal: ArrayLike = (0.0, 0.0, 1.0)) -> TetSlice:
    """Cut ``mesh`` by the plane through ``origin`` with normal ``normal``.

    Parameters
    ----------
    mesh : TetMesh
    values : (n,) float array_like, GeodesicResult or Field, optional
        A vertex field to interpolate (default zeros; ``inf``/NaN allowed), or a field (a result's) of this mesh's
        cells, asked at the cut points (:meth:`~cvxgeodesic.results.Field.distance_at`).
    origin : (3,) float array_like, optional
        A point of the plane; default the centre of the bounding box.
    normal : (3,) float array_like
        The plane's normal (any length but 0).

    Returns
    -------
    TetSlice
        Empty arrays when the plane misses the mesh.

    Raises
    ------
    ParameterError
        ``values`` of the wrong length, or a field of another mesh (another vertex count, or other tetrahedra).

    Examples
    --------
    >>> from cvxgeodesic.mesh.tet_generate import tet_box
    >>> cut = slice_tets(tet_box(3), origin=[0.5, 0.5, 0.4])
    >>> round(cut.area, 12)
    1.0
    """
    d, field = (np.zeros(mesh.n_vertices), None) if values is None else as_field(values, "values", mesh.n_vertices)
    if field is not None and field.mesh is not mesh and not np.array_equal(field.mesh.cells, mesh.cells):
        raise ParameterError(f"values is a field on other tetrahedra than those of {mesh.name} (same vertex count)")
    n, e1, e2 = plane_frame(normal)
    o = (mesh.V.min(axis=0) + mesh.V.max(axis=0)) / 2 if origin is None else as_points(origin, "origin").reshape(3)
    s = (mesh.V - o) @ n
    below = s < 0
    mask = (below[mesh.T] * (1 << np.arange(4))).sum(axis=1)
    tri_t, tri_e = [], []
    for case in range(1, 15):
        tets = np.flatnonzero(mask == case)
        for tri in _CASES[case]:
            tri_t.append(tets)
            tri_e.append(mesh.cell_edges[tets][:, list(tri)])
    tets, edges_of = np.concatenate(tri_t), np.concatenate(tri_e)  # one array per case: none is missing
    cut, first, triangles = np.unique(edges_of, return_index=True, return_inverse=True)
    triangles = triangles.reshape(-1, 3).astype(np.int64)
    a, b = mesh.edges[cut, 0], mesh.edges[cut, 1]
    w = s[a] / (s[a] - s[b])  # in [0, 1]: the ends are on opposite sides
    P = mesh.V[a] + w[:, None] * (mesh.V[b] - mesh.V[a])
    if field is None:
        with np.errstate(invalid="ignore"):
            vals = np.where(w == 0, d[a], np.where(w == 1, d[b], (1 - w) * d[a] + w * d[b]))
    else:
        vals = _field_at_edges(mesh, field, tets[first // 3], a, b, w)
    uv = np.column_stack([(P - o) @ e1, (P - o) @ e2])
    order = np.argsort(tets, kind="stable")
    return TetSlice(P, uv, triangles[order], vals, tets[order].astype(np.int64), _outline(mesh, below, cut), o, n,
                    e1, e2)


def _field_at_edges(mesh: TetMesh, field: Field, cells: np.ndarray, a: np.ndarray, b: np.ndarray,
                    w: np.ndarray) -> np.ndarray:
    """(p,) the field at the points ``(1 − w) V[a] + w V[b]`` of edges ``a``–``b`` (p,) of the tetrahedra ``cells``
    (p,) that hold them."""
    corners = mesh.T[cells]
    bary = np.zeros(corners.shape)
    rows = np.arange(len(cells))
    bary[rows, np.argmax(corners == a[:, None], axis=1)] = 1 - w
    bary[rows, np.argmax(corners == b[:, None], axis=1)] = w
    return np.asarray(field.distance_at(cells, bary), dtype=np.float64)


def _outline(mesh: TetMesh, below: np.ndarray, cut: np.ndarray) -> np.ndarray:
    """Segments where the plane cuts the boundary faces: each such face has exactly two cut edges."""
    B = mesh.boundary_facets
    nb = below[B].sum(axis=1)
    B = B[(nb == 1) | (nb == 2)]
    if B.shape[0] == 0:
        return np.empty((0, 2), dtype=np.int64)
    nv = np.int64(mesh.n_vertices)
    keys = mesh.edges[:, 0] * nv + mesh.edges[:, 1]
    pairs = []
    for a, b in ((0, 1), (1, 2), (2, 0)):
        u, v = np.minimum(B[:, a], B[:, b]), np.maximum(B[:, a], B[:, b])
        pairs.append(np.searchsorted(keys, u * nv + v))
    E = np.stack(pairs, axis=1)  # (r, 3) mesh edges of each face
    crosses = below[mesh.edges[E, 0]] != below[mesh.edges[E, 1]]
    ends = np.searchsorted(cut, E[crosses].reshape(-1, 2))
    return ends.astype(np.int64)
