"""The chain rule from a Gauss pair's law to the pair's four vertices, and its blocks.

The pair energy of Gauss points g on edge a, h on edge b is F = om_g om_h l_a l_b Psi with
Psi (:mod:`tightknot.contact.pair_law`) a function of four scalars z = (s, l_a, l_b, q)
(the contact radius R depends on the lengths), which are functions of three vectors
Y = (r = x_g - x_h, e_a, e_b): s = r.r, l = |e|, q = c^2 with c = t_a.t_b. Gradient and
Hessian go through z and Y, then through the linear map Y -> vertices,

    r = (1 - xg) xa0 + xg xa1 - (1 - xh) xb0 - xh xb1,   e_a = xa1 - xa0,   e_b = xb1 - xb0.

Local vertex order of a pair: [a0, a1, b0, b1]; in the per-pair layout the Hessian entry
(3 v + i, 3 w + j) sits at ``pair * 144 + (3 v + i) * 12 + 3 w + j``.
"""

from __future__ import annotations

import warp as wp

f64 = wp.float64


@wp.struct
class PairAngle:
    """c = t_a.t_b and q = c^2 with their gradients in e_a, e_b [1/m]."""

    c: wp.float64
    q: wp.float64
    dc_a: wp.vec3d
    dc_b: wp.vec3d
    dq_a: wp.vec3d
    dq_b: wp.vec3d


@wp.struct
class AngleHessian:
    """Second derivatives of q in (e_a, e_b) [1/m^2] and the tangents' projectors."""

    Pa: wp.mat33d
    """I - t_a t_a^T."""
    Pb: wp.mat33d
    Hq_aa: wp.mat33d
    Hq_bb: wp.mat33d
    Hq_ab: wp.mat33d


@wp.struct
class VertexVectors:
    """One vector per vertex of a pair, in the local order [a0, a1, b0, b1]."""

    a0: wp.vec3d
    a1: wp.vec3d
    b0: wp.vec3d
    b1: wp.vec3d


@wp.struct
class YBlocks:
    """The Y-space Hessian blocks of one Gauss pair: (r, r), (r, e_a), (r, e_b), (e_a, e_a),
    (e_b, e_b), (e_a, e_b)."""

    rr: wp.mat33d
    ra: wp.mat33d
    rb: wp.mat33d
    aa: wp.mat33d
    bb: wp.mat33d
    ab: wp.mat33d


@wp.struct
class HessianMoments:
    """Sums over the Gauss pairs from which the vertex blocks follow (the map to the
    vertices is linear in (xg, xh)): moments of H_rr in (1, xg, xh, xg^2, xh^2, xg xh), of
    H_ra and H_rb in (1, xg, xh), and the sums of H_aa, H_bb, H_ab."""

    M0: wp.mat33d
    Mg: wp.mat33d
    Mh: wp.mat33d
    Mgg: wp.mat33d
    Mhh: wp.mat33d
    Mgh: wp.mat33d
    A0: wp.mat33d
    Ag: wp.mat33d
    Ah: wp.mat33d
    B0: wp.mat33d
    Bg: wp.mat33d
    Bh: wp.mat33d
    Saa: wp.mat33d
    Sbb: wp.mat33d
    Sab: wp.mat33d


@wp.struct
class PairBlocks:
    """The upper vertex blocks H_vw (v <= w) of a pair's Hessian [N/m]."""

    m00: wp.mat33d
    m01: wp.mat33d
    m02: wp.mat33d
    m03: wp.mat33d
    m11: wp.mat33d
    m12: wp.mat33d
    m13: wp.mat33d
    m22: wp.mat33d
    m23: wp.mat33d
    m33: wp.mat33d


@wp.func
def outer33(a: wp.vec3d, b: wp.vec3d) -> wp.mat33d:
    return wp.outer(a, b)


@wp.func
def crossing_angle(ta: wp.vec3d, tb: wp.vec3d, la: wp.float64, lb: wp.float64) -> PairAngle:
    """c, q and their gradients from the unit tangents and lengths [m] of the edges."""
    out = PairAngle()
    c = wp.dot(ta, tb)
    out.c = c
    out.q = c * c
    out.dc_a = (tb - c * ta) / la
    out.dc_b = (ta - c * tb) / lb
    out.dq_a = f64(2.0) * c * out.dc_a
    out.dq_b = f64(2.0) * c * out.dc_b
    return out


