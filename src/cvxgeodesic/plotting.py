"""Headless pictures of distance fields, error maps and gradient-norm histograms.

Everything here renders with matplotlib's Agg canvas directly (no ``pyplot``,
no display, no global state) and writes PNG files atomically: the picture is
rendered into a temporary file next to the target and moved over it with
:func:`os.replace`, so a reader never sees a half-written PNG.

The surface renderer is a small software pipeline on top of matplotlib:

* orthographic projection along a view direction (a 3/4 view derived from the
  mesh's principal axes by default);
* back-face culling on closed, consistently oriented meshes; two-sided
  lighting on open or non-orientable ones;
* painter's algorithm: triangles sorted far-to-near and drawn with per-vertex
  colours (Gouraud interpolation, colour map times Lambert shading);
* isolines by marching triangles (:func:`isoline_segments`), drawn interleaved
  with the depth-sorted triangles in slabs, so surface in front of an isoline
  hides it.

A 46K-face mesh (bimba) takes about half a second per picture once matplotlib is imported
(about 0.6 s, once per process); time and memory grow linearly (330K faces: 4 s, 210 MB).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ._atomic import atomic_write
from .mesh.io import as_trimesh
from .validation import as_vertex_field, check_count, check_number, check_output_path, vertex_indices

__all__ = ["plot_field", "plot_error_map", "plot_gradient_histogram", "isoline_segments"]

#: Output formats accepted by the ``plot_*`` functions.
PLOT_EXTENSIONS = (".png",)

_UNREACHABLE_RGB = np.array([0.80, 0.80, 0.80])  # light grey for inf / NaN values
_FIGSIZE = (6.4, 5.4)  # inches; the PNG is round(6.4·dpi) × round(5.4·dpi) pixels
_SEGMENT_BLOCK = 400_000  # (triangle, level) pairs processed at once by the marching triangles


# ----------------------------------------------------------------------------------------------------------------------
# validation and output
# ----------------------------------------------------------------------------------------------------------------------


def _surface_inputs(mesh, values, name: str, sources, path, dpi) -> tuple[Any, np.ndarray, np.ndarray, Path, float]:
    """The checked inputs of a surface picture: ``(mesh, values (n,), marked vertices (k,), path, dpi)``."""
    mesh = as_trimesh(mesh)
    vals = as_vertex_field(values, name, mesh.n_vertices)
    marks = np.empty(0, dtype=np.int64) if sources is None else vertex_indices(sources, "sources", mesh.n_vertices)
    return mesh, vals, marks, check_output_path(path, PLOT_EXTENSIONS), check_number(dpi, "dpi", low=10, high=2000)


def _new_figure(dpi: float, figsize=_FIGSIZE):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, dpi=dpi)
    FigureCanvasAgg(fig)
    return fig


def _save_atomic(fig, path: Path) -> None:
    """Write ``fig`` as PNG to ``path`` atomically (see :func:`cvxgeodesic._atomic.atomic_write`)."""
    # compress_level 3: twice as fast as the default 6 for ~20% larger files
    atomic_write(path, lambda fh: fig.canvas.print_png(fh, pil_kwargs={"compress_level": 3}),
                 allow=None)  # a read-only PNG is refused; the plotting functions offer no override


# ----------------------------------------------------------------------------------------------------------------------
# marching triangles
# ----------------------------------------------------------------------------------------------------------------------


def _isolevels(levels, lo: float, hi: float) -> np.ndarray:
    """Resolve ``isolines`` (count or explicit levels) into a sorted float array."""
    if levels is None or levels is False:
        return np.empty(0)
    if isinstance(levels, int | np.integer) and not isinstance(levels, bool):
        k = int(levels)
        if k < 0:
            raise ValueError(f"isolines must be a non-negative count or an array of levels, got {levels}")
        if k == 0 or not (np.isfinite(lo) and np.isfinite(hi)) or hi <= lo:
            return np.empty(0)
        return np.linspace(lo, hi, k + 2)[1:-1]
    arr = np.asarray(levels, dtype=np.float64).ravel()
    if not np.all(np.isfinite(arr)):
        raise ValueError("isolines: explicit levels must be finite")
    return np.unique(arr)


def _marching_triangles(V: np.ndarray, F: np.ndarray, values: np.ndarray, levels: np.ndarray):
    """Segments where the piecewise-linear field crosses each level.

    Returns ``(segments (s, 2, 3), face index (s,))``. A vertex
    counts as *above* a level when its value is strictly greater, so a triangle
    with a vertex exactly at a level gives a segment through that vertex, and
    an edge lying on a level is emitted once (by the triangle on the upper side).
    Zero-length segments are dropped; triangles with a non-finite value give none.
    """
    levels = np.sort(np.asarray(levels, dtype=np.float64).ravel())
    empty = (np.empty((0, 2, 3)), np.empty(0, dtype=np.int64))
    if levels.size == 0 or F.shape[0] == 0:
        return empty
    fval = values[F]
    faces = np.flatnonzero(np.isfinite(fval).all(axis=1))
    fval = fval[faces]
    start = np.searchsorted(levels, fval.min(axis=1), side="left")  # first level >= min
    stop = np.searchsorted(levels, fval.max(axis=1), side="left")  # first level >= max
    counts = stop - start
    keep = counts > 0
    faces, fval, start, counts = faces[keep], fval[keep], start[keep], counts[keep]
    total = int(counts.sum())
    if total == 0:
        return empty
    cum = np.cumsum(counts)
    offsets = cum - counts
    seg_out, face_out = [], []
    # process (face, level) pairs in blocks of faces to bound the temporaries
    block_edges = np.searchsorted(cum, np.arange(_SEGMENT_BLOCK, total, _SEGMENT_BLOCK), side="left")
    bounds = np.r_[0, block_edges + 1, len(faces)]
    bounds = np.unique(np.clip(bounds, 0, len(faces)))  # strictly increasing: no empty block
    for b0, b1 in zip(bounds[:-1], bounds[1:], strict=False):
        cnt = counts[b0:b1]
        n_pairs = int(cnt.sum())
        local = np.repeat(np.arange(b0, b1), cnt)
        lev = start[local] + (np.arange(n_pairs) - (offsets[local] - offsets[b0]))
        lv = levels[lev]
        fv = fval[local]  # (p, 3)
        P = V[F[faces[local]]]  # (p, 3, 3)
        above = fv > lv[:, None]
        i_idx, j_idx = np.array([0, 1, 2]), np.array([1, 2, 0])
        a, b = fv[:, i_idx], fv[:, j_idx]  # edge end values (p, 3)
        cross = above[:, i_idx] != above[:, j_idx]  # exactly two True per row
        denom = np.where(cross, b - a, 1.0)
        t = np.where(cross, (lv[:, None] - a) / denom, 0.0)
        pts = P[:, i_idx] + t[..., None] * (P[:, j_idx] - P[:, i_idx])  # (p, 3 edges, 3)
        order = np.argsort(~cross, axis=1, kind="stable")[:, :2]  # the two crossing edges, in edge order
        seg = np.take_along_axis(pts, order[..., None], axis=1)  # (p, 2, 3)
        nonzero = np.any(seg[:, 0] != seg[:, 1], axis=1)
        seg_out.append(seg[nonzero])
        face_out.append(faces[local][nonzero])
    return np.concatenate(seg_out), np.concatenate(face_out)


def isoline_segments(mesh, values, levels) -> np.ndarray:
    """Isoline segments of a piecewise-linear vertex field (marching triangles).

    Parameters
    ----------
    mesh : TriMesh or (V, F) tuple
        The surface, ``n`` vertices and ``m`` faces.
    values : (n,) array_like of float
        One value per vertex, interpolated linearly inside each triangle.
        Triangles with a non-finite value (``inf`` = unreachable) give no segment.
    levels : float or (k,) array_like of float
        The iso-values.

    Returns
    -------
    (s, 2, 3) float ndarray
        One row per (triangle, level) crossing: the two end points, which lie on
        the triangle's edges. A vertex counts as above a level when its value is
        strictly greater; hence an isoline through a vertex is continuous, an
        edge lying exactly on a level is returned once, and zero-length segments
        are dropped. Rows are grouped by block, not sorted.

    Raises
    ------
    ValueError
        If ``values`` does not have shape ``(n,)`` or a level is not finite.

    Examples
    --------
    >>> from cvxgeodesic.mesh import grid_plane
    >>> mesh = grid_plane(4)
    >>> seg = isoline_segments(mesh, mesh.V[:, 0], [0.3])
    >>> bool(np.allclose(seg[..., 0], 0.3))
    True
    """
    mesh = as_trimesh(mesh)
    vals = as_vertex_field(values, "values", mesh.n_vertices)
    lev = np.asarray(levels, dtype=np.float64).ravel()
    if not np.all(np.isfinite(lev)):
        raise ValueError("levels must be finite")
    return _marching_triangles(mesh.V, mesh.F, vals, lev)[0]


# ----------------------------------------------------------------------------------------------------------------------
# camera and shading
# ----------------------------------------------------------------------------------------------------------------------


def _unit(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v)
    return v / n if n > 0 else v


def _camera(V: np.ndarray, view, focus=None) -> np.ndarray:
    """Rows: screen right, screen up, direction towards the viewer (orthonormal, right-handed).

    ``focus`` (a unit normal, optional) makes the default view pick, among its four mirror images
    (front or back, turned left or right), the one that faces that normal most.
    """
    if view is not None:
        try:
            elev, azim = (float(x) for x in view)
        except (TypeError, ValueError):
            raise ValueError(f"view must be None or (elev, azim) in degrees, got {view!r}") from None
        if not (np.isfinite(elev) and np.isfinite(azim)):
            raise ValueError(f"view must be finite (elev, azim) degrees, got {view!r}")
        e, a = np.radians(elev), np.radians(azim)
        toward = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])
        world_up = np.array([0.0, 0.0, 1.0])
        if abs(toward[2]) > 0.999:  # looking straight down or up: screen up along -azim (or +azim)
            world_up = -np.sign(toward[2]) * np.array([np.cos(a), np.sin(a), 0.0])
        right = _unit(np.cross(world_up, toward))
        up = np.cross(toward, right)
        return np.vstack([right, up, toward])
    # default: principal axes snapped to the nearest world axes (scanned models are usually axis-aligned);
    # of the two longest, world y (OBJ convention) points up if it is one, else world z; we look along the thinnest,
    # from its positive side, then turn 35 degrees sideways and raise the eye 15 degrees (a 3/4 view)
    X = V - V.mean(axis=0)
    _, U = np.linalg.eigh(X.T @ X)
    axes = U[:, ::-1].T  # rows, largest variance first
    snapped, free = [], [0, 1, 2]
    for ax_i in axes:
        j = max(free, key=lambda k: abs(ax_i[k]))
        free.remove(j)
        snapped.append(np.eye(3)[j])
    long1, long2, thin = snapped
    up = long1 if long1[1] == 1.0 else long2 if long2[1] == 1.0 else long1 if long1[2] == 1.0 else long2
    best = _three_quarter(up, thin, 1.0)
    for front, turn in ((1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)) if focus is not None else ():
        R = _three_quarter(up, front * thin, turn)
        if R[2] @ focus > best[2] @ focus + 1e-9:  # the first of near ties: a symmetric mesh keeps the front view
            best = R
    return best


def _three_quarter(up: np.ndarray, toward: np.ndarray, turn: float) -> np.ndarray:
    side = np.cross(up, toward)  # screen right: (right, up, toward) is right-handed
    az, el = np.radians(35.0) * turn, np.radians(15.0)
    toward = np.cos(az) * toward + np.sin(az) * side
    side = _unit(np.cross(up, toward))
    toward = np.cos(el) * toward + np.sin(el) * up
    up = _unit(np.cross(toward, side))
    return np.vstack([side, up, _unit(toward)])


def _closed_oriented(F: np.ndarray, n: int) -> bool:
    """True when every directed edge appears once and its reverse once (closed, consistently oriented)."""
    a, b = F.T.ravel(), np.roll(F, -1, axis=1).T.ravel()  # the directed edges a -> b, corner-major
    fwd, rev = np.sort(a * n + b), np.sort(b * n + a)
    return bool(np.all(fwd[1:] != fwd[:-1]) and np.array_equal(fwd, rev))


def _vertex_normals(V: np.ndarray, F: np.ndarray, fn: np.ndarray) -> np.ndarray:
    N = np.zeros_like(V)
    np.add.at(N, F, fn[:, None])
    nrm = np.linalg.norm(N, axis=1, keepdims=True)
    return N / np.where(nrm > 0, nrm, 1.0)


# ----------------------------------------------------------------------------------------------------------------------
# the surface renderer
# ----------------------------------------------------------------------------------------------------------------------


def _gouraud_artist_class():
    from matplotlib.artist import Artist

    class _GouraudTriangles(Artist):
        """Triangles with per-corner RGBA colours, drawn in the given order (painter's algorithm)."""

        def __init__(self, verts, colors, zorder):
            super().__init__()
            self.set_zorder(zorder)
            self._verts = verts  # (k, 3, 2)
            self._colors = colors  # (k, 3, 4)

        def draw(self, renderer):
            if not self.get_visible() or len(self._verts) == 0:
                return
            gc = renderer.new_gc()
            self._set_gc_clip(gc)
            renderer.draw_gouraud_triangles(gc, self._verts, self._colors, self.get_transform().frozen())
            gc.restore()
            self.stale = False

    return _GouraudTriangles


def _render_surface(ax, mesh, values, *, cmap, norm, levels, view, marks, ambient=0.38, paths=()):
    """Draw the shaded, colour-mapped surface, its isolines and marked vertices into ``ax``."""
    from matplotlib.collections import LineCollection

    V, F = mesh.V, mesh.F
    fn = mesh.face_normals_unnormalized
    closed = _closed_oriented(F, mesh.n_vertices)
    if closed:
        # outward orientation: signed volume positive
        vol = np.einsum("ij,ij->", V[F[:, 0]] - V.mean(axis=0), fn)
        if vol < 0:
            fn = -fn
    vnorm = _vertex_normals(V, F, fn)
    focus = vnorm[marks[0]] if marks.size and np.any(vnorm[marks[0]]) else None
    R = _camera(V, view, focus)
    P = (V - V.mean(axis=0)) @ R.T  # (n, 3): screen x, screen y, depth (towards the viewer)
    facing = fn @ R[2]
    vis = np.flatnonzero(facing > 0) if closed else np.arange(F.shape[0])  # back faces culled on closed meshes
    Fv = F[vis]
    depth = P[Fv, 2].mean(axis=1)
    order = np.argsort(depth, kind="stable")  # far to near
    vis, Fv = vis[order], Fv[order]

    # per-vertex colours: colour map times Lambert shading (two-sided when not closed)
    light = _unit(-0.35 * R[0] + 0.55 * R[1] + 1.0 * R[2])
    lam = vnorm @ light
    lam = np.abs(lam) if not closed else np.clip(lam, 0.0, None)
    shade = ambient + (1.0 - ambient) * lam
    finite = np.isfinite(values)
    rgba = np.empty((len(V), 4))
    rgba[:, 3] = 1.0
    rgba[finite, :3] = cmap(norm(values[finite]))[:, :3]
    rgba[~finite, :3] = _UNREACHABLE_RGB
    rgba[:, :3] *= shade[:, None]

    verts = P[Fv][:, :, :2]  # (k, 3, 2)
    colors = rgba[Fv]  # (k, 3, 4)
    partial = ~finite[Fv].all(axis=1)  # a triangle touching an unreachable vertex is grey as a whole
    if partial.any():
        colors[partial, :, :3] = _UNREACHABLE_RGB * shade[Fv[partial]][..., None]

    # isolines, assigned to the depth slab of their triangle
    k = len(Fv)
    n_slabs = int(np.clip(k // 4, 1, 128))
    bounds = np.linspace(0, k, n_slabs + 1).astype(np.int64)
    slab_of_face = np.full(F.shape[0], -1, dtype=np.int64)  # -1: culled
    slab_of_face[vis] = np.repeat(np.arange(n_slabs), np.diff(bounds))
    seg3, seg_face = _marching_triangles(V, F, values, levels)  # none without levels
    seg_slab = slab_of_face[seg_face]
    on = seg_slab >= 0
    seg2 = ((seg3[on] - V.mean(axis=0)) @ R[:2].T)  # (s, 2, 2)
    seg_slab = seg_slab[on]
    seg_order = np.argsort(seg_slab, kind="stable")
    seg2, seg_slab = seg2[seg_order], seg_slab[seg_order]
    seg_bounds = np.searchsorted(seg_slab, np.arange(n_slabs + 1), side="left")

    # marked vertices: drawn with the slab of their nearest visible incident triangle (hidden if none is visible)
    mark_slab = np.full(marks.size, -1, dtype=np.int64)
    if marks.size:
        want = np.full(mesh.n_vertices, -1, dtype=np.int64)
        np.maximum.at(want, F, slab_of_face[:, None])
        mark_slab = want[marks]

    Gouraud = _gouraud_artist_class()
    for i in range(n_slabs):
        a, b = bounds[i], bounds[i + 1]
        ax.add_artist(Gouraud(verts[a:b], colors[a:b], zorder=1.0 + 2 * i * 1e-3))
        s0, s1 = seg_bounds[i], seg_bounds[i + 1]
        if s1 > s0:
            lc = LineCollection(seg2[s0:s1], colors="black", linewidths=0.45, alpha=0.85,
                                capstyle="round", zorder=1.0 + (2 * i + 1) * 1e-3)
            ax.add_collection(lc, autolim=False)
        here = marks[mark_slab == i]
        if here.size:
            ax.scatter(P[here, 0], P[here, 1], s=28, c="#e8112d", edgecolors="white", linewidths=0.9,
                       zorder=1.0 + (2 * i + 1.5) * 1e-3)

    for path in paths:  # polylines on the surface (geodesic paths), drawn on top
        Q = (np.asarray(path, dtype=float).reshape(-1, 3) - V.mean(axis=0)) @ R[:2].T
        ax.plot(Q[:, 0], Q[:, 1], color="#e8112d", linewidth=2.0, solid_capstyle="round", zorder=3.0)

    lo, hi = P[:, :2].min(axis=0), P[:, :2].max(axis=0)
    pad = 0.03 * max(float(np.max(hi - lo)), 1e-12)
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal", adjustable="box")
    ax.set_axis_off()


def _finite_range(values: np.ndarray, vmin, vmax) -> tuple[float, float]:
    fin = values[np.isfinite(values)]
    lo = float(vmin) if vmin is not None else (float(fin.min()) if fin.size else 0.0)
    hi = float(vmax) if vmax is not None else (float(fin.max()) if fin.size else 1.0)
    if not (np.isfinite(lo) and np.isfinite(hi)):
        raise ValueError(f"vmin and vmax must be finite, got {vmin!r}, {vmax!r}")
    if hi <= lo:
        hi = lo + (abs(lo) * 1e-6 if lo else 1.0)
    return lo, hi


def _layout(fig, show_colorbar: bool, title):
    top = 0.90 if title else 0.97
    if show_colorbar:
        ax = fig.add_axes((0.01, 0.02, 0.80, top - 0.02))
        cax = fig.add_axes((0.84, 0.15, 0.03, (top - 0.02) * 0.78))
    else:
        ax = fig.add_axes((0.01, 0.02, 0.98, top - 0.02))
        cax = None
    if title:
        fig.suptitle(str(title), y=0.975, fontsize=12)
    return ax, cax


def plot_field(
    mesh: Any,
    values: ArrayLike,
    path: str | os.PathLike,
    *,
    isolines: int | ArrayLike | None = 20,
    title: str | None = None,
    cmap: Any = "viridis",
    view: tuple[float, float] | None = None,
    vmin: float | None = None,
    vmax: float | None = None,
    show_colorbar: bool = True,
    dpi: float = 150,
    colorbar_label: str | None = None,
    sources: ArrayLike | None = None,
    paths: Any = (),
) -> Path:
    """Render a per-vertex scalar field on the surface, with isolines, into a PNG.

    Parameters
    ----------
    mesh : TriMesh or (V, F) tuple
        The surface, ``n`` vertices and ``m`` faces.
    values : (n,) array_like of float
        One value per vertex (e.g. a distance field). ``inf`` / ``NaN``
        (unreachable) vertices are drawn light grey and carry no isolines.
    path : str or os.PathLike
        Output file; must end in ``.png``. Its directory must exist. The file
        is written atomically (temporary file + :func:`os.replace`).
    isolines : int or (k,) array_like of float, default 20
        Number of evenly spaced levels strictly inside ``[vmin, vmax]``, or the
        explicit levels; 0 or None draws none. Lines are thin and black.
    title : str, optional
        Title above the picture.
    cmap : str or matplotlib Colormap, default "viridis"
        Colour map.
    view : (elev, azim) tuple of float, optional
        Camera direction in degrees, matplotlib's ``mplot3d`` convention (world
        ``z`` up, ``azim`` around ``z`` from ``+x``). Default: a 3/4 view from
        the mesh's principal axes (the axis closest to world ``y`` on screen up,
        looking along the thinnest axis, turned 35° sideways and raised 20°).
    vmin, vmax : float, optional
        Colour range; default the finite minimum and maximum of ``values``.
    show_colorbar : bool, default True
        Draw a colour bar on the right.
    dpi : float, default 150
        Resolution; the PNG is ``round(6.4·dpi) × round(5.4·dpi)`` pixels
        (960 × 810 at 150 dpi).
    colorbar_label : str, optional
        Label of the colour bar.
    sources : int or (k,) array_like of int, optional
        Vertices to mark with a red dot (where visible). The default view
        then picks, among its mirror images (front/back, turned left/right),
        the one that faces the first of them.
    paths : sequence of (k, 3) float array_like, optional
        Polylines on the surface (e.g. :func:`cvxgeodesic.geodesic_path`), drawn on top in red.

    Returns
    -------
    pathlib.Path
        The written file.

    Raises
    ------
    ValueError
        If ``view`` is malformed; a :class:`~cvxgeodesic.errors.ParameterError` (a ``ValueError``) if
        ``values`` does not have shape ``(n,)``, ``path`` does not end in ``.png`` or cannot be written
        (its directory does not exist), ``dpi`` is out of range or a source index is out of range.

    Notes
    -----
    Closed, consistently oriented meshes are drawn with back-face culling;
    other meshes with two-sided lighting. Isolines are drawn in depth slabs
    interleaved with the surface, so surface in front of them hides them
    (up to the slab thickness: 1/128 of the visible triangles, or 4 triangles).

    Examples
    --------
    >>> from cvxgeodesic.mesh import icosphere
    >>> mesh = icosphere(3)
    >>> plot_field(mesh, mesh.V[:, 2], "/tmp/height.png", title="height")  # doctest: +SKIP
    """
    from matplotlib import colormaps
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Colormap, Normalize

    mesh, vals, marks, p, dpi = _surface_inputs(mesh, values, "values", sources, path, dpi)
    cm = cmap if isinstance(cmap, Colormap) else colormaps[cmap]
    lo, hi = _finite_range(vals, vmin, vmax)
    levels = _isolevels(isolines, lo, hi)
    norm = Normalize(lo, hi, clip=True)

    fig = _new_figure(dpi)
    ax, cax = _layout(fig, show_colorbar, title)
    _render_surface(ax, mesh, vals, cmap=cm, norm=norm, levels=levels, view=view, marks=marks, paths=paths)
    if cax is not None:
        cb = fig.colorbar(ScalarMappable(norm=Normalize(lo, hi), cmap=cm), cax=cax, label=colorbar_label or "")
        if levels.size and levels.size <= 60:
            cb.ax.hlines(levels, 0, 1, colors="black", linewidths=0.4, alpha=0.6)
    _save_atomic(fig, p)
    return p


def plot_error_map(mesh, rel_error, path, *, title=None, vmax=None, view=None, dpi=150, sources=None) -> Path:
    """Relative-error colour map on the surface (paper Fig. 6).

    Parameters
    ----------
    mesh : TriMesh or (V, F) tuple
        The surface, ``n`` vertices.
    rel_error : (n,) array_like of float
        Per-vertex relative error ``|d - d_exact| / d_exact``; ``NaN`` at the
        sources (and ``inf`` / ``NaN`` where undefined) is drawn grey.
    path : str or os.PathLike
        Output ``.png`` file, written atomically.
    title : str, optional
        Title above the picture.
    vmax : float, optional
        Top of the colour range (the range starts at 0); default the 99th
        percentile of the finite errors, so a few outliers do not wash out the map.
    view : (elev, azim) tuple of float, optional
        As in :func:`plot_field`.
    dpi : float, default 150
        Resolution (same picture size as :func:`plot_field`).
    sources : int or (k,) array_like of int, optional
        Vertices to mark (and to face), as in :func:`plot_field`.

    Returns
    -------
    pathlib.Path
        The written file.

    Raises
    ------
    ValueError
        As :func:`plot_field`, for ``rel_error`` in place of ``values``.
    """
    from matplotlib import colormaps
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize
    from matplotlib.ticker import PercentFormatter

    mesh, err, marks, p, dpi = _surface_inputs(mesh, rel_error, "rel_error", sources, path, dpi)
    fin = err[np.isfinite(err)]
    if vmax is None:
        vmax = float(np.percentile(fin, 99.0)) if fin.size else 1.0
    vmax = float(vmax)
    if not np.isfinite(vmax) or vmax <= 0:
        vmax = float(fin.max()) if fin.size and fin.max() > 0 else 1.0
    cm = colormaps["inferno_r"]
    norm = Normalize(0.0, vmax, clip=True)

    fig = _new_figure(dpi)
    ax, cax = _layout(fig, True, title)
    # light shading only: dark shading would read as large error on this colour map
    _render_surface(ax, mesh, err, cmap=cm, norm=norm, levels=np.empty(0), view=view, ambient=0.78,
                    marks=marks)
    extend = "max" if fin.size and fin.max() > vmax else "neither"
    cb = fig.colorbar(ScalarMappable(norm=Normalize(0.0, vmax), cmap=cm), cax=cax, extend=extend,
                      label="relative error |d − d_exact| / d_exact")
    cb.ax.yaxis.set_major_formatter(PercentFormatter(xmax=1.0, decimals=None))
    if fin.size:
        note = f"mean {100 * fin.mean():.2f}%   max {100 * fin.max():.2f}%   (grey: no value, e.g. sources)"
        ax.text(0.01, 0.01, note, transform=ax.transAxes, fontsize=8, color="0.25", ha="left", va="bottom")
    _save_atomic(fig, p)
    return p


# ----------------------------------------------------------------------------------------------------------------------
# gradient-norm histograms
# ----------------------------------------------------------------------------------------------------------------------


def _as_hist_entry(label, entry, weights):
    """Return ('hist', counts, edges) or ('raw', norms, weights) for one label."""
    if isinstance(entry, tuple) and len(entry) == 2:
        counts, edges = (np.asarray(x, dtype=np.float64).ravel() for x in entry)
        if edges.size != counts.size + 1:
            raise ValueError(
                f"norms_by_label[{label!r}]: a (counts, edges) pair needs len(edges) == len(counts) + 1, "
                f"got {counts.size} and {edges.size}"
            )
        return "hist", counts, edges
    norms = np.asarray(entry, dtype=np.float64)
    if norms.ndim != 1:
        raise ValueError(
            f"norms_by_label[{label!r}] must be (m,) norms or a (counts, edges) pair, got shape {norms.shape}"
        )
    w = weights.get(label) if isinstance(weights, Mapping) else weights
    if w is not None:
        w = np.asarray(w, dtype=np.float64)
        if w.shape != norms.shape:
            raise ValueError(f"weights for {label!r} must have shape {norms.shape}, got {w.shape}")
    ok = np.isfinite(norms) if w is None else np.isfinite(norms) & np.isfinite(w)
    return "raw", norms[ok], (None if w is None else w[ok])


def plot_gradient_histogram(norms_by_label, path, *, weights=None, title=None, bins=80, dpi=150) -> Path:
    """Histograms of per-triangle gradient norms ``‖∇d|_t‖`` (paper Fig. 2), one per label.

    Parameters
    ----------
    norms_by_label : dict[str, (m,) array_like or (counts, edges) tuple]
        For each label (method name) either the per-triangle norms or a
        precomputed histogram ``(counts (b,), edges (b + 1,))``. Labels are
        drawn in dict order; a label ``"exact"`` (or else the first one) is the
        reference, drawn grey behind every panel.
    path : str or os.PathLike
        Output ``.png`` file, written atomically.
    weights : (m,) array_like or dict[str, (m,) array_like], optional
        Per-triangle weights for the raw norms (e.g. ``mesh.face_areas`` for an
        area-weighted histogram), one array for all labels or one per label.
    title : str, optional
        Figure title.
    bins : int, default 80
        Number of bins for raw norms, shared by all labels, over
        ``[0, max(1.5, 99.9th percentile)]`` (capped at 3); norms beyond the
        range are counted in the last bin.
    dpi : float, default 150
        Resolution.

    Returns
    -------
    pathlib.Path
        The written file.

    Notes
    -----
    Histograms are normalised to fractions (of triangles, or of total weight)
    and drawn on a log scale, so the small populations away from 1 (across the
    ridge: < 1; at the sources: > 1) stay visible (histograms with nothing counted,
    every cell left out: a linear scale and "no cell to count"). Up to three labels share one
    axis; more are drawn as small multiples. The dashed line marks ``‖∇d‖ = 1``.
    """
    if not isinstance(norms_by_label, Mapping) or len(norms_by_label) == 0:
        raise ValueError("norms_by_label must be a non-empty dict {label: norms or (counts, edges)}")
    p = check_output_path(path, PLOT_EXTENSIONS)
    dpi = check_number(dpi, "dpi", low=10, high=2000)
    bins = check_count(bins, "bins")
    entries = {str(k): _as_hist_entry(k, v, weights) for k, v in norms_by_label.items()}

    raw_all = [e[1] for e in entries.values() if e[0] == "raw" and e[1].size]
    top = 1.5
    if raw_all:
        top = min(3.0, max(1.5, float(np.percentile(np.concatenate(raw_all), 99.9)) * 1.02))
    edges_common = np.linspace(0.0, top, int(bins) + 1)
    hists = {}
    for label, (kind, a, b) in entries.items():
        if kind == "hist":
            counts, edges = a, b
        else:
            counts, edges = np.histogram(np.clip(a, 0.0, top), bins=edges_common, weights=b)
        total = counts.sum()
        hists[label] = (counts / total if total > 0 else counts, edges)

    labels = list(hists)
    ref = "exact" if "exact" in hists else labels[0]
    others = [lab for lab in labels if lab != ref] or [ref]
    import matplotlib as mpl

    colors = mpl.colormaps["tab10"].colors
    single = len(labels) <= 3  # every label on one axis, else one panel per label (the reference in each)
    ncols = 1 if single else 3 if len(others) > 4 else 2
    nrows = int(np.ceil(len(others) / ncols)) if not single else 1
    fig = _new_figure(dpi, figsize=(6.4, 4.2) if single else (3.2 * ncols, 2.3 * nrows + 0.6))
    axes = fig.subplots(nrows, ncols, squeeze=False, sharex=True, sharey=True)
    positive = np.concatenate([h[0][h[0] > 0] for h in hists.values()] + [np.ones(1)])
    ymin = max(float(positive.min()) * 0.5, 1e-7)

    def draw_ref(ax):
        c, e = hists[ref]
        ax.stairs(c, e, fill=True, color="0.80", label=f"{ref}", zorder=1)

    draw_ref(axes[0, 0])
    for i, lab in enumerate(lab for lab in labels if lab != ref):
        ax = axes.flat[0 if single else i]
        if i and not single:
            draw_ref(ax)
        c, e = hists[lab]
        ax.stairs(c, e, color=colors[i % len(colors)], linewidth=1.4 if single else 1.3, label=lab if single else None,
                  zorder=2)
        if not single:
            ax.set_title(lab, fontsize=9, pad=3)
    for ax in axes.flat[len(others):]:
        ax.set_visible(False)
    axes.flat[0].legend(fontsize=8 if single else 7, frameon=False, loc="upper left")
    # no cell counted anywhere (every cell touches a source): a log scale of nothing makes matplotlib warn "Data has
    # no positive values, and therefore cannot be log-scaled", which compare showed as a note
    empty = not any((h[0] > 0).any() for h in hists.values())
    for ax in axes.flat:
        ax.axvline(1.0, color="black", linestyle="--", linewidth=0.9, zorder=3)
        if empty:
            ax.set_ylim(0.0, 1.0)
            ax.text(0.5, 0.5, "no cell to count", transform=ax.transAxes, ha="center", va="center", fontsize=9,
                    color="0.35")
        else:
            ax.set_yscale("log")
            ax.set_ylim(ymin, 1.5)
        ax.tick_params(labelsize=8)
        ax.grid(True, which="major", alpha=0.25)
    for ax in axes[-1, :]:
        ax.set_xlabel("‖∇d‖ per triangle", fontsize=9)
    for ax in axes[:, 0]:
        ax.set_ylabel("fraction" + (" (area-weighted)" if weights is not None else ""), fontsize=9)
    if title:
        fig.suptitle(str(title), fontsize=11)
    fig.set_layout_engine("constrained")
    _save_atomic(fig, p)
    return p
