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
round-off otherwise steers (tests/loading/test_recentre.py). A rod with twist is not
re-centred (its twist field would have to slide too). The returned equilibrium is always
a converged solve; a slide is followed by one.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from tightknot.contact.layer import ContactLayer
from tightknot.contact.sectioned import SectionedLayer
from tightknot.knots import topology
from tightknot.knots.scenes import (
    KnotScene,
    bending_force_scale,
    contact_layer,
    end_vertex,
    gauge,
)
from tightknot.loading.diagnose import topology_change
from tightknot.loading.options import SECTION_PATHS, LoadPath
from tightknot.loading.recentre import recentre_system
from tightknot.rods.state import State
from tightknot.solvers.continuation import (
    ContinuationOptions,
    StaticResult,
    StepRecord,
    continuation,
    descend,
    static_solve,
)
from tightknot.solvers.newton import NewtonOptions, NewtonResult, newton
from tightknot.solvers.program import Coroutine, Program
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
        pull_force_N: final pulling force (open knots) [N]; of a failed pull, the force of
            its last equilibrium.
        system: the last phase's system (its state is the result; after a failed load
            step, the last equilibrium).
        failed_state: where the failing load step's solve stopped (None when converged).
        section_path: the sectioned level's load path as it ran (:func:`path_scene`):
            "final" (the sections joined at the end), "pull" (at the tightened knot) or
            "full"; "" for a level without sections.
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
    section_path: str = ""


def knot_type_of(scene: KnotScene, x: np.ndarray) -> str:
    """Knot type of the scene's centerline ``x`` [m]
    (:func:`tightknot.knots.topology.curve_knot_type`)."""
    return topology.curve_knot_type(x, scene.closed)


def _checker(scene: KnotScene, phase: str, types: list[str], hook: StepHook | None,
             knot_type: Callable[[KnotScene, np.ndarray], str] = knot_type_of):
    def check(system: RodSystem, rec: StepRecord) -> str | None:
        kt = knot_type(scene, system.state.x)
        types.append(kt)
        if hook is not None:
            hook(phase, system, rec)
        if kt != scene.knot_type:
            why = topology_change(scene, system.history or [], system.rest, knot_type)
            return (f"topology changed in phase {phase} at load t={rec.t:.4g}: knot type "
                    f"{kt}, expected {scene.knot_type}: {why}")
        # The next load step starts from the knot centred on its rod (open knots); the
        # last step's equilibrium is the phase's result and stays as it is.
        if rec.t < 1.0 - 1e-12:
            recentre_system(scene, system)
        return None
    return check


def _attached(system: RodSystem, attach: Callable[[RodSystem], None] | None) -> RodSystem:
    """``system`` handed to ``attach`` (a batch), at the start of its load path, keeping the
    iterates of each load step (a topology change is then told from them)."""
    if attach is not None:
        attach(system)
    system.history = []
    system.set_load(0.0)
    return system


def load_step_options(steps: int, tol: float) -> ContinuationOptions:
    """The continuation of a knot's or a tangle's load path: ``steps`` initial load steps,
    Newton to ``tol``."""
    # Knots have limit points along their paths (a loop that flips, a tail that slides
    # through): proximal steps carry the solve through them (proximal_dt).
    return ContinuationOptions(steps=steps, max_step=1.0 / steps, min_step=1e-4,
                               newton=NewtonOptions(residual_tol=tol, max_iterations=60),
                               proximal_dt=1e-3, proximal_steps=200)


