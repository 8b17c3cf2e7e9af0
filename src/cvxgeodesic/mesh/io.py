"""Mesh and distance files: ``load_mesh``, ``save_distance``, ``load_distance``, dispatched by extension.

The formats live in :mod:`cvxgeodesic.mesh.formats` (one module each) and one table,
:data:`~cvxgeodesic.mesh.formats.registry.FORMATS`, says which reads and writes what. This module is
the public face: the readers and writers by extension, atomic writes, and the file's numbering.
"""

from __future__ import annotations

import dataclasses
import os
import re
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from .._atomic import atomic_write, check_replaceable
from ..errors import ParameterError
from ..results import Field, GeodesicResult
from ..validation import as_field
from ..validation import check_output_path as _check_output_path
from .convert import MeshLike, as_mesh, as_trimesh
from .fileorder import file_order_mesh, file_vertices, to_file_order
from .formats import ply
from .formats._common import FieldData, check_file, file_errors, format_error
from .formats.registry import (
    DISTANCE_EXTENSIONS,
    FORMATS,
    MESH_EXTENSIONS,
    VOLUME_DISTANCE_EXTENSIONS,
    field_reader,
    property_reader,
)
from .load import load_mesh
from .trimesh import TriMesh

__all__ = [
    "as_trimesh", "check_output_path", "file_order_mesh", "load_distance", "load_distance_ply", "load_mesh",
    "load_vertex_property", "save_distance", "MESH_EXTENSIONS", "DISTANCE_EXTENSIONS",
]

_NAME_RE = re.compile(r"[A-Za-z_][A-Za-z0-9_.\-]*\Z")
_RESERVED = ("x", "y", "z", "vertex", "file_vertex")


#: What a point cloud's field is written as (readers of .vtu/.glb expect cells).
CLOUD_DISTANCE_EXTENSIONS = (".ply", ".npy", ".csv")


