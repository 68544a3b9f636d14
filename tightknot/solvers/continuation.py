"""Quasi-static equilibrium along a load path, by load continuation.

The load parameter t goes from 0 to 1 in steps; each step is a Newton solve started from
the previous equilibrium. A step that fails is halved (the state is restored), an easy one
lets the next grow, so the path passes where a fixed step would not.

Every failure says where it happened: the load step (its number, counting the converged
steps, and its interval in t), the Newton reason and residual; the iterate at which the
failed step stopped is kept (``StaticResult.failed_state``) so that it can be looked at,
while the system is left at the last equilibrium. A total Newton-iteration budget
(``max_newton_iterations``) bounds the work of a path that keeps halving and regrowing.
"""

from __future__ import annotations

import math
import numbers
import time
from collections.abc import Callable
from dataclasses import dataclass, field

from tightknot.rods.state import State
from tightknot.solvers.dynamic import proximal
from tightknot.solvers.newton import NewtonOptions, NewtonResult, newton
from tightknot.solvers.program import Coroutine, Evaluate, program
from tightknot.solvers.system import RodSystem


@dataclass
class ContinuationOptions:
    """Settings of the load continuation.

    Attributes:
        steps: initial number of equal steps from t = 0 to 1.
        min_step: smallest step in t before giving up.
        max_step: largest step in t.
        grow_below: a step that converged in fewer Newton iterations than this doubles the next.
        newton: options of each Newton solve.
        proximal_dt: when set, a load step whose static solve fails is first retried by
            proximal steps (:func:`tightknot.solvers.dynamic.proximal`) starting with
            this time step [s], before the step is halved: the way through a limit point.
        proximal_steps: their budget.
        max_newton_iterations: total Newton iterations of the whole path, failed attempts
            included, after which it stops as failed (None: no limit).
    """

    steps: int = 1
    min_step: float = 1e-4
    max_step: float = 1.0
    grow_below: int = 6
    newton: NewtonOptions = field(default_factory=NewtonOptions)
    proximal_dt: float | None = None
    proximal_steps: int = 100
    max_newton_iterations: int | None = None

    def __post_init__(self) -> None:
        if not (isinstance(self.steps, numbers.Integral) and self.steps >= 1):
            raise ValueError(f"steps must be a whole number >= 1, got {self.steps!r}")
        for name in ("min_step", "max_step", "grow_below", "proximal_steps"):
            v = getattr(self, name)
            if not (isinstance(v, numbers.Real) and math.isfinite(v)):
                raise ValueError(f"{name} must be a finite number, got {v!r}")
        if not (0 < self.min_step <= self.max_step <= 1):
            raise ValueError(f"need 0 < min_step <= max_step <= 1, got min_step="
                             f"{self.min_step!r}, max_step={self.max_step!r}")
        if self.proximal_dt is not None and not (
                isinstance(self.proximal_dt, numbers.Real) and math.isfinite(self.proximal_dt)
                and self.proximal_dt > 0):
            raise ValueError(f"proximal_dt must be None or finite and > 0 s, got "
                             f"{self.proximal_dt!r}")
        m = self.max_newton_iterations
        if m is not None and not (isinstance(m, numbers.Integral) and m >= 1):
            raise ValueError(f"max_newton_iterations must be None or a whole number >= 1, "
                             f"got {m!r}")


@dataclass
class StepRecord:
    """One converged load step."""

    t: float
    newton: NewtonResult


@dataclass
class StaticResult:
    """Outcome of a continuation.

    Attributes:
        converged: every step to t = 1 converged (and no callback refused a step).
        t: the load parameter reached.
        steps: the converged steps.
        newton_iterations: total Newton iterations, failed attempts included.
        failure: why it stopped early ("" when converged): the load step and its t.
        wall_time_s: wall-clock time [s].
        failed_state: the state where the failing step's solve stopped (None when
            converged, or when a callback refused a converged step: then it is the
            system's state), for looking at what went wrong.
    """

    converged: bool
    t: float
    steps: list[StepRecord]
    newton_iterations: int
    failure: str
    wall_time_s: float
    failed_state: State | None = None


StepCallback = Callable[[RodSystem, StepRecord], str | None]
#: predictor(system, t, t_next): moves the state toward the equilibrium at t_next before
#: the Newton solve (called after the load is set to t_next).
Predictor = Callable[[RodSystem, float, float], None]


