"""VTK (legacy ``.vtk``) and VTU (XML ``.vtu``) through meshio (the ``io`` extra): meshes in, fields out as point data.

meshio is imported only when such a file is read or written; without it the error names the extra to install.
"""

from __future__ import annotations

import contextlib
import io
import tempfile
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np

from ...errors import MeshFormatError, ParameterError
from ._common import FieldData, RawMesh, format_error, optional_package
from ._limits import check_limits

__all__ = ["read_field", "read_mesh", "write_field"]


def _read(path: Path, what: str) -> Any:
    """``meshio.read(path)``, every failure a MeshFormatError."""
    lib = optional_package("meshio", f"{path}: {what} {path.suffix} files", MeshFormatError)
    check_limits(path)  # header counts and compressed arrays within the file's size: meshio allocates what they say
    try:
        # meshio prints its own error and calls sys.exit(1) on files it cannot parse
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            return lib.read(str(path))
    except (Exception, SystemExit) as exc:  # anything from KeyError to their own ReadError, and meshio's exit
        detail = f"{type(exc).__name__}: {exc}" if not isinstance(exc, SystemExit) else "not a valid file"
        raise format_error(path, f"meshio cannot read the file ({detail})") from None


def read_mesh(path: Path) -> RawMesh:
    """The triangle and quad cells of a VTK/VTU file (other cell types are ignored; 2-D points get z = 0).

    Raises
    ------
    MeshFormatError
        meshio is missing (the message says what to install), cannot read the file, or the file
        has no triangles or quads.
    """
    mm = _read(path, "reading")
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
    return RawMesh(V, np.concatenate(parts), np.concatenate(sizes))


def write_field(fh: BinaryIO, field: FieldData, ext: str) -> None:
    """VTU (XML, binary; ``ext=".vtu"``) or legacy VTK (binary; ``".vtk"``) with the field as point data ``field.name``.

    Raises
    ------
    ParameterError
        meshio is not installed (the message says what to install).
    """
    meshio = optional_package("meshio", f"writing {ext} files", ParameterError)
    mesh = meshio.Mesh(np.asarray(field.V, dtype=np.float64), [("triangle", np.asarray(field.F, dtype=np.int64))],
                       point_data={field.name: np.asarray(field.d, dtype=np.float64)})
    # meshio writes to paths only: write into a private temporary folder, then copy into ``fh``
    with tempfile.TemporaryDirectory(prefix="cvxgeodesic-") as tmp:
        out = Path(tmp) / f"field{ext}"
        mesh.write(out, file_format="vtu" if ext == ".vtu" else "vtk")
        fh.write(out.read_bytes())


def read_field(path: Path, name: str) -> np.ndarray:
    """The point data ``name`` as an (n,) float64 array.

    Raises
    ------
    MeshFormatError
        meshio is missing or cannot read the file, or the file has no such scalar point data
        (the message lists what it has).
    """
    mm = _read(path, "reading fields from")
    data = mm.point_data
    if name not in data:
        raise format_error(path, f"no point data {name!r} (the file's: {', '.join(data) or 'none'})")
    values = np.asarray(data[name], dtype=np.float64)
    if values.ndim == 2 and values.shape[1] == 1:
        values = values[:, 0]
    if values.ndim != 1:
        raise format_error(path, f"point data {name!r} has shape {values.shape}, not one value per vertex")
    return values
