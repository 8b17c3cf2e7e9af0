"""GeodesicResult.field (issue 42, "one field"): every strategy's field answers the Field protocol, its values at the
vertices are the result's distances, its gradients match an analytic field on flat meshes, and it carries the medium
instead of info.extra."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic.errors import ParameterError
from cvxgeodesic.mesh.transfer import ProjectedField, SourcePatch
from cvxgeodesic.operators.lagrange import LagrangeField, SplitLagrangeField
from cvxgeodesic.operators.linear_field import LinearField
from cvxgeodesic.operators.metric import Medium
from cvxgeodesic.results import Field


def _rotation() -> np.ndarray:
    """A fixed rotation, so that a flat surface's frames are no coordinate planes."""
    Q, _ = np.linalg.qr(np.random.default_rng(3).normal(size=(3, 3)))
    return Q


def _plane():
    grid = cg.grid_plane(16, jitter=0.2)
    return cg.TriMesh(grid.V @ _rotation().T, grid.F)


def _box():
    box = cg.tet_box(5)
    return cg.TetMesh(box.V @ _rotation().T, box.T)


#: (id, mesh, method, solver keywords, the field's class, bound on the mean gradient error |∇d − ∇d_exact| over
#: points farther than 0.3 from the source). Measured on 2026-12-06 (jittered 16x16 plane, 5^3 box, both rotated):
#: qclp 0.044, qcqp-hessian 0.044, dijkstra 0.23, exact 0.025, heat 0.11, multires 0.16, order 2 4e-10,
#: adapted 7e-10; volumes: qclp 0.17, dijkstra 0.32, order 2 2e-9.
CASES = [
    ("qclp", _plane, "qclp", {}, LinearField, 0.1),
    ("qcqp-hessian", _plane, "qcqp-hessian", {}, LinearField, 0.1),
    ("dijkstra", _plane, "dijkstra", {}, LinearField, 0.4),
    ("exact", _plane, "exact", {}, LinearField, 0.05),
    ("heat", _plane, "heat", {}, LinearField, 0.2),
    ("multires", _plane, "qclp", {"multires": 100}, LinearField, 0.3),
    ("order2", _plane, "qclp", {"order": 2}, LagrangeField, 1e-6),
    ("order2-point", _plane, "qclp", {"order": 2}, SplitLagrangeField, 1e-6),
    ("adapted", _plane, "qclp", {"order": 2, "resolution": 150}, ProjectedField, 1e-6),
    ("tet-qclp", _box, "qclp", {}, LinearField, 0.3),
    ("tet-dijkstra", _box, "dijkstra", {}, LinearField, 0.5),
    ("tet-order2", _box, "qclp", {"order": 2}, LagrangeField, 1e-6),
]


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_every_strategy_returns_its_field(case):
    name, make, method, kw, kind, tol = case
    mesh = make()
    source = 0
    if name == "order2-point":  # a point source: the field of the mesh with the point inserted
        source = cg.SurfacePoint(40, [0.2, 0.3, 0.5])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = cg.GeodesicSolver(mesh, method, **kw).solve(source)
    fld = res.field
    assert isinstance(fld, Field) and type(fld) is kind
    assert fld.mesh.n_vertices == mesh.n_vertices and fld.medium is None
    assert "p2_field" not in res.info.extra and "medium" not in res.info.extra
    np.testing.assert_array_equal(fld.vertex_distance, res.distance)
    # each vertex as a corner of one of its cells: the field there is the result's distance
    cells = np.array([int(np.flatnonzero((mesh.cells == v).any(axis=1))[0]) for v in range(mesh.n_vertices)])
    bary = (mesh.cells[cells] == np.arange(mesh.n_vertices)[:, None]).astype(float)
    np.testing.assert_allclose(fld.distance_at(cells, bary), res.distance, rtol=1e-12,
                               atol=1e-9 * mesh.bbox_diagonal)
    # gradients at random points of every cell against the distance's, away from the source
    x0 = mesh.V[0] if isinstance(source, int) else source.position(mesh)
    b = np.random.default_rng(0).dirichlet(np.ones(mesh.reference.n_corners), size=mesh.n_cells)
    X = np.einsum("kc,kcj->kj", b, mesh.V[mesh.cells])
    r = np.linalg.norm(X - x0, axis=1)
    far = r > 0.3
    g = fld.gradient_at(np.arange(mesh.n_cells), b)
    assert g.shape == (mesh.n_cells, 3) and np.isfinite(g).all()
    err = np.linalg.norm(g - (X - x0) / r[:, None], axis=1)[far]
    assert err.mean() < tol
    if tol < 1e-3:  # the order-2 fields are exact on flat meshes: everywhere, not on average
        assert err.max() < 100 * tol
        np.testing.assert_allclose(fld.distance_at(np.arange(mesh.n_cells), b), r, atol=1e-7)


@pytest.mark.parametrize("make", [_plane, _box], ids=["surface", "volume"])
def test_the_linear_field_has_the_gradient_of_a_linear_function(make):
    mesh = make()
    a = np.array([0.3, -1.2, 0.7])
    fld = LinearField(mesh, mesh.V @ a)
    b = np.random.default_rng(1).dirichlet(np.ones(mesh.reference.n_corners), size=mesh.n_cells)
    g = fld.gradient_at(np.arange(mesh.n_cells), b)
    expected = np.broadcast_to(a, g.shape).copy()
    if mesh.reference.dim == 2:  # the gradient lies in the plane: a without its normal component
        n = _rotation()[:, 2]
        expected -= (a @ n) * n
    np.testing.assert_allclose(g, expected, atol=1e-12)
    X = np.einsum("kc,kcj->kj", b, mesh.V[mesh.cells])
    np.testing.assert_allclose(fld.distance_at(np.arange(mesh.n_cells), b), X @ a, atol=1e-12)


