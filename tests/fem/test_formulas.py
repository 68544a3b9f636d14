"""Closed-form pieces that need no FEM: Hertz formulas, overlap split, power fits."""

import math

import pytest

from tightknot.fem import hertz, overlap


def test_line_approach_inverts():
    # brentq round trip: the inverse must reproduce the forward relation to its own
    # tolerance (rtol 1e-13), so 1e-9 leaves room only for floating point
    radius, e, nu = 4.25e-3, 1.25e6, 0.5
    for w in (1e-6, 1e-5, 1e-4, 4e-4):
        p = hertz.line_force_per_length(w, radius, e, nu)
        assert hertz.line_approach_per_side(p, radius, e, nu) == pytest.approx(w, rel=1e-9)


def test_line_pressure_matches_johnson_445():
    # Johnson (1985) eq. 4.45: p0 = sqrt(P E* / (pi R)) must equal 2P/(pi b) with eq. 4.43
    radius, e_star, p = 4.25e-3, 1.25e6 / 0.75, 30.0
    b = hertz.line_half_width(p, radius, e_star)
    assert hertz.line_peak_pressure(p, b) == pytest.approx(
        math.sqrt(p * e_star / (math.pi * radius)), rel=1e-12)


def test_sphere_peak_pressure_closed_form():
    # p0 = (2/pi) E* sqrt(d/R) follows from eqs. 4.21-4.23; exact identity
    radius, e_star, d = 4.25e-3, 1.25e6 / 0.75, 3e-5
    f = hertz.sphere_force(d, radius, e_star)
    a = hertz.sphere_contact_radius(d, radius)
    assert hertz.sphere_peak_pressure(f, a) == pytest.approx(
        2.0 / math.pi * e_star * math.sqrt(d / radius), rel=1e-12)


def test_rigid_contact_modulus_is_not_the_two_body_one():
    # rigid counter-body: E* = E/(1-nu^2), twice the identical-bodies value
    assert hertz.contact_modulus_rigid(1.0, 0.5) == pytest.approx(4.0 / 3.0)


def test_overlap_split_power_and_general_agree():
    # the closed-form split of power laws must solve the equal-force condition
    k, p, e = 0.3, 1.3, 1.25e6
    d_i, d_j, delta = 8.5e-3, 5e-3, 1e-3

    def law(d):
        return lambda w: k * e * d * (max(w, 0.0) / d) ** p

    w_i, w_j = overlap.split_overlap_power(delta, d_i, d_j, p, length_power=1)
    assert w_i + w_j == pytest.approx(delta, rel=1e-14)
    assert law(d_i)(w_i) == pytest.approx(law(d_j)(w_j), rel=1e-12)
    g_i, g_j, _ = overlap.split_overlap(delta, law(d_i), law(d_j))
    assert g_i == pytest.approx(w_i, rel=1e-9)


def test_identical_rods_split_in_half():
    assert overlap.split_overlap_power(2e-3, 1.0, 1.0, 1.5, 2) == pytest.approx((1e-3, 1e-3))
    assert overlap.pair_overlap(1.0, 1.0, 1.5) == pytest.approx(0.5)
