"""Compiled assembly of the curved Hessian energy (Numba): libigl's matrix, face by face.

libigl's ``curved_hessian_energy`` (Stein et al. 2020) builds four sparse matrices on the
Crouzeix–Raviart vector space (two unknowns per edge) and multiplies them,
``Q = Dᵀ M⁻¹ (L + K) M⁻¹ D``, in Eigen: four sparse–sparse products, single-threaded, with large
temporaries. That was the largest piece of a one-shot QCQP-Hessian set-up (measured 2026-12-01,
shared 2-core machine: 43–48 % of the set-up of bimba, horse, armadillo and of a 1.1M-face bunny,
23 s there; docs/dev/performance-log.md, "Set-up cost").

The same matrix is a sum over faces. ``L + K`` couples only the edges of one face, and a row of
``G = M⁻¹ D`` (one edge unknown) involves only the four vertices of the edge's two faces, so
``Q = Σ_f G_fᵀ (L + K)_f G_f`` with ``G_f`` the 6 × 6 block of ``G`` on the face's six edge
unknowns and its six vertices (its corners and the three vertices across its edges). Here each
face's 6 × 6 block is computed in one compiled pass and the blocks are summed row by row into the
pattern of ``Q`` (the union of the blocks' cliques, which is the structural pattern of libigl's
product). The formulas are libigl's (``scalar_to_cr_vector_gradient``, ``cr_vector_mass``,
``cr_vector_laplacian``, ``cr_vector_curvature_correction``, ``orient_halfedges``, with its
conventions: edge ``e`` of a face is opposite corner ``e``, an edge unknown's sign is + when the
half-edge runs from the lower to the higher vertex index, the angle defect is 0 on boundary
vertices); the result equals libigl's to rounding (``tests/test_operators.py``).

Conventions: ``F`` (m, 3) int64, ``E`` (m, 3) int64 (the edge opposite each corner, as
:attr:`~cvxgeodesic.mesh.TriMesh.cell_edges`), ``twin`` (3m,) the other half-edge ``3 f' + e'`` of
each half-edge ``3 f + e`` (−1 on the boundary).
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from .._jit import HELPER_OPTIONS as _HELPER
from .._jit import KERNEL_OPTIONS as _JIT
from .._jit import njit, prefer_openmp, watch_compiles  # njit: numba.njit, uncached where no cache is writable

watch_compiles()  # one line on stderr when a kernel compiles (a cold cache: the first run after installation)
prefer_openmp()  # the solver's threading layer, for a process that builds an energy before it imports the solver

# Serial, although the face and row loops are written with prange and have no conflicting writes: parallel=True
# doubles these kernels' compile time (the first QCQP-Hessian set-up of spot after an install: 3.1 s serial
# against 5.3-5.9 s), and the four loops take about 80 ms of a 0.5 s set-up of a 97K-face mesh (face_blocks 23 ms,
# gather_rows 43 ms; the same with 2 threads parallel on a 2-core machine shared with other jobs, 2026-12-02).
# The options (_JIT, _HELPER) are the package's (cvxgeodesic._jit.KERNEL_OPTIONS, HELPER_OPTIONS).


@njit(**_JIT)
def twins(E, n_edges):
    """(3m,) int64: the other half-edge of each half-edge's edge, −1 where the edge has one face."""
    first, second = _minus_ones(n_edges), _minus_ones(n_edges)
    m = E.shape[0]
    for h in range(3 * m):
        e = E[h // 3, h % 3]
        if first[e] < 0:
            first[e] = h
        else:
            second[e] = h
    out = np.empty(3 * m, dtype=np.int64)
    for h in range(3 * m):
        e = E[h // 3, h % 3]
        out[h] = second[e] if first[e] == h else first[e]
    return out


@njit(**_HELPER)
def _minus_ones(n):
    """(n,) int64 of −1: a loop, not np.full, whose generic implementation compiles too
    (see the note on NumPy calls in solvers/ipm/_kernels.py)."""
    out = np.empty(n, dtype=np.int64)
    for i in range(n):
        out[i] = -1
    return out


@njit(**_JIT)
def face_geometry(V, F, lsq, dA, theta):
    """Squared edge lengths ``lsq`` (m, 3), double areas ``dA`` (m,) (Kahan's Heron formula, 0 where it has no
    real value) and corner angles ``theta`` (m, 3) of every face, from the edge lengths as libigl does."""
    for f in prange(F.shape[0]):
        for e in range(3):
            a, b = F[f, (e + 1) % 3], F[f, (e + 2) % 3]
            lsq[f, e] = (V[a, 0] - V[b, 0]) ** 2 + (V[a, 1] - V[b, 1]) ** 2 + (V[a, 2] - V[b, 2]) ** 2
        x, y, z = math.sqrt(lsq[f, 0]), math.sqrt(lsq[f, 1]), math.sqrt(lsq[f, 2])
        # sorted a >= b >= c (exact: max, the median of three, min)
        a1, b1, c1 = max(x, y, z), max(min(x, y), min(max(x, y), z)), min(x, y, z)
        arg = (a1 + (b1 + c1)) * (c1 - (a1 - b1)) * (c1 + (a1 - b1)) * (a1 + (b1 - c1))
        dA[f] = 0.5 * math.sqrt(arg) if arg >= 0.0 else 0.0
        for d in range(3):
            s1, s2, s3 = lsq[f, d], lsq[f, (d + 1) % 3], lsq[f, (d + 2) % 3]
            theta[f, d] = math.acos((s3 + s2 - s1) / (2.0 * math.sqrt(s3 * s2)))


@njit(**_HELPER)
def _gradient_rows(F, lsq, dA, h):
    """libigl's ``scalar_to_cr_vector_gradient`` entries of half-edge ``h`` = 3 f + e: (par_i, par_j, perp_i,
    perp_j, perp_k) with i, j, k = F[f, e+1], F[f, e+2], F[f, e]."""
    f, e = h // 3, h % 3
    i, j = F[f, (e + 1) % 3], F[f, (e + 2) % 3]
    o = 1.0 if i < j else -1.0
    eij, ejk, eki = lsq[f, e], lsq[f, (e + 1) % 3], lsq[f, (e + 2) % 3]
    s = math.sqrt(eij)
    return (-o * dA[f] / (6.0 * s), o * dA[f] / (6.0 * s), -o * (eij + ejk - eki) / (12.0 * s),
            -o * (eij - ejk + eki) / (12.0 * s), o * s / 6.0)


# faces per parallel chunk: the scratch arrays are allocated once per chunk, not once per face. Not sensitive:
# measured on horse (97K faces, 2 threads, load 2.4-3.6, 5 alternating runs) 512, 4096 and 32768 faces gave
# 48-63 ms for face_blocks, within the noise
_CHUNK = 4096


@njit(**_JIT)
def face_blocks(F, E, twin, lsq, dA, theta, minv, sk, blocks, verts):
    """Each face's 6 × 6 block ``G_fᵀ (L + K)_f G_f`` of ``Q`` (symmetrized) into ``blocks`` (m, 6, 6), on the
    vertices ``verts`` (m, 6): the corners, then the vertex across each edge (−1 on the boundary).

    ``minv`` (n_edges,): inverse Crouzeix–Raviart mass per edge (0 where it is 0); ``sk`` (n,): angle defect
    divided by the angle sum per vertex (0 on boundary vertices).
    """
    m = F.shape[0]
    for chunk in prange((m + _CHUNK - 1) // _CHUNK):
        C = np.empty((6, 6))  # rows: unknowns par_0..2, perp_0..2; columns: verts[f]
        LK = np.empty((6, 6))
        T = np.empty((6, 6))
        for f in range(chunk * _CHUNK, min(m, (chunk + 1) * _CHUNK)):
            for r in range(6):  # not C[:] = 0.0 (see the note on NumPy calls in solvers/ipm/_kernels.py)
                for c in range(6):
                    C[r, c] = 0.0
                    LK[r, c] = 0.0
            _gradient_block(F, E, twin, lsq, dA, minv, f, C, verts)
            _laplacian_block(F, lsq, dA, theta, sk, f, LK)
            for r in range(6):  # T = LK C
                for c in range(6):
                    acc = 0.0
                    for x in range(6):
                        acc += LK[r, x] * C[x, c]
                    T[r, c] = acc
            for r in range(6):  # blocks = Cᵀ T, symmetrized
                for c in range(r, 6):
                    acc1 = 0.0
                    acc2 = 0.0
                    for x in range(6):
                        acc1 += C[x, r] * T[x, c]
                        acc2 += C[x, c] * T[x, r]
                    blocks[f, r, c] = blocks[f, c, r] = 0.5 * (acc1 + acc2)


@njit(**_HELPER)
def _gradient_block(F, E, twin, lsq, dA, minv, f, C, verts):
    """Rows of ``G = M⁻¹ D`` on the six edge unknowns of face f, columns ``verts[f]`` (filled here)."""
    for e in range(3):
        verts[f, e] = F[f, e]
        h = 3 * f + e
        t = twin[h]
        w = minv[E[f, e]]
        pi, pj, qi, qj, qk = _gradient_rows(F, lsq, dA, h)
        a, b = (e + 1) % 3, (e + 2) % 3  # local corners of i and j
        C[e, a] += w * pi
        C[e, b] += w * pj
        C[3 + e, a] += w * qi
        C[3 + e, b] += w * qj
        C[3 + e, e] += w * qk
        if t >= 0:
            g, ge = t // 3, t % 3
            verts[f, 3 + e] = F[g, ge]
            tpi, tpj, tqi, tqj, tqk = _gradient_rows(F, lsq, dA, t)
            if F[g, (ge + 1) % 3] != F[f, a]:  # the twin runs the other way: its i is our j
                tpi, tpj, tqi, tqj = tpj, tpi, tqj, tqi
            C[e, a] += w * tpi
            C[e, b] += w * tpj
            C[3 + e, a] += w * tqi
            C[3 + e, b] += w * tqj
            C[3 + e, 3 + e] += w * tqk
        else:
            verts[f, 3 + e] = -1


@njit(**_HELPER)
def _laplacian_block(F, lsq, dA, theta, sk, f, LK):
    """libigl's ``cr_vector_laplacian`` plus ``cr_vector_curvature_correction`` on the edge unknowns of face f."""
    for e in range(3):
        e2 = (e + 2) % 3
        i, j, k = F[f, (e + 1) % 3], F[f, (e + 2) % 3], F[f, e]
        o2 = (1.0 if i < j else -1.0) * (1.0 if k < i else -1.0)
        eij, ejk, eki = lsq[f, e], lsq[f, (e + 1) % 3], lsq[f, (e + 2) % 3]
        lens = math.sqrt(eij * eki)
        q = eij - ejk + eki
        ki, kj, kk = sk[i] * theta[f, (e + 1) % 3], sk[j] * theta[f, (e + 2) % 3], sk[k] * theta[f, e]
        diag = 2.0 / dA[f] * eij + (ki + kj + kk)
        par = o2 * q * q / (2.0 * lens * dA[f]) - o2 * (ki - kj - kk) * (q / (2.0 * lens))
        perp = -o2 * q / lens + o2 * (ki - kj - kk) * math.sqrt(1.0 - q * q / (4.0 * eij * eki))
        LK[e, e] += diag
        LK[3 + e, 3 + e] += diag
        LK[e, e2] += par
        LK[e2, e] += par
        LK[3 + e, 3 + e2] += par
        LK[3 + e2, 3 + e] += par
        LK[e, 3 + e2] += perp
        LK[3 + e2, e] += perp
        LK[3 + e, e2] -= perp
        LK[e2, 3 + e] -= perp


@njit(**_JIT)
def vertex_slots(verts, n):
    """CSR (indptr (n+1,), slots) of the (face, slot) pairs, coded ``6 f + a``, where ``verts[f, a]`` is
    vertex u, in face order."""
    indptr = np.empty(n + 1, dtype=np.int64)
    for v in range(n + 1):  # loops, not np.zeros, np.cumsum, .copy() (NumPy calls: ipm/_kernels.py)
        indptr[v] = 0
    m = verts.shape[0]
    for f in range(m):
        for a in range(6):
            v = verts[f, a]
            if v >= 0:
                indptr[v + 1] += 1
    for v in range(n):
        indptr[v + 1] += indptr[v]
    fill = np.empty(n, dtype=np.int64)
    for v in range(n):
        fill[v] = indptr[v]
    slots = np.empty(indptr[n], dtype=np.int64)
    for f in range(m):
        for a in range(6):
            v = verts[f, a]
            if v >= 0:
                slots[fill[v]] = 6 * f + a
                fill[v] += 1
    return indptr, slots


# rows are split into at most this many parallel ranges, each with two (n,) scratch arrays (so few, large ones).
# Not sensitive: measured as _CHUNK above, 4, 16 and 64 ranges gave 102-127 ms for the two row passes
_ROW_RANGES = 16


@njit(**_HELPER)
def _row_columns(u, verts, slot_ptr, slots, seen, cols):
    """The distinct columns of row u into ``cols`` (in order of appearance); ``seen[v] == u`` marks them.
    Returns their count."""
    k = 0
    for s in range(slot_ptr[u], slot_ptr[u + 1]):
        f = slots[s] // 6
        for b in range(6):
            v = verts[f, b]
            if v >= 0 and seen[v] != u:
                seen[v] = u
                cols[k] = v
                k += 1
    return k


@njit(**_JIT)
def row_lengths(verts, slot_ptr, slots, width, length):
    """Number of distinct columns of each row of ``Q`` into ``length`` (n,); ``width`` bounds it."""
    n = slot_ptr.size - 1
    step = max(1, (n + _ROW_RANGES - 1) // _ROW_RANGES)
    for r in prange((n + step - 1) // step):
        seen = _minus_ones(n)
        cols = np.empty(width, dtype=np.int64)
        for u in range(r * step, min(n, (r + 1) * step)):
            length[u] = _row_columns(u, verts, slot_ptr, slots, seen, cols)


@njit(**_JIT)
def gather_rows(verts, blocks, slot_ptr, slots, width, indptr, indices, data):
    """Row u of ``Q``: its sorted distinct columns into ``indices[indptr[u]:indptr[u+1]]`` and the sum of the
    blocks' entries into ``data``, in face order (rows are independent: parallel without conflicts)."""
    n = slot_ptr.size - 1
    step = max(1, (n + _ROW_RANGES - 1) // _ROW_RANGES)
    for r in prange((n + step - 1) // step):
        seen = _minus_ones(n)
        where = np.empty(n, dtype=np.int64)  # column v of the current row is at indices[p + where[v]]
        cols = np.empty(width, dtype=np.int64)
        for u in range(r * step, min(n, (r + 1) * step)):
            k = _row_columns(u, verts, slot_ptr, slots, seen, cols)
            for x in range(1, k):  # insertion sort: rows have about 20 columns
                v = cols[x]
                y = x
                while y > 0 and cols[y - 1] > v:
                    cols[y] = cols[y - 1]
                    y -= 1
                cols[y] = v
            p = indptr[u]
            for x in range(k):
                indices[p + x] = cols[x]
                where[cols[x]] = x
            for s in range(slot_ptr[u], slot_ptr[u + 1]):
                f, a = slots[s] // 6, slots[s] % 6
                for b in range(6):
                    v = verts[f, b]
                    if v >= 0:
                        data[p + where[v]] += blocks[f, a, b]
