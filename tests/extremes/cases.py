"""The extremes of issue 8 as runnable cases, shared by the stress suite and
``bench/extremes.py``.

Each case ties (or steps) a knot at one extreme and returns an :class:`Outcome`: converged,
failed cleanly (a TieResult with a failure string), or rejected (a ValueError with a
message, before any solve); the wall time, the Newton iterations, the knot types seen, the
quantity that limits the case, and whether every number in the state and the outputs is
finite. :func:`check_clean` is the suite's contract on an outcome.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tightknot.knots.open_measures import lambda_oc
from tightknot.knots.scenes import KnotScene, closed_trefoil, open_trefoil, vertex_radii
from tightknot.loading.tie import TieResult, knot_type_of, tie
from tightknot.rods.material import Material

#: The study's rod (physics.md sec. 1).
D0 = 8.5e-3
RUBBER = Material(1.25e6, 0.5, 1160.0)


@dataclass
class Outcome:
    """What one extreme case gave.

    Attributes:
        case: short name.
        outcome: "converged", "failed" (clean: a failure string) or "rejected" (a
            ValueError before any solve).
        message: the failure string or the error message ("" when converged).
        wall_s: wall-clock time [s].
        newton_iterations: total Newton iterations.
        knot_types: knot type after each converged load step.
        limits: the quantities that limit the case (stretch, min gap over D0, ...).
        finite: every number of the final state and of the outputs is finite.
        expected_type: the knot type the case must keep.
        data: extra per-case numbers (e.g. Lambda_OC along a force path).
    """

    case: str
    outcome: str
    message: str
    wall_s: float
    newton_iterations: int = 0
    knot_types: list[str] = field(default_factory=list)
    limits: dict[str, float | None] = field(default_factory=dict)
    finite: bool = True
    expected_type: str = "3_1"
    data: dict[str, Any] = field(default_factory=dict)
    summary: dict[str, Any] = field(default_factory=dict, repr=False)

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready dict."""
        return {"case": self.case, "outcome": self.outcome, "message": self.message,
                "wall_s": self.wall_s, "newton_iterations": self.newton_iterations,
                "knot_types": sorted(set(self.knot_types)), "limits": self.limits,
                "finite": self.finite, "data": self.data}


def all_finite(obj: Any) -> bool:
    """Every float in a nested structure of dicts, lists, tuples and arrays is finite
    (None counts as 'absent', e.g. Lambda_OC of a knot without contact)."""
    if obj is None or isinstance(obj, str | bool):
        return True
    if isinstance(obj, dict):
        return all(all_finite(v) for v in obj.values())
    if isinstance(obj, list | tuple):
        return all(all_finite(v) for v in obj)
    if isinstance(obj, np.ndarray):
        return bool(np.isfinite(obj).all()) if obj.dtype.kind in "fc" else True
    if isinstance(obj, int | float | np.number):
        return math.isfinite(float(obj))
    return True


def check_clean(out: Outcome) -> None:
    """The suite's contract (issue 8): converged, or a clean failure or rejection with a
    message; the knot type kept at every converged step; no NaN anywhere."""
    assert out.outcome in ("converged", "failed", "rejected"), out
    if out.outcome != "converged":
        assert out.message.strip(), f"{out.case}: {out.outcome} without a message"
    assert out.finite, f"{out.case}: non-finite numbers in the state or the outputs"
    if out.outcome == "converged":
        assert set(out.knot_types) == {out.expected_type}, (out.case, out.knot_types)
    else:
        # A failure may be the topology check itself (it names the type it found); every
        # step before it kept the type.
        assert all(k == out.expected_type for k in out.knot_types[:-1]), out.knot_types


def _length(x: np.ndarray, closed: bool) -> float:
    e = (np.roll(x, -1, axis=0) - x) if closed else np.diff(x, axis=0)
    return float(np.linalg.norm(e, axis=1).sum())


