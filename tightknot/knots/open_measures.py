"""Measures of an open knot: knot length Lambda_OC and the arc length centred on the knot.

Johanns et al. 2021 (physics.md sec. 2): Lambda_OC = (s_2 - s_1) / D0, with s_1, s_2 the arc
lengths of the first (entrance) and last (exit) contact points along the rod; open-knot arc
length s = S / D0 with s = 0 at the middle of the knot, (S_1 + S_2) / 2.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def knot_extent(contact_i: NDArray[np.int64], S: NDArray[np.float64]) -> tuple[float, float]:
    """Arc lengths (S_1, S_2) [m] of the first and last vertices in contact; NaN if none."""
    if contact_i.size == 0:
        return float("nan"), float("nan")
    return float(S[contact_i.min()]), float(S[contact_i.max()])


def open_knot_measures(
    contact_i: NDArray[np.int64], S: NDArray[np.float64], diameter: float
) -> dict[str, float | NDArray]:
    """Lambda_OC, S_1, S_2 [m] and s = (S - S_mid) / D0 from the vertices in contact.

    ``contact_i``: vertex indices taking part in a contact (either side of a pair); ``S``:
    vertex arc lengths [m] from the first end; ``diameter`` = D0 [m]. With no contact the
    knot has no extent: Lambda_OC is NaN and s is centred on the rod's middle instead.
    """
    s1, s2 = knot_extent(contact_i, S)
    if np.isnan(s1):
        mid = 0.5 * (S[0] + S[-1])
        lam = float("nan")
    else:
        mid = 0.5 * (s1 + s2)
        lam = (s2 - s1) / diameter
    return {"Lambda_OC": lam, "S1": s1, "S2": s2, "S_mid": float(mid),
            "s": (S - mid) / diameter}


def lambda_oc(x: np.ndarray, diameter: float, radii: np.ndarray | float | None = None,
              tol: float = 0.01) -> float:
    """Open-knot length Lambda_OC of centerline ``x`` (physics.md sec. 2), NaN without
    contact; contact where the distance is at most (1 + tol) times the sum of the radii
    (default D0/2; pass the deformed radii of a simulation, as the summaries do)."""
    from tightknot.knots.contact_map import contact_pairs

    r = np.full(len(x), diameter / 2) if radii is None else radii
    i, j = contact_pairs(x, False, r, tol=tol)
    s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(x, axis=0), axis=1))]
    return float(open_knot_measures(np.unique(np.r_[i, j]), s, diameter)["Lambda_OC"])
