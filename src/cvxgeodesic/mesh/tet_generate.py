"""Tetrahedral meshes generated in code, with analytic distances: a box, an L-shaped prism, a ball (issue 26).

All three are made of Kuhn (Freudenthal) tetrahedra: each hexahedral cell is cut into the six
tetrahedra around its diagonal from the (0, 0, 0) corner to the (1, 1, 1) corner. The cut of every
quadrilateral face runs from its lowest to its highest corner, so neighbouring cells agree and the
mesh is conforming. On an undistorted cube every dihedral angle is 45°, 60° or 90° (the cotangent
Laplacian has no negative weight) and the smallest altitude is 0.41 of the longest edge.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ..errors import ParameterError
from ..validation import as_points, check_count, check_number
from .tetmesh import TetMesh

__all__ = ["kuhn_tets", "l_prism_distance", "tet_ball", "tet_box", "tet_l_prism"]

#: The six tetrahedra of the unit cube around its main diagonal, as corner numbers ``i + 2j + 4k`` of corner
#: ``(i, j, k)``: one per order in which the path from (0,0,0) to (1,1,1) takes the three axes. All are
#: positively oriented.
_KUHN = np.array([[0, 1, 3, 7], [0, 1, 5, 7], [0, 2, 3, 7], [0, 2, 6, 7], [0, 4, 5, 7], [0, 4, 6, 7]],
                 dtype=np.int64)
_KUHN_SIGN = np.array([1, -1, -1, 1, 1, -1])  # orientation of each _KUHN row on the unit cube


def kuhn_tets(corners: np.ndarray) -> np.ndarray:
    """Six positively oriented Kuhn tetrahedra per hexahedral cell (on an undistorted grid).

    Parameters
    ----------
    corners : (c, 8) int ndarray
        Vertex indices of each cell's corners, column ``i + 2j + 4k`` for the corner at offset
        ``(i, j, k)`` along the grid's three axes.

    Returns
    -------
    (6c, 4) int64 ndarray
        Cell ``q``'s tetrahedra are rows ``6q … 6q + 5``.
    """
    T = np.asarray(corners, dtype=np.int64)[:, _KUHN].reshape(-1, 4)
    flip = np.tile(_KUHN_SIGN < 0, len(corners))
    T[flip, 2], T[flip, 3] = T[flip, 3].copy(), T[flip, 2].copy()
    return T


def _grid(nx: int, ny: int, nz: int, size: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (x fastest) and (cells, 8) corner indices of an ``nx × ny × nz`` grid on ``[0, size]``."""
    xs, ys, zs = (np.linspace(0.0, s, k + 1) for s, k in zip(size, (nx, ny, nz), strict=True))
    Z, Y, X = np.meshgrid(zs, ys, xs, indexing="ij")
    V = np.column_stack([X.ravel(), Y.ravel(), Z.ravel()])
    return V, _cell_corners(np.arange(V.shape[0]).reshape(nz + 1, ny + 1, nx + 1))


def _cell_corners(idx: np.ndarray) -> np.ndarray:
    """(cells, 8) corner indices (column ``i + 2j + 4k``) of the grid of vertex indices ``idx`` (nz+1, ny+1, nx+1)."""
    nz, ny, nx = (s - 1 for s in idx.shape)
    return np.stack([idx[k:nz + k, j:ny + j, i:nx + i].reshape(-1)
                     for k in (0, 1) for j in (0, 1) for i in (0, 1)], axis=1)


def _jitter(mesh: TetMesh, jitter: float, cell: float, seed: int) -> TetMesh:
    """Move every vertex off the boundary surface by up to ``jitter · cell`` per coordinate."""
    if not jitter:
        return mesh
    rng = np.random.default_rng(seed)
    V = mesh.V.copy()
    interior = ~np.isin(np.arange(mesh.n_vertices), mesh.boundary_vertices)
    V[interior] += rng.uniform(-jitter, jitter, (int(interior.sum()), 3)) * cell
    return TetMesh(V, mesh.T, name=mesh.name)


