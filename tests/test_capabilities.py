"""The capability table (cvxgeodesic.capabilities): its names are the solvers', every rule refuses something, the
messages name what is supported, and docs/capabilities.md holds the generated table."""

from __future__ import annotations

import itertools
from pathlib import Path

import pytest

from cvxgeodesic import capabilities as cap
from cvxgeodesic.baselines import BASELINES
from cvxgeodesic.errors import ParameterError, SourceError
from cvxgeodesic.formulations import FORMULATIONS
from cvxgeodesic.operators import ENERGIES_BY_DIM
from cvxgeodesic.operators.squared_energy import SQUARED_ENERGIES

DOC = Path(__file__).resolve().parents[1] / "docs" / "capabilities.md"


def _cells():
    for method, dim, order, medium, multires, smoothing, resolution in itertools.product(
            cap.METHODS, cap.DIMS, cap.ORDERS, cap.MEDIA, (False, True), (False, True), (False, True)):
        for source in (None, *cap.SOURCE_KINDS):
            yield method, {"dim": dim, "order": order, "medium": medium, "source": source, "multires": multires,
                           "smoothing": smoothing, "resolution": resolution}


def test_the_table_names_the_solvers_methods():
    assert cap.FORMULATION_METHODS == tuple(FORMULATIONS)
    assert cap.BASELINE_METHODS == tuple(BASELINES)
    # what the solvers implement today, read from their own constants
    assert set(cap.methods_for(2)) == set(cap.METHODS)
    assert cap.methods_for(3) == (*(k for k, (_, e) in FORMULATIONS.items() if e in (None, *ENERGIES_BY_DIM[3])),
                                  "dijkstra", "heat")
    assert set(cap.methods_for(2, 2)) == {"qclp", *(f"qcqp-{e}" for e in SQUARED_ENERGIES)}
    assert cap.methods_for(3, 2) == ("qclp",)
    assert cap.methods_for(2, 1, "cost") == (*FORMULATIONS, "dijkstra")


def test_every_rule_refuses_some_cell_and_nothing_else_does():
    seen = {cap.refusal(method, **cell) for method, cell in _cells()}
    assert seen - {None} == set(cap.RULES)


def test_refusals_follow_the_axes_in_order():
    # a surface method at order 2 in a volume: the dimension is the reason, not the order
    assert cap.refusal("fmm", dim=3, order=2).axis == "method"
    assert cap.refusal("heat", dim=3, order=2, medium="cost").axis == "order"
    assert cap.refusal("qclp", dim=2) is None and cap.supported("heat", dim=3, source="point")
    # smoothing: a smoothed order-2 method takes no medium, its LP (m = 0) does
    assert not cap.supported("qcqp-hessian", dim=2, order=2, medium="metric")
    assert cap.supported("qcqp-hessian", dim=2, order=2, medium="metric", smoothing=False)


def test_check_raises_the_library_errors_naming_what_is_supported():
    with pytest.raises(ParameterError, match=r"^method 'exact' does not apply to tetrahedral meshes \(it is a surface "
                                             r"algorithm\); on a volume use one of lclp, .*, dijkstra, heat$"):
        cap.check("exact", dim=3)
    with pytest.raises(ParameterError, match=r"^order=2 is implemented for qclp on tetrahedral meshes, not for "
                                             r"'qcqp-laplacian' \(the order-2 smoothness energies are implemented on "
                                             r"surfaces only; docs/order2.md\)$"):
        cap.check("qcqp-laplacian", dim=3, order=2)
    with pytest.raises(SourceError, match=r"^method 'heat' cannot take point or curve sources on a surface "
                                          r"\(potpourri3d's heat method takes vertex sources only\); methods that "
                                          r"can: lclp, .*, qcqp-hessian, dijkstra, fmm, exact$"):
        cap.check("heat", dim=2, sources=["vertex", "point"])
    with pytest.raises(SourceError, match=r"^multires cannot take point, curve or boundary sources \(multires takes "
                                          r"vertex sources only"):
        cap.check("qclp", dim=2, multires=True, sources=["boundary"])
    with pytest.raises(ParameterError, match="not implemented with multires"):
        cap.check("qclp", dim=2, multires=True, medium="cost")
    cap.check("heat", dim=3, sources=["point", "boundary faces", "vertex"])  # every volume source


def test_the_docs_hold_the_generated_table():
    if not DOC.is_file():
        pytest.skip("needs the source checkout")
    text = DOC.read_text(encoding="utf-8")
    begin, end = "<!-- begin table -->\n", "<!-- end table -->"
    assert text[text.index(begin) + len(begin):text.index(end)] == cap.markdown_table(), (
        "docs/capabilities.md is out of date: paste cvxgeodesic.capabilities.markdown_table() between its markers")


def test_the_markdown_table_has_a_row_per_method_and_dimension_and_every_reason():
    table = cap.markdown_table()
    for method in cap.METHODS:
        assert table.count(f"| `{method}` |") == 2
    for rule in cap.RULES:
        assert rule.reason in table
    assert "| `qcqp-hessian` | yes | yes | order 1, order 2 with m = 0 [" in table


def test_help_text_lists_each_dimension():
    text = cap.help_text()
    assert "triangle meshes: methods lclp," in text and "exact" in text
    assert "tetrahedral meshes: methods lclp, lcqp-dirichlet, lcqp-laplacian, qclp, qcqp-dirichlet, qcqp-laplacian, " \
           "dijkstra, heat; order 2: qclp; cost/metric: none" in text


def test_source_kinds_of_resolved_sets_in_both_dimensions():
    import cvxgeodesic as cg
    from cvxgeodesic.mesh.tet_generate import tet_box
    from cvxgeodesic.sources import BoundaryFaces, VolumePoint, resolve_sources
    from cvxgeodesic.sources import resolve_sources as resolve_tet_sources

    plane, box = cg.grid_plane(4), tet_box(2)
    p = cg.SurfacePoint(3, [0.2, 0.3, 0.5])
    for sources, kinds in [(0, {"vertex"}), ([p, 2], {"point", "vertex"}), ("boundary", {"boundary"}),
                           (cg.SurfaceCurve([p, cg.SurfacePoint(9, [0.3, 0.3, 0.4])]), {"curve"})]:
        assert cap.source_kinds(resolve_sources(plane, sources)) == kinds
    for sources, kinds in [([0, 4], {"vertex"}), ([VolumePoint(0, [0.25] * 4), 3], {"point", "vertex"}),
                           ("boundary", {"boundary"}), (BoundaryFaces([0, 1]), {"boundary faces"})]:
        assert cap.source_kinds(resolve_tet_sources(box, sources)) == kinds


def test_the_command_line_help_shows_the_table_of_each_dimension(capsys):
    # the CLI's top-level help reads the capability table, not a copy of it
    from cvxgeodesic.cli import build_parser

    text = build_parser().format_help()
    assert cap.help_text() in text
    assert "triangle meshes: methods" in text and "tetrahedral meshes: methods" in text
