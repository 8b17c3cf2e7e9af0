"""The geometric part of the adapted solve's error, and length corrections carried as a medium on the copy.

For each mesh, source vertex and fraction of the faces, ``qclp`` order 2 on the quadric copy (``resolution=``), the
field read at the user's vertices and compared with exact MMP on the user's mesh (mean, max and signed mean relative
error, in %). Two measurements:

* ``--decompose``: the error split in two. *Geometry*: the exact (MMP) distance on the copy, from the source's
  closest point there (inserted as a vertex), against the user's exact distance read at the copy's vertices' closest
  points of the user's surface (the user's mesh is fine, so that interpolation adds little; reading the coarse
  exact field at the user's vertices instead would add the interpolation's overestimate of a convex function).
  *Order 2*: the order-2 field against the exact distance on the copy, at the copy's vertices.
* ``--corrections``: the solve again with a per-face medium on the copy meant to restore the user's lengths (the
  source patches stay: they solve on the user's own mesh). ``cost``: ``sqrt(Σ A / Σ A |cos θ|)`` over the user's
  faces whose centroid is closest to the face (θ: between the two normals; the user's area over its projection on
  the face's plane); ``area``: ``sqrt(Σ A_user / A_face)``, both sums over the face and 3 rings of edge neighbours;
  ``metric``: the 2×2 tensor fitted per face to the user's edges whose midpoint is closest to it,
  ``(P e)ᵀ M (P e) ≈ |e|²`` (P: projection on the face's plane); ``arc``: the tensor giving each edge of the face the
  length of the polyline through the user-surface closest points of 5 equally spaced points of the edge (a stand-in
  for isoparametric P2 edges); ``ones``: a cost of 1 on every face (the program with a medium, nothing corrected).
  Each is exactly 1 / the identity where the copy lies on the user's surface. ``t_corr``: seconds to build it.

Run from the repository root, one thread (docs/dev/adapted-log.md, "A length correction on the copy")::

    CVXGEODESIC_THREADS=1 PYTHONPATH=src python benchmarks/adapted_geometry.py kitten bunny --decompose
    CVXGEODESIC_THREADS=1 PYTHONPATH=src python benchmarks/adapted_geometry.py kitten --corrections cost,metric,arc
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp

import cvxgeodesic as cg
from cvxgeodesic.mesh.closest import closest_point_index
from cvxgeodesic.mesh.locate import bary_positions
from cvxgeodesic.operators.gradient import triangle_frames
from cvxgeodesic.operators.metric import Medium
from cvxgeodesic.strategies import adapted
from report_common import emit_row

MESHES = Path(__file__).resolve().parents[1].parent / "shared" / "meshes"
#: A face where fewer user faces / edges than this map keeps the identity.
MIN_COUNT = 3
#: Length ratios are clipped to [1 / MAX_RATIO, MAX_RATIO] (squared for areas), and user faces or edges turning by
#: more than arccos(MIN_COS) from the copy's face are clipped there / left out.
MAX_RATIO = 2.0
MIN_COS = 0.3


def _unit(n: np.ndarray) -> np.ndarray:
    return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), np.finfo(float).tiny)


def _tensors(coarse: cg.TriMesh, M2: np.ndarray) -> np.ndarray:
    """(m, 3, 3) tensors from (m, 2, 2) ones in the faces' frames (the normal direction: 1)."""
    ex, ey = triangle_frames(coarse)
    E = np.stack([ex, ey], axis=2)
    n = _unit(coarse.face_normals_unnormalized)
    M = np.einsum("kai,kij,kbj->kab", E, M2, E) + np.einsum("ka,kb->kab", n, n)
    M = 0.5 * (M + M.transpose(0, 2, 1))
    M[(M2 == np.eye(2)).all(axis=(1, 2))] = np.eye(3)
    return M


def projected_cost(user: cg.TriMesh, coarse: cg.TriMesh) -> np.ndarray:
    cf, _, _ = closest_point_index(coarse).query(np.ascontiguousarray(user.V[user.F].mean(axis=1)))
    cos = np.abs(np.einsum("ij,ij->i", _unit(user.face_normals_unnormalized),
                           _unit(coarse.face_normals_unnormalized)[cf]))
    A, m = user.face_areas, coarse.n_faces
    Au, Ap = np.bincount(cf, A, m), np.bincount(cf, A * np.clip(cos, MIN_COS, 1.0), m)
    ok = (np.bincount(cf, minlength=m) >= MIN_COUNT) & (Ap > 0)
    ratio = np.ones(m)
    ratio[ok] = np.clip(Au[ok] / Ap[ok], 1.0, MAX_RATIO ** 2)
    ratio[ratio < 1 + 1e-12] = 1.0
    return np.sqrt(ratio)


