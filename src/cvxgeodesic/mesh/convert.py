"""``as_trimesh``: the meshes of other libraries (and file paths) as a :class:`TriMesh`, by duck typing; ``as_mesh``:
the same, or a :class:`~cvxgeodesic.mesh.tetmesh.TetMesh` for tetrahedra."""

from __future__ import annotations

import os
from typing import Any, TypeAlias, overload

import numpy as np

from ..errors import MeshError
from .simplex import MeshT, SimplexMesh
from .tetmesh import TetMesh
from .trimesh import TriMesh

__all__ = ["MeshLike", "as_mesh", "as_trimesh"]

#: What the API edge takes as a mesh and :func:`as_mesh` converts: a :class:`~cvxgeodesic.mesh.simplex.SimplexMesh`,
#: a ``(V, F)`` or ``(V, T)`` pair, a file path, or a mesh or point cloud of trimesh, open3d or meshio. Those are
#: recognised by duck typing (no common base class), so to a type checker this is ``Any``: a function taking it
#: converts it with :func:`as_mesh` before use (``tools/architecture_counts.py`` lists these parameters apart).
MeshLike: TypeAlias = Any


def _is_tet_pair(mesh: MeshLike) -> bool:
    """A ``(V, T)`` pair whose second array has four columns."""
    if not (isinstance(mesh, tuple | list) and len(mesh) == 2):
        return False
    try:
        return np.ndim(mesh[1]) == 2 and np.shape(mesh[1])[1] == 4
    except ValueError:  # ragged
        return False


@overload
def as_mesh(mesh: MeshT, name: str = "mesh") -> MeshT: ...
@overload
def as_mesh(mesh: MeshLike, name: str = "mesh") -> TriMesh | TetMesh: ...


def as_mesh(mesh: MeshLike, name: str = "mesh") -> SimplexMesh:
    """``mesh`` as a :class:`TetMesh` when it holds tetrahedra, else as :func:`as_trimesh` takes it.

    Any :class:`~cvxgeodesic.mesh.simplex.SimplexMesh` (a ``TriMesh``, a ``TetMesh``, a mesh of another domain) is
    returned as it is.

    Tetrahedra: a :class:`TetMesh`, a ``(V, T)`` pair with a 4-column ``T``, a file that holds tetrahedra
    (:func:`~cvxgeodesic.mesh.load.load_mesh`), a ``meshio.Mesh`` with ``tetra`` cells (``tetra10``: their
    corners).

    Examples
    --------
    >>> import numpy as np
    >>> as_mesh((np.eye(4, 3), [[0, 1, 2, 3]]))
    TetMesh(name='mesh', n_vertices=4, n_tets=1)
    """
    if isinstance(mesh, SimplexMesh):
        return mesh
    if _is_tet_pair(mesh):
        return TetMesh(mesh[0], mesh[1], name=name)
    cloud = _as_cloud(mesh)
    if cloud is not None:  # a point cloud or point file: the triangle soup of its fans (mesh/pointcloud.py)
        return cloud.mesh
    if isinstance(mesh, str | os.PathLike):
        from .load import load_mesh

        return load_mesh(mesh)
    cells = getattr(mesh, "cells_dict", None) if hasattr(mesh, "points") else None
    if isinstance(cells, dict) and ("tetra" in cells or "tetra10" in cells):
        T = np.vstack([np.asarray(cells[k])[:, :4] for k in ("tetra", "tetra10") if k in cells])
        label = getattr(mesh, "name", None)
        return TetMesh(np.asarray(mesh.points)[:, :3], T, name=label if isinstance(label, str) and label else name)
    return as_trimesh(mesh, name)


