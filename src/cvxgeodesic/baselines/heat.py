"""The heat method (Crane, Weischedel, Wardetzky 2013): on surfaces via potpourri3d / geometry-central, inside
tetrahedral meshes with the library's own P1 stiffness and mass."""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..linalg import factor_matrix as _factor
from ..mesh.convert import MeshLike
from ..mesh.reference import TETRAHEDRON
from ..mesh.simplex import unit_mesh
from ..mesh.tetmesh import DEGENERATE_TET_TOL, TetMesh
from ..operators.gradient import gradient_blocks
from ..operators.laplacian import barycentric_mass, cotan_stiffness, divergence
from ..validation import check_number
from .base import ComponentwiseSolver

DEFAULT_T_COEF = 1.0
"""Diffusion time ``t = t_coef · h̄²`` with ``h̄`` the mean edge length (potpourri3d's default; Crane et al.'s
``t = h²`` inside volumes)."""


class HeatBaseline(ComponentwiseSolver):
    """The heat method on triangle and tetrahedral meshes (:class:`VolumeHeatBaseline`, which ``HeatBaseline(tetmesh)``
    builds, inside a volume).

    Diffuses heat from the sources for a short time ``t = t_coef · h̄²`` (``h̄``
    the mean edge length), normalizes the gradient of the result and recovers
    the distance by a Poisson solve. The field is smooth across the cut locus
    (it rounds the ridge); its error is largest next to the sources. The
    default ``t_coef = 1.0`` is reported as ``info["t_coef"]``.

    **On a point cloud** (a :class:`~cvxgeodesic.mesh.pointcloud.PointCloud`):
    ``potpourri3d.PointCloudHeatSolver`` on the points of each component of the cloud's triangles (geometry-central
    builds its own intrinsic triangulation of the local fans).

    **On a surface**: ``potpourri3d.MeshHeatMethodDistanceSolver``; relative
    error about 19 % next to the sources on icospheres, almost independent of
    the resolution. With ``use_robust=True`` (default) the library works on an
    intrinsic Delaunay triangulation of the intrinsic tufted cover, so
    non-manifold meshes are accepted. Several sources are solved in one run
    (``compute_distance_multisource``); this is *not* the minimum of
    single-source runs: the heat of all sources is diffused together, which
    smooths the field across the boundary between the sources' Voronoi cells,
    and the field is only shifted as a whole, so with several sources it is
    not exactly 0 at each of them (reported as ``info["max_abs_at_sources"]``;
    about 0.1 edge length on an icosphere). Vertex and boundary sources only.
    Several components are handled by running each component separately
    (the library alone returns finite garbage on unreached components).

    **Inside a volume** (:class:`VolumeHeatBaseline`): the library's own P1 operators
    (:mod:`cvxgeodesic.operators.laplacian`; ``info["solver"]`` is its
    :attr:`~VolumeHeatBaseline.library`), every kind of volume source:

    1. Heat flow for ``t``, one backward Euler step: ``(M + t L) u = u₀`` with the lumped mass ``M`` and
       the cotangent stiffness ``L``; ``u₀`` is 1 at each source vertex, the barycentric weights at a
       point source's corners, the boundary area around each boundary vertex for boundary sources.
    2. The unit field ``X = −∇u / |∇u|`` per tetrahedron (0 where ``∇u`` vanishes: heat that
       underflowed far away, recorded in the notes).
    3. The Poisson equation ``L φ = Gᵀ diag(vol) X``. One source: solved with one pinned vertex per
       component (factored once in the set-up) and shifted so that the source is at 0 (a point
       source: so that the mean of ``φ − |v − p|`` over its tetrahedron's corners is 0). Several
       sources or the boundary: solved with the exact local values fixed (0 at vertex and
       boundary sources, ``|v − p|`` at a point's corners), which factors the reduced matrix at
       every solve.

    Degenerate tetrahedra (:meth:`~cvxgeodesic.mesh.simplex.SimplexMesh.degenerate_cells` at ``1e-3``)
    are left out of both operators, recorded in :attr:`notes`. Both factorizations go through
    :mod:`cvxgeodesic.linalg` (PARDISO, CHOLMOD or SuperLU, whichever is available). The field
    converges under refinement (tested on a box against ``|x − s|`` and on a ball against ``1 − r``).
    It is computed on the mesh divided by a power of two and multiplied back (exact), so a mesh
    scaled by ``s`` gives ``s`` times the field: measured before, the heat underflowed on a box
    1e45 across and the field came back 0.

    Parameters
    ----------
    mesh : TriMesh, TetMesh, or (V, F) / (V, T) tuple
        ``V`` (n, 3) float, ``F`` (m, 3) int or ``T`` (k, 4) int.
    t_coef : float, default 1.0
        Diffusion time in units of the squared mean edge length.
    use_robust : bool, default True
        On a surface: use the intrinsic (tufted-cover, Delaunay) Laplacian. Not used inside a volume.

    Raises
    ------
    ParameterError
        If ``t_coef`` is not a positive finite number.
    """

    name = "heat"
    library = "potpourri3d.MeshHeatMethodDistanceSolver"

    def __init__(self, mesh: MeshLike, *, t_coef: float = DEFAULT_T_COEF, use_robust: bool = True):
        self.t_coef = check_number(t_coef, "t_coef", low=0, low_open=True)
        self.use_robust = bool(use_robust)
        super().__init__(mesh)
        if getattr(self.mesh, "cloud", None) is not None:  # what _build ran (info["solver"])
            self.library = "potpourri3d.PointCloudHeatSolver"

    def _build(self, V: np.ndarray, F: np.ndarray) -> object:
        if getattr(self.mesh, "cloud", None) is not None:  # a PointCloud's soup: the point-cloud heat method
            import potpourri3d as pp3d

            return pp3d.PointCloudHeatSolver(V, t_coef=self.t_coef)
        return self._library(V, F, t_coef=self.t_coef, use_robust=self.use_robust)

    def _run(self, solver, local_sources: np.ndarray) -> np.ndarray:
        if local_sources.size == 1:
            d = solver.compute_distance(int(local_sources[0]))
        else:
            d = solver.compute_distance_multisource([int(s) for s in local_sources])
        return np.asarray(d, dtype=np.float64).reshape(-1)

    def _solve(self, sources: Any) -> tuple[np.ndarray, dict]:
        d, info = super()._solve(sources)
        info.update(t_coef=self.t_coef, use_robust=self.use_robust, max_abs_at_sources=float(np.abs(d[sources]).max()))
        return d, info


