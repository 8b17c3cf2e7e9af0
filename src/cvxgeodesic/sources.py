"""Sources anywhere on the surface: points in faces or on edges, curves, the boundary.

A source of a distance field may be

- a vertex index (or several);
- a :class:`SurfacePoint`: a face and barycentric coordinates;
- a :class:`SurfaceCurve`: a polyline of surface points (the distance is to the whole curve);
- the string ``"boundary"``: every boundary edge (edges with a single face).

:func:`resolve_sources` turns any of these (or a list mixing them) into one normalized
:class:`SourceSet`; :func:`source_constraints` turns a source set into the constraints the
convex formulations add (``docs/sources.md`` explains and measures each choice):

- vertex sources are fixed at 0, their incident faces carry no cone and each star edge bounds
  its other end by its length (as before);
- a point ``p`` inside face ``t`` bounds each vertex of ``t`` by ``|v_i − p|`` (the straight
  segment inside the flat face is a surface path, so this is an upper bound of the geodesic
  distance) and ``t`` carries no cone. A point on an edge does this in both faces of the edge;
  a point within ``1e-9`` (barycentric) of a vertex is that vertex.
- a face next to a point source whose local field ``min_k |v − p_k|`` is steeper than 1 when
  interpolated linearly (the piecewise-linear trace of a cone whose apex is close to the face)
  carries no cone either; the vertices it leaves free are bounded through the edges to the
  source face's vertices, ``d_w ≤ d_v + ℓ_vw`` (a triangle inequality).
- a curve is sampled along each segment at an eighth of the mean edge length (plus its given
  points); every sample is a point source, and two consecutive samples in the same face add the
  bound by the distance to the segment between them (straight in that face).
- ``"boundary"`` fixes every boundary vertex at 0 and bounds the third vertex of each boundary
  face by its distance to the boundary edge.

Every bound is an upper bound of the exact polyhedral distance (tested against pygeodesic), so
none of them cuts the exact field off.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike

from .errors import SourceError
from .mesh.closest import closest_point_index
from .mesh.geometry import clipped_barycentric
from .mesh.trimesh import TriMesh
from .validation import as_points, validate_sources

#: A barycentric coordinate this close to 0 (or 1) counts as exactly 0 (1): the point is on an edge (a vertex).
BARY_SNAP = 1e-9
#: Tolerance of the barycentric checks of :class:`SurfacePoint` (negative coordinates, sum ≠ 1).
BARY_TOL = 1e-9
#: A curve point given as a position must lie this close to the surface (fraction of the bounding-box diagonal).
ON_SURFACE_TOL = 1e-6
#: Curve sampling step as a fraction of the mean edge length.
CURVE_STEP = 1.0 / 8.0


# ---------------------------------------------------------------------------------------------------------------
# user-facing types
# ---------------------------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class SurfacePoint:
    """A point of the surface: a face index and barycentric coordinates.

    Parameters
    ----------
    face : int
        Face index (checked against the mesh when the point is used).
    bary : (3,) float array_like
        Barycentric coordinates with respect to ``F[face]``: each ``>= 0`` and summing to 1
        (to ``1e-9``; tiny negative round-off is clipped and the sum renormalized).

    Raises
    ------
    SourceError
        A face that is not a non-negative integer; ``bary`` not 3 finite numbers, with a
        negative coordinate, or not summing to 1.

    Examples
    --------
    >>> import cvxgeodesic as cg
    >>> p = cg.SurfacePoint(10, [0.2, 0.3, 0.5])
    >>> p.face, p.bary.tolist()
    (10, [0.2, 0.3, 0.5])
    """

    face: int
    bary: np.ndarray = field(repr=False)

    def __post_init__(self):
        f = self.face
        if isinstance(f, bool | np.bool_) or not isinstance(f, numbers.Integral):
            if isinstance(f, numbers.Real) and not isinstance(f, bool | np.bool_) and float(f).is_integer():
                f = int(f)
            else:
                raise SourceError(f"SurfacePoint face must be a face index (int), got {f!r}")
        f = int(f)
        if f < 0:
            raise SourceError(f"SurfacePoint face index {f} is negative")
        try:
            b = np.asarray(self.bary, dtype=float).reshape(-1).copy()
        except (TypeError, ValueError):
            raise SourceError(f"SurfacePoint(face={f}): bary must be 3 numbers, got {self.bary!r}") from None
        if b.shape != (3,):
            raise SourceError(f"SurfacePoint(face={f}): bary must have 3 coordinates, got {b.size}")
        if not np.all(np.isfinite(b)):
            raise SourceError(f"SurfacePoint(face={f}, bary={b.tolist()}): barycentric coordinates must be finite")
        if b.min() < -BARY_TOL:
            raise SourceError(
                f"SurfacePoint(face={f}, bary={b.tolist()}): barycentric coordinates must be >= 0 (a negative one "
                "is outside the face; use surface_point(mesh, xyz) for the closest point)")
        if abs(b.sum() - 1.0) > BARY_TOL:
            raise SourceError(
                f"SurfacePoint(face={f}, bary={b.tolist()}): barycentric coordinates must sum to 1, "
                f"they sum to {b.sum():.12g}")
        b = np.clip(b, 0.0, None)
        b /= b.sum()
        b.setflags(write=False)
        object.__setattr__(self, "face", f)
        object.__setattr__(self, "bary", b)

    def __repr__(self) -> str:
        return f"SurfacePoint(face={self.face}, bary=[{', '.join(f'{x:.6g}' for x in self.bary)}])"

    def __eq__(self, other) -> bool:
        if not isinstance(other, SurfacePoint):
            return NotImplemented
        return self.face == other.face and bool(np.array_equal(self.bary, other.bary))

    def __hash__(self) -> int:
        return hash((self.face, self.bary.tobytes()))

    def position(self, mesh: Any) -> np.ndarray:
        """(3,) float ndarray: the point's position on ``mesh`` (a TriMesh or ``(V, F)``)."""
        mesh = _mesh(mesh)
        _check_face(self, mesh, "point")
        return self.bary @ mesh.V[mesh.F[self.face]]


