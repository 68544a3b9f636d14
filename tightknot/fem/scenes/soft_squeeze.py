"""Scene ``soft_squeeze``: two soft parallel rods pressed together (plane strain), with
barrier contact between the two deformable sections.

The check of the barrier route against the rigid-plane ``squeeze``: for two identical
rods the plane between them is a symmetry plane, so the result must equal the squeeze of
one rod against a rigid frictionless plate at the same per-side approach w.

Geometry (SI): rod A centred at the origin, rod B at (0, D0 + g0), g0 = dhat the initial
gap; both sections meshed as quarter disks (x >= 0: symmetry x = 0), A's upper quarter and
B's lower quarter (their mid-planes y = 0 and y = y_B: a rod squeezed from both sides,
as in ``squeeze``). A's mid-plane is held (u_y = 0), B's moves down by g0 + 2 w, so the
distance between the two section centroids is D0 - 2 w: w is the per-side approach of
:mod:`tightknot.fem.overlap` exactly.
"""

from __future__ import annotations

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
    nearly_incompressible_solid,
)
from ..measure import section_area
from ..mesh import lateral_faces, quarter_disk
from ._common import (
    check_common,
    check_dhat,
    check_positive,
    finite,
    load_schedule,
    mesh_convergence,
    relative,
)
from ._pair import GAP_OVER_DHAT, contact_edge, make_barrier, nodal_contact, stack
from .squeeze import SECTION_POINTS_2D

HEADLINE_KEYS = ("force_per_length_over_e_d0", "half_width_over_d0", "peak_pressure_over_e",
                 "contact_fraction_side", "area_ratio")
"""Outputs compared with the rigid-plane squeeze and across meshes."""


def run(mesh: str = "coarse", max_approach_over_d0: float = 0.3, steps: int = 4,
        compare: bool = True, convergence: bool = False, dhat_over_d0: float = DHAT_OVER_D0,
        diameter: float = ROD_DIAMETER, youngs_modulus: float = YOUNGS_MODULUS
        ) -> dict[str, Any]:
    """Press two soft rods together up to a total approach ``max_approach_over_d0`` D0
    (w per side is half of it); with ``compare``, run the rigid-plane plane-strain
    ``squeeze`` on the same section mesh and load levels and add ``comparison``;
    ``dhat_over_d0`` is the barrier's activation distance over D0 (for a dhat study);
    ``convergence`` adds the three-mesh table (``mesh_convergence``).
    """
    check_common(mesh, max_approach_over_d0, steps)
    check_positive("diameter", diameter)
    check_positive("youngs_modulus", youngs_modulus)
    check_dhat(dhat_over_d0)
    args = (max_approach_over_d0, steps, diameter, youngs_modulus, dhat_over_d0)
    result = _run_one(mesh, *args)
    result["mesh_convergence"] = mesh_convergence(lambda lvl: _run_one(lvl, *args),
                                                  HEADLINE_KEYS, result, mesh, convergence)
    if compare:
        from .squeeze import run as rigid_run

        rigid = rigid_run(mesh=mesh, max_approach_over_d0=max_approach_over_d0, steps=steps,
                          model="plane_strain", convergence=False, diameter=diameter,
                          youngs_modulus=youngs_modulus)
        result["comparison"] = compare_steps(result["steps"], rigid["steps"], HEADLINE_KEYS)
        result["comparison"]["rigid_wall_time_s"] = rigid["wall_time_s"]
    return finite(result)


def compare_steps(soft: list[dict], rigid: list[dict], keys: tuple[str, ...]
                  ) -> dict[str, Any]:
    """Relative differences soft/rigid - 1 of ``keys`` at each common load step."""
    rows = []
    for s, r in zip(soft, rigid, strict=True):
        rows.append({"w_over_d0": s["w_over_d0"],
                     **{k: relative(s[k], r[k]) for k in keys}})
    worst = {k: max(abs(row[k]) for row in rows) for k in keys}
    return {"relative_difference_soft_over_rigid": rows, "worst": worst}


