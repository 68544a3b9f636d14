"""The cross-check's two-soft-rod rows: the soft wrap's mid line load, the clasp's pull
force and the soft crossing's force, FEM against the rod model at each contact level, the
FEM's mesh spread beside each comparison.

=====================  ==================================================  ==============
quantity               compared                                            target
=====================  ==================================================  ==============
soft wrap line load    rod A's contact line load at the middle of the       |rel| <= 10 %
                       wrap per length of the axis (FEM: the nominal axis,
                       as in ``wrap``; rod model: its centreline) [N/m]
clasp force            the pull force at the same clamp travel [N]          |rel| <= 10 %
                       (and, a diagnostic, with the U's kinematics
                       matched, ``force_rel_kinematics_matched``: below)
soft crossing force    the force between the two crossing rods at the       |rel| <= 10 %
                       same approach w per rod [N] (each rod in a stack
                       pressed from both sides,
                       :func:`tightknot.fem.rod_model_soft.soft_crossing_scene`)
section area           A/A0 at the middle of the wrap / at the apex / at    |diff| <= 0.05
                       the crossing; of rod B too (the wrap, the crossing;
                       the clasp's U's are one another's images)
curvature              soft wrap: kappa D0 of the axis at the middle        |rel| <= 10 %
                       (clasp: the apex's, reported only: the FEM's is the
                       section centroids', not the nominal axis's; the
                       crossing's straight rods: none)
profiles along the     L_c and A/A0 at each FEM node layer where either     |diff| <= 0.1,
contact                side is loaded, the rod model's interpolated in      <= 0.05
                       its rest arc length (rod A; rod B too in the
                       wrap; :mod:`tightknot.fem.profile_compare`)
pressure               peak contact pressure over E                        reported only
=====================  ==================================================  ==============

The compared levels: the FEM's levels with an approach (``approach_over_d0``) of at most
:data:`tightknot.fem.crosscheck_targets.APPROACH_LIMIT` D0 and a contact pressure (before the
clasp's bends touch there is nothing to compare).

Mesh spread (``fem_spread_rel``, per compared level): the relative difference of the
compared FEM quantity between the comparison's mesh and the next coarser one (medium:
coarse; fine: medium) at the same load level. On the coarse mesh there is none
(``spread_mesh`` None); the profiles' spread (``fem_spread`` of ``profile_a``, ``profile_b``)
is the coarser mesh's profile against the compared one's, with the same measure. A rod-model
error smaller than the spread is within what the FEM
itself can tell. Where the next finer mesh's run is given too (never run here: the fine
meshes take tens of minutes; ``tightknot fem crosscheck --fem-json REPORT FINE``), each
compared level also reports the compared mesh's difference from it
(``fem_spread_finer_rel``) and the rod model's force error against it
(``force_rel_finer``): the third mesh of the FEM's spread, reported, not judged.

The clasp's kinematic diagnostic. Both models clamp their U's at the same points, but the
U's settle differently before they touch: a tightly bent solid moves its section toward
the bend's centre (the FEM's ``relaxed`` outputs: the apex's inner side 1.06 R from the
mid fibre at rho = 1.5 D0), which the rod model's round section does not, and the two apexes
move out by different amounts. :func:`clasp_kinematic_offset` turns those relaxed
differences into the clamp travel by which the rod model's bends meet late (or early); the
rod model is run again with its clamps moved by it (``rod_force_kinematics_matched``), so
that what is left of the force difference is the contact's. Reported, not judged: the
offset comes from the FEM.
"""

from __future__ import annotations

import math
import time
from typing import Any

from .crosscheck_targets import APPROACH_LIMIT, TARGETS
from .profile_compare import along_contact, spread_summary
from .rod_model import EDGES_PER_D0
from .scenes._common import MESH_LEVELS, relative

ROW_SCENES: tuple[str, ...] = ("soft_wrap", "clasp", "soft_crossing")
"""The cross-check's scenes with two soft rods."""

CONTACT_LEVELS: tuple[str, ...] = ("compliant", "smoothed")
"""The rod model's contact levels compared (:mod:`tightknot.fem.rod_model_soft`)."""


