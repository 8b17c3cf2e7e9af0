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


@pytest.fixture
def four_cores(monkeypatch):
    """Counts up to 4 pass uncapped, whatever the machine: for the tests of what a count reaches, not of the cap."""
    monkeypatch.setattr(_threads, "usable_cores", lambda: 4)


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


def test_environment_variable_and_explicit_value(monkeypatch, four_cores):
    mesh = cg.icosphere(2)
    monkeypatch.setenv(_threads.ENV_VAR, "1")
    assert cg.GeodesicSolver(mesh, "qclp").solve(0).info.extra["threads"] == 1
    monkeypatch.setenv(_threads.ENV_VAR, " 3 ")
    assert cg.GeodesicSolver(mesh, "qclp").solve(0).info.extra["threads"] == 3
    assert cg.GeodesicSolver(mesh, "qclp", threads=2).solve(0).info.extra["threads"] == 2
    assert cg.GeodesicSolver(mesh, "heat", threads=2).solve(0).info.extra["threads"] == 2  # baselines too


def test_a_count_above_the_cores_is_capped_and_noted(no_env):
    cores = _threads.usable_cores()
    note = f"threads=1000000 capped at {cores} (the cores available)"
    # checked before any solve: without the cap the pools would be asked for a million threads (a hang)
    assert _threads.resolve_threads_noted(10**6) == (cores, note)
    assert _threads.resolve_threads(cores) == cores and _threads.resolve_threads_noted(cores)[1] is None
    solver = cg.GeodesicSolver(cg.icosphere(1), "qclp", threads=10**6)
    assert solver.threads == cores and note in solver.notes
    res = solver.solve(0)
    assert res.info.status == "optimal" and res.info.extra["threads"] == cores
    assert res.info.notes.count(note) == 1
    baseline = cg.GeodesicSolver(cg.icosphere(1), "dijkstra", threads=10**6).solve(0)
    assert baseline.info.notes.count(note) == 1


def test_the_environment_variable_is_capped_too(monkeypatch):
    cores = _threads.usable_cores()
    monkeypatch.setenv(_threads.ENV_VAR, str(cores + 1))
    note = f"{_threads.ENV_VAR}={cores + 1} capped at {cores} (the cores available)"
    assert _threads.resolve_threads_noted() == (cores, note)
    res = cg.GeodesicSolver(cg.icosphere(1), "dijkstra").solve(0)
    assert res.info.extra["threads"] == cores and note in res.info.notes


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
def test_limit_reaches_every_pool(threads, four_cores):
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


def test_the_pool_controller_is_kept_until_a_module_is_imported(monkeypatch):
    """threadpoolctl scans every loaded library for a controller (a third of a small heat solve): one is kept, and
    made again after an import, the way a new thread pool arrives."""
    import sys
    import types

    from threadpoolctl import threadpool_info

    with _threads.pool_limits(1):
        first = _threads._controller[1]
        assert {p["num_threads"] for p in threadpool_info()} == {1}
    with _threads.pool_limits(1):
        assert _threads._controller[1] is first
    monkeypatch.setitem(sys.modules, "cvxgeodesic_test_new_module", types.ModuleType("cvxgeodesic_test_new_module"))
    with _threads.pool_limits(1):
        assert _threads._controller[1] is not first
        assert {p["num_threads"] for p in threadpool_info()} == {1}


def test_multires_coarse_solver_inherits(no_env):
    solver = cg.GeodesicSolver(cg.icosphere(4), "qclp", multires=500, threads=1)
    coarse = solver._strategy.coarse.ipm.cholesky  # the coarse mesh's solver, built inside the façade's limit
    if coarse.backend == "pardiso":
        assert coarse.numeric.threads == 1
    assert solver.solve(0).info.extra["threads"] == 1


@pytest.mark.parametrize("method", ["qcqp-hessian", "qclp"])
def test_same_field_at_every_thread_count(method, four_cores):
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


KTHREAD = _threads._PF_KTHREAD


