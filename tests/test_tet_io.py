"""Tetrahedral meshes from files and distance fields to VTU (issue 26): TetGen .node/.ele natively, meshio formats."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from cvxgeodesic.errors import MeshFormatError, MeshRepairWarning, ParameterError
from cvxgeodesic.mesh.tet_generate import tet_box
from cvxgeodesic.mesh.tet_io import load_tet_mesh, read_tetgen, save_tet_distance
from cvxgeodesic.mesh.tetmesh import TetMesh

meshio = pytest.importorskip("meshio")


def write_tetgen(tmp_path, mesh, *, base=1, stem="m", node_extra="", ele_extra="", per=4):
    node = [f"# TetGen node file\n{mesh.n_vertices} 3 1 1  # points, dim, attributes, markers"]
    node += [f"{i + base}  {x!r} {y!r} {z!r}  0.5 1" for i, (x, y, z) in enumerate(mesh.V.tolist())]
    (tmp_path / f"{stem}.node").write_text("\n".join(node) + "\n" + node_extra)
    ele = [f"{mesh.n_tets} {per} 1", ""]
    for t, row in enumerate(mesh.T.tolist()):
        extra = [row[0]] * (per - 4)
        ele.append(f"{t + base} " + " ".join(str(v + base) for v in row + extra) + "   7  # region 7")
    (tmp_path / f"{stem}.ele").write_text("\n".join(ele) + "\n" + ele_extra)
    return tmp_path / f"{stem}.ele"


@pytest.mark.parametrize("base", [0, 1])
def test_tetgen_round_trip(tmp_path, base):
    mesh = tet_box(2, jitter=0.2, seed=1)
    path = write_tetgen(tmp_path, mesh, base=base)
    for p in (path, path.with_suffix(".node")):
        m = load_tet_mesh(p)
        np.testing.assert_array_equal(m.V, mesh.V)
        np.testing.assert_array_equal(m.T, mesh.T)
        assert m.name == "m" and m.notes == ()
    for ext in (".node", ".ele"):  # upper-case names find an upper-case partner
        (tmp_path / f"M{ext.upper()}").write_bytes((tmp_path / f"m{ext}").read_bytes())
    np.testing.assert_array_equal(load_tet_mesh(tmp_path / "M.ELE").T, mesh.T)


def test_tetgen_ten_node_elements_and_unused_points(tmp_path):
    mesh = TetMesh(np.vstack([tet_box(1).V, [[5.0, 5.0, 5.0]]]), tet_box(1).T)
    path = write_tetgen(tmp_path, mesh, per=10)
    with pytest.warns(MeshRepairWarning):
        m = load_tet_mesh(path)
    assert m.n_vertices == 8 and m.file_index.tolist() == list(range(8)) + [-1]
    np.testing.assert_array_equal(m.dropped_vertices, [[5.0, 5.0, 5.0]])
    assert any("10-node" in n for n in m.notes) and any("dropped 1 vertices in no tetrahedron" in n for n in m.notes)


@pytest.mark.parametrize("node, ele, match", [
    ("", "1 4 0\n1 1 2 3 4\n", r"m.node: file is empty"),
    ("4 2 0 0\n", "1 4 0\n", r"m.node, line 1: the header must be"),
    ("4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n", "1 4 0\n", r"announces 4 points, the file has 3"),
    ("4 3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 x\n", "1 4 0\n", r"m.node, line 5: coordinates must be numbers"),
    ("4 3\n1 0 0 0\n2 1 0 0\n2 0 1 0\n4 0 0 1\n", "1 4 0\n1 1 2 3 4\n", r"point number 2 is given more than once"),
    ("4 3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n", "1 4 0\n1 1 2 3 9\n", r"m.ele, line 2: tetrahedron 1 names point 9"),
    ("4 3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n", "1 5 0\n", r"m.ele, line 1: the header must be"),
    ("4 3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n", "2 4 0\n1 1 2 3 4\n", r"announces 2 tetrahedra, the file has 1"),
    ("4 3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n", "1 4 0\n1 1 2 3\n", r"m.ele, line 2: a tetrahedron needs"),
    ("4 3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 nan\n", "1 4\n1 1 2 3 4\n", r"line 5: point 4 has a non-finite"),
])
def test_tetgen_errors_name_file_and_line(tmp_path, node, ele, match):
    (tmp_path / "m.node").write_text(node)
    (tmp_path / "m.ele").write_text(ele)
    with pytest.raises(MeshFormatError, match=match):
        read_tetgen(tmp_path / "m.node")


def test_tetgen_missing_partner(tmp_path):
    (tmp_path / "m.node").write_text("4 3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n")
    with pytest.raises(MeshFormatError, match=r"m.ele: no such file"):
        load_tet_mesh(tmp_path / "m.node")


def test_repeated_vertices_and_duplicates_are_dropped_with_notes(tmp_path):
    (tmp_path / "m.node").write_text("5 3\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n4 1 1 1\n")
    (tmp_path / "m.ele").write_text("4 4\n0 0 1 2 3\n1 0 1 2 2\n2 3 2 1 0\n3 4 1 3 2\n")
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        m = load_tet_mesh(tmp_path / "m.ele")
    assert m.T.tolist() == [[0, 1, 2, 3], [4, 1, 3, 2]]
    assert any("dropped 1 tetrahedra that repeat a vertex (first: tet 1" in n for n in m.notes)
    assert any("dropped 1 duplicate tetrahedra" in n for n in m.notes)
    assert len([x for x in w if issubclass(x.category, MeshRepairWarning)]) == 2


@pytest.mark.parametrize("ext, fmt", [(".vtu", "vtu"), (".vtk", "vtk"), (".msh", "gmsh22"), (".mesh", "medit"),
                                      (".inp", "abaqus")])
def test_meshio_formats(tmp_path, ext, fmt):
    mesh = tet_box(2, jitter=0.2, seed=4)
    tri = mesh.boundary_faces
    path = tmp_path / f"m{ext}"
    cells = [("tetra", mesh.T), ("triangle", tri)]
    kwargs = {"file_format": fmt}
    if fmt == "gmsh22":
        kwargs["binary"] = False
        cell_data = {"gmsh:physical": [np.ones(len(mesh.T), int), np.ones(len(tri), int)],
                     "gmsh:geometrical": [np.ones(len(mesh.T), int), np.ones(len(tri), int)]}
        meshio.Mesh(mesh.V, cells, cell_data=cell_data).write(path, **kwargs)
    else:
        meshio.Mesh(mesh.V, cells).write(path, **kwargs)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MeshRepairWarning)
        m = load_tet_mesh(path)
    np.testing.assert_allclose(m.V, mesh.V, atol=1e-12 if fmt != "abaqus" else 1e-6)
    np.testing.assert_array_equal(m.T, mesh.T)
    assert any(f"ignored cells other than tetrahedra: {len(tri)} triangle" in n for n in m.notes)


def test_meshio_errors(tmp_path):
    p = tmp_path / "surface.vtu"
    meshio.Mesh(np.eye(3), [("triangle", np.array([[0, 1, 2]]))]).write(p)
    with pytest.raises(MeshFormatError, match=r"surface.vtu: no tetrahedra \(cell types: triangle\)"):
        load_tet_mesh(p)
    bad = tmp_path / "bad.vtu"
    bad.write_text("not xml at all")
    with pytest.raises(MeshFormatError, match="meshio cannot read the file"):
        load_tet_mesh(bad)
    with pytest.raises(MeshFormatError, match="no such file"):
        load_tet_mesh(tmp_path / "missing.msh")
    with pytest.raises(MeshFormatError, match="unsupported extension '.obj'"):
        load_tet_mesh(tmp_path / "x.obj")


def test_save_distance_vtu_round_trip(tmp_path):
    mesh = tet_box(3)
    d = np.linalg.norm(mesh.V, axis=1)
    d[5] = np.inf
    for ext in (".vtu", ".vtk"):
        out = save_tet_distance(tmp_path / f"d{ext}", mesh, d, fields={"error": d * 0.1})
        back = meshio.read(out)
        np.testing.assert_array_equal(back.points, mesh.V)
        np.testing.assert_array_equal(back.cells_dict["tetra"], mesh.T)
        np.testing.assert_array_equal(back.point_data["distance"], d)
        np.testing.assert_array_equal(back.point_data["error"], d * 0.1)
        assert load_tet_mesh(out).n_tets == mesh.n_tets
    with pytest.raises(ParameterError, match="distance"):
        save_tet_distance(tmp_path / "x.vtu", mesh, d[:-1])
    with pytest.raises(ParameterError):
        save_tet_distance(tmp_path / "x.ply", mesh, d)
    with pytest.raises(ParameterError, match="fields"):
        save_tet_distance(tmp_path / "x.vtu", mesh, d, fields={"distance": d})
    assert not list(tmp_path.glob(".*.tmp"))
