"""Baselines (dijkstra, fmm, heat, exact) against analytic distances, plus their edge cases.

Tolerances (h̄ = mean edge length):

* flat ``grid_plane(20)``, source at the centre, Euclidean distance on every vertex:
  exact 1e-9 absolute (it is exact on flat meshes); Dijkstra between 1 and
  sqrt(4 - 2 sqrt 2) ≈ 1.0824 times Euclidean (edge paths on a grid with
  diagonals, the bound is attained); fast marching 0.5 h̄ max, 3% mean
  relative; heat 0.75 h̄ max (errors at the boundary), 3% mean relative.
* ``icosphere(4, radius=2)``, great-circle distance ``R·arccos(<p,s>/R²)``:
  exact within the rigorous band ``(r_min/R)·g <= d <= g`` (see
  ``test_sphere_exact``); fmm and heat 0.5 h̄ max and 2.5% mean relative;
  Dijkstra never below exact.
"""

from __future__ import annotations

import numpy as np
import pytest

from cvxgeodesic.baselines import (
    BASELINES,
    DEFAULT_T_COEF,
    BaselineSolver,
    DijkstraBaseline,
    ExactBaseline,
    HeatBaseline,
    nonmanifold_vertices,
)
from cvxgeodesic.errors import NonManifoldError, ParameterError, SolverError
from cvxgeodesic.mesh import TriMesh, grid_plane, icosphere

METHODS = ["dijkstra", "fmm", "heat", "exact"]
DIJKSTRA_GRID_FACTOR = np.sqrt(4.0 - 2.0 * np.sqrt(2.0))  # ≈ 1.0824, worst direction 22.5° off an axis


@pytest.fixture(scope="module")
def plane():
    return grid_plane(20)


@pytest.fixture(scope="module")
def sphere():
    return icosphere(4, radius=2.0)


@pytest.fixture(scope="module")
def sphere3():
    return icosphere(3)


def _great_circle(mesh: TriMesh, s: int, R: float) -> np.ndarray:
    return R * np.arccos(np.clip(mesh.V @ mesh.V[s] / R**2, -1.0, 1.0))


def _two_spheres_and_a_point() -> TriMesh:
    a = icosphere(2)
    V = np.vstack([a.V, a.V + 3.0, [[9.0, 9.0, 9.0]]])
    F = np.vstack([a.F, a.F + a.n_vertices])
    return TriMesh(V, F, name="two_spheres")


def _bowtie() -> TriMesh:
    """Two spheres touching at one vertex: edge-manifold, one non-manifold vertex."""
    a = icosphere(2)
    n = a.n_vertices
    V2 = -a.V + 2.0 * a.V[0]  # point reflection through vertex 0: copy k touches a at vertex 0
    F2 = a.F[:, ::-1] + n
    F2[F2 == n] = 0
    keep = np.r_[np.arange(n), np.arange(n + 1, 2 * n)]
    remap = np.full(2 * n, -1)
    remap[keep] = np.arange(keep.size)
    return TriMesh(np.vstack([a.V, V2])[keep], remap[np.vstack([a.F, F2])], name="bowtie")


def _three_sheets() -> TriMesh:
    """Three triangles on one edge (the nonmanifold_tiny.off toy)."""
    V = [[0, 0, 1], [0, 0, -0.7], [0, -1, 0], [0.4, -0.5, 0], [0.9, -0.1, 0]]
    return TriMesh(V, [[2, 1, 0], [3, 1, 0], [4, 1, 0]], name="three_sheets")


# ---------------------------------------------------------------- interface


def test_registry_and_info_keys(sphere3):
    assert set(BASELINES) == set(METHODS)
    for name, cls in BASELINES.items():
        assert issubclass(cls, BaselineSolver) and cls.name == name and cls.supports_multiple_sources
        solver = cls(sphere3)
        assert solver.setup_time >= 0
        d, info = solver.solve(np.array([0], dtype=np.int64))
        assert d.shape == (sphere3.n_vertices,) and d.dtype == np.float64
        for key in ("solver", "status", "iterations", "solve_time", "setup_time"):
            assert key in info
        assert info["status"] == "optimal" and info["iterations"] == 0
        assert info["solver"] == cls.library and info["setup_time"] == solver.setup_time
        assert d[0] == 0.0 and np.all(d[1:] > 0)


