"""Volumes through the public API, files, the command line and the viewer (issue 26)."""

from __future__ import annotations

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic.cli import main
from cvxgeodesic.errors import MeshError, ParameterError
from cvxgeodesic.mesh.convert import as_mesh
from cvxgeodesic.mesh.tet_generate import l_prism_distance, tet_l_prism
from cvxgeodesic.mesh.tetmesh import TetMesh
from test_viewer import _egl_works


@pytest.fixture(scope="module")
def prism():
    return tet_l_prism(3, jitter=0.2, seed=1)


def _msh(mesh, path):
    meshio = pytest.importorskip("meshio")
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        meshio.write(str(path), meshio.Mesh(mesh.V, [("tetra", mesh.T)]), file_format="gmsh22", binary=False)
    return path


# -- the API ----------------------------------------------------------------------------------------------------
def test_every_way_of_giving_a_volume(prism):
    d = cg.geodesic_distance(prism, 0, method="qclp")
    np.testing.assert_array_equal(cg.geodesic_distance(prism.V, prism.T, 0, method="qclp"), d)
    np.testing.assert_array_equal(cg.geodesic_distance((prism.V, prism.T), 0, method="qclp"), d)
    meshio = pytest.importorskip("meshio")
    mm = meshio.Mesh(prism.V, [("tetra", prism.T)])
    assert isinstance(as_mesh(mm), TetMesh)
    np.testing.assert_array_equal(cg.geodesic_distance(mm, 0, method="qclp"), d)
    D = cg.distance_matrix(prism, [0, 7, 0], method="dijkstra")
    assert D.shape == (3, prism.n_vertices) and D[1, 7] == 0 and np.array_equal(D[0], D[2])
    rows = cg.distance_matrix(prism, [cg.volume_point(prism, [0.5, 0.5, 0.5]), "boundary"], method="heat")
    assert rows.shape == (2, prism.n_vertices)
    with pytest.raises(MeshError, match="tetrahedral mesh is not a triangle surface"):
        cg.mesh.as_trimesh(prism)


def test_heat_and_dijkstra_through_the_solver(prism):
    c = int(np.argmin(np.linalg.norm(prism.V - [0.5, 1.5, 0.5], axis=1)))
    ex = l_prism_distance(prism.V[c], prism.V)
    for method in ("heat", "dijkstra"):
        res = cg.GeodesicSolver(prism, method).solve(c)
        assert res.info.method == method and res.info.status == "optimal"
        assert np.all(np.isfinite(res.distance)) and res.distance[c] == 0
    assert np.all(cg.geodesic_distance(prism, c, method="dijkstra") >= ex - 1e-9)  # an upper bound
    with pytest.raises(ParameterError, match="applies to the convex formulations"):
        cg.GeodesicSolver(prism, "heat", solver="clarabel")
    with pytest.raises(ParameterError, match="order=2"):
        cg.GeodesicSolver(prism, "heat", order=2)


# -- files ------------------------------------------------------------------------------------------------------
def test_load_mesh_returns_a_tetmesh_for_files_with_tetrahedra(prism, tmp_path):
    meshio = pytest.importorskip("meshio")
    for ext in (".msh", ".vtu", ".vtk", ".mesh"):
        path = tmp_path / f"part{ext}"
        if ext == ".msh":
            _msh(prism, path)
        else:
            meshio.write(str(path), meshio.Mesh(prism.V, [("tetra", prism.T)]))
        m = cg.load_mesh(path)
        assert isinstance(m, TetMesh) and m.n_tets == prism.n_tets, ext
    # a VTU without tetrahedra is still a surface
    surf = tmp_path / "surface.vtu"
    meshio.write(str(surf), meshio.Mesh(prism.V, [("triangle", prism.boundary_facets)]))
    with pytest.warns(cg.MeshRepairWarning, match="dropped 32 vertices in no face"):  # the interior ones
        assert isinstance(cg.load_mesh(surf), cg.TriMesh)
    # TetGen's pair
    (tmp_path / "t.node").write_text("5 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 1 1\n")
    (tmp_path / "t.ele").write_text("2 4 0\n1 1 2 3 4\n2 2 3 4 5\n")
    assert isinstance(cg.load_mesh(tmp_path / "t.ele"), TetMesh)
    with pytest.raises(MeshError, match="holds tetrahedra"):
        cg.mesh.as_trimesh(tmp_path / "t.node")


