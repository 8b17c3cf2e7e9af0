"""Adapted solves: order 2 on a quadric-decimated copy of the surface, the answer on the user's mesh.

A point cloud's copy is decimated from the surface through its points (:meth:`PointCloud.surface
<cvxgeodesic.mesh.pointcloud.PointCloud.surface>`, :func:`_decimation_source`), and the answer is read at every point.

The resolution a distance field needs is not the resolution of the file it came in (issue 43, DESIGN.md §11).
:class:`Adapted` decimates the user's mesh once, in its constructor (quadric error, ``fast-simplification``, the
boundary kept vertex for vertex), and every solve then runs the order-2 strategy (:class:`~.order2.Order2`) on that
copy:

1. **sources at their exact positions**: a source vertex, a source point, becomes a point of the solve mesh at its
   closest point there (never the nearest coarse vertex); ``"boundary"`` is the solve mesh's boundary, which is the
   user's (no edge touching it is collapsed); curves are refused (order 2 takes none);
2. **media** moved to the solve mesh: a per-vertex cost or metric read at each coarse vertex's closest point of the
   user's surface, a per-face one from the user's face closest to each coarse face's centroid;
3. **the answer on the user's mesh**: the P2 field evaluated at each user vertex's closest point of the solve mesh
   (found once); :class:`~cvxgeodesic.mesh.transfer.ProjectedField` answers ``distance_at`` at any point of the user's
   faces the same way, and ``geodesic_path`` descends the vertex values on the user's mesh;
4. **next to the sources** a patch of the user's mesh solved at order 2 and mixed in as far as its field is the whole
   mesh's (:data:`SOURCE_PATCH_EDGES`, :func:`patch_reach`);
5. **the ridge rounded** for the smoothed methods (``m > 0``): the field's cut locus on the user's mesh rounded over
   the Hessian energy's smoothing length at ``m`` (:func:`~cvxgeodesic.problems.ridge_rounding.round_ridge`), the
   rest of the field as the copy gave it: the order-2 energy of ``φ = d²`` rounds the ridge only by flattening the
   whole field (docs/dev/adapted-log.md);
6. **retries and fallbacks** (:mod:`.decimation`): a copy that changes the topology (Euler characteristic,
   components, a non-manifold edge) or is folded (:func:`fold_excess`) is decimated again at other targets and
   aggressiveness values (recorded in ``decimation_tries``); a mesh in several components is decimated one component
   at a time, each vertex read on its own component's copy (:meth:`_Copy.closest`); a mesh that is not
   edge-manifold or has faces of zero area, or whose every copy was refused, is solved on itself at order 1, with a
   note (quadric decimation gave NaN fields on a non-manifold mesh, issue 43).

``info.extra["adapted"]`` records the solve mesh, its times and an error estimate (two more solves, on a coarser
and a finer copy: :data:`ESTIMATE_RATIO`, :data:`ESTIMATE_FINER`, :data:`ESTIMATE_FACTOR`).
"""

from __future__ import annotations

import functools
import time
from dataclasses import replace
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import MeshError, ParameterError, SolverError, SourceError
from ..mesh.closest import closest_point_index
from ..mesh.envelope import lipschitz_envelope
from ..mesh.locate import SurfacePoint, bary_positions
from ..mesh.patch import Patch, ball_patch
from ..mesh.simplex import SimplexMesh
from ..mesh.transfer import ProjectedField, SourcePatch, mix_patches
from ..mesh.trimesh import TriMesh
from ..operators.lagrange import FLAT_COS, LagrangeSpace
from ..operators.metric import Medium
from ..problems.formulations import smoothness_weight
from ..problems.ridge_rounding import ridge_rounding_length, round_ridge
from ..results import GeodesicResult
from ..sources import SourceSet, resolve_sources
from .base import Callback, SolveConfig
from .decimation import (
    CLOUD_AGGS,
    MIN_PART_FACES,
    MIN_RESOLUTION_FACES,
    RETRY_AGGS,
    SIMPLIFIER,
    _decimated_parts,
    _unsuitable,
    fold_excess,
    fold_reference,
    max_turn,
)
from .direct import DirectStrategy
from .order2 import Order2

if TYPE_CHECKING:
    from ..mesh.pointcloud import PointCloud

__all__ = ["AUTO_FRACTION", "AUTO_MIN_FACES", "CLEAN_CLOUD_FRACTION", "MIN_RESOLUTION_FACES", "NOISY_CLOUD_COPY_TOL",
           "RESOLUTIONS", "SIMPLIFIER", "Adapted", "edge_shortening", "fold_excess", "fold_reference", "max_turn",
           "patch_reach", "resolution_targets", "resolve_resolution"]

