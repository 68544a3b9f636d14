"""Scalar field -> RGBA colours (uint8) with a perceptual matplotlib colour map.

Only colours: no physics. Used by the rerun logger to paint rods and contacts, and usable by
anyone else who needs the same colours (for example a figure that must match the 3D view).
"""

from __future__ import annotations

import matplotlib
import numpy as np

# Perceptually uniform (viridis, magma) or diverging around a centre (coolwarm). Others are refused
# so that every view of tightknot reads the same way.
COLORMAPS: tuple[str, ...] = ("viridis", "magma", "coolwarm")

# Colour of a value that is not finite (NaN, +-inf): a neutral mid grey, visibly "no data" on
# every map above (none of them passes through grey).
NAN_RGBA: tuple[int, int, int, int] = (128, 128, 128, 255)


def field_limits(
    values: np.ndarray, limits: tuple[float, float] | None = None
) -> tuple[float, float]:
    """Return the ``(low, high)`` limits used to normalise ``values``.

    ``limits`` given: checked (finite, ``low <= high``) and returned as floats. ``limits`` None:
    the minimum and maximum of the finite entries; ``(0.0, 1.0)`` when there is none. Units are
    those of ``values``.
    """
    if limits is not None:
        low, high = float(limits[0]), float(limits[1])
        if not (np.isfinite(low) and np.isfinite(high)) or low > high:
            raise ValueError(f"limits must be finite with low <= high, got {limits!r}")
        return low, high
    finite = np.asarray(values, dtype=np.float64)
    finite = finite[np.isfinite(finite)]
    if finite.size == 0:
        # Nothing to normalise against: any limits give all-grey colours; keep them sane.
        return 0.0, 1.0
    return float(finite.min()), float(finite.max())


def normalize(values: np.ndarray, limits: tuple[float, float] | None = None) -> np.ndarray:
    """Map ``values`` to [0, 1] linearly between the limits, clipping outside; NaN stays NaN.

    A constant field (``low == high``) maps to 0.5, the middle of the map, rather than dividing
    by zero. Returns float64 with the shape of ``values``.
    """
    v = np.asarray(values, dtype=np.float64)
    low, high = field_limits(v, limits)
    span = high - low
    with np.errstate(invalid="ignore"):
        if span > 0.0:
            t = np.clip((v - low) / span, 0.0, 1.0)
        else:
            t = np.where(np.isnan(v), np.nan, 0.5)
    # +-inf are not data we can place on the map: treat them as missing, like NaN.
    return np.where(np.isfinite(v), t, np.nan)


def colorize(
    values: np.ndarray,
    cmap: str = "viridis",
    limits: tuple[float, float] | None = None,
    alpha: bool = True,
) -> np.ndarray:
    """Colour a scalar field.

    Parameters
    ----------
    values:
        Scalar field, any shape, any unit (NaN and +-inf allowed: painted grey).
    cmap:
        One of :data:`COLORMAPS`.
    limits:
        ``(low, high)`` in the unit of ``values``; None = min and max of the finite values.
    alpha:
        True: RGBA, shape ``values.shape + (4,)``; False: RGB, shape ``values.shape + (3,)``.

    Returns
    -------
    np.ndarray of uint8.
    """
    if cmap not in COLORMAPS:
        raise ValueError(f"unknown colour map {cmap!r}; valid: {', '.join(COLORMAPS)}")
    t = normalize(values, limits)
    missing = np.isnan(t)
    # matplotlib's ``bytes=True`` returns uint8 RGBA directly; NaN inputs are replaced first
    # because the map's own "bad" colour is transparent black, not our grey.
    rgba = matplotlib.colormaps[cmap](np.where(missing, 0.0, t), bytes=True)
    rgba = np.asarray(rgba, dtype=np.uint8).reshape(t.shape + (4,))
    rgba[missing] = NAN_RGBA
    return rgba if alpha else rgba[..., :3].copy()
