"""Pulling a tied open knot by a dead force on its sliding end, and to a target knot length
Lambda_OC by searching the force."""

from __future__ import annotations

import dataclasses
import math
import time

from tightknot.knots.open_measures import lambda_oc
from tightknot.knots.scenes import (
    KnotScene,
    bending_force_scale,
    contact_centres,
    end_vertex,
    gauge,
    vertex_radii,
)
from tightknot.loading.diagnose import topology_change
from tightknot.loading.levels import Check, LevelLoad, LevelOptions, LevelPath, SearchOptions
from tightknot.loading.options import LoadPath
from tightknot.loading.recentre import recentre_system
from tightknot.loading.tie import (
    StepHook,
    TieResult,
    end_reaction,
    knot_type_of,
    path_scene,
    resolved_path,
    section_finish,
    system_at,
    tie,
)
from tightknot.solvers.continuation import StepRecord
from tightknot.solvers.newton import NewtonOptions
from tightknot.solvers.program import Coroutine, Program
from tightknot.solvers.system import RodSystem


def pull_path(scene: KnotScene, tied: RodSystem, options: LevelOptions,
              check: Check | None = None) -> LevelPath:
    """The tied open knot ``tied`` (its end held, :func:`tightknot.loading.tie.tie`) pulled
    by a dead force [N] along the pull axis on its sliding end: a level path in the force,
    each solve from the knot centred on its rod. It starts at the force the held end
    carried after the tightening (a jump down to a small dead load would release the knot,
    and it slips off the rod: tie() explains), the state being the tied one."""
    shrink = 1.0 / scene.start_length_ratio
    load = LevelLoad(max(end_reaction(tied), 0.05 * bending_force_scale(scene)))
    axis = scene.pull_axis
    bcs = gauge(scene, positions=tied.state.x)
    bcs.rest_length_scale((shrink, shrink))
    bcs.force(0, end_vertex(scene), lambda t: load(t) * axis)
    system = RodSystem(scene.model, tied.state, bcs)
    system.history = []  # a change of knot type is told from the iterates
    system.add_term(scene.contact)
    return LevelPath(system, load, options, level=load.end, check=check,
                     recentre=lambda s: recentre_system(scene, s)[1])


def knot_kept(scene: KnotScene, types: list[str], rejected: bool,
              hook: StepHook | None = None) -> Check:
    """A level path's check: the equilibrium keeps the scene's knot type (a change is told
    from the solve's iterates: the rod passing through itself, or an end leaving the knot,
    :func:`tightknot.loading.diagnose.topology_change`). Appends each accepted
    equilibrium's type to ``types`` (``rejected``: each refused one's too), and calls
    ``hook("pull", system, record)`` with each accepted one."""

    def check(system: RodSystem, rec: StepRecord, force: float) -> str | None:
        kt = knot_type_of(scene, system.state.x)
        if kt != scene.knot_type:
            if rejected:
                types.append(kt)
            why = topology_change(scene, system.history or [], system.rest, knot_type_of)
            return f"knot type {kt} at force {force:.4g} N: {why}"
        types.append(kt)
        if hook is not None:
            hook("pull", system, rec)
        return None

    return check


def knot_length(scene: KnotScene, system: RodSystem) -> float:
    """Lambda_OC of the system's state, with the deformed radii, on the sections' centres
    (:func:`tightknot.knots.scenes.contact_centres`)."""
    x = system.state.x
    return lambda_oc(contact_centres(scene, x, system.rest), scene.diameter,
                     vertex_radii(scene, x, system.rest)[1])


