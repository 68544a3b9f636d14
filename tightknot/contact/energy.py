"""The contact energy term: detection, the pair kernel, and the stretch-smoothed radius.

At each evaluation the broad phase (:mod:`tightknot.contact.broad_phase`) finds the
candidate pairs at the positions, and the pair kernel (:mod:`tightknot.contact.pair_kernel`)
gives their energies, the gradient and the Hessian, as COO triplets over global dofs or
added into the system's CSC data. With a radius window the contact radius is the smoothed
one (:mod:`tightknot.contact.section_radius`), given to the kernel; its chain rule adds a
gradient term and Hessian terms that couple whole windows. Thinned by each rod's mean
stretch (:mod:`tightknot.contact.rod_mean_radius`) the radius is given to the kernel too;
its chain rule adds a gradient term, terms in the edges' stretch blocks and a dense update
of low rank.
"""

from __future__ import annotations

import numpy as np
import warp as wp

from tightknot.contact.broad_phase import BroadPhase
from tightknot.contact.pair_kernel import Hessian, PairKernel, PairTerms
from tightknot.contact.rod_mean_radius import RodMeanRadius
from tightknot.contact.section_radius import SmoothedRadius
from tightknot.rods.model import Model
from tightknot.rods.staging import Staging


def pair_blocks(edge_vertex: np.ndarray, pairs: np.ndarray, vertex_count: int) -> np.ndarray:
    """Keys vr * V + vc of the 16 vertex blocks of each edge pair (a, b)."""
    ev = edge_vertex.astype(np.int64)
    verts = np.concatenate([ev[pairs[:, 0]], ev[pairs[:, 1]]], axis=1)  # (P, 4)
    return (verts[:, :, None] * vertex_count + verts[:, None, :]).ravel()


