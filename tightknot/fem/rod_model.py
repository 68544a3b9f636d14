"""The rod model in the FEM's scenes: a crossing (indent) and a wrap, solved level by level.

The same load levels and parameters as the FEM scenes of :mod:`tightknot.fem.scenes`, on
the rod model with its contact layer (the rigid counter-bodies as rods of a law scaled to a
rigid partner, :func:`rigid_counterbody_law`); :mod:`tightknot.fem.crosscheck` compares the
two.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from .material import ROD_DIAMETER, YOUNGS_MODULUS

if TYPE_CHECKING:
    from tightknot.loading.levels import LevelLoad

EDGES_PER_D0: int = 12
"""Rod-model edges per diameter: the resolution of the knot scenes (closed trefoil: 200
nodes over 16.37 D0, open trefoil: 300 over 21.8 D0), so that the check speaks for them.
The smallest compared point contact (w = 0.0015 D0) has a patch radius sqrt(D0 w) =
0.04 D0, below one Gauss spacing: its force is expected to be the least accurate."""

DENSITY: float = 1160.0
"""Density [kg/m^3] of the rod model's material (statics: it plays no role)."""


def check_edges_per_d0(edges_per_d0: object) -> None:
    """Refuse a rod resolution that is not an integer of at least 4 edges per D0 (fewer
    cannot follow a crossing's dent, about a diameter long)."""
    if (isinstance(edges_per_d0, bool) or not isinstance(edges_per_d0, (int, np.integer))
            or edges_per_d0 < 4):
        raise ValueError(f"edges_per_d0 must be an integer >= 4, got {edges_per_d0!r}")


def rigid_counterbody_law(law: Any) -> Any:
    """The pair law of a rod against a rigid body of the same diameter: k 2^p for the line
    and point laws, so that the kernel's f(delta/2) becomes the per-side f(w = delta)."""
    return replace(law, k_line=law.k_line * 2.0**law.p_line,
                   k_point=law.k_point * 2.0**law.p_point,
                   source=f"rigid counter-body (w = delta) of {law.source}")


def _line_points(start: np.ndarray, end: np.ndarray, edges: int) -> np.ndarray:
    return np.linspace(start, end, edges + 1)


@dataclass
class RodScene:
    """A rod-model scene before its contact layer: the system, its level load, and where
    its rods are (the compared rod 0 of ``n_rod`` edges, the counter-bodies of ``n_obs``)."""

    system: Any
    load: Any
    n_rod: int
    n_obs: int
    mid: int
    half: float
    rod_v: np.ndarray
    obs_v: np.ndarray

    @property
    def model(self) -> Any:
        return self.system.model


def _vertices(model: Any, rod: int, edges: int) -> np.ndarray:
    start = model.rods[rod].vertex_start
    return np.arange(start, start + edges + 1)


