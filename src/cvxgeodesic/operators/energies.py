"""The three smoothness energies of the paper, as quadratic forms ``E(d) = dᵀ Q d``."""

from __future__ import annotations

from collections.abc import Callable
from typing import cast

import igl
import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike

from ..errors import IndefiniteEnergyWarning, MeshRepairWarning, ParameterError, warn_user
from ..linalg import SymbolicCholesky, is_positive_semidefinite
from ..mesh.cover import manifold_cover, pull_back
from ..mesh.orient import orient_faces
from ..mesh.patch import is_patch
from ..mesh.reference import TRIANGLE
from ..mesh.simplex import SimplexMesh
from ..mesh.trimesh import TriMesh
from . import curved_hessian
from .gradient import gradient_blocks, gradient_matrix
from .laplacian import barycentric_mass, cotan_stiffness, mass_matrix, selected_cells

ENERGIES = ("dirichlet", "laplacian", "hessian")


def _measure(mesh: SimplexMesh, cells: ArrayLike | None) -> float:
    """The area (volume) of the assembled cells: every cell's, or those of ``cells``."""
    return mesh.total_measure if cells is None else float(mesh.cell_measures[selected_cells(mesh, cells)].sum())


def dirichlet_energy_matrix(mesh: SimplexMesh, *, cells: ArrayLike | None = None) -> sp.csc_matrix:
    """Measure-normalized Dirichlet energy (paper eq. 16).

    ``E(d) = Σ_t |t| ‖∇d|_t‖² / Σ_t |t| = dᵀ Q d`` with ``Q = S / |Ω|`` (``E = 1`` for a field of unit gradient).

    Parameters
    ----------
    mesh : SimplexMesh
    cells : (s,) int or (k,) bool array_like, optional
        Cells to assemble (:func:`~.laplacian.cotan_stiffness`).

    Returns
    -------
    (n, n) scipy.sparse.csc_matrix, symmetric PSD
    """
    return sp.csc_matrix(cotan_stiffness(mesh, cells=cells) / _measure(mesh, cells))


def laplacian_energy_matrix(mesh: SimplexMesh, *, cells: ArrayLike | None = None) -> sp.csc_matrix:
    """Squared-Laplacian energy (paper eq. 17): ``Q = S M⁻¹ S``.

    ``S`` is the cotangent stiffness matrix and ``M`` the lumped mass (:func:`~.laplacian.mass_matrix`, or the
    barycentric mass of ``cells``). Vertices with zero mass (unreferenced) get no contribution.

    Parameters
    ----------
    mesh : SimplexMesh
    cells : (s,) int or (k,) bool array_like, optional
        Cells to assemble.

    Returns
    -------
    (n, n) scipy.sparse.csc_matrix, symmetric PSD
    """
    mass = (mass_matrix(mesh) if cells is None else barycentric_mass(mesh, cells=cells)).diagonal()
    return _squared_laplacian(cotan_stiffness(mesh, cells=cells), mass)


def _squared_laplacian(S: sp.spmatrix, mass: np.ndarray) -> sp.csc_matrix:
    """``S M⁻¹ S``, symmetrized, for a stiffness ``S`` and a lumped mass diagonal ``mass`` (0 rows get nothing)."""
    inv = np.zeros_like(mass)
    np.divide(1.0, mass, out=inv, where=mass > 0)
    Q = S @ sp.diags(inv) @ S
    return sp.csc_matrix(0.5 * (Q + Q.T))