def test_save_distance_writes_point_data_for_paraview(prism, tmp_path):
    meshio = pytest.importorskip("meshio")
    d = cg.geodesic_distance(prism, 0, method="qclp")
    out = cg.save_distance(tmp_path / "d.vtu", prism, d)
    mm = meshio.read(out)
    np.testing.assert_allclose(mm.point_data["distance"], d)
    assert mm.cells_dict["tetra"].shape == (prism.n_tets, 4)
    with pytest.raises(ParameterError, match=r"written as \.npy, \.vtk or \.vtu"):
        cg.save_distance(tmp_path / "d.ply", prism, d)
    np.testing.assert_array_equal(np.load(cg.save_distance(tmp_path / "d.npy", prism, d)), d)


def test_file_numbering_is_kept(tmp_path):
    # a file with an unused point: the mesh drops it, the written field has it back (inf) in the file's place
    (tmp_path / "t.node").write_text("6 3 0 0\n1 0 0 0\n2 9 9 9\n3 1 0 0\n4 0 1 0\n5 0 0 1\n6 1 1 1\n")
    (tmp_path / "t.ele").write_text("2 4 0\n1 1 3 4 5\n2 3 4 5 6\n")
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = cg.load_mesh(tmp_path / "t.ele")
    d = cg.geodesic_distance(m, 0, method="dijkstra")
    out = np.load(cg.save_distance(tmp_path / "f.npy", m, d, file_order=True))
    assert out.shape == (6,) and np.isinf(out[1]) and out[0] == 0 and out[5] == pytest.approx(1 + 2**0.5)  # two edges


# -- command line ----------------------------------------------------------------------------------------------
def test_cli_distance_png_order2_and_errors(prism, tmp_path, capsys):
    path = _msh(prism, tmp_path / "part.msh")
    assert main(["distance", str(path), "-s", "0", "-o", str(tmp_path / "d.vtu"), "--png", str(tmp_path / "s.png"),
                 "-q"]) == 0
    assert (tmp_path / "s.png").stat().st_size > 10_000
    import meshio

    d = meshio.read(tmp_path / "d.vtu").point_data["distance"]
    np.testing.assert_allclose(d, cg.geodesic_distance(prism, 0, method="qclp"), atol=1e-12)
    assert main(["distance", str(path), "-s", "0", "--order", "2", "-o", str(tmp_path / "d2.npy"), "-q"]) == 0
    np.testing.assert_allclose(np.load(tmp_path / "d2.npy"), np.linalg.norm(prism.V - prism.V[0], axis=1),
                               atol=1e-6)  # the L seen from its corner: every point is in sight
    assert main(["distance", str(path), "--boundary", "-o", str(tmp_path / "b.npy"), "-q",
                 "--png", str(tmp_path / "b.png"), "--slice-normal", "1,0,0"]) == 0
    assert main(["distance", str(path), "--source-point", "0.5,0.5,0.5", "-o", str(tmp_path / "p.npy"), "-q"]) == 0
    capsys.readouterr()
    assert main(["distance", str(path), "-s", "0", "--method", "fmm", "-o", str(tmp_path / "x.vtu"), "-q"]) == 2
    assert "does not apply to tetrahedral meshes" in capsys.readouterr().err
    assert main(["distance", str(path), "-s", "0", "-o", str(tmp_path / "x.ply"), "-q"]) == 2
    assert ".npy, .vtk, .vtu" in capsys.readouterr().err  # the registry's formats that hold a volume's field
    assert main(["distance", str(path), "--source-point", "5,5,5", "-o", str(tmp_path / "x.vtu"), "-q"]) == 2
    assert "outside" in capsys.readouterr().err
    # a travel cost was ignored without a word inside a solid (the field solved without it): refused
    np.save(tmp_path / "c.npy", np.ones(prism.n_vertices))
    for option in (["--cost", str(tmp_path / "c.npy")], ["--cost-field", "speed"]):
        assert main(["distance", str(path), "-s", "0", *option, "-o", str(tmp_path / "x.npy"), "-q"]) == 2
        assert f"{option[0]}: a travel cost applies to triangle meshes" in capsys.readouterr().err
    assert not (tmp_path / "x.npy").exists()


