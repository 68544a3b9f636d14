"""Scene ``soft_crossing``: two soft rods crossing at 90 degrees, pressed together, with
barrier contact between the two deformable bodies.

The soft-soft counterpart of ``indent`` (a rod between two crossing RIGID cylinders): the
same rod mesh, the same per-rod approach w. The rod model's pair law is calibrated on
rigid counter-bodies and splits a pair overlap delta evenly (w = delta / 2 per rod,
:mod:`tightknot.fem.overlap`), so it predicts the same force here as in ``indent`` at the
same w; Hertz for two identical elastic crossed cylinders (E* = E / (2 (1 - nu^2)) over
the total approach 2 w, Johnson 1985 eq. 4.23) predicts sqrt(2) times the rigid-indenter
force. This scene measures which.

Geometry (SI): rod A along e_z centred at the origin, rod B along e_x centred at
(0, D0 + g0, 0), g0 = dhat the initial gap. Symmetry planes x = 0 and z = 0 of both rods,
and each rod's own mid-plane (y = 0 for A, y = y_B for B: a stack in which every rod is
pressed from both sides, as in ``indent``): one quarter section times half a length of
each rod is meshed, B being A's mesh turned by 180 degrees about the line x = z,
y = y_B / 2. A's mid-plane is held, B's moves down by g0 + 2 w, so the distance between
the two axes is D0 - 2 w.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from .. import hertz
from .._backend import require_felupe
from ..barrier import DHAT_OVER_D0
from ..barrier_solver import BarrierProblem
from ..material import (
    BULK_MODULUS,
    ROD_DIAMETER,
    SHEAR_MODULUS,
    YOUNGS_MODULUS,
    poisson_ratio,
)
from ..measure import section_area
from ..mesh import extrude, lateral_faces, quarter_disk
from ._common import (
    check_common,
    check_dhat,
    check_positive,
    finite,
    load_schedule,
    mesh_convergence,
    relative,
)
from ._pair import (
    GAP_OVER_DHAT,
    bodies_solid,
    contact_edge,
    make_barrier,
    nodal_contact,
    turned_about_x_eq_z,
)
from .indent import AXIAL_FINE_CELLS, REFINED_LENGTH_OVER_D0, SECTION_POINTS, axial_nodes

HEADLINE_KEYS = ("force_over_e_d0sq", "semi_axis_axial_over_d0",
                 "semi_axis_transverse_over_d0", "peak_pressure_over_e", "area_ratio_mid")
"""Outputs compared with the rigid-cylinder indent and across meshes."""


def run(mesh: str = "coarse", max_approach_over_d0: float = 0.3, steps: int = 4,
        length_over_d0: float = 3.0, compare: bool = True, convergence: bool = False,
        dhat_over_d0: float = DHAT_OVER_D0,
        diameter: float = ROD_DIAMETER, youngs_modulus: float = YOUNGS_MODULUS
        ) -> dict[str, Any]:
    """Press two crossing soft rods together up to an approach of their axes of
    ``max_approach_over_d0`` D0 (2 w; w per rod); with ``compare``, run ``indent`` on the
    same rod mesh and per-rod approaches and add ``comparison`` (soft over rigid);
    ``convergence`` adds the three-mesh table (``mesh_convergence``).
    """
    check_common(mesh, max_approach_over_d0, steps)
    check_positive("length_over_d0", length_over_d0)
    check_positive("diameter", diameter)
    check_positive("youngs_modulus", youngs_modulus)
    if length_over_d0 < 2.0 * REFINED_LENGTH_OVER_D0 + 0.2:
        raise ValueError(f"length_over_d0 must be >= {2 * REFINED_LENGTH_OVER_D0 + 0.2} "
                         f"(the refined zone), got {length_over_d0}")
    check_dhat(dhat_over_d0)
    args = (max_approach_over_d0, steps, length_over_d0, diameter, youngs_modulus,
            dhat_over_d0)
    result = _run_one(mesh, *args)
    result["mesh_convergence"] = mesh_convergence(lambda lvl: _run_one(lvl, *args),
                                                  HEADLINE_KEYS, result, mesh, convergence)
    if compare:
        from .indent import run as rigid_run
        from .soft_squeeze import compare_steps

        rigid = rigid_run(mesh=mesh, max_approach_over_d0=max_approach_over_d0, steps=steps,
                          length_over_d0=length_over_d0, convergence=False,
                          diameter=diameter, youngs_modulus=youngs_modulus)
        cmp = compare_steps(result["steps"], rigid["steps"], HEADLINE_KEYS)
        for row, s, r in zip(cmp["relative_difference_soft_over_rigid"], result["steps"],
                             rigid["steps"], strict=True):
            row["force_ratio_soft_over_rigid"] = s["force"] / r["force"]
            row["hertz_ratio"] = math.sqrt(2.0)
        cmp["rigid_steps"] = rigid["steps"]
        cmp["rigid_wall_time_s"] = rigid["wall_time_s"]
        result["comparison"] = cmp
    return finite(result)


def _run_one(level: str, max_approach_over_d0: float, steps: int, length_over_d0: float,
             diameter: float, youngs_modulus: float, dhat_over_d0: float) -> dict[str, Any]:
    require_felupe()  # FElupe missing: the install hint, before any work
    start = time.perf_counter()
    radius = diameter / 2.0
    mu = youngs_modulus / 3.0
    bulk = BULK_MODULUS * mu / SHEAR_MODULUS
    gap0 = GAP_OVER_DHAT * dhat_over_d0 * diameter
    y_b = diameter + gap0
    section = quarter_disk(radius, SECTION_POINTS[level])
    half_length = 0.5 * length_over_d0 * diameter
    rod_a = extrude(section, axial_nodes(half_length, diameter, AXIAL_FINE_CELLS[level]))
    pa = rod_a.points
    # B = A turned by 180 degrees about the line x = z, y = y_B / 2
    body, (idx_a, idx_b), field, solid = bodies_solid(
        [rod_a, turned_about_x_eq_z(rod_a, y_b)], youngs_modulus)
    pts = body.points
    n_a = rod_a.npoints

    lat = lateral_faces(rod_a, radius)
    near = np.all((pa[lat, 1] > 0.3 * radius) & (pa[lat, 2] < 0.8 * diameter), axis=1)
    faces_a = lat[near]
    faces = np.vstack([faces_a, faces_a + n_a])
    contact = make_barrier(field, faces, diameter, youngs_modulus, dhat_over_d0)

    fixed = np.zeros((body.npoints, 3), dtype=bool)
    fixed[np.isclose(pts[:, 0], 0.0), 0] = True  # symmetry x = 0 (both rods)
    fixed[np.isclose(pts[:, 2], 0.0), 2] = True  # symmetry z = 0 (both rods)
    mid_a = idx_a[np.isclose(pa[:, 1], 0.0)]
    mid_b = idx_b[np.isclose(pts[idx_b, 1], y_b)]
    fixed[mid_a, 1] = True
    fixed[mid_b, 1] = True

    def prescribed(w: float) -> np.ndarray:
        u = np.zeros((body.npoints, 3))
        u[mid_b, 1] = -(gap0 + 2.0 * w)
        return u.ravel()

    problem = BarrierProblem(field, solid, contact, fixed.ravel(), prescribed,
                             force_scale=youngs_modulus * diameter**2, load=-0.5 * gap0)
    area0 = section_area(section.points, section.cells)
    nodes_a = np.unique(faces_a)
    nodes_b = nodes_a + n_a
    on_top = np.isclose(pa[nodes_a, 0], 0.0)  # A's generatrix under B
    on_mid = np.isclose(pa[nodes_a, 2], 0.0)  # A's mid cross-section
    layers = np.unique(pa[nodes_a, 2])
    n_sec = section.npoints
    edges_sec = lateral_faces(section, radius)

    def profile(x: np.ndarray, pressure: np.ndarray) -> list[dict[str, float]]:
        """Along rod A: per node layer z, A/A0, the contact width fraction L_c (the
        loaded arcs of both contacts over the perimeter) and the peak pressure."""
        rows = []
        z_all = pa[nodes_a, 2]
        p_max = float(pressure.max())
        for j, z0 in enumerate(layers):
            sel = np.isclose(z_all, z0)
            xs = x[nodes_a[sel], 0]
            order = np.argsort(xs)
            p_layer = pressure[sel][order]
            # a layer with only the peak's 1 % counts as free (see contact_edge)
            loaded = p_layer > 0.01 * p_max
            b = contact_edge(xs[order], np.where(loaded, p_layer, 0.0)) if loaded.any() else 0.0
            layer = slice(j * n_sec, (j + 1) * n_sec)
            xy = x[idx_a][layer][:, :2]
            perimeter = 4.0 * float(np.linalg.norm(xy[edges_sec[:, 1]] - xy[edges_sec[:, 0]],
                                                   axis=1).sum())
            # both contacts of A's section, B above and its image below (the mid-plane's
            # symmetry), each 2 b wide: the loaded part of the whole perimeter, as physics.md
            # defines L_c and as the rod model counts it
            rows.append({"z_over_d0": float(z0) / diameter,
                         "area_ratio": section_area(xy, section.cells) / area0,
                         "contact_fraction": 4.0 * b / perimeter,
                         "peak_pressure_over_e": float(p_layer.max()) / youngs_modulus})
        return rows

    def measure(w: float) -> dict[str, Any]:
        x = pts + field[0].values
        force_a, pressure = nodal_contact(contact, x, faces, nodes_a)
        force_b, pressure_b = nodal_contact(contact, x, faces, nodes_b)
        f = 4.0 * float(-force_a[:, 1].sum())  # x < 0 and z < 0 quarters of the patch
        f_b = 4.0 * float(force_b[:, 1].sum())
        s_z, p_z = x[nodes_a[on_top], 2], pressure[on_top]
        s_x, p_x = x[nodes_a[on_mid], 0], pressure[on_mid]
        a_z = contact_edge(np.sort(s_z), p_z[np.argsort(s_z)])
        a_x = contact_edge(np.sort(s_x), p_x[np.argsort(s_x)])
        area_a = section_area(x[idx_a[:n_sec], :2], section.cells)
        # B's mid cross-section is its x = 0 layer, the image of A's z = 0 layer
        xb = x[idx_b[:n_sec]]
        area_b = section_area(np.column_stack([xb[:, 2], y_b - xb[:, 1]]), section.cells)
        return {
            "approach_over_d0": 2.0 * w / diameter,
            "w_over_d0": w / diameter,
            "force": f,
            "force_over_e_d0sq": f / (youngs_modulus * diameter**2),
            "force_balance_rel": relative(f_b, f),
            "semi_axis_axial_over_d0": a_z / diameter,
            "semi_axis_transverse_over_d0": a_x / diameter,
            "peak_pressure_over_e": float(pressure.max()) / youngs_modulus,
            "peak_pressure_b_over_e": float(pressure_b.max()) / youngs_modulus,
            "area_ratio_mid": area_a / area0,
            "area_ratio_mid_b": area_b / area0,
            "min_gap_over_d0": contact.minimum_distance_over_scale(),
            "profile_a": profile(x, pressure),
            "newton_iterations": int(problem.iterations[-1]),
        }

    loads = load_schedule(0.5 * max_approach_over_d0 * diameter, steps)
    table = problem.run(loads, measure)
    nu = poisson_ratio(bulk, mu)
    return {
        "scene": "soft_crossing",
        "mesh": {"level": level, "elements": int(body.ncells), "points": int(body.npoints),
                 "dofs": int(body.npoints * 3)},
        "parameters": {
            "diameter_m": diameter, "youngs_modulus_pa": youngs_modulus,
            "shear_modulus_pa": mu, "bulk_modulus_pa": bulk, "poisson_ratio": nu,
            "segment_length_m": 2.0 * half_length, "dhat_over_d0": dhat_over_d0,
            "kappa_pa": contact.stiffness, "initial_gap_m": gap0,
        },
        "steps": table,
        "hertz": _hertz(table, radius, youngs_modulus, nu, diameter),
        "newton_iterations_total": int(sum(problem.iterations)),
        "wall_time_s": time.perf_counter() - start,
    }


def _hertz(table: list[dict], radius: float, youngs_modulus: float, nu: float,
           diameter: float) -> dict[str, Any]:
    """Hertz for two identical elastic crossed cylinders at each step: a sphere of radius
    R on a flat (Johnson 1985 sec. 4.2) with E* = E / (2 (1 - nu^2)) (eq. 4.22, both
    bodies compliant) and total approach 2 w: F = (4/3) E* sqrt(R) (2 w)^(3/2) (eq. 4.23),
    sqrt(2) times the rigid-indenter force at the same w."""
    e_star = 0.5 * hertz.contact_modulus_rigid(youngs_modulus, nu)
    rows = []
    for step in table:
        w = step["w_over_d0"] * diameter
        f_h = hertz.sphere_force(2.0 * w, radius, e_star)
        rows.append({"w_over_d0": step["w_over_d0"], "force": step["force"],
                     "force_hertz": f_h, "force_rel_error": relative(step["force"], f_h),
                     "contact_radius_hertz_over_d0":
                         hertz.sphere_contact_radius(2.0 * w, radius) / diameter})
    return {"formula": "two elastic crossed cylinders: E* = E/(2(1-nu^2)), "
                       "F = (4/3) E* sqrt(R) (2w)^1.5, a = sqrt(2 R w) (Johnson 1985 "
                       "eqs. 4.22-4.23)", "steps": rows}
