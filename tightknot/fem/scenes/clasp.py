"""Scene ``clasp``: two U-shaped soft rods hooked through each other and pulled apart by
their clamped ends, with barrier contact between the two deformable bodies.

The orthogonal clasp of Grandgeorge, Baek, Singh, Johanns, Sano, Flynn, Maddocks & Reis
(PNAS 118 (2021) e2021684118): each rod's centerline lies in one of two orthogonal planes,
the two bends hook and press on each other's inner side, and both ends of each rod are
clamped; the clamps of the two rods are pulled apart. Frictionless here. The sizes (bend
radius, leg length) are this scene's parameters, not the paper's specimens.

Geometry (SI). The rods are straight at rest (as the rod model's are, and as the paper's
filaments were before they were bent): each is a straight reference mesh, a half disk
section times half the rod's length (arc length s from the bend's apex, s = 0, to a
clamp), mapped at the start onto a U: a half circle of centreline radius rho (the
``bend_radius_over_d0``) and two straight legs of length ``leg_length_over_d0`` along the
pull axis e_x. Rod A lies in the plane z = 0, its apex at x_a = (D0 + g0) / 2 with its legs
toward -x; rod B is A turned by 180 degrees about the line x = 0, y = z (the proper
rotation (x, y, z) -> (-x, z, y)): it lies in the plane y = 0, its apex at -x_a, legs
toward +x. The two apexes face each other with a gap g0 between their inner sides:
dhat plus the sag of the faceted concave inner sides (so that the meshed surfaces start
apart, as the barrier needs). Symmetry planes y = 0 and z = 0 of the whole clasp: each
rod is modelled by a half section (its own plane cuts it) times one leg (the other plane
cuts its apex), a quarter of the clasp.

The start map bends each rod onto the U as an incompressible block bends (volume kept,
the section's fibres shifted toward the bend's centre); the first solve, before any
pull, relaxes
both rods in their clamps (their bends open or close as the elastica with clamped legs
wants), and the clamps then move apart along x by Delta / 2 each (displacement control,
``max_pull_over_d0`` = the largest Delta over D0). A clamp holds its end face in place:
all three displacement components of its nodes.

Outputs of the relaxation (``relaxed``, :func:`_relaxed_u`): how far the apex moved out
along the pull axis as the U settled in its clamps, the apex's axial force, the stretch and
curvature of its mid fibre, and where its inner and outer sides lie. Outputs per pull level:
the pull force F (the x reaction of A's clamps, whole clasp) against Delta, its balance with
the contact force, the apexes' approach (their section centroids' distance below D0) and the
nominal approach (far fibres moved in by the stretched radius), the apex curvature, the apex
sections' A/A0, peak pressures, the largest contact width fraction; ``profile_a`` and
``profile_b`` along each rod (per node layer: A/A0, L_c, p_max/E), the contact patch maps
``patch_a`` and ``patch_b`` (rest arc length, angle around the section from the inner side,
p/E of each loaded node).
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
from ..mesh import extrude, lateral_faces
from . import wrap
from ._common import (
    MESH_LEVELS,
    check_dhat,
    check_positive,
    finite,
    mesh_convergence,
    relative,
)
from ._pair import GAP_OVER_DHAT, bodies_solid, make_barrier, nodal_contact
from ._sections import RodSections, contact_half_length

CONTACT_ARC_OVER_D0: float = 1.6
"""Arc length from the apex [D0] whose lateral faces can touch the partner: a rod wrapped
around its partner's tube (radius D0 for the two centrelines) over up to 90 degrees stays
in contact over pi/2 D0 ~ 1.6 D0 of its arc."""

AXIAL_CELLS_PER_D0: dict[str, float] = {"coarse": 5.0, "medium": 7.5, "fine": 10.0}
"""Hexahedra per D0 of arc length, uniform from the apex to the clamp (cells of 0.2, 0.13
and 0.1 D0). Uniform because the whole U bends as it settles in its clamps, and trilinear
hexahedra lock in bending the more the longer they are: cells that grow along the rod
stiffen its outer bend and legs against its apex and change the settled shape (cells
growing to 3 D0 moved the apex 4.3 times as far as uniform cells, cells of twice the
apex's 1.3 times; docs/fem_nip.md, "The bend's mesh")."""

DEFAULT_STEPS: int = 6
"""Default number of pull levels."""

HEADLINE_KEYS = ("force_over_e_d0sq", "approach_over_d0", "area_ratio_apex",
                 "peak_pressure_over_e", "contact_fraction_max", "kappa_d0_apex")
"""Outputs compared across meshes (at the largest pull)."""


def check_inputs(mesh: str, max_pull_over_d0: float, steps: int, bend_radius_over_d0: float,
                 leg_length_over_d0: float, diameter: float, youngs_modulus: float) -> None:
    """Raise ValueError naming the parameter and its range for bad input of :func:`run`."""
    if mesh not in MESH_LEVELS:
        raise ValueError(f"mesh must be one of {MESH_LEVELS}, got {mesh!r}")
    if not (isinstance(max_pull_over_d0, (int, float)) and math.isfinite(max_pull_over_d0)
            and 0.0 < max_pull_over_d0 <= 2.0):
        # beyond 2 D0 of clamp travel the legs of these U's (a few D0 long) are stretched
        # by tens of percent: outside the strains the rod model is compared at
        raise ValueError("max_pull_over_d0 must lie in (0, 2] (the clamps' separation "
                         f"change over D0), got {max_pull_over_d0!r}")
    if not isinstance(steps, int) or isinstance(steps, bool) or steps < 1:
        raise ValueError(f"steps must be an integer >= 1, got {steps!r}")
    if not (isinstance(bend_radius_over_d0, (int, float))
            and math.isfinite(bend_radius_over_d0) and 1.25 <= bend_radius_over_d0 <= 4.0):
        # below 1.25 D0 the start map compresses the inner fibre beyond 0.6 of its length
        raise ValueError("bend_radius_over_d0 must lie in [1.25, 4] (the U's centreline "
                         f"radius over D0), got {bend_radius_over_d0!r}")
    if not (isinstance(leg_length_over_d0, (int, float))
            and math.isfinite(leg_length_over_d0) and 1.0 <= leg_length_over_d0 <= 10.0):
        raise ValueError("leg_length_over_d0 must lie in [1, 10] (each leg's straight "
                         f"length over D0), got {leg_length_over_d0!r}")
    check_positive("diameter", diameter)
    check_positive("youngs_modulus", youngs_modulus)


def run(mesh: str = "coarse", max_pull_over_d0: float = 1.0, steps: int = DEFAULT_STEPS,
        bend_radius_over_d0: float = 1.5, leg_length_over_d0: float = 1.5,
        convergence: bool = False, dhat_over_d0: float = DHAT_OVER_D0,
        diameter: float = ROD_DIAMETER, youngs_modulus: float = YOUNGS_MODULUS
        ) -> dict[str, Any]:
    """Pull the clasp's clamps apart by up to ``max_pull_over_d0`` D0 in ``steps`` evenly
    spaced levels (the force is zero until the bends touch, a few tenths of D0 into the
    pull, so the other scenes' quadratic spacing would spend its small first levels on
    nothing); ``convergence`` adds the three-mesh table. Bad input: ValueError naming the
    parameter and its range."""
    check_inputs(mesh, max_pull_over_d0, steps, bend_radius_over_d0, leg_length_over_d0,
                 diameter, youngs_modulus)
    check_dhat(dhat_over_d0)
    kwargs = dict(max_pull_over_d0=max_pull_over_d0, steps=steps,
                  bend_radius_over_d0=bend_radius_over_d0,
                  leg_length_over_d0=leg_length_over_d0, diameter=diameter,
                  youngs_modulus=youngs_modulus, dhat_over_d0=dhat_over_d0)
    result = _run_one(mesh, **kwargs)
    result["mesh_convergence"] = mesh_convergence(lambda lvl: _run_one(lvl, **kwargs),
                                                  HEADLINE_KEYS, result, mesh, convergence)
    return finite(result)


def u_centreline(s: np.ndarray, rho: float, x_c: float) -> tuple[np.ndarray, np.ndarray]:
    """Points [m] and inward unit normals of rod A's U at arc lengths ``s`` [m] from the
    apex: a quarter circle of radius ``rho`` about (x_c, 0, 0) in the plane z = 0 from the
    apex (x_c + rho, 0, 0), then the leg along -x at y = rho."""
    s = np.asarray(s, dtype=float)
    s_arc = 0.5 * math.pi * rho
    phi = np.minimum(s, s_arc) / rho
    on_arc = s <= s_arc
    c = np.where(on_arc[:, None],
                 np.column_stack([x_c + rho * np.cos(phi), rho * np.sin(phi), 0.0 * s]),
                 np.column_stack([x_c - (s - s_arc), np.full_like(s, rho), 0.0 * s]))
    n_in = np.where(on_arc[:, None], -np.column_stack([np.cos(phi), np.sin(phi), 0.0 * s]),
                    np.tile([0.0, -1.0, 0.0], (len(s), 1)))
    return c, n_in


def axial_nodes(length: float, cell: float) -> np.ndarray:
    """Rest arc lengths [m] of the node layers from the apex (0) to a clamp (``length``
    [m]): uniform cells of at most ``cell`` [m]."""
    return np.linspace(0.0, length, max(1, math.ceil(length / cell - 1e-9)) + 1)


def inner_fibre_offset(rho: float, radius: float) -> float:
    """How far [m] the start map puts the inner fibre (b = ``radius``) from the centreline
    of a U of bend radius ``rho`` [m]: b' = rho (1 - sqrt(1 - 2 R / rho)) (Rivlin's bending
    of an incompressible block, as in :func:`_run_one`), more than R: the scene starts the
    two bends with these fibres a small gap apart, so its centrelines start 2 b' apart
    (1.27 D0 at rho = 1.5 D0), and its clamps where that puts them."""
    return rho * (1.0 - math.sqrt(1.0 - 2.0 * radius / rho))


def start_apex_x(rho: float, radius: float, gap: float) -> float:
    """x [m] of rod A's apex on the start U's centreline with the inner fibres a ``gap``
    [m] apart (:func:`inner_fibre_offset`); its clamps lie at this less rho and the leg.
    The rod model's clasp places its U's by the same number, so both clamp alike."""
    return inner_fibre_offset(rho, radius) + 0.5 * gap


def _relaxed_u(x_all: np.ndarray, idx_a: np.ndarray, ref: np.ndarray, s_nodes: np.ndarray,
               radius: float, clamp_reaction: np.ndarray, rho: float, leg: float,
               youngs_modulus: float, centroid: Any) -> dict[str, float]:
    """Rod A's U relaxed in its clamps, before the pull, from the current positions
    ``x_all`` [m] and the reactions [N] on A's clamp nodes (half section):

    - ``apex_shift_over_d0``: how far the apex's mid fibre (the reference section's centre,
      what the rod model's centreline is) moved out along the pull axis, from the clamp
      face's centre, less rho + leg; ``apex_centroid_shift_over_d0`` the same for the apex
      section's area centroid;
    - ``apex_axial_force_over_ea``: the axial force at the apex section over E A0, positive
      in tension, by statics of the quarter model without contact: the clamp's reaction
      along y (the apex's tangent), whole section;
    - ``apex_mid_fibre_stretch``: the mid fibre's stretch over the first cell;
      ``apex_kappa_d0``: its curvature (three layers and their mirror images);
    - ``inner_offset_over_r``, ``outer_offset_over_r``: the apex's inner (toward the bend's
      centre) and outer surface points from its mid fibre along x, over R (1 for a round
      section that keeps its size)."""
    from tightknot.knots.curvature import bergou_curvature

    xa = x_all[idx_a]
    node = _node_lookup(xa, ref, s_nodes, radius)
    last = len(s_nodes) - 1
    mid = np.array([node(0.0, 0.0, j) for j in range(3)]) * np.array([1.0, 1.0, 0.0])
    mirror = mid[1:][::-1] * np.array([1.0, -1.0, 1.0])
    kappa = float(bergou_curvature(np.vstack([mirror, mid]), closed=False)[2])
    d0 = 2.0 * radius
    clamp_x = node(0.0, 0.0, last)[0]
    return {
        "apex_shift_over_d0": float(mid[0, 0] - clamp_x - (rho + leg)) / d0,
        "apex_centroid_shift_over_d0": float(centroid(xa, 0)[0] - centroid(xa, last)[0]
                                             - (rho + leg)) / d0,
        "apex_axial_force_over_ea": float(2.0 * clamp_reaction[:, 1].sum())
        / (youngs_modulus * math.pi * radius**2),
        "apex_mid_fibre_stretch": float(np.linalg.norm(mid[1] - mid[0]) / s_nodes[1]),
        "apex_kappa_d0": kappa * d0,
        **_apex_offsets(node, radius),
    }


def _node_lookup(xa: np.ndarray, ref: np.ndarray, s_nodes: np.ndarray, radius: float) -> Any:
    """The current position of rod A's node at reference section point (a, b) of node layer
    j, from A's positions ``xa`` [m] and reference points ``ref`` [m]."""

    def node(a: float, b: float, j: int) -> np.ndarray:
        hit = np.flatnonzero(np.isclose(ref[:, 0], a, atol=1e-9 * radius)
                             & np.isclose(ref[:, 1], b, atol=1e-9 * radius)
                             & np.isclose(ref[:, 2], s_nodes[j], atol=1e-9 * radius))
        return xa[hit[0]]

    return node


def _apex_offsets(node: Any, radius: float) -> dict[str, float]:
    """The apex section's inner (toward the bend's centre) and outer surface points from its
    mid fibre along x, over R: 1 each for a round section that keeps its size and place; the
    anticlastic shift makes the inner one larger and the outer one smaller."""
    mid = node(0.0, 0.0, 0)[0]
    return {"inner_offset_over_r": float(mid - node(0.0, radius, 0)[0]) / radius,
            "outer_offset_over_r": float(node(0.0, -radius, 0)[0] - mid) / radius}


def rotate_to_b(x: np.ndarray) -> np.ndarray:
    """Rod B's points from rod A's: the proper rotation (x, y, z) -> (-x, z, y), by 180
    degrees about the line x = 0, y = z (also for displacements and forces)."""
    x = np.asarray(x)
    return np.column_stack([-x[:, 0], x[:, 2], x[:, 1]])


def _run_one(level: str, max_pull_over_d0: float, steps: int, bend_radius_over_d0: float,
             leg_length_over_d0: float, diameter: float, youngs_modulus: float,
             dhat_over_d0: float) -> dict[str, Any]:
    fem = require_felupe()
    from tightknot.knots.curvature import bergou_curvature

    start = time.perf_counter()
    radius = diameter / 2.0
    mu = youngs_modulus / 3.0
    bulk = BULK_MODULUS * mu / SHEAR_MODULUS
    rho = bend_radius_over_d0 * diameter
    length = 0.5 * math.pi * rho + leg_length_over_d0 * diameter  # apex to clamp

    # the straight reference: the wrap scene's half disk mirrored to a <= 0 (its point
    # (0, R) the inner side of the bend), so that the start map z = -a keeps the
    # hexahedra positive
    half = wrap.half_disk(radius, wrap.SECTION_POINTS[level])
    section = fem.Mesh(points=np.asarray(half.points) * np.array([-1.0, 1.0]),
                       cells=np.asarray(half.cells)[:, ::-1], cell_type="quad")
    s_nodes = axial_nodes(length, diameter / AXIAL_CELLS_PER_D0[level])
    rod = extrude(section, s_nodes)
    body, (idx_a, idx_b), field, solid = bodies_solid([rod, rod], youngs_modulus)
    ref = np.asarray(rod.points)
    lat = lateral_faces(rod, radius)
    near = np.all((ref[lat, 2] < (CONTACT_ARC_OVER_D0 + 0.4) * diameter)
                  & (ref[lat, 1] > -0.5 * radius), axis=1)
    faces_a = lat[near]
    faces = np.vstack([faces_a, faces_a + rod.npoints])
    contact = make_barrier(field, faces, diameter, youngs_modulus, dhat_over_d0)

    # pure bending of an incompressible rod (plane sections, the centreline unstretched):
    # a fibre at b (toward the bend's centre) goes to b' with db'/db (1 - b'/rho) = 1,
    # b' = rho (1 - sqrt(1 - 2 b / rho)) on the arc (Rivlin's bending of a block,
    # Ogden 1984 sec. 5.2.2), b' = b on the straight legs
    on_arc = ref[:, 2] <= 0.5 * math.pi * rho
    b_bent = np.where(on_arc, rho * (1.0 - np.sqrt(1.0 - 2.0 * ref[:, 1] / rho)), ref[:, 1])

    inner = inner_fibre_offset(rho, radius)

    def u_shape_of(gap: float) -> np.ndarray:
        """Both rods' start positions [m] with the gap ``gap`` [m] between the apexes'
        inner sides."""
        centre, n_in = u_centreline(ref[:, 2], rho, start_apex_x(rho, radius, gap) - rho)
        a = centre + b_bent[:, None] * n_in + (-ref[:, [0]]) * np.array([0.0, 0.0, 1.0])
        return np.vstack([a, rotate_to_b(a)])

    # The inner sides are concave along the rods: their chords sag toward the partner by
    # h = ds_i^2 / (8 r_i) per side (r_i = rho - b'(R) the inner fibre's radius, ds_i =
    # ds r_i / rho its cell length), so two faceted bends a gap dhat apart would cross.
    # Start them apart by dhat plus both sags, and widen that (doubling the extra) until
    # the faceted surfaces are a dhat apart.
    r_inner = rho - inner
    extra = 2.0 * (float(s_nodes[1] - s_nodes[0]) * r_inner / rho) ** 2 / (8.0 * r_inner)
    for _ in range(10):
        gap0 = GAP_OVER_DHAT * dhat_over_d0 * diameter + extra
        u_shape = u_shape_of(gap0)
        u0 = u_shape - body.points
        if contact.minimum_distance_over_scale(u0, within=0.1) >= dhat_over_d0:
            break
        extra *= 2.0
    field[0].values[:] = u0

    tol = 1e-9 * diameter
    fixed = np.zeros((body.npoints, 3), dtype=bool)
    fixed[np.abs(u_shape[:, 1]) < tol, 1] = True  # symmetry y = 0 (both rods)
    fixed[np.abs(u_shape[:, 2]) < tol, 2] = True  # symmetry z = 0 (both rods)
    clamp_a = idx_a[np.isclose(ref[:, 2], length)]
    clamp_b = idx_b[np.isclose(ref[:, 2], length)]
    fixed[clamp_a] = True
    fixed[clamp_b] = True

    def prescribed(pull: float) -> np.ndarray:
        u = u0.copy()
        u[clamp_a, 0] -= 0.5 * pull
        u[clamp_b, 0] += 0.5 * pull
        return u.ravel()

    problem = BarrierProblem(field, solid, contact, fixed.ravel(), prescribed,
                             force_scale=youngs_modulus * diameter**2)
    # The rods settle in their clamps before the pull. The faceted start map leaves volume
    # errors of about a percent per cell (trilinear cells on a curved bend), whose pressure
    # at K = 5000 mu dwarfs the bending stresses and stalls Newton; a continuation in K
    # (10, 100 and 1000 mu, each to the intermediate tolerance) relaxes them first.
    relax = 0
    with problem.failures_as_newton():
        for ratio in (10.0, 100.0, 1000.0):
            solid.bulk = ratio * mu
            relax += problem.correct(problem.intermediate_tol)
        solid.bulk = bulk
        relax += problem.correct()

    lay_a = RodSections.from_section(section, radius, np.array([0.0, radius]), s_nodes, 0)
    lay_b = RodSections.from_section(section, radius, np.array([0.0, radius]), s_nodes,
                                     rod.npoints)
    i_far = int(np.argmin(np.hypot(section.points[:, 0], section.points[:, 1] + radius)))
    quads = np.asarray(section.cells)
    ns = section.npoints
    nodes_all = np.unique(faces)

    def centroid(x: np.ndarray, j: int) -> np.ndarray:
        """Centroid [m] of the modelled half section of layer j (its x and in-plane
        coordinate are the whole section's, by the symmetry of the rod's plane)."""
        c = x[j * ns:(j + 1) * ns][quads]
        area = 0.5 * np.linalg.norm(np.cross(c[:, 2] - c[:, 0], c[:, 3] - c[:, 1]), axis=1)
        return (area[:, None] * c.mean(axis=1)).sum(axis=0) / area.sum()

    relaxed = _relaxed_u(body.points + field[0].values, idx_a, ref, s_nodes, radius,
                         problem.residual().reshape(-1, 3)[clamp_a], rho,
                         leg_length_over_d0 * diameter, youngs_modulus, centroid)

    def measure(pull: float) -> dict[str, Any]:
        x = body.points + field[0].values
        r = problem.residual()
        f_pull = -4.0 * float(r.reshape(-1, 3)[clamp_a, 0].sum())
        force, p_nodes = nodal_contact(contact, x, faces, nodes_all)
        pressure = np.zeros(body.npoints)
        pressure[nodes_all] = p_nodes
        on_a = nodes_all < rod.npoints
        f_contact = 4.0 * float(force[on_a, 0].sum())
        xa, xb = x[idx_a], rotate_to_b(x[idx_b])  # B turned back onto A's frame
        cent_a = np.array([centroid(xa, j) for j in range(4)]) * np.array([1.0, 1.0, 0.0])
        cent_b = np.array([centroid(xb, j) for j in range(4)]) * np.array([1.0, 1.0, 0.0])
        # B turned back: its apex is at +x_a like A's, so the two apexes' distance is
        # the sum of their x (A's at +x, B's own at -x)
        d = float(cent_a[0, 0] + cent_b[0, 0])
        stretch = float(np.linalg.norm(cent_a[1] - cent_a[0]) / (s_nodes[1] - s_nodes[0]))
        r_st = radius * stretch**-0.5
        d_nominal = float(xa[i_far, 0] + xb[i_far, 0]) - 2.0 * r_st
        mirror = cent_a[1:4] * np.array([1.0, -1.0, 1.0])
        kappa = float(bergou_curvature(np.vstack([mirror[::-1], cent_a]), closed=False)[3])
        prof_a = lay_a.profile(x, pressure, youngs_modulus, diameter)
        prof_b = lay_b.profile(x, pressure, youngs_modulus, diameter)
        return {
            "pull_over_d0": pull / diameter,
            "force": f_pull,
            "force_over_e_d0sq": f_pull / (youngs_modulus * diameter**2),
            # before the bends touch both forces are round-off: nothing to balance
            "force_balance_rel": relative(f_contact, f_pull) if pressure.max() > 0 else None,
            "approach_over_d0": (diameter - d) / diameter,
            "approach_nominal_over_d0": (diameter - d_nominal) / diameter,
            "axial_stretch_apex": stretch,
            "kappa_d0_apex": kappa * diameter,
            # the apex's surface from its mid fibre (the relaxed U's measure); the inner
            # side is the contact's, so its offset includes the flattening
            **_apex_offsets(_node_lookup(xa, ref, s_nodes, radius), radius),
            "area_ratio_apex": prof_a[0]["area_ratio"],
            "area_ratio_apex_b": prof_b[0]["area_ratio"],
            "area_ratio_min": min(row["area_ratio"] for row in prof_a),
            "peak_pressure_over_e": float(pressure[idx_a].max()) / youngs_modulus,
            "peak_pressure_b_over_e": float(pressure[idx_b].max()) / youngs_modulus,
            "contact_fraction_max": max(row["contact_fraction"] for row in prof_a),
            "contact_fraction_max_b": max(row["contact_fraction"] for row in prof_b),
            "contact_half_length_over_d0": contact_half_length(prof_a),
            "min_gap_over_d0": contact.minimum_distance_over_scale(),
            "volume_ratio": volume_ratio(solid),
            "profile_a": prof_a,
            "profile_b": prof_b,
            "patch_a": lay_a.patch(pressure, youngs_modulus, diameter),
            "patch_b": lay_b.patch(pressure, youngs_modulus, diameter),
            "newton_iterations": int(problem.iterations[-1]),
        }

    pulls = max_pull_over_d0 * diameter * np.arange(1, steps + 1) / steps
    table = problem.run(pulls, measure)
    return {
        "scene": "clasp",
        "mesh": {"level": level, "elements": int(body.ncells), "points": int(body.npoints),
                 "dofs": int(body.npoints * 3), "section_quads": int(section.ncells),
                 "layers": len(s_nodes)},
        "parameters": {
            "diameter_m": diameter, "youngs_modulus_pa": youngs_modulus,
            "shear_modulus_pa": mu, "bulk_modulus_pa": bulk,
            "poisson_ratio": poisson_ratio(bulk, mu), "bend_radius_m": rho,
            "leg_length_m": leg_length_over_d0 * diameter, "rod_length_m": 2.0 * length,
            "dhat_over_d0": dhat_over_d0, "kappa_pa": contact.stiffness,
            "initial_gap_m": gap0,
            "clamps": "each end face held (all components), both rods' clamps moved apart "
                      "along x by pull / 2 each",
        },
        "relaxation_iterations": int(relax),
        "relaxed": relaxed,
        "steps": table,
        "newton_iterations_total": int(sum(problem.iterations)) + int(relax),
        "wall_time_s": time.perf_counter() - start,
    }
