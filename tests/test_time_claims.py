"""Every claim in the user docs that one thing takes N× the time of another names the benchmark that prints it.

A *time claim* is a ratio (``3×``, ``1–11×``, ``2.9–6.6×``, ``N times faster``) written next to a word about
computing time (faster, slower, speed-up, costs, "the time of", "'s time", "takes"). It is *cited* when the
paragraph or table that holds it, or the section around it (from its heading to the next one), names a script
of ``benchmarks/`` (or ``make report``, which runs one), or when the paragraph links to a section of the docs
that does. The development logs (``docs/dev/``) are dated measurement records, outside this rule.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from test_docs import FENCE, ROOT, github_anchor

DOCS = ROOT / "docs"
pytestmark = pytest.mark.skipif(not (ROOT / "README.md").is_file(), reason="needs the source checkout")

RATIO = r"\d+(?:\.\d+)?(?:\s*[–-]\s*\d+(?:\.\d+)?)?\s*×(?!\s*\d)|\d+(?:\.\d+)?\s+times\s+(?:faster|slower)"
TIME_WORD = r"faster|slower|speed-?up|costs?\b|the time\b|time of\b|'s time\b|takes\b|took\b"
#: a time word within this many characters of a ratio, in the same sentence, makes a time claim
NEAR = 60
GAP = rf"[^.;\n]{{0,{NEAR}}}?"
CLAIM = re.compile(rf"(?:{TIME_WORD}){GAP}(?:{RATIO})|(?:{RATIO}){GAP}(?:{TIME_WORD})", flags=re.I)
CITATION = re.compile(r"benchmarks/[\w/.-]+\.py|make (?:report|bench)\b")
SECTION_LINK = re.compile(r"\]\(([\w./-]*\.md)?#([\w-]+)\)")
#: ratios next to a time word that are not about computing time (the reason beside each)
NOT_COMPUTE = {
    ("metrics.md", "takes 2.4× less time"),  # the travel time along a path in a medium, computed by the page's code
}


def _sections(text: str) -> list[tuple[str, str]]:
    """(anchor, text) of each part of a page between two headings (the part before the first: anchor "")."""
    parts = re.split(r"^(#{1,6}\s+.*)$", text, flags=re.M)
    out = [("", parts[0])]
    for heading, body in zip(parts[1::2], parts[2::2], strict=True):
        out.append((github_anchor(heading.lstrip("#")), heading + body))
    return out


def _cited_sections(page: Path) -> set[str]:
    text = FENCE.sub("", page.read_text(encoding="utf-8"))
    return {anchor for anchor, body in _sections(text) if CITATION.search(body)}


def uncited_claims(page: Path) -> list[str]:
    """The time claims of ``page`` that no benchmark backs, as ``file: claim``."""
    text = FENCE.sub("", page.read_text(encoding="utf-8"))
    # a page a benchmark writes (docs/results.md: benchmarks/report.py) prints every number on it
    generated = "This page is generated" in text[:300] and bool(CITATION.search(text[:1000]))
    out = []
    for _, section in _sections(text):
        for block in re.split(r"\n\s*\n", section):
            if generated or CITATION.search(block):
                continue
            linked = any(anchor in _cited_sections((page.parent / path).resolve() if path else page)
                         for path, anchor in SECTION_LINK.findall(block)
                         if (page.parent / path).resolve().is_file() or not path)
            if linked:
                continue
            for m in CLAIM.finditer(block):
                if not any(page.name == name and phrase in block for name, phrase in NOT_COMPUTE):
                    out.append(f"{page.relative_to(ROOT)}: …{m.group(0)}…")
    return out


def _user_pages() -> list[Path]:
    return [ROOT / "README.md", *sorted(DOCS.glob("*.md"))]


def test_every_time_claim_cites_its_benchmark():
    found = [claim for page in _user_pages() for claim in uncited_claims(page)]
    assert found == [], "time claims without the benchmark that prints them:\n" + "\n".join(found)


def test_an_uncited_claim_is_found(tmp_path, monkeypatch):
    """The check is not vacuous: a claim without a benchmark is reported, with one it is not, and a link to a
    section that names one counts."""
    page = tmp_path / "page.md"
    page.write_text("# Speed\n\nOrder 2 costs 1–11× the time of order 1 on scans.\n\n## Other\n\nIt is 3× faster.\n"
                    "\n## Linked\n\nIt is 2.5× slower ([Speed](#speed)).\n", encoding="utf-8")
    monkeypatch.setattr("test_time_claims.ROOT", tmp_path)
    assert uncited_claims(page) == ["page.md: …costs 1–11×…", "page.md: …3× faster…", "page.md: …2.5× slower…"]
    page.write_text(page.read_text(encoding="utf-8").replace("on scans.", "on scans (`benchmarks/order2.py`)."),
                    encoding="utf-8")
    assert uncited_claims(page) == ["page.md: …3× faster…"]  # the linked section cites one now
