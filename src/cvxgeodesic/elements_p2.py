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
  three edge midpoints (:data:`SAMPLES`), with the cone centred near the expected ``φ``
  (``‖(√a ∇φ, φ − a)‖ ≤ φ + a`` is the same cone for every ``a > 0``);
* on *flat* faces, cutting planes: after a solve, a cone is added where ``|∇φ|² − 4φ`` is
  largest on each violating face (:func:`max_violation`, exact) and the problem re-solved;
* the objective is the mean of ``φ`` with lumped weights ``A/6`` per node of each face
  (``weights="lumped"``; the consistent P2 weights, 0 at corners and ``A/3`` at midpoints,
  are ``weights="p2"``);
* a source vertex ``s`` gets ``φ_s = 0`` and zero derivative at ``s`` along each of its
  edges (``4 φ_mid − φ_j = 0``), which is ``∇φ(s) = 0`` on every incident face without
  redundant rows; the cones at ``s`` (degenerate there) are left out;
* a source point inside a face or on an edge is inserted as a vertex (:class:`SplitMesh`);
  :meth:`P2Builder.build` can instead impose ``φ(p) = 0``, ``∇φ(p) = 0`` on the unsplit face
  (measured less accurate, kept for comparison);
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
SAMPLES["corners"] = SAMPLES["nodes"][:3]
SAMPLES["midpoints"] = SAMPLES["nodes"][3:]
SAMPLES["nodes+centroid"] = np.vstack([SAMPLES["nodes"], [[1 / 3, 1 / 3, 1 / 3]]])
SAMPLES["nodes+gauss"] = np.vstack([SAMPLES["nodes"], [[2 / 3, 1 / 6, 1 / 6], [1 / 6, 2 / 3, 1 / 6],
                                                      [1 / 6, 1 / 6, 2 / 3]]])
