"""The one table of file formats: it drives ``load_mesh``, ``load_point_cloud``, ``save_distance``, ``load_distance``
and the CLI's help.

Adding a format is a module in this package and a line in :data:`FORMATS`; the extension lists, the
dispatch and every command-line help text that lists formats follow. A format says which meshes it holds
(``dims``: 2 for triangle surfaces, 3 for tetrahedral volumes); one reader serves both where a file may
hold either (VTK, VTU), and ``load_mesh`` builds what the file has. A format with ``read_points`` holds point
clouds; one that holds meshes too (PLY) says which a file holds (``holds_points``: a PLY without faces).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import BinaryIO

import numpy as np

from . import csv, gltf, las, npy, obj, off, ply, stl, tetgen, via_meshio, xyz
from ._common import FieldData, RawMesh, RawPoints, format_error

__all__ = ["DISTANCE_EXTENSIONS", "FORMATS", "Format", "MESHIO_TET_EXTENSIONS", "MESH_EXTENSIONS",
           "POINT_EXTENSIONS", "PROPERTY_EXTENSIONS", "TETGEN_EXTENSIONS", "VOLUME_DISTANCE_EXTENSIONS",
           "VOLUME_EXTENSIONS", "field_formats_help", "field_reader", "is_point_file", "mesh_format",
           "mesh_formats_help", "point_formats_help", "point_reader", "property_reader"]


@dataclass(frozen=True)
class Format:
    """One file format: what reads or writes it, and the optional package it needs.

    Attributes
    ----------
    extension : str
        Lower case, with the dot (files are matched case-insensitively).
    description : str
    package : str or None
        The optional package (the ``io`` extra) that reads and writes it, None when built in.
    read_mesh : callable ``(path) -> RawMesh`` or None
        For :func:`~cvxgeodesic.mesh.load.load_mesh`: the polygons and/or tetrahedra of the file.
    write_field : callable ``(fh, FieldData) -> None`` or None
        For :func:`~cvxgeodesic.mesh.io.save_distance`: a field on a mesh of one of ``dims``.
    read_field : callable ``(path, name) -> (n,) float64 ndarray`` or None
        For :func:`~cvxgeodesic.mesh.io.load_distance`; every format with a writer has one.
    field_note : str
        What a field file of this format holds (command-line help).
    dims : tuple of int
        The simplex dimensions of the meshes it holds, read or written: 2, triangle surfaces; 3, tetrahedral
        volumes.
    read_points : callable ``(path) -> RawPoints`` or None
        For :func:`~cvxgeodesic.mesh.pointcloud_io.load_point_cloud`: the points (and normals) of a point file.
    holds_points : callable ``(path) -> bool`` or None
        For a format that holds meshes and points (``read_mesh`` and ``read_points``): whether the file at hand
        holds points (a PLY without faces); None: every file of the format with a ``read_points`` does.
    """

    extension: str
    description: str
    package: str | None = None
    read_mesh: Callable[[Path], RawMesh] | None = None
    write_field: Callable[[BinaryIO, FieldData], None] | None = None
    read_field: Callable[[Path, str], np.ndarray] | None = None
    field_note: str = ""
    dims: tuple[int, ...] = (2,)
    read_points: Callable[[Path], RawPoints] | None = None
    holds_points: Callable[[Path], bool] | None = None


#: Every format, keyed by extension; the order is the order of the extension lists and help texts.
FORMATS: dict[str, Format] = {f.extension: f for f in (
    Format(".obj", "Wavefront OBJ", read_mesh=obj.read_mesh),
    Format(".off", "OFF (ASCII)", read_mesh=off.read_mesh),
    Format(".ply", "PLY (ASCII or binary)", read_mesh=ply.read_mesh, write_field=ply.write_field,
           read_field=ply.read_field, field_note="mesh + field, float64", read_points=ply.read_points,
           holds_points=ply.holds_points),
    Format(".stl", "STL (ASCII or binary)", read_mesh=stl.read_mesh),
    Format(".npy", "NumPy array", write_field=npy.write_field, read_field=npy.read_field, field_note="field only",
           dims=(2, 3), read_points=npy.read_points),
    Format(".csv", "CSV table", write_field=csv.write_field, read_field=csv.read_field,
           field_note="vertex,file_vertex,x,y,z,distance", read_points=csv.read_points),
    Format(".glb", "binary glTF", "trimesh", gltf.read_mesh, gltf.write_field, gltf.read_field,
           field_note="vertex attribute _DISTANCE, float32"),
    Format(".gltf", "glTF", "trimesh", gltf.read_mesh),
    Format(".3mf", "3MF", "trimesh", gltf.read_mesh),
    Format(".vtk", "legacy VTK", "meshio", via_meshio.read_mesh, partial(via_meshio.write_field, ext=".vtk"),
           via_meshio.read_field, field_note="ParaView", dims=(2, 3)),
    Format(".vtu", "VTK XML unstructured grid", "meshio", via_meshio.read_mesh,
           partial(via_meshio.write_field, ext=".vtu"), via_meshio.read_field, field_note="ParaView", dims=(2, 3)),
    Format(".msh", "Gmsh", "meshio", via_meshio.read_mesh, dims=(3,)),
    Format(".mesh", "Medit", "meshio", via_meshio.read_mesh, dims=(3,)),
    Format(".inp", "Abaqus", "meshio", via_meshio.read_mesh, dims=(3,)),
    Format(".xdmf", "XDMF", "meshio", via_meshio.read_mesh, dims=(3,)),
    Format(".med", "Salome MED", "meshio", via_meshio.read_mesh, dims=(3,)),
    Format(".node", "TetGen points (and the .ele beside it)", read_mesh=tetgen.read_mesh, dims=(3,)),
    Format(".ele", "TetGen tetrahedra (and the .node beside it)", read_mesh=tetgen.read_mesh, dims=(3,)),
    Format(".xyz", "XYZ points", dims=(), read_points=xyz.read_points),
    Format(".pts", "PTS points", dims=(), read_points=xyz.read_points),
    Format(".las", "LAS (LiDAR points)", "laspy", dims=(), read_points=las.read_points),
    Format(".laz", "LAZ (compressed LAS)", "laspy", dims=(), read_points=las.read_points),
)}

#: Surface files understood by :func:`~cvxgeodesic.mesh.load.load_mesh` (compared case-insensitively).
MESH_EXTENSIONS = tuple(e for e, f in FORMATS.items() if f.read_mesh is not None and 2 in f.dims)
#: Files holding tetrahedra understood by :func:`~cvxgeodesic.mesh.load.load_mesh` (a VTK or VTU file without
#: tetrahedra is a surface).
VOLUME_EXTENSIONS = tuple(e for e, f in FORMATS.items() if f.read_mesh is not None and 3 in f.dims)
#: The volume files read through meshio, and TetGen's pair (command-line help).
MESHIO_TET_EXTENSIONS = tuple(e for e in VOLUME_EXTENSIONS if FORMATS[e].package == "meshio")
TETGEN_EXTENSIONS = tuple(e for e in VOLUME_EXTENSIONS if FORMATS[e].read_mesh is tetgen.read_mesh)
#: File extensions understood by :func:`~cvxgeodesic.mesh.io.save_distance` and
#: :func:`~cvxgeodesic.mesh.io.load_distance` (compared case-insensitively).
DISTANCE_EXTENSIONS = tuple(e for e, f in FORMATS.items() if f.write_field is not None)
#: The distance files :func:`~cvxgeodesic.mesh.io.save_distance` writes for a field on a tetrahedral mesh.
VOLUME_DISTANCE_EXTENSIONS = tuple(e for e in DISTANCE_EXTENSIONS if 3 in FORMATS[e].dims)
#: Point files understood by :func:`~cvxgeodesic.mesh.pointcloud_io.load_point_cloud` (a ``.ply`` when it has no
#: faces).
POINT_EXTENSIONS = tuple(e for e, f in FORMATS.items() if f.read_points is not None)


#: Mesh file extensions whose files carry named per-vertex properties (PLY properties, VTK point data, glTF
#: attributes ``_NAME``): read by :func:`property_reader`.
PROPERTY_EXTENSIONS = tuple(e for e, f in FORMATS.items() if f.read_mesh is not None and f.read_field is not None)


def property_reader(path: Path) -> Callable[[Path, str], np.ndarray]:
    """The reader of a named per-vertex property of a mesh file (in the file's vertex order), or a MeshFormatError
    naming the formats that have them."""
    fmt = FORMATS.get(path.suffix.lower())
    if fmt is None or fmt.read_mesh is None or fmt.read_field is None:
        raise format_error(path, f"{path.suffix or 'this file'} has no named per-vertex properties; mesh formats "
                                 f"that do: {', '.join(PROPERTY_EXTENSIONS)}")
    return fmt.read_field


def mesh_format(path: Path) -> Format:
    """The format of the mesh file ``path`` (it has a ``read_mesh``), or a MeshFormatError listing the supported
    extensions: the surfaces', then those only volumes have."""
    fmt = FORMATS.get(path.suffix.lower())
    if fmt is None or fmt.read_mesh is None:
        volumes = [e for e in VOLUME_EXTENSIONS if e not in MESH_EXTENSIONS]
        points = f"; {path.suffix} files hold points: load_point_cloud reads them" if fmt is not None else ""
        raise format_error(path, f"unsupported mesh file extension {path.suffix!r}; supported: "
                                 f"{', '.join(MESH_EXTENSIONS)} (any case), and for tetrahedra {', '.join(volumes)}"
                                 + points)
    return fmt


def point_reader(path: Path) -> Callable[[Path], RawPoints]:
    """The points reader for ``path``'s extension, or a MeshFormatError listing the point files' extensions."""
    fmt = FORMATS.get(path.suffix.lower())
    if fmt is None or fmt.read_points is None:
        raise format_error(path, f"unsupported point file extension {path.suffix!r}; supported: "
                                 f"{', '.join(POINT_EXTENSIONS)} (any case; a .ply without faces)")
    return fmt.read_points


def is_point_file(path: str | os.PathLike) -> bool:
    """Whether ``path`` names a point file: a format with ``read_points`` whose file holds points
    (``holds_points``: a PLY whose header declares no face)."""
    p = Path(path)
    fmt = FORMATS.get(p.suffix.lower())
    if fmt is None or fmt.read_points is None:
        return False
    return fmt.holds_points is None or (p.is_file() and fmt.holds_points(p))


def field_reader(path: Path) -> Callable[[Path, str], np.ndarray]:
    """The field reader for ``path``'s extension, or a MeshFormatError listing the supported ones."""
    fmt = FORMATS.get(path.suffix.lower())
    if fmt is None or fmt.read_field is None:
        raise format_error(path, f"unsupported distance file extension {path.suffix!r}; supported: "
                                 f"{', '.join(DISTANCE_EXTENSIONS)} (any case)")
    return fmt.read_field


def _grouped(extensions: tuple[str, ...], note: Callable[[Format], str]) -> str:
    """``".a, .b; .c (note) with pkg"``: the built-in formats first, then one group per optional package."""
    groups: dict[str | None, list[str]] = {}
    for ext in extensions:
        fmt = FORMATS[ext]
        groups.setdefault(fmt.package, []).append(ext + (f" ({note(fmt)})" if note(fmt) else ""))
    return "; ".join(", ".join(items) + (f" with {pkg}" if pkg else "") for pkg, items in groups.items())


def mesh_formats_help() -> str:
    """The mesh formats for command-line help: ``".obj, .off, .ply, .stl; .glb, .gltf, .3mf with trimesh; ..."``."""
    return _grouped(MESH_EXTENSIONS, lambda f: "")


def point_formats_help() -> str:
    """The point files for command-line help: ``".ply (without faces), ...; .las, .laz with laspy"``."""
    return _grouped(POINT_EXTENSIONS, lambda f: "without faces" if f.read_mesh is not None else "")


def field_formats_help() -> str:
    """The distance-file formats for command-line help, each with what it holds."""
    return _grouped(DISTANCE_EXTENSIONS, lambda f: f.field_note)
