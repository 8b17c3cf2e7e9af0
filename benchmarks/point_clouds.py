"""Geodesic distance on point clouds: the vertices of the shared meshes, clean and with Gaussian noise.

Each cloud is the vertex set of a shared mesh (no faces), or with ``--resample`` random points of its surface, as is
or moved by Gaussian noise of ``--noise`` times the bounding-box diagonal (a fixed seed). The reference is the mesh's
exact field (MMP, ``method="exact"``) from the same point, at the original positions: point ``i`` of a vertex cloud
is vertex ``i`` of the mesh; resampled points are inserted into the mesh as vertices for it. Methods:

- ``pc-heat``: the point-cloud heat method (``potpourri3d.PointCloudHeatSolver``; the library's ``heat`` on a
  cloud runs it), the time unit;
- ``knn-dijkstra``: Dijkstra on the symmetrized graph of the ``--knn`` nearest neighbours (scipy), Euclidean edges;
- ``qclp`` at order 1 and 2 on each triangle set of :data:`~cvxgeodesic.mesh.pointcloud.TRIANGLE_SETS`
  (``--sets``), and the smoothed ``qcqp-dirichlet`` (``--m``) at both orders on the first set.

``the default`` is ``GeodesicSolver(PointCloud(P)).solve(src)``: what a user gets without options (``qclp`` at order 2
on a copy, ``resolution="auto"``, or its fallback to order 1 on the cloud's triangles, named in the label; "denoised"
where ``PointCloud``'s ``denoise="auto"`` moved the points onto their jets first). Every other row builds the cloud
of the points as given (``denoise=None``) unless it says "denoised".

Columns: mean and max relative error over the reachable points (``cvxgeodesic.evaluation.errors.relative_error``),
time over pc-heat's (best of ``--repeats``; building the cloud's triangles included for the library's methods:
each is a fresh ``PointCloud`` + solver + solve; pc-heat's includes its own set-up), and unreachable points
(infinite distance). The default's label also counts the points left out of the cloud's triangles (outliers, line
points) that took their distance from their neighbours (``PointCloud.reach_left_out``).
``--denoise 1,2`` adds rows of ``qclp`` at both orders on the first set of the cloud denoised by that many passes of
jet projection (``PointCloud(P, denoise=passes)``, :mod:`cvxgeodesic.mesh.denoise`; its time included), and, on vertex
clouds, a ``floor`` row: the exact field read at each noisy point's closest point of the mesh (the error that no
method answering at the noisy positions avoids: the noise's tangential part moves the point along the field).
``--normals`` adds rows of ``qclp`` at both orders on the first set of the cloud given normals (the mesh's vertex
normals; on resampled clouds each point's face normal): ``PointCloud(P, normals)``'s fans leave out the neighbours
whose normal turns by more than 60 degrees (:func:`cvxgeodesic.mesh.pointcloud.normal_fans`).

``--subsample 0.2,0.25`` adds rows of ``qclp`` at order 2 on a Poisson-disk subsample of the cloud with about that
fraction of its points (:func:`poisson_subsample`), answered at every point of the cloud: the P2 field at each point's
closest point of the subsample's triangles (the order-2 program on fewer points, the lever of ``resolution=`` on
meshes; not a library option: docs/dev/adapted-log.md has why). The source is its point's closest point there; the
time includes the subsampling.

``--resolution auto,0.25`` adds rows of ``qclp`` at order 2 with ``resolution=`` (the library's option: order 2 on a
quadric copy of the surface through the points, :meth:`~cvxgeodesic.mesh.pointcloud.PointCloud.surface`, answered at
every point; the time includes building the cloud and the copy); with ``--denoise``, also on the cloud denoised by
each pass count (``PointCloud(P, denoise=passes)``).

``--neighbours 12,20,30`` measures the neighbour count instead: ``qclp`` at both orders on the union of the fans of
:func:`~cvxgeodesic.mesh.pointcloud.local_fans` (potpourri3d's construction, whose k is fixed at 30; at k = 30 they
build the same triangles on evenly sampled clouds), after a row on potpourri3d's own fans.
One process; run with one thread::

    CVXGEODESIC_THREADS=1 OMP_NUM_THREADS=1 PYTHONPATH=src python benchmarks/point_clouds.py --quick

The date and the load average are printed first.
"""

