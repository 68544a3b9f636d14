"""One evaluation of many independent rods: one set of Warp launches, an answer per rod.

The rods of a batch (:func:`tightknot.loading.batch.build_batch`) sit in one model, far
apart, so their energies, gradients and Hessians are independent. Each rod runs its own
Newton loop (:mod:`tightknot.solvers.lockstep`) and asks, at its own point, for its
energy (with gradient and Hessian or not) or for its largest collision-free step; the
driver gathers the questions of all rods and answers them here with one launch of each
kernel over the whole model.

What makes the answer per rod cheap, whatever the number of rods:

* energies: the kernels write one energy per edge, joint and contact pair; they are
  summed per rod (the model stores rods one after another);
* Hessians: each rod keeps its own CSC pattern (elastic stencils plus the contact vertex
  blocks, :class:`tightknot.solvers.pattern.ContactPattern` on the rod's own
  model) in its own region of one data array; the elastic and contact kernels add straight
  into that region (their slot maps and block tables are the rods' own, shifted), so a rod
  reads its Hessian as a contiguous slice. A new contact grows only that rod's pattern:
  one joint pattern grew and was rebuilt (all rods' entries) whenever any rod touched
  somewhere new, which made the last implementation's iterations cost more per rod than
  one rod alone;
* step bounds: the contact layer's swept-segment bound per candidate pair, reduced to a
  minimum per rod.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Iterator
from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp
import warp as wp

from tightknot.contact.broad_phase import BroadPhase
from tightknot.contact.layer import ContactLayer, pair_blocks
from tightknot.contact.pair_kernel import Hessian
from tightknot.rods import elastic_kernels as ek
from tightknot.rods.elastic import ElasticForces
from tightknot.rods.model import Model
from tightknot.solvers.pattern import ContactPattern, SparsePattern


class BatchBroadPhase(BroadPhase):
    """The broad phase of a batch model, whose candidates may be kept to chosen rods (a rod
    that asked nothing this round costs no pair evaluation), and reused from the last
    detection when the same positions are evaluated again for some rods."""

    #: Rods whose candidate pairs are kept (None: all).
    rod_mask: np.ndarray | None = None
    #: Candidate pairs of the last stored detection (host).
    _last_candidates: np.ndarray | None = None
    _reuse: bool = False
    _store: bool = False

    @contextlib.contextmanager
    def only(self, rods: np.ndarray, reuse: bool = False, store: bool = False
             ) -> Iterator[None]:
        """Within the block, the candidates of the rods in mask ``rods`` only; ``reuse``:
        those of the last stored detection instead of a new one; ``store``: store this
        detection's."""
        self.rod_mask, self._reuse, self._store = rods, reuse, store
        try:
            yield
        finally:
            self.rod_mask = None
            self._reuse = self._store = False

    def arcs_of(self, rest: np.ndarray) -> tuple[wp.array, wp.array]:
        # The base class loops over the rods in Python, each time the rest lengths change.
        # Rods of one edge count: one cumulative sum along each row of a (rods, edges)
        # view, the same additions in the same order as the loop.
        m = self.model
        counts = {r.edge_count for r in m.rods}
        if len(counts) != 1:
            return super().arcs_of(rest)
        le = np.ascontiguousarray(rest, dtype=np.float64).reshape(len(m.rods), -1)
        s1 = np.cumsum(le, axis=1)
        arcs = np.stack([(s1 - le).ravel(), s1.ravel()], axis=1)
        return (wp.array(arcs, dtype=wp.vec2d, device=self.device),
                wp.array(np.ascontiguousarray(s1[:, -1]), dtype=wp.float64,
                         device=self.device))

    def candidates(self, wx: wp.array, wdx: wp.array, margin: wp.array, arcs: wp.array,
                   rod_len: wp.array, window: float | None = None) -> wp.array:
        if self._reuse:
            pn = self._last_candidates
        else:
            pairs = super().candidates(wx, wdx, margin, arcs, rod_len, window)
            if self.rod_mask is None:
                return pairs
            pn = pairs.numpy()
            if self._store:
                self._last_candidates = pn.copy()
        keep = self.rod_mask[self.model.edge_rod[pn[:, 0]]]
        return wp.array(np.ascontiguousarray(pn[keep]).reshape(-1, 2), dtype=wp.vec2i,
                        device=self.device)


