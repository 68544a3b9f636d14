"""Tying and tightening the study's knots: the load paths that solve a :class:`KnotScene`.

Phase 1 (``tighten``): the rest length shrinks from the scene's start length to L0; an open
knot's end slides freely along the pull axis under a small tension (``hold_force``), so
the tails feed the knot as it closes. Phase 2 (``pull``, open knots): the sliding end is
pulled along the axis by a dead force growing geometrically to the target, or moved to a
target end-to-end distance. After every converged load step the knot type is checked
(Alexander polynomial); a change stops the run as failed (physics.md sec. 2: a knot that
passed through itself has failed).

An open knot is kept centred on its rod: after the relaxation, after every converged load
step but the last, and before every force of ``tie_to_lambda``, its material slides along
the rod until the knot's centre is mid-rod (``recentre_open_knot``). Without friction the
knot's place along the rod is a zero mode of the energy, and the short tails of the
study's 185 mm knot (3.9 D0 each at Lambda_OC 15) leave no room for the drift that
round-off otherwise steers (tests/knots/test_recentre.py). A rod with twist is not
re-centred (its twist field would have to slide too). The returned equilibrium is always
a converged solve; a slide is followed by one.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tightknot.knots import topology
from tightknot.knots.scenes import (
    KnotScene,
    bending_force_scale,
    end_vertex,
    gauge,
    vertex_radii,
)
from tightknot.rods.contact import SelfIntersectionError
from tightknot.rods.state import State
from tightknot.solvers.dynamic import ImmediateSystem
from tightknot.solvers.newton import NewtonOptions, newton_gen, newton_solve, run_now
from tightknot.solvers.static import (
    ContinuationOptions,
    StaticResult,
    StepRecord,
    continuation_gen,
)
from tightknot.solvers.system import RodSystem

StepHook = Callable[[str, RodSystem, StepRecord], None]


@dataclass
class TieResult:
    """Outcome of tying a knot.

    Attributes:
        converged: every phase reached its end.
        failure: what failed and where ("" when converged).
        phases: the continuation result of each phase, by name.
        newton_iterations: total Newton iterations.
        wall_time_s: wall-clock time [s].
        knot_types: knot type after each converged load step.
        pull_force_N: final pulling force (open knots) [N].
        system: the last phase's system (its state is the result; after a failed load
            step, the last equilibrium).
        failed_state: where the failing load step's solve stopped (None when converged).
    """

    converged: bool
    failure: str
    phases: dict[str, StaticResult]
    newton_iterations: int
    wall_time_s: float
    knot_types: list[str] = field(default_factory=list)
    pull_force_N: float = 0.0
    system: RodSystem | None = None
    failed_state: State | None = None


def knot_type_of(scene: KnotScene, x: np.ndarray) -> str:
    """Knot type of the centerline (open curves closed by a far-away arc); "undefined"
    when no projection of it is generic (strands within 1e-10 of its size: it passes
    through itself, or nearly), which the topology checks then report as a change."""
    pts = x if scene.closed else topology.close_open_curve(x)
    try:
        return topology.knot_type(pts)
    except topology.TopologyError:
        return "undefined (the curve nearly passes through itself)"


def _checker(scene: KnotScene, phase: str, types: list[str], hook: StepHook | None,
             knot_type: Callable[[KnotScene, np.ndarray], str] = knot_type_of):
    def check(system: RodSystem, rec: StepRecord) -> str | None:
        kt = knot_type(scene, system.state.x)
        types.append(kt)
        if hook is not None:
            hook(phase, system, rec)
        if kt != scene.knot_type:
            why = ("the rod passed through itself" if scene.closed else
                   "the knot slipped off an end, or the rod passed through itself")
            return (f"topology changed in phase {phase} at load t={rec.t:.4g}: knot type "
                    f"{kt}, expected {scene.knot_type} ({why})")
        # The next load step starts from the knot centred on its rod (open knots); the
        # last step's equilibrium is the phase's result and stays as it is.
        if rec.t < 1.0 - 1e-12:
            recentre_system(scene, system)
        return None
    return check


def _opts(steps: int, tol: float) -> ContinuationOptions:
    # Knots have limit points along their paths (a loop that flips, a tail that slides
    # through): proximal steps carry the solve through them (proximal_dt).
    return ContinuationOptions(steps=steps, max_step=1.0 / steps, min_step=1e-4,
                               newton=NewtonOptions(residual_tol=tol, max_iterations=60),
                               proximal_dt=1e-3, proximal_steps=200)


def tie(
    scene: KnotScene,
    pull_force: float | None = None,
    end_distance: float | None = None,
    tighten_steps: int = 20,
    pull_steps: int = 20,
    residual_tol: float = 1e-6,
    hold_force_scale: float = 0.05,
    relax_iterations: int = 2000,
    hook: StepHook | None = None,
) -> TieResult:
    """Tie ``scene``: shrink its rest length to L0, then (open knots) pull.

    Args:
        pull_force: final pulling force [N] (open knots).
        end_distance: final end-to-end distance [m] (open knots; instead of a force).
        tighten_steps, pull_steps: initial numbers of load steps (adaptive afterwards).
        residual_tol: Newton tolerance on the scaled residual.
        hold_force_scale: tension on a sliding end while tightening, over EI/D0^2.
        relax_iterations: Newton budget of the relaxation of the start curve.
        hook: called after each converged step with (phase, system, record).
    """
    return run_now(tie_gen(scene, pull_force, end_distance, tighten_steps, pull_steps,
                           residual_tol, hold_force_scale, relax_iterations, hook))


def tie_gen(
    scene: KnotScene,
    pull_force: float | None = None,
    end_distance: float | None = None,
    tighten_steps: int = 20,
    pull_steps: int = 20,
    residual_tol: float = 1e-6,
    hold_force_scale: float = 0.05,
    relax_iterations: int = 2000,
    hook: StepHook | None = None,
    problem: Callable[[RodSystem], Any] = ImmediateSystem,
    start_state: State | None = None,
    knot_type: Callable[[KnotScene, np.ndarray], str] = knot_type_of,
):
    """:func:`tie` as a generator of the solvers' questions (:mod:`tightknot.solvers.newton`):
    every phase's system is handed to the solvers as ``problem(system)`` (default: answered
    at once; a batch of rods answers many rods' questions together,
    :mod:`tightknot.knots.batch`), starting from ``start_state`` (default: the scene's), with the
    knot type computed by ``knot_type``. Returns the :class:`TieResult`."""
    if scene.contact is None:
        raise ValueError(f"{scene.name}: contact='off' cannot tie a knot (without self-contact "
                         "the rod passes through itself); use 'compliant', 'smoothed' or 'rigid'")
    if pull_force is not None and end_distance is not None:
        raise ValueError("give pull_force or end_distance, not both")
    if scene.closed and (pull_force is not None or end_distance is not None):
        raise ValueError("a closed knot is not pulled: pull_force/end_distance are for open knots")
    if pull_force is not None and not (math.isfinite(pull_force) and pull_force > 0):
        raise ValueError(f"pull_force must be finite and > 0 N, got {pull_force!r}")
    if end_distance is not None and not (math.isfinite(end_distance) and end_distance > 0):
        raise ValueError(f"end_distance must be finite and > 0 m, got {end_distance!r}")
    start = time.perf_counter()
    types: list[str] = []
    phases: dict[str, StaticResult] = {}
    iters = 0
    model = scene.model
    f_unit = bending_force_scale(scene)
    last = end_vertex(scene)
    hold = hold_force_scale * f_unit
    axis = scene.pull_axis if scene.pull_axis is not None else np.zeros(3)

    def fail(msg: str, system: RodSystem | None, force: float,
             failed_state: State | None = None) -> TieResult:
        return TieResult(False, msg, phases, iters, time.perf_counter() - start, types,
                         force, system, failed_state)

    # Phase 1: shrink the rest length from the start to L0.
    shrink = 1.0 / scene.start_length_ratio
    # The start curve is not an equilibrium: relax it first (an open knot's end sliding
    # under a small tension, so the loose loops do not swing freely), with a budget for the
    # long, floppy path of a loose knot (measured: 150 iterations for 150 vertices).
    bcs = gauge(scene)
    if not scene.closed:
        bcs.force(0, last, lambda t: hold * axis)
    system = RodSystem(model, scene.state if start_state is None else start_state, bcs)
    system.add_term(scene.contact)
    p = problem(system)
    p.set_load(0.0)
    relax = yield from newton_gen(p, system.free_vector(), NewtonOptions(
        residual_tol=residual_tol, max_iterations=relax_iterations))
    iters += relax.iterations
    if not relax.converged:
        return fail(f"relax: Newton {relax.reason} (residual {relax.residual:.3g}) at the start",
                    system, hold)
    kt = knot_type(scene, system.state.x)
    types.append(kt)
    if kt != scene.knot_type:
        return fail(f"relax: knot type {kt}, expected {scene.knot_type}", system, hold)
    recentre_system(scene, system)
    if scene.closed:
        bcs = gauge(scene, positions=system.state.x)
    else:
        # The end then follows the shrink (end-to-end distance scaled with the rest
        # length): with a freely sliding end the tail slides out of the shrinking loop and
        # the knot slips off the rod (measured: knot type 0_1 at 55 % of the path).
        bcs = gauge(scene, positions=system.state.x, sliding_end=False)
        span = float(system.state.x[last] @ axis)
        bcs.pin(0, last, translation=lambda t: (shrink - 1.0) * t * span * axis)
    bcs.rest_length_scale((1.0, shrink))
    system = RodSystem(model, system.state, bcs)
    system.add_term(scene.contact)
    p = problem(system)
    p.set_load(0.0)

    def similar(sys_: RodSystem, t0: float, t1: float) -> None:
        # Self-similar predictor: the previous equilibrium scaled about the pinned first
        # vertex (the origin) by the change of rest length keeps every strain; prescribed
        # ends and the gauge's zero coordinates are unchanged by it. (``sys_``: the
        # system, or a batch's rod: what has ``state`` and ``set_load``.)
        c = (1.0 + (shrink - 1.0) * t1) / (1.0 + (shrink - 1.0) * t0)
        sys_.state.x = sys_.state.x * c
        sys_.set_load(t1)

    res = yield from continuation_gen(p, _opts(tighten_steps, residual_tol),
                                      _checker(scene, "tighten", types, hook, knot_type),
                                      similar)
    phases["tighten"] = res
    iters += res.newton_iterations
    if not res.converged:
        return fail(f"tighten: {res.failure}", system, hold, res.failed_state)
    if scene.closed or (pull_force is None and end_distance is None):
        return TieResult(True, "", phases, iters, time.perf_counter() - start, types,
                         hold if not scene.closed else 0.0, system)

    # Phase 2: pull. The end's force at the tightened equilibrium, then the knot centred
    # on its rod.
    f_end = end_reaction(system)
    recentre_system(scene, system)
    state = system.state
    bcs = gauge(scene, positions=state.x)
    bcs.rest_length_scale((shrink, shrink))
    if pull_force is not None:
        # Start from the force the pinned end carried at the end of the tightening (a jump
        # down to a small dead load would release the knot, and it slips off the rod).
        f0 = max(f_end, hold)

        def force_path(t: float) -> np.ndarray:
            return f0 * (pull_force / f0) ** t * axis

        bcs.force(0, last, force_path)
        final_force = pull_force
    else:
        # (after the re-centring, which moves the end by up to an edge's stretch change)
        d_now = float(np.linalg.norm(state.x[last] - state.x[0]))
        delta = end_distance - d_now
        bcs = gauge(scene, positions=state.x, sliding_end=False)
        bcs.rest_length_scale((shrink, shrink))
        bcs.pin(0, last, translation=delta * axis)
        final_force = math.nan
    system = RodSystem(model, state, bcs)
    system.add_term(scene.contact)
    p = problem(system)
    p.set_load(0.0)
    res = yield from continuation_gen(p, _opts(pull_steps, residual_tol),
                                      _checker(scene, "pull", types, hook, knot_type))
    phases["pull"] = res
    iters += res.newton_iterations
    if end_distance is not None:
        # Reaction at the moved end: the residual force there is the pulling force.
        final_force = end_reaction(system)
    if not res.converged:
        return fail(f"pull: {res.failure}", system, final_force, res.failed_state)
    return TieResult(True, "", phases, iters, time.perf_counter() - start, types,
                     final_force, system)


#: A vertex belongs to the knot when a non-local one is within (1 + this) of the nominal
#: diameter (a margin of 5 % finds the loose knots' strands too).
KNOT_EXTENT_TOL = 0.05


def recentre_open_knot(scene: KnotScene, x: np.ndarray, rest: np.ndarray,
                       tol: float = KNOT_EXTENT_TOL) -> tuple[np.ndarray, int]:
    """Slide an open knot's material along the rod by whole edges so that the knot sits
    mid-rod.

    A frictionless knot on a uniform rod can sit anywhere along it: moving the rod's
    material through the knot changes no energy while the tails are straight, so the
    knot's position is a zero mode that Newton steps drift along with whatever asymmetry
    round-off brings (measured: a 1e-9 D0 perturbation of the start left the loose 185 mm
    knot 2 to 6 D0 off centre after the relaxation, and 2 of 4 such runs at 150 vertices,
    3 of 3 at 300, slid off the shorter tail when loosened to Lambda_OC 15). The study's
    knots sit mid-rod, so tie() puts them there. The knot's extent is the span of vertices
    in contact (within ``tol`` of the nominal diameter); the material moves by the whole
    number of edges k nearest to the rest arc between the knot's centre and the rod's
    (``slide_material``: vertex i takes the place of vertex i - k, no interpolation, so
    the knot's shape is kept exactly; an interpolated slide cuts the polyline's corners and
    jammed a tight pull). Returns the new positions [m] and k (0: nothing moved).
    """
    k = _knot_offset(scene, x, rest, tol)
    return (x, 0) if k == 0 else (slide_material(x, k), k)


def _knot_offset(scene: KnotScene, x: np.ndarray, rest: np.ndarray, tol: float) -> int:
    """Whole edges k that bring the knot's centre (middle of the span of vertices in
    contact within ``tol``) to the rod's middle; 0 without contact."""
    from tightknot.knots.contact_map import contact_pairs

    i, j = contact_pairs(x, False, np.full(len(x), scene.diameter / 2.0), tol=tol)
    if not len(i):
        return 0
    idx = np.r_[i, j]
    arc = np.r_[0.0, np.cumsum(rest)]
    delta = 0.5 * arc[-1] - 0.5 * (arc[idx.min()] + arc[idx.max()])
    return int(round(delta / float(np.mean(rest))))


