"""Compiled per-cone kernels of the interior-point solver (Numba).

Every SOC(3) cone of a mesh problem touches three vertices, so each step of an
interior-point iteration is a loop over cones with a handful of flops per cone.
Written as NumPy expressions these loops become many passes over (3, k) arrays
with a temporary each (about 30 ms per iteration on a 46K-face mesh); one
compiled loop per operation does the same work in one pass.

Conventions: an SOC(3) field over k cones is a (3, k) array (row 0 the heads), a
body field a (2, k) array; ``B`` is (2, 3, k) (``B[:, :, t]`` is the 2×3 block of
cone t) and ``cv`` (k, 3) its vertices. The Nesterov–Todd scaling is stored as
``w`` (3, k) (the scaling point w̄), ``eta`` and ``inv_eta2`` (k,) (η and 1/η²),
as in :class:`cvxgeodesic.solvers.ipm.cones._SocScaling`, whose formulas are CVXOPT's.

Loops without scatter (no two cones write the same entry) are written with ``prange`` but compiled
serially: a ``parallel=True`` kernel takes 2-4x longer to compile (the first solve of spot after an install:
qclp 4.6 s with parallel kernels, 2.6 s without; qcqp-hessian, with the curved Hessian energy's kernels of that day,
10.0 s against 5.5 s), and these loops are short (about 1 ms per call at 300K cones) and a few percent of a
solve: in QCLP solves with 2 threads of horse and armadillo (87-97K faces), all kernel calls took 0.21 s serial
against 0.26-0.41 s parallel (waking the threads for each short loop costs more than it saves), of 1.1-1.9 s
(measured 2026-12-02 on a 2-core machine shared with other jobs, load average about 2).

Compiled code is cached on disk (``cache=True``): the first solve after an install compiles for a few seconds
(announced by :mod:`cvxgeodesic._jit`), later processes load the cache in well under a second.
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from ..._jit import HELPER_OPTIONS as _HELPER  # helpers (``_w_apply``, ``_jdiv_winv``, the clique kernels' rows)
from ..._jit import KERNEL_OPTIONS as _JIT
from ..._jit import njit, prefer_openmp, watch_compiles  # njit: numba.njit, uncached where no cache is writable

watch_compiles()  # one line on stderr when a kernel compiles (a cold cache: the first run after installation)
prefer_openmp()  # Numba's thread pool shares PARDISO's OpenMP runtime
# NumPy calls: the kernels fill and copy arrays with loops, not np.full, np.zeros, np.cumsum, .copy() or a[:] = x: each
# such NumPy function is a generic implementation that Numba compiles too (a counting-sort kernel compiled in 0.25 s
# of CPU with loops against 0.8 s with np.cumsum and .copy(), the half-edge twins in 0.29 s against 0.51 s with
# np.full; an empty cache, 2026-12-06), for the same machine code in the end


@njit(**_JIT)
def nt_scaling(s, z, w, eta, inv_eta2, lam):
    """NT scaling of every pair (s_t, z_t) (both interior): fills ``w``, ``eta``, ``inv_eta2`` and ``λ = W z``."""
    for t in prange(s.shape[1]):
        s0, s1, s2 = s[0, t], s[1, t], s[2, t]
        z0, z1, z2 = z[0, t], z[1, t], z[2, t]
        ns = math.sqrt(s1 * s1 + s2 * s2)
        nz = math.sqrt(z1 * z1 + z2 * z2)
        sn = math.sqrt((s0 - ns) * (s0 + ns))
        zn = math.sqrt((z0 - nz) * (z0 + nz))
        sb0, sb1, sb2 = s0 / sn, s1 / sn, s2 / sn
        zb0, zb1, zb2 = z0 / zn, z1 / zn, z2 / zn
        gamma = math.sqrt(0.5 * (1.0 + sb0 * zb0 + sb1 * zb1 + sb2 * zb2))
        inv2g = 0.5 / gamma
        w[0, t] = (sb0 + zb0) * inv2g
        w[1, t] = (sb1 - zb1) * inv2g
        w[2, t] = (sb2 - zb2) * inv2g
        eta[t] = math.sqrt(sn / zn)
        inv_eta2[t] = zn / sn
        den = 1.0 / (sb0 + zb0 + 2.0 * gamma)
        scale = math.sqrt(sn * zn)
        lam[0, t] = gamma * scale
        lam[1, t] = ((gamma + zb0) * sb1 + (gamma + sb0) * zb1) * den * scale
        lam[2, t] = ((gamma + zb0) * sb2 + (gamma + sb0) * zb2) * den * scale


@njit(**_HELPER)
def _w_apply(w0, w1, w2, f, sign, v0, v1, v2):
    """One cone's ``f · W̄ v`` (``sign`` = +1) or ``f · W̄⁻¹ v`` (``sign`` = −1; ``W̄⁻¹ = J W̄ J``)."""
    w1v1 = w1 * v1 + w2 * v2
    c = sign * v0 + w1v1 / (1.0 + w0)
    return (w0 * v0 + sign * w1v1) * f, (v1 + c * w1) * f, (v2 + c * w2) * f


