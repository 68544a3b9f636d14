"""The pair kernel: energy, gradient and Hessian of each candidate edge pair, and its launcher.

For an edge pair (a, b) and Gauss points g on a, h on b at distance rho,

    U_gh = om_g om_h l_a l_b W_excl Psi(s, R, q),

with om the Gauss weights on [0, 1], l the current edge lengths (the law is per unit length
of the deformed rod) and Psi the law of :mod:`tightknot.contact.pair_law`; R = r_a + r_b with
the stretched radii r = r0 (l/l_bar)^-nu, or given per edge (the smoothed radius of
:mod:`tightknot.contact.section_radius`: fixed while the positions move, and the kernel also
writes, per pair, [dE/dR, d2E/dR2, d(grad)/dR (4 vertices x 3)]). Gradient and Hessian:
:mod:`tightknot.contact.pair_assembly`.

The variants (gradient or not; Hessian none, 144 entries per pair, or added into the
system's CSC data; given radius or not) are kernels of one template made by
:func:`pair_kernel` with ``wp.static``: a variant has no run-time flag and takes only the
arrays it uses. All variants are made at import, so that the Warp module is complete before
its first (only) compile.
"""

import functools
import inspect
import types
from collections.abc import Callable
from enum import IntEnum
from typing import NamedTuple

import numpy as np
import warp as wp

from tightknot.contact.broad_phase import BroadPhase
from tightknot.contact.kernel_module import KERNEL_MODULE
from tightknot.contact.pair_assembly import (
    AngleHessian,
    HessianMoments,
    VertexVectors,
    add_moments,
    add_to_vertices,
    angle_hessian,
    crossing_angle,
    psi_gradient_z,
    psi_hessian_z,
    scatter_pair_blocks,
    store_pair_blocks,
    vertex_blocks,
    y_hessian,
)
from tightknot.contact.pair_law import (
    PairLaw,
    barrier_in_s,
    exclusion_weight,
    law_amplitudes,
    law_blend,
    law_kernels,
    pair_barrier,
    psi_derivatives,
    psi_value,
)
from tightknot.rods.staging import Launches, Output, Staging

f64 = wp.float64


class Hessian(IntEnum):
    """Where the pair kernel puts the Hessian."""

    NONE = 0
    PER_PAIR = 1
    """144 entries per pair, vertex order [a0, a1, b0, b1] (pair_assembly)."""
    CSC = 2
    """Added into the system's CSC data through its block tables (pair_assembly)."""


@wp.struct
class PairGeometry:
    """An edge pair (a, b) at the current positions, with its rest arcs and window."""

    xa0: wp.vec3d
    """First vertex of edge a [m]."""
    xb0: wp.vec3d
    ea: wp.vec3d
    """Edge vector of a [m]."""
    eb: wp.vec3d
    arc_a: wp.vec2d
    """Rest arc lengths of a's ends [m]."""
    arc_b: wp.vec2d
    same_rod: int
    closed: int
    """The rod of a is closed."""
    rod_length: wp.float64
    """Rest length of the rod of a [m]."""
    exclusion: wp.float64
    """The pair's exclusion window [m]."""
    d0: wp.float64
    """Rest contact radius r0_a + r0_b [m]."""


@wp.func
def gauss_offset(geo: PairGeometry, xg: wp.float64, xh: wp.float64) -> wp.vec3d:
    """r = x_g - x_h [m] of the Gauss points at (xg, xh) on the two edges."""
    return (geo.xa0 + xg * geo.ea) - (geo.xb0 + xh * geo.eb)


@wp.func
def window_weight(geo: PairGeometry, law: PairLaw, xg: wp.float64, xh: wp.float64
                  ) -> wp.vec3d:
    """(W_excl, g_sep, skip) of a Gauss pair (see pair_law.exclusion_weight)."""
    return exclusion_weight(geo.same_rod, geo.closed, geo.rod_length, geo.arc_a, geo.arc_b,
                            geo.exclusion, geo.d0, law.candidate_window, xg, xh)


