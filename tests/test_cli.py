"""Command-line interface: outputs, exit codes and one-line errors."""

import subprocess
import sys

import numpy as np
import pytest

import cvxgeodesic as cg
from conftest import sphere_file_with_a_loose_vertex
from cvxgeodesic.cli import main
from cvxgeodesic.mesh.io import load_distance_ply


@pytest.fixture(scope="module")
def sphere_file(tmp_path_factory):
    mesh = cg.icosphere(2)
    path = tmp_path_factory.mktemp("mesh") / "sphere.off"
    lines = ["OFF", f"{mesh.n_vertices} {mesh.n_faces} 0"]
    lines += [" ".join(map(repr, v)) for v in mesh.V.tolist()]
    lines += ["3 " + " ".join(map(str, f)) for f in mesh.F.tolist()]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_distance_writes_ply_and_png(sphere_file, tmp_path, capsys):
    out, png = tmp_path / "d.ply", tmp_path / "d.png"
    rc = main(["distance", str(sphere_file), "--source", "0", "--source", "5", "--method", "qclp",
               "--solver", "clarabel", "-o", str(out), "--png", str(png)])
    assert rc == 0
    mesh, props = load_distance_ply(out)
    d = props["distance"]
    assert d.shape == (162,) and d[0] == 0 and d[5] == 0 and np.all(d[[1, 2, 3]] > 0)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "optimal" in capsys.readouterr().err


def test_distance_npy_matches_api(sphere_file, tmp_path):
    out = tmp_path / "d.npy"
    assert main(["distance", str(sphere_file), "-s", "3", "--method", "lclp", "--solver", "clarabel",
                 "-q", "-o", str(out)]) == 0
    expected = cg.geodesic_distance(cg.load_mesh(sphere_file), 3, method="lclp", solver="clarabel")
    np.testing.assert_allclose(np.load(out), expected)


@pytest.mark.parametrize("normalization", ["area", "paper"])
def test_distance_normalization_flag_matches_api(sphere_file, tmp_path, normalization):
    out = tmp_path / "d.npy"
    assert main(["distance", str(sphere_file), "-s", "3", "--solver", "clarabel", "--normalization", normalization,
                 "-q", "-o", str(out)]) == 0
    expected = cg.geodesic_distance(cg.load_mesh(sphere_file), 3, solver="clarabel", normalization=normalization)
    np.testing.assert_allclose(np.load(out), expected, atol=1e-12)


def test_distance_order_two(sphere_file, tmp_path):
    out = tmp_path / "d.npy"
    assert main(["distance", str(sphere_file), "-s", "3", "--method", "qclp", "--order", "2", "-q",
                 "-o", str(out)]) == 0
    expected = cg.geodesic_distance(cg.load_mesh(sphere_file), 3, method="qclp", order=2)
    np.testing.assert_allclose(np.load(out), expected, atol=1e-12)
    p1 = cg.geodesic_distance(cg.load_mesh(sphere_file), 3, method="qclp")
    assert np.abs(np.load(out) - p1).max() > 1e-3


@pytest.mark.parametrize(
    "args, message",
    [(["distance", "missing.obj", "-s", "0", "-o", "x.ply"], "no such file"),
     (["distance", "{mesh}", "-s", "999", "-o", "{tmp}/x.ply"], "out of range"),
     (["distance", "{mesh}", "-s", "0", "-o", "{tmp}/x.txt"], "x.txt"),
     (["distance", "{mesh}", "-s", "0", "-o", "{tmp}/nodir/x.ply"], "nodir")],
)
def test_bad_input_exits_2_with_one_line(sphere_file, tmp_path, capsys, args, message):
    args = [a.format(mesh=sphere_file, tmp=tmp_path) for a in args]
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("cvxgeodesic: error:") and message in err[0]
    assert not (tmp_path / "x.ply").exists()


def test_debug_shows_traceback(capsys):
    assert main(["--debug", "distance", "missing.obj", "-s", "0", "-o", "x.ply"]) == 2
    assert "Traceback" in capsys.readouterr().err


def test_unknown_method_is_usage_error(sphere_file):
    proc = subprocess.run([sys.executable, "-m", "cvxgeodesic.cli", "distance", str(sphere_file), "-s", "0",
                           "--method", "nope", "-o", "x.ply"], capture_output=True, text=True)
    assert proc.returncode == 2 and "invalid choice" in proc.stderr


