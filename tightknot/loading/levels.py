"""Continuation in a level parameter, from equilibrium to equilibrium, and the search for
the level of a target knot length.

A *level* is the value of one load of a rod system (a dead pulling force [N], a tension
[N], an indentation [m]), which the system's boundary conditions read from a
:class:`LevelLoad`. A :class:`LevelPath` moves the system from the equilibrium at one level
to the equilibrium at another (:meth:`LevelPath.move_to`), each solve checked by the
caller (the knot type) and started from the knot recentred on its rod (the caller's hook),
optionally from the extrapolation of the last two equilibria (:class:`SecantPredictor`);
and it searches the level at which the knot length Lambda_OC reaches a target
(:meth:`LevelPath.seek`: level steps until the target is bracketed, then a search inside
the bracket). Every method is a program's coroutine (:mod:`tightknot.solvers.program`):
``yield from path.move_to(f)`` inside a program, ``Program(path.move_to(f), "move").run()``
outside one, so that a batch driver could run many paths together.

Its three users differ in details, each an option here:

======================  =================  =========================  ===============
option                  tie_to_lambda      sweep path                 FEM rod model
======================  =================  =========================  ===============
LevelOptions.steps      "one"              "geometric"                "linear"
.proximal_dt            1e-3 s             1e-3 s                     None
.proximal_steps         200                ``proximal_steps`` (60)
.predictor              None               SecantPredictor(falling=   SecantPredictor()
                                           False, max_extrapolation=
                                           2, guard=keeps_clear(...))
SearchOptions.secant    False              True                       (no search)
.retries                3                  0
.refine                 "bisection"        "regula_falsi"
======================  =================  =========================  ===============

(:func:`tightknot.loading.pull.tie_to_lambda`, :func:`tightknot.sweep.path.tightness_path`,
:mod:`tightknot.fem.rod_model`.)
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from tightknot.solvers.continuation import (
    ContinuationOptions,
    StepRecord,
    continuation,
    static_solve,
)
from tightknot.solvers.newton import NewtonOptions
from tightknot.solvers.program import Coroutine
from tightknot.solvers.system import RodSystem

#: check(system, record, level): after a converged solve at ``level``, None or "" accepts
#: the equilibrium, a string rejects it with that reason (e.g. the knot type changed).
Check = Callable[[RodSystem, StepRecord, float], str | None]
#: recentre(system): before a solve, may move the state along a zero mode of the energy
#: (an open knot slid to mid-rod); returns the map that moves other positions [m] of the
#: rod likewise, or None when nothing moved.
Recentre = Callable[[RodSystem], Callable[[np.ndarray], np.ndarray] | None]
#: measure(system): the knot length Lambda_OC of the system's state.
Measure = Callable[[RodSystem], float]
#: guard(x, guess): whether the predicted positions ``guess`` [m] may replace ``x`` [m].
Guard = Callable[[np.ndarray, np.ndarray], bool]

STEPS = ("one", "geometric", "linear")
REFINE = ("bisection", "regula_falsi")


class LevelLoad:
    """A load value along the load parameter t of a rod system: ``start`` at t = 0 to
    ``end`` at t = 1, linearly; boundary conditions read it (``bcs.force(0, k, lambda t:
    load(t) * axis)``)."""

    def __init__(self, value: float = 0.0) -> None:
        self.start = value
        self.end = value

    def __call__(self, t: float) -> float:
        return self.start + t * (self.end - self.start)

    def hold(self, value: float) -> None:
        """``value`` at every t (exactly: v + t (v - v) = v)."""
        self.start = self.end = value

    def ramp_to(self, value: float) -> None:
        """From the last end value (t = 0) to ``value`` (t = 1)."""
        self.start, self.end = self.end, value


class Contact(Protocol):
    """What :func:`keeps_clear` uses of a contact layer."""

    last_rest: np.ndarray

    def min_distance(self, x: np.ndarray) -> tuple: ...

    def max_step(self, x: np.ndarray, dx: np.ndarray, rest: np.ndarray) -> float: ...


def keeps_clear(contact: Contact, ratio: float = 0.9) -> Guard:
    """A predictor guard: the guess may not bring two pieces of rod closer than ``ratio``
    times their closest distance now, and the straight way to it must pass the contact's
    step bound whole (a predictor must not push the rod into, or through, itself:
    Newton's step bound protects only its own steps)."""

    def guard(x: np.ndarray, guess: np.ndarray) -> bool:
        if contact.max_step(x, guess - x, contact.last_rest) < 1.0:
            return False
        return contact.min_distance(guess)[0] >= ratio * contact.min_distance(x)[0]

    return guard


@dataclass(frozen=True)
class SecantPredictor:
    """Each solve starts from the last two equilibria x0, x1 extrapolated to the new level,
    x1 + c (x1 - x0), c from the levels (linearly in the level with "linear" steps, in its
    logarithm otherwise), so that Newton starts near the new equilibrium instead of at the
    old one. Positions only: a twist field starts where it was.

    Attributes:
        falling: also when the level falls. A pulled knot loosens toward the force below
            which it slips off (a limit point), where a guess along the last motion starts
            Newton on the wrong side of it.
        max_extrapolation: the largest |c| used (far outside the last step a linear
            guess is no better than none).
        guard: a guess it refuses is not used (:func:`keeps_clear`).
    """

    falling: bool = True
    max_extrapolation: float = math.inf
    guard: Guard | None = None

    def __post_init__(self) -> None:
        if not (self.max_extrapolation > 0):
            raise ValueError(f"max_extrapolation must be > 0, got {self.max_extrapolation!r}")


@dataclass(frozen=True)
class LevelOptions:
    """How a :class:`LevelPath` reaches a level.

    Attributes:
        steps: how a move to a new level is made:
            ``"one"``: one static solve at the level (a failed move is the caller's to retry);
            ``"geometric"``: static solves at levels in geometric progression toward it (the
            log step halved after a failed solve, doubled after a converged one), until
            ``max_failures`` solves failed; levels > 0;
            ``"linear"``: one load continuation (:func:`~tightknot.solvers.continuation.
            continuation`) along which the load moves linearly from the last level to the
            new one (:meth:`LevelLoad.ramp_to`), halving a step that fails down to its
            ``min_step``; the new level becomes the current one even where the continuation
            stops short of it (its last equilibrium is kept, and the failure returned).
        max_failures: failed solves after which a "geometric" move gives up (each costs its
            proximal budget; past a few, a knot is slipping: no equilibrium near this path).
        down_ratio: the largest factor by which a "geometric" move lowers the level per
            solve (None: no limit): a sudden drop of a dead load lets a knot spring open and
            slip off (:func:`tightknot.loading.tie.tie` explains).
        newton: the options of every Newton solve.
        proximal_dt: first time step [s] of the proximal steps
            (:func:`~tightknot.solvers.dynamic.proximal`) that descend from a failed static
            solve to the next equilibrium (a limit point: a loop flips, the contact set
            jumps), not after the rod passed through itself; None: no such fallback.
        proximal_steps: their budget.
        predictor: the start of each solve (None: the last equilibrium).
        name, unit: the level's name and unit in messages.
    """

    steps: str = "geometric"
    max_failures: int = 3
    down_ratio: float | None = 1.15
    newton: NewtonOptions = field(default_factory=NewtonOptions)
    proximal_dt: float | None = 1e-3
    proximal_steps: int = 60
    predictor: SecantPredictor | None = None
    name: str = "force"
    unit: str = "N"

    def __post_init__(self) -> None:
        if self.steps not in STEPS:
            raise ValueError(f"steps must be one of {STEPS}, got {self.steps!r}")
        if not (isinstance(self.max_failures, numbers.Integral) and self.max_failures >= 1):
            raise ValueError(f"max_failures must be a whole number >= 1, got "
                             f"{self.max_failures!r}")
        if self.down_ratio is not None and not (math.isfinite(self.down_ratio)
                                                and self.down_ratio > 1):
            raise ValueError(f"down_ratio must be None or finite and > 1, got "
                             f"{self.down_ratio!r}")
        if self.proximal_dt is not None and not (math.isfinite(self.proximal_dt)
                                                 and self.proximal_dt > 0):
            raise ValueError(f"proximal_dt must be None or finite and > 0 s, got "
                             f"{self.proximal_dt!r}")
        if not (isinstance(self.proximal_steps, numbers.Integral) and self.proximal_steps >= 1):
            raise ValueError(f"proximal_steps must be a whole number >= 1, got "
                             f"{self.proximal_steps!r}")


@dataclass(frozen=True)
class SearchOptions:
    """How :meth:`LevelPath.seek` searches the level of a target Lambda_OC (which falls as
    the level rises: a harder pull makes a tighter knot).

    Attributes:
        tolerance: how close to the target Lambda_OC must come.
        step_ratio: the factor of a level step while bracketing (with ``secant``, the
            largest one).
        max_steps: level steps before the search gives up unbracketed.
        secant: steps in log level. While the level rises, predicted from the slope
            dLambda_OC/dlog(level) of the last two measured equilibria of the path (Lambda_OC
            is locally linear in log F), between ``min_step_ratio`` and ``step_ratio``;
            otherwise log(step_ratio). False: the level is multiplied by ``step_ratio`` (or
            by its inverse).
        min_step_ratio: the smallest factor of a secant step (a smaller one changes
            Lambda_OC by less than the contact set's discreteness, so the search would crawl).
        retries: a failed level step is retried from the last equilibrium with the square
            root of the step's factor, up to this many times; the smaller factor stays for
            the rest of the search (retries count as steps).
        refine: the search inside the bracket [lo, hi]: ``"bisection"``, at sqrt(lo hi);
            ``"regula_falsi"``, at lo (hi/lo)^c, c interpolated in log level and kept in
            [0.2, 0.8] (so that the bracket shrinks by a fixed factor every step) while the
            level rises, c = 0.5 otherwise (near the loosest knots Lambda_OC rises steeply as
            the force falls, toward the force where the knot slips off).
        max_refinements: solves inside the bracket.
        bracket_ratio: the search inside stops once hi/lo is below this.
    """

    tolerance: float = 0.1
    step_ratio: float = 1.15
    max_steps: int = 60
    secant: bool = False
    min_step_ratio: float = 1.005
    retries: int = 0
    refine: str = "bisection"
    max_refinements: int = 30
    bracket_ratio: float = 1.0001

    def __post_init__(self) -> None:
        if not (math.isfinite(self.tolerance) and self.tolerance > 0):
            raise ValueError(f"tolerance must be finite and > 0, got {self.tolerance!r}")
        for name in ("step_ratio", "min_step_ratio", "bracket_ratio"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 1):
                raise ValueError(f"{name} must be finite and > 1, got {v!r}")
        for name in ("max_steps", "retries", "max_refinements"):
            v = getattr(self, name)
            if not (isinstance(v, numbers.Integral) and v >= 0):
                raise ValueError(f"{name} must be a whole number >= 0, got {v!r}")
        if self.refine not in REFINE:
            raise ValueError(f"refine must be one of {REFINE}, got {self.refine!r}")


class LevelPath:
    """A rod system moved from equilibrium to equilibrium in one level parameter.

    Args:
        system: the rod system; its boundary conditions read ``load``.
        load: the level's load.
        options: how levels are reached.
        level: the level of the system's current state, an equilibrium there (None: not
            one of any level yet; "linear" steps only).
        check: called after every converged solve (:data:`Check`).
        recentre: called before every solve (:data:`Recentre`).

    Attributes:
        level: the level of the current equilibrium.
        iterations: Newton iterations of all solves, failed ones and proximal steps included.
        solves: solves made, failed ones included.
        history: (log level, Lambda_OC) of every equilibrium :meth:`seek` measured (finite
            values), in path order: the secant's data.
    """

    def __init__(self, system: RodSystem, load: LevelLoad, options: LevelOptions,
                 level: float | None = None, check: Check | None = None,
                 recentre: Recentre | None = None) -> None:
        if level is None and options.steps != "linear":
            raise ValueError(f"steps={options.steps!r} needs the level of the current state")
        self.system = system
        self.load = load
        self.options = options
        self.level = level
        self.check = check
        self.recentre = recentre
        self.iterations = 0
        self.solves = 0
        self.history: list[tuple[float, float]] = []
        #: (level, positions [m]) of the equilibrium before the current one.
        self._previous: tuple[float, np.ndarray] | None = None

    # -- one level -------------------------------------------------------------------------
    def solve(self, value: float) -> Coroutine[str]:
        """The static equilibrium at level ``value`` from the current state; "" when found
        and accepted, else why not (the state and level then stay as they were)."""
        opts = self.options
        system = self.system
        self._recentre()
        saved = system.state.copy()
        guess = self._predicted(value)
        if guess is not None:
            system.state.x = guess
        self.load.hold(value)
        system.set_load(1.0)
        if guess is not None and system.history is not None:
            # The predictor's jump is part of the way a knot type could change.
            system.history.insert(0, saved.x.copy())
        self.solves += 1
        r, iterations, _ = yield from static_solve(system, opts.newton, opts.proximal_dt,
                                                   opts.proximal_steps)
        self.iterations += iterations
        why = "" if r.converged else f"Newton {r.reason} at {opts.name} {value:.4g} {opts.unit}"
        if not why and self.check is not None:
            why = self.check(system, StepRecord(1.0, r), value) or ""
        if why:
            system.state = saved
            self.load.hold(self.level)
            return why
        self._previous = (self.level, saved.x)
        self.level = value
        return ""

    def move_to(self, target: float) -> Coroutine[str]:
        """Reach level ``target`` from the current equilibrium by the options' ``steps``; ""
        on success, else the last reason."""
        steps = self.options.steps
        if steps == "one":
            return (yield from self.solve(target))
        if steps == "linear":
            return (yield from self._ramp(target))
        return (yield from self._geometric(target))

    def _geometric(self, target: float) -> Coroutine[str]:
        opts = self.options
        cap = math.inf if opts.down_ratio is None else math.log(opts.down_ratio)
        step = abs(math.log(target / self.level))
        if target < self.level:
            step = min(step, cap)
        failures = 0
        while self.level != target:
            remaining = math.log(target / self.level)
            if step >= abs(remaining):
                f = target
                taken = abs(remaining)
            else:
                f = self.level * math.exp(math.copysign(step, remaining))
                taken = step
            why = yield from self.solve(f)
            if not why:
                step = 2.0 * taken
                if target < self.level:
                    step = min(step, cap)
                continue
            failures += 1
            if failures >= opts.max_failures:
                return f"{why} (after {failures} tries with smaller {opts.name} steps)"
            step = 0.5 * taken
        return ""

    def _ramp(self, target: float) -> Coroutine[str]:
        opts = self.options
        system = self.system
        self._recentre()
        start = system.state.x.copy()
        guess = self._predicted(target)
        self.load.ramp_to(target)
        predictor = None
        if guess is not None:
            u = self._free_dofs(guess)

            def predictor(sys_: RodSystem, t: float, t_next: float) -> None:
                if t == 0.0 and t_next == 1.0:  # the whole move in one step only
                    sys_.accept(u)

        callback = None
        if self.check is not None:
            check = self.check

            def callback(sys_: RodSystem, rec: StepRecord) -> str | None:
                return check(sys_, rec, self.load(rec.t))

        cont = ContinuationOptions(steps=1, newton=opts.newton, proximal_dt=opts.proximal_dt,
                                   proximal_steps=opts.proximal_steps)
        self.solves += 1
        res = yield from continuation(system, cont, callback, predictor)
        self.iterations += res.newton_iterations
        self._previous = None if self.level is None else (self.level, start)
        self.level = target
        return res.failure

    def _recentre(self) -> None:
        if self.recentre is None:
            return
        moved = self.recentre(self.system)
        if moved is not None and self._previous is not None:
            # The previous equilibrium takes the same move, so that the predictor still
            # pairs like vertices.
            self._previous = (self._previous[0], moved(self._previous[1]))

    def _predicted(self, value: float) -> np.ndarray | None:
        """The predictor's guess of the positions [m] at level ``value``, or None."""
        p = self.options.predictor
        if p is None or self._previous is None:
            return None
        if value < self.level and not p.falling:
            return None
        v0, x0 = self._previous
        if self.options.steps == "linear":
            g0, g1, g = v0, self.level, value
        else:
            g0, g1, g = math.log(v0), math.log(self.level), math.log(value)
        if g1 == g0:
            return None
        c = (g - g1) / (g1 - g0)
        if abs(c) > p.max_extrapolation:
            return None
        x1 = self.system.state.x
        guess = x1 + c * (x1 - x0)
        if p.guard is not None and not p.guard(x1, guess):
            return None
        return guess

    def _free_dofs(self, x: np.ndarray) -> np.ndarray:
        """The free dofs of the current state with positions ``x`` [m]."""
        return self.system.free_vector_at(x)

    # -- the search ------------------------------------------------------------------------
    def seek(self, target: float, measure: Measure, search: SearchOptions,
             slope: float | None = None) -> Coroutine[str]:
        """Move to the level at which Lambda_OC (``measure``) is ``target`` within the
        tolerance, from the current equilibrium; "" on success, else why not. Lambda_OC
        falls as the level rises: the level steps up from a knot longer than the target,
        down from a shorter one, until the target is bracketed, then the bracket is
        searched (``search``). Where it cannot come within the tolerance (Lambda_OC jumps
        between contact sets), the tighter side's equilibrium is kept. ``slope``: an
        estimate of dLambda_OC/dlog(level) that a secant search (``search.secant``) steps
        by while the path has measured fewer than two equilibria (e.g. a cheaper model's
        slope at the same knot); such a step aims half the tolerance past the target."""
        name, unit = self.options.name, self.options.unit
        lam = measure(self.system)
        if abs(lam - target) <= search.tolerance:
            return ""
        self._remember(lam)
        up = lam > target  # longer than the target: pull harder
        f_prev, lam_prev = self.level, lam
        ratio = search.step_ratio
        for _ in range(search.max_steps):
            f = self._search_step(f_prev, lam_prev, target, up, ratio, search, slope)
            why = yield from self.move_to(f)
            if why and ratio > search.step_ratio ** (0.5 ** search.retries):
                ratio = math.sqrt(ratio)
                continue
            if why:
                return (f"toward Lambda_OC = {target:g}: {why} (reached {lam_prev:.3f} at "
                        f"{f_prev:.4g} {unit})")
            lam = measure(self.system)
            self._remember(lam)
            if abs(lam - target) <= search.tolerance:
                return ""
            if (lam > target) != up:
                break  # bracketed between f_prev and f
            f_prev, lam_prev = f, lam
        else:
            return (f"Lambda_OC {lam:.3f} after {search.max_steps} {name} steps "
                    f"(target {target:g})")
        # lo: the looser side (Lambda_OC above the target), hi: the tighter side.
        (lo, lam_lo), (hi, lam_hi) = sorted(((f_prev, lam_prev), (f, lam)))
        state_hi = self.system.state.copy() if f == hi else None
        where = "bisection" if search.refine == "bisection" else "bracket search"
        for _ in range(search.max_refinements):
            if search.refine == "bisection":
                mid = math.sqrt(lo * hi)
            else:
                c = 0.5
                if up and math.isfinite(lam_lo):
                    c = min(max((lam_lo - target) / (lam_lo - lam_hi), 0.2), 0.8)
                mid = lo * (hi / lo) ** c
            why = yield from self.move_to(mid)
            if why:
                return f"{where} toward Lambda_OC = {target:g}: {why}"
            lam = measure(self.system)
            self._remember(lam)
            if abs(lam - target) <= search.tolerance:
                return ""
            if lam > target:
                lo, lam_lo = mid, lam
            else:
                hi, lam_hi = mid, lam
                state_hi = self.system.state.copy()
            if hi / lo < search.bracket_ratio:
                break
        if state_hi is not None:
            self.system.state = state_hi
            self.level = hi
            self.load.hold(hi)
        return (f"Lambda_OC could not be brought within {search.tolerance:g} of {target:g} "
                f"(the knot length jumps between contact sets: {lam_hi:.3f} at {hi:.4g} "
                f"{unit})")

    def _search_step(self, f_prev: float, lam_prev: float, target: float, up: bool,
                     ratio: float, search: SearchOptions, slope: float | None) -> float:
        """The level of the next bracketing step from ``f_prev`` (``slope``: :meth:`seek`'s)."""
        if not search.secant:
            return f_prev * (ratio if up else 1.0 / ratio)
        # Secant steps only when pulling harder (SecantPredictor.falling: loosening nears
        # the slip).
        step = self._secant_step(target, lam_prev, slope, search.tolerance) if up else None
        if step is None or (step > 0) != up:
            step = math.log(ratio)
        step = min(max(abs(step), math.log(search.min_step_ratio)), math.log(ratio))
        return f_prev * math.exp(step if up else -step)

    def _remember(self, lam: float) -> None:
        if math.isfinite(lam):
            self.history.append((math.log(self.level), lam))

    def _secant_step(self, target: float, lam: float, estimate: float | None,
                     tolerance: float) -> float | None:
        """Log-level step to ``target`` predicted from the slope dLambda_OC/dlog(level) of
        the last two equilibria measured on the path, or from ``estimate`` before there are
        two (None without a falling slope). With ``estimate`` the step aims half the
        ``tolerance`` past the target: another model's slope (the compliant level's, for
        the sections) has overestimated the knot's response (0.37 to 0.9 of it on the
        study's open knots, docs/sectioned_level.md), and a weaker response then still
        ends within the tolerance."""
        pts = self.history[-2:]
        if len(pts) < 2:
            slope = estimate
            if slope is None:
                return None
            target = target - 0.5 * tolerance
        elif pts[0][0] == pts[1][0]:
            return None
        else:
            slope = (pts[1][1] - pts[0][1]) / (pts[1][0] - pts[0][0])
        if not (math.isfinite(slope) and slope < 0):
            return None
        return (target - lam) / slope
