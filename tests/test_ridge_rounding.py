"""Ridge rounding (``round_ridge``) and the smoothed adapted solves that use it."""

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic.errors import ParameterError
from cvxgeodesic.evaluation.smoothness import edge_gradient_jumps
from cvxgeodesic.mesh.trimesh import TriMesh
from cvxgeodesic.problems.ridge_rounding import RidgeRounding, ridge_rounding_length
from cvxgeodesic.strategies import adapted


@pytest.fixture(scope="module")
def plane():
    return cg.grid_plane(40)  # 41 x 41 vertices on [0, 1]², cell 0.025


def _two_sources(plane):
    a, b = 20 * 41 + 5, 20 * 41 + 35  # (0.125, 0.5) and (0.875, 0.5): their fronts meet on x = 0.5
    d = np.minimum(*(np.linalg.norm(plane.V - plane.V[s], axis=1) for s in (a, b)))
    return d, [a, b]


def test_a_field_without_a_ridge_is_returned_as_it_is(plane):
    d = np.linalg.norm(plane.V - plane.V[20 * 41 + 20], axis=1)  # one source: no cut locus on the square
    r = cg.round_ridge(plane, d, [20 * 41 + 20], length=0.05)
    assert not r.band.any()
    assert np.array_equal(r.distance, d)


def test_two_fronts_are_rounded_on_their_bisector_only(plane):
    d, sources = _two_sources(plane)
    r = cg.round_ridge(plane, d, sources, length=0.05)
    x = plane.V[:, 0]
    assert r.band.any() and np.all(np.abs(x[r.band] - 0.5) <= 0.05 + 0.025 + 1e-9)  # within ℓ (+ a cell) of it
    assert np.array_equal(r.distance[~r.band], d[~r.band])  # bit for bit off the band
    ridge = np.abs(x - 0.5) < 1e-9
    assert np.all(r.distance[ridge] < d[ridge] - 1e-3)  # the crease is lowered
    assert np.all(r.distance <= d + 1e-3)
    edges, jumps = edge_gradient_jumps(plane, d)
    on = r.band[edges].all(axis=1)
    _, rounded = edge_gradient_jumps(plane, r.distance)
    assert np.nanmax(rounded[on]) < 0.5 * np.nanmax(jumps[on])  # the turn is spread over several rows of edges


def test_the_rounding_scales_with_its_length(plane):
    """The crease is lowered over a width of about ℓ: twice the length, about twice the dip at the ridge."""
    d, sources = _two_sources(plane)
    dips = [float(np.max(d - cg.round_ridge(plane, d, sources, length=ell).distance)) for ell in (0.04, 0.08)]
    assert 1.5 < dips[1] / dips[0] < 2.5
    assert 0.1 * 0.04 < dips[0] < 0.04


def test_default_length_is_the_smoothing_length_of_m():
    plane = cg.grid_plane(20, size=2.0)  # area 4
    assert ridge_rounding_length(plane) == pytest.approx(0.0144 * 2.0, rel=2e-3)
    assert ridge_rounding_length(plane, 8.0) == pytest.approx(2 * ridge_rounding_length(plane))


def test_unreached_vertices_stay_unreached(plane):
    d, sources = _two_sources(plane)
    far = TriMesh(plane.V + [3.0, 0.0, 0.0], plane.F)  # a second component, no source on it
    both = TriMesh(np.vstack([plane.V, far.V]), np.vstack([plane.F, plane.F + plane.n_vertices]))
    r = cg.round_ridge(both, np.r_[d, np.full(plane.n_vertices, np.inf)], sources, length=0.05)
    assert np.isinf(r.distance[plane.n_vertices:]).all() and np.isfinite(r.distance[:plane.n_vertices]).all()
    np.testing.assert_array_equal(r.distance[:plane.n_vertices], cg.round_ridge(plane, d, sources,
                                                                                length=0.05).distance)


@pytest.mark.parametrize("kwargs, match", [
    ({"distance": np.zeros(5)}, "distance"),
    ({"distance": np.full(41 * 41, np.nan)}, "distance"),
    ({"sources": [41 * 41]}, "sources"),
    ({"length": 0.0}, "length"),
    ({"m": -1.0}, "m"),
])
def test_bad_input_names_the_parameter(plane, kwargs, match):
    d, sources = _two_sources(plane)
    args = {"distance": d, "sources": sources, **kwargs}
    with pytest.raises(ParameterError, match=match):
        cg.round_ridge(plane, args.pop("distance"), args.pop("sources"), **args)


