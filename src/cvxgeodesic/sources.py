"""Sources of a distance field on a surface (triangles) or inside a solid (tetrahedra), one module for both.

A source may be

- a vertex index (or several);
- a point located in a cell (:class:`CellPoint`): a :class:`SurfacePoint` (a face and 3 barycentric coordinates,
  :func:`surface_point` finds the closest one) or a :class:`VolumePoint` (a tetrahedron and 4,
  :func:`volume_point` finds the containing one); a point within ``1e-9`` (barycentric) of a vertex is that vertex;
- on a surface a :class:`SurfaceCurve`: a polyline of surface points (the distance is to the whole curve);
- the string ``"boundary"``: every boundary edge of a surface, every boundary face of a solid (the wall distance);
- in a solid :class:`BoundaryFaces`: some faces of the boundary surface (part of the wall).

:func:`resolve_sources` turns any of these (or a list mixing them) into one normalized :class:`SourceSet`, against
the mesh's cell kind (``mesh.reference``: its point type and the kinds of source it takes); :func:`vertex_bounds`
gives the upper bounds of the distance at the vertices of the sources' cells. The rows the convex program adds for
a source set are :func:`cvxgeodesic.problems.source_rows.source_constraints`. The point types and their locators
(:class:`~cvxgeodesic.mesh.locate.SurfacePoint`, :func:`~cvxgeodesic.mesh.locate.surface_point`, ...) live in
:mod:`cvxgeodesic.mesh.locate`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, cast

import numpy as np

from .errors import SourceError
from .mesh.closest import point_triangle_distance, segment_parameter
from .mesh.geometry import clipped_barycentric
from .mesh.locate import CellPoint, SurfacePoint, bary_positions, cells_around, closest_points
from .mesh.reference import TRIANGLE, ReferenceSimplex
from .mesh.simplex import SimplexMesh
from .mesh.tetmesh import TetMesh
from .mesh.trimesh import TriMesh
from .validation import is_integer, validate_sources

__all__ = ["BARY_SNAP", "CURVE_STEP", "ON_SURFACE_TOL", "BoundaryFaces", "SourceSet", "SurfaceCurve", "boundary_edges",
           "resolve_sources", "source_types", "vertex_bounds"]

#: A barycentric coordinate this close to 0 (or 1) counts as exactly 0 (1): the point is on an edge (a vertex).
BARY_SNAP = 1e-9
#: A curve point given as a position must lie this close to the surface (fraction of the bounding-box diagonal).
ON_SURFACE_TOL = 1e-6
#: Curve sampling step as a fraction of the mean edge length.
CURVE_STEP = 1.0 / 8.0


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
        items: list[Any] = []
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


@dataclass(frozen=True, eq=False)
class BoundaryFaces:
    """Some faces of the boundary surface of a tetrahedral mesh, used as one source (part of the wall).

    Parameters
    ----------
    faces : (k,) int array_like or (k, 3) int array_like
        Rows of :attr:`TetMesh.boundary_facets <cvxgeodesic.mesh.tetmesh.TetMesh.boundary_facets>` (indices), or
        the faces' three vertices (any order); checked against the mesh when used.

    Examples
    --------
    The bottom of a unit box, found by the faces' centroids:

    >>> import numpy as np
    >>> from cvxgeodesic.mesh.tet_generate import tet_box
    >>> mesh = tet_box(2)
    >>> bottom = np.flatnonzero(mesh.V[mesh.boundary_facets].mean(axis=1)[:, 2] == 0)
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
        """(k,) int64 ndarray: sorted unique rows of ``mesh.boundary_facets``.

        Raises
        ------
        SourceError
            An index out of range, or a vertex triple that is no boundary face of ``mesh``.
        """
        B = mesh.boundary_facets
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


