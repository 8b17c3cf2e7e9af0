"""Levers of the adapted solve's error estimate (``resolution=``, docs/adapted.md "The error estimate").

For each mesh and setting, from source vertex 0: the exact field (MMP) and the adapted solve (``qclp``, order 2 on a
quadric copy, with its source patch), then the fields of companion copies at other face counts (each with the same
source patch mixed in, as the library's estimate does) and the eikonal residual of the adapted field on the user's
triangles. Printed per row (one JSON line): the true mean relative error, and per candidate its raw figure and time:

``half``, ``quarter``, ``double``  the mean relative difference to the field on a copy with 1/2, 1/4, 2x (``--finer``)
                  the faces;
``resid_p1``      area-weighted mean of ``||grad d| - 1|`` for the P1 gradient of the vertex values on each user face;
``resid_p1_exact`` the same for the exact field (the user's mesh's own floor);
``resid_p2``      the same for the transferred order-2 field's gradient (``ProjectedField.gradient_at``) at centroids;
``shortening``    ``edge_shortening`` (free).

``--save DIR`` also writes each row's per-vertex fields (``npz``) for estimators tried offline.

Run from the repository root, one thread::

    CVXGEODESIC_THREADS=1 PYTHONPATH=src python benchmarks/adapted_estimate.py kitten.obj fandisk.obj
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

import cvxgeodesic as cg
from cvxgeodesic.evaluation.errors import error_stats
from cvxgeodesic.mesh.transfer import mix_patches
from cvxgeodesic.sources import resolve_sources
from cvxgeodesic.strategies import adapted as A
from report_common import emit_row

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "meshes"


def p1_residual(mesh, d: np.ndarray, skip: np.ndarray) -> tuple[float, float]:
    """Area-weighted mean of ``|grad d| - 1`` (absolute, signed) of the P1 interpolant of ``d`` on the faces not in
    ``skip``."""
    F, V = mesh.F, mesh.V
    e1, e2 = V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]
    g11, g12, g22 = (e1 * e1).sum(1), (e1 * e2).sum(1), (e2 * e2).sum(1)
    det = g11 * g22 - g12 ** 2
    a, b = d[F[:, 1]] - d[F[:, 0]], d[F[:, 2]] - d[F[:, 0]]
    with np.errstate(invalid="ignore", divide="ignore"):
        norm2 = (g22 * a * a - 2 * g12 * a * b + g11 * b * b) / det
        r = np.sqrt(np.maximum(norm2, 0)) - 1
    area = 0.5 * np.sqrt(np.maximum(det, 0))
    keep = np.isfinite(r) & ~skip & (area > 0)
    w = area[keep] / area[keep].sum()
    return float((w * np.abs(r[keep])).sum()), float((w * r[keep]).sum())


def companion(ad, target: int, sources, patches, nears, agg):
    """The field (mixed with the patches) on a copy of about ``target`` faces, and seconds (decimation included)."""
    t0 = time.perf_counter()
    coarse, why, _ = A._decimated(ad.config.surface, max(A.MIN_RESOLUTION_FACES, target), agg)
    if coarse is None:
        return None, time.perf_counter() - t0, 0
    copy = A._Copy(ad.config, coarse)
    _, dc, _, _ = copy.solve(sources, None, "bench")
    return mix_patches(dc, patches, nears), time.perf_counter() - t0, coarse.n_faces


def rel_diff(a, b, src):
    return A._relative_difference(a, b, np.array([src]))


def run(mesh, name: str, setting, exact: np.ndarray, save: Path | None, double_max: int, src: int = 0,
        finer: float = 2.0, quarter: bool = True) -> dict | None:
    t0 = time.perf_counter()
    solver = cg.GeodesicSolver(mesh, "qclp", resolution=setting, estimate_error=False)
    res = solver.solve(src)
    t_solve = time.perf_counter() - t0
    ad = solver._strategy
    if ad.copy is None:
        return None
    d = np.asarray(res.distance, float)
    st = error_stats(d, exact, np.array([src]))
    sources = resolve_sources(mesh, src)
    patches = list(res.field.patches)
    nears = [p.at_vertices(mesh.n_vertices) for p in patches]
    faces = ad.copy.mesh.n_faces
    row = {"mesh": name, "faces": mesh.n_faces, "setting": setting, "source": src, "solve_faces": faces,
           "true": st["rel_mean"], "t_solve": t_solve, "agg": ad.record["agg"],
           "shortening": ad.record["edge_shortening"]}
    fields = {"d": d, "exact": exact}
    for key, factor in (("half", 0.5), ("quarter", 0.25 if quarter else 0.0), ("double", finer)):
        if factor == 0:
            continue
        target = int(factor * faces)
        if factor > 1 and (target > double_max or target > 0.7 * mesh.n_faces):
            continue
        dc, t, nf = companion(ad, target, sources, patches, nears, ad.record["agg"])
        if dc is None:
            continue
        row[key], row["t_" + key], row["faces_" + key] = rel_diff(dc, d, src), t, nf
        row[key + "_true"] = error_stats(dc, exact, np.array([src]))["rel_mean"]
        fields[key] = dc
    # faces touching the source patches' inner zone: the residual there is the source's cone, not the error
    near_src = np.zeros(mesh.n_vertices, bool)
    for near, p in zip(nears, patches, strict=True):
        near_src |= near < p.outer
    near_src[src] = True
    skip = near_src[mesh.F].any(axis=1)
    t1 = time.perf_counter()
    row["resid_p1"], row["resid_p1_signed"] = p1_residual(mesh, d, skip)
    row["t_resid_p1"] = time.perf_counter() - t1
    row["resid_p1_exact"], _ = p1_residual(mesh, exact, skip)
    t1 = time.perf_counter()
    fc = np.flatnonzero(~skip)
    g = res.field.gradient_at(fc, np.full((fc.size, 3), 1 / 3))
    r = np.linalg.norm(g, axis=1) - 1
    area = mesh.face_areas[fc]
    ok = np.isfinite(r)
    row["resid_p2"] = float((area[ok] * np.abs(r[ok])).sum() / area[ok].sum())
    row["resid_p2_signed"] = float((area[ok] * r[ok]).sum() / area[ok].sum())
    row["t_resid_p2"] = time.perf_counter() - t1
    if save is not None:
        np.savez(save / f"{name}_{setting}_{src}.npz", **fields, skip=skip)
    return row


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("meshes", nargs="+")
    ap.add_argument("--settings", default="auto,0.25,0.1,0.05")
    ap.add_argument("--double-max", type=int, default=25_000, help="no 2x companion above this many faces")
    ap.add_argument("--source", type=float, default=0, help="vertex index, or a fraction (0, 1) of the vertices")
    ap.add_argument("--finer", type=float, default=2.0, help="the finer companion's faces over the solve's")
    ap.add_argument("--no-quarter", action="store_true", help="no companion with 1/4 of the faces")
    ap.add_argument("--save", type=Path, default=None)
    ap.add_argument("--out", default=None, help="append JSON lines here")
    args = ap.parse_args()
    cg.GeodesicSolver(cg.icosphere(1), "qclp", order=2).solve(0)  # compiled kernels, untimed
    for name in args.meshes:
        mesh = cg.load_mesh(SHARED / name)
        src = int(args.source * mesh.n_vertices) if 0 < args.source < 1 else int(args.source)
        try:
            exact = np.asarray(cg.geodesic_distance(mesh, src, method="exact"), float)
        except cg.errors.CvxGeodesicError:  # MMP refuses non-manifold vertices: order 2 on the mesh is the reference
            exact = np.asarray(cg.geodesic_distance(mesh, src, method="qclp", order=2), float)
        seen = set()
        for s in args.settings.split(","):
            setting = s if s == "auto" else float(s)
            target = A.resolve_resolution(setting, mesh.n_faces)
            if target in seen:
                continue
            seen.add(target)
            row = run(mesh, name, setting, exact, args.save, args.double_max, src, args.finer,
                      not args.no_quarter)
            if row is None:
                continue
            row["load"] = os.getloadavg()[0]
            emit_row(row, args.out)


if __name__ == "__main__":
    main()