def test_a_mesh_that_is_not_a_surface_is_refused(plane):
    d, sources = _two_sources(plane)
    with pytest.raises(TypeError, match="mesh"):
        cg.round_ridge(plane.V, d, sources)


@pytest.fixture(scope="module")
def cylinder():
    return cg.cylinder(48, 24, height=3.0)  # 2304 faces; from one vertex the fronts meet on the opposite line


def _opposite(cylinder):
    """Vertices on the side of the cylinder opposite vertex 0, where the fronts meet."""
    around = cylinder.V[:, :2] / np.linalg.norm(cylinder.V[:, :2], axis=1, keepdims=True)
    return around @ around[0] < -0.95


def test_smoothed_adapted_solves_round_the_ridge(cylinder, monkeypatch):
    assert cg.GeodesicSolver(cylinder, "qclp", order=2, resolution=600).solve(0).info.extra["adapted"][
        "ridge_rounding"] is None
    # m = 30: a rounding length of 1.5 cells around the cylinder (at m = 1 it is half a cell, too short to show)
    smooth = cg.GeodesicSolver(cylinder, "qcqp-hessian", order=2, resolution=600, m=30).solve(0)
    monkeypatch.setattr(adapted, "round_ridge", lambda mesh, d, *a, **k: RidgeRounding(d, d < 0, 1.0, 0.0))
    plain = cg.GeodesicSolver(cylinder, "qcqp-hessian", order=2, resolution=600, m=30).solve(0)
    record = smooth.info.extra["adapted"]["ridge_rounding"]
    assert record["length"] == pytest.approx(ridge_rounding_length(cylinder, 30.0))
    assert record["band_vertices"] > 0 and any("ridge rounded" in n for n in smooth.info.notes)
    edges, sharp = edge_gradient_jumps(cylinder, plain.distance)
    _, round_ = edge_gradient_jumps(cylinder, smooth.distance)
    ridge = _opposite(cylinder)[edges].all(axis=1)
    assert ridge.sum() > 20
    assert np.nanpercentile(round_[ridge], 95) < 0.6 * np.nanpercentile(sharp[ridge], 95)
    assert np.abs(smooth.distance - plain.distance).mean() < 0.01 * plain.distance.max()


def test_distance_at_and_gradient_read_the_rounded_field(cylinder):
    res = cg.GeodesicSolver(cylinder, "qcqp-hessian", order=2, resolution=600, m=30).solve(0)
    faces = np.r_[np.arange(0, cylinder.n_faces, 97), np.flatnonzero(_opposite(cylinder)[cylinder.F].all(axis=1))]
    corners = cylinder.F[faces, 1]
    np.testing.assert_allclose(res.field.distance_at(faces, np.tile([0.0, 1.0, 0.0], (faces.size, 1))),
                               res.distance[corners], atol=1e-12)
    # the gradient is that of distance_at: a finite difference along each face's edge from corner 0 to corner 2
    b0, step = np.array([0.3, 0.4, 0.3]), 1e-6
    B0 = np.tile(b0, (faces.size, 1))
    B1 = np.tile(b0 + step * np.array([-1.0, 0.0, 1.0]), (faces.size, 1))
    P = cylinder.V[cylinder.F[faces]]
    edge = (P[:, 2] - P[:, 0]) * step
    fd = res.field.distance_at(faces, B1) - res.field.distance_at(faces, B0)
    along = np.einsum("pj,pj->p", res.field.gradient_at(faces, B0), edge)
    # all but a few points (where the step crosses an edge of the solve mesh, whose field has a kink there)
    assert np.mean(np.abs(along - fd) <= 1e-3 * np.abs(fd) + 1e-12) > 0.95


def test_smoothed_adapted_field_stays_exact_on_a_flat_mesh():
    """One source on a flat square: no cut locus, nothing rounded, and order 2 is exact there."""
    grid = cg.grid_plane(16, jitter=0.2, seed=3)
    res = cg.GeodesicSolver(grid, "qcqp-hessian", order=2, resolution=80).solve(119)
    assert res.info.extra["adapted"]["ridge_rounding"]["band_vertices"] == 0
    np.testing.assert_allclose(res.distance, np.linalg.norm(grid.V - grid.V[119], axis=1), atol=1e-6)


