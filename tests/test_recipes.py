"""The recipes of docs/architecture.md ("Recipes (the files to touch)") as tests.

Each test builds what one recipe says a new piece needs — exactly the members it names, in this file instead of a
module of the package — and runs the library's public pipeline on it. A recipe that stops holding (shared code that
reads a member the recipe does not name, or tests a dimension instead of asking the mesh) fails here.

- "A domain": :class:`PlanarTriangles`, a dimension-2 :class:`~cvxgeodesic.mesh.simplex.SimplexMesh` that is not a
  ``TriMesh``, with its own :class:`~cvxgeodesic.mesh.reference.ReferenceSimplex`, point type and locator
  (``test_domain_recipe_*``).
- "An element order": ``HIERARCHICAL_P2``, the order-2 space in another basis, declared as a
  :class:`~cvxgeodesic.operators.lagrange.LagrangeElement` and registered in ``ELEMENTS``
  (``test_a_toy_element_order_*``).
"""

from __future__ import annotations

import numpy as np
import pytest
from numpy.typing import ArrayLike

import cvxgeodesic as cg
from cvxgeodesic.capabilities import DOMAINS, Domain
from cvxgeodesic.errors import SourceError
from cvxgeodesic.mesh.locate import CellPoint
from cvxgeodesic.mesh.reference import TRIANGLE, CellWords, ReferenceSimplex
from cvxgeodesic.mesh.simplex import SimplexMesh
from cvxgeodesic.operators.gradient import gradient_blocks
from cvxgeodesic.operators.lagrange import ELEMENTS, LagrangeElement, quadratic_candidates

# -- "A domain": triangles in the plane z = 0 ------------------------------------------------------------------


class PlanarPoint(CellPoint, field="triangle", n_bary=3, word="triangle", cells="triangles",
                  hint="use planar_point(mesh, xyz) to find the containing one"):
    """A point of a planar triangulation: a triangle index and three barycentric coordinates."""

    __slots__ = ()


def planar_point(mesh: PlanarTriangles, xyz: ArrayLike) -> PlanarPoint | list[PlanarPoint]:
    """The point(s) of ``mesh`` at positions ``xyz`` (3,) or (p, 3): the containing triangle (SourceError outside)."""
    X = np.asarray(xyz, dtype=float)
    if X.shape[-1:] != (3,) or not np.all(np.isfinite(X)):
        raise SourceError(f"xyz must be finite (3,) or (p, 3) positions, got {xyz!r}")
    tree, radius = mesh.centroid_tree
    points = []
    for x in X.reshape(-1, 3):
        best, where = -np.inf, None
        for t in tree.query_ball_point(x, radius):
            A = np.vstack([mesh.V[mesh.cells[t], :2].T, np.ones(3)])
            b = np.linalg.solve(A, np.r_[x[:2], 1.0])
            if b.min() > best:
                best, where = b.min(), (t, b)
        if where is None or best < -1e-9:
            raise SourceError(f"xyz = {x.tolist()} is outside {mesh.name}")
        t, b = where
        b = np.clip(b, 0.0, None)
        points.append(PlanarPoint(t, b / b.sum()))
    return points[0] if X.ndim == 1 else points


def _plane_frame(X: np.ndarray) -> np.ndarray:
    """The plane's own frame: the corners' x and y."""
    return X[:, :, :2]


def _plane_vectors(G: np.ndarray, X: np.ndarray) -> np.ndarray:
    """Vectors (k, 2, m) of the plane's frame in world coordinates (k, m, 3): z = 0."""
    return np.concatenate([G.transpose(0, 2, 1), np.zeros((G.shape[0], G.shape[2], 1))], axis=2)


PLANAR = ReferenceSimplex(
    name="planar triangle", dim=2, edges=TRIANGLE.edges, facets=TRIANGLE.facets,
    words=CellWords(one="triangle", many="triangles", short="triangles", shape="(m, 3)", measure="area",
                    mesh="a planar triangulation", meshes="planar triangulations", preposition="in",
                    domain="in the plane", argument="triangles"),
    source_kinds=("vertex", "point", "boundary"), measure_root=np.sqrt, shared_points=True,
    _frame=_plane_frame, _to_world=_plane_vectors, _point_type=PlanarPoint, _locator=planar_point,
)


