"""The total potential of a rod model as a function of its free degrees of freedom.

``Pi(q) = E_elastic(q) + sum_k E_k(q) - f_ext . x + Phi_inertia(q)``, where the ``E_k`` are
extra terms (the contact layer) and the inertia term is present only in implicit dynamics:
``Phi_inertia = sum m/(2 h^2) |q - q_hat|^2`` (implicit Euler as a minimisation, e.g.
Kane et al. 2000; Martin et al. 2011 "Example-based elastic materials"). Quasi-static and
dynamic solves therefore share one Newton loop and differ only by that term.

Reference frames are carried from the last accepted state by time-parallel transport
(Bergou 2010 sec. 4.1); trial evaluations never modify the state until :meth:`accept`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import warp as wp

from tightknot.rods.boundary import BoundaryConditions
from tightknot.rods.elastic import ElasticForces
from tightknot.rods.model import Model
from tightknot.rods.proximity import ProximityCheck
from tightknot.rods.staging import Output
from tightknot.rods.state import State
from tightknot.rods.term import BlockHessian, EnergyTerm
from tightknot.solvers.kept_union import merge_sorted, place_blocks
from tightknot.solvers.linear import LowRankHessian, SparseDirect
from tightknot.solvers.pardiso import section_linear
from tightknot.solvers.pattern import ContactPattern, SparsePattern


@dataclass
class Inertia:
    """Implicit-Euler inertia term: time step ``dt`` [s] and predicted dofs ``q_hat``."""

    dt: float
    q_hat: np.ndarray
    mass: np.ndarray  # per dof: vertex mass [kg] or twist inertia [kg m^2]


@dataclass
class EnergySplit:
    """Energy split of the last evaluation [J]."""

    stretch: float = 0.0
    bend: float = 0.0
    twist: float = 0.0
    external: float = 0.0
    inertia: float = 0.0
    extra: dict[str, float] = field(default_factory=dict)

    @property
    def magnitude(self) -> float:
        """Sum of the absolute values of the parts [J]: the scale of the total's round-off."""
        return (abs(self.stretch) + abs(self.bend) + abs(self.twist) + abs(self.external)
                + abs(self.inertia) + sum(abs(v) for v in self.extra.values()))

    @property
    def total(self) -> float:
        """Total potential [J]."""
        return (self.stretch + self.bend + self.twist + self.external + self.inertia
                + sum(self.extra.values()))


