"""The rod model in the FEM's two-soft-rod scenes: the soft wrap, the clasp and the soft
crossing.

The same load levels and parameters as :mod:`tightknot.fem.scenes.soft_wrap`,
:mod:`tightknot.fem.scenes.clasp` and :mod:`tightknot.fem.scenes.soft_crossing`, on the
rod model (DER rods, straight at rest) with its contact term at a chosen level. Both
partners are soft here, so the pair law is the
shipped one, the overlap split evenly between the two rods (no rigid counter-body
scaling, unlike :mod:`tightknot.fem.rod_model`).

The contact level is one parameter, ``contact``, and one small helper builds its term
(:func:`contact_term`, the knots' :func:`tightknot.knots.scenes.contact_layer`): a further
level plugs in by joining :data:`CONTACT_LEVELS` (the sectioned level has), provided its term
offers what the measurements here use:
its contact forces (:meth:`tightknot.solvers.system.RodSystem.term_gradient`) and
:func:`tightknot.contact.report.contact_report` at the system's state (the per-vertex L_c,
A/A0 and p/E; :func:`_report` is the one call).
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from .material import ROD_DIAMETER, YOUNGS_MODULUS
from .rod_model import (
    DENSITY,
    EDGES_PER_D0,
    WRAP_START_OVERLAP,
    _solve_levels,
    check_edges_per_d0,
    wrap_scene,
)
from .rod_sectioned import axis_reading, far_fibre_axis

CONTACT_LEVELS: tuple[str, ...] = ("compliant", "smoothed", "sectioned")
"""Contact levels of the rod model here (:func:`contact_term`)."""

#: Rods on each side of rod A in the soft crossing's stack (:func:`soft_crossing_scene`):
#: the outermost ones, pressed from one side only, perturb the inner contacts through the
#: chain of sections between them, by turns up and down with the depth. At 6 the sectioned
#: level's force at the FEM's levels within the approach limit moves by at most 0.7 % from
#: 5 (at the deepest, w = 0.15 D0, by 4.5 %; docs/sectioned_level.md).
STACK_DEPTH: int = 6


def check_contact(contact: Any) -> Any:
    """``contact`` if it is one of :data:`CONTACT_LEVELS` or a sectioned level's
    :class:`~tightknot.contact.sectioned.SectionSettings`, else ValueError naming them."""
    from tightknot.contact.sectioned import SectionSettings

    if not isinstance(contact, SectionSettings) and contact not in CONTACT_LEVELS:
        raise ValueError(f"contact must be one of {CONTACT_LEVELS}, got {contact!r}")
    return contact


def _name(contact: Any) -> str:
    """The level's name of ``contact`` (a name, or a sectioned level's settings)."""
    from tightknot.knots.scenes import contact_name

    return contact_name(contact)


def _centres(term: Any, system: Any) -> np.ndarray:
    """The centres [m] of the rod model's sections at the system's state: the centreline,
    or the offset one of a sectioned level whose sections shift in a bend."""
    centres = getattr(term, "boundary_centres", None)
    x = system.state.x
    return x if centres is None else centres(x, system.rest)


def contact_term(model: Any, contact: str = "compliant", law: Any = None) -> Any:
    """The rod model's contact term at level ``contact`` for ``model``, with the pair law
    ``law`` (default: the shipped FEM calibration): the knots' own definition of the level
    (:func:`tightknot.knots.scenes.contact_layer`), so that these scenes judge the level the
    knots are tied with. A new level joins :data:`CONTACT_LEVELS` here once its term gives
    what :func:`_report` and the measurements read."""
    from tightknot.knots.scenes import contact_layer

    return contact_layer(model, check_contact(contact), law)


def _report(term: Any, system: Any) -> Any:
    """Per-vertex contact outputs of the term (L_c, A/A0, p/E, overlap) at the system's
    state (the sectioned level reads its sections there)."""
    from tightknot.contact.report import contact_report

    return contact_report(term, system.state.x, system.rest, system.state)


def _profile(report: Any, vertices: np.ndarray, s_rest: np.ndarray,
             diameter: float) -> list[dict[str, float]]:
    """Per vertex of one rod: rest arc length, A/A0, L_c and p_max/E."""
    return [{"s_over_d0": float(s) / diameter,
             "area_ratio": float(report.area_ratio[v]),
             "contact_fraction": float(report.contact_width_fraction[v]),
             "peak_pressure_over_e": float(report.peak_pressure_over_E[v])}
            for v, s in zip(vertices, s_rest, strict=True)]


def _along(report: Any, vertices: np.ndarray, s_rest: np.ndarray, diameter: float,
           first: int) -> list[dict[str, float]]:
    """The profile judged along the contact, from ``vertices[first]`` outward: at the
    sectioned level per Gauss circle from the edge before it, so that s = 0 lies inside
    (:func:`tightknot.fem.profile_compare.circle_profile`), else per vertex
    (:func:`_profile`)."""
    if report.circles is not None and first > 0:
        from tightknot.fem.profile_compare import circle_profile

        return circle_profile(report.circles, vertices[first - 1:], s_rest[first - 1:],
                              diameter)
    return _profile(report, vertices[first:], s_rest[first:], diameter)


def _builder_rod(points: np.ndarray, diameter: float, youngs_modulus: float) -> tuple:
    from tightknot.rods.builder import RodBuilder
    from tightknot.rods.material import Material

    b = RodBuilder(twist=False)
    b.add_rod(points[0], diameter, Material(youngs_modulus, 0.5, DENSITY))
    b.add_rod(points[1], diameter, Material(youngs_modulus, 0.5, DENSITY))
    return b.finalize()


def rod_soft_wrap(tension_levels: list[float], wrap_angle_deg: float = 90.0,
                  diameter: float = ROD_DIAMETER, youngs_modulus: float = YOUNGS_MODULUS,
                  length_over_d0: float = 4.5, law: Any = None,
                  contact: str = "compliant", edges_per_d0: int = EDGES_PER_D0
                  ) -> dict[str, Any]:
    """The soft wrap with the rod model: rod A (axis e_z at rest) pulled by dead end forces
    T (0, sin(theta), +-cos(theta)) [N] (``tension_levels``) around rod B along e_x, held
    as the FEM scene's stack holds it (:func:`tightknot.fem.rod_model.wrap_scene` with
    ``stack``: B pressed by A and A's mirror image, its axis straight, free to stretch
    along it), with the soft pair law; ``edges_per_d0``: both rods' resolution.

    Returns per level the keys of :func:`tightknot.fem.rod_model.rod_wrap` (the mid line
    load per length of the nominal axis, its curvature and approach, overlap, A/A0, peak
    pressure; the nominal axis is the centreline, or at the sectioned level the far fibre
    moved in by the stretched radius, as the FEM's), ``kappa_d0_mid_centerline`` (the
    centreline's curvature), ``area_ratio_mid_b``, ``profile_a``, ``profile_b``; and the
    wall time.
    """
    from tightknot.knots.curvature import bergou_curvature

    start = time.perf_counter()
    check_contact(contact)
    d0 = diameter
    # The rigid wrap's rods and constraints, B held as the FEM's stack holds it (a pinned
    # B could not thin where it is pressed, as the solid's does).
    scene = wrap_scene(diameter, youngs_modulus, length_over_d0, wrap_angle_deg,
                       edges_per_d0=edges_per_d0, stack=True)
    system, load, model = scene.system, scene.load, scene.model
    n_rod, n_obs, mid, half = scene.n_rod, scene.n_obs, scene.mid, scene.half
    y_obs = d0 - WRAP_START_OVERLAP * d0
    term = contact_term(model, contact, law)
    system.add_term(term)
    rod_v, obs_v = scene.rod_v, scene.obs_v
    s_a = np.linspace(-half, half, n_rod + 1)
    s_b = np.linspace(-2 * d0, 2 * d0, n_obs + 1)

    def measure(tension: float) -> dict[str, Any]:
        x = _centres(term, system)
        g = system.term_gradient(term)
        xr = x[rod_v]
        e = np.linalg.norm(np.diff(xr, axis=0), axis=1)
        voronoi = 0.5 * (e[mid - 1] + e[mid])
        # The axis the FEM's nominal one (its far fibre moved in by the stretched radius)
        # stands for: the centreline, whose far side a compliant or smoothed section keeps
        # at that radius; a sectioned level's far side moves with its modes, so it is read
        # on its far fibre as the rigid wrap's is (rod_sectioned.rod_wrap_sectioned).
        kappa_c = float(bergou_curvature(xr, closed=False)[mid])
        if hasattr(term, "boundary_centres"):
            r_str = 0.5 * d0 / math.sqrt(voronoi / (2.0 * half / n_rod))
            near = rod_v[mid - 3:mid + 4]
            nominal = far_fibre_axis(term, system, near, y_obs, r_str)
            f_mid, kappa = axis_reading(nominal, float(np.linalg.norm(g[rod_v[mid]])))
            xm = nominal[3]
        else:
            f_mid = float(np.linalg.norm(g[rod_v[mid]]) / voronoi)
            kappa = kappa_c
            xm = xr[mid]
        dist = math.hypot(y_obs - xm[1], xm[2])
        rep = _report(term, system)
        prof_a = _profile(rep, rod_v, s_a, d0)
        prof_b = _profile(rep, obs_v, s_b, d0)
        return {
            "tension": tension,
            "tension_over_e_d0sq": tension / (youngs_modulus * d0**2),
            "approach_over_d0": (d0 - dist) / d0,
            "overlap_over_d0": float(rep.overlap[rod_v[mid]]) / d0,
            "contact_weight_sum_mean": rep.weight_sum_mean,
            "axial_stretch_mid": float(voronoi / (2.0 * half / n_rod)),
            # on A (B carries A's and its mirror image's, which cancel)
            "contact_force_total": float(np.linalg.norm(g[rod_v].sum(axis=0))),
            "force_per_length_mid": f_mid,
            "force_per_length_mid_over_e_d0": f_mid / (youngs_modulus * d0),
            "kappa_d0_mid": kappa * d0,
            "kappa_d0_mid_centerline": kappa_c * d0,
            "area_ratio_mid": prof_a[mid]["area_ratio"],
            "area_ratio_mid_b": prof_b[n_obs // 2]["area_ratio"],
            "peak_pressure_over_e": prof_a[mid]["peak_pressure_over_e"],
            "contact_fraction_max": max(r["contact_fraction"] for r in prof_a),
            "profile_a": _along(rep, rod_v, s_a, d0, mid),
            "profile_b": _along(rep, obs_v, s_b, d0, n_obs // 2),
        }

    rows = _solve_levels(system, load, list(tension_levels), measure)
    return {"steps": rows, "wall_time_s": time.perf_counter() - start,
            "vertices": int(model.vertex_count), "contact": _name(contact)}


def clasp_centrelines(bend_radius: float, leg_length: float, diameter: float,
                      edges_per_d0: int = EDGES_PER_D0, initial_gap: float = 0.0
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Both U's of the clasp scene (:mod:`tightknot.fem.scenes.clasp`) as vertex arrays
    [m], clamp to clamp through the apex (an even number of edges, a vertex at the apex),
    and the rest arc length of each vertex from the apex [m]. Placed as the FEM scene
    places its U's, whose start map thickens the bends' inner sides: the apex centrelines
    2 b' + ``initial_gap`` [m] apart (:func:`~tightknot.fem.scenes.clasp.start_apex_x`;
    the FEM's gap is in its ``parameters``), so that both models clamp their rods at the
    same points; the rod model's round sections then start 2 b' - D0 apart."""
    from .scenes.clasp import rotate_to_b, start_apex_x, u_centreline

    x_apex = start_apex_x(bend_radius, 0.5 * diameter, initial_gap)
    length = 0.5 * math.pi * bend_radius + leg_length
    n_half = int(round(length / diameter * edges_per_d0))
    s = np.linspace(-length, length, 2 * n_half + 1)
    c, _ = u_centreline(np.abs(s), bend_radius, x_apex - bend_radius)
    c[s < 0.0, 1] *= -1.0
    return np.stack([c, rotate_to_b(c)]), s


def rod_clasp(pull_levels: list[float], bend_radius_over_d0: float = 1.5,
              leg_length_over_d0: float = 1.5, diameter: float = ROD_DIAMETER,
              youngs_modulus: float = YOUNGS_MODULUS, law: Any = None,
              contact: str = "compliant", initial_gap: float = 0.0,
              edges_per_d0: int = EDGES_PER_D0) -> dict[str, Any]:
    """The clasp with the rod model: two U's (straight at rest, started on the FEM
    scene's U and clamped where it clamps its rods, the FEM's start gap ``initial_gap``
    [m], :func:`clasp_centrelines` at ``edges_per_d0``), each end clamped (its two end
    vertices held), relaxed, then the clamps moved apart along x by ``pull_levels`` [m]
    (half each).

    Returns per level: ``force`` [N] (the x contact force on A: the pull, by statics),
    ``approach_over_d0`` (D0 minus the apex vertices' distance), ``kappa_d0_apex``,
    ``area_ratio_apex``, ``peak_pressure_over_e``, ``contact_fraction_max``,
    ``profile_a``/``profile_b`` (from the apex to a clamp); before the pull,
    ``relaxed_apex_shift_over_d0`` (how far the apex moved out along the pull axis as the
    U settled in its clamps, measured as the FEM scene measures it on its mid fibre) and
    ``relaxed_area_ratio_apex`` and ``relaxed_inner_side_over_r`` (how far the apex's
    inner side reaches from the centreline, over R); and the wall time.
    """
    from tightknot.knots.curvature import bergou_curvature
    from tightknot.loading.levels import LevelLoad, LevelOptions, LevelPath
    from tightknot.rods.boundary import BoundaryConditions
    from tightknot.rods.state import State
    from tightknot.solvers.program import Program
    from tightknot.solvers.system import RodSystem

    start = time.perf_counter()
    check_contact(contact)
    d0 = diameter
    check_edges_per_d0(edges_per_d0)
    curves, s = clasp_centrelines(bend_radius_over_d0 * d0, leg_length_over_d0 * d0, d0,
                                  edges_per_d0, initial_gap=initial_gap)
    model = _builder_rod(curves, d0, youngs_modulus)
    n = len(s) - 1
    apex = n // 2
    load = LevelLoad()
    bcs = BoundaryConditions(model)
    for rod, sign in ((0, -1.0), (1, 1.0)):
        for k in (0, 1, n - 1, n):
            bcs.pin(rod, k, translation=lambda t, sg=sign: np.array([0.5 * sg * load(t),
                                                                      0.0, 0.0]))
    system = RodSystem(model, State.initial(model), bcs)
    term = contact_term(model, contact, law)
    system.add_term(term)
    va = np.arange(model.rods[0].vertex_start, model.rods[0].vertex_start + n + 1)
    vb = np.arange(model.rods[1].vertex_start, model.rods[1].vertex_start + n + 1)
    # the rods settle in their clamps first (straight at rest, started bent)
    path = LevelPath(system, load, LevelOptions(steps="one", proximal_dt=1e-3), level=0.0)
    relaxed = not Program(path.solve(0.0), "relax").run()
    # the relaxed apex's shift out along the pull axis: the apex vertex from the clamped
    # end's (the clamp face's centre), less rho + leg, as the FEM scene measures it
    xr = system.state.x[va]
    apex_shift = float(xr[apex, 0] - xr[0, 0]) - (bend_radius_over_d0
                                                  + leg_length_over_d0) * d0
    relaxed_area = _profile(_report(term, system), va[apex:], s[apex:], d0)[0]["area_ratio"]
    # the inner side's reach from the centreline [R]: the round section's radius, plus the
    # boundary's shift toward the bend's centre (-x at A's apex) where the level has one
    inner = relaxed_area ** 0.5
    shift = getattr(term, "shift", None)
    if shift is not None:
        moved = shift.at(system.state.x, system.rest).x[va[apex]] - xr[apex]
        inner -= float(moved[0]) / (0.5 * d0)

    def measure(pull: float) -> dict[str, Any]:
        x = system.state.x
        g = system.term_gradient(term)
        force = -float(g[va, 0].sum())
        rep = _report(term, system)
        prof_a = _profile(rep, va[apex:], s[apex:], d0)
        xa = x[va]
        e = np.linalg.norm(np.diff(xa, axis=0), axis=1)
        stretch = float(0.5 * (e[apex - 1] + e[apex]) / (s[1] - s[0]))
        return {
            "pull_over_d0": pull / d0,
            "force": force,
            "force_over_e_d0sq": force / (youngs_modulus * d0**2),
            "approach_over_d0": (d0 - float(np.linalg.norm(xa[apex] - x[vb[apex]]))) / d0,
            "axial_stretch_apex": stretch,
            "contact_weight_sum_mean": rep.weight_sum_mean,
            "kappa_d0_apex": float(bergou_curvature(xa, closed=False)[apex]) * d0,
            "area_ratio_apex": prof_a[0]["area_ratio"],
            "area_ratio_min": min(r["area_ratio"] for r in prof_a),
            "peak_pressure_over_e": max(r["peak_pressure_over_e"] for r in prof_a),
            "contact_fraction_max": max(r["contact_fraction"] for r in prof_a),
            "profile_a": _along(rep, va, s, d0, apex),
            "profile_b": _along(rep, vb, s, d0, apex),
        }

    rows = _solve_levels(system, load, list(pull_levels), measure) if relaxed else []
    return {"steps": rows, "relaxed": relaxed, "relaxed_apex_shift_over_d0": apex_shift / d0,
            "relaxed_area_ratio_apex": relaxed_area, "relaxed_inner_side_over_r": inner,
            "wall_time_s": time.perf_counter() - start,
            "vertices": int(model.vertex_count), "contact": _name(contact)}


def soft_crossing_scene(diameter: float, youngs_modulus: float, length_over_d0: float,
                        edges_per_d0: int = EDGES_PER_D0, depth: int = STACK_DEPTH
                        ) -> tuple[Any, Any, list[int], tuple[int, ...]]:
    """The FEM's ``soft_crossing`` stack (:mod:`tightknot.fem.scenes.soft_crossing`) as
    rods: every rod pressed from both sides by rods like it crossing at 90 degrees, each
    held on its mid-plane. 2 ``depth`` + 1 rods, alternately along e_z and e_x, at y = k s
    for k = 0, 1, -1, ..., depth, -depth (s = D0 - 2 w at the level load w, touching at
    rest): rod A (k = 0) and rod B (k = 1) are pressed from both sides, the outermost two
    close the stack (pressed from one side only). Each rod's centreline is held at its y
    (the FEM's held mid-plane) and in the symmetry plane that holds its axis (x = 0 for
    those along e_z, z = 0 for those along e_x), its middle vertex in the other symmetry
    plane; it slides and stretches along its axis. Returns the system, the level load, the
    rods' edge counts and their k."""
    from tightknot.loading.levels import LevelLoad
    from tightknot.rods.boundary import BoundaryConditions
    from tightknot.rods.builder import RodBuilder
    from tightknot.rods.material import Material
    from tightknot.rods.state import State
    from tightknot.solvers.system import RodSystem

    from .rod_model import _line_points

    check_edges_per_d0(edges_per_d0)
    if isinstance(depth, bool) or not isinstance(depth, int) or depth < 1:
        raise ValueError(f"depth must be an integer >= 1, got {depth!r}")
    d0 = diameter
    n = int(round(length_over_d0 * edges_per_d0))
    n += n % 2  # even: a vertex at the crossing
    half = 0.5 * length_over_d0 * d0
    mat = Material(youngs_modulus, 0.5, DENSITY)
    load = LevelLoad()
    b = RodBuilder(twist=False)
    levels = (0, *(k * sign for k in range(1, depth + 1) for sign in (1, -1)))
    for k in levels:
        axis = np.array([0.0, 0.0, 1.0]) if k % 2 == 0 else np.array([1.0, 0.0, 0.0])
        centre = np.array([0.0, k * d0, 0.0])
        b.add_rod(_line_points(centre - half * axis, centre + half * axis, n), d0, mat)
    model = b.finalize()
    bcs = BoundaryConditions(model)
    for rod, k in enumerate(levels):
        plane = 0 if k % 2 == 0 else 2  # the symmetry plane that holds the rod's axis
        for v in range(n + 1):
            bcs.hold_components(rod, v, (1,), lambda t, k=k: np.array(
                [k * (d0 - 2.0 * load(t))]))
            bcs.fix_components(rod, v, (plane,))
        bcs.fix_components(rod, n // 2, (2 - plane,))
    system = RodSystem(model, State.initial(model), bcs)
    return system, load, [n] * len(levels), levels


def rod_soft_crossing(w_levels: list[float], diameter: float = ROD_DIAMETER,
                      youngs_modulus: float = YOUNGS_MODULUS, length_over_d0: float = 3.0,
                      law: Any = None, contact: Any = "compliant",
                      edges_per_d0: int = EDGES_PER_D0, depth: int = STACK_DEPTH
                      ) -> dict[str, Any]:
    """The soft crossing with the rod model: the stack of :func:`soft_crossing_scene`,
    its neighbours moved toward each other by 2 w [m] (``w_levels``: the approach per rod,
    as in the FEM scene), at contact level ``contact``.

    Returns per level: ``force`` [N] between rods A and B (the contact force on the rods
    above A, which inside them only A pushes), ``force_from_below`` (the same for the
    rods below, the stack's symmetry), ``approach_over_d0`` (2 w / D0),
    ``area_ratio_mid`` and ``area_ratio_mid_b`` (A's and B's crossing sections),
    ``peak_pressure_over_e`` and ``contact_width_fraction_mid`` (A's crossing section, its
    two contacts), ``profile_a`` (A from the crossing to its end, as the FEM's; B is its
    image); and the wall time."""
    start = time.perf_counter()
    check_contact(contact)
    d0 = diameter
    system, load, edges, levels = soft_crossing_scene(diameter, youngs_modulus,
                                                      length_over_d0, edges_per_d0, depth)
    model = system.model
    term = contact_term(model, contact, law)
    system.add_term(term)
    mid = edges[0] // 2
    a_v = model.rods[0].vertex_start + mid
    b_v = model.rods[1].vertex_start + mid

    def rods(side: int) -> np.ndarray:
        return np.concatenate([np.arange(model.rods[r].vertex_start,
                                         model.rods[r].vertex_start + edges[r] + 1)
                               for r, k in enumerate(levels) if k * side > 0])

    above, below = rods(1), rods(-1)
    # rod A's vertices from the one before the crossing on, with their rest arc length
    # from the crossing
    va = np.arange(a_v - 1, model.rods[0].vertex_start + edges[0] + 1)
    s_a = (va - a_v) * (length_over_d0 * d0 / edges[0])

    def measure(w: float) -> dict[str, Any]:
        g = system.term_gradient(term)
        force = -float(g[above, 1].sum())
        rep = _report(term, system)
        return {
            "w_over_d0": w / d0, "approach_over_d0": 2.0 * w / d0, "force": force,
            "force_from_below": float(g[below, 1].sum()),
            "force_over_e_d0sq": force / (youngs_modulus * d0**2),
            "area_ratio_mid": float(rep.area_ratio[a_v]),
            "area_ratio_mid_b": float(rep.area_ratio[b_v]),
            "peak_pressure_over_e": float(rep.peak_pressure_over_E[a_v]),
            "contact_width_fraction_mid": float(rep.contact_width_fraction[a_v]),
            "contact_weight_sum_mean": rep.weight_sum_mean,
            "profile_a": _along(rep, va, s_a, d0, 1),
        }

    rows = _solve_levels(system, load, list(w_levels), measure)
    return {"steps": rows, "wall_time_s": time.perf_counter() - start,
            "vertices": int(model.vertex_count), "contact": _name(contact)}
