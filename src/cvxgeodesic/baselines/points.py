"""Point, curve and boundary sources for the baselines, where their libraries can take them.

- ``dijkstra``: the edge graph plus one virtual node joined to every vertex of a source face by
  an edge as long as :func:`~cvxgeodesic.sources.vertex_bounds` (the straight segment to the point
  or curve piece inside that face); vertex sources start at 0.
- ``exact``: the points are inserted into the mesh (a face split in three, an edge and its two
  faces split in two: the same surface) and pygeodesic runs from the new vertices, so the result
  is the exact polyhedral distance to the points. A curve is its samples
  (:data:`~cvxgeodesic.sources.CURVE_STEP`); ``"boundary"`` is the boundary vertices.
- ``fmm``: potpourri3d's fast marching takes ``(face, [b0, b1, b2])`` points natively; a curve is
  its samples; ``"boundary"`` is the boundary vertices. Single-component meshes only.
- ``heat``: potpourri3d's heat method takes vertices only; points and curves raise
  :class:`~cvxgeodesic.errors.SourceError` (from :func:`cvxgeodesic.capabilities.check`, the one table of
  what each method takes), ``"boundary"`` is the boundary vertices.

Each class calls its function here from ``_solve_sources``
(:meth:`~cvxgeodesic.baselines.base.BaselineSolver.solve`, which checks the field); inside a volume the
baselines take every kind of volume source themselves. :func:`graph_distance` is Dijkstra with offsets, for
both dimensions.
"""

from __future__ import annotations

import contextlib
import io

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from ..capabilities import methods_for
from ..errors import SourceError
from ..mesh.locate import closest_points
from ..mesh.trimesh import TriMesh
from ..sources import BARY_SNAP, SourceSet, vertex_bounds


def graph_distance(graph: sp.spmatrix, starts: np.ndarray, near: np.ndarray | None = None,
                   offsets: np.ndarray | None = None) -> np.ndarray:
    """Shortest paths on ``graph`` from the ``starts`` (at 0) and from vertices reached at a known offset.

    The offsets are the straight segments from a source inside a cell (a point, a curve piece) to the cell's
    corners: one virtual node is joined to each vertex of ``near`` by an edge as long as its offset, so the result
    is exactly the minimum over the sources of single runs.

    Parameters
    ----------
    graph : (n, n) sparse matrix
        Edge lengths (symmetric).
    starts : (s,) int ndarray
        Vertices at distance 0.
    near : (q,) int ndarray, optional
        Distinct vertices next to a source that is not a vertex.
    offsets : (q,) float ndarray, optional
        Their distances to that source (finite, ≥ 0). An offset of 0 makes the vertex a start: a zero weight is
        no edge in SciPy's sparse graphs.

    Returns
    -------
    (n,) float64 ndarray
        ``np.inf`` where no source is reachable.
    """
    n = graph.shape[0]
    starts = np.asarray(starts, dtype=np.int64)
    if near is None or offsets is None or not len(near):
        d = dijkstra(graph, directed=False, indices=starts, min_only=True)
        return np.asarray(d, dtype=np.float64)
    near, offsets = np.asarray(near, dtype=np.int64), np.asarray(offsets, dtype=np.float64)
    zero = offsets == 0.0
    starts = np.unique(np.concatenate([starts, near[zero]]))
    near, w = near[~zero], offsets[~zero]
    G = sp.coo_matrix(graph)
    virtual = np.full(near.size, n)
    A = sp.coo_matrix((np.r_[G.data, w, w], (np.r_[G.row, virtual, near], np.r_[G.col, near, virtual])),
                      shape=(n + 1, n + 1)).tocsr()
    idx = np.r_[starts, n] if near.size else starts
    d = dijkstra(A, directed=False, indices=idx, min_only=True)
    return np.asarray(d[:n], dtype=np.float64)


def dijkstra_sources(mesh: TriMesh, ss: SourceSet, graph: sp.csr_matrix, medium=None) -> np.ndarray:
    """Dijkstra's field from a surface's points, curves or boundary: each vertex of a source face starts at
    :func:`~cvxgeodesic.sources.vertex_bounds` (in ``medium`` when given)."""
    bound = vertex_bounds(mesh, ss, medium)
    if medium is not None:
        bound = bound * medium.scale
    near = np.flatnonzero(np.isfinite(bound))
    return graph_distance(graph, ss.vertices, near, bound[near])


