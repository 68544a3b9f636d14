"""Cross-check of the rod model (DER plus the calibrated radial-compliance layer) against
the small 3D solid FEM on the scenes ``indent`` and ``wrap``.

Each scene is run twice: by the FEM (:mod:`tightknot.fem.scenes`, ``DEFAULT_MESH``: the
mesh the shipped law was calibrated on) and by the rod model with the rigid body as a
second, fully pinned rod of the same diameter. At every FEM load level up to an approach
of ``APPROACH_LIMIT`` D0 the two are compared:

=====================  ==================================================  ==============
quantity               compared                                            target
=====================  ==================================================  ==============
contact force          indent: force on one side [N]; wrap: line load at   |rel| <= 10 %
                       the middle of the wrap per length of the axis
                       [N/m] (the wrap's TOTAL force is 2 T sin(theta) in
                       both models by statics, so it is reported but
                       tests nothing)
section area           A/A0 at the contact (mid section)                   |diff| <= 0.05
axis curvature         kappa D0 at the middle (wrap; the indent's axis     |rel| <= 10 %
                       stays straight by symmetry in both models)
pressure               peak contact pressure over E                        reported only
=====================  ==================================================  ==============

Rigid counter-body (see :mod:`tightknot.fem.overlap`). The rod model's law is per side and
its pair kernel reads the per-side approach as w = delta/2 (two identical deformable rods
share the overlap). Against a RIGID body the rod takes all of it, w = delta: the per-side
law f(w) is unchanged, but the pair law must be f(delta) = k E D (delta/D)^p, which the
kernel (which evaluates k E D (delta/(2D))^p) gives with k replaced by k 2^p. This is the
two-springs-in-series split of ``overlap.split_overlap`` with an infinitely stiff second
spring. The same w = delta enters the section outputs of the law (pressure, width).

Section area of the rod model. The law's area factor was calibrated on a section squeezed
on BOTH sides by w (diameter reduction 2 w). A section pressed on one side only (wrap:
diameter reduction delta) is given the factor at the mean per-side approach delta/2, and
a section pressed on both sides by rigid bodies (indent) the factor at w:
A/A0 = (1/lambda)(1 - k_area (w_eff/D)^p_area), with lambda the axial stretch of the
rod's edges at the contact (incompressible thinning).

The wrap's axis: the NOMINAL axis of the FEM section. The rod model's centerline is the
centre of a nominal circle of radius r0 lambda^(-1/2) whose far side (opposite the
contact) it keeps at that distance; the contact's deformation is all overlap on the near
side. The FEM's counterpart is the far fibre (the section's point opposite the contact)
moved toward the cylinder by the same stretched radius (FEM keys ``*_nominal``,
:func:`tightknot.fem.scenes.wrap.nominal_axis`); curvature and line load per length are
taken on it. The section CENTROID is not that point: the flattening at the contact moves
it away from the cylinder, most at the middle where the load peaks, which bends the
centroid line by more than the axis, and the nominal axis's approach is the rod model's
while the centroid's is not (docs/design_notes.md, FEM cross-check). The centroid-axis values
are reported too (``centroid_axis``).

Approach (the gate of the compared levels). indent: the total approach 2 w of the two
indenters; wrap: D0 - d, d the distance from the mid section's centroid to the cylinder
axis (FEM key ``approach_over_d0``, the calibration's centroid definition). It is smaller
than the nominal approach, so it admits more levels: the stricter gate.

Diagnostics (``diagnostics``, not timed, not part of ``passed``): the indent's axial force
at the crossing in both models, and the rod model with nu = 0 (a contact radius that does
not thin with stretch): where the indent's force deficit comes from; the indent's contact
footprint in both models (``indent_footprint``); the wrap with variants of the pair kernel
(``wrap_kernel_variants``, :mod:`tightknot.fem.wrap_variants`): where the wrap's line-load
deficit does not come from.

The FEM's own spread (``fem_spread_rel`` of each compared level, ``fem_force_spread_max``
of each comparison): the same scene on the next coarser mesh (:func:`tightknot.fem.
crosscheck_soft.spread_mesh`; none on the coarse mesh) at the same levels, its force's
relative difference and its A/A0's in points: a rod-model error below it is within what
the FEM itself can tell. Where a run on the next finer mesh is given (``fem_results`` key
"indent@fine" ..., never run here), each level also carries the compared mesh's
difference from it and the rod model's force error against it
(:func:`~tightknot.fem.crosscheck_soft.finer_columns`). Reported beside the targets, not
part of ``passed``.

Wall time. ``fem_over_rod_time_ratio`` is the FEM wall time of the compared runs (one mesh
each, all load levels) over the rod model's (all levels, model set-up included, after
one untimed warm-up that compiles the Warp kernels; the warm-up time is reported too).
"""

