"""The paper's facts (Lemma 1, Theorems 1 and 2), analytic distances, and all eight formulations.

Tolerances: Clarabel is run at its default tolerance here (1e-8 relative gap), so
"equal" means within 1e-6 of the mesh's bounding-box diagonal.
"""

import numpy as np
import pytest
from scipy.sparse.csgraph import dijkstra

import cvxgeodesic as cg
from conftest import shared_mesh_path
from cvxgeodesic.errors import ParameterError
from cvxgeodesic.mesh import cylinder, grid_plane, icosphere
from cvxgeodesic.operators import gradient_norms
from cvxgeodesic.problems.formulations import (
    FORMULATIONS,
    KAPPA,
    MeshOperators,
    build_problem,
    canonical_method,
    smoothness_weight,
    stretch_weights,
)
from cvxgeodesic.solvers import solve_clarabel
from cvxgeodesic.sources import resolve_sources

GENERATED = [icosphere(2), grid_plane(8, jitter=0.3), cylinder(16, 6)]


def _dijkstra(mesh, sources):
    return dijkstra(mesh.vertex_adjacency, indices=np.atleast_1d(sources), min_only=True)


@pytest.mark.parametrize("mesh", GENERATED + [grid_plane(7, 5, jitter=0.2, seed=3)], ids=lambda m: m.name)
def test_lemma1_lclp_equals_dijkstra(mesh):
    for sources in ([0], [3, mesh.n_vertices - 1]):
        d = cg.geodesic_distance(mesh, sources, method="lclp", solver="clarabel")
        np.testing.assert_allclose(d, _dijkstra(mesh, sources), atol=1e-6 * mesh.bbox_diagonal)


@pytest.mark.parametrize("mesh", GENERATED, ids=lambda m: m.name)
def test_theorems_1_and_2_for_qclp(mesh):
    sources = [1]
    d = cg.geodesic_distance(mesh, sources, method="qclp", solver="clarabel")
    tol = 1e-6 * mesh.bbox_diagonal
    # Theorem 2: QCLP <= Dijkstra everywhere
    assert np.all(d <= _dijkstra(mesh, sources) + tol)
    # Theorem 1: edge triangle inequality
    E = mesh.edges
    assert np.all(np.abs(d[E[:, 0]] - d[E[:, 1]]) <= mesh.edge_lengths + tol)
    # and the constraint itself on every triangle away from the source
    away = ~np.isin(mesh.F, sources).any(axis=1)
    assert gradient_norms(mesh, d)[away].max() <= 1 + 1e-6


def test_qclp_on_plane_matches_euclidean_and_converges():
    """On a convex flat square the geodesic distance is Euclidean.

    QCLP is 1-Lipschitz along the surface away from the source star, so it can
    exceed the Euclidean distance only by the detour through a one-ring vertex
    (< one edge length); it undershoots where the piecewise-linear interpolant of
    the exact cone would need a gradient above 1, an O(h / r) effect that
    shrinks under refinement. The worst relative error is next to the source.
    """
    worst = []
    for n in (10, 20, 40):
        mesh = grid_plane(n, jitter=0.25)
        s = int(np.argmin(np.linalg.norm(mesh.V - [0.5, 0.5, 0.0], axis=1)))
        d = cg.geodesic_distance(mesh, s, method="qclp", solver="clarabel")
        e = np.linalg.norm(mesh.V - mesh.V[s], axis=1)
        assert np.all(d <= e + mesh.mean_edge_length)
        band = e > 0.25
        rel = np.abs(d - e)[band] / e[band]
        assert rel.mean() < 0.035
        worst.append(rel.max())
    assert worst[0] > worst[1] > worst[2]
    assert worst[2] < 0.06


