"""Warp kernels of the self-contact layer: broad phase, pair energy, step bound, outputs.

One module, compiled once. Float64 geometry (tight contact needs it); the BVH bounds are
float32 (Warp's BVH), inflated by a margin that covers their rounding. Loops are not
unrolled (``max_unroll`` 1): unrolling the 4 x 4 vertex blocks made this module take 38 s
to compile.

Pair energy (see :mod:`tightknot.contact.law` for the derivation): for an edge pair
(a, b) and Gauss points g on a, h on b at distance rho,

    U_gh = om_g om_h l_a l_b W_excl Psi(s, R, q),   s = rho^2,
    Psi = (1 - xi(q)) A_l R^k_l T_l(rho/R) + xi(q) sqrt(1 - q) A_p R^k_p T_p(rho/R) + b(s),

with T_l, T_p the tabulated Abel and radial inverses of the line and point laws (cubic
splines, C2), R = r_a + r_b, r = r0 (l/l_bar)^-nu, q = cos^2 of the edges' angle, om the
Gauss weights on [0, 1], l the current edge lengths (the law is per unit length of the
deformed rod), xi the C2 line-to-point blend by angle (Meier et al. 2016), W_excl a C2
ramp of the arc-length separation (the exclusion window) and b the hard-core barrier.
U is a function of four scalars z = (s, l_a, l_b, q) of the vectors Y = (r = x_g - x_h,
e_a, e_b); gradient and Hessian follow by the chain rule through z and Y, then the linear
map Y -> vertices. Local vertex order of a pair: [a0, a1, b0, b1]; Hessian entry
(3 v + i, 3 w + j) at ``pair * 144 + (3 v + i) * 12 + 3 w + j``.
"""

from __future__ import annotations

import warp as wp

f64 = wp.float64
HALF_PI = wp.constant(wp.float64(1.5707963267948966))
# Compile time: see the module docstring.
wp.set_module_options({"max_unroll": 1})


@wp.func
def smooth_ramp(u: wp.float64) -> wp.vec3d:
    """Quintic smoothstep S(u) on [0, 1] (C2), with S' and S''."""
    if u <= f64(0.0):
        return wp.vec3d(f64(0.0), f64(0.0), f64(0.0))
    if u >= f64(1.0):
        return wp.vec3d(f64(1.0), f64(0.0), f64(0.0))
    u2 = u * u
    s = u2 * u * (f64(10.0) - f64(15.0) * u + f64(6.0) * u2)
    s1 = f64(30.0) * u2 * (f64(1.0) - u) * (f64(1.0) - u)
    s2 = f64(60.0) * u * (f64(1.0) - u) * (f64(1.0) - f64(2.0) * u)
    return wp.vec3d(s, s1, s2)


@wp.func
def table_eval(table: wp.array2d(dtype=wp.float64), u0: wp.float64, du: wp.float64,
               u: wp.float64) -> wp.vec3d:
    """Cubic-spline table T(u) with T' and T'' (zero for u >= 1; the first piece
    extrapolated below u0)."""
    if u >= f64(1.0):
        return wp.vec3d(f64(0.0), f64(0.0), f64(0.0))
    n = table.shape[0]
    j = int(wp.floor((u - u0) / du))
    j = wp.clamp(j, 0, n - 1)
    t = u - (u0 + f64(j) * du)
    a = table[j, 0]
    b = table[j, 1]
    c = table[j, 2]
    d = table[j, 3]
    return wp.vec3d(a + t * (b + t * (c + t * d)), b + t * (f64(2.0) * c + f64(3.0) * t * d),
                    f64(2.0) * c + f64(6.0) * t * d)


@wp.func
def scaled_kernel(T: wp.vec3d, rk: wp.float64, k: wp.float64, R: wp.float64,
                  u: wp.float64) -> wp.mat33d:
    """f = rk T(rho/R) with rk = amp R^k (computed once per pair), and its derivatives,
    packed as [[f, f_rho, f_R], [f_rhorho, f_rhoR, f_RR], [0, 0, 0]]."""
    f = rk * T[0]
    f_r = rk / R * T[1]
    f_R = rk / R * (k * T[0] - u * T[1])
    f_rr = rk / (R * R) * T[2]
    f_rR = rk / (R * R) * ((k - f64(1.0)) * T[1] - u * T[2])
    f_RR = rk / (R * R) * (k * (k - f64(1.0)) * T[0] - f64(2.0) * (k - f64(1.0)) * u * T[1]
                           + u * u * T[2])
    return wp.mat33d(f, f_r, f_R, f_rr, f_rR, f_RR, f64(0.0), f64(0.0), f64(0.0))