#: Where the API imposes the cone: "flat-nodes" = all six nodes on flat faces (:attr:`P2Space.flat_faces`), the three
#: edge midpoints on the others. Measured 2026-12-01 against exact MMP, source 0, mean relative error all nodes →
#: flat-nodes: bimba 0.22 → 0.11 %, bunny 0.099 → 0.058 %, lucy_20k 0.34 → 0.15 %, dragon_20k 0.62 → 0.32 %, spot
#: 0.25 → 0.15 %; the 53 coarse CAD meshes: median ratio to P1 qclp 0.216 → 0.204, median error 0.85 → 0.95 %
#: (29 better, 24 worse; docs/order2.md); flat meshes unchanged (all their faces are flat).
DEFAULT_SAMPLES = "flat-nodes"
WEIGHTS = ("lumped", "p2", "mixed")
#: Objective weights used by the API (see docs/order2.md for the measurement behind the choice).
DEFAULT_WEIGHTS = "lumped"
#: ``solver="auto"`` uses the structured solver from this many faces on (Clarabel below; 0: always).
IPM_MIN_FACES = 0
#: Cutting-plane rounds add a cone where ``|∇φ|² − 4φ`` exceeds this fraction of ``4φ`` (flat faces only).
REFINE_TOL = 1e-7
#: Edges shorter than this fraction of the bounding-box diagonal get no 1-D cone (their DOF is tied linearly).
MIN_EDGE = 1e-9
#: Tolerance on barycentric coordinates for "this source point is a vertex / on an edge / a sample point".
BARY_TOL = 1e-12
#: Version of the order-2 fields, for caches keyed on the inputs only (``benchmarks/report_common.py``): bump it
#: whenever a change moves an order-2 result beyond the solver tolerance (formulation, samples, weights, defaults),
#: so that fields cached by older code are recomputed instead of silently reused. 1: 2026-12-02 (first version;
#: the fields of the 2026-12-01 defaults, midpoints on curved faces).
ORDER2_CACHE_VERSION = 1


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
        fe = mesh.face_edges  # column k: the edge opposite corner k
        self.face_edges = fe
        self.face_dofs = np.hstack([F, n + fe]).astype(np.int64)
        deg = np.zeros(mesh.n_faces, dtype=bool)
        deg[mesh.degenerate_faces()] = True
        self.degenerate = deg
        with np.errstate(divide="ignore", invalid="ignore"):
            g = gradient_blocks(mesh)
        g[deg] = 0.0
        self.lam_grad = g

    @property
    def flat_faces(self) -> np.ndarray:
        """(m,) bool ndarray: proper faces whose edge-neighbours all lie in their plane (|cos| ≥ 1 − 1e-10)."""
        if getattr(self, "_flat", None) is None:
            nrm = self.mesh.face_normals_unnormalized
            with np.errstate(divide="ignore", invalid="ignore"):
                nrm = nrm / np.linalg.norm(nrm, axis=1, keepdims=True)
            fe = self.face_edges.ravel()
            fo = np.repeat(np.arange(self.mesh.n_faces), 3)
            _, first = np.unique(fe, return_index=True)
            ref = np.zeros((self.n_edges, 3))
            ref[fe[first]] = nrm[fo[first]]
            cos = np.abs(np.einsum("ij,ij->i", nrm[fo], ref[fe]))
            edge_cos = np.ones(self.n_edges)
            np.minimum.at(edge_cos, fe, np.where(np.isfinite(cos), cos, 0.0))
            self._flat = (edge_cos[self.face_edges] >= 1 - 1e-10).all(axis=1) & ~self.degenerate
        return self._flat

    def weights(self, kind: str = "lumped") -> np.ndarray:
        """Objective weights ``w`` (``∫φ ≈ wᵀφ``).

        Parameters
        ----------
        kind : {"lumped", "p2", "mixed"}
            ``"lumped"``: ``A/6`` to each of a face's six nodes. ``"p2"``: the exact
            integrals of the P2 shape functions (0 for corners, ``A/3`` for midpoints).
            ``"mixed"``: their average (``A/12`` and ``A/4``).

        Returns
        -------
        (n_dofs,) float ndarray
        """
        A = self.mesh.face_areas
        if kind == "lumped":
            per = np.repeat(A[:, None] / 6.0, 6, axis=1)
        elif kind == "p2":
            per = np.hstack([np.zeros((A.size, 3)), np.repeat(A[:, None] / 3.0, 3, axis=1)])
        elif kind == "mixed":
            per = np.hstack([np.repeat(A[:, None] / 12.0, 3, axis=1), np.repeat(A[:, None] / 4.0, 3, axis=1)])
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
    guess : (n,) float ndarray or None
        A field the structured solver may start from (scaled into the cones' interior): the P2
        interpolant of the squared Dijkstra distance to the sources; ``None`` when there is none.
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
    guess: np.ndarray | None = None

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
        Key of :data:`SAMPLES`, or "flat-nodes" (:data:`DEFAULT_SAMPLES`).
    weights : {"lumped", "p2", "mixed"}, optional
        Objective weights (:meth:`P2Space.weights`); default :data:`DEFAULT_WEIGHTS`.
    source_hessian : bool
        Also impose ``Hess φ ≼ 2I`` on faces holding a source (measured: no gain; off).
    cone_scale : {"dijkstra", "unit"}
        Centre of each cone: ``a`` = (Dijkstra distance at the sample)², floored at the squared
        mean longest edge, or ``a = 1``.
    hess_lower : bool
        Impose ``Hess φ ≽ 2I`` on every face (exact on flat meshes, worse on curved ones; off).
    """

    def __init__(self, mesh: TriMesh, samples: str = DEFAULT_SAMPLES, weights: str | None = None,
                 source_hessian: bool = False, cone_scale: str = "dijkstra", hess_lower: bool = False):
        weights = DEFAULT_WEIGHTS if weights is None else weights
        self.source_hessian = bool(source_hessian)
        self.hess_lower = bool(hess_lower)
        self.cone_scale = cone_scale
        if samples not in SAMPLES and samples != "flat-nodes":
            raise ParameterError(f"samples must be 'flat-nodes' or one of {tuple(SAMPLES)}, got {samples!r}")
        self.mesh = mesh
        self.space = sp_ = P2Space(mesh)
        self.w = sp_.weights(weights)
        good = np.flatnonzero(~sp_.degenerate)
        if samples == "flat-nodes":
            # every node on flat faces, the edge midpoints on the others (measured in docs/order2.md)
            flat = sp_.flat_faces[good]
            groups = [(good[flat], SAMPLES["nodes"]), (good[~flat], SAMPLES["midpoints"])]
        else:
            groups = [(good, SAMPLES[samples])]
        parts = []
        for faces, bary in groups:
            val, grad = sp_.face_cones(bary)
            parts.append(_cone_rows(np.tile(val, (faces.size, 1)), grad[faces].reshape(-1, 2, 6)))
        Gf, hf = np.concatenate([g for g, _ in parts]), np.concatenate([h for _, h in parts])
        self.notes: list[str] = []
        # 1-D cones along the edges of degenerate faces (each edge once)
        deg = np.flatnonzero(sp_.degenerate)
        Ge = np.zeros((0, 4, 6))
        he = np.zeros((0, 4))
        e_face = np.zeros(0, dtype=np.int64)
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
            rows_v, rows_g, fo, eb = [], [], [], []
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
                bb = np.zeros((ids.size, 3))
                bb[r, a] = 1 - t[j]
                bb[r, b] = t[j]
                eb.append(bb)
            Ge, he = _cone_rows(np.concatenate(rows_v), np.concatenate(rows_g))
            e_face = np.concatenate(fo)
            e_samples = np.concatenate(eb)
            self.notes.append(
                f"{deg.size} degenerate face(s) carry no face cones; their {ids.size} edge(s) get the "
                "1-D cone (dφ/ds)² ≤ 4φ instead")
            warnings.warn(f"{mesh.name}: {deg.size} degenerate face(s) left out of the order-2 face cones "
                          "(their edges carry 1-D cones)", DegenerateFacesWarning, stacklevel=3)
        self.G = np.concatenate([Gf, Ge])
        self.h = np.concatenate([hf, he])
        self.cone_face = np.concatenate([*[np.repeat(f, b.shape[0]) for f, b in groups], e_face]).astype(np.int64)
        self.cone_dofs = sp_.face_dofs[self.cone_face]
        # each cone's barycentric point (for dropping the cones on source vertices, :func:`_on_sources`)
        self.cone_bary = np.concatenate([*[np.tile(b, (f.size, 1)) for f, b in groups], e_samples])

    def _source_equalities(self, vsrc, points, cone_face, cone_bary, keep):
        """The source equalities (φ's value and gradient at the source points, zero derivative along the edges
        at a source vertex) as COO rows ``(rows, cols, vals, count)``, and ``keep`` without the cones that sit
        on a source point."""
        mesh, space = self.mesh, self.space
        n = mesh.n_vertices
        E = mesh.edges
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
                same = (cone_face == f) & (np.abs(cone_bary - bary_f).max(axis=1) < 1e-12)
                keep &= ~same
        return rows, cols, vals, r, keep

    def _source_hessian_cones(self, vsrc, points, reach):
        """The extra SOC(4) cones on the Hessian of φ (``source_hessian``: Q ≼ I on the source faces;
        ``hess_lower``: Hess φ ≽ 2I on every proper face): lists of G (m, 4, 6), h (m, 4) and faces (m,)."""
        mesh, space = self.mesh, self.space
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
        if self.hess_lower:
            # Hess φ ≽ 2I on every proper face: the exact polyhedral d² satisfies it on every face the cut locus
            # misses (each window is |x − p'|² or (σ + |x − v|)²), and it makes |∇φ|² − 4φ convex on the face,
            # so the cones at the corners then hold on the whole face
            hf = np.flatnonzero(~space.degenerate & reach[space.face_dofs].all(axis=1))
            Hq = 0.5 * space.hessian_rows(hf)
            Gq = np.zeros((hf.size, 4, 6))
            Gq[:, 0] = -(Hq[:, 0, 0] + Hq[:, 1, 1])
            Gq[:, 1] = -(Hq[:, 0, 0] - Hq[:, 1, 1])
            Gq[:, 2] = -2 * Hq[:, 0, 1]
            extra_G.append(Gq)
            extra_h.append(np.tile([-2.0, 0.0, 0.0, 0.0], (hf.size, 1)))
            extra_f.append(hf)
        return extra_G, extra_h, extra_f

    def build(self, sources, extra=None) -> P2Problem:
        """The program for one set of sources (see :func:`parse_sources`).

        Parameters
        ----------
        sources
            Vertex indices and/or points (see :func:`parse_sources`).
        extra : tuple (faces (k,) int ndarray, bary (k, 3) float ndarray), optional
            Additional cone sample points (from :func:`max_violation`).
        """
        mesh, space = self.mesh, self.space
        vsrc, points = parse_sources(sources, mesh)
        G0, h0, cone_face, cone_bary = self.G, self.h, self.cone_face, self.cone_bary
        if extra is not None and len(extra[0]):
            ef, eb = np.asarray(extra[0], dtype=np.int64), np.asarray(extra[1], dtype=float)
            ok = ~space.degenerate[ef]
            ef, eb = ef[ok], eb[ok]
            N, dN = p2_basis(eb)
            Gx, hx = _cone_rows(N, np.einsum("kai,kci->kca", dN, space.lam_grad[ef]))
            G0, h0 = np.concatenate([G0, Gx]), np.concatenate([h0, hx])
            cone_face = np.concatenate([cone_face, ef])
            cone_bary = np.concatenate([cone_bary, eb])
        if mesh.n_faces == 0 or np.all(space.degenerate):
            raise MeshError(f"{mesh.name}: every face is degenerate; order 2 needs at least one proper face")
        seed = np.concatenate([vsrc, *[mesh.F[p.face] for p in points]]) if points else vsrc
        reach_v = mesh.connected_to(seed) & mesh.referenced
        reach_v[vsrc] = True
        E = mesh.edges
        reach = np.concatenate([reach_v, reach_v[E[:, 0]] & reach_v[E[:, 1]]])
        fixed = ~reach
        fixed[vsrc] = True
        both = np.flatnonzero(np.isin(E, vsrc).all(axis=1))
        # an edge joining two sources: the zero-derivative rows at both ends give φ_mid = 0, so fix it here (as an
        # E row of one unknown it left its cone columns in place)
        fixed[mesh.n_vertices + both] = True
        keep = ~_on_sources(mesh.F[cone_face], cone_bary, vsrc)
        keep &= reach[space.face_dofs[cone_face]].all(axis=1)
        rows, cols, vals, r, keep = self._source_equalities(vsrc, points, cone_face, cone_bary, keep)
        extra_G, extra_h, extra_f = self._source_hessian_cones(vsrc, points, reach)
        Emat = sp.csr_matrix((vals, (rows, cols)), shape=(r, space.n_dofs))
        # fixed DOFs leave the equalities; drop rows that are then empty
        Emat = Emat[:, :].tolil()
        Emat[:, np.flatnonzero(fixed)] = 0
        Emat = Emat.tocsr()
        Emat.eliminate_zeros()
        nonempty = np.diff(Emat.indptr) > 0
        Emat = Emat[nonempty]
        # the mean of φ, not its integral: the backends' absolute gap tolerance then means the same on any area
        c = -self.w / max(self.w.sum(), 1e-300)
        c[fixed] = 0.0
        cf = np.concatenate([cone_face[keep], *extra_f])
        cb = cone_bary[keep]
        guess = None
        with_guess = vsrc.size > 0 and not space.flat_faces.any()
        if with_guess or (self.cone_scale == "dijkstra" and vsrc.size):
            from scipy.sparse.csgraph import dijkstra
            dv = dijkstra(mesh.vertex_adjacency, indices=vsrc, min_only=True)
            dv = np.where(np.isfinite(dv), dv, 0.0)
        if with_guess:
            # a starting field for the structured solver: squared distance at the vertices, squared mean at the
            # midpoints (on an edge at a source vertex that is ℓ²/4 = φ_j / 4, so it meets the zero-derivative
            # equalities). Not on meshes with flat faces, where the sampled program's optimum is barely determined
            # between the samples: from it a needle strip's solve stopped 7.6e-5 of the largest distance away
            # from the optimum that Mehrotra's start reaches (7.9e-7)
            guess = np.concatenate([dv**2, (0.5 * (dv[E[:, 0]] + dv[E[:, 1]]))**2])
            guess[fixed] = 0.0
        if self.cone_scale == "dijkstra" and vsrc.size:
            # ‖(√a ∇φ, φ − a)‖ ≤ φ + a is |∇φ|² ≤ 4φ for every a > 0; a ≈ φ at the sample centres the cone there
            h2 = np.mean(mesh.face_longest_edges[cf[: cb.shape[0]]]) ** 2
            a = np.maximum(np.einsum("ki,ki->k", cb, dv[mesh.F[cf[: cb.shape[0]]]]) ** 2, h2)
            Gk = G0[keep].copy()
            hk = h0[keep].copy()
            Gk[:, 1:3] *= np.sqrt(a)[:, None, None]
            hk[:, 0] = a
            hk[:, 3] = -a
        else:
            Gk, hk = G0[keep], h0[keep]
        Gall = np.concatenate([Gk, *extra_G])
        hall = np.concatenate([hk, *extra_h])
        # a fixed DOF is 0: its columns do not matter, but zero them so backends need not know
        Gall = np.where(fixed[space.face_dofs[cf]][:, None, :], 0.0, Gall)
        return P2Problem(
            n=space.n_dofs, c=c, cone_dofs=space.face_dofs[cf], cone_face=cf,
            G=Gall, h=hall, E=Emat, f=np.zeros(Emat.shape[0]), fixed=fixed,
            unreachable_vertices=~reach_v, notes=list(self.notes), guess=guess,
        )


def _on_sources(corners: np.ndarray, bary: np.ndarray, vsrc: np.ndarray) -> np.ndarray:
    """Which cone samples lie on source vertices only: at a source, on an edge joining two, or on a face of three.

    With the zero-derivative rows at every source, ``φ`` and ``∇φ`` vanish there for every feasible ``φ`` (on a face
    ``(s, t, x)`` with sources ``s, t`` the rows leave ``φ = φ_x λ_x²``, whose value and gradient are 0 on the edge
    ``st``): such a cone sits at its apex, implied by the rows, and with it the program has no strictly feasible
    point (the structured solver broke down on every pair of adjacent sources and Clarabel took over, docs/order2.md).

    Parameters
    ----------
    corners : (k, 3) int ndarray
        The vertices of each sample's face.
    bary : (k, 3) float ndarray
        The samples' barycentric coordinates in those faces.
    vsrc : (p,) int ndarray
        Source vertices.

    Returns
    -------
    (k,) bool ndarray
    """
    return ((bary <= 0) | np.isin(corners, vsrc)).all(axis=1)


def _frame(mesh: TriMesh, f: int) -> tuple[np.ndarray, np.ndarray]:
    """Local 2-D frame of one face, as :func:`operators.gradient.triangle_frames`."""
    V, F = mesh.V, mesh.F
    ex = V[F[f, 1]] - V[F[f, 0]]
    ex = ex / np.linalg.norm(ex)
    nrm = np.cross(V[F[f, 1]] - V[F[f, 0]], V[F[f, 2]] - V[F[f, 0]])
    ey = np.cross(nrm / np.linalg.norm(nrm), ex)
    return ex, ey


def max_violation(space: P2Space, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Largest ``v = |∇φ|² − 4φ`` on each face, exactly (``v`` is itself a quadratic on the face).

    Parameters
    ----------
    space : P2Space
    x : (n_dofs,) float ndarray
        ``φ`` (finite).

    Returns
    -------
    vmax : (m,) float ndarray
        ``max_T v`` (NaN-free; 0 on degenerate faces).
    bary : (m, 3) float ndarray
        Where it is reached.
    phi_at : (m,) float ndarray
        ``φ`` there.
    """
    nodes = SAMPLES["nodes"]
    N, grad = space.face_cones(nodes)
    xf = x[space.face_dofs]
    g = np.einsum("tsca,ta->tsc", grad, xf)
    v = (g**2).sum(-1) - 4 * np.einsum("sa,ta->ts", N, xf)  # nodal values of the quadratic v
    # candidates: corners, edge extrema, interior extremum, in barycentric coordinates (λ1, λ2), λ0 = 1 − λ1 − λ2
    m = xf.shape[0]
    cands = [np.eye(3)[None].repeat(m, 0)]
    # v(λ) = Σ_a v_a N_a(λ): write v = c0 + b·y + yᵀ A y with y = (λ1, λ2)
    def at(b3):
        Nn, _ = p2_basis(b3.reshape(-1, 3))
        return Nn.reshape(b3.shape[:-1] + (6,))
    # fit the quadratic in y from its nodal values (exact: P2 is unisolvent on the nodes)
    Y = nodes[:, 1:]
    Mfit = np.column_stack([np.ones(6), Y[:, 0], Y[:, 1], Y[:, 0] ** 2, Y[:, 0] * Y[:, 1], Y[:, 1] ** 2])
    coef = np.linalg.solve(Mfit, v.T).T  # (m, 6): c, b1, b2, a11, a12, a22
    c0, b1, b2, a11, a12, a22 = coef.T
    # interior stationary point: [2a11 a12; a12 2a22] y = −b
    det = 4 * a11 * a22 - a12**2
    with np.errstate(divide="ignore", invalid="ignore"):
        y1 = (-b1 * 2 * a22 + b2 * a12) / det
        y2 = (-b2 * 2 * a11 + b1 * a12) / det
    inter = np.stack([1 - y1 - y2, y1, y2], axis=1)
    inter[~np.isfinite(inter).all(axis=1)] = 1 / 3
    cands.append(inter[:, None])
    # edge stationary points: along each edge, v is a 1-D quadratic in t through its three nodal values
    for k in range(3):
        i, j = (k + 1) % 3, (k + 2) % 3
        vi, vm, vj = v[:, i], v[:, 3 + k], v[:, j]
        # q(t) = vi (1−t)(1−2t) + vm 4t(1−t) + vj t(2t−1); q'(t) = 0
        A2 = 2 * vi - 4 * vm + 2 * vj
        B1 = -3 * vi + 4 * vm - vj
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.clip(-B1 / (2 * A2), 0.0, 1.0)
        t = np.where(np.isfinite(t), t, 0.5)
        bb = np.zeros((m, 3))
        bb[:, i] = 1 - t
        bb[:, j] = t
        cands.append(bb[:, None])
    C = np.concatenate(cands, axis=1)  # (m, c, 3)
    inside = (C >= -1e-12).all(axis=2)
    C = np.clip(C, 0.0, None)
    C /= C.sum(axis=2, keepdims=True)
    Nc = at(C)  # (m, c, 6)
    vc = np.einsum("tca,ta->tc", Nc, v)
    vc[~inside] = -np.inf
    best = np.argmax(vc, axis=1)
    r = np.arange(m)
    vmax = vc[r, best]
    vmax[space.degenerate] = 0.0
    bary = C[r, best]
    phi_at = np.einsum("ta,ta->t", Nc[r, best], xf)
    return vmax, bary, phi_at


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
    from .solvers._interrupt import interruptible
    from .solvers.clarabel_backend import clarabel_settings

    t0 = time.perf_counter()
    solver = clarabel.DefaultSolver(sp.csc_matrix((free.size, free.size)), problem.c[free], A, b, cones,
                                    clarabel_settings(tol, max_iter, verbose))
    with interruptible(solver):  # Ctrl-C stops the solve at the next iteration
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


class SplitMesh:
    """A mesh with source points inserted as vertices (each face holding one is split into 2 or 3 faces).

    Face ``f`` of the original mesh keeps its index for its first piece; the other pieces are appended.
    Original vertices keep their indices; point ``i`` becomes vertex ``n + i``.

    Parameters
    ----------
    mesh : TriMesh
    points : list of objects with ``face`` and normalized ``bary`` (on an edge or inside a face)

    Raises
    ------
    SourceError
        Two points on one face.
    """

    def __init__(self, mesh: TriMesh, points):
        n = mesh.n_vertices
        F = [row for row in mesh.F.tolist()]
        V = [mesh.V]
        self.pieces: dict[int, list[tuple[int, int, np.ndarray]]] = {}  # face -> [(corner k, piece, bary)]
        new_ids = []
        for i, p in enumerate(points):
            vid = n + i
            new_ids.append(vid)
            V.append((p.bary @ mesh.V[mesh.F[p.face]])[None])
            nz = np.flatnonzero(p.bary > 0)
            corners = mesh.F[p.face, nz]
            if nz.size == 2:
                fs = np.flatnonzero((mesh.F == corners[0]).any(axis=1) & (mesh.F == corners[1]).any(axis=1))
            else:
                fs = np.array([p.face])
            for f in fs.tolist():
                if f in self.pieces:
                    raise SourceError(f"two source points on face {f}: order 2 takes at most one per face")
                beta = np.zeros(3)
                for kk in range(3):
                    hit = np.flatnonzero(corners == mesh.F[f, kk])
                    if hit.size:
                        beta[kk] = p.bary[nz[hit[0]]]
                lst = []
                for k in np.flatnonzero(beta > 0).tolist():
                    tri = list(mesh.F[f])
                    tri[k] = vid
                    if not lst:
                        F[f] = tri
                        idx = f
                    else:
                        F.append(tri)
                        idx = len(F) - 1
                    lst.append((k, idx, beta))
                self.pieces[f] = lst
        self.mesh = TriMesh(np.vstack(V), np.asarray(F, dtype=np.int64), name=mesh.name)
        self.point_vertices = np.asarray(new_ids, dtype=np.int64)
        self.n_original = n

    def locate(self, faces: np.ndarray, bary: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Original (face, bary) pairs → (piece, bary in the piece)."""
        faces = faces.copy()
        bary = bary.copy()
        for r, f in enumerate(faces.tolist()):
            lst = self.pieces.get(f)
            if not lst:
                continue
            lam = bary[r]
            beta = lst[0][2]
            ratios = [lam[k] / beta[k] for k, _, _ in lst]
            j = int(np.argmin(ratios))
            k, idx, _ = lst[j]
            mu = lam - ratios[j] * beta
            mu[k] = ratios[j]  # corner k of the piece is the inserted point
            mu = np.clip(mu, 0.0, None)
            faces[r], bary[r] = idx, mu / mu.sum()
        return faces, bary


class SplitP2Field(P2Field):
    """:class:`P2Field` of a :class:`SplitMesh`, queried with the original mesh's faces."""

    def __init__(self, original: TriMesh, split: SplitMesh, phi: np.ndarray, space: P2Space | None = None):
        super().__init__(split.mesh, phi, space)
        self.original = original
        self.split = split

    @property
    def vertex_distance(self) -> np.ndarray:
        return super().vertex_distance[: self.split.n_original]

    def squared_distance_at(self, faces, bary) -> np.ndarray:
        faces = np.atleast_1d(np.asarray(faces))
        bary = np.atleast_2d(np.asarray(bary, dtype=float))
        if faces.ndim == 1 and np.issubdtype(faces.dtype, np.integer) and bary.shape == (faces.size, 3) \
                and (faces.size == 0 or (faces.min() >= 0 and faces.max() < self.original.n_faces)):
            faces, bary = self.split.locate(faces, bary)
        else:
            raise ParameterError(f"faces must be indices in [0, {self.original.n_faces}) and bary of shape (k, 3)")
        return super().squared_distance_at(faces, bary)


def p2_field_at(field_: P2Field, faces, bary) -> np.ndarray:
    """Distance at points inside faces of a :class:`P2Field` (``field_.distance_at``)."""
    return field_.distance_at(faces, bary)


# --------------------------------------------------------------------------- API strategy
ORDER2_METHODS = ("qclp",)


def _default_backend() -> str:
    try:
        from .solvers import ipm_soc  # noqa: F401
    except ImportError:
        return "clarabel"
    return "ipm"


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

    def __init__(self, solver, backend: str = "auto", *, samples: str = DEFAULT_SAMPLES, weights: str | None = None,
                 refine: int = 4):
        weights = DEFAULT_WEIGHTS if weights is None else weights
        from .mesh.trimesh import unit_mesh as _unit_mesh

        if solver.method not in ORDER2_METHODS:
            raise ParameterError(
                f"order=2 is implemented for {', '.join(ORDER2_METHODS)}, not for {solver.method!r} "
                "(no consistent P2 smoothing energy for d² yet; see docs/order2.md)")
        self.owner = solver
        self.samples, self.weights, self.refine = samples, weights, int(refine)
        unit, self.scale = _unit_mesh(solver.mesh)
        self.builder = P2Builder(unit, samples=samples, weights=weights)
        # "auto": the structured solver, with Clarabel as its fallback. Measured: it solved all 53 coarse CAD
        # meshes ("optimal", no fallback) and was more accurate on needles with a source inside a face (1.9e-6
        # against Clarabel's 2.5e-5 at aspect 240); with its compiled kernels and correctors it is about twice as
        # fast as Clarabel on spot and bunny_7k (2026-12-01; before them 2–3× slower up to 7K faces; docs/order2.md)
        self._notes: list[str] = []
        if backend == "auto":
            self.backend = "clarabel"
            if unit.n_faces >= IPM_MIN_FACES:
                self.backend = _default_backend()
                if self.backend == "clarabel":
                    self._notes.append("the order-2 interior-point solver is not available in this installation "
                                       "(it needs Numba); solved with Clarabel")
        else:
            self.backend = backend
        self._fallback = backend == "auto"
        self._ipm = None
        if self.backend == "ipm":
            if _default_backend() != "ipm":
                raise ParameterError("solver='ipm' is not available in this installation (order 2 needs Numba)")
            from .solvers.ipm_soc import P2InteriorPoint

            self._ipm = P2InteriorPoint(self.builder)

    def _solve_once(self, problem: P2Problem, ipm, callback, notes: list[str]) -> dict:
        """One conic solve: the structured solver, with Clarabel as the fallback under ``solver="auto"``."""
        own = self.owner
        if ipm is not None:
            try:
                res = ipm.solve(problem, tol=own.tol, max_iter=own.max_iter, callback=callback)
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
        return res

    def solve(self, sources, callback=None):
        from .results import GeodesicResult, SolveInfo

        t0 = time.perf_counter()
        own = self.owner
        vsrc, points = parse_sources(sources, own.mesh)
        builder, split, ipm = self.builder, None, self._ipm
        if points:
            # a point inside a face becomes a vertex of a locally split mesh (measured: imposing φ(p) = 0,
            # ∇φ(p) = 0 on the unsplit face leaves 2–7e-3 errors on a flat grid; see docs/order2.md)
            split = SplitMesh(own.mesh, points)
            # the inserted points lie in the mesh's faces, so the bounding box and the unit scale do not change
            sm = split.mesh
            unit = TriMesh(sm.V / self.scale, sm.F, name=sm.name) if self.scale != 1.0 else sm
            builder = P2Builder(unit, samples=self.samples, weights=self.weights)
            if ipm is not None:
                from .solvers.ipm_soc import P2InteriorPoint

                ipm = P2InteriorPoint(builder)
            sources = np.concatenate([vsrc, split.point_vertices])
        problem = builder.build(sources)
        notes = list(problem.notes) + self._notes
        res = self._solve_once(problem, ipm, callback, notes)
        # cutting planes on flat patches: the corner/midpoint cones leave |∇φ|² ≤ 4φ free between the samples, and
        # there d² is exactly quadratic, so a cone at each face's worst point closes the gap (docs/order2.md)
        flat = builder.space.flat_faces
        extra_f, extra_b = np.zeros(0, dtype=np.int64), np.zeros((0, 3))
        rounds = 0
        while rounds < self.refine and flat.any():
            x = np.where(problem.fixed, 0.0, res["x"])
            vmax, bary, phi_at = max_violation(builder.space, x)
            rel = vmax / np.maximum(4 * phi_at, 1e-300)
            add = np.flatnonzero(flat & (rel > REFINE_TOL) & (vmax > 1e-15))
            if add.size == 0:
                break
            extra_f, extra_b = np.concatenate([extra_f, add]), np.concatenate([extra_b, bary[add]])
            cand = builder.build(sources, extra=(extra_f, extra_b))
            try:
                res_c = self._solve_once(cand, ipm, callback, notes)
            except SolverError:
                res_c = None
            if res_c is None or (res_c["status"] != "optimal" and res["status"] == "optimal"):
                # measured on a needle strip of aspect 1000: a round that only reached "almost" was worse (4.8e-5)
                # than the optimal solve before it (1.3e-7); keep the last fully solved round
                notes.append(f"cutting-plane round {rounds + 1} not fully solved; kept round {rounds}")
                extra_f, extra_b = extra_f[: extra_f.size - add.size], extra_b[: extra_b.shape[0] - add.size]
                break
            rounds += 1
            problem, res = cand, res_c
        if rounds:
            notes.append(f"{rounds} cutting-plane round(s) on flat faces added {extra_f.size} cone(s)")
        if split is not None:
            notes.append(f"{len(points)} source point(s) inserted as vertices ({split.mesh.n_faces - own.mesh.n_faces} "
                         "face(s) added; new symbolic analysis for this solve)")
        phi = res["x"] * self.scale**2
        n = own.mesh.n_vertices
        bm = builder.mesh
        E = bm.edges
        unreach = np.concatenate([problem.unreachable_vertices,
                                  problem.unreachable_vertices[E[:, 0]] | problem.unreachable_vertices[E[:, 1]]])
        phi[unreach] = np.inf
        if split is None:
            fld = P2Field(own.mesh, phi, builder.space)
        else:
            fld = SplitP2Field(own.mesh, split, phi, builder.space)
        d = fld.vertex_distance.copy()
        d[vsrc] = 0.0
        info = SolveInfo(
            method=own.method, solver=res["solver"], status=res["status"], iterations=res["iterations"],
            setup_time=own.setup_time, solve_time=time.perf_counter() - t0,
            primal_residual=res["primal_residual"], dual_residual=res["dual_residual"], gap=res["gap"],
            objective=res["objective"] * self.scale**2, lam=0.0, n_unreachable=int(np.isinf(d[:n]).sum()),
            notes=notes, extra={"order": 2, "p2_field": fld, "n_dofs": problem.n, "n_cones": problem.n_cones},
        )
        return GeodesicResult(distance=d, info=info, sources=vsrc)
