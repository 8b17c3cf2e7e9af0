"""The baseline strategy: Dijkstra, fast marching, heat or exact MMP (:mod:`cvxgeodesic.baselines`), on surfaces
and inside volumes."""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from ..baselines import BASELINES
from ..operators.linear_field import LinearField
from ..results import GeodesicResult, SolveInfo
from .base import Callback, SolveConfig

#: Keys of a baseline's info that :class:`SolveInfo` holds in its own fields (not repeated in ``extra``).
_OWN_FIELDS = ("method", "solver", "status", "iterations", "setup_time", "notes")


class BaselineStrategy:
    """One of :data:`~cvxgeodesic.baselines.BASELINES` on the mesh (its set-up done once).

    Parameters
    ----------
    config : SolveConfig
        ``config.method`` is a key of :data:`~cvxgeodesic.baselines.BASELINES`; ``config.mesh`` a TriMesh or a
        TetMesh.

    Raises
    ------
    NonManifoldError
        ``"fmm"`` / ``"exact"`` on a non-manifold mesh.
    """

    def __init__(self, config: SolveConfig) -> None:
        t0 = time.perf_counter()
        self.config = config
        kwargs = {} if config.medium is None else {"medium": config.medium}  # dijkstra only (validated)
        self.baseline = BASELINES[config.method](config.mesh, **kwargs)
        self.backend = config.method
        # the loader's repairs, then the baseline's own (the faces fast marching reoriented, tetrahedra left out)
        self.notes: list[str] = [*config.notes, *self.baseline.notes]
        self.setup_time = time.perf_counter() - t0

    def solve(self, sources: Any, *, callback: Callback | None = None) -> GeodesicResult:
        """Distance field from a resolved ``SourceSet`` of either dimension; ``callback`` is ignored (no iterations
        to report)."""
        t0 = time.perf_counter()
        d, binfo = self.baseline.solve(sources)
        info = SolveInfo(
            method=self.config.method, solver=binfo["solver"], status=binfo["status"],
            iterations=binfo["iterations"], setup_time=self.setup_time, solve_time=time.perf_counter() - t0,
            n_unreachable=int(np.isinf(d).sum()), notes=[*self.config.notes, *binfo["notes"]],
            # the library's set-up is part of info.setup_time: one name, one quantity
            extra={k: v for k, v in binfo.items() if k not in _OWN_FIELDS},
        )
        return GeodesicResult(distance=d, info=info, sources=sources.vertices,
                              field=LinearField(self.config.mesh, d, self.config.medium),
                              source_set=None if sources.vertex_only else sources)
