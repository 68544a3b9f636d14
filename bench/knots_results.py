"""Results of the knots issue's closing note: the study's three knots, measured.

Ties the closed trefoil (L0/D0 = 16.37) and the two open trefoils (185 mm pulled to
Lambda_OC = 15.0, 125 mm to 10.1) with :func:`tightknot.study.run.run_knot` (the demo's and
the golden runs' path), measures them with :func:`tightknot.knots.measure.analyze_centerline`
and the contact layer's report, writes JSON and prints a markdown table.

Segments (physics.md sec. 2): closed knot, the three inner (minima of rho) and three outer
(maxima of rho) segment middles found by ``closed_knot_profile``; each vertex belongs to
the nearest middle (windows of +- L0/(12 D0) in s). Open knots: physics.md names the
entrance and exit (first and last contact, s = -+Lambda_OC/2) inner segments and the
central loop at s = 0; we split [s_1, s_2] into five equal zones, entrance | outer 1 |
centre | outer 2 | exit (an operational choice: the study gives no finer definition).
Per segment: median kappa D0 (the plateau), min and max.

Usage::

    WARP_CACHE_PATH=.warp_cache .venv/bin/python bench/knots_results.py --json out.json \
        [--closed-nodes 100 --open-nodes 150 100] [--figures DIR]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from tightknot.atomic import write_json_atomic
from tightknot.knots.ideal import load_ideal_trefoil
from tightknot.knots.measure import analyze_centerline
from tightknot.knots.scenes import closed_trefoil, open_trefoil
from tightknot.study.run import KnotRun, draw_figures, run_knot


def _stats(k: np.ndarray) -> dict[str, float]:
    return {"median": float(np.median(k)), "min": float(k.min()), "max": float(k.max())}


def closed_segments(rep: dict) -> dict[str, Any]:
    """kappa D0 by segment type (inner/outer) of a closed-knot report (analyze_centerline)."""
    s = np.asarray(rep["s"])
    k = np.asarray(rep["kappa_D0_sorted"])
    period = float(rep["rest_length_L0"] / rep["diameter_D0"])
    mids = [(m, "inner") for m in rep["inner_segments_s"]] + [
        (m, "outer") for m in rep["outer_segments_s"]]
    d = np.stack([np.abs((s - m + 0.5 * period) % period - 0.5 * period) for m, _ in mids])
    near = np.argmin(d, axis=0)
    out: dict[str, Any] = {}
    for kind in ("inner", "outer"):
        idx = [i for i, (_, kk) in enumerate(mids) if kk == kind]
        sel = np.isin(near, idx)
        out[kind] = _stats(k[sel])
        # kappa at each segment middle (nearest vertex): a minimum or a peak there?
        out[kind]["at_middles"] = [float(k[np.argmin(d[i])]) for i in idx]
    return out


def open_segments(rep: dict) -> dict[str, Any]:
    """kappa D0 in the five zones of an open knot (module docstring) and where the peak is."""
    s = np.asarray(rep["s"])
    k = np.asarray(rep["kappa_D0"])
    lam = rep.get("Lambda_OC")
    if lam is None:
        return {}
    edges = np.linspace(-lam / 2, lam / 2, 6)
    names = ("entrance", "outer_1", "centre", "outer_2", "exit")
    out: dict[str, Any] = {}
    for n, a, b in zip(names, edges[:-1], edges[1:], strict=True):
        sel = (s >= a) & (s <= b)
        out[n] = _stats(k[sel]) if sel.any() else {}
    inside = (s >= -lam / 2) & (s <= lam / 2)
    i = np.flatnonzero(inside)[np.argmax(k[inside])]
    out["peak_kappa_D0"] = float(k[i])
    out["peak_s_over_lambda"] = float(s[i] / lam)  # 0 centre, +-0.5 entrance/exit
    return out


def vertex_s(rep: dict) -> np.ndarray:
    """s of each vertex in rod order (closed reports are sorted by s)."""
    s = np.asarray(rep["s"])
    if not rep["closed"]:
        return s
    out = np.empty_like(s)
    out[np.asarray(rep["vertex_order"])] = s
    return out


def summarise(run: KnotRun, ideal: dict | None) -> dict[str, Any]:
    """The closing note's numbers for one run."""
    rep, c, res = run.report, run.contact, run.result
    sv = vertex_s(rep)
    ia, il, ip = (int(np.argmin(c.area_ratio)), int(np.argmax(c.contact_width_fraction)),
                  int(np.argmax(c.peak_pressure_over_E)))
    out: dict[str, Any] = {
        "scene": run.scene.name, "vertices": run.scene.model.vertex_count,
        "rest_length_mm": run.scene.rest_length * 1e3, "converged": res.converged,
        "failure": res.failure, "knot_type": rep["knot_type"],
        "newton_iterations": res.newton_iterations, "wall_time_s": res.wall_time_s,
        "stretch": rep["stretch_L_over_L0"], "L_over_D": rep["L_over_D"],
        "min_gap_over_D0": run.summary["min_gap_over_D0"],
        "min_area_ratio": float(c.area_ratio[ia]), "min_area_s": float(sv[ia]),
        "max_contact_width_fraction": float(c.contact_width_fraction[il]),
        "max_contact_width_s": float(sv[il]),
        "max_pressure_over_E": float(c.peak_pressure_over_E[ip]),
        "max_pressure_s": float(sv[ip]),
    }
    if run.scene.closed:
        out["segments"] = closed_segments(rep)
        out["inner_segments_s"] = rep["inner_segments_s"]
        out["outer_segments_s"] = rep["outer_segments_s"]
        if ideal is not None:
            s_i, s_e = np.asarray(ideal["s"]), np.asarray(rep["s"])
            per = float(rep["rest_length_L0"] / rep["diameter_D0"])
            rho_i = np.interp(s_e, s_i, np.asarray(ideal["rho"]), period=per)
            z_i = np.interp(s_e, s_i, np.asarray(ideal["z"]), period=per)
            drho = np.asarray(rep["rho"]) - rho_i
            dz = np.asarray(rep["z"]) - z_i
            out["rho_offset_mean"] = float(drho.mean())
            out["rho_offset_min"] = float(drho.min())
            out["rho_offset_max"] = float(drho.max())
            out["z_diff_rms"] = float(np.sqrt(np.mean(dz**2)))
            out["z_amplitude_ideal"] = float(np.max(np.abs(z_i)))
            out["ideal_segments"] = closed_segments(ideal)
    else:
        out["lambda_oc"] = rep.get("Lambda_OC")
        out["pull_force_N"] = float(res.pull_force_N)
        out["segments"] = open_segments(rep)
        lam = rep.get("Lambda_OC") or float("nan")
        for key in ("min_area_s", "max_contact_width_s", "max_pressure_s"):
            out[key[:-2] + "_s_over_lambda"] = out[key] / lam
    return out


