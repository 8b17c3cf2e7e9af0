"""``cvxgeodesic.distance_matrix``: one GeodesicSolver, one row per source vertex."""

import contextlib
import os
import re
import socket
import sys
import threading
import time

import numpy as np
import pytest

import cvxgeodesic as cg
from conftest import interrupt_cli, sphere_file_with_a_loose_vertex
from cvxgeodesic.cli import main
from cvxgeodesic.errors import SourceError


@pytest.fixture(scope="module")
def sphere():
    return cg.icosphere(2)


def test_rows_match_single_solves(sphere):
    verts = [0, 17, 100, 17]
    D = cg.distance_matrix(sphere, verts, method="qcqp-hessian", m=1.0)
    assert D.shape == (4, sphere.n_vertices) and D.dtype == np.float64
    solver = cg.GeodesicSolver(sphere, "qcqp-hessian")
    for i, v in enumerate(verts):
        np.testing.assert_allclose(D[i], solver.solve(v).distance, rtol=1e-9, atol=1e-12)
        assert D[i, v] == 0.0
    np.testing.assert_array_equal(D[1], D[3])  # a repeated vertex is solved once
    # nearly symmetric (each row is its own problem), close to the great-circle distance
    sub = D[:3][:, [0, 17, 100]]
    np.testing.assert_allclose(sub, sub.T, atol=0.05)


def test_single_int_and_baseline(sphere):
    D = cg.distance_matrix(sphere, 5, method="dijkstra", progress=True)
    assert D.shape == (1, sphere.n_vertices)
    np.testing.assert_allclose(D[0], cg.geodesic_distance(sphere, 5, method="dijkstra"))


@pytest.mark.parametrize("verts, match", [([], "vertices is empty"), ([0, 999], "out of range"), ([[0, 1]], "1-D"),
                                          (True, "vertices must be vertex indices"),
                                          ([0.5], "vertices must be integer vertex indices"),
                                          ([[0, 1], [2]], "vertices must be an int or a 1-D sequence of ints")])
def test_bad_vertices(sphere, verts, match):
    with pytest.raises(SourceError, match=match):
        cg.distance_matrix(sphere, verts)


# ---- rows on a Dask cluster (cvxgeodesic.rows): loopback only ----

@pytest.fixture(scope="module")
def cluster():
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as c:
        yield c


def test_cluster_rows_are_the_in_process_rows(sphere, cluster, monkeypatch, capsys):
    """Same solves, the requested order, a duplicate solved once, one contiguous chunk per worker."""
    from cvxgeodesic import rows

    chunks = []
    split = rows.split_rows
    monkeypatch.setattr(rows, "split_rows", lambda n, k: chunks.append(split(n, k)) or chunks[-1])
    verts = [100, 17, 0, 17, 5]
    D = cg.distance_matrix(sphere, verts, method="qcqp-hessian", scheduler=cluster.scheduler_address, progress=True)
    ref = cg.distance_matrix(sphere, verts, method="qcqp-hessian")
    assert D.shape == ref.shape == (5, sphere.n_vertices)
    np.testing.assert_allclose(D, ref, rtol=0, atol=1e-9 * sphere.bbox_diagonal)
    assert all(D[i, v] == 0.0 for i, v in enumerate(verts))
    np.testing.assert_array_equal(D[1], D[3])
    assert chunks == [[slice(0, 2), slice(2, 4)]]  # 4 distinct rows, 2 workers
    assert "4/4" in capsys.readouterr().err  # the bar counts rows


def test_cluster_rows_of_surface_points_and_client_object(cluster):
    distributed = pytest.importorskip("distributed")
    mesh = cg.grid_plane(8, 8)
    pts = [cg.SurfacePoint(30, [0.2, 0.3, 0.5]), 7, "boundary"]
    with distributed.Client(cluster) as client:
        D = cg.distance_matrix(mesh, pts, method="qclp", scheduler=client)
    np.testing.assert_allclose(D, cg.distance_matrix(mesh, pts, method="qclp"), atol=1e-9 * mesh.bbox_diagonal)


