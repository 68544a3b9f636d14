"""The study's three knots at the contact levels ``compliant``, ``smoothed`` and
``sectioned``: Newton iterations, wall time and the knots' measures, in one run (compare
ratios, not seconds: the machines are shared).

Usage: ``python bench/contact_levels.py [--closed-nodes 100] [--open-nodes 150]
[--levels compliant smoothed] [--section-path auto] [--json out.json]``. The level
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--closed-nodes", type=int, default=100)
    parser.add_argument("--open-nodes", type=int, default=150)
    parser.add_argument("--levels", nargs="+", default=["compliant", "smoothed"],
                        choices=["compliant", "smoothed", "sectioned", "sectioned-shift",
                                 "sectioned-rod", "rigid"])
    parser.add_argument("--section-path", default="auto", choices=list(SECTION_PATHS),
                        help="the sectioned level's load path (tightknot.loading.tie.path_scene)")
    parser.add_argument("--json", default=None)
    args = parser.parse_args()
    tie(closed_trefoil(nodes=40), tighten_steps=5).run()  # compile the kernels outside the timing
    rows = []
    for level in args.levels:
        rows.append(closed_case(level, args.closed_nodes, args.section_path))
        print(json.dumps(rows[-1]))
        for name, length, target in OPEN_CASES:
            rows.append(open_case(level, args.open_nodes, name, length, target,
                                  args.section_path))
            print(json.dumps(rows[-1]))
    base = {r["case"]: r for r in rows if r["level"] == args.levels[0]}
    ratios = [{"case": r["case"], "level": r["level"],
               "time_ratio_to_" + args.levels[0]: r["wall_time_s"] / base[r["case"]]["wall_time_s"],
               "iteration_ratio_to_" + args.levels[0]:
                   r["newton_iterations"] / base[r["case"]]["newton_iterations"]}
              for r in rows if r["level"] != args.levels[0]]
    for r in ratios:
        print(json.dumps(r))
    if args.json:
        write_json_atomic(args.json, {"rows": rows, "ratios": ratios})


if __name__ == "__main__":
    main()
