"""Coarse-to-fine solves: simplify the mesh, solve on the coarse mesh, transfer the field to the fine mesh.

Used by :class:`~cvxgeodesic.api.GeodesicSolver` with ``multires=True`` (or a
target face count). The pieces:

1. :func:`simplify_mesh`: edge-collapse decimation to a target face count, by
   default shortest edge first with midpoint placement (libigl ``decimate``), which
   keeps triangles well shaped; quadric error decimation (``fast-simplification``)
   is 2× faster but its elongated triangles make the coarse solve less accurate
   (bimba at 1/4 of the faces, mean ``|Δd|`` against the direct solve: 0.62 % of
   the largest distance with ``"shortest-edge"``, 2.4 % with ``"quadric"``).
2. :class:`SurfaceTransfer`: for every fine vertex, the closest point on the
   coarse surface (libigl's AABB tree, exact point–triangle distance) and its
   barycentric coordinates in that coarse triangle. A coarse per-vertex field is
   moved to the fine mesh by barycentric interpolation.
3. Sources: each fine source vertex is mapped to the nearest coarse vertex.
4. Optionally ("polish") a full solve on the fine mesh, to the same tolerance as
   a direct solve, which returns the fine-mesh optimum; the transferred field is
   then only used to report how far it was from the optimum.

Without the polish the result is an **approximation** of the fine-mesh optimum:
its error is that of solving on a coarser mesh (the coarse surface is smoother
and shorter, and the cone constraints are more conservative on coarse
triangles, so distances are mostly underestimated: mean ``|Δd|`` 0.6 % of the
largest distance on bimba at 1/4 of the faces, 1.6 % at 1/8, 3.4 % on spot at
1/4; README "Coarse-to-fine"), plus the offset between each fine source and its
coarse vertex near the sources.
"""

from __future__ import annotations

import time

import numpy as np

from .errors import MeshError, ParameterError
from .mesh.geometry import clipped_barycentric
from .mesh.trimesh import TriMesh

__all__ = ["DEFAULT_MULTIRES_FACES", "SIMPLIFIERS", "SurfaceTransfer", "default_target_faces", "simplify_mesh"]

#: Upper bound of the coarse face count chosen by ``multires=True``.
DEFAULT_MULTIRES_FACES = 50_000
#: ``multires=True`` simplifies to ``n_faces // DEFAULT_MULTIRES_RATIO`` faces (at most
#: :data:`DEFAULT_MULTIRES_FACES`, at least :data:`MIN_MULTIRES_FACES`).
DEFAULT_MULTIRES_RATIO = 4
#: Smallest target face count accepted.
MIN_MULTIRES_FACES = 100


