"""Each contact level against the truth: ``tightknot bench tradeoff --fem XC.json``.

The trade-off study (:mod:`tightknot.benchmarks.tradeoff`) measures every run against the
finest rod run; this table measures the contact levels against the FEM (issue 18, part 3),
beside what they cost, so that a user can pick a level with numbers. It reads, rather than
reruns, two results:

- a cross-check report (``tightknot fem crosscheck --json XC.json``: the FEM's indent and
  wrap scenes on one mesh against the rod model at the compliant level, and at the smoothed
  level in its ``smoothed_contact_level`` entry);
- optionally the study's three knots at each level (``python bench/contact_levels.py
  --json CL.json``: wall time and Newton iterations);
- optionally a cross-check report of the sectioned level (``tightknot fem crosscheck
  --contact sectioned --json XCS.json``), which adds its row, with the contact width's miss.

Per level: the indent force's and the wrap's mid line load's error against the FEM at every
compared load level (min and max), the largest area miss, the wrap's curvature miss, the rod
model's time on the cross-check scenes and the FEM's time over it, and the knots' time
relative to the compliant level. The rigid level has no row of errors: a rigid tube against
a rigid counter-body has no contact compliance, so its force is set by the constraint and
not by an approach the FEM could be compared at.
"""

from __future__ import annotations

from typing import Any

#: What the table says of the rigid level's FEM errors.
RIGID_REASON = ("a rigid tube has no contact compliance: against the FEM's rigid "
                "counter-bodies its force is set by the constraint, not by an approach")


def _range(levels: list[dict], key: str) -> list[float] | None:
    vals = [lv[key] for lv in levels if lv.get(key) is not None]
    return [min(vals), max(vals)] if vals else None


def _max_abs(levels: list[dict], key: str) -> float | None:
    vals = [abs(lv[key]) for lv in levels if lv.get(key) is not None]
    return max(vals) if vals else None


def _scene_errors(scenes: dict[str, Any]) -> dict[str, Any]:
    ind = scenes["indent"]["comparison"]["levels"]
    wr = scenes["wrap"]["comparison"]["levels"]
    return {
        "indent_force_rel": _range(ind, "force_rel"),
        "indent_area_points_max": _max_abs(ind, "area_points"),
        "wrap_line_load_rel": _range(wr, "force_rel"),
        "wrap_area_points_max": _max_abs(wr, "area_points"),
        "wrap_curvature_rel_max": _max_abs(wr, "curvature_rel"),
        "width_fraction_max": _max_abs(ind + wr, "width_fraction"),
        # along the contact, where the report compares the profiles (the sectioned level)
        "width_profile_max": max(
            (w for w in (scenes[n]["comparison"].get("worst", {}).get("width_profile")
                         for n in ("indent", "wrap")) if w is not None), default=None),
        "compared_levels": {"indent": len(ind), "wrap": len(wr)},
    }


def _soft_errors(report: dict[str, Any], level: str) -> dict[str, Any] | None:
    """The two-soft-rod scenes' errors of ``level`` in a report's ``soft_scenes`` (the soft
    wrap's mid line load, the clasp's pull force and the soft crossing's force, min and
    max over the compared load levels, the FEM over rod time of each and, where the report
    compares them, the largest L_c miss along the contact, ``{scene}_width_profile_max``),
    None where the report has none."""
    entry = (report.get("soft_scenes") or {}).get("levels", {}).get(level)
    if entry is None:
        return None
    out: dict[str, Any] = {}
    for name, sc in entry["scenes"].items():
        out[f"{name}_force_rel"] = _range(sc["comparison"]["levels"], "force_rel")
        out[f"{name}_fem_over_rod_time_ratio"] = sc["fem_over_rod_time_ratio"]
        worst = sc["comparison"].get("worst", {})
        if worst.get("width_profile") is not None:
            out[f"{name}_width_profile_max"] = worst["width_profile"]
    return out


