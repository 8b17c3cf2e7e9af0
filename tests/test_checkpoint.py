"""What ``distance_matrix`` reads back from a checkpoint (``checkpoint=``, the CLI's ``OUTPUT.partial.npz``).

A checkpoint's rows are returned as results without being solved again, so the file is read as strictly as a mesh
file (every entry checked: a column index of 10^9 crashed ``toarray()`` with a segmentation fault) and trusted as
ssh trusts a key (a regular file, not a link, of this user, writable by no one else). A checkpoint that cannot be
written does not lose the finished matrix; one made with the same values typed differently is resumed.
"""

from __future__ import annotations

import errno
import io
import os
import re
import signal
import stat
import sys
import warnings
from types import SimpleNamespace

import numpy as np
import pytest
import scipy.sparse as sp

import cvxgeodesic as cg
from conftest import shared_mesh_path
from cvxgeodesic import rows
from cvxgeodesic.cli import main
from cvxgeodesic.errors import CheckpointWarning, ParameterError

posix_only = pytest.mark.skipif(os.name != "posix", reason="POSIX owners, modes, FIFOs and O_NOFOLLOW")


@pytest.fixture(scope="module")
def ico3():
    return cg.icosphere(3)


@pytest.fixture
def alarm():
    """A test that would block (a FIFO read) fails after 20 s instead of hanging the suite."""
    if not hasattr(signal, "SIGALRM"):
        yield
        return

    def timeout(*_):
        raise TimeoutError("blocked")

    old = signal.signal(signal.SIGALRM, timeout)
    signal.alarm(20)
    yield
    signal.alarm(0)
    signal.signal(signal.SIGALRM, old)


def _rewrite(path, **changes):
    """The checkpoint ``path`` with some entries replaced (None: removed), mode 600 as the library writes it."""
    with np.load(path) as z:
        data = {k: z[k] for k in z.files}
    data.update(changes)
    np.savez(path, **{k: v for k, v in data.items() if v is not None})
    os.chmod(path, 0o600)


def _entries(path):
    with np.load(path) as z:
        return {k: z[k] for k in z.files}


# ---- the contents ----

def _sparse_cases(d):
    cols, vals, lengths = d["cols"], d["vals"], d["lengths"]
    dup = cols.copy()
    dup[2] = dup[1]
    return {
        "column 1e9 (was a segmentation fault)": ({"cols": np.where(np.arange(cols.size) == 3, 10**9, cols)},
                                                  r"column 1000000000 at entry 3 of 'cols', outside \[0, 642\)"),
        "negative column": ({"cols": np.where(np.arange(cols.size) == 0, -1, cols)}, r"column -1 at entry 0"),
        "repeated column": ({"cols": dup}, r"columns of a row repeated or out of order"),
        "NaN distance": ({"vals": np.where(np.arange(vals.size) == 4, np.nan, vals)}, r"distance nan at \(4,\)"),
        "negative distance": ({"vals": -vals}, r"distance -"),
        "inf in a sparse row": ({"vals": np.full(vals.size, np.inf)}, r"distance inf at \(0,\); distances are "
                                                                      r"finite and ≥ 0"),
        "float32 values": ({"vals": vals.astype(np.float32)}, r"'vals' are int64, int64, float32"),
        "lengths too long": ({"lengths": lengths + 1}, r"row lengths summing to"),
        "no cols": ({"cols": None}, r"no 'cols' entry"),
        "repeated row": ({"index": np.array([0, 0])}, r"row numbers in 'index' repeated or out of order"),
        "row out of range": ({"index": np.array([0, 7])}, r"a row number outside \[0, 2\) in 'index'"),
        "float index": ({"index": np.array([0.0, 1.0])}, r"'index' is float64"),
        "format a string": ({"format": np.array("1")}, r"'format' is <U1"),
        "sparse an int": ({"sparse": np.array(1)}, r"'sparse' is int64"),
        "parameters a list": ({"parameters": np.array("[1, 2]")}, r"'parameters' is not the JSON text"),
        "parameters not JSON": ({"parameters": np.array("{x")}, r"'parameters' is not the JSON text"),
        "parameters bytes": ({"parameters": np.array(b"{}")}, r"'parameters' is not the JSON text"),
        "shape of one count": ({"shape": np.array([2])}, r"'shape' is int64 \(1,\)"),
    }


