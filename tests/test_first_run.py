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

# what a fresh process compiles: nothing at import, for a baseline or for a solver's set-up (the curved Hessian energy
# included), then the QCLP solve's kernels, then an order-2 solve's (each kernel once: none of the first solve's
# compiles again)
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
cg.GeodesicSolver(mesh, "qcqp-hessian", threads=1)  # builds the curved Hessian energy
solver = cg.GeodesicSolver(mesh, "qclp", threads=1)
after_setup = list(compiled)
res = solver.solve(0)  # NOTICE LINE
first = list(compiled)
res2 = cg.GeodesicSolver(mesh, "qclp", order=2, threads=1).solve(0)
print(json.dumps({"after_setup": after_setup, "solve": first[len(after_setup):], "status": res.info.status,
                  "order2": compiled[len(first):], "status2": res2.info.status}))
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
    # nothing at import, for a baseline, or while a solver is built (no set-up has a kernel: the curved Hessian
    # energy is assembled in NumPy, whose kernels were half the first QCQP-Hessian run's compile time)
    assert record["after_setup"] == []
    assert record["solve"] and all(k.startswith("cvxgeodesic.solvers.ipm._kernels.") for k in record["solve"])
    # order 2 compiles the clique kernels, and nothing the order-1 solve compiled already
    assert record["status2"] == "optimal" and record["order2"]
    assert all(k.startswith("cvxgeodesic.solvers.ipm._clique_kernels.") for k in record["order2"]), record["order2"]
    every = record["solve"] + record["order2"]
    assert len(set(every)) == len(every), every
    # one line for the process, at the user's first call, whatever the number of kernels and element orders compiled
    assert first.stderr.count(_jit.NOTICE) == 1, first.stderr
    assert "CompileNotice" not in first.stderr.replace(f"CompileNotice: {_jit.NOTICE}", ""), first.stderr
    assert f"user.py:{line}: CompileNotice: {_jit.NOTICE}" in first.stderr
    # the next process loads every kernel from the cache: no compilation, no line
    second = _run([str(script)], cache, tmp_path)
    assert json.loads(second.stdout)["solve"] == [] and json.loads(second.stdout)["order2"] == []
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
        _jit._tell(_dispatcher("cvxgeodesic.solvers.ipm._clique_kernels"))
        _jit._tell(_dispatcher("cvxgeodesic.solvers.ipm._kernels"))
    assert [(w.category, str(w.message)) for w in caught] == [(_jit.CompileNotice, _jit.NOTICE)]
    assert caught[0].filename == __file__  # the caller outside the package, not Numba's internals


def test_notice_never_fails_a_compilation(monkeypatch):
    monkeypatch.setitem(_jit._state, "told", False)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # python -W error
        _jit._tell(_dispatcher("cvxgeodesic.solvers.ipm._kernels"))
    assert _jit._state["told"]


# Numba finds no cache location: NUMBA_CACHE_DIR unset, the home folder and the package's __pycache__ not writable.
# As root, chmod stops no write, so the locators are made to find nothing, as each does in that state.
NO_LOCATOR = """
from numba.core import caching
for cls in caching.CacheImpl._locator_classes:
    cls.from_function = classmethod(lambda cls, py_func, py_file: None)
import cvxgeodesic as cg
import cvxgeodesic.solvers.ipm._kernels, cvxgeodesic.solvers.ipm._clique_kernels  # every kernel module decorated
res = cg.GeodesicSolver(cg.icosphere(1), "qclp", threads=1).solve(0)
print(res.info.status)
"""


def test_without_a_writable_cache_location_the_kernels_compile_uncached_and_say_so(tmp_path):
    env = _env(tmp_path)
    del env["NUMBA_CACHE_DIR"]
    home = tmp_path / "home"
    home.mkdir(mode=0o500)
    env["HOME"] = str(home)
    out = subprocess.run([sys.executable, "-c", NO_LOCATOR], env=env, cwd=tmp_path, capture_output=True, text=True,
                         timeout=300)
    assert out.returncode == 0, out.stderr  # before: RuntimeError: cannot cache function ...: no locator available
    assert out.stdout.split() == ["optimal"]
    assert out.stderr.count(_jit.NO_CACHE_NOTICE) == 1, out.stderr
    assert _jit.NOTICE not in out.stderr  # "later runs load them from the cache" would not be true
    assert "CompileNotice" in out.stderr


def test_njit_compiles_without_cache_when_there_is_no_locator(monkeypatch):
    from numba.core import caching

    for cls in caching.CacheImpl._locator_classes:
        monkeypatch.setattr(cls, "from_function", classmethod(lambda cls, py_func, py_file: None))
    monkeypatch.setitem(_jit._state, "uncached", False)

    @_jit.njit(cache=True)
    def twice(x):
        return 2 * x

    assert twice(21) == 42 and _jit._state["uncached"]
    assert _jit.njit(lambda x: x + 1)(1) == 2  # the bare decorator form