def tie(
    scene: KnotScene,
    pull_force: float | None = None,
    end_distance: float | None = None,
    tighten_steps: int = LoadPath.tighten_steps,
    pull_steps: int = LoadPath.pull_steps,
    residual_tol: float = LoadPath.residual_tol,
    hold_force_scale: float = 0.05,
    relax_iterations: int = LoadPath.relax_iterations,
    hook: StepHook | None = None,
    attach: Callable[[RodSystem], None] | None = None,
    start_state: State | None = None,
    knot_type: Callable[[KnotScene, np.ndarray], str] = knot_type_of,
    section_path: str = LoadPath.section_path,
) -> Program[TieResult]:
    """Tie ``scene``: shrink its rest length to L0, then (open knots) pull. A program
    (:mod:`tightknot.solvers.program`): ``tie(scene).run()`` returns the
    :class:`TieResult`; a batch runs many together (:mod:`tightknot.loading.batch`).

    Args:
        pull_force: final pulling force [N] (open knots).
        end_distance: final end-to-end distance [m] (open knots; instead of a force).
        tighten_steps, pull_steps: initial numbers of load steps (adaptive afterwards).
        residual_tol: Newton tolerance on the scaled residual.
        hold_force_scale: tension on a sliding end while tightening, over EI/D0^2.
        relax_iterations: Newton budget of the relaxation of the start curve.
        hook: called after each converged step with (phase, system, record).
        attach: called with each phase's system before it is solved (a batch attaches
            it, :class:`tightknot.solvers.lockstep.BatchRod`).
        start_state: where to start (default: the scene's state).
        knot_type: the knot type of a centerline (default :func:`knot_type_of`).
        section_path: a sectioned scene's load path (:func:`path_scene`): "final" runs it
            at the compliant level and solves the sections' equilibrium under its last
            load (:func:`section_finish`); "full" runs every step with the sections;
            "pull" relaxes and tightens at the compliant level, solves the sections'
            equilibrium there and pulls with them ("final" where nothing is pulled);
            "auto": "final" for a closed knot and for an open one whose pull loosens it
            (a force below the tightened knot's, an end distance shorter than its own),
            "pull" for an open knot pulled tighter.
    """
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
    via = path_scene(scene, section_path)
    if via is not scene and attach is not None:
        raise ValueError(f"{scene.name}: contact='sectioned' is tied one rod at a time (a "
                         "batch's banded systems hold no section dofs)")
    pulled = pull_force is not None or end_distance is not None
    sections = (scene if via is not scene and pulled
                and resolved_path(scene, section_path) == "pull" else None)
    body = _tie(via, pull_force, end_distance, tighten_steps, pull_steps, residual_tol,
                hold_force_scale, relax_iterations, hook, attach, start_state, knot_type,
                sections, loosen_first=section_path == "auto")
    if via is not scene and sections is None:
        body = _then_sections(scene, body, end_distance is not None, residual_tol, hook,
                              knot_type)
    elif via is scene and isinstance(scene.contact, SectionedLayer):
        body = _routed(body, "full")
    return Program(body, "tie")


def _routed(body: Coroutine[TieResult], section_path: str) -> Coroutine[TieResult]:
    """``body``'s result with its :attr:`TieResult.section_path` set."""
    res = yield from body
    return dataclasses.replace(res, section_path=section_path)


def resolved_path(scene: KnotScene, section_path: str = LoadPath.section_path) -> str:
    """``section_path`` ("auto", "final", "full" or "pull") as it runs on ``scene``:
    "auto" is "final" for a closed knot and "pull" for an open one (which runs as "final"
    where the pull loosens the tightened knot, told after the tightening); "pull" is
    "final" for a closed knot (nothing is pulled)."""
    if section_path not in SECTION_PATHS:
        raise ValueError(f"section_path must be one of {', '.join(SECTION_PATHS)}, got "
                         f"{section_path!r}")
    if section_path == "auto":
        return "final" if scene.closed else "pull"
    if section_path == "pull" and scene.closed:
        return "final"
    return section_path


def path_scene(scene: KnotScene, section_path: str = LoadPath.section_path) -> KnotScene:
    """The scene a load path of ``scene`` runs on: ``scene`` itself, but for a sectioned
    scene with ``section_path`` "final", "pull" or "auto" the same rod and start at the
    compliant level ("pull", and "auto" for an open knot: up to the end of the tightening).

    The sections matter where the knot is tight; on the way there (the start's relaxation,
    the tightening) the compliant level keeps the same centerline guarantees (the step
    bound and the proximity check act on the centerlines at both levels) at a fifth of the
    cost per Newton iteration. A knot with one equilibrium under the final load reaches
    it either way, as the closed trefoil does; a pulled open knot can have two, and the
    way there picks one: sections added only under the final force ("final") can settle
    on the other, so "auto" adds them at the tightened knot and pulls with them ("pull"),
    which reaches the knot of a path with the sections all the way ("full")
    (docs/sectioned_level.md measures the three). A pull that loosens the knot ("auto")
    runs at the compliant level, and the sections join at its end: loosened either way, a
    knot ends at the same equilibrium or one shallow minimum from it (docs/sectioned_level.md,
    "`auto` loosens at the compliant level", compares the two at equal force)."""
    if resolved_path(scene, section_path) == "full" or not isinstance(scene.contact,
                                                                     SectionedLayer):
        return scene
    return dataclasses.replace(scene, contact=contact_layer(scene.model, "compliant"),
                               rebuild=None)


