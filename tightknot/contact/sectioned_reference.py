"""The sectioned level's contact between two deformed sections, in NumPy: the slow, obvious
oracle of the Warp kernel (:mod:`tightknot.contact.sectioned_kernels`).

The section is a field along the rod, carried by its vertices: vertex v's boundary radius
r(phi) = R + sum_{n=2..N} (a_n cos n phi + b_n sin n phi) (docs/sectioned_level.md) has its
coefficients c_v = (a_2, b_2, ..., a_N, b_N) in the frame of the edge that starts at v (the
edge that ends at v for the last vertex of an open rod). Along an edge the coefficients are
interpolated linearly between its two vertices, c(u) = (1 - u) c_0 + u Q^T c_1, where Q
rotates each mode n by n m, m the reference twist between the edge's frame and the next
edge's (the frame c_1 is stored in; an input here: the level turns it with the positions,
:mod:`tightknot.contact.section_twist`),
so that a section deformed along a contact varies continuously, as in the solid. The mean
radius follows from the area, R^2 = r0^2 lambda^(-2 nu) - (1/2) |c(u)|^2 (Parseval; the
area thins as lambda^(-2 nu) with the edge's stretch lambda, nu = 1/2 for the
incompressible solid). The frame (d1, d2) of an edge is its reference frame carried by
time-parallel transport from the last accepted state (Bergou et al. 2010 sec. 4.1), a
smooth function of the edge vector within a Newton iteration: d1 = P(t_ref -> t) d1_ref
with P v = c v + b x v + (b.v) b / (1 + c), b = t_ref x t, c = t_ref . t (Rodrigues'
formula of the rotation taking t_ref onto t).

Contact of a pair (a, b) is a penalty on the penetration of sampled boundary points of each
section into the other's surface (two passes, each at half weight). A sample of a, at
Gauss point u on its axis and angle phi in its frame, is

    P = x_a0 + u e_a + r_a(u, phi) (cos phi d1_a + sin phi d2_a);

its gap to b's surface is g = rho - r_b(v, psi), rho the distance of P to b's axis line, v
the projection of P on that axis (v in [0, 1] on the edge) and psi the angle of P about it
in b's frame (a radial gap of a star-shaped section). The sample is weighed by omega(P) of
a partition of unity over b's rod (:func:`partition`), so that the partner's surface passes
from edge to edge without a jump where the axis bends. It is built on the bisector planes
of b's vertices: at b's vertex x_0 the plane normal to the central chord
c_0 = x_1 - x_prev (x_prev the vertex before x_0 on b's rod), at x_1 the one normal to
c_1 = x_next - x_0, and s_i = 2 (P - x_i) . c_i / |c_i|^2 the scaled signed distance of P
from plane i (s_0 = v and s_1 = v - 1 along a straight partner of equal edges). Then
omega = S(s_0 + 1/2) - S(s_1 + 1/2), S the quintic step (S(2 s_0 + 1) on the first edge of
an open rod, S(2 s_1) on the last: its surface fades over half an edge past the end), and
0 where that difference is not positive (beyond the line where the two planes cross, near
the partner's centre of curvature). Consecutive edges share a vertex and its chord, so
their terms cancel in the sum over the edges about P, which is 1 for any bend and any edge
lengths while P is well within a radius of curvature 1 / kappa of the axis (rho kappa up to
0.7 with kappa the largest over the edges that weigh P: a point far from the axis is
weighed over about 1 / (1 - rho kappa) edges; nearer the centre the planes of consecutive
vertices cross). Parts of the rod that curl back towards P from beyond their own centre of
curvature can add weight there, never where P is in contact with them. Along a straight
partner of equal edges omega is the quintic hat of v on [-1/2, 3/2]
(:func:`partition_weight`). A missing neighbour (an open rod's end, or one not given) is
the ghost of a straight continuation, x_prev = 2 x_0 - x_1, x_next = 2 x_1 - x_0. Pairs of
one rod take the
exclusion ramp W of the compliant level on the rest arcs of P's Gauss point and of its
projection (:mod:`tightknot.contact.pair_law`). The energy of a sample is
(1/2) A omega W phi(pen), pen = -g, A = w_u l_bar r0 2 pi / M its rest area and phi the
rounded penalty of :func:`tightknot.contact.section_squeeze.rounded_penalty`
(kappa pen^2 / 2 past a cubic onset).

Derivatives: the gradient is exact (every dependence above, the frames' through the
transport and the partner's section through v included). So is the Hessian, the mean radii's
second derivatives in the coefficients and their mixed ones in the stretch and v included,
but for the frames' second derivatives, which are central differences of their exact first
ones (:data:`FRAME_STEP`): b's cylinder coordinates
(v, rho, psi) of a sample carry their exact Hessians over (P - x_b0, x_b1 - x_b0)
(:func:`cylinder_coordinates`), the partition its own over P and b's four vertices, and P
its own over a's edge vector.

Local dofs of a pair (L = 24 + 4 K), in this order: x_a0, x_a1, x_b0, x_b1 (3 each), then
the section coefficients of a's two vertices (K each, as stored), then b's two, then the
rods' neighbouring vertices of the partition, x_a_prev, x_a_next, x_b_prev, x_b_next (3
each, from 12 + 4 K; zero rows and columns where a neighbour is a ghost, its dependence
carried onto the edge's own vertices).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from tightknot.contact.section_squeeze import rounded_penalty


def skew(v: NDArray) -> NDArray:
    """The matrix of v x . (3, 3)."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def transported_frame(d1_ref: NDArray, t_ref: NDArray, e: NDArray
                      ) -> tuple[NDArray, NDArray, NDArray, NDArray, NDArray, float]:
    """Frame of an edge with vector ``e`` [m] carried from (``t_ref``, ``d1_ref``) (module
    docstring): (t, d1, d2, dd1/dt, dd2/dt, l), the derivatives with t a free 3-vector
    (chain with dt/de = (I - t t^T) / l)."""
    length = float(np.linalg.norm(e))
    t = e / length
    u = d1_ref
    c = float(t_ref @ t)
    b = np.cross(t_ref, t)
    bu = float(b @ u)
    d1 = c * u + np.cross(b, u) + bu / (1.0 + c) * b
    s = skew(t_ref)  # db/dt
    j1 = (np.outer(u, t_ref) - skew(u) @ s + np.outer(b, u @ s) / (1.0 + c)
          + bu * s / (1.0 + c) - bu * np.outer(b, t_ref) / (1.0 + c) ** 2)
    d2 = np.cross(t, d1)
    j2 = -skew(d1) + skew(t) @ j1
    return t, d1, d2, j1, j2, length


