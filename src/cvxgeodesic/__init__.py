"""cvxgeodesic: geodesic distance fields on triangle meshes by convex optimization.

Quick use::

    import cvxgeodesic as cg
    mesh = cg.load_mesh("bunny.obj")
    d = cg.geodesic_distance(mesh, sources=0)            # QCQP-Hessian, m = 1
    res = cg.GeodesicSolver(mesh, method="qclp").solve([0, 17])
    D = cg.distance_matrix(mesh, [0, 17, 99])          # (3, n): one row per source vertex
    res.distance, res.info.iterations, res.info.solve_time

Inside a solid (tetrahedra; ``docs/volumes.md``)::

    part = cg.load_mesh("part.msh")                      # a TetMesh
    d = cg.geodesic_distance(part, 0, method="qclp", order=2)
    wall = cg.geodesic_distance(part, "boundary", method="qclp")
"""

from . import _threads  # noqa: F401  (first: it sets OpenMP's wait policy before a library loads the runtime)
from .api import (
    ALL_METHODS,
    BASELINE_METHODS,
    GeodesicResult,
    GeodesicSolver,
    SolveInfo,
    distance_matrix,
    geodesic_distance,
)
from .errors import (
    CvxGeodesicError,
    DegenerateFacesWarning,
    IndefiniteEnergyWarning,
    MeshError,
    MeshFileNotFoundError,
    MeshFormatError,
    MeshRepairWarning,
    NonManifoldError,
    ParameterError,
    SolverError,
    SourceError,
)
from .formulations import FORMULATIONS, smoothness_weight
from .mesh import TriMesh, cylinder, grid_plane, icosphere
from .mesh.fileorder import to_file_order
from .mesh.io import load_distance, load_mesh, save_distance
from .mesh.tet_generate import tet_ball, tet_box, tet_l_prism
from .mesh.tet_locate import VolumePoint, volume_point
from .mesh.tetmesh import TetMesh
from .mesh.tetrahedralize import tetrahedralize
from .paths import distance_at, geodesic_path
from .sources import SurfaceCurve, SurfacePoint, surface_point
from .sources_tet import BoundaryFaces

__version__ = "0.1.0"

__all__ = [
    "ALL_METHODS", "BASELINE_METHODS", "FORMULATIONS", "CvxGeodesicError", "DegenerateFacesWarning",
    "IndefiniteEnergyWarning", "GeodesicResult", "GeodesicSolver",
    "MeshError", "MeshFileNotFoundError", "MeshFormatError", "MeshRepairWarning",
    "NonManifoldError", "ParameterError", "SolveInfo", "SolverError", "SourceError",
    "TriMesh", "cylinder", "distance_matrix", "geodesic_distance", "grid_plane", "icosphere", "load_distance",
    "load_mesh", "plot_field", "save_distance", "smoothness_weight", "to_file_order", "SurfaceCurve", "SurfacePoint",
    "surface_point", "distance_at", "geodesic_path", "show",
    "BoundaryFaces", "TetMesh", "VolumePoint", "tet_ball", "tet_box", "tet_l_prism", "tetrahedralize", "volume_point",
]


def __getattr__(name: str) -> object:
    # plot_field needs matplotlib, which costs ~0.3 s to import: only on first use
    if name == "plot_field":
        from .plotting import plot_field

        return plot_field
    if name == "show":  # polyscope is an optional extra: imported when show() runs
        from .viewer import show

        return show
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
