"""Reading a distance field on the surface: values at surface points, geodesic paths.

:func:`geodesic_path` follows the steepest descent of the piecewise-linear field: inside a face
along ``−∇d|_t`` to the exact crossing with the face's boundary; across an edge into the next face
when that face's descent direction enters it, else along the edge (a valley) to its lower end; at a
vertex into the incident face or along the incident edge of steepest descent. It stops at a
source vertex, or goes straight to the source once it reaches a face that contains a point or curve
source (a straight segment inside a flat face is the geodesic there). For a field of
``method="exact"`` (a :class:`~cvxgeodesic.api.GeodesicResult`) from vertex or point sources to a
vertex or a point, the path is pygeodesic's exact (MMP) path instead (on the mesh with the points
inserted as vertices).

With ``straighten=True`` (default) the descent only chooses the corridor: the faces it crossed,
plus, at each vertex it passed through, the fan of faces around that vertex on the side of the
smaller angle. The corridor is unfolded into the plane edge by edge and the shortest path through
it is found exactly (funnel algorithm). Where that path still wraps around a corridor vertex
and the angle on the vertex's other side is smaller, the corridor goes around the other side and
the path is recomputed (at most 64 times). The result is a locally shortest path: straight on a
plane (measured 2e-16 from the chord on a jittered grid, against 6e-3 .. 7e-2 for the raw
descent), and within 0.1 % of the exact polyhedral distance on the unit icosphere (subdivision 4).
``straighten=False`` returns the raw descent.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence
from typing import Any, Literal, TypeAlias, overload

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike

from .errors import ParameterError, SolverError, SourceError
from .mesh.convert import as_mesh
from .mesh.io import as_trimesh
from .mesh.tetmesh import TetMesh
from .mesh.trimesh import TriMesh
from .operators.metric import make_medium
from .results import GeodesicResult
from .sources import BARY_SNAP, SourceSet, SurfacePoint, _barycentric, _incident_faces, resolve_sources
from .validation import as_vertex_field, check_count

#: A distance field as the functions here take it: the vertex values or the result they came from.
Field: TypeAlias = ArrayLike | GeodesicResult


def _field(mesh: TriMesh, distance: Any) -> tuple[np.ndarray, Any]:
    """(n,) float field and the result object it came from (or None)."""
    result = None
    if hasattr(distance, "distance") and hasattr(distance, "info"):
        result, distance = distance, distance.distance
    return as_vertex_field(distance, "distance", mesh.n_vertices, nan_ok=False), result


def _as_points(mesh: TriMesh, points) -> tuple[list[SurfacePoint], bool]:
    from .sources import surface_point

    if isinstance(points, SurfacePoint):
        return [points], True
    if isinstance(points, list | tuple) and all(isinstance(p, SurfacePoint) for p in points):
        pts = list(points)
    else:
        try:
            X = np.asarray(points, dtype=float)
        except (TypeError, ValueError):
            raise SourceError("points must be SurfacePoints or (k, 3) positions") from None
        found = surface_point(mesh, X)
        if isinstance(found, SurfacePoint):
            return [found], True
        pts = found
    for k, p in enumerate(pts):
        if p.face >= mesh.n_faces:
            raise SourceError(f"point {k} {p!r}: face index {p.face} is out of range: the mesh has {mesh.n_faces} "
                              "faces")
    return pts, False


@overload
def distance_at(mesh: Any, distance: Field, points: SurfacePoint) -> float: ...
@overload
def distance_at(mesh: Any, distance: Field, points: Sequence[SurfacePoint]) -> np.ndarray: ...
@overload
def distance_at(mesh: Any, distance: Field, points: ArrayLike) -> float | np.ndarray: ...


def distance_at(mesh: Any, distance: Field, points: Any) -> float | np.ndarray:
    """Values of a distance field at surface points.

    A vertex field is interpolated linearly in each face; the result of an ``order=2`` solve
    (a :class:`~cvxgeodesic.api.GeodesicResult`) is evaluated as its piecewise quadratic squared
    distance, ``√φ``.

    Parameters
    ----------
    mesh : TriMesh or tuple (V, F)
    distance : (n,) float array_like or GeodesicResult
    points : SurfacePoint, sequence of SurfacePoint, or (3,) / (k, 3) positions (closest points are used)

    Returns
    -------
    float for one point, else (k,) float ndarray
        ``Σ_i b_i d[F[face, i]]``.

    Raises
    ------
    SourceError
        A face index out of range, or points that are neither SurfacePoints nor positions.
    ParameterError
        ``distance`` of the wrong length or with NaN.

    Examples
    --------
    >>> import cvxgeodesic as cg
    >>> mesh = cg.grid_plane(4)
    >>> d = cg.geodesic_distance(mesh, 0, method="dijkstra")
    >>> round(cg.distance_at(mesh, d, cg.SurfacePoint(0, [1.0, 0.0, 0.0])), 6)
    0.0

    On a tetrahedral mesh, ``points`` are VolumePoints or positions inside it
    (:func:`~cvxgeodesic.paths_tet.tet_distance_at`).
    """
    if isinstance(volume := as_mesh(mesh), TetMesh):
        from .paths_tet import tet_distance_at

        return tet_distance_at(volume, distance, points)
    mesh = as_trimesh(mesh)
    p2_field = getattr(getattr(distance, "info", None), "extra", {}).get("p2_field")
    if p2_field is not None:  # an order=2 result: its piecewise quadratic field, not the vertex values
        pts, single = _as_points(mesh, points)
        faces = np.array([p.face for p in pts], dtype=np.int64)
        vals = p2_field.distance_at(faces, np.array([p.bary for p in pts]).reshape(-1, 3))
        return float(vals[0]) if single else vals
    d, _ = _field(mesh, distance)
    pts, single = _as_points(mesh, points)
    faces = np.array([p.face for p in pts], dtype=np.int64)
    bary = np.array([p.bary for p in pts]).reshape(-1, 3)
    with np.errstate(invalid="ignore"):
        vals = np.einsum("kj,kj->k", bary, d[mesh.F[faces]])
    # inf * 0 is NaN: a point whose face touches an unreachable vertex with weight 0 takes the others' value
    bad = np.isnan(vals)
    if bad.any():
        Dv = d[mesh.F[faces[bad]]]
        vals[bad] = np.where(np.any((bary[bad] > 0) & np.isinf(Dv), axis=1), np.inf,
                             np.nansum(np.where(bary[bad] > 0, bary[bad] * Dv, 0.0), axis=1))
    return float(vals[0]) if single else vals


class _Geometry:
    """Per-mesh data of the descent: 3D hat-function gradients and edge-to-face maps."""

    def __init__(self, mesh: TriMesh):
        from .operators.gradient import gradient_blocks, triangle_frames

        self.mesh = mesh
        V, F = mesh.V, mesh.F
        with np.errstate(invalid="ignore", divide="ignore"):
            ex, ey = triangle_frames(mesh)
        self.ex, self.ey = ex, ey
        B = gradient_blocks(mesh)  # (m, 2, 3)
        with np.errstate(invalid="ignore"):
            self.H = B[:, 0, :, None] * ex[:, None, :] + B[:, 1, :, None] * ey[:, None, :]  # (m, 3 corners, 3)
        self.ok = np.all(np.isfinite(self.H.reshape(len(F), -1)), axis=1) & ~np.isin(
            np.arange(len(F)), mesh.degenerate_faces())
        self.inc = _incident_faces(mesh)
        self.V, self.F = V, F

    def faces_of_edge(self, a: int, c: int) -> np.ndarray:
        return np.intersect1d(self.inc[a].indices, self.inc[c].indices)

    def faces_of_vertex(self, v: int) -> np.ndarray:
        return self.inc[v].indices


def _source_targets(mesh: TriMesh, ss: SourceSet | None):
    """Per source face, the source points and pieces in it; and the set of source vertices."""
    per_face: dict[int, list[tuple[np.ndarray, np.ndarray]]] = {}
    if ss is None:
        return per_face
    X = ss.point_positions(mesh)
    for f, x in zip(ss.point_faces, X, strict=True):
        per_face.setdefault(int(f), []).append((x, x))
    T = mesh.V[mesh.F[ss.segment_faces]]
    for f, ba, t in zip(ss.segment_faces, ss.segment_bary, T, strict=True):
        per_face.setdefault(int(f), []).append((ba[0] @ t, ba[1] @ t))
    return per_face


def _closest_on(x: np.ndarray, items) -> tuple[np.ndarray | None, float]:
    best: np.ndarray | None = None
    bd = np.inf
    for a, b in items:
        ab = b - a
        den = float(ab @ ab)
        t = 0.0 if den == 0 else float(np.clip((x - a) @ ab / den, 0.0, 1.0))
        y = a + t * ab
        dist = float(np.linalg.norm(x - y))
        if dist < bd:
            best, bd = y, dist
    return best, bd


@overload
def geodesic_path(mesh: Any, distance: Field, target: Any, *, sources: Any = None,
                  return_surface_points: Literal[False] = False, straighten: bool = True,
                  max_steps: int | None = None, cost: Any = None, metric: Any = None) -> np.ndarray: ...
@overload
def geodesic_path(mesh: Any, distance: Field, target: Any, *, sources: Any = None,
                  return_surface_points: Literal[True], straighten: bool = True,
                  max_steps: int | None = None, cost: Any = None,
                  metric: Any = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]: ...
@overload
def geodesic_path(mesh: Any, distance: Field, target: Any, *, sources: Any = None,
                  return_surface_points: bool = False, straighten: bool = True,
                  max_steps: int | None = None, cost: Any = None,
                  metric: Any = None) -> np.ndarray | tuple[np.ndarray, np.ndarray, np.ndarray]: ...


def geodesic_path(mesh: Any, distance: Field, target: Any, *, sources: Any = None,
                  return_surface_points: bool = False, straighten: bool = True,
                  max_steps: int | None = None, cost: Any = None,
                  metric: Any = None) -> np.ndarray | tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Path from ``target`` down the distance field to the nearest source.

    In a travel cost or metric (``cost``/``metric``, or those of the solve when ``distance`` is a
    :class:`~cvxgeodesic.api.GeodesicResult`) the descent follows the metric's gradient,
    ``−M_t⁻¹ ∇d`` in each face (the cost does not turn it), and the straightening finds the path
    of least length *in the medium* through the corridor (a small second-order cone program,
    Clarabel; the medium constant on each face, read at its centroid): it bends at a change of
    cost as Snell's law says (``docs/metrics.md``).

    Parameters
    ----------
    mesh : TriMesh or tuple (V, F)
    distance : (n,) float array_like or GeodesicResult
        The field. A :class:`~cvxgeodesic.api.GeodesicResult` also gives its sources.
    target : int or SurfacePoint
        A vertex index or a surface point.
    sources : optional
        The field's sources (anything :meth:`GeodesicSolver.solve` takes), needed to end a path on a
        point or curve source when ``distance`` is a plain array that did not come from this
        library (an array returned by :func:`geodesic_distance` or ``GeodesicResult.distance``
        remembers its sources). Without them, the sources are the vertices where ``distance``
        takes its minimum (0 for vertex sources).
    return_surface_points : bool
        Also return the face and barycentric coordinates of every path point.
    straighten : bool
        Replace the descent by the shortest path through its corridor of faces (module docstring).
    max_steps : int, optional
        Limit of descent steps (default ``3 · n_faces + 10``).
    cost, metric : optional
        The travel cost and metric the field was computed in (see :class:`~cvxgeodesic.api.GeodesicSolver`);
        by default those of a :class:`~cvxgeodesic.api.GeodesicResult`, else none.

    Returns
    -------
    path : (k, 3) float ndarray
        From the target (first row) to the source (last row).
    faces : (k,) int64 ndarray
        Only with ``return_surface_points``: a face containing each point.
    bary : (k, 3) float ndarray
        Only with ``return_surface_points``: the point's barycentric coordinates in that face.

    Raises
    ------
    SourceError
        Invalid target (vertex or face out of range) or sources.
    ParameterError
        ``distance`` of the wrong length, with NaN, or infinite at the target.
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

    On a tetrahedral mesh the path goes down the field inside the solid, tet by tet (a vertex, VolumePoint or
    position as target; :func:`~cvxgeodesic.paths_tet.tet_geodesic_path`).
    """
    if isinstance(volume := as_mesh(mesh), TetMesh):
        from .paths_tet import tet_geodesic_path

        return tet_geodesic_path(volume, distance, target, sources=sources, max_steps=max_steps)
    mesh = as_trimesh(mesh)
    d, result = _field(mesh, distance)
    ss, src_v = _path_sources(mesh, d, distance, result, sources)
    medium = make_medium(mesh, cost, metric)
    if medium is None and result is not None:
        medium = result.info.extra.get("medium")
    if (result is not None and getattr(result.info, "method", None) == "exact" and ss is not None
            and not ss.segment_faces.size and _exact_target(mesh, target) and mesh.is_edge_manifold
            and mesh.referenced.all() and np.unique(mesh.component_labels).size == 1):
        return _exact_path(mesh, ss, target, return_surface_points)
    geo = _Geometry(mesh)
    if max_steps is None:
        max_steps = 3 * mesh.n_faces + 10
    check_count(max_steps, "max_steps")
    walk = _Descent(mesh, geo, d, src_v, _source_targets(mesh, ss), medium)
    state = walk.start(target)
    for _ in range(max_steps):
        step = walk.from_vertex(state[1]) if state[0] == "v" else walk.from_face(state[1], state[2])
        if step is None:
            break
        state = step
    else:
        raise SolverError(f"geodesic_path: no source reached within max_steps={max_steps} steps",
                          solver="geodesic_path", status="max_steps")
    return _finish_path(mesh, geo, walk.nodes, straighten, return_surface_points, medium)


