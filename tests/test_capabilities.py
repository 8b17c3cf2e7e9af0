"""The capability table (cvxgeodesic.capabilities): its names are the solvers', every rule refuses something, the
messages name what is supported, and docs/capabilities.md holds the generated table."""

from __future__ import annotations

import itertools
from pathlib import Path

import pytest

from cvxgeodesic import capabilities as cap
from cvxgeodesic.baselines import BASELINES
from cvxgeodesic.errors import ParameterError, SourceError
from cvxgeodesic.operators import ENERGIES, check_energy
from cvxgeodesic.operators.squared_energy import SQUARED_ENERGIES
from cvxgeodesic.problems.formulations import FORMULATIONS

DOC = Path(__file__).resolve().parents[1] / "docs" / "capabilities.md"


def _cells():
    for method, domain, order, medium, multires, smoothing, resolution, local, path in itertools.product(
            cap.METHODS, cap.DOMAINS, cap.ORDERS, cap.MEDIA, *[(False, True)] * 5):
        for source in (None, *cap.SOURCE_KINDS):
            yield method, {"domain": domain, "order": order, "medium": medium, "source": source, "multires": multires,
                           "smoothing": smoothing, "resolution": resolution, "local": local, "path": path}


def test_the_table_names_the_solvers_methods():
    from cvxgeodesic.mesh.tet_generate import tet_box

    assert cap.FORMULATION_METHODS == tuple(FORMULATIONS)
    assert cap.BASELINE_METHODS == tuple(BASELINES)
    # what the solvers implement today, read from their own constants and checks
    assert set(cap.methods_for("surface")) == set(cap.METHODS)
    volume_energies = [e for e in ENERGIES if _accepted(lambda e=e: check_energy(tet_box(1), e))]
    assert volume_energies == ["dirichlet", "laplacian"]
    assert cap.methods_for("volume") == (*(k for k, (_, e) in FORMULATIONS.items() if e in (None, *volume_energies)),
                                         "dijkstra", "heat")
    assert set(cap.methods_for("surface", 2)) == {"qclp", *(f"qcqp-{e}" for e in SQUARED_ENERGIES)}
    assert cap.methods_for("volume", 2) == ("qclp",)
    assert cap.methods_for("surface", 1, "cost") == (*FORMULATIONS, "dijkstra")
    # a cloud: the surface's methods but those that need a manifold surface or a consistent orientation
    assert set(cap.methods_for("surface")) - set(cap.methods_for("cloud")) == {"exact", "fmm", "lcqp-hessian",
                                                                                "qcqp-hessian"}


def _accepted(call) -> bool:
    try:
        call()
    except ParameterError:
        return False
    return True


def test_the_domains_are_the_mesh_classes_and_their_defaults_are_supported():
    from cvxgeodesic.mesh.pointcloud import CloudMesh
    from cvxgeodesic.mesh.tetmesh import TetMesh
    from cvxgeodesic.mesh.trimesh import TriMesh

    assert (TriMesh.domain, TetMesh.domain, CloudMesh.domain) == ("surface", "volume", "cloud")
    assert set(cap.DOMAINS) == {"surface", "volume", "cloud"}
    assert (TriMesh.dim, TetMesh.dim, CloudMesh.dim) == tuple(cap.DOMAINS[d].dim for d in cap.DOMAINS)
    for name, domain in cap.DOMAINS.items():
        assert domain.name == name
        assert cap.supported(domain.default_method, domain=name)
        method, order = domain.reference
        assert cap.supported(method, domain=name, order=order), name
        adapted = domain.default_resolution != "mesh"  # an adapted default solves the default method at order 2
        assert cap.supported(domain.default_method, domain=name, order=2 if adapted else 1, resolution=adapted)
    # surfaces and volumes default to their own mesh; clouds to order 2 on a copy (docs/pointclouds.md)
    assert [d.default_resolution for d in cap.DOMAINS.values()] == ["mesh", "mesh", "auto"]


def test_every_rule_refuses_some_cell_and_nothing_else_does():
    seen = {cap.refusal(method, **cell) for method, cell in _cells()}
    assert seen - {None} == set(cap.RULES)


def test_refusals_follow_the_axes_in_order():
    # a surface method at order 2 in a volume: the domain is the reason, not the order
    assert cap.refusal("fmm", domain="volume", order=2).axis == "method"
    assert cap.refusal("heat", domain="volume", order=2, medium="cost").axis == "order"
    assert cap.refusal("qclp", domain="surface") is None and cap.supported("heat", domain="volume", source="point")
    # smoothing: a smoothed order-2 method takes no medium, its LP (m = 0) does
    assert not cap.supported("qcqp-hessian", domain="surface", order=2, medium="metric")
    assert cap.supported("qcqp-hessian", domain="surface", order=2, medium="metric", smoothing=False)
    # the surfaces' rules hold on a cloud's soup too; its own come on top
    assert cap.refusal("qclp", domain="cloud", source="boundary faces") == cap.refusal(
        "qclp", domain="surface", source="boundary faces")
    assert cap.refusal("qclp", domain="cloud", order=2, source="curve").reason.startswith("curves are resampled")
    # local rows: the volume first, then what a patch lacks
    assert "full rows" in cap.refusal("qclp", domain="volume", local=True, medium="cost").reason
    assert cap.refusal("qclp", domain="surface", local=True, medium="cost").axis == "local"


