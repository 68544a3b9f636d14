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

Model levels (issue 7, "model only what a scene requires"; physics.md sec. 4). Every scene
factory takes them as parameters and records them in ``KnotScene.info["model"]``:

* ``twist=True``: one twist angle per edge, twisting energy GJ tau^2/2 (Bergou et al. 2008
  eq. 6); a closed rod is joined with no excess twist and conserves its link, so a change
  of writhe while tying shows up as twist. ``twist=False``: no twist dofs; neglects the
  twisting energy and the bend-twist coupling, i.e. assumes the twist relaxes to zero.
  Exact for an isotropic rod with free or twist-free ends (the open knots: default off);
  for a closed isotropic rod it neglects the twist GJ (2 pi dWr)^2/(2 L) that a writhe
  change dWr forces on a closed rod of conserved link (White 1969), small next to the
  bending energy of a tight knot (closed trefoils: default on, as the study joined them).
* ``contact="compliant"`` (default): the radial-compliance layer with the FEM-calibrated
  law (:class:`~tightknot.contact.law.RadialComplianceLaw`, or the ``law`` given):
  sections flatten and thin with stretch. Neglects friction, the coupling between the
  squeezes of neighbouring contacts on one section (each pair follows the single-pair
  fit) and any deformation beyond the calibrated range (overlap 0.3 D). Every section of
  a rod thins with the rod's mean stretch L/L0 (:mod:`tightknot.contact.rod_mean_radius`;
  with its edge's own stretch a crossing pulled the edges under it apart, 3.4 times the
  FEM's axial force, and a knot pulled hard collapsed: docs/design_notes.md, contact);
  neglects where along the rod a squeezed section extends: the contact's pull toward
  thinner sections acts on the whole rod, so the tails' stretch exceeds the pull's (their
  elastic tension 12 to 15 % above it on the 185 mm knot at 2 to 20 N), while the knot's
  shape sees the pull itself.
  ``contact="smoothed"``: the compliant law with the section thinned by the stretch
  averaged over +-:data:`SMOOTHED_RADIUS_WINDOW` D0 along the rod
  (:mod:`tightknot.contact.section_radius`): the indent force within -8 to +7 % of the
  fine-mesh FEM, its axial force at the crossing 1.07 (deepest level) to 5 times the FEM's
  (compliant: 3.4 to 54 times); the knots come out
  the same within 1e-4 (closed trefoil at 16.37: stretch) to 3 % (the 185 mm knot's pulling
  force, reached at another Lambda_OC within its tolerance), in as many Newton iterations
  at 1.7 to 2.6 times the time (its Hessian couples whole windows of the rod;
  bench/contact_levels.py). Not in the batch (:func:`tightknot.loading.batch.tie_batch`).
  ``contact="sectioned"`` (or its :class:`~tightknot.contact.sectioned.SectionSettings`):
  each vertex carries its section's Fourier modes up to N (default 8) as dofs, and contact
  is between the deformed boundaries (:mod:`tightknot.contact.sectioned`): width, pressure
  and area come out of the state; calibrated on the FEM's squeeze (the modes' local
  compliance), judged by its indent, wrap and crossings (docs/sectioned_level.md).
  Neglects friction, the section's shear along the rod and the bending stiffness a
  flattened section loses; about 2 (N - 1) dofs per vertex more to solve. Not in the batch.
  ``contact="rigid"``: the same layer with ``law.rigid_tube()``, 1000 times stiffer and a
  hard radius D0/2 that does not thin with stretch; neglects every deformation of the
  section (the ideal-knot tube); width, pressure and area are then not reported.
  ``contact="off"``: no contact layer (``KnotScene.contact`` is None); neglects
  self-contact entirely, so the rod may pass through itself: only for shapes without
  contact (a loose start, the elastic cost alone in benchmarks); :func:`tightknot.loading.tie.tie`
  needs a contact layer to tie a knot.
* Inertia is not a scene property: the static solvers (``continuation``, ``newton``)
  neglect it, the dynamic ones (``tightknot.solvers.dynamic``: implicit Euler, proximal
  steps) add the lumped masses of ``Material.density``. Gravity is not modelled by the
  scenes (negligible for these rods, physics.md sec. 1).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from tightknot.contact.law import RadialComplianceLaw
from tightknot.contact.layer import ContactLayer
from tightknot.contact.sectioned import SectionedLayer, SectionSettings
from tightknot.knots import curves
from tightknot.knots.catalogue import IDEAL_L_OVER_D as IDEAL_L_OVER_D  # the scenes' name
from tightknot.knots.catalogue import builtin, ideal_l_over_d, open_curve
from tightknot.knots.smoothing import gaussian_smooth_points
from tightknot.rods.boundary import BoundaryConditions
from tightknot.rods.builder import RodBuilder
from tightknot.rods.material import Material, check_positive
from tightknot.rods.model import Model
from tightknot.rods.state import State

