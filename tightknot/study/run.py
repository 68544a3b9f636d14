"""One knot run: tie a scene, log it to rerun, measure it, summarise it, draw its figures.

Shared by ``tightknot tie`` and the demo, so both report the same quantities with the
same keys (the knots issue's JSON summary).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from tightknot.contact.checks import deepest_approaches
from tightknot.contact.layer import ContactLayer
from tightknot.contact.report import ContactReport, contact_report
from tightknot.contact.section_shift import MEASURED_KAPPA_R
from tightknot.contact.sectioned import SectionedLayer
from tightknot.knots.curvature import bergou_curvature
from tightknot.knots.ideal_overlay import aligned, ideal_report
from tightknot.knots.measure import analyze_centerline
from tightknot.knots.open_measures import lambda_oc
from tightknot.knots.scenes import KnotScene, contact_centres, vertex_radii
from tightknot.loading.pull import tie_to_lambda
from tightknot.loading.refine import tie_refined
from tightknot.loading.tie import TieResult, end_reaction, tie
from tightknot.solvers.system import RodSystem
from tightknot.study.resolution import resolution_note
from tightknot.viz.rerun_log import ROD_FIELDS

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


#: Fields the rod tube can be coloured by.
COLOR_FIELDS = tuple(ROD_FIELDS)

#: progress(phase, t, step): called after each converged load step with the phase name,
#: its load parameter t in [0, 1] and the step's index on the load_step timeline.
ProgressCallback = Callable[[str, float, int], None]


def rod_field(name: str, scene: KnotScene, x: np.ndarray, rest: np.ndarray,
              rep: ContactReport) -> tuple[np.ndarray, str]:
    """Values of colouring field ``name`` at centerline ``x`` [m] and where they live.

    kappa_D0: Bergou curvature times D0 per vertex; area_ratio: A/A0 per vertex and
    contact_width_fraction: L_c per vertex (contact report); stretch: |e|/|e0| per edge
    (``rest``: the edge rest lengths of the current load [m]).
    """
    if name == "kappa_D0":
        return bergou_curvature(x, scene.closed) * scene.diameter, "vertex"
    if name == "area_ratio":
        return rep.area_ratio, "vertex"
    if name == "contact_width_fraction":
        return rep.contact_width_fraction, "vertex"
    if name == "stretch":
        ev = scene.model.edge_vertex
        return np.linalg.norm(x[ev[:, 1]] - x[ev[:, 0]], axis=1) / rest, "edge"
    raise ValueError(f"unknown colouring field {name!r}; valid: {', '.join(COLOR_FIELDS)}")


def check_color_field(name: str) -> str:
    """``name`` if it is a colouring field, else ValueError naming the valid ones."""
    if name not in COLOR_FIELDS:
        raise ValueError(f"--color-by {name!r}: unknown field; valid: {', '.join(COLOR_FIELDS)}")
    return name


def system_contact(system: RodSystem, scene: KnotScene) -> ContactLayer:
    """The contact layer ``system`` is solved with: a sectioned scene's load path runs at
    the compliant level (:func:`tightknot.loading.tie.path_scene`), and its steps are
    reported at that level."""
    return next((t for t in system.extra_terms if isinstance(t, ContactLayer)), scene.contact)


def log_state(log: Any, scene: KnotScene, name: str, system: RodSystem,
              color_by: str = "kappa_D0", phase: str | None = None) -> None:
    """Log the rod (tube coloured by ``color_by``, deformed radii) and its contact pairs
    (coloured by peak p/E) at the logger's current step; open knots also get their
    end-to-end distance [m], pulling force [N] and Lambda_OC [1] (when in contact), under
    ``name/<phase>/`` when the load ``phase`` is given ("tighten", "pull", ...), so that
    the tightening's end reaction and the pull's force are separate series."""
    x = system.state.x
    r_e, r_v = vertex_radii(scene, x, system.rest)
    rep = contact_report(system_contact(system, scene), x, system.rest, system.state)
    values, at = rod_field(color_by, scene, x, system.rest, rep)
    log.log_rod(f"{name}/rod", x, scene.closed, r_e, values, color_by, field_at=at,
                radii_at="edge")
    ia = rep.pairs[:, 0].astype(int)
    ib = rep.pairs[:, 1].astype(int)
    log.log_contacts(f"{name}/contacts", x[ia], x[ib], rep.peak_pressure_over_E[ia])
    if not scene.closed:
        # The force the pulled end carries (its reaction: the dead load of a force-driven
        # pull, what holds a moved end where it is otherwise) [N].
        where = f"{name}/{phase}" if phase else name
        scalars = {f"{where}/end_to_end": float(np.linalg.norm(x[-1] - x[0])),
                   f"{where}/pulling_force": end_reaction(system)}
        lam = lambda_oc(contact_centres(scene, x, system.rest), scene.diameter, r_v,
                        tol=CONTACT_TOL)
        if np.isfinite(lam):
            scalars[f"{where}/lambda_oc"] = lam
        log.log_scalars(scalars)


def pull_point(scene: KnotScene, system: RodSystem) -> tuple[float, float, float | None]:
    """One point of an open knot's force-extension curve: the force on the pulled end [N],
    the end-to-end distance [m] and Lambda_OC (None without contact)."""
    x = system.state.x
    _, r_v = vertex_radii(scene, x, system.rest)
    lam = lambda_oc(contact_centres(scene, x, system.rest), scene.diameter, r_v,
                    tol=CONTACT_TOL)
    return (end_reaction(system), float(np.linalg.norm(x[-1] - x[0])),
            float(lam) if np.isfinite(lam) else None)


def logging_hook(log: Any, scene: KnotScene, name: str, counter: list[int],
                 color_by: str = "kappa_D0", progress: ProgressCallback | None = None,
                 logged: dict | None = None):
    """A tie hook that logs each converged load step under ``name/`` on one timeline.

    ``log`` may be None (no logging: only ``progress`` is called). ``logged`` (optional)
    receives the last logged centerline under ``"x"``, so that the caller can tell whether
    the final state still needs logging.
    """
    check_color_field(color_by)

    def hook(phase: str, system: RodSystem, rec: Any) -> None:
        step = counter[0]
        counter[0] += 1
        if logged is not None:
            logged["phase"] = phase
        if log is not None:
            log.set_step(step, rec.t)
            log_state(log, scene, name, system, color_by, phase)
            sp = system.last_split
            log.log_scalars({
                f"{name}/energy/stretch": sp.stretch, f"{name}/energy/bend": sp.bend,
                f"{name}/energy/twist": sp.twist,
                f"{name}/energy/contact": float(sum(sp.extra.values())),
                f"{name}/newton_residual": float(rec.newton.residual),
                f"{name}/newton_iterations": float(rec.newton.iterations),
            })
            if logged is not None:
                logged["x"] = system.state.x.copy()
        if progress is not None:
            progress(phase, rec.t, step)
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
        # which library solved the Newton systems (the sectioned level's: PARDISO where
        # installed), since round-off can pick between a knot's nearby equilibria
        "linear_solver": getattr(res.system.linear, "name", "superlu"),
        # the sectioned level's load path as it ran ("final", "pull" or "full": "auto"
        # picks by the knot and by whether its pull loosens it); null without sections
        "section_path": res.section_path or None,
        "nodes": scene.model.vertex_count,
        "diameter_m": scene.diameter,
        "rest_length_m": scene.rest_length,
        "stretch": rep["stretch_L_over_L0"],
        "L_over_D": rep["L_over_D"],
        # No pair within the interaction range (a knot that came undone): no gap to report
        # (JSON has no infinity).
        "min_gap_over_D0": dmin / scene.diameter if math.isfinite(dmin) else None,
        # A rigid tube reports no pressure and no width (contact_report): null, not 0.
        "max_pressure_over_E": (None if scene.contact.law.rigid
                                else float(np.max(contact.peak_pressure_over_E))),
        "min_area_ratio": float(np.min(contact.area_ratio)),
        "max_contact_width_fraction": (None if scene.contact.law.rigid
                                       else float(np.max(contact.contact_width_fraction))),
        "kappa_D0_max": rep["kappa_D0_max"],
        "kappa_D0_min": rep["kappa_D0_min"],
        "s": s.tolist(),
        "kappa": np.asarray(rep["kappa_D0"]).tolist(),
        "area_ratio": contact.area_ratio.tolist(),
        "contact_width_fraction": contact.contact_width_fraction.tolist(),
        # the largest contact pressure over E at each vertex's section (null for a rigid
        # tube, which has none)
        "peak_pressure_over_E": (None if scene.contact.law.rigid
                                 else contact.peak_pressure_over_E.tolist()),
        "contact_s": np.asarray(rep["contact_s"]).tolist(),
        "contact_sigma": np.asarray(rep["contact_sigma"]).tolist(),
        "centerline_m": x.tolist(),
    }
    out.update(calibration_range(scene, contact, x, res.system.rest))
    if scene.closed:
        # Null with the reason in "threefold" where the knot has no trefoil's 3-fold axis.
        out["rho"] = None if rep["rho"] is None else np.asarray(rep["rho"]).tolist()
        out["z"] = None if rep["z"] is None else np.asarray(rep["z"]).tolist()
        out["threefold"] = rep["threefold"]
        out["ideal"] = ideal_reference(rep["knot_type"])
    else:
        lam = rep.get("Lambda_OC")
        out["lambda_oc"] = None if lam is None or not np.isfinite(lam) else float(lam)
        out["pull_force_N"] = float(res.pull_force_N)
    return out


def ideal_reference(knot_type: str) -> dict[str, Any]:
    """The ideal (tightest) form of a closed knot of ``knot_type``: its L/D and where that
    comes from (measured on the shipped ideal polygon, estimated from the crossing number,
    or none for a type the table cannot size), and whether its shape is shipped (then the
    figures overlay it)."""
    from tightknot.knots.catalogue import ideal_l_over_d
    from tightknot.knots.ideal import has_ideal

    try:
        value, known = ideal_l_over_d(knot_type)
    except ValueError:  # "unknown(det=..)", candidates "a|b": no crossing number
        return {"L_over_D": None, "source": f"none: {knot_type} has no crossing number",
                "shape_shipped": False}
    source = ("measured on the shipped ideal polygon (Ashton et al. 2011)" if known
              else "estimated from the crossing number (tightknot.knots.catalogue)")
    return {"L_over_D": value, "source": source, "shape_shipped": has_ideal(knot_type)}


def knot_title(closed: bool, knot_type: str) -> str:
    """A knot's name in figure titles: 'closed trefoil 3_1', 'open figure-eight 4_1',
    'closed 5_2 knot' (by its measured type, not the scene's name)."""
    common = {"3_1": "trefoil 3_1", "4_1": "figure-eight 4_1"}
    return f"{'closed' if closed else 'open'} {common.get(knot_type, f'{knot_type} knot')}"


#: How far the sectioned level's mean sum of a contact sample's weights may stray from one
#: before a summary warns: the penalty's own largest force error in the squeeze it was
#: calibrated on is 8.1 % (N = 8, docs/sectioned_level.md), so a bias past 10 % is beyond
#: what the calibration can tell.
WEIGHT_SUM_TOLERANCE = 0.1


def calibration_range(scene: KnotScene, contact: ContactReport, x: np.ndarray | None = None,
                      rest: np.ndarray | None = None) -> dict[str, Any]:
    """Where the state stands against the range its contact law was calibrated in: the
    largest per-side approach w/D0 of its contacts (half the pair overlap), the law's
    calibrated limit, and a warning for each way the run leaves it (a deeper squeeze, whose
    force is then extrapolated; with the positions ``x`` [m] and rest lengths ``rest`` [m],
    a crossing deeper than the point law's fit, whose core was fitted to line squeezes
    only; a rod that is not incompressible, nu != 0.5, while the law was calibrated on an
    incompressible solid; at the sectioned level, sections thinner than the FEM judged
    them, :attr:`~tightknot.contact.sectioned.SectionCalibration.judged_area_ratio`, and
    with its bend shift a bend tighter than the FEM measured the shift at,
    :data:`~tightknot.contact.section_shift.MEASURED_KAPPA_R`, and contacts whose weights
    stray from one by more than :data:`WEIGHT_SUM_TOLERANCE`: ``contact_weight_sum_mean``)."""
    law = scene.contact.law
    w_hat = 0.5 * float(np.max(contact.overlap, initial=0.0)) / scene.diameter
    warnings = []
    w_cross = None
    if not law.rigid and x is not None and rest is not None:
        w_cross = deepest_approaches(scene.contact, x, rest)[1] / scene.diameter
    # The sectioned level's range is its own calibration's (the squeeze fit, the crossing
    # the FEM judged), the other levels' their law's.
    sectioned = isinstance(scene.contact, SectionedLayer)
    limit = scene.contact.calibration.calibrated_w_hat if sectioned else law.calibrated_w_hat
    cross_limit = scene.contact.calibration.crossing_w_hat if sectioned else law.power_w_hat
    what = "the sections were calibrated to" if sectioned else "the law was calibrated to"
    if not law.rigid:
        if w_hat > limit:
            warnings.append(f"the contact reaches a per-side approach w/D0 = {w_hat:.3g}, "
                            f"beyond the {limit:.3g} {what} (its force there is "
                            "extrapolated)")
        if w_cross is not None and w_cross > cross_limit:
            judged = ("the FEM judged a crossing at" if sectioned
                      else "the point law was fitted to")
            warnings.append(f"a crossing reaches w/D0 = {w_cross:.3g}, beyond the "
                            f"{cross_limit:.3g} {judged} (its force there is extrapolated)")
        area = float(np.min(contact.area_ratio, initial=1.0))
        if sectioned and area < scene.contact.calibration.judged_area_ratio:
            warnings.append(f"the sections' area falls to A/A0 = {area:.3g}, below the "
                            f"{scene.contact.calibration.judged_area_ratio:.3g} at which "
                            "the FEM judged them (a section that thin is extrapolated)")
        shift = getattr(scene.contact, "shift", None) if sectioned else None
        if shift is not None and x is not None and rest is not None:
            kr = shift.max_kappa_r(x, rest)
            if kr > MEASURED_KAPPA_R:
                warnings.append(f"the sections' bend shift reaches kappa R = {kr:.3g}, beyond "
                                f"the {MEASURED_KAPPA_R:.3g} at which the FEM measured it "
                                "(docs/fem_nip.md; the shift there is extrapolated)")
        weight_sum = contact.weight_sum_mean  # None but at the sectioned level
        if weight_sum is not None and abs(weight_sum - 1.0) > WEIGHT_SUM_TOLERANCE:
            warnings.append(f"the sections' contacts weigh {weight_sum:.3g} times on average "
                            "where the penalty was calibrated at one: the weights that blend a "
                            "partner's edges do not sum to one there (contacts on the inside "
                            "of a partner bent tighter than the partition is exact for, "
                            "rho kappa above about 0.7, or inside a rod's exclusion ramp; "
                            "docs/sectioned_level.md, 'The partner's partition of unity on a "
                            "bent partner')")
        nus = {r.material.poisson_ratio for r in scene.model.rods}
        if any(abs(nu - 0.5) > 1e-12 for nu in nus):
            warnings.append(f"the rod has Poisson ratio {min(nus):g}, the contact law was "
                            "calibrated on an incompressible solid (nu = 0.5): extrapolated")
    return {"max_approach_w_over_D0": w_hat,
            "contact_weight_sum_mean": contact.weight_sum_mean,
            "calibrated_w_over_D0": None if law.rigid else limit,
            "max_crossing_w_over_D0": w_cross,
            "crossing_calibrated_w_over_D0": None if law.rigid else cross_limit,
            "outside_calibrated_range": bool(warnings), "warnings": warnings}


def run_knot(scene: KnotScene, log: Any | None = None, name: str | None = None,
             counter: list[int] | None = None, *, color_by: str = "kappa_D0",
             progress: ProgressCallback | None = None, **tie_options: Any) -> KnotRun:
    """Tie ``scene`` (options of :func:`tightknot.loading.tie.tie`, or ``target_lambda`` for
    :func:`tightknot.loading.pull.tie_to_lambda`), logging each load step to ``log`` with the
    tube coloured by ``color_by`` and reporting it to ``progress``.

    The final state is logged as one more step whenever it is not the last logged one (a
    failed run, whose last attempt did not converge), so the .rrd always ends on the state
    the summary describes. ``summary["load_steps"]`` counts the converged load steps, each
    passed to the hook: those of the continuation and, in a pull to a target Lambda_OC,
    each equilibrium of the force search.
    """
    check_color_field(color_by)
    name = name or scene.name
    counter = counter if counter is not None else [0]
    logged: dict = {}
    # Always hooked: the hook numbers the steps on the timeline and reports progress.
    inner = logging_hook(log, scene, name, counter, color_by, progress, logged)
    calls = [0]
    pulled: list[tuple[float, float, float | None]] = []

    def hook(phase: str, system: RodSystem, rec: Any) -> None:
        calls[0] += 1
        inner(phase, system, rec)
        if phase == "pull" and not scene.closed:
            pulled.append(pull_point(scene, system))

    target = tie_options.pop("target_lambda", None)
    coarse = tie_options.pop("coarse_nodes", None)
    if coarse is not None and coarse < scene.model.vertex_count:
        # Mesh continuation: the load path on a coarse copy, then refined.
        res = tie_refined(scene, coarse, target_lambda=target, hook=hook,
                          **tie_options).run()
    elif target is not None:
        res = tie_to_lambda(scene, target, hook=hook, **tie_options).run()
    else:
        res = tie(scene, hook=hook, **tie_options).run()
    x = res.system.state.x
    if log is not None and not np.array_equal(logged.get("x"), x):
        log.set_step(counter[0])
        counter[0] += 1
        log_state(log, scene, name, res.system, color_by, logged.get("phase"))
    run = measure_run(scene, res, calls[0])
    if not scene.closed:
        # The pull's own force-extension data, in the order its equilibria were reached (a
        # search for a Lambda_OC brackets its target, so the force need not grow).
        run.summary["pull_series"] = {"pull_force_N": [p[0] for p in pulled],
                                      "end_to_end_m": [p[1] for p in pulled],
                                      "lambda_oc": [p[2] for p in pulled]}
    return run


def measure_run(scene: KnotScene, res: TieResult, load_steps: int) -> KnotRun:
    """The study's measurements of a tied knot (``res``, its final system's state) and its
    JSON summary, with ``load_steps`` converged load steps (as :func:`run_knot` counts
    them)."""
    x = res.system.state.x
    _, r_v = vertex_radii(scene, x, res.system.rest)
    # Contact as physics.md sec. 2 defines it for a rod model: distance at most the sum of
    # the deformed radii; the measurement's 1 % tolerance covers the vertex sampling of the
    # centerline (segments touch between vertices) and the contact law's onset band. The
    # measured line is the sections' centres (the centreline unless they shift in a bend).
    rep = analyze_centerline(contact_centres(scene, x, res.system.rest), scene.diameter,
                             scene.closed, rest_length=scene.rest_length, radii=r_v,
                             contact_tol=CONTACT_TOL)
    contact = contact_report(scene.contact, x, res.system.rest, res.system.state)
    summary = summarise(scene, res, rep, contact)
    summary["load_steps"] = load_steps
    # What the mesh costs in accuracy, so a coarse run says so (the trade-off study's numbers);
    # its warning stays in this entry: "warnings" are about the contact law's validity.
    summary["resolution"] = resolution_note(scene.closed, scene.model.vertex_count)
    if "start" in scene.info:
        # A user's start curve: its file, unit and size; knot_type is the type detected on
        # it and kept at every load step.
        summary["start_curve"] = dict(scene.info["start"])
    return KnotRun(scene, res, rep, contact, summary)


#: Tail shown beyond the knot in an open knot's tube picture, in rest diameters D0.
TUBE_TAIL_D0 = 1.5


def draw_tube(run: KnotRun, path: Path, field: str = "kappa_D0") -> Path:
    """The final rod of ``run`` as a 3D tube (deformed radii) coloured by ``field``.

    An open knot is drawn from TUBE_TAIL_D0 before its first contact to as far after its
    last (the long straight tails would shrink the knot to a dot); without contact, whole.
    """
    from tightknot.viz.tube_figure import render_tube

    system = run.result.system
    x = system.state.x
    _, r_v = vertex_radii(run.scene, x, system.rest)
    values, at = rod_field(check_color_field(field), run.scene, x, system.rest, run.contact)
    if not run.scene.closed:
        touching = np.nonzero(run.contact.contact_width_fraction > 0)[0]
        if touching.size:
            s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(x, axis=0), axis=1))]
            tail = TUBE_TAIL_D0 * run.scene.diameter
            i0 = int(np.searchsorted(s, s[touching[0]] - tail))
            i1 = int(np.searchsorted(s, s[touching[-1]] + tail)) + 1
            x, r_v = x[i0:i1], r_v[i0:i1]
            values = values[i0:i1] if at == "vertex" else values[i0:i1 - 1]
    s = run.summary
    what = (f"L0/D0 = {run.scene.rest_length / run.scene.diameter:.2f}" if run.scene.closed
            else f"L0 = {run.scene.rest_length * 1e3:.0f} mm, F = {s['pull_force_N']:.3g} N" + (
                "" if s.get("lambda_oc") is None else f", Lambda_OC = {s['lambda_oc']:.2f}"))
    title = f"{knot_title(run.scene.closed, s['knot_type'])}: {what}"
    view = (60.0, -60.0) if run.scene.closed else (70.0, -90.0)
    return render_tube(path, x, r_v, run.scene.closed, values, field, title, field_at=at,
                       view=view)


