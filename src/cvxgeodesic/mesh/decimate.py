"""Edge-collapse decimation of a mesh to a target face count (the coarse mesh of coarse-to-fine solves).

By default shortest edge first with midpoint placement (libigl ``decimate``), which keeps triangles well
shaped; quadric error decimation (``fast-simplification``) is 2× faster but its elongated triangles make
the coarse solve less accurate (bimba at 1/4 of the faces, mean ``|Δd|`` against the direct solve: 0.62 %
of the largest distance with ``"shortest-edge"``, 2.4 % with ``"quadric"``).
"""

from __future__ import annotations

import numpy as np

from ..errors import MeshError, ParameterError
from ..validation import check_choice
from .trimesh import TriMesh

__all__ = ["SIMPLIFIERS", "decimate_timeout", "euler_characteristic", "kept_border_floor", "simplify_mesh"]


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


#: Coordinates farther from the origin than this many bounding-box diagonals are moved before the quadric
#: decimation (:func:`_decimation_offset`).
FAR_FROM_ORIGIN = 100.0


def _decimation_offset(mesh: TriMesh) -> np.ndarray:
    """(3,) float: what the quadric decimation's coordinates are moved by: 0, or for a mesh farther from the origin
    than :data:`FAR_FROM_ORIGIN` diagonals its bounding box's low corner, rounded to the last bit of each axis's
    largest coordinate (so that ``(v - c) + c == v`` for the vertices the decimation does not move).

    fast-simplification's quadrics hold plane offsets in the coordinates it is given. Kitten (diagonal 1.7) moved 1e4
    to 2.3e6 diagonals away, as survey coordinates are, made other copies than at the origin, and the default's field
    went 0.511 → 0.29-0.96 % mean error (up to 1e3 diagonals: the same copy). Only far meshes are moved: the optimal
    placement of a collapse on a planar patch is singular, and where the origin lies decides it (centring planar
    clouds' surfaces on their mean or box centre left slivers in 7 of 8 copies, 0.05-0.18 max error where the copy at
    the given coordinates is exact; docs/dev/adapted-log.md, "Survey coordinates").
    """
    V = mesh.V
    if not np.abs(V).max() > FAR_FROM_ORIGIN * mesh.bbox_diagonal:
        return np.zeros(3)
    last_bit = np.spacing(np.abs(V).max(axis=0))
    return np.round(V.min(axis=0) / last_bit) * last_bit


def kept_border_floor(mesh: TriMesh) -> int:
    """The fewest faces a decimation that keeps every boundary vertex and the topology can leave: ``2B − Bₑ − 2χ``.

    A triangulated surface with ``V`` vertices, ``Bₑ`` boundary edges and Euler characteristic ``χ`` has
    ``F = 2V − Bₑ − 2χ`` faces (each face has three edges, each inner edge two faces, each boundary edge one), and with
    its ``B`` boundary vertices kept ``V ≥ B`` (``B = Bₑ`` on boundary loops that touch nowhere; a vertex where two
    loops touch counts once). fast-simplification asked for fewer faces runs all of its 100 passes trying (fandisk's
    0.1 %-noise cloud surface: 27.6 ms for the 2,461 faces it could reach, 11.3 ms asked for 2,461, the same copy);
    asked for the floor it stops when it gets there. A closed surface's floor is ``−2χ``, below any target.

    Parameters
    ----------
    mesh : TriMesh
        Edge-manifold.

    Returns
    -------
    int

    Examples
    --------
    >>> from cvxgeodesic.mesh.generate import grid_plane
    >>> kept_border_floor(grid_plane(10))  # a disc (χ = 1) with 40 boundary vertices
    38
    """
    edges = mesh.boundary_facets
    return 2 * np.unique(edges).size - len(edges) - 2 * euler_characteristic(mesh)


def euler_characteristic(mesh: TriMesh) -> int:
    """``V − E + F`` over the vertices of some face: what a copy must keep (the adapted solves' topology check)."""
    return int(mesh.referenced.sum()) - len(mesh.edges) + mesh.n_faces


def simplify_mesh(mesh: TriMesh, target_faces: int, method: str = "shortest-edge", *,
                  preserve_border: bool = False, agg: float = 7.0) -> TriMesh:
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
    preserve_border : bool
        ``"quadric"`` only: collapse no edge that touches a boundary vertex, so that the coarse mesh's boundary is
        the fine mesh's boundary, vertex for vertex (the adapted solves' ``"boundary"`` sources).
    agg : float
        ``"quadric"`` only: fast-simplification's aggressiveness (its default 7; lower keeps the shape better, and
        may stop short of the target).

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
    check_choice(method, "simplification method", SIMPLIFIERS, lower=False)
    result, used, offset = None, method, np.zeros(3)
    if method == "shortest-edge":
        if mesh.is_edge_manifold:
            result, why = _igl_decimate(mesh, target_faces)
        else:
            why = "the mesh is not edge-manifold"
        if result is None:
            used = f"quadric (shortest-edge: {why})"
    if result is None:
        fs = _fast_simplification()
        offset = _decimation_offset(mesh)
        # below the kept boundary's face floor fast-simplification would run all of its 100 passes without a collapse
        count = max(int(target_faces), kept_border_floor(mesh)) if preserve_border else int(target_faces)
        # writable copies: the extension rejects the read-only arrays of a TriMesh
        result = fs.simplify(np.array(mesh.V - offset, dtype=np.float64), np.array(mesh.F, dtype=np.int64),
                             target_count=count, preserve_border=bool(preserve_border), agg=float(agg))
    pts = np.asarray(result[0], dtype=np.float64) + offset
    tris = np.asarray(result[1], dtype=np.int64).reshape(-1, 3)
    ok = (tris[:, 0] != tris[:, 1]) & (tris[:, 1] != tris[:, 2]) & (tris[:, 0] != tris[:, 2])
    tris = tris[ok]
    if tris.shape[0] == 0:
        raise MeshError(f"{mesh.name}: simplification to {target_faces} faces left no faces")
    used_v, local = np.unique(tris, return_inverse=True)
    coarse = TriMesh(pts[used_v], local.reshape(tris.shape), name=f"{mesh.name}@{tris.shape[0]}")
    coarse.simplifier = used
    return coarse