from __future__ import annotations

import math
import time
from typing import Any

from .crosscheck_soft import (
    aligned_steps,
    fem_runs,
    fem_spread,
    finer_columns,
    finer_mesh,
    finer_summary,
    judge_profiles,
    profile_columns,
    profile_worst,
    same_levels,
    spread_mesh,
)
from .crosscheck_targets import APPROACH_LIMIT, TARGETS
from .material import ROD_DIAMETER
from .rod_model import EDGES_PER_D0, check_edges_per_d0, rod_indent, rod_wrap
from .scenes._common import MESH_LEVELS, finite, relative

DEFAULT_MESH: str = "medium"
"""FEM mesh of the comparison: the mesh the shipped law was calibrated on. The coarse
mesh differs from it by as much as the targets, so it cannot referee them
(docs/fem_crosscheck.md)."""

CONTACT_LEVELS: tuple[str, ...] = ("compliant", "sectioned")
"""Rod-model contact levels the cross-check runs as its subject: the compliant level
(with the smoothed one beside it) or the sectioned level (:mod:`tightknot.fem.rod_sectioned`).
"""


def fem_width_fraction(step: dict[str, Any], scene: str) -> float | None:
    """The FEM's contact width fraction L_c of the mid section: the contact arcs (chords of
    the measured semi-axes: two indenters of half-width a across the rod, or the wrap's one
    contact of half-width b) over the deformed perimeter pi D0 sqrt(A/A0)."""
    perimeter = math.pi * math.sqrt(step["area_ratio_mid"])
    if scene == "indent":
        a = step.get("semi_axis_transverse_over_d0")
        return None if a is None else 4.0 * a / perimeter
    b = step.get("contact_half_width_mid_over_d0")
    return None if b is None else 2.0 * b / perimeter

def _compare(fem_steps: list[dict], rod_steps: list[dict], force_keys: tuple[str, str],
             kappa_key: str | None, width_scene: str | None = None,
             limit: float = APPROACH_LIMIT, spread_steps: list[dict] | None = None,
             finer_steps: list[dict] | None = None) -> dict[str, Any]:
    """Per-level comparison up to an approach of ``limit`` D0 (gated on the FEM's
    ``approach_over_d0``; default ``APPROACH_LIMIT``, the targets' range).
    ``force_keys``: (FEM key, rod key) of the compared force; ``kappa_key``: the FEM
    key of the axis curvature compared with the rod's ``kappa_d0_mid`` (None: not
    compared); ``width_scene``: compare the mid section's
    contact width fraction (the rod's ``contact_width_fraction_mid``) with the FEM's
    (:func:`fem_width_fraction` of that scene), None: not compared; ``spread_steps``: the
    same scene on the next coarser mesh at the same levels, whose difference from
    ``fem_steps`` each row reports as the FEM's own spread (``fem_spread_rel``:
    :func:`~tightknot.fem.crosscheck_soft.fem_spread`; None without; with ``width_scene``,
    where both steps hold the profile ``profile_a`` (the sectioned level), A/A0 and L_c are also
    judged along the contact: :func:`~tightknot.fem.crosscheck_soft.profile_columns`, the
    spread step's profile as the FEM's own spread); ``finer_steps``:
    the scene on the next finer mesh, where given
    (:func:`~tightknot.fem.crosscheck_soft.finer_columns`)."""
    fem_force, rod_force = force_keys
    rows = []
    spread = list(spread_steps or [])
    spread += [None] * (len(fem_steps) - len(spread))
    finer = aligned_steps(fem_steps, finer_steps)
    for f, r, c, g in zip(fem_steps, rod_steps, spread, finer, strict=True):
        if f["approach_over_d0"] > limit + 1e-9:
            continue
        if c is not None and not same_levels(f, c):
            c = None  # another load level: no spread to report
        row = {
            "approach_over_d0": f["approach_over_d0"],
            "rod_approach_over_d0": r["approach_over_d0"],
            "fem_force": f[fem_force], "rod_force": r[rod_force],
            "force_rel": relative(r[rod_force], f[fem_force]),
            "fem_area_ratio": f["area_ratio_mid"], "rod_area_ratio": r["area_ratio_mid"],
            "area_points": r["area_ratio_mid"] - f["area_ratio_mid"],
            "fem_peak_pressure_over_e": f["peak_pressure_over_e"],
            "rod_peak_pressure_over_e": r["peak_pressure_over_e"],
            "pressure_rel": relative(r["peak_pressure_over_e"], f["peak_pressure_over_e"]),
            "rod_converged": r["converged"],
            "fem_spread_rel": fem_spread(f, c, fem_force, "area_ratio_mid", kappa_key),
        }
        if kappa_key is not None:
            row.update(fem_kappa_d0=f[kappa_key], rod_kappa_d0=r["kappa_d0_mid"],
                       curvature_rel=relative(r["kappa_d0_mid"], f[kappa_key]))
        if g is not None:
            row.update(finer_columns(f, r, g, fem_force, rod_force, "area_ratio_mid",
                                     kappa_key))
        row["met"] = {
            "force": abs(row["force_rel"]) <= TARGETS["force_rel"],
            "area": abs(row["area_points"]) <= TARGETS["area_points"],
            "converged": bool(r["converged"]),
        }
        if kappa_key is not None:
            row["met"]["curvature"] = abs(row["curvature_rel"]) <= TARGETS["curvature_rel"]
        if width_scene is not None:
            lc = fem_width_fraction(f, width_scene)
            row.update(fem_width_fraction=lc, rod_width_fraction=r["contact_width_fraction_mid"],
                       width_fraction=None if lc is None
                       else r["contact_width_fraction_mid"] - lc)
            row["met"]["width"] = (row["width_fraction"] is not None
                                   and abs(row["width_fraction"]) <= TARGETS["width_fraction"])
        if width_scene is not None:
            # along the contact, where both sides report a profile (the sectioned level)
            row.update(profile_columns(width_scene, f, r, c))
            judge_profiles(width_scene, row)
        rows.append(row)
    worst = {k: max((abs(x[k]) for x in rows if x.get(k) is not None), default=None)
             for k in ("force_rel", "area_points", "pressure_rel")
             + (("curvature_rel",) if kappa_key is not None else ())
             + (("width_fraction",) if width_scene is not None else ())}
    # only where profiles were compared: the other levels' reports keep their keys
    worst.update({k: v for k, v in profile_worst(rows).items() if v is not None})
    spreads = [abs(x["fem_spread_rel"]["force"]) for x in rows if x["fem_spread_rel"]]
    return {"levels": rows, "worst": worst,
            "fem_force_spread_max": max(spreads, default=None),
            **finer_summary(rows),
            "passed": bool(rows) and all(all(x["met"].values()) for x in rows)}