@dataclass(frozen=True, eq=False)
class SurfaceCurve:
    """A polyline on the surface used as one source: the distance is to the whole curve.

    Parameters
    ----------
    points : sequence of SurfacePoint, or (k, 3) float array_like of positions
        The polyline's vertices, in order (they may be mixed). Positions must lie on the
        surface (within ``1e-6`` of the bounding-box diagonal; checked when the curve is
        used). Each segment is sampled at an eighth of the mean edge length and every sample
        projected to the surface, so on a curved surface the segment follows the surface
        under its chord: keep segments short against the surface's curvature (a chord through
        the inside of a sphere projects to an ill-defined curve).

    Examples
    --------
    >>> import cvxgeodesic as cg
    >>> curve = cg.SurfaceCurve([[0.2, 0.5, 0.0], [0.8, 0.5, 0.0]])
    >>> len(curve.points)
    2
    """

    points: tuple

    def __post_init__(self):
        pts = self.points
        if isinstance(pts, np.ndarray):
            if pts.ndim != 2 or pts.shape[1] != 3:
                raise SourceError(f"SurfaceCurve points must be (k, 3) positions or SurfacePoints, got {pts.shape}")
            pts = [row for row in pts]
        if isinstance(pts, SurfacePoint | str) or not isinstance(pts, Sequence | np.ndarray):
            raise SourceError(f"SurfaceCurve points must be a sequence of SurfacePoints or positions, got {pts!r}")
        items = []
        for k, p in enumerate(pts):
            if isinstance(p, SurfacePoint):
                items.append(p)
                continue
            try:
                x = np.asarray(p, dtype=float).reshape(-1)
            except (TypeError, ValueError):
                raise SourceError(
                    f"SurfaceCurve point {k} must be a SurfacePoint or 3 coordinates, got {p!r}") from None
            if x.shape != (3,) or not np.all(np.isfinite(x)):
                raise SourceError(f"SurfaceCurve point {k} must be a SurfacePoint or 3 finite coordinates, got {p!r}")
            x.setflags(write=False)
            items.append(x)
        if not items:
            raise SourceError("SurfaceCurve has no points")
        object.__setattr__(self, "points", tuple(items))

    def __repr__(self) -> str:
        return f"SurfaceCurve({len(self.points)} points)"


def _mesh(mesh) -> TriMesh:
    from .mesh.io import as_trimesh

    return as_trimesh(mesh)


def _check_face(p: SurfacePoint, mesh: TriMesh, label: str) -> None:
    if p.face >= mesh.n_faces:
        raise SourceError(f"{label} {p!r}: face index {p.face} is out of range: the mesh has {mesh.n_faces} faces "
                          f"(0..{mesh.n_faces - 1})")


