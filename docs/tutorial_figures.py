"""Make the pictures of a page: run the Python blocks of ``docs/tutorial.md`` (or ``docs/volumes.md``) and keep
the PNGs they write.

Run from the repository root (a minute at most; no other input)::

    python docs/tutorial_figures.py                    # docs/tutorial.md: tutorial_*.png
    python docs/tutorial_figures.py volumes            # docs/volumes.md: volumes_*.png
    python docs/tutorial_figures.py docs/metrics.md    # a page by its path: its ``metrics_*.png``

The blocks run in order in a temporary folder, as ``tests/test_tutorial.py`` runs them; every
``<page>_*.png`` they write is reduced to a 256-colour palette (a third of the size, the same picture) and
copied to ``docs/figures/``, where the page shows it.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

from PIL import Image

DOCS = Path(__file__).resolve().parent


def python_blocks(page: Path) -> list[str]:
    """The ```python blocks of a Markdown page, in order."""
    return re.findall(r"```python\n(.*?)```", page.read_text(encoding="utf-8"), flags=re.S)


def main(page: str | Path = "tutorial") -> None:
    """Run the page's Python blocks and copy the ``<stem>_*.png`` they write to docs/figures: ``page`` a name under
    docs/ (``"volumes"``) or a path (``docs/metrics.md``)."""
    page = Path(page) if str(page).endswith(".md") else DOCS / f"{page}.md"
    with tempfile.TemporaryDirectory() as tmp:
        script = Path(tmp) / f"{page.stem}.py"
        script.write_text("\n".join(python_blocks(page)), encoding="utf-8")
        path = os.pathsep.join([str(DOCS.parent / "src"), os.environ.get("PYTHONPATH", "")])
        env = {**os.environ, "PYTHONPATH": path}
        subprocess.run([sys.executable, str(script)], cwd=tmp, env=env, check=True)
        for png in sorted(Path(tmp).glob(f"{page.stem}_*.png")):
            target = DOCS / "figures" / png.name
            Image.open(png).convert("RGB").quantize(256).save(target, optimize=True)
            print(f"wrote {target.relative_to(DOCS.parent)} ({target.stat().st_size // 1024} KiB)")


if __name__ == "__main__":
    main(*sys.argv[1:2])