def _wrap_centroid_axis(fem_steps: list[dict], rod_steps: list[dict]) -> list[dict]:
    """The wrap's FEM line load and curvature on the section-centroid axis (reported
    only: the centroid is not the rod model's centerline, see the module docstring)."""
    rows = []
    for f, r in zip(fem_steps, rod_steps, strict=True):
        if f["approach_over_d0"] > APPROACH_LIMIT + 1e-9:
            continue
        rows.append({
            "approach_over_d0": f["approach_over_d0"],
            "fem_approach_nominal_over_d0": f["approach_nominal_over_d0"],
            "rod_approach_over_d0": r["approach_over_d0"],
            "fem_force_centroid_axis": f["force_per_length_mid"],
            "force_rel_centroid_axis": relative(r["force_per_length_mid"],
                                                f["force_per_length_mid"]),
            "fem_kappa_d0_centroid": f["kappa_d0_mid"],
            "curvature_rel_centroid": relative(r["kappa_d0_mid"], f["kappa_d0_mid"]),
        })
    return rows


def _rod_indent_like(fem: dict[str, Any], run: Any = None, **kw: Any) -> dict[str, Any]:
    """``run`` (default :func:`rod_indent`) at the load levels, diameter, modulus and segment
    length of the FEM indent result ``fem``; ``kw`` go to ``run``."""
    par = fem["parameters"]
    d0 = par["diameter_m"]
    return (run or rod_indent)([s["w_over_d0"] * d0 for s in fem["steps"]], diameter=d0,
                               youngs_modulus=par["youngs_modulus_pa"],
                               length_over_d0=par["segment_length_m"] / d0, **kw)


def _rod_wrap_like(fem: dict[str, Any], run: Any = None, **kw: Any) -> dict[str, Any]:
    """``run`` (default :func:`rod_wrap`) at the tensions, wrap angle, diameter, modulus
    and segment length of the FEM wrap result ``fem``; ``kw`` go to ``run``."""
    par = fem["parameters"]
    return (run or rod_wrap)([s["tension"] for s in fem["steps"]],
                             wrap_angle_deg=par["wrap_angle_deg"], diameter=par["diameter_m"],
                             youngs_modulus=par["youngs_modulus_pa"],
                             length_over_d0=par["segment_length_m"] / par["diameter_m"], **kw)


