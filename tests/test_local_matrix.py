"""``distance_matrix(..., max_distance=r)``: sparse local rows, each solved on the patch around its source."""

import os

import numpy as np
import pytest
import scipy.sparse as sp

import cvxgeodesic as cg
from conftest import shared_mesh_path, sphere_file_with_a_loose_vertex
from cvxgeodesic import rows
from cvxgeodesic.cli import main
from cvxgeodesic.errors import ParameterError, SourceError
from cvxgeodesic.mesh.patch import ball_patch


@pytest.fixture(scope="module")
def spot():
    from pathlib import Path

    return cg.load_mesh(Path(cg.__file__).parent / "data" / "spot.obj")


def _dense(L, fill=np.inf):
    """A sparse local matrix as a dense one: missing entries (farther than r) as ``fill``, stored zeros kept."""
    out = np.full(L.shape, fill)
    coo = L.tocoo()
    out[coo.row, coo.col] = coo.data
    return out


def _errors_inside(mesh, src, r, method, **kw):
    """Mean error against the exact distance over the vertices within r, of the full and of the local rows.

    Both fields are clipped at r (a local row says only "farther than r" beyond it), so a vertex that the
    local row leaves out although it is within r counts with the error of r.
    """
    exact = cg.distance_matrix(mesh, src, method="exact", progress=False)
    full = cg.distance_matrix(mesh, src, method=method, progress=False, **kw)
    local = _dense(cg.distance_matrix(mesh, src, method=method, max_distance=r, progress=False, **kw))
    inside = exact <= r
    err = lambda d: float(np.abs(np.minimum(d, r) - exact)[inside].mean())  # noqa: E731
    return err(full), err(local)


@pytest.mark.parametrize("method", ["qclp", "qcqp-hessian"])
def test_local_rows_are_as_accurate_as_full_rows_inside_r(spot, method):
    pytest.importorskip("pygeodesic")
    r = 0.1 * spot.bbox_diagonal
    full, local = _errors_inside(spot, [0, 1000, 2000], r, method)
    # measured 0.85-0.87x (local rows are more accurate on spot): 1.05x is the bound
    assert local <= 1.05 * full, (local, full)


def test_local_matrix_shape_entries_and_repeated_rows(spot):
    r = 0.1 * spot.bbox_diagonal
    verts = [1000, 0, 1000]
    L = cg.distance_matrix(spot, verts, method="qclp", max_distance=r, progress=False)
    assert sp.issparse(L) and L.format == "csr" and L.shape == (3, spot.n_vertices)
    assert L.data.max() <= r and np.all(L.data >= 0)
    D = _dense(L)
    assert D[0, 1000] == 0 and D[1, 0] == 0  # the source's 0 is a stored entry
    np.testing.assert_array_equal(D[0], D[2])
    full = cg.distance_matrix(spot, [1000, 0], method="qclp", progress=False)
    # every vertex well inside r (the rows differ by ~1 % of r, measured) is in the local row
    assert np.all(np.isfinite(D[:2][full <= 0.9 * r]))


def test_the_patch_holds_the_ball_and_grows_when_the_field_reaches_its_cut(spot, monkeypatch):
    r = 0.1 * spot.bbox_diagonal
    patch = ball_patch(spot, 0, 1.5 * r)
    assert patch.mesh.n_faces < spot.n_faces / 5 and patch.vertices[patch.source] == 0 and patch.cut.size > 0
    assert np.all(np.isin(spot.F[np.isin(spot.F, patch.vertices).all(axis=1)].ravel(), patch.vertices))
    radii = []

    def spy(mesh, source, radius):
        radii.append(radius)
        return ball_patch(mesh, source, radius)

    ref = _dense(cg.distance_matrix(spot, [0], method="qclp", max_distance=r, progress=False))
    monkeypatch.setattr(rows, "ball_patch", spy)
    monkeypatch.setattr(rows, "PATCH_FACTOR", 0.5)  # a patch smaller than the ball: the cut is within r
    grown = _dense(cg.distance_matrix(spot, [0], method="qclp", max_distance=r, progress=False))
    assert len(radii) >= 2 and radii[1] == pytest.approx(radii[0] * rows.PATCH_GROWTH)
    assert np.all(np.isfinite(grown[ref <= 0.9 * r]))  # the grown patch holds the ball again


