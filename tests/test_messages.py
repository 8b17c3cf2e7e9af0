"""Issue 28 item 8: messages and help that tell the user what to do (files, methods, viewer, --m, compare)."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic.cli import build_parser, main
from cvxgeodesic.compare import TABLE_COLUMNS
from cvxgeodesic.errors import NonManifoldError

README = Path(__file__).resolve().parents[1] / "README.md"
# three pages on one edge: fmm and exact refuse it
BOOK = cg.TriMesh([[0, 0, 0], [0, 0, 1], [1, 0, 0.5], [-1, 0, 0.5], [0, 1, 0.5]], [[0, 1, 2], [1, 0, 3], [0, 1, 4]])


@pytest.fixture
def plane_off(tmp_path):
    plane = cg.grid_plane(3, jitter=0.1)
    path = tmp_path / "plane.off"
    path.write_text("OFF\n" + f"{plane.n_vertices} {plane.n_faces} 0\n"
                    + "".join(" ".join(map(repr, v)) + "\n" for v in plane.V.tolist())
                    + "".join("3 " + " ".join(map(str, f)) + "\n" for f in plane.F.tolist()))
    return path


@pytest.mark.parametrize("method", ["fmm", "exact"])
def test_non_manifold_error_names_the_methods_that_work(method):
    with pytest.raises(NonManifoldError) as info:
        cg.geodesic_distance(BOOK, 3, method=method)
    msg = str(info.value)
    named = re.findall(r"'([a-z-]+)'", msg.split("; use ", 1)[1])
    assert {"qcqp-hessian", "qclp", "heat", "dijkstra"} <= set(named), msg
    assert "default 'qcqp-hessian'" in msg
    for other in named:  # and every method it names solves this mesh
        assert np.isfinite(cg.geodesic_distance(BOOK, 3, method=other)).all(), other


def test_missing_viewer_names_the_command_and_the_extra(plane_off, tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "polyscope", None)  # import fails as if not installed
    rc = main(["view", str(plane_off), "-s", "0", "--method", "dijkstra", "--screenshot", str(tmp_path / "v.png")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1, err
    assert "cvxgeodesic view" in err[0] and "pip install 'cvxgeodesic[viewer]'" in err[0], err


@pytest.mark.parametrize("command, option", [("distance", ["--m", "-1"]), ("distance", ["--m", "nan"]),
                                             ("distance", ["--lam", "-2"]), ("matrix", ["--m", "-1"])])
def test_a_bad_number_is_one_line_and_nothing_before_it(plane_off, tmp_path, capsys, command, option):
    rc = main([command, str(plane_off), "-s", "0", *option, "-o", str(tmp_path / "d.npy")])  # no -q
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1, err  # no "<mesh>: 16 vertices ..." header first
    name = option[0][2:]
    assert err[0].startswith(f"cvxgeodesic: error: {name} must be a finite number >= 0"), err


def test_compare_help_explains_every_column(capsys):
    (sub,) = [a for a in build_parser()._actions if a.__class__.__name__ == "_SubParsersAction"]
    text = sub.choices["compare"].format_help()
    for col in TABLE_COLUMNS:
        assert re.search(rf"^  {re.escape(col.header)}: \S", text, flags=re.M), col.header
    vs = re.search(r"^  vs exact: (.*?)(?=^  \S)", text, flags=re.M | re.S).group(1)
    assert "exact field's" in vs and "below 1" in vs and "smoother" in vs


@pytest.mark.skipif(not README.is_file(), reason="needs the source checkout")
def test_readme_says_how_to_read_fields_back():
    text = README.read_text(encoding="utf-8")
    assert "cg.load_distance(path" in text
    glb = text[text.index("`.glb` (vertex attribute"):][:200]
    assert "`_DISTANCE`" in glb and "float32" in glb
    assert 'vertex_attributes["_DISTANCE"]' in text
    assert "`vs\nexact`" in text or "`vs exact`" in text


# ---------------------------------------------------------------------------------------------------------------------
# Issue 34: numbers outside the supported ranges are refused naming the parameter, its value and the range (before,
# m=1e300 was reported as an indefinite Hessian energy, cost=1e300 as "DualInfeasible", cost=1e-300 as a zero area,
# a very anisotropic metric as "not positive definite", and complex costs lost their imaginary part silently)
# ---------------------------------------------------------------------------------------------------------------------
SPHERE = cg.icosphere(1)


@pytest.mark.parametrize("kwargs, match", [
    ({"method": "qcqp-hessian", "m": 1e300}, r"^m = 1e300 is outside the supported range \[0, 1e6\]"),
    ({"method": "qclp", "m": 1e7}, r"^m = 1e7 is outside the supported range \[0, 1e6\]"),  # whatever the method
    ({"method": "qcqp-hessian", "lam": 1e300}, r"^lam = 1e300 is outside the supported range \[0, [0-9.e-]+\] on this "
                                               r"mesh \(the weight of m = 1e6; m = 1 is lam = "),
    ({"method": "qclp", "cost": 1e300}, r"^cost = 1e300 is outside the supported range \[1e-30, 1e30\]"),
    ({"method": "qclp", "cost": 1e-300}, r"^cost = 1e-300 is outside the supported range \[1e-30, 1e30\]"),
    ({"method": "dijkstra", "cost": np.r_[1e31, np.ones(41)]}, r"^cost\[0\] \(vertex 0\) = 1e31 is outside the "
                                                                r"supported range"),
    ({"method": "qclp", "cost": np.r_[1e12, np.ones(41)]}, r"^cost varies by a factor 1e12 \(cost\[0\] \(vertex 0\) = "
                                                           r"1e12, cost\[1\] \(vertex 1\) = 1\); the supported ratio "
                                                           r"of the largest to the smallest cost is at most 1e6"),
    ({"method": "qclp", "metric": np.diag([1e16, 1.0, 1.0])}, r"^metric is too anisotropic in the plane of face \d+ "
                                                               r"\(eigenvalues there .*condition number .*\); "
                                                               r"supported: eigenvalues in \[1e-60, 1e60\] with a "
                                                               r"ratio up to 1e8"),
    ({"method": "qclp", "metric": np.eye(3) * 1e70}, r"^metric is outside the supported range in the plane of face "
                                                      r"\d+ .*eigenvalues in \[1e-60, 1e60\]"),
    ({"method": "qclp", "metric": np.diag([0.0, 1.0, 1.0])}, r"^metric is not positive definite in the plane"),
    ({"method": "qclp", "cost": np.ones(42) * (1 + 1j)}, r"^cost must hold real numbers, got complex values"),
    ({"method": "qclp", "cost": 2 + 0j}, r"^cost must hold real numbers, got complex values"),
    ({"method": "qclp", "cost": [1.0] * 41 + [1j]}, r"^cost must hold real numbers, got complex values"),
    ({"method": "qclp", "metric": np.eye(3) * (1 + 0j)}, r"^metric must hold real numbers, got complex values"),
    # issue 41: a value just past a bound was rounded to it ("m = 1e6 is outside the supported range [0, 1e6]")
    ({"method": "qclp", "m": 1000000.1}, r"^m = 1000000\.1 is outside the supported range \[0, 1000000\]"),
    ({"method": "qclp", "m": 1e6 * (1 + 2e-16)}, r"^m = 1000000\.0000000002 is outside the supported range "
                                                 r"\[0, 1000000\]"),
    ({"method": "qclp", "cost": 1.000001e30}, r"^cost = 1\.000001e30 is outside the supported range \[1e-30, 1e30\]"),
    ({"method": "qclp", "cost": np.r_[1e6 * (1 + 1e-9), np.ones(41)]},
     r"^cost varies by a factor 1000000\.001 \(cost\[0\] \(vertex 0\) = 1000000\.001, cost\[1\] \(vertex 1\) = 1\); "
     r"the supported ratio of the largest to the smallest cost is at most 1e6"),
    ({"method": "qclp", "metric": np.eye(3) * 1.00001e60}, r"^metric is outside the supported range in the plane of "
                                                            r"face \d+ \(eigenvalues there 1\.00001e60, 1\.00001e60: "
                                                            r"condition number 1\); .*\[1e-60, 1e60\]"),
])
def test_numbers_outside_the_supported_ranges_are_refused_naming_the_parameter(kwargs, match):
    with pytest.raises(cg.ParameterError, match=match):
        cg.GeodesicSolver(SPHERE, **kwargs)


def test_the_ends_of_the_supported_ranges_are_solved():
    """m = 1e6, a cost ratio of 1e6 and a metric's condition number of 1e8 (measured solvable: validation.py)."""
    ok = [cg.GeodesicSolver(SPHERE, "qcqp-hessian", m=1e6).solve(0),
          cg.GeodesicSolver(SPHERE, "qclp", cost=np.r_[1e6, np.ones(41)]).solve(0),
          cg.GeodesicSolver(SPHERE, "qclp", cost=1e30).solve(0),
          cg.GeodesicSolver(SPHERE, "qclp", metric=np.diag([1e8, 1.0, 1.0])).solve(0)]
    assert all(r.info.status == "optimal" and np.isfinite(r.distance).all() for r in ok)


def test_a_complex_cost_file_is_refused_by_the_cli(plane_off, tmp_path, capsys):
    cost = tmp_path / "cost.npy"
    np.save(cost, np.ones(16) * (1 + 1j))  # one per vertex of the 4x4 grid
    rc = main(["distance", str(plane_off), "-s", "0", "--method", "qclp", "--cost", str(cost), "-q",
               "-o", str(tmp_path / "d.npy")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1, err
    assert f"--cost {cost} must hold real numbers, got complex values" in err[0], err
    assert not (tmp_path / "d.npy").exists()


def test_a_huge_m_is_one_line_on_the_command_line(plane_off, tmp_path, capsys):
    rc = main(["distance", str(plane_off), "-s", "0", "--m", "1e300", "-o", str(tmp_path / "d.npy")])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1, err
    assert "m = 1e300 is outside the supported range [0, 1e6]" in err[0], err
