"""Interactive viewer (polyscope): the distance field with isolines and its sources; a click re-solves.

polyscope is an optional extra (``pip install 'cvxgeodesic[viewer]'``) and is imported only when
:func:`show` runs. ``show(..., screenshot="out.png")`` renders one frame off-screen (polyscope's EGL
backend when there is no display) and returns without opening a window: tests and headless use.
"""

from __future__ import annotations

import importlib
import os
import time
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from ._atomic import check_replaceable, output_set
from .errors import ParameterError, SourceError
from .mesh.convert import MeshLike, as_mesh
from .mesh.simplex import SimplexMesh
from .mesh.tet_slice import plane_frame
from .plotting import isoline_segments
from .results import Field, GeodesicResult
from .sources import resolve_sources
from .validation import as_field, as_points, as_vertex_field, check_output_path

if TYPE_CHECKING:
    from .api import Method

__all__ = ["show", "show_volume"]

INSTALL_HINT = "pip install 'cvxgeodesic[viewer]' (or pip install polyscope)"
MESH_NAME = "surface"
#: a point cloud's structure (``Domain.drawn_as == "points"``)
POINTS_NAME = "points"
#: a cloud's point radius per mean edge length of its triangles: gaps between neighbours, where isolines show
POINT_RADIUS = 0.3
FIELD_NAME = "geodesic distance"
SOURCES_NAME = "sources"
VOLUME_NAME = "volume"
ISOLINES_NAME = "isolines"
#: isoline tube radius, and source sphere radius, per bounding-box diagonal
ISOLINE_RADIUS = 0.0012
SOURCE_RADIUS = 0.012
#: isolines per field range: the same density as plot_field's default of 20
N_ISOLINES = 20


def _polyscope() -> Any:
    try:
        import polyscope
    except ImportError:
        raise ImportError("the viewer (cvxgeodesic view, cvxgeodesic.show) needs the optional package polyscope: "
                          f"{INSTALL_HINT}") from None
    return polyscope


def _init(ps: Any, headless: bool) -> None:
    """Start polyscope once per process (it cannot be restarted with another backend)."""
    if getattr(_init, "done", False):
        return
    ps.set_program_name("cvxgeodesic")
    ps.set_verbosity(0)  # its backend notes go to stdout, among a command's output
    ps.set_allow_headless_backends(True)
    # "auto" tries GLFW first and logs an X11 error when there is no display: go straight to EGL then
    ps.init("openGL3_egl" if headless else "auto")
    # Dear ImGui would save its window layout to ./imgui.ini at exit, into whatever folder this runs in
    psim: Any = importlib.import_module("polyscope.imgui")
    psim.GetIO().IniFilename = ""
    _init.done = True  # type: ignore[attr-defined]


def _source_positions(mesh: SimplexMesh, source_set: Any, vertices: np.ndarray) -> np.ndarray:
    """(k, 3) positions of the source marks on a surface or in a solid: vertices (and a solid's source faces'
    vertices), points, and the ends of curve pieces."""
    if source_set is None:
        return mesh.V[np.asarray(vertices, dtype=np.int64)]
    return np.concatenate([mesh.V[source_set.fixed_vertices(mesh)], source_set.point_positions(mesh),
                           *source_set.segment_ends(mesh)], axis=0)


def _given_marks(mesh: SimplexMesh, distance: np.ndarray, sources: Any) -> np.ndarray:
    """(k, 3) marks of a given field: its ``sources`` resolved, or the vertices where it is 0."""
    if sources is None:
        return mesh.V[np.flatnonzero(distance == 0)]
    ss = resolve_sources(mesh, sources)
    return _source_positions(mesh, None if ss.vertex_only else ss, ss.vertices)


def _shown(distance: np.ndarray) -> tuple[np.ndarray, float]:
    """The field as polyscope colours it, and its top: it cannot colour inf/NaN, so unreachable vertices get the
    top of the range."""
    finite = np.isfinite(distance)
    top = float(distance[finite].max()) if finite.any() else 1.0
    return np.where(finite, distance, top), top


