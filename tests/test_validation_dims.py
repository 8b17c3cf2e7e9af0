"""Every validation case on a triangle mesh and on a tetrahedral mesh: the same error class in both dimensions.

Where the verdict differs by dimension (a method, an order, a medium or a kind of source one of them lacks), the
capability table (:mod:`cvxgeodesic.capabilities`) refuses exactly that cell and its reason is in the message.
Every case fails in validation, before any solve, so the file runs in seconds.
"""

from __future__ import annotations

import numpy as np
import pytest

import cvxgeodesic as cg
from cvxgeodesic import capabilities
from cvxgeodesic.errors import ParameterError, SourceError
from cvxgeodesic.mesh.locate import VolumePoint
from cvxgeodesic.mesh.tet_generate import tet_box
from cvxgeodesic.problems.formulations import ALIASES
from cvxgeodesic.sources import BoundaryFaces

MESHES = {2: cg.icosphere(2), 3: tet_box(2)}

#: (case, GeodesicSolver keywords, sources or None, error): refused alike on both meshes.
SAME: list[tuple[str, dict, object, type[Exception]]] = [
    ("method not a string", {"method": 3}, None, ParameterError),
    ("method unknown", {"method": "bogus"}, None, ParameterError),
    ("solver unknown", {"method": "qclp", "solver": "bogus"}, None, ParameterError),
    ("solver with a baseline", {"method": "dijkstra", "solver": "ipm"}, None, ParameterError),
    ("m negative", {"method": "qclp", "m": -1.0}, None, ParameterError),
    ("m NaN", {"method": "qclp", "m": float("nan")}, None, ParameterError),
    ("m bool", {"method": "qclp", "m": True}, None, ParameterError),
    ("m string", {"method": "qclp", "m": "1"}, None, ParameterError),
    ("m above MAX_M", {"method": "qclp", "m": 1e7}, None, ParameterError),
    ("lam negative", {"method": "qcqp-laplacian", "lam": -1.0}, None, ParameterError),
    ("lam infinite", {"method": "qcqp-laplacian", "lam": float("inf")}, None, ParameterError),
    ("lam above the weight of MAX_M", {"method": "qcqp-laplacian", "lam": 1e30}, None, ParameterError),
    ("tol zero", {"method": "qclp", "tol": 0.0}, None, ParameterError),
    ("tol one", {"method": "qclp", "tol": 1.0}, None, ParameterError),
    ("tol string", {"method": "qclp", "tol": "x"}, None, ParameterError),
    ("max_iter zero", {"method": "qclp", "max_iter": 0}, None, ParameterError),
    ("max_iter float", {"method": "qclp", "max_iter": 1.5}, None, ParameterError),
    ("threads zero", {"method": "qclp", "threads": 0}, None, ParameterError),
    ("threads float", {"method": "qclp", "threads": 1.5}, None, ParameterError),
    ("order 3", {"method": "qclp", "order": 3}, None, ParameterError),
    ("order 0", {"method": "qclp", "order": 0}, None, ParameterError),
    ("order string", {"method": "qclp", "order": "2"}, None, ParameterError),
    ("order 2 of an LC formulation", {"method": "lclp", "order": 2}, None, ParameterError),
    ("order 2 of a baseline", {"method": "dijkstra", "order": 2}, None, ParameterError),
    ("normalization unknown", {"method": "qclp", "normalization": "x"}, None, ParameterError),
    ("normalization not a string", {"method": "qclp", "normalization": 3}, None, ParameterError),
    ("multires not a count", {"method": "qclp", "multires": "x"}, None, ParameterError),
    ("multires of a baseline", {"method": "heat", "multires": True}, None, ParameterError),
    ("cost with heat", {"method": "heat", "cost": 2.0}, None, ParameterError),
    ("sources empty", {"method": "qclp"}, [], SourceError),
    ("sources repeated", {"method": "qclp"}, [0, 0], SourceError),
    ("sources out of range", {"method": "qclp"}, 10**6, SourceError),
    ("sources negative", {"method": "qclp"}, -1, SourceError),
    ("sources bool", {"method": "qclp"}, True, SourceError),
    ("sources fraction", {"method": "qclp"}, [0.5], SourceError),
    ("sources unknown string", {"method": "qclp"}, "nope", SourceError),
    ("sources ragged", {"method": "qclp"}, [[0], [1, 2]], SourceError),
    ("sources 2-D", {"method": "dijkstra"}, [[0, 1]], SourceError),
    ("sources None", {"method": "dijkstra"}, None, SourceError),
    ("'boundary' mixed with a vertex", {"method": "qclp"}, ["boundary", 0], SourceError),
]


def _attempt(dim: int, kwargs: dict, sources: object, solve: bool) -> Exception | None:
    """The error of building the solver (and solving, when ``solve``), or None when both went through."""
    try:
        solver = cg.GeodesicSolver(MESHES[dim], **kwargs)
        if solve:
            solver.solve(sources)
    except (ParameterError, SourceError) as exc:
        return exc
    return None


@pytest.mark.parametrize("case, kwargs, sources, error", SAME, ids=[c[0] for c in SAME])
def test_every_bad_input_is_refused_alike_on_a_surface_and_in_a_volume(case, kwargs, sources, error):
    solve = error is SourceError
    for dim in (2, 3):
        exc = _attempt(dim, kwargs, sources, solve)
        assert type(exc) is error, f"{case} on {MESHES[dim].domain}: {exc!r}"
        assert str(exc), case


def test_geodesic_distance_refuses_alike_in_both_dimensions():
    for mesh in MESHES.values():
        with pytest.raises(ParameterError, match="^m must be a finite number >= 0"):
            cg.geodesic_distance(mesh, 0, method="qclp", m=-1)
        with pytest.raises(SourceError, match="out of range"):
            cg.geodesic_distance(mesh, mesh.n_vertices, method="dijkstra")
        with pytest.raises(ParameterError, match="^order must be 1"):
            cg.geodesic_distance(mesh, 0, method="qclp", order=5)


