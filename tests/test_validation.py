"""cvxgeodesic.validation: one vocabulary of checks, and the entry points that use it."""

from __future__ import annotations

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic.errors import MeshError, ParameterError, SourceError
from cvxgeodesic.validation import (
    as_points,
    as_vertex_field,
    check_choice,
    check_count,
    check_number,
    check_output_path,
    check_type,
    validate_sources,
    vertex_indices,
    vertex_mask,
)


@pytest.mark.parametrize(("kwargs", "good", "bad", "text"), [
    ({"low": 0, "high": 1, "low_open": True, "high_open": True}, 0.5, [0, 1, 1.5, np.nan], r"a number in \(0, 1\)"),
    ({"low": 10, "high": 2000}, 10, [9.99, 2001, np.inf], r"a number in \[10, 2000\]"),
    ({"low": 0}, 0, [-1e-300, np.inf, np.nan], "a finite number >= 0"),
    ({"low": 0, "low_open": True}, 1e-30, [0.0, -1], "a finite number > 0"),
])
def test_check_number(kwargs, good, bad, text):
    assert check_number(good, "x", **kwargs) == float(good)
    assert isinstance(check_number(np.float32(good), "x", **kwargs), float)
    for value in [*bad, True, "1", None, [1]]:
        with pytest.raises(ParameterError, match=rf"^x must be {text}, got "):
            check_number(value, "x", **kwargs)


def test_check_count_and_choice():
    assert check_count(np.int64(3), "k") == 3 and check_count(0, "k", minimum=0) == 0
    for value in (0, -1, 1.0, True, "2", None):
        with pytest.raises(ParameterError, match="^k must be a positive integer, got"):
            check_count(value, "k")
    with pytest.raises(ParameterError, match="^k must be an integer >= 3 or None, got 2"):
        check_count(2, "k", minimum=3, or_none=True)
    assert check_choice("IPM", "solver", ("auto", "ipm")) == "ipm"
    with pytest.raises(ParameterError, match="^unknown solver 'IPM'; choose one of auto, ipm$"):
        check_choice("IPM", "solver", ("auto", "ipm"), lower=False)
    with pytest.raises(ParameterError, match="unknown solver 3"):
        check_choice(3, "solver", ("auto",))
    with pytest.raises(TypeError, match="mesh must be a TriMesh, got list"):
        check_type([], "mesh", cg.TriMesh, "a TriMesh")


def test_vertex_arrays_name_the_parameter_and_the_index():
    assert vertex_indices(3, "s", 5).tolist() == [3]
    assert vertex_indices([1.0, 1.0], "s", 5).tolist() == [1, 1]  # repeats are fine outside sources
    with pytest.raises(ParameterError, match=r"^s\[2\] = 7 is outside \[0, 5\)"):
        vertex_indices([0, 4, 7, -1], "s", 5)
    with pytest.raises(ParameterError, match=r"^s\[0\] = -1 is outside"):
        vertex_indices([-1], "s", 5)
    with pytest.raises(ParameterError, match="s must hold integer vertex indices"):
        vertex_indices([0.5], "s", 5)
    with pytest.raises(ParameterError, match="s must hold integer vertex indices"):
        vertex_indices(np.array([True]), "s", 5)
    with pytest.raises(ParameterError, match="1-D"):
        vertex_indices([[0, 1]], "s", 5)
    with pytest.raises(ParameterError, match=r"m must have shape \(3,\)"):
        vertex_mask(np.ones(4, bool), "m", 3)
    with pytest.raises(ParameterError, match="boolean vertex mask"):
        vertex_mask(np.ones(3), "m", 3)
    d = as_vertex_field([0.0, np.inf, 1.0], "d", 3, nan_ok=False)
    assert d.dtype == np.float64
    with pytest.raises(ParameterError, match=r"^d has NaN values \(first at vertex 1\)"):
        as_vertex_field([0.0, np.nan, np.nan], "d", 3, nan_ok=False)
    with pytest.raises(ParameterError, match=r"d must have shape \(3,\)"):
        as_vertex_field(np.zeros((3, 1)), "d", 3)


