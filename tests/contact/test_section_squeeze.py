"""The section between two plates: exact derivatives, the undeformed start, the area kept."""

import math

import numpy as np
import pytest

from tightknot.contact.section_modes import boundary_radius
from tightknot.contact.section_squeeze import SectionSqueeze


def test_gradient_and_hessian_match_finite_differences() -> None:
    sq = SectionSqueeze(max_mode=8)
    state, a = sq.solve(0.08)
    a = a + 1e-3 * np.arange(1, len(a) + 1)  # off the minimum, with samples in contact
    e, g, h = sq.energy(a, 0.08)
    eps = 1e-7
    eye = np.eye(len(a))
    g_fd = np.array([(sq.energy(a + eps * d, 0.08)[0] - sq.energy(a - eps * d, 0.08)[0])
                     / (2 * eps) for d in eye])
    h_fd = np.array([(sq.energy(a + eps * d, 0.08)[1] - sq.energy(a - eps * d, 0.08)[1])
                     / (2 * eps) for d in eye])
    # central differences of a C2 function: truncation ~eps^2 |E'''| and round-off
    # ~1e-16 |E| / eps, both below 1e-7 of the entries here
    assert np.allclose(g, g_fd, rtol=1e-6, atol=1e-9)
    assert np.allclose(h, h_fd, rtol=1e-6, atol=1e-7)


def test_no_approach_leaves_the_circle_and_a_squeeze_keeps_the_area() -> None:
    sq = SectionSqueeze(max_mode=8)
    state, a = sq.solve(0.0)
    assert np.all(a == 0.0) and state.force_per_length_over_e_d0 == 0.0
    state, a = sq.solve(0.1)
    assert state.force_per_length_over_e_d0 > 0.0
    modes = np.zeros((7, 2))
    modes[[n - 2 for n in sq.modes], 0] = a
    theta = np.linspace(0.0, 2.0 * math.pi, 20001)
    r = boundary_radius(theta, state.mean_radius_over_d0, modes)
    area = 0.5 * np.trapezoid(r**2, theta)
    assert area == pytest.approx(math.pi / 4.0, rel=1e-10)  # D0 = 1: A0 = pi / 4
    # flattened towards the plates (theta = 0 is the plate normal): a_2 < 0
    assert a[0] < 0.0
    # the penalty is a device: the plates are entered by less than a fiftieth of the approach
    assert state.max_penetration_over_d0 < 0.1 / 50.0


def test_bad_input_is_refused() -> None:
    with pytest.raises(ValueError, match="max_mode"):
        SectionSqueeze(max_mode=1)
    with pytest.raises(ValueError, match="w_over_d0"):
        SectionSqueeze().solve(0.6)
