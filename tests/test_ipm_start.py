"""The graph starting point (``IPMSettings(init="graph")``): the Dijkstra field of the program's edge bounds."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from cvxgeodesic.mesh import TriMesh, icosphere
from cvxgeodesic.problems.conic import kkt_pattern
from cvxgeodesic.problems.formulations import MeshOperators, build_problem, smoothness_weight
from cvxgeodesic.solvers.ipm import InteriorPointSolver, IPMSettings
from cvxgeodesic.solvers.ipm.blocks import PairInequalityBlock, TriangleSOCBlock
from cvxgeodesic.solvers.ipm.graph import edge_arcs, graph_field
from cvxgeodesic.solvers.ipm.program import Program
from cvxgeodesic.solvers.ipm.start import interior_primal

GRAPH = IPMSettings(init="graph")
LEAST_SQUARES = IPMSettings(init="interior", max_correctors=2)  # the defaults before the graph start


@pytest.fixture(scope="module")
def sphere():
    m = icosphere(3)
    ops = MeshOperators(m)
    P = abs(ops.energy("hessian")) + abs(ops.energy("laplacian"))
    return m, ops, kkt_pattern(m.n_vertices, m.F, m.edges, P)


def _program(pattern, p, settings=GRAPH):
    ipm = InteriorPointSolver(pattern, settings=settings)
    return ipm, ipm._prepare(p)


def _cone_norms(pr, x):
    body = pr.blocks[0].Bx(x)
    return np.hypot(body[0], body[1])


def test_cone_edge_bounds_are_the_edge_lengths(sphere):
    # with B_t the gradient of the unit sphere mesh's triangles, ℓ_ab is the Euclidean edge length
    m, ops, pattern = sphere
    _, pr = _program(pattern, build_problem(ops, np.array([0]), "qclp", 0.0))
    cones = pr.blocks[0]
    src, dst, w = edge_arcs(pr)
    on_cones = (src < m.n_vertices) & np.isin(np.arange(src.size), np.arange(6 * cones.count))
    length = np.linalg.norm(m.V[src[on_cones]] - m.V[dst[on_cones]], axis=1)
    scale = np.median(w[on_cones] / length)  # the problem is built on the mesh as given or scaled by a constant
    np.testing.assert_allclose(w[on_cones], scale * length, rtol=1e-9)


@pytest.mark.parametrize("method", ["qclp", "lclp", "qcqp-hessian"])
def test_graph_field_meets_every_edge_bound_and_is_strictly_feasible_once_scaled(sphere, method):
    m, ops, pattern = sphere
    p = build_problem(ops, np.array([0, 200]), method, smoothness_weight(m, 1.0))
    _, pr = _program(pattern, p)
    xg = graph_field(pr)
    assert xg is not None
    src, dst, w = edge_arcs(pr)
    x_ext = np.append(xg, 0.0)
    assert np.all(x_ext[dst] <= x_ext[src] + w + 1e-12)
    np.testing.assert_array_equal(xg[pr.fixed], pr.x_fixed[pr.fixed])
    assert xg[pr.free].min() > 0.0
    xi = interior_primal(pr, xg, GRAPH.interior_fraction)
    assert xi is not None
    for b in pr.blocks:
        assert b.cone.min_eigenvalue(b.slack(xi, pr.x_fixed)) > 0.0
    # an upper bound of every feasible field, so of the optimum; and much closer to it than x_F = 0
    ipm, _ = _program(pattern, p)
    res = ipm.solve(p)
    free = pr.free
    assert np.all(res.x[free] <= xg[free] + 1e-7)
    assert np.median(xi[free] / res.x[free]) > 0.5


@pytest.mark.parametrize("method", ["qclp", "lclp", "qcqp-hessian", "lcqp-laplacian"])
def test_graph_start_reaches_the_same_optimum(sphere, method):
    m, ops, pattern = sphere
    p = build_problem(ops, np.array([3]), method, smoothness_weight(m, 1.0))
    new = InteriorPointSolver(pattern, settings=GRAPH).solve(p)
    old = InteriorPointSolver(pattern, settings=LEAST_SQUARES).solve(p)
    # both within 1e-6 of the diagonal from the optimum to a tighter tolerance (qclp: 5e-9 and 1.5e-7)
    tight = InteriorPointSolver(pattern, settings=LEAST_SQUARES).solve(p, tol=1e-11)
    assert new.status == old.status == "optimal"
    assert np.abs(new.x - tight.x).max() <= 1e-6 * m.bbox_diagonal
    assert np.abs(old.x - tight.x).max() <= 1e-6 * m.bbox_diagonal
    first = {}
    InteriorPointSolver(pattern, settings=GRAPH).solve(p, callback=lambda k, i: first.setdefault(k, i))
    assert first[0]["res_primal"] < 1e-12  # strictly feasible: no primal residual


def test_fixed_values_set_the_field_even_when_negative(sphere):
    m, ops, pattern = sphere
    p = build_problem(ops, np.array([0]), "qclp", 0.0)
    far = int(np.argmin(m.V @ m.V[0]))
    fm, fv = p.fixed_mask.copy(), p.fixed_values.copy()
    fm[far], fv[far], fv[0] = True, 0.5 * m.mean_edge_length, -0.25 * m.mean_edge_length
    _, pr = _program(pattern, dataclasses.replace(p, fixed_mask=fm, fixed_values=fv))
    xg = graph_field(pr)
    assert xg[0] == fv[0] and xg[far] == fv[far]
    src, dst, w = edge_arcs(pr)
    x_ext = np.append(xg, 0.0)
    assert np.all(x_ext[dst] <= x_ext[src] + w + 1e-12)
    assert xg.min() == fv[0]


def test_two_components_and_sources_in_each():
    a, b = icosphere(2), icosphere(1)
    m = TriMesh(np.vstack([a.V, b.V + [3.0, 0.0, 0.0]]), np.vstack([a.F, b.F + a.n_vertices]), name="two-spheres")
    ops = MeshOperators(m)
    for sources in ([5], [5, a.n_vertices + 2]):  # the second sphere unreachable, then reached
        p = build_problem(ops, np.array(sources), "qcqp-hessian", smoothness_weight(m, 1.0))
        pattern = kkt_pattern(m.n_vertices, m.F, m.edges, p.P)
        _, pr = _program(pattern, p)
        xg = graph_field(pr)
        assert xg is not None and np.isfinite(xg).all()
        assert np.all(xg[p.unreachable] == 0.0)
        new = InteriorPointSolver(pattern, settings=GRAPH).solve(p)
        tight = InteriorPointSolver(pattern, settings=LEAST_SQUARES).solve(p, tol=1e-11)
        assert new.status == "optimal"
        assert np.abs(new.x - tight.x).max() <= 1e-6 * m.bbox_diagonal


def _tiny_program(extra_ineq, settings=GRAPH):
    """Two triangles (0, 1, 2), (1, 2, 3) with gradient cones, vertex 0 fixed at 0, vertex 4 constrained only by
    ``extra_ineq`` (rows of (vertices, coefficients, rhs))."""
    V = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    tris = np.array([[0, 1, 2], [1, 3, 2]])
    B = []
    for t in tris:
        E = np.column_stack([V[t[1]] - V[t[0]], V[t[2]] - V[t[0]]])  # 2×2
        G = np.linalg.inv(E.T)  # gradient of the linear interpolant from (x1 − x0, x2 − x0)
        B.append(G @ np.array([[-1.0, 1.0, 0.0], [-1.0, 0.0, 1.0]]))
    B = np.array(B)
    iv = np.array([r[0] for r in extra_ineq], dtype=np.int64)
    ia = np.array([r[1] for r in extra_ineq], dtype=float)
    ib = np.array([r[2] for r in extra_ineq], dtype=float)
    n = 5
    rows = np.concatenate([np.repeat(tris, 3, axis=1).ravel(), np.repeat(iv, 2, axis=1).ravel(), np.arange(n)])
    cols = np.concatenate([np.tile(tris, (1, 3)).ravel(), np.tile(iv, (1, 2)).ravel(), np.arange(n)])
    import scipy.sparse as sp

    pattern = sp.csc_matrix((np.ones(rows.size), (rows, cols)), shape=(n, n))
    ipm = InteriorPointSolver(pattern, settings=settings)
    fixed = np.zeros(n, dtype=bool)
    fixed[0] = True
    q = -np.ones(n)
    q[0] = 0.0

    def blocks(xf, chol):
        return [TriangleSOCBlock(B, tris, xf, chol), PairInequalityBlock(iv, ia, ib, xf, chol)]

    return ipm, Program(None, q, fixed, np.zeros(n), blocks, ipm.cholesky)


def test_a_variable_no_edge_bound_reaches_falls_back_to_the_least_squares_start():
    # vertex 4: 2 x4 + x3 <= 5 and x4 >= 0 bound no difference, so no path reaches it (distance inf)
    ipm, pr = _tiny_program([([4, 3], [2.0, 1.0], 5.0), ([4, 4], [-1.0, 0.0], 0.0)])
    assert graph_field(pr) is None
    res = ipm.solve_program(pr)
    assert res.status == "optimal"
    # the optimum: x1 = x2 = 1/√2, x3 = √2 (the gradient bound of both triangles), then x4 = (5 − √2) / 2
    np.testing.assert_allclose(res.x, [0.0, 0.5 ** 0.5, 0.5 ** 0.5, 2 ** 0.5, (5 - 2 ** 0.5) / 2], atol=1e-6)


def test_an_upper_bound_is_an_arc_from_the_root():
    # x4 <= 0.7 alone: the field is 0.7 there, and the solve from it (x_F strictly feasible) ends at the optimum
    ipm, pr = _tiny_program([([4, 4], [1.0, 0.0], 0.7)])
    xg = graph_field(pr)
    np.testing.assert_allclose(xg, [0.0, 1.0, 1.0, 2.0, 0.7])
    assert interior_primal(pr, xg, GRAPH.interior_fraction) is not None
    res = ipm.solve_program(pr)
    assert res.status == "optimal"
    np.testing.assert_allclose(res.x, [0.0, 0.5 ** 0.5, 0.5 ** 0.5, 2 ** 0.5, 0.7], atol=1e-6)
