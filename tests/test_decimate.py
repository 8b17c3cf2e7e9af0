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
