"""Assemble the paper's eight convex formulations (Table 1) as :class:`ConicProblem` s.

=================  ===========================  =================
name               constraints                  smoothness energy
=================  ===========================  =================
lclp               LC: |d_i − d_j| ≤ ℓ_ij        none
lcqp-dirichlet     LC                           Dirichlet (eq. 16)
lcqp-laplacian     LC                           Laplacian (eq. 17)
lcqp-hessian       LC  (= QGDF, Cao et al.)     Hessian (eq. 18)
qclp               QC: ‖∇d|_t‖ ≤ 1               none
qcqp-dirichlet     QC                           Dirichlet
qcqp-laplacian     QC                           Laplacian
qcqp-hessian       QC  (recommended)            Hessian
=================  ===========================  =================

Objective: minimize ``E_stretch + λ E_smooth`` with
``E_stretch = −(c/n) Σ_i d_i``, ``c = STRETCH_SCALE = 10``, and the paper's
weight ``λ = m · 10² · h / n`` (§4.2.3). Why: with the paper's literal
``−Σ d_i``, ``m = 1`` changes nothing measurable (the ``1/n`` in λ makes the
smoothing force ``n`` times weaker than the stretching force). With the mean
distance (``c = 1``) the ``n`` cancels, so the effect of ``m`` no longer depends
on the resolution or the scale of the mesh, but ``m = 1`` over-smooths (on
bimba the error off the ridge grows from 1.10 % to 1.35 %, the maximum error to
61 %). ``c = 10`` puts the paper's recommended ``m = 1`` where the paper's
pictures are: on spot and bimba the ridge's sharpness drops to about 40 % of the
exact field's (smoother than the heat method) while the error off the ridge
grows by 1–7 % (numbers in ``docs/method.md``). Both terms scale linearly with
the mesh, so the solution is exactly scale-equivariant.

Sources (DESIGN §1, "Situation #1"): source vertices are fixed at 0. The exact
field is a cone around a source, steeper than 1 on the source's incident
triangles when measured piecewise linearly, so the QC is dropped there, as in
the paper. Instead of fixing the one-ring to its Euclidean distance (which can
be infeasible next to obtuse triangles), each source-star edge gets the linear
bound ``d_j ≤ d_s + ‖v_j − v_s‖``: the problem stays feasible (``d = 0`` is
always feasible) and bounded, and the maximization drives the one-ring to the
Euclidean distance wherever the other constraints allow it. The LC
formulations keep every edge constraint (Lemma 1 then makes LCLP equal to
Dijkstra).

Vertices in connected components without a source are fixed and reported as
``inf``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .errors import ParameterError, SourceError
from .mesh.trimesh import TriMesh
from .operators import energy_matrix, gradient_blocks
from .solvers.problem import ConicProblem

FORMULATIONS: dict[str, tuple[str, str | None]] = {
    "lclp": ("lc", None),
    "lcqp-dirichlet": ("lc", "dirichlet"),
    "lcqp-laplacian": ("lc", "laplacian"),
    "lcqp-hessian": ("lc", "hessian"),
    "qclp": ("qc", None),
    "qcqp-dirichlet": ("qc", "dirichlet"),
    "qcqp-laplacian": ("qc", "laplacian"),
    "qcqp-hessian": ("qc", "hessian"),
}
ALIASES = {"qgdf": "lcqp-hessian"}

#: ``c`` in ``E_stretch = −(c/n) Σ d_i``: calibrates the paper's ``m`` (see module docstring).
STRETCH_SCALE = 10.0
STRETCH_WEIGHTS = {"calibrated": lambda n: STRETCH_SCALE / n, "mean": lambda n: 1.0 / n, "sum": lambda n: 1.0}


def canonical_method(method: str) -> str:
    """Lower-case formulation name with aliases resolved; raises ParameterError if unknown."""
    if not isinstance(method, str):
        raise ParameterError(f"method must be a string, got {type(method).__name__}")
    name = ALIASES.get(method.lower(), method.lower())
    if name not in FORMULATIONS:
        raise ParameterError(f"unknown formulation {method!r}; choose one of {', '.join([*FORMULATIONS, *ALIASES])}")
    return name


def smoothness_weight(mesh: TriMesh, m: float) -> float:
    """The paper's weight ``λ = m · 10² · h / n`` (§4.2.3).

    Parameters
    ----------
    mesh : TriMesh
    m : float
        Dimensionless multiplier (the paper recommends 1).

    Returns
    -------
    float
        ``h`` is the mean edge length, ``n`` the number of vertices.
    """
    return float(m) * 100.0 * mesh.mean_edge_length / mesh.n_vertices


def validate_sources(sources, n: int) -> np.ndarray:
    """Check and normalize source vertex indices.

    Parameters
    ----------
    sources : int or sequence of int
    n : int
        Number of vertices.

    Returns
    -------
    (k,) int64 ndarray
        The indices, in the given order.

    Raises
    ------
    SourceError
        Empty, non-integer, negative, out-of-range or duplicated indices.
    """
    if isinstance(sources, bool | np.bool_):
        raise SourceError(f"sources must be vertex indices, got {sources!r}")
    arr = np.atleast_1d(np.asarray(sources))
    if arr.ndim != 1:
        raise SourceError(f"sources must be an int or a 1-D sequence of ints, got shape {arr.shape}")
    if arr.size == 0:
        raise SourceError("sources is empty: give at least one source vertex")
    if arr.dtype.kind == "f" and np.all(np.isfinite(arr)) and np.all(arr == np.round(arr)):
        arr = arr.astype(np.int64)
    if arr.dtype.kind not in "iu":
        raise SourceError(f"sources must be integer vertex indices, got {sources!r}")
    arr = arr.astype(np.int64)
    bad = (arr < 0) | (arr >= n)
    if bad.any():
        raise SourceError(f"source index {int(arr[bad][0])} is out of range: the mesh has {n} vertices (0..{n - 1})")
    uniq, counts = np.unique(arr, return_counts=True)
    if (counts > 1).any():
        raise SourceError(f"source vertex {int(uniq[counts > 1][0])} is given more than once")
    return arr


@dataclass
class MeshOperators:
    """Per-mesh data shared by every solve: gradient blocks and energy matrices (built lazily)."""

    mesh: TriMesh

    def __post_init__(self):
        self._blocks = None
        self._energies: dict[str, sp.csc_matrix] = {}

    @property
    def gradient_blocks(self) -> np.ndarray:
        if self._blocks is None:
            self._blocks = gradient_blocks(self.mesh)
        return self._blocks

    def energy(self, name: str) -> sp.csc_matrix:
        if name not in self._energies:
            self._energies[name] = energy_matrix(self.mesh, name)
        return self._energies[name]


def build_problem(
    ops: MeshOperators,
    sources: np.ndarray,
    method: str,
    lam: float,
    *,
    stretch: str = "calibrated",
) -> ConicProblem:
    """Assemble one formulation for given sources.

    Parameters
    ----------
    ops : MeshOperators
    sources : (k,) int64 ndarray
        Validated source vertices.
    method : str
        A name of :data:`FORMULATIONS` (aliases allowed).
    lam : float
        Smoothness weight λ (ignored by lclp / qclp).
    stretch : {"calibrated", "mean", "sum"}
        Normalization of ``E_stretch``: ``−(10/n) Σd`` (default, see module
        docstring), ``−Σd/n`` or the paper's literal ``−Σd``. The alternatives
        exist to reproduce the normalization study in ``docs/method.md``.

    Returns
    -------
    ConicProblem
    """
    mesh = ops.mesh
    n = mesh.n_vertices
    constraint, energy = FORMULATIONS[canonical_method(method)]
    if not np.isfinite(lam) or lam < 0:
        raise ParameterError(f"smoothness weight lambda must be finite and >= 0, got {lam}")

    labels = mesh.component_labels
    unreachable = ~np.isin(labels, labels[sources])
    in_face = np.zeros(n, dtype=bool)
    in_face[mesh.F.ravel()] = True
    unreachable |= ~in_face
    fixed_mask = unreachable.copy()
    fixed_mask[sources] = True
    fixed_values = np.zeros(n)

    if stretch not in STRETCH_WEIGHTS:
        raise ParameterError(f"stretch must be one of {', '.join(STRETCH_WEIGHTS)}, got {stretch!r}")
    weight = STRETCH_WEIGHTS[stretch](n)
    q = np.where(fixed_mask, 0.0, -weight)

    F = mesh.F
    face_free = ~fixed_mask[F].all(axis=1)
    if constraint == "qc":
        is_source = np.zeros(n, dtype=bool)
        is_source[sources] = True
        keep = face_free & ~is_source[F].any(axis=1)
        cone_vertices = np.ascontiguousarray(F[keep])
        cone_blocks = np.ascontiguousarray(ops.gradient_blocks[keep])
        E, ell = mesh.edges, mesh.edge_lengths
        star = is_source[E[:, 0]] ^ is_source[E[:, 1]]
        s_end = np.where(is_source[E[star, 0]], E[star, 0], E[star, 1])
        o_end = np.where(is_source[E[star, 0]], E[star, 1], E[star, 0])
        # d_j - d_s <= |v_j - v_s|; with d_s fixed at 0 this is a bound on d_j
        ineq_vertices = np.column_stack([o_end, s_end])
        ineq_coeffs = np.tile([1.0, -1.0], (len(o_end), 1))
        ineq_rhs = ell[star].copy()
    else:
        cone_vertices = np.zeros((0, 3), dtype=np.int64)
        cone_blocks = np.zeros((0, 2, 3))
        E, ell = mesh.edges, mesh.edge_lengths
        keep = ~fixed_mask[E].all(axis=1)
        E, ell = E[keep], ell[keep]
        ineq_vertices = np.vstack([E, E])
        ineq_coeffs = np.vstack([np.tile([1.0, -1.0], (len(E), 1)), np.tile([-1.0, 1.0], (len(E), 1))])
        ineq_rhs = np.concatenate([ell, ell])

    P = None
    if energy is not None and lam > 0:
        P = sp.csc_matrix(2.0 * lam * ops.energy(energy))

    return ConicProblem(
        n=n, P=P, q=q,
        cone_vertices=cone_vertices, cone_blocks=cone_blocks,
        ineq_vertices=np.ascontiguousarray(ineq_vertices, dtype=np.int64),
        ineq_coeffs=np.ascontiguousarray(ineq_coeffs), ineq_rhs=ineq_rhs,
        fixed_mask=fixed_mask, fixed_values=fixed_values, unreachable=unreachable,
        method=canonical_method(method),
    )
