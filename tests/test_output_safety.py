"""Issue 34, outputs, signals and argument checks: what a careless or hostile user (or machine) can do to the files.

1. A replaced output keeps its mode (and owner as root); a read-only one is refused unless allowed.
2. No command writes over one of its input files.
3. SIGTERM is handled like Ctrl-C: temporary files removed, one line, exit code 143.
4. Commands writing two files write both or neither.
5. Ctrl-C during the start-up's imports is one line and exit code 130, no traceback.
6. A zero ``--slice-normal`` and an ``--out`` folder that cannot take files are refused before any solve.
"""

from __future__ import annotations

import os
import re
import signal
import stat
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import cvxgeodesic as cg
import cvxgeodesic._atomic as atomic
from cvxgeodesic.cli import main
from cvxgeodesic.errors import ParameterError

SRC = Path(cg.__file__).resolve().parents[1]  # the package under test: subprocesses import the same one


@pytest.fixture
def umask_022():
    """The common umask, so that a fresh file is 644 and a kept 600 is told apart from a reset."""
    old = os.umask(0o022)
    yield
    os.umask(old)


@pytest.fixture(scope="module")
def sphere_file(tmp_path_factory) -> Path:
    return cg.save_distance(tmp_path_factory.mktemp("in") / "sphere.ply", cg.icosphere(1), np.zeros(42))


def write_tetgen(mesh, stem: Path) -> Path:
    """``stem.node`` / ``stem.ele`` (0-based): a tetrahedral mesh file without meshio."""
    nodes = [f"{len(mesh.V)} 3 0 0"] + [f"{i} {x!r} {y!r} {z!r}" for i, (x, y, z) in enumerate(mesh.V.tolist())]
    eles = [f"{len(mesh.T)} 4 0"] + [f"{i} " + " ".join(map(str, t)) for i, t in enumerate(mesh.T.tolist())]
    stem.with_suffix(".node").write_text("\n".join(nodes) + "\n")
    stem.with_suffix(".ele").write_text("\n".join(eles) + "\n")
    return stem.with_suffix(".node")


@pytest.fixture(scope="module")
def tet_file(tmp_path_factory) -> Path:
    return write_tetgen(cg.tet_box(2, jitter=0.2, seed=3), tmp_path_factory.mktemp("tet") / "box")


@pytest.fixture
def no_solve(monkeypatch):
    """Fails the test if a solve starts: the checks under test must come first."""
    def solve(*args, **kwargs):
        raise AssertionError("solved before the arguments were checked")

    monkeypatch.setattr(cg.GeodesicSolver, "solve", solve)


def run(args, capsys) -> tuple[int, list[str]]:
    rc = main([str(a) for a in args])
    return rc, capsys.readouterr().err.strip().splitlines()


def mode(path: Path) -> int:
    return stat.S_IMODE(path.stat().st_mode)


# ----------------------------------------------------------------------------------------------------------------
# 1. a replaced file keeps its metadata; a read-only one is refused
# ----------------------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("ext", [".ply", ".npy", ".csv"])
def test_save_distance_keeps_the_mode_of_the_file_it_replaces(tmp_path, umask_022, ext):
    target = tmp_path / f"d{ext}"
    cg.save_distance(target, cg.icosphere(0), np.zeros(12))
    assert mode(target) == 0o644  # a new file: the umask's
    target.chmod(0o600)
    cg.save_distance(target, cg.icosphere(0), np.ones(12))
    assert mode(target) == 0o600
    np.testing.assert_array_equal(cg.load_distance(target), np.ones(12))


