"""Keeping an open knot centred on its rod: the material slides through the knot.

A frictionless knot on a uniform rod can sit anywhere along it; its place is a zero mode of
the energy that Newton steps drift along with whatever asymmetry round-off brings, and the
short tails of the study's 185 mm knot leave no room for that drift. :func:`recentre_system`
slides the material by whole edges, an exact symmetry of the energy on the open scenes'
equal edges, so that the knot sits mid-rod.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from tightknot.contact.layer import SelfIntersectionError
from tightknot.knots import topology
from tightknot.knots.scenes import KnotScene
from tightknot.rods.state import State
from tightknot.solvers.system import RodSystem

#: A vertex belongs to the knot when a non-local one is within (1 + this) of the nominal
#: diameter (a margin of 5 % finds the loose knots' strands too).
KNOT_EXTENT_TOL = 0.05


def recentre_open_knot(scene: KnotScene, x: np.ndarray, rest: np.ndarray,
                       tol: float = KNOT_EXTENT_TOL) -> tuple[np.ndarray, int]:
    """Slide an open knot's material along the rod by whole edges so that the knot sits
    mid-rod.

    A frictionless knot on a uniform rod can sit anywhere along it: moving the rod's
    material through the knot changes no energy while the tails are straight, so the
    knot's position is a zero mode that Newton steps drift along with whatever asymmetry
    round-off brings (docs/design_notes.md, re-centring). The study's
    knots sit mid-rod, so tie() puts them there. The knot's extent is the span of vertices
    in contact (within ``tol`` of the nominal diameter); the material moves by the whole
    number of edges k nearest to the rest arc between the knot's centre and the rod's
    (``slide_material``: vertex i takes the place of vertex i - k, no interpolation, so
    the knot's shape is kept exactly; an interpolated slide cuts the polyline's corners and
    jammed a tight pull). Returns the new positions [m] and k (0: nothing moved).
    """
    k = _knot_offset(scene, x, rest, tol)
    return (x, 0) if k == 0 else (slide_material(x, k), k)


def _knot_offset(scene: KnotScene, x: np.ndarray, rest: np.ndarray, tol: float) -> int:
    """Whole edges k that bring the knot's centre (middle of the span of vertices in
    contact within ``tol``) to the rod's middle; 0 without contact."""
    from tightknot.knots.contact_map import contact_pairs

    i, j = contact_pairs(x, False, np.full(len(x), scene.diameter / 2.0), tol=tol)
    if not len(i):
        return 0
    idx = np.r_[i, j]
    arc = np.r_[0.0, np.cumsum(rest)]
    delta = 0.5 * arc[-1] - 0.5 * (arc[idx.min()] + arc[idx.max()])
    return int(round(delta / float(np.mean(rest))))


def slide_material(x: np.ndarray, k: int) -> np.ndarray:
    """Open centerline ``x`` [m] with its material moved by ``k`` edges along itself:
    vertex i takes the place of vertex i - k (k > 0: toward the last end). The tail the
    material leaves is extended straight along its end edge, the other is cut, and the
    whole is translated so that the first vertex stays where it was. On a rod of equal
    edges (the open scenes', ``curves.resample_equal_chords``) with straight tails this is
    an exact symmetry of the energy; where edges differ, each takes the strain of the
    length of the place it moves to."""
    n = len(x)
    if not (isinstance(k, (int, np.integer)) and abs(k) < n - 1):
        raise ValueError(f"k must be a whole number with |k| < {n - 1}, got {k!r}")
    if k == 0:
        return x.copy()
    y = np.empty_like(x)
    if k > 0:
        y[k:] = x[:n - k]
        y[:k] = x[0] + (x[0] - x[1]) * np.arange(k, 0, -1)[:, None]
    else:
        m = -k
        y[:n - m] = x[m:]
        y[n - m:] = x[-1] + (x[-1] - x[-2]) * np.arange(1, m + 1)[:, None]
    return y + (x[0] - y[0])


def recentre_system(scene: KnotScene, system: RodSystem
                    ) -> tuple[int, Callable[[np.ndarray], np.ndarray] | None]:
    """Centre an open knot on its rod (``recentre_open_knot``) in place, keeping the
    scene's gauge: the first vertex where it is, the last on the pull axis (e_x through
    the first vertex) and the gauge vertex's z, which a rotation about the pull axis (a
    zero mode as well) restores; a rotation that cannot (the new gauge vertex nearer the
    axis than that z) leaves the knot where it is. A rod with twist keeps its place (its
    twist field would have to slide with it).

    Returns the slide k [edges] and the map that applies the same slide and rotation to
    other positions of the rod (e.g. an earlier equilibrium a predictor extrapolates
    from), or (0, None) when nothing moved."""
    if scene.closed or scene.model.twist or scene.pull_axis is None:
        return 0, None
    if not np.allclose(scene.pull_axis, (1.0, 0.0, 0.0)):
        return 0, None
    x = system.state.x
    k = _knot_offset(scene, x, system.rest, KNOT_EXTENT_TOL)
    if k == 0:
        return 0, None
    y0 = slide_material(x, k)
    g = scene.info["gauge_vertex"]
    p = y0[g] - y0[0]
    zt = x[g, 2] - x[0, 2]
    r = math.hypot(p[1], p[2])
    if r <= abs(zt):
        return 0, None
    beta = math.atan2(p[2], p[1])
    a = math.asin(zt / r)
    # the smaller of the two rotations that put the gauge vertex back at its z
    phi = min((a - beta, math.pi - a - beta),
              key=lambda v: abs(math.remainder(v, 2.0 * math.pi)))
    c, s_ = math.cos(phi), math.sin(phi)

    def turn(w: np.ndarray, z: np.ndarray) -> np.ndarray:
        # slid positions w of z, rotated about the pull axis through their first vertex
        q = w - w[0]
        w[:, 1] = w[0, 1] + c * q[:, 1] - s_ * q[:, 2]
        w[:, 2] = w[0, 2] + s_ * q[:, 1] + c * q[:, 2]
        # The end stays on the pull axis where the gauge holds it (the slid tail is
        # straight to round-off and ~1e-7 m of the tail's own sag: an end pinned at a
        # given end-to-end distance must keep it exactly).
        w[-1, 1:] = z[-1, 1:]
        return w

    def transform(z: np.ndarray) -> np.ndarray:
        return turn(slide_material(z, k), z)

    y = turn(y0, x)
    # The slide must not create what the run would fail on: a tail that is not straight
    # (a knot slipping off an end curls it) is extended along its end edge, which can run
    # it into other strands. Such a slide is not made.
    if scene.contact is not None:
        try:
            scene.contact.check_no_intersection(y)
        except SelfIntersectionError:
            return 0, None
    # (every caller slides an accepted state, whose type is the scene's)
    if topology.curve_knot_type(y, scene.closed) != scene.knot_type:
        return 0, None
    old = system.state
    system.state = State.initial(scene.model, positions=y)
    if old.extra.size:
        # The sectioned level's sections slide and turn with the material.
        turn_matrix = np.array([[1.0, 0.0, 0.0], [0.0, c, -s_], [0.0, s_, c]])
        system.state.extra = system.dof_term.slid_sections(
            old.extra, (old.t_ref, old.d1_ref), (system.state.t_ref, system.state.d1_ref), k,
            turn_matrix)
    return k, transform
