"""Sources inside a tetrahedral mesh, and the constraints they add to the order-1 programs (issue 26).

A source of a distance field inside a :class:`~cvxgeodesic.mesh.tetmesh.TetMesh` may be

- a vertex index (or several);
- a :class:`~cvxgeodesic.mesh.tet_locate.VolumePoint`: a tetrahedron and four barycentric coordinates
  (:func:`~cvxgeodesic.mesh.tet_locate.volume_point` finds it from a position); a point within ``1e-9``
  (barycentric) of a vertex is that vertex;
- the string ``"boundary"``: the whole boundary surface (the distance is then the wall distance);
- :class:`BoundaryFaces`: some faces of the boundary surface (part of the wall).

:func:`resolve_tet_sources` turns any of these (or a list mixing vertices, points and face sets) into one
:class:`TetSources`; :func:`tet_source_constraints` turns it into what the order-1 programs add
(:mod:`cvxgeodesic.formulations_tet`). Every bound below is an upper bound of the exact distance inside the
solid (a straight segment inside one convex tetrahedron is a path in the solid):

- vertex sources and the vertices of source faces are fixed at 0;
- a point ``p`` inside tetrahedron ``t`` bounds each corner of ``t`` by ``|v − p|`` (``t`` carries no cone). Measured
  2026-12-02 against inserting the point as a vertex (:class:`~cvxgeodesic.mesh.tet_split.TetSplitMesh`, what
  order 2 does) at order 1, mean relative error of qclp for two points each: box 3 072 tetrahedra 4.8 / 4.6 %
  against 6.2 / 7.9 %, L-shaped prism 9 216 tetrahedra 4.1 / 4.2 % against 5.9 / 7.6 % (jitter 0.2; the bounds
  were better in 7 of 8 cases, meshes of 384 and 1 152 tetrahedra included);
- a source face bounds the fourth vertex of its tetrahedron by its distance to the (closed) triangle;
- a tetrahedron next to the sources carries no cone where the linear interpolant of the local exact field is
  steeper than 1 (every tetrahedron with a vertex at a source point, since the interpolant of ``|x − s|`` there
  is; near a flat wall the wall distance is linear and the cone stays); the local field is the distance to the
  nearest source vertex, point or source face;
- every edge of a tetrahedron without a cone gets ``|d_i − d_j| ≤ ℓ_ij`` (true of every distance field), which
  keeps the field bounded and below Dijkstra's.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .errors import SourceError
from .mesh.tet_locate import VolumePoint
from .mesh.tetmesh import TetMesh
from .validation import validate_sources

__all__ = ["BoundaryFaces", "TetSourceConstraints", "TetSources", "point_triangle_distance", "resolve_tet_sources",
           "tet_source_constraints"]

#: A barycentric coordinate of a VolumePoint this close to 1 makes the point its vertex; this close to 0, it
#: lies on the face (edge) of the others.
BARY_SNAP = 1e-9


@dataclass(frozen=True, eq=False)
class BoundaryFaces:
    """Some faces of the boundary surface of a tetrahedral mesh, used as one source (part of the wall).

    Parameters
    ----------
    faces : (k,) int array_like or (k, 3) int array_like
        Rows of :attr:`TetMesh.boundary_faces <cvxgeodesic.mesh.tetmesh.TetMesh.boundary_faces>` (indices), or
        the faces' three vertices (any order); checked against the mesh when used.

    Examples
    --------
    The bottom of a unit box, found by the faces' centroids:

    >>> import numpy as np
    >>> from cvxgeodesic.mesh.tet_generate import tet_box
    >>> mesh = tet_box(2)
    >>> bottom = np.flatnonzero(mesh.V[mesh.boundary_faces].mean(axis=1)[:, 2] == 0)
    >>> BoundaryFaces(bottom).resolve(mesh).size
    8
    """

    faces: np.ndarray = field(repr=False)

    def __post_init__(self):
        try:
            arr = np.asarray(self.faces)
        except (TypeError, ValueError):
            raise SourceError(f"BoundaryFaces takes (k,) face indices or (k, 3) vertex triples, got {self.faces!r}") \
                from None
        if arr.dtype.kind == "f" and np.all(np.isfinite(arr)) and np.all(arr == np.round(arr)):
            arr = arr.astype(np.int64)
        if arr.dtype.kind not in "iu" or arr.ndim not in (1, 2) or (arr.ndim == 2 and arr.shape[1] != 3):
            raise SourceError(f"BoundaryFaces takes (k,) face indices or (k, 3) vertex triples, got an array of "
                              f"shape {arr.shape} and dtype {arr.dtype}")
        if arr.shape[0] == 0:
            raise SourceError("BoundaryFaces is empty: give at least one face")
        arr = arr.astype(np.int64)
        arr.setflags(write=False)
        object.__setattr__(self, "faces", arr)

    def __repr__(self) -> str:
        return f"BoundaryFaces({self.faces.shape[0]} faces)"

    def resolve(self, mesh: TetMesh) -> np.ndarray:
        """(k,) int64 ndarray: sorted unique rows of ``mesh.boundary_faces``.

        Raises
        ------
        SourceError
            An index out of range, or a vertex triple that is no boundary face of ``mesh``.
        """
        B = mesh.boundary_faces
        if self.faces.ndim == 1:
            bad = (self.faces < 0) | (self.faces >= B.shape[0])
            if bad.any():
                raise SourceError(f"BoundaryFaces: face index {int(self.faces[bad][0])} is out of range: "
                                  f"{mesh.name} has {B.shape[0]} boundary faces (0..{B.shape[0] - 1})")
            return np.unique(self.faces)
        bad = (self.faces < 0) | (self.faces >= mesh.n_vertices)
        if bad.any():
            raise SourceError(f"BoundaryFaces: vertex index {int(self.faces[bad][0])} is out of range: {mesh.name} "
                              f"has {mesh.n_vertices} vertices")
        # one id per distinct sorted triple, shared by the boundary faces and the given ones
        _, ids = np.unique(np.sort(np.vstack([B, self.faces]), axis=1), axis=0, return_inverse=True)
        ids = ids.ravel()
        row_of = np.full(ids.max() + 1, -1, dtype=np.int64)
        row_of[ids[:B.shape[0]]] = np.arange(B.shape[0])
        rows = row_of[ids[B.shape[0]:]]
        if (rows < 0).any():
            k = int(np.flatnonzero(rows < 0)[0])
            raise SourceError(f"BoundaryFaces: face {self.faces[k].tolist()} is not a boundary face of {mesh.name}")
        return np.unique(rows)


@dataclass(frozen=True)
class TetSources:
    """A validated source set of a tetrahedral mesh.

    Attributes
    ----------
    vertices : (s,) int64 ndarray
        Source vertices (unique), points that lie on a vertex included.
    points : tuple of VolumePoint
        Points inside tetrahedra (checked against the mesh; not on a vertex).
    boundary : bool
        The whole boundary surface is a source (``faces`` then holds every boundary face).
    faces : (f,) int64 ndarray
        Source faces: sorted rows of ``mesh.boundary_faces``.
    description : str
        Short text for messages and titles.
    """

    vertices: np.ndarray
    points: tuple[VolumePoint, ...] = ()
    boundary: bool = False
    faces: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    description: str = ""

    @property
    def count(self) -> int:
        """Number of sources (the boundary or a face set counts as one)."""
        return int(self.vertices.size) + len(self.points) + int(self.faces.size > 0)

    @property
    def vertex_only(self) -> bool:
        """True when every source is a vertex."""
        return not self.points and not self.faces.size

    def face_triangles(self, mesh: TetMesh) -> np.ndarray:
        """(f, 3) int64 ndarray: the source faces' vertices."""
        return mesh.boundary_faces[self.faces]

    def face_slots(self, mesh: TetMesh) -> tuple[np.ndarray, np.ndarray]:
        """The tetrahedron of each source face and the local index of its corner opposite the face:
        ``(tets (f,), local (f,))`` (``mesh.tet_faces[tets, local]`` are the faces' rows of ``mesh.faces``)."""
        tets = mesh.boundary_face_tets[self.faces]
        on_face = (mesh.T[tets][:, :, None] == self.face_triangles(mesh)[:, None, :]).any(axis=2)
        return tets, np.argmin(on_face, axis=1)

    def fixed_vertices(self, mesh: TetMesh) -> np.ndarray:
        """(q,) int64 ndarray: vertices where the distance is 0 (source vertices, vertices of source faces)."""
        return np.unique(np.concatenate([self.vertices, self.face_triangles(mesh).ravel()])).astype(np.int64)

    def seed_vertices(self, mesh: TetMesh) -> np.ndarray:
        """(q,) int64 ndarray: vertices from which the field spreads (the fixed ones and the points' corners)."""
        parts = [self.fixed_vertices(mesh)] + [p.vertices(mesh) for p in self.points]
        return np.unique(np.concatenate(parts)).astype(np.int64)

    def local_values(self, mesh: TetMesh) -> tuple[np.ndarray, np.ndarray]:
        """Vertices at or next to the sources and their exact distances: 0 at fixed vertices, ``|v − p|`` at the
        corners of a point's tetrahedron (the minimum where several meet). Returns ``(vertices (q,), values (q,))``."""
        fixed = self.fixed_vertices(mesh)
        idx = [fixed] + [p.vertices(mesh) for p in self.points]
        val = [np.zeros(fixed.size)] + [np.linalg.norm(mesh.V[p.vertices(mesh)] - p.position(mesh), axis=1)
                                        for p in self.points]
        verts, vals = np.concatenate(idx), np.concatenate(val)
        uniq, inv = np.unique(verts, return_inverse=True)
        best = np.full(uniq.size, np.inf)
        np.minimum.at(best, inv, vals)
        return uniq.astype(np.int64), best