def tie_to_lambda(
    scene: KnotScene,
    target: float,
    tolerance: float = 0.1,
    force_ratio: float = 1.15,
    max_force_steps: int = 60,
    residual_tol: float = LoadPath.residual_tol,
    hook: StepHook | None = None,
    section_path: str = LoadPath.section_path,
) -> Program[TieResult]:
    """Tie an open knot, then pull until Lambda_OC = ``target`` within ``tolerance``; a
    program (:mod:`tightknot.solvers.program`): ``.run()`` returns the
    :class:`~tightknot.loading.tie.TieResult`.

    After the tightening, the pulling force is stepped geometrically by ``force_ratio``
    (up when the knot is longer than the target, down when shorter; Lambda_OC falls as the
    force grows), a failed step retried from the last equilibrium with the square root of
    the ratio (up to three times: a knot loosened too fast slips off a tail), then bisected
    in log force once the target is bracketed (:meth:`tightknot.loading.levels.LevelPath.
    seek`). Each force is a static Newton solve from the last equilibrium (proximal steps
    where it fails).

    A sectioned scene with ``section_path`` "final" (:func:`tightknot.loading.tie.
    path_scene`) runs all this at the compliant level, then solves the sections'
    equilibrium at the force found there and searches the force again from it: the
    sections change the knot length a force gives. With "pull" (and "auto") the knot is
    relaxed and tightened at the compliant level, and the force is sought with the
    sections from their equilibrium at the tightened knot; with "auto" so too, but where
    the tightened knot is already shorter than ``target`` (the search loosens it) as
    with "final"; with "full", all with them.
    """
    if scene.closed:
        raise ValueError("tie_to_lambda is for open knots")
    if not (math.isfinite(target) and target > 0):
        raise ValueError(f"target Lambda_OC must be finite and > 0, got {target!r}")
    search = SearchOptions(tolerance=tolerance, step_ratio=force_ratio,
                           max_steps=max_force_steps, retries=3, refine="bisection")
    via = path_scene(scene, section_path)
    return Program(_tie_to_lambda(scene, via, target, search, residual_tol, hook,
                                  section_path), "tie_to_lambda")


def _tie_to_lambda(scene: KnotScene, via: KnotScene, target: float, search: SearchOptions,
                   residual_tol: float, hook: StepHook | None,
                   section_path: str) -> Coroutine[TieResult]:
    """The coroutine of :func:`tie_to_lambda` (its arguments checked; the load path on
    ``via``, :func:`tightknot.loading.tie.path_scene`)."""
    res = yield from tie(via, tighten_steps=40, residual_tol=residual_tol, hook=hook,
                         section_path="full")
    if not res.converged:
        return res
    if (via is not scene and resolved_path(scene, section_path) == "pull"
            and (section_path == "pull" or knot_length(via, res.system) > target)):
        # The sections join the tightened knot and the force is sought with them. Their
        # solves cost several compliant ones, so the search's first step is a secant one
        # on the compliant level's slope of Lambda_OC in log force at this knot. ("auto":
        # a knot tighter than the target is loosened to it at the compliant level first,
        # below, and the sections join the loosened knot, as in tie().)
        t0 = time.perf_counter()
        slope, iterations = yield from _compliant_slope(via, res, target, search.step_ratio,
                                                        residual_tol)
        res = dataclasses.replace(res, newton_iterations=res.newton_iterations + iterations,
                                  wall_time_s=res.wall_time_s + time.perf_counter() - t0)
        res = yield from section_finish(scene, dataclasses.replace(res, section_path="pull"),
                                        residual_tol, hook)
        if not res.converged:
            return res
        return (yield from _seek(scene, res, target, dataclasses.replace(search, secant=True),
                                 residual_tol, hook, slope=slope, settle=False))
    measured: list[tuple[float, float]] = []
    res = yield from _seek(via, res, target, search, residual_tol, hook, measured=measured)
    if via is scene or not res.converged:
        return res
    res = yield from section_finish(scene, dataclasses.replace(res, section_path="final"),
                                    residual_tol, hook)
    if not res.converged:
        return res
    # (the sections' equilibrium is one under the pull already: no first solve) The
    # sections move Lambda_OC off the target: the search steps back by a secant on the
    # slope of the compliant search's last two equilibria, where it pulls harder.
    slope = _last_slope(measured)
    return (yield from _seek(scene, res, target,
                             dataclasses.replace(search, secant=slope is not None),
                             residual_tol, hook, pulled=True, slope=slope))