def _knot_cost(contact_levels: dict | None, level: str) -> dict[str, Any] | None:
    if contact_levels is None:
        return None
    rows = contact_levels.get("rows", [])
    mine = [r for r in rows if r.get("level") == level]
    base = {r["case"]: r for r in rows if r.get("level") == "compliant"}
    if not mine:
        return None
    # The bench's own ratios where it repeated the runs (bench/contact_levels.py --repeat:
    # the median of each run's ratio, the two levels timed one after the other), else the
    # ratio of the rows' times.
    own = {r["case"]: r["time_ratio_to_compliant"] for r in contact_levels.get("ratios", [])
           if r.get("level") == level and "time_ratio_to_compliant" in r}
    ratios = []
    for r in mine:
        if r["case"] in own:
            ratios.append(own[r["case"]])
        elif r["case"] in base and base[r["case"]]["wall_time_s"] > 0:
            ratios.append(r["wall_time_s"] / base[r["case"]]["wall_time_s"])
    return {"cases": [r["case"] for r in mine],
            "all_converged": all(r.get("converged") for r in mine),
            "wall_time_s": sum(r["wall_time_s"] for r in mine),
            "time_ratio_to_compliant": [min(ratios), max(ratios)] if ratios else None}


def level_truth(crosscheck: dict[str, Any], contact_levels: dict | None = None,
                sectioned: dict[str, Any] | list[dict[str, Any]] | None = None
                ) -> dict[str, Any]:
    """The table (module docstring) from a cross-check report and, optionally, the contact
    levels' knot benchmark and the sectioned level's cross-check reports (one row each,
    e.g. with and without its bend shift; the benchmark's level "sectioned-shift" gives
    the knots' cost of the shifted row). Raises ValueError when ``crosscheck`` is not a
    cross-check report of the compliant level, or a ``sectioned`` one not of the sectioned
    level."""
    if not isinstance(crosscheck, dict) or "scenes" not in crosscheck \
            or "smoothed_contact_level" not in crosscheck:
        raise ValueError("not a cross-check report (tightknot fem crosscheck --json F): it "
                         "needs 'scenes' and 'smoothed_contact_level'")
    fem_time = crosscheck["fem_wall_time_s"]
    sm = crosscheck["smoothed_contact_level"]
    rows = [
        {"level": "compliant", **_scene_errors(crosscheck["scenes"]),
         "rod_wall_time_s": crosscheck["rod_wall_time_s"],
         "fem_over_rod_time_ratio": crosscheck["fem_over_rod_time_ratio"],
         "passed": crosscheck["passed"], "knots": _knot_cost(contact_levels, "compliant"),
         "soft": _soft_errors(crosscheck, "compliant")},
        {"level": "smoothed", **_scene_errors(sm["scenes"]),
         "rod_wall_time_s": sm["rod_wall_time_s"],
         "fem_over_rod_time_ratio": sm["fem_over_rod_time_ratio"],
         "passed": sm["passed"], "knots": _knot_cost(contact_levels, "smoothed"),
         "soft": _soft_errors(crosscheck, "smoothed")},
    ]
    reports = [] if sectioned is None else (
        [sectioned] if isinstance(sectioned, dict) else list(sectioned))
    for sec in reports:
        if sec.get("contact") != "sectioned" or "scenes" not in sec:
            raise ValueError("not a cross-check report of the sectioned level (tightknot fem "
                             "crosscheck --contact sectioned --json F)")
        shift = bool(sec.get("section_bend_shift", False))
        rows.append({"level": "sectioned", **_scene_errors(sec["scenes"]),
                     "section_modes": sec.get("section_modes"),
                     "rod_edges_per_d0": sec.get("rod_edges_per_d0"),
                     "rod_wall_time_s": sec["rod_wall_time_s"],
                     "fem_over_rod_time_ratio": sec["fem_over_rod_time_ratio"],
                     "section_bend_shift": shift,
                     "passed": sec["passed"],
                     "knots": _knot_cost(contact_levels,
                                         "sectioned-shift" if shift else "sectioned"),
                     "soft": _soft_errors(sec, "sectioned")})
    rows.append({"level": "rigid", "fem_errors": None, "reason": RIGID_REASON,
                 "knots": _knot_cost(contact_levels, "rigid")})
    missing = [r["level"] for r in rows if r["level"] != "rigid" and r.get("soft") is None]
    not_covered = ["the FEM's soft_crossing (docs/fem_nip.md)"]
    if missing:
        not_covered.append("the soft wrap and the clasp at " + ", ".join(missing)
                           + " (reports run without --no-soft carry them)")
    if not reports:
        not_covered.append("the sectioned level (add --fem-sectioned XCS.json)")
    return {"fem_mesh": crosscheck.get("mesh"), "fem_wall_time_s": fem_time,
            "targets": crosscheck.get("targets"), "rows": rows,
            "not_covered": "; ".join(not_covered)}