def _snap(mesh: TetMesh, p: VolumePoint) -> int | VolumePoint:
    """A point within :data:`BARY_SNAP` of a vertex is that vertex; near-zero coordinates become 0."""
    p.check(mesh)
    b = p.bary
    k = int(np.argmax(b))
    if b[k] >= 1.0 - BARY_SNAP:
        return int(mesh.T[p.tet, k])
    if (b <= BARY_SNAP).any():
        b = np.where(b <= BARY_SNAP, 0.0, b)
        return VolumePoint(p.tet, b / b.sum())
    return p


def resolve_tet_sources(mesh: TetMesh, sources: Any) -> TetSources:
    """Validate ``sources`` for ``mesh``.

    Parameters
    ----------
    mesh : TetMesh
    sources : int, VolumePoint, BoundaryFaces, "boundary", TetSources, or a sequence of ints, VolumePoints and
        BoundaryFaces

    Returns
    -------
    TetSources

    Raises
    ------
    SourceError
        An unknown string, invalid or repeated vertex indices, a VolumePoint whose tetrahedron is not in the mesh,
        a face that is no boundary face, an empty sequence, ``"boundary"`` mixed with other sources or on a mesh
        without boundary faces.
    """
    if isinstance(sources, TetSources):
        return sources
    if isinstance(sources, str):
        if sources.strip().lower() != "boundary":
            raise SourceError(f"unknown source {sources!r}: give vertex indices, VolumePoints, BoundaryFaces or "
                              "'boundary'")
        nb = mesh.boundary_faces.shape[0]
        if nb == 0:
            raise SourceError(f"{mesh.name}: source 'boundary' but the mesh has no boundary faces")
        return TetSources(np.empty(0, dtype=np.int64), (), True, np.arange(nb, dtype=np.int64),
                          f"boundary ({nb} faces)")
    if isinstance(sources, VolumePoint | BoundaryFaces):
        sources = [sources]
    if isinstance(sources, Sequence) and any(isinstance(s, VolumePoint | BoundaryFaces | str) for s in sources):
        verts: list[int] = []
        points: list[VolumePoint] = []
        faces: list[np.ndarray] = []
        for k, s in enumerate(sources):
            if isinstance(s, VolumePoint):
                snapped = _snap(mesh, s)
                if isinstance(snapped, VolumePoint):
                    points.append(snapped)
                else:
                    verts.append(snapped)
            elif isinstance(s, BoundaryFaces):
                faces.append(s.resolve(mesh))
            elif isinstance(s, str):
                raise SourceError("'boundary' cannot be mixed with other sources (give BoundaryFaces for part of "
                                  "the wall)")
            elif isinstance(s, numbers.Integral | np.integer) or (isinstance(s, float) and float(s).is_integer()):
                try:
                    verts.append(int(validate_sources(s, mesh.n_vertices)[0]))
                except SourceError as exc:
                    raise SourceError(f"source {k}: {exc}") from None
            else:
                raise SourceError(f"source {k} must be a vertex index, a VolumePoint or BoundaryFaces, got {s!r}")
        v = np.unique(np.asarray(verts, dtype=np.int64))
        if v.size < len(verts):
            uniq, counts = np.unique(verts, return_counts=True)
            raise SourceError(f"source vertex {int(uniq[counts > 1][0])} is given more than once")
        f = np.unique(np.concatenate(faces)) if faces else np.zeros(0, dtype=np.int64)
        desc = ", ".join(repr(s) if not isinstance(s, numbers.Integral | np.integer) else f"vertex {int(s)}"
                         for s in list(sources)[:4]) + (f" and {len(sources) - 4} more" if len(sources) > 4 else "")
        return TetSources(v, tuple(points), False, f.astype(np.int64), desc)
    v = validate_sources(sources, mesh.n_vertices)
    return TetSources(v, (), False, np.zeros(0, dtype=np.int64),
                      f"vertices {v.tolist()}" if v.size <= 8 else f"{v.size} vertices")


