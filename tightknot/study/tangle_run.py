"""One two-rod tangle run end to end: pull, measure each rod, summarise, log, draw.

Measurements per rod (physics.md sec. 2, applied to each rod on its own): its stretch L/L0
between the grips and largest edge stretch, its curvature kappa D0 (Bergou's discrete
curvature, the end vertices excluded), its contact with the other rod (how many of its
vertices touch it, over how much rest length, the deepest per-side approach w/D0 and the
peak pressure p/E there) and with itself, and its smallest section area A/A0; for the
pair, the deepest contact between the rods and the angle at which they cross there. The
tangle's invariants and every end's reaction come from the load path
(:mod:`tightknot.loading.tangle_pull`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from tightknot.contact.report import ContactReport, contact_report
from tightknot.knots import tangles
from tightknot.knots.curvature import bergou_curvature
from tightknot.knots.tangle_scenes import ROD_NAMES, TangleScene
from tightknot.knots.topology import TopologyError
from tightknot.loading.tangle_pull import PullResult, end_reactions, pull_tangle, pulling_force
from tightknot.solvers.system import RodSystem
from tightknot.viz.rerun_log import ROD_COLORS_RGB
from tightknot.viz.tangle_figures import plot_force_extension

#: Figure file of the force-extension curve.
FORCE_EXTENSION_PNG = "force_extension.png"


@dataclass
class TangleRun:
    """A pulled tangle: the scene, the load path's result and the JSON summary."""

    scene: TangleScene
    result: PullResult
    summary: dict


def edge_radii(scene: TangleScene, x: np.ndarray, rest: np.ndarray) -> np.ndarray:
    """Deformed edge radii r0 lam^-nu [m] (nu 0 for a rigid tube), lam each edge's stretch."""
    ev = scene.model.edge_vertex
    lam = np.linalg.norm(x[ev[:, 1]] - x[ev[:, 0]], axis=1) / rest
    return scene.model.edge_radius * lam ** (-scene.contact.edge_poisson)


def _split_pairs(scene: TangleScene, rep: ContactReport) -> tuple[np.ndarray, np.ndarray]:
    """The report's contact pairs (P, 3) between the two rods and within a rod."""
    vr = scene.model.vertex_rod
    ia = rep.pairs[:, 0].astype(int)
    ib = rep.pairs[:, 1].astype(int)
    between = vr[ia] != vr[ib]
    return rep.pairs[between], rep.pairs[~between]


def log_tangle(log: Any, scene: TangleScene, name: str, system: RodSystem,
               phase: str, force: float) -> None:
    """Log both rods (one colour each, :data:`ROD_COLORS_RGB`, deformed radii), their
    contacts between the rods and within each rod (coloured by peak p/E), and the end
    distance [m] and pulling ``force`` [N] under ``name/<phase>/``."""
    x = system.state.x
    r_e = edge_radii(scene, x, system.rest)
    for r, info in enumerate(scene.model.rods):
        log.log_rod(f"{name}/rod_{ROD_NAMES[r]}", x[info.vertex_slice], False,
                    r_e[info.edge_slice], radii_at="edge", color=ROD_COLORS_RGB[r])
    rep = contact_report(scene.contact, x, system.rest, system.state)
    between, within = _split_pairs(scene, rep)
    for key, pairs in (("contacts_between_rods", between), ("contacts_within_rods", within)):
        ia, ib = pairs[:, 0].astype(int), pairs[:, 1].astype(int)
        log.log_contacts(f"{name}/{key}", x[ia], x[ib], rep.peak_pressure_over_E[ia])
    log.log_scalars({f"{name}/{phase}/end_to_end": scene.end_distance(x),
                     f"{name}/{phase}/pulling_force": float(force)})