#: The study's rod (physics.md sec. 1).
STUDY_DIAMETER = 8.5e-3
STUDY_MATERIAL = Material(youngs_modulus=1.25e6, poisson_ratio=0.5, density=1160.0)

#: Radial offset of the tails from the cut knot [knot-size units] (curves._open_from_closed).
_CUT_OFFSET = 0.6

#: Contact levels of a scene (module docstring says what each neglects).
CONTACT_LEVELS = ("compliant", "smoothed", "sectioned", "rigid", "off")

#: Half-width [D0] of the stretch window of the "smoothed" contact level: 1 D0 gives the
#: FEM's axial force at the indent's deepest level (1.07 times it; 0.5 D0: 2 times), see
#: docs/fem_crosscheck.md.
SMOOTHED_RADIUS_WINDOW = 1.0

#: Length [D0] of each tail held on the pull axis by a grip (open knots), as the clamps of
#: a tensile test hold a rope: the ends cannot swing, so a frictionless knot that drifts
#: toward an end meets a straight, held tail instead of a hinge it can slip over.
GRIP_LENGTH = 1.0

#: Twist in the grips of an open rod with twist dofs: "free" (the rod may spin about the
#: pull axis inside the grip) or "clamped" (its material frame held).
GRIP_TWIST = ("free", "clamped")

#: Default edge length [D0] of a scene's rod: its vertex count follows its rest length
#: (:func:`default_nodes`). About the study's loose open trefoil's 300 vertices over 21.8 D0;
#: the trade-off study (README) gives the accuracy a resolution buys.
DEFAULT_EDGE_D0 = 0.07


#: Default L0/D0 of the closed figure-eight: 5 % above its ideal 21.04. The trefoil is tied
#: at its ideal value (the study's choice, the rod then stretches ~7 %); the figure-eight is
#: the second knot type that shows the code is not trefoil-only, so it is tied where a
#: polygon of few vertices still closes with the stretch and squeeze the trefoil shows
#: (a coarse polygon's tube is longer than the smooth ideal one), not as a study of its own.
FIGURE_EIGHT_L0_OVER_D0 = 22.1


@dataclass
class KnotScene:
    """A knot ready to be solved.

    Attributes:
        name: "closed_trefoil", "open_trefoil"...
        model, state: the rod and its start.
        contact: the contact layer (tube of diameter D0); None when contact is off.
        diameter: rest diameter D0 [m].
        rest_length: rest length L0 [m] the knot is tied to.
        closed: closed knot.
        start_length_ratio: rest length of the start over L0 (>= 1; the model's edge rest
            lengths are those of the start, scaled by 1/ratio when tying).
        pull_axis: unit pull axis of an open knot (its ends lie on it), else None.
        knot_type: the expected knot type ("3_1", "4_1").
        info: scene parameters; ``info["model"]`` holds the model levels (``twist``,
            ``contact``; module docstring).
    """

    name: str
    model: Model
    state: State
    contact: ContactLayer | None
    diameter: float
    rest_length: float
    closed: bool
    start_length_ratio: float
    pull_axis: np.ndarray | None
    knot_type: str = "3_1"
    info: dict = field(default_factory=dict)
    #: The same scene at another vertex count, ``rebuild(nodes)`` (mesh continuation:
    #: tightknot.loading.refine), None when it cannot be rebuilt.
    rebuild: Callable[[int], KnotScene] | None = field(default=None, repr=False,
                                                        compare=False)


#: Points of the start curve used to measure its spacing (see _largest_diameter).
_SPACING_POINTS = 4000


def _largest_diameter(points: np.ndarray, closed: bool, diameter: float,
                      clearance: float) -> float:
    """Largest tube diameter [m] that fits on the curve with the margin ``clearance``:
    non-local distance (exclusion window of the target diameter) and bend radius."""
    if not isinstance(clearance, (int, float, np.floating)) or not (1.0 <= clearance <= 2.0):
        raise ValueError(f"clearance must be in [1, 2] (a margin on the start's spacing), "
                         f"got {clearance!r}")
    if points.shape[0] > _SPACING_POINTS:
        # The start curve is smooth: a 4000-point resampling gives its spacing to the sag of
        # its chords (far inside the clearance), whereas the KD-tree pairs of a 1e5-vertex
        # polygon within one exclusion window (~1e9) do not fit in memory.
        points = curves.resample_uniform(points, _SPACING_POINTS, closed)
    d, _, _ = curves.min_nonlocal_distance(points, closed,
                                           curves.exclusion_arc_length(diameter))
    kmax = curves.max_curvature(points, closed)
    return min(d, 2.0 / kmax) / clearance


def rotate_to_axes(points: np.ndarray, a: int, b: int, c: int) -> np.ndarray:
    """Rigidly move the curve so that vertex a is at the origin, b on +x, c in the x-y plane."""
    p = points - points[a]
    ex = p[b] / np.linalg.norm(p[b])
    v = p[c] - (p[c] @ ex) * ex
    ey = v / np.linalg.norm(v)
    ez = np.cross(ex, ey)
    return p @ np.stack([ex, ey, ez], axis=1)


