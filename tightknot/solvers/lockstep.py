"""Each rod of a batch runs tie()'s own solver; all rods advance together.

:func:`tightknot.loading.tie.tie` ties a closed knot by a Newton relaxation, then a load
continuation (:func:`tightknot.solvers.continuation.solve_static`) whose failed steps are
retried by proximal steps (:func:`tightknot.solvers.dynamic.proximal_relax`), each step a
damped Newton solve (:func:`tightknot.solvers.newton.newton_solve`). Those solvers are
generators (``newton_gen``, ``proximal_gen``, ``continuation_gen``) that yield each
question they have about the potential (an energy, gradient and Hessian, or a
collision-free step bound) instead of evaluating it; one rod alone answers at once. Here
every rod of a batch runs the same generators, with its own load parameter, step length,
shift, line search and convergence test, through a :class:`RodProblem`, and
:func:`run_lockstep` collects the pending questions of all rods and answers them together
(:class:`tightknot.solvers.batch_eval.BatchEvaluator`: one set of launches), so a rod that
is done costs nothing and no rod waits for another's load step. A rod therefore follows
its own tie's path, up to the round-off of the joint evaluation (sums in another order)
and of the linear solve (banded Cholesky where the matrix is positive definite, banded LU
otherwise, :mod:`tightknot.solvers.banded`, where the one-rod solver uses SuperLU;
``tests/loading/test_batch.py`` compares each rod with its own tie).
"""

from __future__ import annotations

import time
from collections.abc import Generator
from dataclasses import dataclass, field

import numpy as np

from tightknot.rods.state import State
from tightknot.solvers.banded import BandedCholesky, BandPlan, banded_lu_solve
from tightknot.solvers.batch_eval import (
    BatchEvaluator,
    EvalRequest,
    HessianData,
    StepRequest,
)
from tightknot.solvers.linear import factorize
from tightknot.solvers.system import EnergySplit, Inertia, RodSystem

#: What a rod's generator yields (a question) and is sent back (the answer).
Request = EvalRequest | StepRequest
RodGen = Generator[Request, object, object]


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