def hessian_energy_matrix(mesh: TriMesh, notes: list[str] | None = None, *,
                          analyse: Callable[[sp.csc_matrix], SymbolicCholesky] | None = None,
                          planar: bool | None = None) -> sp.csc_matrix:
    """Curved-surface Hessian energy (paper eq. 18; Stein et al. TOG 2020) via libigl.

    ``E(d) = dᵀ Q d ≈ ∫ ‖Hess d‖² dA``. It vanishes on functions linear on a
    flat mesh and, unlike the planar Hessian energy, has no boundary bias.

    The discretization uses edge (Crouzeix–Raviart) elements and needs an
    edge-manifold mesh. On a mesh with an edge of more than two faces the
    energy is built on :func:`~cvxgeodesic.mesh.cover.manifold_cover` (the mesh
    cut along its non-manifold edges, each sheet a surface with that edge on its
    boundary) and pulled back to the mesh's vertices.

    Parameters
    ----------
    mesh : TriMesh
    notes : list of str, optional
        Gets one line per substitution made (manifold cover, planar energy).
    analyse : callable, optional
        ``analyse(Q)`` returns a symbolic analysis of a pattern containing the curved energy ``Q`` (the caller's
        own, e.g. the interior-point solver's, which it keeps); the PSD check then factors ``Q`` in it
        (:func:`~cvxgeodesic.linalg.is_positive_semidefinite`, ``analysis=``). Not called on a manifold cover
        (the cover has vertices of its own).
    planar : bool, optional
        None (default): the curved energy, or the planar one where the curved one is indefinite (the check
        below). False: the curved energy, unchecked (for a caller that factorizes a part of it and checks that,
        as the ridge rounding does on the faces near a band, whose cut edges can make the whole indefinite).
        True: the planar energy.

    Warns
    -----
    IndefiniteEnergyWarning
        The curved energy has a negative eigenvalue on this mesh (checked with one
        PARDISO or CHOLMOD factorization; skipped without either): the planar
        Hessian energy of Stein et al. 2018 (libigl ``hessian_energy``), which is
        PSD, is returned instead.

    Returns
    -------
    (n, n) scipy.sparse.csc_matrix, symmetric PSD
    """
    notes = [] if notes is None else notes
    energy_mesh, to_mesh = mesh, None
    if not mesh.is_edge_manifold:
        bad = int(np.sum(mesh.edge_cell_counts > 2))
        energy_mesh, to_mesh = manifold_cover(mesh)
        notes.append(f"{mesh.name}: {bad} non-manifold edge(s); the Hessian energy is built on the mesh cut along "
                     f"them ({energy_mesh.n_vertices} vertices instead of {int(mesh.referenced.sum())})")
        if not energy_mesh.is_edge_manifold:  # a sheet that closes up around a vertex of a non-manifold edge
            keep = ~(energy_mesh.edge_cell_counts[energy_mesh.cell_edges] > 2).any(axis=1)
            notes.append(f"{mesh.name}: {int((~keep).sum())} face(s) whose non-manifold edge the cut cannot open "
                         "carry no Hessian energy")
            energy_mesh = TriMesh(energy_mesh.V, energy_mesh.F[keep], name=energy_mesh.name)
    energy_mesh = _oriented(energy_mesh, notes)
    n = energy_mesh.n_vertices
    if not planar:
        Q = curved_hessian_energy(energy_mesh)
        analysis = analyse(Q) if analyse is not None and to_mesh is None else None
        if planar is None and is_positive_semidefinite(Q, analysis=analysis) is False:
            # measured: lucy_20k and thingi_37881 (min eigenvalue -59 against a largest diagonal of 1.2e7); the
            # curvature correction of the curved energy is not PSD where the angle defect is large, and the QP would
            # then be non-convex. The planar Hessian energy (Stein et al. 2018) is PSD by construction.
            # a local row's patch (measured: every patch of spot at r = 10 % of the diagonal, not the whole mesh)
            where = ("on this patch, not necessarily on the whole mesh" if is_patch(mesh)
                     else "on this mesh (sharp corners or large angle defects)")
            message = (f"{mesh.name}: libigl's curved Hessian energy is indefinite {where}; using the planar Hessian "
                       "energy (Stein et al. 2018) instead")
            warn_user(message, IndefiniteEnergyWarning)
            notes.append(message)
            planar = True
    if planar:
        Q = _padded_symmetric(igl.hessian_energy(energy_mesh.V, energy_mesh.F), n)
    return Q if to_mesh is None else pull_back(Q, to_mesh, mesh.n_vertices)


def _oriented(mesh: TriMesh, notes: list[str]) -> TriMesh:
    """``mesh`` with its faces oriented consistently (:func:`~cvxgeodesic.mesh.orient.orient_faces`), noted and
    warned. Measured: reversing every other face of an icosphere changed libigl's curved Hessian energy by a quarter
    of its largest entry and ``qcqp-hessian``'s field by 7e-5 of its maximum (a global reversal changes nothing)."""
    orientation = orient_faces(mesh.F, mesh.n_vertices)
    note = orientation.note(mesh.name, "the curved Hessian energy")
    if note is None:
        return mesh
    warn_user(note, MeshRepairWarning)
    notes.append(note)
    return TriMesh(mesh.V, orientation.F, name=mesh.name) if orientation.flipped.any() else mesh


