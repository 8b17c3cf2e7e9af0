"""The formats read and written through meshio (the ``io`` extra): VTK (legacy ``.vtk``), VTU (XML ``.vtu``), Gmsh
``.msh``, Medit ``.mesh``, Abaqus ``.inp``, XDMF, MED. Meshes in (triangles, quads and tetrahedra), fields out
as point data (VTK, VTU).

meshio is imported only when such a file is read or written; without it the error names the extra to install.
"""

from __future__ import annotations

import contextlib
import io
import tempfile
import warnings
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np

from ...errors import MeshFormatError, ParameterError
from ._common import FieldData, RawMesh, format_error, optional_package
from ._limits import check_limits

__all__ = ["read_field", "read_mesh", "write_field"]

#: meshio's cell types of tetrahedra; ``tetra10`` (quadratic) ones are read as their 4 corners.
_TETS = ("tetra", "tetra10")
#: meshio's cell types of faces, read as polygons.
_FACES = ("triangle", "quad")
#: meshio's name of each kind of cell written: a surface's triangles, a volume's tetrahedra.
_CELL_TYPE = {3: "triangle", 4: "tetra"}


def _read(path: Path, what: str) -> Any:
    """``meshio.read(path)``, every failure a MeshFormatError."""
    lib = optional_package("meshio", f"{path}: {what} {path.suffix} files", MeshFormatError)
    check_limits(path)  # header counts and compressed arrays within the file's size: meshio allocates what they say
    try:
        # meshio prints its own error and calls sys.exit(1) on files it cannot parse, and warns about what it skips
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()), \
                warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return lib.read(str(path))
    except (Exception, SystemExit) as exc:  # anything from KeyError to their own ReadError, and meshio's exit
        detail = f"{type(exc).__name__}: {exc}" if not isinstance(exc, SystemExit) else "not a valid file"
        raise format_error(path, f"meshio cannot read the file ({detail})") from None


def read_mesh(path: Path) -> RawMesh:
    """The triangles, quads and tetrahedra of a file meshio reads; the other cells are only counted.

    2-D points get z = 0 in a file without tetrahedra.

    Raises
    ------
    MeshFormatError
        meshio is missing (the message says what to install) or cannot read the file, or the file has
        tetrahedra and its points are not 3-D.
    """
    mm = _read(path, "reading")
    V = np.asarray(mm.points, dtype=np.float64)
    other: dict[str, int] = {}
    faces, sizes, tets, notes = [], [], [], []
    for block in mm.cells:
        if block.type not in _TETS:
            other[block.type] = other.get(block.type, 0) + len(block.data)
        if block.type in _FACES:
            data = np.asarray(block.data, dtype=np.int64)
            faces.append(data.ravel())
            sizes.append(np.full(data.shape[0], data.shape[1], dtype=np.int64))
        elif block.type in _TETS:
            tets.append(np.asarray(block.data, dtype=np.int64)[:, :4])
            if block.type == "tetra10":
                notes.append(f"{path.name}: {len(block.data)} 10-node (quadratic) tetrahedra: their 4 corners are "
                             "used")
    if tets and (V.ndim != 2 or V.shape[1] != 3):
        raise MeshFormatError(f"{path}: points must be 3-D for a tetrahedral mesh, got shape {V.shape}")
    if V.ndim == 2 and V.shape[1] == 2:
        V = np.column_stack([V, np.zeros(V.shape[0])])
    idx = np.concatenate(faces) if faces else np.zeros(0, dtype=np.int64)
    n_sides = np.concatenate(sizes) if sizes else np.zeros(0, dtype=np.int64)
    return RawMesh(V, idx, n_sides, tets=np.vstack(tets) if tets else None, other_cells=other,
                   notes=notes)


def write_field(fh: BinaryIO, field: FieldData, ext: str) -> None:
    """VTU (XML, binary; ``ext=".vtu"``) or legacy VTK (binary; ``".vtk"``): the triangles or tetrahedra, with the
    field as point data ``field.name`` (ParaView opens it: slices, clips, contours of a volume).

    Raises
    ------
    ParameterError
        meshio is not installed (the message says what to install).
    """
    meshio = optional_package("meshio", f"writing {ext} files", ParameterError)
    cells = np.asarray(field.cells, dtype=np.int64)
    mesh = meshio.Mesh(np.asarray(field.V, dtype=np.float64), [(_CELL_TYPE[cells.shape[1]], cells)],
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
