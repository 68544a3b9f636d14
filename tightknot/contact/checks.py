"""Checks of a state against the contact layer: no segments through each other, and the
smallest non-local distance.

Both measure segment distances of the candidate pairs (the step bound's kernel at a zero
step) and judge them by the exclusion window along the rest arcs.
"""

from __future__ import annotations

import math

import numpy as np
import warp as wp

from tightknot.contact.broad_phase import BroadPhase
from tightknot.contact.step_bound import StepBound


class SelfIntersectionError(ValueError):
    """The rods already pass through each other (closer than the hard limit)."""


class ContactChecks:
    """Intersection check and non-local distances of a layer's edges.

    Args:
        broad: the layer's broad phase.
        step_bound: the layer's step bound (its kernel measures the distances).
        hard_fraction: hard limit over the rest diameter [-] (for the messages).
    """

    def __init__(self, broad: BroadPhase, step_bound: StepBound, hard_fraction: float) -> None:
        self.broad = broad
        self.step_bound = step_bound
        self.hard_fraction = float(hard_fraction)

    def pair_distances(self, x: np.ndarray, rest: np.ndarray, margin: wp.array
                       ) -> tuple[np.ndarray, ...]:
        """Candidate edge pairs within ``margin`` [m] bounds (per edge) at
        positions ``x`` [m], their segment distances [m] and the rest arcs [m] of the edges
        (for edge rest lengths ``rest`` [m])."""
        broad = self.broad
        wx = broad.x_in.put(x)
        arcs, rod_len = broad.arcs(rest)
        pairs = broad.candidates(wx, broad.zero_dx, margin, arcs, rod_len)
        n = pairs.shape[0]
        if n == 0:
            return np.zeros((0, 2), dtype=np.int32), np.zeros(0), arcs.numpy()
        self.step_bound.pair_bounds(wx, broad.zero_dx, pairs, arcs, rod_len)
        return pairs.numpy(), self.step_bound.distances(n), arcs.numpy()

    def check_no_intersection(self, x: np.ndarray, rest: np.ndarray) -> None:
        """Refuse positions ``x`` [m] whose non-local segments are closer than the hard
        limit, saying where (rest arc lengths of the offending pair, for edge rest lengths
        ``rest`` [m])."""
        pr, d, ar = self.pair_distances(x, rest, self.step_bound.half_hard)
        if not d.size:
            return
        dh = self.step_bound.edge_hard
        hard = np.maximum(dh[pr[:, 0]], dh[pr[:, 1]])
        bad = np.flatnonzero(d < hard)
        if bad.size:
            k = bad[np.argmin(d[bad] / hard[bad])]
            a, b = pr[k]
            raise SelfIntersectionError(
                f"the rods intersect themselves: edges {a} and {b} (rest arc lengths "
                f"{ar[a][0]:.6g}..{ar[a][1]:.6g} m and {ar[b][0]:.6g}..{ar[b][1]:.6g} m) are "
                f"{d[k]:.4g} m apart, below the hard limit {hard[k]:.4g} m "
                f"({self.hard_fraction:g} D)")

    def window_closest(self, x: np.ndarray, pr: np.ndarray, ar: np.ndarray,
                       grid: int = 17) -> tuple[np.ndarray, ...]:
        """For the pairs of one rod that straddle the exclusion window: their indices in
        ``pr``, and the distance [m] and parameters (s, t) on the two edges of their closest
        point pair among those farther apart along the rod than the window (on a ``grid``
        x ``grid`` set of point pairs; inf and 0.5 where none is): the whole segments'
        closest points would be those of a tight bend's neighbouring points on a coarse
        mesh. ``ar``: the arcs the window is judged by (:meth:`BroadPhase.arcs`)."""
        m = self.broad.model
        same, seps, length, closed, excl = self.broad.window_separations(pr, ar)
        a, b = ar[pr[:, 0]], ar[pr[:, 1]]
        partial = np.flatnonzero(same & (seps.min(axis=1) < excl))
        d = np.full(partial.size, math.inf)
        s = np.full(partial.size, 0.5)
        tt = np.full(partial.size, 0.5)
        u = np.linspace(0.0, 1.0, grid)
        ev = m.edge_vertex
        for i, k in enumerate(partial):
            ea, eb = pr[k]
            pa = x[ev[ea, 0]] + u[:, None] * (x[ev[ea, 1]] - x[ev[ea, 0]])
            pb = x[ev[eb, 0]] + u[:, None] * (x[ev[eb, 1]] - x[ev[eb, 0]])
            sa = a[k, 0] + u * (a[k, 1] - a[k, 0])
            sb = b[k, 0] + u * (b[k, 1] - b[k, 0])
            sep = np.abs(sa[:, None] - sb[None, :])
            if closed[k]:
                sep = np.minimum(sep, length[k] - sep)
            dist = np.where(sep >= excl[k], np.linalg.norm(pa[:, None, :] - pb[None, :, :],
                                                            axis=2), math.inf)
            j = int(np.argmin(dist))
            d[i] = dist.flat[j]
            s[i], tt[i] = u[j // grid], u[j % grid]
        return partial, d, s, tt

    def beyond_window(self, x: np.ndarray, pr: np.ndarray, d: np.ndarray, ar: np.ndarray,
                      grid: int = 17) -> np.ndarray:
        """Distances ``d`` [m] of pairs ``pr``, those of the pairs straddling the exclusion
        window measured only between their points farther apart along the rod than the
        window (:meth:`window_closest`)."""
        partial, dp, _, _ = self.window_closest(x, pr, ar, grid)
        if not partial.size:
            return d
        d = d.copy()
        d[partial] = dp
        return d

    def min_distance(self, x: np.ndarray, rest: np.ndarray) -> tuple[float, int, int]:
        """Smallest non-local segment distance [m] among pairs within the interaction
        range at positions ``x`` [m] and edge rest lengths ``rest`` [m], and its edge pair
        (inf, -1, -1 when none)."""
        pr, d, ar = self.pair_distances(x, rest, self.broad.interaction_margin)
        if d.size:
            keep = self.broad.nonlocal_mask(pr, ar)
            pr, d = pr[keep], d[keep]
        if d.size:
            d = self.beyond_window(x, pr, d, ar)
        if not d.size:
            return math.inf, -1, -1
        k = int(np.argmin(d))
        return float(d[k]), int(pr[k][0]), int(pr[k][1])


def deepest_approaches(layer: object, x: np.ndarray, rest: np.ndarray
                       ) -> tuple[float, float]:
    """The largest per-side approach w = delta/2 [m] of the pairs of ``layer`` (a
    :class:`tightknot.contact.layer.ContactLayer`) at positions ``x`` [m] and edge rest
    lengths ``rest`` [m], among parallel pairs (crossing angle below the law's
    ``angle_line_deg``: line contact) and among crossing pairs (point contact, or the
    blend toward it); 0 where none touches. The overlaps are the pair kernel's, of the
    nominal stretched sections (at the sectioned level: how far the sections flatten)."""
    layer.energy.evaluate(x, rest, False, False)
    pairs, overlap = layer.last_pairs, layer.last_overlap
    touch = overlap > 0.0
    if not touch.any():
        return 0.0, 0.0
    pr, w = pairs[touch], 0.5 * overlap[touch]
    ev = layer.model.edge_vertex
    ta = x[ev[pr[:, 0], 1]] - x[ev[pr[:, 0], 0]]
    tb = x[ev[pr[:, 1], 1]] - x[ev[pr[:, 1], 0]]
    cos = np.abs(np.einsum("ij,ij->i", ta, tb)) / (np.linalg.norm(ta, axis=1)
                                                    * np.linalg.norm(tb, axis=1))
    line = cos >= math.cos(math.radians(layer.law.angle_line_deg))
    return (float(w[line].max(initial=0.0)), float(w[~line].max(initial=0.0)))
