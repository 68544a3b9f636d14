"""The contact layer's broad phase: which edge pairs can touch.

A Warp BVH over the edges' bounds (swept by a step, inflated by a margin), rebuilt at every
query; candidate edge pairs go to a fixed-capacity buffer that grows (and the query reruns)
when it overflows, so no contact is ever dropped. Pairs closer along the rod than the
exclusion window are skipped, measured on the rest arcs scaled by :attr:`BroadPhase.
window_scale` (the window follows the stretched rod, set at every load step).
The bounds are float32 (Warp's BVH), padded so that their rounding never shrinks them.
"""

from __future__ import annotations

import math

import numpy as np
import warp as wp

from tightknot.contact.kernel_module import KERNEL_MODULE
from tightknot.rods.model import Model
from tightknot.rods.staging import Launches, Staging

f64 = wp.float64

#: Bounds margin over the edge radius: the interaction range of an edge is its radius,
#: grown if the edge is compressed (r0 lam^-nu: 1.1 r0 covers lam >= 0.83 at nu = 1/2), so
#: that two edges whose Gauss points can interact (distance < r_a + r_b) have overlapping
#: bounds.
MARGIN = 1.1

#: Most candidate edge pairs the broad phase may return (about 0.5 GB of pair data).
MAX_CANDIDATES = 20_000_000


class ContactCapacityError(ValueError):
    """More candidate contact pairs than memory allows (too fine a mesh for the contact)."""


@wp.func
def arc_separation(sa: wp.float64, sb: wp.float64, same_rod: int, closed: int,
                   rod_length: wp.float64) -> wp.float64:
    """Rest arc length [m] between points at arcs ``sa``, ``sb`` [m] of one rod (the shorter
    way round on a closed rod of length ``rod_length``); 1e30 on two rods."""
    if same_rod == 0:
        return f64(1.0e30)
    d = wp.abs(sa - sb)
    if closed != 0:
        d = wp.min(d, rod_length - d)
    return d


@wp.kernel(module=KERNEL_MODULE)
def edge_bounds_kernel(
    # Model:
    edge_vertex: wp.array(dtype=wp.vec2i),
    # Data in:
    x_in: wp.array(dtype=wp.vec3d),
    dx_in: wp.array(dtype=wp.vec3d),
    margin_in: wp.array(dtype=wp.float64),
    # Out:
    lower_out: wp.array(dtype=wp.vec3),
    upper_out: wp.array(dtype=wp.vec3),
):
    # Bounds of each edge swept by the step dx (zero for a static query), inflated by its
    # margin; float32, padded so rounding never shrinks them.
    j = wp.tid()
    v = edge_vertex[j]
    p0 = x_in[v[0]]
    p1 = x_in[v[1]]
    q0 = p0 + dx_in[v[0]]
    q1 = p1 + dx_in[v[1]]
    lo = wp.min(wp.min(p0, p1), wp.min(q0, q1))
    hi = wp.max(wp.max(p0, p1), wp.max(q0, q1))
    m = margin_in[j] * f64(1.0001) + f64(1.0e-9)
    mv = wp.vec3d(m, m, m)
    lower_out[j] = wp.vec3(lo - mv)
    upper_out[j] = wp.vec3(hi + mv)