@wp.func
def angle_hessian(ta: wp.vec3d, tb: wp.vec3d, la: wp.float64, lb: wp.float64,
                  ang: PairAngle) -> AngleHessian:
    """Hessian of q = c^2: 2 (dc dc^T + c Hess(c)), with Hess(c) of c = t_a.t_b in the
    edge vectors (constants of the pair, used by every Gauss pair)."""
    out = AngleHessian()
    c = ang.c
    eye = wp.identity(n=3, dtype=wp.float64)
    out.Pa = eye - outer33(ta, ta)
    out.Pb = eye - outer33(tb, tb)
    ua = tb - c * ta
    ub = ta - c * tb
    Hc_aa = (-(outer33(ua, ta) + outer33(ta, ua)) - c * out.Pa) / (la * la)
    Hc_bb = (-(outer33(ub, tb) + outer33(tb, ub)) - c * out.Pb) / (lb * lb)
    Hc_ab = (out.Pb - outer33(ta, ub)) / (la * lb)
    out.Hq_aa = f64(2.0) * (outer33(ang.dc_a, ang.dc_a) + c * Hc_aa)
    out.Hq_bb = f64(2.0) * (outer33(ang.dc_b, ang.dc_b) + c * Hc_bb)
    out.Hq_ab = f64(2.0) * (outer33(ang.dc_a, ang.dc_b) + c * Hc_ab)
    return out


@wp.func
def psi_gradient_z(ps: wp.float64, pR: wp.float64, pq: wp.float64, R_a: wp.float64,
                   R_b: wp.float64) -> wp.vec4d:
    """Psi's gradient in z = (s, l_a, l_b, q), from those in (s, R, q) and R's in the
    lengths (R_a = dR/dl_a)."""
    return wp.vec4d(ps, pR * R_a, pR * R_b, pq)


@wp.func
def psi_hessian_z(pss: wp.float64, psR: wp.float64, pRR: wp.float64, psq: wp.float64,
                  pRq: wp.float64, pqq: wp.float64, pR: wp.float64, R_a: wp.float64,
                  R_b: wp.float64, R_aa: wp.float64, R_bb: wp.float64) -> wp.mat44d:
    """Psi's Hessian in z = (s, l_a, l_b, q) (R_aa = d2R/dl_a^2; R is a sum of one function
    of l_a and one of l_b)."""
    return wp.mat44d(
        pss, psR * R_a, psR * R_b, psq,
        psR * R_a, pRR * R_a * R_a + pR * R_aa, pRR * R_a * R_b, pRq * R_a,
        psR * R_b, pRR * R_a * R_b, pRR * R_b * R_b + pR * R_bb, pRq * R_b,
        psq, pRq * R_a, pRq * R_b, pqq)


@wp.func
def add_to_vertices(acc: wp.ref[VertexVectors], xg: wp.float64, xh: wp.float64,
                    gr: wp.vec3d, ga: wp.vec3d, gb: wp.vec3d):
    """Add a gradient in Y = (r, e_a, e_b) to the four vertices (the transpose of the
    linear map Y -> vertices, module docstring)."""
    acc.a0 += (f64(1.0) - xg) * gr - ga
    acc.a1 += xg * gr + ga
    acc.b0 += -(f64(1.0) - xh) * gr - gb
    acc.b1 += -xh * gr + gb


@wp.func
def rank1_pair(u: wp.vec3d, fu: wp.float64, fv: wp.float64, a: wp.vec3d, v: wp.vec3d
               ) -> wp.mat33d:
    """outer(u, fu a + fv v): a Y-space block sum_kl Fzz[k, l] outer(g_k, g_l) with one
    nonzero z-gradient g on the left (``u``) and two on the right (``a``, ``v``)."""
    return outer33(u, fu * a + fv * v)


@wp.func
def rank2_pair(u1: wp.vec3d, u3: wp.vec3d, f11: wp.float64, f13: wp.float64,
               f31: wp.float64, f33: wp.float64, a: wp.vec3d, v: wp.vec3d) -> wp.mat33d:
    """outer(u1, f11 a + f13 v) + outer(u3, f31 a + f33 v): a Y-space block with two
    nonzero z-gradients on each side."""
    return outer33(u1, f11 * a + f13 * v) + outer33(u3, f31 * a + f33 * v)