def nonlocal_vertex_gap(x: np.ndarray, closed: bool, diameter: float) -> float:
    """Smallest distance [m] between two vertices farther apart along the deformed rod than
    the contact layer's exclusion window pi D0/2 (inf when none is within 2 D0).

    An independent check of ``ContactLayer.min_distance``, which measures whole segments of
    any pair that has *some* points beyond the window, and so reports the distance between
    neighbouring edges of one strand on coarse meshes (see the report: 0.63 D0 for a loose
    closed trefoil at 64 vertices whose strands are 0.99 D0 apart)."""
    from scipy.spatial import cKDTree

    s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(x, axis=0), axis=1))]
    total = s[-1] + (float(np.linalg.norm(x[0] - x[-1])) if closed else 0.0)
    pairs = cKDTree(x).query_pairs(2.0 * diameter, output_type="ndarray")
    if pairs.size == 0:
        return math.inf
    sep = np.abs(s[pairs[:, 0]] - s[pairs[:, 1]])
    if closed:
        sep = np.minimum(sep, total - sep)
    keep = pairs[sep > math.pi / 2 * diameter]
    if keep.size == 0:
        return math.inf
    return float(np.linalg.norm(x[keep[:, 0]] - x[keep[:, 1]], axis=1).min())


def knot_limits(scene: KnotScene, res: TieResult) -> dict[str, float | None]:
    """Limiting quantities of a tied knot: stretch L/L0, min centerline gap over D0, peak
    curvature kappa D0, smallest deformed radius over r0, Lambda_OC (open knots)."""
    sys_ = res.system
    x = sys_.state.x
    dmin, _, _ = scene.contact.min_distance(x)
    r_e, r_v = vertex_radii(scene, x, sys_.rest)
    from tightknot.knots.curvature import bergou_curvature

    gap_nl = nonlocal_vertex_gap(x, scene.closed, scene.diameter)
    out: dict[str, float | None] = {
        "stretch": _length(x, scene.closed) / scene.rest_length,
        "min_gap_over_D0": (dmin / scene.diameter) if math.isfinite(dmin) else None,
        "min_vertex_gap_over_D0": gap_nl / scene.diameter if math.isfinite(gap_nl) else None,
        "kappa_D0_max": float(np.max(bergou_curvature(x, scene.closed)) * scene.diameter),
        "min_radius_over_r0": float(np.min(r_e) / (scene.diameter / 2)),
    }
    if not scene.closed:
        lam = lambda_oc(x, scene.diameter, r_v)
        out["lambda_oc"] = lam if math.isfinite(lam) else None
        out["pull_force_N"] = float(res.pull_force_N)
    return out


def run_tie_case(name: str, make_scene: Callable[[], KnotScene], summary: bool = True,
                 **tie_kw: Any) -> Outcome:
    """Build a scene and tie it; ValueError from either is a rejection. With ``summary``
    the run's JSON summary (tightknot.study.run.run_knot) is made and checked for NaN too."""
    start = time.perf_counter()
    try:
        scene = make_scene()
    except ValueError as err:
        return Outcome(name, "rejected", str(err), time.perf_counter() - start)
    try:
        if summary:
            from tightknot.study.run import run_knot

            run = run_knot(scene, **tie_kw)
            res, outputs = run.result, run.summary
        else:
            res, outputs = tie(scene, **tie_kw).run(), {}
    except ValueError as err:
        return Outcome(name, "rejected", str(err), time.perf_counter() - start,
                       expected_type=scene.knot_type)
    st = res.system.state
    limits = knot_limits(scene, res)
    finite = all_finite([st.x, st.theta, st.v, outputs, limits])
    return Outcome(name, "converged" if res.converged else "failed", res.failure,
                   time.perf_counter() - start, res.newton_iterations, list(res.knot_types),
                   limits, finite, scene.knot_type, summary=outputs)