from __future__ import annotations

import argparse
import datetime
import os
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra
from scipy.spatial import cKDTree

import cvxgeodesic as cg
from cvxgeodesic.evaluation.errors import relative_error
from cvxgeodesic.mesh.pointcloud import TRIANGLE_SETS
from report_common import timed

MESHES = Path(__file__).resolve().parents[1].parent / "shared" / "meshes"
QUICK = ("kitten", "bimba")
MIN_VERTICES = 5000


def knn_dijkstra(P: np.ndarray, src: int, k: int) -> np.ndarray:
    """Dijkstra on the symmetrized k-nearest-neighbour graph (Euclidean edge lengths)."""
    dist, idx = cKDTree(P).query(P, k=k + 1)
    n = P.shape[0]
    rows = np.repeat(np.arange(n), k)
    G = sp.coo_matrix((dist[:, 1:].ravel(), (rows, idx[:, 1:].ravel())), shape=(n, n)).tocsr()
    G = G.maximum(G.T)
    return dijkstra(G, indices=src)




def row(name, noise, label, d, exact, src, t, t_heat):
    reach = np.isfinite(d)
    err = relative_error(np.where(reach, d, exact), exact, [src])[reach]  # unreachable: counted, not averaged
    print(f"| {name} | {noise * 100:g} % | {label} | {np.nanmean(err) * 100:.3f} % | {np.nanmax(err) * 100:.2f} % "
          f"| {t / t_heat:.2f}× | {int((~reach).sum())} |", flush=True)