def as_trimesh(mesh: MeshLike, name: str = "mesh") -> TriMesh:
    """Return ``mesh`` as a :class:`TriMesh`, accepting the meshes other libraries use.

    Accepted, by duck typing (none of these libraries is imported or required):

    - a :class:`TriMesh` (returned as is);
    - a ``(V, F)`` tuple or list of arrays;
    - a ``str`` or :class:`os.PathLike`: read with :func:`~cvxgeodesic.mesh.load.load_mesh`;
    - ``trimesh.Trimesh`` (anything with ``.vertices`` and ``.faces``);
    - open3d's legacy ``open3d.geometry.TriangleMesh`` (``.vertices`` and ``.triangles``, converted
      with ``np.asarray``);
    - open3d's tensor ``open3d.t.geometry.TriangleMesh`` (``.vertex["positions"]`` and
      ``.triangle["indices"]`` tensors, copied to the CPU and converted with ``.numpy()``);
    - ``meshio.Mesh`` (``.points`` and ``.cells_dict["triangle"]``; other cell types are ignored);
    - a :class:`~cvxgeodesic.mesh.pointcloud.PointCloud`, a ``trimesh.PointCloud``, an
      ``open3d.geometry.PointCloud`` or a point file (``.xyz``, ``.pts``, ``.csv``, ``.npy``, a PLY without
      faces): the cloud's :class:`~cvxgeodesic.mesh.pointcloud.CloudMesh` (its points, in their order).

    The vertex order of the object is kept (no welding): indices mean the same in both.

    Parameters
    ----------
    mesh : object
        One of the above.
    name : str
        Label for messages (a file's base name for paths; the object's ``name``
        attribute, if it is a non-empty string, for the others).

    Returns
    -------
    TriMesh

    Raises
    ------
    TypeError
        If ``mesh`` is none of these (the message names its type with its module).
    MeshError
        If the arrays are invalid, or a ``meshio.Mesh`` has no triangle cells.

    Examples
    --------
    >>> import numpy as np
    >>> from cvxgeodesic.mesh.convert import as_trimesh
    >>> as_trimesh((np.eye(3), [[0, 1, 2]]))
    TriMesh(name='mesh', n_vertices=3, n_faces=1)
    """
    if isinstance(mesh, TriMesh):
        return mesh
    cloud = _as_cloud(mesh)
    if cloud is not None:  # a point cloud: the triangle soup of its local fans (mesh/pointcloud.py)
        return cloud.mesh
    if isinstance(mesh, str | os.PathLike):
        from .load import load_mesh

        loaded = load_mesh(mesh)
        if isinstance(loaded, TetMesh):
            raise MeshError(f"{loaded.name} holds tetrahedra, not a triangle surface: GeodesicSolver, "
                            "geodesic_distance and distance_matrix take it as a volume; its surface is "
                            "mesh.boundary_mesh()")
        return loaded
    if isinstance(mesh, TetMesh) or _is_tet_pair(mesh):
        raise MeshError("a tetrahedral mesh is not a triangle surface: GeodesicSolver, geodesic_distance and "
                        "distance_matrix take it as a volume; its surface is TetMesh.boundary_mesh()")
    if isinstance(mesh, tuple | list) and len(mesh) == 2:
        return TriMesh(mesh[0], mesh[1], name=name)
    label = getattr(mesh, "name", None)
    label = label if isinstance(label, str) and label else name
    if hasattr(mesh, "vertices") and hasattr(mesh, "faces"):  # trimesh.Trimesh
        return TriMesh(np.asarray(mesh.vertices), np.asarray(mesh.faces), name=label)
    if hasattr(mesh, "vertices") and hasattr(mesh, "triangles"):  # open3d.geometry.TriangleMesh
        return TriMesh(np.asarray(mesh.vertices), np.asarray(mesh.triangles), name=label)
    if hasattr(mesh, "vertex") and hasattr(mesh, "triangle"):  # open3d.t.geometry.TriangleMesh
        return TriMesh(_o3d_tensor(mesh.vertex, "positions", label), _o3d_tensor(mesh.triangle, "indices", label),
                       name=label)
    if hasattr(mesh, "points") and hasattr(mesh, "cells_dict"):  # meshio.Mesh
        cells = mesh.cells_dict
        if "triangle" not in cells:
            raise MeshError(f"{label}: the meshio.Mesh has no 'triangle' cells (cell types: {', '.join(cells)})")
        return TriMesh(np.asarray(mesh.points)[:, :3], np.asarray(cells["triangle"]), name=label)
    kind = type(mesh)
    qualified = kind.__qualname__ if kind.__module__ == "builtins" else f"{kind.__module__}.{kind.__qualname__}"
    raise TypeError(
        "mesh must be a TriMesh, a (V, F) tuple, a file path, a trimesh.Trimesh, an open3d.geometry.TriangleMesh "
        "or open3d.t.geometry.TriangleMesh, or a meshio.Mesh (something with vertices and faces, vertices and "
        f"triangles, vertex and triangle, or points and cells_dict), got {qualified}"
    )


def _as_cloud(obj: Any) -> Any:
    """``obj`` as a :class:`~cvxgeodesic.mesh.pointcloud.PointCloud` when it is one, or a trimesh or open3d point
    cloud, or a point file (:func:`~cvxgeodesic.mesh.formats.registry.is_point_file`); else None."""
    from .pointcloud import PointCloud, is_point_cloud_object

    if isinstance(obj, PointCloud):
        return obj
    if is_point_cloud_object(obj):
        return PointCloud.from_object(obj, name=getattr(obj, "name", None) or None)
    if isinstance(obj, str | os.PathLike):
        from .formats.registry import is_point_file
        from .pointcloud_io import load_point_cloud

        if is_point_file(obj):
            return load_point_cloud(obj)
    return None


def _o3d_tensor(attributes: Any, key: str, label: str) -> np.ndarray:
    """``attributes[key]`` of an open3d tensor mesh (a ``TensorMap``) as a numpy array, on the CPU."""
    try:
        tensor = attributes[key]
    except (KeyError, TypeError, IndexError):
        tensor = getattr(attributes, key, None)
    if tensor is None:
        raise MeshError(f"{label}: the open3d tensor mesh has no {key!r} attribute")
    if hasattr(tensor, "cpu"):  # a tensor on a CUDA device: numpy() works on the CPU only
        tensor = tensor.cpu()
    return np.asarray(tensor.numpy() if hasattr(tensor, "numpy") else tensor)