def test_qclp_on_sphere_converges_to_great_circle_distance():
    h, err = [], []
    for k in (2, 3, 4):
        mesh = icosphere(k)
        d = cg.geodesic_distance(mesh, 0, method="qclp", solver="clarabel")
        gc = np.arccos(np.clip(mesh.V @ mesh.V[0], -1.0, 1.0))
        h.append(mesh.mean_edge_length)
        err.append(np.abs(d - gc)[1:].mean())
    rate = np.polyfit(np.log(h), np.log(err), 1)[0]
    # measured: mean abs error 0.029, 0.022, 0.016 -> rate ≈ 0.43 (the error is dominated by the source cone)
    assert err[0] > err[1] > err[2]
    assert 0.3 < rate < 1.5


def test_qclp_on_cylinder_matches_unrolled_distance():
    mesh = cylinder(48, 24, radius=1.0, height=2.0)
    s = int(np.argmin(np.linalg.norm(mesh.V - [1.0, 0.0, 1.0], axis=1)))
    d = cg.geodesic_distance(mesh, s, method="qclp", solver="clarabel")
    theta = np.arctan2(mesh.V[:, 1], mesh.V[:, 0])
    arc = np.abs(np.angle(np.exp(1j * (theta - theta[s]))))
    e = np.hypot(arc, mesh.V[:, 2] - mesh.V[s, 2])
    far = e > 0.5
    assert (np.abs(d - e)[far] / e[far]).mean() < 0.02


@pytest.mark.parametrize("method", [*FORMULATIONS])
@pytest.mark.parametrize("mesh", GENERATED, ids=lambda m: m.name)
def test_every_formulation_solves_on_generated_meshes(mesh, method):
    res = cg.GeodesicSolver(mesh, method, solver="clarabel").solve([0])
    d = res.distance
    assert res.info.status in ("optimal", "almost_optimal")
    assert np.all(np.isfinite(d)) and d[0] == 0.0 and np.all(d >= -1e-9)
    assert np.all(d <= _dijkstra(mesh, [0]) + 1e-6 * mesh.bbox_diagonal)
    assert res.info.iterations > 0 and res.info.solve_time > 0


@pytest.mark.shared
@pytest.mark.parametrize("name", ["spot.obj", "bunny_7k.off"])
def test_every_formulation_solves_on_real_meshes(name):
    mesh = cg.load_mesh(shared_mesh_path(name))
    ops = MeshOperators(mesh)
    dj = _dijkstra(mesh, [0])
    lam = smoothness_weight(mesh, 1.0)
    for method in FORMULATIONS:
        res = solve_clarabel(build_problem(ops, np.array([0]), method, lam))
        assert res.status in ("optimal", "almost_optimal"), method
        assert np.all(res.x <= dj + 1e-6 * mesh.bbox_diagonal), method


def test_smoothness_lowers_hessian_energy():
    mesh = icosphere(3)
    ops = MeshOperators(mesh)
    H = ops.energy("hessian")
    d0 = cg.geodesic_distance(mesh, 0, method="qclp", solver="clarabel")
    # the default m = 1 rounds by a length on the surface that 642 vertices do not resolve (measured: energy
    # ratio 0.999998); m = 300 gives 0.744, m = 3000 0.372
    d1 = cg.geodesic_distance(mesh, 0, method="qcqp-hessian", m=300.0, solver="clarabel")
    assert d1 @ H @ d1 < 0.8 * (d0 @ H @ d0)
    w = stretch_weights(mesh)
    assert w @ d1 < w @ d0  # QCLP maximizes the area-weighted sum; any other term can only lower it


def test_lam_zero_equals_lp():
    mesh = icosphere(2)
    d_lp = cg.geodesic_distance(mesh, 0, method="qclp", solver="clarabel")
    d_qp = cg.geodesic_distance(mesh, 0, method="qcqp-laplacian", lam=0.0, solver="clarabel")
    np.testing.assert_allclose(d_qp, d_lp, atol=1e-6)


def test_several_sources_give_min_of_single_sources_for_lclp():
    mesh = grid_plane(8, jitter=0.2)
    d01 = cg.geodesic_distance(mesh, [0, 80], method="lclp", solver="clarabel")
    d0 = cg.geodesic_distance(mesh, 0, method="lclp", solver="clarabel")
    d1 = cg.geodesic_distance(mesh, 80, method="lclp", solver="clarabel")
    np.testing.assert_allclose(d01, np.minimum(d0, d1), atol=1e-6)


