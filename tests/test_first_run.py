"""The first run after an installation: kernels compile only when a solve needs them, and one line says so.

The subprocess tests start Python with an empty ``NUMBA_CACHE_DIR`` (the state right after ``pip install``);
each compiles the QCLP solver's kernels once (a few seconds).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import warnings
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic import _jit

pytest.importorskip("numba")

# what a fresh process compiles: nothing at import or for a baseline, then the QCLP solve's kernels
SCRIPT = """
import json, sys
from numba.core import event
import cvxgeodesic as cg

compiled = []

class Record(event.Listener):
    def on_start(self, ev):
        f = ev.data["dispatcher"].py_func
        if f.__module__.startswith("cvxgeodesic."):  # not Numba's own overloads compiled inside a kernel
            compiled.append(f.__module__ + "." + f.__name__)

    def on_end(self, ev):
        pass

event.register("numba:compile", Record())
mesh = cg.icosphere(1)
cg.GeodesicSolver(mesh, "dijkstra").solve(0)
solver = cg.GeodesicSolver(mesh, "qclp", threads=1)
after_setup = list(compiled)
res = solver.solve(0)  # NOTICE LINE
print(json.dumps({"after_setup": after_setup, "solve": compiled[len(after_setup):], "status": res.info.status}))
"""


def _env(cache: Path) -> dict:
    env = dict(os.environ)
    env["NUMBA_CACHE_DIR"] = str(cache)
    env["PYTHONPATH"] = os.pathsep.join([str(Path(cg.__file__).parents[1]), env.get("PYTHONPATH", "")])
    return env


def _run(args: list[str], cache: Path, cwd: Path) -> subprocess.CompletedProcess:
    out = subprocess.run([sys.executable, *args], env=_env(cache), cwd=cwd, capture_output=True, text=True,
                         timeout=300)
    assert out.returncode == 0, out.stderr
    return out


def test_a_cold_cache_compiles_what_the_solve_needs_and_says_so_once(tmp_path):
    script = tmp_path / "user.py"
    script.write_text(SCRIPT)
    line = 1 + SCRIPT.splitlines().index("res = solver.solve(0)  # NOTICE LINE")
    cache = tmp_path / "numba-cache"
    first = _run([str(script)], cache, tmp_path)
    record = json.loads(first.stdout)
    assert record["status"] == "optimal"
    # nothing at import, for a baseline, or while a solver is built (QCLP's set-up has no kernel)
    assert record["after_setup"] == []
    assert record["solve"] and all(k.startswith("cvxgeodesic.solvers.ipm._kernels.") for k in record["solve"])
    # one line, at the user's call, whatever the number of kernels compiled
    assert first.stderr.count(_jit.NOTICE) == 1, first.stderr
    assert f"user.py:{line}: CompileNotice: {_jit.NOTICE}" in first.stderr
    # the next process loads every kernel from the cache: no compilation, no line
    second = _run([str(script)], cache, tmp_path)
    assert json.loads(second.stdout)["solve"] == []
    assert _jit.NOTICE not in second.stderr


def test_the_command_line_prints_the_notice_as_a_note(tmp_path):
    mesh = tmp_path / "sphere.ply"
    cg.save_distance(mesh, cg.icosphere(1), np.zeros(42))
    args = ["-m", "cvxgeodesic.cli", "distance", str(mesh), "-s", "0", "--method", "qclp", "-o",
            str(tmp_path / "out.ply")]
    cache = tmp_path / "numba-cache"
    cold = _run(args, cache, tmp_path)
    assert cold.stderr.count(f"cvxgeodesic: note: {_jit.NOTICE}\n") == 1, cold.stderr
    warm = _run(args, cache, tmp_path)
    assert _jit.NOTICE not in warm.stderr


def _dispatcher(module: str) -> SimpleNamespace:
    return SimpleNamespace(py_func=SimpleNamespace(__module__=module))


def test_notice_once_and_only_for_this_package(monkeypatch):
    monkeypatch.setitem(_jit._state, "told", False)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        _jit._tell(_dispatcher("numba.np.arrayobj"))  # Numba's own overloads compiled inside a kernel
        _jit._tell(_dispatcher("users_module"))  # the user's own jitted code
        _jit._tell(None)
        assert caught == []
        _jit._tell(_dispatcher("cvxgeodesic.operators._hessian_kernels"))
        _jit._tell(_dispatcher("cvxgeodesic.solvers.ipm._kernels"))
    assert [(w.category, str(w.message)) for w in caught] == [(_jit.CompileNotice, _jit.NOTICE)]
    assert caught[0].filename == __file__  # the caller outside the package, not Numba's internals


def test_notice_never_fails_a_compilation(monkeypatch):
    monkeypatch.setitem(_jit._state, "told", False)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # python -W error
        _jit._tell(_dispatcher("cvxgeodesic.solvers.ipm._kernels"))
    assert _jit._state["told"]