def test_cluster_warnings_and_errors_reach_the_caller(cluster):
    from cvxgeodesic.errors import ParameterError

    # a plane with one zero-area face: the worker's DegenerateFacesWarning is issued here, once
    V = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.5, 0.5, 0], [1, 1, 0]]
    F = [[0, 1, 3], [0, 3, 2], [1, 4, 3], [3, 4, 2], [1, 2, 3]]
    with pytest.warns(cg.DegenerateFacesWarning) as record:
        D = cg.distance_matrix((V, F), [0, 4], method="qclp", scheduler=cluster.scheduler_address)
    assert sum(issubclass(w.category, cg.DegenerateFacesWarning) for w in record) == 1
    assert D[0, 0] == 0 and D[1, 4] == 0
    with pytest.raises(ParameterError, match="unknown method 'nope'"):  # raised on a worker, same type and text
        cg.distance_matrix(cg.icosphere(1), [0, 1], method="nope", scheduler=cluster.scheduler_address)


def test_split_rows_and_one_solver_per_chunk():
    from cvxgeodesic.rows import solve_chunk, split_rows

    assert split_rows(5, 2) == [slice(0, 2), slice(2, 5)]
    for n, k in [(1, 4), (7, 3), (16, 2), (3, 3)]:
        parts = split_rows(n, k)
        assert len(parts) == min(n, k) and parts[0].start == 0 and parts[-1].stop == n
        assert all(a.stop == b.start for a, b in zip(parts, parts[1:], strict=False))
        assert max(p.stop - p.start for p in parts) - min(p.stop - p.start for p in parts) <= 1
    built = []

    def factory(mesh, **options):
        built.append(options)
        return cg.GeodesicSolver(mesh, **options)

    sphere = cg.icosphere(1)
    rows, caught = solve_chunk(factory, sphere, [0, 3, 9], {"method": "qclp"})
    assert len(built) == 1 and rows.shape == (3, sphere.n_vertices) and caught == []
    np.testing.assert_array_equal(rows, cg.distance_matrix(sphere, [0, 3, 9], method="qclp"))


def test_cluster_argument_errors_before_any_work(sphere):
    from cvxgeodesic.errors import ParameterError

    with pytest.raises(ParameterError, match="workers must be a positive integer"):
        cg.distance_matrix(sphere, [0], workers=0)
    with pytest.raises(ParameterError, match="not both"):
        cg.distance_matrix(sphere, [0], workers=2, scheduler="tcp://SCHEDULER:8786")
    with pytest.raises(SourceError, match="out of range"):  # sources are checked before a cluster starts
        cg.distance_matrix(sphere, [0, 999], workers=2)


