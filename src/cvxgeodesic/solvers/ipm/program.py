"""The program the algorithm iterates on: ``½xᵀPx + qᵀx`` over cone blocks, fixed variables eliminated.

::

    minimize    ½ xᵀPx + qᵀx
    subject to  A_i x + s_i = b_i,   s_i ∈ K_i   for every block i (:mod:`.blocks`)
                E x = f                          (a few equalities: the zero cone)
                x_j = x_F,j                      for the fixed variables

Fixed variables become identity rows of the reduced Newton matrix ``K = P + Σ_i A_iᵀW_i⁻²A_i``, which
keeps its sparsity pattern (the mesh's :func:`~cvxgeodesic.problems.conic.kkt_pattern`); one
symbolic analysis therefore serves every iteration of every solve on a mesh. The equalities stay out
of that pattern: their rows are few, and the Newton system ``[K Eᵀ; E 0]`` is solved through the
dense Schur complement ``E K⁻¹ Eᵀ`` (:mod:`.newton`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.sparse as sp

from ...linalg import SymbolicCholesky
from ...problems.conic import ConicProblem, Equalities, clique_pattern
from . import _kernels as _kern
from .blocks import CliqueSOCBlock, ConeBlock, PairInequalityBlock, TriangleSOCBlock
from .cones import Scaling, _amax

__all__ = ["PatternMismatch", "Program", "problem_pattern"]


class PatternMismatch(Exception):
    """A problem's Newton matrices do not fit the analysed pattern."""


def problem_pattern(problem: ConicProblem) -> sp.csc_matrix:
    """Sparsity pattern (ones, both triangles, full diagonal) of every Newton matrix of one problem.

    Parameters
    ----------
    problem : ConicProblem

    Returns
    -------
    (n, n) scipy.sparse.csc_matrix
    """
    return clique_pattern(problem.n, [g.dofs for g in problem.cones] + [problem.ineq.vertices], problem.P)


