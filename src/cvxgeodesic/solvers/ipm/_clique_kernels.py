"""Compiled kernels of second-order cones of any dimension on cliques of variables (Numba).

The cones of :class:`~cvxgeodesic.solvers.ipm.blocks.CliqueSOCBlock`: ``s_t = h_t − G_t x[dofs_t] ∈ SOC(d)``
with ``G`` (k, d, c) (each cone's block contiguous: the loops are bound by reading it) and ``dofs`` (k, c): the
six P2 nodes of a face at order 2 (``d = 4``), a tetrahedron's four vertices (``d = 4``), ten P2 nodes of a
tetrahedron (``d = 5``). Fields over the cones are (d, k) arrays, row 0 the heads, as everywhere in
:mod:`..cones`; the Nesterov–Todd scaling is ``w`` (d, k) (the scaling point w̄, ``w̄ᵀJw̄ = 1``), ``eta`` and
``inv_eta2`` (k,), CVXOPT's formulas (the SOC(3) kernels of :mod:`._kernels` are the same, unrolled).

Per-cone work that needs a temporary vector writes it into the output column or a caller's work array, so no
kernel allocates inside its loop. SOC(4), the order-2 surface cones and the order-1 tetrahedron cones, has its cone
algebra unrolled (the ``*4`` kernels): with a trip count known at compile time the loops over cones vectorize, and
Gondzio's term measured 0.08 ms against 1.6 ms for the generic loop over 21K cones (2026-12-02, one thread).
Every kernel is serial (``_JIT``): waking threads for loops this short cost more than they saved in whole solves
(``_kernels``' measurement), and parallel kernels compile 2–4× slower.
"""

from __future__ import annotations

import math

import numpy as np

from ..._jit import njit  # numba.njit, uncached where no cache location is writable

# importing the SOC(3) kernels first selects Numba's threading layer (OpenMP, shared with MKL PARDISO)
from ._kernels import _HELPER, _JIT, soc_step_bounds

__all__ = ["assemble", "assemble4", "gather", "gather4", "gondzio", "gondzio4", "kkt", "kkt4", "max_step", "mehrotra",
           "mehrotra4", "nt_scaling", "nt_scaling4", "scatter", "scatter4", "w_apply", "w_apply4", "winv2_apply",
           "winv2_apply4"]


# ------------------------------------------------------------------------------ SOC(d), row by row
# Each kernel makes a few passes over the (d, k) fields, every inner loop running over the cones of one row: those
# loops vectorize. Per-cone loops over a trip count known only at run time did not (Gondzio's term over 21K
# SOC(5) cones: 11.5 ms per cone against 0.94 ms in passes, 2026-12-02).
@njit(**_HELPER)
def _dot_body(a, b, out):
    """``out[t] = Σ_{i ≥ 1} a[i, t] b[i, t]``."""
    d, k = a.shape
    for t in range(k):  # not out[:] = 0.0 (see the note on NumPy calls in solvers/ipm/_kernels.py)
        out[t] = 0.0
    for i in range(1, d):
        for t in range(k):
            out[t] += a[i, t] * b[i, t]


@njit(**_HELPER)
def _w_rows(w, f, sign, v, out, tmp):
    """``out = f · W̄ v`` (``sign`` = +1) or ``f · W̄⁻¹ v`` (``sign`` = −1), ``f`` (k,); may alias; ``tmp`` (k,)."""
    d, k = v.shape
    _dot_body(w, v, tmp)
    for t in range(k):
        v0 = v[0, t]
        c = sign * v0 + tmp[t] / (1.0 + w[0, t])
        out[0, t] = (w[0, t] * v0 + sign * tmp[t]) * f[t]
        tmp[t] = c
    for i in range(1, d):
        for t in range(k):
            out[i, t] = (v[i, t] + tmp[t] * w[i, t]) * f[t]


@njit(**_HELPER)
def _jprod_rows(a, b, out, tmp):
    """``out = a ∘ b`` (Jordan product); may alias ``a``; ``tmp`` (k,)."""
    d, k = a.shape
    _dot_body(a, b, tmp)
    for t in range(k):
        tmp[t] += a[0, t] * b[0, t]
    for i in range(1, d):
        for t in range(k):
            out[i, t] = a[0, t] * b[i, t] + b[0, t] * a[i, t]
    for t in range(k):
        out[0, t] = tmp[t]