def measure_rods(scene: TangleScene, system: RodSystem) -> list[dict]:
    """Each rod's measurements (module docstring), rod A first."""
    m = scene.model
    x, rest = system.state.x, system.rest
    rep = contact_report(scene.contact, x, rest, system.state)
    between, within = _split_pairs(scene, rep)
    ev = m.edge_vertex
    lengths = np.linalg.norm(x[ev[:, 1]] - x[ev[:, 0]], axis=1)
    # Voronoi rest length of each vertex [m] (half of each adjacent edge).
    vor = np.zeros(m.vertex_count)
    np.add.at(vor, ev[:, 0], 0.5 * rest)
    np.add.at(vor, ev[:, 1], 0.5 * rest)
    out = []
    for r, info in enumerate(m.rods):
        d0 = info.diameter
        free = slice(info.edge_start + 1, info.edge_start + info.edge_count - 1)
        vs = np.arange(info.vertex_start, info.vertex_start + info.vertex_count)
        kappa = bergou_curvature(x[info.vertex_slice], False)[1:-1] * d0
        touch_other = np.unique(np.r_[between[:, 0], between[:, 1]].astype(int))
        touch_other = touch_other[np.isin(touch_other, vs)]
        touch_self = np.unique(np.r_[within[:, 0], within[:, 1]].astype(int))
        touch_self = touch_self[np.isin(touch_self, vs)]
        mine = (m.vertex_rod[between[:, 0].astype(int)] == r) | (
            m.vertex_rod[between[:, 1].astype(int)] == r)
        w_max = 0.5 * float(np.max(between[mine, 2], initial=0.0)) / d0
        pe = rep.peak_pressure_over_E[touch_other]
        out.append({
            "rod": ROD_NAMES[r],
            "diameter_m": d0,
            "youngs_modulus_Pa": info.material.youngs_modulus,
            "rest_length_m": float(rest[info.edge_slice].sum()),
            # Between the grips: the edge inside each grip is held at its length in a
            # clamped grip and free in a dead-loaded one, so it is left out of both.
            "stretch": float(lengths[free].sum() / rest[free].sum()),
            "max_edge_stretch": float(np.max(lengths[info.edge_slice] / rest[info.edge_slice])),
            "max_kappa_D0": float(np.max(kappa)),
            "mean_kappa_D0": float(np.mean(kappa)),
            "contact_with_other_rod": {
                "vertices": int(touch_other.size),
                "rest_length_over_D0": float(vor[touch_other].sum() / d0),
                "max_approach_w_over_D0": w_max,
                "max_peak_pressure_over_E": float(np.max(pe, initial=0.0)),
            },
            "self_contact_vertices": int(touch_self.size),
            "min_area_ratio": float(np.min(rep.area_ratio[vs])),
        })
    return out


def _tangent(scene: TangleScene, x: np.ndarray, v: int) -> np.ndarray:
    """Unit tangent of the centerline at vertex ``v`` (central difference within its rod)."""
    info = scene.model.rods[int(scene.model.vertex_rod[v])]
    lo = max(v - 1, info.vertex_start)
    hi = min(v + 1, info.vertex_start + info.vertex_count - 1)
    t = x[hi] - x[lo]
    return t / np.linalg.norm(t)


def deepest_contact(scene: TangleScene, system: RodSystem) -> dict | None:
    """The deepest contact between the two rods: its vertices, per-side approach w/D0 (D0
    the larger rod diameter) and
    the angle between the two centerlines there [deg] (90: the orthogonal contact of a
    tight clasp, Grandgeorge et al. 2021); None when the rods do not touch."""
    x = system.state.x
    rep = contact_report(scene.contact, x, system.rest, system.state)
    between, _ = _split_pairs(scene, rep)
    if not between.shape[0]:
        return None
    k = int(np.argmax(between[:, 2]))
    va, vb = int(between[k, 0]), int(between[k, 1])
    if scene.model.vertex_rod[va] != 0:
        va, vb = vb, va
    cos = abs(float(_tangent(scene, x, va) @ _tangent(scene, x, vb)))
    d0 = max(scene.diameters)
    return {"vertex_A": va - scene.model.rods[0].vertex_start,
            "vertex_B": vb - scene.model.rods[1].vertex_start,
            "w_over_D0": 0.5 * float(between[k, 2]) / d0,
            "crossing_angle_deg": float(np.degrees(np.arccos(min(cos, 1.0))))}


