"""Iteration-count regression tests of the structured IPM on fixed meshes (issue 13's mutation check).

Exact counts, every formulation, source vertex 0, m = 1, the solver on the union (Hessian + Laplacian) pattern.
Turning off the Gondzio correctors, Mehrotra's corrector, separate step lengths, the graph starting point
(back to the least-squares "interior" start or further) or two of the four correctors changes at least one
count of the generated meshes' tables (``test_broken_settings_change_the_counts`` shows it) and of spot's. A
deliberate algorithmic change updates these tables, with the reason in the commit message.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import shared_mesh_path
from cvxgeodesic.formulations import FORMULATIONS, MeshOperators, build_problem, smoothness_weight
from cvxgeodesic.mesh import cylinder, grid_plane, icosphere
from cvxgeodesic.solvers.ipm import InteriorPointSolver, IPMSettings
from cvxgeodesic.solvers.problem import kkt_pattern

# lclp, lcqp-dirichlet, lcqp-laplacian, lcqp-hessian, qclp, qcqp-dirichlet, qcqp-laplacian, qcqp-hessian
# (2026-12-01, issue 14: the graph starting point and 4 Gondzio correctors; before them
#  icosphere3 [10, 10, 10, 10, 7, 7, 7, 7], grid14 [9, 10, 10, 10, 9, 10, 10, 10], cylinder [8, 8, 8, 8, 9, 9, 10, 10],
#  spot [14, 15, 14, 14, 11, 12, 12, 11])
GENERATED = {
    "icosphere3": (lambda: icosphere(3), [8, 9, 9, 9, 7, 7, 7, 7]),
    "grid14": (lambda: grid_plane(14, jitter=0.35, seed=3), [8, 8, 8, 7, 8, 10, 10, 10]),
    "cylinder": (lambda: cylinder(24, 10), [6, 7, 7, 7, 8, 9, 10, 10]),
}
SPOT = [11, 14, 13, 13, 11, 12, 11, 11]

BREAKAGES = {
    "no_gondzio": IPMSettings(max_correctors=0),
    "no_mehrotra": IPMSettings(mehrotra_correction=False),
    "cvxopt_start": IPMSettings(init="cvxopt"),
    "mehrotra_start": IPMSettings(init="mehrotra"),
    "joint_steps": IPMSettings(separate_steps=False),
    "least_squares_start": IPMSettings(init="interior"),
    "two_correctors": IPMSettings(max_correctors=2),
}


def _counts(mesh, settings: IPMSettings | None = None) -> list[int]:
    ops = MeshOperators(mesh)
    P = abs(ops.energy("hessian")) + abs(ops.energy("laplacian"))
    ipm = InteriorPointSolver(kkt_pattern(mesh.n_vertices, mesh.F, mesh.edges, P), settings=settings)
    out = []
    for method in FORMULATIONS:
        res = ipm.solve(build_problem(ops, np.array([0]), method, smoothness_weight(mesh, 1.0)))
        assert res.status == "optimal", method
        out.append(res.iterations)
    return out


@pytest.mark.parametrize("name", list(GENERATED))
def test_iteration_counts_on_generated_meshes(name):
    make, expected = GENERATED[name]
    assert _counts(make()) == expected


@pytest.mark.shared
def test_iteration_counts_on_spot():
    from cvxgeodesic.mesh import load_mesh

    assert _counts(load_mesh(shared_mesh_path("spot.obj"))) == SPOT


@pytest.mark.parametrize("breakage", list(BREAKAGES))
def test_broken_settings_change_the_counts(breakage):
    """The tables above can fail: each of these weakenings of the algorithm changes some count."""
    changed = [name for name, (make, expected) in GENERATED.items()
               if _counts(make(), BREAKAGES[breakage]) != expected]
    assert changed, f"{breakage} left every count of the generated meshes unchanged"
