"""The cone-block protocol: the algebra of one cone type, vectorized over the cones of a block.

The interior-point algorithm touches a cone only through the methods of :class:`Cone`: the
identity element, the Nesterov–Todd scaling (a :class:`Scaling`: ``W``, ``W⁻¹``, ``W⁻²`` and
``λ = W z = W⁻¹ s``), the step to the boundary, the Jordan product and division, the Mehrotra and
Gondzio terms built on them, and the shifts of the starting point. How a block's slack depends
on ``x`` (its constraint map) is :mod:`.blocks`' business.

Data layout ("structure of arrays"): a field over ``k`` cones of dimension ``d`` is a (d, k) array,
row 0 the heads (contiguous per component, as the compiled kernels want); the nonnegative orthant's
fields are (p,) arrays.

Cone types
----------
:class:`SOC`
    ``{u : u₀ ≥ ‖u₁..‖}`` of any dimension; SOC(3) runs the unrolled kernels of
    :mod:`._kernels`, other dimensions those of :mod:`._clique_kernels` (the same formulas, CVXOPT's).
:class:`Orthant`
    ``{u : u ≥ 0}`` (the linear inequalities).

Adding a cone type is one class here with these methods (plus its kernels when speed matters).
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from . import _clique_kernels as _ck
from . import _kernels as _kern

__all__ = ["SOC", "Cone", "Orthant", "Scaling"]


class Scaling(Protocol):
    """Nesterov–Todd scaling of one block's pairs (s, z): ``W z = W⁻¹ s = λ``."""

    lam: np.ndarray

    def apply_w(self, v: np.ndarray) -> np.ndarray: ...

    def apply_winv(self, v: np.ndarray) -> np.ndarray: ...

    def apply_winv2(self, v: np.ndarray) -> np.ndarray: ...


class Cone(Protocol):
    """The algebra of one cone type over the ``count`` cones of a block (fields shaped ``shape(count)``)."""

    def shape(self, count: int) -> tuple[int, ...]: ...

    def identity(self, count: int) -> np.ndarray:
        """``e``, the identity of the Jordan algebra (the cone's centre)."""
        ...

    def degree(self, count: int) -> int:
        """Barrier degree (the number of cones for the SOC, of entries for the orthant)."""
        return count

    def scaling(self, s: np.ndarray, z: np.ndarray) -> Scaling: ...

    def max_step(self, u: np.ndarray, du: np.ndarray) -> float:
        """Largest ``α`` with ``u + α du`` in the cone (``inf`` when unbounded); ``u`` interior."""
        ...

    def max_step_closed(self, u: np.ndarray, du: np.ndarray) -> np.ndarray:
        """Per cone (per entry for the orthant), the largest ``α`` with ``u + t du`` strictly inside for every ``t``
        in ``(0, α)``; ``u`` may lie on the boundary. 0 where no ``α > 0`` is, ``inf`` where every one is."""
        ...

    def dot(self, u: np.ndarray, v: np.ndarray) -> float:
        """``uᵀv`` summed over all cones."""
        return float((u * v).sum())

    def min_eigenvalue(self, u: np.ndarray) -> float:
        """Smallest eigenvalue of ``u`` over all cones (``inf`` when there are none)."""
        ...

    def product(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Jordan product ``u ∘ v``."""
        ...

    def divide(self, lam: np.ndarray, d: np.ndarray) -> np.ndarray:
        """Jordan division ``λ \\ d`` (the ``x`` with ``λ ∘ x = d``; ``λ`` interior)."""
        ...

    def mehrotra(self, sc: Scaling, ds: np.ndarray, dz: np.ndarray, z: np.ndarray, sigma_mu: float) -> np.ndarray:
        """Combined-step term ``−z − W⁻¹(λ \\ ((W⁻¹Δs_a)∘(WΔz_a) − σμe))``."""
        ...

    def gondzio(self, sc: Scaling, s: np.ndarray, ds: np.ndarray, tp: float, z: np.ndarray, dz: np.ndarray,
                td: float, lo: float, hi: float) -> np.ndarray:
        """Centrality-corrector term ``W⁻¹(λ \\ c)``: ``c`` moves the eigenvalues of ``(W⁻¹s')∘(Wz')`` at the
        trial point ``s' = s + tp Δs``, ``z' = z + td Δz`` into ``[lo, hi]`` (each decrease bounded by ``hi``)."""
        ...

    def add_identity(self, u: np.ndarray, d: float) -> np.ndarray:
        """``u + d e``."""
        ...

    def sum_heads(self, u: np.ndarray) -> float:
        """``eᵀu``-like sum of the heads (the entries for the orthant)."""
        ...

    def dual_shift(self, z: np.ndarray, factor: float) -> np.ndarray:
        """Mehrotra's shift cone by cone: each cone raised by ``factor`` × its own deficit (the orthant's
        entries together by ``factor`` × the most negative one)."""
        ...

    def floor(self, z: np.ndarray, margin: float) -> np.ndarray:
        """``z`` with every cone's margin (smallest eigenvalue) at least ``margin``."""
        ...

    def shift_cones(self, u: np.ndarray, mask: np.ndarray, factor: float, margin: float) -> np.ndarray:
        """``u`` with each cone of ``mask`` (k,) raised by ``factor`` × its own deficit (−smallest eigenvalue, if
        positive) plus ``margin`` × its largest entry in absolute value (at least 1e-3 × the largest over all
        cones): Mehrotra's shift, cone by cone, for the cones a start leaves out."""
        ...


