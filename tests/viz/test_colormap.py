"""Colour maps: shapes, dtype, limits, NaN and constant fields."""

import numpy as np
import pytest

from tightknot.viz.colormap import NAN_RGBA, colorize, field_limits, normalize


def test_shape_and_dtype() -> None:
    values = np.linspace(0.0, 1.0, 7)
    rgba = colorize(values)
    rgb = colorize(values, alpha=False)
    assert rgba.shape == (7, 4) and rgba.dtype == np.uint8
    assert rgb.shape == (7, 3) and rgb.dtype == np.uint8
    assert np.array_equal(rgba[:, :3], rgb)
    assert np.all(rgba[:, 3] == 255)


def test_ends_of_viridis_and_monotone_change() -> None:
    rgb = colorize(np.array([0.0, 1.0]), "viridis", alpha=False).astype(int)
    # viridis runs from dark purple (68, 1, 84) to yellow (253, 231, 37); matplotlib rounds to
    # bytes, so allow 1 unit.
    assert np.all(np.abs(rgb[0] - (68, 1, 84)) <= 1)
    assert np.all(np.abs(rgb[1] - (253, 231, 37)) <= 1)


def test_explicit_limits_clip() -> None:
    rgb = colorize(np.array([-5.0, 0.0, 2.0, 9.0]), "magma", limits=(0.0, 2.0), alpha=False)
    assert np.array_equal(rgb[0], rgb[1])  # below low clips to low
    assert np.array_equal(rgb[2], rgb[3])  # above high clips to high
    assert not np.array_equal(rgb[1], rgb[2])


def test_nan_and_inf_are_grey_and_do_not_move_limits() -> None:
    values = np.array([0.0, np.nan, 1.0, np.inf])
    rgba = colorize(values, "coolwarm")
    assert tuple(rgba[1]) == NAN_RGBA
    assert tuple(rgba[3]) == NAN_RGBA
    assert field_limits(values) == (0.0, 1.0)
    assert np.array_equal(rgba[[0, 2]], colorize(np.array([0.0, 1.0]), "coolwarm"))


def test_constant_and_empty_fields() -> None:
    t = normalize(np.full(5, 3.7))
    assert np.all(t == 0.5)  # constant field -> middle of the map, no division by zero
    assert colorize(np.zeros(0)).shape == (0, 4)
    assert np.all(colorize(np.full(3, np.nan)) == np.array(NAN_RGBA, dtype=np.uint8))


def test_bad_arguments() -> None:
    with pytest.raises(ValueError, match="viridis"):
        colorize(np.zeros(3), "jet")
    with pytest.raises(ValueError):
        colorize(np.zeros(3), limits=(1.0, 0.0))
    with pytest.raises(ValueError):
        colorize(np.zeros(3), limits=(0.0, np.nan))
