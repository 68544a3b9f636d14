"""One place that initialises Warp quietly and resolves devices."""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile
from collections.abc import Iterator

import warp as wp

_initialised = False

#: What Warp's native library prints to stderr on a machine without an NVIDIA driver: true,
#: and of no interest unless a CUDA device was asked for.
NO_DRIVER_WARNING = "Could not find or load the NVIDIA CUDA driver"


@contextlib.contextmanager
def _without_native_line(text: str) -> Iterator[None]:
    """Run the block with file descriptor 2 captured; pass every captured line on to stderr
    except those containing ``text`` (the native library writes to the descriptor, not to
    ``sys.stderr``, so only a descriptor redirect can catch it)."""
    sys.stderr.flush()
    try:
        saved = os.dup(2)
    except OSError:  # no stderr descriptor (an embedded interpreter): nothing to filter
        yield
        return
    with tempfile.TemporaryFile(mode="w+b") as capture:
        os.dup2(capture.fileno(), 2)
        try:
            yield
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            capture.seek(0)
            kept = [line for line in capture.read().decode(errors="replace").splitlines(True)
                    if text not in line]
            if kept:
                sys.stderr.write("".join(kept))
                sys.stderr.flush()


def init_warp(quiet: bool = True, cuda: bool = False) -> None:
    """Initialise Warp once (quiet: no banner or per-module compile lines).

    ``cuda``: a CUDA device was asked for, so a missing NVIDIA driver is worth Warp's
    warning; otherwise that one warning is dropped (every other line of Warp's stays).
    """
    global _initialised
    if _initialised:
        return
    if quiet:
        # Warp 1.19 prints its banner and per-module load lines at INFO level.
        wp.config.log_level = wp.LOG_WARNING
    if cuda:
        wp.init()
    else:
        with _without_native_line(NO_DRIVER_WARNING):
            wp.init()
    _initialised = True


def resolve_device(device: str | None) -> str:
    """A Warp device name: ``None`` picks "cpu" (CI and laptops) unless asked otherwise.

    Raises ValueError naming the parameter when the device does not exist here.
    """
    name = "cpu" if device is None else str(device)
    init_warp(cuda=name.startswith("cuda"))
    try:
        wp.get_device(name)
    except Exception as err:  # Warp raises various errors for unknown devices
        avail = ", ".join(d.alias for d in wp.get_devices())
        why = ("" if not name.startswith("cuda") or wp.get_cuda_device_count() > 0
               else "; no CUDA device or driver was found")
        raise ValueError(f"device {name!r} is not available here (available: {avail}"
                         f"{why})") from err
    return name