def default_nodes(length_over_d0: float, closed: bool) -> int:
    """Vertices of a rod of rest length ``length_over_d0`` D0 with edges of about
    :data:`DEFAULT_EDGE_D0` D0 (a closed rod has as many edges as vertices)."""
    edges = max(1, math.ceil(length_over_d0 / DEFAULT_EDGE_D0 - 1e-9))
    return edges if closed else edges + 1


def _check_common(diameter: float, nodes: int, minimum: int) -> float:
    d0 = check_positive("diameter", diameter, "m")
    if not (1e-9 <= d0 <= 1e3):
        # Far outside, the curve's scaling to the tube overflows or underflows float64.
        raise ValueError(f"diameter must be in [1e-9, 1e3] m, got {diameter!r}")
    if (isinstance(nodes, bool) or not isinstance(nodes, (int, float, np.integer, np.floating))
            or not math.isfinite(nodes) or int(nodes) != nodes or nodes < minimum):
        raise ValueError(f"nodes must be a whole number >= {minimum}, got {nodes!r}")
    return d0


def check_twist(twist: object) -> bool:
    """The ``twist`` model level, checked: a bool (module docstring)."""
    if not isinstance(twist, (bool, np.bool_)):
        raise ValueError(f"twist must be True or False, got {twist!r}")
    return bool(twist)


def _edge_lengths(pts: np.ndarray, closed: bool) -> np.ndarray:
    return np.linalg.norm((np.roll(pts, -1, axis=0) - pts) if closed else np.diff(pts, axis=0),
                          axis=1)


def minimum_nodes(pts: np.ndarray, closed: bool, d0: float) -> int:
    """The fewest vertices [count] a start curve like ``pts`` [m] (any resolution) can be
    resampled to with every edge within pi D0/4 (:func:`_check_edge_length`); 10 % above the
    bare count, since a start grows a little with the resolution (finer polygons bend
    tighter)."""
    length = _edge_lengths(pts, closed).sum()
    return int(math.ceil(1.1 * length / (0.25 * math.pi * d0))) + (0 if closed else 1)


def _check_edge_length(pts: np.ndarray, closed: bool, d0: float, nodes: int,
                       contact: str) -> None:
    """Refuse a start whose edges exceed pi D0/4, half the contact layer's exclusion window
    (pi D0/2): two neighbouring edges would then hold points farther apart than the window,
    become a contact pair, and their shared vertex would read as a self-intersection."""
    if contact == "off":
        return
    longest = _edge_lengths(pts, closed).max()
    if longest > 0.25 * math.pi * d0:
        raise ValueError(f"nodes must be about >= {minimum_nodes(pts, closed, d0)} for this "
                         f"knot (the start's edges are {longest / d0:.3g} D0 long, above "
                         f"pi/4 D0), got {nodes!r}")


def contact_name(contact: str | SectionSettings) -> str:
    """The level's name ("sectioned" for a sectioned level's settings)."""
    return "sectioned" if isinstance(contact, SectionSettings) else contact


def check_contact(contact: str | SectionSettings, law: RadialComplianceLaw | None = None
                  ) -> str | SectionSettings:
    """The ``contact`` model level, checked against :data:`CONTACT_LEVELS` and ``law`` (the
    settings of a sectioned level stand for "sectioned" and are returned as they are)."""
    if contact_name(contact) == "sectioned" and law is not None:
        raise ValueError("contact='sectioned' takes no radial-compliance law: its contact is "
                         "calibrated by the section's FEM calibration "
                         "(tightknot/data/section_calibration.json)")
    if isinstance(contact, SectionSettings):
        return contact
    if contact not in CONTACT_LEVELS:
        raise ValueError(f"contact must be one of {', '.join(CONTACT_LEVELS)}, got {contact!r}")
    if contact == "off" and law is not None:
        raise ValueError("a contact law was given with contact='off'")
    if law is not None and law.rigid and contact in ("compliant", "smoothed"):
        raise ValueError(f"contact={contact!r} was given a rigid-tube law: use contact='rigid'")
    return contact


def contact_layer(model: Model, contact: str | SectionSettings = "compliant",
                  law: RadialComplianceLaw | None = None) -> ContactLayer | None:
    """The contact layer of a model at the level ``contact`` (one of :data:`CONTACT_LEVELS`,
    or the :class:`~tightknot.contact.sectioned.SectionSettings` of a sectioned level; what
    each neglects: module docstring). ``law``: the compliant law (default the shipped FEM
    calibration); "rigid" makes its rigid-tube version; "off" and "sectioned" take none."""
    check_contact(contact, law)
    if contact_name(contact) == "sectioned":
        return SectionedLayer(model, contact if isinstance(contact, SectionSettings) else None)
    if contact == "off":
        return None
    if contact == "rigid":
        base = law or RadialComplianceLaw.from_json()
        return ContactLayer(model, base if base.rigid else base.rigid_tube())
    if contact == "smoothed":
        return ContactLayer(model, law, radius_window=SMOOTHED_RADIUS_WINDOW)
    return ContactLayer(model, law, thinning="rod")