def curved_hessian_face_data(mesh: TriMesh) -> tuple:
    """The per-face inputs of the face-by-face curved Hessian assembly (:mod:`.curved_hessian`).

    Returns ``(F, E, n_edges, lsq, dA, theta, minv, sk)``: faces (m, 3) and their edges (m, 3) as contiguous
    int64, the edge count, squared edge lengths (m, 3), doubled areas (m,), corner angles (m, 3), the inverse
    Crouzeix–Raviart edge masses (n_edges,) (0 on a massless edge) and each vertex's angle defect over its angle
    sum (n,) (0 on the boundary, as libigl).
    """
    V = np.ascontiguousarray(mesh.V, dtype=np.float64)
    F = np.ascontiguousarray(mesh.F, dtype=np.int64)
    E = np.ascontiguousarray(mesh.cell_edges, dtype=np.int64)
    n, n_edges = mesh.n_vertices, len(mesh.edges)
    lsq, dA, theta = curved_hessian.face_geometry(V, F)
    mass = np.bincount(E.ravel(), weights=np.repeat(dA / 6.0, 3), minlength=n_edges)
    minv = np.zeros(n_edges)
    np.divide(1.0, mass, out=minv, where=mass > 0)
    angle_sum = np.bincount(F.ravel(), weights=theta.ravel(), minlength=n)
    defect = 2.0 * np.pi - angle_sum
    defect[mesh.edges[mesh.edge_cell_counts == 1].ravel()] = 0.0  # libigl: no curvature on the boundary
    sk = np.zeros(n)
    np.divide(defect, angle_sum, out=sk, where=angle_sum > 0)
    return F, E, n_edges, lsq, dA, theta, minv, sk


def curved_hessian_energy(mesh: TriMesh, *, libigl: bool = False) -> sp.csc_matrix:
    """libigl's curved Hessian energy matrix (``igl.curved_hessian_energy``), symmetrized, sized (n, n).

    Parameters
    ----------
    mesh : TriMesh
    libigl : bool, optional
        ``False`` (default): the face-by-face assembly of :mod:`.curved_hessian` (the same matrix to rounding,
        3e-16 of its largest entry; 4-8x faster than libigl's products on bimba and a 1.1M-face bunny,
        docs/dev/performance-log.md "Set-up cost"); ``True``: libigl's. libigl's is used anyway on a mesh that is
        not edge-manifold and where the face-by-face assembly has non-finite entries (degenerate faces).

    Returns
    -------
    (n, n) scipy.sparse.csc_matrix
        Symmetric, on the structural pattern of libigl's product less the entries that are exactly 0 (as
        libigl's after SciPy's symmetrization).
    """
    if libigl or not mesh.is_edge_manifold:
        return _padded_symmetric(igl.curved_hessian_energy(mesh.V, mesh.F), mesh.n_vertices)
    F, E, n_edges, lsq, dA, theta, minv, sk = curved_hessian_face_data(mesh)
    Q = curved_hessian.energy_matrix(F, E, n_edges, lsq, dA, theta, minv, sk, mesh.n_vertices)
    if Q is None:
        # faces without a proper shape (zero area, zero-length edges) give inf/nan in both assemblies, where they
        # need not agree: libigl's is the reference
        return _padded_symmetric(igl.curved_hessian_energy(mesh.V, mesh.F), mesh.n_vertices)
    # exact zeros (cancelling contributions) are dropped, as SciPy's symmetrization of libigl's matrix drops them,
    # so that both give one pattern
    Q.eliminate_zeros()
    return Q


def _padded_symmetric(Q, n: int) -> sp.csc_matrix:
    """Symmetrized (n, n) copy; libigl sizes its matrices by the largest referenced vertex index + 1."""
    Q = sp.coo_matrix(Q)
    Q = sp.csc_matrix((Q.data, (Q.row, Q.col)), shape=(n, n))
    return sp.csc_matrix(0.5 * (Q + Q.T))


def metric_stiffness(mesh: TriMesh, transforms: np.ndarray, area_ratio: np.ndarray) -> sp.csc_matrix:
    """The stiffness matrix in a metric: ``dᵀ S d = Σ_t A^M_t ‖T_t ∇d|_t‖²`` (``A^M_t = A_t · area_ratio_t``).

    Parameters
    ----------
    mesh : TriMesh
    transforms : (m, 2, 2) float ndarray
        :attr:`~cvxgeodesic.operators.metric.Medium.face_transforms` (``‖T g‖`` the gradient's norm in the metric).
    area_ratio : (m,) float ndarray

    Returns
    -------
    (n, n) scipy.sparse.csc_matrix, symmetric PSD
        :func:`~cvxgeodesic.operators.cotan_stiffness` when the metric is a constant multiple of the identity (the
        cotangent weights do not see a uniform scaling).
    """
    with np.errstate(invalid="ignore"):
        B = np.einsum("tij,tjk->tik", transforms, gradient_blocks(mesh))
    B = np.where(np.isfinite(B), B, 0.0)
    G = gradient_matrix(mesh, B)
    w = np.repeat(mesh.face_areas * area_ratio, 2)
    S = G.T @ sp.diags(w) @ G
    return sp.csc_matrix(0.5 * (S + S.T))