def _pct(r: list[float] | None) -> str:
    return "n/a" if r is None else f"{100 * r[0]:+.1f} .. {100 * r[1]:+.1f} %"


def format_table(table: dict[str, Any]) -> str:
    """Markdown table of :func:`level_truth`'s result."""
    lines = [f"contact levels against the FEM ({table['fem_mesh']} mesh, "
             f"{table['fem_wall_time_s']:.0f} s of FEM)",
             "| level | indent force | wrap line load | soft wrap line load | clasp force | "
             "soft crossing force | area, max [points] | wrap curvature, max | "
             "L_c, max (middle section) | "
             "clasp L_c along the contact, max | "
             "rod time [s] | FEM / rod time | knots' time / compliant |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    # the rod scenes' resolution names a sectioned row where the rows differ in it
    resolutions = {r.get("rod_edges_per_d0") for r in table["rows"] if r["level"] == "sectioned"}
    for row in table["rows"]:
        knots = row.get("knots")
        kt = ("n/a" if not knots or knots["time_ratio_to_compliant"] is None else
              f"{knots['time_ratio_to_compliant'][0]:.2f} .. "
              f"{knots['time_ratio_to_compliant'][1]:.2f}")
        if row["level"] == "rigid":
            lines.append(f"| rigid | n/a ({RIGID_REASON}) | n/a | n/a | n/a | n/a | n/a | n/a "
                         f"| n/a | n/a | n/a | n/a | {kt} |")
            continue
        area = max(row["indent_area_points_max"] or 0.0, row["wrap_area_points_max"] or 0.0)
        soft = row.get("soft") or {}
        name = row["level"] + (" + bend shift" if row.get("section_bend_shift") else "")
        if len(resolutions) > 1 and row.get("rod_edges_per_d0") is not None:
            name += f", {row['rod_edges_per_d0']} edges per D0"
        lines.append(
            f"| {name} | {_pct(row['indent_force_rel'])} | "
            f"{_pct(row['wrap_line_load_rel'])} | {_pct(soft.get('soft_wrap_force_rel'))} | "
            f"{_pct(soft.get('clasp_force_rel'))} | "
            f"{_pct(soft.get('soft_crossing_force_rel'))} | {100 * area:.1f} | "
            f"{100 * (row['wrap_curvature_rel_max'] or 0.0):.1f} % | "
            + ("n/a" if row["width_fraction_max"] is None
               else f"{row['width_fraction_max']:.2f}")
            + ("" if row.get("width_profile_max") is None
               else f" ({row['width_profile_max']:.2f} along the contact)")
            + (" | n/a" if soft.get("clasp_width_profile_max") is None
               else f" | {soft['clasp_width_profile_max']:.2f}")
            + f" | {row['rod_wall_time_s']:.2f} | {row['fem_over_rod_time_ratio']:.0f} | {kt} |")
    lines.append(f"not covered: {table['not_covered']}")
    return "\n".join(lines)
