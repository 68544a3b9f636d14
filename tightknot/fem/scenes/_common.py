"""Shared pieces of the FEM scenes: argument checks, load schedules, tables."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

MESH_LEVELS: tuple[str, ...] = ("coarse", "medium", "fine")
"""Mesh refinement levels, coarsest first."""

PENALTY_FACTOR: float = 100.0
"""Penalty stiffness eps = 100 E / h_min [Pa/m]: penetration ~ (p/E) h / 100, i.e. below
0.5 % of the smallest contact element for the pressures met here (p < 0.5 E)."""

SMOOTHING_FACTOR: float = 1e-3
"""Penalty onset depth g0 = 1e-3 h_min [m]: C2 onset without a visible force error."""


def check_common(mesh: str, max_approach_over_d0: float, steps: int) -> None:
    """Raise ValueError naming the parameter and its valid range for bad common input."""
    if mesh not in MESH_LEVELS:
        raise ValueError(f"mesh must be one of {MESH_LEVELS}, got {mesh!r}")
    if not (isinstance(max_approach_over_d0, (int, float)) and math.isfinite(max_approach_over_d0)
            and 0.0 < max_approach_over_d0 < 1.0):
        raise ValueError(
            f"max_approach_over_d0 must lie in (0, 1) (total approach below one diameter), "
            f"got {max_approach_over_d0!r}"
        )
    if not isinstance(steps, int) or isinstance(steps, bool) or steps < 1:
        raise ValueError(f"steps must be an integer >= 1, got {steps!r}")


def check_positive(name: str, value: float) -> None:
    """Raise ValueError if ``value`` is not a finite number > 0."""
    if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0.0):
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")


def load_schedule(max_value: float, steps: int) -> np.ndarray:
    """Load values max_value (k/steps)^2, k = 1..steps: quadratic spacing puts several
    steps in the small-strain range where the Hertz checks apply."""
    k = np.arange(1, steps + 1)
    return max_value * (k / steps) ** 2


def relative(a: float, b: float) -> float:
    """Relative difference (a - b) / |b| [-] (0 when both vanish)."""
    if b == 0.0:
        return 0.0 if a == 0.0 else math.copysign(1.0, a)
    return (a - b) / abs(b)


def convergence_table(run: Callable[[str], dict[str, Any]], keys: Sequence[str],
                      first: dict[str, Any] | None = None, level: str | None = None
                      ) -> tuple[dict[str, Any], dict[str, dict[str, Any]]]:
    """Run all mesh levels and tabulate ``keys`` of the last load step.

    ``run(level)`` returns a scene result; ``first`` (already run at ``level``) is reused.
    Returns the table (per mesh: elements, values, relative differences to the finest)
    and the results per level.
    """
    results: dict[str, dict[str, Any]] = {}
    for lvl in MESH_LEVELS:
        results[lvl] = first if (first is not None and lvl == level) else run(lvl)
    finest = results[MESH_LEVELS[-1]]["steps"][-1]
    table: dict[str, Any] = {"keys": list(keys), "at": "last load step", "meshes": []}
    for lvl in MESH_LEVELS:
        last = results[lvl]["steps"][-1]
        table["meshes"].append({
            "mesh": lvl,
            "elements": results[lvl]["mesh"]["elements"],
            "values": {k: last[k] for k in keys},
            "relative_difference_to_finest": {k: relative(last[k], finest[k]) for k in keys},
            "wall_time_s": results[lvl]["wall_time_s"],
        })
    return table, results


def mesh_convergence(run: Callable[[str], dict[str, Any]], keys: Sequence[str],
                     first: dict[str, Any], level: str, computed: bool) -> dict[str, Any]:
    """A scene result's ``mesh_convergence`` entry: the table of :func:`convergence_table`
    when ``computed``, else a note saying how to get it."""
    if not computed:
        return {"computed": False, "reason": "run with convergence=True for the table"}
    return convergence_table(run, keys, first=first, level=level)[0]


def check_dhat(dhat_over_d0: float) -> None:
    """The barrier's activation distance over D0 must lie in [1e-6, 1e-2]."""
    if not (isinstance(dhat_over_d0, (int, float)) and 1e-6 <= dhat_over_d0 <= 1e-2):
        raise ValueError(f"dhat_over_d0 must lie in [1e-6, 1e-2], got {dhat_over_d0!r}")


def finite(obj: Any) -> Any:
    """Convert NumPy scalars to Python and replace non-finite floats by None (JSON-safe)."""
    if isinstance(obj, dict):
        return {str(k): finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [finite(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return finite(obj.tolist())
    if isinstance(obj, (np.bool_, bool)):
        return bool(obj)
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        value = float(obj)
        return value if math.isfinite(value) else None
    return obj
