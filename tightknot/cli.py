"""The ``tightknot`` command line.

Exit codes: 0 success, 1 the physics failed (no convergence, a failed verification,
a topology change) with the reason printed, 2 bad input.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path

from tightknot import __version__

EXIT_OK, EXIT_PHYSICS, EXIT_BAD_INPUT = 0, 1, 2


class _Parser(argparse.ArgumentParser):
    """argparse with exit code 2 and a one-line message on bad arguments."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.print_usage(sys.stderr)
        print(f"{self.prog}: error: {message}", file=sys.stderr)
        raise SystemExit(EXIT_BAD_INPUT)


def _writable_file(path: str | None) -> Path | None:
    """Check before the run that an output file's folder exists (issue: fail early)."""
    if path is None:
        return None
    p = Path(path)
    if not p.parent.exists() and str(p.parent) not in ("", "."):
        raise ValueError(f"output folder does not exist: {p.parent}")
    if p.is_dir():
        raise ValueError(f"output path is a folder, not a file: {p}")
    return p


# -- verify ----------------------------------------------------------------------------------
_VERIFY_EXAMPLES = """examples:
  tightknot verify
  tightknot verify --case euler_buckling --case michell_instability
  tightknot verify --json verify.json
"""


def _cmd_verify(args: argparse.Namespace) -> int:
    from tightknot.atomic import write_json_atomic
    from tightknot.verification import CASES, run_all
    from tightknot.warp_setup import resolve_device

    out = _writable_file(args.json)
    device = resolve_device(args.device)
    unknown = [c for c in (args.case or []) if c not in CASES]
    if unknown:
        raise ValueError(f"unknown --case {unknown}; valid: {', '.join(CASES)}")
    rows = run_all(device, args.case)
    head = (f"{'case':44s} {'reference':>13s} {'computed':>13s} {'rel_error':>10s} "
            f"{'order':>6s}  ok")
    if not args.quiet:
        print(head)
        print("-" * len(head))
        for r in rows:
            order = "" if r.order is None else f"{r.order:.2f}"
            print(f"{r.case:44s} {r.reference:13.6g} {r.computed:13.6g} {r.rel_error:10.2e} "
                  f"{order:>6s}  {'yes' if r.passed else 'NO'}")
    if out is not None:
        write_json_atomic(out, [r.as_dict() for r in rows])
    failed = [r.case for r in rows if not r.passed]
    if failed:
        print(f"verification failed: {', '.join(failed)}", file=sys.stderr)
        return EXIT_PHYSICS
    return EXIT_OK


# -- tie -------------------------------------------------------------------------------------
_TIE_EXAMPLES = """examples:
  tightknot tie closed --json closed.json --figures figs --rrd closed.rrd
  tightknot tie closed --l0-over-d0 18 --nodes 200
  tightknot tie open --length 0.185 --target-lambda 15.0 --json open.json
  tightknot tie open --length 0.125 --target-lambda 10.1 --figures figs
  tightknot tie open --length 0.185 --force 5
"""


def _cmd_tie(args: argparse.Namespace) -> int:
    from tightknot.atomic import write_json_atomic
    from tightknot.knots.run import draw_figures, run_knot
    from tightknot.knots.scenes import closed_trefoil, open_trefoil
    from tightknot.rods.material import Material
    from tightknot.viz.rerun_log import make_logger
    from tightknot.warp_setup import resolve_device

    out = _writable_file(args.json)
    rrd = _writable_file(args.rrd)
    if args.figures is not None and not Path(args.figures).parent.exists():
        raise ValueError(f"--figures parent folder does not exist: {Path(args.figures).parent}")
    device = resolve_device(args.device)
    material = Material(args.youngs_modulus, args.poisson, 1160.0)
    if args.knot == "closed":
        if any(v is not None for v in (args.length, args.force, args.end_distance,
                                       args.target_lambda)):
            raise ValueError("--length/--force/--end-distance/--target-lambda are for open knots")
        scene = closed_trefoil(args.l0_over_d0, args.diameter, args.nodes or 200, material,
                               device=device)
        options: dict = {}
    else:
        given = [v is not None for v in (args.force, args.end_distance, args.target_lambda)]
        if sum(given) != 1:
            raise ValueError("give one of --force F [N], --end-distance X [m] or "
                             "--target-lambda LAMBDA")
        if args.target_lambda is not None and not (0 < args.target_lambda < 1e3):
            raise ValueError(f"--target-lambda must be in (0, 1000), got {args.target_lambda}")
        scene = open_trefoil(args.length if args.length is not None else 0.185, args.diameter,
                             args.nodes or 300, material, device=device)
        options = ({"target_lambda": args.target_lambda} if args.target_lambda is not None
                   else {"pull_force": args.force, "end_distance": args.end_distance})
    with make_logger(rrd) as log:
        run = run_knot(scene, log if rrd is not None else None, args.knot, [0],
                       tighten_steps=40, pull_steps=10, **options)
    summary = run.summary
    if args.figures is not None:
        draw_figures([run], Path(args.figures))
    if out is not None:
        write_json_atomic(out, summary)
    if not args.quiet:
        keys = ("knot_type", "converged", "stretch", "L_over_D", "lambda_oc", "pull_force_N",
                "min_gap_over_D0", "min_area_ratio", "max_contact_width_fraction",
                "max_pressure_over_E", "newton_iterations", "wall_time_s")
        for k in keys:
            if k in summary:
                print(f"  {k:28s} {summary[k]}")
    if not run.result.converged:
        print(f"tightknot tie: failed: {run.result.failure}", file=sys.stderr)
        return EXIT_PHYSICS
    return EXIT_OK


