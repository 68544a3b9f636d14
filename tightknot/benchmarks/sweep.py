"""Cost of a tightness sweep along one continuation path against its tightest level alone.

The 185 mm open trefoil (300 vertices) is tied once and pulled through 20 knot lengths
Lambda_OC, from the study's 15.0 (physics.md sec. 1) down to 10.25, each level from the
previous equilibrium, through the sweep machinery (:func:`tightknot.sweep.run_sweep`,
serial, into a temporary store: the records are written as a user's sweep writes them).
In the same run, the tightest level alone (tie, then one search to it) is timed, so the
ratio sweep / tightest shows what the other 19 levels cost. Target (issue 7): the sweep
in <= 30 s on 2 CPU cores with a warm kernel cache.
"""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

#: The issue's benchmark: 20 levels of the 185 mm knot at 300 vertices.
DEFAULT_LEVELS = 20
DEFAULT_NODES = 300
DEFAULT_LENGTH = 0.185
#: Loosest and tightest Lambda_OC: the study's level of the 185 mm knot, and a knot as tight
#: as the study's 125 mm one (10.1) that this length still reaches by pulling.
DEFAULT_LOOSEST, DEFAULT_TIGHTEST = 15.0, 10.25
TARGET_WALL_TIME_S = 30.0


def _warm_up() -> float:
    """Load Warp's kernels, numba's cache and the contact tables once (what every process
    pays first) and return its time [s]."""
    from tightknot.sweep.execute import run_case

    t0 = time.perf_counter()
    run_case({"knot": "closed", "nodes": 36, "tighten_steps": 10, "l0_over_d0": 20.0})
    return time.perf_counter() - t0


def run(levels: int = DEFAULT_LEVELS, nodes: int = DEFAULT_NODES,
        length: float = DEFAULT_LENGTH, loosest: float = DEFAULT_LOOSEST,
        tightest: float = DEFAULT_TIGHTEST, force: bool = False,
        with_tie_to_lambda: bool = False) -> dict[str, Any]:
    """Time the sweep and its tightest level alone; ``force`` sweeps pulling forces [N]
    from ``loosest`` to ``tightest`` (geometric) instead of Lambda_OC (linear);
    ``with_tie_to_lambda`` also times the knots package's own driver to the tightest
    Lambda_OC (:func:`tightknot.loading.pull.tie_to_lambda`)."""
    from tightknot.sweep import Case, run_case, run_sweep
    from tightknot.sweep.executors import SerialExecutor

    if levels < 1:
        raise ValueError(f"--levels must be >= 1, got {levels}")
    key = "pull_force" if force else "target_lambda"
    values = (np.geomspace(loosest, tightest, levels) if force
              else np.linspace(loosest, tightest, levels))
    values = [round(float(v), 6) for v in values]
    case = Case.of({"knot": "open", "nodes": nodes, "length": length, key: values})
    tight = Case.of({**case.params, key: [case.levels[-1]]})
    warm = _warm_up()
    with tempfile.TemporaryDirectory() as tmp:
        t0, c0 = time.perf_counter(), time.process_time()
        report = run_sweep([case], Path(tmp) / "store", SerialExecutor())
        t_sweep, c_sweep = time.perf_counter() - t0, time.process_time() - c0
        record = report.records()[0]
    t0, c0 = time.perf_counter(), time.process_time()
    alone = run_case(tight.params)
    t_alone, c_alone = time.perf_counter() - t0, time.process_time() - c0
    extra: dict[str, Any] = {}
    if with_tie_to_lambda and not force:
        from tightknot.loading.pull import tie_to_lambda
        from tightknot.sweep.execute import build_scene

        scene = build_scene(tight.params)
        t0 = time.perf_counter()
        ttl = tie_to_lambda(scene, case.levels[-1]).run()
        extra = {"tie_to_lambda_s": time.perf_counter() - t0,
                 "tie_to_lambda_converged": ttl.converged,
                 "tie_to_lambda_force_N": ttl.pull_force_N}
    res = record.get("result") or {}
    rows = [{k: lv[k] for k in ("target", "reached", "pull_force_N", "lambda_oc",
                                "newton_iterations", "solves", "wall_time_s", "failure")}
            for lv in res.get("levels", [])]
    alone_levels = (alone.get("result") or {}).get("levels", [])
    return {
        "levels": len(values),
        "vertices": nodes,
        "length_m": length,
        "level_kind": key,
        "level_values": values,
        "wall_time_s": t_sweep,
        "status": record["status"],
        "failure": record["failure"],
        "levels_reached": sum(r["reached"] for r in rows),
        "tie_wall_time_s": res.get("tie_wall_time_s"),
        "per_level": rows,
        "tightest_level_alone_s": t_alone,
        "tightest_level_alone_status": alone["status"],
        "tightest_level_alone_force_N": alone_levels[0]["pull_force_N"] if alone_levels
        else None,
        "ratio_sweep_over_tightest_alone": t_sweep / t_alone,
        # CPU time of this process (all its threads): on a machine shared with other
        # jobs the wall time grows with the load, this much less.
        "cpu_time_s": c_sweep,
        "tightest_level_alone_cpu_s": c_alone,
        **extra,
        "warmup_s": warm,
        "cpu_count": os.cpu_count(),
        "load_average_1min": os.getloadavg()[0],
        "targets": {"wall_time_max_s": TARGET_WALL_TIME_S},
        "meets_target": t_sweep <= TARGET_WALL_TIME_S,
    }


