"""The one cutting-plane loop of the order-2 strategy (``strategies/order2.py``), on triangles and on tetrahedra:
its stop rule and the guard that keeps the last fully solved round."""

from __future__ import annotations

import numpy as np
import pytest

import cvxgeodesic as cg
import cvxgeodesic.strategies.order2 as o2
from cvxgeodesic.errors import SolverError
from cvxgeodesic.mesh.tet_generate import tet_box, tet_l_prism


def _cut_case(dim: int):
    """A solver and a source that need at least one cutting-plane round: a point inside a face of a flat grid with
    the node samples only (the edge cones would leave nothing to cut), a point inside a tetrahedron of a box."""
    if dim == 2:
        solver = cg.GeodesicSolver(cg.grid_plane(10, jitter=0.3, seed=5), "qclp", order=2)
        solver._strategy.edge_cones = False
        return solver, cg.SurfacePoint(12, (0.2, 0.5, 0.3))
    return cg.GeodesicSolver(tet_box(3, jitter=0.2, seed=1), "qclp", order=2), cg.VolumePoint(7, [0.1, 0.2, 0.3, 0.4])


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("failure", ["almost_optimal", "raises"])
def test_a_round_not_fully_solved_is_dropped_and_the_last_solved_one_kept(dim, failure, monkeypatch):
    solver, src = _cut_case(dim)
    strategy = solver._strategy
    assert solver.solve(src).info.extra["rounds"] >= 1  # the case needs a round
    strategy.refine = 0
    first = solver.solve(src)  # round 0 alone
    strategy.refine = o2.REFINE_ROUNDS
    real, calls = strategy.policy.solve, []

    def second_call_fails(problem, ipm, callback, notes, **kw):
        calls.append(problem)
        res = real(problem, ipm, callback, notes, **kw)
        if len(calls) == 2:  # the first cutting-plane round
            if failure == "raises":
                raise SolverError("stalled", solver=res.solver, status="numerical_error")
            res.status = failure
        return res

    monkeypatch.setattr(strategy.policy, "solve", second_call_fails)
    res = solver.solve(src)
    assert "cutting-plane round 1 not fully solved; kept round 0" in res.info.notes
    assert res.info.status == "optimal" and res.info.extra["rounds"] == 0 and len(calls) == 2
    np.testing.assert_array_equal(res.distance, first.distance)


def test_the_rounds_stop_when_a_round_no_longer_moves_the_field():
    """Where the source is hidden (the far arm of the L prism, behind the re-entrant edge) ``d²`` is not quadratic
    and the cones stay violated between the samples whatever the round: the rounds stop once one moved the field by
    less than REFINE_STALL, not after REFINE_ROUNDS."""
    m = tet_l_prism(4, jitter=0.2, seed=1)
    c = int(np.argmin(np.linalg.norm(m.V - [0.5, 1.5, 0.5], axis=1)))
    res = cg.GeodesicSolver(m, "qclp", order=2).solve(c)
    rounds = res.info.extra["rounds"]
    assert 1 <= rounds < o2.REFINE_ROUNDS
    fld = res.field
    space = fld.space
    x = fld.phi / o2.unit_mesh(m)[1] ** 2  # the program's field, on the unit mesh
    left, _ = space.violations(x, o2.REFINE_TOL, np.flatnonzero(space.flat_cells))
    assert left.size > 0  # violations remained: the stall rule stopped the rounds, not REFINE_TOL
