"""Compiled per-cone kernels of the order-2 interior-point solver (:mod:`~cvxgeodesic.solvers.ipm_soc`).

Every SOC(4) cone of the order-2 program touches the six P2 DOFs of one face, so each
step of an iteration is a loop over cones with a few dozen flops per cone. As NumPy
expressions (batched 4×4 ``matmul``, ``einsum``, ``bincount``) these loops were ~80 % of a
solve (spot, 35K cones: 3.1 s of 7.4 s in the batched 4×4 products alone); one compiled
loop per operation does the same arithmetic in one pass without temporaries.

Conventions: a cone field over k cones is a (k, 4) array (column 0 the heads) and ``dofs``
(k, 6). Every cone of the program is ``h − G x = (φ + 1, ∇φ, φ − 1)``, so rows 0 and 3 of each
4×6 block are equal and the kernels take the blocks compact, ``G`` (k, 3, 6) holding rows 0–2
(a quarter less memory traffic: these loops are bound by reading ``G``). The Nesterov–Todd
scaling of cone k is kept as the scaling point ``w[k]`` (4,) with ``wᵀJw = 1`` and the factor
``eta[k]``:

    W = η [[w0, w1ᵀ], [w1, I + w1 w1ᵀ/(1 + w0)]],   W⁻¹ = J W J / η²   (J = diag(1, −1, −1, −1)),

the same matrices the NumPy version built densely (4×4 per cone). ``W⁻²`` is applied as
``W⁻¹(W⁻¹ v)``. Loops without scatter run in parallel (``prange``); scatters into a DOF
vector or the Newton matrix run serially in cone order (as ``np.bincount`` summed).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

# importing the order-1 kernels first selects Numba's threading layer (OpenMP, shared with MKL PARDISO)
from .ipm._kernels import _JIT, _PJIT


@njit(**_JIT)
def _w_apply(w0, w1, w2, w3, f, sign, v0, v1, v2, v3):
    """One cone's ``W v`` (``sign`` = +1, ``f`` = η) or ``W⁻¹ v`` (``sign`` = −1, ``f`` = 1/η)."""
    wv = w1 * v1 + w2 * v2 + w3 * v3
    c = sign * v0 + wv / (1.0 + w0)
    return (w0 * v0 + sign * wv) * f, (v1 + c * w1) * f, (v2 + c * w2) * f, (v3 + c * w3) * f


@njit(**_JIT)
def _winv2(w, eta, k, v0, v1, v2, v3):
    """One cone's ``W⁻² v``."""
    f = 1.0 / eta[k]
    w0, w1, w2, w3 = w[k, 0], w[k, 1], w[k, 2], w[k, 3]
    a0, a1, a2, a3 = _w_apply(w0, w1, w2, w3, f, -1.0, v0, v1, v2, v3)
    return _w_apply(w0, w1, w2, w3, f, -1.0, a0, a1, a2, a3)


@njit(**_PJIT)
def nt_scaling(s, z, w, eta, lam):
    """NT scaling of every pair (s_k, z_k): fills ``w`` (k, 4), ``eta`` (k,) and ``λ = W z`` (k, 4)."""
    for k in prange(s.shape[0]):
        s0, s1, s2, s3 = s[k, 0], s[k, 1], s[k, 2], s[k, 3]
        z0, z1, z2, z3 = z[k, 0], z[k, 1], z[k, 2], z[k, 3]
        ns = math.sqrt(s1 * s1 + s2 * s2 + s3 * s3)
        nz = math.sqrt(z1 * z1 + z2 * z2 + z3 * z3)
        # (u0 − ‖u1‖)(u0 + ‖u1‖) loses less to cancellation than u0² − ‖u1‖² next to the boundary
        sjs = max((s0 - ns) * (s0 + ns), 1e-300)
        zjz = max((z0 - nz) * (z0 + nz), 1e-300)
        rs, rz = math.sqrt(sjs), math.sqrt(zjz)
        sb0, sb1, sb2, sb3 = s0 / rs, s1 / rs, s2 / rs, s3 / rs
        zb0, zb1, zb2, zb3 = z0 / rz, z1 / rz, z2 / rz, z3 / rz
        gamma = math.sqrt(max((1.0 + (sb0 * zb0 + sb1 * zb1 + sb2 * zb2 + sb3 * zb3)) / 2.0, 1e-300))
        g2 = 2.0 * gamma
        w1, w2, w3 = (sb1 - zb1) / g2, (sb2 - zb2) / g2, (sb3 - zb3) / g2
        w0 = math.sqrt(1.0 + (w1 * w1 + w2 * w2 + w3 * w3))  # restore wᵀJw = 1 exactly
        w[k, 0], w[k, 1], w[k, 2], w[k, 3] = w0, w1, w2, w3
        e = (sjs / zjz) ** 0.25
        eta[k] = e
        lam[k, 0], lam[k, 1], lam[k, 2], lam[k, 3] = _w_apply(w0, w1, w2, w3, e, 1.0, z0, z1, z2, z3)


