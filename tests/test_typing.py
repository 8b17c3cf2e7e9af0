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


def test_method_literals_equal_the_runtime_names() -> None:
    """``cg.Method`` and ``cg.SolverName`` are written out for type checkers; they must list what the API takes."""
    from typing import get_args

    import cvxgeodesic as cg
    from cvxgeodesic import api
    from cvxgeodesic.capabilities import DOMAINS

    assert sorted(get_args(cg.Method)) == sorted(api.ALL_METHODS)
    assert len(get_args(cg.Method)) == len(api.ALL_METHODS)
    assert sorted(get_args(cg.SolverName)) == sorted(api.SOLVERS)
    assert {d.default_method for d in DOMAINS.values()} <= set(get_args(cg.Method))


# mypy --strict on a user's code: every assert_type holds (the overloads give exact types) ...
STRICT_OK = textwrap.dedent("""\
    from pathlib import Path
    from typing import Any, assert_type

    import numpy as np
    import numpy.typing as npt

    import cvxgeodesic as cg


    def main(obj: Path, msh: str) -> None:
        surface = cg.load_mesh(obj, kind="surface")
        assert_type(surface, cg.TriMesh)
        assert_type(surface.F, npt.NDArray[Any])
        volume = cg.load_mesh(msh, kind="volume")
        assert_type(volume.T, npt.NDArray[Any])
        assert_type(cg.load_mesh(obj), cg.TriMesh | cg.TetMesh)
        method: cg.Method = "qgdf"
        d = cg.geodesic_distance(surface, 0, method=method, solver="ipm")
        assert_type(cg.distance_matrix(surface, [0, 1], "heat"), npt.NDArray[Any])
        cg.distance_matrix(surface, [0, 1], method="qclp", max_distance=0.5).nnz
        p = cg.surface_point(surface, [0.1, 0.2, 0.3])
        assert_type(p, cg.SurfacePoint)
        assert_type(cg.surface_point(surface, [[0.1, 0.2, 0.3]]), list[cg.SurfacePoint])
        assert_type(cg.surface_point(surface, np.zeros(3)), cg.SurfacePoint | list[cg.SurfacePoint])
        assert_type(cg.distance_at(surface, d, p), float)
        assert_type(cg.distance_at(surface, d, (0.1, 0.2, 0.3)), float)
        assert_type(cg.distance_at(surface, d, [p, p]), npt.NDArray[Any])
        assert_type(cg.distance_at(surface, d, [[0.1, 0.2, 0.3]]), npt.NDArray[Any])
        assert_type(cg.volume_point(volume, (0.1, 0.2, 0.3)), cg.VolumePoint)
        solver = cg.GeodesicSolver(volume, "qclp", solver="clarabel", order=2)
        assert_type(solver.solve(cg.volume_point(volume, [0.1, 0.2, 0.3])).distance, npt.NDArray[Any])
""")

# ... and each line marked ERROR is refused, and no other
STRICT_ERRORS = textwrap.dedent("""\
    import cvxgeodesic as cg

    mesh = cg.icosphere(2)
    cg.geodesic_distance(mesh, 0, method="qclpp")  # ERROR
    cg.GeodesicSolver(mesh, "QCLP")  # ERROR
    cg.GeodesicSolver(mesh, "qclp", solver="clarabell")  # ERROR
    cg.distance_matrix(mesh, [0], method="dijkstr")  # ERROR
    cg.load_mesh("x.obj", kind="surface").T  # ERROR
    cg.load_mesh("x.msh", kind="volume").F  # ERROR
    cg.load_mesh("x.obj").F  # ERROR
    cg.load_mesh("x.obj", kind="surfaces")  # ERROR
    cg.distance_matrix(mesh, [0, 1]).nnz  # ERROR
    cg.surface_point(mesh, [[0.0, 0.0, 1.0]]).face  # ERROR
    one: list[cg.SurfacePoint] = cg.surface_point(mesh, [0.0, 0.0, 1.0])  # ERROR
    x: float = cg.distance_at(mesh, [0.0] * 162, [[0.0, 0.0, 1.0]])  # ERROR
""")


def test_mypy_strict_on_user_code(tmp_path: Path) -> None:
    (tmp_path / "ok.py").write_text(STRICT_OK)
    (tmp_path / "bad.py").write_text(STRICT_ERRORS)
    config = tmp_path / "mypy.ini"  # --strict, as a user's project; the library's own modules are not checked
    config.write_text("[mypy]\nstrict = true\nfollow_imports = silent\nignore_missing_imports = true\n")
    proc = subprocess.run(
        [sys.executable, "-m", "mypy", "--config-file", str(config), "--cache-dir", str(tmp_path / "cache"),
         "--python-executable", sys.executable, "--no-error-summary", "--show-error-codes", "ok.py", "bad.py"],
        capture_output=True, text=True, env=_mypy_env(tmp_path), cwd=tmp_path, timeout=600,
    )
    errors = [ln for ln in proc.stdout.splitlines() if ": error:" in ln]
    assert not [ln for ln in errors if ln.startswith("ok.py")], proc.stdout + proc.stderr
    marked = [i for i, ln in enumerate(STRICT_ERRORS.splitlines(), 1) if ln.endswith("# ERROR")]
    found = sorted({int(m.group(1)) for ln in errors if (m := re.match(r"bad\.py:(\d+):", ln))})
    assert found == marked, proc.stdout + proc.stderr
    assert len(errors) >= len(marked) and proc.returncode == 1
