"""Static types reach a user's code: mypy on a small user script sees the public API's real types.

An untyped decorator on ``GeodesicSolver``'s methods once made the class, its results and everything read
from them ``Any`` to a type checker, so that ``x: int = res.info.status`` passed unnoticed.
"""

from __future__ import annotations

import os
import re
import site
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

pytest.importorskip("mypy")

# correct uses (each assert_type fails when the expression is Any) and one error, on the line marked ERROR
USER_SCRIPT = textwrap.dedent("""\
    from typing import assert_type

    import numpy as np

    import cvxgeodesic as cg

    mesh = cg.icosphere(2)
    solver = cg.GeodesicSolver(mesh, method="qclp", threads=1)
    assert_type(solver, cg.GeodesicSolver)
    res = solver.solve(0)
    assert_type(res, cg.GeodesicResult)
    assert_type(res.info, cg.SolveInfo)
    assert_type(res.info.status, str)
    assert_type(res.info.iterations, int)
    assert_type(res.info.notes, list[str])
    assert_type(res.distance, np.ndarray)
    many = solver.solve_many([0, 1])
    assert_type(many, list[cg.GeodesicResult])
    path = cg.geodesic_path(mesh, res, 5)
    assert_type(path, np.ndarray)
    path, faces, bary = cg.geodesic_path(mesh, res.distance, 5, return_surface_points=True)
    assert_type(faces, np.ndarray)
    value = cg.distance_at(mesh, res, cg.SurfacePoint(0, np.array([1.0, 0.0, 0.0])))
    assert_type(value, float)
    values = cg.distance_at(mesh, res, [cg.SurfacePoint(0, np.array([1.0, 0.0, 0.0]))])
    assert_type(values, np.ndarray)
    d = cg.geodesic_distance(mesh, 0, method="dijkstra")
    assert_type(d, np.ndarray)
    x: int = res.info.status  # ERROR
""")


def _mypy_env(tmp_path: Path) -> dict[str, str]:
    """The environment for mypy: the imported package's source folder on MYPYPATH unless it is installed.

    An editable install is a path hook that mypy does not follow, and PYTHONPATH=src is how the tests run a
    checkout; an installed package is found by mypy itself (py.typed), and site-packages must not be on MYPYPATH.
    """
    import cvxgeodesic

    env = {k: v for k, v in os.environ.items() if k not in ("MYPYPATH", "PYTHONPATH")}
    root = Path(cvxgeodesic.__file__).resolve().parents[1]
    installed = {Path(p).resolve() for p in [*site.getsitepackages(), site.getusersitepackages()]}
    if root not in installed:
        env["MYPYPATH"] = str(root)
    return env


def test_mypy_sees_the_types_of_solver_results(tmp_path: Path) -> None:
    script = tmp_path / "user_script.py"
    script.write_text(USER_SCRIPT)
    config = tmp_path / "mypy.ini"
    config.write_text("[mypy]\nfollow_imports = silent\nignore_missing_imports = true\n")
    proc = subprocess.run(
        [sys.executable, "-m", "mypy", "--config-file", str(config), "--cache-dir", str(tmp_path / "cache"),
         "--python-executable", sys.executable, "--no-error-summary", "--show-error-codes", str(script)],
        capture_output=True, text=True, env=_mypy_env(tmp_path), cwd=tmp_path, timeout=600,
    )
    errors = [ln for ln in proc.stdout.splitlines() if ": error:" in ln]
    error_line = 1 + USER_SCRIPT.splitlines().index("x: int = res.info.status  # ERROR")
    lines = sorted(int(m.group(1)) for ln in errors if (m := re.search(r"user_script\.py:(\d+):", ln)))
    assert lines == [error_line], proc.stdout + proc.stderr
    assert 'expression has type "str", variable has type "int"' in errors[0]