@wp.func
def closest_approach(geo: PairGeometry, law: PairLaw, gauss_xi: wp.array(dtype=wp.float64),
                     R: wp.float64):
    """The smallest s = rho^2 [m^2] of the pair's Gauss pairs where the law acts, and
    whether a Gauss pair lies inside the local barrier (1) or not (0)."""
    ng = gauss_xi.shape[0]
    s_min = f64(1.0e300)
    local_hit = int(0)  # noqa: UP018 (Warp: a literal is a constant)
    for gi in range(ng):
        for hi in range(ng):
            xg = gauss_xi[gi]
            xh = gauss_xi[hi]
            ex = window_weight(geo, law, xg, xh)
            if ex[2] != f64(0.0):
                continue
            r = gauss_offset(geo, xg, xh)
            ss = wp.dot(r, r)
            if ex[0] > f64(0.0):
                s_min = wp.min(s_min, ss)
            if ex[1] < f64(1.0):
                lim = law.local_core_fraction * ex[1] * R
                if ss < lim * lim:
                    local_hit = 1
    return s_min, local_hit


def _kernel_without(template: Callable, unused: set[str], key: str) -> wp.Kernel:
    """A kernel of the function ``template`` without its parameters ``unused``, in the
    contact kernels' module.

    Warp takes a kernel's parameters from its function's signature and annotations and its
    body from the source: a copy of the function (same code and closure, so the same
    ``wp.static`` values) with those two trimmed is the template minus the parameters that
    only its statically dead branches read."""
    sig = inspect.signature(template)
    params = [p for name, p in sig.parameters.items() if name not in unused]
    func = types.FunctionType(template.__code__, template.__globals__, key,
                              template.__defaults__, template.__closure__)
    func.__signature__ = sig.replace(parameters=params)
    func.__annotations__ = {p.name: p.annotation for p in params}
    return wp.Kernel(func, key=key, module=wp.get_module(KERNEL_MODULE))


