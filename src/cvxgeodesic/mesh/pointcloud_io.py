"""``load_point_cloud``: a point file, read through the format registry, as a
:class:`~cvxgeodesic.mesh.pointcloud.PointCloud`.

The point files are the formats of :data:`~cvxgeodesic.mesh.formats.registry.FORMATS` with a ``read_points``
(:data:`~cvxgeodesic.mesh.formats.registry.POINT_EXTENSIONS`); ``as_mesh`` takes their paths wherever a mesh is
taken (:func:`~cvxgeodesic.mesh.formats.registry.is_point_file` decides: a PLY with faces is a mesh, one without
faces a cloud). ``load_mesh`` keeps reading meshes only.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from .formats._common import check_file, file_errors
from .formats.registry import point_reader
from .pointcloud import PointCloud

__all__ = ["load_point_cloud"]


def load_point_cloud(path: str | os.PathLike, **kwargs: Any) -> PointCloud:
    """Read a point file into a :class:`~cvxgeodesic.mesh.pointcloud.PointCloud`.

    Parameters
    ----------
    path : str or os.PathLike
        ``.xyz`` / ``.pts`` (whitespace-separated ``x y z`` per line, more columns allowed: columns 4–6 are normals
        when there are exactly six; a first line that is a point count, as ``.pts`` files often have, is skipped),
        ``.csv`` (comma-separated, an optional header line; columns ``nx, ny, nz`` in the header are normals),
        ``.npy`` (an (n, 3) or (n, 6) array: points, or points and normals), ``.ply`` without faces (``nx, ny, nz``
        vertex properties are normals), ``.las`` / ``.laz`` with laspy (the ``io`` extra; extra dimensions
        ``nx, ny, nz`` are normals).
    **kwargs
        Passed to :class:`PointCloud` (``neighbours=``, ``triangles=``, ``outliers=``, ``denoise=``).

    Returns
    -------
    PointCloud
        Named after the file's base name.

    Raises
    ------
    MeshError
        The file is unreadable (a :class:`~cvxgeodesic.errors.MeshFormatError`; a missing one:
        :class:`~cvxgeodesic.errors.MeshFileNotFoundError`), a line is not numbers (the message names the line), the
        array has the wrong shape, a PLY has faces (read it with ``load_mesh``), or the points fail
        :class:`PointCloud`'s checks (the message names the file and the point).
    """
    p = Path(path)
    read_points = point_reader(p)
    check_file(p, "a point file")
    with file_errors(p):
        raw = read_points(p)
    kwargs.setdefault("name", p.name)
    return PointCloud(raw.P, raw.normals, **kwargs)
