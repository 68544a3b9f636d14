"""Two-rod tangles: parametric start curves of the clasp and the four bends, and the
invariants that tell them apart.

Construction (documented in docs/tangles.md). Every tangle here is a four-ended tangle of
two rods, rod A with both ends pulled toward -x and rod B with both ends toward +x, built
as the sum of two twist regions in the sense of Conway's rational tangles: the upper side
(y > 0) holds A's upper leg and B's upper leg twisted about each other by ``n_upper`` half
turns, the lower side (y < 0) A's and B's lower legs by ``n_lower`` half turns; A's legs
are joined by a U-turn at +x, B's by one at -x. Closing each rod on its own (its two ends
joined far away in its pull direction) gives the pretzel link P(n_upper, n_lower), a
two-strand pretzel, i.e. the torus link T(2, n_upper + n_lower): its linking number is
(n_upper + n_lower)/2 up to the orientation's sign.

* clasp: one half turn on each side of the same hand, P(1, 1) = the Hopf link (lk = +-1):
  two U-shaped rods hooked (Grandgeorge et al., PNAS 118 (2021) e2021684118).
* granny: three half turns on each side of the same hand, P(3, 3) = T(2, 6) (lk = +-3);
  joining the working ends to each other and the standing ends to each other (the
  parcel closure) gives the granny knot 3_1 # 3_1.
* reef (square): three half turns of opposite hands, P(3, -3) = the unlink (lk = 0);
  the parcel closure gives the square knot 3_1 # 3_1*.
* thief and grief: the reef's and the granny's tangle with the working ends on opposite
  sides (as Patil et al., Science 367 (2020) 71, tie them; an assumption of this
  construction, not checked against a table of tangles). The
  four-end pull loads all four ends, so the working ends are only labels there: a thief
  and a reef (a grief and a granny) are the same tangle, and no invariant of the tangle
  separates them. Only the labels do: the parcel closure joins A's working end to B's
  working end, which for diagonal ends needs two closing arcs that pass each other, one
  above and one below the tangle (:func:`parcel_closure`'s convention). With it the thief
  closes to 6_1 (either way round) and the grief to 3_1 (7_4 the other way round), where
  the reef and the granny both close to a composite of Alexander polynomial
  (t^2 - t + 1)^2, chirality blind, which the square knot 3_1 # 3_1* and the granny knot
  3_1 # 3_1 (and 8_20) share.

So the invariants of the tangle (the linking number of the per-rod closure, each rod's own
knot type) separate {reef, thief} from {granny, grief} from the clasp; the parcel closure
of the labelled tangle also separates the thief from the reef and the grief from the
granny; its Alexander polynomial does not separate the reef from the granny, their linking
numbers do (:data:`CANDIDATES`: the kinds the tangle's own invariants leave).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from tightknot.knots import topology

#: Bend kinds and their twist regions (n_upper, n_lower, hand_upper, hand_lower) and the
#: working ends ("same": both on the upper side; "diagonal": A's upper, B's lower). A hand
#: is the sign of z in a side's helices (:func:`_side`); the lower side is the upper one
#: mirrored in y, so equal hands make helices of opposite handedness: P(3, -3), the reef
#: (the computed linking number, 0, confirms which is which).
BENDS: dict[str, tuple[int, int, int, int, str]] = {
    "reef": (3, 3, 1, 1, "same"),
    "thief": (3, 3, 1, 1, "diagonal"),
    "granny": (3, 3, 1, -1, "same"),
    "grief": (3, 3, 1, -1, "diagonal"),
}
#: The clasp's twist regions (module docstring).
CLASP = (1, 1, 1, -1, "same")

#: Expected invariants of each tangle (module docstring: the pretzel links P(n1, n2) and
#: their parcel closures): |linking number| of the per-rod closure, each rod's own knot
#: type, and the Alexander name of the parcel closure (the square and the granny knot
#: share (t^2 - t + 1)^2 with 8_20; None: no table value to compare with, the diagonal
#: closure being a convention of this module, :func:`parcel_closure`).
EXPECTED: dict[str, tuple[int, str, str | None]] = {
    "clasp": (1, "0_1", "0_1"),
    "reef": (0, "0_1", "8_20|3_1#3_1"),
    "thief": (0, "0_1", None),
    "granny": (3, "0_1", "8_20|3_1#3_1"),
    "grief": (3, "0_1", None),
}

#: Which tangle kinds share every invariant computed here (module docstring).
CANDIDATES: dict[str, tuple[str, ...]] = {
    "clasp": ("clasp",),
    "reef": ("reef", "thief"),
    "thief": ("reef", "thief"),
    "granny": ("granny", "grief"),
    "grief": ("granny", "grief"),
}


@dataclass(frozen=True)
class TangleGeometry:
    """Sizes of a start tangle, in units of the rod diameter D0 [-].

    Attributes:
        helix_radius: half the distance between the two twisted legs of a side.
        side_offset: y of each side's centre.
        twist_length: x-length of the twist regions (centred on x = 0) per half turn of
            the more twisted side: 3 D0 keeps a leg's neighbouring turns and the other
            leg's half a turn away more than a diameter apart (the smooth step's steepest
            pitch is half the mean one).
        tail: x-length of each straight leg beyond the twist region.
    """

    helix_radius: float = 0.8
    side_offset: float = 2.0
    twist_length: float = 3.0
    tail: float = 6.0


def _smooth_step(u: NDArray[np.float64]) -> NDArray[np.float64]:
    # u - sin(2 pi u)/(2 pi): 0 -> 0, 1 -> 1 with zero slope at both ends, so the twist
    # region meets the straight legs and the U-turns with a continuous tangent.
    return u - np.sin(2.0 * math.pi * u) / (2.0 * math.pi)


def _side(n_half: int, n_max: int, hand: int, side: int, g: TangleGeometry, k: int
          ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """A's and B's legs through one side's twist region, both from x = -a to x = +a,
    (k, 3) each [D0]: A starts outside (|y| = w + r), B inside; after an odd number of half
    turns A ends inside, B outside."""
    a = 0.5 * g.twist_length * n_max
    x = np.linspace(-a, a, k)
    phi = n_half * math.pi * _smooth_step((x + a) / (2.0 * a))
    r, w = g.helix_radius, g.side_offset
    ya = side * (w + r * np.cos(phi))
    yb = side * (w - r * np.cos(phi))
    za = hand * r * np.sin(phi)
    return np.c_[x, ya, za], np.c_[x, yb, -za]


def _u_turn(p_from: NDArray, p_to: NDArray, bulge: int, k: int) -> NDArray[np.float64]:
    """Half circle in the z = 0 plane from ``p_from`` to ``p_to`` (same x, z = 0), bulging
    toward ``bulge`` x (+1 or -1); ``k`` points, the end points excluded."""
    cy = 0.5 * (p_from[1] + p_to[1])
    rad = 0.5 * abs(p_from[1] - p_to[1])
    th = np.linspace(0.0, math.pi, k + 2)[1:-1]
    sgn = 1.0 if p_from[1] > p_to[1] else -1.0
    return np.c_[p_from[0] + bulge * rad * np.sin(th), cy + sgn * rad * np.cos(th),
                 np.zeros(k)]


def tangle_curves(kind: str, geometry: TangleGeometry | None = None,
                  samples: int = 400) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Start centerlines of rods A and B of tangle ``kind`` ("clasp" or a :data:`BENDS`
    key), in units of D0, densely sampled (``samples`` points per twist region). Rod A
    runs from its upper end (x = -(a + tail), y > 0) through the upper twist region, the
    U-turn at +x and the lower twist region to its lower end; rod B from its upper end at
    +x likewise (module docstring)."""
    n1, n2, h1, h2, _ = _spec(kind)
    g = geometry or TangleGeometry()
    nmax = max(n1, n2)
    a = 0.5 * g.twist_length * nmax
    k = max(int(samples), 16)
    au, bu = _side(n1, nmax, h1, +1, g, k)
    al, bl = _side(n2, nmax, h2, -1, g, k)
    ends_y = g.side_offset + g.helix_radius
    tail_x = np.linspace(a + g.tail, a, max(k // 2, 8))[:-1]
    bend_k = max(k // 2, 8)
    # Rod A: upper tail (-x) -> upper twist (x increasing) -> U-turn at +a -> lower twist
    # (x decreasing) -> lower tail.
    a_tail_up = np.c_[-tail_x, np.full(tail_x.size, ends_y), np.zeros(tail_x.size)]
    a_turn = _u_turn(au[-1], al[-1], +1, bend_k)
    a_tail_lo = np.c_[-tail_x[::-1], np.full(tail_x.size, -ends_y), np.zeros(tail_x.size)]
    rod_a = np.vstack([a_tail_up, au, a_turn, al[::-1], a_tail_lo])
    # Rod B: upper tail (+x) -> upper twist (x decreasing) -> U-turn at -a -> lower twist
    # (x increasing) -> lower tail. B is outside at x = +a after an odd number of half turns.
    b_tail_up = np.c_[tail_x, np.full(tail_x.size, ends_y), np.zeros(tail_x.size)]
    b_turn = _u_turn(bu[0], bl[0], -1, bend_k)
    b_tail_lo = np.c_[tail_x[::-1], np.full(tail_x.size, -ends_y), np.zeros(tail_x.size)]
    rod_b = np.vstack([b_tail_up, bu[::-1], b_turn, bl, b_tail_lo])
    return rod_a, rod_b


def _spec(kind: str) -> tuple[int, int, int, int, str]:
    if kind == "clasp":
        return CLASP
    if kind not in BENDS:
        raise ValueError(f"tangle kind must be 'clasp' or one of {', '.join(BENDS)}, "
                         f"got {kind!r}")
    return BENDS[kind]


def working_ends(kind: str) -> str:
    """Where the working ends of tangle ``kind`` are: "same" side or "diagonal"."""
    return _spec(kind)[4]


# -- invariants ------------------------------------------------------------------------------
def close_rod(points: ArrayLike, direction: ArrayLike, far: float) -> NDArray[np.float64]:
    """A rod's open centerline (N, 3) closed through two far points, each of its ends
    moved by ``far`` along the unit pull ``direction`` (its two ends are pulled the same
    way): a closure that no other rod of the tangle meets when ``far`` exceeds the
    tangle's size. Returns the closed polygon (the rod's points, then the two far points)."""
    p = np.asarray(points, dtype=np.float64)
    u = np.asarray(direction, dtype=np.float64)
    u = u / np.linalg.norm(u)
    return np.vstack([p, p[-1] + far * u, p[0] + far * u])


def linking_number(c1: ArrayLike, c2: ArrayLike, seed: int = 0, tries: int = 12) -> int:
    """Linking number of two closed polygons (N, 3) and (M, 3): the sum of the signs of
    the crossings where ``c1`` passes over ``c2`` in a generic projection (Rolfsen, *Knots
    and Links*, 1976, sec. 5.D). A projection with a crossing near a vertex or two strands
    at nearly one height is rejected and the next seeded one tried; the two counts (c1 over
    c2, c2 over c1) must agree, else the next one is tried."""
    p = np.asarray(c1, dtype=np.float64)
    q = np.asarray(c2, dtype=np.float64)
    size = float(np.ptp(np.vstack([p, q]), axis=0).max())
    rng = np.random.default_rng(seed)
    for _ in range(tries):
        rot = _random_rotation(rng)
        result = _crossing_signs(p @ rot.T, q @ rot.T, size)
        if result is not None and result[0] == result[1]:
            return int(result[0])
    raise topology.TopologyError("linking number: no generic projection found (the two "
                                 "curves nearly meet)")


def _random_rotation(rng: np.random.Generator) -> NDArray[np.float64]:
    qv = rng.normal(size=4)
    qv /= np.linalg.norm(qv)
    w, x, y, z = qv
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def _crossing_signs(p: NDArray, q: NDArray, size: float) -> tuple[int, int] | None:
    """(sum of signs where p is over q, sum where q is over p) of the projection on z = 0,
    or None for a non-generic projection."""
    a0, a1 = p, np.roll(p, -1, axis=0)
    b0, b1 = q, np.roll(q, -1, axis=0)
    da = (a1 - a0)[:, None, :]
    db = (b1 - b0)[None, :, :]
    r = b0[None, :, :2] - a0[:, None, :2]
    den = da[..., 0] * db[..., 1] - da[..., 1] * db[..., 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (r[..., 0] * db[..., 1] - r[..., 1] * db[..., 0]) / den
        t = (r[..., 0] * da[..., 1] - r[..., 1] * da[..., 0]) / den
    eps = 1e-9
    # Nearly parallel projected segments cross nowhere transversally: in a random
    # projection they come from collinear 3D segments (the straight tails of the two rods
    # on one line, and their closures), which never cross.
    norm = np.linalg.norm(da[..., :2], axis=-1) * np.linalg.norm(db[..., :2], axis=-1)
    transversal = np.abs(den) > 1e-8 * norm
    hit = (s > -eps) & (s < 1 + eps) & (t > -eps) & (t < 1 + eps) & transversal
    if not hit.any():
        return 0, 0
    s, t = s[hit], t[hit]
    # A crossing at a vertex could count on two edges or none after round-off.
    if np.any((np.abs(s) < 1e-7) | (np.abs(s - 1) < 1e-7) | (np.abs(t) < 1e-7)
              | (np.abs(t - 1) < 1e-7)):
        return None
    ia, ib = np.nonzero(hit)
    za = a0[ia, 2] + s * (a1[ia, 2] - a0[ia, 2])
    zb = b0[ib, 2] + t * (b1[ib, 2] - b0[ib, 2])
    dz = za - zb
    if np.any(np.abs(dz) < 1e-9 * size):
        return None
    # The sign of a crossing (right-handed +1): over strand's direction crossed with the
    # under strand's, seen from +z.
    cr = np.sign(den[hit])
    sign_p_over = np.where(dz > 0, cr, -cr)
    return int(np.sum(sign_p_over[dz > 0])), int(np.sum(sign_p_over[dz < 0]))


@dataclass(frozen=True)
class TangleType:
    """Invariants of a two-rod tangle.

    Attributes:
        linking_number: linking number of the two rods, each closed on its own.
        component_types: each rod's own knot type (closed on its own), by Alexander name.
        closure_type: knot type of the parcel closure (working ends joined, standing ends
            joined), by Alexander name; "" when not computed.
    """

    linking_number: int
    component_types: tuple[str, ...]
    closure_type: str = ""

    def label(self) -> str:
        """One string that changes when any invariant changes."""
        comps = ",".join(self.component_types)
        tail = f"; closure {self.closure_type}" if self.closure_type else ""
        return f"lk {self.linking_number}; rods {comps}{tail}"

    def matches(self, kind: str) -> bool:
        """Whether these are the invariants tangle ``kind`` must have (:data:`EXPECTED`)."""
        lk, comp, closure = EXPECTED[kind]
        return (abs(self.linking_number) == lk and all(c == comp for c in self.component_types)
                and (not self.closure_type or closure is None or self.closure_type == closure))


def _far(rods: list[NDArray]) -> float:
    allp = np.vstack(rods)
    return 10.0 * float(np.ptp(allp, axis=0).max())


def parcel_closure(rod_a: NDArray, rod_b: NDArray, ends: str) -> NDArray[np.float64]:
    """One closed curve through both rods: A's upper end (its first vertex) joined to B's
    upper end (``ends="same"``) or to B's lower end (``"diagonal"``), and the other two
    ends to each other, through far points (+-x, then out to +-y or +-z so that the two
    closing arcs never meet)."""
    far = _far([rod_a, rod_b])
    ax = np.array([far, 0.0, 0.0])
    if ends == "same":
        up, lo = np.array([0.0, far, 0.0]), np.array([0.0, -far, 0.0])
        b_path = rod_b[::-1]  # B from its lower end to its upper end
        # A (upper end -> lower end), lower arc to B's lower end, B, upper arc to A's start.
        return np.vstack([rod_a, rod_a[-1] - ax, rod_a[-1] - ax + lo, rod_b[-1] + ax + lo,
                          rod_b[-1] + ax, b_path, rod_b[0] + ax, rod_b[0] + ax + up,
                          rod_a[0] - ax + up, rod_a[0] - ax])
    if ends == "diagonal":
        hi, dn = np.array([0.0, 0.0, far]), np.array([0.0, 0.0, -far])
        # A (upper -> lower), arc below to B's upper end, B (upper -> lower), arc above to A.
        return np.vstack([rod_a, rod_a[-1] - ax, rod_a[-1] - ax + dn, rod_b[0] + ax + dn,
                          rod_b[0] + ax, rod_b, rod_b[-1] + ax, rod_b[-1] + ax + hi,
                          rod_a[0] - ax + hi, rod_a[0] - ax])
    raise ValueError(f"ends must be 'same' or 'diagonal', got {ends!r}")


def tangle_type(rods: list[ArrayLike], directions: list[ArrayLike],
                ends: str | None = None) -> TangleType:
    """Invariants of two open rods (N_i, 3) [m] whose both ends are pulled along the unit
    ``directions`` (one per rod): the linking number of the rods closed on their own
    (:func:`close_rod`), each one's knot type, and (``ends`` given: "same" or "diagonal")
    the knot type of the parcel closure (:func:`parcel_closure`). A projection that is not
    generic anywhere (the rods nearly meet) gives the linking number's error as a
    :class:`~tightknot.knots.topology.TopologyError`."""
    if len(rods) != 2 or len(directions) != 2:
        raise ValueError("tangle_type takes exactly two rods and two pull directions")
    pts = [np.asarray(r, dtype=np.float64) for r in rods]
    far = _far(pts)
    closed = [close_rod(p, d, far) for p, d in zip(pts, directions, strict=True)]
    lk = linking_number(closed[0], closed[1])
    comps = tuple(topology.knot_type(c) for c in closed)
    closure = topology.knot_type(parcel_closure(pts[0], pts[1], ends)) if ends else ""
    return TangleType(lk, comps, closure)


def rod_overlaps(rods: list[ArrayLike], radii: list[float]) -> tuple[float, int, int, int, int]:
    """Smallest distance [m] between the centerlines of two different rods, less the sum
    of their radii (negative: their tubes overlap), and where: (gap, rod i, vertex of i,
    rod j, vertex of j), measured between every vertex of one rod and every segment of the
    other."""
    best = (math.inf, -1, -1, -1, -1)
    pts = [np.asarray(r, dtype=np.float64) for r in rods]
    for i in range(len(pts)):
        for j in range(len(pts)):
            if i == j:
                continue
            p, q = pts[i], pts[j]
            q0, q1 = q[:-1], q[1:]
            d = q1 - q0
            ll = np.einsum("ij,ij->i", d, d)
            tt = np.clip(np.einsum("kij,ij->ki", p[:, None, :] - q0[None], d) / ll, 0.0, 1.0)
            closest = q0[None] + tt[..., None] * d[None]
            dist = np.linalg.norm(p[:, None, :] - closest, axis=2)
            k, m = np.unravel_index(int(np.argmin(dist)), dist.shape)
            gap = float(dist[k, m]) - radii[i] - radii[j]
            if gap < best[0]:
                best = (gap, i, int(k), j, int(m))
    return best


def pull_frame(rod_a: ArrayLike, rod_b: ArrayLike) -> tuple[NDArray, NDArray]:
    """Two rods' centerlines (N, 3) [m] placed in the tangles' frame: the x axis from the
    midpoint of A's two ends to that of B's (A is pulled toward -x, B toward +x), A's first
    end on the +y side, the origin between the two midpoints; B reversed if needed so that
    its first end is on A's first end's side (the parcel closure joins the first ends).
    A rigid motion: lengths and the tangle's type are unchanged."""
    a = np.asarray(rod_a, dtype=np.float64)
    b = np.asarray(rod_b, dtype=np.float64)
    mid_a, mid_b = 0.5 * (a[0] + a[-1]), 0.5 * (b[0] + b[-1])
    ex = mid_b - mid_a
    size = float(np.ptp(np.vstack([a, b]), axis=0).max())
    if np.linalg.norm(ex) <= 1e-6 * size:
        raise ValueError("the midpoints of rod A's and rod B's ends coincide: the rods must "
                         "be pulled apart, A's two ends on one side and B's on the other")
    ex = ex / np.linalg.norm(ex)
    ey = None
    for v in (a[0] - a[-1], b[0] - b[-1]):
        w = v - (v @ ex) * ex
        if np.linalg.norm(w) > 1e-6 * size:
            ey = w / np.linalg.norm(w)
            break
    if ey is None:
        raise ValueError("each rod's two ends lie on the pull axis: a U-shaped rod's ends "
                         "must be apart across it")
    ez = np.cross(ex, ey)
    frame = np.vstack([ex, ey, ez])
    origin = 0.5 * (mid_a + mid_b)
    a2, b2 = (a - origin) @ frame.T, (b - origin) @ frame.T
    if b2[0, 1] < b2[-1, 1]:
        b2 = b2[::-1].copy()
    return a2, b2
