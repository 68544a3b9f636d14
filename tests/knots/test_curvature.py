"""Bergou vertex curvature and the study's smoothing against analytic curves."""

import numpy as np
import pytest

from tightknot.knots import curves
from tightknot.knots.curvature import bergou_curvature, find_spikes
from tightknot.knots.smoothing import gaussian_weights, study_smooth


@pytest.mark.parametrize("n", [20, 100, 1000])
def test_circle_exact_discrete_value(n):
    radius = 0.3
    k = bergou_curvature(curves.circle(n, radius), closed=True)
    # Regular n-gon: turning angle 2 pi/n, edge 2 R sin(pi/n), so 2 tan(pi/n)/(2 R sin(pi/n))
    # = 1/(R cos(pi/n)): an O((pi/n)^2 / 2) overestimate of 1/R, reproduced to round-off.
    # rtol 1e-9: |e x e'| loses digits as the turning angle shrinks (relative round-off
    # ~ eps / (2 pi / n)^2 ~ 6e-12 at n = 1000).
    np.testing.assert_allclose(k, 1 / (radius * np.cos(np.pi / n)), rtol=1e-9)
    assert abs(k.mean() * radius - 1) <= (np.pi / n) ** 2  # discretisation error bound


def test_helix_raw():
    a, b = 0.02, 0.005
    pts = curves.helix(2001, a, b, turns=4)
    k = bergou_curvature(pts, closed=False)
    exact = a / (a * a + b * b)
    # Edge h = sqrt(a^2 + b^2) * dt; the turning-angle formula overestimates by O((kappa h)^2)
    # ~ (8 pi / 2000)^2 ~ 1.6e-4: allow 5e-4.
    np.testing.assert_allclose(k[1:-1], exact, rtol=5e-4)
    assert k[0] == 0.0 and k[-1] == 0.0  # documented end convention


def test_circle_smoothed_matches_gaussian_shrinkage():
    radius = 1.0
    n0 = 600
    pts = curves.circle(n0, radius)
    # Step = the polygon's own edge, so resampling returns the same regular 600-gon and the
    # smoothing alone is tested (resampling a coarser polygon concentrates its turning at the
    # old corners, a separate, resolution-dependent effect).
    step = 2 * radius * np.sin(np.pi / n0)
    sm = study_smooth(pts, True, step, n_gauss=25)
    n = sm.shape[0]
    win = int(round(n / 25))
    w = gaussian_weights(win / 5.0, (win - 1) // 2)
    # Averaging a circle with weights w_k at angles k dtheta scales its radius by
    # f = sum_k w_k cos(k dtheta) (~ exp(-sigma^2 / 2R^2)), so kappa = 1/(f R) up to the
    # n-gon factor 1/cos(pi/n); both exact for a regular polygon, so rtol 1e-9 (round-off).
    dtheta = 2 * np.pi / n
    half = (win - 1) // 2
    f = float(np.sum(w * np.cos(np.arange(-half, half + 1) * dtheta)))
    k = bergou_curvature(sm, True)
    exact = 1 / (f * radius * np.cos(np.pi / n))
    assert sm.shape[0] == n0
    np.testing.assert_allclose(k, exact, rtol=1e-9)
    assert f < 1 - 1e-4  # the shrinkage is real, so the test would see it ignored


def test_helix_smoothed():
    a, b = 0.02, 0.005
    pts = curves.helix(3001, a, b, turns=5)
    length = 5 * 2 * np.pi * np.hypot(a, b)
    step = length / 1500
    sm = study_smooth(pts, False, step, n_gauss=25)
    n = sm.shape[0]
    win = int(round(n / 25))
    half = (win - 1) // 2
    w = gaussian_weights(win / 5.0, half)
    dt = step / np.hypot(a, b)
    f = float(np.sum(w * np.cos(np.arange(-half, half + 1) * dt)))
    # Smoothing shrinks the helix radius to f a and keeps its linear z (b t): kappa' =
    # f a / ((f a)^2 + b^2). Interior only (a window away from the truncated ends).
    exact = f * a / ((f * a) ** 2 + b * b)
    k = bergou_curvature(sm, False)[win:-win]
    np.testing.assert_allclose(k, exact, rtol=5e-4)  # O((kappa h)^2) as in test_helix_raw
    assert abs(exact - a / (a * a + b * b)) / exact > 1e-3  # shrinkage is resolvable


def test_find_spikes_wraps_on_closed_curves():
    s = np.arange(10.0)
    kappa = np.array([3, 0, 0, 3, 3, 0, 0, 0, 0, 3.0])
    spikes = find_spikes(kappa, s, 1.0, closed=True)
    assert len(spikes) == 2  # the run 9,0 wraps
    assert len(find_spikes(kappa, s, 1.0, closed=False)) == 3
