"""Headless pictures of distance fields, error maps and gradient-norm histograms.

Everything here renders with matplotlib's Agg canvas directly (no ``pyplot``,
no display, no global state) and writes PNG files atomically: the picture is
rendered into a temporary file next to the target and moved over it with
:func:`os.replace`, so a reader never sees a half-written PNG.

The surface renderer is a small software pipeline on top of matplotlib:

* orthographic projection along a view direction; by default two panels side by
  side, one facing the first source and one from the opposite side (the field's far
  side, where its ridge lies), with an up axis from the mesh
  (:func:`~cvxgeodesic.evaluation.camera.up_vector`);
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
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from ._atomic import atomic_write
from .evaluation.camera import (
    _ELEV,
    _frame,
    _front_angles,
    _rotation,
    _unit,
    up_vector,
    view_list,
)
from .mesh.convert import MeshLike
from .mesh.io import as_trimesh
from .mesh.trimesh import TriMesh
from .operators.linear_field import LinearField
from .results import Field, GeodesicResult
from .validation import as_field, as_vertex_field, check_count, check_number, check_output_path, vertex_indices

__all__ = ["plot_field", "plot_error_map", "plot_gradient_histogram", "isoline_segments", "up_vector", "view_list"]

#: Output formats accepted by the ``plot_*`` functions.
PLOT_EXTENSIONS = (".png",)

_UNREACHABLE_RGB = np.array([0.80, 0.80, 0.80])  # light grey for inf / NaN values
_FIGSIZE = (6.4, 5.4)  # inches; the PNG is round(6.4·dpi) × round(5.4·dpi) pixels
_SEGMENT_BLOCK = 400_000  # (triangle, level) pairs processed at once by the marching triangles


# ----------------------------------------------------------------------------------------------------------------------
# validation and output
# ----------------------------------------------------------------------------------------------------------------------


def _surface_inputs(mesh, values, name: str, sources, path, dpi, *,
                    field: bool = False) -> tuple[Any, np.ndarray, np.ndarray, Path, float]:
    """The checked inputs of a surface picture: ``(mesh, values (n,), marked vertices (k,), path, dpi)``; ``field``:
    ``values`` may be a result or a field (a field that is not linear in its faces is drawn on the mesh split
    4-to-1, :func:`_sampled`; the first ``n`` vertices are the mesh's)."""
    mesh = as_trimesh(mesh)
    marks = np.empty(0, dtype=np.int64) if sources is None else vertex_indices(sources, "sources", mesh.n_vertices)
    if field:
        mesh, vals = _sampled(mesh, *as_field(values, name, mesh.n_vertices))
    else:
        vals = as_vertex_field(values, name, mesh.n_vertices)
    return mesh, vals, marks, check_output_path(path, PLOT_EXTENSIONS), check_number(dpi, "dpi", low=10, high=2000)


#: A field that is not linear in its faces (order 2, an adapted solve's) is drawn on the mesh split 4-to-1 up to this
#: many faces; above it a face is about a pixel of a 960-pixel panel and the split would not show.
MAX_SAMPLED_FACES = 50_000


def _sampled(mesh: TriMesh, values: np.ndarray, field: Field | None) -> tuple[TriMesh, np.ndarray]:
    """The mesh and vertex values to draw: for a field that is not linear in its faces, the mesh with every face split
    in four at its edge midpoints (its vertices first, then one per edge) and the field asked at the midpoints.

    Drawn linearly, the split field meets a quadratic one at the six nodes of every face, so the isolines follow
    the order-2 field's curves instead of the chords between its vertex values.
    """
    if field is None or isinstance(field, LinearField) or mesh.n_faces > MAX_SAMPLED_FACES:
        return mesh, values
    n, F = mesh.n_vertices, mesh.F
    cell_edges = mesh.cell_edges  # (m, 3): the edge opposite each corner
    first = np.unique(cell_edges.ravel(), return_index=True)[1]  # one (face, corner) across from each edge
    face, corner = first // 3, first % 3
    bary = np.full((face.size, 3), 0.5)
    bary[np.arange(face.size), corner] = 0.0
    mid = field.distance_at(face, bary)  # inf where no source is reachable, as at the vertices
    m0, m1, m2 = (n + cell_edges[:, e] for e in range(3))  # the midpoints opposite corners 0, 1, 2
    a, b, c = F.T
    split = np.concatenate([np.c_[a, m2, m1], np.c_[m2, b, m0], np.c_[m1, m0, c], np.c_[m2, m0, m1]])
    V = np.vstack([mesh.V, mesh.V[mesh.edges].mean(axis=1)])
    return TriMesh(V, split, name=mesh.name), np.concatenate([values, mid])


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


@dataclass
class _Surface:
    """What every panel of one picture shares: the mesh, its normals, whether it is closed, its isolines."""

    mesh: Any
    closed: bool
    fn: np.ndarray  # (m, 3) face normals, outward on a closed mesh
    vnorm: np.ndarray  # (n, 3) unit vertex normals
    seg3: np.ndarray  # (s, 2, 3) isoline segments
    seg_face: np.ndarray  # (s,) their faces


def _surface(mesh, values: np.ndarray, levels: np.ndarray) -> _Surface:
    V, F = mesh.V, mesh.F
    fn = mesh.face_normals_unnormalized
    closed = _closed_oriented(F, mesh.n_vertices)
    if closed and np.einsum("ij,ij->", V[F[:, 0]] - V.mean(axis=0), fn) < 0:  # outward: signed volume positive
        fn = -fn
    seg3, seg_face = _marching_triangles(V, F, values, levels)  # none without levels
    return _Surface(mesh, closed, fn, _vertex_normals(V, F, fn), seg3, seg_face)


def _source_normal(surf: _Surface, s: int) -> np.ndarray | None:
    """The unit normal a ``"front"`` view faces at vertex ``s``: the mean vertex normal within 2 % of the mesh's
    diagonal (one scanned vertex's normal is noisy); the vertex's own where they cancel (a thin part)."""
    V = surf.mesh.V
    near = np.linalg.norm(V - V[s], axis=1) <= 0.02 * np.linalg.norm(np.ptp(V, axis=0))
    n = surf.vnorm[near].sum(axis=0)
    if np.linalg.norm(n) < 0.3 * near.sum():
        n = surf.vnorm[s]
    return _unit(n) if np.linalg.norm(n) > 0 else None


def _occluded(surf: _Surface, s: int, toward: np.ndarray) -> bool:
    """Whether a face hides vertex ``s`` from a viewer in direction ``toward`` (a ray cast, Möller–Trumbore)."""
    V, F = surf.mesh.V, surf.mesh.F
    A = V[F[:, 0]]
    E1, E2 = V[F[:, 1]] - A, V[F[:, 2]] - A
    p = np.cross(toward, E2)
    det = np.einsum("ij,ij->i", E1, p)
    ok = np.abs(det) > 1e-300
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
    tvec = V[s] - A
    u = np.einsum("ij,ij->i", tvec, p) * inv
    q = np.cross(tvec, E1)
    v = (q @ toward) * inv
    t = np.einsum("ij,ij->i", E2, q) * inv
    hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 1e-9 * np.linalg.norm(np.ptp(V, axis=0)))
    hit[np.flatnonzero((F == s).any(axis=1))] = False  # the faces around s meet the ray at its start
    return bool(hit.any())


