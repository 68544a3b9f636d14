"""``tightknot sweep``: sweep a knot scene's parameters into a resumable store.

Every option that takes several values is a sweep axis (the cases are their Cartesian
product); an open knot's ``--lambda`` or ``--force`` levels are one continuation path per
case (tie once, then pull level by level). Results go to ``--out DIR`` (one JSON file per
case, plus ``index.json``); running the same command again skips the finished cases.
Exit codes: 0 every case ok, 1 a case failed (its reason printed), 2 bad input. An open
knot's path that reached some of its levels is ok: every reached level is kept, each missed
one is marked (``reached: false``) and printed as a warning on stderr, and the exit code
stays 0; a path that reached none of them (or whose tie failed) is a failed case.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

EXIT_OK, EXIT_PHYSICS = 0, 1

_EXAMPLES = """examples:
  # the 185 mm open trefoil pulled through 20 knot lengths along one path
  tightknot sweep open --length 0.185 --lambda 15 14.75 14.5 14.25 14 13.75 13.5 13.25 \\
      13 12.75 12.5 12.25 12 11.75 11.5 11.25 11 10.75 10.5 10.25 --out runs/sweep185
  # pulling forces [N] for two rest lengths and two meshes (4 paths, 2 worker processes)
  tightknot sweep open --length 0.185 0.16 --nodes 150 300 --force 2 3 4 5 --out runs/f \\
      --workers 2
  # closed trefoils of three lengths, compliant and rigid-tube contact
  tightknot sweep closed --l0-over-d0 16.37 18 20 --contact compliant rigid --out runs/c
  # the same on a Dask cluster (pip install tightknot[distributed])
  tightknot sweep closed --l0-over-d0 16.37 18 20 --out runs/c --executor dask \\
      --scheduler tcp://scheduler:8786
  # eight closed trefoils tied together in one model, in this process
  tightknot sweep closed --l0-over-d0 17 17.5 18 18.5 19 19.5 20 20.5 --nodes 100 \\
      --batch 8 --executor serial --out runs/cb
  # interrupted? run the same command again: finished cases are skipped
  tightknot sweep closed --l0-over-d0 16.37 18 20 --out runs/c --json runs/c.json

store: DIR/index.json lists every case (id, params, status); DIR/cases/ID.json holds its
record (the knot summary of 'tightknot tie'; for an open knot one entry per level).
Flat table and plots of a store: tightknot table DIR --out t.csv; tightknot plot DIR.

