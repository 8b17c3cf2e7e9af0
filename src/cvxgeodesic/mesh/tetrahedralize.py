"""A closed surface filled with tetrahedra, through an optional mesher (issue 26).

Two meshers are supported, neither a dependency of cvxgeodesic:

``"tetgen"`` (``pip install tetgen``, 0.8.4 checked: wheels for CPython 3.10–3.14 on Linux, macOS
    and Windows; only NumPy needed)
    The TetGen library (Hang Si) behind an MIT-licensed wrapper. **TetGen itself is licensed under
    the AGPL v3** (or a commercial licence from WIAS): installing and calling it is your choice,
    and distributing software that includes it carries the AGPL's terms. Fast (spot, 5.9K faces:
    0.3 s), keeps the input surface exactly (its vertices and faces are the boundary), needs a
    closed, non-self-intersecting surface.
``"wildmeshing"`` (``pip install wildmeshing``, 0.4.1 checked: manylinux/macOS/Windows wheels; needs
    ``svgwrite``)
    fTetWild (Hu et al. 2020), MPL-2.0. Robust to imperfect input (holes, self-intersections:
    it works from the winding number), approximates the surface within an envelope (``epsilon``)
    instead of keeping it, slower (spot: 8 to 17 s on one thread, depending on the load). It
    writes a file into the working directory and prints with ``std::cout``: the call runs in a
    temporary working directory with the process's stdout and stderr sent to /dev/null, so it
    must not run beside other threads that depend on either.

``pytetwild`` (also fTetWild) was tried and left out: its 0.4.2 package imports PyVista (and VTK)
on import although it does not declare it.
"""

from __future__ import annotations

import contextlib
import importlib
import os
import sys
import tempfile
import time
from collections.abc import Iterator
from typing import Any

import numpy as np

from ..errors import MeshError, ParameterError
from ..validation import check_choice, check_number
from .tetmesh import TetMesh
from .trimesh import TriMesh

__all__ = ["MESHERS", "tetrahedralize"]

#: Mesher name → (import name, pip install line).
MESHERS = {"tetgen": ("tetgen", "pip install tetgen"),
           "wildmeshing": ("wildmeshing", "pip install wildmeshing svgwrite (the tet extra: pip install "
                                          "'cvxgeodesic[tet]')")}


def _available(name: str) -> Any:
    try:
        return importlib.import_module(MESHERS[name][0])
    except ImportError:
        return None