def indent_scene(diameter: float, youngs_modulus: float, length_over_d0: float,
                 poisson_ratio: float = 0.5, edges_per_d0: int = EDGES_PER_D0) -> RodScene:
    """The indent scene's rods and constraints: a straight rod (axis e_z, Poisson ratio
    ``poisson_ratio``) between two pinned rods along e_x, touching it at rest, that move
    toward its axis by the level load w [m] each (``obs_v``: the upper one's vertices);
    ``edges_per_d0`` edges per D0 of rod, on every rod."""
    from tightknot.loading.levels import LevelLoad
    from tightknot.rods.boundary import BoundaryConditions
    from tightknot.rods.builder import RodBuilder
    from tightknot.rods.material import Material
    from tightknot.rods.state import State
    from tightknot.solvers.system import RodSystem

    check_edges_per_d0(edges_per_d0)
    d0 = diameter
    n_rod = int(round(length_over_d0 * edges_per_d0))
    n_rod += n_rod % 2  # even: a vertex at z = 0
    n_obs = 4 * edges_per_d0
    half = 0.5 * length_over_d0 * d0
    mat = Material(youngs_modulus, 0.5, DENSITY)
    b = RodBuilder(twist=False)
    b.add_rod(_line_points(np.array([0, 0, -half]), np.array([0, 0, half]), n_rod), d0,
              Material(youngs_modulus, poisson_ratio, DENSITY))
    for sign in (1.0, -1.0):  # indenters above and below, touching at rest
        b.add_rod(_line_points(np.array([-2 * d0, sign * d0, 0]),
                               np.array([2 * d0, sign * d0, 0]), n_obs), d0, mat)
    model = b.finalize()
    load = LevelLoad()
    bcs = BoundaryConditions(model)
    for rod, sign in ((1, 1.0), (2, -1.0)):
        for k in range(n_obs + 1):
            bcs.pin(rod, k, translation=lambda t, s=sign: np.array([0.0, -s * load(t), 0.0]))
    mid = n_rod // 2
    for k in range(n_rod + 1):
        bcs.fix_components(0, k, (0,))  # symmetry plane x = 0
    bcs.fix_components(0, mid, (2,))  # symmetry plane z = 0
    # rigid tilt about x is force-free between two crossing cylinders: gauge it at the
    # ends (their reactions vanish by the up-down symmetry)
    bcs.fix_components(0, 0, (1,))
    bcs.fix_components(0, -1, (1,))
    system = RodSystem(model, State.initial(model), bcs)
    return RodScene(system, load, n_rod, n_obs, mid, half, _vertices(model, 0, n_rod),
                    _vertices(model, 1, n_obs))


#: The wrap's initial overlap over D0: the rod floats on the contact (see scenes.wrap).
WRAP_START_OVERLAP: float = 0.01