@njit(**_HELPER)
def _jdiv_rows(lam, u, tmp, tmp2):
    """``u = λ \\ u`` in place (the ``x`` with ``λ ∘ x = u``; λ interior)."""
    d, k = lam.shape
    _dot_body(lam, lam, tmp)
    _dot_body(lam, u, tmp2)
    for t in range(k):
        l0 = lam[0, t]
        nl = math.sqrt(tmp[t])
        tmp[t] = (l0 * u[0, t] - tmp2[t]) / ((l0 - nl) * (l0 + nl))
        u[0, t] = tmp[t]
    for i in range(1, d):
        for t in range(k):
            u[i, t] = (u[i, t] - tmp[t] * lam[i, t]) / lam[0, t]


# ------------------------------------------------------------------------------ cone algebra over a block
@njit(**_JIT)
def nt_scaling(s, z, w, eta, inv_eta2, lam):
    """NT scaling of every pair (s_t, z_t) (both interior): fills ``w``, ``eta``, ``inv_eta2`` and ``λ = W z``."""
    d, k = s.shape
    sn, zn, gamma = np.empty(k), np.empty(k), np.empty(k)
    _dot_body(s, s, sn)
    _dot_body(z, z, zn)
    for t in range(k):
        ns, nz = math.sqrt(sn[t]), math.sqrt(zn[t])
        # (u0 − ‖u1‖)(u0 + ‖u1‖) loses less to cancellation next to the boundary than u0² − ‖u1‖²
        sn[t] = math.sqrt(max((s[0, t] - ns) * (s[0, t] + ns), 1e-300))
        zn[t] = math.sqrt(max((z[0, t] - nz) * (z[0, t] + nz), 1e-300))
    _dot_body(s, z, gamma)
    for t in range(k):
        gamma[t] = math.sqrt(0.5 * (1.0 + (gamma[t] + s[0, t] * z[0, t]) / (sn[t] * zn[t])))
        sb0, zb0 = s[0, t] / sn[t], z[0, t] / zn[t]
        w[0, t] = (sb0 + zb0) / (2.0 * gamma[t])
        eta[t] = math.sqrt(sn[t] / zn[t])
        inv_eta2[t] = zn[t] / sn[t]
        lam[0, t] = gamma[t] * math.sqrt(sn[t] * zn[t])
    for i in range(1, d):
        for t in range(k):
            sb0, zb0, g = s[0, t] / sn[t], z[0, t] / zn[t], gamma[t]
            sbi, zbi = s[i, t] / sn[t], z[i, t] / zn[t]
            w[i, t] = (sbi - zbi) / (2.0 * g)
            lam[i, t] = ((g + zb0) * sbi + (g + sb0) * zbi) / (sb0 + zb0 + 2.0 * g) * math.sqrt(sn[t] * zn[t])


@njit(**_JIT)
def w_apply(w, eta, v, sign, out):
    """``out = W v`` (``sign`` = +1) or ``W⁻¹ v`` (``sign`` = −1)."""
    f = eta if sign > 0 else 1.0 / eta
    _w_rows(w, f, sign, v, out, np.empty(v.shape[1]))


@njit(**_JIT)
def winv2_apply(w, inv_eta2, v, out):
    """``out = W⁻² v = (2 v̂ (v̂ᵀv) − J v)/η²`` with ``v̂ = J w̄``."""
    d, k = v.shape
    a = np.empty(k)
    _dot_body(w, v, a)
    for t in range(k):
        a[t] = 2.0 * (w[0, t] * v[0, t] - a[t])
        out[0, t] = (a[t] * w[0, t] - v[0, t]) * inv_eta2[t]
    for i in range(1, d):
        for t in range(k):
            out[i, t] = (v[i, t] - a[t] * w[i, t]) * inv_eta2[t]


@njit(**_JIT)
def _step_bounds(u, du, out):
    d, k = u.shape
    nb, ud, r2 = np.empty(k), np.empty(k), np.empty(k)
    for t in range(k):  # not np.zeros (see the note on NumPy calls in solvers/ipm/_kernels.py)
        r2[t] = 0.0
    _dot_body(u, u, nb)
    _dot_body(u, du, ud)
    c = np.empty(k)
    det = np.empty(k)
    for t in range(k):
        u0 = u[0, t]
        n = math.sqrt(nb[t])
        det[t] = (u0 - n) * (u0 + n)
        lk = math.sqrt(det[t])
        ud[t] = (u0 * du[0, t] - ud[t]) / det[t]  # ρ₀
        c[t] = (ud[t] * lk + du[0, t]) / (u0 + lk)
    for i in range(1, d):
        for t in range(k):
            r = du[i, t] - c[t] * u[i, t]
            r2[t] += r * r
    for t in range(k):
        out[t] = math.sqrt(r2[t] / det[t]) - ud[t]


