"""Common interface of the baseline distance methods, on triangle and tetrahedral meshes.

Every baseline is a stateful class: the constructor does all per-mesh
precomputation (and records its duration in ``setup_time``), ``solve`` computes
the distance from the sources the mesh's dimension takes (vertices; points,
curves and the boundary of a surface where the library can; volume points and
boundary faces inside a volume) and checks the field. The convex-optimization
methods of the library expose the same shape of result, so evaluation code
treats every method alike::

    solver = BASELINES["exact"](mesh)
    d, info = solver.solve(np.array([0]))

The surface libraries are wrapped as below; inside a volume Dijkstra runs on the
edge graph and the heat method on the library's own P1 operators.

Components
----------
The libraries wrapped here behave badly on meshes with several connected
components (potpourri3d fills unreachable components with finite garbage and
drops unreferenced vertices from its output; pygeodesic refuses meshes with
unreferenced vertices). :class:`ComponentwiseSolver` therefore builds one
library solver per connected component (a submesh with local indices), runs
only the components that contain a source and scatters the result back.
Vertices in components without a source, and unreferenced vertices (in no
face; each is its own component), get ``np.inf``.

Scale and orientation
---------------------
The libraries have absolute tolerances (pygeodesic returned infinite distances
on a sphere of radius 1e-15 and 24x too small ones at 1e-30), so
:class:`ComponentwiseSolver` hands them the coordinates divided by the power of
two of :func:`~cvxgeodesic.mesh.simplex.unit_scale` and multiplies the fields
back: exact, so ``d(s V) = s d(V)`` for every ``s`` the mesh check accepts. A
method whose library depends on the face orientation (``orient = True``: fast
marching) gets the faces oriented consistently
(:func:`~cvxgeodesic.mesh.orient.orient_faces`), recorded in :attr:`notes`
with a :class:`~cvxgeodesic.errors.MeshRepairWarning`.
"""

from __future__ import annotations

import importlib
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..errors import (
    CvxGeodesicError,
    MeshError,
    MeshRepairWarning,
    NonManifoldError,
    ParameterError,
    SolverError,
    SourceError,
    warn_user,
)
from ..mesh.convert import MeshLike, as_mesh
from ..mesh.orient import Orientation, orient_faces
from ..mesh.reference import ReferenceSimplex
from ..mesh.simplex import SimplexMesh, unit_scale
from ..mesh.trimesh import TriMesh
from ..sources import SourceSet, resolve_sources


