"""Tetrahedral meshes from files and distance fields to VTU (issue 26), through the one format registry (issue 35):
TetGen .node/.ele natively, meshio's formats by the reader that reads their surfaces, fields by save_distance."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic.errors import MeshFormatError, MeshRepairWarning, ParameterError
from cvxgeodesic.mesh.formats import registry, tetgen
from cvxgeodesic.mesh.io import load_distance, load_mesh, save_distance
from cvxgeodesic.mesh.tet_generate import tet_box
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
        m = load_mesh(p)
        np.testing.assert_array_equal(m.V, mesh.V)
        np.testing.assert_array_equal(m.T, mesh.T)
        assert m.name == "m" and m.notes == ()
    for ext in (".node", ".ele"):  # upper-case names find an upper-case partner
        (tmp_path / f"M{ext.upper()}").write_bytes((tmp_path / f"m{ext}").read_bytes())
    np.testing.assert_array_equal(load_mesh(tmp_path / "M.ELE").T, mesh.T)


def test_tetgen_ten_node_elements_and_unused_points(tmp_path):
    mesh = TetMesh(np.vstack([tet_box(1).V, [[5.0, 5.0, 5.0]]]), tet_box(1).T)
    path = write_tetgen(tmp_path, mesh, per=10)
    with pytest.warns(MeshRepairWarning):
        m = load_mesh(path)
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
        tetgen.read_mesh(tmp_path / "m.node")


def test_tetgen_missing_partner(tmp_path):
    (tmp_path / "m.node").write_text("4 3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n")
    with pytest.raises(MeshFormatError, match=r"m.ele: no such file"):
        load_mesh(tmp_path / "m.node")


def test_repeated_vertices_and_duplicates_are_dropped_with_notes(tmp_path):
    (tmp_path / "m.node").write_text("5 3\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n4 1 1 1\n")
    (tmp_path / "m.ele").write_text("4 4\n0 0 1 2 3\n1 0 1 2 2\n2 3 2 1 0\n3 4 1 3 2\n")
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        m = load_mesh(tmp_path / "m.ele")
    assert m.T.tolist() == [[0, 1, 2, 3], [4, 1, 3, 2]]
    assert any("dropped 1 tetrahedra that repeat a vertex (first: tet 1" in n for n in m.notes)
    assert any("dropped 1 duplicate tetrahedra" in n for n in m.notes)
    assert len([x for x in w if issubclass(x.category, MeshRepairWarning)]) == 2


@pytest.mark.parametrize("ext, fmt", [(".vtu", "vtu"), (".vtk", "vtk"), (".msh", "gmsh22"), (".mesh", "medit"),
                                      (".inp", "abaqus")])
def test_meshio_formats(tmp_path, ext, fmt):
    mesh = tet_box(2, jitter=0.2, seed=4)
    tri = mesh.boundary_facets
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
        m = load_mesh(path)
    np.testing.assert_allclose(m.V, mesh.V, atol=1e-12 if fmt != "abaqus" else 1e-6)  # Abaqus: 7 digits written
    np.testing.assert_array_equal(m.T, mesh.T)
    assert m.name == path.name
    assert any(f"ignored cells other than tetrahedra: {len(tri)} triangle" in n for n in m.notes)


def test_meshio_quadratic_tetrahedra_give_their_corners(tmp_path):
    mesh = tet_box(1)
    mids = mesh.V.shape[0] + np.arange(6 * mesh.n_tets).reshape(-1, 6)  # one point per edge, all distinct
    V = np.vstack([mesh.V, np.zeros((mids.size, 3))])
    meshio.Mesh(V, [("tetra10", np.hstack([mesh.T, mids]))]).write(tmp_path / "q.vtu")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", MeshRepairWarning)
        m = load_mesh(tmp_path / "q.vtu")
    np.testing.assert_array_equal(m.T, mesh.T)
    assert m.notes[0] == f"q.vtu: {mesh.n_tets} 10-node (quadratic) tetrahedra: their 4 corners are used"
    assert m.notes[1].startswith(f"q.vtu: dropped {mids.size} vertices in no tetrahedron")  # the edge midpoints


def test_meshio_errors(tmp_path):
    p = tmp_path / "surface.msh"  # a Gmsh file of triangles: .msh holds volumes only
    meshio.Mesh(np.eye(3), [("triangle", np.array([[0, 1, 2]]))]).write(p, file_format="gmsh22", binary=False)
    with pytest.raises(MeshFormatError, match=r"surface.msh: no tetrahedra \(cell types: triangle\)"):
        load_mesh(p)
    lines = tmp_path / "lines.vtu"  # a VTU may hold either: without both, neither
    meshio.Mesh(np.eye(3), [("line", np.array([[0, 1], [1, 2]]))]).write(lines)
    with pytest.raises(MeshFormatError, match=r"lines.vtu: no triangle or quad cells \(cell types: line\)"):
        load_mesh(lines)
    bad = tmp_path / "bad.vtu"
    bad.write_text("not xml at all")
    with pytest.raises(MeshFormatError, match="meshio cannot read the file"):
        load_mesh(bad)
    with pytest.raises(MeshFormatError, match="no such file"):
        load_mesh(tmp_path / "missing.msh")


@pytest.mark.parametrize("points, cells, match", [
    ([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, np.nan]], [[0, 1, 2, 3]], r"m.vtu: point 3 has a non-finite coordinate"),
    ([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], [[0, 1, 2, 4]],
     r"m.vtu: tetrahedron 0 has point index \[0, 1, 2, 4\] outside \[0, 4\)"),
])
def test_meshio_volume_guards(tmp_path, points, cells, match):
    path = tmp_path / "m.vtu"
    meshio.Mesh(np.array(points, dtype=float), [("tetra", np.array(cells))]).write(path)
    with pytest.raises(MeshFormatError, match=match):
        load_mesh(path)


def test_two_dimensional_points_make_no_volume(tmp_path):
    path = tmp_path / "flat.vtk"  # legacy VTK stores 3 coordinates: a 2-D file is written by hand
    path.write_text("# vtk DataFile Version 4.2\nflat\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n"
                    "0 0 0\n1 0 0\n0 1 0\n0 0 1\nCELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\n")
    real = meshio.read

    def flat(*args, **kwargs):
        mm = real(*args, **kwargs)
        mm.points = mm.points[:, :2]
        return mm

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(meshio, "read", flat)
        with pytest.raises(MeshFormatError, match=r"flat.vtk: points must be 3-D for a tetrahedral mesh, got shape "
                                                  r"\(4, 2\)"):
            load_mesh(path)


def test_a_vtu_is_read_once(tmp_path, monkeypatch):
    """One reader returns the triangles and the tetrahedra it found: a surface VTU was parsed twice before."""
    calls = []
    real = meshio.read
    monkeypatch.setattr(meshio, "read", lambda *a, **k: calls.append(a) or real(*a, **k))
    sphere = cg.icosphere(1)
    save_distance(tmp_path / "s.vtu", sphere, np.zeros(sphere.n_vertices))
    assert isinstance(load_mesh(tmp_path / "s.vtu"), cg.TriMesh) and len(calls) == 1
    save_distance(tmp_path / "v.vtu", tet_box(1), np.zeros(8))
    assert isinstance(load_mesh(tmp_path / "v.vtu"), TetMesh) and len(calls) == 2


def test_the_registry_says_which_formats_hold_volumes(tmp_path):
    assert set(registry.VOLUME_EXTENSIONS) == {".msh", ".vtu", ".vtk", ".mesh", ".inp", ".xdmf", ".med", ".node",
                                               ".ele"}
    assert set(registry.MESHIO_TET_EXTENSIONS) == {".msh", ".vtu", ".vtk", ".mesh", ".inp", ".xdmf", ".med"}
    assert registry.TETGEN_EXTENSIONS == (".node", ".ele")
    assert set(registry.VOLUME_DISTANCE_EXTENSIONS) == {".vtu", ".vtk", ".npy"}
    path = tmp_path / "x.abc"  # an extension no format has (.xyz is a point file's: test_pointcloud)
    path.write_text("0 0 0\n")
    volumes_only = r"\.msh, \.mesh, \.inp, \.xdmf, \.med, \.node, \.ele"
    with pytest.raises(MeshFormatError, match=r"x.abc: unsupported mesh file extension '.abc'; supported: \.obj, .*"
                                              rf"\(any case\), and for tetrahedra {volumes_only}$"):
        load_mesh(path)


@pytest.mark.parametrize("ext", [".vtu", ".vtk"])
def test_save_distance_on_a_volume_round_trip(tmp_path, ext):
    mesh = tet_box(3)
    d = np.linalg.norm(mesh.V, axis=1)
    d[5] = np.inf
    out = save_distance(tmp_path / f"d{ext.upper()}", mesh, d, name="geo")
    back = meshio.read(out)
    np.testing.assert_array_equal(back.points, mesh.V)
    np.testing.assert_array_equal(back.cells_dict["tetra"], mesh.T)
    np.testing.assert_array_equal(back.point_data["geo"], d)
    np.testing.assert_array_equal(load_distance(out, "geo"), d)  # the same reader as a surface's field
    assert load_mesh(out).n_tets == mesh.n_tets
    assert not list(tmp_path.glob(".*.tmp"))


def test_save_distance_on_a_volume_refuses(tmp_path):
    mesh = tet_box(2)
    d = np.zeros(mesh.n_vertices)
    with pytest.raises(ParameterError, match="distance"):
        save_distance(tmp_path / "x.vtu", mesh, d[:-1])
    for ext in (".ply", ".csv", ".glb"):
        with pytest.raises(ParameterError, match=rf"x{ext}: a field on a tetrahedral mesh is written as \.npy, \.vtk "
                                                 rf"or \.vtu, not '{ext}'"):
            save_distance(tmp_path / f"x{ext}", mesh, d)
    for name in ("x", "a b"):  # the surfaces' rule: a name every format can hold, not a coordinate's
        with pytest.raises(ParameterError, match=f"invalid field name '{name}'"):
            save_distance(tmp_path / "x.vtu", mesh, d, name=name)
    assert not list(tmp_path.iterdir())


def test_save_distance_on_a_volume_in_the_file_numbering(tmp_path):
    # point 2 of the file is in no tetrahedron: written back at its place with inf, the tetrahedra in the file's numbers
    (tmp_path / "t.node").write_text("6 3\n1 0 0 0\n2 9 9 9\n3 1 0 0\n4 0 1 0\n5 0 0 1\n6 1 1 1\n")
    (tmp_path / "t.ele").write_text("2 4\n1 1 3 4 5\n2 3 4 5 6\n")
    with pytest.warns(MeshRepairWarning, match="dropped 1 vertices in no tetrahedron"):
        mesh = load_mesh(tmp_path / "t.ele")
    d = np.arange(5.0)
    back = meshio.read(save_distance(tmp_path / "f.vtu", mesh, d, file_order=True))
    np.testing.assert_array_equal(back.points[1], [9, 9, 9])
    np.testing.assert_array_equal(back.point_data["distance"], [0, np.inf, 1, 2, 3, 4])
    np.testing.assert_array_equal(back.cells_dict["tetra"], [[0, 2, 3, 4], [2, 3, 4, 5]])


def test_load_mesh_kind_asks_for_a_surface_or_a_volume(tmp_path):
    """``kind=`` (the statically typed form of load_mesh): the mesh of that kind, or a MeshError naming the file."""
    from cvxgeodesic.errors import MeshError

    box = tet_box(2)
    ele = write_tetgen(tmp_path, box)
    assert isinstance(load_mesh(ele, kind="volume"), TetMesh)
    with pytest.raises(MeshError, match=r"m\.ele: kind='surface' asks for a triangle surface, and a \.ele file holds "
                                        r"only a tetrahedral volume \(kind='volume'\)"):
        load_mesh(ele, kind="surface")
    sphere = cg.icosphere(1)
    obj = tmp_path / "s.obj"
    obj.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in sphere.V) + "".join(
        f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in sphere.F))
    assert isinstance(load_mesh(obj, kind="surface"), cg.TriMesh)
    with pytest.raises(MeshError, match=r"s\.obj: kind='volume' asks for a tetrahedral volume, and a \.obj file"):
        load_mesh(obj, kind="volume")
    # a VTU holds either: the check comes after reading it
    meshio.Mesh(box.V, [("tetra", box.T)]).write(tmp_path / "v.vtu")
    meshio.Mesh(sphere.V, [("triangle", sphere.F)]).write(tmp_path / "t.vtu")
    assert isinstance(load_mesh(tmp_path / "v.vtu", kind="volume"), TetMesh)
    assert isinstance(load_mesh(tmp_path / "t.vtu", kind="surface"), cg.TriMesh)
    with pytest.raises(MeshError, match=r"v\.vtu: kind='surface' asks for a triangle surface, and this file holds a "
                                        r"tetrahedral volume \(kind='volume'\)"):
        load_mesh(tmp_path / "v.vtu", kind="surface")
    with pytest.raises(MeshError, match=r"t\.vtu: kind='volume' asks for a tetrahedral volume, and this file holds a "
                                        r"triangle surface \(kind='surface'\)"):
        load_mesh(tmp_path / "t.vtu", kind="volume")
    with pytest.raises(ParameterError, match="unknown kind 'solid'; choose one of surface, volume"):
        load_mesh(obj, kind="solid")  # type: ignore[call-overload]
    assert isinstance(load_mesh(obj), cg.TriMesh) and isinstance(load_mesh(ele), TetMesh)  # kind=None: either
