"""Pictures, never physics: rerun logs (.rrd) of rods and contacts, their reading back, and
matplotlib figures of tubes and of the study's measurements."""

from tightknot._lazy import lazy_exports

__getattr__, __dir__, __all__ = lazy_exports(__name__, {
    "RerunLogger": ".rerun_log",
    "NullLogger": ".rerun_log",
    "make_logger": ".rerun_log",
    "render_tube": ".tube_figure",
})
