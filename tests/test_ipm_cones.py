"""The cone-block protocol of the interior-point solver against dense NumPy references, and a made-up program
with SOC(3), SOC(4) and orthant blocks against Clarabel."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from cvxgeodesic.linalg import SymbolicCholesky
from cvxgeodesic.solvers.ipm import InteriorPointSolver, IPMSettings
from cvxgeodesic.solvers.ipm.blocks import SparseBlock
from cvxgeodesic.solvers.ipm.cones import SOC, Orthant
from cvxgeodesic.solvers.ipm.program import Program

CONES = [SOC(3), SOC(4), SOC(6), Orthant()]
IDS = ["soc3", "soc4", "soc6", "orthant"]
K = 40  # cones per block


def _inside(cone, u: np.ndarray) -> np.ndarray:
    """Membership of every cone of ``u`` from the cone's definition (not through the code under test)."""
    if isinstance(cone, Orthant):
        return u >= 0
    return u[0] >= np.linalg.norm(u[1:], axis=0)


def _interior(cone, rng, k=K, margin=(1e-2, 2.0)) -> np.ndarray:
    if isinstance(cone, Orthant):
        return rng.uniform(*margin, k)
    v = rng.normal(size=(cone.size, k))
    v[0] = np.linalg.norm(v[1:], axis=0) + rng.uniform(*margin, k)
    return v


def _dense(apply, cone, i: int) -> np.ndarray:
    """The matrix of a per-cone linear map (``apply`` on (d, K) fields), for cone ``i``."""
    if isinstance(cone, Orthant):
        e = np.zeros(K)
        e[i] = 1.0
        return np.array([[apply(e)[i]]])
    d = cone.size
    cols = []
    for j in range(d):
        e = np.zeros((d, K))
        e[j, i] = 1.0
        cols.append(apply(e)[:, i])
    return np.array(cols).T


def _arrow(cone, u: np.ndarray) -> np.ndarray:
    """Dense Jordan multiplication matrix ``L(u)`` with ``u ∘ v = L(u) v`` (one cone's ``u``)."""
    if isinstance(cone, Orthant):
        return np.array([[float(u[0])]])
    L = u[0] * np.eye(u.size)
    L[0, 1:] = L[1:, 0] = u[1:]
    return L


def _col(u: np.ndarray, i: int) -> np.ndarray:
    return np.atleast_1d(u[..., i])


@pytest.mark.parametrize("cone", CONES, ids=IDS)
def test_identity_is_inside_and_neutral(cone):
    rng = np.random.default_rng(0)
    e = cone.identity(K)
    u = _interior(cone, rng)
    assert _inside(cone, e).all()
    np.testing.assert_allclose(cone.product(e, u), u, rtol=1e-13, atol=1e-13)
    assert cone.min_eigenvalue(cone.add_identity(u, 5.0)) == pytest.approx(cone.min_eigenvalue(u) + 5.0)


@pytest.mark.parametrize("cone", CONES, ids=IDS)
def test_max_step_matches_bisection(cone):
    rng = np.random.default_rng(1)
    u = _interior(cone, rng, margin=(1e-6, 1.0))
    du = rng.normal(size=u.shape) * 3.0
    for i in range(0, K, 5):
        ui, dui = u[..., i : i + 1], du[..., i : i + 1]
        a = cone.max_step(ui, dui)
        if np.isinf(a):
            assert _inside(cone, ui + 1e6 * dui).all()
        else:
            assert _inside(cone, ui + a * (1 - 1e-7) * dui).all() and not _inside(cone, ui + a * (1 + 1e-7) * dui).all()
    steps = [cone.max_step(u[..., i : i + 1], du[..., i : i + 1]) for i in range(K)]
    assert cone.max_step(u, du) == pytest.approx(min(steps))


