"""Batched tying against one-after-another: ``tightknot bench batch``.

The cases are a sweep of closed trefoils over L0/D0 (the small cases a sweep runs), each
tied by :func:`tightknot.loading.tie.tie` one after another, and all together by
:func:`tightknot.loading.batch.tie_batch` (one model; every rod runs tie()'s own solver, all
rods' evaluations answered by one set of launches per round). Both are timed in the same
run, under the same BLAS setting; the batched result is checked against the sequential
one (largest vertex difference over D0, and the curvature profile at the best shift along
the rod: :func:`shape_difference`) and the Newton iterations of each case are compared.
Where the time goes is measured too: the cost of one Newton iteration's parts (evaluation
with Hessian, factorization and solve) per rod, for one rod alone and inside the batch, at
the tied state, and the batched run's split into evaluation, step bounds, linear algebra,
knot-type checks and the rest of the rods' own work.
"""

from __future__ import annotations

import math
import time

import numpy as np

from tightknot.benchmarks.der import newton_iteration_parts
from tightknot.knots.scenes import closed_trefoil
from tightknot.loading.batch import BatchResult, tie_batch
from tightknot.loading.tie import tie
from tightknot.solvers.banded import single_blas_thread
from tightknot.solvers.batch_eval import EvalRequest
from tightknot.solvers.linear import LowRankHessian
from tightknot.solvers.lockstep import BandedSolver, LinearStats
from tightknot.solvers.system import RodSystem

#: The issue's target: 64 trefoils of 100 vertices batched >= 5x faster than sequential.
TARGET_SPEEDUP = 5.0


def _iteration_parts(system: RodSystem, repeats: int = 9) -> dict[str, float]:
    """Median times [s] of one evaluation with Hessian and one factorization + solve of a
    one-rod system (as :func:`tightknot.solvers.newton.newton` does them)."""
    evaluate_s, solve_s = newton_iteration_parts(system, repeats)
    return {"evaluate_s": evaluate_s, "factorize_solve_s": solve_s}


def _batched_parts(batch: BatchResult, repeats: int = 9) -> dict[str, float]:
    """Median times [s] per rod of one batched evaluation of every rod with Hessian, and of
    each rod's factorization + solve (the batch's banded solver), at the final states."""
    ev = batch.evaluator
    systems = [o.system for o in batch.rods]
    n = len(systems)
    solvers = [BandedSolver(LinearStats()) for _ in systems]
    te, tf = [], []
    with single_blas_thread():
        for rep in range(repeats + 1):
            reqs = [EvalRequest(k, s.state.x, s.state.theta, s.state.d1_ref, s.state.t_ref,
                                s.state.m_ref) for k, s in enumerate(systems)]
            t0 = time.perf_counter()
            answers = ev.evaluate(reqs)
            t1 = time.perf_counter()
            for k, (s, solver) in enumerate(zip(systems, solvers, strict=True)):
                ans = answers[k]
                h = ans.hess if ans.low_rank is None else LowRankHessian(ans.hess,
                                                                         *ans.low_rank)
                solver.shifted_direction(h, ans.grad[s.pattern.free_dofs], 0.0,
                                         np.abs(ans.hess.data[ans.hess.diag_slot]))
            t2 = time.perf_counter()
            if rep:  # the first builds each rod's ordering (once per contact pattern)
                te.append((t1 - t0) / n)
                tf.append((t2 - t1) / n)
    return {"evaluate_s": float(np.median(te)), "factorize_solve_s": float(np.median(tf))}


def shape_difference(x: np.ndarray, y: np.ndarray, diameter: float) -> float:
    """RMS difference of the curvature profiles kappa D0 of two closed centerlines of the
    same vertex count, at the best circular shift of one along the other: zero for the same
    knot shape wherever it sits along the rod. A tied closed knot can slide along its own
    (uniform) rod at almost no cost, so two solves may stop at shifted copies of one shape
    whose vertex positions differ by a good part of D0."""
    from tightknot.knots.curvature import bergou_curvature

    ka = bergou_curvature(x, True) * diameter
    kb = bergou_curvature(y, True) * diameter
    return float(min(np.sqrt(np.mean((ka - np.roll(kb, k)) ** 2)) for k in range(len(kb))))


