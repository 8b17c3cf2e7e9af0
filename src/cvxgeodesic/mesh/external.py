"""Mesh formats read and written through optional libraries: trimesh (glTF, GLB, 3MF) and meshio (VTK, VTU).

Neither library is a dependency of cvxgeodesic: ``pip install 'cvxgeodesic[io]'`` installs
both. Each is imported only when a file of its formats is read or written; without it the
error names the package to install.
"""

from __future__ import annotations

import contextlib
import importlib
import io
import tempfile
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np

from ..errors import MeshFormatError, ParameterError

__all__ = ["EXTERNAL_MESH_EXTENSIONS", "EXTERNAL_DISTANCE_EXTENSIONS", "read_external", "write_external",
           "write_meshio", "write_glb", "glb_attribute_name"]

#: Mesh files read through trimesh (key ``"trimesh"``) or meshio (``"meshio"``).
_READERS = {".glb": "trimesh", ".gltf": "trimesh", ".3mf": "trimesh", ".vtk": "meshio", ".vtu": "meshio"}
EXTERNAL_MESH_EXTENSIONS = tuple(_READERS)
#: Distance files written through meshio (``.vtu``, ``.vtk``: ParaView reads both) or trimesh (``.glb``: the
#: field as a custom glTF vertex attribute, which ``trimesh.load`` puts in ``vertex_attributes``).
_WRITERS = {".vtu": "meshio", ".vtk": "meshio", ".glb": "trimesh"}
EXTERNAL_DISTANCE_EXTENSIONS = tuple(_WRITERS)
#: Value written in a ``.glb`` for a vertex without a distance (``inf``): glTF's JSON header holds each
#: accessor's min/max, and JSON has no infinity (trimesh would write ``Infinity``, which strict readers reject).
GLB_NO_DISTANCE = -1.0

_HINT = "pip install 'cvxgeodesic[io]' (or pip install {pkg})"


def _optional_package(pkg: str, needed_for: str, error: type[Exception]) -> Any:
    """The optional package ``pkg``, or ``error("<needed_for> needs the optional package <pkg>: <hint>")``."""
    try:
        return importlib.import_module(pkg)
    except ImportError:
        raise error(f"{needed_for} needs the optional package {pkg}: " + _HINT.format(pkg=pkg)) from None