@wp.func
def y_hessian(Fz: wp.vec4d, Fzz: wp.mat44d, gr_s: wp.vec3d, ta: wp.vec3d, tb: wp.vec3d,
              la: wp.float64, lb: wp.float64, ang: PairAngle, ah: AngleHessian) -> YBlocks:
    """The Y-space blocks sum_kl Fzz[k, l] outer(g_k, g_l) + sum_k Fz[k] Hess(z_k) over the
    z-gradients of the blocks' variables (r: only s, gradient 2 r; e_a: l_a (t_a) and q;
    e_b: l_b and q; Hess(l) = P/l)."""
    out = YBlocks()
    eye = wp.identity(n=3, dtype=wp.float64)
    out.rr = outer33(gr_s, Fzz[0, 0] * gr_s) + (f64(2.0) * Fz[0]) * eye
    out.ra = rank1_pair(gr_s, Fzz[0, 1], Fzz[0, 3], ta, ang.dq_a)
    out.rb = rank1_pair(gr_s, Fzz[0, 2], Fzz[0, 3], tb, ang.dq_b)
    out.aa = rank2_pair(ta, ang.dq_a, Fzz[1, 1], Fzz[1, 3], Fzz[3, 1], Fzz[3, 3], ta,
                        ang.dq_a) + (Fz[1] / la) * ah.Pa + Fz[3] * ah.Hq_aa
    out.bb = rank2_pair(tb, ang.dq_b, Fzz[2, 2], Fzz[2, 3], Fzz[3, 2], Fzz[3, 3], tb,
                        ang.dq_b) + (Fz[2] / lb) * ah.Pb + Fz[3] * ah.Hq_bb
    out.ab = rank2_pair(ta, ang.dq_a, Fzz[1, 2], Fzz[1, 3], Fzz[3, 2], Fzz[3, 3], tb,
                        ang.dq_b) + Fz[3] * ah.Hq_ab
    return out


@wp.func
def add_moments(mo: wp.ref[HessianMoments], xg: wp.float64, xh: wp.float64, y: YBlocks):
    """Add a Gauss pair's Y blocks to the moments (see :class:`HessianMoments`)."""
    mo.M0 = mo.M0 + y.rr
    mo.Mg = mo.Mg + xg * y.rr
    mo.Mh = mo.Mh + xh * y.rr
    mo.Mgg = mo.Mgg + (xg * xg) * y.rr
    mo.Mhh = mo.Mhh + (xh * xh) * y.rr
    mo.Mgh = mo.Mgh + (xg * xh) * y.rr
    mo.A0 = mo.A0 + y.ra
    mo.Ag = mo.Ag + xg * y.ra
    mo.Ah = mo.Ah + xh * y.ra
    mo.B0 = mo.B0 + y.rb
    mo.Bg = mo.Bg + xg * y.rb
    mo.Bh = mo.Bh + xh * y.rb
    mo.Saa = mo.Saa + y.aa
    mo.Sbb = mo.Sbb + y.bb
    mo.Sab = mo.Sab + y.ab


