"""Many independent closed knots tied together: one model, one set of Warp launches.

A sweep of small cases pays, per case and per Newton iteration, a fixed cost for every
Warp launch, BVH build and Python step. Putting the rods of many cases into one
:class:`~tightknot.rods.model.Model` (the builder lays them out one after another, every
array carries a rod index) pays the launches once per round for all rods.

The copies are placed far apart in space (a grid with a gap of many diameters between
their bounding boxes), so the contact layer, which also handles rod-rod contact, never
finds a pair between two copies: the rods are independent. Each rod runs the closed-knot
path of :func:`tightknot.loading.tie.tie` with its own solver state
(:mod:`tightknot.solvers.lockstep`: its own load parameter and step, Newton shift, line
search and convergence test, and the same knot-type check after every load step); all
rods' questions about their potentials are answered together by one evaluation
(:mod:`tightknot.solvers.batch_eval`). Each rod thus follows its own tie's path up to
round-off (the joint evaluation sums in another order; the Newton systems are solved by a
banded Cholesky factorization, :mod:`tightknot.solvers.banded`). Where a path is close
to a fork, round-off can still lead a rod to another equilibrium than its tie's, e.g. the
same closed knot shifted along its rod; ``tightknot bench batch`` reports each case's
difference from its own tie.

The launches, BVH builds and Python steps of an evaluation are paid once per round for all
rods; what batching cannot share stays per rod: the factorizations of each rod's Newton
system, the rods' own Python steps and the knot-type checks. On a GPU the evaluation's
share is where the gain lies; the linear solves would need a batched solver there too
(docs/design_notes.md, batched rods: what it buys on the CPU).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from tightknot.contact.layer import ContactLayer, ContactSettings
from tightknot.knots.scenes import KnotScene, gauge
from tightknot.loading.options import LoadPath
from tightknot.loading.tie import TieResult, knot_type_of, tie
from tightknot.rods.builder import RodBuilder
from tightknot.rods.model import Model
from tightknot.solvers.banded import single_blas_thread
from tightknot.solvers.batch_eval import (
    BatchContactLayer,
    BatchEvaluator,
    batch_contact_layer,
)
from tightknot.solvers.continuation import StaticResult
from tightknot.solvers.lockstep import (
    BatchRod,
    LinearStats,
    LockstepStats,
    run_lockstep,
)
from tightknot.solvers.pattern import SparsePattern
from tightknot.solvers.program import Coroutine
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
    contact: BatchContactLayer


@dataclass
class RodOutcome:
    """Outcome of one rod of a batch: its own tie's result, and where its time went.

    Attributes:
        tie: the rod's :class:`tightknot.loading.tie.TieResult` (its system: its own one-rod
            system at the result, with its scene's contact layer, so that it evaluates on
            its own; state in the scene's frame).
        linear: its factorizations (banded Cholesky, banded LU where it failed).
        check_s: wall-clock time of its knot-type checks [s].
    """

    tie: TieResult
    linear: LinearStats
    check_s: float

    @property
    def converged(self) -> bool:
        """The rod reached its rest length with its knot type kept."""
        return self.tie.converged

    @property
    def failure(self) -> str:
        """What failed and where ("" when converged)."""
        return self.tie.failure

    @property
    def newton_iterations(self) -> int:
        """Its Newton iterations, failed attempts included."""
        return self.tie.newton_iterations

    @property
    def knot_types(self) -> list[str]:
        """Knot type after each converged step."""
        return self.tie.knot_types

    @property
    def phases(self) -> dict[str, StaticResult]:
        """The continuation result of its tightening."""
        return self.tie.phases

    @property
    def system(self) -> RodSystem:
        """Its own one-rod system at the result."""
        return self.tie.system


@dataclass
class BatchResult:
    """Outcome of tying a batch of knots.

    Attributes:
        converged: every rod reached its rest length with its knot type kept.
        failure: the first failed rod and what failed ("" when converged).
        positions: final centerline of each rod in its own scene's frame [m].
        newton_iterations: Newton iterations summed over the rods.
        rounds: rounds of the lockstep (each one evaluation and one step-bound launch set
            for all rods that had a question).
        wall_time_s: wall-clock time [s].
        knot_types: knot type of each rod after its last converged step.
        rods: each rod's outcome.
        stats: where the lockstep's time went.
        evaluator: the batch's evaluator (at the result: every rod's final state).
    """

    converged: bool
    failure: str
    positions: list[np.ndarray]
    newton_iterations: int
    rounds: int
    wall_time_s: float
    knot_types: list[str] = field(default_factory=list)
    rods: list[RodOutcome] = field(default_factory=list)
    stats: LockstepStats | None = None
    evaluator: BatchEvaluator | None = None


def _layer_settings(layer: ContactLayer) -> ContactSettings:
    return layer.settings


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
        if sc.contact.dof_count:
            raise ValueError(f"scenes[{k}] has contact='sectioned': the batch's banded systems "
                             "cannot hold its section dofs; tie it on its own")
    first = scenes[0]
    twist, device = first.model.twist, first.model.device
    law = first.contact.law
    for k, sc in enumerate(scenes):
        if sc.model.twist != twist or sc.model.device != device:
            raise ValueError(f"scenes[{k}] differs from scenes[0] in twist or device: one "
                             "model has one twist setting and one device")
        if sc.contact.law != law or _layer_settings(sc.contact) != _layer_settings(
                first.contact):
            raise ValueError(f"scenes[{k}] has another contact law or contact settings than "
                             "scenes[0]: one contact layer has one law")
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
    return BatchModel(model, offsets, list(scenes), batch_contact_layer(model, first.contact))



def _tie_program(k: int, scene: KnotScene, evaluator: BatchEvaluator, tighten_steps: int,
                 residual_tol: float, relax_iterations: int) -> Coroutine[RodOutcome]:
    """:func:`tightknot.loading.tie.tie` of the closed knot ``scene`` as rod ``k`` of the
    batch: tie's own program, its systems attached to the batch's evaluator, from a copy of
    the scene's state."""
    check_s = [0.0]
    rod = BatchRod(k, evaluator)

    def timed_knot_type(sc: KnotScene, x: np.ndarray) -> str:
        t0 = time.perf_counter()
        try:
            return knot_type_of(sc, x)
        finally:
            check_s[0] += time.perf_counter() - t0

    res = yield from tie(scene, tighten_steps=tighten_steps, residual_tol=residual_tol,
                         relax_iterations=relax_iterations, attach=rod.attach,
                         start_state=scene.state.copy(), knot_type=timed_knot_type)
    if res.system is not None:
        rod.detach(res.system)  # the result's system evaluates on its own
    return RodOutcome(res, rod.stats, check_s[0])