def fem_spread(fem: dict[str, Any], coarser: dict[str, Any] | None, force_key: str,
               area_key: str, kappa_key: str | None = None) -> dict[str, Any] | None:
    """The FEM's own spread at one level: its force relative to the coarser mesh's at the
    same level, its area's difference in points and (``kappa_key``) its curvature's
    relative one; None without the coarser run."""
    if coarser is None:
        return None
    return {"force": relative(fem[force_key], coarser[force_key]),
            "area_points": fem[area_key] - coarser[area_key],
            "curvature": (relative(fem[kappa_key], coarser[kappa_key]) if kappa_key
                          else None)}


def spread_mesh(mesh: str) -> str | None:
    """The mesh whose difference from ``mesh`` is the FEM's spread: the next coarser one
    (None for the coarsest)."""
    k = MESH_LEVELS.index(mesh)
    return MESH_LEVELS[k - 1] if k > 0 else None


def finer_mesh(mesh: str) -> str | None:
    """The next finer mesh than ``mesh`` (None for the finest): its run, where one is
    given (never run by the cross-check: the fine meshes take tens of minutes), shows how
    far ``mesh`` itself is from converged."""
    k = MESH_LEVELS.index(mesh)
    return MESH_LEVELS[k + 1] if k + 1 < len(MESH_LEVELS) else None


def same_levels(a: dict[str, Any], b: dict[str, Any]) -> bool:
    """Whether two steps of a scene on different meshes are at one load level (the
    scenes' load keys: approach, tension, clamp travel)."""
    keys = [k for k in ("w_over_d0", "tension", "tension_over_e_d0sq", "pull_over_d0")
            if k in a and k in b]
    return all(math.isclose(a[k], b[k], rel_tol=1e-9, abs_tol=1e-15) for k in keys)


def merge_fem_results(files: list[tuple[str, dict[str, Any]]], mesh: str
                      ) -> dict[str, dict]:
    """The FEM results of several files for a cross-check on ``mesh``: each (name, data)
    is a cross-check report (its ``fem_results``, keys as it holds them) or one scene's
    result (``tightknot fem SCENE --json``: key SCENE on ``mesh``, SCENE@LEVEL on another
    mesh). The first file holding a key wins. ValueError naming the file that is
    neither."""
    out: dict[str, dict] = {}
    for name, data in files:
        if isinstance(data, dict) and isinstance(data.get("fem_results"), dict):
            found = data["fem_results"]
        elif isinstance(data, dict) and "scene" in data and "steps" in data:
            level = data.get("mesh", {}).get("level")
            if level not in MESH_LEVELS:
                raise ValueError(f"--fem-json {name}: its mesh level {level!r} is none of "
                                 f"{MESH_LEVELS}")
            found = {data["scene"] if level == mesh else f"{data['scene']}@{level}": data}
        else:
            raise ValueError(f"--fem-json {name}: neither a crosscheck report with "
                             f"fem_results nor a FEM scene result")
        for key, value in found.items():
            out.setdefault(key, value)
    return out


def fem_runs(mesh: str, fem_results: dict[str, dict] | None = None,
             scenes: tuple[str, ...] = ROW_SCENES) -> dict[str, dict]:
    """The FEM results a comparison needs: each of ``scenes`` (default the soft rows',
    :data:`ROW_SCENES`) on ``mesh`` (keys "soft_wrap", ...) and on the spread mesh (keys
    "soft_wrap@coarse" ...); those in ``fem_results`` are reused, the others run with the
    scenes' default load levels."""
    from . import run_scene

    out = dict(fem_results or {})
    spread = spread_mesh(mesh)
    for name in scenes:
        for level, key in ((mesh, name), (spread, f"{name}@{spread}")):
            if level is None or key in out:
                continue
            # (the scenes' own comparison with a rigid counter-body is not needed here)
            extra = {"compare": False} if name in ("soft_wrap", "soft_crossing") else {}
            out[key] = run_scene(name, mesh=level, convergence=False, **extra)
    return out