class BaselineSolver:
    """Base class of the baseline distance methods, on triangle and tetrahedral meshes.

    Subclasses implement :meth:`_setup` (per-mesh precomputation) and :meth:`_solve` (one distance
    computation). Which dimensions a method takes is in :mod:`cvxgeodesic.capabilities`.

    Parameters
    ----------
    mesh : TriMesh, TetMesh, or (V, F) / (V, T) tuple
        ``V`` (n, 3) float, ``F`` (m, 3) int triangles or ``T`` (k, 4) int tetrahedra
        (:func:`~cvxgeodesic.mesh.convert.as_mesh`).

    Attributes
    ----------
    name : str
        Method name used as key of :data:`cvxgeodesic.baselines.BASELINES`.
    library : str
        The library function doing the work (reported as ``info["solver"]``).
    cells : tuple of ReferenceSimplex, or None
        The cell kinds (:attr:`SimplexMesh.reference <cvxgeodesic.mesh.simplex.SimplexMesh.reference>`) the class
        computes on; None: any.
    variants : tuple of type
        Classes of the same method for other cell kinds: calling the class on a mesh of such cells builds the first
        variant whose :attr:`cells` hold the mesh's (the heat method inside a volume), else the class itself.
    source_sets : bool
        True: ``_solve`` takes the resolved :class:`~cvxgeodesic.sources.SourceSet` of any source (the class reads
        points and facets itself: the volume baselines). False: ``_solve`` takes vertex indices and
        ``_solve_sources`` the points, curves and boundary, where the library can.
    supports_multiple_sources : bool
        Whether the library computes the distance to a set of sources in one
        run (otherwise the class takes the minimum over single-source runs).
    mesh : TriMesh or TetMesh
    dim : {2, 3}
        The simplex dimension of ``mesh``.
    setup_time : float
        Seconds spent in the constructor.
    notes : list of str
        What the set-up changed or left out (the faces it reoriented, the degenerate tetrahedra it left out),
        copied into every ``info["notes"]``.

    Raises
    ------
    ParameterError
        A library of triangles on a tetrahedral mesh (which methods take which mesh: the capability table, checked at
        the API edge; this is the class's own argument check for a direct user).
    """

    name: str = ""
    library: str = ""
    supports_multiple_sources: bool = True
    cells: tuple[ReferenceSimplex, ...] | None = None
    variants: tuple[type[BaselineSolver], ...] = ()
    source_sets: bool = False

    def __new__(cls, mesh: MeshLike = None, *args: Any, **kwargs: Any) -> BaselineSolver:
        if cls.variants and mesh is not None:  # (no mesh: unpickling, which builds the pickled class)
            kind = as_mesh(mesh).reference
            cls = next((v for v in cls.variants if v.cells is None or kind in v.cells), cls)
        return super().__new__(cls)

    def __init__(self, mesh: MeshLike):
        self.mesh: Any = as_mesh(mesh)
        self.dim = self.mesh.dim
        if self.cells is not None and self.mesh.reference not in self.cells:
            takes = " and ".join(c.words.meshes for c in self.cells)
            raise ParameterError(f"baseline {self.name!r} takes {takes} only ({self.library} is a surface "
                                 f"algorithm); {self.mesh.name} holds {self.mesh.reference.words.many}")
        self.notes: list[str] = []
        t0 = time.perf_counter()
        with _library_errors(self, "setup failed on"):
            self._setup()
        self.setup_time = time.perf_counter() - t0

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.mesh!r})"

    # -- to override ------------------------------------------------------------------------------------------
    def _setup(self) -> None:
        """Per-mesh precomputation (called once by the constructor)."""

    def _solve(self, sources: Any) -> tuple[np.ndarray, dict]:
        """Distance from validated sources: a (k,) int64 array of vertices, or the
        :class:`~cvxgeodesic.sources.SourceSet` of a class with :attr:`source_sets`. Returns ``(d, extra_info)``."""
        raise NotImplementedError

    def _solve_sources(self, ss: SourceSet) -> tuple[np.ndarray, dict]:
        """Distance from a surface's points, curves or boundary (validated): the boundary's vertices here (the
        capability table refuses points and curves at the API edge; a direct user gets this class's own check); the
        classes whose library takes points override it (:mod:`~cvxgeodesic.baselines.points`)."""
        if not ss.boundary and (ss.point_faces.size or ss.segment_faces.size):
            raise SourceError(f"baseline {self.name!r} takes vertex sources and 'boundary' only ({self.library} "
                              "computes from vertices)")
        d, extra = self._solve(ss.vertices)
        return d, {**extra, "sources": "boundary vertices"}

    # -- public -----------------------------------------------------------------------------------------------
    def solve(self, sources: Any) -> tuple[np.ndarray, dict]:
        """Geodesic distance from the nearest of ``sources`` to every vertex.

        Parameters
        ----------
        sources : int, (k,) int array_like, or the dimension's other sources
            Source vertex indices (unique, in ``[0, n)``, ``k >= 1``) or, on a surface, anything
            :func:`~cvxgeodesic.sources.resolve_sources` takes (SurfacePoints, SurfaceCurves, ``"boundary"``:
            where the library can, :mod:`~cvxgeodesic.baselines.points`); inside a volume anything
            :func:`~cvxgeodesic.sources.resolve_sources` takes.

        Returns
        -------
        d : (n,) float64 ndarray
            Distance of each vertex; ``np.inf`` where no source is reachable.
        info : dict
            ``solver`` (library used), ``status`` (``"optimal"``), ``iterations``
            (0: not iterative), ``solve_time`` and ``setup_time`` (seconds),
            ``method``, ``n_sources``, ``notes`` (list of str), plus method-specific keys.

        Raises
        ------
        SourceError
            Invalid sources.
        SolverError
            If the library fails or returns non-finite values where a source is
            reachable.
        """
        src, seeds, count = self._resolve(sources)
        t0 = time.perf_counter()
        with _library_errors(self, "failed on"):
            # points, curves or the boundary go through the library's point support, unless _solve takes source sets
            by_library = isinstance(src, SourceSet) and not self.source_sets
            d, extra = self._solve_sources(src) if by_library else self._solve(src)
        solve_time = time.perf_counter() - t0
        d = np.array(d, dtype=np.float64).reshape(-1)
        if d.shape != (self.mesh.n_vertices,):
            raise SolverError(
                f"baseline {self.name!r} returned {d.shape[0]} values for {self.mesh.n_vertices} vertices",
                solver=self.library,
                status="bad_output",
            )
        reach = self.mesh.connected_to(seeds)
        d[~reach] = np.inf
        bad = reach & ~np.isfinite(d)
        if bad.any():
            raise SolverError(
                f"baseline {self.name!r} returned {int(bad.sum())} non-finite distances at vertices connected to a "
                f"source (first: vertex {int(np.flatnonzero(bad)[0])})",
                solver=self.library,
                status="bad_output",
            )
        info = {
            "method": self.name,
            "solver": self.library,
            "status": "optimal",
            "iterations": 0,
            "solve_time": solve_time,
            "setup_time": self.setup_time,
            "n_sources": count,
            "notes": [*self.notes, *extra.pop("notes", [])],
        }
        info.update(extra)
        return d, info


    def _resolve(self, sources: Any) -> tuple[Any, np.ndarray, int]:
        """The validated sources (vertex indices, or a SourceSet of points, curves or boundary; always the SourceSet
        for a class with :attr:`source_sets`), the vertices the field spreads from, and how many sources there are."""
        ss = resolve_sources(self.mesh, sources)
        if self.source_sets:
            return ss, ss.seed_vertices(self.mesh), ss.count
        if ss.vertex_only:
            return ss.vertices, ss.vertices, int(ss.vertices.size)
        C = self.mesh.cells
        seeds = np.unique(np.concatenate([ss.vertices, C[ss.point_faces].ravel(), C[ss.segment_faces].ravel()]))
        return ss, seeds.astype(np.int64), int(ss.vertices.size + ss.point_faces.size)


