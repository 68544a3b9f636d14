"""The sectioned contact level's calibration from the FEM: the section's local compliance.

The sectioned level (:mod:`tightknot.contact.sectioned`) carries the section's boundary as
Fourier modes up to N. Their plane-strain energy is closed form and confirmed by the FEM
(docs/sectioned_level.md); their spread along the rod is the FEM's decay lengths
(:data:`tightknot.contact.section_field.DECAY_LENGTH_OVER_D0`). What the truncated series
cannot hold is the compliance of the modes above N, which a narrow contact patch loads: the
contact's penalty stands for it, a surface layer of stiffness kappa = penalty E / D0 (the
pressure per penetration).

:func:`calibrate_section_penalty` fits ``penalty`` for each N to the FEM's plane-strain
squeeze (:mod:`tightknot.fem.scenes.squeeze`: a section between two rigid plates, the 2D
problem of the modes alone): the penalty that minimises the largest relative error of the
force per length of :class:`tightknot.contact.section_squeeze.SectionSqueeze` over the
squeeze's levels where the FEM is converged (its ``check_mesh`` within
``CONVERGED`` of ``mesh``). The 3D scenes (indent, wrap, crossings) then judge it
(``tightknot fem crosscheck --contact sectioned``, docs/sectioned_level.md).

:func:`area_range` measures how thin a section the FEM confirms: the rigid wrap pulled
further than the cross-check pulls it (:data:`AREA_RANGE_TENSION`), the sectioned level
compared at every tension within the cross-check's approach limit, and the smallest FEM
area A/A0 at which every target is met (:func:`judged_area_ratio`). A knot whose sections
thin below it says so in its summary (``tightknot.study.run.calibration_range``).
"""

from __future__ import annotations

import datetime
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

#: FEM levels whose check mesh is within this relative force of the calibration mesh enter
#: the fit: a reference that is itself off by more cannot calibrate a percent.
CONVERGED = 0.01

#: The rigid wrap that judges the sections' area: end tensions up to this [E D0^2] in
#: :data:`AREA_RANGE_STEPS` levels (quadratic spacing), further than the cross-check's
#: 0.25, so that its deepest levels within the approach limit thin the section more.
AREA_RANGE_TENSION: float = 0.5
AREA_RANGE_STEPS: int = 8

#: The calibration file's keys that :func:`write_area_range` owns.
AREA_KEYS: tuple[str, ...] = ("validated_min_area_ratio", "area_range")

#: Where the calibration is shipped.
CALIBRATION_FILE = Path(__file__).resolve().parents[1] / "data" / "section_calibration.json"


def calibrate_section_penalty(modes: range | list[int] = range(4, 13), mesh: str = "fine",
                              check_mesh: str = "medium", steps: int = 24,
                              max_approach_over_d0: float = 0.3) -> dict[str, Any]:
    """Fit the penalty of each mode count N in ``modes`` to the FEM squeeze (module
    docstring). Returns the calibration record: per N the penalty [E/D0] and the largest
    error it leaves, the FEM's levels and forces, and the provenance."""
    from scipy.optimize import minimize_scalar

    from tightknot.contact.section_field import DECAY_LENGTH_OVER_D0
    from tightknot.contact.section_squeeze import SectionSqueeze
    from tightknot.fem.scenes import squeeze

    runs = {m: squeeze.run(mesh=m, max_approach_over_d0=max_approach_over_d0, steps=steps,
                           convergence=False) for m in (mesh, check_mesh)}
    ws = np.array([s["w_over_d0"] for s in runs[mesh]["steps"]])
    force = np.array([s["force_per_length_over_e_d0"] for s in runs[mesh]["steps"]])
    check = np.array([s["force_per_length_over_e_d0"] for s in runs[check_mesh]["steps"]])
    keep = np.abs(check / force - 1.0) <= CONVERGED
    w_fit, f_fit = ws[keep], force[keep]
    fits = {}
    for n in modes:
        def worst(log_p: float, n: int = n) -> float:
            out = SectionSqueeze(max_mode=n, penalty_factor=10.0**log_p).path(list(w_fit))
            f = np.array([s.force_per_length_over_e_d0 for s in out])
            return float(np.max(np.abs(f / f_fit - 1.0)))

        best = minimize_scalar(worst, bounds=(0.5, 3.5), method="bounded",
                               options={"xatol": 1e-3})
        fits[str(n)] = {"penalty": round(10.0**best.x, 2), "max_force_error": float(best.fun)}
    return {
        "schema": "tightknot.section_calibration/1",
        "decay_length_over_d0": {str(k): v for k, v in DECAY_LENGTH_OVER_D0.items()},
        "penalty_by_max_mode": fits,
        "fem": {"scene": "squeeze (plane strain)", "mesh": mesh, "check_mesh": check_mesh,
                "w_over_d0": ws.tolist(), "force_per_length_over_e_d0": force.tolist(),
                "check_force_per_length_over_e_d0": check.tolist(),
                "fitted_levels": int(keep.sum()),
                "fitted_w_over_d0": [float(w_fit[0]), float(w_fit[-1])]},
        # The deepest indent level of the FEM cross-check (crosscheck --contact sectioned).
        "validated_crossing_w_over_d0": 0.1215,
        "provenance": {"date": datetime.date.today().isoformat(),
                       "function": "tightknot.fem.section_calibration."
                                   "calibrate_section_penalty",
                       "converged_within": CONVERGED},
    }


