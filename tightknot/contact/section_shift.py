"""The tight bend's section shift: where a bent rod's boundary is centred.

In a bent rod the fibres on the inner side are shortened and, by the Poisson effect, widen;
those on the outer side are stretched and narrow. The linear solution of pure bending
(Saint-Venant; e.g. Lai, Rubin & Krempl, Introduction to Continuum Mechanics, ch. 5, "Pure
bending of a beam") displaces the section by u_y = nu kappa (y^2 - x^2) / 2, u_x = nu kappa
x y, y toward the centre of curvature, whose radial part on the boundary r = R is (nu kappa
R^2 / 2) cos(theta): the boundary stays round and its centre moves toward the centre of
curvature by nu kappa R^2 / 2, while the mid fibre (the rod's centreline) stays where it is.
Our FEM's clasp U's show it (docs/fem_nip.md, "The relaxed U": 0.247 to 0.217 kappa R^2 at
kappa R 0.15 to 0.44, against 1/4 at nu = 1/2).

The contact therefore sees the boundary about the offset centreline

    x~_v = x_v + (nu R^2 / 2) kappa_v,   kappa_v = 2 (t_1 - t_0) / (L_0_bar + L_1_bar),

kappa_v the curvature vector at vertex v over the chords x_{v-m} -> x_v -> x_{v+m} (unit
vectors t_0, t_1, rest arc lengths L_bar; :class:`SectionShift` says why a chord of at
least D0), R the rest radius. The offset centreline's edge stretch is the section's mean
fibre stretch, lam (1 - nu kappa^2 R^2 / 2), which the FEM's section area follows.
Gradients and Hessians over x~ are carried back to x through the sparse Jacobian J = dx~/dx
(each x~_v on x_{v-m}, x_v, x_{v+m}): g = J^T g~, H = J^T H~ J + sum_v g~_v . d2 x~_v /
dx2.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from tightknot.rods.model import Model
from tightknot.rods.term import BlockHessian

#: The largest kappa R at which our FEM measured the shift (docs/fem_nip.md, "The relaxed
#: U": the clasp's U at bend radius 1.25 D0, where it is 0.217 kappa R^2, 13 % below nu/2).
MEASURED_KAPPA_R = 0.444

#: Shortest chord [D0] the curvature is taken over: the Jacobian's eigenvalues stay at or
#: above 1 - 2 nu R^2 / s^2 = 0.56 at nu = 1/2 (class docstring).
MIN_CHORD = 0.75


class SectionShift:
    """The offset centreline of a model's rods (module docstring).

    The curvature at vertex v is taken over chords of m edges each side, x_{v-m}, x_v,
    x_{v+m}, with m the fewest edges that span ``chord`` rest diameters: the Jacobian is
    then I + (nu R^2 / 2) times a second difference over a chord s, whose eigenvalues lie
    in [1 - 2 nu R^2 / s^2, 1] (0.75 at s = D0, nu = 1/2). Over single edges shorter than
    R it would turn the zigzag mode over (a centreline zigzag moving the boundary the other
    way), so that a contact could be relieved by a zigzag. Near an open rod's end the chord
    stops at the end vertex; vertices closer to an end than :data:`MIN_CHORD` do not
    shift (a shift that switched on a whole chord from the end would switch on inside a
    short rod's contact).

    Args:
        model: the rods.
        rods: which rods shift (e.g. not rigid counter-bodies), (rod count,) bool; None: all.
        chord: the chords' least length over D0 (>= :data:`MIN_CHORD`).
    """

    def __init__(self, model: Model, rods: np.ndarray | None = None, chord: float = 2.0
                 ) -> None:
        if not (math.isfinite(chord) and chord >= MIN_CHORD):
            raise ValueError(f"section bend_shift_chord must be >= {MIN_CHORD} D0 (shorter "
                             f"chords turn the zigzag mode over), got {chord!r}")
        self.model = model
        #: The chords' least length over D0.
        self.chord = float(chord)
        keep = (np.ones(len(model.rods), dtype=bool) if rods is None
                else np.asarray(rods, dtype=bool))
        mids, counts, nu_r2, radius = [], [], [], []
        rest0 = np.asarray(model.edge_rest_length, dtype=np.float64)
        for r, rod in enumerate(model.rods):
            if not keep[r] or rod.edge_count < 2:
                continue
            edges = np.arange(rod.edge_start, rod.edge_start + rod.edge_count)
            d0 = float(rod.diameter)
            h = float(np.median(rest0[edges]))
            m = max(1, int(math.ceil(chord * d0 / h - 1e-9)))
            nv = rod.vertex_count
            if rod.closed:
                if 2 * m >= nv:
                    continue
                local = np.arange(nv)
                before = after = np.full(nv, m)
            else:
                # near an end the chord stops at the end vertex, but spans at least
                # MIN_CHORD: vertices closer to an end than that do not shift
                least = max(1, int(math.ceil(MIN_CHORD * d0 / h - 1e-9)))
                local = np.arange(least, nv - least)
                before = np.minimum(m, local)
                after = np.minimum(m, nv - 1 - local)
            if local.size == 0:
                continue
            mids.append((rod, local))
            counts.append((before, after))
            nu_r2.append(np.full(local.size, rod.material.poisson_ratio * (0.5 * d0) ** 2))
            radius.append(np.full(local.size, 0.5 * d0))
        total = sum(loc.size for _, loc in mids)
        width = max((int(max(bf.max(), af.max())) for bf, af in counts), default=1)
        self._prev = np.zeros(total, dtype=np.int64)
        self._mid = np.zeros(total, dtype=np.int64)
        self._next = np.zeros(total, dtype=np.int64)
        # each vertex's chords' edges, padded to one width with edges weighted zero
        self._before = np.zeros((total, width), dtype=np.int64)
        self._after = np.zeros((total, width), dtype=np.int64)
        self._weight_before = np.zeros((total, width))
        self._weight_after = np.zeros((total, width))
        row = 0
        steps = np.arange(width)
        for (rod, local), (bf, af) in zip(mids, counts, strict=True):
            nv = rod.vertex_count
            rows = slice(row, row + local.size)
            # edge j joins local vertices j and j + 1 (mod nv on a closed rod)
            self._prev[rows] = rod.vertex_start + (local - bf) % nv
            self._mid[rows] = rod.vertex_start + local
            self._next[rows] = rod.vertex_start + (local + af) % nv
            in_b = steps[None, :] < bf[:, None]
            in_a = steps[None, :] < af[:, None]
            self._before[rows] = rod.edge_start + np.where(
                in_b, (local[:, None] - bf[:, None] + steps[None, :]) % nv, 0)
            self._after[rows] = rod.edge_start + np.where(
                in_a, (local[:, None] + steps[None, :]) % nv, 0)
            self._weight_before[rows] = in_b
            self._weight_after[rows] = in_a
            row += local.size
        #: nu R^2 of each shifting vertex [m^2] and its rest radius R [m].
        self.nu_r2 = np.concatenate(nu_r2) if nu_r2 else np.zeros(0)
        self.radius = np.concatenate(radius) if radius else np.zeros(0)
        #: The fraction of the shift applied, in (0, 1]: below 1 only on a continuation
        #: path toward the full shift (:func:`tightknot.loading.tie.section_finish`).
        self.scale = 1.0

    def set_scale(self, scale: float) -> None:
        """Apply the fraction ``scale`` in (0, 1] of the shift."""
        if not (math.isfinite(scale) and 0.0 < scale <= 1.0):
            raise ValueError(f"the bend shift's scale must be in (0, 1], got {scale!r}")
        self.scale = float(scale)

    @property
    def count(self) -> int:
        """Number of vertices that shift."""
        return int(self._mid.size)

    def max_kappa_r(self, x: np.ndarray, rest: np.ndarray) -> float:
        """The largest kappa R [-] of the shifting vertices at positions ``x`` [m] and edge
        rest lengths ``rest`` [m] (the chords' curvature; 0 where none shift)."""
        if self.count == 0:
            return 0.0
        sh = self.at(x, rest)
        # |s_v| = c |t_1 - t_0| = scale (nu R^2 / 2) kappa
        size = sh.c * np.linalg.norm(sh.t1 - sh.t0, axis=1) / self.scale
        return float(np.max(2.0 * size * self.radius / self.nu_r2))

    def at(self, x: np.ndarray, rest: np.ndarray) -> ShiftedCentreline:
        """The offset centreline at positions ``x`` [m] (V, 3) and edge rest lengths
        ``rest`` [m], with what its derivatives need."""
        x = np.asarray(x, dtype=np.float64)
        rest = np.asarray(rest, dtype=np.float64)
        e0 = x[self._mid] - x[self._prev]
        e1 = x[self._next] - x[self._mid]
        l0 = np.linalg.norm(e0, axis=1)
        l1 = np.linalg.norm(e1, axis=1)
        t0 = e0 / l0[:, None]
        t1 = e1 / l1[:, None]
        # s_v = (nu R^2 / 2) kappa_v = nu R^2 (t_1 - t_0) / (L0_bar + L1_bar), the chords'
        # rest lengths L_bar
        arc = (np.sum(rest[self._before] * self._weight_before, axis=1)
               + np.sum(rest[self._after] * self._weight_after, axis=1))
        c = self.scale * self.nu_r2 / arc
        shifted = x.copy()
        shifted[self._mid] += c[:, None] * (t1 - t0)
        return ShiftedCentreline(self, shifted, c, t0, t1, l0, l1)


@dataclass
class ShiftedCentreline:
    """The offset centreline x~ [m] (V, 3) of one state and its Jacobian's pieces.

    Attributes:
        shift: the :class:`SectionShift` it came from.
        x: the offset centreline [m].
        c: nu R^2 / (L0_bar + L1_bar) of each shifting vertex [m].
        t0, t1: the unit vectors of its chords before and after it.
        l0, l1: the chords' lengths [m].
    """

    shift: SectionShift
    x: np.ndarray
    c: np.ndarray
    t0: np.ndarray
    t1: np.ndarray
    l0: np.ndarray
    l1: np.ndarray
    _jac: tuple[np.ndarray, np.ndarray] | None = field(default=None, repr=False, compare=False)

    def _jacobian(self) -> tuple[np.ndarray, np.ndarray]:
        """Per vertex, its three Jacobian neighbours (x_{v-m}, x_v, x_{v+m}; -1 where
        none) and the 3 x 3 blocks d x~_v / d x_neighbour (symmetric); built once, for the
        gradient's, the Hessian's and the twist columns' pull-backs of one evaluation."""
        if self._jac is None:
            self._jac = self._build_jacobian()
        return self._jac

    def _build_jacobian(self) -> tuple[np.ndarray, np.ndarray]:
        """The pieces :meth:`_jacobian` returns."""
        sh = self.shift
        nv = self.x.shape[0]
        nbr = np.full((nv, 3), -1, dtype=np.int64)
        nbr[:, 1] = np.arange(nv)
        jac = np.zeros((nv, 3, 3, 3))
        jac[:, 1] = np.eye(3)
        eye = np.eye(3)
        # d s_v / d x_prev = c P_0 / l_0, d s_v / d x_next = c P_1 / l_1, d s_v / d x_v =
        # minus their sum (P = I - t t^T, the derivative of a unit tangent over its edge)
        a0 = (self.c / self.l0)[:, None, None] * (eye - self.t0[:, :, None] * self.t0[:, None, :])
        a1 = (self.c / self.l1)[:, None, None] * (eye - self.t1[:, :, None] * self.t1[:, None, :])
        mid = sh._mid
        nbr[mid, 0] = sh._prev
        nbr[mid, 2] = sh._next
        jac[mid, 0] = a0
        jac[mid, 1] -= a0 + a1
        jac[mid, 2] = a1
        return nbr, jac

    def pull_back_gradient(self, g: np.ndarray) -> np.ndarray:
        """A gradient over x~ (V, 3) carried to x: J^T g."""
        sh = self.shift
        out = np.array(g, dtype=np.float64)
        if sh.count == 0:
            return out
        nbr, jac = self._jacobian()
        gm = g[sh._mid]
        # the Jacobian blocks are symmetric: J^T g at a neighbour is the block times g
        out[sh._mid] += np.einsum("nij,nj->ni", jac[sh._mid, 1] - np.eye(3), gm)
        np.add.at(out, sh._prev, np.einsum("nij,nj->ni", jac[sh._mid, 0], gm))
        np.add.at(out, sh._next, np.einsum("nij,nj->ni", jac[sh._mid, 2], gm))
        return out

    def pull_back_entries(self, vertex: np.ndarray, comp: np.ndarray, value: np.ndarray
                          ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Entries of vectors over x~ (``value`` at coordinate ``comp`` of vertex ``vertex``)
        carried to x, J^T: (which input entry each output entry comes from, its vertex,
        its coordinate, its value); entries that J's blocks make zero are left out."""
        vertex = np.asarray(vertex, dtype=np.int64)
        comp = np.asarray(comp, dtype=np.int64)
        value = np.asarray(value, dtype=np.float64)
        nbr, jac = self._jacobian()
        # (J^T v)_(w, j) = sum over the x~_v that x_w moves of (d x~_(v, i) / d x_(w, j))
        # v_(v, i): row i = ``comp`` of each of the entry's three blocks
        src = np.repeat(np.arange(vertex.size), 9)
        out_vertex = np.repeat(nbr[vertex], 3, axis=1).ravel()
        out_comp = np.tile(np.arange(3), (vertex.size, 3)).ravel()
        out_value = (jac[vertex, :, comp, :] * value[:, None, None]).ravel()
        keep = (out_vertex >= 0) & (out_value != 0.0)
        return src[keep], out_vertex[keep], out_comp[keep], out_value[keep]

    def _curvature_blocks(self, g: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The term sum_v g_v . d2 x~_v / dx2 as 3 x 3 blocks: node pairs (J, 2) and blocks
        (J, 3, 3), for the shifting vertices whose g_v is not zero."""
        sh = self.shift
        gm = g[sh._mid]
        live = np.flatnonzero(np.any(gm != 0.0, axis=1))
        if live.size == 0:
            return np.zeros((0, 2), np.int64), np.zeros((0, 3, 3))

        def second(t: np.ndarray, length: np.ndarray, gv: np.ndarray) -> np.ndarray:
            # g . d2 t / de2 = [3 (g.t) t t^T - (g.t) I - g t^T - t g^T] / |e|^2
            gt = np.einsum("ni,ni->n", gv, t)[:, None, None]
            outer_tt = t[:, :, None] * t[:, None, :]
            sym = gv[:, :, None] * t[:, None, :] + t[:, :, None] * gv[:, None, :]
            return (3.0 * gt * outer_tt - gt * np.eye(3) - sym) / (length**2)[:, None, None]

        c = self.c[live][:, None, None]
        gv = gm[live]
        s1 = c * second(self.t1[live], self.l1[live], gv)
        s0 = c * second(self.t0[live], self.l0[live], gv)
        p, v, n = sh._prev[live], sh._mid[live], sh._next[live]
        # s_v = c (t_1 - t_0): t_1 on (x_v, x_next) with signs (-, +), t_0 on (x_prev, x_v)
        # with signs (-, +)
        pairs = [(n, n, s1), (v, v, s1 - s0), (n, v, -s1), (v, n, -s1),
                 (p, p, -s0), (p, v, s0), (v, p, s0)]
        keys = np.concatenate([np.stack([r, q], axis=1) for r, q, _ in pairs])
        return keys, np.concatenate([b for _, _, b in pairs])

    def pull_back_hessian(self, hess: BlockHessian, g: np.ndarray) -> BlockHessian:
        """A Hessian over x~ in node blocks (each node's first 3 dofs its position, the rest
        its own dofs, which the shift leaves alone), with the gradient ``g`` over x~ (V, 3)
        it was taken with, carried to x: J^T H J + sum_v g_v . d2 x~_v / dx2. The result's
        node pairs are the input's and their Jacobian neighbours', sorted."""
        sh = self.shift
        if sh.count == 0:
            return hess
        nodes = hess.node_dofs.shape[0]
        nbr, jac = self._jacobian()
        keys = hess.keys
        blocks = hess.blocks
        b = blocks.shape[1]
        a_node, b_node = keys[:, 0], keys[:, 1]
        pp = blocks[:, :3, :3]
        pc = blocks[:, :3, 3:]
        cp = blocks[:, 3:, :3]
        pp_keys, pp_vals, pc_keys, pc_vals, cp_keys, cp_vals = [], [], [], [], [], []
        for k1 in range(3):
            u = nbr[a_node, k1]
            ok_u = u >= 0
            ju = jac[a_node, k1]
            left = np.matmul(np.swapaxes(ju, 1, 2), pp)
            for k2 in range(3):
                w = nbr[b_node, k2]
                ok = ok_u & (w >= 0)
                if not ok.any():
                    continue
                pp_keys.append(u[ok] * nodes + w[ok])
                pp_vals.append(np.matmul(left[ok], jac[b_node[ok], k2]))
            if b > 3 and ok_u.any():
                pc_keys.append(u[ok_u] * nodes + b_node[ok_u])
                pc_vals.append(np.matmul(np.swapaxes(ju[ok_u], 1, 2), pc[ok_u]))
        if b > 3:
            for k2 in range(3):
                w = nbr[b_node, k2]
                ok = w >= 0
                if ok.any():
                    cp_keys.append(a_node[ok] * nodes + w[ok])
                    cp_vals.append(np.matmul(cp[ok], jac[b_node[ok], k2]))
        ck, cb = self._curvature_blocks(g)
        if ck.size:
            pp_keys.append(ck[:, 0] * nodes + ck[:, 1])
            pp_vals.append(cb)
        old = a_node * nodes + b_node
        all_keys, inverse = np.unique(np.concatenate([old, *pp_keys, *pc_keys, *cp_keys]),
                                      return_inverse=True)
        count = all_keys.size
        out = np.zeros((count, b, b))
        at = inverse[:old.size]
        out[at, 3:, 3:] = blocks[:, 3:, 3:]
        pos = old.size
        out[:, :3, :3] = _summed(inverse, pos, pp_keys, pp_vals, count, (3, 3))
        pos += sum(k.size for k in pp_keys)
        if b > 3:
            out[:, :3, 3:] = _summed(inverse, pos, pc_keys, pc_vals, count, (3, b - 3))
            pos += sum(k.size for k in pc_keys)
            out[:, 3:, :3] = _summed(inverse, pos, cp_keys, cp_vals, count, (b - 3, 3))
        # rows past the position come from the input's own rows (its blocks and the
        # coefficient-position pieces), columns likewise
        rows_in, cols_in = hess.masks()
        full_rows = np.zeros(count, dtype=bool)
        full_cols = np.zeros(count, dtype=bool)
        full_rows[at] = rows_in
        full_cols[at] = cols_in
        start = old.size + sum(k.size for k in pp_keys)
        n_pc = sum(k.size for k in pc_keys)
        if n_pc:
            full_cols[inverse[start:start + n_pc]] = True
        if cp_keys:
            full_rows[inverse[start + n_pc:]] = True
        pairs = np.stack([all_keys // nodes, all_keys % nodes], axis=1)
        return BlockHessian(hess.node_dofs, pairs, out, full_rows, full_cols)


def _summed(inverse: np.ndarray, start: int, keys: list[np.ndarray], vals: list[np.ndarray],
            count: int, shape: tuple[int, int]) -> np.ndarray:
    """Blocks ``vals`` summed into ``count`` slots, the slot of each from ``inverse`` read
    from ``start`` on."""
    size = shape[0] * shape[1]
    if not keys:
        return np.zeros((count, *shape))
    slots = inverse[start:start + sum(k.size for k in keys)]
    flat = (slots[:, None] * size + np.arange(size)).ravel()
    values = np.concatenate(vals).reshape(-1)
    return np.bincount(flat, weights=values, minlength=count * size).reshape(count, *shape)