def _closed_knot(name: str, knot_type: str, curve: np.ndarray, ratio: float, d0: float,
                 nodes: int, material: Material | None, law: RadialComplianceLaw | None,
                 twist: bool, contact: str, device: str, clearance: float) -> KnotScene:
    """A closed knot of rest length ``ratio`` D0 from a dense closed ``curve`` (any scale):
    resampled, scaled to L0, grown until the tube D0 fits (module docstring)."""
    pts = curves.resample_uniform(curve, int(nodes), closed=True)
    length = float(np.linalg.norm(np.roll(pts, -1, axis=0) - pts, axis=1).sum())
    pts *= ratio * d0 / length
    n = pts.shape[0]
    pts = rotate_to_axes(pts, 0, n // 3, 2 * n // 3)
    # Grow the start until the tube D0 fits (scale >= 1 means the rest length shrinks).
    grow = max(1.0, d0 / _largest_diameter(pts, True, d0, clearance))
    pts *= grow
    _check_edge_length(pts, True, d0, nodes, contact)
    b = RodBuilder(twist=twist)
    b.add_rod(pts, d0, material or STUDY_MATERIAL, closed=True)
    model = b.finalize(device)
    state = State.initial(model)
    layer = contact_layer(model, contact, law)
    return KnotScene(name, model, state, layer, d0, ratio * d0, True, grow, None,
                     knot_type=knot_type,
                     info={"l0_over_d0": ratio,
                           "model": {"twist": twist, "contact": contact_name(contact)}})


def _check_ratio(l0_over_d0: float, knot_type: str) -> float:
    ratio = check_positive("l0_over_d0", l0_over_d0, "")
    # 0.61 of the ideal value (10 for the trefoil): far below it the rod would have to
    # stretch by more than half to close, outside any meaningful regime.
    ideal, known = ideal_l_over_d(knot_type)
    low = round(0.61 * ideal)
    if ratio < low:
        raise ValueError(f"l0_over_d0 must be >= {low} (the ideal {knot_type} needs "
                         f"{ideal:.2f}{'' if known else ', estimated'}), got {l0_over_d0!r}")
    return ratio


def closed_trefoil(
    l0_over_d0: float = 16.37,
    diameter: float = STUDY_DIAMETER,
    nodes: int | None = None,
    material: Material | None = None,
    law: RadialComplianceLaw | None = None,
    twist: bool = True,
    device: str = "cpu",
    clearance: float = 1.02,
    contact: str = "compliant",
) -> KnotScene:
    """The study's closed trefoil: rest length L0 = ``l0_over_d0`` D0, joined with no excess
    twist, no external load (physics.md sec. 1, scene 1). ``twist``, ``contact``: model
    levels (module docstring)."""
    ratio = _check_ratio(l0_over_d0, "3_1")
    nodes = default_nodes(ratio, True) if nodes is None else nodes
    d0 = _check_common(diameter, nodes, 24)
    twist, contact = check_twist(twist), check_contact(contact, law)
    scene = _closed_knot("closed_trefoil", "3_1", curves.trefoil(4000), ratio, d0, nodes,
                         material, law, twist, contact, device, clearance)
    scene.rebuild = lambda n: closed_trefoil(l0_over_d0, diameter, n, material, law, twist,
                                             device, clearance, contact)
    return scene


def closed_figure_eight(
    l0_over_d0: float = FIGURE_EIGHT_L0_OVER_D0,
    diameter: float = STUDY_DIAMETER,
    nodes: int | None = None,
    material: Material | None = None,
    law: RadialComplianceLaw | None = None,
    twist: bool = True,
    device: str = "cpu",
    clearance: float = 1.02,
    contact: str = "compliant",
) -> KnotScene:
    """A closed figure-eight knot (4_1) of rest length L0 = ``l0_over_d0`` D0 (default
    :data:`FIGURE_EIGHT_L0_OVER_D0`, 5 % above the ideal 21.04), joined with no excess
    twist, no external load: the trefoil's scene for a second knot type. ``twist``,
    ``contact``: model levels (module docstring)."""
    ratio = _check_ratio(l0_over_d0, "4_1")
    nodes = default_nodes(ratio, True) if nodes is None else nodes
    d0 = _check_common(diameter, nodes, 32)
    twist, contact = check_twist(twist), check_contact(contact, law)
    scene = _closed_knot("closed_figure_eight", "4_1", curves.figure_eight(4000), ratio, d0,
                         nodes, material, law, twist, contact, device, clearance)
    scene.rebuild = lambda n: closed_figure_eight(l0_over_d0, diameter, n, material, law,
                                                  twist, device, clearance, contact)
    return scene


def _open_knot(name: str, knot_type: str, curve_fn, rest_length: float, diameter: float,
               nodes: int | None, material: Material | None,
               law: RadialComplianceLaw | None, twist: bool, contact: str, device: str,
               tail_fraction: float,
               clearance: float, corner_std: float, grip_length: float, grip_twist: str,
               corner_window: float | None = None) -> KnotScene:
    """An open knot with straight tails from ``curve_fn(n, size, tail)`` (a curves.open_*
    helper; module docstring and :func:`open_trefoil`); ``corner_std``: std of the Gaussian
    rounding of the tail corners [knot-size units], applied to the whole curve, or only
    within ``corner_window`` units of the corners when given; ``nodes`` None: from the
    rest length (:func:`default_nodes`)."""
    if nodes is None:
        nodes = default_nodes(check_positive("rest_length", rest_length, "m")
                              / check_positive("diameter", diameter, "m"), False)
    d0 = _check_common(diameter, nodes, 40)
    twist, contact = check_twist(twist), check_contact(contact, law)
    l0 = check_positive("rest_length", rest_length, "m")
    if l0 < 10.0 * d0:
        raise ValueError(f"rest_length must be >= 10 D0 = {10 * d0:.4g} m for an open knot, "
                         f"got {rest_length!r}")
    if not isinstance(tail_fraction, (int, float, np.floating)) or not (
            0.05 <= tail_fraction <= 0.45):
        raise ValueError(f"tail_fraction must be in [0.05, 0.45], got {tail_fraction!r}")
    # A grip may hold at most a quarter of the rod at each end (the knot needs the rest).
    grip_max = 0.25 * l0 / d0
    if not (isinstance(grip_length, (int, float, np.floating)) and math.isfinite(grip_length)
            and 0.0 <= grip_length <= grip_max):
        raise ValueError(f"grip_length must be in [0, {grip_max:.3g}] D0 (a quarter of the rod), "
                         f"got {grip_length!r}")
    if grip_twist not in GRIP_TWIST:
        raise ValueError(f"grip_twist must be one of {', '.join(GRIP_TWIST)}, got {grip_twist!r}")
    # The core of the helper curve is ~26 size units long (trefoil); tails of tail * size each.
    core = curve_fn(4000, 1.0, 0.0)
    lc = float(np.linalg.norm(np.diff(core, axis=0), axis=1).sum())
    tail = tail_fraction * lc / (1.0 - 2.0 * tail_fraction)
    raw = curve_fn(4000, 1.0, tail)
    # Round the corners where the tails join the knot (std ``corner_std`` knot-size units):
    # they bend 60x tighter than the knot itself and would otherwise set the start radius.
    per_unit = raw.shape[0] / float(np.linalg.norm(np.diff(raw, axis=0), axis=1).sum())
    smooth = gaussian_smooth_points(raw, closed=False, std_points=corner_std * per_unit,
                                    ends="reflect")
    if corner_window is None:
        raw = smooth
    else:
        # Only near the corners (the tails plus ``corner_window`` units into the knot, a C1
        # smoothstep back to the raw curve): smoothing the whole knot that much would pull
        # its strands together and set the start's size instead.
        arc = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(raw, axis=0), axis=1))]
        j1, j2 = tail + _CUT_OFFSET, arc[-1] - tail - _CUT_OFFSET
        depth = np.where((arc < j1) | (arc > j2), 0.0,
                         np.minimum(np.abs(arc - j1), np.abs(arc - j2)))
        u = np.clip(depth / corner_window, 0.0, 1.0)
        w = (1.0 - u * u * (3.0 - 2.0 * u))[:, None]
        raw = w * smooth + (1.0 - w) * raw
    # Equal edges: a uniform rod, on which sliding the material through the knot by whole
    # edges is an exact symmetry (tie.recentre_open_knot relies on it).
    pts = curves.resample_equal_chords(raw, int(nodes))
    length = float(np.linalg.norm(np.diff(pts, axis=0), axis=1).sum())
    pts *= l0 / length
    # Pull axis on x: first end at the origin, last end on +x; the vertex farthest from the
    # axis in the x-y plane, so that fixing its z removes the rotation about the axis.
    n = pts.shape[0]
    axis = pts[-1] - pts[0]
    axis /= np.linalg.norm(axis)
    radial = np.linalg.norm((pts - pts[0]) - np.outer((pts - pts[0]) @ axis, axis), axis=1)
    far = int(np.argmax(radial))
    pts = rotate_to_axes(pts, 0, n - 1, far)
    grow = max(1.0, d0 / _largest_diameter(pts, False, d0, clearance))
    pts *= grow
    _check_edge_length(pts, False, d0, nodes, contact)
    b = RodBuilder(twist=twist)
    b.add_rod(pts, d0, material or STUDY_MATERIAL, closed=False)
    model = b.finalize(device)
    state = State.initial(model)
    layer = contact_layer(model, contact, law)
    # The grip holds the end vertex and every vertex within grip_length of it in rest arc
    # length at L0 (equal edges of l0 / (n - 1)).
    grip = 1 + int(math.floor(grip_length * d0 * (n - 1) / l0 + 1e-9))
    return KnotScene(name, model, state, layer, d0, l0, False, grow,
                     np.array([1.0, 0.0, 0.0]), knot_type=knot_type,
                     info={"gauge_vertex": far, "tail_fraction": tail_fraction,
                           "grip_length": float(grip_length), "grip_vertices": grip,
                           "grip_twist": grip_twist,
                           "model": {"twist": twist, "contact": contact_name(contact)}})


