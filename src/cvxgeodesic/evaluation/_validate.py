"""The evaluation functions' mesh type check (private); every other check is :mod:`cvxgeodesic.validation`'s."""

from __future__ import annotations

from ..mesh.simplex import SimplexMesh
from ..mesh.trimesh import TriMesh
from ..validation import check_type

__all__ = ["check_mesh"]


def check_mesh(mesh: object, *, volumes: bool = False) -> TriMesh:
    """``mesh`` if it is a :class:`TriMesh` (with ``volumes``, any simplex mesh: a TetMesh too), else a TypeError
    naming it."""
    if volumes:
        return check_type(mesh, "mesh", SimplexMesh, "a TriMesh or a TetMesh")
    return check_type(mesh, "mesh", TriMesh, "a TriMesh")
