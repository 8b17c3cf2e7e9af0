"""The squared-distance strategy (``order=2``): the order's Lagrange element for the squared distance on any simplex
mesh, solved by the one interior-point solver.

Per mesh: the mesh scaled to unit size, the program's per-mesh part
(:class:`~cvxgeodesic.problems.squared_distance.SquaredDistanceBuilder`)
and one :class:`~cvxgeodesic.solvers.ipm.InteriorPointSolver` on the cell-clique pattern with the order-2 settings
(:data:`~cvxgeodesic.solvers.ipm.settings.ORDER2`), under the backend policy every strategy shares
(:class:`~cvxgeodesic.strategies.backend.Backend`). Per solve: source points inserted as vertices
(:class:`~cvxgeodesic.mesh.split.SplitMesh`), the program built and solved, then cutting planes on the flat cells
(:attr:`~cvxgeodesic.operators.lagrange.LagrangeSpace.flat_cells`: the flat faces of a surface, every tetrahedron)
where the samples leave ``|∇φ|² ≤ 4φ`` free between them (on a surface: where the edge cones
:class:`~cvxgeodesic.problems.squared_distance.BernsteinEdgeCones` do not reach, a source vertex's edges and a line of
sources; in a solid: everywhere between the ten node samples). There ``d²`` is exactly quadratic wherever the source
is visible, so a cone at the violating points (:meth:`~cvxgeodesic.operators.lagrange.LagrangeElement.violations`,
exact) closes the
gap (docs/order2.md).
"""

from __future__ import annotations

import functools
import time
from typing import Any

import numpy as np

from ..errors import SolverError, SourceError
from ..mesh.simplex import SimplexMesh, unit_mesh
from ..mesh.split import SplitMesh
from ..operators.lagrange import LagrangeField, SplitLagrangeField
from ..operators.metric import Medium
from ..problems.conic import BackendResult, clique_pattern
from ..problems.squared_distance import SquaredDistanceBuilder, SquaredDistanceProgram, source_edges
from ..results import GeodesicResult, SolveInfo
from .backend import Backend
from .base import Callback, SolveConfig

__all__ = ["REFINE_ROUNDS", "REFINE_STALL", "REFINE_TOL", "Order2"]

#: Cutting-plane rounds add a cone where ``|∇φ|² − 4φ`` exceeds this fraction of ``4φ`` (flat cells only). A
#: violation ``v`` lets ``|∇d|`` exceed 1 by ``v / 8φ`` there, so 1e-5 bounds the field's overshoot by about 1e-6 of
#: the largest distance. Measured 2026-12-02 against 1e-7: the flat test cases within 1e-7 of the largest distance
#: either way; thingi_37881 3 solves instead of 5 (the violations shrink ~4× per round, 2.7e-4 → 4.2e-7 there), the
#: same mean error against exact MMP (1.653e-2).
REFINE_TOL = 1e-5
#: The rounds also stop after a round that moved no vertex distance by more than this fraction of the largest.
#: Where the source is hidden (behind an edge of a solid, a saddle of a surface) ``d²`` is not quadratic and the
#: cones are violated between the samples whatever the round, so :data:`REFINE_TOL` alone runs every round there.
#: Measured on the jittered L prism (n = 8, 9.2K tetrahedra, 2026-12-02): the rounds moved the field by 2.0e-4,
#: 1.9e-5, 6.9e-6, 3.5e-6 of its maximum and the mean error went 0.234 % → 0.230 % after the first and stayed there
#: (5 digits); on jittered boxes no round is needed. One loop for both dimensions since 2026-12-03, with this rule
#: (the surfaces' loop had REFINE_TOL alone): on the prism (n = 4 / 8) 51 / 72 iterations in 2 rounds, against
#: 82 / 118 in 4 rounds with REFINE_TOL alone, the same mean error (0.3839 % / 0.2296 %); on the surface cases of
#: the tests the violations vanish first and nothing changes. The violating points are every stationary point over
#: the tolerance (the surfaces' rule; the volumes took each tetrahedron's worst one): prism 51 against 53
#: iterations, the same error; a point source on a flat grid with the node samples 3.2e-9 against 1.1e-8 of the
#: largest distance.
REFINE_STALL = 1e-4
#: At most this many cutting-plane rounds per solve.
REFINE_ROUNDS = 4