def open_trefoil(
    rest_length: float = 0.185,
    diameter: float = STUDY_DIAMETER,
    nodes: int | None = None,
    material: Material | None = None,
    law: RadialComplianceLaw | None = None,
    twist: bool = False,
    device: str = "cpu",
    tail_fraction: float = 0.2,
    clearance: float = 1.02,
    contact: str = "compliant",
    grip_length: float = GRIP_LENGTH,
    grip_twist: str = "free",
) -> KnotScene:
    """The study's open trefoil (overhand knot) of rest length L0 with straight tails along
    the x axis (the pull axis); its first end is pinned, its last end slides along x, and
    the last ``grip_length`` D0 of each tail is held on the axis (a grip; 0: hinged ends),
    the rod free to spin in it about the axis or not (``grip_twist``, with twist dofs).

    ``twist=False`` by default: an isotropic rod with twist-free ends relaxes its twist to
    zero, so the twist dofs change nothing (model only what the scene requires).
    ``contact``: contact level (module docstring).
    """
    scene = _open_knot("open_trefoil", "3_1", curves.open_trefoil, rest_length, diameter,
                       nodes, material, law, twist, contact, device, tail_fraction, clearance,
                       corner_std=0.5, grip_length=grip_length, grip_twist=grip_twist)
    scene.rebuild = lambda n: open_trefoil(rest_length, diameter, n, material, law, twist,
                                           device, tail_fraction, clearance, contact,
                                           grip_length, grip_twist)
    return scene