@wp.func
def vertex_blocks(mo: HessianMoments) -> PairBlocks:
    """Vertex blocks H_vw = sum_gh C_v^T H_Y C_w with the coefficients of (r, e_a, e_b) in
    vertex v: c_r = alpha_v + beta_v xg + gamma_v xh (alpha = (1, 0, -1, 0), beta =
    (-1, 1, 0, 0), gamma = (0, 0, 1, -1)), c_a = (-1, 1, 0, 0), c_b = (0, 0, -1, 1).

    Written out with the zero coefficients dropped (the moments' sums are linear in the
    coefficients); the remaining terms keep the order of the generic sum
    (alpha alpha) M0 + (alpha beta + beta alpha) Mg + (alpha gamma + gamma alpha) Mh
    + (beta beta) Mgg + (gamma gamma) Mhh + (beta gamma + gamma beta) Mgh
    + c_a,w Ra_v + c_b,w Rb_v + c_a,v Ra_w^T + c_b,v Rb_w^T
    + c_a,v c_a,w Saa + c_b,v c_b,w Sbb + c_a,v c_b,w Sab + c_b,v c_a,w Sab^T,
    with Ra_v = sum c_r,v H_ra, Rb_v = sum c_r,v H_rb (a + (-1) b is a - b exactly, and
    -a + b is b - a: the same bits as the sum)."""
    Ra0 = mo.A0 - mo.Ag
    Rb0 = mo.B0 - mo.Bg
    Ra1 = mo.Ag
    Rb1 = mo.Bg
    Ra2 = mo.Ah - mo.A0
    Rb2 = mo.Bh - mo.B0
    Ra3 = -mo.Ah
    Rb3 = -mo.Bh
    out = PairBlocks()
    out.m00 = mo.M0 - f64(2.0) * mo.Mg + mo.Mgg - Ra0 - wp.transpose(Ra0) + mo.Saa
    out.m01 = mo.Mg - mo.Mgg + Ra0 - wp.transpose(Ra1) - mo.Saa
    out.m02 = mo.Mg - mo.M0 + mo.Mh - mo.Mgh - Rb0 - wp.transpose(Ra2) + mo.Sab
    out.m03 = mo.Mgh - mo.Mh + Rb0 - wp.transpose(Ra3) - mo.Sab
    out.m11 = mo.Mgg + Ra1 + wp.transpose(Ra1) + mo.Saa
    out.m12 = mo.Mgh - mo.Mg - Rb1 + wp.transpose(Ra2) - mo.Sab
    out.m13 = Rb1 - mo.Mgh + wp.transpose(Ra3) + mo.Sab
    out.m22 = mo.M0 - f64(2.0) * mo.Mh + mo.Mhh - Rb2 - wp.transpose(Rb2) + mo.Sbb
    out.m23 = mo.Mh - mo.Mhh + Rb2 - wp.transpose(Rb3) - mo.Sbb
    out.m33 = mo.Mhh + Rb3 + wp.transpose(Rb3) + mo.Sbb
    return out


# -- per-pair layout (144 entries per pair) ------------------------------------------------
@wp.func
def set_hess(out: wp.array(dtype=wp.float64), base: int, v: int, w: int, m: wp.mat33d):
    for i in range(3):
        for j in range(3):
            out[base + (3 * v + i) * 12 + 3 * w + j] = m[i, j]


@wp.func
def set_block_pair(out: wp.array(dtype=wp.float64), base: int, v: int, w: int,
                   m: wp.mat33d):
    """Block (v, w) and, off the diagonal, its transpose (w, v)."""
    set_hess(out, base, v, w, m)
    if w != v:
        set_hess(out, base, w, v, wp.transpose(m))


@wp.func
def store_pair_blocks(out: wp.array(dtype=wp.float64), pair: int, bl: PairBlocks):
    """The pair's 4 x 4 vertex blocks into its 144 entries of ``out``."""
    base = pair * 144
    set_block_pair(out, base, 0, 0, bl.m00)
    set_block_pair(out, base, 0, 1, bl.m01)
    set_block_pair(out, base, 0, 2, bl.m02)
    set_block_pair(out, base, 0, 3, bl.m03)
    set_block_pair(out, base, 1, 1, bl.m11)
    set_block_pair(out, base, 1, 2, bl.m12)
    set_block_pair(out, base, 1, 3, bl.m13)
    set_block_pair(out, base, 2, 2, bl.m22)
    set_block_pair(out, base, 2, 3, bl.m23)
    set_block_pair(out, base, 3, 3, bl.m33)


# -- into the system's CSC data ------------------------------------------------------------
@wp.func
def find_key(keys: wp.array(dtype=wp.int64), key: wp.int64, lo: int, hi: int) -> int:
    """Index of ``key`` in the sorted array ``keys`` within [lo, hi), -1 if absent (binary
    search)."""
    a = int(lo)
    b = int(hi)
    while a < b:
        mid = (a + b) // 2
        if keys[mid] < key:
            a = mid + 1
        else:
            b = mid
    if a < hi:
        if keys[a] == key:
            return a
    return -1