def test_every_damage_to_a_sparse_checkpoint_is_refused_naming_the_file(ico3, tmp_path):
    """The issue's case: icosphere(3), rows [0, 5], max_distance 0.5, then cols[3] = 10**9."""
    path = tmp_path / "c.npz"
    good = cg.distance_matrix(ico3, [0, 5], method="dijkstra", max_distance=0.5, progress=False, checkpoint=path)
    original = _entries(path)
    for what, (changes, match) in _sparse_cases(original).items():
        np.savez(path, **original)
        os.chmod(path, 0o600)
        _rewrite(path, **changes)
        before = path.read_bytes()
        with pytest.raises(ParameterError) as info:
            cg.distance_matrix(ico3, [0, 5], method="dijkstra", max_distance=0.5, progress=False, checkpoint=path)
        message = str(info.value)
        assert re.search(match, message), (what, message)
        assert message.startswith(f"checkpoint {path} is damaged"), (what, message)
        assert message.endswith("it was not used: delete it to start again, or give another path"), (what, message)
        assert path.read_bytes() == before, what  # refused: left as it was, for the user to look at
    np.savez(path, **original)
    os.chmod(path, 0o600)
    again = cg.distance_matrix(ico3, [0, 5], method="dijkstra", max_distance=0.5, progress=False, checkpoint=path)
    assert (again != good).nnz == 0


def test_every_damage_to_a_dense_checkpoint_is_refused(ico3, tmp_path):
    path = tmp_path / "c.npz"
    cg.distance_matrix(ico3, [0, 5], method="dijkstra", progress=False, checkpoint=path)
    original = _entries(path)
    R = original["rows"]
    cases = {
        "a (2, 700) matrix for 642 vertices": ({"rows": np.zeros((2, 700))},
                                              r"'rows' is float64 \(2, 700\), expected float64 \(2, 642\)"),
        "one row for two": ({"rows": R[:1]}, r"'rows' is float64 \(1, 642\)"),
        "NaN row": ({"rows": np.where(np.arange(642) == 9, np.nan, R)}, r"distance nan at \(0, 9\)"),
        "negative row": ({"rows": -R}, r"distance -[0-9.]+ at \(0, [0-9]+\); distances are ≥ 0 \(or inf\)"),
        "integer rows": ({"rows": R.astype(np.int64)}, r"'rows' is int64"),
        "no rows": ({"rows": None}, r"no 'rows' entry"),
    }
    for what, (changes, match) in cases.items():
        np.savez(path, **original)
        _rewrite(path, **changes)
        with pytest.raises(ParameterError, match=match) as info:
            cg.distance_matrix(ico3, [0, 5], method="dijkstra", progress=False, checkpoint=path)
        assert str(info.value).startswith(f"checkpoint {path} is damaged"), what


def test_inf_for_an_unreachable_vertex_is_resumed(tmp_path):
    """What the library writes for a vertex in no face (inf) is a valid row."""
    mesh = cg.icosphere(2)
    V = np.vstack([mesh.V, [[5.0, 5.0, 5.0]]])
    path = tmp_path / "c.npz"
    D = cg.distance_matrix((V, mesh.F), [0, 5], method="dijkstra", progress=False, checkpoint=path)
    assert np.isinf(_entries(path)["rows"][:, -1]).all()
    np.testing.assert_array_equal(cg.distance_matrix((V, mesh.F), [0, 5], method="dijkstra", progress=False,
                                                     checkpoint=path), D)


