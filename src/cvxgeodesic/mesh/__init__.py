"""Mesh model, generators and file I/O."""

from .generate import cylinder, grid_plane, icosphere
from .io import as_trimesh, load_mesh, save_distance
from .trimesh import TriMesh

__all__ = ["TriMesh", "as_trimesh", "grid_plane", "icosphere", "cylinder", "load_mesh", "save_distance"]