# ---------------------------------------------------------------------------------------------------------------
# closest points
# ---------------------------------------------------------------------------------------------------------------
def _barycentric(T: np.ndarray, X: np.ndarray) -> np.ndarray:
    """(k, 3) barycentric coordinates of points ``X`` (k, 3) in triangles ``T`` (k, 3, 3), clipped to the face."""
    return clipped_barycentric(X, T[:, 0], T[:, 1], T[:, 2])


def closest_points(mesh: TriMesh, X) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Closest surface points of positions (one search in the mesh's
    :func:`~cvxgeodesic.mesh.closest.closest_point_index`).

    Parameters
    ----------
    mesh : TriMesh
    X : (k, 3) float array_like
        Finite positions.

    Returns
    -------
    faces : (k,) int64 ndarray
    bary : (k, 3) float ndarray
    dist : (k,) float ndarray
        Distance from each position to its closest point.
    """
    X = np.ascontiguousarray(np.asarray(X, dtype=np.float64).reshape(-1, 3))
    index = closest_point_index(mesh)
    faces, C, dist = index.query(X)
    return faces, _barycentric(index.V[index.F[faces]], C), dist  # in the search's frame: the same coordinates


def surface_point(mesh: Any, xyz: ArrayLike) -> SurfacePoint | list[SurfacePoint]:
    """The closest :class:`SurfacePoint` of a 3D position (or of each of ``k`` positions).

    Parameters
    ----------
    mesh : TriMesh or tuple (V, F)
    xyz : (3,) or (k, 3) float array_like

    Returns
    -------
    SurfacePoint, or list of SurfacePoint for a ``(k, 3)`` input

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


# ---------------------------------------------------------------------------------------------------------------
# normalized source sets
# ---------------------------------------------------------------------------------------------------------------
@dataclass
class SourceSet:
    """Any accepted ``sources`` value, normalized against one mesh.

    Attributes
    ----------
    vertices : (k,) int64 ndarray
        Vertex sources (fixed at 0), including points that lie on a vertex and boundary vertices.
    point_faces : (p,) int64 ndarray
        Face of each point source; a point on an edge appears once per face of the edge.
    point_bary : (p, 3) float ndarray
        Its barycentric coordinates in that face.
    segment_faces : (s,) int64 ndarray
        Face of each curve (or boundary) piece that is straight within one face.
    segment_bary : (s, 2, 3) float ndarray
        Barycentric coordinates of the piece's two ends in that face.
    kind : str
        ``"vertices"``, ``"points"``, ``"curve"``, ``"boundary"`` or ``"mixed"``.
    description : str
        Short text for messages and plot titles.
    """

    vertices: np.ndarray
    point_faces: np.ndarray
    point_bary: np.ndarray
    segment_faces: np.ndarray
    segment_bary: np.ndarray
    kind: str
    description: str

    @property
    def vertex_only(self) -> bool:
        """True when every source is a vertex (the classic problem)."""
        return self.point_faces.size == 0 and self.segment_faces.size == 0

    def point_positions(self, mesh: TriMesh) -> np.ndarray:
        """(p, 3) float ndarray: positions of the point sources on ``mesh``."""
        if not self.point_faces.size:
            return np.zeros((0, 3))
        return np.einsum("pk,pkj->pj", self.point_bary, mesh.V[mesh.F[self.point_faces]])

    def source_faces(self) -> np.ndarray:
        """(q,) int64 ndarray: faces that contain a point source or a curve piece (sorted, unique)."""
        return np.unique(np.concatenate([self.point_faces, self.segment_faces])).astype(np.int64)

    def distinct_points(self, mesh: TriMesh) -> list[SurfacePoint]:
        """The point sources once each: a point on an edge, listed here once per face of the edge, comes back once
        (in its first face).

        Returns
        -------
        list of SurfacePoint
        """
        out: list[SurfacePoint] = []
        seen: set[tuple] = set()
        for f, b in zip(self.point_faces.tolist(), self.point_bary, strict=True):
            nz = np.flatnonzero(b > 0)
            key = tuple(sorted(zip(mesh.F[f, nz].tolist(), b[nz].tolist(), strict=True)))
            if key not in seen:
                seen.add(key)
                out.append(SurfacePoint(f, b))
        return out

    def anchor_vertices(self, mesh: TriMesh) -> np.ndarray:
        """(r,) int64 ndarray: vertices whose connected components contain a source."""
        return np.unique(np.concatenate([self.vertices, mesh.F[self.source_faces()].ravel()])).astype(np.int64)


