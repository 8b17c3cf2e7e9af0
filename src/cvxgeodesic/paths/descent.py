"""Reading a distance field on a mesh: values at points, geodesic paths, on a surface or inside a volume.

:func:`geodesic_path` follows the steepest descent of the piecewise-linear field cell by cell, on triangles
and tetrahedra alike: inside a cell along ``−∇d|_t`` (constant there) to the exact crossing with its boundary;
across a facet (an edge of a triangle, a face of a tetrahedron) into the next cell when that cell's descent
direction enters it, else (a valley, or the mesh's boundary) along the facet to its lowest corner; at a vertex
into the incident cell or along the incident edge of steepest descent. It stops at a source vertex, or goes
straight to the source once it reaches a cell that holds a source point, a piece of a source curve or a source
face (a straight segment inside a flat triangle or a tetrahedron is the geodesic there); a descent that crosses
a source face of a volume ends on it. For an order-2 field inside a volume the direction is ``−∇φ`` of its
quadratic ``φ = d²``, read at the current point: the descent asks the field (:class:`~cvxgeodesic.results.Field`)
for its gradient wherever no straightening follows.

On a surface the descent then only chooses the corridor (``straighten=True``, default): the faces it crossed,
plus, at each vertex it passed through, the fan of faces around that vertex on the side of the smaller angle.
The corridor is unfolded into the plane edge by edge and the shortest path through it is found exactly (funnel
algorithm). Where that path still wraps around a corridor vertex and the angle on the vertex's other side is
smaller, the corridor goes around the other side and the path is recomputed (at most 64 times). The result is a
locally shortest path: straight on a plane (measured 2e-16 from the chord on a jittered grid, against 6e-3 ..
7e-2 for the raw descent), and within 0.1 % of the exact polyhedral distance on the unit icosphere (subdivision
4). ``straighten=False`` returns the raw descent. For a field of ``method="exact"`` (a
:class:`~cvxgeodesic.api.GeodesicResult`) from vertex or point sources to a vertex or a point, the surface path
is pygeodesic's exact (MMP) path instead (on the mesh with the points inserted as vertices).

Inside a volume the path is the raw descent, not shortened: a polyline that follows the field, whose length
exceeds the distance by a few per cent where the field's gradient turns (measured: 1.1 % on a jittered box from
the opposite corner, docs/volumes.md).
"""

from __future__ import annotations

import contextlib
import io
from collections.abc import Callable, Sequence
from typing import Any, Literal, TypeAlias, cast, overload

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike

from ..capabilities import check_path
from ..errors import ParameterError, SolverError, SourceError
from ..mesh.closest import segment_point, triangle_point
from ..mesh.convert import MeshLike, as_mesh
from ..mesh.locate import CellPoint, SurfacePoint, VolumePoint, closest_points, corner_interpolant
from ..mesh.reference import TRIANGLE, ReferenceSimplex
from ..mesh.simplex import SimplexMesh
from ..mesh.trimesh import TriMesh
from ..operators.gradient import triangle_frames
from ..operators.linear_field import LinearField
from ..operators.metric import make_medium
from ..results import Field, GeodesicResult, remembered_sources
from ..sources import BARY_SNAP, SourceSet, resolve_sources
from ..validation import as_field, check_count, is_integer
from .cells import Cells
from .corridor import node_position, straighten_corridor

#: A distance field as the functions here take it: the vertex values, the result they came from, or its field.
FieldLike: TypeAlias = ArrayLike | GeodesicResult | Field
#: A point of a mesh's cells: on a surface, or inside a volume.
MeshPoint: TypeAlias = SurfacePoint | VolumePoint

#: The straightening of each cell kind's descent (module docstring): a corridor of triangles unfolds into the plane.
#: A kind without one keeps the raw descent, which then follows the gradient of the field itself.
STRAIGHTENERS: dict[ReferenceSimplex, Callable[..., list[tuple]]] = {TRIANGLE: straighten_corridor}


def _field(mesh: SimplexMesh, distance: Any) -> tuple[np.ndarray, GeodesicResult | None, Field]:
    """The (n,) float vertex values, the result they came from (or None) and the field (a plain array's is its
    piecewise-linear interpolant)."""
    result = distance if isinstance(distance, GeodesicResult) else None
    # a result's field, whose vertex values the walk reads (not the result's distance, set to 0 at source vertices)
    d, field = as_field(distance if result is None else result.field, "distance", mesh.n_vertices, nan_ok=False)
    return d, result, LinearField(mesh, d) if field is None else field


