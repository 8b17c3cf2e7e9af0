"""The order-2 strategy: P2 elements for the squared distance (:mod:`cvxgeodesic.elements_p2`)."""

from __future__ import annotations

import time
from typing import Any

from ..results import GeodesicResult
from .base import Callback, SolveConfig


class Order2:
    """Adapter around :class:`~cvxgeodesic.elements_p2.Order2Strategy` with the strategy signature.

    ``Order2Strategy`` reads ``mesh``, ``method``, ``tol``, ``max_iter``, ``verbose`` and ``setup_time``
    from the object it is given: this adapter, whose attributes come from the config.

    Parameters
    ----------
    config : SolveConfig
        ``config.method`` is one of :data:`~cvxgeodesic.elements_p2.ORDER2_METHODS`.

    Attributes
    ----------
    p2 : Order2Strategy
    """

    def __init__(self, config: SolveConfig) -> None:
        from ..elements_p2 import Order2Strategy

        t0 = time.perf_counter()
        self.config = config
        self.mesh, self.method = config.mesh, config.method
        self.tol, self.max_iter, self.verbose = config.tol, config.max_iter, config.verbose
        self.setup_time = 0.0
        self.notes: list[str] = list(config.notes)
        self.p2 = Order2Strategy(self, config.solver)
        self.backend: str = self.p2.backend
        self.setup_time = time.perf_counter() - t0

    def solve(self, sources: Any, *, callback: Callback | None = None) -> GeodesicResult:
        """Distance field from vertex and ``(face, bary)`` point sources (see ``Order2Strategy.solve``)."""
        return self.p2.solve(sources, callback=callback)
