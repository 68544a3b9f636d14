"""The contact law of one pair of Gauss points, as Warp functions, with its derivatives.

For an edge pair (a, b) and Gauss points g on a, h on b at distance rho (see
:mod:`tightknot.contact.law` for the derivation of the kernels),

    Psi(s, R, q) = (1 - xi(q)) A_l R^k_l T_l(rho/R) + xi(q) sqrt(1 - q) A_p R^k_p T_p(rho/R)
                   + b(s),   s = rho^2,

with T_l, T_p the tabulated Abel and radial inverses of the line and point laws (cubic
splines, C2), R = r_a + r_b the contact radius, q = cos^2 of the edges' angle, xi the C2
line-to-point blend by angle (Meier et al. 2016) and b the hard core's barrier (Li et al.
2020, eq. 6). The laws are weighted by W_excl, a C2 ramp of the arc-length separation (the
exclusion window). Each function returns the value with its first and second derivatives
in (s, R, q): the chain rule to the vertices is :mod:`tightknot.contact.pair_assembly`.
"""

from __future__ import annotations

import math

import warp as wp

from tightknot.contact.broad_phase import arc_separation
from tightknot.contact.law import TABLE_INTERVALS, U_MIN, RadialComplianceLaw, kernel_table
from tightknot.contact.settings import ContactSettings

f64 = wp.float64
HALF_PI = wp.constant(wp.float64(1.5707963267948966))


@wp.struct
class PairLaw:
    """The law's parameters and tables, with the layer's settings that shape it."""

    line_coefficient: wp.float64
    """k_line of the line law f/(E D) = k (w/D)^p [-]."""
    line_exponent: wp.float64
    """m_l = p_line + 1, the exponent of the line energy in the overlap [-]."""
    point_coefficient: wp.float64
    """k_point of the point law F/(E D^2) = k (w/D)^p [-]."""
    point_exponent: wp.float64
    """m_p = p_point + 1 [-]."""
    q_line: wp.float64
    """cos^2 of the crossing angle below which the contact is a line contact [-]."""
    q_point: wp.float64
    """cos^2 of the crossing angle above which it is a point contact [-]."""
    hard_relative: wp.float64
    """The barrier's divergence over R [-] (0: the absolute floor only)."""
    core_fraction: wp.float64
    """Start of the barrier over R [-]."""
    local_core_fraction: wp.float64
    """Start of the local-thickness barrier over the chord of the tightest bend [-]."""
    hard_fraction: wp.float64
    """Hard limit of the step bound over the rest contact radius [-]."""
    core_stiffness: wp.float64
    """The barrier's stiffness over E/D [-]."""
    candidate_window: wp.float64
    """Pairs of one rod closer along it than this times the exclusion window are off [-]."""
    table_u0: wp.float64
    """First abscissa u = rho/R of the tables [-]."""
    table_du: wp.float64
    """Interval of the tables in u [-]."""
    line_table: wp.array2d(dtype=wp.float64)
    """Cubic pieces (a, b, c, d) of T_l, shape (TABLE_INTERVALS, 4)."""
    point_table: wp.array2d(dtype=wp.float64)
    """Cubic pieces of T_p, shape (TABLE_INTERVALS, 4)."""


def pair_law(law: RadialComplianceLaw, settings: ContactSettings, device: str) -> PairLaw:
    """The :class:`PairLaw` of ``law`` under ``settings`` on ``device``."""
    out = PairLaw()
    out.line_coefficient = law.k_line
    out.line_exponent = law.p_line + 1.0
    out.point_coefficient = law.k_point
    out.point_exponent = law.p_point + 1.0
    out.q_line = math.cos(math.radians(law.angle_line_deg)) ** 2
    out.q_point = math.cos(math.radians(law.angle_point_deg)) ** 2
    out.hard_relative = settings.hard_relative
    out.core_fraction = settings.core_fraction
    # The local barrier starts at most at 0.7 of the chord (see local_barrier).
    out.local_core_fraction = min(settings.core_fraction, 0.7)
    out.hard_fraction = settings.hard_fraction
    out.core_stiffness = settings.core_stiffness
    out.candidate_window = settings.candidate_window
    out.table_u0 = U_MIN
    out.table_du = (1.0 - U_MIN) / TABLE_INTERVALS
    out.line_table = wp.array(kernel_table("line", law.p_line + 1.0, law.onset_band),
                              dtype=f64, device=device)
    out.point_table = wp.array(kernel_table("point", law.p_point + 1.0, law.onset_band),
                               dtype=f64, device=device)
    return out


@wp.struct
class LawAmplitudes:
    """The pair's kernel amplitudes: f = rk T(rho/R) with rk = A R^k."""

    line_rk: wp.float64
    """A_l R^k_l [J/m^2]."""
    line_k: wp.float64
    """k_l = m_l - 1 [-]."""
    point_rk: wp.float64
    """A_p R^k_p [J/m^2]."""
    point_k: wp.float64
    """k_p = m_p - 2 [-]."""


