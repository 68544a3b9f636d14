"""The section's Fourier modes: boundary, area (Parseval) and the closed-form mode energy."""

import math

import numpy as np
import pytest

from tightknot.contact.section_modes import (
    boundary_radius,
    mean_radius,
    mode_amplitudes,
    mode_energy,
    mode_stiffness,
)


def test_the_mean_radius_keeps_the_area_of_the_deformed_boundary() -> None:
    modes = np.array([[0.3e-3, -0.2e-3], [0.1e-3, 0.05e-3], [-0.08e-3, 0.0]])
    area = math.pi * 4.25e-3**2
    r0 = mean_radius(area, modes)
    theta = np.linspace(0.0, 2.0 * math.pi, 4001)[:-1]
    r = boundary_radius(theta, r0, modes)
    # polar area (1/2) int r^2 dtheta by the periodic trapezoid rule, exact for these
    # trigonometric polynomials up to round-off
    assert 0.5 * np.mean(r**2) * 2.0 * math.pi == pytest.approx(area, rel=1e-12)
    assert r0 < 4.25e-3  # the modes take area that the mean radius gives up


def test_mode_amplitudes_recover_the_modes_of_an_uneven_sampling() -> None:
    rng = np.random.default_rng(3)
    theta = np.sort(rng.uniform(-math.pi, math.pi, 3))
    theta = np.concatenate([theta, np.linspace(-math.pi, math.pi, 400, endpoint=False)])
    u = 0.2 * np.cos(3 * theta) - 0.1 * np.sin(3 * theta) + 0.05 * np.cos(2 * theta)
    a, b = mode_amplitudes(theta, u, 3)
    # the few extra samples make the weights uneven: trapezoid error O(h^2) ~ 1e-4
    assert a == pytest.approx(0.2, abs=1e-3)
    assert b == pytest.approx(-0.1, abs=1e-3)


def test_the_mode_energy_grows_as_n_minus_one_over_n() -> None:
    e = 1.25e6
    assert mode_stiffness(2, e) == pytest.approx(2.0 * math.pi * (e / 3.0) * 1.5)
    assert mode_energy(4, 1e-4, e) == pytest.approx(0.5 * mode_stiffness(4, e) * 1e-8)
    for bad in (0, 1, 2.5):
        with pytest.raises(ValueError, match="mode number n"):
            mode_stiffness(bad, e)
    with pytest.raises(ValueError, match="youngs_modulus"):
        mode_stiffness(2, 0.0)
    with pytest.raises(ValueError, match="leave no mean radius"):
        mean_radius(1e-6, np.array([[1e-3, 0.0]]))