def _run_one(level: str, max_approach_over_d0: float, steps: int, diameter: float,
             youngs_modulus: float, dhat_over_d0: float) -> dict[str, Any]:
    fem = require_felupe()
    start = time.perf_counter()
    radius = diameter / 2.0
    mu = youngs_modulus / 3.0
    bulk = BULK_MODULUS * mu / SHEAR_MODULUS
    gap0 = GAP_OVER_DHAT * dhat_over_d0 * diameter
    y_b = diameter + gap0
    sec_a = quarter_disk(radius, SECTION_POINTS_2D[level])
    faces_a = lateral_faces(sec_a, radius)
    # B: A mirrored about the line y = y_B / 2 (cells reordered to keep them positive)
    sec_b = fem.Mesh(points=np.column_stack([sec_a.points[:, 0], y_b - sec_a.points[:, 1]]),
                     cells=sec_a.cells[:, ::-1], cell_type="quad")
    body, (idx_a, idx_b) = stack([sec_a, sec_b])
    region = fem.RegionQuad(body)
    field = fem.FieldContainer([fem.FieldPlaneStrain(region, dim=2)])
    solid = nearly_incompressible_solid(field, mu=mu, bulk=bulk)
    pts = body.points
    # only the halves facing each other can touch
    top_a = faces_a[np.all(sec_a.points[faces_a, 1] > 0.5 * radius, axis=1)]
    faces = np.vstack([top_a, top_a + sec_a.npoints])
    contact = make_barrier(field, faces, diameter, youngs_modulus, dhat_over_d0)

    fixed = np.zeros((body.npoints, 2), dtype=bool)
    fixed[np.isclose(pts[:, 0], 0.0), 0] = True  # symmetry x = 0
    mid_a = idx_a[np.isclose(pts[idx_a, 1], 0.0)]
    mid_b = idx_b[np.isclose(pts[idx_b, 1], y_b)]
    fixed[mid_a, 1] = True
    fixed[mid_b, 1] = True

    def prescribed(w: float) -> np.ndarray:
        u = np.zeros((body.npoints, 2))
        u[mid_b, 1] = -(gap0 + 2.0 * w)
        return u.ravel()

    problem = BarrierProblem(field, solid, contact, fixed.ravel(), prescribed,
                             force_scale=youngs_modulus * diameter, load=-0.5 * gap0)
    area0 = section_area(sec_a.points, sec_a.cells)
    nodes_a = np.unique(top_a)
    edges_a = lateral_faces(sec_a, radius)

    def measure(w: float) -> dict[str, Any]:
        x = pts + field[0].values
        force, pressure = nodal_contact(contact, x, faces, nodes_a)
        f_side = 2.0 * float(-force[:, 1].sum())  # the x < 0 half: x2
        f_b = 2.0 * float(contact.nodal_forces()[np.unique(top_a + sec_a.npoints), 1].sum())
        order = np.argsort(x[nodes_a, 0])
        s, p = x[nodes_a, 0][order], pressure[order]
        b = contact_edge(s, p)
        xa = x[idx_a]
        perimeter = 4.0 * float(np.linalg.norm(xa[edges_a[:, 1]] - xa[edges_a[:, 0]],
                                               axis=1).sum())
        return {
            "approach_over_d0": 2.0 * w / diameter,
            "w_over_d0": w / diameter,
            "force_per_length": f_side,
            "force_per_length_over_e_d0": f_side / (youngs_modulus * diameter),
            "force_balance_rel": relative(f_b, f_side),
            "half_width_over_d0": b / diameter,
            "contact_fraction_side": 2.0 * b / perimeter,
            "peak_pressure_over_e": float(pressure.max()) / youngs_modulus,
            "area_ratio": section_area(xa, sec_a.cells) / area0,
            "min_gap_over_d0": contact.minimum_distance_over_scale(),
            "newton_iterations": int(problem.iterations[-1]),
        }

    loads = load_schedule(0.5 * max_approach_over_d0 * diameter, steps)
    table = problem.run(loads, measure)
    return {
        "scene": "soft_squeeze",
        "model": "plane_strain",
        "mesh": {"level": level, "elements": int(body.ncells), "points": int(body.npoints),
                 "dofs": int(body.npoints * 2)},
        "parameters": {
            "diameter_m": diameter, "youngs_modulus_pa": youngs_modulus,
            "shear_modulus_pa": mu, "bulk_modulus_pa": bulk,
            "dhat_over_d0": dhat_over_d0, "kappa_pa": contact.stiffness,
            "initial_gap_m": gap0,
        },
        "steps": table,
        "newton_iterations_total": int(sum(problem.iterations)),
        "wall_time_s": time.perf_counter() - start,
    }