def _clean(obj: Any) -> Any:
    """JSON-ready copy: non-finite floats (no contact: gap inf, Lambda_OC NaN) become None."""
    if isinstance(obj, dict):
        return {k: _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, float) and not np.isfinite(obj):
        return None
    return obj


def _fmt(v: Any, nd: int = 3) -> str:
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.{nd}f}"
    return str(v)


def markdown(rows: list[dict]) -> str:
    """The closing note's table."""
    head = ["quantity"] + [f"{r['scene']} {r['rest_length_mm']:.0f} mm ({r['vertices']} v)"
                           for r in rows]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]

    def row(label: str, f: Any) -> None:
        lines.append("| " + label + " | " + " | ".join(f(r) for r in rows) + " |")

    row("converged, type", lambda r: f"{r['converged']}, {r['knot_type']}")
    row("stretch L/L0", lambda r: _fmt(r["stretch"], 4))
    row("L/D", lambda r: _fmt(r["L_over_D"], 2))
    row("Lambda_OC", lambda r: _fmt(r.get("lambda_oc"), 2))
    row("pulling force [N]", lambda r: _fmt(r.get("pull_force_N"), 2))
    row("min gap / D0", lambda r: _fmt(r["min_gap_over_D0"]))

    def seg(r: dict, name: str) -> str:
        g = r["segments"].get(name)
        if not g:
            return "-"
        return f"{g['median']:.2f} [{g['min']:.2f}, {g['max']:.2f}]"

    row("kappa D0 inner: median [min, max]", lambda r: seg(r, "inner") if r["scene"].startswith(
        "closed") else "-")
    row("kappa D0 outer: median [min, max]", lambda r: seg(r, "outer") if r["scene"].startswith(
        "closed") else "-")
    row("kappa D0 at inner middles", lambda r: ", ".join(
        f"{v:.2f}" for v in r["segments"]["inner"]["at_middles"]) if "inner" in r["segments"]
        else "-")
    for z in ("entrance", "outer_1", "centre", "outer_2", "exit"):
        row(f"kappa D0 {z}", lambda r, z=z: seg(r, z) if not r["scene"].startswith("closed")
            else "-")
    row("peak kappa D0 at s/Lambda", lambda r: (
        f"{r['segments']['peak_kappa_D0']:.2f} at {r['segments']['peak_s_over_lambda']:+.2f}"
        if "peak_kappa_D0" in r["segments"] else "-"))
    row("rho - rho_ideal: mean [min, max]", lambda r: (
        f"{r['rho_offset_mean']:+.3f} [{r['rho_offset_min']:+.3f}, {r['rho_offset_max']:+.3f}]"
        if "rho_offset_mean" in r else "-"))
    row("z - z_ideal rms (ideal amplitude)", lambda r: (
        f"{r['z_diff_rms']:.3f} ({r['z_amplitude_ideal']:.3f})" if "z_diff_rms" in r else "-"))
    row("min A/A0 at s", lambda r: f"{r['min_area_ratio']:.3f} at {r['min_area_s']:+.2f}")
    row("max L_c at s", lambda r: (f"{r['max_contact_width_fraction']:.3f} at "
                                   f"{r['max_contact_width_s']:+.2f}"))
    row("max p/E at s", lambda r: f"{r['max_pressure_over_E']:.4f} at {r['max_pressure_s']:+.2f}")
    row("Newton iterations, wall [s]", lambda r: (f"{r['newton_iterations']}, "
                                                  f"{r['wall_time_s']:.1f}"))
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--json", metavar="FILE", help="write the results as JSON")
    ap.add_argument("--closed-nodes", type=int, default=100, help="closed trefoil vertices")
    ap.add_argument("--open-nodes", type=int, nargs=2, default=(150, 100),
                    metavar=("N185", "N125"), help="vertices of the 185 mm and 125 mm knots")
    ap.add_argument("--figures", metavar="DIR", help="draw the study's figures into DIR")
    args = ap.parse_args(argv)
    if args.json is not None and not Path(args.json).resolve().parent.is_dir():
        print(f"--json: folder does not exist: {Path(args.json).parent}", file=sys.stderr)
        return 2
    t0 = time.perf_counter()
    d0 = 8.5e-3
    ideal = analyze_centerline(load_ideal_trefoil(d0), d0, True, contact_tol=0.002)
    runs = [run_knot(closed_trefoil(16.37, nodes=args.closed_nodes), tighten_steps=40)]
    for length, target, nodes in ((0.185, 15.0, args.open_nodes[0]),
                                  (0.125, 10.1, args.open_nodes[1])):
        runs.append(run_knot(open_trefoil(length, nodes=nodes), target_lambda=target))
    rows = [summarise(r, ideal if r.scene.closed else None) for r in runs]
    rows_ideal = {"ideal_trefoil_segments": closed_segments(ideal),
                  "ideal_L_over_D": ideal["L_over_D"]}
    table = markdown(rows)
    print(table)
    print(f"\nideal trefoil: kappa D0 inner median [min, max] "
          f"{rows_ideal['ideal_trefoil_segments']['inner']['median']:.2f} "
          f"[{rows_ideal['ideal_trefoil_segments']['inner']['min']:.2f}, "
          f"{rows_ideal['ideal_trefoil_segments']['inner']['max']:.2f}], outer "
          f"{rows_ideal['ideal_trefoil_segments']['outer']['median']:.2f} "
          f"[{rows_ideal['ideal_trefoil_segments']['outer']['min']:.2f}, "
          f"{rows_ideal['ideal_trefoil_segments']['outer']['max']:.2f}]")
    for r in rows:
        if not r["converged"]:
            print(f"FAILED {r['scene']} {r['rest_length_mm']:.0f} mm ({r['vertices']} v): "
                  f"{r['failure']}")
    print(f"total {time.perf_counter() - t0:.1f} s")
    if args.figures:
        draw_figures(runs, Path(args.figures))
    if args.json:
        write_json_atomic(Path(args.json), _clean({"rows": rows, "ideal": rows_ideal,
                                                   "markdown": table}))
    return 0 if all(r["converged"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