def test_a_read_only_file_is_refused_unless_allowed_and_stays_read_only(tmp_path):
    target = tmp_path / "d.npy"
    cg.save_distance(target, cg.icosphere(0), np.zeros(12))
    target.chmod(0o444)
    with pytest.raises(ParameterError, match=re.escape(f"{target} is read-only (-r--r--r--): refusing to replace "
                                                       "it; make it writable (chmod u+w) or allow it with "
                                                       "overwrite_read_only=True")):
        cg.save_distance(target, cg.icosphere(0), np.ones(12))
    np.testing.assert_array_equal(np.load(target), np.zeros(12))  # untouched
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.npy"]  # no temporary file left
    cg.save_distance(target, cg.icosphere(0), np.ones(12), overwrite_read_only=True)
    np.testing.assert_array_equal(np.load(target), np.ones(12))
    assert mode(target) == 0o444


def test_another_users_file_is_refused_too(tmp_path, monkeypatch, umask_022):
    # its owner may write it (644), this process may not, the folder lets it rename over it: os.access tells
    target = tmp_path / "theirs.npy"
    np.save(target, np.zeros(3))
    monkeypatch.setattr(atomic.os, "access", lambda path, how: False)
    with pytest.raises(ParameterError, match=re.escape(f"{target} is not writable by this user (-rw-r--r--): "
                                                       "refusing to replace it; make it writable for you or allow "
                                                       "it with overwrite_read_only=True")):
        cg.save_distance(target, cg.icosphere(0), np.zeros(12))


def test_a_tetrahedral_field_file_follows_the_same_rules(tmp_path):
    pytest.importorskip("meshio")
    box = cg.tet_box(1)
    target = tmp_path / "d.vtu"
    cg.save_distance(target, box, np.zeros(box.n_vertices))
    target.chmod(0o440)
    with pytest.raises(ParameterError, match="read-only"):
        cg.save_distance(target, box, np.ones(box.n_vertices))
    cg.save_distance(target, box, np.ones(box.n_vertices), overwrite_read_only=True)
    assert mode(target) == 0o440


@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() != 0, reason="only root may give a file away")
def test_as_root_the_owner_and_group_are_kept(tmp_path):
    target = tmp_path / "d.npy"
    cg.save_distance(target, cg.icosphere(0), np.zeros(12))
    os.chown(target, 12345, 23456)
    cg.save_distance(target, cg.icosphere(0), np.ones(12))
    st = target.stat()
    assert (st.st_uid, st.st_gid) == (12345, 23456)


def test_output_set_keeps_modes_and_refuses_a_read_only_target_before_the_block(tmp_path, umask_022):
    a, b = tmp_path / "a.bin", tmp_path / "b.bin"
    a.write_bytes(b"old a")
    a.chmod(0o640)
    with atomic.output_set(a, b) as (ta, tb):
        atomic.atomic_write(ta, lambda fh: fh.write(b"new a"))  # through atomic_write, as save_distance does
        assert mode(ta) == 0o640  # already while the block runs, not only once renamed
        tb.write_bytes(b"new b")  # directly, as polyscope's screenshot does
    assert (a.read_bytes(), mode(a), mode(b)) == (b"new a", 0o640, 0o644)
    b.chmod(0o400)
    entered = False
    with pytest.raises(ParameterError, match=re.escape(f"{b} is read-only")):
        with atomic.output_set(a, b):
            entered = True
    assert not entered and b.read_bytes() == b"new b"
    with atomic.output_set(a, b, overwrite_read_only=True) as (ta, tb):
        ta.write_bytes(b"3")
        tb.write_bytes(b"3")
    assert (b.read_bytes(), mode(b)) == (b"3", 0o400)


def test_the_new_content_is_never_readable_under_a_wider_mode(tmp_path, umask_022, monkeypatch):
    # a 600 file holds something private: its replacement must not sit in the folder as 644 while it is written
    target = tmp_path / "secret.npy"
    target.write_bytes(b"x")
    target.chmod(0o600)
    seen = []
    real = atomic._give_metadata

    def spy(fd, st):
        real(fd, st)
        seen.append(stat.S_IMODE(os.fstat(fd).st_mode))

    monkeypatch.setattr(atomic, "_give_metadata", spy)
    atomic.atomic_write(target, lambda fh: seen.append("write") or fh.write(b"y"))
    assert seen == [0o600, "write"]


