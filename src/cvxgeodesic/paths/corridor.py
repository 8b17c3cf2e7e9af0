"""Shortest paths through a corridor of faces of a triangle mesh: the straightening of
:func:`cvxgeodesic.paths.geodesic_path` on surfaces.

The descent's path is a list of nodes: ``("v", vertex)``, ``("e", (a, c), face_in, face_out, position)`` (a
crossing of edge ``(a, c)``; ``face_in == face_out`` for a slide along it) and ``("p", face, position)``. Here the
vertices it passed through are opened into fans of edge crossings on the side of the smaller angle, each chain of
crossings is unfolded into the plane and replaced by the shortest path through it (the funnel algorithm; in a
medium, :meth:`~cvxgeodesic.operators.metric.Medium.least_crossings`), and where that path still wraps around a
vertex with the smaller angle on the other side, the corridor goes around that side (at most 64 rounds).

``geo`` is the descent's view of the mesh (:class:`cvxgeodesic.paths.Cells`): ``V``, ``C`` (the faces),
``cells_of(vertices)`` (the faces around an edge), ``bary(face, x)`` and ``mesh``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .cells import Cells

__all__ = ["straighten_corridor"]


def straighten_corridor(geo: Cells, nodes: list[tuple], medium: Any = None) -> list[tuple]:
    """The locally shortest path through the corridor of the descent's ``nodes`` (a new list; module docstring).

    Parameters
    ----------
    geo : Cells
        The descent's view of a triangle mesh.
    nodes : list of tuple
        The raw descent, from the target to the source.
    medium : Medium, optional
        A travel cost or metric on ``geo.mesh``: the path of least length in it.

    Returns
    -------
    list of tuple
        The nodes with the crossings moved (and vertices replaced by crossings around them).
    """
    nodes = _open_vertices(geo, nodes)
    for _ in range(64):
        _straighten(geo, nodes, medium)
        nodes, switched = _switch_sides(geo, nodes)
        if not switched:
            break
    return nodes


def node_position(geo: Cells, node: tuple) -> np.ndarray:
    """(3,) float ndarray: the position of a node of the path (module docstring)."""
    return geo.V[node[1]] if node[0] == "v" else node[-1]


def _segment_face(geo: Cells, a, b) -> int | None:
    """A face that contains the path segment between nodes ``a`` and ``b``."""
    if b[0] == "e":
        return b[2]
    if a[0] == "e":
        return a[3]
    if a[0] == "p":
        return a[1]
    if b[0] == "p":
        return b[1]
    shared = geo.cells_of((a[1], b[1]))  # an edge walk
    return int(shared[0]) if len(shared) else None


def _fan(geo: Cells, v: int, start: int, goal: int) -> list[tuple[list[int], list[int]]]:
    """The two walks around vertex ``v`` from face ``start`` to face ``goal``: (edge ends, faces) each."""
    F = geo.C
    walks = []
    for first in range(2):
        f = start
        others = [int(u) for u in F[f] if u != v]
        u = others[first]
        faces, ends = [f], []
        for _ in range(64):
            across = [int(h) for h in geo.cells_of((v, u)) if h != f]
            if len(across) != 1:
                break  # the boundary, or a non-manifold edge
            ends.append(u)
            f = across[0]
            faces.append(f)
            if f == goal:
                walks.append((ends, faces))
                break
            u = next(int(w) for w in F[f] if w != v and w != u)
    return walks


def _open_vertices(geo: Cells, nodes: list) -> list:
    """Replace each vertex the descent passed through by crossings of the edges around it.

    The crossings start at the vertex; :func:`_straighten` may then pull them off it, on the side of the
    smaller angle (where the straight line between the path's neighbours runs on a flat surface).
    """
    # the start of a valley (a point on an edge from which the descent slid along it) is in the face of the
    # crossing before it together with the vertex after it: the straight segment between those replaces it
    nodes = [nd for i, nd in enumerate(nodes) if i in (0, len(nodes) - 1) or not (nd[0] == "e" and nd[2] == nd[3])]
    out = [nodes[0]]
    for i in range(1, len(nodes) - 1):
        nd, walks = nodes[i], []
        if nd[0] == "v":
            f_in, f_out = _segment_face(geo, nodes[i - 1], nd), _segment_face(geo, nd, nodes[i + 1])
            if f_in is not None and f_out is not None and f_in != f_out:
                walks = _fan(geo, nd[1], f_in, f_out)
        if not walks:
            out.append(nd)
            continue
        q0, q1 = node_position(geo, nodes[i - 1]), node_position(geo, nodes[i + 1])
        angles = [_walk_angle(geo, nd[1], w, q0, q1) for w in walks]
        out.extend(_crossings(geo, nd[1], walks[int(np.argmin(angles))]))
    out.append(nodes[-1])
    return out


def _crossings(geo: Cells, u: int, walk: tuple[list[int], list[int]]) -> list[tuple]:
    """The edge crossings of a walk around vertex ``u``, placed near it (:func:`_straighten` moves them)."""
    ends, faces = walk
    return [("e", (u, w), faces[k], faces[k + 1], 0.7 * geo.V[u] + 0.3 * geo.V[w]) for k, w in enumerate(ends)]


def _corner(V, u, p, q) -> float:
    a, b = V[p] - V[u] if np.ndim(p) == 0 else p - V[u], V[q] - V[u] if np.ndim(q) == 0 else q - V[u]
    na, nb = np.linalg.norm(a), np.linalg.norm(b)
    if na == 0 or nb == 0:
        return 0.0
    return float(np.arccos(np.clip(a @ b / (na * nb), -1.0, 1.0)))


def _walk_angle(geo: Cells, u: int, walk, q0: np.ndarray, q1: np.ndarray) -> float:
    """Angle at ``u`` swept by a walk around it from the direction of ``q0`` to that of ``q1``."""
    V, F = geo.V, geo.C
    ends, faces = walk
    total = _corner(V, u, q0, V[ends[0]]) + _corner(V, u, V[ends[-1]], q1)
    for f in faces[1:-1]:
        a, b = [int(w) for w in F[f] if w != u]
        total += _corner(V, u, a, b)
    return total


def _switch_sides(geo: Cells, nodes: list) -> tuple[list, bool]:
    """Where the straightened path is held at a vertex, go around it on the side of the smaller angle.

    A run of crossings that all sit on one vertex means the shortest path through the current faces wraps
    around that vertex; if the angle on the other side is smaller, the path through the faces there is
    shorter (on a flat surface it is the straight line), so the run is replaced by the walk on that side.
    """
    V = geo.V
    tol = 1e-12 * geo.mesh.bbox_diagonal

    def held(nd):
        if nd[0] != "e" or nd[2] == nd[3]:
            return None
        for w in nd[1]:
            if np.linalg.norm(nd[-1] - V[w]) <= tol:
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
        f_in, f_out = run[0][2], run[-1][3]
        current = [run[0][2], *(r[3] for r in run)]
        q0, q1 = node_position(geo, out[-1]), node_position(geo, nodes[j + 1])
        walks = [w for w in _fan(geo, u, f_in, f_out) if w[1] != current] if f_in != f_out else []
        cur_walk = ([r[1][1] if r[1][0] == u else r[1][0] for r in run], current)
        if (walks and np.linalg.norm(q0 - V[u]) > tol and np.linalg.norm(q1 - V[u]) > tol
                and _walk_angle(geo, u, walks[0], q0, q1) < _walk_angle(geo, u, cur_walk, q0, q1) - 1e-9):
            out.extend(_crossings(geo, u, walks[0]))
            switched = True
        else:
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


def _chain_crossings(geo: Cells, q0: np.ndarray, chain: list, q1: np.ndarray) -> list[float]:
    """Shortest path from ``q0`` (in the first face) through the chain's edges to ``q1`` (in the last face): where
    it crosses each edge ``(a, c)``, as the parameter ``t`` of ``(1 − t) a + t c``."""
    V, F = geo.V, geo.C
    f0 = chain[0][2]
    tri = V[F[f0]]
    # 2D frame of the first face
    ex = tri[1] - tri[0]
    ex = ex / np.linalg.norm(ex)
    nrm = np.cross(tri[1] - tri[0], tri[2] - tri[0])
    ey = np.cross(nrm / np.linalg.norm(nrm), ex)
    pos2 = {int(F[f0, k]): np.array([(tri[k] - tri[0]) @ ex, (tri[k] - tri[0]) @ ey]) for k in range(3)}
    start = np.array([(q0 - tri[0]) @ ex, (q0 - tri[0]) @ ey])
    portals, flipped = [], []
    prev_face = f0
    for nd in chain:
        (a, c), f_out = nd[1], nd[3]
        pa, pc = pos2[a], pos2[c]
        o_prev = next(int(w) for w in F[prev_face] if w != a and w != c)
        ref = pos2[o_prev]
        o = next(int(w) for w in F[f_out] if w != a and w != c)
        po = _unfold_third(pa, pc, float(np.linalg.norm(V[o] - V[a])), float(np.linalg.norm(V[o] - V[c])), ref)
        pos2 = {a: pa, c: pc, o: po}
        # left / right as seen when entering f_out from prev_face: (a, c), or (c, a) when flipped
        flipped.append(not _cross(pc - ref, pa - ref) > 0)
        portals.append((pc, pa) if flipped[-1] else (pa, pc))
        prev_face = f_out
    # the end point, in the last face's unfolded position (barycentric coordinates carry over)
    fl = chain[-1][3]
    b = geo.bary(fl, q1)
    end = sum(b[k] * pos2[int(F[fl, k])] for k in range(3))
    corners, idx = _funnel(start, portals, end)
    out = []
    k = 0
    for j in range(1, len(chain) + 1):
        while idx[k + 1] < j:
            k += 1
        lft, rgt = portals[j - 1]
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
        out.append(1.0 - t if flipped[j - 1] else t)
    return out


def _straighten(geo: Cells, nodes: list, medium: Any = None) -> None:
    """Move every chain of edge crossings between two fixed nodes to the shortest path through its faces
    (in a medium: the path of least length in it, :meth:`~cvxgeodesic.operators.metric.Medium.least_crossings`)."""
    n = len(nodes)
    i = 1
    while i < n - 1:
        if not (nodes[i][0] == "e" and nodes[i][2] != nodes[i][3]):
            i += 1
            continue
        j = i
        while (j + 1 < n - 1 and nodes[j + 1][0] == "e" and nodes[j + 1][2] != nodes[j + 1][3]
               and nodes[j + 1][2] == nodes[j][3]):
            j += 1
        q0, q1 = node_position(geo, nodes[i - 1]), node_position(geo, nodes[j + 1])
        chain = nodes[i:j + 1]
        if medium is None:
            t = _chain_crossings(geo, q0, chain, q1)
        else:
            ends = np.array([nd[1] for nd in chain], dtype=np.int64)
            faces = np.array([chain[0][2], *(nd[3] for nd in chain)], dtype=np.int64)  # of the K + 1 pieces
            t = medium.least_crossings(q0, ends, faces, q1)
        if t is not None:
            nodes[i:j + 1] = [(*nd[:4], (1 - tk) * geo.V[nd[1][0]] + tk * geo.V[nd[1][1]])
                              for nd, tk in zip(chain, t, strict=True)]
        i = j + 1