def open_figure_eight(
    rest_length: float = 0.30,
    diameter: float = STUDY_DIAMETER,
    nodes: int | None = None,
    material: Material | None = None,
    law: RadialComplianceLaw | None = None,
    twist: bool = False,
    device: str = "cpu",
    tail_fraction: float = 0.2,
    clearance: float = 1.02,
    contact: str = "compliant",
    grip_length: float = GRIP_LENGTH,
    grip_twist: str = "free",
) -> KnotScene:
    """An open figure-eight knot (4_1) of rest length L0 with straight tails along the x
    axis, built, held and pulled like :func:`open_trefoil`. Default L0 = 0.30 m (35 D0):
    the figure-eight's core is ~1.3 times the trefoil's (ideal closed 21.04 D0 against
    16.37 D0), and its tails must stay long enough while the rest length shrinks
    (docs/design_notes.md, scenes)."""
    # Tail corners rounded with std 2 knot-size units within 5 units of them: the
    # trefoil's 0.5 leaves a corner whose bend, not the knot, sets the start's size, and
    # std 2 over the whole curve pulls the strands together.
    scene = _open_knot("open_figure_eight", "4_1", curves.open_figure_eight, rest_length,
                       diameter, nodes, material, law, twist, contact, device, tail_fraction,
                       clearance, corner_std=2.0, grip_length=grip_length,
                       grip_twist=grip_twist, corner_window=5.0)
    scene.rebuild = lambda n: open_figure_eight(rest_length, diameter, n, material, law,
                                                twist, device, tail_fraction, clearance,
                                                contact, grip_length, grip_twist)
    return scene


