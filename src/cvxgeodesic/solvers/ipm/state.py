"""Iterate and direction state: ``x`` and the per-block slacks ``s`` and duals ``z``."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Direction", "Iterate"]


@dataclass
class Iterate:
    """A primal–dual point: ``x`` (n,) and, per block, ``s[i]`` and ``z[i]`` in the block's field layout."""

    x: np.ndarray
    s: list[np.ndarray]
    z: list[np.ndarray]

    def step(self, d: Direction, step_p: float, step_d: float) -> Iterate:
        """``(x, s) + step_p (Δx, Δs)``, ``z + step_d Δz``."""
        return Iterate(self.x + step_p * d.dx, [s + step_p * ds for s, ds in zip(self.s, d.ds, strict=True)],
                       [z + step_d * dz for z, dz in zip(self.z, d.dz, strict=True)])


@dataclass
class Direction:
    """A Newton direction ``(Δx, Δs, Δz)`` and the reduced right-hand side ``rhs`` that gave ``Δx``."""

    dx: np.ndarray
    ds: list[np.ndarray]
    dz: list[np.ndarray]
    rhs: np.ndarray