# -- points of the cells: the point type of the mesh's reference cell (SurfacePoint, VolumePoint) -----------------
def _as_points(mesh: SimplexMesh, points: Any) -> tuple[np.ndarray, np.ndarray, bool]:
    """(cells (k,), bary (k, dim + 1), single) of points of the mesh's kind or of positions."""
    kind = mesh.reference.point_type
    found = points
    if not isinstance(points, kind) and not (isinstance(points, list | tuple)
                                             and all(isinstance(p, kind) for p in points)):
        try:
            X = np.asarray(points, dtype=float)
        except (TypeError, ValueError):
            raise SourceError(f"points must be {kind.__name__}s or (k, 3) positions") from None
        found = mesh.reference.locate(mesh, X)
    single = isinstance(found, kind)
    pts: list[CellPoint] = [found] if single else list(found)
    for k, p in enumerate(pts):
        p.check(mesh, f"point {k}")
    cells = np.array([p.cell for p in pts], dtype=np.int64)
    return cells, np.array([p.bary for p in pts]).reshape(-1, mesh.reference.n_corners), single


@overload
def distance_at(mesh: MeshLike, distance: FieldLike, points: MeshPoint) -> float: ...
@overload
def distance_at(mesh: MeshLike, distance: FieldLike, points: Sequence[MeshPoint]) -> np.ndarray: ...
@overload
def distance_at(mesh: MeshLike, distance: FieldLike, points: Sequence[float]) -> float: ...
@overload
def distance_at(mesh: MeshLike, distance: FieldLike, points: Sequence[Sequence[float]]) -> np.ndarray: ...
@overload
def distance_at(mesh: MeshLike, distance: FieldLike, points: ArrayLike) -> float | np.ndarray: ...


def distance_at(mesh: MeshLike, distance: FieldLike, points: Any) -> float | np.ndarray:
    """Values of a distance field at points of a surface or inside a volume.

    A vertex field is interpolated linearly in each cell (face or tetrahedron); a
    :class:`~cvxgeodesic.api.GeodesicResult` answers with its field (:attr:`~cvxgeodesic.api.GeodesicResult.field`):
    an ``order=2`` solve's is its piecewise quadratic squared distance, ``√φ``.

    Parameters
    ----------
    mesh : TriMesh, TetMesh, or tuple (V, F) / (V, T)
    distance : (n,) float array_like, GeodesicResult or Field
    points : SurfacePoint (VolumePoint in a TetMesh), a sequence of them, or (3,) / (k, 3) positions
        On a surface the closest points of positions are used; in a volume positions must lie inside it.

    Returns
    -------
    float for one point, else (k,) float ndarray
        ``Σ_i b_i d[cells[cell, i]]``. Typed ``float`` for a point or a sequence of 3 numbers, ``np.ndarray`` for
        a sequence of points or of sequences, the union for an ndarray of positions (its shape is unknown to a
        type checker).

    Raises
    ------
    SourceError
        A face (tetrahedron) index out of range, a position outside the volume, or points that are neither
        points of the mesh's kind nor positions.
    ParameterError
        ``distance`` of the wrong length or with NaN.

    Examples
    --------
    >>> import cvxgeodesic as cg
    >>> mesh = cg.grid_plane(4)
    >>> d = cg.geodesic_distance(mesh, 0, method="dijkstra")
    >>> round(cg.distance_at(mesh, d, cg.SurfacePoint(0, [1.0, 0.0, 0.0])), 6)
    0.0
    """
    mesh = as_mesh(mesh)
    cells, bary, single = _as_points(mesh, points)
    _, _, field = _field(mesh, distance)
    vals = field.distance_at(cells, bary)
    return float(vals[0]) if single else vals