def shared_meshes(names: list[str] | None) -> list[Path]:
    if names:
        return [next(MESHES.glob(f"{n}.*")) for n in names]
    out = []
    for line in (MESHES / "MANIFEST.tsv").read_text().splitlines()[1:]:
        cols = line.split("\t")
        if int(cols[3]) >= MIN_VERTICES and cols[5] == "yes" and "/" not in cols[0]:
            out.append(MESHES / cols[0])
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--meshes", nargs="*", help="mesh names in ../shared/meshes (default: all manifold ones with "
                    f"at least {MIN_VERTICES} vertices)")
    ap.add_argument("--quick", action="store_true", help=f"the meshes {', '.join(QUICK)}")
    ap.add_argument("--noise", default="0,0.001,0.003", help="noise levels, fractions of the diagonal")
    ap.add_argument("--sets", default=",".join(TRIANGLE_SETS))
    ap.add_argument("--knn", type=int, default=8)
    ap.add_argument("--source", type=float, default=0.5, help="source vertex, as a fraction of the vertex count")
    ap.add_argument("--no-order2", action="store_true")
    ap.add_argument("--m", type=float, default=1.0, help="smoothness of qcqp-dirichlet")
    ap.add_argument("--repeats", type=int, default=2, help="times are the best of this many runs")
    ap.add_argument("--neighbours", default="", help="instead of the methods: qclp at both orders on the union of "
                    "the fans of pointcloud.local_fans at these neighbour counts (e.g. 12,20,30,45)")
    ap.add_argument("--denoise", default="", help="also qclp on the first set of the cloud denoised by these "
                    "passes of jet projection (e.g. 1,2), and the floor row")
    ap.add_argument("--normals", action="store_true", help="also qclp at both orders on the first set of the cloud "
                    "with normals (the mesh's vertex normals; on resampled clouds each point's face normal)")
    ap.add_argument("--resolution", default="", help="also qclp order 2 with these resolution= values (e.g. auto,0.25; "
                    "tenth: the count auto takes on a cloud that is not clean, 1/10 of the faces, at least 2,000)")
    ap.add_argument("--subsample", default="", help="also qclp order 2 on Poisson-disk subsamples with about these "
                    "fractions of the points (e.g. 0.2,0.25), answered at every point")
    ap.add_argument("--resample", default="", help="instead of the vertices: random surface points, these fractions "
                    "of the face count (e.g. 0.5,0.25: two densities); the reference is exact MMP on the mesh with "
                    "the points inserted as vertices")
    args = ap.parse_args()
    print(f"# {datetime.datetime.now(datetime.UTC):%Y-%m-%d %H:%M} UTC, load {os.getloadavg()[0]:.2f} "
          f"{os.getloadavg()[1]:.2f}, threads {os.environ.get('CVXGEODESIC_THREADS', 'default')}", flush=True)
    print("| cloud | noise | method | mean err | max err | time / pc-heat | unreachable |")
    print("|---|---|---|---|---|---|---|")
    paths = shared_meshes(list(QUICK) if args.quick else args.meshes)
    sets = args.sets.split(",")
    rng = np.random.default_rng(0)
    for path in paths:
        mesh = cg.load_mesh(path, kind="surface")
        try:
            clouds = clouds_of(mesh, path.stem, args, rng)
        except cg.NonManifoldError as exc:  # the reference, exact MMP, needs a manifold mesh (beetle_open)
            print(f"| {path.stem} | | skipped: no reference ({exc}) | | | | |", flush=True)
            continue
        for name, V0, exact, src, normals in clouds:
            for noise in (float(x) for x in args.noise.split(",")):
                P = V0 + rng.normal(scale=noise * mesh.bbox_diagonal, size=V0.shape) if noise else V0
                if args.neighbours:
                    compare_neighbours(name, noise, P, exact, src, args)
                else:
                    compare(name, noise, P, exact, src, sets, args)
                    if args.normals:
                        compare_normals(name, noise, P, normals, exact, src, sets[0], args)
                    if args.resolution:
                        compare_resolution(name, noise, P, exact, src, args)
                    if args.subsample:
                        compare_subsampled(name, noise, P, exact, src, args)
                    if args.denoise:
                        compare_denoised(name, noise, P, exact, src, sets[0], args,
                                         None if args.resample else mesh)


def clouds_of(mesh, stem: str, args, rng) -> list[tuple[str, np.ndarray, np.ndarray, int, np.ndarray]]:
    """``(label, points, exact field at them, source index, normals)``: the vertices (libigl's vertex normals), or with
    ``--resample`` the clouds of random surface points (:func:`resample`; each point's face normal)."""
    import igl

    if not args.resample:
        src = int(args.source * mesh.n_vertices)
        return [(f"{stem} ({mesh.n_vertices // 1000}K)", mesh.V, cg.geodesic_distance(mesh, src, method="exact"),
                 src, igl.per_vertex_normals(mesh.V, mesh.F.astype(np.int64)))]
    out = []
    normals = mesh.face_normals_unnormalized / np.linalg.norm(mesh.face_normals_unnormalized, axis=1)[:, None]
    for fraction in (float(x) for x in args.resample.split(",")):
        X, split, idx, faces = resample(mesh, fraction, rng)
        src = int(args.source * X.shape[0])
        exact = cg.geodesic_distance(split, int(idx[src]), method="exact")[idx]
        out.append((f"{stem} resampled ({X.shape[0] // 1000}K)", X, exact, src, normals[faces]))
    return out


