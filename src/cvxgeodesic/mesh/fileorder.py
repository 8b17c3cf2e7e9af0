"""The file's vertex numbering: map fields and source indices between a file and its :class:`TriMesh`.

:func:`~cvxgeodesic.mesh.io.load_mesh` welds vertices with identical positions and drops
vertices that no face uses, so the mesh's vertex ``i`` need not be the file's vertex ``i``.
The Python API always works in the mesh's numbering; :func:`to_file_order` turns a field
into the file's numbering (the command line does so for every file it writes, and reads
``--source`` as a file index through :func:`file_sources`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from ..errors import ParameterError, SourceError
from .io import as_trimesh
from .trimesh import TriMesh

__all__ = ["file_sources", "to_file_order"]


def to_file_order(mesh: TriMesh, field: ArrayLike, *, fill: float = np.inf) -> np.ndarray:
    """A per-vertex field in the numbering of the file ``mesh`` was read from.

    Parameters
    ----------
    mesh : TriMesh
        A mesh from :func:`~cvxgeodesic.mesh.io.load_mesh` (any other mesh is its own
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
    mesh = as_trimesh(mesh)
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


def file_sources(mesh: TriMesh, sources: ArrayLike) -> np.ndarray:
    """Mesh indices of source vertices given as vertex indices *of the file*.

    Parameters
    ----------
    mesh : TriMesh
        A mesh from :func:`~cvxgeodesic.mesh.io.load_mesh`.
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