def slide_material(x: np.ndarray, k: int) -> np.ndarray:
    """Open centerline ``x`` [m] with its material moved by ``k`` edges along itself:
    vertex i takes the place of vertex i - k (k > 0: toward the last end). The tail the
    material leaves is extended straight along its end edge, the other is cut, and the
    whole is translated so that the first vertex stays where it was. On a rod of equal
    edges (the open scenes', ``curves.resample_equal_chords``) with straight tails this is
    an exact symmetry of the energy; where edges differ, each takes the strain of the
    length of the place it moves to."""
    n = len(x)
    if not (isinstance(k, (int, np.integer)) and abs(k) < n - 1):
        raise ValueError(f"k must be a whole number with |k| < {n - 1}, got {k!r}")
    if k == 0:
        return x.copy()
    y = np.empty_like(x)
    if k > 0:
        y[k:] = x[:n - k]
        y[:k] = x[0] + (x[0] - x[1]) * np.arange(k, 0, -1)[:, None]
    else:
        m = -k
        y[:n - m] = x[m:]
        y[n - m:] = x[-1] + (x[-1] - x[-2]) * np.arange(1, m + 1)[:, None]
    return y + (x[0] - y[0])


def recentre_system(scene: KnotScene, system: RodSystem
                    ) -> tuple[int, Callable[[np.ndarray], np.ndarray] | None]:
    """Centre an open knot on its rod (``recentre_open_knot``) in place, keeping the
    scene's gauge: the first vertex where it is, the last on the pull axis (e_x through
    the first vertex) and the gauge vertex's z, which a rotation about the pull axis (a
    zero mode as well) restores; a rotation that cannot (the new gauge vertex nearer the
    axis than that z) leaves the knot where it is. A rod with twist keeps its place (its
    twist field would have to slide with it).

    Returns the slide k [edges] and the map that applies the same slide and rotation to
    other positions of the rod (e.g. an earlier equilibrium a predictor extrapolates
    from), or (0, None) when nothing moved."""
    if scene.closed or scene.model.twist or scene.pull_axis is None:
        return 0, None
    if not np.allclose(scene.pull_axis, (1.0, 0.0, 0.0)):
        return 0, None
    x = system.state.x
    k = _knot_offset(scene, x, system.rest, KNOT_EXTENT_TOL)
    if k == 0:
        return 0, None
    y0 = slide_material(x, k)
    g = scene.info["gauge_vertex"]
    p = y0[g] - y0[0]
    zt = x[g, 2] - x[0, 2]
    r = math.hypot(p[1], p[2])
    if r <= abs(zt):
        return 0, None
    beta = math.atan2(p[2], p[1])
    a = math.asin(zt / r)
    # the smaller of the two rotations that put the gauge vertex back at its z
    phi = min((a - beta, math.pi - a - beta),
              key=lambda v: abs(math.remainder(v, 2.0 * math.pi)))
    c, s_ = math.cos(phi), math.sin(phi)

    def turn(w: np.ndarray, z: np.ndarray) -> np.ndarray:
        # slid positions w of z, rotated about the pull axis through their first vertex
        q = w - w[0]
        w[:, 1] = w[0, 1] + c * q[:, 1] - s_ * q[:, 2]
        w[:, 2] = w[0, 2] + s_ * q[:, 1] + c * q[:, 2]
        # The end stays on the pull axis where the gauge holds it (the slid tail is
        # straight to round-off and ~1e-7 m of the tail's own sag: an end pinned at a
        # given end-to-end distance must keep it exactly).
        w[-1, 1:] = z[-1, 1:]
        return w

    def transform(z: np.ndarray) -> np.ndarray:
        return turn(slide_material(z, k), z)

    y = turn(y0, x)
    # The slide must not create what the run would fail on: a tail that is not straight
    # (a knot slipping off an end curls it) is extended along its end edge, which can run
    # it into other strands. Such a slide is not made.
    if scene.contact is not None:
        try:
            scene.contact.check_no_intersection(y)
        except SelfIntersectionError:
            return 0, None
    # (every caller slides an accepted state, whose type is the scene's)
    if knot_type_of(scene, y) != scene.knot_type:
        return 0, None
    system.state = State.initial(scene.model, positions=y)
    return k, transform


