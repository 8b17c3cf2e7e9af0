"""What a point cloud's default solve runs on once its points are denoised (``PointCloud(denoise="auto")``): the
copy of the surface through the moved points, or order 1 on their triangles where that surface's holes keep every copy
far above its target (:func:`denoised_copy_refusal`, read by ``GeodesicSolver``'s default)."""

from __future__ import annotations

from typing import Any

from ..mesh import decimate
from ..mesh.simplex import SimplexMesh
from .adapted import resolution_targets

__all__ = ["DENOISED_COPY_FLOOR", "denoised_copy_refusal"]

#: The default's copy of a denoised noisy point cloud is taken where a decimation keeping its holes' borders can reach
#: at most this multiple of its target (:func:`denoised_copy_refusal`): measured 2026-12-07 (docs/dev/adapted-log.md,
#: "The noisy default on the denoised cloud"), at floors of 1.08-1.09 times the target the copy was as accurate as
#: order 1 on the denoised triangles or more (the CAD part's 13K random points at 0.3 % noise: 0.26 of pc-heat's
#: error against 0.36), from 1.28 up order 1 as accurate or more and faster. Not on the copy of the points as given:
#: the clean statues read above ``CLEAN_NOISE_MAX`` (their detail), and their copies, over surfaces with many holes,
#: beat order 1 (lucy_20k 3.21 % against 4.86 %; the same log, "The floor rule for the copy of the points as given").
DENOISED_COPY_FLOOR = 1.25


def denoised_copy_refusal(mesh: SimplexMesh, resolution: Any) -> str | None:
    """Why the default's copy of a denoised noisy point cloud is not taken, or None: the surface through its moved
    points (:meth:`~cvxgeodesic.mesh.pointcloud.PointCloud.surface`) has so many holes that a decimation keeping
    their borders cannot come within :data:`DENOISED_COPY_FLOOR` of the copy's target
    (:func:`~cvxgeodesic.mesh.decimate.kept_border_floor`).

    Such a copy stops at the floor, several times its target, and its solve costs more than order 1 on the cloud's
    triangles, which was as accurate there. Measured 2026-12-07 (docs/dev/adapted-log.md, "The noisy default on the
    denoised cloud"): horse's and armadillo's vertex clouds at 0.3 % noise, floors 2.5 and 2.4 times the target, the
    copy 0.28 and 0.27 of the point-cloud heat method's error at 3.6 and 3.5 times its time, order 1 on the denoised
    triangles 0.15 and 0.17 at 2.2 and 1.9 times.

    Parameters
    ----------
    mesh : SimplexMesh
        The user's mesh (a point cloud's soup carries its cloud).
    resolution : "auto", int or float
        The default's resolution.

    Returns
    -------
    str or None
        None for a mesh, a cloud as given (:attr:`~cvxgeodesic.mesh.pointcloud.PointCloud.denoised` 0), a clean one,
        one without a surface (the strategy's own fallback says why), or a copy that can reach its target.
    """
    cloud = getattr(mesh, "cloud", None)
    if cloud is None or not cloud.denoised or cloud.clean:
        return None
    surface, _ = cloud.surface()
    target = resolution_targets(resolution, mesh)[0]
    if surface is None or target is None:
        return None
    floor = decimate.kept_border_floor(surface)
    if floor <= DENOISED_COPY_FLOOR * target:
        return None
    return (f"the surface through its denoised points has holes whose borders keep every copy at {floor} faces or "
            f"more, {floor / target:.2f} times its target of {target}")