@functools.cache
def pair_kernel(gradient: bool, hessian: Hessian, given_radius: bool) -> wp.Kernel:
    """The pair kernel's variant: with the gradient or not, the Hessian ``hessian`` (which
    needs the gradient) and the contact radius given per edge or from the stretch."""
    if hessian != Hessian.NONE and not gradient:
        raise ValueError("a Hessian needs the gradient")
    per_pair = hessian == Hessian.PER_PAIR
    csc = hessian == Hessian.CSC
    any_hessian = hessian != Hessian.NONE
    radius_terms = given_radius and gradient

    def contact_pair(
        # Model:
        edge_vertex: wp.array(dtype=wp.vec2i),
        edge_rod: wp.array(dtype=wp.int32),
        rod_closed: wp.array(dtype=wp.int32),
        edge_radius0: wp.array(dtype=wp.float64),
        edge_poisson: wp.array(dtype=wp.float64),
        edge_modulus: wp.array(dtype=wp.float64),
        edge_exclusion: wp.array(dtype=wp.float64),
        gauss_xi: wp.array(dtype=wp.float64),
        gauss_w: wp.array(dtype=wp.float64),
        law: PairLaw,
        # Data in:
        x_in: wp.array(dtype=wp.vec3d),
        pairs_in: wp.array(dtype=wp.vec2i),
        edge_rest_length_in: wp.array(dtype=wp.float64),
        edge_arc_in: wp.array(dtype=wp.vec2d),
        rod_length_in: wp.array(dtype=wp.float64),
        edge_radius_in: wp.array(dtype=wp.float64),  # given_radius
        block_keys_in: wp.array(dtype=wp.int64),  # csc: the pattern's block table
        block_rows_in: wp.array(dtype=wp.int32),  # csc
        block_cols_in: wp.array(dtype=wp.vec3i),  # csc
        vertex_rank_in: wp.array(dtype=wp.vec3i),  # csc
        # Out:
        energy_out: wp.array(dtype=wp.float64),
        overlap_out: wp.array(dtype=wp.float64),
        grad_out: wp.array(dtype=wp.vec3d),  # gradient
        hess_out: wp.array(dtype=wp.float64),  # per_pair: 144 per pair
        csc_out: wp.array(dtype=wp.float64),  # csc: the CSC data, added into
        missing_out: wp.array(dtype=wp.int32),  # csc: count of missing blocks
        dR_out: wp.array(dtype=wp.float64),  # radius_terms: 14 per pair
    ):
        p = wp.tid()
        pr = pairs_in[p]
        a = pr[0]
        b = pr[1]
        va = edge_vertex[a]
        vb = edge_vertex[b]
        xa0 = x_in[va[0]]
        xb0 = x_in[vb[0]]
        ea = x_in[va[1]] - xa0
        eb = x_in[vb[1]] - xb0
        la = wp.length(ea)
        lb = wp.length(eb)
        ta = ea / la
        tb = eb / lb
        if wp.static(given_radius):
            r_a = edge_radius_in[a]
            r_b = edge_radius_in[b]
        else:
            r_a = edge_radius0[a] * wp.pow(la / edge_rest_length_in[a], -edge_poisson[a])
            r_b = edge_radius0[b] * wp.pow(lb / edge_rest_length_in[b], -edge_poisson[b])
        R = r_a + r_b
        geo = PairGeometry()
        geo.xa0 = xa0
        geo.xb0 = xb0
        geo.ea = ea
        geo.eb = eb
        geo.arc_a = edge_arc_in[a]
        geo.arc_b = edge_arc_in[b]
        rod = edge_rod[a]
        if edge_rod[b] == rod:
            geo.same_rod = 1
        geo.closed = rod_closed[rod]
        geo.rod_length = rod_length_in[rod]
        geo.exclusion = wp.max(edge_exclusion[a], edge_exclusion[b])
        d0 = edge_radius0[a] + edge_radius0[b]
        geo.d0 = d0
        # Most candidates do not interact: find the closest Gauss pair first and leave
        # before the pair constants (powers) when it lies outside the contact radius.
        s_min, local_hit = closest_approach(geo, law, gauss_xi, R)
        if s_min >= R * R and local_hit == 0:
            if wp.static(radius_terms):
                for k in range(14):
                    dR_out[p * 14 + k] = f64(0.0)
            energy_out[p] = f64(0.0)
            overlap_out[p] = R - wp.sqrt(s_min)
            return
        # The harmonic-mean modulus of the pair [Pa].
        emod = f64(2.0) * edge_modulus[a] * edge_modulus[b] / (edge_modulus[a]
                                                                + edge_modulus[b])
        amp = law_amplitudes(law, emod, d0, R)
        # dR/dl and d2R/dl2 of the stretched radii; zero for a given radius.
        R_a = f64(0.0)
        R_b = f64(0.0)
        R_aa = f64(0.0)
        R_bb = f64(0.0)
        if wp.static(not given_radius):
            nua = edge_poisson[a]
            nub = edge_poisson[b]
            R_a = -nua * r_a / la
            R_b = -nub * r_b / lb
            R_aa = nua * (nua + f64(1.0)) * r_a / (la * la)
            R_bb = nub * (nub + f64(1.0)) * r_b / (lb * lb)
        ang = crossing_angle(ta, tb, la, lb)
        bl = law_blend(law, ang.q)
        # Which laws the blend uses (its weights and their derivatives in q exactly zero
        # otherwise): skipping a law whose every weight is zero changes no bit of the sums.
        use_line = int(1)  # noqa: UP018 (Warp: a literal is a constant)
        if bl.line == f64(0.0) and bl.line_q == f64(0.0) and bl.line_qq == f64(0.0):
            use_line = 0
        use_point = int(0)  # noqa: UP018 (Warp: a literal is a constant)
        if bl.xi > f64(0.0):
            use_point = 1
        # The barrier diverges at rho_hard = hard + 0.58 l_max: every point of a polyline is
        # within 0.29 l of one of its Gauss points (2 per edge: 0.577 l apart inside an
        # edge, 0.42 l across a vertex; 3 per edge: closer), so it stops two segments
        # before their distance reaches the step bound's hard limit.
        lmax = wp.max(edge_rest_length_in[a], edge_rest_length_in[b])
        rho_hard = law.hard_fraction * d0 + f64(0.58) * lmax
        # Barrier stiffness k E/D [J/m^2 per m^2 of (rho - rho_core)^2]: the barrier density
        # k E D (dy/D)^2 ln(y/yc) is an energy per length^2 like the law's.
        kcore = law.core_stiffness * emod / d0
        ah = AngleHessian()
        if wp.static(any_hessian):
            ah = angle_hessian(ta, tb, la, lb, ang)
        energy = f64(0.0)
        xmax = f64(-1.0e30)
        grad = VertexVectors()
        grad_R = VertexVectors()
        e_R = f64(0.0)
        e_RR = f64(0.0)
        mo = HessianMoments()
        any_hess = int(0)  # noqa: UP018 (Warp: a literal is a constant)
        ng = gauss_xi.shape[0]
        for gi in range(ng):
            for hi in range(ng):
                xg = gauss_xi[gi]
                xh = gauss_xi[hi]
                ex = window_weight(geo, law, xg, xh)
                if ex[2] != f64(0.0):
                    continue
                wex = ex[0]
                r = gauss_offset(geo, xg, xh)
                s = wp.dot(r, r)
                rho = wp.sqrt(s)
                if wex > f64(0.0):
                    xmax = wp.max(xmax, R - rho)
                if rho >= R:
                    continue
                u = rho / R
                Fl, Fp = law_kernels(law, amp, use_line, use_point, wex, R, u)
                hb = pair_barrier(law, rho, R, rho_hard, ex[1], kcore)
                if hb[0, 0] >= f64(1.0e299):
                    # Past the barrier's divergence: an energy no line search accepts, and
                    # no derivatives (they would overflow the assembled matrix).
                    energy += f64(1.0e300)
                    continue
                bv = barrier_in_s(hb, rho, s)
                Psi = psi_value(bl, Fl, Fp, bv)
                wgt = gauss_w[gi] * gauss_w[hi]
                P = la * lb
                energy += wgt * P * Psi
                if wp.static(gradient):
                    d = psi_derivatives(bl, Fl, Fp, hb, bv, rho, s)
                    Pz = psi_gradient_z(d.s, d.R, d.q, R_a, R_b)
                    # F = P Psi with P = l_a l_b.
                    Pp = wp.vec4d(f64(0.0), lb, la, f64(0.0))
                    Fz = wgt * (P * Pz + Psi * Pp)
                    gr_s = f64(2.0) * r
                    add_to_vertices(grad, xg, xh, Fz[0] * gr_s, Fz[1] * ta + Fz[3] * ang.dq_a,
                                    Fz[2] * tb + Fz[3] * ang.dq_b)
                    if wp.static(given_radius):
                        # d/dR at fixed positions (R_a = R_b = 0 here): Pz = (Ps, 0, 0, Pq).
                        e_R += wgt * P * d.R
                        e_RR += wgt * P * d.RR
                        dF0 = wgt * P * d.sR
                        dF1 = wgt * d.R * lb
                        dF2 = wgt * d.R * la
                        dF3 = wgt * P * d.Rq
                        add_to_vertices(grad_R, xg, xh, dF0 * gr_s, dF1 * ta + dF3 * ang.dq_a,
                                        dF2 * tb + dF3 * ang.dq_b)
                    if wp.static(any_hessian):
                        Pzz = psi_hessian_z(d.ss, d.sR, d.RR, d.sq, d.Rq, d.qq, d.R, R_a, R_b,
                                            R_aa, R_bb)
                        Fzz = wgt * (P * Pzz + wp.outer(Pp, Pz) + wp.outer(Pz, Pp))
                        Fzz[1, 2] = Fzz[1, 2] + wgt * Psi
                        Fzz[2, 1] = Fzz[2, 1] + wgt * Psi
                        add_moments(mo, xg, xh, y_hessian(Fz, Fzz, gr_s, ta, tb, la, lb, ang,
                                                          ah))
                        any_hess = 1
        if wp.static(per_pair):
            if any_hess != 0:
                store_pair_blocks(hess_out, p, vertex_blocks(mo))
        if wp.static(csc):
            if any_hess != 0:
                scatter_pair_blocks(block_keys_in, block_rows_in, block_cols_in,
                                    vertex_rank_in, wp.vec4i(va[0], va[1], vb[0], vb[1]),
                                    vertex_blocks(mo), csc_out, missing_out)
        energy_out[p] = energy
        overlap_out[p] = xmax
        if wp.static(radius_terms):
            o = p * 14
            dR_out[o] = e_R
            dR_out[o + 1] = e_RR
            for i in range(3):
                dR_out[o + 2 + i] = grad_R.a0[i]
                dR_out[o + 5 + i] = grad_R.a1[i]
                dR_out[o + 8 + i] = grad_R.b0[i]
                dR_out[o + 11 + i] = grad_R.b1[i]
        if wp.static(gradient):
            wp.atomic_add(grad_out, va[0], grad.a0)
            wp.atomic_add(grad_out, va[1], grad.a1)
            wp.atomic_add(grad_out, vb[0], grad.b0)
            wp.atomic_add(grad_out, vb[1], grad.b1)

    unused = set()
    if not given_radius:
        unused.add("edge_radius_in")
    if not csc:
        unused |= {"block_keys_in", "block_rows_in", "block_cols_in", "vertex_rank_in",
                   "csc_out", "missing_out"}
    if not gradient:
        unused.add("grad_out")
    if not per_pair:
        unused.add("hess_out")
    if not radius_terms:
        unused.add("dR_out")
    key = f"contact_pair_g{int(gradient)}_h{int(hessian)}_r{int(given_radius)}"
    return _kernel_without(contact_pair, unused, key)