#: The named values of ``resolution``; any other is a face count (int) or a fraction of the faces (float).
RESOLUTIONS = ("mesh", "auto")
#: ``resolution="auto"``: this fraction of the user's faces (issue 43: at 1/10 order 2 costs what order 1 costs on
#: the user's mesh, with 2-4x less error) ...
AUTO_FRACTION = 0.1
#: ... but never fewer faces than this; a mesh with fewer than ``AUTO_MIN_FACES / AUTO_FRACTION`` faces is solved at
#: this count, and one with at most ``AUTO_MIN_FACES`` on itself (see docs/adapted.md for the measurement).
AUTO_MIN_FACES = 2000
#: ``resolution="auto"`` on a clean point cloud (:attr:`~cvxgeodesic.mesh.pointcloud.PointCloud.clean`): this
#: fraction of its faces (at least :data:`AUTO_MIN_FACES`), and where that copy is refused, :data:`AUTO_FRACTION`.
#: A clean cloud's error is the copy's, not the noise's, and the surface through its points is rougher than a mesh:
#: measured 2026-12-07 (docs/pointclouds.md, "The copy of a clean cloud") on the vertex clouds of 13 shared meshes
#: and the random surface points of 13, against 1/10.
CLEAN_CLOUD_FRACTION = 0.25
#: A source's barycentric coordinate on the solve mesh below this is set to 0: the point moves onto the edge (by at
#: most this fraction of the face's altitude) instead of splitting the face into a sliver, which the order-2 program
#: leaves without cones (measured on fandisk at 1/10, source vertex 0 at 4.6e-4 from an edge: mean error 1.95 %, max
#: 108 %, against 1.08 % at 1/20 where the point fell on the edge). Recorded as ``source_offset``.
SOURCE_SNAP = 2e-3
#: The error estimate brackets the solve between two companion copies: a coarser one with ``ESTIMATE_RATIO`` of the
#: solve mesh's faces and a finer one with ``ESTIMATE_FINER`` times them (the user's mesh itself when that reaches its
#: face count). With ``Dc``, ``Df`` the mean relative differences of their fields to the solve's, the estimate is
#: ``ESTIMATE_FACTOR * sqrt(Dc * Df)``. Measured on 17 meshes of 5.9-97K faces, sources vertex 0 and n/2, 104 solves
#: (docs/dev/accuracy_per_second.md, run 4): ``Dc`` alone follows the coarser field's error, 1-3x the solve's from
#: mesh to mesh (``Dc`` / true error 0.47-3.35), ``Df`` alone 0.30-1.74; ``sqrt(Dc * Df)`` 0.42-1.78, a spread of 4.2
#: that this factor centres (0.49-2.06). The finer solve costs about 1.4x the solve, the coarser 0.45x (medians).
ESTIMATE_RATIO = 0.5
#: The error estimate's finer copy has this many times the solve mesh's faces (:data:`ESTIMATE_RATIO`).
ESTIMATE_FINER = 2.0
#: The error estimate is this times the geometric mean of the two differences (:data:`ESTIMATE_RATIO`).
ESTIMATE_FACTOR = 1.16
#: Near each source the field is solved again on the user's own mesh, on the patch of faces within this many of the
#: copy's mean edge lengths (edge-graph distance, :func:`~cvxgeodesic.mesh.patch.ball_patch`), and mixed in as far
#: as it is the whole mesh's field (:func:`patch_reach`): the copy's field is weakest next to the sources
#: (docs/adapted.md). 0 turns it off. Not for ``"boundary"`` or more than :data:`MAX_SOURCE_PATCHES` sources; with a
#: cost or metric the patch carries it and the ball is in travel time (kitten from vertex 0 and n/2 with the cost
#: ``1 + z²``: 0.562 → 0.537 % and 0.564 → 0.537 % against order 2 on the mesh with that cost; with the metric
#: diag(2, 1, 0.5): 0.609 → 0.587 % and 0.617 → 0.592 %, the max 8.98 → 5.49 % from n/2; 2026-12-06). Not on a
#: point cloud that is not clean (:attr:`~cvxgeodesic.mesh.pointcloud.PointCloud.clean`): order 2 on its own noisy
#: triangles reads the noise as length, and at 0.1 % noise the patch bought nothing (mean errors equal within 1.2 % on
#: six clouds, the max errors mixed) for 5-8 % of the time (docs/dev/adapted-log.md, 2026-12-07).
SOURCE_PATCH_EDGES = 3.0
#: The patch's field replaces the copy's fully below this share of its reach and is mixed in linearly up to the
#: reach (a seam of a third of it: the copy's error next to the source, 1-4 %, becomes a gradient error of a few %).
PATCH_FULL_SHARE = 2 / 3
#: The patch's faces are those within :data:`SOURCE_PATCH_EDGES` of the source by the copy's field (a round ball),
#: and within this many times that on the edge graph (a bound where several sources' balls meet).
PATCH_DETOUR = 1.5
#: ... and, where the mesh lies on the copy (every patch vertex within :data:`ON_COPY_EDGES` of the copy's mean edge
#: from it: the copy's geometry is the mesh's, and the patch adds resolution only), at most this share of the copy's
#: face count (both radii shrunk to fit). Measured 2026-12-07 (docs/dev/adapted-log.md, "A smaller patch where the
#: mesh lies on the copy"): fandisk at ``resolution=0.1`` (its 1,117 patch faces beside the copy's 1,295) 0.434 →
#: 0.439 % at 0.27 → 0.17 s; applied everywhere the cap cost camelhead_open and spot 12-13 % of their accuracy.
PATCH_MAX_SHARE = 0.25
#: See :data:`PATCH_MAX_SHARE`: the farthest vertex of a source's ball from the copy, in the copy's mean edges
#: (2026-12-07, from vertex 0 and n/2): on the CAD parts fandisk (at ``"auto"``, 0.1 and 0.05), thingi_37881 and
#: thingi_32770 0.002-0.027; on camelhead_open, spot, dragon_20k, buddha and lucy_20k 0.053-0.20.
ON_COPY_EDGES = 0.04
#: The copy's program is solved to this relative tolerance (or the solver's, when looser): the copy's field is
#: 0.2-2 % from the user's exact distances, so the last digits of the default 1e-8 bought nothing there. Measured
#: 2026-12-06 on 8 shared surfaces from vertex 0 and n/2 (docs/dev/adapted-log.md, "The copy's tolerance"): 3-5
#: fewer iterations, 3-12 % less time, the mean errors equal to 1e-4 of a point. 1e-4 saved more on the scans but
#: left fandisk's flat faces a violation that cost a cutting-plane round (21 → 28 iterations). The source patches
#: are solved to it too (fandisk, spot, bimba, armadillo, camelhead_open: the same mean and max errors to 4 digits,
#: the patches 15-25 % faster); a planar copy or patch (its field is exact: flat meshes stay exact to 1e-6) keeps the
#: solver's tolerance (:func:`_tol`).
COPY_TOL = 1e-5
#: ... and to this one where no face is flat (no face whose edge-neighbours lie in its plane, lone faces not counted):
#: there the order-2 solve has no cutting-plane round for a looser solve to trigger. Measured 2026-12-06 against 1e-5,
#: from vertex n/2: bunny, horse and armadillo 5-11 % faster (one iteration fewer), the mean errors 0.0002-0.0003
#: points higher (0.1966 → 0.1969 %, 0.1728 → 0.1730 %, 0.4390 → 0.4392 %); the point clouds of max_planck and kitten
#: at 0.1 % noise 2 and 1 iterations fewer, 0.621 → 0.623 % and 0.491 → 0.491 %. A copy with flat faces keeps 1e-5:
#: fandisk's clean cloud at 1e-4 took 32 iterations instead of 19 (a cutting-plane round).
CURVED_COPY_TOL = 1e-4
#: ... and to this one on the copy of a point cloud that is not clean
#: (:attr:`~cvxgeodesic.mesh.pointcloud.PointCloud.clean`), where no face is flat: its noise leaves a field 0.5-2 %
#: off. Measured 2026-12-07 at 0.1 % noise on kitten, bimba, max_planck, fandisk, bug_surface and dragon_20k
#: (docs/dev/adapted-log.md): 1-2 iterations fewer, 2.5-5 % less time, the mean errors within 1.5 % of themselves.
NOISY_CLOUD_COPY_TOL = 1e-3
#: A copy farther than this many of its mean edges from a point of the mesh is refused (:func:`_lost_surface`): on
#: the shared surfaces and their vertex clouds the farthest point lay 0.02-0.66 edges from the mesh's copy and
#: 0.21-3.75 from the cloud's; thingi_32770's cloud copy lost a part, 48 edges from 1,526 of its 18,944 points, which
#: read the field of another part (5.35 % mean error, against 2.14 % at order 1 and 0.10 % at order 2 on the surface
#: through the points).
MAX_GAP_EDGES = 10.0
#: The note of an adapted solve from ``"boundary"``: order 2 from a curve source runs short on a coarse copy. Measured
#: on camelhead_open (2026-12-06, docs/dev/adapted-log.md): the copy's exact distance read at the user's vertices is
#: 0.77 % off, order 2 on the copy 4.35 % off the copy's exact distance (too short everywhere, 8.5 % in the tenth
#: nearest the boundary), so the field is 3.9 % off against order 1's 0.86 % on the mesh.
BOUNDARY_NOTE = ("resolution={requested!r} from the boundary: order 2 from a curve source runs short on a coarse copy "
                 "(camelhead_open: 3.9 % mean error against 0.86 % at order 1 on the mesh, docs/adapted.md); order=1 "
                 "or resolution='mesh' is more accurate")