def _c(a: np.ndarray) -> np.ndarray:
    """``a`` as a C-contiguous float64 array (the compiled kernels' layout)."""
    return np.ascontiguousarray(a, dtype=np.float64)


def _amax(a: np.ndarray) -> float:
    return float(np.abs(a).max()) if a.size else 0.0


# ---------------------------------------------------------------------------------------------------------------
# Second-order cone
# ---------------------------------------------------------------------------------------------------------------


#: SOC dimension → the kernels of the NT scaling, ``W v`` and ``W⁻² v`` (unrolled for 3 and 4; 0: any dimension)
_SCALING_KERNELS = {3: (_kern.nt_scaling, _kern.apply_w, _kern.apply_inv2),
                    4: (_ck.nt_scaling4, _ck.w_apply4, _ck.winv2_apply4),
                    0: (_ck.nt_scaling, _ck.w_apply, _ck.winv2_apply)}


class _SocScaling:
    """NT scaling ``W = η W̄`` of SOC pairs (s, z), vectorized (CVXOPT's formulas).

    ``W̄ = [[w₀, w₁ᵀ], [w₁, I + w₁w₁ᵀ/(1 + w₀)]]`` with ``w̄ᵀJw̄ = 1`` (``J = diag(1, −1, …)``);
    ``W z = W⁻¹ s = λ``; ``W⁻² = (2 v vᵀ − J)/η²`` with ``v = J w̄``. SOC(3) runs the unrolled kernels of
    :mod:`._kernels`, other dimensions the same formulas in :mod:`._clique_kernels`.
    """

    def __init__(self, s: np.ndarray, z: np.ndarray):
        d, k = s.shape
        nt_scaling, self._w_kernel, self._winv2_kernel = _SCALING_KERNELS.get(d, _SCALING_KERNELS[0])
        self.w = np.empty((d, k))
        self.eta = np.empty(k)
        self.inv_eta2 = np.empty(k)
        self.lam = np.empty((d, k))
        nt_scaling(_c(s), _c(z), self.w, self.eta, self.inv_eta2, self.lam)

    def _apply(self, v: np.ndarray, sign: float) -> np.ndarray:
        out = np.empty(v.shape)
        self._w_kernel(self.w, self.eta, _c(v), sign, out)
        return out

    def apply_w(self, v: np.ndarray) -> np.ndarray:
        """``W v``."""
        return self._apply(v, 1.0)

    def apply_winv(self, v: np.ndarray) -> np.ndarray:
        """``W⁻¹ v``."""
        return self._apply(v, -1.0)

    def apply_winv2(self, v: np.ndarray) -> np.ndarray:
        """``W⁻² v = (2 v̂ (v̂ᵀv) − J v)/η²`` with ``v̂ = J w̄``."""
        out = np.empty(v.shape)
        self._winv2_kernel(self.w, self.inv_eta2, _c(v), out)
        return out