def test_cli_compare_lists_heat_and_dijkstra(prism, tmp_path, capsys):
    path = _msh(prism, tmp_path / "part.msh")
    assert main(["compare", str(path), "-s", "5", "--methods", "qclp,heat,dijkstra", "--out", str(tmp_path / "c"),
                 "-q"]) == 0
    out = capsys.readouterr().out
    for name in ("qclp", "heat", "dijkstra", "errors against: qclp order 2"):
        assert name in out
    csv = (tmp_path / "c" / "compare.csv").read_text().splitlines()
    assert csv[0].startswith("method,order") and len(csv) == 5
    # the surface's pictures: each field and its error on the slice, the gradient histogram
    runs = ["dijkstra", "heat", "qclp", "qclp_order2"]
    assert sorted(p.name for p in (tmp_path / "c").glob("*.png")) == sorted(
        [f"field_{r}.png" for r in runs] + [f"error_{r}.png" for r in runs] + ["gradient_histogram.png"])


def test_cli_path_inside_a_volume(prism, tmp_path, capsys):
    """One path command for both dimensions: inside a solid it was refused (only the Python API drew it)."""
    path = _msh(prism, tmp_path / "part.msh")
    target = int(np.argmax(np.linalg.norm(prism.V - prism.V[0], axis=1)))
    assert main(["path", str(path), "-s", "0", "--to", str(target), "-o", str(tmp_path / "p.csv"),
                 "--png", str(tmp_path / "p.png"), "--slice-normal", "0,1,0"]) == 0
    assert "qclp: path of" in capsys.readouterr().err  # the volume's default method
    lines = (tmp_path / "p.csv").read_text().splitlines()
    assert lines[0] == "x,y,z,tet,b0,b1,b2,b3"
    P = np.array([[float(c) for c in line.split(",")[:3]] for line in lines[1:]])
    expected = cg.geodesic_path(prism, cg.GeodesicSolver(prism, "qclp").solve(0), target)
    np.testing.assert_array_equal(P, expected)  # the same solve and descent, written with repr()
    assert (tmp_path / "p.png").stat().st_size > 10_000
    assert main(["path", str(path), "-s", "0", "--to-point", "0.5,1.5,0.5", "-o", str(tmp_path / "q.npy"), "-q"]) == 0
    np.testing.assert_allclose(np.load(tmp_path / "q.npy")[0], [0.5, 1.5, 0.5], atol=1e-12)  # starts at the target


def test_cli_matrix_of_a_volume(prism, tmp_path):
    path = _msh(prism, tmp_path / "part.msh")
    assert main(["matrix", str(path), "-s", "7,0", "-o", str(tmp_path / "D.npy"), "-q"]) == 0  # qclp by default
    np.testing.assert_array_equal(np.load(tmp_path / "D.npy"), cg.distance_matrix(prism, [7, 0], method="qclp"))
    # the file's numbering: a point in no tetrahedron is back at its place, unreached (to_file_order on volumes)
    (tmp_path / "t.node").write_text("6 3 0 0\n1 0 0 0\n2 9 9 9\n3 1 0 0\n4 0 1 0\n5 0 0 1\n6 1 1 1\n")
    (tmp_path / "t.ele").write_text("2 4 0\n1 1 3 4 5\n2 3 4 5 6\n")
    assert main(["matrix", str(tmp_path / "t.ele"), "-s", "5", "--method", "dijkstra", "-o", str(tmp_path / "E.npy"),
                 "-q"]) == 0
    E = np.load(tmp_path / "E.npy")
    assert E.shape == (1, 6) and np.isinf(E[0, 1]) and E[0, 5] == 0 and E[0, 0] == pytest.approx(1 + 2**0.5)


# -- the viewer (off-screen) -----------------------------------------------------------------------------------
def test_view_draws_the_slice(prism, tmp_path):
    pytest.importorskip("polyscope", reason="polyscope not installed", exc_type=ImportError)
    if not _egl_works(tmp_path):
        pytest.skip("no off-screen OpenGL context (EGL/Mesa missing)")
    import matplotlib.image as mpimg

    path = _msh(prism, tmp_path / "part.msh")
    assert main(["view", str(path), "-s", "0", "--screenshot", str(tmp_path / "v.png"), "-q"]) == 0
    img = mpimg.imread(tmp_path / "v.png")[..., :3]
    drawn = np.abs(img - 1.0).sum(axis=-1) > 0.05
    assert drawn.mean() > 0.05
    colours = img[drawn]
    assert np.median(colours.max(axis=1) - colours.min(axis=1)) > 0.1  # the field in colour, not grey
    d = cg.show(prism, sources=0, screenshot=tmp_path / "w.png", window_size=(200, 150))
    np.testing.assert_array_equal(d, cg.geodesic_distance(prism, 0, method="qclp"))
