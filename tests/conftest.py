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
