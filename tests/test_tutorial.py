"""docs/tutorial.md runs as written: its Python blocks print what their comments say, its shell block prints the
transcript shown under it (times and iteration counts aside) and writes the files it names."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

TUTORIAL = Path(__file__).resolve().parents[1] / "docs" / "tutorial.md"
pytestmark = pytest.mark.skipif(not TUTORIAL.is_file(), reason="needs the source checkout")


def _blocks(kind: str) -> list[str]:
    return re.findall(rf"```{kind}\n(.*?)```", TUTORIAL.read_text(encoding="utf-8"), flags=re.S)


def _env() -> dict[str, str]:
    import cvxgeodesic as cg

    src = str(Path(cg.__file__).parents[1])  # the package under test (the checkout's src/)
    return {**os.environ, "CVXGEODESIC_THREADS": "1", "PYTHONWARNINGS": "ignore",
            "PYTHONPATH": os.pathsep.join([src, os.environ.get("PYTHONPATH", "")])}


def test_python_blocks_print_what_their_comments_say(tmp_path):
    blocks = _blocks("python")
    assert len(blocks) >= 4
    expected = [m.group(1).strip() for b in blocks for m in re.finditer(r"^print\(.*\)\s+# (.*)$", b, flags=re.M)]
    script = tmp_path / "tutorial.py"
    script.write_text("\n".join(blocks), encoding="utf-8")  # one session: later blocks use earlier names
    res = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True, timeout=300,
                         env=_env())
    assert res.returncode == 0, res.stderr[-2000:]
    assert res.stdout.splitlines() == expected
    shown = re.findall(r"\(figures/(tutorial_\w+\.png)\)", TUTORIAL.read_text(encoding="utf-8"))
    assert shown and all((tmp_path / name).is_file() for name in shown)
    assert all((TUTORIAL.parent / "figures" / name).is_file() for name in shown)


#: The progress lines a solve prints once it has run for PROGRESS_DELAY seconds: whether they appear depends on the
#: machine's speed and load (issue 34: the transcript test failed on a loaded machine), so the comparison drops them.
PROGRESS_LINE = re.compile(r"^\s+iteration\s+\d+\s+gap\s")


def _normalized(text: str) -> list[str]:
    text = re.sub(r"\d+\.\d+ s\b", "T s", text)  # times vary
    text = re.sub(r"\d+ iterations", "N iterations", text)
    return [line for line in text.strip().splitlines() if not PROGRESS_LINE.match(line)]


def test_the_transcript_comparison_ignores_progress_lines_only():
    from cvxgeodesic._verbose import progress_printer

    lines = []
    stream = type("S", (), {"write": lambda self, s: lines.append(s), "flush": lambda self: None})()
    progress_printer(stream, delay=0.0)(12, {"gap_rel": 3e-4, "res_primal": 1e-9, "res_dual": 3e-8})
    printed = "".join(lines)
    assert _normalized(f"spot.obj: 2930 vertices\n{printed}qclp via ipm: optimal") == [
        "spot.obj: 2930 vertices", "qclp via ipm: optimal"]


def test_shell_block_prints_the_transcript_and_writes_its_files(tmp_path):
    (commands,) = _blocks("sh")
    (transcript,) = _blocks("text")
    shim = f'cvxgeodesic() {{ "{sys.executable}" -m cvxgeodesic.cli "$@"; }}\npython() {{ "{sys.executable}" "$@"; }}\n'
    res = subprocess.run(["bash", "-e", "-c", shim + commands], cwd=tmp_path, capture_output=True, text=True,
                         timeout=300, env=_env())
    assert res.returncode == 0, res.stderr[-2000:]
    assert _normalized(res.stderr) == _normalized(transcript)
    for name in re.findall(r"(?:-o|--png) (\S+)", commands):
        assert (tmp_path / name).is_file(), name
