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
        # The smallest FEM A/A0 the cross-check compares the sections' area at (the wrap's
        # deepest level, medium mesh; the sectioned level 0.7 points from it).
        "validated_min_area_ratio": 0.6927,
        "provenance": {"date": datetime.date.today().isoformat(),
                       "function": "tightknot.fem.section_calibration."
                                   "calibrate_section_penalty",
                       "converged_within": CONVERGED},
    }


def write_section_calibration(record: dict[str, Any], path: str | Path = CALIBRATION_FILE
                              ) -> Path:
    """Write a calibration record as JSON (atomically) and return the path."""
    from tightknot.atomic import atomic_open

    if not all(math.isfinite(v["penalty"]) for v in record["penalty_by_max_mode"].values()):
        raise ValueError("a fitted penalty is not finite")
    path = Path(path)
    with atomic_open(path, "w") as fh:
        json.dump(record, fh, indent=2)
        fh.write("\n")
    return path
