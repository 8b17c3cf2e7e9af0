"""Order 1 on both simplex dimensions (issue 35): one program builder, one source resolution, one direct strategy.

Each test runs on a surface (triangles) and in a solid (tetrahedra): the behaviours the two copies of the code had
drifted apart on, and the guards that had a test in one dimension only.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.sparse.csgraph import dijkstra

import cvxgeodesic as cg
from cvxgeodesic.errors import ParameterError
from cvxgeodesic.mesh.locate import SurfacePoint, VolumePoint
from cvxgeodesic.mesh.tet_generate import tet_box
from cvxgeodesic.mesh.tetmesh import TetMesh
from cvxgeodesic.problems.formulations import (
    KAPPA,
    MIN_STRETCH_WEIGHT,
    NONNEGATIVE_EDGE_RADIUS,
    NONNEGATIVE_HOPS,
    MeshOperators,
    build_problem,
    smoothing_length,
    smoothness_weight,
    stretch_weights,
)
from cvxgeodesic.sources import resolve_sources
from cvxgeodesic.strategies.backend import Backend

MESHES = {"surface": lambda: cg.grid_plane(6), "volume": lambda: tet_box(3, jitter=0.1, seed=3)}
SMOOTH = {"surface": "qcqp-laplacian", "volume": "qcqp-laplacian"}


@pytest.fixture(params=sorted(MESHES))
def kind(request):
    return request.param


def _point_at_vertex(mesh, cell: int, corner: int):
    bary = np.zeros(mesh.dim + 1)
    bary[corner] = 1.0
    return (SurfacePoint if mesh.dim == 2 else VolumePoint)(cell, bary)


def test_point_on_a_vertex_with_that_vertex_is_the_vertex_once(kind):
    """A point on a vertex given together with that vertex was accepted on surfaces and refused in volumes
    ("source vertex ... is given more than once"): both accept it now, as the vertex, once."""
    mesh = MESHES[kind]()
    v = int(mesh.cells[1, 2])
    sources = [_point_at_vertex(mesh, 1, 2), v]
    assert resolve_sources(mesh, sources).vertices.tolist() == [v]
    res = cg.GeodesicSolver(mesh, "qclp").solve(sources)
    alone = cg.GeodesicSolver(mesh, "qclp").solve(v)
    assert res.distance[v] == 0.0
    np.testing.assert_array_equal(res.distance, alone.distance)  # the same problem, solved the same way


def _nonnegative_rows(problem) -> np.ndarray:
    """The vertices bounded below by 0 (rows ``-d_v <= 0``)."""
    ineq = problem.ineq
    pick = (ineq.coeffs[:, 0] == -1.0) & (ineq.coeffs[:, 1] == 0.0) & (ineq.rhs == 0.0)
    return np.unique(ineq.vertices[pick, 0])


def test_near_source_bounds_in_both_dimensions(kind):
    """The bounds ``d >= 0`` on the vertices within NONNEGATIVE_HOPS edges of a source existed on surfaces only;
    those within NONNEGATIVE_EDGE_RADIUS mean edge lengths along edges are bounded in both dimensions, and a
    second-order energy adds those within NONNEGATIVE_RADIUS smoothing lengths, the length measured in the volume
    in a solid."""
    mesh = MESHES[kind]()
    ops = MeshOperators(mesh)
    src = resolve_sources(mesh, 0)
    near = np.zeros(mesh.n_vertices, dtype=bool)
    near[0] = True
    for _ in range(NONNEGATIVE_HOPS):
        near[mesh.edges[near[mesh.edges].any(axis=1)].ravel()] = True
    path = dijkstra(mesh.vertex_adjacency, indices=0)  # edge-path lengths
    near |= path <= NONNEGATIVE_EDGE_RADIUS * mesh.mean_edge_length
    near[0] = False
    plain = _nonnegative_rows(build_problem(ops, src, "qclp", 0.0))
    assert plain.tolist() == np.flatnonzero(near).tolist()
    lam = smoothness_weight(mesh, 5e4, energy="laplacian")  # 4 ℓ = 2.1 |Ω|^(1/dim): the whole mesh
    smooth = _nonnegative_rows(build_problem(ops, src, SMOOTH[kind], lam))
    assert set(plain) < set(smooth)


def test_smoothing_length_is_a_length_in_both_dimensions(kind):
    """``ℓ = (m κ)^(1/3) |Ω|^(1/dim)`` under the area normalization: doubling the mesh doubles it."""
    mesh = MESHES[kind]()
    big = TetMesh(2 * mesh.V, mesh.T) if mesh.dim == 3 else cg.TriMesh(2 * mesh.V, mesh.F)
    lengths = []
    for m in (mesh, big):
        lam = smoothness_weight(m, 1.0, energy="laplacian")
        lengths.append(smoothing_length(MeshOperators(m), lam))
    expect = np.cbrt(KAPPA["laplacian"]) * mesh.total_measure ** (1 / mesh.dim)
    assert lengths[0] == pytest.approx(expect, rel=1e-12)  # the same formula, rounding only
    assert lengths[1] == pytest.approx(2 * lengths[0], rel=1e-12)


@pytest.mark.parametrize("lam", [-1e-3, np.nan, np.inf])
def test_builder_refuses_a_bad_lambda(kind, lam):
    mesh = MESHES[kind]()
    with pytest.raises(ParameterError, match="smoothness weight lambda must be a finite number >= 0"):
        build_problem(MeshOperators(mesh), resolve_sources(mesh, 0), SMOOTH[kind], lam)


def test_builder_refuses_the_hessian_in_a_volume():
    mesh = MESHES["volume"]()
    with pytest.raises(ParameterError, match="does not apply to tetrahedral meshes"):
        build_problem(MeshOperators(mesh), resolve_sources(mesh, 0), "qcqp-hessian", 1e-3)
    with pytest.raises(ParameterError, match="energy 'hessian' does not apply to tetrahedral meshes"):
        MeshOperators(mesh).energy("hessian")


def test_negative_optimum_is_resolved_with_bounds(kind, monkeypatch):
    """An optimum with a negative value away from the near-source bounds is re-solved with ``d >= 0`` everywhere
    and says so (the first solve is made to return a negative value far from the source: ordinary meshes have
    none)."""
    mesh = MESHES[kind]()
    far = int(np.argmax(np.linalg.norm(mesh.V - mesh.V[0], axis=1)))
    real = Backend.solve
    calls = []

    def solve(self, problem, *args, **kwargs):
        res = real(self, problem, *args, **kwargs)
        calls.append(problem)
        if len(calls) == 1:
            res.x = np.array(res.x, dtype=float)
            res.x[far] = -0.1
        return res

    monkeypatch.setattr(Backend, "solve", solve)
    res = cg.GeodesicSolver(mesh, "qclp").solve(0)
    assert len(calls) == 2 and res.info.extra["resolved_nonnegative"] is True
    assert any("re-solved with the bounds d >= 0" in n for n in res.info.notes)
    assert res.distance.min() >= 0.0 and res.distance[far] > 0.1
    assert far in _nonnegative_rows(calls[1])


def _with_sliver(mesh):
    """``mesh`` and one cell more, of (almost) no measure, on a new vertex next to a boundary facet."""
    facet = mesh.boundary_facets[0]
    x = mesh.V[facet].mean(axis=0) + 1e-9 * (mesh.V.max(axis=0) - mesh.V.min(axis=0))
    V = np.vstack([mesh.V, x])
    cells = np.vstack([mesh.cells, [*facet, mesh.n_vertices]])
    return TetMesh(V, cells) if mesh.dim == 3 else cg.TriMesh(V, cells)


def test_stretch_weight_floor(kind):
    """A vertex whose cells have (almost) no measure keeps MIN_STRETCH_WEIGHT of the mean weight (without the floor
    its weight is ~1e-9 of the mean and the optimum is not unique there)."""
    mesh = _with_sliver(MESHES[kind]())
    w = stretch_weights(mesh)
    mean = 1.0 / mesh.n_vertices
    assert w[-1] >= 0.9 * MIN_STRETCH_WEIGHT * mean  # the floor, less its share of the renormalization
    assert w.sum() == pytest.approx(1.0, rel=1e-12)


def test_one_newton_pattern_for_both_dimensions():
    """The direct strategy's pattern from the edges is the tetrahedra's clique pattern (the analysis TetDirect made)."""
    from cvxgeodesic.problems.conic import clique_pattern, kkt_pattern

    mesh = MESHES["volume"]()
    P = MeshOperators(mesh).energy("laplacian")
    edges = kkt_pattern(mesh.n_vertices, mesh.cells, mesh.edges, P)
    clique = clique_pattern(mesh.n_vertices, [mesh.T]) + abs(P).astype(bool).astype(float)
    clique.data[:] = 1.0
    clique.sort_indices()
    assert (edges != clique.tocsc()).nnz == 0


@pytest.mark.parametrize("cls, field, bary", [(SurfacePoint, "face", [0.2, 0.3, 0.5]),
                                              (VolumePoint, "tet", [0.1, 0.2, 0.3, 0.4])])
def test_one_point_type_located_in_a_cell(cls, field, bary):
    """SurfacePoint and VolumePoint are one CellPoint(cell, bary) under their public names and attributes."""
    import pickle

    from cvxgeodesic.mesh.locate import CellPoint

    p = cls(**{field: 3, "bary": bary})
    assert isinstance(p, CellPoint) and getattr(p, field) == p.cell == 3
    assert repr(p) == f"{cls.__name__}({field}=3, bary=[{', '.join(f'{x:.6g}' for x in bary)}])"
    assert pickle.loads(pickle.dumps(p)) == p and hash(pickle.loads(pickle.dumps(p))) == hash(p)
    other = SurfacePoint(3, [0.2, 0.3, 0.5]) if cls is VolumePoint else VolumePoint(3, [0.25] * 4)
    assert p != cls(3, bary[::-1]) and p != other
    with pytest.raises(AttributeError, match="immutable"):
        p.bary = np.zeros(len(bary))
    with pytest.raises(cg.SourceError, match=f"{cls.__name__} {field} must be"):
        cls(1.5, bary)
