"""Load paths: tying, tightening and pulling knots (one rod, or a batch of them), the
continuation in a level parameter with its search for a target knot length, and keeping
an open knot centred on its rod."""

from tightknot._lazy import lazy_exports

__getattr__, __dir__, __all__ = lazy_exports(__name__, {
    "tie": ".tie",
    "TieResult": ".tie",
    "end_reaction": ".tie",
    "knot_type_of": ".tie",
    "tie_to_lambda": ".pull",
    "pull_path": ".pull",
    "LevelPath": ".levels",
    "LevelLoad": ".levels",
    "LevelOptions": ".levels",
    "SearchOptions": ".levels",
    "SecantPredictor": ".levels",
    "recentre_system": ".recentre",
    "tie_batch": ".batch",
    "BatchResult": ".batch",
})