# ---------------------------------------------------------------------------------------------------------------
# normalized source sets
# ---------------------------------------------------------------------------------------------------------------
@dataclass
class SourceSet:
    """Any accepted ``sources`` value, normalized against one mesh (a surface or a solid).

    Attributes
    ----------
    vertices : (k,) int64 ndarray
        Vertex sources (fixed at 0, unique), including points that lie on a vertex and boundary vertices.
    point_faces : (p,) int64 ndarray
        Cell (face, tetrahedron) of each point source; on a surface a point on an edge appears once per face of the
        edge.
    point_bary : (p, dim + 1) float ndarray
        Its barycentric coordinates in that cell.
    segment_faces : (s,) int64 ndarray
        Face of each curve (or boundary) piece that is straight within one face (surfaces).
    segment_bary : (s, 2, 3) float ndarray
        Barycentric coordinates of the piece's two ends in that face.
    kind : str
        ``"vertices"``, ``"points"``, ``"curve"``, ``"boundary"``, ``"faces"`` or ``"mixed"``.
    description : str
        Short text for messages and plot titles.
    facets : (f,) int64 ndarray
        Source facets, sorted rows of ``mesh.boundary_facets`` (volumes: ``"boundary"`` and :class:`BoundaryFaces`;
        their vertices are fixed at 0).
    reference : ReferenceSimplex
        The cell kind of the mesh (``mesh.reference``): the type of :attr:`points`.
    """

    vertices: np.ndarray
    point_faces: np.ndarray
    point_bary: np.ndarray
    segment_faces: np.ndarray
    segment_bary: np.ndarray
    kind: str
    description: str
    facets: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    reference: ReferenceSimplex = TRIANGLE

    @property
    def vertex_only(self) -> bool:
        """True when every source is a vertex (the classic problem)."""
        return self.point_faces.size == 0 and self.segment_faces.size == 0 and self.facets.size == 0

    @property
    def points(self) -> tuple[CellPoint, ...]:
        """The point sources as objects of the cell kind's point type (``SurfacePoint``, ``VolumePoint``; see
        :attr:`point_faces`)."""
        kind: Any = self.reference.point_type  # a CellPoint subclass
        return tuple(kind._exact(c, b) for c, b in zip(self.point_faces.tolist(), self.point_bary, strict=True))

    @property
    def boundary(self) -> bool:
        """True when the source is the whole boundary."""
        return self.kind == "boundary"

    @property
    def faces(self) -> np.ndarray:
        """(f,) int64 ndarray: :attr:`facets` (the source faces of a volume)."""
        return self.facets

    @property
    def count(self) -> int:
        """Number of sources: vertices, point entries, and one for the facets or curve pieces together."""
        return int(self.vertices.size) + int(self.point_faces.size) + int(self.facets.size > 0
                                                                          or self.segment_faces.size > 0)

    def point_positions(self, mesh: SimplexMesh) -> np.ndarray:
        """(p, 3) float ndarray: positions of the point sources on (in) ``mesh``."""
        return bary_positions(mesh, self.point_faces, self.point_bary)

    def segment_ends(self, mesh: TriMesh) -> tuple[np.ndarray, np.ndarray]:
        """(s, 3), (s, 3) float ndarrays: the two ends of each curve (boundary) piece."""
        return (bary_positions(mesh, self.segment_faces, self.segment_bary[:, 0]),
                bary_positions(mesh, self.segment_faces, self.segment_bary[:, 1]))

    def source_faces(self) -> np.ndarray:
        """(q,) int64 ndarray: cells that contain a point source or a curve piece (sorted, unique)."""
        return np.unique(np.concatenate([self.point_faces, self.segment_faces])).astype(np.int64)

    def distinct_points(self, mesh: SimplexMesh) -> list[CellPoint]:
        """The point sources once each: a point on an edge, listed here once per face of the edge, comes back once
        (in its first face).

        Returns
        -------
        list of SurfacePoint or VolumePoint
        """
        out: list[CellPoint] = []
        seen: set[tuple] = set()
        for p in self.points:
            nz = np.flatnonzero(p.bary > 0)
            key = tuple(sorted(zip(mesh.cells[p.cell, nz].tolist(), p.bary[nz].tolist(), strict=True)))
            if key not in seen:
                seen.add(key)
                out.append(p)
        return out

    def face_triangles(self, mesh: SimplexMesh) -> np.ndarray:
        """(f, dim) int64 ndarray: the source facets' vertices."""
        return mesh.boundary_facets[self.facets]

    def face_slots(self, mesh: TetMesh) -> tuple[np.ndarray, np.ndarray]:
        """The tetrahedron of each source face and the local index of its corner opposite the face:
        ``(tets (f,), local (f,))`` (``mesh.tet_faces[tets, local]`` are the faces' rows of ``mesh.faces``)."""
        tets = mesh.boundary_face_tets[self.facets]
        on_face = (mesh.T[tets][:, :, None] == self.face_triangles(mesh)[:, None, :]).any(axis=2)
        return tets, np.argmin(on_face, axis=1)

    def fixed_vertices(self, mesh: SimplexMesh) -> np.ndarray:
        """(q,) int64 ndarray: vertices where the distance is 0 (source vertices, vertices of source facets)."""
        return np.unique(np.concatenate([self.vertices, self.face_triangles(mesh).ravel()])).astype(np.int64)

    def seed_vertices(self, mesh: SimplexMesh) -> np.ndarray:
        """(q,) int64 ndarray: vertices from which the field spreads (the fixed ones and the points' corners)."""
        parts = [self.fixed_vertices(mesh), mesh.cells[self.point_faces].ravel()]
        return np.unique(np.concatenate(parts)).astype(np.int64)

    def anchor_vertices(self, mesh: SimplexMesh) -> np.ndarray:
        """(r,) int64 ndarray: vertices whose connected components contain a source."""
        return np.unique(np.concatenate([self.fixed_vertices(mesh), mesh.cells[self.source_faces()].ravel()])
                         ).astype(np.int64)

    def local_values(self, mesh: SimplexMesh) -> tuple[np.ndarray, np.ndarray]:
        """Vertices at or next to the sources and their exact distances: 0 at fixed vertices, ``|v − p|`` at the
        corners of a point's cell (the minimum where several meet). Returns ``(vertices (q,), values (q,))``."""
        fixed = self.fixed_vertices(mesh)
        corners = mesh.cells[self.point_faces]
        dist = np.linalg.norm(mesh.V[corners] - self.point_positions(mesh)[:, None, :], axis=2)
        verts, vals = np.concatenate([fixed, corners.ravel()]), np.concatenate([np.zeros(fixed.size), dist.ravel()])
        uniq, inv = np.unique(verts, return_inverse=True)
        best = np.full(uniq.size, np.inf)
        np.minimum.at(best, inv, vals)
        return uniq.astype(np.int64), best