#: The domain's entry of the capability table: its defaults and the words of its messages. Rules of RULES that name
#: no domain hold for it; a rule for it alone would name "plane" in its ``domains``.
PLANE = Domain("plane", "planar triangulations", "in the plane", "in the plane", 2, "qclp", "mesh", ("qclp", 2), "ply")


@pytest.fixture(autouse=True)
def _plane_domain(monkeypatch):
    """The toy domain declared in the capability table for the test (a package domain is a line of DOMAINS)."""
    monkeypatch.setitem(DOMAINS, PLANE.name, PLANE)


class PlanarTriangles(SimplexMesh):
    """Triangles in the plane z = 0: the members "A domain" names, nothing else."""

    dim = 2
    reference = PLANAR
    domain = PLANE.name

    def __init__(self, V: ArrayLike, cells: ArrayLike, *, name: str | None = None, **numbering) -> None:
        super().__init__(V, cells, name=name or "planar", **numbering)

    @property
    def cell_measures(self) -> np.ndarray:
        P = self.V[self.cells]
        e1, e2 = P[:, 1, :2] - P[:, 0, :2], P[:, 2, :2] - P[:, 0, :2]
        return 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])

    @property
    def cell_facet_measures(self) -> np.ndarray:
        return self.edge_lengths[self.cell_edges]

    def _with_vertices(self, V: np.ndarray) -> PlanarTriangles:
        return PlanarTriangles(V, self.cells, name=self.name)


N = 10  # cells per side of the unit square


@pytest.fixture(scope="module")
def square() -> tuple[PlanarTriangles, cg.TriMesh]:
    """The unit square as the toy domain and as the TriMesh of the same vertices and triangles."""
    tri = cg.grid_plane(N)
    return PlanarTriangles(tri.V, tri.F, name="square"), tri


def _solve(mesh, sources, method: str, order: int = 1) -> cg.GeodesicResult:
    return cg.GeodesicSolver(mesh, method, order=order).solve(sources)


def _boundary_distance(V: np.ndarray) -> np.ndarray:
    x, y = V[:, 0], V[:, 1]
    return np.minimum.reduce([x, 1 - x, y, 1 - y])


def test_domain_recipe_mesh_has_the_vocabulary(square):
    mesh, tri = square
    assert not isinstance(mesh, cg.TriMesh) and mesh.reference is PLANAR
    np.testing.assert_allclose(mesh.cell_measures, tri.face_areas, rtol=1e-12)
    assert mesh.total_measure == pytest.approx(1.0, rel=1e-12)
    np.testing.assert_array_equal(mesh.boundary_facets, tri.boundary_facets)
    p = planar_point(mesh, [0.33, 0.71, 0.0])
    assert isinstance(p, PlanarPoint) and np.allclose(p.position(mesh), [0.33, 0.71, 0.0])
    # the gradient of a linear function, in the reference's frame and back in world coordinates
    f = mesh.V @ [2.0, -3.0, 0.0]
    g = np.einsum("kdc,kc->kd", gradient_blocks(mesh), f[mesh.cells])
    np.testing.assert_allclose(PLANAR.to_world(g[:, :, None], mesh.V[mesh.cells])[:, 0], [[2.0, -3.0, 0.0]] * 200,
                               atol=1e-12)


@pytest.mark.parametrize("method", ["qclp", "qcqp-dirichlet"])
def test_domain_recipe_order1_point_source(square, method):
    """Order 1 from a point source: the field equals the TriMesh's (same vertices and cells) to rounding, and
    ``|x − p|`` to the discretization error of a 10 × 10 grid (measured 0.043 for both, 2026-12-06)."""
    mesh, tri = square
    p = np.array([0.37, 0.52, 0.0])
    res = _solve(mesh, planar_point(mesh, p), method)
    ref = _solve(tri, cg.surface_point(tri, p), method)
    np.testing.assert_allclose(res.distance, ref.distance, rtol=1e-7, atol=1e-9)
    assert np.abs(res.distance - np.linalg.norm(mesh.V - p, axis=1)).max() < 0.05


def test_domain_recipe_boundary_source(square):
    """``"boundary"``: the distance to the square's sides, exact on this grid up to the solver's tolerance."""
    mesh, tri = square
    res = _solve(mesh, "boundary", "qclp")
    assert res.source_set is not None and res.source_set.kind == "boundary"
    np.testing.assert_allclose(res.distance, _solve(tri, "boundary", "qclp").distance, rtol=1e-7, atol=1e-9)
    np.testing.assert_allclose(res.distance, _boundary_distance(mesh.V), atol=1e-6)


