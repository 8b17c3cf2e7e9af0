"""Ctrl-C in the first milliseconds of the command (issue 41): while the package and the command line's modules
load, before ``cli.main`` installs its handlers, a SIGINT printed a ``KeyboardInterrupt`` traceback.

The package's ``__init__`` installs a handler first thing in the command's process (``_install_early``). The
tests send SIGINT at chosen import points through a ``sitecustomize`` hook (deterministic), and immediately after
the start (as a user would); what comes before the package's first line is Python's own start-up, which no package
code can reach: a traceback there (``site``, ``runpy``) is told apart from ours by its frames.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
from pathlib import Path

import pytest

import cvxgeodesic as cg

SRC = str(Path(cg.__file__).resolve().parents[1])

#: Installed by ``sitecustomize`` (run by ``site`` at start-up, before the command's imports): SIGINT to the
#: process when the module named by CVXGEODESIC_TEST_KICK is about to be imported.
KICK = """
import os, signal, sys

class _Kick:
    def find_spec(self, name, path=None, target=None):
        if name == os.environ.get("CVXGEODESIC_TEST_KICK"):
            sys.meta_path.remove(self)
            os.kill(os.getpid(), signal.SIGINT)  # its handler runs at the import's next bytecode
        return None

sys.meta_path.insert(0, _Kick())
"""

#: A console script as pip writes it (``bin/cvxgeodesic``).
SCRIPT = """import re
import sys
from cvxgeodesic.cli import main
if __name__ == "__main__":
    sys.argv[0] = re.sub(r"(-script\\.pyw|\\.exe)?$", "", sys.argv[0])
    sys.exit(main())
"""


@pytest.fixture(scope="module")
def launch(tmp_path_factory):
    """``launch(form, kick=None, at_once=False)``: ``distance`` on a small mesh, started as the console script or
    with ``python -m``; SIGINT at the import of the module ``kick``, or right after the start; returns
    ``(returncode, stderr)``."""
    root = tmp_path_factory.mktemp("early")
    (root / "hook").mkdir()
    (root / "hook" / "sitecustomize.py").write_text(KICK)
    (root / "bin").mkdir()
    (root / "bin" / "cvxgeodesic").write_text(SCRIPT)
    mesh = cg.icosphere(2)
    path = root / "sphere.obj"
    path.write_text("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in mesh.V.tolist())
                    + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in mesh.F.tolist()))
    args = ["distance", str(path), "-s", "0", "-o", str(root / "d.npy")]

    def run(form: str, kick: str | None = None, *, at_once: bool = False) -> tuple[int, str]:
        env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(root / "hook"), SRC]), CVXGEODESIC_THREADS="1")
        env.pop("CVXGEODESIC_TEST_KICK", None)
        if kick is not None:
            env["CVXGEODESIC_TEST_KICK"] = kick
        head = [sys.executable, "-m", "cvxgeodesic.cli"] if form == "-m" else [sys.executable,
                                                                              str(root / "bin" / "cvxgeodesic")]
        proc = subprocess.Popen([*head, *args], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env)
        if at_once:
            proc.send_signal(signal.SIGINT)
        err = proc.communicate(timeout=120)[1].decode(errors="replace")
        return proc.returncode, err

    return run


# the package's first module, the modules of the command line, a standard module the command line imports
POINTS = ["cvxgeodesic._threads", "cvxgeodesic.errors", "cvxgeodesic.cli", "cvxgeodesic.cli._common", "argparse"]


@pytest.mark.parametrize("form", ["script", "-m"])
@pytest.mark.parametrize("point", POINTS)
def test_ctrl_c_while_the_command_loads_is_one_line_and_130(launch, form, point):
    returncode, err = launch(form, point)
    assert "Traceback" not in err and returncode == 130, (returncode, err)
    assert err.strip().splitlines() == ["cvxgeodesic: interrupted"], err


def test_the_hook_reaches_python_before_the_package(launch):
    """The hook works: a SIGINT as the package is about to be imported, before its first line, is Python's
    KeyboardInterrupt with its traceback: what no handler of the package can reach."""
    returncode, err = launch("script", "cvxgeodesic")  # the package itself: before its first line runs
    assert "KeyboardInterrupt" in err and returncode in (1, -signal.SIGINT), (returncode, err)


def _our_frames(err: str) -> list[str]:
    """The traceback lines that point into cvxgeodesic's files."""
    return [ln for ln in err.splitlines() if re.search(r'File ".*cvxgeodesic', ln)]


@pytest.mark.parametrize("form", ["script", "-m"])
def test_ctrl_c_right_after_the_start(launch, form):
    """As a user would: SIGINT at once, a few times. Before Python installs its own handler the process just ends
    (by SIGINT: a shell shows 130); in Python's start-up (site, runpy) Python prints its traceback; from the
    package's first line on, the command's line and 130. Never a traceback through the package."""
    for _ in range(6):
        returncode, err = launch(form, at_once=True)
        assert not _our_frames(err), err
        if "Traceback" not in err:
            assert returncode in (130, -signal.SIGINT), (returncode, err)
            assert err.strip() in ("", "cvxgeodesic: interrupted"), err


def test_a_python_session_keeps_its_ctrl_c():
    """Only the command's process gets the early handler: ``import cvxgeodesic`` in a program leaves SIGINT alone."""
    code = "import signal, cvxgeodesic; print(signal.getsignal(signal.SIGINT) is signal.default_int_handler)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60,
                         env=dict(os.environ, PYTHONPATH=SRC))
    assert out.stdout.strip() == "True", out.stderr


def test_the_command_line_takes_over_from_the_early_handler():
    """``main``'s handlers replace the early one (which exits at once, without the ``finally`` blocks that remove
    temporary files) for the command's duration, and put it back after."""
    from cvxgeodesic import _interrupted_early
    from cvxgeodesic.cli._common import Signals

    previous = signal.signal(signal.SIGINT, _interrupted_early)
    try:
        with Signals():
            assert getattr(signal.getsignal(signal.SIGINT), "cvxgeodesic_stops_solves", False)
        assert signal.getsignal(signal.SIGINT) is _interrupted_early
    finally:
        signal.signal(signal.SIGINT, previous)