@njit(**_PJIT)
def apply_w(w, eta, v, power, out):
    """``out = W^power v`` per cone, ``power`` ∈ {1, −1, −2}."""
    for k in prange(v.shape[0]):
        v0, v1, v2, v3 = v[k, 0], v[k, 1], v[k, 2], v[k, 3]
        if power == -2:
            out[k, 0], out[k, 1], out[k, 2], out[k, 3] = _winv2(w, eta, k, v0, v1, v2, v3)
        else:
            sign = 1.0 if power > 0 else -1.0
            f = eta[k] if power > 0 else 1.0 / eta[k]
            out[k, 0], out[k, 1], out[k, 2], out[k, 3] = _w_apply(w[k, 0], w[k, 1], w[k, 2], w[k, 3], f, sign,
                                                                  v0, v1, v2, v3)


@njit(**_JIT)
def _gx(G, dofs, x, k):
    """One cone's ``G_k x[dofs[k]]`` (four values; G compact)."""
    a0 = a1 = a2 = 0.0
    for j in range(6):
        xj = x[dofs[k, j]]
        a0 += G[k, 0, j] * xj
        a1 += G[k, 1, j] * xj
        a2 += G[k, 2, j] * xj
    return a0, a1, a2, a0


@njit(**_PJIT)
def gather(G, dofs, x, out):
    """``out[k] = G_k x[dofs[k]]`` (k, 4)."""
    for k in prange(G.shape[0]):
        out[k, 0], out[k, 1], out[k, 2], out[k, 3] = _gx(G, dofs, x, k)


@njit(**_JIT)
def scatter(G, dofs, z, out):
    """``out[dofs[k]] += G_kᵀ z[k]`` for every cone in order: ``out += Gᵀ z``."""
    for k in range(G.shape[0]):
        z0, z1, z2 = z[k, 0] + z[k, 3], z[k, 1], z[k, 2]
        for j in range(6):
            out[dofs[k, j]] += G[k, 0, j] * z0 + G[k, 1, j] * z1 + G[k, 2, j] * z2


@njit(**_JIT)
def assemble(G, w, eta, pos, tri, tci, data):
    """``data[pos[k, e]] += (G_kᵀ W_k⁻² G_k)[tri[e], tci[e]]`` for the 21 lower-triangle entries of every cone."""
    u = np.empty((3, 6))
    for k in range(G.shape[0]):
        for j in range(6):
            g0 = G[k, 0, j]
            u0, u[1, j], u[2, j], u3 = _winv2(w, eta, k, g0, G[k, 1, j], G[k, 2, j], g0)
            u[0, j] = u0 + u3  # row 3 of G_k equals row 0
        for e in range(tri.shape[0]):
            a, b = tri[e], tci[e]
            data[pos[k, e]] += G[k, 0, a] * u[0, b] + G[k, 1, a] * u[1, b] + G[k, 2, a] * u[2, b]


@njit(**_PJIT)
def rhs_cones(w, eta, bu, bp, wib, t):
    """``wib = W⁻¹ bu`` and ``t = wib − W⁻² bp`` (the cone part of the reduced right-hand side)."""
    for k in prange(bu.shape[0]):
        f = 1.0 / eta[k]
        a0, a1, a2, a3 = _w_apply(w[k, 0], w[k, 1], w[k, 2], w[k, 3], f, -1.0, bu[k, 0], bu[k, 1], bu[k, 2], bu[k, 3])
        wib[k, 0], wib[k, 1], wib[k, 2], wib[k, 3] = a0, a1, a2, a3
        c0, c1, c2, c3 = _winv2(w, eta, k, bp[k, 0], bp[k, 1], bp[k, 2], bp[k, 3])
        t[k, 0], t[k, 1], t[k, 2], t[k, 3] = a0 - c0, a1 - c1, a2 - c2, a3 - c3


