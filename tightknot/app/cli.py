"""The ``tightknot`` command line.

Exit codes: 0 success, 1 the physics failed (no convergence, a failed verification,
a topology change) with the reason printed, 2 bad input.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import textwrap
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


# -- verify ----------------------------------------------------------------------------------
_VERIFY_EXAMPLES = """examples:
  tightknot verify
  tightknot verify --case euler_buckling --case michell_instability
  tightknot verify --json verify.json
"""


def _cmd_verify(args: argparse.Namespace) -> int:
    from tightknot.atomic import writable_file, write_json_atomic
    from tightknot.verification import CASES, run_all
    from tightknot.warp_setup import resolve_device

    out = writable_file(args.json)
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
  tightknot tie closed                                   # writes runs/closed_trefoil-<time>/
  tightknot tie closed --nodes 100 --out runs/closed100 --color-by area_ratio
  tightknot tie open --length 0.185 --target-lambda 15.0 --out runs/loose
  tightknot tie open --length 0.125 --target-lambda 10.1 --out runs/tight
  tightknot tie open --length 0.185 --force 5 --json open.json
  tightknot tie closed --knot-type 4_1 --out runs/eight  # the figure-eight knot
  tightknot tie closed --knot 5_1                        # any built-in knot (--knot-type)
  tightknot tie clasp --force 1                          # two rods: tightknot tie clasp --help
  tightknot tie bend --kind reef                         # reef, granny, thief, grief
  tightknot tie open --knot 5_2 --force 1
  tightknot tie --start knot.csv --closed --l0-over-d0 24 --units mm   # your own curve
  tightknot tie --start overhand.txt --open --force 1    # its type is detected and kept
  tightknot tie --config runs/tight/config.json --out runs/tight-again   # rerun a run
  tightknot tie --config runs/tight/config.json --nodes 400              # ... with a change

run folder (--out DIR, default runs/<scene>-<UTC time>):
  config.json     the exact parameters; tightknot tie --config FILE reruns them (JSON or TOML)
  summary.json    converged, failure, knot type, measurements, final centerline_m [m]
  centerline.csv  final centerline x,y,z [m]; its header says how to tightknot analyze it
  figures/        the study's figures and the tube coloured by curvature (tube_kappa_D0.png)
  run.rrd         rerun log of every load step: tightknot view DIR/run.rrd
--json/--rrd/--figures send one output elsewhere.
{keys}
Exit codes: 0 converged, 1 the physics failed (summary and .rrd are still written), 2 bad input.
"""

def tie_config(args: argparse.Namespace):
    """The run's :class:`tightknot.app.config.TieConfig`: ``--config FILE`` (if given), then the
    knot and every flag given on the command line on top (a load flag replaces the file's
    load). Every config key but the knot is a flag of the same name (``--name-with-dashes``)."""
    from tightknot.app.config import config_from_dict, config_keys, knot_specific, load_config
    from tightknot.loading.options import LOADS

    data: dict = load_config(args.config).to_dict() if args.config is not None else {}
    flag = getattr(args, "knot_flag", None)  # --closed / --open (with --start)
    if flag is not None and args.knot is not None and flag != args.knot:
        raise ValueError(f"--{flag} contradicts the knot {args.knot}")
    knot = args.knot or flag or data.get("knot")
    if knot is None:
        raise ValueError("give the knot (closed or open) or --config FILE")
    if "knot" in data:
        old = (data["knot"], data["knot_type"])
        new = (knot, args.knot_type or old[1])
        if new != old:
            # Another knot: the file's values for its own knot do not carry over.
            drop = knot_specific(old, new)
            data = {k: v for k, v in data.items() if k not in drop}
    data["knot"] = knot
    flags = {k: getattr(args, k) for k in config_keys()
             if k != "knot" and getattr(args, k) is not None}
    if any(k in flags for k in LOADS):
        data = {k: v for k, v in data.items() if k not in LOADS}
    data.update(flags)
    return config_from_dict(data)