def tie_batch(
    scenes: list[KnotScene],
    tighten_steps: int = LoadPath.tighten_steps,
    residual_tol: float = LoadPath.residual_tol,
    relax_iterations: int = LoadPath.relax_iterations,
) -> BatchResult:
    """Tie closed knots together, each along its own path as :func:`tightknot.loading.tie.tie`
    would (relax the start curve, then shrink the rest length from the start length to L0
    by load continuation), with one evaluation of all rods per round.

    Args:
        scenes: closed knot scenes (same twist setting, device and contact settings).
        tighten_steps: initial number of load steps (adaptive afterwards, per rod).
        residual_tol: Newton tolerance on each rod's scaled residual.
        relax_iterations: Newton budget of the relaxation of each start curve.
    """
    if not (math.isfinite(residual_tol) and residual_tol > 0):
        raise ValueError(f"residual_tol must be finite and > 0, got {residual_tol!r}")
    if int(tighten_steps) != tighten_steps or tighten_steps < 1:
        raise ValueError(f"tighten_steps must be a whole number >= 1, got {tighten_steps!r}")
    if int(relax_iterations) != relax_iterations or relax_iterations < 1:
        raise ValueError(f"relax_iterations must be a whole number >= 1, got "
                         f"{relax_iterations!r}")
    start = time.perf_counter()
    batch = build_batch(scenes)
    patterns = [SparsePattern(sc.model, ~gauge(sc).fixed_mask()) for sc in scenes]
    evaluator = BatchEvaluator(batch.model, batch.contact, batch.offsets,
                               [sc.model for sc in scenes], patterns)
    programs = [_tie_program(k, sc, evaluator, int(tighten_steps), residual_tol,
                             int(relax_iterations)) for k, sc in enumerate(scenes)]
    stats = LockstepStats()
    with single_blas_thread():
        outcomes: list[RodOutcome] = run_lockstep(programs, evaluator, stats)  # type: ignore
    failed = [k for k, o in enumerate(outcomes) if not o.converged]
    failure = (f"rod {failed[0]} ({scenes[failed[0]].name}, L0/D0 "
               f"{scenes[failed[0]].rest_length / scenes[failed[0]].diameter:.4g}): "
               f"{outcomes[failed[0]].failure}" if failed else "")
    return BatchResult(
        not failed, failure, [o.system.state.x.copy() for o in outcomes],
        sum(o.newton_iterations for o in outcomes), stats.rounds,
        time.perf_counter() - start, [o.knot_types[-1] if o.knot_types else "" for o in
                                      outcomes], outcomes, stats, evaluator)