@wp.func
def hard_core(rho: wp.float64, R: wp.float64, hard_abs: wp.float64, hard_rel: wp.float64,
              core_rel: wp.float64, k: wp.float64) -> wp.mat33d:
    """Barrier b = -k dy^2 ln(y/yc) of the centerline distance rho and the contact radius
    R = r_a + r_b (Li et al. 2020, eq. 6, shifted): y = rho - rho_h, yc = rho_c - rho_h,
    dy = rho - rho_c, with the band's start rho_c = core_rel R (where the calibrated law
    ends) and its divergence rho_h = max(hard_rel R, hard_abs). Zero and C2 at rho_c.

    Returns rows (b, b_rho, b_rhorho), (b_R, b_rhoR, b_RR), (0, 0, 0)."""
    out = wp.mat33d()
    rho_c = core_rel * R
    rho_h = hard_abs
    h1 = f64(0.0)
    if hard_rel * R > hard_abs:
        rho_h = hard_rel * R
        h1 = hard_rel
    if rho >= rho_c or rho_c <= rho_h:
        return out
    if rho <= rho_h:
        # Outside the barrier's domain: an energy no line search accepts.
        out[0, 0] = f64(1.0e300)
        return out
    c1 = core_rel
    y = rho - rho_h
    yc = rho_c - rho_h
    dy = rho - rho_c
    lg = wp.log(y / yc)
    lr = -h1 / y - (c1 - h1) / yc                       # d ln(y/yc) / dR
    lrr = -(h1 * h1) / (y * y) + ((c1 - h1) * (c1 - h1)) / (yc * yc)
    out[0, 0] = -k * dy * dy * lg
    out[0, 1] = -k * (f64(2.0) * dy * lg + dy * dy / y)
    out[0, 2] = -k * (f64(2.0) * lg + f64(4.0) * dy / y - dy * dy / (y * y))
    out[1, 0] = -k * (-f64(2.0) * c1 * dy * lg + dy * dy * lr)
    out[1, 1] = -k * (-f64(2.0) * c1 * lg + f64(2.0) * dy * lr - f64(2.0) * c1 * dy / y
                      + h1 * dy * dy / (y * y))
    out[1, 2] = -k * (f64(2.0) * c1 * c1 * lg - f64(4.0) * c1 * dy * lr + dy * dy * lrr)
    return out


@wp.func
def arc_separation(sa: wp.float64, sb: wp.float64, same_rod: int, closed: int,
                   rod_length: wp.float64) -> wp.float64:
    if same_rod == 0:
        return f64(1.0e30)
    d = wp.abs(sa - sb)
    if closed != 0:
        d = wp.min(d, rod_length - d)
    return d


@wp.func
def outer33(a: wp.vec3d, b: wp.vec3d) -> wp.mat33d:
    return wp.outer(a, b)


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
def set_hess(out: wp.array(dtype=wp.float64), base: int, v: int, w: int, m: wp.mat33d):
    for i in range(3):
        for j in range(3):
            out[base + (3 * v + i) * 12 + 3 * w + j] = m[i, j]


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
def put_block(want_hess: int, hess_out: wp.array(dtype=wp.float64), base: int,
              block_keys: wp.array(dtype=wp.int64), block_rows: wp.array(dtype=wp.int32),
              block_cols: wp.array(dtype=wp.vec3i), vertex_rank: wp.array(dtype=wp.vec3i),
              csc_out: wp.array(dtype=wp.float64), missing_out: wp.array(dtype=wp.int32),
              verts: wp.vec4i, v: int, w: int, m: wp.mat33d):
    """Store the pair's vertex block (v, w) and, off the diagonal, its transpose (w, v):
    into the 144 per-pair entries (want_hess 1) or the CSC data (2)."""
    if want_hess == 1:
        set_hess(hess_out, base, v, w, m)
        if w != v:
            set_hess(hess_out, base, w, v, wp.transpose(m))
    else:
        scatter_block(block_keys, block_rows, block_cols, vertex_rank, verts[v], verts[w], m,
                      csc_out, missing_out)
        if w != v:
            scatter_block(block_keys, block_rows, block_cols, vertex_rank, verts[w], verts[v],
                          wp.transpose(m), csc_out, missing_out)


@wp.kernel
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