def read_external(path: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Read a glTF/GLB/3MF (trimesh) or VTK/VTU (meshio) file as a polygon soup.

    Parameters
    ----------
    path : pathlib.Path
        An existing file whose lower-case suffix is in :data:`EXTERNAL_MESH_EXTENSIONS`.

    Returns
    -------
    V : (n, 3) float64 ndarray
        Vertex positions in the file's order (for a glTF scene of several meshes, the
        meshes' vertices one after the other, as trimesh concatenates them).
    idx : (k,) int64 ndarray
        Concatenated polygon vertex indices.
    sizes : (p,) int64 ndarray
        Vertices per polygon (3 for triangles, 4 for meshio quads).

    Raises
    ------
    MeshFormatError
        The library is missing (the message says what to install), cannot read the
        file, or the file has no triangles.
    """
    ext = path.suffix.lower()
    pkg = _READERS[ext]
    lib = _optional_package(pkg, f"{path}: reading {path.suffix} files", MeshFormatError)
    try:
        if pkg == "trimesh":
            # process=False: no merging or reordering, so indices stay the file's
            tm = lib.load(str(path), force="mesh", process=False)
            V = np.asarray(tm.vertices, dtype=np.float64)
            F = np.asarray(tm.faces, dtype=np.int64)
            return V, F.ravel(), np.full(F.shape[0], 3, dtype=np.int64)
        # meshio prints its own error and calls sys.exit(1) on files it cannot parse
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            mm = lib.read(str(path))
    except MeshFormatError:
        raise
    except (Exception, SystemExit) as exc:  # anything from KeyError to their own ReadError, and meshio's exit
        detail = f"{type(exc).__name__}: {exc}" if not isinstance(exc, SystemExit) else "not a valid file"
        if isinstance(exc, ImportError) and ext == ".3mf":  # trimesh's 3MF reader needs networkx
            detail += "; 3MF files need networkx too: pip install networkx"
        raise MeshFormatError(f"{path}: {pkg} cannot read the file ({detail})") from None
    V = np.asarray(mm.points, dtype=np.float64)
    if V.ndim == 2 and V.shape[1] == 2:
        V = np.column_stack([V, np.zeros(V.shape[0])])
    parts, sizes = [], []
    for block in mm.cells:
        if block.type in ("triangle", "quad"):
            data = np.asarray(block.data, dtype=np.int64)
            parts.append(data.ravel())
            sizes.append(np.full(data.shape[0], data.shape[1], dtype=np.int64))
    if not parts:
        types = ", ".join(sorted({b.type for b in mm.cells})) or "none"
        raise MeshFormatError(f"{path}: no triangle or quad cells (cell types: {types})")
    return V, np.concatenate(parts), np.concatenate(sizes)


def write_meshio(fh: BinaryIO, V: np.ndarray, F: np.ndarray, d: np.ndarray, name: str, ext: str) -> None:
    """Write a VTU (XML, binary) or legacy VTK (binary) file with the field as point data ``name``.

    Parameters
    ----------
    fh : binary file object
    V : (n, 3) float ndarray
    F : (m, 3) int ndarray
    d : (n,) float ndarray
    name : str
    ext : {".vtu", ".vtk"}

    Raises
    ------
    ParameterError
        meshio is not installed (the message says what to install).
    """
    meshio = _optional_package("meshio", f"writing {ext} files", ParameterError)
    mesh = meshio.Mesh(np.asarray(V, dtype=np.float64), [("triangle", np.asarray(F, dtype=np.int64))],
                       point_data={name: np.asarray(d, dtype=np.float64)})
    # meshio writes to paths only: write into a private temporary folder, then copy into ``fh``
    with tempfile.TemporaryDirectory(prefix="cvxgeodesic-") as tmp:
        out = Path(tmp) / f"field{ext}"
        mesh.write(out, file_format="vtu" if ext == ".vtu" else "vtk")
        fh.write(out.read_bytes())


def write_external(fh: BinaryIO, V: np.ndarray, F: np.ndarray, d: np.ndarray, name: str, ext: str) -> None:
    """Write a distance file in a format of :data:`EXTERNAL_DISTANCE_EXTENSIONS` (dispatch by ``ext``).

    Parameters
    ----------
    fh : binary file object
    V : (n, 3) float ndarray
    F : (m, 3) int ndarray
    d : (n,) float ndarray
    name : str
    ext : {".vtu", ".vtk", ".glb"}
    """
    if _WRITERS[ext] == "trimesh":
        write_glb(fh, V, F, d, name)
    else:
        write_meshio(fh, V, F, d, name, ext)


def glb_attribute_name(name: str) -> str:
    """The glTF vertex attribute a field called ``name`` is stored as: ``"_" + name.upper()``.

    glTF 2.0 requires application-specific attribute semantics to start with an underscore, and writes
    them in capitals by convention (``_TEMPERATURE`` in the specification); ``"distance"`` becomes
    ``"_DISTANCE"``.

    Parameters
    ----------
    name : str

    Returns
    -------
    str
    """
    return "_" + name.upper().replace(".", "_").replace("-", "_")


def write_glb(fh: BinaryIO, V: np.ndarray, F: np.ndarray, d: np.ndarray, name: str) -> None:
    """Write a binary glTF (GLB) file with the field as the custom vertex attribute :func:`glb_attribute_name`.

    glTF stores 32-bit floats only, so positions and the field are rounded to float32 (use ``.ply`` for
    float64); ``inf`` (a vertex without a distance) is written as :data:`GLB_NO_DISTANCE`. trimesh reads
    the field back as ``trimesh.load(path).geometry[...].vertex_attributes["_DISTANCE"]``.

    Parameters
    ----------
    fh : binary file object
    V : (n, 3) float ndarray
    F : (m, 3) int ndarray
    d : (n,) float ndarray
    name : str

    Raises
    ------
    ParameterError
        trimesh is not installed (the message says what to install).
    """
    trimesh = _optional_package("trimesh", "writing .glb files", ParameterError)
    mesh = trimesh.Trimesh(np.asarray(V, dtype=np.float64), np.asarray(F, dtype=np.int64), process=False)
    values = np.where(np.isfinite(d), d, GLB_NO_DISTANCE).astype(np.float32)
    mesh.vertex_attributes[glb_attribute_name(name)] = values
    data = mesh.export(file_type="glb")
    if not isinstance(data, bytes):  # trimesh returns the GLB as bytes; anything else is a trimesh change
        raise TypeError(f"trimesh's GLB export returned {type(data).__name__}, not bytes")
    fh.write(data)