#: At most this many sources get a patch (each is an order-2 solve of its own).
MAX_SOURCE_PATCHES = 8
#: A point cloud's surface (:meth:`~cvxgeodesic.mesh.pointcloud.PointCloud.surface`) is decimated at this many targets
#: per aggressiveness: a noisy cloud's surface has handles and holes that no nearby target mends (at 0.3 % noise every
#: copy of kitten, bimba and max_planck was refused, and the 11 decimations tried cost 2-3x the point-cloud heat
#: method's time before the fallback to order 1: docs/pointclouds.md).
CLOUD_TARGETS = 1


def resolve_resolution(resolution: Any, n_faces: int) -> int | None:
    """The solve mesh's target face count for ``resolution``, or None to solve on the mesh itself.

    Parameters
    ----------
    resolution : "mesh", "auto", int or float
        ``"mesh"``: the mesh itself; an int >= :data:`MIN_RESOLUTION_FACES`: that many faces; a float in (0, 1):
        that fraction of the faces; ``"auto"``: :data:`AUTO_FRACTION` of the faces, at least :data:`AUTO_MIN_FACES`.
    n_faces : int
        The user's face count.

    Returns
    -------
    int or None
        None for ``"mesh"``; otherwise the target, which may be at or above ``n_faces`` (then the strategy solves
        on the mesh itself, with a note).

    Raises
    ------
    ParameterError
        Anything else (the message names ``resolution`` and what it takes).
    """
    if isinstance(resolution, str):
        key = resolution.strip().lower()
        if key == "mesh":
            return None
        if key == "auto":
            return max(AUTO_MIN_FACES, int(round(AUTO_FRACTION * n_faces)))
    elif isinstance(resolution, int | np.integer) and not isinstance(resolution, bool | np.bool_):
        if resolution >= MIN_RESOLUTION_FACES:
            return int(resolution)
    elif isinstance(resolution, float | np.floating) and 0 < resolution < 1:
        return max(MIN_RESOLUTION_FACES, int(round(float(resolution) * n_faces)))
    raise ParameterError(f"resolution must be 'mesh', 'auto', a face count >= {MIN_RESOLUTION_FACES} (int) or a "
                         f"fraction of the faces in (0, 1) (float), got {resolution!r}")


def resolution_targets(resolution: Any, mesh: SimplexMesh) -> tuple[int | None, int | None]:
    """The solve mesh's target face count for ``resolution`` on ``mesh`` (:func:`resolve_resolution`), and a coarser
    one to try where the copy at the first is refused, or None.

    ``"auto"`` on a clean point cloud (:attr:`~cvxgeodesic.mesh.pointcloud.PointCloud.clean`) targets
    :data:`CLEAN_CLOUD_FRACTION` of its faces first, then ``"auto"``'s own count; everything else has one target.

    Parameters
    ----------
    resolution : "mesh", "auto", int or float
    mesh : SimplexMesh
        The user's mesh (a point cloud's soup carries its cloud).

    Returns
    -------
    target, retry : int or None
    """
    target = resolve_resolution(resolution, mesh.n_cells)
    cloud = getattr(mesh, "cloud", None)
    auto = isinstance(resolution, str) and resolution.strip().lower() == "auto"
    if target is None or not auto or cloud is None or not cloud.clean:
        return target, None
    finer = max(AUTO_MIN_FACES, int(round(CLEAN_CLOUD_FRACTION * mesh.n_cells)))
    return (finer, target) if finer > target else (target, None)


def _decimation_source(mesh: TriMesh) -> tuple[TriMesh, str | None]:
    """The surface the copies are decimated from, and why there is none: the mesh itself, or for a point cloud's
    soup the surface through its points (:meth:`~cvxgeodesic.mesh.pointcloud.PointCloud.surface`; the answer is
    still read at every point of the cloud)."""
    if getattr(mesh, "domain", "surface") != "cloud":
        return mesh, None
    surface, why = mesh.cloud.surface()  # type: ignore[attr-defined]
    if surface is None:
        return mesh, f"no manifold surface through the points ({why})"
    return surface, None


def patch_reach(patch: Patch, distance: np.ndarray, edge_lengths: np.ndarray | None = None) -> float:
    """How far from its source a patch's field is the whole mesh's: below the least distance it gives a point of its
    cut.

    A shortest path of the whole mesh that leaves the patch crosses the cut first at a point ``x`` that it reached
    inside the patch, so the patch's distance at ``x`` is the whole mesh's. The patch's distance is never below the
    whole mesh's (it has fewer paths), so where it is below its least value on the cut the whole mesh's is too, and its
    shortest path never reached the cut: there the two are one field, whatever the shape of the patch. On a cut edge
    ``ab`` of length (travel time along it) ``ℓ`` the field, which changes by at most ``ℓ`` along it, is at least
    ``(d_a + d_b - ℓ) / 2``.

    Parameters
    ----------
    patch : Patch
        From :func:`~cvxgeodesic.mesh.patch.ball_patch`, with a mesh.
    distance : (p,) float ndarray
        The patch's field at its vertices.
    edge_lengths : (e,) float ndarray, optional
        The travel time along each edge of the patch's mesh (``mesh.edges``) with a cost or metric, at least the
        medium's distance between its ends (:attr:`~cvxgeodesic.operators.metric.Medium.edge_lengths` times its
        scale); default the Euclidean lengths.

    Returns
    -------
    float
        ``inf`` for a patch without a cut (its source's whole component).
    """
    if patch.cut.size == 0:
        return float("inf")
    mesh = patch.mesh
    assert mesh is not None
    d = np.asarray(distance, dtype=float)
    edges = mesh.boundary_facets  # the patch's rim: its cut, and the mesh's own boundary where they share an edge
    edges = edges[np.isin(edges, patch.cut).all(axis=1)]
    if edge_lengths is None:
        lengths = np.linalg.norm(mesh.V[edges[:, 0]] - mesh.V[edges[:, 1]], axis=1)
    else:  # both edge lists have sorted rows in lexicographic order: look the rim's up by key
        n = mesh.n_vertices
        keys = mesh.edges[:, 0] * n + mesh.edges[:, 1]
        lengths = np.asarray(edge_lengths, dtype=float)[np.searchsorted(keys, edges[:, 0] * n + edges[:, 1])]
    on_edges = (d[edges[:, 0]] + d[edges[:, 1]] - lengths) / 2
    return float(min(d[patch.cut].min(), on_edges.min(initial=np.inf)))