class BatchContactLayer(ContactLayer):
    """The contact layer of a batch model, with per-pair energies and per-rod step bounds
    (the base class sums them over the whole model), evaluated on the pairs of chosen rods
    only."""

    broad_phase_class = BatchBroadPhase

    def pair_terms(self, x: np.ndarray, rest: np.ndarray, rods: np.ndarray,
                   tables: tuple[wp.array, ...], csc: wp.array, again: bool = False,
                   geo: dict[str, np.ndarray] | None = None
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, wp.array, int]:
        """Candidate pairs (P, 2) of the rods in mask ``rods``, their energies [J] and
        overlaps [m] (P,), the gradient over vertex positions (Warp, (V, 3)) [N] and the
        count of Hessian blocks missing from ``tables`` (the Hessian is added into
        ``csc``). ``again``: the same positions as the last call, whose candidate pairs
        are reused (no new detection). ``geo``: the given contact radii of a rod-mean
        thinning (:meth:`mean_geometry`; then the pairs' radius derivatives are in the
        kernel's :meth:`~tightknot.contact.pair_kernel.PairKernel.radius_derivatives`)."""
        radius = None if geo is None else self.energy._in_radius.put(geo["rho"])
        with self.broad_phase.only(rods, reuse=again, store=not again):
            out = self.energy.launch(x, rest, True, Hessian.CSC, tables, csc, radius)
        return self.last_pairs, out.energy, out.overlap, out.grad, int(out.missing.numpy()[0])

    def mean_geometry(self, x: np.ndarray, rest: np.ndarray) -> dict[str, np.ndarray] | None:
        """The radii of a rod-mean thinning at positions ``x`` [m] and rest lengths
        ``rest`` [m] (:meth:`RodMeanRadius.radii`), None for an edge's own stretch."""
        mean = self.energy.mean
        return None if mean is None else mean.radii(x, rest)

    def step_bounds(self, x: np.ndarray, dx: np.ndarray, rest: np.ndarray,
                    rods: np.ndarray) -> np.ndarray:
        """Largest fraction in [0, 1] of the step ``dx`` [m] of each rod in mask ``rods``
        that keeps its segment pairs sharing no vertex at least their floor apart (as
        :meth:`max_step`), at edge rest lengths ``rest`` [m]."""
        bp = self.broad_phase
        wx = bp.x_in.put(x)
        wdx = bp.dx_in.put(dx)
        arcs, rod_len = bp.arcs(rest)
        with bp.only(rods):
            pairs = bp.candidates(wx, wdx, self.step_bound.half_hard, arcs, rod_len,
                                  window=0.0)
        out = np.ones(len(rods))
        n = pairs.shape[0]
        if n == 0:
            return out
        alpha = self.step_bound.pair_bounds(wx, wdx, pairs, arcs, rod_len)
        rod = self.model.edge_rod[pairs.numpy()[:, 0]]
        np.minimum.at(out, rod, np.clip(alpha, 0.0, 1.0))
        return out


def batch_contact_layer(model: Model, like: ContactLayer) -> BatchContactLayer:
    """A :class:`BatchContactLayer` on ``model`` with the settings of ``like``."""
    if like.radius_window > 0.0:
        # Its Hessian couples whole windows of the rod: not the banded per-rod systems of
        # the batch (tightknot.contact.section_radius).
        raise ValueError(f"the batch does not support a contact layer with radius_window > 0 "
                         f"(got {like.radius_window:g} D0): tie these scenes one by one")
    # The batch's exclusion factor is the first edge's window over its diameter, as it has
    # always been (for most diameters the factor itself, bit for bit).
    settings = replace(like.settings,
                       exclusion_factor=float(like.exclusion[0] / like.edge_diameter[0]))
    return BatchContactLayer(model, like.law, **settings.as_kwargs())


@dataclass
class EvalRequest:
    """A rod's question: its energy at ``x``, ``theta`` (frames carried from the base ones).

    Attributes:
        rod: rod index in the batch.
        x: positions in the rod's own frame [m], (n, 3).
        theta: twist angles [rad], (edges,).
        d1_base, t_base, m_ref_base: the accepted frames the trial frames are carried from.

    Every answer holds the gradient and the Hessian too: a rod asks for the energy of a
    trial point mostly to accept it and then needs both there, so they come in the same
    round (one round per Newton iteration instead of two).
    """

    rod: int
    x: np.ndarray
    theta: np.ndarray
    d1_base: np.ndarray
    t_base: np.ndarray
    m_ref_base: np.ndarray