def resample(mesh, fraction: float, rng) -> tuple[np.ndarray, cg.TriMesh, np.ndarray, np.ndarray]:
    """Random surface points: ``fraction`` of the faces drawn without replacement with probability proportional to
    their area, one uniform point in each. Returns the points, the mesh with each point inserted as a vertex (its face
    split in three: the same surface, so exact MMP on it gives the exact field at the points), their indices there
    and the faces they lie in."""
    V, F = mesh.V, mesh.F
    area = mesh.face_areas
    k = int(fraction * mesh.n_faces)
    faces = rng.choice(mesh.n_faces, size=k, replace=False, p=area / area.sum())
    X = np.einsum("ki,kij->kj", rng.dirichlet([1.0, 1.0, 1.0], size=k), V[F[faces]])
    idx = mesh.n_vertices + np.arange(k)
    a, b, c = F[faces].T
    keep = np.ones(mesh.n_faces, dtype=bool)
    keep[faces] = False
    split = cg.TriMesh(np.vstack([V, X]), np.vstack([F[keep], np.c_[a, b, idx], np.c_[b, c, idx], np.c_[c, a, idx]]))
    return X, split, idx, faces


def timed_pc_heat(P: np.ndarray, src: int, repeats: int) -> tuple[np.ndarray, float]:
    """The point-cloud heat method's field on ``P`` from ``src`` and its time (set-up and solve), the time unit."""
    def pc_heat():
        import potpourri3d as pp3d

        return pp3d.PointCloudHeatSolver(P).compute_distance(src)
    return timed(pc_heat, repeats)


def compare(name: str, noise: float, P: np.ndarray, exact: np.ndarray, src: int, sets: list[str], args) -> None:
    """One row per method on the cloud ``P``."""
    d, t_heat = timed_pc_heat(P, src, args.repeats)
    row(name, noise, "pc-heat", d, exact, src, t_heat, t_heat)
    d, t = timed(lambda: knn_dijkstra(P, src, args.knn), args.repeats)
    row(name, noise, f"{args.knn}-NN Dijkstra", d, exact, src, t, t_heat)
    res, t = timed(lambda: cg.GeodesicSolver(cg.PointCloud(P)).solve(src), args.repeats)
    row(name, noise, f"the default ({_solved_on(res)})", res.distance, exact, src, t, t_heat)
    for kind in sets:
        runs = [("qclp", 1, 0.0)] + ([] if args.no_order2 else [("qclp", 2, 0.0)])
        if kind == sets[0]:  # the smoothed formulation, at both orders, on the first set
            runs += [("qcqp-dirichlet", order, args.m) for order in (1, 2) if order == 1 or not args.no_order2]
        for method, order, m in runs:
            def solve(kind=kind, method=method, order=order, m=m):
                cloud = cg.PointCloud(P, triangles=kind, denoise=None)  # the points as given
                return cg.GeodesicSolver(cloud, method, order=order, m=m).solve(src).distance
            d, t = timed(solve, args.repeats)
            label = f"{method} order {order}{f' m={m:g}' if m else ''}, {kind}"
            row(name, noise, label, d, exact, src, t, t_heat)


def compare_normals(name: str, noise: float, P: np.ndarray, normals: np.ndarray, exact: np.ndarray, src: int,
                    kind: str, args) -> None:
    """Rows of the default and of ``qclp`` at both orders on the cloud given ``normals`` (``PointCloud(P, normals)``:
    fans that leave out neighbours whose normal turns by more than 60 degrees,
    :func:`~cvxgeodesic.mesh.pointcloud.normal_fans`)."""
    _, t_heat = timed_pc_heat(P, src, args.repeats)
    res, t = timed(lambda: cg.GeodesicSolver(cg.PointCloud(P, normals)).solve(src), args.repeats)
    row(name, noise, f"the default ({_solved_on(res)}), with normals", res.distance, exact, src, t, t_heat)
    for order in (1,) if args.no_order2 else (1, 2):
        def solve(order=order):
            cloud = cg.PointCloud(P, normals, triangles=kind, denoise=None)  # the points as given
            return cg.GeodesicSolver(cloud, "qclp", order=order).solve(src).distance
        d, t = timed(solve, args.repeats)
        row(name, noise, f"qclp order {order}, {kind}, with normals", d, exact, src, t, t_heat)