def test_two_sources_on_a_flat_mesh_are_rounded_between_them_only(monkeypatch):
    grid = cg.grid_plane(24)  # cell 1/24
    a, b = 12 * 25 + 3, 12 * 25 + 21  # their fronts meet on x = 0.5
    smooth = cg.GeodesicSolver(grid, "qcqp-hessian", order=2, resolution=300, m=30).solve([a, b])
    length = smooth.info.extra["adapted"]["ridge_rounding"]["length"]
    assert length == pytest.approx(ridge_rounding_length(grid, 30.0))
    monkeypatch.setattr(adapted, "round_ridge", lambda mesh, d, *a, **k: RidgeRounding(d, d < 0, 1.0, 0.0))
    plain = cg.GeodesicSolver(grid, "qcqp-hessian", order=2, resolution=300, m=30).solve([a, b])
    changed = smooth.distance != plain.distance
    ridge = np.abs(grid.V[:, 0] - 0.5) < 1e-9
    assert smooth.distance[ridge].mean() < plain.distance[ridge].mean() - 1e-3  # the crease is lowered
    # no ridge is looked for within 3 longest edges of a source (the cone's tip): nothing changes there
    near = np.minimum(*(np.linalg.norm(grid.V - grid.V[s], axis=1) for s in (a, b))) < 3 / 24 * np.sqrt(2) - length
    assert not changed[near].any() and near.sum() > 20


def test_the_default_length_rounds_about_as_the_default_method_does():
    """One m, one rounding: two sources on a jittered square, the ridge's deficit below the exact field after
    ``round_ridge`` at m = 1 against the default method's (order 1, m = 1) beyond `qclp`'s (measured 1.78x at 64²,
    1.23x at 128²: widths 1.33x and 1.11x, the square root)."""
    from cvxgeodesic.evaluation.smoothness import ridge_deficit

    g = cg.grid_plane(64, jitter=0.25, seed=1)
    a, b = (int(np.argmin(np.linalg.norm(g.V - [x, 0.5, 0.0], axis=1))) for x in (0.25, 0.75))
    exact = np.minimum(*(np.linalg.norm(g.V - g.V[s], axis=1) for s in (a, b)))

    def deficit(d):
        return ridge_deficit(g, d, exact, 0.3, sources=[a, b])["deficit_integral"]

    rounded = deficit(cg.round_ridge(g, exact, [a, b]).distance)
    default = deficit(cg.GeodesicSolver(g).solve([a, b]).distance) - deficit(
        cg.GeodesicSolver(g, "qclp").solve([a, b]).distance)
    assert 1.0 < rounded / default < 2.5


def test_band_rows_are_the_whole_meshs_energy_rows():
    from cvxgeodesic.operators.energies import curved_hessian_energy
    from cvxgeodesic.problems.ridge_rounding import band_energy_rows

    cyl = cg.cylinder(48, 24, height=3.0)
    d = cg.GeodesicSolver(cyl, "qclp").solve(0).distance
    band = cg.round_ridge(cyl, d, [0], m=30.0).band
    assert 0 < band.sum() < 0.5 * cyl.n_vertices
    whole = curved_hessian_energy(cyl).tocsr()[band]
    near = band_energy_rows(cyl, band)[band]
    assert abs(whole - near).max() <= 1e-12 * abs(whole).max()


def test_an_indefinite_band_block_is_rounded_with_the_planar_energy(plane, monkeypatch):
    from cvxgeodesic.linalg import NotPositiveDefiniteError
    from cvxgeodesic.problems import ridge_rounding

    real, calls = ridge_rounding.factor_matrix, []

    def first_fails(K):
        calls.append(1)
        if len(calls) == 1:
            raise NotPositiveDefiniteError("test")
        return real(K)

    monkeypatch.setattr(ridge_rounding, "factor_matrix", first_fails)
    d, sources = _two_sources(plane)
    r = cg.round_ridge(plane, d, sources, length=0.05)
    assert len(calls) == 2 and any("planar Hessian energy" in n for n in r.notes)
    assert np.isfinite(r.distance).all() and r.distance[20 * 41 + 20] < d[20 * 41 + 20]
