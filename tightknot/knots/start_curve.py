"""A user's own start curve: read, checked, its knot type detected, made into a scene.

A centerline file (the reader of ``tightknot analyze``, :mod:`tightknot.knots.centerline_io`)
becomes a :class:`~tightknot.knots.scenes.KnotScene` tied as the built-in knots are
(:mod:`tightknot.knots.scenes`, module docstring): the curve, resampled to the rod's
vertices, is the start, and the rest length shrinks from the curve's own length to L0
(``tightknot.loading.tie``). The curve keeps its size and shape; it is only grown, by at
most :data:`MAX_GROW`, where its closest non-local strands are nearer than the built-in
starts' margin ``clearance`` D0 (a start in contact would begin with a squeeze the
relaxation would have to resolve first).

Its knot type is the one detected on it (Alexander polynomial, named from
:mod:`tightknot.knots.knot_table`), kept at every load step by the tie's topology checks.

Bad input is a :class:`StartCurveError` naming the file: a curve that passes closer to
itself than the rod diameter in a non-local pair (which vertices, how close), a type that
does not match the one asked for, a rest length longer than the curve.

An open curve's pull axis is the line through its ends. Its grips (the last
``grip_length`` D0 of each tail, held on the axis) must lie on that axis: the tails' offsets
from it are blended to zero over the grip and the :data:`BLEND_D0` D0 beyond it (a C1
smoothstep), the rest of the curve left as given.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from tightknot.contact.law import RadialComplianceLaw
from tightknot.knots import curves, topology
from tightknot.knots.catalogue import ideal_l_over_d
from tightknot.knots.centerline_io import (
    CLOSING_GAP_FACTOR,
    HEADER_UNITS,
    checked_points,
    read_raw,
)
from tightknot.knots.knot_table import PRIME_ALEXANDER
from tightknot.knots.scenes import (
    STUDY_MATERIAL,
    KnotScene,
    _check_common,
    _check_edge_length,
    check_contact,
    check_twist,
    contact_layer,
    contact_name,
    rotate_to_axes,
)
from tightknot.rods.builder import RodBuilder
from tightknot.rods.material import Material, check_positive
from tightknot.rods.state import State

#: Most a start curve is grown to give its strands the margin ``clearance``: 5 %, above
#: the 1 % a curve in contact reads closer than D0 by its vertex sampling (the measurements'
#: contact tolerance) plus the built-in starts' 2 % margin; a curve closer than that is
#: refused as one that intersects itself.
MAX_GROW = 1.05
#: Length [D0] beyond each grip over which an open curve's tail is blended onto its pull
#: axis (module docstring): two diameters, so the blend bends the tail gently.
BLEND_D0 = 2.0


#: A rest length up to this fraction longer than the rod's start is the curve's own length:
#: resampling the file's polygon at the rod's vertices (equal chords) and blending its
#: tails onto the axis shorten it by far less (0.02 % on a 400-vertex open figure-eight).
RESAMPLE_TOL = 0.01


class StartCurveError(ValueError):
    """A start curve that cannot be tied; the message names the file."""


@dataclass(frozen=True)
class StartCurve:
    """A start curve read from ``source``: its ``points`` [m] (N, 3), closed or open, and
    the unit its file was read in (words)."""

    source: str
    points: np.ndarray
    closed: bool
    unit: str


def units_factor(text: str | None, header: str | None, source: str) -> tuple[float, str]:
    """Metres per file unit and where it came from: ``text`` (m, cm, mm, um or a positive
    factor) when given, which must agree with the unit the file's ``header`` names; else
    the header's unit; else metres."""
    if text is None:
        if header is None:
            return 1.0, "m (no --units, no unit in the header)"
        return HEADER_UNITS[header], f"{header} (from the file's header)"
    key = text.strip()
    if key in HEADER_UNITS:
        factor = HEADER_UNITS[key]
    else:
        try:
            factor = float(key)
        except ValueError:
            raise StartCurveError(f"units {text!r}: unknown unit; use m, cm, mm, um or a "
                                  "factor (metres per file unit)") from None
        if not (math.isfinite(factor) and factor > 0):
            raise StartCurveError(f"units {text!r}: the factor must be a positive finite "
                                  "number (metres per file unit)")
    if header is not None and not math.isclose(factor, HEADER_UNITS[header], rel_tol=1e-12):
        raise StartCurveError(f"units {text}: the header of {source} gives {header}; drop "
                              "units or fix the header")
    return factor, f"{text} (units)"


