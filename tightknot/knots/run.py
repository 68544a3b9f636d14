"""One knot run: tie a scene, log it to rerun, measure it, summarise it, draw its figures.

Shared by ``tightknot tie`` and the demo, so both report the same quantities with the
same keys (the knots issue's JSON summary).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from tightknot.knots import figures
from tightknot.knots.curvature import bergou_curvature
from tightknot.knots.ideal import load_ideal_trefoil
from tightknot.knots.measure import analyze_centerline
from tightknot.knots.scenes import KnotScene, vertex_radii
from tightknot.knots.tie import TieResult, tie, tie_to_lambda
from tightknot.rods.contact import ContactReport, contact_report
from tightknot.solvers.system import RodSystem

#: Contact tolerance of the measurements (the default of tightknot.knots.measure).
CONTACT_TOL = 0.01


@dataclass
class KnotRun:
    """A finished run: the tie result, the study's measurements, the contact outputs and the
    JSON summary."""

    scene: KnotScene
    result: TieResult
    report: dict
    contact: ContactReport
    summary: dict


def logging_hook(log: Any, scene: KnotScene, name: str, counter: list[int]):
    """A tie hook that logs each converged load step under ``name/`` on one timeline."""
    d0 = scene.diameter

    def hook(phase: str, system: RodSystem, rec: Any) -> None:
        x = system.state.x
        r_e, _ = vertex_radii(scene, x, system.rest)
        kappa = bergou_curvature(x, scene.closed) * d0
        log.set_step(counter[0], rec.t)
        counter[0] += 1
        log.log_rod(f"{name}/rod", x, scene.closed, r_e, kappa, "kappa_D0")
        rep = contact_report(scene.contact, x)
        ia = rep.pairs[:, 0].astype(int)
        ib = rep.pairs[:, 1].astype(int)
        log.log_contacts(f"{name}/contacts", x[ia], x[ib], rep.peak_pressure_over_E[ia])
        sp = system.last_split
        log.log_scalars({
            f"{name}/energy/stretch": sp.stretch, f"{name}/energy/bend": sp.bend,
            f"{name}/energy/twist": sp.twist,
            f"{name}/energy/contact": float(sum(sp.extra.values())),
            f"{name}/newton_residual": float(rec.newton.residual),
            f"{name}/newton_iterations": float(rec.newton.iterations),
        })
    return hook


def summarise(scene: KnotScene, res: TieResult, rep: dict, contact: ContactReport) -> dict:
    """The JSON summary of one knot (the knots issue's keys, NaN-free)."""
    x = res.system.state.x
    dmin, _, _ = scene.contact.min_distance(x)
    s = np.asarray(rep["s"])
    out: dict[str, Any] = {
        "scene": scene.name,
        "converged": res.converged,
        "failure": res.failure,
        "knot_type": rep["knot_type"],
        "alexander_at_minus1": rep["knot_determinant"],
        "newton_iterations": res.newton_iterations,
        "wall_time_s": res.wall_time_s,
        "nodes": scene.model.vertex_count,
        "diameter_m": scene.diameter,
        "rest_length_m": scene.rest_length,
        "stretch": rep["stretch_L_over_L0"],
        "L_over_D": rep["L_over_D"],
        "min_gap_over_D0": dmin / scene.diameter,
        "max_pressure_over_E": float(np.max(contact.peak_pressure_over_E)),
        "min_area_ratio": float(np.min(contact.area_ratio)),
        "max_contact_width_fraction": float(np.max(contact.contact_width_fraction)),
        "kappa_D0_max": rep["kappa_D0_max"],
        "kappa_D0_min": rep["kappa_D0_min"],
        "s": s.tolist(),
        "kappa": np.asarray(rep["kappa_D0"]).tolist(),
        "area_ratio": contact.area_ratio.tolist(),
        "contact_width_fraction": contact.contact_width_fraction.tolist(),
        "contact_s": np.asarray(rep["contact_s"]).tolist(),
        "contact_sigma": np.asarray(rep["contact_sigma"]).tolist(),
        "centerline_m": x.tolist(),
    }
    if scene.closed:
        out["rho"] = np.asarray(rep["rho"]).tolist()
        out["z"] = np.asarray(rep["z"]).tolist()
    else:
        lam = rep.get("Lambda_OC")
        out["lambda_oc"] = None if lam is None or not np.isfinite(lam) else float(lam)
        out["pull_force_N"] = float(res.pull_force_N)
    return out


def run_knot(scene: KnotScene, log: Any | None = None, name: str | None = None,
             counter: list[int] | None = None, **tie_options: Any) -> KnotRun:
    """Tie ``scene`` (options of :func:`tightknot.knots.tie.tie`), logging to ``log``."""
    hook = None
    if log is not None:
        hook = logging_hook(log, scene, name or scene.name, counter if counter else [0])
    target = tie_options.pop("target_lambda", None)
    if target is not None:
        res = tie_to_lambda(scene, target, hook=hook)
    else:
        res = tie(scene, hook=hook, **tie_options)
    x = res.system.state.x
    _, r_v = vertex_radii(scene, x, res.system.rest)
    # Contact as physics.md sec. 2 defines it for a rod model: distance at most the sum of
    # the deformed radii; the measurement's 1 % tolerance covers the vertex sampling of the
    # centerline (segments touch between vertices) and the contact law's onset band.
    rep = analyze_centerline(x, scene.diameter, scene.closed, rest_length=scene.rest_length,
                             radii=r_v, contact_tol=CONTACT_TOL)
    contact = contact_report(scene.contact, x)
    return KnotRun(scene, res, rep, contact, summarise(scene, res, rep, contact))


def draw_figures(runs: list[KnotRun], folder: Path) -> list[Path]:
    """The study's figures of the runs into ``folder`` (created); returns the paths."""
    import matplotlib

    matplotlib.use("Agg")
    folder.mkdir(parents=True, exist_ok=True)
    paths: list[Path] = []
    closed = [r for r in runs if r.scene.closed]
    opened = [r for r in runs if not r.scene.closed]
    if closed:
        d0 = closed[0].scene.diameter
        ideal = analyze_centerline(load_ideal_trefoil(d0), d0, True, contact_tol=0.002)
        for r in closed:
            p1, p2 = folder / "closed_profiles.png", folder / "closed_contact_map.png"
            figures.plot_closed_profiles(r.report, p1, ideal=ideal, label="elastic rod")
            figures.plot_contact_map(r.report, p2, ideal=ideal, label="elastic rod")
            paths += [p1, p2]
    if opened:
        reps, lcs, areas = {}, {}, {}
        for r in opened:
            lab = f"L0 = {r.scene.rest_length * 1e3:.0f} mm, F = {r.result.pull_force_N:.3g} N"
            order = np.asarray(r.report.get("vertex_order", np.arange(len(r.contact.area_ratio))),
                               dtype=int)
            reps[lab] = r.report
            lcs[lab] = r.contact.contact_width_fraction[order]
            areas[lab] = r.contact.area_ratio[order]
        p = folder / "open_knots.png"
        figures.plot_open_knots(reps, p, contact_width=lcs, area_ratio=areas)
        paths.append(p)
    return paths