def point_triangle_distance(P: np.ndarray, A: np.ndarray, B: np.ndarray, C: np.ndarray) -> np.ndarray:
    """(k,) distances from points ``P`` to the closed triangles ``(A, B, C)`` (all (k, 3)).

    The closest point by the Voronoi regions of the triangle's corners, edges and face (Ericson, *Real-Time
    Collision Detection*, §5.1.5); a degenerate triangle gives the distance to its nearest edge.
    """
    P, A, B, C = (np.asarray(x, dtype=float).reshape(-1, 3) for x in (P, A, B, C))
    dot = lambda u, v: np.einsum("ij,ij->i", u, v)  # noqa: E731

    def seg(a, b):
        ab = b - a
        den = dot(ab, ab)
        t = np.clip(np.divide(dot(P - a, ab), den, out=np.zeros(len(P)), where=den > 0), 0.0, 1.0)
        return np.linalg.norm(P - (a + t[:, None] * ab), axis=1)

    edges = np.minimum(np.minimum(seg(A, B), seg(B, C)), seg(C, A))
    nrm = np.cross(B - A, C - A)
    nn = dot(nrm, nrm)
    with np.errstate(divide="ignore", invalid="ignore"):
        # barycentric coordinates of the projection onto the plane; inside when all are >= 0
        u = dot(np.cross(C - B, P - B), nrm) / nn
        v = dot(np.cross(A - C, P - C), nrm) / nn
        plane = np.abs(dot(P - A, nrm)) / np.sqrt(nn)
    inside = (nn > 0) & (u >= 0) & (v >= 0) & (u + v <= 1)
    return np.where(inside, plane, edges)