def _calibration(scene: TangleScene, rods: list[dict]) -> dict:
    """Where the run stands against the contact law's calibrated range."""
    law = scene.contact.law
    warnings = list(scene.info.get("warnings", []))
    w_hat = max(r["contact_with_other_rod"]["max_approach_w_over_D0"] for r in rods)
    if not law.rigid and w_hat > law.calibrated_w_hat:
        warnings.append(f"the contact between the rods reaches a per-side approach w/D0 = "
                        f"{w_hat:.3g}, beyond the {law.calibrated_w_hat:.3g} the law was "
                        "calibrated to (its force there is extrapolated)")
    nus = {info.material.poisson_ratio for info in scene.model.rods}
    if not law.rigid and any(abs(nu - 0.5) > 1e-12 for nu in nus):
        warnings.append(f"a rod has Poisson ratio {min(nus):g}; the contact law was calibrated "
                        "on an incompressible solid (nu = 0.5): extrapolated")
    return {"max_approach_w_over_D0": w_hat,
            "calibrated_w_over_D0": None if law.rigid else law.calibrated_w_hat,
            "outside_calibrated_range": bool(warnings), "warnings": warnings}


def summarise(scene: TangleScene, res: PullResult) -> dict:
    """The JSON summary of a pulled tangle."""
    system = res.system
    rods = measure_rods(scene, system)
    try:
        final = scene.tangle_type(system.state.x)
        final_type = {"linking_number": final.linking_number,
                      "component_types": list(final.component_types),
                      "closure_type": final.closure_type, "final": final.label()}
    except TopologyError:
        final_type = {"linking_number": None, "component_types": None, "closure_type": None,
                      "final": "undefined (two pieces of rod nearly meet)"}
    cal = _calibration(scene, rods)
    return {
        "scene": scene.name,
        "kind": scene.kind,
        "converged": res.converged,
        "failure": res.failure,
        "tangle_type": {
            **final_type,
            "working_ends": scene.ends,
            "start": scene.start_type.label(),
            "kept": final_type["final"] == scene.start_type.label(),
            "candidates": list(tangles.CANDIDATES[scene.kind]),
        },
        "tangle_types_per_step": res.tangle_types,
        "force_extension": {
            "end_to_end_m": [p[0] for p in res.force_extension],
            "pulling_force_N": [p[1] for p in res.force_extension],
            "phase": [p[2] for p in res.force_extension],
        },
        "pull_force_N": res.pull_force_N if math.isfinite(res.pull_force_N) else None,
        "end_to_end_m": scene.end_distance(system.state.x),
        "end_reactions": [r.to_dict() for r in res.reactions],
        "rods": rods,
        "deepest_contact_between_rods": deepest_contact(scene, system),
        "calibration": cal,
        "warnings": cal["warnings"],
        "load_steps": len(res.force_extension),
        "newton_iterations": res.newton_iterations,
        "wall_time_s": res.wall_time_s,
        "nodes_per_rod": scene.info["nodes"],
        "contact": scene.info["contact"],
    }


def run_tangle(scene: TangleScene, log: Any | None = None, name: str | None = None,
               **pull_options: Any) -> TangleRun:
    """Pull ``scene`` (options of :func:`tightknot.loading.tangle_pull.pull_tangle`),
    logging every converged load step to ``log``; the final state is logged once more when
    it is not the last logged one (a failed step), so the .rrd ends on the summary's
    state."""
    name = name or scene.name
    step = [0]
    last: dict = {}

    def hook(phase: str, system: RodSystem, rec: Any) -> None:
        if log is None:
            return
        log.set_step(step[0], rec.t if rec is not None else 0.0)
        step[0] += 1
        force = pulling_force(end_reactions(scene, system))
        log_tangle(log, scene, name, system, phase, force)
        last["x"] = system.state.x.copy()
        last["phase"] = phase

    res = pull_tangle(scene, hook=hook, **pull_options)
    x = res.system.state.x
    if log is not None and not np.array_equal(last.get("x"), x):
        log.set_step(step[0])
        log_tangle(log, scene, name, res.system, last.get("phase", "relax"),
                   res.pull_force_N if math.isfinite(res.pull_force_N) else 0.0)
    return TangleRun(scene, res, summarise(scene, res))


def draw_tangle_figures(run: TangleRun, folder: Path) -> list[Path]:
    """The force-extension figure of ``run`` in ``folder`` (made if missing)."""
    folder.mkdir(parents=True, exist_ok=True)
    fe = run.summary["force_extension"]
    if not fe["pulling_force_N"]:
        return []
    path = folder / FORCE_EXTENSION_PNG
    title = f"{run.scene.kind} ({'two rods' if run.scene.kind == 'clasp' else 'bend'}): " \
        f"pulling force vs end-to-end distance"
    plot_force_extension(fe["end_to_end_m"], fe["pulling_force_N"], fe["phase"], path, title)
    return [path]