def test_unreachable_component_is_inf():
    a, b = icosphere(1), icosphere(1)
    V = np.vstack([a.V, b.V + [5.0, 0, 0]])
    F = np.vstack([a.F, b.F + a.n_vertices])
    for method in ("qclp", "lclp", "qcqp-hessian"):
        res = cg.GeodesicSolver((V, F), method, solver="clarabel").solve(0)
        assert np.all(np.isfinite(res.distance[: a.n_vertices]))
        assert np.all(np.isinf(res.distance[a.n_vertices:]))
        assert res.info.n_unreachable == b.n_vertices


@pytest.mark.parametrize("method", ["qclp", "qcqp-hessian", "lcqp-laplacian"])
def test_scale_equivariance(method):
    mesh = icosphere(2)
    d = cg.geodesic_distance(mesh, 0, method=method, solver="clarabel")
    for s in (1e-3, 1e3):
        ds = cg.geodesic_distance((mesh.V * s, mesh.F), 0, method=method, solver="clarabel")
        np.testing.assert_allclose(ds / s, d, atol=1e-5 * mesh.bbox_diagonal)


def test_smoothness_weight_formula():
    mesh = icosphere(2)
    paper = smoothness_weight(mesh, 2.0, normalization="paper")
    assert paper == pytest.approx(2.0 * 100 * mesh.mean_edge_length / mesh.n_vertices)
    area = smoothness_weight(mesh, 2.0)
    assert area == pytest.approx(2.0 * KAPPA["hessian"] * np.sqrt(mesh.face_areas.sum()))
    with pytest.raises(ParameterError, match="unknown normalization 'mean'; choose one of area, paper"):
        smoothness_weight(mesh, 1.0, normalization="mean")


def test_canonical_method_resolves_case_and_aliases_and_names_the_choices():
    assert canonical_method("QGDF") == "lcqp-hessian" and canonical_method("QCLP") == "qclp"
    for bad in ("qcqp", 5):
        with pytest.raises(ParameterError, match=f"^unknown formulation {bad!r}; choose one of lclp, .*, qgdf$"):
            canonical_method(bad)  # type: ignore[arg-type]


def test_area_normalization_does_not_depend_on_the_triangulation():
    """λ and the stretch weights of two triangulations of one square: same λ, same integral of a linear field."""
    coarse = grid_plane(6, jitter=0.3, seed=2)
    g = grid_plane(23)
    graded = cg.TriMesh(np.column_stack([g.V[:, 0] ** 1.5, g.V[:, 1:]]), g.F)  # dense near x = 0
    assert smoothness_weight(coarse, 1.0) == pytest.approx(smoothness_weight(graded, 1.0), rel=1e-12)
    for mesh, tol in ((coarse, 1e-12), (graded, 1e-4)):  # graded: its corner vertices get the floor weight
        w = stretch_weights(mesh)
        assert w.sum() == pytest.approx(1.0) and w.min() > 0
        assert w @ mesh.V[:, 0] == pytest.approx(0.5, abs=tol)  # the mean of x over the unit square
    uniform = stretch_weights(graded, "mean")
    assert uniform @ graded.V[:, 0] == pytest.approx(0.4, abs=1e-2)  # vertices counted, not area