def _jitter_value(jitter: float) -> float:
    # beyond 0.25 of a cell a Kuhn tetrahedron (altitude 0.71 cells) can invert
    return check_number(jitter, "jitter", low=0.0, high=0.25)


def tet_box(nx: int = 8, ny: int | None = None, nz: int | None = None, size: float | ArrayLike = 1.0, *,
            jitter: float = 0.0, seed: int = 0) -> TetMesh:
    """A box ``[0, sx] × [0, sy] × [0, sz]`` of Kuhn tetrahedra.

    Parameters
    ----------
    nx, ny, nz : int
        Cells along x, y and z (``ny`` and ``nz`` default to ``nx``).
    size : float or (3,) array_like of float
        Side lengths (one number: a cube).
    jitter : float
        Vertices off the boundary move by up to ``jitter`` times the smallest cell side in each
        coordinate (uniform, deterministic for a given ``seed``); in ``[0, 0.25]``, 0 gives the
        regular grid. Boundary vertices stay, so the box keeps its shape.
    seed : int
        Seed of the jitter.

    Returns
    -------
    TetMesh
        ``(nx + 1)(ny + 1)(nz + 1)`` vertices (x fastest, then y, then z; vertex 0 at the origin),
        ``6 nx ny nz`` positively oriented tetrahedra.

    Examples
    --------
    >>> mesh = tet_box(2)
    >>> mesh.n_vertices, mesh.n_tets, round(mesh.total_volume, 12)
    (27, 48, 1.0)
    """
    nx = check_count(nx, "nx")
    ny = nx if ny is None else check_count(ny, "ny")
    nz = nx if nz is None else check_count(nz, "nz")
    try:
        sz = np.broadcast_to(np.asarray(size, dtype=float), (3,))
    except (TypeError, ValueError):
        sz = np.zeros(3)
    if not np.all(np.isfinite(sz)) or np.any(sz <= 0):
        raise ParameterError(f"size must be a positive number or three positive numbers, got {size!r}")
    jitter = _jitter_value(jitter)
    V, corners = _grid(nx, ny, nz, sz)
    mesh = TetMesh(V, kuhn_tets(corners), name=f"box{nx}x{ny}x{nz}")
    return _jitter(mesh, jitter, float(min(sz / (nx, ny, nz))), seed)


def tet_l_prism(n: int = 8, *, jitter: float = 0.0, seed: int = 0) -> TetMesh:
    """The L-shaped prism ``[0, 2]² × [0, 1]`` minus ``[1, 2]² × [0, 1]``, of Kuhn tetrahedra.

    The re-entrant edge is the segment ``x = y = 1``, ``0 ≤ z ≤ 1``; :func:`l_prism_distance` is
    the exact distance inside. With ``n`` cells per unit length the mesh has ``18 n³``
    tetrahedra: 1 152, 9 216 and 31 104 for ``n = 4, 8, 12`` (issue 26's sizes).

    Parameters
    ----------
    n : int
        Cells per unit length (in x, y and z).
    jitter : float
        Vertices off the boundary move by up to ``jitter`` cells in each coordinate (see
        :func:`tet_box`); in ``[0, 0.25]``.
    seed : int
        Seed of the jitter.

    Returns
    -------
    TetMesh
        Vertices ordered x fastest, then y, then z; vertex 0 at the origin.

    Examples
    --------
    >>> mesh = tet_l_prism(8)
    >>> mesh.n_tets, round(mesh.total_volume, 12)
    (9216, 3.0)
    """
    n = check_count(n, "n")
    jitter = _jitter_value(jitter)
    V, corners = _grid(2 * n, 2 * n, n, np.array([2.0, 2.0, 1.0]))
    centre = V[corners].mean(axis=1)
    keep = ~((centre[:, 0] > 1.0) & (centre[:, 1] > 1.0))
    corners = corners[keep]
    used = np.unique(corners)
    renumber = np.full(V.shape[0], -1, dtype=np.int64)
    renumber[used] = np.arange(used.size)
    mesh = TetMesh(V[used], kuhn_tets(renumber[corners]), name=f"lprism{n}")
    return _jitter(mesh, jitter, 1.0 / n, seed)