def _indent_diagnostics(fem: dict[str, Any], rod: dict[str, Any]) -> dict[str, Any]:
    """Why the rod model's indent force falls short (not timed, not part of ``passed``):
    the axial force that the contact layer puts into the rod at the crossing, against the
    FEM's, and the rod model rerun with nu = 0 (its contact radius r0 lambda^(-nu) then
    does not thin with stretch, so the contact energy has no derivative along the rod)."""
    rest = _rod_indent_like(fem, poisson_ratio=0.0)
    rows = []
    for f, r, b in zip(fem["steps"], rod["steps"], rest["steps"], strict=True):
        if f["approach_over_d0"] > APPROACH_LIMIT + 1e-9:
            continue
        rows.append({
            "approach_over_d0": f["approach_over_d0"],
            "fem_axial_force_mid_over_e_d0sq": f.get("axial_force_mid_over_e_d0sq"),
            "rod_axial_force_mid_over_e_d0sq": r["axial_force_mid_over_e_d0sq"],
            "rod_axial_stretch_mid": r["axial_stretch_mid"],
            "rod_overlap_over_w": r["overlap_over_d0"] / f["w_over_d0"],
            "force_rel": relative(r["force"], f["force"]),
            "rod_nu0_axial_force_mid_over_e_d0sq": b["axial_force_mid_over_e_d0sq"],
            "force_rel_rod_nu0": relative(b["force"], f["force"]),
            "rod_nu0_converged": bool(b["converged"]),
        })
    return {
        "indent_axial": {
            "what": "diagnostic (not timed, not part of passed): the axial force in the mid "
                    "section at the crossing (rod model, FEM), the rod model's stretch there "
                    "and its overlap over w; and the rod model with nu = 0 for the rod, whose "
                    "contact radius then stays r0 (no thinning with stretch)",
            "levels": rows,
        },
    }


#: Footprint of the rod model's force over a Hertz patch's: a patch of semi-axis a with an
#: elliptical pressure has a line density (1 - x^2/a^2) along a diameter, whose rms is
#: a/sqrt(5) (Johnson 1985, sec. 4.2).
HERTZ_RMS_TO_SEMI_AXIS: float = math.sqrt(5.0)

#: Kernel variants of the wrap diagnostic (tightknot.fem.wrap_variants): the shipped
#: kernel (re-implemented, as a check), its footprint shrunk to the Hertz patch, the line law.
WRAP_VARIANTS: tuple[tuple[str, float], ...] = (("point", 1.0), ("point", 2.0), ("line", 1.0))


def _indent_footprint(fem: dict[str, Any], rod: dict[str, Any]) -> dict[str, Any]:
    """The rod model's contact footprint along the indenter against the FEM's patch."""
    rows = []
    for f, r in zip(fem["steps"], rod["steps"], strict=True):
        if f["approach_over_d0"] > APPROACH_LIMIT + 1e-9:
            continue
        a_rod = HERTZ_RMS_TO_SEMI_AXIS * r["force_rms_halfwidth_over_d0"]
        a_fem = f.get("semi_axis_transverse_over_d0")
        rows.append({
            "approach_over_d0": f["approach_over_d0"],
            "rod_equivalent_semi_axis_over_d0": a_rod,
            "fem_semi_axis_transverse_over_d0": a_fem,
            "fem_semi_axis_axial_over_d0": f.get("semi_axis_axial_over_d0"),
            "rod_over_fem_semi_axis": a_rod / a_fem if a_fem else None,
            "kernel_reach_over_d0": math.sqrt(max(2.0 * r["overlap_over_d0"], 0.0)),
        })
    return {
        "what": "diagnostic: the semi-axis of a Hertz patch with the rms spread of the rod "
                "model's force on the indenter (sqrt(5) rms), against the FEM's patch; the "
                "kernel reaches sqrt(R^2 - d^2) ~ sqrt(2 R delta) along each strand",
        "levels": rows,
    }