class Program:
    """Everything about one program that does not change across iterations.

    Parameters
    ----------
    P : (n, n) sparse matrix or None
        Symmetric PSD quadratic term (both triangles).
    q : (n,) float ndarray
    fixed : (n,) bool ndarray
    fixed_values : (n,) float ndarray
        Values of the fixed variables (ignored elsewhere).
    blocks : callable
        ``blocks(x_fixed, chol) -> list of ConeBlock`` (built here so that a block's pattern check comes
        before any other work).
    chol : SymbolicCholesky
        The analysed pattern; :class:`PatternMismatch` when a block or ``P`` does not fit it.
    eq : Equalities, optional
        ``E x = f``.
    guess : (n,) float ndarray, optional
        A field near the optimum for the "guess" start (:mod:`.start`).

    Attributes
    ----------
    blocks : list of ConeBlock
    nu : int
        Barrier degree (Σ over the blocks).
    free, fixed : (n,) bool ndarrays
        A free variable that nothing constrains or couples and that has no cost is fixed at 0 here;
        with a cost, :attr:`unbounded_var` is its index (else −1).
    """

    def __init__(self, P, q: np.ndarray, fixed: np.ndarray, fixed_values: np.ndarray, blocks, chol: SymbolicCholesky,
                 eq: Equalities | None = None, guess: np.ndarray | None = None):
        n = int(np.asarray(q).shape[0])
        if n != chol.n:
            raise ValueError(f"problem has {n} variables but the solver was built for {chol.n} (another mesh?)")
        self.n = n
        self.fixed = np.asarray(fixed, dtype=bool).copy()
        self.x_fixed = np.where(self.fixed, np.asarray(fixed_values, dtype=np.float64), 0.0)
        self.P = None if P is None else sp.csr_matrix(P, dtype=np.float64)
        self.q = np.asarray(q, dtype=np.float64)
        nnz = chol.nnz
        # Assembly plan first: a problem that does not fit the pattern is detected before any other work.
        self.base = np.zeros(nnz)
        try:
            self.blocks: Sequence[ConeBlock] = blocks(self.x_fixed, chol)
            if self.P is not None:
                Pl = sp.tril(self.P, format="coo")
                self.base += np.bincount(_kern.positions(chol, Pl.row, Pl.col), weights=Pl.data, minlength=nnz)
        except ValueError as exc:
            raise PatternMismatch(str(exc)) from None
        self.nu = sum(b.cone.degree(b.count) for b in self.blocks)
        self._eq_touch = np.unique(sp.csr_matrix(eq.E).indices) if eq is not None and eq.count else None
        self._fix_loose()

        # Constants of the reduced problem: q̃ = q_f + P_fF x_F, const = objective of x_F (b̃ is in the blocks).
        self.Px_fixed = self.P @ self.x_fixed if self.P is not None else np.zeros(n)
        self.qt_free = (self.q + self.Px_fixed)[self.free]
        self.const = float(self.q @ self.x_fixed) + 0.5 * float(self.x_fixed @ self.Px_fixed)
        self._equalities(eq)
        self.norm_b = max([b.norm_b() for b in self.blocks] + [_amax(self.f_tilde)], default=0.0)
        self.norm_q = _amax(self.qt_free)
        self.guess = None if guess is None else np.asarray(guess, dtype=np.float64)

        # Fixed variables: rows and columns replaced by identity rows.
        r = chol.indices.astype(np.int64)
        c = np.repeat(np.arange(n), np.diff(chol.indptr))
        self.keep = (self.free[r] & self.free[c]).astype(np.float64)
        self.fixed_diag = chol.diag_positions[self.fixed]
        self.diag_pos = chol.diag_positions
        self.nnz = nnz

    def _equalities(self, eq: Equalities | None) -> None:
        """``E`` and ``f`` with the fixed variables eliminated: ``E_f`` (fixed columns zeroed, so that ``K⁻¹Eᵀ``
        vanishes on them as every direction does), ``f̃ = f − E x_F``; rows left empty are dropped."""
        self.E = self.ET = None
        self.f = self.f_tilde = np.zeros(0)
        self.p = 0
        if eq is None or not eq.count:
            return
        E = sp.csr_matrix(eq.E, dtype=np.float64)
        f_tilde = np.asarray(eq.f, dtype=np.float64) - E @ self.x_fixed
        Ef = (E @ sp.diags(self.free.astype(np.float64))).tocsr()
        Ef.eliminate_zeros()
        rows = np.diff(Ef.indptr) > 0
        if (~rows).any() and np.abs(f_tilde[~rows]).max() > 0:
            bad = int(np.flatnonzero(~rows & (f_tilde != 0))[0])
            raise ValueError(f"equality {bad} involves fixed variables only and is violated by their values")
        self.E, self.f, self.f_tilde = Ef[rows], np.asarray(eq.f, dtype=np.float64)[rows], f_tilde[rows]
        self.E_full = E[rows]
        self.ET = self.E.T.tocsr()
        self.p = int(self.E.shape[0])

    def Et(self, y: np.ndarray) -> np.ndarray:
        """``Eᵀy`` (n,) (zero on the fixed variables)."""
        return self.ET @ y if self.p else np.zeros(self.n)

    def eq_residual(self, x: np.ndarray) -> np.ndarray:
        """``E x − f`` (p,) at a full-space ``x``."""
        return self.E_full @ x - self.f if self.p else np.zeros(0)

    def _fix_loose(self) -> None:
        """A free variable that nothing constrains or couples is either free to go to ±∞ or irrelevant."""
        touched = np.zeros(self.n, dtype=bool)
        for b in self.blocks:
            b.touch(touched)
        if self.P is not None:
            touched |= np.asarray(abs(self.P).sum(axis=1)).ravel() > 0
        if self._eq_touch is not None:
            touched[self._eq_touch] = True
        loose = ~self.fixed & ~touched
        self.unbounded_var = -1
        if loose.any():
            bad = np.flatnonzero(loose & (self.q != 0))
            if bad.size:
                self.unbounded_var = int(bad[0])
            self.fixed |= loose  # q_i = 0: any value is optimal; keep 0
        self.free = ~self.fixed

    @classmethod
    def from_problem(cls, problem: ConicProblem, chol: SymbolicCholesky) -> Program:
        """The blocks of a :class:`ConicProblem`: each cone group (the fused SOC(3) triangle kernels for unit
        gradient bounds on triangles, :class:`~.blocks.CliqueSOCBlock` otherwise), then the pair inequalities."""

        def blocks(x_fixed, chol):
            out: list[ConeBlock] = []
            for g in problem.cones:
                B = g.unit_blocks() if (g.size, g.clique) == (3, 3) else None
                out.append(TriangleSOCBlock(B, g.dofs, x_fixed, chol) if B is not None
                           else CliqueSOCBlock(g, x_fixed, chol))
            ineq = problem.ineq
            out.append(PairInequalityBlock(ineq.vertices, ineq.coeffs, ineq.rhs, x_fixed, chol))
            return out

        return cls(problem.P, problem.q, problem.fixed_mask, problem.fixed_values, blocks, chol, eq=problem.eq,
                   guess=problem.guess)

    # --- products with the constraint matrix ---
    def identity_scalings(self) -> list[Scaling]:
        """``W = I`` for every block (the starting point's system)."""
        return [b.cone.scaling(b.cone.identity(b.count), b.cone.identity(b.count)) for b in self.blocks]

    def At(self, z: Sequence[np.ndarray]) -> np.ndarray:
        """``Aᵀz`` (n,) with fixed entries set to 0."""
        out = np.zeros(self.n)
        for b, zb in zip(self.blocks, z, strict=True):
            b.At_add(zb, out)
        out[self.fixed] = 0.0
        return out

    def Pmul(self, x: np.ndarray) -> np.ndarray:
        return self.P @ x if self.P is not None else np.zeros(self.n)

    def kkt_mul(self, v: np.ndarray, scalings: Sequence[Scaling], with_P: bool = True) -> np.ndarray:
        """``(P + AᵀW⁻²A) v`` (without P if not ``with_P``) on the free variables, ``v`` on the fixed ones:
        the operator, unregularized."""
        out = self.Pmul(v) if with_P else np.zeros(self.n)
        for b, sc in zip(self.blocks, scalings, strict=True):
            b.kkt_add(sc, v, out)
        out[self.fixed] = v[self.fixed]
        return out

    def assemble(self, scalings: Sequence[Scaling], with_P: bool = True) -> np.ndarray:
        """Lower-triangle data of ``P + AᵀW⁻²A`` (``AᵀW⁻²A`` if not ``with_P``), identity rows for fixed
        variables, aligned with the pattern."""
        data = self.base.copy() if with_P else np.zeros(self.nnz)
        for b, sc in zip(self.blocks, scalings, strict=True):
            b.assemble_add(sc, data)
        data *= self.keep
        data[self.fixed_diag] = 1.0
        return data