def test_without_dask_the_error_names_the_extra(sphere, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # makes `import distributed` fail
    with pytest.raises(ImportError, match=r"distance_matrix on a Dask cluster.*cvxgeodesic\[cluster\]"):
        cg.distance_matrix(sphere, [0, 1], workers=2)
    np.testing.assert_array_equal(cg.distance_matrix(sphere, [0, 1], method="qclp"),  # in-process needs no Dask
                                  np.stack([cg.geodesic_distance(sphere, v, method="qclp") for v in (0, 1)]))


@contextlib.contextmanager
def _http_server():
    """The address of a TCP server on 127.0.0.1 that answers like a web server, not a Dask scheduler."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(4)
    conns = []

    def serve():
        while True:
            try:
                conn, _ = server.accept()
            except OSError:
                return
            conns.append(conn)
            conn.sendall(b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n")

    threading.Thread(target=serve, daemon=True).start()
    try:
        yield f"tcp://127.0.0.1:{server.getsockname()[1]}"
    finally:
        for c in conns:
            c.close()
        server.close()


def test_non_dask_scheduler_fails_fast(sphere, tmp_path, capsys):
    pytest.importorskip("distributed")
    with _http_server() as address:
        t0 = time.perf_counter()
        with pytest.raises(ConnectionError, match="does not speak Dask's protocol"):
            cg.distance_matrix(sphere, [0, 1], scheduler=address)
        path = cg.save_distance(tmp_path / "in.ply", sphere, np.zeros(sphere.n_vertices))
        assert main(["matrix", str(path), "-s", "0,1", "-q", "--scheduler", address, "-o",
                     str(tmp_path / "D.npy")]) == 2
        assert time.perf_counter() - t0 < 20
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("cvxgeodesic: error: ") and "Dask's protocol" in err[0], err
    assert not (tmp_path / "D.npy").exists()


def test_cli_matrix_on_a_cluster(cluster, tmp_path, capsys):
    mesh, path = sphere_file_with_a_loose_vertex(tmp_path)
    ref, out = tmp_path / "ref.npy", tmp_path / "D.npy"
    args = ["matrix", str(path), "-s", "6,1", "-s", "6", "-s", "30", "--method", "qclp"]
    assert main([*args, "-q", "-o", str(ref)]) == 0
    assert main([*args, "--scheduler", cluster.scheduler_address, "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert f"on {cluster.scheduler_address}" in err and "3/3" in err  # 3 distinct rows counted by the bar
    assert re.search(r"^qclp: rows 3/3, \d+ s$", err, flags=re.M)  # the cluster's progress (no terminal: lines)
    D = np.load(out)
    assert D.shape == (4, 163) and np.all(np.isinf(D[:, 0])) and D[0, 6] == 0 and D[1, 1] == 0 and D[3, 30] == 0
    np.testing.assert_allclose(D, np.load(ref), rtol=0, atol=1e-9 * mesh.bbox_diagonal)
    assert not list(tmp_path.glob(".*.tmp"))
    assert main([*args, "--workers", "2", "--scheduler", cluster.scheduler_address, "-o", str(tmp_path / "E.npy")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "not both" in err[0] and not (tmp_path / "E.npy").exists()


def test_cli_matrix_on_a_local_cluster(tmp_path, capsys):
    pytest.importorskip("distributed")
    mesh, path = sphere_file_with_a_loose_vertex(tmp_path)
    out = tmp_path / "D.npy"
    assert main(["matrix", str(path), "-s", "1,6", "--method", "qclp", "--workers", "1", "-o", str(out)]) == 0
    assert "a local cluster of 1 worker processes" in capsys.readouterr().err
    expected = cg.distance_matrix(mesh, [0, 5], method="qclp")
    np.testing.assert_allclose(np.load(out)[:, 1:], expected, rtol=0, atol=1e-9 * mesh.bbox_diagonal)


def test_ctrl_c_in_a_cluster_matrix_is_one_line_and_exit_130(tmp_path):
    pytest.importorskip("distributed")
    big = cg.grid_plane(130, jitter=0.1)  # ~3.6 s per Clarabel solve (70×70 took 0.9 s): still running at Ctrl-C
    path = cg.save_distance(tmp_path / "big.ply", big, np.zeros(big.n_vertices))
    out = tmp_path / "D.npy"
    args = ["matrix", str(path), "-s", "0,1,2,3", "--solver", "clarabel", "--workers", "2", "-o", str(out)]
    returncode, text, elapsed = interrupt_cli(args, lambda err: b"row" in err.split(b"rows;")[-1])  # the bar is up
    lines = [ln for ln in re.split(r"[\r\n]+", text) if ln.strip() and not ln.lstrip().startswith("qclp: rows")]
    assert returncode == 130, text
    assert "Traceback" not in text and "WARNING" not in text and "CancelledError" not in text, text
    assert lines[-1] == "cvxgeodesic: interrupted" and len(lines) <= 2, lines  # the start line and this one
    assert elapsed < 5, elapsed
    assert not out.exists() and not list(tmp_path.glob(".*.tmp"))


def test_local_cluster_workers_share_the_cores(monkeypatch):
    """workers=N gives every worker process cpu_count // N threads (two full OpenMP pools slow each other down)."""
    pytest.importorskip("distributed")
    from cvxgeodesic import _cluster

    monkeypatch.setattr(_cluster.os, "cpu_count", lambda: 8)  # read in this process when the cluster starts
    names = ("CVXGEODESIC_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS")
    for name in (*names, "MALLOC_TRIM_THRESHOLD_"):  # set here (conftest, earlier tests) they would be inherited
        monkeypatch.delenv(name, raising=False)
    with contextlib.ExitStack() as stack:
        client, cluster = _cluster.open_client(stack, None, 2)
        assert cluster is not None
        seen = client.run(lambda: {k: os.environ.get(k) for k in (*names, "MALLOC_TRIM_THRESHOLD_")})
    # Dask's MALLOC_TRIM_THRESHOLD_=65536 made every solve ~1.8x slower on a worker: it is left unset
    assert len(seen) == 2 and all(v == {**dict.fromkeys(names, "4"), "MALLOC_TRIM_THRESHOLD_": None}
                                  for v in seen.values()), seen
    # Dask's nanny writes them into this process too: left there, they would pin the caller's later solves
    assert not any(name in os.environ for name in names), {k: os.environ.get(k) for k in names}


# ---- rows that survive: checkpoint, resume, Ctrl-C, progress ----

class _Counting:
    """Counts GeodesicSolver.solve calls; raises KeyboardInterrupt at call ``stop`` (1-based) when given."""

    def __init__(self, monkeypatch, stop=None):
        self.calls, self.stop = 0, stop
        solve = cg.GeodesicSolver.solve

        def counting(solver, sources, **kw):
            self.calls += 1
            if self.stop is not None and self.calls == self.stop:
                raise KeyboardInterrupt
            return solve(solver, sources, **kw)

        monkeypatch.setattr(cg.GeodesicSolver, "solve", counting)


def test_ctrl_c_keeps_the_finished_rows_and_the_same_call_resumes(sphere, tmp_path, monkeypatch):
    from cvxgeodesic.rows import checkpoint_rows

    verts = [3, 0, 17, 100, 3, 42]  # 5 distinct rows
    ref = cg.distance_matrix(sphere, verts, method="qclp", progress=False)
    path = tmp_path / "rows.npz"
    counter = _Counting(monkeypatch, stop=3)  # Ctrl-C during the third row: two are done
    with pytest.raises(KeyboardInterrupt) as info:  # without a checkpoint the note says how to keep them
        cg.distance_matrix(sphere, verts, method="qclp", progress=False)
    assert info.value.__notes__ == ["distance_matrix: 2 of 5 rows were done; with checkpoint='rows.npz' they are "
                                    "kept and the same call resumes"]
    counter.calls = 0
    with pytest.raises(KeyboardInterrupt) as info:
        cg.distance_matrix(sphere, verts, method="qclp", progress=False, checkpoint=path)
    assert checkpoint_rows(path) == (2, 5)
    assert any("2 of 5 rows kept in" in note for note in info.value.__notes__)
    assert not list(tmp_path.glob(".*.tmp"))
    counter.calls, counter.stop = 0, None
    D = cg.distance_matrix(sphere, verts, method="qclp", progress=False, checkpoint=path)
    assert counter.calls == 3  # only the rows the checkpoint did not hold
    # the same solves in the same order of operations: equal to rounding
    np.testing.assert_allclose(D, ref, rtol=1e-12, atol=0)
    assert checkpoint_rows(path) == (5, 5)
    counter.calls = 0
    np.testing.assert_array_equal(cg.distance_matrix(sphere, verts, method="qclp", progress=False, checkpoint=path), D)
    assert counter.calls == 0  # a complete checkpoint is the answer


def test_a_failing_row_keeps_the_rows_before_it(sphere, tmp_path, monkeypatch):
    from cvxgeodesic.errors import SolverError
    from cvxgeodesic.rows import checkpoint_rows

    solve = cg.GeodesicSolver.solve

    def failing(solver, sources, **kw):
        if sources == 17:
            raise SolverError("row 17 failed", solver="ipm", status="max_iter")
        return solve(solver, sources, **kw)

    monkeypatch.setattr(cg.GeodesicSolver, "solve", failing)
    with pytest.raises(SolverError, match="row 17 failed"):
        cg.distance_matrix(sphere, [0, 5, 17, 30], method="qclp", progress=False, checkpoint=tmp_path / "c.npz")
    assert checkpoint_rows(tmp_path / "c.npz") == (2, 4)


def test_a_checkpoint_of_other_parameters_is_refused(sphere, tmp_path):
    from cvxgeodesic.errors import ParameterError

    path = tmp_path / "rows.npz"
    cg.distance_matrix(sphere, [0, 5], method="qclp", progress=False, checkpoint=path)
    with pytest.raises(ParameterError, match=r"other parameters \(method: 'qclp' there, 'dijkstra' here\)"):
        cg.distance_matrix(sphere, [0, 5], method="dijkstra", checkpoint=path)
    with pytest.raises(ParameterError, match=r"other parameters \(sources: \[0, 5\] there, \[0, 6\] here\)"):
        cg.distance_matrix(sphere, [0, 6], method="qclp", checkpoint=path)
    curve = [cg.SurfacePoint(0, [1, 0, 0]), cg.SurfacePoint(3, [0.2, 0.3, 0.5])]
    cg.distance_matrix(sphere, [cg.SurfaceCurve(curve)], method="qclp", checkpoint=tmp_path / "curve.npz")
    with pytest.raises(ParameterError, match=r"other parameters \(sources: \['SurfaceCurve [0-9a-f]+'\] there"):
        cg.distance_matrix(sphere, [cg.SurfaceCurve(curve[::-1])], method="qclp", checkpoint=tmp_path / "curve.npz")
    tet = cg.tet_l_prism(2)
    cg.distance_matrix(tet, [0, 1], method="qclp", checkpoint=tmp_path / "tet.npz")
    with pytest.raises(ParameterError, match="other parameters.*mesh: 162 vertices"):
        cg.distance_matrix(cg.icosphere(1), [0, 5], method="qclp", checkpoint=path)
    with pytest.raises(ParameterError, match="other parameters.*m: 1.0 there, 2.0 here"):
        cg.distance_matrix(sphere, [0, 5], method="qclp", m=2.0, checkpoint=path)
    # another thread count changes at most the last digits: the checkpoint is the answer
    cg.distance_matrix(sphere, [0, 5], method="qclp", threads=1, checkpoint=path)
    (tmp_path / "junk.npz").write_bytes(b"not a zip")
    with pytest.raises(ParameterError, match="junk.npz is not a distance_matrix checkpoint"):
        cg.distance_matrix(sphere, [0, 5], checkpoint=tmp_path / "junk.npz")
    np.savez(tmp_path / "other.npz", x=1)
    with pytest.raises(ParameterError, match=r"other.npz is damaged or not a distance_matrix checkpoint \(no 'format' "
                                             r"entry\); it was not used: delete it"):
        cg.distance_matrix(sphere, [0, 5], checkpoint=tmp_path / "other.npz")
    with pytest.raises(ParameterError, match="unsupported output file extension '.npy'"):
        cg.distance_matrix(sphere, [0, 5], checkpoint=tmp_path / "rows.npy")


def test_progress_shows_after_the_delay_by_default(sphere, monkeypatch, capsys):
    from cvxgeodesic import _verbose

    monkeypatch.setattr(_verbose, "PROGRESS_DELAY", 1e6)  # a fast matrix: silent
    cg.distance_matrix(sphere, [0, 5, 9], method="dijkstra")
    assert capsys.readouterr().err == ""
    monkeypatch.setattr(_verbose, "PROGRESS_DELAY", 0.0)  # a slow one: the bar counts rows
    cg.distance_matrix(sphere, [0, 5, 9], method="dijkstra")
    assert "3/3" in capsys.readouterr().err
    cg.distance_matrix(sphere, [0, 5, 9], method="dijkstra", progress=False)
    assert capsys.readouterr().err == ""


def test_cli_matrix_interrupted_then_resumed(tmp_path, monkeypatch, capsys):
    mesh, path = sphere_file_with_a_loose_vertex(tmp_path)
    out = tmp_path / "D.npy"
    partial = tmp_path / "D.npy.partial.npz"
    args = ["matrix", str(path), "-s", "6,1,30,9", "--method", "qclp", "-o", str(out)]
    counter = _Counting(monkeypatch, stop=3)
    assert main(args) == 130
    err = capsys.readouterr().err
    assert f"cvxgeodesic: 2 of 4 rows kept in {partial}; run the same command again to resume" in err, err
    assert err.strip().splitlines()[-1] == "cvxgeodesic: interrupted"
    assert partial.exists() and not out.exists()
    counter.calls, counter.stop = 0, None
    assert main(args) == 0
    assert f"resuming from {partial}: 2 of 4 rows already done" in capsys.readouterr().err
    assert counter.calls == 2 and not partial.exists()
    expected = cg.distance_matrix(mesh, [5, 0, 29, 8], method="qclp", progress=False)
    np.testing.assert_allclose(np.load(out)[:, 1:], expected, rtol=1e-12, atol=0)


def test_cli_matrix_real_ctrl_c_keeps_rows_and_resumes(tmp_path):
    """A real SIGINT once some rows are done (read from the bar), whatever the machine's speed."""
    from cvxgeodesic.rows import checkpoint_rows

    mesh = cg.icosphere(3)
    path = cg.save_distance(tmp_path / "s.ply", mesh, np.zeros(mesh.n_vertices))
    out = tmp_path / "D.npy"
    partial = tmp_path / "D.npy.partial.npz"
    rows = ",".join(str(v) for v in range(0, 640, 2))  # 320 rows of ~50 ms: far from done after the first
    args = ["matrix", str(path), "-s", rows, "--method", "qclp", "-o", str(out)]
    returncode, text, _ = interrupt_cli(args, lambda err: re.search(rb"\b[1-9]\d*/320\b", err) is not None,
                                        settle=0.2)
    assert returncode == 130, text
    kept = checkpoint_rows(partial)
    assert kept is not None and 1 <= kept[0] < 320 and kept[1] == 320, (kept, text)
    assert f"{kept[0]} of 320 rows kept in" in text and "Traceback" not in text, text
    assert not out.exists() and not list(tmp_path.glob(".*.tmp"))
    assert main([*args[:3], ",".join(str(v) for v in range(0, 640, 2)), *args[4:], "-q"]) == 0
    D = np.load(out)
    some = [0, 150, 319]  # rows before and after the interruption, against a fresh solve
    np.testing.assert_allclose(D[some], cg.distance_matrix(mesh, [2 * i for i in some], method="qclp",
                                                         progress=False), rtol=1e-12, atol=0)


def test_checkpoint_writes_are_spaced_by_their_own_duration(tmp_path, monkeypatch):
    """A slow write (a large dense matrix) is not repeated every SAVE_EVERY seconds: at most ~10 % of the time."""
    from cvxgeodesic import rows

    clock = {"t": 0.0}
    monkeypatch.setattr(rows.time, "monotonic", lambda: clock["t"])
    real, writes = rows.atomic_write, []

    def slow_write(path, write):
        writes.append(clock["t"])
        clock["t"] += 3.0  # this write takes 3 s
        return real(path, write)

    monkeypatch.setattr(rows, "atomic_write", slow_write)
    store = rows.RowStore(10, 4, sparse=False, path=tmp_path / "c.npz", parameters={})
    for i, t in enumerate([1.0, 2.5, 10.0, 35.0, 36.0, 70.0, 80.0]):
        clock["t"] = max(clock["t"], t)
        store.put(i, np.zeros(4))
        store.save(force=False)
    # the first write once SAVE_EVERY (2 s) has passed, then only 10 × 3 s after the last one ended (5.5 s, 39 s)
    assert writes == [2.5, 36.0, 70.0], writes
    store.save()
    assert len(writes) == 4 and rows.checkpoint_rows(tmp_path / "c.npz") == (7, 10)