def read_start_curve(path: str | os.PathLike[str], closed: bool, units: str | None = None,
                     columns: tuple[int, int, int] | tuple[str, str, str] | None = None
                     ) -> StartCurve:
    """The start curve in file ``path`` [m]: closed or open as ``closed`` says (a closed
    curve's ends must join), in ``units`` (:func:`units_factor`), ``columns`` as
    :func:`tightknot.knots.centerline_io.parse_columns` gives them. Unreadable or bad
    data: :class:`~tightknot.knots.centerline_io.CenterlineError` (a ValueError) naming the
    file and line."""
    raw = read_raw(path, columns)
    if raw.closed is not None and raw.closed != closed:
        raise StartCurveError(f"{path}: the file holds {'a closed' if raw.closed else 'an open'}"
                              f" polyline, the knot is {'closed' if closed else 'open'}")
    factor, unit = units_factor(units, raw.unit, str(path))
    if not closed:
        pts = checked_points(raw, str(path), factor, False)
        gap = float(np.linalg.norm(pts[-1] - pts[0]))
        if gap <= CLOSING_GAP_FACTOR * float(np.linalg.norm(np.diff(pts, axis=0), axis=1).mean()):
            raise StartCurveError(f"{path}: the curve's ends join (it looks closed): tie it "
                                  "as a closed knot")
        return StartCurve(str(path), pts, False, unit)
    return StartCurve(str(path), checked_points(raw, str(path), factor, closed), closed, unit)


def detect_knot_type(curve: StartCurve) -> str:
    """The knot type of the start curve (a name of :mod:`tightknot.knots.knot_table`)."""
    return topology.curve_knot_type(curve.points, curve.closed)


def check_knot_type(curve: StartCurve, detected: str, expected: str | None) -> None:
    """StartCurveError naming the file when ``expected`` (a name asked for) is not among the
    ``detected`` type's candidates (``"8_20|3_1#3_1"`` matches ``8_20``)."""
    if expected is not None and expected != detected and expected not in detected.split("|"):
        raise StartCurveError(f"{curve.source}: the curve is a {detected} knot, not the "
                              f"{expected} asked for (Alexander polynomial)")


def nearest_vertex(points: np.ndarray, closed: bool, s: float) -> int:
    """Index of the vertex of ``points`` nearest arc length ``s`` [m]."""
    arc = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))]
    if closed:
        total = arc[-1] + float(np.linalg.norm(points[0] - points[-1]))
        gap = np.abs(arc - s)
        return int(np.argmin(np.minimum(gap, total - gap)))
    return int(np.argmin(np.abs(arc - s)))


def closest_pair(points: np.ndarray, closed: bool, d0: float) -> tuple[float, int, int]:
    """(distance [m], vertex, vertex) of the curve's closest non-local pair: points more
    than pi D0/2 apart along it (:func:`tightknot.knots.curves.exclusion_arc_length`);
    (inf, -1, -1) when none is."""
    d, sa, sb = curves.min_nonlocal_distance(points, closed, curves.exclusion_arc_length(d0))
    if not math.isfinite(d):
        return d, -1, -1
    return d, nearest_vertex(points, closed, sa), nearest_vertex(points, closed, sb)


def check_no_intersection(curve: StartCurve, d0: float) -> float:
    """The factor (>= 1) that grows the curve until its closest non-local strands are
    ``clearance`` D0 apart; StartCurveError naming the file and the two vertices when it
    would take more than :data:`MAX_GROW` (the tube of diameter D0 on it intersects
    itself)."""
    d, i, j = closest_pair(curve.points, curve.closed, d0)
    if not math.isfinite(d):
        return 1.0
    if d * MAX_GROW < CLEARANCE * d0:
        raise StartCurveError(
            f"{curve.source}: the curve intersects itself: vertices {i} and {j} (0-based, "
            f"file order) are {d / d0:.3g} D0 apart, closer than the rod diameter D0 = "
            f"{d0:.4g} m (check the units and the diameter)")
    return max(1.0, CLEARANCE * d0 / d)


#: Margin of the start's closest strands over D0, the built-in starts' (tightknot.knots.
#: scenes: clearance 1.02).
CLEARANCE = 1.02


def curve_length(points: np.ndarray, closed: bool) -> float:
    """Length [m] of the polygon."""
    e = np.diff(np.vstack([points, points[:1]]) if closed else points, axis=0)
    return float(np.linalg.norm(e, axis=1).sum())


