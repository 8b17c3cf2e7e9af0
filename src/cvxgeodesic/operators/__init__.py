"""Discrete differential operators and smoothness energies, on triangles and tetrahedra."""

from .energies import (
    ENERGIES,
    check_energy,
    dirichlet_energy_matrix,
    energy_matrix,
    hessian_energy_matrix,
    laplacian_energy_matrix,
)
from .gradient import gradient_blocks, gradient_matrix, gradient_norms, triangle_frames
from .laplacian import barycentric_mass, cotan_stiffness, divergence, mass_matrix

__all__ = [
    "ENERGIES", "barycentric_mass", "check_energy", "cotan_stiffness", "dirichlet_energy_matrix",
    "divergence", "energy_matrix", "gradient_blocks", "gradient_matrix", "gradient_norms", "hessian_energy_matrix",
    "laplacian_energy_matrix", "mass_matrix", "triangle_frames",
]