@wp.kernel(module=KERNEL_MODULE)
def candidate_pairs_kernel(
    # Model:
    edge_vertex: wp.array(dtype=wp.vec2i),
    edge_rod: wp.array(dtype=wp.int32),
    rod_closed: wp.array(dtype=wp.int32),
    edge_exclusion: wp.array(dtype=wp.float64),
    candidate_window: wp.float64,
    # Data in:
    bvh_id: wp.uint64,
    lower_in: wp.array(dtype=wp.vec3),
    upper_in: wp.array(dtype=wp.vec3),
    edge_arc_in: wp.array(dtype=wp.vec2d),
    rod_length_in: wp.array(dtype=wp.float64),
    capacity: int,
    # Out:
    count_out: wp.array(dtype=wp.int32),
    pairs_out: wp.array(dtype=wp.vec2i),
):
    # Edge pairs (a < b) whose bounds overlap and that hold at least one point pair
    # farther apart along the rod than candidate_window times the exclusion window.
    a = wp.tid()
    query = wp.bvh_query_aabb(bvh_id, lower_in[a], upper_in[a])
    b = int(0)  # noqa: UP018 (Warp: a literal is a constant)
    ra = edge_rod[a]
    arc_a = edge_arc_in[a]
    va = edge_vertex[a]
    while wp.bvh_query_next(query, b):
        if b <= a:
            continue
        # Edges that share a vertex are neighbours, never a contact (edges longer than the
        # exclusion window would otherwise pair up and touch at their common vertex).
        vb = edge_vertex[b]
        if va[0] == vb[0] or va[0] == vb[1] or va[1] == vb[0] or va[1] == vb[1]:
            continue
        same = int(0)  # noqa: UP018 (Warp: a literal is a constant)
        if edge_rod[b] == ra:
            same = 1
        if same != 0:
            arc_b = edge_arc_in[b]
            excl = wp.max(edge_exclusion[a], edge_exclusion[b])
            # Largest separation of any two points of the two edges.
            s1 = arc_separation(arc_a[0], arc_b[1], 1, rod_closed[ra], rod_length_in[ra])
            s2 = arc_separation(arc_a[1], arc_b[0], 1, rod_closed[ra], rod_length_in[ra])
            s3 = arc_separation(arc_a[0], arc_b[0], 1, rod_closed[ra], rod_length_in[ra])
            s4 = arc_separation(arc_a[1], arc_b[1], 1, rod_closed[ra], rod_length_in[ra])
            if wp.max(wp.max(s1, s2), wp.max(s3, s4)) < candidate_window * excl:
                continue
        k = wp.atomic_add(count_out, 0, 1)
        if k < capacity:
            pairs_out[k] = wp.vec2i(a, b)