class SOC(Cone):
    """The second-order cone ``SOC(size)`` (``size ≥ 2`` entries per cone), fields (size, k); see :class:`Cone`."""

    def __init__(self, size: int = 3):
        if size < 2:
            raise ValueError(f"SOC size must be at least 2, got {size}")
        self.size = int(size)

    def shape(self, count: int) -> tuple[int, ...]:
        return (self.size, count)

    def identity(self, count: int) -> np.ndarray:
        e = np.zeros((self.size, count))
        e[0] = 1.0
        return e

    def scaling(self, s: np.ndarray, z: np.ndarray) -> _SocScaling:
        return _SocScaling(s, z)

    def _norm_body(self, u: np.ndarray) -> np.ndarray:
        return np.sqrt(u[1] ** 2 + u[2] ** 2) if self.size == 3 else np.linalg.norm(u[1:], axis=0)

    def max_step(self, u: np.ndarray, du: np.ndarray) -> float:
        """By the quadratic representation of ``u^{-1/2}`` (:func:`._clique_kernels.max_step`)."""
        return _ck.max_step(_c(u), _c(du))

    def max_step_closed(self, u: np.ndarray, du: np.ndarray) -> np.ndarray:
        """Per cone, the largest ``α`` with ``u + t du`` strictly inside for every ``t`` in ``(0, α)``, where ``u``
        may lie on the boundary (the order-2 cones at ``φ = 0``): (k,) ndarray, 0 where no ``α > 0`` is, ``inf``
        where every one is.

        The margin ``head² − ‖body‖²`` at ``t`` is the quadratic ``m₀ + B t + A t²``; from inside (``m₀ > 0``, or
        ``m₀ = 0`` and ``B > 0``) the first positive root ends the interval.
        """
        m0 = u[0] ** 2 - (u[1:] ** 2).sum(axis=0)
        m0 = np.where(np.abs(m0) <= 1e-12 * u[0] ** 2, 0.0, m0)
        B = 2.0 * (u[0] * du[0] - (u[1:] * du[1:]).sum(axis=0))
        A = du[0] ** 2 - (du[1:] ** 2).sum(axis=0)
        disc = B * B - 4.0 * A * m0
        sq = np.sqrt(np.maximum(disc, 0.0))
        with np.errstate(divide="ignore", invalid="ignore"):
            root = np.where(A != 0, (-B - sq) / (2 * A), -m0 / B)
        alpha = np.where((disc >= 0) & (root > 0), root, np.inf)
        inside = (m0 > 0) & (u[0] > 0) | (m0 == 0) & (B > 0)
        return np.where(inside, alpha, 0.0)

    def min_eigenvalue(self, u: np.ndarray) -> float:
        return float((u[0] - self._norm_body(u)).min()) if u.shape[1] else np.inf

    def product(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        return np.concatenate([(u * v).sum(axis=0)[None], u[0] * v[1:] + v[0] * u[1:]])

    def divide(self, lam: np.ndarray, d: np.ndarray) -> np.ndarray:
        nl = self._norm_body(lam)
        x0 = (lam[0] * d[0] - (lam[1:] * d[1:]).sum(axis=0)) / ((lam[0] - nl) * (lam[0] + nl))
        return np.concatenate([x0[None], (d[1:] - x0 * lam[1:]) / lam[0]])

    def mehrotra(self, sc, ds, dz, z, sigma_mu):
        out = np.empty(z.shape)
        if self.size == 3:
            _kern.mehrotra_cones(sc.w, sc.eta, sc.lam, ds, dz, z, sigma_mu, out)
        elif self.size == 4:
            _ck.mehrotra4(sc.w, sc.eta, sc.lam, _c(ds), _c(dz), _c(z), sigma_mu, out)
        else:
            _ck.mehrotra(sc.w, sc.eta, sc.lam, _c(ds), _c(dz), _c(z), sigma_mu, np.empty(z.shape), out)
        return out

    def gondzio(self, sc, s, ds, tp, z, dz, td, lo, hi):
        out = np.empty(z.shape)
        if self.size == 3:
            _kern.gondzio_cones(sc.w, sc.eta, sc.lam, s, ds, tp, z, dz, td, lo, hi, out)
        elif self.size == 4:
            _ck.gondzio4(sc.w, sc.eta, sc.lam, _c(s), _c(ds), tp, _c(z), _c(dz), td, lo, hi, out)
        else:
            _ck.gondzio(sc.w, sc.eta, sc.lam, _c(s), _c(ds), tp, _c(z), _c(dz), td, lo, hi, np.empty(z.shape), out)
        return out

    def add_identity(self, u: np.ndarray, d: float) -> np.ndarray:
        u = u.copy()
        u[0] += d
        return u

    def sum_heads(self, u: np.ndarray) -> float:
        return float(u[0].sum())

    def dual_shift(self, z: np.ndarray, factor: float) -> np.ndarray:
        z = z.copy()
        z[0] += factor * np.maximum(self._norm_body(z) - z[0], 0.0)
        return z

    def floor(self, z: np.ndarray, margin: float) -> np.ndarray:
        z = z.copy()
        z[0] = np.maximum(z[0], self._norm_body(z) + margin)
        return z

    def shift_cones(self, u: np.ndarray, mask: np.ndarray, factor: float, margin: float) -> np.ndarray:
        u = u.copy()
        sub = u[:, mask]
        size = np.maximum(np.abs(sub).max(axis=0, initial=0.0), 1e-3 * _amax(u))
        u[0, mask] = sub[0] + factor * np.maximum(self._norm_body(sub) - sub[0], 0.0) + margin * size
        return u


# ---------------------------------------------------------------------------------------------------------------
# Nonnegative orthant
# ---------------------------------------------------------------------------------------------------------------


class _OrthantScaling:
    """``W = diag(√(s/z))``: ``λ = √(sz)``, ``W⁻² = z/s``."""

    def __init__(self, s: np.ndarray, z: np.ndarray):
        self.lam = np.sqrt(s * z)
        self.w2inv = z / s  # W⁻²
        self.winv = np.sqrt(self.w2inv)  # W⁻¹

    def apply_w(self, v: np.ndarray) -> np.ndarray:
        return v / self.winv

    def apply_winv(self, v: np.ndarray) -> np.ndarray:
        return self.winv * v

    def apply_winv2(self, v: np.ndarray) -> np.ndarray:
        return self.w2inv * v


class Orthant(Cone):
    """The nonnegative orthant ``R₊^p``, fields (p,); see :class:`Cone`."""

    def shape(self, count: int) -> tuple[int, ...]:
        return (count,)

    def identity(self, count: int) -> np.ndarray:
        return np.ones(count)

    def scaling(self, s: np.ndarray, z: np.ndarray) -> _OrthantScaling:
        return _OrthantScaling(s, z)

    def max_step(self, u: np.ndarray, du: np.ndarray) -> float:
        return _kern.max_step_lp(u, du) if u.size else np.inf

    def max_step_closed(self, u: np.ndarray, du: np.ndarray) -> np.ndarray:
        with np.errstate(divide="ignore", invalid="ignore"):
            alpha = np.where(du < 0, -u / du, np.inf)
        return np.where((u > 0) | (u == 0) & (du > 0), alpha, 0.0)

    def min_eigenvalue(self, u: np.ndarray) -> float:
        return float(u.min()) if u.size else np.inf

    def dot(self, u: np.ndarray, v: np.ndarray) -> float:
        return float(u @ v)

    def product(self, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        return u * v

    def divide(self, lam: np.ndarray, d: np.ndarray) -> np.ndarray:
        return d / lam

    def mehrotra(self, sc, ds, dz, z, sigma_mu):
        # (W⁻¹Δs)(WΔz) = Δs Δz for a diagonal W
        return -z - sc.winv * (ds * dz - sigma_mu) / sc.lam

    def gondzio(self, sc, s, ds, tp, z, dz, td, lo, hi):
        v = (s + tp * ds) * (z + td * dz)
        return sc.winv * np.maximum(np.clip(v, lo, hi) - v, -hi) / sc.lam

    def add_identity(self, u: np.ndarray, d: float) -> np.ndarray:
        return u + d

    def sum_heads(self, u: np.ndarray) -> float:
        return float(u.sum())

    def dual_shift(self, z: np.ndarray, factor: float) -> np.ndarray:
        return z + max(-factor * float(z.min()), 0.0) if z.size else z.copy()

    def floor(self, z: np.ndarray, margin: float) -> np.ndarray:
        return np.maximum(z, margin)

    def shift_cones(self, u: np.ndarray, mask: np.ndarray, factor: float, margin: float) -> np.ndarray:
        u = u.copy()
        sub = u[mask]
        u[mask] = sub + factor * np.maximum(-sub, 0.0) + margin * np.maximum(np.abs(sub), 1e-3 * _amax(u))
        return u
