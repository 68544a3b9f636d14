"""Scene ``soft_wrap``: a soft rod pulled under tension around a soft rod of the same
material and diameter, with barrier contact between the two deformable bodies.

The soft-soft counterpart of ``wrap`` (a rod pulled around a RIGID cylinder): rod A is the
wrap scene's rod, on the same mesh, with the same dead end loads T (0, sin(theta),
+-cos(theta)), theta = wrap_angle / 2; the rigid cylinder is replaced by rod B.

Geometry (SI). A: straight at rest along e_z, centred at the origin, half section x >= 0
(the wrap scene's graded half disk) times half its length (z >= 0). B: along e_x, its axis
through (0, y_B, 0), y_B = D0 + g0 with the initial gap g0 = ``GAP_OVER_DHAT`` dhat; it is
the ``indent`` rod mesh turned by 180 degrees about the line x = z, y = y_B / 2 (as B of
``soft_crossing``), its quarter section facing A (y <= y_B, z >= 0) times half its length
(x >= 0), free far end. Symmetry planes x = 0 and z = 0 of both rods; B's mid-plane
y = y_B is held (u_y = 0): a stack, B pressed by A from below and by A's mirror image from
above, so that B's axis stays straight as the rigid cylinder's does and only B's section
deforms.

Force control and the start. A is held across its axis by the contact alone. The barrier
has stiffness only inside its activation distance, so the rods start at the gap
g0 = 0.5 dhat (``GAP_OVER_DHAT``): A's translation toward B is then stiff from the first
Newton step (the unloaded start carries a small barrier force that the first tension
level takes over; only converged tension levels are reported).

Outputs per tension level, on A (the wrap scene's keys, the same definitions: mid line
load per length of the nominal axis, its curvature, approaches, mid-section A/A0, peak
pressure) and on B (mid-section A/A0, peak pressure); ``profile_a`` and ``profile_b``
(per node layer along each rod: A/A0, the contact width fraction L_c, p_max/E), the
contact patch maps ``patch_a``, ``patch_b`` (rest axial position, angle around the
section from the contact centre, p/E of every loaded node), and the force-displacement
pair (T, the end face centroid's displacement along the load). With ``compare``, the
rigid ``wrap`` on the same rod-A mesh and tensions, and soft/rigid ratios.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

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
from ..measure import volume_ratio
from ..mesh import _HEX_FACES, extrude, lateral_faces, lumped_face_weights, quarter_disk
from . import indent, wrap
from ._common import check_dhat, finite, load_schedule, mesh_convergence
from ._pair import (
    bodies_solid,
    contact_edge,
    make_barrier,
    nodal_contact,
    turned_about_x_eq_z,
)
from ._sections import RodSections, contact_half_length

GAP_OVER_DHAT: float = 0.5
"""Initial gap between the rods [dhat]: inside the barrier's activation distance, so that
A, held across its axis by the contact alone, is not free at the start (module docstring)."""

B_REFINED_OVER_D0: float = 0.6
"""Uniformly refined length of B along its axis [D0]: A's contact spans its flattened
width, a half-width up to about 0.4 D0 in the rigid wrap."""

DEFAULT_STEPS: int = wrap.DEFAULT_STEPS
"""Default number of tension levels (the wrap scene's)."""

HEADLINE_KEYS = ("force_per_length_mid_nominal_over_e_d0", "kappa_d0_mid_nominal",
                 "approach_nominal_over_d0", "area_ratio_mid", "area_ratio_mid_b",
                 "peak_pressure_over_e", "contact_half_width_mid_over_d0")
"""Outputs compared across meshes (at the largest tension)."""

RIGID_KEYS = ("force_per_length_mid_nominal_over_e_d0", "kappa_d0_mid_nominal",
              "approach_nominal_over_d0", "area_ratio_mid", "peak_pressure_over_e",
              "contact_half_width_mid_over_d0", "contact_half_length_over_d0",
              "force_per_length_mid_over_e_d0", "kappa_d0_mid")
"""Outputs of rod A compared with the rigid wrap's (soft over rigid)."""


def run(mesh: str = "coarse", max_tension_over_e_d0sq: float = 0.25,
        steps: int = DEFAULT_STEPS, wrap_angle_deg: float = 90.0, length_over_d0: float = 4.5,
        compare: bool = True, convergence: bool = False, dhat_over_d0: float = DHAT_OVER_D0,
        diameter: float = ROD_DIAMETER, youngs_modulus: float = YOUNGS_MODULUS
        ) -> dict[str, Any]:
    """Pull rod A around rod B with end tensions up to ``max_tension_over_e_d0sq`` E D0^2
    [N] in ``steps`` levels (quadratic spacing). ``compare``: also run the rigid ``wrap``
    on the same A mesh and tensions (``comparison``); ``convergence``: the three-mesh
    table; ``dhat_over_d0``: the barrier's activation distance over D0. Bad input:
    ValueError naming the parameter (the wrap scene's ranges)."""
    wrap.check_inputs(mesh, max_tension_over_e_d0sq, steps, wrap_angle_deg, length_over_d0,
                      diameter, youngs_modulus)
    check_dhat(dhat_over_d0)
    kwargs = dict(max_tension_over_e_d0sq=max_tension_over_e_d0sq, steps=steps,
                  wrap_angle_deg=wrap_angle_deg, length_over_d0=length_over_d0,
                  diameter=diameter, youngs_modulus=youngs_modulus, dhat_over_d0=dhat_over_d0)
    result = _run_one(mesh, **kwargs)
    result["mesh_convergence"] = mesh_convergence(lambda lvl: _run_one(lvl, **kwargs),
                                                  HEADLINE_KEYS, result, mesh, convergence)
    if compare:
        rigid = wrap.run(mesh=mesh, max_tension_over_e_d0sq=max_tension_over_e_d0sq,
                         steps=steps, wrap_angle_deg=wrap_angle_deg,
                         length_over_d0=length_over_d0, convergence=False,
                         diameter=diameter, youngs_modulus=youngs_modulus)
        rows = [{"tension_over_e_d0sq": s["tension_over_e_d0sq"],
                 **{f"{k}_soft_over_rigid": s[k] / r[k] if r[k] else None for k in RIGID_KEYS}}
                for s, r in zip(result["steps"], rigid["steps"], strict=True)]
        result["comparison"] = {"ratios": rows, "rigid_steps": rigid["steps"],
                                "rigid_wall_time_s": rigid["wall_time_s"]}
    return finite(result)


def _run_one(level: str, max_tension_over_e_d0sq: float, steps: int, wrap_angle_deg: float,
             length_over_d0: float, diameter: float, youngs_modulus: float,
             dhat_over_d0: float) -> dict[str, Any]:
    require_felupe()  # FElupe missing: the install hint, before any work
    from tightknot.knots.curvature import bergou_curvature

    start = time.perf_counter()
    radius = diameter / 2.0
    mu = youngs_modulus / 3.0
    bulk = BULK_MODULUS * mu / SHEAR_MODULUS
    theta = 0.5 * math.radians(wrap_angle_deg)
    gap0 = GAP_OVER_DHAT * dhat_over_d0 * diameter
    y_b = diameter + gap0

    # rod A: the wrap scene's mesh
    sec_a = wrap.half_disk(radius, wrap.SECTION_POINTS[level])
    ns = sec_a.npoints
    quads = np.asarray(sec_a.cells)
    half_length = 0.5 * length_over_d0 * diameter
    refined = (theta + 0.3) * diameter
    z = wrap.axial_nodes(half_length, refined, wrap.AXIAL_FINE_CELLS[level],
                         wrap.AXIAL_COARSE_CELLS[level])
    rod_a = extrude(sec_a, z)
    # rod B: indent's section, refined over B_REFINED_OVER_D0 along its axis
    sec_b = quarter_disk(radius, indent.SECTION_POINTS[level])
    x_b = wrap.axial_nodes(1.5 * diameter, B_REFINED_OVER_D0 * diameter,
                           wrap.AXIAL_FINE_CELLS[level], indent.AXIAL_COARSE_CELLS)
    local_b = extrude(sec_b, x_b)
    pb = local_b.points
    rod_b = turned_about_x_eq_z(local_b, y_b)  # along e_x, facing A
    body, (idx_a, idx_b), field, solid = bodies_solid([rod_a, rod_b], youngs_modulus)
    pts = body.points
    pa = rod_a.points

    lat_a = lateral_faces(rod_a, radius)
    near_a = np.all((pa[lat_a, 1] > 0.0) & (pa[lat_a, 2] < refined + 0.2 * diameter), axis=1)
    lat_b = lateral_faces(local_b, radius)
    near_b = np.all((pb[lat_b, 1] > 0.3 * radius) & (pb[lat_b, 2] < 1.0 * diameter), axis=1)
    faces_a, faces_b = lat_a[near_a], lat_b[near_b] + rod_a.npoints
    faces = np.vstack([faces_a, faces_b])
    contact = make_barrier(field, faces, diameter, youngs_modulus, dhat_over_d0)

    fixed = np.zeros((body.npoints, 3), dtype=bool)
    fixed[np.isclose(pts[:, 0], 0.0), 0] = True  # symmetry x = 0 (both rods)
    fixed[np.isclose(pts[:, 2], 0.0), 2] = True  # symmetry z = 0 (both rods)
    fixed[idx_b[np.isclose(pts[idx_b, 1], y_b)], 1] = True  # B's mid-plane (the stack)

    # A's end face z = L/2: the modelled half face carries T/2 as a uniform traction
    cell_faces = np.asarray(rod_a.cells)[:, _HEX_FACES].reshape(-1, 4)
    end_faces = cell_faces[np.all(np.isclose(pa[cell_faces, 2], half_length), axis=1)]
    end_share = lumped_face_weights(pa, end_faces)
    end_nodes = np.nonzero(end_share > 0.0)[0]
    end_share = end_share / end_share.sum()
    direction = np.array([0.0, math.sin(theta), math.cos(theta)])

    def external(tension: float) -> np.ndarray:
        f = np.zeros((body.npoints, 3))
        f[idx_a] = np.outer(0.5 * tension * end_share, direction)
        return f.ravel()

    problem = BarrierProblem(field, solid, contact, fixed.ravel(),
                             lambda t: np.zeros(body.npoints * 3),
                             force_scale=youngs_modulus * diameter**2, external=external)

    lay_a = RodSections.from_section(sec_a, radius, np.array([0.0, radius]), z, 0)
    lay_b = RodSections.from_section(sec_b, radius, np.array([0.0, radius]), x_b,
                                     rod_a.npoints)
    n_fine = wrap.AXIAL_FINE_CELLS[level] + 1
    top_a = np.unique(faces_a)
    layer_of = np.rint(np.searchsorted(z, pa[top_a, 2] - 1e-12 * diameter)).astype(int)
    on_mid = np.isclose(pa[top_a, 2], 0.0)
    i_bottom = int(np.argmin(np.hypot(sec_a.points[:, 0], sec_a.points[:, 1] + radius)))

    def measure(tension: float) -> dict[str, Any]:
        x = pts + field[0].values
        force, pressure_top = nodal_contact(contact, x, faces, top_a)
        nodes_all = np.unique(faces)
        _, p_all = nodal_contact(contact, x, faces, nodes_all)
        pressure = np.zeros(body.npoints)
        pressure[nodes_all] = p_all
        total = 4.0 * float(-force[:, 1].sum())  # the force on A is -y (toward B is +y)
        xa = x[idx_a]
        cent = wrap._layer_centroids(xa, quads, ns, n_fine)
        stretch = float(np.linalg.norm(cent[1] - cent[0]) / (z[1] - z[0]))
        r_stretched = radius * stretch**-0.5
        d = abs(y_b - cent[0, 1])
        # line load per layer: |nodal force| (x2 for x < 0) over the tributary length
        load = np.zeros(n_fine)
        inside = layer_of < n_fine
        np.add.at(load, layer_of[inside], 2.0 * np.linalg.norm(force[inside], axis=1))
        seg = np.linalg.norm(np.diff(cent, axis=0), axis=1)
        trib = np.concatenate([[0.5 * seg[0]], 0.5 * (seg[:-1] + seg[1:])])
        line = load[:-1] / trib
        layers = np.arange(n_fine) * ns
        bottom = xa[layers + i_bottom]
        nominal = wrap.nominal_axis(bottom[:-1, 1:], np.full(n_fine - 1, r_stretched))
        seg_n = np.linalg.norm(np.diff(nominal, axis=0), axis=1)
        trib_n = np.concatenate([[0.5 * seg_n[0]], 0.5 * (seg_n[:-1] + seg_n[1:])])
        line_n = load[:-2] / trib_n
        kappa = _mid_curvature(bergou_curvature, cent)
        kappa_n = _mid_curvature(bergou_curvature,
                                 np.column_stack([np.zeros(len(nominal)), nominal]))
        s_x = x[top_a[on_mid], 0]
        order = np.argsort(s_x)
        b_mid = contact_edge(s_x[order], pressure_top[on_mid][order])
        prof_a = lay_a.profile(x, pressure, youngs_modulus, diameter)
        prof_b = lay_b.profile(x, pressure, youngs_modulus, diameter)
        end_disp = float((field[0].values[idx_a][end_nodes] @ direction).mean())
        f_mid = float(line[0])
        return {
            "tension": tension,
            "tension_over_e_d0sq": tension / (youngs_modulus * diameter**2),
            "end_displacement_over_d0": end_disp / diameter,
            "approach_over_d0": (diameter - d) / diameter,
            "approach_nominal_over_d0": (diameter - (y_b - nominal[0, 0])) / diameter,
            "axial_stretch_mid": stretch,
            "area_ratio_mid": prof_a[0]["area_ratio"],  # layer 0: the mid section
            "area_ratio_mid_b": prof_b[0]["area_ratio"],
            "contact_force_total": total,
            "contact_force_total_over_2t_sin_theta": total / (2.0 * tension
                                                              * math.sin(theta)),
            "force_per_length_mid": f_mid,
            "force_per_length_mid_over_e_d0": f_mid / (youngs_modulus * diameter),
            "force_per_length_mid_nominal": float(line_n[0]),
            "force_per_length_mid_nominal_over_e_d0": float(line_n[0])
            / (youngs_modulus * diameter),
            "kappa_d0_mid": kappa * diameter,
            "kappa_d0_mid_nominal": kappa_n * diameter,
            "membrane_line_load_over_e_d0": tension / (youngs_modulus * diameter**2)
            * kappa_n * diameter,
            "peak_pressure_over_e": float(pressure[idx_a].max()) / youngs_modulus,
            "peak_pressure_b_over_e": float(pressure[idx_b].max()) / youngs_modulus,
            "contact_half_width_mid_over_d0": b_mid / diameter,
            "contact_half_length_over_d0": contact_half_length(prof_a),
            "contact_fraction_max": max(r["contact_fraction"] for r in prof_a),
            "contact_fraction_max_b": max(r["contact_fraction"] for r in prof_b),
            "min_gap_over_d0": contact.minimum_distance_over_scale(),
            "volume_ratio": volume_ratio(solid),
            "profile_a": prof_a,
            "profile_b": prof_b,
            "patch_a": lay_a.patch(pressure, youngs_modulus, diameter),
            "patch_b": lay_b.patch(pressure, youngs_modulus, diameter),
            "line_load_profile_nominal_over_e_d0": (line_n / (youngs_modulus * diameter)
                                                    ).tolist(),
            "newton_iterations": int(problem.iterations[-1]),
        }

    tensions = load_schedule(max_tension_over_e_d0sq * youngs_modulus * diameter**2, steps)
    table = problem.run(tensions, measure)
    nu = poisson_ratio(bulk, mu)
    return {
        "scene": "soft_wrap",
        "mesh": {"level": level, "elements": int(body.ncells), "points": int(body.npoints),
                 "dofs": int(body.npoints * 3), "elements_a": int(rod_a.ncells),
                 "elements_b": int(rod_b.ncells)},
        "parameters": {
            "diameter_m": diameter, "youngs_modulus_pa": youngs_modulus,
            "shear_modulus_pa": mu, "bulk_modulus_pa": bulk, "poisson_ratio": nu,
            "wrap_angle_deg": wrap_angle_deg, "segment_length_m": 2.0 * half_length,
            "rod_b_length_m": 3.0 * diameter, "dhat_over_d0": dhat_over_d0,
            "kappa_pa": contact.stiffness, "initial_gap_m": gap0,
            "end_load": "dead force T (0, sin(theta), +-cos(theta)) per end of A, uniform "
                        "traction; B's mid-plane held (a stack)",
        },
        "steps": table,
        "newton_iterations_total": int(sum(problem.iterations)),
        "wall_time_s": time.perf_counter() - start,
    }


def _mid_curvature(bergou: Any, axis_yz_points: np.ndarray) -> float:
    """Curvature [1/m] at the first of ``axis_yz_points`` (x, y, z; the middle z = 0),
    from the 7-point stencil with its mirror image about z = 0 (as in ``wrap``)."""
    pts = np.asarray(axis_yz_points)[:4]
    mirror = pts[1:4] * np.array([1.0, 1.0, -1.0])
    return float(bergou(np.vstack([mirror[::-1], pts]), closed=False)[3])
