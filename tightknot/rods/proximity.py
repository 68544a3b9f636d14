"""An independent check that no two pieces of rod pass through each other.

The contact layer keeps rods apart by its energy and bounds every Newton step so that no
pair it watches comes closer than its hard limit. This check does not trust it: after every
accepted iterate it measures the segment distance of *every* pair of edges that share no
vertex (through a uniform grid of cells, in its own code), and reports the closest pair
against a floor, so that a pair any part of the contact model skips is named the moment it
comes too close, not found later as a changed knot type. Only two rods that stand for one
body's mirror images (``Model.mirror_rod_pairs``, a FEM scene's stack) are not material to
each other and not checked.

Floor of a pair of edges of one rod whose nearest ends are an arc length s apart (rest
lengths): ``min(hard, local * D sin(min(s / D, pi / 2)))``; D sin(s/D) is the chord between
two points an arc s apart on the tightest bend a tube of diameter D allows (radius D/2), so
a legal bend keeps every pair above ``local`` times it. Pairs of different rods, or farther
apart along the rod than pi D / 2, have the floor ``hard``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from tightknot.rods.model import Model

#: Default floor of distant pairs over the pair's larger rest diameter, and of near pairs
#: over the chord of the tightest legal bend (module docstring): nine tenths of the contact
#: layer's step-bound floors (0.05, 0.25), so that a step the bound allows never fails the
#: check by round-off, while a pair the bound does not see fails it before it meets.
HARD_FRACTION = 0.045
LOCAL_FRACTION = 0.225


@dataclass(frozen=True)
class Proximity:
    """The closest pair of a state relative to its floor.

    Attributes:
        ratio: distance over floor of the closest pair (inf when no pair is near) [-].
        edges: the pair's edge indices (-1, -1 when none).
        distance: its segment distance [m].
        floor: its floor [m].
        separation: rest arc length between the pair's nearest edge ends along the rod
            (inf for edges of different rods) [m].
    """

    ratio: float
    edges: tuple[int, int]
    distance: float
    floor: float
    separation: float

    @property
    def violated(self) -> bool:
        """The closest pair is below its floor."""
        return self.ratio < 1.0

    def describe(self, diameter: float) -> str:
        """One line naming the pair, in diameters ``diameter`` [m]."""
        a, b = self.edges
        sep = ("on different rods" if not math.isfinite(self.separation) else
               f"{self.separation / diameter:.3g} D0 apart along the rod")
        return (f"edges {a} and {b} ({sep}) are {self.distance / diameter:.3g} D0 apart "
                f"(floor {self.floor / diameter:.3g} D0)")


@numba.njit(cache=True)
def _segment_distance(p0, p1, q0, q1):
    # Closest points of two segments (Ericson 2005, sec. 5.1.9), the degenerate cases
    # included.
    d1 = p1 - p0
    d2 = q1 - q0
    r = p0 - q0
    a = d1 @ d1
    e = d2 @ d2
    f = d2 @ r
    tiny = 1e-30
    if a <= tiny and e <= tiny:
        s, t = 0.0, 0.0
    elif a <= tiny:
        s = 0.0
        t = min(max(f / e, 0.0), 1.0)
    else:
        c = d1 @ r
        if e <= tiny:
            t = 0.0
            s = min(max(-c / a, 0.0), 1.0)
        else:
            b = d1 @ d2
            denom = a * e - b * b
            s = min(max((b * f - c * e) / denom, 0.0), 1.0) if denom > 1e-14 * a * e else 0.0
            t = (b * s + f) / e
            if t < 0.0:
                t = 0.0
                s = min(max(-c / a, 0.0), 1.0)
            elif t > 1.0:
                t = 1.0
                s = min(max((b - c) / a, 0.0), 1.0)
    dv = (p0 + s * d1) - (q0 + t * d2)
    return math.sqrt(dv @ dv)


@numba.njit(cache=True)
def _closest(x, ev, rod, closed, rod_len, arc0, arc1, diam, cell, hard, local, mirror):
    ne = ev.shape[0]
    mid = np.empty((ne, 3))
    for j in range(ne):
        mid[j] = 0.5 * (x[ev[j, 0]] + x[ev[j, 1]])
    lo = np.empty(3)
    key = np.empty(ne, dtype=np.int64)
    ijk = np.empty((ne, 3), dtype=np.int64)
    dims = np.empty(3, dtype=np.int64)
    for d in range(3):
        lo[d] = mid[:, d].min()
        dims[d] = int((mid[:, d].max() - lo[d]) / cell) + 3
    for j in range(ne):
        for d in range(3):
            ijk[j, d] = int((mid[j, d] - lo[d]) / cell) + 1
        key[j] = (ijk[j, 0] * dims[1] + ijk[j, 1]) * dims[2] + ijk[j, 2]
    order = np.argsort(key)
    skey = key[order]
    best = (np.inf, -1, -1, 0.0, 0.0, 0.0)
    for a in range(ne):
        for di in range(-1, 2):
            for dj in range(-1, 2):
                for dk in range(-1, 2):
                    k = ((ijk[a, 0] + di) * dims[1] + ijk[a, 1] + dj) * dims[2] + ijk[a, 2] + dk
                    i0 = np.searchsorted(skey, k)
                    i1 = np.searchsorted(skey, k + 1)
                    for ii in range(i0, i1):
                        b = order[ii]
                        if b <= a:
                            continue
                        va0, va1, vb0, vb1 = ev[a, 0], ev[a, 1], ev[b, 0], ev[b, 1]
                        if va0 == vb0 or va0 == vb1 or va1 == vb0 or va1 == vb1:
                            continue
                        if mirror[rod[a], rod[b]]:
                            continue  # mirror images of one body (Model.mirror_rod_pairs)
                        big = max(diam[a], diam[b])
                        floor = hard * big
                        sep = np.inf
                        if rod[a] == rod[b]:
                            # Rest arc between the edges' nearest ends: forward from a's end
                            # to b's start (a < b on one rod), or around a closed rod.
                            sep = abs(arc0[b] - arc1[a])
                            if closed[rod[a]]:
                                sep = min(sep, rod_len[rod[a]] - abs(arc1[b] - arc0[a]))
                            arg = min(sep / big, 0.5 * math.pi)
                            floor = min(floor, local * big * math.sin(arg))
                        dist = _segment_distance(x[va0], x[va1], x[vb0], x[vb1])
                        ratio = dist / floor if floor > 0.0 else np.inf
                        if ratio < best[0]:
                            best = (ratio, a, b, dist, floor, sep)
    return best


class ProximityCheck:
    """The check of the module docstring for the rods of ``model``.

    Args:
        model: the rods.
        hard_fraction: floor of distant pairs over the pair's larger rest diameter.
        local_fraction: floor of near pairs over the tightest legal bend's chord.
    """

    def __init__(self, model: Model, hard_fraction: float = HARD_FRACTION,
                 local_fraction: float = LOCAL_FRACTION) -> None:
        for name, v in (("hard_fraction", hard_fraction), ("local_fraction", local_fraction)):
            if not (math.isfinite(v) and 0.0 < v < 1.0):
                raise ValueError(f"{name} must be in (0, 1), got {v!r}")
        self.model = model
        self.hard_fraction = float(hard_fraction)
        self.local_fraction = float(local_fraction)
        self._ev = model.edge_vertex.astype(np.int64)
        self._rod = model.edge_rod.astype(np.int64)
        self._closed = np.array([r.closed for r in model.rods], dtype=np.bool_)
        self._diam = 2.0 * model.edge_radius.astype(np.float64)
        self._mirror = model.mirror_matrix()

    def check(self, x: np.ndarray, rest: np.ndarray) -> Proximity:
        """The closest pair of positions ``x`` [m] relative to its floor, with edge rest
        lengths ``rest`` [m] (they set the arc separations)."""
        m = self.model
        if m.edge_count < 2:
            return Proximity(math.inf, (-1, -1), math.inf, 0.0, math.inf)
        arc0 = np.empty(m.edge_count)
        arc1 = np.empty(m.edge_count)
        lengths = np.empty(len(m.rods))
        for r, info in enumerate(m.rods):
            le = rest[info.edge_slice]
            s1 = np.cumsum(le)
            arc0[info.edge_slice] = s1 - le
            arc1[info.edge_slice] = s1
            lengths[r] = s1[-1]
        e = np.linalg.norm(x[self._ev[:, 1]] - x[self._ev[:, 0]], axis=1)
        # Two edges within a floor of each other have midpoints within a cell of each
        # other: half of each edge plus the floor (the largest floor is hard * D).
        cell = float(e.max() + self.hard_fraction * self._diam.max())
        ratio, a, b, dist, floor, sep = _closest(
            np.ascontiguousarray(x, dtype=np.float64), self._ev, self._rod, self._closed,
            lengths, arc0, arc1, self._diam, cell, self.hard_fraction, self.local_fraction,
            self._mirror)
        return Proximity(float(ratio), (int(a), int(b)), float(dist), float(floor),
                         float(sep))