#: The variants the layer launches: energy only, with the gradient, with a Hessian.
VARIANTS = [(g, h, r) for r in (False, True)
            for g, h in ((False, Hessian.NONE), (True, Hessian.NONE),
                         (True, Hessian.PER_PAIR), (True, Hessian.CSC))]
for _variant in VARIANTS:
    pair_kernel(*_variant)


class PairTerms(NamedTuple):
    """What one launch of the pair kernel gives."""

    pairs: wp.array
    """The pairs evaluated (vec2i)."""
    energy: np.ndarray
    """Energy of each pair [J] (host)."""
    grad: wp.array
    """Gradient over vertex positions [N], (vertex_count,) vec3d (zero without gradient)."""
    hess: wp.array | None
    """The per-pair Hessian entries [N/m] (Hessian.PER_PAIR), else None."""
    overlap: np.ndarray
    """Largest R - rho of each pair's Gauss pairs where the law acts [m] (host)."""
    missing: wp.array
    """Count of Hessian blocks missing from the tables (Hessian.CSC), (1,) int32."""


class PairKernel:
    """Launches the pair kernel variants over candidate pairs of a model.

    Args:
        broad: the layer's broad phase (edge tables, candidate buffer).
        law: the pair law (:func:`tightknot.contact.pair_law.pair_law`).
        gauss: Gauss points and weights on [0, 1].
        edge_radius0: rest radius of each edge [m].
        edge_poisson: Poisson ratio nu of each edge's section thinning [-].
        edge_modulus: Young's modulus of each edge [Pa].
    """

    def __init__(self, broad: BroadPhase, law: PairLaw,
                 gauss: tuple[list[float], list[float]], edge_radius0: np.ndarray,
                 edge_poisson: np.ndarray, edge_modulus: np.ndarray) -> None:
        dev = broad.device
        self.broad = broad
        self.device = dev
        self.law = law
        self._model_args = [
            broad.edge_vertex, broad.edge_rod, broad.rod_closed,
            wp.array(edge_radius0, dtype=f64, device=dev),
            wp.array(edge_poisson, dtype=f64, device=dev),
            wp.array(edge_modulus, dtype=f64, device=dev),
            broad.edge_exclusion,
            wp.array(gauss[0], dtype=f64, device=dev),
            wp.array(gauss[1], dtype=f64, device=dev),
            law,
        ]
        vertex_count = broad.model.vertex_count
        # Inputs and outputs reused from call to call, and the launches recorded over them
        # (tightknot.rods.staging).
        self._in_rest = Staging(wp.float64, dev)
        self._grad = wp.zeros(vertex_count, dtype=wp.vec3d, device=dev)
        self._missing = wp.zeros(1, dtype=wp.int32, device=dev)
        self._energy = Output(wp.float64, dev)
        self._overlap = Output(wp.float64, dev)
        self._dR = Output(wp.float64, dev)
        self._launches = Launches()

    def launch(self, wx: wp.array, pairs: wp.array, rest: np.ndarray, arcs: wp.array,
               rod_len: wp.array, gradient: bool, hessian: Hessian,
               tables: tuple[wp.array, ...] | None = None, csc: wp.array | None = None,
               radius: wp.array | None = None) -> PairTerms:
        """Evaluate ``pairs`` at positions ``wx`` [m] with edge rest lengths ``rest`` [m]
        and rest arcs ``arcs``, ``rod_len`` (:meth:`BroadPhase.arcs`). ``tables``, ``csc``:
        the block tables and CSC data for Hessian.CSC; ``radius``: the contact radius of
        each edge [m] if given (then :meth:`radius_derivatives` holds the pairs' dE/dR,
        d2E/dR2 and d(grad)/dR)."""
        dev = self.device
        npairs = pairs.shape[0]
        # The gradient and the missing-block count are returned: fresh for each call, as
        # callers may hold them; zeroed reused arrays for the kernel's sums.
        grad, missing = self._grad, self._missing
        grad.zero_()
        missing.zero_()
        if npairs == 0:
            return PairTerms(pairs, np.zeros(0), wp.clone(grad), None, np.zeros(0),
                             wp.clone(missing))
        gradient = bool(gradient or hessian != Hessian.NONE)
        given = radius is not None
        # The kernel writes every pair's energy and overlap (no zeroing needed).
        energy = self._energy.get(npairs)
        overlap = self._overlap.get(npairs)
        inputs = [*self._model_args, wx, self.broad.buffer_of(pairs),
                  self._in_rest.put(rest), arcs, rod_len]
        outputs = [energy, overlap]
        if given:
            inputs.append(radius)
        if hessian == Hessian.CSC:
            inputs.extend(tables)
        if gradient:
            outputs.append(grad)
        hess = None
        if hessian == Hessian.PER_PAIR:
            hess = wp.zeros(npairs * 144, dtype=wp.float64, device=dev)
            outputs.append(hess)
        if hessian == Hessian.CSC:
            outputs.extend([csc, missing])
        if given and gradient:
            outputs.append(self._dR.get(14 * npairs))
        self._launches.launch(pair_kernel(gradient, hessian, given), npairs, dev, inputs,
                              outputs)
        return PairTerms(pairs, self._energy.numpy(npairs), wp.clone(grad), hess,
                         self._overlap.numpy(npairs), wp.clone(missing))

    def radius_derivatives(self, npairs: int) -> np.ndarray:
        """Per pair of the last launch with a given radius and the gradient: [dE/dR [J/m],
        d2E/dR2 [J/m^2], d(grad)/dR (4 vertices x 3) [N/m]], shape (npairs, 14)."""
        return self._dR.numpy(14 * npairs).reshape(-1, 14)