@njit(**_JIT)
def apply_w(w, eta, v, sign, out):
    """``out = W v`` (``sign`` = +1) or ``W⁻¹ v`` (``sign`` = −1)."""
    for t in prange(v.shape[1]):
        f = eta[t] if sign > 0 else 1.0 / eta[t]
        out[0, t], out[1, t], out[2, t] = _w_apply(w[0, t], w[1, t], w[2, t], f, sign, v[0, t], v[1, t], v[2, t])


@njit(**_JIT)
def apply_inv2(w, inv_eta2, v, out):
    """``out = W⁻² v = (2 v̂ (v̂ᵀv) − J v)/η²`` with ``v̂ = J w̄``."""
    for t in prange(v.shape[1]):
        w0, w1, w2 = w[0, t], w[1, t], w[2, t]
        v0, v1, v2 = v[0, t], v[1, t], v[2, t]
        a = 2.0 * (w0 * v0 - w1 * v1 - w2 * v2)
        f = inv_eta2[t]
        out[0, t] = (a * w0 - v0) * f
        out[1, t] = (v1 - a * w1) * f
        out[2, t] = (v2 - a * w2) * f


@njit(**_JIT)
def gather(B, cv, x, out):
    """``out[:, t] = B_t x[cv[t]]`` (2, k): the cone bodies of ``B x``."""
    for t in prange(cv.shape[0]):
        xa, xb, xc = x[cv[t, 0]], x[cv[t, 1]], x[cv[t, 2]]
        out[0, t] = B[0, 0, t] * xa + B[0, 1, t] * xb + B[0, 2, t] * xc
        out[1, t] = B[1, 0, t] * xa + B[1, 1, t] * xb + B[1, 2, t] * xc


@njit(**_JIT)
def scatter(B, cv, g, sign, out):
    """``out[cv[t]] += sign · B_tᵀ g[:, t]`` for every cone: ``out += sign · Bᵀ g``."""
    for t in range(cv.shape[0]):
        g0, g1 = sign * g[0, t], sign * g[1, t]
        for j in range(3):
            out[cv[t, j]] += B[0, j, t] * g0 + B[1, j, t] * g1


@njit(**_JIT)
def kkt_cones(B, cv, w, inv_eta2, v, out):
    """``out += Σ_t B_tᵀ [W_t⁻²]_body B_t v[cv[t]]`` with ``[W⁻²]_body g = (g + 2 w₁(w₁ᵀg))/η²``."""
    for t in range(cv.shape[0]):
        xa, xb, xc = v[cv[t, 0]], v[cv[t, 1]], v[cv[t, 2]]
        g0 = B[0, 0, t] * xa + B[0, 1, t] * xb + B[0, 2, t] * xc
        g1 = B[1, 0, t] * xa + B[1, 1, t] * xb + B[1, 2, t] * xc
        w1, w2 = w[1, t], w[2, t]
        a = 2.0 * (w1 * g0 + w2 * g1)
        f = inv_eta2[t]
        h0 = (g0 + a * w1) * f
        h1 = (g1 + a * w2) * f
        for j in range(3):
            out[cv[t, j]] += B[0, j, t] * h0 + B[1, j, t] * h1


@njit(**_JIT)
def assemble_cones(B, btb, w, inv_eta2, pos, data):
    """``data[pos] += (B_tᵀB_t + 2 (B_tᵀw̄₁)(B_tᵀw̄₁)ᵀ)/η²`` for the 6 lower-triangle clique entries of each cone.

    ``btb`` (6, k) holds ``B_tᵀB_t`` and ``pos`` (6·k,) the data positions, clique-entry-major
    (entry e of cone t at ``e·k + t``), entries ordered (0,0), (1,1), (2,2), (1,0), (2,0), (2,1).
    """
    k = B.shape[2]
    for t in range(k):
        w1, w2 = w[1, t], w[2, t]
        v0 = B[0, 0, t] * w1 + B[1, 0, t] * w2
        v1 = B[0, 1, t] * w1 + B[1, 1, t] * w2
        v2 = B[0, 2, t] * w1 + B[1, 2, t] * w2
        f = inv_eta2[t]
        data[pos[t]] += (btb[0, t] + 2.0 * v0 * v0) * f
        data[pos[k + t]] += (btb[1, t] + 2.0 * v1 * v1) * f
        data[pos[2 * k + t]] += (btb[2, t] + 2.0 * v2 * v2) * f
        data[pos[3 * k + t]] += (btb[3, t] + 2.0 * v1 * v0) * f
        data[pos[4 * k + t]] += (btb[4, t] + 2.0 * v2 * v0) * f
        data[pos[5 * k + t]] += (btb[5, t] + 2.0 * v2 * v1) * f