def _cmd_tie(args: argparse.Namespace) -> int:
    from tightknot.app.progress import Progress, phase_progress
    from tightknot.app.run_folder import plan_outputs, write_centerline
    from tightknot.atomic import write_json_atomic
    from tightknot.knots.ideal import has_ideal, load_ideal
    from tightknot.study.params import build_scene
    from tightknot.study.run import draw_figures, run_knot
    from tightknot.viz.rerun_log import make_logger
    from tightknot.warp_setup import resolve_device

    cfg = tie_config(args)
    # Every output path is checked before any work (issue 6: fail early, not after minutes).
    outs = plan_outputs(cfg.scene_name, args.out, args.json, args.rrd, args.figures,
                        overwrite=args.overwrite)
    # The device actually used goes into config.json (None would mean "cpu" here but
    # perhaps not in a later version): the file records what ran.
    cfg = dataclasses.replace(cfg, device=resolve_device(cfg.device))
    scene = build_scene(cfg.to_dict(), cfg.device)
    outs.create()
    # The parameters first: a run killed half-way can still be repeated.
    write_json_atomic(outs.config, cfg.to_dict())
    bar = Progress(scene.name, enabled=False if args.quiet else None)
    with make_logger(outs.rrd) as log:
        if scene.closed and has_ideal(scene.knot_type):
            ideal = load_ideal(scene.knot_type, scene.diameter)
            # Beside the rod (6 D0 below), so that both stay visible.
            log.log_reference("ideal_trefoil" if scene.knot_type == "3_1"
                              else f"ideal_{scene.knot_type}",
                              ideal - ideal.mean(axis=0) + [0.0, 0.0, -6 * scene.diameter],
                              scene.diameter / 2)
        with bar:
            bar.update(0.0, "relaxing the start curve")
            run = run_knot(scene, log, cfg.knot, [0], color_by=cfg.color_by,
                           progress=phase_progress(bar, scene.closed), **cfg.tie_options())
    summary = run.summary
    x = run.result.system.state.x
    write_json_atomic(outs.summary, summary)
    write_centerline(outs.centerline, x, scene.name, scene.diameter, scene.rest_length,
                     scene.closed)
    figures = draw_figures([run], outs.figures, tube=cfg.color_by)
    if not args.quiet:
        keys = ("knot_type", "converged", "load_steps", "stretch", "L_over_D", "lambda_oc",
                "pull_force_N", "min_gap_over_D0", "min_area_ratio",
                "max_contact_width_fraction", "max_pressure_over_E", "max_approach_w_over_D0",
                "calibrated_w_over_D0", "contact_weight_sum_mean", "section_path",
                "newton_iterations", "wall_time_s")
        for k in keys:
            if summary.get(k) is not None:
                print(f"  {k:28s} {summary[k]}")
        print(written_outputs(outs, figures))
        print(f"look at it: tightknot view {outs.rrd}")
    coarse = (summary.get("resolution") or {}).get("warning")
    for warning in [*summary.get("warnings", []), *([coarse] if coarse else [])]:
        print(f"tightknot tie: warning: {warning}", file=sys.stderr)
    if not run.result.converged:
        print(f"tightknot tie: failed: {run.result.failure} (after {summary['load_steps']} "
              f"converged load steps; the final state is the last step of {outs.rrd})",
              file=sys.stderr)
        return EXIT_PHYSICS
    return EXIT_OK


def written_outputs(outs, figures: list[Path]) -> str:
    """What a tie wrote: the run folder's files by name (figures under their folder), and
    any output sent elsewhere by its path."""
    inside, outside = [], []
    for path in (outs.config, outs.summary, outs.centerline, outs.rrd):
        (inside if path.parent == outs.folder else outside).append(path)
    figs = ", ".join(p.name for p in figures)
    lines = [f"wrote {outs.folder}/ ({', '.join(p.name for p in inside)}"
             + (f", {outs.figures.name}/: {figs})" if outs.figures.parent == outs.folder
                else ")")]
    lines += [f"wrote {p}" for p in outside]
    if outs.figures.parent != outs.folder:
        lines.append(f"wrote {outs.figures}/ ({figs})")
    return "\n".join(lines)


# -- view ------------------------------------------------------------------------------------
_VIEW_EXAMPLES = """examples:
  tightknot view runs/demo/demo.rrd
  tightknot view runs/closed_trefoil-20261123-160000/run.rrd
  tightknot view run.rrd --print-only      # just print the command that opens it

The viewer is the 'rerun' executable of rerun-sdk (a dependency of tightknot). Without a
display (no DISPLAY or WAYLAND_DISPLAY on Linux) the command to run elsewhere is printed;
'rerun --web-viewer FILE' serves the viewer to a browser instead.
"""

