"""Shared fixtures: generated meshes (always) and ../shared/meshes (skipped when absent)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

# One thread per solver unless the caller chose otherwise: the suite's meshes are small (one thread is as fast),
# and test runs beside other jobs or in parallel then never oversubscribe the cores. Dask workers the tests
# start inherit it. Tests of the default policy remove it (tests/test_threads.py).
os.environ.setdefault("CVXGEODESIC_THREADS", "1")

SHARED_MESHES = Path(__file__).resolve().parents[1].parent / "shared" / "meshes"


def shared_mesh_path(name: str) -> Path:
    """Path of a file in ../shared/meshes, or skip the test when the folder or file is absent."""
    path = SHARED_MESHES / name
    if not path.exists():
        pytest.skip(f"{path} not available (development data, not part of a user checkout)")
    return path


def plane_points(n: int = 20, seed: int = 1):
    """(n², 3) points of a point cloud's tests: a jittered n × n grid of the unit square, rotated into a generic plane
    of 3-D."""
    import numpy as np

    rng = np.random.default_rng(seed)
    g = np.linspace(0.0, 1.0, n)
    x, y = np.meshgrid(g, g)
    P = np.c_[x.ravel(), y.ravel(), np.zeros(x.size)]
    P[:, :2] += rng.uniform(-0.2 / n, 0.2 / n, (P.shape[0], 2))
    return P @ np.linalg.qr(rng.normal(size=(3, 3)))[0].T


def sphere_points(n: int = 1500, seed: int = 2):
    """(n, 3) random points of the unit sphere (a point cloud's tests)."""
    import numpy as np

    X = np.random.default_rng(seed).normal(size=(n, 3))
    return X / np.linalg.norm(X, axis=1)[:, None]


def sphere_file_with_a_loose_vertex(tmp_path: Path):
    """icosphere(2) as OBJ with a vertex in no face first: the file's numbering is the mesh's plus one.

    Returns the mesh and the path.
    """
    import cvxgeodesic as cg

    mesh = cg.icosphere(2)
    path = tmp_path / "sphere.obj"
    lines = ["v 9 9 9"] + [f"v {x!r} {y!r} {z!r}" for x, y, z in mesh.V.tolist()]
    lines += [f"f {a + 2} {b + 2} {c + 2}" for a, b, c in mesh.F.tolist()]
    path.write_text("\n".join(lines) + "\n")
    return mesh, path


def interrupt_cli(args: list[str], ready, *, settle: float = 1.5):
    """Run ``python -m cvxgeodesic.cli ARGS`` in its own process group and press Ctrl-C once it is working.

    ``ready(stderr_bytes)`` says when the command is under way (e.g. its progress bar is up); after
    ``settle`` more seconds SIGINT goes to the whole group, as a terminal's Ctrl-C does. The package under
    test is the imported one (the checkout's src/ when it has one, else the installed one).

    Returns
    -------
    returncode : int
    stderr : str
    seconds : float
        From the signal to the process's exit.
    """
    import signal
    import subprocess
    import sys
    import threading
    import time

    import cvxgeodesic as cg

    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(Path(cg.__file__).parents[1]),
                                                       os.environ.get("PYTHONPATH", "")]))
    proc = subprocess.Popen([sys.executable, "-m", "cvxgeodesic.cli", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, env=env, start_new_session=True)
    chunks: list[bytes] = []
    reader = threading.Thread(target=lambda: chunks.extend(iter(lambda: proc.stderr.read1(4096), b"")), daemon=True)
    reader.start()
    deadline = time.time() + 60
    while time.time() < deadline and not ready(b"".join(chunks)):
        time.sleep(0.1)
    time.sleep(settle)
    t0 = time.time()
    os.killpg(proc.pid, signal.SIGINT)
    proc.wait(timeout=60)
    elapsed = time.time() - t0
    reader.join(timeout=10)
    return proc.returncode, b"".join(chunks).decode(), elapsed


@pytest.fixture
def plot_field_calls(monkeypatch) -> list[dict]:
    """The keyword arguments of every ``cvxgeodesic.plotting.plot_field`` call during the test (the picture is still
    drawn): what the CLI and compare hand to the picture."""
    import cvxgeodesic.plotting as plotting

    calls: list[dict] = []
    real = plotting.plot_field

    def spy(*args, **kwargs):
        calls.append(kwargs)
        return real(*args, **kwargs)

    monkeypatch.setattr(plotting, "plot_field", spy)
    return calls
