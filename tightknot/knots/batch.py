"""Many independent closed knots tied together: one model, one Newton loop, one set of launches.

A sweep of small cases pays, per case and per Newton iteration, a fixed cost for every
Warp launch, BVH build, sparse factorization and Python step. Putting the rods of many
cases into one :class:`~tightknot.rods.model.Model` (the builder lays them out one after
another, every array carries a rod index) pays that cost once per iteration for all. On
the CPU it buys little (``tightknot bench batch``, 100-vertex trefoils: the evaluation per
rod falls from 1.8 to 0.95 ms, the factorization stays 1.5 ms per rod, and the joint loop
needs more iterations than one rod); the launches are where a GPU gains.

The copies are placed far apart in space (a grid with a gap of many diameters between
their bounding boxes), so the contact layer, which also handles rod-rod contact, never
finds a pair between two copies: the joint system is block diagonal and each block is the
single case's. The tie follows :func:`tightknot.knots.tie.tie` (same continuation
settings, same self-similar predictor, same knot-type check after every step), except
that the load parameter, the Newton step length and the damping are shared: a step is
accepted only when every rod converged, and the line search takes the shortest step any
rod allows. Each rod then ends at an equilibrium of its own case to the same residual
tolerance, but along another path than its own tie: where the path can fork, it may be
another equilibrium than the one tie() finds, e.g. the same closed knot shifted along its
rod (measured: 1 of 16 identical trefoils 0.19 D0 off in positions, 3e-5 in the
curvature profile at the best shift).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from tightknot.knots.scenes import KnotScene
from tightknot.knots.tie import _opts as tie_continuation_options
from tightknot.knots.tie import knot_type_of
from tightknot.rods.boundary import BoundaryConditions
from tightknot.rods.builder import RodBuilder
from tightknot.rods.contact import ContactLayer
from tightknot.rods.model import Model
from tightknot.rods.state import State
from tightknot.solvers.newton import NewtonOptions, newton_solve
from tightknot.solvers.static import StaticResult, StepRecord, solve_static
from tightknot.solvers.system import RodSystem

#: Gap between the bounding boxes of two copies, in rest diameters: far beyond the
#: contact layer's interaction range (1.1 D0 bounds), so no inter-copy pair is a candidate.
GAP_DIAMETERS = 20.0


@dataclass
class BatchModel:
    """Several scenes' rods in one model.

    Attributes:
        model: the joint model (rod k is scene k).
        offsets: translation of each copy [m], shape (rods, 3).
        scenes: the scenes, in rod order.
        contact: one contact layer over all rods.
    """

    model: Model
    offsets: np.ndarray
    scenes: list[KnotScene]
    contact: ContactLayer


@dataclass
class BatchResult:
    """Outcome of tying a batch of knots.

    Attributes:
        converged: every rod reached its rest length with its knot type kept.
        failure: what failed and where ("" when converged).
        positions: final centerline of each rod in its own scene's frame [m].
        newton_iterations: Newton iterations of the joint loop (each one covers all rods).
        wall_time_s: wall-clock time [s].
        knot_types: knot type of each rod after the last converged step.
        phases: the continuation result of each phase, by name.
        system: the joint system (its state is the result, copies offset in space).
    """

    converged: bool
    failure: str
    positions: list[np.ndarray]
    newton_iterations: int
    wall_time_s: float
    knot_types: list[str] = field(default_factory=list)
    phases: dict[str, StaticResult] = field(default_factory=dict)
    system: RodSystem | None = None


def build_batch(scenes: list[KnotScene]) -> BatchModel:
    """One model holding the rods of ``scenes`` (closed knots), placed far apart."""
    if not scenes:
        raise ValueError("scenes must hold at least one knot scene")
    for k, sc in enumerate(scenes):
        if not sc.closed:
            raise ValueError(f"scenes[{k}] is open ({sc.name}): the batch ties closed knots "
                             "only (an open knot's moving end needs its own load path)")
        if sc.contact is None:
            raise ValueError(f"scenes[{k}] has contact='off': tying a knot needs a contact "
                             "layer")
        if len(sc.model.rods) != 1:
            raise ValueError(f"scenes[{k}] has {len(sc.model.rods)} rods; one rod per scene")
    first = scenes[0]
    twist, device = first.model.twist, first.model.device
    law = first.contact.law
    for k, sc in enumerate(scenes):
        if sc.model.twist != twist or sc.model.device != device:
            raise ValueError(f"scenes[{k}] differs from scenes[0] in twist or device: one "
                             "model has one twist setting and one device")
        if sc.contact.law != law:
            raise ValueError(f"scenes[{k}] has another contact law than scenes[0]: one "
                             "contact layer has one law")
    boxes = [(sc.model.vertex_initial_position.min(axis=0),
              sc.model.vertex_initial_position.max(axis=0)) for sc in scenes]
    size = max(float((hi - lo).max()) for lo, hi in boxes)
    gap = GAP_DIAMETERS * max(sc.diameter for sc in scenes)
    pitch = size + gap
    side = math.ceil(math.sqrt(len(scenes)))
    builder = RodBuilder(twist=twist)
    offsets = np.zeros((len(scenes), 3))
    for k, sc in enumerate(scenes):
        offsets[k] = [pitch * (k % side), pitch * (k // side), 0.0]
        info = sc.model.rods[0]
        builder.add_rod(sc.model.vertex_initial_position + offsets[k], info.diameter,
                        info.material, closed=True,
                        edge_rest_lengths=sc.model.edge_rest_length)
    model = builder.finalize(device)
    return BatchModel(model, offsets, list(scenes), ContactLayer(model, law))


def batch_gauge(batch: BatchModel, positions: np.ndarray | None = None) -> BoundaryConditions:
    """The closed-knot gauge of :func:`tightknot.knots.scenes.gauge`, on every rod."""
    model = batch.model
    bcs = BoundaryConditions(model, positions)
    for r, info in enumerate(model.rods):
        n = info.vertex_count
        bcs.pin(r, 0).fix_components(r, n // 3, (1, 2)).fix_components(r, 2 * n // 3, (2,))
        if model.twist:
            bcs.fix_twist(r, 0)  # the uniform-twist rotation is a zero mode
    return bcs


def _knot_types(batch: BatchModel, x: np.ndarray) -> list[str]:
    return [knot_type_of(sc, x[info.vertex_slice] - batch.offsets[r])
            for r, (sc, info) in enumerate(zip(batch.scenes, batch.model.rods, strict=True))]


def _first_wrong(batch: BatchModel, types: list[str]) -> int | None:
    for r, (sc, kt) in enumerate(zip(batch.scenes, types, strict=True)):
        if kt != sc.knot_type:
            return r
    return None


def tie_batch(
    scenes: list[KnotScene],
    tighten_steps: int = 20,
    residual_tol: float = 1e-6,
    relax_iterations: int = 2000,
) -> BatchResult:
    """Tie closed knots together: relax the start curves, then shrink each rod's rest
    length from its start length to its L0 by one shared continuation (as
    :func:`tightknot.knots.tie.tie` does for one knot).

    Args:
        scenes: closed knot scenes (same twist setting, device and contact law).
        tighten_steps: initial number of load steps (adaptive afterwards).
        residual_tol: Newton tolerance on the scaled residual, over all rods.
        relax_iterations: Newton budget of the relaxation of the start curves.
    """
    if not (math.isfinite(residual_tol) and residual_tol > 0):
        raise ValueError(f"residual_tol must be finite and > 0, got {residual_tol!r}")
    if int(tighten_steps) != tighten_steps or tighten_steps < 1:
        raise ValueError(f"tighten_steps must be a whole number >= 1, got {tighten_steps!r}")
    start = time.perf_counter()
    batch = build_batch(scenes)
    model = batch.model
    rods = model.rods
    phases: dict[str, StaticResult] = {}
    iters = 0
    types: list[str] = []

    def result(ok: bool, msg: str, system: RodSystem) -> BatchResult:
        x = system.state.x
        pos = [x[info.vertex_slice] - batch.offsets[r] for r, info in enumerate(rods)]
        return BatchResult(ok, msg, pos, iters, time.perf_counter() - start, list(types),
                           phases, system)

    # Relax the start curves (not equilibria), all at once.
    system = RodSystem(model, State.initial(model), batch_gauge(batch))
    system.add_term(batch.contact)
    system.set_load(0.0)
    relax = newton_solve(system, system.free_vector(),
                         NewtonOptions(residual_tol=residual_tol, max_iterations=relax_iterations))
    iters += relax.iterations
    if not relax.converged:
        return result(False, f"relax: Newton {relax.reason} (residual {relax.residual:.3g})",
                      system)
    types = _knot_types(batch, system.state.x)
    bad = _first_wrong(batch, types)
    if bad is not None:
        return result(False, f"relax: rod {bad} has knot type {types[bad]}, expected "
                      f"{scenes[bad].knot_type}", system)

    # Shrink every rod's rest length from its start length to its L0 along one path.
    shrink = np.array([1.0 / sc.start_length_ratio for sc in scenes])
    bcs = batch_gauge(batch, positions=system.state.x)
    for r in range(len(rods)):
        bcs.rest_length_scale((1.0, float(shrink[r])), rod=r)
    system = RodSystem(model, system.state, bcs)
    system.add_term(batch.contact)
    system.set_load(0.0)
    first = np.array([info.vertex_start for info in rods])
    vrod = model.vertex_rod

    def similar(sys_: RodSystem, t0: float, t1: float) -> None:
        # tie()'s self-similar predictor, per rod about its pinned first vertex: the
        # previous equilibrium scaled by the change of its rest length keeps every strain.
        c = (1.0 + (shrink - 1.0) * t1) / (1.0 + (shrink - 1.0) * t0)
        x = sys_.state.x
        pivot = x[first][vrod]
        sys_.state.x = pivot + (x - pivot) * c[vrod][:, None]
        sys_.set_load(t1)

    def check(sys_: RodSystem, rec: StepRecord) -> str | None:
        nonlocal types
        types = _knot_types(batch, sys_.state.x)
        r = _first_wrong(batch, types)
        if r is not None:
            return (f"topology changed in phase tighten at load t={rec.t:.4g}: rod {r} has "
                    f"knot type {types[r]}, expected {scenes[r].knot_type} (the rod passed "
                    "through itself)")
        return None

    res = solve_static(system, tie_continuation_options(tighten_steps, residual_tol),
                       callback=check, predictor=similar)
    phases["tighten"] = res
    iters += res.newton_iterations
    if not res.converged:
        return result(False, f"tighten: {res.failure}", system)
    return result(True, "", system)