def test_cli_refuses_a_read_only_output_before_solving(sphere_file, tmp_path, capsys, no_solve):
    out = tmp_path / "d.ply"
    out.write_text("keep")
    out.chmod(0o444)
    rc, err = run(["distance", sphere_file, "-s", "0", "-o", out], capsys)
    assert rc == 2 and err == [f"cvxgeodesic: error: {out} is read-only (-r--r--r--): refusing to replace it; make "
                               "it writable (chmod u+w) or allow it with --overwrite-read-only"]
    png = tmp_path / "p.png"
    png.write_text("keep")
    png.chmod(0o444)
    for args in (["distance", sphere_file, "-s", "0", "-o", tmp_path / "new.ply", "--png", png],
                 ["path", sphere_file, "-s", "0", "--to", "5", "-o", tmp_path / "new.csv", "--png", png],
                 ["view", sphere_file, "-s", "0", "--screenshot", png]):
        rc, err = run(args, capsys)
        assert rc == 2 and len(err) == 1 and f"{png} is read-only" in err[0], (args, err)
    assert out.read_text() == "keep" and png.read_text() == "keep"


def test_cli_overwrite_read_only_replaces_and_keeps_each_mode(sphere_file, tmp_path, capsys, umask_022):
    out, png = tmp_path / "d.ply", tmp_path / "d.png"
    args = ["distance", sphere_file, "-s", "0", "--method", "dijkstra", "-q", "-o", out, "--png", png]
    assert run(args, capsys)[0] == 0
    out.chmod(0o600)
    png.chmod(0o444)
    rc, _ = run([*args, "--overwrite-read-only"], capsys)
    assert rc == 0 and (mode(out), mode(png)) == (0o600, 0o444)
    path_out = tmp_path / "p.csv"
    path_args = ["path", sphere_file, "-s", "0", "--to", "5", "--method", "dijkstra", "-q", "-o", path_out]
    assert run(path_args, capsys)[0] == 0
    path_out.chmod(0o444)
    assert run(path_args, capsys)[0] == 2
    assert run([*path_args, "--overwrite-read-only"], capsys)[0] == 0 and mode(path_out) == 0o444


def test_overwrite_read_only_is_in_the_help(capsys):
    for command in ("distance", "path", "view"):
        with pytest.raises(SystemExit):
            main([command, "--help"])
        out = " ".join(capsys.readouterr().out.split())
        assert "--overwrite-read-only replace an output file even when it is read-only" in out, command


# ----------------------------------------------------------------------------------------------------------------
# 2. never overwrite an input
# ----------------------------------------------------------------------------------------------------------------
def test_no_command_writes_over_its_input(tmp_path, capsys, no_solve, tet_file):
    mesh = cg.save_distance(tmp_path / "t.ply", cg.icosphere(1), np.zeros(42))
    before = mesh.read_bytes()
    link = tmp_path / "link.ply"
    os.link(mesh, link)  # the same file under another name
    png_link = tmp_path / "shot.png"
    os.link(mesh, png_link)
    tet_png = tmp_path / "box.png"
    os.link(tet_file, tet_png)
    cost = tmp_path / "cost.npy"
    np.save(cost, np.ones(42))
    cases = [
        (["distance", mesh, "-s", "0", "-o", mesh], "-o"),
        (["distance", mesh, "-s", "0", "-o", link], "-o"),
        (["distance", mesh, "-s", "0", "-o", tmp_path / "sub" / ".." / "t.ply"], "-o"),
        (["distance", mesh, "-s", "0", "--cost", cost, "-o", cost], "-o"),
        (["path", mesh, "-s", "0", "--to", "3", "-o", link], "-o"),
        (["view", mesh, "-s", "0", "--screenshot", png_link], "--screenshot"),
        (["distance", tet_file, "-s", "0", "-o", tmp_path / "d.npy", "--png", tet_png], "--png"),
    ]
    (tmp_path / "sub").mkdir()
    for args, option in cases:
        rc, err = run(args, capsys)
        assert rc == 2 and len(err) == 1, (args, err)
        assert err[0].startswith(f"cvxgeodesic: error: {option} ") and "refusing to overwrite an input" in err[0], err
    assert mesh.read_bytes() == before and np.array_equal(np.load(cost), np.ones(42))


