"""A PNG of a field on a planar slice of a tetrahedral mesh (issue 26), headless like :mod:`cvxgeodesic.plotting`;
:func:`draw_field`, a field on a surface or on a volume's slice.

The slice (:func:`~cvxgeodesic.mesh.tet_slice.slice_tets`) is drawn flat in the plane's own frame
(``e1`` to the right, ``e2`` up; for the default normal ``z`` that is the ``x``–``y`` view from
above), coloured by the field with Gouraud shading, with isolines and the outline of the cut.
Unreachable parts (``inf``/NaN) are light grey. A result's field (:class:`~cvxgeodesic.results.Field`) gives the
values at the cut points, so an order-2 field is drawn with its own (quadratic) values there.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ..errors import MeshError, ParameterError
from ..mesh.convert import MeshLike, as_mesh
from ..mesh.simplex import SimplexMesh
from ..mesh.tet_slice import slice_tets
from ..mesh.tetmesh import TetMesh
from ..plotting import PLOT_EXTENSIONS, _finite_range, _isolevels, _new_figure, _save_atomic
from ..results import Field, GeodesicResult
from ..validation import as_points, check_number, check_output_path

__all__ = ["draw_field", "plot_slice"]

_AXES = "xyz"


def _axis_label(e: np.ndarray) -> str:
    k = int(np.argmax(np.abs(e)))
    if abs(abs(e[k]) - 1.0) < 1e-12:
        return ("−" if e[k] < 0 else "") + _AXES[k]
    return "(" + ", ".join(f"{x:.2f}" for x in e) + ")"


def plot_slice(
    mesh: MeshLike,
    values: ArrayLike | GeodesicResult | Field,
    path: str | os.PathLike,
    *,
    origin: ArrayLike | None = None,
    normal: ArrayLike = (0.0, 0.0, 1.0),
    isolines: int | ArrayLike | None = 20,
    title: str | None = None,
    cmap: str = "viridis",
    vmin: float | None = None,
    vmax: float | None = None,
    dpi: float = 150,
    colorbar_label: str | None = None,
    points: ArrayLike | None = None,
) -> Path:
    """Render a field on the slice of a tetrahedral mesh by a plane into a PNG.

    Parameters
    ----------
    mesh : TetMesh, (V, T) tuple or file path
        ``n`` vertices (what :func:`~cvxgeodesic.mesh.convert.as_mesh` takes, holding tetrahedra).
    values : (n,) float array_like, GeodesicResult or Field
        One value per vertex (``inf``/NaN: grey, no isolines), interpolated linearly along the cut edges; or a result
        of a solve on this mesh (or its :attr:`~cvxgeodesic.results.GeodesicResult.field`), asked at the cut points
        (:func:`~cvxgeodesic.mesh.tet_slice.slice_tets`).
    path : str or os.PathLike
        Output ``.png`` (written atomically; its folder must exist).
    origin : (3,) float array_like, optional
        A point of the plane; default the centre of the bounding box.
    normal : (3,) float array_like
        Normal of the plane (default ``z``: a horizontal slice seen from above).
    isolines : int or (k,) float array_like, default 20
        Number of evenly spaced levels inside the colour range, or the levels; 0 or None: none.
    title : str, optional
    cmap : str
        A matplotlib colour map name.
    vmin, vmax : float, optional
        Colour range; default the finite range of the field *on the slice*.
    dpi : float
        Resolution (960 × 810 pixels at 150).
    colorbar_label : str, optional
    points : (s, 3) float array_like, optional
        Points (e.g. sources) drawn as red dots at their projection onto the plane.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    MeshError
        A mesh without tetrahedra (a surface: :func:`~cvxgeodesic.plotting.plot_field`).
    ParameterError
        ``values`` of the wrong length (a field of another mesh), a bad path, normal or dpi; or the plane misses the
        mesh.

    Examples
    --------
    >>> from cvxgeodesic.mesh.tet_generate import tet_box
    >>> mesh = tet_box(6)
    >>> plot_slice(mesh, mesh.V[:, 0], "/tmp/slice.png", origin=[0.5, 0.5, 0.5])  # doctest: +SKIP
    """
    from matplotlib import colormaps
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize
    from matplotlib.tri import Triangulation

    tets = as_mesh(mesh)
    if not isinstance(tets, TetMesh):  # dimension: the input check of a TetMesh-only function (slice_tets)
        raise MeshError(f"plot_slice takes a tetrahedral mesh; {tets.name} is {tets.reference.words.mesh} (plot_field "
                        "draws it)")
    p = check_output_path(path, PLOT_EXTENSIONS)
    dpi = check_number(dpi, "dpi", low=10, high=2000)
    cut = slice_tets(tets, values, origin=origin, normal=normal)
    if cut.triangles.shape[0] == 0:
        raise ParameterError(f"the plane through {cut.origin.tolist()} with normal {cut.normal.tolist()} misses "
                             f"{tets.name}")
    vals = cut.values
    lo, hi = _finite_range(vals, vmin, vmax)
    levels = _isolevels(isolines, lo, hi)
    cm = colormaps[cmap]
    norm = Normalize(lo, hi, clip=True)

    fig = _new_figure(dpi)
    top = 0.90 if title else 0.96
    ax = fig.add_axes((0.09, 0.09, 0.72, top - 0.11))
    cax = fig.add_axes((0.85, 0.15, 0.03, (top - 0.02) * 0.78))
    if title:
        fig.suptitle(str(title), y=0.975, fontsize=12)
    finite = np.isfinite(vals)
    uv = cut.uv
    # slivers of the cut (a vertex on the plane to round-off) show as dark seams in the Gouraud shading: leave out
    # triangles of almost no area
    a, b, c = (uv[cut.triangles[:, i]] for i in range(3))
    area2 = np.abs((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])
    drawn = area2 > 1e-6 * np.median(area2)
    good = finite[cut.triangles].all(axis=1) & drawn
    if (~good & drawn).any():
        tri_bad = Triangulation(uv[:, 0], uv[:, 1], cut.triangles[~good & drawn])
        ax.tripcolor(tri_bad, np.zeros(len(uv)), cmap="Greys", vmin=-4, vmax=1, shading="flat")
    if good.any():
        tri = Triangulation(uv[:, 0], uv[:, 1], cut.triangles[good])
        shown = np.where(finite, vals, lo)
        ax.tripcolor(tri, shown, cmap=cm, norm=norm, shading="gouraud")
        if levels.size:
            ax.tricontour(tri, shown, levels=levels, colors="black", linewidths=0.45)
    if cut.outline.size:
        from matplotlib.collections import LineCollection

        ax.add_collection(LineCollection(uv[cut.outline], colors="black", linewidths=0.8))
    if points is not None:
        P = as_points(points, "points").reshape(-1, 3) - cut.origin
        ax.plot(P @ cut.e1, P @ cut.e2, "o", color="red", markersize=4)
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_xlabel(_axis_label(cut.e1))
    ax.set_ylabel(_axis_label(cut.e2))
    ax.tick_params(labelsize=7)
    fig.colorbar(ScalarMappable(norm=Normalize(lo, hi), cmap=cm), cax=cax, label=colorbar_label or "")
    _save_atomic(fig, p)
    return p


def draw_field(mesh: SimplexMesh, values: ArrayLike | GeodesicResult | Field, path: str | os.PathLike, *, title: str,
               sources: ArrayLike = (), points: ArrayLike | None = None, line: ArrayLike | None = None,
               normal: ArrayLike = (0.0, 0.0, 1.0), levels: int | ArrayLike | None = 20, vmin: float | None = None,
               vmax: float | None = None, label: str | None = None, error: bool = False, view: Any = None,
               up: Any = "auto") -> None:
    """A field (``error``: a relative error) into a PNG: on a surface (:func:`~cvxgeodesic.plotting.plot_field`,
    :func:`~cvxgeodesic.plotting.plot_error_map`), or on the slice of a tetrahedral mesh by the plane through its
    centre with this ``normal`` (:func:`plot_slice`): what the command line and the comparison draw. A field is
    (n,) vertex values, or a result or its field, which a slice asks at its cut points; an error is vertex values.

    The (k,) ``sources`` are marked, in a volume at their positions or at the (p, 3) ``points`` when given; a (q, 3)
    ``line`` (a geodesic path) replaces the marks. ``levels`` (isolines), ``vmin``, ``vmax`` and ``label`` (the
    colour bar's) style a field; an error has its own colour map and label, no isolines, and starts at 0. ``view``
    and ``up``: a surface's camera (:func:`~cvxgeodesic.plotting.plot_field`; default: facing the first source, and
    the far side); a slice is seen along its normal. How the mesh is drawn: ``mesh.reference.picture``.
    """
    if mesh.reference.picture == "slice":
        marks = mesh.V[np.asarray(sources, dtype=np.int64)] if points is None else points
        plot_slice(mesh, values, path, normal=normal, vmin=0.0 if error else vmin, vmax=vmax, title=title,
                   points=marks if line is None else line, isolines=None if error else levels,
                   cmap="inferno_r" if error else "viridis", colorbar_label="relative error" if error else label)
    elif error:
        from ..plotting import plot_error_map  # looked up at the call: tests replace it

        plot_error_map(mesh, values, path, title=title, vmax=vmax, sources=sources, view=view, up=up)
    else:
        from ..plotting import plot_field

        plot_field(mesh, values, path, isolines=levels, title=title, vmin=vmin, vmax=vmax, colorbar_label=label,
                   sources=None if line is not None else sources, paths=() if line is None else [line], view=view,
                   up=up)