def _stat_line(pid: int, name: str, state: str, flags: int = 0, threads: int = 1) -> str:
    """A /proc/PID/stat line: fields after the name are state, ppid, ..., flags (9th), ..., num_threads (20th)."""
    fields = [state, "1", str(pid), str(pid), "0", "-1", str(flags), *["0"] * 10, str(threads), *["0"] * 32]
    return f"{pid} ({name}) {' '.join(fields)}\n"


def fake_proc(root: Path, processes: dict[int, tuple[str, list[str], int]], procs_running: int = 1) -> Path:
    """A /proc tree: ``{pid: (name, [state of each thread, main first], flags)}`` and /proc/stat."""
    root.mkdir(parents=True, exist_ok=True)
    (root / "stat").write_text(f"cpu  1 2 3 4\nprocs_running {procs_running}\nprocs_blocked 0\n")
    for pid, (name, states, flags) in processes.items():
        (root / str(pid) / "task").mkdir(parents=True)
        (root / str(pid) / "stat").write_text(_stat_line(pid, name, states[0], flags, len(states)))
        for k, state in enumerate(states):
            tid = pid if k == 0 else pid * 100 + k
            (root / str(pid) / "task" / str(tid)).mkdir()
            (root / str(pid) / "task" / str(tid) / "stat").write_text(_stat_line(tid, name, state, flags, len(states)))
    return root


def idle_machine(root: Path, own: dict | None = None, **neighbours) -> Path:
    """An idle machine as this VM showed it, with ``neighbours`` added: init and kthreadd asleep, a kernel thread
    that is always runnable, sleeping user processes, and this process's own threads (spinning after import)."""
    procs = {1: ("systemd", ["S"], 0), 2: ("kthreadd", ["S"], KTHREAD), 17: ("rcu_preempt", ["R"], KTHREAD),
             311: ("sshd: user (priv)", ["S"], 0), 420: ("python3", ["S", "S", "S"], 0)}
    procs[os.getpid()] = ("python", ["R", "R", "R", "S"], 0)  # main thread + two spinning OpenBLAS/OpenMP workers
    procs.update(own or {})
    procs.update({int(k[1:]): v for k, v in neighbours.items()})
    return fake_proc(root, procs, procs_running=5)


def test_busy_neighbours_idle_machine_is_idle(monkeypatch, tmp_path, no_env):
    """Neither this process's runnable threads nor an always-runnable kernel thread count as a neighbour."""
    monkeypatch.setattr(_threads, "_PROC", str(idle_machine(tmp_path / "proc")))
    assert _threads.busy_neighbours(interval=0) == 0
    for cores in (2, 8):
        monkeypatch.setattr(_threads, "usable_cores", lambda cores=cores: cores)
        assert _threads.default_threads() == cores


@pytest.mark.parametrize(("neighbours", "busy"), [
    ({"p500": ("python3", ["R"], 0)}, 1),  # a busy loop
    ({"p500": ("a (b) c)", ["R"], 0)}, 1),  # parentheses and spaces in the name
    ({"p500": ("python3", ["R", "R"], 0), "p501": ("make", ["R"], 0)}, 3),  # a 2-thread solver and a build
    ({"p500": ("dask worker", ["S", "R", "S", "R"], 0)}, 2),  # the main thread waits while two threads work
    ({"p500": ("kworker/0:1", ["R"], KTHREAD)}, 0),
    ({"p500": ("zombie", ["Z"], 0), "p501": ("disk", ["D"], 0)}, 0),
])
def test_busy_neighbours_counts_other_processes_threads(monkeypatch, tmp_path, neighbours, busy):
    monkeypatch.setattr(_threads, "_PROC", str(idle_machine(tmp_path / "proc", **neighbours)))
    assert _threads.busy_neighbours(interval=0) == busy
    monkeypatch.setattr(_threads, "usable_cores", lambda: 2)
    assert _threads.default_threads() == max(1, 2 - busy)


