"""The report's caches (benchmarks/report.py, report_common.py): order-2 fields and the order-2 section carry the
order-2 code version, so changed order-2 code does not silently reuse stale results; order-1 keys are unchanged."""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

import pytest

import cvxgeodesic.problems.squared_distance as ep2

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"


@pytest.fixture(scope="module")
def bench():
    sys.path.insert(0, str(BENCH))
    try:
        yield importlib.import_module("report_common"), importlib.import_module("report")
    finally:
        sys.path.remove(str(BENCH))


def test_order1_keys_unchanged(bench):
    rc, _ = bench
    # the format the existing order-1 cache was written with: it must stay valid
    assert rc.field_key("spot", "qclp", 0, 1.0, 1, "area", "abc") == "spot__qclp__m-__s0__abc"
    assert rc.field_key("a/b", "qcqp-hessian", 3, 2.0, 1, "paper", "f") == "a+b__qcqp-hessian__npaper__m2__s3__f"


def test_order2_key_follows_the_code_version(bench, monkeypatch):
    rc, _ = bench
    key = rc.field_key("spot", "qclp", 0, 1.0, 2, "area", "abc")
    assert key == f"spot__qclp__o2v{ep2.ORDER2_CACHE_VERSION}__m-__s0__abc"
    monkeypatch.setattr(ep2, "ORDER2_CACHE_VERSION", ep2.ORDER2_CACHE_VERSION + 1)
    assert rc.field_key("spot", "qclp", 0, 1.0, 2, "area", "abc") != key
    assert rc.field_key("spot", "qclp", 0, 1.0, 1, "area", "abc") == "spot__qclp__m-__s0__abc"  # order 1 unaffected


def test_cached_order2_section_is_recomputed_after_a_version_bump(bench, monkeypatch, tmp_path):
    _, rep = bench
    (tmp_path / "fig.png").write_bytes(b"")
    data = {"figures": ["fig.png"], "code_version": ep2.ORDER2_CACHE_VERSION}
    assert rep.cached_section_ok("order2", data, tmp_path)
    assert not rep.cached_section_ok("order2", {"figures": ["fig.png"]}, tmp_path)  # cached before versions
    assert not rep.cached_section_ok("order2", {**data, "figures": ["gone.png"]}, tmp_path)
    assert rep.cached_section_ok("table2", {"figures": ["fig.png"]}, tmp_path)  # order-1 sections keep their caches
    monkeypatch.setattr(ep2, "ORDER2_CACHE_VERSION", ep2.ORDER2_CACHE_VERSION + 1)
    assert not rep.cached_section_ok("order2", data, tmp_path)


def test_report_main_stores_and_checks_the_order2_version(bench, monkeypatch, tmp_path):
    from conftest import shared_mesh_path

    _, rep = bench
    calls = []

    def fake_section(ctx, plan):
        calls.append(1)
        return {"value": len(calls), "figures": []}

    monkeypatch.setattr(rep, "SECTIONS", {"order2": fake_section})
    monkeypatch.setattr(rep, "render", lambda *a, **k: "")
    argv = ["--out", str(tmp_path / "out"), "--cache", str(tmp_path / "cache"),
            "--shared", str(Path(shared_mesh_path("bunny.obj")).parent)]
    assert rep.main(argv) == 0 and len(calls) == 1
    stored = rep.json.loads((tmp_path / "cache" / "sections" / "order2.json").read_text())
    assert stored["code_version"] == ep2.ORDER2_CACHE_VERSION
    assert rep.main(argv) == 0 and len(calls) == 1  # cached, same version: reused
    monkeypatch.setattr(ep2, "ORDER2_CACHE_VERSION", ep2.ORDER2_CACHE_VERSION + 1)
    assert rep.main(argv) == 0 and len(calls) == 2  # changed order-2 code: recomputed