def test_default_m_rounds_the_ridge_and_keeps_accuracy_off_it():
    """The calibration documented in docs/method.md, on the bundled spot mesh (source 0).

    Measured: ridge sharpness 0.725 (exact) -> 0.492 (qcqp-hessian, m = 1; the paper normalization:
    0.291); error off the ridge 1.88 % (qclp) -> 1.90 % (paper: 1.94 %).
    """
    from cvxgeodesic.demo import demo_mesh
    from cvxgeodesic.evaluation import smoothness_report

    mesh = demo_mesh()
    exact = cg.geodesic_distance(mesh, 0, method="exact")
    reports = {}
    for method in ("qclp", "qcqp-hessian"):
        d = cg.geodesic_distance(mesh, 0, method=method, solver="clarabel")
        reports[method] = smoothness_report(mesh, d, exact, [0])
    assert reports["qcqp-hessian"]["ridge_jump_p95"] < 0.75 * reports["qcqp-hessian"]["exact_ridge_jump_p95"]
    assert reports["qclp"]["ridge_jump_p95"] > 0.9 * reports["qclp"]["exact_ridge_jump_p95"]
    assert reports["qcqp-hessian"]["off_ridge_rel_mean"] < 1.05 * reports["qclp"]["off_ridge_rel_mean"]


def test_edge_bounds_at_rounding_level_are_floored():
    # vertex 3 sits 1e-15 from vertex 1 (not an exact duplicate, so not welded): |d_1 - d_3| <= 1e-15 would be
    # an equality in disguise, whose duals blow up in the interior-point method
    V = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1e-15, 0.0], [1.0, 1.0, 0.0]])
    F = np.array([[0, 1, 2], [1, 3, 2], [3, 4, 2]])
    mesh = cg.TriMesh(V, F, name="near_duplicate")
    ops = MeshOperators(mesh)
    floor = cg.problems.formulations.MIN_EDGE_BOUND * mesh.bbox_diagonal
    for method in ("lclp", "qclp"):
        p = build_problem(ops, np.array([0]), method, 0.0)
        edge_rows = p.ineq.coeffs[:, 1] != 0  # two-vertex rows (not the bounds d >= 0 next to the source)
        assert p.ineq.rhs[edge_rows].min() == pytest.approx(floor), method
    d = cg.geodesic_distance(mesh, [0], method="lclp", solver="ipm")
    np.testing.assert_allclose(d, _dijkstra(mesh, 0), atol=1e-7)


def test_lclp_on_a_mesh_with_near_duplicate_vertices_equals_dijkstra(monkeypatch):
    # thingi_65395 has edges of length 6e-16; before the floor the IPM stopped at an objective 5x too high
    # (uniform stretch weights: with the area weights, which span 0.05 to 54 times their mean on this file, the
    # IPM from the least-squares start does not converge within 200 iterations, and solver="auto" retries with
    # Clarabel, as checked below; from the graph start it converges in 41)
    import cvxgeodesic.solvers.ipm.solver as ipm_solver
    from cvxgeodesic.solvers.ipm import IPMSettings

    mesh = cg.load_mesh(shared_mesh_path("thingi_65395.stl"))
    res = cg.GeodesicSolver(mesh, "lclp", solver="ipm", normalization="paper").solve(0)
    assert res.info.status == "optimal" and res.info.solver == "ipm"
    np.testing.assert_allclose(res.distance, _dijkstra(mesh, 0), atol=1e-6 * mesh.bbox_diagonal)
    res = cg.GeodesicSolver(mesh, "lclp").solve(0)
    assert res.info.solver == "ipm" and res.info.status == "optimal"
    np.testing.assert_allclose(res.distance, _dijkstra(mesh, 0), atol=1e-6 * mesh.bbox_diagonal)
    monkeypatch.setattr(ipm_solver, "IPMSettings", lambda: IPMSettings(init="interior"))
    with pytest.warns(RuntimeWarning, match="solving with Clarabel instead"):
        res = cg.GeodesicSolver(mesh, "lclp").solve(0)
    assert res.info.solver == "clarabel" and any("Clarabel" in note for note in res.info.notes)
    np.testing.assert_allclose(res.distance, _dijkstra(mesh, 0), atol=1e-6 * mesh.bbox_diagonal)