@wp.kernel
def candidate_pairs_kernel(
    # Model:
    edge_vertex: wp.array(dtype=wp.vec2i),
    edge_rod: wp.array(dtype=wp.int32),
    rod_closed: wp.array(dtype=wp.int32),
    # Data in:
    bvh_id: wp.uint64,
    lower_in: wp.array(dtype=wp.vec3),
    upper_in: wp.array(dtype=wp.vec3),
    edge_arc_in: wp.array(dtype=wp.vec2d),
    rod_length_in: wp.array(dtype=wp.float64),
    edge_exclusion_in: wp.array(dtype=wp.float64),
    local_window: wp.float64,
    capacity: int,
    # Out:
    count_out: wp.array(dtype=wp.int32),
    pairs_out: wp.array(dtype=wp.vec2i),
):
    # Edge pairs (a < b) whose bounds overlap and that hold at least one point pair
    # farther apart along the rod than the exclusion window.
    a = wp.tid()
    query = wp.bvh_query_aabb(bvh_id, lower_in[a], upper_in[a])
    b = int(0)
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
        same = int(0)
        if edge_rod[b] == ra:
            same = 1
        if same != 0:
            arc_b = edge_arc_in[b]
            excl = wp.max(edge_exclusion_in[a], edge_exclusion_in[b])
            # Largest separation of any two points of the two edges.
            s1 = arc_separation(arc_a[0], arc_b[1], 1, rod_closed[ra], rod_length_in[ra])
            s2 = arc_separation(arc_a[1], arc_b[0], 1, rod_closed[ra], rod_length_in[ra])
            s3 = arc_separation(arc_a[0], arc_b[0], 1, rod_closed[ra], rod_length_in[ra])
            s4 = arc_separation(arc_a[1], arc_b[1], 1, rod_closed[ra], rod_length_in[ra])
            if wp.max(wp.max(s1, s2), wp.max(s3, s4)) < local_window * excl:
                continue
        k = wp.atomic_add(count_out, 0, 1)
        if k < capacity:
            pairs_out[k] = wp.vec2i(a, b)


