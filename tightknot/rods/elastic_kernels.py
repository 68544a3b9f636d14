"""Warp kernels of the elastic energies (stretch, bend, twist) and of the reference frames.

One module, so it compiles once. Float64 throughout (tight contact needs it). Kernels follow
the mujoco_warp layout: parameters grouped as Model / Data in / Out, each kernel launched by
a thin function in :mod:`tightknot.rods.elastic`.

Energies (Bergou, Wardetzky, Robinson, Audoly, Grinspun 2008, "Discrete elastic rods";
Bergou, Audoly, Vouga, Wardetzky, Grinspun 2010, "Discrete viscous threads"):

* Stretch of edge j, incompressible neo-Hookean in uniaxial stretch lam = |e_j|/l_bar_j:
  ``E_s = mu A0 l_bar (lam^2 + 2/lam - 3) / 2``; tension ``dE/d|e| = mu A0 (lam - lam^-2)``.
* Bend at joint i, curvature binormal (Bergou 2008 eq. 1)
  ``kb = 2 e0 x e1 / (|e0||e1| + e0.e1)``, ``|kb| = 2 tan(phi/2)``, over the deformed
  Voronoi length ``V = (|e0| + |e1|)/2`` (Bergou 2008 eq. 3 with the deformed length):
  ``E_b = EI(lam) |kb|^2 / (2 V)``, with the section thinning r = r0 lam^-nu, i.e.
  ``EI(lam) = EI0 lam^(-4 nu)``, lam = l/l_bar, l = |e0| + |e1|. Hence
  ``E_b = (EI0 / l_bar) g(l) T`` with ``T = |kb|^2`` and ``g = (l/l_bar)^-(4 nu + 1)``.
  T depends on the edges only through a = |e0|^2, b = |e1|^2, d = e0.e1:
  ``T = 4 (sqrt(ab) - d)/(sqrt(ab) + d) = 4 - 8 d / S`` with ``S = sqrt(ab) + d``,
  so gradient and Hessian follow from the chain rule through (a, b, d).
* Twist at joint i: ``m = theta_after - theta_before + m_ref`` (Bergou 2010 sec. 4.2),
  ``E_t = GJ(lam) m^2 / (2 V) = (GJ0 / l_bar) g(l) m^2``. The gradient of the reference
  twist is ``dm/de0 = kb/(2|e0|)``, ``dm/de1 = kb/(2|e1|)`` (Bergou 2010 eq. 9); its Hessian
  is that of Jawed, Novelia, O'Reilly, "A primer on the kinematics of discrete elastic
  rods" (2018), sec. 7 (also dismech's ``hessTwist``).

Local stencil dofs of a joint: [x_{i-1} (0..2), x_i (3..5), x_{i+1} (6..8), theta_before (9),
theta_after (10)]; the Hessian slot of local entry (r, c) is ``hess_slot[j, 11 r + c]``
(-1: not assembled, e.g. a fixed dof). An edge's local dofs are [x_a (0..2), x_b (3..5)].
"""

from __future__ import annotations

import warp as wp

f64 = wp.float64


@wp.func
def _outer(a: wp.vec3d, b: wp.vec3d) -> wp.mat33d:
    return wp.outer(a, b)


@wp.func
def _scatter_block(
    slots: wp.array2d(dtype=wp.int32),
    row: int,
    width: int,
    r0: int,
    c0: int,
    m: wp.mat33d,
    hess_out: wp.array(dtype=wp.float64),
):
    for a in range(3):
        for b in range(3):
            s = slots[row, (r0 + a) * width + c0 + b]
            if s >= 0:
                wp.atomic_add(hess_out, s, m[a, b])


@wp.func
def _scatter_col(
    slots: wp.array2d(dtype=wp.int32),
    row: int,
    width: int,
    r0: int,
    c: int,
    v: wp.vec3d,
    hess_out: wp.array(dtype=wp.float64),
):
    # Adds the 3-vector v at rows r0..r0+2 of column c and, symmetrically, row c.
    for a in range(3):
        s = slots[row, (r0 + a) * width + c]
        if s >= 0:
            wp.atomic_add(hess_out, s, v[a])
        s2 = slots[row, c * width + r0 + a]
        if s2 >= 0:
            wp.atomic_add(hess_out, s2, v[a])


@wp.func
def _scatter_scalar(
    slots: wp.array2d(dtype=wp.int32),
    row: int,
    width: int,
    r: int,
    c: int,
    v: wp.float64,
    hess_out: wp.array(dtype=wp.float64),
):
    s = slots[row, r * width + c]
    if s >= 0:
        wp.atomic_add(hess_out, s, v)


