"""Point clouds with oriented normals: fans that do not cross a thin wall or a sharp crease (pointcloud.normal_fans)."""

from __future__ import annotations

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic.mesh.pointcloud import PointCloud, _oriented_normals, fan_triangles

THICKNESS = 0.05


def _thin_box(n: int = 6000, seed: int = 3, t: float = THICKNESS) -> tuple[np.ndarray, np.ndarray, int, int]:
    """Points sampled evenly on a 1 x 1 x ``t`` box, each with its face's outward normal; the indices of the
    points nearest the centres of the top and the bottom face."""
    rng = np.random.default_rng(seed)
    faces = [  # (origin, u, v, normal)
        ([0, 0, t], [1, 0, 0], [0, 1, 0], [0, 0, 1]), ([0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, -1]),
        ([0, 0, 0], [1, 0, 0], [0, 0, t], [0, -1, 0]), ([0, 1, 0], [1, 0, 0], [0, 0, t], [0, 1, 0]),
        ([0, 0, 0], [0, 1, 0], [0, 0, t], [-1, 0, 0]), ([1, 0, 0], [0, 1, 0], [0, 0, t], [1, 0, 0])]
    area = np.array([np.linalg.norm(np.cross(u, v)) for _, u, v, _ in faces])
    counts = rng.multinomial(n, area / area.sum())
    P, N = [], []
    for (o, u, v, nrm), c in zip(faces, counts, strict=True):
        a, b = rng.random((2, c))
        P.append(np.asarray(o) + a[:, None] * np.asarray(u) + b[:, None] * np.asarray(v))
        N.append(np.tile(np.asarray(nrm, dtype=float), (c, 1)))
    P, N = np.vstack(P), np.vstack(N)
    top, bottom = (int(np.argmin(np.linalg.norm(P - [0.5, 0.5, z], axis=1) + (N[:, 2] != side)))
                   for z, side in ((t, 1), (0, -1)))  # on the top face and on the bottom face
    return P, N, top, bottom


def test_oriented_normals_keep_the_fans_from_crossing_a_thin_wall():
    """From the top face's centre, the bottom face's centre is reached around the rim (about 1 + THICKNESS); without
    normals the fans of a neighbourhood wider than the wall join the two faces, and it is about THICKNESS away."""
    P, N, top, bottom = _thin_box()
    around = 1.0 + THICKNESS
    with_normals = cg.geodesic_distance(PointCloud(P, N), top, method="qclp")
    without = cg.geodesic_distance(PointCloud(P), top, method="qclp")
    assert without[bottom] < 0.2 * around  # the defect the normals remove
    assert abs(with_normals[bottom] - around) < 0.05 * around, with_normals[bottom]
    assert np.isfinite(with_normals).all()


def test_oriented_normals_across_a_gap_thinner_than_a_spacing_are_used_and_not_averaged_away():
    """A box 0.6 spacings thick (the statues' folds, closed lips): the facing sides' normals point apart but are
    oriented. Counting such pairs took them as unoriented, and averaging each normal with the facing side's turned
    many over; now the normals are used as given and the field goes around the rim."""
    P, N, top, bottom = _thin_box(6000, t=0.012)  # spacing about 0.019
    cloud = PointCloud(P, N)
    assert not any("unoriented" in n for n in cloud.notes), cloud.notes
    averaged = _oriented_normals(N, P, np.arange(len(P)), "box", [])
    assert (np.einsum("ni,ni->n", averaged, N) > 0).all()  # averaged with the facing side's, 979 of them turned over
    d = cg.geodesic_distance(cloud, top, method="qclp")
    assert abs(d[bottom] - 1.012) < 0.05, d[bottom]
    assert np.isfinite(d).all()


def _grid(n: int = 40, seed: int = 2) -> tuple[np.ndarray, np.ndarray, float]:
    """A jittered n x n grid of the unit square with normals +z, and its spacing."""
    rng = np.random.default_rng(seed)
    g = np.linspace(0, 1, n)
    x, y = np.meshgrid(g, g)
    h = 1 / (n - 1)
    P = np.c_[x.ravel(), y.ravel(), np.zeros(n * n)] + rng.normal(scale=0.1 * h, size=(n * n, 3)) * [1, 1, 0]
    return P, np.tile([0.0, 0.0, 1.0], (n * n, 1)), h


@pytest.mark.parametrize("k", [3, 6])
def test_a_few_points_facing_away_from_all_their_neighbours_stay_reachable(k):
    """A few points a third of a spacing over a plane, their normals facing it (buddha's thin sheets, whose nearest
    neighbours all lie on the facing side): their fans hold only each other, so they were a piece of their own
    (distance inf); a group that small gets its whole fans back."""
    P, N, h = _grid()
    rng = np.random.default_rng(k)
    Q = np.r_[P, np.c_[0.5 + rng.normal(scale=0.5 * h, size=(k, 2)), np.full(k, 0.3 * h)]]
    d = cg.geodesic_distance(PointCloud(Q, np.r_[N, np.tile([0.0, 0.0, -1.0], (k, 1))]), 0, method="qclp")
    np.testing.assert_allclose(d[-k:], np.linalg.norm(Q[-k:] - Q[0], axis=1), rtol=0.05)