def test_heat_reports_t_coef(sphere3):
    d, info = HeatBaseline(sphere3).solve(np.array([0]))
    assert info["t_coef"] == DEFAULT_T_COEF == 1.0 and info["use_robust"] is True
    d2, info2 = HeatBaseline(sphere3, t_coef=4.0).solve(np.array([0]))
    assert info2["t_coef"] == 4.0 and not np.allclose(d, d2)
    for bad in (0.0, -1.0, np.nan, "x"):
        with pytest.raises(ParameterError, match="t_coef"):
            HeatBaseline(sphere3, t_coef=bad)


# ---------------------------------------------------------------- flat plane


@pytest.mark.parametrize("jitter", [0.0, 0.3])
def test_plane_exact(jitter):
    mesh = grid_plane(20, jitter=jitter)
    s = 220  # the centre vertex (10, 10)
    d, _ = ExactBaseline(mesh).solve(np.array([s]))
    np.testing.assert_allclose(d, np.linalg.norm(mesh.V - mesh.V[s], axis=1), rtol=0, atol=1e-9)


def test_plane_dijkstra_metric_bias(plane):
    s = 220  # x + y even: diagonals leave this vertex in all four directions
    e = np.linalg.norm(plane.V - plane.V[s], axis=1)
    d, _ = DijkstraBaseline(plane).solve(np.array([s]))
    assert np.all(d >= e - 1e-12)
    assert np.all(d <= DIJKSTRA_GRID_FACTOR * e + 1e-12)
    ratio = d[e > 0] / e[e > 0]
    assert ratio.max() > 1.08  # the bias is real and the bound is nearly attained


@pytest.mark.parametrize(("method", "max_abs_h", "mean_rel"), [("fmm", 0.5, 0.03), ("heat", 0.75, 0.03)])
def test_plane_approximate(plane, method, max_abs_h, mean_rel):
    s = 220
    e = np.linalg.norm(plane.V - plane.V[s], axis=1)
    d, _ = BASELINES[method](plane).solve(np.array([s]))
    h = plane.mean_edge_length
    assert np.abs(d - e).max() <= max_abs_h * h
    mask = e > 0
    assert np.mean(np.abs(d[mask] - e[mask]) / e[mask]) <= mean_rel


# ---------------------------------------------------------------- sphere


def test_sphere_exact(sphere):
    """The exact polyhedral distance d_P lies in a rigorous band around the great-circle distance g.

    Upper bound: the nearest-point projection onto the convex polyhedron P is 1-Lipschitz
    and maps the sphere S onto ∂P, fixing the vertices, so d_P <= g. Lower bound: the
    radial projection x -> R x/|x| maps ∂P onto S with Lipschitz constant R / r_min
    (r_min = distance of the origin to the closest face plane), so g <= (R / r_min) d_P.
    For icosphere(4) the band is 1 - r_min/R ≈ 0.1%; the measured mean error is 0.06%.
    """
    R, s = 2.0, 0
    g = _great_circle(sphere, s, R)
    d, _ = ExactBaseline(sphere).solve(np.array([s]))
    nrm = sphere.face_normals_unnormalized
    r_min = np.min(np.abs(np.einsum("ij,ij->i", nrm, sphere.V[sphere.F[:, 0]])) / np.linalg.norm(nrm, axis=1))
    assert 0.998 < r_min / R < 1.0
    assert np.all(d <= g + 1e-9)
    assert np.all(d >= (r_min / R) * g - 1e-9)
    assert np.mean(np.abs(d[1:] - g[1:]) / g[1:]) < 1e-3


@pytest.mark.parametrize("method", ["fmm", "heat"])
def test_sphere_approximate(sphere, method):
    R, s = 2.0, 0
    g = _great_circle(sphere, s, R)
    d, _ = BASELINES[method](sphere).solve(np.array([s]))
    assert np.abs(d - g).max() <= 0.5 * sphere.mean_edge_length
    assert np.mean(np.abs(d[1:] - g[1:]) / g[1:]) <= 0.025