def _wrap_variants(fem_wrap: dict[str, Any]) -> dict[str, Any]:
    """The wrap with kernel variants (:mod:`tightknot.fem.wrap_variants`) against the FEM."""
    from tightknot.contact.law import RadialComplianceLaw

    from .wrap_variants import rod_wrap_variant

    out = []
    # The variants leave out the hard core and thin each edge by its own stretch: the rod
    # model so made is their reference.
    coreless = RadialComplianceLaw.from_json().without_core()
    runs = [("warp_without_core", None,
             _rod_wrap_like(fem_wrap, law=coreless, thinning="edge"))]
    runs += [(kernel, footprint, _rod_wrap_like(fem_wrap, rod_wrap_variant, kernel=kernel,
                                                footprint=footprint, law=coreless))
             for kernel, footprint in WRAP_VARIANTS]
    for kernel, footprint, res in runs:
        levels = []
        for f, r in zip(fem_wrap["steps"], res["steps"], strict=True):
            if f["approach_over_d0"] > APPROACH_LIMIT + 1e-9:
                continue
            levels.append({
                "tension_over_e_d0sq": f["tension_over_e_d0sq"],
                "force_rel": relative(r["force_per_length_mid"],
                                      f["force_per_length_mid_nominal"]),
                "curvature_rel": relative(r["kappa_d0_mid"], f["kappa_d0_mid_nominal"]),
                "rod_contact_half_length_over_d0": r.get("contact_half_length_over_d0"),
                "converged": bool(r["converged"]),
            })
        out.append({"kernel": kernel, "footprint": footprint, "levels": levels,
                    "wall_time_s": res["wall_time_s"]})
    return {
        "what": "diagnostic: the wrap's mid line load and curvature with variants of the "
                "pair kernel (tightknot/fem/wrap_variants.py: point kernel with its "
                "footprint shrunk by 'footprint', or the line law), relative to the FEM; "
                "all without the hard core and with each edge's own thinning, the first the rod "
                "model's own kernel",
        "variants": out,
    }


def _smoothed_level(fem_ind: dict[str, Any], fem_wrap: dict[str, Any],
                    rod_ind: dict[str, Any], rod_wr: dict[str, Any],
                    spread: dict[str, list[dict] | None],
                    finer: dict[str, list[dict] | None]) -> dict[str, Any]:
    """Both scenes with the "smoothed" contact level (the section thinned by the stretch
    averaged over +-1 D0 along the rod, :mod:`tightknot.contact.section_radius`): the same
    comparisons and targets as the default level's, reported beside them (``passed`` of
    the report is the default level's)."""
    from tightknot.knots.scenes import SMOOTHED_RADIUS_WINDOW as window

    ind = _rod_indent_like(fem_ind, radius_window=window)
    wr = _rod_wrap_like(fem_wrap, radius_window=window)
    comp = {
        "indent": _compare(fem_ind["steps"], ind["steps"], ("force", "force"), None,
                           spread_steps=spread["indent"], finer_steps=finer["indent"]),
        "wrap": _compare(fem_wrap["steps"], wr["steps"],
                         ("force_per_length_mid_nominal", "force_per_length_mid"),
                         "kappa_d0_mid_nominal", spread_steps=spread["wrap"],
                         finer_steps=finer["wrap"]),
    }
    axial = [{"approach_over_d0": f["approach_over_d0"],
              "fem_axial_force_mid_over_e_d0sq": f.get("axial_force_mid_over_e_d0sq"),
              "rod_axial_force_mid_over_e_d0sq": r["axial_force_mid_over_e_d0sq"],
              "default_level_rod_axial_force_mid_over_e_d0sq": r0["axial_force_mid_over_e_d0sq"]}
             for f, r, r0 in zip(fem_ind["steps"], ind["steps"], rod_ind["steps"], strict=True)
             if f["approach_over_d0"] <= APPROACH_LIMIT + 1e-9]
    rod_time = ind["wall_time_s"] + wr["wall_time_s"]
    fem_time = fem_ind["wall_time_s"] + fem_wrap["wall_time_s"]
    return {
        "what": "the 'smoothed' contact level (ContactLayer(radius_window=1 D0)): the same "
                "comparisons and targets; not part of the report's passed",
        "radius_window_d0": window,
        "scenes": {k: {"comparison": v} for k, v in comp.items()},
        "indent_axial": axial,
        "rod_steps": {"indent": ind["steps"], "wrap": wr["steps"]},
        "rod_wall_time_s": rod_time,
        "default_level_rod_wall_time_s": rod_ind["wall_time_s"] + rod_wr["wall_time_s"],
        "fem_over_rod_time_ratio": fem_time / rod_time,
        "passed": all(c["passed"] for c in comp.values()) and fem_time / rod_time >= 1000.0,
    }


def _warm_up() -> float:
    """Build and solve a tiny contact problem once so that Warp compiles its kernels
    outside the timed runs; return the time it took [s]."""
    start = time.perf_counter()
    rod_indent([0.01 * ROD_DIAMETER], length_over_d0=1.5)
    return time.perf_counter() - start