@contextmanager
def _library_errors(solver: BaselineSolver, what: str) -> Iterator[None]:
    """Turn any failure but the library's own errors into a :class:`SolverError` naming the baseline and the mesh:
    a library's exception never escapes bare."""
    try:
        yield
    except CvxGeodesicError:
        raise
    except Exception as exc:
        raise SolverError(f"baseline {solver.name!r}: {what} {solver.mesh.name}: {type(exc).__name__}: {exc}",
                          solver=solver.library, status="error") from exc


#: Vertices connected to at least one source through the edge graph (kept for its old import).
reachable_mask = SimplexMesh.connected_to


def nonmanifold_vertices(mesh: TriMesh) -> np.ndarray:
    """Vertices whose incident faces do not form a single edge-connected fan.

    A vertex where two sheets touch (a "bowtie": two cones sharing their apex)
    is non-manifold even when every edge is manifold. pygeodesic silently
    treats the sheets as disconnected there (the far sheet came back ``inf``
    in a test) and potpourri3d's fast marching refuses such meshes.

    Parameters
    ----------
    mesh : TriMesh

    Returns
    -------
    (k,) int64 ndarray
        Sorted indices of the referenced vertices with more than one fan.
        Unreferenced vertices are not listed.
    """
    F = np.asarray(mesh.cells, dtype=np.int64)
    n, m = mesh.n_vertices, F.shape[0]
    # corner (t, i): vertex F[t, i], whose fan links the two other vertices of t.
    centre = F.ravel()  # (3m,)
    a = F[:, [1, 2, 0]].ravel()
    b = F[:, [2, 0, 1]].ravel()
    # nodes of the fan graph: directed pairs (centre, neighbour), as the keys centre·n + neighbour (a 1-D unique is
    # 20x faster than np.unique(axis=0) on the pairs: 1.4 s on horse's 97K faces); each corner joins (c, a) and (c, b)
    keys = np.concatenate([centre * n + a, centre * n + b])
    uniq, inv = np.unique(keys, return_inverse=True)
    inv = inv.reshape(-1)
    k = 3 * m
    graph = sp.csr_matrix((np.ones(k, dtype=np.int8), (inv[:k], inv[k:])), shape=(len(uniq), len(uniq)))
    n_fans, lab = connected_components(graph, directed=False)
    centre_of_fan = np.empty(n_fans, dtype=np.int64)
    centre_of_fan[lab] = uniq // n  # every node of a fan has the same centre
    return np.flatnonzero(np.bincount(centre_of_fan, minlength=n) > 1).astype(np.int64)


