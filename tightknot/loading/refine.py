"""Mesh continuation: tie a knot on a coarse rod, then refine it and solve again.

A long rod at the resolution its knot needs has many vertices, and the relaxation of its
loose start (a floppy path as long as the rod is) costs about a Newton iteration per vertex:
on a 1 m rod at 1682 vertices it outgrows the relaxation's budget. The knot's shape, though,
is set at a few tens of vertices per diameter of knot only where the strands touch. So the
load path runs on a coarse copy of the scene, and its equilibrium is carried to the fine rod
in steps that double the vertex count: the centerline resampled at equal chords (the open
scenes' rods have equal rest edges), the load path's last boundary conditions and load
(the gauge, the grips, the final pulling force or the final end position), and one static
solve (proximal steps where Newton fails) with the knot type checked.

A closed rod with twist starts each refinement joined with no excess twist (the study's
closed knot is joined so at its start; the twist a writhe change forced on the coarse rod is
not carried over, a small part of a tight knot's energy).
"""

from __future__ import annotations

import math
import time
from dataclasses import replace

import numpy as np

from tightknot.knots import curves
from tightknot.knots.scenes import KnotScene, end_vertex, gauge, minimum_nodes, rotate_to_axes
from tightknot.loading.options import LoadPath
from tightknot.loading.pull import tie_to_lambda
from tightknot.loading.tie import StepHook, TieResult, knot_type_of, tie
from tightknot.rods.state import State
from tightknot.solvers.continuation import ContinuationOptions, StepRecord, continuation
from tightknot.solvers.newton import NewtonOptions
from tightknot.solvers.program import Coroutine, Program
from tightknot.solvers.system import RodSystem


def refinements(coarse: int, fine: int) -> list[int]:
    """Vertex counts from ``coarse`` to ``fine``, each about twice the one before."""
    if not (2 <= coarse < fine):
        raise ValueError(f"need 2 <= coarse_nodes < nodes, got {coarse} and {fine}")
    steps = max(1, math.ceil(math.log2(fine / coarse) - 1e-9))
    return [round(coarse * (fine / coarse) ** (k / steps)) for k in range(1, steps)] + [fine]


def carry(x: np.ndarray, closed: bool, nodes: int) -> np.ndarray:
    """The centerline ``x`` [m] resampled to ``nodes`` vertices at equal chords (open) or
    equal arc length (closed), its end points kept."""
    if closed:
        return curves.resample_uniform(x, nodes, closed=True)
    return curves.resample_equal_chords(x, nodes)


