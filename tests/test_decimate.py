"""simplify_mesh's parameter checks (the decimation itself is tested with multires, tests/test_multires.py)."""

from __future__ import annotations

import re

import numpy as np
import pytest

from cvxgeodesic.errors import ParameterError
from cvxgeodesic.mesh import TriMesh, icosphere
from cvxgeodesic.mesh.decimate import simplify_mesh


@pytest.mark.parametrize("method", ["Quadric", "edge", None])
def test_unknown_method_names_the_choices(method):
    message = f"unknown simplification method {method!r}; choose one of shortest-edge, quadric"
    with pytest.raises(ParameterError, match=re.escape(message)):
        simplify_mesh(icosphere(1), 40, method=method)


@pytest.mark.parametrize("target", [0, 80, 100])
def test_target_outside_the_face_count_is_refused(target):
    with pytest.raises(ParameterError, match=re.escape(f"target_faces must be in (0, 80), got {target}")):
        simplify_mesh(icosphere(1), target)


def test_the_quadric_copy_does_not_depend_on_where_the_mesh_lies():
    # survey coordinates: kitten at (5e5, 4e6, 100) made a copy up to 0.92 off the same copy at the origin (its
    # default's field 0.511 -> 0.962 % mean error); a mesh that far is moved to the origin for the decimation
    sphere = icosphere(4)
    offset = np.array([5e5, 4e6, 100.0])
    here = simplify_mesh(sphere, 1000, method="quadric")
    there = simplify_mesh(TriMesh(sphere.V + offset, sphere.F), 1000, method="quadric")
    np.testing.assert_array_equal(there.F, here.F)
    np.testing.assert_allclose(there.V - offset, here.V, atol=1e-7)


def _grid_with_holes(n: int, holes: int) -> TriMesh:
    """An ``n`` × ``n`` grid of the unit square without ``holes`` of its triangles, three squares apart:
    χ = 1 − holes."""
    from cvxgeodesic.mesh.generate import grid_plane

    grid = grid_plane(n)
    cell = grid.V[grid.F].mean(axis=1) * n
    picked = np.flatnonzero((np.floor(cell[:, 0]) % 3 == 1) & (np.floor(cell[:, 1]) % 3 == 1) & (cell[:, 0] % 1 < 0.5))
    return TriMesh(grid.V, np.delete(grid.F, picked[:holes], axis=0))


@pytest.mark.parametrize("holes", [0, 1, 12])
def test_a_kept_border_copy_stops_at_the_face_floor_and_is_the_same_copy(holes, monkeypatch):
    from cvxgeodesic.mesh import decimate

    mesh = _grid_with_holes(24, holes)
    floor = decimate.kept_border_floor(mesh)
    boundary = np.unique(mesh.boundary_facets).size
    assert floor == boundary - 2 * (1 - holes)  # a disc with holes: χ = 1 − holes, its loops apart
    asked = simplify_mesh(mesh, 4, method="quadric", preserve_border=True)  # far below the floor
    assert asked.n_faces >= floor
    monkeypatch.setattr(decimate, "kept_border_floor", lambda m: 0)  # fast-simplification asked for 4 faces
    unasked = simplify_mesh(mesh, 4, method="quadric", preserve_border=True)
    np.testing.assert_array_equal(asked.F, unasked.F)
    np.testing.assert_array_equal(asked.V, unasked.V)


def test_the_face_floor_counts_a_vertex_where_two_boundary_loops_touch_once():
    from cvxgeodesic.mesh.decimate import kept_border_floor

    # two triangles sharing one vertex: 5 vertices, 6 boundary edges, χ = 1; fully decimated it keeps both faces
    bowtie = TriMesh(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0]], dtype=float),
                     np.array([[0, 1, 2], [0, 3, 4]]))
    assert kept_border_floor(bowtie) == 2 * 5 - 6 - 2 * 1 == 2
