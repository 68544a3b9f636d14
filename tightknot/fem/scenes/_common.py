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


def level_table(results: dict[str, dict[str, Any]], keys: Sequence[str], load_key: str
                ) -> list[dict[str, Any]]:
    """The three-mesh table at every load level: ``results`` maps mesh levels (of
    :data:`MESH_LEVELS`) to results of one scene at the same load levels (each step's
    ``load_key``, equal to 1e-12 relative); per level the finest mesh's values of ``keys``
    and each other mesh's relative difference to them (as :func:`convergence_table` at the
    last level). A key a result lacks is None."""
    meshes = [m for m in MESH_LEVELS if m in results]
    if len(meshes) != len(results) or len(meshes) < 2:
        raise ValueError(f"level_table: results on two or more of {MESH_LEVELS} needed, "
                         f"got {sorted(results)}")
    finest = results[meshes[-1]]["steps"]
    if any(len(results[m]["steps"]) != len(finest) for m in meshes):
        raise ValueError("level_table: the meshes' results have different load levels "
                         f"({[len(results[m]['steps']) for m in meshes]} steps)")
    for m in meshes:
        for a, b in zip(results[m]["steps"], finest, strict=True):
            if abs(relative(a[load_key], b[load_key])) > 1e-12:
                raise ValueError(f"level_table: {m}'s {load_key} {a[load_key]!r} is not the "
                                 f"{meshes[-1]} mesh's {b[load_key]!r}")
    rows = []
    for k, top in enumerate(finest):
        row: dict[str, Any] = {"step": k, "finest": meshes[-1], "load": top[load_key],
                               "values": {key: top.get(key) for key in keys}, "relative": {}}
        for m in meshes[:-1]:
            other = results[m]["steps"][k]
            row["relative"][m] = {
                key: (relative(other[key], top[key])
                      if other.get(key) is not None and top.get(key) is not None else None)
                for key in keys}
        rows.append(row)
    return rows


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
