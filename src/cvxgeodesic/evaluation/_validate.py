"""The evaluation functions' checks: :mod:`cvxgeodesic.validation`, plus the mesh type check (private)."""

from __future__ import annotations

from ..mesh.simplex import SimplexMesh
from ..mesh.trimesh import TriMesh
from ..validation import as_vertex_field as vertex_field
from ..validation import check_type, vertex_indices, vertex_mask

__all__ = ["check_mesh", "vertex_field", "vertex_indices", "vertex_mask"]


def check_mesh(mesh: object, name: str = "mesh", *, volumes: bool = False) -> TriMesh:
    """``mesh`` if it is a :class:`TriMesh` (with ``volumes``, any simplex mesh: a TetMesh too), else a TypeError
    naming ``name``."""
    if volumes:
        return check_type(mesh, name, SimplexMesh, "a TriMesh or a TetMesh")
    return check_type(mesh, name, TriMesh, "a TriMesh")