def test_sphere_dijkstra_upper_bounds_exact(sphere):
    d_dij, _ = DijkstraBaseline(sphere).solve(np.array([0]))
    d_ex, _ = ExactBaseline(sphere).solve(np.array([0]))
    assert np.all(d_dij >= d_ex - 1e-9)  # an edge path is a path on the surface
    assert np.all(d_dij <= 1.25 * _great_circle(sphere, 0, 2.0) + 1e-9)


# ---------------------------------------------------------------- several sources


@pytest.mark.parametrize("method", ["dijkstra", "exact"])
def test_multisource_is_min_of_single_runs(sphere3, method):
    solver = BASELINES[method](sphere3)
    srcs = np.array([0, 5, 100])
    d, info = solver.solve(srcs)
    singles = np.min([solver.solve(np.array([s]))[0] for s in srcs], axis=0)
    np.testing.assert_allclose(d, singles, rtol=0, atol=1e-12)
    assert info["n_sources"] == 3


def test_multisource_fmm_marches_fronts_together(sphere3):
    """Native multi-source FMM is never above the min of single runs, and below it by < 0.5 h̄ (measured 0.18 h̄)."""
    solver = BASELINES["fmm"](sphere3)
    srcs = np.array([0, 5, 100])
    d, _ = solver.solve(srcs)
    singles = np.min([solver.solve(np.array([s]))[0] for s in srcs], axis=0)
    diff = d - singles
    assert diff.max() <= 1e-12
    assert diff.min() >= -0.5 * sphere3.mean_edge_length
    np.testing.assert_array_equal(d[srcs], 0.0)


def test_multisource_heat_close_to_exact(sphere3):
    """Multi-source heat diffuses all sources together: not the min of single runs, but as accurate.

    Measured on icosphere(3): mean relative error 4.0% vs exact (min of single heat runs: 2.5%);
    |multi - min| up to 0.9 h̄; values at the sources up to 0.12 h̄ off zero.
    """
    srcs = np.array([0, 5, 100])
    h = sphere3.mean_edge_length
    solver = HeatBaseline(sphere3)
    d, info = solver.solve(srcs)
    singles = np.min([solver.solve(np.array([s]))[0] for s in srcs], axis=0)
    assert np.abs(d - singles).max() <= 1.5 * h
    assert info["max_abs_at_sources"] <= 0.25 * h
    d_ex, _ = ExactBaseline(sphere3).solve(srcs)
    mask = np.ones(sphere3.n_vertices, bool)
    mask[srcs] = False
    assert np.mean(np.abs(d[mask] - d_ex[mask]) / d_ex[mask]) < 0.06


# ---------------------------------------------------------------- components, non-manifold


@pytest.mark.parametrize("method", METHODS)
def test_unreached_components_are_inf(method):
    mesh = _two_spheres_and_a_point()  # 162 + 162 vertices, then one unreferenced vertex
    solver = BASELINES[method](mesh)
    d, _ = solver.solve(np.array([0]))
    assert np.all(np.isinf(d[162:]))
    alone, _ = BASELINES[method](icosphere(2)).solve(np.array([0]))
    np.testing.assert_allclose(d[:162], alone, rtol=0, atol=1e-12)
    # a source in each component (and on the unreferenced vertex): finite everywhere
    d, _ = solver.solve(np.array([0, 170, 324]))
    assert np.all(np.isfinite(d)) and d[324] == 0.0
    # a source only on the unreferenced vertex
    d, _ = solver.solve(np.array([324]))
    assert d[324] == 0.0 and np.all(np.isinf(d[:324]))


def test_nonmanifold_vertices():
    assert nonmanifold_vertices(icosphere(2)).size == 0
    assert nonmanifold_vertices(grid_plane(3)).size == 0
    np.testing.assert_array_equal(nonmanifold_vertices(_bowtie()), [0])