@dataclass(frozen=True)
class HessianData:
    """A rod's Hessian as evaluated: CSC structure (the rod's pattern at that moment; a
    later evaluation may grow the pattern, never these arrays) and entries.

    Attributes:
        indptr, indices: CSC structure over the rod's free dofs.
        diag_slot: data slot of each diagonal entry.
        data: the entries [N/m, N, N m].
    """

    indptr: np.ndarray
    indices: np.ndarray
    diag_slot: np.ndarray
    data: np.ndarray

    def matrix(self, data: np.ndarray | None = None) -> sp.csc_matrix:
        """The CSC matrix (with ``data`` instead of the evaluated entries if given; the
        evaluated one is built once)."""
        n = len(self.indptr) - 1
        if data is not None:
            return sp.csc_matrix((data, self.indices, self.indptr), shape=(n, n))
        m = self.__dict__.get("_matrix")
        if m is None:
            m = sp.csc_matrix((self.data, self.indices, self.indptr), shape=(n, n))
            object.__setattr__(self, "_matrix", m)
        return m

    def diagonal(self) -> np.ndarray:
        """The diagonal entries (every one is stored)."""
        return self.data[self.diag_slot]


@dataclass
class EvalAnswer:
    """Energy parts [J], gradient over the rod's own dofs [N, N m], Hessian, the frames
    carried to the trial point, and the contact's low-rank Hessian update (U over the rod's
    free dofs, C) of a rod-mean thinning (None without one, or without contact)."""

    stretch: float
    bend: float
    twist: float
    contact: float
    grad: np.ndarray
    hess: HessianData
    d1: np.ndarray
    t: np.ndarray
    m_ref: np.ndarray
    low_rank: tuple[np.ndarray, np.ndarray] | None = None


@dataclass
class StepRequest:
    """A rod's question: the largest fraction of the move ``dx`` [m] from ``x`` [m]."""

    rod: int
    x: np.ndarray
    dx: np.ndarray


class _RodLayout:
    """Where rod k's entries live: its ranges in the joint model, its own patterns and its
    regions of the joint Hessian data (elastic: fixed; contact: moves with its pattern)."""

    def __init__(self, model: Model, k: int, own: SparsePattern, own_model: Model) -> None:
        info = model.rods[k]
        self.v0, self.nv = info.vertex_start, info.vertex_count
        self.e0, self.ne = info.edge_start, info.edge_count
        self.j0, self.nj = info.joint_start, info.joint_count
        self.dof0 = int(model.vertex_dof[info.vertex_start])
        self.ndof = own_model.dof_count
        self.pattern = own
        self.cpattern = ContactPattern(own_model, own)
        self.elastic_offset = 0
        self.offset = 0
        self.capacity = 0
        self.dirty = True


