"""Scene ``wrap``: a rod under axial tension T pulled around a rigid frictionless cylinder
of the same diameter D0 (a strand of a knot bent around another).

Geometry (SI). At rest the rod is straight, diameter D0, axis e_z, centred at the origin,
length L. The rigid cylinder (radius D0/2) lies along e_x above the rod, its axis through
(0, D0 - s0, 0): it touches the rod's top generatrix at z = 0 with a small initial overlap
s0 (see below). Both ends carry a dead (fixed-direction) force of magnitude T,

    F_end(z = +-L/2) = T (0, sin(theta), +-cos(theta)),   theta = wrap_angle / 2,

spread over the end face as a uniform traction, so the rod is pulled up around the
cylinder and, once aligned with its end loads, wraps it over the angle ``wrap_angle``
(the angle between the two straight tails). Symmetry planes x = 0 (the plane of the rod's
axis) and z = 0 (the middle of the contact): one quarter of the rod is meshed, a HALF
section (x >= 0; no symmetry in y: the contact side is at y > 0) times half the length.

Force control and the rigid-body mode. The rod is held in y only by the contact, whose
stiffness vanishes at first touch (C2 penalty onset), so a force-controlled start from an
exact touch is singular. The cylinder therefore starts overlapping the rod by
s0 = ``INITIAL_OVERLAP`` x h_min: the first Newton iterations slide the rod down onto the
cylinder. Under force control the rod's position relative to the cylinder is an OUTPUT, so
s0 changes nothing in the converged states (only the start of the first increment).

Approach and overlap of the mid section (z = 0), with d the distance from its centroid to
the cylinder axis (one-sided: the cylinder is rigid, so the rod takes all of it, w = delta;
see :mod:`tightknot.fem.overlap`):

- ``approach_over_d0`` = (D0 - d) / D0: nominal radii (rest rod radius D0/2);
- ``overlap_over_d0`` = (r0 lambda^(-1/2) + D0/2 - d) / D0: the rod model's pair overlap
  delta, with the stretched radius r0 lambda^(-nu), nu = 1/2 (incompressible), lambda the
  axial stretch of the centroid line at the mid section.

Nominal axis (keys ``*_nominal``): the far fibre (the section's point opposite the
contact, x = 0, y lowest) moved toward the cylinder along the far fibre's normal by the
stretched radius r0 lambda^(-1/2) of the mid section: the centre of the circle that the
rod model puts around its centerline, whose far side it keeps undeformed.
``approach_nominal_over_d0`` is D0 minus its distance to the cylinder axis at z = 0,
``kappa_d0_mid_nominal`` its Bergou curvature at z = 0 (the same 7-point stencil as the
centroid's), ``force_per_length_mid_nominal`` the mid layer's contact force per length of
it. The centroid line (``kappa_d0_mid``, ``force_per_length_mid``) bends more than this
axis where the section flattens (see :mod:`tightknot.fem.crosscheck`). ``profile`` holds,
per refined layer, the centroid, far and near fibres, nominal axis and line loads.

Closed forms (key ``closed_form``; there is no Hertz formula for this conforming contact):
the total contact force equals 2 T sin(theta) exactly (equilibrium of the whole rod with a
frictionless cylinder), and where the bending moment is nearly constant along the wrap the
line load obeys the membrane (Laplace) relation f = N kappa with N the axial force in the
section, N = T at the middle to first order (frictionless: no axial load is lost on the
cylinder; Johnson 1985 does not cover this, it is string statics, e.g. the capstan equation
with zero friction).
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from .._backend import require_felupe
from ..contact import PenaltyContact, RigidCylinder
from ..material import (
    BULK_MODULUS,
    ROD_DIAMETER,
    SHEAR_MODULUS,
    YOUNGS_MODULUS,
    nearly_incompressible_solid,
    poisson_ratio,
)
from ..measure import contact_nodal, edge_position, volume_ratio
from ..mesh import _HEX_FACES, extrude, lateral_faces, lumped_face_weights, quarter_disk
from ..solver import Problem
from ._common import (
    PENALTY_FACTOR,
    check_positive,
    finite,
    load_schedule,
    mesh_convergence,
    relative,
)
from ._sections import RodSections

SECTION_POINTS: dict[str, int] = {"coarse": 5, "medium": 7, "fine": 9}
"""Points per edge n of each quarter of the half section (6 (n - 1)^2 quads: 96, 216, 384)."""

AXIAL_FINE_CELLS: dict[str, int] = {"coarse": 6, "medium": 9, "fine": 12}
"""Uniform hexahedra along z over the refined zone (the wrapped arc plus 0.3 D0)."""

AXIAL_COARSE_CELLS: dict[str, int] = {"coarse": 4, "medium": 5, "fine": 6}
"""Geometrically growing hexahedra from the refined zone to the loaded end."""

INITIAL_OVERLAP: float = 0.5
"""Initial overlap s0 of the cylinder into the rod over the smallest contact element [-]."""

WRAP_SMOOTHING_FACTOR: float = 0.05
"""Penalty onset depth g0 over h_min. Larger than the displacement-controlled scenes'
(``SMOOTHING_FACTOR`` = 1e-3): under force control the rod floats on the contact, and a
sharp onset lets nodes at the patch edge switch on and off between Newton iterations.
With g0 = 0.05 h_min the quadratic onset covers pressures up to eps g0 / 2 = 2.5 E, so the
whole contact uses p = eps pen^2 / (2 g0): penetration sqrt(2 g0 p / eps) = 0.022 h_min at
p = 0.5 E (0.2 % of D0 on the coarse mesh)."""

DEFAULT_STEPS: int = 6
"""Default number of tension levels."""

HEADLINE_KEYS = (
    "overlap_over_d0",
    "area_ratio_mid",
    "height_over_d0",
    "force_per_length_mid_over_e_d0",
    "peak_pressure_over_e",
    "kappa_d0_mid",
    "approach_nominal_over_d0",
    "force_per_length_mid_nominal_over_e_d0",
    "kappa_d0_mid_nominal",
)
"""Outputs compared across meshes (at the largest tension)."""


def _check_angle(wrap_angle_deg: float) -> None:
    if not (isinstance(wrap_angle_deg, (int, float)) and math.isfinite(wrap_angle_deg)
            and 10.0 <= wrap_angle_deg <= 120.0):
        raise ValueError(f"wrap_angle_deg must lie in [10, 120] degrees, got {wrap_angle_deg!r}")


def check_inputs(mesh: str, max_tension_over_e_d0sq: float, steps: int, wrap_angle_deg: float,
                 length_over_d0: float, diameter: float, youngs_modulus: float) -> None:
    """Raise ValueError naming the parameter for bad input of :func:`run`."""
    from ._common import MESH_LEVELS

    if mesh not in MESH_LEVELS:
        raise ValueError(f"mesh must be one of {MESH_LEVELS}, got {mesh!r}")
    if not (isinstance(max_tension_over_e_d0sq, (int, float))
            and math.isfinite(max_tension_over_e_d0sq)
            and 0.0 < max_tension_over_e_d0sq <= 0.5):
        # T = 0.5 E D0^2 is an axial nominal stress 0.64 E (stretch ~ 1.8): beyond it the
        # section thins so much that the contact leaves the calibrated range.
        raise ValueError("max_tension_over_e_d0sq must lie in (0, 0.5] (tension over "
                         f"E D0^2), got {max_tension_over_e_d0sq!r}")
    if not isinstance(steps, int) or isinstance(steps, bool) or steps < 1:
        raise ValueError(f"steps must be an integer >= 1, got {steps!r}")
    _check_angle(wrap_angle_deg)
    check_positive("length_over_d0", length_over_d0)
    check_positive("diameter", diameter)
    check_positive("youngs_modulus", youngs_modulus)
    half_arc = 0.5 * math.radians(wrap_angle_deg)
    if length_over_d0 < 2.0 * (half_arc + 1.3):
        raise ValueError(f"length_over_d0 must be >= {2.0 * (half_arc + 1.3):.3g} (the wrapped "
                         f"arc plus straight tails) for this wrap angle, got {length_over_d0}")


def half_disk(radius: float, n: int) -> Any:
    """Quad mesh of the half disk x >= 0 of radius ``radius`` [m]: the graded quarter disk
    (:func:`tightknot.fem.mesh.quarter_disk`, finest at the top (0, radius) where the
    cylinder presses) mirrored about y = 0, duplicate points on y = 0 merged."""
    fem = require_felupe()
    top = quarter_disk(radius, n)
    pts_top = np.asarray(top.points)
    pts_bot = pts_top * np.array([1.0, -1.0])
    cells_bot = np.asarray(top.cells)[:, ::-1] + len(pts_top)  # mirrored: keep orientation
    points = np.vstack([pts_top, pts_bot])
    cells = np.vstack([np.asarray(top.cells), cells_bot])
    # merge the points of the mirror plane y = 0 (exactly zero in quarter_disk)
    key = np.round(points / radius, 12)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    order = np.sort(first)  # kept points in their original order
    new_index = np.searchsorted(order, first)[inverse.ravel()]
    return fem.Mesh(points=points[order], cells=new_index[cells], cell_type="quad")


def axial_nodes(half_length: float, refined: float, fine_cells: int, coarse_cells: int
                ) -> np.ndarray:
    """z [m]: uniform over [0, ``refined``], then growing by a constant ratio to the end."""
    h = refined / fine_cells
    rest = half_length - refined
    lo, hi = 1.0 + 1e-9, 10.0  # ratio q with h q (q^n - 1)/(q - 1) = rest (bisection)
    for _ in range(200):
        q = 0.5 * (lo + hi)
        total = h * q * (q**coarse_cells - 1.0) / (q - 1.0)
        lo, hi = (q, hi) if total < rest else (lo, q)
    steps = h * q ** np.arange(1, coarse_cells + 1)
    steps *= rest / steps.sum()
    return np.concatenate([np.linspace(0.0, refined, fine_cells + 1), refined + np.cumsum(steps)])


def run(mesh: str = "coarse", max_tension_over_e_d0sq: float = 0.25,
        steps: int = DEFAULT_STEPS, wrap_angle_deg: float = 90.0, length_over_d0: float = 4.5,
        convergence: bool = True, diameter: float = ROD_DIAMETER,
        youngs_modulus: float = YOUNGS_MODULUS) -> dict[str, Any]:
    """Pull a rod around a rigid cylinder with end tensions up to
    ``max_tension_over_e_d0sq`` E D0^2 [N] in ``steps`` levels (quadratic spacing).

    Returns a JSON-serialisable dict with ``steps`` (per tension level), ``closed_form``
    (statics checks), ``hertz`` (not applicable), ``mesh_convergence`` (if
    ``convergence``), ``mesh``, ``parameters`` and ``wall_time_s``.
    """
    check_inputs(mesh, max_tension_over_e_d0sq, steps, wrap_angle_deg, length_over_d0,
                 diameter, youngs_modulus)
    kwargs = dict(max_tension_over_e_d0sq=max_tension_over_e_d0sq, steps=steps,
                  wrap_angle_deg=wrap_angle_deg, length_over_d0=length_over_d0,
                  diameter=diameter, youngs_modulus=youngs_modulus)
    result = _run_one(mesh, **kwargs)
    result["mesh_convergence"] = mesh_convergence(lambda lvl: _run_one(lvl, **kwargs),
                                                  HEADLINE_KEYS, result, mesh, convergence)
    return finite(result)


def _layer_centroids(x: np.ndarray, quads: np.ndarray, ns: int, layers: int) -> np.ndarray:
    """Centroids [m] of the full sections of the first ``layers`` layers (y, z from the
    half section, x = 0 by symmetry): area-weighted quad centroids of the deformed layer."""
    out = np.zeros((layers, 3))
    for k in range(layers):
        c = x[k * ns:(k + 1) * ns][quads]  # (nq, 4, 3)
        area = 0.5 * np.linalg.norm(np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 1]), axis=1)
        out[k, 1:] = (area[:, None] * c.mean(axis=1)[:, 1:]).sum(axis=0) / area.sum()
    return out


def _run_one(level: str, max_tension_over_e_d0sq: float, steps: int, wrap_angle_deg: float,
             length_over_d0: float, diameter: float, youngs_modulus: float) -> dict[str, Any]:
    fem = require_felupe()
    from tightknot.knots.curvature import bergou_curvature

    start = time.perf_counter()
    radius = diameter / 2.0
    mu = youngs_modulus / 3.0
    bulk = BULK_MODULUS * mu / SHEAR_MODULUS
    theta = 0.5 * math.radians(wrap_angle_deg)
    section = half_disk(radius, SECTION_POINTS[level])
    ns = section.npoints
    quads = np.asarray(section.cells)
    half_length = 0.5 * length_over_d0 * diameter
    refined = (theta + 0.3) * diameter  # the wrapped arc is about theta D0 long per half
    z = axial_nodes(half_length, refined, AXIAL_FINE_CELLS[level], AXIAL_COARSE_CELLS[level])
    body = extrude(section, z)
    region = fem.RegionHexahedron(body)
    field = fem.FieldContainer([fem.Field(region, dim=3)])
    solid = nearly_incompressible_solid(field, mu=mu, bulk=bulk)
    pts = body.points
    fixed = np.zeros((body.npoints, 3), dtype=bool)
    fixed[np.isclose(pts[:, 0], 0.0), 0] = True  # symmetry x = 0 (plane of the rod's axis)
    fixed[np.isclose(pts[:, 2], 0.0), 2] = True  # symmetry z = 0 (middle of the wrap)

    faces = lateral_faces(body, radius)
    weights = lumped_face_weights(pts, faces)
    candidates = np.unique(faces)
    candidates = candidates[pts[candidates, 1] > 0.0]  # only the upper side meets the cylinder
    edges = np.linalg.norm(pts[faces[:, 1]] - pts[faces[:, 0]], axis=1)
    h_min = float(edges[edges > 0].min())
    s0 = INITIAL_OVERLAP * h_min
    cylinder = RigidCylinder(center=np.array([0.0, diameter - s0, 0.0]),
                             axis=np.array([1.0, 0.0, 0.0]), radius=radius)
    contact = PenaltyContact(cylinder, candidates, weights[candidates],
                             stiffness=PENALTY_FACTOR * youngs_modulus / h_min,
                             smoothing=WRAP_SMOOTHING_FACTOR * h_min)
    problem = Problem(field, solid, [contact], fixed.ravel(),
                      force_scale=youngs_modulus * diameter**2, max_backtracks=6)

    # End face z = L/2: the modelled half face carries T/2, spread as a uniform traction.
    cell_faces = np.asarray(body.cells)[:, _HEX_FACES].reshape(-1, 4)
    end_faces = cell_faces[np.all(np.isclose(pts[cell_faces, 2], half_length), axis=1)]
    end_weights = lumped_face_weights(pts, end_faces)
    end_share = end_weights / end_weights.sum()
    direction = np.array([0.0, math.sin(theta), math.cos(theta)])
    external = np.zeros((body.npoints, 3))

    area0 = 2.0 * float(_polygon_area(section.points, quads))
    on_top = np.isclose(pts[candidates, 0], 0.0) & np.isclose(pts[candidates, 1], radius)
    on_mid = np.isclose(pts[candidates, 2], 0.0)
    layer_of = np.rint(np.searchsorted(z, pts[candidates, 2] - 1e-12 * diameter)).astype(int)
    n_layers_fine = AXIAL_FINE_CELLS[level] + 1
    sec = np.asarray(section.points)
    i_bottom = int(np.argmin(np.hypot(sec[:, 0], sec[:, 1] + radius)))  # (0, -r)
    i_top = int(np.argmin(np.hypot(sec[:, 0], sec[:, 1] - radius)))  # (0, r)
    # the rod's sections layer by layer, the contact centre on top (the cylinder's side)
    sections = RodSections.from_section(section, radius, np.array([0.0, radius]), z, 0)

    def apply(tension: float) -> None:
        external[:] = np.outer(0.5 * tension * end_share, direction)
        problem.external = external.ravel()

    def measure(tension: float) -> dict[str, Any]:
        x = problem.positions()
        force, pressure = contact_nodal(contact, x, faces)
        # quarter model -> whole rod: the z components cancel between the halves (they are
        # the symmetry reactions of z = 0 here), the y components add up
        total = 4.0 * abs(float(force[:, 1].sum()))
        cent = _layer_centroids(x, quads, ns, n_layers_fine)
        mid = cent[0]
        axis_y = cylinder.center[1] + cylinder.shift[1]
        d = abs(axis_y - mid[1])
        stretch = float(np.linalg.norm(cent[1] - cent[0]) / (z[1] - z[0]))
        r_stretched = radius * stretch**-0.5  # incompressible: r0 lambda^(-1/2)
        # line load per deformed axis length, layer by layer: nodal forces of the layer
        # (x2 for x < 0) over the layer's tributary length of the centroid line
        seg = np.linalg.norm(np.diff(cent, axis=0), axis=1)
        trib = np.concatenate([[0.5 * seg[0]], 0.5 * (seg[:-1] + seg[1:])])
        load = np.zeros(n_layers_fine)
        fmag = np.linalg.norm(force, axis=1)
        inside = layer_of < n_layers_fine
        np.add.at(load, layer_of[inside], 2.0 * fmag[inside])
        line = load[:-1] / trib  # the last refined layer lacks its outer neighbour
        # contact edges: across at the mid section, along the top generatrix (arc length)
        s_x = x[candidates[on_mid], 0]
        order = np.argsort(s_x)
        b_mid = edge_position(s_x[order], pressure[on_mid][order])
        top = x[candidates[on_top]]
        order = np.argsort(pts[candidates[on_top], 2])
        arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(top[order], axis=0),
                                                             axis=1))])
        a_len = edge_position(arc, pressure[on_top][order])
        xy = x[:ns, :2]
        area = 2.0 * float(_polygon_area(xy, quads))
        height = float(xy[:, 1].max() - xy[:, 1].min())
        width = 2.0 * float(xy[:, 0].max())
        mirror = cent[1:4] * np.array([1.0, 1.0, -1.0])
        axis_pts = np.vstack([mirror[::-1], cent[:4]])
        kappa = float(bergou_curvature(axis_pts, closed=False)[3])
        layers = np.arange(n_layers_fine) * ns
        bottom = x[layers + i_bottom]
        top_f = x[layers + i_top]
        # nominal axis (the rod model's centerline, see the module docstring): the far
        # fibre moved toward the cylinder by the stretched radius of the mid section (one
        # value: N = T all along a frictionless wrap, so the stretch is uniform there; a
        # radius per layer from the centroid line's lengths would carry the flattening's
        # centroid shifts into the axis)
        nominal = nominal_axis(bottom[:-1, 1:], np.full(n_layers_fine - 1, r_stretched))
        seg_n = np.linalg.norm(np.diff(nominal, axis=0), axis=1)
        trib_n = np.concatenate([[0.5 * seg_n[0]], 0.5 * (seg_n[:-1] + seg_n[1:])])
        line_n = load[:-2] / trib_n
        pts_n = np.column_stack([np.zeros(len(nominal)), nominal])
        mirror_n = pts_n[1:4] * np.array([1.0, 1.0, -1.0])
        kappa_n = float(bergou_curvature(np.vstack([mirror_n[::-1], pts_n[:4]]),
                                         closed=False)[3])
        d_n = axis_y - nominal[0, 0]
        f_mid = float(line[0])
        p_all = np.zeros(body.npoints)
        p_all[contact.points] = pressure
        return {
            "tension": tension,
            "tension_over_e_d0sq": tension / (youngs_modulus * diameter**2),
            "approach_over_d0": (diameter - d) / diameter,
            "overlap_over_d0": (r_stretched + radius - d) / diameter,
            "centroid_distance_over_d0": d / diameter,
            "axial_stretch_mid": stretch,
            "area_ratio_mid": area / area0,
            "area_ratio_stretch_only": 1.0 / stretch,
            "height_over_d0": height / diameter,
            "width_over_d0": width / diameter,
            "flattening": 1.0 - height / width,
            "contact_force_total": total,
            "contact_force_total_over_e_d0sq": total / (youngs_modulus * diameter**2),
            "force_per_length_mid": f_mid,
            "force_per_length_mid_over_e_d0": f_mid / (youngs_modulus * diameter),
            "force_per_length_max_over_e_d0": float(line.max()) / (youngs_modulus * diameter),
            "peak_pressure_over_e": float(pressure.max()) / youngs_modulus,
            "mean_pressure_mid_over_e": (f_mid / (2.0 * b_mid) / youngs_modulus
                                         if b_mid > 0 else 0.0),
            "contact_half_width_mid_over_d0": b_mid / diameter,
            "contact_half_length_over_d0": a_len / diameter,
            "kappa_d0_mid": kappa * diameter,
            "approach_nominal_over_d0": (diameter - d_n) / diameter,
            "force_per_length_mid_nominal": float(line_n[0]),
            "force_per_length_mid_nominal_over_e_d0": float(line_n[0])
            / (youngs_modulus * diameter),
            "kappa_d0_mid_nominal": kappa_n * diameter,
            "volume_ratio": volume_ratio(solid),
            "newton_iterations": int(problem.iterations[-1]) if problem.iterations else 0,
            # A/A0, L_c and p/E per node layer along the rod (the soft scenes' profile)
            "profile_a": sections.profile(x, p_all, youngs_modulus, diameter),
            "profile": {
                "z_rest_over_d0": z[:n_layers_fine] / diameter,
                "centroid_yz_over_d0": cent[:, 1:] / diameter,
                "far_fibre_yz_over_d0": bottom[:, 1:] / diameter,
                "near_fibre_yz_over_d0": top_f[:, 1:] / diameter,
                "line_load_over_e_d0": line / (youngs_modulus * diameter),
                "nominal_axis_yz_over_d0": nominal / diameter,
                "line_load_nominal_over_e_d0": line_n / (youngs_modulus * diameter),
                "cylinder_axis_y_over_d0": axis_y / diameter,
            },
        }

    tensions = load_schedule(max_tension_over_e_d0sq * youngs_modulus * diameter**2, steps)
    table = problem.run(tensions, apply, measure)
    nu = poisson_ratio(bulk, mu)
    return {
        "scene": "wrap",
        "mesh": {"level": level, "elements": int(body.ncells), "points": int(body.npoints),
                 "section_quads": int(section.ncells), "dofs": int(body.npoints * 3)},
        "parameters": {
            "diameter_m": diameter, "youngs_modulus_pa": youngs_modulus,
            "shear_modulus_pa": mu, "bulk_modulus_pa": bulk, "poisson_ratio": nu,
            "cylinder_radius_m": radius, "wrap_angle_deg": wrap_angle_deg,
            "segment_length_m": 2.0 * half_length, "initial_overlap_m": s0,
            "penalty_pa_per_m": contact.stiffness, "penalty_onset_m": contact.smoothing,
            "smallest_contact_element_m": h_min,
            "end_load": "dead force T (0, sin(theta), +-cos(theta)) per end, uniform traction",
        },
        "steps": table,
        "closed_form": _closed_form(table, theta),
        "hertz": {"applicable": False,
                  "reason": "conforming wrap contact: no Hertz formula; see closed_form"},
        "wall_time_s": time.perf_counter() - start,
    }


def nominal_axis(far_yz: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """Points (y, z) [m] of the nominal axis: each far-fibre point ``far_yz`` (first at
    z = 0, ascending z) moved by ``radius`` [m] (per point) along the far fibre's unit
    normal toward the cylinder (+y at z = 0). Tangents by central differences, the one at
    z = 0 from the mirror image (it is e_z by symmetry), the last one-sided."""
    far = np.asarray(far_yz, dtype=float)
    t = np.empty_like(far)
    t[0] = (0.0, 1.0)
    t[1:-1] = far[2:] - far[:-2]
    t[-1] = far[-1] - far[-2]
    t /= np.linalg.norm(t, axis=1)[:, None]
    normal = np.column_stack([t[:, 1], -t[:, 0]])  # t turned by -90 degrees in (y, z)
    return far + np.asarray(radius, dtype=float)[:, None] * normal


def _polygon_area(points_2d: np.ndarray, quads: np.ndarray) -> float:
    from ..mesh import polygon_area

    return polygon_area(np.asarray(points_2d)[:, :2], quads)


def _closed_form(table: list[dict], theta: float) -> dict[str, Any]:
    """Statics checks per level: total contact force against 2 T sin(theta) (exact), and
    the mid line load against the membrane relation f = T kappa (string statics; bending
    moments vary along the wrap, so this holds only approximately)."""
    rows = []
    for step in table:
        t = step["tension"]
        exact = 2.0 * t * math.sin(theta)
        kappa = step["kappa_d0_mid"]  # times D0 below
        rows.append({
            "tension_over_e_d0sq": step["tension_over_e_d0sq"],
            "contact_force_total_rel_error": relative(step["contact_force_total"], exact),
            "membrane_line_load_over_e_d0": step["tension_over_e_d0sq"] * kappa,
            "line_load_rel_to_membrane": relative(step["force_per_length_mid_over_e_d0"],
                                                  step["tension_over_e_d0sq"] * kappa),
        })
    return {
        "formula": "sum of contact forces = 2 T sin(theta) (equilibrium, exact); "
                   "f_mid ~ T kappa_mid (membrane / frictionless capstan, approximate)",
        "steps": rows,
    }
