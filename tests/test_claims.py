"""Every time and accuracy figure of the user docs has an entry in ``benchmarks/claims.py``, which measures it.

A *figure* is a ratio (``3×``, ``2.3–4.1×``) next to a word about time or accuracy, a percentage next to
"error", or a range of iterations, in README.md or docs/*.md (not docs/dev/, the dated development logs, nor a
page a benchmark generates). The paragraph, list or table holding it (text between two blank lines) carries a
mark ``<!-- claim: ID ... -->`` naming entries of ``benchmarks/claims.CLAIMS`` for that page; each entry's text
is on its page; ``make claims`` prints a line for every entry, and docs/claims.md, its committed output, has
every entry and none outside its measured range.
"""

from __future__ import annotations

import importlib.util
import re
import sys
from pathlib import Path

import pytest

from test_docs import FENCE, ROOT
from test_time_claims import CLAIM, RATIO

DOCS = ROOT / "docs"
pytestmark = pytest.mark.skipif(not (ROOT / "benchmarks" / "claims.py").is_file(), reason="needs the source checkout")

NEAR = r"[^.;\n]{0,60}?"
#: a ratio with a word about time or accuracy after it ("38–45× its time", "5–11× lower mean error", "3× MMP")
RATIO_AFTER = re.compile(rf"(?:{RATIO})[^.;\n]{{0,25}}?(?:time|heat|order[ -]1|exact|MMP|error|accurate|faster|"
                         r"slower|costs?)", flags=re.I)
PERCENT = r"\d+(?:\.\d+)?(?:\s*[–-]\s*\d+(?:\.\d+)?)?\s*%"
ERROR = re.compile(rf"{PERCENT}{NEAR}\berrors?\b|\berrors?\b{NEAR}{PERCENT}", flags=re.I)
ITERATIONS = re.compile(r"\d+\s*[–-]\s*\d+\s+iterations|iterations[^.;\n]{0,30}?\d+\s*[–-]\s*\d+", flags=re.I)
MARK = re.compile(r"<!--\s*claim:\s*([\w\s,-]+?)\s*-->")