@njit(**_PJIT)
def back_cones(G, dofs, w, eta, dx, bp, wib, ds, dz):
    """``ds = bp − G dx`` and ``dz = wib − W⁻² ds`` (Δs, Δz from Δx)."""
    for k in prange(G.shape[0]):
        g0, g1, g2, g3 = _gx(G, dofs, dx, k)
        r0, r1, r2, r3 = bp[k, 0] - g0, bp[k, 1] - g1, bp[k, 2] - g2, bp[k, 3] - g3
        ds[k, 0], ds[k, 1], ds[k, 2], ds[k, 3] = r0, r1, r2, r3
        c0, c1, c2, c3 = _winv2(w, eta, k, r0, r1, r2, r3)
        dz[k, 0], dz[k, 1], dz[k, 2], dz[k, 3] = wib[k, 0] - c0, wib[k, 1] - c1, wib[k, 2] - c2, wib[k, 3] - c3


@njit(**_JIT)
def residual_cones(G, dofs, w, eta, dx, ds, dz, bp, u, r3, r4, gtz):
    """``r3 = bp − G dx − ds``, ``r4 = u − W dz − W⁻¹ ds`` (cone rows of the full Newton residual) and
    ``gtz += Gᵀ dz``, in one pass over ``G`` (serial: the scatter)."""
    for k in range(G.shape[0]):
        g0, g1, g2, g3 = _gx(G, dofs, dx, k)
        r3[k, 0], r3[k, 1] = bp[k, 0] - g0 - ds[k, 0], bp[k, 1] - g1 - ds[k, 1]
        r3[k, 2], r3[k, 3] = bp[k, 2] - g2 - ds[k, 2], bp[k, 3] - g3 - ds[k, 3]
        z0, z1, z2 = dz[k, 0] + dz[k, 3], dz[k, 1], dz[k, 2]
        for j in range(6):
            gtz[dofs[k, j]] += G[k, 0, j] * z0 + G[k, 1, j] * z1 + G[k, 2, j] * z2
        w0, w1, w2, w3, e = w[k, 0], w[k, 1], w[k, 2], w[k, 3], eta[k]
        a0, a1, a2, a3 = _w_apply(w0, w1, w2, w3, e, 1.0, dz[k, 0], dz[k, 1], dz[k, 2], dz[k, 3])
        b0, b1, b2, b3 = _w_apply(w0, w1, w2, w3, 1.0 / e, -1.0, ds[k, 0], ds[k, 1], ds[k, 2], ds[k, 3])
        r4[k, 0], r4[k, 1] = u[k, 0] - a0 - b0, u[k, 1] - a1 - b1
        r4[k, 2], r4[k, 3] = u[k, 2] - a2 - b2, u[k, 3] - a3 - b3


@njit(**_PJIT)
def _soc_steps(u, du, out):
    for k in prange(u.shape[0]):
        u0, d0 = u[k, 0], du[k, 0]
        dd = du[k, 1] * du[k, 1] + du[k, 2] * du[k, 2] + du[k, 3] * du[k, 3]
        ud = u[k, 1] * du[k, 1] + u[k, 2] * du[k, 2] + u[k, 3] * du[k, 3]
        uu = u[k, 1] * u[k, 1] + u[k, 2] * u[k, 2] + u[k, 3] * u[k, 3]
        a = d0 * d0 - dd
        b = 2.0 * (u0 * d0 - ud)
        c = max(u0 * u0 - uu, 0.0)
        disc = b * b - 4.0 * a * c
        if a < 0.0 or (b < 0.0 and disc >= 0.0):
            den = -b + math.sqrt(max(disc, 0.0))
            out[k] = 2.0 * c / den if den > 0.0 else 0.0
        else:
            out[k] = np.inf


def max_step(u: np.ndarray, du: np.ndarray) -> float:
    """Largest ``α`` with ``u + α du`` in every closed SOC(4) (``inf`` when unbounded); u, du (k, 4)."""
    out = np.empty(u.shape[0])
    _soc_steps(u, du, out)
    return float(np.min(out, initial=np.inf))


@njit(**_PJIT)
def jprod(a, b, out):
    """Jordan product ``out = a ∘ b = (aᵀb, a0 b1 + b0 a1)`` per cone."""
    for k in prange(a.shape[0]):
        a0, b0 = a[k, 0], b[k, 0]
        out[k, 0] = a0 * b0 + a[k, 1] * b[k, 1] + a[k, 2] * b[k, 2] + a[k, 3] * b[k, 3]
        for i in range(1, 4):
            out[k, i] = a0 * b[k, i] + b0 * a[k, i]


