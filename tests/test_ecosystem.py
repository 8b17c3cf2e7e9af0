"""Issue 16, items 3 and 4: take the meshes people have, give files other tools read.

trimesh and meshio are optional (the ``io`` extra): the tests that need them skip without them;
the "missing library" paths are tested by hiding the module.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic.errors import MeshError, MeshFormatError, ParameterError
from cvxgeodesic.mesh.io import load_distance_ply

SPHERE = cg.icosphere(2)  # 162 vertices


def _field(mesh):
    d = np.linspace(0.0, 2.0, mesh.n_vertices)
    d[5] = np.inf
    return d


# ----------------------------------------------------------------------------------------------------------------------
# Item 3: meshes from other libraries, by duck typing
# ----------------------------------------------------------------------------------------------------------------------


class _O3dVector:
    """What open3d's Vector3dVector / Vector3iVector offer to numpy: ``np.asarray`` works, nothing else."""

    def __init__(self, a):
        self._a = np.asarray(a)

    def __array__(self, dtype=None, copy=None):
        return self._a if dtype is None else self._a.astype(dtype)


class _O3dTriangleMesh:
    """A stand-in for ``open3d.geometry.TriangleMesh`` (open3d itself is ~400 MB)."""

    def __init__(self, V, F):
        self.vertices = _O3dVector(V)
        self.triangles = _O3dVector(F)


def test_open3d_like_mesh_is_accepted():
    d = cg.geodesic_distance(_O3dTriangleMesh(SPHERE.V, SPHERE.F), 0, method="dijkstra")
    np.testing.assert_array_equal(d, cg.geodesic_distance(SPHERE, 0, method="dijkstra"))


def test_trimesh_and_meshio_objects_are_accepted():
    trimesh = pytest.importorskip("trimesh")
    meshio = pytest.importorskip("meshio")
    expected = cg.geodesic_distance(SPHERE, 3, method="dijkstra")
    tm = trimesh.Trimesh(SPHERE.V, SPHERE.F, process=False)
    np.testing.assert_array_equal(cg.geodesic_distance(tm, 3, method="dijkstra"), expected)
    mm = meshio.Mesh(SPHERE.V, [("vertex", np.arange(3)[:, None]), ("triangle", SPHERE.F)])
    np.testing.assert_array_equal(cg.GeodesicSolver(mm, "dijkstra").solve(3).distance, expected)
    with pytest.raises(MeshError, match="no 'triangle' cells"):
        cg.GeodesicSolver(meshio.Mesh(SPHERE.V, [("line", SPHERE.edges)]), "dijkstra")


def test_a_path_is_accepted(tmp_path):
    path = tmp_path / "sphere.ply"
    cg.save_distance(path, SPHERE, np.zeros(SPHERE.n_vertices))
    expected = cg.geodesic_distance(SPHERE, 1, method="dijkstra")
    np.testing.assert_allclose(cg.geodesic_distance(path, 1, method="dijkstra"), expected, rtol=1e-15)
    np.testing.assert_allclose(cg.geodesic_distance(str(path), 1, method="dijkstra"), expected, rtol=1e-15)


def test_unknown_object_is_a_type_error_naming_the_accepted_kinds():
    with pytest.raises(TypeError, match=r"a trimesh.Trimesh, an open3d.geometry.TriangleMesh or open3d.t.geometry."
                                        r"TriangleMesh, or a meshio.Mesh .*, got int$"):
        cg.geodesic_distance(3, 0)


def test_potpourri3d_argument_order():
    V, F = SPHERE.V, SPHERE.F
    for method in ("dijkstra", "qclp"):
        expected = cg.geodesic_distance(SPHERE, [0, 7], method=method)
        np.testing.assert_array_equal(cg.geodesic_distance(V, F, [0, 7], method=method), expected)
        np.testing.assert_array_equal(cg.geodesic_distance(V, F, [0, 7], method), expected)
        np.testing.assert_array_equal(cg.geodesic_distance(V.tolist(), F.tolist(), sources=[0, 7], method=method),
                                      expected)
    # the mesh form keeps working, positional and keyword
    np.testing.assert_array_equal(cg.geodesic_distance(SPHERE, 0, "dijkstra"),
                                  cg.geodesic_distance(SPHERE, sources=0, method="dijkstra"))
    with pytest.raises(TypeError, match="missing the source vertices"):
        cg.geodesic_distance(V, F)
    with pytest.raises(TypeError, match="multiple values for argument 'method'"):
        cg.geodesic_distance(V, F, 0, "qclp", method="qclp")


def test_vertices_are_read_only_and_copy_is_the_writable_form():
    with pytest.raises(ValueError, match="read-only"):
        SPHERE.V[0, 0] = 1.0
    # what open3d.utility.Vector3dVector needs (a writable float64 (n, 3) array): the documented mesh.V.copy()
    V = SPHERE.V.copy()
    assert V.flags.writeable and V.flags.c_contiguous and V.dtype == np.float64 and V.shape == (162, 3)
    assert "mesh.V.copy()" in cg.TriMesh.__doc__