def write_section_calibration(record: dict[str, Any], path: str | Path = CALIBRATION_FILE
                              ) -> Path:
    """Write a calibration record as JSON (atomically) and return the path. The file's
    area range (:func:`write_area_range`), measured apart from the penalty, is kept."""
    if not all(math.isfinite(v["penalty"]) for v in record["penalty_by_max_mode"].values()):
        raise ValueError("a fitted penalty is not finite")
    path = Path(path)
    old = json.loads(path.read_text()) if path.exists() else {}
    kept = {k: old[k] for k in AREA_KEYS if k in old and k not in record}
    return _write(path, {**record, **kept})


def _write(path: Path, record: dict[str, Any]) -> Path:
    from tightknot.atomic import atomic_open

    with atomic_open(path, "w") as fh:
        json.dump(record, fh, indent=2)
        fh.write("\n")
    return path


def judged_area_ratio(levels: list[dict[str, Any]]) -> dict[str, Any] | None:
    """Of the cross-check's compared levels (rows of :func:`tightknot.fem.crosscheck.
    _compare`, each with ``fem_area_ratio`` and ``met``), the one with the thinnest FEM
    section among those that meet every target; None when none does."""
    met = [row for row in levels if row["met"] and all(row["met"].values())]
    return min(met, key=lambda row: row["fem_area_ratio"], default=None)


def area_range(fem_wrap: dict[str, Any], section: Any = None,
               spread: dict[str, dict[str, Any]] | None = None) -> dict[str, Any]:
    """The sections' area range the FEM confirms (module docstring): the sectioned level
    (``section``: its :class:`~tightknot.contact.sectioned.SectionSettings`, default
    settings when None) in the wrap at the tensions of the FEM wrap result ``fem_wrap``,
    compared as the cross-check compares it (targets and approach limit of
    :mod:`tightknot.fem.crosscheck_targets`; the levels past the limit are reported, not
    judged). ``spread``: FEM wrap results of other meshes at the same tensions (a mesh's
    run may stop early), reported at the judged level beside the comparison. Returns the
    record :func:`write_area_range` stores, with ``judged_area_ratio`` (None when no level
    meets every target)."""
    from tightknot.contact.sectioned import SectionSettings

    from .crosscheck import _compare, _rod_wrap_like
    from .crosscheck_targets import APPROACH_LIMIT, TARGETS
    from .rod_sectioned import rod_wrap_sectioned
    from .scenes._common import finite

    section = section or SectionSettings()
    rod = _rod_wrap_like(fem_wrap, rod_wrap_sectioned, section=section)

    def compared(limit: float) -> list[dict[str, Any]]:
        return _compare(fem_wrap["steps"], rod["steps"],
                        ("force_per_length_mid_nominal", "force_per_length_mid"),
                        "kappa_d0_mid_nominal", width_scene="wrap", limit=limit)["levels"]

    levels = compared(APPROACH_LIMIT)
    past = compared(math.inf)[len(levels):]
    judged = judged_area_ratio(levels)
    at = None if judged is None else levels.index(judged)
    keys = ("approach_over_d0", "fem_force", "rod_force", "force_rel", "fem_area_ratio",
            "rod_area_ratio", "area_points", "curvature_rel", "fem_width_fraction",
            "rod_width_fraction", "width_fraction", "met")
    spread_rows = {}
    if at is not None:
        for mesh, other in (spread or {}).items():
            if len(other["steps"]) > at:
                f, m = fem_wrap["steps"][at], other["steps"][at]
                spread_rows[mesh] = {
                    "force_rel": m["force_per_length_mid_nominal"]
                    / f["force_per_length_mid_nominal"] - 1.0,
                    "area_points": m["area_ratio_mid"] - f["area_ratio_mid"]}
    par = fem_wrap["parameters"]
    return finite({
        "scene": "wrap (rigid cylinder, frictionless)",
        "fem_mesh": fem_wrap["mesh"],
        "wrap_angle_deg": par["wrap_angle_deg"],
        "tension_over_e_d0sq": [s["tension_over_e_d0sq"] for s in fem_wrap["steps"]],
        "approach_limit_over_d0": APPROACH_LIMIT,
        "targets": TARGETS,
        "section_modes": section.max_mode,
        "levels": [{k: row.get(k) for k in keys} for row in levels],
        # past the approach limit: reported, not judged (the targets' range ends there)
        "past_approach_limit": [{k: row.get(k) for k in keys} for row in past],
        "judged_area_ratio": None if judged is None else judged["fem_area_ratio"],
        "judged_tension_over_e_d0sq": (
            None if at is None else fem_wrap["steps"][at]["tension_over_e_d0sq"]),
        "mesh_spread_at_judged_level": spread_rows,
        "fem_wall_time_s": fem_wrap["wall_time_s"],
        "rod_wall_time_s": rod["wall_time_s"],
        "provenance": {"date": datetime.date.today().isoformat(),
                       "function": "tightknot.fem.section_calibration.area_range"},
    })


def write_area_range(record: dict[str, Any], path: str | Path = CALIBRATION_FILE) -> Path:
    """Store an :func:`area_range` record in the calibration file (atomically): its
    judged area as ``validated_min_area_ratio``, which a sectioned run's summary compares
    its thinnest section with, and the record beside it. Refused when no level met every
    target."""
    if record["judged_area_ratio"] is None:
        raise ValueError("the area range has no level that meets every target: nothing "
                         "to validate")
    path = Path(path)
    old = json.loads(path.read_text())
    old.pop("validated_min_area_note", None)
    return _write(path, {**old, "validated_min_area_ratio": record["judged_area_ratio"],
                         "area_range": record})