def test_cli_refuses_a_damaged_partial_file_without_a_crash_or_a_resume_line(tmp_path, capsys, monkeypatch):
    mesh = cg.icosphere(3)
    path = cg.save_distance(tmp_path / "ico3.ply", mesh, np.zeros(mesh.n_vertices))
    out, partial = tmp_path / "L.npz", tmp_path / "L.npz.partial.npz"
    args = ["matrix", str(path), "-s", "0,5,9", "--method", "dijkstra", "--max-distance", "0.5", "-o", str(out)]
    solve, calls = rows.LocalRows.solve, []

    def stopping(self, v):
        calls.append(v)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return solve(self, v)

    monkeypatch.setattr(rows.LocalRows, "solve", stopping)
    assert main(args) == 130 and rows.checkpoint_rows(partial) == (2, 3)
    capsys.readouterr()
    cols = _entries(partial)["cols"]
    _rewrite(partial, cols=np.where(np.arange(cols.size) == 3, 10**9, cols))
    calls.clear()
    assert main(args) == 2
    err = capsys.readouterr().err
    assert f"checkpoint {partial} is damaged" in err and "delete it to start again" in err, err
    assert "resuming from" not in err and "Traceback" not in err and calls == [], err
    assert partial.exists() and not out.exists()


# ---- whose file it is ----

@posix_only
def test_a_checkpoint_writable_by_others_is_refused_and_ours_are_private(ico3, tmp_path):
    path = tmp_path / "D.npy.partial.npz"
    cg.distance_matrix(ico3, [0, 5], method="dijkstra", progress=False, checkpoint=path)
    assert stat.S_IMODE(path.stat().st_mode) == 0o600  # written for its owner only
    _rewrite(path, rows=np.full((2, 642), 42.0))  # the planted file: every value 42.0
    for mode, who in ((0o666, "group and others"), (0o602, "others"), (0o620, "its group")):
        os.chmod(path, mode)
        with pytest.raises(ParameterError, match=re.escape(f"checkpoint {path} is writable by {who} (") +
                           r".*it was not used: if you made it and trust it, chmod go-w it to resume; else delete it"):
            cg.distance_matrix(ico3, [0, 5], method="dijkstra", progress=False, checkpoint=path)
    os.chmod(path, 0o644)  # the owner's own call: chmod go-w, and its rows are the answer
    assert (cg.distance_matrix(ico3, [0, 5], method="dijkstra", progress=False, checkpoint=path) == 42.0).all()


@posix_only
@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() != 0, reason="only root may give a file away")
def test_another_users_checkpoint_is_refused(ico3, tmp_path):
    path = tmp_path / "c.npz"
    cg.distance_matrix(ico3, [0, 5], method="dijkstra", progress=False, checkpoint=path)
    os.chown(path, 65534, 65534)  # nobody's, mode 600: only its owner could have written it
    with pytest.raises(ParameterError, match=re.escape(f"checkpoint {path} belongs to another user (uid 65534, you "
                                                       "are uid 0)")):
        cg.distance_matrix(ico3, [0, 5], method="dijkstra", progress=False, checkpoint=path)
    assert rows.checkpoint_rows(path) is None


@posix_only
def test_a_link_a_fifo_and_a_folder_are_refused_without_blocking(ico3, tmp_path, alarm):
    real = tmp_path / "real.npz"
    cg.distance_matrix(ico3, [0, 5], method="dijkstra", progress=False, checkpoint=real)
    link = tmp_path / "link.npz"
    link.symlink_to(real)
    with pytest.raises(ParameterError, match=re.escape(f"checkpoint {link} is a symbolic link")):
        cg.distance_matrix(ico3, [0, 5], method="dijkstra", progress=False, checkpoint=link)
    (tmp_path / "dangling.npz").symlink_to(tmp_path / "nothing")
    with pytest.raises(ParameterError, match="is a symbolic link"):
        cg.distance_matrix(ico3, [0, 5], method="dijkstra", progress=False, checkpoint=tmp_path / "dangling.npz")
    fifo = tmp_path / "fifo.npz"
    os.mkfifo(fifo)
    with pytest.raises(ParameterError, match=re.escape(f"checkpoint {fifo} is a FIFO, not a checkpoint file; it "
                                                       "was not used: give the path of a file")):
        cg.distance_matrix(ico3, [0, 5], method="dijkstra", progress=False, checkpoint=fifo)
    assert rows.checkpoint_rows(fifo) is None  # the CLI's count after Ctrl-C does not block either


