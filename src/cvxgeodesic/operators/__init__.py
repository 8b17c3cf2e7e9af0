"""Discrete differential operators and smoothness energies."""

from .energies import (
    ENERGIES,
    dirichlet_energy_matrix,
    energy_matrix,
    hessian_energy_matrix,
    laplacian_energy_matrix,
)
from .gradient import gradient_blocks, gradient_matrix, gradient_norms, triangle_frames
from .laplacian import cotan_stiffness, mass_matrix

__all__ = [
    "ENERGIES", "cotan_stiffness", "dirichlet_energy_matrix", "energy_matrix", "gradient_blocks",
    "gradient_matrix", "gradient_norms", "hessian_energy_matrix", "laplacian_energy_matrix",
    "mass_matrix", "triangle_frames",
]
