"""Run one sweep case: build its scene, solve it, return its JSON record.

:func:`run_case` is the function the executors ship to their workers: a top-level function
of plain JSON data (picklable, importable in a spawned process or a Dask worker), returning
plain JSON data. It never raises for a case that fails: a physics failure gives status
"failed", an exception status "error" with its message, so one bad case does not stop a
sweep.
"""

from __future__ import annotations

import os
import platform
import time
import traceback
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from tightknot.sweep.cases import Case
from tightknot.sweep.store import ERROR, FAILED, OK

if TYPE_CHECKING:
    from tightknot.knots.scenes import KnotScene

#: Keys of a record that depend on the machine and the moment, not on the physics.
TIMING_KEYS = ("wall_time_s", "cumulative_wall_time_s", "tie_wall_time_s", "host", "pid")


def build_scene(params: Mapping[str, Any], device: str = "cpu") -> KnotScene:
    """The :class:`~tightknot.knots.scenes.KnotScene` of canonical case ``params``."""
    from tightknot.knots import scenes
    from tightknot.rods.material import Material

    material = Material(params["youngs_modulus"], params["poisson"], params["density"])
    name = {"3_1": "trefoil", "4_1": "figure_eight"}[params["knot_type"]]
    make = getattr(scenes, f"{params['knot']}_{name}")
    length = params["l0_over_d0"] if params["knot"] == "closed" else params["length"]
    return make(length, params["diameter"], params["nodes"], material, twist=params["twist"],
                contact=params["contact"], device=device)


def solve_case(case: Case, device: str = "cpu") -> dict[str, Any]:
    """Solve ``case``; returns {"status", "failure", "result"} (may raise)."""
    p = case.params
    scene = build_scene(p, device)
    if p["knot"] == "closed":
        from tightknot.knots.run import run_knot

        run = run_knot(scene, tighten_steps=p["tighten_steps"], residual_tol=p["residual_tol"])
        ok = run.result.converged
        return {"status": OK if ok else FAILED, "failure": run.result.failure,
                "result": run.summary}
    from tightknot.sweep.path import level_table, tightness_path

    key = "pull_force" if "pull_force" in p else "target_lambda"
    path = tightness_path(scene, **{key: p[key]}, lambda_tolerance=p["lambda_tolerance"],
                          residual_tol=p["residual_tol"], tighten_steps=p["tighten_steps"])
    levels = [lv.as_dict() for lv in path.levels]
    cumulative = path.tie_wall_time_s
    for lv in levels:
        cumulative += lv["wall_time_s"]
        lv["cumulative_wall_time_s"] = cumulative
    result = {
        "scene": scene.name,
        "nodes": scene.model.vertex_count,
        "tie_newton_iterations": path.tie.newton_iterations,
        "tie_wall_time_s": path.tie_wall_time_s,
        "knot_types": sorted(set(path.knot_types)),
        "table": level_table(path),
        "levels": levels,
    }
    for row in result["table"]:
        row.pop("wall_time_s", None)  # timings live in "levels"; the table is the physics
    return {"status": OK if path.converged else FAILED, "failure": path.failure,
            "result": result}


def run_case(params: Mapping[str, Any], device: str = "cpu") -> dict[str, Any]:
    """The record of one case: {"id", "params", "status", "failure", "result",
    "wall_time_s", "host", "pid"}. Never raises for a failing case (module docstring)."""
    from tightknot.warp_setup import init_warp

    case = Case.of(params)
    start = time.perf_counter()
    try:
        init_warp()
        out = solve_case(case, device)
    except Exception as err:  # noqa: BLE001 (one case's crash must not stop the sweep)
        tb = traceback.format_exception_only(type(err), err)[-1].strip()
        out = {"status": ERROR, "failure": tb, "result": None}
    return {"id": case.id, "params": case.params, **out,
            "wall_time_s": time.perf_counter() - start,
            "host": platform.node(), "pid": os.getpid()}


def physics(record: Mapping[str, Any]) -> Any:
    """``record`` without the machine- and time-dependent keys (:data:`TIMING_KEYS`), for
    comparing two runs of the same case."""
    if isinstance(record, Mapping):
        return {k: physics(v) for k, v in record.items() if k not in TIMING_KEYS}
    if isinstance(record, list):
        return [physics(v) for v in record]
    return record
