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



def _interrupted_early(signum: int, frame: object) -> None:
    """Ctrl-C in the command's process before :func:`cvxgeodesic.cli.main` installs its handler: the command's line
    and exit code, no traceback (nothing is written yet; :mod:`cvxgeodesic._signals`)."""
    import os

    os.write(2, b"cvxgeodesic: interrupted\n")
    os._exit(130)


_interrupted_early.cvxgeodesic_early = True  # type: ignore[attr-defined]  # _signals.EARLY_MARK


def _install_early() -> None:
    """Install :func:`_interrupted_early` in the command's process only: the console script ``cvxgeodesic`` or
    ``python -m cvxgeodesic.cli`` (``sys.orig_argv``: while ``-m`` imports the package, ``sys.argv[0]`` is
    ``"-m"``). Defined here, not imported, and with the builtin ``_signal``: every module imported before it
    is a moment where Ctrl-C still gives a traceback. A SIGINT the process ignores stays ignored."""
    import _signal
    import os
    import sys

    orig = list(getattr(sys, "orig_argv", ()))
    i = orig.index("cvxgeodesic.cli") if "cvxgeodesic.cli" in orig else 0
    command = (i > 0 and orig[i - 1] == "-m") or (
        bool(sys.argv) and os.path.basename(sys.argv[0]) in ("cvxgeodesic", "cvxgeodesic.exe", "cvxgeodesic-script.py"))
    if command and _signal.getsignal(_signal.SIGINT) is _signal.default_int_handler:
        try:
            _signal.signal(_signal.SIGINT, _interrupted_early)
        except ValueError:  # not the main thread
            pass


_install_early()  # first

from typing import TYPE_CHECKING  # noqa: E402

from . import _threads  # noqa: E402, F401  (it sets OpenMP's wait policy before a library loads the runtime)

# The names below are imported on first use (PEP 562): ``import cvxgeodesic`` and ``import cvxgeodesic.cli`` load
# no NumPy, SciPy or Numba, so the command line's Ctrl-C handling is in place before the heavy imports start.
# Type checkers and IDEs read the same names from this block.
if TYPE_CHECKING:
    from .api import (
        ALL_METHODS,
        BASELINE_METHODS,
        GeodesicResult,
        GeodesicSolver,
        Method,
        SolveInfo,
        SolverName,
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
        OutputError,
        ParameterError,
        SolverError,
        SourceError,
    )
    from .mesh import TriMesh, cylinder, grid_plane, icosphere
    from .mesh.fileorder import to_file_order
    from .mesh.io import load_distance, load_mesh, save_distance
    from .mesh.locate import SurfacePoint, VolumePoint, surface_point, volume_point
    from .mesh.pointcloud import PointCloud
    from .mesh.pointcloud_io import load_point_cloud
    from .mesh.tet_generate import tet_ball, tet_box, tet_l_prism
    from .mesh.tetmesh import TetMesh
    from .mesh.tetrahedralize import tetrahedralize
    from .paths import distance_at, geodesic_path
    from .plotting import plot_field
    from .problems.formulations import FORMULATIONS, smoothness_weight
    from .problems.ridge_rounding import round_ridge
    from .results import Field
    from .sources import BoundaryFaces, SurfaceCurve
    from .viewer import show

__version__ = "0.1.0"

__all__ = [
    "ALL_METHODS", "BASELINE_METHODS", "FORMULATIONS", "CvxGeodesicError", "DegenerateFacesWarning",
    "IndefiniteEnergyWarning", "GeodesicResult", "GeodesicSolver",
    "MeshError", "MeshFileNotFoundError", "MeshFormatError", "MeshRepairWarning",
    "NonManifoldError", "OutputError", "ParameterError", "SolveInfo", "SolverError", "SourceError",
    "TriMesh", "cylinder", "distance_matrix", "geodesic_distance", "grid_plane", "icosphere", "load_distance",
    "load_mesh", "plot_field", "round_ridge", "save_distance", "smoothness_weight", "to_file_order", "SurfaceCurve",
    "SurfacePoint",
    "surface_point", "distance_at", "geodesic_path", "show", "Method", "SolverName",
    "BoundaryFaces", "TetMesh", "VolumePoint", "tet_ball", "tet_box", "tet_l_prism", "tetrahedralize", "volume_point",
    "PointCloud", "load_point_cloud",
    "Field",
]


#: public name -> the module that defines it (relative to the package)
_LAZY = {
    **dict.fromkeys(("ALL_METHODS", "BASELINE_METHODS", "GeodesicResult", "GeodesicSolver", "SolveInfo",
                     "distance_matrix", "geodesic_distance", "Method", "SolverName"), ".api"),
    **dict.fromkeys(("CvxGeodesicError", "DegenerateFacesWarning", "IndefiniteEnergyWarning", "MeshError",
                     "MeshFileNotFoundError", "MeshFormatError", "MeshRepairWarning", "NonManifoldError",
                     "OutputError", "ParameterError", "SolverError", "SourceError"), ".errors"),
    **dict.fromkeys(("FORMULATIONS", "smoothness_weight"), ".problems.formulations"),
    "round_ridge": ".problems.ridge_rounding",
    **dict.fromkeys(("TriMesh", "cylinder", "grid_plane", "icosphere"), ".mesh"),
    "to_file_order": ".mesh.fileorder",
    **dict.fromkeys(("load_distance", "load_mesh", "save_distance"), ".mesh.io"),
    **dict.fromkeys(("tet_ball", "tet_box", "tet_l_prism"), ".mesh.tet_generate"),
    "TetMesh": ".mesh.tetmesh",
    "tetrahedralize": ".mesh.tetrahedralize",
    "PointCloud": ".mesh.pointcloud",
    "load_point_cloud": ".mesh.pointcloud_io",
    **dict.fromkeys(("distance_at", "geodesic_path"), ".paths"),
    "plot_field": ".plotting",  # matplotlib costs ~0.3 s to import
    **dict.fromkeys(("SurfacePoint", "VolumePoint", "surface_point", "volume_point"), ".mesh.locate"),
    **dict.fromkeys(("BoundaryFaces", "SurfaceCurve"), ".sources"),
    "show": ".viewer",  # polyscope is an optional extra: imported when show() runs
    "Field": ".results",
}


def __getattr__(name: str) -> object:
    import importlib
    import importlib.util

    module = _LAZY.get(name)
    if module is None:
        # a submodule not imported yet (cvxgeodesic.api, .mesh, ...): the eager package had them all loaded
        if not name.startswith("_") and importlib.util.find_spec(f"{__name__}.{name}") is not None:
            return importlib.import_module(f"{__name__}.{name}")
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(module, __name__), name)
    globals()[name] = value  # once: later lookups do not come here
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
