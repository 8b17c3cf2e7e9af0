"""Adapted solves: order 2 on a quadric-decimated copy of the surface, the answer on the user's mesh.

The resolution a distance field needs is not the resolution of the file it came in (issue 43, DESIGN.md §11).
:class:`Adapted` decimates the user's mesh once, in its constructor (quadric error, ``fast-simplification``, the
boundary kept vertex for vertex), and every solve then runs the order-2 strategy (:class:`~.order2.Order2`) on that
copy:

1. **sources at their exact positions**: a source vertex, a source point, becomes a point of the solve mesh at its
   closest point there (never the nearest coarse vertex); ``"boundary"`` is the solve mesh's boundary, which is the
   user's (no edge touching it is collapsed); curves are refused (order 2 takes none);
2. **media** moved to the solve mesh: a per-vertex cost or metric read at each coarse vertex's closest point of the
   user's surface, a per-face one from the user's face closest to each coarse face's centroid;
3. **the answer on the user's mesh**: the P2 field evaluated at each user vertex's closest point of the solve mesh
   (found once); :class:`~cvxgeodesic.mesh.transfer.ProjectedField` answers ``distance_at`` at any point of the user's
   faces the same way, and ``geodesic_path`` descends the vertex values on the user's mesh;
4. **fallbacks**: a mesh that is not edge-manifold, has several components or degenerate faces, or whose copy
   changes its topology (Euler characteristic, components, a non-manifold edge), is solved on itself at order 2,
   with a note (quadric decimation gave NaN fields on a non-manifold mesh, issue 43).

``info.extra["adapted"]`` records the solve mesh, its times and an error estimate (:func:`edge_shortening`).
"""

from __future__ import annotations

import time
from dataclasses import replace
from typing import Any

import numpy as np

from ..errors import ParameterError, SourceError
from ..mesh.closest import closest_point_index
from ..mesh.decimate import simplify_mesh
from ..mesh.locate import SurfacePoint, bary_positions
from ..mesh.transfer import ProjectedField
from ..mesh.trimesh import TriMesh
from ..operators.metric import Medium
from ..results import GeodesicResult, SolveInfo
from ..sources import SourceSet, resolve_sources
from .base import Callback, SolveConfig
from .order2 import Order2

__all__ = ["AUTO_FRACTION", "AUTO_MIN_FACES", "MIN_RESOLUTION_FACES", "RESOLUTIONS", "SIMPLIFIER", "Adapted",
           "edge_shortening", "resolve_resolution"]

#: The named values of ``resolution``; any other is a face count (int) or a fraction of the faces (float).
RESOLUTIONS = ("mesh", "auto")
#: The smallest face count ``resolution`` takes.
MIN_RESOLUTION_FACES = 4
#: ``resolution="auto"``: this fraction of the user's faces (issue 43: at 1/10 order 2 costs what order 1 costs on
#: the user's mesh, with 2-4x less error) ...
AUTO_FRACTION = 0.1
#: ... but never fewer faces than this; a mesh with fewer than ``AUTO_MIN_FACES / AUTO_FRACTION`` faces is solved at
#: this count, and one with at most ``AUTO_MIN_FACES`` on itself (see docs/adapted.md for the measurement).
AUTO_MIN_FACES = 2000
#: How the solve mesh is made (recorded in ``info.extra["adapted"]["simplifier"]``).
SIMPLIFIER = "quadric (fast-simplification, boundary kept)"


