"""No passing through: the largest fraction of a step that keeps every pair of segments
sharing no vertex at least its floor apart along the straight path.

Along the straight step, the points a(s) of one edge and b(t) of the other move by alpha
da(s) and alpha db(t), so |a(s) - b(t)| falls by at most alpha |da(s) - db(t)|; da(s) -
db(t) is affine in (s, t), so its norm is convex and largest at a corner of the unit
square: M = max |da_i - db_j| over the four vertex pairs. No point pair then comes closer
than d0 - alpha M, and alpha = (d0 - floor) / M keeps the pair at least ``floor`` apart
along the whole step: no passing through by construction. The relative motion counts, not
the sum of the two edges' largest motions (M <= m_a + m_b): material sliding along a rod
through a knot moves the near pairs of that rod alike, and a bound on the sum cut such
steps (docs/design_notes.md, "The step bound"). Every pair counts,
neighbours along the rod too (the energy may not watch them: the exclusion window). The
floor of a pair is the hard limit (``hard_fraction`` D), or, for two edges of one rod whose
nearest ends are an arc s apart, ``local_fraction`` D sin(min(s/D, pi/2)) where smaller: a
quarter of the chord between two points an arc s apart on the tightest bend a tube of
diameter D allows, so a legal bend is never blocked. The candidates are the pairs whose
bounds, swept by the step and inflated by half the hard limit, overlap.
"""

from __future__ import annotations

import numpy as np
import warp as wp

from tightknot.contact.broad_phase import BroadPhase, ContactCapacityError, arc_separation
from tightknot.contact.kernel_module import KERNEL_MODULE
from tightknot.rods.staging import Launches, Output

f64 = wp.float64

#: Floor of near pairs of one rod over the tightest legal bend's chord (module docstring).
LOCAL_FRACTION = 0.25

#: Longest vertex move, over the largest rest diameter, a step is cut to when its swept
#: bounds hold more candidate pairs than the broad phase allows (a floppy start's first
#: Newton steps move thousands of diameters on a rod of 1e4 D0 and sweep their edges over
#: much of the rod): a smaller fraction of a step is always safe.
STEP_REACH = 20.0
HALF_PI = wp.constant(wp.float64(1.5707963267948966))


@wp.func
def segment_distance(p0: wp.vec3d, p1: wp.vec3d, q0: wp.vec3d, q1: wp.vec3d) -> wp.vec3d:
    """Closest points of segments [p0, p1], [q0, q1]: returns (distance, s, t).

    Ericson, "Real-Time Collision Detection" (2005) sec. 5.1.9, with the parallel and
    zero-length cases handled.
    """
    d1 = p1 - p0
    d2 = q1 - q0
    r = p0 - q0
    a = wp.dot(d1, d1)
    e = wp.dot(d2, d2)
    f = wp.dot(d2, r)
    tiny = f64(1.0e-30)
    s = f64(0.0)
    t = f64(0.0)
    if a <= tiny and e <= tiny:
        s = f64(0.0)
        t = f64(0.0)
    elif a <= tiny:
        s = f64(0.0)
        t = wp.clamp(f / e, f64(0.0), f64(1.0))
    else:
        c = wp.dot(d1, r)
        if e <= tiny:
            t = f64(0.0)
            s = wp.clamp(-c / a, f64(0.0), f64(1.0))
        else:
            b = wp.dot(d1, d2)
            denom = a * e - b * b
            if denom > f64(1.0e-14) * a * e:
                s = wp.clamp((b * f - c * e) / denom, f64(0.0), f64(1.0))
            else:
                s = f64(0.0)  # parallel: any s works; pick an end
            t = (b * s + f) / e
            if t < f64(0.0):
                t = f64(0.0)
                s = wp.clamp(-c / a, f64(0.0), f64(1.0))
            elif t > f64(1.0):
                t = f64(1.0)
                s = wp.clamp((b - c) / a, f64(0.0), f64(1.0))
    cp = p0 + s * d1
    cq = q0 + t * d2
    return wp.vec3d(wp.length(cp - cq), s, t)


@wp.func
def pair_floor(a: int, b: int, edge_rod: wp.array(dtype=wp.int32),
               rod_closed: wp.array(dtype=wp.int32), edge_hard: wp.array(dtype=wp.float64),
               edge_diameter: wp.array(dtype=wp.float64), local_fraction: wp.float64,
               edge_arc: wp.array(dtype=wp.vec2d), rod_length: wp.array(dtype=wp.float64)
               ) -> wp.float64:
    """The floor [m] of edge pair (a, b) (module docstring)."""
    hard = wp.max(edge_hard[a], edge_hard[b])
    ra = edge_rod[a]
    if edge_rod[b] != ra:
        return hard
    arc_a = edge_arc[a]
    arc_b = edge_arc[b]
    closed = rod_closed[ra]
    length = rod_length[ra]
    sep = wp.min(wp.min(arc_separation(arc_a[0], arc_b[1], 1, closed, length),
                        arc_separation(arc_a[1], arc_b[0], 1, closed, length)),
                 wp.min(arc_separation(arc_a[0], arc_b[0], 1, closed, length),
                        arc_separation(arc_a[1], arc_b[1], 1, closed, length)))
    d = wp.max(edge_diameter[a], edge_diameter[b])
    return wp.min(hard, local_fraction * d * wp.sin(wp.min(sep / d, HALF_PI)))