@pytest.mark.parametrize("source", ["vertex", "point"])
def test_domain_recipe_order2(square, source):
    """Order 2 holds the flat distance exactly (a quadratic ``d²``), from a vertex and from a point inserted into
    the mesh as a vertex (a split toy mesh)."""
    mesh, tri = square
    p = mesh.V[0] if source == "vertex" else np.array([0.37, 0.52, 0.0])
    res = _solve(mesh, 0 if source == "vertex" else planar_point(mesh, p), "qclp", order=2)
    ref = _solve(tri, 0 if source == "vertex" else cg.surface_point(tri, p), "qclp", order=2)
    np.testing.assert_allclose(res.distance, ref.distance, rtol=1e-6, atol=1e-8)
    np.testing.assert_allclose(res.distance, np.linalg.norm(mesh.V - p, axis=1), atol=1e-6)


def test_domain_recipe_order2_smoothed_boundary(square):
    """An order-2 smoothness energy of ``φ = d²`` and the boundary source: still the distance to the sides."""
    mesh, tri = square
    res = _solve(mesh, "boundary", "qcqp-dirichlet", order=2)
    np.testing.assert_allclose(res.distance, _solve(tri, "boundary", "qcqp-dirichlet", order=2).distance,
                               rtol=1e-6, atol=1e-8)
    np.testing.assert_allclose(res.distance, _boundary_distance(mesh.V), atol=1e-6)


@pytest.mark.parametrize("method", ["dijkstra", "heat"])
def test_domain_recipe_baselines(square, method):
    """The baselines take the domain's triangles as they take a TriMesh's: the same field."""
    mesh, tri = square
    np.testing.assert_allclose(_solve(mesh, 0, method).distance, _solve(tri, 0, method).distance, rtol=1e-12)


def test_domain_recipe_distance_at_and_geodesic_path(square, monkeypatch):
    """The field between vertices (the order-1 interpolant: within 0.02 of ``|x|``) and the path back to a vertex
    source: the straight segment in the plane, once the domain's triangles name their straightening (the corridor of
    faces unfolded; a kind without one keeps the raw descent along the field's gradient)."""
    from cvxgeodesic.paths.corridor import straighten_corridor
    from cvxgeodesic.paths.descent import STRAIGHTENERS

    monkeypatch.setitem(STRAIGHTENERS, PLANAR, straighten_corridor)
    mesh, _ = square
    res = _solve(mesh, 0, "qclp")
    X = np.array([[0.55, 0.45, 0.0], [0.91, 0.13, 0.0]])
    np.testing.assert_allclose(cg.distance_at(mesh, res, X), np.linalg.norm(X, axis=1), atol=0.02)
    P = cg.geodesic_path(mesh, res, [0.8, 0.6, 0.0])
    np.testing.assert_allclose(P[[0, -1]], [[0.8, 0.6, 0.0], [0.0, 0.0, 0.0]], atol=1e-12)
    assert np.linalg.norm(np.diff(P, axis=0), axis=1).sum() == pytest.approx(1.0, abs=1e-9)  # |(0.8, 0.6)|
    assert np.abs(P[:, 0] * 0.6 - P[:, 1] * 0.8).max() < 1e-9  # on the segment
    assert np.all(P[:, 2] == 0.0)


# ---------------------------------------------------------------- "An element order"