@wp.struct
class LawBlend:
    """Weights of the line and point kernels in q and their q-derivatives."""

    xi: wp.float64
    """The blend xi(q): 1 (point) for q <= q_point, 0 (line) for q >= q_line."""
    line: wp.float64
    """1 - xi."""
    line_q: wp.float64
    line_qq: wp.float64
    point: wp.float64
    """xi sqrt(1 - q) (the point law's pair weight sin(phi), law docstring)."""
    point_q: wp.float64
    point_qq: wp.float64


@wp.struct
class PsiDerivatives:
    """First and second derivatives of Psi(s, R, q) [J/m^2 over the units of s, R, q]."""

    s: wp.float64
    R: wp.float64
    q: wp.float64
    ss: wp.float64
    sR: wp.float64
    RR: wp.float64
    sq: wp.float64
    Rq: wp.float64
    qq: wp.float64


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
def pair_barrier(law: PairLaw, rho: wp.float64, R: wp.float64, rho_hard: wp.float64,
                 g_sep: wp.float64, kcore: wp.float64) -> wp.mat33d:
    """The hard core of a Gauss pair (see :func:`hard_core`), or its local-thickness form
    for points of one rod less than a quarter turn of the tightest bend apart."""
    if g_sep < f64(1.0):
        # Local thickness: two points an arc sep apart on a bend of the tightest legal
        # radius D/2 are a chord D sin(sep/D) apart; closer than local_core_fraction of
        # that (with R for D), the rod folds onto itself inside the exclusion window, where
        # the law is off: the barrier stops the fold.
        return hard_core(rho, R, rho_hard, f64(0.0), law.local_core_fraction * g_sep, kcore)
    return hard_core(rho, R, rho_hard, law.hard_relative, law.core_fraction, kcore)


@wp.func
def barrier_in_s(hb: wp.mat33d, rho: wp.float64, s: wp.float64) -> wp.vec3d:
    """The barrier in s = rho^2: (b, b_s, b_ss), b_s = b_rho/(2 rho),
    b_ss = (b_rhorho - b_rho/rho)/(4 s)."""
    return wp.vec3d(hb[0, 0], hb[0, 1] * f64(0.5) / rho,
                    (hb[0, 2] - hb[0, 1] / rho) / (f64(4.0) * s))


@wp.func
def exclusion_weight(same_rod: int, closed: int, rod_length: wp.float64, arc_a: wp.vec2d,
                     arc_b: wp.vec2d, exclusion: wp.float64, d0: wp.float64,
                     candidate_window: wp.float64, xg: wp.float64, xh: wp.float64
                     ) -> wp.vec3d:
    """(W_excl, g_sep, skip) of the Gauss pair at (xg, xh) on edges with rest arcs
    ``arc_a``, ``arc_b`` [m]: the exclusion ramp (a C2 ramp over a quarter window past the
    window ``exclusion``), sin of the separation over the rest contact radius ``d0``
    (capped at pi/2: the local barrier's chord, see :func:`pair_barrier`), and 1 for a
    pair inside the candidate window (neither the law nor the local barrier acts)."""
    if same_rod == 0:
        return wp.vec3d(f64(1.0), f64(1.0), f64(0.0))
    sa = arc_a[0] + xg * (arc_a[1] - arc_a[0])
    sb = arc_b[0] + xh * (arc_b[1] - arc_b[0])
    sep = arc_separation(sa, sb, same_rod, closed, rod_length)
    wex = smooth_ramp((sep - exclusion) / (f64(0.25) * exclusion))[0]
    g_sep = wp.sin(wp.min(sep / d0, HALF_PI))
    skip = f64(0.0)
    if wex <= f64(0.0) and sep < candidate_window * exclusion:
        skip = f64(1.0)
    return wp.vec3d(wex, g_sep, skip)


@wp.func
def law_amplitudes(law: PairLaw, emod: wp.float64, d0: wp.float64, R: wp.float64
                   ) -> LawAmplitudes:
    """Amplitudes A R^k of the pair's kernels from the rest contact radius D = ``d0`` [m],
    the harmonic-mean modulus ``emod`` [Pa] and the contact radius ``R`` [m]: e_line =
    K_l delta^m_l with K_l = 2 k E D^2 (2D)^-m/m (law docstring), likewise K_p; kernels
    line (Abel inverse) A = K m/pi, k = m - 1; point (radial inverse) A = K m/(2 pi),
    k = m - 2."""
    m_l = law.line_exponent
    m_p = law.point_exponent
    two_d = f64(2.0) * d0
    K_l = f64(2.0) * law.line_coefficient * emod * d0 * d0 * wp.pow(two_d, -m_l) / m_l
    K_p = f64(2.0) * law.point_coefficient * emod * d0 * d0 * d0 * wp.pow(two_d, -m_p) / m_p
    A_l = K_l * m_l / f64(3.141592653589793)
    A_p = K_p * m_p / (f64(2.0) * f64(3.141592653589793))
    out = LawAmplitudes()
    out.line_k = m_l - f64(1.0)
    out.point_k = m_p - f64(2.0)
    out.line_rk = A_l * wp.pow(R, out.line_k)
    out.point_rk = A_p * wp.pow(R, out.point_k)
    return out


