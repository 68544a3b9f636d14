"""The study's knot scenes: they build a model, its state and contact layer; they never solve.

Both trefoils start from a loose parametric curve scaled until a tube of the full diameter
D0 fits on it with a margin; that start is longer than the requested rest length L0, and
the rod is tied by continuation, shrinking its rest length from the start length to L0
(physics.md sec. 4; the issue's "shrinking rest length"), so the knot is tightened by the
mechanics, not by the start curve. The tube keeps the diameter D0 throughout.

Rigid motions are removed by a gauge that exerts no force at equilibrium: the curve is
rotated so that chosen vertices lie on coordinate axes/planes, and only coordinates along
which a rigid motion would move them are fixed (the energy is invariant under that motion,
so the reaction there vanishes at equilibrium).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from tightknot.knots import curves
from tightknot.knots.smoothing import gaussian_smooth_points
from tightknot.rods.boundary import BoundaryConditions
from tightknot.rods.builder import RodBuilder
from tightknot.rods.contact import ContactLayer
from tightknot.rods.contact_law import RadialComplianceLaw
from tightknot.rods.material import Material, check_positive
from tightknot.rods.model import Model
from tightknot.rods.state import State

#: The study's rod (physics.md sec. 1).
STUDY_DIAMETER = 8.5e-3
STUDY_MATERIAL = Material(youngs_modulus=1.25e6, poisson_ratio=0.5, density=1160.0)


@dataclass
class KnotScene:
    """A knot ready to be solved.

    Attributes:
        name: "closed_trefoil", "open_trefoil"...
        model, state: the rod and its start.
        contact: the contact layer (tube of diameter D0).
        diameter: rest diameter D0 [m].
        rest_length: rest length L0 [m] the knot is tied to.
        closed: closed knot.
        start_length_ratio: rest length of the start over L0 (>= 1; the model's edge rest
            lengths are those of the start, scaled by 1/ratio when tying).
        pull_axis: unit pull axis of an open knot (its ends lie on it), else None.
        knot_type: the expected knot type ("3_1").
    """

    name: str
    model: Model
    state: State
    contact: ContactLayer
    diameter: float
    rest_length: float
    closed: bool
    start_length_ratio: float
    pull_axis: np.ndarray | None
    knot_type: str = "3_1"
    info: dict = field(default_factory=dict)


def _largest_diameter(points: np.ndarray, closed: bool, diameter: float,
                      clearance: float) -> float:
    """Largest tube diameter [m] that fits on the curve with the margin ``clearance``:
    non-local distance (exclusion window of the target diameter) and bend radius."""
    d, _, _ = curves.min_nonlocal_distance(points, closed,
                                           curves.exclusion_arc_length(diameter))
    kmax = curves.max_curvature(points, closed)
    return min(d, 2.0 / kmax) / clearance


def _rotate_to_axes(points: np.ndarray, a: int, b: int, c: int) -> np.ndarray:
    """Rigidly move the curve so that vertex a is at the origin, b on +x, c in the x-y plane."""
    p = points - points[a]
    ex = p[b] / np.linalg.norm(p[b])
    v = p[c] - (p[c] @ ex) * ex
    ey = v / np.linalg.norm(v)
    ez = np.cross(ex, ey)
    return p @ np.stack([ex, ey, ez], axis=1)


def _check_common(diameter: float, nodes: int, minimum: int) -> float:
    d0 = check_positive("diameter", diameter, "m")
    if int(nodes) != nodes or nodes < minimum:
        raise ValueError(f"nodes must be a whole number >= {minimum}, got {nodes!r}")
    return d0


def closed_trefoil(
    l0_over_d0: float = 16.37,
    diameter: float = STUDY_DIAMETER,
    nodes: int = 200,
    material: Material | None = None,
    law: RadialComplianceLaw | None = None,
    twist: bool = True,
    device: str = "cpu",
    clearance: float = 1.02,
) -> KnotScene:
    """The study's closed trefoil: rest length L0 = ``l0_over_d0`` D0, joined with no excess
    twist, no external load (physics.md sec. 1, scene 1)."""
    d0 = _check_common(diameter, nodes, 24)
    ratio = check_positive("l0_over_d0", l0_over_d0, "")
    if ratio < 10.0:
        raise ValueError(f"l0_over_d0 must be >= 10 (a trefoil needs 16.37 when ideal), got "
                         f"{l0_over_d0!r}")
    pts = curves.resample_uniform(curves.trefoil(4000), int(nodes), closed=True)
    length = float(np.linalg.norm(np.roll(pts, -1, axis=0) - pts, axis=1).sum())
    pts *= ratio * d0 / length
    n = pts.shape[0]
    pts = _rotate_to_axes(pts, 0, n // 3, 2 * n // 3)
    # Grow the start until the tube D0 fits (scale >= 1 means the rest length shrinks).
    grow = max(1.0, d0 / _largest_diameter(pts, True, d0, clearance))
    pts *= grow
    b = RodBuilder(twist=twist)
    b.add_rod(pts, d0, material or STUDY_MATERIAL, closed=True)
    model = b.finalize(device)
    state = State.initial(model)
    contact = ContactLayer(model, law)
    return KnotScene("closed_trefoil", model, state, contact, d0, ratio * d0, True, grow,
                     None, info={"l0_over_d0": ratio})


def open_trefoil(
    rest_length: float = 0.185,
    diameter: float = STUDY_DIAMETER,
    nodes: int = 300,
    material: Material | None = None,
    law: RadialComplianceLaw | None = None,
    twist: bool = False,
    device: str = "cpu",
    tail_fraction: float = 0.2,
    clearance: float = 1.02,
) -> KnotScene:
    """The study's open trefoil (overhand knot) of rest length L0 with straight tails along
    the x axis (the pull axis); its first end is pinned, its last end slides along x.

    ``twist=False`` by default: an isotropic rod with twist-free ends relaxes its twist to
    zero, so the twist dofs change nothing (model only what the scene requires).
    """
    d0 = _check_common(diameter, nodes, 40)
    l0 = check_positive("rest_length", rest_length, "m")
    if l0 < 10.0 * d0:
        raise ValueError(f"rest_length must be >= 10 D0 = {10 * d0:.4g} m for an open trefoil, "
                         f"got {rest_length!r}")
    if not (0.05 <= tail_fraction <= 0.45):
        raise ValueError(f"tail_fraction must be in [0.05, 0.45], got {tail_fraction!r}")
    # The core of the helper curve is ~26 size units long; tails of tail * size each.
    core = curves.open_trefoil(4000, 1.0, 0.0)
    lc = float(np.linalg.norm(np.diff(core, axis=0), axis=1).sum())
    tail = tail_fraction * lc / (1.0 - 2.0 * tail_fraction)
    raw = curves.open_trefoil(4000, 1.0, tail)
    # Round the corners where the tails join the knot (std 0.5 knot-size units): they bend
    # 60x tighter than the knot itself and would otherwise set the start radius.
    per_unit = raw.shape[0] / float(np.linalg.norm(np.diff(raw, axis=0), axis=1).sum())
    raw = gaussian_smooth_points(raw, closed=False, std_points=0.5 * per_unit, ends="reflect")
    pts = curves.resample_uniform(raw, int(nodes), closed=False)
    length = float(np.linalg.norm(np.diff(pts, axis=0), axis=1).sum())
    pts *= l0 / length
    # Pull axis on x: first end at the origin, last end on +x; the vertex farthest from the
    # axis in the x-y plane, so that fixing its z removes the rotation about the axis.
    n = pts.shape[0]
    axis = pts[-1] - pts[0]
    axis /= np.linalg.norm(axis)
    radial = np.linalg.norm((pts - pts[0]) - np.outer((pts - pts[0]) @ axis, axis), axis=1)
    far = int(np.argmax(radial))
    pts = _rotate_to_axes(pts, 0, n - 1, far)
    grow = max(1.0, d0 / _largest_diameter(pts, False, d0, clearance))
    pts *= grow
    b = RodBuilder(twist=twist)
    b.add_rod(pts, d0, material or STUDY_MATERIAL, closed=False)
    model = b.finalize(device)
    state = State.initial(model)
    contact = ContactLayer(model, law)
    return KnotScene("open_trefoil", model, state, contact, d0, l0, False, grow,
                     np.array([1.0, 0.0, 0.0]),
                     info={"gauge_vertex": far, "tail_fraction": tail_fraction})


def gauge(scene: KnotScene, positions: np.ndarray | None = None,
          sliding_end: bool = True) -> BoundaryConditions:
    """The scene's force-free gauge (module docstring) at ``positions`` (default the start):
    first vertex pinned; closed knots fix two more vertices' coordinates that a rigid
    rotation would move and the uniform twist; open knots let the last end slide along the
    pull axis (``sliding_end``) and fix the z of the vertex farthest from the axis."""
    model = scene.model
    bcs = BoundaryConditions(model, positions).pin(0, 0)
    if scene.closed:
        n = model.vertex_count
        bcs.fix_components(0, n // 3, (1, 2)).fix_components(0, 2 * n // 3, (2,))
        if model.twist:
            bcs.fix_twist(0, 0)  # the uniform-twist rotation is a zero mode
        return bcs
    if sliding_end:
        bcs.fix_components(0, -1, (1, 2))
    bcs.fix_components(0, scene.info["gauge_vertex"], (2,))
    return bcs


def end_vertex(scene: KnotScene) -> int:
    """Index of the sliding (pulled) end of an open knot."""
    return scene.model.vertex_count - 1


def bending_force_scale(scene: KnotScene) -> float:
    """EI/D0^2 [N], the force scale of a knot made of this rod."""
    mat = scene.model.rods[0].material
    return mat.youngs_modulus * math.pi * scene.diameter**4 / 64.0 / scene.diameter**2


def vertex_radii(scene: KnotScene, x: np.ndarray, rest: np.ndarray) -> tuple[np.ndarray, ...]:
    """Deformed edge radii r0 lam^-nu [m] (the rest radius for a rigid tube) and their
    vertex averages [m], for centerline ``x`` and edge rest lengths ``rest``."""
    m = scene.model
    ev = m.edge_vertex
    lam = np.linalg.norm(x[ev[:, 1]] - x[ev[:, 0]], axis=1) / rest
    nu = 0.0 if scene.contact.law.rigid else m.rods[0].material.poisson_ratio
    r_e = m.edge_radius * lam ** (-nu)
    r_v = np.zeros(m.vertex_count)
    cnt = np.zeros(m.vertex_count)
    np.add.at(r_v, ev.ravel(), np.repeat(r_e, 2))
    np.add.at(cnt, ev.ravel(), 1.0)
    return r_e, r_v / np.maximum(cnt, 1.0)