@njit(**_PJIT)
def jdiv(lam, d, out):
    """``out`` with ``lam ∘ out = d`` per cone."""
    for k in prange(lam.shape[0]):
        l0 = lam[k, 0]
        det = l0 * l0 - (lam[k, 1] * lam[k, 1] + lam[k, 2] * lam[k, 2] + lam[k, 3] * lam[k, 3])
        u0 = (l0 * d[k, 0] - (lam[k, 1] * d[k, 1] + lam[k, 2] * d[k, 2] + lam[k, 3] * d[k, 3])) / det
        out[k, 0] = u0
        for i in range(1, 4):
            out[k, i] = (d[k, i] - u0 * lam[k, i]) / l0


@njit(**_PJIT)
def mehrotra_rhs(w, eta, d_a, dsa, dza, sigma_mu, out):
    """``out = d_a − (W⁻¹Δs_a) ∘ (W Δz_a) + σμ e`` (the corrector's complementarity right-hand side)."""
    for k in prange(d_a.shape[0]):
        w0, w1, w2, w3, e = w[k, 0], w[k, 1], w[k, 2], w[k, 3], eta[k]
        p0, p1, p2, p3 = _w_apply(w0, w1, w2, w3, 1.0 / e, -1.0, dsa[k, 0], dsa[k, 1], dsa[k, 2], dsa[k, 3])
        q0, q1, q2, q3 = _w_apply(w0, w1, w2, w3, e, 1.0, dza[k, 0], dza[k, 1], dza[k, 2], dza[k, 3])
        out[k, 0] = d_a[k, 0] - (p0 * q0 + p1 * q1 + p2 * q2 + p3 * q3) + sigma_mu
        out[k, 1] = d_a[k, 1] - (p0 * q1 + q0 * p1)
        out[k, 2] = d_a[k, 2] - (p0 * q2 + q0 * p2)
        out[k, 3] = d_a[k, 3] - (p0 * q3 + q0 * p3)


@njit(**_PJIT)
def gondzio_rhs(w, eta, s, ds, tp, z, dz, td, lo, hi, out):
    """Gondzio's corrector right-hand side ``out = c`` of every cone (the direction solves ``λ∘(WΔz + W⁻¹Δs) = c``).

    At the trial point ``(s + tp·Δs, z + td·Δz)`` the two eigenvalues ``v0 ∓ ‖v1‖`` of the scaled complementarity
    product ``v = (W⁻¹s)∘(Wz)`` are moved into ``[lo, hi]``: ``c`` is that move (each eigenvalue's decrease bounded
    by ``hi``), expressed in the product's Jordan frame (as the order-1 solver's ``gondzio_cones``).
    """
    for k in prange(z.shape[0]):
        w0, w1, w2, w3, e = w[k, 0], w[k, 1], w[k, 2], w[k, 3], eta[k]
        a0, a1, a2, a3 = _w_apply(w0, w1, w2, w3, 1.0 / e, -1.0, s[k, 0] + tp * ds[k, 0], s[k, 1] + tp * ds[k, 1],
                                  s[k, 2] + tp * ds[k, 2], s[k, 3] + tp * ds[k, 3])
        b0, b1, b2, b3 = _w_apply(w0, w1, w2, w3, e, 1.0, z[k, 0] + td * dz[k, 0], z[k, 1] + td * dz[k, 1],
                                  z[k, 2] + td * dz[k, 2], z[k, 3] + td * dz[k, 3])
        v0 = a0 * b0 + a1 * b1 + a2 * b2 + a3 * b3
        v1, v2, v3 = a0 * b1 + b0 * a1, a0 * b2 + b0 * a2, a0 * b3 + b0 * a3
        nv = math.sqrt(v1 * v1 + v2 * v2 + v3 * v3)
        e1, e2 = v0 - nv, v0 + nv
        t1 = max(min(max(e1, lo), hi) - e1, -hi)
        t2 = max(min(max(e2, lo), hi) - e2, -hi)
        f = 0.5 * (t2 - t1) / nv if nv > 0 else 0.0
        out[k, 0] = 0.5 * (t1 + t2)
        out[k, 1], out[k, 2], out[k, 3] = f * v1, f * v2, f * v3