def default_target_faces(n_faces: int) -> int:
    """Coarse face count used by ``multires=True``: ``clip(n_faces // 4, 100, 50_000)``.

    Parameters
    ----------
    n_faces : int
        Face count of the fine mesh.

    Returns
    -------
    int
    """
    return int(min(DEFAULT_MULTIRES_FACES, max(MIN_MULTIRES_FACES, n_faces // DEFAULT_MULTIRES_RATIO)))


def resolve_target(multires, n_faces: int) -> int | None:
    """Target face count for the ``multires`` argument of :class:`GeodesicSolver`, or None when off.

    Parameters
    ----------
    multires : bool or int
        ``False``/``None``/``0``: off; ``True``: :func:`default_target_faces`; an int: that face count.
    n_faces : int

    Returns
    -------
    int or None

    Raises
    ------
    ParameterError
        ``multires`` is neither a bool nor an int >= :data:`MIN_MULTIRES_FACES`.
    """
    if multires is None or multires is False:
        return None
    if multires is True:
        return default_target_faces(n_faces)
    if isinstance(multires, int | np.integer) and not isinstance(multires, bool | np.bool_):
        if multires == 0:
            return None
        if multires >= MIN_MULTIRES_FACES:
            return int(multires)
    raise ParameterError(
        f"multires must be True/False or a target face count >= {MIN_MULTIRES_FACES}, got {multires!r}"
    )


def _fast_simplification():
    try:
        import fast_simplification
    except ImportError as exc:  # pragma: no cover - depends on the installation
        raise ImportError(
            "multires needs the package 'fast-simplification' (a dependency of cvxgeodesic): "
            "pip install fast-simplification"
        ) from exc
    return fast_simplification


#: Decimation methods of :func:`simplify_mesh`.
SIMPLIFIERS = ("shortest-edge", "quadric")


# libigl's decimate runs in a child process: on some meshes (near-degenerate faces, boundaries; 4 of the 60
# Thingi10K files in ../shared/meshes) it never returns, and a C++ loop cannot be interrupted in-process.
_DECIMATE_SCRIPT = """
import sys
import numpy as np
import igl
d, m = sys.argv[1], int(sys.argv[2])
V, F = np.load(d + "/V.npy"), np.load(d + "/F.npy")
U, G, _, _ = igl.decimate(np.asfortranarray(V), np.asfortranarray(F), m)
np.save(d + "/U.npy", np.asarray(U, dtype=np.float64))
np.save(d + "/G.npy", np.asarray(G, dtype=np.int64))
"""


def decimate_timeout(n_faces: int) -> float:
    """Seconds the ``"shortest-edge"`` decimation of an ``n_faces`` mesh may take before it is abandoned."""
    return 10.0 + 1e-4 * n_faces


def _igl_decimate(mesh: TriMesh, target_faces: int):
    """``((U, G), None)`` from libigl's decimate in a child process, or ``(None, reason)``."""
    import subprocess
    import sys
    import tempfile

    timeout = decimate_timeout(mesh.n_faces)
    with tempfile.TemporaryDirectory(prefix="cvxgeodesic-decimate-") as tmp:
        np.save(f"{tmp}/V.npy", mesh.V)
        np.save(f"{tmp}/F.npy", mesh.F.astype(np.int32))
        try:
            proc = subprocess.run([sys.executable, "-c", _DECIMATE_SCRIPT, tmp, str(int(target_faces))],
                                  capture_output=True, text=True, timeout=timeout, stdin=subprocess.DEVNULL)
        except subprocess.TimeoutExpired:
            return None, f"libigl decimate did not finish within {timeout:.0f} s"
        except OSError as exc:  # pragma: no cover - no way to start a process
            return None, f"cannot run libigl decimate ({exc})"
        if proc.returncode != 0:
            last = (proc.stderr.strip().splitlines() or [f"exit code {proc.returncode}"])[-1]
            return None, f"libigl decimate failed ({last})"
        U, G = np.load(f"{tmp}/U.npy"), np.load(f"{tmp}/G.npy")
    if G.shape[0] == 0:
        return None, "libigl decimate found no collapsible edges"
    return (U, G), None


def simplify_mesh(mesh: TriMesh, target_faces: int, method: str = "shortest-edge") -> TriMesh:
    """Decimate a mesh to about ``target_faces`` faces by edge collapses.

    Parameters
    ----------
    mesh : TriMesh
        Fine mesh with ``m`` faces.
    target_faces : int
        Wanted face count (``< m``); the result may differ by a few faces.
    method : {"shortest-edge", "quadric"}
        ``"shortest-edge"``: libigl ``decimate`` (shortest edge first, midpoint
        placement: well-shaped triangles). It runs in a child process with a time
        limit (:func:`decimate_timeout`) because it never returns on some meshes;
        when it fails, times out, or the mesh is not edge-manifold, ``"quadric"``
        is used instead. ``"quadric"``: quadric error decimation of
        ``fast-simplification`` (faster, robust, elongated triangles).

    Returns
    -------
    TriMesh
        The coarse mesh, without unreferenced vertices or degenerate faces,
        named ``"<name>@<faces>"``. Its ``vertex_map`` is the identity (coarse
        vertices are new points, not fine vertices). ``coarse.simplifier`` says
        which method made it (with the reason of a fallback).

    Raises
    ------
    ParameterError
        ``target_faces`` is not below the mesh's face count.
    MeshError
        The simplification left no faces.
    """
    if not 0 < target_faces < mesh.n_faces:
        raise ParameterError(f"target_faces must be in (0, {mesh.n_faces}), got {target_faces}")
    if method not in SIMPLIFIERS:
        raise ParameterError(f"unknown simplification method {method!r}; choose one of {', '.join(SIMPLIFIERS)}")
    result, used = None, method
    if method == "shortest-edge":
        if mesh.is_edge_manifold:
            result, why = _igl_decimate(mesh, target_faces)
        else:
            why = "the mesh is not edge-manifold"
        if result is None:
            used = f"quadric (shortest-edge: {why})"
    if result is None:
        fs = _fast_simplification()
        # writable copies: the extension rejects the read-only arrays of a TriMesh
        result = fs.simplify(np.array(mesh.V, dtype=np.float64), np.array(mesh.F, dtype=np.int64),
                             target_count=int(target_faces))
    pts = np.asarray(result[0], dtype=np.float64)
    tris = np.asarray(result[1], dtype=np.int64).reshape(-1, 3)
    ok = (tris[:, 0] != tris[:, 1]) & (tris[:, 1] != tris[:, 2]) & (tris[:, 0] != tris[:, 2])
    tris = tris[ok]
    if tris.shape[0] == 0:
        raise MeshError(f"{mesh.name}: simplification to {target_faces} faces left no faces")
    used_v = np.unique(tris)
    remap = np.full(pts.shape[0], -1, dtype=np.int64)
    remap[used_v] = np.arange(used_v.size)
    coarse = TriMesh(pts[used_v], remap[tris], name=f"{mesh.name}@{tris.shape[0]}")
    coarse.simplifier = used
    return coarse


class SurfaceTransfer:
    """Interpolation of coarse per-vertex fields at points near the coarse surface.

    Parameters
    ----------
    coarse : TriMesh
        Mesh the fields live on (``nc`` vertices, ``mc`` faces).
    points : (k, 3) float ndarray
        Where the fields are wanted (the fine mesh's vertices).

    Attributes
    ----------
    face : (k,) int64 ndarray
        Coarse triangle holding the closest point of each query point.
    weights : (k, 3) float ndarray
        Barycentric coordinates of that closest point.
    sq_distance : (k,) float ndarray
        Squared distance of each point to the coarse surface.
    setup_time : float
        Seconds spent in the constructor.
    """

    def __init__(self, coarse: TriMesh, points: np.ndarray):
        t0 = time.perf_counter()
        self.coarse = coarse
        self.points = np.ascontiguousarray(points, dtype=np.float64)
        self.face, self.weights, self.sq_distance = self._project(np.arange(coarse.n_faces))
        self._kdtree = None
        self.setup_time = time.perf_counter() - t0

    def _project(self, faces: np.ndarray, idx: np.ndarray | None = None):
        import igl

        P = self.points if idx is None else self.points[idx]
        F = np.ascontiguousarray(self.coarse.F[faces])
        sqd, fi, C = igl.point_mesh_squared_distance(P, self.coarse.V, F)
        fi = faces[np.asarray(fi, dtype=np.int64)]
        Vt = self.coarse.V[self.coarse.F[fi]]
        W = clipped_barycentric(np.asarray(C), Vt[:, 0], Vt[:, 1], Vt[:, 2])
        return fi, W, np.asarray(sqd)

    def apply(self, values: np.ndarray, need: np.ndarray | None = None) -> np.ndarray:
        """Interpolate a coarse field at the query points.

        Parameters
        ----------
        values : (nc,) float ndarray
            Coarse per-vertex values; ``inf`` marks vertices without a value.
        need : (k,) bool ndarray, optional
            Points that must get a finite value when one exists: a point whose
            closest coarse triangle has a non-finite corner is re-projected onto
            the triangles whose three values are finite.

        Returns
        -------
        (k,) float ndarray
        """
        tri_vals = values[self.coarse.F[self.face]]
        out = np.einsum("ij,ij->i", self.weights, np.where(np.isfinite(tri_vals), tri_vals, 0.0))
        bad = ~np.isfinite(tri_vals).all(axis=1)
        out[bad] = np.inf
        if need is not None:
            redo = np.flatnonzero(bad & need)
            finite_faces = np.flatnonzero(np.isfinite(values[self.coarse.F]).all(axis=1))
            if redo.size and finite_faces.size:
                fi, W, _ = self._project(finite_faces, redo)
                out[redo] = np.einsum("ij,ij->i", W, values[self.coarse.F[fi]])
        return out

    def nearest_vertex(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Nearest coarse vertex of each point.

        Parameters
        ----------
        points : (k, 3) float ndarray

        Returns
        -------
        index : (k,) int64 ndarray
        distance : (k,) float ndarray
        """
        if self._kdtree is None:
            from scipy.spatial import cKDTree

            self._kdtree = cKDTree(self.coarse.V)
        dist, idx = self._kdtree.query(np.atleast_2d(points))
        return np.asarray(idx, dtype=np.int64), np.asarray(dist)


class CoarseToFine:
    """The multires part of a :class:`~cvxgeodesic.api.GeodesicSolver` (built by it, not by users).

    Parameters
    ----------
    fine : GeodesicSolver
        The solver being built; its mesh, method, ``m``/``lam``, tolerance and
        iteration limit are used for the coarse solver.
    target_faces : int
        Coarse face count (``< fine.mesh.n_faces``).
    solver : str
        Backend name requested for ``fine`` (``"auto"``, ``"ipm"``, ``"clarabel"``).
    polish : bool
        Finish every solve with a full solve on the fine mesh.
    """

    def __init__(self, fine, target_faces: int, solver: str, polish: bool):
        from .api import GeodesicSolver

        mesh = fine.mesh
        self.polish = bool(polish)
        self.target_faces = int(target_faces)
        t0 = time.perf_counter()
        self.coarse_mesh = simplify_mesh(mesh, self.target_faces)
        if fine.energy == "hessian" and not self.coarse_mesh.is_edge_manifold and \
                self.coarse_mesh.simplifier == "shortest-edge":  # a manifold coarse mesh needs no cut for the Hessian
            other = simplify_mesh(mesh, self.target_faces, method="quadric")
            if other.is_edge_manifold:
                other.simplifier = "quadric (shortest-edge: its result was not edge-manifold)"
                self.coarse_mesh = other
        self.simplify_time = time.perf_counter() - t0
        if fine.normalization == "area":  # λ is a length on the surface: the fine mesh's, also for the coarse one
            kw = {"lam": fine.lam}
        elif fine.m is None:  # paper normalization: keep λ·n/h, the quantity the paper's m fixes
            h, n = mesh.mean_edge_length, mesh.n_vertices
            hc, nc = self.coarse_mesh.mean_edge_length, self.coarse_mesh.n_vertices
            kw = {"lam": fine.lam * (hc / nc) / (h / n)}
        else:
            kw = {"m": fine.m}
        self.coarse = GeodesicSolver(self.coarse_mesh, fine.method, solver=solver, tol=fine.tol,
                                     max_iter=fine.max_iter, verbose=fine.verbose,
                                     normalization=fine.normalization, **kw)
        self.transfer = SurfaceTransfer(self.coarse_mesh, mesh.V)

    def summary(self) -> dict:
        """Per-mesh facts reported in ``info.extra["multires"]``."""
        return {
            "target_faces": self.target_faces,
            "coarse_faces": self.coarse_mesh.n_faces,
            "coarse_vertices": self.coarse_mesh.n_vertices,
            "simplifier": getattr(self.coarse_mesh, "simplifier", ""),
            "simplify_time": self.simplify_time,
            "transfer_setup_time": self.transfer.setup_time,
            "coarse_setup_time": self.coarse.setup_time,
            "max_surface_distance": float(np.sqrt(self.transfer.sq_distance.max())),
        }

    def solve(self, fine, src: np.ndarray, callback=None):
        """Coarse solve, transfer and (with ``polish``) fine solve; returns a GeodesicResult on the fine mesh."""
        from .api import GeodesicResult, SolveInfo

        t0 = time.perf_counter()
        mesh = fine.mesh
        reach = mesh.connected_to(src) & mesh.referenced
        csrc, offset = self.transfer.nearest_vertex(mesh.V[src])
        cres = self.coarse.solve(np.unique(csrc), callback=callback)
        t1 = time.perf_counter()
        d = self.transfer.apply(cres.distance, need=reach)
        d[~reach] = np.inf
        d[src] = 0.0
        t2 = time.perf_counter()
        mr = self.summary()
        mr.update(
            polished=self.polish,
            coarse_sources=[int(i) for i in csrc],
            max_source_offset=float(offset.max()),
            coarse_solve_time=cres.info.solve_time,
            coarse_iterations=cres.info.iterations,
            coarse_status=cres.info.status,
            transfer_time=t2 - t1,
        )
        if self.polish:
            res = fine._solve_direct(src, time.perf_counter(), callback)
            both = np.isfinite(res.distance) & np.isfinite(d)
            diff = float(np.abs(res.distance[both] - d[both]).max()) if both.any() else 0.0
            scale = float(res.distance[both].max()) if both.any() else 0.0
            mr.update(max_diff_to_coarse_transfer=diff,
                      rel_max_diff_to_coarse_transfer=diff / scale if scale > 0 else 0.0,
                      fine_solve_time=res.info.solve_time)
            res.info.solve_time = time.perf_counter() - t0
            res.info.extra["multires"] = mr
            return res
        cinfo = cres.info
        info = SolveInfo(
            method=fine.method, solver=cinfo.solver, status="approximate", iterations=cinfo.iterations,
            setup_time=fine.setup_time, solve_time=time.perf_counter() - t0, lam=fine.lam,
            n_unreachable=int((~reach).sum()), notes=[f"coarse mesh: {note}" for note in cinfo.notes],
            extra={"multires": mr, "coarse": {k: v for k, v in cinfo.as_dict().items() if k != "extra"}},
        )
        return GeodesicResult(distance=d, info=info, sources=src)