# -- the descent's slope --------------------------------------------------------------------------------------------
class _Slope:
    """The direction of steepest descent and its rate per unit length.

    Piecewise linear (``p1``): constant in a cell, ``−∇d`` and ``|∇d|`` (in a medium on a surface ``−M⁻¹∇d`` and
    ``√(∇dᵀM⁻¹∇d)``); another ``field`` (an order-2 field in a volume): ``−∇d`` at the point, which the field
    answers (``φ = d²`` is quadratic where the source is visible, so ``−∇d`` points straight at it). NaN in cells
    the walk skips.
    """

    def __init__(self, geo: Cells, p1: LinearField, medium: Any = None, field: Field | None = None):
        mesh = geo.mesh
        self.geo, self.field = geo, field
        grad = p1.cell_gradients  # (k, 3) gradient of the field in each cell, NaN where the walk does not step
        self.adjacency = sp.csr_matrix(mesh.vertex_adjacency)
        if medium is None:
            self.down, self.rate = -grad, np.linalg.norm(grad, axis=1)
        else:
            self._in_medium(geo, grad, medium.on(mesh))

    def _in_medium(self, geo: Cells, grad: np.ndarray, medium: Any) -> None:
        """``−M_t⁻¹∇d`` and its rate in each face of a surface (the medium read at the face's centroid)."""
        self.adjacency = sp.csr_matrix(medium.adjacency())  # edge lengths in the medium, as the rates
        mesh = cast(TriMesh, geo.mesh)  # a medium lives on a surface (make_medium)
        with np.errstate(invalid="ignore", divide="ignore"):
            ex, ey = triangle_frames(mesh)
        P = medium.plane(np.arange(mesh.n_faces), np.full(3, 1 / 3))
        P[~geo.ok] = np.eye(2)
        g2 = np.stack([np.einsum("fj,fj->f", grad, ex), np.einsum("fj,fj->f", grad, ey)], 1)
        with np.errstate(invalid="ignore"):
            step = -np.linalg.solve(P, g2[:, :, None])[:, :, 0]  # −M⁻¹∇d in the face's frame
            self.down = step[:, :1] * ex + step[:, 1:] * ey
            self.rate = np.sqrt(np.maximum(-np.einsum("fi,fi->f", g2, step), 0.0))

    def at(self, c: int, b: np.ndarray) -> tuple[np.ndarray, float]:
        """(3,) descent direction and its rate at barycentric ``b`` of cell ``c``."""
        if self.field is None or not self.geo.ok[c]:
            return self.down[c], float(self.rate[c])
        g = self.field.gradient_at(np.array([c]), b[None])[0]
        return -g, float(np.linalg.norm(g))


# -- the sources as the walk ends on them ------------------------------------------------------------------------
class _Ends:
    """Where the walk stops: ``vertices`` (n,) bool; ``items`` {cell: [(q, 3) simplex]} — the source points
    (q = 1), curve pieces (2) and faces (3) in each cell, gone to straight from inside it; ``facets``, the
    source faces of a volume (frozensets of vertices), on which a crossing ends; ``ss``, the source set."""

    def __init__(self, mesh: SimplexMesh, geo: Cells, d: np.ndarray, distance: Any, result: GeodesicResult | None,
                 sources: Any):
        self.ss = _source_set(mesh, distance, result, sources)
        self.vertices = np.zeros(mesh.n_vertices, dtype=bool)
        self.items: dict[int, list[np.ndarray]] = {}
        self.facets: set[frozenset[int]] = set()
        if self.ss is None:  # unknown: the vertices where the field takes its minimum
            finite = d[np.isfinite(d)]
            self.vertices = d <= (finite.min() if finite.size else 0.0) + 1e-12 * mesh.bbox_diagonal
        else:
            self._sources(mesh, geo, self.ss)

    def _add(self, cell: int, simplex: np.ndarray) -> None:
        self.items.setdefault(int(cell), []).append(simplex)

    def _sources(self, mesh: SimplexMesh, geo: Cells, ss: SourceSet) -> None:
        """Fixed vertices; each point in every cell around it (a point on a facet or an edge in each cell that holds
        it); curve pieces in their faces; each source face in its tetrahedron, and as a wall on which the walk ends."""
        self.vertices[ss.fixed_vertices(mesh)] = True
        for f, x, b in zip(ss.point_faces, ss.point_positions(mesh), ss.point_bary, strict=True):
            for c in geo.cells_of(mesh.cells[f][b > 0]):
                self._add(c, x[None])
        if ss.segment_faces.size:  # curves are sources of surfaces (the capability table)
            for f, xa, xb in zip(ss.segment_faces, *ss.segment_ends(cast(TriMesh, mesh)), strict=True):
                self._add(f, np.stack([xa, xb]))
        for f in ss.face_triangles(mesh):  # a volume's source faces, each in its one cell
            for t in geo.cells_of(f):
                self._add(t, mesh.V[f])
            self.facets.add(frozenset(f.tolist()))

    def closest(self, cell: int, x: np.ndarray) -> tuple[np.ndarray | None, float]:
        """The source point nearest to ``x`` among those of ``cell``, and its distance."""
        best: np.ndarray | None = None
        bd = np.inf
        for S in self.items.get(cell, ()):
            y = _closest_on_simplex(x, S)
            dist = float(np.linalg.norm(x - y))
            if dist < bd:
                best, bd = y, dist
        return best, bd