def test_points_name_the_first_bad_row():
    assert as_points([1, 2, 3], "x").shape == (3,) and as_points(np.zeros((4, 3)), "x").shape == (4, 3)
    with pytest.raises(ParameterError, match=r"x\[2\] = \[0.0, nan, 0.0\]"):
        as_points([[0, 0, 0], [1, 1, 1], [0, np.nan, 0]], "x")
    with pytest.raises(ParameterError, match=r"got shape \(2, 2\)"):
        as_points(np.zeros((2, 2)), "x")
    with pytest.raises(SourceError, match=r"xyz must be .* finite positions: xyz = \[0.5, inf, 0.0\]"):
        cg.surface_point(cg.grid_plane(3), [0.5, np.inf, 0.0])


def test_rows_of_a_data_set_name_the_set_and_the_row():
    # a point cloud's points (mesh/pointcloud.py): the message names the cloud (its file) and the point
    with pytest.raises(MeshError, match=r"^scan.xyz: point 2 has a non-finite coordinate \(\[0.0, nan, 0.0\]\); "
                                        "2 such points in all$"):
        as_points([[0, 0, 0], [1, 1, 1], [0, np.nan, 0], [np.inf, 0, 0]], "scan.xyz", error=MeshError, row="point")
    with pytest.raises(MeshError, match=r"^c: normals must be an \(n, 3\) array, got shape \(3,\)$"):
        as_points([0.0, 0.0, 1.0], "c", error=MeshError, row="normal")  # one position is not rows
    with pytest.raises(MeshError, match=r"^c: points must be an \(n, 3\) array of numbers"):
        as_points([["a", 0, 0]], "c", error=MeshError, row="point")


def test_validate_sources():
    assert validate_sources(np.uint8(2), 3).tolist() == [2]
    for value, text in [([], "empty"), ([0, 0], "vertex 0 is given more than once"), (3, "source index 3 is out"),
                        ([[0], [1, 2]], "1-D sequence"), (True, "vertex indices"), ([2**70], "out of range"),
                        ([0.5], "integer vertex indices")]:
        with pytest.raises(SourceError, match=text):
            validate_sources(value, 3)
    # distance_matrix's rows: its parameter's name in the messages, a vertex asked for twice accepted
    assert validate_sources([2, 0, 2.0], 3, name="vertices", repeats=True).tolist() == [2, 0, 2]
    for value, text in [([], "vertices is empty"), (True, "vertices must be vertex indices"),
                        ([[0], [1, 2]], "vertices must be an int or a 1-D sequence"),
                        ([0.5], "vertices must be integer"), ([1, 3], "source index 3 is out of range")]:
        with pytest.raises(SourceError, match=text):
            validate_sources(value, 3, name="vertices", repeats=True)


def test_check_output_path(tmp_path):
    assert check_output_path(tmp_path / "a.PNG", (".png",)) == tmp_path / "a.PNG"
    assert list(tmp_path.iterdir()) == []  # the probe file is removed
    with pytest.raises(ParameterError, match="unsupported output file extension '.jpg'"):
        check_output_path(tmp_path / "a.jpg", (".png",))
    with pytest.raises(ParameterError, match="does not exist"):
        check_output_path(tmp_path / "no" / "a.png", (".png",))
    (tmp_path / "d.png").mkdir()
    with pytest.raises(ParameterError, match="it is a directory"):
        check_output_path(tmp_path / "d.png", (".png",))
    with pytest.raises(TypeError, match="path must be a str or os.PathLike"):
        check_output_path(3, (".png",))


