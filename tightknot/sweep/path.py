"""Tightness sweep of an open knot along ONE continuation path.

The knot is tied once (:func:`tightknot.loading.tie.tie`: rest length shrunk to L0, end held; a
long rod coarse first and refined, as ``tightknot tie`` does), then pulled by a dead force on
its sliding end, level after level, each level's equilibrium starting from the previous one.
The levels are visited from the loosest to the tightest (a pull that only grows, as in the
study's experiments; physics.md sec. 1): pulling forces in increasing order, or target knot
lengths Lambda_OC in decreasing order. The pull is a level path in the force
(:class:`tightknot.loading.levels.LevelPath`, set up by
:func:`tightknot.loading.pull.pull_path`, as tie_to_lambda's): a force level is one static
solve (split into smaller force steps where Newton fails, :func:`path_options`); a Lambda_OC
level is the search of :func:`tightknot.loading.pull.tie_to_lambda` (force steps until the
target is bracketed, then a search on the force inside the bracket) started from the previous
level's force and shape instead of from the tied knot, its force predicted from the previous
levels (secant in log F, :func:`path_search`), and every solve starts from the secant
extrapolation of the last two equilibria. So twenty levels cost the tie plus twenty short
searches, little more than the tightest level alone (``tightknot bench sweep`` measures the
ratio).

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

from tightknot.knots.scenes import KnotScene, vertex_radii
from tightknot.loading.levels import LevelOptions, SearchOptions, SecantPredictor, keeps_clear
from tightknot.loading.options import LoadPath, default_coarse_nodes
from tightknot.loading.pull import knot_kept, knot_length, pull_path
from tightknot.loading.refine import tie_refined
from tightknot.loading.tie import TieResult, tie
from tightknot.solvers.newton import NewtonOptions
from tightknot.solvers.program import Coroutine, Program
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


def measure(scene: KnotScene, result: TieResult) -> dict:
    """The knot summary of ``result``'s state (the measurements of
    :func:`tightknot.study.run.run_knot`, same keys)."""
    from tightknot.contact.report import contact_report
    from tightknot.knots.measure import analyze_centerline
    from tightknot.study.resolution import resolution_note
    from tightknot.study.run import CONTACT_TOL, summarise

    x = result.system.state.x
    _, r_v = vertex_radii(scene, x, result.system.rest)
    rep = analyze_centerline(x, scene.diameter, scene.closed, rest_length=scene.rest_length,
                             radii=r_v, contact_tol=CONTACT_TOL)
    out = summarise(scene, result, rep, contact_report(scene.contact, x, result.system.rest,
                                                         result.system.state))
    # A level's mesh costs what a tie's does (the trade-off study's numbers, as run_knot says).
    out["resolution"] = resolution_note(scene.closed, scene.model.vertex_count)
    return out


def path_options(scene: KnotScene, residual_tol: float = 1e-6, proximal_steps: int = 60,
                 predictor: bool = True) -> LevelOptions:
    """How the path reaches a force level (:class:`tightknot.loading.levels.LevelOptions`):
    geometric force steps, a failed one split, giving up after three failed solves, a
    falling force by at most 1.15 per step (tie_to_lambda's step); with ``predictor`` each
    solve starts from the secant extrapolation of the last two equilibria in log force,
    only while the pull grows (loosening approaches the force below which the knot slips
    off, where a guess along the last motion starts Newton on the wrong side of that limit
    point), within twice the last step, and never bringing two pieces of rod closer by
    more than 10 %."""
    guess = SecantPredictor(falling=False, max_extrapolation=2.0,
                            guard=keeps_clear(scene.contact, 0.9))
    return LevelOptions(steps="geometric", max_failures=3, down_ratio=1.15,
                        newton=NewtonOptions(residual_tol=residual_tol, max_iterations=60),
                        proximal_dt=1e-3, proximal_steps=proximal_steps,
                        predictor=guess if predictor else None)


def path_search(lambda_tolerance: float = 0.1) -> SearchOptions:
    """How the path searches a Lambda_OC level (:class:`tightknot.loading.levels.
    SearchOptions`): tie_to_lambda's search with its steps predicted, since Lambda_OC is
    locally linear in log F. The slope of the last two equilibria of the path (the previous
    levels) predicts the force of the next level (never a larger step than tie_to_lambda's
    1.15, which it takes while no slope is known), and the bracket is narrowed by regula
    falsi in log F. Both only while the pull grows: near the loosest knots Lambda_OC rises
    steeply as the force falls, toward the force where the knot slips off, and a long step
    down releases it."""
    return SearchOptions(tolerance=lambda_tolerance, step_ratio=1.15, max_steps=60,
                         secant=True, refine="regula_falsi")


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
    coarse_nodes: int | str | None = "auto",
) -> PathResult:
    """Tie the open knot ``scene`` once, then reach each level from the previous one.

    Args:
        pull_force: forces [N] (visited in increasing order), or
        target_lambda: knot lengths Lambda_OC (visited in decreasing order).
        lambda_tolerance: how close a Lambda_OC level must be reached.
        residual_tol: Newton tolerance on the scaled residual.
        tighten_steps: initial load steps of the tightening.
        proximal_steps: budget of the proximal fallback of one failed solve (tie_to_lambda
            allows 200: a fallback that takes more than a few tens of steps ends with the
            knot slipped off, expensively).
        predictor: start each solve from the secant extrapolation of the last two
            equilibria (in log force) instead of from the last one.
        on_level: called with each level's result as soon as it is measured.
        coarse_nodes: tie by mesh continuation from this many vertices
            (:func:`tightknot.loading.refine.tie_refined`); "auto": the rule of ``tightknot
            tie`` (:func:`tightknot.loading.options.default_coarse_nodes`) where the scene
            can be rebuilt; None: tie at the scene's own resolution.
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
    if coarse_nodes == "auto":
        coarse_nodes = (default_coarse_nodes(scene.model.vertex_count)
                        if scene.rebuild is not None else None)
    elif coarse_nodes is not None and not (isinstance(coarse_nodes, int)
                                           and 2 <= coarse_nodes < scene.model.vertex_count):
        raise ValueError(f"coarse_nodes must be 'auto', None or an int in [2, "
                         f"{scene.model.vertex_count}), got {coarse_nodes!r}")
    levels = sorted(raw, reverse=(kind == LAMBDA))
    return Program(_tightness_path(scene, kind, levels, lambda_tolerance, residual_tol,
                                   tighten_steps, proximal_steps, predictor, on_level,
                                   coarse_nodes), "tightness_path").run()


def _tightness_path(scene: KnotScene, kind: str, levels: list[float], lambda_tolerance: float,
                    residual_tol: float, tighten_steps: int, proximal_steps: int,
                    predictor: bool, on_level: Callable[[LevelResult], None] | None,
                    coarse_nodes: int | None) -> Coroutine[PathResult]:
    """The coroutine of :func:`tightness_path` (its arguments checked, levels in order)."""
    start = time.perf_counter()
    if coarse_nodes is None:
        tied = yield from tie(scene, tighten_steps=tighten_steps, residual_tol=residual_tol)
    else:
        tied = yield from tie_refined(scene, coarse_nodes, tighten_steps=tighten_steps,
                                      residual_tol=residual_tol)
    t_tie = time.perf_counter() - start
    if not tied.converged:
        return PathResult(False, f"tie: {tied.failure}", tied, [], t_tie,
                          time.perf_counter() - start, list(tied.knot_types))
    types: list[str] = []  # the accepted equilibria's only
    path = pull_path(scene, tied.system, path_options(scene, residual_tol, proximal_steps,
                                                      predictor), knot_kept(scene, types, False))
    search = path_search(lambda_tolerance)

    def knot_length_or_inf(system: RodSystem) -> float:
        # +inf without contact: the loosest possible knot
        lam = knot_length(scene, system)
        return lam if math.isfinite(lam) else math.inf

    # The tied knot under the dead load it carried while held: the path's first equilibrium.
    why = yield from path.solve(path.level)
    if why:
        return PathResult(False, f"pull: first equilibrium: {why}", tied, [], t_tie,
                          time.perf_counter() - start, list(tied.knot_types) + types,
                          path.system)
    results: list[LevelResult] = []
    failure = ""
    for target in levels:
        t0 = time.perf_counter()
        it0, s0 = path.iterations, path.solves
        if kind == FORCE:
            why = yield from path.move_to(target)
        else:
            why = yield from path.seek(target, knot_length_or_inf, search)
        lam = knot_length_or_inf(path.system)
        level = LevelResult(kind, float(target), not why, why, float(path.level),
                            lam if math.isfinite(lam) else None, path.iterations - it0,
                            path.solves - s0, 0.0)
        if not why:
            res = TieResult(True, "", tied.phases, level.newton_iterations, 0.0,
                            [types[-1]] if types else [], path.level, path.system)
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
                      list(tied.knot_types) + types, path.system)


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
