"""Tightness sweep of an open knot along ONE continuation path.

The knot is tied once (:func:`tightknot.loading.tie.tie`: rest length shrunk to L0, end held),
then pulled by a dead force on its sliding end, level after level, each level's equilibrium
starting from the previous one. The levels are visited from the loosest to the tightest (a
pull that only grows, as in the study's experiments; physics.md sec. 1): pulling forces in
increasing order, or target knot lengths Lambda_OC in decreasing order. A force level is
one static solve (split into smaller force steps where Newton fails); a Lambda_OC level is
the search of :func:`tightknot.loading.pull.tie_to_lambda` (force steps until the target is
bracketed, then a search on the force inside the bracket) started from the previous level's
force and shape instead of from the tied knot, its force predicted from the previous
levels (secant in log F), and every solve starts from the secant extrapolation of the last
two equilibria. So twenty levels cost the tie plus twenty short searches, little more
than the tightest level alone (``tightknot bench sweep`` measures the ratio).

Every converged solve is checked for the knot type (Alexander polynomial): a change is a
topology failure (the knot slipped off an end or the rod passed through itself), never
accepted; the state goes back to the last good equilibrium and the step is split. A level
that cannot be reached is reported as failed with the reason, and the path goes on to the
next level from the last good equilibrium.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tightknot.knots.open_measures import lambda_oc
from tightknot.knots.scenes import (
    KnotScene,
    bending_force_scale,
    end_vertex,
    gauge,
    vertex_radii,
)
from tightknot.loading.options import LoadPath
from tightknot.loading.tie import TieResult, end_reaction, knot_type_of, tie
from tightknot.solvers.newton import NewtonOptions, newton
from tightknot.solvers.system import RodSystem

#: Level kinds: a pulling force [N] or a target knot length Lambda_OC.
FORCE, LAMBDA = "pull_force", "target_lambda"


@dataclass
class LevelResult:
    """One level of a tightness path.

    Attributes:
        kind: "pull_force" or "target_lambda".
        target: the level's force [N] or Lambda_OC.
        reached: the level was reached (force applied; Lambda_OC within the tolerance)
            with the knot type kept.
        failure: why not ("" when reached).
        pull_force_N: force on the end at the level's equilibrium [N] (the last good one
            when not reached).
        lambda_oc: Lambda_OC there (None without contact).
        newton_iterations: Newton iterations of this level's solves (from the previous level).
        solves: static solves of this level (failed ones included).
        wall_time_s: wall-clock time of this level, its measurements included [s].
        summary: the knot summary at the level (keys of :func:`tightknot.study.run.summarise`;
            its newton_iterations and wall_time_s are this level's), None when not reached.
    """

    kind: str
    target: float
    reached: bool
    failure: str
    pull_force_N: float
    lambda_oc: float | None
    newton_iterations: int
    solves: int
    wall_time_s: float
    summary: dict | None = None

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready dict."""
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


@dataclass
class PathResult:
    """A tightness path: the tie, then every level in the order visited.

    Attributes:
        converged: the tie and every level succeeded.
        failure: the first failure ("" when converged).
        tie: the tie's result (its system is the tied, held knot).
        levels: one result per level, loosest first.
        tie_wall_time_s: wall-clock time of the tie [s].
        wall_time_s: wall-clock time of the whole path [s].
        knot_types: knot type of the tie's steps and of each accepted equilibrium of the
            pull (a solve that changed it was rejected: see the levels' failures).
        system: the pull system (its state is the last good equilibrium), None if the tie
            failed.
    """

    converged: bool
    failure: str
    tie: TieResult
    levels: list[LevelResult]
    tie_wall_time_s: float
    wall_time_s: float
    knot_types: list[str] = field(default_factory=list)
    system: RodSystem | None = None


class _Pull:
    """The pulled knot: a dead force on the sliding end, stepped from equilibrium to
    equilibrium (the pull set-up of :func:`tightknot.loading.pull.tie_to_lambda`)."""

    def __init__(self, scene: KnotScene, tied: TieResult, residual_tol: float,
                 proximal_steps: int, predictor: bool = True) -> None:
        self.scene = scene
        system = tied.system
        shrink = 1.0 / scene.start_length_ratio
        # Start from the force the held end carries after the tightening (a jump to a small
        # dead load would release the knot; tie() explains).
        self.force = max(end_reaction(system), 0.05 * bending_force_scale(scene))
        self._applied = self.force
        axis = scene.pull_axis
        bcs = gauge(scene, positions=system.state.x)
        bcs.rest_length_scale((shrink, shrink))
        bcs.force(0, end_vertex(scene), lambda t: self._applied * axis)
        self.system = RodSystem(scene.model, system.state, bcs)
        self.system.add_term(scene.contact)
        self.system.set_load(1.0)
        self.options = NewtonOptions(residual_tol=residual_tol, max_iterations=60)
        self.proximal_steps = proximal_steps
        self.predictor = predictor
        #: (log force, positions) of the equilibrium before the current one.
        self._previous: tuple[float, np.ndarray] | None = None
        self.iterations = 0
        self.solves = 0
        self.knot_types: list[str] = []
        #: (log force, Lambda_OC) of the equilibria measured so far, in path order.
        self.history: list[tuple[float, float]] = []

    def solve(self, f: float) -> str:
        """Equilibrium under force ``f`` [N] from the current state; "" on success, else
        the reason (the state is then put back)."""
        from tightknot.loading.recentre import recentre_system
        from tightknot.solvers.dynamic import proximal

        _, moved = recentre_system(self.scene, self.system)
        if moved is not None and self._previous is not None:
            # The knot was slid back to mid-rod (tie() explains): the previous equilibrium
            # takes the same slide, so that the secant predictor still pairs like vertices.
            self._previous = (self._previous[0], moved(self._previous[1]))
        saved = self.system.state.copy()
        if self.predictor:
            self._predict(f)
        self._applied = f
        self.system.set_load(1.0)
        self.solves += 1
        r = newton(self.system, self.system.free_vector(), self.options).run()
        self.iterations += r.iterations
        why = ""
        if not r.converged:
            # A limit point (a loop flips, the contact set jumps): proximal steps descend to
            # the next equilibrium where static Newton has no nearby solution (as tie_to_lambda).
            prox = proximal(self.system, 1e-3, self.proximal_steps, self.options).run()
            self.iterations += prox.newton_iterations
            if not prox.converged:
                why = f"Newton {r.reason} at force {f:.4g} N"
        if not why:
            kt = knot_type_of(self.scene, self.system.state.x)
            if kt == self.scene.knot_type:
                self.knot_types.append(kt)  # the accepted equilibria only
            else:
                why = (f"knot type {kt} at force {f:.4g} N (the knot slipped off an end, or "
                       "the rod passed through itself)")
        if why:
            self.system.state = saved
            self._applied = self.force
            return why
        self._previous = (math.log(self.force), saved.x)
        self.force = f
        return ""

    def _predict(self, f: float) -> None:
        """Secant predictor: extrapolate the last two equilibria linearly in log force to
        ``f`` (Newton then starts near the new equilibrium instead of at the old one).
        Only when the pull grows: loosening approaches the force below which the knot
        slips off (a limit point), where a guess along the last motion starts Newton on the
        wrong side of it (measured on the 185 mm knot at 300 vertices: with the predictor
        it slipped at 2.04 N on the way to Lambda_OC = 15, without it 15.0 is reached at
        1.77 N, as tie_to_lambda reaches it). Skipped also when it would bring two pieces
        of rod closer by more than 10 %: a predictor must not push the rod into (or
        through) itself; Newton's contact step bound protects only its own steps."""
        if self._previous is None or f < self.force:
            return
        g0, x0 = self._previous
        g1 = math.log(self.force)
        if g1 == g0:
            return
        c = (math.log(f) - g1) / (g1 - g0)
        if abs(c) > 2.0:
            return  # far outside the last step: a linear guess is no better than none
        x1 = self.system.state.x
        xp = x1 + c * (x1 - x0)
        contact = self.scene.contact
        if contact.min_distance(xp)[0] >= 0.9 * contact.min_distance(x1)[0]:
            self.system.state.x = xp

    def move_to(self, target: float, max_failures: int = 3, down_ratio: float = 1.15) -> str:
        """Reach force ``target`` [N] from the current equilibrium: one step when it
        converges, else geometric sub-steps (the log-force step halved after a failure,
        doubled after a success), giving up after ``max_failures`` failed solves (a failed
        solve costs its proximal budget; past a few, the knot is slipping: no equilibrium
        near this path). A falling force moves by at most a factor ``down_ratio`` per step
        (tie_to_lambda's step): a sudden drop of the dead load lets the knot spring open
        and slip off (tie() explains). "" on success, else the last reason."""
        step = abs(math.log(target / self.force))
        if target < self.force:
            step = min(step, math.log(down_ratio))
        failures = 0
        while self.force != target:
            remaining = math.log(target / self.force)
            if step >= abs(remaining):
                f = target
                taken = abs(remaining)
            else:
                f = self.force * math.exp(math.copysign(step, remaining))
                taken = step
            why = self.solve(f)
            if not why:
                step = 2.0 * taken
                if target < self.force:
                    step = min(step, math.log(down_ratio))
                continue
            failures += 1
            if failures >= max_failures:
                return f"{why} (after {failures} tries with smaller force steps)"
            step = 0.5 * taken
        return ""

    def lambda_oc(self) -> float:
        """Lambda_OC of the current state with the deformed radii (+inf without contact:
        the loosest possible knot)."""
        x = self.system.state.x
        lam = lambda_oc(x, self.scene.diameter, vertex_radii(self.scene, x, self.system.rest)[1])
        return lam if math.isfinite(lam) else math.inf

    def _remember(self, lam: float) -> None:
        if math.isfinite(lam):
            self.history.append((math.log(self.force), lam))

    def _secant_step(self, target: float, lam: float) -> float | None:
        """Log-force step to ``target`` predicted from the slope dLambda_OC/dlog F of the
        last two equilibria measured on the path (None without a falling slope)."""
        pts = self.history[-2:]
        if len(pts) < 2 or pts[0][0] == pts[1][0]:
            return None
        slope = (pts[1][1] - pts[0][1]) / (pts[1][0] - pts[0][0])
        if not (math.isfinite(slope) and slope < 0):
            return None
        return (target - lam) / slope

    def seek_lambda(self, target: float, tolerance: float, force_ratio: float = 1.15,
                    max_force_steps: int = 60) -> str:
        """Pull to Lambda_OC = ``target`` within ``tolerance`` from the current force; ""
        on success, else the reason. Lambda_OC falls as the force grows.

        The search of tie_to_lambda (force steps until the target is bracketed, then a
        search on the force inside the bracket), with the steps predicted: Lambda_OC is
        locally linear in log F, so the slope of the last two equilibria of the path (the
        previous levels) predicts the force of the next level (secant; never a larger step
        than tie_to_lambda's ``force_ratio``, which it takes while no slope is known), and
        the bracket is narrowed by regula falsi in log F, kept within its middle 60 % so
        that it shrinks by a fixed factor every step. Both only when the pull grows: when it
        must fall (the path's first level, looser than the tied knot) the search is
        tie_to_lambda's own (``force_ratio`` steps, bisection): near the loosest knots
        Lambda_OC rises steeply as the force falls, toward the force where the knot slips
        off, and a long secant step down released the 185 mm knot at 300 vertices
        (measured: slipped at 1.83 N coming from 2.46 N).
        """
        lam = self.lambda_oc()
        if abs(lam - target) <= tolerance:
            return ""
        self._remember(lam)
        up = lam > target  # longer than the target: pull harder
        f_prev, lam_prev = self.force, lam
        for _ in range(max_force_steps):
            # Secant steps only when pulling harder (see _predict: loosening nears the slip).
            step = self._secant_step(target, lam_prev) if up else None
            if step is None or (step > 0) != up:
                step = math.log(force_ratio)
            # At least 0.5 %: a smaller step changes Lambda_OC by less than the contact
            # set's discreteness, so the search would crawl.
            step = min(max(abs(step), math.log(1.005)), math.log(force_ratio))
            f = f_prev * math.exp(step if up else -step)
            why = self.move_to(f)
            if why:
                return (f"toward Lambda_OC = {target:g}: {why} (reached {lam_prev:.3f} at "
                        f"{f_prev:.4g} N)")
            lam = self.lambda_oc()
            self._remember(lam)
            if abs(lam - target) <= tolerance:
                return ""
            if (lam > target) != up:
                break  # bracketed between f_prev and f
            f_prev, lam_prev = f, lam
        else:
            return (f"Lambda_OC {lam:.3f} after {max_force_steps} force steps "
                    f"(target {target:g})")
        # lo: the looser side (Lambda_OC above the target), hi: the tighter side.
        (lo, lam_lo), (hi, lam_hi) = sorted(((f_prev, lam_prev), (f, lam)))
        state_hi = self.system.state.copy() if f == hi else None
        for _ in range(30):
            t = 0.5  # bisection in log F, as tie_to_lambda
            if up and math.isfinite(lam_lo):
                t = min(max((lam_lo - target) / (lam_lo - lam_hi), 0.2), 0.8)
            mid = lo * (hi / lo) ** t
            why = self.move_to(mid)
            if why:
                return f"bracket search toward Lambda_OC = {target:g}: {why}"
            lam = self.lambda_oc()
            self._remember(lam)
            if abs(lam - target) <= tolerance:
                return ""
            if lam > target:
                lo, lam_lo = mid, lam
            else:
                hi, lam_hi = mid, lam
                state_hi = self.system.state.copy()
            if hi / lo < 1.0001:
                break
        if state_hi is not None:
            # Keep the tighter side of the bracket (as tie_to_lambda does).
            self.system.state = state_hi
            self.force = self._applied = hi
        return (f"Lambda_OC could not be brought within {tolerance:g} of {target:g} (the knot "
                f"length jumps between contact sets: {lam_hi:.3f} at {hi:.4g} N)")


def measure(scene: KnotScene, result: TieResult) -> dict:
    """The knot summary of ``result``'s state (the measurements of
    :func:`tightknot.study.run.run_knot`, same keys)."""
    from tightknot.contact.report import contact_report
    from tightknot.knots.measure import analyze_centerline
    from tightknot.study.run import CONTACT_TOL, summarise

    x = result.system.state.x
    _, r_v = vertex_radii(scene, x, result.system.rest)
    rep = analyze_centerline(x, scene.diameter, scene.closed, rest_length=scene.rest_length,
                             radii=r_v, contact_tol=CONTACT_TOL)
    return summarise(scene, result, rep, contact_report(scene.contact, x))


def tightness_path(
    scene: KnotScene,
    pull_force: list[float] | None = None,
    target_lambda: list[float] | None = None,
    lambda_tolerance: float = LoadPath.lambda_tolerance,
    residual_tol: float = LoadPath.residual_tol,
    tighten_steps: int = LoadPath.tighten_steps,
    proximal_steps: int = 60,
    predictor: bool = True,
    on_level: Callable[[LevelResult], None] | None = None,
) -> PathResult:
    """Tie the open knot ``scene`` once, then reach each level from the previous one.

    Args:
        pull_force: forces [N] (visited in increasing order), or
        target_lambda: knot lengths Lambda_OC (visited in decreasing order).
        lambda_tolerance: how close a Lambda_OC level must be reached.
        residual_tol: Newton tolerance on the scaled residual.
        tighten_steps: initial load steps of the tightening.
        proximal_steps: budget of the proximal fallback of one failed solve (tie_to_lambda
            allows 200; measured on the 185 mm knot at 300 vertices, a fallback that takes
            more than a few tens of steps ends with the knot slipped off, at ~30 s each).
        predictor: start each solve from the secant extrapolation of the last two
            equilibria (in log force) instead of from the last one.
        on_level: called with each level's result as soon as it is measured.
    """
    if scene.closed:
        raise ValueError("a tightness path is for open knots (the closed knot is not pulled)")
    if (pull_force is None) == (target_lambda is None):
        raise ValueError("give pull_force [N] or target_lambda (Lambda_OC), one of them")
    kind = FORCE if pull_force is not None else LAMBDA
    raw = pull_force if pull_force is not None else target_lambda
    if not raw or not all(math.isfinite(v) and v > 0 for v in raw):
        raise ValueError(f"{kind} must be a non-empty list of finite values > 0, got {raw!r}")
    if not (math.isfinite(lambda_tolerance) and lambda_tolerance > 0):
        raise ValueError(f"lambda_tolerance must be finite and > 0, got {lambda_tolerance!r}")
    levels = sorted(raw, reverse=(kind == LAMBDA))
    start = time.perf_counter()
    tied = tie(scene, tighten_steps=tighten_steps, residual_tol=residual_tol).run()
    t_tie = time.perf_counter() - start
    if not tied.converged:
        return PathResult(False, f"tie: {tied.failure}", tied, [], t_tie,
                          time.perf_counter() - start, list(tied.knot_types))
    pull = _Pull(scene, tied, residual_tol, proximal_steps, predictor)
    # The tied knot under the dead load it carried while held: the path's first equilibrium.
    why = pull.solve(pull.force)
    if why:
        return PathResult(False, f"pull: first equilibrium: {why}", tied, [], t_tie,
                          time.perf_counter() - start, list(tied.knot_types) + pull.knot_types,
                          pull.system)
    results: list[LevelResult] = []
    failure = ""
    for target in levels:
        t0 = time.perf_counter()
        it0, s0 = pull.iterations, pull.solves
        why = (pull.move_to(target) if kind == FORCE
               else pull.seek_lambda(target, lambda_tolerance))
        lam = pull.lambda_oc()
        level = LevelResult(kind, float(target), not why, why, float(pull.force),
                            lam if math.isfinite(lam) else None, pull.iterations - it0,
                            pull.solves - s0, 0.0)
        if not why:
            res = TieResult(True, "", tied.phases, level.newton_iterations, 0.0,
                            [pull.knot_types[-1]] if pull.knot_types else [],
                            pull.force, pull.system)
            level.summary = measure(scene, res)
        level.wall_time_s = time.perf_counter() - t0
        if level.summary is not None:
            level.summary["wall_time_s"] = level.wall_time_s
        if why and not failure:
            failure = f"level {kind} = {target:g}: {why}"
        results.append(level)
        if on_level is not None:
            on_level(level)
    return PathResult(not failure, failure, tied, results, t_tie, time.perf_counter() - start,
                      list(tied.knot_types) + pull.knot_types, pull.system)


def level_table(result: PathResult) -> list[dict[str, Any]]:
    """One short row per level (no profiles): target, reached, force, Lambda_OC, gap..."""
    rows = []
    for lv in result.levels:
        s = lv.summary or {}
        rows.append({"kind": lv.kind, "target": lv.target, "reached": lv.reached,
                     "pull_force_N": lv.pull_force_N, "lambda_oc": lv.lambda_oc,
                     "min_gap_over_D0": s.get("min_gap_over_D0"),
                     "min_area_ratio": s.get("min_area_ratio"),
                     "newton_iterations": lv.newton_iterations,
                     "wall_time_s": lv.wall_time_s, "failure": lv.failure})
    return rows