def area_cost(user: cg.TriMesh, coarse: cg.TriMesh, rings: int = 3) -> np.ndarray:
    cf, _, gap = closest_point_index(coarse).query(np.ascontiguousarray(user.V[user.F].mean(axis=1)))
    m = coarse.n_faces
    sums = [np.bincount(cf, user.face_areas, m), coarse.face_areas.copy(),
            np.bincount(cf, minlength=m).astype(float), np.bincount(cf, gap, m)]
    inc = sp.csr_matrix((np.ones(3 * m), (np.repeat(np.arange(m), 3), coarse.cell_edges.ravel())))
    S = (inc @ inc.T).tocsr()
    S.data[:] = 1.0
    for _ in range(rings):
        sums = [S @ s for s in sums]
    Au, Ac, count, off = sums
    ratio = np.where(count >= MIN_COUNT, np.clip(Au / Ac, MAX_RATIO ** -2, MAX_RATIO ** 2), 1.0)
    ratio[off <= 1e-9 * coarse.bbox_diagonal] = 1.0  # the user's faces lie on the copy there
    return np.sqrt(ratio)


def fitted_metric(user: cg.TriMesh, coarse: cg.TriMesh) -> np.ndarray:
    E, V = user.edges, user.V
    cf, _, _ = closest_point_index(coarse).query(np.ascontiguousarray(0.5 * (V[E[:, 0]] + V[E[:, 1]])))
    ex, ey = triangle_frames(coarse)
    d = V[E[:, 1]] - V[E[:, 0]]
    u, v = np.einsum("ij,ij->i", d, ex[cf]), np.einsum("ij,ij->i", d, ey[cf])
    p2, l2 = u * u + v * v, np.einsum("ij,ij->i", d, d)
    keep = p2 > MIN_COS ** 2 * l2
    cf, u, v, p2, l2 = cf[keep], u[keep], v[keep], p2[keep], l2[keep]
    # M = I + D with D fitted to the relative excess (|e|² − |Pe|²) / |Pe|²: exactly 0 where the user's edges lie in
    # the face's plane
    x = np.stack([u * u, 2 * u * v, v * v], axis=1) / p2[:, None]
    r = np.maximum(l2 - p2, 0.0) / p2
    m = coarse.n_faces
    N, b = np.zeros((m, 3, 3)), np.zeros((m, 3))
    for i in range(3):
        b[:, i] = np.bincount(cf, x[:, i] * r, m)
        for j in range(i, 3):
            N[:, i, j] = N[:, j, i] = np.bincount(cf, x[:, i] * x[:, j], m)
    ok = np.bincount(cf, minlength=m) >= MIN_COUNT
    ok &= np.linalg.cond(np.where(ok[:, None, None], N, np.eye(3))) < 1e6
    s = np.linalg.solve(N[ok], b[ok][:, :, None])[:, :, 0]
    w, Q = np.linalg.eigh(np.stack([np.stack([s[:, 0], s[:, 1]], -1), np.stack([s[:, 1], s[:, 2]], -1)], -2))
    w = np.clip(w, 0.0, MAX_RATIO ** 2 - 1)
    w[w < 1e-12] = 0.0
    D = np.zeros((m, 2, 2))
    D[ok] = np.einsum("kij,kj,klj->kil", Q, w, Q)
    return _tensors(coarse, np.eye(2) + D)


def arc_metric(user: cg.TriMesh, coarse: cg.TriMesh, k: int = 4) -> np.ndarray:
    F, V, m = coarse.F, coarse.V, coarse.n_faces
    pairs = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    edges, inv = np.unique(pairs, axis=0, return_inverse=True)
    A, B = V[edges[:, 0]], V[edges[:, 1]]
    t = np.linspace(0.0, 1.0, k + 1)[None, :, None]
    X = (A[:, None, :] + t * (B - A)[:, None, :]).reshape(-1, 3)
    f, bary, _ = closest_point_index(user).query(np.ascontiguousarray(X))
    P = bary_positions(user, f, bary).reshape(len(edges), k + 1, 3)
    ratio = np.linalg.norm(np.diff(P, axis=1), axis=2).sum(axis=1) / np.linalg.norm(B - A, axis=1)
    ratio[np.abs(ratio - 1) < 1e-9] = 1.0
    r3 = np.clip(ratio, 1 / MAX_RATIO, MAX_RATIO)[inv.ravel()].reshape(3, m).T
    ex, ey = triangle_frames(coarse)
    ev = np.stack([V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 1]], V[F[:, 0]] - V[F[:, 2]]], axis=1)
    u, v = np.einsum("kej,kj->ke", ev, ex), np.einsum("kej,kj->ke", ev, ey)
    # the tensor giving the three edges their new lengths (three equations, three unknowns)
    a, b, c = np.linalg.solve(np.stack([u * u, 2 * u * v, v * v], axis=2), (r3 ** 2 * (u * u + v * v))[:, :, None]
                              )[:, :, 0].T
    M2 = np.zeros((m, 2, 2))
    M2[:, 0, 0], M2[:, 0, 1], M2[:, 1, 0], M2[:, 1, 1] = a, b, b, c
    bad = ~((a > 0) & (a * c - b * b > 0)) | (r3 == 1.0).all(axis=1)
    M2[bad] = np.eye(2)
    return _tensors(coarse, M2)