def _incident_faces(mesh: TriMesh) -> sp.csr_matrix:
    """(n, m) csr_matrix with a 1 where a vertex belongs to a face (cached on the mesh object)."""
    cached = getattr(mesh, "_cg_vertex_faces", None)
    if cached is None:
        m = mesh.n_faces
        cached = sp.csr_matrix((np.ones(3 * m), (mesh.F.ravel(), np.repeat(np.arange(m), 3))),
                               shape=(mesh.n_vertices, m))
        mesh._cg_vertex_faces = cached
    return cached


def boundary_edges(mesh: TriMesh) -> tuple[np.ndarray, np.ndarray]:
    """Edges with a single face.

    Returns
    -------
    edges : (b, 2) int64 ndarray
    faces : (b,) int64 ndarray
        The face of each boundary edge.
    """
    F = mesh.F
    n = mesh.n_vertices
    E = np.sort(np.concatenate([F[:, [1, 2]], F[:, [2, 0]], F[:, [0, 1]]]), axis=1)
    face_of = np.tile(np.arange(mesh.n_faces), 3)
    keys = E[:, 0] * n + E[:, 1]
    uniq, idx, counts = np.unique(keys, return_index=True, return_counts=True)
    one = idx[counts == 1]
    return E[one].astype(np.int64), face_of[one].astype(np.int64)


class _Builder:
    """Accumulates vertices, points and pieces while resolving, with snapping."""

    def __init__(self, mesh: TriMesh):
        self.mesh = mesh
        self.vertices: list[int] = []
        self.pf: list[int] = []
        self.pb: list[np.ndarray] = []
        self.sf: list[int] = []
        self.sb: list[np.ndarray] = []

    def add_point(self, p: SurfacePoint) -> None:
        """Snap to a vertex or an edge, else an interior point."""
        self.add_bary(p.face, p.bary)

    def add_bary(self, face: int, b: np.ndarray) -> None:
        """:meth:`add_point` of a face and valid barycentric coordinates (``>= 0``, summing to 1)."""
        F = self.mesh.F
        k = int(np.argmax(b))
        if b[k] >= 1.0 - BARY_SNAP:
            self.vertices.append(int(F[face, k]))
            return
        zero = b <= BARY_SNAP
        if zero.any():
            b = np.where(zero, 0.0, b)
            b = b / b.sum()
            on = np.flatnonzero(~zero)  # exactly two corners: an edge point
            va, vb = int(F[face, on[0]]), int(F[face, on[1]])
            inc = _incident_faces(self.mesh)  # the faces of a vertex: its row's indices (no sparse slicing)
            shared = np.intersect1d(inc.indices[inc.indptr[va]:inc.indptr[va + 1]],
                                    inc.indices[inc.indptr[vb]:inc.indptr[vb + 1]])
            for g in shared:
                bg = np.zeros(3)
                bg[F[g] == va] = b[on[0]]
                bg[F[g] == vb] = b[on[1]]
                self.pf.append(int(g))
                self.pb.append(bg)
            return
        self.pf.append(int(face))
        self.pb.append(np.array(b, dtype=float))

    def add_piece(self, face: int, ba: np.ndarray, bb: np.ndarray) -> None:
        self.sf.append(int(face))
        self.sb.append(np.stack([ba, bb]))

    def build(self, kind: str, description: str) -> SourceSet:
        return SourceSet(
            vertices=np.unique(np.asarray(self.vertices, dtype=np.int64)),
            point_faces=np.asarray(self.pf, dtype=np.int64),
            point_bary=np.asarray(self.pb, dtype=float).reshape(-1, 3),
            segment_faces=np.asarray(self.sf, dtype=np.int64),
            segment_bary=np.asarray(self.sb, dtype=float).reshape(-1, 2, 3),
            kind=kind, description=description,
        )


def _curve_points(mesh: TriMesh, curve: SurfaceCurve, label: str) -> list[SurfacePoint]:
    """The curve's points as SurfacePoints; positions are checked to lie on the surface (one search for all)."""
    tol = ON_SURFACE_TOL * mesh.bbox_diagonal
    given = [k for k, p in enumerate(curve.points) if not isinstance(p, SurfacePoint)]
    found = {}
    if given:
        faces, bary, dist = closest_points(mesh, np.stack([curve.points[k] for k in given]))
        found = {k: (int(f), b, d) for k, f, b, d in zip(given, faces, bary, dist, strict=True)}
    out = []
    for k, p in enumerate(curve.points):
        if isinstance(p, SurfacePoint):
            _check_face(p, mesh, f"{label} point {k}")
            out.append(p)
            continue
        face, bc, d = found[k]
        if d > tol:
            raise SourceError(
                f"{label} point {k} at {[round(float(x), 9) for x in p]} is {d:.3g} from the surface, more than "
                f"{ON_SURFACE_TOL:g} of the bounding-box diagonal ({tol:.3g}); project it with "
                "surface_point(mesh, xyz) first")
        out.append(SurfacePoint(face, bc))
    return out


