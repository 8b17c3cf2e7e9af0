"""Reading a distance field on a mesh: values at points (:func:`distance_at`) and geodesic paths
(:func:`geodesic_path`), on a surface or inside a volume.

:mod:`~cvxgeodesic.paths.descent` walks down the field cell by cell over :class:`Cells` (the walk's view of a mesh,
:mod:`~cvxgeodesic.paths.cells`); :mod:`~cvxgeodesic.paths.corridor` straightens a surface path through the corridor
of faces the walk crossed.
"""

from .cells import Cells
from .descent import distance_at, geodesic_path

__all__ = ["Cells", "distance_at", "geodesic_path"]
