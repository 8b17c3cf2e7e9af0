"""Every bad input to the command line ends with exit code 2 and one line on stderr, before any solve.

The CLI runs in-process (``cvxgeodesic.cli.main``) for speed; one test runs it as a subprocess.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic.cli import main


def write_off(path: Path, V, F) -> Path:
    lines = ["OFF", f"{len(V)} {len(F)} 0"]
    lines += [" ".join(repr(float(x)) for x in v) for v in V]
    lines += ["3 " + " ".join(str(int(i)) for i in f) for f in F]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    root = tmp_path_factory.mktemp("cli_meshes")
    plane = cg.grid_plane(3, jitter=0.1)
    out = {"ok": write_off(root / "plane.off", plane.V, plane.F)}
    V_nan = plane.V.astype(object)
    V_nan[5, 2] = float("nan")
    out["nan"] = write_off(root / "nan.off", V_nan, plane.F)
    # three pages on one edge: the Hessian energy is undefined there
    out["book"] = write_off(root / "book.off", [[0, 0, 0], [0, 0, 1], [1, 0, 0.5], [-1, 0, 0.5], [0, 1, 0.5]],
                            [[0, 1, 2], [1, 0, 3], [0, 1, 4]])
    (root / "bad.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n")
    out["malformed"] = root / "bad.obj"
    (root / "mesh.abc").write_text("0 0 0\n")
    out["extension"] = root / "mesh.abc"
    (root / "empty.stl").write_bytes(b"")
    out["empty"] = root / "empty.stl"
    out["plain_file"] = root / "not_a_dir"
    out["plain_file"].write_text("x")
    return out


def run_cli(args, capsys) -> tuple[int, list[str]]:
    rc = main([str(a) for a in args])
    err = capsys.readouterr().err.strip().splitlines()
    return rc, err


BAD_INPUT = [
    ("missing file", ["{tmp}/missing.obj", "-s", "0"], "no such file"),
    ("bad extension", ["{extension}", "-s", "0"], "unsupported mesh file extension '.abc'"),
    ("malformed file", ["{malformed}", "-s", "0"], r"line 4: face \('f'\) has a non-integer vertex index 'x'"),
    ("empty file", ["{empty}", "-s", "0"], "file is empty"),
    ("NaN coordinates", ["{nan}", "-s", "0"], r"vertex 5 \(line 8\) has a non-finite coordinate"),
    ("source out of range", ["{ok}", "-s", "16"], "source index 16 is out of range: the mesh has 16 vertices"),
    ("negative source", ["{ok}", "-s", "-1"], "source index -1 is out of range"),
    ("repeated source", ["{ok}", "-s", "2", "-s", "2"], "source vertex 2 is given more than once"),
    ("non-manifold + fmm", ["{book}", "-s", "3", "--method", "fmm"], "needs an edge-manifold mesh"),
    ("baseline + solver", ["{ok}", "-s", "0", "--method", "heat", "--solver", "clarabel"], "applies to the convex"),
    ("negative m", ["{ok}", "-s", "0", "--m", "-1"], "m must be a finite number"),
    ("nan lam", ["{ok}", "-s", "0", "--lam", "nan"], "lam must be a finite number"),
]


@pytest.mark.parametrize("case, args, message", BAD_INPUT, ids=[c[0] for c in BAD_INPUT])
def test_bad_input_exits_2_with_one_line(files, tmp_path, capsys, case, args, message):
    out = tmp_path / "d.ply"
    args = ["distance", *[a.format(tmp=tmp_path, **files) for a in args], "-o", out]
    rc, err = run_cli([*args, "-q"], capsys)
    assert rc == 2, case
    assert len(err) == 1 and err[0].startswith("cvxgeodesic: error: "), err
    assert re.search(message, err[0]), (message, err[0])
    assert not out.exists() and not list(tmp_path.glob(".*"))  # nothing written, no temporary file left
    # without -q a progress line may come first; the error is still one line, the last
    rc, err = run_cli(args, capsys)
    assert rc == 2 and err[-1].startswith("cvxgeodesic: error: ") and len(err) <= 2, err
    assert sum(line.startswith("cvxgeodesic:") for line in err) == 1


@pytest.mark.parametrize(
    "case, output, message",
    [
        ("directory missing", "{tmp}/nodir/d.ply", "directory .*nodir does not exist"),
        ("parent is a file", "{plain_file}/d.ply", "does not exist"),
        ("output is a directory", "{tmp}", "unsupported output file extension"),
        ("bad output extension", "{tmp}/d.txt", "unsupported output file extension '.txt'"),
        ("unwritable directory", "/sys/d.ply", "cannot create files in directory /sys"),
        ("bad png extension", "--png {tmp}/d.jpg", "unsupported output file extension '.jpg'"),
    ],
)
def test_bad_output_exits_2_before_solving(files, tmp_path, capsys, monkeypatch, case, output, message):
    if case == "unwritable directory" and not Path("/sys").is_dir():
        pytest.skip("no /sys")
    solved = []
    monkeypatch.setattr(cg.GeodesicSolver, "solve", lambda *a, **k: solved.append(1))
    if output.startswith("--png"):
        args = ["-o", tmp_path / "d.ply", "--png", output.split()[1].format(tmp=tmp_path)]
    else:
        args = ["-o", output.format(tmp=tmp_path, **files)]
    rc, err = run_cli(["distance", files["ok"], "-s", "0", "--method", "qclp", "--solver", "clarabel", "-q", *args],
                      capsys)
    assert rc == 2 and len(err) == 1 and err[0].startswith("cvxgeodesic: error: "), err
    assert re.search(message, err[0]), (message, err[0])
    assert not solved  # checked before the (possibly long) solve


def test_path_bad_output_extension_exits_2_before_solving(files, tmp_path, capsys, monkeypatch):
    solved = []
    monkeypatch.setattr(cg.GeodesicSolver, "solve", lambda *a, **k: solved.append(1))
    rc, err = run_cli(["path", files["ok"], "-s", "0", "--to", "1", "-q", "-o", tmp_path / "p.txt"], capsys)
    assert rc == 2 and len(err) == 1, err
    assert "unsupported output file extension '.txt'; supported: .csv, .npy, .ply" in err[0]  # validation's message
    assert not solved and not list(tmp_path.iterdir())


def test_write_failure_is_one_line_and_leaves_no_partial_file(files, tmp_path, capsys, monkeypatch):
    import cvxgeodesic._atomic as atomic

    def boom(*args):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(atomic.os, "replace", boom)
    out = tmp_path / "d.npy"
    rc, err = run_cli(["distance", files["ok"], "-s", "0", "--method", "lclp", "--solver", "clarabel", "-q",
                       "-o", out], capsys)
    assert rc == 2 and len(err) == 1 and "No space left on device" in err[0]
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_nonmanifold_mesh_solves_with_the_laplacian_and_warnings_are_one_line(files, tmp_path, capsys):
    out = tmp_path / "d.npy"
    rc, err = run_cli(["distance", files["book"], "-s", "3", "--method", "qcqp-laplacian", "--solver", "clarabel",
                       "-o", out], capsys)
    assert rc == 0 and np.all(np.isfinite(np.load(out)))
    # a zero-area face: solved, with a one-line note instead of a file:line warning report
    V = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.5, 0.5, 0], [1, 1, 0]]
    sliver = write_off(tmp_path / "sliver.off", V, [[0, 1, 3], [0, 3, 2], [1, 4, 3], [3, 4, 2], [1, 2, 3]])
    rc, err = run_cli(["distance", sliver, "-s", "0", "--method", "qclp", "--solver", "clarabel", "-q", "-o", out],
                      capsys)
    assert rc == 0 and np.all(np.isfinite(np.load(out)))
    assert len(err) == 1 and err[0].startswith("cvxgeodesic: note: sliver.off: 1 degenerate face"), err


def test_debug_flag_shows_the_traceback(files, tmp_path, capsys):
    rc = main(["--debug", "distance", str(files["book"]), "-s", "3", "--method", "fmm", "-o",
               str(tmp_path / "d.ply")])
    err = capsys.readouterr().err
    assert rc == 2 and "Traceback" in err and "NonManifoldError" in err


def test_subprocess_bad_input(files, tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "cvxgeodesic.cli", "distance", str(files["nan"]), "-s", "0", "-o",
         str(tmp_path / "d.ply")],
        capture_output=True, text=True, timeout=120,
    )
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1 and "non-finite coordinate" in lines[0], proc.stderr
    assert proc.stdout == "" and not (tmp_path / "d.ply").exists()