def _add_marks(ps: Any, marks: np.ndarray, diag: float) -> None:
    cloud = ps.register_point_cloud(SOURCES_NAME, marks.reshape(-1, 3), color=(0.9, 0.05, 0.05))
    cloud.set_radius(SOURCE_RADIUS * diag, relative=False)


class _Viewer:
    """The polyscope scene of one mesh: field, isolines, source marks; ``pick`` re-solves from a vertex."""

    def __init__(self, ps: Any, mesh: SimplexMesh, *, method: Method, solver_kwargs: dict, isolines: bool) -> None:
        self.ps = ps
        self.mesh = mesh
        self.method = method
        self.solver_kwargs = solver_kwargs
        self.isolines = isolines
        self._solver: Any = None  # built on the first re-solve: per-mesh work done once
        self._last_selection: tuple | None = None
        self.message = "click a vertex to re-solve from it"
        self.distance: np.ndarray | None = None
        self.name, self.surface = self._register(ps, mesh)
        diag = float(mesh.bbox_diagonal)
        self._diag = diag if np.isfinite(diag) and diag > 0 else 1.0

    @staticmethod
    def _register(ps: Any, mesh: SimplexMesh) -> tuple[str, Any]:
        """The structure that shows the field, by the mesh's domain (``Domain.drawn_as``): a point cloud's points,
        else the surface's triangles, clickable at vertices."""
        from .capabilities import DOMAINS

        if DOMAINS[mesh.domain].drawn_as == "points":
            cloud = ps.register_point_cloud(POINTS_NAME, mesh.V, color=(0.8, 0.8, 0.8))
            cloud.set_radius(POINT_RADIUS * float(mesh.mean_edge_length), relative=False)
            return POINTS_NAME, cloud
        surface = ps.register_surface_mesh(MESH_NAME, mesh.V, mesh.cells, smooth_shade=True, color=(0.8, 0.8, 0.8))
        surface.set_selection_mode("vertices_only")
        return MESH_NAME, surface

    def solver(self) -> Any:
        if self._solver is None:
            from .api import GeodesicSolver

            self._solver = GeodesicSolver(self.mesh, self.method, **self.solver_kwargs)
        return self._solver

    def set_field(self, distance: np.ndarray, marks: np.ndarray) -> None:
        """Show ``distance`` ((n,) float) on the surface and ``marks`` ((k, 3) float) as red spheres."""
        d = np.asarray(distance, dtype=np.float64)
        shown, top = _shown(d)  # unreachable vertices at the top of the range, and no isoline there
        # polyscope 2.6's own isolines are bands a third of the period wide whatever the thickness
        # option (and their on/off state persists per quantity name): keep them off, and draw thin tubes
        # along marching-triangles isolines instead, the levels plot_field would draw
        self.surface.add_scalar_quantity(FIELD_NAME, shown, enabled=True, cmap="viridis", isolines_enabled=False)
        if self.ps.has_curve_network(ISOLINES_NAME):
            self.ps.remove_curve_network(ISOLINES_NAME)
        if self.isolines and top > float(shown.min()):
            levels = np.linspace(float(shown.min()), top, N_ISOLINES + 1)[1:-1]
            seg = isoline_segments(self.mesh, np.where(np.isfinite(d), d, np.inf), levels)
            if len(seg):
                edges = np.arange(2 * len(seg)).reshape(-1, 2)
                lines = self.ps.register_curve_network(ISOLINES_NAME, seg.reshape(-1, 3), edges,
                                                       color=(0.05, 0.05, 0.05))
                lines.set_radius(ISOLINE_RADIUS * self._diag, relative=False)
        self.distance = d
        _add_marks(self.ps, marks, self._diag)

    def solve(self, sources: Any) -> np.ndarray:
        t0 = time.perf_counter()
        res = self.solver().solve(sources)
        self.set_field(res.distance, _source_positions(self.mesh, res.source_set, res.sources))
        self.message = (f"{res.info.method}: sources {res.sources.tolist() if res.source_set is None else 'set'}, "
                        f"{time.perf_counter() - t0:.2f} s")
        return res.distance

    def pick(self, result: Any) -> bool:
        """Re-solve from the vertex of a polyscope ``PickResult`` on the surface (or from the point of a cloud); False
        if it is none."""
        data = getattr(result, "structure_data", {}) or {}
        # a point cloud's pick has only the index: every pick of it is a point
        if not (getattr(result, "is_hit", False) and getattr(result, "structure_name", None) == self.name
                and data.get("element_type", "vertex") == "vertex"):
            return False
        try:
            self.solve([int(data["index"])])
        except SourceError as exc:  # a cloud's outlier (in no triangle): the field stays, the message says why
            self.message = str(exc)
        return True

    def callback(self) -> None:
        """Per-frame user callback: a new selection (a click, not a drag) on a vertex re-solves."""
        ps = self.ps
        if ps.have_selection():
            sel = ps.get_selection()
            key = (sel.structure_name, sel.structure_data.get("element_type"), sel.structure_data.get("index"))
            if key != self._last_selection:
                self._last_selection = key
                self.pick(sel)
        # bound in C++ with no stub: Any, so mypy is the same with and without polyscope installed
        psim: Any = importlib.import_module("polyscope.imgui")
        psim.TextUnformatted(self.message)


