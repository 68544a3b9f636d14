"""Pulling a two-rod tangle apart by its four ends: the clasp's and the bends' load path.

Every end is held in a grip: its end vertex and the next one are clamped (their positions
prescribed; no twist dofs, so the material frame is free), as the jaws of a tensile test
hold a rod's tail on the pull axis. Rod A's grips move along -x, rod B's along +x.

1. ``relax``: the start curve (not an equilibrium) relaxes with the grips where they are.
2. ``pull``: the grips move apart, by displacement (load continuation on the end-to-end
   distance), to ``end_distance``; or, given a ``force``, until the pulling force on rod
   B's ends reaches it (displacement control first: a dead force on a slack tangle has no
   equilibrium to go to, the tails would only swing), up to ``max_end_distance``.
3. ``force`` (given a force): rod A's grips stay, rod B's end vertices carry the dead force
   ``force`` / 2 each along +x (their neighbours and their y, z held on the grip's line), from
   the last displacement step: the pulled equilibrium under the dead load.

After every converged load step the tangle's invariants are computed
(:meth:`tightknot.knots.tangle_scenes.TangleScene.tangle_type`); a change stops the run as
failed, the state of that step kept. Each converged step gives one point of the
force-extension curve: the end-to-end distance and the pulling force, the mean of the x
reactions of B's two grips and minus A's two (they balance at equilibrium).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from tightknot.knots.tangle_scenes import ROD_NAMES, TangleScene
from tightknot.knots.topology import TopologyError
from tightknot.loading.options import LoadPath
from tightknot.loading.tie import load_step_options
from tightknot.rods.boundary import BoundaryConditions
from tightknot.rods.state import State
from tightknot.solvers.continuation import (
    StaticResult,
    StepRecord,
    continuation,
)
from tightknot.solvers.newton import NewtonOptions, newton
from tightknot.solvers.system import RodSystem

StepHook = Callable[[str, RodSystem, StepRecord | None], None]


@dataclass
class EndReaction:
    """The force a grip exerts on its rod's end [N] (vector, (3,)), by rod and end."""

    rod: str
    end: str
    force_N: np.ndarray

    def to_dict(self) -> dict:
        """JSON form."""
        return {"rod": self.rod, "end": self.end, "force_N": [float(v) for v in self.force_N]}


@dataclass
class PullResult:
    """Outcome of pulling a tangle.

    Attributes:
        converged: every phase reached its end.
        failure: what failed and where ("" when converged).
        phases: each phase's continuation result (the relaxation's Newton as a one-step one).
        force_extension: (end-to-end distance [m], pulling force [N], phase) per converged
            load step.
        tangle_types: the tangle's label after each converged step.
        reactions: each end's reaction at the last equilibrium.
        newton_iterations: total Newton iterations.
        wall_time_s: wall-clock time [s].
        system: the last phase's system (its state is the last equilibrium).
        failed_state: where the failing step's solve stopped (None when converged).
    """

    converged: bool
    failure: str
    phases: dict[str, StaticResult] = field(default_factory=dict)
    force_extension: list[tuple[float, float, str]] = field(default_factory=list)
    tangle_types: list[str] = field(default_factory=list)
    reactions: list[EndReaction] = field(default_factory=list)
    newton_iterations: int = 0
    wall_time_s: float = 0.0
    system: RodSystem | None = None
    failed_state: State | None = None

    @property
    def pull_force_N(self) -> float:
        """The pulling force of the last equilibrium [N] (nan before any)."""
        return self.force_extension[-1][1] if self.force_extension else math.nan


def end_reactions(scene: TangleScene, system: RodSystem) -> list[EndReaction]:
    """The external force on each end [N], its grip's and any dead load on it: at
    equilibrium of the free dofs it balances the internal (elastic and contact) force on
    the grip's two vertices, f = dE/dx summed over them."""
    x = system.state.x
    _, grad = system.forces.evaluate(x, system.state.theta, system.state.m_ref, system.rest,
                                     True, None)
    g = grad[system.model.position_dofs].copy()
    for term in system.extra_terms:
        gk = system.term_gradient(term)
        g += gk
    out = []
    for r, end, v in scene.end_vertices():
        nb = v + 1 if end == "start" else v - 1
        out.append(EndReaction(ROD_NAMES[r], end, g[v] + g[nb]))
    return out