# -- the cases ---------------------------------------------------------------------------------
def slenderness(l0_over_d0: float, nodes: int, closed: bool = True, **tie_kw: Any) -> Outcome:
    """A trefoil of rest length L0 = ``l0_over_d0`` D0 (closed, or open with its tails)."""
    name = f"slenderness L0/D0={l0_over_d0:g} {'closed' if closed else 'open'} N={nodes}"
    tie_kw = {"tighten_steps": 20, **tie_kw}  # the suite's cases were set up with 20
    if closed:
        return run_tie_case(name, lambda: closed_trefoil(l0_over_d0, D0, nodes), **tie_kw)
    return run_tie_case(name, lambda: open_trefoil(l0_over_d0 * D0, D0, nodes), **tie_kw)


def closed_tightness(l0_over_d0: float, nodes: int = 48) -> Outcome:
    """The closed trefoil from loose (40) to over-tight (12 < 16.37, the ideal)."""
    return run_tie_case(f"closed L0/D0={l0_over_d0:g} N={nodes}",
                        lambda: closed_trefoil(l0_over_d0, D0, nodes), tighten_steps=40)


def material(youngs_modulus: float, poisson: float, nodes: int = 48) -> Outcome:
    """The closed trefoil at L0/D0 = 16.37 in another material."""
    mat = Material(youngs_modulus, poisson, 1160.0)
    return run_tie_case(f"closed E={youngs_modulus:.3g} Pa nu={poisson:g} N={nodes}",
                        lambda: closed_trefoil(16.37, D0, nodes, mat), tighten_steps=40)


def vertex_count(nodes: int, budget: int | None = None, l0_over_d0: float = 16.37) -> Outcome:
    """The closed trefoil with ``nodes`` vertices; ``budget`` caps the Newton iterations of
    the start's relaxation (the big meshes: a clean failure there measures the cost)."""
    kw: dict[str, Any] = {"tighten_steps": 40}
    if budget is not None:
        kw["relax_iterations"] = budget
    return run_tie_case(f"closed L0/D0={l0_over_d0:g} N={nodes}"
                        + (f" (relax budget {budget})" if budget else ""),
                        lambda: closed_trefoil(l0_over_d0, D0, nodes), summary=budget is None,
                        **kw)


def open_force_path(final_force: float, nodes: int = 150, pull_steps: int = 20) -> Outcome:
    """The open trefoil (L0 = 185 mm) tightened, then pulled by a force growing (or
    falling) geometrically from the tightening's end reaction to ``final_force`` [N];
    Lambda_OC and the min gap are recorded at every pull step (``data["path"]``)."""
    path: list[dict[str, float | None]] = []

    def hook(phase: str, system: Any, rec: Any) -> None:
        if phase != "pull":
            return
        x = system.state.x
        f = float(np.linalg.norm(system.bcs.external_force(rec.t)[-1]))
        lam = lambda_oc(x, scene.diameter, vertex_radii(scene, x, system.rest)[1])
        dmin, _, _ = scene.contact.min_distance(x)
        gap_nl = nonlocal_vertex_gap(x, False, scene.diameter)
        path.append({"force_N": f, "lambda_oc": lam if math.isfinite(lam) else None,
                     "min_gap_over_D0": dmin / scene.diameter if math.isfinite(dmin) else None,
                     "min_vertex_gap_over_D0": (gap_nl / scene.diameter
                                                if math.isfinite(gap_nl) else None),
                     "stretch": _length(x, False) / scene.rest_length})

    scene = open_trefoil(0.185, D0, nodes)
    out = run_tie_case(f"open 185 mm pulled to F={final_force:g} N N={nodes}", lambda: scene,
                       summary=False, pull_force=final_force, tighten_steps=40,
                       pull_steps=pull_steps, hook=hook)
    out.data["path"] = path
    out.finite = out.finite and all_finite(path)
    lams = [p["lambda_oc"] for p in path if p["lambda_oc"] is not None]
    if lams:
        out.limits["lambda_oc_min_on_path"] = min(lams)
    return out


