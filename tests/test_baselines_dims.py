"""The baselines' one interface on both dimensions: the guards of BaselineSolver.solve hold on a surface and in a
volume alike (a library failure, a field of the wrong length, non-finite values where a source is reachable,
unreachable components), and the baseline strategy reports the same fields of info."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

import cvxgeodesic as cg
from cvxgeodesic.baselines import BASELINES, DijkstraBaseline, HeatBaseline, graph_distance
from cvxgeodesic.errors import SolverError
from cvxgeodesic.mesh.tet_generate import tet_box
from cvxgeodesic.mesh.tetmesh import TetMesh
from cvxgeodesic.mesh.trimesh import TriMesh

MESHES = {2: cg.icosphere(2), 3: tet_box(2)}
DIMS = pytest.mark.parametrize("dim", [2, 3])


def _two_copies(mesh):
    """The mesh and a translated copy of it, as one mesh of two components."""
    V = np.vstack([mesh.V, mesh.V + 5.0])
    cells = mesh.F if isinstance(mesh, TriMesh) else mesh.T
    C = np.vstack([cells, cells + mesh.n_vertices])
    return TriMesh(V, C) if isinstance(mesh, TriMesh) else TetMesh(V, C)


@DIMS
@pytest.mark.parametrize("where, what", [("_setup", "setup failed on"), ("_solve", "failed on")])
def test_a_library_failure_is_a_solver_error_naming_the_baseline_and_the_mesh(monkeypatch, dim, where, what):
    def boom(self, *args):
        raise ValueError("boom")

    for cls in (DijkstraBaseline, *DijkstraBaseline.variants):  # the volume's variant has its own _solve
        monkeypatch.setattr(cls, where, boom)
    with pytest.raises(SolverError, match=rf"^baseline 'dijkstra': {what} {MESHES[dim].name}: ValueError: boom "
                                          r"\(solver=scipy.sparse.csgraph.dijkstra, status=error\)$"):
        DijkstraBaseline(MESHES[dim]).solve(0)


@DIMS
def test_non_finite_values_where_a_source_is_reachable_are_a_solver_error(monkeypatch, dim):
    n = MESHES[dim].n_vertices
    d = np.ones(n)
    d[3] = np.nan
    for cls in (DijkstraBaseline, *DijkstraBaseline.variants):
        monkeypatch.setattr(cls, "_solve", lambda self, src: (d.copy(), {}))
    with pytest.raises(SolverError, match=r"returned 1 non-finite distances at vertices connected to a source "
                                          r"\(first: vertex 3\)"):
        DijkstraBaseline(MESHES[dim]).solve(0)


@DIMS
def test_a_field_of_the_wrong_length_is_a_solver_error(monkeypatch, dim):
    for cls in (DijkstraBaseline, *DijkstraBaseline.variants):
        monkeypatch.setattr(cls, "_solve", lambda self, src: (np.zeros(5), {}))
    with pytest.raises(SolverError, match=rf"returned 5 values for {MESHES[dim].n_vertices} vertices"):
        DijkstraBaseline(MESHES[dim]).solve(0)


@DIMS
@pytest.mark.parametrize("name", ["dijkstra", "heat"])
def test_unreachable_components_are_inf_whatever_the_library_returns(monkeypatch, dim, name):
    mesh = _two_copies(MESHES[dim])
    n = MESHES[dim].n_vertices
    d, _ = BASELINES[name](mesh).solve(0)
    assert np.isfinite(d[:n]).all() and np.isinf(d[n:]).all()
    # a library that leaves finite garbage on the unreached copy (potpourri3d does, without the per-component runs)
    cls = BASELINES[name]
    solve = cls._solve
    monkeypatch.setattr(cls, "_solve", lambda self, src: (np.where(np.isinf(solve(self, src)[0]), 7.0,
                                                                   solve(self, src)[0]), {}))
    d, _ = cls(mesh).solve(0)
    assert np.isinf(d[n:]).all()


@DIMS
@pytest.mark.parametrize("name", ["dijkstra", "heat"])
def test_the_info_has_the_same_fields_in_both_dimensions(dim, name):
    d, info = BASELINES[name](MESHES[dim]).solve([0, 5])
    assert {"method", "solver", "status", "iterations", "solve_time", "setup_time", "n_sources",
            "notes"} <= set(info)
    assert info["n_sources"] == 2 and info["status"] == "optimal" and isinstance(info["notes"], list)
    res = cg.GeodesicSolver(MESHES[dim], name).solve([0, 5])
    np.testing.assert_array_equal(res.distance, d)  # the strategy adds nothing to the field
    assert res.info.method == name and res.info.solver == info["solver"]
    # the fields SolveInfo holds itself are not repeated in extra
    assert not {"method", "solver", "status", "iterations", "setup_time", "notes"} & set(res.info.extra)


def test_the_heat_method_names_its_implementation_per_dimension():
    assert HeatBaseline(MESHES[2]).library == "potpourri3d.MeshHeatMethodDistanceSolver"
    assert HeatBaseline(MESHES[3]).library == "cvxgeodesic heat method (P1 tetrahedra)"
    assert HeatBaseline((MESHES[3].V, MESHES[3].T)).dim == 3  # a (V, T) pair is a volume


def test_a_baseline_class_builds_its_variant_for_the_mesh_cells():
    """HeatBaseline and DijkstraBaseline on tetrahedra are their volume variants (chosen by mesh.reference)."""
    from cvxgeodesic.baselines import VolumeDijkstraBaseline, VolumeHeatBaseline

    assert type(HeatBaseline(MESHES[2])) is HeatBaseline and type(DijkstraBaseline(MESHES[2])) is DijkstraBaseline
    assert type(HeatBaseline(MESHES[3])) is VolumeHeatBaseline
    assert type(DijkstraBaseline((MESHES[3].V, MESHES[3].T))) is VolumeDijkstraBaseline
    assert type(BASELINES["heat"](MESHES[3], t_coef=2.0)) is VolumeHeatBaseline


def test_graph_distance_starts_at_zero_offsets_and_joins_the_others_through_one_node():
    # a path 0 - 1 - 2 - 3 with unit edges
    G = sp.csr_matrix(sp.diags([1.0, 1.0, 1.0], 1, shape=(4, 4)))
    G = G + G.T
    np.testing.assert_array_equal(graph_distance(G, np.array([0])), [0, 1, 2, 3])
    # a source between 2 and 3 (offsets 0.25 and 0.75), and one exactly on vertex 1 (offset 0: a start, d = 0 exactly)
    d = graph_distance(G, np.zeros(0, dtype=np.int64), np.array([2, 3, 1]), np.array([0.25, 0.75, 0.0]))
    np.testing.assert_array_equal(d, [1.0, 0.0, 0.25, 0.75])


@pytest.mark.parametrize("name", ["dijkstra", "fmm", "exact"])
def test_a_surface_baseline_takes_points_curves_and_the_boundary_itself(name):
    # one interface: solve() takes the dimension's sources, as inside a volume; the same field as the solver's
    plane = cg.grid_plane(6)
    point = cg.SurfacePoint(7, [0.2, 0.3, 0.5])
    curve = cg.SurfaceCurve([point, cg.SurfacePoint(30, [0.6, 0.2, 0.2])])
    baseline = BASELINES[name](plane)
    for sources in (point, [point, 3], curve, "boundary"):
        d, info = baseline.solve(sources)
        np.testing.assert_array_equal(d, cg.GeodesicSolver(plane, name).solve(sources).distance)
        assert info["method"] == name and info["status"] == "optimal" and "sources" in info
    # the class's own check (the API edge gives the capability table's reason, test_capabilities)
    with pytest.raises(cg.SourceError, match="^baseline 'heat' takes vertex sources and 'boundary' only"):
        HeatBaseline(plane).solve(point)
    assert HeatBaseline(plane).solve("boundary")[1]["sources"] == "boundary vertices"
