"""simplify_mesh's parameter checks (the decimation itself is tested with multires, tests/test_multires.py)."""

from __future__ import annotations

import re

import pytest

from cvxgeodesic.errors import ParameterError
from cvxgeodesic.mesh import icosphere
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
