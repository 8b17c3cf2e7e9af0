"""A cheap distance field for the starting point: Dijkstra on the graph of the program's edge bounds.

Every constraint of a mesh problem bounds a difference of two values: a triangle cone ``‖B_t x_t‖ ≤ 1``
implies ``|x_a − x_b| ≤ ℓ_ab`` for each of its edges, with ``ℓ_ab = ‖(B_tB_tᵀ)⁻¹B_t(e_a − e_b)‖`` (the edge
length in the cone's own metric: ``x_a − x_b = wᵀB_t x`` for the ``w`` with ``B_tᵀw = e_a − e_b``), a pair
inequality ``c x_i − c x_j ≤ r`` bounds ``x_i − x_j`` by ``r / c``, and a one-variable bound ``c x_i ≤ r``
(``c > 0``) and a fixed value bound a value from above. The shortest-path field through these arcs from
the fixed variables (at their values) is the largest field meeting all of them, an upper bound of every
feasible field and close to the optimum: a far better primal start than ``x_F`` (all distances 0), once
scaled into the interior (:func:`.start.interior_primal`).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from . import _kernels as _kern
from .blocks import PairInequalityBlock, TriangleSOCBlock
from .program import Program

__all__ = ["edge_arcs", "graph_field"]

_EDGES = ((0, 1), (1, 2), (2, 0))


def _cone_arcs(b: TriangleSOCBlock) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Both directions of the three edges of every cone with their bound ``ℓ_ab`` (degenerate cones, whose
    ``B_tB_tᵀ`` is singular, give none)."""
    B = b.B  # (2, 3, k)
    g00 = (B[0] * B[0]).sum(axis=0)
    g01 = (B[0] * B[1]).sum(axis=0)
    g11 = (B[1] * B[1]).sum(axis=0)
    det = g00 * g11 - g01 * g01
    ok = det > 1e-14 * np.maximum(g00 * g11, 1e-300)
    src, dst, w = [], [], []
    for a, c in _EDGES:
        v0, v1 = B[0, a] - B[0, c], B[1, a] - B[1, c]
        with np.errstate(divide="ignore", invalid="ignore"):
            u0, u1 = (g11 * v0 - g01 * v1) / det, (g00 * v1 - g01 * v0) / det
        ell = np.hypot(u0, u1)
        keep = ok & np.isfinite(ell)
        ia, ic = b.cv[keep, a], b.cv[keep, c]
        src += [ia, ic]
        dst += [ic, ia]
        w += [ell[keep], ell[keep]]
    return np.concatenate(src), np.concatenate(dst), np.concatenate(w)


def _pair_arcs(b: PairInequalityBlock, root: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``c x_i − c x_j ≤ r`` as the arc ``j → i`` of weight ``r / c`` (``i → j`` when ``c < 0``); ``c x_i ≤ r``
    (``c > 0``) as ``root → i``. Other inequalities (lower bounds, unequal coefficients) bound no difference:
    left out."""
    iv, ia, r = b.iv, b.ia, b.rhs
    single = (iv[:, 0] == iv[:, 1]) | (ia[:, 1] == 0)
    c = ia[:, 0]
    diff = ~single & (c != 0) & (ia[:, 1] == -c)
    upper = single & (c > 0)
    head = np.where(c[diff] > 0, iv[diff, 0], iv[diff, 1])  # the variable bounded from above
    tail = np.where(c[diff] > 0, iv[diff, 1], iv[diff, 0])
    src = np.concatenate([tail, np.full(int(upper.sum()), root)])
    dst = np.concatenate([head, iv[upper, 0]])
    w = np.concatenate([r[diff] / np.abs(c[diff]), r[upper] / c[upper]])
    return src, dst, w


def edge_arcs(pr: Program) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """The arcs ``(src, dst, weight)`` meaning ``x[dst] ≤ x[src] + weight`` over the ``n + 1`` nodes (node ``n``
    the root, ``x = 0`` there), from every block and the fixed values; ``None`` when a block is of another
    kind (a general :class:`~.blocks.SparseBlock`: no field)."""
    n = pr.n
    parts = []
    for b in pr.blocks:
        if isinstance(b, TriangleSOCBlock):
            parts.append(_cone_arcs(b))
        elif isinstance(b, PairInequalityBlock):
            parts.append(_pair_arcs(b, n))
        else:
            return None
    fixed = np.flatnonzero(pr.fixed)
    parts.append((np.full(fixed.size, n), fixed, pr.x_fixed[fixed]))
    src, dst, w = (np.concatenate(p) for p in zip(*parts, strict=True))
    return src, dst, w


def graph_field(pr: Program) -> np.ndarray | None:
    """The largest field meeting the program's edge bounds (shortest paths from the fixed variables), (n,).

    ``None`` when the arcs do not give one: a block of another kind, a negative or non-finite bound (the
    fixed values are shifted to be nonnegative first), or a free variable that no path reaches.
    """
    arcs = edge_arcs(pr)
    if arcs is None:
        return None
    src, dst, w = arcs
    n = pr.n
    root = src == n
    offset = min(0.0, float(w[root].min())) if root.any() else 0.0
    w = np.where(root, w - offset, w)  # the root's arcs nonnegative; every path from it has one
    if w.size == 0 or not (np.isfinite(w).all() and (w >= 0).all()):
        return None
    # csgraph drops explicit zeros: a zero bound (two sources, a zero-length edge) becomes the smallest weight
    w = np.maximum(w, 1e-300)
    indptr = np.empty(n + 2, dtype=np.int32 if src.size < 2**31 else np.int64)
    indices = np.empty(src.size, dtype=indptr.dtype)
    data = np.empty(src.size)
    _kern.arcs_to_csr(src, dst, w, n + 1, indptr, indices, data)
    G = sp.csr_matrix((data, indices, indptr), shape=(n + 1, n + 1))
    d = dijkstra(G, directed=True, indices=n)[:n] + offset
    d[pr.fixed] = pr.x_fixed[pr.fixed]
    if not np.isfinite(d[pr.free]).all():
        return None
    return d