def l_prism_distance(source: ArrayLike, points: ArrayLike) -> np.ndarray:
    """Exact distance inside the L-shaped prism of :func:`tet_l_prism` from ``source`` to ``points``.

    The prism is a product ``L × [0, 1]`` of the planar L and an interval, so the distance is
    ``√(d_L² + Δz²)`` with ``d_L`` the distance in the plane: the straight length where the segment
    stays in the L, else ``|s − c| + |c − x|`` around the re-entrant corner ``c = (1, 1)``.

    Parameters
    ----------
    source : (3,) array_like of float
        A point of the prism.
    points : (p, 3) array_like of float
        Points of the prism.

    Returns
    -------
    (p,) float ndarray
    """
    s = as_points(source, "source").reshape(3)
    X = as_points(points, "points").reshape(-1, 3)
    c = np.array([1.0, 1.0])
    d = X[:, :2] - s[:2]
    # the segment s → x (planar) meets the open square (1, 2)²: Liang–Barsky clipping of t ∈ [0, 1]
    lo, hi = np.zeros(len(X)), np.ones(len(X))
    for k in range(2):
        with np.errstate(divide="ignore", invalid="ignore"):
            t1, t2 = (1.0 - s[k]) / d[:, k], (2.0 - s[k]) / d[:, k]
        inside_slab = (s[k] > 1.0) & (s[k] < 2.0)
        parallel = d[:, k] == 0
        lo = np.where(parallel, np.where(inside_slab, lo, np.inf), np.maximum(lo, np.minimum(t1, t2)))
        hi = np.where(parallel, np.where(inside_slab, hi, -np.inf), np.minimum(hi, np.maximum(t1, t2)))
    blocked = hi - lo > 1e-12
    straight = np.linalg.norm(d, axis=1)
    around = np.linalg.norm(s[:2] - c) + np.linalg.norm(X[:, :2] - c, axis=1)
    planar = np.where(blocked, around, straight)
    return np.hypot(planar, X[:, 2] - s[2])