def clasp_kinematic_offset(fem_relaxed: dict[str, float], rod: dict[str, Any]
                           ) -> dict[str, float]:
    """How much later [D0 of clamp travel] the rod model's clasp bends touch than the
    FEM's, from the two relaxed U's (before the pull): twice (both rods) the sum of how
    much further out the rod model's apex moved (``apex_shift``, its centreline against
    the FEM's mid fibre) and how much further the FEM's inner side reaches from its mid
    fibre than the rod model's section from its centreline (``inner_side``: the FEM's
    ``inner_offset_over_r`` R against the rod model's ``relaxed_inner_side_over_r`` R, its
    section's radius and, where the level shifts its sections, their shift).
    Negative: earlier."""
    shift = rod["relaxed_apex_shift_over_d0"] - fem_relaxed["apex_shift_over_d0"]
    inner = 0.5 * (fem_relaxed["inner_offset_over_r"] - rod["relaxed_inner_side_over_r"])
    return {"apex_shift_over_d0": shift, "inner_side_over_d0": inner,
            "clamp_travel_over_d0": 2.0 * (shift + inner)}


def rod_runs(fem: dict[str, dict], contact: Any, scenes: tuple[str, ...] = ROW_SCENES,
             law: Any = None, edges_per_d0: int = EDGES_PER_D0) -> dict[str, dict]:
    """The rod model of ``scenes`` (default the soft rows', :data:`ROW_SCENES`) at the FEM's
    load levels and parameters (``fem`` holds each scene's FEM result), at level
    ``contact`` (a compliant or smoothed level with the pair law ``law``, default the
    shipped one) and ``edges_per_d0`` (the rods' resolution); with the clasp and the FEM's
    relaxed U's at hand also the clasp with the kinematics matched (key "clasp_matched",
    its ``kinematic_offset``, :func:`clasp_kinematic_offset`)."""
    from .rod_model_soft import rod_clasp, rod_soft_crossing, rod_soft_wrap

    unknown = [name for name in scenes if name not in ROW_SCENES]
    if unknown:
        raise ValueError(f"rod_runs: scenes must be among {ROW_SCENES}, got {unknown}")

    def soft_wrap() -> dict[str, Any]:
        wp = fem["soft_wrap"]["parameters"]
        return rod_soft_wrap([s["tension"] for s in fem["soft_wrap"]["steps"]],
                             wrap_angle_deg=wp["wrap_angle_deg"], diameter=wp["diameter_m"],
                             youngs_modulus=wp["youngs_modulus_pa"],
                             length_over_d0=wp["segment_length_m"] / wp["diameter_m"],
                             contact=contact, law=law, edges_per_d0=edges_per_d0)

    def clasp(gap: float | None = None) -> dict[str, Any]:
        # gap None: the FEM's own initial gap
        cp = fem["clasp"]["parameters"]
        d0 = cp["diameter_m"]
        gap = cp["initial_gap_m"] if gap is None else gap
        return rod_clasp([s["pull_over_d0"] * d0 for s in fem["clasp"]["steps"]],
                         bend_radius_over_d0=cp["bend_radius_m"] / d0,
                         leg_length_over_d0=cp["leg_length_m"] / d0, diameter=d0,
                         youngs_modulus=cp["youngs_modulus_pa"], contact=contact,
                         initial_gap=gap, law=law, edges_per_d0=edges_per_d0)

    def soft_crossing() -> dict[str, Any]:
        xp = fem["soft_crossing"]["parameters"]
        return rod_soft_crossing(
            [s["w_over_d0"] * xp["diameter_m"] for s in fem["soft_crossing"]["steps"]],
            diameter=xp["diameter_m"], youngs_modulus=xp["youngs_modulus_pa"],
            length_over_d0=xp["segment_length_m"] / xp["diameter_m"], contact=contact,
            law=law, edges_per_d0=edges_per_d0)

    build = {"soft_wrap": soft_wrap, "clasp": clasp, "soft_crossing": soft_crossing}
    runs = {name: build[name]() for name in ROW_SCENES if name in scenes}
    relaxed = fem["clasp"].get("relaxed") if "clasp" in runs else None
    if relaxed is not None and runs["clasp"]["relaxed"]:
        offset = clasp_kinematic_offset(relaxed, runs["clasp"])
        # the clamps moved in by the offset: the bends start that much closer
        cp = fem["clasp"]["parameters"]
        runs["clasp_matched"] = clasp(cp["initial_gap_m"]
                                      - offset["clamp_travel_over_d0"] * cp["diameter_m"])
        runs["clasp_matched"]["kinematic_offset"] = offset
    return runs