def _source_set(mesh: SimplexMesh, distance: Any, result: GeodesicResult | None, sources: Any) -> Any:
    """The field's normalized sources: given, from the result, remembered by the array; None when unknown."""
    if sources is not None:
        return resolve_sources(mesh, sources)
    if result is not None:
        return result.source_set if result.source_set is not None else resolve_sources(mesh, result.sources)
    if isinstance(distance, Field):  # a result's field: its vertex values may be the result's remembered array
        distance = distance.vertex_distance
    return remembered_sources(distance)  # an array returned by geodesic_distance


def _closest_on_simplex(x: np.ndarray, S: np.ndarray) -> np.ndarray:
    """The point of the simplex ``S`` (a point (1, 3), a segment (2, 3) or a triangle (3, 3)) closest to ``x``."""
    if len(S) == 1:
        return S[0]
    return (segment_point if len(S) == 2 else triangle_point)(x[None], *S[:, None])[0]


# -- the walk ----------------------------------------------------------------------------------------------------
class _Descent:
    """The steepest-descent walk of :func:`geodesic_path`: a state ``("v", vertex)`` or ``("c", cell, bary)``.

    ``nodes`` collects the path: ``("v", vertex) | ("e", facet, cell_in, cell_out, position) | ("p", cell,
    position)``, ``facet`` the vertices of the edge (face) crossed or slid along. Each step appends what it
    crossed and returns the next state, or None at a source.
    """

    def __init__(self, geo: Cells, d: np.ndarray, ends: _Ends, slope: _Slope) -> None:
        self.geo, self.d, self.ends, self.slope = geo, d, ends, slope
        self.tol = 1e-12 * geo.mesh.bbox_diagonal
        self.nodes: list[tuple] = []

    def start(self, target: Any) -> tuple:
        """The first state, from a vertex index, a point of the mesh's kind or a position (validated)."""
        geo, d = self.geo, self.d
        p = _as_target(geo.mesh, target)
        if not isinstance(p, int) and p.bary.max() >= 1 - BARY_SNAP:  # on a vertex
            p = int(geo.C[p.cell, np.argmax(p.bary)])
        if isinstance(p, int):
            state: tuple = ("v", p)
            value = d[p]
            self.nodes.append(state)
        else:
            state = ("c", p.cell, np.where(p.bary <= BARY_SNAP, 0.0, p.bary))
            value = corner_interpolant(d[geo.C[p.cell]][None], p.bary[None])[0]
            self.nodes.append(("p", p.cell, p.position(geo.mesh)))
        if not np.isfinite(value):
            where = f"vertex {p}" if isinstance(p, int) else f"the point in cell {p.cell}"
            raise ParameterError(f"the distance is infinite at the target ({where}): no source is reachable from it "
                                 "(it lies on another component, or piece of a cloud, than the sources)")
        return state

    def _finish_in(self, c: int, x: np.ndarray, dx: float) -> bool:
        """Go straight to a source of cell ``c`` unless another source is nearer through the field."""
        y, dist = self.ends.closest(c, x)
        if y is None or dist > dx + 1e-9 * self.geo.mesh.bbox_diagonal + 1e-6 * dx:
            return False
        self.nodes.append(("p", c, y))
        return True

    def from_vertex(self, v: int) -> tuple | None:
        """Step from vertex ``v``: into the steepest cell or along the steepest edge."""
        geo, d, V = self.geo, self.d, self.geo.V
        if self.ends.vertices[v]:
            return None
        cells = geo.cells_of((v,))
        if any(self._finish_in(int(c), V[v], d[v]) for c in cells):
            return None
        best, choice = 1e-14, cast(tuple | None, None)
        for c in cells:
            iv = int(np.flatnonzero(geo.C[c] == v)[0])
            corner = np.eye(geo.C.shape[1])[iv]
            down, rate = self.slope.at(int(c), corner)
            if not np.all(np.isfinite(down)) or rate <= best:
                continue
            db = geo.H[c] @ down  # change of the barycentric coordinates per unit step
            if all(db[j] >= -1e-12 * np.abs(db).max() for j in range(len(db)) if j != iv):
                best, choice = rate, ("c", int(c), corner)
        nb = self.slope.adjacency[v]
        for w, length in zip(nb.indices, nb.data, strict=True):
            if length > 0 and np.isfinite(d[w]) and (d[v] - d[w]) / length > best:
                best, choice = (d[v] - d[w]) / length, ("v", int(w))
        if choice is None:
            self._stuck_at(v, cells)
            return None
        if choice[0] == "v":
            self.nodes.append(choice)
        return choice

    def _stuck_at(self, v: int, cells: np.ndarray) -> None:
        """No way down from ``v``: a smoothed field can sit below the straight distance next to its source, then
        the path ends on the nearest source of the cells around; else the field has a false minimum."""
        near = [(*self.ends.closest(int(c), self.geo.V[v]), int(c)) for c in cells if int(c) in self.ends.items]
        if not near:
            raise SolverError(f"geodesic_path: the field has a local minimum at vertex {v} (d = {self.d[v]:.6g}), "
                              "which is no source", solver="geodesic_path", status="local_minimum")
        y, _, c = min(near, key=lambda e: e[1])
        self.nodes.append(("p", c, y))

    def from_cell(self, c: int, b: np.ndarray) -> tuple | None:
        """Step from barycentric ``b`` inside (or on the boundary of) cell ``c`` to where the descent leaves it."""
        geo, d = self.geo, self.d
        corners = geo.C[c]
        x = b @ geo.V[corners]
        if self._finish_in(c, x, float(b @ d[corners])):
            return None
        down, rate = self.slope.at(c, b)
        if not np.all(np.isfinite(down)) or rate <= 1e-14:  # flat or degenerate cell: to its lowest corner
            return self._to_vertex(int(corners[np.argmin(d[corners])]))
        db = geo.H[c] @ down
        out = db < -1e-12 * np.abs(db).max()
        ts = np.where(out, b / np.where(out, -db, 1.0), np.inf)
        step = float(ts.min())
        nb = np.clip(b + step * db, 0.0, None)
        nb[ts <= step * (1 + 1e-9)] = 0.0  # every coordinate that reaches 0 there: a facet, or an edge of one
        nb /= nb.sum()
        if np.count_nonzero(nb > 1e-10) <= 1:
            return self._to_vertex(int(corners[np.argmax(nb)]))
        y = nb @ geo.V[corners]
        zero = np.flatnonzero(nb <= 1e-10)
        if zero.size == 1:  # through the facet opposite that corner
            facet = tuple(int(u) for u in corners[geo.mesh.reference.facets[zero[0]]])
            if frozenset(facet) in self.ends.facets:  # a source face of the volume: the path ends on it
                self.nodes.append(("p", c, y))
                return None
            entered = self._cell_across(c, facet, nb)
            if entered is not None:
                self.nodes.append(("e", facet, c, entered[1], y))
                return entered
        else:
            facet = tuple(int(u) for u in corners[nb > 1e-10])
        # a valley along the facet (or an edge of it), or the mesh's boundary: slide to its lowest corner
        w = facet[int(np.argmin(d[list(facet)]))]
        if np.linalg.norm(y - geo.V[w]) > self.tol and step > 0:
            self.nodes.append(("e", facet, c, c, y))
        return self._to_vertex(w)

    def _cell_across(self, c: int, facet: tuple[int, ...], b: np.ndarray) -> tuple | None:
        """The state in the cell across ``facet`` of ``c`` into which the descent continues, or None."""
        geo = self.geo
        for h in (int(h) for h in geo.cells_of(facet) if h != c):
            bh = np.zeros(geo.C.shape[1])
            for j, u in enumerate(geo.C[c]):
                bh[geo.C[h] == u] = b[j]
            down, _ = self.slope.at(h, bh)
            if not geo.ok[h] or not np.all(np.isfinite(down)):
                continue
            dbh = geo.H[h] @ down
            opp = int(np.flatnonzero(~np.isin(geo.C[h], facet))[0])
            if dbh[opp] > 1e-12 * max(np.abs(dbh).max(), 1e-300):
                return ("c", h, bh)
        return None

    def _to_vertex(self, v: int) -> tuple:
        state = ("v", v)
        self.nodes.append(state)
        return state