def _source_ball(copy: _Copy, center: int, radius: float, d: np.ndarray, reach_radius: float,
                 allowed: np.ndarray) -> Patch:
    """The source patch around vertex ``center`` of the user's mesh: the faces within ``reach_radius`` by the copy's
    field ``d`` (the least distance to any source: a round ball; ``allowed`` is ``d <= reach_radius``, made once for
    every source) and within :data:`PATCH_DETOUR` times ``radius`` on the edge graph. Where the mesh there lies on the
    copy (every vertex within :data:`ON_COPY_EDGES` of its mean edge) and the ball holds more than
    :data:`PATCH_MAX_SHARE` of the copy's faces, both radii shrink by the square root of the excess."""
    mesh = copy.user
    patch = ball_patch(mesh, center, PATCH_DETOUR * radius, allowed=allowed)
    max_faces = PATCH_MAX_SHARE * copy.mesh.n_faces
    if patch.mesh is None or patch.faces.size <= max_faces:
        return patch
    if copy.gap[patch.vertices].max() > ON_COPY_EDGES * copy.mesh.mean_edge_length:
        return patch
    shrink = float(np.sqrt(max_faces / patch.faces.size))
    return ball_patch(mesh, center, PATCH_DETOUR * radius * shrink, allowed=d <= reach_radius * shrink)


def _lost_surface(copy: _Copy) -> str | None:
    """Why the copy is refused although it passed the decimation's checks: a point of the mesh farther from it than
    :data:`MAX_GAP_EDGES` of its mean edges (part of the surface gone: its points would read the field of another part
    of the copy), or None."""
    edge = copy.mesh.mean_edge_length
    if copy.max_gap <= MAX_GAP_EDGES * edge:
        return None
    return (f"the decimated copy lost part of the surface (a point of the mesh lies {copy.max_gap / edge:.0f} of the "
            f"copy's mean edges from it)")


def _tol(config: SolveConfig, mesh: TriMesh) -> float:
    """The tolerance of an order-2 solve on a copy or a source patch: :data:`CURVED_COPY_TOL` where no face is flat
    (:data:`NOISY_CLOUD_COPY_TOL` for a point cloud that is not clean), else :data:`COPY_TOL`; ``tol=`` when looser or
    when ``mesh`` is planar (its field is exact there: flat meshes stay exact to 1e-6)."""
    if _is_planar(mesh):
        return config.tol
    joined = (mesh.edge_cell_counts[mesh.cell_edges] > 1).any(axis=1)  # a lone face (a cloud's copy has a few)
    flat = (LagrangeSpace(mesh, 1).flat_cells & joined).any()  # is flat whatever the surface: no flat region
    if flat:
        return max(config.tol, COPY_TOL)
    return max(config.tol, CURVED_COPY_TOL if _noisy_cloud(config.surface) is None else NOISY_CLOUD_COPY_TOL)


def _noisy_cloud(mesh: TriMesh) -> PointCloud | None:
    """The point cloud whose soup ``mesh`` is, where it is not clean
    (:attr:`~cvxgeodesic.mesh.pointcloud.PointCloud.clean`: its copy is solved looser and gets no source patch), or
    None (a mesh, or a clean cloud)."""
    cloud = getattr(mesh, "cloud", None)
    return None if cloud is None or cloud.clean else cloud


def _is_planar(mesh: TriMesh) -> bool:
    """Every proper face in one plane (|cos| ≥ :data:`~cvxgeodesic.operators.lagrange.FLAT_COS` between unit
    normals, the order-2 builder's flatness)."""
    N = mesh.face_normals_unnormalized
    length = np.linalg.norm(N, axis=1)
    proper = length > 0
    if not proper.any():
        return False
    unit = N[proper] / length[proper, None]
    return bool(np.all(np.abs(unit @ unit[0]) >= FLAT_COS))


def _medium_on(medium: Medium | None, mesh: TriMesh, coarse: TriMesh) -> Medium | None:
    """The user's medium moved to the solve mesh: per-vertex values at each coarse vertex's closest user point,
    per-face values of the user face closest to each coarse face's centroid (its normalization kept)."""
    if medium is None:
        return None
    index = closest_point_index(mesh)
    vf, vb, _ = index.query(np.ascontiguousarray(coarse.V))
    cf, _, _ = index.query(np.ascontiguousarray(coarse.V[coarse.F].mean(axis=1)))

    def moved(values: np.ndarray | None, kind: str | None) -> np.ndarray | None:
        if values is None or kind == "constant":
            return values
        if kind == "faces":
            return values[cf]
        return np.einsum("kc,kc...->k...", vb, values[mesh.F[vf]])

    try:
        return Medium(coarse, moved(medium.cost, medium.cost_kind), medium.cost_kind,
                      moved(medium.metric, medium.metric_kind), medium.metric_kind, scale=medium.scale)
    except ParameterError as exc:
        raise ParameterError(f"the metric moved to the {coarse.n_faces}-face solve mesh of resolution= is not "
                             f"positive definite there ({exc}); give resolution='mesh'") from None


def edge_shortening(mesh: TriMesh, positions: np.ndarray) -> float:
    """The error estimate of an adapted solve: how much shorter the user's edges are on the solve mesh.

    Each user edge ``(i, j)`` is compared with the segment between the closest points of its ends on the solve
    mesh: ``Σ (ℓ_ij − |p_i − p_j|) / Σ ℓ_ij`` over the edges: roughness below the solve mesh's scale. It follows
    the adapted error on scans, but it is not that error's cause: the solve mesh's own exact distances are longer
    than the user's there, and order 2 on it falls short of them (docs/dev/adapted-log.md, "A length correction").

    Parameters
    ----------
    mesh : TriMesh
        The user's mesh (``n`` vertices).
    positions : (n, 3) float ndarray
        The closest point of each user vertex on the solve mesh.

    Returns
    -------
    float
        A relative length (0 when the solve mesh is the user's).
    """
    E = mesh.edges
    ell = mesh.edge_lengths
    short = np.linalg.norm(positions[E[:, 0]] - positions[E[:, 1]], axis=1)
    total = float(ell.sum())
    return float(np.maximum(ell - short, 0.0).sum() / total) if total > 0 else 0.0