def _path_sources(mesh: TriMesh, d: np.ndarray, distance: Any, result: Any,
                  sources: Any) -> tuple[SourceSet | None, np.ndarray]:
    """The field's source set (None when unknown) and the (n,) bool mask of its source vertices."""
    ss = None
    if sources is not None:
        ss = resolve_sources(mesh, sources)
    elif result is not None:
        ss = result.source_set if result.source_set is not None else resolve_sources(mesh, result.sources)
    else:
        from .results import remembered_sources

        ss = remembered_sources(distance)  # an array returned by geodesic_distance from surface sources
    if ss is not None:
        src_v = np.zeros(mesh.n_vertices, dtype=bool)
        src_v[ss.vertices] = True
    else:
        finite = d[np.isfinite(d)]
        zero = (finite.min() if finite.size else 0.0) + 1e-12 * mesh.bbox_diagonal
        src_v = d <= zero
    return ss, src_v


class _Descent:
    """The steepest-descent walk of :func:`geodesic_path`: a state ``("v", vertex)`` or ``("f", face, bary)``.

    ``nodes`` collects the path: ``("v", vertex) | ("e", a, c, face_in, face_out, position) | ("p", face,
    position)``. Each step appends what it crossed and returns the next state, or None at a source.
    """

    def __init__(self, mesh: TriMesh, geo: _Geometry, d: np.ndarray, src_v: np.ndarray, per_face: dict,
                 medium: Any = None) -> None:
        self.mesh, self.geo, self.d, self.src_v, self.per_face = mesh, geo, d, src_v, per_face
        self.tol = 1e-12 * mesh.bbox_diagonal
        with np.errstate(invalid="ignore"):
            grad = np.einsum("fkj,fk->fj", geo.H, d[geo.F])  # (m, 3) gradient of the field in each face
        grad[~geo.ok] = np.nan
        self.grad = grad
        # the direction of steepest descent and the rate of descent per unit length, both in the medium
        self.adjacency = mesh.vertex_adjacency
        if medium is None:
            self.down, self.rate = -grad, np.linalg.norm(grad, axis=1)
        else:
            medium = medium.on(mesh)
            self.adjacency = medium.adjacency()  # normalized, as the rates below
            P = medium.plane(np.arange(mesh.n_faces), np.full(3, 1 / 3))
            P[~geo.ok] = np.eye(2)
            g2 = np.stack([np.einsum("fj,fj->f", grad, geo.ex), np.einsum("fj,fj->f", grad, geo.ey)], 1)
            with np.errstate(invalid="ignore"):
                step = -np.linalg.solve(P, g2[:, :, None])[:, :, 0]  # −M⁻¹∇d in the face's frame
                self.down = step[:, :1] * geo.ex + step[:, 1:] * geo.ey
                self.rate = np.sqrt(np.maximum(-np.einsum("fi,fi->f", g2, step), 0.0))
        self.nodes: list[tuple] = []

    def start(self, target: Any) -> tuple:
        """The first state, from a vertex index or a SurfacePoint (validated)."""
        mesh, F, V = self.mesh, self.geo.F, self.geo.V
        if isinstance(target, SurfacePoint):
            if target.face >= mesh.n_faces:
                raise SourceError(f"target {target!r}: face index {target.face} is out of range: the mesh has "
                                  f"{mesh.n_faces} faces")
            b = target.bary
            k = int(np.argmax(b))
            if b[k] >= 1 - BARY_SNAP:
                state: tuple = ("v", int(F[target.face, k]))
                self.nodes.append(state)
            else:
                self.nodes.append(("p", target.face, b @ V[F[target.face]]))
                state = ("f", target.face, np.where(b <= BARY_SNAP, 0.0, b))
        else:
            if isinstance(target, bool | np.bool_) or not isinstance(target, numbers.Integral):
                raise SourceError(f"target must be a vertex index or a SurfacePoint, got {target!r}")
            if not 0 <= int(target) < mesh.n_vertices:
                raise SourceError(f"target vertex {int(target)} is out of range: the mesh has {mesh.n_vertices} "
                                  "vertices")
            state = ("v", int(target))
            self.nodes.append(state)
        t_val = distance_at(mesh, self.d, SurfacePoint(*_locate(mesh, self.geo, self.nodes[0])))
        if not np.isfinite(t_val):
            raise ParameterError("the distance is infinite at the target: no source is reachable from it")
        return state

    def _finish_in_face(self, f: int, x: np.ndarray, dx: float) -> bool:
        items = self.per_face.get(f)
        if not items:
            return False
        y, dist = _closest_on(x, items)
        if dist > dx + 1e-9 * self.mesh.bbox_diagonal + 1e-6 * dx:
            return False  # another source is nearer: keep descending
        self.nodes.append(("p", f, y))
        return True

    def from_vertex(self, v: int) -> tuple | None:
        """Step from vertex ``v``: into the steepest face or along the steepest edge."""
        geo, d, F, V = self.geo, self.d, self.geo.F, self.geo.V
        if self.src_v[v]:
            return None
        fs = geo.faces_of_vertex(v)
        if any(self._finish_in_face(int(f), V[v], d[v]) for f in fs):
            return None
        best = 1e-14
        choice: tuple | None = None
        for f in fs:
            g = self.down[f]
            if not np.all(np.isfinite(g)):
                continue
            rate = float(self.rate[f])
            if rate <= best:
                continue
            db = geo.H[f] @ g
            iv = int(np.flatnonzero(F[f] == v)[0])
            others = [j for j in range(3) if j != iv]
            if all(db[j] >= -1e-12 * np.abs(db).max() for j in others):
                best, choice = rate, ("f", int(f), np.eye(3)[iv])
        nb = sp.csr_matrix(self.adjacency)[v]
        for w, length in zip(nb.indices, nb.data, strict=True):
            if length <= 0 or not np.isfinite(d[w]):
                continue
            rate = (d[v] - d[w]) / length
            if rate > best:
                best, choice = rate, ("v", int(w))
        if choice is None and any(int(f) in self.per_face for f in fs):
            # a smoothed field can sit below the straight distance next to its source: end there
            ends = [(*_closest_on(V[v], self.per_face[int(f)]), int(f)) for f in fs if int(f) in self.per_face]
            y, _, f_end = min(ends, key=lambda e: e[1])
            self.nodes.append(("p", f_end, y))
            return None
        if choice is None:
            raise SolverError(f"geodesic_path: the field has a local minimum at vertex {v} (d = {d[v]:.6g}), "
                              "which is no source", solver="geodesic_path", status="local_minimum")
        if choice[0] == "v":
            self.nodes.append(choice)
        return choice

    def from_face(self, f: int, b: np.ndarray) -> tuple | None:
        """Step from barycentric ``b`` inside (or on the boundary of) face ``f`` to where the descent leaves it."""
        geo, d, F, V = self.geo, self.d, self.geo.F, self.geo.V
        x = b @ V[F[f]]
        if self._finish_in_face(f, x, float(b @ d[F[f]])):
            return None
        g = self.down[f]
        if not np.all(np.isfinite(g)) or self.rate[f] <= 1e-14:
            j = int(np.argmin(d[F[f]]))  # flat or degenerate face: to its lowest corner
            return self._to_vertex(int(F[f, j]))
        db = geo.H[f] @ g
        scale = np.abs(db).max()
        out = db < -1e-12 * scale
        ts = np.where(out, b / np.where(out, -db, 1.0), np.inf)
        t = float(ts.min())
        nb_ = np.clip(b + t * db, 0.0, None)
        nb_[int(np.argmin(ts))] = 0.0
        nb_ /= nb_.sum()
        k = int(np.argmax(nb_))
        if nb_[k] >= 1 - 1e-10:
            return self._to_vertex(int(F[f, k]))
        i = int(np.argmin(nb_))  # the exit edge is opposite corner i
        a, c = int(F[f, (i + 1) % 3]), int(F[f, (i + 2) % 3])
        y = nb_ @ V[F[f]]
        entered = self._face_across(f, a, c)
        if entered is None:  # a valley along the edge (or the boundary): slide to its lower end
            w = a if d[a] <= d[c] else c
            if np.linalg.norm(y - V[w]) > self.tol and t > 0:
                self.nodes.append(("e", a, c, f, f, y))
            return self._to_vertex(w)
        bh = np.zeros(3)
        bh[F[entered] == a] = nb_[(i + 1) % 3]
        bh[F[entered] == c] = nb_[(i + 2) % 3]
        self.nodes.append(("e", a, c, f, entered, y))
        return ("f", entered, bh)

    def _to_vertex(self, v: int) -> tuple:
        state = ("v", v)
        self.nodes.append(state)
        return state

    def _face_across(self, f: int, a: int, c: int) -> int | None:
        """The face across edge ``(a, c)`` of ``f`` into which the descent continues, or None."""
        geo, F = self.geo, self.geo.F
        for h in (int(h) for h in geo.faces_of_edge(a, c) if h != f):
            gh = self.down[h]
            if not np.all(np.isfinite(gh)):
                continue
            third = int(np.flatnonzero((F[h] != a) & (F[h] != c))[0])
            dbh = geo.H[h] @ gh
            if dbh[third] > 1e-12 * max(np.abs(dbh).max(), 1e-300):
                return h
        return None