# ----------------------------------------------------------------------------------------------------------------
# 3. SIGTERM like Ctrl-C
# ----------------------------------------------------------------------------------------------------------------
def _signal_cli(args: list[str], ready, sig: int, cwd: Path) -> tuple[int, str]:
    """Run ``python -m cvxgeodesic.cli ARGS``; once ``ready(stderr)`` holds, send ``sig``. Returns (code, stderr)."""
    proc = subprocess.Popen([sys.executable, "-m", "cvxgeodesic.cli", *args], stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, cwd=cwd, env=dict(os.environ, PYTHONPATH=str(SRC)),
                            start_new_session=True)
    chunks: list[bytes] = []
    assert proc.stderr is not None
    stream = proc.stderr
    reader = threading.Thread(target=lambda: chunks.extend(iter(lambda: stream.read1(4096), b"")), daemon=True)
    reader.start()
    deadline = time.monotonic() + 300  # a bound for a broken run only: ready() is what the test waits for
    while time.monotonic() < deadline and proc.poll() is None and not ready(b"".join(chunks)):
        time.sleep(0.05)
    proc.send_signal(sig)
    proc.wait(timeout=120)
    reader.join(timeout=10)
    return proc.returncode, b"".join(chunks).decode()


@pytest.fixture(scope="module")
def big_grid(tmp_path_factory) -> Path:
    # ~15 s per Clarabel solve on a loaded 2-core machine, 3.6 s unloaded: still running when the signal comes
    big = cg.grid_plane(130, jitter=0.1)
    return cg.save_distance(tmp_path_factory.mktemp("big") / "grid.ply", big, np.zeros(big.n_vertices))


def test_sigterm_during_the_solve_is_one_line_and_exit_143(big_grid, tmp_path):
    args = ["distance", str(big_grid), "-s", "0", "--solver", "clarabel", "-o", "g.ply", "--png", "g.png"]
    # the progress lines begin once the solve runs (Clarabel: the signal must stop it within an iteration)
    rc, text = _signal_cli(args, lambda err: b"iteration" in err, signal.SIGTERM, tmp_path)
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("iteration")]
    assert rc == 143, text
    assert "Traceback" not in text and lines[-1] == "cvxgeodesic: terminated", text
    assert "wrote" not in text  # stopped, not finished
    assert sorted(os.listdir(tmp_path)) == []


SIGNAL_IN_THE_WRITE = """
import os, signal, sys
import cvxgeodesic.plotting as plotting
from cvxgeodesic.cli import main

def plot_field(mesh, d, path, **kwargs):  # the PNG is the second file: the first is written by now
    assert any(".part." in name for name in os.listdir(".")), os.listdir(".")
    os.kill(os.getpid(), signal.{sig})
    raise AssertionError("the signal did not stop the command")

plotting.plot_field = plot_field
sys.exit(main(sys.argv[1:]))
"""


@pytest.mark.parametrize(("sig", "code", "line"), [("SIGTERM", 143, "terminated"), ("SIGINT", 130, "interrupted")])
def test_a_signal_while_the_files_are_written_leaves_no_part_file(sphere_file, tmp_path, sig, code, line):
    old = b"old contents"
    (tmp_path / "g.ply").write_bytes(old)
    proc = subprocess.run([sys.executable, "-c", SIGNAL_IN_THE_WRITE.format(sig=sig), "distance", str(sphere_file),
                           "-s", "0", "--method", "dijkstra", "-q", "-o", "g.ply", "--png", "g.png"],
                          capture_output=True, text=True, cwd=tmp_path, env=dict(os.environ, PYTHONPATH=str(SRC)),
                          timeout=300)
    assert proc.returncode == code and proc.stderr.strip().splitlines() == [f"cvxgeodesic: {line}"], proc.stderr
    assert sorted(os.listdir(tmp_path)) == ["g.ply"] and (tmp_path / "g.ply").read_bytes() == old


