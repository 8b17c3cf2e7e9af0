"""What every solve strategy shares: the validated :class:`SolveConfig` and the :class:`SolveStrategy` protocol."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Protocol, cast

from ..capabilities import Capability
from ..mesh.simplex import SimplexMesh
from ..mesh.trimesh import TriMesh
from ..operators.metric import Medium
from ..problems.formulations import FORMULATIONS, smoothness_weight
from ..results import GeodesicResult
from ..sources import SourceSet

#: ``callback(iteration, info_dict)`` after every interior-point iteration.
Callback = Callable[[int, dict], None]


@dataclass(frozen=True)
class SolveConfig:
    """The validated parameters of one :class:`~cvxgeodesic.api.GeodesicSolver`, as its strategies see them.

    Attributes
    ----------
    mesh : SimplexMesh
        The mesh in its own units (``n`` vertices, ``m`` cells: faces or tetrahedra).
    method : str
        Canonical formulation name (a key of :data:`~cvxgeodesic.problems.formulations.FORMULATIONS`) or baseline name.
    lam : float
        Smoothness weight λ in the mesh's units (0 for LP formulations; dimensionless at order 2).
    m : float or None
        The multiplier ``lam`` came from, or None when λ was given directly.
    normalization : {"area", "paper"}
    solver : {"auto", "ipm", "clarabel"}
        The backend asked for (``"auto"``: the structured solver when available, Clarabel as its fallback).
    tol : float
    max_iter : int
    verbose : bool
    notes : tuple of str
        Substitutions already made before any strategy ran (the loader's repairs of the mesh).
    medium : Medium or None
        A travel cost and/or metric on ``mesh`` (:mod:`cvxgeodesic.operators.metric`), validated; None for the
        Euclidean distance.
    capability : Capability or None
        The cell the capability table accepted for this solver (:func:`cvxgeodesic.capabilities.check`, once, at
        the API edge): the strategies and builders below do not consult the table again. None for a strategy built
        directly (the builders' own argument checks then stand between it and a crash).
    """

    mesh: SimplexMesh
    method: str
    lam: float = 0.0
    m: float | None = None
    normalization: str = "area"
    solver: str = "auto"
    tol: float = 1e-8
    max_iter: int = 200
    verbose: bool = False
    notes: tuple[str, ...] = field(default_factory=tuple)
    medium: Medium | None = None
    capability: Capability | None = None

    @property
    def surface(self) -> TriMesh:
        """:attr:`mesh` as the triangle surface it is for the strategies that exist on surfaces only (multires, an
        adapted resolution): the capability table (:func:`cvxgeodesic.capabilities.check`) gives them no other."""
        return cast(TriMesh, self.mesh)

    @property
    def stretch(self) -> str:
        """Weights of the stretch term that go with the normalization of ``m``
        (:func:`~cvxgeodesic.problems.formulations.stretch_weights`): ``"area"``, or ``"calibrated"`` for
        ``"paper"``."""
        return "area" if self.normalization == "area" else "calibrated"

    @property
    def energy(self) -> str | None:
        """Smoothness energy of the formulation (``"hessian"``, ``"laplacian"``, ``"dirichlet"``), None for LPs."""
        entry = FORMULATIONS.get(self.method)
        return None if entry is None else entry[1]

    def on(self, mesh: SimplexMesh, *, lam: float | None = None, m: float | None = None) -> SolveConfig:
        """The same parameters on another mesh (a coarse one), with λ given directly or recomputed from ``m``.

        Parameters
        ----------
        mesh : SimplexMesh
        lam : float, optional
            λ on ``mesh``; exclusive with ``m``.
        m : float, optional
            Multiplier: λ is :func:`~cvxgeodesic.problems.formulations.smoothness_weight` of ``mesh``.

        Returns
        -------
        SolveConfig
        """
        if m is not None:
            lam = smoothness_weight(mesh, m, self.normalization, self.energy or "hessian")
        lam = 0.0 if self.energy is None else float(lam if lam is not None else self.lam)
        return replace(self, mesh=mesh, lam=lam, m=m, notes=tuple(getattr(mesh, "notes", ())))


class SolveStrategy(Protocol):
    """How a :class:`~cvxgeodesic.api.GeodesicSolver` computes its fields; built once per solver object.

    Attributes
    ----------
    backend : str
        The backend that will produce the fields (``"ipm"``, ``"clarabel"`` or the baseline's name), reported
        as ``GeodesicSolver.solver_name``.
    notes : list of str
        Substitutions made for every solve of this object (copied into each ``info.notes``).
    setup_time : float
        Seconds the constructor took (per-mesh work).
    """

    backend: str
    notes: list[str]
    setup_time: float

    def solve(self, sources: SourceSet, *, callback: Callback | None = None) -> GeodesicResult:
        """Distance field from ``sources``, resolved once by :meth:`GeodesicSolver.solve`
        (:func:`~cvxgeodesic.sources.resolve_sources`), on the config's mesh."""
        ...
