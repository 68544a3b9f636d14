"""One knot studied end to end: tied, measured, summarised, logged, drawn; the golden runs."""

from tightknot._lazy import lazy_exports

__getattr__, __dir__, __all__ = lazy_exports(__name__, {
    "run_knot": ".run",
    "KnotRun": ".run",
    "logging_hook": ".run",
    "summarise": ".run",
    "measure_run": ".run",
    "draw_figures": ".run",
})
