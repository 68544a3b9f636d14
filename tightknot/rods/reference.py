"""A slow, obvious NumPy version of the elastic energies: the test oracle of the Warp kernels.

Everything here is written from the definitions, one edge or joint at a time, sharing no
code with :mod:`tightknot.rods.elastic_kernels` or :mod:`tightknot.rods.frames`, so that the
kernels (and their bookkeeping) are checked against an independent computation.

Energies [J] (Bergou, Wardetzky, Robinson, Audoly, Grinspun 2008, "Discrete elastic rods",
hereafter B08; Bergou, Audoly, Vouga, Wardetzky, Grinspun 2010, "Discrete viscous threads",
hereafter B10):

* Stretch of edge j (incompressible neo-Hookean bar in uniaxial stretch, Treloar 1975)::

      E_s = mu A0 l_bar / 2 (lam^2 + 2/lam - 3),   lam = |e| / l_bar,

  mu = E/3, A0 = pi D0^2/4 (the model stores mu A0 as ``edge_mu_area``).
* Bend at joint i with edges e0 (before) and e1 (after), curvature binormal B08 eq. 1::

      kb = 2 e0 x e1 / (|e0| |e1| + e0 . e1),
      E_b = EI0 lam_v^(-4 nu) |kb|^2 / l,

  l = |e0| + |e1| (deformed, twice the Voronoi length of B08 eq. 3), l_bar its rest value,
  lam_v = l / l_bar, EI0 = E pi D0^4 / 64; lam_v^(-4 nu) is the section thinning
  r = r0 lam^(-nu) raised to the fourth power.
* Twist at joint i (B10 sec. 4.2, B08 eq. 5)::

      E_t = GJ0 lam_v^(-4 nu) m^2 / l,   GJ0 = G pi D0^4 / 32,  G = E / (2 (1 + nu)),

  m the twist of the *material* frame between the two edges: the material director
  m1 = cos(theta) d1 + sin(theta) d2 (d2 = t x d1) of the edge before, parallel-transported
  onto the edge after (the rotation about t0 x t1 that takes t0 to t1, B08 sec. 4.1), then
  the signed angle from it to m1 of the edge after, about that edge's tangent. This is
  ``theta_after - theta_before + m_ref`` modulo 2 pi, computed without theta differences or
  the reference twist, so it checks the reference-twist bookkeeping of the kernels too.

The kernels fold the thinning into one exponent, ``joint_thinning_exponent`` q = 4 nu + 1,
since lam_v^(-4 nu) / l = lam_v^(-q) / l_bar; the oracle writes the formula as above and takes
E, nu and D0 from each rod's :class:`~tightknot.rods.material.Material` and diameter rather
than from the model's per-edge and per-joint stiffness arrays.

The 2 pi ambiguity of the twist: the frames alone give m only modulo 2 pi. The simulation
tracks m continuously (never wrapped), so a closed rod keeps whole turns of link, recorded
at its closing joint as ``model.joint_link_offset`` = 2 pi k. The oracle takes the value of
m congruent to the frame angle that lies nearest to the *unwrap hint*
``theta_after - theta_before + m_ref_hint``, where ``m_ref_hint`` defaults to
``model.joint_link_offset`` (0 at every joint but the closing joint of a closed rod given
``link_offset``). That default assumes the geometric part of the reference twist (m_ref
minus its link offset) lies within (-pi, pi), true for space-parallel initial frames and for
moderate motion from them; after long runs in which a reference twist winds past pi, pass
the tracked ``state.m_ref`` as ``m_ref_hint`` (the hint then only picks the whole turn, the
fractional part still comes from the frames).
"""

from __future__ import annotations

import math

import numpy as np

from tightknot.rods.model import Model

#: Tolerance on |d1| - 1 and d1 . t for the given reference directors [-].
_FRAME_TOL = 1e-8