def _curve_samples(mesh: TriMesh, pts: list[SurfacePoint]) -> tuple[np.ndarray, np.ndarray]:
    """The curve's samples: its points, and between two of them the closest surface points of their chord at
    :data:`CURVE_STEP` (all searched at once).

    Returns
    -------
    faces : (s,) int64 ndarray
    bary : (s, 3) float ndarray
        The samples in order along the curve.
    """
    step = CURVE_STEP * mesh.mean_edge_length
    X = np.stack([p.position(mesh) for p in pts])
    counts = np.ones(len(pts) - 1, dtype=np.int64)
    if step > 0:
        counts = np.maximum(1, np.ceil(np.linalg.norm(np.diff(X, axis=0), axis=1) / step)).astype(np.int64)
    # segment j's inner samples at t = i / counts[j], i = 1 .. counts[j] - 1, as np.linspace places them
    seg = np.repeat(np.arange(len(counts)), counts - 1)
    t = np.concatenate([np.linspace(0.0, 1.0, k + 1)[1:-1] for k in counts.tolist()] or [np.zeros(0)])[:, None]
    inner_f, inner_b, _ = closest_points(mesh, (1 - t) * X[seg] + t * X[seg + 1])
    # each point, then its segment's inner samples: point j sits after the samples of the segments before it
    where = np.arange(len(pts)) + np.concatenate([[0], np.cumsum(counts - 1)])
    faces = np.empty(len(pts) + len(seg), dtype=np.int64)
    bary = np.empty((faces.size, 3))
    inner = np.ones(faces.size, dtype=bool)
    inner[where] = False
    faces[where] = [p.face for p in pts]
    bary[where] = [p.bary for p in pts]
    faces[inner], bary[inner] = inner_f, inner_b
    return faces, bary


def _add_curve(builder: _Builder, mesh: TriMesh, curve: SurfaceCurve, label: str) -> None:
    pts = _curve_points(mesh, curve, label)
    faces, bary = _curve_samples(mesh, pts)
    # every sample as a SurfacePoint stores it (clipped to >= 0, summing to 1), then snapped
    points = np.clip(bary, 0.0, None)
    points /= points.sum(axis=1, keepdims=True)
    for f, b in zip(faces.tolist(), points, strict=True):
        builder.add_bary(f, b)
    for f, ba, bb in _curve_pieces(mesh, faces, bary):
        builder.add_piece(f, ba, bb)


def _curve_pieces(mesh: TriMesh, faces: np.ndarray, bary: np.ndarray) -> list[tuple[int, np.ndarray, np.ndarray]]:
    """The straight pieces between consecutive samples that lie in one face, in order.

    Two samples in one face make a piece of that face; two samples in two faces make one when both lie in one of
    the two faces (through a shared edge or vertex), expressed in it.

    Returns
    -------
    list of (face, bary_a (3,), bary_b (3,))
    """
    V, F = mesh.V, mesh.F
    fa, fb, ba, bb = faces[:-1], faces[1:], bary[:-1], bary[1:]
    out: list = [None] * fa.size
    for i in np.flatnonzero(fa == fb).tolist():
        out[i] = (int(fa[i]), ba[i], bb[i])
    cross = np.flatnonzero(fa != fb)
    if cross.size:
        def at(b, T):  # positions b @ T row by row (matmul: the same rounding as one point's b @ T)
            return np.matmul(b[:, None, :], T)[:, 0, :]

        xa, xb = at(ba[cross], V[F[fa[cross]]]), at(bb[cross], V[F[fb[cross]]])
        tol = 1e-12 * mesh.bbox_diagonal
        left = np.ones(cross.size, dtype=bool)
        for g in (fa[cross], fb[cross]):  # the first face, then the second
            T = V[F[g]]
            ga, gb = _barycentric(T, xa), _barycentric(T, xb)
            ok = (left & (np.linalg.norm(at(ga, T) - xa, axis=1) <= tol)
                  & (np.linalg.norm(at(gb, T) - xb, axis=1) <= tol))
            for j in np.flatnonzero(ok).tolist():
                out[int(cross[j])] = (int(g[j]), ga[j], gb[j])
            left &= ~ok
    return [piece for piece in out if piece is not None]


