"""Second-order (P2) elements for the *squared* geodesic distance (``order=2``).

The unknown is ``φ = d²`` in the continuous piecewise-quadratic space: one value per
vertex and one per edge midpoint. ``|∇√φ| ≤ 1`` is the same as ``|∇φ|² ≤ 4φ``, which is
a second-order cone in ``(φ, ∇φ)``::

    ‖(∇φ, φ − 1)‖ ≤ φ + 1      ⇔      |∇φ|² ≤ 4φ

Maximizing ``∫φ`` under that constraint with ``φ = 0`` at the sources has ``d²`` as its
maximizer in the continuum (``√φ`` is 1-Lipschitz and vanishes at the sources, so
``√φ ≤ d``). On a flat region ``d²`` is a quadratic polynomial, which P2 represents
exactly, so flat distances come out exact on triangles of any shape.

Discretization (choices and measurements in ``docs/order2.md``):

* the cone is imposed at sample points of every face, by default its three corners and
  three edge midpoints (:data:`SAMPLES`);
* the objective is ``Σ w_a φ_a`` with lumped weights ``w_a = A/6`` per node of each
  face (``weights="lumped"``; the consistent P2 weights, 0 at corners and ``A/3`` at
  midpoints, are ``weights="p2"``);
* a source vertex ``s`` gets ``φ_s = 0`` and zero derivative at ``s`` along each of its
  edges (``4 φ_mid − φ_j = 0``), which is ``∇φ(s) = 0`` on every incident face without
  redundant rows; the cones at ``s`` (degenerate there) are left out;
* a source point ``p`` inside a face gets ``φ(p) = 0`` and ``∇φ(p) = 0`` on its face
  (on an edge: on every face of the edge, without the redundant along-edge rows);
* a degenerate face (:meth:`TriMesh.degenerate_faces`) gets no face cones; the 1-D cone
  ``(∂φ/∂s)² ≤ 4φ`` along each of its edges (endpoints and midpoint) bounds its DOFs
  whatever its shape;
* non-manifold edges need nothing special: the edge DOF is shared by all its faces.

Distances at vertices are ``√max(φ, 0)``; :class:`P2Field` evaluates the field inside
faces.
"""

from __future__ import annotations

import numbers
import time
import warnings
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from .errors import DegenerateFacesWarning, MeshError, ParameterError, SolverError, SourceError
from .mesh.trimesh import TriMesh
from .operators.gradient import gradient_blocks

#: Barycentric sample points where the cone is imposed on each face (corners, then edge midpoints).
SAMPLES = {
    "nodes": np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0.5, 0.5], [0.5, 0, 0.5], [0.5, 0.5, 0]], float),
}
SAMPLES["nodes+centroid"] = np.vstack([SAMPLES["nodes"], [[1 / 3, 1 / 3, 1 / 3]]])
SAMPLES["nodes+gauss"] = np.vstack([SAMPLES["nodes"], [[2 / 3, 1 / 6, 1 / 6], [1 / 6, 2 / 3, 1 / 6],
                                                      [1 / 6, 1 / 6, 2 / 3]]])
WEIGHTS = ("lumped", "p2")
#: Edges shorter than this fraction of the bounding-box diagonal get no 1-D cone (their DOF is tied linearly).
MIN_EDGE = 1e-9
#: Tolerance on barycentric coordinates for "this source point is a vertex / on an edge / a sample point".
BARY_TOL = 1e-12


