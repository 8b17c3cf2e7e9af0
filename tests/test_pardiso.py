"""The MKL PARDISO binding: solves, errors, and thread-count changes between phases."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from threadpoolctl import threadpool_limits

from cvxgeodesic.linalg import NotPositiveDefiniteError, SymbolicCholesky
from cvxgeodesic.linalg.pardiso import PardisoError, PardisoFactor, pardiso_available
from cvxgeodesic.mesh import icosphere
from cvxgeodesic.problems.conic import kkt_pattern
from cvxgeodesic.problems.formulations import MeshOperators, build_problem, smoothness_weight
from cvxgeodesic.solvers.clarabel_backend import solve_clarabel
from cvxgeodesic.solvers.ipm import InteriorPointSolver

pytestmark = pytest.mark.skipif(not pardiso_available(), reason="MKL (PARDISO) not installed")


def _spd_lower(seed=0):
    """A random SPD matrix on a mesh pattern, as its lower-triangular CSC part."""
    m = icosphere(2)
    S = sp.tril(kkt_pattern(m.n_vertices, m.F, m.edges), format="csc")
    rng = np.random.default_rng(seed)
    S.data = rng.uniform(-1.0, 0.0, S.nnz)
    A = S + sp.tril(S, -1).T
    A = A - sp.diags(A.diagonal()) + sp.diags(np.asarray(abs(A).sum(axis=1)).ravel() + 0.5)
    low = sp.tril(A, format="csc")
    low.sort_indices()
    return low, A.tocsc()


def test_factor_and_solve_one_and_several_right_hand_sides():
    low, A = _spd_lower()
    f = PardisoFactor(low.indptr, low.indices)
    assert f.nnz_factor >= low.nnz
    f.factorize(low.data)
    rng = np.random.default_rng(1)
    b1 = rng.normal(size=A.shape[0])
    B = rng.normal(size=(A.shape[0], 3))
    np.testing.assert_allclose(A @ f.solve(b1), b1, atol=1e-10)
    np.testing.assert_allclose(A @ f.solve(B), B, atol=1e-10)
    # new values, same analysis
    f.factorize(2.0 * low.data)
    np.testing.assert_allclose(2.0 * (A @ f.solve(b1)), b1, atol=1e-10)


def test_errors_are_clear():
    low, A = _spd_lower()
    f = PardisoFactor(low.indptr, low.indices)
    with pytest.raises(RuntimeError, match="no successful factorization"):
        f.solve(np.ones(A.shape[0]))
    for bad in (-low.data, np.where(np.arange(low.nnz) < low.indptr[6], 0.0, low.data)):  # negative, zero pivots
        with pytest.raises(PardisoError, match="not positive definite") as info:
            f.factorize(bad)
        assert info.value.code == -4 and info.value.phase == 22
        with pytest.raises(RuntimeError, match="no successful factorization"):
            f.solve(np.ones(A.shape[0]))
    f.factorize(low.data)
    with pytest.raises(ValueError, match="right-hand side must have shape"):
        f.solve(np.ones(A.shape[0] + 1))
    with pytest.raises(ValueError, match="non-finite"):
        f.solve(np.full(A.shape[0], np.nan))


def test_symbolic_cholesky_maps_not_positive_definite():
    low, _ = _spd_lower()
    chol = SymbolicCholesky(low, backend="pardiso")
    pos = chol.positions(*sp.find(low)[:2])
    vals = np.zeros(chol.nnz)
    vals[pos] = sp.find(low)[2]
    with pytest.raises(NotPositiveDefiniteError):
        chol.factorize(-vals)(np.ones(chol.n))
    # a semidefinite matrix made definite by the diagonal shift beta
    chol.factorize(vals - 0.5 * np.isin(np.arange(chol.nnz), chol.diag_positions), beta=0.5)


def test_auto_ordering_is_amd_on_small_patterns_and_metis_on_large(monkeypatch):
    """``ordering="auto"`` (the default) picks by the pattern's stored entries; both orderings solve exactly."""
    import cvxgeodesic.linalg.symbolic as symbolic

    low, A = _spd_lower()
    b = np.random.default_rng(2).normal(size=A.shape[0])
    picked = {}
    for limit, expected in ((low.nnz + 1, "amd"), (low.nnz, "metis")):
        monkeypatch.setattr(symbolic, "AMD_BELOW_NNZ", limit)
        chol = SymbolicCholesky(low, backend="pardiso")
        assert chol.ordering == expected
        vals = np.zeros(chol.nnz)
        vals[chol.positions(*sp.find(low)[:2])] = sp.find(low)[2]
        np.testing.assert_allclose(A @ chol.factorize(vals)(b), b, atol=1e-10)
        picked[expected] = chol.numeric.factor._iparm[1]
    assert picked["amd"] == 0 and picked["metis"] != 0  # PARDISO's iparm[1]: 0 is minimum degree
    assert SymbolicCholesky(low, backend="pardiso", ordering="metis").ordering == "metis"  # a name is kept


def test_thread_limits_between_phases_are_safe():
    """PARDISO crashed (segfault) when MKL's thread count changed between analysis and factorization."""
    low, A = _spd_lower()
    f = PardisoFactor(low.indptr, low.indices)
    b = np.ones(A.shape[0])
    with threadpool_limits(1):
        f.factorize(low.data)
        x = f.solve(b)
    np.testing.assert_allclose(A @ x, b, atol=1e-10)
    with threadpool_limits(1):
        g = PardisoFactor(low.indptr, low.indices)
    g.factorize(low.data)
    np.testing.assert_allclose(A @ g.solve(b), b, atol=1e-10)


@pytest.mark.parametrize("backend", ["pardiso", "cholmod"])
@pytest.mark.parametrize("method", ["qclp", "qcqp-hessian", "lcqp-laplacian"])
def test_ipm_backends_agree_with_clarabel(backend, method):
    if backend == "cholmod":
        pytest.importorskip("sksparse.cholmod")
    m = icosphere(3)
    ops = MeshOperators(m)
    p = build_problem(ops, np.array([5]), method, smoothness_weight(m, 1.0))
    ipm = InteriorPointSolver(kkt_pattern(m.n_vertices, m.F, m.edges, p.P), backend=backend)
    res = ipm.solve(p)
    ref = solve_clarabel(p)
    assert res.extra["backend"] == backend
    assert abs(res.objective - ref.objective) <= 1e-6 * max(1.0, abs(ref.objective))
    assert np.max(np.abs(res.x - ref.x)) <= 1e-5 * m.bbox_diagonal