def _as_target(mesh: SimplexMesh, target: Any) -> int | CellPoint:
    """A vertex index or a point of the mesh's kind (a position: the closest surface point, the point inside)."""
    kind = mesh.reference.point_type
    if isinstance(target, kind):
        point = cast(CellPoint, target)
        point.check(mesh, "target")
        return point
    if is_integer(target):
        if not 0 <= int(target) < mesh.n_vertices:
            raise SourceError(f"target vertex {int(target)} is out of range: the mesh has {mesh.n_vertices} "
                              "vertices")
        if not mesh.referenced[int(target)]:  # a cloud's outlier has a distance (carried), but no cell to descend
            raise ParameterError(f"target vertex {int(target)} is in no {mesh.reference.words.one} (a loose vertex, or "
                                 "a point cloud's outlier, line point or isolated point, left out of its triangles): "
                                 "no path runs from it")
        return int(target)
    wrong = f"target must be a vertex index, a {kind.__name__} or a finite (3,) position, got {target!r}"
    try:
        X = np.asarray(target, dtype=float)
    except (TypeError, ValueError):
        raise SourceError(wrong) from None
    if X.shape != (3,) or not np.all(np.isfinite(X)):
        raise SourceError(wrong)
    return cast(CellPoint, mesh.reference.locate(mesh, X))  # one position: one point