@wp.func
def _add_grad(grad_out: wp.array(dtype=wp.float64), dof: int, v: wp.float64):
    if dof >= 0:
        wp.atomic_add(grad_out, dof, v)


@wp.kernel
def stretch_kernel(
    # Model:
    edge_vertex: wp.array(dtype=wp.vec2i),
    edge_mu_area: wp.array(dtype=wp.float64),
    edge_dofs: wp.array2d(dtype=wp.int32),
    # Data in:
    x_in: wp.array(dtype=wp.vec3d),
    edge_rest_length_in: wp.array(dtype=wp.float64),
    hess_slot_in: wp.array2d(dtype=wp.int32),
    want_grad: int,
    want_hess: int,
    # Out:
    energy_out: wp.array(dtype=wp.float64),
    grad_out: wp.array(dtype=wp.float64),
    hess_out: wp.array(dtype=wp.float64),
):
    j = wp.tid()
    v = edge_vertex[j]
    e = x_in[v[1]] - x_in[v[0]]
    n = wp.length(e)
    lbar = edge_rest_length_in[j]
    mua = edge_mu_area[j]
    eps = (n - lbar) / lbar
    lam = f64(1.0) + eps
    # Neo-Hookean uniaxial energy (Treloar): W = mu/2 (lam^2 + 2/lam - 3) per rest volume,
    # written (lam - 1)^2 (lam + 2)/lam so that small strains keep full relative precision
    # (the Newton line search compares energies that differ by 1e-18 J near convergence).
    energy_out[j] = f64(0.5) * mua * lbar * eps * eps * (lam + f64(2.0)) / lam
    if want_grad == 0:
        return
    t = e / n
    # Tension mu A0 (lam - lam^-2) = mu A0 eps (lam^2 + lam + 1)/lam^2, likewise.
    tension = mua * eps * (lam * lam + lam + f64(1.0)) / (lam * lam)
    g = tension * t
    for a in range(3):
        _add_grad(grad_out, edge_dofs[j, a], -g[a])
        _add_grad(grad_out, edge_dofs[j, 3 + a], g[a])
    if want_hess == 0:
        return
    # d2E/dn2 = mu A0 (1 + 2 lam^-3) / l_bar; transverse part tension/n (I - t t).
    k_ax = mua * (f64(1.0) + f64(2.0) / (lam * lam * lam)) / lbar
    tt = _outer(t, t)
    h = k_ax * tt + (tension / n) * (wp.identity(n=3, dtype=wp.float64) - tt)
    _scatter_block(hess_slot_in, j, 6, 0, 0, h, hess_out)
    _scatter_block(hess_slot_in, j, 6, 3, 3, h, hess_out)
    _scatter_block(hess_slot_in, j, 6, 0, 3, -h, hess_out)
    _scatter_block(hess_slot_in, j, 6, 3, 0, -h, hess_out)


