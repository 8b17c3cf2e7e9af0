"""Issue 16, item 2: a vertex index means the file's vertex index (CLI ``-s`` and every file the CLI writes)."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import cvxgeodesic as cg
from conftest import shared_mesh_path
from cvxgeodesic.batch import solve_one
from cvxgeodesic.cli import main
from cvxgeodesic.errors import MeshRepairWarning, ParameterError, SourceError
from cvxgeodesic.mesh.fileorder import file_sources
from cvxgeodesic.mesh.io import file_order_mesh, load_distance_ply

PLANE = cg.grid_plane(4, jitter=0.05)  # 25 vertices, 32 faces


def _messy_obj(path):
    """The plane with file vertex 0 unreferenced and mesh vertex 12 split into file vertices 13 and 26.

    File numbering: 0 is a stray point, 1 + i is plane vertex i, 26 repeats the position of plane
    vertex 12 (file vertex 13) and the faces after the first 16 use it instead of 13.
    """
    V = np.vstack([[9.0, 9.0, 9.0], PLANE.V, PLANE.V[12]])
    F = PLANE.F + 1
    F[16:][F[16:] == 13] = 26
    text = "".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in V.tolist())
    text += "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in F.tolist())
    path.write_text(text)
    return path, V


@pytest.fixture
def messy(tmp_path):
    return _messy_obj(tmp_path / "messy.obj")


def test_load_mesh_records_the_file_numbering_and_warns(messy):
    path, V = messy
    with pytest.warns(MeshRepairWarning, match=r"27 vertices in the file, 25 in the mesh \(welded 1 .*dropped 1 "):
        mesh = cg.load_mesh(path)
    assert (mesh.n_file_vertices, mesh.n_vertices) == (27, 25)
    expected = np.r_[-1, np.arange(25), 12]
    np.testing.assert_array_equal(mesh.file_index, expected)
    np.testing.assert_array_equal(mesh.dropped_vertices, [[9.0, 9.0, 9.0]])
    assert any("27 vertices in the file" in n for n in mesh.notes)
    # positions agree through the map, for every referenced file vertex
    keep = mesh.file_index >= 0
    np.testing.assert_array_equal(mesh.V[mesh.file_index[keep]], V[keep])


def test_clean_file_keeps_its_numbering_without_warning(tmp_path):
    path = tmp_path / "clean.obj"
    path.write_text("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in PLANE.V.tolist())
                    + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in PLANE.F.tolist()))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mesh = cg.load_mesh(path)
    assert mesh.n_file_vertices == mesh.n_vertices == 25 and mesh.notes == ()
    np.testing.assert_array_equal(mesh.file_index, np.arange(25))


def test_to_file_order_shares_welded_values_and_gives_dropped_inf(messy):
    with pytest.warns(MeshRepairWarning):
        mesh = cg.load_mesh(messy[0])
    d = np.arange(25.0)
    out = cg.to_file_order(mesh, d)
    assert out.shape == (27,)
    assert out[0] == np.inf  # the stray point
    np.testing.assert_array_equal(out[1:26], d)
    assert out[26] == out[13] == 12.0  # the welded duplicate shares its value
    D = cg.to_file_order(mesh, np.vstack([d, 2 * d]))  # distance_matrix rows
    assert D.shape == (2, 27) and D[1, 26] == 24.0
    assert cg.to_file_order(mesh, d, fill=-1.0)[0] == -1.0
    with pytest.raises(ParameterError, match="25 values"):
        cg.to_file_order(mesh, d[:-1])
    # a mesh that is not from a file is its own file
    np.testing.assert_array_equal(cg.to_file_order(PLANE, d), d)


def test_file_sources_map_and_refuse_dropped_vertices(messy):
    with pytest.warns(MeshRepairWarning):
        mesh = cg.load_mesh(messy[0])
    np.testing.assert_array_equal(file_sources(mesh, [1, 26]), [0, 12])
    np.testing.assert_array_equal(file_sources(mesh, [13, 26]), [12])  # two names of one vertex: one source
    with pytest.raises(SourceError, match="source vertex 0 of messy.obj is in no face"):
        file_sources(mesh, 0)
    with pytest.raises(SourceError, match="source index 27 is out of range: the mesh has 27 vertices"):
        file_sources(mesh, 27)


def test_cli_source_and_outputs_use_the_file_numbering(messy, tmp_path, capsys):
    path, V = messy
    with pytest.warns(MeshRepairWarning):
        mesh = cg.load_mesh(path)
    file_src = 20  # mesh vertex 19
    expected = cg.to_file_order(mesh, cg.geodesic_distance(mesh, 19, method="dijkstra"))
    for ext in ("npy", "ply", "csv"):
        out = tmp_path / f"d.{ext}"
        rc = main(["distance", str(path), "-s", str(file_src), "--method", "dijkstra", "-q", "-o", str(out)])
        assert rc == 0, capsys.readouterr().err
        if ext == "npy":
            d = np.load(out)
        elif ext == "ply":
            m2, fields = load_distance_ply(out)
            d = fields["distance"]
            assert m2.n_vertices == 27
            np.testing.assert_array_equal(m2.V, V)  # the file's coordinates, the stray point included
        else:
            rows = np.genfromtxt(out, delimiter=",", skip_header=1)
            assert rows.shape == (27, 6)
            np.testing.assert_array_equal(rows[:, 0], mesh.file_index)  # the mesh's index (-1: dropped)
            d = rows[:, 5]
        assert d.shape == (27,)
        assert d[file_src] == 0.0
        np.testing.assert_array_equal(d, expected)


def test_cli_source_on_a_dropped_vertex_is_a_clear_error(messy, tmp_path, capsys):
    rc = main(["distance", str(messy[0]), "-s", "0", "--method", "dijkstra", "-o", str(tmp_path / "d.npy")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and err[-1] == ("cvxgeodesic: error: source vertex 0 of messy.obj is in no face, so it has no "
                                   "distance field; choose a vertex of a triangle")
    assert not (tmp_path / "d.npy").exists()


def _file_faces(path):
    """The OBJ's triangles, 0-based, as written."""
    return np.array([[int(t) - 1 for t in line.split()[1:]] for line in path.read_text().splitlines()
                     if line.startswith("f ")])


