"""The embedded demo behind ``make demo`` / ``tightknot demo``.

Until the knot scenes land it shows the DER core: the verification table, and a
large-deflection cantilever (the elastica) followed along its load path, logged to rerun
with the rod coloured by curvature, with figures of the convergence order and of the
tip path against the independent solve_bvp reference.
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from tightknot.atomic import atomic_open, write_json_atomic
from tightknot.knots.curvature import bergou_curvature
from tightknot.rods.boundary import BoundaryConditions
from tightknot.rods.material import second_moment
from tightknot.rods.state import State
from tightknot.solvers.static import ContinuationOptions, solve_static
from tightknot.solvers.system import RodSystem
from tightknot.verification import run_all
from tightknot.verification.cases import DIAMETER, LENGTH, MODULUS, _clamped_straight_rod
from tightknot.verification.elastica import cantilever_tip
from tightknot.viz.rerun_log import make_logger


def _save_figure(fig, path: Path) -> None:
    """Save a matplotlib figure as PNG atomically (temporary file, then rename)."""
    with atomic_open(path, "wb") as handle:
        fig.savefig(handle, format="png", dpi=150)


def run_demo(out: Path, quiet: bool = False) -> dict:
    """Run the demo into folder ``out`` (created); returns the summary written to
    ``out/summary.json``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out.mkdir(parents=True, exist_ok=True)
    figs = out / "figures"
    figs.mkdir(exist_ok=True)
    t0 = time.perf_counter()
    rows = run_all("cpu")

    # The elastica along its load path, logged step by step.
    ei = MODULUS * second_moment(DIAMETER)
    lp_max = 3.0
    model = _clamped_straight_rod(100)
    load = lp_max * ei / LENGTH**2
    system = RodSystem(model, State.initial(model),
                       BoundaryConditions(model).clamp(0, "start").force(0, -1, [0, -load, 0]))
    tips: list[tuple[float, float, float]] = []
    with make_logger(out / "demo.rrd") as log:
        step_no = [0]

        def on_step(sys_: RodSystem, rec) -> None:
            x = sys_.state.x
            kappa = bergou_curvature(x, closed=False) * DIAMETER
            log.set_step(step_no[0], rec.t)
            log.log_rod("rod", x, False, np.full(model.edge_count, DIAMETER / 2), kappa,
                        "kappa_D0")
            split = sys_.last_split
            log.log_scalars({
                "tip_deflection_over_L": float(-x[-1, 1] / LENGTH),
                "energy/stretch": split.stretch, "energy/bend": split.bend,
                "energy/twist": split.twist,
                "newton_residual": rec.newton.residual,
                "newton_iterations": float(rec.newton.iterations),
            })
            tips.append((rec.t * lp_max, float(x[-1, 0]), float(x[-1, 1])))
            step_no[0] += 1

        res = solve_static(system, ContinuationOptions(steps=12, max_step=1 / 12),
                           callback=lambda s, r: on_step(s, r))

    # Figure 1: convergence of the small-deflection cantilever.
    conv = [r for r in rows if r.case.startswith("cantilever_small_deflection")]
    ns = [int(r.case.split("n=")[1]) for r in conv]
    errs = [r.rel_error for r in conv]
    fig, ax = plt.subplots(figsize=(5, 4))
    ax.loglog(ns, errs, "o-", label="tightknot DER")
    ax.loglog(ns, [errs[0] * (ns[0] / n) ** 2 for n in ns], "k--", label="slope -2")
    ax.set_xlabel("vertices N")
    ax.set_ylabel("tip deflection relative error")
    ax.set_title("Cantilever F L^3/(3EI): second order")
    ax.legend()
    fig.tight_layout()
    _save_figure(fig, figs / "cantilever_convergence.png")
    plt.close(fig)

    # Figure 2: tip path against the elastica reference.
    lps = np.array([t[0] for t in tips])
    ref = np.array([cantilever_tip(lp, LENGTH) for lp in lps])
    fig, ax = plt.subplots(figsize=(5, 4))
    ax.plot(lps, -ref[:, 1] / LENGTH, "k-", label="elastica (solve_bvp)")
    ax.plot(lps, [-t[2] / LENGTH for t in tips], "o", label="tightknot DER, 100 vertices")
    ax.plot(lps, 1 - ref[:, 0] / LENGTH, "k:", label="end shortening (elastica)")
    ax.plot(lps, [1 - t[1] / LENGTH for t in tips], "s", mfc="none", label="end shortening")
    ax.set_xlabel("load F L^2 / EI")
    ax.set_ylabel("tip displacement / L")
    ax.set_title("Large-deflection cantilever")
    ax.legend()
    fig.tight_layout()
    _save_figure(fig, figs / "elastica_tip.png")
    plt.close(fig)

    worst = max(
        float(np.hypot(t[1] - r[0], t[2] - r[1]) / LENGTH) for t, r in zip(tips, ref, strict=True)
    )
    summary = {
        "scene": "elastica cantilever (DER core demo)",
        "converged": res.converged,
        "load_steps": len(res.steps),
        "newton_iterations": res.newton_iterations,
        "elastica_max_tip_error_over_L": worst,
        "verification_passed": all(r.passed for r in rows),
        "passed": bool(res.converged and all(r.passed for r in rows) and math.isfinite(worst)),
        "wall_time_s": time.perf_counter() - t0,
        "verification": [r.as_dict() for r in rows],
    }
    write_json_atomic(out / "summary.json", summary)
    return summary