#: The methods that solve non-manifold meshes, for the message of :func:`require_manifold`.
NON_MANIFOLD_METHODS = "a convex formulation (the default 'qcqp-hessian', 'qclp', ...), 'heat' or 'dijkstra'"


def require_manifold(mesh: TriMesh, method: str, alternatives: str = NON_MANIFOLD_METHODS) -> None:
    """Raise :class:`NonManifoldError` unless the mesh is edge- and vertex-manifold.

    Parameters
    ----------
    mesh : TriMesh
    method : str
        Name of the method that needs a manifold mesh (used in the message).
    alternatives : str, default NON_MANIFOLD_METHODS
        Methods that work on the mesh (used in the message).
    """
    if not mesh.is_edge_manifold:
        n_bad = int(np.sum(mesh.edge_cell_counts > 2))
        raise NonManifoldError(
            f"{mesh.name}: method {method!r} needs an edge-manifold mesh, but {n_bad} edges are shared by more "
            f"than two faces; use {alternatives} instead"
        )
    bad = nonmanifold_vertices(mesh)
    if bad.size:
        raise NonManifoldError(
            f"{mesh.name}: method {method!r} needs a manifold mesh, but {bad.size} vertices join several sheets "
            f"(first: vertex {int(bad[0])}); use {alternatives} instead"
        )


def require_orientable(mesh: TriMesh, method: str, orientation: Orientation) -> None:
    """Raise :class:`~cvxgeodesic.errors.MeshError` when part of the mesh cannot be oriented consistently.

    Measured on a Möbius strip (24 × 4 vertices): potpourri3d's fast marching was 11 % of the largest distance off
    the exact field on average (1.3 % on the untwisted band of the same size), whatever the faces' orientation.
    """
    bad = orientation.non_orientable
    if bad.any():
        raise MeshError(
            f"{mesh.name}: method {method!r} needs an orientable surface, but {int(bad.sum())} faces lie on a "
            f"non-orientable piece (a Möbius strip or the like; first: face {int(np.flatnonzero(bad)[0])}); use "
            "'exact', 'heat', 'dijkstra' or a convex formulation instead"
        )


@dataclass
class _Part:
    """One connected component with faces, as a submesh with local vertex indices."""

    vertices: np.ndarray  # (n_c,) global indices of the component's vertices, sorted
    V: np.ndarray  # (n_c, 3) float64
    F: np.ndarray  # (m_c, 3) int64, local indices
    solver: object = None