def _hierarchical_basis(reference: ReferenceSimplex, bary: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Another basis of the order-2 space: the hat functions ``λ_i`` at the corners and the edge bubbles
    ``4 λ_a λ_b`` (its edge DOF is the departure of the midpoint value from the mean of the edge's ends)."""
    lam = np.atleast_2d(np.asarray(bary, dtype=float))
    s, c = lam.shape
    E = reference.edges
    N = np.hstack([lam, 4 * lam[:, E[:, 0]] * lam[:, E[:, 1]]])
    dN = np.zeros((s, c + len(E), c))
    dN[:, range(c), range(c)] = 1.0
    dN[:, c + np.arange(len(E)), E[:, 0]] = 4 * lam[:, E[:, 1]]
    dN[:, c + np.arange(len(E)), E[:, 1]] = 4 * lam[:, E[:, 0]]
    return N, dN


def _hierarchical_second_derivatives(reference: ReferenceSimplex) -> np.ndarray:
    c, E = reference.n_corners, reference.edges
    D2 = np.zeros((c + len(E), c, c))
    D2[c + np.arange(len(E)), E[:, 0], E[:, 1]] = 4.0
    D2[c + np.arange(len(E)), E[:, 1], E[:, 0]] = 4.0
    return D2


#: The toy order, declared as the recipe says: the DOFs per vertex, edge, triangle and tetrahedron with their nodes,
#: the shape functions and the violation search of its degree.
HIERARCHICAL_P2 = LagrangeElement(
    "P2-hierarchical", 2, ([[1.0]], [[0.5, 0.5]], np.zeros((0, 3)), np.zeros((0, 4))),
    search=quadratic_candidates, basis_function=_hierarchical_basis,
    second_derivative_function=_hierarchical_second_derivatives,
)


def _euclid(mesh, source: int) -> np.ndarray:
    return np.linalg.norm(mesh.V - mesh.V[source], axis=1)


@pytest.mark.parametrize("mesh", [cg.grid_plane(10, jitter=0.3, seed=2), cg.tet_box(3, jitter=0.2, seed=1)],
                         ids=["surface", "volume"])
def test_a_toy_element_order_declared_by_the_recipe_runs_through_the_order2_path(mesh, monkeypatch):
    """The recipe's toy order: another basis of the order-2 space, registered in ``ELEMENTS`` under its order. The
    order-2 path (builder, strategy, violation search, field) then solves in it: on a flat mesh ``d²`` is in the
    space and the distance comes out exact; and it is the same program in other coordinates, so it agrees with the
    regular P2 element to the solver's tolerance."""
    regular = cg.GeodesicSolver(mesh, "qclp", order=2).solve(0)
    monkeypatch.setitem(ELEMENTS, 2, HIERARCHICAL_P2)
    solver = cg.GeodesicSolver(mesh, "qclp", order=2)
    assert solver._strategy.builder.space.element is HIERARCHICAL_P2
    res = solver.solve(0)
    exact = _euclid(mesh, 0)
    assert res.info.status == "optimal"
    # measured 2026-12-06: 7.6e-10 (surface) and 2.0e-10 (volume) of the largest distance from the exact one, 2.8e-10
    # and 4.2e-11 from the regular element's field, in as many iterations
    np.testing.assert_allclose(res.distance, exact, rtol=0, atol=1e-8 * exact.max())
    np.testing.assert_allclose(res.distance, regular.distance, rtol=0, atol=1e-8 * exact.max())
    assert res.info.iterations == regular.info.iterations
    # its DOFs are not values: the edge DOF of d² = |x − s|² is the bubble's coefficient −|e|²/4
    space, phi = res.field.space, res.field.phi
    E = mesh.edges
    bubbles = phi[space.edge_dofs[:, 0]]
    np.testing.assert_allclose(bubbles, -0.25 * np.sum((mesh.V[E[:, 0]] - mesh.V[E[:, 1]]) ** 2, axis=1),
                               atol=1e-8 * exact.max() ** 2)
    # and the field inside the cells is the element's: exact at any point
    rng = np.random.default_rng(0)
    cells, bary = rng.integers(0, mesh.n_cells, 30), rng.dirichlet(np.ones(mesh.dim + 1), 30)
    P = np.einsum("pi,pix->px", bary, mesh.V[mesh.cells[cells]])
    inside = res.field.distance_at(cells, bary)
    np.testing.assert_allclose(inside, np.linalg.norm(P - mesh.V[0], axis=1), atol=1e-8 * exact.max())


def test_the_toy_element_agrees_with_p2_on_a_curved_surface(monkeypatch):
    """Where ``d²`` is not in the space (a sphere), the two bases still hold one program: the same field (measured
    1e-15 of the largest distance apart, 2026-12-06)."""
    mesh = cg.icosphere(2)
    regular = cg.GeodesicSolver(mesh, "qclp", order=2).solve(0)
    monkeypatch.setitem(ELEMENTS, 2, HIERARCHICAL_P2)
    toy = cg.GeodesicSolver(mesh, "qclp", order=2).solve(0)
    assert toy.info.status == "optimal"
    np.testing.assert_allclose(toy.distance, regular.distance, rtol=0, atol=1e-10 * regular.distance.max())
