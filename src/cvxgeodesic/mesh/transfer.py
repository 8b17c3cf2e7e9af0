"""Moving per-vertex fields between two meshes of one surface by closest-point barycentric interpolation.

For every query point (the fine mesh's vertices), :class:`SurfaceTransfer` finds the closest point on the
coarse surface (libigl's AABB tree, exact point–triangle distance) and its barycentric coordinates in that
coarse triangle; a coarse per-vertex field is then interpolated there. :class:`ProjectedField` does the same for a
field that answers at points of the coarse mesh's faces (an order-2 field): it answers at points of the fine mesh, a
:class:`~cvxgeodesic.results.Field` there.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np

from .closest import closest_point_index
from .geometry import clipped_barycentric
from .locate import bary_positions, checked_points
from .trimesh import TriMesh

__all__ = ["ProjectedField", "SourcePatch", "SurfaceTransfer", "mix_patches"]


class SurfaceTransfer:
    """Interpolation of coarse per-vertex fields at points near the coarse surface.

    Parameters
    ----------
    coarse : TriMesh
        Mesh the fields live on (``nc`` vertices, ``mc`` faces).
    points : (k, 3) float ndarray
        Where the fields are wanted (the fine mesh's vertices).

    Attributes
    ----------
    face : (k,) int64 ndarray
        Coarse triangle holding the closest point of each query point.
    weights : (k, 3) float ndarray
        Barycentric coordinates of that closest point.
    sq_distance : (k,) float ndarray
        Squared distance of each point to the coarse surface.
    setup_time : float
        Seconds spent in the constructor.
    """

    def __init__(self, coarse: TriMesh, points: np.ndarray):
        t0 = time.perf_counter()
        self.coarse = coarse
        self.points = np.ascontiguousarray(points, dtype=np.float64)
        self.face, self.weights, self.sq_distance = self._project(np.arange(coarse.n_faces))
        self._kdtree: Any = None  # built on the first nearest_vertex call
        self.setup_time = time.perf_counter() - t0

    def _project(self, faces: np.ndarray, idx: np.ndarray | None = None):
        import igl

        P = self.points if idx is None else self.points[idx]
        F = np.ascontiguousarray(self.coarse.F[faces])
        sqd, fi, C = igl.point_mesh_squared_distance(P, self.coarse.V, F)
        fi = faces[np.asarray(fi, dtype=np.int64)]
        Vt = self.coarse.V[self.coarse.F[fi]]
        W = clipped_barycentric(np.asarray(C), Vt[:, 0], Vt[:, 1], Vt[:, 2])
        return fi, W, np.asarray(sqd)

    def apply(self, values: np.ndarray, need: np.ndarray | None = None) -> np.ndarray:
        """Interpolate a coarse field at the query points.

        Parameters
        ----------
        values : (nc,) float ndarray
            Coarse per-vertex values; ``inf`` marks vertices without a value.
        need : (k,) bool ndarray, optional
            Points that must get a finite value when one exists: a point whose
            closest coarse triangle has a non-finite corner is re-projected onto
            the triangles whose three values are finite.

        Returns
        -------
        (k,) float ndarray
        """
        tri_vals = values[self.coarse.F[self.face]]
        out = np.einsum("ij,ij->i", self.weights, np.where(np.isfinite(tri_vals), tri_vals, 0.0))
        bad = ~np.isfinite(tri_vals).all(axis=1)
        out[bad] = np.inf
        if need is not None:
            redo = np.flatnonzero(bad & need)
            finite_faces = np.flatnonzero(np.isfinite(values[self.coarse.F]).all(axis=1))
            if redo.size and finite_faces.size:
                fi, W, _ = self._project(finite_faces, redo)
                out[redo] = np.einsum("ij,ij->i", W, values[self.coarse.F[fi]])
        return out

    def nearest_vertex(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Nearest coarse vertex of each point.

        Parameters
        ----------
        points : (k, 3) float ndarray

        Returns
        -------
        index : (k,) int64 ndarray
        distance : (k,) float ndarray
        """
        if self._kdtree is None:
            from scipy.spatial import cKDTree

            self._kdtree = cKDTree(self.coarse.V)
        dist, idx = self._kdtree.query(np.atleast_2d(points))
        return np.asarray(idx, dtype=np.int64), np.asarray(dist)


class SourcePatch:
    """A field solved on a patch of faces of a mesh around a source, mixed into another field near the source
    (:func:`mix_patches`): where the patch's field is at most ``inner`` it replaces the other field, between
    ``inner`` and ``outer`` it is mixed in linearly (by its own value), beyond ``outer`` (or outside the patch) the
    other field stays.

    Parameters
    ----------
    face_map : (m,) int64 ndarray
        The patch's face of each face of the whole mesh, -1 outside the patch.
    vertices : (p,) int64 ndarray
        The whole mesh's index of each patch vertex.
    field : Field
        A :class:`~cvxgeodesic.results.Field` on the patch (its faces, its vertices).
    inner, outer : float
        Distances of the blend, ``0 < inner < outer``; ``outer`` inf: the patch's field wherever it is finite.
    """

    def __init__(self, face_map: np.ndarray, vertices: np.ndarray, field: Any, inner: float, outer: float) -> None:
        self.face_map, self.vertices, self.field = face_map, vertices, field
        self.inner, self.outer = float(inner), float(outer)

    def weight(self, near: np.ndarray) -> np.ndarray:
        """(k,) float in [0, 1]: the patch's share where its field is ``near``."""
        if np.isinf(self.outer):  # the patch is its source's whole component
            return np.where(np.isfinite(near), 1.0, 0.0)
        with np.errstate(invalid="ignore"):
            w = np.clip((self.outer - near) / (self.outer - self.inner), 0.0, 1.0)
        return np.where(np.isfinite(near), w, 0.0)

    def at_vertices(self, n: int) -> np.ndarray:
        """(n,) the patch's field at the whole mesh's vertices, inf outside the patch."""
        out = np.full(n, np.inf)
        out[self.vertices] = np.asarray(self.field.vertex_distance, dtype=float)
        return out

    def at_points(self, faces: np.ndarray, bary: np.ndarray) -> np.ndarray:
        """(k,) the patch's field at points of the whole mesh's faces, inf outside the patch."""
        out = np.full(faces.size, np.inf)
        local = self.face_map[faces]
        inside = np.flatnonzero(local >= 0)
        if inside.size:
            out[inside] = np.asarray(self.field.distance_at(local[inside], bary[inside]), dtype=float)
        return out

    def gradient_at_points(self, faces: np.ndarray, bary: np.ndarray) -> np.ndarray:
        """(k, 3) the patch's field's gradient at points of the whole mesh's faces, NaN outside the patch."""
        out = np.full((faces.size, 3), np.nan)
        local = self.face_map[faces]
        inside = np.flatnonzero(local >= 0)
        if inside.size:
            out[inside] = self.field.gradient_at(local[inside], bary[inside])
        return out


def mix_patches(base: np.ndarray, patches: Any, nears: Any) -> np.ndarray:
    """``base`` with the fields of source patches mixed in: where points are within some patch's ``outer``, the
    least of those patches' blends (:meth:`SourcePatch.weight`), elsewhere ``base``.

    Parameters
    ----------
    base : (k,) float ndarray
    patches : sequence of SourcePatch
    nears : sequence of (k,) float ndarray
        Each patch's field at the points (inf outside it).

    Returns
    -------
    (k,) float ndarray
    """
    best = np.full(base.shape, np.inf)
    for patch, near in zip(patches, nears, strict=True):
        w = patch.weight(near)
        with np.errstate(invalid="ignore"):
            best = np.minimum(best, np.where(w > 0, w * near + (1 - w) * base, np.inf))
    return np.where(np.isfinite(best), best, base)


class ProjectedField:
    """A distance field solved on another mesh of the same surface, read at points of this one.

    A point of ``mesh`` (a face and barycentric coordinates) is moved to its closest point on ``solve_mesh``, where
    ``field`` is evaluated: the field of an adapted solve (:mod:`cvxgeodesic.strategies.adapted`) answers
    :func:`~cvxgeodesic.paths.distance_at` on the user's surface this way.

    Parameters
    ----------
    mesh : TriMesh
        The mesh the queries name faces of (``m`` faces).
    solve_mesh : TriMesh
        The mesh the field lives on.
    field : Field
        A :class:`~cvxgeodesic.results.Field` on ``solve_mesh`` (a
        :class:`~cvxgeodesic.operators.lagrange.LagrangeField`).
    vertex_distance : (n,) float ndarray
        The field at ``mesh``'s vertices (what the solve returned).
    patches : sequence of SourcePatch
        Fields solved on ``mesh`` itself around the sources, mixed in near them (in order).
    medium : Medium, optional
        The travel cost or metric the field measures, on ``mesh``; None: Euclidean.
    correction : (n,) finite float ndarray, optional
        Added to the field, linearly interpolated on ``mesh``'s faces (the ridge rounding of an adapted solve,
        :func:`~cvxgeodesic.problems.ridge_rounding.round_ridge`: the rounded minus the transferred vertex values, 0
        at vertices of no finite value), after the patches are mixed in.
    closest : callable, optional
        ``closest(X (p, 3), labels (p,)) -> (faces, bary, distance)`` on ``solve_mesh`` for points of ``mesh``'s
        components ``labels``: a copy made one component at a time answers each point on its own component's copy.
        Default: the closest point on the whole of ``solve_mesh``.
    """

    def __init__(self, mesh: TriMesh, solve_mesh: TriMesh, field: Any, vertex_distance: np.ndarray,
                 patches: Any = (), medium: Any = None, correction: np.ndarray | None = None,
                 closest: Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]] | None = None
                 ) -> None:
        self.mesh = mesh
        self.solve_mesh = solve_mesh
        self.field = field
        self.vertex_distance = vertex_distance
        self.patches = tuple(patches)
        self.medium = medium
        self.correction = correction
        self.closest = closest

    def _projected(self, faces: Any, bary: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``(faces, bary)`` as arrays and the closest points of those points on ``solve_mesh`` (faces, bary)."""
        faces, B = checked_points(self.mesh, faces, bary)
        X = np.ascontiguousarray(bary_positions(self.mesh, faces, B))
        if self.closest is None:
            cf, cb, _ = closest_point_index(self.solve_mesh).query(X)
        else:
            cf, cb, _ = self.closest(X, self.mesh.component_labels[self.mesh.F[faces, 0]])
        return faces, B, cf, cb

    def distance_at(self, faces: Any, bary: Any) -> np.ndarray:
        """Distance at points of ``mesh``'s faces.

        Parameters
        ----------
        faces : int or (p,) int array_like
        bary : (3,) or (p, 3) float array_like

        Returns
        -------
        (p,) float ndarray
        """
        faces, B, cf, cb = self._projected(faces, bary)
        out = np.asarray(self.field.distance_at(cf, cb), dtype=float)
        if self.patches:
            out = mix_patches(out, self.patches, [p.at_points(faces, B) for p in self.patches])
        if self.correction is not None:
            out = out + np.einsum("pc,pc->p", B, self.correction[self.mesh.F[faces]])
        return out

    def gradient_at(self, faces: Any, bary: Any) -> np.ndarray:
        """Gradient of :meth:`distance_at` at points of ``mesh``'s faces: the solve mesh's field's gradient at the
        closest point, in the plane of ``mesh``'s face; where a source patch is mixed in, the gradient of the blend.

        Returns
        -------
        (p, 3) float ndarray
        """
        faces, B, cf, cb = self._projected(faces, bary)
        base = np.asarray(self.field.distance_at(cf, cb), dtype=float)
        grad = np.asarray(self.field.gradient_at(cf, cb), dtype=float)
        n = self.mesh.face_normals_unnormalized[faces]
        with np.errstate(invalid="ignore", divide="ignore"):
            n = n / np.linalg.norm(n, axis=1, keepdims=True)
        grad = grad - np.einsum("pj,pj->p", grad, n)[:, None] * n
        best = np.full(faces.size, np.inf)
        out = grad.copy()
        for patch in self.patches:  # the gradient of the blend mix_patches takes, where it takes one
            near = patch.at_points(faces, B)
            w = patch.weight(near)
            with np.errstate(invalid="ignore"):
                blend = np.where(w > 0, w * near + (1 - w) * base, np.inf)
                # d/dx [w(near) near + (1 − w(near)) base], with w' = −1/(outer − inner) inside the ramp
                slope = np.where((w > 0) & (w < 1), -1.0 / (patch.outer - patch.inner), 0.0)
            take = blend < best
            if take.any():
                gn = patch.gradient_at_points(faces[take], B[take])
                wt, st = w[take, None], slope[take, None]
                out[take] = wt * gn + (1 - wt) * grad[take] + st * (near[take] - base[take])[:, None] * gn
                best[take] = blend[take]
        if self.correction is not None:
            out = out + _linear_gradients(self.mesh, faces, self.correction)
        return out


def _linear_gradients(mesh: TriMesh, faces: np.ndarray, values: np.ndarray) -> np.ndarray:
    """(p, 3) the gradients on ``faces`` of the linear interpolant of the vertex ``values`` (0 on faces of no area):
    ``(c₁ − c₀) ∇λ₁ + (c₂ − c₀) ∇λ₂`` with ``∇λᵢ = n × eᵢ / (2A)``, ``eᵢ`` the edge opposite corner ``i``."""
    P = mesh.V[mesh.F[faces]]
    c = values[mesh.F[faces]]
    N = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
    twice_area = np.linalg.norm(N, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        n = N / twice_area[:, None]
        g = ((c[:, 1] - c[:, 0])[:, None] * np.cross(n, P[:, 0] - P[:, 2])
             + (c[:, 2] - c[:, 0])[:, None] * np.cross(n, P[:, 1] - P[:, 0])) / twice_area[:, None]
    return np.where(twice_area[:, None] > 0, g, 0.0)