def crosscheck(mesh: str = DEFAULT_MESH, fem_results: dict[str, dict] | None = None,
               contact: str = "compliant", section_modes: int = 8, soft: bool = True,
               bend_shift: bool = False, thinning: str = "edge",
               rod_edges_per_d0: int = EDGES_PER_D0) -> dict[str, Any]:
    """Run indent and wrap with the FEM (``mesh``) and the rod model at the contact level
    ``contact`` (:data:`CONTACT_LEVELS`; ``section_modes``: the sectioned level's N,
    ``bend_shift``: its sections centred on the bend's offset centreline, ``thinning``:
    the stretch that thins them, :class:`~tightknot.contact.sectioned.SectionSettings`;
    ``rod_edges_per_d0``: the sectioned rod scenes' resolution, the two-soft-rod scenes'
    too, docs/sectioned_level.md, "Resolution") and
    compare them; with ``soft``, also the two-soft-rod scenes soft_wrap, clasp and
    soft_crossing (:mod:`tightknot.fem.crosscheck_soft`: key ``soft_scenes``, at every level of
    :data:`~tightknot.fem.rod_model_soft.CONTACT_LEVELS` in a compliant report, at the
    sectioned level in a sectioned one; that level's ``passed`` part of the report's).

    ``fem_results`` may hold already computed FEM results (keys "indent", "wrap",
    "soft_wrap", "clasp", "soft_crossing", each scene on the spread mesh,
    "soft_wrap@coarse" ..., and optionally on the next finer mesh, "soft_wrap@fine" ...,
    run with the default load levels, as a report's ``fem_results`` keeps them) to reuse;
    their own ``wall_time_s`` then enters the ratio. Returns the JSON-serialisable report
    (module docstring): per-scene comparisons, ``fem_over_rod_time_ratio``, ``passed``.
    """
    if mesh not in MESH_LEVELS:
        raise ValueError(f"mesh must be one of {MESH_LEVELS}, got {mesh!r}")
    if contact not in CONTACT_LEVELS:
        raise ValueError(f"contact must be one of {', '.join(CONTACT_LEVELS)}, got "
                         f"{contact!r}")
    if contact == "sectioned":
        from tightknot.contact.sectioned import SectionSettings

        # bad input first
        SectionSettings(max_mode=section_modes, bend_shift=bend_shift, thinning=thinning)
        check_edges_per_d0(rod_edges_per_d0)
    elif rod_edges_per_d0 != EDGES_PER_D0:
        raise ValueError(f"rod_edges_per_d0 is a setting of the sectioned level's rod scenes "
                         f"(contact sectioned), got contact {contact!r}")
    start = time.perf_counter()
    # each scene on ``mesh`` and, for the FEM's own spread beside each compared level, on
    # the next coarser mesh
    fem_results = fem_runs(mesh, fem_results, ("indent", "wrap"))
    fem_ind, fem_wrap = fem_results["indent"], fem_results["wrap"]
    coarser = spread_mesh(mesh)
    spread = {name: None if coarser is None else fem_results[f"{name}@{coarser}"]["steps"]
              for name in ("indent", "wrap")}
    # the next finer mesh where a run of it was given: the third mesh of the spread
    finest = finer_mesh(mesh)
    finer = {name: (fem_results[f"{name}@{finest}"]["steps"]
                    if f"{name}@{finest}" in fem_results else None)
             for name in ("indent", "wrap")}
    if contact == "sectioned":
        report = _sectioned_report(mesh, fem_ind, fem_wrap, section_modes, start, bend_shift,
                                   thinning, rod_edges_per_d0, spread, finer)
        report["fem_results"].update({k: v for k, v in fem_results.items()
                                      if k.startswith(("indent@", "wrap@"))})
        if soft:
            from tightknot.contact.sectioned import SectionSettings

            from .crosscheck_soft import soft_rows

            fem_results = fem_runs(mesh, fem_results)
            section = SectionSettings(max_mode=section_modes, bend_shift=bend_shift,
                                      thinning=thinning)
            report["soft_scenes"] = soft_rows(mesh, fem_results, section=section,
                                              levels=("sectioned",),
                                              edges_per_d0=rod_edges_per_d0)
            report["fem_results"].update({k: v for k, v in fem_results.items()
                                          if k not in ("indent", "wrap")})
            report["passed"] = report["passed"] and report["soft_scenes"]["passed"]
            report["wall_time_s"] = time.perf_counter() - start
        return finite(report)
    warm = _warm_up()
    rod_ind = _rod_indent_like(fem_ind)
    rod_wr = _rod_wrap_like(fem_wrap)
    wp_ = fem_wrap["parameters"]
    diagnostics = _indent_diagnostics(fem_ind, rod_ind)
    diagnostics["indent_footprint"] = _indent_footprint(fem_ind, rod_ind)
    diagnostics["wrap_kernel_variants"] = _wrap_variants(fem_wrap)
    smoothed = _smoothed_level(fem_ind, fem_wrap, rod_ind, rod_wr, spread, finer)
    fem_time = fem_ind["wall_time_s"] + fem_wrap["wall_time_s"]
    rod_time = rod_ind["wall_time_s"] + rod_wr["wall_time_s"]
    scenes = {
        "indent": {
            "force": "force on one side [N] (point contact)",
            "curvature": "not compared: the axis stays straight by symmetry in both models",
            "fem_mesh": fem_ind["mesh"], "fem_wall_time_s": fem_ind["wall_time_s"],
            "rod_wall_time_s": rod_ind["wall_time_s"], "rod_vertices": rod_ind["vertices"],
            "comparison": _compare(fem_ind["steps"], rod_ind["steps"], ("force", "force"),
                                   None, spread_steps=spread["indent"],
                                   finer_steps=finer["indent"]),
            "fem_steps": fem_ind["steps"], "rod_steps": rod_ind["steps"],
        },
        "wrap": {
            "force": "contact line load at the middle of the wrap [N/m]",
            "fem_mesh": fem_wrap["mesh"], "fem_wall_time_s": fem_wrap["wall_time_s"],
            "rod_wall_time_s": rod_wr["wall_time_s"], "rod_vertices": rod_wr["vertices"],
            "wrap_angle_deg": wp_["wrap_angle_deg"],
            "comparison": _compare(fem_wrap["steps"], rod_wr["steps"],
                                   ("force_per_length_mid_nominal", "force_per_length_mid"),
                                   "kappa_d0_mid_nominal", spread_steps=spread["wrap"],
                                   finer_steps=finer["wrap"]),
            "centroid_axis": _wrap_centroid_axis(fem_wrap["steps"], rod_wr["steps"]),
            "total_force_statics": [
                {"tension_over_e_d0sq": f["tension_over_e_d0sq"],
                 "fem_over_2T_sin_theta": f["contact_force_total"]
                 / (2 * f["tension"] * math.sin(math.radians(wp_["wrap_angle_deg"]) / 2)),
                 "rod_over_2T_sin_theta": r["contact_force_total"]
                 / (2 * f["tension"] * math.sin(math.radians(wp_["wrap_angle_deg"]) / 2))}
                for f, r in zip(fem_wrap["steps"], rod_wr["steps"], strict=True)],
            "fem_steps": fem_wrap["steps"], "rod_steps": rod_wr["steps"],
        },
    }
    report = {
        "schema": "tightknot.fem_crosscheck/1",
        "mesh": mesh,
        "approach_limit_over_d0": APPROACH_LIMIT,
        "targets": TARGETS,
        "law": "tightknot/data/contact_law.json, rigid counter-body pair law (k 2^p)",
        "scenes": scenes,
        "diagnostics": diagnostics,
        "fem_wall_time_s": fem_time,
        "rod_wall_time_s": rod_time,
        "rod_warm_up_s": warm,
        "fem_over_rod_time_ratio": fem_time / rod_time,
        "smoothed_contact_level": smoothed,
        "rod_at_least_1000x_faster": fem_time / rod_time >= 1000.0,
        "passed": (all(s["comparison"]["passed"] for s in scenes.values())
                   and fem_time / rod_time >= 1000.0),
        "contact": "compliant",
        "fem_results": {k: v for k, v in fem_results.items()
                        if k in ("indent", "wrap") or k.startswith(("indent@", "wrap@"))},
    }
    if soft:
        from .crosscheck_soft import soft_rows

        fem_results = fem_runs(mesh, fem_results)
        report["soft_scenes"] = soft_rows(mesh, fem_results)
        report["fem_results"].update({k: v for k, v in fem_results.items()
                                      if k not in ("indent", "wrap")})
        report["passed"] = report["passed"] and report["soft_scenes"]["passed"]
    report["wall_time_s"] = time.perf_counter() - start
    return finite(report)