@contextlib.contextmanager
def _silent_native_output() -> Iterator[None]:
    """Send what compiled code prints to the process's stdout and stderr to /dev/null (fTetWild prints its
    progress with ``std::cout`` whatever its log level)."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 1)
            os.dup2(null.fileno(), 2)
            yield
    finally:
        with contextlib.suppress(Exception):  # C stdio buffers still hold output meant for /dev/null
            import ctypes

            ctypes.CDLL(None).fflush(None)
        for fd, copy in zip((1, 2), saved, strict=True):
            os.dup2(copy, fd)
            os.close(copy)


def tetrahedralize(surface: TriMesh | tuple, *, mesher: str = "auto", max_volume: float | None = None,
                   edge_length: float | None = None, quality: float = 1.5, threads: int = 1) -> TetMesh:
    """Fill a closed triangle surface with tetrahedra.

    Parameters
    ----------
    surface : TriMesh or (V, F) tuple
        A closed surface (every edge shared by two faces) for ``"tetgen"``; ``"wildmeshing"``
        accepts imperfect ones.
    mesher : {"auto", "tetgen", "wildmeshing"}
        ``"auto"``: TetGen if installed, else wildmeshing (see the module's notes on licences).
    max_volume : float, optional
        TetGen: target largest tetrahedron volume (``-a``; TetGen's mesh improvement after the
        refinement leaves some up to about 1.1 × larger). Default: no bound beyond the quality
        refinement.
    edge_length : float, optional
        wildmeshing: target edge length (default: 1/20 of the bounding-box diagonal, fTetWild's).
    quality : float
        TetGen: largest radius-edge ratio (``-q``; TetGen's default 2.0, ours 1.5 for rounder tets;
        at least 1.1).
    threads : int
        wildmeshing: threads (0: all cores).

    Returns
    -------
    TetMesh
        Positively oriented tetrahedra; its notes name the mesher and its parameters.

    Raises
    ------
    ParameterError
        No mesher installed (the message says what to install), an unknown mesher or a bad parameter.
    MeshError
        TetGen given an open surface (boundary edges), or the mesher failing on the input.

    Examples
    --------
    >>> from cvxgeodesic.mesh.generate import icosphere
    >>> ball = tetrahedralize(icosphere(2))  # doctest: +SKIP
    >>> ball.boundary_facets.shape  # doctest: +SKIP
    (320, 3)
    """
    mesh = surface if isinstance(surface, TriMesh) else TriMesh(*surface)
    mesher = check_choice(mesher, "mesher", ("auto", *MESHERS))
    quality = check_number(quality, "quality", low=1.1)
    if max_volume is not None:
        max_volume = check_number(max_volume, "max_volume", low=0.0, low_open=True)
    if edge_length is not None:
        edge_length = check_number(edge_length, "edge_length", low=0.0, low_open=True)
    if mesher == "auto":
        mesher = next((m for m in MESHERS if _available(m) is not None), "")
        if not mesher:
            raise ParameterError("tetrahedralize needs a mesher: pip install tetgen (fast; TetGen is AGPL-licensed) "
                                 "or pip install wildmeshing svgwrite (fTetWild, MPL-2.0; the extra "
                                 "'cvxgeodesic[tet]')")
    lib = _available(mesher)
    if lib is None:
        raise ParameterError(f"mesher {mesher!r} is not installed: {MESHERS[mesher][1]}")
    t0 = time.perf_counter()
    if mesher == "tetgen":
        open_edges = int(np.count_nonzero(mesh.edge_cell_counts == 1))
        if open_edges or not mesh.is_edge_manifold:
            raise MeshError(f"{mesh.name}: TetGen needs a closed manifold surface, this one has {open_edges} boundary "
                            f"edges and {int(np.count_nonzero(mesh.edge_cell_counts > 2))} edges of more than two "
                            "faces; repair it or use mesher='wildmeshing'")
        try:
            tg = lib.TetGen(np.asarray(mesh.V, dtype=np.float64), np.asarray(mesh.F, dtype=np.int32))
            V, T, *_ = tg.tetrahedralize(quality=True, minratio=quality, maxvolume=max_volume or -1.0,
                                         fixedvolume=max_volume is not None, quiet=True)
        except Exception as exc:
            raise MeshError(f"{mesh.name}: TetGen failed: {type(exc).__name__}: {exc}") from None
        params = f"minratio={quality:g}" + (f", maxvolume={max_volume:g}" if max_volume else "")
    else:
        try:
            # in a private working directory: fTetWild's get_tet_mesh writes __tracked_surface.stl into it
            with (_silent_native_output(), tempfile.TemporaryDirectory(prefix="cvxgeodesic-tetwild-") as tmp,
                  contextlib.chdir(tmp)):
                tz = lib.Tetrahedralizer(max_threads=int(threads), **(
                    {"edge_length_r": edge_length / mesh.bbox_diagonal} if edge_length else {}))
                tz.set_log_level(6)
                tz.set_mesh(np.asarray(mesh.V, dtype=np.float64), np.asarray(mesh.F, dtype=np.int32))
                tz.tetrahedralize()
                V, T, *_ = tz.get_tet_mesh()
        except Exception as exc:
            raise MeshError(f"{mesh.name}: fTetWild (wildmeshing) failed: {type(exc).__name__}: {exc}") from None
        params = f"edge_length={edge_length:g}" if edge_length else "edge_length=diagonal/20"
    T = np.asarray(T, dtype=np.int64)
    if T.ndim != 2 or T.shape[0] == 0:
        raise MeshError(f"{mesh.name}: the mesher {mesher!r} returned no tetrahedra")
    out = TetMesh(np.asarray(V, dtype=np.float64), T[:, :4], name=f"{mesh.name} (tetrahedralized)")
    note = (f"{mesh.name}: tetrahedralized by {mesher} ({params}) in {time.perf_counter() - t0:.2f} s: "
            f"{out.n_vertices} vertices, {out.n_tets} tetrahedra")
    return TetMesh(out.V, out.positive_tets, name=out.name, notes=[note])
