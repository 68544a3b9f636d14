"""The embedded demo behind ``make demo`` / ``tightknot demo``: the study's knots.

Ties the study's three knots in its elastomer rod: the closed trefoil (L0/D0 = 16.37) and
the open trefoils of L0 = 185 mm pulled to Lambda_OC = 15.0 and L0 = 125 mm pulled to 10.1;
logs every load step to rerun (rod coloured by curvature, contacts coloured by pressure,
energies and Newton statistics), measures them exactly as the study did next to the
ideal trefoil, and draws the study's figures. 100 to 150
vertices, so that it runs in seconds.
"""

from __future__ import annotations

import time
from pathlib import Path

from tightknot.app.progress import Progress, phase_progress
from tightknot.atomic import write_json_atomic
from tightknot.knots.ideal import load_ideal_trefoil
from tightknot.knots.scenes import closed_trefoil, open_trefoil
from tightknot.study.run import draw_figures, draw_tube, run_knot
from tightknot.viz.rerun_log import make_logger

#: The tube picture of each knot in ``figures/``.
TUBE_PNG = "tube_{name}.png"
#: What the summary's "passed" says, and what it does not.
PASSED_MEANS = ("every knot's load path converged: each load step's Newton solve met its "
                "tolerance, the knot type never changed, and each open knot reached its "
                "target Lambda_OC within 0.1; not a statement on accuracy: each knot's "
                "'resolution' gives the expected error of its vertex count")
#: The study's open knots: (name, rest length [m], target Lambda_OC, vertices).
OPEN_KNOTS = (("open_185mm", 0.185, 15.0, 150), ("open_125mm", 0.125, 10.1, 100))


def run_demo(out: Path, quiet: bool = False) -> dict:
    """Run the demo into folder ``out`` (created); returns the summary written to
    ``out/summary.json`` (per knot: the knots issue's keys, without the long arrays)."""
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    closed = closed_trefoil(nodes=100)
    counter = [0]
    with make_logger(out / "demo.rrd") as log:
        ideal = load_ideal_trefoil(closed.diameter)
        log.log_reference("ideal_trefoil",
                          ideal - ideal.mean(axis=0) + [0.0, 0.0, -6 * closed.diameter],
                          closed.diameter / 2)
        with Progress("closed_trefoil", enabled=False if quiet else None) as bar:
            runs = {"closed_trefoil": run_knot(closed, log, "closed", counter,
                                               progress=phase_progress(bar, True),
                                               tighten_steps=40)}
        for name, length, target, nodes in OPEN_KNOTS:
            scene = open_trefoil(rest_length=length, nodes=nodes)
            # A pull to a target Lambda_OC reports its tightening; the force search after
            # it shows as the bar standing at the end of the tightening.
            with Progress(name, enabled=False if quiet else None) as bar:
                runs[name] = run_knot(scene, log, name, counter, target_lambda=target,
                                      progress=phase_progress(bar, False))
    draw_figures(list(runs.values()), out / "figures")
    for name, r in runs.items():
        # The knot itself, as the README's picture: the tube coloured by curvature.
        draw_tube(r, out / "figures" / TUBE_PNG.format(name=name))
    summary = {
        "knots": {name: {k: v for k, v in r.summary.items() if not isinstance(v, list)}
                  for name, r in runs.items()},
        "passed": all(r.result.converged for r in runs.values()),
        "passed_means": PASSED_MEANS,
        "wall_time_s": time.perf_counter() - t0,
    }
    write_json_atomic(out / "summary.json", summary)
    return summary