def max_step(u: np.ndarray, du: np.ndarray) -> float:
    """Largest ``α`` with ``u + α du`` in the cone for every cone (``inf`` if unbounded); ``u`` interior.

    The quadratic representation of ``u^{-1/2}`` maps ``u`` to the identity (as ECOS does); there the condition
    reads ``1 + αρ₀ ≥ α‖ρ₁‖``. SOC(3) and SOC(4) have their bounds unrolled (SOC(3)'s in :mod:`._kernels`).
    """
    if not u.shape[1]:
        return np.inf
    bounds = np.empty(u.shape[1])
    d = u.shape[0]
    kernel = soc_step_bounds if d == 3 else _step_bounds4 if d == 4 else _step_bounds
    kernel(np.ascontiguousarray(u), np.ascontiguousarray(du), bounds)
    worst = float(bounds.max())
    return 1.0 / worst if worst > 0 else np.inf


@njit(**_JIT)
def mehrotra(w, eta, lam, ds_a, dz_a, z, sigma_mu, work, out):
    """Combined-step term ``out = −z − W⁻¹(λ \\ ((W⁻¹Δs_a)∘(WΔz_a) − σμe))`` of every cone (``work`` (d, k))."""
    d, k = z.shape
    inv, tmp, tmp2 = 1.0 / eta, np.empty(k), np.empty(k)
    _w_rows(w, inv, -1.0, ds_a, out, tmp)
    _w_rows(w, eta, 1.0, dz_a, work, tmp)
    _jprod_rows(out, work, out, tmp)
    for t in range(k):
        out[0, t] -= sigma_mu
    _jdiv_rows(lam, out, tmp, tmp2)
    _w_rows(w, inv, -1.0, out, out, tmp)
    for i in range(d):
        for t in range(k):
            out[i, t] = -z[i, t] - out[i, t]


@njit(**_JIT)
def gondzio(w, eta, lam, s, ds, tp, z, dz, td, lo, hi, work, out):
    """Gondzio's corrector term ``out = W⁻¹(λ \\ c)`` of every cone (``work`` (d, k)).

    At the trial point ``(s + tp·Δs, z + td·Δz)`` the two eigenvalues of the scaled complementarity product
    ``(W⁻¹s)∘(Wz)`` are moved into ``[lo, hi]``: ``c`` is that move (each eigenvalue's decrease bounded by
    ``hi``), expressed in the product's Jordan frame.
    """
    d, k = z.shape
    inv, tmp, tmp2 = 1.0 / eta, np.empty(k), np.empty(k)
    for i in range(d):
        for t in range(k):
            out[i, t] = s[i, t] + tp * ds[i, t]
            work[i, t] = z[i, t] + td * dz[i, t]
    _w_rows(w, inv, -1.0, out, out, tmp)
    _w_rows(w, eta, 1.0, work, work, tmp)
    _jprod_rows(out, work, out, tmp)
    _dot_body(out, out, tmp2)
    for t in range(k):
        nv = math.sqrt(tmp2[t])
        v0 = out[0, t]
        e1, e2 = v0 - nv, v0 + nv
        t1 = max(min(max(e1, lo), hi) - e1, -hi)
        t2 = max(min(max(e2, lo), hi) - e2, -hi)
        tmp2[t] = 0.5 * (t2 - t1) / nv if nv > 0 else 0.0
        out[0, t] = 0.5 * (t1 + t2)
    for i in range(1, d):
        for t in range(k):
            out[i, t] *= tmp2[t]
    _jdiv_rows(lam, out, tmp, tmp2)
    _w_rows(w, inv, -1.0, out, out, tmp)


# ------------------------------------------------------------------------------ the clique maps
@njit(**_JIT)
def gather(G, dofs, x, out):
    """``out[:, t] = G_t x[dofs[t]]`` (d, k)."""
    k, d, c = G.shape
    for t in range(k):
        for i in range(d):
            acc = 0.0
            for j in range(c):
                acc += G[t, i, j] * x[dofs[t, j]]
            out[i, t] = acc


