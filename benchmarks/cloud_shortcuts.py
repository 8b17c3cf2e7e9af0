"""Fan edges that cut across: how far a vertex cloud's triangles are from the surface its points came from.

For the vertex cloud of each shared mesh (``PointCloud(mesh.V)``, the union of the fans), every fan edge's length is
compared with the path between its ends along the edges of the mesh subdivided twice (``igl.upsample``: the same
surface, paths within a few percent of the geodesic): an edge shorter than ``1/ratio`` of that path joins points
that lie far apart on the surface. Columns:

- ``> 2``, ``> 3``: fan edges whose path is more than 2 and 3 times their length;
- ``normals``: the median cosine between the vertex normals (libigl's) at the ends of the edges above 3: near −1,
  sheets that face each other closer than a spacing;
- ``union`` and ``oracle``: ``qclp`` at orders 1 and 2 on the union, and on the union less every triangle with an
  edge above 2 (an oracle: it reads the mesh), mean relative error against exact MMP from vertex ``n/2``;
- ``flipped``: the exact field on the mesh after one pass of extrinsic Delaunay flips (an edge whose two opposite
  angles sum above π is replaced by the other diagonal, quads apart) against the mesh's: how much the vertices alone
  leave the geodesics open.

One process; run with one thread::

    CVXGEODESIC_THREADS=1 PYTHONPATH=src python benchmarks/cloud_shortcuts.py --meshes lucy_20k buddha camelhead_open

The date and the load average are printed first (docs/pointclouds.md, "Why the statues miss").
"""

from __future__ import annotations

import argparse
import datetime
import os

import numpy as np
from scipy.sparse.csgraph import dijkstra

import cvxgeodesic as cg
from cvxgeodesic.evaluation.errors import relative_error
from cvxgeodesic.mesh.pointcloud import CloudMesh, PointCloud
from point_clouds import shared_meshes


def path_ratios(mesh, cloud_mesh, most: float = 3.0) -> np.ndarray:
    """(e,) the path along the edges of ``mesh`` subdivided twice between the ends of each edge of ``cloud_mesh``
    (whose vertices are ``mesh``'s), over its length; ``inf`` above ``most`` (the search stops there)."""
    import igl

    VU, FU = igl.upsample(mesh.V, mesh.F.astype(np.int64), 2)  # the mesh's vertices first, in their order
    graph = cg.TriMesh(VU, FU).vertex_adjacency
    E, length = cloud_mesh.edges, cloud_mesh.edge_lengths
    ratio = np.full(len(E), np.inf)
    starts = np.unique(E[:, 0])
    for batch in np.array_split(starts, max(1, len(starts) // 500)):
        mine = np.isin(E[:, 0], batch)
        far = dijkstra(graph, indices=batch, limit=most * length[mine].max())
        row = np.searchsorted(batch, E[mine, 0])
        ratio[mine] = far[row, E[mine, 1]] / length[mine]
    return np.where(ratio > most, np.inf, ratio)


def flipped(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """The faces after one pass of extrinsic Delaunay flips (each quad at most once, no edge made twice)."""
    F = F.copy()
    half = np.sort(np.stack([F[:, [1, 2]], F[:, [2, 0]], F[:, [0, 1]]], axis=1), axis=2).reshape(-1, 2)
    code = half[:, 0].astype(np.int64) * len(V) + half[:, 1]  # half-edge 3f + k lies opposite corner k of face f
    order = np.argsort(code, kind="stable")
    pair = np.flatnonzero(code[order][1:] == code[order][:-1])
    h1, h2 = order[pair], order[pair + 1]

    def angle(h: np.ndarray) -> np.ndarray:
        f, k = h // 3, h % 3
        a, b, c = V[F[f, k]], V[F[f, (k + 1) % 3]], V[F[f, (k + 2) % 3]]
        u, v = b - a, c - a
        cos = (u * v).sum(axis=1) / np.linalg.norm(u, axis=1) / np.linalg.norm(v, axis=1)
        return np.arccos(np.clip(cos, -1.0, 1.0))

    existing, used = set(code.tolist()), np.zeros(len(F), dtype=bool)
    for i in np.flatnonzero(angle(h1) + angle(h2) > np.pi + 1e-9):
        (f1, k1), (f2, k2) = divmod(int(h1[i]), 3), divmod(int(h2[i]), 3)
        c1, c2 = F[f1, k1], F[f2, k2]
        key = min(c1, c2) * len(V) + max(c1, c2)
        if used[f1] or used[f2] or key in existing:
            continue
        p, q = F[f1, (k1 + 1) % 3], F[f1, (k1 + 2) % 3]
        F[f1], F[f2] = [c1, p, c2], [c2, q, c1]
        used[f1] = used[f2] = True
        existing.add(key)
    return F


def mean_error(d: np.ndarray, exact: np.ndarray, src: int) -> float:
    reach = np.isfinite(d)
    return float(np.nanmean(relative_error(np.where(reach, d, exact), exact, [src])[reach]) * 100)


def measure(path, ratio_cut: float) -> str:
    import igl

    mesh = cg.load_mesh(path, kind="surface")
    src = mesh.n_vertices // 2
    exact = cg.geodesic_distance(mesh, src, method="exact")
    cloud = PointCloud(mesh.V)
    E = cloud.mesh.edges
    ratio = path_ratios(mesh, cloud.mesh)
    normals = igl.per_vertex_normals(mesh.V, mesh.F.astype(np.int64))
    worst = ratio > 3
    cos = np.median((normals[E[worst, 0]] * normals[E[worst, 1]]).sum(axis=1)) if worst.any() else np.nan
    cut = (ratio > ratio_cut)[cloud.mesh.cell_edges].any(axis=1)
    n = mesh.n_vertices
    oracle = CloudMesh(mesh.V, cloud.mesh.F[~cut], name="oracle", vertex_map=np.arange(n), file_index=np.arange(n),
                       notes=[])
    oracle.cloud = cloud
    fields = [cg.GeodesicSolver(m, "qclp", order=order).solve(src).distance
              for m in (cloud, oracle) for order in (1, 2)]
    union, kept = (" / ".join(f"{mean_error(d, exact, src):.3g} %" for d in pair) for pair in (fields[:2], fields[2:]))
    other = cg.geodesic_distance(cg.TriMesh(mesh.V, flipped(mesh.V, mesh.F)), src, method="exact")
    return (f"| {path.stem} | {len(E):,} | {int((ratio > 2).sum()):,} | {int(worst.sum()):,} | {cos:.2f} | {union} | "
            f"{kept} ({int(cut.sum()):,} triangles cut) | {mean_error(other, exact, src):.3g} % |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--meshes", nargs="*", default=["lucy_20k", "buddha", "camelhead_open"],
                    help="mesh names in ../shared/meshes")
    ap.add_argument("--ratio", type=float, default=2.0, help="the oracle cuts the triangles with an edge above this")
    args = ap.parse_args()
    print(f"# {datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M} UTC, load {os.getloadavg()[0]:.2f}, threads "
          f"{os.environ.get('CVXGEODESIC_THREADS', 'default')}", flush=True)
    print("| cloud | fan edges | > 2 | > 3 | normals | union, order 1 / 2 | oracle, order 1 / 2 | flipped |")
    print("|---|---|---|---|---|---|---|---|")
    for path in shared_meshes(args.meshes):
        print(measure(path, args.ratio), flush=True)


if __name__ == "__main__":
    main()
