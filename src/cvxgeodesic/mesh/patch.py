"""The patch of a mesh around one vertex: the faces within an edge-graph distance, as a mesh of its own.

``distance_matrix(..., max_distance=r)`` solves each row on such a patch (:mod:`cvxgeodesic.rows`). Dijkstra's
distance on the edge graph is never shorter than the geodesic one, and at most ``ρ`` times it (a path along edges
zigzags: ``ρ`` ≈ 1.2 measured on scans). The faces whose three vertices are within ``c·r`` of the source by
Dijkstra therefore hold the whole geodesic ``r``-ball when ``c ≥ ρ``, and a margin around it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse.csgraph import dijkstra

from .trimesh import TriMesh

__all__ = ["PATCH_LABEL", "Patch", "ball_patch", "is_patch"]

#: What a patch's name adds to its mesh's: every note about the patch then says it is one, and reads the same on
#: every patch (a warning shown once, not once per row).
PATCH_LABEL = " (patch around a source)"


def is_patch(mesh: TriMesh) -> bool:
    """True for the mesh of a :class:`Patch` (or a copy of it that kept its name, as the solvers' scaled copies do)."""
    return str(mesh.name).endswith(PATCH_LABEL)


@dataclass(frozen=True)
class Patch:
    """Faces of a mesh around a source, as a mesh with maps back to the whole one.

    Attributes
    ----------
    mesh : TriMesh or None
        The patch, its vertices numbered ``0 .. p-1``; None when it has no face.
    vertices : (p,) int64 ndarray
        The whole mesh's index of each patch vertex (increasing).
    source : int
        The patch's index of the source vertex.
    cut : (c,) int64 ndarray
        Patch indices of the vertices on the cut: in a face of the whole mesh that the patch left out
        (the mesh's own boundary is not a cut). Empty when the patch is the source's whole component.
    radius : float
        The edge-graph distance that chose the faces.
    faces : (k,) int64 ndarray
        The whole mesh's index of each patch face, in the patch's order (empty without a face).
    """

    mesh: TriMesh | None
    vertices: np.ndarray
    source: int
    cut: np.ndarray
    radius: float
    faces: np.ndarray


def ball_patch(mesh: TriMesh, source: int, radius: float, allowed: np.ndarray | None = None) -> Patch:
    """The faces of ``mesh`` whose three vertices are within ``radius`` of ``source`` on the edge graph (and
    ``allowed``).

    Parameters
    ----------
    mesh : TriMesh
    source : int
        A valid vertex index.
    radius : float
        Edge-graph (Dijkstra) distance, > 0.
    allowed : (n,) bool ndarray, optional
        The vertices a face may have besides (a rounder ball from an estimate of the geodesic distance).

    Returns
    -------
    Patch
        Without a face (``mesh`` None, ``vertices == [source]``) when ``source`` is in no face or each of its
        faces reaches past ``radius``.
    """
    source = int(source)
    near = dijkstra(mesh.vertex_adjacency, indices=source, limit=radius) <= radius
    if allowed is not None:
        near &= allowed
    inside = near[mesh.F]
    keep = inside.all(axis=1)
    if not keep.any():
        empty = np.zeros(0, dtype=np.int64)
        return Patch(None, np.array([source], dtype=np.int64), 0, empty, float(radius), empty)
    faces = mesh.F[keep]
    vertices = np.unique(faces)
    local = np.full(mesh.n_vertices, -1, dtype=np.int64)
    local[vertices] = np.arange(vertices.size)
    # a left-out face that touches the patch marks its patch vertices as the cut
    touching = mesh.F[~keep & inside.any(axis=1)].ravel()
    cut = np.unique(local[touching])
    patch = TriMesh(mesh.V[vertices], local[faces], name=f"{mesh.name}{PATCH_LABEL}")
    return Patch(patch, vertices, int(local[source]), cut[cut >= 0], float(radius), np.flatnonzero(keep))
