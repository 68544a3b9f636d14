"""Golden regression: the canonical runs' curvature profiles against tests/golden/.

Regenerated only by ``python -m tightknot.knots.golden --write``. Tolerances: the runs are
deterministic on one machine (identical to round-off here); across machines the solver
tolerance (scaled residual 1e-6) and float reordering move kappa D0 by far less than 1e-3,
while a physics change (law, discretisation) moves it by 1e-2 or more: 2e-3 in kappa D0,
0.05 in Lambda_OC and 1e-3 in stretch separate the two.
"""

import json
from pathlib import Path

import numpy as np
import pytest

from tightknot.knots.golden import CANONICAL, profile, run_canonical

GOLDEN = Path(__file__).resolve().parents[1] / "golden"


@pytest.mark.parametrize("name", list(CANONICAL))
def test_profile_matches_golden(name: str) -> None:
    gold = json.loads((GOLDEN / f"{name}.json").read_text())
    now = profile(run_canonical(name))
    assert len(now["kappa"]) == len(gold["kappa"])
    assert np.allclose(now["s"], gold["s"], atol=1e-6)
    assert np.max(np.abs(np.asarray(now["kappa"]) - np.asarray(gold["kappa"]))) <= 2e-3
    assert now["stretch"] == pytest.approx(gold["stretch"], abs=1e-3)
    if "lambda_oc" in gold:
        assert now["lambda_oc"] == pytest.approx(gold["lambda_oc"], abs=0.05)