@overload
def geodesic_path(mesh: MeshLike, distance: FieldLike, target: Any, *, sources: Any = None,
                  return_surface_points: Literal[False] = False, straighten: bool = True,
                  max_steps: int | None = None, cost: Any = None, metric: Any = None) -> np.ndarray: ...
@overload
def geodesic_path(mesh: MeshLike, distance: FieldLike, target: Any, *, sources: Any = None,
                  return_surface_points: Literal[True], straighten: bool = True,
                  max_steps: int | None = None, cost: Any = None,
                  metric: Any = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]: ...
@overload
def geodesic_path(mesh: MeshLike, distance: FieldLike, target: Any, *, sources: Any = None,
                  return_surface_points: bool = False, straighten: bool = True,
                  max_steps: int | None = None, cost: Any = None,
                  metric: Any = None) -> np.ndarray | tuple[np.ndarray, np.ndarray, np.ndarray]: ...


def geodesic_path(mesh: MeshLike, distance: FieldLike, target: Any, *, sources: Any = None,
                  return_surface_points: bool = False, straighten: bool = True,
                  max_steps: int | None = None, cost: Any = None,
                  metric: Any = None) -> np.ndarray | tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Path from ``target`` down the distance field to the nearest source, on a surface or inside a volume.

    In a travel cost or metric on a surface (``cost``/``metric``, or those of the solve when ``distance`` is a
    :class:`~cvxgeodesic.api.GeodesicResult`) the descent follows the metric's gradient,
    ``−M_t⁻¹ ∇d`` in each face (the cost does not turn it), and the straightening finds the path
    of least length *in the medium* through the corridor (a small second-order cone program,
    Clarabel; the medium constant on each face, read at its centroid): it bends at a change of
    cost as Snell's law says (``docs/metrics.md``).

    Parameters
    ----------
    mesh : TriMesh, TetMesh, or tuple (V, F) / (V, T)
    distance : (n,) float array_like, GeodesicResult or Field
        The field. A :class:`~cvxgeodesic.api.GeodesicResult` also gives its sources; a field that is no plain
        array (an order-2 solve's, :attr:`~cvxgeodesic.api.GeodesicResult.field`) gives the gradient the raw
        descent follows inside a volume.
    target : int, SurfacePoint (VolumePoint in a TetMesh) or (3,) position
        A vertex index or a point; a position stands for its closest surface point (the point inside the volume).
    sources : optional
        The field's sources (anything :meth:`GeodesicSolver.solve` takes), needed to end a path on a
        point, curve or face source when ``distance`` is a plain array (or a field) that did not come from
        this library (an array returned by :func:`geodesic_distance` or ``GeodesicResult.distance``
        remembers its sources, and so does an order-1 ``GeodesicResult.field``). Without them, the sources
        are the vertices where ``distance`` takes its minimum (0 for vertex sources).
    return_surface_points : bool
        Also return the cell (face, or tetrahedron) and barycentric coordinates of every path point.
    straighten : bool
        On a surface, replace the descent by the shortest path through its corridor of faces (module
        docstring); inside a volume the path is always the descent.
    max_steps : int, optional
        Limit of descent steps (default ``(dim + 1) · n_cells + 10``: ``3 · n_faces + 10``, ``4 · n_tets + 10``).
    cost, metric : optional
        The travel cost and metric the field was computed in on a surface (see
        :class:`~cvxgeodesic.api.GeodesicSolver`); by default those of a
        :class:`~cvxgeodesic.api.GeodesicResult`, else none.

    Returns
    -------
    path : (k, 3) float ndarray
        From the target (first row) to the source (last row).
    faces : (k,) int64 ndarray
        Only with ``return_surface_points``: a face (tetrahedron) containing each point.
    bary : (k, 3) or (k, 4) float ndarray
        Only with ``return_surface_points``: the point's barycentric coordinates in that cell.

    Raises
    ------
    SourceError
        Invalid target (vertex or cell out of range, a position outside the volume) or sources.
    ParameterError
        ``distance`` of the wrong length, with NaN, or infinite at the target (a target in another component
        than the sources); a cost or metric with a tetrahedral mesh.
    SolverError
        The descent stopped at a local minimum that is no source, or ran past ``max_steps``.

    Examples
    --------
    >>> import cvxgeodesic as cg
    >>> mesh = cg.grid_plane(8)
    >>> d = cg.geodesic_distance(mesh, 0, method="exact")
    >>> path = cg.geodesic_path(mesh, d, 80)
    >>> path[0].tolist(), path[-1].tolist()
    ([1.0, 1.0, 0.0], [0.0, 0.0, 0.0])
    """
    mesh = as_mesh(mesh)
    d, result, field = _field(mesh, distance)
    p1 = LinearField(mesh, d)  # the walk's cells, and its slope wherever the field's own gradient is not asked
    geo = Cells(mesh, p1.hat_gradients)
    ends = _Ends(mesh, geo, d, distance, result, sources)
    medium = _path_medium(mesh, field, cost, metric)
    if _exact_applies(mesh, result, ends.ss, target):
        return _exact_path(cast(TriMesh, mesh), ends.ss, target, return_surface_points)
    max_steps = check_count(mesh.reference.n_corners * mesh.n_cells + 10 if max_steps is None else max_steps,
                            "max_steps")
    straighten_with = STRAIGHTENERS.get(mesh.reference)
    inner = None if straighten_with is not None or isinstance(field, LinearField) else field
    walk = _Descent(geo, d, ends, _Slope(geo, p1, medium, inner))
    state: tuple | None = walk.start(target)
    for _ in range(max_steps):
        assert state is not None
        state = walk.from_vertex(state[1]) if state[0] == "v" else walk.from_cell(state[1], state[2])
        if state is None:
            break
    else:
        raise SolverError(f"geodesic_path: no source reached within max_steps={max_steps} steps",
                          solver="geodesic_path", status="max_steps")
    return _finish_path(geo, walk.nodes, straighten_with if straighten else None, return_surface_points, medium)


def _path_medium(mesh: SimplexMesh, field: Field, cost: Any, metric: Any) -> Any:
    """The surface's travel cost or metric (given, else the field's); a volume's paths are Euclidean (the capability
    table refuses a medium there: a volume's fields have none)."""
    check_path(domain=mesh.domain, medium="none" if cost is None and metric is None else "cost")
    medium = make_medium(mesh, cost, metric)
    if medium is None:
        medium = field.medium
    return medium