# ----------------------------------------------------------------------------------------------------------------
# 4. both files or neither
# ----------------------------------------------------------------------------------------------------------------
def _failing_png(*args, **kwargs):
    raise OSError(28, "No space left on device")


def test_path_writes_both_files_or_neither(sphere_file, tmp_path, capsys, monkeypatch):
    out, png = tmp_path / "p.npy", tmp_path / "p.png"
    args = ["path", sphere_file, "-s", "0", "--to", "30", "--method", "dijkstra", "-q", "-o", out, "--png", png]
    monkeypatch.setattr("cvxgeodesic.plotting.plot_field", _failing_png)
    rc, err = run(args, capsys)
    assert rc == 2 and err == ["cvxgeodesic: error: [Errno 28] No space left on device"]
    assert os.listdir(tmp_path) == []  # neither file, no temporary one
    out.write_bytes(b"old path")
    rc, _ = run(args, capsys)
    assert rc == 2 and os.listdir(tmp_path) == ["p.npy"] and out.read_bytes() == b"old path"
    monkeypatch.undo()
    assert run(args, capsys)[0] == 0 and np.load(out).shape[1] == 3 and png.stat().st_size > 0


@pytest.mark.parametrize("first_existed", [True, False])
def test_a_failed_rename_puts_the_first_target_back(tmp_path, monkeypatch, first_existed):
    a, b = tmp_path / "a.ply", tmp_path / "b.png"
    if first_existed:
        a.write_bytes(b"old a")
    b.write_bytes(b"old b")
    real, calls = os.replace, []

    def replace(src, dst):
        calls.append(dst)
        if len(calls) == 2:  # the second target's rename: the disk went away
            raise OSError(5, "Input/output error")
        real(src, dst)

    monkeypatch.setattr(atomic.os, "replace", replace)
    with pytest.raises(OSError, match="Input/output error"):
        with atomic.output_set(a, b) as (ta, tb):
            ta.write_bytes(b"new a")
            tb.write_bytes(b"new b")
    assert b.read_bytes() == b"old b"
    assert (a.read_bytes() == b"old a") if first_existed else not a.exists()
    assert sorted(os.listdir(tmp_path)) == (["a.ply", "b.png"] if first_existed else ["b.png"])


def test_tetrahedral_distance_writes_both_files_or_neither(tet_file, tmp_path, capsys, monkeypatch):
    out, png = tmp_path / "d.npy", tmp_path / "d.png"
    monkeypatch.setattr("cvxgeodesic.evaluation.slice_plot.plot_slice", _failing_png)
    rc, err = run(["distance", tet_file, "-s", "0", "--method", "dijkstra", "-q", "-o", out, "--png", png], capsys)
    assert rc == 2 and "No space left on device" in err[0]
    assert os.listdir(tmp_path) == []


def test_surface_distance_writes_both_files_or_neither(sphere_file, tmp_path, capsys, monkeypatch):
    out, png = tmp_path / "d.ply", tmp_path / "d.png"
    monkeypatch.setattr("cvxgeodesic.plotting.plot_field", _failing_png)
    rc, _ = run(["distance", sphere_file, "-s", "0", "--method", "dijkstra", "-q", "-o", out, "--png", png], capsys)
    assert rc == 2 and os.listdir(tmp_path) == []


# ----------------------------------------------------------------------------------------------------------------
# 5. Ctrl-C during the start-up
# ----------------------------------------------------------------------------------------------------------------
CONSOLE_SCRIPT = "import re, sys\nfrom cvxgeodesic.cli import main\nsys.exit(main())\n"  # what pip's wrapper does


