"""Meshes generated in code: for tests with analytic distances and for the demo."""

from __future__ import annotations

import numpy as np

from ..validation import check_count, check_number
from .trimesh import TriMesh


def grid_plane(
    nx: int = 20, ny: int | None = None, size: float = 1.0, *, jitter: float = 0.0, seed: int = 0
) -> TriMesh:
    """A flat square ``[0, size]²`` in the z = 0 plane, split into right triangles.

    Parameters
    ----------
    nx, ny : int
        Number of cells along x and y (``ny`` defaults to ``nx``).
    size : float
        Side length of the square.
    jitter : float
        Interior vertices move by up to ``jitter`` times the cell size in x and y
        (deterministic for a given ``seed``); 0 gives a regular grid.
    seed : int
        Seed of the jitter.

    Returns
    -------
    TriMesh
        ``(nx + 1)(ny + 1)`` vertices, ``2 nx ny`` faces, consistently oriented (+z).
    """
    nx = check_count(nx, "nx", minimum=1)
    ny = nx if ny is None else check_count(ny, "ny", minimum=1)
    xs, ys = np.linspace(0.0, size, nx + 1), np.linspace(0.0, size, ny + 1)
    X, Y = np.meshgrid(xs, ys, indexing="xy")
    V = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    if jitter:
        rng = np.random.default_rng(seed)
        interior = (V[:, 0] > 0) & (V[:, 0] < size) & (V[:, 1] > 0) & (V[:, 1] < size)
        V[interior, :2] += rng.uniform(-jitter, jitter, (interior.sum(), 2)) * size / max(nx, ny)
    idx = np.arange((nx + 1) * (ny + 1)).reshape(ny + 1, nx + 1)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, 1:].ravel(), idx[1:, :-1].ravel()
    # alternate the diagonal so the grid has no preferred direction
    flip = ((np.arange(ny)[:, None] + np.arange(nx)[None, :]) % 2).ravel().astype(bool)
    F1 = np.where(flip[:, None], np.column_stack([a, b, d]), np.column_stack([a, b, c]))
    F2 = np.where(flip[:, None], np.column_stack([b, c, d]), np.column_stack([a, c, d]))
    return TriMesh(V, np.vstack([F1, F2]), name=f"plane{nx}x{ny}")