def default_rest_length(curve: StartCurve, knot_type: str, d0: float) -> float:
    """Default rest length L0 [m] of a start curve: an open one its own length (the pull
    tightens it); a closed one 5 % above its type's ideal L/D (known or estimated from the
    crossing number, :func:`tightknot.knots.catalogue.ideal_l_over_d`; the largest of
    several candidates), rounded up to 0.1 D0, as the built-in knots, unless the curve is
    shorter (then its own length). StartCurveError when the type has no crossing number."""
    length = curve_length(curve.points, curve.closed) * check_no_intersection(curve, d0)
    if not curve.closed:
        return length
    names = knot_type.split("|")
    if not all(_table_name(n) for n in names):
        raise StartCurveError(f"{curve.source}: a {knot_type} knot has no ideal length to "
                              "default to; give l0_over_d0")
    ideal = max(ideal_l_over_d(n)[0] for n in names)
    ratio = math.ceil(10.0 * 1.05 * ideal - 1e-9) / 10.0
    return min(ratio * d0, length)


def _table_name(name: str) -> bool:
    return all(part in PRIME_ALEXANDER for part in name.split("#")) and name != "0_1"


def is_knot_name(name: str) -> bool:
    """Whether ``name`` is a knot type the topology can name: table knots joined by "|",
    sums by "#", or "unknown(det=D)"."""
    if name.startswith("unknown(det=") and name.endswith(")"):
        return name[len("unknown(det="):-1].isdigit()
    return all(all(p in PRIME_ALEXANDER for p in n.split("#")) for n in name.split("|"))


def _prepare(curve: StartCurve, d0: float, rest_length: float, nodes: int
             ) -> tuple[np.ndarray, float]:
    """The rod's start vertices [m] from the curve and its length over L0."""
    grow = check_no_intersection(curve, d0)
    pts = curve.points
    if curve.closed:
        pts = curves.resample_uniform(pts, nodes, closed=True)
    else:
        # Equal chords: a uniform rod, as the built-in open knots (tie.recentre_open_knot).
        pts = curves.resample_equal_chords(pts, nodes)
    pts = pts * grow
    length = curve_length(pts, curve.closed)
    if rest_length > length * (1.0 + RESAMPLE_TOL):
        what = "l0_over_d0" if curve.closed else "length"
        value = f"{rest_length / d0:.4g} D0" if curve.closed else f"{rest_length:.4g} m"
        limit = f"{length / d0:.4g} D0" if curve.closed else f"{length:.4g} m"
        raise StartCurveError(f"{curve.source}: {what} {value} is longer than the start "
                              f"curve ({limit}): the rest length shrinks from the curve's "
                              "length to L0")
    # Within RESAMPLE_TOL of the curve's length, the rest length grows that little to L0.
    return pts, length / rest_length