def test_the_patch_gets_the_whole_meshs_smoothness(spot, monkeypatch):
    """λ is the whole mesh's, scaled by the area ratio (the stretch term is a mean over the surface solved)."""
    seen = []

    def factory(mesh, **options):
        seen.append((mesh, options))
        return cg.GeodesicSolver(mesh, **options)

    local = rows.LocalRows(spot, max_distance=0.1 * spot.bbox_diagonal, factory=factory, method="qcqp-hessian", m=3.0)
    assert local.lam == pytest.approx(cg.GeodesicSolver(spot, "dijkstra", m=3.0).lam or
                                      cg.smoothness_weight(spot, 3.0, "area", "hessian"), rel=1e-12)
    local.solve(0)
    patch, options = seen[-1]
    assert options["lam"] == pytest.approx(local.lam * spot.face_areas.sum() / patch.face_areas.sum(), rel=1e-12)


def test_order2_and_a_baseline_on_patches(spot):
    r = 0.1 * spot.bbox_diagonal
    L = cg.distance_matrix(spot, [7], method="dijkstra", max_distance=r, progress=False)
    full = cg.distance_matrix(spot, [7], method="dijkstra", progress=False)
    # Dijkstra inside the patch is Dijkstra on the mesh for every vertex within r (paths longer than r leave it)
    np.testing.assert_allclose(_dense(L)[full <= r], full[full <= r], rtol=1e-12)
    L2 = cg.distance_matrix(spot, [7], order=2, max_distance=r, progress=False)
    assert L2.nnz > 10 and L2.data.max() <= r


def test_local_rows_resume_from_a_checkpoint(spot, tmp_path, monkeypatch):
    r = 0.1 * spot.bbox_diagonal
    verts = [0, 500, 1000, 1500]
    ref = cg.distance_matrix(spot, verts, method="qclp", max_distance=r, progress=False)
    calls = {"n": 0}
    solve = rows.LocalRows.solve

    def stopping(self, v):
        calls["n"] += 1
        if calls["n"] == 3:
            raise KeyboardInterrupt
        return solve(self, v)

    monkeypatch.setattr(rows.LocalRows, "solve", stopping)
    path = tmp_path / "local.npz"
    with pytest.raises(KeyboardInterrupt):
        cg.distance_matrix(spot, verts, method="qclp", max_distance=r, progress=False, checkpoint=path)
    assert rows.checkpoint_rows(path) == (2, 4)
    calls["n"] = 10
    L = cg.distance_matrix(spot, verts, method="qclp", max_distance=r, progress=False, checkpoint=path)
    assert calls["n"] == 12  # two rows left
    assert (L != ref).nnz == 0 and L.nnz == ref.nnz and np.all(_dense(L)[np.arange(4), verts] == 0)
    with pytest.raises(ParameterError, match=r"max_distance: .* there, .* here"):
        cg.distance_matrix(spot, verts, method="qclp", max_distance=2 * r, checkpoint=path)


@pytest.mark.parametrize("kwargs, error, match", [
    ({"max_distance": 0}, ParameterError, "max_distance"),
    ({"max_distance": -1.0}, ParameterError, "max_distance"),
    ({"max_distance": float("inf")}, ParameterError, "max_distance"),
    ({"max_distance": float("nan")}, ParameterError, "max_distance"),
    ({"max_distance": "far"}, ParameterError, "max_distance"),
    ({"max_distance": 0.5, "multires": 200}, ParameterError, "max_distance does not take multires="),
    ({"max_distance": 0.5, "cost": np.ones(162)}, ParameterError, "max_distance does not take cost="),
])
def test_bad_local_arguments(kwargs, error, match):
    with pytest.raises(error, match=match):
        cg.distance_matrix(cg.icosphere(2), [0, 1], **kwargs)


def test_local_rows_are_cells_of_the_capability_table():
    # a volume, a metric, a word: refused by the table's rules of local rows, with their reasons
    with pytest.raises(ParameterError, match="^max_distance is not available for method 'qclp' on tetrahedral meshes: "
                                             "local rows are solved on patches of a triangle mesh"):
        cg.distance_matrix(cg.tet_box(2), [0], "qclp", max_distance=0.5)
    with pytest.raises(ParameterError, match="max_distance does not take cost= or metric="):
        cg.distance_matrix(cg.icosphere(1), [0], "qclp", max_distance=0.5, metric=np.eye(3))
    with pytest.raises(SourceError, match="^max_distance cannot take .*boundary"):
        cg.distance_matrix(cg.icosphere(1), ["boundary"], "qclp", max_distance=0.5)