@wp.kernel
def contact_pair_kernel(
    # Model:
    edge_vertex: wp.array(dtype=wp.vec2i),
    edge_rod: wp.array(dtype=wp.int32),
    rod_closed: wp.array(dtype=wp.int32),
    edge_radius0: wp.array(dtype=wp.float64),
    edge_poisson: wp.array(dtype=wp.float64),
    edge_modulus: wp.array(dtype=wp.float64),
    gauss_xi: wp.array(dtype=wp.float64),
    gauss_w: wp.array(dtype=wp.float64),
    law: wp.array(dtype=wp.float64),
    line_table: wp.array2d(dtype=wp.float64),
    point_table: wp.array2d(dtype=wp.float64),
    # Data in:
    x_in: wp.array(dtype=wp.vec3d),
    pairs_in: wp.array(dtype=wp.vec2i),
    edge_rest_length_in: wp.array(dtype=wp.float64),
    edge_arc_in: wp.array(dtype=wp.vec2d),
    rod_length_in: wp.array(dtype=wp.float64),
    edge_exclusion_in: wp.array(dtype=wp.float64),
    local_window: wp.float64,
    want_grad: int,
    want_hess: int,
    # Contact radii given per edge (radius_given = 1): the energy then depends on the
    # positions at FIXED radii (no derivative through the edge lengths), and dR_out gets,
    # per pair, [dE/dR, d2E/dR2, d(grad)/dR (4 vertices x 3)] with R = r_a + r_b.
    radius_in: wp.array(dtype=wp.float64),
    radius_given: int,
    # Hessian target (want_hess = 1: 144 entries per pair in hess_out; 2: added into the
    # CSC data array csc_out through the block table, see scatter_block):
    block_keys: wp.array(dtype=wp.int64),
    block_rows: wp.array(dtype=wp.int32),
    block_cols: wp.array(dtype=wp.vec3i),
    vertex_rank: wp.array(dtype=wp.vec3i),
    # Out:
    energy_out: wp.array(dtype=wp.float64),
    grad_out: wp.array(dtype=wp.vec3d),
    hess_out: wp.array(dtype=wp.float64),
    overlap_out: wp.array(dtype=wp.float64),
    csc_out: wp.array(dtype=wp.float64),
    missing_out: wp.array(dtype=wp.int32),
    dR_out: wp.array(dtype=wp.float64),
):
    p = wp.tid()
    pr = pairs_in[p]
    a = pr[0]
    b = pr[1]
    va = edge_vertex[a]
    vb = edge_vertex[b]
    xa0 = x_in[va[0]]
    xa1 = x_in[va[1]]
    xb0 = x_in[vb[0]]
    xb1 = x_in[vb[1]]
    ea = xa1 - xa0
    eb = xb1 - xb0
    la = wp.length(ea)
    lb = wp.length(eb)
    ta = ea / la
    tb = eb / lb
    # Law parameters: [K_line coef, m_line, -, K_point coef, m_point, q_line, q_point,
    #                  hard_relative,
    #                  core_fraction, hard_fraction, core_stiffness, u0, du].
    m_l = law[1]
    m_p = law[4]
    q_line = law[5]
    q_point = law[6]
    core_frac = law[8]
    hard_frac = law[9]
    core_k = law[10]
    u0 = law[11]
    du = law[12]
    # Stretched radii r = r0 (l/l_bar)^-nu and their derivatives in l.
    nua = edge_poisson[a]
    nub = edge_poisson[b]
    r_a = edge_radius0[a] * wp.pow(la / edge_rest_length_in[a], -nua)
    r_b = edge_radius0[b] * wp.pow(lb / edge_rest_length_in[b], -nub)
    if radius_given != 0:
        r_a = radius_in[a]
        r_b = radius_in[b]
    R = r_a + r_b
    # Most candidates do not interact: find the closest Gauss pair first and leave before
    # the pair constants (powers) when it lies outside the contact radius.
    ng = gauss_xi.shape[0]
    ra_ = edge_rod[a]
    same = int(0)
    if edge_rod[b] == ra_:
        same = 1
    excl = wp.max(edge_exclusion_in[a], edge_exclusion_in[b])
    arc_a = edge_arc_in[a]
    arc_b = edge_arc_in[b]
    d0 = edge_radius0[a] + edge_radius0[b]
    core_local = wp.min(core_frac, f64(0.7))
    s_min = f64(1.0e300)
    local_hit = int(0)
    for gi in range(ng):
        for hi in range(ng):
            xg = gauss_xi[gi]
            xh = gauss_xi[hi]
            wex = f64(1.0)
            g_sep = f64(1.0)
            if same != 0:
                sa = arc_a[0] + xg * (arc_a[1] - arc_a[0])
                sb = arc_b[0] + xh * (arc_b[1] - arc_b[0])
                sep = arc_separation(sa, sb, same, rod_closed[ra_], rod_length_in[ra_])
                wex = smooth_ramp((sep - excl) / (f64(0.25) * excl))[0]
                g_sep = wp.sin(wp.min(sep / d0, HALF_PI))
                if wex <= f64(0.0) and sep < local_window * excl:
                    continue
            r = (xa0 + xg * ea) - (xb0 + xh * eb)
            ss = wp.dot(r, r)
            if wex > f64(0.0):
                s_min = wp.min(s_min, ss)
            if g_sep < f64(1.0):
                lim = core_local * g_sep * R
                if ss < lim * lim:
                    local_hit = 1
    if s_min >= R * R and local_hit == 0:
        if radius_given != 0 and want_grad != 0:
            for k in range(14):
                dR_out[p * 14 + k] = f64(0.0)
        energy_out[p] = f64(0.0)
        overlap_out[p] = R - wp.sqrt(s_min)
        return
    # Pair constants from the rest diameter D = r_a + r_b and the harmonic-mean modulus:
    # e_line = K_l delta^m_l with K_l = 2 k E D^2 (2D)^-m/m (contact_law), likewise K_p.
    emod = f64(2.0) * edge_modulus[a] * edge_modulus[b] / (edge_modulus[a] + edge_modulus[b])
    two_d = f64(2.0) * d0
    K_l = f64(2.0) * law[0] * emod * d0 * d0 * wp.pow(two_d, -m_l) / m_l
    K_p = f64(2.0) * law[3] * emod * d0 * d0 * d0 * wp.pow(two_d, -m_p) / m_p
    # Kernels A R^k T(rho/R): line (Abel inverse) A = K m/pi, k = m - 1; point (radial
    # inverse) A = K m/(2 pi), k = m - 2.
    A_l = K_l * m_l / f64(3.141592653589793)
    k_l = m_l - f64(1.0)
    A_p = K_p * m_p / (f64(2.0) * f64(3.141592653589793))
    k_p = m_p - f64(2.0)
    R_a = -nua * r_a / la
    R_b = -nub * r_b / lb
    R_aa = nua * (nua + f64(1.0)) * r_a / (la * la)
    R_bb = nub * (nub + f64(1.0)) * r_b / (lb * lb)
    if radius_given != 0:
        R_a = f64(0.0)
        R_b = f64(0.0)
        R_aa = f64(0.0)
        R_bb = f64(0.0)
    eR = f64(0.0)
    eRR = f64(0.0)
    gR0 = wp.vec3d()
    gR1 = wp.vec3d()
    gR2 = wp.vec3d()
    gR3 = wp.vec3d()
    # Angle: c = ta . tb, q = c^2 and its gradients in e_a, e_b.
    c = wp.dot(ta, tb)
    q = c * c
    dc_a = (tb - c * ta) / la
    dc_b = (ta - c * tb) / lb
    dq_a = f64(2.0) * c * dc_a
    dq_b = f64(2.0) * c * dc_b
    # Blend xi(q): 1 (point) for q <= q_point, 0 (line) for q >= q_line.
    sv = smooth_ramp((q_line - q) / (q_line - q_point))
    inv_dq = f64(-1.0) / (q_line - q_point)
    xi = sv[0]
    xi1 = sv[1] * inv_dq
    xi2 = sv[2] * inv_dq * inv_dq
    A = f64(1.0) - xi
    A1 = -xi1
    A2 = -xi2
    sn = wp.sqrt(wp.max(f64(1.0) - q, f64(0.0)))
    B = f64(0.0)
    B1 = f64(0.0)
    B2 = f64(0.0)
    if xi > f64(0.0):
        # sqrt(1 - q) is smooth where xi > 0 (q <= q_line < 1).
        s1 = -f64(0.5) / sn
        s2 = -f64(0.25) / (sn * sn * sn)
        B = xi * sn
        B1 = xi1 * sn + xi * s1
        B2 = xi2 * sn + f64(2.0) * xi1 * s1 + xi * s2
    # Hard core (IPC barrier, Li et al. 2020, eq. 6, see hard_core): zero for
    # rho >= core_fraction R, C2 there, infinite before the hard limit of the step bound.
    # Every point of a polyline is within 0.29 l of one of its Gauss points (2 per edge:
    # 0.577 l apart inside an edge, 0.42 l across a vertex; 3 per edge: closer), so the
    # barrier diverges at rho_hard = hard + 0.58 l_max: it stops two segments before their
    # distance reaches the step bound's hard limit, whatever Gauss points they hold.
    lmax = wp.max(edge_rest_length_in[a], edge_rest_length_in[b])
    rho_hard = hard_frac * d0 + f64(0.58) * lmax
    hard_rel = law[7]
    # Barrier stiffness [J/m^2 per m^2 of (rho - rho_core)^2]: k E / D, so that the
    # barrier density k E D (dy/D)^2 ln(y/yc) is an energy per length^2 like the law's.
    kcore = core_k * emod / d0
    # amp R^k of the line and point kernels, once per pair.
    rk_l = A_l * wp.pow(R, k_l)
    rk_p = A_p * wp.pow(R, k_p)
    energy = f64(0.0)
    g0 = wp.vec3d()
    g1 = wp.vec3d()
    g2 = wp.vec3d()
    g3 = wp.vec3d()
    base = p * 144
    # Hessian accumulators over the Gauss pairs (see the block assembly after the loop):
    # moments of H_rr in (1, xg, xh, xg^2, xh^2, xg xh), of H_ra and H_rb in (1, xg, xh),
    # and the sums of H_aa, H_bb, H_ab.
    M0 = wp.mat33d()
    Mg = wp.mat33d()
    Mh = wp.mat33d()
    Mgg = wp.mat33d()
    Mhh = wp.mat33d()
    Mgh = wp.mat33d()
    A0 = wp.mat33d()
    Ag = wp.mat33d()
    Ah = wp.mat33d()
    B0 = wp.mat33d()
    Bg = wp.mat33d()
    Bh = wp.mat33d()
    Saa = wp.mat33d()
    Sbb = wp.mat33d()
    Sab = wp.mat33d()
    any_hess = int(0)
    xmax = f64(-1.0e30)
    # Second derivatives of q = c^2, constants of the pair (the Hessian of c: see module
    # docstring); computed once here, used by every Gauss pair.
    eye = wp.identity(n=3, dtype=wp.float64)
    Pa = eye - outer33(ta, ta)
    Pb = eye - outer33(tb, tb)
    Hq_aa = wp.mat33d()
    Hq_bb = wp.mat33d()
    Hq_ab = wp.mat33d()
    if want_hess != 0:
        ua = tb - c * ta
        ub = ta - c * tb
        Hc_aa = (-(outer33(ua, ta) + outer33(ta, ua)) - c * Pa) / (la * la)
        Hc_bb = (-(outer33(ub, tb) + outer33(tb, ub)) - c * Pb) / (lb * lb)
        Hc_ab = (Pb - outer33(ta, ub)) / (la * lb)
        Hq_aa = f64(2.0) * (outer33(dc_a, dc_a) + c * Hc_aa)
        Hq_bb = f64(2.0) * (outer33(dc_b, dc_b) + c * Hc_bb)
        Hq_ab = f64(2.0) * (outer33(dc_a, dc_b) + c * Hc_ab)
    # Which laws the blend uses (its weights and their derivatives in q exactly zero
    # otherwise): near-parallel pairs need only the line law, crossing pairs only the
    # point law; skipping a law whose every weight is zero changes no bit of the sums.
    use_line = int(1)
    if A == f64(0.0) and A1 == f64(0.0) and A2 == f64(0.0):
        use_line = 0
    use_point = int(0)
    if xi > f64(0.0):
        use_point = 1
    for gi in range(ng):
        for hi in range(ng):
            xg = gauss_xi[gi]
            xh = gauss_xi[hi]
            sa = arc_a[0] + xg * (arc_a[1] - arc_a[0])
            sb = arc_b[0] + xh * (arc_b[1] - arc_b[0])
            sep = arc_separation(sa, sb, same, rod_closed[ra_], rod_length_in[ra_])
            wex = f64(1.0)
            g_sep = f64(1.0)
            if same != 0:
                wex = smooth_ramp((sep - excl) / (f64(0.25) * excl))[0]
                g_sep = wp.sin(wp.min(sep / d0, HALF_PI))
                if wex <= f64(0.0) and sep < local_window * excl:
                    continue
            r = (xa0 + xg * ea) - (xb0 + xh * eb)
            s = wp.dot(r, r)
            rho = wp.sqrt(s)
            if wex > f64(0.0):
                xmax = wp.max(xmax, R - rho)
            if rho >= R:
                continue
            u = rho / R
            # The law, weighted by the exclusion ramp (zero inside the window).
            Fl = wp.mat33d()
            Fp = wp.mat33d()
            if wex > f64(0.0):
                if use_line != 0:
                    Fl = wex * scaled_kernel(table_eval(line_table, u0, du, u), rk_l, k_l, R,
                                             u)
                if use_point != 0:
                    Fp = wex * scaled_kernel(table_eval(point_table, u0, du, u), rk_p, k_p,
                                             R, u)
            hb = wp.mat33d()
            if g_sep < f64(1.0):
                # Local thickness: two points an arc sep apart on a bend of the tightest
                # legal radius D/2 are a chord D sin(sep/D) apart; closer than core_local
                # of that (with R for D), the rod folds onto itself inside the exclusion
                # window, where the law is off. The barrier stops the fold (a tight pull
                # creased a 125 mm trefoil into a hairpin, legs 0.05 D apart, without it).
                hb = hard_core(rho, R, rho_hard, f64(0.0), core_local * g_sep, kcore)
            else:
                hb = hard_core(rho, R, rho_hard, hard_rel, core_frac, kcore)
            if hb[0, 0] >= f64(1.0e299):
                # Past the barrier's divergence: an energy no line search accepts, and no
                # derivatives (they would overflow the assembled matrix).
                energy += f64(1.0e300)
                continue
            # The barrier in s = rho^2: b_s = b_rho/(2 rho), b_ss = (b_rr - b_r/rho)/(4 s).
            bv = wp.vec3d(hb[0, 0], hb[0, 1] * f64(0.5) / rho,
                          (hb[0, 2] - hb[0, 1] / rho) / (f64(4.0) * s))
            Psi = A * Fl[0, 0] + B * Fp[0, 0] + bv[0]
            wgt = gauss_w[gi] * gauss_w[hi]
            P = la * lb
            energy += wgt * P * Psi
            if want_grad == 0:
                continue
            # Derivatives in rho -> in s = rho^2: f_s = f_rho/(2 rho),
            # f_ss = (f_rhorho - f_rho/rho)/(4 rho^2), f_sR = f_rhoR/(2 rho).
            inv2r = f64(0.5) / rho
            Ls = Fl[0, 1] * inv2r
            Lss = (Fl[1, 0] - Fl[0, 1] / rho) / (f64(4.0) * s)
            LsR = Fl[1, 1] * inv2r
            Qs = Fp[0, 1] * inv2r
            Qss = (Fp[1, 0] - Fp[0, 1] / rho) / (f64(4.0) * s)
            QsR = Fp[1, 1] * inv2r
            Ps = A * Ls + B * Qs + bv[1]
            PR = A * Fl[0, 2] + B * Fp[0, 2] + hb[1, 0]
            Pss = A * Lss + B * Qss + bv[2]
            PsR = A * LsR + B * QsR + hb[1, 1] * f64(0.5) / rho
            PRR = A * Fl[1, 2] + B * Fp[1, 2] + hb[1, 2]
            Pq = A1 * Fl[0, 0] + B1 * Fp[0, 0]
            Pqq = A2 * Fl[0, 0] + B2 * Fp[0, 0]
            Psq = A1 * Ls + B1 * Qs
            PRq = A1 * Fl[0, 2] + B1 * Fp[0, 2]
            # Psi in z = (s, l_a, l_b, q): R depends on l_a, l_b.
            Pz = wp.vec4d(Ps, PR * R_a, PR * R_b, Pq)
            Pzz = wp.mat44d(
                Pss, PsR * R_a, PsR * R_b, Psq,
                PsR * R_a, PRR * R_a * R_a + PR * R_aa, PRR * R_a * R_b, PRq * R_a,
                PsR * R_b, PRR * R_a * R_b, PRR * R_b * R_b + PR * R_bb, PRq * R_b,
                Psq, PRq * R_a, PRq * R_b, Pqq)
            # F = P Psi with P = l_a l_b.
            Pp = wp.vec4d(f64(0.0), lb, la, f64(0.0))
            Fz = wgt * (P * Pz + Psi * Pp)
            # Gradients of z in the Y blocks (r, e_a, e_b).
            gr_s = f64(2.0) * r
            ga_la = ta
            gb_lb = tb
            grad_r = Fz[0] * gr_s
            grad_a = Fz[1] * ga_la + Fz[3] * dq_a
            grad_b = Fz[2] * gb_lb + Fz[3] * dq_b
            # Y -> vertices: r = (1-xg) xa0 + xg xa1 - (1-xh) xb0 - xh xb1.
            g0 += (f64(1.0) - xg) * grad_r - grad_a
            g1 += xg * grad_r + grad_a
            g2 += -(f64(1.0) - xh) * grad_r - grad_b
            g3 += -xh * grad_r + grad_b
            if radius_given != 0:
                # d/dR at fixed positions (R_a = R_b = 0 here): Pz = (Ps, 0, 0, Pq)
                eR += wgt * P * PR
                eRR += wgt * P * PRR
                dF0 = wgt * P * PsR
                dF1 = wgt * PR * lb
                dF2 = wgt * PR * la
                dF3 = wgt * P * PRq
                dgr = dF0 * gr_s
                dga = dF1 * ga_la + dF3 * dq_a
                dgb = dF2 * gb_lb + dF3 * dq_b
                gR0 += (f64(1.0) - xg) * dgr - dga
                gR1 += xg * dgr + dga
                gR2 += -(f64(1.0) - xh) * dgr - dgb
                gR3 += -xh * dgr + dgb
            if want_hess == 0:
                continue
            Fzz = wgt * (P * Pzz + wp.outer(Pp, Pz) + wp.outer(Pz, Pp))
            Fzz[1, 2] = Fzz[1, 2] + wgt * Psi
            Fzz[2, 1] = Fzz[2, 1] + wgt * Psi
            # The Y-space blocks sum_kl Fzz[k, l] outer(g_k, g_l) over the z-gradients of
            # the blocks' variables (r: only s; e_a: l_a and q; e_b: l_b and q).
            Hrr = outer33(gr_s, Fzz[0, 0] * gr_s) + (f64(2.0) * Fz[0]) * eye
            Hra = rank1_pair(gr_s, Fzz[0, 1], Fzz[0, 3], ga_la, dq_a)
            Hrb = rank1_pair(gr_s, Fzz[0, 2], Fzz[0, 3], gb_lb, dq_b)
            Haa = rank2_pair(ga_la, dq_a, Fzz[1, 1], Fzz[1, 3], Fzz[3, 1], Fzz[3, 3], ga_la,
                             dq_a) + (Fz[1] / la) * Pa + Fz[3] * Hq_aa
            Hbb = rank2_pair(gb_lb, dq_b, Fzz[2, 2], Fzz[2, 3], Fzz[3, 2], Fzz[3, 3], gb_lb,
                             dq_b) + (Fz[2] / lb) * Pb + Fz[3] * Hq_bb
            Hab = rank2_pair(ga_la, dq_a, Fzz[1, 2], Fzz[1, 3], Fzz[3, 2], Fzz[3, 3], gb_lb,
                             dq_b) + Fz[3] * Hq_ab
            # Accumulate; the map to the vertices is linear in (xg, xh), done once below.
            any_hess = 1
            M0 = M0 + Hrr
            Mg = Mg + xg * Hrr
            Mh = Mh + xh * Hrr
            Mgg = Mgg + (xg * xg) * Hrr
            Mhh = Mhh + (xh * xh) * Hrr
            Mgh = Mgh + (xg * xh) * Hrr
            A0 = A0 + Hra
            Ag = Ag + xg * Hra
            Ah = Ah + xh * Hra
            B0 = B0 + Hrb
            Bg = Bg + xg * Hrb
            Bh = Bh + xh * Hrb
            Saa = Saa + Haa
            Sbb = Sbb + Hbb
            Sab = Sab + Hab
    if want_hess != 0 and any_hess != 0:
        # Vertex blocks H_vw = sum_gh C_v^T H_Y C_w with the coefficients of (r, e_a, e_b)
        # in vertex v: c_r = alpha_v + beta_v xg + gamma_v xh (r = (1-xg) xa0 + xg xa1
        # - (1-xh) xb0 - xh xb1: alpha = (1, 0, -1, 0), beta = (-1, 1, 0, 0), gamma =
        # (0, 0, 1, -1)), c_a = (-1, 1, 0, 0), c_b = (0, 0, -1, 1). Written out with the
        # zero coefficients dropped (the moments' sums are linear in the coefficients; the
        # order of the remaining terms is that of the generic sum
        # (alpha alpha) M0 + (alpha beta + beta alpha) Mg + (alpha gamma + gamma alpha) Mh
        # + (beta beta) Mgg + (gamma gamma) Mhh + (beta gamma + gamma beta) Mgh
        # + c_a,w Ra_v + c_b,w Rb_v + c_a,v Ra_w^T + c_b,v Rb_w^T
        # + c_a,v c_a,w Saa + c_b,v c_b,w Sbb + c_a,v c_b,w Sab + c_b,v c_a,w Sab^T,
        # with Ra_v = sum c_r,v H_ra, Rb_v = sum c_r,v H_rb).
        # (a + (-1) b is a - b exactly, and -a + b is b - a: the same bits as the sum.)
        Ra0 = A0 - Ag
        Rb0 = B0 - Bg
        Ra1 = Ag
        Rb1 = Bg
        Ra2 = Ah - A0
        Rb2 = Bh - B0
        Ra3 = -Ah
        Rb3 = -Bh
        m00 = M0 - f64(2.0) * Mg + Mgg - Ra0 - wp.transpose(Ra0) + Saa
        m01 = Mg - Mgg + Ra0 - wp.transpose(Ra1) - Saa
        m02 = Mg - M0 + Mh - Mgh - Rb0 - wp.transpose(Ra2) + Sab
        m03 = Mgh - Mh + Rb0 - wp.transpose(Ra3) - Sab
        m11 = Mgg + Ra1 + wp.transpose(Ra1) + Saa
        m12 = Mgh - Mg - Rb1 + wp.transpose(Ra2) - Sab
        m13 = Rb1 - Mgh + wp.transpose(Ra3) + Sab
        m22 = M0 - f64(2.0) * Mh + Mhh - Rb2 - wp.transpose(Rb2) + Sbb
        m23 = Mh - Mhh + Rb2 - wp.transpose(Rb3) - Sbb
        m33 = Mhh + Rb3 + wp.transpose(Rb3) + Sbb
        verts = wp.vec4i(va[0], va[1], vb[0], vb[1])
        put_block(want_hess, hess_out, base, block_keys, block_rows, block_cols, vertex_rank,
                  csc_out, missing_out, verts, 0, 0, m00)
        put_block(want_hess, hess_out, base, block_keys, block_rows, block_cols, vertex_rank,
                  csc_out, missing_out, verts, 0, 1, m01)
        put_block(want_hess, hess_out, base, block_keys, block_rows, block_cols, vertex_rank,
                  csc_out, missing_out, verts, 0, 2, m02)
        put_block(want_hess, hess_out, base, block_keys, block_rows, block_cols, vertex_rank,
                  csc_out, missing_out, verts, 0, 3, m03)
        put_block(want_hess, hess_out, base, block_keys, block_rows, block_cols, vertex_rank,
                  csc_out, missing_out, verts, 1, 1, m11)
        put_block(want_hess, hess_out, base, block_keys, block_rows, block_cols, vertex_rank,
                  csc_out, missing_out, verts, 1, 2, m12)
        put_block(want_hess, hess_out, base, block_keys, block_rows, block_cols, vertex_rank,
                  csc_out, missing_out, verts, 1, 3, m13)
        put_block(want_hess, hess_out, base, block_keys, block_rows, block_cols, vertex_rank,
                  csc_out, missing_out, verts, 2, 2, m22)
        put_block(want_hess, hess_out, base, block_keys, block_rows, block_cols, vertex_rank,
                  csc_out, missing_out, verts, 2, 3, m23)
        put_block(want_hess, hess_out, base, block_keys, block_rows, block_cols, vertex_rank,
                  csc_out, missing_out, verts, 3, 3, m33)
    energy_out[p] = energy
    overlap_out[p] = xmax
    if radius_given != 0 and want_grad != 0:
        o = p * 14
        dR_out[o] = eR
        dR_out[o + 1] = eRR
        for i in range(3):
            dR_out[o + 2 + i] = gR0[i]
            dR_out[o + 5 + i] = gR1[i]
            dR_out[o + 8 + i] = gR2[i]
            dR_out[o + 11 + i] = gR3[i]
    if want_grad != 0:
        wp.atomic_add(grad_out, va[0], g0)
        wp.atomic_add(grad_out, va[1], g1)
        wp.atomic_add(grad_out, vb[0], g2)
        wp.atomic_add(grad_out, vb[1], g3)


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


