"""A local Dask cluster listens on loopback only: nothing of a ``--workers`` job is reachable from the network.

Dask's ``dashboard_address=":0"`` binds the scheduler's dashboard (an HTTP server that runs even without
Bokeh) to every interface; ``_cluster.open_client`` binds every socket of its cluster to 127.0.0.1. On
loopback, every user of the machine reaches them: none may speak Dask in clear (it runs what a client
submits); the cluster's TLS is tested in depth in tests/test_cluster_security.py.
"""

from __future__ import annotations

import ipaddress
import os
import socket
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

import cvxgeodesic as cg

pytest.importorskip("distributed")
psutil = pytest.importorskip("psutil")  # a dependency of distributed


def _listening(pid: int) -> set[tuple[int, str, int]]:
    """(pid, address, port) of every listening TCP socket of process ``pid`` and its descendants."""
    found = set()
    try:
        root = psutil.Process(pid)
        procs = [root, *root.children(recursive=True)]
    except psutil.NoSuchProcess:
        return found
    for p in procs:
        try:
            conns = p.net_connections(kind="inet")
        except (psutil.NoSuchProcess, psutil.AccessDenied, psutil.ZombieProcess):
            continue
        found.update((p.pid, c.laddr.ip, c.laddr.port) for c in conns if c.status == psutil.CONN_LISTEN)
    return found


def _first_bytes(address: str, port: int) -> bytes:
    """What a listener sends to a plain TCP connection that says nothing: a Dask comm in clear sends its handshake.

    Empty when it sends nothing within a second (a TLS listener waits for the client's hello, an HTTP server for
    the request) or is gone already; only a listener speaking plain Dask answers, at once.
    """
    try:
        with socket.create_connection((address, port), timeout=1.0) as sock:
            sock.settimeout(1.0)
            return sock.recv(8)
    except OSError:  # refused (the job ended), reset or timed out
        return b""


def test_cli_matrix_on_workers_listens_on_loopback_only(tmp_path: Path) -> None:
    mesh = cg.icosphere(3)
    path = cg.save_distance(tmp_path / "sphere.ply", mesh, np.zeros(mesh.n_vertices))
    out = tmp_path / "D.npy"
    env = dict(os.environ)
    env["PYTHONPATH"] = str(Path(cg.__file__).resolve().parents[1])  # the package under test, checkout or installed
    proc = subprocess.Popen(
        [sys.executable, "-m", "cvxgeodesic.cli", "matrix", str(path), "-s", "0,1,2,3,4,5", "--method", "qclp",
         "--workers", "2", "-q", "-o", str(out)],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env)
    seen: set[tuple[int, str, int]] = set()
    deadline = time.monotonic() + 300
    with ThreadPoolExecutor(8) as pool:
        probes = {}
        while proc.poll() is None and time.monotonic() < deadline:
            for pid, ip, port in _listening(proc.pid) - seen:  # each listener once, as another user would
                probes[(pid, ip, port)] = pool.submit(_first_bytes, "127.0.0.1" if ip in ("0.0.0.0", "::") else ip,
                                                      port)
                seen.add((pid, ip, port))
            time.sleep(0.05)
        if proc.poll() is None:
            proc.kill()
        spoken = {where: fut.result() for where, fut in probes.items()}
    output = proc.communicate()[0].decode(errors="replace")
    assert proc.returncode == 0, output
    assert np.load(out).shape == (6, mesh.n_vertices)
    # the sampling saw the job: the scheduler and its dashboard in the job's own process, the workers in others
    assert sum(pid == proc.pid for pid, _, _ in seen) >= 2, seen
    assert any(pid != proc.pid for pid, _, _ in seen), seen
    exposed = sorted(s for s in seen if not ipaddress.ip_address(s[1]).is_loopback)
    assert exposed == [], f"listening beyond loopback: {exposed}"
    in_clear = sorted(where for where, first in spoken.items() if first)
    assert in_clear == [], f"speaking Dask in clear to any local user: {in_clear}"


@pytest.mark.parametrize("reply, scheme", [(b"", "tcp://"), (b"abc", "")])
def test_probe_of_a_server_that_closes_before_the_handshake(reply: bytes, scheme: str) -> None:
    """A server that closes the connection before 8 bytes: the probe names it, not a bare socket error (an
    address with or without ``tcp://``)."""
    from cvxgeodesic._cluster import check_scheduler

    with socket.socket() as srv:
        srv.bind(("127.0.0.1", 0))
        srv.listen(1)

        def answer() -> None:
            conn, _ = srv.accept()
            with conn:
                conn.sendall(reply)

        with ThreadPoolExecutor(1) as pool:
            done = pool.submit(answer)
            with pytest.raises(ConnectionError, match="closed the connection without a Dask handshake"):
                check_scheduler(f"{scheme}127.0.0.1:{srv.getsockname()[1]}", timeout=30.0)
            done.result()


def test_probe_leaves_other_schemes_to_dask_and_rejects_an_address_without_a_port() -> None:
    from cvxgeodesic._cluster import check_scheduler

    assert check_scheduler("tls://127.0.0.1:1") is None  # not probed: nothing listens there
    with pytest.raises(ConnectionError, match="is not an address like tcp://SCHEDULER:8786"):
        check_scheduler("tcp://127.0.0.1")
