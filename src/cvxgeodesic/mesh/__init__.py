"""Mesh model, generators and file I/O."""

from .convert import as_trimesh
from .generate import cylinder, grid_plane, icosphere
from .io import load_distance, load_mesh, save_distance
from .trimesh import TriMesh

__all__ = ["TriMesh", "as_trimesh", "grid_plane", "icosphere", "cylinder", "load_distance", "load_mesh",
           "save_distance"]