def _finish_path(mesh: TriMesh, geo: _Geometry, nodes: list[tuple], straighten: bool,
                 return_surface_points: bool, medium: Any = None) -> Any:
    """Straighten the walk's nodes, drop duplicates and return positions (and faces, barycentric coordinates)."""
    tol = 1e-12 * mesh.bbox_diagonal
    if straighten:
        nodes = _open_vertices(mesh, geo, nodes)
        for _ in range(64):
            _straighten(mesh, nodes, None if medium is None else medium.on(mesh))
            nodes, switched = _switch_sides(mesh, geo, nodes)
            if not switched:
                break
    P = np.array([_position(mesh, nd) for nd in nodes])
    # consecutive duplicates (a valley that starts at a crossing, a point that was already on its source)
    keep = np.r_[True, np.linalg.norm(np.diff(P, axis=0), axis=1) > tol]
    keep[-1] = True  # the end is the source itself: a crossing that sits on it goes instead
    if len(P) > 1 and np.linalg.norm(P[-1] - P[np.flatnonzero(keep[:-1])[-1]]) <= tol and keep[:-1].sum() > 1:
        keep[np.flatnonzero(keep[:-1])[-1]] = False
    nodes = [nd for nd, kp in zip(nodes, keep, strict=True) if kp]
    P = P[keep]
    if not return_surface_points:
        return P
    fb = [_locate(mesh, geo, nd) for nd in nodes]
    return P, np.array([f for f, _ in fb], dtype=np.int64), np.array([b for _, b in fb]).reshape(-1, 3)