def _is_int_like(x) -> bool:
    return isinstance(x, numbers.Integral) and not isinstance(x, bool | np.bool_)


def resolve_sources(mesh: TriMesh, sources) -> SourceSet:
    """Normalize any accepted ``sources`` value against ``mesh``.

    Parameters
    ----------
    mesh : TriMesh
    sources : int, sequence of int, SurfacePoint, SurfaceCurve, "boundary", or a list mixing ints,
        SurfacePoints and SurfaceCurves

    Returns
    -------
    SourceSet

    Raises
    ------
    SourceError
        Anything else, naming the offending item: invalid vertex indices (see
        :func:`~cvxgeodesic.validation.validate_sources`), a face index out of range, a curve
        point off the surface, ``"boundary"`` on a closed mesh, an unknown string.
    """

    if isinstance(sources, SourceSet):
        return sources
    n = mesh.n_vertices
    if isinstance(sources, str):
        if sources.lower() != "boundary":
            raise SourceError(f"unknown source {sources!r}: sources must be integer vertex indices, SurfacePoints, "
                              "SurfaceCurves or 'boundary' (the only named source)")
        E, faces = boundary_edges(mesh)
        if not len(E):
            raise SourceError(f"sources='boundary' but {mesh.name} is closed: it has no boundary edge "
                              "(an edge with a single face)")
        builder = _Builder(mesh)
        builder.vertices.extend(np.unique(E).tolist())
        F = mesh.F
        for (a, b), f in zip(E, faces, strict=True):
            ba = (F[f] == a).astype(float)
            bb = (F[f] == b).astype(float)
            builder.add_piece(int(f), ba, bb)
        return builder.build("boundary", f"boundary ({len(E)} edges)")
    if isinstance(sources, SurfacePoint | SurfaceCurve):
        sources = [sources]
    if (isinstance(sources, tuple) and len(sources) == 2 and _is_int_like(sources[0])
            and np.ndim(sources[1]) == 1 and np.size(sources[1]) == 3):
        raise SourceError(f"sources = {sources!r} looks like a (face, bary) pair: give a point inside a face as "
                          f"cg.SurfacePoint({sources[0]}, {list(sources[1])})")
    if isinstance(sources, list | tuple) and any(isinstance(s, SurfacePoint | SurfaceCurve | str) for s in sources):
        builder = _Builder(mesh)
        kinds = set()
        for k, s in enumerate(sources):
            label = f"source {k}"
            if isinstance(s, SurfacePoint):
                _check_face(s, mesh, label)
                builder.add_point(s)
                kinds.add("points")
            elif isinstance(s, SurfaceCurve):
                _add_curve(builder, mesh, s, f"{label} (SurfaceCurve)")
                kinds.add("curve")
            elif _is_int_like(s) or (isinstance(s, float | np.floating) and float(s).is_integer()):
                try:
                    builder.vertices.append(int(validate_sources(s, n)[0]))
                except SourceError as exc:
                    raise SourceError(f"{label}: {exc}") from None
                kinds.add("vertices")
            else:
                raise SourceError(f"{label} must be a vertex index, a SurfacePoint or a SurfaceCurve, got {s!r}"
                                  + (" ('boundary' must be given alone)" if isinstance(s, str) else ""))
        kind = kinds.pop() if len(kinds) == 1 else "mixed"
        return builder.build(kind, _describe(sources))
    src = validate_sources(sources, n)
    return SourceSet(vertices=src, point_faces=np.zeros(0, np.int64), point_bary=np.zeros((0, 3)),
                     segment_faces=np.zeros(0, np.int64), segment_bary=np.zeros((0, 2, 3)), kind="vertices",
                     description=f"vertices {src.tolist()}" if src.size <= 8 else f"{src.size} vertices")


def _describe(items) -> str:
    parts = []
    for s in items[:4]:
        parts.append(repr(s) if not _is_int_like(s) else f"vertex {int(s)}")
    return ", ".join(parts) + (f" and {len(items) - 4} more" if len(items) > 4 else "")