def _then_sections(scene: KnotScene, path: Coroutine[TieResult], end_held: bool,
                   residual_tol: float, hook: StepHook | None,
                   knot_type: Callable[[KnotScene, np.ndarray], str]) -> Coroutine[TieResult]:
    """The load path ``path`` (on :func:`path_scene`), then the sections' equilibrium."""
    res = yield from path
    if not res.converged:
        return dataclasses.replace(res, failure=f"{res.failure} (on the way, at the "
                                   "compliant level: section_path final)")
    return (yield from section_finish(scene, dataclasses.replace(res, section_path="final"),
                                      residual_tol, hook, knot_type, end_held))


def system_at(scene: KnotScene, done: RodSystem, history: bool = False) -> RodSystem:
    """A rod system of ``scene`` (its contact) at the state, boundary conditions and load
    of ``done``, another level's system of the same rod; the state a copy, so that
    ``done`` is left as it was. ``history``: it records its accepted positions."""
    system = RodSystem(scene.model, done.state.copy(), done.bcs)
    system.add_term(scene.contact)
    if history:
        system.history = []
    system.set_load(done.t)
    return system


#: Newton iterations of :func:`section_finish`'s first solve at the full penalty.
DIRECT_SECTION_ITERATIONS = 150
#: The first shift, relative to the Hessian's diagonal, of :func:`section_finish`'s first
#: solve after a refused factorization (its NewtonOptions.shift_initial and, after PARDISO
#: reports a negative eigenvalue, shift_inertia: 1e-8 and 1e-6 by default). A free closed
#: knot's Hessian keeps near-rigid modes with eigenvalues 1e-11 of its diagonal, within
#: the round-off of its LDL^T, whose inertia can then count a negative pivot of a positive
#: definite matrix; a shift of 1e-6 then swamps those modes and Newton stalls at a residual
#: of 1e-3 (docs/sectioned_level.md, "The fix: the chords' planes").
DIRECT_SECTION_SHIFT_INERTIA = 1e-10
#: The residual, as a fraction of its start, at which :func:`section_finish`'s first solve
#: leaves its Gauss-Newton phase for the exact Hessian, and that phase's most iterations.
GAUSS_NEWTON_FRACTION = 0.1
GAUSS_NEWTON_ITERATIONS = 20
#: The penalty factors of :func:`section_finish`'s homotopy, the last the level's own.
PENALTY_HOMOTOPY = (0.125, 0.25, 0.5, 1.0)
#: The fractions of the bend shift in :func:`section_finish`'s shift homotopy, the last
#: the whole shift.
SHIFT_HOMOTOPY = (0.25, 0.5, 0.75, 1.0)


def _homotopy(system: RodSystem, factors: tuple[float, ...], apply: Callable[[float], None],
              what: str, steps: ContinuationOptions
              ) -> Coroutine[tuple[NewtonResult, int, str]]:
    """Static solves of ``system`` at the ``factors`` of a parameter (set by
    ``apply``, ``what`` it is) in turn, each from the last one's equilibrium (Newton, then
    proximal steps); the last solve's result (the first failed one's where one fails), the
    iterations of all and how it ended. The parameter's own value (factor 1) is
    restored."""
    iters = 0
    try:
        for f in factors:
            apply(f)
            r, it, prox = yield from static_solve(
                system, dataclasses.replace(steps.newton, max_iterations=400),
                steps.proximal_dt, steps.proximal_steps, steps.newton)
            iters += it
            if not r.converged:
                return r, iters, (f"at {f:g} of the {what}, Newton {r.reason}"
                                  + (f", proximal steps {prox}" if prox else ""))
    finally:
        apply(1.0)
    return r, iters, "converged"


def _retriable(r: NewtonResult, system: RodSystem) -> bool:
    """A failed solve that a solve from its start along another path may mend (not a
    step that passed through, which the system's check reports)."""
    return not r.converged and system.violation is None and r.reason != "passed_through"