def resolve_resolution(resolution: Any, n_faces: int) -> int | None:
    """The solve mesh's target face count for ``resolution``, or None to solve on the mesh itself.

    Parameters
    ----------
    resolution : "mesh", "auto", int or float
        ``"mesh"``: the mesh itself; an int >= :data:`MIN_RESOLUTION_FACES`: that many faces; a float in (0, 1):
        that fraction of the faces; ``"auto"``: :data:`AUTO_FRACTION` of the faces, at least :data:`AUTO_MIN_FACES`.
    n_faces : int
        The user's face count.

    Returns
    -------
    int or None
        None for ``"mesh"``; otherwise the target, which may be at or above ``n_faces`` (then the strategy solves
        on the mesh itself, with a note).

    Raises
    ------
    ParameterError
        Anything else (the message names ``resolution`` and what it takes).
    """
    if isinstance(resolution, str):
        key = resolution.strip().lower()
        if key == "mesh":
            return None
        if key == "auto":
            return max(AUTO_MIN_FACES, int(round(AUTO_FRACTION * n_faces)))
    elif isinstance(resolution, int | np.integer) and not isinstance(resolution, bool | np.bool_):
        if resolution >= MIN_RESOLUTION_FACES:
            return int(resolution)
    elif isinstance(resolution, float | np.floating) and 0 < resolution < 1:
        return max(MIN_RESOLUTION_FACES, int(round(float(resolution) * n_faces)))
    raise ParameterError(f"resolution must be 'mesh', 'auto', a face count >= {MIN_RESOLUTION_FACES} (int) or a "
                         f"fraction of the faces in (0, 1) (float), got {resolution!r}")


def _euler(mesh: TriMesh) -> int:
    return int(mesh.referenced.sum()) - len(mesh.edges) + mesh.n_faces


def _unsuitable(mesh: TriMesh) -> str | None:
    """Why the mesh is not decimated (solved on itself instead), or None."""
    if not mesh.is_edge_manifold:
        return "the mesh is not edge-manifold (quadric decimation can merge its sheets)"
    comps = np.unique(mesh.component_labels[mesh.referenced]).size
    if comps > 1:
        return f"the mesh has {comps} connected components (decimation could merge them)"
    if mesh.degenerate_faces(0.0).size:
        return f"the mesh has {mesh.degenerate_faces(0.0).size} face(s) of zero area"
    return None


def _decimated(mesh: TriMesh, target: int) -> tuple[TriMesh | None, str | None]:
    """The quadric copy of ``mesh`` with about ``target`` faces, or ``(None, why)`` when its topology changed."""
    try:
        coarse = simplify_mesh(mesh, target, method="quadric", preserve_border=True)
    except Exception as exc:  # noqa: BLE001 - any failure of the extension falls back, with its message
        return None, f"the decimation failed ({type(exc).__name__}: {exc})"
    checks = ((not coarse.is_edge_manifold, "the decimated copy has non-manifold edges"),
              (coarse.n_components != 1, f"the decimated copy has {coarse.n_components} components"),
              (_euler(coarse) != _euler(mesh), f"the decimated copy changed the Euler characteristic "
                                               f"({_euler(mesh)} -> {_euler(coarse)})"),
              (coarse.degenerate_faces(0.0).size > 0, "the decimated copy has faces of zero area"))
    for bad, why in checks:
        if bad:
            return None, why
    coarse.simplifier = SIMPLIFIER
    return coarse, None


def _medium_on(medium: Medium | None, mesh: TriMesh, coarse: TriMesh) -> Medium | None:
    """The user's medium moved to the solve mesh: per-vertex values at each coarse vertex's closest user point,
    per-face values of the user face closest to each coarse face's centroid (its normalization kept)."""
    if medium is None:
        return None
    index = closest_point_index(mesh)
    vf, vb, _ = index.query(np.ascontiguousarray(coarse.V))
    cf, _, _ = index.query(np.ascontiguousarray(coarse.V[coarse.F].mean(axis=1)))

    def moved(values: np.ndarray | None, kind: str | None) -> np.ndarray | None:
        if values is None or kind == "constant":
            return values
        if kind == "faces":
            return values[cf]
        return np.einsum("kc,kc...->k...", vb, values[mesh.F[vf]])

    try:
        return Medium(coarse, moved(medium.cost, medium.cost_kind), medium.cost_kind,
                      moved(medium.metric, medium.metric_kind), medium.metric_kind, scale=medium.scale)
    except ParameterError as exc:
        raise ParameterError(f"the metric moved to the {coarse.n_faces}-face solve mesh of resolution= is not "
                             f"positive definite there ({exc}); give resolution='mesh'") from None