def test_busy_neighbours_without_a_full_view_of_proc(monkeypatch, tmp_path):
    """hidepid (process 1 not visible): procs_running less this process's runnable threads; no /proc: 0."""
    root = fake_proc(tmp_path / "proc", {os.getpid(): ("python", ["R", "R", "S"], 0)}, procs_running=5)
    monkeypatch.setattr(_threads, "_PROC", str(root))
    assert _threads.busy_neighbours(interval=0) == 3
    monkeypatch.setattr(_threads, "_PROC", str(tmp_path / "nothing"))
    assert _threads.busy_neighbours(samples=3, interval=0) == 0


def test_busy_neighbours_takes_the_median(monkeypatch):
    counts = iter([0, 2, 0, 1, 3])
    monkeypatch.setattr(_threads, "_other_runnable", lambda: next(counts))
    assert _threads.busy_neighbours(samples=5, interval=0) == 1
    monkeypatch.undo()
    assert _threads._procs_running() is None or _threads._procs_running() >= 1  # the real files, where there are
    assert _threads._other_runnable() is None or _threads._other_runnable() >= 0


def _fresh_process_env() -> dict:
    env = {k: v for k, v in os.environ.items() if k not in (_threads.ENV_VAR, "OMP_NUM_THREADS", "NUMBA_NUM_THREADS")}
    env["PYTHONPATH"] = os.pathsep.join([str(Path(cg.__file__).parents[1]), env.get("PYTHONPATH", "")])
    return env


# a fresh process: import, then the machine as `root` shows it, but this process's own task states are the real
# ones (the library's thread pools right after import, and after building a solver)
FRESH = """
import os, sys
import cvxgeodesic as cg
from cvxgeodesic import _threads
root = sys.argv[1]
if os.path.lexists(f"{root}/{os.getpid()}"):  # a fake neighbour has this pid (a fresh container's pids are small)
    os.rename(f"{root}/{os.getpid()}", f"{root}/{max(int(p) for p in os.listdir(root) if p.isdigit()) + 1}")
os.symlink(f"/proc/{os.getpid()}", f"{root}/{os.getpid()}")
_threads._PROC = root
first = _threads.busy_neighbours()
solver = cg.GeodesicSolver(cg.icosphere(2), "qclp")
print(first, _threads.busy_neighbours(), solver.threads, _threads.usable_cores())
"""


def test_fresh_processes_on_an_idle_machine_use_every_core(tmp_path):
    """In 20 of 20 fresh processes the default is every usable core: the machine is faked idle (other sessions
    load the real one), the process's own threads are real."""
    counts = []
    for k in range(20):
        root = idle_machine(tmp_path / f"proc{k}", own={})
        (root / str(os.getpid())).rename(root / "this-test")  # the test process is a neighbour here, but asleep
        out = subprocess.run([sys.executable, "-c", FRESH, str(root)], env=_fresh_process_env(),
                             capture_output=True, text=True, timeout=120)
        assert out.returncode == 0, out.stderr
        counts.append(tuple(int(x) for x in out.stdout.split()))
    assert all(c[:2] == (0, 0) and c[2] == c[3] for c in counts), counts


def test_beside_a_busy_process_the_default_leaves_it_a_core(tmp_path):
    """The real /proc: a spinning neighbour is always runnable, so a fresh process sees it and keeps to its share."""
    spin = subprocess.Popen([sys.executable, "-c", "import time\nprint(flush=True)\nt = time.monotonic() + 60\n"
                             "while time.monotonic() < t:\n    pass\n"], stdout=subprocess.PIPE)
    try:
        assert spin.stdout is not None and spin.stdout.readline() == b"\n"
        code = ("from cvxgeodesic import _threads as t\n"
                "print(t.busy_neighbours(), t.default_threads(), t.usable_cores())")
        out = subprocess.run([sys.executable, "-c", code], env=_fresh_process_env(), capture_output=True, text=True,
                             timeout=120)
    finally:
        spin.kill()
        spin.wait()
    assert out.returncode == 0, out.stderr
    busy, threads, cores = (int(x) for x in out.stdout.split())
    assert busy >= 1
    assert threads == max(1, cores - busy) and (cores == 1 or threads < cores)


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