def save_distance(path: str | os.PathLike, mesh: MeshLike, distance: ArrayLike | GeodesicResult | Field, *,
                  name: str = "distance", file_order: bool = False, overwrite_read_only: bool = False) -> Path:
    """Write a per-vertex distance field, atomically.

    The format follows the extension (case-insensitive; the list is
    :data:`~cvxgeodesic.mesh.formats.registry.DISTANCE_EXTENSIONS`); :func:`load_distance`
    reads every one of them back:

    - ``.ply``: binary little-endian PLY; vertices with ``double`` ``x, y, z`` and a
      ``double`` property called ``name``; faces as ``property list uchar int
      vertex_indices``. open3d's tensor reader (``o3d.t.io.read_triangle_mesh``) and meshio
      (``point_data[name]``) read the field by name. trimesh (5.2) keeps custom PLY properties
      only in ``mesh.metadata["_ply_raw"]["vertex"]["data"][name]``, never in
      ``vertex_attributes`` (it does not read them back from its own PLY export either):
      write ``.glb`` for trimesh.
    - ``.npy``: the (n,) float64 array (``numpy.save``).
    - ``.csv``: header ``vertex,file_vertex,x,y,z,<name>``, one row per vertex;
      ``file_vertex`` is ``mesh.vertex_map``; infinite values are written as ``inf``.
    - ``.vtu`` / ``.vtk`` (needs meshio, ``pip install 'cvxgeodesic[io]'``): VTK
      unstructured grid with the field as point data ``name``, for ParaView.
    - ``.glb`` (needs trimesh, ``pip install 'cvxgeodesic[io]'``): binary glTF with the field
      as the custom vertex attribute ``"_" + name.upper()`` (``_DISTANCE``), which
      ``trimesh.load(path, process=False)`` puts in each geometry's ``vertex_attributes``;
      float32 (glTF has no float64), and ``inf`` is written as -1 (the format's JSON header
      cannot hold infinity).

    A field on a :class:`~cvxgeodesic.mesh.pointcloud.PointCloud` is written on its points as given (before any
    denoising), without the triangles it was solved on (a ``.ply`` then has no faces, and
    :func:`~cvxgeodesic.mesh.pointcloud_io.load_point_cloud` reads it back as a cloud); ``.vtu`` and ``.glb`` are
    refused for clouds.

    A field on a tetrahedral mesh (:class:`~cvxgeodesic.mesh.tetmesh.TetMesh`) is written as ``.vtu`` / ``.vtk``
    with the tetrahedra (ParaView opens it: slices, clips, contours), or as ``.npy``
    (:data:`~cvxgeodesic.mesh.formats.registry.VOLUME_DISTANCE_EXTENSIONS`).

    The data is written to a temporary file in the target directory which then
    replaces ``path`` (``os.replace``); if anything fails, the temporary file is
    removed and ``path`` is left as it was. A replaced file keeps its mode (and owner and
    group where the process may set them); a read-only one (no write bit for its owner) is
    refused unless ``overwrite_read_only=True``.

    Parameters
    ----------
    path : str or os.PathLike
        Output file; its directory must exist.
    mesh : TriMesh, TetMesh or tuple (V, F) or (V, T)
        The mesh the field lives on, with ``n`` vertices (anything
        :func:`~cvxgeodesic.mesh.convert.as_mesh` takes).
    distance : (n,) array_like of float, GeodesicResult or Field
        One value per vertex (``inf`` allowed, e.g. for unreachable vertices), or a result of a solve on this mesh
        (its ``distance``) or a field (its ``vertex_distance``).
    name : str, optional
        Name of the PLY property / CSV column (letters, digits, ``_``, ``.``, ``-``;
        not ``x``, ``y``, ``z``, ``vertex`` or ``file_vertex``).
    file_order : bool, default False
        Write the file's vertices and faces in the numbering of the file ``mesh`` was read
        from (``mesh.n_file_vertices`` rows, :func:`~cvxgeodesic.mesh.fileorder.to_file_order`:
        welded duplicates share a value, vertices in no face get ``inf``; the faces are the
        file's own, :func:`~cvxgeodesic.mesh.fileorder.file_order_mesh`), so the output joins
        the input file by vertex index and has its connectivity. In the CSV, ``vertex`` is then
        the mesh index (-1 for dropped vertices). A volume's file vertices in no tetrahedron are
        written at their place, with ``inf``. The command line always does this.
    overwrite_read_only : bool, default False
        Replace ``path`` even when it is read-only (it stays read-only: its mode is kept).

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    ParameterError
        If the extension is unsupported (for the mesh's kind), ``distance`` does not have shape (n,) (or is the field
        of a mesh with another vertex count),
        ``name`` is invalid, the parent directory does not exist, or ``path`` is a read-only
        file and ``overwrite_read_only`` is False.
    OSError
        If writing fails (e.g. permission denied).

    Examples
    --------
    >>> import tempfile, numpy as np, cvxgeodesic as cg
    >>> mesh = cg.icosphere(1)
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     path = cg.save_distance(f"{tmp}/d.ply", mesh, np.arange(42.0))
    ...     print(cg.load_distance(path)[:3])
    [0. 1. 2.]
    """
    p = check_output_path(path)
    check_replaceable(p, overwrite_read_only=overwrite_read_only)  # before the work of formatting the data
    fmt = FORMATS[p.suffix.lower()]
    assert fmt.write_field is not None  # check_output_path accepted only DISTANCE_EXTENSIONS
    mesh = as_mesh(mesh)
    if mesh.dim not in fmt.dims:  # every format holds surfaces: only a volume's field can be refused here
        *first, last = VOLUME_DISTANCE_EXTENSIONS
        raise ParameterError(f"{p}: a field on a tetrahedral mesh is written as {', '.join(first)} or {last}, not "
                             f"{p.suffix!r}")
    d = as_field(distance, "distance", mesh.n_vertices)[0]
    if not isinstance(name, str) or not _NAME_RE.match(name) or name in _RESERVED:
        raise ParameterError(
            f"invalid field name {name!r}: use letters, digits, '_', '.', '-' (not x, y, z, vertex, file_vertex)"
        )
    if not file_order:
        field = FieldData(mesh.V, mesh.cells, d, name, np.arange(mesh.n_vertices), mesh.vertex_map, mesh.name)
    else:
        field = FieldData(file_vertices(mesh), mesh.file_cells, to_file_order(mesh, d), name, mesh.file_index,
                          np.arange(mesh.n_file_vertices), mesh.name)
    if getattr(mesh, "cloud", None) is not None:  # a point cloud's field: its points, not the fans' triangle soup
        if p.suffix.lower() not in CLOUD_DISTANCE_EXTENSIONS:
            raise ParameterError(f"{p}: a field on a point cloud is written as {', '.join(CLOUD_DISTANCE_EXTENSIONS)} "
                                 f"(its points, no faces), not {p.suffix!r}")
        # at the points as given (a denoised cloud's moved points are where it was solved, not the user's data)
        field = dataclasses.replace(field, V=mesh.cloud.points_as_given[field.vertex], cells=field.cells[:0])
    write = fmt.write_field
    atomic_write(p, lambda fh: write(fh, field), overwrite_read_only=overwrite_read_only)
    return p