def _last_slope(measured: list[tuple[float, float]]) -> float | None:
    """dLambda_OC/dlog(F) between the last two (log F, Lambda_OC) of a search, None where
    there are fewer, at one force, or Lambda_OC does not fall as the force grows."""
    if len(measured) < 2 or measured[-1][0] == measured[-2][0]:
        return None
    (log_f0, lam0), (log_f1, lam1) = measured[-2:]
    slope = (lam1 - lam0) / (log_f1 - log_f0)
    return slope if math.isfinite(slope) and slope < 0 else None


def _compliant_slope(scene: KnotScene, res: TieResult, target: float, ratio: float,
                     residual_tol: float) -> Coroutine[tuple[float | None, int]]:
    """dLambda_OC/dlog(F) of the tied knot ``res`` of ``scene`` (a level without sections)
    between the force its held end carries and ``ratio`` times that force as a dead load
    (one static solve on a copy: ``res`` is left as it was), None where that solve fails
    or the knot does not tighten, or where the knot is not longer than ``target`` (the
    search then loosens it, by fixed steps: secant steps only pull harder); and the Newton
    iterations it took."""
    tied = system_at(scene, res.system)
    options = LevelOptions(steps="one", proximal_dt=None,
                           newton=NewtonOptions(residual_tol=residual_tol, max_iterations=60))
    path = pull_path(scene, tied, options, knot_kept(scene, [], False))
    f0, lam0 = path.level, knot_length(scene, path.system)
    if not lam0 > target:
        return None, 0
    if (yield from path.solve(f0 * ratio)):
        return None, path.iterations
    slope = (knot_length(scene, path.system) - lam0) / math.log(ratio)
    return (slope if math.isfinite(slope) and slope < 0 else None), path.iterations


def _seek(scene: KnotScene, res: TieResult, target: float, search: SearchOptions,
          residual_tol: float, hook: StepHook | None, pulled: bool = False,
          slope: float | None = None, settle: bool = True,
          measured: list[tuple[float, float]] | None = None) -> Coroutine[TieResult]:
    """From ``res`` (an open knot of ``scene`` in equilibrium), the pull whose Lambda_OC is
    ``target``: first the equilibrium under the force the end carries now, centred on its
    rod (unless ``pulled``: ``res`` is one under that dead force already; without
    ``settle`` only where ``res``'s Lambda_OC is within the tolerance already), then the
    force searched (``search``; ``slope``: :meth:`~tightknot.loading.levels.LevelPath.
    seek`'s first estimate of dLambda_OC/dlog F). ``measured``: filled with the search's
    (log F, Lambda_OC) of each equilibrium it measured, in order."""
    start = time.perf_counter()
    types = list(res.knot_types)
    # Every force is one static solve: the search itself retries a failed step.
    options = LevelOptions(steps="one", proximal_steps=200,
                           newton=NewtonOptions(residual_tol=residual_tol, max_iterations=60))
    path = pull_path(scene, res.system, options, knot_kept(scene, types, True, hook))

    def done(why: str) -> TieResult:
        return TieResult(not why, f"pull: {why}" if why else "", res.phases,
                         res.newton_iterations + path.iterations,
                         res.wall_time_s + time.perf_counter() - start, types, path.level,
                         path.system, section_path=res.section_path)

    # The held end's equilibrium is one under the dead force it carries but for the
    # end's moment and the re-centring (Lambda_OC 0.002 apart on the 125 mm knot with
    # sections): where the search steps from it anyway, that first solve may be left out.
    if not pulled and (settle or abs(knot_length(scene, path.system) - target)
                       <= search.tolerance):
        why = yield from path.solve(path.level)
        if why:
            return done(why)
    why = yield from path.seek(target, lambda s: knot_length(scene, s), search, slope)
    if measured is not None:
        measured.extend(path.history)
    return done(why)