def test_local_rows_take_vertices_only():
    with pytest.raises(SourceError, match=r"^max_distance cannot take point, curve or boundary sources \(local rows "
                                          r"take source vertices"):
        cg.distance_matrix(cg.icosphere(2), [cg.SurfacePoint(0, [0.2, 0.3, 0.5])], max_distance=0.5)


def test_cli_matrix_max_distance(tmp_path, capsys):
    mesh, path = sphere_file_with_a_loose_vertex(tmp_path)
    out = tmp_path / "L.npz"
    assert main(["matrix", str(path), "-s", "6,1", "--method", "qclp", "--max-distance", "0.5", "-o", str(out)]) == 0
    assert "distances up to 0.5" in capsys.readouterr().err
    L = sp.load_npz(out)
    expected = cg.distance_matrix(mesh, [5, 0], method="qclp", max_distance=0.5, progress=False)
    assert L.shape == (2, 163) and L[:, 0].nnz == 0  # the loose file vertex has no entry
    np.testing.assert_array_equal(_dense(L)[:, 1:], _dense(expected))
    assert _dense(L)[0, 6] == 0 and not (tmp_path / "L.npz.partial.npz").exists()
    assert main(["matrix", str(path), "-s", "1", "--max-distance", "0.5", "-o", str(tmp_path / "L.npy")]) == 2
    assert "--max-distance writes a sparse matrix (scipy.sparse.save_npz): give -o FILE.npz" in capsys.readouterr().err
    assert main(["matrix", str(path), "-s", "1", "-o", str(tmp_path / "D.npz")]) == 2
    assert "a full matrix is written as .npy" in capsys.readouterr().err
    assert main(["matrix", str(path), "-s", "1", "--max-distance", "0", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["cvxgeodesic: error: --max-distance must be a finite number > 0, got 0.0"], err


def test_sparse_file_order_keeps_zeros_and_welded_duplicates():
    mesh = cg.TriMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], file_index=[2, 0, -1, 1, 0])
    D = sp.csr_matrix((np.array([0.0, 1.0, 0.5]), np.array([0, 1, 2]), np.array([0, 2, 3])), shape=(2, 3))
    out = rows.sparse_to_file_order(mesh, D)
    assert out.shape == (2, 5) and out.nnz == 4  # file vertices 1 and 4 share mesh vertex 0, whose 0 is stored
    np.testing.assert_array_equal(_dense(out), [[np.inf, 0, np.inf, 1, 0], [0.5, np.inf, np.inf, np.inf, np.inf]])


@pytest.mark.shared
def test_local_rows_on_a_scan_are_as_accurate_as_full_rows():
    pytest.importorskip("pygeodesic")
    mesh = cg.load_mesh(shared_mesh_path("kitten.obj"))
    r = 0.1 * mesh.bbox_diagonal
    full, local = _errors_inside(mesh, [6016, 4828, 8034], r, "qclp")
    # measured 0.81-0.92x per row (3 rows, kitten, c = 1.5): 1.05x is the bound
    assert local <= 1.05 * full, (local, full)


@pytest.mark.parametrize("max_distance", [None, 0.5])
def test_the_rows_limit_the_thread_pools_once(max_distance, monkeypatch):
    """threadpoolctl's library discovery (~10 ms) once per matrix, not twice per row (16 % of a local row)."""
    import traceback

    from cvxgeodesic import _threads

    calls = []
    real = _threads.pool_limits
    def counting(*args, **kwargs):
        calls.append(traceback.extract_stack()[-2].name)
        return real(*args, **kwargs)

    monkeypatch.setattr(_threads, "pool_limits", counting)
    cg.distance_matrix(cg.icosphere(3), [0, 5, 9], method="qclp", max_distance=max_distance, progress=False)
    assert calls.count("thread_limit") == 1, calls  # the IPM's own limit is another (solve)