# ----------------------------------------------------------------------------------------------------------------------
# Item 3: glTF/GLB/3MF (trimesh) and VTK/VTU (meshio) input
# ----------------------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("ext", ["glb", "gltf"])
def test_gltf_read_through_trimesh(tmp_path, ext):
    trimesh = pytest.importorskip("trimesh")
    path = tmp_path / f"sphere.{ext}"
    trimesh.Trimesh(SPHERE.V, SPHERE.F, process=False).export(path)
    mesh = cg.load_mesh(path)
    np.testing.assert_array_equal(mesh.F, SPHERE.F)
    np.testing.assert_allclose(mesh.V, SPHERE.V, atol=1e-7)  # glTF stores float32 positions


@pytest.mark.parametrize("ext", ["vtu", "vtk"])
def test_vtk_read_through_meshio(tmp_path, ext):
    meshio = pytest.importorskip("meshio")
    path = tmp_path / f"sphere.{ext}"
    meshio.Mesh(SPHERE.V, [("triangle", SPHERE.F)]).write(path)
    mesh = cg.load_mesh(path)
    np.testing.assert_array_equal(mesh.F, SPHERE.F)
    np.testing.assert_array_equal(mesh.V, SPHERE.V)


@pytest.mark.parametrize("ext, pkg", [("glb", "trimesh"), ("3mf", "trimesh"), ("vtu", "meshio"), ("vtk", "meshio")])
def test_missing_library_gives_the_install_hint(tmp_path, monkeypatch, ext, pkg):
    path = tmp_path / f"m.{ext}"
    path.write_bytes(b"not empty")
    monkeypatch.setitem(sys.modules, pkg, None)  # import fails as if not installed
    with pytest.raises(MeshFormatError, match=rf"needs the optional package {pkg}: pip install 'cvxgeodesic\[io\]'"):
        cg.load_mesh(path)


def test_3mf_without_networkx_names_it(tmp_path, monkeypatch):
    trimesh = pytest.importorskip("trimesh")
    path = tmp_path / "m.3mf"
    try:
        trimesh.Trimesh(SPHERE.V, SPHERE.F, process=False).export(path)
    except ImportError:  # trimesh's 3MF writer needs networkx and lxml as well
        path.write_bytes(b"PK not really a 3mf")
    monkeypatch.setitem(sys.modules, "networkx", None)
    with pytest.raises(MeshFormatError, match="networkx"):
        cg.load_mesh(path)


def test_unreadable_external_file_is_a_mesh_format_error(tmp_path):
    pytest.importorskip("meshio")
    path = tmp_path / "junk.vtu"
    path.write_text("<not xml")
    with pytest.raises(MeshFormatError, match="junk.vtu: meshio cannot read the file"):
        cg.load_mesh(path)


# ----------------------------------------------------------------------------------------------------------------------
# Item 4: files that other tools read
# ----------------------------------------------------------------------------------------------------------------------


def test_ply_keeps_georeferenced_coordinates_exactly(tmp_path):
    V = SPHERE.V * 10.0 + np.array([4_512_345.678, 5_401_234.321, 312.5])  # UTM-like easting/northing
    mesh = cg.TriMesh(V, SPHERE.F)
    assert np.abs(V.astype(np.float32) - V).max() > 0.1  # what float32 coordinates would lose
    path = cg.save_distance(tmp_path / "geo.ply", mesh, _field(mesh))
    m2, fields = load_distance_ply(path)
    np.testing.assert_array_equal(m2.V, V)
    np.testing.assert_array_equal(fields["distance"], _field(mesh))


def test_ply_field_read_by_trimesh_and_meshio(tmp_path):
    trimesh = pytest.importorskip("trimesh")
    meshio = pytest.importorskip("meshio")
    d = _field(SPHERE)
    path = cg.save_distance(tmp_path / "d.ply", SPHERE, d)
    tm = trimesh.load(path, process=False)
    np.testing.assert_array_equal(tm.vertices, SPHERE.V)
    # trimesh 5.2 keeps custom PLY vertex properties in the raw PLY data only (save_distance's docstring says so;
    # the .glb output below is the file trimesh reads into vertex_attributes)
    np.testing.assert_array_equal(np.asarray(tm.metadata["_ply_raw"]["vertex"]["data"]["distance"]), d)
    mm = meshio.read(path)
    np.testing.assert_array_equal(mm.point_data["distance"], d)
    np.testing.assert_array_equal(mm.points, SPHERE.V)


@pytest.mark.parametrize("ext", ["vtu", "vtk"])
def test_vtk_output_for_paraview(tmp_path, ext):
    meshio = pytest.importorskip("meshio")
    d = _field(SPHERE)
    path = cg.save_distance(tmp_path / f"d.{ext.upper()}", SPHERE, d, name="geodesic")
    mm = meshio.read(path)
    np.testing.assert_array_equal(mm.points, SPHERE.V)
    np.testing.assert_array_equal(mm.cells_dict["triangle"], SPHERE.F)
    np.testing.assert_array_equal(mm.point_data["geodesic"], d)
    assert sorted(p.name for p in tmp_path.iterdir()) == [f"d.{ext.upper()}"]  # no temporary file left