def test_cli_refuses_a_planted_partial_file(tmp_path, capsys, monkeypatch):
    """The issue's sticky-folder case, as far as one user can play it: a world-writable partial file of 42.0."""
    if os.name != "posix":
        pytest.skip("POSIX modes")
    mesh = cg.icosphere(3)
    path = cg.save_distance(tmp_path / "ico3.ply", mesh, np.zeros(mesh.n_vertices))
    out, partial = tmp_path / "D.npy", tmp_path / "D.npy.partial.npz"
    args = ["matrix", str(path), "-s", "0,5,9", "--method", "dijkstra", "-o", str(out), "-q"]
    solve, calls = cg.GeodesicSolver.solve, []

    def stopping(self, s, **kw):
        calls.append(s)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return solve(self, s, **kw)

    monkeypatch.setattr(cg.GeodesicSolver, "solve", stopping)
    assert main(args) == 130 and rows.checkpoint_rows(partial) == (2, 3)
    _rewrite(partial, rows=np.full((2, mesh.n_vertices), 42.0))  # what another user wrote there
    os.chmod(partial, 0o666)
    capsys.readouterr()
    assert main(args) == 2
    err = capsys.readouterr().err
    assert f"checkpoint {partial} is writable by group and others (-rw-rw-rw-)" in err, err
    assert not out.exists() and partial.exists()
    os.chmod(partial, 0o600)  # the same file, were it private, would be resumed: what the refusal keeps out
    calls.clear()
    assert main(args) == 0 and (np.load(out)[:2] == 42.0).all()


# ---- writing it ----

def test_a_full_disk_while_checkpointing_returns_the_matrix_with_a_warning(ico3, tmp_path, monkeypatch):
    calls = []

    def full(path, write):
        calls.append(path)
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(rows, "atomic_write", full)
    monkeypatch.setattr(rows, "SAVE_EVERY", 0.0)  # a write attempt after every row
    path = tmp_path / "c.npz"
    with pytest.warns(CheckpointWarning, match=re.escape(f"could not be written to the checkpoint {path} (No space "
                                                         "left on device); the rows go on without it")):
        D = cg.distance_matrix(ico3, [0, 5, 9], method="dijkstra", progress=False, checkpoint=path)
    np.testing.assert_array_equal(D, cg.distance_matrix(ico3, [0, 5, 9], method="dijkstra", progress=False))
    assert len(calls) == 1  # tried once, not after every row