def test_local_rows_on_a_local_cluster_with_a_checkpoint(spot, tmp_path):
    pytest.importorskip("distributed")
    r = 0.1 * spot.bbox_diagonal
    verts = [0, 500, 1000]
    ref = cg.distance_matrix(spot, verts, method="qclp", max_distance=r, progress=False)
    path = tmp_path / "c.npz"
    L = cg.distance_matrix(spot, verts, method="qclp", max_distance=r, progress=False, workers=2, checkpoint=path)
    assert sp.issparse(L) and L.nnz == ref.nnz and rows.checkpoint_rows(path) == (3, 3)
    # the same solves in other processes: equal to round-off (thread counts may change the last digits)
    np.testing.assert_allclose(_dense(L), _dense(ref), rtol=0, atol=1e-9 * spot.bbox_diagonal)


def test_local_rows_default_to_the_looser_tolerance_and_full_rows_do_not(spot, monkeypatch):
    """tol=None: 1e-8 for full rows (the solve geodesic_distance makes), api.LOCAL_ROW_TOL for local rows; an
    explicit tol is used for both."""
    import cvxgeodesic.api as api

    seen = []
    real_init = api.GeodesicSolver.__init__

    def spy(self, mesh, *args, **kwargs):  # on the base class: the patches' solver (api._PatchSolver) too
        seen.append(kwargs.get("tol"))
        real_init(self, mesh, *args, **kwargs)

    monkeypatch.setattr(api.GeodesicSolver, "__init__", spy)
    r = 0.1 * spot.bbox_diagonal
    for kwargs, want in (({}, api.DEFAULT_TOL), ({"max_distance": r}, api.LOCAL_ROW_TOL),
                         ({"max_distance": r, "tol": 1e-7}, 1e-7)):
        seen.clear()
        cg.distance_matrix(spot, [0], method="qclp", progress=False, **kwargs)
        assert seen and set(seen) == {want}, kwargs  # every solver of the call (local rows: one per patch)
    assert api.LOCAL_ROW_TOL == 1e-5 and api.DEFAULT_TOL == 1e-8


def test_a_small_patch_is_not_refused_for_the_whole_meshs_smoothness():
    """λ on a patch is the whole mesh's scaled by the area ratio: past the weight of m = 1e6 *of the patch* for
    patches under ~1e-4 m^(2/3) of the surface, which the range check of lam= refused (found in review: m = 100,
    an 80-face patch). The range is checked once, on the whole mesh."""
    sphere = cg.icosphere(4)
    L = cg.distance_matrix(sphere, [0], method="qcqp-hessian", m=100, max_distance=0.05, progress=False)
    assert L.nnz > 1 and L.data.max() <= 0.05
    with pytest.raises(cg.ParameterError, match=r"lam = 1e9 is outside the supported range"):
        cg.distance_matrix(sphere, [0], method="qcqp-hessian", lam=1e9, max_distance=0.05, progress=False)


def test_a_read_only_checkpoint_is_refused_before_any_row(spot, tmp_path):
    """Found in review: it failed at its first periodic write, and the save error hid the row's own error."""
    path = tmp_path / "rows.npz"
    cg.distance_matrix(spot, [0, 5], method="dijkstra", progress=False, checkpoint=path)
    os.chmod(path, 0o444)
    with pytest.raises(cg.ParameterError, match=r"rows.npz is read-only .*make it writable \(chmod u\+w\) first"):
        cg.distance_matrix(spot, [0, 5, 9], method="dijkstra", progress=False, checkpoint=path)


def test_a_failing_save_does_not_hide_the_rows_error(spot, tmp_path, monkeypatch):
    def fail(*args, **kwargs):
        raise OSError(28, "No space left on device")

    real_solve, calls = cg.GeodesicSolver.solve, []

    def second_row_fails(self, source, *args, **kwargs):
        calls.append(source)
        if len(calls) == 2:  # one finished row to save when the second fails
            raise RuntimeError("row failed")
        return real_solve(self, source, *args, **kwargs)

    monkeypatch.setattr(rows, "atomic_write", fail)
    monkeypatch.setattr(cg.GeodesicSolver, "solve", second_row_fails)
    with pytest.raises(RuntimeError, match="row failed") as info:
        cg.distance_matrix(spot, [0, 5], method="dijkstra", progress=False, checkpoint=tmp_path / "c.npz")
    assert any("could not be written" in note for note in getattr(info.value, "__notes__", []))