def _facing_source(surf: _Surface, s: int, focus: np.ndarray, frame: np.ndarray, elev: float, azim: float):
    """``(elev, azim)``: the front view turned (up to 90°) or raised/lowered until vertex ``s`` is in sight."""
    tries = [(elev, azim + d) for d in (0, 30, -30, 60, -60, 90, -90)] + [(60.0, azim), (-30.0, azim)]
    for e, a in tries:
        toward = _rotation(e, a, frame)[2]
        if toward @ focus > 0 and not _occluded(surf, s, toward):
            return e, a % 360.0
    return elev, azim


def _up_name(up: np.ndarray) -> str:
    k = int(np.argmax(np.abs(up)))
    if abs(abs(up[k]) - 1.0) < 1e-12:
        return ("−" if up[k] < 0 else "+") + "xyz"[k]
    return "(" + ", ".join(f"{x:.2f}" for x in up) + ")"


def _panel_cameras(surf: _Surface, marks: np.ndarray, view: Any, up: Any) -> list[tuple[np.ndarray, str]]:
    """One ``(rotation (3, 3), caption)`` per panel of ``view`` (:func:`~cvxgeodesic.evaluation.camera.view_list`)."""
    V = surf.mesh.V
    u = up_vector(V, up)
    frame = _frame(u)
    s = int(marks[0]) if marks.size else None
    focus = _source_normal(surf, s) if s is not None else None
    out = []
    for spec in view_list(view):
        if isinstance(spec, tuple):
            (elev, azim), label = spec, ""
        else:
            elev, azim = _front_angles(V, frame, focus)
            if focus is not None:
                elev, azim = _facing_source(surf, s, focus, frame, elev, azim)
            if spec == "back":  # the other side; from below when the front looks down on the source, and so on
                elev, azim = (-elev if abs(elev) > _ELEV else _ELEV), (azim + 180.0) % 360.0
            label = ("facing source " + str(s) if spec == "front" else "far side") if s is not None else spec
            label += ": "
        out.append((_rotation(elev, azim, frame), f"{label}elev {elev:.0f}°, azim {azim:.0f}°, up {_up_name(u)}"))
    return out