@wp.kernel
def bend_twist_kernel(
    # Model:
    joint_vertex: wp.array(dtype=wp.vec3i),
    joint_edge: wp.array(dtype=wp.vec2i),
    joint_bend_stiffness: wp.array(dtype=wp.float64),
    joint_twist_stiffness: wp.array(dtype=wp.float64),
    joint_thinning_exponent: wp.array(dtype=wp.float64),
    joint_dofs: wp.array2d(dtype=wp.int32),
    twist_enabled: int,
    # Data in:
    x_in: wp.array(dtype=wp.vec3d),
    theta_in: wp.array(dtype=wp.float64),
    m_ref_in: wp.array(dtype=wp.float64),
    edge_rest_length_in: wp.array(dtype=wp.float64),
    hess_slot_in: wp.array2d(dtype=wp.int32),
    want_grad: int,
    want_hess: int,
    # Out:
    bend_energy_out: wp.array(dtype=wp.float64),
    twist_energy_out: wp.array(dtype=wp.float64),
    grad_out: wp.array(dtype=wp.float64),
    hess_out: wp.array(dtype=wp.float64),
):
    j = wp.tid()
    jv = joint_vertex[j]
    je = joint_edge[j]
    e0 = x_in[jv[1]] - x_in[jv[0]]
    e1 = x_in[jv[2]] - x_in[jv[1]]
    a = wp.dot(e0, e0)
    b = wp.dot(e1, e1)
    d = wp.dot(e0, e1)
    n0 = wp.sqrt(a)
    n1 = wp.sqrt(b)
    nn = n0 * n1
    s = nn + d
    # Antiparallel edges (a hairpin of zero radius) have unbounded curvature; clamp S so
    # the energy stays finite and huge, and the line search rejects the step.
    s = wp.max(s, f64(1.0e-12) * nn)
    c = wp.cross(e0, e1)
    tval = f64(4.0) * wp.dot(c, c) / (s * s)
    ell = n0 + n1
    lbar = edge_rest_length_in[je[0]] + edge_rest_length_in[je[1]]
    q = joint_thinning_exponent[j]
    gval = wp.pow(ell / lbar, -q)
    kb_coef = joint_bend_stiffness[j] / lbar
    bend_energy_out[j] = kb_coef * gval * tval
    mtw = f64(0.0)
    kt_coef = f64(0.0)
    if twist_enabled != 0:
        mtw = theta_in[je[1]] - theta_in[je[0]] + m_ref_in[j]
        kt_coef = joint_twist_stiffness[j] / lbar
        twist_energy_out[j] = kt_coef * gval * mtw * mtw
    else:
        twist_energy_out[j] = f64(0.0)
    if want_grad == 0:
        return

    # g(l) and its derivatives in l, then in (a, b) through l = sqrt(a) + sqrt(b).
    g1 = -q * gval / ell
    g2 = q * (q + f64(1.0)) * gval / (ell * ell)
    l_a = f64(0.5) / n0
    l_b = f64(0.5) / n1
    l_aa = -f64(0.25) / (a * n0)
    l_bb = -f64(0.25) / (b * n1)
    G_a = g1 * l_a
    G_b = g1 * l_b
    G_aa = g2 * l_a * l_a + g1 * l_aa
    G_bb = g2 * l_b * l_b + g1 * l_bb
    G_ab = g2 * l_a * l_b

    # T = 4 - 8 d / S, S = sqrt(ab) + d: derivatives through f(S, d) = -8 d / S.
    f_S = f64(8.0) * d / (s * s)
    f_d = -f64(8.0) / s
    f_SS = -f64(16.0) * d / (s * s * s)
    f_Sd = f64(8.0) / (s * s)
    S_a = n1 / (f64(2.0) * n0)
    S_b = n0 / (f64(2.0) * n1)
    S_aa = -n1 / (f64(4.0) * a * n0)
    S_bb = -n0 / (f64(4.0) * b * n1)
    S_ab = f64(1.0) / (f64(4.0) * nn)
    T_a = f_S * S_a
    T_b = f_S * S_b
    T_d = f_S + f_d
    T_aa = f_SS * S_a * S_a + f_S * S_aa
    T_bb = f_SS * S_b * S_b + f_S * S_bb
    T_ab = f_SS * S_a * S_b + f_S * S_ab
    T_ad = (f_SS + f_Sd) * S_a
    T_bd = (f_SS + f_Sd) * S_b
    T_dd = f_SS + f64(2.0) * f_Sd

    K = kb_coef
    F_a = K * (G_a * tval + gval * T_a)
    F_b = K * (G_b * tval + gval * T_b)
    F_d = K * gval * T_d

    ge0 = f64(2.0) * F_a * e0 + F_d * e1
    ge1 = f64(2.0) * F_b * e1 + F_d * e0
    gth0 = f64(0.0)
    gth1 = f64(0.0)

    # Twist: reference-twist gradient (Bergou 2010 eq. 9).
    kb = (f64(2.0) / s) * c
    dm0 = kb / (f64(2.0) * n0)
    dm1 = kb / (f64(2.0) * n1)
    Gv0 = (f64(2.0) * G_a) * e0
    Gv1 = (f64(2.0) * G_b) * e1
    if twist_enabled != 0:
        m2 = mtw * mtw
        ge0 = ge0 + kt_coef * (m2 * Gv0 + f64(2.0) * gval * mtw * dm0)
        ge1 = ge1 + kt_coef * (m2 * Gv1 + f64(2.0) * gval * mtw * dm1)
        gth1 = f64(2.0) * kt_coef * gval * mtw
        gth0 = -gth1

    for k in range(3):
        _add_grad(grad_out, joint_dofs[j, k], -ge0[k])
        _add_grad(grad_out, joint_dofs[j, 3 + k], ge0[k] - ge1[k])
        _add_grad(grad_out, joint_dofs[j, 6 + k], ge1[k])
    if twist_enabled != 0:
        _add_grad(grad_out, joint_dofs[j, 9], gth0)
        _add_grad(grad_out, joint_dofs[j, 10], gth1)
    if want_hess == 0:
        return

    F_aa = K * (G_aa * tval + f64(2.0) * G_a * T_a + gval * T_aa)
    F_bb = K * (G_bb * tval + f64(2.0) * G_b * T_b + gval * T_bb)
    F_ab = K * (G_ab * tval + G_a * T_b + G_b * T_a + gval * T_ab)
    F_ad = K * (G_a * T_d + gval * T_ad)
    F_bd = K * (G_b * T_d + gval * T_bd)
    F_dd = K * gval * T_dd
    eye = wp.identity(n=3, dtype=wp.float64)
    va = f64(2.0) * e0
    vb = f64(2.0) * e1
    # Chain rule through u = (a, b, d): da/de0 = 2 e0, db/de1 = 2 e1, dd/de0 = e1, dd/de1 = e0.
    H00 = F_aa * _outer(va, va) + F_ad * (_outer(va, e1) + _outer(e1, va)) + F_dd * _outer(
        e1, e1) + (f64(2.0) * F_a) * eye
    H11 = F_bb * _outer(vb, vb) + F_bd * (_outer(vb, e0) + _outer(e0, vb)) + F_dd * _outer(
        e0, e0) + (f64(2.0) * F_b) * eye
    H01 = F_ab * _outer(va, vb) + F_ad * _outer(va, e0) + F_bd * _outer(e1, vb) + F_dd * _outer(
        e1, e0) + F_d * eye
    # Edge-theta coupling vectors W_k = d2E/(de_k dtheta_after); d/dtheta_before = -W_k.
    W0 = wp.vec3d(f64(0.0), f64(0.0), f64(0.0))
    W1 = wp.vec3d(f64(0.0), f64(0.0), f64(0.0))
    htt = f64(0.0)
    if twist_enabled != 0:
        m2 = mtw * mtw
        t0 = e0 / n0
        t1 = e1 / n1
        chi = f64(1.0) + wp.dot(t0, t1)
        tilde_t = (t0 + t1) / chi
        # Reference twist Hessian (Jawed et al. 2018, sec. 7).
        D2m00 = (-f64(0.25) / a) * (_outer(kb, t0 + tilde_t) + _outer(t0 + tilde_t, kb))
        D2m11 = (-f64(0.25) / b) * (_outer(kb, t1 + tilde_t) + _outer(t1 + tilde_t, kb))
        D2m01 = (f64(0.5) / nn) * ((f64(2.0) / chi) * wp.skew(t0) - _outer(kb, tilde_t))
        HG00 = (f64(4.0) * G_aa) * _outer(e0, e0) + (f64(2.0) * G_a) * eye
        HG11 = (f64(4.0) * G_bb) * _outer(e1, e1) + (f64(2.0) * G_b) * eye
        HG01 = (f64(4.0) * G_ab) * _outer(e0, e1)
        tg = f64(2.0) * mtw
        tw = f64(2.0) * gval
        H00 = H00 + kt_coef * (m2 * HG00 + tg * (_outer(Gv0, dm0) + _outer(dm0, Gv0))
                               + tw * (_outer(dm0, dm0) + mtw * D2m00))
        H11 = H11 + kt_coef * (m2 * HG11 + tg * (_outer(Gv1, dm1) + _outer(dm1, Gv1))
                               + tw * (_outer(dm1, dm1) + mtw * D2m11))
        H01 = H01 + kt_coef * (m2 * HG01 + tg * (_outer(Gv0, dm1) + _outer(dm0, Gv1))
                               + tw * (_outer(dm0, dm1) + mtw * D2m01))
        W0 = kt_coef * (tg * Gv0 + tw * dm0)
        W1 = kt_coef * (tg * Gv1 + tw * dm1)
        htt = f64(2.0) * kt_coef * gval

    # Map edge space (e0, e1) to vertices: x_{i-1}: -e0, x_i: e0 - e1, x_{i+1}: e1.
    H10 = wp.transpose(H01)
    B00 = H00
    B01 = -H00 + H01
    B02 = -H01
    B11 = H00 - H01 - H10 + H11
    B12 = H01 - H11
    B22 = H11
    _scatter_block(hess_slot_in, j, 11, 0, 0, B00, hess_out)
    _scatter_block(hess_slot_in, j, 11, 0, 3, B01, hess_out)
    _scatter_block(hess_slot_in, j, 11, 3, 0, wp.transpose(B01), hess_out)
    _scatter_block(hess_slot_in, j, 11, 0, 6, B02, hess_out)
    _scatter_block(hess_slot_in, j, 11, 6, 0, wp.transpose(B02), hess_out)
    _scatter_block(hess_slot_in, j, 11, 3, 3, B11, hess_out)
    _scatter_block(hess_slot_in, j, 11, 3, 6, B12, hess_out)
    _scatter_block(hess_slot_in, j, 11, 6, 3, wp.transpose(B12), hess_out)
    _scatter_block(hess_slot_in, j, 11, 6, 6, B22, hess_out)
    if twist_enabled != 0:
        # Column theta_after (10) gets W mapped to vertices; theta_before (9) gets -that.
        _scatter_col(hess_slot_in, j, 11, 0, 10, -W0, hess_out)
        _scatter_col(hess_slot_in, j, 11, 3, 10, W0 - W1, hess_out)
        _scatter_col(hess_slot_in, j, 11, 6, 10, W1, hess_out)
        _scatter_col(hess_slot_in, j, 11, 0, 9, W0, hess_out)
        _scatter_col(hess_slot_in, j, 11, 3, 9, W1 - W0, hess_out)
        _scatter_col(hess_slot_in, j, 11, 6, 9, -W1, hess_out)
        _scatter_scalar(hess_slot_in, j, 11, 9, 9, htt, hess_out)
        _scatter_scalar(hess_slot_in, j, 11, 10, 10, htt, hess_out)
        _scatter_scalar(hess_slot_in, j, 11, 9, 10, -htt, hess_out)
        _scatter_scalar(hess_slot_in, j, 11, 10, 9, -htt, hess_out)