def _metric_energy(mesh: TriMesh, energy: str, face_metric: tuple[np.ndarray, np.ndarray], notes: list[str],
                   analyse: Callable[[sp.csc_matrix], SymbolicCholesky] | None) -> sp.csc_matrix:
    """The named energy of the surface measured in a metric (a travel cost is the metric ``c² I``).

    Dirichlet: the metric stiffness over the metric area. Laplacian: ``S_M M_M⁻¹ S_M`` with the mixed-Voronoi mass
    times each vertex's mean area ratio (area-weighted over its faces). Hessian: the Euclidean curved Hessian energy
    divided by the surface's mean area ratio (noted): exactly the energy of the surface scaled by ``c`` for a
    constant cost ``c``, and a uniform stand-in otherwise. All three are then, for a constant cost, those of the
    mesh scaled by ``c``, so the field is ``c`` times the unweighted one.
    """
    T, ratio = face_metric
    A = mesh.face_areas
    mean_ratio = float((A * ratio).sum() / A.sum())
    if energy == "hessian":
        notes.append(f"{mesh.name}: with a travel cost or metric, the Hessian energy is the Euclidean surface's "
                     "divided by the mean area ratio of the medium (exact for a constant cost; the Dirichlet and "
                     "Laplacian energies use the metric itself)")
        Q = hessian_energy_matrix(mesh, notes, analyse=analyse)  # a csc_matrix
        Q.data /= mean_ratio  # in place: a symbolic analysis ``analyse`` made for this very matrix stays its own
        return Q
    S = metric_stiffness(mesh, T, ratio)
    if energy == "dirichlet":
        return sp.csc_matrix(S / float((A * ratio).sum()))
    n = mesh.n_vertices
    num = np.bincount(mesh.F.ravel(), weights=np.repeat(A * ratio, 3), minlength=n)
    den = np.bincount(mesh.F.ravel(), weights=np.repeat(A, 3), minlength=n)
    vr = np.ones(n)
    np.divide(num, den, out=vr, where=den > 0)
    return _squared_laplacian(S, mass_matrix(mesh).diagonal() * vr)


def check_energy(mesh: SimplexMesh, energy: str) -> str:
    """``energy`` when it is one of :data:`ENERGIES` that ``mesh``'s cells have (the curved Hessian energy is built on
    triangles); ParameterError otherwise. Which method takes which energy on which domain is the capability table's
    (:data:`cvxgeodesic.capabilities.RULES`), checked at the API edge; this is the energies' own argument check."""
    allowed = ENERGIES if mesh.reference is TRIANGLE else tuple(e for e in ENERGIES if e != "hessian")
    if energy not in allowed:
        raise ParameterError(f"energy {energy!r} does not apply to {mesh.reference.words.meshes}; use "
                             f"{' or '.join(map(repr, allowed))}")
    return energy


def energy_matrix(mesh: SimplexMesh, energy: str, notes: list[str] | None = None, *,
                  analyse: Callable[[sp.csc_matrix], SymbolicCholesky] | None = None,
                  face_metric: tuple[np.ndarray, np.ndarray] | None = None,
                  cells: ArrayLike | None = None) -> sp.csc_matrix:
    """The matrix of a named energy (``"dirichlet"``, ``"laplacian"`` or, on triangles, ``"hessian"``).

    ``notes`` (optional list) gets one line per substitution made while building it; ``analyse`` is passed to
    :func:`hessian_energy_matrix` (the other energies are PSD by construction and have no check).
    ``face_metric``, ``(transforms (m, 2, 2), area_ratio (m,))`` of a travel cost or metric
    (:class:`~cvxgeodesic.operators.metric.Medium`, surfaces only), measures the energy in it
    (:func:`_metric_energy`). ``cells`` (indices or mask) assembles the energy on those cells only. The Laplacian
    energy is divided by ``(|Ω|^(1/dim))^(dim − 2)`` (``mesh.reference.measure_root``): ``∫ (Δd)² dV`` has the units
    of a length to the ``dim − 2`` (a length in a solid, dimensionless on a surface), so that one smoothness weight
    means one rounding at every scale.

    Raises
    ------
    ParameterError
        An energy not defined on the mesh's dimension (:func:`check_energy`).
    """
    check_energy(mesh, energy)
    if cells is not None and mesh.reference.libigl_operators:  # libigl's operators take a mesh: the kept triangles
        mesh, cells = TriMesh(mesh.V, mesh.cells[selected_cells(mesh, cells)], name=mesh.name), None
    # a medium and the curved Hessian energy are surface notions: the capability table admits them on surfaces only
    if face_metric is not None:
        return _metric_energy(cast(TriMesh, mesh), energy, face_metric, [] if notes is None else notes, analyse)
    if energy == "hessian":
        return hessian_energy_matrix(cast(TriMesh, mesh), notes, analyse=analyse)
    if energy == "dirichlet":
        return dirichlet_energy_matrix(mesh, cells=cells)
    Q = laplacian_energy_matrix(mesh, cells=cells)
    return sp.csc_matrix(Q / mesh.reference.measure_root(_measure(mesh, cells)) ** (mesh.dim - 2))