exit codes: 0 every case ok (a level an open knot's path missed is a warning: the others
are kept), 1 a case failed (a tie that failed, or a path that reached no level), 2 bad input.
"""



def _options() -> tuple[tuple[str, ...], tuple[str, ...]]:
    """(axes, single): the case parameters that are sweep axes (the scene's: several values
    are their product) and those given once (the load path's)."""
    from tightknot.loading.options import parameters
    from tightknot.study.params import Scene
    from tightknot.sweep.cases import CASE_KEYS

    axes = tuple(k for k in parameters(Scene) if k != "knot")
    keys = dict.fromkeys(CASE_KEYS["closed"] + CASE_KEYS["open"])
    return axes, tuple(k for k in keys if k not in axes)


#: The flag of each level list (the loads' own names are the tie command's).
_LEVEL_FLAGS = {"target_lambda": "--lambda", "pull_force": "--force"}


def register(subparsers: Any) -> None:
    """Add ``tightknot sweep`` to an argparse ``subparsers``; the case parameters' flags
    are generated from their declarations (:mod:`tightknot.study.params`)."""
    from tightknot.loading.options import flag, flag_kwargs, flags
    from tightknot.study.params import RUN_PARAMS
    from tightknot.sweep.cases import LEVELS
    from tightknot.sweep.executors import EXECUTORS

    p = subparsers.add_parser(
        "sweep", help="sweep knot parameters (tightness, length, E, mesh...) into a store",
        description="Run a sweep of the study's knots: every multi-valued option is an "
        "axis, an open knot's --lambda/--force levels are one continuation path. One JSON "
        "file per case in --out, written atomically, with an index; an interrupted sweep "
        "started again skips the finished cases.",
        epilog=_EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    knot = RUN_PARAMS["knot"]
    p.add_argument("knot", choices=knot.valid, help=knot.what)
    p.add_argument("--out", required=True, metavar="DIR",
                   help="the store folder (created; its parent must exist)")
    axes, single = _options()
    for name in axes:
        p.add_argument(*flags(RUN_PARAMS[name]), **flag_kwargs(RUN_PARAMS[name], nargs="+"))
    levels = p.add_mutually_exclusive_group()
    what = {"target_lambda": ("open: target knot lengths Lambda_OC", ", one path visiting "
                              "them from the loosest"),
            "pull_force": ("open: pulling forces", ", one path from the weakest")}
    for name, load in LEVELS.items():
        levels.add_argument(_LEVEL_FLAGS[name], dest=name, **flag_kwargs(
            RUN_PARAMS[load], nargs="+", what=what[name][0], note=what[name][1]))
    for name in single:
        p.add_argument(flag(name), **flag_kwargs(RUN_PARAMS[name]))
    p.add_argument("--executor", choices=EXECUTORS, default="process",
                   help="where cases run: local processes (default), serial (this "
                   "process), dask (a local cluster, or --scheduler)")
    p.add_argument("--workers", type=int, default=None,
                   help="worker processes (default: the CPU count, at most the cases)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="dask: address of a running scheduler (tcp://host:8786)")
    p.add_argument("--batch", type=int, default=None, metavar="N",
                   help="closed knots: tie up to N cases together in one model (one set of "
                   "Warp launches per round for all of them; each batch one task of the "
                   "executor)")
    p.add_argument("--retry-failed", action="store_true",
                   help="run again the cases stored as failed")
    p.add_argument("--json", metavar="FILE", help="write a summary of every case as JSON")
    p.add_argument("--device", **flag_kwargs(RUN_PARAMS["device"]))
    p.add_argument("--quiet", action="store_true", help="print nothing but errors")
    p.set_defaults(handler=run_command)


def build_cases(args: argparse.Namespace) -> list:
    """The sweep's cases from the parsed options (ValueError on bad input)."""
    from tightknot.loading.options import flag
    from tightknot.sweep.cases import CASE_KEYS, LEVELS, grid

    axes, single = _options()
    given = [k for k in (*axes, *LEVELS, *single) if getattr(args, k) is not None]
    allowed = set(CASE_KEYS[args.knot]) | (set(LEVELS) if args.knot == "open" else set())
    foreign = [k for k in given if k not in allowed]
    if foreign:
        other = "open" if args.knot == "closed" else "closed"
        names = ", ".join(_LEVEL_FLAGS.get(k, flag(k)) for k in foreign)
        raise ValueError(f"{names}: for {other} knots only")
    if args.knot == "open" and not any(k in given for k in LEVELS):
        raise ValueError("an open knot needs its levels: --lambda LAMBDA... or --force "
                         "F... [N]")
    base: dict[str, Any] = {"knot": args.knot}
    base.update({k: getattr(args, k) for k in given if k not in axes})
    return grid(base, **{k: getattr(args, k) for k in given if k in axes})


def short_result(record: dict[str, Any]) -> dict[str, Any]:
    """A record's headline numbers (no profiles) for the --json summary."""
    out = {k: record[k] for k in ("id", "params", "status", "failure", "wall_time_s")}
    out["warnings"] = record.get("warnings", [])
    res = record.get("result") or {}
    if "table" in res:
        out["levels"] = res["table"]
    else:
        for k in ("knot_type", "stretch", "L_over_D", "min_gap_over_D0", "min_area_ratio",
                  "max_pressure_over_E", "kappa_D0_max", "kappa_D0_min", "newton_iterations"):
            if k in res:
                out[k] = res[k]
    return out


def _line(record: dict[str, Any], label: str) -> str:
    head = f"{record['id']}  {label}: {record['status']} ({record['wall_time_s']:.1f} s)"
    res = record.get("result") or {}
    if record["status"] != "ok":
        head += f"\n    {record['failure']}"
    if "table" in res:
        for row in res["table"]:
            lam = "-" if row["lambda_oc"] is None else f"{row['lambda_oc']:.3f}"
            mark = "" if row["reached"] else "  NOT REACHED"
            head += (f"\n    {row['kind']} {row['target']:g}: force {row['pull_force_N']:.4g} N,"
                     f" Lambda_OC {lam}{mark}")
    elif "L_over_D" in res:
        gap = res.get("min_gap_over_D0")
        gap_s = "-" if gap is None else f"{gap:.4f}"  # None: no pair in range (knot undone)
        head += (f"\n    L/D {res['L_over_D']:.4f}, stretch {res['stretch']:.4f}, min gap/D0 "
                 f"{gap_s}, kappa D0 max {res['kappa_D0_max']:.3f}")
    return head


def run_command(args: argparse.Namespace) -> int:
    """Handler of ``tightknot sweep``: 0 every case ok, 1 a case failed, 2 bad input."""
    from tightknot.atomic import writable_file, write_json_atomic
    from tightknot.sweep.executors import make_executor
    from tightknot.sweep.store import Store
    from tightknot.sweep.sweep import run_sweep
    from tightknot.warp_setup import resolve_device

    out_json = writable_file(args.json)
    if args.workers is not None and args.workers < 1:
        raise ValueError(f"--workers must be >= 1, got {args.workers}")
    if args.scheduler is not None and args.executor != "dask":
        raise ValueError("--scheduler is for --executor dask")
    if args.batch is not None:
        if args.batch < 1:
            raise ValueError(f"--batch must be >= 1, got {args.batch}")
        if args.knot != "closed":
            raise ValueError("--batch is for closed knots (open knots follow one "
                             "continuation path per case)")
    cases = build_cases(args)
    labels = {c.id: c.label() for c in cases}
    device = resolve_device(args.device)
    workers = args.workers
    if args.executor == "process" and workers is None:
        import os

        workers = min(len(cases), os.cpu_count() or 1)
    done = [0]

    def progress(record: dict[str, Any]) -> None:
        done[0] += 1
        if not args.quiet:
            print(f"[{done[0]}] {_line(record, labels.get(record['id'], ''))}", flush=True)

    # The executor first (a missing Dask is bad input), then the store (checks its folder),
    # both before any case runs.
    executor = make_executor(args.executor, workers, args.scheduler)
    try:
        store = Store.open(args.out)
        if not args.quiet:
            print(f"sweep of {len(cases)} case(s) into {store.folder} ({args.executor})",
                  flush=True)
        report = run_sweep(cases, store, executor, retry_failed=args.retry_failed,
                           on_record=progress, device=device, batch=args.batch)
    except BaseException:
        # Interrupted (Ctrl-C) or broken: the finished cases are stored; do not wait for
        # the running ones (they are run again by the next call).
        executor.shutdown(wait=False, cancel_futures=True)
        raise
    executor.shutdown()
    if not args.quiet and report.skipped:
        print(f"{len(report.skipped)} case(s) already finished in {store.folder} (skipped)")
    records = report.records()
    if out_json is not None:
        write_json_atomic(out_json, {
            "store": str(store.folder), "cases": [short_result(r) for r in records],
            "ran": report.ran, "skipped": report.skipped,
            "failed": report.failed, "wall_time_s": report.wall_time_s})
    for r in records:
        for warning in r.get("warnings", []):
            print(f"tightknot sweep: warning: case {r['id']} ({labels.get(r['id'], '')}): "
                  f"{warning}", file=sys.stderr)
    if report.failed:
        for r in records:
            if r["id"] in report.failed:
                print(f"tightknot sweep: case {r['id']} ({labels[r['id']]}) {r['status']}: "
                      f"{r['failure']}", file=sys.stderr)
        return EXIT_PHYSICS
    return EXIT_OK