def pulling_force(reactions: list[EndReaction]) -> float:
    """The pulling force [N]: the mean of B's grips' x force and minus A's (the two pairs
    balance at equilibrium; the mean halves the residual's imbalance)."""
    fa = sum(float(r.force_N[0]) for r in reactions if r.rod == "A")
    fb = sum(float(r.force_N[0]) for r in reactions if r.rod == "B")
    return 0.5 * (fb - fa)


def _grips(scene: TangleScene, positions: np.ndarray, shift: float = 0.0,
           hold_b: bool = True) -> BoundaryConditions:
    """The four grips at ``positions``; A's moving by -shift/2 and B's by +shift/2 along x
    over the load path (linearly in t). ``hold_b=False``: B's grips let the end vertex
    slide along x (the force phase), holding y and z of both grip vertices."""
    bcs = BoundaryConditions(scene.model, positions)
    for r, end, v in scene.end_vertices():
        u = scene.pull_directions[r]
        if r == 1 and not hold_b:
            nb = v + 1 if end == "start" else v - 1
            info = scene.model.rods[r]
            for w in (v, nb):
                bcs.fix_components(r, w - info.vertex_start, (1, 2))
            continue
        bcs.clamp(r, end, translation=(0.5 * shift) * u)
    return bcs


def pull_tangle(
    scene: TangleScene,
    end_distance: float | None = None,
    force: float | None = None,
    max_end_distance: float | None = None,
    pull_steps: int = 40,
    force_steps: int = 4,
    residual_tol: float = LoadPath.residual_tol,
    relax_iterations: int = LoadPath.relax_iterations,
    hook: StepHook | None = None,
    tangle_type: Callable[[TangleScene, np.ndarray], str] | None = None,
) -> PullResult:
    """Pull ``scene`` (module docstring) to ``end_distance`` [m] or to a pulling ``force``
    [N] (exactly one). ``max_end_distance`` [m]: how far a force pull may move the grips
    looking for the force (default: the end distance at which the rods, straight, would
    reach past each other's grips, the start's plus the shorter rod's rest length).
    ``hook(phase, system, record)`` runs after each converged step (and after the
    relaxation, record None); ``tangle_type(scene, x)`` replaces the invariants' label
    (tests)."""
    if (end_distance is None) == (force is None):
        raise ValueError("give exactly one of end_distance [m] and force [N]")
    for name, v in (("end_distance", end_distance), ("force", force),
                    ("max_end_distance", max_end_distance)):
        if v is not None and not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise ValueError(f"{name} must be finite and > 0, got {v!r}")
    # The grips hold the ends where they start, so the relaxed start's end distance is the
    # start's: a target short of it is bad input, known before any solve.
    d_start = scene.end_distance(scene.state.x)
    if end_distance is not None and end_distance <= d_start:
        raise ValueError(f"end_distance must exceed the start's end-to-end distance "
                         f"{d_start:.6g} m (the grips pull the rods apart), got {end_distance!r}")
    if max_end_distance is not None and max_end_distance <= d_start:
        raise ValueError(f"max_end_distance must exceed the start's end-to-end distance "
                         f"{d_start:.6g} m, got {max_end_distance!r}")
    start = time.perf_counter()
    label = tangle_type or _label
    expected = scene.start_type.label()
    res = PullResult(False, "")

    def finish(failure: str, system: RodSystem, failed: State | None = None) -> PullResult:
        res.converged = not failure
        res.failure = failure
        res.system = system
        res.failed_state = failed
        res.reactions = end_reactions(scene, system)
        res.wall_time_s = time.perf_counter() - start
        return res

    def record(phase: str, system: RodSystem, rec: StepRecord | None) -> str | None:
        kt = label(scene, system.state.x)
        res.tangle_types.append(kt)
        react = end_reactions(scene, system)
        res.force_extension.append((scene.end_distance(system.state.x), pulling_force(react),
                                    phase))
        if hook is not None:
            hook(phase, system, rec)
        if kt != expected:
            return (f"the tangle came apart in phase {phase}: rods A and B are now "
                    f"'{kt}', they started as '{expected}'")
        return None

    # 1. Relax the start curve in the grips.
    bcs = _grips(scene, scene.state.x)
    system = RodSystem(scene.model, scene.state, bcs)
    system.add_term(scene.contact)
    relax = newton(system, system.free_vector(), NewtonOptions(
        residual_tol=residual_tol, max_iterations=relax_iterations)).run()
    res.newton_iterations += relax.iterations
    if not relax.converged:
        return finish(f"relax: Newton {relax.reason} (residual {relax.residual:.3g}) from the "
                      "start curves in the grips", system, system.state.copy())
    why = record("relax", system, None)
    if why:
        return finish(why, system, system.state.copy())

    # 2. Pull by displacement.
    d_now = scene.end_distance(system.state.x)
    if end_distance is not None:
        target = float(end_distance)
    else:
        lmin = min(scene.model.rest_length(r) for r in range(2))
        target = float(max_end_distance) if max_end_distance is not None else d_now + lmin
    if target <= d_now:
        return finish(f"pull: the end distance {target:.4g} m is not beyond the relaxed "
                      f"start's {d_now:.4g} m", system)
    bcs = _grips(scene, system.state.x, shift=target - d_now)
    system = RodSystem(scene.model, system.state, bcs)
    system.add_term(scene.contact)
    system.set_load(0.0)

    def pull_step(sys_: RodSystem, rec: StepRecord) -> str | None:
        why = record("pull", sys_, rec)
        if why:
            return why
        if force is not None and res.force_extension[-1][1] >= force:
            return _REACHED
        return None

    cont = continuation(system, load_step_options(pull_steps, residual_tol), pull_step).run()
    res.phases["pull"] = cont
    res.newton_iterations += cont.newton_iterations
    reached = _REACHED in cont.failure
    if not cont.converged and not reached:
        at = res.force_extension[-1]
        return finish(f"pull: {cont.failure} (last equilibrium: end distance {at[0]:.4g} m, "
                      f"force {at[1]:.4g} N)", system, cont.failed_state)
    if force is None:
        return finish("", system)
    if not reached:
        return finish(f"pull: the force {force:g} N was not reached by moving the grips to "
                      f"the end distance {target:.4g} m (max_end_distance): the force there "
                      f"is {res.force_extension[-1][1]:.4g} N", system)

    # 3. The dead force on B's ends, from the displacement step that reached it.
    f_from = res.force_extension[-1][1]
    bcs = _grips(scene, system.state.x, hold_b=False)
    ends_b = [(end, v) for r, end, v in scene.end_vertices() if r == 1]
    info_b = scene.model.rods[1]
    u = scene.pull_directions[1]
    for _end, v in ends_b:
        bcs.force(1, v - info_b.vertex_start,
                  lambda t, f0=f_from: 0.5 * (f0 + (force - f0) * t) * u)
    system = RodSystem(scene.model, system.state, bcs)
    system.add_term(scene.contact)
    system.set_load(0.0)
    cont = continuation(system, load_step_options(force_steps, residual_tol),
                        lambda s, r: record("force", s, r)).run()
    res.phases["force"] = cont
    res.newton_iterations += cont.newton_iterations
    if not cont.converged:
        return finish(f"force: the dead force {force:g} N on rod B's ends (from {f_from:.4g} N, "
                      f"reached by displacement) did not converge: {cont.failure}", system,
                      cont.failed_state)
    return finish("", system)


def _label(scene: TangleScene, x: np.ndarray) -> str:
    """The tangle's label at ``x``; "undefined" where no projection is generic (two pieces
    of rod within round-off of each other), which the check then reports as a change."""
    try:
        return scene.tangle_type(x).label()
    except TopologyError:
        return "undefined (two pieces of rod nearly meet)"


#: The pull step's callback's way of saying "force reached" (stops the continuation).
_REACHED = "target force reached"
