"""The set-up of a solve (docs/dev/performance-log.md, "Set-up cost"): faster constructions give the same objects."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

import cvxgeodesic as cg
from cvxgeodesic.operators import hessian_energy_matrix, laplacian_energy_matrix
from cvxgeodesic.problems.conic import kkt_pattern


def _reference_pattern(n, faces, edges, P=None):
    """kkt_pattern as it was built before 2026-12-01: one list of coordinates, every triangle's six couplings."""
    r = [np.arange(n), faces[:, [0, 0, 1, 1, 2, 2]].ravel(), edges[:, 0], edges[:, 1]]
    c = [np.arange(n), faces[:, [1, 2, 0, 2, 0, 1]].ravel(), edges[:, 1], edges[:, 0]]
    if P is not None:
        Pc = sp.coo_matrix(P)
        r.append(Pc.row)
        c.append(Pc.col)
    rows, cols = np.concatenate(r), np.concatenate(c)
    S = sp.csc_matrix((np.ones(rows.size), (rows, cols)), shape=(n, n))
    S.data[:] = 1.0
    S.sort_indices()
    return S


def _loose_grid():
    g = cg.grid_plane(6, jitter=0.3, seed=4)
    return cg.TriMesh(np.vstack([g.V, [[5.0, 5.0, 0.0]]]), g.F, name="grid+loose")


@pytest.mark.parametrize("mesh", [cg.icosphere(2), _loose_grid(), cg.cylinder(8, 3)], ids=lambda m: m.name)
def test_kkt_pattern_is_the_coordinate_list_pattern(mesh):
    n, F, E = mesh.n_vertices, mesh.F, mesh.edges
    lower = sp.tril(hessian_energy_matrix(mesh), format="coo")  # a pattern that is not symmetric
    coo_with_duplicates = sp.coo_matrix((np.r_[lower.data, lower.data], (np.r_[lower.row, lower.row],
                                                                        np.r_[lower.col, lower.col])), shape=(n, n))
    for P in (None, hessian_energy_matrix(mesh), laplacian_energy_matrix(mesh), lower, coo_with_duplicates):
        S, ref = kkt_pattern(n, F, E, P), _reference_pattern(n, F, E, P)
        assert S.format == "csc" and S.has_sorted_indices and S.shape == (n, n)
        np.testing.assert_array_equal(S.indptr, ref.indptr)
        np.testing.assert_array_equal(S.indices, ref.indices)
        assert (S.data == 1.0).all()
