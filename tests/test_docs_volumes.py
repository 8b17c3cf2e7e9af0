"""docs/volumes.md runs as written: its Python blocks print what their comments say and write the picture it shows."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from test_tutorial import _env

PAGE = Path(__file__).resolve().parents[1] / "docs" / "volumes.md"
pytestmark = pytest.mark.skipif(not PAGE.is_file(), reason="needs the source checkout")


def test_python_blocks_print_what_their_comments_say(tmp_path):
    pytest.importorskip("meshio")  # save_distance writes a .vtu
    text = PAGE.read_text(encoding="utf-8")
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    expected = []
    for b in blocks:  # a comment after the call, or the lines of comments after a loop
        expected += [m.group(1).strip() for m in re.finditer(r"^print\(.*\)\s+# (.*)$", b, flags=re.M)]
        expected += [m.group(1).strip() for m in re.finditer(r"^# (order .*|heat .*)$", b, flags=re.M)]
    script = tmp_path / "volumes.py"
    script.write_text("\n".join(blocks), encoding="utf-8")
    res = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True, timeout=300,
                         env=_env())
    assert res.returncode == 0, res.stderr[-2000:]
    assert sorted(res.stdout.splitlines()) == sorted(expected)
    shown = re.findall(r"\(figures/(volumes_\w+\.png)\)", text)
    assert shown and all((tmp_path / name).is_file() for name in shown)
    assert all((PAGE.parent / "figures" / name).is_file() for name in shown)
    assert (tmp_path / "prism.vtu").is_file()