def test_without_the_floor_the_solver_fails_loudly_rather_than_wrongly(monkeypatch):
    # the edge floor removed: duals of the 6e-16 edges reach 1e13 and the dual residual relative to ‖z‖ looks
    # converged (5e-8) at an objective 5x off; the residual relative to ‖q‖ + ‖x‖ alone must stop that
    import cvxgeodesic.problems.formulations as formulations
    from cvxgeodesic.errors import SolverError

    monkeypatch.setattr(formulations, "MIN_EDGE_BOUND", 0.0)
    mesh = cg.load_mesh(shared_mesh_path("thingi_65395.stl"))
    try:
        res = cg.GeodesicSolver(mesh, "lclp", solver="ipm").solve(0)
    except SolverError:
        return
    np.testing.assert_allclose(res.distance, _dijkstra(mesh, 0), atol=1e-5 * mesh.bbox_diagonal)


def _bounded_below(problem) -> np.ndarray:
    """The vertices with a row ``-d_v <= 0`` (the bounds d >= 0)."""
    rows = (problem.ineq.coeffs[:, 0] == -1.0) & (problem.ineq.coeffs[:, 1] == 0.0)
    return np.unique(problem.ineq.vertices[rows, 0])


def test_the_bounds_next_to_a_source_cover_one_surface_disc_at_every_resolution():
    """The dip below 0 next to a source is as wide as the smoothing length, a length on the surface: max_planck
    subdivided to 21K vertices went negative three edges from its sources, beyond the NONNEGATIVE_HOPS = 2 that
    covered it at 5K (2026-12-03). The bounds reach NONNEGATIVE_RADIUS smoothing lengths along edges, whatever the
    triangulation (m = 20 makes the disc wider than two edges of the finer grid, so the radius shows)."""
    from cvxgeodesic.problems.formulations import (
        NONNEGATIVE_EDGE_RADIUS,
        NONNEGATIVE_HOPS,
        NONNEGATIVE_RADIUS,
        smoothing_length,
    )

    reach = {}
    for n in (9, 41):
        mesh = grid_plane(n)  # the unit square, the source at its centre
        ops = MeshOperators(mesh)
        lam = smoothness_weight(mesh, 20.0)
        centre = int(np.argmin(np.linalg.norm(mesh.V[:, :2] - 0.5, axis=1)))
        radius = NONNEGATIVE_RADIUS * smoothing_length(ops, lam)
        # (20 · 3e-6)^(1/3) on the unit square: the formula of the area normalization
        assert radius == pytest.approx(NONNEGATIVE_RADIUS * (20.0 * KAPPA["hessian"]) ** (1 / 3), rel=1e-9)
        bounded = _bounded_below(build_problem(ops, np.array([centre]), "qcqp-hessian", lam))
        path = dijkstra(mesh.vertex_adjacency, indices=centre)  # edge-path lengths, as the bounds measure them
        hops = dijkstra(mesh.vertex_adjacency, indices=centre, unweighted=True)
        edge_radius = NONNEGATIVE_EDGE_RADIUS * mesh.mean_edge_length
        inside = np.flatnonzero((path <= max(radius, edge_radius)) | (hops <= NONNEGATIVE_HOPS))
        np.testing.assert_array_equal(bounded, inside[inside != centre])
        reach[n] = (float(path[bounded].max()), int(hops[bounded].max()), radius)
    assert reach[9][1] == NONNEGATIVE_HOPS  # the coarse grid: two edges (0.25, 0.35 long) reach beyond the disc
    far, deep, radius = reach[41]
    assert deep > NONNEGATIVE_HOPS + 2  # the fine grid: the same disc is many edges wide ...
    assert radius - 0.05 < far <= radius  # ... and filled to within a diagonal edge (0.035) of its radius