class BatchEvaluator:
    """Energies, gradients, Hessians and step bounds of the rods of a batch model.

    The elastic kernels add their Hessian entries into one array holding each rod's
    elastic pattern (fixed: its stencils and free dofs); the contact kernel adds into
    another holding each rod's contact pattern (elastic pattern plus contact blocks, as
    RodSystem assembles it), where a rod's region moves only when its pattern outgrows its
    room. A rod's Hessian is its contact region plus its elastic entries (the one-rod
    assembly, in the same order). A contact new to a rod's pattern re-runs the contact
    kernel on that rod's pairs only.

    Args:
        model: the batch model (rods one after another).
        layer: its contact layer.
        offsets: translation of each rod in the batch [m], (rods, 3).
        rod_models: each rod's own one-rod model (same layout as its part of ``model``).
        patterns: each rod's free-dof pattern on its own model.
    """

    #: Spare room of a rod's contact region, over its entries, so that new contacts
    #: rarely move the other rods' regions.
    HEADROOM = 1.5
    #: Gap [D0] below which a pair's blocks join a growing pattern (see _grow).
    GROW_GAP = 0.05

    def __init__(self, model: Model, layer: BatchContactLayer, offsets: np.ndarray,
                 rod_models: list[Model], patterns: list[SparsePattern]) -> None:
        self.model = model
        self.layer = layer
        self.device = model.device
        self.offsets = np.asarray(offsets, dtype=np.float64)
        n_rods = len(model.rods)
        self.rods = [_RodLayout(model, k, patterns[k], rod_models[k]) for k in range(n_rods)]
        for k, r in enumerate(self.rods):
            if r.ndof != (model.vertex_dof[r.v0 + r.nv - 1] + (4 if model.twist else 3)
                          - r.dof0) or r.nv != rod_models[k].vertex_count:
                raise ValueError(f"rod {k}'s own model does not match its part of the batch")
        self.forces = ElasticForces(model)
        dev = self.device
        self.x = model.vertex_initial_position.copy()
        self.theta = np.zeros(model.edge_count)
        self.d1 = np.zeros((model.edge_count, 3))
        self.t = np.zeros((model.edge_count, 3))
        self.m_ref = np.zeros(model.joint_count)
        self.rest = model.edge_rest_length.copy()
        self._e_stretch = wp.zeros(model.edge_count, dtype=wp.float64, device=dev)
        self._e_bend = wp.zeros(model.joint_count, dtype=wp.float64, device=dev)
        self._e_twist = wp.zeros(model.joint_count, dtype=wp.float64, device=dev)
        self._grad = wp.zeros(model.dof_count, dtype=wp.float64, device=dev)
        self._empty_f = wp.zeros(1, dtype=wp.float64, device=dev)
        # Elastic slot maps: each rod's own, shifted to its region (fixed for the run).
        jslot = np.full((model.joint_count, 121), -1, dtype=np.int32)
        eslot = np.full((model.edge_count, 36), -1, dtype=np.int32)
        off = 0
        for r in self.rods:
            r.elastic_offset = off
            js, es = r.pattern.joint_slot, r.pattern.edge_slot
            jslot[r.j0 : r.j0 + r.nj] = np.where(js >= 0, js + off, -1)
            eslot[r.e0 : r.e0 + r.ne] = np.where(es >= 0, es + off, -1)
            off += r.pattern.nnz
        self._wjslot = wp.array(jslot, dtype=wp.int32, device=dev)
        self._weslot = wp.array(eslot, dtype=wp.int32, device=dev)
        self._eslot = eslot
        self._edata = wp.zeros(max(off, 1), dtype=wp.float64, device=dev)
        self._tables = None
        self._cdata = None
        ranks = np.concatenate([r.cpattern.vertex_rank for r in self.rods])
        self._wrank = wp.array(np.ascontiguousarray(ranks), dtype=wp.vec3i, device=dev)
        self._edge_starts = np.array([r.e0 for r in self.rods])
        self._joint_starts = np.array([r.j0 for r in self.rods])
        self._touching: list[np.ndarray] = [np.zeros((0, 2), dtype=np.int64)] * n_rods
        self.relayouts = 0
        self.contact_reruns = 0
        self._layout(full=True)

    # -- per-rod state ---------------------------------------------------------------------
    def set_rest(self, k: int, rest: np.ndarray) -> None:
        """Edge rest lengths of rod k at its load step [m]."""
        r = self.rods[k]
        self.rest[r.e0 : r.e0 + r.ne] = rest

    def set_window(self, k: int, x: np.ndarray, edge_vertex: np.ndarray) -> None:
        """Rod k's exclusion window at its load step, from its positions ``x`` [m] (its own
        frame; ``edge_vertex``: its own model's edges) and rest lengths (as
        :meth:`tightknot.contact.layer.ContactLayer.begin_load_step`)."""
        r = self.rods[k]
        lengths = np.linalg.norm(x[edge_vertex[:, 1]] - x[edge_vertex[:, 0]], axis=1)
        edges = slice(r.e0, r.e0 + r.ne)
        scale = self.layer.broad_phase.window_scale.copy()
        scale[edges] = self.layer.window_scale(lengths, self.rest[edges], edges)
        self.layer.broad_phase.window_scale = scale

    def compact(self, k: int) -> None:
        """Drop rod k's contact blocks that no longer interact (at its new load step, as
        :meth:`tightknot.solvers.system.RodSystem.compact_pattern`)."""
        r = self.rods[k]
        keep = np.unique(self._local_blocks(k, self._touching[k]))
        # Rebuilding a pattern costs more than the fill of a few stale blocks in the
        # factorization, so the pattern is rebuilt when at least a quarter of its blocks
        # went stale, not at every load step.
        if keep.size >= 0.75 * r.cpattern.block_keys.size:
            return
        r.cpattern.reset(keep)
        r.dirty = True

    def _local_blocks(self, k: int, pairs: np.ndarray) -> np.ndarray:
        """Rod k's own block keys of joint edge pairs of rod k."""
        r = self.rods[k]
        keys = pair_blocks(self.model.edge_vertex, pairs, self.model.vertex_count)
        nv = self.model.vertex_count
        vr, vc = keys // nv - r.v0, keys % nv - r.v0
        return vr * r.nv + vc

    # -- layout of the contact Hessian data -----------------------------------------------
    def _layout(self, full: bool = False) -> bool:
        """Rebuild the block tables after patterns changed; place the rods' contact regions
        anew (returns True) when one outgrew its room."""
        rods = self.rods
        if not full and any(r.cpattern.nnz > r.capacity for r in rods if r.dirty):
            full = True
        if full:
            off = 0
            for r in rods:
                r.offset = off
                r.capacity = int(math.ceil(self.HEADROOM * r.cpattern.nnz)) + 64
                off += r.capacity
            self._cdata = wp.zeros(off, dtype=wp.float64, device=self.device)
            self.relayouts += 1
        for r in rods:
            r.dirty = False
        dev = self.device
        nv = self.model.vertex_count
        keys, cols = [], []
        for r in rods:
            cp = r.cpattern
            vr, vc = cp.block_keys // r.nv + r.v0, cp.block_keys % r.nv + r.v0
            keys.append(vr * nv + vc)
            cols.append(np.where(cp.block_cols >= 0, cp.block_cols + r.offset, -1))
        k_all = np.concatenate(keys)
        c_all = np.concatenate(cols).astype(np.int32)
        self._keys = k_all if k_all.size else np.full(1, -1, np.int64)
        # Row ranges of the table (as ContactPattern.warp_tables): row vr's keys are
        # keys[rows[vr]:rows[vr + 1]].
        rows = np.searchsorted(k_all, np.arange(nv + 1, dtype=np.int64) * nv)
        if not k_all.size:
            k_all = np.full(1, -1, np.int64)
            c_all = np.full((1, 3), -1, np.int32)
        self._tables = (wp.array(k_all, dtype=wp.int64, device=dev),
                        wp.array(rows.astype(np.int32), dtype=wp.int32, device=dev),
                        wp.array(np.ascontiguousarray(c_all), dtype=wp.vec3i, device=dev),
                        self._wrank)
        return full

    def _grow(self, pairs: np.ndarray, e_pair: np.ndarray, overlap: np.ndarray) -> np.ndarray:
        """Grow the patterns of the rods whose interacting pairs lack blocks; their mask.

        Such a rod also takes the blocks of its pairs less than ``GROW_GAP`` D0 from
        touching: a tightening knot's contacts spread to neighbouring pairs one
        evaluation after another, and each growth costs a pattern rebuild and a second
        contact launch. (The blocks of all candidate pairs instead widened the band so
        much that most solves fell back on SuperLU: 44 s of linear algebra instead of
        26 s for 32 rods.)"""
        m = self.model
        grown = np.zeros(len(self.rods), dtype=bool)
        act = e_pair != 0.0
        active = pairs[act]
        if not len(active):
            return grown
        # Which rods miss blocks: all needed keys at once against the joint table.
        keys = pair_blocks(m.edge_vertex, active, m.vertex_count)
        table = self._keys
        pos = np.minimum(np.searchsorted(table, keys), len(table) - 1)
        lacking = table[pos] != keys
        rods = np.unique(m.edge_rod[active[np.flatnonzero(lacking) // 16, 0]])
        near = act | (overlap > -self.GROW_GAP * self.layer.edge_diameter[pairs[:, 0]])
        prod = m.edge_rod[pairs[:, 0]]
        for k in rods:
            cp = self.rods[k].cpattern
            cp.grow(self._local_blocks(int(k), pairs[near & (prod == k)]))
            self.rods[k].dirty = True
            grown[k] = True
        return grown

    # -- evaluation ------------------------------------------------------------------------
    def evaluate(self, requests: list[EvalRequest]) -> dict[int, EvalAnswer]:
        """Answer every request with one launch of each kernel over the whole model (the
        contact pairs of the asking rods only)."""
        m = self.model
        dev = self.device
        asking = np.zeros(len(self.rods), dtype=bool)
        for q in requests:
            r = self.rods[q.rod]
            asking[q.rod] = True
            self.x[r.v0 : r.v0 + r.nv] = q.x + self.offsets[q.rod]
            self.theta[r.e0 : r.e0 + r.ne] = q.theta
            self.d1[r.e0 : r.e0 + r.ne] = q.d1_base
            self.t[r.e0 : r.e0 + r.ne] = q.t_base
            self.m_ref[r.j0 : r.j0 + r.nj] = q.m_ref_base
        if any(r.dirty for r in self.rods):
            self._layout()  # patterns compacted at a rod's new load step
        d1, tt, mref = self.forces.transport_frames(self.x, self.d1, self.t, self.m_ref)
        wx = wp.array(self.x, dtype=wp.vec3d, device=dev)
        wth = wp.array(self.theta, dtype=wp.float64, device=dev) if m.twist else self._empty_f
        wmr = wp.array(mref, dtype=wp.float64, device=dev)
        wrest = wp.array(self.rest, dtype=wp.float64, device=dev)
        self._edata.zero_()
        self._grad.zero_()
        wp.launch(ek.stretch_kernel, dim=m.edge_count, device=dev,
                  inputs=[m.wp("edge_vertex"), m.wp("edge_mu_area"), m.wp("edge_dofs"),
                          wx, wrest, self._weslot, 1, 1],
                  outputs=[self._e_stretch, self._grad, self._edata])
        wp.launch(ek.bend_twist_kernel, dim=m.joint_count, device=dev,
                  inputs=[m.wp("joint_vertex"), m.wp("joint_edge"),
                          m.wp("joint_bend_stiffness"), m.wp("joint_twist_stiffness"),
                          m.wp("joint_thinning_exponent"), m.wp("joint_dofs"),
                          int(m.twist), wx, wth, wmr, wrest, self._wjslot, 1, 1],
                  outputs=[self._e_bend, self._e_twist, self._grad, self._edata])
        self._cdata.zero_()
        geo = self.layer.mean_geometry(self.x, self.rest)
        pairs, e_pair, overlap, cgrad, missing = self.layer.pair_terms(
            self.x, self.rest, asking, self._tables, self._cdata, geo=geo)
        # A rod-mean radius: the pairs' radius derivatives of this first run (a re-run
        # below covers some rods only).
        d_r = (None if geo is None else
               self.layer.energy.kernel.radius_derivatives(len(pairs)).copy())
        redo = asking
        gp, ge, go = pairs, e_pair, overlap  # what the growth looks at
        while missing:
            # New contact blocks: grow the patterns of the rods that lack them and run the
            # contact kernel again on those rods' pairs (all asking rods' if the regions
            # moved); the energies and gradients of the first run stand.
            grown = self._grow(gp, ge, go)
            if self._layout():
                redo = asking
                self._cdata.zero_()
            else:
                redo = grown
                cd = self._cdata.numpy()
                for k in np.flatnonzero(grown):
                    r = self.rods[k]
                    cd[r.offset : r.offset + r.capacity] = 0.0
            self.contact_reruns += 1
            gp, ge, go, _, missing = self.layer.pair_terms(self.x, self.rest, redo,
                                                            self._tables, self._cdata,
                                                            again=True, geo=geo)
        n_rods = len(self.rods)
        rods_e = m.edge_rod[pairs[:, 0]] if len(pairs) else np.zeros(0, dtype=np.int64)
        e_contact = np.bincount(rods_e, weights=e_pair, minlength=n_rods)
        # The pairs in contact, per rod, for the compaction at its next load step.
        touching = overlap > 0.0
        order = np.argsort(rods_e[touching], kind="stable")
        split = np.searchsorted(rods_e[touching][order], np.arange(n_rods + 1))
        tp = pairs[touching][order]
        for q in requests:
            self._touching[q.rod] = tp[split[q.rod] : split[q.rod + 1]]
        e_s = np.add.reduceat(self._e_stretch.numpy(), self._edge_starts)
        e_b = np.add.reduceat(self._e_bend.numpy(), self._joint_starts)
        e_t = np.add.reduceat(self._e_twist.numpy(), self._joint_starts)
        grad = self._grad.numpy().copy()
        grad[m.position_dofs] += cgrad.numpy()
        cdata = self._cdata.numpy()
        edata = self._edata.numpy()
        low: dict[int, tuple[np.ndarray, np.ndarray] | None] = {}
        if geo is not None:
            low = self._mean_terms(geo, pairs, e_pair, d_r, grad, edata, requests)
        out = {}
        for q in requests:
            k = q.rod
            r = self.rods[k]
            cp = r.cpattern
            # As RodSystem.evaluate: the contact data, then the elastic entries added.
            data = cdata[r.offset : r.offset + cp.nnz].copy()
            data[cp.elastic_slot] += edata[r.elastic_offset : r.elastic_offset
                                           + r.pattern.nnz]
            h = HessianData(cp.indptr, cp.indices, cp.diag_slot, data)
            # Views: grad and the frames are fresh arrays of this call, never written.
            out[k] = EvalAnswer(float(e_s[k]), float(e_b[k]), float(e_t[k]),
                                float(e_contact[k]), grad[r.dof0 : r.dof0 + r.ndof], h,
                                d1[r.e0 : r.e0 + r.ne], tt[r.e0 : r.e0 + r.ne],
                                mref[r.j0 : r.j0 + r.nj], low.get(k))
        return out

    def _mean_terms(self, geo: dict[str, np.ndarray], pairs: np.ndarray, e_pair: np.ndarray,
                    d_r: np.ndarray, grad: np.ndarray, edata: np.ndarray,
                    requests: list[EvalRequest]
                    ) -> dict[int, tuple[np.ndarray, np.ndarray] | None]:
        """The chain rule of a rod-mean contact radius (as
        :meth:`tightknot.contact.energy.ContactEnergy.evaluate_into`): its gradient term
        added into ``grad`` (all dofs), its stretch blocks into the elastic Hessian data
        ``edata`` (through the edges' slots), and each asking rod's low-rank update over
        its free dofs."""
        m = self.model
        energy = self.layer.energy
        mean = energy.mean
        active = np.flatnonzero(e_pair != 0.0)
        pr = pairs[active].astype(np.int64)
        dr = d_r[active]
        g, big_g = mean.gradient(geo, pr, dr[:, 0])
        grad[m.position_dofs] += g
        blk = mean.stretch_blocks(geo, big_g).reshape(m.edge_count, 36)
        slot = self._eslot
        ok = slot >= 0
        np.add.at(edata, slot[ok], blk[ok])
        out: dict[int, tuple[np.ndarray, np.ndarray] | None] = {}
        rod_of = m.edge_rod[pr[:, 0]] if len(pr) else np.zeros(0, dtype=np.int64)
        for q in requests:
            k = q.rod
            mine = rod_of == k
            r = self.rods[k]
            lr = mean.low_rank(geo, pr[mine], energy.pair_dofs(pr[mine]), dr[mine, 0],
                               dr[mine, 1], dr[mine, 2:], dofs=(r.dof0, r.dof0 + r.ndof))
            out[k] = None if lr is None else (lr[0][r.pattern.free_dofs], lr[1])
        return out

    def max_step(self, requests: list[StepRequest]) -> dict[int, float]:
        """Largest collision-free fraction of each requested move (1 = full)."""
        dx = np.zeros_like(self.x)
        for q in requests:
            r = self.rods[q.rod]
            self.x[r.v0 : r.v0 + r.nv] = q.x + self.offsets[q.rod]
            dx[r.v0 : r.v0 + r.nv] = q.dx
        asking = np.zeros(len(self.rods), dtype=bool)
        asking[[q.rod for q in requests]] = True
        bounds = self.layer.step_bounds(self.x, dx, self.rest, asking)
        return {q.rod: float(bounds[q.rod]) for q in requests}