@pytest.mark.parametrize("mesh_factory", [_three_sheets, _bowtie])
@pytest.mark.parametrize("method", ["fmm", "exact"])
def test_nonmanifold_rejected_up_front(mesh_factory, method):
    with pytest.raises(NonManifoldError, match="dijkstra"):
        BASELINES[method](mesh_factory())


@pytest.mark.parametrize("method", ["dijkstra", "heat"])
def test_nonmanifold_accepted(method):
    mesh = _three_sheets()
    d, _ = BASELINES[method](mesh).solve(np.array([2]))
    assert np.all(np.isfinite(d)) and d[2] == 0.0
    # through the shared edge (1, 0): vertex 4 is at least its straight-line distance away
    assert d[4] >= np.linalg.norm(mesh.V[4] - mesh.V[2]) - 1e-9


# ---------------------------------------------------------------- library failures are wrapped


class _Broken:
    def compute_distance(self, *args, **kwargs):
        raise RuntimeError("boom")

    compute_distance_multisource = compute_distance

    def geodesicDistances(self, *args, **kwargs):  # noqa: N802 (pygeodesic's name)
        print("Error in PyGeodesicAlgorithmExact.geodesicDistances: broken")
        return None, None


@pytest.mark.parametrize("method", ["fmm", "heat", "exact"])
def test_library_failure_becomes_solver_error(sphere3, method):
    solver = BASELINES[method](sphere3)
    for part in solver._parts.values():
        part.solver = _Broken()
    with pytest.raises(SolverError, match=method) as exc:
        solver.solve(np.array([0]))
    assert exc.value.solver == BASELINES[method].library
    assert exc.value.status == "error"


# ---------------------------------------------------------------- face orientation (issue 34)


def _every_other_face_reversed(mesh: TriMesh) -> TriMesh:
    F = mesh.F.copy()
    F[::2] = F[::2, ::-1]
    return TriMesh(mesh.V, F, name=mesh.name)


def _mobius(nu: int = 24, nv: int = 4) -> TriMesh:
    """A Möbius strip: ``nu`` steps around, ``nv`` vertices across; the last row of faces joins the first twisted."""
    u, w = np.meshgrid(np.linspace(0, 2 * np.pi, nu, endpoint=False), np.linspace(-0.3, 0.3, nv), indexing="ij")
    r = 1 + w * np.cos(u / 2)
    V = np.c_[(r * np.cos(u)).ravel(), (r * np.sin(u)).ravel(), (w * np.sin(u / 2)).ravel()]
    F = []
    for i in range(nu):
        for j in range(nv - 1):
            a, b = i * nv + j, i * nv + j + 1
            c, d = ((i + 1) * nv + j, (i + 1) * nv + j + 1) if i + 1 < nu else (nv - 1 - j, nv - 2 - j)
            F += [[a, c, b], [b, c, d]]
    return TriMesh(V, F, name="mobius")


def _consistent(F: np.ndarray) -> bool:
    """Every edge of two faces is run through in opposite directions (no directed edge appears twice)."""
    directed = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    return np.unique(directed, axis=0).shape[0] == directed.shape[0]


# Without orienting, fmm moved by 10 % (icosphere) and 13 % (grid) of the largest distance and qcqp-hessian by
# 7e-5 / 9.6e-5 (libigl's curved Hessian energy). Oriented, the libraries see the same faces up to a global
# reversal, which changes neither (measured: 0 for fmm, 6e-14 for qcqp-hessian: round-off in the energy); heat and
# exact never depended on the orientation. Tolerances: 1e-12 for the libraries, 1e-9 for the convex solves (the
# interior-point iterates see a round-off-sized change of the energy).
@pytest.mark.parametrize("method, tol", [("fmm", 1e-12), ("heat", 1e-12), ("exact", 1e-12), ("qcqp-hessian", 1e-9),
                                         ("lcqp-hessian", 1e-9)])