def _glb_json(path):
    import json
    import struct

    data = path.read_bytes()
    assert data[:4] == b"glTF"
    (length,) = struct.unpack("<I", data[12:16])
    # strict JSON: trimesh would write Infinity for an inf field, which JavaScript/Blender readers reject
    return json.loads(data[20:20 + length], parse_constant=lambda c: pytest.fail(f"non-JSON constant {c}"))


def test_glb_field_is_a_trimesh_vertex_attribute(tmp_path):
    trimesh = pytest.importorskip("trimesh")
    from cvxgeodesic.mesh.formats.gltf import GLB_NO_DISTANCE

    d = _field(SPHERE)
    path = cg.save_distance(tmp_path / "d.glb", SPHERE, d)
    header = _glb_json(path)
    assert "_DISTANCE" in header["meshes"][0]["primitives"][0]["attributes"]
    scene = trimesh.load(path, process=False)
    (tm,) = scene.geometry.values()
    np.testing.assert_allclose(tm.vertices, SPHERE.V, atol=1e-6)  # glTF positions are float32
    got = np.asarray(tm.vertex_attributes["_DISTANCE"], dtype=np.float64).ravel()
    finite = np.isfinite(d)
    np.testing.assert_allclose(got[finite], d[finite], rtol=1e-7)
    assert got[~finite].tolist() == [GLB_NO_DISTANCE]
    np.testing.assert_array_equal(tm.faces, SPHERE.F)


def test_glb_attribute_name_follows_the_field_name(tmp_path):
    pytest.importorskip("trimesh")
    path = cg.save_distance(tmp_path / "d.GLB", SPHERE, np.zeros(SPHERE.n_vertices), name="geo.dist-1")
    assert "_GEO_DIST_1" in _glb_json(path)["meshes"][0]["primitives"][0]["attributes"]


def test_glb_output_without_trimesh_names_the_extra(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "trimesh", None)
    with pytest.raises(ParameterError, match=r"writing \.glb files needs the optional package trimesh: "
                                             r"pip install 'cvxgeodesic\[io\]'"):
        cg.save_distance(tmp_path / "d.glb", SPHERE, _field(SPHERE))
    assert list(tmp_path.iterdir()) == []


def test_cli_writes_glb_in_file_order(tmp_path):
    trimesh = pytest.importorskip("trimesh")
    from cvxgeodesic.cli import main

    src = cg.save_distance(tmp_path / "in.ply", SPHERE, np.zeros(SPHERE.n_vertices))
    out = tmp_path / "out.glb"
    assert main(["distance", str(src), "-s", "3", "--method", "dijkstra", "-q", "-o", str(out)]) == 0
    (tm,) = trimesh.load(out, process=False).geometry.values()
    np.testing.assert_allclose(np.asarray(tm.vertex_attributes["_DISTANCE"]).ravel(),
                               cg.geodesic_distance(SPHERE, 3, method="dijkstra"), rtol=1e-7)


def test_vtk_output_without_meshio_names_the_extra(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "meshio", None)
    with pytest.raises(ParameterError, match=r"writing \.vtu files needs the optional package meshio: "
                                             r"pip install 'cvxgeodesic\[io\]'"):
        cg.save_distance(tmp_path / "d.vtu", SPHERE, _field(SPHERE))
    assert list(tmp_path.iterdir()) == []


def test_cli_writes_vtu(tmp_path, capsys):
    meshio = pytest.importorskip("meshio")
    from cvxgeodesic.cli import main

    src = cg.save_distance(tmp_path / "in.ply", SPHERE, np.zeros(SPHERE.n_vertices))
    out = tmp_path / "out.vtu"
    assert main(["distance", str(src), "-s", "0", "--method", "dijkstra", "-q", "-o", str(out)]) == 0
    np.testing.assert_array_equal(meshio.read(out).point_data["distance"],
                                  cg.geodesic_distance(SPHERE, 0, method="dijkstra"))


def test_open3d_reads_the_field_and_takes_a_copy_of_the_vertices(tmp_path):
    o3d = pytest.importorskip("open3d")
    d = _field(SPHERE)
    path = cg.save_distance(tmp_path / "d.ply", SPHERE, d)
    pc = o3d.t.io.read_point_cloud(str(path))  # the tensor PLY reader that keeps custom properties
    np.testing.assert_array_equal(pc.point["distance"].numpy().ravel(), d)
    np.testing.assert_array_equal(pc.point["positions"].numpy(), SPHERE.V)
    with pytest.raises(ValueError, match="not writeable"):
        o3d.utility.Vector3dVector(SPHERE.V)
    tm = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(SPHERE.V.copy()),
                                   o3d.utility.Vector3iVector(SPHERE.F.astype(np.int32)))
    np.testing.assert_array_equal(cg.geodesic_distance(tm, 0, method="dijkstra"),
                                  cg.geodesic_distance(SPHERE, 0, method="dijkstra"))
