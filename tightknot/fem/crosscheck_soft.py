"""The cross-check's two-soft-rod rows: the soft wrap's mid line load and the clasp's pull
force, FEM against the rod model at each contact level, the FEM's mesh spread beside
each comparison.

=====================  ==================================================  ==============
quantity               compared                                            target
=====================  ==================================================  ==============
soft wrap line load    rod A's contact line load at the middle of the       |rel| <= 10 %
                       wrap per length of the axis (FEM: the nominal axis,
                       as in ``wrap``; rod model: its centreline) [N/m]
clasp force            the pull force at the same clamp travel [N]          |rel| <= 10 %
                       (and, a diagnostic, at the FEM's nominal approach
                       of the apexes, ``force_rel_same_approach``)
section area           A/A0 at the middle of the wrap / at the apex         |diff| <= 0.05
curvature              soft wrap: kappa D0 of the axis at the middle        |rel| <= 10 %
                       (clasp: the apex's, reported only: the FEM's is the
                       section centroids', not the nominal axis's)
pressure               peak contact pressure over E                        reported only
=====================  ==================================================  ==============

The compared levels: the FEM's levels with an approach (``approach_over_d0``) of at most
:data:`tightknot.fem.crosscheck_targets.APPROACH_LIMIT` D0 and a contact pressure (before the
clasp's bends touch there is nothing to compare).

Mesh spread (``fem_spread_rel``, per compared level): the relative difference of the
compared FEM quantity between the comparison's mesh and the next coarser one (medium:
coarse; fine: medium) at the same load level. On the coarse mesh there is none
(``spread_mesh`` None). A rod-model error smaller than the spread is within what the FEM
itself can tell.
"""

from __future__ import annotations

import time
from typing import Any

from .crosscheck_targets import APPROACH_LIMIT, TARGETS
from .scenes._common import MESH_LEVELS, relative

ROW_SCENES: tuple[str, ...] = ("soft_wrap", "clasp")
"""The cross-check's scenes with two soft rods."""

CONTACT_LEVELS: tuple[str, ...] = ("compliant", "smoothed")
"""The rod model's contact levels compared (:mod:`tightknot.fem.rod_model_soft`)."""


def spread_mesh(mesh: str) -> str | None:
    """The mesh whose difference from ``mesh`` is the FEM's spread: the next coarser one
    (None for the coarsest)."""
    k = MESH_LEVELS.index(mesh)
    return MESH_LEVELS[k - 1] if k > 0 else None


def fem_runs(mesh: str, fem_results: dict[str, dict] | None = None) -> dict[str, dict]:
    """The FEM results the soft rows need: each soft scene on ``mesh`` (keys "soft_wrap",
    "clasp") and on the spread mesh (keys "soft_wrap@coarse" ...); those in
    ``fem_results`` are reused, the others run with the scenes' default load levels."""
    from . import run_scene

    out = dict(fem_results or {})
    spread = spread_mesh(mesh)
    for name in ROW_SCENES:
        for level, key in ((mesh, name), (spread, f"{name}@{spread}")):
            if level is None or key in out:
                continue
            extra = {"compare": False} if name == "soft_wrap" else {}
            out[key] = run_scene(name, mesh=level, convergence=False, **extra)
    return out


def _rod_runs(fem: dict[str, dict], contact: str) -> dict[str, dict]:
    """The rod model at the FEM's load levels and parameters, at level ``contact``."""
    from .rod_model_soft import rod_clasp, rod_soft_wrap

    wp = fem["soft_wrap"]["parameters"]
    cp = fem["clasp"]["parameters"]
    d0 = cp["diameter_m"]
    return {
        "soft_wrap": rod_soft_wrap([s["tension"] for s in fem["soft_wrap"]["steps"]],
                                   wrap_angle_deg=wp["wrap_angle_deg"],
                                   diameter=wp["diameter_m"],
                                   youngs_modulus=wp["youngs_modulus_pa"],
                                   length_over_d0=wp["segment_length_m"] / wp["diameter_m"],
                                   contact=contact),
        "clasp": rod_clasp([s["pull_over_d0"] * d0 for s in fem["clasp"]["steps"]],
                           bend_radius_over_d0=cp["bend_radius_m"] / d0,
                           leg_length_over_d0=cp["leg_length_m"] / d0, diameter=d0,
                           youngs_modulus=cp["youngs_modulus_pa"], contact=contact),
    }


#: Per scene: (FEM force key, rod force key, FEM area key, rod area key, FEM curvature key,
#: rod curvature key, whether the curvature has a target).
_KEYS: dict[str, tuple[str, str, str, str, str, str, bool]] = {
    "soft_wrap": ("force_per_length_mid_nominal", "force_per_length_mid", "area_ratio_mid",
                  "area_ratio_mid", "kappa_d0_mid_nominal", "kappa_d0_mid", True),
    "clasp": ("force", "force", "area_ratio_apex", "area_ratio_apex", "kappa_d0_apex",
              "kappa_d0_apex", False),
}


