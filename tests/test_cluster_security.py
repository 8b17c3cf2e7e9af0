"""A local cluster (``batch``, ``matrix --workers N``, ``distance_matrix(workers=N)``) runs code for its own run only.

A Dask scheduler, worker or nanny on ``tcp://`` runs any function a client submits, and a loopback port is
open to every user of the machine: another local user could connect and run code as the caller. The local
cluster of ``_cluster.open_client`` speaks mutual TLS with a certificate made for the run: these tests are
that other user, connecting without it.
"""

from __future__ import annotations

import gc
import os
import socket
import ssl
import sys
import urllib.error
import urllib.request
from concurrent.futures import ThreadPoolExecutor
from contextlib import ExitStack
from urllib.parse import urlsplit

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic._cluster import DASHBOARD_VARIABLE, LOCAL_HOST, open_client
from cvxgeodesic.batch import run_batch
from cvxgeodesic.errors import ParameterError

distributed = pytest.importorskip("distributed")
pytest.importorskip("cryptography")

# Every refused connection below ends at once on a TLS listener (handshake refused or reset); the waits are
# upper bounds that only a listener speaking plain Dask would use up: short, so the test stays quick.
PROBE_S = 2.0


@pytest.fixture(scope="module")
def local_run():
    """The client and local cluster of one run, as ``batch``/``matrix --workers 2`` open them."""
    with ExitStack() as stack:
        client, cluster = open_client(stack, None, 2, what="test")
        yield client, cluster


def _addresses(client, cluster) -> dict[str, str]:
    """The listening Dask addresses of the run: scheduler, each worker and each nanny."""
    info = client.scheduler_info()
    found = {"scheduler": cluster.scheduler_address}
    for i, (addr, w) in enumerate(info["workers"].items()):
        found[f"worker {i}"] = addr
        if w.get("nanny"):
            found[f"nanny {i}"] = w["nanny"]
    return found


def _host_port(address: str) -> tuple[str, int]:
    parts = urlsplit(address)
    assert parts.hostname is not None and parts.port is not None, address
    return parts.hostname, parts.port


def _plain_tcp_first_bytes(address: str) -> bytes:
    """What a listener sends to a plain TCP connection that says nothing (a Dask comm sends its handshake)."""
    with socket.create_connection(_host_port(address), timeout=PROBE_S) as sock:
        sock.settimeout(PROBE_S)
        try:
            return sock.recv(8)
        except (TimeoutError, ConnectionError):
            return b""


def _tls_without_certificate_first_bytes(address: str) -> bytes:
    """What a listener sends after a TLS handshake from a client that has no certificate (and checks none)."""
    ctx = ssl.SSLContext(ssl.PROTOCOL_TLS_CLIENT)
    ctx.check_hostname = False
    ctx.verify_mode = ssl.CERT_NONE
    with socket.create_connection(_host_port(address), timeout=PROBE_S) as raw:
        try:
            with ctx.wrap_socket(raw) as sock:
                sock.settimeout(PROBE_S)
                return sock.recv(8)  # TLS 1.3: the server's refusal of the missing certificate arrives here
        except (ssl.SSLError, TimeoutError, ConnectionError):
            return b""


def test_every_listener_of_the_local_cluster_is_tls_on_loopback(local_run):
    client, cluster = local_run
    addresses = _addresses(client, cluster)
    assert {"scheduler", "worker 0", "nanny 0"} <= set(addresses), addresses
    for role, address in addresses.items():
        assert address.startswith(f"tls://{LOCAL_HOST}:"), (role, address)
    # the run's own client holds the credentials: its tasks run
    assert client.submit(os.getpid, pure=False).result() != os.getpid()


def test_clients_without_the_run_certificate_are_refused(local_run):
    client, cluster = local_run
    port = _host_port(cluster.scheduler_address)[1]
    attempts = {
        "tcp://": (f"tcp://{LOCAL_HOST}:{port}", {}),
        "tls:// without certificates": (f"tls://{LOCAL_HOST}:{port}", {}),
        "tls:// with another certificate": (f"tls://{LOCAL_HOST}:{port}",
                                           {"security": distributed.security.Security.temporary()}),
    }
    for what, (address, kwargs) in attempts.items():
        with pytest.raises((OSError, TypeError)):  # refused (TypeError: Dask's client has no TLS context)
            with distributed.Client(address, timeout=f"{PROBE_S}s", **kwargs) as intruder:
                intruder.submit(os.getuid, pure=False).result(timeout=PROBE_S)
                pytest.fail(f"a client over {what} ran code on the run's cluster")
        # The refused client is half built and sits in a reference cycle: its __del__ closes its loop runner, and
        # run by a garbage collection that happens to fall inside the next Client's loop start (which holds the
        # runner's lock) it waits for that lock forever. Seen twice on 2026-12-03 (CI hung here). Collect now.
        gc.collect()
    assert client.submit(sum, [1, 2], pure=False).result() == 3  # the run goes on