def mode_basis(modes: NDArray, phi: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    """B(phi), B'(phi), B''(phi) of the coefficients (a_2, b_2, ..., a_N, b_N): rows per
    angle, shape (len(phi), 2 len(modes))."""
    phi = np.atleast_1d(phi)
    npk = np.outer(phi, modes)
    c, s = np.cos(npk), np.sin(npk)
    b0 = np.empty((phi.size, 2 * len(modes)))
    b1 = np.empty_like(b0)
    b2 = np.empty_like(b0)
    b0[:, 0::2], b0[:, 1::2] = c, s
    b1[:, 0::2], b1[:, 1::2] = -modes * s, modes * c
    b2[:, 0::2], b2[:, 1::2] = -(modes**2) * c, -(modes**2) * s
    return b0, b1, b2


def quintic_step(x: NDArray) -> tuple[NDArray, NDArray, NDArray]:
    """The C2 smoothstep S(x) = x^3 (10 - 15 x + 6 x^2) on [0, 1] (0 below, 1 above), with
    S' and S''."""
    x = np.clip(x, 0.0, 1.0)
    s = x**3 * (10.0 - 15.0 * x + 6.0 * x * x)
    s1 = 30.0 * x * x * (1.0 - x) ** 2
    s2 = 60.0 * x * (1.0 - x) * (1.0 - 2.0 * x)
    return s, s1, s2


def partition_weight(v: NDArray, first_open: bool, last_open: bool
                     ) -> tuple[NDArray, NDArray, NDArray]:
    """omega(v) of a partner edge and its first two derivatives: S(v + 1/2) on [-1/2, 1/2],
    1 - S(v - 1/2) on [1/2, 3/2] (consecutive edges' hats sum to one along a straight partner
    of equal edges only). The first or last edge of an open rod keeps the weight 1 up to its
    end vertex and fades over the next half edge, S(2 v + 1) below v = 0 and 1 - S(2 v - 2)
    above v = 1. The contact weighs its samples by :func:`partition` instead, which is this
    hat along a straight partner of equal edges and sums to one along any polyline."""
    v = np.asarray(v, dtype=np.float64)
    lo_s, lo_1, lo_2 = quintic_step(2.0 * v + 1.0) if first_open else quintic_step(v + 0.5)
    lo_1, lo_2 = (2.0 * lo_1, 4.0 * lo_2) if first_open else (lo_1, lo_2)
    hi_s, hi_1, hi_2 = quintic_step(2.0 * v - 2.0) if last_open else quintic_step(v - 0.5)
    hi_1, hi_2 = (2.0 * hi_1, 4.0 * hi_2) if last_open else (hi_1, hi_2)
    low_side = v < (0.0 if first_open else 0.5)
    high_side = v > (1.0 if last_open else 0.5)
    w = np.where(low_side, lo_s, np.where(high_side, 1.0 - hi_s, 1.0))
    w1 = np.where(low_side, lo_1, np.where(high_side, -hi_1, 0.0))
    w2 = np.where(low_side, lo_2, np.where(high_side, -hi_2, 0.0))
    return w, w1, w2


def _plane_distance(y: NDArray, c: NDArray) -> tuple[float, NDArray, NDArray]:
    """s = 2 y . c / (c . c) [-] of a point at y = P - x_i [m] from the plane through x_i
    normal to the chord c [m], with its gradient (6,) and Hessian (6, 6) over (y, c)."""
    dd = float(c @ c)
    yc = float(y @ c)
    s = 2.0 * yc / dd
    grad = np.concatenate([2.0 * c / dd, 2.0 * y / dd - 4.0 * yc * c / dd**2])
    hess = np.zeros((6, 6))
    hess[:3, 3:] = 2.0 * np.eye(3) / dd - 4.0 * np.outer(c, c) / dd**2
    hess[3:, :3] = hess[:3, 3:].T
    hess[3:, 3:] = (-4.0 * (np.outer(y, c) + np.outer(c, y)) / dd**2
                    - 4.0 * yc * np.eye(3) / dd**2 + 16.0 * yc * np.outer(c, c) / dd**3)
    return s, grad, hess


def partition(p: NDArray, x_prev: NDArray | None, x0: NDArray, x1: NDArray,
              x_next: NDArray | None, first_open: bool, last_open: bool
              ) -> tuple[float, NDArray, NDArray]:
    """omega(P) [-] of the partner edge (x0, x1) [m] at the point ``p`` [m] (module
    docstring): S(s_0 + 1/2) - S(s_1 + 1/2) on the bisector planes of the edge's vertices,
    x_prev and x_next [m] the rod's vertices before x0 and after x1 (None: the ghost of a
    straight continuation), clamped at 0. Returns omega, its gradient (15,) [1/m] and Hessian
    (15, 15) [1/m^2] over (P, x_prev, x0, x1, x_next); a ghost's rows and columns are zero,
    its dependence carried onto x0 and x1."""
    ghost_prev, ghost_next = x_prev is None, x_next is None
    xp = 2.0 * x0 - x1 if x_prev is None else x_prev
    xn = 2.0 * x1 - x0 if x_next is None else x_next
    eye = np.eye(3)
    # (y, c) of each plane over z = (P, x_prev, x0, x1, x_next): y_0 = P - x0,
    # c_0 = x1 - x_prev, y_1 = P - x1, c_1 = x_next - x0
    j0 = np.zeros((6, 15))
    j0[:3, 0:3], j0[:3, 6:9] = eye, -eye
    j0[3:, 9:12], j0[3:, 3:6] = eye, -eye
    j1 = np.zeros((6, 15))
    j1[:3, 0:3], j1[:3, 9:12] = eye, -eye
    j1[3:, 12:15], j1[3:, 6:9] = eye, -eye
    omega = 0.0
    grad = np.zeros(15)
    hess = np.zeros((15, 15))
    # sigma_i = S(scale s_i + shift); omega = sigma_0 - sigma_1
    for sign, y, c, jac, scale, shift in (
            (1.0, p - x0, x1 - xp, j0, *((2.0, 1.0) if first_open else (1.0, 0.5))),
            (-1.0, p - x1, xn - x0, j1, *((2.0, 0.0) if last_open else (1.0, 0.5)))):
        s, gs, hs = _plane_distance(y, c)
        st, st1, st2 = (float(z) for z in quintic_step(np.array(scale * s + shift)))
        gz = jac.T @ gs
        omega += sign * st
        grad += sign * scale * st1 * gz
        hess += sign * (scale**2 * st2 * np.outer(gz, gz) + scale * st1 * (jac.T @ hs @ jac))
    if omega <= 0.0:
        # the planes cross past the centre of curvature: no weight there
        return 0.0, np.zeros(15), np.zeros((15, 15))
    # a ghost is linear in x0, x1: z_full = T z carries its rows onto them exactly
    fold = np.eye(15)
    if ghost_prev:
        fold[3:6, 3:6] = 0.0
        fold[3:6, 6:9], fold[3:6, 9:12] = 2.0 * eye, -eye
    if ghost_next:
        fold[12:15, 12:15] = 0.0
        fold[12:15, 9:12], fold[12:15, 6:9] = 2.0 * eye, -eye
    return omega, fold.T @ grad, fold.T @ hess @ fold


@dataclass
class EdgeSection:
    """One edge of a pair: its vertices, frame base, section and constants.

    Attributes:
        x0, x1: vertex positions [m].
        t_ref, d1_ref: the accepted tangent and reference director the frame is carried
            from (unit vectors).
        coeffs0, coeffs1: section coefficients (a_2, b_2, ..., a_N, b_N) [m] of the edge's
            first vertex (in this edge's frame) and of its second (in the frame it is
            stored in: the next edge's, or this one's at the end of an open rod).
        twist1: the reference twist [rad] from this edge's frame to the frame coeffs1 is
            stored in (0 when it is this edge's).
        rest: edge rest length [m].
        r0: rest radius [m].
        nu: Poisson ratio of the area's thinning with stretch [-].
        rigid: a rigid section (radius r0, coefficients ignored, no thinning).
        arc: rest arcs of the edge's ends [m] (the exclusion window's).
        first_open, last_open: the edge is the first / last of an open rod.
        x_prev, x_next: the rod's vertices [m] before x0 and after x1, which shape the
            partition (:func:`partition`); None for the ghost of a straight continuation
            (an open rod's end, or a caller that gives no neighbours).
    """

    x0: NDArray
    x1: NDArray
    t_ref: NDArray
    d1_ref: NDArray
    coeffs0: NDArray
    coeffs1: NDArray
    rest: float
    r0: float
    nu: float = 0.5
    rigid: bool = False
    twist1: float = 0.0
    arc: tuple[float, float] = (0.0, 0.0)
    first_open: bool = False
    last_open: bool = False
    x_prev: NDArray | None = None
    x_next: NDArray | None = None


@dataclass
class PairSettings:
    """What a pair's evaluation needs beyond its two edges.

    Attributes:
        modes: the mode numbers n = 2..N.
        gauss_xi, gauss_w: Gauss points and weights on [0, 1] along each edge.
        samples: boundary samples per section M (angles 2 pi (k + 1/2) / M).
        kappa: penalty stiffness [Pa/m] (pressure per penetration).
        onset: the penalty's rounded onset [m].
        same_rod: the two edges belong to one rod (the exclusion ramp applies).
        closed: that rod is closed (arcs wrap at ``rod_length``).
        rod_length: rest length of that rod [m] (scaled like the arcs).
        exclusion: exclusion window [m] of rest arc.
    """

    modes: NDArray
    gauss_xi: NDArray
    gauss_w: NDArray
    samples: int
    kappa: float
    onset: float
    same_rod: bool = False
    closed: bool = False
    rod_length: float = 0.0
    exclusion: float = 0.0


def mode_rotation(modes: NDArray, angle: float) -> NDArray:
    """Q(angle) on the coefficients (a_2, b_2, ..., a_N, b_N): per mode n the rotation
    [[cos n m, sin n m], [-sin n m, cos n m]] that takes a shape's coefficients in one frame
    to those in a frame turned by m about the tangent, (K, K)."""
    k = 2 * len(modes)
    q = np.zeros((k, k))
    for j, n in enumerate(modes):
        c, s = math.cos(n * angle), math.sin(n * angle)
        q[2 * j:2 * j + 2, 2 * j:2 * j + 2] = [[c, s], [-s, c]]
    return q


def interpolated(edge: EdgeSection, modes: NDArray, u: float) -> tuple[NDArray, NDArray]:
    """The coefficients c(u) = (1 - u) c_0 + u Q^T c_1 [m] at axial parameter ``u`` (any real:
    a partner's projection extrapolates) and the matrix dc(u)/dc_1 = u Q^T."""
    q = mode_rotation(modes, edge.twist1)
    return (1.0 - u) * edge.coeffs0 + u * (q.T @ edge.coeffs1), u * q.T


def exclusion_ramp(sep: NDArray, exclusion: float) -> tuple[NDArray, NDArray, NDArray]:
    """The compliant level's exclusion ramp W(sep) (a quintic step over a quarter window past
    the window), with dW/dsep and d2W/dsep2."""
    q = 0.25 * exclusion
    s, s1, s2 = quintic_step((sep - exclusion) / q)
    return s, s1 / q, s2 / (q * q)


def _expand(nloc: int, k: int, first: int, weight0: float, rot1: NDArray, vec: NDArray
            ) -> NDArray:
    """A direction over the local dofs: ``vec`` (over c at a point of an edge) carried to the
    edge's two vertex sections, ``weight0`` vec on the first (its dofs from ``first``) and
    ``rot1^T`` vec on the second (rot1 = dc/dc_1)."""
    out = np.zeros(nloc)
    out[first:first + k] = weight0 * vec
    out[first + k:first + 2 * k] = rot1.T @ vec
    return out


#: Relative step of the central differences that give the frames' second derivatives
#: (of their exact first derivatives: truncation (1e-6)^2, round-off 1e-16 / 1e-6).
FRAME_STEP = 1e-6


def frame_derivatives(d1_ref: NDArray, t_ref: NDArray, e: NDArray
                      ) -> tuple[NDArray, NDArray, NDArray, NDArray, NDArray, NDArray]:
    """(d1, d2, M1, M2, T1, T2) of an edge with vector ``e`` [m]: its transported frame,
    M = d(d)/de (3, 3) exactly, and T[k, i, j] = d2 d_k / de_i de_j (3, 3, 3) by central
    differences of M (:data:`FRAME_STEP` of |e|), symmetrised in (i, j)."""
    def firsts(vec: NDArray) -> tuple[NDArray, ...]:
        t, d1, d2, j1, j2, length = transported_frame(d1_ref, t_ref, vec)
        pt = (np.eye(3) - np.outer(t, t)) / length
        return d1, d2, j1 @ pt, j2 @ pt

    d1, d2, m1, m2 = firsts(e)
    h = FRAME_STEP * float(np.linalg.norm(e))
    t1 = np.zeros((3, 3, 3))
    t2 = np.zeros((3, 3, 3))
    for j in range(3):
        step = np.zeros(3)
        step[j] = h
        _, _, m1p, m2p = firsts(e + step)
        _, _, m1m, m2m = firsts(e - step)
        t1[:, :, j] = (m1p - m1m) / (2.0 * h)
        t2[:, :, j] = (m2p - m2m) / (2.0 * h)
    t1 = 0.5 * (t1 + t1.transpose(0, 2, 1))
    t2 = 0.5 * (t2 + t2.transpose(0, 2, 1))
    return d1, d2, m1, m2, t1, t2


def radius_partials(edge: EdgeSection, length: float, c: NDArray
                    ) -> tuple[float, float, float, NDArray]:
    """Mean radius R [m] where the coefficients are ``c`` [m] at an edge of current
    ``length`` [m], dR/dlambda, d2R/dlambda2 [m] and dR/dc [-] (all zero but R for a rigid
    section)."""
    if edge.rigid:
        return edge.r0, 0.0, 0.0, np.zeros(c.size)
    lam = length / edge.rest
    nu, r0 = edge.nu, edge.r0
    s = r0**2 * lam ** (-2.0 * nu) - 0.5 * float(c @ c)
    if s <= 0.0:
        raise ValueError("a section's mean radius is not real (R^2 <= 0)")
    big_r = math.sqrt(s)
    s1 = -2.0 * nu * r0**2 * lam ** (-2.0 * nu - 1.0)
    s2 = 2.0 * nu * (2.0 * nu + 1.0) * r0**2 * lam ** (-2.0 * nu - 2.0)
    return (big_r, s1 / (2.0 * big_r), s2 / (2.0 * big_r) - s1 * s1 / (4.0 * big_r**3),
            -c / (2.0 * big_r))


def cylinder_coordinates(w: NDArray, e: NDArray, d1: NDArray, d2: NDArray, m1: NDArray,
                         m2: NDArray, t1: NDArray, t2: NDArray) -> dict[str, NDArray | float]:
    """A point at w = P - x_b0 [m] about the axis e = x_b1 - x_b0 [m] of an edge whose frame
    is (d1, d2) with derivatives M, T in e (:func:`frame_derivatives`): its projection v,
    distance rho and angle psi, each with its gradient (6,) and Hessian (6, 6) over (w, e),
    and the edge's stretch direction (d lambda / de = t / rest is the caller's)."""
    ll = float(e @ e)
    v = float(w @ e) / ll
    dvec = w - v * e
    rho = float(np.linalg.norm(dvec))
    nrm = dvec / rho
    a = w - 2.0 * v * e
    gv = np.concatenate([e / ll, a / ll])
    hv = np.zeros((6, 6))
    hv[:3, 3:] = np.eye(3) / ll - 2.0 * np.outer(e, e) / ll**2
    hv[3:, :3] = hv[:3, 3:].T
    hv[3:, 3:] = -2.0 * (np.outer(e, a) + np.outer(a, e)) / ll**2 - 2.0 * v * np.eye(3) / ll
    # D = w - v e: dD/d(w, e) (3, 6); its second derivatives contract as -(grad v x y_e +
    # y_e x grad v) - (y . e) hess v for any fixed vector y (y_e = (0, y)).
    jd = np.concatenate([np.eye(3) - np.outer(e, e) / ll, -v * np.eye(3) - np.outer(e, a) / ll],
                        axis=1)

    def d2_dot(y: NDArray) -> NDArray:
        ye = np.concatenate([np.zeros(3), y])
        return -(np.outer(gv, ye) + np.outer(ye, gv)) - float(y @ e) * hv

    grho = nrm @ jd
    hrho = jd.T @ ((np.eye(3) - np.outer(nrm, nrm)) / rho) @ jd + d2_dot(nrm)
    out: dict[str, NDArray | float] = {"v": v, "rho": rho, "gv": gv, "hv": hv, "grho": grho,
                                        "hrho": hrho, "nrm": nrm, "dvec": dvec}
    comps = []
    for d, m, t in ((d1, m1, t1), (d2, m2, t2)):
        val = float(dvec @ d)
        dm = np.concatenate([np.zeros((3, 3)), m], axis=1)  # d(d)/d(w, e)
        grad = d @ jd + dvec @ dm
        hess = d2_dot(d) + jd.T @ dm + dm.T @ jd
        hess[3:, 3:] += np.einsum("k,kij->ij", dvec, t)
        comps.append((val, grad, hess))
    (x, gx, hx), (y, gy, hy) = comps
    s = x * x + y * y
    out["psi"] = math.atan2(y, x)
    out["gpsi"] = (x * gy - y * gx) / s
    # psi = Im log(X + i Y): its Hessian is Im(hess Z / Z - grad Z grad Z^T / Z^2).
    out["hpsi"] = ((x * hy - y * hx) / s
                   - ((np.outer(gx, gx) - np.outer(gy, gy)) * (-2.0 * x * y)
                      + (np.outer(gx, gy) + np.outer(gy, gx)) * (x * x - y * y)) / s**2)
    return out


def pass_terms(ea_: EdgeSection, eb_: EdgeSection, st: PairSettings, want_hess: bool = True
               ) -> dict[str, NDArray | float]:
    """One pass of a pair: a's boundary samples against b's surface. Returns the energy [J],
    its gradient (L,) and Hessian (L, L) over the local dofs (module docstring), and per
    sample (Gauss point major): the penetration ``pen`` [m] and the weight ``weight`` =
    omega W of the sample [-]."""
    modes = np.asarray(st.modes, dtype=np.float64)
    k = 2 * modes.size
    nloc = 24 + 4 * k
    ia0, ia1, ib0, ib1 = slice(0, 3), slice(3, 6), slice(6, 9), slice(9, 12)
    nb = 12 + 4 * k  # the neighbours' block
    ib_prev, ib_next = slice(nb + 6, nb + 9), slice(nb + 9, nb + 12)
    vec_a = ea_.x1 - ea_.x0
    vec_b = eb_.x1 - eb_.x0
    la, lb = float(np.linalg.norm(vec_a)), float(np.linalg.norm(vec_b))
    ta, tb = vec_a / la, vec_b / lb
    d1a, d2a, m1a, m2a, t1a, t2a = frame_derivatives(ea_.d1_ref, ea_.t_ref, vec_a)
    d1b, d2b, m1b, m2b, t1b, t2b = frame_derivatives(eb_.d1_ref, eb_.t_ref, vec_b)
    m = st.samples
    phis = 2.0 * math.pi * (np.arange(m) + 0.5) / m
    bphi = mode_basis(modes, phis)[0]
    area = ea_.rest * ea_.r0 * 2.0 * math.pi / m
    energy = 0.0
    grad = np.zeros(nloc)
    hess = np.zeros((nloc, nloc))
    pens, weights = [], []
    zero = np.zeros(k)
    # (w, e) of b's cylinder coordinates over the local dofs: w = P - x_b0, e = x_b1 - x_b0
    e_rows = np.zeros((3, nloc))
    e_rows[:, ib1] = np.eye(3)
    e_rows[:, ib0] = -np.eye(3)
    lam_b_dir = np.concatenate([np.zeros(3), tb / eb_.rest])  # d lambda_b / d(w, e)
    lam_b_hess = np.zeros((6, 6))
    lam_b_hess[3:, 3:] = (np.eye(3) - np.outer(tb, tb)) / (lb * eb_.rest)
    # the partition's (P, x_prev, x0, x1, x_next) over the local dofs, but for P's rows
    # (the sample's own, filled per sample); a ghost's rows carry a zero gradient
    om_rows = np.zeros((15, nloc))
    for rows, cols in ((slice(3, 6), ib_prev), (slice(6, 9), ib0), (slice(9, 12), ib1),
                       (slice(12, 15), ib_next)):
        om_rows[rows, cols] = np.eye(3)
    dcb = zero if eb_.rigid else interpolated(eb_, modes, 1.0)[0] - eb_.coeffs0
    rot_b1 = interpolated(eb_, modes, 1.0)[1]
    for u, wu in zip(st.gauss_xi, st.gauss_w, strict=True):
        if ea_.rigid:
            ca, rot_a = zero, np.zeros((k, k))
        else:
            ca, rot_a = interpolated(ea_, modes, u)
        ra_mean, ra_l, ra_ll, ra_c = radius_partials(ea_, la, ca)
        dra = ra_l * ta / ea_.rest  # dr_a / de_a
        hra = ra_ll * np.outer(ta, ta) / ea_.rest**2 + ra_l * (np.eye(3) - np.outer(ta, ta)) / (
            la * ea_.rest)
        for kk, phi in enumerate(phis):
            cphi, sphi = math.cos(phi), math.sin(phi)
            dirv = cphi * d1a + sphi * d2a
            m_dir = cphi * m1a + sphi * m2a  # d dir / d e_a
            r_a = ra_mean + float(bphi[kk] @ ca)
            p = ea_.x0 + u * vec_a + r_a * dirv
            cyl = cylinder_coordinates(p - eb_.x0, vec_b, d1b, d2b, m1b, m2b, t1b, t2b)
            v, rho, psi = cyl["v"], cyl["rho"], cyl["psi"]
            b0, b1, b2 = (arr[0] for arr in mode_basis(modes, np.array([psi])))
            if eb_.rigid:
                cb, rot_b = zero, np.zeros((k, k))
            else:
                cb, rot_b = interpolated(eb_, modes, v)
            rb_mean, rb_l, rb_ll, rb_c = radius_partials(eb_, lb, cb)
            r_b = rb_mean + float(b0 @ cb)
            pen = r_b - rho
            # weights: partner partition (of P) and exclusion ramp (of v)
            om, om_g, om_h = partition(p, eb_.x_prev, eb_.x0, eb_.x1, eb_.x_next,
                                       eb_.first_open, eb_.last_open)
            wex, wex1, wex2 = 1.0, 0.0, 0.0
            if st.same_rod:
                s_a = ea_.arc[0] + u * (ea_.arc[1] - ea_.arc[0])
                s_b = eb_.arc[0] + v * (eb_.arc[1] - eb_.arc[0])
                dsep = s_b - s_a
                sgn = 1.0 if dsep >= 0.0 else -1.0
                sep = abs(dsep)
                if st.closed and st.rod_length - sep < sep:
                    sep = st.rod_length - sep
                    sgn = -sgn
                ww = exclusion_ramp(np.array(sep), st.exclusion)
                dsdv = sgn * (eb_.arc[1] - eb_.arc[0])
                wex, wex1, wex2 = float(ww[0]), float(ww[1]) * dsdv, float(ww[2]) * dsdv**2
            wt = om * wex
            pens.append(pen)
            weights.append(wt)
            if wt == 0.0 or pen <= 0.0:
                continue
            ph, ph1, ph2 = (float(z) for z in rounded_penalty(np.array(pen), st.kappa,
                                                              st.onset))
            a_s = 0.5 * wu * area
            energy += a_s * wt * ph
            # -- P over the local dofs ---------------------------------------------------
            dp_de = u * np.eye(3) + r_a * m_dir + np.outer(dirv, dra)
            dp = np.zeros((3, nloc))
            dp[:, ia0] = np.eye(3) - dp_de
            dp[:, ia1] = dp_de
            basis_a = bphi[kk] + ra_c  # dr_a/dc_a(u)
            e_alpha = np.zeros(nloc)
            if not ea_.rigid:
                e_alpha = _expand(nloc, k, 12, 1.0 - u, rot_a, basis_a)
                dp += np.outer(dirv, e_alpha)
            jwe = np.concatenate([dp - np.concatenate([np.zeros((3, 6)), np.eye(3),
                                                        np.zeros((3, nloc - 9))], axis=1),
                                  e_rows])  # (6, L)
            # -- b's radius at (psi, v) and its partials -----------------------------------
            r_psi = float(b1 @ cb)
            r_psipsi = float(b2 @ cb)
            basis_b = b0 + rb_c  # dr_b/dc_b(v)
            r_v = float(basis_b @ dcb)
            r_vv = (-float(dcb @ dcb) / (2.0 * rb_mean) - float(cb @ dcb) ** 2
                    / (4.0 * rb_mean**3)) if not eb_.rigid else 0.0
            r_psiv = float(b1 @ dcb)
            e_beta = np.zeros(nloc)
            e_gamma = np.zeros(nloc)
            e_delta = np.zeros(nloc)
            if not eb_.rigid:
                e_beta = _expand(nloc, k, 12 + 2 * k, 1.0 - v, rot_b, basis_b)
                e_gamma = _expand(nloc, k, 12 + 2 * k, 1.0 - v, rot_b, b1)
                # d/dv of the interpolation weights: -1 on c_b0, Q on c_b1
                e_delta = _expand(nloc, k, 12 + 2 * k, -1.0, rot_b1, basis_b)
            # -- the gap g = rho - r_b over (w, e), then over the local dofs -------------
            gpsi, gv = cyl["gpsi"], cyl["gv"]
            g_we = cyl["grho"] - r_psi * gpsi - r_v * gv - rb_l * lam_b_dir
            h_we = (cyl["hrho"] - r_psipsi * np.outer(gpsi, gpsi) - r_psi * cyl["hpsi"]
                    - r_vv * np.outer(gv, gv) - r_v * cyl["hv"]
                    - r_psiv * (np.outer(gpsi, gv) + np.outer(gv, gpsi))
                    - rb_ll * np.outer(lam_b_dir, lam_b_dir) - rb_l * lam_b_hess)
            grad_g = jwe.T @ g_we - e_beta
            grad_v = jwe.T @ gv
            om_rows[:3] = dp
            grad_om = om_rows.T @ om_g
            # wt = omega(P, b's vertices) W(v): dwt/dP, and over the local dofs
            wt_p = wex * om_g[:3] + om * wex1 * gv[:3]
            grad_wt = wex * grad_om + om * wex1 * grad_v
            # energy a_s wt phi(-g)
            grad += a_s * (-wt * ph1 * grad_g + ph * grad_wt)
            if not want_hess:
                continue
            # second derivatives of g and v over the local dofs
            psi_l = jwe.T @ gpsi
            v_l = grad_v
            hg = jwe.T @ h_we @ jwe
            hg -= np.outer(psi_l, e_gamma) + np.outer(e_gamma, psi_l)
            hg -= np.outer(v_l, e_delta) + np.outer(e_delta, v_l)
            hvl = jwe.T @ cyl["hv"] @ jwe
            hom = om_rows.T @ om_h @ om_rows
            # P's own second derivatives (a's side), contracted with dg/dw, dv/dw and
            # d omega/dP
            for gw, target in ((g_we[:3], hg), (gv[:3], hvl), (om_g[:3], hom)):
                pee = (r_a * np.einsum("k,kij->ij", gw, cphi * t1a + sphi * t2a)
                       + np.outer(gw @ m_dir, dra) + np.outer(dra, gw @ m_dir)
                       + float(gw @ dirv) * hra)
                target[ia1, ia1] += pee
                target[ia0, ia0] += pee
                target[ia0, ia1] -= pee
                target[ia1, ia0] -= pee
                if not ea_.rigid:
                    row = np.zeros(nloc)
                    row[ia1] = gw @ m_dir
                    row[ia0] = -row[ia1]
                    target += np.outer(row, e_alpha) + np.outer(e_alpha, row)
            hwt = (wex * hom + wex1 * (np.outer(grad_om, grad_v) + np.outer(grad_v, grad_om))
                   + om * (wex2 * np.outer(grad_v, grad_v) + wex1 * hvl))
            h = wt * ph2 * np.outer(grad_g, grad_g) - wt * ph1 * hg
            h -= ph1 * (np.outer(grad_g, grad_wt) + np.outer(grad_wt, grad_g))
            h += ph * hwt
            hess += a_s * h
            # The mean radii's second derivatives in the coefficients, and mixed in the
            # stretch and (b's) in v, times dE/dr: R = sqrt(S(lam) - |c|^2 / 2) has
            # R_cc = -I / (2 R) - c c^T / (4 R^3) and R_clam = c R_lam / (2 R^2).
            if not ea_.rigid:
                g_alpha = a_s * (-wt * ph1 * float(g_we[:3] @ dirv) + ph * float(wt_p @ dirv))
                map_a = np.zeros((nloc, k))
                map_a[12:12 + k] = (1.0 - u) * np.eye(k)
                map_a[12 + k:12 + 2 * k] = rot_a.T
                hess += g_alpha * _radius_second(map_a, ca, ra_mean, ra_l, ta / ea_.rest,
                                                 ia0, ia1, None)
            if not eb_.rigid:
                map_b = np.zeros((nloc, k))
                map_b[12 + 2 * k:12 + 3 * k] = (1.0 - v) * np.eye(k)
                map_b[12 + 3 * k:nb] = rot_b.T
                hess += a_s * wt * ph1 * _radius_second(map_b, cb, rb_mean, rb_l,
                                                        tb / eb_.rest, ib0, ib1,
                                                        (dcb, grad_v))
    return {"energy": energy, "grad": grad, "hess": hess, "pen": np.array(pens),
            "weight": np.array(weights)}


def _radius_second(cmap: NDArray, c: NDArray, big_r: float, r_lam: float,
                   lam_dir: NDArray, i0: slice, i1: slice,
                   along_v: tuple[NDArray, NDArray] | None) -> NDArray:
    """The second derivatives of a mean radius R(lam, c) over the local dofs (L, L):
    R_cc carried by ``cmap`` (dc/d(local coefficients), (L, K)) from the coefficients ``c``
    [m] at the point, R_clam against the stretch lam = |x_1 - x_0| / rest (d lam / dx_1 =
    ``lam_dir`` on the edge's positions ``i0``, ``i1``) and, with ``along_v`` = (dc/dv,
    dv/d(local)), R_cc dc/dv against v (a partner's c(v) at its projection v)."""
    k = c.size
    rcc = -np.eye(k) / (2.0 * big_r) - np.outer(c, c) / (4.0 * big_r**3)
    out = cmap @ rcc @ cmap.T
    lam = np.zeros(cmap.shape[0])
    lam[i1] = lam_dir
    lam[i0] = -lam_dir
    col = cmap @ (c * r_lam / (2.0 * big_r**2))
    out += np.outer(col, lam) + np.outer(lam, col)
    if along_v is not None:
        dc_dv, v_local = along_v
        col = cmap @ (rcc @ dc_dv)
        out += np.outer(col, v_local) + np.outer(v_local, col)
    return out


def swap_order(k: int) -> NDArray:
    """Local dof permutation taking a pass of (b, a) to the pair order (a, b): entry i is
    the pair's index of the pass's dof i (its a is the pair's b, and the neighbours swap
    with the edges)."""
    nb = 12 + 4 * k
    return np.concatenate([np.arange(6, 12), np.arange(0, 6),
                           np.arange(12 + 2 * k, 12 + 4 * k), np.arange(12, 12 + 2 * k),
                           np.arange(nb + 6, nb + 12), np.arange(nb, nb + 6)])


def pair_terms(ea_: EdgeSection, eb_: EdgeSection, st: PairSettings, want_hess: bool = True
               ) -> dict[str, NDArray | float]:
    """Both passes of a pair (module docstring): energy [J], gradient (L,) [N, N/m per m
    of coefficient], Hessian (L, L), and each side's sample penetrations [m]."""
    k = 2 * len(st.modes)
    one = pass_terms(ea_, eb_, st, want_hess)
    two = pass_terms(eb_, ea_, st, want_hess)
    perm = swap_order(k)
    grad = one["grad"].copy()
    grad[perm] += two["grad"]
    hess = one["hess"].copy()
    hess[np.ix_(perm, perm)] += two["hess"]
    return {"energy": one["energy"] + two["energy"], "grad": grad, "hess": hess,
            "pen_a": one["pen"], "pen_b": two["pen"], "weight_a": one["weight"],
            "weight_b": two["weight"]}