@njit(**_JIT)
def scatter(G, dofs, z, sign, out):
    """``out[dofs[t]] += sign · G_tᵀ z[:, t]`` for every cone."""
    k, d, c = G.shape
    for t in range(k):
        for j in range(c):
            acc = 0.0
            for i in range(d):
                acc += G[t, i, j] * z[i, t]
            out[dofs[t, j]] += sign * acc


@njit(**_JIT)
def kkt(G, dofs, w, inv_eta2, v, out):
    """``out += Σ_t G_tᵀ W_t⁻² G_t v[dofs[t]]``."""
    k, d, c = G.shape
    g = np.empty(d)
    for t in range(k):
        for i in range(d):
            acc = 0.0
            for j in range(c):
                acc += G[t, i, j] * v[dofs[t, j]]
            g[i] = acc
        a = w[0, t] * g[0]
        for i in range(1, d):
            a -= w[i, t] * g[i]
        a *= 2.0
        f = inv_eta2[t]
        g[0] = (a * w[0, t] - g[0]) * f
        for i in range(1, d):
            g[i] = (g[i] - a * w[i, t]) * f
        for j in range(c):
            acc = 0.0
            for i in range(d):
                acc += G[t, i, j] * g[i]
            out[dofs[t, j]] += acc


@njit(**_JIT)
def assemble(G, gjg, w, inv_eta2, tri_a, tri_b, pos, data):
    """``data[pos] += G_tᵀ W_t⁻² G_t = (2 (G_tᵀv̂)(G_tᵀv̂)ᵀ − G_tᵀJG_t)/η²`` (``v̂ = J w̄``) on each clique's lower
    triangle: entry ``e`` = (``tri_a[e]``, ``tri_b[e]``) of cone ``t`` at ``pos[t·ne + e]`` (each cone's positions
    contiguous: with one position stream per entry the scattered writes took twice as long, 17.7 against 8.7 ms over
    armadillo's 259K order-2 cones, 2026-12-02); ``gjg`` (k, ne) holds ``G_tᵀJG_t`` at those entries."""
    k, d, c = G.shape
    ne = tri_a.shape[0]
    u = np.empty(c)
    for t in range(k):
        for j in range(c):
            acc = w[0, t] * G[t, 0, j]
            for i in range(1, d):
                acc -= w[i, t] * G[t, i, j]
            u[j] = acc
        f = inv_eta2[t]
        for e in range(ne):
            data[pos[t * ne + e]] += (2.0 * u[tri_a[e]] * u[tri_b[e]] - gjg[t, e]) * f


# ------------------------------------------------------------------------------ SOC(4), unrolled
@njit(**_HELPER)
def _w4(w, t, f, sign, v0, v1, v2, v3):
    """Cone ``t``'s ``f · W̄ v`` (``sign`` = +1) or ``f · W̄⁻¹ v`` (``sign`` = −1)."""
    w0, w1, w2, w3 = w[0, t], w[1, t], w[2, t], w[3, t]
    wv = w1 * v1 + w2 * v2 + w3 * v3
    c = sign * v0 + wv / (1.0 + w0)
    return (w0 * v0 + sign * wv) * f, (v1 + c * w1) * f, (v2 + c * w2) * f, (v3 + c * w3) * f


@njit(**_HELPER)
def _jdiv_winv4(w, t, inv_eta, lam, d0, d1, d2, d3):
    """Cone ``t``'s ``W⁻¹ (λ \\ d)``."""
    l0, l1, l2, l3 = lam[0, t], lam[1, t], lam[2, t], lam[3, t]
    nl = math.sqrt(l1 * l1 + l2 * l2 + l3 * l3)
    x0 = (l0 * d0 - l1 * d1 - l2 * d2 - l3 * d3) / ((l0 - nl) * (l0 + nl))
    return _w4(w, t, inv_eta, -1.0, x0, (d1 - x0 * l1) / l0, (d2 - x0 * l2) / l0, (d3 - x0 * l3) / l0)