def _system_at(scene: KnotScene, start: np.ndarray, pull_force: float | None) -> RodSystem:
    """The system of ``scene`` (at its rest length L0) from the carried centerline ``start``
    [m] under the coarse path's last load (:func:`resolve`)."""
    model = scene.model
    shrink = 1.0 / scene.start_length_ratio
    if scene.closed:
        # The gauge's vertices back on their axes (vertex 0 at the origin, n/3 on x, 2n/3
        # in the x-y plane), so that the gauge exerts no force at equilibrium.
        n = model.vertex_count
        start = rotate_to_axes(start, 0, n // 3, 2 * n // 3)
    bcs = gauge(scene, positions=start, sliding_end=pull_force is not None)
    bcs.rest_length_scale((shrink, shrink))
    if not scene.closed:
        if pull_force is not None:
            force = pull_force * scene.pull_axis
            bcs.force(0, end_vertex(scene), lambda _t: force)  # the same load at every t
        else:
            bcs.pin(0, end_vertex(scene))
    system = RodSystem(model, State.initial(model, positions=start), bcs)
    system.add_term(scene.contact)
    system.history = []
    system.set_load(1.0)
    return system


def carried_failure(scene: KnotScene, res: TieResult, pull_force: float | None
                    ) -> TieResult:
    """A failed stage of the mesh continuation (``res``, on a coarser copy of ``scene``)
    as a result on the scene's own rod: its last equilibrium carried to the scene's vertex
    count, not solved again, so that a run saves and measures the scene's rod."""
    n = res.system.model.vertex_count
    start = carry(res.system.state.x, scene.closed, scene.model.vertex_count)
    system = _system_at(scene, start, pull_force)
    return replace(res, failure=f"at {n} vertices (mesh continuation): {res.failure}",
                   system=system, failed_state=None)


def resolve(scene: KnotScene, start: np.ndarray, coarse: TieResult,
            pull_force: float | None, residual_tol: float,
            hook: StepHook | None = None) -> Coroutine[TieResult]:
    """The equilibrium of ``scene`` (the fine rod, at its rest length L0) from the carried
    centerline ``start`` [m], under the last load of the coarse load path ``coarse``: the
    dead force ``pull_force`` [N] on the sliding end, or (None) the end held where the
    coarse path left it; one static solve, the knot type checked."""
    t0 = time.perf_counter()
    model = scene.model
    system = _system_at(scene, start, pull_force)
    # One step: the loads do not change with t, so a halved step solves the same problem
    # again from where the last attempt was put back. The carried shape is near, not at,
    # the fine rod's equilibrium, and a loose knot's is a long floppy way off: a larger
    # Newton budget than a load step's.
    opts = ContinuationOptions(steps=1, newton=NewtonOptions(residual_tol=residual_tol,
                                                              max_iterations=400),
                               proximal_dt=1e-3, proximal_steps=200, min_step=0.25)
    types: list[str] = []

    def check(sys_: RodSystem, rec: StepRecord) -> str | None:
        kt = knot_type_of(scene, sys_.state.x)
        types.append(kt)
        if hook is not None:
            hook("refine", sys_, rec)
        if kt != scene.knot_type:
            return f"knot type {kt} after refining to {model.vertex_count} vertices"
        return None

    res = yield from continuation(system, opts, check)
    phases = dict(coarse.phases)
    phases[f"refine_{model.vertex_count}"] = res
    failure = "" if res.converged else f"refine to {model.vertex_count} vertices: {res.failure}"
    return TieResult(res.converged, failure, phases,
                     coarse.newton_iterations + res.newton_iterations,
                     coarse.wall_time_s + time.perf_counter() - t0,
                     list(coarse.knot_types) + types, coarse.pull_force_N, system,
                     res.failed_state)


def tie_refined(scene: KnotScene, coarse_nodes: int, target_lambda: float | None = None,
                **tie_options: object) -> Program[TieResult]:
    """Tie ``scene`` by mesh continuation (module docstring): its load path
    (:func:`tightknot.loading.tie.tie` with ``tie_options``, or
    :func:`tightknot.loading.pull.tie_to_lambda` to ``target_lambda``) on the same scene
    at ``coarse_nodes`` vertices, then refined by doubling to the scene's own count, each
    refinement one static solve under the coarse path's last load. The coarse count is
    raised to the fewest vertices the scene's start allows with contact
    (:func:`tightknot.knots.scenes.minimum_nodes`: edges within pi D0/4); where that is
    the scene's own count there is no coarser stage and the load path runs on the scene.
    A program (:mod:`tightknot.solvers.program`); the result's system is the scene's own
    model, and a ``hook`` in ``tie_options`` sees its final solve only."""
    if scene.rebuild is None:
        raise ValueError(f"{scene.name}: this scene cannot be rebuilt at another resolution "
                         "(mesh continuation needs the scene's rebuild)")
    if target_lambda is not None and scene.closed:
        raise ValueError("target_lambda is for open knots")
    if scene.contact is not None:
        coarse_nodes = max(int(coarse_nodes),
                           minimum_nodes(scene.state.x, scene.closed, scene.diameter))
    if coarse_nodes >= scene.model.vertex_count:
        if target_lambda is not None:
            return tie_to_lambda(scene, target_lambda, **tie_options)
        return tie(scene, **tie_options)
    counts = refinements(int(coarse_nodes), scene.model.vertex_count)
    # The fine rod's end: pulled by the coarse path's final force, or (an end distance, or
    # a tightening without a pull) held where the coarse path left it.
    pull_force = tie_options.get("pull_force")
    return Program(_tie_refined(scene, counts, coarse_nodes, target_lambda, pull_force,
                                dict(tie_options)), "tie_refined")


def _tie_refined(scene: KnotScene, counts: list[int], coarse_nodes: int,
                 target_lambda: float | None, pull_force: object,
                 tie_options: dict) -> Coroutine[TieResult]:
    """The coroutine of :func:`tie_refined`."""
    coarse = scene.rebuild(int(coarse_nodes))
    # The hook sees the scene's own rod only (a run's log and its measures are of that
    # rod): the final refinement, not the coarse path.
    hook = tie_options.pop("hook", None)
    residual_tol = float(tie_options.get("residual_tol", LoadPath.residual_tol))
    if target_lambda is not None:
        res = yield from tie_to_lambda(coarse, target_lambda, **tie_options)
        force = res.pull_force_N  # the force that reached the target, held on the fine rod
    else:
        res = yield from tie(coarse, **tie_options)
        force = pull_force
    for n in counts:
        if not res.converged:
            return carried_failure(scene, res, None if force is None else float(force))
        fine = scene if n == scene.model.vertex_count else scene.rebuild(n)
        start = carry(res.system.state.x, scene.closed, n)
        res = yield from resolve(fine, start, res, None if force is None else float(force),
                                 residual_tol, hook if fine is scene else None)
    return res
