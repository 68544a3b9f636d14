"""The embedded demo behind ``make demo`` / ``tightknot demo``: the study's knots.

Ties the closed trefoil (L0/D0 = 16.37) and the open trefoil (L0 = 185 mm, pulled to 5 N)
in the study's elastomer rod, logs every load step to rerun (rod coloured by curvature,
contacts coloured by pressure, energies and Newton statistics), measures both exactly as
the study did (``tightknot.knots.measure``) next to the ideal trefoil, and draws the
study's figures. The closed knot uses 100 vertices and the open one 150, so the demo runs
in well under a minute; the measurement code is resolution independent.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

from tightknot.atomic import write_json_atomic
from tightknot.knots import figures
from tightknot.knots.curvature import bergou_curvature
from tightknot.knots.ideal import load_ideal_trefoil
from tightknot.knots.measure import analyze_centerline
from tightknot.knots.scenes import KnotScene, closed_trefoil, open_trefoil
from tightknot.knots.tie import TieResult, tie
from tightknot.rods.contact import contact_report
from tightknot.solvers.system import RodSystem
from tightknot.viz.rerun_log import make_logger

PULL_FORCE_N = 5.0


def _vertex_radii(scene: KnotScene, x: np.ndarray, rest: np.ndarray) -> tuple[np.ndarray, ...]:
    """Deformed edge radii r0 lam^-nu [m] and their vertex averages."""
    m = scene.model
    ev = m.edge_vertex
    lam = np.linalg.norm(x[ev[:, 1]] - x[ev[:, 0]], axis=1) / rest
    nu = m.rods[0].material.poisson_ratio
    r_e = m.edge_radius * lam ** (-nu)
    r_v = np.zeros(m.vertex_count)
    cnt = np.zeros(m.vertex_count)
    np.add.at(r_v, ev.ravel(), np.repeat(r_e, 2))
    np.add.at(cnt, ev.ravel(), 1.0)
    return r_e, r_v / np.maximum(cnt, 1.0)


def _logging_hook(log: Any, scene: KnotScene, name: str, counter: list[int]):
    d0 = scene.diameter

    def hook(phase: str, system: RodSystem, rec: Any) -> None:
        x = system.state.x
        r_e, _ = _vertex_radii(scene, x, system.rest)
        kappa = bergou_curvature(x, scene.closed) * d0
        log.set_step(counter[0], rec.t)
        counter[0] += 1
        log.log_rod(f"{name}/rod", x, scene.closed, r_e, kappa, "kappa_D0")
        rep = contact_report(scene.contact, x)
        if rep.pairs.shape[0]:
            ia = rep.pairs[:, 0].astype(int)
            ib = rep.pairs[:, 1].astype(int)
            log.log_contacts(f"{name}/contacts", x[ia], x[ib], rep.peak_pressure_over_E[ia])
        else:
            log.log_contacts(f"{name}/contacts", np.zeros((0, 3)), np.zeros((0, 3)),
                             np.zeros(0))
        sp = system.last_split
        log.log_scalars({
            f"{name}/energy/stretch": sp.stretch, f"{name}/energy/bend": sp.bend,
            f"{name}/energy/twist": sp.twist,
            f"{name}/energy/contact": float(sum(sp.extra.values())),
            f"{name}/newton_residual": float(rec.newton.residual),
            f"{name}/newton_iterations": float(rec.newton.iterations),
        })
    return hook


def _summary(scene: KnotScene, res: TieResult, rep: dict, contact: Any) -> dict:
    """The JSON summary of one knot (keys of the knots issue)."""
    x = res.system.state.x
    dmin, _, _ = scene.contact.min_distance(x)
    out = {
        "scene": scene.name,
        "converged": res.converged,
        "failure": res.failure,
        "knot_type": rep["knot_type"],
        "alexander_at_minus1": rep["knot_determinant"],
        "newton_iterations": res.newton_iterations,
        "wall_time_s": res.wall_time_s,
        "nodes": scene.model.vertex_count,
        "rest_length_m": scene.rest_length,
        "stretch": rep["stretch_L_over_L0"],
        "L_over_D": rep["L_over_D"],
        "min_gap_over_D0": dmin / scene.diameter,
        "max_pressure_over_E": float(np.max(contact.peak_pressure_over_E)),
        "min_area_ratio": float(np.min(contact.area_ratio)),
        "argmin_area_ratio_s": float(np.asarray(rep["s"])[int(np.argmin(contact.area_ratio))])
        if not scene.closed else None,
        "max_contact_width_fraction": float(np.max(contact.contact_width_fraction)),
        "kappa_D0_max": rep["kappa_D0_max"],
        "kappa_D0_min": rep["kappa_D0_min"],
    }
    if not scene.closed:
        out["lambda_oc"] = rep.get("Lambda_OC")
        out["pull_force_N"] = res.pull_force_N
    return out


def run_demo(out: Path, quiet: bool = False) -> dict:
    """Run the demo into folder ``out`` (created); returns the summary written to
    ``out/summary.json``."""
    import matplotlib

    matplotlib.use("Agg")
    out.mkdir(parents=True, exist_ok=True)
    figs = out / "figures"
    figs.mkdir(exist_ok=True)
    t0 = time.perf_counter()
    closed = closed_trefoil(nodes=100)
    opened = open_trefoil(nodes=150)
    d0 = closed.diameter
    counter = [0]
    with make_logger(out / "demo.rrd") as log:
        ideal = load_ideal_trefoil(d0)
        log.log_reference("ideal_trefoil", ideal - ideal.mean(axis=0) + [0.0, 0.0, -6 * d0],
                          d0 / 2)
        res_c = tie(closed, tighten_steps=40, hook=_logging_hook(log, closed, "closed", counter))
        res_o = tie(opened, pull_force=PULL_FORCE_N, tighten_steps=40, pull_steps=10,
                    hook=_logging_hook(log, opened, "open", counter))

    knots = {}
    for scene, res in ((closed, res_c), (opened, res_o)):
        x = res.system.state.x
        _, r_v = _vertex_radii(scene, x, res.system.rest)
        rep = analyze_centerline(x, scene.diameter, scene.closed, rest_length=scene.rest_length,
                                 radii=r_v)
        contact = contact_report(scene.contact, x)
        knots[scene.name] = (rep, contact, _summary(scene, res, rep, contact))

    ideal_rep = analyze_centerline(load_ideal_trefoil(d0), d0, True, contact_tol=0.002)
    rep_c = knots["closed_trefoil"][0]
    figures.plot_closed_profiles(rep_c, figs / "closed_profiles.png", ideal=ideal_rep,
                                 label="elastic rod (tightknot)")
    figures.plot_contact_map(rep_c, figs / "closed_contact_map.png", ideal=ideal_rep,
                             label="elastic rod (tightknot)")
    rep_o, con_o, _ = knots["open_trefoil"]
    lab = f"L0 = 185 mm, F = {PULL_FORCE_N:g} N"
    order = np.asarray(rep_o.get("vertex_order", np.arange(len(con_o.area_ratio))), dtype=int)
    figures.plot_open_knots({lab: rep_o}, figs / "open_knot.png",
                            contact_width={lab: con_o.contact_width_fraction[order]},
                            area_ratio={lab: con_o.area_ratio[order]})
    summary = {
        "knots": {name: k[2] for name, k in knots.items()},
        "passed": bool(res_c.converged and res_o.converged),
        "wall_time_s": time.perf_counter() - t0,
    }
    write_json_atomic(out / "summary.json", summary)
    return summary