@njit(**_JIT)
def nt_scaling4(s, z, w, eta, inv_eta2, lam):
    """:func:`nt_scaling` for SOC(4)."""
    for t in range(s.shape[1]):
        s0, s1, s2, s3 = s[0, t], s[1, t], s[2, t], s[3, t]
        z0, z1, z2, z3 = z[0, t], z[1, t], z[2, t], z[3, t]
        ns = math.sqrt(s1 * s1 + s2 * s2 + s3 * s3)
        nz = math.sqrt(z1 * z1 + z2 * z2 + z3 * z3)
        sn = math.sqrt(max((s0 - ns) * (s0 + ns), 1e-300))
        zn = math.sqrt(max((z0 - nz) * (z0 + nz), 1e-300))
        sb0, sb1, sb2, sb3 = s0 / sn, s1 / sn, s2 / sn, s3 / sn
        zb0, zb1, zb2, zb3 = z0 / zn, z1 / zn, z2 / zn, z3 / zn
        gamma = math.sqrt(0.5 * (1.0 + sb0 * zb0 + sb1 * zb1 + sb2 * zb2 + sb3 * zb3))
        inv2g = 0.5 / gamma
        w[0, t] = (sb0 + zb0) * inv2g
        w[1, t] = (sb1 - zb1) * inv2g
        w[2, t] = (sb2 - zb2) * inv2g
        w[3, t] = (sb3 - zb3) * inv2g
        eta[t] = math.sqrt(sn / zn)
        inv_eta2[t] = zn / sn
        scale = math.sqrt(sn * zn)
        den = scale / (sb0 + zb0 + 2.0 * gamma)
        lam[0, t] = gamma * scale
        lam[1, t] = ((gamma + zb0) * sb1 + (gamma + sb0) * zb1) * den
        lam[2, t] = ((gamma + zb0) * sb2 + (gamma + sb0) * zb2) * den
        lam[3, t] = ((gamma + zb0) * sb3 + (gamma + sb0) * zb3) * den


@njit(**_JIT)
def w_apply4(w, eta, v, sign, out):
    """:func:`w_apply` for SOC(4)."""
    for t in range(v.shape[1]):
        f = eta[t] if sign > 0 else 1.0 / eta[t]
        out[0, t], out[1, t], out[2, t], out[3, t] = _w4(w, t, f, sign, v[0, t], v[1, t], v[2, t], v[3, t])


@njit(**_JIT)
def winv2_apply4(w, inv_eta2, v, out):
    """:func:`winv2_apply` for SOC(4)."""
    for t in range(v.shape[1]):
        w0, w1, w2, w3 = w[0, t], w[1, t], w[2, t], w[3, t]
        v0, v1, v2, v3 = v[0, t], v[1, t], v[2, t], v[3, t]
        a = 2.0 * (w0 * v0 - w1 * v1 - w2 * v2 - w3 * v3)
        f = inv_eta2[t]
        out[0, t] = (a * w0 - v0) * f
        out[1, t] = (v1 - a * w1) * f
        out[2, t] = (v2 - a * w2) * f
        out[3, t] = (v3 - a * w3) * f


@njit(**_JIT)
def _step_bounds4(u, du, out):
    for t in range(u.shape[1]):
        u0, u1, u2, u3 = u[0, t], u[1, t], u[2, t], u[3, t]
        d0, d1, d2, d3 = du[0, t], du[1, t], du[2, t], du[3, t]
        nb = math.sqrt(u1 * u1 + u2 * u2 + u3 * u3)
        det = (u0 - nb) * (u0 + nb)
        lk = math.sqrt(det)
        rho0 = (u0 * d0 - u1 * d1 - u2 * d2 - u3 * d3) / det
        c = (rho0 * lk + d0) / (u0 + lk)
        r1, r2, r3 = d1 - c * u1, d2 - c * u2, d3 - c * u3
        out[t] = math.sqrt((r1 * r1 + r2 * r2 + r3 * r3) / det) - rho0


@njit(**_JIT)
def mehrotra4(w, eta, lam, ds_a, dz_a, z, sigma_mu, out):
    """:func:`mehrotra` for SOC(4)."""
    for t in range(z.shape[1]):
        e = eta[t]
        a0, a1, a2, a3 = _w4(w, t, 1.0 / e, -1.0, ds_a[0, t], ds_a[1, t], ds_a[2, t], ds_a[3, t])
        b0, b1, b2, b3 = _w4(w, t, e, 1.0, dz_a[0, t], dz_a[1, t], dz_a[2, t], dz_a[3, t])
        c0 = a0 * b0 + a1 * b1 + a2 * b2 + a3 * b3 - sigma_mu
        r0, r1, r2, r3 = _jdiv_winv4(w, t, 1.0 / e, lam, c0, a0 * b1 + b0 * a1, a0 * b2 + b0 * a2, a0 * b3 + b0 * a3)
        out[0, t] = -z[0, t] - r0
        out[1, t] = -z[1, t] - r1
        out[2, t] = -z[2, t] - r2
        out[3, t] = -z[3, t] - r3