@wp.kernel(module=KERNEL_MODULE)
def step_bound_kernel(
    # Model:
    edge_vertex: wp.array(dtype=wp.vec2i),
    edge_rod: wp.array(dtype=wp.int32),
    rod_closed: wp.array(dtype=wp.int32),
    edge_hard: wp.array(dtype=wp.float64),
    edge_diameter: wp.array(dtype=wp.float64),
    local_fraction: wp.float64,
    # Data in:
    x_in: wp.array(dtype=wp.vec3d),
    dx_in: wp.array(dtype=wp.vec3d),
    pairs_in: wp.array(dtype=wp.vec2i),
    edge_arc_in: wp.array(dtype=wp.vec2d),
    rod_length_in: wp.array(dtype=wp.float64),
    # Out:
    alpha_out: wp.array(dtype=wp.float64),
    distance_out: wp.array(dtype=wp.float64),
):
    # Each pair's largest step fraction (module docstring: the largest relative motion of
    # two vertices, one of each edge) and its segment distance.
    p = wp.tid()
    pr = pairs_in[p]
    va = edge_vertex[pr[0]]
    vb = edge_vertex[pr[1]]
    res = segment_distance(x_in[va[0]], x_in[va[1]], x_in[vb[0]], x_in[vb[1]])
    d0 = res[0]
    distance_out[p] = d0
    a0 = dx_in[va[0]]
    a1 = dx_in[va[1]]
    b0 = dx_in[vb[0]]
    b1 = dx_in[vb[1]]
    hard = pair_floor(pr[0], pr[1], edge_rod, rod_closed, edge_hard, edge_diameter,
                      local_fraction, edge_arc_in, rod_length_in)
    move = wp.max(wp.max(wp.length(a0 - b0), wp.length(a0 - b1)),
                  wp.max(wp.length(a1 - b0), wp.length(a1 - b1)))
    alpha = f64(1.0e30)
    if move > f64(0.0):
        alpha = (d0 - hard) / move
    alpha_out[p] = alpha


class StepBound:
    """The step bound of a layer's edges, and the segment distances of candidate pairs.

    Args:
        broad: the layer's broad phase.
        edge_hard: hard limit of each edge [m]: a pair's is the larger of its two edges'.
    """

    def __init__(self, broad: BroadPhase, edge_hard: np.ndarray,
                 edge_diameter: np.ndarray, local_fraction: float = LOCAL_FRACTION) -> None:
        dev = broad.device
        self.broad = broad
        self.device = dev
        self.local_fraction = float(local_fraction)
        self._diameter = wp.array(np.asarray(edge_diameter, dtype=np.float64), dtype=f64,
                                  device=dev)
        #: The largest rest diameter [m] (the unit of :data:`STEP_REACH`).
        self._dmax = float(np.max(edge_diameter))
        #: Hard limit of each edge [m] (host).
        self.edge_hard = np.asarray(edge_hard, dtype=np.float64)
        self._hard = wp.array(self.edge_hard, dtype=f64, device=dev)
        #: Bounds margin of the step's candidates: half the hard limit [m] per edge.
        self.half_hard = wp.array(0.5 * self.edge_hard, dtype=f64, device=dev)
        self._alpha = Output(wp.float64, dev)
        self._dist = Output(wp.float64, dev)
        self._launches = Launches()

    def max_step(self, x: np.ndarray, dx: np.ndarray, rest: np.ndarray) -> float:
        """Largest fraction of the step ``dx`` [m] (vertices) from positions ``x`` [m] that
        keeps every segment pair sharing no vertex at least its floor apart along the
        straight path (1 = full; a step whose candidates overflow the broad phase is first
        cut to :data:`STEP_REACH` diameters); ``rest``: edge rest lengths [m] (the arcs of
        the near pairs' floors, :meth:`BroadPhase.arcs`)."""
        broad = self.broad
        wx = broad.x_in.put(x)
        wdx = broad.dx_in.put(dx)
        arcs, rod_len = broad.arcs(rest)
        cut = 1.0
        try:
            pairs = broad.candidates(wx, wdx, self.half_hard, arcs, rod_len, window=0.0)
        except ContactCapacityError:
            longest = float(np.sqrt(np.max(np.sum(dx * dx, axis=1))))
            if longest <= STEP_REACH * self._dmax:
                raise  # a dense contact set, not a long step
            cut = STEP_REACH * self._dmax / longest
            wdx = broad.dx_in.put(cut * dx)
            pairs = broad.candidates(wx, wdx, self.half_hard, arcs, rod_len, window=0.0)
        if pairs.shape[0] == 0:
            return cut
        alpha = self.pair_bounds(wx, wdx, pairs, arcs, rod_len)
        return cut * float(np.clip(alpha.min(), 0.0, 1.0))

    def pair_bounds(self, wx: wp.array, wdx: wp.array, pairs: wp.array, arcs: wp.array,
                    rod_len: wp.array) -> np.ndarray:
        """Each pair's largest step fraction (host copy; step_bound_kernel) at the arcs
        ``arcs``, ``rod_len`` (:meth:`BroadPhase.arcs`); the pairs' segment distances [m]
        are kept for :meth:`distances`."""
        n = pairs.shape[0]
        alpha = self._alpha.get(n)  # written for every pair: no zeroing needed
        dist = self._dist.get(n)
        b = self.broad
        self._launches.launch(step_bound_kernel, n, self.device,
                              [b.edge_vertex, b.edge_rod, b.rod_closed, self._hard,
                               self._diameter, self.local_fraction, wx, wdx,
                               b.buffer_of(pairs), arcs, rod_len], [alpha, dist])
        return self._alpha.numpy(n)

    def distances(self, n: int) -> np.ndarray:
        """Segment distances [m] of the first ``n`` pairs of the last :meth:`pair_bounds`."""
        return self._dist.numpy(n)