def _exact_target(mesh: TriMesh, target) -> bool:
    if isinstance(target, SurfacePoint):
        return target.face < mesh.n_faces
    return (isinstance(target, numbers.Integral) and not isinstance(target, bool | np.bool_)
            and 0 <= int(target) < mesh.n_vertices)


def _exact_path(mesh: TriMesh, ss: SourceSet, target, return_surface_points: bool):
    """pygeodesic's exact (MMP) path from ``target`` to the nearest source (points inserted as vertices)."""
    import contextlib
    import io

    from pygeodesic import geodesic

    from .baselines.points import _unique_points, insert_points
    from .sources import closest_points

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


def _position(mesh: TriMesh, node) -> np.ndarray:
    if node[0] == "v":
        return mesh.V[node[1]]
    return node[-1]


def _locate(mesh: TriMesh, geo: _Geometry, node) -> tuple[int, np.ndarray]:
    """A face containing the node and the node's barycentric coordinates in it."""
    F, V = mesh.F, mesh.V
    if node[0] == "v":
        f = int(geo.faces_of_vertex(node[1])[0])
        return f, (F[f] == node[1]).astype(float)
    f = node[4] if node[0] == "e" else node[1]
    b = _barycentric(V[F[f]][None], node[-1][None])[0]
    if node[0] == "e":  # exactly on the edge (a, c)
        a, c = node[1], node[2]
        b[(F[f] != a) & (F[f] != c)] = 0.0
        b /= b.sum()
    return int(f), b


