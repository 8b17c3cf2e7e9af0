"""The tuning constants of the interior-point solver, each with its default and the measurement that chose it."""

from __future__ import annotations

from dataclasses import dataclass, fields

__all__ = ["ORDER2", "IPMSettings"]

_INITS = ("graph", "interior", "mehrotra", "cvxopt", "guess")

#: Centrality correctors per iteration below :data:`LARGE_PATTERN_NNZ` (see ``IPMSettings.max_correctors``).
CORRECTORS_SMALL = 2
#: ... and from it.
CORRECTORS_LARGE = 4
#: Stored entries (lower triangle) of the Newton pattern from which :data:`CORRECTORS_LARGE` correctors pay:
#: between the 280K-face bunny's QCQP-Hessian pattern (1.4M, where 2 and 4 cost about the same) and the
#: 1.1M-face bunny's (5.6M, where 4 is faster); the 100K-face meshes have 0.17–0.49M.
LARGE_PATTERN_NNZ = 2_000_000


@dataclass(frozen=True)
class IPMSettings:
    """Tuning constants of :class:`~cvxgeodesic.solvers.ipm.InteriorPointSolver` (frozen; the defaults are the
    measured choices, change them for experiments and tests).

    Attributes
    ----------
    step : float
        Fraction of the step to the boundary of the cone that is taken (CVXOPT's STEP). Default 0.99.
    sigma_exp : float
        Mehrotra's centering exponent. Default 3. Measured 2026-12-01 over spot, bimba, horse, armadillo (QCLP,
        QCQP-Hessian) and the 70K, 280K bunnies (QCQP-Hessian), graph start, 4 correctors, β = (0.5, 2): 134
        iterations with 3, 125 with 4, 119 with 6 (the 280K bunny 18, 17, 18); with β = (0.1, 10) and 2
        correctors, 2 took 179 against 154. Not adopted with the narrower β: the fields moved by up to 2.8e-6 of
        the bounding-box diagonal on spot (``benchmarks/ipm_regression.py --compare``), beyond its 1e-6 gate.
        Measured again 2026-12-02 (σ exponent 4 with β = (0.5, 2) against the defaults, tol 1e-8, fields against a
        tol-1e-11 solve): 628 → 540 iterations over bunny_7k, fandisk, kitten, camelhead, fertility, dragon_20k × the
        formulations (bunny_7k 93 → 77, fandisk 111 → 96, camelhead 129 → 112), but on thingi_65395 (near-duplicate
        vertices) 116 → 136 iterations on QCLP with the field 5.8e-6 of the diagonal from the reference against 7.0e-7,
        and LCLP's field there 2.7e-6 from Dijkstra (``tests/test_formulations.py`` asks 1e-6): the narrower centring
        is faster on well-shaped meshes and slower and less accurate on the hard ones. Not adopted.
    mehrotra_correction : bool
        The second-order term ``(W⁻¹Δs_a)∘(WΔz_a)`` of Mehrotra's combined step. Default True; False leaves the
        centering term ``σμe`` alone (a breakage for tests).
    static_reg : float
        Proportional static regularization of the diagonal, ``K_ii (1 + δ)``, undone by iterative refinement.
        Default 1e-12.
    tol_infeas : float
        Relative tolerance of the infeasibility certificates (Clarabel's ``tol_infeas_rel``). Default 1e-8.
    max_refine : int
        Iterative refinement of the reduced Newton solves: at most this many steps. Default 4.
    refine_fraction : float
        ... until the residual of the reduced system is below this fraction of the dual-residual tolerance.
        Default 0.1.
    gap_aware_below : float
        Once the gap is below this many times ``tol``, refinement also aims at ``|xᵀr_x| ≤ 0.1·tol·max(1, |cost|)``:
        the gap contains ``xᵀr_x`` summed over n variables, and an ∞-norm residual far below ``tol`` left a gap
        floor of 5e-8 on dragon_20k's QGDF (n = 10K; 26 iterations ending "almost_optimal" → 15 "optimal"). Only
        in the end game: from the first iteration it cost bimba's QCQP-Hessian 21 more refinement solves (+10 %);
        from 100·tol, 7 and no measurable time. Default 100.
    separate_steps : bool
        Separate primal and dual step lengths when ``P`` is None (measured: 20 → 18 iterations on spot's QCLP).
        Default True.
    max_correctors : int or None
        Gondzio's centrality correctors per iteration (measured on bimba's QCLP: 24 iterations without, 18 with
        2, 18 with 4). Each costs one triangular solve, a pass over the cones and up to three step-length
        evaluations, and no factorization, so its worth depends on how a factorization compares with a solve:
        Gondzio (1996) chooses the count from that ratio. ``None`` (the default) does the same from the size
        of the Newton pattern, which the ratio grows with (:meth:`correctors_for`): :data:`CORRECTORS_SMALL`
        below :data:`LARGE_PATTERN_NNZ` stored entries, :data:`CORRECTORS_LARGE` from it. An integer fixes the
        count. Measured 2026-12-02 (source 0; factorizations / triangular solves / iterations, deterministic):
        horse QCLP 17 / 76 / 16 with 2 against 17 / 108 / 16 with 4; bimba QCQP-Hessian 16 / 71 / 15 against
        15 / 93 / 14; the 280K-face bunny QCQP-Hessian 22 / 99 / 21 against 20 / 128 / 19; the 1.1M-face
        bunny 30 / 145 / 29 against 27 / 178 / 26. One solve with 1 thread (min of 3, variants alternating,
        2-core machine shared with one other job, load 1.1–3.3), 1 / 2 / 4 correctors: bimba QCLP 0.74 /
        0.87 / 0.92 s, QCQP-Hessian 1.50 / 1.73 / 1.87 s; horse QCLP 2.22 / 2.13 / 2.56 s, QCQP-Hessian 4.39
        / 4.56 / 4.70 s; armadillo QCLP 1.54 / 1.52 / 1.98 s, QCQP-Hessian 3.39 / 3.22 / 3.49 s. Quiet, 2 threads,
        the rule against 4: 0–13 % faster on the same six solves (docs/performance.md, "Corrector count by size").
        At 1.1M faces a factorization costs about 20 triangular solves (2.0 s against 0.1 s), and the three
        factorizations 4 correctors save there about pay for their 33 extra solves and cone passes (solve 98.6 s
        in 26 iterations against 96.4 s in 29 at commit 55873ee, 2 correctors and another start); 4 keeps the
        count down there. 2 rather than 1 below the threshold: 1 was faster on bimba, slower on horse QCLP and
        armadillo, and 2–3 iterations longer.
    short_step : float
        With ``max_correctors=None``: an iteration whose combined step (before the correctors) is shorter than
        this gets :data:`CORRECTORS_LARGE` correctors whatever the size (counted in
        ``info.extra["corrector_escalations"]``). On thingi_65395 (near-duplicate vertices, 1.2K vertices) 2
        correctors took QCLP 116 → 135 iterations and QCQP-Hessian 114 "optimal" → 130 "almost_optimal"
        against 4; with this rule 120 and 117, both "optimal" (2026-12-02). Default 0.35: 0.2 gave 121 / 117,
        0.5 gave 116 / 115 but added 4–6 solves on horse and armadillo, where 0.35 adds 0–2 (bimba none).
    beta_min, beta_max : float
        Corrector target: complementarity eigenvalues into ``[β_min σμ, β_max σμ]``. Defaults 0.1, 10. Over the
        set of ``sigma_exp`` (graph start, 4 correctors): 143 iterations with (0.1, 10), 139 with (0.3, 3), 134
        with (0.5, 2), 132 with (0.7, 1.4); not adopted: with (0.5, 2) spot's QCLP field moved by 2.0e-6 of the
        diagonal (the 1e-6 gate; (0.1, 10) moves it by 6e-7).
    gz_a, gz_b : float
        ... at the trial step ``min(1, a·α + b)``. Defaults 1.5, 0.1.
    corrector_weights : tuple of float
        Weighted correctors (Colombo & Gondzio, "Further development of multiple centrality correctors for
        interior point methods", 2008): a corrector that shortens the step at full weight is tried at these
        smaller weights (no extra solve) before giving up. Measured: 783 → 766 iterations over 7 meshes × 8
        formulations, 119 → 115 on spot/bimba/armadillo/horse (QCLP, QCQP-Hessian), 23 → 22 on a 278K-face
        bunny. Default (1.0, 0.5, 0.25).
    reduced_factor : float
        When the iterations end in numerical trouble, a stall or ``max_iter``, the best iterate is returned as
        ``"almost_optimal"`` if its residuals and gap are below ``reduced_factor × tol`` (1e-6 at the default
        tol; Clarabel's reduced tolerances, 1e-4 and 5e-5, let through a field 5× off on a sliver mesh whose
        dual residual was hidden by ‖z‖ ≈ 1e7 in its scale). Seen on Thingi10K slivers: gap 1.6e-8, dual
        residual 1.5e-9, then rounding takes over. Default 100.
    accept_factor : float
        An ``"almost_optimal"`` best iterate within this multiple of ``tol`` (residuals and gap, the plain dual
        residual at ``plain_dual_factor × accept_factor × tol``) is marked acceptable
        (``extra["acceptable"]``): ``solver="auto"`` keeps it, with a note, instead of re-solving with Clarabel.
        Default 10. The iterations stop short there when the dual residual reaches its rounding floor: on the split
        max_planck (42K faces, QCQP-Hessian) 8 of 15 sources ended with the best iterate just above tol (four read:
        gaps 1.6e-9–5e-8, dual residuals 4.5e-9–1.6e-8) and went to Clarabel at 7–25× the time (23–36 s against
        1.4–3.3 s; Clarabel itself ended two of them ``AlmostSolved``); the fields of four such iterates were
        7e-8–8.1e-7 of the largest distance from Clarabel solves at tol 1e-10, as close as ``"optimal"`` fields at
        tol 1e-8 (2.6e-7, and 8.1e-7 for a solve of source 10768 refined further), and a solve at tol 1e-6 was 2.3e-6
        from it (2026-12-06, docs/dev/endgame.md).
    stall_iterations : int
        ... and iterating stops when the best iterate, meeting them, has not been improved on for this many
        iterations (seen: the dual residual stuck at 3–8e-8 by rounding while μ underflows, up to max_iter).
        Default 10.
    init : {"graph", "interior", "mehrotra", "cvxopt", "guess"}
        Starting point: "cvxopt" (``z = A x − b`` shifted into the cone), "mehrotra" (least-norm dual
        ``z = A y`` with ``Aᵀz = −q − Px``, one uniform shift of s and of z, then balancing), "interior" (the
        least-squares x of the ``W = I`` system scaled towards ``x_F`` so that s is strictly feasible without a
        shift, the same least-norm z shifted cone by cone, no balancing; falls back to "mehrotra" when ``x_F``
        is not strictly feasible) or "graph" (as "interior" with the shortest-path field of the program's edge
        bounds, :mod:`.graph`, in place of the least-squares x: no ``W = I`` system with P to factorize; falls
        back to "interior" when there is no such field). Measured on bimba: QCLP 18 (cvxopt) → 17 (mehrotra) →
        15 (interior) iterations; QCQP-Hessian 25 (y from the P + AᵀA factor) → 19 (mehrotra with y from the
        P-free system AᵀA y = …, one extra factorization) → 16 (interior). Over 7 meshes × 8 formulations (spot,
        fandisk, bunny_7k, kitten, camelhead, fertility, dragon_20k) "interior" took 783 iterations against 913,
        never more. "graph" (2026-12-01, spot/bimba/horse/armadillo QCLP and QCQP-Hessian, 70K and 280K
        bunnies QCQP-Hessian): 154 → 153 iterations with 2 correctors, 146 → 143 with 4, and one factorization
        fewer per QCQP solve. Default "graph". "guess" (the order-2 programs, :data:`ORDER2`): the program's own
        guess field scaled into the interior of the cones that allow a step of at least
        :data:`.start.PARTIAL_GUESS_MIN_STEP` towards it, the others' slacks shifted (:func:`.start.guess_primal`),
        the least-norm z with Mehrotra's shift of z alone; "mehrotra" without a guess.
    plain_dual_factor : float
        The dual residual relative to ``max(1, ‖q‖ + ‖x‖)`` alone (without ``‖z‖`` in its scale, the guard against a
        dual blown up along a direction ``Aᵀ`` cancels, :mod:`.residuals`) is accepted at this multiple of ``tol``.
        Default 10: the same end-game rounding at order 1 left thingi_32770's QCLP and Dirichlet solves from vertex
        3318 at a plain residual of 1.1e-8 with the gap met (4.5e-9) and the scaled residual 2.9e-9, so they ended
        "almost_optimal" and went to Clarabel at 10× the time (reliability sweep, 2026-12-02); the blown-up duals
        the guard is for have plain residuals of 1e-2 and more. The iteration tables of
        ``tests/test_ipm_regression.py`` do not change with 10 instead of 1. The order-2 programs (:data:`ORDER2`)
        accept 1000: near their optimum ``Δz = W⁻²(…)`` magnifies
        rounding by up to 1/μ and that residual stalls at 1e-7–1e-4 in ∞-norm while ``x`` has converged (bimba:
        relative gap 3.4e-9, the residual scaled by ``‖z‖`` 1.7e-13, the plain one 2.2e-7; measured on a flat grid:
        x within 5e-8 of Clarabel's optimum, relative to max φ, when the gap was 2e-8 and the plain residual 1e-7).
    least_squares_cost : bool
        The least-squares ``x`` of the starting point ("interior", "mehrotra") solves ``K x = Aᵀb̃ − q̃``; False
        leaves the cost out (``K x = Aᵀb̃``), the order-2 solver's choice (:data:`ORDER2`), measured with it. Default
        True.
    sigma_cap_guess : float
        After a "guess" start, Mehrotra's σ is capped at this. From a primal-feasible start the tail converged
        linearly with σ ≈ 0.3 at steps of 0.95 (order 2, bimba: the gap ÷ 2.5 per iteration over 15 iterations);
        measured iterations for caps 1 / 0.2 / 0.1 / 0.05: spot 21 / 20 / 18, bunny_7k 22 / 21 / 19, bimba
        28 / – / 22 / 21 (2026-12-01). Default 1 (no cap; :data:`ORDER2` has 0.1).
    interior_fraction : float
        "interior", "graph": fraction of the largest feasible step from ``x_F`` towards the least-squares x (the
        graph field) that is taken. Default 0.9 (0.5 with the graph field: 143 → 146 iterations on the set above).
    shift_factor : float
        Mehrotra's shift: 1.5× the most negative eigenvalue (per cone for the "interior" dual). Default 1.5.
    dual_floor : float
        "interior": every dual cone's margin (head − ‖body‖) at least this fraction of the mean head (1e-3: the
        same iteration counts on spot/bimba/horse/armadillo, 1e-6 too; 1e-2 one fewer on two of them).
        Default 1e-2.
    """

    step: float = 0.99
    sigma_exp: float = 3
    mehrotra_correction: bool = True
    static_reg: float = 1e-12
    tol_infeas: float = 1e-8
    max_refine: int = 4
    refine_fraction: float = 0.1
    gap_aware_below: float = 100.0
    separate_steps: bool = True
    max_correctors: int | None = None
    short_step: float = 0.35
    beta_min: float = 0.1
    beta_max: float = 10.0
    gz_a: float = 1.5
    gz_b: float = 0.1
    corrector_weights: tuple[float, ...] = (1.0, 0.5, 0.25)
    reduced_factor: float = 100.0
    accept_factor: float = 10.0
    stall_iterations: int = 10
    init: str = "graph"
    interior_fraction: float = 0.9
    shift_factor: float = 1.5
    dual_floor: float = 1e-2
    sigma_cap_guess: float = 1.0
    least_squares_cost: bool = True
    plain_dual_factor: float = 10.0

    def correctors_for(self, pattern_nnz: int) -> int:
        """Centrality correctors per iteration for a Newton pattern of ``pattern_nnz`` stored entries (lower
        triangle): ``max_correctors`` when set, else by size (see ``max_correctors``)."""
        if self.max_correctors is not None:
            return self.max_correctors
        return CORRECTORS_LARGE if pattern_nnz >= LARGE_PATTERN_NNZ else CORRECTORS_SMALL

    def __post_init__(self) -> None:
        if self.init not in _INITS:
            raise ValueError(f"IPMSettings.init must be one of {', '.join(map(repr, _INITS))}, got {self.init!r}")
        if not 0.0 < self.step < 1.0:
            raise ValueError(f"IPMSettings.step must be in (0, 1), got {self.step!r}")
        if not 0.0 <= self.short_step <= 1.0:
            raise ValueError(f"IPMSettings.short_step must be in [0, 1], got {self.short_step!r}")
        if not 0.0 < self.sigma_cap_guess <= 1.0:
            raise ValueError(f"IPMSettings.sigma_cap_guess must be in (0, 1], got {self.sigma_cap_guess!r}")
        if not 0.0 < self.interior_fraction <= 1.0:
            raise ValueError(f"IPMSettings.interior_fraction must be in (0, 1], got {self.interior_fraction!r}")
        if not self.corrector_weights or not all(0.0 < w <= 1.0 for w in self.corrector_weights):
            raise ValueError(f"IPMSettings.corrector_weights must be weights in (0, 1], got {self.corrector_weights!r}")
        if not 0.0 < self.beta_min <= 1.0 <= self.beta_max:
            raise ValueError(f"IPMSettings.beta_min and beta_max need 0 < beta_min <= 1 <= beta_max, got "
                             f"{self.beta_min!r}, {self.beta_max!r}")
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name == "max_correctors" and value is None:
                continue
            if f.name in ("max_refine", "max_correctors", "stall_iterations"):
                if isinstance(value, bool) or not isinstance(value, int) or value < 0:
                    raise ValueError(f"IPMSettings.{f.name} must be a nonnegative integer, got {value!r}")
            elif isinstance(value, float) and not value >= 0.0:
                raise ValueError(f"IPMSettings.{f.name} must be a nonnegative number, got {value!r}")


#: The settings of the order-2 programs (SOC(4) cones on P2 face cliques; linear objective), each measured on them
#: (2026-12-01, docs/order2.md): four correctors always (27 solves: 829 iterations without, 534 with 2, 470 with 4;
#: the worst flat error 1.9e-6 without, 3.5e-7 with 4), equal primal and dual steps (465 against 470 iterations with
#: separate ones, but the worst flat error 1.1e-6 against 3.5e-7), the guess start with σ capped at 0.1, and a
#: static regularization relative to each diagonal entry of 1e-13 (relative to the largest entry it swamped the
#: far-from-source rows, ~1e10 smaller near the optimum).
ORDER2 = IPMSettings(max_correctors=4, separate_steps=False, init="guess", sigma_cap_guess=0.1, static_reg=1e-13,
                     least_squares_cost=False, plain_dual_factor=1000.0)