def closed_knot(
    knot_type: str,
    l0_over_d0: float | None = None,
    diameter: float = STUDY_DIAMETER,
    nodes: int | None = None,
    material: Material | None = None,
    law: RadialComplianceLaw | None = None,
    twist: bool = True,
    device: str = "cpu",
    clearance: float = 1.02,
    contact: str = "compliant",
    start_shape: str = "parametric",
) -> KnotScene:
    """A closed knot of any built-in type (:mod:`tightknot.knots.catalogue`) of rest length
    L0 = ``l0_over_d0`` D0 (default :func:`default_l0_over_d0`), joined with no excess twist,
    no external load: the trefoil and figure-eight are :func:`closed_trefoil` and
    :func:`closed_figure_eight`, the others the same scene from their own start curve.

    ``start_shape``: "parametric" (those start curves) or "ideal": the shipped ideal polygon
    of the type (:data:`tightknot.knots.ideal.IDEAL_KNOTS`), resampled, scaled to L0 and
    grown until the tube D0 fits as every start is (so at L0 near the ideal L/D the rod
    starts a few per cent longer than L0, already in the tight shape)."""
    l0_over_d0 = default_l0_over_d0(knot_type) if l0_over_d0 is None else l0_over_d0
    if start_shape not in START_SHAPES:
        raise ValueError(f"start_shape must be one of {', '.join(START_SHAPES)}, got "
                         f"{start_shape!r}")
    if start_shape == "ideal":
        return _closed_ideal(knot_type, l0_over_d0, diameter, nodes, material, law, twist,
                             device, clearance, contact)
    if knot_type == "3_1":
        return closed_trefoil(l0_over_d0, diameter, nodes, material, law, twist, device,
                              clearance, contact)
    if knot_type == "4_1":
        return closed_figure_eight(l0_over_d0, diameter, nodes, material, law, twist, device,
                                   clearance, contact)
    knot = builtin(knot_type)
    ratio = _check_ratio(l0_over_d0, knot_type)
    nodes = default_nodes(ratio, True) if nodes is None else nodes
    d0 = _check_common(diameter, nodes, 32)
    twist, contact = check_twist(twist), check_contact(contact, law)
    scene = _closed_knot(f"closed_{knot_type}", knot_type, knot.curve(4000), ratio, d0, nodes,
                         material, law, twist, contact, device, clearance)
    scene.rebuild = lambda n: closed_knot(knot_type, l0_over_d0, diameter, n, material, law,
                                          twist, device, clearance, contact)
    return scene


#: Start curves of a closed built-in knot (:func:`closed_knot`).
START_SHAPES = ("parametric", "ideal")


def _closed_ideal(knot_type: str, l0_over_d0: float, diameter: float, nodes: int | None,
                  material: Material | None, law: RadialComplianceLaw | None, twist: bool,
                  device: str, clearance: float, contact: str) -> KnotScene:
    """:func:`closed_knot` started from the shipped ideal polygon of ``knot_type``."""
    from tightknot.knots.ideal import load_ideal

    curve = load_ideal(knot_type)  # ValueError naming the shipped knots
    ratio = _check_ratio(l0_over_d0, knot_type)
    nodes = default_nodes(ratio, True) if nodes is None else nodes
    d0 = _check_common(diameter, nodes, 24)
    twist, contact = check_twist(twist), check_contact(contact, law)
    name = {"3_1": "closed_trefoil", "4_1": "closed_figure_eight"}.get(
        knot_type, f"closed_{knot_type}")
    scene = _closed_knot(name, knot_type, curve, ratio, d0, nodes, material, law, twist,
                         contact, device, clearance)
    scene.info["start_shape"] = "ideal"
    scene.rebuild = lambda n: _closed_ideal(knot_type, l0_over_d0, diameter, n, material, law,
                                            twist, device, clearance, contact)
    return scene


def open_knot(
    knot_type: str,
    rest_length: float | None = None,
    diameter: float = STUDY_DIAMETER,
    nodes: int | None = None,
    material: Material | None = None,
    law: RadialComplianceLaw | None = None,
    twist: bool = False,
    device: str = "cpu",
    tail_fraction: float = 0.2,
    clearance: float = 1.02,
    contact: str = "compliant",
    grip_length: float = GRIP_LENGTH,
    grip_twist: str = "free",
) -> KnotScene:
    """An open knot of any built-in type of rest length L0 (default
    :func:`default_open_length`) with straight tails along the x axis, built, held and pulled
    like :func:`open_trefoil`: the trefoil and figure-eight are :func:`open_trefoil` and
    :func:`open_figure_eight`, the others cut from their closed start curve
    (:func:`tightknot.knots.catalogue.open_curve`)."""
    rest_length = default_open_length(knot_type) if rest_length is None else rest_length
    if knot_type == "3_1":
        return open_trefoil(rest_length, diameter, nodes, material, law, twist, device,
                            tail_fraction, clearance, contact, grip_length, grip_twist)
    if knot_type == "4_1":
        return open_figure_eight(rest_length, diameter, nodes, material, law, twist, device,
                                 tail_fraction, clearance, contact, grip_length, grip_twist)
    builtin(knot_type)

    def curve_fn(n: int, size: float, tail: float) -> np.ndarray:
        return open_curve(knot_type, n, size, tail)

    # Tail corners rounded as the figure-eight's (std 2 units within 5 units of them): the
    # start curves of these knots have its size (a tube diameter of about one unit).
    scene = _open_knot(f"open_{knot_type}", knot_type, curve_fn, rest_length, diameter,
                       nodes, material, law, twist, contact, device, tail_fraction,
                       clearance, corner_std=2.0, grip_length=grip_length,
                       grip_twist=grip_twist, corner_window=5.0)
    scene.rebuild = lambda n: open_knot(knot_type, rest_length, diameter, n, material, law,
                                        twist, device, tail_fraction, clearance, contact,
                                        grip_length, grip_twist)
    return scene