class RodProblem:
    """One rod's potential as the Newton loop sees it (the NewtonProblem of one-rod
    solves), answered by the batch evaluator.

    Args:
        k: rod index in the batch.
        system: the rod's own system (its model, boundary conditions, load and state).
        evaluator: the batch's evaluator.
    """

    #: Largest n bw^2 (dofs times half-bandwidth squared) solved in band storage: banded
    #: LU costs about 4 n bw^2 flops; at 393 dofs a band of 81 took 0.5 ms (SuperLU 1.5),
    #: one of 230 (a few distant contacts of a loose knot) far longer than SuperLU.
    BAND_WORK_LIMIT = 5e6

    def __init__(self, k: int, system: RodSystem, evaluator: BatchEvaluator) -> None:
        self.k = k
        self.system = system
        self.evaluator = evaluator
        if np.any(system.f_ext != 0.0) or system.gravity is not None:
            raise ValueError("batched rods carry no dead load (closed knots)")
        own = evaluator.rods[k].pattern
        if not np.array_equal(own.free_dofs, system.pattern.free_dofs):
            raise ValueError(f"rod {k}'s boundary conditions changed its free dofs")
        m = system.model
        # Dof maps, computed once (the model builds them on every access).
        self._pos = m.position_dofs
        self._edge_dof = m.edge_dof
        self._free = system.pattern.free_dofs
        self.inertia: Inertia | None = None
        self.last_split = EnergySplit()
        self.trial: tuple[np.ndarray, ...] | None = None
        self.stats = LinearStats()
        self._plan: tuple[np.ndarray, BandPlan] | None = None
        self._cache: tuple | None = None
        self._certificate: tuple[HessianData, float, float] | None = None

    # -- load path ---------------------------------------------------------------------
    @property
    def state(self) -> State:
        """The rod's state (what tie()'s predictor moves)."""
        return self.system.state

    def set_load(self, t: float) -> None:
        """As RodSystem.set_load, and tell the evaluator the rod's new rest lengths."""
        self.system.set_load(t)
        self.evaluator.set_rest(self.k, self.system.rest)
        self.evaluator.compact(self.k)

    # -- evaluation (yields the question) ------------------------------------------------
    def evaluate(self, u: np.ndarray, want_grad: bool = True, want_hess: bool = True):
        """Total potential [J], free-dof gradient and Hessian at ``u`` (as RodSystem).

        Every question asks for all three (:class:`EvalRequest`); the last answer is kept,
        so that the full evaluation at an accepted trial point costs no second round. It
        is reused only at the same ``u``, the same rest lengths and base frames that are
        either those it was carried from or its own (after the trial was accepted: the
        one-rod solver carries the frames once more, onto the same tangents, which changes
        them by round-off only)."""
        s = self.system
        st = s.state
        q = self._dofs(u)
        x = q[self._pos]
        theta = q[self._edge_dof] if s.model.twist else st.theta
        c = self._cache
        if (c is not None and c[1] is s.rest and (c[2] is st.d1_ref or c[3].d1 is st.d1_ref)
                and np.array_equal(c[0], u)):
            ans = c[3]
        else:
            ans = yield EvalRequest(self.k, x, theta, st.d1_ref, st.t_ref, st.m_ref)
            self._cache = (u.copy(), s.rest, st.d1_ref, ans)
        self.trial = (u.copy(), x, theta, ans.d1, ans.t, ans.m_ref)
        split = EnergySplit(stretch=ans.stretch, bend=ans.bend, twist=ans.twist)
        split.extra["contact"] = ans.contact
        grad = ans.grad
        if self.inertia is not None:
            dq = q - self.inertia.q_hat
            w = self.inertia.mass / self.inertia.dt**2
            split.inertia = 0.5 * float(np.sum(w * dq * dq))
            grad = grad + w * dq
        self.last_split = split
        free = self._free
        g_free = grad[free] if (want_grad or want_hess) else None
        h = None
        if want_hess:
            h = ans.hess
            if self.inertia is not None:
                w = self.inertia.mass / self.inertia.dt**2
                data = h.data.copy()
                data[h.diag_slot] += w[free]
                h = HessianData(h.indptr, h.indices, h.diag_slot, data)
        return split.total, g_free, h

    def max_step(self, u: np.ndarray, du: np.ndarray):
        """Largest step fraction the contact layer allows (yields the question)."""
        x0 = self._dofs(u)[self._pos]
        dx = self._dofs(u + du)[self._pos] - x0
        alpha = yield StepRequest(self.k, x0, dx)
        return alpha

    def _dofs(self, u: np.ndarray) -> np.ndarray:
        """All dofs of the state with the free ones from ``u`` (RodSystem's q)."""
        st = self.system.state
        q = np.empty(self.system.model.dof_count)
        q[self._pos] = st.x
        if self.system.model.twist:
            q[self._edge_dof] = st.theta
        q[self._free] = u
        return q

    def accept(self, u: np.ndarray):
        """Make ``u`` the state (re-evaluated first if it was not the last trial)."""
        if self.trial is None or not np.array_equal(self.trial[0], u):
            yield from self.evaluate(u, want_grad=False, want_hess=False)
        _, x, theta, d1, tt, mref = self.trial
        st = self.system.state
        st.x, st.d1_ref, st.t_ref, st.m_ref = x.copy(), d1, tt, mref
        if self.system.model.twist:
            st.theta = theta.copy()

    def energy_roundoff(self) -> float:
        """As RodSystem.energy_roundoff [J]."""
        return 1e-13 * self.last_split.magnitude

    def residual_norm(self, g: np.ndarray) -> float:
        """As RodSystem.residual_norm [-]."""
        return self.system.residual_norm(g)

    def step_norm(self, du: np.ndarray) -> float:
        """As RodSystem.step_norm [-]."""
        return self.system.step_norm(du)

    @property
    def handle(self) -> RodProblem:
        """What a continuation's predictor is given: this rod (its ``set_load`` tells the
        evaluator the new rest lengths)."""
        return self

    def set_inertia(self, inertia: Inertia | None) -> None:
        """The proximal steps' inertia term (added in :meth:`evaluate`)."""
        self.inertia = inertia

    @staticmethod
    def matrix(h: HessianData) -> object:
        """The Hessian as a sparse matrix (for products)."""
        return h.matrix()

    @staticmethod
    def diagonal(h: HessianData) -> np.ndarray:
        return h.diagonal()

    # -- linear algebra ----------------------------------------------------------------------
    def shifted_direction(self, h: HessianData, g: np.ndarray, mu: float,
                          diag: np.ndarray) -> np.ndarray | None:
        """Solve (H + mu D) d = -g (as the Newton loop's ``_shifted_direction``)."""
        t0 = time.perf_counter()
        try:
            return self._solve(h, g, mu, diag)
        finally:
            self.stats.seconds += time.perf_counter() - t0

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


def run_lockstep(programs: list[RodGen], evaluator: BatchEvaluator,
                 stats: LockstepStats | None = None) -> list[object]:
    """Run the rods' generators together until each returns; their return values."""
    stats = stats if stats is not None else LockstepStats()
    results: list[object] = [None] * len(programs)
    pending: dict[int, Request] = {}

    def advance(k: int, answer: object) -> None:
        t0 = time.perf_counter()
        try:
            pending[k] = programs[k].send(answer)
        except StopIteration as stop:
            results[k] = stop.value
            pending.pop(k, None)
        stats.rod_s += time.perf_counter() - t0

    for k in range(len(programs)):
        advance(k, None)
    while pending:
        stats.rounds += 1
        stats.active.append(len(pending))
        # Step bounds first: the rods that get one ask for their trial point's energy
        # next, which the evaluation of this same round then answers.
        steps = [q for q in pending.values() if isinstance(q, StepRequest)]
        if steps:
            t0 = time.perf_counter()
            bounds = evaluator.max_step(steps)
            stats.step_bound_s += time.perf_counter() - t0
            stats.step_bounds += 1
            stats.answered += len(bounds)
            for k, alpha in bounds.items():
                advance(k, alpha)
        evals = [q for q in pending.values() if isinstance(q, EvalRequest)]
        if evals:
            t0 = time.perf_counter()
            answers = evaluator.evaluate(evals)
            stats.evaluate_s += time.perf_counter() - t0
            stats.evaluations += 1
            stats.answered += len(answers)
            for k, ans in answers.items():
                advance(k, ans)
    return results
