"""Scene ``squeeze``: a rod section pressed between two rigid frictionless plates.

By symmetry about the mid-plane between two rods, this is also one rod pressed against an
identical parallel rod (line contact of parallel strands).

Geometry (SI): rod of diameter D0, axis e_z, plates normal to e_y at y = +-(D0/2 - w).
Models:
- ``plane_strain``: quarter section (symmetry planes x = 0 and y = 0), per unit length.
- ``3d``: quarter section extruded over half a segment of length L (symmetry z = 0), with
  ``ends="plane"`` (u_z = 0 on both end faces: the exact plane-strain solution, a check)
  or ``ends="free"`` (traction-free end faces: the section spreads axially and its area
  drops).

Per-side approach w: the plates move by w each, and the section centroid stays at
y = 0 by symmetry, so w is exactly the reduction of the centroid-to-contact-plane distance
on one side; the total diameter reduction (the scene's "approach") is 2 w.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from .. import hertz
from .._backend import require_felupe
from ..contact import PenaltyContact, RigidPlane
from ..material import (
    BULK_MODULUS,
    ROD_DIAMETER,
    SHEAR_MODULUS,
    YOUNGS_MODULUS,
    nearly_incompressible_solid,
    poisson_ratio,
)
from ..measure import (
    boundary_length,
    contact_nodal,
    edge_position,
    line_profile,
    section_area,
    volume_ratio,
)
from ..mesh import axial_coordinates, extrude, lateral_faces, lumped_face_weights, quarter_disk
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

SECTION_POINTS: dict[str, int] = {"coarse": 9, "medium": 13, "fine": 19}
"""Points per edge n of the quarter section in 3D (3 (n - 1)^2 quads)."""

SECTION_POINTS_2D: dict[str, int] = {"coarse": 9, "medium": 17, "fine": 33}
"""Points per edge n of the plane-strain quarter section: 192, 768, 3072 quads."""

AXIAL_CELLS: dict[str, int] = {"coarse": 4, "medium": 6, "fine": 9}
"""Hexahedra along the half segment (free ends: graded toward the free end)."""

HEADLINE_KEYS = (
    "force_per_length_over_e_d0",
    "half_width_over_d0",
    "peak_pressure_over_e",
    "contact_fraction_side",
    "area_ratio",
)
"""Outputs compared across meshes (at the largest load)."""

MODELS = ("plane_strain", "3d")
ENDS = ("plane", "free")


def _validate(model: str, ends: str, length_over_d0: float) -> None:
    if model not in MODELS:
        raise ValueError(f"model must be one of {MODELS}, got {model!r}")
    if ends not in ENDS:
        raise ValueError(f"ends must be one of {ENDS}, got {ends!r}")
    check_positive("length_over_d0", length_over_d0)


def run(mesh: str = "coarse", max_approach_over_d0: float = 0.3, steps: int = 12,
        model: str = "plane_strain", ends: str = "plane", length_over_d0: float = 2.0,
        convergence: bool = True, diameter: float = ROD_DIAMETER,
        youngs_modulus: float = YOUNGS_MODULUS) -> dict[str, Any]:
    """Squeeze a rod between two plates up to a total approach ``max_approach_over_d0`` D0.

    Returns a JSON-serialisable dict: ``steps`` (per load step), ``hertz`` (plane-strain
    Hertz check at small loads), ``mesh_convergence`` (if ``convergence``), ``mesh``,
    ``parameters``, ``wall_time_s``. See the module docstring for the geometry.
    """
    check_common(mesh, max_approach_over_d0, steps)
    _validate(model, ends, length_over_d0)
    check_positive("diameter", diameter)
    check_positive("youngs_modulus", youngs_modulus)
    kwargs = dict(max_approach_over_d0=max_approach_over_d0, steps=steps, model=model, ends=ends,
                  length_over_d0=length_over_d0, diameter=diameter,
                  youngs_modulus=youngs_modulus)
    result = _run_one(mesh, **kwargs)
    result["mesh_convergence"] = mesh_convergence(lambda lvl: _run_one(lvl, **kwargs),
                                                  HEADLINE_KEYS, result, mesh, convergence)
    return finite(result)


def _run_one(level: str, max_approach_over_d0: float, steps: int, model: str, ends: str,
             length_over_d0: float, diameter: float, youngs_modulus: float) -> dict[str, Any]:
    fem = require_felupe()
    start = time.perf_counter()
    radius = diameter / 2.0
    mu = youngs_modulus / 3.0
    bulk = BULK_MODULUS * mu / SHEAR_MODULUS  # keep K/mu fixed
    plane = model == "plane_strain"
    n = (SECTION_POINTS_2D if plane else SECTION_POINTS)[level]
    section = quarter_disk(radius, n)
    half_length = 0.5 * length_over_d0 * diameter
    if plane:
        body = section
        region = fem.RegionQuad(body)
        field = fem.FieldContainer([fem.FieldPlaneStrain(region, dim=2)])
    else:
        grading = 0.5 if ends == "free" else 0.0
        z = half_length - axial_coordinates(half_length, AXIAL_CELLS[level], grading)[::-1]
        body = extrude(section, z)
        region = fem.RegionHexahedron(body)
        field = fem.FieldContainer([fem.Field(region, dim=3)])
    dim = 2 if plane else 3
    solid = nearly_incompressible_solid(field, mu=mu, bulk=bulk)
    pts = body.points
    fixed = np.zeros((body.npoints, dim), dtype=bool)
    fixed[np.isclose(pts[:, 0], 0.0), 0] = True  # symmetry x = 0
    fixed[np.isclose(pts[:, 1], 0.0), 1] = True  # symmetry y = 0 (mid-plane of the section)
    if not plane:
        fixed[np.isclose(pts[:, 2], 0.0), 2] = True  # symmetry z = 0
        if ends == "plane":
            fixed[np.isclose(pts[:, 2], half_length), 2] = True  # frictionless plane end

    faces = lateral_faces(body, radius)
    weights = lumped_face_weights(pts, faces)
    candidates = np.unique(faces)
    candidates = candidates[pts[candidates, 1] > 0.5 * radius]  # only the top can touch
    edges2d = lateral_faces(section, radius)
    h_min = float(np.linalg.norm(section.points[edges2d[:, 1]] - section.points[edges2d[:, 0]],
                                 axis=1).min())
    plate = RigidPlane(point=np.array([0.0, radius, 0.0]), normal=np.array([0.0, -1.0, 0.0]))
    contact = PenaltyContact(plate, candidates, weights[candidates],
                             stiffness=PENALTY_FACTOR * youngs_modulus / h_min,
                             smoothing=SMOOTHING_FACTOR * h_min)
    force_scale = youngs_modulus * diameter * (1.0 if plane else half_length)
    problem = Problem(field, solid, [contact], fixed.ravel(), force_scale)

    area0 = section_area(section.points, section.cells)
    perimeter0 = boundary_length(section.points, edges2d)
    on_mid = np.ones(len(candidates), bool) if plane else np.isclose(pts[candidates, 2], 0.0)
    mid_points = np.arange(section.npoints)  # first layer of the extrusion is z = 0

    def apply(w: float) -> None:
        plate.shift = np.array([0.0, -w, 0.0])

    def measure(w: float) -> dict[str, Any]:
        x = problem.positions()
        force, pressure = contact_nodal(contact, x, faces)
        total = float(force[:, 1].sum())  # on the quarter (2D) or eighth (3D) model
        # force per unit length of the whole side: x2 for the x < 0 half, and in 3D per
        # unit length of the modelled half segment
        f_side = 2.0 * total / (1.0 if plane else half_length)
        s, p = line_profile(contact, x, pressure, on_mid, axis=0)
        b = edge_position(s, p)
        xy = x[mid_points, :2]
        area = section_area(xy, section.cells)
        perimeter = 4.0 * boundary_length(xy, edges2d)
        mid_p = pressure[on_mid]
        return {
            "approach_over_d0": 2.0 * w / diameter,
            "w_over_d0": w / diameter,
            "force_per_length": f_side,
            "force_per_length_over_e_d0": f_side / (youngs_modulus * diameter),
            "half_width_over_d0": b / diameter,
            "contact_fraction_side": 2.0 * b / perimeter,
            "perimeter_ratio": perimeter / (4.0 * perimeter0),
            "peak_pressure_over_e": float(pressure.max()) / youngs_modulus,
            "peak_pressure_mid_over_e": float(mid_p.max()) / youngs_modulus,
            "mean_pressure_over_e": (f_side / (2.0 * b) / youngs_modulus) if b > 0 else 0.0,
            "area_ratio": area / area0,
            "volume_ratio": volume_ratio(solid),
            "newton_iterations": int(problem.iterations[-1]) if problem.iterations else 0,
        }

    loads = load_schedule(0.5 * max_approach_over_d0 * diameter, steps)
    table = problem.run(loads, apply, measure)
    nu = poisson_ratio(bulk, mu)
    result: dict[str, Any] = {
        "scene": "squeeze",
        "model": model,
        "ends": ends if not plane else "plane strain",
        "mesh": {"level": level, "elements": int(body.ncells), "points": int(body.npoints),
                 "section_quads": int(section.ncells),
                 "dofs": int(body.npoints * dim)},
        "parameters": {
            "diameter_m": diameter, "youngs_modulus_pa": youngs_modulus,
            "shear_modulus_pa": mu, "bulk_modulus_pa": bulk, "poisson_ratio": nu,
            "segment_length_m": None if plane else 2.0 * half_length,
            "penalty_pa_per_m": contact.stiffness, "penalty_onset_m": contact.smoothing,
            "smallest_contact_element_m": h_min,
        },
        "steps": table,
        "hertz": _hertz_check(table, radius, youngs_modulus, nu, diameter)
        if (plane or ends == "plane") else
        {"applicable": False, "reason": "free ends: no plane-strain closed form"},
        "wall_time_s": time.perf_counter() - start,
    }
    return result


def _hertz_check(table: list[dict], radius: float, youngs_modulus: float, nu: float,
                 diameter: float, w_hat_max: float = 0.0125) -> dict[str, Any]:
    """Compare the small-load steps (w/D0 <= ``w_hat_max``) with plane-strain Hertz.

    Force: Johnson (1985) sec. 5.6 approach of the disk centre (see
    :func:`tightknot.fem.hertz.line_approach_per_side`) inverted for P(w). Half-width and
    peak pressure: eqs. (4.43)-(4.44) at the FEM force, E* = E / (1 - nu^2) (rigid plate).
    """
    e_star = hertz.contact_modulus_rigid(youngs_modulus, nu)
    rows = []
    for step in table:
        if step["w_over_d0"] > w_hat_max:
            continue
        w = step["w_over_d0"] * diameter
        f = step["force_per_length"]
        f_h = hertz.line_force_per_length(w, radius, youngs_modulus, nu)
        b_h = hertz.line_half_width(f, radius, e_star)
        p_h = hertz.line_peak_pressure(f, b_h)
        rows.append({
            "w_over_d0": step["w_over_d0"],
            "force_per_length": f, "force_per_length_hertz": f_h,
            "force_rel_error": relative(f, f_h),
            "half_width_over_d0": step["half_width_over_d0"],
            "half_width_hertz_over_d0": b_h / diameter,
            "half_width_rel_error": relative(step["half_width_over_d0"] * diameter, b_h),
            "peak_pressure_over_e": step["peak_pressure_mid_over_e"],
            "peak_pressure_hertz_over_e": p_h / youngs_modulus,
            "peak_pressure_rel_error": relative(step["peak_pressure_mid_over_e"] * youngs_modulus,
                                                p_h),
        })
    return {
        "applicable": True,
        "formula": "plane-strain Hertz line contact on a rigid flat, E* = E/(1-nu^2); "
                   "w = P(1-nu^2)/(pi E) (2 ln(4R/b) - 1) per side (Johnson 1985 sec. 5.6), "
                   "b = sqrt(4PR/(pi E*)) (eq. 4.43), p0 = 2P/(pi b) (eq. 4.44)",
        "w_over_d0_max": w_hat_max,
        "steps": rows,
    }