def draw_figures(runs: list[KnotRun], folder: Path, tube: str | None = None) -> list[Path]:
    """The study's figures of the runs into ``folder`` (created); returns the paths.

    ``tube``: also draw each run's final rod as a tube coloured by this field
    (``tube_<field>.png``; ``<i>_tube_<field>.png`` for several runs).
    """
    # matplotlib only here: importing it costs 1.5-2 s in every fresh sweep worker.
    import matplotlib

    matplotlib.use("Agg")
    from tightknot.viz import figures

    folder.mkdir(parents=True, exist_ok=True)
    paths: list[Path] = []
    if tube is not None:
        for i, r in enumerate(runs):
            name = f"tube_{tube}.png" if len(runs) == 1 else f"{i}_tube_{tube}.png"
            paths.append(draw_tube(r, folder / name, tube))
    closed = [r for r in runs if r.scene.closed]
    opened = [r for r in runs if not r.scene.closed]
    if closed:
        ideals: dict[tuple[str, float], dict | None] = {}
        for r in closed:
            # The ideal knot of the run's own type, where its shape is shipped; another
            # knot's is placed on the run's s by its best-matching curvature profile.
            kt, d0 = r.report["knot_type"], r.scene.diameter
            if (kt, d0) not in ideals:
                ideals[(kt, d0)] = ideal_report(kt, d0)
            ref = ideals[(kt, d0)]
            ref = None if ref is None else aligned(r.report, ref)
            p1, p2 = folder / "closed_profiles.png", folder / "closed_contact_map.png"
            figures.plot_closed_profiles(r.report, p1, ideal=ref, label="elastic rod",
                                         knot=knot_title(True, kt))
            figures.plot_contact_map(r.report, p2, ideal=ref, label="elastic rod",
                                     knot=knot_title(True, kt))
            paths += [p1, p2]
    if opened:
        reps, lcs, areas, press = {}, {}, {}, {}
        judged = [r.scene.contact.calibration.judged_area_ratio for r in opened
                  if isinstance(r.scene.contact, SectionedLayer)]
        for r in opened:
            lab = f"L0 = {r.scene.rest_length * 1e3:.0f} mm, F = {r.result.pull_force_N:.3g} N"
            order = np.asarray(r.report.get("vertex_order", np.arange(len(r.contact.area_ratio))),
                               dtype=int)
            reps[lab] = r.report
            lcs[lab] = r.contact.contact_width_fraction[order]
            areas[lab] = r.contact.area_ratio[order]
            if not r.scene.contact.law.rigid:
                press[lab] = r.contact.peak_pressure_over_E[order]
        p = folder / "open_knots.png"
        figures.plot_open_knots(reps, p, contact_width=lcs, area_ratio=areas, pressure=press,
                                judged_area_ratio=max(judged) if judged else None)
        paths.append(p)
    return paths
