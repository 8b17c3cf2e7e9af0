"""Accuracy, gradient-norm, anisotropy and ridge-smoothness measures (paper §4)."""

from .anisotropy import mesh_anisotropy, triangle_anisotropy
from .errors import error_stats, percentile, relative_error
from .gradient import gradient_norm_histogram, gradient_norm_stats
from .smoothness import (
    cut_locus_band,
    edge_gradient_jumps,
    interior_edges,
    off_ridge_error,
    ridge_band,
    ridge_deficit,
    ridge_sharpness,
    rounding_width,
    smoothness_report,
    triangle_gradients_3d,
)

__all__ = [
    "cut_locus_band", "edge_gradient_jumps", "error_stats", "gradient_norm_histogram", "gradient_norm_stats",
    "interior_edges", "mesh_anisotropy", "off_ridge_error", "percentile", "relative_error", "ridge_band",
    "ridge_deficit", "ridge_sharpness", "rounding_width", "smoothness_report", "triangle_anisotropy",
    "triangle_gradients_3d",
]
