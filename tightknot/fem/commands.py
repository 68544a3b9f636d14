"""Command-line subcommands of the FEM part: ``fem SCENE`` and ``calibrate``.

The CLI owner calls :func:`register` from ``tightknot/app/cli.py``; each parser gets a
``handler`` default (``args.handler(args) -> int``): 0 ok, 2 bad input or FElupe missing
(one line on stderr, with the install hint when FElupe is missing).
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ._backend import FelupeMissingError

_FEM_EXAMPLES = """examples:
  tightknot fem squeeze                         # plane strain, coarse mesh, 3 meshes table
  tightknot fem squeeze --mesh medium --json out/squeeze.json
  tightknot fem squeeze --model 3d --ends free  # 3D segment with free ends
  tightknot fem indent --mesh coarse --no-convergence
  tightknot fem wrap --tension 0.25 --wrap-angle 90 --no-convergence
  tightknot fem crosscheck --json out/crosscheck.json   # FEM (medium) versus rod model
  tightknot fem soft_squeeze --mesh medium      # two soft rods pressed together (barrier)
  tightknot fem soft_crossing --json out/x.json # two soft rods crossing at 90 degrees
  tightknot fem soft_wrap --tension 0.25        # a soft rod pulled around a soft rod
  tightknot fem clasp --pull 1.0 --json out/clasp.json  # two U's hooked, pulled apart
"""

_CAL_EXAMPLES = """examples:
  tightknot calibrate                           # medium meshes, writes the shipped law
  tightknot calibrate --mesh coarse --out /tmp/contact_law.json