# ---------------------------------------------------------------------------------------------------------------
# constraints of the convex formulations
# ---------------------------------------------------------------------------------------------------------------
@dataclass
class SourceConstraints:
    """What the sources add to a formulation (read by :func:`~cvxgeodesic.formulations.build_problem`).

    Attributes
    ----------
    fixed : (k,) int64 ndarray
        Vertices fixed at 0.
    no_cone : (m,) bool ndarray
        Faces that carry no cone.
    star_other, star_source : (e,) int64 ndarray
        Edge bounds ``d[star_other] − d[star_source] ≤ star_rhs``.
    star_rhs : (e,) float ndarray
    bound_vertices : (b,) int64 ndarray
        Vertex bounds ``d[bound_vertices] ≤ bound_rhs`` (free vertices only, one per vertex).
    bound_rhs : (b,) float ndarray
    anchors : (r,) int64 ndarray
        Vertices whose components contain a source (the others are unreachable).
    """

    fixed: np.ndarray
    no_cone: np.ndarray
    star_other: np.ndarray
    star_source: np.ndarray
    star_rhs: np.ndarray
    bound_vertices: np.ndarray
    bound_rhs: np.ndarray
    anchors: np.ndarray


def _segment_parameter(P: np.ndarray, A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """(k,) parameter ``t ∈ [0, 1]`` of the closest point ``A + t (B − A)`` to each point P (all (k, 3))."""
    ab = B - A
    den = np.einsum("ij,ij->i", ab, ab)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(den > 0, np.einsum("ij,ij->i", P - A, ab) / den, 0.0)
    return np.clip(t, 0.0, 1.0)


def _segment_distance(P: np.ndarray, A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """(k,) distances from points P to segments [A, B] (all (k, 3))."""
    t = _segment_parameter(P, A, B)
    return np.linalg.norm(P - (A + t[:, None] * (B - A)), axis=1)


def _segment_ends(mesh: TriMesh, ss: SourceSet) -> tuple[np.ndarray, np.ndarray]:
    T = mesh.V[mesh.F[ss.segment_faces]]
    return (np.einsum("sk,skj->sj", ss.segment_bary[:, 0], T), np.einsum("sk,skj->sj", ss.segment_bary[:, 1], T))


def vertex_bounds(mesh: TriMesh, ss: SourceSet, medium: Any = None) -> np.ndarray:
    """Upper bounds of the distance at the vertices of the source faces.

    Parameters
    ----------
    mesh : TriMesh
    ss : SourceSet
    medium : Medium, optional
        A travel cost or metric (:mod:`cvxgeodesic.operators.metric`): the segments are measured in it (to a
        curve piece: to its Euclidean closest point), normalized as its edge lengths.

    Returns
    -------
    (n,) float ndarray
        ``min |v − p|`` over the point sources ``p`` in a face of ``v`` and the distance to the curve
        pieces in a face of ``v`` (straight segments within one flat face, so each is the length of a
        surface path); ``inf`` at other vertices.
    """
    F, V = mesh.F, mesh.V
    bound = np.full(mesh.n_vertices, np.inf)
    eye = np.eye(3)
    if ss.point_faces.size:
        X = ss.point_positions(mesh)
        Fv = F[ss.point_faces]  # (p, 3)
        if medium is None:
            dist = np.linalg.norm(V[Fv] - X[:, None, :], axis=2)
        else:
            dist = np.stack([medium.segment_lengths(ss.point_faces, ss.point_bary, eye[i]) for i in range(3)], 1)
        np.minimum.at(bound, Fv.ravel(), dist.ravel())
    if ss.segment_faces.size:
        Fs = F[ss.segment_faces]
        A, B = _segment_ends(mesh, ss)
        for i in range(3):
            if medium is None:
                dist = _segment_distance(V[Fs[:, i]], A, B)
            else:  # a path to the Euclidean closest point of the piece, measured in the medium
                t = _segment_parameter(V[Fs[:, i]], A, B)[:, None]
                closest = (1 - t) * ss.segment_bary[:, 0] + t * ss.segment_bary[:, 1]
                dist = medium.segment_lengths(ss.segment_faces, closest, eye[i])
            np.minimum.at(bound, Fs[:, i], dist)
    return bound


def source_constraints(ops, sources, min_edge_bound: float) -> SourceConstraints:
    """Constraints of a source set (or of validated source vertices) for one mesh.

    Parameters
    ----------
    ops : MeshOperators
        The mesh (possibly the solver's rescaled copy), its gradient blocks and degenerate faces.
    sources : (k,) int64 ndarray or SourceSet
    min_edge_bound : float
        The formulations' floor of the edge bounds (:data:`~cvxgeodesic.formulations.MIN_EDGE_BOUND`),
        as a fraction of the bounding-box diagonal; passed in so that sources do not import the formulations.

    Returns
    -------
    SourceConstraints
    """
    mesh = ops.mesh
    n, F, E = mesh.n_vertices, mesh.F, mesh.edges
    # the formulations' floor of the edge bounds, also for the vertex bounds next to a point that almost
    # touches a vertex: it keeps them inequalities
    floor = min_edge_bound * mesh.bbox_diagonal
    ell = np.maximum(ops.edge_lengths, floor)
    medium = getattr(ops, "medium", None)
    ss = sources if isinstance(sources, SourceSet) else None
    fixed = np.asarray(ss.vertices if ss is not None else sources, dtype=np.int64)
    is_source = np.zeros(n, dtype=bool)
    is_source[fixed] = True
    no_cone = is_source[F].any(axis=1)
    star = is_source[E[:, 0]] ^ is_source[E[:, 1]]
    s_end = np.where(is_source[E[star, 0]], E[star, 0], E[star, 1])
    o_end = np.where(is_source[E[star, 0]], E[star, 1], E[star, 0])
    star_rhs = ell[star]
    empty = np.zeros(0, dtype=np.int64)
    if ss is None or (not ss.point_faces.size and not ss.segment_faces.size):
        return SourceConstraints(fixed, no_cone, o_end, s_end, star_rhs, empty, np.zeros(0), fixed)

    V = mesh.V
    bound = vertex_bounds(mesh, ss, medium)
    A, B = _segment_ends(mesh, ss)
    src_faces = ss.source_faces()
    no_cone[src_faces] = True
    src_verts = np.zeros(n, dtype=bool)
    src_verts[F[src_faces].ravel()] = True

    # faces next to the source faces where the cone of the local field min_k |v - p_k| is steeper than 1 once
    # interpolated linearly (an apex close to their edge or corner): the exact field violates their cone too
    near = src_verts[F].any(axis=1) & ~no_cone & ~ops.degenerate
    if near.any():
        from scipy.spatial import cKDTree

        pts = [ss.point_positions(mesh), V[fixed]]
        if ss.segment_faces.size:  # the pieces' ends and midpoints stand in for the pieces here
            pts += [A, B, 0.5 * (A + B)]
        P = np.concatenate(pts)
        tree = cKDTree(P)
        fn = np.flatnonzero(near)
        loc, nearest = tree.query(V[F[fn]].reshape(-1, 3))
        e = loc.reshape(-1, 3)
        if medium is not None:  # the local field in the medium: the distance to the nearest point, in face fn's
            U = V[F[fn]].reshape(-1, 3) - P[nearest]
            e = medium.vector_lengths(np.repeat(fn, 3), U).reshape(-1, 3)
        g = np.einsum("tij,tj->ti", ops.gradient_blocks[fn], e)
        steep = fn[np.linalg.norm(g, axis=1) > 1.0 + 1e-9]
        no_cone[steep] = True
    # every edge from a source-face vertex to a free vertex outside them bounds that vertex (triangle inequality);
    # this keeps the vertices of steep faces bounded and costs nothing elsewhere
    a_src, b_src = src_verts[E[:, 0]], src_verts[E[:, 1]]
    one = (a_src ^ b_src) & ~is_source[E[:, 0]] & ~is_source[E[:, 1]]
    s2 = np.where(a_src[one], E[one, 0], E[one, 1])
    o2 = np.where(a_src[one], E[one, 1], E[one, 0])
    # the edges of every face left without a cone keep |d_i - d_j| <= l_ij (both ways; true of every distance
    # field): without them an edge between two free vertices of two such faces is unconstrained and the field
    # can climb above Dijkstra's (measured on a jittered grid with the boundary as source: +0.034 at one vertex)
    ei = np.unique(mesh.face_edges[no_cone & ~ops.degenerate])
    ei = ei[~is_source[E[ei, 0]] & ~is_source[E[ei, 1]]]
    o2 = np.concatenate([o2, E[ei, 0], E[ei, 1]])
    s2 = np.concatenate([s2, E[ei, 1], E[ei, 0]])
    rhs2 = np.concatenate([ell[one], ell[ei], ell[ei]])
    bv = np.flatnonzero(np.isfinite(bound) & ~is_source)
    anchors = np.unique(np.concatenate([fixed, F[src_faces].ravel()])).astype(np.int64)
    return SourceConstraints(
        fixed=fixed, no_cone=no_cone,
        star_other=np.concatenate([o_end, o2]).astype(np.int64),
        star_source=np.concatenate([s_end, s2]).astype(np.int64),
        star_rhs=np.concatenate([star_rhs, rhs2]),
        bound_vertices=bv.astype(np.int64), bound_rhs=np.maximum(bound[bv], floor), anchors=anchors,
    )