def _segment_face(geo: _Geometry, a, b) -> int | None:
    """A face that contains the path segment between nodes ``a`` and ``b``."""
    if b[0] == "e":
        return b[3]
    if a[0] == "e":
        return a[4]
    if a[0] == "p":
        return a[1]
    if b[0] == "p":
        return b[1]
    shared = geo.faces_of_edge(a[1], b[1])  # an edge walk
    return int(shared[0]) if len(shared) else None


def _fan(geo: _Geometry, v: int, start: int, goal: int) -> list[tuple[list[int], list[int]]]:
    """The two walks around vertex ``v`` from face ``start`` to face ``goal``: (edge ends, faces) each."""
    F = geo.F
    walks = []
    for first in range(2):
        f = start
        others = [int(u) for u in F[f] if u != v]
        u = others[first]
        faces, ends = [f], []
        ok = False
        for _ in range(64):
            across = [int(h) for h in geo.faces_of_edge(v, u) if h != f]
            if len(across) != 1:
                break  # the boundary, or a non-manifold edge
            ends.append(u)
            f = across[0]
            faces.append(f)
            if f == goal:
                ok = True
                break
            u = next(int(w) for w in F[f] if w != v and w != u)
        if ok:
            walks.append((ends, faces))
    return walks


def _open_vertices(mesh: TriMesh, geo: _Geometry, nodes: list) -> list:
    """Replace each vertex the descent passed through by crossings of the edges around it.

    The crossings start at the vertex; :func:`_straighten` may then pull them off it, on the side of the
    smaller angle (where the straight line between the path's neighbours runs on a flat surface).
    """
    V = mesh.V
    # the start of a valley (a point on an edge from which the descent slid along it) is in the face of the
    # crossing before it together with the vertex after it: the straight segment between those replaces it
    nodes = [nd for i, nd in enumerate(nodes) if i in (0, len(nodes) - 1) or not (nd[0] == "e" and nd[3] == nd[4])]
    out = [nodes[0]]
    for i in range(1, len(nodes) - 1):
        nd = nodes[i]
        if nd[0] != "v":
            out.append(nd)
            continue
        v = nd[1]
        f_in = _segment_face(geo, nodes[i - 1], nd)
        f_out = _segment_face(geo, nd, nodes[i + 1])
        if f_in is None or f_out is None or f_in == f_out:
            out.append(nd)
            continue
        walks = _fan(geo, v, f_in, f_out)
        if not walks:
            out.append(nd)
            continue

        q0, q1 = _position(mesh, nodes[i - 1]), _position(mesh, nodes[i + 1])
        ends, faces = walks[int(np.argmin([_walk_angle(geo, v, w, q0, q1) for w in walks]))]
        for j, u in enumerate(ends):
            out.append(("e", v, u, faces[j], faces[j + 1], 0.7 * V[v] + 0.3 * V[u]))
    out.append(nodes[-1])
    return out