"""


def register(subparsers: Any, draw_profiles: Callable[..., Any] | None = None) -> None:
    """Add the ``fem`` and ``calibrate`` subcommands to an argparse ``subparsers``;
    ``draw_profiles(path, level, soft_scenes, scenes)`` draws ``crosscheck --figure``
    from the report's soft and rigid scenes (the command line passes
    :func:`tightknot.viz.profile_figures.plot_profiles`: pictures are a layer above the
    FEM's)."""
    fem = subparsers.add_parser(
        "fem", help="run a small 3D solid FEM scene (needs tightknot[fem])",
        description="Run a FEM contact scene of a nearly incompressible neo-Hookean rod "
                    "(E = 1.25 MPa, D0 = 8.5 mm) and print or save its JSON result.",
        epilog=_FEM_EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    fem.add_argument("scene", help="squeeze | indent | wrap | soft_squeeze | soft_crossing | "
                                   "soft_wrap | clasp, or crosscheck (the FEM scenes with "
                                   "the rod model, compared)")
    fem.add_argument("--mesh", default=None,
                     help="coarse | medium | fine (default: coarse for a scene, medium for "
                          "crosscheck: the mesh the shipped law was calibrated on)")
    fem.add_argument("--approach", type=float, default=None,
                     help="squeeze, indent, soft_squeeze, soft_crossing: total approach "
                          "over D0, in (0, 1) (default 0.3)")
    fem.add_argument("--tension", type=float, default=None,
                     help="wrap, soft_wrap: largest end tension over E D0^2, in (0, 0.5] "
                          "(default 0.25)")
    fem.add_argument("--wrap-angle", type=float, default=None,
                     help="wrap, soft_wrap: angle between the two tails [deg] (default 90)")
    fem.add_argument("--pull", type=float, default=None,
                     help="clasp only: largest change of the clamps' separation over D0, "
                          "in (0, 2] (default 1.0)")
    fem.add_argument("--bend-radius", type=float, default=None,
                     help="clasp only: the U's centreline bend radius over D0, in [1.25, 4] "
                          "(default 1.5)")
    fem.add_argument("--leg-length", type=float, default=None,
                     help="clasp only: each leg's straight length over D0, in [1, 10] "
                          "(default 1.5)")
    fem.add_argument("--steps", type=int, default=None, help="number of load steps")
    fem.add_argument("--model", default=None, help="squeeze only: plane_strain | 3d")
    fem.add_argument("--ends", default=None, help="squeeze 3d only: plane | free")
    fem.add_argument("--no-convergence", action="store_true",
                     help="skip the three-mesh convergence table")
    fem.add_argument("--convergence", action="store_true",
                     help="soft_* and clasp: add the three-mesh table (off by default: the "
                          "fine meshes take from minutes to hours)")
    fem.add_argument("--no-compare", action="store_true",
                     help="soft_* only: skip the rigid counterpart (squeeze, indent or wrap)")
    fem.add_argument("--no-soft", action="store_true",
                     help="crosscheck only: leave out the two-soft-rod scenes (soft_wrap, "
                          "clasp, soft_crossing; on the medium mesh they take most of the "
                          "time)")
    fem.add_argument("--json", default=None, metavar="FILE",
                     help="write the result to FILE (atomically) instead of stdout")
    fem.add_argument("--contact", default="compliant", choices=("compliant", "sectioned"),
                     help="crosscheck only: the rod model's contact level (default compliant)")
    fem.add_argument("--section-modes", type=int, default=8, metavar="N",
                     help="crosscheck --contact sectioned: the sections' highest Fourier mode "
                          "N, in [4, 12] (default 8)")
    fem.add_argument("--section-bend-shift", action="store_true",
                     help="crosscheck --contact sectioned: centre the sections on the tight "
                          "bend's offset centreline (Saint-Venant's anticlastic shift; "
                          "docs/sectioned_level.md)")
    fem.add_argument("--section-thinning", default="edge", choices=["edge", "rod"],
                     help="crosscheck --contact sectioned: the stretch that thins the "
                          "sections, each edge's own (default) or the rod's mean "
                          "(docs/sectioned_level.md, 'Resolution')")
    fem.add_argument("--rod-edges-per-d0", type=int, default=None, metavar="N",
                     help="crosscheck --contact sectioned: edges per D0 of the rod scenes, "
                          "the rigid and the two-soft-rod ones (default 12; the 0.012 D0 "
                          "indent needs 24 or more, docs/sectioned_level.md, 'Resolution')")
    fem.add_argument("--fem-json", default=None, nargs="+", metavar="FILE",
                     help="crosscheck only: reuse FEM results instead of running them: "
                          "earlier crosscheck reports (their fem_results) or scene results "
                          "(tightknot fem SCENE --json), the first file holding a scene "
                          "and mesh winning; a scene on the next finer mesh is compared "
                          "too (the FEM's third mesh, reported)")
    fem.add_argument("--figure", default=None, metavar="PNG",
                     help="crosscheck only: draw the scenes' profiles along the contact "
                          "(L_c, A/A0, p/E; FEM and rod model side by side) to this PNG: "
                          "the two-soft-rod scenes, and with --contact sectioned the "
                          "indent and the wrap too (with --no-soft only those)")
    fem.set_defaults(handler=_run_fem, draw_profiles=draw_profiles)

    cal = subparsers.add_parser(
        "calibrate", help="calibrate the radial-compliance contact law from the FEM",
        description="Run squeeze (plane strain, 3D plane and free ends) and indent, fit "
                    "the per-side power laws and write contact_law.json.",
        epilog=_CAL_EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    cal.add_argument("--mesh", default="medium", help="coarse | medium | fine")
    cal.add_argument("--out", default=None, metavar="PATH",
                     help="output JSON (default: the package's data/contact_law.json)")
    cal.add_argument("--core", action="store_true",
                     help="only fit the hard core to deep plane-strain squeezes and add it to "
                          "the law file (the power laws are kept)")
    cal.set_defaults(handler=_run_calibrate)


def _fail(message: str) -> int:
    print(f"tightknot: {message}", file=sys.stderr)
    return 2


def _check_out(path: str | None) -> str | None:
    if path is not None and not Path(path).resolve().parent.is_dir():
        return f"output folder does not exist: {Path(path).parent}"
    return None


def _run_fem(args: argparse.Namespace) -> int:
    from . import run_scene
    from .barrier_solver import BarrierNewtonFailure
    from .scenes._common import finite
    from .solver import NewtonFailure

    problem = _check_out(args.json)
    if problem:
        return _fail(problem)
    if args.scene == "crosscheck":
        return _run_crosscheck(args)
    if args.figure is not None:
        return _fail(f"--figure draws a crosscheck's profiles; scene {args.scene!r} has none")
    from . import SOFT_SCENES

    if args.scene in SOFT_SCENES:
        options: dict[str, Any] = {"convergence": args.convergence and not args.no_convergence}
        if args.scene != "clasp":  # the clasp has no rigid counterpart
            options["compare"] = not args.no_compare
    else:
        options = {"convergence": not args.no_convergence}
    if args.tension is not None:
        options["max_tension_over_e_d0sq"] = args.tension
    if args.wrap_angle is not None:
        options["wrap_angle_deg"] = args.wrap_angle
    for flag, key in ((args.pull, "max_pull_over_d0"),
                      (args.bend_radius, "bend_radius_over_d0"),
                      (args.leg_length, "leg_length_over_d0")):
        if flag is not None:
            options[key] = flag
    if args.model is not None:
        options["model"] = args.model
    if args.ends is not None:
        options["ends"] = args.ends
    try:
        result = run_scene(args.scene, mesh=args.mesh or "coarse",
                           max_approach_over_d0=args.approach,
                           steps=args.steps, **options)
    except (ValueError, FelupeMissingError) as err:
        return _fail(str(err))
    except (NewtonFailure, BarrierNewtonFailure) as err:
        # the physics failed, not the input: one line and exit 1 (ground rule 6)
        print(f"tightknot fem {args.scene}: the solve failed: {err}", file=sys.stderr)
        return 1
    if args.json is None:
        print(json.dumps(finite(result), indent=2, allow_nan=False))
    else:
        from tightknot.atomic import write_json_atomic

        write_json_atomic(args.json, result)
    return 0


def _run_crosscheck(args: argparse.Namespace) -> int:
    """``fem crosscheck``: exit 0 when every target is met, 1 when one is missed (the
    report is written either way), 2 for bad input or a missing FElupe."""
    from .scenes._common import finite

    problem = _check_out(args.json) or _check_out(args.figure)
    if problem:
        return _fail(problem)
    if args.figure is not None and args.no_soft and args.contact != "sectioned":
        return _fail("--figure with --no-soft draws the indent's and the wrap's profiles, "
                     "which only --contact sectioned reports")
    if args.figure is not None and not args.figure.endswith(".png"):
        return _fail(f"--figure must name a .png file, got {args.figure!r}")
    if args.figure is not None and args.draw_profiles is None:
        return _fail("--figure: this command line has no figures (tightknot[fem] without "
                     "its drawing)")
    try:
        from .crosscheck import DEFAULT_MESH, crosscheck
        from .crosscheck_soft import merge_fem_results

        fem_results = None
        mesh = args.mesh or DEFAULT_MESH
        if args.fem_json is not None:
            files = []
            for name in args.fem_json:
                try:
                    files.append((name, json.loads(Path(name).read_text())))
                except (OSError, ValueError) as err:
                    return _fail(f"--fem-json {name}: not readable JSON ({err})")
            fem_results = merge_fem_results(files, mesh)
        report = crosscheck(mesh=mesh, fem_results=fem_results,
                            contact=args.contact, section_modes=args.section_modes,
                            soft=not args.no_soft, bend_shift=args.section_bend_shift,
                            thinning=args.section_thinning,
                            **({} if args.rod_edges_per_d0 is None
                               else {"rod_edges_per_d0": args.rod_edges_per_d0}))
    except (ValueError, FelupeMissingError) as err:
        return _fail(str(err))
    if args.json is None:
        print(json.dumps(finite(report), indent=2, allow_nan=False))
    else:
        from tightknot.atomic import write_json_atomic

        write_json_atomic(args.json, report)
    if args.figure is not None:
        args.draw_profiles(args.figure, report["contact"], report.get("soft_scenes"),
                           report["scenes"])
    summary = {name: scene["comparison"]["worst"] for name, scene in report["scenes"].items()}
    line = {"contact": report["contact"], "passed": report["passed"],
            "fem_over_rod_time_ratio": report["fem_over_rod_time_ratio"], "worst": summary}
    sm = report.get("smoothed_contact_level")
    if sm is not None:
        line["smoothed_contact_level"] = {
            "passed": sm["passed"],
            "worst": {k: v["comparison"]["worst"] for k, v in sm["scenes"].items()}}
    if "soft_scenes" in report:
        line["soft_scenes"] = {
            level: {k: v["comparison"]["worst"] for k, v in entry["scenes"].items()}
            for level, entry in report["soft_scenes"]["levels"].items()}
    print(json.dumps(line), file=sys.stderr)
    return 0 if report["passed"] else 1


def _run_calibrate(args: argparse.Namespace) -> int:
    problem = _check_out(args.out)
    if problem:
        return _fail(problem)
    try:
        from .calibration import LAW_PATH, write_core, write_law

        if args.core:
            core = write_core(args.out or LAW_PATH, mesh=args.mesh)
            print(json.dumps({k: v for k, v in core.items() if k != "core_fit"} |
                             {"max_rel_error": core["core_fit"]["max_rel_error"]}, indent=2))
            return 0
        law = write_law(args.out or LAW_PATH, mesh=args.mesh)
    except (ValueError, FelupeMissingError) as err:
        return _fail(str(err))
    print(json.dumps({k: law[k] for k in law if k.startswith(("k_", "p_", "c_"))}, indent=2))
    return 0
