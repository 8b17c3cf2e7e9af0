"""Solve strategies behind :class:`~cvxgeodesic.api.GeodesicSolver`, all with one signature.

Every strategy solves on surfaces and inside tetrahedral meshes alike (``config.mesh.dim``; what each dimension
supports is :mod:`cvxgeodesic.capabilities`). Each strategy is built once per solver object from a validated
:class:`SolveConfig` (the per-mesh work) and then answers ``strategy.solve(sources, callback=None) -> GeodesicResult``:

=========================  =====================================================================
:class:`DirectStrategy`    one conic solve of a P1 formulation, with the backend policy (IPM,
                           Clarabel retry under ``solver="auto"``, the ``d >= 0`` re-solve)
:class:`BaselineStrategy`  Dijkstra, fast marching, heat, exact (:mod:`cvxgeodesic.baselines`)
:class:`CoarseToFine`      two direct solves: a decimated mesh, then (with polish) the mesh itself
:class:`Order2`            P2 elements for d², edge cones and cutting planes on flat faces
:class:`Adapted`           order 2 on a decimated copy (``resolution=``), the field read on the mesh
=========================  =====================================================================
"""

from __future__ import annotations

from typing import Any

from .adapted import Adapted, resolution_targets
from .backend import Backend, ipm_available
from .base import Callback, SolveConfig, SolveStrategy
from .baseline import BaselineStrategy
from .coarse_to_fine import CoarseToFine, default_target_faces, resolve_target
from .direct import DirectStrategy
from .order2 import Order2

__all__ = [
    "Adapted", "Backend", "BaselineStrategy", "Callback", "CoarseToFine", "DirectStrategy", "Order2", "SolveConfig",
    "SolveStrategy",
    "default_target_faces", "ipm_available", "make_strategy", "resolve_target",
]


def make_strategy(config: SolveConfig, *, baseline: bool, order: int = 1, multires_target: int | None = None,
                  polish: bool = False, resolution: Any = "mesh", estimate: bool = True) -> SolveStrategy:
    """The strategy for a validated config.

    Parameters
    ----------
    config : SolveConfig
    baseline : bool
        ``config.method`` is a baseline.
    order : int
        A key of :data:`~cvxgeodesic.operators.lagrange.ELEMENTS` (validated).
    multires_target : int, optional
        Coarse face count (from :func:`resolve_target`); None for a direct solve.
    polish : bool
        With ``multires_target``: finish with a direct solve on the mesh.
    resolution : "mesh", "auto", int or float
        Anything but ``"mesh"``: an :class:`Adapted` solve (order 2 on a decimated copy,
        :func:`~.adapted.resolution_targets`).
    estimate : bool
        With ``resolution``: estimate each solve's error (a second, coarser solve; :class:`Adapted`).

    Returns
    -------
    SolveStrategy
    """
    if resolution != "mesh":
        target, retry = resolution_targets(resolution, config.mesh)
        return Adapted(config, target, resolution, estimate=estimate, retry=retry)
    if order > 1:  # above order 1 the program solves for φ = d² in the order's element (order 1: for d)
        return Order2(config, order)
    if baseline:
        return BaselineStrategy(config)
    if multires_target is not None:
        return CoarseToFine(config, multires_target, polish)
    return DirectStrategy(config)