def icosphere(subdivisions: int = 3, radius: float = 1.0) -> TriMesh:
    """A sphere made by repeated 4-to-1 subdivision of an icosahedron.

    Parameters
    ----------
    subdivisions : int
        Number of subdivision rounds; the mesh has ``20 · 4**subdivisions`` faces.
    radius : float
        Sphere radius.

    Returns
    -------
    TriMesh
        Outward-oriented sphere; vertex 0 is ``(0, 0, radius)``-adjacent icosahedron vertex.
    """
    subdivisions = check_count(subdivisions, "subdivisions", minimum=0)
    t = (1.0 + 5.0**0.5) / 2.0
    V = np.array(
        [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
         [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]], dtype=float)
    F = np.array(
        [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
         [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
         [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]], dtype=np.int64)
    V /= np.linalg.norm(V, axis=1, keepdims=True)
    for _ in range(subdivisions):
        V, F = _subdivide_midpoint(V, F)
        V /= np.linalg.norm(V, axis=1, keepdims=True)
    return TriMesh(V * radius, F, name=f"icosphere{subdivisions}")


def _subdivide_midpoint(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    E.sort(axis=1)
    uniq, inv = np.unique(E, axis=0, return_inverse=True)
    mid = len(V) + inv.reshape(3, -1).T  # (m, 3): midpoints of edges 01, 12, 20
    Vn = np.vstack([V, 0.5 * (V[uniq[:, 0]] + V[uniq[:, 1]])])
    a, b, c = F[:, 0], F[:, 1], F[:, 2]
    ab, bc, ca = mid[:, 0], mid[:, 1], mid[:, 2]
    Fn = np.vstack([np.column_stack([a, ab, ca]), np.column_stack([b, bc, ab]),
                    np.column_stack([c, ca, bc]), np.column_stack([ab, bc, ca])])
    return Vn, Fn


def cylinder(n_around: int = 32, n_along: int = 16, radius: float = 1.0, height: float = 2.0) -> TriMesh:
    """An open cylinder (no caps) around the z axis, ``0 <= z <= height``.

    Geodesic distances on it equal Euclidean distances in the unrolled
    rectangle (taking the shorter way around), which tests use as ground truth.

    Returns
    -------
    TriMesh
        ``n_around · (n_along + 1)`` vertices, ``2 · n_around · n_along`` faces.
    """
    n_around = check_count(n_around, "n_around", minimum=3)
    n_along = check_count(n_along, "n_along", minimum=1)
    theta = 2.0 * np.pi * np.arange(n_around) / n_around
    z = np.linspace(0.0, height, n_along + 1)
    T, Z = np.meshgrid(theta, z, indexing="xy")
    V = np.column_stack([radius * np.cos(T.ravel()), radius * np.sin(T.ravel()), Z.ravel()])
    idx = np.arange(n_around * (n_along + 1)).reshape(n_along + 1, n_around)
    nxt = np.roll(idx, -1, axis=1)
    a, b, c, d = idx[:-1].ravel(), nxt[:-1].ravel(), nxt[1:].ravel(), idx[1:].ravel()
    F = np.vstack([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    return TriMesh(V, F, name=f"cylinder{n_around}x{n_along}")


def needle_strip(nx: int = 10, aspect: float = 50.0) -> TriMesh:
    """A flat strip of needle triangles: ``2·nx`` faces of aspect ratio about ``aspect``.

    The bottom row has ``nx + 1`` vertices on ``[0, 1]``, the top row the same shifted by half a cell at
    height ``1 / (nx · aspect)``; every face has a long edge of one cell and an altitude ``aspect``
    times shorter. A test of accuracy on badly shaped, flat triangles (exact distance: Euclidean).

    Parameters
    ----------
    nx : int
        Number of cells along the strip.
    aspect : float
        Cell length / strip height (> 0).

    Returns
    -------
    TriMesh
        ``2 (nx + 1)`` vertices in the plane z = 0, ``2 nx`` faces.
    """
    nx = check_count(nx, "nx", minimum=1)
    aspect = check_number(aspect, "aspect", low=0.0, low_open=True)
    height = 1.0 / nx / aspect
    xs = np.linspace(0.0, 1.0, nx + 1)
    V = np.vstack([np.column_stack([xs, np.zeros_like(xs), np.zeros_like(xs)]),
                   np.column_stack([xs + 0.5 / nx, np.full_like(xs, height), np.zeros_like(xs)])])
    i = np.arange(nx)
    F = np.vstack([np.column_stack([i, i + 1, nx + 1 + i]), np.column_stack([i + 1, nx + 2 + i, nx + 1 + i])])
    F = F.reshape(2, nx, 3).transpose(1, 0, 2).reshape(-1, 3)  # the two faces of a cell next to each other
    return TriMesh(V, F, name=f"needle strip (aspect {aspect:g})")


def delaunay_plane(k: int = 300, seed: int = 3) -> TriMesh:
    """The Delaunay triangulation of ``k`` uniform random points of the unit square (z = 0).

    Parameters
    ----------
    k : int
        Number of points (≥ 3).
    seed : int
        Seed of the points.

    Returns
    -------
    TriMesh
        ``k`` vertices, random slivers near the boundary included.
    """
    from scipy.spatial import Delaunay

    k = check_count(k, "k", minimum=3)
    P = np.random.default_rng(seed).random((k, 2))
    return TriMesh(np.c_[P, np.zeros(k)], Delaunay(P).simplices, name=f"random Delaunay ({k} points)")


def delaunay_grid(nx: int = 60, jitter: float = 0.3, seed: int = 1, *, fix_rows: tuple[float, ...] = ()) -> TriMesh:
    """The Delaunay triangulation of a jittered ``(nx + 1)²`` grid of the unit square (z = 0): faces of every
    orientation, no preferred direction, no slivers (the analytic tests of ``docs/metrics.md``).

    Parameters
    ----------
    nx : int
        Cells along each side.
    jitter : float
        Interior points move by up to ``jitter`` cells in x and y (:func:`grid_plane`).
    seed : int
    fix_rows : tuple of float
        Heights ``y`` (multiples of ``1/nx``) whose row of points keeps its height, so that the line ``y`` is made
        of edges (an interface between two media).

    Returns
    -------
    TriMesh
        ``(nx + 1)²`` vertices.
    """
    from scipy.spatial import Delaunay

    nx = check_count(nx, "nx", minimum=1)
    V = grid_plane(nx, jitter=jitter, seed=seed).V.copy()
    for y in fix_rows:
        if not np.isclose(y * nx, np.round(y * nx)):
            raise ValueError(f"fix_rows: {y} is not a multiple of 1/{nx}")
        V[np.round(V[:, 1] * nx) == np.round(y * nx), 1] = y  # jitter moves a point by less than half a cell
    F = Delaunay(V[:, :2]).simplices.astype(np.int64)
    e1, e2 = V[F[:, 1], :2] - V[F[:, 0], :2], V[F[:, 2], :2] - V[F[:, 0], :2]
    cw = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] < 0
    F[cw] = F[cw][:, [0, 2, 1]]  # every face counter-clockwise (+z)
    return TriMesh(V, F, name=f"jittered Delaunay grid {nx}x{nx}")


def fan_plate(k: int = 12) -> TriMesh:
    """A flat 2 × 1 CAD-style plate: ``k`` points on each long side, every face a fan from one of two corners.

    Vertices ``0 … k−1`` are the bottom row, ``k … 2k−1`` the top row; corner 0 fans to the top row and
    corner ``2k − 1`` to the bottom row, so the faces are long and thin (aspect above 20 for ``k = 12``).

    Parameters
    ----------
    k : int
        Points per long side (≥ 2).

    Returns
    -------
    TriMesh
        ``2k`` vertices, ``2(k − 1)`` faces in the plane z = 0.
    """
    k = check_count(k, "k", minimum=2)
    xs = np.linspace(0.0, 2.0, k)
    V = np.vstack([np.column_stack([xs, np.zeros(k), np.zeros(k)]), np.column_stack([xs, np.ones(k), np.zeros(k)])])
    i = np.arange(k - 1)
    F = np.vstack([np.column_stack([np.zeros(k - 1, dtype=np.int64), k + i + 1, k + i]),
                   np.column_stack([i, i + 1, np.full(k - 1, 2 * k - 1)])])
    F = F[(F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 0] != F[:, 2])]
    return TriMesh(V, F, name="CAD plate of fans")