def _render_surface(ax, surf: _Surface, values, R, *, cmap, norm, marks, ambient=0.38, paths=()):
    """Draw the shaded, colour-mapped surface, its isolines and marked vertices seen through ``R`` (rows: screen
    right, screen up, towards the viewer) into ``ax``."""
    from matplotlib.collections import LineCollection

    mesh, closed, fn, vnorm = surf.mesh, surf.closed, surf.fn, surf.vnorm
    V, F = mesh.V, mesh.F
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
    seg3, seg_face = surf.seg3, surf.seg_face
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


def _figsize(n: int, show_colorbar: bool) -> tuple[float, float]:
    """The figure of ``n`` panels side by side, each as wide as the one of a one-panel picture."""
    return _FIGSIZE[0] + (n - 1) * _FIGSIZE[0] * (0.80 if show_colorbar else 0.98), _FIGSIZE[1]


def _layout(fig, show_colorbar: bool, title, n: int = 1):
    """``n`` picture axes side by side (a caption line under each when there are several) and the colour bar's."""
    top = 0.90 if title else 0.97
    s = _FIGSIZE[0] / fig.get_figwidth()  # figure fractions of the one-panel layout
    pw = (0.80 if show_colorbar else 0.98) * s
    bottom = 0.02 if n == 1 else 0.07
    axes = [fig.add_axes((0.01 * s + i * pw, bottom, pw, top - bottom)) for i in range(n)]
    cax = fig.add_axes((1.0 - 0.16 * s, 0.15, 0.03 * s, (top - 0.02) * 0.78)) if show_colorbar else None
    if title:
        fig.suptitle(str(title), y=0.975, fontsize=12)
    return axes, cax


def _draw_panels(fig, axes, surf: _Surface, values, cameras, **kwargs) -> None:
    """One view of ``cameras`` (:func:`_panel_cameras`) into each of ``axes``, captioned when there are several."""
    for ax, (R, caption) in zip(axes, cameras, strict=True):
        _render_surface(ax, surf, values, R, **kwargs)
        if len(axes) > 1:
            x0, _, w, _ = ax.get_position(original=True).bounds
            fig.text(x0 + w / 2, 0.02, caption, ha="center", va="bottom", fontsize=8, color="0.3")