def test_file_order_mesh_has_the_file_faces(messy):
    with pytest.warns(MeshRepairWarning):
        mesh = cg.load_mesh(messy[0])
    F_file = _file_faces(messy[0])
    assert 26 in F_file  # the duplicate is used by the file's faces
    fm = file_order_mesh(mesh)
    assert fm.n_vertices == 27 and fm.n_faces == mesh.n_faces
    np.testing.assert_array_equal(fm.F, F_file)  # the file's own indices, the duplicate's included
    np.testing.assert_array_equal(fm.V, messy[1])
    np.testing.assert_array_equal(fm.V[fm.F], mesh.V[mesh.F])  # the same triangles


def _written_faces(path):
    ext = path.suffix
    if ext == ".ply":
        return load_distance_ply(path)[0].F
    if ext in (".vtu", ".vtk"):
        return pytest.importorskip("meshio").read(path).cells_dict["triangle"]
    (tm,) = pytest.importorskip("trimesh").load(path, process=False).geometry.values()
    return tm.faces


@pytest.mark.parametrize("ext", [".ply", ".vtu", ".vtk", ".glb"])
def test_output_files_keep_the_input_faces(messy, tmp_path, capsys, ext):
    """Issue 28 item 7: duplicated and unreferenced vertices; every writer with faces, from the CLI and Python."""
    if ext != ".ply":
        pytest.importorskip("meshio" if ext != ".glb" else "trimesh")
    path, V = messy
    F_file = _file_faces(path)
    with pytest.warns(MeshRepairWarning):
        mesh = cg.load_mesh(path)
    expected = cg.to_file_order(mesh, cg.geodesic_distance(mesh, 19, method="dijkstra"))
    out = tmp_path / f"cli{ext}"
    assert main(["distance", str(path), "-s", "20", "--method", "dijkstra", "-q", "-o", str(out)]) == 0
    capsys.readouterr()
    np.testing.assert_array_equal(_written_faces(out), F_file)
    got = cg.load_distance(out)
    assert got.shape == (27,)
    np.testing.assert_allclose(got, expected, rtol=1e-7 if ext == ".glb" else 0)
    # save_distance given the file's path: loads it, writes the file's faces too
    out2 = tmp_path / f"py{ext}"
    with pytest.warns(MeshRepairWarning):
        cg.save_distance(out2, str(path), cg.geodesic_distance(mesh, 19, method="dijkstra"), file_order=True)
    np.testing.assert_array_equal(_written_faces(out2), F_file)
    # in the mesh's numbering: the mesh's faces
    cg.save_distance(out2, mesh, np.zeros(25))
    np.testing.assert_array_equal(_written_faces(out2), mesh.F)


def test_file_faces_leave_out_faces_that_repeat_a_vertex(tmp_path):
    path = tmp_path / "q.obj"
    # a quad (fan-triangulated), a triangle naming vertex 1 twice, and vertex 5 at vertex 1's position
    path.write_text("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 0 0 0\n"
                    "f 1 2 3 4\nf 2 5 3\nf 1 1 5\nf 6 5 2\n")
    with pytest.warns(MeshRepairWarning):
        mesh = cg.load_mesh(path)
    np.testing.assert_array_equal(mesh.file_cells, [[0, 1, 2], [0, 2, 3], [1, 4, 2], [5, 4, 1]])
    assert mesh.n_faces == 4 and mesh.n_vertices == 5  # the last face is the mesh's (0, 4, 1)
    np.testing.assert_array_equal(file_order_mesh(mesh).F, mesh.file_cells)
    # a clean file stores nothing extra: file_cells is vertex_map[F]
    clean = tmp_path / "c.obj"
    clean.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    m2 = cg.load_mesh(clean)
    assert m2._file_faces is None and file_order_mesh(m2) is m2


def test_batch_task_uses_the_file_numbering(messy, tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    row = solve_one(str(messy[0]), [20], str(out), method="dijkstra", output_format="npy")
    assert row["status"] == "ok", row
    d = np.load(out / "messy.npy")
    assert d.shape == (27,) and d[20] == 0.0 and d[0] == np.inf and d[26] == d[13]
    meta = json.loads((out / "messy.json").read_text())
    assert meta["n_vertices"] == 27 and meta["n_mesh_vertices"] == 25
    assert meta["params"]["numbering"] == "file"
    assert any("27 vertices in the file" in n for n in meta["notes"])


@pytest.mark.shared
def test_beetle_source_15000_is_file_vertex_15000(tmp_path, capsys):
    path = shared_mesh_path("beetle_open.off")
    out = tmp_path / "d.npy"
    rc = main(["distance", str(path), "-s", "15000", "--method", "dijkstra", "-q", "-o", str(out)])
    err = capsys.readouterr().err
    assert rc == 0, err
    d = np.load(out)
    assert d.shape == (19887,)  # the file's vertex count (19885 after welding)
    assert d[15000] == 0.0 and np.count_nonzero(d == 0.0) == 1
    # welded pairs (file vertices 14/386 and 40/387) share their value
    assert d[14] == d[386] and d[40] == d[387]
    assert "19887 vertices in the file, 19885 in the mesh" in err