def dynamics(dt: float, steps: int = 3, nodes: int = 48, speed: float = 0.05,
             tied: tuple[KnotScene, Any] | None = None, max_iterations: int = 100) -> Outcome:
    """Implicit-Euler steps of ``dt`` [s] from the tied closed trefoil given a velocity
    field (a rigid spin plus a smooth wobble, peak ``speed`` [m/s]); free rod, contact on.
    Limits: the largest growth of the total energy (potential + kinetic) over a step
    relative to the start's kinetic energy (backward Euler dissipates), the last kinetic
    energy over the first."""
    from tightknot.rods.boundary import BoundaryConditions
    from tightknot.solvers.dynamic import implicit_euler_step, kinetic_energy
    from tightknot.solvers.newton import NewtonOptions
    from tightknot.solvers.system import RodSystem

    name = f"implicit Euler dt={dt:g} s x{steps} N={nodes}"
    start = time.perf_counter()
    scene, tied_state = tied if tied is not None else tied_closed_trefoil(nodes)
    state = tied_state.copy()
    x = state.x
    c = x.mean(axis=0)
    spin = np.cross([0.0, 0.0, 1.0], x - c)
    wobble = np.sin(np.linspace(0, 6 * np.pi, len(x), endpoint=False))[:, None] * [0, 0, 1.0]
    v = spin / np.abs(spin).max() + wobble
    state.v = speed * v / np.abs(v).max()
    # A free rod (inertia makes the step well posed without a gauge) at the tied rest length.
    shrink = 1.0 / scene.start_length_ratio
    bcs = BoundaryConditions(scene.model, state.x).rest_length_scale((shrink, shrink))
    system = RodSystem(scene.model, state, bcs)
    system.add_term(scene.contact)
    system.set_load(0.0)
    e0, _, _ = system.evaluate(system.free_vector(), False, False)
    ke0 = kinetic_energy(system)
    total = [e0 + ke0]
    iters = 0
    types: list[str] = []
    message = ""
    for _ in range(steps):
        step = implicit_euler_step(system, dt, NewtonOptions(max_iterations=max_iterations))
        iters += step.newton.iterations
        if not step.newton.converged:
            message = (f"implicit Euler step of {dt:g} s: Newton {step.newton.reason} "
                       f"(residual {step.newton.residual:.3g}) at time {system.state.time:g} s")
            break
        e, _, _ = system.evaluate(system.free_vector(), False, False)
        total.append(e + step.kinetic_energy)
        types.append(knot_type_of(scene, system.state.x))
    st = system.state
    growth = max((b - a for a, b in zip(total, total[1:], strict=False)), default=0.0)
    limits = {"energy_growth_over_ke0": growth / ke0,
              "ke_last_over_ke0": kinetic_energy(system) / ke0}
    return Outcome(name, "failed" if message else "converged", message,
                   time.perf_counter() - start, iters, types, limits,
                   all_finite([st.x, st.theta, st.v, st.theta_dot, total, limits]))


def tied_closed_trefoil(nodes: int = 48) -> tuple[KnotScene, Any]:
    """A closed trefoil scene (L0/D0 = 16.37) and its tied state (velocities zero)."""
    scene = closed_trefoil(16.37, D0, nodes)
    res = tie(scene, tighten_steps=40).run()
    if not res.converged:
        raise RuntimeError(f"tying the closed trefoil failed: {res.failure}")
    state = res.system.state.copy()
    state.v[:] = 0.0
    return scene, state


def float32_floor(scene: KnotScene, res: TieResult) -> dict[str, float]:
    """What float32 would do to a converged knot: the scaled residual of the float64
    equilibrium after rounding its positions to float32 (the floor below which a float32
    solver could not converge), beside the float64 residual and the tolerance."""
    system = res.system
    _, g, _ = system.evaluate(system.free_vector(), True, False)
    r64 = system.residual_norm(g)
    saved = system.state.x.copy()
    try:
        system.state.x = saved.astype(np.float32).astype(np.float64)
        _, g32, _ = system.evaluate(system.free_vector(), True, False)
        r32 = system.residual_norm(g32)
    finally:
        system.state.x = saved
    return {"residual_float64": r64, "residual_positions_rounded_to_float32": r32}
