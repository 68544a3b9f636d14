"""Shared pytest configuration: one Warp kernel cache for the whole test session."""

import os
from pathlib import Path

# Tests share one kernel cache so each Warp module compiles once per checkout
# (compiling is seconds per module; a cache hit is milliseconds).
os.environ.setdefault("WARP_CACHE_PATH", str(Path(__file__).resolve().parents[1] / ".warp_cache"))