def _unique_points(mesh: TriMesh, ss: SourceSet) -> np.ndarray:
    """(p, 3) positions of the point sources, one per point (an edge point is listed once per face)."""
    X = ss.point_positions(mesh)
    if not len(X):
        return X
    key = np.round(X / max(mesh.bbox_diagonal, 1e-300), 12)
    _, first = np.unique(key, axis=0, return_index=True)
    return X[np.sort(first)]


def insert_points(V: np.ndarray, F: np.ndarray, X: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Insert surface points as vertices (the surface does not change).

    Parameters
    ----------
    V : (n, 3) float ndarray
    F : (m, 3) int ndarray
    X : (p, 3) float ndarray
        Positions on the surface.

    Returns
    -------
    V2 : (n + q, 3) float ndarray
    F2 : (m + 2q', 3) int64 ndarray
    index : (p,) int64 ndarray
        Vertex of each point in ``V2`` (an old vertex where a point lies on one).
    """
    V2, F2 = [np.asarray(V, dtype=float)], np.array(F, dtype=np.int64)
    Vc = V2[0]
    index = np.zeros(len(X), dtype=np.int64)
    for i, x in enumerate(X):
        tm = TriMesh(Vc, F2)
        (f,), (b,), _ = closest_points(tm, x[None])
        k = int(np.argmax(b))
        if b[k] >= 1 - BARY_SNAP:
            index[i] = F2[f, k]
            continue
        new = len(Vc)
        Vc = np.vstack([Vc, b @ Vc[F2[f]]])
        zero = np.flatnonzero(b <= BARY_SNAP)
        if zero.size:  # on the edge opposite corner zero[0]: split every face of that edge in two
            a, c = F2[f, (zero[0] + 1) % 3], F2[f, (zero[0] + 2) % 3]
            faces = np.flatnonzero((F2 == a).any(axis=1) & (F2 == c).any(axis=1))
            add = []
            for g in faces:
                tri = F2[g].copy()
                ia, ic = int(np.flatnonzero(tri == a)[0]), int(np.flatnonzero(tri == c)[0])
                t1, t2 = tri.copy(), tri.copy()
                t1[ic] = new  # keeps a and the third corner
                t2[ia] = new
                F2[g] = t1
                add.append(t2)
            F2 = np.vstack([F2, np.array(add)])
        else:
            a, bb, c = F2[f]
            F2[f] = [a, bb, new]
            F2 = np.vstack([F2, [[bb, c, new], [c, a, new]]])
        index[i] = new
    return Vc, F2, index


def exact_inserted(cls: type, mesh: TriMesh, ss: SourceSet) -> tuple[np.ndarray, dict]:
    """The exact field of ``cls`` (:class:`~cvxgeodesic.baselines.exact.ExactBaseline`) from the points of ``ss``
    inserted into the mesh as vertices (a curve: its samples)."""
    X = _unique_points(mesh, ss)
    V2, F2, idx = insert_points(mesh.V, mesh.F, X)
    solver = cls(TriMesh(V2, F2, name=mesh.name))
    src = np.unique(np.r_[ss.vertices, idx]).astype(np.int64)
    with contextlib.redirect_stdout(io.StringIO()):
        d, _ = solver.solve(src)
    return np.asarray(d[: mesh.n_vertices], dtype=float), {
        "sources": f"{len(X)} point(s) inserted into the mesh", "inserted_vertices": int(len(V2) - mesh.n_vertices)}


def fmm_points(baseline, ss: SourceSet) -> tuple[np.ndarray, dict]:
    """potpourri3d's fast marching from the points of ``ss`` (a curve: its samples), on a mesh of one component."""
    mesh = baseline.mesh
    parts = baseline._parts
    if len(parts) != 1 or next(iter(parts.values())).vertices.size != mesh.n_vertices:
        can = [m for m in methods_for(mesh.domain, source="point") if m != "fmm"]
        raise SourceError("method 'fmm' cannot take point or curve sources on a mesh with several components or "
                          "unreferenced vertices (the library's face indices are per component); methods that can: "
                          + ", ".join(can))
    solver = next(iter(parts.values())).solver
    pts = [(int(v), []) for v in ss.vertices]
    bary = np.asarray(ss.point_bary, dtype=np.float64).reshape(-1, 3)
    if baseline.orientation is not None:  # the library has the reoriented faces: their corners in its order
        bary = baseline.orientation.bary(ss.point_faces, bary)
    pts += [(int(f), [float(x) for x in b]) for f, b in zip(ss.point_faces, bary, strict=True)]
    d = np.asarray(solver.compute_distance([pts], [], False), dtype=np.float64).reshape(-1) * baseline.scale
    return d, {"sources": "potpourri3d surface points"}