def test_importing_the_cli_loads_the_standard_library_only():
    """The console script imports cvxgeodesic.cli before main() installs its Ctrl-C handler: nothing heavy may load
    then (a Ctrl-C during NumPy's import would be a traceback), whichever command module the package holds."""
    code = ("import sys, cvxgeodesic.cli, cvxgeodesic.cli._common, cvxgeodesic.cli._options\n"
            "for name in cvxgeodesic.cli.COMMANDS:\n"
            "    __import__(f'cvxgeodesic.cli.{name}')\n"
            "print(sorted(m for m in ('numpy', 'scipy', 'numba', 'matplotlib', 'tqdm') if m in sys.modules))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert proc.stdout.strip() == "[]", proc.stdout + proc.stderr


@pytest.mark.parametrize("module", ["cvxgeodesic", "cvxgeodesic.cli"])
def test_python_m_runs_the_command(module):
    proc = subprocess.run([sys.executable, "-m", module, "--version"], capture_output=True, text=True)
    assert proc.returncode == 0 and proc.stdout.startswith("cvxgeodesic ")


def test_matrix_rows_in_the_given_order_in_file_numbering(tmp_path):
    """`cvxgeodesic matrix`: one row per -s in the given order (repeats allowed), columns in the file's numbering."""
    mesh, path = sphere_file_with_a_loose_vertex(tmp_path)  # file vertex 0 is in no face
    out = tmp_path / "D.npy"
    assert main(["matrix", str(path), "-s", "6,1", "-s", "6", "--method", "qclp", "-q", "-o", str(out)]) == 0
    D = np.load(out)
    assert D.shape == (3, 163) and np.all(np.isinf(D[:, 0]))
    expected = cg.distance_matrix(mesh, [5, 0, 5], method="qclp")
    np.testing.assert_allclose(D[:, 1:], expected, atol=1e-12)
    assert D[0, 6] == 0 and D[1, 1] == 0
    assert main(["matrix", str(path), "-s", "0", "-q", "-o", str(tmp_path / "E.npy")]) == 2  # in no face
    assert not (tmp_path / "E.npy").exists()
    assert main(["matrix", str(path), "-s", "1", "-q", "-o", str(tmp_path / "E.csv")]) == 2


def test_demo_prints_one_aligned_table_and_writes_its_files(tmp_path, capsys):
    from cvxgeodesic.demo import DEMO_CASES

    assert main(["demo", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out.splitlines()
    head, rule = out[1], out[2]
    rows = out[3: 3 + len(DEMO_CASES) + 1]
    assert head.split()[:2] == ["method", "solver"] and set(rule) == {"-", " "}
    assert [r[:head.index("solver")].strip() for r in rows] == [*(c[0] for c in DEMO_CASES), "exact"]
    # numbers are right-aligned under their headers: each ends where its header ends
    for title in ("time [s]", "iters", "mean rel err", "off-ridge err"):
        end = head.index(title) + len(title)
        assert all(r[end - 1] != " " and (len(r) == end or r[end] == " ") for r in rows), title
    assert rows[-1].split()[4:6] == ["0.000%", "0.00%"]  # the exact field against itself
    assert {p.name for p in tmp_path.iterdir()} == {"spot_qcqp-hessian.ply", "spot_qcqp-hessian.png"}
    # under the table, which method to use for what, with this run's numbers
    guide = out[out.index(next(ln for ln in out if ln.startswith("which method to use"))):]
    assert [ln.split()[0] for ln in guide[1:5]] == ["smooth", "accuracy", "order-1", "speed"]
    assert "the default, qcqp-hessian" in guide[1] and "qclp with order=2" in guide[2] and "heat:" in guide[4]


def test_demo_guidance_quotes_the_rows():
    from cvxgeodesic.demo import guidance

    def row(method, t, err, ridge):
        return {"method": method, "time_s": t, "rel_mean": err, "ridge_jump_p95": ridge}

    rows = [row("qcqp-hessian", 0.2, 0.021, 0.49), row("qclp", 0.1, 0.020, 0.72),
            row("qclp order=2", 0.9, 0.0015, 0.74), row("heat", 0.02, 0.017, 0.53), row("fmm", 0.03, 0.024, 0.69),
            row("dijkstra", 0.001, 0.071, 0.87), row("exact", 0.07, 0.0, 0.72)]
    text = guidance(rows)
    assert "ridge 0.49 (heat 0.53, exact 0.72)" in text
    assert "mean error 0.150%, 11x below the best" in text and "(heat), in 9x the time of qclp" in text
    assert "heat: 0.020 s, mean error 1.70%" in text