class BroadPhase:
    """Candidate edge pairs of a model's rods, and the rest-arc tables they are judged by.

    Args:
        model: the rods.
        exclusion: exclusion window of each edge [m], (edge_count,).
        candidate_window: pairs of one rod whose points all lie closer along it than this
            times the exclusion window are never candidates [-].
        initial_capacity: first size of the candidate-pair buffer (grows on demand).

    The positions and steps reach the kernels through :attr:`x_in` and :attr:`dx_in`, which
    every part of the layer shares, so that the recorded launches
    (:class:`tightknot.rods.staging.Launches`) see the same arrays from call to call.
    """

    def __init__(self, model: Model, exclusion: np.ndarray, candidate_window: float,
                 initial_capacity: int = 1024) -> None:
        dev = model.device
        self.model = model
        self.device = dev
        self.candidate_window = float(candidate_window)
        self.edge_vertex = model.wp("edge_vertex")
        self.edge_rod = wp.array(model.edge_rod, dtype=wp.int32, device=dev)
        self.rod_closed = wp.array([int(r.closed) for r in model.rods], dtype=wp.int32,
                                   device=dev)
        #: Exclusion window of each edge [m] (host).
        self.exclusion = np.asarray(exclusion, dtype=np.float64)
        self.edge_exclusion = wp.array(self.exclusion, dtype=f64, device=dev)
        #: Bounds margin of each edge for the interaction range [m] (see MARGIN).
        self.interaction_margin = wp.array(MARGIN * model.edge_radius, dtype=f64, device=dev)
        #: Staged positions [m] and steps [m] of the vertices (device).
        self.x_in = Staging(wp.vec3d, dev)
        self.dx_in = Staging(wp.vec3d, dev)
        #: A zero step, for static queries.
        self.zero_dx = wp.zeros(model.vertex_count, dtype=wp.vec3d, device=dev)
        self._lower = wp.empty(model.edge_count, dtype=wp.vec3, device=dev)
        self._upper = wp.empty(model.edge_count, dtype=wp.vec3, device=dev)
        self._capacity = int(initial_capacity)
        self._alloc(self._capacity)
        #: Scale of each edge's rest length in the arcs the window is judged by [-]: the
        #: window follows the deformed rod (ContactLayer.begin_load_step); 1 at rest.
        self.window_scale = np.ones(model.edge_count)
        #: (rest lengths, window scale, their arc tables) of the last :meth:`arcs` call.
        self._arcs_memo: tuple[np.ndarray, np.ndarray, tuple[wp.array, wp.array]] | None = None
        self._launches = Launches()
        #: Rods that are mirror images of each other (Model.mirror_rod_pairs), or None.
        self._mirror = model.mirror_matrix() if model.mirror_rod_pairs else None

    def _alloc(self, capacity: int) -> None:
        self._pairs = wp.zeros(capacity, dtype=wp.vec2i, device=self.device)
        self._count = wp.zeros(1, dtype=wp.int32, device=self.device)

    # -- rest arcs -------------------------------------------------------------------------
    def arcs(self, rest: np.ndarray) -> tuple[wp.array, wp.array]:
        """Arc lengths [m] of each edge's ends (vec2d per edge) and each rod's length [m]
        that the exclusion window is judged by: the edge rest lengths ``rest`` [m] times
        :attr:`window_scale`."""
        # The arcs change once per load step but are asked for at every evaluation and
        # step bound (a Python loop over the rods and two device copies each time): reused
        # while the rest lengths and the scale are the same.
        memo = self._arcs_memo
        if (memo is not None and np.array_equal(memo[0], rest)
                and np.array_equal(memo[1], self.window_scale)):
            return memo[2]
        out = self.arcs_of(np.asarray(rest, dtype=np.float64) * self.window_scale)
        self._arcs_memo = (np.array(rest, dtype=np.float64), self.window_scale.copy(), out)
        return out

    def arcs_of(self, rest: np.ndarray) -> tuple[wp.array, wp.array]:
        """As :meth:`arcs`, computed (no reuse)."""
        m = self.model
        arcs = np.zeros((m.edge_count, 2))
        lengths = np.zeros(len(m.rods))
        for r, rod in enumerate(m.rods):
            le = rest[rod.edge_slice]
            s1 = np.cumsum(le)
            arcs[rod.edge_slice, 0] = s1 - le
            arcs[rod.edge_slice, 1] = s1
            lengths[r] = s1[-1]
        return (wp.array(arcs, dtype=wp.vec2d, device=self.device),
                wp.array(lengths, dtype=wp.float64, device=self.device))

    # -- candidates ------------------------------------------------------------------------
    def candidates(self, wx: wp.array, wdx: wp.array, margin: wp.array, arcs: wp.array,
                   rod_len: wp.array, window: float | None = None) -> wp.array:
        """Candidate edge pairs (a < b, vec2i) at positions ``wx`` [m] whose bounds, swept
        by the step ``wdx`` [m] and inflated by ``margin`` [m] per edge, overlap; ``arcs``,
        ``rod_len`` from :meth:`arcs`; ``window``: the candidate window over the exclusion
        window (default :attr:`candidate_window`; 0: every pair sharing no vertex). A
        prefix of the candidate buffer (see :meth:`buffer_of`), valid until the next
        query."""
        window = self.candidate_window if window is None else float(window)
        m = self.model
        dev = self.device
        lower, upper = self._lower, self._upper
        self._launches.launch(edge_bounds_kernel, m.edge_count, dev,
                              [self.edge_vertex, wx, wdx, margin], [lower, upper])
        bvh = wp.Bvh(lower, upper)
        while True:
            self._count.zero_()
            # Not a recorded launch: the BVH is new at every call.
            wp.launch(candidate_pairs_kernel, dim=m.edge_count, device=dev,
                      inputs=[self.edge_vertex, self.edge_rod, self.rod_closed,
                              self.edge_exclusion, window, bvh.id, lower,
                              upper, arcs, rod_len, self._capacity],
                      outputs=[self._count, self._pairs])
            n = int(self._count.numpy()[0])
            if n <= self._capacity:
                return self._pairs[:n] if self._mirror is None else self._without_mirrors(n)
            if n > MAX_CANDIDATES:
                # Pairs per contact grow as (D/l)^2: a fine mesh of a knot whose strands
                # touch over many diameters outgrows memory.
                diam = 2.0 * m.edge_radius
                raise ContactCapacityError(
                    f"{n} candidate contact pairs exceed the limit {MAX_CANDIDATES}: "
                    f"{m.vertex_count} vertices are too many for this contact set (edges of "
                    f"{np.median(m.edge_rest_length) / np.median(diam):.2g}"
                    " D); use fewer nodes (pairs grow as the square of the vertex count)")
            # Overflow: grow and query again, never drop a candidate.
            self._capacity = int(2 ** math.ceil(math.log2(n * 1.25)))
            self._alloc(self._capacity)

    def _without_mirrors(self, n: int) -> wp.array:
        """The first ``n`` candidates less the pairs of two mirror images
        (:attr:`tightknot.rods.model.Model.mirror_rod_pairs`), as a prefix of the buffer."""
        pairs = self._pairs[:n].numpy()
        rod = self.model.edge_rod
        keep = ~self._mirror[rod[pairs[:, 0]], rod[pairs[:, 1]]]
        if keep.all():
            return self._pairs[:n]
        kept = np.ascontiguousarray(pairs[keep])
        if kept.shape[0]:
            wp.copy(self._pairs, wp.array(kept, dtype=wp.vec2i, device=self.device),
                    count=kept.shape[0])
        return self._pairs[:kept.shape[0]]

    def buffer_of(self, pairs: wp.array) -> wp.array:
        """The candidate buffer itself when ``pairs`` is its prefix (as :meth:`candidates`
        returns it), so that recorded launches see the same array at every call; kernels
        launched over ``pairs`` read only its first ``dim`` pairs."""
        if pairs.ptr == self._pairs.ptr and pairs.device == self._pairs.device:
            return self._pairs
        return pairs

    def nonlocal_pairs(self, x: np.ndarray, rest: np.ndarray) -> np.ndarray:
        """Candidate edge pairs (P, 2) within the interaction range at positions ``x`` [m]
        and rest lengths ``rest`` [m] that hold two points farther apart along the rod than
        the exclusion window (not the pairs only the local barrier sees)."""
        wx = self.x_in.put(x)
        arcs, rod_len = self.arcs(rest)
        pairs = self.candidates(wx, self.zero_dx, self.interaction_margin, arcs,
                                rod_len).numpy()
        if pairs.shape[0]:
            pairs = pairs[self.nonlocal_mask(pairs, arcs.numpy())]
        return pairs

    # -- the exclusion window on the host --------------------------------------------------
    def window_separations(self, pr: np.ndarray, ar: np.ndarray) -> tuple[np.ndarray, ...]:
        """For edge pairs ``pr`` with rest arcs ``ar`` [m]: whether both edges lie on one rod,
        the rest arc separations [m] of their four end pairs (the shorter way round on a
        closed rod), each pair's rod length [m] and closure, and its exclusion window [m]."""
        m = self.model
        rod = m.edge_rod[pr]
        a, b = ar[pr[:, 0]], ar[pr[:, 1]]
        seps = np.abs(a[:, :, None] - b[:, None, :]).reshape(-1, 4)
        length = np.array([ar[r.edge_slice][-1, 1] for r in m.rods])[rod[:, 0]]
        closed = np.array([r.closed for r in m.rods])[rod[:, 0]]
        seps = np.where(closed[:, None], np.minimum(seps, length[:, None] - seps), seps)
        excl = np.maximum(self.exclusion[pr[:, 0]], self.exclusion[pr[:, 1]])
        return rod[:, 0] == rod[:, 1], seps, length, closed, excl

    def nonlocal_mask(self, pr: np.ndarray, ar: np.ndarray) -> np.ndarray:
        """Mask of the pairs that hold two points farther apart along the rod than the
        exclusion window (the candidates also hold closer pairs, for the local barrier)."""
        same, seps, _, _, excl = self.window_separations(pr, ar)
        return ~same | (seps.max(axis=1) >= excl)