def run(rods: int = 64, nodes: int = 100, l0_over_d0: tuple[float, float] = (17.0, 20.0),
        sequential_rods: int | None = None, residual_tol: float = 1e-6,
        device: str = "cpu") -> dict:
    """Tie ``rods`` closed trefoils of ``nodes`` vertices (L0/D0 evenly over the range)
    batched and one by one; ``sequential_rods`` < rods ties only that many evenly chosen
    cases one by one and extrapolates the sequential time (said so in the result). Both
    run on the Warp ``device`` (the linear algebra stays on the CPU)."""
    if int(rods) != rods or rods < 1:
        raise ValueError(f"rods must be a whole number >= 1, got {rods!r}")
    seq_n = rods if sequential_rods is None else int(sequential_rods)
    if not (1 <= seq_n <= rods):
        raise ValueError(f"sequential_rods must be in [1, rods={rods}], got {sequential_rods!r}")
    lo, hi = (float(v) for v in l0_over_d0)
    if not (math.isfinite(lo) and math.isfinite(hi) and 10.0 <= lo <= hi):
        raise ValueError(f"l0_over_d0 must be a range LO <= HI with LO >= 10, got {l0_over_d0}")
    ratios = np.linspace(lo, hi, rods)
    scenes = [closed_trefoil(l0_over_d0=float(r), nodes=nodes, device=device)
              for r in ratios]
    # Warm up both paths on one small case (kernel modules loaded, tables cached), so that
    # neither pays a one-time cost inside its timing.
    tie(closed_trefoil(l0_over_d0=lo, nodes=nodes, device=device), tighten_steps=20).run()
    tie_batch([closed_trefoil(l0_over_d0=lo, nodes=nodes, device=device)], tighten_steps=20)
    t0 = time.perf_counter()
    batch = tie_batch(scenes, tighten_steps=20, residual_tol=residual_tol)
    tb = time.perf_counter() - t0
    if not batch.converged:
        raise RuntimeError(f"batched tie failed: {batch.failure}")

    pick = np.unique(np.round(np.linspace(0, rods - 1, seq_n)).astype(int))
    ts = 0.0
    seq_iters = []
    diffs = []
    shape_diffs = []
    last = None
    # The batch runs with one BLAS thread (tightknot.solvers.banded); the one-by-one
    # ties run under the same setting, so that the ratio measures the batching alone.
    with single_blas_thread():
        for k in pick:
            scene = closed_trefoil(l0_over_d0=float(ratios[k]), nodes=nodes, device=device)
            t0 = time.perf_counter()
            single = tie(scene, tighten_steps=20, residual_tol=residual_tol).run()
            ts += time.perf_counter() - t0
            if not single.converged:
                raise RuntimeError(f"sequential tie of case {k} failed: {single.failure}")
            seq_iters.append(single.newton_iterations)
            diffs.append(float(np.abs(single.system.state.x - batch.positions[k]).max())
                         / scene.diameter)
            shape_diffs.append(shape_difference(single.system.state.x, batch.positions[k],
                                                scene.diameter))
            last = single
        one = _iteration_parts(last.system)
    many = _batched_parts(batch)
    extrapolated = len(pick) < rods
    sequential_s = ts * rods / len(pick)
    seq_total = int(round(sum(seq_iters) * rods / len(pick)))
    st = batch.stats
    linear_s = sum(o.linear.seconds for o in batch.rods)
    check_s = sum(o.check_s for o in batch.rods)
    return {
        "rods": rods,
        "vertices": nodes,
        "device": device,
        "l0_over_d0": [lo, hi],
        "cases": "sweep: L0/D0 evenly over the range, one case per rod",
        "batched_s": tb,
        "sequential_s": sequential_s,
        "speedup": sequential_s / tb,
        "sequential_extrapolated": extrapolated,
        "sequential_measured_rods": int(len(pick)),
        "batched_newton_iterations": batch.newton_iterations,
        "sequential_newton_iterations": seq_total,
        "batched_rounds": batch.rounds,
        "newton_iterations_per_case": {
            "batched": [batch.rods[k].newton_iterations for k in pick],
            "sequential": seq_iters},
        "ms_per_rod_iteration": {"batched": 1e3 * tb / batch.newton_iterations,
                                 "sequential": 1e3 * sequential_s / seq_total},
        "batched_time_split_s": {
            "evaluate": st.evaluate_s, "step_bound": st.step_bound_s,
            "linear_solve": linear_s, "knot_type_checks": check_s,
            "rods_other": st.rod_s - linear_s - check_s},
        "factorizations": {
            "banded_cholesky": sum(o.linear.cholesky for o in batch.rods),
            "banded_lu": sum(o.linear.lu for o in batch.rods),
            "superlu": sum(o.linear.superlu for o in batch.rods)},
        "max_position_diff_over_D0": max(diffs),
        "max_kappa_profile_diff": max(shape_diffs),
        # Per case: a case whose batched equilibrium is another one than its own tie's
        # (round-off took it along another branch at a fork) shows here.
        "position_diff_over_D0": diffs,
        "cases_differing_over_1e-6_D0": [float(ratios[k]) for k, d in zip(pick, diffs,
                                                                            strict=True)
                                         if d > 1e-6],
        "kappa_profile_diff": shape_diffs,
        "iteration_cost": {"single_rod": one, "batched_per_rod": many},
        "target_speedup_min": TARGET_SPEEDUP,
    }