def _corner(V, u, p, q) -> float:
    a, b = V[p] - V[u] if np.ndim(p) == 0 else p - V[u], V[q] - V[u] if np.ndim(q) == 0 else q - V[u]
    na, nb = np.linalg.norm(a), np.linalg.norm(b)
    if na == 0 or nb == 0:
        return 0.0
    return float(np.arccos(np.clip(a @ b / (na * nb), -1.0, 1.0)))


def _walk_angle(geo: _Geometry, u: int, walk, q0: np.ndarray, q1: np.ndarray) -> float:
    """Angle at ``u`` swept by a walk around it from the direction of ``q0`` to that of ``q1``."""
    V, F = geo.V, geo.F
    ends, faces = walk
    total = _corner(V, u, q0, V[ends[0]]) + _corner(V, u, V[ends[-1]], q1)
    for f in faces[1:-1]:
        a, b = [int(w) for w in F[f] if w != u]
        total += _corner(V, u, a, b)
    return total


def _switch_sides(mesh: TriMesh, geo: _Geometry, nodes: list) -> tuple[list, bool]:
    """Where the straightened path is held at a vertex, go around it on the side of the smaller angle.

    A run of crossings that all sit on one vertex means the shortest path through the current faces wraps
    around that vertex; if the angle on the other side is smaller, the path through the faces there is
    shorter (on a flat surface it is the straight line), so the run is replaced by the walk on that side.
    """
    V = mesh.V
    tol = 1e-12 * mesh.bbox_diagonal

    def held(nd):
        if nd[0] != "e" or nd[3] == nd[4]:
            return None
        for w in (nd[1], nd[2]):
            if np.linalg.norm(nd[5] - V[w]) <= tol:
                return int(w)
        return None

    out, switched, i, n = [nodes[0]], False, 1, len(nodes)
    while i < n - 1:
        u = held(nodes[i])
        if u is None:
            out.append(nodes[i])
            i += 1
            continue
        j = i
        while j + 1 < n - 1 and held(nodes[j + 1]) == u:
            j += 1
        run = nodes[i:j + 1]
        f_in, f_out = run[0][3], run[-1][4]
        current = [run[0][3], *(r[4] for r in run)]
        q0, q1 = _position(mesh, out[-1]), _position(mesh, nodes[j + 1])
        walks = [w for w in _fan(geo, u, f_in, f_out) if w[1] != current] if f_in != f_out else []
        if walks and np.linalg.norm(q0 - V[u]) > tol and np.linalg.norm(q1 - V[u]) > tol:
            cur_walk = ([r[2] if r[1] == u else r[1] for r in run], current)
            other = walks[0]
            if _walk_angle(geo, u, other, q0, q1) < _walk_angle(geo, u, cur_walk, q0, q1) - 1e-9:
                ends, faces = other
                out.extend(("e", u, w, faces[k], faces[k + 1], 0.7 * V[u] + 0.3 * V[w]) for k, w in enumerate(ends))
                switched = True
                i = j + 1
                continue
        out.extend(run)
        i = j + 1
    out.append(nodes[-1])
    return out, switched