def tet_ball(n: int = 8, radius: float = 1.0, *, layers: int | None = None, smooth: int = 5) -> TetMesh:
    """A ball of Kuhn tetrahedra: a cube in the middle and six shells out to the sphere (a "cubed sphere").

    The inner cube ``[-r/2, r/2]³`` has ``n`` cells per side. Each of its faces is joined to the
    sphere by a shell of ``n × n × layers`` hexahedra: a point ``(u, v)`` of the cube face is
    joined linearly to the sphere point in the direction ``(1, tan(πu/4), tan(πv/4))``
    (equal-angle, so the sphere's cells are close to uniform). The shells meet on the planes
    ``|x| = |y|`` etc., where their grids coincide, and every hexahedron is cut into six Kuhn
    tetrahedra with axes increasing outward and along the global coordinates, so the mesh is
    conforming. Boundary vertices lie exactly on the sphere (to round-off). Then ``smooth`` rounds
    of Laplacian smoothing (each interior vertex moves halfway to the mean of its neighbours) relax
    the twisted cells where three shells meet: the smallest altitude over longest edge goes from
    0.098 to 0.196 at ``n = 8`` (5 rounds; the undistorted Kuhn tetrahedron has 0.408).

    Parameters
    ----------
    n : int
        Cells along each side of the inner cube and each shell face (even or odd).
    radius : float
        Radius of the ball.
    layers : int, optional
        Radial cells of each shell; default ``max(1, round(0.4 n))``, which makes the radial and
        tangential cell sizes about equal at mid-shell.
    smooth : int
        Rounds of Laplacian smoothing of the interior vertices (0: none).

    Returns
    -------
    TetMesh
        ``6 n³ + 36 n² · layers`` tetrahedra (9 984 for ``n = 8``: 3 072 in the cube), all positively
        oriented. For even ``n`` one vertex lies at the centre (within ``1e-4 · radius`` after
        smoothing): ``argmin(norm(V, axis=1))``.

    Examples
    --------
    >>> mesh = tet_ball(8)
    >>> mesh.n_tets, bool(abs(mesh.total_volume - 4 / 3 * 3.141592653589793) < 0.1)
    (9984, True)
    """
    n = check_count(n, "n")
    radius = check_number(radius, "radius", low=0.0, low_open=True)
    m = max(1, round(0.4 * n)) if layers is None else check_count(layers, "layers")
    smooth = check_count(smooth, "smooth", minimum=0)
    a = 0.5  # half side of the inner cube, for a unit ball
    Vc, Cc = _grid(n, n, n, np.full(3, 2 * a))
    parts_V, parts_C = [Vc - a], [Cc]
    offset = Vc.shape[0]
    t = np.linspace(-1.0, 1.0, n + 1)
    rho = np.linspace(0.0, 1.0, m + 1)
    # shell grid axes (u, v, rho) -> local grid "x, y, z" = (u, v, rho): Kuhn cuts increase along u, v and outward
    R, Vg, U = np.meshgrid(rho, t, t, indexing="ij")  # shape (m+1, n+1, n+1), u fastest
    inner = np.stack([np.ones_like(U), U, Vg], axis=-1) * a
    outer = np.stack([np.ones_like(U), np.tan(np.pi / 4 * U), np.tan(np.pi / 4 * Vg)], axis=-1)
    outer /= np.linalg.norm(outer, axis=-1, keepdims=True)
    P = ((1 - R)[..., None] * inner + R[..., None] * outer).reshape(-1, 3)  # local: (normal, u, v)
    corners = _cell_corners(np.arange(P.shape[0]).reshape(m + 1, n + 1, n + 1))
    for axis in range(3):
        others = [ax for ax in range(3) if ax != axis]
        for sign in (1.0, -1.0):
            Q = np.empty_like(P)
            Q[:, axis] = sign * P[:, 0]
            Q[:, others[0]] = P[:, 1]
            Q[:, others[1]] = P[:, 2]
            parts_V.append(Q)
            parts_C.append(corners + offset)
            offset += P.shape[0]
    V = np.vstack(parts_V)
    C = np.vstack(parts_C)
    # the shells share their side planes with each other and their inner face with the cube: weld coincident
    # vertices (the same formula in permuted coordinates, equal to round-off)
    pairs = cKDTree(V).query_pairs(1e-9, output_type="ndarray")
    graph = sp.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(V), len(V)))
    _, label = connected_components(graph, directed=False)
    first = np.full(label.max() + 1, len(V))
    np.minimum.at(first, label, np.arange(len(V)))
    keep = np.sort(first)
    new_id = np.empty(label.max() + 1, dtype=np.int64)
    new_id[label[keep]] = np.arange(keep.size)
    T = kuhn_tets(new_id[label[C]])
    # the local frame of a shell is a rotation or a reflection of the global one: orient every row positively
    mesh = TetMesh(V[keep], T, name=f"ball{n}")
    V = mesh.V.copy()
    if smooth:
        A = (mesh.vertex_adjacency > 0).astype(float)
        degree = np.asarray(A.sum(axis=1)).ravel()
        interior = ~np.isin(np.arange(mesh.n_vertices), mesh.boundary_vertices)
        for _ in range(smooth):
            V[interior] = 0.5 * V[interior] + 0.5 * (A @ V)[interior] / degree[interior, None]
    return TetMesh(V * radius, mesh.positive_tets, name=mesh.name)
