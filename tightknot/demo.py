"""The embedded demo behind ``make demo`` / ``tightknot demo``: the study's knots.

Ties the closed trefoil (L0/D0 = 16.37) and the open trefoil (L0 = 185 mm, pulled to 5 N)
in the study's elastomer rod, logs every load step to rerun (rod coloured by curvature,
contacts coloured by pressure, energies and Newton statistics), measures both exactly as
the study did next to the ideal trefoil, and draws the study's figures. 100 and 150
vertices, so that it runs in seconds.
"""

from __future__ import annotations

import time
from pathlib import Path

from tightknot.atomic import write_json_atomic
from tightknot.knots.ideal import load_ideal_trefoil
from tightknot.knots.run import draw_figures, run_knot
from tightknot.knots.scenes import closed_trefoil, open_trefoil
from tightknot.viz.rerun_log import make_logger

PULL_FORCE_N = 5.0


def run_demo(out: Path, quiet: bool = False) -> dict:
    """Run the demo into folder ``out`` (created); returns the summary written to
    ``out/summary.json`` (per knot: the knots issue's keys, without the long arrays)."""
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    closed = closed_trefoil(nodes=100)
    opened = open_trefoil(nodes=150)
    counter = [0]
    with make_logger(out / "demo.rrd") as log:
        ideal = load_ideal_trefoil(closed.diameter)
        log.log_reference("ideal_trefoil",
                          ideal - ideal.mean(axis=0) + [0.0, 0.0, -6 * closed.diameter],
                          closed.diameter / 2)
        runs = [run_knot(closed, log, "closed", counter, tighten_steps=40),
                run_knot(opened, log, "open", counter, pull_force=PULL_FORCE_N,
                         tighten_steps=40, pull_steps=10)]
    draw_figures(runs, out / "figures")
    summary = {
        "knots": {r.scene.name: {k: v for k, v in r.summary.items() if not isinstance(v, list)}
                  for r in runs},
        "passed": all(r.result.converged for r in runs),
        "wall_time_s": time.perf_counter() - t0,
    }
    write_json_atomic(out / "summary.json", summary)
    return summary