def test_cli_full_disk_while_checkpointing_still_writes_the_output(tmp_path, capsys, monkeypatch):
    mesh = cg.icosphere(2)
    path = cg.save_distance(tmp_path / "s.ply", mesh, np.zeros(mesh.n_vertices))
    monkeypatch.setattr(rows, "atomic_write", lambda *a: (_ for _ in ()).throw(OSError(errno.ENOSPC, "No space")))
    out = tmp_path / "D.npy"
    assert main(["matrix", str(path), "-s", "0,5", "--method", "dijkstra", "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert "cvxgeodesic: note: distance_matrix: the finished rows could not be written to the checkpoint" in err, err
    assert np.load(out).shape == (2, mesh.n_vertices)


def test_cli_writes_the_output_when_the_partial_file_cannot_be_removed(tmp_path, capsys, monkeypatch):
    """The issue's sticky folder: the run failed on unlinking the partial file after writing D.npy."""
    mesh = cg.icosphere(2)
    path = cg.save_distance(tmp_path / "s.ply", mesh, np.zeros(mesh.n_vertices))
    out, partial = tmp_path / "D.npy", tmp_path / "D.npy.partial.npz"
    unlink = type(partial).unlink

    def refuse(self, missing_ok=False):
        if self.name == partial.name:
            raise PermissionError(errno.EPERM, "Operation not permitted")
        return unlink(self, missing_ok=missing_ok)

    monkeypatch.setattr(type(partial), "unlink", refuse)
    assert main(["matrix", str(path), "-s", "0,5", "--method", "dijkstra", "-o", str(out)]) == 0
    assert (f"cvxgeodesic: note: {partial} could not be removed (Operation not permitted); delete it before another "
            "run") in capsys.readouterr().err
    assert np.load(out).shape == (2, mesh.n_vertices)


# ---- the same call, typed differently ----

def test_the_same_values_typed_differently_resume(ico3, tmp_path, monkeypatch):
    path = tmp_path / "c.npz"
    cg.distance_matrix(ico3, [0, 5], method="qclp", m=1.0, order=1, tol=1e-8, progress=False, checkpoint=path)
    solved = []
    monkeypatch.setattr(cg.GeodesicSolver, "solve", lambda self, s, **kw: solved.append(s))
    for kwargs in ({"method": "qclp", "m": 1}, {"method": "qclp", "m": np.float64(1.0)}, {"method": "QCLP"},
                   {"method": None}, {"method": "qclp", "order": np.int64(1), "tol": np.float64(1e-8)},
                   {"method": "qclp", "max_iter": np.int32(200), "solver": "AUTO", "normalization": "Area"}):
        D = cg.distance_matrix(ico3, [0, 5], progress=False, checkpoint=path, **kwargs)
        assert D.shape == (2, 642), kwargs
    assert solved == []
    with pytest.raises(ParameterError, match="other parameters.*m: 1.0 there, 1.5 here"):
        cg.distance_matrix(ico3, [0, 5], method="qclp", m=1.5, checkpoint=path)
    items = [0, 5]
    assert rows.fingerprint(ico3, items, {"cost": 2}) == rows.fingerprint(ico3, items, {"cost": np.float64(2.0)})
    assert rows.fingerprint(ico3, items, {"method": "qgdf"}) == rows.fingerprint(ico3, items,
                                                                              {"method": "lcqp-hessian"})
    assert rows.fingerprint(ico3, items, {"m": "1"}) != rows.fingerprint(ico3, items, {"m": 1.0})  # refused later


def test_resuming_is_said_once_the_checkpoint_is_accepted(ico3, tmp_path, capsys):
    path = tmp_path / "c.npz"
    cg.distance_matrix(ico3, [0, 5], method="dijkstra", progress=False, checkpoint=path)
    capsys.readouterr()
    with pytest.raises(ParameterError):
        cg.distance_matrix(ico3, [0, 6], method="dijkstra", checkpoint=path)
    assert "resuming" not in capsys.readouterr().err
    cg.distance_matrix(ico3, [0, 5], method="dijkstra", checkpoint=path)
    assert capsys.readouterr().err == f"resuming from {path}: 2 of 2 rows already done\n"


# ---- defaults and options of the rows ----

def test_rows_default_to_qclp_in_the_api_and_the_cli(tmp_path, capsys):
    mesh = cg.icosphere(2)
    np.testing.assert_array_equal(cg.distance_matrix(mesh, [0, 5], progress=False),
                                  cg.distance_matrix(mesh, [0, 5], method="qclp", progress=False))
    path = cg.save_distance(tmp_path / "s.ply", mesh, np.zeros(mesh.n_vertices))
    assert main(["matrix", str(path), "-s", "0,5", "-o", str(tmp_path / "D.npy")]) == 0
    assert "method qclp" in capsys.readouterr().err
    np.testing.assert_allclose(np.load(tmp_path / "D.npy"), cg.distance_matrix(mesh, [0, 5], progress=False),
                               rtol=1e-12, atol=0)
    with pytest.raises(SystemExit):
        main(["matrix", "-h"])
    assert "(default qclp," in " ".join(capsys.readouterr().out.split())


def test_cli_matrix_takes_order_tol_and_lam(tmp_path, capsys):
    mesh = cg.icosphere(2)
    path = cg.save_distance(tmp_path / "s.ply", mesh, np.zeros(mesh.n_vertices))
    out = tmp_path / "D.npy"
    assert main(["matrix", str(path), "-s", "0,5", "--method", "qcqp-dirichlet", "--order", "2", "--tol", "1e-6",
                 "--lam", "0.02", "-q", "-o", str(out)]) == 0
    ref = cg.distance_matrix(mesh, [0, 5], method="qcqp-dirichlet", order=2, tol=1e-6, lam=0.02, progress=False)
    np.testing.assert_allclose(np.load(out), ref, rtol=1e-12, atol=0)
    other = cg.distance_matrix(mesh, [0, 5], method="qcqp-dirichlet", progress=False)
    assert np.abs(ref - other).max() > 1e-4  # the options changed the rows
    for bad, match in ((["--tol", "0"], r"--tol must be a number in \(0, 1\), got 0.0"),
                       (["--tol", "2"], r"--tol must be a number in \(0, 1\)"),
                       (["--lam", "-1"], r"lam must be a finite number >= 0")):
        assert main(["matrix", str(tmp_path / "missing.ply"), "-s", "0", "-o", str(out), *bad]) == 2
        assert re.search(match, capsys.readouterr().err), bad  # before the (missing) mesh is read
    with pytest.raises(SystemExit):
        main(["matrix", str(path), "-s", "0", "--order", "3", "-o", str(out)])


# ---- progress off a terminal ----

def test_progress_off_a_terminal_is_a_plain_line_every_few_seconds():
    clock = SimpleNamespace(t=100.0)
    stream = io.StringIO()
    lines = rows.RowLines(1000, 0, "qclp", stream, delay=2.0, clock=lambda: clock.t)
    for _ in range(1000):  # 1,000 rows of 1/8 s (exact in binary: no rounding at the 10 s marks)
        clock.t += 0.125
        lines.update(1)
    lines.close()
    text = stream.getvalue()
    assert "\r" not in text and len(text) < 1000, len(text)  # tqdm wrote 45 KB for 1,000 rows to a file
    out = text.splitlines()
    assert out[0] == "qclp: rows 16/1000, 2 s, ~123 s left"  # after the delay
    assert out[1] == "qclp: rows 96/1000, 12 s, ~113 s left"  # then every LINE_EVERY = 10 s
    assert out[-1] == "qclp: rows 1000/1000, 125 s" and len(out) == 14, out
    quiet = io.StringIO()  # rows that end before the delay print nothing
    with rows.RowLines(10, 0, "qclp", quiet, delay=2.0, clock=lambda: clock.t) as fast:
        fast.update(10)
    assert quiet.getvalue() == ""
    resumed = io.StringIO()  # rows from a checkpoint count as done, not in the time per row
    with rows.RowLines(10, 5, "qclp", resumed, delay=0.0, clock=lambda: clock.t) as bar:
        clock.t += 2.0
        bar.update(1)
    assert resumed.getvalue() == "qclp: rows 5/10, 0 s\nqclp: rows 6/10, 2 s, ~8 s left\n"  # at once, then


def test_rows_progress_is_a_bar_in_a_terminal_and_lines_elsewhere(monkeypatch, capsys):
    from tqdm import tqdm

    assert isinstance(rows._row_bar(3, 0, "qclp", True), rows.RowLines)  # capsys: stderr is no terminal
    monkeypatch.setattr(sys, "stderr", SimpleNamespace(isatty=lambda: True, write=lambda s: None, flush=lambda: None))
    bar = rows._row_bar(3, 0, "qclp", True)
    try:
        assert isinstance(bar, tqdm)
    finally:
        bar.close()


# ---- the note of a patch ----

@pytest.mark.shared
def test_an_indefinite_energy_on_a_patch_is_said_of_the_patch():
    spot = cg.load_mesh(shared_mesh_path("spot.obj"))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        cg.distance_matrix(spot, [0], method="qcqp-hessian", max_distance=0.1 * spot.bbox_diagonal, progress=False)
        patch = [str(w.message) for w in caught]
        caught.clear()
        cg.GeodesicSolver(spot, "qcqp-hessian")  # the whole mesh's energy is PSD: no note
    assert patch == ["spot.obj (patch around a source): libigl's curved Hessian energy is indefinite on this "
                     "patch, not necessarily on the whole mesh; using the planar Hessian energy (Stein et al. 2018) "
                     "instead"], patch
    assert not [w for w in caught if issubclass(w.category, cg.IndefiniteEnergyWarning)]


def test_sparse_rows_read_back_keep_their_stored_zeros(ico3, tmp_path):
    """The source's 0 is a stored entry of its local row, also when the row comes from the checkpoint."""
    path = tmp_path / "c.npz"
    L = cg.distance_matrix(ico3, [0, 5], method="dijkstra", max_distance=0.5, progress=False, checkpoint=path)
    again = cg.distance_matrix(ico3, [0, 5], method="dijkstra", max_distance=0.5, progress=False, checkpoint=path)
    assert sp.issparse(again) and again.nnz == L.nnz and again[1, 5] == 0 and 5 in again[1].indices
