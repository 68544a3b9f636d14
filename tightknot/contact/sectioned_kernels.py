"""Warp kernels of the sectioned level's contact between deformed sections.

The formulation, the local dof order and what the Hessian leaves out are those of the NumPy
oracle :mod:`tightknot.contact.sectioned_reference` (its module docstring). One thread
evaluates one pass of one candidate pair: the boundary samples of its first edge A against
the surface of its second edge B (thread 2 p: A = a, B = b; thread 2 p + 1: A = b, B = a).
Each thread writes its energy and its gradient over the pass's local dofs (x_A0, x_A1,
x_B0, x_B1, then the section coefficients of A's two vertices and of B's, then the
vertices before and after B on its rod, x_Bprev and x_Bnext, which B's partition weight
depends on; L = 18 + 4 K for K coefficients per vertex) into its own slice of the outputs,
and adds its Hessian into the dense blocks of the node pairs it couples (a node: a vertex
with its 3 coordinates and K coefficients; the blocks' slots come with the pairs, 36 per
pass), which :mod:`tightknot.contact.sectioned` hands to the rod system.

Per sample, every derivative over the L dofs is a combination of 16 reduced directions: the
12 vertex coordinates and, for the sections, A's boundary at the sample's angle (along
B(phi) + dR/dc, carried to A's two vertices by the interpolation weights), B's boundary at
the angle psi facing the sample, its slope in psi, and the derivative of B's interpolation
weights in the projection v; and the 6 components of B's neighbour chords' offsets f0 =
x_B0 - x_Bprev, f1 = x_Bnext - x_B1, on which only the weight depends (a ghost at an open
end, f = x_B1 - x_B0, folded onto B's own vertices). The per-sample Hessian is formed in
those directions,
carried to the pass's dofs (the mean radii's second derivatives in the coefficients, and
mixed in the stretch and v, added there) and summed over the pass's samples in registers,
one block per pair of its nodes (the coordinates' 18 x 18, the coordinates against each
vertex's coefficients, the coefficients' K x K blocks), which are added into the node-pair
blocks once per pass.

With ``gauss_newton`` set (:meth:`tightknot.contact.sectioned.SectionedLayer.
set_gauss_newton`), a sample's Hessian is its Gauss-Newton part alone, a_s wt phi''(pen)
grad(pen) grad(pen)^T: every term weighed by the penalty's slope or the partition's
derivatives (the gap's own curvature, the mean radii's second derivatives, P's second
derivatives in A's edge vector) is left out; energy and gradient are unchanged.

Work is skipped where no contact can be: a pass whose edges lie farther apart than the
two sections' largest radii (B's axis taken over the reach of its weight,
:func:`reach_range`), a Gauss circle of A whose axis point is farther from it than those
radii, a sample outside the planes that bound B's weight, and a sample farther from B's
axis than B's largest radius (the bounds:
the mean radius at the edge's stretch and the coefficients' amplitude sums, which bound
every boundary radius; computed once per state by :func:`section_bounds`). A sample is
first tested at its mean radius, with A's amplitude sum as margin, so that the samples
skipped never have their modes summed.

Loops are not unrolled and no backward code is generated (derivatives are written by hand;
local vectors are assigned in place), as in the compliant level's module.
"""

from __future__ import annotations

import warp as wp

f64 = wp.float64
#: The most section coefficients per vertex the kernels hold (modes up to N = 12).
MAX_COEFF = 22
vecKd = wp.types.vector(length=MAX_COEFF, dtype=wp.float64)
vec16d = wp.types.vector(length=16, dtype=wp.float64)
mat16d = wp.types.matrix(shape=(16, 16), dtype=wp.float64)
mat3x16d = wp.types.matrix(shape=(3, 16), dtype=wp.float64)
vec6d = wp.types.vector(length=6, dtype=wp.float64)
mat66d = wp.types.matrix(shape=(6, 6), dtype=wp.float64)
mat36d = wp.types.matrix(shape=(3, 6), dtype=wp.float64)
mat6x16d = wp.types.matrix(shape=(6, 16), dtype=wp.float64)
mat12d = wp.types.matrix(shape=(12, 12), dtype=wp.float64)
vec12d = wp.types.vector(length=12, dtype=wp.float64)
mat18d = wp.types.matrix(shape=(18, 18), dtype=wp.float64)
mat18xKd = wp.types.matrix(shape=(18, MAX_COEFF), dtype=wp.float64)
mat12xKd = wp.types.matrix(shape=(12, MAX_COEFF), dtype=wp.float64)
matKd = wp.types.matrix(shape=(MAX_COEFF, MAX_COEFF), dtype=wp.float64)
mat6xKd = wp.types.matrix(shape=(6, MAX_COEFF), dtype=wp.float64)
mat12x6d = wp.types.matrix(shape=(12, 6), dtype=wp.float64)
vec5d = wp.types.vector(length=5, dtype=wp.float64)

wp.set_module_options({"max_unroll": 1, "enable_backward": False})

TWO_PI = 6.283185307179586
#: Relative step of the frames' second derivatives (sectioned_reference.FRAME_STEP).
FRAME_STEP = 1.0e-6


@wp.func
def transported_frame(d1r: wp.vec3d, tr: wp.vec3d, t: wp.vec3d):
    """d1 = P(tr -> t) d1r (Rodrigues' rotation taking unit tr onto unit t), d2 = t x d1,
    and dd1/dt, dd2/dt with t a free 3-vector (sectioned_reference.transported_frame)."""
    c = wp.dot(tr, t)
    b = wp.cross(tr, t)
    bu = wp.dot(b, d1r)
    inv = f64(1.0) / (f64(1.0) + c)
    d1 = c * d1r + wp.cross(b, d1r) + (bu * inv) * b
    s = wp.skew(tr)
    j1 = (wp.outer(d1r, tr) - wp.skew(d1r) @ s + inv * wp.outer(b, wp.transpose(s) @ d1r)
          + (bu * inv) * s - (bu * inv * inv) * wp.outer(b, tr))
    d2 = wp.cross(t, d1)
    j2 = wp.skew(t) @ j1 - wp.skew(d1)
    return d1, d2, j1, j2


@wp.func
def quintic(x: wp.float64) -> wp.vec3d:
    """S(x) = x^3 (10 - 15 x + 6 x^2) on [0, 1], clamped, with S' and S''."""
    if x <= f64(0.0):
        return wp.vec3d(f64(0.0), f64(0.0), f64(0.0))
    if x >= f64(1.0):
        return wp.vec3d(f64(1.0), f64(0.0), f64(0.0))
    x2 = x * x
    return wp.vec3d(x2 * x * (f64(10.0) - f64(15.0) * x + f64(6.0) * x2),
                    f64(30.0) * x2 * (f64(1.0) - x) * (f64(1.0) - x),
                    f64(60.0) * x * (f64(1.0) - x) * (f64(1.0) - f64(2.0) * x))


@wp.func
def exclusion_weight(same_rod: int, closed: int, rod_length: wp.float64, s_a: wp.float64,
                     arc_b: wp.vec2d, exclusion: wp.float64, v: wp.float64) -> wp.vec3d:
    """W(v), dW/dv, d2W/dv2 of the exclusion ramp between arcs s_a and s_b(v) [m]
    (sectioned_reference.exclusion_ramp)."""
    if same_rod == 0:
        return wp.vec3d(f64(1.0), f64(0.0), f64(0.0))
    s_b = arc_b[0] + v * (arc_b[1] - arc_b[0])
    dsep = s_b - s_a
    sgn = f64(1.0)
    if dsep < f64(0.0):
        sgn = f64(-1.0)
    sep = wp.abs(dsep)
    if closed != 0:
        if rod_length - sep < sep:
            sep = rod_length - sep
            sgn = -sgn
    q = f64(0.25) * exclusion
    s = quintic((sep - exclusion) / q)
    dsdv = sgn * (arc_b[1] - arc_b[0]) / q
    return wp.vec3d(s[0], s[1] * dsdv, s[2] * dsdv * dsdv)


@wp.func
def rounded_penalty(pen: wp.float64, kappa: wp.float64, onset: wp.float64) -> wp.vec3d:
    """phi(pen), phi', phi'' (sectioned_reference.rounded_penalty)."""
    if pen <= f64(0.0):
        return wp.vec3d(f64(0.0), f64(0.0), f64(0.0))
    if pen < onset:
        return wp.vec3d(kappa * pen * pen * pen / (f64(6.0) * onset),
                        kappa * pen * pen / (f64(2.0) * onset), kappa * pen / onset)
    return wp.vec3d(kappa * (f64(0.5) * pen * pen - f64(0.5) * onset * pen
                             + onset * onset / f64(6.0)),
                    kappa * (pen - f64(0.5) * onset), kappa)


@wp.func
def mode_basis(phi: wp.float64, k: int):
    """B(phi) and B'(phi) of the coefficients (a_2, b_2, ..., a_N, b_N), k = 2 (N - 1): cos n
    phi, sin n phi and their derivatives (:func:`mode_basis_cs`)."""
    return mode_basis_cs(wp.cos(phi), wp.sin(phi), k)


