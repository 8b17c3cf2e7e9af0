"""The one table of file formats: it drives ``load_mesh``, ``save_distance``, ``load_distance`` and the CLI's help.

Adding a format is a module in this package and a line in :data:`FORMATS`; the extension lists, the
dispatch and every command-line help text that lists formats follow.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import BinaryIO

import numpy as np

from . import csv, gltf, npy, obj, off, ply, stl, vtk
from ._common import FieldData, RawMesh, format_error

__all__ = ["DISTANCE_EXTENSIONS", "FORMATS", "Format", "MESH_EXTENSIONS", "PROPERTY_EXTENSIONS", "field_formats_help",
           "field_reader", "mesh_formats_help", "mesh_reader", "property_reader"]


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
        For :func:`~cvxgeodesic.mesh.load.load_mesh`.
    write_field : callable ``(fh, FieldData) -> None`` or None
        For :func:`~cvxgeodesic.mesh.io.save_distance`.
    read_field : callable ``(path, name) -> (n,) float64 ndarray`` or None
        For :func:`~cvxgeodesic.mesh.io.load_distance`; every format with a writer has one.
    field_note : str
        What a field file of this format holds (command-line help).
    """

    extension: str
    description: str
    package: str | None = None
    read_mesh: Callable[[Path], RawMesh] | None = None
    write_field: Callable[[BinaryIO, FieldData], None] | None = None
    read_field: Callable[[Path, str], np.ndarray] | None = None
    field_note: str = ""


#: Every format, keyed by extension; the order is the order of the extension lists and help texts.
FORMATS: dict[str, Format] = {f.extension: f for f in (
    Format(".obj", "Wavefront OBJ", read_mesh=obj.read_mesh),
    Format(".off", "OFF (ASCII)", read_mesh=off.read_mesh),
    Format(".ply", "PLY (ASCII or binary)", read_mesh=ply.read_mesh, write_field=ply.write_field,
           read_field=ply.read_field, field_note="mesh + field, float64"),
    Format(".stl", "STL (ASCII or binary)", read_mesh=stl.read_mesh),
    Format(".npy", "NumPy array", write_field=npy.write_field, read_field=npy.read_field, field_note="field only"),
    Format(".csv", "CSV table", write_field=csv.write_field, read_field=csv.read_field,
           field_note="vertex,file_vertex,x,y,z,distance"),
    Format(".glb", "binary glTF", "trimesh", gltf.read_mesh, gltf.write_field, gltf.read_field,
           field_note="vertex attribute _DISTANCE, float32"),
    Format(".gltf", "glTF", "trimesh", gltf.read_mesh),
    Format(".3mf", "3MF", "trimesh", gltf.read_mesh),
    Format(".vtk", "legacy VTK", "meshio", vtk.read_mesh, partial(vtk.write_field, ext=".vtk"), vtk.read_field,
           field_note="ParaView"),
    Format(".vtu", "VTK XML unstructured grid", "meshio", vtk.read_mesh, partial(vtk.write_field, ext=".vtu"),
           vtk.read_field, field_note="ParaView"),
)}

#: File extensions understood by :func:`~cvxgeodesic.mesh.load.load_mesh` (compared case-insensitively).
MESH_EXTENSIONS = tuple(e for e, f in FORMATS.items() if f.read_mesh is not None)
#: File extensions understood by :func:`~cvxgeodesic.mesh.io.save_distance` and
#: :func:`~cvxgeodesic.mesh.io.load_distance` (compared case-insensitively).
DISTANCE_EXTENSIONS = tuple(e for e, f in FORMATS.items() if f.write_field is not None)


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


def mesh_reader(path: Path) -> Callable[[Path], RawMesh]:
    """The mesh reader for ``path``'s extension, or a MeshFormatError listing the supported ones."""
    fmt = FORMATS.get(path.suffix.lower())
    if fmt is None or fmt.read_mesh is None:
        raise format_error(path, f"unsupported mesh file extension {path.suffix!r}; supported: "
                                 f"{', '.join(MESH_EXTENSIONS)} (any case)")
    return fmt.read_mesh


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
    parts = [", ".join(items) + (f" with {pkg}" if pkg else "") for pkg, items in groups.items()]
    return "; ".join(parts)


def mesh_formats_help() -> str:
    """The mesh formats for command-line help: ``".obj, .off, .ply, .stl; .glb, .gltf, .3mf with trimesh; ..."``."""
    return _grouped(MESH_EXTENSIONS, lambda f: "")


def field_formats_help() -> str:
    """The distance-file formats for command-line help, each with what it holds."""
    return _grouped(DISTANCE_EXTENSIONS, lambda f: f.field_note)