def _pinned(K: sp.spmatrix, pinned: np.ndarray) -> sp.csc_matrix:
    """``K`` with the rows and columns of ``pinned`` replaced by those of the identity."""
    keep = np.ones(K.shape[0])
    keep[pinned] = 0.0
    D = sp.diags(keep)
    return sp.csc_matrix(D @ K @ D + sp.diags(1.0 - keep))


class VolumeHeatBaseline(HeatBaseline):
    """The P1 heat method inside a tetrahedral mesh (what ``HeatBaseline(tetmesh)`` builds; the steps are
    :class:`HeatBaseline`'s "Inside a volume"). ``use_robust`` is not used."""

    library = "cvxgeodesic heat method (P1 tetrahedra)"
    cells = (TETRAHEDRON,)
    source_sets = True
    mesh: TetMesh

    def _setup(self) -> None:
        notes = self.notes
        mesh, self.scale = unit_mesh(self.mesh)
        self._unit = mesh
        deg = mesh.degenerate_cells(DEGENERATE_TET_TOL)
        self._keep = keep = np.ones(mesh.n_tets, dtype=bool)
        keep[deg] = False
        if deg.size:
            notes.append(f"{mesh.name}: heat method: left out {deg.size} degenerate tetrahedra (smallest altitude "
                         f"below {DEGENERATE_TET_TOL:g} of the longest edge; first: tet {int(deg[0])})")
        self._blocks = gradient_blocks(mesh)
        self._blocks[~keep] = 0.0
        self._L = L = cotan_stiffness(mesh, cells=keep, blocks=self._blocks)
        mass = barycentric_mass(mesh, cells=keep).diagonal()
        self.t = self.t_coef * mesh.mean_edge_length ** 2  # on the unit mesh (info["t"] is in the mesh's units)
        self._idle = idle = mass <= 0  # in no kept tetrahedron: u = 0 and φ = 0 there (d = inf: unreachable)
        self._heat, self.backend = _factor(sp.diags(mass + idle) + self.t * L)
        # the Neumann problem, one pinned vertex per component of the kept tetrahedra's graph
        _, self._labels = connected_components(abs(L) + sp.diags(idle.astype(float)), directed=False)
        _, self._pins = np.unique(self._labels, return_index=True)
        self._poisson = _factor(_pinned(L, self._pins))[0]

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

    def _solve(self, src: Any) -> tuple[np.ndarray, dict]:
        """The field from a :class:`~cvxgeodesic.sources.SourceSet` (:attr:`source_sets`)."""
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
        b = divergence(mesh, X, cells=self._keep, blocks=self._blocks)
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




HeatBaseline.variants = (VolumeHeatBaseline,)