def _numpy_loaded(pid: int) -> bool:
    try:
        return "_multiarray_umath" in Path(f"/proc/{pid}/maps").read_text()
    except OSError:
        return False


@pytest.mark.skipif(not Path("/proc/self/maps").exists(), reason="watches the process's mapped libraries (Linux)")
@pytest.mark.parametrize("delay", [0.0, 0.05, 0.3, 1.0])
def test_ctrl_c_during_the_start_up_imports_is_one_line_and_exit_130(big_grid, tmp_path, delay):
    # The signal comes `delay` seconds after NumPy's library is mapped: the start-up's heavy imports (NumPy, SciPy,
    # Numba, ~1.5 s) are under way, whatever the machine's speed. Before this, the package imported NumPy before
    # main() could catch anything. (What runs before the script's first line is the interpreter's own start,
    # which no package can handle: not tested.)
    proc = subprocess.Popen([sys.executable, "-c", CONSOLE_SCRIPT, "distance", str(big_grid), "-s", "0",
                             "--solver", "clarabel", "-o", str(tmp_path / "d.ply")], stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, env=dict(os.environ, PYTHONPATH=str(SRC)), start_new_session=True)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None and not _numpy_loaded(proc.pid):
        time.sleep(0.002)
    time.sleep(delay)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    text = err.decode()
    assert proc.returncode == 130, text
    assert "Traceback" not in text and text.strip().splitlines()[-1] == "cvxgeodesic: interrupted", text
    assert os.listdir(tmp_path) == []


def _interrupted_import(monkeypatch, then):
    """build_parser's imports interrupted by a real SIGINT, which an extension module's import turns into ``then``."""
    import cvxgeodesic.cli as cli

    real = cli.build_parser

    def build_parser():
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(5)  # the handler raises within it
            raise AssertionError("SIGINT did not arrive")
        except KeyboardInterrupt:
            then()
        return real()

    monkeypatch.setattr(cli, "build_parser", build_parser)


def test_an_interrupt_turned_into_an_import_error_is_still_an_interrupt(sphere_file, tmp_path, capsys, monkeypatch):
    def import_error():
        raise ImportError("Error importing numpy: PyCapsule_Import could not import module 'datetime'")

    _interrupted_import(monkeypatch, import_error)
    rc, err = run(["distance", sphere_file, "-s", "0", "--method", "dijkstra", "-q", "-o", tmp_path / "d.npy"], capsys)
    assert rc == 130 and err == ["cvxgeodesic: interrupted"]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # restored


def test_an_interrupt_that_an_import_swallowed_still_stops_the_command(sphere_file, tmp_path, capsys, monkeypatch):
    _interrupted_import(monkeypatch, lambda: None)  # `try: import optional; except ImportError: pass`
    rc, err = run(["distance", sphere_file, "-s", "0", "--method", "dijkstra", "-q", "-o", tmp_path / "d.npy"], capsys)
    assert rc == 130 and err == ["cvxgeodesic: interrupted"] and os.listdir(tmp_path) == []


# ----------------------------------------------------------------------------------------------------------------
# 6. bad arguments and unwritable folders before any solve
# ----------------------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("command", ["distance", "view"])
def test_a_zero_slice_normal_is_refused_before_solving(tet_file, tmp_path, capsys, no_solve, command):
    out = ["-o", tmp_path / "d.npy", "--png", tmp_path / "d.png"] if command == "distance" else \
        ["--screenshot", tmp_path / "v.png"]
    rc, err = run([command, tet_file, "-s", "0", "--slice-normal", "0,0,0", *out], capsys)
    assert rc == 2 and err == ["cvxgeodesic: error: --slice-normal 0,0,0: the normal of the slice must not be zero "
                               "(e.g. 0,0,1)"]