def compare_denoised(name: str, noise: float, P: np.ndarray, exact: np.ndarray, src: int, kind: str, args,
                     mesh) -> None:
    """Rows of ``qclp`` at both orders on the cloud denoised by each of ``--denoise``'s pass counts (the time: the
    denoising, the triangles, the solver and the solve, over pc-heat's on the raw cloud); first, given the mesh whose
    vertices the cloud's points are, the floor: the exact field at each point's closest point of the mesh."""
    from cvxgeodesic.mesh.closest import closest_point_index

    _, t_heat = timed_pc_heat(P, src, args.repeats)
    if mesh is not None:
        faces, bary, _ = closest_point_index(mesh).query(P)
        floor = np.einsum("ki,ki->k", exact[mesh.F[faces]], bary)
        row(name, noise, "floor: exact at the closest surface point", floor, exact, src, t_heat, t_heat)
    for passes in (int(x) for x in args.denoise.split(",")):
        for order in (1,) if args.no_order2 else (1, 2):
            def solve(passes=passes, order=order):
                cloud = cg.PointCloud(P, triangles=kind, denoise=passes)
                return cg.GeodesicSolver(cloud, "qclp", order=order).solve(src).distance
            d, t = timed(solve, args.repeats)
            row(name, noise, f"qclp order {order}, {kind}, denoised ({passes} pass{'es' if passes > 1 else ''})", d,
                exact, src, t, t_heat)


def compare_resolution(name: str, noise: float, P: np.ndarray, exact: np.ndarray, src: int, args) -> None:
    """Rows of ``qclp`` at order 2 with each ``--resolution`` value, on the cloud and on the cloud denoised by each of
    ``--denoise``'s pass counts (the denoising's time included); a fallback's reason goes in the label."""
    _, t_heat = timed_pc_heat(P, src, args.repeats)
    passes = [None] + [int(x) for x in args.denoise.split(",") if x]
    for value, denoise in ((v, p) for v in args.resolution.split(",") for p in passes):
        def solve(value=value, denoise=denoise):
            cloud = cg.PointCloud(P, denoise=denoise)
            return cg.GeodesicSolver(cloud, "qclp", order=2, resolution=_resolution(value, cloud)).solve(src)
        res, t = timed(solve, args.repeats)
        smoothed = "" if denoise is None else f", denoised ({denoise} pass{'es' if denoise > 1 else ''})"
        row(name, noise, f"qclp order 2, resolution={value}{smoothed} ({_solved_on(res)})", res.distance, exact,
            src, t, t_heat)


def _resolution(value: str, cloud) -> str | int | float:
    """``resolution=`` for a ``--resolution`` value: ``auto``, a fraction, a face count, or ``tenth``: the face
    count ``"auto"`` takes on a cloud that is not clean (1/10 of the faces, at least 2,000; the default before
    2026-12-07 on every cloud)."""
    from cvxgeodesic.strategies.adapted import AUTO_FRACTION, AUTO_MIN_FACES

    if value == "auto":
        return value
    if value == "tenth":
        return max(AUTO_MIN_FACES, round(AUTO_FRACTION * cloud.mesh.n_cells))
    return int(value) if value.isdigit() else float(value)


def _solved_on(res) -> str:
    """What an adapted solve ran on: the copy's faces, or the fallback's reason (order 1 on the cloud's triangles);
    and how many points left out of the triangles (outliers) took their distance from their neighbours."""
    ad = res.info.extra.get("adapted")
    carried = res.info.extra.get("left_out_reached", 0)
    also = f"; {carried} left-out point{'s' if carried > 1 else ''} carried" if carried else ""
    first = "denoised; " if res.info.extra.get("denoised", {}).get("automatic") else ""  # "auto" moved the points
    if ad is None:
        return first + "the cloud's triangles" + also
    return first + (f"{ad['faces']} faces" if ad["fallback"] is None else f"fallback: {ad['fallback']}") + also