class RodSystem:
    """Energy, gradient and Hessian of a model under boundary conditions at load parameter t:
    the one problem the solvers' programs (:mod:`tightknot.solvers.program`) ask about.

    A system is evaluated by itself (:meth:`evaluate`), or, when a batch has attached it
    (``batch``: :class:`tightknot.solvers.lockstep.BatchRod`), together with the other rods
    of its batch, whose joint answer :meth:`evaluated` completes as :meth:`evaluate` would.
    Its Newton systems are solved by ``linear`` (sparse direct by default; a batch rod's
    banded solver).

    Args:
        model: the rods.
        state: their state; the solver writes accepted iterates into it.
        bcs: boundary conditions and loads (default: none).
        gravity: gravitational acceleration vector [m/s^2] or None (the study's scenes
            neglect gravity; physics.md sec. 1).
    """

    def __init__(
        self,
        model: Model,
        state: State,
        bcs: BoundaryConditions | None = None,
        gravity: np.ndarray | None = None,
    ) -> None:
        self.model = model
        self.state = state
        self.bcs = bcs if bcs is not None else BoundaryConditions(model)
        self.gravity = None if gravity is None else np.asarray(gravity, dtype=np.float64)
        self.extra_terms: list[EnergyTerm] = []
        #: The term that owns dofs beyond the model's (State.extra), or None.
        self.dof_term: EnergyTerm | None = None
        self._own_pattern: dict | None = None
        self.inertia: Inertia | None = None
        self.pattern = SparsePattern(model, ~self.bcs.fixed_mask())
        self.forces = ElasticForces(model, self.pattern.joint_slot, self.pattern.edge_slot)
        self._hess = wp.zeros(max(self.pattern.nnz, 1), dtype=wp.float64, device=model.device)
        self.bcs.capture(state.d1_ref, state.t_ref, state.theta)
        free = self.pattern.free_dofs
        is_theta = np.zeros(model.dof_count, dtype=bool)
        if model.twist:
            is_theta[model.edge_dof] = True
        self.free_is_theta = is_theta[free]
        self.dof_mass = np.zeros(model.dof_count)
        self.dof_mass[model.position_dofs] = model.vertex_mass[:, None]
        if model.twist:
            self.dof_mass[model.edge_dof] = model.edge_rot_inertia
        # Scales of the convergence tests: a bending force and moment of the stiffest rod
        # over its own length, EI/L^2 [N] and EI/L [N m], and the smallest rest radius [m].
        ei = model.joint_bend_stiffness.max() if model.joint_count else 1.0
        lmax = max(model.rest_length(r) for r in range(len(model.rods)))
        self.force_scale = float(ei / lmax**2)
        self.moment_scale = float(ei / lmax)
        self.length_scale = float(model.edge_radius.min())
        self.t = 0.0
        self.last_split = EnergySplit()
        self._cpattern: ContactPattern | None = None
        self._cdata = Output(wp.float64, model.device)
        self._trial: tuple[np.ndarray, ...] | None = None
        #: The linear algebra of the Newton loop (SuperLU; a batch rod's banded solver).
        self.linear: Any = SparseDirect()
        #: The batch that answers this system's evaluations, None when it answers them.
        self.batch: Any = None
        #: The independent check of every accepted state (on once a term keeps rods apart).
        self.proximity: ProximityCheck | None = None
        #: Accepted states since the last load step, and the first one that came closer
        #: than the check's floor: why a solve must stop (None while none did).
        self.accepted_count = 0
        self.violation: str | None = None
        #: When a list: the positions [m] at the start of the load step and after every
        #: accepted iterate since (what a topology check looks back on).
        self.history: list[np.ndarray] | None = None
        self.set_load(0.0)

    def add_term(self, term: EnergyTerm) -> None:
        """Add an energy term (e.g. the contact layer); it first checks the state
        (``term.check_state``: a start that already violates it is refused)."""
        term.check_state(self.state.x)
        if term.dof_count:
            if self.dof_term is not None:
                raise ValueError("a rod system takes one term with dofs of its own")
            self.dof_term = term
            if self.state.extra.shape != (term.dof_count,):
                self.state.extra = term.initial_dofs()
            # Section dofs make dense node blocks, which a supernodal LDL^T factors
            # several times faster than SuperLU (tightknot.solvers.pardiso).
            self.linear = section_linear()
        self.extra_terms.append(term)
        term.begin_load_step(self.state.x, self.rest)
        if term.keeps_apart and self.proximity is None:
            self.proximity = ProximityCheck(self.model)

    # -- load path -------------------------------------------------------------------
    def set_load(self, t: float) -> None:
        """Move to load parameter t: rest lengths, dead loads and prescribed dofs."""
        self.t = float(t)
        self.rest = self.bcs.edge_rest_length(self.t)
        f = self.bcs.external_force(self.t)
        if self.gravity is not None:
            f = f + self.model.vertex_mass[:, None] * self.gravity[None, :]
        self.f_ext = f
        st = self.state
        # External work is measured from the positions at this load step, so that its
        # round-off stays that of the displacements, not of the coordinates.
        self._x_ref = st.x.copy()
        x = st.x.copy()
        self.bcs.prescribe_positions(self.t, x)
        d1, tt, mref = self.forces.transport_frames(x, st.d1_ref, st.t_ref, st.m_ref)
        st.x, st.d1_ref, st.t_ref, st.m_ref = x, d1, tt, mref
        self.bcs.prescribe_twist(self.t, st.theta, st.d1_ref, st.t_ref)
        for term in self.extra_terms:
            term.begin_load_step(st.x, self.rest)
        self._trial = None
        self.accepted_count = 0
        self.violation = None
        if self.history is not None:
            self.history = [st.x.copy()]
        # A new load step: contact blocks that stopped interacting leave the pattern.
        self.compact_pattern()
        if self.batch is not None:
            self.batch.loaded(self)

    # -- dof vectors -----------------------------------------------------------------
    def full_dofs(self) -> np.ndarray:
        """The state's dof vector (all dofs)."""
        return self.state.dofs(self.model)

    def free_vector(self) -> np.ndarray:
        """The state's free dofs (then the dofs of a term that owns some, State.extra)."""
        return self.free_vector_at(self.state.x)

    def free_vector_at(self, x: np.ndarray) -> np.ndarray:
        """:meth:`free_vector` with the positions ``x`` [m] in place of the state's."""
        q = self.full_dofs()
        q[self.model.position_dofs] = x
        u = q[self.pattern.free_dofs]
        if self.dof_term is None:
            return u
        return np.concatenate([u, self.state.extra])

    def _split(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        q = self.full_dofs()
        q[self.pattern.free_dofs] = u[: self.pattern.n]
        x = q[self.model.position_dofs]
        theta = q[self.model.edge_dof] if self.model.twist else self.state.theta
        return x, theta

    def positions(self, u: np.ndarray) -> np.ndarray:
        """Vertex positions [m] of free-dof vector ``u``."""
        return self._split(u)[0]

    # -- evaluation ------------------------------------------------------------------
    def evaluate(
        self, u: np.ndarray, want_grad: bool = True, want_hess: bool = True
    ) -> tuple[float, np.ndarray | None, sp.csc_matrix | None]:
        """Total potential [J], its gradient on the free dofs, and the free-dof Hessian."""
        if self.batch is not None:
            raise RuntimeError("this system is a rod of a batch: its evaluations are answered "
                               "by the batch (tightknot.solvers.lockstep.run_lockstep)")
        m, st = self.model, self.state
        x, theta = self._split(u)
        d1, tt, mref = self.forces.transport_frames(x, st.d1_ref, st.t_ref, st.m_ref)
        self._trial = (u.copy(), x, theta, d1, tt, mref)
        n_model = self.pattern.n
        own = None  # the dof term's (gradient over its dofs, Hessian COO)
        if want_hess:
            self._hess.zero_()
        el, grad = self.forces.evaluate(x, theta, mref, self.rest, want_grad or want_hess,
                                        self._hess if want_hess else None)
        split = EnergySplit(stretch=el.stretch, bend=el.bend, twist=el.twist)
        split.external = -float(np.sum(self.f_ext * (x - self._x_ref)))
        coo_parts = []
        if grad is not None:
            grad[m.position_dofs] -= self.f_ext
        # Terms that add their Hessian straight into the CSC data (the contact layer) share
        # one pattern that grows with the contact set (tightknot.solvers.pattern).
        direct = [t for t in self.extra_terms if want_hess and t.assembles_in_place]
        cdata = None
        results = {}
        if direct:
            if self._cpattern is None:
                self._cpattern = ContactPattern(m, self.pattern)
            while True:
                # One reused array (its first nnz entries zeroed), so that the contact
                # kernel's recorded launch sees the same target at every evaluation.
                cdata = self._cdata.get(self._cpattern.nnz, zero=True)
                tables = self._cpattern.warp_tables(m.device)
                for term in direct:
                    results[id(term)] = term.evaluate_into(x, self.rest, tables, cdata)
                    if results[id(term)][1] is None:
                        # New contact blocks: grow the pattern, assemble again.
                        self._cpattern.grow(term.missing_blocks())
                        break
                else:
                    break
        low_rank = []
        for term in self.extra_terms:
            if term is self.dof_term:
                # the sections turn with the reference twist of the frames carried to x
                e_k, g_k, g_own, h_own = term.evaluate_with_dofs(
                    x, u[n_model:], st.frames, self.rest,
                    want_grad or want_hess, want_hess, twist=mref)
                split.extra[term.name] = e_k
                if grad is not None and g_k is not None:
                    grad[m.position_dofs] += g_k
                own = (g_own, h_own)
                continue
            if id(term) in results:
                # (energy, gradient) or, from a contact layer with a radius window, also the
                # COO Hessian terms outside its pair blocks; with a rod-mean radius also a
                # dense update (U, C) of low rank (tightknot.contact.rod_mean_radius)
                e_k, g_k, *rest_k = results[id(term)]
                h_k = rest_k[0] if rest_k else None
                if len(rest_k) > 1 and rest_k[1] is not None:
                    low_rank.append(rest_k[1])
            else:
                e_k, g_k, h_k = term.evaluate(x, self.rest, want_grad or want_hess, want_hess)
            split.extra[term.name] = e_k
            if grad is not None and g_k is not None:
                grad[m.position_dofs] += g_k
            if want_hess and h_k is not None:
                coo_parts.append(h_k)
        grad = self._with_inertia(u, split, grad)
        self.last_split = split
        g_free = grad[self.pattern.free_dofs] if grad is not None else None
        if own is not None and g_free is not None:
            g_free = np.concatenate([g_free, own[0]])
        hmat = None
        if want_hess:
            data = self._hess.numpy()[: self.pattern.nnz].copy()
            pattern = self.pattern
            if cdata is not None:
                pattern = self._cpattern
                full = self._cdata.numpy(pattern.nnz)
                full[pattern.elastic_slot] += data
                data = full
            self._add_inertia_diagonal(data, pattern.diag_slot)
            hmat = pattern.matrix(data)
            if coo_parts:
                hmat = hmat + self._coo_free(coo_parts)
            n_own = 0
            if own is not None:
                hmat = self._with_own_hessian(hmat, own[1])
                n_own = self.dof_term.dof_count
            free = self.pattern.free_dofs
            # each update's columns over the free dofs, then the dof term's own (zero for a
            # layer's update, which has none)
            cols = [np.vstack([u[free], np.zeros((n_own, u.shape[1]))]) if n_own else u[free]
                    for u, _ in low_rank]
            cores = [c for _, c in low_rank]
            if own is not None and own[1].low_rank is not None:
                ue, c = own[1].low_rank
                cols.append(np.vstack([ue[:m.dof_count][free], ue[m.dof_count:]]))
                cores.append(c)
            if cols:
                hmat = LowRankHessian(hmat, np.hstack(cols), sla.block_diag(*cores))
        return split.total, g_free, hmat

    def term_gradient(self, term: EnergyTerm) -> np.ndarray:
        """The gradient [N] (vertex_count, 3) over the positions of one of the system's
        extra terms at the state (a term with dofs of its own at the state's, State.extra)."""
        st = self.state
        if term is self.dof_term:
            return term.evaluate_with_dofs(st.x, st.extra, st.frames,
                                           self.rest, True, False, twist=st.m_ref)[1]
        return term.evaluate(st.x, self.rest, True, False)[1]

    def evaluated(self, u: np.ndarray, x: np.ndarray, theta: np.ndarray, answer: Any,
                  want_grad: bool, want_hess: bool) -> tuple[float, np.ndarray | None, Any]:
        """:meth:`evaluate`'s result at ``u`` (positions ``x``, twist ``theta``) from a
        batch's answer (:class:`tightknot.solvers.batch_eval.EvalAnswer`: energy parts, the
        gradient over all dofs, the Hessian and the carried frames of this rod): the
        inertia term added, the free dofs taken. The Hessian stays the batch's
        :class:`~tightknot.solvers.batch_eval.HessianData` (its banded solver's input)."""
        self._trial = (u.copy(), x, theta, answer.d1, answer.t, answer.m_ref)
        split = EnergySplit(stretch=answer.stretch, bend=answer.bend, twist=answer.twist)
        split.extra["contact"] = answer.contact
        grad = self._with_inertia(u, split, answer.grad)
        self.last_split = split
        g_free = grad[self.pattern.free_dofs] if (want_grad or want_hess) else None
        h = None
        if want_hess:
            h = answer.hess
            if self.inertia is not None:
                data = h.data.copy()
                self._add_inertia_diagonal(data, h.diag_slot)
                h = type(h)(h.indptr, h.indices, h.diag_slot, data)
            if answer.low_rank is not None:
                h = LowRankHessian(h, *answer.low_rank)
        return split.total, g_free, h

    def _with_inertia(self, u: np.ndarray, split: EnergySplit,
                      grad: np.ndarray | None) -> np.ndarray | None:
        """The inertia term of implicit dynamics (module docstring) at ``u``: its energy
        into ``split``, and ``grad`` (all dofs) with its gradient added (a new array)."""
        if self.inertia is None:
            return grad
        q = self.full_dofs()
        q[self.pattern.free_dofs] = u[: self.pattern.n]
        dq = q - self.inertia.q_hat
        w = self.inertia.mass / self.inertia.dt**2
        split.inertia = 0.5 * float(np.sum(w * dq * dq))
        return None if grad is None else grad + w * dq

    def _add_inertia_diagonal(self, data: np.ndarray, diag_slot: np.ndarray) -> None:
        """Add the inertia term's Hessian m/dt^2 to the diagonal entries ``diag_slot`` of the
        free-dof Hessian data ``data`` (in place)."""
        if self.inertia is not None:
            w = self.inertia.mass / self.inertia.dt**2
            data[diag_slot] += w[self.pattern.free_dofs]

    def compact_pattern(self) -> None:
        """Drop contact blocks that no longer interact (call between load steps: a pattern
        that only grows would carry stale zeros into every later factorization)."""
        self._own_pattern = None
        if self._cpattern is None:
            return
        keys = [t.active_blocks() for t in self.extra_terms]
        self._cpattern.reset(np.concatenate(keys) if keys else np.zeros(0, np.int64))

    def _with_own_hessian(self, hmat: sp.csc_matrix, own: BlockHessian) -> sp.csc_matrix:
        """The free-dof Hessian ``hmat`` of the model's dofs grown by the dof term's dofs,
        with that term's node blocks ``own`` added.

        The union of the two patterns and each entry's slot in it are kept through a load
        step: while ``hmat``'s pattern is the same and the blocks' node pairs are among the
        kept ones (contacts that come and go within a step), an evaluation only places
        values; node pairs that are new are merged into the kept union (:meth:`_own_grow`).
        A new load step starts afresh (:meth:`compact_pattern`), so that pairs no longer in
        contact leave it."""
        cache = self._own_pattern
        same_base = (cache is not None and np.array_equal(cache["indptr"], hmat.indptr)
                     and np.array_equal(cache["indices"], hmat.indices))
        nodes = own.node_dofs.shape[0]
        new_keys = own.keys[:, 0] * nodes + own.keys[:, 1]
        rows_in, cols_in = own.masks()
        if same_base:
            at, found = _kept_at(cache, new_keys)
            kept_r, kept_c = cache["full_rows"][at], cache["full_cols"][at]
            grown = found & ((rows_in & ~kept_r) | (cols_in & ~kept_c))
            if grown.any() or not found.all():
                # kept blocks that gain rows or columns (their new entries join the union
                # as shadow pairs: the same node pair, only those entries), then new pairs
                add = np.concatenate([np.flatnonzero(grown), np.flatnonzero(~found)])
                kept = found[add]
                cache = self._own_grow(cache, own.node_dofs, new_keys[add],
                                       rows_in[add] | (kept_r[add] & kept),
                                       cols_in[add] | (kept_c[add] & kept),
                                       np.where(kept, at[add], -1))
                at, _ = _kept_at(cache, new_keys)
        if not same_base:
            if cache is None:
                keys, full_r, full_c = new_keys, rows_in, cols_in
            else:
                keys = np.union1d(cache["keys"], new_keys)
                full_r = np.zeros(keys.size, dtype=bool)
                full_c = np.zeros(keys.size, dtype=bool)
                old_at = np.searchsorted(keys, cache["keys"])
                full_r[old_at], full_c[old_at] = cache["full_rows"], cache["full_cols"]
                new_at = np.searchsorted(keys, new_keys)
                full_r[new_at] |= rows_in
                full_c[new_at] |= cols_in
            cache = self._own_union(hmat, own.node_dofs, keys, full_r, full_c)
            at, _ = _kept_at(cache, new_keys)
        # which of own's blocks each kept pair takes (-1: none); a shadow pair its kept
        # pair's
        source = np.full(cache["keys"].size, -1, dtype=np.int64)
        source[at] = np.arange(at.size)
        if cache["shadow"].size:
            source[cache["shadow"]] = source[cache["shadow_src"]]
        data = np.zeros(cache["indices_u"].size)
        data[cache["slot_e"]] = hmat.data
        # each (row, column) entry belongs to one node pair: the slots are distinct
        place_blocks(data, cache["valid"], cache["slot_t"], source, own.blocks)
        size = cache["size"]
        return sp.csc_matrix((data, cache["indices_u"], cache["indptr_u"]), shape=(size, size))

    def _block_entries(self, node_dofs: np.ndarray, keys: np.ndarray, full_rows: np.ndarray,
                       full_cols: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The free rows and columns (each (K, b, b)) of the node blocks of node-pair
        ``keys`` (row node x nodes + column node) and which entries are in the system
        (flat, K b b): both dofs free, and past a node's position only the rows
        ``full_rows`` and the columns ``full_cols`` of each block."""
        n, n_own = self.pattern.n, self.dof_term.dof_count
        nodes = node_dofs.shape[0]
        index = np.concatenate([self.pattern.free_index, n + np.arange(n_own)])
        node_free = np.where(node_dofs >= 0, index[node_dofs], -1)
        b = node_free.shape[1]
        shape = (keys.size, b, b)
        rows = np.broadcast_to(node_free[keys // nodes][:, :, None], shape)
        cols = np.broadcast_to(node_free[keys % nodes][:, None, :], shape)
        local = np.arange(b)
        valid = ((rows >= 0) & (cols >= 0)
                 & ((local[None, :, None] < 3) | full_rows[:, None, None])
                 & ((local[None, None, :] < 3) | full_cols[:, None, None])).ravel()
        return rows, cols, valid

    def _own_union(self, hmat: sp.csc_matrix, node_dofs: np.ndarray, keys: np.ndarray,
                   full_rows: np.ndarray, full_cols: np.ndarray) -> dict:
        """The union of ``hmat``'s pattern with the node blocks of node-pair ``keys``
        (:meth:`_block_entries`), and each entry's slot in it (kept as the cache)."""
        n, n_own = self.pattern.n, self.dof_term.dof_count
        rows, cols, valid = self._block_entries(node_dofs, keys, full_rows, full_cols)
        size = n + n_own
        e_cols = np.repeat(np.arange(n), np.diff(hmat.indptr))
        all_r = np.concatenate([hmat.indices, rows.ravel()[valid]]).astype(np.int64)
        all_c = np.concatenate([e_cols, cols.ravel()[valid]]).astype(np.int64)
        union = sp.csc_matrix((np.ones(all_r.size), (all_r, all_c)), shape=(size, size))
        union.sum_duplicates()
        u_cols = np.repeat(np.arange(size, dtype=np.int64), np.diff(union.indptr))
        lin_u = u_cols * size + union.indices
        slots = np.searchsorted(lin_u, all_c * size + all_r)
        cache = {"keys": keys, "sort": np.arange(keys.size), "sorted_keys": keys,
                 "full_rows": full_rows, "full_cols": full_cols,
                 "indptr": hmat.indptr.copy(), "indices": hmat.indices.copy(),
                 "valid": valid, "slot_e": slots[:hmat.nnz], "slot_t": slots[hmat.nnz:],
                 "lin_u": lin_u, "indptr_u": union.indptr, "indices_u": union.indices,
                 "size": size, "shadow": np.zeros(0, np.int64),
                 "shadow_src": np.zeros(0, np.int64)}
        self._own_pattern = cache
        return cache

    def _own_grow(self, cache: dict, node_dofs: np.ndarray, add_keys: np.ndarray,
                  full_rows: np.ndarray, full_cols: np.ndarray, shadow_of: np.ndarray
                  ) -> dict:
        """``cache`` (:meth:`_own_union`) with the node blocks of the node pairs
        ``add_keys`` merged in: the same union and slots as built afresh, found from the
        new blocks' entries alone. The kept pairs are in the order they came, the new ones
        after them, so that the kept slots stay a prefix. ``shadow_of``: for each of
        ``add_keys``, its entry among the kept pairs where it is kept already (-1: a new
        pair). A kept pair's rows and columns grow to ``full_rows``,
        ``full_cols``: only its entries not yet in the union are added, as a shadow pair
        that takes the kept pair's block (:meth:`_with_own_hessian`)."""
        size = cache["size"]
        rows, cols, valid = self._block_entries(node_dofs, add_keys, full_rows, full_cols)
        shadow_of = np.asarray(shadow_of, dtype=np.int64)
        is_shadow = shadow_of >= 0
        if is_shadow.any():
            sh = shadow_of[is_shadow]
            kept_valid = self._block_entries(node_dofs, add_keys[is_shadow],
                                             cache["full_rows"][sh], cache["full_cols"][sh])[2]
            per_pair = valid.reshape(add_keys.size, -1)
            per_pair[is_shadow] &= ~kept_valid.reshape(sh.size, -1)
            valid = per_pair.ravel()
        lin = cols.ravel()[valid].astype(np.int64) * size + rows.ravel()[valid]
        lin_u = cache["lin_u"]
        fresh = np.unique(lin)
        pos = np.searchsorted(lin_u, fresh)
        present = lin_u[np.minimum(pos, lin_u.size - 1)] == fresh
        added = fresh[~present]
        dtype = cache["indices_u"].dtype
        grown, old_to_new, indices_u = merge_sorted(lin_u, added, size, dtype)
        keys = np.concatenate([cache["keys"], add_keys])
        # stable: a shadow pair sorts after its kept pair, which _kept_at then finds
        order = np.argsort(keys, kind="stable")
        full_r = np.concatenate([cache["full_rows"], full_rows])
        full_c = np.concatenate([cache["full_cols"], full_cols])
        shadow, shadow_src = cache["shadow"], cache["shadow_src"]
        if is_shadow.any():
            sh = shadow_of[is_shadow]
            full_r[sh], full_c[sh] = full_rows[is_shadow], full_cols[is_shadow]
            shadow = np.concatenate([shadow, cache["keys"].size + np.flatnonzero(is_shadow)])
            shadow_src = np.concatenate([shadow_src, sh])
        counts = np.diff(cache["indptr_u"]) + np.bincount(added // size, minlength=size)
        cache = dict(cache, keys=keys, sort=order, sorted_keys=keys[order],
                     full_rows=full_r, full_cols=full_c, shadow=shadow, shadow_src=shadow_src,
                     valid=np.concatenate([cache["valid"], valid]),
                     slot_e=old_to_new[cache["slot_e"]],
                     slot_t=np.concatenate([old_to_new[cache["slot_t"]],
                                            np.searchsorted(grown, lin)]),
                     lin_u=grown,
                     indptr_u=np.concatenate([[0], np.cumsum(counts)]).astype(dtype),
                     indices_u=indices_u)
        self._own_pattern = cache
        return cache

    def _coo_free(self, parts: list[tuple[np.ndarray, np.ndarray, np.ndarray]]) -> sp.csc_matrix:
        fi = self.pattern.free_index
        rows = np.concatenate([p[0] for p in parts])
        cols = np.concatenate([p[1] for p in parts])
        vals = np.concatenate([p[2] for p in parts])
        r, c = fi[rows], fi[cols]
        keep = (r >= 0) & (c >= 0)
        n = self.pattern.n
        return sp.csc_matrix((vals[keep], (r[keep], c[keep])), shape=(n, n))

    def max_step(self, u: np.ndarray, du: np.ndarray) -> float:
        """Largest step fraction allowed by the extra terms (e.g. no passing through)."""
        if not self.extra_terms:
            return 1.0
        x0 = self.positions(u)
        dx = self.positions(u + du) - x0
        return min(term.max_step(x0, dx, self.rest) for term in self.extra_terms)

    def has_trial(self, u: np.ndarray) -> bool:
        """The last evaluation was at ``u`` (its frames are at hand for :meth:`accept`)."""
        return self._trial is not None and np.array_equal(self._trial[0], u)

    def accept(self, u: np.ndarray) -> None:
        """Make ``u`` the state (positions, twist, transported frames)."""
        if not self.has_trial(u):
            self.evaluate(u, want_grad=False, want_hess=False)
        _, x, theta, d1, tt, mref = self._trial
        st = self.state
        st.x, st.d1_ref, st.t_ref, st.m_ref = x.copy(), d1, tt, mref
        if self.dof_term is not None:
            st.extra = np.array(u[self.pattern.n:], dtype=np.float64)
        if self.model.twist:
            st.theta = theta.copy()
        if self.history is not None:
            self.history.append(st.x.copy())
        if self.proximity is not None:
            self.accepted_count += 1
            near = self.proximity.check(st.x, self.rest)
            if near.violated and self.violation is None:
                d0 = float(2.0 * self.model.edge_radius.max())
                self.violation = (f"the rod passes through itself: at accepted iterate "
                                  f"{self.accepted_count} of load t={self.t:.6g}, "
                                  f"{near.describe(d0)}")

    def energy_roundoff(self) -> float:
        """An upper estimate of the round-off of the last total potential [J]."""
        return 1e-13 * self.last_split.magnitude

    def residual_floor(self) -> float:
        """The smallest scaled residual [-] round-off lets a solve reach: the stretching
        forces are differences of absolute coordinates, each known to eps |x|, times an
        edge's axial stiffness (3 mu A0 / l at the current rest length l, the neo-Hookean
        EA/l), several per vertex (a margin of 64). Far below the tolerances of the study's
        rods; a long, finely divided rod reaches it (1 m at 1682 vertices: a residual of
        1.4e-6 no Newton step lowers)."""
        m = self.model
        if not m.edge_count:
            return 0.0
        stiff = float(np.max(3.0 * m.edge_mu_area / self.rest))
        reach = float(np.max(np.abs(self.state.x)))
        return 64.0 * np.finfo(np.float64).eps * stiff * reach / self.force_scale

    # -- norms -------------------------------------------------------------------------
    def residual_norm(self, g: np.ndarray) -> float:
        """Max-norm of the free-dof gradient, forces over EI/L^2 and moments over EI/L [-]."""
        if g.size == 0:
            return 0.0
        # A dof term's generalised forces (energy per coefficient length) are forces.
        scale = np.where(self._is_theta(g.size), self.moment_scale, self.force_scale)
        return float(np.max(np.abs(g) / scale))

    def step_norm(self, du: np.ndarray) -> float:
        """Max-norm of a step, displacements over the smallest radius, angles in rad [-]."""
        if du.size == 0:
            return 0.0
        scale = np.where(self._is_theta(du.size), 1.0, self.length_scale)
        return float(np.max(np.abs(du) / scale))

    def _is_theta(self, size: int) -> np.ndarray:
        """Which of ``size`` free dofs are twist angles (a dof term's are lengths)."""
        if size == self.free_is_theta.size:
            return self.free_is_theta
        return np.concatenate([self.free_is_theta,
                               np.zeros(size - self.free_is_theta.size, dtype=bool)])


def _kept_at(cache: dict, keys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where node-pair ``keys`` are among a kept union's pairs (:meth:`RodSystem._own_union`)
    and whether they are there at all."""
    kept = cache["sorted_keys"]
    if kept.size == 0:
        return np.zeros(keys.size, dtype=np.int64), np.zeros(keys.size, dtype=bool)
    pos = np.minimum(np.searchsorted(kept, keys), kept.size - 1)
    return cache["sort"][pos], kept[pos] == keys