# -- command line (``tightknot bench batch``) ------------------------------------------------
_EXAMPLES = """examples:
  tightknot bench batch --json batch.json
  tightknot bench batch --rods 8 --nodes 60
  tightknot bench batch --sequential-rods 8   # extrapolates the sequential time (said so)
"""


def register(subparsers) -> None:  # noqa: ANN001 (argparse's private subparsers type)
    """Add ``tightknot bench batch``."""
    import argparse

    p = subparsers.add_parser(
        "batch", help="many closed trefoils tied in one model vs one after another",
        description="Tie ROD closed trefoils (L0/D0 swept over a range) in one model, each "
        "with its own solver and all evaluated by one set of launches per round, and one "
        "after another; report both times and their ratio.",
        epilog=_EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--json", metavar="FILE", help="write the result as JSON")
    p.add_argument("--rods", type=int, default=64, help="number of knots (default 64)")
    p.add_argument("--nodes", type=int, default=100, help="vertices per knot (default 100)")
    p.add_argument("--l0-over-d0", type=float, nargs=2, default=(17.0, 20.0),
                   metavar=("LO", "HI"), help="range of L0/D0 (default 17 20)")
    p.add_argument("--device", default=None, help="Warp device (default cpu)")
    p.add_argument("--sequential-rods", type=int, default=None,
                   help="tie only this many one by one and extrapolate (default: all)")
    p.set_defaults(handler=_command)


def _command(args) -> int:  # noqa: ANN001
    from tightknot.atomic import writable_file, write_json_atomic

    out = writable_file(args.json)
    if args.nodes < 24:
        raise ValueError(f"--nodes must be >= 24, got {args.nodes}")
    from tightknot.warp_setup import resolve_device

    r = run(args.rods, args.nodes, tuple(args.l0_over_d0), args.sequential_rods,
            device=resolve_device(args.device))
    note = " (extrapolated)" if r["sequential_extrapolated"] else ""
    print(f"{r['rods']} closed trefoils of {r['vertices']} vertices: batched "
          f"{r['batched_s']:.2f} s ({r['batched_newton_iterations']} iterations), sequential "
          f"{r['sequential_s']:.2f} s{note} ({r['sequential_newton_iterations']} iterations)")
    ms = r["ms_per_rod_iteration"]
    print(f"  {r['batched_rounds']} rounds; per rod and Newton iteration: batched "
          f"{ms['batched']:.2f} ms, sequential {ms['sequential']:.2f} ms")
    split = ", ".join(f"{k} {v:.2f} s" for k, v in r["batched_time_split_s"].items())
    print(f"  batched time: {split}")
    print(f"speedup {r['speedup']:.2f} (target >= {TARGET_SPEEDUP:g}); largest difference "
          f"{r['max_position_diff_over_D0']:.2e} D0 in positions, "
          f"{r['max_kappa_profile_diff']:.2e} in the kappa D0 profile (best shift)")
    c = r["iteration_cost"]
    for k in ("single_rod", "batched_per_rod"):
        print(f"  {k:>16s}: evaluate {c[k]['evaluate_s'] * 1e3:.2f} ms, factorize+solve "
              f"{c[k]['factorize_solve_s'] * 1e3:.2f} ms")
    if out is not None:
        write_json_atomic(out, r)
    return 0
