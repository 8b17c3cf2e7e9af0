"""The ``threads=`` parameter, ``CVXGEODESIC_THREADS`` and the default thread policy (no timings here)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic import _threads
from cvxgeodesic.errors import ParameterError

numba = pytest.importorskip("numba")


@pytest.fixture
def no_env(monkeypatch):
    monkeypatch.delenv(_threads.ENV_VAR, raising=False)


@pytest.mark.parametrize("bad", [0, -1, 1.5, True, "2", np.float64(2.0)])
def test_bad_threads_parameter(bad):
    with pytest.raises(ParameterError, match="threads must be a positive integer"):
        cg.GeodesicSolver(cg.icosphere(1), "qclp", threads=bad)
    with pytest.raises(ParameterError, match="threads"):
        cg.geodesic_distance(cg.icosphere(1), 0, method="qclp", threads=bad)
    with pytest.raises(ParameterError, match="threads"):
        cg.distance_matrix(cg.icosphere(1), [0, 1], method="qclp", threads=bad)


@pytest.mark.parametrize("bad", ["0", "-2", "two", "1.5"])
def test_bad_environment_variable(monkeypatch, bad):
    monkeypatch.setenv(_threads.ENV_VAR, bad)
    with pytest.raises(ParameterError, match=_threads.ENV_VAR):
        cg.GeodesicSolver(cg.icosphere(1), "qclp")
    cg.GeodesicSolver(cg.icosphere(1), "qclp", threads=1)  # an explicit value does not read the variable


def test_environment_variable_and_explicit_value(monkeypatch):
    mesh = cg.icosphere(2)
    monkeypatch.setenv(_threads.ENV_VAR, "1")
    assert cg.GeodesicSolver(mesh, "qclp").solve(0).info.extra["threads"] == 1
    monkeypatch.setenv(_threads.ENV_VAR, " 3 ")
    assert cg.GeodesicSolver(mesh, "qclp").solve(0).info.extra["threads"] == 3
    assert cg.GeodesicSolver(mesh, "qclp", threads=2).solve(0).info.extra["threads"] == 2
    assert cg.GeodesicSolver(mesh, "heat", threads=2).solve(0).info.extra["threads"] == 2  # baselines too


def _pool_threads() -> dict:
    from threadpoolctl import threadpool_info

    seen = {"numba": numba.get_num_threads()}
    for pool in threadpool_info():
        seen.setdefault(pool["internal_api"], set()).add(pool["num_threads"])
    from cvxgeodesic.linalg import pardiso

    if pardiso.pardiso_available():
        seen["MKL_Get_Max_Threads"] = pardiso._load().MKL_Get_Max_Threads()
    return seen


@pytest.mark.parametrize("threads", [1, 2])
def test_limit_reaches_every_pool(threads):
    """Inside a solve (at every interior-point iteration) each pool is bounded, and restored afterwards."""
    expected = min(threads, numba.config.NUMBA_NUM_THREADS)
    before = _pool_threads()
    solver = cg.GeodesicSolver(cg.icosphere(3), "qcqp-hessian", solver="ipm", threads=threads)
    seen = []
    res = solver.solve(0, callback=lambda it, info: seen.append(_pool_threads()))
    assert res.info.extra["threads"] == threads and seen
    for pools in seen:
        assert pools["numba"] == expected
        assert pools.get("openmp", {threads}) == {threads}  # libgomp: PARDISO's and the kernels' runtime
        if "MKL_Get_Max_Threads" in pools:
            assert pools["MKL_Get_Max_Threads"] == threads
            assert pools["mkl"] == {threads}
    factor = solver._strategy.ipm.cholesky.numeric
    if solver._strategy.ipm.cholesky.backend == "pardiso":
        assert factor.threads == threads  # fixed by the analysis, which ran in the constructor's limit
    assert _pool_threads() == before


def test_blas_pools_bounded_during_setup(no_env):
    from threadpoolctl import threadpool_info

    with _threads.thread_limit(1):
        assert {p["num_threads"] for p in threadpool_info()} == {1}
        assert numba.get_num_threads() == 1
        assert _threads.resolve_threads() == 1  # a solver built inside (multires' coarse one) inherits it
    assert _threads._local.limit is None


def test_multires_coarse_solver_inherits(no_env):
    solver = cg.GeodesicSolver(cg.icosphere(4), "qclp", multires=500, threads=1)
    coarse = solver._strategy.coarse.ipm.cholesky  # the coarse mesh's solver, built inside the façade's limit
    if coarse.backend == "pardiso":
        assert coarse.numeric.threads == 1
    assert solver.solve(0).info.extra["threads"] == 1


@pytest.mark.parametrize("method", ["qcqp-hessian", "qclp"])
def test_same_field_at_every_thread_count(method):
    mesh = cg.icosphere(4)
    fields = [cg.geodesic_distance(mesh, 3, method=method, solver="ipm", threads=t) for t in (1, 2, 3)]
    for d in fields[1:]:
        assert np.abs(d - fields[0]).max() <= 1e-9 * mesh.bbox_diagonal


def test_default_policy(monkeypatch, no_env):
    monkeypatch.setattr(_threads, "usable_cores", lambda: 4)
    for busy, expected in [(0, 4), (1, 3), (3, 1), (9, 1)]:
        monkeypatch.setattr(_threads, "busy_neighbours", lambda busy=busy: busy)
        assert _threads.default_threads() == expected
        assert _threads.resolve_threads(None) == expected
    monkeypatch.setattr(_threads, "usable_cores", lambda: 1)
    assert _threads.default_threads() == 1


def test_busy_neighbours_reads_procs_running(monkeypatch):
    counts = iter([3, 1, 3, 3, 2])
    monkeypatch.setattr(_threads, "_procs_running", lambda: next(counts))
    assert _threads.busy_neighbours(samples=5, interval=0) == 2  # median 3, less this thread
    monkeypatch.setattr(_threads, "_procs_running", lambda: None)
    assert _threads.busy_neighbours(samples=3, interval=0) == 0
    assert _threads._procs_running() is None or _threads._procs_running() >= 1  # the real file, where there is one


def test_wait_policy_set_before_libgomp_loads(monkeypatch):
    monkeypatch.delenv("GOMP_SPINCOUNT", raising=False)
    monkeypatch.delenv("OMP_WAIT_POLICY", raising=False)
    monkeypatch.setattr(_threads, "_libgomp_loaded", lambda: False)
    assert _threads.set_openmp_wait_policy() == _threads.SPINCOUNT_DEFAULT
    assert os.environ["GOMP_SPINCOUNT"] == _threads.SPINCOUNT_DEFAULT
    monkeypatch.setenv("GOMP_SPINCOUNT", "5")  # the user's choice stays
    assert _threads.set_openmp_wait_policy() is None and os.environ["GOMP_SPINCOUNT"] == "5"
    monkeypatch.delenv("GOMP_SPINCOUNT")
    monkeypatch.setenv("OMP_WAIT_POLICY", "ACTIVE")
    assert _threads.set_openmp_wait_policy() is None and "GOMP_SPINCOUNT" not in os.environ
    monkeypatch.delenv("OMP_WAIT_POLICY")
    monkeypatch.setattr(_threads, "_libgomp_loaded", lambda: True)  # too late: the runtime read its variables
    assert _threads.set_openmp_wait_policy() is None and "GOMP_SPINCOUNT" not in os.environ


@pytest.mark.parametrize("user", [None, "7"])
def test_import_sets_the_wait_policy_first(user):
    """In a fresh process ``import cvxgeodesic`` loads libgomp (CHOLMOD, MKL): the variable is set before."""
    env = {k: v for k, v in os.environ.items() if k not in ("GOMP_SPINCOUNT", "OMP_WAIT_POLICY")}
    if user:
        env["GOMP_SPINCOUNT"] = user
    env["PYTHONPATH"] = os.pathsep.join([str(Path(cg.__file__).parents[1]), env.get("PYTHONPATH", "")])
    code = ("import os, cvxgeodesic.linalg; "
            "print(os.environ['GOMP_SPINCOUNT'], 'libgomp' in open('/proc/self/maps').read())")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    value, loaded = out.stdout.split()
    assert value == (user or _threads.SPINCOUNT_DEFAULT)
    if not loaded == "True":
        pytest.skip("no library loaded libgomp at import here")


def test_batch_local_cluster_sets_the_variable(monkeypatch):
    from cvxgeodesic import _cluster

    monkeypatch.setattr(_cluster.os, "cpu_count", lambda: 8)
    env = _cluster.local_worker_environ(4)
    assert env["distributed.nanny.pre-spawn-environ.CVXGEODESIC_THREADS"] == 2
    assert {v for k, v in env.items() if not k.endswith("MALLOC_TRIM_THRESHOLD_")} == {2}
    assert env["distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_"] is None  # unset: see _cluster
    assert _cluster.local_worker_environ(16)["distributed.nanny.pre-spawn-environ.CVXGEODESIC_THREADS"] == 1
