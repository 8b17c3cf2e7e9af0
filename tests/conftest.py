"""Shared fixtures: generated meshes (always) and ../shared/meshes (skipped when absent)."""

from __future__ import annotations

from pathlib import Path

import pytest

SHARED_MESHES = Path(__file__).resolve().parents[1].parent / "shared" / "meshes"


def shared_mesh_path(name: str) -> Path:
    """Path of a file in ../shared/meshes, or skip the test when the folder or file is absent."""
    path = SHARED_MESHES / name
    if not path.exists():
        pytest.skip(f"{path} not available (development data, not part of a user checkout)")
    return path