# ---------------------------------------------------------------- entry points: the same checks everywhere
def test_entry_points_share_the_vocabulary(tmp_path):
    mesh = cg.icosphere(1)
    d = cg.geodesic_distance(mesh, 0, method="dijkstra")
    from cvxgeodesic.evaluation import error_stats, gradient_norm_stats
    from cvxgeodesic.plotting import plot_field

    with pytest.raises(ParameterError, match=r"^sources\[1\] = 99 is outside"):
        error_stats(d, d, sources=[0, 99])
    with pytest.raises(ParameterError, match=r"^d must have shape \(42,\)"):
        gradient_norm_stats(mesh, d[:-1])
    with pytest.raises(ParameterError, match=r"^sources\[0\] = 42 is outside"):
        plot_field(mesh, d, tmp_path / "a.png", sources=[42])
    with pytest.raises(ParameterError, match=r"^dpi must be a number in \[10, 2000\], got 5"):
        plot_field(mesh, d, tmp_path / "a.png", dpi=5)
    with pytest.raises(ParameterError, match="does not exist"):
        plot_field(mesh, d, tmp_path / "no" / "a.png")
    bad = d.copy()
    bad[5] = np.nan
    with pytest.raises(ParameterError, match=r"distance has NaN values \(first at vertex 5\)"):
        cg.geodesic_path(mesh, bad, 3)
    with pytest.raises(ParameterError, match="^t_coef must be a finite number > 0, got 0"):
        from cvxgeodesic.baselines import HeatBaseline

        HeatBaseline(mesh, t_coef=0)
    with pytest.raises(SourceError, match="source index 42 is out of range: the mesh has 42 vertices"):
        from cvxgeodesic.baselines import DijkstraBaseline

        DijkstraBaseline(mesh).solve([0, 42])
    with pytest.raises(ParameterError, match="^subdivisions must be an integer >= 0, got -1"):
        cg.icosphere(-1)
    with pytest.raises(ParameterError, match="^unknown normalization 'cotan'; choose one of area, paper"):
        cg.GeodesicSolver(mesh, normalization="cotan")
    with pytest.raises(ParameterError, match=r"^tol must be a number in \(0, 1\), got 0"):
        cg.GeodesicSolver(mesh, tol=0)
    with pytest.raises(ParameterError, match="^max_iter must be a positive integer, got 0"):
        cg.GeodesicSolver(mesh, max_iter=0)
    with pytest.raises(ParameterError, match="^threads must be a positive integer or None, got 0"):
        cg.GeodesicSolver(mesh, threads=0)


def test_batch_uses_the_same_checks(tmp_path):
    from cvxgeodesic.batch import run_batch

    mesh_path = tmp_path / "m.obj"
    mesh_path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    for kwargs, text in [({"method": "nope"}, "^unknown method 'nope'; choose one of"),
                         ({"solver": "IPM"}, "^unknown solver 'IPM'"),
                         ({"m": True}, "^m must be a finite number >= 0, got True"),
                         ({"output_format": "obj"}, "^unknown output_format 'obj'; choose one of"),
                         ({"n_workers": 0}, "^n_workers must be a positive integer, got 0"),
                         ({"method": "heat", "multires": 500}, "^multires is not available for method 'heat'")]:
        with pytest.raises(ParameterError, match=text):
            run_batch([mesh_path], 0, tmp_path / "out", **kwargs)


# ---------------------------------------------------------------- both element orders: one verdict
_INVALID = [
    ("sources []", {}, []),
    ("sources repeated", {}, [0, 0]),
    ("sources out of range", {}, 99),
    ("sources bool", {}, True),
    ("sources fraction", {}, [0.5]),
    ("sources string", {}, "nope"),
    ("sources ragged", {}, [[0], [1, 2]]),
    ("sources face tuple", {}, (3, [0.2, 0.3, 0.5])),
    ("point face out of range", {}, "point-face"),
    ("m negative", {"m": -5}, 0),
    ("m nan", {"m": np.nan}, 0),
    ("m bool", {"m": True}, 0),
    ("lam negative", {"lam": -1.0}, 0),
    ("tol", {"tol": 0}, 0),
    ("max_iter", {"max_iter": 0}, 0),
    ("threads", {"threads": 0}, 0),
    ("normalization", {"normalization": "cotan"}, 0),
    ("solver", {"solver": "IPM!"}, 0),
]