def load_distance(path: str | os.PathLike, name: str = "distance") -> np.ndarray:
    """Read a per-vertex field back from any file :func:`save_distance` writes.

    Parameters
    ----------
    path : str or os.PathLike
        A ``.ply``, ``.npy``, ``.csv``, ``.vtu``/``.vtk`` (needs meshio) or ``.glb`` (needs
        trimesh) file (any case).
    name : str, default "distance"
        The field's name, as given to :func:`save_distance`: the PLY vertex property, the CSV
        column, the VTK point data, the GLB vertex attribute ``"_" + name.upper()``. A ``.npy``
        holds one unnamed array; ``name`` is ignored there.

    Returns
    -------
    (n,) float64 ndarray
        One value per vertex of the file, in the file's order (for files the command line
        writes: the input mesh file's numbering). From a ``.glb``, the values are the file's
        float32 ones and -1 (how ``inf`` is written) comes back as ``inf``.

    Raises
    ------
    MeshFileNotFoundError
        If the file does not exist (also a ``FileNotFoundError``).
    MeshFormatError
        If the extension is unsupported, the file is empty or malformed, has no field called
        ``name`` (the message lists the fields it has), or needs trimesh/meshio that is not
        installed (the message says what to install).
    ParameterError
        If ``name`` is not a string.

    Examples
    --------
    >>> import tempfile, numpy as np, cvxgeodesic as cg
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     path = cg.save_distance(f"{tmp}/d.csv", cg.icosphere(0), np.full(12, np.inf), name="geo")
    ...     print(cg.load_distance(path, name="geo").shape)
    (12,)
    """
    if not isinstance(name, str):
        raise ParameterError(f"name must be a string, got {type(name).__name__}")
    p = Path(path)
    read = field_reader(p)
    check_file(p, "a distance file")
    with file_errors(p):
        return read(p, name)


def load_vertex_property(path: str | os.PathLike, name: str) -> np.ndarray:
    """A named per-vertex property of a mesh file (a PLY vertex property, VTK/VTU point data, a glTF attribute
    ``_NAME``), one value per vertex of the file, in its order (:func:`~cvxgeodesic.mesh.fileorder.from_file_order`
    turns it into the loaded mesh's).

    Parameters
    ----------
    path : str or os.PathLike
    name : str

    Returns
    -------
    (n_file,) float64 ndarray

    Raises
    ------
    MeshFormatError
        A format without named properties (the message lists those with), or no property ``name`` (the message
        lists the file's).
    """
    p = Path(path)
    read = property_reader(p)
    check_file(p, "a mesh file")
    with file_errors(p):
        return read(p, name)


def check_output_path(path: str | os.PathLike, extensions: tuple[str, ...] = DISTANCE_EXTENSIONS) -> Path:
    """:func:`cvxgeodesic.validation.check_output_path` with the distance-file extensions as the default."""
    return _check_output_path(path, extensions)


def load_distance_ply(path: str | os.PathLike) -> tuple[TriMesh, dict[str, np.ndarray]]:
    """Read a PLY file written by :func:`save_distance`, mesh and every field, without welding.

    Parameters
    ----------
    path : str or os.PathLike
        A PLY file (any PLY with triangle faces works).

    Returns
    -------
    mesh : TriMesh
        The mesh exactly as stored (vertex order kept, no welding; coordinates are
        the file's: float64 for files from :func:`save_distance`).
    fields : dict of str to (n,) ndarray
        Every scalar per-vertex property other than ``x``, ``y``, ``z``, as float64.

    Raises
    ------
    MeshFormatError
        If the file is missing (:class:`~cvxgeodesic.errors.MeshFileNotFoundError`) or
        malformed, or has non-triangle faces.
    """
    p = Path(path)
    with file_errors(p):
        V, idx, sizes, fields = ply.read_fields(p)
        if not np.all(sizes == 3):
            raise format_error(p, "faces must all be triangles")
        return TriMesh(V, idx.reshape(-1, 3), name=p.name), fields
