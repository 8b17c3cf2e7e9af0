"""Ridge rounding: a distance field's cut locus rounded over a length, the rest of the field left as it is.

An order-2 field read at the user's vertices (an adapted solve, :mod:`cvxgeodesic.strategies.adapted`) is as creased
at the ridge as the exact field, and the order-2 smoothness energy of ``φ = d²`` rounds that crease only by flattening
the whole field (docs/dev/adapted-log.md, "The default switch"). :func:`round_ridge` rounds the ridge alone: in a band
around the field's own cut locus (:func:`~cvxgeodesic.operators.ridge.cut_locus_band` of the field, every vertex
within :data:`RIDGE_BAND` lengths of it) the values are replaced by the minimizer of

    ``∫ |∇²u|² dA + ℓ⁻⁴ ∫ (u − d)² dA``  (the curved Hessian energy, the barycentric mass)

with ``u = d`` outside the band: a convex quadratic problem, one sparse Cholesky factorization of the band's size.
The energy's rows in the band are built on the faces near it (:func:`band_energy_rows`: the whole mesh's rows, at a
fraction of the cost); where the band's block is not positive definite (the curved energy's curvature term is
indefinite where angle defects are large), the planar Hessian energy of Stein et al. 2018 is used, with a note.
For a crease of the field rounded over a width ``w`` the first term is about ``θ² L / w`` and the second
``θ² L w³ / ℓ⁴`` (``θ`` its turn, ``L`` its length): they balance at ``w = ℓ``, the rounding width. Off the band the
field is unchanged bit for bit; a field without a ridge (one source on a plane) is returned as it is.

The default length is the order-1 Hessian energy's smoothing length at the multiplier ``m``
(:func:`~cvxgeodesic.problems.formulations.smoothing_length`: ``(m κ)^(1/3) √|S|``, 0.0144 √|S| at ``m = 1``) times
:data:`RIDGE_LENGTH`: a length on the surface, whatever the triangulation.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike

from ..linalg import NotPositiveDefiniteError, factor_matrix
from ..mesh.trimesh import TriMesh
from ..operators.energies import hessian_energy_matrix
from ..operators.laplacian import barycentric_mass
from ..operators.ridge import cut_locus_band, ring_dilate
from ..validation import as_vertex_field, check_number, check_type, vertex_indices
from .formulations import KAPPA

__all__ = ["ENERGY_RINGS", "RIDGE_BAND", "RIDGE_LENGTH", "RidgeRounding", "band_energy_rows", "ridge_rounding_length",
           "round_ridge"]

#: The rounding length is this times the order-1 Hessian energy's smoothing length at the multiplier ``m``.
#: Measured with ``RIDGE_BAND = 1`` on bimba, horse, bunny and armadillo (sources vertex 0 and n/2, the adapted
#: ``"auto"`` field): docs/dev/adapted-log.md, "Rounding the ridge".
RIDGE_LENGTH = 1.0
#: The band rounded: the vertices within this many rounding lengths (edge-graph distance) of the field's cut locus.
RIDGE_BAND = 1.0
#: :func:`band_energy_rows` builds the energy on the faces touching a vertex within this many rings of the band.
ENERGY_RINGS = 2


@dataclass(frozen=True)
class RidgeRounding:
    """What :func:`round_ridge` did.

    Attributes
    ----------
    distance : (n,) float ndarray
        The rounded field (the input outside ``band``).
    band : (n,) bool ndarray
        The vertices whose values were replaced.
    length : float
        The rounding length ``ℓ`` (the mesh's units).
    time : float
        Seconds (band, energy, factorization and solve).
    notes : tuple of str
        What the energy near the band needed (:func:`band_energy_rows`: a manifold cover, the faces' orientation)
        and the planar Hessian energy where the band's block of the curved one is not positive definite.
    """

    distance: np.ndarray
    band: np.ndarray
    length: float
    time: float
    notes: tuple[str, ...] = ()


def ridge_rounding_length(mesh: TriMesh, m: float = 1.0) -> float:
    """The default rounding length of :func:`round_ridge` at the multiplier ``m``: :data:`RIDGE_LENGTH` times
    ``(m κ)^(1/3) √|S|`` (``κ`` the Hessian energy's :data:`~cvxgeodesic.problems.formulations.KAPPA`, ``|S|`` the
    surface area).

    Examples
    --------
    >>> import cvxgeodesic as cg
    >>> round(ridge_rounding_length(cg.grid_plane(20)), 4)
    0.0144
    """
    m = check_number(m, "m", low=0, low_open=True)
    return RIDGE_LENGTH * float(np.cbrt(m * KAPPA["hessian"])) * float(np.sqrt(mesh.face_areas.sum()))


def band_energy_rows(mesh: TriMesh, band: np.ndarray, notes: list[str] | None = None, *,
                     planar: bool = False) -> sp.csr_matrix:
    """The Hessian energy's rows of the ``band`` vertices, built on the faces near the band only.

    A row of the curved Hessian energy (:func:`~cvxgeodesic.operators.energies.hessian_energy_matrix`) sums the
    blocks of the faces within one ring of its vertex; each block reads its face's neighbours across its edges, their
    edge masses and its corners' angle defects. So the faces touching a vertex within :data:`ENERGY_RINGS` rings of
    the band give the band's rows as the whole mesh's energy does (to rounding, on a mesh the energy takes as it is:
    ``tests/test_ridge_rounding.py``), at a fraction of its cost when the band is small.

    Parameters
    ----------
    mesh : TriMesh
    band : (n,) bool ndarray
    notes : list of str, optional
        Gets the energy's repairs (:func:`~cvxgeodesic.operators.energies.hessian_energy_matrix`: a manifold cover,
        the faces' orientation) on the faces near the band.
    planar : bool
        The planar Hessian energy instead of the curved one. The curved one is not checked here: its rows in the band
        are the whole mesh's, and :func:`round_ridge` checks the band's block by factorizing it.

    Returns
    -------
    (n, n) scipy.sparse.csr_matrix
        Exact in the rows of ``band``; the other rows are of the faces near the band.
    """
    near = ring_dilate(mesh, band, ENERGY_RINGS)
    faces = near[mesh.F].any(axis=1)
    local = mesh if faces.all() else TriMesh(mesh.V, mesh.F[faces], name=mesh.name)
    return sp.csr_matrix(hessian_energy_matrix(local, notes, planar=planar))


def round_ridge(mesh: TriMesh, distance: ArrayLike, sources: ArrayLike, *, length: float | None = None,
                m: float = 1.0) -> RidgeRounding:
    """Round a distance field's ridge (cut locus) over a length, leaving the rest of it as it is.

    Parameters
    ----------
    mesh : TriMesh
        A triangle surface with ``n`` vertices.
    distance : (n,) float array_like
        A distance field measured in the mesh's own lengths (unit speed: its ridge is found where its gradient norm
        drops below 0.9 or its normal derivative jumps across an edge); ``inf`` on unreached vertices, which stay so.
    sources : int or (k,) int array_like
        The vertices where the field is 0 by construction (no ridge is looked for next to them).
    length : float, optional
        The rounding width ``ℓ`` (> 0, the mesh's units); default :func:`ridge_rounding_length` at ``m``.
    m : float, default 1.0
        The multiplier of the default length.

    Returns
    -------
    RidgeRounding

    Raises
    ------
    TypeError
        ``mesh`` not a :class:`~cvxgeodesic.TriMesh`.
    ParameterError
        ``distance`` not of length ``n`` or NaN, a source index out of range, ``length`` or ``m`` not positive.

    Examples
    --------
    Two sources on a flat square: their fronts meet on the bisector, which the rounding lowers; far from it the
    field is untouched.

    >>> import numpy as np
    >>> import cvxgeodesic as cg
    >>> plane = cg.grid_plane(40)
    >>> a, b = 20 * 41 + 5, 20 * 41 + 35
    >>> d = np.minimum(*(np.linalg.norm(plane.V - plane.V[s], axis=1) for s in (a, b)))
    >>> r = cg.round_ridge(plane, d, [a, b], length=0.05)
    >>> bool(r.band[20 * 41 + 20]), bool(r.distance[20 * 41 + 20] < d[20 * 41 + 20]), bool(r.band[a])
    (True, True, False)
    """
    t0 = time.perf_counter()
    mesh = check_type(mesh, "mesh", TriMesh, "a TriMesh")
    n = mesh.n_vertices
    d = as_vertex_field(distance, "distance", n, nan_ok=False)
    fixed = vertex_indices(sources, "sources", n)
    ell = ridge_rounding_length(mesh, m) if length is None else check_number(length, "length", low=0, low_open=True)
    is_source = np.zeros(n, dtype=bool)
    is_source[fixed] = True
    band = cut_locus_band(mesh, d, 2 * RIDGE_BAND * ell, is_source)
    band[fixed] = False
    out = d.copy()
    inner = np.flatnonzero(band)
    notes: list[str] = []
    if inner.size:
        rows = band_energy_rows(mesh, band, notes)[inner]
        mass = sp.diags(barycentric_mass(mesh).diagonal()[inner] / ell**4)
        try:
            factor, _ = factor_matrix(rows[:, inner] + mass)
        except NotPositiveDefiniteError:
            # the curved energy's curvature term is not positive where angle defects are large (lucy_20k,
            # thingi_37881): the planar energy, positive semidefinite by construction, as hessian_energy_matrix does
            notes.append(f"{mesh.name}: the curved Hessian energy is indefinite near the ridge; the ridge rounded with "
                         "the planar Hessian energy (Stein et al. 2018)")
            rows = band_energy_rows(mesh, band, planar=True)[inner]
            factor, _ = factor_matrix(rows[:, inner] + mass)
        outside = np.where(band | ~np.isfinite(d), 0.0, d)
        out[inner] = factor(mass @ d[inner] - rows @ outside)
    return RidgeRounding(out, band, float(ell), time.perf_counter() - t0, tuple(notes))