# -- demo ------------------------------------------------------------------------------------
_DEMO_EXAMPLES = """examples:
  tightknot demo                 # writes runs/demo/
  tightknot demo --out /tmp/tk
"""


def _cmd_demo(args: argparse.Namespace) -> int:
    from tightknot.demo import run_demo

    out = Path(args.out)
    summary = run_demo(out, quiet=args.quiet)
    if not args.quiet:
        print(json.dumps(summary, indent=2))
        print(f"wrote {out}/ (summary.json, figures/, demo.rrd)")
    return EXIT_OK if summary.get("passed", False) else EXIT_PHYSICS


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of every subcommand."""
    parser = _Parser(
        prog="tightknot",
        description="Tight physical knots in elastic rods: discrete elastic rods in Warp.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"tightknot {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)

    p = sub.add_parser("verify", help="run the verification cases against closed-form mechanics",
                       description="Run the DER verification cases (cantilevers, buckling, "
                       "rings, Michell, neo-Hookean stretch, implicit Euler) and print a table.",
                       epilog=_VERIFY_EXAMPLES,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--case", action="append", help="run only this case (repeatable)")
    p.add_argument("--json", metavar="FILE", help="write the rows as JSON")
    p.add_argument("--device", default=None, help="Warp device (default cpu)")
    p.add_argument("--quiet", action="store_true", help="print nothing but errors")
    p.set_defaults(handler=_cmd_verify)

    p = sub.add_parser("tie", help="tie and tighten the study's trefoils, measure them",
                       description="Tie a closed trefoil (rest length L0 = l0/d0 D0) or an "
                       "open trefoil (tightened, then pulled by a force or to an end-to-end "
                       "distance) in an elastomer rod, and measure it as the study did.",
                       epilog=_TIE_EXAMPLES,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("knot", choices=["closed", "open"], help="closed or open trefoil")
    p.add_argument("--l0-over-d0", type=float, default=16.37, help="closed: L0/D0 (16.37)")
    p.add_argument("--length", type=float, default=None, help="open: rest length L0 [m]")
    p.add_argument("--force", type=float, default=None, help="open: pulling force [N]")
    p.add_argument("--end-distance", type=float, default=None,
                   help="open: final end-to-end distance [m]")
    p.add_argument("--target-lambda", type=float, default=None,
                   help="open: pull until Lambda_OC reaches this (within 0.1)")
    p.add_argument("--nodes", type=int, default=None, help="vertices (200 closed, 300 open)")
    p.add_argument("--diameter", type=float, default=8.5e-3, help="rest diameter D0 [m]")
    p.add_argument("--youngs-modulus", type=float, default=1.25e6, help="E [Pa]")
    p.add_argument("--poisson", type=float, default=0.5, help="Poisson ratio in (-1, 0.5]")
    p.add_argument("--json", metavar="FILE", help="write the summary as JSON")
    p.add_argument("--figures", metavar="DIR", help="write the study's figures here")
    p.add_argument("--rrd", metavar="FILE", help="write a rerun log of every load step")
    p.add_argument("--device", default=None, help="Warp device (default cpu)")
    p.add_argument("--quiet", action="store_true", help="print nothing but errors")
    p.set_defaults(handler=_cmd_tie)

    p = sub.add_parser("demo", help="run the demo scene: figures, JSON and an .rrd",
                       description="Run the embedded demo and write its outputs to --out.",
                       epilog=_DEMO_EXAMPLES,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", default="runs/demo", help="output folder (created)")
    p.add_argument("--quiet", action="store_true", help="print nothing but errors")
    p.set_defaults(handler=_cmd_demo)

    from tightknot.benchmarks.commands import register as register_bench
    from tightknot.fem.commands import register as register_fem
    from tightknot.knots.commands import register as register_knots

    register_knots(sub)
    register_fem(sub)
    register_bench(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``tightknot`` console script; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if getattr(args, "handler", None) is None:
        parser.print_help()
        return EXIT_BAD_INPUT
    try:
        return int(args.handler(args))
    except ValueError as err:
        print(f"tightknot {args.command}: error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT


if __name__ == "__main__":
    sys.exit(main())