@wp.func
def mode_basis_cs(c1: wp.float64, s1: wp.float64, k: int):
    """:func:`mode_basis` at the angle of cosine ``c1`` and sine ``s1``, by the
    angle-addition recurrence."""
    cn = c1 * c1 - s1 * s1  # n = 2
    sn = f64(2.0) * s1 * c1
    b = vecKd()
    d = vecKd()
    for j in range(k // 2):
        n = f64(2 + j)
        b[2 * j] = cn
        b[2 * j + 1] = sn
        d[2 * j] = -n * sn
        d[2 * j + 1] = n * cn
        cn_next = cn * c1 - sn * s1
        sn = sn * c1 + cn * s1
        cn = cn_next
    return b, d


@wp.func
def load_section(coeff: wp.array(dtype=wp.float64), off: int, k: int) -> vecKd:
    """The k coefficients from ``off`` (zero for a rigid section, off < 0)."""
    c = vecKd()
    if off >= 0:
        for j in range(k):
            c[j] = coeff[off + j]
    return c


@wp.func
def mode_turn(angle: wp.float64, k: int):
    """cos n angle and sin n angle of the modes n = 2 .. N (entries 0 .. k/2 - 1): a turn
    that several coefficient vectors share (:func:`turn_modes`)."""
    cs = vecKd()
    sn = vecKd()
    for j in range(k // 2):
        n = f64(2 + j)
        cs[j] = wp.cos(n * angle)
        sn[j] = wp.sin(n * angle)
    return cs, sn


@wp.func
def b_moment_row(q: int, dcb: vecKd, cb0: vecKd, cb1: vecKd) -> vecKd:
    """The coefficient vector that B's z-moment ``q`` multiplies: 0 the difference
    c_b1 - c_b0 over the pass (``dcb``), 1 c_b0, 2 c_b1."""
    if q == 1:
        return cb0
    if q == 2:
        return cb1
    return dcb


@wp.func
def turn_modes(c: vecKd, cs: vecKd, sn: vecKd, k: int, transpose: int) -> vecKd:
    """Q c, or Q^T c (transpose != 0), with Q's cosines and sines ``cs``, ``sn``
    (:func:`mode_turn`)."""
    out = vecKd()
    for j in range(k // 2):
        s_j = sn[j]
        if transpose != 0:
            s_j = -s_j
        out[2 * j] = cs[j] * c[2 * j] + s_j * c[2 * j + 1]
        out[2 * j + 1] = -s_j * c[2 * j] + cs[j] * c[2 * j + 1]
    return out


@wp.func
def amplitude_sum(c: vecKd, k: int) -> wp.float64:
    """sum_n sqrt(a_n^2 + b_n^2) [m]: no boundary point lies farther than this from the
    mean radius (|a cos n phi + b sin n phi| <= sqrt(a^2 + b^2))."""
    t = f64(0.0)
    for j in range(k // 2):
        t += wp.sqrt(c[2 * j] * c[2 * j] + c[2 * j + 1] * c[2 * j + 1])
    return t


@wp.func
def segment_line_distance(p0: wp.vec3d, p1: wp.vec3d, q0: wp.vec3d, e: wp.vec3d,
                          v_lo: wp.float64, v_hi: wp.float64) -> wp.float64:
    """A lower bound of the distance [m] from segment p0 p1 to the segment q0 + v e,
    v in [v_lo, v_hi] (the reach of a partner edge's partition weight, :func:`reach_range`):
    the distance of their closest points (Ericson 2005 sec. 5.1.9, clamped)."""
    d1 = p1 - p0
    r = p0 - (q0 + v_lo * e)
    d2 = (v_hi - v_lo) * e
    a = wp.dot(d1, d1)
    ee = wp.dot(d2, d2)
    f = wp.dot(d2, r)
    c = wp.dot(d1, r)
    b = wp.dot(d1, d2)
    den = a * ee - b * b
    s = f64(0.0)
    if den > f64(1.0e-14) * a * ee:
        s = wp.clamp((b * f - c * ee) / den, f64(0.0), f64(1.0))
    t = (b * s + f) / ee
    if t < f64(0.0):
        t = f64(0.0)
        s = wp.clamp(-c / a, f64(0.0), f64(1.0))
    elif t > f64(1.0):
        t = f64(1.0)
        s = wp.clamp((b - c) / a, f64(0.0), f64(1.0))
    return wp.length(p0 + s * d1 - (q0 + v_lo * e + t * d2))


@wp.func
def reach_range(e: wp.vec3d, c0: wp.vec3d, c1: wp.vec3d, radius: wp.float64) -> wp.vec2d:
    """The range [v_lo, v_hi] of the projection v on an edge's axis (vector ``e`` [m])
    of every point within ``radius`` [m] of the axis where the edge's partition weight is
    not zero (between the planes s0 = -1/2 and s1 = 1/2 of its chords ``c0``, ``c1``,
    :func:`partition_terms`): on the plane (P - x0) . c0 = -|c0|^2 / 4 a point at
    distance rho from the axis has v (e . c0) >= -|c0|^2 / 4 - rho |c0 x t|. Unbounded
    (+-1e30) where a chord makes a right angle or more with the edge."""
    ll = wp.length(e)
    t = e / ll
    v_lo = f64(-1.0e30)
    v_hi = f64(1.0e30)
    ec0 = wp.dot(e, c0)
    if ec0 > f64(0.0):
        v_lo = -(f64(0.25) * wp.dot(c0, c0) + radius * wp.length(wp.cross(c0, t))) / ec0
    ec1 = wp.dot(e, c1)
    if ec1 > f64(0.0):
        v_hi = f64(1.0) + (f64(0.25) * wp.dot(c1, c1) + radius * wp.length(wp.cross(c1, t))) / ec1
    return wp.vec2d(v_lo, v_hi)


@wp.func
def chord_coordinate(y: wp.vec3d, c: wp.vec3d):
    """s = 2 y . c / (c . c) of a point at y from a vertex whose chord is c, with ds/dy,
    ds/dc and the second derivatives d2s/dy dc, d2s/dc2 (d2s/dy2 = 0)
    (sectioned_reference.partition)."""
    dd = wp.dot(c, c)
    yc = wp.dot(y, c)
    eye = wp.identity(n=3, dtype=wp.float64)
    gy = (f64(2.0) / dd) * c
    gc = (f64(2.0) / dd) * y - (f64(4.0) * yc / (dd * dd)) * c
    hyc = (f64(2.0) / dd) * eye - (f64(4.0) / (dd * dd)) * wp.outer(c, c)
    hcc = ((f64(-4.0) / (dd * dd)) * (wp.outer(y, c) + wp.outer(c, y))
           - (f64(4.0) * yc / (dd * dd)) * eye
           + (f64(16.0) * yc / (dd * dd * dd)) * wp.outer(c, c))
    return f64(2.0) * yc / dd, gy, gc, hyc, hcc


@wp.func
def side_step(s: wp.float64, is_open: int, low: int) -> wp.vec3d:
    """sigma(s) and its first two derivatives at one vertex of an edge: S(s + 1/2) at a
    vertex shared with the next edge, S(2 s + 1) at the start and S(2 s) at the end of an
    open rod (``low``: the edge's first vertex)."""
    scale = f64(1.0)
    shift = f64(0.5)
    if is_open != 0:
        scale = f64(2.0)
        shift = f64(0.0)
        if low != 0:
            shift = f64(1.0)
    q = quintic(scale * s + shift)
    return wp.vec3d(q[0], scale * q[1], scale * scale * q[2])


@wp.func
def partition_value(w: wp.vec3d, e: wp.vec3d, c0: wp.vec3d, c1: wp.vec3d, first_open: int,
                    last_open: int) -> wp.float64:
    """The partner edge's partition weight omega at w = P - x_B0 (:func:`partition_terms`
    without derivatives)."""
    s0 = f64(2.0) * wp.dot(w, c0) / wp.dot(c0, c0)
    s1 = f64(2.0) * wp.dot(w - e, c1) / wp.dot(c1, c1)
    om = side_step(s0, first_open, 1)[0] - side_step(s1, last_open, 0)[0]
    return wp.max(om, f64(0.0))


@wp.func
def add_block12(h: mat12d, bi: int, bj: int, m: wp.mat33d) -> mat12d:
    """h with m added at block (bi, bj) (blocks of 3)."""
    for i in range(3):
        for j in range(3):
            h[3 * bi + i, 3 * bj + j] = h[3 * bi + i, 3 * bj + j] + m[i, j]
    return h


@wp.func
def put3(g: vec12d, b: int, v: wp.vec3d, scale: wp.float64) -> vec12d:
    """g with scale v added at block b (blocks of 3)."""
    for i in range(3):
        g[3 * b + i] = g[3 * b + i] + scale * v[i]
    return g


@wp.func
def fold_ghost(g: vec12d, h: mat12d, src: int):
    """A ghost neighbour's chord offset f = e (block ``src``) folded onto e (block 1):
    g_e += g_f, H's rows and columns likewise, block ``src`` zeroed."""
    for i in range(3):
        g[3 + i] = g[3 + i] + g[3 * src + i]
        g[3 * src + i] = f64(0.0)
    for i in range(3):
        for j in range(12):
            h[3 + i, j] = h[3 + i, j] + h[3 * src + i, j]
    for i in range(12):
        for j in range(3):
            h[i, 3 + j] = h[i, 3 + j] + h[i, 3 * src + j]
    for i in range(3):
        for j in range(12):
            h[3 * src + i, j] = f64(0.0)
            h[j, 3 * src + i] = f64(0.0)
    return g, h


@wp.func
def partition_terms(w: wp.vec3d, e: wp.vec3d, f0: wp.vec3d, f1: wp.vec3d, ghost0: int,
                    ghost1: int, first_open: int, last_open: int):
    """The partner edge's partition weight omega = sigma0(s0) - sigma1(s1) (clamped at 0)
    with its gradient and Hessian over (w, e, f0, f1) = (P - x_B0, x_B1 - x_B0, x_B0 -
    x_Bprev, x_Bnext - x_B1) (sectioned_reference.partition): s0 = 2 w . c0 / |c0|^2 with
    the chord c0 = e + f0, s1 = 2 (w - e) . c1 / |c1|^2 with c1 = e + f1. A ghost
    neighbour (an open end: f = e) has its block folded onto e."""
    g = vec12d()
    h = mat12d()
    c0 = e + f0
    c1 = e + f1
    s0, gy0, gc0, hyc0, hcc0 = chord_coordinate(w, c0)
    s1, gy1, gc1, hyc1, hcc1 = chord_coordinate(w - e, c1)
    q0 = side_step(s0, first_open, 1)
    q1 = side_step(s1, last_open, 0)
    om = q0[0] - q1[0]
    if om <= f64(0.0):
        return f64(0.0), g, h
    # ds/d(w, e, f0, f1): s0 through y = w, c = e + f0; s1 through y = w - e, c = e + f1
    g0 = vec12d()
    g0 = put3(g0, 0, gy0, f64(1.0))
    g0 = put3(g0, 1, gc0, f64(1.0))
    g0 = put3(g0, 2, gc0, f64(1.0))
    g1 = vec12d()
    g1 = put3(g1, 0, gy1, f64(1.0))
    g1 = put3(g1, 1, gc1 - gy1, f64(1.0))
    g1 = put3(g1, 3, gc1, f64(1.0))
    g = q0[1] * g0 - q1[1] * g1
    h = q0[2] * wp.outer(g0, g0) - q1[2] * wp.outer(g1, g1)
    # sigma' times the chord coordinates' own second derivatives (hyc, hcc symmetric)
    a0 = q0[1]
    h = add_block12(h, 0, 1, a0 * hyc0)
    h = add_block12(h, 1, 0, a0 * hyc0)
    h = add_block12(h, 0, 2, a0 * hyc0)
    h = add_block12(h, 2, 0, a0 * hyc0)
    h = add_block12(h, 1, 1, a0 * hcc0)
    h = add_block12(h, 1, 2, a0 * hcc0)
    h = add_block12(h, 2, 1, a0 * hcc0)
    h = add_block12(h, 2, 2, a0 * hcc0)
    a1 = -q1[1]
    h = add_block12(h, 0, 1, a1 * hyc1)
    h = add_block12(h, 1, 0, a1 * hyc1)
    h = add_block12(h, 0, 3, a1 * hyc1)
    h = add_block12(h, 3, 0, a1 * hyc1)
    h = add_block12(h, 1, 1, a1 * (hcc1 - f64(2.0) * hyc1))
    h = add_block12(h, 1, 3, a1 * (hcc1 - hyc1))
    h = add_block12(h, 3, 1, a1 * (hcc1 - hyc1))
    h = add_block12(h, 3, 3, a1 * hcc1)
    if ghost0 != 0:
        g, h = fold_ghost(g, h, 2)
    if ghost1 != 0:
        g, h = fold_ghost(g, h, 3)
    return om, g, h


@wp.struct
class FrameDerivatives:
    """An edge's transported frame with its derivatives in the edge vector e
    (sectioned_reference.frame_derivatives): M = d(d)/de, and T, d2 d_k/de de for k = x, y,
    z (central differences of M)."""

    d1: wp.vec3d
    d2: wp.vec3d
    m1: wp.mat33d
    m2: wp.mat33d
    t1x: wp.mat33d
    t1y: wp.mat33d
    t1z: wp.mat33d
    t2x: wp.mat33d
    t2y: wp.mat33d
    t2z: wp.mat33d


@wp.func
def frame_firsts(d1r: wp.vec3d, tr: wp.vec3d, e: wp.vec3d):
    """d1, d2 and their exact derivatives in the edge vector e (3 x 3)."""
    length = wp.length(e)
    t = e / length
    d1, d2, j1, j2 = transported_frame(d1r, tr, t)
    pt = (wp.identity(n=3, dtype=wp.float64) - wp.outer(t, t)) / length
    return d1, d2, j1 @ pt, j2 @ pt


@wp.func
def frame_derivatives(d1r: wp.vec3d, tr: wp.vec3d, e: wp.vec3d) -> FrameDerivatives:
    """The frame and its first and second derivatives in e (FrameDerivatives)."""
    out = FrameDerivatives()
    d1, d2, m1, m2 = frame_firsts(d1r, tr, e)
    out.d1 = d1
    out.d2 = d2
    out.m1 = m1
    out.m2 = m2
    h = f64(FRAME_STEP) * wp.length(e)
    t1x = wp.mat33d()
    t1y = wp.mat33d()
    t1z = wp.mat33d()
    t2x = wp.mat33d()
    t2y = wp.mat33d()
    t2z = wp.mat33d()
    for j in range(3):
        step = wp.vec3d()
        step[j] = h
        _p1, _p2, m1p, m2p = frame_firsts(d1r, tr, e + step)
        _q1, _q2, m1m, m2m = frame_firsts(d1r, tr, e - step)
        g1 = (m1p - m1m) / (f64(2.0) * h)
        g2 = (m2p - m2m) / (f64(2.0) * h)
        for i in range(3):
            t1x[i, j] = g1[0, i]
            t1y[i, j] = g1[1, i]
            t1z[i, j] = g1[2, i]
            t2x[i, j] = g2[0, i]
            t2y[i, j] = g2[1, i]
            t2z[i, j] = g2[2, i]
    out.t1x = f64(0.5) * (t1x + wp.transpose(t1x))
    out.t1y = f64(0.5) * (t1y + wp.transpose(t1y))
    out.t1z = f64(0.5) * (t1z + wp.transpose(t1z))
    out.t2x = f64(0.5) * (t2x + wp.transpose(t2x))
    out.t2y = f64(0.5) * (t2y + wp.transpose(t2y))
    out.t2z = f64(0.5) * (t2z + wp.transpose(t2z))
    return out


@wp.func
def contract(y: wp.vec3d, tx: wp.mat33d, ty: wp.mat33d, tz: wp.mat33d) -> wp.mat33d:
    """sum_k y_k T_k."""
    return y[0] * tx + y[1] * ty + y[2] * tz


@wp.func
def join6(a: wp.vec3d, b: wp.vec3d) -> vec6d:
    """(a, b)."""
    return vec6d(a[0], a[1], a[2], b[0], b[1], b[2])


@wp.func
def add_block(m: mat66d, r0: int, c0: int, b: wp.mat33d) -> mat66d:
    """m with b added at rows r0.., columns c0.."""
    for i in range(3):
        for j in range(3):
            m[r0 + i, c0 + j] = m[r0 + i, c0 + j] + b[i, j]
    return m


@wp.struct
class Cylinder:
    """A point's projection v, distance rho and angle psi about an edge's axis, each with
    gradient and Hessian over (w, e) = (P - x_b0, x_b1 - x_b0)
    (sectioned_reference.cylinder_coordinates)."""

    v: wp.float64
    rho: wp.float64
    psi: wp.float64
    gv: vec6d
    hv: mat66d
    grho: vec6d
    hrho: mat66d
    gpsi: vec6d
    hpsi: mat66d


@wp.func
def d2_dot(gv: vec6d, hv: mat66d, y: wp.vec3d, e: wp.vec3d) -> mat66d:
    """y . d2 D over (w, e), D = w - v e: -(grad v y_e^T + y_e grad v^T) - (y . e) hess v."""
    ye = join6(wp.vec3d(), y)
    return -(wp.outer(gv, ye) + wp.outer(ye, gv)) - wp.dot(y, e) * hv


@wp.func
def frame_component(dvec: wp.vec3d, d: wp.vec3d, m: wp.mat33d, tx: wp.mat33d,
                    ty: wp.mat33d, tz: wp.mat33d, jd: mat36d, gv: vec6d, hv: mat66d,
                    e: wp.vec3d):
    """X = D . d over (w, e): value, gradient and Hessian, d the frame vector with
    derivative m and second derivatives T in e."""
    dm = mat36d()
    for i in range(3):
        for j in range(3):
            dm[i, 3 + j] = m[i, j]
    grad = wp.transpose(jd) @ d + wp.transpose(dm) @ dvec
    hess = d2_dot(gv, hv, d, e) + wp.transpose(jd) @ dm + wp.transpose(dm) @ jd
    hess = add_block(hess, 3, 3, contract(dvec, tx, ty, tz))
    return wp.dot(dvec, d), grad, hess


@wp.func
def cylinder(w: wp.vec3d, e: wp.vec3d, fd: FrameDerivatives) -> Cylinder:
    """Cylinder coordinates of w about e with their derivatives (Cylinder)."""
    out = Cylinder()
    ll = wp.dot(e, e)
    v = wp.dot(w, e) / ll
    dvec = w - v * e
    rho = wp.length(dvec)
    nrm = dvec / rho
    a = w - f64(2.0) * v * e
    gv = join6(e / ll, a / ll)
    eye = wp.identity(n=3, dtype=wp.float64)
    hv = mat66d()
    hv = add_block(hv, 0, 3, eye / ll - f64(2.0) * wp.outer(e, e) / (ll * ll))
    hv = add_block(hv, 3, 0, eye / ll - f64(2.0) * wp.outer(e, e) / (ll * ll))
    hv = add_block(hv, 3, 3, f64(-2.0) * (wp.outer(e, a) + wp.outer(a, e)) / (ll * ll)
                   - (f64(2.0) * v / ll) * eye)
    jd = mat36d()
    left = eye - wp.outer(e, e) / ll
    right = -v * eye - wp.outer(e, a) / ll
    for i in range(3):
        for j in range(3):
            jd[i, j] = left[i, j]
            jd[i, 3 + j] = right[i, j]
    out.v = v
    out.rho = rho
    out.gv = gv
    out.hv = hv
    out.grho = wp.transpose(jd) @ nrm
    out.hrho = (wp.transpose(jd) @ (((eye - wp.outer(nrm, nrm)) / rho) @ jd)
                + d2_dot(gv, hv, nrm, e))
    x, gx, hx = frame_component(dvec, fd.d1, fd.m1, fd.t1x, fd.t1y, fd.t1z, jd, gv, hv, e)
    y, gy, hy = frame_component(dvec, fd.d2, fd.m2, fd.t2x, fd.t2y, fd.t2z, jd, gv, hv, e)
    ss = x * x + y * y
    out.psi = wp.atan2(y, x)
    out.gpsi = (x * gy - y * gx) / ss
    # psi = Im log(X + i Y): its Hessian is Im(hess Z / Z - grad Z grad Z^T / Z^2).
    out.hpsi = ((x * hy - y * hx) / ss
                - ((wp.outer(gx, gx) - wp.outer(gy, gy)) * (f64(-2.0) * x * y)
                   + (wp.outer(gx, gy) + wp.outer(gy, gx)) * (x * x - y * y)) / (ss * ss))
    return out


@wp.func
def radius_base(r0: wp.float64, nu: wp.float64, lam: wp.float64) -> wp.vec3d:
    """r0^2 lam^(-2 nu) [m^2] and its first two derivatives in lam: the mean radius's
    parts that depend on the stretch alone (a pass's constants, :func:`radius_partials`)."""
    s0 = r0 * r0 * wp.pow(lam, f64(-2.0) * nu)
    s1 = f64(-2.0) * nu * r0 * r0 * wp.pow(lam, f64(-2.0) * nu - f64(1.0))
    s2 = f64(2.0) * nu * (f64(2.0) * nu + f64(1.0)) * r0 * r0 * wp.pow(lam, f64(-2.0) * nu
                                                                      - f64(2.0))
    return wp.vec3d(s0, s1, s2)


@wp.func
def radius_partials(c: vecKd, k: int, rigid: int, r0: wp.float64, base: wp.vec3d):
    """R, dR/dlam and d2R/dlam2 where the coefficients are c and the stretch's part is
    ``base`` (:func:`radius_base`): R^2 = r0^2 lam^(-2 nu) - |c|^2 / 2 (r0, 0, 0 for a
    rigid section; R = -1 where it is not real)."""
    if rigid != 0:
        return r0, f64(0.0), f64(0.0)
    s = base[0]
    for j in range(k):
        s -= f64(0.5) * c[j] * c[j]
    if s <= f64(0.0):
        return f64(-1.0), f64(0.0), f64(0.0)
    big_r = wp.sqrt(s)
    s1 = base[1]
    s2 = base[2]
    return big_r, s1 / (f64(2.0) * big_r), (s2 / (f64(2.0) * big_r)
                                            - s1 * s1 / (f64(4.0) * big_r * big_r * big_r))


@wp.func
def reduce_vec(y: vec6d, dmat: wp.mat33d, dirv: wp.vec3d, deform_a: int) -> vec16d:
    """J^T y for a 6-vector y over (w, e) = (P - x_B0, x_B1 - x_B0): the reduced
    directions (x_A0, x_A1, x_B0, x_B1, A's section direction; B's three are zero), where
    dP/dx_A1 = ``dmat``, dP/dx_A0 = I - dmat and dP/dalpha = ``dirv`` (``deform_a``)."""
    out = vec16d()
    for i in range(3):
        t = f64(0.0)
        for r in range(3):
            t += dmat[r, i] * y[r]
        out[i] = y[i] - t
        out[3 + i] = t
        out[6 + i] = -(y[i] + y[3 + i])
        out[9 + i] = y[3 + i]
    if deform_a != 0:
        out[12] = dirv[0] * y[0] + dirv[1] * y[1] + dirv[2] * y[2]
    return out


@wp.func
def reduce_mat(h6: mat66d, dmat: wp.mat33d, dirv: wp.vec3d, deform_a: int) -> mat16d:
    """J^T H J for a symmetric 6 x 6 H over (w, e) (J as in :func:`reduce_vec`), by J's
    blocks (identities, dP/dx_A1 and A's section direction) rather than as dense products."""
    g = mat6x16d()  # H J, its 13 nonzero columns
    for r in range(6):
        for i in range(3):
            hd = f64(0.0)
            for m in range(3):
                hd += h6[r, m] * dmat[m, i]
            g[r, i] = h6[r, i] - hd
            g[r, 3 + i] = hd
            g[r, 6 + i] = -(h6[r, i] + h6[r, 3 + i])
            g[r, 9 + i] = h6[r, 3 + i]
        if deform_a != 0:
            g[r, 12] = h6[r, 0] * dirv[0] + h6[r, 1] * dirv[1] + h6[r, 2] * dirv[2]
    out = mat16d()
    for c in range(13):
        for i in range(3):
            t = f64(0.0)
            for m in range(3):
                t += dmat[m, i] * g[m, c]
            out[i, c] = g[i, c] - t
            out[3 + i, c] = t
            out[6 + i, c] = -(g[i, c] + g[3 + i, c])
            out[9 + i, c] = g[3 + i, c]
        if deform_a != 0:
            out[12, c] = dirv[0] * g[0, c] + dirv[1] * g[1, c] + dirv[2] * g[2, c]
    return out


@wp.func
def add_pee(target: mat16d, pee: wp.mat33d, row: wp.vec3d, deform_a: int) -> mat16d:
    """target with the second derivatives of P in a's edge vector (``pee``, on x_A0 and
    x_A1 with the signs of e = x_A1 - x_A0) and their coupling ``row`` to a's section
    direction (index 12) added."""
    for i in range(3):
        for j in range(3):
            target[3 + i, 3 + j] = target[3 + i, 3 + j] + pee[i, j]
            target[i, j] = target[i, j] + pee[i, j]
            target[i, 3 + j] = target[i, 3 + j] - pee[i, j]
            target[3 + i, j] = target[3 + i, j] - pee[i, j]
        if deform_a != 0:
            target[3 + i, 12] = target[3 + i, 12] + row[i]
            target[12, 3 + i] = target[12, 3 + i] + row[i]
            target[i, 12] = target[i, 12] - row[i]
            target[12, i] = target[12, i] - row[i]
    return target


@wp.func
def turn_direction(c: vecKd, k: int) -> vecKd:
    """d(Q^T(m) c)/dm at m = 0: n J c per mode, (a_n, b_n) -> n (-b_n, a_n)
    (:func:`turn_modes`' Q^T turns mode n by n m)."""
    out = vecKd()
    for j in range(k // 2):
        n = f64(2 + j)
        out[2 * j] = -n * c[2 * j + 1]
        out[2 * j + 1] = n * c[2 * j]
    return out


@wp.func
def chord_target(i: int, side: int):
    """The coordinate (of the pass's 18: x_A0, x_A1, x_B0, x_B1, x_Bprev, x_Bnext) and sign
    of one of the two vertices that chord offset component ``i`` depends on: f0 = x_B0 -
    x_Bprev (i < 3), f1 = x_Bnext - x_B1 (i >= 3)."""
    if i < 3:
        if side == 0:
            return 6 + i, f64(1.0)
        return 12 + i, f64(-1.0)
    if side == 0:
        return 12 + i, f64(1.0)
    return 6 + i, f64(-1.0)


@wp.func
def local_coordinate(i: int, k: int) -> int:
    """The pass's local dof of its coordinate i (of 18): the neighbours' come after the
    sections' 4 k coefficients."""
    if i < 12:
        return i
    return 4 * k + i


@wp.func
def twist_column(out: wp.array(dtype=wp.float64), to: int, grad: wp.array(dtype=wp.float64),
                 g_at: int, v: vecKd, k: int, node: int, h_x: mat18xKd, h_0: matKd,
                 h_1: matKd, h_2: matKd, h_3: matKd):
    """Write H[y, c] v over the pass's local dofs y, c the coefficients of local node
    ``node`` (1: A's second vertex, 3: B's), v = n J c (:func:`turn_direction`), plus
    (n J)^T grad_c (the gradient at ``grad[g_at:]``) on c's rows. ``h_x``: the coordinates
    against c (18 x k); ``h_0`` .. ``h_3``: the coefficient blocks of the four nodes
    against c's node as the pass holds them: for node 1, (A0, A1) [A0 row], (A1, A1)
    upper, (A1, B0) and (A1, B1) [A1 row]; for node 3, (A0, B1), (A1, B1), (B0, B1)
    [B1 column] and (B1, B1) upper."""
    for i in range(18):
        s = f64(0.0)
        for j in range(k):
            s += h_x[i, j] * v[j]
        out[to + local_coordinate(i, k)] = s
    for i in range(k):
        s0 = f64(0.0)
        s1 = f64(0.0)
        s2 = f64(0.0)
        s3 = f64(0.0)
        for j in range(k):
            if node == 1:
                s0 += h_0[i, j] * v[j]
                if j >= i:
                    s1 += h_1[i, j] * v[j]
                else:
                    s1 += h_1[j, i] * v[j]
                s2 += h_2[j, i] * v[j]
                s3 += h_3[j, i] * v[j]
            else:
                s0 += h_0[i, j] * v[j]
                s1 += h_1[i, j] * v[j]
                s2 += h_2[i, j] * v[j]
                if j >= i:
                    s3 += h_3[i, j] * v[j]
                else:
                    s3 += h_3[j, i] * v[j]
        out[to + 12 + i] = s0
        out[to + 12 + k + i] = s1
        out[to + 12 + 2 * k + i] = s2
        out[to + 12 + 3 * k + i] = s3
    # (n J)^T grad_c on c's own rows: (g_a, g_b) -> n (g_b, -g_a)
    row = to + 12 + node * k
    for j in range(k // 2):
        n = f64(2 + j)
        out[row + 2 * j] = out[row + 2 * j] + n * grad[g_at + 2 * j + 1]
        out[row + 2 * j + 1] = out[row + 2 * j + 1] - n * grad[g_at + 2 * j]


@wp.func
def qt_entry(cs: vecKd, sn: vecKd, i: int, j: int) -> wp.float64:
    """Entry (i, j) of Q^T: per mode [[cos, -sin], [sin, cos]] (:func:`turn_modes`)."""
    qt = f64(0.0)
    if i // 2 == j // 2:
        mo = i // 2
        if i % 2 == j % 2:
            qt = cs[mo]
        elif i % 2 == 0:
            qt = -sn[mo]
        else:
            qt = sn[mo]
    return qt


@wp.func
def radius_cc(h00: matKd, h01: matKd, h11: matKd, g: wp.float64, c: vecKd, qc: vecKd,
              big_r: wp.float64, w0: wp.float64, w1: wp.float64, cs: vecKd, sn: vecKd,
              k: int):
    """``g`` times a mean radius's R_cc = -I / (2 R) - c c^T / (4 R^3) added to an edge's
    coefficient blocks, c = w0 c_0 + w1 Q^T c_1 (``qc`` = Q c; Q's cosines and sines
    ``cs``, ``sn``): w0^2 R_cc on (0, 0), w0 w1 R_cc Q^T on (0, 1), w1^2 Q R_cc Q^T on (1, 1)
    (the diagonal blocks' upper triangles)."""
    ia = g / (f64(2.0) * big_r)
    ib = g / (f64(4.0) * big_r * big_r * big_r)
    for i in range(k):
        for j in range(k):
            h01[i, j] = h01[i, j] + w0 * w1 * (-ia * qt_entry(cs, sn, i, j) - ib * c[i] * qc[j])
            if j >= i:
                d0 = -ib * c[i] * c[j]
                d1 = -ib * qc[i] * qc[j]
                if i == j:
                    d0 = d0 - ia
                    d1 = d1 - ia
                h00[i, j] = h00[i, j] + w0 * w0 * d0
                h11[i, j] = h11[i, j] + w1 * w1 * d1
    return h00, h01, h11


@wp.func
def radius_moments(h00: matKd, h01: matKd, h11: matKd, mom_a: wp.vec3d, mom_b: vec5d,
                   c0: vecKd, c1: vecKd, qc0: vecKd, qc1: vecKd, cs: vecKd, sn: vecKd,
                   k: int):
    """A partner's R_cc summed over a pass's samples at c(v) = (1 - v) c0 + v c1 (``qc0``,
    ``qc1`` = Q c0, Q c1): ``mom_a`` = sum g / (2 R) ((1 - v)^2, (1 - v) v, v^2) and
    ``mom_b`` = sum g / (4 R^3) (1 - v)^(4 - i) v^i, i = 0 .. 4, added to the blocks as
    :func:`radius_cc` adds one sample's."""
    for i in range(k):
        for j in range(k):
            h01[i, j] = h01[i, j] - (mom_a[1] * qt_entry(cs, sn, i, j)
                                     + mom_b[1] * c0[i] * qc0[j]
                                     + mom_b[2] * (c0[i] * qc1[j] + c1[i] * qc0[j])
                                     + mom_b[3] * c1[i] * qc1[j])
            if j >= i:
                d0 = (mom_b[0] * c0[i] * c0[j] + mom_b[1] * (c0[i] * c1[j] + c1[i] * c0[j])
                      + mom_b[2] * c1[i] * c1[j])
                d1 = (mom_b[2] * qc0[i] * qc0[j]
                      + mom_b[3] * (qc0[i] * qc1[j] + qc1[i] * qc0[j])
                      + mom_b[4] * qc1[i] * qc1[j])
                if i == j:
                    d0 = d0 + mom_a[0]
                    d1 = d1 + mom_a[2]
                h00[i, j] = h00[i, j] - d0
                h11[i, j] = h11[i, j] - d1
    return h00, h01, h11


def make_pass_kernel(derivatives: bool, report: bool) -> wp.Kernel:
    """The pass kernel's variant: energy only, or with the gradient and Hessian
    (``derivatives``); ``report`` also writes each sample's penetration and weight."""

    def sectioned_pass(
        # Model:
        edge_vertex: wp.array(dtype=wp.vec2i),
        edge_rod: wp.array(dtype=wp.int32),
        rod_closed: wp.array(dtype=wp.int32),
        edge_r0: wp.array(dtype=wp.float64),
        edge_nu: wp.array(dtype=wp.float64),
        edge_modulus: wp.array(dtype=wp.float64),
        edge_rigid: wp.array(dtype=wp.int32),
        vertex_offset: wp.array(dtype=wp.int32),
        edge_end: wp.array(dtype=wp.vec2i),
        edge_exclusion: wp.array(dtype=wp.float64),
        gauss_xi: wp.array(dtype=wp.float64),
        gauss_w: wp.array(dtype=wp.float64),
        sample_cos: wp.array(dtype=wp.float64),
        sample_sin: wp.array(dtype=wp.float64),
        coeff_count: int,
        samples: int,
        penalty: wp.float64,
        onset: wp.float64,
        rod_mean: int,
        gauss_newton: int,
        edge_neighbour: wp.array(dtype=wp.vec2i),
        # Data in:
        x_in: wp.array(dtype=wp.vec3d),
        coeff_in: wp.array(dtype=wp.float64),
        t_ref_in: wp.array(dtype=wp.vec3d),
        d1_ref_in: wp.array(dtype=wp.vec3d),
        end_twist_in: wp.array(dtype=wp.float64),
        rest_in: wp.array(dtype=wp.float64),
        arc_in: wp.array(dtype=wp.vec2d),
        rod_length_in: wp.array(dtype=wp.float64),
        lam_in: wp.array(dtype=wp.float64),
        vertex_amp_in: wp.array(dtype=wp.float64),
        edge_rbase_in: wp.array(dtype=wp.float64),
        pairs_in: wp.array(dtype=wp.vec2i),
        slots_in: wp.array(dtype=wp.int32),
        # Out:
        energy_out: wp.array(dtype=wp.float64),
        grad_out: wp.array(dtype=wp.float64),
        blocks_out: wp.array(dtype=wp.float64),
        sample_pen_out: wp.array(dtype=wp.float64),
        sample_weight_out: wp.array(dtype=wp.float64),
        dlam_out: wp.array(dtype=wp.float64),
        twist_col_out: wp.array(dtype=wp.float64),
    ):
        tid = wp.tid()
        pr = pairs_in[tid // 2]
        ea = pr[0]
        eb = pr[1]
        if tid % 2 == 1:
            ea = pr[1]
            eb = pr[0]
        k = coeff_count
        nl = 18 + 4 * k
        ng = gauss_xi.shape[0]
        # 1 for the exact Hessian, 0 for its Gauss-Newton part (a_s wt phi'' grad(pen)
        # grad(pen)^T per sample, positive semidefinite)
        curv = f64(1.0)
        if gauss_newton != 0:
            curv = f64(0.0)
        so = tid * ng * samples
        if wp.static(report):
            for q in range(ng * samples):
                sample_pen_out[so + q] = f64(0.0)
                sample_weight_out[so + q] = f64(0.0)
        energy = f64(0.0)
        va = edge_vertex[ea]
        vb = edge_vertex[eb]
        xa0 = x_in[va[0]]
        xb0 = x_in[vb[0]]
        vec_a = x_in[va[1]] - xa0
        vec_b = x_in[vb[1]] - xb0
        la = wp.length(vec_a)
        lb = wp.length(vec_b)
        ta = vec_a / la
        tb = vec_b / lb
        rig_a = edge_rigid[ea]
        rig_b = edge_rigid[eb]
        lam_a = la / rest_in[ea]
        lam_b = lb / rest_in[eb]
        if rod_mean != 0:
            # the sections thin with their rods' mean stretch, given per edge (its chain
            # rule through the rods' lengths is the host's, from dlam_out)
            lam_a = lam_in[ea]
            lam_b = lam_in[eb]
        # Largest boundary radii: the mean radius is at most r0 lam^-nu, a vertex's modes
        # move the boundary by at most their amplitudes' sum (turning keeps each mode's
        # amplitude), and over the partner's reach (v in [-1/2, 3/2]) the interpolation
        # weighs the two vertices by at most 1.5 each (:func:`section_bounds`).
        amp_a = wp.max(vertex_amp_in[va[0]], vertex_amp_in[va[1]])
        r_a_max = edge_rbase_in[ea] + amp_a
        r_b_max = edge_rbase_in[eb] + f64(1.5) * (vertex_amp_in[vb[0]] + vertex_amp_in[vb[1]])
        if rig_a != 0:
            r_a_max = edge_r0[ea]
            amp_a = f64(0.0)
        if rig_b != 0:
            r_b_max = edge_r0[eb]
        # B's chords at its vertices (its rod's neighbours; a ghost at an open end, f = e)
        # and the reach of its partition weight along its axis
        nb = edge_neighbour[eb]
        ghost0 = int(1)
        ghost1 = int(1)
        f0 = vec_b
        f1 = vec_b
        if nb[0] >= 0:
            f0 = xb0 - x_in[nb[0]]
            ghost0 = 0
        if nb[1] >= 0:
            f1 = x_in[nb[1]] - x_in[vb[1]]
            ghost1 = 0
        ch0 = vec_b + f0
        ch1 = vec_b + f1
        ds0 = f64(2.0) / wp.length(ch0)  # |dP s0|: s0 moves by at most this per metre
        ds1 = f64(2.0) / wp.length(ch1)
        reach = reach_range(vec_b, ch0, ch1, r_b_max)
        if segment_line_distance(xa0, x_in[va[1]], xb0, vec_b, reach[0],
                                 reach[1]) > r_a_max + r_b_max:
            energy_out[tid] = energy
            return
        # The sections of the edges' vertices, the second one's turned into the edge's
        # frame.
        ca0 = load_section(coeff_in, vertex_offset[va[0]], k)
        ca1 = load_section(coeff_in, vertex_offset[va[1]], k)
        cb0 = load_section(coeff_in, vertex_offset[vb[0]], k)
        cb1 = load_section(coeff_in, vertex_offset[vb[1]], k)
        turn_ac, turn_as = mode_turn(end_twist_in[ea], k)
        turn_bc, turn_bs = mode_turn(end_twist_in[eb], k)
        ca1 = turn_modes(ca1, turn_ac, turn_as, k, 1)
        cb1 = turn_modes(cb1, turn_bc, turn_bs, k, 1)
        base_a = radius_base(edge_r0[ea], edge_nu[ea], lam_a)
        base_b = radius_base(edge_r0[eb], edge_nu[eb], lam_b)
        if wp.static(derivatives):
            fa = frame_derivatives(d1_ref_in[ea], t_ref_in[ea], vec_a)
            fb = frame_derivatives(d1_ref_in[eb], t_ref_in[eb], vec_b)
            d1a = fa.d1
            d2a = fa.d2
            d1b = fb.d1
            d2b = fb.d2
        else:
            d1a, d2a, _j1a, _j2a = transported_frame(d1_ref_in[ea], t_ref_in[ea], ta)
            d1b, d2b, _j1b, _j2b = transported_frame(d1_ref_in[eb], t_ref_in[eb], tb)
        eye = wp.identity(n=3, dtype=wp.float64)
        emod = f64(2.0) * edge_modulus[ea] * edge_modulus[eb] / (edge_modulus[ea]
                                                                  + edge_modulus[eb])
        d0 = edge_r0[ea] + edge_r0[eb]
        kappa = penalty * emod / d0
        onset_m = onset * d0
        rod = edge_rod[ea]
        same_rod = int(0)
        if edge_rod[eb] == rod:
            same_rod = 1
        closed = rod_closed[rod]
        rod_len = rod_length_in[rod]
        excl = wp.max(edge_exclusion[ea], edge_exclusion[eb])
        arc_a = arc_in[ea]
        arc_b = arc_in[eb]
        endb = edge_end[eb]
        area = rest_in[ea] * edge_r0[ea] * f64(TWO_PI) / f64(samples)
        dcb = cb1 - cb0  # dc_b/dv
        go = tid * nl
        touched = int(0)
        dlam_a = f64(0.0)
        dlam_b = f64(0.0)
        if wp.static(derivatives):
            # The pass's Hessian over (x_A0, x_A1, x_B0, x_B1, c_A0, c_A1, c_B0, c_B1),
            # summed over its samples in registers: the coordinates' block, the
            # coordinates against each vertex's coefficients, and the coefficients' blocks
            # of the node pairs (the diagonal ones upper triangles only).
            h_xx = mat18d()
            h_xa0 = mat18xKd()
            h_xa1 = mat18xKd()
            h_xb0 = mat18xKd()
            h_xb1 = mat18xKd()
            h_a0a0 = matKd()
            h_a0a1 = matKd()
            h_a1a1 = matKd()
            h_a0b0 = matKd()
            h_a0b1 = matKd()
            h_a1b0 = matKd()
            h_a1b1 = matKd()
            h_b0b0 = matKd()
            h_b0b1 = matKd()
            h_b1b1 = matKd()
        # B's radius sums over the pass (the samples' moments in v) and the v terms
        mom_a = wp.vec3d()
        mom_g = wp.vec3d()
        mom_b = vec5d()
        zx = mat12x6d()
        for gi in range(ng):
            u = gauss_xi[gi]
            xu = xa0 + u * vec_a
            # the Gauss circle cannot reach B
            rel0 = xu - xb0
            v0 = wp.dot(rel0, vec_b) / (lb * lb)
            v0c = wp.clamp(v0, reach[0], reach[1])
            if wp.length(rel0 - v0c * vec_b) > r_a_max + r_b_max:
                continue
            ca = (f64(1.0) - u) * ca0 + u * ca1
            ra_mean, ra_l, ra_ll = radius_partials(ca, k, rig_a, edge_r0[ea], base_a)
            ga_sum = f64(0.0)
            za = mat6xKd()
            hit = int(0)
            if ra_mean <= f64(0.0):
                energy_out[tid] = f64(1.0e300)
                return
            s_a = arc_a[0] + u * (arc_a[1] - arc_a[0])
            for kk in range(samples):
                cphi = sample_cos[kk]
                sphi = sample_sin[kk]
                dirv = cphi * d1a + sphi * d2a
                if rig_a == 0:
                    # The modes move the sample by at most amp_a from the mean circle's
                    # point q, so q shows (with a margin for round-off) the samples that
                    # the tests below would skip, before the modes are summed.
                    slack = amp_a * f64(1.000001) + f64(1.0e-9) * (r_a_max + r_b_max)
                    relq = xu + ra_mean * dirv - xb0
                    vq = wp.dot(relq, vec_b) / (lb * lb)
                    s0q = f64(2.0) * wp.dot(relq, ch0) / wp.dot(ch0, ch0)
                    s1q = f64(2.0) * wp.dot(relq - vec_b, ch1) / wp.dot(ch1, ch1)
                    if s0q <= f64(-0.5) - slack * ds0 or s1q >= f64(0.5) + slack * ds1:
                        continue
                    if wp.length(relq - vq * vec_b) - slack >= r_b_max:
                        continue
                bphi, bphi1 = mode_basis_cs(cphi, sphi, k)
                r_a = ra_mean
                if rig_a == 0:
                    r_a += wp.dot(bphi, ca)
                p = xu + r_a * dirv
                rel = p - xb0
                v = wp.dot(rel, vec_b) / (lb * lb)
                om = partition_value(rel, vec_b, ch0, ch1, endb[0], endb[1])
                if om <= f64(0.0):
                    continue
                dvec = rel - v * vec_b
                rho = wp.length(dvec)
                if rho >= r_b_max:
                    continue
                bx = wp.dot(dvec, d1b)
                by = wp.dot(dvec, d2b)
                psi = wp.atan2(by, bx)
                bpsi, bpsi1 = mode_basis(psi, k)
                cb = (f64(1.0) - v) * cb0 + v * cb1
                rb_mean, rb_l, rb_ll = radius_partials(cb, k, rig_b, edge_r0[eb], base_b)
                if rb_mean <= f64(0.0):
                    energy_out[tid] = f64(1.0e300)
                    return
                r_b = rb_mean
                r_b1 = f64(0.0)
                r_b2 = f64(0.0)
                if rig_b == 0:
                    r_b += wp.dot(bpsi, cb)
                    r_b1 = wp.dot(bpsi1, cb)
                    for j in range(k // 2):
                        n2 = f64((2 + j) * (2 + j))
                        r_b2 -= n2 * (bpsi[2 * j] * cb[2 * j] + bpsi[2 * j + 1] * cb[2 * j + 1])
                pen = r_b - rho
                wex = exclusion_weight(same_rod, closed, rod_len, s_a, arc_b, excl, v)
                wt = om * wex[0]
                if wp.static(report):
                    sample_pen_out[so + gi * samples + kk] = pen
                    sample_weight_out[so + gi * samples + kk] = wt
                if pen <= f64(0.0) or wt <= f64(0.0):
                    continue
                ph = rounded_penalty(pen, kappa, onset_m)
                a_s = f64(0.5) * gauss_w[gi] * area
                energy += a_s * wt * ph[0]
                if wp.static(derivatives):
                    cyl = cylinder(rel, vec_b, fb)
                    # The weight wt = omega W(v) over (w, e, f0, f1): omega's derivatives
                    # (partition_terms), W's through the projection v, whose own
                    # curvature (hv) enters the (w, e) block below.
                    _om, g_om, h_om = partition_terms(rel, vec_b, f0, f1, ghost0, ghost1,
                                                       endb[0], endb[1])
                    gv12 = vec12d()
                    for i in range(6):
                        gv12[i] = cyl.gv[i]
                    gwt = wex[0] * g_om + (om * wex[1]) * gv12
                    hwt = (wex[0] * h_om + wex[1] * (wp.outer(g_om, gv12) + wp.outer(gv12, g_om))
                           + (om * wex[2]) * wp.outer(gv12, gv12))
                    gwt6 = vec6d()
                    gwtf = vec6d()
                    hwt6 = mat66d()
                    hwtf = mat66d()  # rows f, columns (w, e)
                    hwff = mat66d()
                    for i in range(6):
                        gwt6[i] = gwt[i]
                        gwtf[i] = gwt[6 + i]
                        for j in range(6):
                            hwt6[i, j] = hwt[i, j] + om * wex[1] * cyl.hv[i, j]
                            hwtf[i, j] = hwt[6 + i, j]
                            hwff[i, j] = hwt[6 + i, 6 + j]
                    # dr/dc at the sample on each side, and B's radius partials in (psi, v)
                    ba = bphi - ca / (f64(2.0) * ra_mean)
                    bb = bpsi - cb / (f64(2.0) * rb_mean)
                    rbv = f64(0.0)
                    rbvv = f64(0.0)
                    rbpsiv = f64(0.0)
                    if rig_b == 0:
                        rbv = wp.dot(bb, dcb)
                        rbvv = (-wp.dot(dcb, dcb) / (f64(2.0) * rb_mean)
                                - wp.dot(cb, dcb) * wp.dot(cb, dcb)
                                / (f64(4.0) * rb_mean * rb_mean * rb_mean))
                        rbpsiv = wp.dot(bpsi1, dcb)
                    # P over the reduced directions: x_A0, x_A1 and A's section direction
                    m_dir = cphi * fa.m1 + sphi * fa.m2
                    # the radii's stretch partials through the pass's own edges (none
                    # when the stretch is the rod's mean)
                    ra_lx = ra_l
                    ra_llx = ra_ll
                    rb_lx = rb_l
                    rb_llx = rb_ll
                    if rod_mean != 0:
                        ra_lx = f64(0.0)
                        ra_llx = f64(0.0)
                        rb_lx = f64(0.0)
                        rb_llx = f64(0.0)
                    dra = (ra_lx / rest_in[ea]) * ta
                    dp_de = u * eye + r_a * m_dir + wp.outer(dirv, dra)
                    lam_dir = join6(wp.vec3d(), tb / rest_in[eb])
                    lam_hess = add_block(mat66d(), 3, 3, (eye - wp.outer(tb, tb))
                                         / (lb * rest_in[eb]))
                    gpsi = cyl.gpsi
                    gv = cyl.gv
                    g_we = cyl.grho - r_b1 * gpsi - rbv * gv - rb_lx * lam_dir
                    h_we = (cyl.hrho - r_b2 * wp.outer(gpsi, gpsi) - r_b1 * cyl.hpsi
                            - rbvv * wp.outer(gv, gv) - rbv * cyl.hv
                            - rbpsiv * (wp.outer(gpsi, gv) + wp.outer(gv, gpsi))
                            - rb_llx * wp.outer(lam_dir, lam_dir) - rb_lx * lam_hess)
                    if rod_mean != 0:
                        # dE/dlam of each side's stretch: A's sample moves along its
                        # direction d by dR_A/dlam, changing pen (dpen/dw = -g_we) and the
                        # partition's v (dv/dw = gv); B's radius grows by dR_B/dlam
                        dwa = wp.vec3d(g_we[0], g_we[1], g_we[2])
                        dva = wp.vec3d(gwt6[0], gwt6[1], gwt6[2])
                        dlam_a += a_s * ra_l * (-wt * ph[1] * wp.dot(dwa, dirv)
                                                + ph[0] * wp.dot(dva, dirv))
                        dlam_b += a_s * wt * ph[1] * rb_l
                    # The sample's gradient and Hessian over the 16 reduced directions:
                    # E = a_s wt phi(pen) with pen = r_B - rho, its 6-space part over
                    # (w, e) carried by the reduced Jacobian J (reduce_vec, reduce_mat),
                    # then B's section directions (beta: r_B itself, gamma: psi, delta: v)
                    # and P's own second derivatives.
                    c_gg = a_s * wt * ph[2]
                    c_g = a_s * wt * ph[1]
                    c_gw = a_s * ph[1]  # on grad g grad wt^T
                    c_w = a_s * ph[0]  # on grad wt and its Hessian
                    # The Hessian's terms that carry the penalty's or the weight's first
                    # derivative (the gap's and the weight's own curvature), which the
                    # Gauss-Newton Hessian leaves out (curv = 0).
                    hc_g = curv * c_g
                    hc_gw = curv * c_gw
                    hc_w = curv * c_w
                    h6 = (c_gg * wp.outer(g_we, g_we) - hc_gw * (wp.outer(g_we, gwt6)
                                                                 + wp.outer(gwt6, g_we))
                          + hc_w * hwt6 - hc_g * h_we)
                    h = reduce_mat(h6, dp_de, dirv, 1 - rig_a)
                    jg = reduce_vec(g_we, dp_de, dirv, 1 - rig_a)
                    jq = reduce_vec(gv, dp_de, dirv, 1 - rig_a)
                    jw = reduce_vec(gwt6, dp_de, dirv, 1 - rig_a)
                    r_grad = -c_g * jg + c_w * jw
                    if rig_b == 0:
                        # pen's -1 in beta, and dpen/dgamma = -r_psi, dpen/ddelta = -r_v
                        # about the sample (r_psi = J^T grad psi, r_v = J^T grad v)
                        js = reduce_vec(gpsi, dp_de, dirv, 1 - rig_a)
                        r_grad[13] = c_g
                        for c in range(13):
                            v13 = -c_gg * jg[c] + hc_gw * jw[c]
                            h[c, 13] = h[c, 13] + v13
                            h[13, c] = h[13, c] + v13
                            h[c, 14] = h[c, 14] + hc_g * js[c]
                            h[14, c] = h[14, c] + hc_g * js[c]
                            h[c, 15] = h[c, 15] + hc_g * jq[c]
                            h[15, c] = h[15, c] + hc_g * jq[c]
                        h[13, 13] = h[13, 13] + c_gg
                    # P's own second derivatives in A's edge vector, contracted with the
                    # energy's gradient over w (linear in it: one contraction for both
                    # the penetration's and the partition's parts)
                    hra = ((ra_llx / (rest_in[ea] * rest_in[ea])) * wp.outer(ta, ta)
                           + (ra_lx / (la * rest_in[ea])) * (eye - wp.outer(ta, ta)))
                    gw = (-hc_g * wp.vec3d(g_we[0], g_we[1], g_we[2])
                          + hc_w * wp.vec3d(gwt6[0], gwt6[1], gwt6[2]))
                    row = wp.transpose(m_dir) @ gw
                    pee = (r_a * (cphi * contract(gw, fa.t1x, fa.t1y, fa.t1z)
                                  + sphi * contract(gw, fa.t2x, fa.t2y, fa.t2z))
                           + wp.outer(row, dra) + wp.outer(dra, row) + wp.dot(gw, dirv) * hra)
                    h = add_pee(h, pee, row, 1 - rig_a)
                    # The sample's gradient and Hessian carried from the 16 reduced
                    # directions to the pass's dofs (the section directions: alpha by
                    # (1 - u) and u Q to A's vertices, beta and gamma by (1 - v) and v Q,
                    # delta by -1 and Q to B's), added to the registers above.
                    qa = turn_modes(ba, turn_ac, turn_as, k, 0)
                    qb = turn_modes(bb, turn_bc, turn_bs, k, 0)
                    qs = turn_modes(bpsi1, turn_bc, turn_bs, k, 0)
                    one_u = f64(1.0) - u
                    one_v = f64(1.0) - v
                    wa0 = one_u * ba
                    wa1 = u * qa
                    x0 = one_v * bb
                    y0 = one_v * bpsi1
                    x1 = v * qb
                    y1 = v * qs
                    for i in range(12):
                        grad_out[go + i] = grad_out[go + i] + r_grad[i]
                        for j in range(12):
                            if j >= i:
                                h_xx[i, j] = h_xx[i, j] + h[i, j]
                            else:
                                h_xx[i, j] = h_xx[i, j] + h[j, i]
                    # B's neighbour chords f0 = x_B0 - x_Bprev and f1 = x_Bnext - x_B1 (the
                    # weight alone depends on them): their rows against the reduced
                    # directions and among themselves, carried to the coordinates (rows
                    # 12..14: x_Bprev, 15..17: x_Bnext) with f's signs (chord_target).
                    for i in range(6):
                        row6 = vec6d()
                        for j in range(6):
                            row6[j] = hc_w * hwtf[i, j] - hc_gw * gwtf[i] * g_we[j]
                        fr = reduce_vec(row6, dp_de, dirv, 1 - rig_a)
                        fb13 = hc_gw * gwtf[i]
                        for side in range(2):
                            tgt, sg = chord_target(i, side)
                            grad_out[go + local_coordinate(tgt, k)] = (
                                grad_out[go + local_coordinate(tgt, k)] + sg * c_w * gwtf[i])
                            for c in range(12):
                                h_xx[tgt, c] = h_xx[tgt, c] + sg * fr[c]
                                h_xx[c, tgt] = h_xx[c, tgt] + sg * fr[c]
                            for j in range(6):
                                for side2 in range(2):
                                    tgt2, sg2 = chord_target(j, side2)
                                    h_xx[tgt, tgt2] = h_xx[tgt, tgt2] + sg * sg2 * hc_w * hwff[i, j]
                            if rig_a == 0:
                                for j in range(k):
                                    h_xa0[tgt, j] = h_xa0[tgt, j] + sg * fr[12] * wa0[j]
                                    h_xa1[tgt, j] = h_xa1[tgt, j] + sg * fr[12] * wa1[j]
                            if rig_b == 0:
                                for j in range(k):
                                    h_xb0[tgt, j] = h_xb0[tgt, j] + sg * fb13 * x0[j]
                                    h_xb1[tgt, j] = h_xb1[tgt, j] + sg * fb13 * x1[j]
                    if rig_a == 0:
                        for j in range(k):
                            grad_out[go + 12 + j] = grad_out[go + 12 + j] + r_grad[12] * wa0[j]
                            grad_out[go + 12 + k + j] = (grad_out[go + 12 + k + j]
                                                         + r_grad[12] * wa1[j])
                        for i in range(12):
                            cxa = h[i, 12]
                            for j in range(k):
                                h_xa0[i, j] = h_xa0[i, j] + cxa * wa0[j]
                                h_xa1[i, j] = h_xa1[i, j] + cxa * wa1[j]
                        caa = h[12, 12]
                        for i in range(k):
                            for j in range(k):
                                h_a0a1[i, j] = h_a0a1[i, j] + caa * wa0[i] * wa1[j]
                                if j >= i:
                                    h_a0a0[i, j] = h_a0a0[i, j] + caa * wa0[i] * wa0[j]
                                    h_a1a1[i, j] = h_a1a1[i, j] + caa * wa1[i] * wa1[j]
                    if rig_b == 0:
                        for j in range(k):
                            grad_out[go + 12 + 2 * k + j] = (grad_out[go + 12 + 2 * k + j]
                                                             + r_grad[13] * x0[j])
                            grad_out[go + 12 + 3 * k + j] = (grad_out[go + 12 + 3 * k + j]
                                                             + r_grad[13] * x1[j])
                        for i in range(12):
                            hb_i = h[i, 13]
                            hg_i = h[i, 14]
                            hd_i = h[i, 15]
                            for j in range(k):
                                h_xb0[i, j] = (h_xb0[i, j] + hb_i * x0[j] + hg_i * y0[j]
                                               - hd_i * bb[j])
                                h_xb1[i, j] = (h_xb1[i, j] + hb_i * x1[j] + hg_i * y1[j]
                                               + hd_i * qb[j])
                        for i in range(k):
                            # B's rows in (beta, gamma, delta), times h_BB
                            p0 = h[13, 13] * x0[i] + h[14, 13] * y0[i] - h[15, 13] * bb[i]
                            q0 = h[13, 14] * x0[i] + h[14, 14] * y0[i] - h[15, 14] * bb[i]
                            s0 = h[13, 15] * x0[i] + h[14, 15] * y0[i] - h[15, 15] * bb[i]
                            p1 = h[13, 13] * x1[i] + h[14, 13] * y1[i] + h[15, 13] * qb[i]
                            q1 = h[13, 14] * x1[i] + h[14, 14] * y1[i] + h[15, 14] * qb[i]
                            s1 = h[13, 15] * x1[i] + h[14, 15] * y1[i] + h[15, 15] * qb[i]
                            for j in range(k):
                                h_b0b1[i, j] = h_b0b1[i, j] + p0 * x1[j] + q0 * y1[j] + s0 * qb[j]
                                if j >= i:
                                    h_b0b0[i, j] = (h_b0b0[i, j] + p0 * x0[j] + q0 * y0[j]
                                                    - s0 * bb[j])
                                    h_b1b1[i, j] = (h_b1b1[i, j] + p1 * x1[j] + q1 * y1[j]
                                                    + s1 * qb[j])
                        if rig_a == 0:
                            rb = h[12, 13]
                            rg = h[12, 14]
                            rd = h[12, 15]
                            t0 = rb * x0 + rg * y0 - rd * bb
                            t1 = rb * x1 + rg * y1 + rd * qb
                            for i in range(k):
                                for j in range(k):
                                    h_a0b0[i, j] = h_a0b0[i, j] + wa0[i] * t0[j]
                                    h_a0b1[i, j] = h_a0b1[i, j] + wa0[i] * t1[j]
                                    h_a1b0[i, j] = h_a1b0[i, j] + wa1[i] * t0[j]
                                    h_a1b1[i, j] = h_a1b1[i, j] + wa1[i] * t1[j]
                    # The mean radii's second derivatives (the oracle's _radius_second),
                    # gathered as sums over the samples and added per Gauss circle (A's)
                    # and per pass (B's): R = sqrt(S(lam) - |c|^2 / 2) has R_cc = -I / (2 R)
                    # - c c^T / (4 R^3) and R_clam = c R_lam / (2 R^2). A's c is the
                    # circle's; B's c(v) = (1 - v) c_B0 + v c_B1' spans two vectors, and
                    # R_cc dc/dv = z = -dc / (2 R) - (c . dc) c / (4 R^3) three (dc_b, c_B0,
                    # c_B1'), so sums of moments in v carry them.
                    hit = 1
                    if rig_a == 0 and gauss_newton == 0:
                        ga_sum += r_grad[12]
                    if rig_b == 0:
                        al = hc_g / (f64(2.0) * rb_mean)
                        be = hc_g / (f64(4.0) * rb_mean * rb_mean * rb_mean)
                        ga = hc_g * rb_lx / (f64(2.0) * rb_mean * rb_mean)
                        mv = wp.vec3d(one_v * one_v, one_v * v, v * v)
                        mom_a = mom_a + al * mv
                        mom_g = mom_g + ga * mv
                        w4 = one_v * one_v
                        w4 = w4 * w4
                        mom_b[0] = mom_b[0] + be * w4
                        mom_b[1] = mom_b[1] + be * one_v * one_v * one_v * v
                        mom_b[2] = mom_b[2] + be * one_v * one_v * v * v
                        mom_b[3] = mom_b[3] + be * one_v * v * v * v
                        mom_b[4] = mom_b[4] + be * v * v * v * v
                        # z's coordinates on (dc_b, c_B0, c_B1') times c_g, for the two
                        # vertices' weights (1 - v), v
                        cdc = wp.dot(cb, dcb) / (f64(4.0) * rb_mean * rb_mean * rb_mean)
                        zc = wp.vec3d(-f64(1.0) / (f64(2.0) * rb_mean), -cdc * one_v, -cdc * v)
                        for q in range(3):
                            for i in range(12):
                                zx[i, q] = zx[i, q] + hc_g * one_v * zc[q] * jq[i]
                                zx[i, 3 + q] = zx[i, 3 + q] + hc_g * v * zc[q] * jq[i]
                            if rig_a == 0:
                                for j in range(k):
                                    za[q, j] = za[q, j] + hc_g * jq[12] * one_v * zc[q] * ba[j]
                                    za[3 + q, j] = (za[3 + q, j]
                                                    + hc_g * jq[12] * v * zc[q] * ba[j])
                    touched = 1
            if wp.static(derivatives):
                if hit != 0:
                    # this circle's sums (A's radius and the v terms against A's direction)
                    one_u = f64(1.0) - u
                    if rig_a == 0:
                        qca = turn_modes(ca, turn_ac, turn_as, k, 0)
                        h_a0a0, h_a0a1, h_a1a1 = radius_cc(h_a0a0, h_a0a1, h_a1a1, ga_sum, ca, qca,
                                                           ra_mean, one_u, u, turn_ac, turn_as, k)
                        ra_lx = ra_l
                        if rod_mean != 0:
                            ra_lx = f64(0.0)
                        wla = (ga_sum * ra_lx / (f64(2.0) * ra_mean * ra_mean)) * ca
                        qwla = turn_modes(wla, turn_ac, turn_as, k, 0)
                        for r in range(3):
                            dl = ta[r] / rest_in[ea]
                            for j in range(k):
                                h_xa0[r, j] = h_xa0[r, j] - dl * one_u * wla[j]
                                h_xa0[3 + r, j] = h_xa0[3 + r, j] + dl * one_u * wla[j]
                                h_xa1[r, j] = h_xa1[r, j] - dl * u * qwla[j]
                                h_xa1[3 + r, j] = h_xa1[3 + r, j] + dl * u * qwla[j]
                    if rig_a == 0 and rig_b == 0:
                        for q in range(3):
                            zv = b_moment_row(q, dcb, cb0, cb1)
                            qzv = turn_modes(zv, turn_bc, turn_bs, k, 0)
                            y0 = vecKd()
                            y1 = vecKd()
                            for j in range(k):
                                y0[j] = za[q, j]
                                y1[j] = za[3 + q, j]
                            qy0 = turn_modes(y0, turn_ac, turn_as, k, 0)
                            qy1 = turn_modes(y1, turn_ac, turn_as, k, 0)
                            for i in range(k):
                                for j in range(k):
                                    h_a0b0[i, j] = h_a0b0[i, j] + one_u * y0[i] * zv[j]
                                    h_a1b0[i, j] = h_a1b0[i, j] + u * qy0[i] * zv[j]
                                    h_a0b1[i, j] = h_a0b1[i, j] + one_u * y1[i] * qzv[j]
                                    h_a1b1[i, j] = h_a1b1[i, j] + u * qy1[i] * qzv[j]
        if wp.static(derivatives):
            if rig_b == 0 and touched != 0:
                # B's sums over the pass: R_cc on its coefficients, R_clam against its
                # stretch, z against the positions (through v)
                qcb0 = turn_modes(cb0, turn_bc, turn_bs, k, 0)
                qcb1 = turn_modes(cb1, turn_bc, turn_bs, k, 0)
                h_b0b0, h_b0b1, h_b1b1 = radius_moments(h_b0b0, h_b0b1, h_b1b1, mom_a, mom_b,
                                                        cb0, cb1, qcb0, qcb1, turn_bc,
                                                        turn_bs, k)
                wl0 = mom_g[0] * cb0 + mom_g[1] * cb1
                wl1 = turn_modes(mom_g[1] * cb0 + mom_g[2] * cb1, turn_bc, turn_bs, k, 0)
                for r in range(3):
                    dl = tb[r] / rest_in[eb]
                    for j in range(k):
                        h_xb0[6 + r, j] = h_xb0[6 + r, j] - dl * wl0[j]
                        h_xb0[9 + r, j] = h_xb0[9 + r, j] + dl * wl0[j]
                        h_xb1[6 + r, j] = h_xb1[6 + r, j] - dl * wl1[j]
                        h_xb1[9 + r, j] = h_xb1[9 + r, j] + dl * wl1[j]
                for q in range(3):
                    zv = b_moment_row(q, dcb, cb0, cb1)
                    qzv = turn_modes(zv, turn_bc, turn_bs, k, 0)
                    for i in range(12):
                        for j in range(k):
                            h_xb0[i, j] = h_xb0[i, j] + zx[i, q] * zv[j]
                            h_xb1[i, j] = h_xb1[i, j] + zx[i, 3 + q] * qzv[j]
            if touched != 0:
                pair = tid // 2
                flip = tid % 2
                bsz = 3 + k
                for n in range(6):
                    for m in range(6):
                        base = _slot_base(slots_in, pair, flip, n, m, bsz)
                        for r in range(3):
                            for c in range(3):
                                wp.atomic_add(blocks_out, base + r * bsz + c,
                                              h_xx[3 * n + r, 3 * m + c])
                # each deformable side's coefficients against the coordinates and among
                # themselves, then A's against B's
                if rig_a == 0:
                    scatter_side(blocks_out, slots_in, pair, flip, bsz, k, 0, h_xa0, h_xa1,
                                 h_a0a0, h_a1a1, h_a0a1)
                if rig_b == 0:
                    scatter_side(blocks_out, slots_in, pair, flip, bsz, k, 2, h_xb0, h_xb1,
                                 h_b0b0, h_b1b1, h_b0b1)
                if rig_a == 0 and rig_b == 0:
                    scatter_coeff(blocks_out, slots_in, pair, flip, bsz, k, 0, 2, h_a0b0, 0)
                    scatter_coeff(blocks_out, slots_in, pair, flip, bsz, k, 0, 3, h_a0b1, 0)
                    scatter_coeff(blocks_out, slots_in, pair, flip, bsz, k, 1, 2, h_a1b0, 0)
                    scatter_coeff(blocks_out, slots_in, pair, flip, bsz, k, 1, 3, h_a1b1, 0)
            if touched != 0:
                # The pass's second derivatives against each side's end twist m (the
                # reference twist that turns the side's second vertex's coefficients into
                # its edge's frame): the energy sees m and c_1 only through Q^T(m) c_1, so
                # d/dm = grad_c1 . (n J c_1) and d2/(dm dy) = H[y, c_1] n J c_1, plus
                # (n J)^T grad_c1 on c_1's own rows (the host's chain rule through m(x)).
                to = tid * 2 * nl
                if rig_a == 0:
                    twist_column(twist_col_out, to, grad_out, go + 12 + k,
                                 turn_direction(load_section(coeff_in, vertex_offset[va[1]], k),
                                                k),
                                 k, 1, h_xa1, h_a0a1, h_a1a1, h_a1b0, h_a1b1)
                if rig_b == 0:
                    twist_column(twist_col_out, to + nl, grad_out, go + 12 + 3 * k,
                                 turn_direction(load_section(coeff_in, vertex_offset[vb[1]], k),
                                                k),
                                 k, 3, h_xb1, h_a0b1, h_a1b1, h_b0b1, h_b1b1)
        if wp.static(derivatives):
            if rod_mean != 0:
                dlam_out[2 * tid] = dlam_a
                dlam_out[2 * tid + 1] = dlam_b
        energy_out[tid] = energy

    key = f"sectioned_pass_d{int(derivatives)}_r{int(report)}"
    return wp.Kernel(sectioned_pass, key=key, module=wp.get_module(__name__))


@wp.func
def _slot_base(slots: wp.array(dtype=wp.int32), pair: int, flip: int, n: int, m: int,
               bsz: int) -> int:
    """Offset of the node-pair block (pass nodes n, m: A0, A1, B0, B1, Bprev, Bnext) in the
    blocks: pass ``flip`` of pair p has its 36 blocks at ``slots[72 p + 36 flip + 6 n +
    m]`` (pass 1 takes A = b)."""
    return slots[pair * 72 + flip * 36 + n * 6 + m] * bsz * bsz


@wp.func
def scatter_x_coeff(blocks: wp.array(dtype=wp.float64), slots: wp.array(dtype=wp.int32),
                    pair: int, flip: int, bsz: int, k: int, m: int, hx: mat18xKd):
    """Add the coordinates' rows against node m's coefficients (``hx``, 18 x k) into the
    node-pair blocks (n, m), and their transposes into (m, n), for the six nodes n."""
    for n in range(6):
        base = _slot_base(slots, pair, flip, n, m, bsz)
        base_t = _slot_base(slots, pair, flip, m, n, bsz)
        for r in range(3):
            for j in range(k):
                val = hx[3 * n + r, j]
                wp.atomic_add(blocks, base + r * bsz + 3 + j, val)
                wp.atomic_add(blocks, base_t + (3 + j) * bsz + r, val)


@wp.func
def scatter_side(blocks: wp.array(dtype=wp.float64), slots: wp.array(dtype=wp.int32),
                 pair: int, flip: int, bsz: int, k: int, first: int, hx0: mat18xKd,
                 hx1: mat18xKd, h00: matKd, h11: matKd, h01: matKd):
    """Add one side's coefficient blocks (its vertices: nodes ``first`` and ``first`` + 1):
    against the coordinates (``hx0``, ``hx1``), its two diagonal blocks (upper triangles
    ``h00``, ``h11``) and the block between its vertices (``h01``)."""
    scatter_x_coeff(blocks, slots, pair, flip, bsz, k, first, hx0)
    scatter_x_coeff(blocks, slots, pair, flip, bsz, k, first + 1, hx1)
    scatter_coeff(blocks, slots, pair, flip, bsz, k, first, first, h00, 1)
    scatter_coeff(blocks, slots, pair, flip, bsz, k, first + 1, first + 1, h11, 1)
    scatter_coeff(blocks, slots, pair, flip, bsz, k, first, first + 1, h01, 0)


@wp.func
def scatter_coeff(blocks: wp.array(dtype=wp.float64), slots: wp.array(dtype=wp.int32),
                  pair: int, flip: int, bsz: int, k: int, n: int, m: int, hc: matKd,
                  upper: int):
    """Add the coefficients' block of nodes (n, m) (``hc``, k x k; ``upper``: a diagonal
    block held as its upper triangle) into the node-pair block (n, m), and, for n != m,
    its transpose into (m, n)."""
    base = _slot_base(slots, pair, flip, n, m, bsz)
    if upper != 0:
        for i in range(k):
            for j in range(k):
                val = hc[i, j]
                if j < i:
                    val = hc[j, i]
                wp.atomic_add(blocks, base + (3 + i) * bsz + 3 + j, val)
        return
    base_t = _slot_base(slots, pair, flip, m, n, bsz)
    for i in range(k):
        for j in range(k):
            val = hc[i, j]
            wp.atomic_add(blocks, base + (3 + i) * bsz + 3 + j, val)
            wp.atomic_add(blocks, base_t + (3 + j) * bsz + 3 + i, val)


@wp.kernel
def section_bounds(
    edge_vertex: wp.array(dtype=wp.vec2i),
    vertex_offset: wp.array(dtype=wp.int32),
    edge_r0: wp.array(dtype=wp.float64),
    edge_nu: wp.array(dtype=wp.float64),
    edge_rigid: wp.array(dtype=wp.int32),
    coeff_count: int,
    rod_mean: int,
    x_in: wp.array(dtype=wp.vec3d),
    coeff_in: wp.array(dtype=wp.float64),
    rest_in: wp.array(dtype=wp.float64),
    lam_in: wp.array(dtype=wp.float64),
    amp_out: wp.array(dtype=wp.float64),
    rbase_out: wp.array(dtype=wp.float64),
):
    """The pass kernels' bounds on the boundaries, once per state: each vertex's modes'
    amplitude sum [m] (threads 0 .. V - 1) and each edge's largest mean radius
    r0 lam^-nu [m] (threads V .. V + E - 1; r0 for a rigid section)."""
    tid = wp.tid()
    nv = amp_out.shape[0]
    if tid < nv:
        amp_out[tid] = amplitude_sum(load_section(coeff_in, vertex_offset[tid], coeff_count),
                                     coeff_count)
        return
    e = tid - nv
    if edge_rigid[e] != 0:
        rbase_out[e] = edge_r0[e]
        return
    ev = edge_vertex[e]
    lam = wp.length(x_in[ev[1]] - x_in[ev[0]]) / rest_in[e]
    if rod_mean != 0:
        lam = lam_in[e]
    rbase_out[e] = edge_r0[e] * wp.pow(lam, -edge_nu[e])


@wp.kernel
def sample_directions(samples: int, cos_out: wp.array(dtype=wp.float64),
                      sin_out: wp.array(dtype=wp.float64)):
    """cos and sin of the boundary samples' angles phi_k = 2 pi (k + 1/2) / M (the pass
    kernels read them, so that each pass does not evaluate them again)."""
    kk = wp.tid()
    phi = f64(TWO_PI) * (f64(kk) + f64(0.5)) / f64(samples)
    cos_out[kk] = wp.cos(phi)
    sin_out[kk] = wp.sin(phi)


#: The variants: energy only, energy with derivatives, energy with the samples' report.
ENERGY = make_pass_kernel(False, False)
DERIVATIVES = make_pass_kernel(True, False)
REPORT = make_pass_kernel(False, True)
