"""``tightknot tie clasp`` and ``tightknot tie bend``: two rods tangled and pulled apart.

Exit codes: 0 converged with the tangle kept, 1 the physics failed (no convergence, the
tangle came apart; the summary, the .rrd and the centerlines of the last equilibrium and
of the failing iterate are written), 2 bad input (one line naming the parameter, the rod
or the pair).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from collections.abc import Sequence

#: The ``tie`` scenes this module handles (``tightknot tie clasp|bend ...``).
TANGLES = ("clasp", "bend")

EXIT_OK, EXIT_PHYSICS, EXIT_BAD_INPUT = 0, 1, 2

_EXAMPLES = """examples:
  tightknot tie clasp                                  # 2 x 100 vertices, pulled to 1 N
  tightknot tie clasp --force 2 --nodes 150 --out runs/clasp
  tightknot tie clasp --end-distance 0.17              # pulled to a 170 mm end distance
  tightknot tie clasp --youngs-modulus-b 2.5e6         # rod B twice as stiff
  tightknot tie bend --kind reef --force 1 --out runs/reef
  tightknot tie bend --kind granny --nodes 150
  tightknot tie bend --kind reef --start-a a.csv --start-b b.csv --units mm   # own curves

outputs (in --out DIR, default runs/<scene>-<UTC time>):
  summary.json         converged, failure, tangle type (linking number, each rod's knot type,
                       the parcel closure's), force_extension, end_reactions, per-rod
                       measurements
  centerline_A.csv     each rod's final centerline x,y,z [m] (tightknot analyze reads it)
  centerline_B.csv
  figures/force_extension.png
  run.rrd              every load step: rods A and B in their own colours, contacts between
                       and within the rods

exit codes: 0 converged, 1 the physics failed (outputs still written), 2 bad input.
"""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # type: ignore[override]
        self.print_usage(sys.stderr)
        print(f"{self.prog}: error: {message}", file=sys.stderr)
        raise SystemExit(EXIT_BAD_INPUT)


def build_parser(scene: str) -> argparse.ArgumentParser:
    """The parser of ``tightknot tie clasp`` or ``tightknot tie bend``."""
    from tightknot.knots import tangles
    from tightknot.knots.tangle_scenes import MIN_NODES

    what = ("two U-shaped rods hooked and pulled apart by their four ends (Grandgeorge et al., "
            "PNAS 2021)" if scene == "clasp" else
            "a bend (reef, granny, thief or grief knot) tied between two rods and pulled by "
            "its four ends (Patil et al., Science 2020)")
    p = _Parser(prog=f"tightknot tie {scene}",
                description=f"Tie {what}; the tangle's type (linking number, each rod's knot "
                "type) is checked at every load step; report the pulling force against the "
                "end-to-end distance.", epilog=_EXAMPLES,
                formatter_class=argparse.RawDescriptionHelpFormatter)
    if scene == "bend":
        p.add_argument("--kind", required=True, choices=list(tangles.BENDS),
                       help="which bend (thief/grief: the reef's/granny's tangle with the "
                       "working ends diagonal)")
    p.add_argument("--nodes", type=int, default=100,
                   help=f"vertices per rod (>= {MIN_NODES}; default 100)")
    p.add_argument("--diameter", type=float, default=None, metavar="M",
                   help="rod A's rest diameter D0 [m] (default the study's 8.5e-3)")
    p.add_argument("--diameter-b", type=float, default=None, metavar="M",
                   help="rod B's rest diameter [m] (default rod A's)")
    for rod, who, e_def, nu_def in (("", "rod A's", "the study's 1.25e6", "the study's 0.5"),
                                    ("-b", "rod B's", "rod A's", "rod A's")):
        p.add_argument(f"--youngs-modulus{rod}", type=float, default=None, metavar="PA",
                       help=f"{who} Young's modulus [Pa] (default {e_def})")
        p.add_argument(f"--poisson{rod}", type=float, default=None, metavar="NU",
                       help=f"{who} Poisson ratio (default {nu_def})")
    load = p.add_mutually_exclusive_group()
    load.add_argument("--force", type=float, default=None, metavar="N",
                      help="pull until this pulling force [N], then hold it as a dead load on "
                      "rod B's ends (default 1 N)")
    load.add_argument("--end-distance", type=float, default=None, metavar="M",
                      help="pull the grips apart to this end-to-end distance [m] instead")
    p.add_argument("--max-end-distance", type=float, default=None, metavar="M",
                   help="a force pull gives up beyond this end distance [m] (default: the "
                   "start's plus the shorter rod's length)")
    p.add_argument("--pull-steps", type=int, default=40,
                   help="initial load steps of the pull (adaptive afterwards; default 40)")
    p.add_argument("--contact", default="compliant", choices=("compliant", "smoothed", "rigid"),
                   help="contact level (default compliant: the FEM-calibrated law)")
    geo = tangles.TangleGeometry()
    for f in dataclasses.fields(geo):
        p.add_argument(f"--{f.name.replace('_', '-')}", type=float, default=None, metavar="D0",
                       help=f"start curve: {f.name.replace('_', ' ')} in rod diameters "
                       f"(default {getattr(geo, f.name):g}; docs/tangles.md)")
    p.add_argument("--start-a", metavar="FILE", default=None,
                   help="rod A's start centerline (csv, tsv or x y z per line, as analyze "
                   "reads; open, U-shaped, both ends pulled one way), with --start-b")
    p.add_argument("--start-b", metavar="FILE", default=None, help="rod B's start centerline")
    p.add_argument("--units", default=None, metavar="UNIT",
                   help="unit of the --start files: m, cm, mm, um or metres per file unit "
                   "(default: the header's, else m)")
    p.add_argument("--device", default=None, help="Warp device (default cpu)")
    p.add_argument("--out", metavar="DIR", help="run folder (default runs/<scene>-<UTC time>)")
    p.add_argument("--json", metavar="FILE", help="write the summary here instead")
    p.add_argument("--figures", metavar="DIR", help="write the figures here instead")
    p.add_argument("--rrd", metavar="FILE", help="write the rerun log here instead")
    p.add_argument("--overwrite", action="store_true",
                   help="replace the outputs of an earlier run in --out")
    p.add_argument("--quiet", action="store_true", help="print nothing but errors")
    return p


def _scene(args: argparse.Namespace, kind: str):
    from tightknot.knots import tangles
    from tightknot.knots.scenes import STUDY_DIAMETER, STUDY_MATERIAL
    from tightknot.knots.tangle_scenes import tangle_scene
    from tightknot.rods.material import Material
    from tightknot.warp_setup import resolve_device

    base = STUDY_MATERIAL
    mats = []
    for rod, e, nu, like in (("A", args.youngs_modulus, args.poisson, base),
                             ("B", args.youngs_modulus_b, args.poisson_b, None)):
        like = like or mats[0]
        try:
            mats.append(Material(e if e is not None else like.youngs_modulus,
                                 nu if nu is not None else like.poisson_ratio, base.density))
        except ValueError as err:
            flags = ("--youngs-modulus-b, --poisson-b" if rod == "B"
                     else "--youngs-modulus, --poisson")
            raise ValueError(f"rod {rod} ({flags}): {err}") from None
    mat_a, mat_b = mats
    geo = tangles.TangleGeometry(**{
        f.name: getattr(args, f.name) for f in dataclasses.fields(tangles.TangleGeometry)
        if getattr(args, f.name) is not None})
    for f in dataclasses.fields(geo):
        v = getattr(geo, f.name)
        if not (v > 0 and v < 1e3):
            raise ValueError(f"--{f.name.replace('_', '-')} must be in (0, 1000) D0, got {v!r}")
    starts = None
    if (args.start_a is None) != (args.start_b is None):
        raise ValueError("--start-a and --start-b go together (one start curve per rod)")
    if args.start_a is not None:
        from tightknot.app.analyze import file_units, read_points

        starts = []
        for path in (args.start_a, args.start_b):
            factor, _ = file_units(path, args.units, None)
            pts, _ = read_points(path, factor, False)
            starts.append(pts)
    elif args.units is not None:
        raise ValueError("--units applies to --start-a/--start-b files only")
    try:
        return tangle_scene(kind, nodes=args.nodes, curves_m=starts,
                            diameter=(args.diameter if args.diameter is not None
                                      else STUDY_DIAMETER),
                            material=mat_a, diameter_b=args.diameter_b, material_b=mat_b,
                            geometry=geo, contact=args.contact,
                            device=resolve_device(args.device))
    except ValueError as err:
        if starts is None:
            raise
        raise ValueError(f"--start-a {args.start_a}, --start-b {args.start_b}: {err}") from None


def run(scene_kind: str, argv: Sequence[str]) -> int:
    """Run ``tightknot tie clasp|bend`` with the arguments after the scene's name."""
    args = build_parser(scene_kind).parse_args(list(argv))
    try:
        return _run(args, scene_kind)
    except ValueError as err:
        print(f"tightknot tie {scene_kind}: error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT


def _run(args: argparse.Namespace, scene_kind: str) -> int:
    from tightknot.app.run_folder import plan_outputs, write_centerline
    from tightknot.atomic import write_json_atomic
    from tightknot.study.tangle_run import draw_tangle_figures, run_tangle
    from tightknot.viz.rerun_log import make_logger

    kind = "clasp" if scene_kind == "clasp" else args.kind
    name = kind if kind == "clasp" else f"{kind}_bend"
    if args.pull_steps < 1:
        raise ValueError(f"--pull-steps must be >= 1, got {args.pull_steps}")
    outs = plan_outputs(name, args.out, args.json, args.rrd, args.figures,
                        overwrite=args.overwrite)
    scene = _scene(args, kind)
    load = ({"end_distance": args.end_distance} if args.end_distance is not None
            else {"force": args.force if args.force is not None else 1.0})
    pull = dict(load, max_end_distance=args.max_end_distance, pull_steps=args.pull_steps)
    # Checked before the run, as the load path would check them.
    for key, v in pull.items():
        if key != "pull_steps" and v is not None and not (v > 0 and v < float("inf")):
            raise ValueError(f"--{key.replace('_', '-')} must be finite and > 0, got {v!r}")
    outs.create()
    config = {"scene": name, "kind": kind, **{k: v for k, v in vars(args).items()
                                                if k not in ("out", "json", "rrd", "figures",
                                                             "overwrite", "quiet")}}
    write_json_atomic(outs.config, config)
    with make_logger(outs.rrd) as log:
        run = run_tangle(scene, log, name, **pull)
    summary = run.summary
    res = run.result
    write_json_atomic(outs.summary, summary)
    for r, info in enumerate(scene.model.rods):
        rod = "AB"[r]
        x = res.system.state.x[info.vertex_slice]
        write_centerline(outs.folder / f"centerline_{rod}.csv", x, f"{name}_rod_{rod}",
                         info.diameter, scene.model.rest_length(r), False)
        if res.failed_state is not None:
            write_centerline(outs.folder / f"failed_centerline_{rod}.csv",
                             res.failed_state.x[info.vertex_slice], f"{name}_rod_{rod}_failed",
                             info.diameter, scene.model.rest_length(r), False)
    figures = draw_tangle_figures(run, outs.figures)
    if not args.quiet:
        tt = summary["tangle_type"]
        print(f"  {'scene':28s} {name}")
        print(f"  {'converged':28s} {summary['converged']}")
        print(f"  {'tangle type':28s} {tt['final']} (kept: {tt['kept']}; candidates "
              f"{', '.join(tt['candidates'])})")
        force = summary["pull_force_N"]
        print(f"  {'pull_force_N':28s} {'none' if force is None else f'{force:.6g}'}")
        print(f"  {'end_to_end_m':28s} {summary['end_to_end_m']:.6g}")
        for e in summary["end_reactions"]:
            f = e["force_N"]
            print(f"  {'reaction ' + e['rod'] + ' ' + e['end'] + ' [N]':28s} "
                  f"({f[0]:.4g}, {f[1]:.4g}, {f[2]:.4g})")
        for rod in summary["rods"]:
            c = rod["contact_with_other_rod"]
            print(f"  {'rod ' + rod['rod']:28s} stretch {rod['stretch']:.4f}, max kappa D0 "
                  f"{rod['max_kappa_D0']:.3g}, contact with the other rod over "
                  f"{c['rest_length_over_D0']:.3g} D0 (max w/D0 {c['max_approach_w_over_D0']:.3g})")
        deep = summary["deepest_contact_between_rods"]
        if deep is not None:
            print(f"  {'deepest contact A-B':28s} w/D0 {deep['w_over_D0']:.3g} at vertices "
                  f"{deep['vertex_A']} (A), {deep['vertex_B']} (B), crossing angle "
                  f"{deep['crossing_angle_deg']:.1f} deg")
        print(f"  {'load_steps':28s} {summary['load_steps']}")
        print(f"  {'newton_iterations':28s} {summary['newton_iterations']}")
        print(f"  {'wall_time_s':28s} {summary['wall_time_s']:.3g}")
        print(f"wrote {outs.summary}, {outs.rrd}, "
              + ", ".join(str(p) for p in figures))
    for warning in summary["warnings"]:
        print(f"tightknot tie {scene_kind}: warning: {warning}", file=sys.stderr)
    if not res.converged:
        print(f"tightknot tie {scene_kind}: failed: {res.failure} (the last equilibrium is in "
              f"{outs.summary} and the centerline_*.csv, the failing iterate in "
              "failed_centerline_*.csv)", file=sys.stderr)
        return EXIT_PHYSICS
    return EXIT_OK
