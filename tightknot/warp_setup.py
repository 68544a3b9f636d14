"""One place that initialises Warp quietly and resolves devices."""

from __future__ import annotations

import warp as wp

_initialised = False


def init_warp(quiet: bool = True) -> None:
    """Initialise Warp once (quiet: no banner or per-module compile lines)."""
    global _initialised
    if _initialised:
        return
    if quiet:
        # Warp 1.19 prints its banner and per-module load lines at INFO level.
        wp.config.log_level = wp.LOG_WARNING
    wp.init()
    _initialised = True


def resolve_device(device: str | None) -> str:
    """A Warp device name: ``None`` picks "cpu" (CI and laptops) unless asked otherwise.

    Raises ValueError naming the parameter when the device does not exist here.
    """
    init_warp()
    name = "cpu" if device is None else str(device)
    try:
        wp.get_device(name)
    except Exception as err:  # Warp raises various errors for unknown devices
        avail = ", ".join(d.alias for d in wp.get_devices())
        raise ValueError(f"device {name!r} is not available here (available: {avail})") from err
    return name