def test_the_medium_travels_on_the_field():
    mesh = cg.grid_plane(12, jitter=0.2)
    cost = 1.0 + 3.0 * mesh.V[:, 0]
    res = cg.GeodesicSolver(mesh, "qclp", cost=cost).solve(7)
    assert isinstance(res.field.medium, Medium) and "medium" not in res.info.extra
    assert res.info.extra["cost"] == "per-vertex"
    via_result = cg.geodesic_path(mesh, res, 150)
    np.testing.assert_array_equal(via_result, cg.geodesic_path(mesh, res.distance, 150, cost=cost))
    np.testing.assert_array_equal(via_result, cg.geodesic_path(mesh, res.field, 150))
    euclidean = cg.geodesic_path(mesh, res.distance, 150)  # the same array without its medium: another path
    assert euclidean.shape != via_result.shape or not np.allclose(euclidean, via_result)


def test_a_field_object_answers_distance_at_and_geodesic_path():
    mesh = cg.grid_plane(10, jitter=0.2)
    res = cg.GeodesicSolver(mesh, "qclp", order=2).solve(0)
    pts = [cg.SurfacePoint(f, [0.2, 0.3, 0.5]) for f in (10, 50, 90)]
    np.testing.assert_array_equal(cg.distance_at(mesh, res.field, pts), cg.distance_at(mesh, res, pts))
    np.testing.assert_array_equal(cg.geodesic_path(mesh, res.field, 99), cg.geodesic_path(mesh, res, 99))


def test_an_order2_volume_path_does_not_depend_on_the_mesh_units():
    """The descent in a volume follows the order-2 field's gradient. Its rate was once read on the solver's unit copy
    of the mesh (a power of two off the edges' rates), which sent the walk along edges on a small L prism: 31 %
    longer than the straight path it takes at scale 1. Now the path scales with the mesh."""
    prism = cg.tet_l_prism(3)
    paths = {}
    for scale in (0.125, 1.0, 8.0):  # powers of two: the solver sees the same unit mesh, the same field
        mesh = cg.TetMesh(prism.V * scale, prism.T)
        res = cg.GeodesicSolver(mesh, "qclp", order=2).solve(3)
        paths[scale] = [cg.geodesic_path(mesh, res, t) / scale for t in (mesh.n_vertices - 1, 40, 77)]
    for scale in (0.125, 8.0):
        for P, Q in zip(paths[scale], paths[1.0], strict=True):
            assert P.shape == Q.shape
            np.testing.assert_allclose(P, Q, atol=1e-9)


def test_the_projected_field_gradient_is_the_derivative_of_its_blend():
    """Near a source an adapted field mixes a patch solve into the copy's field (mesh/transfer.SourcePatch): its
    gradient is the blend's, ramp included. Two linear fields on a flat mesh (its own solve mesh) make the blend
    exact to check against central differences of distance_at inside faces."""
    mesh = cg.grid_plane(12, jitter=0.2)
    base = LinearField(mesh, mesh.V @ [1.0, 0.5, 0.0] + 0.2)
    near = LinearField(mesh, mesh.V @ [-0.3, 1.2, 0.0] + 0.1)
    patch = SourcePatch(np.arange(mesh.n_faces), np.arange(mesh.n_vertices), near, inner=0.4, outer=0.9)
    fld = ProjectedField(mesh, mesh, base, base.vertex_distance, [patch])
    rng = np.random.default_rng(2)
    faces = rng.integers(0, mesh.n_faces, 600)
    b = rng.dirichlet(np.full(3, 4.0), size=faces.size)
    g = fld.gradient_at(faces, b)
    tri = mesh.V[mesh.F[faces]]
    step = np.array([1e-6, -1e-6, 0.0])  # along edge 0 → 1 of each face
    fd = (fld.distance_at(faces, b + step) - fld.distance_at(faces, b - step)) / 2e-6
    along = np.einsum("kj,kj->k", g, tri[:, 0] - tri[:, 1])
    v = near.distance_at(faces, b)
    ramp = (v > 0.41) & (v < 0.89)
    clear = np.abs(v - 0.4) > 1e-3
    clear &= np.abs(v - 0.9) > 1e-3
    assert ramp.sum() > 50 and (~ramp & clear).sum() > 50  # both the ramp and the rest are checked
    np.testing.assert_allclose(along[clear], fd[clear], atol=1e-7)


def test_an_order1_field_remembers_its_point_sources():
    mesh = cg.grid_plane(10, jitter=0.2)
    point = cg.SurfacePoint(60, [0.2, 0.3, 0.5])
    res = cg.GeodesicSolver(mesh, "qclp").solve(point)
    P = cg.geodesic_path(mesh, res.field, 0)
    np.testing.assert_allclose(P[-1], point.position(mesh), atol=1e-12)  # ends on the point, not on a vertex
    np.testing.assert_array_equal(P, cg.geodesic_path(mesh, res, 0))


@pytest.mark.parametrize("kw", [{}, {"order": 2}, {"order": 2, "resolution": 150}], ids=["P1", "P2", "adapted"])
def test_a_field_names_the_bad_cell_or_coordinates(kw):
    mesh = cg.grid_plane(10, jitter=0.2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fld = cg.GeodesicSolver(mesh, "qclp", **kw).solve(0).field
    for ask in (fld.distance_at, fld.gradient_at):
        with pytest.raises(ParameterError, match=rf"faces must lie in \[0, {mesh.n_faces}\)"):
            ask([mesh.n_faces], [[1.0, 0.0, 0.0]])
        with pytest.raises(ParameterError, match="bary must have shape"):
            ask([0], [[0.5, 0.5]])