@njit(**_JIT)
def scatter_add(values, pos, data):
    """``data[pos[i]] += values[i]`` (repeated positions accumulate)."""
    for i in range(pos.shape[0]):
        data[pos[i]] += values[i]


@njit(**_JIT)
def soc_step_bounds(u, du, out):
    """``out[t]``: the reciprocal of cone ``t``'s largest step (:func:`._clique_kernels.max_step`)."""
    for t in prange(u.shape[1]):
        u0, u1, u2 = u[0, t], u[1, t], u[2, t]
        nb = math.sqrt(u1 * u1 + u2 * u2)
        det = (u0 - nb) * (u0 + nb)
        lk = math.sqrt(det)
        inv_det = 1.0 / det
        rho0 = (u0 * du[0, t] - u1 * du[1, t] - u2 * du[2, t]) * inv_det
        c = (rho0 * lk + du[0, t]) / (u0 + lk)
        r1 = du[1, t] - c * u1
        r2 = du[2, t] - c * u2
        out[t] = math.sqrt((r1 * r1 + r2 * r2) * inv_det) - rho0


@njit(**_JIT)
def max_step_lp(u, du):
    """Largest ``α`` with ``u + α du ≥ 0`` (``inf`` if unbounded); ``u > 0``."""
    best = np.inf
    for i in range(u.shape[0]):
        if du[i] < 0:
            a = -u[i] / du[i]
            if a < best:
                best = a
    return best


@njit(**_JIT)
def newton_cones(g, w, inv_eta2, wu, wrc, rzc, dz, ds):
    """Cone parts of a Newton direction from ``g = B Δx``.

    ``Δz = W⁻² (0, −g) + wu + W⁻² r_z`` (``wrc`` holds ``W⁻² r_z``) and ``Δs = −r_z + (0, g)``.
    """
    for t in prange(g.shape[1]):
        g0, g1 = g[0, t], g[1, t]
        w0, w1, w2 = w[0, t], w[1, t], w[2, t]
        a = 2.0 * (w1 * g0 + w2 * g1)
        f = inv_eta2[t]
        dz[0, t] = a * w0 * f + wu[0, t] + wrc[0, t]
        dz[1, t] = (-g0 - a * w1) * f + wu[1, t] + wrc[1, t]
        dz[2, t] = (-g1 - a * w2) * f + wu[2, t] + wrc[2, t]
        ds[0, t] = -rzc[0, t]
        ds[1, t] = -rzc[1, t] + g0
        ds[2, t] = -rzc[2, t] + g1


@njit(**_HELPER)
def _jdiv_winv(w0, w1, w2, inv_eta, l0, l1, l2, d0, d1, d2):
    """``W⁻¹ (λ \\ d)``."""
    nl = math.sqrt(l1 * l1 + l2 * l2)
    x0 = (l0 * d0 - l1 * d1 - l2 * d2) / ((l0 - nl) * (l0 + nl))
    x1 = (d1 - x0 * l1) / l0
    x2 = (d2 - x0 * l2) / l0
    return _w_apply(w0, w1, w2, inv_eta, -1.0, x0, x1, x2)


@njit(**_JIT)
def mehrotra_cones(w, eta, lam, ds_a, dz_a, z, sigma_mu, out):
    """Combined-step term ``out = −z − W⁻¹(λ \\ ((W⁻¹Δs_a)∘(WΔz_a) − σμe))`` of every cone."""
    for t in prange(z.shape[1]):
        w0, w1, w2 = w[0, t], w[1, t], w[2, t]
        e = eta[t]
        a0, a1, a2 = _w_apply(w0, w1, w2, 1.0 / e, -1.0, ds_a[0, t], ds_a[1, t], ds_a[2, t])
        b0, b1, b2 = _w_apply(w0, w1, w2, e, 1.0, dz_a[0, t], dz_a[1, t], dz_a[2, t])
        c0 = a0 * b0 + a1 * b1 + a2 * b2 - sigma_mu
        c1 = a0 * b1 + b0 * a1
        c2 = a0 * b2 + b0 * a2
        r0, r1, r2 = _jdiv_winv(w0, w1, w2, 1.0 / e, lam[0, t], lam[1, t], lam[2, t], c0, c1, c2)
        out[0, t] = -z[0, t] - r0
        out[1, t] = -z[1, t] - r1
        out[2, t] = -z[2, t] - r2


