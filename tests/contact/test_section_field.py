"""The section field along a straight rod: exact derivatives, the incompressible Poisson
effect, bad input."""

import math

import numpy as np
import pytest

from tightknot.contact.section_field import StraightSectionedRod, decay_length


@pytest.mark.parametrize("body", ["cylinder", "plates"])
def test_gradient_and_hessian_match_finite_differences(body: str) -> None:
    rod = StraightSectionedRod(body, max_mode=6, half_length=0.6, edges=12, samples=256)
    _, u = rod.solve(0.05)
    u = u + 1e-4 * np.random.default_rng(0).standard_normal(rod.ndof)  # off equilibrium
    _, g, h = rod.energy(u, 0.05)
    eps = 1e-7
    eye = np.eye(rod.ndof)
    g_fd = np.array([(rod.energy(u + eps * d, 0.05)[0] - rod.energy(u - eps * d, 0.05)[0])
                     / (2 * eps) for d in eye])
    h_fd = np.array([(rod.energy(u + eps * d, 0.05)[1] - rod.energy(u - eps * d, 0.05)[1])
                     / (2 * eps) for d in eye])
    # central differences of a C2 energy: truncation ~eps^2 and round-off ~1e-16 E / eps,
    # below 1e-6 of the largest entry (measured 1e-9 to 3e-8)
    assert np.max(np.abs(g - g_fd)) <= 1e-6 * np.max(np.abs(g))
    assert np.max(np.abs(h - h_fd)) <= 1e-6 * np.max(np.abs(h))


def test_the_soft_crossing_has_an_exact_gradient_and_a_gauss_newton_hessian() -> None:
    rod = StraightSectionedRod("rod", max_mode=6, half_length=0.6, edges=12, samples=256)
    _, u = rod.solve(0.03)
    u = u + 1e-4 * np.random.default_rng(0).standard_normal(rod.ndof)
    _, g, h = rod.energy(u, 0.03)
    eps = 1e-8  # the penalty's stiff onset makes the truncation error (eps^2) large
    g_fd = np.array([(rod.energy(u + eps * d, 0.03)[0] - rod.energy(u - eps * d, 0.03)[0])
                     / (2 * eps) for d in np.eye(rod.ndof)])
    # measured 3.7e-9 at eps = 1e-8, falling as eps^2 (3.8e-7 at 1e-7): exact
    assert np.max(np.abs(g - g_fd)) <= 1e-7 * np.max(np.abs(g))
    h_fd = np.array([(rod.energy(u + 1e-7 * d, 0.03)[1] - rod.energy(u - 1e-7 * d, 0.03)[1])
                     / 2e-7 for d in np.eye(rod.ndof)])
    # the contact part drops phi' times the penetration's second derivative (docstring):
    # measured 0.4 % of the largest entry; an error in the kept part would be O(1)
    assert np.max(np.abs(h - h_fd)) <= 0.02 * np.max(np.abs(h))


def test_a_soft_crossing_is_stiffer_than_a_rigid_one_at_the_same_approach() -> None:
    # Two identical soft rods at per-rod approach w against a rod on a rigid cylinder at w:
    # Hertz gives sqrt(2) at small approach (half the contact modulus over twice the
    # approach); once the patch spans the section the flatter contact surface adds more
    # (measured 1.50 at w = 0.024 D0 to 2.05 at 0.15 D0, with 75 edges). The compliant
    # level's even split of the overlap predicts 1 (issue 18).
    ws = [0.024, 0.0375]
    rigid = StraightSectionedRod("cylinder", 8, half_length=1.0, edges=25, samples=256)
    soft = StraightSectionedRod("rod", 8, half_length=1.0, edges=25, samples=256)
    for r, s in zip(rigid.path(ws), soft.path(ws), strict=True):
        ratio = s.force_over_e_d0sq / r.force_over_e_d0sq
        assert math.sqrt(2.0) < ratio < 2.1, ratio


def test_plates_along_the_whole_rod_stretch_it_as_an_incompressible_rod() -> None:
    # Plates along the whole rod press every section alike: no gradient acts, and the rod is
    # free to lengthen. With no axial stress, the mean of sigma_yy over the section is
    # -F (D0 - 2 w) / A0 per unit length (F the force of one plate on it, D0 - 2 w the plates'
    # distance) and sigma_xx's mean is 0, so an incompressible rod (nu = 1/2) stretches by
    # lambda - 1 = F (D0 - 2 w) / (2 E A0) to first order in w; the model does so through
    # R = sqrt(R0^2 / lambda - ...) alone (module docstring).
    w = 0.01
    half = 0.4
    rod = StraightSectionedRod("plates", max_mode=8, half_length=half, edges=8, samples=512)
    state, u = rod.solve(w)
    z, a = rod.split(u)
    lam = np.diff(z) / rod.h
    assert np.allclose(lam, lam[0], rtol=1e-9) and np.allclose(a, a[0], atol=1e-12)
    f = state.force_over_e_d0sq / (2.0 * half)  # per unit length, E = D0 = 1
    expected = f * (1.0 - 2.0 * w) / (2.0 * math.pi / 4.0)
    # second order in w: measured 1.3 % above at w = 0.01 D0 (4.9 % at 0.04, 8.4 % at 0.08)
    assert lam[0] - 1.0 == pytest.approx(expected, rel=0.03)
    assert state.area_ratio_mid == pytest.approx(1.0 / lam[0], rel=1e-12)


def test_measured_decay_lengths_and_the_extrapolated_ones_are_told_apart() -> None:
    assert decay_length(2) == (0.183, True)
    length, measured = decay_length(8)
    assert not measured and length == pytest.approx(0.077 * 4 / 8)
    assert StraightSectionedRod(max_mode=8).extrapolated == [6, 8]
    assert math.isfinite(StraightSectionedRod(max_mode=4).solve(0.01)[0].force_over_e_d0sq)


def test_bad_input_is_refused() -> None:
    with pytest.raises(ValueError, match="body"):
        StraightSectionedRod("sphere")
    with pytest.raises(ValueError, match="max_mode"):
        StraightSectionedRod(max_mode=1)
    with pytest.raises(ValueError, match="w must be"):
        StraightSectionedRod().solve(0.7)
