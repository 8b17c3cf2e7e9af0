"""``cvxgeodesic batch`` / ``run_batch`` on a real ``dask.distributed.LocalCluster``."""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic.batch import expand_mesh_paths, format_summary, run_batch
from cvxgeodesic.cli import main
from cvxgeodesic.errors import ParameterError
from cvxgeodesic.mesh.io import load_distance_ply

distributed = pytest.importorskip("distributed")

SOURCES = [0, 50]


def _write_off(path, mesh):
    lines = ["OFF", f"{mesh.n_vertices} {mesh.n_faces} 0"]
    lines += [" ".join(map(repr, v)) for v in mesh.V.tolist()]
    lines += ["3 " + " ".join(map(str, f)) for f in mesh.F.tolist()]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture(scope="module")
def cluster():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as c:
        yield c


@pytest.fixture
def meshes(tmp_path):
    """Three good meshes, one corrupt file, one mesh too small for source 50."""
    d = tmp_path / "meshes"
    d.mkdir()
    good = [_write_off(d / "sphere2.off", cg.icosphere(2)),
            _write_off(d / "plane.off", cg.grid_plane(9, 9)),
            _write_off(d / "cylinder.off", cg.cylinder(12, 6))]
    corrupt = d / "corrupt.obj"
    corrupt.write_text("v 0 0 0\nv 1 0 0\nf 1 2 7\n")
    small = _write_off(d / "small.off", cg.icosphere(1))  # 42 vertices: source 50 is out of range
    return good, corrupt, small


def _by_name(rows):
    return {r["mesh"].rsplit("/", 1)[-1]: r for r in rows}


def test_outputs_failures_and_rerun(cluster, meshes, tmp_path):
    good, corrupt, small = meshes
    out = tmp_path / "out"
    paths = [*good, corrupt, small]
    rows = run_batch(paths, SOURCES, out, method="qcqp-hessian", m=1.0, solver="auto",
                     scheduler=cluster.scheduler_address, progress=False)
    assert [r["mesh"] for r in rows] == [str(p.resolve()) for p in paths]  # input order
    by = _by_name(rows)
    assert by["corrupt.obj"]["status"] == "failed" and "MeshFormatError" in by["corrupt.obj"]["error"]
    assert by["small.off"]["status"] == "failed" and "out of range" in by["small.off"]["error"]
    assert not (out / "corrupt.json").exists() and not (out / "small.ply").exists()
    for p in good:
        r = by[p.name]
        assert r["status"] == "ok" and r["solve_status"] == "optimal", r
        mesh, fields = load_distance_ply(out / f"{p.stem}.ply")
        expected = cg.geodesic_distance(cg.load_mesh(p), SOURCES)
        np.testing.assert_allclose(fields["distance"], expected, rtol=1e-7, atol=1e-9)
        meta = json.loads((out / f"{p.stem}.json").read_text())
        assert meta["mesh"] == str(p.resolve()) and meta["params"]["sources"] == SOURCES
        assert meta["info"]["status"] == "optimal" and meta["info"]["iterations"] == r["iterations"] > 0
        assert meta["n_vertices"] == mesh.n_vertices and meta["n_cells"] == r["n_cells"] == mesh.n_faces
    assert not list(out.glob(".*.tmp"))  # atomic writes leave no temporary files

    table = format_summary(rows)
    assert "3 solved, 0 skipped (already done), 2 failed" in table and "out of range" in table

    # a rerun skips finished meshes and retries the failed ones
    stamp = {p.name: (out / f"{p.stem}.ply").stat().st_mtime_ns for p in good}
    rows2 = _by_name(run_batch(paths, SOURCES, out, scheduler=cluster.scheduler_address, progress=False))
    assert all(rows2[p.name]["status"] == "skipped" for p in good)
    assert rows2["corrupt.obj"]["status"] == "failed" and rows2["small.off"]["status"] == "failed"
    assert all((out / f"{p.stem}.ply").stat().st_mtime_ns == stamp[p.name] for p in good)

    # other parameters are not "done": recomputed; force recomputes everything
    rows3 = run_batch(good[:1], SOURCES, out, m=0.5, scheduler=cluster.scheduler_address, progress=False)
    assert rows3[0]["status"] == "ok"
    assert json.loads((out / "sphere2.json").read_text())["params"]["m"] == 0.5
    rows4 = run_batch(good[1:], SOURCES, out, force=True, scheduler=cluster.scheduler_address, progress=False)
    assert [r["status"] for r in rows4] == ["ok", "ok"]


def test_npy_output_and_client_object(cluster, meshes, tmp_path):
    good, _, _ = meshes
    out = tmp_path / "npy"
    with distributed.Client(cluster) as client:
        rows = run_batch(good[:1], [3], out, method="qclp", scheduler=client, progress=False, output_format="npy")
    assert rows[0]["status"] == "ok"
    np.testing.assert_allclose(np.load(out / "sphere2.npy"),
                               cg.geodesic_distance(cg.load_mesh(good[0]), 3, method="qclp"), rtol=1e-7, atol=1e-9)


