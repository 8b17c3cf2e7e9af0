"""CLI: --source-point, --boundary and ``cvxgeodesic path`` (issue 15)."""

from __future__ import annotations

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic.batch import solve_one
from cvxgeodesic.cli import main


@pytest.fixture(scope="module")
def plane_file(tmp_path_factory):
    mesh = cg.grid_plane(10, jitter=0.2)
    path = tmp_path_factory.mktemp("mesh") / "plane.obj"
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in mesh.V.tolist()]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in mesh.F.tolist()]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_distance_source_point_matches_api(plane_file, tmp_path):
    out = tmp_path / "d.npy"
    assert main(["distance", str(plane_file), "--source-point", "0.33,0.41,0", "--source-point", "0.8,0.2,0",
                 "--method", "qclp", "-q", "-o", str(out)]) == 0
    mesh = cg.load_mesh(plane_file)
    pts = cg.surface_point(mesh, [[0.33, 0.41, 0.0], [0.8, 0.2, 0.0]])
    np.testing.assert_allclose(np.load(out), cg.geodesic_distance(mesh, pts, method="qclp"), atol=1e-7)


def test_distance_boundary_and_png(plane_file, tmp_path):
    out, png = tmp_path / "b.npy", tmp_path / "b.png"
    assert main(["distance", str(plane_file), "--boundary", "--method", "qclp", "-q", "-o", str(out),
                 "--png", str(png)]) == 0
    d = np.load(out)
    mesh = cg.load_mesh(plane_file)
    on_boundary = (mesh.V[:, 0] <= 0) | (mesh.V[:, 0] >= 1) | (mesh.V[:, 1] <= 0) | (mesh.V[:, 1] >= 1)
    assert np.all(d[on_boundary] == 0) and np.all(d[~on_boundary] > 0)
    assert png.read_bytes()[:4] == b"\x89PNG"


@pytest.mark.parametrize("ext", ["csv", "npy", "ply"])
def test_path_outputs(plane_file, tmp_path, ext):
    out = tmp_path / f"p.{ext}"
    png = tmp_path / "p.png"
    args = ["path", str(plane_file), "--source", "0", "--to-point", "0.9,0.7,0", "--method", "qclp", "-q",
            "-o", str(out)] + (["--png", str(png)] if ext == "csv" else [])
    assert main(args) == 0
    mesh = cg.load_mesh(plane_file)
    if ext == "npy":
        P = np.load(out)
    elif ext == "csv":
        assert out.read_text().splitlines()[0] == "x,y,z,face,b0,b1,b2"  # the cell column named by the reference
        table = np.loadtxt(out, delimiter=",", skiprows=1)
        P, faces, bary = table[:, :3], table[:, 3].astype(int), table[:, 4:]
        np.testing.assert_allclose(np.einsum("kj,kji->ki", bary, mesh.V[mesh.F[faces]]), P, atol=1e-12)
        assert png.read_bytes()[:4] == b"\x89PNG"
    else:
        text = out.read_text().splitlines()
        k = int(next(t for t in text if t.startswith("element vertex")).split()[-1])
        start = text.index("end_header") + 1
        P = np.array([[float(c) for c in t.split()] for t in text[start:start + k]])
        assert len(text) == start + k + (k - 1)
    np.testing.assert_allclose(P[0], [0.9, 0.7, 0.0], atol=1e-12)
    np.testing.assert_allclose(P[-1], mesh.V[0])


def test_path_to_vertex_from_point(plane_file, tmp_path):
    out = tmp_path / "p.npy"
    assert main(["path", str(plane_file), "--source-point", "0.3,0.3,0", "--to", "100", "--method", "exact",
                 "-q", "-o", str(out)]) == 0
    P = np.load(out)
    np.testing.assert_allclose(P[-1], [0.3, 0.3, 0.0], atol=1e-12)


def test_path_takes_a_source_list_like_every_command(plane_file, tmp_path):
    a, b = tmp_path / "a.npy", tmp_path / "b.npy"
    assert main(["path", str(plane_file), "-s", "0,120", "--to", "60", "--method", "dijkstra", "-q", "-o", str(a)]) == 0
    assert main(["path", str(plane_file), "-s", "0", "-s", "120", "--to", "60", "--method", "dijkstra", "-q",
                 "-o", str(b)]) == 0
    np.testing.assert_array_equal(np.load(a), np.load(b))


@pytest.mark.parametrize("args, message", [
    (["distance", "{mesh}", "-o", "{tmp}/x.npy"], "give a source"),
    (["distance", "{mesh}", "--boundary", "-s", "0", "-o", "{tmp}/x.npy"], "on its own"),
    (["path", "{mesh}", "-s", "0", "--to", "5", "-o", "{tmp}/x.txt"], "supported: .csv, .npy, .ply"),
    (["path", "{mesh}", "-s", "0", "-o", "{tmp}/x.csv"], "exactly one target"),
    (["path", "{mesh}", "-s", "0", "--to", "9999", "-o", "{tmp}/x.csv"], "out of range"),
    (["distance", "{mesh}", "--source-point", "1,2", "-o", "{tmp}/x.npy"], None),
])
def test_errors(plane_file, tmp_path, capsys, args, message):
    args = [a.format(mesh=plane_file, tmp=tmp_path) for a in args]
    if message is None:  # argparse rejects a malformed point
        with pytest.raises(SystemExit) as info:
            main(args)
        assert info.value.code == 2 and "X,Y,Z" in capsys.readouterr().err
        return
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]
    assert not any(tmp_path.iterdir())