def boundary_edges(mesh: SimplexMesh) -> tuple[np.ndarray, np.ndarray]:
    """Edges with a single cell (on a surface
    :attr:`TriMesh.boundary_facets <cvxgeodesic.mesh.trimesh.TriMesh.boundary_facets>`).

    Returns
    -------
    edges : (b, 2) int64 ndarray
    faces : (b,) int64 ndarray
        The cell of each boundary edge.
    """
    one = mesh.edge_cell_counts == 1
    face_of = np.empty(len(one), dtype=np.int64)
    per_cell = mesh.cell_edges.shape[1]
    face_of[mesh.cell_edges.ravel()] = np.repeat(np.arange(mesh.n_cells), per_cell)  # exact where an edge has one
    return mesh.edges[one], face_of[one]


class _Builder:
    """Accumulates vertices, points, pieces and facets while resolving, with snapping."""

    def __init__(self, mesh: SimplexMesh):
        self.mesh = mesh
        self.vertices: list[int] = []
        self.pf: list[int] = []
        self.pb: list[np.ndarray] = []
        self.sf: list[int] = []
        self.sb: list[np.ndarray] = []
        self.facets: list[np.ndarray] = []

    def add_bary(self, cell: int, b: np.ndarray) -> None:
        """A point of a cell and valid barycentric coordinates (``>= 0``, summing to 1), snapped.

        A point within :data:`BARY_SNAP` of a vertex is that vertex; coordinates that small become 0. On a surface a
        point on an edge is then listed in each face of the edge (its bounds hold in both); in a solid it stays in
        its tetrahedron.
        """
        C = self.mesh.cells
        k = int(np.argmax(b))
        if b[k] >= 1.0 - BARY_SNAP:
            self.vertices.append(int(C[cell, k]))
            return
        zero = b <= BARY_SNAP
        if zero.any():
            b = np.where(zero, 0.0, b)
            b = b / b.sum()
        if zero.any() and self.mesh.reference.shared_points:
            on = C[cell, np.flatnonzero(~zero)]  # the corners of the edge (facet, ...) the point lies on
            for g in cells_around(self.mesh, on.tolist()):
                bg = np.zeros(C.shape[1])
                for v, w in zip(on.tolist(), b[~zero].tolist(), strict=True):
                    bg[C[g] == v] = w
                self.pf.append(int(g))
                self.pb.append(bg)
            return
        self.pf.append(int(cell))
        self.pb.append(np.array(b, dtype=float))

    def add_piece(self, face: int, ba: np.ndarray, bb: np.ndarray) -> None:
        self.sf.append(int(face))
        self.sb.append(np.stack([ba, bb]))

    def build(self, kind: str, description: str) -> SourceSet:
        w = self.mesh.reference.n_corners
        facets = np.unique(np.concatenate(self.facets)) if self.facets else np.zeros(0)
        return SourceSet(
            vertices=np.unique(np.asarray(self.vertices, dtype=np.int64)),
            point_faces=np.asarray(self.pf, dtype=np.int64),
            point_bary=np.asarray(self.pb, dtype=float).reshape(-1, w),
            segment_faces=np.asarray(self.sf, dtype=np.int64),
            segment_bary=np.asarray(self.sb, dtype=float).reshape(-1, 2, 3),
            kind=kind, description=description, facets=facets.astype(np.int64), reference=self.mesh.reference,
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
            p.check(mesh, f"{label} point {k}")
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
    fa, fb, ba, bb = faces[:-1], faces[1:], bary[:-1], bary[1:]
    out: list = [None] * fa.size
    for i in np.flatnonzero(fa == fb).tolist():
        out[i] = (int(fa[i]), ba[i], bb[i])
    cross = np.flatnonzero(fa != fb)
    xa, xb = bary_positions(mesh, fa[cross], ba[cross]), bary_positions(mesh, fb[cross], bb[cross])
    tol = 1e-12 * mesh.bbox_diagonal
    left = np.ones(cross.size, dtype=bool)
    for g in (fa[cross], fb[cross]):  # the first face, then the second
        corners = mesh.V[mesh.F[g]].transpose(1, 0, 2)
        ga, gb = clipped_barycentric(xa, *corners), clipped_barycentric(xb, *corners)
        ok = (left & (np.linalg.norm(bary_positions(mesh, g, ga) - xa, axis=1) <= tol)
              & (np.linalg.norm(bary_positions(mesh, g, gb) - xb, axis=1) <= tol))
        for j in np.flatnonzero(ok).tolist():
            out[int(cross[j])] = (int(g[j]), ga[j], gb[j])
        left &= ~ok
    return [piece for piece in out if piece is not None]


#: The source object of each kind of source (:data:`cvxgeodesic.capabilities.SOURCE_KINDS`) that has one; a point is
#: the cell kind's point type (``mesh.reference.point_type``).
SOURCE_CLASSES: dict[str, type] = {"curve": SurfaceCurve, "boundary faces": BoundaryFaces}


def source_types(mesh: SimplexMesh) -> tuple[type, ...]:
    """The source objects ``mesh`` takes besides vertex indices, in the order of ``mesh.reference.source_kinds``.

    Examples
    --------
    >>> import cvxgeodesic as cg
    >>> [t.__name__ for t in source_types(cg.icosphere(1))]
    ['SurfacePoint', 'SurfaceCurve']
    >>> [t.__name__ for t in source_types(cg.tet_box(1))]
    ['VolumePoint', 'BoundaryFaces']
    """
    classes = {"point": mesh.reference.point_type, **SOURCE_CLASSES}
    return tuple(classes[k] for k in mesh.reference.source_kinds if k in classes)


def _named_source(mesh: SimplexMesh, name: str) -> SourceSet:
    """The one named source, ``"boundary"``: every boundary edge of a surface, every boundary face of a solid."""
    if name.strip().lower() != "boundary":
        kinds = ", ".join(f"{t.__name__}s" if t is not BoundaryFaces else t.__name__ for t in source_types(mesh))
        raise SourceError(f"unknown source {name!r}: sources must be integer vertex indices, {kinds} or 'boundary' "
                          "(the only named source)")
    builder = _Builder(mesh)
    # a cell kind whose boundary facets can be sources (BoundaryFaces) takes the boundary as all of them: their
    # vertices are fixed, the cells' opposite corners bounded; the others take it as curve pieces along the edges
    if "boundary faces" in mesh.reference.source_kinds:
        nb = mesh.boundary_facets.shape[0]
        if nb == 0:
            raise SourceError(f"sources='boundary' but {mesh.name} has no boundary faces")
        builder.facets.append(np.arange(nb, dtype=np.int64))
        return builder.build("boundary", f"boundary ({nb} faces)")
    E, faces = boundary_edges(mesh)
    if not len(E):
        raise SourceError(f"sources='boundary' but {mesh.name} is closed: it has no boundary edge "
                          "(an edge with a single face)")
    builder.vertices.extend(np.unique(E).tolist())
    C = mesh.cells
    for (a, b), f in zip(E, faces, strict=True):
        builder.add_piece(int(f), (C[f] == a).astype(float), (C[f] == b).astype(float))
    return builder.build("boundary", f"boundary ({len(E)} edges)")


def resolve_sources(mesh: SimplexMesh, sources: Any) -> SourceSet:
    """Normalize any accepted ``sources`` value against ``mesh``.

    Parameters
    ----------
    mesh : TriMesh or TetMesh
    sources : int, sequence of int, "boundary", a SourceSet, or
        on a surface: SurfacePoint, SurfaceCurve, or a list mixing ints, SurfacePoints and SurfaceCurves;
        in a solid: VolumePoint, BoundaryFaces, or a list mixing ints, VolumePoints and BoundaryFaces.
        A point on a vertex is that vertex (given with the vertex itself, it counts once).

    Returns
    -------
    SourceSet

    Raises
    ------
    SourceError
        Anything else, naming the offending item: invalid vertex indices (see
        :func:`~cvxgeodesic.validation.validate_sources`), a cell index out of range, a curve
        point off the surface, a face that is no boundary face, ``"boundary"`` on a mesh without boundary or mixed
        with other sources, an unknown string.
    """
    if isinstance(sources, SourceSet):
        return sources
    n, corners = mesh.n_vertices, mesh.reference.n_corners
    accepted = source_types(mesh)
    if isinstance(sources, str):
        return _named_source(mesh, sources)
    if isinstance(sources, CellPoint | SurfaceCurve | BoundaryFaces):
        sources = [sources]
    if (isinstance(sources, tuple) and len(sources) == 2 and is_integer(sources[0])
            and np.ndim(sources[1]) == 1 and np.size(sources[1]) == corners):
        kind = mesh.reference.point_type.__name__
        raise SourceError(f"sources = {sources!r} looks like a (cell, bary) pair: give a point inside a cell as "
                          f"cg.{kind}({sources[0]}, {list(sources[1])})")
    if isinstance(sources, list | tuple) and any(isinstance(s, CellPoint | SurfaceCurve | BoundaryFaces | str)
                                                 for s in sources):
        builder = _Builder(mesh)
        kinds = set()
        for k, s in enumerate(sources):
            label = f"source {k}"
            if isinstance(s, mesh.reference.point_type):
                s.check(mesh, label)
                builder.add_bary(s.cell, s.bary)
                kinds.add("points")
            elif isinstance(s, SurfaceCurve) and isinstance(s, accepted):
                _add_curve(builder, cast(TriMesh, mesh), s, f"{label} (SurfaceCurve)")  # accepted: a surface
                kinds.add("curve")
            elif isinstance(s, BoundaryFaces) and isinstance(s, accepted):
                builder.facets.append(s.resolve(cast(TetMesh, mesh)))  # accepted: a solid
                kinds.add("faces")
            elif is_integer(s) or (isinstance(s, float | np.floating) and float(s).is_integer()):
                try:
                    builder.vertices.append(int(_startable(mesh, validate_sources(s, n))[0]))
                except SourceError as exc:
                    raise SourceError(f"{label}: {exc}") from None
                kinds.add("vertices")
            else:
                names = " or ".join(t.__name__ for t in accepted)
                raise SourceError(f"{label} must be a vertex index, a {names}, got {s!r}" + (
                    "" if not isinstance(s, str) else ": 'boundary' cannot be mixed with other sources (it must be "
                    "given alone" + ("; give BoundaryFaces for part of the wall)" if BoundaryFaces in accepted
                                     else ")")))
        kind = kinds.pop() if len(kinds) == 1 else "mixed"
        return builder.build(kind, _describe(sources))
    src = _startable(mesh, validate_sources(sources, n))
    return SourceSet(vertices=src, point_faces=np.zeros(0, np.int64), point_bary=np.zeros((0, corners)),
                     segment_faces=np.zeros(0, np.int64), segment_bary=np.zeros((0, 2, 3)), kind="vertices",
                     description=f"vertices {src.tolist()}" if src.size <= 8 else f"{src.size} vertices",
                     reference=mesh.reference)


def _startable(mesh: SimplexMesh, vertices: np.ndarray) -> np.ndarray:
    """``vertices``, once the mesh has refused those no solve can start from (a point cloud's outliers)."""
    mesh.check_source_vertices(vertices)
    return vertices


def _describe(items) -> str:
    parts = [repr(s) if not is_integer(s) else f"vertex {int(s)}" for s in list(items)[:4]]
    return ", ".join(parts) + (f" and {len(items) - 4} more" if len(items) > 4 else "")


# ---------------------------------------------------------------------------------------------------------------
# bounds at the vertices around the sources (the program's rows, problems/source_rows.py, and the baselines' seeds)
# ---------------------------------------------------------------------------------------------------------------
def vertex_bounds(mesh: SimplexMesh, ss: SourceSet, medium: Any = None) -> np.ndarray:
    """Upper bounds of the distance at the vertices of the cells of the sources.

    Parameters
    ----------
    mesh : TriMesh or TetMesh
    ss : SourceSet
    medium : Medium, optional
        A travel cost or metric on a surface (:mod:`cvxgeodesic.operators.metric`): the segments are measured in
        it (to a curve piece: to its Euclidean closest point), normalized as its edge lengths.

    Returns
    -------
    (n,) float ndarray
        ``min |v − p|`` over the point sources ``p`` in a cell of ``v``, the distance to the curve pieces in a face
        of ``v`` and, at the corner of a tetrahedron opposite a source face, the distance to that face (straight
        segments within one flat cell, so each is the length of a path in the mesh); ``inf`` at other vertices.
    """
    C, V = mesh.cells, mesh.V
    bound = np.full(mesh.n_vertices, np.inf)
    eye = np.eye(3)
    X = ss.point_positions(mesh)
    Cv = C[ss.point_faces]  # (p, dim + 1)
    if medium is None:
        dist = np.linalg.norm(V[Cv] - X[:, None, :], axis=2)
    else:
        dist = np.stack([medium.segment_lengths(ss.point_faces, ss.point_bary, eye[i]) for i in range(3)], 1)
    np.minimum.at(bound, Cv.ravel(), dist.ravel())
    Fs = C[ss.segment_faces]  # the curve pieces' faces (none in a solid)
    A, B = ss.segment_ends(cast(TriMesh, mesh))  # curve pieces lie on a surface (none elsewhere)
    for i in range(3):
        t = segment_parameter(V[Fs[:, i]], A, B)[:, None]
        if medium is None:
            dist = np.linalg.norm(V[Fs[:, i]] - (A + t * (B - A)), axis=1)
        else:  # a path to the Euclidean closest point of the piece, measured in the medium
            closest = (1 - t) * ss.segment_bary[:, 0] + t * ss.segment_bary[:, 1]
            dist = medium.segment_lengths(ss.segment_faces, closest, eye[i])
        np.minimum.at(bound, Fs[:, i], dist)
    if ss.facets.size:  # the fourth corner of each source face's tetrahedron: its distance to the face
        tri = ss.face_triangles(mesh)
        t_of, local = ss.face_slots(cast(TetMesh, mesh))  # source faces bound a solid
        other = C[t_of, local]
        np.minimum.at(bound, other, point_triangle_distance(V[other], V[tri[:, 0]], V[tri[:, 1]], V[tri[:, 2]]))
    return bound
