"""The report's field cache keys (benchmarks/report_common.py): order-2 keys carry the order-2 code version."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

import cvxgeodesic.elements_p2 as ep2

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"


@pytest.fixture(scope="module")
def rc():
    spec = importlib.util.spec_from_file_location("report_common", BENCH / "report_common.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("report_common", mod)  # its dataclasses look their module up there
    spec.loader.exec_module(mod)
    return mod


def test_order1_keys_unchanged(rc):
    # the format the existing order-1 cache was written with: it must stay valid
    assert rc.field_key("spot", "qclp", 0, 1.0, 1, "area", "abc") == "spot__qclp__m-__s0__abc"
    assert rc.field_key("a/b", "qcqp-hessian", 3, 2.0, 1, "paper", "f") == "a+b__qcqp-hessian__npaper__m2__s3__f"


def test_order2_key_follows_the_code_version(rc, monkeypatch):
    key = rc.field_key("spot", "qclp", 0, 1.0, 2, "area", "abc")
    assert key == f"spot__qclp__o2v{ep2.ORDER2_CACHE_VERSION}__m-__s0__abc"
    monkeypatch.setattr(ep2, "ORDER2_CACHE_VERSION", ep2.ORDER2_CACHE_VERSION + 1)
    bumped = rc.field_key("spot", "qclp", 0, 1.0, 2, "area", "abc")
    assert bumped != key
    # order 1 does not depend on it
    assert rc.field_key("spot", "qclp", 0, 1.0, 1, "area", "abc") == "spot__qclp__m-__s0__abc"