def _direct_solve(system: RodSystem, layer: ContactLayer | None, options: NewtonOptions
                  ) -> Coroutine[tuple[NewtonResult, int]]:
    """:func:`section_finish`'s first solve of ``system`` from round sections: on the
    sectioned level a Gauss-Newton phase first (the contact's Hessian without the gaps'
    own curvature, :meth:`SectionedLayer.set_gauss_newton`) until the residual is
    :data:`GAUSS_NEWTON_FRACTION` of its start (at most :data:`GAUSS_NEWTON_ITERATIONS`
    iterations), then Newton with the exact Hessian (``options``) to convergence. The
    result spans both (iterations summed, residual histories joined); the iterations
    spent."""
    first = None
    iters = 0
    if isinstance(layer, SectionedLayer):
        # Round sections start inside their partners (a compliant knot's overlaps), where
        # the penalty's slope times the gaps' curvature makes the exact Hessian strongly
        # indefinite: its shifted steps crawl. The contact's Gauss-Newton Hessian is positive
        # semidefinite there (Nocedal & Wright 2006 sec. 10.3), and its steps bring the
        # sections out to where the exact one converges fast.
        layer.set_gauss_newton(True)
        try:
            first, iters, _ = yield from static_solve(
                system, dataclasses.replace(options, max_iterations=GAUSS_NEWTON_ITERATIONS,
                                            relative_tol=GAUSS_NEWTON_FRACTION), None, 0)
        finally:
            layer.set_gauss_newton(False)
        if first.reason == "passed_through":
            return first, iters
    r, more, _ = yield from static_solve(system, options, None, 0)
    if first is not None:
        r = dataclasses.replace(r, iterations=first.iterations + r.iterations,
                                history=first.history + r.history[1:])
    return r, iters + more


def _route_hint(scene: KnotScene, route: str) -> str:
    """What to try where the sections failed to join a pulled open knot at its end (the
    ``final`` route): the ``pull`` path adds them before the pull, which then moves the
    sections with the knot (docs/sectioned_level.md, "Cost, and what is left")."""
    if route != "final" or scene.closed:
        return ""
    return (" (the sections joined the knot at the end of its pull; --section-path pull "
            "adds them before the pull)")


def section_finish(scene: KnotScene, res: TieResult, residual_tol: float,
                   hook: StepHook | None = None,
                   knot_type: Callable[[KnotScene, np.ndarray], str] = knot_type_of,
                   end_held: bool = False) -> Coroutine[TieResult]:
    """The equilibrium of ``scene`` at its own contact level under the last load of
    ``res``, a converged load path of the same rod at another level (:func:`path_scene`):
    one static solve from its equilibrium, round sections added (Gauss-Newton steps
    first, :func:`_direct_solve`; where Newton fails
    within :data:`DIRECT_SECTION_ITERATIONS`, the same start again with the bend shift
    grown by :data:`SHIFT_HOMOTOPY` where the level has one, then with the penalty grown
    by :data:`PENALTY_HOMOTOPY` (:func:`_homotopy`), then proximal steps alone), the knot
    type checked,
    ``hook("section", ...)`` called with it. With
    ``end_held`` the pulling force is the held end's reaction at the new equilibrium.
    On failure the result's state is the load path's equilibrium (round sections), the
    failed solve's end in ``failed_state``."""
    t0 = time.perf_counter()
    done = res.system
    system = system_at(scene, done, history=True)
    start = system.state.copy()
    steps = load_step_options(1, residual_tol)
    layer = scene.contact
    # A first Newton solve at the full penalty, on a budget of twice the most iterations
    # it took where it converged (27 to 75 on the study's knots, docs/sectioned_level.md).
    r, iters = yield from _direct_solve(
        system, layer, dataclasses.replace(
            steps.newton, max_iterations=DIRECT_SECTION_ITERATIONS, stall_on_residual=True,
            shift_inertia=DIRECT_SECTION_SHIFT_INERTIA,
            shift_initial=min(steps.newton.shift_initial, DIRECT_SECTION_SHIFT_INERTIA)))
    retry = _retriable(r, system)
    tried = [f"Newton {r.reason}"]
    homotopies = []
    if isinstance(layer, SectionedLayer):
        if layer.shift is not None:
            # The bend shift moves a tight knot's inner sides into their partners all at
            # once (the round sections' start is the knot without it): it is grown from a
            # quarter.
            homotopies.append((SHIFT_HOMOTOPY, layer.set_shift_scale, "bend shift"))
        # From round sections at a tight knot's contacts, Newton can leap into a far basin
        # (single edges necking under their sections' thinning, docs/sectioned_level.md):
        # the penalty is grown from an eighth of its value by doubling.
        homotopies.append((PENALTY_HOMOTOPY, layer.set_penalty_scale, "penalty"))
    for factors, apply, what in homotopies:
        if not retry:
            break
        # every homotopy from the same start, its solves each from the last equilibrium
        system.state = start.copy()
        r, again, stopped = yield from _homotopy(system, factors, apply, what, steps)
        iters += again
        tried.append(f"the {what} grown from the start: {stopped}")
        retry = _retriable(r, system)
    if retry:
        # Proximal steps alone from the same start only ever descend.
        system.state = start.copy()
        r, again, reason = yield from descend(system, r, steps.proximal_dt,
                                              steps.proximal_steps, steps.newton)
        iters += again
        tried.append(f"proximal steps from the start: {reason}")
    why = ""
    if not r.converged:
        why = ("; ".join(tried) + (f": {system.violation}" if system.violation else "")
               + _route_hint(scene, res.section_path))
    types = list(res.knot_types)
    rec = StepRecord(done.t, r)
    if not why:
        kt = knot_type(scene, system.state.x)
        types.append(kt)
        if kt != scene.knot_type:
            why = (f"knot type {kt}, expected {scene.knot_type}: "
                   f"{topology_change(scene, system.history or [], system.rest, knot_type)}")
    failed = None
    if why:
        failed = system.state.copy()
        system.state = start
    elif hook is not None:
        hook("section", system, rec)
    wall = time.perf_counter() - t0
    phases = dict(res.phases)
    phases["section"] = StaticResult(not why, done.t if not why else 0.0,
                                     [] if why else [rec], iters, why, wall, failed)
    force = end_reaction(system) if end_held and not why else res.pull_force_N
    return TieResult(not why, f"section: {why}" if why else "", phases,
                     res.newton_iterations + iters, res.wall_time_s + wall, types, force,
                     system, failed, res.section_path)


