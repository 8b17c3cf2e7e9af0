"""The rows a source set adds to the order-1 program, on a surface (triangles) or inside a solid (tetrahedra).

:func:`source_constraints` turns a :class:`~cvxgeodesic.sources.SourceSet` (or validated source vertices) into the
constraints the convex formulations add (``docs/sources.md`` and ``docs/volumes.md`` explain and measure each
choice):

- vertex sources and the vertices of source faces are fixed at 0; the cells incident to a source vertex carry no
  cone; each star edge bounds its other end by its length;
- a point ``p`` in cell ``t`` bounds each vertex of ``t`` by ``|v_i − p|`` (the straight segment inside the flat
  cell is a path, so this is an upper bound of the geodesic distance; :func:`~cvxgeodesic.sources.vertex_bounds`)
  and ``t`` carries no cone. On a surface a point on an edge does this in both faces of the edge;
- a cell next to the sources whose local field (the distance to the nearest source vertex, point, curve piece or
  source face) is steeper than 1 when interpolated linearly (the trace of a cone whose apex is close to the cell)
  carries no cone either. The vertices it leaves free are bounded through the edges to the source cells'
  vertices, ``d_w ≤ d_v + ℓ_vw`` (a triangle inequality), and the edges of those cells keep ``|d_i − d_j| ≤ ℓ_ij``.
  The surface program adds these edge rows; the solid one bounds every edge of a tetrahedron without a cone
  instead, which implies them (:func:`~cvxgeodesic.problems.formulations.build_problem`);
- a curve is sampled along each segment at an eighth of the mean edge length (plus its given
  points); every sample is a point source, and two consecutive samples in the same face add the
  bound by the distance to the segment between them (straight in that face);
- the boundary of a surface fixes every boundary vertex at 0 and bounds the third vertex of each boundary
  face by its distance to the boundary edge; a source face of a solid bounds the fourth vertex of its tetrahedron
  by its distance to the (closed) triangle.

Every bound is an upper bound of the exact distance (tested against pygeodesic on surfaces), so none of them cuts
the exact field off.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from ..mesh.closest import nearest_triangle_distance
from ..mesh.simplex import SimplexMesh
from ..sources import SourceSet, vertex_bounds

__all__ = ["SourceConstraints", "source_constraints"]


@dataclass
class SourceConstraints:
    """What the sources add to a formulation (read by :func:`~cvxgeodesic.problems.formulations.build_problem`).

    Attributes
    ----------
    fixed : (k,) int64 ndarray
        Vertices fixed at 0.
    no_cone : (m,) bool ndarray
        Cells that carry no cone.
    star_other, star_source : (e,) int64 ndarray
        Edge bounds ``d[star_other] − d[star_source] ≤ star_rhs``: each star edge bounds its other end, then the
        edges around the cone-free cells of points and curves (:func:`_edge_bounds`). The surface program adds
        them; the solid one bounds every edge of a tetrahedron without a cone instead, which implies them.
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


def _steep_cells(ops: Any, ss: SourceSet, near: np.ndarray, medium: Any) -> np.ndarray:
    """(q,) int64 ndarray: the cells of ``near`` where the linear interpolant of the local exact field is steeper
    than 1: the distance to the nearest source vertex, point, curve piece (its ends and midpoint stand in for it) or
    source face. There the exact field violates the cone too (an apex close to the cell's facet or corner)."""
    mesh = ops.mesh
    V, C = mesh.V, mesh.cells
    cand = np.flatnonzero(near)
    corners = C[cand].reshape(-1)
    A, B = ss.segment_ends(mesh)  # the curve pieces (none in a solid)
    P = np.concatenate([ss.point_positions(mesh), V[ss.vertices], A, B, 0.5 * (A + B)])
    local = np.full(corners.size, np.inf)
    nearest = np.zeros(corners.size, dtype=np.int64)
    if len(P):
        local, nearest = cKDTree(P).query(V[corners])
    if medium is not None:  # the local field in the medium: the distance to the nearest point, in cell cand's
        local = medium.vector_lengths(np.repeat(cand, C.shape[1]), V[corners] - P[nearest])
    if ss.facets.size:
        local = np.minimum(local, nearest_triangle_distance(mesh.V, ss.face_triangles(mesh), V[corners]))
        local[np.isin(corners, ss.fixed_vertices(mesh))] = 0.0
    g = np.einsum("tij,tj->ti", ops.gradient_blocks[cand], local.reshape(len(cand), -1))
    return cand[np.linalg.norm(g, axis=1) > 1.0 + 1e-9]