def test_cli_exit_codes(cluster, meshes, tmp_path, capsys):
    good, corrupt, _ = meshes
    out = tmp_path / "cli"
    folder = good[0].parent
    args = ["batch", "--scheduler", cluster.scheduler_address, "-s", "0", "-s", "50", "--out", str(out), "-q"]
    assert main([*args, str(folder / "*.off"), str(corrupt)]) == 1  # small.off and corrupt.obj fail
    captured = capsys.readouterr()
    assert "2 failed" in captured.out and "corrupt.obj" in captured.out
    assert main([*args, *map(str, good)]) == 0  # all three done already: skipped, exit 0
    assert "3 skipped" in capsys.readouterr().out
    assert main([*args, str(folder / "*.nothing")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no mesh file" in err[0]


def test_default_local_cluster(meshes, tmp_path, capsys):
    """The CLI's own cluster (TLS with the run's certificate, tests/test_cluster_security.py) solves a batch."""
    good, _, _ = meshes
    rc = main(["batch", str(good[0]), str(good[1]), "-s", "0", "--method", "qclp", "--out", str(tmp_path / "local"),
               "--workers", "2"])
    assert rc == 0 and (tmp_path / "local" / "plane.ply").exists() and (tmp_path / "local" / "sphere2.ply").exists()
    assert "2 solved" in capsys.readouterr().out


def test_a_volume_takes_its_default_method_and_its_points_inside(tmp_path):
    """No method: a tetrahedral mesh is solved with the volume default (qclp), as geodesic_distance does; the
    surface default qcqp-hessian does not apply to volumes (this batch used it everywhere and failed). A source
    position is the point inside the solid."""
    from cvxgeodesic.batch import _finished, _params, output_paths, solve_one
    from cvxgeodesic.mesh.locate import volume_point
    from cvxgeodesic.mesh.tet_generate import tet_box

    mesh = tet_box(2)
    (tmp_path / "box.node").write_text(f"{mesh.n_vertices} 3 0 0\n" + "".join(
        f"{i} {x!r} {y!r} {z!r}\n" for i, (x, y, z) in enumerate(mesh.V.tolist())))
    (tmp_path / "box.ele").write_text(f"{mesh.n_tets} 4 0\n" + "".join(
        f"{i} {' '.join(map(str, t))}\n" for i, t in enumerate(mesh.T.tolist())))
    row = solve_one(str(tmp_path / "box.ele"), [0], str(tmp_path), output_format="npy")
    assert row["status"] == "ok", row["error"]
    # the same solve in this process: agreement far below the solver's tolerance (1e-8), not bit for bit
    np.testing.assert_allclose(np.load(tmp_path / "box.npy"), cg.geodesic_distance(mesh, 0), rtol=1e-7, atol=1e-9)
    dist_path, sidecar = output_paths(tmp_path / "box.ele", tmp_path, "npy")
    meta = json.loads(sidecar.read_text())
    assert meta["info"]["method"] == meta["params"]["method"] == "qclp" and meta["dim"] == 3
    # the cell count is the tetrahedra's, under a name that does not call them faces (issue 42)
    assert row["n_cells"] == meta["n_cells"] == mesh.n_tets and "n_faces" not in row and "n_faces" not in meta
    assert "cells" in format_summary([row]).splitlines()[0]
    # done: for a rerun with the default and for one naming qclp, not for one naming another method
    for method, done in ((None, True), ("qclp", True), ("lclp", None)):
        assert _finished(dist_path, sidecar, _params([0], method, 1.0, "auto", False, "npy")) is done
    # the default is the domain's (capabilities.DOMAINS); a sidecar written before it had one: its dimension's
    assert meta["domain"] == "volume"
    sidecar.write_text(json.dumps({k: v for k, v in meta.items() if k != "domain"}))
    assert _finished(dist_path, sidecar, _params([0], None, 1.0, "auto", False, "npy")) is True
    # a position is the point inside the solid (it was the closest surface point, which a volume has not)
    row = solve_one(str(tmp_path / "box.ele"), [[0.4, 0.5, 0.5]], str(tmp_path), output_format="npy")
    assert row["status"] == "ok", row["error"]
    expected = cg.geodesic_distance(mesh, volume_point(mesh, [0.4, 0.5, 0.5]))
    np.testing.assert_allclose(np.load(tmp_path / "box.npy"), expected, rtol=1e-7, atol=1e-9)


def test_usage_errors_before_any_work(meshes, tmp_path):
    good, _, _ = meshes
    twin = tmp_path / "other" / "plane.obj"
    twin.parent.mkdir()
    twin.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    with pytest.raises(ParameterError, match="same outputs"):
        run_batch([good[1], twin], [0], tmp_path / "o")
    with pytest.raises(ParameterError, match="sources"):
        run_batch(good, [], tmp_path / "o")
    with pytest.raises(ParameterError, match="unknown method"):
        run_batch(good, [0], tmp_path / "o", method="nope")
    with pytest.raises(ParameterError, match="no mesh file"):
        expand_mesh_paths([str(tmp_path / "*.stl")])
    with pytest.raises(ParameterError, match="no such file"):
        expand_mesh_paths([str(tmp_path / "missing.obj")])
    assert not (tmp_path / "o").exists()


def test_without_dask_names_the_package(meshes, tmp_path, monkeypatch, capsys):
    good, _, _ = meshes
    monkeypatch.setitem(sys.modules, "distributed", None)  # makes `import distributed` fail
    with pytest.raises(ImportError, match=r"dask\[distributed\]"):
        run_batch(good[:1], [0], tmp_path / "o", progress=False)
    assert main(["batch", str(good[0]), "-s", "0", "--out", str(tmp_path / "o")]) == 2
    assert "pip install 'dask[distributed]'" in capsys.readouterr().err


def test_a_file_name_that_is_not_utf8_is_solved_with_the_others(cluster, meshes, tmp_path):
    """A name from os.listdir with an undecodable byte (surrogate escape) once broke the submission of every task."""
    good, _, _ = meshes
    folder = tmp_path / "names"
    folder.mkdir()
    bad = folder / os.fsdecode(b"bad\xff.off")
    try:
        bad.write_bytes(good[1].read_bytes())
    except (OSError, UnicodeEncodeError):  # a file system (or locale) that refuses such names
        pytest.skip("this file system does not take a non-UTF-8 file name")
    plain = folder / "plain.off"
    plain.write_bytes(good[0].read_bytes())
    out = tmp_path / "out"
    rows = run_batch(expand_mesh_paths([str(folder / "*.off")]), [0], out, method="qclp",
                     scheduler=cluster.scheduler_address, progress=False)
    assert [r["status"] for r in rows] == ["ok", "ok"], rows
    assert (out / os.fsdecode(b"bad\xff.ply")).is_file() and (out / "plain.ply").is_file()
    meta = json.loads((out / os.fsdecode(b"bad\xff.json")).read_text())
    assert meta["mesh"] == str(bad.resolve())  # the path round-trips (JSON escapes the surrogate)
    table = format_summary(rows)
    table.encode("utf-8")  # printable on a strict UTF-8 stdout: the byte is shown as \xff
    assert "bad\\xff.off" in table and "2 solved" in table


def test_out_folder_of_the_inputs_is_refused(meshes, tmp_path, monkeypatch, capsys):
    """``batch 'in/*.ply' --out in`` would replace each mesh by its distance file: refused before any solve."""
    good, _, _ = meshes
    folder = tmp_path / "in"
    folder.mkdir()
    mesh = cg.icosphere(1)
    ply = cg.save_distance(folder / "a.ply", mesh, np.zeros(mesh.n_vertices))
    npy = folder / "b.npy"  # a plain file name is an input whatever its extension
    np.save(npy, np.zeros(3))
    before = {p: p.read_bytes() for p in (ply, npy)}
    monkeypatch.setattr("cvxgeodesic.batch.open_client", _no_cluster)
    with pytest.raises(ParameterError, match=r"--out .*a\.ply is the input file"):
        run_batch([ply], [0], folder, progress=False)
    with pytest.raises(ParameterError, match=r"--out .*b\.npy is the input file"):
        run_batch([npy, good[1]], [0], folder, output_format="npy", progress=False)
    assert main(["batch", str(folder / "*.ply"), "-s", "0", "--out", str(folder), "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "a.ply is the input file" in err[0] and "--out" in err[0]
    assert {p: p.read_bytes() for p in (ply, npy)} == before
    assert sorted(p.name for p in folder.iterdir()) == ["a.ply", "b.npy"]
    # the same folder is fine when no output is an input (.npy distances beside .ply meshes): on to the cluster
    with pytest.raises(AssertionError, match="reached its cluster"):
        run_batch([ply], [0], folder, output_format="npy", progress=False)


def test_unwritable_out_fails_before_any_solve(meshes, tmp_path, monkeypatch, capsys):
    """An --out that cannot be created or written: exit 2, one line naming --out, no cluster started.

    Permission bits do not stop root, so the cases are ones that fail for root too.
    """
    good, _, _ = meshes
    monkeypatch.setattr("cvxgeodesic.batch.open_client", _no_cluster)
    blocker = tmp_path / "somefile"
    blocker.write_text("not a folder\n")
    for out in (blocker, blocker / "sub"):
        assert main(["batch", str(good[1]), "-s", "0", "--out", str(out), "-q"]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and f"--out {out}" in err[0], err
    proc = f"/proc/{os.getpid()}"  # an existing folder in which no one, root included, creates files
    if not os.path.isdir(proc):
        pytest.skip("no /proc")
    with pytest.raises(ParameterError, match=r"--out /proc/\d+: cannot write files in it"):
        run_batch([good[1]], [0], proc, progress=False)


def _no_cluster(*args, **kwargs):
    raise AssertionError("the batch reached its cluster: the check must come before any solve")


@pytest.mark.parametrize("text", ["[1, 2]", '"ok"', "3", "null"])
def test_a_sidecar_that_is_not_an_object_means_not_done(tmp_path, text):
    """A sidecar holding valid JSON of another shape (not written by batch) is not a finished solve: the mesh is
    solved again, where ``meta.get`` raised AttributeError and stopped the batch."""
    from cvxgeodesic.batch import _finished, _params

    dist_path, sidecar = tmp_path / "plane.ply", tmp_path / "plane.json"
    dist_path.write_text("ply\n")
    sidecar.write_text(text)
    assert _finished(dist_path, sidecar, _params([0], None, 1.0, "auto", False, "ply")) is False


def _write_tet_files(folder):
    """box.msh (Gmsh 2.2, tetrahedra only), the TetGen pair tg.node + tg.ele, and a surface plane.off."""
    meshio = pytest.importorskip("meshio")
    from cvxgeodesic.mesh.tet_generate import tet_box

    mesh = tet_box(2)
    meshio.Mesh(mesh.V, [("tetra", mesh.T)]).write(folder / "box.msh", file_format="gmsh22", binary=False)
    (folder / "tg.node").write_text(f"{mesh.n_vertices} 3 0 0\n" + "".join(
        f"{i} {x!r} {y!r} {z!r}\n" for i, (x, y, z) in enumerate(mesh.V.tolist())))
    (folder / "tg.ele").write_text(f"{mesh.n_tets} 4 0\n" + "".join(
        f"{i} {' '.join(map(str, t))}\n" for i, t in enumerate(mesh.T.tolist())))
    _write_off(folder / "plane.off", cg.grid_plane(5, 5))
    return mesh


def test_a_glob_takes_every_mesh_format_and_volumes_get_a_volume_format(cluster, tmp_path):
    """issue 41: ``batch 'b/*'`` skipped .msh files silently, and an explicit .msh was solved, then failed writing
    .ply (no tetrahedra in PLY). Volumes now get a .vtu (tetrahedra + field), surfaces still a .ply; TetGen's pair
    is one mesh."""
    folder = tmp_path / "b"
    folder.mkdir()
    mesh = _write_tet_files(folder)
    paths = expand_mesh_paths([str(folder / "*")])
    assert [p.name for p in paths] == ["box.msh", "plane.off", "tg.ele"]
    out = tmp_path / "out"
    rows = run_batch(paths, [0], out, scheduler=cluster.scheduler_address, progress=False)
    assert [r["status"] for r in rows] == ["ok", "ok", "ok"], [r["error"] for r in rows]
    assert sorted(p.name for p in out.iterdir()) == ["box.json", "box.vtu", "plane.json", "plane.ply", "tg.json",
                                                     "tg.vtu"]
    expected = cg.geodesic_distance(mesh, 0)
    for stem in ("box", "tg"):
        np.testing.assert_allclose(cg.load_distance(out / f"{stem}.vtu"), expected, rtol=1e-7, atol=1e-9)
        assert json.loads((out / f"{stem}.json").read_text())["params"]["format"] == "vtu"
    # a rerun finds them done, in the format each mesh got
    again = run_batch(paths, [0], out, scheduler=cluster.scheduler_address, progress=False)
    assert [r["status"] for r in again] == ["skipped"] * 3
    assert [Path(r["output"]).name for r in again] == ["box.vtu", "plane.ply", "tg.vtu"]


def test_a_volume_with_a_surface_format_fails_before_its_solve(tmp_path, monkeypatch):
    from cvxgeodesic import api
    from cvxgeodesic.batch import solve_one

    _write_tet_files(tmp_path)

    def no_solve(*args, **kwargs):
        raise AssertionError("solved a mesh whose output cannot be written")

    monkeypatch.setattr(api, "GeodesicSolver", no_solve)
    row = solve_one(str(tmp_path / "box.msh"), [0], str(tmp_path), output_format="ply")
    assert row["status"] == "failed"
    assert row["error"] == ("ParameterError: box.msh is a tetrahedral volume: its field cannot be written as .ply "
                            "(PLY (ASCII or binary) holds no tetrahedra); give --format npy or vtu, or no --format "
                            "(.vtu)")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["box.msh", "plane.off", "tg.ele", "tg.node"]