def static_solve(p: RodSystem, newton_options: NewtonOptions, proximal_dt: float | None,
                 proximal_steps: int, proximal_newton: NewtonOptions | None = None
                 ) -> Coroutine[tuple[NewtonResult, int, str]]:
    """One static solve of ``p`` at its current load from its state: Newton, then (where it
    fails, unless the rod passed through itself, and with ``proximal_dt`` set) proximal
    steps from its last iterate, their solves with ``proximal_newton`` (default the
    Newton options). Returns the result (``"converged_by_proximal_steps"`` with the
    residual there when the proximal steps found the equilibrium), the Newton iterations
    spent, the proximal steps' included, and why the proximal steps stopped ("" when none
    ran)."""
    res = yield from newton(p, p.free_vector(), newton_options)
    iterations = res.iterations
    prox_reason = ""
    if not res.converged and proximal_dt is not None and res.reason != "passed_through":
        # The static path may have a limit point here: descend through it by proximal
        # (fully damped implicit) steps from the last iterate at this load.
        res, prox_iterations, prox_reason = yield from descend(
            p, res, proximal_dt, proximal_steps, proximal_newton or newton_options)
        iterations += prox_iterations
    return res, iterations, prox_reason


def descend(p: RodSystem, res: NewtonResult, dt: float, steps: int,
            options: NewtonOptions) -> Coroutine[tuple[NewtonResult, int, str]]:
    """Proximal steps from the state of ``p`` after the failed Newton solve ``res``
    (:func:`~tightknot.solvers.dynamic.proximal`): ``res`` itself where they fail, else
    its ``"converged_by_proximal_steps"`` result with the residual there; and the Newton
    iterations of the steps and why they stopped."""
    prox = yield from proximal(p, dt, steps, options)
    if prox.converged:
        _, g, _ = yield Evaluate(p, p.free_vector(), True, False)
        res = NewtonResult(True, res.iterations + prox.newton_iterations,
                           p.residual_norm(g), 0.0, p.last_split.total,
                           "converged_by_proximal_steps", res.history)
    return res, prox.newton_iterations, prox.reason


@program
def continuation(p: RodSystem, options: ContinuationOptions | None = None,
                 callback: StepCallback | None = None, predictor: Predictor | None = None,
                 t_start: float = 0.0) -> Coroutine:
    """Follow the load path of system ``p`` from ``t_start`` to 1, as a program
    (:mod:`tightknot.solvers.program`); ``.run()`` returns the :class:`StaticResult`.

    ``callback(system, record)`` runs after each converged step; returning a string stops
    the run as failed with that reason (e.g. a topology check that found the knot changed).
    ``predictor(system, t, t_next)`` may move the state before each step's Newton solve.
    """
    opt = options or ContinuationOptions()
    system = p
    start = time.perf_counter()
    t = float(t_start)
    dt = min(opt.max_step, (1.0 - t) / opt.steps) if t < 1.0 else 0.0
    records: list[StepRecord] = []
    total_iters = 0
    if t >= 1.0 or dt == 0.0:
        p.set_load(1.0)
        res = yield from newton(p, system.free_vector(), opt.newton)
        rec = StepRecord(1.0, res)
        total_iters += res.iterations
        if res.converged:
            records.append(rec)
        return StaticResult(res.converged, 1.0, records, total_iters,
                            "" if res.converged else
                            f"Newton {res.reason} (residual {res.residual:.3g}) at load step 1 "
                            f"(t=1){': ' + system.violation if system.violation else ''}",
                            time.perf_counter() - start,
                            None if res.converged else system.state.copy())
    while t < 1.0 - 1e-14:
        t_next = min(1.0, t + dt)
        saved = system.state.copy()
        p.set_load(t_next)
        if predictor is not None:
            predictor(p, t, t_next)
        res, iterations, _ = yield from static_solve(p, opt.newton, opt.proximal_dt,
                                                     opt.proximal_steps)
        total_iters += iterations
        where = f"load step {len(records) + 1} (from t={t:.6g} to t={t_next:.6g})"
        if not res.converged:
            failed = system.state.copy()
            passed = f": {system.violation}" if res.reason == "passed_through" else ""
            system.state = saved
            p.set_load(t)
            dt *= 0.5
            why = None
            if dt < opt.min_step:
                why = f"step halved below min_step={opt.min_step:g}"
            elif opt.max_newton_iterations is not None and \
                    total_iters >= opt.max_newton_iterations:
                why = f"Newton budget of {opt.max_newton_iterations} iterations spent"
            if why is not None:
                return StaticResult(
                    False, t, records, total_iters,
                    f"Newton {res.reason}{passed} (residual {res.residual:.3g}) at {where}; "
                    f"{why}",
                    time.perf_counter() - start, failed)
            continue
        rec = StepRecord(t_next, res)
        records.append(rec)
        t = t_next
        if callback is not None:
            reason = callback(system, rec)
            if reason:
                return StaticResult(False, t, records, total_iters, f"{reason} [{where}]",
                                    time.perf_counter() - start, system.state.copy())
        if (opt.max_newton_iterations is not None and total_iters >= opt.max_newton_iterations
                and t < 1.0 - 1e-14):
            return StaticResult(
                False, t, records, total_iters,
                f"Newton budget of {opt.max_newton_iterations} iterations spent after {where}",
                time.perf_counter() - start, system.state.copy())
        if res.iterations < opt.grow_below:
            dt = min(opt.max_step, dt * 2.0)
    return StaticResult(True, 1.0, records, total_iters, "", time.perf_counter() - start)