def poisson_subsample(P: np.ndarray, fraction: float, seed: int = 1) -> np.ndarray:
    """Indices (ascending) of a Poisson-disk subsample of ``P`` with ``fraction`` of its points, within 5 %: points
    taken in a random order, each kept unless a kept point lies within ``r`` of it, ``r`` bisected on the count."""
    tree = cKDTree(P)
    order = np.random.default_rng(seed).permutation(P.shape[0])
    target = fraction * P.shape[0]
    lo, hi = 0.0, 4 * float(np.mean(tree.query(P, k=2)[0][:, 1])) / np.sqrt(fraction)
    for _ in range(20):
        r = 0.5 * (lo + hi)
        alive = np.ones(P.shape[0], dtype=bool)
        keep = []
        for i, near in zip(order, tree.query_ball_point(P[order], r), strict=True):
            if alive[i]:
                keep.append(i)
                alive[near] = False
        if abs(len(keep) - target) <= 0.05 * target:
            break
        lo, hi = (r, hi) if len(keep) > target else (lo, r)
    return np.sort(np.asarray(keep, dtype=np.int64))


def compare_subsampled(name: str, noise: float, P: np.ndarray, exact: np.ndarray, src: int, args) -> None:
    """Rows of ``qclp`` at order 2 on Poisson-disk subsamples (``--subsample``), answered at every point of ``P``
    (the P2 field at each point's closest point of the subsample's triangles; the source at its point's closest
    point there). The time: subsampling, the subsample's cloud, the solver, the solve and the answer."""
    from cvxgeodesic.mesh.closest import closest_point_index
    from cvxgeodesic.mesh.locate import SurfacePoint

    _, t_heat = timed_pc_heat(P, src, args.repeats)
    for fraction in (float(x) for x in args.subsample.split(",")):
        def solve(fraction=fraction):
            keep = poisson_subsample(P, fraction)
            cloud = cg.PointCloud(P[keep], denoise=None)
            faces, bary, _ = closest_point_index(cloud.mesh).query(np.ascontiguousarray(P))
            res = cg.GeodesicSolver(cloud, "qclp", order=2).solve([SurfacePoint(int(faces[src]), bary[src])])
            d = np.asarray(res.field.distance_at(faces, bary), dtype=float)
            d[src] = 0.0
            return d, keep.size
        (d, kept), t = timed(solve, args.repeats)
        row(name, noise, f"qclp order 2 on a Poisson-disk subsample of {kept} points ({fraction:g})", d, exact, src,
            t, t_heat)


def compare_neighbours(name: str, noise: float, P: np.ndarray, exact: np.ndarray, src: int, args) -> None:
    """One row per neighbour count and order: ``qclp`` on the union of the fans of
    :func:`~cvxgeodesic.mesh.pointcloud.local_fans`; first on potpourri3d's own fans (k = 30, the default). Times
    include building the fans, as in :func:`compare`."""
    from cvxgeodesic.mesh.pointcloud import CloudMesh, local_fans, triangle_set

    d, t_heat = timed_pc_heat(P, src, args.repeats)
    row(name, noise, "pc-heat", d, exact, src, t_heat, t_heat)
    orders = (1,) if args.no_order2 else (1, 2)

    def solve(k: int | None, order: int) -> tuple[np.ndarray, int]:
        if k is None:
            mesh = cg.PointCloud(P, outliers="keep", denoise=None).mesh  # the fans alone, as the rows of local_fans
        else:
            tri, owner = local_fans(P, k)
            mesh = CloudMesh(P, triangle_set(tri, owner, P, "union")[0])
        return cg.GeodesicSolver(mesh, "qclp", order=order).solve(src).distance, mesh.n_faces

    for k in [None, *(int(x) for x in args.neighbours.split(","))]:
        for order in orders:
            (d, n_faces), t = timed(lambda k=k, order=order: solve(k, order), args.repeats)
            fans = "potpourri3d's fans (k = 30)" if k is None else f"k = {k}"
            row(name, noise, f"qclp order {order}, {fans}, {n_faces} triangles)", d, exact, src, t, t_heat)


if __name__ == "__main__":
    main()
