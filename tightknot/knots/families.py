"""Parametric curves of knot families: torus knots T(p, q) and twist knots.

Closed curves of ``n`` vertices (the first not repeated), in knot-size units (any length
unit; the scenes scale them to the rod). They are loose start shapes, not tight ones.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from tightknot.knots._arclength import resample_uniform
from tightknot.knots.smoothing import gaussian_smooth_points


def torus_knot(p: int, q: int, n: int = 800, size: float = 1.0) -> NDArray[np.float64]:
    """Torus knot T(p, q) on the torus of radii 2 and 1: it winds p times about the z axis
    and q times about the torus' core, x = (2 + cos qt) cos pt, y = (2 + cos qt) sin pt,
    z = -sin qt, times ``size``. A knot for coprime p, q >= 2 (T(p, q) = T(q, p)); with
    p < q its projection on the x-y plane has q (p - 1) crossings, the crossing number
    (Murasugi 1991): T(2, 3) = 3_1, T(2, 5) = 5_1, T(2, 7) = 7_1, T(3, 4) = 8_19."""
    if math.gcd(p, q) != 1 or min(p, q) < 1:
        raise ValueError(f"a torus knot needs coprime p, q >= 1, got T({p}, {q})")
    t = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    r = 2.0 + np.cos(q * t)
    return size * np.stack([r * np.cos(p * t), r * np.sin(p * t), -np.sin(q * t)], axis=1)


def twist_knot(half_twists: int, n: int = 2000, size: float = 1.0) -> NDArray[np.float64]:
    """Twist knot with ``half_twists`` = h >= 1 half-twists, times ``size``: h = 1 is 3_1,
    2 is 4_1, 3 is 5_2, 4 is 6_1, 5 is 7_2, 6 is 8_1 (Rolfsen 1976, the twist knots).

    Built as a twist knot is defined: a closed loop twisted about itself, its ends then
    hooked together (a clasp). Two strands of radius 0.8 about the x axis turn by pi per
    1.2 units of x; at x < 0 a cap joins them, at the far end they form a hook that runs
    back above the twisted pair and hooks through the cap. With a clasp of fixed sign, an
    even number 2k of half-turns of one sense gives the twist knot of 2k half-twists and
    2k of the other sense the one of 2k - 1 (an odd twist knot's clasp, read with the
    opposite crossing sense), so the curve always turns by a whole number of turns and its
    two strands end where they started. The control polygon is smoothed by a Gaussian
    average of std 0.8 units: the corners then bend no tighter than the strands' spacing
    (bend radius 0.58, strands 0.96 apart), so neither sets the tube alone.
    """
    if isinstance(half_twists, bool) or not isinstance(half_twists, int | np.integer) or (
            half_twists < 1):
        raise ValueError(f"half_twists must be a whole number >= 1, got {half_twists!r}")
    turns = half_twists if half_twists % 2 == 0 else -(half_twists + 1)
    a, w, xc = 0.8, 1.2, 1.0  # strand radius, length per half-turn, cap centre at x = -xc
    width = abs(turns) * w
    x = np.linspace(0.0, width, 40 * abs(turns) + 1)
    phase = np.sign(turns) * np.pi * x / w
    strand_a = np.stack([x, a * np.cos(phase), a * np.sin(phase)], axis=1)
    strand_b = np.stack([x, -a * np.cos(phase), -a * np.sin(phase)], axis=1)
    # The cap: the arc of the circle through both strands' starts centred at (-xc, 0, 0).
    rc = math.hypot(xc, a)
    phi0 = math.atan2(a, xc)
    phi = np.linspace(-phi0, -2.0 * math.pi + phi0, 60)[1:-1]
    cap = np.stack([-xc + rc * np.cos(phi), rc * np.sin(phi), 0.0 * phi], axis=1)
    # The hook: out of the twisted pair's end, up to z = top, back above it to the cap,
    # down through the cap's loop (x = -xc), under the cap, up outside it, and back along
    # the other side (y < 0) to the other strand.
    hole, top, bottom, out = -xc, 2.4, -1.4, -xc - rc - 1.3
    hook = np.array([
        [width + 1.0, 0.6 * a, 0.6], [width + 1.3, 0.8, 1.6], [width + 0.6, 0.8, top],
        [hole + 0.6, 0.5, top], [hole, 0.0, top - 0.8], [hole, 0.0, 0.0],
        [hole, 0.0, bottom + 0.5], [hole - 0.5, 0.0, bottom], [out + 0.5, 0.0, bottom],
        [out, 0.0, bottom + 0.5], [out, 0.0, top - 0.8], [out + 0.5, -0.6, top],
        [width + 0.6, -0.8, top], [width + 1.3, -0.8, 1.6], [width + 1.0, -0.6 * a, 0.6]])
    poly = np.vstack([strand_a, hook, strand_b[::-1], cap])
    dense = resample_uniform(poly, 4 * n, closed=True)
    length = float(np.linalg.norm(np.roll(dense, -1, axis=0) - dense, axis=1).sum())
    smooth = gaussian_smooth_points(dense, closed=True, std_points=0.8 / length * 4 * n)
    return size * resample_uniform(smooth, n, closed=True)