def show(
    mesh: MeshLike,
    distance: ArrayLike | GeodesicResult | Field | None = None,
    *,
    sources: Any = None,
    method: Method | None = None,
    screenshot: str | os.PathLike | None = None,
    isolines: bool = True,
    normal: ArrayLike = (0.0, 0.0, 1.0),
    window_size: tuple[int, int] = (1024, 768),
    overwrite_read_only: bool = False,
    **solver_kwargs: Any,
) -> np.ndarray:
    """Show a distance field in an interactive polyscope window; clicking a vertex re-solves from it.

    Parameters
    ----------
    mesh : TriMesh, (V, F) tuple or path
        The surface, ``n`` vertices (anything :class:`~cvxgeodesic.GeodesicSolver` accepts); a mesh drawn by a
        slice (``mesh.reference.picture``: a tetrahedral mesh) goes to :func:`show_volume` (default method
        ``"qclp"``); a point cloud (a :class:`~cvxgeodesic.PointCloud`, its ``CloudMesh``, a point file) is drawn
        as its points coloured by the field (``Domain.drawn_as``), clicking a point re-solves from it.
    distance : (n,) array_like of float, GeodesicResult or Field, optional
        The field to show (``inf`` where unreachable): vertex values, or a result of a solve on this mesh (its
        ``distance``) or a field (its ``vertex_distance``). Without it the field is solved from ``sources``.
    sources : optional
        Anything :meth:`GeodesicSolver.solve` takes. With ``distance``: only marked (default: the
        vertices where ``distance`` is 0). Without ``distance``: solved (default: vertex 0).
    method : str (:data:`~cvxgeodesic.api.Method`), optional
        Method of the initial solve (when ``distance`` is None) and of the re-solves after a click (default
        the domain's: ``"qcqp-hessian"`` on a surface, ``"qclp"`` on a cloud).
    screenshot : str or path-like, optional
        Render one frame to this PNG and return without opening a window (works without a display).
    isolines : bool
        Draw isolines (20 over the field's range).
    normal : (3,) float array_like
        A solid's slice plane normal (:func:`show_volume`); unused on a surface.
    window_size : (int, int)
        Width and height in pixels of the window or screenshot.
    overwrite_read_only : bool, default False
        Replace a read-only ``screenshot`` file (refused otherwise, before the solve); it keeps its mode.
    **solver_kwargs
        Passed to :class:`GeodesicSolver` (``m``, ``lam``, ``solver``, ...).

    Returns
    -------
    (n,) float ndarray
        The field shown last (after the user's clicks, if any).

    Raises
    ------
    ImportError
        polyscope is not installed (``pip install 'cvxgeodesic[viewer]'``).
    ParameterError
        ``distance`` of the wrong shape, a bad ``window_size``, a bad ``screenshot`` path (or a read-only file
        without ``overwrite_read_only``), or no display (or polyscope already started off-screen in this process)
        and no ``screenshot``.
    """
    mesh = as_mesh(mesh)
    if distance is not None:  # a result or a field: its vertex values
        distance = d = as_field(distance, "distance", mesh.n_vertices)[0]
    if mesh.reference.picture == "slice":
        return show_volume(mesh, distance, sources=sources, method=method or "qclp", screenshot=screenshot,
                           normal=normal, window_size=window_size, overwrite_read_only=overwrite_read_only,
                           **solver_kwargs)
    ps = _start(window_size, screenshot, overwrite_read_only)
    viewer = _Viewer(ps, mesh, method=method or _default_method(mesh), solver_kwargs=solver_kwargs, isolines=isolines)
    if distance is None:
        viewer.solve(0 if sources is None else sources)
    else:
        viewer.set_field(d, _given_marks(mesh, d, sources))
    _present(ps, screenshot, viewer.callback, overwrite_read_only=overwrite_read_only)
    assert viewer.distance is not None
    return viewer.distance