def wrap_scene(diameter: float, youngs_modulus: float, length_over_d0: float,
               wrap_angle_deg: float, edges_per_d0: int = EDGES_PER_D0,
               stack: bool = False) -> RodScene:
    """The wrap scene's rods and constraints: a rod (axis e_z at rest) pulled by dead end
    forces, the level load T [N] times (0, sin(theta), +-cos(theta)), around a rod along
    e_x above it at y = D0 - ``WRAP_START_OVERLAP`` D0 (:func:`wrap_constraints`);
    ``edges_per_d0`` edges per D0 of rod, on both rods. The rod above is pinned (a rigid
    cylinder's stand-in), or with ``stack`` held as the FEM's ``soft_wrap`` holds its rod
    B, whose held mid-plane makes it a stack: B pressed by the wrapped rod from below and
    by its mirror image from above (a third rod, mirrored about B's axis, with mirrored
    loads and constraints), B's axis straight (y and z held at every vertex: the held
    mid-plane and the symmetry plane z = 0), free to stretch along it but for its middle
    vertex (the symmetry plane x = 0), so that its pressed section thins as the solid's
    does."""
    from tightknot.loading.levels import LevelLoad
    from tightknot.rods.boundary import BoundaryConditions
    from tightknot.rods.builder import RodBuilder
    from tightknot.rods.material import Material
    from tightknot.rods.state import State
    from tightknot.solvers.system import RodSystem

    check_edges_per_d0(edges_per_d0)
    d0 = diameter
    theta = 0.5 * math.radians(wrap_angle_deg)
    n_rod = int(round(length_over_d0 * edges_per_d0))
    n_rod += n_rod % 2
    n_obs = 4 * edges_per_d0
    half = 0.5 * length_over_d0 * d0
    y_obs = d0 - WRAP_START_OVERLAP * d0
    mat = Material(youngs_modulus, 0.5, DENSITY)
    b = RodBuilder(twist=False)
    b.add_rod(_line_points(np.array([0, 0, -half]), np.array([0, 0, half]), n_rod), d0, mat)
    b.add_rod(_line_points(np.array([-2 * d0, y_obs, 0]), np.array([2 * d0, y_obs, 0]),
                           n_obs), d0, mat)
    if stack:
        b.add_rod(_line_points(np.array([0, 2 * y_obs, -half]), np.array([0, 2 * y_obs, half]),
                               n_rod), d0, mat)
    # the wrapped rod and its mirror image: their tails cross in the plane x = 0
    model = b.finalize(mirror_rod_pairs=((0, 2),) if stack else ())
    load = LevelLoad()
    bcs = BoundaryConditions(model)
    for k in range(n_obs + 1):
        if stack:
            bcs.fix_components(1, k, (1, 2))
        else:
            bcs.pin(1, k)
    mid = wrap_constraints(bcs, n_rod, theta, load)
    if stack:
        bcs.fix_components(1, n_obs // 2, (0,))
        wrap_constraints(bcs, n_rod, theta, load, rod=2, side=-1.0)
    system = RodSystem(model, State.initial(model), bcs)
    return RodScene(system, load, n_rod, n_obs, mid, half, _vertices(model, 0, n_rod),
                    _vertices(model, 1, n_obs))


def _solve_levels(system: Any, load: LevelLoad, levels: list[float],
                  measure: Any) -> list[dict[str, Any]]:
    """Solve each level from the last one: one load continuation each, along which the load
    moves linearly from the last level to this one; from the third level on, Newton starts
    from the linear extrapolation (in the load value) of the last two equilibria (a failed
    first step retries smaller steps from the last equilibrium without it)."""
    from tightknot.loading.levels import LevelOptions, LevelPath, SecantPredictor
    from tightknot.solvers.program import Program

    path = LevelPath(system, load, LevelOptions(steps="linear", proximal_dt=None,
                                                predictor=SecantPredictor()))
    rows = []
    for value in levels:
        it0 = path.iterations
        why = Program(path.move_to(value), "move_to").run()
        row = measure(value)
        row["converged"] = not why
        row["newton_iterations"] = path.iterations - it0
        rows.append(row)
    return rows


def _section_stretch(layer: Any, x: np.ndarray, model: Any, mid: int, own: float) -> float:
    """The stretch that thins the rod's mid section: ``own`` (the mid edges' mean) for a layer
    thinning each edge by its own stretch, else the layer's (a window mean, or the rod's mean
    stretch) over the two mid edges."""
    if layer.radius_window == 0.0 and layer.thinning == "edge":
        return own
    lam = layer.section_stretch(x, model.edge_rest_length)
    e0 = model.rods[0].edge_start
    return float(0.5 * (lam[e0 + mid - 1] + lam[e0 + mid]))


def rod_indent(w_levels: list[float], diameter: float = ROD_DIAMETER,
               youngs_modulus: float = YOUNGS_MODULUS, length_over_d0: float = 3.0,
               law: Any = None, poisson_ratio: float = 0.5,
               radius_window: float = 0.0, thinning: str = "rod") -> dict[str, Any]:
    """The indent scene with the rod model: a straight rod (axis e_z) between two pinned
    rods along e_x that move toward its axis by w [m] each (``w_levels``).

    ``poisson_ratio`` of the rod (a diagnostic at 0: the contact radius r0 lambda^(-nu)
    then does not thin with stretch; the straight rod's bending plays no role).
    ``radius_window``, ``thinning``: the contact layer's (:class:`tightknot.contact.layer.
    ContactLayer`; the default "rod" is the knots' default level, a window takes "edge").
    Returns per level: ``force`` [N] from the upper indenter, ``overlap_over_d0``,
    ``axial_force_mid_over_e_d0sq`` (the contact forces' axial resultant on one half),
    ``area_ratio_mid``, ``peak_pressure_over_e``, and the wall time.
    """
    from tightknot.contact.law import RadialComplianceLaw
    from tightknot.contact.layer import ContactLayer

    start = time.perf_counter()
    law = law or RadialComplianceLaw.from_json()
    pair_law = rigid_counterbody_law(law)
    d0 = diameter
    scene = indent_scene(diameter, youngs_modulus, length_over_d0, poisson_ratio)
    system, load, model = scene.system, scene.load, scene.model
    n_rod, mid, half = scene.n_rod, scene.mid, scene.half
    layer = ContactLayer(model, pair_law, gauss_points=2, radius_window=radius_window,
                         thinning="edge" if radius_window > 0.0 else thinning)
    system.add_term(layer)
    rod_v, up_v = scene.rod_v, scene.obs_v

    def measure(w: float) -> dict[str, Any]:
        x = system.state.x
        _, g, _ = layer.evaluate(x, model.edge_rest_length, True, False)
        # the pair's forces are equal and opposite: the upper indenter's (on it, -g) is the
        # magnitude of the force on the rod
        force = -float(g[up_v, 1].sum())
        # footprint: rms distance of the upper indenter's contact force from the crossing,
        # along the indenter (by the 90-degree symmetry of the kernel also along the rod)
        f_up = -g[up_v, 1]
        rms = math.sqrt(float((f_up * x[up_v, 0] ** 2).sum()) / force) if force > 0 else 0.0
        # axial force in the mid section (tension > 0): the contact forces' z components
        # on the z > 0 half (force on the rod: -g)
        axial = -float(g[rod_v[mid + 1:], 2].sum())
        xm = x[rod_v[mid]]
        y_up = x[up_v[0], 1]
        dist = math.hypot(y_up - xm[1], xm[2])
        e = np.linalg.norm(np.diff(x[rod_v], axis=0), axis=1)
        stretch = float(0.5 * (e[mid - 1] + e[mid]) / (2.0 * half / n_rod))
        sec = _section_stretch(layer, x, model, mid, stretch)
        overlap = d0 / 2.0 * sec**-0.5 + d0 / 2.0 - dist
        w_side = max(overlap, 0.0)  # rigid indenter: the rod takes the whole overlap
        return {
            "w_over_d0": w / d0,
            "approach_over_d0": 2.0 * w / d0,
            "force": force,
            "force_over_e_d0sq": force / (youngs_modulus * d0**2),
            "overlap_over_d0": overlap / d0,
            "axial_stretch_mid": stretch,
            "axial_force_mid_over_e_d0sq": axial / (youngs_modulus * d0**2),
            "area_ratio_mid": float(law.area_factor(w_side, d0)) / sec,
            "peak_pressure_over_e": float(law.peak_pressure_point(w_side, d0)),
            "semi_axis_over_d0": float(law._power(law.k_patch, law.p_patch, w_side, d0)),
            "force_rms_halfwidth_over_d0": rms / d0,
        }

    rows = _solve_levels(system, load, list(w_levels), measure)
    return {"steps": rows, "wall_time_s": time.perf_counter() - start,
            "vertices": int(model.vertex_count), "law": pair_law.source}


def wrap_constraints(bcs: Any, n_rod: int, theta: float, load: LevelLoad, rod: int = 0,
                     side: float = 1.0) -> int:
    """The wrapped rod's (``rod``, ``n_rod`` edges) constraints of the wrap scene: the plane
    x = 0, the symmetry plane z = 0 at its middle vertex, and dead end forces
    ``load(t)`` (0, ``side`` sin(theta), +-cos(theta)) [N] (``side`` -1: the mirror image
    of a stack). Returns the middle vertex."""
    mid = n_rod // 2
    for k in range(n_rod + 1):
        bcs.fix_components(rod, k, (0,))  # symmetry plane x = 0
    bcs.fix_components(rod, mid, (2,))  # symmetry plane z = 0
    s, c = side * math.sin(theta), math.cos(theta)
    bcs.force(rod, 0, lambda t: load(t) * np.array([0.0, s, -c]))
    bcs.force(rod, -1, lambda t: load(t) * np.array([0.0, s, c]))
    return mid


def rod_wrap(tension_levels: list[float], wrap_angle_deg: float = 90.0,
             diameter: float = ROD_DIAMETER, youngs_modulus: float = YOUNGS_MODULUS,
             length_over_d0: float = 4.5, law: Any = None,
             radius_window: float = 0.0, thinning: str = "rod") -> dict[str, Any]:
    """The wrap scene with the rod model: a rod (axis e_z at rest) pulled by dead end
    forces T (0, sin(theta), +-cos(theta)) around a pinned rod along e_x above it.

    Returns per tension level [N]: ``force_per_length_mid`` [N/m] (contact line load at
    the middle vertex over its deformed Voronoi length), ``contact_force_total`` [N],
    ``approach_over_d0``, ``overlap_over_d0``, ``area_ratio_mid``, ``kappa_d0_mid``
    (Bergou curvature), ``peak_pressure_over_e`` and the wall time. ``radius_window``,
    ``thinning``: the contact layer's (as :func:`rod_indent`).
    """
    from tightknot.contact.law import RadialComplianceLaw
    from tightknot.contact.layer import ContactLayer
    from tightknot.knots.curvature import bergou_curvature

    start = time.perf_counter()
    law = law or RadialComplianceLaw.from_json()
    pair_law = rigid_counterbody_law(law)
    d0 = diameter
    scene = wrap_scene(diameter, youngs_modulus, length_over_d0, wrap_angle_deg)
    system, load, model = scene.system, scene.load, scene.model
    n_rod, mid, half = scene.n_rod, scene.mid, scene.half
    y_obs = d0 - WRAP_START_OVERLAP * d0
    layer = ContactLayer(model, pair_law, gauss_points=2, radius_window=radius_window,
                         thinning="edge" if radius_window > 0.0 else thinning)
    system.add_term(layer)
    rod_v, obs_v = scene.rod_v, scene.obs_v

    def measure(tension: float) -> dict[str, Any]:
        x = system.state.x
        _, g, _ = layer.evaluate(x, model.edge_rest_length, True, False)
        total = float(np.linalg.norm(g[obs_v].sum(axis=0)))
        xr = x[rod_v]
        e = np.linalg.norm(np.diff(xr, axis=0), axis=1)
        voronoi = 0.5 * (e[mid - 1] + e[mid])
        f_mid = float(np.linalg.norm(g[rod_v[mid]])) / voronoi
        stretch = float(voronoi / (2.0 * half / n_rod))
        sec = _section_stretch(layer, x, model, mid, stretch)
        xm = xr[mid]
        dist = math.hypot(y_obs - xm[1], xm[2])
        overlap = d0 / 2.0 * sec**-0.5 + d0 / 2.0 - dist
        w_side = max(overlap, 0.0)  # rigid cylinder: the rod takes the whole overlap
        kappa = float(bergou_curvature(xr, closed=False)[mid])
        return {
            "tension": tension,
            "tension_over_e_d0sq": tension / (youngs_modulus * d0**2),
            "approach_over_d0": (d0 - dist) / d0,
            "overlap_over_d0": overlap / d0,
            "axial_stretch_mid": stretch,
            "contact_force_total": total,
            "force_per_length_mid": f_mid,
            "force_per_length_mid_over_e_d0": f_mid / (youngs_modulus * d0),
            # one-sided: diameter reduction delta, i.e. delta/2 per side on average
            "area_ratio_mid": float(law.area_factor(0.5 * w_side, d0)) / sec,
            "kappa_d0_mid": kappa * d0,
            # the kernel blends to the point law at crossing angles above 35 degrees
            # (here 90): its pressure law; the line law's value for comparison
            "peak_pressure_over_e": float(law.peak_pressure_point(w_side, d0)),
            "peak_pressure_line_law_over_e": float(law.peak_pressure_line(w_side, d0)),
        }

    rows = _solve_levels(system, load, list(tension_levels), measure)
    return {"steps": rows, "wall_time_s": time.perf_counter() - start,
            "vertices": int(model.vertex_count), "law": pair_law.source}