def compare(scene: str, fem_steps: list[dict], rod_steps: list[dict],
            spread_steps: list[dict] | None) -> dict[str, Any]:
    """Per-level comparison of one soft scene (module docstring): force, area, curvature,
    pressure, each FEM value's mesh spread, and the targets met."""
    import numpy as np


    f_key, r_key, fa_key, ra_key, fk_key, rk_key, kappa_target = _KEYS[scene]
    # the clasp's force at the FEM's nominal approach (diagnostic): the rod model's force
    # interpolated in its own apex approach, so that the U's relaxed shape (where the
    # bends first touch) drops out and the contact's stiffness remains
    rod_app = np.array([r["approach_over_d0"] for r in rod_steps])
    rod_f = np.array([r[r_key] for r in rod_steps])
    order = np.argsort(rod_app)
    rows = []
    spread_steps = spread_steps or [None] * len(fem_steps)
    for f, r, c in zip(fem_steps, rod_steps, spread_steps, strict=True):
        # no contact yet (the clasp's bends apart): the FEM's force is round-off there
        if f["approach_over_d0"] > APPROACH_LIMIT + 1e-9 or f["peak_pressure_over_e"] <= 0.0:
            continue
        row = {
            "load": f.get("tension_over_e_d0sq", f.get("pull_over_d0")),
            "approach_over_d0": f["approach_over_d0"],
            "fem_force": f[f_key], "rod_force": r[r_key],
            "force_rel": relative(r[r_key], f[f_key]),
            "fem_area_ratio": f[fa_key], "rod_area_ratio": r[ra_key],
            "area_points": r[ra_key] - f[fa_key],
            "fem_kappa_d0": f[fk_key], "rod_kappa_d0": r[rk_key],
            "curvature_rel": relative(r[rk_key], f[fk_key]),
            "fem_peak_pressure_over_e": f["peak_pressure_over_e"],
            "rod_peak_pressure_over_e": r["peak_pressure_over_e"],
            "pressure_rel": relative(r["peak_pressure_over_e"], f["peak_pressure_over_e"]),
            "rod_converged": bool(r["converged"]),
            "fem_spread_rel": None if c is None else {
                "force": relative(f[f_key], c[f_key]),
                "area_points": f[fa_key] - c[fa_key],
                "curvature": relative(f[fk_key], c[fk_key])},
        }
        if scene == "clasp":
            a = f["approach_nominal_over_d0"]
            inside = rod_app.min() <= a <= rod_app.max()
            at = float(np.interp(a, rod_app[order], rod_f[order])) if inside else None
            row["rod_force_at_fem_nominal_approach"] = at
            row["force_rel_same_approach"] = None if at is None else relative(at, f[f_key])
        row["met"] = {"force": abs(row["force_rel"]) <= TARGETS["force_rel"],
                      "area": abs(row["area_points"]) <= TARGETS["area_points"],
                      "converged": row["rod_converged"]}
        if kappa_target:
            row["met"]["curvature"] = abs(row["curvature_rel"]) <= TARGETS["curvature_rel"]
        rows.append(row)
    worst = {k: max((abs(x[k]) for x in rows), default=None)
             for k in ("force_rel", "area_points", "curvature_rel", "pressure_rel")}
    spreads = [x["fem_spread_rel"]["force"] for x in rows if x["fem_spread_rel"]]
    return {"levels": rows, "worst": worst,
            "fem_force_spread_max": max((abs(s) for s in spreads), default=None),
            "passed": bool(rows) and all(all(x["met"].values()) for x in rows)}


def soft_rows(mesh: str, fem_results: dict[str, dict] | None = None) -> dict[str, Any]:
    """The report's ``soft_scenes`` entry: the FEM runs (:func:`fem_runs`), the rod model at
    each of :data:`CONTACT_LEVELS`, and their comparisons (:func:`compare`); ``passed``
    is the compliant level's (both scenes, every target, the rod model at least 1000
    times faster than the FEM on each scene)."""
    fem = fem_runs(mesh, fem_results)
    spread = spread_mesh(mesh)
    levels = {}
    for contact in CONTACT_LEVELS:
        start = time.perf_counter()
        rod = _rod_runs(fem, contact)
        scenes = {}
        for name in ROW_SCENES:
            ref = fem.get(f"{name}@{spread}") if spread else None
            scenes[name] = {
                "comparison": compare(name, fem[name]["steps"], rod[name]["steps"],
                                      ref["steps"] if ref else None),
                "fem_wall_time_s": fem[name]["wall_time_s"],
                "rod_wall_time_s": rod[name]["wall_time_s"],
                "fem_over_rod_time_ratio": fem[name]["wall_time_s"] / rod[name]["wall_time_s"],
                "rod_steps": rod[name]["steps"],
            }
        levels[contact] = {
            "scenes": scenes,
            "rod_wall_time_s": time.perf_counter() - start,
            "passed": all(s["comparison"]["passed"] and s["fem_over_rod_time_ratio"] >= 1000.0
                          for s in scenes.values()),
        }
    return {
        "what": "two soft rods: the soft wrap's mid line load and the clasp's pull force, "
                "FEM against the rod model at each contact level, with the FEM's mesh "
                "spread (tightknot/fem/crosscheck_soft.py)",
        "mesh": mesh,
        "spread_mesh": spread,
        "fem": {name: {"mesh": fem[name]["mesh"], "wall_time_s": fem[name]["wall_time_s"],
                       "steps": fem[name]["steps"],
                       "spread_steps": (fem[f"{name}@{spread}"]["steps"] if spread else None)}
                for name in ROW_SCENES},
        "levels": levels,
        "passed": levels["compliant"]["passed"],
    }
