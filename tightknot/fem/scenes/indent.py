"""Scene ``indent``: crossing contact of two strands, a rod squeezed between two rigid
cylinders of the same diameter D0 crossing it at 90 degrees (one above, one below).

Geometry (SI): rod of diameter D0 along e_z, indenters along e_x with centres at
(0, +-(D0/2 + D0/2 - w), 0). Symmetry planes x = 0, y = 0 and z = 0: one eighth is meshed
(quarter section times half length). The far end z = L/2 is traction free; L = 3 D0 by
default, long enough that the end does not feel the contact (the rod's section deforms
over about one diameter around the crossing).

Per-side approach w: each indenter moves by w toward the rod axis; by symmetry the
centroid of the rod's mid cross-section stays on the axis, so w is the reduction of the
distance from that centroid to the indenter's contact plane on one side, and the total
approach of the two indenters (the scene's "approach") is 2 w.

Note: the indenters here are RIGID; two elastic strands crossing each other share the
overlap (w_i + w_j = delta), see :mod:`tightknot.fem.overlap`.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from .. import hertz
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
from ..measure import contact_nodal, edge_position, line_profile, section_area, volume_ratio
from ..mesh import extrude, lateral_faces, lumped_face_weights, quarter_disk
from ..solver import Problem
from ._common import (
    PENALTY_FACTOR,
    SMOOTHING_FACTOR,
    check_common,
    check_positive,
    finite,
    load_schedule,
    mesh_convergence,
    relative,
)
from ._sections import RodSections

SECTION_POINTS: dict[str, int] = {"coarse": 7, "medium": 9, "fine": 11}
"""Points per edge n of the quarter section (3 (n - 1)^2 quads: 108, 192, 300)."""

AXIAL_FINE_CELLS: dict[str, int] = {"coarse": 6, "medium": 9, "fine": 12}
"""Uniform hexahedra along z in the refined zone 0 <= z <= 0.4 D0 under the contact."""

AXIAL_COARSE_CELLS: int = 4
"""Geometrically growing hexahedra from z = 0.4 D0 to the free end."""

REFINED_LENGTH_OVER_D0: float = 0.4
"""Length of the uniformly refined zone [D0]: the patch semi-axis reaches ~0.3 D0."""

HEADLINE_KEYS = (
    "force_over_e_d0sq",
    "semi_axis_axial_over_d0",
    "semi_axis_transverse_over_d0",
    "peak_pressure_over_e",
    "area_ratio_mid",
)


def axial_nodes(half_length: float, diameter: float, fine_cells: int) -> np.ndarray:
    """z coordinates [m]: uniform in the refined zone, then growing by a constant ratio."""
    z_fine = REFINED_LENGTH_OVER_D0 * diameter
    if half_length <= z_fine:
        return np.linspace(0.0, half_length, fine_cells + 1)
    h = z_fine / fine_cells
    rest = half_length - z_fine
    # ratio q with h q (q^n - 1)/(q - 1) = rest, n = AXIAL_COARSE_CELLS (bisection)
    n = AXIAL_COARSE_CELLS
    lo, hi = 1.0 + 1e-9, 10.0
    for _ in range(200):
        q = 0.5 * (lo + hi)
        total = h * q * (q**n - 1.0) / (q - 1.0)
        lo, hi = (q, hi) if total < rest else (lo, q)
    steps = h * q ** np.arange(1, n + 1)
    steps *= rest / steps.sum()
    return np.concatenate([np.linspace(0.0, z_fine, fine_cells + 1),
                           z_fine + np.cumsum(steps)])


def run(mesh: str = "coarse", max_approach_over_d0: float = 0.3, steps: int = 10,
        length_over_d0: float = 3.0, convergence: bool = True,
        diameter: float = ROD_DIAMETER, youngs_modulus: float = YOUNGS_MODULUS
        ) -> dict[str, Any]:
    """Indent a rod by two crossing rigid cylinders up to a total approach
    ``max_approach_over_d0`` D0 (``w`` per side is half of it).

    Returns a JSON-serialisable dict with ``steps``, ``hertz`` (crossed cylinders =
    sphere on a flat, rigid indenter), ``mesh_convergence`` (if ``convergence``), ``mesh``,
    ``parameters`` and ``wall_time_s``.
    """
    check_common(mesh, max_approach_over_d0, steps)
    check_positive("length_over_d0", length_over_d0)
    check_positive("diameter", diameter)
    check_positive("youngs_modulus", youngs_modulus)
    if length_over_d0 < 2.0 * REFINED_LENGTH_OVER_D0 + 0.2:
        raise ValueError(f"length_over_d0 must be >= {2 * REFINED_LENGTH_OVER_D0 + 0.2} "
                         f"(the refined zone), got {length_over_d0}")
    kwargs = dict(max_approach_over_d0=max_approach_over_d0, steps=steps,
                  length_over_d0=length_over_d0, diameter=diameter,
                  youngs_modulus=youngs_modulus)
    result = _run_one(mesh, **kwargs)
    result["mesh_convergence"] = mesh_convergence(lambda lvl: _run_one(lvl, **kwargs),
                                                  HEADLINE_KEYS, result, mesh, convergence)
    return finite(result)


def _run_one(level: str, max_approach_over_d0: float, steps: int, length_over_d0: float,
             diameter: float, youngs_modulus: float) -> dict[str, Any]:
    fem = require_felupe()
    start = time.perf_counter()
    radius = diameter / 2.0
    mu = youngs_modulus / 3.0
    bulk = BULK_MODULUS * mu / SHEAR_MODULUS
    section = quarter_disk(radius, SECTION_POINTS[level])
    half_length = 0.5 * length_over_d0 * diameter
    z = axial_nodes(half_length, diameter, AXIAL_FINE_CELLS[level])
    body = extrude(section, z)
    region = fem.RegionHexahedron(body)
    field = fem.FieldContainer([fem.Field(region, dim=3)])
    solid = nearly_incompressible_solid(field, mu=mu, bulk=bulk)
    pts = body.points
    fixed = np.zeros((body.npoints, 3), dtype=bool)
    for axis in range(3):  # symmetry planes x = 0, y = 0, z = 0
        fixed[np.isclose(pts[:, axis], 0.0), axis] = True

    faces = lateral_faces(body, radius)
    weights = lumped_face_weights(pts, faces)
    candidates = np.unique(faces)
    near = (pts[candidates, 1] > 0.3 * radius) & (pts[candidates, 2] < 0.8 * diameter)
    candidates = candidates[near]
    edges = np.linalg.norm(pts[faces[:, 1]] - pts[faces[:, 0]], axis=1)
    h_min = float(edges[edges > 0].min())
    indenter = RigidCylinder(center=np.array([0.0, radius + radius, 0.0]),
                             axis=np.array([1.0, 0.0, 0.0]), radius=radius)
    contact = PenaltyContact(indenter, candidates, weights[candidates],
                             stiffness=PENALTY_FACTOR * youngs_modulus / h_min,
                             smoothing=SMOOTHING_FACTOR * h_min)
    problem = Problem(field, solid, [contact], fixed.ravel(),
                      force_scale=youngs_modulus * diameter**2)
    area0 = section_area(section.points, section.cells)
    on_top = np.isclose(pts[candidates, 0], 0.0)  # generatrix x = 0 under the indenter
    on_mid = np.isclose(pts[candidates, 2], 0.0)  # mid cross-section z = 0
    mid_points = np.arange(section.npoints)
    # the rod's sections layer by layer, the contact centre under the indenter
    sections = RodSections.from_section(section, radius, np.array([0.0, radius]), z, 0)

    def apply(w: float) -> None:
        indenter.shift = np.array([0.0, -w, 0.0])

    def measure(w: float) -> dict[str, Any]:
        x = problem.positions()
        force, pressure = contact_nodal(contact, x, faces)
        f_side = 4.0 * float(force[:, 1].sum())  # x < 0 and z < 0 quarters of the patch
        # axial force in the mid section (tension > 0): the z > 0 half of the rod is held
        # by it against the contact forces' axial components (on the rod: -force), two
        # indenters times two x halves
        axial = 4.0 * float(-force[:, 2].sum())
        s_z, p_z = line_profile(contact, x, pressure, on_top, axis=2)
        s_x, p_x = line_profile(contact, x, pressure, on_mid, axis=0)
        a_z, a_x = edge_position(s_z, p_z), edge_position(s_x, p_x)
        area = section_area(x[mid_points, :2], section.cells)
        p_all = np.zeros(body.npoints)
        p_all[contact.points] = pressure
        return {
            "approach_over_d0": 2.0 * w / diameter,
            "w_over_d0": w / diameter,
            "force": f_side,
            "force_over_e_d0sq": f_side / (youngs_modulus * diameter**2),
            "semi_axis_axial_over_d0": a_z / diameter,
            "semi_axis_transverse_over_d0": a_x / diameter,
            "peak_pressure_over_e": float(pressure.max()) / youngs_modulus,
            "mean_pressure_over_e": (f_side / (math.pi * a_x * a_z) / youngs_modulus
                                     if a_x * a_z > 0 else 0.0),
            "area_ratio_mid": area / area0,
            "axial_force_mid_over_e_d0sq": axial / (youngs_modulus * diameter**2),
            "volume_ratio": volume_ratio(solid),
            "newton_iterations": int(problem.iterations[-1]) if problem.iterations else 0,
            # A/A0, L_c and p/E per node layer along the rod (the soft scenes' profile)
            "profile_a": sections.profile(x, p_all, youngs_modulus, diameter),
        }

    loads = load_schedule(0.5 * max_approach_over_d0 * diameter, steps)
    table = problem.run(loads, apply, measure)
    nu = poisson_ratio(bulk, mu)
    return {
        "scene": "indent",
        "mesh": {"level": level, "elements": int(body.ncells), "points": int(body.npoints),
                 "section_quads": int(section.ncells), "dofs": int(body.npoints * 3)},
        "parameters": {
            "diameter_m": diameter, "youngs_modulus_pa": youngs_modulus,
            "shear_modulus_pa": mu, "bulk_modulus_pa": bulk, "poisson_ratio": nu,
            "indenter_radius_m": radius, "segment_length_m": 2.0 * half_length,
            "penalty_pa_per_m": contact.stiffness, "penalty_onset_m": contact.smoothing,
            "smallest_contact_element_m": h_min,
        },
        "steps": table,
        "hertz": _hertz_check(table, radius, youngs_modulus, nu, diameter),
        "wall_time_s": time.perf_counter() - start,
    }


def _hertz_check(table: list[dict], radius: float, youngs_modulus: float, nu: float,
                 diameter: float, w_hat_max: float = 0.015) -> dict[str, Any]:
    """Compare small-load steps with Hertz crossed cylinders (rigid indenter, E* = E/(1-nu^2)).

    Force at the same approach: F = (4/3) E* sqrt(R) w^(3/2) (Johnson 1985 eq. 4.23),
    taking the centroid approach w as the Hertz approach (the section's own flattening
    adds a compliance linear in F, so the FEM force is expected slightly BELOW Hertz).
    Patch radius and peak pressure at the FEM force: a = (3 F R / (4 E*))^(1/3),
    p0 = 3 F / (2 pi a^2) (Johnson 1985 eqs. 4.21-4.22), which are local and sharper.
    """
    e_star = hertz.contact_modulus_rigid(youngs_modulus, nu)
    rows = []
    for step in table:
        if step["w_over_d0"] > w_hat_max:
            continue
        w = step["w_over_d0"] * diameter
        f = step["force"]
        f_h = hertz.sphere_force(w, radius, e_star)
        a_h = (3.0 * f * radius / (4.0 * e_star)) ** (1.0 / 3.0)
        p_h = hertz.sphere_peak_pressure(f, a_h)
        rows.append({
            "w_over_d0": step["w_over_d0"], "force": f, "force_hertz": f_h,
            "force_rel_error": relative(f, f_h),
            "semi_axis_axial_over_d0": step["semi_axis_axial_over_d0"],
            "semi_axis_transverse_over_d0": step["semi_axis_transverse_over_d0"],
            "contact_radius_hertz_over_d0": a_h / diameter,
            "semi_axis_axial_rel_error": relative(step["semi_axis_axial_over_d0"] * diameter,
                                                  a_h),
            "semi_axis_transverse_rel_error": relative(
                step["semi_axis_transverse_over_d0"] * diameter, a_h),
            "peak_pressure_over_e": step["peak_pressure_over_e"],
            "peak_pressure_hertz_over_e": p_h / youngs_modulus,
            "peak_pressure_rel_error": relative(step["peak_pressure_over_e"] * youngs_modulus,
                                                p_h),
        })
    return {
        "applicable": True,
        "formula": "Hertz crossed cylinders of equal radius R = sphere of radius R on a flat; "
                   "rigid indenter: E* = E/(1-nu^2); F = (4/3) E* sqrt(R) w^(3/2) (Johnson "
                   "1985 eq. 4.23), a = (3FR/(4E*))^(1/3), p0 = 3F/(2 pi a^2)",
        "w_over_d0_max": w_hat_max,
        "steps": rows,
    }
