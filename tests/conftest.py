"""Shared pytest configuration: one Warp kernel cache for the whole test session, and one
MKL thread per xdist worker."""

import os
from pathlib import Path

# Tests share one kernel cache so each Warp module compiles once per checkout
# (compiling is seconds per module; a cache hit is milliseconds).
os.environ.setdefault("WARP_CACHE_PATH", str(Path(__file__).resolve().parents[1] / ".warp_cache"))

# `make test` runs one xdist worker per core: the FEM's PARDISO solves (on MKL's own
# thread count, by default a thread per core) would put two threads of each worker on
# every core. MKL reads this when our code first loads it, after this file.
if os.environ.get("PYTEST_XDIST_WORKER"):
    os.environ.setdefault("MKL_NUM_THREADS", "1")
