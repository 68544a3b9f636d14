"""How thin a section the FEM confirms at the sectioned level: the rigid wrap pulled to
``AREA_RANGE_TENSION`` E D0^2 (:func:`tightknot.fem.section_calibration.area_range`).

Runs the FEM wrap (or reads a saved one), the sectioned rod model at its tensions, and
prints each level against the cross-check's targets; the levels past the approach limit
are printed too, marked, and not judged. ``--write`` stores the record and its judged
area in the shipped calibration (``tightknot/data/section_calibration.json``), which the
knots' summaries compare their thinnest section with.

Usage: ``python bench/section_area_range.py [--mesh medium] [--fem-json F]
[--spread-json G ...] [--json out.json] [--write]``. ``--fem-json``: a saved
``tightknot fem wrap --tension 0.5 --steps 8 --no-convergence --json F`` result;
``--spread-json``: the same wrap on other meshes (a run may stop early), for the FEM's
own spread at the judged level.
"""

from __future__ import annotations

import argparse
import json

from tightknot.atomic import write_json_atomic
from tightknot.fem.crosscheck_targets import APPROACH_LIMIT
from tightknot.fem.scenes import wrap
from tightknot.fem.section_calibration import (
    AREA_RANGE_STEPS,
    AREA_RANGE_TENSION,
    area_range,
    write_area_range,
)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mesh", default="medium")
    parser.add_argument("--fem-json", help="a saved FEM wrap result at these tensions")
    parser.add_argument("--spread-json", nargs="*", default=[],
                        help="the same wrap on other meshes")
    parser.add_argument("--json", help="write the record here")
    parser.add_argument("--write", action="store_true",
                        help="store it in the shipped section calibration")
    args = parser.parse_args()
    if args.fem_json:
        with open(args.fem_json) as f:
            fem = json.load(f)
    else:
        fem = wrap.run(mesh=args.mesh, max_tension_over_e_d0sq=AREA_RANGE_TENSION,
                       steps=AREA_RANGE_STEPS, convergence=False)
    spread = {}
    for path in args.spread_json:
        with open(path) as f:
            other = json.load(f)
        spread[other["mesh"]["level"]] = other
    rec = area_range(fem, spread=spread)
    print("T/(E D0^2)  approach  force    A/A0 FEM  rod   points  L_c FEM  rod   kappa   met")
    past = f"(past {APPROACH_LIMIT} D0: not judged)"
    rows = ([(row, "yes" if all(row["met"].values()) else "no") for row in rec["levels"]]
            + [(row, past) for row in rec["past_approach_limit"]])
    for t, (row, judged) in zip(rec["tension_over_e_d0sq"], rows, strict=True):
        print(f"{t:9.4f}  {row['approach_over_d0']:7.3f}  {row['force_rel']:+6.1%}  "
              f"{row['fem_area_ratio']:8.4f} {row['rod_area_ratio']:6.4f} "
              f"{100 * row['area_points']:+5.1f}   {row['fem_width_fraction']:6.3f} "
              f"{row['rod_width_fraction']:5.3f} {row['curvature_rel']:+6.1%}  {judged}")
    print(f"judged down to A/A0 {rec['judged_area_ratio']} at T = "
          f"{rec['judged_tension_over_e_d0sq']} E D0^2; FEM spread there: "
          f"{rec['mesh_spread_at_judged_level']}; FEM {rec['fem_wall_time_s']:.1f} s, "
          f"rod {rec['rod_wall_time_s']:.2f} s")
    if args.json:
        write_json_atomic(args.json, rec)
    if args.write:
        print("wrote", write_area_range(rec))


if __name__ == "__main__":
    main()
