"""Many rods' programs run together: one joint evaluation answers all their questions.

A solver program (:mod:`tightknot.solvers.program`: the Newton loop, load continuation,
proximal steps, a knot's load path) yields questions about its system: an evaluation or a
step bound. One rod alone answers each at once (``Program.run``). Here every rod of a batch
runs its own program, with its own load parameter, step length, shift, line search and
convergence test, on its own :class:`~tightknot.solvers.system.RodSystem`, which a
:class:`BatchRod` has attached to the batch; :func:`run_lockstep` collects the pending
questions of all rods and answers them together (:class:`tightknot.solvers.batch_eval.
BatchEvaluator`: one set of launches), so a rod that is done costs nothing and no rod waits
for another's load step. A rod therefore follows its own path, up to the round-off of the
joint evaluation (sums in another order) and of the linear solve (banded Cholesky where the
matrix is positive definite, banded LU otherwise, :mod:`tightknot.solvers.banded`, where
the one-rod solver uses SuperLU; ``tests/loading/test_batch.py`` compares each rod with its
own tie).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tightknot.solvers.banded import BandedCholesky, BandPlan, banded_lu_solve
from tightknot.solvers.batch_eval import (
    BatchEvaluator,
    EvalAnswer,
    EvalRequest,
    HessianData,
    StepRequest,
)
from tightknot.solvers.linear import LowRankHessian, SparseDirect, factorize, woodbury_solve
from tightknot.solvers.program import Coroutine, Evaluate, StepBound
from tightknot.solvers.system import RodSystem


@dataclass
class LinearStats:
    """Factorizations of one rod: banded Cholesky, banded LU where it failed, SuperLU where
    the band was too wide, Cholesky attempts skipped (proven indefinite), and their
    wall-clock time [s]."""

    cholesky: int = 0
    lu: int = 0
    superlu: int = 0
    skipped: int = 0
    seconds: float = 0.0


class BandedSolver:
    """The Newton loop's linear algebra for a batch rod's Hessian
    (:class:`~tightknot.solvers.batch_eval.HessianData`): banded Cholesky, banded LU where
    the matrix is indefinite, SuperLU where the band is most of the matrix.

    Args:
        stats: where its factorizations are counted (shared by a rod's phases).
    """

    #: The solver's name in run summaries.
    name = "banded"
    #: It reads no inertia (:attr:`tightknot.solvers.linear.SparseDirect.refused_indefinite`).
    refused_indefinite = False

    #: Largest n bw^2 (dofs times half-bandwidth squared) solved in band storage: banded
    #: LU costs about 4 n bw^2 flops; a band of a few distant contacts of a loose knot
    #: costs more than SuperLU.
    BAND_WORK_LIMIT = 5e6

    def __init__(self, stats: LinearStats) -> None:
        self.stats = stats
        self._plan: tuple[np.ndarray, BandPlan] | None = None
        self._certificate: tuple[HessianData, float, float] | None = None

    @staticmethod
    def matrix(h: HessianData | LowRankHessian) -> Any:
        """The Hessian as an operator for products (with its low-rank update, if any)."""
        if isinstance(h, LowRankHessian):
            return h.product(h.base.matrix())
        return h.matrix()

    @staticmethod
    def diagonal(h: HessianData | LowRankHessian) -> np.ndarray:
        """The Hessian's diagonal."""
        if isinstance(h, LowRankHessian):
            return h.base.diagonal() + h.diagonal_update()
        return h.diagonal()

    def shifted_direction(self, h: HessianData | LowRankHessian, g: np.ndarray, mu: float,
                          diag: np.ndarray) -> np.ndarray | None:
        """Solve (H + mu D) d = -g (as :class:`tightknot.solvers.linear.SparseDirect`; a
        low-rank update by :func:`tightknot.solvers.linear.woodbury_solve` around the
        factorization of the band)."""
        t0 = time.perf_counter()
        try:
            if isinstance(h, LowRankHessian):
                return self._woodbury(h, g, mu, diag)
            return self._solve(h, g, mu, diag)
        finally:
            self.stats.seconds += time.perf_counter() - t0

    def _woodbury(self, h: LowRankHessian, g: np.ndarray, mu: float,
                  diag: np.ndarray) -> np.ndarray | None:
        """The solve of a low-rank update: the band's solver on the right-hand side and on
        the update's columns together (one factorization)."""
        rhs = np.column_stack([-g, h.u])
        sol = self._solve(h.base, -rhs, mu, diag)
        if sol is None:
            return None
        y, z = sol[:, 0], sol[:, 1:]
        return woodbury_solve(lambda b: y if b.ndim == 1 else z, h.u, h.c, -g)

    def _solve(self, h: HessianData, g: np.ndarray, mu: float,
               diag: np.ndarray) -> np.ndarray | None:
        a = h.data.copy()
        if mu != 0.0:
            a[h.diag_slot] += mu * diag
        if self._plan is None or self._plan[0] is not h.indptr:
            # The ordering depends only on the pattern, which changes with the contact set.
            self._plan = (h.indptr, BandPlan(h.indptr, h.indices))
        plan = self._plan[1]
        if plan.n * plan.bandwidth**2 > self.BAND_WORK_LIMIT:
            # A band of most of the matrix (a few contacts far apart along the rod while
            # the knot is loose): band storage would be dense work; SuperLU as one rod.
            self.stats.superlu += 1
            try:
                d = factorize(h.matrix(a)).solve(-g)
            except RuntimeError:  # exactly singular
                return None
            return d if np.isfinite(d).all() else None
        # A vector proving H + mu D indefinite at a smaller shift of this Newton iteration
        # proves it at this shift too while z.(H + mu D)z stays <= 0: skip the Cholesky
        # attempt (it would fail) and go to LU directly.
        cert = self._certificate
        if cert is not None and cert[0] is h and cert[1] + mu * cert[2] <= 0.0:
            chol = None
            self.stats.skipped += 1
        else:
            chol, z = BandedCholesky.factor_or_certificate(plan, a)
            if z is not None:
                hz = h.matrix() @ z
                self._certificate = (h, float(z @ hz), float(np.sum(diag * z * z)))
        if chol is not None:
            self.stats.cholesky += 1
            d = chol.solve(-g)
        else:
            self.stats.lu += 1
            d = banded_lu_solve(self._plan[1], a, -g)
            if d is None:  # exactly singular
                return None
        return d if np.isfinite(d).all() else None



class BatchRod:
    """Rod ``k`` of a batch: attaches a rod's systems to the batch evaluator.

    A load path makes a new system for each phase; :meth:`attach` hands each one to the
    batch (its evaluations answered jointly, its Newton systems solved by a fresh
    :class:`BandedSolver` counting into this rod's :attr:`stats`).

    Args:
        k: rod index in the batch.
        evaluator: the batch's evaluator.
    """

    def __init__(self, k: int, evaluator: BatchEvaluator) -> None:
        self.k = k
        self.evaluator = evaluator
        self.stats = LinearStats()
        self._cache: tuple | None = None

    def attach(self, system: RodSystem) -> None:
        """Make ``system`` this rod's: checked against the batch's layout of the rod."""
        if np.any(system.f_ext != 0.0) or system.gravity is not None:
            raise ValueError("batched rods carry no dead load (closed knots)")
        own = self.evaluator.rods[self.k].pattern
        if not np.array_equal(own.free_dofs, system.pattern.free_dofs):
            raise ValueError(f"rod {self.k}'s boundary conditions changed its free dofs")
        system.batch = self
        system.linear = BandedSolver(self.stats)
        self._cache = None

    def detach(self, system: RodSystem) -> None:
        """Give ``system`` back to itself (it evaluates and solves alone again)."""
        if system.batch is self:
            system.batch = None
            system.linear = SparseDirect()

    def loaded(self, system: RodSystem) -> None:
        """The system moved to a new load step: tell the evaluator its rest lengths and its
        exclusion window."""
        self.evaluator.set_rest(self.k, system.rest)
        self.evaluator.set_window(self.k, system.state.x, system.model.edge_vertex)
        self.evaluator.compact(self.k)

    def cached(self, q: Evaluate) -> EvalAnswer | None:
        """The last answer when it is still valid for ``q``: the same ``u``, the same rest
        lengths and base frames that are either those it was carried from or its own
        (after the trial was accepted: the frames carried once more onto the same tangents
        change by round-off only)."""
        s = q.system
        c = self._cache
        if (c is not None and c[1] is s.rest and (c[2] is s.state.d1_ref
                                                  or c[3].d1 is s.state.d1_ref)
                and np.array_equal(c[0], q.u)):
            return c[3]
        return None

    def request(self, q: Evaluate) -> tuple[EvalRequest, np.ndarray, np.ndarray]:
        """The evaluator's question for ``q`` (every answer holds gradient and Hessian),
        with the trial positions [m] and twist [rad]."""
        s = q.system
        st = s.state
        x, theta = s._split(q.u)
        return EvalRequest(self.k, x, theta, st.d1_ref, st.t_ref, st.m_ref), x, theta

    def answered(self, q: Evaluate, answer: EvalAnswer, x: np.ndarray | None = None,
                 theta: np.ndarray | None = None) -> tuple:
        """The answer to ``q`` from the evaluator's ``answer`` (kept for reuse)."""
        s = q.system
        if x is None:
            x, theta = s._split(q.u)
        else:
            self._cache = (q.u.copy(), s.rest, s.state.d1_ref, answer)
        return s.evaluated(q.u, x, theta, answer, q.want_grad, q.want_hess)

    def step_request(self, q: StepBound) -> StepRequest:
        """The evaluator's question for a step bound."""
        x0 = q.system.positions(q.u)
        dx = q.system.positions(q.u + q.du) - x0
        return StepRequest(self.k, x0, dx)


@dataclass
class LockstepStats:
    """Work of a lockstep run.

    Attributes:
        rounds: rounds of questions (each answered by at most one evaluation and one
            step-bound launch set).
        evaluations: evaluation launch sets (over all rods).
        step_bounds: step-bound launch sets.
        answered: questions answered (over all rods).
        evaluate_s, step_bound_s: wall-clock time in the evaluator [s].
        rod_s: wall-clock time in the rods' own work (linear solves, checks) [s].
    """

    rounds: int = 0
    evaluations: int = 0
    step_bounds: int = 0
    answered: int = 0
    evaluate_s: float = 0.0
    step_bound_s: float = 0.0
    rod_s: float = 0.0
    active: list[int] = field(default_factory=list)


def run_lockstep(programs: list[Any], evaluator: BatchEvaluator,
                 stats: LockstepStats | None = None) -> list[object]:
    """Run the rods' programs (each a :class:`~tightknot.solvers.program.Program` or its
    coroutine, over systems attached by a :class:`BatchRod`) together until each returns;
    their results."""
    stats = stats if stats is not None else LockstepStats()
    gens: list[Coroutine] = [iter(p) for p in programs]
    results: list[object] = [None] * len(gens)
    pending: dict[int, Any] = {}
    built: dict[int, tuple] = {}

    def advance(k: int, answer: object) -> None:
        t0 = time.perf_counter()
        try:
            while True:
                q = gens[k].send(answer)
                rod = q.system.batch
                if rod is None:
                    raise RuntimeError(f"rod {k}'s program asked about a system that no "
                                       "BatchRod attached")
                if isinstance(q, Evaluate):
                    hit = rod.cached(q)
                    if hit is not None:
                        # The last answer still holds: no round needed.
                        answer = rod.answered(q, hit)
                        continue
                    built[k] = rod.request(q)
                pending[k] = q
                break
        except StopIteration as stop:
            results[k] = stop.value
            pending.pop(k, None)
        stats.rod_s += time.perf_counter() - t0

    for k in range(len(gens)):
        advance(k, None)
    while pending:
        stats.rounds += 1
        stats.active.append(len(pending))
        # Step bounds first: the rods that get one ask for their trial point's energy
        # next, which the evaluation of this same round then answers.
        steps = {k: q for k, q in pending.items() if isinstance(q, StepBound)}
        if steps:
            t0 = time.perf_counter()
            bounds = evaluator.max_step([q.system.batch.step_request(q)
                                         for q in steps.values()])
            stats.step_bound_s += time.perf_counter() - t0
            stats.step_bounds += 1
            stats.answered += len(bounds)
            for k, alpha in bounds.items():
                advance(k, alpha)
        evals = {k: q for k, q in pending.items() if isinstance(q, Evaluate)}
        if evals:
            t0 = time.perf_counter()
            answers = evaluator.evaluate([built[k][0] for k in evals])
            stats.evaluate_s += time.perf_counter() - t0
            stats.evaluations += 1
            stats.answered += len(answers)
            for k, ans in answers.items():
                q = evals[k]
                _, x, theta = built.pop(k)
                t0 = time.perf_counter()
                answer = q.system.batch.answered(q, ans, x, theta)
                stats.rod_s += time.perf_counter() - t0
                advance(k, answer)
    return results