#: Per scene: the key of a step's load level (the soft wrap's tension over E D0^2, the
#: clasp's clamp travel over D0, the crossing's approach per rod over D0).
LOAD_KEYS: dict[str, str] = {"soft_wrap": "tension_over_e_d0sq", "clasp": "pull_over_d0",
                             "soft_crossing": "w_over_d0"}

#: Per scene: (FEM force key, rod force key, FEM area key, rod area key, FEM curvature key,
#: rod curvature key (None: no curvature), whether the curvature has a target).
_KEYS: dict[str, tuple[str, str, str, str, str | None, str | None, bool]] = {
    "soft_wrap": ("force_per_length_mid_nominal", "force_per_length_mid", "area_ratio_mid",
                  "area_ratio_mid", "kappa_d0_mid_nominal", "kappa_d0_mid", True),
    "clasp": ("force", "force", "area_ratio_apex", "area_ratio_apex", "kappa_d0_apex",
              "kappa_d0_apex", False),
    "soft_crossing": ("force", "force", "area_ratio_mid", "area_ratio_mid", None, None,
                      False),
}


#: Per scene: the key of rod B's mid-section A/A0, where B is compared too (the clasp's
#: two U's are one another's images: its rod model reports one).
_AREA_B_KEYS: dict[str, str] = {"soft_wrap": "area_ratio_mid_b",
                                "soft_crossing": "area_ratio_mid_b"}


def compare(scene: str, fem_steps: list[dict], rod_steps: list[dict],
            spread_steps: list[dict] | None, matched_steps: list[dict] | None = None,
            finer_steps: list[dict] | None = None) -> dict[str, Any]:
    """Per-level comparison of one soft scene (module docstring): force, area, curvature,
    pressure, each FEM value's mesh spread, and the targets met; with ``matched_steps``
    (the clasp's rod model with the kinematics matched) also that diagnostic's force; with
    ``finer_steps`` (the scene on the next finer mesh) :func:`finer_columns`."""
    f_key, r_key, fa_key, ra_key, fk_key, rk_key, kappa_target = _KEYS[scene]
    rows = []
    spread_steps = spread_steps or [None] * len(fem_steps)
    matched = matched_steps or [None] * len(fem_steps)
    finer = aligned_steps(fem_steps, finer_steps)
    for f, r, c, m, g in zip(fem_steps, rod_steps, spread_steps, matched, finer,
                             strict=True):
        # no contact yet (the clasp's bends apart): the FEM's force is round-off there
        if f["approach_over_d0"] > APPROACH_LIMIT + 1e-9 or f["peak_pressure_over_e"] <= 0.0:
            continue
        row = {
            "load": f[LOAD_KEYS[scene]],
            "approach_over_d0": f["approach_over_d0"],
            "fem_force": f[f_key], "rod_force": r[r_key],
            "force_rel": relative(r[r_key], f[f_key]),
            "fem_area_ratio": f[fa_key], "rod_area_ratio": r[ra_key],
            "area_points": r[ra_key] - f[fa_key],
            "fem_kappa_d0": f[fk_key] if fk_key else None,
            "rod_kappa_d0": r[rk_key] if rk_key else None,
            "curvature_rel": relative(r[rk_key], f[fk_key]) if fk_key else None,
            "fem_peak_pressure_over_e": f["peak_pressure_over_e"],
            "rod_peak_pressure_over_e": r["peak_pressure_over_e"],
            "pressure_rel": relative(r["peak_pressure_over_e"], f["peak_pressure_over_e"]),
            "rod_converged": bool(r["converged"]),
            "fem_spread_rel": fem_spread(f, c, f_key, fa_key, fk_key),
        }
        b_key = _AREA_B_KEYS.get(scene)
        if b_key is not None:
            row.update({"fem_area_ratio_b": f[b_key], "rod_area_ratio_b": r[b_key],
                        "area_points_b": r[b_key] - f[b_key]})
        row.update(profile_columns(scene, f, r, c))
        if g is not None:
            row.update(finer_columns(f, r, g, f_key, r_key, fa_key, fk_key))
        if m is not None:
            row["rod_force_kinematics_matched"] = m[r_key]
            row["force_rel_kinematics_matched"] = relative(m[r_key], f[f_key])
        row["met"] = {"force": abs(row["force_rel"]) <= TARGETS["force_rel"],
                      "area": abs(row["area_points"]) <= TARGETS["area_points"],
                      "converged": row["rod_converged"]}
        if b_key is not None:
            row["met"]["area_b"] = abs(row["area_points_b"]) <= TARGETS["area_points"]
        judge_profiles(scene, row)
        if kappa_target:
            row["met"]["curvature"] = abs(row["curvature_rel"]) <= TARGETS["curvature_rel"]
        rows.append(row)
    worst = {k: max((abs(x[k]) for x in rows if x.get(k) is not None), default=None)
             for k in ("force_rel", "area_points", "area_points_b", "curvature_rel",
                       "pressure_rel")}
    worst.update(profile_worst(rows))
    spreads = [x["fem_spread_rel"]["force"] for x in rows if x["fem_spread_rel"]]
    return {"levels": rows, "worst": worst,
            "fem_force_spread_max": max((abs(s) for s in spreads), default=None),
            **finer_summary(rows),
            "passed": bool(rows) and all(all(x["met"].values()) for x in rows)}


