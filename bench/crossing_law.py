"""The compliant level's point law recalibrated on two soft rods crossing, and what the other
two-soft-rod scenes say of it (issue 18: "recalibrate from two-soft-rod scenes if it holds").

    tightknot fem soft_crossing --mesh medium --steps 10 --no-compare --no-convergence --json X
    python bench/crossing_law.py --fem-json R --fit X --spread C F --out J

The shipped point law (k_point, p_point, its patch and peak pressure) is fitted to a rod
between two RIGID crossing cylinders (``indent``); the knots' pairs split an overlap delta
evenly (w = delta / 2 per rod) and take that law per rod. Two soft rods crossing (the FEM's
``soft_crossing``, the same rod mesh and w) carry about 1.5 to 1.8 times the indent's force.
This bench fits the point law to the soft crossing (``--fit``: a scene result; default the
soft crossing of the report ``--fem-json``; ``--spread``: the same scene on other meshes,
fitted alike, for the fit's own mesh spread), then runs the rod model's three soft rows
(:func:`tightknot.fem.crosscheck_soft.rod_runs`: the soft crossing, the soft wrap, the clasp
with and without the kinematics matched) at each level of ``--levels`` with the shipped law
and with the refitted one, against the report's FEM (``--fem-json``: a cross-check report
holding the three scenes, e.g. ``tightknot fem crosscheck --json R``). The soft crossing is
the refit's own scene (a check of the kernels' realisation of the law, not of the law); the
soft wrap and the clasp judge it.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np


def _errors(comparison: dict[str, Any]) -> dict[str, list[float | None]]:
    rows = comparison["levels"]
    return {
        "load": [r["load"] for r in rows],
        "force_rel": [r["force_rel"] for r in rows],
        "area_points": [r["area_points"] for r in rows],
        "curvature_rel": [r["curvature_rel"] for r in rows],
        "force_rel_kinematics_matched": [r.get("force_rel_kinematics_matched") for r in rows],
        "fem_spread_force": [r["fem_spread_rel"]["force"] if r["fem_spread_rel"] else None
                             for r in rows],
    }


def run(report: dict[str, Any], fit_result: dict[str, Any],
        spread_results: list[dict[str, Any]], levels: list[str]) -> dict[str, Any]:
    """The fits and the rows (module docstring)."""
    from tightknot.contact.law import RadialComplianceLaw
    from tightknot.fem.calibration import soft_crossing_point_law, with_point_law
    from tightknot.fem.crosscheck_soft import ROW_SCENES, compare, rod_runs, spread_mesh

    fem = report["fem_results"]
    missing = [name for name in ROW_SCENES if name not in fem]
    if missing:
        raise ValueError(f"--fem-json: the report holds no FEM result of {missing}")
    shipped = RadialComplianceLaw.from_json()
    fit = soft_crossing_point_law(fit_result)
    fits = [fit] + [soft_crossing_point_law(r) for r in spread_results]
    refit = with_point_law(shipped, fit, f"the soft crossing ({fit['mesh']} mesh)")
    w = np.array([0.003, 0.01, 0.0375, 0.15])
    ratio = (refit.k_point * w**refit.p_point) / (shipped.k_point * w**shipped.p_point)
    spread = spread_mesh(report.get("mesh", "medium"))
    out: dict[str, Any] = {
        "fits": fits,  # the refit's first, then the spread files' in their order
        "shipped": {"k_point": shipped.k_point, "p_point": shipped.p_point,
                    "k_patch": shipped.k_patch, "p_patch": shipped.p_patch,
                    "k_pmax_point": shipped.k_pmax_point,
                    "p_pmax_point": shipped.p_pmax_point},
        "force_ratio_refit_over_shipped": dict(zip(map(str, w), ratio.tolist(), strict=True)),
        "rows": {},
    }
    for level in levels:
        for name, law in (("shipped", None), ("soft_crossing", refit)):
            start = time.perf_counter()
            rod = rod_runs(fem, level, law=law)
            rows = {}
            for scene in ROW_SCENES:
                ref = fem.get(f"{scene}@{spread}") if spread else None
                matched = rod.get(f"{scene}_matched")
                rows[scene] = _errors(compare(scene, fem[scene]["steps"],
                                              rod[scene]["steps"],
                                              ref["steps"] if ref else None,
                                              matched["steps"] if matched else None))
            out["rows"][f"{level}/{name}"] = {"scenes": rows,
                                              "wall_time_s": time.perf_counter() - start}
    return out


def _pct(values: list[float | None], scale: float = 100.0) -> str:
    return " / ".join("-" if v is None else f"{scale * v:+.1f}" for v in values)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--fem-json", type=Path, required=True, metavar="R",
                    help="a cross-check report holding soft_crossing, soft_wrap and clasp")
    ap.add_argument("--fit", type=Path, metavar="X",
                    help="the soft crossing result to fit (default: the report's)")
    ap.add_argument("--spread", type=Path, nargs="*", default=[], metavar="F",
                    help="the soft crossing on other meshes, fitted alike")
    ap.add_argument("--levels", nargs="+", default=["compliant"],
                    choices=["compliant", "smoothed"])
    ap.add_argument("--out", type=Path, metavar="J", help="write the JSON here")
    args = ap.parse_args(argv)
    try:
        report = json.loads(args.fem_json.read_text())
        fit_result = (json.loads(args.fit.read_text()) if args.fit
                      else report.get("fem_results", {}).get("soft_crossing"))
        if fit_result is None or fit_result.get("scene") != "soft_crossing":
            raise ValueError("--fit: not a soft_crossing scene result")
        spread = [json.loads(p.read_text()) for p in args.spread]
        if any(r.get("scene") != "soft_crossing" for r in spread):
            raise ValueError("--spread: every file must be a soft_crossing scene result")
        out = run(report, fit_result, spread, args.levels)
    except (OSError, ValueError, KeyError) as err:
        print(f"crossing_law: {err}", file=sys.stderr)
        return 2
    for i, fit in enumerate(out["fits"]):
        what = "the refit" if i == 0 else "spread"
        print(f"soft crossing fit ({what}: {fit['mesh']} mesh, {len(fit['w_hat'])} levels "
              f"to w/D0 {max(fit['w_hat']):g}): k_point {fit['k_point']:.3f} p_point "
              f"{fit['p_point']:.3f} (largest error {100 * fit['residuals']['point']:.1f} %), "
              f"k_patch {fit['k_patch']:.3f} p_patch {fit['p_patch']:.3f}, "
              f"k_pmax {fit['k_pmax_point']:.3f} p_pmax {fit['p_pmax_point']:.3f}")
    s = out["shipped"]
    print(f"shipped (indent): k_point {s['k_point']:.3f} p_point {s['p_point']:.3f}; refit / "
          f"shipped force at w/D0 " + ", ".join(
              f"{w}: {r:.2f}" for w, r in out["force_ratio_refit_over_shipped"].items()))
    for key, row in out["rows"].items():
        print(f"\n{key} ({row['wall_time_s']:.1f} s)")
        for scene, e in row["scenes"].items():
            line = f"  {scene:14s} force {_pct(e['force_rel'])} %, A/A0 " \
                   f"{_pct(e['area_points'])} pts"
            if any(v is not None for v in e["curvature_rel"]):
                line += f", curvature {_pct(e['curvature_rel'])} %"
            if any(v is not None for v in e["force_rel_kinematics_matched"]):
                line += f", kinematics matched {_pct(e['force_rel_kinematics_matched'])} %"
            print(line)
    if args.out:
        from tightknot.atomic import atomic_open

        with atomic_open(args.out, "w") as fh:
            json.dump(out, fh, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