def _default_method(mesh: SimplexMesh) -> Method:
    """The method of a surface's solves without ``method=``: the mesh's domain's (a cloud's is ``qclp``)."""
    from .capabilities import DOMAINS

    return DOMAINS[mesh.domain].default_method  # type: ignore[return-value]


def _start(window_size: tuple[int, int], screenshot: str | os.PathLike | None, overwrite_read_only: bool) -> Any:
    """Checks, then polyscope started and emptied: the window size, a display or a screenshot path."""
    try:
        w, h = (int(x) for x in window_size)
    except (TypeError, ValueError):
        raise ParameterError(f"window_size must be (width, height), got {window_size!r}") from None
    if w < 16 or h < 16:
        raise ParameterError(f"window_size must be at least 16 x 16 pixels, got {window_size!r}")
    headless = screenshot is not None or not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
    if screenshot is None and headless:
        raise ParameterError("no display (DISPLAY/WAYLAND_DISPLAY unset): render off-screen with "
                             "screenshot='out.png' (CLI: --screenshot out.png)")
    if screenshot is not None:  # before the solve: a bad path fails at once, not after it
        check_output_path(screenshot, (".png",))
        check_replaceable(screenshot, overwrite_read_only=overwrite_read_only)
    ps = _polyscope()
    _init(ps, headless)
    if screenshot is None and ps.is_headless():
        raise ParameterError("polyscope runs off-screen in this process (an earlier screenshot=, or no display "
                             "when it started) and cannot open a window now: pass screenshot='out.png'")
    ps.remove_all_structures()
    ps.remove_all_slice_planes()
    ps.set_window_size(w, h)
    ps.set_ground_plane_mode("none")
    return ps


def _present(ps: Any, screenshot: str | os.PathLike | None, callback: Any,
             camera: tuple[np.ndarray, np.ndarray] | None = None, *, overwrite_read_only: bool = False) -> None:
    """One frame into ``screenshot``, or the interactive window with ``callback`` each frame; ``camera``:
    (position, target), else polyscope's home view."""
    ps.reset_camera_to_home_view()
    if camera is not None:
        ps.look_at(tuple(float(c) for c in camera[0]), tuple(float(c) for c in camera[1]))
    try:
        if screenshot is not None:
            # polyscope reports a failed write only on stdout: output_set sees the missing file
            with output_set(screenshot, overwrite_read_only=overwrite_read_only) as tmp:
                ps.screenshot(str(tmp[0]), transparent_bg=False)
        else:
            ps.set_user_callback(callback)
            ps.show()
    finally:
        ps.clear_user_callback()


