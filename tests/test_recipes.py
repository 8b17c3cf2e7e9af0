"""The recipes of docs/architecture.md as tests."""

from __future__ import annotations

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic.mesh.reference import ReferenceSimplex
from cvxgeodesic.operators.lagrange import ELEMENTS, LagrangeElement, quadratic_candidates

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
    space, phi = res.info.extra["p2_field"].space, res.info.extra["p2_field"].phi
    E = mesh.edges
    bubbles = phi[space.edge_dofs[:, 0]]
    np.testing.assert_allclose(bubbles, -0.25 * np.sum((mesh.V[E[:, 0]] - mesh.V[E[:, 1]]) ** 2, axis=1),
                               atol=1e-8 * exact.max() ** 2)
    # and the field inside the cells is the element's: exact at any point
    rng = np.random.default_rng(0)
    cells, bary = rng.integers(0, mesh.n_cells, 30), rng.dirichlet(np.ones(mesh.dim + 1), 30)
    P = np.einsum("pi,pix->px", bary, mesh.V[mesh.cells[cells]])
    inside = res.info.extra["p2_field"].distance_at(cells, bary)
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