def _tie(scene: KnotScene, pull_force: float | None, end_distance: float | None,
         tighten_steps: int, pull_steps: int, residual_tol: float, hold_force_scale: float,
         relax_iterations: int, hook: StepHook | None,
         attach: Callable[[RodSystem], None] | None, start_state: State | None,
         knot_type: Callable[[KnotScene, np.ndarray], str],
         sections: KnotScene | None = None,
         loosen_first: bool = False) -> Coroutine[TieResult]:
    """The coroutine of :func:`tie` (its arguments checked); with ``sections`` (the
    sectioned scene of the same rod, section_path "pull"), the pull runs on it from the
    sections' equilibrium at the tightened knot, but with ``loosen_first`` (section_path
    "auto") a pull that loosens the knot runs at this level and the sections join at its
    end."""
    start = time.perf_counter()
    types: list[str] = []
    phases: dict[str, StaticResult] = {}
    iters = 0
    model = scene.model
    f_unit = bending_force_scale(scene)
    last = end_vertex(scene)
    hold = hold_force_scale * f_unit
    axis = scene.pull_axis if scene.pull_axis is not None else np.zeros(3)

    # the sectioned level's path once the sections have joined (TieResult.section_path)
    route = ""

    def fail(msg: str, system: RodSystem | None, force: float,
             failed_state: State | None = None) -> TieResult:
        return TieResult(False, msg, phases, iters, time.perf_counter() - start, types,
                         force, system, failed_state, route)

    # Phase 1: shrink the rest length from the start to L0.
    shrink = 1.0 / scene.start_length_ratio
    # The start curve is not an equilibrium: relax it first (an open knot's end sliding
    # under a small tension, so the loose loops do not swing freely), with a budget for the
    # long, floppy path of a loose knot.
    bcs = gauge(scene)
    if not scene.closed:
        bcs.force(0, last, lambda t: hold * axis)
    system = RodSystem(model, scene.state if start_state is None else start_state, bcs)
    system.add_term(scene.contact)
    p = _attached(system, attach)
    relax = yield from newton(p, system.free_vector(), NewtonOptions(
        residual_tol=residual_tol, max_iterations=relax_iterations))
    iters += relax.iterations
    if not relax.converged:
        hint = ("; the loose start of a long rod may need more: raise relax_iterations, "
                f"{relax_iterations} now" if relax.reason == "max_iterations" else "")
        return fail(f"relax: Newton {relax.reason} (residual {relax.residual:.3g}) at the "
                    f"start{hint}", system, hold)
    kt = knot_type(scene, system.state.x)
    types.append(kt)
    if kt != scene.knot_type:
        why = topology_change(scene, system.history or [], system.rest, knot_type)
        return fail(f"relax: knot type {kt}, expected {scene.knot_type}: {why}", system, hold)
    recentre_system(scene, system)
    if scene.closed:
        bcs = gauge(scene, positions=system.state.x)
    else:
        # The end then follows the shrink (end-to-end distance scaled with the rest
        # length): with a freely sliding end the tail slides out of the shrinking loop and
        # the knot slips off the rod.
        bcs = gauge(scene, positions=system.state.x, sliding_end=False)
        span = float(system.state.x[last] @ axis)
        bcs.pin(0, last, translation=lambda t: (shrink - 1.0) * t * span * axis)
    bcs.rest_length_scale((1.0, shrink))
    system = RodSystem(model, system.state, bcs)
    system.add_term(scene.contact)
    p = _attached(system, attach)

    def similar(sys_: RodSystem, t0: float, t1: float) -> None:
        # Self-similar predictor: the previous equilibrium scaled about the pinned first
        # vertex (the origin) by the change of rest length keeps every strain; prescribed
        # ends and the gauge's zero coordinates are unchanged by it.
        c = (1.0 + (shrink - 1.0) * t1) / (1.0 + (shrink - 1.0) * t0)
        sys_.state.x = sys_.state.x * c
        sys_.set_load(t1)

    res = yield from continuation(p, load_step_options(tighten_steps, residual_tol),
                                  _checker(scene, "tighten", types, hook, knot_type), similar)
    phases["tighten"] = res
    iters += res.newton_iterations
    if not res.converged:
        return fail(f"tighten: {res.failure}", system, hold, res.failed_state)
    if scene.closed or (pull_force is None and end_distance is None):
        return TieResult(True, "", phases, iters, time.perf_counter() - start, types,
                         hold if not scene.closed else 0.0, system)

    # section_path "auto" on a pull that loosens the knot: the sections join at its end, as
    # on the "final" path (their solves through the tighter states on the way cost several
    # compliant ones, and measured, the loosened knot ends within a shallow minimum of the
    # one loosened with them, docs/sectioned_level.md).
    late = (sections is not None and loosen_first
            and _loosens(system, last, pull_force, end_distance, hold))
    if sections is not None and not late:
        # section_path "pull": the sections join the tightened knot, whose equilibrium
        # with them under the tightening's last load starts the pull.
        route = "pull"
        done = TieResult(True, "", phases, iters, time.perf_counter() - start, types,
                         hold, system, section_path=route)
        res = yield from section_finish(sections, done, residual_tol, hook, knot_type)
        if not res.converged:
            return res
        phases, iters, types = dict(res.phases), res.newton_iterations, list(res.knot_types)
        scene, system = sections, res.system

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
    p = _attached(system, attach)
    res = yield from continuation(p, load_step_options(pull_steps, residual_tol),
                                  _checker(scene, "pull", types, hook, knot_type))
    phases["pull"] = res
    iters += res.newton_iterations
    if end_distance is not None:
        # Reaction at the moved end: the residual force there is the pulling force.
        final_force = end_reaction(system)
    if not res.converged:
        if pull_force is not None:
            # The force of the last equilibrium (the state kept), not the one aimed at.
            final_force = f0 * (pull_force / f0) ** res.t
        way = " (at the compliant level: the sections join the loosened knot)" if late else ""
        return fail(f"pull: {res.failure}{way}", system, final_force, res.failed_state)
    out = TieResult(True, "", phases, iters, time.perf_counter() - start, types, final_force,
                    system, section_path="final" if late else route)
    if late:
        out = yield from section_finish(sections, out, residual_tol, hook, knot_type,
                                        end_distance is not None)
    return out


def _loosens(system: RodSystem, last: int, pull_force: float | None,
             end_distance: float | None, hold: float) -> bool:
    """Whether the pull of the tightened open knot ``system`` loosens it: a force [N] below
    the one its held end ``last`` carries (or the hold, where the pull starts), or an end
    distance [m] shorter than its own."""
    if pull_force is not None:
        return pull_force < max(end_reaction(system), hold)
    x = system.state.x
    return end_distance < float(np.linalg.norm(x[last] - x[0]))


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
        gk = system.term_gradient(term)
        g += gk[-1]
    return float(g[0])