def end_reaction(system: RodSystem) -> float:
    """Axial force [N] needed to hold the last vertex where it is (the pulling force)."""
    model = system.model
    x = system.state.x
    # At equilibrium of the free dofs, the external force on the held vertex balances the
    # gradient of the internal energy there: f = dE/dx_end.
    _, grad = system.forces.evaluate(x, system.state.theta, system.state.m_ref, system.rest,
                                     True, None)
    g = grad[model.position_dofs][-1].copy()
    for term in system.extra_terms:
        _, gk, _ = term.evaluate(x, system.rest, True, False)
        g += gk[-1]
    return float(g[0])


def lambda_oc(x: np.ndarray, diameter: float, radii: np.ndarray | float | None = None,
              tol: float = 0.01) -> float:
    """Open-knot length Lambda_OC of centerline ``x`` (physics.md sec. 2), NaN without
    contact; contact where the distance is at most (1 + tol) times the sum of the radii
    (default D0/2; pass the deformed radii of a simulation, as the summaries do)."""
    from tightknot.knots.contact_map import contact_pairs
    from tightknot.knots.open_measures import open_knot_measures

    r = np.full(len(x), diameter / 2) if radii is None else radii
    i, j = contact_pairs(x, False, r, tol=tol)
    s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(x, axis=0), axis=1))]
    return float(open_knot_measures(np.unique(np.r_[i, j]), s, diameter)["Lambda_OC"])