#: Per scene: the rods whose profiles are compared along the contact (the clasp's U's and
#: the crossing's rods are one another's images: A's only; the rigid scenes' one rod).
PROFILE_RODS: dict[str, tuple[str, ...]] = {"soft_wrap": ("a", "b"), "clasp": ("a",),
                                            "soft_crossing": ("a",), "wrap": ("a",),
                                            "indent": ("a",)}


def judge_profiles(scene: str, row: dict[str, Any]) -> None:
    """Add to ``row["met"]`` the targets along the contact (L_c within
    ``TARGETS["width_fraction"]``, A/A0 within ``TARGETS["area_points"]``) of each rod of
    :data:`PROFILE_RODS` whose comparison (:func:`profile_columns`) the row holds."""
    for rod in PROFILE_RODS[scene]:
        prof = row.get(f"profile_{rod}")
        if prof is not None:
            row["met"][f"width_profile_{rod}"] = (prof["width_fraction_max"]
                                                  <= TARGETS["width_fraction"])
            row["met"][f"area_profile_{rod}"] = (prof["area_points_max"]
                                                 <= TARGETS["area_points"])


def profile_worst(rows: list[dict[str, Any]]) -> dict[str, float | None]:
    """The largest L_c and A/A0 differences along the contact over the rows' profile
    comparisons of both rods (``width_profile``, ``area_profile_points``; None without)."""
    return {key: max((x[f"profile_{rod}"][name] for x in rows for rod in "ab"
                      if x.get(f"profile_{rod}") is not None), default=None)
            for key, name in (("width_profile", "width_fraction_max"),
                              ("area_profile_points", "area_points_max"))}


def profile_columns(scene: str, fem: dict[str, Any], rod: dict[str, Any],
                    coarser: dict[str, Any] | None) -> dict[str, Any]:
    """A compared level's profiles along the contact (:func:`tightknot.fem.profile_compare.
    along_contact`, the rod model's against the FEM's) per rod of :data:`PROFILE_RODS` whose
    profile both steps hold (``profile_a``, ``profile_b``; None where neither is loaded),
    each with the FEM's own spread on the same measure (``fem_spread``: the coarser mesh's
    profile against the compared one's; None without it)."""
    out: dict[str, Any] = {}
    for rod_name in PROFILE_RODS[scene]:
        key = f"profile_{rod_name}"
        if key not in fem or key not in rod:
            continue
        comp = along_contact(fem[key], rod[key])
        if comp is not None:
            comp["fem_spread"] = (spread_summary(along_contact(fem[key], coarser[key]))
                                  if coarser is not None and key in coarser else None)
        out[key] = comp
    return out


def aligned_steps(fem_steps: list[dict], other: list[dict] | None) -> list[dict | None]:
    """``other``'s step at each of ``fem_steps``' load levels (None where it has none)."""
    out: list[dict | None] = []
    for f in fem_steps:
        out.append(next((g for g in other or [] if same_levels(f, g)), None))
    return out