#: (case, GeodesicSolver keywords, sources or None, the source kinds asked about): one dimension refuses, with the
#: table's reason; the other accepts.
DIFFERENT: list[tuple[str, dict, object, tuple[str, ...]]] = [
    ("the curved Hessian energy", {"method": "qcqp-hessian"}, None, ()),
    ("the alias qgdf", {"method": "qgdf"}, None, ()),
    ("fast marching", {"method": "fmm"}, None, ()),
    ("the exact method", {"method": "exact"}, None, ()),
    ("order 2 with smoothing", {"method": "qcqp-laplacian", "order": 2}, None, ()),
    ("multires", {"method": "qclp", "multires": 100}, None, ()),
    ("a travel cost", {"method": "qclp", "cost": 2.0}, None, ()),
    ("a metric", {"method": "dijkstra", "metric": np.eye(3)}, None, ()),
    ("a cost at order 2", {"method": "qclp", "order": 2, "cost": 2.0}, None, ()),
    ("heat from a point", {"method": "heat"}, "point", ("point",)),
    ("a curve", {"method": "qclp"}, "curve", ("curve",)),
    ("boundary faces", {"method": "qclp"}, "boundary faces", ("boundary faces",)),
]


def _sources(kind: object, dim: int) -> object:
    """A source of ``kind`` written for ``dim`` (a SurfaceCurve and BoundaryFaces are written for both)."""
    if kind == "point":
        return cg.SurfacePoint(5, [0.2, 0.3, 0.5]) if dim == 2 else VolumePoint(5, [0.1, 0.2, 0.3, 0.4])
    if kind == "curve":
        return cg.SurfaceCurve([cg.SurfacePoint(5, [0.2, 0.3, 0.5]), cg.SurfacePoint(9, [0.3, 0.3, 0.4])])
    if kind == "boundary faces":
        return BoundaryFaces([0, 1])
    return 0


@pytest.mark.parametrize("case, kwargs, kind, kinds", DIFFERENT, ids=[c[0] for c in DIFFERENT])
def test_where_the_dimensions_differ_the_table_says_why(case, kwargs, kind, kinds):
    verdicts = {}
    for dim in (2, 3):
        exc = _attempt(dim, kwargs, _sources(kind, dim), solve=True)
        method = ALIASES.get(kwargs["method"], kwargs["method"])
        cell = {"domain": MESHES[dim].domain, "order": kwargs.get("order", 1), "multires": "multires" in kwargs,
                "medium": "cost" if "cost" in kwargs else "metric" if "metric" in kwargs else "none"}
        rules = [capabilities.refusal(method, source=k, **cell) for k in kinds] or [
            capabilities.refusal(method, **cell)]
        rule = next((r for r in rules if r is not None), None)
        verdicts[dim] = exc is None
        if rule is None:
            assert exc is None, f"{case} on {MESHES[dim].domain}: the table accepts it, the solver refused"
        else:
            assert isinstance(exc, SourceError if rule.axis == "source" else ParameterError), (case, dim, exc)
            assert rule.reason in str(exc), (case, dim, str(exc))
    assert verdicts[2] != verdicts[3], f"{case}: the same verdict in both dimensions, move it to SAME"


def test_a_cost_on_a_tetrahedral_mesh_is_a_parameter_error_naming_the_reason():
    # measured before the table: AttributeError 'TetMesh' object has no attribute 'n_faces' (a traceback from
    # deep inside the medium's set-up)
    for kw in ({"cost": 2.0}, {"metric": np.eye(3)}, {"cost": np.ones(27)}):
        with pytest.raises(ParameterError, match=r"^method 'qclp' cannot take a travel cost or metric on tetrahedral "
                                                 r"meshes \(travel costs and metrics are implemented on surfaces "
                                                 r"only\); no method can there$"):
            cg.GeodesicSolver(MESHES[3], "qclp", **kw)


def test_unknown_methods_name_the_methods_of_the_dimension():
    with pytest.raises(ParameterError, match=r"^unknown method 'bogus'; choose one of lclp, .*, qgdf, dijkstra, fmm, "
                                             r"heat, exact \(on triangle meshes\)$"):
        cg.GeodesicSolver(MESHES[2], "bogus")
    with pytest.raises(ParameterError, match=r"^unknown method 'bogus'; choose one of lclp, lcqp-dirichlet, "
                                             r"lcqp-laplacian, qclp, qcqp-dirichlet, qcqp-laplacian, dijkstra, heat "
                                             r"\(on tetrahedral meshes\)$"):
        cg.GeodesicSolver(MESHES[3], "bogus")


def test_kinds_of_source_are_checked_at_the_api_edge_with_the_tables_reason():
    # the strategies keep their own checks for direct users; through GeodesicSolver the table answers first
    sphere, curve = MESHES[2], _sources("curve", 2)
    with pytest.raises(SourceError, match=r"^method 'qclp' cannot take curve sources on a surface at order 2 \(solve "
                                          r"curves at order 1\)"):
        cg.GeodesicSolver(sphere, "qclp", order=2).solve(curve)
    with pytest.raises(SourceError, match=r"^multires cannot take point, curve or boundary sources \(multires takes "
                                          r"vertex sources only"):
        cg.GeodesicSolver(sphere, "qclp", multires=100).solve(_sources("point", 2))
    with pytest.raises(SourceError, match=r"^method 'heat' cannot take point or curve sources on a surface"):
        cg.GeodesicSolver(sphere, "heat").solve([0, curve])