def test_check_raises_the_library_errors_naming_what_is_supported():
    with pytest.raises(ParameterError, match=r"^method 'exact' does not apply to tetrahedral meshes \(it is a surface "
                                             r"algorithm\); on a volume use one of lclp, .*, dijkstra, heat$"):
        cap.check("exact", domain="volume")
    with pytest.raises(ParameterError, match=r"^order=2 is implemented for qclp on tetrahedral meshes, not for "
                                             r"'qcqp-laplacian' \(the order-2 smoothness energies are implemented on "
                                             r"surfaces only; docs/order2.md\)$"):
        cap.check("qcqp-laplacian", domain="volume", order=2)
    with pytest.raises(SourceError, match=r"^method 'heat' cannot take point or curve sources on a surface "
                                          r"\(potpourri3d's heat method takes vertex sources only\); methods that "
                                          r"can: lclp, .*, qcqp-hessian, dijkstra, fmm, exact$"):
        cap.check("heat", domain="surface", sources=["vertex", "point"])
    with pytest.raises(SourceError, match=r"^multires cannot take point, curve or boundary sources \(multires takes "
                                          r"vertex sources only"):
        cap.check("qclp", domain="surface", multires=True, sources=["boundary"])
    with pytest.raises(ParameterError, match="not implemented with multires"):
        cap.check("qclp", domain="surface", multires=True, medium="cost")
    with pytest.raises(ParameterError, match=r"^method 'fmm' does not apply to point clouds \(it needs a manifold "
                                             r"surface; .*\); on a point cloud use one of lclp, .*, dijkstra, heat$"):
        cap.check("fmm", domain="cloud")
    with pytest.raises(ParameterError, match="^max_distance is not available for method 'qclp' on triangle meshes: "
                                             "max_distance does not take multires="):
        cap.check("qclp", domain="surface", local=True, multires=True)
    with pytest.raises(SourceError, match=r"^max_distance cannot take point, curve or boundary sources \(local rows "
                                          "take source vertices"):
        cap.check("qclp", domain="surface", local=True, sources=["vertex", "point"])
    # the accepted cell comes back; its sources are checked per solve against the same rules
    cell = cap.check("heat", domain="volume", sources=["point", "boundary faces", "vertex"])  # every volume source
    assert cell == cap.Capability("heat", "volume")
    cell.admit(["point", "boundary"])
    with pytest.raises(SourceError, match="^method 'heat' cannot take curve sources inside a volume"):
        cell.admit(["curve"])


def test_paths_take_a_medium_where_the_table_says():
    cap.check_path(domain="surface", medium="cost")
    cap.check_path(domain="cloud", medium="metric")
    cap.check_path(domain="volume", medium="none")
    with pytest.raises(ParameterError, match="^cost and metric apply to paths on triangle meshes and point clouds; "
                                             "inside a tetrahedral mesh the path follows the Euclidean distance$"):
        cap.check_path(domain="volume", medium="cost")


def test_the_docs_hold_the_generated_table():
    if not DOC.is_file():
        pytest.skip("needs the source checkout")
    text = DOC.read_text(encoding="utf-8")
    begin, end = "<!-- begin table -->\n", "<!-- end table -->"
    assert text[text.index(begin) + len(begin):text.index(end)] == cap.markdown_table(), (
        "docs/capabilities.md is out of date: paste cvxgeodesic.capabilities.markdown_table() between its markers")


def test_the_markdown_table_has_a_row_per_method_and_domain_and_every_reason():
    table = cap.markdown_table()
    for method in cap.METHODS:
        assert table.count(f"| `{method}` |") == len(cap.DOMAINS)
    for rule in cap.RULES:
        assert rule.reason in table
    assert "| `qcqp-hessian` | yes | yes | order 1, order 2 with m = 0 [" in table


def test_help_text_lists_each_domain():
    text = cap.help_text()
    assert "triangle meshes: methods lclp," in text and "exact" in text
    assert "tetrahedral meshes: methods lclp, lcqp-dirichlet, lcqp-laplacian, qclp, qcqp-dirichlet, qcqp-laplacian, " \
           "dijkstra, heat; order 2: qclp; cost/metric: none" in text
    assert "point clouds: methods lclp, lcqp-dirichlet, lcqp-laplacian, qclp, qcqp-dirichlet, qcqp-laplacian, " \
           "dijkstra, heat; order 2: qclp, qcqp-dirichlet, qcqp-laplacian; cost/metric: " in text