@pytest.mark.parametrize("cone", CONES, ids=IDS)
def test_nesterov_todd_scaling_identities(cone):
    rng = np.random.default_rng(2)
    s, z = _interior(cone, rng), _interior(cone, rng)
    sc = cone.scaling(s, z)
    np.testing.assert_allclose(sc.apply_w(z), sc.lam, rtol=1e-10, atol=1e-12)  # W z = λ
    np.testing.assert_allclose(sc.apply_winv(s), sc.lam, rtol=1e-10, atol=1e-12)  # W⁻¹ s = λ
    assert _inside(cone, sc.lam).all()
    for i in (0, 7, K - 1):
        W, Winv, Winv2 = (_dense(f, cone, i) for f in (sc.apply_w, sc.apply_winv, sc.apply_winv2))
        np.testing.assert_allclose(W, W.T, rtol=1e-10, atol=1e-12)  # symmetric
        assert np.linalg.eigvalsh(W).min() > 0  # positive definite
        np.testing.assert_allclose(W @ Winv, np.eye(W.shape[0]), atol=1e-9)
        np.testing.assert_allclose(Winv2, Winv @ Winv, rtol=1e-9, atol=1e-9)
        # W² = quadratic-representation form of the NT point: W² z = s
        np.testing.assert_allclose(W @ W @ _col(z, i), _col(s, i), rtol=1e-9, atol=1e-9)
    # an automorphism of the cone: W maps interior points inside
    assert _inside(cone, sc.apply_w(_interior(cone, rng))).all()


