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
from typing import Any

from tightknot.study.params import build_scene
from tightknot.sweep.cases import Case
from tightknot.sweep.store import ERROR, FAILED, OK

#: Keys of a record that depend on the machine, the moment and how the case was run (alone
#: or in a batch), not on the physics.
TIMING_KEYS = ("wall_time_s", "cumulative_wall_time_s", "tie_wall_time_s", "host", "pid",
               "batch")
#: Parameters that every case of one batch shares (tie_batch ties them in one call, with
#: one twist setting, one contact law, one load path); the rest (L0/D0, E, nu, D0, nodes,
#: knot type) may differ from rod to rod.
BATCH_KEYS = ("knot", "twist", "contact", "tighten_steps", "residual_tol")


def batch_key(params: Mapping[str, Any]) -> tuple | None:
    """What a case shares with the others of its batch, or None when it cannot be batched
    (open knots: tie_batch ties closed knots only; the "smoothed" contact level: its
    Hessian couples whole windows of a rod, outside the batch's banded systems; the
    "sectioned" level: its section dofs are outside them too)."""
    if params["knot"] != "closed" or params.get("contact") in ("smoothed", "sectioned"):
        return None
    return tuple(params[k] for k in BATCH_KEYS)


def solve_case(case: Case, device: str = "cpu") -> dict[str, Any]:
    """Solve ``case``; returns {"status", "failure", "result"} (may raise)."""
    p = case.params
    scene = build_scene(p, device)
    if p["knot"] == "closed":
        from tightknot.study.run import run_knot

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
    # A level the path could not reach does not undo the others: the case is ok when the
    # tie held and some level was reached, each missed level a warning.
    reached = any(lv.reached for lv in path.levels)
    missed = [f"level {lv.kind} = {lv.target:g} not reached: {lv.failure}"
              for lv in path.levels if not lv.reached]
    ok = path.converged or reached
    return {"status": OK if ok else FAILED, "failure": "" if ok else path.failure,
            "warnings": missed, "result": result}


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
    out.setdefault("warnings", [])
    return {"id": case.id, "params": case.params, **out,
            "wall_time_s": time.perf_counter() - start,
            "host": platform.node(), "pid": os.getpid()}


def run_batch(params_list: list[Mapping[str, Any]], device: str = "cpu") -> list[dict[str, Any]]:
    """The records of closed-knot cases tied together in one model
    (:func:`tightknot.loading.batch.tie_batch`: every rod runs tie()'s own program, all rods'
    evaluations answered by one set of launches per round), in the order given. Each
    record is that of :func:`run_case` (the same summary, measured the same way), with
    ``wall_time_s`` the whole batch's and ``batch`` saying which batch it was run in. Never
    raises for failing cases: an exception gives every case of the batch status "error"."""
    from tightknot.warp_setup import init_warp

    cases = [Case.of(p) for p in params_list]
    start = time.perf_counter()
    try:
        keys = {batch_key(c.params) for c in cases}
        if None in keys or len(keys) != 1:
            raise ValueError("a batch holds closed-knot cases that share "
                             f"{', '.join(BATCH_KEYS)}")
        init_warp()
        outs = _solve_batch(cases, device)
    except Exception as err:  # noqa: BLE001 (as run_case)
        tb = traceback.format_exception_only(type(err), err)[-1].strip()
        outs = [{"status": ERROR, "failure": tb, "result": None}] * len(cases)
    wall = time.perf_counter() - start
    host, pid = platform.node(), os.getpid()
    return [{"id": c.id, "params": c.params, **out, "wall_time_s": wall, "host": host,
             "pid": pid, "batch": {"rods": len(cases), "index": k}}
            for k, (c, out) in enumerate(zip(cases, outs, strict=True))]


def _solve_batch(cases: list[Case], device: str) -> list[dict[str, Any]]:
    import dataclasses

    from tightknot.loading.batch import tie_batch
    from tightknot.study.run import measure_run

    scenes = [build_scene(c.params, device) for c in cases]
    p0 = cases[0].params
    batch = tie_batch(scenes, tighten_steps=p0["tighten_steps"], residual_tol=p0["residual_tol"])
    outs = []
    for sc, rod in zip(scenes, batch.rods, strict=True):
        # the rod's own tie result; its time is the batch's (the rods ran together)
        res = dataclasses.replace(rod.tie, wall_time_s=batch.wall_time_s)
        # tie()'s hook runs once per converged load step of its tightening
        steps = sum(len(ph.steps) for ph in rod.phases.values())
        run = measure_run(sc, res, steps)
        outs.append({"status": OK if rod.converged else FAILED, "failure": rod.failure,
                     "warnings": [], "result": run.summary})
    return outs


def physics(record: Mapping[str, Any]) -> Any:
    """``record`` without the machine- and time-dependent keys (:data:`TIMING_KEYS`), for
    comparing two runs of the same case."""
    if isinstance(record, Mapping):
        return {k: physics(v) for k, v in record.items() if k not in TIMING_KEYS}
    if isinstance(record, list):
        return [physics(v) for v in record]
    return record