@wp.kernel
def step_bound_kernel(
    # Model:
    edge_vertex: wp.array(dtype=wp.vec2i),
    # Data in:
    x_in: wp.array(dtype=wp.vec3d),
    dx_in: wp.array(dtype=wp.vec3d),
    pairs_in: wp.array(dtype=wp.vec2i),
    hard_in: wp.array(dtype=wp.float64),
    # Out:
    alpha_out: wp.array(dtype=wp.float64),
    distance_out: wp.array(dtype=wp.float64),
):
    # Segment distance is 1-Lipschitz in the motion of its points, and each point of an edge
    # moves at most max(|dx| of its two vertices) along the straight step; so no point pair
    # comes closer than d0 - alpha (m_a + m_b), and alpha = (d0 - hard)/(m_a + m_b) keeps the
    # pair at least ``hard`` apart along the whole step: no passing through by construction.
    p = wp.tid()
    pr = pairs_in[p]
    va = edge_vertex[pr[0]]
    vb = edge_vertex[pr[1]]
    res = segment_distance(x_in[va[0]], x_in[va[1]], x_in[vb[0]], x_in[vb[1]])
    d0 = res[0]
    distance_out[p] = d0
    ma = wp.max(wp.length(dx_in[va[0]]), wp.length(dx_in[va[1]]))
    mb = wp.max(wp.length(dx_in[vb[0]]), wp.length(dx_in[vb[1]]))
    hard = wp.max(hard_in[pr[0]], hard_in[pr[1]])
    move = ma + mb
    alpha = f64(1.0e30)
    if move > f64(0.0):
        alpha = (d0 - hard) / move
    alpha_out[p] = alpha