def test_two_plates_facing_within_a_spacing_stay_apart():
    """A second plate 0.4 spacings over the first, facing it, not joined: a surface of its own, not given the
    fans that would join it to the first."""
    P, N, h = _grid()
    Q = np.r_[P, np.c_[P[:, :2] + 0.3 * h, np.full(len(P), 0.4 * h)]]
    d = cg.geodesic_distance(PointCloud(Q, np.r_[N, -N]), 0, method="qclp")
    assert np.isinf(d[len(P):]).all() and np.isfinite(d[:len(P)]).all()


def test_unoriented_normals_are_not_used_and_a_note_says_so():
    P, N, top, _ = _thin_box(3000)
    flipped = N * np.where(np.random.default_rng(0).random(len(N)) < 0.5, -1.0, 1.0)[:, None]
    cloud = PointCloud(P, flipped)
    assert any("normals look unoriented" in n for n in cloud.notes)
    np.testing.assert_array_equal(cloud.mesh.F, PointCloud(P).mesh.F)
    res = cg.GeodesicSolver(cloud, "qclp").solve(top)
    assert any("normals look unoriented" in n for n in res.info.notes)


def test_a_crease_sampled_with_its_faces_normals_stays_connected():
    """Points of two faces meeting at a right angle, each with its own face's normal: the averaged normals of the
    points next to the crease bridge it (no point cut off), and the distance across it is the unfolded one."""
    rng = np.random.default_rng(5)
    a = rng.random((1500, 2))
    P = np.vstack([np.c_[a[:750, 0], a[:750, 1], np.zeros(750)], np.c_[a[750:, 0], np.zeros(750), a[750:, 1]]])
    N = np.vstack([np.tile([0.0, 0.0, 1.0], (750, 1)), np.tile([0.0, -1.0, 0.0], (750, 1))])
    src = int(np.argmin(np.linalg.norm(P - [0.5, 0.8, 0.0], axis=1)))
    d = cg.geodesic_distance(PointCloud(P, N), src, method="qclp")
    assert np.isfinite(d).all()
    far = int(np.argmin(np.linalg.norm(P - [0.5, 0.0, 0.8], axis=1)))
    unfolded = np.hypot(P[far, 0] - P[src, 0], P[src, 1] + P[far, 2])
    assert abs(d[far] - unfolded) < 0.05 * unfolded, (d[far], unfolded)


@pytest.mark.parametrize("neighbours", [30, 20])
def test_without_normals_the_fans_are_unchanged(neighbours):
    P, _, _, _ = _thin_box(2000)
    tri, owner = fan_triangles(P, neighbours)
    tri2, owner2 = fan_triangles(P, neighbours, None)
    np.testing.assert_array_equal(tri, tri2)
    np.testing.assert_array_equal(owner, owner2)


def test_use_normals_false_builds_the_fans_without_them_and_a_bad_value_is_refused():
    from cvxgeodesic.errors import ParameterError

    P, N, _, _ = _thin_box(2000)
    np.testing.assert_array_equal(PointCloud(P, N, use_normals=False).mesh.F, PointCloud(P).mesh.F)
    assert not np.array_equal(PointCloud(P, N).mesh.F, PointCloud(P).mesh.F)
    with pytest.raises(ParameterError, match="use_normals must be True or False"):
        PointCloud(P, N, use_normals="no")


def test_the_command_line_reads_a_point_file_s_normals_and_can_ignore_them(tmp_path, capsys):
    from cvxgeodesic.cli import main

    P, N, top, bottom = _thin_box(3000)
    np.savetxt(tmp_path / "box.xyz", np.c_[P, N])  # six columns: points and normals
    out = tmp_path / "d.npy"
    base = ["distance", str(tmp_path / "box.xyz"), "--source", str(top), "--method", "qclp", "--quiet", "-o", str(out)]
    assert main(base) == 0
    assert np.load(out)[bottom] > 0.9
    assert main([*base, "--overwrite", "--ignore-normals"]) == 0
    assert np.load(out)[bottom] < 0.3
    mesh = tmp_path / "m.obj"
    mesh.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    assert main(["distance", str(mesh), "--source", "0", "--ignore-normals", "-o", str(tmp_path / "m.npy")]) == 2
    assert "--ignore-normals applies to point files; " in capsys.readouterr().err


def test_a_point_whose_every_neighbour_turns_away_gets_its_plain_fan_back():
    from cvxgeodesic.mesh.pointcloud import local_fans, normal_fans

    rng = np.random.default_rng(4)
    P = np.c_[rng.random((800, 2)), np.zeros(800)]
    N = np.tile([0.0, 0.0, 1.0], (800, 1))
    lone = int(np.argmin(np.linalg.norm(P - [0.5, 0.5, 0.0], axis=1)))
    N[lone] = -N[lone]  # every neighbour's normal turns by 180 degrees from this one's
    tri, owner = normal_fans(P, N, 20)
    tri0, owner0 = local_fans(P, 20)
    mine = tri[owner == lone]
    assert mine.size and np.array_equal(np.unique(mine, axis=0), np.unique(tri0[owner0 == lone], axis=0))