def _finish_path(geo: Cells, nodes: list[tuple], straighten: Callable[..., list[tuple]] | None, return_points: bool,
                 medium: Any = None) -> Any:
    """Straighten the walk's nodes (the shortest path through the corridor of faces of a surface), drop duplicates
    and return positions (and cells, barycentric coordinates)."""
    mesh = geo.mesh
    tol = 1e-12 * mesh.bbox_diagonal
    if straighten is not None:
        nodes = straighten(geo, nodes, None if medium is None else medium.on(mesh))
    P = np.array([node_position(geo, nd) for nd in nodes])
    # consecutive duplicates (a valley that starts at a crossing, a point that was already on its source)
    keep = np.r_[True, np.linalg.norm(np.diff(P, axis=0), axis=1) > tol]
    if not keep[-1]:  # the end is the source itself: the point it repeats goes instead (a target on its source:
        keep[np.flatnonzero(keep)[-1]] = False  # the path is that one point)
        keep[-1] = True
    nodes = [nd for nd, kp in zip(nodes, keep, strict=True) if kp]
    P = P[keep]
    if not return_points:
        return P
    located = [_locate(geo, nd) for nd in nodes]
    return (P, np.array([c for c, _ in located], dtype=np.int64),
            np.array([b for _, b in located]).reshape(-1, mesh.reference.n_corners))