@njit(**_JIT)
def gondzio_cones(w, eta, lam, s, ds, tp, z, dz, td, lo, hi, out):
    """Gondzio's corrector term ``out = W⁻¹(λ \\ c)`` of every cone.

    At the trial point ``(s + tp·Δs, z + td·Δz)`` the two eigenvalues of the scaled
    complementarity product ``(W⁻¹s)∘(Wz)`` are moved into ``[lo, hi]``: ``c`` is that move
    (each eigenvalue's decrease bounded by ``hi``), expressed in the product's Jordan frame.
    """
    for t in prange(z.shape[1]):
        w0, w1, w2 = w[0, t], w[1, t], w[2, t]
        e = eta[t]
        a0, a1, a2 = _w_apply(w0, w1, w2, 1.0 / e, -1.0, s[0, t] + tp * ds[0, t], s[1, t] + tp * ds[1, t],
                              s[2, t] + tp * ds[2, t])
        b0, b1, b2 = _w_apply(w0, w1, w2, e, 1.0, z[0, t] + td * dz[0, t], z[1, t] + td * dz[1, t],
                              z[2, t] + td * dz[2, t])
        v0 = a0 * b0 + a1 * b1 + a2 * b2
        v1 = a0 * b1 + b0 * a1
        v2 = a0 * b2 + b0 * a2
        nv = math.sqrt(v1 * v1 + v2 * v2)
        e1, e2 = v0 - nv, v0 + nv
        t1 = max(min(max(e1, lo), hi) - e1, -hi)
        t2 = max(min(max(e2, lo), hi) - e2, -hi)
        u1, u2 = (v1 / nv, v2 / nv) if nv > 0 else (0.0, 0.0)
        c0 = 0.5 * (t1 + t2)
        c1 = 0.5 * (t2 - t1) * u1
        c2 = 0.5 * (t2 - t1) * u2
        out[0, t], out[1, t], out[2, t] = _jdiv_winv(w0, w1, w2, 1.0 / e, lam[0, t], lam[1, t], lam[2, t], c0, c1,
                                                     c2)


@njit(**_JIT)
def find_positions(indptr, indices, rows, cols, out):
    """``out[i]`` = position of entry (rows[i], cols[i]) in the lower-triangular CSC structure (binary search
    in its column); returns the first ``i`` not in the pattern, or −1.

    The compiled twin of :meth:`cvxgeodesic.linalg.SymbolicCholesky.positions` (NumPy/SciPy there, since that
    layer does without Numba): every solve maps its cliques onto the pattern, 7.8 ms against 12.3 ms for
    bimba's 277K clique entries (2026-12-01, shared 2-core machine).
    """
    n = indptr.shape[0] - 1
    for i in range(rows.shape[0]):
        r, c = rows[i], cols[i]
        if r < c:
            r, c = c, r
        if c < 0 or r >= n:
            return i
        lo, hi = indptr[c], indptr[c + 1]
        while lo < hi:
            mid = (lo + hi) // 2
            if indices[mid] < r:
                lo = mid + 1
            else:
                hi = mid
        if lo >= indptr[c + 1] or indices[lo] != r:
            return i
        out[i] = lo
    return -1


def positions(chol, rows, cols):
    """:meth:`SymbolicCholesky.positions <cvxgeodesic.linalg.SymbolicCholesky.positions>` with the compiled
    search: (N,) int64 positions of the entries ``(rows[i], cols[i])``; ValueError naming the first entry that
    is not in the pattern."""
    rows = np.ascontiguousarray(rows, dtype=np.int64).ravel()
    cols = np.ascontiguousarray(cols, dtype=np.int64).ravel()
    out = np.empty(rows.size, dtype=np.int64)
    bad = find_positions(chol.indptr, chol.indices, rows, cols, out)
    if bad >= 0:
        raise ValueError(f"entry ({rows[bad]}, {cols[bad]}) is not in the sparsity pattern")
    return out


@njit(**_JIT)
def arcs_to_csr(src, dst, w, n_nodes, indptr, indices, data):
    """Counting sort of arcs by ``src`` into CSR arrays (``indptr`` (n_nodes + 1,), ``indices`` and ``data``
    (m,)), duplicates kept: parallel arcs are harmless to a shortest-path search, and an O(m) pass replaces a
    sort (the graph start's lexsort took 3 s of a 280K-face solve's start, this takes milliseconds)."""
    for i in range(indptr.size):  # loops, not indptr[:] = 0 and .copy() (NumPy calls, above)
        indptr[i] = 0
    for a in range(src.size):
        indptr[src[a] + 1] += 1
    for i in range(n_nodes):
        indptr[i + 1] += indptr[i]
    fill = np.empty(n_nodes, dtype=np.int64)
    for i in range(n_nodes):
        fill[i] = indptr[i]
    for a in range(src.size):
        k = fill[src[a]]
        indices[k] = dst[a]
        data[k] = w[a]
        fill[src[a]] = k + 1