class ContactEnergy:
    """The energy of a model's contacts, with its gradient and Hessian.

    Args:
        model: the rods.
        broad: the layer's broad phase.
        kernel: the pair kernel's launcher.
        smooth: the smoothed contact radius (None: each edge's own stretch thins it).
        mean: the radius thinned by each rod's mean stretch (None: not; not with
            ``smooth``).
    """

    def __init__(self, model: Model, broad: BroadPhase, kernel: PairKernel,
                 smooth: SmoothedRadius | None, mean: RodMeanRadius | None = None) -> None:
        if smooth is not None and mean is not None:
            raise ValueError("a contact radius is smoothed over a window or thinned by the "
                             "rod's mean stretch, not both")
        self.model = model
        self.broad = broad
        self.kernel = kernel
        self.smooth = smooth
        self.mean = mean
        given = smooth is not None or mean is not None
        self._in_radius = Staging(wp.float64, model.device) if given else None
        #: Candidate pairs (P, 2) of the last evaluation and their overlaps [m] (P,).
        self.last_pairs = np.zeros((0, 2), dtype=np.int32)
        self.last_overlap = np.zeros(0)
        #: Edge rest lengths [m] of the last evaluation (the load path changes them).
        self.last_rest = model.edge_rest_length.copy()
        self._missing_pairs = np.zeros((0, 2), dtype=np.int64)

    # -- one launch ------------------------------------------------------------------------
    def launch(self, x: np.ndarray, rest: np.ndarray, gradient: bool, hessian: Hessian,
               tables: tuple[wp.array, ...] | None = None, csc: wp.array | None = None,
               radius: wp.array | None = None) -> PairTerms:
        """Detect and evaluate every candidate pair at positions ``x`` [m] and edge rest
        lengths ``rest`` [m] (see :meth:`PairKernel.launch`), and remember the pairs."""
        broad = self.broad
        self.last_rest = np.array(rest, dtype=np.float64)
        wx = broad.x_in.put(x)
        arcs, rod_len = broad.arcs(rest)
        pairs = broad.candidates(wx, broad.zero_dx, broad.interaction_margin, arcs, rod_len)
        out = self.kernel.launch(wx, pairs, rest, arcs, rod_len, gradient, hessian, tables,
                                 csc, radius)
        self.remember(out.pairs, out.overlap)
        return out

    def remember(self, pairs: wp.array, overlap: np.ndarray) -> None:
        """Keep ``pairs`` and their ``overlap`` [m] as the last evaluation's."""
        self.last_pairs = pairs.numpy().astype(np.int64) if pairs.shape[0] else np.zeros(
            (0, 2), dtype=np.int64)
        self.last_overlap = overlap.copy()

    # -- the energy term -------------------------------------------------------------------
    def evaluate(
        self, x: np.ndarray, rest: np.ndarray, want_grad: bool = True, want_hess: bool = True
    ) -> tuple[float, np.ndarray | None, tuple[np.ndarray, np.ndarray, np.ndarray] | None]:
        """Contact energy [J], gradient over vertex positions (N, 3) [N], Hessian COO
        triplets over global dofs."""
        m = self.model
        geo = self._geometry(x, rest)
        out = self.launch(x, rest, want_grad, Hessian(int(want_hess)),
                          radius=self._radius_array(geo))
        e_pair = out.energy
        if out.pairs.shape[0] == 0:
            empty = (np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0))
            return 0.0, (np.zeros((m.vertex_count, 3)) if want_grad else None), (
                empty if want_hess else None)
        e = float(e_pair.sum())
        g = out.grad.numpy().copy() if want_grad else None
        coo = None
        if want_hess:
            # Only pairs that interact carry a Hessian (most candidates do not).
            active = np.flatnonzero(e_pair != 0.0)
            npairs = active.size
            hvals = out.hess.numpy().reshape(-1, 144)[active].ravel()
            dofs = self.pair_dofs(self.last_pairs[active])
            rows = np.broadcast_to(dofs[:, :, None], (npairs, 12, 12)).ravel()
            cols = np.broadcast_to(dofs[:, None, :], (npairs, 12, 12)).ravel()
            coo = (rows, cols, hvals)
        if geo is not None and (want_grad or want_hess):
            if self.mean is not None:
                g_s, h_s, low = self._mean_terms(geo, e_pair, want_hess)
                if h_s is not None and low is not None:
                    # Dense here (tests and diagnostics; the solver keeps it low-rank).
                    h_s = _with_dense(h_s, *low)
            else:
                g_s, h_s = self._smoothed_terms(geo, e_pair, want_hess)
            if g is not None:
                g += g_s
            if coo is not None:
                coo = tuple(np.concatenate([u, v]) for u, v in zip(coo, h_s, strict=True))
        return e, g, coo

    def evaluate_into(self, x: np.ndarray, rest: np.ndarray, tables: tuple[wp.array, ...],
                      data: wp.array) -> tuple:
        """Energy [J] and gradient (N, 3) [N]; the Hessian is added into ``data``, the CSC
        data array of the system's pattern (zeroed by the caller), through its block
        ``tables`` (:meth:`tightknot.solvers.pattern.ContactPattern.warp_tables`). Blocks of
        new contacts missing from the tables are signalled by None for the gradient: the
        caller grows its pattern by :meth:`missing_blocks` and calls again. With a radius
        window a third item holds the Hessian terms of the smoothed radius (COO over global
        dofs), which couple whole windows and so lie outside the pair blocks; with the
        rod's mean stretch a third item holds the terms in the edges' stretch blocks (COO)
        and a fourth the dense update (U, C) over global dofs, or None
        (:mod:`tightknot.contact.rod_mean_radius`)."""
        geo = self._geometry(x, rest)
        out = self.launch(x, rest, True, Hessian.CSC, tables, data,
                          radius=self._radius_array(geo))
        e_pair = out.energy
        if int(out.missing.numpy()[0]) > 0:
            self._missing_pairs = self.last_pairs[e_pair != 0.0]
            return float(e_pair.sum()), None
        g = out.grad.numpy().copy()
        if geo is None:
            return float(e_pair.sum()), g
        if self.mean is not None:
            g_s, h_s, low = self._mean_terms(geo, e_pair, True)
            return float(e_pair.sum()), g + g_s, h_s, low
        g_s, h_s = self._smoothed_terms(geo, e_pair, True)
        return float(e_pair.sum()), g + g_s, h_s

    def missing_blocks(self) -> np.ndarray:
        """Vertex-block keys of the interacting pairs of the last :meth:`evaluate_into` that
        found a block missing from the tables."""
        return pair_blocks(self.model.edge_vertex, self._missing_pairs, self.model.vertex_count)

    def active_blocks(self) -> np.ndarray:
        """Vertex-block keys of the pairs that interacted at the last evaluation."""
        active = self.last_pairs[self.last_overlap > 0.0]
        return pair_blocks(self.model.edge_vertex, active, self.model.vertex_count)

    def pair_dofs(self, pairs: np.ndarray) -> np.ndarray:
        """The 12 position dofs of each edge pair's vertices [a0, a1, b0, b1], (P, 12)."""
        m = self.model
        ev = m.edge_vertex.astype(np.int64)
        verts = np.concatenate([ev[pairs[:, 0]], ev[pairs[:, 1]]], axis=1)  # (P, 4)
        return (m.vertex_dof.astype(np.int64)[verts][:, :, None] + np.arange(3)).reshape(-1, 12)

    # -- the stretch-smoothed radius (radius_window > 0) ----------------------------------
    def section_stretch(self, x: np.ndarray, rest: np.ndarray) -> np.ndarray:
        """The stretch that thins each edge's section [-]: its own, or the window mean."""
        if self.smooth is not None:
            return self.smooth.stretch(x, np.asarray(rest, dtype=np.float64))
        if self.mean is not None:
            return self.mean.stretch(x, rest)
        ev = self.model.edge_vertex
        return np.linalg.norm(x[ev[:, 1]] - x[ev[:, 0]], axis=1) / rest

    def _geometry(self, x: np.ndarray, rest: np.ndarray) -> dict[str, np.ndarray] | None:
        """Tangents, lengths, given radii and their derivatives (None: each edge's own)."""
        if self.mean is not None:
            return self.mean.radii(x, rest)
        if self.smooth is None:
            return None
        return self.smooth.radii(x, np.asarray(rest, dtype=np.float64))

    def _radius_array(self, geo: dict[str, np.ndarray] | None) -> wp.array | None:
        return None if geo is None else self._in_radius.put(geo["rho"])

    def _smoothed_terms(self, geo: dict[str, np.ndarray], e_pair: np.ndarray,
                        want_hess: bool) -> tuple[np.ndarray, tuple | None]:
        """The smoothed radius's gradient term (V, 3) [N] and Hessian COO (or None)."""
        active = np.flatnonzero(e_pair != 0.0)
        pr = self.last_pairs[active]
        d_r = self.kernel.radius_derivatives(e_pair.size)[active]
        g, big_g, c = self.smooth.gradient(geo, pr, d_r[:, 0])
        if not want_hess:
            return g, None
        return g, self.smooth.hessian(geo, pr, self.pair_dofs(pr), d_r[:, 1], d_r[:, 2:],
                                      big_g, c)

    def _mean_terms(self, geo: dict[str, np.ndarray], e_pair: np.ndarray, want_hess: bool
                    ) -> tuple[np.ndarray, tuple | None, tuple | None]:
        """The mean-stretch radius's gradient term (V, 3) [N], its Hessian terms in the
        edges' stretch blocks (COO over global dofs) and its low-rank update (U, C) or
        None; both Hessian items None without ``want_hess``."""
        active = np.flatnonzero(e_pair != 0.0)
        pr = self.last_pairs[active]
        d_r = self.kernel.radius_derivatives(e_pair.size)[active]
        mean = self.mean
        g, big_g = mean.gradient(geo, pr, d_r[:, 0])
        if not want_hess:
            return g, None, None
        blk = mean.stretch_blocks(geo, big_g)
        ed = mean.edge_dofs
        coo = (np.repeat(ed, 6, axis=1).ravel(), np.tile(ed, (1, 6)).ravel(), blk.ravel())
        low = mean.low_rank(geo, pr, self.pair_dofs(pr), d_r[:, 0], d_r[:, 1], d_r[:, 2:])
        return g, coo, low


def _with_dense(coo: tuple[np.ndarray, np.ndarray, np.ndarray], u: np.ndarray,
                c: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """COO triplets ``coo`` with the dense U C U^T added on the rows where U is not zero."""
    rows = np.flatnonzero(np.any(u != 0.0, axis=1))
    ur = u[rows]
    dense = ur @ c @ ur.T
    r = np.repeat(rows, rows.size)
    k = np.tile(rows, rows.size)
    return (np.concatenate([coo[0], r]), np.concatenate([coo[1], k]),
            np.concatenate([coo[2], dense.ravel()]))