# -- command line (``tightknot bench sweep``) ------------------------------------------------
_EXAMPLES = """examples:
  tightknot bench sweep --json sweep.json
  tightknot bench sweep --levels 5 --nodes 150
  tightknot bench sweep --force --loosest 2.2 --tightest 6
"""


def register(subparsers) -> None:  # noqa: ANN001 (argparse's private subparsers type)
    """Add ``tightknot bench sweep``."""
    import argparse

    p = subparsers.add_parser(
        "sweep", help="a 20-level tightness sweep along one path vs its tightest level alone",
        description="Tie the 185 mm open trefoil once and pull it through N knot lengths "
        "along one continuation path (the sweep machinery, serial); time it, and the "
        "tightest level alone in the same run. Target: <= 30 s for 20 levels, 300 vertices.",
        epilog=_EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--json", metavar="FILE", help="write the result as JSON")
    p.add_argument("--levels", type=int, default=DEFAULT_LEVELS, help="levels (20)")
    p.add_argument("--nodes", type=int, default=DEFAULT_NODES, help="vertices (300)")
    p.add_argument("--length", type=float, default=DEFAULT_LENGTH, help="L0 [m] (0.185)")
    p.add_argument("--loosest", type=float, default=None,
                   help="loosest level: Lambda_OC (15.0), or force [N] with --force")
    p.add_argument("--tightest", type=float, default=None,
                   help="tightest level: Lambda_OC (10.25), or force [N] with --force")
    p.add_argument("--force", action="store_true",
                   help="levels are pulling forces (geometric), not knot lengths")
    p.add_argument("--with-tie-to-lambda", action="store_true",
                   help="also time tightknot.loading.pull.tie_to_lambda to the tightest level")
    p.set_defaults(handler=_command)


def _command(args) -> int:  # noqa: ANN001
    from tightknot.atomic import writable_file, write_json_atomic

    out = writable_file(args.json)
    if args.force and (args.loosest is None or args.tightest is None):
        raise ValueError("--force needs --loosest F1 and --tightest F2 [N]")
    loosest = DEFAULT_LOOSEST if args.loosest is None else args.loosest
    tightest = DEFAULT_TIGHTEST if args.tightest is None else args.tightest
    result = run(args.levels, args.nodes, args.length, loosest, tightest, args.force,
                 args.with_tie_to_lambda)
    for r in result["per_level"]:
        lam = "-" if r["lambda_oc"] is None else f"{r['lambda_oc']:.3f}"
        print(f"  level {r['target']:8.4g}: {'ok ' if r['reached'] else 'NOT'} force "
              f"{r['pull_force_N']:.4g} N, Lambda_OC {lam}, {r['newton_iterations']:4d} "
              f"iterations, {r['wall_time_s']:.2f} s")
    print(f"sweep of {result['levels']} levels, {result['vertices']} vertices: "
          f"{result['wall_time_s']:.2f} s (tie {result['tie_wall_time_s'] or 0:.2f} s; "
          f"target <= {TARGET_WALL_TIME_S:g} s: {'met' if result['meets_target'] else 'MISSED'})")
    print(f"CPU time: sweep {result['cpu_time_s']:.2f} s, tightest level alone "
          f"{result['tightest_level_alone_cpu_s']:.2f} s")
    print(f"tightest level alone: {result['tightest_level_alone_s']:.2f} s; ratio "
          f"{result['ratio_sweep_over_tightest_alone']:.2f}; {result['levels_reached']}/"
          f"{result['levels']} levels reached; load average {result['load_average_1min']:.1f}"
          f" on {result['cpu_count']} CPUs")
    if "tie_to_lambda_s" in result:
        print(f"tie_to_lambda to the tightest level: {result['tie_to_lambda_s']:.2f} s "
              f"(force {result['tie_to_lambda_force_N']:.4g} N)")
    if result["failure"]:
        print(f"  failure: {result['failure']}")
    if out is not None:
        write_json_atomic(out, result)
    return 0
