"""Baseline distances inside tetrahedral meshes: Dijkstra on the edges and the heat method (issue 26).

The same shape as the surface baselines (:mod:`cvxgeodesic.baselines.base`): the constructor does
the per-mesh work (timed as ``setup_time``), ``solve(sources)`` returns ``(d, info)``. Sources may
be

- vertex indices (an int or a sequence),
- :class:`~cvxgeodesic.mesh.tet_locate.VolumePoint` objects (points inside tetrahedra), alone or
  mixed with vertex indices in one sequence,
- the string ``"boundary"``: the distance to the boundary surface (wall distance);
- :class:`~cvxgeodesic.sources_tet.BoundaryFaces`: the distance to part of the boundary surface.

(:func:`~cvxgeodesic.sources_tet.resolve_tet_sources`, re-exported here.)

Vertices not connected to any source get ``np.inf``.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components, dijkstra

from ..errors import CvxGeodesicError, SolverError
from ..linalg import analyse
from ..mesh.tetmesh import DEGENERATE_TET_TOL, as_tetmesh
from ..mesh.trimesh import unit_mesh
from ..operators.gradient import gradient_blocks as tet_gradient_blocks
from ..operators.laplacian import barycentric_mass as tet_mass_matrix
from ..operators.laplacian import cotan_stiffness as tet_stiffness
from ..operators.laplacian import divergence as tet_divergence
from ..sources import SourceSet as TetSources
from ..sources import resolve_sources as resolve_tet_sources
from ..validation import check_number

__all__ = ["DEFAULT_TET_T_COEF", "TET_BASELINES", "TetBaselineSolver", "TetDijkstraBaseline", "TetHeatBaseline",
           "TetSources", "resolve_tet_sources"]

#: Diffusion time of :class:`TetHeatBaseline` in units of the squared mean edge length (Crane et al.'s ``t = h²``).
DEFAULT_TET_T_COEF = 1.0


class TetBaselineSolver:
    """Base class of the tetrahedral baselines: :meth:`_setup` once, :meth:`_solve` per source set.

    Parameters
    ----------
    mesh : TetMesh or (V, T) tuple
        ``V`` (n, 3) float, ``T`` (k, 4) int.

    Attributes
    ----------
    name : str
        Method name (key of :data:`TET_BASELINES`).
    library : str
        What does the work (``info["solver"]``).
    mesh : TetMesh
    setup_time : float
        Seconds spent in the constructor.
    notes : list of str
        What the set-up left out or changed (copied into every ``info["notes"]``).
    """

    name: str = ""
    library: str = ""

    def __init__(self, mesh: Any):
        self.mesh = as_tetmesh(mesh)
        self.notes: list[str] = []
        t0 = time.perf_counter()
        with self._library_errors("setup"):
            self._setup()
        self.setup_time = time.perf_counter() - t0

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.mesh!r})"

    def _library_errors(self, what: str):
        return _LibraryErrors(self, what)

    def _setup(self) -> None:
        """Per-mesh precomputation."""

    def _solve(self, src: TetSources) -> tuple[np.ndarray, dict]:
        raise NotImplementedError

    def solve(self, sources: Any) -> tuple[np.ndarray, dict]:
        """Distance from the nearest source to every vertex.

        Parameters
        ----------
        sources : int, VolumePoint, "boundary", or sequence of int and VolumePoint
            See :func:`resolve_tet_sources`.

        Returns
        -------
        d : (n,) float64 ndarray
            ``np.inf`` where no source is reachable.
        info : dict
            ``method``, ``solver``, ``status`` (``"optimal"``), ``iterations`` (0), ``solve_time``,
            ``setup_time``, ``n_sources``, ``notes`` (list of str), plus method-specific keys.

        Raises
        ------
        SourceError
            Invalid sources.
        SolverError
            The computation failed or returned non-finite values where a source is reachable.
        """
        src = resolve_tet_sources(self.mesh, sources)
        t0 = time.perf_counter()
        with self._library_errors("solve"):
            d, extra = self._solve(src)
        solve_time = time.perf_counter() - t0
        reach = self.mesh.connected_to(src.seed_vertices(self.mesh))
        d = np.asarray(d, dtype=np.float64).reshape(-1)
        d[~reach] = np.inf
        bad = reach & ~np.isfinite(d)
        if bad.any():
            raise SolverError(f"baseline {self.name!r} returned {int(bad.sum())} non-finite distances at vertices "
                              f"connected to a source (first: vertex {int(np.flatnonzero(bad)[0])})",
                              solver=self.library, status="bad_output")
        info = {"method": self.name, "solver": self.library, "status": "optimal", "iterations": 0,
                "solve_time": solve_time, "setup_time": self.setup_time, "n_sources": src.count,
                "notes": list(self.notes)}
        info["notes"] += extra.pop("notes", [])
        info.update(extra)
        return d, info


class _LibraryErrors:
    """Turn any failure but our own errors into a :class:`SolverError` naming the baseline and the mesh."""

    def __init__(self, solver: TetBaselineSolver, what: str):
        self.solver, self.what = solver, what

    def __enter__(self):
        return self

    def __exit__(self, kind, exc, tb):
        if exc is None or isinstance(exc, CvxGeodesicError) or not isinstance(exc, Exception):
            return False
        s = self.solver
        raise SolverError(f"baseline {s.name!r}: {self.what} failed on {s.mesh.name}: {type(exc).__name__}: {exc}",
                          solver=s.library, status="error") from exc


class TetDijkstraBaseline(TetBaselineSolver):
    """Shortest paths along the edges of a tetrahedral mesh (``scipy.sparse.csgraph.dijkstra``).

    An upper bound of the distance inside the solid that does not converge under refinement: on a
    Kuhn grid the edge directions are the axes, the face diagonals and the cube diagonal, so the
    path length overestimates the straight distance by up to about 8 % between those directions.
    A point source is joined to the corners of its tetrahedron by straight segments; the boundary
    source starts from every boundary vertex. Several sources: exactly the minimum of single runs.

    Parameters
    ----------
    mesh : TetMesh or (V, T) tuple

    Examples
    --------
    >>> from cvxgeodesic.mesh.tet_generate import tet_box
    >>> d, info = TetDijkstraBaseline(tet_box(2)).solve(0)
    >>> round(float(d[26]), 6)  # the opposite corner: two cube diagonals of length sqrt(3)/2
    1.732051
    """

    name = "dijkstra"
    library = "scipy.sparse.csgraph.dijkstra"

    def _setup(self) -> None:
        self._graph = self.mesh.vertex_adjacency

    def _solve(self, src: TetSources) -> tuple[np.ndarray, dict]:
        mesh, n = self.mesh, self.mesh.n_vertices
        starts = [src.fixed_vertices(mesh)]
        graph = self._graph
        if src.points:
            # one extra node per point, joined to its tetrahedron's corners by straight segments; a point at a vertex
            # is that vertex (a zero-weight arc would vanish from the sparse graph)
            rows: list[int] = []
            cols: list[int] = []
            w: list[float] = []
            virtual: list[int] = []
            for p in src.points:
                corners = p.vertices(mesh)
                dist = np.linalg.norm(mesh.V[corners] - p.position(mesh), axis=1)
                if dist.min() == 0.0:
                    starts.append(corners[dist == 0.0][:1])
                    continue
                node = n + len(virtual)
                virtual.append(node)
                rows += [node] * 4
                cols += corners.tolist()
                w += dist.tolist()
            m = n + len(virtual)
            extra = sp.coo_matrix((np.r_[w, w], (np.r_[rows, cols], np.r_[cols, rows])), shape=(m, m))
            graph = (sp.block_diag([graph, sp.csr_matrix((m - n, m - n))]) + extra).tocsr()
            starts.append(np.array(virtual, dtype=np.int64))
        idx = np.unique(np.concatenate(starts)).astype(np.int64)
        d = dijkstra(graph, directed=False, indices=idx, min_only=True)
        return np.asarray(d[:n], dtype=np.float64), {}


def _factor(K: sp.spmatrix):
    """A Cholesky factor of the SPD matrix ``K`` through :mod:`cvxgeodesic.linalg`, and the backend's name."""
    K = sp.csc_matrix(K)
    S = analyse(K)
    low = sp.tril(K, format="coo")
    data = np.zeros(S.nnz)
    np.add.at(data, S.positions(low.row, low.col), low.data)
    return S.factorize(data), S.backend


