"""The file's vertex numbering: map fields and source indices between a file and its :class:`TriMesh`.

:func:`~cvxgeodesic.mesh.load.load_mesh` welds vertices with identical positions and drops
vertices that no face uses, so the mesh's vertex ``i`` need not be the file's vertex ``i``.
The Python API always works in the mesh's numbering; :func:`to_file_order` turns a field
into the file's numbering and :func:`file_order_mesh` gives the file's vertices and faces
(the command line does both for every file it writes, and reads ``--source`` as a file
index through :func:`file_sources`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..errors import ParameterError, SourceError
from .convert import as_mesh
from .simplex import SimplexMesh
from .trimesh import TriMesh

__all__ = ["file_order_mesh", "file_sources", "file_vertices", "from_file_order", "to_file_order"]


def to_file_order(mesh: SimplexMesh, field: ArrayLike, *, fill: float = np.inf) -> np.ndarray:
    """A per-vertex field in the numbering of the file ``mesh`` was read from.

    Parameters
    ----------
    mesh : TriMesh or TetMesh
        A mesh from :func:`~cvxgeodesic.mesh.load.load_mesh` (any other mesh is its own
        file: the field comes back unchanged, as a copy).
    field : (..., n) array_like of float
        Values per mesh vertex on the last axis, e.g. a distance field (n,) or a
        :func:`~cvxgeodesic.api.distance_matrix` (k, n).
    fill : float, default inf
        Value of file vertices that are in no face (the mesh dropped them; as
        unreachable vertices, their distance is ``inf``).

    Returns
    -------
    (..., n_file) float64 ndarray
        ``out[..., j]`` is the value of file vertex ``j``: welded duplicates share the
        value of their mesh vertex; dropped vertices get ``fill``.

    Raises
    ------
    ParameterError
        If the last axis of ``field`` is not ``mesh.n_vertices`` long.

    Examples
    --------
    >>> import cvxgeodesic as cg
    >>> mesh = cg.icosphere(1)
    >>> cg.to_file_order(mesh, cg.geodesic_distance(mesh, 0, method="dijkstra")).shape
    (42,)
    """
    mesh = as_mesh(mesh)  # a volume has a file numbering too (its vertices in no tetrahedron dropped)
    try:
        values = np.asarray(field, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ParameterError(f"field must be a numeric array of shape (..., {mesh.n_vertices}) ({exc})") from None
    if values.ndim == 0 or values.shape[-1] != mesh.n_vertices:
        raise ParameterError(
            f"field must have {mesh.n_vertices} values (one per mesh vertex) on its last axis, got shape {values.shape}"
        )
    idx = mesh.file_index
    out = np.full((*values.shape[:-1], idx.size), float(fill))
    keep = idx >= 0
    out[..., keep] = values[..., idx[keep]]
    return out


def from_file_order(mesh: SimplexMesh, values: ArrayLike, name: str) -> tuple[np.ndarray, str | None]:
    """A per-vertex field given in the file's numbering, in the mesh's (the inverse of :func:`to_file_order`).

    Parameters
    ----------
    mesh : TriMesh or TetMesh
        A mesh from :func:`~cvxgeodesic.mesh.load.load_mesh`.
    values : (n_file,) float array_like
        One value per vertex of the file.
    name : str
        What the values are (for messages).

    Returns
    -------
    (n,) float64 ndarray
        File vertices welded into one mesh vertex give it their mean; vertices in no face are dropped.
    note : str or None
        Says so when welded vertices had different values.

    Raises
    ------
    ParameterError
        ``values`` is not one number per file vertex.
    """
    arr = np.asarray(values, dtype=np.float64)
    idx = mesh.file_index
    if arr.shape != (idx.size,):
        raise ParameterError(f"{name} must have one value per vertex of {mesh.name} ({idx.size}), got shape "
                             f"{arr.shape}")
    keep = idx >= 0
    total = np.bincount(idx[keep], weights=arr[keep], minlength=mesh.n_vertices)
    count = np.bincount(idx[keep], minlength=mesh.n_vertices)
    out = np.divide(total, count, out=np.ones(mesh.n_vertices), where=count > 0)
    spread = np.abs(arr[keep] - out[idx[keep]])
    with np.errstate(invalid="ignore"):
        differ = spread > 1e-12 * np.maximum(np.abs(out[idx[keep]]), 1e-300)
    note = None
    if differ.any():
        j = int(np.flatnonzero(keep)[np.flatnonzero(differ)[0]])
        note = (f"{name}: vertices welded into one have different values (first: file vertex {j}); each mesh vertex "
                "takes their mean")
    return out, note


def file_sources(mesh: SimplexMesh, sources: ArrayLike) -> np.ndarray:
    """Mesh indices of source vertices given as vertex indices *of the file*.

    Parameters
    ----------
    mesh : TriMesh or TetMesh
        A mesh from :func:`~cvxgeodesic.mesh.load.load_mesh`.
    sources : int or (k,) array_like of int
        File vertex indices in ``[0, mesh.n_file_vertices)``.

    Returns
    -------
    (k',) int64 ndarray
        The mesh indices, in the given order; file vertices welded into the same mesh
        vertex appear once.

    Raises
    ------
    SourceError
        A source is not an integer, is given twice, is out of the file's range, or is a file vertex in
        no face (the mesh dropped it, so it has no distance field).
    """
    from ..validation import validate_sources

    # the same checks and messages as the Python API, against the file's vertex count
    arr = validate_sources(sources, mesh.n_file_vertices)
    idx = mesh.file_index[arr]
    if (idx < 0).any():
        bad = int(arr[np.flatnonzero(idx < 0)[0]])
        raise SourceError(f"source vertex {bad} of {mesh.name} is in no face, so it has no distance field; "
                          "choose a vertex of a triangle")
    _, first = np.unique(idx, return_index=True)
    return idx[np.sort(first)]


def file_order_mesh(mesh: TriMesh) -> TriMesh:
    """The mesh with the file's vertices, faces, numbering and vertex count (for writing files).

    Parameters
    ----------
    mesh : TriMesh
        A mesh from :func:`~cvxgeodesic.mesh.load.load_mesh` (any other mesh is its own file).

    Returns
    -------
    TriMesh
        ``mesh.n_file_vertices`` vertices: welded duplicates at their mesh vertex's position
        (the same, as welding joins identical positions), dropped vertices at their file
        position; the faces are ``mesh.file_cells``, the file's own triangles (polygons
        fan-triangulated), including those the loader dropped as duplicates or degenerate
        after welding. ``mesh`` itself when the file needs nothing else.

    Examples
    --------
    >>> import cvxgeodesic as cg
    >>> from cvxgeodesic.mesh.fileorder import file_order_mesh
    >>> mesh = cg.icosphere(1)
    >>> file_order_mesh(mesh) is mesh
    True
    """
    idx = mesh.file_index
    faces = mesh.file_cells
    if idx.size == mesh.n_vertices and np.array_equal(idx, np.arange(idx.size)) and np.array_equal(faces, mesh.F):
        return mesh
    return TriMesh(file_vertices(mesh), faces, name=mesh.name)


def file_vertices(mesh: SimplexMesh) -> np.ndarray:
    """(n_file, 3) float: the file's vertex positions, welded duplicates at their mesh vertex (the same position),
    dropped vertices at their own (at the origin when the mesh does not know them)."""
    idx = mesh.file_index
    keep = idx >= 0
    V = np.empty((idx.size, 3))
    V[keep] = mesh.V[idx[keep]]
    V[~keep] = mesh.dropped_vertices
    if not np.all(np.isfinite(V[~keep])):  # positions unknown (file_index given without them): put them at the origin
        V[~keep] = 0.0
    return V