def _claims_module():
    spec = importlib.util.spec_from_file_location("claims", ROOT / "benchmarks" / "claims.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("claims", module)
    spec.loader.exec_module(module)
    return module


claims = _claims_module()


def _generated(text: str) -> bool:
    return "This page is generated" in text[:300]


def user_pages(root: Path = ROOT) -> list[Path]:
    """README.md and docs/*.md less the pages a benchmark writes."""
    pages = [root / "README.md", *sorted((root / "docs").glob("*.md"))]
    return [p for p in pages if p.is_file() and not _generated(p.read_text(encoding="utf-8"))]


def figures(block: str) -> list[str]:
    """The quoted figures of a paragraph, list or table."""
    found = [m.group(0) for rx in (CLAIM, RATIO_AFTER, ERROR, ITERATIONS) for m in rx.finditer(block)]
    return sorted(set(found), key=block.find)


def marks(block: str) -> list[str]:
    return [i for m in MARK.finditer(block) for i in re.split(r"[\s,]+", m.group(1)) if i]


def unmarked_figures(page: Path, registry, root: Path = ROOT) -> list[str]:
    """``page: figure`` for each figure whose block names no claim of ``registry`` quoted on ``page``."""
    name = page.relative_to(root).as_posix()
    ids = {c.id for c in registry if any(p == name for p, _ in c.where)}
    text = FENCE.sub("", page.read_text(encoding="utf-8"))
    out = []
    for block in re.split(r"\n\s*\n", text):
        found = figures(MARK.sub("", block))
        if found and not set(marks(block)) & ids:
            out += [f"{name}: …{f}…" for f in found]
    return out


def _norm(text: str) -> str:
    return " ".join(text.split())


def test_every_figure_names_its_claim():
    found = [f for page in user_pages() for f in unmarked_figures(page, claims.CLAIMS)]
    assert found == [], ("figures without a <!-- claim: ID --> mark naming an entry of benchmarks/claims.py "
                         "for their page:\n" + "\n".join(found))


def test_every_mark_names_an_entry_of_its_page():
    where = {c.id: {p for p, _ in c.where} for c in claims.CLAIMS}
    bad = []
    for page in [ROOT / "README.md", *sorted(DOCS.glob("*.md"))]:
        name = page.relative_to(ROOT).as_posix()
        for i in marks(page.read_text(encoding="utf-8")):
            if name not in where.get(i, set()):
                bad.append(f"{name}: claim {i!r}" + (" has no entry" if i not in where else " is not quoted there"))
    assert bad == []


def test_every_entry_is_quoted_and_marked_on_its_pages():
    bad = []
    for c in claims.CLAIMS:
        for page, text in c.where:
            body = (ROOT / page).read_text(encoding="utf-8")
            if _norm(text) not in _norm(body):
                bad.append(f"{c.id}: {page} no longer says {text!r}")
            if c.id not in marks(body):
                bad.append(f"{c.id}: {page} has no <!-- claim: {c.id} --> mark")
    assert bad == []


def test_every_entry_is_measured_or_a_dated_record():
    ids = [c.id for c in claims.CLAIMS]
    assert len(ids) == len(set(ids)), "duplicate claim ids"
    for c in claims.CLAIMS:
        if c.record:
            assert re.search(r"20\d\d-\d\d-\d\d", c.record), c.id
            assert re.search(r"`[^`]+`|no script|own code|report", c.record), c.id
        else:
            assert c.experiment in claims.EXPERIMENTS and c.value is not None, c.id


def test_the_output_has_a_line_per_entry():
    page = claims.report({}, True, {"date": "d"}, {})
    missing = [c.id for c in claims.CLAIMS if f"| `{c.id}` |" not in page]
    assert missing == []


def test_committed_output_covers_every_entry_and_none_is_outside():
    path = DOCS / "claims.md"
    text = path.read_text(encoding="utf-8")
    missing = [c.id for c in claims.CLAIMS if f"| `{c.id}` |" not in text]
    assert missing == [], "docs/claims.md is older than the registry: run make claims"
    for key in ("- date: 20", "- machine: ", "- load average", "- mode: "):
        assert key in text
    outside = [line.split("|")[1].strip() for line in text.splitlines() if line.rstrip().endswith("| OUTSIDE |")]
    assert outside == [], f"quoted figures outside their measured range: {outside}"


def test_verdict_rounds_as_the_page_does():
    c = claims.Claim("x", (("README.md", "2.3–4.1×"),), quoted=(2.3, 4.1))
    assert claims.verdict(c, {"a": 2.26, "b": 4.14}) == "inside"  # 2.3 and 4.1 once rounded
    assert claims.verdict(c, {"a": 2.26, "b": 4.16}) == "OUTSIDE"
    assert claims.verdict(c, {"a": 2.24}) == "OUTSIDE"
    assert claims.verdict(c, {}) == "not measured"
    measured, worst = claims.describe(c, {"kitten": 3.0, "horse": 6.5}, 2)
    assert measured.startswith("3–6.5× over 2 meshes (of 2 in this run)") and worst == "horse 6.5×"


def test_an_unmarked_figure_is_found(tmp_path):
    """Not vacuous: each kind of figure is found without a mark, none with one, and a mark of another page's
    entry does not count."""
    (tmp_path / "docs").mkdir()
    page = tmp_path / "README.md"
    page.write_text("# Speed\n\nFull rows take 38–45× its time.\n\nThe mean error is 2.1 %.\n\n"
                    "It takes 14–17 iterations.\n\nA cube has 6 faces.\n", encoding="utf-8")
    registry = [claims.Claim("a", (("README.md", "38–45×"),)), claims.Claim("b", (("docs/x.md", "2.1 %"),))]
    assert unmarked_figures(page, registry, tmp_path) == [
        "README.md: …38–45× its time…", "README.md: …error is 2.1 %…", "README.md: …14–17 iterations…"]
    page.write_text(page.read_text(encoding="utf-8").replace("its time.", "its time. <!-- claim: a -->")
                    .replace("2.1 %.", "2.1 %. <!-- claim: b -->"), encoding="utf-8")
    assert unmarked_figures(page, registry, tmp_path) == ["README.md: …error is 2.1 %…",
                                                          "README.md: …14–17 iterations…"]