class ComponentwiseSolver(BaselineSolver):
    """A baseline whose library is run separately on each connected component.

    Subclasses implement :meth:`_build` (library solver for one submesh, from the class ``library`` names,
    imported by the set-up) and :meth:`_run` (distance on one submesh from local source indices). The
    library sees the coordinates divided by :attr:`scale` and, when ``orient``
    is set, the faces of :attr:`orientation` (module docstring).

    Parameters
    ----------
    mesh : TriMesh or (V, F) tuple
        ``V`` (n, 3) float, ``F`` (m, 3) int; edge- and vertex-manifold where ``manifold`` is set.

    Raises
    ------
    NonManifoldError
        ``manifold``: if an edge has more than two faces or a vertex joins several sheets.
    MeshError
        ``orient``: if the surface is not orientable (the message names the methods that work).

    Attributes
    ----------
    scale : float
        The power of two the library's coordinates were divided by (its fields are multiplied by it).
    orientation : Orientation or None
        The consistently oriented faces the library was given (``orient`` only).
    """

    #: The library depends on the faces' orientation: give it consistently oriented faces.
    orient: bool = False
    #: The library needs an edge- and vertex-manifold mesh (:func:`require_manifold`, checked before it is loaded).
    manifold: bool = False

    def _setup(self) -> None:
        module, _, cls = self.library.rpartition(".")
        self._library = getattr(importlib.import_module(module), cls)
        mesh = self.mesh
        if self.manifold:
            require_manifold(mesh, self.name)  # the message names the methods that solve non-manifold meshes
        self.scale = unit_scale(mesh)
        V = mesh.V / self.scale  # exact: a power of two
        F = mesh.cells  # triangles: what the surface libraries take
        self.orientation: Orientation | None = None
        if self.orient:
            self.orientation = orient_faces(mesh.cells, mesh.n_vertices)
            require_orientable(mesh, self.name, self.orientation)
            note = self.orientation.note(mesh.name, f"{self.name!r} ({self.library})")
            if note:
                warn_user(note, MeshRepairWarning)
                self.notes.append(note)
            F = self.orientation.F
        labels = mesh.component_labels
        face_label = labels[F[:, 0]]
        comp_ids = np.unique(face_label)
        self._parts: dict[int, _Part] = {}
        if comp_ids.size == 1 and mesh.referenced.all():
            # the common case: one component, every vertex referenced -> no copy of the faces
            part = _Part(np.arange(mesh.n_vertices), V, np.asarray(F))
            part.solver = self._build(part.V, part.F)
            self._parts[int(comp_ids[0])] = part
            return
        order = np.argsort(face_label, kind="stable")
        bounds = np.searchsorted(face_label[order], comp_ids, side="left").tolist() + [len(order)]
        for j, c in enumerate(comp_ids):
            faces = F[order[bounds[j]:bounds[j + 1]]]
            verts = np.unique(faces)
            local = np.searchsorted(verts, faces)
            part = _Part(verts, np.ascontiguousarray(V[verts]), np.ascontiguousarray(local, dtype=np.int64))
            part.solver = self._build(part.V, part.F)
            self._parts[int(c)] = part

    def _build(self, V: np.ndarray, F: np.ndarray) -> object:
        raise NotImplementedError

    def _run(self, solver: object, local_sources: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def _solve(self, sources: np.ndarray) -> tuple[np.ndarray, dict]:
        labels = self.mesh.component_labels
        d = np.full(self.mesh.n_vertices, np.inf)
        n_runs = 0
        for c in np.unique(labels[sources]):
            part = self._parts.get(int(c))
            src_c = sources[labels[sources] == c]
            if part is None:  # an unreferenced vertex: its own component
                d[src_c] = 0.0
                continue
            local = np.searchsorted(part.vertices, src_c)
            d[part.vertices] = self._run(part.solver, local) * self.scale
            n_runs += 1
        # every library here solves several sources in one run
        return d, {"n_components": len(self._parts), "n_components_solved": n_runs, "multisource": "native"}