@wp.func
def law_blend(law: PairLaw, q: wp.float64) -> LawBlend:
    """The line/point blend at q = cos^2 of the edges' angle."""
    sv = smooth_ramp((law.q_line - q) / (law.q_line - law.q_point))
    inv_dq = f64(-1.0) / (law.q_line - law.q_point)
    out = LawBlend()
    xi = sv[0]
    xi1 = sv[1] * inv_dq
    xi2 = sv[2] * inv_dq * inv_dq
    out.xi = xi
    out.line = f64(1.0) - xi
    out.line_q = -xi1
    out.line_qq = -xi2
    if xi > f64(0.0):
        # sqrt(1 - q) is smooth where xi > 0 (q <= q_line < 1).
        sn = wp.sqrt(wp.max(f64(1.0) - q, f64(0.0)))
        s1 = -f64(0.5) / sn
        s2 = -f64(0.25) / (sn * sn * sn)
        out.point = xi * sn
        out.point_q = xi1 * sn + xi * s1
        out.point_qq = xi2 * sn + f64(2.0) * xi1 * s1 + xi * s2
    return out


@wp.func
def law_kernels(law: PairLaw, amp: LawAmplitudes, use_line: int, use_point: int,
                wex: wp.float64, R: wp.float64, u: wp.float64):
    """The line and point kernels at u = rho/R with their derivatives (see
    :func:`scaled_kernel`), weighted by the exclusion ramp ``wex`` (zero inside the window)
    and zero for a law the blend does not use."""
    Fl = wp.mat33d()
    Fp = wp.mat33d()
    if wex > f64(0.0):
        if use_line != 0:
            Fl = wex * scaled_kernel(table_eval(law.line_table, law.table_u0, law.table_du,
                                                u), amp.line_rk, amp.line_k, R, u)
        if use_point != 0:
            Fp = wex * scaled_kernel(table_eval(law.point_table, law.table_u0, law.table_du,
                                                u), amp.point_rk, amp.point_k, R, u)
    return Fl, Fp


@wp.func
def psi_value(bl: LawBlend, Fl: wp.mat33d, Fp: wp.mat33d, bv: wp.vec3d) -> wp.float64:
    """Psi [J/m^2]: the blended kernels plus the barrier."""
    return bl.line * Fl[0, 0] + bl.point * Fp[0, 0] + bv[0]


@wp.func
def psi_derivatives(bl: LawBlend, Fl: wp.mat33d, Fp: wp.mat33d, hb: wp.mat33d,
                    bv: wp.vec3d, rho: wp.float64, s: wp.float64) -> PsiDerivatives:
    """Derivatives of Psi in (s, R, q), from those of the kernels in rho: f_s =
    f_rho/(2 rho), f_ss = (f_rhorho - f_rho/rho)/(4 rho^2), f_sR = f_rhoR/(2 rho)."""
    A = bl.line
    B = bl.point
    inv2r = f64(0.5) / rho
    Ls = Fl[0, 1] * inv2r
    Lss = (Fl[1, 0] - Fl[0, 1] / rho) / (f64(4.0) * s)
    LsR = Fl[1, 1] * inv2r
    Qs = Fp[0, 1] * inv2r
    Qss = (Fp[1, 0] - Fp[0, 1] / rho) / (f64(4.0) * s)
    QsR = Fp[1, 1] * inv2r
    out = PsiDerivatives()
    out.s = A * Ls + B * Qs + bv[1]
    out.R = A * Fl[0, 2] + B * Fp[0, 2] + hb[1, 0]
    out.ss = A * Lss + B * Qss + bv[2]
    out.sR = A * LsR + B * QsR + hb[1, 1] * f64(0.5) / rho
    out.RR = A * Fl[1, 2] + B * Fp[1, 2] + hb[1, 2]
    out.q = bl.line_q * Fl[0, 0] + bl.point_q * Fp[0, 0]
    out.qq = bl.line_qq * Fl[0, 0] + bl.point_qq * Fp[0, 0]
    out.sq = bl.line_q * Ls + bl.point_q * Qs
    out.Rq = bl.line_q * Fl[0, 2] + bl.point_q * Fp[0, 2]
    return out
