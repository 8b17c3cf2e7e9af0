"""glTF, GLB, 3MF through trimesh (the ``io`` extra): meshes in; fields out as the GLB vertex attribute ``_DISTANCE``.

trimesh is imported only when such a file is read or written; without it the error names the extra to install.
"""

from __future__ import annotations

import json
import struct
from collections.abc import Callable
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np

from ...errors import MeshFormatError, ParameterError
from ._common import FieldData, RawMesh, format_error, optional_package

__all__ = ["GLB_NO_DISTANCE", "glb_attribute_name", "read_field", "read_mesh", "write_field"]

#: Value written in a ``.glb`` for a vertex without a distance (``inf``): glTF's JSON header holds each
#: accessor's min/max, and JSON has no infinity (trimesh would write ``Infinity``, which strict readers reject).
GLB_NO_DISTANCE = -1.0


def read_mesh(path: Path) -> RawMesh:
    """The triangles of a glTF, GLB or 3MF file, read by trimesh without merging or reordering.

    For a scene of several meshes, their vertices one after the other, as trimesh concatenates them.

    Raises
    ------
    MeshFormatError
        trimesh is missing (the message says what to install) or cannot read the file.
    """
    V, F = _load(path, "reading", lambda tm: (np.asarray(tm.vertices, dtype=np.float64),
                                              np.asarray(tm.faces, dtype=np.int64)), force="mesh")
    return RawMesh(V, F.ravel(), np.full(F.shape[0], 3, dtype=np.int64))


def _load(path: Path, what: str, convert: Callable[[Any], Any] = lambda loaded: loaded, **kwargs: Any) -> Any:
    """``convert(trimesh.load(path, process=False, **kwargs))`` after :func:`check_json`, every failure a
    MeshFormatError."""
    lib = optional_package("trimesh", f"{path}: {what} {path.suffix} files", MeshFormatError)
    check_json(path)
    try:
        # process=False: no merging or reordering, so indices stay the file's
        return convert(lib.load(str(path), process=False, **kwargs))
    except Exception as exc:  # anything from KeyError to trimesh's own errors
        detail = f"{type(exc).__name__}: {exc}"
        if isinstance(exc, ImportError) and path.suffix.lower() == ".3mf":  # trimesh's 3MF reader needs networkx
            detail += "; 3MF files need networkx too: pip install networkx"
        raise format_error(path, f"trimesh cannot read the file ({detail})") from None


def check_json(path: Path) -> None:
    """Refuse a ``.gltf`` or ``.glb`` whose JSON does not parse, naming the JSON problem.

    trimesh reports broken JSON as a missing file (``FileNotFoundError: model.gltf``: it then looks for the
    JSON under another name), which sends a user looking for a file that is there. 3MF (a zip) is left to trimesh.

    Raises
    ------
    MeshFormatError
        ``"<path>: not valid glTF JSON (<problem> at line L, column C)"`` (JSON nested too deeply for the parser
        included), or a GLB whose header or first chunk is not glTF's.
    """
    ext = path.suffix.lower()
    if ext not in (".gltf", ".glb"):
        return
    try:
        with path.open("rb") as fh:
            data = _glb_json_chunk(path, fh) if ext == ".glb" else fh.read()
    except OSError as exc:
        raise format_error(path, f"cannot read file ({exc.strerror or exc})") from None
    try:
        doc = json.loads(data.decode("utf-8-sig"))
    except UnicodeDecodeError as exc:
        raise format_error(path, f"not valid glTF JSON (not UTF-8 text: byte {exc.start})") from None
    except json.JSONDecodeError as exc:
        raise format_error(path, f"not valid glTF JSON ({exc.msg} at line {exc.lineno}, column {exc.colno})") from None
    except RecursionError:  # arrays or objects nested deeper than the parser's recursion (a glTF nests a few levels)
        raise format_error(path, "not valid glTF JSON (arrays or objects nested too deeply to parse)") from None
    if not isinstance(doc, dict):
        raise format_error(path, f"not valid glTF JSON (a glTF file is a JSON object, this one is a "
                                 f"{type(doc).__name__})")


def _glb_json_chunk(path: Path, fh: BinaryIO) -> bytes:
    """The JSON chunk of a GLB (only it is read): a 12-byte header (``glTF``, version, length), then the chunk's
    length and type ``JSON``."""
    head = fh.read(20)
    if len(head) < 20 or head[:4] != b"glTF":
        raise format_error(path, "not a binary glTF file (it does not start with the GLB header 'glTF')")
    version, = struct.unpack_from("<I", head, 4)
    length, kind = struct.unpack_from("<I4s", head, 12)
    data = fh.read(length) if kind == b"JSON" else b""
    if kind != b"JSON" or len(data) < length:
        raise format_error(path, f"binary glTF (version {version}) whose first chunk is not a complete JSON chunk")
    return data


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


def write_field(fh: BinaryIO, field: FieldData) -> None:
    """Binary glTF (GLB) with the field as the custom vertex attribute :func:`glb_attribute_name`.

    glTF stores 32-bit floats only, so positions and the field are rounded to float32 (use ``.ply`` for
    float64); ``inf`` (a vertex without a distance) is written as :data:`GLB_NO_DISTANCE`.

    Raises
    ------
    ParameterError
        trimesh is not installed (the message says what to install).
    """
    trimesh = optional_package("trimesh", "writing .glb files", ParameterError)
    V, F = np.asarray(field.V, dtype=np.float64), np.asarray(field.cells, dtype=np.int64)
    mesh = trimesh.Trimesh(V, F, process=False)
    values = np.where(np.isfinite(field.d), field.d, GLB_NO_DISTANCE).astype(np.float32)
    mesh.vertex_attributes[glb_attribute_name(field.name)] = values
    data = mesh.export(file_type="glb")
    if not isinstance(data, bytes):  # trimesh returns the GLB as bytes; anything else is a trimesh change
        raise TypeError(f"trimesh's GLB export returned {type(data).__name__}, not bytes")
    fh.write(data)


def read_field(path: Path, name: str) -> np.ndarray:
    """The vertex attribute :func:`glb_attribute_name` (``name``) of a one-mesh GLB, as float64.

    :data:`GLB_NO_DISTANCE` (-1) comes back as ``inf``; the values are the file's float32 ones.

    Raises
    ------
    MeshFormatError
        trimesh is missing, cannot read the file, the file holds several meshes, or the mesh has no
        such attribute (the message lists the ones it has).
    """
    scene = _load(path, "reading fields from")
    meshes = list(scene.geometry.values()) if hasattr(scene, "geometry") else [scene]
    if len(meshes) != 1:
        raise format_error(path, f"expected one mesh, the file has {len(meshes)}")
    attrs = getattr(meshes[0], "vertex_attributes", {})
    key = glb_attribute_name(name)
    if key not in attrs:
        raise format_error(path, f"no vertex attribute {key!r} (the file's: {', '.join(attrs) or 'none'})")
    values = np.asarray(attrs[key], dtype=np.float64).ravel()
    return np.where(values == GLB_NO_DISTANCE, np.inf, values)
