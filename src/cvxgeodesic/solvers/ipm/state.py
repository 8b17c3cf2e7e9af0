"""Iterate and direction state: ``x``, the per-block slacks ``s`` and duals ``z``, the equality duals ``y``."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["Direction", "Iterate"]


def _empty() -> np.ndarray:
    return np.zeros(0)


@dataclass
class Iterate:
    """A primal–dual point: ``x`` (n,), per block ``s[i]`` and ``z[i]`` in the block's field layout, and ``y`` (p,)
    the duals of the equalities (empty without them)."""

    x: np.ndarray
    s: list[np.ndarray]
    z: list[np.ndarray]
    y: np.ndarray = field(default_factory=_empty)

    def step(self, d: Direction, step_p: float, step_d: float) -> Iterate:
        """``(x, s) + step_p (Δx, Δs)``, ``(z, y) + step_d (Δz, Δy)``."""
        return Iterate(self.x + step_p * d.dx, [s + step_p * ds for s, ds in zip(self.s, d.ds, strict=True)],
                       [z + step_d * dz for z, dz in zip(self.z, d.dz, strict=True)],
                       self.y + step_d * d.dy if self.y.size else self.y)


@dataclass
class Direction:
    """A Newton direction ``(Δx, Δs, Δz, Δy)`` and the reduced right-hand side ``(rhs, ey)`` that gave
    ``(Δx, Δy)``."""

    dx: np.ndarray
    ds: list[np.ndarray]
    dz: list[np.ndarray]
    rhs: np.ndarray
    dy: np.ndarray = field(default_factory=_empty)
    ey: np.ndarray = field(default_factory=_empty)