def _cross(u, v) -> float:
    return float(u[0] * v[1] - u[1] * v[0])


def _unfold_third(pa, pc, la, lc, side_ref) -> np.ndarray:
    """2D position of the third corner at distances ``la`` from ``pa`` and ``lc`` from ``pc``, on the side of
    the line (pa, pc) opposite to ``side_ref``."""
    e = pc - pa
    L = float(np.hypot(*e))
    ex = e / L
    ey = np.array([-ex[1], ex[0]])
    x = (la * la - lc * lc + L * L) / (2 * L)
    y = np.sqrt(max(la * la - x * x, 0.0))
    if _cross(e, side_ref - pa) > 0:
        y = -y
    return pa + x * ex + y * ey


def _funnel(start, portals, end) -> tuple[list[np.ndarray], list[int]]:
    """Shortest path in a simple polygon strip (the 'simple stupid funnel algorithm').

    ``portals`` are (left, right) 2D pairs in travel order. Returns the path's corners (start, portal
    endpoints, end) and, for each corner, the index of its portal (0 for start, len(portals) + 1 for end).
    """
    P = [(start, start), *portals, (end, end)]
    apex, pl, pr = start, start, start
    ia = il = ir = 0
    path, idx = [start], [0]
    i = 1
    while i < len(P):
        left, right = P[i]
        corner = None
        if _cross(pr - apex, right - apex) >= 0:  # tightens the right side
            if np.array_equal(apex, pr) or _cross(pl - apex, right - apex) < 0:
                pr, ir = right, i
            else:  # crosses the left side: the left point becomes a corner
                corner, ic = pl, il
        if corner is None and _cross(pl - apex, left - apex) <= 0:  # tightens the left side
            if np.array_equal(apex, pl) or _cross(pr - apex, left - apex) > 0:
                pl, il = left, i
            else:  # crosses the right side: the right point becomes a corner
                corner, ic = pr, ir
        if corner is not None:  # the funnel closed: restart it at the new corner
            path.append(corner)
            idx.append(ic)
            apex, ia = corner, ic
            pl = pr = apex
            il = ir = ia
            i = ia + 1
            continue
        i += 1
    if not np.array_equal(path[-1], end) or idx[-1] != len(P) - 1:
        path.append(end)
        idx.append(len(P) - 1)
    return path, idx