@wp.func
def _parallel_transport(u: wp.vec3d, t1: wp.vec3d, t2: wp.vec3d) -> wp.vec3d:
    # Rotate u by the rotation taking unit t1 to unit t2 about t1 x t2 (Bergou 2008 sec. 4.1).
    bvec = wp.cross(t1, t2)
    nb = wp.length(bvec)
    if nb < f64(1.0e-14):
        return u
    bh = bvec / nb
    n1 = wp.cross(t1, bh)
    n2 = wp.cross(t2, bh)
    return wp.dot(u, t1) * t2 + wp.dot(u, n1) * n2 + wp.dot(u, bh) * bh


@wp.kernel
def transport_frames_kernel(
    # Model:
    edge_vertex: wp.array(dtype=wp.vec2i),
    # Data in:
    x_in: wp.array(dtype=wp.vec3d),
    d1_base_in: wp.array(dtype=wp.vec3d),
    t_base_in: wp.array(dtype=wp.vec3d),
    # Out:
    d1_out: wp.array(dtype=wp.vec3d),
    t_out: wp.array(dtype=wp.vec3d),
):
    # Time-parallel transport of each edge's reference director (Bergou 2010 sec. 4.1).
    j = wp.tid()
    v = edge_vertex[j]
    t = wp.normalize(x_in[v[1]] - x_in[v[0]])
    d1 = _parallel_transport(d1_base_in[j], t_base_in[j], t)
    d1 = wp.normalize(d1 - wp.dot(d1, t) * t)
    d1_out[j] = d1
    t_out[j] = t


@wp.kernel
def reference_twist_kernel(
    # Model:
    joint_edge: wp.array(dtype=wp.vec2i),
    # Data in:
    d1_in: wp.array(dtype=wp.vec3d),
    t_in: wp.array(dtype=wp.vec3d),
    m_ref_base_in: wp.array(dtype=wp.float64),
    # Out:
    m_ref_out: wp.array(dtype=wp.float64),
):
    # Reference twist: signed angle from the space-parallel transport of d1 of the edge
    # before onto the edge after, to d1 of the edge after, about its tangent (Bergou 2010
    # sec. 4.2); unwrapped next to the previous value so that link is never lost.
    j = wp.tid()
    je = joint_edge[j]
    ta = t_in[je[0]]
    tb = t_in[je[1]]
    u = _parallel_transport(d1_in[je[0]], ta, tb)
    v = d1_in[je[1]]
    ang = wp.atan2(wp.dot(wp.cross(u, v), tb), wp.dot(u, v))
    base = m_ref_base_in[j]
    two_pi = f64(6.283185307179586)
    diff = ang - base
    diff = diff - two_pi * wp.floor((diff + f64(3.141592653589793)) / two_pi)
    m_ref_out[j] = base + diff