def _sectioned_report(mesh: str, fem_ind: dict[str, Any], fem_wrap: dict[str, Any],
                      section_modes: int, start: float, bend_shift: bool = False,
                      thinning: str = "edge", edges_per_d0: int = EDGES_PER_D0,
                      spread: dict[str, list[dict] | None] | None = None,
                      finer: dict[str, list[dict] | None] | None = None
                      ) -> dict[str, Any]:
    """The cross-check of the sectioned level (:mod:`tightknot.fem.rod_sectioned`): force,
    A/A0, L_c and (wrap) curvature at every level, against the targets."""
    from tightknot.contact.sectioned import SectionSettings

    from .rod_sectioned import rod_indent_sectioned, rod_wrap_sectioned

    section = SectionSettings(max_mode=section_modes, bend_shift=bend_shift, thinning=thinning)
    t0 = time.perf_counter()
    rod_indent_sectioned([0.01 * ROD_DIAMETER], length_over_d0=1.5, section=section)
    warm = time.perf_counter() - t0
    rod_ind = _rod_indent_like(fem_ind, rod_indent_sectioned, section=section,
                               edges_per_d0=edges_per_d0)
    rod_wr = _rod_wrap_like(fem_wrap, rod_wrap_sectioned, section=section,
                            edges_per_d0=edges_per_d0)
    fem_time = fem_ind["wall_time_s"] + fem_wrap["wall_time_s"]
    rod_time = rod_ind["wall_time_s"] + rod_wr["wall_time_s"]
    scenes = {
        "indent": {
            "force": "force on one side [N] (point contact)",
            "fem_mesh": fem_ind["mesh"], "fem_wall_time_s": fem_ind["wall_time_s"],
            "rod_wall_time_s": rod_ind["wall_time_s"], "rod_vertices": rod_ind["vertices"],
            "comparison": _compare(fem_ind["steps"], rod_ind["steps"], ("force", "force"),
                                   None, width_scene="indent",
                                   spread_steps=(spread or {}).get("indent"),
                                   finer_steps=(finer or {}).get("indent")),
            "fem_steps": fem_ind["steps"], "rod_steps": rod_ind["steps"],
        },
        "wrap": {
            "force": "contact line load at the middle of the wrap [N/m] (nominal axis)",
            "fem_mesh": fem_wrap["mesh"], "fem_wall_time_s": fem_wrap["wall_time_s"],
            "rod_wall_time_s": rod_wr["wall_time_s"], "rod_vertices": rod_wr["vertices"],
            "comparison": _compare(fem_wrap["steps"], rod_wr["steps"],
                                   ("force_per_length_mid_nominal", "force_per_length_mid"),
                                   "kappa_d0_mid_nominal", width_scene="wrap",
                                   spread_steps=(spread or {}).get("wrap"),
                                   finer_steps=(finer or {}).get("wrap")),
            "centroid_axis": [
                {"tension_over_e_d0sq": f["tension_over_e_d0sq"],
                 "fem_kappa_d0_centroid": f["kappa_d0_mid"],
                 "rod_kappa_d0_centroid": r["kappa_d0_mid_centroid"],
                 "curvature_rel_centroid": relative(r["kappa_d0_mid_centroid"],
                                                    f["kappa_d0_mid"]),
                 "force_rel_centroid_axis": relative(r["force_per_length_mid_centroid"],
                                                     f["force_per_length_mid"]),
                 "rod_kappa_d0_centerline": r["kappa_d0_mid_centerline"]}
                for f, r in zip(fem_wrap["steps"], rod_wr["steps"], strict=True)
                if f["approach_over_d0"] <= APPROACH_LIMIT + 1e-9],
            "fem_steps": fem_wrap["steps"], "rod_steps": rod_wr["steps"],
        },
    }
    report = {
        "schema": "tightknot.fem_crosscheck/1",
        "contact": "sectioned",
        "section_modes": section_modes,
        "section_bend_shift": bend_shift,
        "section_thinning": thinning,
        "rod_edges_per_d0": edges_per_d0,
        "penalty_over_e_per_d0": rod_ind["penalty"],
        "mesh": mesh,
        "approach_limit_over_d0": APPROACH_LIMIT,
        "targets": TARGETS,
        "calibration": "tightknot/data/section_calibration.json (the penalty fitted to the "
                       "FEM's plane-strain squeeze; the decay lengths from rod_mode_decay)",
        "scenes": scenes,
        "fem_wall_time_s": fem_time,
        "rod_wall_time_s": rod_time,
        "rod_warm_up_s": warm,
        "fem_over_rod_time_ratio": fem_time / rod_time,
        "rod_at_least_1000x_faster": fem_time / rod_time >= 1000.0,
        "passed": (all(s["comparison"]["passed"] for s in scenes.values())
                   and fem_time / rod_time >= 1000.0),
        "wall_time_s": time.perf_counter() - start,
        "fem_results": {"indent": fem_ind, "wrap": fem_wrap},
    }
    return finite(report)