def _straighten_chain(mesh: TriMesh, q0: np.ndarray, chain: list, q1: np.ndarray) -> list:
    """Shortest path from ``q0`` (in the first face) through the chain's edges to ``q1`` (in the last face)."""
    V, F = mesh.V, mesh.F
    f0 = chain[0][3]
    tri = V[F[f0]]
    # 2D frame of the first face
    ex = tri[1] - tri[0]
    ex = ex / np.linalg.norm(ex)
    nrm = np.cross(tri[1] - tri[0], tri[2] - tri[0])
    ey = np.cross(nrm / np.linalg.norm(nrm), ex)
    pos2 = {int(F[f0, k]): np.array([(tri[k] - tri[0]) @ ex, (tri[k] - tri[0]) @ ey]) for k in range(3)}
    start = np.array([(q0 - tri[0]) @ ex, (q0 - tri[0]) @ ey])
    portals, ends = [], []
    prev_face = f0
    for nd in chain:
        a, c, f_out = nd[1], nd[2], nd[4]
        pa, pc = pos2[a], pos2[c]
        o_prev = next(int(w) for w in F[prev_face] if w != a and w != c)
        ref = pos2[o_prev]
        o = next(int(w) for w in F[f_out] if w != a and w != c)
        po = _unfold_third(pa, pc, float(np.linalg.norm(V[o] - V[a])), float(np.linalg.norm(V[o] - V[c])), ref)
        pos2 = {a: pa, c: pc, o: po}
        # left / right as seen when entering f_out from prev_face
        if _cross(pc - ref, pa - ref) > 0:
            portals.append((pa, pc))
            ends.append((a, c))
        else:
            portals.append((pc, pa))
            ends.append((c, a))
        prev_face = f_out
    # the end point, in the last face's unfolded position (barycentric coordinates carry over)
    fl = chain[-1][4]
    b = _barycentric(V[F[fl]][None], q1[None])[0]
    end = sum(b[k] * pos2[int(F[fl, k])] for k in range(3))
    corners, idx = _funnel(start, portals, end)
    out = []
    k = 0
    for j, nd in enumerate(chain, start=1):
        while idx[k + 1] < j:
            k += 1
        (lft, rgt), (vl, vr) = portals[j - 1], ends[j - 1]
        if idx[k] == j:  # the path bends at an endpoint of this edge
            t = 0.0 if np.array_equal(corners[k], lft) else 1.0
        else:
            A, B = corners[k], corners[k + 1]
            d = B - A
            den = _cross(d, rgt - lft)
            if abs(den) <= 1e-14 * (np.hypot(*d) * np.hypot(*(rgt - lft)) + 1e-300):
                # a corner repeated (zero-length segment) or a segment along the edge: the nearest edge point
                w = rgt - lft
                t = float(np.clip((A - lft) @ w / (w @ w), 0.0, 1.0))
            else:
                t = float(np.clip(_cross(lft - A, d) / den, 0.0, 1.0))
        x = (1 - t) * V[vl] + t * V[vr]
        out.append((*nd[:5], x))
    return out


def _straighten(mesh: TriMesh, nodes: list, medium: Any = None) -> None:
    """Move every chain of edge crossings between two fixed nodes to the shortest path through its faces
    (in a medium: the path of least length in it, :meth:`~cvxgeodesic.operators.metric.Medium.least_crossings`)."""
    n = len(nodes)
    i = 1
    while i < n - 1:
        if not (nodes[i][0] == "e" and nodes[i][3] != nodes[i][4]):
            i += 1
            continue
        j = i
        while (j + 1 < n - 1 and nodes[j + 1][0] == "e" and nodes[j + 1][3] != nodes[j + 1][4]
               and nodes[j + 1][3] == nodes[j][4]):
            j += 1
        q0, q1 = _position(mesh, nodes[i - 1]), _position(mesh, nodes[j + 1])
        if medium is None:
            nodes[i:j + 1] = _straighten_chain(mesh, q0, nodes[i:j + 1], q1)
        else:
            chain = nodes[i:j + 1]
            ends = np.array([nd[1:3] for nd in chain], dtype=np.int64)
            faces = np.array([chain[0][3], *(nd[4] for nd in chain)], dtype=np.int64)  # of the K + 1 pieces
            t = medium.least_crossings(q0, ends, faces, q1)
            if t is not None:
                V = mesh.V
                nodes[i:j + 1] = [(*nd[:5], (1 - tk) * V[nd[1]] + tk * V[nd[2]]) for nd, tk in zip(chain, t,
                                                                                                  strict=True)]
        i = j + 1