def _locate(geo: Cells, node) -> tuple[int, np.ndarray]:
    """A cell containing the node and the node's barycentric coordinates in it."""
    if node[0] == "v":
        c = int(geo.cells_of((node[1],))[0])
        return c, (geo.C[c] == node[1]).astype(float)
    c = node[3] if node[0] == "e" else node[1]
    b = geo.bary(c, node[-1])
    if node[0] == "e":  # exactly on the facet
        b[~np.isin(geo.C[c], node[1])] = 0.0
        b /= b.sum()
    return int(c), b


# -- surfaces: the exact path of method="exact" -------------------------------------------------------------------
def _exact_applies(mesh: SimplexMesh, result: GeodesicResult | None, ss: Any, target: Any) -> bool:
    """pygeodesic's path applies: an exact field (a surface's: the capability table refuses ``"exact"`` elsewhere),
    vertex or point sources, a vertex or point target, one manifold component."""
    if result is None or result.info.method != "exact" or ss is None:
        return False
    mesh = cast(TriMesh, mesh)
    if isinstance(target, SurfacePoint):
        on_mesh = target.face < mesh.n_faces
    else:
        on_mesh = is_integer(target) and 0 <= int(target) < mesh.n_vertices
    return bool(on_mesh and not ss.segment_faces.size and mesh.is_edge_manifold and mesh.referenced.all()
                and np.unique(mesh.component_labels).size == 1)


def _exact_path(mesh: TriMesh, ss: SourceSet, target, return_surface_points: bool):
    """pygeodesic's exact (MMP) path from ``target`` to the nearest source (points inserted as vertices)."""
    from pygeodesic import geodesic

    from ..baselines.points import _unique_points, insert_points

    X = _unique_points(mesh, ss)
    start = target.position(mesh) if isinstance(target, SurfacePoint) else mesh.V[int(target)]
    extra = np.vstack([X, start[None]]) if isinstance(target, SurfacePoint) else X
    V2, F2, idx = (insert_points(mesh.V, mesh.F, extra) if len(extra) else (mesh.V, mesh.F, np.zeros(0, np.int64)))
    sources = np.unique(np.r_[ss.vertices, idx[: len(X)]]).astype(np.int64)
    t2 = int(idx[-1]) if isinstance(target, SurfacePoint) else int(target)
    best: tuple | None = None
    if t2 in set(sources.tolist()):
        best = (0.0, np.array([V2[t2]]))
    with contextlib.redirect_stdout(io.StringIO()):
        alg = geodesic.PyGeodesicAlgorithmExact(np.ascontiguousarray(V2), np.ascontiguousarray(F2, dtype=np.int32))
        for s in sources if best is None else []:
            dist, path = alg.geodesicDistance(int(s), t2)
            if path is not None and dist is not None and 0 <= dist < 1e99 and (best is None or dist < best[0]):
                best = (dist, np.asarray(path, dtype=float).reshape(-1, 3), int(s))
    if best is None:
        raise ParameterError("the distance is infinite at the target: no source is reachable from it")
    P = best[1]
    P[0] = start
    if len(best) > 2:
        P[-1] = V2[best[2]]
    if not return_surface_points:
        return P
    faces, bary, _ = closest_points(mesh, P)
    return P, faces, bary