@pytest.fixture
def not_a_folder(tmp_path) -> Path:
    # a folder under a regular file cannot be created, by root either (chmod does not stop root)
    plain = tmp_path / "plain"
    plain.write_text("x")
    return plain / "sub"


def test_compare_and_demo_check_the_out_folder_before_solving(sphere_file, not_a_folder, capsys, no_solve):
    for args in (["compare", sphere_file, "-s", "0", "--methods", "dijkstra", "--out", not_a_folder],
                 ["demo", "--out", not_a_folder]):
        rc, err = run(args, capsys)
        assert rc == 2 and err == [f"cvxgeodesic: error: --out {not_a_folder} cannot be created: "
                                   f"{not_a_folder.parent} is a file"], err
    rc, err = run(["compare", sphere_file, "-s", "0", "--out", not_a_folder.parent], capsys)
    assert rc == 2 and err == [f"cvxgeodesic: error: --out {not_a_folder.parent} is a file, not a folder"]


def test_a_folder_that_takes_no_files_is_refused_before_solving(sphere_file, tet_file, tmp_path, capsys, no_solve,
                                                                monkeypatch):
    # a read-only folder (or file system): as root, chmod 555 would not stop the writes, so the probe fails here
    def read_only(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(atomic.tempfile, "mkstemp", read_only)
    out = tmp_path / "ro"
    out.mkdir()
    for args in (["compare", sphere_file, "-s", "0", "--methods", "dijkstra", "--out", out],
                 ["compare", tet_file, "-s", "0", "--methods", "dijkstra", "--out", out],
                 ["demo", "--out", out]):
        rc, err = run(args, capsys)
        assert rc == 2 and err == [f"cvxgeodesic: error: --out {out}: cannot write files in it (Permission denied)"]
    rc, err = run(["demo", "--out", out / "new"], capsys)
    assert rc == 2 and err == [f"cvxgeodesic: error: --out {out / 'new'}: cannot be created in {out} "
                               "(Permission denied)"]


def test_the_python_entry_points_check_their_folder_first(sphere_file, not_a_folder, no_solve):
    from cvxgeodesic.compare import run_compare
    from cvxgeodesic.demo import run_demo

    with pytest.raises(ParameterError, match=re.escape(f"out_dir {not_a_folder} cannot be created")):
        run_demo(not_a_folder)
    with pytest.raises(ParameterError, match="out_dir"):
        run_compare(cg.icosphere(1), 0, "dijkstra", not_a_folder)
    with pytest.raises(ParameterError, match="out_dir"):
        run_compare(cg.tet_box(1), 0, "dijkstra", not_a_folder)


# ---------------------------------------------------------------------------------------------------------------
# a Ctrl-C that a ctypes callback swallows (threadpoolctl's library discovery) still stops the command
# ---------------------------------------------------------------------------------------------------------------
def _swallowed_sigint() -> None:
    """SIGINT delivered while a ctypes callback runs: its handler's KeyboardInterrupt is lost there."""
    import ctypes
    import signal as _signal

    @ctypes.CFUNCTYPE(None)
    def callback() -> None:
        os.kill(os.getpid(), _signal.SIGINT)
        for _ in range(1000):  # the handler runs at one of these bytecodes, inside the callback
            pass

    callback()


def test_a_ctrl_c_swallowed_by_a_ctypes_callback_stops_the_matrix(tmp_path, monkeypatch, capsys):
    """Seen in a loaded run: the interrupt landed in threadpoolctl's dl_iterate_phdr callback, was printed as
    'Exception ignored on calling ctypes callback function', and the 320-row matrix ran to its end (exit 0)."""
    from cvxgeodesic import _threads
    from cvxgeodesic.cli import main

    mesh = cg.icosphere(2)
    path = cg.save_distance(tmp_path / "s.ply", mesh, np.zeros(mesh.n_vertices))
    calls = {"n": 0}
    real = _threads.pool_limits

    def limits_with_a_swallowed_interrupt(*args, **kwargs):
        calls["n"] += 1
        if calls["n"] == 1:  # the matrix's one thread limit, around all its rows
            _swallowed_sigint()
        return real(*args, **kwargs)

    monkeypatch.setattr(_threads, "pool_limits", limits_with_a_swallowed_interrupt)
    out = tmp_path / "D.npy"
    code = main(["matrix", str(path), "-s", ",".join(map(str, range(0, 160, 4))), "--method", "dijkstra", "-o",
                 str(out), "-q"])
    assert calls["n"] >= 1
    assert code == 130 and not out.exists()
    assert capsys.readouterr().err.strip().endswith("cvxgeodesic: interrupted")


# ---------------------------------------------------------------------------------------------------------------
# found in review: symbolic links, set-id bits, an ignored SIGTERM
# ---------------------------------------------------------------------------------------------------------------
def test_a_symlinked_output_is_replaced_without_its_targets_metadata(tmp_path):
    """The rename replaces the link itself: the target's mode (here set-uid 4755) must not reach the new file."""
    from cvxgeodesic._atomic import atomic_write

    target = tmp_path / "program"
    target.write_bytes(b"#!/bin/sh\n")
    os.chmod(target, 0o4755)
    link = tmp_path / "out.npy"
    link.symlink_to(target)
    atomic_write(link, lambda fh: fh.write(b"data"))
    assert not link.is_symlink() and link.read_bytes() == b"data"
    assert stat.S_IMODE(link.stat().st_mode) & 0o7000 == 0
    assert target.read_bytes() == b"#!/bin/sh\n" and stat.S_IMODE(target.stat().st_mode) == 0o4755


def test_set_id_bits_of_a_replaced_file_are_not_copied(tmp_path):
    from cvxgeodesic._atomic import atomic_write

    out = tmp_path / "d.npy"
    out.write_bytes(b"old")
    os.chmod(out, 0o6750)
    atomic_write(out, lambda fh: fh.write(b"new"))
    assert stat.S_IMODE(out.stat().st_mode) == 0o750


def test_an_ignored_sigterm_stays_ignored():
    import signal as _signal

    from cvxgeodesic.cli._common import Signals as _Signals

    previous = _signal.signal(_signal.SIGTERM, _signal.SIG_IGN)
    try:
        with _Signals():
            assert _signal.getsignal(_signal.SIGTERM) is _signal.SIG_IGN
    finally:
        _signal.signal(_signal.SIGTERM, previous)


def test_batch_checks_the_range_of_m_once_before_any_mesh(tmp_path):
    """m above validation.MAX_M failed every mesh of a Python run_batch one by one (the CLI checked it)."""
    from cvxgeodesic.batch import run_batch

    path = cg.save_distance(tmp_path / "a.ply", cg.icosphere(1), np.zeros(42))
    with pytest.raises(cg.ParameterError, match=r"m = 1e\+?7 is outside the supported range"):
        run_batch([path], [0], tmp_path / "out", m=1e7, progress=False)
    assert not (tmp_path / "out").exists()


def test_batch_refuses_a_read_only_output_before_any_solve(tmp_path):
    """Found in review: a read-only OUT/<stem>.ply was refused only after its mesh was solved, with a message
    naming a keyword batch does not take."""
    from cvxgeodesic.batch import run_batch

    path = cg.save_distance(tmp_path / "a.ply", cg.icosphere(1), np.zeros(42))
    out = tmp_path / "out"
    out.mkdir()
    (out / "a.ply").write_bytes(b"kept")
    os.chmod(out / "a.ply", 0o444)
    with pytest.raises(cg.ParameterError, match=r"a.ply is read-only .*make it writable \(chmod u\+w\) first"):
        run_batch([path], [0], out, method="dijkstra", progress=False, force=True)
    assert (out / "a.ply").read_bytes() == b"kept" and not (out / "a.json").exists()