def plot_field(
    mesh: MeshLike,
    values: ArrayLike | GeodesicResult | Field,
    path: str | os.PathLike,
    *,
    isolines: int | ArrayLike | None = 20,
    title: str | None = None,
    cmap: Any = "viridis",
    view: Any = None,
    up: Any = "auto",
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
    values : (n,) array_like of float, GeodesicResult or Field
        One value per vertex (e.g. a distance field), or a result of a solve on this mesh (or its
        :attr:`~cvxgeodesic.results.GeodesicResult.field`). Vertex values are drawn linearly across each face; a
        field that is not linear in its faces (order 2, ``resolution=``) is also asked at every edge's midpoint
        and drawn on the faces split in four there, so that its isolines show its curves (up to
        :data:`MAX_SAMPLED_FACES` faces, above which a face is about a pixel). ``inf`` / ``NaN`` (unreachable)
        vertices are drawn light grey and carry no isolines.
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
    view : str, (elev, azim) tuple of float, or a list of them, optional
        The panels, side by side, sharing one colour bar. Default ``["front", "back"]``: ``"front"`` faces the
        first of ``sources`` (the mean normal around it, turned up to 90° or raised until no part of the surface
        hides it), without sources it is a 3/4 view (along the thinnest principal axis across ``up``, turned 35°
        and raised 15°); ``"back"`` is the front turned 180° about ``up``: the far side of the field, where its
        ridge lies. ``(elev, azim)``: the camera direction in degrees, ``elev`` above the plane across ``up`` and
        ``azim`` about ``up`` (for ``up="z"`` matplotlib's ``mplot3d`` convention: from ``+x`` towards ``+y``; for
        ``"y"`` from ``+z`` towards ``+x``; for ``"x"`` from ``+y`` towards ``+z``). Each panel of several is
        captioned with its ``elev`` and ``azim``, so a view can be drawn again on its own. At most 4 panels.
    up : {"auto", "x", "y", "z", "-x", "-y", "-z"} or (3,) array_like of float, default "auto"
        The world direction drawn upwards. ``"auto"``: away from the flat, axis-aligned end of the convex hull the
        model stands on (feet, a base); without one ``+y`` (the OBJ convention), ``+z`` where ``y`` is the mesh's
        thinnest principal axis (:func:`~cvxgeodesic.evaluation.camera.up_vector`, which says how it was checked).
    vmin, vmax : float, optional
        Colour range; default the finite minimum and maximum of ``values``.
    show_colorbar : bool, default True
        Draw a colour bar on the right.
    dpi : float, default 150
        Resolution; one panel makes a PNG of ``6.4·dpi × 5.4·dpi`` pixels (960 × 810 at 150 dpi),
        each further panel adds ``5.12·dpi`` pixels of width (``6.27·dpi`` without the colour bar): the default
        two panels are 1728 × 810 at 150 dpi.
    colorbar_label : str, optional
        Label of the colour bar.
    sources : int or (k,) array_like of int, optional
        Vertices to mark with a red dot (where visible); the ``"front"`` view faces the first of them.
    paths : sequence of (k, 3) float array_like, optional
        Polylines on the surface (e.g. :func:`cvxgeodesic.geodesic_path`), drawn on top in red.

    Returns
    -------
    pathlib.Path
        The written file.

    Raises
    ------
    ValueError
        A :class:`~cvxgeodesic.errors.ParameterError` (a ``ValueError``) if ``view`` or ``up`` is malformed,
        ``values`` does not have shape ``(n,)`` (or is a field of another mesh), ``path`` does not end in ``.png``
        or cannot be written (its directory does not exist), ``dpi`` is out of range or a source index is out of
        range.

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

    mesh, vals, marks, p, dpi = _surface_inputs(mesh, values, "values", sources, path, dpi, field=True)
    views = view_list(view)
    up_vector(mesh.V, up)  # checked before the work
    cm = cmap if isinstance(cmap, Colormap) else colormaps[cmap]
    lo, hi = _finite_range(vals, vmin, vmax)
    levels = _isolevels(isolines, lo, hi)
    norm = Normalize(lo, hi, clip=True)

    surf = _surface(mesh, vals, levels)
    cameras = _panel_cameras(surf, marks, views, up)
    fig = _new_figure(dpi, _figsize(len(cameras), show_colorbar))
    axes, cax = _layout(fig, show_colorbar, title, len(cameras))
    _draw_panels(fig, axes, surf, vals, cameras, cmap=cm, norm=norm, marks=marks, paths=paths)
    if cax is not None:
        cb = fig.colorbar(ScalarMappable(norm=Normalize(lo, hi), cmap=cm), cax=cax, label=colorbar_label or "")
        if levels.size and levels.size <= 60:
            cb.ax.hlines(levels, 0, 1, colors="black", linewidths=0.4, alpha=0.6)
    _save_atomic(fig, p)
    return p


def plot_error_map(mesh, rel_error, path, *, title=None, vmax=None, view=None, up="auto", dpi=150,
                   sources=None) -> Path:
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
    view : str, (elev, azim) tuple of float, or a list of them, optional
        The panels, as in :func:`plot_field` (default: facing the first source, and the far side).
    up : str or (3,) array_like of float, default "auto"
        The world direction drawn upwards, as in :func:`plot_field`.
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
    views = view_list(view)
    up_vector(mesh.V, up)  # checked before the work
    fin = err[np.isfinite(err)]
    if vmax is None:
        vmax = float(np.percentile(fin, 99.0)) if fin.size else 1.0
    vmax = float(vmax)
    if not np.isfinite(vmax) or vmax <= 0:
        vmax = float(fin.max()) if fin.size and fin.max() > 0 else 1.0
    cm = colormaps["inferno_r"]
    norm = Normalize(0.0, vmax, clip=True)

    surf = _surface(mesh, err, np.empty(0))
    cameras = _panel_cameras(surf, marks, views, up)
    fig = _new_figure(dpi, _figsize(len(cameras), True))
    axes, cax = _layout(fig, True, title, len(cameras))
    # light shading only: dark shading would read as large error on this colour map
    _draw_panels(fig, axes, surf, err, cameras, cmap=cm, norm=norm, ambient=0.78, marks=marks)
    ax = axes[0]
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
