"""Point clouds: raw points (no faces) solved on the triangles of their local Delaunay fans.

:class:`PointCloud` validates the points (finite, at least four, not all on a line; exact duplicates merged with a
note; isolated outliers and points of line-like neighbourhoods left out with a note, :mod:`.cloud_outliers`, a
solve's field carried to them from their neighbours, :meth:`PointCloud.reach_left_out`) and
builds a triangle soup from ``potpourri3d.PointCloudLocalTriangulation``: for every point, the fan of triangles
around it in its tangent plane (its ``neighbours`` nearest points, Delaunay in the plane fitted to them). The soup
is a :class:`CloudMesh`, a :class:`~cvxgeodesic.mesh.trimesh.TriMesh` that remembers its cloud, so every function
that takes a mesh takes the cloud (``mesh/convert.as_mesh``) and returns one value per point. The convex
formulations accept the non-manifold soup as it is (one cone per triangle). docs/pointclouds.md has the choices and
their measured errors.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..errors import MeshError, ParameterError, SourceError
from ..validation import as_points
from .cloud_outliers import DEFECT_NEIGHBOURS, CloudDefects, find_defects, nearest_neighbours
from .cloud_tilt import (
    TILT_ANGLE,
    TILT_NEIGHBOURS,
    principal_planes,
    stranded_points,
    triangle_components,
    untilted_fans,
)
from .denoise import DENOISE_PASSES, denoise_passes, denoised_with_note, jet_noise
from .frames import plane_fits, scatter_matrices, tangent_frames
from .simplex import unique_rows
from .trimesh import TriMesh

__all__ = ["AUTO_DENOISE_MIN_POINTS", "AUTO_NOISE_MAX", "CLEAN_NOISE_MAX", "DETAIL_GROWTH", "NORMAL_FAN_ANGLE",
           "OUTLIER_HANDLING", "TRIANGLE_SETS", "CloudMesh", "PointCloud", "fan_triangles", "local_fans", "normal_fans",
           "triangle_set"]

#: The triangle sets a cloud can be solved on (docs/pointclouds.md has their measured errors):
#: ``"union"`` every triangle of every fan; ``"consensus"`` the triangles that appear in at least two fans;
#: ``"repaired"`` the consensus plus, for every point that the consensus leaves outside the largest component it
#: reaches in the union, the union's triangles of its fan (so no point becomes unreachable).
TRIANGLE_SETS = ("union", "consensus", "repaired")
DEFAULT_NEIGHBOURS = 30
#: The fans are chosen on the points moved by this fraction of their mean spacing (:func:`_tie_broken`), so that
#: cocircular neighbours (a grid) are triangulated alike in every fan.
TIE_JITTER = 1e-7
#: A fan triangle whose smallest altitude is below this fraction of its longest edge is dropped: its points are on a
#: line to rounding (altitude = twice the area over the longest edge).
FLAT_TRIANGLE = 1e-9
#: Fewer neighbours than this leave most fans open (benchmarks/point_clouds.py --neighbours: at 8 a cloud of irregular
#: spacing already loses accuracy).
MIN_NEIGHBOURS = 4
#: docs/pointclouds.md: the repaired consensus has the lower mean error on clean and on unevenly sampled clouds (up to
#: 1.5× at order 2) but leaves holes where the fans disagree (max error up to 4.5× the union's on a sphere's cloud);
#: the union has the lower mean error on noisy evenly sampled clouds (up to 1.5×) and no holes.
DEFAULT_TRIANGLES = "union"
#: The default solve of a cloud (order 2 on a decimated copy, ``resolution="auto"``) applies up to this noise, in
#: units of the point spacing (:func:`~cvxgeodesic.mesh.denoise.jet_noise`; about 0.55 of the noise's standard
#: deviation over the spacing); a noisier cloud is solved at order 1 on its own triangles. Measured 2026-12-06 on the
#: vertex clouds of kitten, bimba, max_planck, fandisk and dragon_20k at 0.1-0.3 % noise (docs/pointclouds.md, "Which
#: to use"): the copy's field was more accurate than order 1 up to 0.071 (bimba at 0.1 %), less accurate on max_planck
#: at 0.2 % (0.079: 1.0-1.8 % against 1.1-1.3 %) and above, equal on kitten and dragon at 0.2 % (0.087, 0.099).
AUTO_NOISE_MAX = 0.075
#: ... unless the jets' distance grows by this much or more from 12 to 30 neighbours: detail finer than the
#: neighbourhood, which the copy follows (clean lucy_20k and buddha read 0.116 and 0.098, growing 2.7× and 2.2×: the
#: copy 3.23 % and 5.06 % against order 1's 4.85 % and 8.45 %; buddha at 0.1 % noise grew 2.0×, the copy 5.15 %
#: against 10.0 %). The scans and the CAD part with noise grew 1.2-1.6×; lucy_20k and thingi_32770 at 0.3 % noise
#: 1.7-1.87×, where the copy lost (7.39 % against 6.99 %, 12.1 % against 7.0 %).
DETAIL_GROWTH = 1.9
#: A cloud whose noise reads at most this is clean (:attr:`PointCloud.clean`): its default copy is finer
#: (:data:`~cvxgeodesic.strategies.adapted.CLEAN_CLOUD_FRACTION`). Read 2026-12-07 (docs/pointclouds.md, "The copy of
#: a clean cloud"): the vertex clouds of 13 shared meshes 0.000-0.024 but dragon_20k 0.035, lucy_20k 0.118 and buddha
#: 0.098 (detail, which grows 2.2-2.6× from 12 to 30 neighbours: telling it apart would cost a second reading, 23 ms
#: on max_planck, a fifth of the point-cloud heat method's time), their random surface points 0.001-0.027 (the two
#: statues' 0.046-0.091); at 0.05 % noise of the diagonal 0.025-0.125, at 0.1 % 0.041-0.176.
CLEAN_NOISE_MAX = 0.03
#: ``denoise="auto"`` (the default) takes :data:`~cvxgeodesic.mesh.denoise.DENOISE_PASSES` where the noise rule
#: would leave the default at order 1 on the cloud's triangles (:data:`AUTO_NOISE_MAX`, :data:`DETAIL_GROWTH`), the
#: cloud has at least this many points and no oriented normals shape its fans (the jets do not read them, and a gap
#: thinner than a spacing, which the normals keep open, reads as noise: the jets would join its sides). The default
#: is then order 2 on a copy of the surface through the moved points. Measured 2026-12-07 (docs/pointclouds.md,
#: "Noise and the default"; docs/dev/adapted-log.md, "The noisy default on the denoised cloud"): on the benchmark's
#: noisy vertex clouds of eight scans and CAD parts it took the default from 0.21-0.63 of the point-cloud heat
#: method's error to 0.088-0.46 (the statues lost 10-19 %); below 6,000 points the denoised copy, at the copy's floor
#: of 2,000 faces (AUTO_MIN_FACES), took 2.8-4.4x that method's time (a scratch script).
AUTO_DENOISE_MIN_POINTS = 6000
#: With oriented normals, a point's fan leaves out the neighbours whose normal turns from its own by more than this
#: many degrees: the other side of a thin wall, the other face of a sharp crease (docs/pointclouds.md, "Normals":
#: fandisk's order-2 field 3.34 -> 0.052 % with the mesh's vertex normals; 45 degrees cut points off, 75 the same
#: as 60).
NORMAL_FAN_ANGLE = 60.0
#: Before the test, each normal is averaged with those of its nearest neighbours, this many: a sampled crease whose
#: two faces carry their own normals is bridged by the points next to it (fandisk's points sampled on its faces, with
#: the faces' normals: 9,817 of 12,946 points cut off unaveraged, none with 6, order 2 2.23 -> 0.84 %).
NORMAL_SMOOTHING_NEIGHBOURS = 6
#: Normals are taken as unoriented (and not used for the fans, with a note) where more than this fraction of the
#: pairs of a point and one of its :data:`NORMAL_SMOOTHING_NEIGHBOURS` nearest neighbours point apart (a negative dot
#: product): about half with random signs, almost none for oriented normals (so few neighbours reach across a wall
#: only where it is thinner than about one spacing).
UNORIENTED_FRACTION = 0.1
#: ... counting only the pairs within this many degrees of the point's tangent plane (all pairs where fewer than a
#: quarter are): across a gap thinner than a spacing (facing sheets: the statues' folds and closed lips) neighbours
#: lie off that plane and point apart on oriented clouds too. lucy_20k's vertex normals read 11.1 % apart over every
#: pair and were refused, 1.8 % so; random signs read 49-50 % so on the 13 shared scans and CAD parts; the normals
#: of a box 0.26-0.6 spacings thick are kept (at 30 degrees, 0.42 spacings read 23 % and were refused).
TANGENT_PAIR_ANGLE = 10.0
#: ... and a normal is averaged only with those that turn from it by less than this many degrees: the other side of a
#: gap thinner than a spacing faces it, and the mean of the two is no normal of either.
NORMAL_SMOOTHING_ANGLE = 120.0
#: With normals, a group of at most this many points that the normals cut off from the rest gets its whole fans back
#: (three points of buddha's vertex cloud, on a sheet thinner than a spacing whose 7 nearest neighbours lie on the
#: facing side, made a triangle of their own: unreachable); a larger group is a surface of its own (a plate facing
#: another within a spacing) and stays apart. A neighbourhood's size, as for groups of outliers.
CUT_OFF_MAX = 30
#: :meth:`PointCloud.surface` drops the pieces that break off the consensus surface while they hold at most this
#: fraction of its triangles (noise of 0.1 % of the diagonal broke 2-8 small pieces off kitten, bimba and max_planck;
#: at 0.3 % the consensus falls apart: docs/pointclouds.md, "Order 2 on a surface through the points").
SURFACE_FRAGMENTS = 0.05
#: A cloud whose second principal extent is below this fraction of its first lies on a line.
COLLINEAR_TOL = 1e-9
#: What a cloud does with its isolated outliers and points of line-like neighbourhoods
#: (:func:`~cvxgeodesic.mesh.cloud_outliers.find_defects`): ``"exclude"`` leaves them out of the fans (their neighbours'
#: fans are built without them; a solve carries the field to them, :meth:`PointCloud.reach_left_out`; a note names
#: them); ``"keep"`` triangulates every point
#: (no detection); ``"error"`` refuses the cloud naming them.
OUTLIER_HANDLING = ("exclude", "keep", "error")
DEFAULT_OUTLIERS = "exclude"
#: A point that :func:`~cvxgeodesic.mesh.cloud_outliers.find_defects` flags as an outlier is kept when it lies closer
#: than this fraction of its mean distance to its 30 nearest to the fans of the other points (the surface they
#: sample). Measured on the shared clouds: outliers planted 5 spacings off and more, at least 0.80; the points it
#: flagged on the clean scans (in sparse regions: horse, lucy_20k, the CAD part thingi_32770) 0.01-0.99, most below
#: 0.75.
ON_SURFACE = 0.75


class CloudMesh(TriMesh):
    """The triangle soup of a :class:`PointCloud` (its vertices are the cloud's points, in the same order).

    A :class:`TriMesh` with one more attribute, :attr:`cloud`, and its own domain, ``"cloud"``: the capability
    table's rules of that domain refuse the methods and sources that need a manifold surface
    (:data:`cvxgeodesic.capabilities.RULES`).
    """

    domain = "cloud"
    cloud: PointCloud

    def check_source_vertices(self, vertices: np.ndarray) -> None:
        """The cloud's outliers and line points are no sources (:meth:`PointCloud.check_sources`)."""
        self.cloud.check_sources(vertices)


def fan_triangles(P: np.ndarray, neighbours: int,
                  normals: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Every fan triangle of the cloud's local triangulation, and the point whose fan it is in.

    At the default 30 neighbours, ``potpourri3d.PointCloudLocalTriangulation`` (geometry-central); at another count,
    which potpourri3d 1.4 does not take, :func:`local_fans`, the same construction in numpy; with oriented normals,
    :func:`normal_fans`. Each chooses on the points moved alike by :data:`TIE_JITTER` of about their spacing
    (:func:`_tie_broken`: a grid's cocircular squares get one diagonal in every fan), and the triangles of three
    points on a line (:data:`FLAT_TRIANGLE`) are dropped.

    Parameters
    ----------
    P : (n, 3) float ndarray
    neighbours : int
        Points in each local neighbourhood, below ``n``.
    normals : (n, 3) float ndarray, optional
        Unit normals, oriented consistently.

    Returns
    -------
    tri : (k, 3) int64 ndarray
        Point indices (global), each row sorted (so that a triangle of several fans has one spelling).
    owner : (k,) int64 ndarray
        The point whose fan holds it (row ``i`` of the library's ``(n, max_neighbours, 3)`` array, padded with -1).
    """
    import potpourri3d as pp3d

    Q = _tie_broken(P)
    if normals is not None:
        tri, owner = normal_fans(Q, normals, neighbours)
    elif neighbours != DEFAULT_NEIGHBOURS:  # geometry-central's k; potpourri3d 1.4 does not pass another one
        tri, owner = local_fans(Q, neighbours)
    else:
        fans = np.asarray(pp3d.PointCloudLocalTriangulation(Q).get_local_triangulation(), dtype=np.int64)
        owner = np.repeat(np.arange(fans.shape[0]), fans.shape[1])
        flat = fans.reshape(-1, 3)
        keep = (flat >= 0).all(axis=1)
        tri, owner = np.sort(flat[keep], axis=1), owner[keep]
    solid = ~_flat_triangles(P, tri)
    return tri[solid], owner[solid]


def _tie_broken(P: np.ndarray) -> np.ndarray:
    """``P`` moved by a fixed pseudo-random :data:`TIE_JITTER` of about its spacing (the bounding box's diagonal over
    the square root of the point count), for the fans' Delaunay choices only.

    On a regular grid every square's corners are cocircular, and fans that picked its two diagonals differently
    overlapped and left the consensus in pieces (a 30 x 30 grid: 28; the default solve fell back to order 1, 0.033 max
    error where order 2 is exact). The same move in every fan makes their choices agree. Measured 2026-12-07 on the
    vertex clouds of kitten, bimba and fandisk, clean and at 0.1 % noise: the same triangles, but for clean fandisk
    (a CAD part's regular rows: 224 of its 38,383 changed; its default's error from vertex 0 and n/2 1.453 / 0.681 %
    → 1.444 / 0.655 %).
    """
    span = float(np.linalg.norm(P.max(axis=0) - P.min(axis=0)))
    jitter = np.random.default_rng(0).uniform(-1.0, 1.0, P.shape)
    return np.ascontiguousarray(P + jitter * (TIE_JITTER * span / np.sqrt(P.shape[0])))


def _flat_triangles(P: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """(k,) bool: the triangles ``tri`` of ``P`` whose smallest altitude is below :data:`FLAT_TRIANGLE` of their
    longest edge: three points on a line (a grid's border row, which the tie-breaking move turns into a sliver)."""
    A = P[tri[:, 0]]
    AB, AC = P[tri[:, 1]] - A, P[tri[:, 2]] - A
    cross = np.cross(AB, AC)
    BC = AC - AB
    longest2 = np.maximum(np.maximum(np.einsum("ij,ij->i", AB, AB), np.einsum("ij,ij->i", AC, AC)),
                          np.einsum("ij,ij->i", BC, BC))
    return np.einsum("ij,ij->i", cross, cross) <= FLAT_TRIANGLE**2 * longest2**2  # squared: no roots


def local_fans(P: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """The fans of every point among its ``k`` nearest neighbours, as :func:`fan_triangles` returns them.

    A point's fan is its 1-ring in the Delaunay triangulation of its neighbours projected on their principal plane.
    Inverted about the point (``w = q / |q|²``), a circle through the point becomes a line, so its Delaunay
    neighbours are the corners of the convex hull of the inverted neighbours and the point itself, and its triangles
    the hull's edges that do not touch it: one gift-wrapping march over all points at once. At ``k = 30`` it builds
    potpourri3d's triangles on evenly sampled clouds (99.95 % of kitten's); on uneven ones 85–91 % of them (its
    tangent planes and degeneracy heuristic differ).

    Parameters
    ----------
    P : (n, 3) float ndarray
    k : int
        Neighbours of each point, ``0 < k < n``.

    Returns
    -------
    tri : (m, 3) int64 ndarray
        Point indices, each row sorted.
    owner : (m,) int64 ndarray
        The point whose fan holds each triangle.
    """
    from scipy.spatial import cKDTree

    idx = cKDTree(P).query(P, k=k + 1)[1]  # column 0: the point itself
    return _fans(_tangent_coordinates(P, idx), idx)


def normal_fans(P: np.ndarray, N: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """:func:`local_fans` in the tangent planes of oriented normals, without the neighbours whose normal turns by more
    than :data:`NORMAL_FAN_ANGLE` from the point's (the other side of a thin wall or of a sharp crease).

    A point whose fan is then empty gets its fan of :func:`local_fans` back, and the points of a group of at most
    :data:`CUT_OFF_MAX` that the left-out neighbours cut off from the piece their whole fans reach
    (:func:`~cvxgeodesic.mesh.cloud_tilt.stranded_points`: a few points of a thin sheet whose nearest neighbours all
    lie on its facing side) get their whole fans in their normals' planes back.

    Parameters
    ----------
    P : (n, 3) float ndarray
    N : (n, 3) float ndarray
        Unit normals, oriented consistently.
    k : int
        Neighbours of each point, ``0 < k < n``.

    Returns
    -------
    tri, owner
        As :func:`local_fans`.
    """
    from scipy.spatial import cKDTree

    idx = cKDTree(P).query(P, k=k + 1)[1]
    frame = tangent_frames(N)[:, :, 1:]  # (n, 3, 2): the normal's plane
    uv = np.einsum("nki,nij->nkj", P[idx] - P[:, None, :], frame)
    turned = np.einsum("nki,ni->nk", N[idx], N) < np.cos(np.radians(NORMAL_FAN_ANGLE))
    tri, owner = _fans(uv, idx, turned)
    empty = np.setdiff1d(np.arange(P.shape[0]), owner)
    if empty.size:  # their fans of local_fans, from the same neighbours
        tri0, owner0 = _fans(_tangent_coordinates(P, idx[empty]), idx[empty])
        tri, owner = np.concatenate([tri, tri0]), np.concatenate([owner, owner0])
    labels = triangle_components(P.shape[0], tri)
    apart = np.flatnonzero(np.bincount(labels)[labels] <= CUT_OFF_MAX)  # a facing sheet of its own is left apart
    if apart.size:
        whole, whole_owner = _fans(uv[apart], idx[apart])
        stranded = np.intersect1d(stranded_points(P.shape[0], np.concatenate([tri, whole]), tri), apart)
        back, mine = np.isin(whole_owner, stranded), ~np.isin(owner, stranded)
        tri, owner = np.concatenate([tri[mine], whole[back]]), np.concatenate([owner[mine], whole_owner[back]])
    return tri, owner


def _fans(uv: np.ndarray, idx: np.ndarray, left_out: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The fans of the points whose neighbours ``idx`` (r, k + 1; column 0 the point itself) lie at ``uv``
    (r, k + 1, 2) in their tangent planes; ``left_out`` (r, k + 1) bool: neighbours in no triangle of that fan. Any
    rows of the cloud's: the owners are the points ``idx[:, 0]``."""
    r2 = np.einsum("nkj,nkj->nk", uv, uv)
    r2[:, 0] = 1.0
    W = uv / r2[..., None]
    W[:, 0] = 0.0  # the point itself, a corner of the hull when it lies on the cloud's border
    hull = np.full((W.shape[0], W.shape[1] + 2), -1)
    marched = np.arange(W.shape[0])
    if left_out is not None:
        W[left_out] = 0.0  # on the point itself: never a corner but on the border, where the test below drops it
        marched = np.flatnonzero((~left_out[:, 1:]).sum(axis=1) >= 2)  # fewer neighbours make no triangle
    hull[marched] = _hull_march(W[marched])
    a, b = hull[:, :-1], hull[:, 1:]
    row, t = np.nonzero((a > 0) & (b > 0) & (a != b))  # hull edges that do not touch the point
    A, B = a[row, t], b[row, t]
    if left_out is not None:
        kept = ~left_out[row, A] & ~left_out[row, B]
        row, A, B = row[kept], A[kept], B[kept]
    ua, ub = uv[row, A], uv[row, B]
    flat = np.abs(ua[:, 0] * ub[:, 1] - ua[:, 1] * ub[:, 0]) <= 1e-12 * np.sqrt(r2[row, A] * r2[row, B])
    row, A, B = row[~flat], A[~flat], B[~flat]
    tri = np.stack([idx[row, 0], idx[row, A], idx[row, B]], axis=1)
    return np.sort(tri, axis=1).astype(np.int64), idx[row, 0].astype(np.int64)


def _tangent_coordinates(P: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """(r, k + 1, 2): the neighbours ``P[idx]`` of each row's point ``P[idx[:, 0]]``, relative to it, in the plane of
    their two principal axes."""
    X = P[idx]
    normal = plane_fits(scatter_matrices(X - X.mean(axis=1, keepdims=True)))[1]
    return np.einsum("nki,nij->nkj", X - X[:, :1, :], tangent_frames(normal)[:, :, 1:])


def _hull_march(W: np.ndarray) -> np.ndarray:
    """(n, k + 2) int: the corners of the convex hull of each row of ``W`` (n, k, 2), counter-clockwise from its
    lowest point back to it (Jarvis' march, all rows at once; -1 after a row's end). Of points on one hull edge only
    the ends are corners."""
    n, k = W.shape[:2]
    rows = np.arange(n)
    start = np.argmin(W[..., 1], axis=1)
    hull = np.full((n, k + 1), -1)
    hull[:, 0] = start
    cur = start.copy()
    d = np.tile([1.0, 0.0], (n, 1))  # the direction the march arrived in
    live = rows
    for step in range(1, k + 1):
        c = cur[live]
        V = W[live] - W[live, c][:, None, :]
        turn = np.arctan2(d[live, :1] * V[..., 1] - d[live, 1:] * V[..., 0],
                          d[live, :1] * V[..., 0] + d[live, 1:] * V[..., 1]) % (2.0 * np.pi)
        length = np.hypot(V[..., 0], V[..., 1])
        turn[length <= 0.0] = np.inf  # the current corner (and points on it)
        nearest = turn <= turn.min(axis=1, keepdims=True) + 1e-12
        nxt = np.argmax(np.where(nearest, length, -1.0), axis=1)  # of points in one direction, the farthest
        j = np.arange(live.size)
        hull[live, step] = cur[live] = nxt
        d[live] = V[j, nxt] / length[j, nxt][:, None]
        live = live[nxt != start[live]]
        if live.size == 0:
            break
    return np.c_[hull, np.full(n, -1)]


def triangle_set(tri: np.ndarray, owner: np.ndarray, P: np.ndarray, kind: str) -> tuple[np.ndarray, list[str]]:
    """The triangles of one of :data:`TRIANGLE_SETS` from the fans' triangles (:func:`fan_triangles`) of the points
    ``P`` (n, 3).

    Returns
    -------
    F : (m, 3) int64 ndarray
        Distinct triangles.
    notes : list of str
        What the repair added, if anything.
    """
    uniq, inverse, counts = unique_rows(tri, P.shape[0])
    if kind == "union":
        return uniq, []
    chosen = counts >= 2
    if kind == "consensus":
        return uniq[chosen], []
    # repaired: points the consensus leaves in a smaller piece than the union's component get their fans back; one
    # whose own fan is empty (left out across a thin wall, cloud_tilt) the other fans' triangles through it
    stranded = stranded_points(P.shape[0], uniq, uniq[chosen])
    if not stranded.size:
        return uniq[chosen], []
    chosen = chosen.copy()
    chosen[np.unique(inverse[np.isin(owner, stranded)])] = True
    chosen[np.isin(uniq, np.setdiff1d(stranded, owner)).any(axis=1)] = True
    notes = [f"point cloud: {stranded.size} points would be cut off by the consensus triangles; their fans' "
             "triangles (the other fans' triangles through a point whose own fan is empty) were added back"]
    return uniq[chosen], notes


class PointCloud:
    """Points in 3-D with no faces, solved on the triangles of their local fans.

    Parameters
    ----------
    P : (n, 3) array_like of float
        The points. Finite; at least 4 distinct ones, not all on one line.
    normals : (n, 3) array_like of float, optional
        Normals as read from a file, oriented consistently (outward, say). Unless ``use_normals=False``, each point's
        fan is built in the plane of its normal (averaged with those of its 6 nearest neighbours on its side) and
        leaves out the neighbours whose normal turns by more than :data:`NORMAL_FAN_ANGLE` degrees: no triangle
        across a thin wall or a sharp crease (:func:`normal_fans`; docs/pointclouds.md, "Normals"). Normals that
        look unoriented are not used, with a note.
    neighbours : int, default 30
        Points in each local neighbourhood: at 30, potpourri3d's local triangulation; another count (4 or more,
        below the number of distinct points) builds the same fans with :func:`local_fans`.
    triangles : {"union", "consensus", "repaired"}, default "union"
        Which of the fans' triangles to solve on (:data:`TRIANGLE_SETS`; docs/pointclouds.md measures them).
    outliers : {"exclude", "keep", "error"}, default "exclude"
        Isolated outliers (points far off the surface their neighbours sample) and points whose neighbours lie on a
        line (:data:`OUTLIER_HANDLING`): left out of the triangles with a note, kept, or refused.
    use_normals : bool, default True
        Whether given ``normals`` shape the fans (above); ``False`` builds them as without normals.
    denoise : {"auto", None, "jet"} or int, default "auto"
        Move the points onto the jets (degree-2 height fits to their 12 nearest neighbours) before the triangles are
        built (:func:`cvxgeodesic.mesh.denoise.jet_project`): ``"jet"`` two passes, an integer that many passes
        (0: none, as ``None``); ``"auto"`` two passes where the points read as :attr:`noisy` and number at least
        :data:`AUTO_DENOISE_MIN_POINTS`, else none. The points keep their order and count; :attr:`P`, the triangles
        and the lengths are the moved points', a note says so and why, and :attr:`denoised` counts the passes.
        docs/pointclouds.md ("Noise and the default", "Denoised clouds") measures it.
    name : str, optional
        Label for messages.

    Attributes
    ----------
    P : (n, 3) float ndarray, read-only
        The distinct points (duplicates merged: :attr:`file_index` maps the input's points to them), denoised when
        ``denoise`` asks.
    mesh : CloudMesh
        The triangle soup; its vertices are ``P``.
    notes : tuple of str
        Every repair made (merged duplicates, outliers left out, stranded points given their fans back, points in no
        triangle).
    noise : float
        The noise of the points as given, in units of their spacing (:attr:`noisy`, :attr:`clean`).
    denoised : int
        Passes of jet projection the points took (``denoise``); 0 where they are as given.
    denoised_automatically : bool
        Whether ``denoise="auto"`` chose them (a solve records it in ``info.extra["denoised"]``).
    points_as_given : (n, 3) float ndarray
        The distinct points before any denoising (:attr:`P` itself where :attr:`denoised` is 0): where
        :func:`~cvxgeodesic.save_distance` writes the field.
    outliers, line_points : (a,), (b,) int64 ndarray
        The distinct points left out of the triangles as isolated outliers and as points of line-like
        neighbourhoods (empty with ``outliers="keep"``); they cannot be sources, and a solve's field reaches them
        from their neighbours (:meth:`reach_left_out`).

    Raises
    ------
    MeshError
        A non-finite coordinate (the message names the point), fewer than 4 distinct points, all points on a line;
        with ``outliers="error"``, outliers or line-like neighbourhoods (the message names the first points).
    ParameterError
        An unknown ``triangles`` or ``outliers``, ``neighbours`` not an integer, below 4 or not below the number of
        distinct points (after the outliers are left out), or ``denoise`` not None, "jet" or an integer from 0 to 10.

    Examples
    --------
    >>> import numpy as np
    >>> g = np.linspace(0, 1, 12)
    >>> x, y = np.meshgrid(g, g)
    >>> cloud = PointCloud(np.c_[x.ravel(), y.ravel(), 0 * x.ravel()])
    >>> cloud.n_points
    144
    """

    def __init__(self, P: ArrayLike, normals: ArrayLike | None = None, *, neighbours: int = DEFAULT_NEIGHBOURS,
                 triangles: str = DEFAULT_TRIANGLES, outliers: str = DEFAULT_OUTLIERS,
                 use_normals: bool = True, denoise: str | int | None = "auto", name: str | None = None) -> None:
        self.name = name or "point cloud"
        passes = denoise_passes(denoise)
        if triangles not in TRIANGLE_SETS:
            raise ParameterError(f"triangles must be one of {', '.join(TRIANGLE_SETS)}, got {triangles!r}")
        if outliers not in OUTLIER_HANDLING:
            raise ParameterError(f"outliers must be one of {', '.join(OUTLIER_HANDLING)}, got {outliers!r}")
        if isinstance(neighbours, bool) or not isinstance(neighbours, int | np.integer):
            raise ParameterError(f"neighbours must be an integer, got {neighbours!r}")
        self.neighbours, self.triangles = int(neighbours), triangles
        raw = as_points(P, self.name, error=MeshError, row="point")
        notes: list[str] = []
        if _has_duplicates(raw):
            uniq, first, inverse = np.unique(raw, axis=0, return_index=True, return_inverse=True)
            inverse = inverse.reshape(-1)
            keep = np.sort(first)  # the input's order, first occurrence of each position
            remap = np.empty(uniq.shape[0], dtype=np.int64)
            remap[inverse[keep]] = np.arange(keep.size)
            file_index = remap[inverse]
            dup = np.flatnonzero(np.bincount(file_index)[file_index] > 1)
            notes.append(f"{self.name}: merged {raw.shape[0] - keep.size} duplicate points (same coordinates; "
                         f"first: input points {', '.join(str(int(i)) for i in dup[:4])}); fields have one value "
                         "per distinct point, file_index maps the input's points to them")
            pts = raw[keep]
        else:
            keep = np.arange(raw.shape[0])
            file_index = keep
            pts = raw
        _check_shape(pts, self.name)
        knn = nearest_neighbours(pts, max(DEFECT_NEIGHBOURS, TILT_NEIGHBOURS))  # one query for all three
        defects = _defects(pts, outliers, keep, self.name, knn)
        self.outliers, self.line_points = defects.outliers, defects.lines
        notes += _defect_notes(defects, keep, self.name)
        solid = np.setdiff1d(np.arange(pts.shape[0]), defects.points)  # the points the fans are built on
        if solid.size < pts.shape[0]:
            _check_shape(pts[solid], f"{self.name} without its {pts.shape[0] - solid.size} outliers")
        if not MIN_NEIGHBOURS <= self.neighbours < solid.size:
            raise ParameterError(f"neighbours must be at least {MIN_NEIGHBOURS} and below the number of distinct "
                                 f"points ({solid.size}{' without the outliers' if solid.size < pts.shape[0] else ''})"
                                 f", got {self.neighbours}")
        self.file_index = file_index
        self.normals = None if normals is None else _check_normals(normals, raw.shape[0], self.name)[keep]
        #: The noise of the points as given, in units of the spacing (:func:`~cvxgeodesic.mesh.denoise.jet_noise`),
        #: and above :data:`AUTO_NOISE_MAX` how much it grows from 12 to 30 neighbours (None below): growing less
        #: than :data:`DETAIL_GROWTH`, it is noise, not detail (:attr:`noisy`).
        self.noise = jet_noise(pts, *knn, points=solid)
        self.noise_growth = (jet_noise(pts, *knn, points=solid, k=DEFECT_NEIGHBOURS) / self.noise
                             if self.noise > AUTO_NOISE_MAX else None)  # asked only above the threshold
        if not isinstance(use_normals, bool | np.bool_):
            raise ParameterError(f"use_normals must be True or False, got {use_normals!r}")
        oriented = _oriented_normals(self.normals if use_normals else None, pts, solid, self.name, notes)
        #: Whether oriented normals shape the fans (:func:`normal_fans`).
        self.fans_by_normals = oriented is not None
        why = None
        if passes is None:  # "auto": where the noise would leave the default at order 1; normals keep sheets apart
            auto = self.noisy and pts.shape[0] >= AUTO_DENOISE_MIN_POINTS and oriented is None
            passes, why = (DENOISE_PASSES, f"denoise='auto', as {self._noise_words()}") if auto else (0, None)
        #: Passes of jet projection the points took (0: the points as given), and whether ``"auto"`` chose them.
        self.denoised = passes
        self.denoised_automatically = why is not None
        self.points_as_given = pts.view()  # the distinct points before any denoising (what save_distance writes)
        self.points_as_given.flags.writeable = False
        if passes:  # the points the fans are built on, fitted without the outliers
            pts = pts.copy()
            reuse = knn[1] if solid.size == pts.shape[0] else None  # the outliers' rows would need renumbering
            pts[solid] = denoised_with_note(pts[solid], passes, self.name, notes, reuse, why)
        tri, owner = fan_triangles(pts[solid], self.neighbours, oriented)
        if oriented is None:  # fans in fitted planes: those standing across a thin wall or a sharp crease left out
            planes = principal_planes(pts, knn[1])  # an outlier among a point's neighbours moves its plane a little
            tri, owner, dropped, restored = untilted_fans(pts[solid], tri, owner, tuple(a[solid] for a in planes))
            if dropped:
                notes.append(f"{self.name}: {dropped} fan triangles turned by more than {TILT_ANGLE:g} degrees from "
                             "the plane of the points around a corner (across a thin wall or a sharp crease) were "
                             f"left out" + (f"; {restored} points they would cut off kept their fans" if restored
                                            else ""))
        self._fans = (solid[tri], solid[owner])  # for surface(): the consensus of the same fans
        self._surface: tuple[TriMesh | None, str | None] | None = None
        F, added = triangle_set(solid[tri], solid[owner], pts, triangles)
        notes += added
        alone = np.setdiff1d(solid, F.ravel())
        if alone.size:
            notes.append(f"{self.name}: {alone.size} points are in no triangle (isolated; first: "
                         f"{', '.join(str(int(i)) for i in alone[:4])}): their distance is carried from their "
                         "nearest neighbours")
        if F.shape[0] == 0:
            raise MeshError(f"{self.name}: the local triangulation of the {pts.shape[0]} points made no triangle")
        left_out = np.setdiff1d(np.arange(pts.shape[0]), F.ravel())  # outliers, line points, isolated points
        self._left_out = (left_out, knn[0][left_out], knn[1][left_out])  # for reach_left_out
        mesh = CloudMesh(pts, F, name=self.name, vertex_map=keep, file_index=file_index, notes=notes)
        mesh.cloud = self
        self.mesh = mesh
        self.notes = tuple(notes)

    @property
    def left_out(self) -> np.ndarray:
        """(k,) int64 ndarray: the points in no triangle (outliers, line points, isolated points), ascending."""
        return self._left_out[0]

    def reach_left_out(self, distance: np.ndarray) -> tuple[np.ndarray, int]:
        """A field of the cloud's triangles carried to the points in none (outliers, line points, isolated points).

        Each such point takes the least, over its :data:`~cvxgeodesic.mesh.cloud_outliers.DEFECT_NEIGHBOURS`
        nearest points, of a neighbour's distance plus the straight distance to it, through other such points too
        (Dijkstra on those neighbour edges): a point beside the surface is as far as its foot plus the step to it, a
        wire's points as far as its foot plus the length along it. A point whose neighbours are all unreached (on
        another piece than the sources) stays ``inf``.

        Parameters
        ----------
        distance : (n,) float ndarray
            A field on the cloud's points, ``inf`` at the points in no triangle.

        Returns
        -------
        distance : (n,) float ndarray
            A copy with those points' values, or ``distance`` itself where the cloud has none.
        reached : int
            Points given a finite value.

        Examples
        --------
        >>> import numpy as np
        >>> g = np.linspace(0, 1, 12)
        >>> x, y = np.meshgrid(g, g)
        >>> P = np.r_[np.c_[x.ravel(), y.ravel(), 0 * x.ravel()], [[0.5, 0.5, 0.6]]]  # one point far above the grid
        >>> cloud = PointCloud(P)
        >>> cloud.outliers.tolist()
        [144]
        >>> d = np.linalg.norm(P[:, :2] - P[0, :2], axis=1)  # the plane's distances from point 0
        >>> d[144] = np.inf
        >>> carried, reached = cloud.reach_left_out(d)
        >>> reached, round(float(carried[144]), 3)  # through a neighbour: 0.927 straight, 1.307 through its foot
        (1, 1.11)
        """
        from scipy.sparse.csgraph import dijkstra

        points, dist, idx = self._left_out
        if points.size == 0:
            return distance, 0
        row_of = np.full(distance.shape[0], -1)
        row_of[points] = np.arange(points.size)
        other = row_of[idx]  # each neighbour's row among the left-out points, -1 for a point of the triangles
        first = np.where(other < 0, distance[idx] + dist, np.inf).min(axis=1)  # one step from the triangles
        carried = distance.copy()
        carried[points] = np.minimum(distance[points], dijkstra(_left_out_graph(other, dist, first), indices=0)[1:])
        return carried, int(np.isfinite(carried[points]).sum())

    @property
    def noisy(self) -> bool:
        """Whether the points as given read as too noisy for order 2 on a copy of the surface through them: their
        :attr:`noise` above :data:`AUTO_NOISE_MAX`, growing by less than :data:`DETAIL_GROWTH` (noise, not detail).
        ``denoise="auto"`` denoises such a cloud (:data:`AUTO_DENOISE_MIN_POINTS`)."""
        return self.noise_growth is not None and self.noise_growth < DETAIL_GROWTH

    def _noise_words(self) -> str:
        return (f"its noise, {self.noise:.3f} of the point spacing by its jets (growing {self.noise_growth:.2f}× "
                f"from 12 to 30 neighbours: noise, not detail), is above {AUTO_NOISE_MAX}")

    def default_refusal(self) -> str | None:
        """Why the default solve (order 2 on a copy, ``resolution="auto"``) is not taken on this cloud, or None: the
        points as given too :attr:`noisy` for it, and not denoised (:attr:`denoised`: a denoised cloud's copy is
        decimated from the moved points)."""
        if self.denoised or not self.noisy:
            return None
        if self.n_points < AUTO_DENOISE_MIN_POINTS:
            kept = f"; a cloud of fewer than {AUTO_DENOISE_MIN_POINTS} points is not denoised by denoise='auto'"
        elif self.fans_by_normals:
            kept = ("; denoise='auto' does not denoise a cloud whose normals shape its fans (the jets would join the "
                    "sides of gaps thinner than a spacing)")
        else:
            kept = ""  # denoise=None
        return f"{self._noise_words()}, where order 2 on a copy of the raw points stops paying{kept}"

    @property
    def clean(self) -> bool:
        """Whether the cloud reads as free of noise: its :attr:`noise` at most :data:`CLEAN_NOISE_MAX`. The default
        solve of a clean cloud takes a finer copy (:data:`~cvxgeodesic.strategies.adapted.CLEAN_CLOUD_FRACTION`)."""
        return self.noise <= CLEAN_NOISE_MAX

    @property
    def P(self) -> np.ndarray:
        """(n, 3) float ndarray: the distinct points (the soup's vertices)."""
        return self.mesh.V

    def surface(self) -> tuple[TriMesh | None, str | None]:
        """A manifold triangle surface through the points, for ``resolution=`` (quadric decimation needs one).

        The consensus of the fans (the triangles in two fans or more, :data:`TRIANGLE_SETS`) without the triangles
        on an edge of more than two; in each piece of the cloud's own triangles (a cloud of several objects), its
        largest connected piece, as long as the pieces that break off it (noise makes a few) hold at most
        :data:`SURFACE_FRAGMENTS` of that piece's consensus triangles.

        Returns
        -------
        surface : TriMesh or None
            Its vertices are the cloud's points (:attr:`P`, the same indices; the points off it are unreferenced);
            one connected piece in each piece of the cloud's triangles.
        why : str or None
            Why there is none: a piece of the cloud's triangles without consensus, or its consensus in pieces.
        """
        if self._surface is None:  # built once: the default's check of a denoised cloud's copy reads it too
            self._surface = self._consensus_surface()
        return self._surface

    def _consensus_surface(self) -> tuple[TriMesh | None, str | None]:
        tri, owner = self._fans
        F, _ = triangle_set(tri, owner, self.P, "consensus")
        if F.shape[0] == 0:
            return None, "no triangle is in two fans"
        consensus = TriMesh(self.P, F)
        F = F[~(consensus.edge_cell_counts[consensus.cell_edges] > 2).any(axis=1)]
        if F.shape[0] == 0:
            return None, "every consensus triangle is on a non-manifold edge"
        name = f"{self.name} (consensus surface)"
        labels = triangle_components(self.P.shape[0], F)[F[:, 0]]  # the edge graph's, without a mesh to validate
        piece_of_face = self.mesh.component_labels[F[:, 0]]
        pieces = np.unique(self.mesh.component_labels[self.mesh.referenced])
        keep = np.zeros(F.shape[0], dtype=bool)
        for k, piece in enumerate(pieces):
            inside = piece_of_face == piece
            where = f" in piece {k + 1} of the cloud's {pieces.size}" if pieces.size > 1 else ""
            if not inside.any():
                return None, f"no consensus triangle{where}"
            values, counts = np.unique(labels[inside], return_counts=True)
            if counts.max() < (1 - SURFACE_FRAGMENTS) * counts.sum():
                return None, (f"the consensus of the fans{where} breaks into {values.size} pieces (the largest "
                              f"holds {counts.max() / counts.sum():.0%} of its triangles)")
            keep |= inside & (labels == values[np.argmax(counts)])
        return TriMesh(self.P, F[keep], name=name), None

    def check_sources(self, vertices: np.ndarray) -> None:
        """Refuse source points that were left out of the triangles (their field would be ``inf`` everywhere).

        Parameters
        ----------
        vertices : (s,) int ndarray
            Source indices among the distinct points.

        Raises
        ------
        SourceError
            Naming the first such point and why it was left out.
        """
        v = np.asarray(vertices, dtype=np.int64).reshape(-1)
        bad = v[np.isin(v, self.outliers) | np.isin(v, self.line_points)]
        if bad.size:
            why = "an isolated outlier" if bad[0] in self.outliers else "a point whose neighbours lie on a line"
            raise SourceError(f"source point {int(bad[0])} of {self.name} is {why}, left out of the cloud's triangles "
                              "(no field starts there): choose another source, or build the cloud with "
                              "PointCloud(..., outliers='keep') (--outliers keep on the command line)")

    @property
    def n_points(self) -> int:
        """Number of distinct points."""
        return self.mesh.n_vertices

    n_vertices = n_points

    def __repr__(self) -> str:
        return (f"PointCloud(name={self.name!r}, n_points={self.n_points}, triangles={self.triangles!r}, "
                f"n_triangles={self.mesh.n_faces})")

    @classmethod
    def from_object(cls, obj: Any, **kwargs: Any) -> PointCloud:
        """A cloud from a ``trimesh.PointCloud`` (``.vertices``) or an ``open3d.geometry.PointCloud``
        (``.points``, and ``.normals`` when it has them), by duck typing."""
        return cls(*_object_points(obj), **kwargs)


def _object_points(obj: Any) -> tuple[np.ndarray, np.ndarray | None]:
    """Points and normals (or None) of another library's point-cloud object."""
    if isinstance(obj, PointCloud):
        return obj.P, obj.normals
    if hasattr(obj, "points") and hasattr(obj, "has_normals"):  # open3d.geometry.PointCloud
        normals = np.asarray(obj.normals) if obj.has_normals() else None
        return np.asarray(obj.points), normals
    if hasattr(obj, "vertices") and not hasattr(obj, "faces"):  # trimesh.PointCloud
        return np.asarray(obj.vertices), None
    raise TypeError(f"not a point cloud: {type(obj).__module__}.{type(obj).__qualname__} (expected a "
                    "trimesh.PointCloud or an open3d.geometry.PointCloud)")


def is_point_cloud_object(obj: Any) -> bool:
    """Whether ``obj`` is a point cloud of this library, trimesh or open3d (no faces)."""
    if isinstance(obj, PointCloud):
        return True
    kind = f"{type(obj).__module__}.{type(obj).__qualname__}"
    return kind.startswith(("trimesh.points.PointCloud", "open3d")) and "PointCloud" in kind


def _left_out_graph(other: np.ndarray, dist: np.ndarray, first: np.ndarray) -> Any:
    """The graph :meth:`PointCloud.reach_left_out` runs Dijkstra on, a ``scipy.sparse`` CSR matrix: node 0 joined
    to each left-out point (node ``i + 1``) at its best step from the triangles, ``first`` (m,), where finite; two
    left-out points joined both ways where one is among the other's neighbours (``other`` (m, k): their rows, -1 for a
    point of the triangles), at their distance ``dist`` (m, k). One entry per pair: a sparse matrix sums repeats."""
    import scipy.sparse as sp

    m = other.shape[0]
    r, c = np.nonzero(other >= 0)
    a, b, w = r + 1, other[r, c] + 1, dist[r, c]
    keys, at = np.unique(np.r_[a * (m + 1) + b, b * (m + 1) + a], return_index=True)
    start = np.flatnonzero(np.isfinite(first))
    rows = np.r_[keys // (m + 1), np.zeros(start.size, dtype=np.int64)]
    cols = np.r_[keys % (m + 1), start + 1]
    return sp.csr_matrix((np.r_[np.r_[w, w][at], first[start]], (rows, cols)), shape=(m + 1, m + 1))


def _has_duplicates(P: np.ndarray) -> bool:
    """Whether two rows of ``P`` (n, 3) are equal: a sort by columns, 3-4× faster than ``np.unique(axis=0)``, which
    the rare cloud with duplicates then runs for the merge."""
    rows = P[np.lexsort(P.T[::-1])]
    return bool((rows[1:] == rows[:-1]).all(axis=1).any())


def _check_shape(P: np.ndarray, name: str) -> None:
    if P.shape[0] < 4:
        raise MeshError(f"{name}: a point cloud needs at least 4 distinct points, got {P.shape[0]}")
    s = np.linalg.svd(P - P.mean(axis=0), compute_uv=False)
    if s[1] <= COLLINEAR_TOL * s[0]:
        raise MeshError(f"{name}: all {P.shape[0]} points lie on one line (second principal extent "
                        f"{s[1] / max(s[0], 1e-300):.1e} of the first): there is no surface to measure on")


def _defects(P: np.ndarray, outliers: str, keep: np.ndarray, name: str,
             knn: tuple[np.ndarray, np.ndarray]) -> CloudDefects:
    """The points to leave out (none with ``outliers="keep"``); refused with ``outliers="error"``."""
    none = np.zeros(0, dtype=np.int64)
    if outliers == "keep":
        return CloudDefects(none, none)
    found = find_defects(P, knn=knn)
    if found.outliers.size:
        kept = _on_the_others_fans(P, found, knn)
        found = CloudDefects(np.setdiff1d(found.outliers, kept), found.lines, found.grouped)  # kept: none grouped
    if outliers == "error" and found.points.size:
        raise MeshError(f"{name}: {_describe_defects(found, keep)} (outliers='error'; outliers='exclude' leaves them "
                        "out of the triangles, outliers='keep' triangulates them)")
    return found


def _on_the_others_fans(P: np.ndarray, found: CloudDefects, knn: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """The outliers of ``found`` that lie on the surface the other points sample: not in a small group apart from
    the rest (whose unflagged members' fans would hold the flagged ones), and closer to the triangles of the other
    points' fans than :data:`ON_SURFACE` times their mean distance to their
    :data:`~cvxgeodesic.mesh.cloud_outliers.DEFECT_NEIGHBOURS` nearest. The fans (:func:`local_fans`'
    construction, at :data:`DEFAULT_NEIGHBOURS`) are built on the other points, only for those near the outliers."""
    from scipy.spatial import cKDTree

    from .closest import nearest_triangle_distance

    solid = np.setdiff1d(np.arange(P.shape[0]), found.points)
    lone = np.setdiff1d(found.outliers, found.grouped)
    if solid.size <= DEFAULT_NEIGHBOURS or not lone.size:
        return lone[:0]
    tree = cKDTree(P[solid])
    near = np.unique(tree.query(P[lone], k=DEFECT_NEIGHBOURS)[1])
    idx = tree.query(P[solid[near]], k=DEFAULT_NEIGHBOURS + 1)[1]  # column 0: the point itself
    tri = solid[_fans(_tangent_coordinates(P[solid], idx), idx)[0]]
    gap = nearest_triangle_distance(P, tri, P[lone])
    return lone[gap < ON_SURFACE * knn[0][lone, :DEFECT_NEIGHBOURS].mean(axis=1)]


def _describe_defects(found: CloudDefects, keep: np.ndarray) -> str:
    """The defects in words, naming the first points in the input's numbering (``keep``: distinct → input)."""
    parts = []
    for idx, what in ((found.outliers, "isolated outliers (far off the surface their neighbours sample"),
                      (found.lines, "points whose neighbours lie on a line (no surface around them")):
        if idx.size:
            parts.append(f"{idx.size} {what}; first: input points {', '.join(str(int(i)) for i in keep[idx[:4]])})")
    return " and ".join(parts)


def _defect_notes(found: CloudDefects, keep: np.ndarray, name: str) -> list[str]:
    if not found.points.size:
        return []
    return [f"{name}: {_describe_defects(found, keep)} were left out of the triangles: their distance is carried "
            "from their nearest neighbours (PointCloud(..., outliers='keep'), --outliers keep on the command line, "
            "triangulates them)"]


def _oriented_normals(normals: np.ndarray | None, P: np.ndarray, solid: np.ndarray, name: str,
                      notes: list[str]) -> np.ndarray | None:
    """The unit normals of the points ``solid`` for :func:`normal_fans`, each averaged with those of its
    :data:`NORMAL_SMOOTHING_NEIGHBOURS` nearest neighbours that turn by less than :data:`NORMAL_SMOOTHING_ANGLE`; or
    None: without normals, and where they look unoriented (:data:`UNORIENTED_FRACTION` of the pairs within
    :data:`TANGENT_PAIR_ANGLE` of the tangent plane point apart; noted) or some are zero (noted)."""
    if normals is None:
        return None
    from scipy.spatial import cKDTree

    N = normals[solid]
    length = np.linalg.norm(N, axis=1)
    if not (length > 0).all():
        notes.append(f"{name}: {int((length <= 0).sum())} normals are zero: the fans are built without the normals")
        return None
    N = N / length[:, None]
    X = P[solid]
    near = cKDTree(X).query(X, k=min(NORMAL_SMOOTHING_NEIGHBOURS, solid.size - 1) + 1)[1][:, 1:]
    agree = np.einsum("nki,ni->nk", N[near], N)
    offset = X[near] - X[:, None, :]
    rise = np.abs(np.einsum("nki,ni->nk", offset, N)) / np.maximum(np.linalg.norm(offset, axis=2), 1e-300)
    beside = rise <= np.sin(np.radians(TANGENT_PAIR_ANGLE))  # across a thin gap a neighbour lies off the plane
    apart = float((agree[beside] < 0).mean() if beside.mean() >= 0.25 else (agree < 0).mean())
    if apart > UNORIENTED_FRACTION:
        notes.append(f"{name}: the normals look unoriented ({100 * apart:.0f} % of nearest-neighbour pairs beside "
                     "each other point apart): the fans are built without them; orient them consistently to keep the "
                     "fans from crossing thin walls and sharp creases")
        return None
    same_side = agree > np.cos(np.radians(NORMAL_SMOOTHING_ANGLE))  # not the facing side of a thin gap
    mean = N + np.einsum("nk,nki->ni", same_side, N[near])
    length = np.linalg.norm(mean, axis=1)
    return np.where(length[:, None] > 1e-6, mean / np.maximum(length, 1e-300)[:, None], N)


def _check_normals(N: ArrayLike, n: int, name: str) -> np.ndarray:
    X = as_points(N, name, error=MeshError, row="normal")
    if X.shape != (n, 3):
        raise MeshError(f"{name}: normals must have the points' shape ({n}, 3), got {X.shape}")
    return X
