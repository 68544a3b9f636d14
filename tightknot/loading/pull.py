"""Pulling a tied open knot to a target knot length Lambda_OC by searching the force."""

from __future__ import annotations

import math
import time

from tightknot.knots.open_measures import lambda_oc
from tightknot.knots.scenes import (
    KnotScene,
    bending_force_scale,
    end_vertex,
    gauge,
    vertex_radii,
)
from tightknot.loading.recentre import recentre_system
from tightknot.loading.tie import StepHook, TieResult, end_reaction, knot_type_of, tie
from tightknot.solvers.continuation import StepRecord
from tightknot.solvers.dynamic import proximal
from tightknot.solvers.newton import NewtonOptions, newton
from tightknot.solvers.program import Coroutine, Program
from tightknot.solvers.system import RodSystem


def tie_to_lambda(
    scene: KnotScene,
    target: float,
    tolerance: float = 0.1,
    force_ratio: float = 1.15,
    max_force_steps: int = 60,
    residual_tol: float = 1e-6,
    hook: StepHook | None = None,
) -> Program[TieResult]:
    """Tie an open knot, then pull until Lambda_OC = ``target`` within ``tolerance``; a
    program (:mod:`tightknot.solvers.program`): ``.run()`` returns the
    :class:`~tightknot.loading.tie.TieResult`.

    After the tightening, the pulling force is stepped geometrically by ``force_ratio``
    (up when the knot is longer than the target, down when shorter; Lambda_OC falls as the
    force grows), then bisected on the force once the target is bracketed. Each force is a
    static Newton solve from the last equilibrium (proximal steps where it fails).
    """
    if scene.closed:
        raise ValueError("tie_to_lambda is for open knots")
    if not (math.isfinite(target) and target > 0):
        raise ValueError(f"target Lambda_OC must be finite and > 0, got {target!r}")
    return Program(_tie_to_lambda(scene, target, tolerance, force_ratio, max_force_steps,
                                  residual_tol, hook), "tie_to_lambda")


def _tie_to_lambda(scene: KnotScene, target: float, tolerance: float, force_ratio: float,
                   max_force_steps: int, residual_tol: float,
                   hook: StepHook | None) -> Coroutine[TieResult]:
    """The coroutine of :func:`tie_to_lambda` (its arguments checked)."""
    res = yield from tie(scene, tighten_steps=40, residual_tol=residual_tol, hook=hook)
    if not res.converged:
        return res
    start = time.perf_counter()
    system = res.system
    shrink = 1.0 / scene.start_length_ratio
    last = end_vertex(scene)
    axis = scene.pull_axis
    force = [max(end_reaction(system), 0.05 * bending_force_scale(scene))]
    bcs = gauge(scene, positions=system.state.x)
    bcs.rest_length_scale((shrink, shrink))
    bcs.force(0, last, lambda t: force[0] * axis)
    pull = RodSystem(scene.model, system.state, bcs)
    pull.add_term(scene.contact)
    opts = NewtonOptions(residual_tol=residual_tol, max_iterations=60)
    iters = res.newton_iterations
    types = list(res.knot_types)

    def solve_at(f: float) -> Coroutine[tuple[bool, float, str]]:
        nonlocal iters
        recentre_system(scene, pull)  # each force starts from the knot centred on its rod
        saved = pull.state.copy()
        saved_force = force[0]
        force[0] = f
        pull.set_load(1.0)
        r = yield from newton(pull, pull.free_vector(), opts)
        iters += r.iterations
        if not r.converged:
            prox = yield from proximal(pull, 1e-3, 200, opts)
            iters += prox.newton_iterations
            if not prox.converged:
                pull.state = saved
                force[0] = saved_force
                return False, math.nan, f"Newton {r.reason} at force {f:.4g} N"
        kt = knot_type_of(scene, pull.state.x)
        types.append(kt)
        if kt != scene.knot_type:
            pull.state = saved  # back to the last equilibrium that kept the knot
            force[0] = saved_force
            return False, math.nan, (f"knot type {kt} at force {f:.4g} N (the knot slipped "
                                     "off an end, or the rod passed through itself)")
        if hook is not None:
            # Each equilibrium of the force search is a load step of the run's log.
            hook("pull", pull, StepRecord(1.0, r))
        x = pull.state.x
        return True, lambda_oc(x, scene.diameter, vertex_radii(scene, x, pull.rest)[1]), ""

    def done(ok: bool, msg: str) -> TieResult:
        return TieResult(ok, msg, res.phases, iters, res.wall_time_s + time.perf_counter()
                         - start, types, force[0], pull)

    ok, lam, msg = yield from solve_at(force[0])
    if not ok:
        return done(False, f"pull: {msg}")
    if abs(lam - target) <= tolerance:
        return done(True, "")
    up = lam > target  # longer than the target: pull harder
    f_prev, lam_prev = force[0], lam
    ratio = force_ratio
    for _ in range(max_force_steps):
        f = f_prev * (ratio if up else 1.0 / ratio)
        ok, lam, msg = yield from solve_at(f)
        if not ok and ratio > force_ratio ** 0.125:
            # A failed force step (Newton, or the knot slipping off a tail while it
            # loosens) is retried from the last equilibrium with half the step in log
            # force, up to three times (measured: the 185 mm knot slid off at 1.707 N on
            # its way from 1.963 N to Lambda_OC 15, which it reaches at 1.8 N).
            ratio = math.sqrt(ratio)
            continue
        if not ok:
            return done(False, f"pull toward Lambda_OC = {target:g}: {msg} (reached "
                        f"{lam_prev:.3f} at {f_prev:.4g} N)")
        if abs(lam - target) <= tolerance:
            return done(True, "")
        if (lam > target) != up:
            break  # bracketed between f_prev and f
        f_prev, lam_prev = f, lam
    else:
        return done(False, f"Lambda_OC {lam:.3f} after {max_force_steps} force steps "
                    f"(target {target:g})")
    lo, hi = sorted((f_prev, f))
    state_hi = pull.state.copy()
    for _ in range(30):
        mid = math.sqrt(lo * hi)
        ok, lam, msg = yield from solve_at(mid)
        if not ok:
            return done(False, f"bisection toward Lambda_OC = {target:g}: {msg}")
        if abs(lam - target) <= tolerance:
            return done(True, "")
        # Lambda_OC falls as the force grows.
        if lam > target:
            lo = mid
        else:
            hi = mid
            state_hi = pull.state.copy()
        if hi / lo < 1.0001:
            break
    pull.state = state_hi
    return done(False, f"Lambda_OC could not be brought within {tolerance:g} of {target:g} "
                "(the knot length jumps between contact sets)")
