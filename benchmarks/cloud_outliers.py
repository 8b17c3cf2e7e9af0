"""Outliers of point clouds: false positives on the shared scans' clouds and planted outliers found.

For each cloud of ``benchmarks/point_clouds.py`` (the vertices of a shared mesh, and with ``--resample`` random
surface points of it; clean and with Gaussian noise of ``--noise`` times the bounding-box diagonal, a fixed seed),
``PointCloud(P)`` is built on the cloud as it is (every point it leaves out as an outlier or a line point is a false
positive: :func:`cvxgeodesic.mesh.cloud_outliers.find_defects`, then the flagged outliers that lie on the other
points' fans kept, ``pointcloud.ON_SURFACE``) and on the cloud with outliers planted:

- ``f`` (each of ``--heights``): 20 points moved along their neighbours' normal and 20 in a random direction by ``f``
  local spacings (the mean distance to their 6 nearest neighbours), kept only if they end at least ``0.9 f``
  spacings from every point of the cloud and ``f`` spacings from each other (isolated outliers);
- ``group f``: 3 groups of 5 points (Gaussian, half the median spacing) around points moved ``f`` spacings along
  the normal.

Columns: the points, false positives (outliers, line points), then per height the planted points found. One
process::

    OMP_NUM_THREADS=1 PYTHONPATH=src python benchmarks/cloud_outliers.py --resample 1.0,0.25

The date and the load average are printed first.
"""

from __future__ import annotations

import argparse
import datetime
import os
from collections.abc import Iterator

import numpy as np
from scipy.spatial import cKDTree

import cvxgeodesic as cg
from cvxgeodesic.mesh.cloud_outliers import CloudDefects
from cvxgeodesic.mesh.pointcloud import PointCloud
from point_clouds import resample, shared_meshes

DEFAULT_MESHES = ("kitten", "bimba", "max_planck", "fandisk")


def clouds(args, rng) -> Iterator[tuple[str, np.ndarray]]:
    """``(label, points)`` of every mesh, sampling and noise level."""
    for path in shared_meshes(args.meshes or list(DEFAULT_MESHES)):
        mesh = cg.load_mesh(path, kind="surface")
        samples = [("vertices", mesh.V)]
        samples += [(f"resampled {fr}", resample(mesh, float(fr), rng)[0]) for fr in args.resample.split(",") if fr]
        for kind, X in samples:
            for noise in (float(x) for x in args.noise.split(",")):
                noisy = X + rng.normal(scale=noise * mesh.bbox_diagonal, size=X.shape) if noise else X
                yield f"{path.stem} {kind}, {noise * 100:.1f} %", noisy


def plant(P: np.ndarray, rng, f: float, m: int, normal: bool, others: list[np.ndarray]) -> list[np.ndarray]:
    """``m`` isolated outliers ``f`` local spacings off the cloud ``P``, also ``f`` spacings from ``others``."""
    tree = cKDTree(P)
    dist, idx = tree.query(P, k=31)
    h = dist[:, 1:7].mean(axis=1)
    out: list[np.ndarray] = []
    for i in rng.permutation(P.shape[0]):
        if normal:
            Q = P[idx[i]] - P[idx[i]].mean(axis=0)
            u = np.linalg.eigh(Q.T @ Q)[1][:, 0]
        else:
            u = rng.normal(size=3)
            u /= np.linalg.norm(u)
        y = P[i] + f * h[i] * u * rng.choice([-1.0, 1.0])
        if tree.query(y)[0] < 0.9 * f * h[i]:
            continue  # landed near another part of the surface: not off it by f spacings
        if others + out and np.linalg.norm(np.array(others + out) - y, axis=1).min() < f * h[i]:
            continue
        out.append(y)
        if len(out) == m:
            break
    return out


def left_out(P: np.ndarray) -> CloudDefects:
    """The outliers and line points that ``PointCloud(P)`` leaves out (``P``: distinct points, its numbering)."""
    cloud = PointCloud(P)
    return CloudDefects(cloud.outliers, cloud.line_points)


def found(P: np.ndarray, planted: np.ndarray) -> int:
    """How many of ``planted`` the cloud ``P`` with them appended leaves out."""
    return int(np.count_nonzero(left_out(np.r_[P, planted]).points >= P.shape[0]))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--meshes", nargs="*", help=f"mesh names in ../shared/meshes (default: {' '.join(DEFAULT_MESHES)})")
    ap.add_argument("--noise", default="0,0.001,0.003", help="noise levels, fractions of the diagonal")
    ap.add_argument("--resample", default="", help="also random surface points, these fractions of the face count")
    ap.add_argument("--heights", default="5,10,20,50", help="planted outliers' heights, in local spacings")
    ap.add_argument("--no-plant", action="store_true", help="false positives only")
    args = ap.parse_args()
    print(f"# {datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M} UTC, load {os.getloadavg()[0]:.2f}", flush=True)
    heights = [] if args.no_plant else [float(x) for x in args.heights.split(",")]
    print("| cloud | points | false outliers | false line points | "
          + " | ".join(f"{f:g} spacings | group {f:g}" for f in heights) + " |")
    print("|---|---|---|---|" + "---|---|" * len(heights))
    rng = np.random.default_rng(0)
    for label, P in clouds(args, rng):
        d = left_out(P)
        cells = [str(P.shape[0]), str(d.outliers.size), str(d.lines.size)]
        for f in heights:
            lone = plant(P, rng, f, 20, True, [])
            lone += plant(P, rng, f, 20, False, lone)
            cells.append(f"{found(P, np.array(lone))}/{len(lone)}")
            centres = plant(P, rng, f, 3, True, [])
            h = np.median(cKDTree(P).query(P, k=7)[0][:, 1:].mean(axis=1))
            groups = np.repeat(np.array(centres), 5, axis=0) + rng.normal(scale=0.5 * h, size=(5 * len(centres), 3))
            cells.append(f"{found(P, groups)}/{groups.shape[0]}")
        print(f"| {label} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
