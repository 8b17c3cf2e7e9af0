"""The documentation's links lead somewhere, and the numbers it repeats agree with their one source."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
pytestmark = pytest.mark.skipif(not (ROOT / "README.md").is_file(), reason="needs the source checkout")

LINK = re.compile(r"(?<!!)\[[^\]]*\]\(([^)\s]+)\)")
FENCE = re.compile(r"^(```|~~~).*?^\1", flags=re.S | re.M)


def _pages() -> list[Path]:
    return [ROOT / "README.md", *sorted(DOCS.rglob("*.md"))]


def github_anchor(heading: str) -> str:
    """The anchor GitHub (and myst-parser's ``heading_anchors``) gives a markdown heading."""
    text = re.sub(r"[`*]", "", heading.strip()).lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(page: Path) -> set[str]:
    text = page.read_text(encoding="utf-8")
    included = re.match(r"```\{include\} (\S+)", text)  # a page that only includes another (docs/readme.md)
    if included:
        return anchors((page.parent / included.group(1)).resolve())
    text = FENCE.sub("", text)
    seen: dict[str, int] = {}
    out = set()
    for m in re.finditer(r"^#{1,6}\s+(.*?)\s*$", text, flags=re.M):
        slug = github_anchor(m.group(1))
        n = seen.get(slug, 0)
        seen[slug] = n + 1
        out.add(slug if n == 0 else f"{slug}-{n}")
    return out


def broken_links(page: Path, root: Path = ROOT) -> list[str]:
    text = FENCE.sub("", page.read_text(encoding="utf-8"))
    bad = []
    for target in LINK.findall(text):
        if re.match(r"[a-z]+:", target):  # http:, https:, mailto:
            continue
        path, _, anchor = target.partition("#")
        dest = (page.parent / path).resolve() if path else page
        if not dest.exists():
            bad.append(f"{page.relative_to(root)}: {target} (no such file)")
        elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
            bad.append(f"{page.relative_to(root)}: {target} (no such heading)")
    return bad


def test_anchor_rule_matches_github():
    assert github_anchor("Where issue 14's targets stand (2026-12-02, 01:25 to 01:41 UTC, quiet machine)") == \
        "where-issue-14s-targets-stand-2026-12-02-0125-to-0141-utc-quiet-machine"
    assert github_anchor("Solver benchmark: Clarabel, `ipm` and the heat method") == \
        "solver-benchmark-clarabel-ipm-and-the-heat-method"


def test_every_relative_link_resolves():
    bad = [b for page in _pages() for b in broken_links(page)]
    assert bad == []


def test_a_broken_link_is_found(tmp_path):
    page = tmp_path / "page.md"
    (tmp_path / "other.md").write_text("# Title\n\n## A section\n", encoding="utf-8")
    page.write_text("[ok](other.md#a-section) [gone](missing.md) [anchor](other.md#nothing)\n"
                    "```\n[in code](ignored.md)\n```\n", encoding="utf-8")
    assert broken_links(page, tmp_path) == ["page.md: missing.md (no such file)",
                                            "page.md: other.md#nothing (no such heading)"]


def test_user_docs_cite_no_tracker_issue():
    """Tracker issue numbers mean nothing to a user; the development notes under docs/dev may cite them."""
    pages = [ROOT / "README.md", *sorted(p for p in DOCS.glob("*.md") if p.name != "architecture.md")]
    found = [f"{p.relative_to(ROOT)}: {m.group(0)}" for p in pages
             for m in re.finditer(r"\b[Ii]ssues? \d+", FENCE.sub("", p.read_text(encoding="utf-8")))]
    assert found == []


def _order2_speed_range() -> tuple[int, int]:
    section = (DOCS / "order2.md").read_text(encoding="utf-8").split("\n## Speed\n", 1)[1].split("\n## ", 1)[0]
    bounds = [int(x) for r in re.findall(r"\|\s*(\d+(?:–\d+)?)×\s*\|", section) for x in r.split("–")]
    return min(bounds), max(bounds)


def test_readme_quotes_the_measured_order2_speed():
    """docs/order2.md's "Speed" table is where the order-2 timings live; the README quotes its range."""
    lo, hi = _order2_speed_range()
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert f"{lo}–{hi}×" in readme
    assert f"{lo}–{hi}×" in (DOCS / "order2.md").read_text(encoding="utf-8").split("\n## ", 1)[0]