class Order2:
    """Squared-distance solves on one simplex mesh in the space of an order's element (``order=2``).

    Parameters
    ----------
    config : SolveConfig
        ``config.method`` is one of :func:`~cvxgeodesic.capabilities.methods_for` of the mesh's cells at ``order``.
    order : int
        The element's order (:data:`~cvxgeodesic.operators.lagrange.ELEMENTS`), as the caller validated it.

    Attributes
    ----------
    refine : int
        Cutting-plane rounds at most (:data:`REFINE_ROUNDS`).
    edge_cones : bool
        Whether the flat faces of a surface get the :class:`~cvxgeodesic.problems.squared_distance.BernsteinEdgeCones`
        (False: their midpoints are sampled, and the cutting planes close the gaps; for tests and studies).
    builder : SquaredDistanceBuilder
        The mesh's own program builder (made at the first solve from vertex sources).
    ipm : InteriorPointSolver or None
    scale : float
        The power of two the mesh was divided by.
    medium_scale : float
        The medium's normalization (:attr:`~cvxgeodesic.operators.metric.Medium.scale`; 1 without one): the
        program's distances are the field's divided by ``scale · medium_scale``.

    Raises
    ------
    ParameterError
        A method without an order-2 program on this kind of mesh; ``solver="ipm"`` without Numba.
    """

    def __init__(self, config: SolveConfig, order: int = 2) -> None:
        t0 = time.perf_counter()
        self.config = config
        self.order = order
        self.refine = REFINE_ROUNDS
        self.edge_cones = True
        self._unit, self.scale = unit_mesh(config.mesh)
        self._unit_medium = None if config.medium is None else config.medium.on(self._unit)
        self.medium_scale = 1.0 if self._unit_medium is None else self._unit_medium.scale
        # λ is dimensionless at order 2 (the energy has the units of the mean of φ): the same on the unit mesh
        self.energy = config.energy if config.lam > 0 else None
        SquaredDistanceBuilder.check(config.mesh, config.medium, self.energy, config.lam)
        self.policy = Backend(config.solver, config.tol, config.max_iter, config.verbose, config.mesh.name)
        self.backend = self.policy.name
        self.notes: list[str] = [*config.notes, *self.policy.notes, *_contrast_note(config.medium)]
        self.setup_time = time.perf_counter() - t0

    @functools.cached_property
    def builder(self) -> SquaredDistanceBuilder:
        """The program builder of the mesh itself, made at the first solve that needs it: a solve from source points
        builds its own on the split mesh, so the copy of an adapted solve never makes this one (fandisk's 2,000-face
        copy: 6 ms of 0.29 s)."""
        return self._builder(self._unit, self._unit_medium)

    @functools.cached_property
    def ipm(self) -> Any:
        """The structured solver of the mesh's own program (:meth:`_ipm`), analysed at the first solve that needs it:
        a solve from source points builds its own on the split mesh, so the copy of an adapted solve, whose sources
        are always points, never pays for this one (armadillo's copy: 0.05 s of 1.1 s)."""
        return self._ipm(self.builder)

    def _builder(self, mesh: SimplexMesh, medium: Medium | None) -> SquaredDistanceBuilder:
        return SquaredDistanceBuilder(mesh, self.order, medium=medium, energy=self.energy,
                                      lam=self.config.lam if self.energy else 0.0)

    def _ipm(self, builder: SquaredDistanceBuilder) -> Any:
        """The structured solver on ``builder``'s cell-clique pattern (one symbolic analysis), or None; with a
        smoothness energy the pattern also couples the two vertices opposite each interior edge (the jump term,
        :func:`~cvxgeodesic.operators.squared_energy.edge_diamonds`)."""
        if self.backend != "ipm":
            return None
        from ..solvers.ipm import InteriorPointSolver
        from ..solvers.ipm.settings import ORDER2

        space = builder.space
        cliques = [space.cell_dofs] if builder.energy is None else builder.energy.cliques
        return InteriorPointSolver(clique_pattern(space.n_dofs, cliques), settings=ORDER2)

    def solve(self, sources: Any, *, callback: Callback | None = None) -> GeodesicResult:
        """Distance field from vertex, point and boundary sources (and, in a solid, face sources).

        Raises
        ------
        SourceError
            Curves on a surface (order 1 only), or two source points in one cell.
        """
        t0 = time.perf_counter()
        mesh = self.config.mesh
        if sources.segment_faces.size and not sources.boundary:  # the API edge refuses curves; this: a direct user
            raise SourceError("the order-2 solve takes no curve sources (solve curves at order 1)")
        # where φ = 0, the vertex sources alone (source_edges), the points to insert, a solid's source wall
        fixed = source_fixed = sources.fixed_vertices(mesh)
        vertex_sources, points = np.asarray(sources.vertices, dtype=np.int64), sources.distinct_points(mesh)
        split = None
        notes = list(self.notes)
        if not points:
            builder, ipm = self.builder, self.ipm
        else:
            # a point inside a cell becomes a vertex of a locally split mesh (measured: imposing φ(p) = 0,
            # ∇φ(p) = 0 on the unsplit face leaves 2–7e-3 errors on a flat grid; docs/order2.md)
            split = SplitMesh(mesh, points)
            sm = split.mesh  # the points lie in the mesh's cells: the bounding box and the unit scale do not change
            unit_sm = type(sm)(sm.V / self.scale, sm.cells, name=sm.name) if self.scale != 1.0 else sm
            medium = self.config.medium
            builder = self._builder(unit_sm, None if medium is None else
                                    medium.split(sm, split.cell_parent, points).on(unit_sm))
            ipm = self._ipm(builder)
            fixed = np.concatenate([fixed, split.point_vertices])
            vertex_sources = np.concatenate([vertex_sources, split.point_vertices])
            added = f"{sm.n_cells - mesh.n_cells} {mesh.reference.words.many} added"
            notes.append(f"{len(points)} source point(s) inserted as vertices ({added}; new symbolic analysis for "
                         "this solve)")
        zero = source_edges(builder.mesh, vertex_sources, sources.face_triangles(mesh))
        program, res, rounds = self._solve_with_cuts(builder, ipm, fixed, zero, callback, notes)
        return self._result(program, res, rounds, builder, split, sources, source_fixed, notes, t0)

    def _solve_with_cuts(self, builder: SquaredDistanceBuilder, ipm: Any, fixed: np.ndarray, zero: np.ndarray,
                         callback: Callback | None,
                         notes: list[str]) -> tuple[SquaredDistanceProgram, BackendResult, list[int]]:
        """The program solved, then re-solved with cutting planes on the flat cells until no cell violates the cone
        by :data:`REFINE_TOL`, a round moved the field by less than :data:`REFINE_STALL`, or ``refine`` rounds ran:
        ``(program, result, iterations of each round)``.

        A round that ends short of optimal (or raises) after an optimal one is dropped, with a note, and the last
        fully solved round kept: measured on a needle strip of aspect 1000, a round that only reached "almost" was
        worse (4.8e-5) than the optimal solve before it (1.3e-7).
        """
        program, res = self._first_solve(builder, ipm, fixed, zero, callback, notes)
        rounds = [res.iterations]
        cells = np.flatnonzero(builder.space.flat_cells)
        extra_c, extra_b = np.zeros(0, dtype=np.int64), np.zeros((0, builder.space.reference.n_corners))
        x = program.restore(res.x)
        moved = np.inf
        while len(rounds) <= self.refine and cells.size and moved > REFINE_STALL:
            add, bary = builder.space.violations(x, REFINE_TOL, cells)
            if add.size == 0:
                break
            # the last round's optimum, scaled into the new cones, is the next round's start: 25-30 % fewer
            # iterations in the later rounds, the same optimum (thingi_37881: rounds of 26, 25, 26, 28, 26 iterations
            # from Mehrotra's start, 26, 18, 19, 19, 18 from the last one; the L prism, n = 8: 27 → 22; 2026-12-02)
            cand = builder.build(fixed, zero, extra=(np.concatenate([extra_c, add]), np.concatenate([extra_b, bary])),
                                 edge_cones=program.has_edge_cones, guess=res.x)
            try:
                res_c: BackendResult | None = self.policy.solve(cand.problem, ipm, callback, notes)
            except SolverError:
                res_c = None
            if res_c is None or (res_c.status != "optimal" and res.status == "optimal"):
                notes.append(f"cutting-plane round {len(rounds)} not fully solved; kept round {len(rounds) - 1}")
                break
            extra_c, extra_b = np.concatenate([extra_c, add]), np.concatenate([extra_b, bary])
            program, res = cand, res_c
            rounds.append(res.iterations)
            x_new = program.restore(res.x)
            moved = _moved(x, x_new, builder.mesh.n_vertices)
            x = x_new
        if len(rounds) > 1:
            notes.append(f"{len(rounds) - 1} cutting-plane round(s) added {extra_c.size} cone(s)")
        return program, res, rounds

    def _first_solve(self, builder: SquaredDistanceBuilder, ipm: Any, fixed: np.ndarray, zero: np.ndarray,
                     callback: Callback | None, notes: list[str]) -> tuple[SquaredDistanceProgram, BackendResult]:
        """The program solved; when its flat faces' edge cones leave it infeasible or the solver short of optimal
        (they are stricter than the gradient bound where the field is not a point's squared distance: between two
        sources of one flat region, measured on thingi_243015), solved again with the midpoint samples in their
        place, and the cutting planes after it, with a note."""
        program = builder.build(fixed, zero, edge_cones=self.edge_cones)
        notes[len(self.notes):len(self.notes)] = program.notes
        if not program.has_edge_cones:
            return program, self.policy.solve(program.problem, ipm, callback, notes)
        try:
            res = self.policy.solve(program.problem, ipm, callback, notes, fallback=False)
            if res.status == "optimal":
                return program, res
            why = f"ended {res.status!r}"
        except SolverError as exc:
            why = f"ended {exc.status!r}"
        notes.append(f"the program with the flat faces' edge cones {why}; solved again with the edge midpoints "
                     "sampled instead, and cutting planes")
        program = builder.build(fixed, zero, edge_cones=False)
        return program, self.policy.solve(program.problem, ipm, callback, notes)

    def _result(self, program: SquaredDistanceProgram, res: BackendResult, rounds: list[int],
                builder: SquaredDistanceBuilder, split: SplitMesh | None, sources: Any, source_fixed: np.ndarray,
                notes: list[str], t0: float) -> GeodesicResult:
        mesh = self.config.mesh
        problem = program.problem
        unit2 = (self.scale * self.medium_scale) ** 2
        phi = program.restore(res.x) * unit2
        phi[problem.unreachable] = np.inf
        medium = self.config.medium
        fld = (LagrangeField(mesh, phi, builder.space, medium=medium) if split is None
               else SplitLagrangeField(mesh, split, phi, builder.space, medium=medium))
        d = fld.vertex_distance.copy()
        d[source_fixed] = 0.0
        info = SolveInfo(
            method=self.config.method, solver=res.solver, status=res.status, iterations=int(sum(rounds)),
            setup_time=self.setup_time, solve_time=time.perf_counter() - t0,
            primal_residual=res.primal_residual, dual_residual=res.dual_residual, gap=res.gap,
            objective=(res.objective + program.objective_constant) * unit2, lam=self.config.lam,
            n_unreachable=int(np.isinf(d).sum()),
            notes=notes, extra={**res.extra, "order": self.order, "n_dofs": problem.n,
                                "n_cones": problem.n_cones, "rounds": len(rounds) - 1, "round_iterations": rounds},
        )
        return GeodesicResult(distance=d, info=info, sources=sources.vertices, field=fld,
                              source_set=None if sources.vertex_only else sources)