@dataclass
class TetSourceConstraints:
    """What the sources add to an order-1 program on tetrahedra (read by
    :func:`~cvxgeodesic.formulations_tet.build_tet_problem`).

    Attributes
    ----------
    fixed : (q,) int64 ndarray
        Vertices fixed at 0.
    no_cone : (k,) bool ndarray
        Tetrahedra that carry no cone (their edges get the edge bounds).
    bound_vertices : (b,) int64 ndarray
        Vertex bounds ``d[bound_vertices] ≤ bound_rhs`` (free vertices only, one per vertex).
    bound_rhs : (b,) float ndarray
    anchors : (r,) int64 ndarray
        Vertices whose components contain a source (the others are unreachable).
    """

    fixed: np.ndarray
    no_cone: np.ndarray
    bound_vertices: np.ndarray
    bound_rhs: np.ndarray
    anchors: np.ndarray


def _nearest_triangle_distance(mesh: TetMesh, tri: np.ndarray, X: np.ndarray) -> np.ndarray:
    """(p,) distance from each row of ``X`` to the nearest of the triangles ``tri`` (f, 3) of ``mesh``."""
    import igl

    if not len(X) or not len(tri):
        return np.full(len(X), np.inf)
    sqd, _, _ = igl.point_mesh_squared_distance(np.ascontiguousarray(X, dtype=np.float64),
                                               np.ascontiguousarray(mesh.V, dtype=np.float64),
                                               np.ascontiguousarray(tri, dtype=np.int64))
    return np.sqrt(np.maximum(np.asarray(sqd, dtype=float).reshape(-1), 0.0))