@pytest.mark.parametrize("method", ["qclp", "lclp", "qcqp-dirichlet"])
def test_without_a_second_order_energy_the_bounds_reach_two_edges(method):
    # the smoothing length is that of the energies of second derivatives; QCLP's negative values (the medial-axis
    # bug) and the Dirichlet energy's were all within NONNEGATIVE_HOPS edges, or NONNEGATIVE_EDGE_RADIUS mean edge
    # lengths on camelhead_open: on this uniform grid 2.5 mean edge lengths (0.071) fall short of three edges (0.075)
    from cvxgeodesic.problems.formulations import NONNEGATIVE_HOPS

    mesh = grid_plane(41)
    centre = int(np.argmin(np.linalg.norm(mesh.V[:, :2] - 0.5, axis=1)))
    problem = build_problem(MeshOperators(mesh), np.array([centre]), method, smoothness_weight(mesh, 20.0))
    hops = dijkstra(mesh.vertex_adjacency, indices=centre, unweighted=True)
    assert hops[_bounded_below(problem)].max() == NONNEGATIVE_HOPS


def test_the_bounds_next_to_a_source_reach_a_radius_in_mean_edge_lengths_through_tiny_edges():
    """camelhead_open's QCLP from vertex 6104 went negative (-5.2e-3) 3-8 edges from the source, 0.7-3.3 mean edge
    lengths along edges, among skinny faces with edges 0.1x the mean: the two edges bounded then reached a tenth of
    that, and the solve was repeated with d >= 0 everywhere (2026-12-06, docs/dev/endgame.md). Every formulation now
    also bounds the vertices within NONNEGATIVE_EDGE_RADIUS mean edge lengths along edges. Here a grid graded
    cubically towards its centre (edges of 0.0005 at the source, 0.060 on average): 24 vertices within two edges,
    164 within the radius (0.150), up to 6 edges away."""
    from cvxgeodesic.problems.formulations import NONNEGATIVE_EDGE_RADIUS, NONNEGATIVE_HOPS

    grid = grid_plane(20)
    t = 2.0 * grid.V[:, :2] - 1.0
    V = grid.V.copy()
    V[:, :2] = 0.5 + 0.5 * np.sign(t) * np.abs(t) ** 3
    mesh = cg.TriMesh(V, grid.F)
    centre = int(np.argmin(np.linalg.norm(mesh.V[:, :2] - 0.5, axis=1)))
    assert mesh.edge_lengths[(mesh.edges == centre).any(axis=1)].max() < 0.02 * mesh.mean_edge_length
    path = dijkstra(mesh.vertex_adjacency, indices=centre)
    hops = dijkstra(mesh.vertex_adjacency, indices=centre, unweighted=True)
    inside = np.flatnonzero((path <= NONNEGATIVE_EDGE_RADIUS * mesh.mean_edge_length) | (hops <= NONNEGATIVE_HOPS))
    for method in ("qclp", "qcqp-hessian"):  # the smoothing length of m = 1 is shorter than this radius here
        bounded = _bounded_below(build_problem(MeshOperators(mesh), np.array([centre]), method,
                                               smoothness_weight(mesh, 1.0)))
        np.testing.assert_array_equal(bounded, inside[inside != centre])
    assert (hops[bounded] <= NONNEGATIVE_HOPS).sum() == 24 and len(bounded) == 164
    assert hops[bounded].max() == NONNEGATIVE_HOPS + 4


def test_the_bounded_disc_of_a_constant_travel_cost_is_that_of_the_scaled_mesh():
    # a constant cost c is the mesh scaled by c (docs/metrics.md): the smoothing length is measured in the medium,
    # whose edge lengths and areas are normalized by its own power of two, as lambda is
    def bounded(solver):
        st = solver._strategy
        src = resolve_sources(solver.mesh, [220])
        return _bounded_below(build_problem(st.ops, src, "qcqp-hessian", st.config.lam / st.scale))

    mesh = grid_plane(41)
    scaled = cg.TriMesh(3.0 * mesh.V, mesh.F)
    with_cost = bounded(cg.GeodesicSolver(mesh, "qcqp-hessian", m=20.0, cost=3.0))
    np.testing.assert_array_equal(with_cost, bounded(cg.GeodesicSolver(scaled, "qcqp-hessian", m=20.0)))
    assert with_cost.size > 20  # beyond the two edges' 19 vertices around an interior vertex: the disc decides
