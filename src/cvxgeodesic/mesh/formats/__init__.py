"""Mesh and field file formats, one module per format; :mod:`.registry` is the table that drives them.

Every format module offers some of ``read_mesh(path) -> RawMesh`` (a polygon soup in file order,
welded and checked by :func:`~cvxgeodesic.mesh.load.load_mesh`), ``write_field(fh, field)`` (a
per-vertex field on its mesh, for :func:`~cvxgeodesic.mesh.io.save_distance`) and
``read_field(path, name) -> (n,) ndarray`` (for :func:`~cvxgeodesic.mesh.io.load_distance`).
"""