@wp.func
def scatter_block(block_keys: wp.array(dtype=wp.int64), block_rows: wp.array(dtype=wp.int32),
                  block_cols: wp.array(dtype=wp.vec3i), vertex_rank: wp.array(dtype=wp.vec3i),
                  vr: int, vc: int, m: wp.mat33d, csc_out: wp.array(dtype=wp.float64),
                  missing_out: wp.array(dtype=wp.int32)):
    """Add the 3 x 3 block of vertex rows ``vr``, columns ``vc`` into the CSC data.

    Block table (tightknot.solvers.pattern): key vr * V + vc; block_cols[k][j] is
    the data slot of the first free row of vr in the column of component j of vc (-1 if
    that component is fixed); vertex_rank[vr][i] the offset of component i among the free
    components of vr (-1 if fixed): the free rows of one vertex are consecutive in a
    column; block_rows[vr] .. block_rows[vr + 1] the range of row vr's keys (the search
    stays in one row: a few dozen keys, not the whole table). A block missing from the
    table is counted in ``missing_out`` (the caller grows the pattern and evaluates
    again)."""
    key = wp.int64(vr) * wp.int64(vertex_rank.shape[0]) + wp.int64(vc)
    k = find_key(block_keys, key, block_rows[vr], block_rows[vr + 1])
    if k < 0:
        wp.atomic_add(missing_out, 0, 1)
        return
    cols = block_cols[k]
    rank = vertex_rank[vr]
    for j in range(3):
        if cols[j] >= 0:
            for i in range(3):
                if rank[i] >= 0:
                    wp.atomic_add(csc_out, cols[j] + rank[i], m[i, j])


@wp.func
def scatter_block_pair(block_keys: wp.array(dtype=wp.int64),
                       block_rows: wp.array(dtype=wp.int32),
                       block_cols: wp.array(dtype=wp.vec3i),
                       vertex_rank: wp.array(dtype=wp.vec3i), verts: wp.vec4i, v: int,
                       w: int, m: wp.mat33d, csc_out: wp.array(dtype=wp.float64),
                       missing_out: wp.array(dtype=wp.int32)):
    """Block (v, w) of the pair's local vertices ``verts`` and, off the diagonal, its
    transpose (w, v), added into the CSC data."""
    scatter_block(block_keys, block_rows, block_cols, vertex_rank, verts[v], verts[w], m,
                  csc_out, missing_out)
    if w != v:
        scatter_block(block_keys, block_rows, block_cols, vertex_rank, verts[w], verts[v],
                      wp.transpose(m), csc_out, missing_out)


@wp.func
def scatter_pair_blocks(block_keys: wp.array(dtype=wp.int64),
                        block_rows: wp.array(dtype=wp.int32),
                        block_cols: wp.array(dtype=wp.vec3i),
                        vertex_rank: wp.array(dtype=wp.vec3i), verts: wp.vec4i,
                        bl: PairBlocks, csc_out: wp.array(dtype=wp.float64),
                        missing_out: wp.array(dtype=wp.int32)):
    """The pair's 4 x 4 vertex blocks added into the CSC data (see :func:`scatter_block`)."""
    scatter_block_pair(block_keys, block_rows, block_cols, vertex_rank, verts, 0, 0, bl.m00,
                       csc_out, missing_out)
    scatter_block_pair(block_keys, block_rows, block_cols, vertex_rank, verts, 0, 1, bl.m01,
                       csc_out, missing_out)
    scatter_block_pair(block_keys, block_rows, block_cols, vertex_rank, verts, 0, 2, bl.m02,
                       csc_out, missing_out)
    scatter_block_pair(block_keys, block_rows, block_cols, vertex_rank, verts, 0, 3, bl.m03,
                       csc_out, missing_out)
    scatter_block_pair(block_keys, block_rows, block_cols, vertex_rank, verts, 1, 1, bl.m11,
                       csc_out, missing_out)
    scatter_block_pair(block_keys, block_rows, block_cols, vertex_rank, verts, 1, 2, bl.m12,
                       csc_out, missing_out)
    scatter_block_pair(block_keys, block_rows, block_cols, vertex_rank, verts, 1, 3, bl.m13,
                       csc_out, missing_out)
    scatter_block_pair(block_keys, block_rows, block_cols, vertex_rank, verts, 2, 2, bl.m22,
                       csc_out, missing_out)
    scatter_block_pair(block_keys, block_rows, block_cols, vertex_rank, verts, 2, 3, bl.m23,
                       csc_out, missing_out)
    scatter_block_pair(block_keys, block_rows, block_cols, vertex_rank, verts, 3, 3, bl.m33,
                       csc_out, missing_out)