def tet_source_constraints(mesh: TetMesh, blocks: np.ndarray, degenerate: np.ndarray, src: TetSources,
                           floor: float) -> TetSourceConstraints:
    """The constraints of a source set (see the module docstring).

    Parameters
    ----------
    mesh : TetMesh
        The mesh the program is built on (possibly a scaled copy).
    blocks : (k, 3, 4) float ndarray
        Gradient blocks (zero on degenerate tetrahedra).
    degenerate : (k,) bool ndarray
    src : TetSources
    floor : float
        Smallest right-hand side of a bound (keeps bounds next to a point that almost touches a vertex
        inequalities).

    Returns
    -------
    TetSourceConstraints
    """
    n, T, V = mesh.n_vertices, mesh.T, mesh.V
    fixed = src.fixed_vertices(mesh)
    is_fixed = np.zeros(n, dtype=bool)
    is_fixed[fixed] = True
    no_cone = np.zeros(mesh.n_tets, dtype=bool)
    bound = np.full(n, np.inf)
    near_v = is_fixed.copy()
    point_tets = np.array([p.tet for p in src.points], dtype=np.int64)
    if point_tets.size:
        no_cone[point_tets] = True
        X = np.array([p.position(mesh) for p in src.points])
        corners = T[point_tets]
        np.minimum.at(bound, corners.ravel(), np.linalg.norm(V[corners] - X[:, None, :], axis=2).ravel())
        near_v[corners.ravel()] = True
    if src.faces.size:  # the fourth vertex of each source face's tetrahedron: its distance to the face
        tri = src.face_triangles(mesh)
        t_of, local = src.face_slots(mesh)
        other = T[t_of, local]
        np.minimum.at(bound, other, point_triangle_distance(V[other], V[tri[:, 0]], V[tri[:, 1]], V[tri[:, 2]]))
    # tetrahedra next to the sources whose linear interpolant of the local exact field is steeper than 1
    near = near_v[T].any(axis=1) & ~no_cone & ~degenerate
    if near.any():
        from scipy.spatial import cKDTree

        tn = np.flatnonzero(near)
        verts = np.unique(T[tn])
        local = np.full(n, np.inf)
        pts = [V[src.vertices]] + ([X] if point_tets.size else [])
        P = np.concatenate(pts)
        if len(P):
            local[verts] = cKDTree(P).query(V[verts])[0]
        if src.faces.size:
            local[verts] = np.minimum(local[verts], _nearest_triangle_distance(mesh, src.face_triangles(mesh),
                                                                               V[verts]))
        local[is_fixed] = 0.0
        g = np.einsum("tij,tj->ti", blocks[tn], local[T[tn]])
        no_cone[tn[np.linalg.norm(g, axis=1) > 1.0 + 1e-9]] = True
    bv = np.flatnonzero(np.isfinite(bound) & ~is_fixed)
    anchors = np.unique(np.concatenate([fixed, T[point_tets].ravel()])).astype(np.int64)
    return TetSourceConstraints(fixed=fixed, no_cone=no_cone, bound_vertices=bv.astype(np.int64),
                                bound_rhs=np.maximum(bound[bv], floor), anchors=anchors)