#: The first bytes of a rerun recording file (rerun's RRF2 encoding).
RRD_MAGIC = b"RRF2"


def find_viewer() -> str | None:
    """Path of the ``rerun`` viewer executable: the one installed beside this Python
    (rerun-sdk's console script), else the first on PATH; None when there is none."""
    import os
    import shutil

    beside = Path(sys.executable).with_name("rerun")
    if beside.is_file() and os.access(beside, os.X_OK):
        return str(beside)
    return shutil.which("rerun")


def _has_display() -> bool:
    import os

    if sys.platform in ("darwin", "win32"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def _cmd_view(args: argparse.Namespace) -> int:
    import shlex
    import subprocess

    path = Path(args.file)
    if not path.is_file():
        raise ValueError(f"{path}: no such file" if not path.exists() else
                         f"{path}: not a file")
    try:
        with path.open("rb") as handle:
            magic = handle.read(len(RRD_MAGIC))
    except OSError as exc:
        raise ValueError(f"{path}: cannot read ({exc.strerror})") from None
    if magic != RRD_MAGIC:
        raise ValueError(f"{path}: not a rerun recording (.rrd files start with "
                         f"{RRD_MAGIC.decode()})")
    viewer = find_viewer()
    command = f"{shlex.quote(viewer or 'rerun')} {shlex.quote(str(path))}"
    if args.print_only or viewer is None or not _has_display():
        if not args.print_only:
            why = ("no 'rerun' executable found (pip install 'rerun-sdk>=0.41,<0.42')"
                   if viewer is None else "no display here")
            print(f"tightknot view: {why}; open the recording with:")
        print(command)
        return EXIT_OK
    rc = subprocess.call([viewer, str(path)])
    if rc != 0:
        print(f"tightknot view: the viewer exited with code {rc}: {command}", file=sys.stderr)
        return EXIT_PHYSICS
    return EXIT_OK


# -- demo ------------------------------------------------------------------------------------
_DEMO_EXAMPLES = """examples:
  tightknot demo                 # writes runs/demo/
  tightknot demo --out /tmp/tk
  tightknot demo --overwrite     # run again into runs/demo/

"passed" in summary.json: every knot's load path converged (each load step's Newton solve
met its tolerance, the knot type never changed, an open knot reached its target Lambda_OC
within its tolerance). It says nothing about the accuracy of the coarse meshes: each knot's
"resolution" entry gives the expected error of its vertex count (README, speed vs accuracy).
"""


def _cmd_demo(args: argparse.Namespace) -> int:
    from tightknot.app.demo import run_demo

    # Checked before the run: a folder under runs/ (the default runs/demo) is made with its
    # parents, any other only under an existing parent (a missing parent is likely a typo).
    from tightknot.app.run_folder import check_output_dir, in_runs_tree, refuse_existing

    out = Path(args.out)
    check_output_dir(out, "--out", parents=in_runs_tree(out))
    if not args.overwrite:
        refuse_existing([out / "summary.json", out / "demo.rrd", out / "figures"],
                        "--overwrite")
    summary = run_demo(out, quiet=args.quiet)
    if not args.quiet:
        print(json.dumps(summary, indent=2))
        figures = ", ".join(sorted(p.name for p in (out / "figures").glob("*.png")))
        print(f"wrote {out}/ (summary.json, demo.rrd, figures/: {figures})")
    return EXIT_OK if summary.get("passed", False) else EXIT_PHYSICS


_TOP_EXAMPLES = """examples:
  tightknot demo                          # the study's three knots into runs/demo/
  tightknot tie closed --out runs/closed  # one knot, one run folder
  tightknot view runs/closed/run.rrd      # look at every load step
  tightknot COMMAND --help                # each command's options and examples

exit codes: 0 success, 1 the physics failed (reason printed), 2 bad input.
"""


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of every subcommand."""
    parser = _Parser(
        prog="tightknot",
        description="Tight physical knots in elastic rods: discrete elastic rods in Warp.",
        epilog=_TOP_EXAMPLES,
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

    from tightknot.app.config import TieConfig, config_keys
    from tightknot.loading.options import flag_kwargs, flags, parameters

    p = sub.add_parser("tie", help="tie and tighten the study's knots, measure them",
                       description="Tie a closed knot (rest length L0 = l0/d0 D0) or an "
                       "open knot (tightened, then pulled by a force, to an end-to-end "
                       "distance or to a target Lambda_OC) in an elastomer rod, measure it as "
                       "the study did, and write everything into one run folder. An open knot "
                       "takes exactly one load: --force, --end-distance or --target-lambda. "
                       "Each option but --config and the outputs is a config key of the same "
                       "name.",
                       epilog=_TIE_EXAMPLES.format(keys=textwrap.fill(
                           "config keys: " + ", ".join(config_keys()) + ".", 90)),
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    params = parameters(TieConfig)
    p.add_argument("knot", nargs="?", choices=params["knot"].valid,
                   help=f"{params['knot'].what} (optional with --config)")
    p.add_argument("--config", metavar="FILE",
                   help="parameters from a run folder's config.json (or TOML); flags override")
    for name, par in params.items():
        if name != "knot":
            p.add_argument(*flags(par), **flag_kwargs(par))
    closed_open = p.add_mutually_exclusive_group()
    for kind in ("closed", "open"):
        closed_open.add_argument(f"--{kind}", dest="knot_flag", action="store_const",
                                 const=kind, help=f"the knot is {kind} (as the positional "
                                 f"{kind}; reads well with --start)")
    p.add_argument("--out", metavar="DIR", help="run folder (default runs/<scene>-<UTC time>; "
                   "made with its parents under runs/, elsewhere its parent must exist)")
    p.add_argument("--json", metavar="FILE", help="write the summary here instead")
    p.add_argument("--figures", metavar="DIR", help="write the figures here instead")
    p.add_argument("--rrd", metavar="FILE", help="write the rerun log here instead")
    p.add_argument("--overwrite", action="store_true",
                   help="replace the outputs of an earlier run in --out (refused without it)")
    p.add_argument("--quiet", action="store_true", help="print nothing but errors")
    p.set_defaults(handler=_cmd_tie)

    p = sub.add_parser("demo", help="run the demo scene: figures, JSON and an .rrd",
                       description="Run the embedded demo and write its outputs to --out.",
                       epilog=_DEMO_EXAMPLES,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", default="runs/demo", metavar="DIR",
                   help="output folder (default runs/demo; created)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace the outputs of an earlier demo in --out (refused without it)")
    p.add_argument("--quiet", action="store_true", help="print nothing but errors")
    p.set_defaults(handler=_cmd_demo)

    p = sub.add_parser("view", help="open a .rrd in the rerun viewer (or print how)",
                       description="Open a rerun recording written by tie or demo in the rerun "
                       "viewer; without a viewer or a display, print the command that opens it.",
                       epilog=_VIEW_EXAMPLES,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("file", metavar="FILE.rrd", help="the recording")
    p.add_argument("--print-only", action="store_true",
                   help="print the viewer command instead of running it")
    p.set_defaults(handler=_cmd_view)

    from tightknot.app.analyze import register as register_knots
    from tightknot.benchmarks.commands import register as register_bench
    from tightknot.fem.commands import register as register_fem
    from tightknot.sweep.commands import register as register_sweep

    register_knots(sub)
    register_fem(sub, draw_profiles=_draw_profiles)
    register_bench(sub)
    register_sweep(sub)
    from tightknot.app.sweep_outputs import register as register_sweep_outputs

    register_sweep_outputs(sub)
    return parser


def _draw_profiles(path: str, level: str, soft: dict | None, rigid: dict | None
                   ) -> list[str]:
    """``tightknot fem crosscheck --figure``: the scenes' profiles side by side
    (:func:`tightknot.viz.profile_figures.plot_profiles`, imported when drawn: it loads
    matplotlib)."""
    from tightknot.viz.profile_figures import plot_profiles

    return plot_profiles(path, level, soft=soft, rigid=rigid)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``tightknot`` console script; returns the exit code."""
    from tightknot.app import tangle_cli

    words = list(sys.argv[1:] if argv is None else argv)
    if words[:1] == ["tie"] and words[1:2] and words[1] in tangle_cli.TANGLES:
        return tangle_cli.run(words[1], words[2:])  # two rods: tightknot tie clasp|bend
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
