"""What a noisy point cloud's default solves on (denoised by ``PointCloud(denoise="auto")`` or as given): the copy
of the surface through its points, or order 1 on their triangles where that surface's holes keep every copy far above
its target (:func:`noisy_copy_refusal`, read by ``GeodesicSolver``'s default)."""

from __future__ import annotations

from typing import Any

from ..mesh import decimate
from ..mesh.simplex import SimplexMesh
from .adapted import resolution_targets

__all__ = ["NOISY_COPY_FLOOR", "noisy_copy_refusal"]

#: The default's copy of a point cloud that is not clean is taken where a decimation keeping its holes' borders can
#: reach at most this multiple of its target (:func:`noisy_copy_refusal`): measured 2026-12-07 (docs/dev/adapted-log.md,
#: "The noisy default on the denoised cloud"), on denoised clouds at floors of 1.08-1.09 times the target the copy was
#: as accurate as order 1 on the denoised triangles or more (the CAD part's 13K random points at 0.3 % noise: 0.26 of
#: pc-heat's error against 0.36), from 1.28 up order 1 as accurate or more and faster; on clouds as given ("A noisy
#: copy that cannot reach its target"), lucy_20k's 20K random points at 0.1 % noise (floor 2.9 times the target): the
#: copy 0.74 of pc-heat's error at 3.8 times its time, order 1 0.21.
NOISY_COPY_FLOOR = 1.25


def noisy_copy_refusal(mesh: SimplexMesh, resolution: Any) -> str | None:
    """Why the default's copy of a point cloud that is not clean (denoised or as given) is not taken, or None: the
    surface through its points (:meth:`~cvxgeodesic.mesh.pointcloud.PointCloud.surface`) has so many holes that a
    decimation keeping their borders cannot come within :data:`NOISY_COPY_FLOOR` of the copy's target
    (:func:`~cvxgeodesic.mesh.decimate.kept_border_floor`).

    Such a copy stops at the floor, several times its target: its solve costs more than order 1 on the cloud's
    triangles, and its many holes' borders, kept, leave it no more accurate (docs/dev/adapted-log.md, "The noisy
    default on the denoised cloud": horse's and armadillo's denoised vertex clouds at 0.3 % noise, floors 2.5 and 2.4
    times the target, the copy 0.28 and 0.27 of the point-cloud heat method's error at 3.6 and 3.5 times its time,
    order 1 on the denoised triangles 0.15 and 0.17 at 2.2 and 1.9 times).

    Parameters
    ----------
    mesh : SimplexMesh
        The user's mesh (a point cloud's soup carries its cloud).
    resolution : "auto", int or float
        The default's resolution.

    Returns
    -------
    str or None
        None for a mesh, a clean cloud (:attr:`~cvxgeodesic.mesh.pointcloud.PointCloud.clean`: its copy is finer and
        its retry coarser), one without a surface (the strategy's own fallback says why), or a copy that can come
        near its target.
    """
    cloud = getattr(mesh, "cloud", None)
    if cloud is None or cloud.clean:
        return None
    surface, _ = cloud.surface()
    target = resolution_targets(resolution, mesh)[0]
    if surface is None or target is None:
        return None
    floor = decimate.kept_border_floor(surface)
    if floor <= NOISY_COPY_FLOOR * target:
        return None
    points = "denoised points" if cloud.denoised else "points"
    return (f"the surface through its {points} has holes whose borders keep every copy at {floor} faces or more, "
            f"{floor / target:.2f} times its target of {target}")
