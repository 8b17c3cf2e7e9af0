"""Outliers and line-like neighbourhoods of point clouds (mesh/cloud_outliers.py, PointCloud(outliers=...)): found,
left out of the fans with a note, refused as sources; the rest of the field as on the clean cloud."""

from __future__ import annotations

import numpy as np
import pytest

import cvxgeodesic as cg
from conftest import sphere_points
from cvxgeodesic.errors import MeshError, ParameterError, SourceError
from cvxgeodesic.mesh.cloud_outliers import find_defects
from cvxgeodesic.mesh.pointcloud import PointCloud

#: 1,500 random points of the unit sphere: mean distance to the 6 nearest about 0.063
SPACING = 0.063



def _with_outliers(X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``X`` with five points moved off the sphere by 5, 10, 20 and 50 spacings (out and in) inserted at scattered
    positions; returns the cloud and the outliers' indices in it."""
    heights = np.array([5.0, 10.0, -5.0, 20.0, 50.0]) * SPACING
    rows = np.array([3, 400, 777, 1200, 1500])  # positions in the result
    U = sphere_points(5, seed=9)
    Y = np.insert(X, rows - np.arange(5), U * (1.0 + heights)[:, None], axis=0)
    return Y, rows


def _carried(Y: np.ndarray, d: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """The outliers' distances through their 30 nearest other points (none of them an outlier here)."""
    from scipy.spatial import cKDTree

    dist, idx = cKDTree(Y).query(Y[rows], k=31)
    assert not np.isin(idx[:, 1:], rows).any()
    return (d[idx[:, 1:]] + dist[:, 1:]).min(axis=1)


def test_planted_outliers_are_left_out_with_a_note_and_their_distance_carried_from_their_neighbours():
    X = sphere_points()
    Y, rows = _with_outliers(X)
    cloud = PointCloud(Y)
    assert cloud.outliers.tolist() == rows.tolist() and cloud.line_points.size == 0
    assert not np.isin(cloud.mesh.F, rows).any()  # no fan reaches up to them
    note = "5 isolated outliers (far off the surface their neighbours sample; first: input points 3, 400, 777, 1200)"
    assert any(note in n and "left out of the triangles" in n for n in cloud.notes)
    res = cg.GeodesicSolver(cloud, "qclp").solve(0)
    assert any(note in n for n in res.info.notes)
    # the outliers: a neighbour's distance plus the step to it, the least of them; 5 to 50 spacings off the sphere:
    # at least the straight distance from the source (less order 1's shortness, ~1 %), at most the great circle to
    # their foot plus their height (plus a spacing: the foot's nearest point is among the neighbours)
    np.testing.assert_allclose(res.distance[rows], _carried(Y, res.distance, rows), rtol=1e-12)
    assert res.info.extra["left_out_reached"] == 5 and res.info.n_unreachable == 0
    assert any("5 point(s) in no triangle (outliers, line points or isolated points" in n for n in res.info.notes)
    foot = np.arccos(np.clip(Y[rows] @ Y[0] / np.linalg.norm(Y[rows], axis=1), -1, 1))
    height = np.abs(np.linalg.norm(Y[rows], axis=1) - 1.0)
    assert np.all(res.distance[rows] >= 0.98 * np.linalg.norm(Y[rows] - Y[0], axis=1))
    assert np.all(res.distance[rows] <= foot + height + SPACING)
    # the other points: the clean cloud's triangles, so its field up to the solver's tolerance (the unknowns are in
    # another order): measured 1.6e-6 (5e-7 of the largest distance), asserted at 1e-5 of it
    ref = PointCloud(X)
    to_clean = np.cumsum(~np.isin(np.arange(Y.shape[0]), rows)) - 1
    assert {tuple(t) for t in np.sort(to_clean[cloud.mesh.F], axis=1).tolist()} == \
        {tuple(t) for t in np.sort(ref.mesh.F, axis=1).tolist()}
    clean = cg.geodesic_distance(ref, 0, method="qclp")
    assert np.abs(np.delete(res.distance, rows) - clean).max() <= 1e-5 * clean.max()
    heat = cg.geodesic_distance(cloud, 0, method="heat")
    np.testing.assert_allclose(heat[rows], _carried(Y, heat, rows), rtol=1e-12)


@pytest.mark.parametrize("triangles", ["union", "consensus", "repaired"])
@pytest.mark.parametrize("neighbours", [30, 20])
def test_without_its_outliers_a_cloud_has_the_clean_cloud_s_triangles(triangles, neighbours):
    # potpourri3d's fans at 30 neighbours, local_fans at 20; the consensus and its repair count the fans' agreement
    X = sphere_points()
    Y, rows = _with_outliers(X)
    cloud = PointCloud(Y, triangles=triangles, neighbours=neighbours)
    to_clean = np.cumsum(~np.isin(np.arange(Y.shape[0]), rows)) - 1
    ours = {tuple(t) for t in np.sort(to_clean[cloud.mesh.F], axis=1).tolist()}
    clean = PointCloud(X, triangles=triangles, neighbours=neighbours)
    assert ours == {tuple(t) for t in np.sort(clean.mesh.F, axis=1).tolist()}
    assert cloud.notes[1:] == clean.notes  # the outliers' note, then the same repairs


def test_the_repair_gives_back_the_fan_of_the_stranded_point_not_of_its_clean_number(monkeypatch):
    # the fans are built on the points without the outliers (renumbered); a point the other fans forget gets its own
    # fan back in the input's numbering (as in test_pointcloud's test without outliers)
    from cvxgeodesic.mesh import pointcloud

    Y, rows = _with_outliers(sphere_points())
    real = pointcloud.fan_triangles
    lonely = 44  # among the points the fans are built on: input point 45 (outlier 3 comes before it)

    def forgetful(P, k, normals=None):
        tri, owner = real(P, k, normals)
        keep = ~(tri == lonely).any(axis=1) | (owner == lonely)
        return tri[keep], owner[keep]

    monkeypatch.setattr(pointcloud, "fan_triangles", forgetful)
    cloud = PointCloud(Y, triangles="repaired")
    assert 45 in cloud.mesh.F and any("1 points would be cut off" in n for n in cloud.notes)
    assert np.isfinite(cg.geodesic_distance(cloud, 0, method="dijkstra")[45])


def test_kept_outliers_are_triangulated_and_pull_the_field():
    X = sphere_points()
    Y, rows = _with_outliers(X)
    kept = PointCloud(Y, outliers="keep")
    assert kept.outliers.size == 0 and np.isin(rows, kept.mesh.F).all()
    d = cg.geodesic_distance(kept, 0, method="qclp")
    assert np.isfinite(d).all()  # the outliers are reached, through the long triangles of their neighbours' fans


@pytest.mark.parametrize("noise", [0.001, 0.003, 0.01, 0.03])
def test_no_point_of_a_noisy_sphere_is_an_outlier(noise):
    # Gaussian noise of 0.1 %, 0.3 %, 1 % and 3 % of the diagonal (2√3): up to 1.6 spacings. Measured: at 3 % three
    # points would be outliers by their height without the threshold's median absolute deviations (HEIGHT_MADS)
    X = sphere_points()
    P = X + np.random.default_rng(4).normal(scale=noise * 2 * np.sqrt(3), size=X.shape)
    found = find_defects(P)
    assert found.outliers.size == 0 and found.lines.size == 0
    notes = PointCloud(P).notes  # at most the fan triangles that the noise stands across the surface (cloud_tilt)
    assert all("fan triangles turned by more than" in n for n in notes), notes


@pytest.mark.parametrize("size", [5, 12])
def test_a_tight_group_of_outliers_apart_from_the_surface_is_found(size):
    # within 0.2 spacings of each other, 20 spacings off the sphere: each other's nearest neighbours, so only their
    # group apart from the surface (cloud_outliers.GAP) tells them from a sparse piece of it
    X = sphere_points()
    G = np.array([0.0, 0.6, 0.8]) * (1 + 20 * SPACING) + \
        np.random.default_rng(5).normal(scale=0.2 * SPACING, size=(size, 3))
    found = find_defects(np.r_[X, G])
    assert found.outliers.tolist() == list(range(X.shape[0], X.shape[0] + size))


@pytest.mark.parametrize("seed", [5, 6])
def test_a_far_group_of_twenty_is_found(seed):
    # 20 points within 0.2 spacings of each other, 50 spacings off the sphere: each one's 30 nearest are the 19 others
    # and 11 far points of the sphere. Measured (seed 5): spread 1.0, height 0.01, isolation 6.2, flatness 0.004 (just
    # above LINE_TOL; 0.000 with other draws, line points then): no rule of a single point finds them; apart from the
    # surface and reaching far, they are a group of outliers
    X = sphere_points()
    G = np.array([0.0, 0.6, 0.8]) * (1 + 50 * SPACING) + \
        np.random.default_rng(seed).normal(scale=0.2 * SPACING, size=(20, 3))
    found = find_defects(np.r_[X, G])
    assert found.outliers.tolist() == list(range(X.shape[0], X.shape[0] + 20)) and found.lines.size == 0


def test_a_sparse_face_beside_a_dense_patch_is_kept():
    # a CAD part's vertices: a large flat face sampled 12 spacings apart beside a dense patch, in its plane. Its points'
    # mean distance to their 30 nearest is 6-20 times the cloud's median (isolation), as for a group of outliers, but
    # they are joined to the patch (cloud_outliers.GAP): before, all 100 were flagged; now only the 8 of its first two
    # columns whose nearest are the patch's points (spread above 4.7, as for a point planted beside the surface),
    # and the cloud keeps even those
    g = np.linspace(0.0, 1.0, 30)
    x, y = np.meshgrid(g, g)
    s = 12 * g[1] * np.arange(10)
    xs, ys = np.meshgrid(1.0 + 12 * g[1] + s, s)
    P = np.r_[np.c_[x.ravel(), y.ravel(), np.zeros(x.size)], np.c_[xs.ravel(), ys.ravel(), np.zeros(xs.size)]]
    found = find_defects(P)
    column = (found.outliers - 900) % 10
    assert found.outliers.size == 8 and (found.outliers >= 900).all() and (column <= 1).all()
    # those 8 lie on the fans of the other points (pointcloud.ON_SURFACE): the cloud keeps them
    cloud = PointCloud(P)
    assert cloud.outliers.size == 0 and np.isin(found.outliers, cloud.mesh.F).all() and not cloud.notes
    lifted = P.copy()
    lifted[955, 2] = 5 * 12 * g[1]  # a point inside the sparse face lifted by 5 of its spacings: left out
    assert 955 in find_defects(lifted).outliers and PointCloud(lifted).outliers.tolist() == [955]


@pytest.mark.shared
@pytest.mark.parametrize("name", ["max_planck.obj", "fandisk.obj", "kitten.obj"])
def test_no_point_of_a_shared_scan_s_cloud_is_an_outlier(name):
    # the clouds of benchmarks/cloud_outliers.py that come closest to the thresholds (max_planck's: the pair rule fires
    # at 1.3 times their largest values; fandisk's sharp edges: height up to 1.05), clean and with 0.3 % noise
    from conftest import shared_mesh_path

    mesh = cg.load_mesh(shared_mesh_path(name), kind="surface")
    rng = np.random.default_rng(0)
    random = np.einsum("fi,fij->fj", rng.dirichlet([1.0, 1.0, 1.0], size=mesh.n_faces), mesh.V[mesh.F])
    for X in (mesh.V, random):  # its vertices, and a random point in every face
        for P in (X, X + rng.normal(scale=0.003 * mesh.bbox_diagonal, size=X.shape)):
            found = find_defects(P)
            assert found.outliers.size == 0 and found.lines.size == 0


def test_outliers_error_names_them_in_the_input_numbering():
    X = sphere_points()
    Y, rows = _with_outliers(X)
    Y = np.insert(Y, 1, Y[0], axis=0)  # a duplicate before them: the input's numbering is one ahead of the cloud's
    with pytest.raises(MeshError, match=r"^point cloud: 5 isolated outliers .*first: input points 4, 401, 778, 1201\) "
                                        r"\(outliers='error'"):
        PointCloud(Y, outliers="error")
    cloud = PointCloud(Y)
    assert cloud.outliers.tolist() == rows.tolist()  # the distinct points' numbering, that of the field
    assert any("first: input points 4, 401, 778, 1201" in n for n in cloud.notes)


def test_a_source_at_an_outlier_is_refused():
    Y, rows = _with_outliers(sphere_points())
    cloud = PointCloud(Y)
    with pytest.raises(SourceError, match=f"^source point {rows[1]} of point cloud is an isolated outlier, left out "
                                          r"of the cloud's triangles .*outliers='keep'"):
        cg.geodesic_distance(cloud, int(rows[1]), method="qclp")
    with pytest.raises(SourceError, match=f"^source 1: source point {rows[0]} of point cloud is an isolated outlier"):
        cg.GeodesicSolver(cloud, "qclp").solve([0, int(rows[0]), cg.surface_point(cloud, Y[10])])
    with pytest.raises(SourceError, match="is an isolated outlier"):
        cg.distance_matrix(cloud, [0, int(rows[2])], method="dijkstra")
    with pytest.raises(SourceError, match=f"^source point {rows[2]} of point cloud is an isolated outlier"):
        cg.distance_matrix(cloud, [0, int(rows[2])], method="qclp", max_distance=0.5)  # local rows: no resolution


def _plane_and_wire() -> tuple[np.ndarray, float]:
    """A 20 × 20 grid of the unit square and a line of 40 points, one spacing apart, standing on it."""
    g = np.linspace(0.0, 1.0, 20)
    x, y = np.meshgrid(g, g)
    h = g[1]
    wire = np.c_[np.full(40, 0.5 + h / 3), np.full(40, 0.5 + h / 3), h * np.arange(1, 41)]
    return np.r_[np.c_[x.ravel(), y.ravel(), np.zeros(x.size)], wire], h


def test_a_wire_standing_on_a_plane_is_left_out_as_a_line():
    P, h = _plane_and_wire()
    cloud = PointCloud(P)
    # measured: the wire's points from 12 spacings up (their 30 nearest are on it) are line points; the 11 below keep
    # fans that join them to the plane
    assert cloud.line_points.tolist() == list(range(411, 440)) and cloud.outliers.size == 0
    assert any("29 points whose neighbours lie on a line (no surface around them; first: input points 411, 412, 413, "
               "414) were left out" in n for n in cloud.notes)
    assert not np.isin(cloud.mesh.F, cloud.line_points).any()
    assert cloud.mesh.face_areas.min() > 0.1 * h**2  # no sliver of the wire reaches the solver
    d = cg.geodesic_distance(cloud, 0, method="qclp")
    # the line points carry the field up the wire, a step of h from each to the next (no point of the plane is
    # among their 30 nearest)
    assert np.isfinite(d).all()
    np.testing.assert_allclose(np.diff(d[410:]), h, rtol=1e-9)
    with pytest.raises(SourceError, match="source point 420 of point cloud is a point whose neighbours lie on a line"):
        cg.geodesic_distance(cloud, 420, method="qclp")
    with pytest.raises(MeshError, match="29 points whose neighbours lie on a line"):
        PointCloud(P, outliers="error")


def test_points_along_scan_lines_are_no_line_points():
    # a surface scanned along lines 5 spacings apart (as beetle_open's vertices are): each point's 10 nearest lie on
    # its line, its 30 nearest span three lines; measured flatness at least 0.30 (LINE_TOL: 0.003)
    t = np.arange(0.0, 60.0)
    x, y = np.meshgrid(t, 5.0 * np.arange(12))
    P = np.c_[x.ravel(), y.ravel(), 0.002 * (x * y).ravel()]
    found = find_defects(P)
    assert found.lines.size == 0 and found.outliers.size == 0


def test_an_unknown_outlier_handling_and_too_few_points_left_are_refused():
    with pytest.raises(ParameterError, match="outliers must be one of exclude, keep, error, got 'drop'"):
        PointCloud(sphere_points(50), outliers="drop")
    P, _ = _plane_and_wire()
    with pytest.raises(ParameterError, match=r"below the number of distinct points \(411 without the outliers\), "
                                             "got 420"):
        PointCloud(P, neighbours=420)


def test_a_click_on_an_outlier_in_the_viewer_says_why_and_keeps_the_field():
    from types import SimpleNamespace

    from cvxgeodesic.viewer import _Viewer

    class _Recorder:  # the polyscope calls of _Viewer.solve, recorded (no OpenGL)
        def __getattr__(self, name):
            return lambda *args, **kw: self

    Y, rows = _with_outliers(sphere_points())
    cloud = PointCloud(Y)
    v = _Viewer(_Recorder(), cloud.mesh, method="dijkstra", solver_kwargs={}, isolines=False)
    before = v.solve([0])
    assert v.pick(SimpleNamespace(is_hit=True, structure_name="points", structure_data={"index": int(rows[0])}))
    assert v.message.startswith(f"source point {rows[0]} of point cloud is an isolated outlier")
    np.testing.assert_array_equal(v.distance, before)


def test_the_command_line_builds_the_cloud_with_its_options(tmp_path, capsys):
    """``--outliers``, ``--triangles``, ``--neighbours`` and ``--denoise`` reach the cloud of a point file; a mesh
    file refuses them; their values are the library's (the command line spells them to build its parser without
    NumPy)."""
    from cvxgeodesic.cli import _options, main
    from cvxgeodesic.mesh import pointcloud

    assert _options.CLOUD_TRIANGLES == pointcloud.TRIANGLE_SETS
    assert _options.CLOUD_OUTLIERS == pointcloud.OUTLIER_HANDLING
    X, planted = _with_outliers(sphere_points())
    np.savetxt(tmp_path / "c.xyz", X)
    out = tmp_path / "d.npy"
    base = ["distance", str(tmp_path / "c.xyz"), "--source", "0", "--method", "qclp", "--quiet", "-o", str(out)]
    assert main([*base, "--outliers", "error"]) == 2
    assert f"input points {planted[0]}" in capsys.readouterr().err
    assert main([*base, "--outliers", "keep", "--neighbours", "20", "--triangles", "repaired"]) == 0
    kept = np.load(out)
    assert np.isfinite(kept).all()
    np.testing.assert_allclose(kept, cg.geodesic_distance(PointCloud(X, outliers="keep", neighbours=20,
                                                                     triangles="repaired"), 0), rtol=1e-6, atol=1e-9)
    assert main([*base, "--overwrite"]) == 0  # the default: left out, their distance carried from their neighbours
    left_out = cg.GeodesicSolver(PointCloud(X), "qclp").solve(0).distance
    assert np.isfinite(left_out).all()
    np.testing.assert_allclose(np.load(out), left_out, rtol=1e-6, atol=1e-9)
    assert main([*base, "--overwrite", "--denoise", "1"]) == 0
    np.testing.assert_allclose(np.load(out), cg.geodesic_distance(PointCloud(X, denoise=1), 0), rtol=1e-6, atol=1e-9)
    assert main([*base, "--overwrite", "--denoise", "11"]) == 2
    assert "denoise must be 'auto', None, 'jet' or an integer from 0 to 10" in capsys.readouterr().err
    mesh = tmp_path / "m.obj"
    mesh.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    assert main(["distance", str(mesh), "--source", "0", "--neighbours", "12", "-o", str(tmp_path / "m.npy")]) == 2
    assert "--neighbours applies to point files; " in capsys.readouterr().err


def test_local_rows_carry_the_outliers_like_whole_rows_and_no_path_starts_at_one():
    Y, rows = _with_outliers(sphere_points())
    cloud = PointCloud(Y)
    assert cloud.left_out.tolist() == rows.tolist()
    local = cg.distance_matrix(cloud, [0, 10], method="qclp", max_distance=1.5)
    for i in range(2):
        row = np.full(cloud.n_points, np.inf)
        row[local[i].indices] = local[i].data
        expected = _carried(Y, row, rows)  # from the patch's field, as whole rows carry the whole field
        inside = expected <= 1.5
        assert inside.any() and (~inside).any()  # some outliers within the radius, some beyond
        np.testing.assert_allclose(row[rows][inside], expected[inside], rtol=1e-12)
        assert np.isinf(row[rows][~inside]).all()
    res = cg.GeodesicSolver(cloud, "qclp").solve(0)
    with pytest.raises(ParameterError, match=f"target vertex {rows[0]} is in no face .*outlier.*no path runs from it"):
        cg.geodesic_path(cloud, res, int(rows[0]))