def p2_basis(bary: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """P2 shape functions and their derivatives in the barycentric coordinates.

    Local DOF order: corners 0, 1, 2, then the midpoints of the edges opposite corners
    0, 1, 2 (edges (1, 2), (2, 0), (0, 1)).

    Parameters
    ----------
    bary : (s, 3) float ndarray
        Barycentric coordinates of ``s`` points.

    Returns
    -------
    N : (s, 6) float ndarray
        Shape function values.
    dN : (s, 6, 3) float ndarray
        ``∂N_a/∂λ_i``; the gradient on a face is ``Σ_i dN[..., i] ∇λ_i``.
    """
    lam = np.atleast_2d(np.asarray(bary, dtype=float))
    s = lam.shape[0]
    N = np.empty((s, 6))
    dN = np.zeros((s, 6, 3))
    for k in range(3):
        N[:, k] = lam[:, k] * (2 * lam[:, k] - 1)
        dN[:, k, k] = 4 * lam[:, k] - 1
        i, j = (k + 1) % 3, (k + 2) % 3
        N[:, 3 + k] = 4 * lam[:, i] * lam[:, j]
        dN[:, 3 + k, i] = 4 * lam[:, j]
        dN[:, 3 + k, j] = 4 * lam[:, i]
    return N, dN


def _edge_basis(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """1-D P2 shape functions on an edge ``[0, 1]`` for DOFs (start, midpoint, end) and their t-derivatives."""
    t = np.asarray(t, dtype=float)
    N = np.stack([(1 - t) * (1 - 2 * t), 4 * t * (1 - t), t * (2 * t - 1)], axis=-1)
    dN = np.stack([4 * t - 3, 4 - 8 * t, 4 * t - 1], axis=-1)
    return N, dN


class P2Space:
    """Continuous P2 space on a mesh: DOF numbering, per-face shape-function gradients, weights.

    Parameters
    ----------
    mesh : TriMesh

    Attributes
    ----------
    n_dofs : int
        ``n_vertices + n_edges``: vertex DOFs first, then one per edge of ``mesh.edges``.
    face_dofs : (m, 6) int64 ndarray
        Global DOFs of each face in the local order of :func:`p2_basis`.
    face_edges : (m, 3) int64 ndarray
        Index into ``mesh.edges`` of the edge opposite each corner.
    lam_grad : (m, 2, 3) float ndarray
        ``∇λ_i`` of each face in its local 2-D frame (``operators.gradient_blocks``).
    degenerate : (m,) bool ndarray
        Faces left out of the face cones.
    """

    def __init__(self, mesh: TriMesh):
        self.mesh = mesh
        n, F = mesh.n_vertices, mesh.F
        E = mesh.edges
        self.n_edges = int(E.shape[0])
        self.n_dofs = n + self.n_edges
        key = E[:, 0] * n + E[:, 1]
        order = np.argsort(key)
        fe = np.empty((mesh.n_faces, 3), dtype=np.int64)
        for k in range(3):
            a, b = F[:, (k + 1) % 3], F[:, (k + 2) % 3]
            q = np.minimum(a, b) * n + np.maximum(a, b)
            fe[:, k] = order[np.searchsorted(key, q, sorter=order)]
        self.face_edges = fe
        self.face_dofs = np.hstack([F, n + fe]).astype(np.int64)
        deg = np.zeros(mesh.n_faces, dtype=bool)
        deg[mesh.degenerate_faces()] = True
        self.degenerate = deg
        with np.errstate(divide="ignore", invalid="ignore"):
            g = gradient_blocks(mesh)
        g[deg] = 0.0
        self.lam_grad = g

    def weights(self, kind: str = "lumped") -> np.ndarray:
        """Objective weights ``w`` (``∫φ ≈ wᵀφ``).

        Parameters
        ----------
        kind : {"lumped", "p2"}
            ``"lumped"``: ``A/6`` to each of a face's six nodes. ``"p2"``: the exact
            integrals of the P2 shape functions (0 for corners, ``A/3`` for midpoints).

        Returns
        -------
        (n_dofs,) float ndarray
        """
        A = self.mesh.face_areas
        if kind == "lumped":
            per = np.repeat(A[:, None] / 6.0, 6, axis=1)
        elif kind == "p2":
            per = np.hstack([np.zeros((A.size, 3)), np.repeat(A[:, None] / 3.0, 3, axis=1)])
        else:
            raise ParameterError(f"weights must be one of {WEIGHTS}, got {kind!r}")
        return np.bincount(self.face_dofs.ravel(), per.ravel(), minlength=self.n_dofs)

    def face_cones(self, samples: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Value and gradient rows of ``φ`` at the sample points of every face.

        Returns
        -------
        val : (s, 6) float ndarray
            Same for every face.
        grad : (m, s, 2, 6) float ndarray
            ``∇φ(sample) = grad[t, j] @ φ[face_dofs[t]]`` in the face's 2-D frame.
        """
        N, dN = p2_basis(samples)
        grad = np.einsum("sai,tci->tsca", dN, self.lam_grad)
        return N, grad

    def hessian_rows(self, faces: np.ndarray) -> np.ndarray:
        """Hessian of ``φ`` (constant on a face) as a linear map of the face's DOFs.

        Returns
        -------
        (k, 2, 2, 6) float ndarray
            ``Hess φ|_t = H[t] @ φ[face_dofs[t]]``.
        """
        g = self.lam_grad[faces]  # (k, 2, 3)
        D2 = np.zeros((6, 3, 3))
        for k in range(3):
            D2[k, k, k] = 4.0
            i, j = (k + 1) % 3, (k + 2) % 3
            D2[3 + k, i, j] = D2[3 + k, j, i] = 4.0
        return np.einsum("aij,tci,tdj->tcda", D2, g, g)

    def point_rows(self, face: int, bary: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Value row (6,) and gradient rows (2, 6) of ``φ`` at one point of one face."""
        N, dN = p2_basis(np.asarray(bary, dtype=float)[None])
        return N[0], np.einsum("ai,ci->ca", dN[0], self.lam_grad[face])


# --------------------------------------------------------------------------- sources
@dataclass
class _Point:
    face: int
    bary: np.ndarray


def _is_int(v) -> bool:
    return isinstance(v, numbers.Integral | np.integer) and not isinstance(v, bool | np.bool_)


def _as_point(item):
    """A ``(face, bary)`` tuple or an object with ``.face`` and ``.bary``, else None."""
    if hasattr(item, "face") and hasattr(item, "bary"):
        return item.face, item.bary
    if isinstance(item, tuple) and len(item) == 2 and _is_int(item[0]) and np.ndim(item[1]) == 1 \
            and np.size(item[1]) == 3:
        return item
    return None


def parse_sources(sources, mesh: TriMesh) -> tuple[np.ndarray, list[_Point]]:
    """Split ``sources`` into vertex indices and points inside faces.

    Parameters
    ----------
    sources : int, (face, bary) tuple, object with ``.face``/``.bary``, or a sequence of these
        ``bary`` is three barycentric coordinates (non-negative, summing to 1 within 1e-9).
    mesh : TriMesh

    Returns
    -------
    vertices : (k,) int64 ndarray
        Vertex sources, including points that lie on a vertex.
    points : list
        The other points (on an edge or inside a face), barycentric coordinates normalized.

    Raises
    ------
    SourceError
        Empty, out of range, repeated vertices, bad barycentric coordinates.
    """
    if isinstance(sources, bool | np.bool_):
        raise SourceError(f"sources must be vertex indices or (face, bary) points, got {sources!r}")
    if _is_int(sources) or _as_point(sources) is not None:
        items = [sources]
    else:
        try:
            items = list(sources)
        except TypeError:
            raise SourceError(f"sources must be an int, a (face, bary) point or a sequence of them, "
                              f"got {type(sources).__name__}") from None
    if not items:
        raise SourceError("sources is empty: give at least one source")
    verts: list[int] = []
    points: list[_Point] = []
    n, m = mesh.n_vertices, mesh.n_faces
    for pos, item in enumerate(items):
        pt = _as_point(item)
        if pt is None:
            if isinstance(item, np.ndarray) and item.ndim == 0:
                item = item.item()
            if not _is_int(item):
                raise SourceError(f"sources[{pos}] must be a vertex index or a (face, bary) point, got {item!r}")
            v = int(item)
            if not 0 <= v < n:
                raise SourceError(f"sources[{pos}] = {v} is out of range for a mesh with {n} vertices")
            verts.append(v)
            continue
        f, b = pt
        if not _is_int(f) or not 0 <= int(f) < m:
            raise SourceError(f"sources[{pos}]: face {f!r} is not a face index in [0, {m})")
        try:
            b = np.asarray(b, dtype=float).reshape(3)
        except (TypeError, ValueError):
            raise SourceError(f"sources[{pos}]: bary must be three numbers, got {b!r}") from None
        if not np.all(np.isfinite(b)) or np.any(b < -1e-9) or abs(b.sum() - 1) > 1e-9:
            raise SourceError(f"sources[{pos}]: bary {b.tolist()} must be >= 0 and sum to 1")
        b = np.clip(b, 0.0, None)
        b /= b.sum()
        b[b < BARY_TOL] = 0.0
        b /= b.sum()
        f = int(f)
        if np.count_nonzero(b) == 1:
            verts.append(int(mesh.F[f, int(np.argmax(b))]))
        else:
            points.append(_Point(f, b))
    varr = np.asarray(verts, dtype=np.int64)
    if np.unique(varr).size != varr.size:
        raise SourceError("sources contains a vertex more than once")
    return varr, points


# --------------------------------------------------------------------------- the conic program
@dataclass
class P2Problem:
    """``min cᵀx  s.t.  s_k = h_k − G_k x[dofs_k] ∈ SOC(4) for each cone k,  E x = f,  x[fixed] = 0``.

    Attributes
    ----------
    n : int
        Number of DOFs.
    c : (n,) float ndarray
    cone_dofs : (k, 6) int64 ndarray
        The six DOFs of the face each cone lives on.
    cone_face : (k,) int64 ndarray
    G : (k, 4, 6) float ndarray
    h : (k, 4) float ndarray
    E : (p, n) scipy.sparse.csr_matrix
    f : (p,) float ndarray
    fixed : (n,) bool ndarray
        DOFs held at 0 (source vertices, components without a source).
    unreachable_vertices : (n_vertices,) bool ndarray
    notes : list of str
    """

    n: int
    c: np.ndarray
    cone_dofs: np.ndarray
    cone_face: np.ndarray
    G: np.ndarray
    h: np.ndarray
    E: sp.csr_matrix
    f: np.ndarray
    fixed: np.ndarray
    unreachable_vertices: np.ndarray
    notes: list[str] = field(default_factory=list)

    @property
    def n_cones(self) -> int:
        return int(self.G.shape[0])


def _cone_rows(val: np.ndarray, grad: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``G, h`` with ``h − G x = (φ + 1, ∇φ, φ − 1)``: val (k, 6), grad (k, 2, 6) or (k, 1, 6)."""
    k = val.shape[0]
    G = np.zeros((k, 4, 6))
    G[:, 0] = -val
    G[:, 1:1 + grad.shape[1]] = -grad
    G[:, 3] = -val
    h = np.tile([1.0, 0.0, 0.0, -1.0], (k, 1))
    return G, h


class P2Builder:
    """Per-mesh part of the order-2 program (everything that does not depend on the sources).

    Parameters
    ----------
    mesh : TriMesh
        Already scaled to unit size by the caller.
    samples : str
        Key of :data:`SAMPLES`.
    weights : {"lumped", "p2"}
    """

    def __init__(self, mesh: TriMesh, samples: str = "nodes", weights: str = "p2", source_hessian: bool = False, cone_scale: str = "dijkstra"):
        self.source_hessian = bool(source_hessian)
        self.cone_scale = cone_scale
        if samples not in SAMPLES:
            raise ParameterError(f"samples must be one of {tuple(SAMPLES)}, got {samples!r}")
        self.mesh = mesh
        self.space = sp_ = P2Space(mesh)
        self.w = sp_.weights(weights)
        self.sample_bary = SAMPLES[samples]
        good = np.flatnonzero(~sp_.degenerate)
        val, grad = sp_.face_cones(self.sample_bary)
        ns = val.shape[0]
        Gf, hf = _cone_rows(np.tile(val, (good.size, 1)), grad[good].reshape(-1, 2, 6))
        self.notes: list[str] = []
        # 1-D cones along the edges of degenerate faces (each edge once)
        deg = np.flatnonzero(sp_.degenerate)
        Ge = np.zeros((0, 4, 6))
        he = np.zeros((0, 4))
        e_face = np.zeros(0, dtype=np.int64)
        e_corner = np.zeros(0, dtype=np.int64)  # local corner index at the sample (−1 for midpoints)
        e_samples = np.zeros((0, 3))
        if deg.size:
            fe = sp_.face_edges[deg]
            ids, first = np.unique(fe.ravel(), return_index=True)
            owner = deg[first // 3]
            kloc = first % 3  # edge opposite local corner kloc of its owner face
            L = mesh.edge_lengths[ids]
            ok = L > MIN_EDGE * max(mesh.bbox_diagonal, 1e-300)
            ids, owner, kloc, L = ids[ok], owner[ok], kloc[ok], L[ok]
            t = np.array([0.0, 0.5, 1.0])
            Nt, dNt = _edge_basis(t)
            rows_v, rows_g, fo, co, eb = [], [], [], [], []
            for j in range(3):
                # edge opposite corner k runs from corner k+1 to corner k+2; local DOFs (k+1, 3+k, k+2)
                val_e = np.zeros((ids.size, 6))
                grd_e = np.zeros((ids.size, 1, 6))
                a, b = (kloc + 1) % 3, (kloc + 2) % 3
                r = np.arange(ids.size)
                for col, coeff_v, coeff_d in ((a, Nt[j, 0], dNt[j, 0]), (3 + kloc, Nt[j, 1], dNt[j, 1]),
                                              (b, Nt[j, 2], dNt[j, 2])):
                    val_e[r, col] = coeff_v
                    grd_e[r, 0, col] = coeff_d / L
                rows_v.append(val_e)
                rows_g.append(grd_e)
                fo.append(owner)
                co.append(np.where(j == 0, a, np.where(j == 2, b, -1)))
                bb = np.zeros((ids.size, 3))
                bb[r, a] = 1 - t[j]
                bb[r, b] = t[j]
                eb.append(bb)
            Ge, he = _cone_rows(np.concatenate(rows_v), np.concatenate(rows_g))
            e_face = np.concatenate(fo)
            e_corner = np.concatenate(co)
            e_samples = np.concatenate(eb)
            self.notes.append(
                f"{deg.size} degenerate face(s) carry no face cones; their {ids.size} edge(s) get the "
                "1-D cone (dφ/ds)² ≤ 4φ instead")
            warnings.warn(f"{mesh.name}: {deg.size} degenerate face(s) left out of the order-2 face cones "
                          "(their edges carry 1-D cones)", DegenerateFacesWarning, stacklevel=3)
        self.G = np.concatenate([Gf, Ge])
        self.h = np.concatenate([hf, he])
        self.cone_face = np.concatenate([np.repeat(good, ns), e_face]).astype(np.int64)
        self.cone_dofs = sp_.face_dofs[self.cone_face]
        # which local corner a cone sits on (for dropping the cones at a source vertex), and its barycentric point
        corner_of_sample = np.array([int(np.argmax(b)) if np.max(b) == 1.0 else -1 for b in self.sample_bary])
        self.cone_corner = np.concatenate([np.tile(corner_of_sample, good.size), e_corner]).astype(np.int64)
        self.cone_bary = np.concatenate([np.tile(self.sample_bary, (good.size, 1)), e_samples])
        self.cone_vertex = np.where(self.cone_corner >= 0,
                                    mesh.F[self.cone_face, np.maximum(self.cone_corner, 0)], -1)

    def build(self, sources) -> P2Problem:
        """The program for one set of sources (see :func:`parse_sources`)."""
        mesh, space = self.mesh, self.space
        n = mesh.n_vertices
        vsrc, points = parse_sources(sources, mesh)
        if mesh.n_faces == 0 or np.all(space.degenerate):
            raise MeshError(f"{mesh.name}: every face is degenerate; order 2 needs at least one proper face")
        seed = np.concatenate([vsrc, *[mesh.F[p.face] for p in points]]) if points else vsrc
        reach_v = mesh.connected_to(seed) & mesh.referenced
        reach_v[vsrc] = True
        E = mesh.edges
        reach = np.concatenate([reach_v, reach_v[E[:, 0]] & reach_v[E[:, 1]]])
        fixed = ~reach
        fixed[vsrc] = True
        keep = ~np.isin(self.cone_vertex, vsrc)
        keep &= reach[self.cone_dofs].all(axis=1)
        rows, cols, vals = [], [], []
        r = 0
        # vertex sources: zero derivative along every incident edge at s: 4 φ_mid − φ_j − 3 φ_s = 0 (φ_s fixed 0)
        if vsrc.size:
            inc = np.flatnonzero(np.isin(E[:, 0], vsrc) | np.isin(E[:, 1], vsrc))
            for eid in inc:
                a, b = E[eid]
                far = b if a in vsrc else a
                rows += [r, r]
                cols += [n + eid, far]
                vals += [4.0, -1.0]
                r += 1
        for p in points:
            nz = np.flatnonzero(p.bary > 0)
            corners = mesh.F[p.face, nz]
            if nz.size == 2:  # on an edge: every face of that edge
                fs = np.flatnonzero((mesh.F == corners[0]).any(axis=1) & (mesh.F == corners[1]).any(axis=1))
            else:
                fs = np.array([p.face])
            fs = fs[~space.degenerate[fs]]
            if fs.size == 0:
                raise SourceError(f"source point on face {p.face} lies only on degenerate faces")
            edge_dir = None
            for j, f in enumerate(fs):
                bary_f = np.zeros(3)
                for kk in range(3):
                    hit = np.flatnonzero(corners == mesh.F[f, kk])
                    if hit.size:
                        bary_f[kk] = p.bary[nz[hit[0]]]
                val, grad = space.point_rows(f, bary_f)
                dofs = space.face_dofs[f]
                if j == 0:
                    rows += [r] * 6
                    cols += dofs.tolist()
                    vals += val.tolist()
                    r += 1
                if nz.size == 2:
                    # along-edge derivative is shared by the faces: impose it once, then the normal part per face
                    ex, ey = _frame(mesh, f)
                    u3 = mesh.V[corners[1]] - mesh.V[corners[0]]
                    u = np.array([u3 @ ex, u3 @ ey])
                    u /= np.linalg.norm(u)
                    dirs = [u, np.array([-u[1], u[0]])] if edge_dir is None else [np.array([-u[1], u[0]])]
                    edge_dir = u
                    grad = np.stack([d @ grad for d in dirs])
                for g in grad:
                    rows += [r] * 6
                    cols += dofs.tolist()
                    vals += g.tolist()
                    r += 1
                # a sample coinciding with the point has a degenerate cone there
                same = (self.cone_face == f) & (np.abs(self.cone_bary - bary_f).max(axis=1) < 1e-12)
                keep &= ~same
        extra_G, extra_h, extra_f = [], [], []
        if self.source_hessian:
            # on a face holding a source point or vertex, φ = (x − p)ᵀ Q (x − p) exactly (the face is flat and convex),
            # and |∇φ|² ≤ 4φ everywhere on it ⇔ Q ≼ I: an SOC(3) on Q = Hess φ / 2 (tr(I − Q) ≥ ‖(Q11 − Q22, 2 Q12)‖)
            sf = [p.face for p in points]
            if vsrc.size:
                sf += np.flatnonzero(np.isin(mesh.F, vsrc).any(axis=1)).tolist()
            sf = np.unique(np.asarray(sf, dtype=np.int64))
            sf = sf[~space.degenerate[sf]]
            if sf.size:
                Hq = 0.5 * space.hessian_rows(sf)
                Gq = np.zeros((sf.size, 4, 6))
                Gq[:, 0] = Hq[:, 0, 0] + Hq[:, 1, 1]
                Gq[:, 1] = -(Hq[:, 0, 0] - Hq[:, 1, 1])
                Gq[:, 2] = -2 * Hq[:, 0, 1]
                extra_G.append(Gq)
                extra_h.append(np.tile([2.0, 0.0, 0.0, 0.0], (sf.size, 1)))
                extra_f.append(sf)
        Emat = sp.csr_matrix((vals, (rows, cols)), shape=(r, space.n_dofs))
        # fixed DOFs leave the equalities; drop rows that are then empty
        Emat = Emat[:, :].tolil()
        Emat[:, np.flatnonzero(fixed)] = 0
        Emat = Emat.tocsr()
        Emat.eliminate_zeros()
        nonempty = np.diff(Emat.indptr) > 0
        Emat = Emat[nonempty]
        c = -self.w.copy()
        c[fixed] = 0.0
        cf = np.concatenate([self.cone_face[keep], *extra_f])
        cb = self.cone_bary[keep]
        if self.cone_scale == "dijkstra" and vsrc.size:
            # ‖(√a ∇φ, φ − a)‖ ≤ φ + a is |∇φ|² ≤ 4φ for every a > 0; a ≈ φ at the sample centres the cone there
            from scipy.sparse.csgraph import dijkstra
            dv = dijkstra(mesh.vertex_adjacency, indices=vsrc, min_only=True)
            dv = np.where(np.isfinite(dv), dv, 0.0)
            h2 = np.mean(mesh.face_longest_edges[cf[: cb.shape[0]]]) ** 2
            a = np.maximum(np.einsum("ki,ki->k", cb, dv[mesh.F[cf[: cb.shape[0]]]]) ** 2, h2)
            Gk = self.G[keep].copy()
            hk = self.h[keep].copy()
            Gk[:, 1:3] *= np.sqrt(a)[:, None, None]
            hk[:, 0] = a
            hk[:, 3] = -a
        else:
            Gk, hk = self.G[keep], self.h[keep]
        Gall = np.concatenate([Gk, *extra_G])
        hall = np.concatenate([hk, *extra_h])
        # a fixed DOF is 0: its columns do not matter, but zero them so backends need not know
        Gall = np.where(fixed[space.face_dofs[cf]][:, None, :], 0.0, Gall)
        return P2Problem(
            n=space.n_dofs, c=c, cone_dofs=space.face_dofs[cf], cone_face=cf,
            G=Gall, h=hall, E=Emat, f=np.zeros(Emat.shape[0]), fixed=fixed,
            unreachable_vertices=~reach_v, notes=list(self.notes),
        )


def _frame(mesh: TriMesh, f: int) -> tuple[np.ndarray, np.ndarray]:
    """Local 2-D frame of one face, as :func:`operators.gradient.triangle_frames`."""
    V, F = mesh.V, mesh.F
    ex = V[F[f, 1]] - V[F[f, 0]]
    ex = ex / np.linalg.norm(ex)
    nrm = np.cross(V[F[f, 1]] - V[F[f, 0]], V[F[f, 2]] - V[F[f, 0]])
    ey = np.cross(nrm / np.linalg.norm(nrm), ex)
    return ex, ey


# --------------------------------------------------------------------------- Clarabel backend
def solve_p2_clarabel(problem: P2Problem, *, tol: float = 1e-8, max_iter: int = 200, verbose: bool = False) -> dict:
    """Solve a :class:`P2Problem` with Clarabel.

    Returns
    -------
    dict
        ``x`` (n,) with the fixed DOFs at 0, ``status`` ("optimal" / "almost_optimal"),
        ``iterations``, ``objective``, ``primal_residual``, ``dual_residual``, ``gap``.

    Raises
    ------
    SolverError
        Clarabel stopped without ``Solved`` or ``AlmostSolved``.
    """
    import clarabel

    free = np.flatnonzero(~problem.fixed)
    remap = -np.ones(problem.n, dtype=np.int64)
    remap[free] = np.arange(free.size)
    k = problem.n_cones
    loc = remap[problem.cone_dofs]  # (k, 6); fixed DOFs are 0, so their columns just drop
    rr = np.broadcast_to(np.arange(4 * k).reshape(k, 4, 1), (k, 4, 6))
    cc = np.broadcast_to(loc[:, None, :], (k, 4, 6))
    mask = (cc >= 0) & (problem.G != 0)
    Gs = sp.csc_matrix((problem.G[mask], (rr[mask], cc[mask])), shape=(4 * k, free.size))
    Ef = problem.E[:, free]
    A = sp.vstack([Ef, Gs]).tocsc()
    b = np.concatenate([problem.f, problem.h.ravel()])
    cones = []
    if Ef.shape[0]:
        cones.append(clarabel.ZeroConeT(Ef.shape[0]))
    cones.extend([clarabel.SecondOrderConeT(4)] * k)
    settings = clarabel.DefaultSettings()
    settings.verbose = verbose
    settings.max_iter = max_iter
    settings.tol_gap_abs = tol
    settings.tol_gap_rel = tol
    settings.tol_feas = tol
    settings.tol_ktratio = 1e-6
    t0 = time.perf_counter()
    solver = clarabel.DefaultSolver(sp.csc_matrix((free.size, free.size)), problem.c[free], A, b, cones, settings)
    sol = solver.solve()
    status = str(sol.status)
    if status not in ("Solved", "AlmostSolved"):
        raise SolverError("Clarabel did not solve the order-2 problem", solver="clarabel", status=status,
                          info={"iterations": int(sol.iterations)})
    x = np.zeros(problem.n)
    x[free] = np.asarray(sol.x)
    return {
        "x": x, "status": "optimal" if status == "Solved" else "almost_optimal", "solver": "clarabel",
        "iterations": int(sol.iterations), "objective": float(sol.obj_val),
        "primal_residual": float(sol.r_prim), "dual_residual": float(sol.r_dual),
        "gap": abs(float(sol.obj_val) - float(sol.obj_val_dual)) / max(1.0, abs(float(sol.obj_val))),
        "time": time.perf_counter() - t0,
    }


# --------------------------------------------------------------------------- the field
class P2Field:
    """A piecewise-quadratic squared-distance field ``φ`` on a mesh, evaluated as ``√max(φ, 0)``.

    Parameters
    ----------
    mesh : TriMesh
    phi : (n_vertices + n_edges,) float ndarray
        Squared distance at the vertices then at the midpoints of ``mesh.edges``, in the
        mesh's units squared; ``inf`` on components without a source.
    """

    def __init__(self, mesh: TriMesh, phi: np.ndarray, space: P2Space | None = None):
        self.mesh = mesh
        self.space = space if space is not None else P2Space(mesh)
        self.phi = np.asarray(phi, dtype=float)

    @property
    def vertex_distance(self) -> np.ndarray:
        """(n,) float ndarray: ``√max(φ, 0)`` at the vertices."""
        return np.sqrt(np.maximum(self.phi[: self.mesh.n_vertices], 0.0))

    def squared_distance_at(self, faces, bary) -> np.ndarray:
        """``φ`` at points given by faces and barycentric coordinates.

        Parameters
        ----------
        faces : int or (k,) int array_like
        bary : (3,) or (k, 3) float array_like

        Returns
        -------
        (k,) float ndarray
        """
        faces = np.atleast_1d(np.asarray(faces))
        bary = np.atleast_2d(np.asarray(bary, dtype=float))
        if faces.ndim != 1 or not np.issubdtype(faces.dtype, np.integer):
            raise ParameterError("faces must be an int or a 1-D array of face indices")
        if bary.shape != (faces.size, 3):
            raise ParameterError(f"bary must have shape ({faces.size}, 3), got {bary.shape}")
        if faces.size and (faces.min() < 0 or faces.max() >= self.mesh.n_faces):
            raise ParameterError(f"faces must lie in [0, {self.mesh.n_faces})")
        if not np.all(np.isfinite(bary)) or np.any(bary < -1e-9) or np.any(np.abs(bary.sum(axis=1) - 1) > 1e-9):
            raise ParameterError("bary rows must be >= 0 and sum to 1")
        N, _ = p2_basis(bary)
        vals = self.phi[self.space.face_dofs[faces]]
        with np.errstate(invalid="ignore"):
            out = np.einsum("ka,ka->k", N, np.where(np.isinf(vals), 0.0, vals))
        out[np.isinf(vals).any(axis=1)] = np.inf
        return out

    def distance_at(self, faces, bary) -> np.ndarray:
        """Geodesic distance ``√max(φ, 0)`` at points inside faces (see :meth:`squared_distance_at`)."""
        return np.sqrt(np.maximum(self.squared_distance_at(faces, bary), 0.0))


def p2_field_at(field_: P2Field, faces, bary) -> np.ndarray:
    """Distance at points inside faces of a :class:`P2Field` (``field_.distance_at``)."""
    return field_.distance_at(faces, bary)


# --------------------------------------------------------------------------- API strategy
ORDER2_METHODS = ("qclp",)


class Order2Strategy:
    """What :class:`~cvxgeodesic.api.GeodesicSolver` delegates to when ``order=2``.

    Parameters
    ----------
    solver : GeodesicSolver
        Its ``mesh``, ``method``, ``tol``, ``max_iter``, ``verbose`` are used.
    backend : {"auto", "ipm", "clarabel"}
    samples, weights
        See :class:`P2Builder`.
    """

    def __init__(self, solver, backend: str = "auto", *, samples: str = "nodes", weights: str = "lumped"):
        from .api import _unit_mesh

        if solver.method not in ORDER2_METHODS:
            raise ParameterError(
                f"order=2 is implemented for {', '.join(ORDER2_METHODS)}, not for {solver.method!r} "
                "(no consistent P2 smoothing energy for d² yet; see docs/order2.md)")
        self.owner = solver
        unit, self.scale = _unit_mesh(solver.mesh)
        self.builder = P2Builder(unit, samples=samples, weights=weights)
        self.backend = "ipm" if backend == "auto" else backend
        self._fallback = backend == "auto"
        self._ipm = None
        if self.backend == "ipm":
            from .solvers.ipm_soc import P2InteriorPoint

            self._ipm = P2InteriorPoint(self.builder)

    def solve(self, sources, callback=None):
        from .api import GeodesicResult, SolveInfo

        t0 = time.perf_counter()
        own = self.owner
        problem = self.builder.build(sources)
        notes = list(problem.notes)
        if self._ipm is not None:
            try:
                res = self._ipm.solve(problem, tol=own.tol, max_iter=own.max_iter, callback=callback)
            except SolverError as exc:
                if not self._fallback:
                    raise
                notes.append(f"the order-2 interior-point solver stopped ({exc.status}); solved with Clarabel")
                res = solve_p2_clarabel(problem, tol=own.tol, max_iter=own.max_iter, verbose=own.verbose)
            else:
                if res["status"] != "optimal" and self._fallback:
                    try:
                        res2 = solve_p2_clarabel(problem, tol=own.tol, max_iter=own.max_iter, verbose=own.verbose)
                        if res2["status"] == "optimal":
                            notes.append("order-2 interior-point solver was almost optimal; re-solved with Clarabel")
                            res = res2
                    except SolverError:
                        pass
        else:
            res = solve_p2_clarabel(problem, tol=own.tol, max_iter=own.max_iter, verbose=own.verbose)
        phi = res["x"] * self.scale**2
        n = own.mesh.n_vertices
        E = own.mesh.edges
        unreach = np.concatenate([problem.unreachable_vertices,
                                  problem.unreachable_vertices[E[:, 0]] | problem.unreachable_vertices[E[:, 1]]])
        phi[unreach] = np.inf
        fld = P2Field(own.mesh, phi, self.builder.space)
        d = fld.vertex_distance
        vsrc, _ = parse_sources(sources, own.mesh)
        d[vsrc] = 0.0
        info = SolveInfo(
            method=own.method, solver=res["solver"], status=res["status"], iterations=res["iterations"],
            setup_time=own.setup_time, solve_time=time.perf_counter() - t0,
            primal_residual=res["primal_residual"], dual_residual=res["dual_residual"], gap=res["gap"],
            objective=res["objective"] * self.scale**2, lam=0.0, n_unreachable=int(np.isinf(d[:n]).sum()),
            notes=notes, extra={"order": 2, "p2_field": fld, "n_dofs": problem.n, "n_cones": problem.n_cones},
        )
        return GeodesicResult(distance=d, info=info, sources=vsrc)
