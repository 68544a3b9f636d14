"""Hypothesis settings of the fuzz tests: few, small examples (the whole folder runs in
well under 20 s), no deadline (the first call of a Warp kernel compiles or loads it),
derandomized in CI so a run is reproducible (HYPOTHESIS_PROFILE=explore for fresh seeds)."""

from __future__ import annotations

import os

from hypothesis import HealthCheck, settings

settings.register_profile("fuzz", max_examples=60, deadline=None, derandomize=True,
                          suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("explore", max_examples=500, deadline=None,
                          suppress_health_check=[HealthCheck.too_slow])
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "fuzz"))