def default_l0_over_d0(knot_type: str) -> float:
    """Default L0/D0 of a closed knot: the study's 16.37 for the trefoil, and for the others
    5 % above the ideal L/D (:func:`tightknot.knots.catalogue.ideal_l_over_d`, known or
    estimated), rounded up to 0.1, as the figure-eight's 22.1: reachable by a rod that
    stretches and squeezes a little, as the trefoil's does at its ideal length. The
    figure-eight keeps its scene's :data:`FIGURE_EIGHT_L0_OVER_D0` (4.997 % above the
    21.0483 measured on the shipped ideal polygon, which the rule would round to 22.2)."""
    if knot_type == "3_1":
        return 16.37
    if knot_type == "4_1":
        return FIGURE_EIGHT_L0_OVER_D0
    builtin(knot_type)
    return math.ceil(10.0 * 1.05 * ideal_l_over_d(knot_type)[0] - 1e-9) / 10.0


def default_open_length(knot_type: str, diameter: float = STUDY_DIAMETER) -> float:
    """Default rest length [m] of an open knot: the study's 185 mm for the trefoil, 0.30 m
    for the figure-eight, and for the others 1.6 times the closed knot's default L0 (the
    figure-eight's proportion: the knot plus tails that stay long while it tightens),
    rounded up to 5 mm, for a rod of ``diameter`` [m]."""
    if knot_type == "3_1":
        return 0.185
    if knot_type == "4_1":
        return 0.30
    length = 1.6 * default_l0_over_d0(knot_type) * diameter
    return math.ceil(length / 0.005 - 1e-9) * 0.005


def gauge(scene: KnotScene, positions: np.ndarray | None = None,
          sliding_end: bool = True) -> BoundaryConditions:
    """The scene's force-free gauge (module docstring) at ``positions`` (default the start):
    first vertex pinned; closed knots fix two more vertices' coordinates that a rigid
    rotation would move and the uniform twist; open knots let the last end slide along the
    pull axis (``sliding_end``; else the caller pins it), fix the z of the vertex farthest
    from the axis, and hold their grips: the vertices of the last ``grip_length`` D0 of each
    tail on the pull axis (y = z = 0, written into the state at every load step; their
    twist too when ``grip_twist`` is "clamped")."""
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
    n = model.vertex_count
    grip = scene.info.get("grip_vertices", 1)
    for v in (*range(1, grip), *range(n - grip, n - 1)):
        bcs.hold_components(0, v, (1, 2), (0.0, 0.0))
    if model.twist and scene.info.get("grip_twist") == "clamped" and grip > 1:
        for e in (*range(grip - 1), *range(n - grip, n - 1)):
            bcs.fix_twist(0, e)
    return bcs


def end_vertex(scene: KnotScene) -> int:
    """Index of the sliding (pulled) end of an open knot."""
    return scene.model.vertex_count - 1


def bending_force_scale(scene: KnotScene) -> float:
    """EI/D0^2 [N], the force scale of a knot made of this rod."""
    mat = scene.model.rods[0].material
    return mat.youngs_modulus * math.pi * scene.diameter**4 / 64.0 / scene.diameter**2


def contact_centres(scene: KnotScene, x: np.ndarray, rest: np.ndarray) -> np.ndarray:
    """The centres [m] (V, 3) of the sections the contact sees, for centerline ``x`` and
    edge rest lengths ``rest``: ``x`` itself, or a sectioned level's offset centreline
    where its sections shift in a bend
    (:meth:`tightknot.contact.sectioned.SectionedLayer.boundary_centres`). Gaps, contact
    maps and Lambda_OC measured on them see the surfaces the contact keeps apart."""
    centres = getattr(scene.contact, "boundary_centres", None)
    return x if centres is None else centres(x, rest)


def vertex_radii(scene: KnotScene, x: np.ndarray, rest: np.ndarray) -> tuple[np.ndarray, ...]:
    """Deformed edge radii r0 lam^-nu [m] (the rest radius for a rigid tube; lam the stretch
    that thins the section: the rod's mean, the edge's own, or a window mean; of the
    sections' centres, :func:`contact_centres`) and their vertex averages [m], for
    centerline ``x`` and edge rest lengths ``rest``."""
    m = scene.model
    ev = m.edge_vertex
    x = contact_centres(scene, x, rest)
    if scene.contact is not None and (scene.contact.radius_window > 0.0
                                      or scene.contact.thinning == "rod"):
        lam = scene.contact.section_stretch(x, rest)
    else:
        lam = np.linalg.norm(x[ev[:, 1]] - x[ev[:, 0]], axis=1) / rest
    rigid = scene.contact is not None and scene.contact.law.rigid
    nu = 0.0 if rigid else m.rods[0].material.poisson_ratio
    r_e = m.edge_radius * lam ** (-nu)
    r_v = np.zeros(m.vertex_count)
    cnt = np.zeros(m.vertex_count)
    np.add.at(r_v, ev.ravel(), np.repeat(r_e, 2))
    np.add.at(cnt, ev.ravel(), 1.0)
    return r_e, r_v / np.maximum(cnt, 1.0)