def _pinned(K: sp.spmatrix, pinned: np.ndarray) -> sp.csc_matrix:
    """``K`` with the rows and columns of ``pinned`` replaced by those of the identity."""
    keep = np.ones(K.shape[0])
    keep[pinned] = 0.0
    D = sp.diags(keep)
    return sp.csc_matrix(D @ K @ D + sp.diags(1.0 - keep))


class TetHeatBaseline(TetBaselineSolver):
    """The heat method (Crane, Weischedel, Wardetzky 2013) on tetrahedra, with the P1 operators of
    :mod:`cvxgeodesic.operators.tet`.

    1. Heat flow for a time ``t = t_coef · h²`` (``h`` the mean edge length), one backward Euler step:
       ``(M + t L) u = u₀`` with the lumped mass ``M`` and the cotangent stiffness ``L``; ``u₀`` is 1 at
       each source vertex, the barycentric weights at a point source's corners, the boundary area
       around each boundary vertex for ``"boundary"``.
    2. The unit field ``X = −∇u / |∇u|`` per tetrahedron (0 where ``∇u`` vanishes: heat that
       underflowed far away, recorded in the notes).
    3. The Poisson equation ``L φ = Gᵀ diag(vol) X``. One source: solved with one pinned vertex per
       component (factored once in the set-up) and shifted so that the source is at 0 (a point
       source: so that the mean of ``φ − |v − p|`` over its tetrahedron's corners is 0). Several
       sources or the boundary: solved with the exact local values fixed (0 at vertex and
       boundary sources, ``|v − p|`` at a point's corners), which factors the reduced matrix at
       every solve.

    Degenerate tetrahedra (:meth:`~cvxgeodesic.mesh.tetmesh.TetMesh.degenerate_tets` at ``1e-3``)
    are left out of both operators, recorded in :attr:`notes`. Both factorizations go through
    :mod:`cvxgeodesic.linalg` (PARDISO, CHOLMOD or SuperLU, whichever is available).

    The field smooths the ridges (cut locus) and is not exact next to the sources; it converges
    under refinement (tested on a box against ``|x − s|`` and on a ball against ``1 − r``).

    Everything is computed on the mesh divided by the power of two of
    :func:`~cvxgeodesic.mesh.tetmesh.unit_tetmesh` and the field multiplied back (exact), so a mesh scaled
    by ``s`` gives ``s`` times the field: measured before, the heat underflowed on a box 1e45 across and
    the field came back 0.

    Parameters
    ----------
    mesh : TetMesh or (V, T) tuple
    t_coef : float, default 1.0
        Diffusion time in units of the squared mean edge length.

    Raises
    ------
    ParameterError
        ``t_coef`` not a positive finite number.
    """

    name = "heat"
    library = "cvxgeodesic heat method (P1 tetrahedra)"

    def __init__(self, mesh: Any, *, t_coef: float = DEFAULT_TET_T_COEF):
        self.t_coef = check_number(t_coef, "t_coef", low=0, low_open=True)
        super().__init__(mesh)

    def _setup(self) -> None:
        mesh, self.scale = unit_mesh(self.mesh)
        self._unit = mesh
        deg = mesh.degenerate_tets(DEGENERATE_TET_TOL)
        keep = np.ones(mesh.n_tets, dtype=bool)
        keep[deg] = False
        if deg.size:
            self.notes.append(f"{mesh.name}: heat method: left out {deg.size} degenerate tetrahedra (smallest altitude "
                              f"below {DEGENERATE_TET_TOL:g} of the longest edge; first: tet {int(deg[0])})")
        self._keep = keep
        self._blocks = tet_gradient_blocks(mesh)
        self._blocks[~keep] = 0.0
        L = tet_stiffness(mesh, cells=keep, blocks=self._blocks)
        mass = tet_mass_matrix(mesh, cells=keep).diagonal()
        self.t = self.t_coef * mesh.mean_edge_length ** 2  # on the unit mesh (info["t"] is in the mesh's units)
        idle = mass <= 0  # in no kept tetrahedron: u = 0 and φ = 0 there (d = inf: unreachable)
        self._L = L
        self._idle = idle
        A = sp.diags(mass + idle) + self.t * L
        self._heat, self.backend = _factor(A)
        # the Neumann problem, one pinned vertex per component of the kept tetrahedra's graph
        _, labels = connected_components(abs(L) + sp.diags(idle.astype(float)), directed=False)
        _, first = np.unique(labels, return_index=True)
        self._labels = labels
        self._poisson = _factor(_pinned(L, first))[0]
        self._pins = first

    def _unit_field(self, u0: np.ndarray, notes: list[str]) -> np.ndarray:
        u = self._heat(u0)
        g = np.einsum("tij,tj->ti", self._blocks, u[self._unit.T])
        norm = np.linalg.norm(g, axis=1)
        ok = (norm > 0) & np.isfinite(norm) & self._keep
        X = np.zeros_like(g)
        X[ok] = -g[ok] / norm[ok, None]
        flat = int(np.count_nonzero(~ok & self._keep))
        if flat:
            notes.append(f"{self.mesh.name}: heat method: the heat gradient is zero on {flat} tetrahedra (underflow "
                         "far from the sources, or unreached components); their unit field is set to 0")
        return X

    def _solve(self, src: TetSources) -> tuple[np.ndarray, dict]:
        mesh = self._unit  # the sources are indices and barycentric coordinates: the same on it
        notes: list[str] = []
        u0 = np.zeros(mesh.n_vertices)
        u0[src.vertices] = 1.0
        for p in src.points:
            np.add.at(u0, p.vertices(mesh), p.bary)
        if src.faces.size:
            B = src.face_triangles(mesh)
            area = 0.5 * np.linalg.norm(np.cross(mesh.V[B[:, 1]] - mesh.V[B[:, 0]], mesh.V[B[:, 2]] - mesh.V[B[:, 0]]),
                                        axis=1)
            np.add.at(u0, B.ravel(), np.repeat(area / 3.0, 3))
        u0[self._idle] = 0.0
        X = self._unit_field(u0, notes)
        b = tet_divergence(mesh, X, cells=self._keep, blocks=self._blocks)
        if src.count == 1 and not src.faces.size:
            b[self._pins] = 0.0
            phi = self._poisson(b)
            if src.vertices.size:
                phi -= phi[src.vertices[0]]
            else:
                # the exact distances |v − p| at the point's corners fix the offset (mean): 7.4 % mean error against
                # 10.3 % for φ(p) = 0 on a jittered 8³ box (the heat field is rounded off at its source)
                corners, exact = src.local_values(mesh)
                phi -= float(np.mean(phi[corners] - exact))
            mode = "neumann"
        else:
            fixed, values = src.local_values(mesh)
            phi = self._dirichlet(b, fixed, values)
            mode = "dirichlet"
        phi = self._fill_idle(phi, notes)
        at = src.local_values(mesh)
        return phi * self.scale, {"t_coef": self.t_coef, "t": self.t * self.scale**2, "poisson": mode,
                                  "backend": self.backend, "notes": notes,
                                  "max_abs_at_sources": float(np.abs(phi[at[0]] - at[1]).max()) * self.scale}

    def _fill_idle(self, phi: np.ndarray, notes: list[str]) -> np.ndarray:
        """Vertices of left-out tetrahedra only: the shortest edge step from a solved neighbour (one pass)."""
        lone = np.flatnonzero(self._idle & self._unit.referenced)
        if lone.size == 0:
            return phi
        A = self._unit.vertex_adjacency[lone].tocoo()
        ok = ~self._idle[A.col]
        best = np.full(lone.size, np.inf)
        np.minimum.at(best, A.row[ok], phi[A.col[ok]] + A.data[ok])
        phi = phi.copy()
        phi[lone] = best
        notes.append(f"{self.mesh.name}: heat method: {lone.size} vertices are only in left-out tetrahedra; their "
                     "distance is the shortest edge from a neighbour")
        return phi

    def _dirichlet(self, b: np.ndarray, fixed: np.ndarray, values: np.ndarray) -> np.ndarray:
        """``L φ = b`` with ``φ[fixed] = values`` (and one pin in each component without a fixed vertex)."""
        L = self._L
        has_fixed = np.zeros(self._labels.max() + 1, dtype=bool)
        has_fixed[self._labels[fixed]] = True
        pins = np.union1d(fixed, self._pins[~has_fixed])
        phi = np.zeros(L.shape[0])
        phi[fixed] = values
        rhs = b - L @ phi
        rhs[pins] = phi[pins]
        return _factor(_pinned(L, pins))[0](rhs)


TET_BASELINES: dict[str, type[TetBaselineSolver]] = {cls.name: cls for cls in (TetDijkstraBaseline, TetHeatBaseline)}
"""Tetrahedral baseline classes by method name: ``"dijkstra"``, ``"heat"``."""