@njit(**_JIT)
def gondzio4(w, eta, lam, s, ds, tp, z, dz, td, lo, hi, out):
    """:func:`gondzio` for SOC(4)."""
    for t in range(z.shape[1]):
        e = eta[t]
        a0, a1, a2, a3 = _w4(w, t, 1.0 / e, -1.0, s[0, t] + tp * ds[0, t], s[1, t] + tp * ds[1, t],
                             s[2, t] + tp * ds[2, t], s[3, t] + tp * ds[3, t])
        b0, b1, b2, b3 = _w4(w, t, e, 1.0, z[0, t] + td * dz[0, t], z[1, t] + td * dz[1, t],
                             z[2, t] + td * dz[2, t], z[3, t] + td * dz[3, t])
        v0 = a0 * b0 + a1 * b1 + a2 * b2 + a3 * b3
        v1, v2, v3 = a0 * b1 + b0 * a1, a0 * b2 + b0 * a2, a0 * b3 + b0 * a3
        nv = math.sqrt(v1 * v1 + v2 * v2 + v3 * v3)
        e1, e2 = v0 - nv, v0 + nv
        t1 = max(min(max(e1, lo), hi) - e1, -hi)
        t2 = max(min(max(e2, lo), hi) - e2, -hi)
        f = 0.5 * (t2 - t1) / nv if nv > 0 else 0.0
        out[0, t], out[1, t], out[2, t], out[3, t] = _jdiv_winv4(w, t, 1.0 / e, lam, 0.5 * (t1 + t2), f * v1, f * v2,
                                                                 f * v3)


@njit(**_JIT)
def gather4(G, dofs, x, out):
    """:func:`gather` for SOC(4) cones."""
    k, _, c = G.shape
    for t in range(k):
        a0 = a1 = a2 = a3 = 0.0
        for j in range(c):
            xj = x[dofs[t, j]]
            a0 += G[t, 0, j] * xj
            a1 += G[t, 1, j] * xj
            a2 += G[t, 2, j] * xj
            a3 += G[t, 3, j] * xj
        out[0, t], out[1, t], out[2, t], out[3, t] = a0, a1, a2, a3


@njit(**_JIT)
def scatter4(G, dofs, z, sign, out):
    """:func:`scatter` for SOC(4) cones."""
    k, _, c = G.shape
    for t in range(k):
        z0, z1, z2, z3 = sign * z[0, t], sign * z[1, t], sign * z[2, t], sign * z[3, t]
        for j in range(c):
            out[dofs[t, j]] += G[t, 0, j] * z0 + G[t, 1, j] * z1 + G[t, 2, j] * z2 + G[t, 3, j] * z3


@njit(**_JIT)
def kkt4(G, dofs, w, inv_eta2, v, out):
    """:func:`kkt` for SOC(4) cones."""
    k, _, c = G.shape
    for t in range(k):
        g0 = g1 = g2 = g3 = 0.0
        for j in range(c):
            vj = v[dofs[t, j]]
            g0 += G[t, 0, j] * vj
            g1 += G[t, 1, j] * vj
            g2 += G[t, 2, j] * vj
            g3 += G[t, 3, j] * vj
        w0, w1, w2, w3 = w[0, t], w[1, t], w[2, t], w[3, t]
        a = 2.0 * (w0 * g0 - w1 * g1 - w2 * g2 - w3 * g3)
        f = inv_eta2[t]
        h0, h1, h2, h3 = (a * w0 - g0) * f, (g1 - a * w1) * f, (g2 - a * w2) * f, (g3 - a * w3) * f
        for j in range(c):
            out[dofs[t, j]] += G[t, 0, j] * h0 + G[t, 1, j] * h1 + G[t, 2, j] * h2 + G[t, 3, j] * h3


@njit(**_JIT)
def assemble4(G, gjg, w, inv_eta2, tri_a, tri_b, pos, data):
    """:func:`assemble` for SOC(4) cones."""
    k, _, c = G.shape
    ne = tri_a.shape[0]
    u = np.empty(c)
    for t in range(k):
        w0, w1, w2, w3 = w[0, t], w[1, t], w[2, t], w[3, t]
        for j in range(c):
            u[j] = w0 * G[t, 0, j] - w1 * G[t, 1, j] - w2 * G[t, 2, j] - w3 * G[t, 3, j]
        f = inv_eta2[t]
        for e in range(ne):
            data[pos[t * ne + e]] += (2.0 * u[tri_a[e]] * u[tri_b[e]] - gjg[t, e]) * f
