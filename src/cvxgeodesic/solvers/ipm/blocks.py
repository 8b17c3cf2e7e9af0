"""Constraint blocks: one cone type (:mod:`.cones`) and the linear map that gives its slack, ``s = b − A x``.

A block owns everything of the algorithm that involves its rows of ``A``: the residual ``A x + s − b``,
``Aᵀz``, its term ``AᵀW⁻²A`` of the reduced Newton matrix (as an operator and assembled into the
fixed pattern), the Newton direction's ``Δs``, ``Δz`` from ``Δx``, ``b̃ᵀz`` and the recession test
of the unboundedness certificate. ``x`` is always the full variable vector (fixed entries at their
values); ``b̃ = b − A x_F`` is the right-hand side of the problem with the fixed variables eliminated.

:class:`TriangleSOCBlock`
    The mesh problems' cones ``s_t = (1, B_t x_t)`` (every cone touches three variables): SOC(3)
    with the fused compiled kernels of :mod:`._kernels`.
:class:`CliqueSOCBlock`
    Second-order cones of any dimension on variable cliques, ``s_t = h_t − G_t x[dofs_t]`` (a
    :class:`~cvxgeodesic.problems.conic.ConeGroup`): the order-2 cones on a face's six P2 nodes, the
    gradient bounds of tetrahedra; the compiled kernels of :mod:`._clique_kernels`.
:class:`PairInequalityBlock`
    The mesh problems' linear inequalities ``a_k · x_k ≤ r_k`` (each touches at most two variables),
    on the nonnegative orthant.
:class:`SparseBlock`
    Any cone (:class:`~.cones.SOC` of any size, :class:`~.cones.Orthant`)
    with a general sparse ``A``, in NumPy/SciPy: for programs that are not mesh-shaped, and the reference
    the structured blocks are tested against.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np
import scipy.sparse as sp

from ...linalg import SymbolicCholesky
from ...problems.conic import ConeGroup
from . import _clique_kernels as _ck
from . import _kernels as _kern
from .cones import SOC, Cone, Orthant, Scaling, _amax

__all__ = ["CliqueSOCBlock", "ConeBlock", "PairInequalityBlock", "SparseBlock", "TriangleSOCBlock"]

# local (a, b) index pairs of the 6 lower-triangle entries of a 3×3 clique
_CLIQUE_A = np.array([0, 1, 2, 1, 2, 2])
_CLIQUE_B = np.array([0, 1, 2, 0, 0, 1])


class ConeBlock(Protocol):
    """What the algorithm needs of one block of constraints ``s = b − A x``, ``s ∈ K``.

    A block that subclasses it inherits :meth:`b_dot`, :meth:`norm_b`, :meth:`newton` and :meth:`refine` from
    its :meth:`A` and ``W⁻²`` (:meth:`_winv2`, the scaling's ``apply_winv2``).
    """

    cone: Cone
    count: int
    #: the block's rows of the reduced right-hand side ``b̃ = b − A x_F``
    b_tilde: np.ndarray

    def slack(self, x: np.ndarray, x_fixed: np.ndarray) -> np.ndarray:
        """``s = b − A x`` (computed as ``b̃ − A(x − x_F)`` where that rounds as the original solver did)."""
        ...

    def residual(self, x: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, object]:
        """``r_z = A x + s − b`` and an opaque by-product for :meth:`recession_violation`."""
        ...

    def recession_violation(self, aux: object) -> float:
        """How far ``−A d`` is from the cone for the free part ``d`` of the current ``x`` (∞-norm)."""
        ...

    def b_dot(self, z: np.ndarray) -> float:
        """``b̃ᵀz``."""
        return float((self.b_tilde * z).sum())

    def norm_b(self) -> float:
        """``‖b̃‖∞`` (0 for an empty block)."""
        return _amax(self.b_tilde)

    def A(self, x: np.ndarray) -> np.ndarray:
        """``A x``."""
        ...

    def At_add(self, z: np.ndarray, out: np.ndarray) -> None:
        """``out += Aᵀz``."""
        ...

    def kkt_add(self, sc: Scaling, v: np.ndarray, out: np.ndarray) -> None:
        """``out += AᵀW⁻²A v``."""
        ...

    def assemble_add(self, sc: Scaling, data: np.ndarray) -> None:
        """``data += AᵀW⁻²A`` on the pattern's lower triangle."""
        ...

    def newton(self, dx: np.ndarray, sc: Scaling, wu: np.ndarray, wr: np.ndarray, rz: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
        """``Δs = −r_z − A Δx``, ``Δz = W⁻² A Δx + wu + wr`` (``wr = W⁻² r_z``)."""
        adx = self.A(dx)
        return -rz - adx, self._winv2(sc, adx) + wu + wr

    def refine(self, delta: np.ndarray, sc: Scaling, ds: np.ndarray, dz: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
        """``(Δs, Δz)`` after ``Δx += δ``: ``Δs − A δ``, ``Δz + W⁻² A δ``."""
        ad = self.A(delta)
        return ds - ad, dz + self._winv2(sc, ad)

    def _winv2(self, sc: Scaling, u: np.ndarray) -> np.ndarray:
        """``W⁻² u``."""
        return sc.apply_winv2(u)

    def touch(self, mask: np.ndarray) -> None:
        """Mark the variables the block constrains."""
        ...


class TriangleSOCBlock(ConeBlock):
    """SOC(3) cones ``‖B_t x[cv[t]]‖ ≤ 1``: ``s_t = (1, B_t x_t)``, i.e. ``A_t = [0; −B_t]``, ``b_t = (1, 0)``.

    Parameters
    ----------
    blocks : (k, 2, 3) float ndarray
        ``B_t``.
    vertices : (k, 3) int ndarray
        The variables of each cone.
    x_fixed : (n,) float ndarray
        Fixed values (0 on the free variables).
    chol : SymbolicCholesky
        The pattern; raises ValueError when a clique is not in it.
    """

    cone = SOC(3)

    def __init__(self, blocks: np.ndarray, vertices: np.ndarray, x_fixed: np.ndarray, chol: SymbolicCholesky):
        cv = np.asarray(vertices, dtype=np.int64).reshape(-1, 3)
        Bt = np.asarray(blocks, dtype=np.float64).reshape(-1, 2, 3)
        self.count = k = cv.shape[0]
        self.pos = _kern.positions(chol, cv[:, _CLIQUE_A].T.ravel(), cv[:, _CLIQUE_B].T.ravel())
        # SoA order for the kernels: B[:, :, t] is B_t
        self.B = B = np.ascontiguousarray(Bt.transpose(1, 2, 0))  # (2, 3, k)
        self.cv = np.ascontiguousarray(cv)
        # clique constants B_tᵀB_t (6, k): each iteration adds a rank-one term
        self.BtB6 = np.stack([B[0, a] * B[0, b] + B[1, a] * B[1, b] for a, b in zip(_CLIQUE_A, _CLIQUE_B, strict=True)])
        self.shift = self.Bx(x_fixed)  # b̃ body = +B x_F (A body is −B)
        self.b_tilde = np.concatenate([np.ones((1, k)), self.shift])

    def Bx(self, x: np.ndarray) -> np.ndarray:
        """(2, k): ``B_t x_t`` for every cone."""
        out = np.empty((2, self.count))
        _kern.gather(self.B, self.cv, x, out)
        return out

    def slack(self, x, x_fixed):
        return np.concatenate([np.ones((1, self.count)), self.Bx(x)])

    def residual(self, x, s):
        Bx = self.Bx(x)
        rz = s.copy()
        rz[0] -= 1.0
        rz[1:] -= Bx
        return rz, Bx

    def recession_violation(self, aux) -> float:
        bd = aux - self.shift  # B x_f
        return _amax(np.sqrt(bd[0] ** 2 + bd[1] ** 2))

    def b_dot(self, z) -> float:
        return float(z[0].sum() + (self.shift * z[1:]).sum())

    def norm_b(self) -> float:
        return max(1.0, float(np.abs(self.shift).max())) if self.count else 0.0

    def A(self, x):
        return np.concatenate([np.zeros((1, self.count)), -self.Bx(x)])

    def At_add(self, z, out) -> None:
        if self.count:
            _kern.scatter(self.B, self.cv, z[1:], -1.0, out)

    def kkt_add(self, sc, v, out) -> None:
        if self.count:
            _kern.kkt_cones(self.B, self.cv, sc.w, sc.inv_eta2, v, out)

    def assemble_add(self, sc, data) -> None:
        """``(B_tᵀB_t + 2 (B_tᵀw̄₁)(B_tᵀw̄₁)ᵀ)/η²`` per clique: ``[W_t⁻²]_body = (I + 2 w̄₁w̄₁ᵀ)/η²``."""
        if self.count:
            _kern.assemble_cones(self.B, self.BtB6, sc.w, sc.inv_eta2, self.pos, data)

    def newton(self, dx, sc, wu, wr, rz):
        g = self.Bx(dx)  # A Δx = (0, −g)
        dz = np.empty((3, self.count))
        ds = np.empty((3, self.count))
        _kern.newton_cones(g, sc.w, sc.inv_eta2, wu, wr, rz, dz, ds)
        return ds, dz

    def touch(self, mask) -> None:
        mask[self.cv.ravel()] = True


class CliqueSOCBlock(ConeBlock):
    """Second-order cones on cliques of variables: ``s_t = h_t − G_t x[dofs_t] ∈ SOC(d)`` (``A_t = G_t``,
    ``b_t = h_t``).

    Parameters
    ----------
    group : ConeGroup
        ``dofs`` (k, c), ``G`` (k, d, c), ``h`` (k, d).
    x_fixed : (n,) float ndarray
        Fixed values (0 on the free variables).
    chol : SymbolicCholesky
        The pattern; raises ValueError when a clique is not in it.

    Notes
    -----
    ``G_tᵀW_t⁻²G_t = (2 (G_tᵀv̂)(G_tᵀv̂)ᵀ − G_tᵀJG_t)/η²`` (``v̂ = J w̄``): the constant ``G_tᵀJG_t`` is kept per
    clique entry, so each iteration adds a rank-one term per cone, as for the triangles.
    """

    def __init__(self, group: ConeGroup, x_fixed: np.ndarray, chol: SymbolicCholesky):
        self.cone = SOC(group.size)
        self.count = group.count
        self.G = G = group.G  # (k, d, c), C-contiguous (ConeGroup makes it so)
        self.dofs = dofs = group.dofs
        self.h = np.ascontiguousarray(group.h.T)  # (d, k)
        ta, tb = np.tril_indices(group.clique)  # lower-triangle clique entries (a ≥ b)
        self.tri_a, self.tri_b = ta.astype(np.int64), tb.astype(np.int64)
        self.pos = _kern.positions(chol, dofs[:, ta].ravel(), dofs[:, tb].ravel())
        self.gjg = np.ascontiguousarray(np.einsum("ke,ke->ke", G[:, 0, ta], G[:, 0, tb])
                                        - np.einsum("kie,kie->ke", G[:, 1:, ta], G[:, 1:, tb]))
        four = group.size == 4  # SOC(4): the unrolled kernels
        self._gather = _ck.gather4 if four else _ck.gather
        self._scatter = _ck.scatter4 if four else _ck.scatter
        self._kkt = _ck.kkt4 if four else _ck.kkt
        self._assemble = _ck.assemble4 if four else _ck.assemble
        self.shift = self.A(x_fixed)
        self.b_tilde = self.h - self.shift

    def A(self, x: np.ndarray) -> np.ndarray:
        """(d, k): ``G_t x[dofs_t]`` for every cone (``A_t = G_t``)."""
        out = np.empty((self.h.shape[0], self.count))
        if self.count:
            self._gather(self.G, self.dofs, np.ascontiguousarray(x, dtype=np.float64), out)
        return out

    def slack(self, x, x_fixed):
        return self.h - self.A(x)

    def residual(self, x, s):
        gx = self.A(x)
        return gx + s - self.h, gx

    def recession_violation(self, aux) -> float:
        return max(-self.cone.min_eigenvalue(self.shift - aux), 0.0) if self.count else 0.0  # −G d ∈ K

    def At_add(self, z, out) -> None:
        if self.count:
            self._scatter(self.G, self.dofs, np.ascontiguousarray(z), 1.0, out)

    def kkt_add(self, sc, v, out) -> None:
        if self.count:
            self._kkt(self.G, self.dofs, sc.w, sc.inv_eta2, np.ascontiguousarray(v, dtype=np.float64), out)

    def assemble_add(self, sc, data) -> None:
        if self.count:
            self._assemble(self.G, self.gjg, sc.w, sc.inv_eta2, self.tri_a, self.tri_b, self.pos, data)

    def touch(self, mask) -> None:
        used = np.abs(self.G).max(axis=1) > 0  # (k, c): a column of zeros constrains nothing
        mask[self.dofs[used]] = True


class PairInequalityBlock(ConeBlock):
    """Linear inequalities ``a_k · x[iv[k]] ≤ r_k`` with at most two variables each, on the orthant.

    Parameters
    ----------
    vertices : (p, 2) int ndarray
        A one-variable bound repeats the variable with coefficient 0 for the second.
    coeffs : (p, 2) float ndarray
    rhs : (p,) float ndarray
    x_fixed : (n,) float ndarray
    chol : SymbolicCholesky
    """

    cone = Orthant()

    def __init__(self, vertices: np.ndarray, coeffs: np.ndarray, rhs: np.ndarray, x_fixed: np.ndarray,
                 chol: SymbolicCholesky):
        iv = np.asarray(vertices, dtype=np.int64).reshape(-1, 2)
        ia = np.asarray(coeffs, dtype=np.float64).reshape(-1, 2)
        self.count = p = iv.shape[0]
        n = chol.n
        self.pos = _kern.positions(chol, iv[:, [0, 1, 1]].T.ravel(), iv[:, [0, 1, 0]].T.ravel())
        self.iv, self.ia = iv, ia
        self.L = sp.csr_matrix((ia.ravel(), (np.repeat(np.arange(p), 2), iv.ravel())), shape=(p, n))
        self.LT = self.L.T.tocsr()
        self.rhs = np.asarray(rhs, dtype=np.float64)
        # clique constants a_i a_j (3, p); a repeated vertex gets its cross term twice
        same = np.where(iv[:, 0] == iv[:, 1], 2.0, 1.0)
        self.coef = np.stack([ia[:, 0] ** 2, ia[:, 1] ** 2, ia[:, 0] * ia[:, 1] * same])
        self.b_tilde = self.rhs - self.L @ x_fixed

    def slack(self, x, x_fixed):
        return self.b_tilde - self.L @ (x - x_fixed)

    def residual(self, x, s):
        ax = self.L @ x
        return ax + s - self.rhs, ax

    def recession_violation(self, aux) -> float:
        ad = aux - (self.rhs - self.b_tilde)  # a·x_f
        return _amax(np.maximum(ad, 0.0))

    def b_dot(self, z) -> float:
        return float(self.b_tilde @ z)

    def A(self, x):
        return self.L @ x

    def At_add(self, z, out) -> None:
        if self.count:
            out += self.LT @ z

    def kkt_add(self, sc, v, out) -> None:
        if self.count:
            out += self.LT @ (sc.w2inv * (self.L @ v))

    def assemble_add(self, sc, data) -> None:
        if self.count:
            _kern.scatter_add((self.coef * sc.w2inv).ravel(), self.pos, data)

    def _winv2(self, sc, u):
        return sc.w2inv * u

    def touch(self, mask) -> None:
        mask[self.iv[self.ia != 0]] = True


class SparseBlock(ConeBlock):
    """``count`` cones of one type with a general sparse map: ``s = b − A x`` (NumPy/SciPy throughout).

    Parameters
    ----------
    cone : Cone
        :class:`~.cones.SOC` (any dimension) or :class:`~.cones.Orthant`.
    A : (count·dim, n) sparse matrix
        Rows cone-major: row ``t·dim + i`` is component ``i`` of cone ``t`` (``dim = 1`` for the orthant).
    b : (count·dim,) float ndarray
    x_fixed : (n,) float ndarray
    chol : SymbolicCholesky
        Its pattern must hold the pattern of ``AᵀA`` (ValueError otherwise).
    """

    def __init__(self, cone: Cone, A, b: np.ndarray, x_fixed: np.ndarray, chol: SymbolicCholesky):
        self.cone = cone
        self.A_mat = sp.csr_matrix(A, dtype=np.float64)
        rows = self.A_mat.shape[0]
        dim = int(np.prod(cone.shape(1)))
        if rows % dim:
            raise ValueError(f"A has {rows} rows, not a multiple of the cone dimension {dim}")
        self.count = rows // dim
        self._shape = cone.shape(self.count)
        self.AT = self.A_mat.T.tocsr()
        self.b = np.asarray(b, dtype=np.float64).reshape(rows)
        M = sp.coo_matrix(self.AT @ self.A_mat)
        chol.positions(M.row, M.col)  # fits the pattern, or ValueError
        self._chol = chol
        self.b_tilde = self._field(self.b - self.A_mat @ x_fixed)

    def _field(self, flat: np.ndarray) -> np.ndarray:
        """Cone-major rows → the cone's field layout."""
        if len(self._shape) == 1:
            return flat
        return np.ascontiguousarray(flat.reshape(self._shape[1], self._shape[0]).T)

    def _flat(self, u: np.ndarray) -> np.ndarray:
        return u if u.ndim == 1 else u.T.ravel()

    def slack(self, x, x_fixed):
        return self._field(self.b - self.A_mat @ x)

    def residual(self, x, s):
        Ax = self.A(x)
        return Ax + s - self._field(self.b), Ax

    def recession_violation(self, aux) -> float:
        # −A d ∈ K for d = x − x_F, A d = A x − (b − b̃); the distance measured as the most negative eigenvalue
        v = -(aux - self._field(self.b) + self.b_tilde)
        return max(-self.cone.min_eigenvalue(v), 0.0) if self.count else 0.0

    def A(self, x):
        return self._field(self.A_mat @ x)

    def At_add(self, z, out) -> None:
        out += self.AT @ self._flat(z)

    def kkt_add(self, sc, v, out) -> None:
        out += self.AT @ self._flat(sc.apply_winv2(self.A(v)))

    def assemble_add(self, sc, data) -> None:
        # AᵀW⁻²A column by column of A: W⁻² applied to the fields of A's columns (dense per cone)
        n = self.A_mat.shape[1]
        cols = self.A_mat.tocsc()
        touched = np.flatnonzero(np.diff(cols.indptr))
        WA = np.zeros((self.A_mat.shape[0], touched.size))
        for j, c in enumerate(touched):
            e = np.zeros(n)
            e[c] = 1.0
            WA[:, j] = self._flat(sc.apply_winv2(self.A(e)))
        M = sp.coo_matrix(self.AT[touched] @ sp.csr_matrix(WA))
        rows, colsj = touched[M.row], touched[M.col]
        low = rows >= colsj
        np.add.at(data, self._chol.positions(rows[low], colsj[low]), M.data[low])

    def touch(self, mask) -> None:
        mask[np.flatnonzero(np.diff(self.A_mat.tocsc().indptr))] = True