def test_compare_with_source_point(plane_file, tmp_path, capsys):
    assert main(["compare", str(plane_file), "--source-point", "0.33,0.41,0", "--methods", "qclp,heat,dijkstra",
                 "--out", str(tmp_path / "cmp"), "-q"]) == 0
    table = capsys.readouterr().out
    assert "cannot take point or curve sources" in table  # heat's row names the methods that can
    assert (tmp_path / "cmp" / "field_qclp.png").exists()


def test_batch_task_with_positions_and_boundary(plane_file, tmp_path):
    row = solve_one(str(plane_file), [0, [0.33, 0.41, 0.0]], str(tmp_path), method="qclp", output_format="npy")
    assert row["status"] == "ok", row["error"]
    mesh = cg.load_mesh(plane_file)
    expected = cg.geodesic_distance(mesh, [0, cg.surface_point(mesh, [0.33, 0.41, 0.0])], method="qclp")
    np.testing.assert_allclose(np.load(row["output"]), expected, atol=1e-7)
    (tmp_path / "b").mkdir()
    row = solve_one(str(plane_file), "boundary", str(tmp_path / "b"), method="qclp", output_format="npy")
    assert row["status"] == "ok", row["error"]
    assert np.load(row["output"]).min() == 0.0


def test_batch_source_options_and_spec():
    from cvxgeodesic.batch import _source_spec
    from cvxgeodesic.cli import build_parser
    from cvxgeodesic.cli._options import batch_sources
    from cvxgeodesic.errors import ParameterError, SourceError

    args = build_parser().parse_args(["batch", "x.obj", "-s", "3", "--source-point", "0.1,0.2,0.3", "--out", "o"])
    spec = batch_sources(args)
    assert spec == [3, [0.1, 0.2, 0.3]] and _source_spec(spec) == [3, [0.1, 0.2, 0.3]]
    assert batch_sources(build_parser().parse_args(["batch", "x.obj", "--boundary", "--out", "o"])) == "boundary"
    with pytest.raises(SourceError, match="give a source"):
        batch_sources(build_parser().parse_args(["batch", "x.obj", "--out", "o"]))
    with pytest.raises(ParameterError, match="3 finite numbers"):
        _source_spec([0, [0.1, 0.2]])
    with pytest.raises(ParameterError, match="duplicate"):
        _source_spec([1, 1])


def test_source_points_are_located_by_the_mesh_reference_with_a_note_off_the_surface(capsys):
    """issue 42: ``--source-point`` asks ``mesh.reference.locate`` (no branch on the dimension): a surface's closest
    point, with a note when the position is off the surface; a solid's point inside, and no note."""
    from cvxgeodesic.cli import build_parser
    from cvxgeodesic.cli._options import cli_sources
    from cvxgeodesic.errors import SourceError
    from cvxgeodesic.mesh.locate import SurfacePoint, VolumePoint
    from cvxgeodesic.mesh.tet_generate import tet_box

    sphere = cg.icosphere(2)  # radius 1
    args = build_parser().parse_args(["distance", "x.obj", "--source-point", "0,0,2", "--source-point",
                                      ",".join(map(repr, sphere.V[5].tolist())), "-o", "o.npy"])
    points, _ = cli_sources(args, sphere)
    assert [type(p) for p in points] == [SurfacePoint, SurfacePoint]
    np.testing.assert_allclose(points[1].position(sphere), sphere.V[5], atol=1e-12)
    err = capsys.readouterr().err
    assert err.count("note:") == 1 and "--source-point 0,0,2 is 1 from" in err and "closest point on it" in err
    box = tet_box(2)
    args = build_parser().parse_args(["distance", "x.ele", "--source-point", "0.3,0.4,0.2", "-o", "o.npy"])
    (p,), _ = cli_sources(args, box)
    assert isinstance(p, VolumePoint) and np.allclose(p.position(box), [0.3, 0.4, 0.2])
    assert "note" not in capsys.readouterr().err
    args = build_parser().parse_args(["distance", "x.ele", "--source-point", "0.3,0.4,5", "-o", "o.npy"])
    with pytest.raises(SourceError, match="outside"):
        cli_sources(args, box)
    # the message of a missing source says where a point goes, in the reference's words
    with pytest.raises(SourceError, match=r"--source-point X,Y,Z \(inside a volume\) or --boundary"):
        cli_sources(build_parser().parse_args(["distance", "x.ele", "-o", "o.npy"]), box)
