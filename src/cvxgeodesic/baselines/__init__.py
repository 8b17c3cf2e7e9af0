"""Baseline geodesic-distance methods behind one interface, on triangle and tetrahedral meshes.

Every class takes a mesh in its constructor (all per-mesh precomputation,
timed as ``setup_time``) and has ``solve(sources) -> (d, info)``; see
:class:`~cvxgeodesic.baselines.base.BaselineSolver`. Which method takes which
mesh, medium and source is in :mod:`cvxgeodesic.capabilities`.

- ``dijkstra``: ``scipy.sparse.csgraph.dijkstra`` on the edge graph; any surface or volume; several
  sources natively (exactly the minimum of single-source runs).
- ``fmm``: ``potpourri3d.MeshFastMarchingDistanceSolver``; manifold surfaces only; several
  sources natively (fronts marched together, slightly below the minimum of single runs).
- ``heat``: on a surface ``potpourri3d.MeshHeatMethodDistanceSolver`` (``t_coef = 1``; any mesh:
  intrinsic tufted cover); inside a volume the library's own P1 stiffness and mass; several sources
  natively (diffused together, not the minimum of single runs).
- ``exact``: ``pygeodesic.geodesic.PyGeodesicAlgorithmExact`` (MMP); manifold surfaces only;
  several sources natively (exactly the minimum of single-source runs).

Vertices not connected to any source get ``np.inf`` with every method.
"""

from .base import BaselineSolver, ComponentwiseSolver, nonmanifold_vertices, reachable_mask, require_manifold
from .dijkstra import DijkstraBaseline, VolumeDijkstraBaseline
from .exact import ExactBaseline
from .fmm import FastMarchingBaseline
from .heat import DEFAULT_T_COEF, HeatBaseline, VolumeHeatBaseline
from .points import graph_distance

BASELINES: dict[str, type[BaselineSolver]] = {
    cls.name: cls for cls in (DijkstraBaseline, FastMarchingBaseline, HeatBaseline, ExactBaseline)
}
"""Baseline classes by method name: ``"dijkstra"``, ``"fmm"``, ``"heat"``, ``"exact"``."""

__all__ = [
    "BASELINES", "BaselineSolver", "ComponentwiseSolver", "DEFAULT_T_COEF", "DijkstraBaseline", "ExactBaseline",
    "FastMarchingBaseline", "HeatBaseline", "VolumeDijkstraBaseline", "VolumeHeatBaseline",
    "graph_distance", "nonmanifold_vertices", "reachable_mask",
    "require_manifold",
]