def correction(kind: str, user: cg.TriMesh, coarse: cg.TriMesh) -> Medium:
    if kind == "ones":
        return Medium(coarse, np.ones(coarse.n_faces), "faces")
    if kind in ("cost", "area"):
        return Medium(coarse, (projected_cost if kind == "cost" else area_cost)(user, coarse), "faces")
    if kind in ("metric", "arc"):
        return Medium(coarse, metric=(fitted_metric if kind == "metric" else arc_metric)(user, coarse),
                      metric_kind="faces")
    raise SystemExit(f"unknown correction {kind!r}")


def _errors(d: np.ndarray, ref: np.ndarray) -> dict:
    keep = np.isfinite(d) & np.isfinite(ref) & (ref > 1e-12 * np.nanmax(np.where(np.isfinite(ref), ref, 0)))
    rel = (d[keep] - ref[keep]) / ref[keep]
    return {"mean": 100 * float(np.mean(np.abs(rel))), "max": 100 * float(np.max(np.abs(rel))),
            "signed": 100 * float(np.mean(rel))}


def decompose(mesh: cg.TriMesh, src: int, res: cg.GeodesicResult, exact: np.ndarray) -> dict:
    """The geometric and the order-2 parts of ``res``'s error (module docstring)."""
    C = res.info.extra["solve_mesh"]
    f, b, _ = closest_point_index(C).query(np.ascontiguousarray(mesh.V[[src]]))
    nv, (i, j, k) = C.n_vertices, C.F[f[0]]
    F = np.concatenate([np.delete(C.F, f[0], axis=0), [[i, j, nv], [j, k, nv], [k, i, nv]]])
    on_copy = cg.geodesic_distance(cg.TriMesh(np.concatenate([C.V, bary_positions(C, f, b)]), F), nv,
                                   method="exact")[:nv]
    vf, vc = np.zeros(nv, dtype=np.int64), np.zeros(nv, dtype=np.int64)
    vf[C.F.ravel()], vc[C.F.ravel()] = np.repeat(np.arange(C.n_faces), 3), np.tile(np.arange(3), C.n_faces)
    order2 = np.asarray(res.field.field.distance_at(vf, np.eye(3)[vc]))
    uf, ub, _ = closest_point_index(mesh).query(np.ascontiguousarray(C.V))
    user_at_copy = np.einsum("kc,kc->k", ub, exact[mesh.F[uf]])
    geo, o2 = _errors(on_copy, user_at_copy), _errors(order2, on_copy)
    return {"geometry_mean": geo["mean"], "geometry_signed": geo["signed"],
            "order2_mean": o2["mean"], "order2_signed": o2["signed"]}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("meshes", nargs="+")
    ap.add_argument("--fractions", default="0.1,0.25")
    ap.add_argument("--sources", default="0,0.5", help="vertex indices, or fractions (0, 1) of the vertex count")
    ap.add_argument("--corrections", default="", help="comma-separated: cost, area, metric, arc, ones")
    ap.add_argument("--decompose", action="store_true")
    ap.add_argument("--out", default=None, help="append JSON lines here")
    args = ap.parse_args()
    kinds = [""] + [k for k in args.corrections.split(",") if k]
    state = {"kind": "", "t": 0.0}
    plain = adapted._medium_on

    def medium_on(medium, mesh, coarse):  # the correction where the user gave no medium (the patches stay)
        if medium is not None or not state["kind"]:
            return plain(medium, mesh, coarse)
        t0 = time.perf_counter()
        out = correction(state["kind"], mesh, coarse)
        state["t"] = time.perf_counter() - t0
        return out

    adapted._medium_on = medium_on
    for name in args.meshes:
        mesh = cg.load_mesh(next(MESHES.glob(f"{name}.*")))
        for s in (float(x) for x in args.sources.split(",")):
            src = int(s * mesh.n_vertices) if 0 < s < 1 else int(s)
            exact = cg.geodesic_distance(mesh, src, method="exact")
            t0 = time.perf_counter()
            cg.geodesic_distance(mesh, src, method="heat")
            t_heat = time.perf_counter() - t0
            for frac in (float(x) for x in args.fractions.split(",")):
                for kind in kinds:
                    state.update(kind=kind, t=0.0)
                    t0 = time.perf_counter()
                    res = cg.GeodesicSolver(mesh, "qclp", resolution=frac, m=0.0,
                                              estimate_error=False).solve(src)
                    t = time.perf_counter() - t0
                    ad = res.info.extra["adapted"]
                    d = res.distance.copy()
                    d[src] = np.nan
                    row = {"mesh": name, "faces": mesh.n_faces, "source": src, "fraction": frac,
                           "solve_faces": ad["faces"], "correction": kind or "none", **_errors(d, exact),
                           "t_corr": state["t"], "solve": ad["solve_time"], "time_over_heat": t / t_heat,
                           "source_patches": ad.get("source_patches")}
                    if args.decompose and not kind:
                        row.update(decompose(mesh, src, res, exact))
                    emit_row(row, args.out)


if __name__ == "__main__":
    main()
