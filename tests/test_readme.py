"""The README's Python examples run, and the quick start prints what its comments say."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"
pytestmark = pytest.mark.skipif(not README.is_file(), reason="needs the source checkout")


def _python_blocks() -> list[str]:
    return re.findall(r"```python\n(.*?)```", README.read_text(encoding="utf-8"), flags=re.S)


def test_readme_examples_run_and_print_what_they_say(tmp_path):
    blocks = _python_blocks()
    assert len(blocks) >= 2
    # the comment after each print(...) of the quick start is its output
    expected = [m.group(1).strip() for m in re.finditer(r"^print\(.*\)\s+# (.*)$", blocks[0], flags=re.M)]
    assert len(expected) == 2
    script = tmp_path / "readme_examples.py"
    script.write_text("\n".join(blocks), encoding="utf-8")  # later blocks use the first one's mesh
    env = {**os.environ, "CVXGEODESIC_THREADS": "1", "PYTHONWARNINGS": "ignore"}
    res = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True, timeout=300,
                         env=env)
    assert res.returncode == 0, res.stderr[-2000:]
    assert res.stdout.splitlines() == expected
    assert (tmp_path / "sphere_distance.ply").is_file()