def finer_columns(fem: dict[str, Any], rod: dict[str, Any], finer: dict[str, Any],
                  force_key: str, rod_force_key: str, area_key: str,
                  kappa_key: str | None) -> dict[str, Any]:
    """A compared level's columns against the next finer mesh (reported, not part of
    ``passed``): the compared mesh's own difference from it (``fem_spread_finer_rel``, as
    :func:`fem_spread`) and the rod model's force error against it (``force_rel_finer``)."""
    return {"fem_spread_finer_rel": fem_spread(fem, finer, force_key, area_key, kappa_key),
            "force_rel_finer": relative(rod[rod_force_key], finer[force_key])}


def finer_summary(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """A comparison's largest finer-mesh spread and rod error (empty without a finer run)."""
    spreads = [abs(x["fem_spread_finer_rel"]["force"]) for x in rows
               if "fem_spread_finer_rel" in x]
    if not spreads:
        return {}
    return {"fem_force_spread_finer_max": max(spreads),
            "force_rel_finer_worst": max(abs(x["force_rel_finer"]) for x in rows
                                         if "force_rel_finer" in x)}


def soft_rows(mesh: str, fem_results: dict[str, dict] | None = None,
              section: Any = None, levels: tuple[str, ...] | None = None,
              edges_per_d0: int = EDGES_PER_D0) -> dict[str, Any]:
    """The report's ``soft_scenes`` entry: the FEM runs (:func:`fem_runs`), the rod model at
    each of ``levels`` (default :data:`CONTACT_LEVELS`; the sectioned level with the
    settings ``section`` where given) and ``edges_per_d0`` (its rods' resolution,
    reported as ``rod_edges_per_d0``), and their comparisons (:func:`compare`); ``passed``
    is the first level's, the compliant one by default (both scenes, every target, the rod
    model at least 1000 times faster than the FEM on each scene)."""
    fem = fem_runs(mesh, fem_results)
    spread = spread_mesh(mesh)
    finer = finer_mesh(mesh)
    names = tuple(CONTACT_LEVELS if levels is None else levels)
    from .rod_model_soft import CONTACT_LEVELS as ROD_LEVELS

    if not names or any(n not in ROD_LEVELS for n in names):
        raise ValueError(f"soft rows: levels must be among {ROD_LEVELS}, got {names}")
    levels = {}
    for contact in names:
        start = time.perf_counter()
        rod = rod_runs(fem, section if (contact == "sectioned" and section is not None)
                        else contact, edges_per_d0=edges_per_d0)
        scenes = {}
        for name in ROW_SCENES:
            ref = fem.get(f"{name}@{spread}") if spread else None
            fine = fem.get(f"{name}@{finer}") if finer else None
            matched = rod.get(f"{name}_matched")
            scenes[name] = {
                "comparison": compare(name, fem[name]["steps"], rod[name]["steps"],
                                      ref["steps"] if ref else None,
                                      matched["steps"] if matched else None,
                                      fine["steps"] if fine else None),
                "fem_wall_time_s": fem[name]["wall_time_s"],
                "rod_wall_time_s": rod[name]["wall_time_s"],
                "fem_over_rod_time_ratio": fem[name]["wall_time_s"] / rod[name]["wall_time_s"],
                "rod_steps": rod[name]["steps"],
            }
            if matched:
                scenes[name]["kinematic_offset"] = matched["kinematic_offset"]
        levels[contact] = {
            "scenes": scenes,
            "rod_wall_time_s": time.perf_counter() - start,
            "passed": all(s["comparison"]["passed"] and s["fem_over_rod_time_ratio"] >= 1000.0
                          for s in scenes.values()),
        }
    return {
        "what": "two soft rods: the soft wrap's mid line load, the clasp's pull force and "
                "the soft crossing's force, FEM against the rod model at each contact "
                "level, with the FEM's mesh spread (tightknot/fem/crosscheck_soft.py)",
        "mesh": mesh,
        "spread_mesh": spread,
        "finer_mesh": finer if any(f"{n}@{finer}" in fem for n in ROW_SCENES) else None,
        "fem": {name: {"mesh": fem[name]["mesh"], "wall_time_s": fem[name]["wall_time_s"],
                       "steps": fem[name]["steps"],
                       "spread_steps": (fem[f"{name}@{spread}"]["steps"] if spread else None)}
                for name in ROW_SCENES},
        "levels": levels,
        "rod_edges_per_d0": edges_per_d0,
        "passed": levels[names[0]]["passed"],
    }
