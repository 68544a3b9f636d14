"""Parametric curves of knot families: torus knots T(p, q) and twist knots.

Closed curves of ``n`` vertices (the first not repeated), in knot-size units (any length
unit; the scenes scale them to the rod). They are loose start shapes, not tight ones.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray


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
