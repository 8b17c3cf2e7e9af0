"""Study switches of the programs: choices no caller of the library makes, kept for the measurements that made them.
Not part of the API; the defaults are the library's.

* the squared-distance program's objective weights (``benchmarks/order2.py --weights=consistent``): set
  ``cvxgeodesic.problems._study.WEIGHTS = "consistent"`` before the program is built;
* the order-1 program's uniform stretch weights of the normalization study (docs/method.md):
  ``build_problem(..., stretch="mean" | "sum")`` (:data:`STRETCH_WEIGHTS`).
"""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from ..operators.lagrange import LagrangeSpace

#: The uniform stretch weights of the normalization study: ``"mean"`` is ``1 / n``, ``"sum"`` is 1 (the paper's
#: literal ``−Σ d_i``) per vertex (:func:`stretch_scale`).
STRETCH_WEIGHTS = ("mean", "sum")
#: The objective weights (:func:`objective_weights`).
WEIGHTS_CHOICES = ("lumped", "consistent")
#: The objective weights of every squared-distance program built from now on (docs/order2.md, "Objective weights",
#: has the measurement behind ``"lumped"``).
WEIGHTS = "lumped"


def stretch_scale(stretch: str, n: int) -> float:
    """The weight per vertex of a study stretch of :data:`STRETCH_WEIGHTS` on ``n`` vertices."""
    return 1.0 / n if stretch == "mean" else 1.0


def objective_weights(space: LagrangeSpace) -> np.ndarray:
    """(n_dofs,) float ndarray: the program's objective weights (``∫φ ≈ wᵀφ``) under :data:`WEIGHTS`.

    ``"lumped"``: :meth:`LagrangeSpace.weights`. ``"consistent"``: the exact integrals of the order-2 shape functions
    of a triangle, 0 for corners and ``A/3`` for midpoints (on a tetrahedron the corners' would be negative,
    ``−vol/20``).

    Raises
    ------
    ParameterError
        An unknown switch, or ``"consistent"`` on a space that is not of order 2 on triangles.
    """
    if WEIGHTS == "lumped":
        return space.weights()
    if WEIGHTS != "consistent":
        raise ParameterError(f"_study.WEIGHTS must be one of {WEIGHTS_CHOICES}, got {WEIGHTS!r}")
    c, n_loc = space.reference.n_corners, space.cell_dofs.shape[1]
    if space.order != 2 or n_loc - c != c:  # three edges: a triangle
        raise ParameterError("consistent weights are defined for order-2 triangles only; use 'lumped'")
    A = space.cell_measures
    per = np.hstack([np.zeros((A.size, c)), np.repeat(A[:, None] / 3.0, 3, axis=1)])
    return np.bincount(space.cell_dofs.ravel(), per.ravel(), minlength=space.n_dofs)