def edge_shortening(mesh: TriMesh, positions: np.ndarray) -> float:
    """The error estimate of an adapted solve: how much shorter the user's edges are on the solve mesh.

    Each user edge ``(i, j)`` is compared with the segment between the closest points of its ends on the solve
    mesh: ``Σ (ℓ_ij − |p_i − p_j|) / Σ ℓ_ij`` over the edges. On detailed scans the error of an adapted solve is
    mostly this shortening (issue 43); order 2 adds little on the solve mesh itself.

    Parameters
    ----------
    mesh : TriMesh
        The user's mesh (``n`` vertices).
    positions : (n, 3) float ndarray
        The closest point of each user vertex on the solve mesh.

    Returns
    -------
    float
        A relative length (0 when the solve mesh is the user's).
    """
    E = mesh.edges
    ell = mesh.edge_lengths
    short = np.linalg.norm(positions[E[:, 0]] - positions[E[:, 1]], axis=1)
    total = float(ell.sum())
    return float(np.maximum(ell - short, 0.0).sum() / total) if total > 0 else 0.0


class Adapted:
    """Order-2 solves on a decimated copy of a surface, answered on the surface itself.

    Parameters
    ----------
    config : SolveConfig
        The user's mesh and an order-2 method (:func:`~cvxgeodesic.capabilities.check` passed with
        ``resolution=True``).
    target : int or None
        The solve mesh's face count (:func:`resolve_resolution`); None or at least the mesh's face count: the mesh
        itself, with a note.
    requested : object
        The ``resolution`` the user gave (for the record).

    Attributes
    ----------
    solve_mesh : TriMesh
        The mesh the order-2 program is solved on (the user's when it fell back).
    inner : Order2
        The order-2 strategy on ``solve_mesh``.
    record : dict
        What ``info.extra["adapted"]`` reports for every solve (per-solve times are added).
    """

    def __init__(self, config: SolveConfig, target: int | None, requested: Any = None) -> None:
        t0 = time.perf_counter()
        mesh = config.mesh
        self.config = config
        self.notes: list[str] = list(config.notes)
        self.record: dict[str, Any] = {"resolution": requested, "target_faces": target, "user_faces": mesh.n_faces,
                                       "faces": mesh.n_faces, "simplifier": None, "decimate_time": 0.0,
                                       "fallback": None}
        coarse, why = None, None
        if target is None or target >= mesh.n_faces:
            why = f"the target of {target} faces is not below the mesh's {mesh.n_faces}"
        else:
            why = _unsuitable(mesh)
            if why is None:
                coarse, why = _decimated(mesh, target)
        self.record["decimate_time"] = time.perf_counter() - t0
        if coarse is None:
            self.solve_mesh = mesh
            self.record["fallback"] = why
            self.notes.append(f"resolution={requested!r}: solved on the mesh itself at order 2 ({why})")
            self.inner = Order2(config)
        else:
            self.solve_mesh = coarse
            medium = _medium_on(config.medium, mesh, coarse)
            self.inner = Order2(replace(config.on(coarse, lam=config.lam), medium=medium))
            self.notes.append(f"resolution={requested!r}: solved at order 2 on a {coarse.n_faces}-face copy of the "
                              f"mesh ({mesh.n_faces} faces; {SIMPLIFIER}), the field read at the mesh's vertices")
            self.record.update(faces=coarse.n_faces, simplifier=SIMPLIFIER)
            self._project_vertices()
        self.backend = self.inner.backend
        self.setup_time = time.perf_counter() - t0

    def _project_vertices(self) -> None:
        """Each user vertex's closest point on the solve mesh, the distance to it and the error estimate."""
        mesh = self.config.mesh
        self.vertex_faces, self.vertex_bary, gap = closest_point_index(self.solve_mesh).query(
            np.ascontiguousarray(mesh.V))
        positions = bary_positions(self.solve_mesh, self.vertex_faces, self.vertex_bary)
        self.record.update(max_surface_distance=float(gap[mesh.referenced].max(initial=0.0)),
                           error_estimate=edge_shortening(mesh, positions),
                           error_estimate_method="edge shortening: the user's edges against the segments between "
                                                 "their ends' closest points on the solve mesh")

    @property
    def adapted(self) -> bool:
        """True when the solves run on a decimated copy (False after a fallback)."""
        return self.solve_mesh is not self.config.mesh

    def solve(self, sources: SourceSet, *, callback: Callback | None = None) -> GeodesicResult:
        """Distance field on the user's mesh from sources resolved on it.

        Raises
        ------
        SourceError
            Two sources that fall into one face of the solve mesh (order 2 takes one point per face).
        """
        if not self.adapted:
            res = self.inner.solve(sources, callback=callback)
            res.info.extra["adapted"] = {**self.record, "solve_time": res.info.solve_time, "transfer_time": 0.0,
                                         "error_estimate": 0.0, "error_estimate_method": "solved on the mesh itself"}
            return res
        t0 = time.perf_counter()
        coarse_sources = self._sources(sources)
        try:
            cres = self.inner.solve(coarse_sources, callback=callback)
        except SourceError as exc:
            raise SourceError(f"resolution={self.record['resolution']!r}: on the {self.solve_mesh.n_faces}-face "
                              f"solve mesh, {exc}; give a finer resolution or resolution='mesh'") from None
        t1 = time.perf_counter()
        d = self._on_user_mesh(cres, sources)
        t2 = time.perf_counter()
        return self._result(cres, d, sources, t0, t1, t2)

    def _sources(self, sources: SourceSet) -> SourceSet:
        """The user's sources on the solve mesh, at their positions: vertices and points become the closest points
        there; the boundary stays the boundary (kept by the decimation)."""
        mesh, coarse = self.config.mesh, self.solve_mesh
        if sources.boundary:
            return resolve_sources(coarse, "boundary")
        X = np.concatenate([mesh.V[sources.vertices],
                            np.array([p.position(mesh) for p in sources.distinct_points(mesh)]).reshape(-1, 3)])
        faces, bary, _ = closest_point_index(coarse).query(np.ascontiguousarray(X))
        return resolve_sources(coarse, [SurfacePoint(int(f), b) for f, b in zip(faces, bary, strict=True)])

    def _on_user_mesh(self, cres: GeodesicResult, sources: SourceSet) -> np.ndarray:
        """The solve mesh's field at the user's vertices; 0 at source vertices, inf at vertices of no face."""
        mesh = self.config.mesh
        fld = cres.info.extra["p2_field"]
        d = np.asarray(fld.distance_at(self.vertex_faces, self.vertex_bary), dtype=float)
        d[sources.fixed_vertices(mesh)] = 0.0
        d[~mesh.referenced] = np.inf
        return d

    def _result(self, cres: GeodesicResult, d: np.ndarray, sources: SourceSet, t0: float, t1: float,
                t2: float) -> GeodesicResult:
        ci = cres.info
        mesh = self.config.mesh
        record = {**self.record, "solve_time": t1 - t0, "transfer_time": t2 - t1}
        extra = {k: v for k, v in ci.extra.items() if k != "p2_field"}
        extra.update(adapted=record, p2_field=ProjectedField(mesh, self.solve_mesh, ci.extra["p2_field"], d),
                     solve_mesh=self.solve_mesh)
        info = replace(ci, setup_time=self.setup_time, solve_time=time.perf_counter() - t0,
                       n_unreachable=int(np.isinf(d).sum()), notes=[*self.notes, *ci.notes],
                       extra=extra)
        return GeodesicResult(distance=d, info=info, sources=sources.vertices,
                              source_set=None if sources.vertex_only else sources)
