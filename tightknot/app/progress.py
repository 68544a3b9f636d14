"""A one-line progress bar on stderr for long work (load steps of tie and demo).

No dependency: a carriage-return line redrawn at most every ``min_interval`` seconds. Silent
when asked (``--quiet``) and when stderr is not a terminal (a log file or a pipe gets no
control characters), so it can always be passed in.
"""

from __future__ import annotations

import sys
import time
from typing import TextIO

#: Width of the bar in characters.
BAR_WIDTH = 24


class Progress:
    """Progress of one task in [0, 1], drawn as ``label [#####.....]  45%  detail``.

    Parameters
    ----------
    label:
        What is running (for example ``"closed_trefoil"``).
    enabled:
        None: draw only when ``stream`` is a terminal; False: never (``--quiet``).
    stream:
        Where to draw (default ``sys.stderr``).
    min_interval:
        Least time between redraws [s], so that fast steps cost nothing visible.
    """

    def __init__(self, label: str, enabled: bool | None = None, stream: TextIO | None = None,
                 min_interval: float = 0.1) -> None:
        self.stream = stream if stream is not None else sys.stderr
        if enabled is None:
            isatty = getattr(self.stream, "isatty", None)
            enabled = bool(isatty and isatty())
        self.enabled = enabled
        self.label = label
        self.min_interval = min_interval
        self._last = -float("inf")
        self._width = 0
        self._start = time.perf_counter()

    def update(self, fraction: float, detail: str = "") -> None:
        """Show ``fraction`` (clipped to [0, 1]) with a short ``detail`` text."""
        if not self.enabled:
            return
        now = time.perf_counter()
        if now - self._last < self.min_interval and fraction < 1.0:
            return
        self._last = now
        f = min(max(float(fraction), 0.0), 1.0)
        filled = int(round(f * BAR_WIDTH))
        line = (f"{self.label} [{'#' * filled}{'.' * (BAR_WIDTH - filled)}] {100 * f:3.0f}%  "
                f"{now - self._start:5.1f} s  {detail}")
        pad = max(0, self._width - len(line))
        self._width = len(line)
        self.stream.write("\r" + line + " " * pad)
        self.stream.flush()

    def close(self, message: str = "") -> None:
        """End the line (and print ``message`` on it, e.g. ``"done"``)."""
        if not self.enabled or self._width == 0:
            return
        self.stream.write(f"\r{' ' * self._width}\r" + (message + "\n" if message else ""))
        self.stream.flush()
        self._width = 0

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


#: Share of the bar given to each phase of a tie run (the pull follows the tightening).
PHASE_SPAN = {"tighten": (0.0, 0.7), "pull": (0.7, 1.0)}


def phase_progress(bar: Progress, closed: bool):
    """A ``progress(phase, t, step)`` callback for :func:`tightknot.study.run.run_knot` that
    maps each phase's load parameter t in [0, 1] onto the bar (a closed knot only tightens)."""

    def update(phase: str, t: float, step: int) -> None:
        lo, hi = (0.0, 1.0) if closed else PHASE_SPAN.get(phase, (0.0, 1.0))
        bar.update(lo + (hi - lo) * t, f"{phase} t={t:.3f} step {step}")

    return update
