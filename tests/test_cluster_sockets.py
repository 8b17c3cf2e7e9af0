"""A local Dask cluster listens on loopback only: nothing of a ``--workers`` job is reachable from the network.

Dask's ``dashboard_address=":0"`` binds the scheduler's dashboard (an HTTP server that runs even without
Bokeh) to every interface; ``_cluster.open_client`` binds every socket of its cluster to 127.0.0.1.
"""

from __future__ import annotations

import ipaddress
import os
import subprocess
import sys
import time
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
    while proc.poll() is None and time.monotonic() < deadline:
        seen |= _listening(proc.pid)
        time.sleep(0.05)
    if proc.poll() is None:
        proc.kill()
    output = proc.communicate()[0].decode(errors="replace")
    assert proc.returncode == 0, output
    assert np.load(out).shape == (6, mesh.n_vertices)
    # the sampling saw the job: the scheduler and its dashboard in the job's own process, the workers in others
    assert sum(pid == proc.pid for pid, _, _ in seen) >= 2, seen
    assert any(pid != proc.pid for pid, _, _ in seen), seen
    exposed = sorted(s for s in seen if not ipaddress.ip_address(s[1]).is_loopback)
    assert exposed == [], f"listening beyond loopback: {exposed}"