def show_volume(
    mesh: MeshLike,
    distance: ArrayLike | None = None,
    *,
    sources: Any = None,
    method: Method = "qclp",
    screenshot: str | os.PathLike | None = None,
    origin: ArrayLike | None = None,
    normal: ArrayLike = (0.0, 0.0, 1.0),
    window_size: tuple[int, int] = (1024, 768),
    overwrite_read_only: bool = False,
    **solver_kwargs: Any,
) -> np.ndarray:
    """Show a distance field inside a tetrahedral mesh (polyscope's volume mesh) cut by a slice plane.

    The plane shows the field on the cut through the solid; in the window its widget moves and turns it.

    Parameters
    ----------
    mesh : TetMesh, (V, T) tuple or path of a file holding tetrahedra
    distance : (n,) array_like of float, optional
        The field; without it the field is solved from ``sources`` (default vertex 0) with ``method``.
    sources : optional
        Anything :meth:`GeodesicSolver.solve` takes on a tetrahedral mesh; marked as red points.
    method : str (:data:`~cvxgeodesic.api.Method`)
        Method of the solve when ``distance`` is None (default ``"qclp"``).
    screenshot : str or path-like, optional
        Render one frame to this PNG and return without opening a window.
    origin : (3,) float array_like, optional
        A point of the slice plane (default the centre of the bounding box, moved by 1 % of its diagonal along
        ``normal``).
    normal : (3,) float array_like
        The plane's normal; the part on its positive side is cut away.
    window_size : (int, int)
    overwrite_read_only : bool, default False
        Replace a read-only ``screenshot`` file (as :func:`show`).
    **solver_kwargs
        Passed to :class:`GeodesicSolver` (``m``, ``solver``, ``order``, ...).

    Returns
    -------
    (n,) float ndarray
        The field shown.

    Raises
    ------
    ImportError
        polyscope is not installed.
    ParameterError
        As :func:`show`; a zero normal.
    """
    mesh = as_mesh(mesh)
    if mesh.reference.picture != "slice":
        raise ParameterError(f"show_volume takes a tetrahedral mesh; show() draws {mesh.reference.words.mesh}")
    unit = plane_frame(normal)[0]  # a zero normal refused there
    diag = float(mesh.bbox_diagonal) if mesh.bbox_diagonal > 0 else 1.0
    # the default plane is nudged off the centre by 1 % of the diagonal: on a structured mesh the centre plane holds
    # whole faces, and the renderer's depth test then draws the cut in stripes
    centre = 0.5 * (mesh.V.min(axis=0) + mesh.V.max(axis=0)) + 0.01 * diag * unit
    org = centre if origin is None else as_points(origin, "origin").reshape(3)
    ps = _start(window_size, screenshot, overwrite_read_only)
    if distance is None:
        from .api import GeodesicSolver

        res = GeodesicSolver(mesh, method, **solver_kwargs).solve(0 if sources is None else sources)
        d, marks = res.distance, _source_positions(mesh, res.source_set, res.sources)
    else:
        d = as_vertex_field(distance, "distance", mesh.n_vertices)
        marks = _given_marks(mesh, d, sources)
    vol = ps.register_volume_mesh(VOLUME_NAME, mesh.V, tets=mesh.cells, color=(0.8, 0.8, 0.8))
    vol.add_scalar_quantity(FIELD_NAME, _shown(d)[0], defined_on="vertices", enabled=True, cmap="viridis",
                            isolines_enabled=True)
    if len(marks):
        _add_marks(ps, marks, diag)
    plane = ps.add_scene_slice_plane()
    # polyscope keeps the side the normal points to: flip it so that the part on the positive side is cut away
    plane.set_pose(tuple(org.tolist()), tuple((-unit).tolist()))
    plane.set_draw_plane(False)
    plane.set_draw_widget(screenshot is None)
    plane.set_volume_mesh_to_inspect(VOLUME_NAME)  # the cut through the tetrahedra, the field interpolated on it
    # looking at the cut from the side that was cut away, a little off its normal so that the solid shows depth
    side = np.cross(unit, [0.0, 0.0, 1.0] if abs(unit[2]) < 0.9 else [1.0, 0.0, 0.0])
    eye = org + 1.6 * diag * unit + 0.35 * diag * side / np.linalg.norm(side)
    _present(ps, screenshot, lambda: None, camera=(eye, org), overwrite_read_only=overwrite_read_only)
    return d