def closed_from_curve(curve: StartCurve, knot_type: str, l0_over_d0: float,
                      diameter: float, nodes: int, material: Material | None = None,
                      law: RadialComplianceLaw | None = None, twist: bool = True,
                      device: str = "cpu", contact: str = "compliant") -> KnotScene:
    """A closed knot tied from the user's closed ``curve`` [m] of type ``knot_type`` (as
    detected) to L0 = ``l0_over_d0`` D0, joined with no excess twist (module docstring)."""
    if not curve.closed:
        raise StartCurveError(f"{curve.source}: an open curve cannot make a closed knot")
    d0 = _check_common(diameter, nodes, 24)
    ratio = check_positive("l0_over_d0", l0_over_d0, "")
    twist, contact = check_twist(twist), check_contact(contact, law)
    pts, start_ratio = _prepare(curve, d0, ratio * d0, int(nodes))
    n = pts.shape[0]
    pts = rotate_to_axes(pts, 0, n // 3, 2 * n // 3)
    _check_edge_length(pts, True, d0, nodes, contact)
    b = RodBuilder(twist=twist)
    b.add_rod(pts, d0, material or STUDY_MATERIAL, closed=True)
    model = b.finalize(device)
    scene = KnotScene("closed_start", model, State.initial(model),
                      contact_layer(model, contact, law), d0, ratio * d0, True, start_ratio,
                      None, knot_type=knot_type,
                      info={"l0_over_d0": ratio, "start": start_info(curve, start_ratio, d0),
                            "model": {"twist": twist, "contact": contact_name(contact)}})
    scene.rebuild = lambda k: closed_from_curve(curve, knot_type, l0_over_d0, diameter, k,
                                                material, law, twist, device, contact)
    return scene


def open_from_curve(curve: StartCurve, knot_type: str, rest_length: float, diameter: float,
                    nodes: int, material: Material | None = None,
                    law: RadialComplianceLaw | None = None, twist: bool = False,
                    device: str = "cpu", contact: str = "compliant",
                    grip_length: float = 1.0, grip_twist: str = "free") -> KnotScene:
    """An open knot tied from the user's open ``curve`` [m] of type ``knot_type``, rest
    length ``rest_length`` [m], its pull axis the line through its ends (x after the
    gauge's rotation), held and pulled as the built-in open knots
    (:func:`tightknot.knots.scenes.open_trefoil`; module docstring for the grips)."""
    if curve.closed:
        raise StartCurveError(f"{curve.source}: a closed curve cannot make an open knot")
    d0 = _check_common(diameter, nodes, 40)
    l0 = check_positive("length", rest_length, "m")
    twist, contact = check_twist(twist), check_contact(contact, law)
    if not (math.isfinite(grip_length) and 0.0 <= grip_length <= 0.25 * l0 / d0):
        raise StartCurveError(f"grip_length must be in [0, {0.25 * l0 / d0:.3g}] D0 (a "
                              f"quarter of the rod), got {grip_length!r}")
    raw = curve.points
    axis = raw[-1] - raw[0]
    if np.linalg.norm(axis) < d0:
        raise StartCurveError(f"{curve.source}: the open curve's ends are less than a rod "
                              "diameter apart: no pull axis")
    axis /= np.linalg.norm(axis)
    # The grips onto the axis first: the rod is then resampled at equal chords.
    held = StartCurve(curve.source, _blend_onto_axis(raw, axis, (grip_length + BLEND_D0) * d0,
                                                     grip_length * d0), False, curve.unit)
    pts, start_ratio = _prepare(held, d0, l0, int(nodes))
    n = pts.shape[0]
    rel = pts - pts[0]
    radial = np.linalg.norm(rel - np.outer(rel @ axis, axis), axis=1)
    far = int(np.argmax(radial))
    pts = rotate_to_axes(pts, 0, n - 1, far)
    _check_edge_length(pts, False, d0, nodes, contact)
    b = RodBuilder(twist=twist)
    b.add_rod(pts, d0, material or STUDY_MATERIAL, closed=False)
    model = b.finalize(device)
    grip = 1 + int(math.floor(grip_length * d0 * (n - 1) / l0 + 1e-9))
    scene = KnotScene("open_start", model, State.initial(model),
                      contact_layer(model, contact, law), d0, l0, False, start_ratio,
                      np.array([1.0, 0.0, 0.0]), knot_type=knot_type,
                      info={"gauge_vertex": far, "grip_length": float(grip_length),
                            "grip_vertices": grip, "grip_twist": grip_twist,
                            "start": start_info(held, start_ratio, d0),
                            "model": {"twist": twist, "contact": contact_name(contact)}})
    scene.rebuild = lambda k: open_from_curve(curve, knot_type, rest_length, diameter, k,
                                              material, law, twist, device, contact,
                                              grip_length, grip_twist)
    return scene


def _blend_onto_axis(pts: np.ndarray, axis: np.ndarray, window: float, held: float
                     ) -> np.ndarray:
    """``pts`` with each tail's offset from the line through the ends scaled to zero within
    ``held`` [m] of arc length of its end and back to one at ``window`` (C1 smoothstep)."""
    arc = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))]
    depth = np.minimum(arc, arc[-1] - arc)
    u = np.clip((depth - held) / max(window - held, 1e-300), 0.0, 1.0)
    w = (u * u * (3.0 - 2.0 * u))[:, None]
    rel = pts - pts[0]
    on_axis = pts[0] + np.outer(rel @ axis, axis)
    return on_axis + w * (pts - on_axis)


def start_info(curve: StartCurve, start_ratio: float, d0: float) -> dict:
    """What a scene records of its start curve (JSON-ready)."""
    return {"file": curve.source, "units": curve.unit, "closed": curve.closed,
            "vertices_in_file": int(curve.points.shape[0]),
            "length_over_D0": curve_length(curve.points, curve.closed) / d0,
            "grown_by": check_no_intersection(curve, d0),
            "start_length_over_L0": start_ratio}