def _verdict(order: int, kwargs: dict, sources):
    mesh = cg.icosphere(1)
    if sources == "point-face":
        sources = [cg.SurfacePoint(mesh.n_faces, [1.0, 0.0, 0.0])]
    try:
        cg.GeodesicSolver(mesh, "qclp", order=order, **kwargs).solve(sources)
    except Exception as exc:  # the verdict: the error's type and message
        return type(exc).__name__, str(exc)
    return None


@pytest.mark.parametrize(("case", "kwargs", "sources"), _INVALID, ids=[c[0] for c in _INVALID])
def test_both_orders_give_the_same_verdict_on_invalid_input(case, kwargs, sources):
    first, second = _verdict(1, kwargs, sources), _verdict(2, kwargs, sources)
    assert first is not None and first[0] in ("ParameterError", "SourceError"), first
    assert first == second


def test_order_is_checked_like_every_parameter():
    for bad in (0, 3, 1.5, True, "2"):
        with pytest.raises(ParameterError, match="^order must be 1 .* or 2 .*, got"):
            cg.GeodesicSolver(cg.icosphere(1), "qclp", order=bad)
    assert cg.GeodesicSolver(cg.icosphere(1), "qclp", order=None).order == 1  # None: the domain's default


# ---------------------------------------------------------------------------------------------------------------------
# issue 34: real numbers and the supported ranges
# ---------------------------------------------------------------------------------------------------------------------
def test_check_real_refuses_complex_and_non_numeric_arrays():
    from cvxgeodesic.validation import check_real

    for ok in (1.0, 3, np.ones(3), np.arange(4), [1.0, 2.0], np.float32(2.0)):
        check_real(ok, "x")
    for bad, match in ((np.ones(3) * 1j, "complex values"), ([1.0, 2j], "complex values"), (1 + 0j, "complex"),
                       (np.array(["1.0", "2.0"]), "dtype <U3"), (np.array([1 + 0j], dtype=object), "complex")):
        with pytest.raises(ParameterError, match=r"^--cost c\.npy must hold real numbers"):
            check_real(bad, "--cost c.npy")
        with pytest.raises(ParameterError, match=match):
            check_real(bad, "x")


def test_check_lam_and_m_bounds():
    from cvxgeodesic.validation import MAX_M, check_lam, check_smoothness

    assert check_smoothness(MAX_M, None) == (MAX_M, None)
    with pytest.raises(ParameterError, match=r"^m = 1\.5e6 is outside the supported range \[0, 1e6\]"):
        check_smoothness(1.5e6, None)
    assert check_lam(0.5, 1e-6) == 0.5 and check_lam(5.0, 0.0) == 5.0  # no smoothing weight: nothing to bound
    with pytest.raises(ParameterError, match=r"^lam = 2 is outside the supported range \[0, 1\] on this mesh"):
        check_lam(2.0, 1e-6)


def test_check_coordinates_names_the_vertex_and_the_range():
    from cvxgeodesic.errors import MeshError
    from cvxgeodesic.validation import check_coordinates

    check_coordinates(np.array([[0.0, 0, 0], [1e40, 0, 0]]), "m")
    with pytest.raises(MeshError, match=r"^m: vertex 1 has a coordinate beyond ±1e\+40 \[0\.0, -2e\+40, 0\.0\]"):
        check_coordinates(np.array([[0.0, 0, 0], [0, -2e40, 0]]), "m")
    with pytest.raises(MeshError, match=r"^m: the mesh is only 5e-41 across"):
        check_coordinates(np.array([[0.0, 0, 0], [5e-41, 0, 0]]), "m")