@pytest.mark.parametrize("cone", CONES, ids=IDS)
def test_jordan_product_and_division(cone):
    rng = np.random.default_rng(3)
    lam, u = _interior(cone, rng), rng.normal(size=_interior(cone, rng).shape)
    prod = cone.product(lam, u)
    for i in (0, 11, K - 1):
        np.testing.assert_allclose(_col(prod, i), _arrow(cone, _col(lam, i)) @ _col(u, i), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(cone.divide(lam, prod), u, rtol=1e-9, atol=1e-9)
    assert _inside(cone, cone.product(lam, lam)).all()  # squares lie in the cone


def _scaled_pair_and_steps(cone, seed):
    """Interior ``s, z``, their NT scaling and random directions ``ds, dz`` (the same draws as each test had)."""
    rng = np.random.default_rng(seed)
    s, z = _interior(cone, rng), _interior(cone, rng)
    return s, z, cone.scaling(s, z), rng.normal(size=s.shape), rng.normal(size=s.shape)


def _dense_mehrotra(cone, sc, ds, dz, z, sigma_mu, i):
    W, Winv = _dense(sc.apply_w, cone, i), _dense(sc.apply_winv, cone, i)
    a, b = Winv @ _col(ds, i), W @ _col(dz, i)
    c = _arrow(cone, a) @ b - sigma_mu * _col(cone.identity(K), i)
    return -_col(z, i) - Winv @ np.linalg.solve(_arrow(cone, _col(sc.lam, i)), c)


@pytest.mark.parametrize("cone", CONES, ids=IDS)
def test_mehrotra_term_matches_dense_reference(cone):
    s, z, sc, ds, dz = _scaled_pair_and_steps(cone, 4)
    out = cone.mehrotra(sc, ds, dz, z, 0.3)
    for i in (0, 5, K - 1):
        np.testing.assert_allclose(_col(out, i), _dense_mehrotra(cone, sc, ds, dz, z, 0.3, i), rtol=1e-8, atol=1e-9)


def _spectral(cone, v):
    """Eigenvalues and Jordan frame of one cone's element ``v`` (dense, in the cone's own coordinates)."""
    if isinstance(cone, Orthant):
        return np.array([v[0]]), [np.ones(1)]
    w = v
    nb = np.linalg.norm(w[1:])
    u = w[1:] / nb if nb > 0 else np.zeros(w.size - 1)
    frames = [0.5 * np.r_[1.0, -u], 0.5 * np.r_[1.0, u]]
    return np.array([w[0] - nb, w[0] + nb]), frames


@pytest.mark.parametrize("cone", CONES, ids=IDS)
def test_gondzio_term_matches_dense_reference(cone):
    s, z, sc, ds, dz = _scaled_pair_and_steps(cone, 5)
    tp, td, lo, hi = 0.7, 0.4, 0.05, 0.8
    out = cone.gondzio(sc, s, ds, tp, z, dz, td, lo, hi)
    for i in range(0, K, 7):
        W, Winv = _dense(sc.apply_w, cone, i), _dense(sc.apply_winv, cone, i)
        v = _arrow(cone, Winv @ (_col(s, i) + tp * _col(ds, i))) @ (W @ (_col(z, i) + td * _col(dz, i)))
        eig, frames = _spectral(cone, v)
        t = np.maximum(np.clip(eig, lo, hi) - eig, -hi)
        c = sum(ti * f for ti, f in zip(t, frames, strict=True))
        ref = Winv @ np.linalg.solve(_arrow(cone, _col(sc.lam, i)), c)
        np.testing.assert_allclose(_col(out, i), ref, rtol=1e-8, atol=1e-9)


@pytest.mark.parametrize("cone", CONES, ids=IDS)
def test_starting_point_shifts(cone):
    rng = np.random.default_rng(6)
    z = rng.normal(size=_interior(cone, rng).shape)
    shifted = cone.floor(cone.dual_shift(z, 1.5), 0.1)
    assert cone.min_eigenvalue(shifted) >= 0.1 - 1e-12
    assert _inside(cone, shifted).all()


@pytest.mark.parametrize("cone", CONES, ids=IDS)
def test_shift_cones_moves_the_masked_cones_inside_and_leaves_the_others(cone):
    rng = np.random.default_rng(7)
    u = rng.normal(size=_interior(cone, rng).shape)  # about half of the cones outside
    mask = rng.random(K) < 0.5
    shifted = cone.shift_cones(u, mask, 1.5, 1e-2)
    inside = _inside(cone, shifted)
    assert inside[mask].all() and cone.min_eigenvalue(shifted[..., mask]) > 0  # strictly inside
    assert np.abs(shifted[..., ~mask] - u[..., ~mask]).max() <= 1e-14 * np.abs(u).max()  # the others unchanged
    if not isinstance(cone, Orthant):  # only the heads move
        assert np.allclose(shifted[1:], u[1:])


# ---------------------------------------------------------------------------------------------------------------
# A made-up program through the generic blocks, against Clarabel
# ---------------------------------------------------------------------------------------------------------------


def _made_up(seed: int, quadratic: bool):
    """``min ½xᵀPx + qᵀx`` with SOC(3), SOC(4) and box (orthant) blocks, strictly feasible at ``x0``;
    one variable fixed at its ``x0`` value."""
    rng = np.random.default_rng(seed)
    n = 12
    x0 = rng.normal(size=n)
    spec = [(SOC(3), 6), (SOC(4), 5)]
    blocks = []
    for cone, k in spec:
        A = sp.random(cone.size * k, n, density=0.4, random_state=rng, format="csr")
        s0 = _interior(cone, rng, k)
        blocks.append((cone, A, A @ x0 + s0.T.ravel()))
    box = sp.vstack([sp.identity(n), -sp.identity(n)], format="csr")  # −5 ≤ x ≤ 5 keeps the LP bounded
    blocks.append((Orthant(), box, np.full(2 * n, 5.0)))
    P = sp.identity(n, format="csc") * 0.5 if quadratic else None
    q = rng.normal(size=n)
    fixed = np.zeros(n, dtype=bool)
    fixed[3] = True
    return n, P, q, fixed, x0, blocks


def _clarabel(n, P, q, fixed, x0, blocks):
    import clarabel

    rows, rhs, cones = [], [], []
    e = sp.csr_matrix(([1.0], ([0], [3])), shape=(1, n))
    rows.append(e)
    rhs.append(np.array([x0[3]]))
    cones.append(clarabel.ZeroConeT(1))
    for cone, A, b in blocks:
        if isinstance(cone, Orthant):
            rows.append(A)
            rhs.append(b)
            cones.append(clarabel.NonnegativeConeT(A.shape[0]))
            continue
        rows.append(A)
        rhs.append(b)
        cones.extend([clarabel.SecondOrderConeT(cone.size)] * (A.shape[0] // cone.size))
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.tol_gap_abs = settings.tol_gap_rel = settings.tol_feas = 1e-10
    Pu = sp.triu(P if P is not None else sp.csc_matrix((n, n)), format="csc")
    sol = clarabel.DefaultSolver(Pu, q, sp.vstack(rows, format="csc"), np.concatenate(rhs), cones, settings).solve()
    assert str(sol.status) == "Solved"
    return np.array(sol.x), sol.obj_val


@pytest.mark.parametrize("quadratic", [True, False], ids=["qp", "lp"])
def test_made_up_program_matches_clarabel(quadratic):
    n, P, q, fixed, x0, blocks = _made_up(7, quadratic)
    pattern = sp.identity(n, format="csc")
    for _, A, _ in blocks:
        pattern = pattern + abs(A.T @ A)
    ipm = InteriorPointSolver(pattern)
    prog = Program(P, q, fixed, np.where(fixed, x0, 0.0),
                   lambda xf, chol: [SparseBlock(c, A, b, xf, chol) for c, A, b in blocks], ipm.cholesky)
    res = ipm.solve_program(prog, tol=1e-9)
    x_ref, obj_ref = _clarabel(n, P, q, fixed, x0, blocks)
    assert res.status == "optimal"
    assert res.objective == pytest.approx(obj_ref, rel=1e-7, abs=1e-7)
    np.testing.assert_allclose(res.x, x_ref, atol=1e-5)
    assert res.x[3] == x0[3]
    for cone, A, b in blocks:  # feasible: b − A x in the cone
        slack = b - A @ res.x
        field = slack if isinstance(cone, Orthant) else slack.reshape(-1, cone.size).T
        assert _inside(cone, field + 1e-8 * cone.identity(field.shape[-1])).all()
    # the settings reach the generic solver too
    ipm.settings = IPMSettings(max_correctors=0)
    assert ipm.solve_program(prog, tol=1e-9).extra["correctors"] == 0


def test_sparse_block_rejects_a_pattern_that_does_not_fit():
    n, P, q, fixed, x0, blocks = _made_up(8, True)
    chol = SymbolicCholesky(sp.identity(n, format="csc"), backend="scipy")
    cone, A, b = blocks[0]
    with pytest.raises(ValueError, match="not in the sparsity pattern"):
        SparseBlock(cone, A, b, np.zeros(n), chol)
    with pytest.raises(ValueError, match="not a multiple of the cone dimension"):
        SparseBlock(SOC(4), A[:7], b[:7], np.zeros(n), chol)


def test_settings_are_validated_and_frozen():
    import dataclasses

    for bad, name in (({"init": "warm"}, "init"), ({"step": 1.0}, "step"), ({"max_correctors": -1}, "max_correctors"),
                      ({"max_refine": 1.5}, "max_refine"), ({"corrector_weights": ()}, "corrector_weights"),
                      ({"beta_min": 2.0}, "beta_min"), ({"tol_infeas": -1e-8}, "tol_infeas"),
                      ({"interior_fraction": 0.0}, "interior_fraction")):
        with pytest.raises(ValueError, match=rf"IPMSettings.*{name}"):
            IPMSettings(**bad)
    with pytest.raises(dataclasses.FrozenInstanceError):
        IPMSettings().step = 0.5  # type: ignore[misc]
    with pytest.raises(TypeError, match="settings must be an IPMSettings"):
        InteriorPointSolver(sp.identity(3, format="csc"), settings={"step": 0.9})  # type: ignore[arg-type]
