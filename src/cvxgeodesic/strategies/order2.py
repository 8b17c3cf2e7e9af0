"""The order-2 strategy: P2 elements for the squared distance, solved by the one interior-point solver.

Per mesh: the mesh scaled to unit size, the program's per-mesh part (:class:`~cvxgeodesic.formulations_p2.P2Builder`)
and one :class:`~cvxgeodesic.solvers.ipm.InteriorPointSolver` on the face-clique pattern with the order-2 settings
(:data:`~cvxgeodesic.solvers.ipm.settings.ORDER2`), under the backend policy every strategy shares
(:class:`~cvxgeodesic.strategies.backend.Backend`). Per solve: source points inserted as vertices
(:class:`~cvxgeodesic.mesh.split.SplitMesh`), the program built and solved, then cutting planes on the flat faces
the edge cones (:class:`~cvxgeodesic.formulations_p2.BernsteinEdgeCones`) do not cover (a source vertex's edges, a
line of sources): the corner and midpoint cones leave ``|∇φ|² ≤ 4φ`` free between the samples, and there ``d²`` is
exactly quadratic, so a cone at each face's worst point (:func:`~cvxgeodesic.operators.p2.max_violation`, exact)
closes the gap (docs/order2.md).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from ..errors import ParameterError, SolverError, SourceError
from ..formulations_p2 import DEFAULT_SAMPLES, ORDER2_METHODS, P2Builder, P2Program
from ..mesh.split import SplitMesh
from ..mesh.trimesh import TriMesh, unit_mesh
from ..operators.metric import Medium
from ..operators.p2 import P2Field, SplitP2Field, violations
from ..results import GeodesicResult, SolveInfo
from ..solvers.problem import BackendResult, clique_pattern
from ..sources import SourceSet
from .backend import Backend
from .base import Callback, SolveConfig

__all__ = ["REFINE_ROUNDS", "REFINE_TOL", "Order2"]

#: Cutting-plane rounds add a cone where ``|∇φ|² − 4φ`` exceeds this fraction of ``4φ`` (flat faces only). A
#: violation ``v`` lets ``|∇d|`` exceed 1 by ``v / 8φ`` there, so 1e-5 bounds the field's overshoot by about 1e-6 of
#: the largest distance. Measured 2026-12-02 against 1e-7: the flat test cases within 1e-7 of the largest distance
#: either way; thingi_37881 3 solves instead of 5 (the violations shrink ~4× per round, 2.7e-4 → 4.2e-7 there), the
#: same mean error against exact MMP (1.653e-2).
REFINE_TOL = 1e-5
#: At most this many cutting-plane rounds per solve.
REFINE_ROUNDS = 4


class Order2:
    """P2 squared-distance solves on one mesh (``order=2``).

    Parameters
    ----------
    config : SolveConfig
        ``config.method`` is one of :data:`~cvxgeodesic.formulations_p2.ORDER2_METHODS`.
    refine : int
        Cutting-plane rounds at most (:data:`REFINE_ROUNDS`).
    samples : str
        Where the cones are imposed (:data:`~cvxgeodesic.formulations_p2.DEFAULT_SAMPLES`, :class:`P2Builder`).

    Attributes
    ----------
    builder : P2Builder
    ipm : InteriorPointSolver or None
    scale : float
        The power of two the mesh was divided by.
    medium_scale : float
        The medium's normalization (:attr:`~cvxgeodesic.operators.metric.Medium.scale`; 1 without one): the
        program's distances are the field's divided by ``scale · medium_scale``.

    Raises
    ------
    ParameterError
        A method without an order-2 program; ``solver="ipm"`` without Numba.
    """

    def __init__(self, config: SolveConfig, refine: int = REFINE_ROUNDS, samples: str = DEFAULT_SAMPLES) -> None:
        t0 = time.perf_counter()
        if config.method not in ORDER2_METHODS:
            raise ParameterError(
                f"order=2 is implemented for {', '.join(ORDER2_METHODS)}, not for {config.method!r} "
                "(docs/order2.md)")
        self.config = config
        self.refine = int(refine)
        self.samples = samples
        unit, self.scale = unit_mesh(config.mesh)
        medium = None if config.medium is None else config.medium.on(unit)
        self.medium_scale = 1.0 if medium is None else medium.scale
        # λ is dimensionless at order 2 (the energy has the units of the mean of φ): the same on the unit mesh
        self.energy = config.energy if config.lam > 0 else None
        self.builder = self._builder(unit, medium)
        self.policy = Backend(config.solver, config.tol, config.max_iter, config.verbose, config.mesh.name)
        self.backend = self.policy.name
        self.notes: list[str] = [*config.notes, *self.policy.notes]
        self.ipm = self._ipm(self.builder)
        self.setup_time = time.perf_counter() - t0

    def _builder(self, mesh: TriMesh, medium: Medium | None) -> P2Builder:
        return P2Builder(mesh, samples=self.samples, medium=medium, energy=self.energy,
                         lam=self.config.lam if self.energy else 0.0)

    def _ipm(self, builder: P2Builder) -> Any:
        """The structured solver on ``builder``'s face-clique pattern (one symbolic analysis), or None; with a
        smoothness energy the pattern also couples the two vertices opposite each interior edge (the jump term,
        :func:`~cvxgeodesic.operators.p2_energy.edge_diamonds`)."""
        if self.backend != "ipm":
            return None
        from ..solvers.ipm import InteriorPointSolver
        from ..solvers.ipm.settings import ORDER2

        space = builder.space
        cliques = [space.face_dofs] if builder.energy is None else builder.energy.cliques
        return InteriorPointSolver(clique_pattern(space.n_dofs, cliques), settings=ORDER2)

    def solve(self, sources: SourceSet, *, callback: Callback | None = None) -> GeodesicResult:
        """Distance field from vertex, point or boundary sources.

        Raises
        ------
        SourceError
            Curves (order 1 only), or two source points in one face.
        """
        t0 = time.perf_counter()
        mesh = self.config.mesh
        if sources.segment_faces.size and sources.kind != "boundary":
            raise SourceError("order=2 takes vertex, point and 'boundary' sources; solve curves at order 1")
        points = sources.distinct_points(mesh)
        builder, ipm, split = self.builder, self.ipm, None
        vsrc = sources.vertices
        notes = list(self.notes)
        if points:
            # a point inside a face becomes a vertex of a locally split mesh (measured: imposing φ(p) = 0,
            # ∇φ(p) = 0 on the unsplit face leaves 2–7e-3 errors on a flat grid; docs/order2.md)
            split = SplitMesh(mesh, points)
            sm = split.mesh  # the points lie in the mesh's faces: the bounding box and the unit scale do not change
            unit_sm = TriMesh(sm.V / self.scale, sm.F, name=sm.name) if self.scale != 1.0 else sm
            medium = self.config.medium
            builder = self._builder(unit_sm, None if medium is None else
                                    medium.split(sm, split.face_parent, points).on(unit_sm))
            ipm = self._ipm(builder)
            vsrc = np.concatenate([vsrc, split.point_vertices])
            notes.append(f"{len(points)} source point(s) inserted as vertices "
                         f"({sm.n_faces - mesh.n_faces} face(s) added; new symbolic analysis for this solve)")
        program, res, rounds = self._solve_with_cuts(builder, ipm, vsrc, callback, notes)
        return self._result(program, res, rounds, builder, split, sources, notes, t0)

    def _solve_with_cuts(self, builder: P2Builder, ipm: Any, vsrc: np.ndarray, callback: Callback | None,
                         notes: list[str]) -> tuple[P2Program, BackendResult, list[int]]:
        """The program solved, then re-solved with cutting planes on flat faces: ``(program, result, iterations of
        each round)``."""
        program, res = self._first_solve(builder, ipm, vsrc, callback, notes)
        rounds = [res.iterations]
        flat = builder.space.flat_faces
        extra_f, extra_b = np.zeros(0, dtype=np.int64), np.zeros((0, 3))
        flat_ids = np.flatnonzero(flat)
        while len(rounds) <= self.refine and flat.any():
            add, bary = violations(builder.space, program.restore(res.x), REFINE_TOL, flat_ids)
            if add.size == 0:
                break
            cand = builder.build(vsrc, extra=(np.concatenate([extra_f, add]), np.concatenate([extra_b, bary])),
                                 edge_cones=program.has_edge_cones)
            # the last round's optimum, scaled into the new cones, is the next round's start: 25-30 % fewer
            # iterations in the later rounds, the same optimum (thingi_37881: rounds of 26, 25, 26, 28, 26 iterations
            # from Mehrotra's start, 26, 18, 19, 19, 18 from the last one; 2026-12-02)
            cand.problem.guess = np.where(cand.problem.fixed_mask, 0.0, res.x)
            try:
                res_c = self.policy.solve(cand.problem, ipm, callback, notes)
            except SolverError:
                res_c = None
            if res_c is None or (res_c.status != "optimal" and res.status == "optimal"):
                # measured on a needle strip of aspect 1000: a round that only reached "almost" was worse (4.8e-5)
                # than the optimal solve before it (1.3e-7); keep the last fully solved round
                notes.append(f"cutting-plane round {len(rounds)} not fully solved; kept round {len(rounds) - 1}")
                break
            extra_f, extra_b = np.concatenate([extra_f, add]), np.concatenate([extra_b, bary])
            program, res = cand, res_c
            rounds.append(res.iterations)
        if len(rounds) > 1:
            notes.append(f"{len(rounds) - 1} cutting-plane round(s) on flat faces added {extra_f.size} cone(s)")
        return program, res, rounds

    def _first_solve(self, builder: P2Builder, ipm: Any, vsrc: np.ndarray, callback: Callback | None,
                     notes: list[str]) -> tuple[P2Program, BackendResult]:
        """The program solved; when its flat faces' edge cones leave it infeasible or the solver short of optimal
        (they are stricter than the gradient bound where the field is not a point's squared distance: between two
        sources of one flat region, measured on thingi_243015), solved again with the midpoint samples in their
        place, and the cutting planes after it, with a note."""
        program = builder.build(vsrc)
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
        program = builder.build(vsrc, edge_cones=False)
        return program, self.policy.solve(program.problem, ipm, callback, notes)

    def _result(self, program: P2Program, res: BackendResult, rounds: list[int], builder: P2Builder,
                split: SplitMesh | None, sources: SourceSet, notes: list[str], t0: float) -> GeodesicResult:
        mesh = self.config.mesh
        problem = program.problem
        unit2 = (self.scale * self.medium_scale) ** 2
        phi = program.restore(res.x) * unit2
        phi[problem.unreachable] = np.inf
        fld = P2Field(mesh, phi, builder.space) if split is None else SplitP2Field(mesh, split, phi, builder.space)
        d = fld.vertex_distance.copy()
        d[sources.vertices] = 0.0
        info = SolveInfo(
            method=self.config.method, solver=res.solver, status=res.status, iterations=int(sum(rounds)),
            setup_time=self.setup_time, solve_time=time.perf_counter() - t0,
            primal_residual=res.primal_residual, dual_residual=res.dual_residual, gap=res.gap,
            objective=(res.objective + program.objective_constant) * unit2, lam=self.config.lam,
            n_unreachable=int(np.isinf(d).sum()),
            notes=notes, extra={**res.extra, "order": 2, "p2_field": fld, "n_dofs": problem.n,
                                "n_cones": problem.n_cones, "rounds": len(rounds) - 1, "round_iterations": rounds},
        )
        return GeodesicResult(distance=d, info=info, sources=sources.vertices,
                              source_set=None if sources.vertex_only else sources)