def source_constraints(ops: Any, sources: Any, min_edge_bound: float) -> SourceConstraints:
    """Constraints of a source set (or of validated source vertices) for one mesh, a surface or a solid: those the
    module docstring lists (the bounds at the corners of the sources' cells:
    :func:`~cvxgeodesic.sources.vertex_bounds`; the cells next to the sources where the local field is steeper than 1:
    :func:`_steep_cells`; the edge bounds around the cone-free cells: :func:`_edge_bounds`).

    Parameters
    ----------
    ops : MeshOperators
        The mesh (possibly the solver's rescaled copy), its gradient blocks and degenerate cells.
    sources : (k,) int64 ndarray or SourceSet
    min_edge_bound : float
        The formulations' floor of the edge bounds (:data:`~cvxgeodesic.problems.formulations.MIN_EDGE_BOUND`),
        as a fraction of the bounding-box diagonal; passed in so that sources do not import the formulations.

    Returns
    -------
    SourceConstraints
    """
    mesh = ops.mesh
    n, C, E = mesh.n_vertices, mesh.cells, mesh.edges
    # the formulations' floor of the edge bounds, also for the vertex bounds next to a point that almost
    # touches a vertex: it keeps them inequalities
    floor = min_edge_bound * mesh.bbox_diagonal
    ell = np.maximum(ops.edge_lengths, floor)
    medium = getattr(ops, "medium", None)
    ss = sources if isinstance(sources, SourceSet) else None
    vertices = np.asarray(ss.vertices if ss is not None else sources, dtype=np.int64)
    fixed = ss.fixed_vertices(mesh) if ss is not None and ss.facets.size else vertices
    is_source = np.zeros(n, dtype=bool)
    is_source[vertices] = True
    no_cone = is_source[C].any(axis=1)
    is_source[fixed] = True
    # each star edge bounds its other end
    star = is_source[E[:, 0]] ^ is_source[E[:, 1]]
    o_end, s_end = _edge_ends(E, star, is_source)
    star_rhs = ell[star]
    empty = np.zeros(0, dtype=np.int64)
    if ss is None or ss.vertex_only:
        return SourceConstraints(fixed, no_cone, o_end, s_end, star_rhs, empty, np.zeros(0), fixed)

    bound = vertex_bounds(mesh, ss, medium)
    src_faces = ss.source_faces()
    no_cone[src_faces] = True
    src_verts = is_source.copy()
    src_verts[C[src_faces].ravel()] = True
    near = src_verts[C].any(axis=1) & ~no_cone & ~ops.degenerate
    if near.any():
        no_cone[_steep_cells(ops, ss, near, medium)] = True
    bv = np.flatnonzero(np.isfinite(bound) & ~is_source)
    o_end, s_end, star_rhs = _edge_bounds(mesh, ops, ell, is_source, src_verts & ~is_source, no_cone,
                                          (o_end, s_end, star_rhs))
    return SourceConstraints(fixed=fixed, no_cone=no_cone, star_other=o_end.astype(np.int64),
                             star_source=s_end.astype(np.int64), star_rhs=star_rhs, bound_vertices=bv.astype(np.int64),
                             bound_rhs=np.maximum(bound[bv], floor), anchors=ss.anchor_vertices(mesh))


def _edge_ends(E: np.ndarray, mask: np.ndarray, first: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(other end, first end) of the edges ``E[mask]`` (each with exactly one end where ``first`` is True)."""
    a = first[E[mask, 0]]
    return np.where(a, E[mask, 1], E[mask, 0]), np.where(a, E[mask, 0], E[mask, 1])


def _edge_bounds(mesh: SimplexMesh, ops: Any, ell: np.ndarray, is_source: np.ndarray, src_verts: np.ndarray,
                 no_cone: np.ndarray, star: tuple) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The star bounds ``star`` followed by the edge bounds around the cone-free faces of points and curves.

    Every edge from a source-face vertex to a free vertex outside them bounds that vertex (triangle inequality);
    this keeps the vertices of steep faces bounded and costs nothing elsewhere. The edges of every face left without a
    cone keep ``|d_i − d_j| ≤ l_ij`` (both ways; true of every distance field): without them an edge between two
    free vertices of two such faces is unconstrained and the field can climb above Dijkstra's (measured on a
    jittered grid with the boundary as source: +0.034 at one vertex).
    """
    E = mesh.edges
    one = (src_verts[E[:, 0]] ^ src_verts[E[:, 1]]) & ~is_source[E[:, 0]] & ~is_source[E[:, 1]]
    o2, s2 = _edge_ends(E, one, src_verts)
    ei = np.unique(mesh.cell_edges[no_cone & ~ops.degenerate])
    ei = ei[~is_source[E[ei, 0]] & ~is_source[E[ei, 1]]]
    o_end, s_end, star_rhs = star
    return (np.concatenate([o_end, o2, E[ei, 0], E[ei, 1]]), np.concatenate([s_end, s2, E[ei, 1], E[ei, 0]]),
            np.concatenate([star_rhs, ell[one], ell[ei], ell[ei]]))