@pytest.mark.parametrize("mesh", [icosphere(2), grid_plane(8, jitter=0.2, seed=1)], ids=["sphere", "grid"])
def test_reversed_faces_give_the_consistently_oriented_field(method, tol, mesh):
    import cvxgeodesic as cg
    from cvxgeodesic.errors import MeshRepairWarning

    d = cg.GeodesicSolver(mesh, method).solve(0).distance
    flipped = _every_other_face_reversed(mesh)
    if method in ("heat", "exact"):  # nothing to repair for them: no note, no warning
        res = cg.GeodesicSolver(flipped, method).solve(0)
        assert not any("reversed" in n for n in res.info.notes)
    else:
        with pytest.warns(MeshRepairWarning, match="faces reversed to orient the surface consistently"):
            res = cg.GeodesicSolver(flipped, method).solve(0)
        assert any(f"{mesh.n_faces // 2} of {mesh.n_faces} faces reversed to orient the surface consistently" in n
                   for n in res.info.notes), res.info.notes
    np.testing.assert_allclose(res.distance, d, rtol=0, atol=tol * d.max())


def test_fmm_point_sources_follow_the_reoriented_faces():
    """The barycentric coordinates of a point in a reversed face are reversed with it."""
    import cvxgeodesic as cg

    mesh = icosphere(2)
    F = mesh.F.copy()
    F[[0, 7, 30]] = F[[0, 7, 30], ::-1]  # a minority: these are the faces orient_faces turns back
    flipped = TriMesh(mesh.V, F)
    d = cg.GeodesicSolver(mesh, "fmm").solve([cg.SurfacePoint(0, [0.6, 0.3, 0.1])]).distance
    with pytest.warns(UserWarning, match="3 of 320 faces reversed"):
        d_f = cg.GeodesicSolver(flipped, "fmm").solve([cg.SurfacePoint(0, [0.1, 0.3, 0.6])]).distance
    np.testing.assert_allclose(d_f, d, rtol=0, atol=1e-12 * d.max())  # the same point: the same field


def test_orient_faces_makes_every_shared_edge_consistent_and_keeps_the_majority():
    from cvxgeodesic.mesh.orient import orient_faces

    mesh = icosphere(2)
    rng = np.random.default_rng(3)
    flip = rng.random(mesh.n_faces) < 0.3
    F = mesh.F.copy()
    F[flip] = F[flip, ::-1]
    o = orient_faces(F, mesh.n_vertices)
    assert _consistent(o.F) and not o.non_orientable.any()
    np.testing.assert_array_equal(o.flipped, flip)  # the 30 % minority is turned back, the rest kept
    np.testing.assert_array_equal(o.F, mesh.F)
    assert orient_faces(mesh.F, mesh.n_vertices).note("s", "x") is None  # consistent already: nothing to say
    # two pieces joined by a non-manifold edge are oriented each on its own
    three = _three_sheets()
    assert not orient_faces(three.F, three.n_vertices).changed


def test_a_non_orientable_surface_is_refused_by_fmm_and_solved_by_the_others():
    """Measured on this strip: fmm was 11 % of the largest distance off exact on average (1.3 % on the untwisted
    band), whatever the orientation, so it is refused; the other methods do not need an orientation."""
    import cvxgeodesic as cg
    from cvxgeodesic.errors import MeshError
    from cvxgeodesic.mesh.orient import orient_faces

    strip = _mobius()
    o = orient_faces(strip.F, strip.n_vertices)
    assert o.non_orientable.all() and not o.flipped.any()
    with pytest.raises(MeshError, match=r"mobius: method 'fmm' needs an orientable surface, but 144 faces lie on a "
                                        r"non-orientable piece .*use 'exact', 'heat', 'dijkstra'"):
        cg.GeodesicSolver(strip, "fmm")
    exact = cg.GeodesicSolver(strip, "exact").solve(0).distance
    for method in ("heat", "dijkstra", "qclp"):
        assert np.isfinite(cg.GeodesicSolver(strip, method).solve(0).distance).all(), method
    with pytest.warns(UserWarning, match="non-orientable piece"):
        res = cg.GeodesicSolver(strip, "qcqp-hessian").solve(0)
    assert any("non-orientable piece" in n for n in res.info.notes)
    assert np.isfinite(res.distance).all() and abs(res.distance.max() - exact.max()) < 0.1 * exact.max()
