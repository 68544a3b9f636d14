"""What a change of knot type was: the rod passing through itself, or an end leaving the knot.

A knot's type can change in two ways. The rod passes through itself: two pieces of it meet
on the way from one accepted iterate to the next. Or, for an open knot, an end leaves the
knot: a tail's end swings out through a loop, and the type of the curve (closed far away
along its pull axis) changes without any two pieces of rod meeting. The iterates of the
failing load step tell the two apart: the first iterate of another type is found, and the
straight path from the one before it is sampled for the closest approach of any two pieces
of rod (:class:`tightknot.rods.proximity.ProximityCheck`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from tightknot.knots.scenes import KnotScene
from tightknot.rods.proximity import ProximityCheck

#: Closest approach [D0] below which the change is taken for the rod passing through
#: itself: pieces of rod a thousandth of a diameter apart on the path of a step have met
#: (a crossing of two segments reaches zero only at one point of a sampled path).
MET_D0 = 0.02


def topology_change(scene: KnotScene, iterates: Sequence[np.ndarray], rest: np.ndarray,
                    knot_type: Callable[[KnotScene, np.ndarray], str],
                    samples: int = 32) -> str:
    """A sentence saying how the knot type changed along ``iterates`` (the accepted
    positions [m] of one load step, from its start), rest lengths ``rest`` [m]."""
    expected = scene.knot_type
    types = [knot_type(scene, x) for x in iterates]
    changed = next((k for k, t in enumerate(types) if t != expected), None)
    if changed is None or changed == 0:
        # No iterate of the load step kept the type (or none changed it): nothing to locate.
        return "the change came before this load step's first iterate"
    check = ProximityCheck(scene.model)
    a, b = iterates[changed - 1], iterates[changed]
    closest = None
    for u in np.linspace(0.0, 1.0, samples + 1):
        p = check.check(a + u * (b - a), rest)
        if closest is None or p.distance < closest[1].distance:
            closest = (u, p)
    u, p = closest
    d0 = scene.diameter
    where = f"between accepted iterates {changed} and {changed + 1} of the load step"
    if p.distance <= MET_D0 * d0:
        return (f"the rod passed through itself {where}: {p.describe(d0)} at "
                f"{u:.2f} of the way")
    if scene.closed:
        return (f"the type changed {where} although no two pieces of rod came closer than "
                f"{p.distance / d0:.3g} D0: a step crossed a pair too fast to be sampled")
    return (f"an end left the knot {where}: no two pieces of rod came closer than "
            f"{p.distance / d0:.3g} D0 on the way (a tail swung out through a loop)")
