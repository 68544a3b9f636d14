"""The study's three knots at the contact levels ``compliant``, ``smoothed`` and
``sectioned``: Newton iterations, wall time and the knots' measures, in one run (compare
ratios, not seconds: the machines are shared).

Usage: ``python bench/contact_levels.py [--closed-nodes 100] [--open-nodes 150]
[--levels compliant smoothed] [--section-path auto] [--repeat 1] [--json out.json]``. The level
``sectioned-shift`` is the sectioned level with its bend shift
(``SectionSettings(bend_shift=True)``, docs/sectioned_level.md); ``sectioned-rod`` the
sectioned level with its sections thinned by the rod's mean stretch
(``SectionSettings(thinning="rod")``).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from tightknot.atomic import write_json_atomic
from tightknot.contact.sectioned import SectionSettings
from tightknot.knots.open_measures import lambda_oc
from tightknot.knots.scenes import (
    closed_trefoil,
    contact_centres,
    open_trefoil,
    vertex_radii,
)
from tightknot.loading.options import SECTION_PATHS
from tightknot.loading.pull import tie_to_lambda
from tightknot.loading.tie import tie

#: (name, rest length [m], target Lambda_OC) of the study's open knots (physics.md sec. 1).
OPEN_CASES = (("open_125mm_to_10.1", 0.125, 10.1), ("open_185mm_to_15", 0.185, 15.0))


def _contact(level: str) -> str | SectionSettings:
    """The scenes' contact of a benchmark level."""
    if level == "sectioned-shift":
        return SectionSettings(bend_shift=True)
    if level == "sectioned-rod":
        return SectionSettings(thinning="rod")
    return level


def closed_case(level: str, nodes: int, section_path: str = "auto") -> dict:
    """The closed trefoil at L0/D0 = 16.37 (``section_path``: the sectioned level's load
    path, :func:`tightknot.loading.tie.path_scene`)."""
    scene = closed_trefoil(16.37, nodes=nodes, contact=_contact(level))
    t0 = time.perf_counter()
    res = tie(scene, tighten_steps=20, section_path=section_path).run()
    wall = time.perf_counter() - t0
    x = res.system.state.x
    length = float(np.linalg.norm(np.roll(x, -1, axis=0) - x, axis=1).sum())
    return {"case": "closed_16.37", "level": level, "vertices": nodes,
            "section_path": section_path,
            "converged": res.converged, "failure": res.failure,
            "knot_types": sorted(set(res.knot_types)), "newton_iterations": res.newton_iterations,
            "wall_time_s": wall, "stretch": length / scene.rest_length}


def open_case(level: str, nodes: int, name: str, length: float, target: float,
              section_path: str = "auto") -> dict:
    """An open trefoil of rest ``length`` [m] pulled to Lambda_OC ``target``."""
    scene = open_trefoil(length, nodes=nodes, contact=_contact(level))
    t0 = time.perf_counter()
    res = tie_to_lambda(scene, target, section_path=section_path).run()
    wall = time.perf_counter() - t0
    x = res.system.state.x
    lam = lambda_oc(contact_centres(scene, x, res.system.rest), scene.diameter,
                    vertex_radii(scene, x, res.system.rest)[1])
    return {"case": name, "level": level, "vertices": nodes, "section_path": section_path,
            "converged": res.converged,
            "failure": res.failure, "knot_types": sorted(set(res.knot_types)),
            "newton_iterations": res.newton_iterations, "wall_time_s": wall,
            "lambda_oc": lam, "pull_force_N": res.pull_force_N,
            **_edge_stretch(x, res.system.rest)}


def _edge_stretch(x: np.ndarray, rest: np.ndarray) -> dict:
    """The edges' largest stretch and its ratio to their median (an open rod: the edges
    between consecutive vertices; the nip's edges pulled apart show as a large ratio)."""
    lam = np.linalg.norm(np.diff(x, axis=0), axis=1) / np.asarray(rest)[: len(x) - 1]
    return {"edge_stretch_max": float(lam.max()),
            "edge_stretch_max_over_median": float(lam.max() / np.median(lam))}


def _warm_up(levels: list[str]) -> None:
    """Compile (or load) every level's kernels and load its linear solver's library outside
    the timing: a 40-vertex closed trefoil tied at each level."""
    for level in dict.fromkeys(levels):
        tie(closed_trefoil(nodes=40, contact=_contact(level)), tighten_steps=5).run()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--closed-nodes", type=int, default=100)
    parser.add_argument("--open-nodes", type=int, default=150)
    parser.add_argument("--levels", nargs="+", default=["compliant", "smoothed"],
                        choices=["compliant", "smoothed", "sectioned", "sectioned-shift",
                                 "sectioned-rod", "rigid"])
    parser.add_argument("--section-path", default="auto", choices=list(SECTION_PATHS),
                        help="the sectioned level's load path (tightknot.loading.tie.path_scene)")
    parser.add_argument("--repeat", type=int, default=1,
                        help="runs of every case at every level, the levels of a case one "
                             "after the other (a shared machine's load drifts): the time "
                             "ratios are the medians of the runs' ratios")
    parser.add_argument("--json", default=None)
    args = parser.parse_args()
    if args.repeat < 1:
        parser.error(f"--repeat must be >= 1, got {args.repeat}")
    _warm_up(args.levels)
    cases = [("closed_16.37", lambda lv: closed_case(lv, args.closed_nodes, args.section_path))]
    cases += [(name, lambda lv, n=name, ln=length, t=target:
               open_case(lv, args.open_nodes, n, ln, t, args.section_path))
              for name, length, target in OPEN_CASES]
    runs: dict[tuple[str, str], list[dict]] = {}
    for _ in range(args.repeat):
        for name, run in cases:
            for level in args.levels:
                row = run(level)
                runs.setdefault((name, level), []).append(row)
                print(json.dumps(row))
    rows = []
    for (name, level), rs in runs.items():
        walls = [r["wall_time_s"] for r in rs]
        # the runs are deterministic: the same iterations every time
        if len({r["newton_iterations"] for r in rs}) != 1:
            raise SystemExit(f"{name} at {level}: Newton iterations differ between runs")
        rows.append({**rs[0], "wall_time_s": float(np.median(walls)), "wall_times_s": walls})
    first = args.levels[0]
    ratios = []
    for (name, level), rs in runs.items():
        if level == first:
            continue
        base = runs[(name, first)]
        per_run = [r["wall_time_s"] / b["wall_time_s"] for r, b in zip(rs, base, strict=True)]
        ratios.append({"case": name, "level": level,
                       "time_ratio_to_" + first: float(np.median(per_run)),
                       "time_ratios_of_runs": per_run,
                       "iteration_ratio_to_" + first:
                           rs[0]["newton_iterations"] / base[0]["newton_iterations"]})
    for r in ratios:
        print(json.dumps(r))
    if args.json:
        write_json_atomic(args.json, {"rows": rows, "ratios": ratios})


if __name__ == "__main__":
    main()