def _moved(x_old: np.ndarray, x_new: np.ndarray, n: int) -> float:
    """The largest change of the vertex distances ``√max(φ, 0)`` between two rounds, relative to the largest."""
    d_old, d_new = (np.sqrt(np.maximum(v[:n], 0.0)) for v in (x_old, x_new))
    return float(np.abs(d_new - d_old).max(initial=0.0) / max(d_new.max(initial=0.0), 1e-300))


#: The cost ratio from which an order-2 field is noted as less accurate than order 1 (docs/input.md, "Costs at
#: order 2": measured on icosphere(2) and flat grids, up to 6 % of the largest distance at a ratio of 100).
CONTRAST_NOTE_RATIO = 100.0


def _contrast_note(medium: Medium | None) -> list[str]:
    """A note when a strong cost contrast makes the order-2 field fall below the travel time on its cheap side."""
    ratio = 1.0 if medium is None else medium.cost_ratio
    if ratio < CONTRAST_NOTE_RATIO:
        return []
    return [f"order 2 with a travel-cost ratio of {ratio:.3g}: the order-2 field can fall below the travel time on "
            "the cheap side of a strong contrast (up to 6 % of the largest distance at a ratio of 100, 10-13 % at "
            "1e3; docs/input.md); order=1 is more accurate there"]