class _Copy:
    """One decimated copy of the user's mesh: its order-2 strategy and the user's vertices projected onto it.

    Parameters
    ----------
    config : SolveConfig
        The user's.
    coarse : TriMesh
        The copy (:func:`~.decimation._decimated_parts`).
    """

    def __init__(self, config: SolveConfig, coarse: TriMesh, part_of_face: np.ndarray | None = None) -> None:
        mesh = config.surface
        self.user, self.mesh = mesh, coarse
        self.part_of_face = part_of_face
        # a planar copy's field is exact (order 2 on flat faces): it keeps the solver's tolerance
        self.tol = _tol(config, coarse)
        self.strategy = Order2(replace(config.on(coarse, lam=config.lam), tol=self.tol,
                                       medium=_medium_on(config.medium, mesh, coarse)))
        self.vertex_faces, self.vertex_bary, self.gap = self.closest(np.ascontiguousarray(mesh.V),
                                                                    mesh.component_labels)
        self.max_gap = float(self.gap[mesh.referenced].max(initial=0.0))
        self.shortening = edge_shortening(mesh, bary_positions(coarse, self.vertex_faces, self.vertex_bary))

    def closest(self, X: np.ndarray, labels: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Closest face, barycentric coordinates and distance on the copy of each position ``X`` (k, 3), found on the
        copy of its own component of the user's mesh (``labels`` (k,)) when the components were decimated apart:
        two components near each other (a shell inside another) must not read each other's field. A position of no
        decimated component (an unreferenced vertex) gets face 0 and an infinite distance."""
        if self.part_of_face is None:
            return closest_point_index(self.mesh).query(X)
        faces, gap = np.zeros(len(X), dtype=np.int64), np.full(len(X), np.inf)
        bary = np.tile([1.0, 0.0, 0.0], (len(X), 1))
        for label, (ids, index) in self._part_indexes.items():
            inside = labels == label
            if inside.any():
                f, bary[inside], gap[inside] = index.query(X[inside])
                faces[inside] = ids[f]
        return faces, bary, gap

    @functools.cached_property
    def _part_indexes(self) -> dict[int, tuple[np.ndarray, Any]]:
        """Component label → (the copy's faces of that component, a closest-point index of them)."""
        assert self.part_of_face is not None
        out = {}
        for label in np.unique(self.part_of_face):
            ids = np.flatnonzero(self.part_of_face == label)
            out[int(label)] = (ids, closest_point_index(TriMesh(self.mesh.V, self.mesh.F[ids])))
        return out

    def sources(self, sources: SourceSet) -> tuple[SourceSet, float]:
        """The user's sources on the copy, at their positions, and the largest snap (:data:`SOURCE_SNAP`): vertices
        and points become the closest points there; the boundary stays the boundary (kept by the decimation)."""
        mesh, coarse = self.user, self.mesh
        if sources.boundary:
            return resolve_sources(coarse, "boundary"), 0.0
        given = sources.distinct_points(mesh)
        X = np.concatenate([mesh.V[sources.vertices], np.array([p.position(mesh) for p in given]).reshape(-1, 3)])
        at = np.concatenate([sources.vertices, [mesh.F[p.cell][0] for p in given]]).astype(np.int64)
        faces, bary, _ = self.closest(np.ascontiguousarray(X), mesh.component_labels[at])
        snapped = np.where(bary < SOURCE_SNAP, 0.0, bary)
        snapped /= snapped.sum(axis=1, keepdims=True)
        moved = np.linalg.norm(bary_positions(coarse, faces, snapped) - bary_positions(coarse, faces, bary), axis=1)
        points = [SurfacePoint(int(f), b) for f, b in zip(faces, snapped, strict=True)]
        return resolve_sources(coarse, points), float(moved.max(initial=0.0))

    def solve(self, sources: SourceSet, callback: Callback | None,
              requested: Any) -> tuple[GeodesicResult, np.ndarray, float, float]:
        """``(result on the copy, the field at the user's vertices, the sources' snap, seconds of the transfer)``;
        the field is 0 at source vertices, inf at vertices of no face.

        Raises
        ------
        SourceError
            Two sources in one face of the copy (order 2 takes one point per face), saying so.
        """
        csources, offset = self.sources(sources)
        try:
            cres = self.strategy.solve(csources, callback=callback)
        except SourceError as exc:
            raise SourceError(f"resolution={requested!r}: on the {self.mesh.n_faces}-face solve mesh, {exc}; give a "
                              "finer resolution or resolution='mesh'") from None
        t0 = time.perf_counter()
        d = np.asarray(cres.field.distance_at(self.vertex_faces, self.vertex_bary), dtype=float)
        d[sources.fixed_vertices(self.user)] = 0.0
        d[~self.user.referenced] = np.inf
        return cres, d, offset, time.perf_counter() - t0


def _relative_difference(a: np.ndarray, b: np.ndarray, fixed: np.ndarray) -> float:
    """Mean of ``|a − b| / b`` over the vertices where both are finite, ``b > 0``, and not in ``fixed``."""
    keep = np.isfinite(a) & np.isfinite(b) & (b > 0)
    keep[fixed] = False
    return float(np.mean(np.abs(a[keep] - b[keep]) / b[keep])) if keep.any() else 0.0


def _fallback(config: SolveConfig) -> tuple[Any, int]:
    """The strategy of a mesh that is not decimated, and its order: order 1 on the mesh (what an adapted solve
    costs; order 2 on the whole mesh costs 5-30x more), or order 2 where λ was given for order 2 (``lam=``)."""
    if config.energy is not None and config.lam > 0 and config.m is None:
        return Order2(config), 2
    lam = 0.0 if config.energy is None or not config.m else smoothness_weight(
        config.mesh, config.m, config.normalization, config.energy, medium=config.medium, order=1)
    return DirectStrategy(replace(config, lam=lam)), 1


class Adapted:
    """Order-2 solves on a decimated copy of a surface, answered on the surface itself.

    Parameters
    ----------
    config : SolveConfig
        The user's mesh and an order-2 method (:func:`~cvxgeodesic.capabilities.check` passed with
        ``resolution=True``; λ is order 2's).
    target : int or None
        The solve mesh's face count (:func:`resolve_resolution`); None or at least the mesh's face count: the mesh
        itself, with a note.
    requested : object
        The ``resolution`` the user gave (for the record).
    estimate : bool
        Estimate the error of every solve by two more solves, on a coarser and a finer copy (:data:`ESTIMATE_RATIO`,
        :data:`ESTIMATE_FINER`, :data:`ESTIMATE_FACTOR`).
    retry : int, optional
        A coarser target, tried where the copy at ``target`` is refused (a clean point cloud's ``"auto"``:
        :func:`resolution_targets`); the refused one is recorded as ``record["refused"]``, with a note.

    Attributes
    ----------
    solve_mesh : TriMesh
        The mesh the order-2 program is solved on (the user's after a fallback).
    copy : _Copy or None
        The solve mesh's copy.
    companions : list of _Copy
        The error estimate's coarser and finer copies (empty without an estimate).
    inner : Order2 or DirectStrategy
        The strategy on ``solve_mesh``.
    record : dict
        What ``info.extra["adapted"]`` reports for every solve (per-solve times are added).
    """

    def __init__(self, config: SolveConfig, target: int | None, requested: Any = None, *,
                 estimate: bool = True, retry: int | None = None) -> None:
        t0 = time.perf_counter()
        mesh = config.surface  # an adapted resolution: triangle surfaces only
        self.config = config
        self.requested = requested
        self.notes: list[str] = list(config.notes)
        self.record: dict[str, Any] = {"resolution": requested, "target_faces": target, "user_faces": mesh.n_faces,
                                       "faces": mesh.n_faces, "simplifier": None, "decimate_time": 0.0,
                                       "fallback": None, "refused": None, "order": 2, "error_estimate": None,
                                       "error_estimate_method": None}
        copy: _Copy | None = None
        components: int | None = None  # a mesh in several components, decimated one at a time: how many
        self.source, why = _decimation_source(mesh)
        self._targets = None if self.source is mesh else CLOUD_TARGETS
        self._aggs = RETRY_AGGS if self.source is mesh else CLOUD_AGGS
        # a cloud's surface: its faces by the piece of the cloud's triangles their points are in (the labels the
        # points read the copy by); a mesh: its own components
        self._face_label = (self.source.component_labels if self.source is mesh else mesh.component_labels)[
            self.source.F[:, 0]]
        if retry is not None and target is not None and target >= self.source.n_faces:
            target, retry = retry, None  # a clean cloud whose surface is smaller than its finer copy's target
        small = why is None and (target is None or target >= self.source.n_faces)
        if target is None or small:
            why = f"the target of {target} faces is not below the mesh's {self.source.n_faces}"
        elif why is None:
            why = _unsuitable(self.source)
            if why is None:
                if retry is not None:
                    noise = mesh.cloud.noise  # type: ignore[attr-defined]
                    self.notes.append(f"resolution={requested!r} on a clean point cloud (its noise {noise:.3f} of "
                                      f"the point spacing): a copy with {CLEAN_CLOUD_FRACTION:g} of the faces, not "
                                      f"{AUTO_FRACTION:g} (docs/pointclouds.md)")
                copy, why, components = self._copy(target)
                if copy is None and retry is not None:  # a clean cloud's finer copy: the usual one next
                    self.notes.append(f"resolution={requested!r}: the {target}-face copy was refused ({why}); "
                                      f"tried {retry} faces")
                    self.record["refused"] = {"target_faces": target, "why": why,
                                              "decimation_tries": self.record["decimation_tries"]}
                    self.record["target_faces"] = retry
                    copy, why, components = self._copy(retry)
        self.record["decimate_time"] = time.perf_counter() - t0
        self.copy: _Copy | None = None
        self.companions: list[_Copy] = []
        self.inner: Any
        if copy is None:
            self.solve_mesh = mesh
            # a small mesh is the solve mesh asked for; a mesh that cannot be decimated gets what a copy would cost
            self.inner, order = (Order2(config), 2) if small else _fallback(config)
            self.record.update(fallback=why, order=order, error_estimate_method="none: solved on the mesh itself")
            self.notes.append(f"resolution={requested!r}: solved on the mesh itself at order {order} ({why})")
        else:
            self.copy, coarse = copy, copy.mesh
            self.solve_mesh, self.inner = coarse, self.copy.strategy
            self.notes.append(f"resolution={requested!r}: solved at order 2 on a {coarse.n_faces}-face copy of the "
                              f"mesh ({mesh.n_faces} faces; {SIMPLIFIER}) to a relative tolerance of "
                              f"{self.copy.tol:g}, the field read at the mesh's vertices")
            if components is not None:
                self.notes.append(f"resolution={requested!r}: the mesh's {components} components were "
                                  f"decimated one at a time (those under {MIN_PART_FACES} faces of the target kept as "
                                  "they are), each vertex read on its own component's copy")
                self.record["components"] = components
            self.record.update(faces=coarse.n_faces, simplifier=SIMPLIFIER, max_surface_distance=self.copy.max_gap,
                               edge_shortening=self.copy.shortening, copy_tol=self.copy.tol)
            if estimate:
                self._companion(coarse.n_faces)
        self.ridge_length = self._ridge_length()
        self.backend = self.inner.backend
        self.setup_time = time.perf_counter() - t0

    def _copy(self, target: int) -> tuple[_Copy | None, str | None, int | None]:
        """The copy decimated from :attr:`source` to ``target`` faces (its decimation recorded), or None and why
        (every decimation refused, or the copy lost part of the surface: :func:`_lost_surface`); and the mesh's
        component count where they were decimated one at a time."""
        coarse, why, made = _decimated_parts(self.source, target, targets=self._targets, aggs=self._aggs,
                                             face_label=self._face_label)
        self._record_decimation(made, "")
        if coarse is None:
            return None, why, None
        copy = _Copy(self.config, coarse, made.get("part_of_face"))
        lost = _lost_surface(copy)
        return (None, lost, None) if lost is not None else (copy, None, made.get("components"))

    def _ridge_length(self) -> float | None:
        """The ridge rounding's length (:func:`~cvxgeodesic.problems.ridge_rounding.ridge_rounding_length` at ``m``),
        or None: a method without smoothing, ``m = 0``, or a fallback to the mesh itself (its own order-1 smoothing
        rounds the ridge). A smoothed order-2 method takes no medium (the capability table), so the field is of unit
        speed, as the rounding's ridge test assumes."""
        config = self.config
        if self.copy is None or config.energy is None or not config.m:
            self.record["ridge_rounding"] = None
            return None
        if self.source is not config.surface:  # a cloud: its soup's ridge is not rounded
            self.record["ridge_rounding"] = "none: a point cloud (the ridge of its triangle soup is not rounded)"
            return None
        length = ridge_rounding_length(config.surface, config.m)
        self.record["ridge_rounding"] = {"length": length}
        return length

    def _round_ridge(self, d: np.ndarray, sources: SourceSet, notes: list[str],
                     record: dict[str, Any]) -> np.ndarray | None:
        """``d`` with its ridge rounded in place (:attr:`ridge_length`), the correction (rounded minus transferred)
        returned; None without rounding."""
        if self.ridge_length is None:
            return None
        mesh = self.config.surface
        # the energy's rows are built on the faces near each solve's band (band_energy_rows): 0.05-0.14 s on bimba
        # and horse against 0.3-0.5 s for the whole mesh's energy
        rounded = round_ridge(mesh, d, sources.fixed_vertices(mesh), length=self.ridge_length)
        correction = np.where(np.isfinite(d), rounded.distance - d, 0.0)
        d[:] = rounded.distance
        notes += [*rounded.notes, f"the ridge rounded over {self.ridge_length:.3g} on the mesh "
                                  f"({int(rounded.band.sum())} vertices around the field's cut locus)"]
        record["ridge_rounding"] = {"length": self.ridge_length, "band_vertices": int(rounded.band.sum()),
                                    "time": rounded.time}
        return correction

    def _companion(self, faces: int) -> None:
        """The coarser and finer copies of the error estimate (none, with the reason, when a decimation fails)."""
        t0 = time.perf_counter()
        mesh = self.source
        # the solve copy's aggressiveness first: a companion folded where the copy is not would be an estimate of the
        # fold (bimba at 1/10: the agg-5 copy 0.33 % off, the agg-7 companion 1.58 %, the estimate 1.44 %)
        coarser, why, made = _decimated_parts(mesh, max(MIN_RESOLUTION_FACES, int(ESTIMATE_RATIO * faces)),
                                              self.record["agg"], self._targets, self._aggs,
                                              face_label=self._face_label)
        coarser_parts = made.get("part_of_face")
        self._record_decimation(made, "estimate_")
        finer: TriMesh | None = mesh
        fine_target, made = int(ESTIMATE_FINER * faces), {"tries": []}
        if coarser is not None and fine_target < mesh.n_faces:
            finer, why_fine, made = _decimated_parts(mesh, fine_target, self.record["agg"], self._targets, self._aggs,
                                                     face_label=self._face_label)
            why = None if finer is not None else f"the finer copy failed ({why_fine})"
        self._record_decimation(made, "estimate_fine_")
        self.record["decimate_time"] += time.perf_counter() - t0
        if coarser is None or finer is None:
            self.record["error_estimate_method"] = (f"none: the coarser copy failed ({why})" if coarser is None
                                                    else f"none: {why}")
            return
        # the mesh itself as the finer copy: read by component too when it has several (a point must not read a
        # neighbouring component's field)
        several = np.unique(self._face_label).size > 1
        finer_parts = (self._face_label if several else None) if finer is mesh else made.get("part_of_face")
        self.companions = [_Copy(self.config, coarser, coarser_parts), _Copy(self.config, finer, finer_parts)]
        self.record["estimate_faces"] = [coarser.n_faces, finer.n_faces]
        fine = "the mesh itself" if finer is mesh and mesh is self.config.surface else f"a {finer.n_faces}-face copy"
        self.record["error_estimate_method"] = (
            f"two resolutions around the solve's: {ESTIMATE_FACTOR:g} x the geometric mean of the mean relative "
            f"differences to the fields solved on a {coarser.n_faces}-face copy ({ESTIMATE_RATIO:g} of the solve "
            f"mesh's faces) and on {fine}")

    def _record_decimation(self, made: dict[str, Any], prefix: str) -> None:
        """``made`` (:func:`~.decimation._decimated_parts`) into the record (keys ``agg``, ``fold_angle``,
        ``decimation_tries``, with ``prefix``), and a note when the copy is not the first decimation's or is folded."""
        tries = made["tries"]
        self.record[prefix + "decimation_tries"] = [{"agg": a, "target": t, "outcome": o} for a, t, o in tries]
        self.record[prefix + "agg"] = made.get("agg")
        self.record[prefix + "fold_angle"] = made.get("fold_angle")
        what = "the error estimate's copy" if prefix else "the solve mesh"
        if made.get("folded"):
            self.notes.append(f"resolution={self.requested!r}: every copy for {what} is folded (an edge turns "
                              f"{made['fold_angle']:.0f} deg, the mesh at most {made['mesh_turn']:.0f}); the least "
                              f"folded is used (aggressiveness {made['agg']:g})")
        elif made.get("agg") is not None and (refused := [o for _, _, o in tries if not o.endswith("kept")]):
            summary = "; ".join(f"{refused.count(o)}x {o}" for o in dict.fromkeys(refused))
            # several components: a try per component kept, each at its own target
            kept = "" if "part_of_face" in made else f"; kept aggressiveness {made['agg']:g}, {tries[-1][1]} faces"
            self.notes.append(f"resolution={self.requested!r}: {what} was decimated {len(tries)} times "
                              f"({summary}){kept}")

    def solve(self, sources: SourceSet, *, callback: Callback | None = None) -> GeodesicResult:
        """Distance field on the user's mesh from sources resolved on it.

        Raises
        ------
        SourceError
            Two sources that fall into one face of the solve mesh (order 2 takes one point per face).
        """
        if self.copy is None:
            res = self.inner.solve(sources, callback=callback)
            res.info.notes.insert(len(self.config.notes), self.notes[len(self.config.notes)])  # the fallback's note
            res.info.extra["adapted"] = {**self.record, "solve_time": res.info.solve_time, "transfer_time": 0.0}
            return res
        t0 = time.perf_counter()
        cres, d, offset, transfer = self.copy.solve(sources, callback, self.requested)
        t1 = time.perf_counter()
        notes = [*self.notes, *cres.info.notes]
        patches = self._source_patches(sources, d, notes)
        n = self.config.mesh.n_vertices
        nears = [p.at_vertices(n) for p in patches]
        d = mix_patches(d, patches, nears)
        record = {**self.record, "solve_time": t1 - t0 - transfer, "transfer_time": transfer,
                  "source_offset": offset, "source_patches": len(patches),
                  "source_patch_faces": [int(np.count_nonzero(p.face_map >= 0)) for p in patches],
                  "source_patch_time": time.perf_counter() - t1}
        if offset > 1e-12 * self.config.mesh.bbox_diagonal:
            notes.append(f"a source within {SOURCE_SNAP:g} of a face's altitude from an edge of the solve mesh was "
                         f"moved onto it (by {offset:.3g})")
        if sources.boundary:
            notes.append(BOUNDARY_NOTE.format(requested=self.requested))
        t_envelope = time.perf_counter()
        lowered = self._cloud_envelope(d)
        if lowered is not None:
            self._record_envelope(lowered, time.perf_counter() - t_envelope, notes, record)
            d = d + lowered
        if self.companions:  # of the order-2 field, before the rounding
            t2 = time.perf_counter()
            self._estimate(sources, d, patches, nears, record)
            record["estimate_time"] = time.perf_counter() - t2
        correction = self._round_ridge(d, sources, notes, record)
        if lowered is not None:
            correction = lowered if correction is None else correction + lowered
        return self._result(cres, d, sources, notes, record, t0, patches, correction)

    def _cloud_envelope(self, d: np.ndarray) -> np.ndarray | None:
        """On a point cloud, how far the transferred field ``d`` drops to its envelope along the cloud's own
        triangles' edges (:func:`~cvxgeodesic.mesh.envelope.lipschitz_envelope`, ≤ 0, 0 where ``d`` is not finite);
        None on a mesh.

        The copy is decimated from the surface through the points, which leaves out the triangles the fans disagree
        on: its field goes around those holes, which the cloud's triangles close. Measured 2026-12-06 (one thread;
        docs/dev/adapted-log.md, "The cloud envelope") on the vertex clouds of kitten, bimba, max_planck and fandisk
        at 0, 0.1 and 0.3 % noise from vertex 0 and n/2, and 1,500 points of a sphere: of the 19 solved on a copy,
        14 more accurate (clean fandisk from 0 4.41 → 1.53 % mean error, at 0.1 % noise 2.43 → 1.49 %; max_planck
        0.71 → 0.51 %; the sphere's max error 10 → 2.7 %), 2 equal, 5 less (by 1-11 %: fandisk at 0.1 % from n/2
        3.35 → 3.73 %, max_planck from n/2 0.47 → 0.52 %), where the fans' chords cut across a corner or a thin
        wall. Lowering only the drops above 0.5-1.5 edges kept neither side whole. 1-7 ms.
        """
        if self.source is self.config.surface:
            return None
        drop = np.zeros_like(d)
        finite = np.isfinite(d)  # an unreached point stays unreached (inf - inf is no drop)
        drop[finite] = lipschitz_envelope(self.config.surface, d)[finite] - d[finite]
        return drop

    @staticmethod
    def _record_envelope(lowered: np.ndarray, seconds: float, notes: list[str], record: dict[str, Any]) -> None:
        """What :meth:`_cloud_envelope` lowered, into the solve's record and, where it lowered a point, its notes."""
        count = int(np.count_nonzero(lowered < 0))
        record["cloud_envelope"] = {"points": count, "max_lowered": float(-lowered.min(initial=0.0)), "time": seconds}
        if count:
            notes.append(f"{count} point(s) lowered to the least distance over the cloud's triangle edges (the "
                         f"surface through the points, which the copy is decimated from, has holes there; by at "
                         f"most {-lowered.min():.3g})")

    def _estimate(self, sources: SourceSet, d: np.ndarray, patches: list[SourcePatch], nears: list[np.ndarray],
                  record: dict[str, Any]) -> None:
        """The error estimate into ``record``: :data:`ESTIMATE_FACTOR` times the geometric mean of the mean relative
        differences of the companions' fields to ``d`` (``estimate_differences``: coarser, finer)."""
        fixed = sources.fixed_vertices(self.config.mesh)
        diffs = []
        for which, companion in zip(("coarser", "finer"), self.companions, strict=True):
            try:
                _, dc, _, _ = companion.solve(sources, None, self.requested)
            except SourceError as exc:
                record["error_estimate_method"] = f"none: the {which} copy took not the sources ({exc})"
                return
            dc = mix_patches(dc, patches, nears)  # the same near the sources: the estimate is of the rest
            envelope = self._cloud_envelope(dc)
            if envelope is not None:
                dc = dc + envelope
            diffs.append(_relative_difference(dc, d, fixed))
        record["estimate_differences"] = diffs
        record["error_estimate"] = ESTIMATE_FACTOR * float(np.sqrt(diffs[0] * diffs[1]))

    def _source_patches(self, sources: SourceSet, d: np.ndarray, notes: list[str]) -> list[SourcePatch]:
        """The order-2 fields on the user's mesh around each source (:data:`SOURCE_PATCH_EDGES`)."""
        mesh = self.config.surface
        if SOURCE_PATCH_EDGES <= 0 or sources.boundary or self.copy is None:
            return []
        if (cloud := _noisy_cloud(mesh)) is not None:
            notes.append(f"no patch solve around the sources: a noisy point cloud (its noise {cloud.noise:.3f} of the "
                         "point spacing), whose own triangles read the noise as length at order 2")
            return []
        items: list[tuple[int, Any]] = [(int(v), None) for v in sources.vertices]
        items += [(int(mesh.F[p.cell][np.argmax(p.bary)]), p) for p in sources.distinct_points(mesh)]
        if len(items) > MAX_SOURCE_PATCHES:
            notes.append(f"{len(items)} sources: no patch solve around them (at most {MAX_SOURCE_PATCHES})")
            return []
        radius = SOURCE_PATCH_EDGES * self.copy.mesh.mean_edge_length
        copy_medium = self.copy.strategy.config.medium  # the field's units: travel time with a cost or metric
        reach_radius = radius if copy_medium is None else SOURCE_PATCH_EDGES * copy_medium.mean_edge_length
        allowed = d <= reach_radius  # every source's ball by the copy's field (the least distance to any source)
        out = []
        for center, point in items:
            patch = _source_ball(self.copy, center, radius, d, reach_radius, allowed)
            if patch.mesh is None:
                continue
            face_map = np.full(mesh.n_faces, -1, dtype=np.int64)
            face_map[patch.faces] = np.arange(patch.faces.size)
            src = patch.source if point is None else SurfacePoint(int(face_map[point.cell]), point.bary)
            try:
                medium = None if self.config.medium is None else self.config.medium.subset(
                    patch.mesh, patch.vertices, patch.faces)
                res = Order2(replace(self.config.on(patch.mesh, lam=self.config.lam), tol=_tol(self.config, patch.mesh),
                                     medium=medium)).solve(resolve_sources(patch.mesh, src))
            except (SolverError, SourceError, MeshError, ParameterError) as exc:  # the copy's field stays
                notes.append(f"the patch solve around source vertex {center} failed ({exc}); the copy's field kept")
                continue
            reach = patch_reach(patch, res.field.vertex_distance,
                                None if medium is None else medium.edge_lengths * medium.scale)
            if not reach > 0:  # the source on the cut: no room to mix it in
                notes.append(f"the patch around source vertex {center} touches its own cut; the copy's field kept")
                continue
            out.append((face_map, patch.vertices, res.field, reach))
        if not out:
            return []
        # one reach for all: where a patch's field is mixed in fully, so is that of any source nearer there
        reach = min(r for *_, r in out)
        notes.append(f"{len(out)} patch(es) of the mesh around the sources solved at order 2 and mixed in within "
                     f"{reach:.3g} of them")
        return [SourcePatch(*p[:3], PATCH_FULL_SHARE * reach, reach) for p in out]

    def _result(self, cres: GeodesicResult, d: np.ndarray, sources: SourceSet, notes: list[str], record: dict,
                t0: float, patches: list[SourcePatch], correction: np.ndarray | None) -> GeodesicResult:
        ci = cres.info
        assert self.copy is not None
        extra = dict(ci.extra, adapted=record, solve_mesh=self.solve_mesh)
        field = ProjectedField(self.config.surface, self.solve_mesh, cres.field, d, patches, medium=self.config.medium,
                               correction=correction, closest=self.copy.closest)
        info = replace(ci, setup_time=self.setup_time, solve_time=time.perf_counter() - t0,
                       n_unreachable=int(np.isinf(d).sum()), notes=notes, extra=extra)
        return GeodesicResult(distance=d, info=info, sources=sources.vertices, field=field,
                              source_set=None if sources.vertex_only else sources)