def _rotate_about(v: np.ndarray, axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotate ``v`` by ``angle`` [rad] about unit ``axis`` (Rodrigues' formula)."""
    c, s = math.cos(angle), math.sin(angle)
    return v * c + np.cross(axis, v) * s + axis * np.dot(axis, v) * (1.0 - c)


def parallel_transport(v: np.ndarray, t_from: np.ndarray, t_to: np.ndarray) -> np.ndarray:
    """Transport ``v`` from unit tangent ``t_from`` to unit tangent ``t_to`` (B08 sec. 4.1).

    The rotation about ``t_from x t_to`` by the angle between the tangents; the identity
    when they are parallel. Written as an axis-angle rotation, not in the (t, n, b) basis
    the kernels use.
    """
    b = np.cross(t_from, t_to)
    nb = float(np.linalg.norm(b))
    if nb == 0.0:
        return v.copy()
    angle = math.atan2(nb, float(np.dot(t_from, t_to)))
    return _rotate_about(v, b / nb, angle)


def signed_angle(u: np.ndarray, v: np.ndarray, axis: np.ndarray) -> float:
    """Angle [rad] in (-pi, pi] that rotates ``u`` onto ``v`` about unit ``axis``."""
    return math.atan2(float(np.dot(np.cross(u, v), axis)), float(np.dot(u, v)))


def curvature_binormal(e0: np.ndarray, e1: np.ndarray) -> np.ndarray:
    """kb = 2 e0 x e1 / (|e0||e1| + e0.e1) [-] of two consecutive edges (B08 eq. 1)."""
    return 2.0 * np.cross(e0, e1) / (np.linalg.norm(e0) * np.linalg.norm(e1) + np.dot(e0, e1))


def material_director(t: np.ndarray, d1: np.ndarray, theta: float) -> np.ndarray:
    """m1 = cos(theta) d1 + sin(theta) (t x d1) of an edge (B08 sec. 4.1)."""
    return math.cos(theta) * d1 + math.sin(theta) * np.cross(t, d1)


def material_twist(
    t0: np.ndarray, m1_0: np.ndarray, t1: np.ndarray, m1_1: np.ndarray, hint: float
) -> float:
    """Twist [rad] of the material frame from edge 0 to edge 1, nearest to ``hint``.

    ``m1_0`` is transported onto edge 1 and its signed angle to ``m1_1`` about ``t1`` is
    taken; the frames fix it modulo 2 pi, ``hint`` picks the turn (module docstring).
    """
    phi = signed_angle(parallel_transport(m1_0, t0, t1), m1_1, t1)
    return phi + 2.0 * math.pi * round((hint - phi) / (2.0 * math.pi))


def reference_energies(
    model: Model,
    x: np.ndarray,
    theta: np.ndarray,
    d1_ref: np.ndarray,
    edge_rest_length: np.ndarray | None = None,
    m_ref_hint: np.ndarray | None = None,
) -> dict[str, float]:
    """Stretch, bend and twist energies [J] of ``model`` at the given configuration.

    Args:
        model: the rods (topology, stiffnesses, link offsets).
        x: vertex positions [m], shape (vertex_count, 3).
        theta: twist angle of each edge's material frame from its reference frame [rad],
            shape (edge_count,); ignored when the model has no twist.
        d1_ref: reference director of each edge, unit and normal to the edge at ``x``,
            shape (edge_count, 3).
        edge_rest_length: rest length of each edge [m]; default the model's.
        m_ref_hint: per joint [rad], only picks the whole turn of each twist (module
            docstring); default ``model.joint_link_offset``.

    Returns:
        ``dict(stretch=, bend=, twist=)`` [J]; twist is 0 for a model without twist.

    Raises:
        ValueError: on a shape mismatch or a ``d1_ref`` that is not a unit normal.
    """
    x = np.asarray(x, dtype=np.float64)
    d1_ref = np.asarray(d1_ref, dtype=np.float64)
    theta = np.asarray(theta, dtype=np.float64)
    rest = np.asarray(
        model.edge_rest_length if edge_rest_length is None else edge_rest_length, np.float64
    )
    hint = np.asarray(
        model.joint_link_offset if m_ref_hint is None else m_ref_hint, dtype=np.float64
    )
    ne, nj = model.edge_count, model.joint_count
    for name, arr, shape in (
        ("x", x, (model.vertex_count, 3)), ("d1_ref", d1_ref, (ne, 3)),
        ("edge_rest_length", rest, (ne,)), ("m_ref_hint", hint, (nj,)),
    ):
        if arr.shape != shape:
            raise ValueError(f"{name} must have shape {shape}, got {arr.shape}")
    if model.twist and theta.shape != (ne,):
        raise ValueError(f"theta must have shape {(ne,)}, got {theta.shape}")

    # Edge vectors, tangents and material directors, one edge at a time.
    edge_vec, tangent, m1 = [], [], []
    for j in range(ne):
        a, b = model.edge_vertex[j]
        e = x[b] - x[a]
        t = e / np.linalg.norm(e)
        d1 = d1_ref[j]
        if abs(np.linalg.norm(d1) - 1.0) > _FRAME_TOL or abs(np.dot(d1, t)) > _FRAME_TOL:
            raise ValueError(f"d1_ref[{j}] must be a unit vector normal to edge {j}")
        edge_vec.append(e)
        tangent.append(t)
        m1.append(material_director(t, d1, float(theta[j])) if model.twist else None)

    stretch = bend = twist = 0.0
    for rod in model.rods:
        # Section stiffnesses from the rod's material and diameter, not from the model's
        # per-joint arrays, so that the builder's arithmetic is checked as well.
        mat, d0 = rod.material, rod.diameter
        nu = mat.poisson_ratio
        mu_area = mat.youngs_modulus / 3.0 * math.pi * d0**2 / 4.0  # mu A0 [N]
        ei0 = mat.youngs_modulus * math.pi * d0**4 / 64.0  # EI0 [N m^2]
        gj0 = mat.youngs_modulus / (2.0 * (1.0 + nu)) * math.pi * d0**4 / 32.0  # GJ0 [N m^2]
        for j in range(rod.edge_start, rod.edge_start + rod.edge_count):
            lam = np.linalg.norm(edge_vec[j]) / rest[j]
            stretch += mu_area * rest[j] / 2.0 * (lam**2 + 2.0 / lam - 3.0)
        for i in range(rod.joint_start, rod.joint_start + rod.joint_count):
            ja, jb = model.joint_edge[i]
            e0, e1 = edge_vec[ja], edge_vec[jb]
            ell = np.linalg.norm(e0) + np.linalg.norm(e1)
            lam_v = ell / (rest[ja] + rest[jb])
            thinning = lam_v ** (-4.0 * nu)
            kb = curvature_binormal(e0, e1)
            bend += ei0 * thinning * np.dot(kb, kb) / ell
            if model.twist:
                m = material_twist(
                    tangent[ja], m1[ja], tangent[jb], m1[jb],
                    float(theta[jb] - theta[ja] + hint[i]),
                )
                twist += gj0 * thinning * m**2 / ell
    return dict(stretch=float(stretch), bend=float(bend), twist=float(twist))