def test_no_listener_speaks_dask_to_a_stranger(local_run):
    """Scheduler, worker and nanny: neither plain TCP nor TLS without the certificate gets a Dask handshake."""
    addresses = _addresses(*local_run)
    # at once: a TLS listener waits out each plain probe silently, PROBE_S per listener one after the other
    with ThreadPoolExecutor(len(addresses)) as pool:
        plain = dict(zip(addresses, pool.map(_plain_tcp_first_bytes, addresses.values()), strict=True))
        tls = dict(zip(addresses, pool.map(_tls_without_certificate_first_bytes, addresses.values()), strict=True))
    for role, address in addresses.items():
        assert plain[role] == b"", f"{role} at {address} speaks Dask over plain TCP"
        assert tls[role] == b"", f"{role} at {address} speaks Dask over TLS to a client without the run's certificate"


def test_batch_and_rows_run_on_the_tls_cluster(local_run, tmp_path):
    """The run's client drives its workers over TLS: a batch of two meshes and a distance matrix."""
    client, _ = local_run
    a, b = cg.icosphere(1), cg.grid_plane(5, 5)
    paths = [cg.save_distance(tmp_path / "a.ply", a, np.zeros(a.n_vertices)),
             cg.save_distance(tmp_path / "b.ply", b, np.zeros(b.n_vertices))]
    rows = run_batch(paths, [0], tmp_path / "out", method="qclp", scheduler=client, progress=False)
    assert [r["status"] for r in rows] == ["ok", "ok"], rows
    sphere = cg.icosphere(2)
    D = cg.distance_matrix(sphere, [0, 5, 9], method="qclp", scheduler=client)
    # the same solves as in-process; thread counts may change the last digits (docs/performance.md)
    np.testing.assert_allclose(D, cg.distance_matrix(sphere, [0, 5, 9], method="qclp"), rtol=1e-7, atol=1e-9)


def test_without_cryptography_the_error_names_it(monkeypatch):
    monkeypatch.setitem(sys.modules, "cryptography", None)  # makes `import cryptography` fail
    with ExitStack() as stack, pytest.raises(ImportError, match=r"pip install cryptography"):
        open_client(stack, None, 1)


def _http_status(port: int, path: str) -> int:
    """The HTTP status of ``GET path`` on 127.0.0.1:port (404 included)."""
    try:
        with urllib.request.urlopen(f"http://{LOCAL_HOST}:{port}{path}", timeout=10) as reply:
            return int(reply.status)
    except urllib.error.HTTPError as exc:
        return int(exc.code)


#: Pages of Dask's HTTP servers: the dashboard, the scheduler's info pages (``/info/logs/<address>.html`` makes the
#: scheduler connect to that address and log the failure into the job's stderr: issue 41), health and metrics.
PAGES = ("/status", "/info/main/workers.html", f"/info/logs/tls://{LOCAL_HOST}:1.html", "/health", "/metrics",
         "/statics/")


def test_the_local_cluster_has_no_dashboard_and_no_pages(local_run):
    """Dask starts an HTTP server in the scheduler and each worker whatever the dashboard; without
    CVXGEODESIC_DASHBOARD=1, every page of theirs is 404 (a local user reached all of them)."""
    client, cluster = local_run
    assert cluster.scheduler_spec["options"]["dashboard"] is False
    ports = {"scheduler": client.scheduler_info()["services"]["dashboard"]}
    ports.update(client.run(lambda dask_worker: dask_worker.http_server._sockets and
                            next(iter(dask_worker.http_server._sockets.values())).getsockname()[1]))
    assert len(ports) >= 3, ports  # the scheduler and two workers
    for who, port in ports.items():
        assert {path: _http_status(port, path) for path in PAGES} == dict.fromkeys(PAGES, 404), who


def test_the_dashboard_on_request_is_on_loopback(monkeypatch, capsys):
    monkeypatch.setenv(DASHBOARD_VARIABLE, "1")
    with ExitStack() as stack:
        client, cluster = open_client(stack, None, 1, what="test")
        link = f"http://{LOCAL_HOST}:{client.scheduler_info()['services']['dashboard']}/status"
        assert cluster.dashboard_link == link and _http_status(int(urlsplit(link).port or 0), "/status") == 200
    assert f"cvxgeodesic: Dask dashboard at {link} (CVXGEODESIC_DASHBOARD=1)" in capsys.readouterr().err
    monkeypatch.setenv(DASHBOARD_VARIABLE, "yes")
    with ExitStack() as stack, pytest.raises(ParameterError, match="CVXGEODESIC_DASHBOARD must be 1 .* got 'yes'"):
        open_client(stack, None, 1)