def test_source_kinds_of_resolved_sets_in_both_dimensions():
    import cvxgeodesic as cg
    from cvxgeodesic.mesh.locate import VolumePoint
    from cvxgeodesic.mesh.tet_generate import tet_box
    from cvxgeodesic.sources import BoundaryFaces, resolve_sources
    from cvxgeodesic.sources import resolve_sources as resolve_tet_sources

    plane, box = cg.grid_plane(4), tet_box(2)
    p = cg.SurfacePoint(3, [0.2, 0.3, 0.5])
    for sources, kinds in [(0, {"vertex"}), ([p, 2], {"point", "vertex"}), ("boundary", {"boundary"}),
                           (cg.SurfaceCurve([p, cg.SurfacePoint(9, [0.3, 0.3, 0.4])]), {"curve"})]:
        assert cap.source_kinds(resolve_sources(plane, sources)) == kinds
    for sources, kinds in [([0, 4], {"vertex"}), ([VolumePoint(0, [0.25] * 4), 3], {"point", "vertex"}),
                           ("boundary", {"boundary"}), (BoundaryFaces([0, 1]), {"boundary faces"})]:
        assert cap.source_kinds(resolve_tet_sources(box, sources)) == kinds


def test_the_command_line_help_shows_the_table_of_each_domain(capsys):
    # the CLI's top-level help reads the capability table, not a copy of it
    from cvxgeodesic.cli import build_parser

    text = build_parser().format_help()
    assert cap.help_text() in text
    assert "triangle meshes: methods" in text and "tetrahedral meshes: methods" in text
    assert "point clouds: methods" in text


def test_the_command_line_choices_and_defaults_read_the_table(monkeypatch):
    import argparse
    from dataclasses import replace

    from cvxgeodesic.cli import _options
    from cvxgeodesic.mesh.tet_generate import tet_box
    from cvxgeodesic.problems.formulations import ALIASES

    p = argparse.ArgumentParser()
    _options.add_solve_options(p)
    _options.add_precision_options(p, tol_default="1e-8")
    method = next(a for a in p._actions if a.dest == "method")
    assert tuple(method.choices) == (*cap.METHODS, *ALIASES)
    assert next(a for a in p._actions if a.dest == "order").choices == cap.ORDERS
    assert _options.default_methods() == "qcqp-hessian; qclp on tetrahedral meshes; qclp on point clouds"
    monkeypatch.setitem(cap.DOMAINS, "volume", replace(cap.DOMAINS["volume"], default_method="heat"))
    assert _options.method_for(argparse.Namespace(method=None), tet_box(1)) == "heat"
    # a travel cost: refused where no method of the domain takes one, before its file is read
    args = argparse.Namespace(cost="missing.npy", cost_field=None)
    with pytest.raises(ParameterError, match=r"^--cost: a travel cost applies to triangle meshes and point clouds, not "
                                             r"to tetrahedral meshes \("):
        _options.cli_cost(args, tet_box(1))


# -- one consultation per solve ------------------------------------------------------------------------------------
def _solve_cases():
    import cvxgeodesic as cg
    from cvxgeodesic.mesh.tet_generate import tet_box

    return {"surface": (cg.icosphere(1), {"method": "qclp"}), "volume": (tet_box(2), {"method": "qclp"}),
            "order 2": (cg.icosphere(1), {"method": "qcqp-laplacian", "order": 2}),
            "baseline": (cg.icosphere(1), {"method": "heat"}),
            "multires": (cg.icosphere(3), {"method": "qclp", "multires": 100}),
            "resolution": (cg.icosphere(3), {"method": "qclp", "resolution": 200, "estimate_error": False})}


@pytest.mark.parametrize("case", list(_solve_cases()))
def test_one_solve_consults_the_table_once(case, monkeypatch):
    # the API edge checks the cell once and passes it down (SolveConfig.capability); the strategies, builders and
    # baselines below do not call capabilities.check again
    import sys

    import cvxgeodesic as cg

    original = cap.check
    calls: list[tuple] = []

    def counting(*args, **kwargs):
        calls.append((args, kwargs))
        return original(*args, **kwargs)

    monkeypatch.setattr(cap, "check", counting)
    # every caller reaches it through the module: no module holds the function under a name of its own
    holders = [name for name, module in list(sys.modules.items()) if name.startswith("cvxgeodesic")
               and any(value is original for value in vars(module).values()) and module is not cap]
    assert holders == []
    mesh, kwargs = _solve_cases()[case]
    source = cg.SurfacePoint(3, [0.2, 0.3, 0.5]) if case in ("surface", "order 2") else 0
    cg.GeodesicSolver(mesh, **kwargs).solve(source)
    assert len(calls) == 1, calls
    calls.clear()
    if "estimate_error" not in kwargs and "multires" not in kwargs:
        cg.geodesic_distance(mesh, source, **kwargs)
        assert len(calls) == 1, calls
    # the solver keeps the accepted cell and hands it to its strategy
    solver = cg.GeodesicSolver(mesh, **kwargs)
    assert solver._strategy.config.capability == solver.capability == cap.Capability(
        solver.method, mesh.domain, solver.order, multires="multires" in kwargs, smoothing=solver.lam > 0,
        resolution="resolution" in kwargs)