def tie_to_lambda(
    scene: KnotScene,
    target: float,
    tolerance: float = 0.1,
    force_ratio: float = 1.15,
    max_force_steps: int = 60,
    residual_tol: float = 1e-6,
    hook: StepHook | None = None,
) -> TieResult:
    """Tie an open knot, then pull until Lambda_OC = ``target`` within ``tolerance``.

    After the tightening, the pulling force is stepped geometrically by ``force_ratio``
    (up when the knot is longer than the target, down when shorter; Lambda_OC falls as the
    force grows), then bisected on the force once the target is bracketed. Each force is a
    static Newton solve from the last equilibrium (proximal steps where it fails).
    """
    from tightknot.solvers.dynamic import proximal_relax

    if scene.closed:
        raise ValueError("tie_to_lambda is for open knots")
    if not (math.isfinite(target) and target > 0):
        raise ValueError(f"target Lambda_OC must be finite and > 0, got {target!r}")
    res = tie(scene, tighten_steps=40, residual_tol=residual_tol, hook=hook)
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

    def solve_at(f: float) -> tuple[bool, float, str]:
        nonlocal iters
        recentre_system(scene, pull)  # each force starts from the knot centred on its rod
        saved = pull.state.copy()
        saved_force = force[0]
        force[0] = f
        pull.set_load(1.0)
        r = newton_solve(pull, pull.free_vector(), opts)
        iters += r.iterations
        if not r.converged:
            prox = proximal_relax(pull, 1e-3, 200, opts)
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

    ok, lam, msg = solve_at(force[0])
    if not ok:
        return done(False, f"pull: {msg}")
    if abs(lam - target) <= tolerance:
        return done(True, "")
    up = lam > target  # longer than the target: pull harder
    f_prev, lam_prev = force[0], lam
    ratio = force_ratio
    for _ in range(max_force_steps):
        f = f_prev * (ratio if up else 1.0 / ratio)
        ok, lam, msg = solve_at(f)
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
        ok, lam, msg = solve_at(mid)
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
